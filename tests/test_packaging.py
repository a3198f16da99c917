"""The wheel's explicit package list (pyproject.toml) covers every subpackage: a package
left out is missing from a non-editable install (``pip install .``), where the CLI and
``from hybridship import HybridPredictor`` then fail with ModuleNotFoundError, while the
tests, run from the source tree, still pass."""

import tomllib
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
