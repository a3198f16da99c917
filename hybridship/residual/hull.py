"""A physically structured, linear-in-parameters correction of the model's acceleration.

Grey-box system identification in the spirit of the MMG model's polynomial hull
derivatives: before the nets, the one-step residual acceleration (body frame, per DOF) is
regressed on fixed MMG-style regressors of the model-predicted velocities and the
commands,

.. math::  \\Delta\\dot\\nu \\approx \\Theta^T \\phi(u, v, r, n, \\delta, u_{rw}, v_{rw}),

with a ridge penalty on standardised regressors (a closed-form fit). The nets then learn
what remains. The regressors (:data:`HULL_REGRESSORS`) are the products of the MMG hull
polynomial up to second order (``r`` enters as ``r L``, a speed), the rudder normal-force
terms (``sin(delta)`` times ``u|u|``, ``u n`` and ``n|n|``, and ``sin(delta)^2`` times ``u^2``
and ``n^2``; ``n`` is the rpm over its maximum), the propeller terms ``n|n|`` and ``u n``, the wind terms
``u_rw|u_rw|``, ``v_rw|v_rw|`` and ``u_rw v_rw``, plus a constant (the offset). They are built from the
hybrid's full feature vector (:data:`~hybridship.residual.features.ALL_FEATURES` order),
so every rollout step has them at no extra physics cost. Multi-step training may fine-tune
``Theta`` together with the nets (:class:`~hybridship.residual.multistep.MultiStepConfig`
``tune_hull``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import check_number, real_array
from .features import ALL_FEATURES

#: Names of the regressors, in the order of :func:`hull_regressors` (``rL`` = r times L_pp,
#: ``n`` = rpm over its maximum, ``d`` = rudder angle).
HULL_REGRESSORS = ("u|u|", "v|v|", "rL|rL|", "u v", "u rL", "v rL", "|v| rL", "v |rL|", "v^2", "rL^2",
                   "u|u| sin d", "u n sin d", "n|n| sin d", "u^2 sin^2 d", "n^2 sin^2 d",
                   "n|n|", "u n", "urw|urw|", "vrw|vrw|", "urw vrw")

_COL = {k: ALL_FEATURES.index(k) for k in ("u_hat_m_s", "v_hat_m_s", "r_hat_rad_s", "rpm_main_rel",
                                           "angle_main_rad", "wind_rel_u_m_s", "wind_rel_v_m_s")}


def hull_regressors(full, length_m: float, lib=np):
    """The :data:`HULL_REGRESSORS` (..., P) from full feature vectors (..., len(ALL_FEATURES)).

    ``full`` may be a torch tensor (``lib=torch``). Columns of features that are not
    computed (no command features) are zeros, and so are the regressors built from them.
    """
    u, v = full[..., _COL["u_hat_m_s"]], full[..., _COL["v_hat_m_s"]]
    rl = full[..., _COL["r_hat_rad_s"]] * length_m
    n, d = full[..., _COL["rpm_main_rel"]], full[..., _COL["angle_main_rad"]]
    urw, vrw = full[..., _COL["wind_rel_u_m_s"]], full[..., _COL["wind_rel_v_m_s"]]
    ab = lib.abs
    sd = lib.sin(d)
    cols = [u * ab(u), v * ab(v), rl * ab(rl), u * v, u * rl, v * rl, ab(v) * rl, v * ab(rl), v * v, rl * rl,
            u * ab(u) * sd, u * n * sd, n * ab(n) * sd, u * u * sd * sd, n * n * sd * sd,
            n * ab(n), u * n, urw * ab(urw), vrw * ab(vrw), urw * vrw]
    return lib.stack(cols, -1)


@dataclass
class HullCorrection:
    """``Theta`` (P, 3) on standardised regressors: ``correction = ((phi - mean) / std) @ Theta + offset``.

    Attributes
    ----------
    theta : ndarray, shape (P, 3)
        Coefficients per regressor and DOF (surge [m/s^2], sway [m/s^2], yaw [rad/s^2] per
        standardised unit).
    phi_mean, phi_std : ndarray, shape (P,)
        Standardisation of the regressors (std 1 and theta 0 for a constant or absent one).
    offset : ndarray, shape (3,)
        Mean target (the intercept).
    length_m : float
        Ship length that turns ``r`` into a speed [m].
    ridge : float
        Ridge penalty per training row on the standardised coefficients.
    scale : ndarray, shape (3,)
        Standard deviation of the targets it was fitted to (the step size of a multi-step
        fine-tuning; not stored in model files).
    """

    theta: np.ndarray
    phi_mean: np.ndarray
    phi_std: np.ndarray
    offset: np.ndarray
    length_m: float
    ridge: float = 1e-3
    scale: np.ndarray | None = None

    def __post_init__(self):
        if self.scale is None:
            self.scale = np.ones(3)

    @classmethod
    def fit(cls, full: np.ndarray, Y: np.ndarray, length_m: float, ridge: float = 1e-3) -> "HullCorrection":
        """Ridge regression of targets ``Y`` (N, 3) on the regressors of ``full`` (N, F); ``ridge``
        0 is least squares over the regressors that vary.

        Raises
        ------
        TypeError, ValueError
            ``full`` not (N, len(ALL_FEATURES)) with N >= 1, ``Y`` not (N, 3), NaN or inf in
            either, ``length_m`` not a finite number > 0, or ``ridge`` not a finite number >= 0,
            naming the argument.
        """
        full = real_array("hull correction: full", full)
        Y = real_array("hull correction: Y", Y)
        # a NaN length left the yaw-rate regressors out and was stored, so every later
        # correction was NaN; 0 left them out without a word
        length_m = check_number("hull correction: length_m", length_m, lo=0.0, lo_open=True)
        ridge = check_number("hull correction: ridge", ridge, lo=0.0)
        if full.ndim != 2 or full.shape[0] == 0 or full.shape[1] != len(ALL_FEATURES) \
                or Y.shape != (full.shape[0], 3):
            raise ValueError(f"hull correction: expected full (N, {len(ALL_FEATURES)}) with N >= 1 and Y (N, 3), "
                             f"got {full.shape} and {Y.shape}")
        if not np.all(np.isfinite(full)) or not np.all(np.isfinite(Y)):
            raise ValueError("hull correction: features and targets must be finite")
        phi = hull_regressors(full, length_m)
        mean = phi.mean(0)
        std = phi.std(0)
        live = std > 1e-12
        std = np.where(live, std, 1.0)
        Z = (phi - mean) / std
        Z[:, ~live] = 0.0
        off = Y.mean(0)
        N = Z.shape[0]
        if ridge > 0:
            A = Z.T @ Z / N + ridge * np.eye(Z.shape[1])
            theta = np.linalg.solve(A, Z.T @ (Y - off) / N)
        else:
            # plain least squares over the live regressors (those without spread have no
            # equation; collinear ones get the minimum-norm split)
            theta = np.zeros((Z.shape[1], Y.shape[1]))
            theta[live] = np.linalg.lstsq(Z[:, live], Y - off, rcond=None)[0]
        theta[~live] = 0.0
        return cls(theta, mean, std, off, float(length_m), float(ridge), np.where(Y.std(0) > 0, Y.std(0), 1.0))

    def zeroed(self) -> "HullCorrection":
        """The same regressors and standardisation with no correction (the start of a free-run fit)."""
        return HullCorrection(np.zeros_like(self.theta), self.phi_mean, self.phi_std, np.zeros(3), self.length_m,
                              self.ridge, self.scale)

    def predict(self, full: np.ndarray) -> np.ndarray:
        """Correction (..., 3) at full feature vectors (..., F) (numpy)."""
        return ((hull_regressors(full, self.length_m) - self.phi_mean) / self.phi_std) @ self.theta + self.offset

    def predict_torch(self, full, theta, offset):
        """The same with torch tensors ``theta`` (P, 3) and ``offset`` (3,) (for multi-step training)."""
        import torch

        z = (hull_regressors(full, self.length_m, lib=torch)
             - torch.as_tensor(self.phi_mean, dtype=full.dtype)) / torch.as_tensor(self.phi_std, dtype=full.dtype)
        return z @ theta + offset

    def arrays(self) -> dict:
        """The arrays of a model file."""
        return {"hull_theta": self.theta, "hull_phi_mean": self.phi_mean, "hull_phi_std": self.phi_std,
                "hull_offset": self.offset}

    @classmethod
    def from_arrays(cls, data: dict, length_m: float, ridge: float) -> "HullCorrection":
        """Read back from a model file's arrays; ValueError on wrong shapes or non-finite values."""
        P = len(HULL_REGRESSORS)
        theta = np.asarray(data["hull_theta"], dtype=float)
        mean, std = (np.asarray(data[k], dtype=float) for k in ("hull_phi_mean", "hull_phi_std"))
        off = np.asarray(data["hull_offset"], dtype=float)
        if theta.shape != (P, 3) or mean.shape != (P,) or std.shape != (P,) or off.shape != (3,):
            raise ValueError(f"hull correction: expected theta ({P}, 3), phi_mean/phi_std ({P},), offset (3,)")
        if not all(np.all(np.isfinite(a)) for a in (theta, mean, std, off)) or np.any(std <= 0):
            raise ValueError("hull correction contains NaN, inf or a non-positive scale")
        return cls(theta, mean, std, off, float(length_m), float(ridge))
