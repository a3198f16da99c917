"""benchmarks/esso_error_sources.py: the wind oracles and the mean over sampled wind futures."""

from types import SimpleNamespace

import numpy as np
import pytest

from conftest import load_benchmark
from hybridship.forecast_inputs.wind import WindForecast
from hybridship.frames import speed_dir_to_vector
from hybridship.predictors.result import ForecastResult


@pytest.fixture(scope="module")
def es():
    return load_benchmark("esso_error_sources")


def _wind_log(n=400, dt=0.1, constant=False, seed=0):
    rng = np.random.default_rng(seed)
    speed = np.full(n, 2.0) if constant else 2.0 + np.cumsum(rng.normal(0, 0.05, n))
    direction = np.full(n, 0.7) if constant else 0.7 + np.cumsum(rng.normal(0, 0.01, n))
    return SimpleNamespace(time_s=np.arange(n) * dt, wind=np.column_stack([np.abs(speed), direction]),
                           wind_logged=np.ones(n, bool), dt_s=dt)


def test_the_logged_future_wind_is_the_wind_of_each_step_after_the_start(es):
    a = _wind_log()
    rows = np.array([3, 10, 395])
    w = es._logged_future_wind().steps(a.wind, a.time_s, rows, a.wind[rows], 8, a.dt_s)
    assert w.shape == (3, 8, 2)
    np.testing.assert_array_equal(w[0], a.wind[3:11])
    np.testing.assert_array_equal(w[1], a.wind[10:18])
    np.testing.assert_array_equal(w[2], a.wind[[395, 396, 397, 398, 399, 399, 399, 399]])  # held at the end


def test_the_logged_future_mean_wind_holds_the_vector_mean_of_the_steps_after_the_start(es):
    a = _wind_log()
    rows = np.array([3, 396])
    w = es._logged_future_mean_wind().steps(a.wind, a.time_s, rows, a.wind[rows], 8, a.dt_s)
    assert w.shape == (2, 8, 2)
    vec = speed_dir_to_vector(a.wind)
    np.testing.assert_allclose(speed_dir_to_vector(w[0]), np.repeat(vec[3:11].mean(axis=0)[None], 8, 0), atol=1e-12)
    # at the log's end the last sample stands in for the steps beyond it
    np.testing.assert_allclose(speed_dir_to_vector(w[1][:1]), vec[[396, 397, 398, 399, 399, 399, 399, 399]].mean(
        axis=0, keepdims=True), atol=1e-12)


def test_the_trailing_wind_is_the_causal_vector_mean_of_the_last_samples(es):
    """``wind_trail<s>``: by hand, a step from 2 to 6 m/s averages over the last 3 samples
    (the first held before the log starts, no later sample read), and directions 350 and
    10 deg average through north (a mean of the angles would point south)."""
    w = np.column_stack([[2.0, 2.0, 2.0, 6.0, 6.0, 6.0, 6.0], np.full(7, 0.4)])
    out = es.trailing_wind(w, 3)
    np.testing.assert_allclose(out[:, 0], [2.0, 2.0, 2.0, 10.0 / 3, 14.0 / 3, 6.0, 6.0], rtol=1e-12)
    np.testing.assert_allclose(out[:, 1], 0.4, rtol=1e-12)
    gusty = np.column_stack([np.full(6, 8.0), np.radians([350.0, 10.0] * 3)])
    out = es.trailing_wind(gusty, 2)
    np.testing.assert_allclose(out[1:, 0], 8.0 * np.cos(np.radians(10.0)), rtol=1e-12)
    np.testing.assert_allclose(out[1:, 1], 0.0, atol=1e-12)


