"""Spread calibration (issue 17): the scale function, its config, the hybrid's default and the model file."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hybridship.physics.model import DynamicModel
from hybridship.predictors import HybridPredictor
from hybridship.residual.calibration import (CalibrationConfig, SpreadCalibration, coverage_of,
                                             fit_spread_scale)
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=3, hidden=8, max_epochs=15, patience=5, seed=0)


def test_scale_recovers_a_known_underdispersion_and_gives_nominal_coverage_on_new_data():
    rng = np.random.default_rng(0)
    lead = np.array([1.0, 2.0, 5.0])
    true_ratio = np.array([3.0, 5.0, 0.5])           # errors are this many times the reported spread
    s = rng.uniform(0.5, 2.0, (20_000, 3))
    e = np.abs(rng.normal(0.0, s * true_ratio))
    cal = fit_spread_scale(e, s, lead, floor_quantile=0.0)
    np.testing.assert_allclose(cal.scale, true_ratio, rtol=0.05)
    s2 = rng.uniform(0.5, 2.0, (20_000, 3))
    e2 = np.abs(rng.normal(0.0, s2 * true_ratio))
    cov = coverage_of(e2, cal.apply(s2, lead))
    np.testing.assert_allclose(cov[:, 1], 0.9545, atol=0.01)
    np.testing.assert_allclose(cov[:, 0], 0.6827, atol=0.02)   # Gaussian errors: 1 sigma follows


def test_floor_keeps_a_zero_spread_from_hiding_an_error():
    rng = np.random.default_rng(1)
    s = rng.uniform(0.5, 1.5, (1000, 1))
    s[:200] = 0.0                                      # members agree (guard shrank the correction)
    e = np.abs(rng.normal(0.0, 1.0, (1000, 1)))
    cal = fit_spread_scale(e, s, [1.0], floor_quantile=0.3)
    assert cal.floor[0] > 0.4 and np.isfinite(cal.scale[0])
    assert coverage_of(e, cal.apply(s, np.array([1.0])))[0, 1] >= 0.95


def test_apply_interpolates_holds_beyond_and_leaves_the_start_alone():
    cal = SpreadCalibration([1.0, 3.0], [2.0, 4.0], [0.0, 0.0])
    out = cal.apply(np.ones((2, 5)), np.array([0.0, 1.0, 2.0, 3.0, 10.0]))
    np.testing.assert_allclose(out[0], [1.0, 2.0, 3.0, 4.0, 4.0])


def test_spread_calibration_refuses_a_lead_time_of_zero_by_name():
    """Lead 0 (the start) was taken as a calibrated lead: its scale then set the spread of
    every lead before the first real one by interpolation, and a model file with it read."""
    for lead in ([0.0, 1.0], [0.0]):
        with pytest.raises(ValueError, match=r"^lead_s: expected lead times > 0 \[s\]"):
            SpreadCalibration(lead, [1.0] * len(lead), [0.0] * len(lead))
    assert SpreadCalibration([0.5, 1.0], [1.0, 1.0], [0.0, 0.0]).lead_s[0] == 0.5


def test_likelihood_exponent_follows_how_much_the_spread_says_about_the_error():
    """An uninformative spread gets exponent 0 (one band for all), an informative one 1; on
    new data the chosen band covers about 95 % in each third of the raw spreads, where the
    plain scale (exponent 1) on the uninformative spread does not."""
    rng = np.random.default_rng(2)
    lead = np.array([1.0, 2.0])
    raw = np.exp(rng.normal(0.0, 1.5, (6000, 2)))
    noise = np.abs(rng.normal(0.0, 1.0, (6000, 2)))
    flat = fit_spread_scale(noise[:3000], raw[:3000], lead, exponent="likelihood")
    sharp = fit_spread_scale(raw[:3000] * noise[:3000], raw[:3000], lead, exponent="likelihood")
    assert flat.exponent == 0.0 and sharp.exponent == 1.0
    plain = fit_spread_scale(noise[:3000], raw[:3000], lead)
    assert plain.exponent == 1.0
    e2, s2 = noise[3000:, :1], raw[3000:, :1]
    thirds = np.array_split(np.argsort(s2[:, 0]), 3)
    cov = [coverage_of(e2[i], flat.apply(s2[i], lead[:1]))[0, 1] for i in thirds]
    np.testing.assert_allclose(cov, 0.95, atol=0.03)
    cov_plain = [coverage_of(e2[i], plain.apply(s2[i], lead[:1]))[0, 1] for i in thirds]
    assert cov_plain[0] < 0.9 and cov_plain[2] > 0.99
    # a fixed exponent is used as given, and apply raises the floored spread to it
    half = fit_spread_scale(noise[:3000], raw[:3000], lead, exponent=0.5)
    assert half.exponent == 0.5
    cal = SpreadCalibration([1.0], [2.0], [1.0], 0.5)
    np.testing.assert_allclose(cal.apply(np.array([[0.0, 0.25, 4.0]]).T, np.array([1.0]))[:, 0], [2.0, 2.0, 4.0])
    with pytest.raises(ValueError, match=r"exponent must be a number in \[0, 1\] or 'likelihood', got 2.0"):
        fit_spread_scale(noise, raw, lead, exponent=2.0)
    with pytest.raises(ValueError, match="exponent"):
        SpreadCalibration([1.0], [2.0], [1.0], 1.5)
    # a spread that is not finite stays as it is, whatever the exponent
    assert np.isnan(flat.apply(np.array([[np.nan, np.nan]]), lead)).all()


def test_exponent_one_is_the_plain_conformal_scale():
    """The default reproduces ``k = quantile(|e| / max(s, floor)) / sigma`` and ``k max(s, floor)``
    exactly (the option must leave the default's numbers bit for bit)."""
    rng = np.random.default_rng(4)
    s = rng.uniform(0.0, 2.0, (500, 3))
    e = np.abs(rng.normal(0.0, 1.0 + s))
    lead = np.array([1.0, 2.0, 4.0])
    cal = fit_spread_scale(e, s, lead)
    n = 500
    k = int(np.ceil((n + 1) * 0.9544997361036416))         # 479: the 479-th smallest of 500
    for h in range(3):
        f = max(float(np.quantile(s[:, h], 0.1)), 1e-12)
        assert cal.floor[h] == f
        assert cal.scale[h] == float(np.sort(e[:, h] / np.maximum(s[:, h], f))[k - 1]) / 2.0
    # on 1..n the k-th smallest, k = ceil((n + 1) 0.9): not the (k + 1)-th
    for n in (20, 50, 1000):
        got = fit_spread_scale(np.arange(1.0, n + 1)[:, None], np.ones((n, 1)), [1.0], sigma=1.0, coverage=0.9,
                               floor_quantile=0.0)
        assert got.scale[0] == min(n, np.ceil((n + 1) * 0.9))
    x = np.array([0.0, 1.0, 1.5, 4.0, 9.0])
    k, f = np.interp(x, lead, cal.scale), np.interp(x, lead, cal.floor)
    np.testing.assert_array_equal(cal.apply(np.ones((2, 5)), x)[:, 1:], (k * np.maximum(1.0, f))[None, 1:].repeat(2, 0))


@pytest.mark.parametrize("kw, field", [(dict(fraction=0.7), "fraction"), (dict(commands=("later",)), "commands"),
                                       (dict(spread_exponent=1.5), "spread_exponent"),
                                       (dict(spread_exponent="ml"), "spread_exponent"),
                                       (dict(horizon_s=0.0), "horizon_s"), (dict(coverage=1.0), "coverage"),
                                       (dict(max_starts=2), "max_starts")])
def test_config_errors_name_the_field(kw, field):
    with pytest.raises(ValueError, match=field):
        CalibrationConfig(**kw)


def test_fit_spread_scale_refuses_bad_shapes_and_negative_errors():
    with pytest.raises(ValueError, match="abs_err and std"):
        fit_spread_scale(np.ones((30, 2)), np.ones((30, 3)), [1.0, 2.0])
    with pytest.raises(ValueError, match=">= 0"):
        fit_spread_scale(-np.ones((30, 1)), np.ones((30, 1)), [1.0])
    with pytest.raises(ValueError, match="finite samples"):
        fit_spread_scale(np.ones((5, 1)), np.ones((5, 1)), [1.0])


def test_fit_spread_scale_refuses_negative_spreads_and_bad_settings_by_name():
    e, s = np.ones((30, 1)), np.ones((30, 1))
    # before: a negative spread fell to the 1e-12 floor and gave a scale of 1e12, silently
    with pytest.raises(ValueError, match="std must be >= 0"):
        fit_spread_scale(e, -s, [1.0])
    # before: "'>' not supported between instances of 'NoneType' and 'int'", an IndexError
    with pytest.raises(TypeError, match="sigma: expected a number"):
        fit_spread_scale(e, s, [1.0], sigma=None)
    with pytest.raises(ValueError, match="coverage: must be < 1"):
        fit_spread_scale(e, s, [1.0], coverage=1.5)
    with pytest.raises(ValueError, match="min_samples: expected a whole number >= 1"):
        fit_spread_scale(e[:0], s[:0], [1.0], min_samples=0)
    with pytest.raises(TypeError, match="abs_err: expected an array of real numbers"):
        fit_spread_scale([["a"]] * 30, s, [1.0])


def test_fit_spread_scale_refuses_the_start_as_a_lead_time():
    """lead_s holds lead times > 0: a forecast's first column (lead 0, no error, no spread)
    given with the others is refused by name; it made the likelihood choose the exponent 1
    for errors that do not follow the spread (0 without it) and so moved every scale."""
    rng = np.random.default_rng(1)
    lead = np.arange(1.0, 6.0)
    s = np.abs(rng.normal(1, 0.5, (200, 5))) * lead
    e = np.abs(rng.normal(0, 1, (200, 5))) * lead
    assert fit_spread_scale(e, s, lead, exponent="likelihood").exponent == 0.0
    z = np.zeros((200, 1))
    with pytest.raises(ValueError, match=r"lead_s: expected finite lead times > 0 \[s\] \(leave out the start"):
        fit_spread_scale(np.hstack([z, e]), np.hstack([z, s]), np.r_[0.0, lead], exponent="likelihood")
    with pytest.raises(ValueError, match="lead_s: expected finite lead times > 0"):
        fit_spread_scale(e, s, [1.0, 2.0, np.nan, 4.0, 5.0])


def test_fit_spread_scale_refuses_no_lead_and_leads_out_of_order_by_its_own_name():
    """No lead time (an empty calibration set of leads) was refused after the fit in the words
    of SpreadCalibration ('lead_s, scale and floor need one equal non-zero length'), leads out
    of order or repeated as '[SpreadCalibration]'; both now name fit_spread_scale's lead_s."""
    e, s = np.ones((30, 3)), np.ones((30, 3))
    with pytest.raises(ValueError, match=r"^fit_spread_scale: lead_s: expected at least one lead time, increasing"):
        fit_spread_scale(e[:, :0], s[:, :0], [])
    for lead in ([2.0, 1.0, 3.0], [1.0, 1.0, 2.0]):
        with pytest.raises(ValueError, match=r"^fit_spread_scale: lead_s: .*increasing, got \["):
            fit_spread_scale(e, s, lead)


@pytest.fixture(scope="module")
def fitted():
    m = DynamicModel("gunnerus")
    logs = [physics_log(m, seed=s, duration_s=600.0, t_shutdown_s=None, current=(0.2, 1.0)) for s in (3, 4)]
    cfg = CalibrationConfig(horizon_s=30.0, max_starts=200)
    return HybridPredictor(m.vessel, ensemble_config=TINY, calibration_config=cfg).fit(logs), logs


def test_fit_holds_back_the_end_and_forecasts_carry_the_calibrated_spread(fitted, tmp_path):
    hp, logs = fitted
    uncal = HybridPredictor(hp.model.vessel, ensemble_config=TINY,
                            calibration_config=CalibrationConfig(fraction=0.0)).fit(logs)
    assert uncal.calibration == {} and set(hp.calibration) == {"held", "known"}
    # the held-back 20 % are not trained on
    assert hp.training_info["n_rows"] < 0.85 * uncal.training_info["n_rows"]
    assert hp.training_info["calibration"]["n_starts"]["held"] >= 50
    # ... proof by change (the row count alone passed a fit that trained on the held-back end
    # and not on the start): each log moved from its held-back end on gives the same nets bit
    # for bit, and other scales
    from hybridship.predictors import as_log_arrays

    dp_only = hp.training_info["calibration"]["dp_only"]
    cuts = [hp._calibration_cut(as_log_arrays(x, hp.model.vessel), hp.calibration_config, dp_only) for x in logs]
    assert all(0.75 * len(x) < c < len(x) for x, c in zip(logs, cuts))          # the last part in time
    moved = []
    for x, c in zip(logs, cuts):
        x = x.copy()
        late = np.arange(len(x)) >= c
        x.loc[late, "north_m"] += 0.05 * np.arange(late.sum())
        x.loc[late, "heading_deg"] = (x.loc[late, "heading_deg"] + 0.1 * np.arange(late.sum())) % 360.0
        moved.append(x)
    hm = HybridPredictor(hp.model.vessel, ensemble_config=TINY, calibration_config=hp.calibration_config).fit(moved)
    for w, w_moved in zip(hp.ensemble.weights, hm.ensemble.weights):
        np.testing.assert_array_equal(w_moved, w)
    assert not np.allclose(hm.calibration["held"]["position"].scale, hp.calibration["held"]["position"].scale)
    starts = [300.0, 350.0]
    raw = hp.forecast(logs[0], starts, 40.0, calibrated=False)
    with pytest.warns(UserWarning, match="calibrated up to 30 s"):   # 40 s runs past the calibrated leads
        fc = hp.forecast(logs[0], starts, 40.0)
    np.testing.assert_allclose(fc.eta, raw.eta)
    expected = hp.calibration["held"]["position"].apply(raw.eta_std[..., 0], raw.lead_s)
    np.testing.assert_allclose(fc.eta_std[..., 0], expected)
    assert not np.allclose(fc.eta_std[:, 1:], raw.eta_std[:, 1:])
    # round trip through the model file keeps the scales
    back = HybridPredictor.load(hp.save(tmp_path / "m.npz"))
    with pytest.warns(UserWarning, match="calibrated up to 30 s"):
        np.testing.assert_allclose(back.forecast(logs[0], starts, 40.0).eta_std, fc.eta_std)
    assert back.calibration_config == hp.calibration_config
    # ... and their exponents
    import copy
    hq = copy.deepcopy(hp)
    c = hq.calibration["held"]["position"]
    hq.calibration["held"]["position"] = SpreadCalibration(c.lead_s, c.scale, c.floor, 0.3)
    back = HybridPredictor.load(hq.save(tmp_path / "m3.npz"))
    assert back.calibration["held"]["position"].exponent == 0.3
    with pytest.warns(UserWarning, match="calibrated up to 30 s"):
        np.testing.assert_allclose(back.forecast(logs[0], starts, 40.0).eta_std,
                                   hq.forecast(logs[0], starts, 40.0).eta_std)
    # quantiles come from the calibrated spread, about the forecast itself (z(0.95) = 1.6448536)
    q = fc.quantiles([0.05, 0.95])
    np.testing.assert_allclose(q[1] - q[0], 2 * 1.6448536 * fc.eta_std, rtol=1e-6)
    np.testing.assert_allclose(q[1], fc.eta + 1.6448536 * fc.eta_std, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(q[0], fc.eta - 1.6448536 * fc.eta_std, rtol=1e-6, atol=1e-9)
    # ... and each column of the table holds its own state's band (start by start, lead by lead)
    df = fc.to_frame(quantiles=[0.05, 0.95])
    assert {"north_q0.05_m", "east_q0.95_m", "heading_q0.95_deg"} <= set(df.columns)
    row = df.set_index(["start_time_s", "lead_s"]).loc[(350.0, 25.0)]
    k, j = 1, int(np.flatnonzero(fc.lead_s == 25.0)[0])
    assert abs(fc.eta[k, j, 0] - fc.eta[k, j, 1]) > 1.0 and fc.eta_std[k, j, 0] > 0  # north and east differ
    for name, i in (("north", 0), ("east", 1)):
        assert row[f"{name}_q0.95_m"] == pytest.approx(fc.eta[k, j, i] + 1.6448536 * fc.eta_std[k, j, i], rel=1e-6)
        assert row[f"{name}_q0.05_m"] == pytest.approx(fc.eta[k, j, i] - 1.6448536 * fc.eta_std[k, j, i], rel=1e-6)
    half_deg = np.degrees(1.6448536 * fc.eta_std[k, j, 2])
    assert row["heading_q0.95_deg"] - row["heading_deg"] == pytest.approx(half_deg, rel=1e-6)
    assert row["heading_deg"] - row["heading_q0.05_deg"] == pytest.approx(half_deg, rel=1e-6)


def test_cli_forecast_quantiles(fitted, tmp_path, capsys):
    from hybridship.cli import main
    from hybridship.logs.io import write_log

    hp, logs = fitted
    model = hp.save(tmp_path / "m.npz")
    write_log(logs[0], tmp_path / "log.csv.gz")
    out = tmp_path / "fc.csv"
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "log.csv.gz"), "--start-time", "300",
                 "--horizon-s", "20", "--quantiles", "0.05,0.95", "--out", str(out)]) == 0
    df = pd.read_csv(out)
    assert (df["north_q0.95_m"] >= df["north_q0.05_m"]).all()
    # the file holds the forecast the model makes (held commands, guard on, calibrated spread)
    # and its bands: the same numbers as forecast() and to_frame() give for that start
    want = hp.forecast(logs[0], [300.0], 20.0).to_frame(quantiles=[0.05, 0.95])
    assert len(df) == len(want) == 21
    for col in ("north_m", "east_m", "heading_deg", "north_std_m", "east_std_m", "north_q0.05_m", "north_q0.95_m",
                "east_q0.05_m", "east_q0.95_m", "heading_q0.05_deg", "heading_q0.95_deg"):
        np.testing.assert_allclose(df[col], want[col], rtol=1e-9, atol=1e-9, err_msg=col)
    np.testing.assert_allclose(df["east_q0.95_m"] - df["east_m"], 1.6448536 * df["east_std_m"], rtol=1e-6)
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "log.csv.gz"), "--start-time", "300",
                 "--quantiles", "0.05,1.5", "--out", str(out)]) == 2
    assert "--quantiles" in capsys.readouterr().err
    # probabilities that differ only past the sixth digit keep a column each; a repeat is refused
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "log.csv.gz"), "--start-time", "300",
                 "--horizon-s", "5", "--quantiles", "0.1000001,0.1000002,0.9999999", "--out", str(out)]) == 0
    assert {"north_q0.1000001_m", "north_q0.1000002_m", "north_q0.9999999_m"} <= set(pd.read_csv(out).columns)
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "log.csv.gz"), "--start-time", "300",
                 "--quantiles", "0.5,0.5", "--out", str(out)]) == 2
    assert "--quantiles" in capsys.readouterr().err
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "log.csv.gz"), "--start-time", "300",
                 "--quantiles", ",,,", "--out", str(out)]) == 2     # commas alone name no quantile
    assert "--quantiles" in capsys.readouterr().err
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "log.csv.gz"), "--start-time", "300",
                 "--quantiles", "0.05,,0.95", "--out", str(out)]) == 2  # a quantile left out, not skipped
    assert "--quantiles" in capsys.readouterr().err
    # another file (here a log) at --out is not replaced by a forecast
    other = tmp_path / "other_log.csv"
    write_log(logs[1], other)
    before = other.read_bytes()
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "log.csv.gz"), "--start-time", "300",
                 "--out", str(other)]) == 2
    assert "is not a forecast table" in capsys.readouterr().err and other.read_bytes() == before


