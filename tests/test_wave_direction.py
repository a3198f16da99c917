"""The waves' axis from the wave-frequency motion, and the held yaw load turned with it."""

from __future__ import annotations

import numpy as np
import pytest

from hybridship.predictors import HybridPredictor, as_log_arrays
from hybridship.predictors.hybrid import _corrected_step
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import EnvironmentConfig
from hybridship.residual.wave_direction import wave_axis, yaw_load_factor
from hybridship.sim.synthetic import physics_log

from conftest import load_benchmark


def _wave_motion(n: int, rel_deg: float, seed: int = 0, amplitude: float = 0.2, noise: float = 0.01):
    """Body velocities (u, v) [m/s] of an 8-s wave motion along ``rel_deg`` from the bow, plus noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=float)
    swing = amplitude * np.sin(2 * np.pi * t / 8.0 + rng.uniform(0, 2 * np.pi))
    rel = np.radians(rel_deg)
    return t, swing * np.cos(rel) + noise * rng.standard_normal(n), swing * np.sin(rel) + noise * rng.standard_normal(n)


@pytest.mark.parametrize("rel_deg, psi_deg", [(30.0, 0.0), (100.0, 250.0), (-60.0, 359.0)])
def test_the_axis_of_a_wave_motion_is_found_in_ned(rel_deg, psi_deg):
    """The axis (modulo 180 deg) is the heading plus the motion's direction in the body frame."""
    t, u, v = _wave_motion(600, rel_deg)
    psi = np.full(t.size, np.radians(psi_deg))
    axis = wave_axis(t, psi, u, v)
    assert axis is not None and axis.anisotropy > 100
    err = (np.degrees(axis.axis_ned_rad) - (psi_deg + rel_deg) + 90.0) % 180.0 - 90.0
    assert abs(err) < 1.0
    assert axis.sin2_station == pytest.approx(np.sin(2 * np.radians(rel_deg)), abs=0.03)


def _turning_through_fixed_waves():
    """A ship turning 0 -> 120 deg over 600 s through a wave motion fixed at 70 deg in NED:
    time [s], heading [rad], wave axis [rad], surge and sway [m/s]."""
    rng = np.random.default_rng(0)
    t = np.arange(600, dtype=float)
    psi = np.radians(np.linspace(0.0, 120.0, t.size))
    d = np.radians(70.0)
    swing = 0.2 * np.sin(2 * np.pi * t / 8.0 + 0.3)
    u = swing * np.cos(d - psi) + 0.01 * rng.standard_normal(t.size)
    v = swing * np.sin(d - psi) + 0.01 * rng.standard_normal(t.size)
    return t, psi, d, u, v


def test_the_axis_is_fixed_in_ned_while_the_ship_turns():
    """A ship turning 120 deg through a wave motion fixed at 70 deg in NED: each sample is
    turned with its own heading (one heading for all smears the axis away), and
    ``sin2_station`` averages ``sin(2 (d - psi))`` over the last ``average_s`` only (over the
    whole window it is +0.14, not the recent -0.53)."""
    t, psi, d, u, v = _turning_through_fixed_waves()
    axis = wave_axis(t, psi, u, v, average_s=300.0)
    assert axis is not None and axis.anisotropy > 100
    err = (np.degrees(axis.axis_ned_rad) - 70.0 + 90.0) % 180.0 - 90.0
    assert abs(err) < 1.0
    recent = t >= t[-1] - 300.0
    assert axis.sin2_station == pytest.approx(np.mean(np.sin(2 * (d - psi[recent]))), abs=0.03)


def test_a_missing_heading_leaves_out_its_sample_not_the_axis():
    """A forecast log may miss a heading sample: the turning ship's axis and sin2_station
    are still found (the sample's motion is left out; the unwrapped heading carried the NaN
    into every later sample and the axis was lost); without a heading in the last
    ``average_s`` there is none."""
    t, psi, d, u, v = _turning_through_fixed_waves()
    full = wave_axis(t, psi, u, v, average_s=300.0)
    gappy = psi.copy()
    gappy[[100, 450]] = np.nan
    psi_given = gappy.copy()
    axis = wave_axis(t, gappy, u, v, average_s=300.0)
    np.testing.assert_array_equal(gappy, psi_given)                    # the caller's array is not changed
    assert axis is not None
    assert axis.axis_ned_rad == pytest.approx(full.axis_ned_rad, abs=np.radians(0.5))
    assert axis.sin2_station == pytest.approx(full.sin2_station, abs=0.01)
    late_gap = psi.copy()
    late_gap[t >= t[-1] - 300.0] = np.nan
    assert wave_axis(t, late_gap, u, v, average_s=300.0) is None


