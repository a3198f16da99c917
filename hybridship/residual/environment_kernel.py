"""Compiled kernels of the environment estimator's extended Kalman filter.

The filter itself (state layout, noise model, what is identified) is described in
:mod:`hybridship.residual.environment`; this module holds its inner loop, compiled with
numba so that filtering the 30 minutes before a forecast costs milliseconds, not a
Python-level loop over samples. Everything here trusts its inputs: the estimator checks
the log once, at its boundary, before calling :func:`filter_grid`.

The process model is the dynamic model's own right-hand side and RK4 step
(:mod:`hybridship.physics.rhs`, :mod:`hybridship.physics.integrate`), so the filter and
the forecasts share one set of equations.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..physics.integrate import rk4_step_scalar
from ..physics.rhs import prepare_inputs, vessel_rhs
from ..physics.thrusters import THR_X, THR_Y

#: Indices of the state (see :func:`hybridship.residual.environment.state_names`); the
#: thrust-model error (one per degree of freedom or one per thruster) fills the rest.
_CUR = 6
_LOAD = 8
_THR = 11
_YAW_LOAD = _LOAD + 2


@numba.njit(cache=True)
def _prep_for(x, rpm, az, wind, P, prep):
    """Prepared held inputs of the model at state ``x`` (its current as speed and direction)."""
    cn, ce = x[_CUR], x[_CUR + 1]
    prepare_inputs(az, wind[0], wind[1], math.hypot(cn, ce), math.atan2(ce, cn), P, prep)


@numba.njit(cache=True)
def _thrust_basis(x, rpm, prep, P, per_thruster, zeros3, thrusts, T):
    """The thrust-error basis ``T`` (3, n_theta) at state ``x``: ``accel = T @ theta``.

    Per degree of freedom, ``T = diag(M^-1 tau_thr)`` (thrusters and rudders together); per
    thruster, column ``i`` is ``M^-1`` times thruster ``i``'s generalised force
    ``f_i [cos a_i, sin a_i, x_i sin a_i - y_i cos a_i]`` (the thrust configuration matrix
    times its delivered thrust), so an efficiency error of one thruster acts through its own
    lever arm.
    """
    c, s = math.cos(x[2]), math.sin(x[2])
    r = vessel_rhs(c, s, x[3], x[4], x[5], rpm, prep, zeros3, zeros3, P, thrusts, 0)
    mi = P.m_inv
    T[:, :] = 0.0
    if not per_thruster:
        for i in range(3):
            T[i, i] = mi[i, 0] * r[6] + mi[i, 1] * r[7] + mi[i, 2] * r[8]
        return
    K = P.thr.shape[0]
    for k in range(K):
        ca, sa, f = prep[k], prep[K + k], thrusts[0, k]
        g0, g1, g2 = ca * f, sa * f, (P.thr[k, THR_X] * sa - P.thr[k, THR_Y] * ca) * f
        for i in range(3):
            T[i, k] = mi[i, 0] * g0 + mi[i, 1] * g1 + mi[i, 2] * g2


@numba.njit(cache=True)
def _external_accel(x, T, drift_yaw_uv, load_map, out):
    """``R(psi)^T b + T theta``, plus the hull's yaw moment in a drift ``k u v`` (``drift_yaw_uv``
    = k [rad/m^2], 0 while the thrusters run): the filter's extra body-frame acceleration (3,).

    ``load_map`` (3, 3) makes the load a force: ``A [R(psi)^T b_ne; b_yaw]`` in place of
    ``[R(psi)^T b_ne; b_yaw]`` (``A = M^-1 diag(m_ref, m_ref, I_ref)``, the load a NED force and
    a yaw moment per reference mass and inertia); an empty (0, 3) map: the load is an
    acceleration (the default)."""
    c, s = math.cos(x[2]), math.sin(x[2])
    bn, be = x[_LOAD], x[_LOAD + 1]
    if load_map.shape[0] == 0:
        out[0] = c * bn + s * be
        out[1] = -s * bn + c * be
        out[2] = x[_LOAD + 2] + drift_yaw_uv * x[3] * x[4]
    else:
        fu, fv, fr = c * bn + s * be, -s * bn + c * be, x[_LOAD + 2]
        for i in range(3):
            out[i] = load_map[i, 0] * fu + load_map[i, 1] * fv + load_map[i, 2] * fr
        out[2] += drift_yaw_uv * x[3] * x[4]
    for j in range(T.shape[1]):
        for i in range(3):
            out[i] += T[i, j] * x[_THR + j]


@numba.njit(cache=True)
def _rk4(x, dt, rpm, prep, acc, P, f, work):
    """The motion part ``f[0:6]`` of one RK4 step of the dynamic model from ``x[0:6]``, with
    the prepared inputs ``prep`` and the external acceleration ``acc`` held."""
    zeros3, thrusts, s6, k1, k2, k3, k4, xt = work[1], work[2], work[5], work[6], work[7], work[8], work[9], work[10]
    for i in range(6):
        s6[i] = x[i]
    rk4_step_scalar(s6, dt, rpm, prep, zeros3, acc, P, k1, k2, k3, k4, xt, thrusts)
    for i in range(6):
        f[i] = s6[i]


@numba.njit(cache=True)
def _transition(x, dt, rpm, az, wind, P, per_thruster, drift_yaw_uv, load_map, f, work, T, acc, prep_ready=False):
    """One process-model step of the state ``x`` into ``f``: RK4 of the dynamic model with
    the current and the external acceleration of :func:`_external_accel` (left in ``T`` and
    ``acc``); the environment states are random walks (kept). With ``prep_ready``,
    ``work[0]`` already holds the prepared inputs of ``x``'s current."""
    prep = work[0]
    if not prep_ready:
        _prep_for(x, rpm, az, wind, P, prep)
    _thrust_basis(x, rpm, prep, P, per_thruster, work[1], work[2], T)
    _external_accel(x, T, drift_yaw_uv, load_map, acc)
    _rk4(x, dt, rpm, prep, acc, P, f, work)
    for i in range(6, x.size):
        f[i] = x[i]