def test_sampled_wind_adds_the_forecasts_own_error_paths(es):
    forecast = WindForecast(mean_window_s=5.0, time_constant_s=2.0)
    # one error path, from row 1 (the only start when the spacing exceeds the log): sampled at
    # that same row, the forecast plus its own error is exactly the wind the log measured
    gusty = _wind_log(seed=1)
    sampled = es._sampled_wind(forecast, [gusty], 30, every=10_000)
    got = sampled.steps(gusty.wind, gusty.time_s, np.array([1, 1]), gusty.wind[[1, 1]], 30, gusty.dt_s)
    np.testing.assert_allclose(speed_dir_to_vector(got), speed_dir_to_vector(gusty.wind[1:31])[None].repeat(2, 0),
                               atol=1e-12)
    # at other starts the drawn error is added to that start's forecast; the first step keeps the start value
    rows = np.array([60, 120, 200])
    base = forecast.steps(gusty.wind, gusty.time_s, rows, gusty.wind[rows], 30, gusty.dt_s)
    got = sampled.steps(gusty.wind, gusty.time_s, rows, gusty.wind[rows], 30, gusty.dt_s)
    path = speed_dir_to_vector(gusty.wind[1:31]) - speed_dir_to_vector(
        forecast.steps(gusty.wind, gusty.time_s, np.array([1]), gusty.wind[[1]], 30, gusty.dt_s))[0]
    np.testing.assert_allclose(speed_dir_to_vector(got[:, 1:]) - speed_dir_to_vector(base[:, 1:]),
                               path[None, 1:].repeat(3, 0), atol=1e-12)
    np.testing.assert_allclose(speed_dir_to_vector(got[:, 0]), speed_dir_to_vector(base[:, 0]), atol=1e-12)


def test_sampled_wind_draws_a_path_per_start_and_new_paths_at_each_call(es):
    """The mean over sampled wind futures calls the forecast once per draw: each call must draw
    again (a generator seeded anew at every call would give every copy the same future, and the
    mean would be one draw), and each start its own path, one of the forecast's error paths
    (with one path, as above, any drawing passes)."""
    from hybridship.forecast_inputs.wind import wind_error_paths

    forecast = WindForecast(mean_window_s=5.0, time_constant_s=2.0)
    gusty = _wind_log(seed=1)
    paths = wind_error_paths(forecast, [gusty], 30, every=20)
    paths[:, 0] = 0.0
    assert len(paths) > 10
    sampled = es._sampled_wind(forecast, [gusty], 30, every=20)
    rows = np.arange(50, 250, 25)
    base = speed_dir_to_vector(forecast.steps(gusty.wind, gusty.time_s, rows, gusty.wind[rows], 30, gusty.dt_s))
    drawn = []
    for _ in range(2):
        got = sampled.steps(gusty.wind, gusty.time_s, rows, gusty.wind[rows], 30, gusty.dt_s)
        d = speed_dir_to_vector(got) - base
        # which path each start drew: the one it matches to round-off
        miss = np.abs(d[:, None] - paths[None]).max(axis=(2, 3))
        assert np.all(miss.min(axis=1) < 1e-9)
        drawn.append(miss.argmin(axis=1))
    assert len(set(drawn[0])) > 1                           # the starts of one call draw apart
    assert not np.array_equal(drawn[0], drawn[1])           # and the next call draws again


def test_sampled_wind_refuses_logs_without_a_whole_measured_future(es):
    forecast = WindForecast(mean_window_s=5.0, time_constant_s=2.0)
    a = _wind_log(n=200, seed=2)
    a.wind_logged[:150] = False
    with pytest.raises(ValueError, match="60 steps of logged wind"):
        es._sampled_wind(forecast, [a], 60, every=1)


