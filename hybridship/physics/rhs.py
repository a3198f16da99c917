"""Right-hand side of the 3-DOF model for one vessel: eq. 1 solved for nu_dot (compiled kernels).

The loads of the hull (:mod:`.hull`), thrusters (:mod:`.thrusters`), rudders
(:mod:`.rudder`) and wind (eq. 3) are summed and multiplied by M^-1; see
:mod:`hybridship.physics.model` for the equations and :class:`~.model.ModelArrays` for the
packed parameters ``P`` every kernel reads. Both :class:`~.model.DynamicModel` and the
integrator (:mod:`.integrate`) call these kernels; keeping them here, apart from the model
class, lets the integrator use them without importing the model (no import cycle).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from . import hull
from .compiled_cache import KERNEL_FASTMATH
from .rudder import rudder_forces_scalar
from .thrusters import thrust_directions, thruster_forces_scalar


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def wind_force_scalar(u, v, c, s, wn, we, wind_p, table):
    """Wind load (eq. 3) on one vessel, returned as ``(X_N, Y_N, N_Nm)``.

    Relative wind per Fossen (2021, sec. 10.1): ``(u_rw, v_rw) = (u, v) - wind velocity in
    body axes``, ``gamma_rw = -atan2(v_rw, u_rw)`` (0 head wind, > 0 from port).
    ``c, s`` are cos and sin of the heading, ``wn, we`` the true wind velocity (the way it
    blows, NED) [m/s] from :func:`prepare_inputs`.
    """
    urw = u - (c * wn + s * we)
    vrw = v - (-s * wn + c * we)
    vr2 = urw * urw + vrw * vrw
    if vr2 == 0.0:
        return 0.0, 0.0, 0.0
    gamma = -math.atan2(vrw, urw)
    n = table.shape[0]
    pos = (gamma + math.pi) / (2.0 * math.pi) * (n - 1)
    i0 = int(math.floor(pos))
    if i0 < 0:
        i0 = 0
    if i0 > n - 2:
        i0 = n - 2
    f = pos - i0
    q = 0.5 * wind_p[0] * vr2
    return (q * wind_p[1] * ((1.0 - f) * table[i0, 0] + f * table[i0 + 1, 0]),
            q * wind_p[2] * ((1.0 - f) * table[i0, 1] + f * table[i0 + 1, 1]),
            q * wind_p[2] * wind_p[3] * ((1.0 - f) * table[i0, 2] + f * table[i0 + 1, 2]))


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def vessel_rhs(c, s, u, v, r, rpm, prep, tau_ext, acc_ext, P, thrusts, b):
    """nu_dot of one vessel (eq. 1 solved for nu_dot).

    ``c, s`` are cos and sin of the heading psi (computed once by the caller); ``prep`` the
    prepared held inputs of :func:`prepare_inputs`; thrusts [N] go to ``thrusts[b]``.

    Returns a 12-tuple: nu_dot (3), then the hull, thruster and wind loads (3 each).
    """
    K = P.thr.shape[0]
    vcn = prep[2 * K + 2]
    vce = prep[2 * K + 3]
    uc = c * vcn + s * vce
    vc = -s * vcn + c * vce
    ur = u - uc
    vr = v - vc
    h0, h1, h2 = hull.hull_forces_scalar(u, v, r, ur, vr, P.rb[0], P.rb[1], P.m_a, P.d_lin, P.d_quad,
                                         P.d_lift, P.strip_x, P.strip_w)
    t0, t1, t2 = thruster_forces_scalar(ur, vr, r, rpm, prep, P.thr, P.thr_coef, P.rb[2], thrusts, b)
    if P.rud.shape[0] > 0:
        q0, q1, q2 = rudder_forces_scalar(ur, vr, r, prep, 2 * K + 4, P.rud, P.thr, P.rb[2], thrusts, b)
        t0 += q0
        t1 += q1
        t2 += q2
    w0, w1, w2 = wind_force_scalar(u, v, c, s, prep[2 * K], prep[2 * K + 1], P.wind_p, P.wind_table)
    # M_A d(nu_c)/dt: the current seen from the rotating body frame changes direction.
    ncd0 = r * vc
    ncd1 = -r * uc
    m_a = P.m_a
    rhs0 = h0 + t0 + w0 + tau_ext[0] + m_a[0, 0] * ncd0 + m_a[0, 1] * ncd1
    rhs1 = h1 + t1 + w1 + tau_ext[1] + m_a[1, 0] * ncd0 + m_a[1, 1] * ncd1
    rhs2 = h2 + t2 + w2 + tau_ext[2] + m_a[2, 0] * ncd0 + m_a[2, 1] * ncd1
    mi = P.m_inv
    return (mi[0, 0] * rhs0 + mi[0, 1] * rhs1 + mi[0, 2] * rhs2 + acc_ext[0],
            mi[1, 0] * rhs0 + mi[1, 1] * rhs1 + mi[1, 2] * rhs2 + acc_ext[1],
            mi[2, 0] * rhs0 + mi[2, 1] * rhs1 + mi[2, 2] * rhs2 + acc_ext[2],
            h0, h1, h2, t0, t1, t2, w0, w1, w2)


@numba.njit(cache=True)
def prepare_inputs(azimuth, wind_speed, wind_dir_from, cur_speed, cur_dir_to, P, prep):
    """Trigonometry of inputs held over a step, into ``prep[2K + 4 + 2R]``.

    Layout: cos(alpha) (K), sin(alpha) (K), wind velocity north, east (the way it blows)
    [m/s], current velocity north, east [m/s], cos(delta) (R), sin(delta) (R). ``azimuth``
    has one entry per command channel: K thrusters, then R rudders.
    """
    K = P.thr.shape[0]
    R = P.rud.shape[0]
    thrust_directions(azimuth, P.thr, prep)
    prep[2 * K] = -wind_speed * math.cos(wind_dir_from)  # "from" -> velocity points the other way
    prep[2 * K + 1] = -wind_speed * math.sin(wind_dir_from)
    prep[2 * K + 2] = cur_speed * math.cos(cur_dir_to)
    prep[2 * K + 3] = cur_speed * math.sin(cur_dir_to)
    for j in range(R):
        prep[2 * K + 4 + j] = math.cos(azimuth[K + j])
        prep[2 * K + 4 + R + j] = math.sin(azimuth[K + j])


@numba.njit(cache=True)
def dynamics_batch(eta, nu, rpm, azimuth, wind, current, tau_ext, acc_ext, P, nu_dot, parts, thrusts):
    """Batched :func:`vessel_rhs`: all arrays have a leading batch axis B."""
    prep = np.empty(2 * P.thr.shape[0] + 4 + 2 * P.rud.shape[0])
    for b in range(eta.shape[0]):
        prepare_inputs(azimuth[b], wind[b, 0], wind[b, 1], current[b, 0], current[b, 1], P, prep)
        out = vessel_rhs(math.cos(eta[b, 2]), math.sin(eta[b, 2]), nu[b, 0], nu[b, 1], nu[b, 2], rpm[b], prep,
                         tau_ext[b], acc_ext[b], P, thrusts, b)
        for i in range(3):
            nu_dot[b, i] = out[i]
            parts[b, 0, i] = out[3 + i]
            parts[b, 1, i] = out[6 + i]
            parts[b, 2, i] = out[9 + i]
            parts[b, 3, i] = tau_ext[b, i]