def test_no_axis_without_a_directed_wave_motion_or_enough_station_keeping():
    rng = np.random.default_rng(1)
    t = np.arange(600, dtype=float)
    u, v = 0.05 * rng.standard_normal((2, t.size))                    # isotropic: no axis
    assert wave_axis(t, np.zeros(t.size), u, v) is None
    t, u, v = _wave_motion(100, 30.0)                                  # under ten of the longest periods
    assert wave_axis(t, np.zeros(t.size), u, v) is None
    # no sample at all: None as for one sample (an IndexError on t[-1] before)
    assert wave_axis(t[:1], np.zeros(1), u[:1], v[:1]) is None
    assert wave_axis(t[:0], np.zeros(0), u[:0], v[:0]) is None


def test_only_the_last_window_s_gives_the_axis():
    """A sea along 100 deg ten minutes ago is left out: the last ``window_s`` moves along 30 deg."""
    t, u_old, v_old = _wave_motion(1200, 100.0, seed=2)
    _, u_new, v_new = _wave_motion(1200, 30.0, seed=3)
    old = t < 600.0
    u, v = np.where(old, u_old, u_new), np.where(old, v_old, v_new)
    axis = wave_axis(t, np.zeros(t.size), u, v, window_s=500.0)
    assert axis is not None and abs(np.degrees(axis.axis_ned_rad) - 30.0) < 1.0


def test_no_axis_when_the_sampling_cannot_resolve_the_wave_band():
    """Samples every 2 s put the Nyquist period at 4 s, above the band's shortest (3.5 s): no axis."""
    t, u, v = _wave_motion(1200, 30.0)
    assert wave_axis(t[::2], np.zeros(600), u[::2], v[::2]) is None
    assert wave_axis(t, np.zeros(t.size), u, v) is not None


def test_missing_velocity_samples_count_as_zero():
    """A few NaN velocities (a dropped speed log) leave the axis where it is."""
    t, u, v = _wave_motion(600, 30.0)
    u[[100, 250, 251, 400]] = np.nan
    v[[100, 250, 251, 400]] = np.nan
    axis = wave_axis(t, np.zeros(t.size), u, v)
    assert axis is not None and abs(np.degrees(axis.axis_ned_rad) - 30.0) < 1.0


def test_a_station_heading_with_no_sin_2_beta_holds_the_load():
    """``sin2_station = 0`` gives no amplitude: the factor is 1 (held), not a division by zero."""
    factor = yaw_load_factor(np.radians([10.0, 70.0]), np.array([[np.radians(40.0), 0.0]] * 2))
    np.testing.assert_array_equal(factor, [1.0, 1.0])


def test_yaw_load_factor_follows_sin_2_beta_and_holds_without_an_axis():
    axis = np.array([[np.radians(40.0), np.sin(np.radians(80.0))], [np.nan, np.nan]])
    psi = np.radians([0.0, 0.0])
    np.testing.assert_allclose(yaw_load_factor(psi, axis), [1.0, 1.0])            # at the station's heading
    psi = np.radians([40.0, 40.0])                                                   # head or following seas
    np.testing.assert_allclose(yaw_load_factor(psi, axis), [0.0, 1.0], atol=1e-12)
    psi = np.radians([-10.0, 123.0])                                                 # beta 50 deg: sin 100 deg
    np.testing.assert_allclose(yaw_load_factor(psi, axis)[0], np.sin(np.radians(100.0)) / np.sin(np.radians(80.0)))


