"""Out-of-envelope guard: how far do the current inputs lie outside the training data?

The paper's hybrid became worse than physics alone once the drifting ship left the speed
range of its training data (Skulstad et al. 2022, Table 3). The guard measures the
Mahalanobis distance of a feature vector from the training features,

.. math::  d(x) = \\sqrt{(x - \\mu)^T \\Sigma^{-1} (x - \\mu)},

and shrinks the learned correction towards zero outside the envelope:

.. math::  w(d) = 1 \\ \\text{for}\\ d \\le d_0, \\qquad w(d) = \\exp\\left(-\\frac{d - d_0}{s}\\right) \\ \\text{otherwise},

with ``d_0`` a high quantile of the training distances (the envelope's edge) and ``s``
the decay scale. ``w`` is reported with every forecast step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class EnvelopeGuard:
    """Mahalanobis envelope of training features.

    Attributes
    ----------
    mean : ndarray, shape (n,)
        Feature mean.
    inv_cov : ndarray, shape (n, n)
        Inverse (regularised) covariance.
    d0 : float
        Distance at which shrinking starts (the ``quantile`` of training distances).
    scale : float
        E-folding distance of the shrink factor beyond ``d0``.
    """

    mean: np.ndarray
    inv_cov: np.ndarray
    d0: float
    scale: float

    @classmethod
    def fit(cls, X: np.ndarray, *, quantile: float = 0.99, scale: float | None = None,
            ridge: float = 1e-6) -> "EnvelopeGuard":
        """Fit the envelope to training features ``X (N, n)``.

        ``scale`` defaults to ``d0 / 2``: the correction halves about 0.35 d0 beyond the edge.
        """
        X = np.asarray(X, dtype=float)
        if not 0.5 <= quantile < 1.0:
            raise ValueError(f"quantile must lie in [0.5, 1), got {quantile}")
        mean = X.mean(axis=0)
        cov = np.cov(X, rowvar=False)
        cov = np.atleast_2d(cov) + ridge * np.trace(np.atleast_2d(cov)) / X.shape[1] * np.eye(X.shape[1])
        inv_cov = np.linalg.inv(cov)
        d = cls._distance(X, mean, inv_cov)
        d0 = float(np.quantile(d, quantile))
        return cls(mean, inv_cov, d0, float(scale) if scale is not None else 0.5 * d0)

    @staticmethod
    def _distance(X, mean, inv_cov):
        Z = np.asarray(X, dtype=float) - mean
        return np.sqrt(np.maximum(np.einsum("...i,ij,...j->...", Z, inv_cov, Z), 0.0))

    def distance(self, X: np.ndarray) -> np.ndarray:
        """Mahalanobis distance of each row of ``X (..., n)`` from the training features."""
        return self._distance(X, self.mean, self.inv_cov)

    def weight(self, X: np.ndarray) -> np.ndarray:
        """Shrink factor in (0, 1] for each row of ``X``: 1 inside the envelope."""
        d = self.distance(X)
        return np.exp(-np.maximum(d - self.d0, 0.0) / self.scale)


@dataclass
class ThrustRegime:
    """Were the nets trained with the thrusters working the way they work now?

    Station-keeping logs are full of thrust, and the residual the nets learn there is
    largely the thruster model's error: a function of the commanded thrust that has no
    meaning once the thrusters stop. The Mahalanobis envelope of the nets' own features
    does not see this (after a failure the model-predicted accelerations are small, well
    inside the station-keeping range), so the guard also compares the thrust level,

    .. math::  \\ell = \\lVert (M^{-1} \\tau_{thr}) / s \\rVert,

    with ``s`` the per-axis standard deviation of the training thrust accelerations,
    against ``lo``, a low quantile of the training levels: the weight ramps from 0 at
    ``lo / 2`` to 1 at ``lo``. It is 1 whenever the training data held thrust levels as low as
    the present one (for example when the nets were trained on drifting logs as well),
    and goes to 0 as the thrusters stop on a model trained on station keeping only.

    Attributes
    ----------
    scale : ndarray, shape (3,)
        Per-axis scale of ``M^-1 tau_thr`` [m/s^2, m/s^2, rad/s^2].
    lo : float
        Thrust level below which the weight falls (dimensionless).
    """

    scale: np.ndarray
    lo: float

    @classmethod
    def fit(cls, thrust_acc: np.ndarray, *, quantile: float = 0.01) -> "ThrustRegime":
        """Fit to the training rows' thrust accelerations ``(N, 3)``."""
        A = np.asarray(thrust_acc, dtype=float)
        if A.ndim != 2 or A.shape[1] != 3 or not np.all(np.isfinite(A)):
            raise ValueError("ThrustRegime.fit: thrust_acc must be a finite (N, 3) array")
        if not 0.0 <= quantile < 0.5:
            raise ValueError(f"ThrustRegime.fit: quantile must lie in [0, 0.5), got {quantile}")
        scale = A.std(axis=0)
        scale = np.where(scale > 1e-12, scale, 1.0)
        lo = float(np.quantile(np.linalg.norm(A / scale, axis=1), quantile))
        return cls(scale, lo)

    def level(self, thrust_acc: np.ndarray) -> np.ndarray:
        """Normalised thrust level of each row of ``thrust_acc (..., 3)``."""
        return np.linalg.norm(np.asarray(thrust_acc, dtype=float) / self.scale, axis=-1)

    def weight(self, thrust_acc: np.ndarray) -> np.ndarray:
        """Weight in [0, 1] for each row: 1 where training saw such thrust levels."""
        lev = self.level(thrust_acc)
        if self.lo <= 0.0:
            return np.ones_like(lev)
        return np.clip(2.0 * lev / self.lo - 1.0, 0.0, 1.0)
