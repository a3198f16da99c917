"""benchmarks/esso_validation.py: its options."""

import pytest

from conftest import load_benchmark


@pytest.mark.parametrize("bad", [["--quantiles", "2"], ["--quantiles", "0.9,x"], ["--quantiles", "nan"],
                                 ["--horizons-s", "5,x"], ["--horizons-s", "0"]])
def test_a_bad_quantile_or_horizon_is_a_usage_error_before_any_work(bad, tmp_path, capsys):
    """A guard quantile outside [0.5, 1) ended in EnvelopeGuard.fit's traceback after the
    hybrid was trained, and an item that is not a number in a traceback; both are now usage
    errors (exit 2) naming the option, before the runs are read."""
    ev = load_benchmark("esso_validation")
    with pytest.raises(SystemExit) as exc:
        ev.main([*bad, "--train", str(tmp_path / "absent"), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert f"error: {bad[0]}: " in capsys.readouterr().err
