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

from ..config import check_number, real_array
from ..frames import wrap_pi


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

        ``scale`` defaults to ``d0 / 2``: the correction halves about 0.35 d0 beyond the edge;
        a given one must be finite and >= 0 (0: no correction beyond the edge). ``ridge`` (> 0)
        adds that share of the mean feature variance to the covariance's diagonal.

        Raises
        ------
        TypeError, ValueError
            ``X`` not a finite 2-D array of real numbers with at least two rows and one
            column that varies (its covariance would be NaN or singular), naming it.
        """
        X = real_array("EnvelopeGuard.fit: X", X)
        if X.ndim != 2 or X.shape[0] < 2 or X.shape[1] == 0:
            raise ValueError(f"EnvelopeGuard.fit: X: expected a 2-D array (N, n) of features with N >= 2 rows "
                             f"and n >= 1, got shape {X.shape}")
        if not np.all(np.isfinite(X)):
            raise ValueError("EnvelopeGuard.fit: X: NaN or inf in the features (every distance would be NaN)")
        if not np.any(np.ptp(X, axis=0) > 0):
            raise ValueError("EnvelopeGuard.fit: X: every feature is constant over the rows (the covariance "
                             "is singular); expected at least one that varies")
        quantile = check_number("EnvelopeGuard.fit: quantile", quantile, lo=0.5)
        if quantile >= 1.0:
            raise ValueError(f"EnvelopeGuard.fit: quantile: must lie in [0.5, 1), got {quantile!r}")
        if scale is not None:
            scale = check_number("EnvelopeGuard.fit: scale", scale, lo=0.0)
        ridge = check_number("EnvelopeGuard.fit: ridge", ridge, lo=0.0, lo_open=True)
        mean = X.mean(axis=0)
        cov = np.cov(X, rowvar=False)
        cov = np.atleast_2d(cov) + ridge * np.trace(np.atleast_2d(cov)) / X.shape[1] * np.eye(X.shape[1])
        inv_cov = np.linalg.inv(cov)
        d = cls._distance(X, mean, inv_cov)
        d0 = float(np.quantile(d, quantile))
        return cls(mean, inv_cov, d0, scale if scale is not None else 0.5 * d0)

    @staticmethod
    def _distance(X, mean, inv_cov):
        Z = np.asarray(X, dtype=float) - mean
        return np.sqrt(np.maximum(np.einsum("...i,ij,...j->...", Z, inv_cov, Z), 0.0))

    def distance(self, X: np.ndarray) -> np.ndarray:
        """Mahalanobis distance of each row of ``X (..., n)`` from the training features."""
        return self._distance(X, self.mean, self.inv_cov)

    def weight(self, X: np.ndarray) -> np.ndarray:
        """Shrink factor in [0, 1] for each row of ``X``: 1 inside the envelope, 0 beyond it with
        ``scale`` 0 (and, as ``exp`` underflows, far beyond it with any scale)."""
        excess = np.maximum(self.distance(X) - self.d0, 0.0)
        # a point envelope (d0 = 0 and the default scale d0 / 2 = 0): 1 on it, 0 beyond, not 0 / 0
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(excess == 0.0, 1.0, np.exp(-excess / self.scale))


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
        """Fit to the training rows' thrust accelerations ``(N, 3)``.

        Raises
        ------
        TypeError, ValueError
            ``thrust_acc`` not a finite (N, 3) array of real numbers with N >= 1 (text and
            complex numbers included), or ``quantile`` not in [0, 0.5), naming it.
        """
        A = real_array("ThrustRegime.fit: thrust_acc", thrust_acc)
        if A.ndim != 2 or A.shape[1] != 3 or A.shape[0] == 0 or not np.all(np.isfinite(A)):
            raise ValueError(f"ThrustRegime.fit: thrust_acc must be a finite (N, 3) array with N >= 1, "
                             f"got shape {A.shape}")
        quantile = check_number("ThrustRegime.fit: quantile", quantile, lo=0.0)
        if quantile >= 0.5:
            raise ValueError(f"ThrustRegime.fit: quantile: must lie in [0, 0.5), got {quantile!r}")
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


@dataclass
class CommandRegime:
    """Shrink the learned correction in command regimes where it did not help on held-back data.

    The Mahalanobis envelope sees the nets' inputs, not the way the ship is driven: a slow
    approach with the propeller reversing lies inside the envelope of forward-speed
    turning runs, yet the residual there is another function. Each step is put in one of
    12 regimes,

    * propeller: ahead (rpm / max rpm > ``rpm_eps``), stopped, astern (< ``-rpm_eps``);
    * speed: low (Froude number of ``|u|`` below ``froude_lo``) or not;
    * first rotatable actuator (rudder): hard over (``|angle| > angle_hard_rad``, the angle
      wrapped to [-pi, pi)) or not;

    and each regime has a weight in [0, 1]: the least-squares scale of the nets' mean
    one-step prediction onto the measured residual deviation on rows the nets were not
    trained on (the part :meth:`hybridship.predictors.HybridPredictor.fit` holds back),
    clipped to [0, 1], summed over the three standardised outputs. A regime with fewer than
    ``min_rows`` held-back rows keeps weight 1 if the training rows covered it (at least
    ``min_rows`` of them) and gets 0 if neither did (never seen: no correction).

    Attributes
    ----------
    weights : ndarray, shape (12,)
        Weight per regime (see :meth:`regime`).
    n_train, n_held : ndarray of int, shape (12,)
        Training and held-back rows per regime.
    rpm_eps, froude_lo, angle_hard_rad, length_m : float
        Regime boundaries and the ship length of the Froude number [m].
    """

    weights: np.ndarray
    n_train: np.ndarray
    n_held: np.ndarray
    rpm_eps: float = 0.05
    froude_lo: float = 0.05
    angle_hard_rad: float = float(np.radians(20.0))
    length_m: float = 1.0

    N_REGIMES = 12

    def regime(self, rpm_rel, u_m_s, angle_rad) -> np.ndarray:
        """Regime index 0..11 of each row (arrays of one shape)."""
        rpm_rel = np.asarray(rpm_rel, dtype=float)
        prop = np.where(rpm_rel > self.rpm_eps, 0, np.where(rpm_rel < -self.rpm_eps, 2, 1))
        low = np.abs(np.asarray(u_m_s, dtype=float)) < self.froude_lo * np.sqrt(9.81 * self.length_m)
        # on the circle: an azimuth logged as 350 deg is the one logged as -10 deg
        hard = np.abs(wrap_pi(np.asarray(angle_rad, dtype=float))) > self.angle_hard_rad
        return prop * 4 + low.astype(int) * 2 + hard.astype(int)

    def weight(self, rpm_rel, u_m_s, angle_rad) -> np.ndarray:
        """Weight of each row's regime."""
        return self.weights[self.regime(rpm_rel, u_m_s, angle_rad)]

    @classmethod
    def fit(cls, train_cmd, held_cmd, held_target, held_pred, *, length_m: float, min_rows: int = 50,
            **bounds) -> "CommandRegime":
        """Fit from ``(rpm_rel, u_m_s, angle_rad)`` tuples of arrays for the training and the
        held-back rows, and the held-back rows' standardised targets and mean predictions ``(N, 3)``."""
        obj = cls(np.ones(cls.N_REGIMES), np.zeros(cls.N_REGIMES, int), np.zeros(cls.N_REGIMES, int),
                  length_m=float(length_m), **bounds)
        rt = obj.regime(*train_cmd)
        rh = obj.regime(*held_cmd)
        obj.n_train = np.bincount(rt.ravel(), minlength=cls.N_REGIMES)
        obj.n_held = np.bincount(rh.ravel(), minlength=cls.N_REGIMES)
        T = np.asarray(held_target, dtype=float)
        Pm = np.asarray(held_pred, dtype=float)
        w = np.ones(cls.N_REGIMES)
        for k in range(cls.N_REGIMES):
            sel = rh == k
            if obj.n_held[k] >= min_rows:
                num = float((T[sel] * Pm[sel]).sum())
                den = float((Pm[sel] ** 2).sum())
                w[k] = float(np.clip(num / den, 0.0, 1.0)) if den > 0 else 1.0
            elif obj.n_train[k] < min_rows:
                w[k] = 0.0
        obj.weights = w
        return obj
