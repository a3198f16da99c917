"""Batched blackout rollouts: every sample and heading integrated in one compiled call.

One *sample* is one vessel, drifting from rest at ``eta = [0, 0, psi0]`` after a blackout
at t = 0. The right-hand side is the dynamic model's own kernel
(:func:`hybridship.physics.model.vessel_rhs`, eq. 1-3) evaluated with per-sample packed
parameters (a perturbed vessel, :mod:`hybridship.driftoff.spread`), plus the loads of the
sea-trial simulator (:mod:`hybridship.sim.environment`):

* **wind**: mean speed plus Harris-spectrum gusts (a sum of ``n_gust`` harmonics, as
  :func:`~hybridship.sim.environment.gust_wind`), direction held per sample;
* **current**: speed and direction per sample, constant over the drift (the simulator's
  Gauss-Markov current has a 600 s time constant, longer than a drift-off);
* **wave drift**: Newman's geometric slowly varying drift of long-crested JONSWAP
  components at the ship's heading and position (the same formulas as
  :func:`~hybridship.sim.environment.drift_coefficients` and
  :func:`~hybridship.sim.environment.wave_drift_loads`, evaluated inside the loop because
  they depend on the state; a test checks the two agree);
* an optional extra acceleration in NED (``accel_ned``: the live mode's residual bias);
* **the thrusters spinning down**: ``rpm(t) = rpm0 exp(-t / tau_rpm)`` through the
  model's four-quadrant propellers (azimuths frozen), and, in "balanced" mode, a holding
  load equal and opposite to the environment at rest at t = 0 (what an integral-action DP
  converges to) that decays like the thrust, ``(rpm / rpm0)^2 = exp(-2 t / tau_rpm)``.

Inputs are held over an output step ``dt_s`` (wind, wave drift, as
``DynamicModel.rollout`` does); the spin-down and the holding load are evaluated at every
RK4 stage. First passage of each radius is interpolated linearly within the step.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..physics.compiled_cache import KERNEL_FASTMATH
from ..physics.model import ModelArrays, prepare_inputs, vessel_rhs

__all__ = ["run_kernel", "HULL_FIELDS"]

#: Layout of the ``hull`` array the kernel reads: drift-model hull and water constants.
HULL_FIELDS = ("L_m", "B_m", "T_m", "bow_factor", "side_factor", "yaw_lever_factor", "rho_kg_m3", "g_m_s2")


#: Columns of the per-component table of :func:`_wave_prep`.
_WP_W, _WP_KX, _WP_KE, _WP_CCHI, _WP_SCHI, _WP_PH, _WP_AX, _WP_AY, _WP_AN, _WP_MX, _WP_MY, _WP_MN = range(12)
_WP_NCOL = 12

# The physics kernels' flags (no "contract", no "reassoc": the same bits whether this process
# compiled the kernel or read it from numba's cache, on a cluster's workers too) without
# "nnan"/"ninf": the kernel tests for unreached radii and diverged states.
_KERNEL_MATH = KERNEL_FASTMATH - {"nnan", "ninf"}


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _wave_prep(w, a, ph, chi, hull, pre):
    """Per-component constants of the drift loads of one ship into ``pre`` (n, ``_WP_NCOL``).

    With ``F_x = -(rho g / 2) c_x B p(k) f(k, L)`` and ``F_y = -(rho g / 2) c_y L p(k) f(k, B)``
    (:func:`hybridship.sim.environment.drift_coefficients`), ``D_x = F_x cos b |cos b|``,
    ``D_y = F_y sin b |sin b|`` and ``D_n = c_n L cos b D_y``; so ``A sqrt|D|`` factors into a
    constant (stored here) times ``|cos b|``, ``|sin b|`` and ``sqrt|cos b| |sin b|``.
    """
    L, B, T = hull[0], hull[1], hull[2]
    cx, cy, cn = hull[3], hull[4], hull[5]
    half_rho_g = 0.5 * hull[6] * hull[7]
    g = hull[7]
    for j in range(w.shape[0]):
        k = w[j] * w[j] / g
        p = -math.expm1(-2.0 * k * T)
        kl = (k * L) ** 2
        kb = (k * B) ** 2
        fx = -half_rho_g * cx * B * p * kl / (1.0 + kl)
        fy = -half_rho_g * cy * L * p * kb / (1.0 + kb)
        a2 = a[j] * a[j]
        pre[j, _WP_W] = w[j]
        pre[j, _WP_KX] = k * math.cos(chi[j])
        pre[j, _WP_KE] = k * math.sin(chi[j])
        pre[j, _WP_CCHI] = math.cos(chi[j])
        pre[j, _WP_SCHI] = math.sin(chi[j])
        pre[j, _WP_PH] = ph[j]
        pre[j, _WP_MX] = a2 * fx                    # signed: mean load = M * (trig factor)
        pre[j, _WP_MY] = a2 * fy
        pre[j, _WP_MN] = a2 * cn * L * fy
        pre[j, _WP_AX] = math.sqrt(abs(a2 * fx))
        pre[j, _WP_AY] = math.sqrt(abs(a2 * fy))
        pre[j, _WP_AN] = math.sqrt(abs(a2 * cn * L * fy))


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _wave_eval(t, n, e, psi, pre, mean_only, out, work):
    """Newman geometric slowly varying drift (or its mean) at time ``t``, position ``(n, e)``
    and heading ``psi``, body frame, into ``out[3]`` (``work``: a (4, 3) buffer)."""
    work[:, :] = 0.0
    cpsi = math.cos(psi)
    spsi = math.sin(psi)
    for c in range(3):
        out[c] = 0.0
    for j in range(pre.shape[0]):
        cb = pre[j, _WP_CCHI] * cpsi + pre[j, _WP_SCHI] * spsi      # cos(chi - psi)
        sb = pre[j, _WP_SCHI] * cpsi - pre[j, _WP_CCHI] * spsi      # sin(chi - psi)
        if mean_only:
            out[0] += pre[j, _WP_MX] * cb * abs(cb)
            out[1] += pre[j, _WP_MY] * sb * abs(sb)
            out[2] += pre[j, _WP_MN] * cb * sb * abs(sb)
            continue
        theta = pre[j, _WP_W] * t + pre[j, _WP_KX] * n + pre[j, _WP_KE] * e + pre[j, _WP_PH]
        ct = math.cos(theta)
        st = math.sin(theta)
        amp0 = pre[j, _WP_AX] * abs(cb)
        amp1 = pre[j, _WP_AY] * abs(sb)
        amp2 = pre[j, _WP_AN] * math.sqrt(abs(cb)) * abs(sb)
        # the sign of each drift coefficient picks the group (|Z+|^2 - |Z-|^2)
        g0 = 0 if pre[j, _WP_MX] * cb > 0.0 else 2
        g1 = 0 if pre[j, _WP_MY] * sb > 0.0 else 2
        g2 = 0 if pre[j, _WP_MN] * cb * sb > 0.0 else 2
        work[g0, 0] += amp0 * ct
        work[g0 + 1, 0] += amp0 * st
        work[g1, 1] += amp1 * ct
        work[g1 + 1, 1] += amp1 * st
        work[g2, 2] += amp2 * ct
        work[g2 + 1, 2] += amp2 * st
    if not mean_only:
        for c in range(3):
            out[c] = work[0, c] ** 2 + work[1, c] ** 2 - work[2, c] ** 2 - work[3, c] ** 2


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _wave_drift(t, n, e, psi, w, a, ph, chi, hull, mean_only, out):
    """Newman geometric slowly varying drift (or its mean) of one ship, body frame, into ``out[3]``.

    Same loads as :func:`hybridship.sim.environment.wave_drift_loads` (``newman="geometric"``)
    and :func:`~hybridship.sim.environment.mean_drift_loads` for components ``w, a, ph, chi``
    (frequency, amplitude, phase, direction from).
    """
    pre = np.empty((w.shape[0], _WP_NCOL))
    _wave_prep(w, a, ph, chi, hull, pre)
    _wave_eval(t, n, e, psi, pre, mean_only, out, np.zeros((4, 3)))


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _deriv(x, t, rpm0, rpm_now, inv_tau, prep, tau_wave, hold, acc_ned, Q, thrusts, k, tau, acc):
    """State derivative of one ship at time ``t`` (spin-down evaluated at ``t``); ``tau``, ``acc`` are (3,) buffers."""
    c = math.cos(x[2])
    s = math.sin(x[2])
    decay = math.exp(-t * inv_tau)
    for i in range(rpm0.shape[0]):
        rpm_now[i] = rpm0[i] * decay
    d2 = decay * decay
    for i in range(3):
        tau[i] = tau_wave[i] + hold[i] * d2
    acc[0] = c * acc_ned[0] + s * acc_ned[1]
    acc[1] = -s * acc_ned[0] + c * acc_ned[1]
    acc[2] = acc_ned[2]
    out = vessel_rhs(c, s, x[3], x[4], x[5], rpm_now, prep, tau, acc, Q, thrusts, 0)
    k[0] = c * x[3] - s * x[4]
    k[1] = s * x[3] + c * x[4]
    k[2] = x[5]
    k[3] = out[0]
    k[4] = out[1]
    k[5] = out[2]


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _gust_speed(wind_mean, gust_f, gust_a, gust_ph, t):
    """Mean wind plus the gust harmonics of one sample at time ``t`` [m/s], at least 0."""
    ws = wind_mean
    for h in range(gust_f.shape[0]):
        ws += gust_a[h] * math.cos(2.0 * math.pi * gust_f[h] * t + gust_ph[h])
    if ws < 0.0:
        ws = 0.0
    return ws


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _holding_load(x, m_inv, az, wind_mean, wind_dir, cur, acc_ned, Q, pre, prep, tau_wave, work, rpm_now,
                  zeros_rpm, inv_tau, hold, thrusts, k1, tau_b, acc_b):
    """``hold = -(environment at rest with the mean wind and mean wave drift) = -M nu_dot0`` of one sample."""
    prepare_inputs(az, wind_mean, wind_dir, cur[0], cur[1], Q, prep)
    _wave_eval(0.0, 0.0, 0.0, x[2], pre, True, tau_wave, work)
    _deriv(x, 1e9, zeros_rpm, rpm_now, inv_tau, prep, tau_wave, hold, acc_ned, Q, thrusts, k1, tau_b, acc_b)
    Mb = np.linalg.inv(m_inv)
    for i in range(3):
        hold[i] = -(Mb[i, 0] * k1[3] + Mb[i, 1] * k1[4] + Mb[i, 2] * k1[5])


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _rk4_step(x, t0, dt, rpm0, rpm_now, inv_tau, prep, tau_wave, hold, acc_ned, Q, thrusts,
              xt, k1, k2, k3, k4, tau_b, acc_b):
    """One RK4 step of ``x`` in place, the spin-down evaluated at the stage times."""
    _deriv(x, t0, rpm0, rpm_now, inv_tau, prep, tau_wave, hold, acc_ned, Q, thrusts, k1, tau_b, acc_b)
    for i in range(6):
        xt[i] = x[i] + 0.5 * dt * k1[i]
    _deriv(xt, t0 + 0.5 * dt, rpm0, rpm_now, inv_tau, prep, tau_wave, hold, acc_ned, Q, thrusts, k2, tau_b, acc_b)
    for i in range(6):
        xt[i] = x[i] + 0.5 * dt * k2[i]
    _deriv(xt, t0 + 0.5 * dt, rpm0, rpm_now, inv_tau, prep, tau_wave, hold, acc_ned, Q, thrusts, k3, tau_b, acc_b)
    for i in range(6):
        xt[i] = x[i] + dt * k3[i]
    _deriv(xt, t0 + dt, rpm0, rpm_now, inv_tau, prep, tau_wave, hold, acc_ned, Q, thrusts, k4, tau_b, acc_b)
    for i in range(6):
        x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _record_passages(r, r_prev, m_prev, t0, dt, radii, t_react, reached, done_q, t_reach, r_react):
    """First passage of each radius (interpolated in the step) and the largest excursion up to each
    reaction time, for one sample's step from ``t0`` to ``t0 + dt``; returns whether every radius is reached."""
    t1 = t0 + dt
    all_reached = True
    for i in range(radii.shape[0]):
        if not reached[i]:
            if r >= radii[i]:
                reached[i] = True
                t_reach[i] = t0 + dt * (radii[i] - r_prev) / (r - r_prev) if r > r_prev else t1
            else:
                all_reached = False
    for q in range(t_react.shape[0]):
        if not done_q[q] and t1 >= t_react[q]:
            done_q[q] = True
            f = (t_react[q] - t0) / dt
            # max excursion up to t_react: the farthest before the step, or the track interpolated
            # in it (as the passage times are), whichever is farther
            r_react[q] = max(m_prev, r_prev + f * (r - r_prev))
    return all_reached


