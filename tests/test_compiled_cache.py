"""The compiled kernels' cache is dropped when any kernel module changes (not only the caller's file)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from hybridship.physics.compiled_cache import (
    PACKAGE_DIR,
    STAMP_NAME,
    drop_stale_compiled_kernels,
    kernel_source_files,
)


def _fake_package(root: Path) -> Path:
    pkg = root / "pkg"
    (pkg / "physics" / "__pycache__").mkdir(parents=True)
    (pkg / "physics" / "hull.py").write_text("import numba\n\n@numba.njit(cache=True)\ndef f(x):\n    return x\n")
    (pkg / "physics" / "rhs.py").write_text("from numba import njit\n")
    (pkg / "cli.py").write_text('"""Mentions numba in prose only."""\n')
    return pkg


def _cache_files(pkg: Path) -> list[str]:
    return sorted(p.name for p in (pkg / "physics" / "__pycache__").iterdir() if p.suffix in (".nbi", ".nbc"))


def test_a_change_in_any_kernel_module_drops_every_cached_kernel(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    pkg = _fake_package(tmp_path)
    assert [p.name for p in kernel_source_files(pkg)] == ["hull.py", "rhs.py"]
    cache = pkg / "physics" / "__pycache__"
    (cache / "rhs.rollout-12.py311.nbi").write_bytes(b"index")
    (cache / "rhs.rollout-12.py311.1.nbc").write_bytes(b"code")
    assert drop_stale_compiled_kernels(pkg)  # no stamp yet: whatever is cached is of unknown sources
    assert _cache_files(pkg) == []
    assert (pkg / "__pycache__" / STAMP_NAME).exists()

    (cache / "rhs.rollout-12.py311.nbi").write_bytes(b"index")  # numba caches again
    assert not drop_stale_compiled_kernels(pkg)  # sources unchanged: the cache is kept
    assert _cache_files(pkg) == ["rhs.rollout-12.py311.nbi"]

    (pkg / "cli.py").write_text('"""Edited prose."""\n')  # not a kernel module
    assert not drop_stale_compiled_kernels(pkg)

    (pkg / "physics" / "hull.py").write_text("import numba\n# the hull changed; rhs.py did not\n")
    assert drop_stale_compiled_kernels(pkg)
    assert _cache_files(pkg) == []


def test_a_user_cache_dir_is_left_alone(tmp_path, monkeypatch):
    pkg = _fake_package(tmp_path)
    (pkg / "physics" / "__pycache__" / "hull.f-3.py311.nbi").write_bytes(b"index")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    assert not drop_stale_compiled_kernels(pkg)
    assert _cache_files(pkg) == ["hull.f-3.py311.nbi"]


#: Cache files numba would write beside two kernel modules in two folders: the hull's, and the
#: drift-off engine's, which calls the hull kernels from another file and folder.
_PLANTED = ("physics/__pycache__/hull.hull_forces_scalar-41.py311.nbi",
            "physics/__pycache__/hull.hull_forces_scalar-41.py311.1.nbc",
            "driftoff/__pycache__/engine._kernel-218.py311.nbi",
            "driftoff/__pycache__/engine._kernel-218.py311.1.nbc")


def _import_the_physics(pkg: Path) -> None:
    """Import ``hybridship.physics`` from the copy ``pkg`` in a fresh process, with numba's
    default in-tree cache (what every kernel module imports first)."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(pkg.parent)
    out = subprocess.run([sys.executable, "-c", "import hybridship.physics as p; print(p.__file__)"],
                         cwd=pkg.parent, env=env, capture_output=True, text=True, check=True).stdout
    assert Path(out.strip()).is_relative_to(pkg), out       # the copy, not the installed package


def _plant(pkg: Path) -> None:
    for name in _PLANTED:
        (pkg / name).parent.mkdir(parents=True, exist_ok=True)
        (pkg / name).write_bytes(b"compiled")


def _still_cached(pkg: Path) -> list[str]:
    return [name for name in _PLANTED if (pkg / name).exists()]


