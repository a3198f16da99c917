"""The out-of-envelope guard and the regime weights of the learned correction."""

from __future__ import annotations

import numpy as np
import pytest

from hybridship.residual.guard import EnvelopeGuard, ThrustRegime


@pytest.mark.parametrize("X, match", [
    (np.array([[1.0, 2.0], [np.nan, 1.0], [3.0, 4.0], [5.0, 1.0]]), "NaN or inf"),
    (np.ones((10, 3)), "constant"),
    (np.zeros((1, 2)), "N >= 2"),
    (np.zeros((0, 2)), "N >= 2"),
    (np.arange(5.0), "2-D"),
])
def test_envelope_fit_refuses_features_it_cannot_measure_a_distance_on(X, match):
    """A NaN feature gave a NaN edge and NaN weights without a word, constant features
    numpy's 'Singular matrix', one row a NaN covariance and none an IndexError."""
    with pytest.raises(ValueError, match=f"EnvelopeGuard.fit: X: .*{match}"):
        EnvelopeGuard.fit(X)


def test_envelope_fit_refuses_text_features():
    with pytest.raises(TypeError, match="EnvelopeGuard.fit: X"):
        EnvelopeGuard.fit([["1", "2"], ["3", "4"]])


def test_thrust_regime_fit_refuses_no_rows():
    """No training rows stopped in numpy's IndexError of an empty quantile."""
    with pytest.raises(ValueError, match=r"ThrustRegime.fit: thrust_acc.*N >= 1.*\(0, 3\)"):
        ThrustRegime.fit(np.zeros((0, 3)))


def test_thrust_regime_fit_refuses_text_and_complex_thrust_by_name():
    """Text that reads as numbers was parsed into a regime, complex accelerations lost their
    imaginary part with only numpy's warning, and other text failed in float()'s words; each
    is now refused naming thrust_acc, as EnvelopeGuard.fit refuses its features."""
    A = np.random.default_rng(0).normal(size=(50, 3))
    for bad in (A.astype(str), A + 1j, [["a", "b", "c"]] * 5):
        with pytest.raises(TypeError, match="ThrustRegime.fit: thrust_acc: expected an array of real numbers"):
            ThrustRegime.fit(bad)


@pytest.mark.parametrize("fit, lo, hi", [(EnvelopeGuard.fit, 0.5, 1.0), (ThrustRegime.fit, 0.0, 0.5)])
def test_a_quantile_that_is_not_a_number_in_range_is_refused_by_name(fit, lo, hi):
    """Text or None stopped in Python's own "'<=' not supported between ..."."""
    X = np.random.default_rng(0).normal(size=(50, 3))
    name = fit.__qualname__
    for bad in ("0.9", None, True):
        with pytest.raises(TypeError, match=f"{name}: quantile: expected a number"):
            fit(X, quantile=bad)
    for bad in (lo - 0.01, hi, float("nan")):
        with pytest.raises(ValueError, match=f"{name}: quantile: must"):
            fit(X, quantile=bad)


def test_the_shrink_factor_reaches_zero_beyond_the_edge():
    """The documented range is [0, 1]: with scale 0 (no correction beyond the edge) and far
    outside with the default scale the factor is exactly 0, not in (0, 1]."""
    X = np.random.default_rng(1).normal(size=(200, 2))
    inside, far = np.zeros((1, 2)), np.full((1, 2), 1e4)
    hard = EnvelopeGuard.fit(X, scale=0.0)
    assert hard.weight(inside)[0] == 1.0 and hard.weight(far)[0] == 0.0
    assert EnvelopeGuard.fit(X).weight(far)[0] == 0.0
    w = EnvelopeGuard.fit(X).weight(np.linspace(-50, 50, 101)[:, None] * [1.0, 0.5])
    assert np.all((w >= 0.0) & (w <= 1.0))


@pytest.mark.parametrize("ridge, error", [(-2.0, ValueError), (0.0, ValueError), (float("nan"), ValueError),
                                          ("1e-6", TypeError)])
def test_a_ridge_that_is_not_a_positive_number_is_refused_by_name(ridge, error):
    """A ridge of -2 gave an envelope of edge 0 whose weight was 1 everywhere, NaN gave NaN
    weights, text numpy's "can't multiply sequence"; 0 leaves collinear features singular."""
    X = np.random.default_rng(0).normal(size=(500, 2))
    with pytest.raises(error, match="EnvelopeGuard.fit: ridge"):
        EnvelopeGuard.fit(X, ridge=ridge)


def test_the_quantiles_set_the_edge_and_the_low_level_and_the_ridge_is_a_share_of_the_variance():
    """``quantile`` is the share of the training rows inside the envelope's edge ``d0`` and the
    share of training thrust levels below ``lo`` (the tests above fit at the defaults only, so
    a fit that ignored it passed); the ridge is a share of the mean feature variance, so the
    envelope does not depend on the features' units."""
    rng = np.random.default_rng(2)
    X = rng.normal(size=(1000, 2)) * [1.0, 30.0]
    for q in (0.6, 0.9):
        g = EnvelopeGuard.fit(X, quantile=q)
        assert g.d0 == pytest.approx(np.quantile(g.distance(X), q), rel=1e-12)
        assert np.mean(g.weight(X) == 1.0) == pytest.approx(q, abs=2e-3)
    x = np.array([[3.0, -40.0], [0.5, 90.0]])
    wide, narrow = EnvelopeGuard.fit(X, ridge=0.5), EnvelopeGuard.fit(1e3 * X, ridge=0.5)
    np.testing.assert_allclose(narrow.distance(1e3 * x), wide.distance(x), rtol=1e-9)
    assert narrow.d0 == pytest.approx(wide.d0, rel=1e-9)
    A = rng.normal([0.02, -0.01, 0.0005], [0.01, 0.01, 0.0003], size=(2000, 3))
    for q in (0.1, 0.3):
        regime = ThrustRegime.fit(A, quantile=q)
        assert regime.lo == pytest.approx(np.quantile(regime.level(A), q), rel=1e-12)
