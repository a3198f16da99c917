"""Tests of hybridship.fileio: atomic writes and the Markdown tables of the benchmarks."""

from __future__ import annotations

import pandas as pd


def test_markdown_table_keeps_a_bar_in_its_cell():
    """A '|' in a name or value was written as is and split its cell in two (the row then
    had more cells than the header)."""
    from hybridship.fileio import markdown_table

    lines = markdown_table(pd.DataFrame({"a|b": ["x|y"], "c": [1]})).splitlines()
    assert lines == [r"| a\|b | c |", "| --- | --- |", r"| x\|y | 1 |"]


def test_atomic_write_writes_through_a_symbolic_link(tmp_path):
    """The rename replaced the link itself with a regular file and left the file it pointed
    to as it was; now the link is kept and its file written, as open() would."""
    from hybridship.fileio import write_text

    target = tmp_path / "data" / "log.csv"
    target.parent.mkdir()
    target.write_text("old")
    link = tmp_path / "log.csv"
    link.symlink_to(target)
    assert write_text(link, "new") == link
    assert link.is_symlink() and target.read_text() == "new"
    assert sorted(p.name for p in target.parent.iterdir()) == ["log.csv"]     # no temporary file left


def test_atomic_write_keeps_the_permissions_of_the_file_it_replaces(tmp_path):
    """The new file took the umask's permissions: a log only its owner could read (0600)
    became readable by everyone (0644) when it was written again."""
    import os
    import stat

    from hybridship.fileio import write_text

    path = tmp_path / "private.csv"
    path.write_text("old")
    path.chmod(0o600)
    write_text(path, "new")
    assert path.read_text() == "new" and stat.S_IMODE(path.stat().st_mode) == 0o600
    old = os.umask(0o077)
    try:
        fresh = write_text(tmp_path / "fresh.csv", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE(fresh.stat().st_mode) == 0o600      # a new file: the umask


def test_lies_within_tells_a_sub_folder_from_a_sibling_that_shares_its_prefix(tmp_path):
    """The output-folder checks of the command line and the manoeuvre benchmark share this
    rule: the folder itself and any folder below it (through a link too) lie within it; a
    sibling whose name only starts like it does not."""
    from hybridship.fileio import lies_within

    runs = tmp_path / "runs"
    (runs / "a" / "b").mkdir(parents=True)
    (tmp_path / "runs2").mkdir()
    (tmp_path / "link").symlink_to(runs)
    assert lies_within(runs, runs) and lies_within(runs / "a" / "b", runs)
    assert lies_within(tmp_path / "link" / "a", runs)
    assert not lies_within(tmp_path / "runs2", runs) and not lies_within(tmp_path, runs)


def test_atomic_write_replaces_a_file_whose_name_is_near_the_length_limit(tmp_path):
    """The temporary file's name added 38 characters to the file's own, so a file of a valid
    230-character name could not be written again ('File name too long')."""
    from hybridship.fileio import write_text

    path = tmp_path / ("a" * 230 + ".csv")
    path.write_text("old")
    assert write_text(path, "new") == path and path.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == [path.name]     # no temporary file left
