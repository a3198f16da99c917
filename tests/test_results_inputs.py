"""Committed results made from other committed results are not stale: every
``docs/results/**/*.inputs.json`` (written by :func:`hybridship.fileio.record_inputs`) names
files whose content is still what its result was made from. A result re-made upstream (a drift
benchmark's ``drift_hull.csv``) then fails here until the result built on it is re-run."""

import hashlib
import json
from pathlib import Path

import pytest

from hybridship.fileio import record_inputs

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"
RECORDS = sorted(RESULTS.rglob("*.inputs.json"))


def test_some_result_records_its_inputs():
    assert RECORDS, "no docs/results/**/*.inputs.json: the derived results lost their records"


@pytest.mark.parametrize("record", RECORDS, ids=[str(p.relative_to(RESULTS)) for p in RECORDS])
def test_a_derived_result_was_made_from_the_committed_inputs(record):
    meta = json.loads(record.read_text(encoding="utf-8"))
    assert (record.parent / meta["output"]).is_file(), f"{record}: its output {meta['output']} is missing"
    # a record naming no input would pass below whatever changed upstream
    assert meta["made_from"], f"{record}: names no input, so it cannot tell when its output is stale"
    for rel, sha in meta["made_from"].items():
        path = record.parent / rel
        assert path.is_file(), f"{record}: input {rel} is missing"
        assert hashlib.sha256(path.read_bytes()).hexdigest() == sha, (
            f"docs/results/{record.parent.relative_to(RESULTS)}/{meta['output']} is stale: its input {rel} changed "
            f"since it was made; re-run the command that made it")


def test_record_inputs_keys_inputs_by_their_path_from_the_output(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    src = tmp_path / "a" / "in.csv"
    src.write_bytes(b"x,y\n1,2\n")
    written = record_inputs(tmp_path / "b" / "out.md", [src])
    meta = json.loads(written.read_text())
    assert written.name == "out.md.inputs.json" and meta["output"] == "out.md"
    assert meta["made_from"] == {"../a/in.csv": hashlib.sha256(b"x,y\n1,2\n").hexdigest()}
