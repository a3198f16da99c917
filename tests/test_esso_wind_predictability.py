"""benchmarks/esso_wind_predictability.py: the trailing means and the linear wind predictor."""

from types import SimpleNamespace

import numpy as np
import pytest

from conftest import load_benchmark
from hybridship.frames import speed_dir_to_vector
from hybridship.forecast_inputs.wind import WindForecast


@pytest.fixture(scope="module")
def wp():
    return load_benchmark("esso_wind_predictability")


def _wind_log(n=200, dt=0.5, seed=0):
    rng = np.random.default_rng(seed)
    speed = 2.0 + np.abs(np.cumsum(rng.normal(0, 0.1, n)))
    direction = 0.7 + np.cumsum(rng.normal(0, 0.02, n))
    return SimpleNamespace(time_s=np.arange(n) * dt, wind=np.column_stack([speed, direction]),
                           wind_logged=np.ones(n, bool), segment_id=np.zeros(n, int), dt_s=dt)


def test_trailing_means_are_the_mean_vectors_of_the_samples_before_the_start(wp):
    a = _wind_log()
    rows = np.array([10, 50, 199])
    got = wp.trailing_means(a, rows, (2.0, 10.0))
    vec = speed_dir_to_vector(a.wind)
    for i, r in enumerate(rows):
        # (t_r - window, t_r]: 4 and 20 samples at dt = 0.5 s (fewer at the log's start)
        np.testing.assert_allclose(got[i, 0], vec[r - 3:r + 1].mean(axis=0), atol=1e-12)
        np.testing.assert_allclose(got[i, 1], vec[max(0, r - 19):r + 1].mean(axis=0), atol=1e-12)


def test_the_linear_fit_recovers_coefficients_shared_by_both_components(wp):
    rng = np.random.default_rng(1)
    feats = rng.normal(size=(500, 4, 2))
    coef = rng.normal(size=(4, 6))
    targets = np.einsum("sfc,fh->shc", feats, coef)
    np.testing.assert_allclose(wp.fit_linear(feats, targets, ridge=0.0), coef, atol=1e-10)
    # noise on one component only does not make the two components' coefficients differ
    noisy = targets + np.stack([rng.normal(0, 0.1, targets.shape[:2]), np.zeros(targets.shape[:2])], axis=-1)
    np.testing.assert_allclose(wp.fit_linear(feats, noisy), coef, atol=0.02)


def test_forecasts_start_from_the_logged_wind_and_the_gust_matches_the_library(wp):
    a = _wind_log()
    gust = WindForecast(mean_window_s=20.0, time_constant_s=5.0)
    steps = 8
    (rows, level, feats, future), = wp.sample_starts([a], gust, steps, 10)
    coef = np.zeros((feats.shape[1], steps))
    fc = wp.forecasts(a, rows, level, feats, future, gust, coef, steps)
    vec = speed_dir_to_vector(a.wind)
    np.testing.assert_allclose(fc["held"], np.broadcast_to(vec[rows][:, None], future.shape), atol=1e-12)
    np.testing.assert_allclose(fc["linear"], np.broadcast_to(level[:, None], future.shape))  # zero coefficients
    want = speed_dir_to_vector(gust.steps(a.wind, a.time_s, rows, a.wind[rows], steps + 1, a.dt_s))[:, 1:]
    np.testing.assert_allclose(fc["gust"], want, atol=1e-12)
    np.testing.assert_allclose(future, vec[rows[:, None] + np.arange(1, steps + 1)], atol=1e-12)


def test_the_linear_forecast_weights_the_start_and_the_trailing_means_and_the_bound_is_the_future_mean(wp):
    """Non-zero coefficients pick out the features: a 1 on the start sample's deviation forecasts
    the start sample, a 1 on the 3-s mean's deviation that mean (over the logged samples only,
    as is the level, the mean over the gust forecast's 20 s); ``future_mean`` is the mean of the
    next ``steps`` logged vectors."""
    a = _wind_log()
    a.wind_logged[[28, 29, 38, 58]] = False              # inside the trailing windows of some starts
    gust = WindForecast(mean_window_s=20.0, time_constant_s=5.0)
    steps = 4
    (rows, level, feats, future), = wp.sample_starts([a], gust, steps, 10)
    vec = speed_dir_to_vector(a.wind)

    def logged_mean(r, n):                               # the logged samples among the last n rows
        idx = [j for j in range(max(0, r - n + 1), r + 1) if a.wind_logged[j]]
        return vec[idx].mean(axis=0)

    np.testing.assert_allclose(level, [logged_mean(r, 40) for r in rows], atol=1e-12)
    assert set(rows) >= {31, 41, 61}                      # starts whose windows lose samples
    coef = np.zeros((feats.shape[1], steps))
    coef[0, 0] = 1.0                                     # lead 1: the start sample
    coef[1 + wp.TRAILING_S.index(3.0), 1] = 1.0          # lead 2: the 3-s mean (6 samples)
    coef[0, 2] = 0.5                                     # lead 3: half way from the level to the start
    fc = wp.forecasts(a, rows, level, feats, future, gust, coef, steps)
    np.testing.assert_allclose(fc["linear"][:, 0], vec[rows], atol=1e-12)
    np.testing.assert_allclose(fc["linear"][:, 1], [logged_mean(r, 6) for r in rows], atol=1e-12)
    np.testing.assert_allclose(fc["linear"][:, 2], 0.5 * (vec[rows] + level), atol=1e-12)
    np.testing.assert_allclose(fc["linear"][:, 3], level, atol=1e-12)
    want = np.mean([vec[rows + k] for k in range(1, steps + 1)], axis=0)
    np.testing.assert_allclose(fc["future_mean"], np.broadcast_to(want[:, None], future.shape), atol=1e-12)


def test_the_ridge_is_relative_to_the_mean_diagonal_of_the_gram_matrix(wp):
    """Orthogonal features with ``X^T X = 4 I`` (both components stacked): the ridge adds
    ``ridge * 4`` to the diagonal, so ``ridge = 1`` halves the least-squares coefficients."""
    one = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [0.0, 1.0]])
    feats = np.stack([one, one], axis=-1)                          # (S=4, F=2, 2)
    coef = np.array([[1.0, -2.0, 0.5], [3.0, 0.0, -1.0]])          # (F, H=3)
    targets = np.einsum("sfc,fh->shc", feats, coef)
    np.testing.assert_allclose(wp.fit_linear(feats, targets, ridge=1.0), coef / 2, atol=1e-12)
    np.testing.assert_allclose(wp.fit_linear(feats, targets, ridge=0.25), coef / 1.25, atol=1e-12)
