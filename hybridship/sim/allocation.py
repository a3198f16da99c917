"""Thrust allocation: generalised force demand -> thruster rpm and azimuth angles.

The extended-thrust formulation (Fossen 2021, sec. 11.2.2) turns every azimuth thruster
into two orthogonal force components ``(f_x, f_y)`` and every fixed-axis thruster (tunnel,
or a fixed propeller) into one component along its axis, so that the configuration is the
constant matrix ``T_e`` and ``tau = T_e f_e`` is linear:

* azimuth at ``(x, y)``: columns ``[1, 0, -y]`` and ``[0, 1, x]``;
* fixed axis ``alpha``: column ``[cos a, sin a, x sin a - y cos a]`` (tunnel: ``[0, 1, x]``).

The unconstrained demand is met by the weighted least-norm solution
``f_e = W^-1 T_e^T (T_e W^-1 T_e^T)^-1 tau`` (a weighted pseudo-inverse). On a vessel whose
thrusters cannot load the hull in every direction (:func:`station_keeping_rank` < 3, e.g. a
single propeller) the pseudo-inverse gives the least-squares solution instead: the part of the
demand no thruster makes is left out, without ``saturated`` (compare ``tau_achieved``). Each azimuth is
then commanded to ``alpha = atan2(f_y, f_x)`` with thrust ``|f|``. Thruster limits come from
the propeller model: the largest force is what ``+max_rpm`` (and, when reversing,
``-max_rpm``) delivers at the bollard condition, times ``(1 - thrust_deduction)``.

Saturation. If the pseudo-inverse solution exceeds a limit, the null space of ``T_e`` is
searched first for a feasible solution (smallest move from the least-norm one); if none
exists, the demand is scaled down, keeping its direction, to the largest feasible fraction
(a min-max utilisation problem solved with SLSQP over the null-space coordinates). The
achieved load is then ``scale * tau`` for the magnitudes; rate limits may cut it further
and :attr:`AllocationResult.tau_achieved` reports what the propeller model delivers.

Commands. Azimuth angles are rate limited (``max_azimuth_rate_deg_s``, shortest way round)
and may point opposite to the demanded force with negative rpm when that is the shorter
turn (with some hysteresis against chattering). The force along the angle actually
reached (the projection of the demanded force) is converted to rpm by inverting the
four-quadrant propeller model at the current inflow
``V_a = (1 - w) [(u_r - y r) cos a + (v_r + x r) sin a]``, so the rpm reproduces the force
in :class:`hybridship.physics.model.DynamicModel`; the rpm is then rate limited.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.optimize

from hybridship.config import check_flags, check_number, real_array
from hybridship.frames import wrap_pi
from hybridship.physics.propeller import load_wageningen, rpm_for_thrust, thrust_torque
from hybridship.physics.thrusters import configuration_matrix

__all__ = ["AllocationResult", "ThrusterLimits", "ThrustAllocator", "bollard_thrust_limits", "thrust_capacity",
           "thrust_capacity_by_sign",
           "extended_configuration", "station_keeping_rank", "check_station_keeping"]

#: Default time to ramp a shaft from 0 to max_rpm when no rpm rate limit is given [s].
DEFAULT_RPM_RAMP_TIME_S = 10.0


# --------------------------------------------------------------------------- helpers


def _vessel(vessel):
    from hybridship.vessel import Vessel, load_vessel

    return vessel if isinstance(vessel, Vessel) else load_vessel(vessel)


def _vector(name, value, n):
    """``value`` as a finite float array of shape (n,), or ValueError naming ``name``."""
    a = real_array(name, value)
    if a.shape != (n,):
        raise ValueError(f"{name}: expected shape ({n},), got {np.shape(value)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    return a.copy()


@dataclass(frozen=True)
class ThrusterLimits:
    """Force limits of each thruster at the bollard condition (delivered force, after thrust deduction).

    Attributes
    ----------
    forward_N : ndarray, shape (K,)
        Force at ``+max_rpm`` [N] (> 0).
    reverse_N : ndarray, shape (K,)
        Magnitude of the force at ``-max_rpm`` [N] (> 0; B-series propellers
        are weaker astern).
    """

    forward_N: np.ndarray
    reverse_N: np.ndarray


def bollard_thrust_limits(vessel) -> ThrusterLimits:
    """Largest delivered force of each thruster ahead and astern at zero inflow.

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str
        Vessel, or a packaged name or vessel-file path (see :func:`hybridship.vessel.load_vessel`).

    Returns
    -------
    ThrusterLimits
    """
    v = _vessel(vessel)
    rho = v.particulars.rho_water_kg_m3
    fwd, rev = [], []
    for t in v.thrusters:
        prop = load_wageningen(t.propeller_series, t.pitch_ratio)
        n = np.array([t.max_rpm, -t.max_rpm]) / 60.0
        T, _ = thrust_torque(n, np.zeros(2), t.diameter_m, prop, rho)
        fwd.append((1.0 - t.thrust_deduction) * T[0])
        rev.append(-(1.0 - t.thrust_deduction) * T[1])
    fwd, rev = np.array(fwd), np.array(rev)
    if np.any(fwd <= 0) or np.any(rev <= 0):
        raise ValueError("thrusters: a propeller gives no bollard thrust at max_rpm "
                         f"(ahead {fwd}, astern {-rev} N); check propeller_series/pitch_ratio")
    return ThrusterLimits(fwd, rev)


def extended_configuration(vessel):
    """Extended thrust configuration matrix and the variable layout.

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str
        Vessel, or a packaged name or vessel-file path (see :func:`hybridship.vessel.load_vessel`).

    Returns
    -------
    T_e : ndarray, shape (3, n)
        Constant configuration matrix, ``tau = T_e @ f_e``.
    owner : ndarray of int, shape (n,)
        Thruster index of each variable (azimuths own two consecutive variables
        ``f_x, f_y``; fixed-axis thrusters one, along their axis).
    """
    v = _vessel(vessel)
    cols, owner = [], []
    for i, t in enumerate(v.thrusters):
        if t.type == "azimuth":
            cols += [[1.0, 0.0, -t.y_m], [0.0, 1.0, t.x_m]]
            owner += [i, i]
        else:
            cols.append(configuration_matrix([t.fixed_angle_rad], [t.x_m], [t.y_m])[:, 0])
            owner.append(i)
    return np.array(cols, dtype=float).reshape(-1, 3).T, np.array(owner, dtype=int)   # (3, 0) without thrusters


#: Relative tolerance of the rank test in :func:`station_keeping_rank` (the matrix entries are O(1)).
_RANK_RTOL = 1e-9

_DOF_LOADS = ("pure surge force", "pure sway force", "pure yaw moment")


def _scaled_configuration(vessel):
    """``T_e`` with its yaw row divided by ``L_pp``, so that every entry is a dimensionless O(1)
    number and the rank test does not depend on the vessel's size."""
    v = _vessel(vessel)
    T_e, _ = extended_configuration(v)
    if T_e.size == 0:
        return np.zeros((3, 0))
    return T_e / np.array([1.0, 1.0, v.particulars.L_pp_m])[:, None]


