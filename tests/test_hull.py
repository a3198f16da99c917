"""The linear, MMG-structured hull correction fitted before the nets (issue 17)."""

from __future__ import annotations

import numpy as np
import pytest

from hybridship.physics.model import DynamicModel
from hybridship.predictors import HybridPredictor, as_log_arrays
from hybridship.residual.calibration import CalibrationConfig
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import ALL_FEATURES, COMMAND_FEATURES, PAPER_FEATURES, ResidualConfig
from hybridship.residual.hull import HULL_REGRESSORS, HullCorrection, hull_regressors
from hybridship.residual.multistep import MultiStepConfig
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=2, hidden=8, max_epochs=20, patience=5, seed=0)


def _features(rng, n):
    full = np.zeros((n, len(ALL_FEATURES)))
    full[:, 0] = rng.uniform(-0.2, 0.6, n)        # u
    full[:, 1] = rng.normal(0, 0.05, n)           # v
    full[:, 2] = rng.normal(0, 0.05, n)           # r
    full[:, 9] = rng.uniform(-1, 1, n)            # rpm / max
    full[:, 11] = rng.uniform(-0.6, 0.6, n)       # rudder angle
    full[:, 13:15] = rng.normal(0, 0.5, (n, 2))   # relative wind
    return full


def test_regressors_torch_and_numpy_agree():
    torch = pytest.importorskip("torch")
    full = _features(np.random.default_rng(0), 50)
    a = hull_regressors(full, 3.0)
    b = hull_regressors(torch.tensor(full), 3.0, lib=torch).numpy()
    assert a.shape == (50, len(HULL_REGRESSORS))
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)


def test_fit_recovers_a_correction_that_is_linear_in_the_regressors():
    rng = np.random.default_rng(1)
    full = _features(rng, 4000)
    phi = hull_regressors(full, 3.0)
    coef = rng.normal(0, 0.01, (phi.shape[1], 3))
    Y = phi @ coef + np.array([1e-3, -2e-3, 5e-4])
    h = HullCorrection.fit(full, Y, 3.0, ridge=1e-10)
    np.testing.assert_allclose(h.predict(full), Y, atol=1e-8)
    # without the command and wind columns their regressors vanish and get no weight
    bare = full.copy()
    bare[:, 9:] = 0.0
    hb = HullCorrection.fit(bare, Y, 3.0)
    dead = np.array(["n" in k or "d" in k or "rw" in k for k in HULL_REGRESSORS])
    assert np.all(hb.theta[dead] == 0.0) and np.all(np.isfinite(hb.predict(bare)))
    with pytest.raises(ValueError, match="finite"):
        HullCorrection.fit(np.full_like(full, np.nan), Y, 3.0)


def test_hybrid_with_hull_correction_tunes_it_and_round_trips(tmp_path):
    m = DynamicModel("gunnerus")
    logs = [physics_log(m, seed=s, duration_s=400.0, t_shutdown_s=None, current=(0.3, 1.0)) for s in (5, 6)]
    cfg = MultiStepConfig(horizon_s=10.0, iterations=6, batch_starts=16, start_every_s=5.0, lr=3e-3, val_every=3,
                          loss="absolute", tune_hull=True)
    rc = ResidualConfig(features=PAPER_FEATURES[:6] + COMMAND_FEATURES, bias_window_s=0.0)
    hp = HybridPredictor(m.vessel, residual_config=rc, ensemble_config=TINY, training="multi_step",
                         multistep_config=cfg, calibration_config=CalibrationConfig(fraction=0.0),
                         hull_correction=True).fit(logs)
    assert hp.hull is not None and hp.hull.theta.shape == (len(HULL_REGRESSORS), 3)
    assert "hull_residual_std" in hp.training_info
    back = HybridPredictor.load(hp.save(tmp_path / "m.npz"))
    assert back.hull_correction and back.multistep_config.tune_hull
    np.testing.assert_allclose(back.hull.theta, hp.hull.theta)
    a = as_log_arrays(logs[0], m.vessel)
    fc = hp.forecast(a, [100.0, 200.0], 20.0, commands="known")
    np.testing.assert_allclose(back.forecast(a, [100.0, 200.0], 20.0, commands="known").eta, fc.eta)
    assert np.all(np.isfinite(fc.eta))
    # the correction is part of the learned model: off with the nets
    off = hp.forecast(a, [100.0], 20.0, commands="known", nets=False)
    plain = HybridPredictor(m.vessel, residual_config=rc, ensemble_config=TINY,
                            calibration_config=CalibrationConfig(fraction=0.0))
    plain.ensemble, plain.guard, plain.thrust_regime, plain.estimator = hp.ensemble, hp.guard, hp.thrust_regime, \
        hp.estimator
    np.testing.assert_allclose(off.eta, plain.forecast(a, [100.0], 20.0, commands="known", nets=False).eta)
    with pytest.raises(ValueError, match="hull_ridge"):
        HybridPredictor(m.vessel, hull_correction=True, hull_ridge=-1.0)


