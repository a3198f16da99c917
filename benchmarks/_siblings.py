"""A sibling benchmark script loaded as a module (the scripts are not a package).

The scripts import it as ``from _siblings import sibling``: the script's own folder is on
``sys.path`` when it runs (and ``tests/conftest.py`` puts it there for the tests).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path


def sibling(name: str):
    """``benchmarks/<name>.py`` as a module, executed once per call."""
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