def _rank(a) -> int:
    return 0 if a.size == 0 else int(np.linalg.matrix_rank(a, tol=_RANK_RTOL * max(1.0, np.abs(a).max())))


def station_keeping_rank(vessel) -> int:
    """Number of independent directions of ``[X, Y, N]`` the thrusters can load the hull in.

    The rank of the extended thrust configuration matrix ``T_e``
    (:func:`extended_configuration`): its columns cover every azimuth angle an azimuth
    thruster can take (the vessel file sets no sector limits) and each fixed-axis
    thruster's own axis. Every thruster pushes both ways (:func:`bollard_thrust_limits`
    refuses a propeller without thrust ahead or astern), so the loads the thrusters can
    make form a symmetric convex set around zero that spans the column space of ``T_e``.
    Rank 3 therefore means that every small enough demand in surge, sway and yaw is met
    exactly; below 3 some direction of load cannot be made at all, however small.

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str
        Vessel, or a packaged name or vessel-file path.

    Returns
    -------
    int
        0..3 (3: the thrusters can hold station in surge, sway and yaw).

    Notes
    -----
    Rudders do not count: the DP system commands thrusters only, and a rudder makes
    lift only in a flow. Rank 3 says nothing about capacity, i.e. whether the thrusters
    are strong enough for a given weather (:func:`thrust_capacity`).
    """
    return _rank(_scaled_configuration(vessel))