def test_the_mean_forecast_averages_the_heading_on_the_circle(es):
    calls = []

    class Stub:
        def forecast(self, a, start_times_s, horizon_s, **kw):
            calls.append((np.asarray(start_times_s), kw))
            copy = len(calls) - 1                                           # one call per draw
            S = len(start_times_s)
            eta = np.zeros((S, 2, 3))
            eta[..., 0] = (copy + 1.0 + 10.0 * np.arange(S))[:, None]       # north 1..4 m (+10 m for start 1)
            eta[..., 2] = (1.0 if copy % 2 == 0 else -1.0) * np.radians(179.0)
            nu = np.full((S, 2, 3), copy + 1.0)                             # surge etc. 1..4 m/s
            return ForecastResult(np.asarray(start_times_s), np.arange(2.0), eta, nu, eta_std=np.ones((S, 2, 3)))

    fc = es._mean_forecast(Stub(), 4)(None, [0.0, 5.0], 1.0, commands="known")
    assert len(calls) == 4 and all(kw == {"commands": "known"} for _, kw in calls)
    for st, _ in calls:                           # each start once per call: a forecast refuses repeats
        np.testing.assert_array_equal(st, [0.0, 5.0])
    np.testing.assert_array_equal(fc.start_time_s, [0.0, 5.0])
    np.testing.assert_allclose(fc.eta[0, :, 0], 2.5)
    np.testing.assert_allclose(fc.eta[1, :, 0], 12.5)
    np.testing.assert_allclose(np.abs(fc.eta[..., 2]), np.pi)     # +-179 deg average to 180, not 0
    np.testing.assert_allclose(fc.nu, 2.5)                         # the velocities are averaged too
    assert fc.eta_std is None


def test_the_scaled_correction_scales_the_hybrids_difference_from_the_physics(es):
    class Const:
        def __init__(self, north_m, psi_deg, u_m_s):
            self.north_m, self.psi, self.u = north_m, np.radians(psi_deg), u_m_s

        def forecast(self, a, start_times_s, horizon_s, **kw):
            S = len(start_times_s)
            eta, nu = np.zeros((S, 2, 3)), np.zeros((S, 2, 3))
            eta[..., 0], eta[..., 2], nu[..., 0] = self.north_m, self.psi, self.u
            return ForecastResult(np.asarray(start_times_s), np.arange(2.0), eta, nu)

    hybrid, physics = Const(3.0, -175.0, 2.0), Const(1.0, 175.0, 1.0)     # 10 deg apart across +-180
    for w, north, psi_deg, u in ((0.0, 1.0, 175.0, 1.0), (1.0, 3.0, -175.0, 2.0), (1.5, 4.0, -170.0, 2.5)):
        fc = es._scaled_correction(hybrid, physics, w)(None, [0.0, 5.0], 1.0)
        np.testing.assert_allclose(fc.eta[..., 0], north)
        np.testing.assert_allclose((np.degrees(fc.eta[..., 2]) - psi_deg + 180.0) % 360.0 - 180.0, 0.0, atol=1e-9)
        np.testing.assert_allclose(fc.nu[..., 0], u)


def test_the_heading_fit_rate_is_the_slope_of_a_quadratic_heading(es):
    t = np.arange(0.0, 20.0, 0.1)
    psi = 0.3 + 0.05 * t - 0.002 * t ** 2                  # [rad]; crosses no wrap
    r = es.heading_fit_rate(t, psi, 2.0)
    assert np.isnan(r[:19]).all()                           # no whole 2-s window (20 samples) behind
    np.testing.assert_allclose(r[19:], 0.05 - 0.004 * t[19:], atol=1e-9)
    wrapped = np.angle(np.exp(1j * (np.pi - 0.1 + 0.02 * t)))  # through +-pi
    np.testing.assert_allclose(es.heading_fit_rate(t, wrapped, 2.0)[19:], 0.02, atol=1e-9)
    rng = np.random.default_rng(0)                          # a least-squares fit: as np.polyfit's slope
    noisy = psi + rng.normal(0.0, 0.01, t.size)
    np.testing.assert_allclose(es.heading_fit_rate(t, noisy, 2.0)[100],
                               np.polyfit(t[81:101] - t[100], noisy[81:101], 2)[1], rtol=1e-9)


