"""benchmarks/after_stop_calibration.py: its options."""

import pytest

from conftest import load_benchmark


@pytest.mark.parametrize("bad, says", [
    (["--n", "0"], "--n: expected a positive integer"),
    (["--own", "21"], "--own: expected 0-20"),
    (["--own", "-1"], "--own: expected 0-20"),
    (["--vessel-spread", "-1"], "--vessel-spread: expected a finite number >= 0"),
    (["--vessel-spread", "nan"], "--vessel-spread: expected a finite number >= 0"),
    (["--dp-s", "-5"], "--dp-s: must be > 0"),
    (["--beaufort", "5", "2"], "--beaufort: must satisfy"),
    (["--seed", "-1"], "--seed: must be >= 0"),
    (["--held-load-window-s", "-1"], "--held-load-window-s: must be >= 0"),
])
def test_a_value_the_run_cannot_take_is_a_usage_error_before_any_work(bad, says, monkeypatch, capsys):
    """--n 0 trained the hybrid on the embedded scenarios and failed in calibrate_after_stop,
    --own outside 0-20 and the DPLossConfig and EnvironmentConfig values ended in the
    library's traceback (in its argument names), and a negative or NaN --vessel-spread was
    read as no spread; each is now a usage error (exit 2) naming the option."""
    asc = load_benchmark("after_stop_calibration")

    def no_work(*a, **k):
        raise AssertionError("work started")

    monkeypatch.setattr(asc, "calibration_logs", no_work)
    monkeypatch.setattr(asc, "embedded_scenarios", no_work)
    with pytest.raises(SystemExit) as exc:
        asc.main(bad)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"error: {says}" in err, err


def test_the_default_options_pass_the_checks(monkeypatch):
    """The checks refuse nothing the documented runs use."""
    asc = load_benchmark("after_stop_calibration")

    class Stop(Exception):
        pass

    def stop(*a, **k):
        raise Stop

    monkeypatch.setattr(asc, "calibration_logs", stop)
    for argv in ([], ["--n", "8", "--vessel-spread", "1", "--beaufort", "2", "6", "--dp-s", "1800"],
                 ["--own", "20", "--source", "own"]):
        monkeypatch.setattr(asc, "embedded_scenarios", stop)
        with pytest.raises(Stop):
            asc.main(argv)