def check_station_keeping(vessel) -> None:
    """Refuse a vessel whose thrusters cannot hold station in surge, sway and yaw.

    The criterion is :func:`station_keeping_rank` < 3 (a vessel with no thrusters has rank 0).

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str

    Raises
    ------
    ValueError
        One line naming the vessel, the rank and the loads its thrusters cannot make.
    """
    v = _vessel(vessel)
    T = _scaled_configuration(v)
    rank = _rank(T)
    if rank == 3:
        return
    # A pure load along one axis is possible iff adding that axis does not raise the rank.
    missing = [load for j, load in enumerate(_DOF_LOADS) if _rank(np.column_stack([T, np.eye(3)[:, j]])) > rank]
    kinds = ", ".join(f"{t.name}: {t.type}" for t in v.thrusters) or "none"
    raise ValueError(f"vessel {v.name!r} cannot hold station in surge, sway and yaw: its thrusters ({kinds}) "
                     f"make no {' or '.join(missing)} at any azimuth angle (extended thrust configuration "
                     f"matrix of rank {rank} < 3; rudders are not DP actuators)")


@dataclass(frozen=True)
class AllocationResult:
    """Thruster commands of one allocation step.

    Attributes
    ----------
    rpm : ndarray, shape (K,)
        Shaft speed commands [rpm], signed, within ``+-max_rpm``.
    azimuth_rad : ndarray, shape (K,)
        Thrust directions [rad] in [-pi, pi) (fixed-axis thrusters: their axis).
    thrust_N : ndarray, shape (K,)
        Delivered force along each thruster axis at the commanded rpm and the
        given inflow (four-quadrant model, after thrust deduction) [N].
    tau_achieved : ndarray, shape (3,)
        Generalised force ``[X_N, Y_N, N_Nm]`` those commands deliver.
    saturated : bool
        True when a thrust limit (bollard limit or max_rpm at the actual inflow) cut
        the demand. Thrusters at their bollard limit then run at ``+-max_rpm``. A load the
        thrusters cannot make at all (a vessel of :func:`station_keeping_rank` < 3) is
        left out without it: only ``tau_achieved`` shows it.
    rate_limited : bool
        True when an azimuth or rpm rate limit was active.
    demand_scale : float
        Fraction of the demand the magnitude limits allow (1 when feasible; of the
        least-squares part of it on a vessel of :func:`station_keeping_rank` < 3).
    tau_desired : ndarray, shape (3,)
        The demand ``[X_N, Y_N, N_Nm]``, for reference.
    """

    rpm: np.ndarray
    azimuth_rad: np.ndarray
    thrust_N: np.ndarray
    tau_achieved: np.ndarray
    saturated: bool
    rate_limited: bool = False
    demand_scale: float = 1.0
    tau_desired: np.ndarray = field(default_factory=lambda: np.zeros(3))


# --------------------------------------------------------------------------- allocator