def test_the_mean_forecast_of_several_predictors_weighs_each_forecast_once(es):
    class Const:
        def __init__(self, north_m, psi_deg):
            self.north_m, self.psi = north_m, np.radians(psi_deg)

        def forecast(self, a, start_times_s, horizon_s, **kw):
            S = len(start_times_s)
            eta = np.zeros((S, 2, 3))
            eta[..., 0], eta[..., 2] = self.north_m, self.psi
            return ForecastResult(np.asarray(start_times_s), np.arange(2.0), eta, np.full((S, 2, 3), self.north_m))

    fc = es._mean_forecast([Const(1.0, 170.0), Const(4.0, -170.0)])(None, [0.0, 5.0, 9.0], 1.0)
    assert fc.eta.shape == (3, 2, 3)
    np.testing.assert_allclose(fc.eta[..., 0], 2.5)
    np.testing.assert_allclose(np.abs(np.degrees(fc.eta[..., 2])), 180.0)
    np.testing.assert_allclose(fc.nu, 2.5)                  # velocities 1 and 4: their mean, not the first's


def test_error_feedback_adds_the_earlier_forecasts_error_turned_with_the_heading(es):
    t = np.arange(100.0)
    psi = np.where(t < 40, 0.0, np.pi / 2)
    a = SimpleNamespace(time_s=t, eta=np.column_stack([t, np.zeros_like(t), psi]))
    calls = []

    class Hold:  # forecasts that the ship stays where it is at the start
        def forecast(self, log, start_times_s, horizon_s, **kw):
            calls.append(kw)
            rows = np.searchsorted(log.time_s, start_times_s)
            lead = np.arange(int(horizon_s) + 1.0)
            eta = np.repeat(log.eta[rows][:, None], lead.size, axis=1)
            return ForecastResult(np.asarray(start_times_s), lead, eta, np.zeros_like(eta))

    fc = es._error_feedback(Hold(), 0.5, lag_s=30.0)(a, [10.0, 45.0], 30.0, commands="known")
    assert all(kw == {"commands": "known"} for kw in calls)
    np.testing.assert_array_equal(fc.eta[0], np.repeat(a.eta[[10]], 31, axis=0))   # no forecast 30 s before
    # the forecast from 15 s missed 30 m north (and 90 deg); the ship has turned 90 deg since,
    # so the miss is carried over as 30 m east, growing with lead^2 to alpha x 30 m at 30 s
    shape = 0.5 * (np.arange(31) / 30.0) ** 2
    np.testing.assert_allclose(fc.eta[1, :, 0], 45.0, atol=1e-12)
    np.testing.assert_allclose(fc.eta[1, :, 1], 30.0 * shape, atol=1e-12)
    np.testing.assert_allclose(fc.eta[1, :, 2], np.pi / 2 * (1 + shape), atol=1e-12)
    plain = es._error_feedback(Hold(), 0.0)(a, [45.0], 30.0)
    np.testing.assert_array_equal(plain.eta[0], np.repeat(a.eta[[45]], 31, axis=0))


def test_the_feedback_gain_is_chosen_on_the_held_back_starts_by_the_longest_lead(es):
    """A ship accelerating at 0.02 m/s^2 north, forecast at its start velocity: every forecast
    misses by 0.01 tau^2 m (9 m at 30 s), and the feedback adds alpha times that same miss, so
    by hand the 30-s distance error is 9 (1 - alpha) m, heading 0, and the largest gain (0.5)
    wins. The starts are the held-back rows from the cut plus 30 s (rows 230, 235, ..., 265
    of a 300-s log cut at row 200), while 30 s of truth remain."""
    t = np.arange(300.0)
    a = SimpleNamespace(time_s=t, eta=np.column_stack([0.01 * t ** 2, np.zeros_like(t), np.zeros_like(t)]))
    plain_starts = []

    class ConstantVelocity:
        training_info = {"calibration": {"dp_only": False}}
        calibration_config = None

        @staticmethod
        def _calibration_cut(log, cal, dp_only):
            return 200

        def forecast(self, log, start_times_s, horizon_s, **kw):
            st = np.asarray(start_times_s, dtype=float)
            if horizon_s > 30.0 - 1e-9 and st.min() >= 230.0:     # the scored forecasts, not the earlier ones
                plain_starts.append(st)
            lead = np.arange(int(round(horizon_s)) + 1.0)
            eta = np.zeros((st.size, lead.size, 3))
            eta[..., 0] = 0.01 * st[:, None] ** 2 + 0.02 * st[:, None] * lead[None]
            return ForecastResult(st, lead, eta, np.zeros_like(eta))

    alpha, scores = es._choose_feedback(ConstantVelocity(), [a], np.array([10, 30]), 5.0)
    assert alpha == 0.5
    assert set(scores) == set(es.FEEDBACK_ALPHAS)
    for k, (distance, heading) in scores.items():
        assert distance == pytest.approx(9.0 * (1.0 - k), abs=1e-9) and heading == pytest.approx(0.0, abs=1e-9)
    assert len(plain_starts) == len(es.FEEDBACK_ALPHAS)
    for st in plain_starts:
        np.testing.assert_array_equal(st, t[230:270:5])