@numba.njit(cache=True)
def _workspace(P):
    K = P.thr.shape[0]
    return (np.empty(2 * K + 4 + 2 * P.rud.shape[0]), np.zeros(3), np.empty((1, max(K, 1))), np.empty(3),
            np.empty(3), np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6))


@numba.njit(cache=True)
def predict(x, Pc, dt, rpm, az, wind, Q, fd_step, P, per_thruster, drift_yaw_uv, load_map, work):
    """EKF time update over ``dt`` [s]: the mean through the process model, the covariance
    through its Jacobian ``F``. Returns ``(x, P)`` (new arrays).

    ``F`` is taken by forward differences (steps ``fd_step``) where the state enters the
    model nonlinearly (heading, velocities, current). The rest follows from the model's
    structure, which saves most of the model steps: position does not enter the dynamics
    (unit columns); the load ``b`` and the thrust error ``theta`` enter only through the
    held external acceleration ``acc = R(psi)^T b + T theta``, so their columns are the
    step's sensitivity to ``acc`` (three differences) times ``R(psi)^T`` and ``T`` (with a
    force ``load_map`` ``A``: ``A blockdiag(R(psi)^T, 1)``, see :func:`_external_accel`).
    """
    n = x.size
    n_theta = n - _THR
    f0 = np.empty(n)
    T = np.empty((3, n_theta))
    acc = np.empty(3)
    _transition(x, dt, rpm, az, wind, P, per_thruster, drift_yaw_uv, load_map, f0, work, T, acc)
    F = np.zeros((n, n))
    for j in range(n):
        if j < 2 or j >= _LOAD:
            F[j, j] = 1.0
    fj = np.empty(n)
    acc_j = np.empty(3)
    # sensitivity G (6, 3) of the step to the held acceleration, with the nominal inputs
    # (work[0] holds those of x until the current is perturbed below)
    G = np.empty((6, 3))
    for d in range(3):
        h = fd_step[_LOAD + d]
        acc_j[:] = acc
        acc_j[d] += h
        _rk4(x, dt, rpm, work[0], acc_j, P, fj, work)
        for i in range(6):
            G[i, d] = (fj[i] - f0[i]) / h
    xp = x.copy()
    T_j = np.empty((3, n_theta))
    for j in range(2, _LOAD):                   # heading, velocities, current
        xp[j] = x[j] + fd_step[j]
        # the prepared inputs depend on the current alone: those of x serve the heading
        # and the velocities
        _transition(xp, dt, rpm, az, wind, P, per_thruster, drift_yaw_uv, load_map, fj, work, T_j, acc_j, j < _CUR)
        for i in range(n):
            F[i, j] = (fj[i] - f0[i]) / fd_step[j]
        xp[j] = x[j]
    c, s = math.cos(x[2]), math.sin(x[2])
    GA = G
    if load_map.shape[0] != 0:                  # a force: d acc / d b = A blockdiag(R(psi)^T, 1)
        GA = np.zeros((6, 3))
        for i in range(6):
            for k in range(3):
                for d in range(3):
                    GA[i, k] += G[i, d] * load_map[d, k]
    for i in range(6):
        F[i, _LOAD] = c * GA[i, 0] - s * GA[i, 1]        # d acc / d b = R(psi)^T
        F[i, _LOAD + 1] = s * GA[i, 0] + c * GA[i, 1]
        F[i, _LOAD + 2] = GA[i, 2]
        for j in range(n_theta):                         # d acc / d theta = T
            F[i, _THR + j] = G[i, 0] * T[0, j] + G[i, 1] * T[1, j] + G[i, 2] * T[2, j]
    return f0, F @ Pc @ F.T + Q