class ThrustAllocator:
    """Extended-thrust allocation with saturation, reversal and rate limits (module docstring).

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str
        Vessel (or packaged name) with tunnel, fixed and/or azimuth thrusters.
    dt_s : float
        Time between successive :meth:`allocate` calls [s] (for the rate limits).
    rpm_rate_limit_rpm_s : float or sequence of K floats, optional
        Largest rpm change per second of each thruster; ``inf`` disables the limit. Default:
        ``max_rpm / 10 s`` per thruster (Gunnerus: 21.7 rpm/s azimuths, 42.4 rpm/s tunnel).
    weights : sequence of K floats, optional
        Cost of each thruster's force in the weighted pseudo-inverse (``f^T W f``; both
        components of an azimuth share its weight). Default ``1 / F_max^2``, i.e. equal
        utilisation of each thruster's bollard capacity.
    reverse_hysteresis_rad : float
        An azimuth changes between forward and reversed thrust only when the other choice
        saves more than this much turning [rad].
    warn_unlimited_slew : bool
        Warn that azimuths without ``max_azimuth_rate_deg_s`` turn instantly (the simulator's
        allocation); False for a static use such as :func:`thrust_capacity`.

    Notes
    -----
    The allocator remembers the previous angles and rpm. After construction or
    :meth:`reset` without arguments the first call is not rate limited (angles and rpm are
    taken as free), which also makes a fresh allocator a static allocation.
    """

    def __init__(self, vessel, *, dt_s: float, rpm_rate_limit_rpm_s=None, weights=None,
                 reverse_hysteresis_rad: float = math.radians(15.0), warn_unlimited_slew: bool = True):
        self.vessel = _vessel(vessel)
        th = self.vessel.thrusters
        K = len(th)
        if K == 0:
            raise ValueError("vessel.thrusters: the vessel has no thrusters to allocate to")
        if isinstance(dt_s, (bool, np.bool_)) or not isinstance(dt_s, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(dt_s) and dt_s > 0):
            raise ValueError(f"dt_s: must be finite and > 0, got {dt_s!r}")
        check_flags(warn_unlimited_slew=warn_unlimited_slew)     # a text "no" is truthy
        if check_number("reverse_hysteresis_rad", reverse_hysteresis_rad, lo=0.0) >= math.pi:
            raise ValueError(f"reverse_hysteresis_rad: must be in [0, pi), got {reverse_hysteresis_rad!r}")
        self.dt_s = float(dt_s)
        self.reverse_hysteresis_rad = float(reverse_hysteresis_rad)
        self.n_thrusters = K

        self.max_rpm = np.array([t.max_rpm for t in th], float)
        if rpm_rate_limit_rpm_s is None:
            rate = self.max_rpm / DEFAULT_RPM_RAMP_TIME_S
        else:
            rate = real_array("rpm_rate_limit_rpm_s", rpm_rate_limit_rpm_s)
            if rate.ndim == 0:
                rate = np.full(K, float(rate))
            if rate.shape != (K,):
                raise ValueError(f"rpm_rate_limit_rpm_s: expected a scalar or shape ({K},), "
                                 f"got {np.shape(rpm_rate_limit_rpm_s)}")
            if np.any(np.isnan(rate)) or np.any(rate <= 0):
                raise ValueError(f"rpm_rate_limit_rpm_s: every limit must be > 0 (inf = none), got {rate}")
        self.rpm_rate_limit_rpm_s = rate

        self.is_azimuth = np.array([t.type == "azimuth" for t in th])
        fixed = np.array([t.fixed_angle_rad for t in th], float)
        # in the documented [-pi, pi) (a file's angle_deg = 270 gave 4.71 rad); angles within it kept bit for bit
        self.fixed_angle_rad = np.where((fixed >= -math.pi) & (fixed < math.pi), fixed, wrap_pi(fixed))
        # Azimuths without a slew limit turn instantly: said, since a real one cannot
        unlimited = [t.name for t in th if t.type == "azimuth" and not t.max_azimuth_rate_deg_s]
        if unlimited and warn_unlimited_slew:
            from hybridship.messages import warn_user

            warn_user(f"vessel {self.vessel.name!r}: azimuth thruster(s) {', '.join(unlimited)} have no "
                      f"max_azimuth_rate_deg_s and turn instantly in the simulation (real ones slew at a few "
                      f"deg/s: give the rate in the vessel file)", UserWarning)
        self.azimuth_rate_limit_rad_s = np.array(
            [math.radians(t.max_azimuth_rate_deg_s) if t.max_azimuth_rate_deg_s else np.inf for t in th])
        self.x_m = np.array([t.x_m for t in th], float)
        self.y_m = np.array([t.y_m for t in th], float)
        self.wake = np.array([t.wake_fraction for t in th], float)
        self.tded = np.array([t.thrust_deduction for t in th], float)
        self.rho_kg_m3 = float(self.vessel.particulars.rho_water_kg_m3)
        self.limits = bollard_thrust_limits(self.vessel)

        # Thrusters with the same propeller share one vectorised rpm inversion.
        groups: dict[tuple, list[int]] = {}
        for i, t in enumerate(th):
            groups.setdefault((t.diameter_m, t.propeller_series, t.pitch_ratio, t.max_rpm), []).append(i)
        self._groups = [(np.array(idx), k[0], load_wageningen(k[1], k[2]), k[3]) for k, idx in groups.items()]

        # Extended formulation and its weighted pseudo-inverse.
        self.T_e, self._owner = extended_configuration(self.vessel)
        if weights is None:
            w = 1.0 / self.limits.forward_N**2
        else:
            w = _vector("weights", weights, K)
            if np.any(w <= 0):
                raise ValueError(f"weights: every weight must be > 0, got {w}")
        self.weights = w
        w_inv_sqrt = 1.0 / np.sqrt(w[self._owner])
        # f = W^-1/2 pinv(T W^-1/2) tau: the weighted least-norm (least-squares if rank deficient) solution.
        self._P = w_inv_sqrt[:, None] * np.linalg.pinv(self.T_e * w_inv_sqrt[None, :])
        self._N = scipy.linalg.null_space(self.T_e)
        self._f_ref = float(np.mean(self.limits.forward_N))
        self._az_first = np.array([np.flatnonzero(self._owner == i)[0] for i in range(K)])
        self.reset()

    # ----------------------------------------------------------------- state

    def reset(self, azimuth_rad=None, rpm=None) -> None:
        """Set the remembered angles [rad] and rpm (each (K,)); None makes them free for the next call."""
        K = self.n_thrusters
        self._angle = None if azimuth_rad is None else wrap_pi(_vector("azimuth_rad", azimuth_rad, K))
        if rpm is None:
            self._rpm = None
        else:
            r = _vector("rpm", rpm, K)
            if np.any(np.abs(r) > self.max_rpm * (1 + 1e-9)):
                raise ValueError(f"rpm: |rpm| must not exceed max_rpm {self.max_rpm}, got {r}")
            self._rpm = r

    @property
    def azimuth_rad(self):
        """Last commanded angles (K,) [rad], or None before the first call."""
        return None if self._angle is None else self._angle.copy()

    @property
    def rpm(self):
        """Last commanded rpm (K,), or None before the first call."""
        return None if self._rpm is None else self._rpm.copy()

    # ----------------------------------------------------------------- magnitude problem

    def _utilisation(self, f):
        """Per-thruster use of its bollard limit for extended forces ``f`` (..., n) -> (..., K)."""
        lim = self.limits
        u = np.empty(f.shape[:-1] + (self.n_thrusters,))
        for i in range(self.n_thrusters):
            j = self._az_first[i]
            if self.is_azimuth[i]:
                u[..., i] = np.hypot(f[..., j], f[..., j + 1]) / lim.forward_N[i]
            else:
                u[..., i] = np.where(f[..., j] >= 0, f[..., j] / lim.forward_N[i], -f[..., j] / lim.reverse_N[i])
        return u

    def _minmax(self, f0):
        """Null-space move ``d`` minimising the largest utilisation of ``f0 + d`` (SLSQP)."""
        N = self._N
        m = N.shape[1]
        if m == 0:
            return np.zeros_like(f0)
        g0 = float(self._utilisation(f0).max())
        # Solve for f0 / g0 (utilisation 1) with coordinates in units of a typical
        # thruster force, so that every variable is O(1); the problem is homogeneous.
        fn = f0 / g0
        Ns = N * self._f_ref
        lim = self.limits
        cons = []
        eps = 1e-9
        for i in range(self.n_thrusters):
            j = self._az_first[i]
            if self.is_azimuth[i]:
                F = lim.forward_N[i]

                def c_az(x, j=j, F=F):
                    f = fn[j:j + 2] + Ns[j:j + 2] @ x[:m]
                    return np.array([x[m] - math.sqrt(f @ f + eps) / F])

                def j_az(x, j=j, F=F):
                    f = fn[j:j + 2] + Ns[j:j + 2] @ x[:m]
                    grad = -(f @ Ns[j:j + 2]) / (math.sqrt(f @ f + eps) * F)
                    return np.append(grad, 1.0)[None, :]

                cons.append({"type": "ineq", "fun": c_az, "jac": j_az})
            else:
                for sgn, F in ((1.0, lim.forward_N[i]), (-1.0, lim.reverse_N[i])):
                    a = np.append(-sgn * Ns[j] / F, 1.0)
                    b = -sgn * fn[j] / F
                    cons.append({"type": "ineq", "fun": lambda x, a=a, b=b: np.array([a @ x + b]),
                                 "jac": lambda x, a=a: a[None, :]})
        x0 = np.append(np.zeros(m), 1.0)
        res = scipy.optimize.minimize(lambda x: x[m], x0, jac=lambda x: np.eye(m + 1)[m],
                                      constraints=cons, method="SLSQP",
                                      options={"maxiter": 100, "ftol": 1e-10})
        d = g0 * (Ns @ res.x[:m])
        # Keep the least-norm solution if the optimiser did not improve on it.
        if not np.all(np.isfinite(d)) or self._utilisation(f0 + d).max() >= g0:
            return np.zeros_like(f0)
        return d

    def _solve_extended(self, tau):
        """Extended forces within the limits and the fraction of ``tau`` they achieve."""
        f0 = self._P @ tau
        g0 = float(self._utilisation(f0).max())
        if g0 <= 1.0:
            return f0, 1.0
        d = self._minmax(f0)
        g1 = float(self._utilisation(f0 + d).max())
        if g1 > 1.0:
            # Infeasible: keep the direction of the demand, scale to the largest feasible fraction.
            return (f0 + d) / g1, 1.0 / g1
        # Feasible in the null space: smallest step from the least-norm solution (g is
        # convex along the segment, so bisection finds where it crosses 1).
        lo, hi = 0.0, 1.0
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            if self._utilisation(f0 + mid * d).max() > 1.0:
                lo = mid
            else:
                hi = mid
        return f0 + hi * d, 1.0

    # ----------------------------------------------------------------- commands

    def _inflow(self, angle, nu_r):
        u, v, r = nu_r
        return (1.0 - self.wake) * ((u - self.y_m * r) * np.cos(angle) + (v + self.x_m * r) * np.sin(angle))

    def _delivered(self, rpm, va):
        out = np.empty(self.n_thrusters)
        for idx, D, prop, _ in self._groups:
            T, _ = thrust_torque(rpm[idx] / 60.0, va[idx], D, prop, self.rho_kg_m3)
            out[idx] = (1.0 - self.tded[idx]) * T
        return out

    def _rpm_for(self, force, va):
        out = np.empty(self.n_thrusters)
        for idx, D, prop, max_rpm in self._groups:
            # rpm_for_thrust inverts the open-water thrust; the hull takes (1 - t) of it.
            out[idx] = rpm_for_thrust(force[idx] / (1.0 - self.tded[idx]), va[idx], D, prop,
                                      self.rho_kg_m3, max_rpm)
        return out

    def allocate(self, tau_desired_N, nu_r) -> AllocationResult:
        """Thruster commands for a body-frame force demand.

        Parameters
        ----------
        tau_desired_N : array_like, shape (3,)
            Demanded ``[X_N, Y_N, N_Nm]`` in the body frame.
        nu_r : array_like, shape (3,)
            Velocity relative to the water ``[u_r_m_s, v_r_m_s, r_rad_s]`` (for the inflow).

        Returns
        -------
        AllocationResult
        """
        tau = _vector("tau_desired_N", tau_desired_N, 3)
        nu_r = _vector("nu_r", nu_r, 3)
        K = self.n_thrusters
        f_e, scale = self._solve_extended(tau)

        prev_angle = self._angle
        prev_rpm = self._rpm
        lim = self.limits
        small_N = 1e-3 * lim.forward_N
        target = self.fixed_angle_rad.copy()
        for i in np.flatnonzero(self.is_azimuth):
            j = self._az_first[i]
            fx, fy = f_e[j], f_e[j + 1]
            F = math.hypot(fx, fy)
            if prev_angle is None:
                target[i] = float(wrap_pi(math.atan2(fy, fx))) if F > small_N[i] else 0.0   # atan2 may give pi
                continue
            if F <= small_N[i]:
                target[i] = prev_angle[i]  # no meaningful direction: do not chase noise
                continue
            a_fwd = math.atan2(fy, fx)
            a_rev = float(wrap_pi(a_fwd + math.pi))
            turn_fwd = abs(float(wrap_pi(a_fwd - prev_angle[i])))
            turn_rev = abs(float(wrap_pi(a_rev - prev_angle[i])))
            reversing = prev_rpm is not None and prev_rpm[i] < 0.0
            # Hysteresis favours the present shaft direction; reversing only if astern can deliver.
            if reversing:
                turn_rev -= self.reverse_hysteresis_rad
            else:
                turn_fwd -= self.reverse_hysteresis_rad
            use_rev = turn_rev < turn_fwd and F <= lim.reverse_N[i]
            target[i] = a_rev if use_rev else a_fwd

        angle = target.copy()
        rate_limited = False
        if prev_angle is not None:
            step = wrap_pi(target - prev_angle)
            max_step = self.azimuth_rate_limit_rad_s * self.dt_s
            clipped = np.clip(step, -max_step, max_step)
            rate_limited |= bool(np.any(self.is_azimuth & (np.abs(clipped) < np.abs(step) - 1e-12)))
            angle = np.where(self.is_azimuth, wrap_pi(prev_angle + clipped), self.fixed_angle_rad)

        # Force along the axis actually reached: the projection of the demanded force.
        force = np.empty(K)
        for i in range(K):
            j = self._az_first[i]
            if self.is_azimuth[i]:
                force[i] = f_e[j] * math.cos(angle[i]) + f_e[j + 1] * math.sin(angle[i])
            else:
                force[i] = f_e[j]
        force = np.clip(force, -lim.reverse_N, lim.forward_N)

        va = self._inflow(angle, nu_r)
        rpm_wanted = self._rpm_for(force, va)
        if scale < 1.0:
            # Infeasible demand: thrusters at their bollard limit give all they have at the
            # actual inflow (more than at the bollard when the water meets them head on).
            full = (force >= lim.forward_N * (1 - 1e-6)) | (force <= -lim.reverse_N * (1 - 1e-6))
            rpm_wanted = np.where(full, np.sign(force) * self.max_rpm, rpm_wanted)
        saturated = scale < 1.0 - 1e-9 or bool(np.any(np.abs(rpm_wanted) >= self.max_rpm * (1 - 1e-6)))
        rpm = rpm_wanted
        if prev_rpm is not None:
            max_d = self.rpm_rate_limit_rpm_s * self.dt_s
            rpm = prev_rpm + np.clip(rpm_wanted - prev_rpm, -max_d, max_d)
            rate_limited |= bool(np.any(np.abs(rpm - rpm_wanted) > 1e-9))
        rpm = np.clip(rpm, -self.max_rpm, self.max_rpm)

        thrust = self._delivered(rpm, va)
        tau_achieved = configuration_matrix(angle, self.x_m, self.y_m) @ thrust
        self._angle = angle.copy()
        self._rpm = rpm.copy()
        return AllocationResult(rpm=rpm, azimuth_rad=angle, thrust_N=thrust, tau_achieved=tau_achieved,
                                saturated=bool(saturated), rate_limited=rate_limited,
                                demand_scale=float(scale), tau_desired=tau)