def test_free_run_fit_of_the_hull_correction_lowers_its_loss(tmp_path):
    m = DynamicModel("gunnerus")
    logs = [physics_log(m, seed=s, duration_s=400.0, t_shutdown_s=None, current=(0.3, 1.0)) for s in (5, 6)]
    cfg = MultiStepConfig(horizon_s=10.0, iterations=3, batch_starts=16, start_every_s=5.0, val_every=3,
                          hull_iterations=6)
    rc = ResidualConfig(features=PAPER_FEATURES[:6], bias_window_s=0.0)
    hp = HybridPredictor(m.vessel, residual_config=rc, ensemble_config=TINY, training="one_step",
                         multistep_config=cfg, calibration_config=CalibrationConfig(fraction=0.0),
                         hull_correction=True, hull_fit="multi_step").fit(logs)
    info = hp.training_info["hull_multi_step"]
    assert info["iterations"] == 6 and info["best_val_loss"] <= info["val_loss"][0]
    assert np.any(hp.hull.theta != 0.0)
    assert HybridPredictor.load(hp.save(tmp_path / "m.npz")).hull_fit == "multi_step"
    with pytest.raises(ValueError, match="hull_fit"):
        HybridPredictor(m.vessel, hull_correction=True, hull_fit="two_step")


def test_each_regressor_is_the_product_its_name_says():
    """Hand values for one feature vector: ``rL`` is r times the ship length, ``n`` the relative
    rpm, ``d`` the rudder angle, ``urw``, ``vrw`` the relative wind's surge and sway parts."""
    u, v, r, n, d, urw, vrw, L = -0.7, 0.3, -0.02, -0.4, 0.5, 2.0, -3.0, 30.0
    full = np.zeros(len(ALL_FEATURES))
    for name, x in (("u_hat_m_s", u), ("v_hat_m_s", v), ("r_hat_rad_s", r), ("rpm_main_rel", n),
                    ("angle_main_rad", d), ("wind_rel_u_m_s", urw), ("wind_rel_v_m_s", vrw)):
        full[ALL_FEATURES.index(name)] = x
    rl, s = r * L, np.sin(d)
    want = {"u|u|": u * abs(u), "v|v|": v * abs(v), "rL|rL|": rl * abs(rl), "u v": u * v, "u rL": u * rl,
            "v rL": v * rl, "|v| rL": abs(v) * rl, "v |rL|": v * abs(rl), "v^2": v * v, "rL^2": rl * rl,
            "u|u| sin d": u * abs(u) * s, "u n sin d": u * n * s, "n|n| sin d": n * abs(n) * s,
            "u^2 sin^2 d": u * u * s * s, "n^2 sin^2 d": n * n * s * s, "n|n|": n * abs(n), "u n": u * n,
            "urw|urw|": urw * abs(urw), "vrw|vrw|": vrw * abs(vrw), "urw vrw": urw * vrw}
    assert set(want) == set(HULL_REGRESSORS)
    np.testing.assert_allclose(hull_regressors(full, L), [want[k] for k in HULL_REGRESSORS], rtol=1e-14)


