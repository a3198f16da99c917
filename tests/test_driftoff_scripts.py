"""benchmarks/driftoff_live.py and driftoff_season.py: their options."""

import pytest

from conftest import load_benchmark


@pytest.mark.parametrize("bad", [["--samples", "0"], ["--vessel-spread", "-1"], ["--vessel-spread", "nan"],
                                 ["--seed", "-1"]])
def test_live_settings_it_cannot_use_are_usage_errors(bad, tmp_path, capsys):
    """Settings the drift-off model refuses stop with a usage error (exit 2) naming the option
    and the reason, before any log is read (they ended in DriftOffSettings' traceback)."""
    live = load_benchmark("driftoff_live")
    with pytest.raises(SystemExit) as exc:
        live.main([*bad, "--data", str(tmp_path), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"error: {bad[0]}: " in err and ("must be" in err or "expected" in err), err
    assert not (tmp_path / "out").exists()