def thrust_capacity(vessel) -> np.ndarray:
    """Largest pure surge force, sway force and yaw moment the thrusters give at the bollard.

    Each is the smaller of the two signs (:func:`thrust_capacity_by_sign`), with the other
    two components held at zero (direction-preserving limit of :class:`ThrustAllocator`).

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str
        Vessel, or a packaged name or vessel-file path (see :func:`hybridship.vessel.load_vessel`).

    Returns
    -------
    ndarray, shape (3,)
        ``[X_N, Y_N, N_Nm]``, each > 0 when the vessel can produce that load at all.
    """
    return thrust_capacity_by_sign(vessel).min(axis=0)


def thrust_capacity_by_sign(vessel) -> np.ndarray:
    """:func:`thrust_capacity` for each sign: row 0 the largest positive surge force, sway
    force and yaw moment, row 1 the largest negative ones (as magnitudes), each with the
    other two components held at zero.

    Returns
    -------
    ndarray, shape (2, 3)
        ``[[X_N, Y_N, N_Nm] towards +, [X_N, Y_N, N_Nm] towards -]``, each >= 0.
    """
    alloc = ThrustAllocator(vessel, dt_s=1.0, warn_unlimited_slew=False)     # a static capacity: no slewing
    big = 1e12
    cap = np.empty((2, 3))
    for k in range(3):
        for i, sgn in enumerate((1.0, -1.0)):
            tau = np.zeros(3)
            tau[k] = sgn * big
            f, scale = alloc._solve_extended(tau)
            # what the forces give, not what was asked: a pure load the thrusters cannot make
            # (no thruster acts in that direction, or only together with another load) gets the
            # least-squares answer, which is not the scaled demand; its capacity is 0. The check
            # is relative to the load achieved: the demand's bound is 1e7 times larger.
            achieved = alloc.T_e @ f
            cap[i, k] = scale * big if np.abs(achieved - scale * tau).max() <= 1e-6 * scale * big else 0.0
    return cap