def test_the_torch_correction_equals_numpy_and_a_zeroed_one_corrects_nothing():
    """``predict_torch`` with the fitted ``theta``, offset is ``predict``; ``zeroed`` keeps the
    standardisation and gives zero; a model file's zero or negative scale is refused."""
    torch = pytest.importorskip("torch")
    rng = np.random.default_rng(2)
    full = _features(rng, 300)
    h = HullCorrection.fit(full, rng.normal(0, 1e-3, (300, 3)) + np.array([1e-3, -2e-3, 5e-4]), 3.0)
    got = h.predict_torch(torch.tensor(full), torch.tensor(h.theta), torch.tensor(h.offset)).numpy()
    np.testing.assert_allclose(got, h.predict(full), rtol=1e-12, atol=1e-15)
    z = h.zeroed()
    np.testing.assert_array_equal(z.predict(full), 0.0)
    np.testing.assert_array_equal(z.phi_std, h.phi_std)
    arrays = h.arrays()
    arrays["hull_phi_std"] = np.where(np.arange(len(HULL_REGRESSORS)) == 3, 0.0, arrays["hull_phi_std"])
    with pytest.raises(ValueError, match="non-positive scale"):
        HullCorrection.from_arrays(arrays, 3.0, 1e-3)


def test_ridge_halves_a_single_live_slope_when_it_equals_the_regressor_variance():
    """With only ``u`` non-zero the one live regressor is ``u|u|``; its standardised variance is 1,
    so a ridge of 1 per training row halves the fitted slope about the mean (by hand:
    ``x = u|u| = -1, 0, 1, 2`` has mean 0.5, and ``Y = a x + b`` is fitted as
    ``b + 0.5 a + 0.5 a (x - 0.5)``); every other coefficient stays 0."""
    u = np.array([-1.0, 0.0, 1.0, np.sqrt(2.0)])              # u|u| = -1, 0, 1, 2 [m^2/s^2]
    full = np.zeros((4, len(ALL_FEATURES)))
    full[:, ALL_FEATURES.index("u_hat_m_s")] = u
    a = np.array([0.2, -0.4, 0.06])                           # slopes per DOF
    b = np.array([1e-3, -2e-3, 5e-4])                         # intercepts [m/s^2, m/s^2, rad/s^2]
    x = np.array([-1.0, 0.0, 1.0, 2.0])
    Y = x[:, None] * a + b
    h = HullCorrection.fit(full, Y, 3.0, ridge=1.0)
    want = b + np.array([-0.25, 0.25, 0.75, 1.25])[:, None] * a
    np.testing.assert_allclose(h.predict(full), want, rtol=1e-12, atol=1e-15)
    assert np.all(h.theta[1:] == 0.0)
    # with a negligible ridge the fit is exact
    np.testing.assert_allclose(HullCorrection.fit(full, Y, 3.0, ridge=1e-12).predict(full), Y, rtol=1e-9, atol=1e-12)


def test_a_regressor_at_creep_speed_is_fitted_like_any_other():
    """The fit standardises each regressor, so its scale does not matter: a sway speed of about
    1 mm/s (``v|v|`` near 1e-6 m^2/s^2, as in station keeping) is still a live regressor, and a
    target proportional to it [m/s^2] is fitted exactly (``v|v|`` and ``v^2`` are the only live ones)."""
    rng = np.random.default_rng(3)
    v = rng.normal(0.0, 1e-3, 200)                             # [m/s]
    full = np.zeros((200, len(ALL_FEATURES)))
    full[:, ALL_FEATURES.index("v_hat_m_s")] = v
    Y = np.outer(v * np.abs(v), [0.0, 2e3, -50.0])              # by hand: a pure v|v| load
    h = HullCorrection.fit(full, Y, 3.0, ridge=1e-12)
    np.testing.assert_allclose(h.predict(full), Y, rtol=0, atol=1e-9 * np.abs(Y).max())
    assert np.any(h.theta[HULL_REGRESSORS.index("v|v|")] != 0.0)


def test_the_hybrids_hull_ridge_reaches_the_fit():
    """``hull_ridge`` is the fit's ridge: with ``A = Z^T Z / N + ridge I`` (eigenvalues >= ridge) and
    each ``|Z^T y / N|`` at most std(y) (Cauchy-Schwarz on unit-variance columns), every DOF's
    coefficients have norm at most ``sqrt(P) std(y) / ridge``; a ridge of 1e6 leaves them tiny."""
    m = DynamicModel("gunnerus")
    logs = [physics_log(m, seed=5, duration_s=200.0, t_shutdown_s=None, current=(0.3, 1.0))]
    rc = ResidualConfig(features=PAPER_FEATURES[:6], bias_window_s=0.0)
    hp = HybridPredictor(m.vessel, residual_config=rc, ensemble_config=TINY,
                         calibration_config=CalibrationConfig(fraction=0.0), hull_correction=True,
                         hull_ridge=1e6).fit(logs)
    y_std = np.asarray(hp.training_info["residual_std"])        # [m/s^2, m/s^2, rad/s^2]
    bound = np.sqrt(len(HULL_REGRESSORS)) * y_std / 1e6
    assert np.all(np.linalg.norm(hp.hull.theta, axis=0) <= bound * (1.0 + 1e-9))