@numba.njit(cache=True)
def _wrap_pi(angle_rad):
    """An angle wrapped to [-pi, pi) [rad]: :func:`hybridship.frames.wrap_pi`, compiled."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


@numba.njit(cache=True)
def update(x, Pc, z, z_ok, r_std, gate, max_gated, gate_state):
    """EKF measurement update with the measured components ``z_ok`` (6,) of ``[eta, nu]``.

    The heading innovation is wrapped to [-pi, pi) (:func:`_wrap_pi`). A component whose innovation exceeds
    ``gate`` standard deviations of its predicted spread (``P + r^2``) and jumped there, by
    as much, from its innovation at the sample before, is an outlier (a position spike, a
    corrupted sample, a datum change) and is not used; so are the samples after it while
    their innovation stays beyond the gate, until ``max_gated`` were in a row. A lasting
    shift is then followed by restarting that component at the measurement (its variance
    ``r^2``, no covariance with the rest), not by a Kalman update, which would put the shift
    into the velocities and the environment. An innovation that grows past the gate without
    a jump is the ship's own motion outrunning the model (a drifting ship's turn): it is
    used, so the filter follows it. ``gate_state`` (2, 6), updated in place, holds per
    component the outliers in a row and the innovation at its last measured sample.
    Returns ``(x, P)`` (new arrays).
    """
    innov = z[:6] - x[:6]
    innov[2] = _wrap_pi(innov[2])
    use = z_ok.copy()
    shift = np.zeros(6, dtype=np.bool_)
    for c in range(6):
        if not use[c]:
            continue
        bound = gate[c] ** 2 * (Pc[c, c] + r_std[c] ** 2)
        step = innov[c] - gate_state[1, c]
        if c == 2:
            step = _wrap_pi(step)
        if innov[c] ** 2 > bound and (gate_state[0, c] > 0 or step ** 2 > bound):
            use[c] = False
            shift[c] = gate_state[0, c] >= max_gated
            gate_state[0, c] = 0 if shift[c] else gate_state[0, c] + 1
        else:
            gate_state[0, c] = 0
        gate_state[1, c] = 0.0 if shift[c] else innov[c]
    idx = np.flatnonzero(use)
    x_new, P_new = _kalman_update(x, Pc, innov, idx, r_std) if idx.size else (x, Pc)
    if shift.any():
        x_new, P_new = x_new.copy(), P_new.copy()
        for c in np.flatnonzero(shift):
            x_new[c] = x[c] + innov[c]          # the measurement (the heading's turn kept)
            P_new[c, :] = 0.0
            P_new[:, c] = 0.0
            P_new[c, c] = r_std[c] ** 2
    return x_new, P_new


@numba.njit(cache=True)
def _kalman_update(x, Pc, innov, idx, r_std):
    """The Kalman update with the innovations of the components ``idx``."""
    n, m = x.size, idx.size
    y = np.empty(m)
    S = np.empty((m, m))
    PHt = np.empty((n, m))
    for a in range(m):
        y[a] = innov[idx[a]]
        for b in range(m):
            S[a, b] = Pc[idx[a], idx[b]]
        S[a, a] += r_std[idx[a]] ** 2
        for i in range(n):
            PHt[i, a] = Pc[i, idx[a]]
    K = np.linalg.solve(S, PHt.T).T
    x = x + K @ y
    Pn = Pc - K @ PHt.T
    return x, 0.5 * (Pn + Pn.T)


@numba.njit(cache=True)
def process_noise(dt, q_base):
    """Process-noise covariance over ``dt`` [s]: position noise fixed, velocity noise growing
    with ``dt``, the environment's random walks with ``dt`` (variance)."""
    n = q_base.size
    Q = np.zeros((n, n))
    for i in range(n):
        if i < 3:
            Q[i, i] = q_base[i] ** 2
        elif i < 6:
            Q[i, i] = (q_base[i] * dt) ** 2
        else:
            Q[i, i] = q_base[i] ** 2 * dt
    return Q