def test_corrected_step_turns_only_the_yaw_part_of_the_bias():
    """Two starts at heading 40 deg: one now in head seas (factor 0), one 30 deg the other
    side of the waves, where the load changes sign and grows: ``sin(-60 deg) / 0.5``."""
    eta1, nu1 = np.array([[0.0, 0.0, np.radians(40.0)]] * 2), np.zeros((2, 3))
    bias = np.array([[[1e-3, 2e-3, 1e-4]] * 2])
    axis = np.array([[np.radians(40.0), 0.5], [np.radians(10.0), 0.5]])
    z = np.zeros((1, 2, 3))
    held = _corrected_step(eta1, nu1, z, bias, 1.0, np.zeros((1, 2, 3)), np.zeros((1, 2, 3)))
    turned = _corrected_step(eta1, nu1, z, bias, 1.0, np.zeros((1, 2, 3)), np.zeros((1, 2, 3)), axis)
    np.testing.assert_allclose(turned[1][:, :2], held[1][:, :2])
    np.testing.assert_allclose(turned[0][:, :2], held[0][:, :2])
    np.testing.assert_allclose(held[1][:, 2], 1e-4)
    assert turned[1][0, 2] == pytest.approx(0.0, abs=1e-15)
    assert turned[1][1, 2] == pytest.approx(1e-4 * np.sin(np.radians(-60.0)) / 0.5)      # -1.73 x held
    assert turned[0][1, 2] - eta1[1, 2] == pytest.approx(0.5 * turned[1][1, 2])             # eta += dt^2 / 2 r


def test_the_hybrid_turns_the_held_yaw_load_after_a_failure_only_with_the_option(model, tmp_path):
    """A log whose station keeping carries a wave motion along a fixed NED axis, 30 deg off
    the bow at the failure: with the option, forecasts after the failure get the axis (and
    differ in heading through the yaw load), forecasts during station keeping none; without
    it, nothing changes."""
    log = physics_log(model, duration_s=1200, t_shutdown_s=900, seed=4, tau_ext_N=(2000.0, 0.0, 2000.0),
                      rpm_scale=0.0, wind=(0.0, 0.0))                 # a yaw load; the ship turns slowly
    psi = np.radians(log.heading_deg.to_numpy())
    rel = psi[899] + np.radians(30.0) - psi                       # the axis fixed in NED, seen from the bow
    _, swing, _ = _wave_motion(len(log), 0.0, noise=0.0)
    log["u_m_s"] += swing * np.cos(rel)
    log["v_m_s"] += swing * np.sin(rel)
    a = as_log_arrays(log, model.vessel)
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=5, patience=2, seed=0)
    off = HybridPredictor(model.vessel, ensemble_config=tiny).fit([a])
    on = HybridPredictor(model.vessel, ensemble_config=tiny,
                         environment_config=EnvironmentConfig(wave_turned_yaw_load=True)).fit([a])
    starts = [800.0, 905.0]
    assert off._wave_axes(_setup(off, a, starts)) is None
    axes = on._wave_axes(_setup(on, a, starts))
    assert np.isnan(axes[0]).all()                                       # during station keeping
    psi_fail = a.eta[899, 2]
    err = (np.degrees(axes[1, 0] - psi_fail) - 30.0 + 90.0) % 180.0 - 90.0
    d = psi[899] + np.radians(30.0)
    assert abs(err) < 3.0 and axes[1, 1] == pytest.approx(np.mean(np.sin(2 * (d - psi[600:900]))), abs=0.05)
    f_off, f_on = off.forecast(a, starts, 60.0), on.forecast(a, starts, 60.0)
    np.testing.assert_allclose(f_on.eta[0], f_off.eta[0])               # during station keeping: the same
    assert np.abs(f_on.eta[1, -1, 2] - f_off.eta[1, -1, 2]) > 1e-6      # after the failure: the yaw load turned
    # with wind futures in the spread, every per-start input is tiled over them
    on_ws = HybridPredictor(model.vessel, ensemble_config=tiny, wind_samples=2,
                            environment_config=EnvironmentConfig(wave_turned_yaw_load=True)).fit([a])
    assert np.isfinite(on_ws.forecast(a, starts, 60.0).eta_std).all()
    back = HybridPredictor.load(on.save(tmp_path / "on.npz"))           # the model file keeps the option
    assert back.environment_config.wave_turned_yaw_load
    np.testing.assert_allclose(back.forecast(a, starts, 60.0).eta, f_on.eta)


