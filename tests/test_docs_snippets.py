"""The Python examples a new user copies first run as written: the README's API block and
the equations page's, each executed whole in a fresh namespace (and folder, for the files
they write)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = {"README.md": "## Python API", "docs/concepts/equations.md": "# "}


def _first_python_block(page: str, after: str) -> str:
    text = (ROOT / page).read_text(encoding="utf-8")
    m = re.search(r"```python\n(.*?)```", text[text.index(after):], flags=re.S)
    assert m, f"{page}: no python block after {after!r}"
    return m.group(1)


@pytest.mark.parametrize("page", sorted(PAGES))
def test_the_pages_python_example_runs_as_written(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(_first_python_block(page, PAGES[page]), page, "exec"), namespace)   # noqa: S102 (our own docs)
    assert namespace["res"].eta.shape[1:] == (61, 3)
    if page == "README.md":
        assert (tmp_path / "gunnerus.hybrid.npz").is_file() and namespace["fc"].eta.shape[:2] == (2, 61)
