"""benchmarks/station_keeping_coverage.py: leave-one-log-out forecasts during station keeping."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hybridship.logs.ingest import ingest
from hybridship.physics.model import DynamicModel
from hybridship.predictors import HybridPredictor
from hybridship.residual.calibration import CalibrationConfig
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.sim.synthetic import physics_log

from conftest import load_benchmark

TINY = EnsembleConfig(n_members=2, max_epochs=5, patience=5, seed=1)


@pytest.fixture(scope="module")
def skc():
    return load_benchmark("station_keeping_coverage")


@pytest.fixture(scope="module")
def logs():
    m = DynamicModel("gunnerus")
    return m.vessel, {f"log{s}": ingest(physics_log(m, seed=s, duration_s=2100.0, t_shutdown_s=1950.0,
                                                    current=(0.2, 1.0)), m.vessel, purpose="fit")
                      for s in (3, 4, 5)}


def test_starts_leave_the_whole_forecast_in_station_keeping(skc, logs):
    a = logs[1]["log3"]
    st = skc.station_keeping_starts(a, 20.0, 60.0, 120.0)
    assert st[0] == pytest.approx(120.0) and np.all(np.diff(st) == pytest.approx(20.0))
    assert st[-1] + 60.0 < 1950.0 <= st[-1] + 60.0 + 20.0      # the last one that ends before the failure
    assert skc.station_keeping_starts(a, 20.0, 1900.0, 120.0).size == 0


def test_spread_rows_count_the_band_and_pool_north_and_east(skc):
    lead = np.array([0.0, 15.0, 60.0])
    abs_ne = np.array([[0.0, 0.5, 1.5], [0.0, 1.5, 3.0], [0.0, 2.5, 0.5], [0.0, 0.2, 2.5]])
    std = np.ones_like(abs_ne)
    rows = skc.spread_rows("x", lead, abs_ne, std, 10 * std)
    assert [r["lead_s"] for r in rows] == [15.0, 60.0]
    assert rows[0]["coverage_1sigma"] == 0.5 and rows[0]["coverage_2sigma"] == 0.75
    assert rows[1]["coverage_1sigma"] == 0.25 and rows[1]["coverage_2sigma"] == 0.5
    assert rows[1]["rms_error_m"] == pytest.approx(np.sqrt(np.mean(abs_ne[:, 2] ** 2)))
    assert rows[1]["median_raw_std_m"] == 10.0


def test_run_scores_every_log_with_a_model_fitted_on_the_others(skc, logs, monkeypatch):
    vessel, arrays = logs
    fitted_on = []
    real_fit = HybridPredictor.fit

    def fit(self, training_logs, **kw):
        fitted_on.append({id(b) for b in training_logs})
        return real_fit(self, training_logs, **kw)

    monkeypatch.setattr(HybridPredictor, "fit", fit)
    make = lambda: HybridPredictor(vessel, ensemble_config=TINY,  # noqa: E731
                                   calibration_config=CalibrationConfig(horizon_s=30.0, max_starts=100))
    errors, spread = skc.run(arrays, vessel, 100.0, 30.0, hybrid_factory=make)
    assert [ids for ids in fitted_on] == [{id(b) for k, b in arrays.items() if k != name} for name in arrays]
    assert set(errors.model) == {"hybrid", "hybrid_nets_off", "dynamic", "dead_reckoning"}
    assert list(spread.log.unique()) == ["log3", "log4", "log5", "all"]
    assert np.isfinite(errors[["distance_m", "heading_deg"]].to_numpy()).all()
    assert (spread[spread.log != "all"].spread_exponent == 1.0).all()       # the default
    # the pooled row weighs each log by its starts
    n = errors[errors.model == "hybrid"].drop_duplicates("log").set_index("log").n_starts
    for lead, g in spread.groupby("lead_s"):
        per_log = g[g.log != "all"].set_index("log")
        pooled = (per_log.coverage_2sigma * n).sum() / n.sum()
        assert g[g.log == "all"].coverage_2sigma.item() == pytest.approx(pooled)


class _Stub:
    """Forecasts the logged track plus ``north`` m north (``north_nets_off`` with the nets off)
    and 2 m east, its heading 0.02 rad to port written as 2 pi - 0.02 rad more than the logged
    one; spread 1 m (raw 10 m)."""

    def __init__(self, north=1.0, north_nets_off=3.0):
        self.north, self.north_nets_off = north, north_nets_off

    def forecast(self, a, starts, horizon_s, nets=True, calibrated=True):
        from hybridship.predictors.result import ForecastResult

        lead = np.arange(int(horizon_s / a.dt_s) + 1) * a.dt_s
        rows = np.searchsorted(a.time_s, np.asarray(starts)[:, None] + lead[None, :])
        eta = a.eta[rows] + np.array([self.north if nets else self.north_nets_off, 2.0, 2 * np.pi - 0.02])
        std = np.full(eta.shape, 1.0 if calibrated else 10.0)
        return ForecastResult(np.asarray(starts), lead, eta, np.zeros_like(eta), std)


def test_score_log_aligns_the_truth_and_pools_north_and_east(skc, logs):
    """The hybrid's errors with and without its nets, the heading's wrapped, and the north and
    east errors and spreads of the calibrated forecast with the nets on."""
    a = logs[1]["log3"]
    errors, abs_ne, std, raw, lead, abs_h, std_h = skc.score_log(_Stub(), {"dynamic": _Stub(north=4.0)}, a,
                                                                 np.array([100.0, 200.0]), 30.0)
    assert set(errors) == {"hybrid", "hybrid_nets_off", "dynamic"}
    np.testing.assert_allclose(errors["hybrid"][0], np.sqrt(5.0))
    np.testing.assert_allclose(errors["hybrid"][1], 0.02)
    np.testing.assert_allclose(errors["hybrid_nets_off"][0], np.sqrt(13.0))
    np.testing.assert_allclose(errors["dynamic"][0], np.sqrt(20.0))
    np.testing.assert_allclose(abs_ne[:2], 1.0)
    np.testing.assert_allclose(abs_ne[2:], 2.0)
    (row,) = skc.spread_rows("log3", lead, abs_ne, std, raw)      # 60 s is beyond this 30-s horizon
    assert row["coverage_1sigma"] == 0.5 and row["coverage_2sigma"] == 1.0
    assert row["median_std_m"] == 1.0 and row["median_raw_std_m"] == 10.0
    np.testing.assert_allclose(abs_h, 0.02)
    (row,) = skc.spread_rows("log3", lead, abs_ne, std, raw, abs_hdg=abs_h + 1.5, std_hdg=std_h)
    assert row["heading_coverage_1sigma"] == 0.0 and row["heading_coverage_2sigma"] == 1.0


def test_run_reports_each_models_mean_errors_in_metres_and_degrees(skc, logs, monkeypatch):
    """run's error rows, with stand-ins for every model: each model's own mean errors at 15,
    30, 45 and 60 s, the heading in degrees, the starts counted (every 100 s from the 120-s
    warm-up to 1820 s, the last whose 60 s end before the failure at 1950 s), and no spread
    exponent for a model without a station-keeping calibration."""
    vessel, arrays = logs

    class Fitted(_Stub):
        warm_up_s = 120.0
        calibration = {}

        def fit(self, training_logs):
            return self

    monkeypatch.setattr(skc, "DynamicPredictor", lambda v: _Stub(north=4.0))
    monkeypatch.setattr(skc, "DeadReckoning", lambda v: _Stub(north=0.0))
    errors, spread = skc.run(arrays, vessel, 100.0, 60.0, hybrid_factory=Fitted)
    assert set(errors.n_starts) == {18}
    for model, distance in (("hybrid", np.sqrt(5.0)), ("hybrid_nets_off", np.sqrt(13.0)),
                            ("dynamic", np.sqrt(20.0)), ("dead_reckoning", 2.0)):
        rows = errors[errors.model == model]
        assert list(rows.lead_s) == [15.0, 30.0, 45.0, 60.0] * 3, model
        np.testing.assert_allclose(rows.distance_m, distance, err_msg=model)
        np.testing.assert_allclose(rows.heading_deg, np.degrees(0.02), err_msg=model)
    assert spread.spread_exponent.isna().all()


def test_worse_cells_count_each_state_where_the_hybrid_errs_more(skc):
    import pandas as pd

    errors = pd.DataFrame({"model": ["hybrid", "hybrid", "dynamic", "dynamic", "dead_reckoning", "dead_reckoning"],
                           "log": ["a", "b"] * 3, "lead_s": [60.0] * 6,
                           "distance_m": [1.0, 2.0, 0.5, 3.0, 2.0, 2.0], "heading_deg": [1.0, 1.0, 2.0, 0.5, 1.0, 3.0]})
    assert skc.worse_cells(errors) == {"dynamic": 2, "dead_reckoning": 0}


def test_nominal_distance_averages_the_per_log_rows(skc):
    spread = pd.DataFrame({"log": ["a", "a", "b", "all"], "coverage_1sigma": [0.683, 0.583, 0.883, 0.0],
                           "coverage_2sigma": [0.954, 1.0, 0.9, 0.0]})
    d = skc.nominal_distance(spread)
    assert d[1] == pytest.approx((0.0003 + 0.0997 + 0.2003) / 3, abs=1e-3)
    assert d[2] == pytest.approx((0.0005 + 0.0455 + 0.0545) / 3, abs=1e-3)
    assert "3 log x lead" in skc.nominal_distance_line(spread)


def test_bad_arguments_are_refused(skc, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(skc, "TRUTHSIM", tmp_path / "nowhere")
    assert skc.main(["--data", str(tmp_path / "nowhere"), "--out", str(tmp_path / "o")]) == 0
    assert "skipped" in capsys.readouterr().err
    assert skc.main(["--data", str(tmp_path / "misspelt"), "--out", str(tmp_path / "o")]) == 2
    assert "--data" in capsys.readouterr().err
    (tmp_path / "d").mkdir()
    assert skc.main(["--data", str(tmp_path / "d"), "--every-s", "0", "--out", str(tmp_path / "o")]) == 2
    assert "--every-s" in capsys.readouterr().err
    assert skc.main(["--data", str(tmp_path / "d"), "--spread-exponent", "2", "--out", str(tmp_path / "o")]) == 2
    assert "--spread-exponent" in capsys.readouterr().err
    assert skc.main(["--data", str(tmp_path / "d"), "--out", str(tmp_path / "o")]) == 2
    assert "--data" in capsys.readouterr().err
    assert skc.main(["--data", str(tmp_path / "d"), "--vessel", "no_such_ship", "--out", str(tmp_path / "o")]) == 2
    assert "--vessel" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        skc.main(["--station-keeping-spread", "weather", "--out", str(tmp_path / "o")])
    assert "--station-keeping-spread" in capsys.readouterr().err


@pytest.mark.parametrize("argv, want", [([], CalibrationConfig().station_keeping_spread),
                                        (["--station-keeping-spread", "ensemble"], "ensemble")])
def test_the_spread_flag_defaults_to_the_calibration_default(skc, tmp_path, monkeypatch, argv, want):
    m = DynamicModel("gunnerus")
    (tmp_path / "d").mkdir()
    for s in (3, 4):
        physics_log(m, seed=s, duration_s=300.0, t_shutdown_s=250.0).to_csv(tmp_path / "d" / f"l{s}.csv", index=False)
    seen = []

    class Stop(Exception):
        pass

    def fake_run(logs, vessel, every_s, horizon_s, hybrid_factory):
        seen.append(hybrid_factory().calibration_config.station_keeping_spread)
        raise Stop

    monkeypatch.setattr(skc, "run", fake_run)
    with pytest.raises(Stop):
        skc.main(["--data", str(tmp_path / "d"), "--out", str(tmp_path / "o"), *argv])
    assert seen == [want]
