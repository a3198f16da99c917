"""Perturbed vessels: per-sample model parameters drawn with the ``[true_vessel]`` spread.

The vessel file's ``[true_vessel]`` table says how far the simulator's "real" ship is from
the identified model (factors per DOF on added mass, linear and nonlinear damping, wind
coefficients, and a thrust factor). A drift-off study does not know the real ship, so each
Monte-Carlo sample draws its own factors, log-normally around the nominal model::

    factor = exp(spread * |ln f_true| * z),   z ~ N(0, 1) per factor and DOF

so that the file's "true" vessel is a one-sigma draw (``spread = 1``); ``spread = 0``
gives the nominal model. The factors act on the nominal packed parameters exactly as
:func:`hybridship.physics.model.build_model_arrays` applies ``[true_vessel]`` (a test
checks that :func:`scaled_arrays` with the file's own factors reproduces it).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..config import check_number, check_whole_number
from ..physics.model import ModelArrays
from ..physics.thrusters import THR_TDED

__all__ = ["VesselScales", "StackedArrays", "draw_scales", "true_vessel_scales", "scaled_arrays", "spread_text"]


class VesselScales(NamedTuple):
    """Per-sample factors, each ``(N, 3)`` per DOF [surge, sway, yaw] except ``thrust`` ``(N,)``."""

    added_mass: np.ndarray
    linear_damping: np.ndarray
    nonlinear_damping: np.ndarray
    wind_coefficient: np.ndarray
    thrust: np.ndarray


class StackedArrays(NamedTuple):
    """The per-sample parts of :class:`~hybridship.physics.model.ModelArrays`, batch-first."""

    m_inv: np.ndarray     # (N, 3, 3)
    m_a: np.ndarray       # (N, 3, 3)
    d_lin: np.ndarray     # (N, 3, 3)
    d_quad: np.ndarray    # (N, 3)
    d_lift: np.ndarray    # (N, 8)
    strip_w: np.ndarray   # (N, n_strips)
    thr: np.ndarray       # (N, K, 8)
    wind_p: np.ndarray    # (N, 4)


def true_vessel_scales(vessel, n: int = 1) -> VesselScales:
    """The file's own ``[true_vessel]`` factors repeated ``n`` times."""
    p = vessel.true_vessel
    rep = lambda v: np.repeat(np.asarray(v, float)[None, :], n, axis=0)  # noqa: E731
    return VesselScales(rep(p.added_mass_scale), rep(p.linear_damping_scale), rep(p.nonlinear_damping_scale),
                        rep(p.wind_coefficient_scale), np.full(n, float(p.thrust_scale)))


def spread_text(vessel, spread: float) -> str:
    """The vessel spread as a report states it; "none" when it draws nothing (spread 0, or
    a vessel file without ``[true_vessel]`` factors other than 1)."""
    if spread == 0:
        return "none (the nominal model)"
    if all(np.all(np.asarray(f, float) == 1.0) for f in true_vessel_scales(vessel, 1)):
        return "none: the vessel file has no [true_vessel] factors (every sample is the nominal model)"
    return f"{spread:g} x [true_vessel]"


def draw_scales(vessel, n: int, rng: np.random.Generator, spread: float = 1.0) -> VesselScales:
    """``n`` log-normal draws around the nominal model with the ``[true_vessel]`` spread (module notes)."""
    # True read as spread 1; text, None and a float count failed in numpy's words
    spread = check_number("vessel_spread", spread, lo=0.0)
    n = check_whole_number("n", n)
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng: expected a numpy.random.Generator (numpy.random.default_rng(seed)), got "
                        f"{type(rng).__name__}")
    ref = true_vessel_scales(vessel, 1)
    out = []
    for f in ref:
        sigma = spread * np.abs(np.log(np.asarray(f[0], float)))
        z = rng.standard_normal((n,) + np.shape(sigma))
        out.append(np.exp(sigma * z))
    return VesselScales(*out)


def scaled_arrays(P: ModelArrays, scales: VesselScales) -> StackedArrays:
    """Per-sample packed parameters: the nominal ``P`` with the factors of ``scales`` applied."""
    am = np.asarray(scales.added_mass, float)
    n = am.shape[0]
    M_RB = np.linalg.inv(P.m_inv) - P.m_a
    s = np.sqrt(am)
    m_a = P.m_a[None] * s[:, :, None] * s[:, None, :]     # keeps M_A symmetric
    m_inv = np.linalg.inv(M_RB[None] + m_a)
    d_lin = P.d_lin[None] * np.asarray(scales.linear_damping, float)[:, :, None]
    nd = np.asarray(scales.nonlinear_damping, float)
    d_quad = P.d_quad[None] * nd
    d_lift = P.d_lift[None] * nd[:, [1, 1, 2, 2, 1, 1, 2, 2]]
    strip_w = P.strip_w[None] * nd[:, 1:2]
    thr = np.repeat(P.thr[None], n, axis=0)
    th = np.asarray(scales.thrust, float)[:, None]
    thr[:, :, THR_TDED] = 1.0 - th * (1.0 - P.thr[None, :, THR_TDED])
    # Scaling C_X, C_Y, C_N by (s0, s1, s2) = scaling A_F by s0, A_L by s1 and the moment arm by s2 / s1.
    wc = np.asarray(scales.wind_coefficient, float)
    wind_p = np.repeat(P.wind_p[None], n, axis=0)
    wind_p[:, 1] *= wc[:, 0]
    wind_p[:, 2] *= wc[:, 1]
    wind_p[:, 3] *= wc[:, 2] / wc[:, 1]
    return StackedArrays(m_inv, m_a, d_lin, d_quad, d_lift, strip_w, thr, wind_p)
