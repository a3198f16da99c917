"""The spread after a failure from the load's variability in the station keeping before it."""

from __future__ import annotations

import numpy as np
import pytest

from hybridship.predictors import HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import EnvironmentConfig, EnvironmentEstimator
from hybridship.residual.load_variability import held_load_rows, held_load_spread, unexplained_load_std
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=3, hidden=4, max_epochs=2, patience=1, seed=0)


def _blocky_load(n: int, sigma_N: float, dof: int, *, block: int = 30, seed: int = 0) -> np.ndarray:
    """A 1 kN sway load plus, in ``dof``, levels of std ``sigma_N`` [N] held for ``block`` steps
    (a ship at low speed, as in station keeping)."""
    rng = np.random.default_rng(seed)
    levels = np.zeros((-(-n // block), 3))
    levels[:, dof] = sigma_N * rng.standard_normal(len(levels))
    return np.repeat(levels, block, axis=0)[:n] + np.array([0.0, 1000.0, 0.0])


def _sigma_b(model, tau, *, window_s: float = 600.0, block_s: float = 30.0) -> np.ndarray:
    """sigma_b over the last ``window_s`` of an idle ship under the load ``tau`` (all station keeping)."""
    log = physics_log(model, duration_s=len(tau), t_shutdown_s=None, seed=1, tau_ext_N=tau, wind=(0.0, 0.0),
                      rpm_scale=0.0)
    a = as_log_arrays(log, model.vessel)
    rows = held_load_rows(a.dp_active, a.time_s, len(a.time_s), 1, window_s, a.dt_s)
    est = EnvironmentEstimator(model).run(a, rows, first_row=0)
    return unexplained_load_std(model, a, est, int(block_s))


def test_held_load_rows_are_station_keeping_rows_before_the_start():
    dp = np.array([1] * 50 + [0] * 10)
    rows = held_load_rows(dp, np.arange(60.0), 55, 2, 20.0, 1.0)
    assert rows.max() == 49 and np.all(np.diff(rows) == 2) and rows.size == 10
    assert np.all(dp[rows] == 1)
    assert held_load_rows(np.zeros(10, int), np.arange(10.0), 5, 1, 100.0, 1.0).size == 0


def test_held_load_rows_span_the_window_in_seconds_across_a_gap():
    """A 30-s gap in a 40-s window leaves the 20 s of rows after it (the window was 40 rows,
    70 s of log); an evenly sampled log keeps round(window_s / dt_s) rows, at 10 Hz too."""
    t = np.arange(100.0)
    t[80:] += 30.0
    np.testing.assert_array_equal(held_load_rows(np.ones(100, int), t, 100, 1, 40.0, 1.0), np.arange(80, 100))
    t10 = np.arange(7000) * 0.1
    rows = held_load_rows(np.ones(7000, int), t10, 7000, 10, 600.0, 0.1)
    assert rows.size == 600 and rows[-1] == 6999 and rows[0] == 6999 - 5990


def test_a_constant_load_has_no_variability_and_a_varying_one_is_measured(model):
    """A constant load leaves almost nothing unexplained; a load whose level changes every
    30 s with a standard deviation sigma is measured as about sigma / M in that DOF, and
    twice the variation gives twice sigma_b."""
    n = 1200
    flat = _sigma_b(model, _blocky_load(n, 0.0, 0))
    sway = _sigma_b(model, _blocky_load(n, 1500.0, 1))
    sway2 = _sigma_b(model, _blocky_load(n, 3000.0, 1))
    want = abs(model.arrays.m_inv[1, 1]) * 1500.0
    assert 0.4 * want < sway[1] < 1.3 * want
    assert flat[1] < 0.15 * sway[1]
    assert 1.7 < sway2[1] / sway[1] < 2.3


def test_held_load_rows_and_the_variability_refuse_counts_that_are_not_whole_numbers(model):
    """A fractional start row failed in Python's words ('slice indices must be integers'), a
    step of 0 in its division by zero and one of 1.5 in numpy's indexing; a block of 0 or -3
    rows gave a variability of exactly zero without a word and one of 30.5 failed in numpy's
    indexing; each is now a ValueError naming the argument."""
    from hybridship.residual.load_variability import unexplained_load_std_windows

    dp, t = np.ones(100, int), np.arange(100.0)
    for start, step, why in ((5.5, 1, "start: expected a whole number >= 0"),
                             (-1, 1, "start: expected a whole number >= 0"),
                             (101, 1, "start: expected a row of the log, at most 100"),
                             (50, 0, "step: expected a whole number >= 1"),
                             (50, 1.5, "step: expected a whole number >= 1")):
        with pytest.raises(ValueError, match=f"^held_load_rows: {why}"):
            held_load_rows(dp, t, start, step, 30.0, 1.0)
    for window_s, dt_s, name in ((-1.0, 1.0, "window_s"), (30.0, 0.0, "dt_s"), ("30", 1.0, "window_s")):
        with pytest.raises((TypeError, ValueError), match=f"^held_load_rows: {name}: "):
            held_load_rows(dp, t, 50, 1, window_s, dt_s)
    with pytest.raises(ValueError, match=r"^held_load_rows: dp_active, time_s: expected two 1-D arrays of one "
                                         r"length, got shapes \(100,\) and \(99,\)"):
        held_load_rows(dp, t[:99], 50, 1, 30.0, 1.0)
    np.testing.assert_array_equal(held_load_rows(dp, t, np.int64(50), np.int32(2), 10, 1), np.arange(41, 50, 2))
    log = physics_log(model, duration_s=300, t_shutdown_s=None, seed=1, rpm_scale=0.0, wind=(0.0, 0.0))
    a = as_log_arrays(log, model.vessel)
    est = EnvironmentEstimator(model).run(a, np.arange(300), first_row=0)
    for block in (0, 30.5, -3, True):
        with pytest.raises(ValueError, match="^unexplained_load_std: block_rows: expected a whole number >= 1"):
            unexplained_load_std(model, a, est, block)
        with pytest.raises(ValueError, match="^unexplained_load_std_windows: block_rows: expected a whole number"):
            unexplained_load_std_windows(model, a, est, [0], [300], block)
    for first, stop, why in (([0.5], [300], "first, stop: expected whole numbers"),
                             ([0, 0], [300], "first, stop: expected two 1-D arrays of one length"),
                             ([10], [5], "first, stop: expected 0 <= first <= stop <= 300"),
                             ([0], [301], "first, stop: expected 0 <= first <= stop <= 300")):
        with pytest.raises(ValueError, match=f"^unexplained_load_std_windows: {why}"):
            unexplained_load_std_windows(model, a, est, first, stop, 30)
    np.testing.assert_array_equal(unexplained_load_std_windows(model, a, est, np.array([0]), np.array([300]), 30)[0],
                                  unexplained_load_std(model, a, est, np.int64(30)))


def test_held_load_spread_grows_with_the_square_of_the_lead():
    s = held_load_spread(np.array([[3e-3, 4e-3, 1e-4]]), np.array([0.0, 10.0, 20.0]))
    pos = np.sqrt(0.5 * (9e-6 + 16e-6))
    np.testing.assert_allclose(s[0, :, 0], 0.5 * pos * np.array([0.0, 100.0, 400.0]))
    np.testing.assert_allclose(s[0, :, 1], s[0, :, 0])
    np.testing.assert_allclose(s[0, 2, 2], 0.5 * 1e-4 * 400.0)


def test_held_load_spread_refuses_bad_input_by_name():
    """One start's sigma_b as a flat row failed in numpy's indexing words, a fourth column was
    dropped, text was read as numbers, a negative sigma_b gave a negative yaw spread, a
    negative lead the spread of a positive one and a NaN a NaN spread, all without a word."""
    sb, lead = np.array([[3e-3, 4e-3, 1e-4]]), np.array([0.0, 10.0])
    for sigma_b in (sb[0], np.c_[sb, [[1.0]]], np.zeros((1, 2))):
        with pytest.raises(ValueError, match=r"^held_load_spread: sigma_b: expected the shape \(S, 3\)"):
            held_load_spread(sigma_b, lead)
    for sigma_b in (-sb, sb * np.nan, sb * np.inf):
        with pytest.raises(ValueError, match=r"^held_load_spread: sigma_b: expected finite values >= 0"):
            held_load_spread(sigma_b, lead)
    with pytest.raises(TypeError, match=r"^held_load_spread: sigma_b: expected an array of real numbers"):
        held_load_spread(np.array([["1", "2", "3"]]), lead)
    for bad in ([-10.0], [np.nan], [[1.0, 2.0]]):
        with pytest.raises(ValueError, match=r"^held_load_spread: lead_s: expected a 1-D array of finite lead times"):
            held_load_spread(sb, bad)
    with pytest.raises(TypeError, match=r"^held_load_spread: lead_s: expected an array of real numbers"):
        held_load_spread(sb, ["10"])
    assert held_load_spread(np.zeros((0, 3)), lead).shape == (0, 2, 3)
    np.testing.assert_array_equal(held_load_spread(sb.tolist(), [0, 10]), held_load_spread(sb, lead))


def _reference_sigma_b(acc, nu, t, block):
    """sigma_b of one window by its definition: reshape into blocks ending at the window's
    end, velocity change between block ends less the block's mean model acceleration."""
    nb = len(t) // block
    if nb < 3:
        return np.zeros(3)
    keep = slice(len(t) - nb * block, None)
    acc, nu, t = acc[keep].reshape(nb, block, 3), nu[keep].reshape(nb, block, 3), t[keep].reshape(nb, block)
    missed = np.diff(nu[:, -1], axis=0) / np.diff(t[:, -1])[:, None] - acc[1:].mean(axis=1)
    return missed.std(axis=0, ddof=1)


def test_batched_windows_equal_each_window_by_its_definition(model, drift_log):
    """Overlapping windows of every length (fewer than three blocks give zeros), evaluated in
    one batch, equal each window's block statistics computed on its own."""
    from hybridship.residual.environment import current_input, external_accel, thrust_error_accel
    from hybridship.residual.environment import CUR, LOAD, THR
    from hybridship.residual.load_variability import unexplained_load_std_windows

    a = as_log_arrays(drift_log, model.vessel)
    rows = np.arange(100, 1190, 1)
    est = EnvironmentEstimator(model).run(a, rows, first_row=0)
    rng = np.random.default_rng(0)
    stop = rng.integers(20, len(rows) + 1, 40)
    first = np.maximum(0, stop - rng.integers(1, 700, 40))
    block = 30
    got = unexplained_load_std_windows(model, a, est, first, stop, block)
    x = est.x
    ext = external_accel(x[:, 2], x[:, LOAD], 0.0, 0.0) + thrust_error_accel(
        model, est.thrust_error_model, x[:, 0:3], x[:, 3:6], a.rpm[rows], a.azimuth_rad[rows], a.wind[rows],
        x[:, CUR], x[:, THR])
    acc = model.acceleration(x[:, 0:3], x[:, 3:6], rpm=a.rpm[rows], azimuth_rad=a.azimuth_rad[rows],
                             wind=a.wind[rows], current=current_input(x[:, CUR]), accel_ext=ext)
    for k in range(len(stop)):
        w = slice(first[k], stop[k])
        np.testing.assert_allclose(got[k], _reference_sigma_b(acc[w], x[w, 3:6], a.time_s[rows][w], block),
                                   rtol=1e-9, atol=1e-15)
    assert np.any((stop - first) // block < 3) and np.all(got[(stop - first) // block < 3] == 0)
    assert np.all(got[(stop - first) // block >= 3] > 0)
    np.testing.assert_allclose(unexplained_load_std(model, a, est.take(slice(first[0], stop[0])), block), got[0])


@pytest.fixture(scope="module")
def drift_log(model):
    n = 1500
    return physics_log(model, duration_s=n, t_shutdown_s=1200, seed=2, tau_ext_N=_blocky_load(n, 3000.0, 1),
                       wind=(5.0, 0.5), rpm_scale=0.3)


def test_forecast_spread_after_a_failure_includes_the_held_load(model, drift_log):
    """Starts after the failure get the held-load term on top of the ensemble's spread (it can
    be switched off); starts during station keeping do not; the term uses no sample after
    the start."""
    from hybridship.residual.calibration import CalibrationConfig

    ens = CalibrationConfig(station_keeping_spread="ensemble")      # the members' spread on station
    on = HybridPredictor(model.vessel, ensemble_config=TINY, calibration_config=ens).fit([drift_log], dp_only=True)
    off = HybridPredictor(model.vessel, ensemble_config=TINY, calibration_config=ens,
                          environment_config=EnvironmentConfig(held_load_window_s=0.0)).fit([drift_log], dp_only=True)
    starts = [1100.0, 1205.0]
    f_on = on.forecast(drift_log, starts, 60.0, calibrated=False)
    f_off = off.forecast(drift_log, starts, 60.0, calibrated=False)
    np.testing.assert_allclose(f_on.eta, f_off.eta)                      # the mean is untouched
    np.testing.assert_allclose(f_on.eta_std[0], f_off.eta_std[0])         # during station keeping
    assert np.all(f_on.eta_std[1, -1, :2] > 1.2 * f_off.eta_std[1, -1, :2])
    # "on top" is the independent sum sqrt(s^2 + held^2), held from the station keeping
    # before the failure (computed here from the filter directly); a plain sum s + held, or a
    # held term of the wrong window, also passed the bound above
    a = as_log_arrays(drift_log, model.vessel)
    i = int(np.searchsorted(a.time_s, starts[1]))
    c = on.environment_config
    est = on._run_estimator(a, np.array([i]), held_load_rows(a.dp_active, a.time_s, i, 1, c.held_load_window_s,
                                                             a.dt_s))[1]
    held = held_load_spread(unexplained_load_std(on.model, a, est, int(c.held_load_block_s))[None], f_on.lead_s)[0]
    np.testing.assert_allclose(f_on.eta_std[1], np.sqrt(f_off.eta_std[1] ** 2 + held ** 2), rtol=1e-9)
    later = drift_log.copy()
    later.loc[later.time_s > 1205.0, ["north_m", "east_m"]] += 100.0
    f_later = on.forecast(later, [1205.0], 60.0, calibrated=False)
    np.testing.assert_allclose(f_later.eta_std[0], f_on.eta_std[1])


def test_the_held_load_window_is_ten_minutes_of_log_time_across_a_gap(model, drift_log):
    """The held-load window was counted in rows: 600 rows of a log with a 99-s gap reached
    back 699 s. It is now the station keeping of the last 600 s before the failure, a gap
    leaving fewer rows (here 1000-1199 s and 600-900 s, computed from the filter directly)."""
    from hybridship.residual.calibration import CalibrationConfig

    ens = CalibrationConfig(station_keeping_spread="ensemble")
    on = HybridPredictor(model.vessel, ensemble_config=TINY, calibration_config=ens).fit([drift_log], dp_only=True)
    off = HybridPredictor(model.vessel, ensemble_config=TINY, calibration_config=ens,
                          environment_config=EnvironmentConfig(held_load_window_s=0.0)).fit([drift_log], dp_only=True)
    gapped = drift_log[(drift_log.time_s <= 900.0) | (drift_log.time_s >= 1000.0)].reset_index(drop=True)
    f_on = on.forecast(gapped, [1205.0], 60.0, calibrated=False)
    f_off = off.forecast(gapped, [1205.0], 60.0, calibrated=False)
    a = as_log_arrays(gapped, model.vessel)
    rows = np.flatnonzero((a.time_s >= 600.0) & (a.time_s < 1200.0))
    assert np.all(a.dp_active[rows] == 1) and rows.size == 501
    est = on._run_estimator(a, np.array([int(np.searchsorted(a.time_s, 1205.0))]), rows)[1]
    c = on.environment_config
    held = held_load_spread(unexplained_load_std(on.model, a, est, int(c.held_load_block_s))[None], f_on.lead_s)[0]
    np.testing.assert_allclose(f_on.eta_std[0], np.sqrt(f_off.eta_std[0] ** 2 + held ** 2), rtol=1e-9)


def test_station_keeping_spread_held_load_option(model, drift_log, tmp_path):
    """With ``station_keeping_spread="held_load"`` a start during station keeping reports
    ``held_load_spread`` of the load's variability over the window before it (computed here
    from the filter directly), uses no sample after the start, and starts after the failure
    and the mean forecast are as with the default; the option survives the model file."""
    from hybridship.residual.calibration import CalibrationConfig

    assert CalibrationConfig().station_keeping_spread == "held_load"          # the default
    held = HybridPredictor(model.vessel, ensemble_config=TINY).fit([drift_log], dp_only=True)
    base = HybridPredictor(model.vessel, ensemble_config=TINY,
                           calibration_config=CalibrationConfig(station_keeping_spread="ensemble")
                           ).fit([drift_log], dp_only=True)
    starts = [900.0, 1100.0, 1205.0]
    f = held.forecast(drift_log, starts, 60.0, calibrated=False)
    g = base.forecast(drift_log, starts, 60.0, calibrated=False)
    np.testing.assert_allclose(f.eta, g.eta)
    np.testing.assert_allclose(f.eta_std[2], g.eta_std[2])               # after the failure: unchanged
    a = as_log_arrays(drift_log, model.vessel)
    c = held.environment_config
    for k, t in enumerate(starts[:2]):
        i = int(np.searchsorted(a.time_s, t))
        rows = held_load_rows(a.dp_active, a.time_s, i, 1, c.held_load_window_s, a.dt_s)
        est = held._run_estimator(a, np.array([i]), rows)[1]
        sb = unexplained_load_std(held.model, a, est, int(c.held_load_block_s))
        np.testing.assert_allclose(f.eta_std[k], held_load_spread(sb[None], f.lead_s)[0], rtol=1e-9)
        assert np.all(f.eta_std[k, -1] > 0)
    later = drift_log.copy()
    later.loc[later.time_s > 1100.0, ["north_m", "east_m"]] += 100.0
    np.testing.assert_allclose(held.forecast(later, [1100.0], 60.0, calibrated=False).eta_std[0], f.eta_std[1])
    cal_pos = held.calibration["held"]["position"]                             # calibrated on that spread
    np.testing.assert_allclose(held.forecast(drift_log, starts[:1], 60.0).eta_std[0, :, 0],
                               cal_pos.apply(f.eta_std[0, :, 0], f.lead_s))
    early_fc = held.forecast(drift_log, [40.0, 900.0], 60.0, calibrated=False)       # < 3 blocks before 40 s
    early = early_fc.eta_std[0]
    np.testing.assert_allclose(early, base.forecast(drift_log, [40.0], 60.0, calibrated=False).eta_std[0])
    assert np.all(early[1:, :2] > 0)                                          # the members' spread, not zero
    assert "from the members'" in early_fc.notes[0] and "from the members'" not in early_fc.notes[1]  # and says so
    assert all("from the members'" not in n for n in g.notes)      # the option that asks for the members' spread
    over = HybridPredictor(model.vessel, ensemble_config=TINY).fit(
        [drift_log], dp_only=True, calibration=CalibrationConfig(station_keeping_spread="ensemble"))
    assert over.calibration_config.station_keeping_spread == "ensemble"       # fit's override is what forecasts use
    np.testing.assert_allclose(over.forecast(drift_log, starts[:1], 60.0, calibrated=False).eta_std, g.eta_std[:1])
    off = HybridPredictor(model.vessel, ensemble_config=TINY,      # no held-load window: the members' spread
                          environment_config=EnvironmentConfig(held_load_window_s=0.0)).fit([drift_log], dp_only=True)
    no_window = off.forecast(drift_log, starts[:1], 60.0, calibrated=False).eta_std[0]
    np.testing.assert_allclose(no_window, g.eta_std[0])
    path = held.save(tmp_path / "m.npz")
    back = HybridPredictor.load(path)
    assert back.calibration_config.station_keeping_spread == "held_load"
    np.testing.assert_allclose(back.forecast(drift_log, starts, 60.0).eta_std, held.forecast(drift_log, starts, 60.0).eta_std)


def test_station_keeping_spread_is_validated():
    from hybridship.residual.calibration import CalibrationConfig

    with pytest.raises(ValueError, match="station_keeping_spread"):
        CalibrationConfig(station_keeping_spread="weather")


def test_the_filter_window_must_cover_the_held_load_window():
    from hybridship.predictors import HybridPredictor
    from hybridship.residual.environment import EnvironmentConfig

    with pytest.raises(ValueError, match="environment_window_s: must be at least .*held_load_window_s = 600 s"):
        HybridPredictor("gunnerus", environment_window_s=300.0)
    # without the held load, or without the estimator, a short window is fine
    HybridPredictor("gunnerus", environment_window_s=300.0,
                    environment_config=EnvironmentConfig(held_load_window_s=0.0))
    HybridPredictor("gunnerus", environment_window_s=300.0, environment="mean")
    HybridPredictor("gunnerus", environment_window_s=600.0)


def test_held_load_rows_end_before_the_start_during_station_keeping():
    """A start during station keeping measures the load on the rows before it, not on its own row."""
    dp = np.ones(100, int)
    rows = held_load_rows(dp, np.arange(100.0), 60, 1, 30.0, 1.0)
    assert rows.max() == 59 and rows.min() == 30 and rows.size == 30


def test_a_start_within_one_filter_step_of_the_log_start_measures_no_held_load_after_it(model):
    """On station the held-load window ends one filter step before the start; a start less
    than a step into the log (filter_step_s 5 s at 10 Hz, a start at 2 s) ended it at a
    negative row, which sliced the log from its end: the spread came from the rows after the
    start. It now has no station keeping before it, so the members' spread, and says so."""
    log = physics_log(model, duration_s=400, t_shutdown_s=None, seed=2, dt_s=0.1)
    hp = HybridPredictor(model.vessel, ensemble_config=TINY,
                         environment_config=EnvironmentConfig(filter_step_s=5.0)).fit([log])
    fc = hp.forecast(log, [2.0], 60.0, calibrated=False)
    assert "from the members'" in fc.notes[0]
    later = log.copy()
    after = later.time_s > 2.0
    later.loc[after, ["u_m_s", "v_m_s"]] += 0.05 * np.random.default_rng(0).standard_normal((int(after.sum()), 2))
    np.testing.assert_array_equal(hp.forecast(later, [2.0], 60.0, calibrated=False).eta_std, fc.eta_std)


def test_held_load_rows_leave_out_an_earlier_drift_in_the_window():
    """A window reaching back over an earlier stretch without station keeping keeps only the
    station-keeping rows: a drift's estimates do not measure the held load."""
    dp = np.array([1] * 10 + [0] * 10 + [1] * 30 + [0] * 5)
    t = np.arange(dp.size, dtype=float)
    rows = held_load_rows(dp, t, 52, 1, 40.0, 1.0)
    np.testing.assert_array_equal(rows, np.arange(20, 50))
    np.testing.assert_array_equal(held_load_rows(dp, t, 52, 3, 40.0, 1.0), np.arange(22, 50, 3))


def _reference_sigma_b_in_time(acc, nu, t, block):
    """sigma_b of one window of 1-s estimates by its definition in log time: blocks of
    ``block`` seconds ending at the window's end, the velocity change between the ends of two
    consecutive blocks that both hold all their seconds, less the later block's mean model
    acceleration."""
    slot = np.rint(t[-1] - t).astype(int)                 # seconds back from the window's end
    at = {s: i for i, s in enumerate(slot)}
    missed = []
    for m in range((slot[0] + 1) // block - 1):
        later, earlier = range(m * block, (m + 1) * block), range((m + 1) * block, (m + 2) * block)
        if all(s in at for s in (*later, *earlier)):
            end, prev = at[m * block], at[(m + 1) * block]
            missed.append((nu[end] - nu[prev]) / (t[end] - t[prev]) - acc[[at[s] for s in later]].mean(axis=0))
    return np.std(missed, axis=0, ddof=1) if len(missed) >= 2 else np.zeros(3)


def _model_accel(model, a, est):
    from hybridship.residual.environment import CUR, LOAD, THR, current_input, external_accel, thrust_error_accel

    x, rows = est.x, est.rows
    ext = external_accel(x[:, 2], x[:, LOAD], 0.0, 0.0) + thrust_error_accel(
        model, est.thrust_error_model, x[:, 0:3], x[:, 3:6], a.rpm[rows], a.azimuth_rad[rows], a.wind[rows],
        x[:, CUR], x[:, THR])
    return model.acceleration(x[:, 0:3], x[:, 3:6], rpm=a.rpm[rows], azimuth_rad=a.azimuth_rad[rows],
                              wind=a.wind[rows], current=current_input(x[:, CUR]), accel_ext=ext)


def test_held_load_blocks_are_spans_of_log_time_across_a_gap(model, drift_log):
    """The blocks were counted in estimates: across a 20-s gap in a 1-Hz log, the block of 30
    estimates holding it spanned 50 s of log time, its velocity change and mean acceleration
    those of a longer block than the others. Blocks are now held_load_block_s of log time
    ending at the window's end; a pair of blocks counts only when both hold all their
    seconds, so the gap leaves out the blocks it falls in and the other pairs are those of
    the log without it. In a forecast from a start after the gap the spread is that of the
    blocks in time."""
    from hybridship.residual.calibration import CalibrationConfig

    a = as_log_arrays(drift_log, model.vessel)
    rows = np.arange(600, 1200)
    est = EnvironmentEstimator(model).run(a, rows, first_row=0)
    acc = _model_accel(model, a, est)
    keep = np.flatnonzero((a.time_s[rows] < 1000.0) | (a.time_s[rows] >= 1020.0))      # 20 s left out
    gapped = est.take(keep)
    got = unexplained_load_std(model, a, gapped, 30)
    want = _reference_sigma_b_in_time(acc[keep], est.x[keep, 3:6], a.time_s[rows][keep], 30)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-15)
    # the same as the pairs of the log without the gap, less the two pairs of the block it falls in
    nu, t = est.x[:, 3:6], a.time_s[rows]
    ends = np.arange(599, 0, -30)                                       # block ends, back from the end
    missed = (nu[ends[:-1]] - nu[ends[1:]]) / (t[ends[:-1]] - t[ends[1:]])[:, None] - np.stack(
        [acc[e - 29:e + 1].mean(axis=0) for e in ends[:-1]])
    touched = np.array([np.any((t[e - 59:e + 1] >= 1000.0) & (t[e - 59:e + 1] < 1020.0)) for e in ends[:-1]])
    assert touched.sum() == 2
    np.testing.assert_allclose(got, missed[~touched].std(axis=0, ddof=1), rtol=1e-9, atol=1e-15)
    # a forecast from a start after a 20-s gap in the log: the blocks of its window in time
    ens = CalibrationConfig(station_keeping_spread="ensemble")
    on = HybridPredictor(model.vessel, ensemble_config=TINY, calibration_config=ens).fit([drift_log], dp_only=True)
    off = HybridPredictor(model.vessel, ensemble_config=TINY, calibration_config=ens,
                          environment_config=EnvironmentConfig(held_load_window_s=0.0)).fit([drift_log], dp_only=True)
    log = drift_log[(drift_log.time_s < 1000.0) | (drift_log.time_s >= 1020.0)].reset_index(drop=True)
    f_on = on.forecast(log, [1205.0], 60.0, calibrated=False)
    f_off = off.forecast(log, [1205.0], 60.0, calibrated=False)
    b = as_log_arrays(log, model.vessel)
    window = np.flatnonzero((b.time_s >= 600.0) & (b.time_s < 1200.0))
    est = on._run_estimator(b, np.array([int(np.searchsorted(b.time_s, 1205.0))]), window)[1]
    sb = _reference_sigma_b_in_time(_model_accel(on.model, b, est), est.x[:, 3:6], b.time_s[window], 30)
    held = held_load_spread(sb[None], f_on.lead_s)[0]
    np.testing.assert_allclose(f_on.eta_std[0], np.sqrt(f_off.eta_std[0] ** 2 + held ** 2), rtol=1e-9)


def test_held_load_blocks_on_a_log_without_a_gap_are_those_of_the_estimates(model):
    """On an evenly sampled log the blocks in log time are the runs of block_rows estimates
    they were, at 10 Hz on a 1-s grid too (step 10)."""
    log = physics_log(model, duration_s=400, t_shutdown_s=None, seed=3, dt_s=0.1)
    a = as_log_arrays(log, model.vessel)
    rows = np.arange(a.time_s.size - 1, -1, -10)[::-1]
    est = EnvironmentEstimator(model, EnvironmentConfig(filter_step_s=1.0)).run(a, rows, first_row=0)
    acc, nu, t = _model_accel(model, a, est), est.x[:, 3:6], a.time_s[rows]
    for block in (5, 30):
        for first in (0, 17):
            got = unexplained_load_std(model, a, est.take(slice(first, None)), block, 10)
            np.testing.assert_allclose(got, _reference_sigma_b(acc[first:], nu[first:], t[first:], block),
                                       rtol=1e-12, atol=1e-18)
            assert np.all(got > 0)


def test_the_note_of_a_start_without_whole_held_load_blocks_names_gaps_as_a_cause(model):
    """A start 1290 s into station keeping, on a log missing every 25th sample over the 700 s
    before it: no 30-s block is whole, so the spread is the members'. The note said to start
    90 s or more into the station keeping, which this start is; it now names the gaps too."""
    log = physics_log(model, duration_s=1500, t_shutdown_s=None, seed=3)
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=5, patience=2, seed=0)
    hp = HybridPredictor(model.vessel, ensemble_config=tiny).fit([log])
    assert hp.forecast(log, [1290.0], 60.0).notes == ("",)
    gappy = log.drop(index=[i for i in range(600, 1300) if i % 25 == 0]).reset_index(drop=True)
    note, = hp.forecast(gappy, [1290.0], 60.0).notes
    assert note.startswith("spread: the held load's needs three whole 30-s blocks of station keeping")
    assert "after any gap in the log that breaks the blocks" in note