@numba.njit(cache=True, fastmath=_KERNEL_MATH)
def _kernel(psi0, P, m_inv, m_a, d_lin, d_quad, d_lift, strip_w, thr, wind_p,
            az, rpm0, tau_rpm_s, balance, wind_mean, wind_dir, gust_f, gust_a, gust_ph,
            cur, acc_ned, nu0, wave_w, wave_a, wave_ph, wave_dir, hull, dt, n_steps, radii, t_react,
            max_speed, t_reach, r_react, track, hold_out):
    B = psi0.shape[0]
    n_r = radii.shape[0]
    n_q = t_react.shape[0]
    keep = track.shape[0] == B
    t_need = 0.0
    for q in range(n_q):
        t_need = max(t_need, t_react[q])
    inv_tau = 1.0 / tau_rpm_s
    n_ch = az.shape[1]
    prep = np.empty(2 * P.thr.shape[0] + 4 + 2 * P.rud.shape[0])
    thrusts = np.empty((1, max(P.thr.shape[0], 1)))
    rpm_now = np.empty(n_ch)
    x = np.empty(6)
    xt = np.empty(6)
    k1 = np.empty(6)
    k2 = np.empty(6)
    k3 = np.empty(6)
    k4 = np.empty(6)
    tau_wave = np.empty(3)
    hold = np.zeros(3)
    zeros_rpm = np.zeros(n_ch)
    tau_b = np.empty(3)
    acc_b = np.empty(3)
    work = np.zeros((4, 3))
    pre = np.empty((wave_w.shape[1], _WP_NCOL))
    for b in range(B):
        Q = ModelArrays(m_inv[b], m_a[b], P.rb, d_lin[b], d_quad[b], d_lift[b], P.strip_x, strip_w[b],
                        thr[b], P.thr_coef, wind_p[b], P.wind_table, P.rud)
        _wave_prep(wave_w[b], wave_a[b], wave_ph[b], wave_dir[b], hull, pre)
        for i in range(3):
            x[i] = 0.0
        x[2] = psi0[b]
        for i in range(3):
            x[3 + i] = nu0[b, i]
        for i in range(3):
            hold[i] = 0.0
        if balance:
            _holding_load(x, m_inv[b], az[b], wind_mean[b], wind_dir[b], cur[b], acc_ned[b], Q, pre, prep,
                          tau_wave, work, rpm_now, zeros_rpm, inv_tau, hold, thrusts, k1, tau_b, acc_b)
        for i in range(3):
            hold_out[b, i] = hold[i]
        reached = np.zeros(n_r, dtype=np.bool_)
        done_q = np.zeros(n_q, dtype=np.bool_)
        for i in range(n_r):
            t_reach[b, i] = np.inf
        for q in range(n_q):
            r_react[b, q] = 0.0
        r_prev = 0.0
        m_prev = 0.0
        if keep:
            for i in range(3):
                track[b, 0, i] = x[i]
        for j in range(n_steps):
            t0 = j * dt
            ws = _gust_speed(wind_mean[b], gust_f[b], gust_a[b], gust_ph[b], t0)
            prepare_inputs(az[b], ws, wind_dir[b], cur[b, 0], cur[b, 1], Q, prep)
            _wave_eval(t0, x[0], x[1], x[2], pre, False, tau_wave, work)
            _rk4_step(x, t0, dt, rpm0[b], rpm_now, inv_tau, prep, tau_wave, hold, acc_ned[b], Q, thrusts,
                      xt, k1, k2, k3, k4, tau_b, acc_b)
            t1 = t0 + dt
            r = math.sqrt(x[0] * x[0] + x[1] * x[1])
            m = max(m_prev, r)
            if keep:
                for i in range(3):
                    track[b, j + 1, i] = x[i]
            all_reached = _record_passages(r, r_prev, m_prev, t0, dt, radii, t_react, reached, done_q,
                                           t_reach[b], r_react[b])
            r_prev = r
            m_prev = m
            if not (r <= max_speed * t1 + 1.0):
                # diverged (or NaN): farther than any drift could carry the ship; no result,
                # whether or not the radii were "reached" on the way
                for i in range(n_r):
                    t_reach[b, i] = np.nan
                for q in range(n_q):
                    r_react[b, q] = np.nan
                    done_q[q] = True
                break
            if all_reached and t1 >= t_need and not keep:
                break
        for q in range(n_q):
            if not done_q[q]:
                r_react[b, q] = m_prev   # reaction time beyond the horizon


