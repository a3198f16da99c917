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

from ..config import real_array
from .compiled_cache import KERNEL_FASTMATH
from .propeller import thrust_scalar

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
    # text refused naming the argument (numpy read "1.57" as the number)
    a, x, y = real_array("alpha_rad", alpha_rad), real_array("x_m", x_m), real_array("y_m", y_m)
    try:
        np.broadcast_shapes(a.shape, x.shape, y.shape)
    except ValueError:
        raise ValueError(f"alpha_rad, x_m, y_m: expected one entry per thruster, got shapes {a.shape}, {x.shape} "
                         f"and {y.shape}") from None
    c, s = np.cos(a), np.sin(a)
    return np.stack([c, s, x * s - y * c], axis=-2)


@numba.njit(cache=True)
def thrust_directions(azimuth_rad, thr, prep):
    """cos and sin of each thruster's thrust direction into ``prep[i]``, ``prep[K + i]``.

    ``azimuth_rad`` is used for azimuth thrusters; the others use their fixed angle.
    Computed once per time step because the commands are held within a step.
    """
    for i in range(thr.shape[0]):
        a = azimuth_rad[i] if thr[i, THR_IS_AZIMUTH] > 0.5 else thr[i, THR_ALPHA_FIXED]
        prep[i] = math.cos(a)
        prep[thr.shape[0] + i] = math.sin(a)


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def thruster_forces_scalar(ur, vr, r, rpm, prep, thr, coef, rho, thrusts, b):
    """Generalised force ``(X_N, Y_N, N_Nm)`` of all thrusters of one vessel.

    Parameters
    ----------
    ur, vr, r : float
        Velocity relative to the water [m/s, m/s, rad/s].
    rpm : ndarray, shape (K,)
        Shaft speed commands [rpm].
    prep : ndarray
        Prepared inputs; ``prep[i]``, ``prep[K + i]`` are cos and sin of thruster i's
        thrust direction (see :func:`thrust_directions`).
    thr : ndarray, shape (K, 8)
        Packed parameters (see ``THR_*`` columns).
    coef : ndarray, shape (K, 4, N)
        Four-quadrant Fourier coefficients per thruster.
    rho : float
        Water density [kg/m^3].
    thrusts : ndarray, shape (B, K)
        Delivered thrust of each thruster [N] is written to row ``b``.
    """
    K = thr.shape[0]
    fx = 0.0
    fy = 0.0
    fn = 0.0
    for i in range(K):
        x = thr[i, THR_X]
        y = thr[i, THR_Y]
        ca = prep[i]
        sa = prep[K + i]
        va = (1.0 - thr[i, THR_WAKE]) * ((ur - y * r) * ca + (vr + x * r) * sa)
        f = (1.0 - thr[i, THR_TDED]) * thrust_scalar(rpm[i] / 60.0, va, thr[i, THR_D], rho, coef, i)
        thrusts[b, i] = f
        fx += ca * f
        fy += sa * f
        fn += (x * sa - y * ca) * f
    return fx, fy, fn