def _long_drift_in_waves(model):
    """A 1-h log, failure at 1800 s, whose wave motion lies along an axis fixed in NED 30 deg off
    the bow at the failure (the ship turns slowly under a yaw load), and a hybrid fitted on it
    with the yaw load turned with the waves."""
    log = physics_log(model, duration_s=3600, t_shutdown_s=1800, seed=4, tau_ext_N=(2000.0, 0.0, 2000.0),
                      rpm_scale=0.0, wind=(0.0, 0.0))
    psi = np.radians(log.heading_deg.to_numpy())
    rel = psi[1799] + np.radians(30.0) - psi
    _, swing, _ = _wave_motion(len(log), 0.0, noise=0.0)
    log["u_m_s"] += swing * np.cos(rel)
    log["v_m_s"] += swing * np.sin(rel)
    a = as_log_arrays(log, model.vessel)
    on = HybridPredictor(model.vessel, ensemble_config=EnsembleConfig(n_members=2, hidden=8, max_epochs=5, patience=2,
                                                                      seed=0),
                         environment_config=EnvironmentConfig(wave_turned_yaw_load=True)).fit([a])
    return a, on


def test_a_starts_wave_axis_does_not_depend_on_the_other_starts_of_its_batch(model):
    """The axis window was cut at the first row of the log read for the batch: a start 1700 s
    into a drift, alone, had the last 400 s of station keeping, and with a start 5 s after the
    failure beside it the whole 600 s, so its forecast depended on the batch. A start's window
    now lies within the rows its own filter reads (here the last 300 s), in any batch."""
    a, on = _long_drift_in_waves(model)
    alone = on._wave_axes(_setup(on, a, [3500.0]))[0]
    batched = on._wave_axes(_setup(on, a, [1805.0, 3500.0]))
    assert np.isfinite(alone).all() and np.isfinite(batched).all()
    np.testing.assert_array_equal(batched[1], alone)
    np.testing.assert_array_equal(on.forecast(a, [1805.0, 3500.0], 60.0).eta[1], on.forecast(a, [3500.0], 60.0).eta[0])


def test_the_turned_yaw_load_starts_from_the_estimate_at_the_starts_own_heading(model):
    """A start 1700 s into a drift, after the ship has turned: the yaw load it starts with is the
    estimator's at its own heading, so the factor on it is 1 there and follows the shape from
    that heading. It was referred to the station keeping's heading, which scaled the load at the
    start by sin(2 beta_start) / sin(2 beta_station) (here -0.99 / 0.71, reversing it), a load the estimator had
    already followed through the turn."""
    a, on = _long_drift_in_waves(model)
    st = _setup(on, a, [1805.0, 3500.0])
    axes = on._wave_axes(st)
    assert np.isfinite(axes).all()
    turned = np.degrees(abs(np.angle(np.exp(1j * (st.eta0[1, 2] - st.eta0[0, 2])))))
    assert turned > 20.0                                                  # the ship has turned since the failure
    np.testing.assert_allclose(axes[:, 1], np.sin(2.0 * (axes[:, 0] - st.eta0[:, 2])))
    np.testing.assert_allclose(yaw_load_factor(st.eta0[:, 2], axes), 1.0)
    ahead = st.eta0[:, 2] + np.radians(10.0)
    np.testing.assert_allclose(yaw_load_factor(ahead, axes), np.sin(2.0 * (axes[:, 0] - ahead)) / axes[:, 1])


def _setup(p, a, starts):
    from hybridship.predictors.forecast_setup import _forecast_setup

    return _forecast_setup(p.model, p.residual_config, a, starts, 60.0, p.stop_after_failure, "held",
                           history_s=p.history_s, wind_forecast=p.wind_forecast)


def test_benchmark_axis_error_is_taken_modulo_180():
    wd = load_benchmark("wave_direction")
    assert wd.axis_error_deg(179.0, 1.0) == pytest.approx(-2.0)
    assert wd.axis_error_deg(10.0, 5.0) == pytest.approx(5.0)


def test_the_choice_per_test_log_leaves_it_out_and_needs_five_other_failures():
    """benchmarks/wave_yaw_choice.py: a test log's choice is made on the other failures only."""
    wyc = load_benchmark("wave_yaw_choice")
    held = np.array([2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0])
    turned = held - np.array([-5.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])     # all gain but the first, which loses much
    chosen = wyc.decide(np.stack([held, turned]))
    assert chosen[0][0] and chosen[0][1] == pytest.approx(1 / 64)       # its own loss plays no part
    assert not any(c for c, _ in chosen[1:])                            # the first's loss is among the others
    few = wyc.decide(np.stack([held[:5], turned[:5]]))
    assert not any(c for c, _ in few) and all(np.isnan(p) for _, p in few)


