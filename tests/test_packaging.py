"""The wheel's explicit package list (pyproject.toml) covers every subpackage: a package
left out is missing from a non-editable install (``pip install .``), where the CLI and
``from hybridship import HybridPredictor`` then fail with ModuleNotFoundError, while the
tests, run from the source tree, still pass."""

import tomllib
from fnmatch import fnmatch
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_package_list_covers_every_subpackage():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]
    listed = set(config["packages"])
    # every folder holding a module, also one without an __init__.py (a namespace package imports
    # from the source tree, but an explicit package list leaves it out of the wheel)
    found = {".".join(module.parent.relative_to(ROOT).parts)
             for module in (ROOT / "hybridship").rglob("*.py")
             if "__pycache__" not in module.parts}
    assert found - listed == set(), f"subpackages missing from pyproject.toml [tool.setuptools] packages: {sorted(found - listed)}"
    for name, folder in config.get("package-dir", {}).items():
        assert name in listed and (ROOT / folder).is_dir(), f"package-dir {name} -> {folder}"


def test_package_data_covers_every_data_file():
    """Every file beside the modules of a listed package (the wind tables, the vessel files)
    matches one of its ``[tool.setuptools.package-data]`` globs: a file left out is missing
    from the wheel, where e.g. ``load_vessel("gunnerus")`` then fails, while the tests, run from
    the source tree, still find it."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]
    folders, globs = config.get("package-dir", {}), config.get("package-data", {})
    missing = []
    for name in config["packages"]:
        folder = ROOT / folders.get(name, name.replace(".", "/"))
        patterns = globs.get(name, []) + globs.get("*", [])
        missing += [str(f.relative_to(ROOT)) for f in sorted(folder.iterdir())
                    if f.is_file() and f.suffix not in (".py", ".pyc") and not f.name.startswith(".")
                    and not any(fnmatch(f.name, p) for p in patterns)]
    assert missing == [], f"files not in pyproject.toml [tool.setuptools.package-data]: {missing}"