def test_a_forecast_past_the_calibrated_leads_says_its_spread_is_not_calibrated_there(fitted, tmp_path, capsys):
    """Beyond the calibration's last lead its scale is held: the spread (and the quantiles)
    there were reported as calibrated without a word."""
    import warnings

    from hybridship.cli import main
    from hybridship.logs.io import write_log

    hp, logs = fitted
    with pytest.warns(UserWarning, match=r"^horizon_s: the spread is calibrated up to 30 s; beyond, the scale"):
        hp.forecast(logs[0], [300.0], 40.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hp.forecast(logs[0], [300.0], 30.0)                     # within the calibrated leads
        hp.forecast(logs[0], [300.0], 40.0, calibrated=False)   # the raw spread claims no calibration
    # fitted on logs with jittered time stamps, the last lead is 29.97 s for a 30-s horizon:
    # the same lead as a clean log's 30 s (within half a step), not a lead past the calibration
    import copy
    from dataclasses import replace

    jittered = copy.copy(hp)
    jittered.calibration = {mode: {k: replace(c, lead_s=c.lead_s * (29.97 / c.lead_s[-1])) for k, c in cals.items()}
                            for mode, cals in hp.calibration.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        jittered.forecast(logs[0], [300.0], 30.0)
    with pytest.warns(UserWarning, match="calibrated up to 29.97 s"):
        jittered.forecast(logs[0], [300.0], 31.0)
    write_log(logs[0], tmp_path / "log.csv")
    assert main(["forecast", "--model", str(hp.save(tmp_path / "m.npz")), "--log", str(tmp_path / "log.csv"),
                 "--start-time", "300", "--horizon-s", "40", "--out", str(tmp_path / "fc.csv")]) == 0
    assert capsys.readouterr().err.startswith("hybridship forecast: warning: --horizon-s: the spread is calibrated "
                                              "up to 30 s")


def test_forecast_options_and_quantiles_are_checked(fitted):
    hp, logs = fitted
    fc = hp.forecast(logs[0], [300.0], 10.0)
    for bad in (["a"], "0.5", [[0.1]], [0.5, 0.5], 1.0):
        with pytest.raises(ValueError, match="^quantiles"):
            fc.to_frame(quantiles=bad)
    assert "north_q0.5_m" in fc.to_frame(quantiles=0.5)
    for name, bad in (("guard", "no"), ("nets", "False"), ("calibrated", "false"), ("nets_after_stop", 1)):
        with pytest.raises(TypeError, match=f"^{name}: expected True or False"):
            hp.forecast(logs[0], [300.0], 10.0, **{name: bad})


def test_station_keeping_calibration_leaves_a_drift_start_raw():
    m = DynamicModel("gunnerus")
    logs = [physics_log(m, seed=s, duration_s=900.0, t_shutdown_s=700.0, current=(0.2, 1.0)) for s in (3, 4)]
    hp = HybridPredictor(m.vessel, ensemble_config=TINY,
                         calibration_config=CalibrationConfig(horizon_s=30.0, max_starts=100)).fit(logs)
    assert hp.training_info["calibration"]["dp_only"] and "held" in hp.calibration
    starts = [600.0, 750.0]                      # station keeping, then a drift after the failure at 700 s
    fc, raw = hp.forecast(logs[0], starts, 30.0), hp.forecast(logs[0], starts, 30.0, calibrated=False)
    assert not np.allclose(fc.eta_std[0, 1:], raw.eta_std[0, 1:])
    np.testing.assert_allclose(fc.eta_std[1], raw.eta_std[1])
    # ... and says so in that start's note (it was reported as if calibrated, and far too narrow)
    assert "spread: not calibrated" not in fc.notes[0]
    assert fc.notes[1].startswith("spread: not calibrated for a start after a failure")
    assert raw.notes == ("", "")                 # the raw spread asked for claims no calibration


# --- coverage with an interval over whole failures ---------------------------------------

def _grouped(inside_per_group, n_starts=20, n_h=2):
    """pred/truth/std (G, n_starts, n_h, 3) whose north/east errors are inside the 2-sigma band
    for a given share of each group's starts."""
    G = len(inside_per_group)
    std = np.ones((G, n_starts, n_h, 3))
    pred = np.zeros_like(std)
    for g, share in enumerate(inside_per_group):
        k = int(round((1 - share) * n_starts))
        pred[g, :k, :, :2] = 3.0                                   # outside 2 sigma
    return pred, np.zeros_like(std), std


def test_coverage_interval_matches_the_pooled_coverage_and_widens_with_few_failures():
    from hybridship.evaluation import metrics

    pred, truth, std = _grouped([1, 1, 1, 0.0, 1, 1, 1, 1, 1, 1])
    ci = metrics.coverage_interval(pred, truth, std, 2.0, seed=3)
    assert ci.shape == (2, 3)
    np.testing.assert_allclose(ci[:, 0], metrics.coverage(pred, truth, std)[:, 1])
    np.testing.assert_allclose(ci[:, 0], 0.9)
    # one failure in ten missed: the interval spans it, and does not pretend 200 starts are independent
    assert np.all(ci[:, 1] <= 0.8) and np.all(ci[:, 2] == 1.0)
    np.testing.assert_array_equal(ci, metrics.coverage_interval(pred, truth, std, 2.0, seed=3))
    many = metrics.coverage_interval(*_grouped([1, 1, 1, 0.0, 1, 1, 1, 1, 1, 1] * 10), 2.0, seed=3)
    assert np.all(many[:, 2] - many[:, 1] < 0.5 * (ci[:, 2] - ci[:, 1]))


def test_coverage_interval_is_a_point_when_every_failure_agrees_and_undefined_for_one():
    from hybridship.evaluation import metrics

    ci = metrics.coverage_interval(*_grouped([0.5] * 6), 2.0)
    np.testing.assert_allclose(ci, 0.5)
    one = metrics.coverage_interval(*_grouped([0.5]), 2.0)
    np.testing.assert_allclose(one[:, 0], 0.5)
    assert np.isnan(one[:, 1:]).all()


def test_grouped_coverage_pools_groups_of_different_sizes_by_their_counts():
    from hybridship.evaluation import metrics

    hits = np.array([[90.0], [0.0], [5.0]])
    counts = np.array([100, 10, 5])
    ci = metrics.grouped_coverage_interval(hits, counts, seed=1)
    np.testing.assert_allclose(ci[0, 0], 95.0 / 115.0)
    assert ci[0, 1] < ci[0, 0] < ci[0, 2]
    np.testing.assert_array_equal(ci, metrics.grouped_coverage_interval(hits, counts, seed=1))


def test_grouped_coverage_interval_stays_within_the_groups_coverages():
    """Property: for any groups (sizes, hits), the pooled coverage is the hits over the counts,
    and the interval is ordered and never leaves the range of the groups' own coverages (a
    resample's coverage is a count-weighted mean of them)."""
    from hypothesis import example, given, settings
    from hypothesis import strategies as st

    from hybridship.evaluation import metrics

    @settings(max_examples=40, deadline=None)
    @given(st.lists(st.tuples(st.integers(1, 50), st.floats(0.0, 1.0)), min_size=2, max_size=12))
    @example([(43, 0.125), (43, 0.125)])               # found by a random run: lo above hi by one ulp
    def check(groups):
        counts = np.array([n for n, _ in groups])
        hits = np.array([[round(f * n)] for n, f in groups], dtype=float)
        cov, lo, hi = metrics.grouped_coverage_interval(hits, counts, n_resamples=500)[0]
        np.testing.assert_allclose(cov, hits.sum() / counts.sum())
        own = hits[:, 0] / counts
        # (groups of one coverage: the quantiles of a constant differ in the last bit)
        assert own.min() - 1e-12 <= lo <= hi + 1e-12 and hi <= own.max() + 1e-12

    check()


def test_sharpness_is_the_band_width_plus_the_penalty_for_misses():
    """Hand values: a miss by 1 m outside a +-2 sigma band costs (2 / alpha) m on top of its width."""
    from types import SimpleNamespace

    from hybridship.evaluation.manoeuvre import sharpness_table
    from hybridship.residual.calibration import GAUSS_COVERAGE

    alpha = 1 - GAUSS_COVERAGE[2.0]
    err = np.zeros((2, 1, 4))
    err[0, 0, :2] = [0.5, 3.0]                       # inside; 1 m beyond the band of 2 x 1 m
    err[1, 0, :2] = [0.0, 0.0]
    sd = np.ones((2, 1, 2))
    runs = [SimpleNamespace(kind="zigzag"), SimpleNamespace(kind="berthing")]
    with pytest.raises(ValueError, match="sigma: expected 1 or 2"):
        sharpness_table({}, {}, runs, (30.0,), sigma=3.0)
    t = sharpness_table({("hybrid", "known"): [err[:1], err[1:]]}, {("hybrid", "known"): [sd[:1], sd[1:]]}, runs,
                        (30.0,))
    row = t.set_index("kind").loc[["zigzag", "berthing", "all"]]
    np.testing.assert_allclose(row.mean_std_m, 1.0)
    np.testing.assert_allclose(row.interval_score_m, [4 + (2 / alpha) / 2, 4.0, 4 + (2 / alpha) / 4])


def test_after_stop_scales_pool_north_and_east_at_the_default_two_sigma_level():
    from hybridship.predictors.hybrid import after_stop_scales
    from hybridship.residual.calibration import GAUSS_COVERAGE, CalibrationConfig, fit_spread_scale

    assert CalibrationConfig().fit_kwargs == dict(sigma=2.0, coverage=GAUSS_COVERAGE[2.0], floor_quantile=0.1,
                                                  exponent=1.0)
    rng = np.random.default_rng(2)
    lead = np.array([1.0, 2.0])
    errors = []
    for _ in range(3):
        sd = rng.uniform(0.5, 1.5, (20, 2, 3))
        e = np.abs(rng.normal(size=(20, 2, 3))) * sd * np.array([1.0, 5.0, 0.1])   # east errs most
        errors.append((e, sd, lead))
    got = after_stop_scales(errors, CalibrationConfig())
    e = np.concatenate([x[0] for x in errors])
    sd = np.concatenate([x[1] for x in errors])
    pos = fit_spread_scale(np.concatenate([e[..., 0], e[..., 1]]), np.concatenate([sd[..., 0], sd[..., 1]]), lead)
    np.testing.assert_array_equal(got["position"].scale, pos.scale)
    np.testing.assert_array_equal(got["heading"].scale, fit_spread_scale(e[..., 2], sd[..., 2], lead).scale)


def test_after_stop_scales_refuse_no_logs_and_leave_one_out_a_single_log_by_name():
    """No logs' errors, and a single log left out (which leaves none to calibrate on), failed
    in Python's words ('min() arg is an empty sequence')."""
    from hybridship.predictors.hybrid import after_stop_scales, leave_one_out_after_stop_scales

    one = (np.ones((30, 2, 3)), np.ones((30, 2, 3)), np.array([1.0, 2.0]))
    with pytest.raises(ValueError, match=r"^after_stop_scales: errors: expected the errors after a failure of at "
                                         r"least one log \(after_stop_errors\), got none"):
        after_stop_scales([], CalibrationConfig())
    with pytest.raises(ValueError, match=r"^leave_one_out_after_stop_scales: errors: expected the errors after a "
                                         r"failure of at least two logs .*, got 1"):
        leave_one_out_after_stop_scales([one], CalibrationConfig())
    assert after_stop_scales([one], CalibrationConfig())["position"].lead_s.tolist() == [1.0, 2.0]
    assert len(leave_one_out_after_stop_scales([one, one], CalibrationConfig())) == 2


def test_after_stop_scales_pool_logs_of_different_steps_at_equal_lead_times():
    """A 10-Hz log's errors at 0.1..2 s were pooled with a 1-Hz log's at 1..20 s, column by
    column: the 1-Hz lead times are kept, and the 10-Hz log gives its errors at those times."""
    from hybridship.predictors.hybrid import after_stop_scales

    rng = np.random.default_rng(3)
    coarse, fine = np.arange(1, 21) * 1.0, np.arange(1, 201) * 0.1
    errors = []
    for lead in (coarse, fine, coarse):
        sd = np.ones((30, lead.size, 3))
        errors.append((np.abs(rng.normal(size=sd.shape)) * lead[None, :, None], sd, lead))   # errors grow with lead
    got = after_stop_scales(errors, CalibrationConfig())
    on_coarse = [(e[:, 9::10] if e.shape[1] == 200 else e, s[:, :20], coarse) for e, s, _ in errors]
    want = after_stop_scales(on_coarse, CalibrationConfig())
    np.testing.assert_array_equal(got["position"].lead_s, coarse)
    np.testing.assert_array_equal(got["position"].scale, want["position"].scale)
    np.testing.assert_array_equal(got["heading"].scale, want["heading"].scale)


def test_apply_and_coverage_of_refuse_text_bad_shapes_and_silent_nans_by_name():
    cal = SpreadCalibration([1.0, 2.0], [2.0, 3.0], [0.1, 0.1])
    lead = np.array([1.0, 2.0])
    # before: numpy's "ufunc 'maximum' did not contain a loop with signature matching types"
    with pytest.raises(TypeError, match="apply: std: expected an array of real numbers"):
        cal.apply(["a", "b"], lead)
    with pytest.raises(TypeError, match="apply: lead_s: expected an array of real numbers"):
        cal.apply([1.0, 2.0], ["1", "2"])
    with pytest.raises(ValueError, match="apply: std: expected the lead time on the last axis"):
        cal.apply(np.ones((1, 2)), np.array([1.0, 2.0, 3.0]))
    with pytest.raises(ValueError, match="apply: lead_s: expected a 1-D array of finite lead times"):
        cal.apply([1.0, 1.0], [1.0, np.nan])        # before: the raw spread came back, uncalibrated
    with pytest.raises(ValueError, match="apply: std: expected standard deviations >= 0"):
        cal.apply([-1.0, 1.0], lead)                # before: floored to a positive spread
    np.testing.assert_allclose(cal.apply([1.0, np.nan], lead), [2.0, np.nan])   # a NaN passes as documented
    # before: "could not convert string to float" or text "1" read as 1
    with pytest.raises(TypeError, match="coverage_of: abs_err: expected an array of real numbers"):
        coverage_of([["a"]], [[1.0]])
    with pytest.raises(TypeError, match="coverage_of: std: expected an array of real numbers"):
        coverage_of([[1.0]], [["1"]])
    with pytest.raises(TypeError, match="coverage_of: sigmas: expected an array of real numbers"):
        coverage_of([[1.0]], [[1.0]], ("a",))
    # before: broadcast silently, an AxisError, a NaN coverage with a warning, or a NaN counted as a miss
    for e, s in (([[1.0, 2.0]], [[1.0]]), ([1.0, 2.0], [1.0, 1.0]), (np.zeros((0, 2)), np.zeros((0, 2)))):
        with pytest.raises(ValueError, match="coverage_of: abs_err and std: expected one shape"):
            coverage_of(e, s)
    with pytest.raises(ValueError, match="coverage_of: abs_err: NaN or inf"):
        coverage_of([[np.nan]], [[1.0]])
    with pytest.raises(ValueError, match="coverage_of: std: expected values >= 0"):
        coverage_of([[1.0]], [[-1.0]])
    with pytest.raises(ValueError, match="coverage_of: sigmas: expected a list"):
        coverage_of([[1.0]], [[1.0]], 2.0)
    np.testing.assert_allclose(coverage_of([[0.5, 3.0], [1.5, 1.0]], np.ones((2, 2))), [[0.5, 1.0], [0.5, 0.5]])


def test_calibrated_std_returns_floats_and_refuses_bad_input_by_name():
    """An integer spread came back as integers (a scale of 2.5 gave 2), a fourth column was
    returned as uninitialised memory, a nested list failed in Python's words ('list indices
    must be integers') and the other problems in SpreadCalibration.apply's, on its axes."""
    hp = HybridPredictor("gunnerus")
    c = SpreadCalibration([1.0, 2.0], [2.5, 2.5], [0.0, 0.0])
    hp.calibration = {"held": {"position": c, "heading": c}}
    lead = np.array([0.0, 1.0, 2.0])
    out = hp.calibrated_std(np.ones((1, 3, 3), dtype=int), lead, "held")
    assert out.dtype == float
    np.testing.assert_array_equal(out[0], [[1.0] * 3, [2.5] * 3, [2.5] * 3])
    np.testing.assert_array_equal(hp.calibrated_std([[[1.0] * 3] * 3], lead, "held"), out)
    for std, why in ((np.ones((1, 3, 4)), "shape"), (np.ones((1, 2, 3)), "shape"), (np.ones(3), "shape"),
                     (-np.ones((1, 3, 3)), "standard deviations >= 0")):
        with pytest.raises(ValueError, match=f"^calibrated_std: std: expected .*{why}"):
            hp.calibrated_std(std, lead, "held")
    with pytest.raises(TypeError, match="^calibrated_std: std: expected an array of real numbers"):
        hp.calibrated_std(np.full((1, 3, 3), "1"), lead, "held")
    for bad in ([0.0, 1.0, np.nan], [0.0, -1.0, 2.0], np.ones((3, 1))):
        with pytest.raises(ValueError, match=r"^calibrated_std: lead_s: expected a 1-D array of finite lead times"):
            hp.calibrated_std(np.ones((1, 3, 3)), bad, "held")
    with pytest.raises(ValueError, match=r"^commands: expected one of \['held'\], got \['held'\]"):
        hp.calibrated_std(np.ones((1, 3, 3)), lead, ["held"])


def test_after_stop_window_does_not_depend_on_the_order_of_logs_of_different_steps(fitted, monkeypatch):
    """The window of starts the after-stop calibration was fitted on (``starts_within_s``,
    which decides which forecast starts count as late) and its horizon came from the first
    log: 2 s or 20 s for the same 10-Hz and 1-Hz failures, by their order."""
    import copy

    rng = np.random.default_rng(5)
    coarse, fine = np.arange(1, 61) * 1.0, np.arange(1, 601) * 0.1
    errs = [(np.abs(rng.normal(size=(20, lead.size, 3))), np.ones((20, lead.size, 3)), lead) for lead in (fine, coarse)]
    infos = []
    for order in (errs, errs[::-1]):
        hp = copy.deepcopy(fitted[0] if isinstance(fitted, tuple) else fitted)
        monkeypatch.setattr(hp, "after_stop_errors", lambda logs, late=False, **kw: [] if late else order)
        hp.calibrate_after_stop([None, None])
        infos.append(hp.training_info["calibration"]["after_stop"])
    assert infos[0] == infos[1]
    assert infos[0]["starts_within_s"] == 20.0 and infos[0]["horizon_s"] == 60.0
