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
