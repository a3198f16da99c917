"""The wind over a forecast (hybridship.forecast_inputs.wind): held, or a gust decaying to the recent mean.

Checked against hand values (the decay law, vector means through north), for causality,
for missing samples, and for identification: on a synthetic first-order gust process of
known time constant, the fit picks a time constant near it and beats the held wind; on a
steady wind it keeps the held wind. A hybrid fitted with ``wind_forecast="fit"`` carries
the chosen forecast in its model file.
"""

from __future__ import annotations

import numpy as np
import pytest

from hybridship.forecast_inputs.wind import HELD_WIND, WindForecast, fit_wind_forecast
from hybridship.predictors import DynamicPredictor, HybridPredictor
from hybridship.residual.ensemble import EnsembleConfig
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


def test_missing_wind_samples_are_skipped_and_an_empty_window_holds():
    t = np.arange(100.0)
    w = _wind(np.where(np.arange(100) % 2 == 0, 4.0, 8.0), np.zeros(100))
    w[np.arange(100) % 2 == 1] = np.nan               # only the 4 m/s samples remain
    wf = WindForecast(mean_window_s=50.0, time_constant_s=0.0)
    out = wf.steps(w, t, np.array([98]), np.array([[6.0, 0.0]]), 3, 1.0)
    np.testing.assert_allclose(out[0, 1:, 0], 4.0)
    w[:] = np.nan
    held = wf.steps(w, t, np.array([98]), np.array([[6.0, 0.1]]), 3, 1.0)
    np.testing.assert_allclose(held[0], [[6.0, 0.1]] * 3)
    assert np.isfinite(held).all()


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
    assert wf == HELD_WIND
    assert scores["n_starts"] > 100


def test_the_fit_reads_only_the_rows_it_is_given():
    log = _gusty_log(20.0, n=3000)
    bad = _Log(log.time_s, log.wind.copy())
    bad.wind[2000:] = [[25.0, 3.0]]                    # beyond the end it may use
    a = fit_wind_forecast([log], 30.0, ends=[2000])
    b = fit_wind_forecast([bad], 30.0, ends=[2000])
    assert a == b


def test_bad_settings_are_refused_with_the_field_name():
    with pytest.raises(ValueError, match=r"wind_forecast\.mean_window_s: .*greater than 0"):
        WindForecast(mean_window_s=-5.0)
    with pytest.raises(ValueError, match=r"wind_forecast\.time_constant_s: .*finite"):
        WindForecast(time_constant_s=float("nan"))
    with pytest.raises(ValueError, match="wind_forecast"):
        HybridPredictor("gunnerus", wind_forecast="mean")
    with pytest.raises(TypeError, match="wind_forecast"):
        DynamicPredictor("gunnerus", wind_forecast="fit")


def test_a_hybrid_fits_the_wind_forecast_and_carries_it_in_its_model_file(model, tmp_path):
    log = physics_log(model, seed=3, duration_s=1500.0, t_shutdown_s=None)
    rng = np.random.default_rng(1)
    g = np.zeros(len(log))
    for k in range(1, len(g)):
        g[k] = 0.95 * g[k - 1] + 0.6 * rng.normal()
    log["wind_speed_m_s"] = 8.0 + g                   # a gusty logged wind
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=10, patience=5, seed=0)
    hp = HybridPredictor(model.vessel, ensemble_config=tiny, wind_forecast="fit").fit([log])
    info = hp.training_info["wind_forecast"]
    assert not hp.wind_forecast.held
    assert info["error_m_s"] < info["held_error_m_s"]
    q = HybridPredictor.load(hp.save(tmp_path / "m.npz"))
    assert q.wind_forecast == hp.wind_forecast and q.wind_forecast_option == "fit"
    starts = [1200.0, 1300.0]
    a, b = hp.forecast(log, starts, 60.0), q.forecast(log, starts, 60.0)
    np.testing.assert_allclose(a.eta, b.eta)
    held = HybridPredictor.load(hp.save(tmp_path / "h.npz"))
    held.wind_forecast = HELD_WIND
    assert not np.allclose(held.forecast(log, starts, 60.0).eta, a.eta)     # the wind forecast is used
    dyn = DynamicPredictor(model.vessel)
    np.testing.assert_array_equal(dyn.forecast(log, starts, 60.0).eta,
                                  DynamicPredictor(model.vessel, wind_forecast=HELD_WIND).forecast(log, starts, 60.0).eta)
