"""The wind over a forecast (hybridship.forecast_inputs.wind): held, or a gust decaying to the recent mean.

Checked against hand values (the decay law, vector means through north), for causality
(also through a forecast, with a sensor gap the log fills from later samples), for
missing samples, for the rollout (a constant per-step wind is the held wind), and for
identification: on a synthetic first-order gust process of
known time constant, the fit picks a time constant near it and beats the held wind; on a
steady wind it keeps the held wind. A hybrid fitted with ``wind_forecast="fit"`` carries
the chosen forecast in its model file.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from hybridship.forecast_inputs.wind import HELD_WIND, WindForecast, fit_wind_forecast, wind_error_paths, wind_starts
from hybridship.frames import vector_to_speed_dir, wrap_pi
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.predictors.forecast_setup import _forecast_setup
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.multistep import MultiStepConfig
from hybridship.sim.synthetic import physics_log


class _Log:
    """Just what the wind forecast reads."""

    def __init__(self, time_s, wind):
        self.time_s, self.wind = np.asarray(time_s, float), np.asarray(wind, float)


def _wind(speed, dir_rad):
    return np.column_stack([np.broadcast_to(speed, np.shape(dir_rad)), dir_rad])


def _vec(w):
    return np.stack([w[..., 0] * np.cos(w[..., 1]), w[..., 0] * np.sin(w[..., 1])], axis=-1)


def test_held_wind_is_the_start_value_for_every_step():
    t = np.arange(100.0)
    w = _wind(np.linspace(5, 10, 100), np.zeros(100))
    out = HELD_WIND.steps(w, t, np.array([50, 80]), w[[50, 80]], 30, 1.0)
    assert out.shape == (2, 1, 2)
    np.testing.assert_allclose(out[:, 0], w[[50, 80]])


def test_a_gust_decays_to_the_trailing_mean_with_the_time_constant():
    t = np.arange(200.0)
    speed = np.full(200, 6.0)
    speed[150] = 10.0                                 # a gust at the start sample
    w = _wind(speed, np.full(200, 0.3))
    wf = WindForecast(mean_window_s=100.0, time_constant_s=20.0)
    out = wf.steps(w, t, np.array([150]), w[[150]], 61, 1.0)
    mean = (99 * 6.0 + 10.0) / 100                    # samples in (50, 150]
    expect = mean + (10.0 - mean) * np.exp(-np.arange(61) / 20.0)
    np.testing.assert_allclose(out[0, :, 0], expect, rtol=1e-12)
    np.testing.assert_allclose(out[0, :, 1], 0.3, atol=1e-12)
    now = WindForecast(mean_window_s=100.0, time_constant_s=0.0).steps(w, t, np.array([150]), w[[150]], 5, 1.0)
    np.testing.assert_allclose(out[0, 0], now[0, 0])                 # step 0 is the start value
    np.testing.assert_allclose(now[0, 1:, 0], mean)                  # then the mean at once


def test_directions_are_averaged_as_vectors_through_north():
    t = np.arange(20.0)
    w = _wind(8.0, np.where(np.arange(20) % 2 == 0, np.radians(350.0), np.radians(10.0)))
    out = WindForecast(mean_window_s=20.0, time_constant_s=0.0).steps(w, t, np.array([19]), w[[19]], 3, 1.0)
    assert abs(np.degrees(out[0, 2, 1])) < 1e-9                      # north, not south
    assert out[0, 2, 0] == pytest.approx(8.0 * np.cos(np.radians(10.0)))


def test_the_forecast_uses_no_sample_after_its_start():
    rng = np.random.default_rng(0)
    t = np.arange(300.0)
    w = _wind(6 + rng.normal(0, 1, 300), rng.normal(0, 0.2, 300))
    wf = WindForecast(mean_window_s=60.0, time_constant_s=10.0)
    a = wf.steps(w, t, np.array([200]), w[[200]], 30, 1.0)
    w2 = w.copy()
    w2[201:] = [[30.0, 2.0]]
    np.testing.assert_array_equal(a, wf.steps(w2, t, np.array([200]), w2[[200]], 30, 1.0))


def test_unlogged_wind_samples_are_skipped_and_an_empty_window_holds():
    t = np.arange(100.0)
    w = _wind(np.where(np.arange(100) % 2 == 0, 4.0, 8.0), np.zeros(100))
    logged = np.arange(100) % 2 == 0                  # the 8 m/s samples were filled in by the log
    wf = WindForecast(mean_window_s=50.0, time_constant_s=0.0)
    out = wf.steps(w, t, np.array([98]), np.array([[6.0, 0.0]]), 3, 1.0, logged=logged)
    np.testing.assert_allclose(out[0, 1:, 0], 4.0)
    w[1::2] = np.nan                                  # NaN samples count as missing too
    np.testing.assert_allclose(wf.steps(w, t, np.array([98]), np.array([[6.0, 0.0]]), 3, 1.0)[0, 1:, 0], 4.0)
    held = wf.steps(w, t, np.array([98]), np.array([[6.0, 0.1]]), 3, 1.0, logged=np.zeros(100, bool))
    np.testing.assert_allclose(held[0], [[6.0, 0.1]] * 3)
    hold = wf.steps(w, t, np.array([98, 98]), np.array([[6.0, 0.1], [6.0, 0.1]]), 3, 1.0,
                    hold=np.array([True, False]))
    np.testing.assert_allclose(hold[0], [[6.0, 0.1]] * 3)
    assert not np.allclose(hold[1], hold[0])


def _gusty_log(tau_s: float, n: int = 6000, seed: int = 0):
    """First-order gust process about a steady 8 m/s wind from 30 deg, 1-s samples."""
    rng = np.random.default_rng(seed)
    phi = np.exp(-1.0 / tau_s)
    g = np.zeros((n, 2))
    for k in range(1, n):
        g[k] = phi * g[k - 1] + np.sqrt(1 - phi ** 2) * 1.5 * rng.normal(size=2)
    v = np.array([8 * np.cos(0.5), 8 * np.sin(0.5)]) + g
    return _Log(np.arange(n, dtype=float), np.column_stack([np.hypot(v[:, 0], v[:, 1]), np.arctan2(v[:, 1], v[:, 0])]))


def test_the_fit_finds_the_gust_time_constant_and_beats_the_held_wind():
    wf, scores = fit_wind_forecast([_gusty_log(20.0, seed=s) for s in range(2)], 60.0, start_every_s=5.0)
    assert not wf.held
    assert 10.0 <= wf.time_constant_s <= 30.0
    assert wf.mean_window_s >= 120.0                  # the mean is steady: long windows estimate it best
    held = min(v for k, v in scores.items() if k != "n_starts" and k[1] is None)
    assert scores[(wf.mean_window_s, wf.time_constant_s)] < 0.9 * held


def test_a_steady_wind_keeps_the_held_forecast():
    t = np.arange(2000.0)
    wf, scores = fit_wind_forecast([_Log(t, _wind(7.0, np.full(2000, 1.0)))], 30.0)
    assert wf == HELD_WIND                            # round-off differences do not count
    assert scores["n_starts"] > 100


def test_the_fit_reads_only_the_rows_it_is_given():
    log = _gusty_log(20.0, n=3000)
    bad = _Log(log.time_s, log.wind.copy())
    bad.wind[2000:] = [[25.0, 3.0]]                    # rows it may not use
    mask = np.arange(3000) < 2000
    a = fit_wind_forecast([log], 30.0, masks=[mask])
    b = fit_wind_forecast([bad], 30.0, masks=[mask])
    assert a == b
    gap = mask.copy()
    gap[:5] = False                                   # a few unusable rows at the start cost nothing
    wf, scores = fit_wind_forecast([log], 30.0, masks=[gap])
    assert scores["n_starts"] >= a[1]["n_starts"] - 1 and wf == a[0]


def test_bad_settings_are_refused_with_the_field_name():
    with pytest.raises(ValueError, match=r"wind_forecast\.mean_window_s: must be > 0"):
        WindForecast(mean_window_s=-5.0)
    with pytest.raises(ValueError, match=r"wind_forecast\.time_constant_s: .*finite"):
        WindForecast(time_constant_s=float("nan"))
    with pytest.raises(ValueError, match="wind_forecast"):
        HybridPredictor("gunnerus", wind_forecast="mean")
    with pytest.raises(TypeError, match="wind_forecast"):
        DynamicPredictor("gunnerus", wind_forecast="fit")



def test_fit_wind_forecast_refuses_bad_arguments_by_name():
    t = np.arange(600.0)
    log = _Log(t, _wind(8.0 + np.sin(t / 30.0), np.ones_like(t)))
    # before: numpy's "cannot convert float NaN to integer", a ZeroDivisionError, an IndexError
    for bad in (float("nan"), 0.0, -5.0, None):
        with pytest.raises((TypeError, ValueError), match="horizon_s: "):
            fit_wind_forecast([log], bad)
    with pytest.raises(ValueError, match="start_every_s: "):
        fit_wind_forecast([log], 60.0, start_every_s=float("nan"))
    # before: "60" was read as the windows 6 s and 0 s, 5000 s and a negative decay time accepted
    with pytest.raises(TypeError, match="mean_windows_s: expected a sequence"):
        fit_wind_forecast([log], 60.0, mean_windows_s="60")
    with pytest.raises(ValueError, match=r"mean_windows_s\[0\]: must be <= 1800"):
        fit_wind_forecast([log], 60.0, mean_windows_s=(5000.0,))
    with pytest.raises(ValueError, match="mean_windows_s: expected at least one"):
        fit_wind_forecast([log], 60.0, mean_windows_s=())
    with pytest.raises(ValueError, match=r"time_constants_s\[1\]: must be >= 0"):
        fit_wind_forecast([log], 60.0, time_constants_s=(5.0, -5.0))
    # before: the second log, without a mask, was silently left out of the fit
    with pytest.raises(ValueError, match=r"masks: expected one per log \(2\), got 1"):
        fit_wind_forecast([log, log], 60.0, masks=[None])
    with pytest.raises(ValueError, match=r"masks: expected one flag per row of the log \(600\)"):
        fit_wind_forecast([log], 60.0, masks=[np.ones(5, bool)])
    fit_wind_forecast([log], 60, mean_windows_s=[60], time_constants_s=[None, 10])   # lists and ints are fine


def test_fit_wind_forecast_refuses_a_horizon_shorter_than_half_a_step():
    t = np.arange(600.0)
    log = _Log(t, _wind(8.0 + np.sin(t / 30.0), np.ones_like(t)))
    # before: a ZeroDivisionError (no step of any log to score the candidates on)
    with pytest.raises(ValueError, match=r"^horizon_s: 0.4 s is shorter than one step of the log \(1 s\), in "
                                         r"logs\[0\]"):
        fit_wind_forecast([log], 0.4)


def test_fit_wind_forecast_refuses_a_horizon_that_is_not_whole_steps_of_a_log():
    """fit_wind_forecast rounded the horizon to each log's step itself: 0.6 s was scored as one
    step of 1 s and 60.4 s as 60 steps, without a word. It now counts the steps with the
    forecast's own horizon_steps, which refuses both naming horizon_s and the log, and keeps
    its tolerance (60.2 s is 60 steps of 1 s, as a forecast takes it)."""
    from hybridship.forecast_inputs.horizon import HorizonError

    t = np.arange(600.0)
    log = _Log(t, _wind(8.0 + np.sin(t / 30.0), np.ones_like(t)))
    fine = _Log(np.arange(0.0, 600.0, 0.1), _wind(8.0 + np.sin(np.arange(6000) / 300.0), np.ones(6000)))
    for horizon in (0.6, 60.4):
        with pytest.raises(HorizonError, match=rf"^horizon_s: {horizon:g} s is not a whole number of the log's "
                                               rf"steps \(1 s\); the nearest is .*, in logs\[1\]$"):
            fit_wind_forecast([fine, log], horizon)
    assert fit_wind_forecast([log], 60.2)[1] == fit_wind_forecast([log], 60.0)[1]

def _gusty_physics_log(model, seed=3, duration_s=1500.0, **kw):
    log = physics_log(model, seed=seed, duration_s=duration_s, t_shutdown_s=None, **kw)
    rng = np.random.default_rng(1)
    g = np.zeros(len(log))
    for k in range(1, len(g)):
        g[k] = 0.95 * g[k - 1] + 0.6 * rng.normal()
    log["wind_speed_m_s"] = 8.0 + g                   # a gusty logged wind
    return log


TINY = EnsembleConfig(n_members=2, hidden=8, max_epochs=10, patience=5, seed=0)


@pytest.fixture(scope="module")
def gusty(model):
    """(log, hybrid fitted with wind_forecast="fit") on a gusty logged wind."""
    log = _gusty_physics_log(model)
    return log, HybridPredictor(model.vessel, ensemble_config=TINY, wind_forecast="fit").fit([log])


def test_a_hybrid_fits_the_wind_forecast_and_carries_it_in_its_model_file(gusty, tmp_path):
    log, hp = gusty
    info = hp.training_info["wind_forecast"]
    assert not hp.wind_forecast.held and not info["held"]
    assert info["error_m_s"] < info["held_error_m_s"]
    q = HybridPredictor.load(hp.save(tmp_path / "m.npz"))
    assert q.wind_forecast == hp.wind_forecast and q.wind_forecast_option == "fit"
    starts = [1200.0, 1300.0]
    a, b = hp.forecast(log, starts, 60.0), q.forecast(log, starts, 60.0)
    np.testing.assert_allclose(a.eta, b.eta)
    held = HybridPredictor.load(hp.save(tmp_path / "h.npz"))
    held.wind_forecast = HELD_WIND
    assert not np.allclose(held.forecast(log, starts, 60.0).eta, a.eta)     # the wind forecast is used


def test_a_given_wind_forecast_is_kept_and_stored_as_given(model, tmp_path):
    log = _gusty_physics_log(model, duration_s=600.0)
    wf = WindForecast(mean_window_s=60.0, time_constant_s=10.0)
    hp = HybridPredictor(model.vessel, ensemble_config=TINY, wind_forecast=wf).fit([log])
    assert hp.wind_forecast == wf and "wind_forecast" not in hp.training_info
    q = HybridPredictor.load(hp.save(tmp_path / "g.npz"))
    assert q.wind_forecast == wf and q.wind_forecast_option == wf


def test_a_constant_wind_per_step_is_the_held_wind(gusty):
    """The rollout reads the wind of each step; the same wind at every step is the held wind
    (guards included)."""
    log, hp = gusty
    st = _forecast_setup(hp.model, hp.residual_config, log, [1200.0, 1300.0], 30.0)      # commands held
    S, H = st.idx.size, st.H
    held = st.wind[:, :1]
    # commands in the thrust guard's ramp, where its weight follows the state step by step
    for k in np.linspace(0.02, 1.0, 50):
        rpm = np.ascontiguousarray(st.rpm * k)
        w = hp._thrust_weight(st.eta0, st.nu0, rpm[:, 0], st.az[:, 0], held[:, 0])
        if np.all((w > 0.2) & (w < 0.8)):
            break
    else:
        pytest.fail("no command level in the thrust guard's ramp")
    args = (st.eta0, st.nu0, np.zeros((S, 3)), np.zeros((S, 3)), rpm, st.az)
    a = hp.rollout(*args, held, H, st.dt, guard=True, substeps=st.substeps)
    b = hp.rollout(*args, np.ascontiguousarray(np.repeat(held, H, axis=1)), H, st.dt, guard=True,
                   substeps=st.substeps)
    np.testing.assert_allclose(a[0], b[0], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(a[3], b[3])


def test_forecasts_use_no_wind_after_their_start_and_hold_a_dropped_wind(model):
    log = _gusty_physics_log(model, duration_s=900.0)
    wf = WindForecast(mean_window_s=120.0, time_constant_s=10.0)
    p = DynamicPredictor(model.vessel, wind_forecast=wf)
    start = 600.0
    later = log.copy()
    later.loc[later.time_s > start, "wind_speed_m_s"] += 10.0
    np.testing.assert_array_equal(p.forecast(log, [start], 60.0).eta, p.forecast(later, [start], 60.0).eta)
    # no wind logged before 620 s: the log fills it from later samples, the forecast must not use them
    gap = log.copy()
    gap.loc[gap.time_s < 620.0, "wind_speed_m_s"] = np.nan
    gap2 = gap.copy()
    gap2.loc[gap2.time_s >= 620.0, "wind_speed_m_s"] += 10.0
    st = _forecast_setup(p.model, p.residual_config, gap, [start], 60.0, wind_forecast=wf)
    assert st.flags["wind_dropped"][0]
    np.testing.assert_array_equal(st.wind[0, :, 0], 0.0)                  # forecast without wind, as flagged
    np.testing.assert_array_equal(p.forecast(gap, [start], 60.0).eta, p.forecast(gap2, [start], 60.0).eta)
    # the sensor dropped 10 s before the start: flagged "forecast without wind", and so it is
    dropped = log.copy()
    dropped.loc[dropped.time_s > 590.0, "wind_speed_m_s"] = np.nan
    st = _forecast_setup(p.model, p.residual_config, dropped, [start], 60.0, wind_forecast=wf)
    assert st.flags["wind_dropped"][0]
    np.testing.assert_array_equal(st.wind[0, :, 0], 0.0)


def test_the_mean_skips_the_samples_the_log_filled_over_a_gap(model):
    log = _gusty_physics_log(model, duration_s=900.0)
    log["wind_dir_deg"] = 30.0
    log["wind_speed_m_s"] = np.where(log.time_s < 590.0, 5.0, 15.0)
    log.loc[(log.time_s > 500.0) & (log.time_s < 590.0), "wind_speed_m_s"] = np.nan   # filled with 5 m/s by the log
    wf = WindForecast(mean_window_s=120.0, time_constant_s=0.0)
    st = _forecast_setup(model, DynamicPredictor(model.vessel).residual_config, log, [600.0], 10.0, wind_forecast=wf)
    t = log.time_s.to_numpy()
    logged = (t > 480.0) & (t <= 600.0) & np.isfinite(log.wind_speed_m_s.to_numpy())
    expect = log.wind_speed_m_s.to_numpy()[logged].mean()                  # 5 m/s before the gap, 15 after
    assert st.wind[0, 1, 0] == pytest.approx(expect)
    assert st.wind[0, 0, 0] == pytest.approx(15.0)


def test_the_physics_baseline_holds_the_wind_whatever_its_history(model):
    log = _gusty_physics_log(model, duration_s=900.0)
    other = log.copy()
    other.loc[other.time_s < 590.0, "wind_speed_m_s"] = 2.0                # another history, same start window
    start = [600.0]
    d = DynamicPredictor(model.vessel)
    np.testing.assert_array_equal(d.forecast(log, start, 60.0).eta, d.forecast(other, start, 60.0).eta)
    f = DynamicPredictor(model.vessel, wind_forecast=WindForecast(mean_window_s=120.0, time_constant_s=10.0))
    assert not np.allclose(f.forecast(log, start, 60.0).eta, f.forecast(other, start, 60.0).eta)


def test_multi_step_training_rolls_out_with_the_forecast_wind(model, gusty):
    log, hp = gusty
    ms = MultiStepConfig(horizon_s=10.0, iterations=2, batch_starts=8, start_every_s=20.0, val_every=1,
                         max_val_starts=8)
    q = HybridPredictor(model.vessel, ensemble_config=TINY, training="multi_step", multistep_config=ms,
                        wind_forecast=hp.wind_forecast)
    q.fit([log])
    starts = q._multistep_starts([as_log_arrays(log, model.vessel)], None, True)
    assert starts.wind.shape[1] == 10                 # per step, not held
    assert q.training_info["multi_step"]["iterations"] == 2
    assert np.isfinite(q.forecast(log, [1200.0], 10.0, commands="known").eta).all()


def test_a_forecast_wind_beyond_the_valid_range_is_clipped_and_flagged(model):
    log = _gusty_physics_log(model, duration_s=900.0)
    log["wind_speed_m_s"] = np.where(log.time_s < 560.0, 75.0, 45.0)      # a storm before, 45 m/s at the start
    wf = WindForecast(mean_window_s=120.0, time_constant_s=5.0)
    st = _forecast_setup(model, DynamicPredictor(model.vessel).residual_config, log, [600.0], 30.0, wind_forecast=wf)
    assert st.wind[0, :, 0].max() == pytest.approx(100.0 * 0.514444, rel=1e-3)     # the envelope's 100 kn
    assert st.flags["input_clipped"][0]


def test_flow_vectors_round_trip_and_point_where_the_direction_says():
    from hypothesis import given, strategies as st
    from hybridship.frames import speed_dir_to_vector, vector_to_speed_dir

    np.testing.assert_allclose(speed_dir_to_vector([[2.0, np.pi / 2]]), [[0.0, 2.0]], atol=1e-15)  # east

    @given(st.floats(0.01, 80.0), st.floats(-np.pi + 1e-9, np.pi))
    def round_trip(speed, d):
        back = vector_to_speed_dir(speed_dir_to_vector([speed, d]))
        assert back[0] == pytest.approx(speed) and back[1] == pytest.approx(d, abs=1e-9)

    round_trip()


def test_error_paths_are_logged_minus_forecast_wind_where_the_log_measured_the_whole_future():
    forecast = WindForecast(mean_window_s=20.0, time_constant_s=5.0)
    a = _gusty_log(10.0, n=200, seed=2)
    a.dt_s, a.wind_logged = 1.0, np.ones(200, bool)
    paths = wind_error_paths(forecast, [a], 60, every=1)
    assert paths.shape == (138, 60, 2)                                           # starts 1..138
    rows = np.array([17])
    want = _vec(a.wind[17:77]) - _vec(forecast.steps(a.wind, a.time_s, rows, a.wind[rows], 60, 1.0))[0]
    np.testing.assert_allclose(paths[16], want, atol=1e-12)
    np.testing.assert_allclose(paths[:, 0], 0.0, atol=1e-12)                   # from the logged start wind
    held = wind_error_paths(HELD_WIND, [a], 60, every=1)                        # a held forecast broadcasts
    np.testing.assert_allclose(held[16], _vec(a.wind[17:77]) - _vec(a.wind[17]), atol=1e-12)
    a.segment_id = np.where(np.arange(200) < 100, 0, 1)
    assert len(wind_error_paths(forecast, [a], 60, every=1)) == 40 + 39         # starts 1..40, 100..138
    mask = np.arange(200) < 100
    assert len(wind_error_paths(forecast, [a], 60, every=1, masks=[mask])) == 40
    a.wind_logged[:150] = False                  # wind filled in before row 150: no whole future
    assert wind_error_paths(forecast, [a], 60, every=1).shape == (0, 60, 2)
    # before: the second log, without a mask, was silently left out of the paths
    with pytest.raises(ValueError, match=r"masks: expected one per log \(2\), got 1"):
        wind_error_paths(forecast, [a, a], 60, every=1, masks=[mask])


def test_error_paths_and_wind_starts_refuse_steps_that_are_not_a_whole_number_by_name():
    """Before: a negative horizon was numpy's "negative dimensions are not allowed", a float one
    "'float' object cannot be interpreted as an integer", wind_starts with horizon -1 an IndexError,
    and a spacing of 2.5 rows was read as 2 unseen."""
    a = _gusty_log(10.0, n=100, seed=2)
    a.dt_s, a.wind_logged = 1.0, np.ones(100, bool)
    forecast = WindForecast(mean_window_s=20.0, time_constant_s=5.0)
    for kw, name in ((dict(horizon_steps=-1), "horizon_steps"), (dict(horizon_steps=5.0), "horizon_steps"),
                     (dict(horizon_steps=0), "horizon_steps"), (dict(horizon_steps=5, every=2.5), "every")):
        with pytest.raises(ValueError, match=rf"{name}: expected a whole number >= 1"):
            wind_error_paths(forecast, [a], **kw)
        with pytest.raises(ValueError, match=rf"{name}: expected a whole number >= 1"):
            wind_starts(a, kw["horizon_steps"], kw.get("every", 1))
    assert wind_error_paths(forecast, [a], np.int64(5), every=np.int64(20)).shape == (5, 5, 2)


@pytest.fixture(scope="module")
def wind_spread_model(model):
    """(log, hybrid fitted with its wind forecast and 6 wind futures in the spread; the mean
    environment, so that a start on station reports the members' spread, as on a manoeuvre)."""
    log = _gusty_physics_log(model, seed=4)
    return log, HybridPredictor(model.vessel, ensemble_config=TINY, environment="mean", wind_forecast="fit",
                                wind_samples=6).fit([log])


def test_wind_futures_widen_the_spread_and_leave_the_forecast(wind_spread_model, tmp_path):
    log, hp = wind_spread_model
    info = hp.training_info["wind_spread"]
    assert info["samples"] == 6 == len(hp.wind_error_paths) <= info["candidate_paths"]
    starts = [1100.0, 1200.0, 1300.0]
    with_wind = hp.forecast(log, starts, 60.0, calibrated=False)
    assert np.array_equal(with_wind.eta_std, hp.forecast(log, starts, 60.0, calibrated=False).eta_std)  # seeded
    alone = hp.forecast(log, starts[1:2], 60.0, calibrated=False)          # whatever else is in the batch
    np.testing.assert_allclose(alone.eta_std[0], with_wind.eta_std[1], rtol=1e-12, atol=1e-12)
    plain = HybridPredictor.load(hp.save(tmp_path / "w.npz"))
    plain.wind_samples = 0
    members = plain.forecast(log, starts, 60.0, calibrated=False)
    np.testing.assert_array_equal(with_wind.eta, members.eta)                 # the forecast is unchanged
    # the members' spread and the wind term add in quadrature: the wind term alone, by hand, at
    # every lead and in heading too (the rollouts' heading on the circle)
    extra = np.sqrt(np.maximum(with_wind.eta_std ** 2 - members.eta_std ** 2, 0.0))
    manual = _wind_term_by_hand(hp, tmp_path / "w.npz", log, starts, members, hp.wind_error_paths)
    np.testing.assert_allclose(extra, manual, rtol=1e-6, atol=1e-9)
    assert np.all(extra[:, -1] > 0)                                         # the wind's future adds spread
    calm = HybridPredictor.load(tmp_path / "w.npz")
    calm.wind_error_paths = np.zeros_like(calm.wind_error_paths)             # a wind forecast that never errs
    np.testing.assert_allclose(calm.forecast(log, starts, 60.0, calibrated=False).eta_std, members.eta_std,
                               atol=1e-9)


def _wind_term_by_hand(hp, saved, log, starts, members, paths):
    """The wind futures' spread by hand: the RMS over ``paths`` of how far the members' mean
    forecast moves when the forecast wind gets one path added (heading on the circle)."""
    manual = []
    for path in paths:
        shifted = HybridPredictor.load(saved)
        shifted.wind_samples, shifted.wind_error_paths = 0, None

        class Plus(WindForecast):                  # the forecast wind plus this one path
            def steps(self, *a, **k):
                base = hp.wind_forecast.steps(*a, **k)
                return vector_to_speed_dir(_vec(np.broadcast_to(base, (base.shape[0], a[4], 2))) + path[None, :a[4]])
        shifted.wind_forecast = Plus(mean_window_s=hp.wind_forecast.mean_window_s,
                                     time_constant_s=hp.wind_forecast.time_constant_s)
        d = shifted.forecast(log, starts, 60.0, calibrated=False).eta - members.eta
        d[..., 2] = wrap_pi(d[..., 2])
        manual.append(d)
    return np.sqrt(np.mean(np.square(manual), axis=0))


def test_wind_futures_enter_the_calibration_and_edge_cases(wind_spread_model, model, tmp_path):
    log, hp = wind_spread_model
    plain = HybridPredictor(model.vessel, ensemble_config=TINY, environment="mean", wind_forecast="fit").fit([log])
    np.testing.assert_array_equal(plain.forecast(log, [1200.0], 60.0).eta, hp.forecast(log, [1200.0], 60.0).eta)
    assert not np.allclose(plain.calibration["held"]["position"].scale, hp.calibration["held"]["position"].scale)
    with pytest.raises(ValueError, match=r"horizon_s: 0\.5 s is shorter than one step of the log \(1 s\)"):
        hp.forecast(log, [1200.0], 0.5)                                    # rounds to no step: refused
    other = log.iloc[::2].reset_index(drop=True)                           # another sample step
    with pytest.raises(ValueError, match="wind_samples: the training logs have different sample steps"):
        HybridPredictor(model.vessel, ensemble_config=TINY, environment="mean", wind_samples=2).fit([log, other])


def test_wind_futures_follow_the_paths_time_on_a_log_at_another_step(wind_spread_model, tmp_path):
    """The paths have the training logs' 1-s step; on a 2-s log, forecast step j (at 2 j s)
    takes path step 2 j, not j. By hand: the forecasts with the wind plus every other sample
    of each path give the wind term (a path read step for step would reach only 30 s into
    its 60 s)."""
    log, hp = wind_spread_model
    coarse = log.iloc[::2].reset_index(drop=True)
    starts = [1100.0, 1300.0]
    with pytest.warns(UserWarning, match="step is 2 s"):
        with_wind = hp.forecast(coarse, starts, 60.0, calibrated=False)
        plain = HybridPredictor.load(hp.save(tmp_path / "w.npz"))
        plain.wind_samples = 0
        members = plain.forecast(coarse, starts, 60.0, calibrated=False)
        # every other step of each path: the paths' 1-s time on the 2-s log
        manual = _wind_term_by_hand(hp, tmp_path / "w.npz", coarse, starts, members, hp.wind_error_paths[:, ::2])
    extra = np.sqrt(np.maximum(with_wind.eta_std ** 2 - members.eta_std ** 2, 0.0))
    np.testing.assert_allclose(extra, manual, rtol=1e-6, atol=1e-9)


def test_wind_futures_are_error_paths_of_the_training_rows_only(wind_spread_model, model):
    """The paths are drawn from the wind forecast's error paths on the rows before the
    calibration cut (the held-back end stays unseen, as for the nets): the candidates are
    those paths, one start every 2 s, fewer than over the whole log, and every stored path is
    one of them. (The fit's own record, ``samples <= candidate_paths``, holds either way.)"""
    log, hp = wind_spread_model
    a = as_log_arrays(log, model.vessel)
    cal = hp.calibration_config
    cut = HybridPredictor._calibration_cut(a, cal, bool(hp.training_info["calibration"]["dp_only"]))
    assert 0 < cut < len(a)
    dt = hp.wind_error_dt_s
    H, every = int(round(cal.horizon_s / dt)), int(round(2.0 / dt))
    candidates = wind_error_paths(hp.wind_forecast, [a], H, every=every, masks=[np.arange(len(a)) < cut])
    assert hp.training_info["wind_spread"]["candidate_paths"] == len(candidates)
    assert len(wind_error_paths(hp.wind_forecast, [a], H, every=every)) > len(candidates)
    for path in hp.wind_error_paths:
        assert np.abs(candidates - path[None]).max(axis=(1, 2)).min() < 1e-12


def test_wind_futures_are_stored_in_the_model_file(wind_spread_model, tmp_path):
    log, hp = wind_spread_model
    q = HybridPredictor.load(hp.save(tmp_path / "w.npz"))
    assert q.wind_samples == 6 and q.wind_error_dt_s == hp.wind_error_dt_s
    np.testing.assert_array_equal(q.wind_error_paths, hp.wind_error_paths)
    a, b = hp.forecast(log, [1200.0], 60.0), q.forecast(log, [1200.0], 60.0)
    np.testing.assert_array_equal(a.eta_std, b.eta_std)


def test_wind_samples_must_be_a_whole_number():
    for bad in (-1, 2.5, True, "8", 257):
        with pytest.raises(ValueError, match="wind_samples: expected a whole number from 0 to 256"):
            HybridPredictor("gunnerus", wind_samples=bad)


def test_starts_need_logged_wind_over_the_whole_horizon_in_one_segment():
    n = 40
    rng = np.random.default_rng(0)
    a = SimpleNamespace(time_s=np.arange(n) * 0.5, wind=np.column_stack([2.0 + rng.random(n), np.full(n, 0.7)]),
                        wind_logged=np.ones(n, bool), segment_id=np.zeros(n, int), dt_s=0.5)
    a.wind_logged[20] = False
    a.segment_id[30:] = 1
    rows, ok = wind_starts(a, 5, 1)
    # a start at r uses rows r..r+5: none may be row 20, none may cross into segment 1 at row 30
    assert set(rows) == set(range(1, 15)) | set(range(21, 25)) | set(range(30, 35))
    assert not ok[20] and ok.sum() == n - 1


def test_the_fit_scores_a_candidate_by_its_mean_vector_error_at_each_lead():
    """A candidate's score, by hand: from each start, the forecast at lead ``k dt`` (``k = 1..H``)
    against the logged wind vector ``k`` rows later, the mean taken over the usable samples
    in ``(t - window, t]``."""
    log = _gusty_log(10.0, n=300, seed=3)
    wf, scores = fit_wind_forecast([log], 10.0, start_every_s=7.0, mean_windows_s=(30.0,), time_constants_s=(4.0,))
    rows, ok = wind_starts(log, 10, 7)
    vec, errors = _vec(log.wind), []
    for r in rows:
        past = ok & (log.time_s > log.time_s[r] - 30.0) & (log.time_s <= log.time_s[r])
        mean = vec[past].mean(axis=0)
        for k in range(1, 11):
            errors.append(np.hypot(*(mean + (vec[r] - mean) * np.exp(-k / 4.0) - vec[r + k])))
    assert scores["n_starts"] == len(rows) > 30
    assert scores[(30.0, 4.0)] == pytest.approx(np.mean(errors), rel=1e-12)
    assert scores[(30.0, None)] == pytest.approx(np.mean([np.hypot(*(vec[r] - vec[r + k])) for r in rows
                                                          for k in range(1, 11)]), rel=1e-12)


def test_the_held_wind_is_a_candidate_and_a_gain_under_one_percent_keeps_it():
    """The held wind is scored even when the candidates leave it out, and a decay so slow that
    it beats the held wind by less than ``MIN_IMPROVEMENT`` (here about 0.4 %) is not chosen."""
    from hybridship.forecast_inputs.wind import MIN_IMPROVEMENT

    wf, scores = fit_wind_forecast([_gusty_log(20.0, n=3000, seed=1)], 60.0, mean_windows_s=(120.0,),
                                   time_constants_s=(3000.0,))
    assert (120.0, None) in scores
    gain = 1.0 - scores[(120.0, 3000.0)] / scores[(120.0, None)]
    assert 0.0 < gain < MIN_IMPROVEMENT
    assert wf == HELD_WIND


def test_error_paths_need_every_step_logged_and_use_only_logged_wind_in_the_mean():
    """A start's path covers rows ``r .. r + H - 1``: one unlogged row removes exactly the starts
    whose path holds it. Unlogged rows before a start stay out of its forecast's mean."""
    forecast = WindForecast(mean_window_s=20.0, time_constant_s=5.0)
    a = _gusty_log(10.0, n=120, seed=4)
    a.dt_s, a.wind_logged = 1.0, np.ones(120, bool)
    H = 10
    every = wind_error_paths(forecast, [a], H, every=1)
    assert len(every) == 120 - H - 2                                            # starts 1 .. n - H - 2
    a.wind_logged[60] = False                                                   # in the paths of starts 51..60
    assert len(wind_error_paths(forecast, [a], H, every=1)) == len(every) - H
    a.wind_logged[60] = True
    a.wind_logged[40:50:2] = False                                              # filled in before the start 50
    a.wind[40:50:2] = [[30.0, 2.5]]
    paths = wind_error_paths(forecast, [a], H, every=50)                        # starts 1, 51 and 101
    rows = np.array([51])
    want = _vec(a.wind[51:61]) - _vec(forecast.steps(a.wind, a.time_s, rows, a.wind[rows], H, 1.0,
                                                     logged=a.wind_logged))[0]
    assert len(paths) == 3
    np.testing.assert_allclose(paths[1], want, atol=1e-12)


@pytest.mark.parametrize("settings", [dict(fraction=0.0), {}])
def test_fit_refuses_a_calibration_horizon_that_is_not_whole_steps_before_any_training(model, monkeypatch, settings):
    """fit counted the calibration horizon's steps with a rounding of its own where it fitted the
    wind forecast and its error paths, picked the failures with enough drift and the
    calibration starts: with nothing held back, 60.4 s on a 1-s log drew the wind's error
    paths over 60 steps without a word, and with the default held-back part the calibration forecasts
    refused it only after the nets were trained. It is now refused up front, naming
    calibration_config.horizon_s and the log; 60.2 s (within the forecast's tolerance) is taken."""
    from hybridship.forecast_inputs.horizon import HorizonError
    from hybridship.residual.calibration import CalibrationConfig

    log = as_log_arrays(physics_log(model, duration_s=600, t_shutdown_s=None, seed=5), model.vessel)
    hp = HybridPredictor(model.vessel, wind_samples=2,
                         calibration_config=CalibrationConfig(horizon_s=60.4, **settings))

    def trained(*args, **kwargs):
        raise AssertionError("the nets were trained")

    monkeypatch.setattr(HybridPredictor, "_fit_nets", trained)
    with pytest.raises(HorizonError, match=r"^calibration_config.horizon_s: 60.4 s is not a whole number of the "
                                           r"log's steps \(1 s\); the nearest is 60 s, in logs\[0\]$"):
        hp.fit([log])
    from hybridship.predictors.training_logs import check_calibration_horizon

    check_calibration_horizon([log], ["logs[0]"], 60.2)