@numba.njit(cache=True)
def current_yaw_accel(x, P, work):
    """Yaw acceleration [rad/s^2] of the hull's response to the estimated current at state
    ``x`` (no thrust, no wind): ``a_r(current) - a_r(no current)``."""
    return _current_response(x, x[_CUR], x[_CUR + 1], P, work)[2] - _current_response(x, 0.0, 0.0, P, work)[2]


@numba.njit(cache=True)
def _current_response(x, cn, ce, P, work):
    """Body-frame acceleration (3) [m/s^2, m/s^2, rad/s^2] of the hull at state ``x`` in the
    current ``(cn, ce)`` [m/s, NED], with no thrust and no wind."""
    prep, zeros3, thrusts = work[0], work[1], work[2]
    W = P.thr.shape[0] + P.rud.shape[0]
    rpm = np.zeros(W)
    az = np.zeros(W)
    prepare_inputs(az, 0.0, 0.0, math.hypot(cn, ce), math.atan2(ce, cn), P, prep)
    out = vessel_rhs(math.cos(x[2]), math.sin(x[2]), x[3], x[4], x[5], rpm, prep, zeros3, zeros3, P, thrusts, 0)
    return np.array([out[0], out[1], out[2]])


@numba.njit(cache=True)
def at_thrust_stop(x, Pc, kept, stop_std, yaw_prior, P, work):
    """State and covariance at a thrust stop: the yaw environment restarts (see
    :meth:`hybridship.residual.environment.EnvironmentEstimator.at_thrust_stop`)."""
    k = _YAW_LOAD
    x = x.copy()
    Pn = Pc.copy()
    current_yaw = current_yaw_accel(x, P, work)
    total = x[k] + current_yaw
    x[k] = kept * total - current_yaw
    for i in range(x.size):
        Pn[k, i] = 0.0
        Pn[i, k] = 0.0
    Pn[k, k] = yaw_prior ** 2 + (stop_std * total) ** 2
    return x, Pn


