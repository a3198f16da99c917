"""Tests of hybridship.fileio: atomic writes and the Markdown tables of the benchmarks."""

from __future__ import annotations

import pandas as pd


def test_markdown_table_keeps_a_bar_in_its_cell():
    """A '|' in a name or value was written as is and split its cell in two (the row then
    had more cells than the header)."""
    from hybridship.fileio import markdown_table

    lines = markdown_table(pd.DataFrame({"a|b": ["x|y"], "c": [1]})).splitlines()
    assert lines == [r"| a\|b | c |", "| --- | --- |", r"| x\|y | 1 |"]
