"""Rudder forces by the MMG standard method (Yasukawa & Yoshimura 2015), extended to any inflow sign.

Each rudder ``j`` sits at ``(x_R, y_R)`` in the body frame, behind the propeller it is
paired with (a ``fixed`` thruster pointing forward) or in the plain wake. Its command is
the rudder angle ``delta`` [rad]; positive delta deflects the trailing edge to starboard
and turns the ship to starboard (the MMG convention, and that of the Esso Osaka data).

Inflow (Yasukawa & Yoshimura 2015, eqs. 36-41, written without ``J_P`` so that it holds
through ``n = 0``):

.. math::

    u_P = (1 - w_P)(u_r - y_P r), \\qquad c_T = \\frac{8 T}{\\pi \\rho D_P^2}
    \\quad(T \\ge 0 \\text{ the open-water thrust; } c_T = u_\\infty^2 - u_P^2 \\text{ in momentum theory})

    u_{jet} = (1 - \\kappa) u_P + \\kappa \\sqrt{u_P^2 + c_T}
    \\qquad\\Big(= u_P\\big[1 + \\kappa(\\sqrt{1 + 8K_T/(\\pi J_P^2)} - 1)\\big]\\Big)

    u_R = \\varepsilon \\sqrt{\\eta\\, u_{jet}^2 + (1 - \\eta)\\, u_P^2}, \\qquad \\eta = \\min(D_P / H_R,\\ 1)

    v_R = -\\gamma_R (v_r + l_R r) \\qquad (= U \\gamma_R \\beta_R \\text{ for small drift; }
    \\gamma_R \\text{ by the sign of } \\beta_R)

Normal force, with ``U_R^2 = u_R^2 + v_R^2``; for ``u_R > 0`` this is the MMG
``(rho/2) A_R U_R^2 f_alpha sin(delta - atan(v_R/u_R))``:

.. math::

    F_N = \\tfrac12 \\rho A_R f_\\alpha U_R (u_R \\sin\\delta - v_R \\cos\\delta)

    X_R = -(1 - t_R) F_N \\sin\\delta, \\quad Y_R = -(1 + a_H) F_N \\cos\\delta, \\quad
    N_R = -(x_R + a_H x_H) F_N \\cos\\delta - y_R X_R

Beyond the standard method (which is for ``u > 0``):

* **Astern inflow** (``u_P < 0``): the flat-plate form above keeps ``F_N`` along the
  rudder normal, so the rudder's effect reverses, as it does on a real ship going astern;
  ``u_jet = u_P + kappa sqrt(c_T)`` (a jet of an ahead-turning propeller against the
  reverse flow) joins the ahead branch continuously at ``u_P = 0``, and
  ``u_R = epsilon sgn(X) sqrt|X|`` with ``X = eta u_jet |u_jet| + (1 - eta) u_P |u_P|``.
* **Reversing propeller** (``T < 0``): its race runs forward, away from the rudder, so
  ``c_T = 0`` (the rudder sees the plain wake).

References
----------
Yasukawa, H., Yoshimura, Y. (2015). Introduction of MMG standard method for ship
maneuvering predictions. J. Mar. Sci. Technol. 20, 37-52. doi:10.1007/s00773-014-0293-y
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..config import real_array
from .compiled_cache import KERNEL_FASTMATH
from .thrusters import THR_D, THR_TDED, THR_WAKE, THR_Y

#: Column layout of the packed rudder parameter array ``rud (R, 14)``.
(RUD_X, RUD_Y, RUD_AREA, RUD_FALPHA, RUD_ETA, RUD_EPS, RUD_KAPPA, RUD_LR, RUD_GNEG, RUD_GPOS, RUD_TR,
 RUD_AH, RUD_XH, RUD_PROP) = range(14)
RUD_NCOL = 14


def pack_rudders(vessel) -> np.ndarray:
    """Packed rudder parameters ``(R, RUD_NCOL)`` of a vessel (``RUD_PROP`` = thruster index or -1)."""
    names = [t.name for t in vessel.thrusters]
    rud = np.zeros((len(vessel.rudders), RUD_NCOL))
    for j, r in enumerate(vessel.rudders):
        p = names.index(r.propeller) if r.propeller is not None else -1
        D_P = vessel.thrusters[p].diameter_m if p >= 0 else 0.0
        rud[j, RUD_X] = r.x_m
        rud[j, RUD_Y] = r.y_m
        rud[j, RUD_AREA] = r.area_m2
        rud[j, RUD_FALPHA] = r.f_alpha
        # eta = D_P / H_R: the part of the rudder span in the slipstream (at most all of it)
        rud[j, RUD_ETA] = min(D_P / r.span_m, 1.0)
        rud[j, RUD_EPS] = r.wake_ratio
        rud[j, RUD_KAPPA] = r.slipstream_factor
        rud[j, RUD_LR] = r.l_R_m if r.l_R_m is not None else r.x_m
        rud[j, RUD_GNEG] = r.flow_straightening_neg
        rud[j, RUD_GPOS] = r.flow_straightening_pos
        rud[j, RUD_TR] = r.steering_resistance_deduction
        rud[j, RUD_AH] = r.hull_force_factor
        rud[j, RUD_XH] = r.x_H_m if r.x_H_m is not None else r.x_m
        rud[j, RUD_PROP] = p
    return rud


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def rudder_inflow_scalar(u_p, thrust_open_N, diameter_m, rho, eps, kappa, eta):
    """Axial rudder inflow u_R [m/s] from the propeller inflow u_P [m/s] and open-water thrust [N]."""
    c_t = 0.0
    if thrust_open_N > 0.0 and diameter_m > 0.0:
        c_t = 8.0 * thrust_open_N / (math.pi * rho * diameter_m * diameter_m)
    if u_p >= 0.0:
        u_jet = (1.0 - kappa) * u_p + kappa * math.sqrt(u_p * u_p + c_t)
    else:
        u_jet = u_p + kappa * math.sqrt(c_t)
    x = eta * u_jet * abs(u_jet) + (1.0 - eta) * u_p * abs(u_p)
    if x >= 0.0:
        return eps * math.sqrt(x)
    return -eps * math.sqrt(-x)


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def rudder_force_scalar(ur, vr, r, cd, sd, thrust_open_N, u_p, diameter_m, rho, rud, j):
    """Load ``(X_N, Y_N, N_Nm)`` of rudder ``j`` (row of ``rud``) at angle cos/sin ``cd, sd``.

    ``ur, vr, r`` are the body-origin velocities relative to the water; ``u_p`` the
    propeller inflow [m/s] and ``thrust_open_N`` its open-water thrust (0 without a propeller).
    """
    u_r = rudder_inflow_scalar(u_p, thrust_open_N, diameter_m, rho, rud[j, RUD_EPS], rud[j, RUD_KAPPA],
                               rud[j, RUD_ETA])
    lat = vr + rud[j, RUD_LR] * r          # lateral velocity of the rudder through the water
    gamma = rud[j, RUD_GNEG] if lat > 0.0 else rud[j, RUD_GPOS]  # beta_R < 0 when lat > 0
    v_r = -gamma * lat
    U_R = math.sqrt(u_r * u_r + v_r * v_r)
    f_n = 0.5 * rho * rud[j, RUD_AREA] * rud[j, RUD_FALPHA] * U_R * (u_r * sd - v_r * cd)
    x = -(1.0 - rud[j, RUD_TR]) * f_n * sd
    y = -(1.0 + rud[j, RUD_AH]) * f_n * cd
    n = -(rud[j, RUD_X] + rud[j, RUD_AH] * rud[j, RUD_XH]) * f_n * cd - rud[j, RUD_Y] * x
    return x, y, n


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def rudder_forces_scalar(ur, vr, r, prep, off, rud, thr, rho, thrusts, b):
    """Summed load ``(X_N, Y_N, N_Nm)`` of all rudders of one vessel.

    ``prep[off + j]`` and ``prep[off + R + j]`` hold cos and sin of rudder j's angle;
    ``thrusts[b, p]`` the delivered thrust of its propeller ``p`` (already computed this
    stage), from which the open-water thrust is ``thrusts / (1 - t)``.
    """
    R = rud.shape[0]
    fx = 0.0
    fy = 0.0
    fn = 0.0
    for j in range(R):
        p = int(rud[j, RUD_PROP])
        if p >= 0:
            t_open = thrusts[b, p] / (1.0 - thr[p, THR_TDED])
            u_p = (1.0 - thr[p, THR_WAKE]) * (ur - thr[p, THR_Y] * r)
            dia = thr[p, THR_D]
        else:
            t_open = 0.0
            u_p = ur - rud[j, RUD_Y] * r
            dia = 0.0
        x, y, n = rudder_force_scalar(ur, vr, r, prep[off + j], prep[off + R + j], t_open, u_p, dia, rho, rud, j)
        fx += x
        fy += y
        fn += n
    return fx, fy, fn


@numba.njit(cache=True)
def _rudder_batch(nu_r, delta, thrust_open, u_p, dia, rho, rud, out):
    for b in range(nu_r.shape[0]):
        for j in range(rud.shape[0]):
            x, y, n = rudder_force_scalar(nu_r[b, 0], nu_r[b, 1], nu_r[b, 2], math.cos(delta[b, j]),
                                          math.sin(delta[b, j]), thrust_open[b, j], u_p[b, j], dia[j], rho, rud, j)
            out[b, j, 0] = x
            out[b, j, 1] = y
            out[b, j, 2] = n


def _finite_rows(name, value, B, width):
    """``value`` as finite floats ``(B, width)`` from ``(width,)`` or ``(B, width)`` (B = None: any
    batch), or a ValueError naming the argument (not numpy's broadcasting or conversion message)."""
    a = real_array(name, value)
    batch = "B" if B is None else str(B)
    if a.ndim == 0 and B is not None:       # one number for every rudder
        a = np.full(width, float(a))
    if a.ndim not in (1, 2) or a.shape[-1] != width or (B is not None and a.ndim == 2 and a.shape[0] not in (1, B)):
        raise ValueError(f"{name}: expected shape ({width},) or ({batch}, {width}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    a = np.atleast_2d(a)
    return a if B is None else np.broadcast_to(a, (B, width))


def rudder_forces(model, nu_r, delta_rad, thrust_open_N=None):
    """Load of each rudder of a model for given states, angles and propeller thrusts (numpy API).

    Parameters
    ----------
    model : hybridship.physics.model.DynamicModel
        The model whose rudders are evaluated.
    nu_r : array_like, shape (B, 3) or (3,)
        ``[u_r, v_r, r]`` relative to the water [m/s, m/s, rad/s].
    delta_rad : array_like, shape (B, R) or (R,)
        Rudder angles [rad], positive turns the ship to starboard.
    thrust_open_N : array_like, shape (B, R) or (R,), optional
        Open-water thrust of each rudder's propeller [N] (default 0; ignored for a rudder
        without propeller).

    Returns
    -------
    ndarray, shape (B, R, 3)
        ``[X_N, Y_N, N_Nm]`` per rudder.
    """
    P = model.arrays
    rud, thr = P.rud, P.thr
    R = rud.shape[0]
    nu_r = _finite_rows("nu_r", nu_r, None, 3)
    B = nu_r.shape[0]
    delta = np.ascontiguousarray(_finite_rows("delta_rad", delta_rad, B, R))
    t_open = np.zeros((B, R)) if thrust_open_N is None else _finite_rows("thrust_open_N", thrust_open_N, B, R)
    p = rud[:, RUD_PROP].astype(int)
    has = p >= 0
    u_p = nu_r[:, :1] - rud[None, :, RUD_Y] * nu_r[:, 2:3]
    if has.any():
        pp = p[has]
        u_p[:, has] = (1.0 - thr[pp, THR_WAKE])[None, :] * (nu_r[:, :1] - thr[pp, THR_Y][None, :] * nu_r[:, 2:3])
    t_open = np.where(has[None, :], t_open, 0.0)
    dia = np.where(has, thr[np.maximum(p, 0), THR_D] if thr.shape[0] else 0.0, 0.0)
    out = np.empty((B, R, 3))
    _rudder_batch(np.ascontiguousarray(nu_r), delta, np.ascontiguousarray(t_open), np.ascontiguousarray(u_p),
                  np.ascontiguousarray(dia, dtype=float), float(P.rb[2]), rud, out)
    return out