@numba.njit(cache=True)
def current_ridge_at_stop(x, Pc, std, P, work):
    """Covariance at a thrust stop, widened by ``std`` [m/s] per NED axis of the current
    along the ridge on which station keeping cannot tell a current from a load (see
    :meth:`hybridship.residual.environment.EnvironmentEstimator.at_thrust_stop`).

    Each current change comes with the load change that keeps the hull's acceleration at
    the stop: a body-frame change ``d`` is undone by the NED load ``-R(psi) d``. The mean is
    unchanged; the drift samples then decide the split.
    """
    n = x.size
    G = np.zeros((n, 2))
    c, s = math.cos(x[2]), math.sin(x[2])
    h = 0.01                                    # [m/s], central: the quadratic damping's slope
    for j in range(2):
        dn, de = (h, 0.0) if j == 0 else (0.0, h)
        d = (_current_response(x, x[_CUR] + dn, x[_CUR + 1] + de, P, work)
             - _current_response(x, x[_CUR] - dn, x[_CUR + 1] - de, P, work)) / (2.0 * h)
        G[_CUR + j, j] = 1.0
        G[_LOAD, j] = -(c * d[0] - s * d[1])
        G[_LOAD + 1, j] = -(s * d[0] + c * d[1])
        G[_YAW_LOAD, j] = -d[2]
    Pn = Pc + std * std * (G @ G.T)
    return x, 0.5 * (Pn + Pn.T)


@numba.njit(cache=True)
def load_to_current_at_stop(x, frac, P, work):
    """State at a thrust stop with the fraction ``frac`` of the NED load's surge/sway
    acceleration re-explained as a current (see
    :meth:`hybridship.residual.environment.EnvironmentEstimator.at_thrust_stop`).

    Newton's method finds the current whose hull response at the stop state adds ``frac``
    of the load's body-frame acceleration to that of the estimated current (at most 1 m/s;
    steps of at most 0.1 m/s); the load then gives up what the current took over, in yaw
    too, so the acceleration at the stop is unchanged.
    """
    x = x.copy()
    c, s = math.cos(x[2]), math.sin(x[2])
    bn, be = x[_LOAD], x[_LOAD + 1]
    want0 = frac * (c * bn + s * be)            # R^T b: the load's body-frame acceleration
    want1 = frac * (-s * bn + c * be)
    cn0, ce0 = x[_CUR], x[_CUR + 1]
    a_est = _current_response(x, cn0, ce0, P, work)
    cn, ce = cn0, ce0
    h = 0.005
    for _ in range(50):
        a = _current_response(x, cn, ce, P, work)
        r0, r1 = a[0] - a_est[0] - want0, a[1] - a_est[1] - want1
        if abs(r0) < 1e-7 and abs(r1) < 1e-7:
            break
        dn = (_current_response(x, cn + h, ce, P, work) - _current_response(x, cn - h, ce, P, work)) / (2.0 * h)
        de = (_current_response(x, cn, ce + h, P, work) - _current_response(x, cn, ce - h, P, work)) / (2.0 * h)
        det = dn[0] * de[1] - de[0] * dn[1]
        if abs(det) < 1e-12:
            break
        sn = -(de[1] * r0 - de[0] * r1) / det
        se = -(-dn[1] * r0 + dn[0] * r1) / det
        step = math.hypot(sn, se)
        if step > 0.1:
            sn, se = 0.1 * sn / step, 0.1 * se / step
        cn, ce = cn + sn, ce + se
        speed = math.hypot(cn, ce)
        if speed > 1.0:
            cn, ce = cn / speed, ce / speed
    d = _current_response(x, cn, ce, P, work) - a_est
    x[_CUR], x[_CUR + 1] = cn, ce
    x[_LOAD] -= c * d[0] - s * d[1]
    x[_LOAD + 1] -= s * d[0] + c * d[1]
    x[_YAW_LOAD] -= d[2]
    return x


@numba.njit(cache=True)
def _restarted(z_i, x, Pc, keep_environment, gap_s, prior_thr, prior_sd, q_base, load_prior_ne):
    """The state and covariance of a (re)start at a sample ``z_i``: motion states from the
    measurement (a velocity not logged: 0), the rest from the prior (the NED load's block
    ``load_prior_ne`` (2, 2) [m^2/s^4] where its first entry is positive, else
    ``prior_sd``'s); with ``keep_environment``, the environment of ``x, Pc`` kept, its
    covariance grown over the gap ``gap_s`` [s]."""
    n = prior_sd.size
    x0 = np.zeros(n)
    P0 = np.zeros((n, n))
    for j in range(3):
        x0[j] = z_i[j]
        x0[3 + j] = z_i[3 + j] if math.isfinite(z_i[3 + j]) else 0.0
    for j in range(n - _THR):
        x0[_THR + j] = prior_thr[j]
    for j in range(n):
        P0[j, j] = prior_sd[j] ** 2
    if load_prior_ne[0, 0] > 0.0:
        for a in range(2):
            for b in range(2):
                P0[_LOAD + a, _LOAD + b] = load_prior_ne[a, b]
    if keep_environment:
        Qg = process_noise(gap_s, q_base)
        for a in range(6, n):
            x0[a] = x[a]
            for b in range(6, n):
                P0[a, b] = Pc[a, b] + Qg[a, b]
    return x0, P0