def test_tables_give_ratios_to_the_physics_and_the_wind_futures_share(es):
    import pandas as pd

    rows = []
    # physics 0.5 m / 10 deg pooled; the future wind takes 0.1 m / 3 deg, its mean held 0.05 m / 1 deg
    for model, d, h in (("as_logged", 0.5, 10.0), ("wind_future", 0.4, 7.0), ("wind_future_mean", 0.45, 9.0)):
        for kind, f in (("random", 1.0), ("zigzag", 2.0), ("all", 1.5)):
            for horizon in (5.0, 10.0, 20.0, 30.0):
                scale = horizon / 30.0 * (f if model != "wind_future" or kind != "zigzag" else 1.0)
                rows += [(model, kind, "distance_m", horizon, d * scale, "known"),
                         (model, kind, "heading_deg", horizon, h * scale, "known"),
                         (model, kind, "distance_m", horizon, 99.0, "held")]
    text = es.tables(pd.DataFrame(rows, columns=["model", "kind", "state", "horizon_s", "mae", "commands"]), "cmd")
    assert text.startswith("Command: `cmd`")
    lines = text.splitlines()
    pooled = next(x for x in lines if x.startswith("| wind_future |"))
    # 30-s pooled distance 0.4 * 1.5, heading 7 * 1.5; ratios 0.8 and 0.7 to the physics
    assert pooled == "| wind_future | 0.100 | 0.200 | 0.400 | 0.600 | 10.50 | 0.80 | 0.70 |"
    # per kind: zigzag's future-wind distance is 0.4 against the physics' 1.0 there
    per_kind = [x for x in lines if x.startswith("| wind_future |")][1]
    assert per_kind == "| wind_future | 0.80 | 0.40 |"
    assert "| as_logged | distance_m | 20% | 10% | 50% |" in lines
    assert "| as_logged | heading_deg | 30% | 10% | 33% |" in lines
    assert "99" not in text                    # the commands-held rows play no part


def test_tables_only_renders_the_run_again_with_its_command(es, tmp_path):
    import pandas as pd

    rows = [(m, k, s, h, v, "known") for m, v in (("as_logged", 1.0), ("hybrid", 0.5))
            for k in ("random", "all") for s in ("distance_m", "heading_deg") for h in (5.0, 10.0, 20.0, 30.0)]
    pd.DataFrame(rows, columns=["model", "kind", "state", "horizon_s", "mae", "commands"]).to_csv(
        tmp_path / "errors.csv", index=False)
    (tmp_path / "tables.md").write_text("Command: `python benchmarks/esso_error_sources.py --hybrid`\nold\n")
    assert es.main(["--tables-only", "--out", str(tmp_path), "--results", str(tmp_path / "docs")]) == 0
    text = (tmp_path / "docs" / "tables.md").read_text()
    assert text.startswith("Command: `python benchmarks/esso_error_sources.py --hybrid`\n") and "old" not in text
    assert "| hybrid | 0.500 / 0.50 | 0.500 / 0.50 | 0.50 / 0.50 |" in text
    (tmp_path / "tables.md").write_text("something else\n")
    assert es.main(["--tables-only", "--out", str(tmp_path)]) == 2
