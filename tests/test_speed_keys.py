"""benchmarks/speed.py: its docstring describes every key of the JSON it prints."""

import json
from pathlib import Path

import pytest

from conftest import load_benchmark

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "speed"


@pytest.mark.parametrize("name", ["speed.json", "long-log-1.json", "start-windows.json"])
def test_every_key_of_the_committed_timings_is_described_in_the_docstring(name):
    """docs/results/speed/README.md sends a reader to the script's docstring for the keys."""
    doc = load_benchmark("speed").__doc__
    keys = json.loads((RESULTS / name).read_text())
    assert [k for k in keys if f"``{k}``" not in doc] == []