@numba.njit(cache=True)
def _cut_motion_environment(Pc):
    """Cut the covariance between the motion states and the environment (in place): the
    next update then moves the motion states alone."""
    n = Pc.shape[0]
    for a in range(6):
        for b in range(6, n):
            Pc[a, b] = 0.0
            Pc[b, a] = 0.0


@numba.njit(cache=True)
def filter_grid(grid, slot, t, seg, z, z_ok, r_std, rpm, az, wind, dp, cmd_known, P, per_thruster, prior_thr,
                prior_sd, q_base, q_base_stopped, fd_step, reset_at_stop, kept, stop_std, yaw_prior, current_stop_std,
                load_to_current, drift_yaw_uv, gate, max_gated, settle_s, max_bridge_s, step_s, resume, x_resume,
                P_resume, settle_io, gate_io, out_x, out_P, done, load_map, load_prior_ne):
    """Run the filter over the log rows ``grid`` (increasing).

    At a row ``i`` with ``slot[i] >= 0`` the estimate goes to ``out_x[slot[i]]``,
    ``out_P[slot[i]]`` and ``done[slot[i]]`` is set. A new segment after a gap of at most
    ``max_bridge_s`` [s] is filtered across: the process model predicts through the gap in
    about ``step_s``-long steps (the grid's), as without measurements. A longer gap (or a
    lost estimate) restarts the motion states from the measurement and keeps the
    environment, whose covariance grows by the process noise over the gap (``q_base_stopped``
    when the thrusters were stopped at the last filtered row, as across a bridged gap). Rows whose
    position or heading is missing cannot start the filter: a new segment restarts at its
    first row with them.
    At a thrust stop (``dp`` 1 -> 0) the yaw environment restarts with ``reset_at_stop``
    (:func:`at_thrust_stop`), the fraction ``load_to_current`` of the load becomes a current
    (:func:`load_to_current_at_stop`; 0: none) and the current's uncertainty widens along
    the current-load ridge by ``current_stop_std`` [m/s] (:func:`current_ridge_at_stop`; 0: not).
    While ``dp`` is 0 at a step's first row, the process model adds the hull's yaw
    acceleration in a drift ``drift_yaw_uv u v`` [rad/s^2], and its noise intensities are
    ``q_base_stopped`` instead of ``q_base`` (the environment of a drifting ship changes
    faster). With ``resume``,
    ``x_resume, P_resume`` is the estimate at ``grid[0]`` (of an earlier run) and the filter
    goes on from there. A (re)start takes the NED load's prior from ``load_prior_ne`` (:func:`_restarted`).
    Measurements beyond ``gate`` standard deviations are outliers
    (:func:`update`; ``max_gated`` in a row are followed); a restart resets that count.
    For ``settle_s`` [s] after each (re)start of the motion states, the covariance between
    them and the environment is cut before every update, so that the measurements settle
    the motion states and leave the environment as it was: the start-up transient (motion
    states started from one noisy sample) would otherwise leave its mark on the split
    between current and load, which station keeping cannot correct. So it is after a step
    from a row whose commands the log does not record while the thrusters run (``cmd_known``
    False; the reader held the last logged ones): its thrust is a guess, whose error the
    environment would otherwise take up. ``settle_io[0]`` holds
    the time [s] until which a run settles and ``gate_io`` (2, 6) the gate's state per channel
    (:func:`update`: outliers in a row, last innovation): read with ``resume``, written at
    the end, so that a resumed run gates as the run it continues would have.
    """
    work = _workspace(P)
    gate_state = np.zeros((2, 6))
    n = prior_sd.size
    x, Pc = np.zeros(n), np.zeros((n, n))
    started, prev, settle_until = False, -1, -math.inf
    if resume:
        x, Pc, started, prev = x_resume.copy(), P_resume.copy(), True, grid[0]
        settle_until = settle_io[0]
        gate_state[:] = gate_io
        s = slot[prev]
        if s >= 0:
            out_x[s] = x
            out_P[s] = Pc
            done[s] = True
    for gi in range(1 if resume else 0, grid.size):
        i = grid[gi]
        finite = True
        for j in range(n):
            if not math.isfinite(x[j]):
                finite = False
        if not started or not finite or (seg[i] != seg[prev] and t[i] - t[prev] > max_bridge_s):
            if not (z_ok[i, 0] and z_ok[i, 1] and z_ok[i, 2]):
                if not (started and finite):
                    prev = i
                # else: prev stays the last filtered row, so the next row with a position
                # restarts the new segment (not a prediction across the gap)
                continue
            # the environment walks over the gap as across a bridged one: stopped or not at the last row
            keep = started and finite
            x, Pc = _restarted(z[i], x, Pc, keep, max(t[i] - t[prev], 0.0), prior_thr, prior_sd,
                               q_base if not keep or dp[prev] else q_base_stopped, load_prior_ne)
            gate_state[:] = 0.0
            started = True
            settle_until = t[i] + settle_s
        else:
            dt = t[i] - t[prev]
            # a bridged gap in steps of about the grid's (one step on a gap-free grid)
            n_sub = max(1, int(round(dt / step_s)))
            h = dt / n_sub
            for _ in range(n_sub):
                q = process_noise(h, q_base if dp[prev] else q_base_stopped)
                x, Pc = predict(x, Pc, h, rpm[prev], az[prev], wind[prev], q, fd_step, P, per_thruster,
                                0.0 if dp[prev] else drift_yaw_uv, load_map, work)
            if t[i] <= settle_until or not cmd_known[prev]:
                _cut_motion_environment(Pc)
            x, Pc = update(x, Pc, z[i], z_ok[i], r_std[i], gate, max_gated, gate_state)
            if dp[prev] and not dp[i]:
                if reset_at_stop:
                    x, Pc = at_thrust_stop(x, Pc, kept, stop_std, yaw_prior, P, work)
                if load_to_current > 0.0:
                    x = load_to_current_at_stop(x, load_to_current, P, work)
                if current_stop_std > 0.0:
                    x, Pc = current_ridge_at_stop(x, Pc, current_stop_std, P, work)
        prev = i
        s = slot[i]
        if s >= 0:
            out_x[s] = x
            out_P[s] = Pc
            done[s] = True
    settle_io[0] = settle_until
    gate_io[:] = gate_state


@numba.njit(cache=True)
def thrust_error_accel_batch(eta, nu, rpm, az, wind, current_ned, theta, P, per_thruster, out):
    """``T theta`` (B, 3) [m/s^2, m/s^2, rad/s^2]: the acceleration of the thrust-model error
    ``theta`` (B, n_theta) at each state, commands and current ``current_ned`` (B, 2) [m/s]."""
    work = _workspace(P)
    n_theta = theta.shape[1]
    x = np.zeros(_THR + n_theta)
    T = np.empty((3, n_theta))
    for b in range(eta.shape[0]):
        for i in range(3):
            x[i] = eta[b, i]
            x[3 + i] = nu[b, i]
        x[_CUR] = current_ned[b, 0]
        x[_CUR + 1] = current_ned[b, 1]
        _prep_for(x, rpm[b], az[b], wind[b], P, work[0])
        _thrust_basis(x, rpm[b], work[0], P, per_thruster, work[1], work[2], T)
        for i in range(3):
            acc = 0.0
            for j in range(n_theta):
                acc += T[i, j] * theta[b, j]
            out[b, i] = acc