def test_importing_the_package_drops_a_cache_made_stale_by_another_kernel_file(tmp_path):
    """The real package, imported as a user would after a ``git pull`` that changed the hull
    kernels only: the engine's cached kernel (its own file unchanged, another folder) must go
    too, and a cache whose sources did not change must be kept and read, not dropped at every
    start. Kills: the call at the physics package's import removed, a stamp that never
    matches (each process would compile every kernel anew), the drop confined to one folder."""
    pkg = tmp_path / "hybridship"
    shutil.copytree(PACKAGE_DIR, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    _plant(pkg)
    _import_the_physics(pkg)
    assert _still_cached(pkg) == []                 # no stamp yet: caches of unknown sources
    assert (pkg / "__pycache__" / STAMP_NAME).is_file()

    _plant(pkg)
    _import_the_physics(pkg)
    assert _still_cached(pkg) == list(_PLANTED)     # nothing changed: the cache is kept
    _import_the_physics(pkg)
    assert _still_cached(pkg) == list(_PLANTED)

    with open(pkg / "physics" / "hull.py", "a", encoding="utf-8") as fh:
        fh.write("\n# an edit of the hull kernels' file alone\n")
    _import_the_physics(pkg)
    assert _still_cached(pkg) == []                 # every kernel module's cache, in every folder

    _plant(pkg)                                     # numba caches the new kernels: kept from now on
    _import_the_physics(pkg)
    assert _still_cached(pkg) == list(_PLANTED)


def test_the_package_s_kernel_modules_are_all_covered():
    names = {p.relative_to(p.parents[1]).as_posix() for p in kernel_source_files()}
    assert {"physics/hull.py", "physics/rhs.py", "physics/integrate.py", "residual/environment_kernel.py",
            "driftoff/engine.py", "physics/compiled_cache.py"} <= names   # the last holds the kernels' flags


def test_compiling_the_kernels_or_loading_them_from_the_cache_gives_the_same_bits(monkeypatch):
    """A rollout of the Esso Osaka model (rudder kernels with fused multiply-add) differed in
    its last bits between a run that compiled the kernels and one that loaded them; the same
    command must give the same table either way (``benchmarks/compile_cache_determinism.py``).
    Equal bits say nothing unless the second run did load: the first run must have written
    the kernels' cache files, and the second left every one as it was (none dropped,
    recompiled or rewritten), or both runs compiled."""
    from conftest import load_benchmark

    bench = load_benchmark("compile_cache_determinism")
    run, cached = bench._run, []

    def run_then_list_the_cache(copy, tag):
        rows = run(copy, tag)
        cached.append({p.relative_to(copy).as_posix(): (p.stat().st_mtime_ns, p.read_bytes())
                       for p in sorted(copy.rglob("*.nb[ic]"))})
        return rows

    monkeypatch.setattr(bench, "_run", run_then_list_the_cache)
    compiled, loaded, gaps = bench.compiled_and_loaded()
    written = {name.split("-")[0] for name in cached[0]}
    assert {f"hybridship/physics/__pycache__/{kernel}" for kernel in (
        "integrate.rollout_batch", "rhs.dynamics_batch", "rudder.rudder_forces_scalar")} <= written, sorted(written)
    assert cached[1].keys() == cached[0].keys()
    assert [name for name in cached[0] if cached[1][name] != cached[0][name]] == []
    assert [row[0] for row in compiled] == ["gunnerus", "esso_osaka_model", "simulator"]
    assert compiled == loaded, gaps
    assert max(gaps.values()) == 0.0


def test_the_determinism_script_s_help_is_its_usage_not_a_run(monkeypatch, capsys):
    """benchmarks/compile_cache_determinism.py read no arguments: --help (or a misspelt
    option) copied the package and ran both child processes, printing digests and no usage."""
    import pytest

    from conftest import load_benchmark

    bench = load_benchmark("compile_cache_determinism")
    monkeypatch.setattr(bench, "compiled_and_loaded", lambda: pytest.fail("the check ran"))
    with pytest.raises(SystemExit) as exc:
        bench.main(["--help"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith("usage: ")
    with pytest.raises(SystemExit) as exc:
        bench.main(["--quick"])
    assert exc.value.code == 2