#: Drift speed [m/s] (about 58 kn) beyond which a drift is not a drift but a diverged
#: integration (no ship drifts off station this fast): a sample whose excursion outruns it
#: (or turns NaN) while it is integrated gives no result. A sample stops once it has passed
#: every radius and reaction time (unless the tracks are kept), so a blow-up after that is
#: not seen: checking every sample to the horizon would cost several times the run.
MAX_DRIFT_SPEED_M_S = 30.0


def run_kernel(psi0, P, stack, az, rpm0, tau_rpm_s, balance, wind_mean, wind_dir, gust_f, gust_a, gust_ph,
               cur, acc_ned, waves, hull, dt_s, n_steps, radii_m, t_react_s, keep_tracks=False, nu0=None,
               holding_load=None):
    """Call the compiled kernel on contiguous float arrays (``nu0`` (B, 3): start velocities, default rest).

    Returns ``(t_reach_s (B, R), excursion_m (B, Q), track (B, n_steps + 1, 3) or None)``; a
    sample that diverged while it was integrated (:data:`MAX_DRIFT_SPEED_M_S`; up to its
    early stop, or to the horizon with ``keep_tracks``) has NaN in both.
    ``holding_load`` (B, 3), when given, receives each sample's holding load at t = 0 in the
    "balanced" mode ``[X_N, Y_N, N_Nm]`` (body frame; what the thrusters held before the
    blackout), zeros otherwise.
    """
    B = int(np.shape(psi0)[0])
    f = lambda a: np.ascontiguousarray(a, dtype=float)  # noqa: E731
    t_reach = np.empty((B, len(radii_m)))
    r_react = np.empty((B, len(t_react_s)))
    track = np.full((B, n_steps + 1, 3), np.nan) if keep_tracks else np.empty((0, 1, 3))
    _kernel(f(psi0), P, f(stack.m_inv), f(stack.m_a), f(stack.d_lin), f(stack.d_quad), f(stack.d_lift),
            f(stack.strip_w), f(stack.thr), f(stack.wind_p), f(az), f(rpm0), float(tau_rpm_s), bool(balance),
            f(wind_mean), f(wind_dir), f(gust_f), f(gust_a), f(gust_ph), f(cur), f(acc_ned),
            f(np.zeros((B, 3)) if nu0 is None else np.broadcast_to(nu0, (B, 3))), f(waves[0]), f(waves[1]), f(waves[2]), f(waves[3]), f(hull), float(dt_s), int(n_steps),
            f(radii_m), f(t_react_s), float(MAX_DRIFT_SPEED_M_S), t_reach, r_react, track,
            np.empty((B, 3)) if holding_load is None else holding_load)
    return t_reach, r_react, (track if keep_tracks else None)
