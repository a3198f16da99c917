"""benchmarks/refactor_snapshot.py: how the snapshot is written."""

import numpy as np
import pytest

from conftest import load_benchmark


def _with_parts(monkeypatch, part):
    rs = load_benchmark("refactor_snapshot")
    for name in ("_drift", "_simulator", "_ensemble", "_multistep"):
        monkeypatch.setattr(rs, name, part)
    return rs


def test_a_snapshot_stopped_part_way_leaves_the_previous_one(tmp_path, monkeypatch):
    """np.savez wrote the snapshot in place: an array that failed part way left a truncated
    zip over the previous snapshot; it is now written atomically."""
    class Fails:
        def __array__(self, *a, **k):
            raise RuntimeError("stopped part way")

    def part(out):
        out["a"] = np.zeros(1000)
        out["b"] = Fails()

    rs = _with_parts(monkeypatch, part)
    path = tmp_path / "before.npz"
    path.write_bytes(b"previous snapshot")
    with pytest.raises(RuntimeError, match="stopped part way"):
        rs.snap(str(path))
    assert path.read_bytes() == b"previous snapshot"
    assert [p.name for p in tmp_path.iterdir()] == ["before.npz"]


def test_the_snapshot_is_written_to_the_path_given(tmp_path, monkeypatch, capsys):
    """np.savez added .npz to a path without it, so 'snap --out /tmp/before' printed
    '-> /tmp/before' and wrote /tmp/before.npz, which 'compare /tmp/before ...' did not find."""
    rs = _with_parts(monkeypatch, lambda out: out.update(a=np.arange(3.0)))
    path = tmp_path / "before"
    rs.snap(str(path))
    assert [p.name for p in tmp_path.iterdir()] == ["before"]
    assert f"-> {path}" in capsys.readouterr().out
    assert rs.compare(str(path), str(path)) == 0