@pytest.mark.parametrize("key, shape", [("hull_theta", (len(HULL_REGRESSORS), 2)),
                                        ("hull_theta", (len(HULL_REGRESSORS) - 1, 3)),
                                        ("hull_phi_mean", (len(HULL_REGRESSORS) + 1,)), ("hull_offset", (2,))])
def test_a_model_files_hull_arrays_of_the_wrong_shape_are_refused(key, shape):
    """A model file's ``theta`` must be (P, 3), ``phi_mean``/``phi_std`` (P,) and ``offset`` (3,)
    with P = 20 regressors; finite arrays of another shape are refused, not read."""
    full = _features(np.random.default_rng(4), 100)
    arrays = HullCorrection.fit(full, np.zeros((100, 3)), 3.0).arrays()
    arrays[key] = np.ones(shape)
    with pytest.raises(ValueError, match=r"expected theta \(20, 3\)"):
        HullCorrection.from_arrays(arrays, 3.0, 1e-3)


def test_a_zero_ridge_is_least_squares_over_the_regressors_that_vary():
    """``ridge=0`` (accepted by the hybrid's ``hull_ridge``): without command and wind columns their
    regressors have no spread and no equation; the fit is ordinary least squares on the others,
    whose predictions match ``numpy.linalg.lstsq`` on the raw regressors with an intercept."""
    rng = np.random.default_rng(4)
    full = _features(rng, 500)
    full[:, 9:] = 0.0
    Y = rng.normal(0.0, 1e-2, (500, 3))
    h = HullCorrection.fit(full, Y, 3.0, ridge=0.0)
    phi = hull_regressors(full, 3.0)
    live = phi.std(0) > 0
    assert 0 < live.sum() < len(HULL_REGRESSORS) and np.all(h.theta[~live] == 0.0)
    design = np.column_stack([np.ones(500), phi[:, live]])
    want = design @ np.linalg.lstsq(design, Y, rcond=None)[0]
    np.testing.assert_allclose(h.predict(full), want, rtol=1e-9, atol=1e-12)


def test_fit_refuses_rows_it_cannot_fit_on_by_name():
    """No rows gave a NaN correction with only numpy's warnings, a Y of other rows numpy's
    matmul message, and a negative or NaN ridge was taken as least squares and stored."""
    rng = np.random.default_rng(5)
    full, Y = _features(rng, 40), rng.normal(0, 1e-3, (40, 3))
    for f, y in ((full[:0], Y[:0]), (full, Y[:30]), (full[:, :9], Y), (full[0], Y[0]), (full, Y[:, :2])):
        with pytest.raises(ValueError, match=r"hull correction: expected full \(N, \d+\) with N >= 1 and Y \(N, 3\)"):
            HullCorrection.fit(f, y, 3.0)
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="hull correction: ridge: must"):
            HullCorrection.fit(full, Y, 3.0, ridge=bad)
    with pytest.raises(TypeError, match="hull correction: ridge"):
        HullCorrection.fit(full, Y, 3.0, ridge="0.1")


def test_fit_refuses_a_ship_length_that_is_not_a_positive_number_by_name():
    """A NaN length was stored with a fit that left out the yaw-rate regressors, and every
    correction it then made was NaN; 0 left those regressors out and -3 was taken; text failed
    in numpy's ufunc words."""
    rng = np.random.default_rng(5)
    full, Y = _features(rng, 40), rng.normal(0, 1e-3, (40, 3))
    for bad in (float("nan"), 0.0, -3.0):
        with pytest.raises(ValueError, match="hull correction: length_m: must"):
            HullCorrection.fit(full, Y, bad)
    with pytest.raises(TypeError, match="hull correction: length_m: expected a number"):
        HullCorrection.fit(full, Y, "3")
    assert np.all(np.isfinite(HullCorrection.fit(full, Y, 3.0).predict(full)))
