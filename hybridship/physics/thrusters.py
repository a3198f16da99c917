"""Thrust configuration (Skulstad et al. eq. 2) and thruster forces with four-quadrant propellers.

Every thruster ``i`` sits at ``(x_i, y_i)`` in the body frame (metres from the body
origin, x forward, y starboard) and produces a thrust ``T_i`` along the unit vector
``[cos alpha_i, sin alpha_i]``:

* ``azimuth``: ``alpha`` is commanded, 0 = thrust forward (+x), +90 deg = to starboard;
* ``tunnel``: fixed ``alpha = 90 deg``, so positive rpm pushes the bow to starboard and its
  configuration column is ``[0, 1, l_x]``;
* ``fixed``: a main propeller or any thruster with a fixed axis given in the vessel file.

The configuration column is ``t(alpha) = [cos a, sin a, x sin a - y cos a]`` (the yaw
moment of the force about the origin), so ``tau = T(alpha) f`` with ``f`` the thrusts.

The propeller inflow is the velocity of the thruster's position through the water,
projected on its axis and reduced by the wake fraction ``w``:
``V_a = (1 - w) [(u_r - y r) cos a + (v_r + x r) sin a]``; the delivered force is
``(1 - t) T(n, V_a)`` with the thrust-deduction factor ``t``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .propeller import thrust_torque_scalar

#: Column layout of the packed thruster parameter array ``thr (K, 8)``.
THR_X, THR_Y, THR_D, THR_WAKE, THR_TDED, THR_ALPHA_FIXED, THR_IS_AZIMUTH, THR_MAX_RPM = range(8)


def configuration_matrix(alpha_rad, x_m, y_m):
    """Thrust configuration matrix T(alpha), batched.

    Parameters
    ----------
    alpha_rad : array_like, shape (..., K)
        Thrust direction of each thruster [rad] (0 forward, +pi/2 starboard).
    x_m, y_m : array_like, shape (K,)
        Thruster positions in the body frame [m].

    Returns
    -------
    ndarray, shape (..., 3, K)
        Columns ``[cos a, sin a, x sin a - y cos a]``; ``tau = T @ f`` with thrusts ``f`` [N].
    """
    a = np.asarray(alpha_rad, dtype=float)
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    c, s = np.cos(a), np.sin(a)
    return np.stack([c, s, x * s - y * c], axis=-2)


@numba.njit(cache=True)
def thruster_forces_scalar(ur, vr, r, rpm, azimuth_rad, thr, coef, rho, out, thrusts):
    """Generalised force of all thrusters of one vessel into ``out[3]``; thrusts into ``thrusts[K]``.

    Parameters
    ----------
    ur, vr, r : float
        Velocity relative to the water [m/s, m/s, rad/s].
    rpm, azimuth_rad : ndarray, shape (K,)
        Commands; ``azimuth_rad`` is ignored for thrusters with a fixed axis.
    thr : ndarray, shape (K, 8)
        Packed parameters (see ``THR_*`` columns).
    coef : ndarray, shape (K, 4, N)
        Four-quadrant Fourier coefficients per thruster.
    rho : float
        Water density [kg/m^3].
    """
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 0.0
    for i in range(thr.shape[0]):
        x = thr[i, THR_X]
        y = thr[i, THR_Y]
        a = azimuth_rad[i] if thr[i, THR_IS_AZIMUTH] > 0.5 else thr[i, THR_ALPHA_FIXED]
        ca = math.cos(a)
        sa = math.sin(a)
        va = (1.0 - thr[i, THR_WAKE]) * ((ur - y * r) * ca + (vr + x * r) * sa)
        t, _q = thrust_torque_scalar(rpm[i] / 60.0, va, thr[i, THR_D], rho, coef[i])
        f = (1.0 - thr[i, THR_TDED]) * t
        thrusts[i] = f
        out[0] += ca * f
        out[1] += sa * f
        out[2] += (x * sa - y * ca) * f
