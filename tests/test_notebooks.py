"""The documentation notebooks run, and the reference pages keep up with the code.

* Every ``docs/notebooks/*.py`` (Jupytext percent format) is converted with jupytext and
  executed with nbclient in its small configuration (``HYBRIDSHIP_SMALL=1``), each in a
  fresh kernel with a temporary working directory. Skipped, with a message, when
  jupytext, nbclient or ipykernel are not installed (``pip install -e ".[test]"``
  installs them).
* Every notebook is in the site's navigation (``mkdocs.yml``).
* ``docs/reference/vessel-file.md`` names every field of the vessel-file schema, and
  ``docs/reference/cli.md`` every command and option of ``hybridship --help``.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import re
from pathlib import Path

import pytest

from conftest import ROOT, shared_data_path

DOCS = ROOT / "docs"
NOTEBOOKS = sorted((DOCS / "notebooks").glob("*.py"))
TRUTHSIM_DEV = shared_data_path("truthsim-dev")     # optional: notebook 2 uses it when present
_MISSING = [m for m in ("jupytext", "nbclient", "ipykernel") if importlib.util.find_spec(m) is None]


def test_there_are_notebooks():
    assert NOTEBOOKS, f"no notebooks found in {DOCS / 'notebooks'}"


def _execute(path, tmp_path, monkeypatch, truthsim_dev):
    """Run the notebook at ``path`` small, in a fresh kernel working in ``tmp_path``; its stream output."""
    if _MISSING:
        pytest.skip(f"executing notebooks needs {', '.join(_MISSING)} (pip install -e '.[test]')")
    import jupytext
    import nbclient

    monkeypatch.setenv("HYBRIDSHIP_SMALL", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")           # no figure rendering: faster, no display
    # the kernel imports the hybridship beside this test, not another installed copy
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    if truthsim_dev is not None:
        monkeypatch.setenv("HYBRIDSHIP_TRUTHSIM_DEV", str(truthsim_dev))
    nb = jupytext.read(path)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()                                  # raises CellExecutionError with the traceback
    return "".join(out.get("text", "") for cell in nb.cells if cell.cell_type == "code"
                   for out in cell.get("outputs", []) if out.get("output_type") == "stream")


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_in_small_configuration(path, tmp_path, monkeypatch):
    _execute(path, tmp_path, monkeypatch, TRUTHSIM_DEV if TRUTHSIM_DEV.is_dir() else None)


@pytest.mark.slow
def test_truthsim_dev_notebook_without_the_data_says_where_it_looked(tmp_path, monkeypatch):
    absent = tmp_path / "no-truthsim-dev"
    out = _execute(DOCS / "notebooks" / "02_truthsim_dev.py", tmp_path, monkeypatch, absent)
    assert f"SKIPPED: the shared truthsim-dev data set was not found (no logs/*.csv.gz in {absent}" in out
    assert "trained" not in out


def test_every_notebook_is_in_the_site_navigation():
    """An entry ``- Title: notebooks/<name>.py`` of the ``nav:`` of mkdocs.yml, not a comment and
    not elsewhere (as under ``not_in_nav``)."""
    text = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    nav = re.split(r"^nav:[ \t]*$", text, maxsplit=1, flags=re.M)[-1]
    nav = re.split(r"^\S", nav, maxsplit=1, flags=re.M)[0]          # up to the next top-level key
    nav = re.sub(r"(^|\s)#.*$", "", nav, flags=re.M)                   # without the comments
    assert nav != text and nav.strip(), "no nav: in mkdocs.yml"
    missing = [p.name for p in NOTEBOOKS
               if not re.search(rf"^\s*- (?:[^\n]*:\s+)?notebooks/{re.escape(p.name)}\s*$", nav, flags=re.M)]
    assert not missing, f"add these notebooks to the nav of mkdocs.yml: {missing}"


# --------------------------------------------------------------------------- reference pages


def _schema_fields(model, prefix=""):
    """(dotted path, field name) of every field of a pydantic model, recursively."""
    import typing

    from pydantic import BaseModel

    out = []
    for name, info in model.model_fields.items():
        out.append((prefix + name, name))
        ann = info.annotation
        stack = [ann]
        while stack:
            a = stack.pop()
            if isinstance(a, type) and issubclass(a, BaseModel):
                out += _schema_fields(a, prefix + name + ".")
            else:
                stack.extend(typing.get_args(a))
    return out


def _page_sections(page: str) -> dict[str, str]:
    """Table path ("" for "## Top level", "damping.linear" for ``## `[damping.linear]` ``,
    "thrusters" for ``## `[[thrusters]]` ``) -> the text of its section of the page."""
    out = {}
    for part in re.split(r"^## ", page, flags=re.M)[1:]:
        title, _, body = part.partition("\n")
        table = re.fullmatch(r"`\[\[?([\w.]+)\]\]?`", title.strip())
        if table is not None or title.strip() == "Top level":
            out[table.group(1) if table else ""] = body
    return out


def test_vessel_file_reference_names_every_field():
    """Every field is named in the section of its own table (or of the nearest enclosing table
    with a section): ``x_m`` in the thrusters' table does not describe a rudder's ``x_m``."""
    from hybridship.vessel import Vessel

    sections = _page_sections((DOCS / "reference" / "vessel-file.md").read_text(encoding="utf-8"))
    assert {"", "particulars", "thrusters", "rudders", "wind"} <= set(sections), sorted(sections)
    missing = []
    for path, name in _schema_fields(Vessel):
        table = path.rpartition(".")[0]
        while table not in sections:
            table = table.rpartition(".")[0]
        text = sections[table]
        if (f"`{name}`" not in text and f"[{name}]" not in text and f"[[{name}]]" not in text
                and not re.search(rf"\[[a-z_.]*\.{re.escape(name)}\]", text)):
            missing.append(f"{path} (section [{table}])" if table else path)
    assert not missing, f"docs/reference/vessel-file.md does not describe these vessel-file fields: {sorted(missing)}"


def _help(*args) -> str:
    from hybridship.cli import main

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main([*args, "--help"]) == 0
    return buf.getvalue()


def _subcommands(*prefix) -> list[tuple[str, ...]]:
    """Every command below ``prefix`` (depth first), from the help texts."""
    text = _help(*prefix)
    if "positional arguments:" not in text:
        return []
    body = text.split("positional arguments:", 1)[1].split("\noptions:", 1)[0]
    out = []
    for c in re.findall(r"^ {4}(\w[\w-]*)(?: {2,}|$)", body, flags=re.M):
        out.append((*prefix, c))
        out += _subcommands(*prefix, c)
    return out


def _parser_commands(parser, prefix=()) -> list[tuple[str, ...]]:
    """Every command registered below ``parser`` (depth first), from the parser objects."""
    import argparse

    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out += [(*prefix, name), *_parser_commands(sub, (*prefix, name))]
    return out


def test_every_registered_command_is_listed_in_the_help():
    """A command registered without a ``help=`` is left out of its parent's ``--help`` (the
    metavars COMMAND, MODE, ... hide the choices), and so out of the reference page's checks."""
    from hybridship.cli import _build_parser

    registered = _parser_commands(_build_parser())
    assert len(registered) >= 10, registered
    listed = _subcommands()
    hidden = [" ".join(c) for c in registered if c not in listed]
    assert not hidden, f"commands registered without help= (not in their parent's --help): {hidden}"
    assert sorted(listed) == sorted(registered)


def test_cli_reference_names_every_command_and_option():
    page = (DOCS / "reference" / "cli.md").read_text(encoding="utf-8")
    commands = _subcommands()
    assert commands, f"could not find the commands in:\n{_help()}"
    missing = []
    for cmd in commands:
        heading = re.search(rf"^#+ `hybridship {' '.join(cmd)}`\n", page, flags=re.M)
        if heading is None:
            missing.append(f"hybridship {' '.join(cmd)}")
            continue
        section = re.split(r"^#+ `hybridship ", page[heading.end():], maxsplit=1, flags=re.M)[0]
        for opt in sorted(set(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", _help(*cmd))) - {"--help"}):
            if opt not in section:
                missing.append(f"hybridship {' '.join(cmd)} {opt}")
    assert not missing, ("docs/reference/cli.md is behind `hybridship --help`; add a section with the help "
                         f"text and a description for: {missing}")


@pytest.mark.skipif(__import__("sys").version_info[:2] != (3, 11),
                    reason="docs/reference/cli.md holds Python 3.11's argparse layout")
def test_cli_reference_help_texts_are_the_programs_own(monkeypatch):
    """Every command's section of docs/reference/cli.md, and the page's introduction for
    ``hybridship --help`` itself, holds a ``usage:`` block that is the help the command prints
    (``COLUMNS=100``), so the page cannot fall behind an option's or a command's wording."""
    monkeypatch.setenv("COLUMNS", "100")
    page = (DOCS / "reference" / "cli.md").read_text(encoding="utf-8")
    intro = re.split(r"^#+ `hybridship", page, maxsplit=1, flags=re.M)[0]
    stale = []
    for heading, body in [("", intro), *re.findall(r"^#+ `hybridship ?([^`]*)`\n(.*?)(?=^#+ `hybridship|\Z)",
                                                   page, flags=re.M | re.S)]:
        block = re.search(r"^```text\n(usage:.*?)\n```", body, flags=re.M | re.S)
        if block is None or block.group(1) != _help(*heading.split()).rstrip("\n"):
            stale.append(f"hybridship {heading}".strip())
    assert not stale, f"docs/reference/cli.md: the help text of {stale} is missing or not the program's; regenerate it"


def test_api_reference_covers_every_module():
    """Every top-level module and subpackage of hybridship has a ``::: hybridship.<name>`` entry
    (subpackages render their submodules with ``show_submodules``)."""
    import hybridship

    pkg = Path(hybridship.__file__).parent
    names = {p.stem for p in pkg.glob("*.py") if p.stem not in ("__init__", "__main__")}  # __main__: the CLI entry
    names |= {p.name for p in pkg.iterdir() if (p / "__init__.py").is_file() and p.name not in ("data", "vessels")}
    pages = "".join(p.read_text(encoding="utf-8") for p in (DOCS / "reference" / "api").glob("*.md"))
    documented = set(re.findall(r"^::: hybridship\.(\w+)", pages, flags=re.M))
    missing = sorted(names - documented)
    assert not missing, f"add `::: hybridship.<name>` entries to docs/reference/api/*.md for: {missing}"


def test_api_reference_renders_every_submodule():
    """Every module of a subpackage is rendered: by ``show_submodules: true`` on the package's
    entry, by a ``::: hybridship.<package>.<module>`` entry of its own, or, for a module whose
    names the package re-exports, named in backquotes on the page of the package's entry."""
    pages = [p.read_text(encoding="utf-8") for p in sorted((DOCS / "reference" / "api").glob("*.md"))]
    text = "\n".join(pages)
    missing = []
    for init in sorted((ROOT / "hybridship").glob("*/__init__.py")):
        pkg = init.parent.name
        if pkg in ("data", "vessels") or re.search(
                rf"^::: hybridship\.{pkg}[ \t]*\n(?:[ \t]+\S.*\n)*?[ \t]+show_submodules: true", text, flags=re.M):
            continue
        page = next((t for t in pages if re.search(rf"^::: hybridship\.{pkg}[ \t]*$", t, flags=re.M)), "")
        missing += [f"hybridship.{pkg}.{mod.stem}" for mod in sorted(init.parent.glob("*.py"))
                    if mod.stem != "__init__" and f"`{mod.stem}`" not in page
                    and not re.search(rf"^::: hybridship\.{pkg}\.{mod.stem}[ \t]*$", text, flags=re.M)]
    assert not missing, f"add `::: hybridship.<package>.<module>` entries to docs/reference/api/*.md for: {missing}"
