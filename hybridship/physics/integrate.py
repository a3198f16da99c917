"""Fixed-step RK4 integration of eta_dot = R(psi) nu, nu_dot = f(...), batched over vessels.

The state of one vessel is ``x = [north_m, east_m, psi_rad, u_m_s, v_m_s, r_rad_s]`` with
the heading left unwrapped. Inputs (commands, wind, current, external loads and
accelerations) are held constant within an output step of length ``dt_s``; each output
step is split into ``substeps`` RK4 steps. Inputs are given per output step as arrays
with a time axis of length ``n_steps`` (or 1, meaning held at the start value).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .compiled_cache import KERNEL_FASTMATH
from .rhs import prepare_inputs, vessel_rhs


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def _deriv(x, rpm, prep, tau, acc, P, k, thrusts):
    c = math.cos(x[2])
    s = math.sin(x[2])
    out = vessel_rhs(c, s, x[3], x[4], x[5], rpm, prep, tau, acc, P, thrusts, 0)
    k[3] = out[0]
    k[4] = out[1]
    k[5] = out[2]
    k[0] = c * x[3] - s * x[4]
    k[1] = s * x[3] + c * x[4]
    k[2] = x[5]


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def rk4_step_scalar(x, h, rpm, prep, tau, acc, P, k1, k2, k3, k4, xt, thrusts):
    """One classical RK4 step of length ``h`` [s] for one vessel, updating ``x[6]`` in place.

    ``prep`` holds the prepared held inputs (:func:`hybridship.physics.rhs.prepare_inputs`).
    """
    _deriv(x, rpm, prep, tau, acc, P, k1, thrusts)
    for i in range(6):
        xt[i] = x[i] + 0.5 * h * k1[i]
    _deriv(xt, rpm, prep, tau, acc, P, k2, thrusts)
    for i in range(6):
        xt[i] = x[i] + 0.5 * h * k2[i]
    _deriv(xt, rpm, prep, tau, acc, P, k3, thrusts)
    for i in range(6):
        xt[i] = x[i] + h * k3[i]
    _deriv(xt, rpm, prep, tau, acc, P, k4, thrusts)
    for i in range(6):
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def rollout_batch(eta0, nu0, rpm, az, wind, current, tau_ext, acc_ext, P, dt, n_steps, substeps,
                  eta_out, nu_out, nu_dot_out):
    """Integrate B vessels for ``n_steps`` output steps of ``dt`` seconds.

    Inputs have shape ``(B, S, ...)`` with ``S`` either ``n_steps`` or 1 (held). Outputs
    ``(B, n_steps + 1, 3)``: index 0 is the initial state; ``nu_dot_out[:, j]`` is the
    acceleration at sample j with the inputs of step j (the last one with step n-1's).
    """
    B = eta0.shape[0]
    K = rpm.shape[2]
    h = dt / substeps
    x = np.empty(6)
    k1 = np.empty(6)
    k2 = np.empty(6)
    k3 = np.empty(6)
    k4 = np.empty(6)
    xt = np.empty(6)
    thrusts = np.empty((1, max(K, 1)))
    prep = np.empty(2 * P.thr.shape[0] + 4 + 2 * P.rud.shape[0])
    for b in range(B):
        for i in range(3):
            x[i] = eta0[b, i]
            x[3 + i] = nu0[b, i]
        for j in range(n_steps + 1):
            js = min(j, n_steps - 1)
            ir = js if rpm.shape[1] > 1 else 0
            ia = js if az.shape[1] > 1 else 0
            iw = js if wind.shape[1] > 1 else 0
            ic = js if current.shape[1] > 1 else 0
            it = js if tau_ext.shape[1] > 1 else 0
            ix = js if acc_ext.shape[1] > 1 else 0
            for i in range(3):
                eta_out[b, j, i] = x[i]
                nu_out[b, j, i] = x[3 + i]
            prepare_inputs(az[b, ia], wind[b, iw, 0], wind[b, iw, 1], current[b, ic, 0], current[b, ic, 1], P, prep)
            _deriv(x, rpm[b, ir], prep, tau_ext[b, it], acc_ext[b, ix], P, k1, thrusts)
            for i in range(3):
                nu_dot_out[b, j, i] = k1[3 + i]
            if j == n_steps:
                break
            for _s in range(substeps):
                rk4_step_scalar(x, h, rpm[b, ir], prep, tau_ext[b, it], acc_ext[b, ix],
                                P, k1, k2, k3, k4, xt, thrusts)


@numba.njit(cache=True)
def step_batch(eta, nu, rpm, az, wind, current, tau_ext, acc_ext, P, dt, substeps, eta_next, nu_next):
    """Advance B vessels by one output step of ``dt`` seconds (inputs ``(B, ...)``, held)."""
    K = rpm.shape[1]
    h = dt / substeps
    x = np.empty(6)
    k1 = np.empty(6)
    k2 = np.empty(6)
    k3 = np.empty(6)
    k4 = np.empty(6)
    xt = np.empty(6)
    thrusts = np.empty((1, max(K, 1)))
    prep = np.empty(2 * P.thr.shape[0] + 4 + 2 * P.rud.shape[0])
    for b in range(eta.shape[0]):
        for i in range(3):
            x[i] = eta[b, i]
            x[3 + i] = nu[b, i]
        prepare_inputs(az[b], wind[b, 0], wind[b, 1], current[b, 0], current[b, 1], P, prep)
        for _s in range(substeps):
            rk4_step_scalar(x, h, rpm[b], prep, tau_ext[b], acc_ext[b], P, k1, k2, k3, k4, xt, thrusts)
        for i in range(3):
            eta_next[b, i] = x[i]
            nu_next[b, i] = x[3 + i]
