"""The compiled kernels' cache is dropped when any kernel module changes (not only the caller's file)."""

from __future__ import annotations

from pathlib import Path

from hybridship.physics.compiled_cache import (
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


def test_the_package_s_kernel_modules_are_all_covered():
    names = {p.relative_to(p.parents[1]).as_posix() for p in kernel_source_files()}
    assert {"physics/hull.py", "physics/rhs.py", "physics/integrate.py", "residual/environment_kernel.py",
            "driftoff/engine.py"} <= names


def test_compiling_the_kernels_or_loading_them_from_the_cache_gives_the_same_bits():
    """A rollout of the Esso Osaka model (rudder kernels with fused multiply-add) differed in
    its last bits between a run that compiled the kernels and one that loaded them; the same
    command must give the same table either way (``benchmarks/compile_cache_determinism.py``)."""
    from conftest import load_benchmark

    compiled, loaded, gaps = load_benchmark("compile_cache_determinism").compiled_and_loaded()
    assert [row[0] for row in compiled] == ["gunnerus", "esso_osaka_model", "simulator"]
    assert compiled == loaded, gaps
    assert max(gaps.values()) == 0.0
