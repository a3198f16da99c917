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