@pytest.mark.parametrize("gain_rad, n_logs, turned", [(0.01, 5, True), (-0.01, 5, False), (0.01, 4, False)])
def test_auto_turns_the_yaw_load_only_where_the_training_failures_gain(model, monkeypatch, gain_rad, n_logs, turned):
    """``wave_turned_yaw_load="auto"`` (the default): fit turns the yaw load when, over five
    failures or more, the estimator's heading error along their drifts is lower turned and
    every failure gains (the signed-rank test); not when it is higher, nor with four failures,
    nor when fit learns nothing from failures (``drift_hull=False``, the paper's protocol)."""
    logs = [physics_log(model, duration_s=300, t_shutdown_s=200, seed=s) for s in range(n_logs)]
    asked = []

    def drift_errors(self, log, horizon_s, turned=None, label="log"):     # the check's forecasts, made up
        asked.append(turned)
        return np.array([1.0, 0.05 - (gain_rad if turned else 0.0) + 1e-3 * len(asked)])

    monkeypatch.setattr(HybridPredictor, "_drift_errors", drift_errors)
    monkeypatch.setattr(HybridPredictor, "_fit_drift_hull", lambda self, logs_, h: None)    # not the point here
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=5, patience=2, seed=0)
    assert EnvironmentConfig().wave_turned_yaw_load == "auto"
    strict = HybridPredictor(model.vessel, ensemble_config=tiny, drift_hull=False).fit(logs)
    assert asked == [] and "wave_yaw_load" not in strict.training_info and not strict.turns_yaw_load
    assert not strict.chooses_wave_yaw_load
    hp = HybridPredictor(model.vessel, ensemble_config=tiny).fit(logs)
    assert hp.chooses_wave_yaw_load
    info = hp.training_info["wave_yaw_load"]
    assert hp.wave_yaw_turned is turned and hp.turns_yaw_load is turned and info["turned"] is turned
    assert info["n_failures"] == n_logs and info["horizon_s"] == 60.0
    if n_logs >= 5:
        assert sorted(asked, key=str) == [False] * n_logs + [True] * n_logs
        assert info["p_value"] == pytest.approx(1 / 32 if turned else 1.0)
    else:
        assert asked == [] and "p_value" not in info
    fixed = HybridPredictor(model.vessel, ensemble_config=tiny, drift_hull=False,
                            environment_config=EnvironmentConfig(wave_turned_yaw_load=True)).fit(logs[:1])
    assert "wave_yaw_load" not in fixed.training_info and fixed.turns_yaw_load


def test_wave_yaw_errors_are_checked_at_the_boundary_and_small_on_the_models_own_logs(model):
    """HybridPredictor.wave_yaw_errors: an unfitted predictor, a bad horizon, one DataFrame and
    a log without a failure are refused by name (an unfitted one failed in an internal
    AttributeError, a DataFrame was iterated by its columns, a log without a drift was not
    named); on noise-free logs the model made, without waves, both errors are small, and a log's
    errors do not depend on the logs beside it."""
    from hybridship.predictors.forecast_setup import HorizonError

    logs = [physics_log(model, duration_s=400, t_shutdown_s=250, seed=s) for s in (1, 2)]
    with pytest.raises(RuntimeError, match="fit"):
        HybridPredictor(model.vessel).wave_yaw_errors(logs, 60.0)
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=5, patience=2, seed=0)
    hp = HybridPredictor(model.vessel, ensemble_config=tiny, drift_hull=False).fit(logs)
    errors = hp.wave_yaw_errors(logs, 60.0)
    assert errors.shape == (2, 2) and np.all(errors > 0) and np.all(errors < np.radians(0.1))
    np.testing.assert_array_equal(hp.wave_yaw_errors(logs[1], 60.0), errors[:, 1:])
    with pytest.raises(HorizonError, match="^horizon_s: 60.4 s is not a whole number"):
        hp.wave_yaw_errors(logs, 60.4)
    station = physics_log(model, duration_s=400, t_shutdown_s=None, seed=3)
    with pytest.raises(ValueError, match=r"^logs\[1\]: no failure followed by 60 s of drift"):
        hp.wave_yaw_errors([logs[0], station], 60.0)
    with pytest.raises(ValueError, match="^logs: expected at least one log"):
        hp.wave_yaw_errors([], 60.0)
