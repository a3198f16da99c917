"""The 3-DOF dynamic model: eq. 1 solved for nu_dot, with thrusters (eq. 2), rudders and wind (eq. 3).

.. math::

    (M_{RB} + M_A)\\dot\\nu = \\tau_c + \\tau_{wi} + \\tau_{ext}
        - C_{RB}(\\nu)\\nu - C_A(\\nu_r)\\nu_r - D\\nu_r - D_n(\\nu_r)\\nu_r + M_A\\dot\\nu_c

    \\dot\\eta = R(\\psi)\\nu

The current is irrotational and constant in NED (speed, direction it flows TO); in the
rotating body frame ``nu_c = R(psi)^T v_c`` so ``d(nu_c)/dt = [r v_c, -r u_c, 0]``.
``tau_ext`` is any further body-frame load (the simulator's wave drift) and ``accel_ext``
an additive acceleration (the hybrid's residual correction).

Actuators, as in Fossen's and the MMG model's terms, are thrusters (and propellers) and
rudders; each is one command channel, the K thrusters of the vessel file in order, then its
R rudders (:attr:`DynamicModel.n_thrusters`, :attr:`~DynamicModel.n_rudders`,
:attr:`~DynamicModel.n_channels`). A thruster is commanded by its shaft speed ``rpm`` and,
for an azimuth thruster, its thrust direction ``azimuth_rad``; a rudder by its angle
``rudder_rad`` (delta, positive turns the ship to starboard). The compiled kernels read the
rudder angles packed after the thruster azimuths in one angle array; at the public methods,
``rpm`` and ``azimuth_rad`` may be given for the K thrusters alone and the rudder angles as
``rudder_rad``, or both K + R wide (a rudder's ``rpm`` column is then ignored and its angle
sits in its ``azimuth_rad`` column, the packing the logs use). Rudder loads
(:mod:`.rudder`) use the thrust of their propeller and count as actuator ("thrust") loads.

A vessel file is turned once into :class:`ModelArrays`, a tuple of plain float arrays
that the compiled kernels read; :class:`DynamicModel` is the thin object around them.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..config import check_flags, check_whole_number, real_array
from . import hull, wind as wind_curves
from .hull import mass_matrices  # moved to hull (vessel validation needs it without this module)
from .integrate import rollout_batch, step_batch
from .propeller import load_wageningen
from .rhs import dynamics_batch, prepare_inputs, vessel_rhs, wind_force_scalar  # noqa: F401 (kernels' old home)
from .rudder import RUD_NCOL, pack_rudders
from .thrusters import THR_ALPHA_FIXED, THR_D, THR_IS_AZIMUTH, THR_MAX_RPM, THR_TDED, THR_WAKE, THR_X, THR_Y

#: Number of samples of the uniform wind-coefficient table over gamma in [-pi, pi].
WIND_TABLE_SIZE = 721

#: Order of the load components in ``tau_parts``: hull (C, D terms), actuators (thrusters,
#: propellers and rudders), wind, external.
TAU_PARTS = ("hull", "thrust", "wind", "external")

#: Largest ``|rpm| / max_rpm`` the model accepts (as the forecasts' envelope,
#: ``Envelope.rpm_refuse_factor``): beyond it a command is a unit error.
RPM_LIMIT_FACTOR = 2.0


class ModelArrays(NamedTuple):
    """Packed parameters read by the compiled kernels (SI units, radians).

    Attributes
    ----------
    m_inv : ndarray, shape (3, 3)
        Inverse of M = M_RB + M_A.
    m_a : ndarray, shape (3, 3)
        Symmetric added-mass matrix M_A.
    rb : ndarray, shape (3,)
        ``[mass_kg, x_g_m, rho_water_kg_m3]``.
    d_lin : ndarray, shape (3, 3)
        Linear damping D.
    d_quad : ndarray, shape (3,)
        Quadratic damping ``[d_uu, d_vv, d_rr]`` (force ``-d |x| x``).
    d_lift : ndarray, shape (8,)
        Speed-proportional sway/yaw damping ``[d_vv, d_vr, d_rv, d_rr]`` per unit |u_r|, then
        the same four per unit u_r (see ``hull.clarke1983_lift``); the vessel's ``lift_speed``
        fills one half and leaves the other zero.
    strip_x, strip_w : ndarray, shape (n,)
        Cross-flow drag strip positions [m] and weights [kg/m] (``0.5 rho T C_d dx``).
    thr : ndarray, shape (K, 8)
        Thruster parameters (columns ``THR_*`` of :mod:`.thrusters`).
    thr_coef : ndarray, shape (K, 4, N)
        Four-quadrant Fourier coefficients.
    wind_p : ndarray, shape (4,)
        ``[rho_air_kg_m3, A_F_m2, A_L_m2, L_oa_m]``.
    wind_table : ndarray, shape (WIND_TABLE_SIZE, 3)
        C_X, C_Y, C_N on ``linspace(-pi, pi)``.
    rud : ndarray, shape (R, RUD_NCOL)
        Rudder parameters (columns ``RUD_*`` of :mod:`.rudder`); R may be 0.
    """

    m_inv: np.ndarray
    m_a: np.ndarray
    rb: np.ndarray
    d_lin: np.ndarray
    d_quad: np.ndarray
    d_lift: np.ndarray
    strip_x: np.ndarray
    strip_w: np.ndarray
    thr: np.ndarray
    thr_coef: np.ndarray
    wind_p: np.ndarray
    wind_table: np.ndarray
    rud: np.ndarray


# --------------------------------------------------------------------------- building


def wind_coefficient_curve(vessel):
    """The vessel's wind-coefficient function ``gamma_rad -> (C_X, C_Y, C_N)``, or None."""
    w, p = vessel.wind, vessel.particulars
    L_oa = w.L_oa_m or p.L_oa_m
    if w.method == "table":
        t = w.table
        return lambda g: wind_curves.tabulated_coefficients(g, angle_deg=t.angle_deg, C_X=t.C_X,
                                                            C_Y=t.C_Y, C_N=t.C_N)
    if w.method == "blendermann":
        b = w.blendermann
        return lambda g: wind_curves.blendermann_coefficients(g, vessel_type=b.vessel_type, A_F_m2=w.A_F_m2,
                                                              A_L_m2=w.A_L_m2, L_oa_m=L_oa, s_L_m=b.s_L_m)
    if w.method == "isherwood":
        i = w.isherwood
        return lambda g: wind_curves.isherwood_coefficients(g, L_oa_m=L_oa, B_m=p.B_m, A_L_m2=w.A_L_m2,
                                                            A_F_m2=w.A_F_m2, A_SS_m2=i.A_SS_m2, S_m=i.S_m,
                                                            C_m=i.C_m, M=i.M)
    return None


def check_step(dt_s, substeps) -> None:
    """Refuse a step length that is not a finite number of seconds > 0, or a substep count
    that is not a whole number >= 1 (ValueError naming the argument)."""
    if isinstance(dt_s, bool) or not isinstance(dt_s, (int, float, np.integer, np.floating)) \
            or not (0.0 < float(dt_s) < np.inf):
        raise ValueError(f"dt_s: expected a finite step > 0 s, got {dt_s!r}")
    check_whole_number("substeps", substeps, 1)


def build_model_arrays(vessel, *, true_vessel: bool = False) -> ModelArrays:
    """Derive every coefficient of a vessel file and pack them for the kernels.

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel
    true_vessel : bool
        Apply the file's ``[true_vessel]`` perturbation (the simulator's "real" ship).
    """
    pert = vessel.true_vessel
    ones = (1.0, 1.0, 1.0)
    am_s = pert.added_mass_scale if true_vessel else ones
    ld_s = np.asarray(pert.linear_damping_scale if true_vessel else ones)
    nd_s = np.asarray(pert.nonlinear_damping_scale if true_vessel else ones)
    wc_s = np.asarray(pert.wind_coefficient_scale if true_vessel else ones)
    th_s = pert.thrust_scale if true_vessel else 1.0

    p, rb = vessel.particulars, vessel.rigid_body
    rho = p.rho_water_kg_m3
    M_RB, M_A = mass_matrices(vessel, am_s)
    M = M_RB + M_A

    lin = vessel.damping.linear
    if lin.method == "time_constants":
        # Time constants refer to the nominal model's inertia so that a perturbed
        # true vessel's damping differs only by the stated factors.
        M_nom = sum(mass_matrices(vessel))
        D = hull.linear_damping_from_time_constants(M_nom, lin.T_surge_s, lin.T_sway_s, lin.T_yaw_s)
    else:
        D = np.asarray(lin.D, float)
    D = D * ld_s[:, None]

    nl = vessel.damping.nonlinear
    d_quad = np.array([nl.d_uu, nl.d_vv, nl.d_rr], float)
    strip_x = np.zeros(0)
    strip_w = np.zeros(0)
    if nl.method == "crossflow":
        if nl.surge_resistance == "ittc1957":
            d_quad[0] += hull.surge_quadratic_resistance(nl.wetted_surface_m2, p.L_pp_m, nl.speed_ref_m_s,
                                                         nl.form_factor_k, nl.C_R, rho)
        cd = nl.cd_2d if nl.cd_2d is not None else hull.hoerner_cd(p.B_m, p.T_m)
        strip_x, strip_w = hull.crossflow_strips(p.L_pp_m, p.T_m, cd, nl.strips, rho, x_aft_m=nl.strips_x_aft_m)
    elif nl.method == "none":
        d_quad[:] = 0.0
    lift = np.zeros(4)
    if nl.lift == "clarke1983":
        derivs = hull.clarke1983_derivatives(p.L_pp_m, p.B_m, p.T_m, p.C_B, rho)
        lift = hull.clarke1983_lift(derivs, sum(mass_matrices(vessel)) - M_RB) * nd_s[[1, 1, 2, 2]]
    elif nl.lift == "mmg":
        g = nl.mmg
        lift = hull.mmg_lift(g.Y_v, g.Y_r, g.N_v, g.N_r, p.L_pp_m, p.T_m, sum(mass_matrices(vessel)) - M_RB,
                             rho) * nd_s[[1, 1, 2, 2]]
    d_lift = np.zeros(8)
    d_lift[slice(4, 8) if nl.lift_speed == "signed" else slice(0, 4)] = lift
    # Sway and yaw cross-flow share strips; scale sway via the weights and yaw on top
    # through d_rr so that both factors act independently to first order.
    d_quad = d_quad * nd_s
    strip_w = strip_w * nd_s[1]

    K = len(vessel.thrusters)
    thr = np.zeros((K, 8))
    coefs = []
    for i, t in enumerate(vessel.thrusters):
        thr[i, THR_X] = t.x_m
        thr[i, THR_Y] = t.y_m
        thr[i, THR_D] = t.diameter_m
        thr[i, THR_WAKE] = t.wake_fraction
        # thrust_scale acts as a loss/gain on delivered thrust: (1 - t') = s (1 - t)
        thr[i, THR_TDED] = 1.0 - th_s * (1.0 - t.thrust_deduction)
        thr[i, THR_ALPHA_FIXED] = t.fixed_angle_rad
        thr[i, THR_IS_AZIMUTH] = 1.0 if t.type == "azimuth" else 0.0
        thr[i, THR_MAX_RPM] = t.max_rpm
        coefs.append(load_wageningen(t.propeller_series, t.pitch_ratio).coef)
    n_coef = max((c.shape[1] for c in coefs), default=1)
    thr_coef = np.zeros((K, 4, n_coef))
    for i, c in enumerate(coefs):
        thr_coef[i, :, : c.shape[1]] = c

    w = vessel.wind
    curve = wind_coefficient_curve(vessel)
    if curve is None:
        wind_table = np.zeros((WIND_TABLE_SIZE, 3))
        wind_p = np.array([w.rho_air_kg_m3, 0.0, 0.0, p.L_oa_m])
    else:
        _, wind_table = wind_curves.coefficient_table(curve, WIND_TABLE_SIZE)
        wind_table = wind_table * wc_s[None, :]
        wind_p = np.array([w.rho_air_kg_m3, w.A_F_m2, w.A_L_m2, w.L_oa_m or p.L_oa_m])

    arrays = ModelArrays(
        m_inv=np.linalg.inv(M), m_a=M_A, rb=np.array([rb.mass_kg, rb.x_g_m, rho]), d_lin=D,
        d_quad=d_quad, d_lift=d_lift, strip_x=strip_x, strip_w=strip_w, thr=thr, thr_coef=thr_coef,
        wind_p=wind_p, wind_table=np.ascontiguousarray(wind_table, dtype=float),
        rud=pack_rudders(vessel).reshape(-1, RUD_NCOL))
    return ModelArrays(*(np.ascontiguousarray(a, dtype=float) for a in arrays))


# --------------------------------------------------------------------------- thin class


class RolloutResult(NamedTuple):
    """Integrated trajectories, batch-first.

    Attributes
    ----------
    time_s : ndarray, shape (S+1,)
        Time since the start [s].
    eta : ndarray, shape (B, S+1, 3)
        ``[north_m, east_m, psi_rad]`` (heading unwrapped).
    nu : ndarray, shape (B, S+1, 3)
        ``[u_m_s, v_m_s, r_rad_s]``.
    nu_dot : ndarray, shape (B, S+1, 3)
        ``[u_dot_m_s2, v_dot_m_s2, r_dot_rad_s2]``.
    """

    time_s: np.ndarray
    eta: np.ndarray
    nu: np.ndarray
    nu_dot: np.ndarray


_INPUT_WIDTH = {"wind": 2, "current": 2, "tau_ext": 3, "accel_ext": 3}


def _as_float_array(name, value) -> np.ndarray:
    """``value`` as a float array, or a ValueError naming ``name`` (not numpy's conversion message);
    text is refused, also text that reads as a number (numpy would parse ``"100"``)."""
    try:
        return real_array(name, value)
    except TypeError:
        raise ValueError(f"{name}: expected numbers, got {value!r}") from None


def _as_input(name, value, B, S, width, default=0.0):
    """Normalise one input to ``(B, S_or_1, width)`` float64 with a clear error on bad shape/NaN."""
    if value is None:
        return np.full((B, 1, width), default)
    a = _as_float_array(name, value)
    if a.ndim == 1:
        a = a[None, None, :]
    elif a.ndim == 2:
        a = a[:, None, :]
    # per-step inputs (B, S, width) only where there are steps (a rollout); elsewhere one step
    steps_ok = a.ndim == 3 and (a.shape[1] == 1 if S is None else a.shape[1] in (1, S))
    if a.ndim != 3 or a.shape[-1] != width or a.shape[0] not in (1, B) or not steps_ok:
        steps = f" or (B, {S}, {width})" if S is not None else ""
        raise ValueError(f"{name}: expected shape ({width},), (B, {width}){steps} with B = {B}, got {np.shape(value)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    return np.ascontiguousarray(np.broadcast_to(a, (B,) + a.shape[1:]))


def _check_flow_speeds(**flows) -> None:
    """Refuse a negative wind or current speed (ValueError naming the input): the direction
    carries the way the flow goes, and a negative speed silently turned the flow round."""
    convention = {"wind": "dir_from_rad", "current": "dir_to_rad"}
    for name, flow in flows.items():
        if flow.size and flow[..., 0].min() < 0.0:
            raise ValueError(f"{name}: speed {flow[..., 0].min():g} m/s is negative; expected "
                             f"[speed_m_s >= 0, {convention[name]}]")


class DynamicModel:
    """Physics-only 3-DOF model of one vessel (eq. 1-3), batched over vessels.

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str
        A validated vessel or a packaged vessel name / file path.
    true_vessel : bool
        Use the file's ``[true_vessel]`` perturbation (the simulator's "real" ship).

    Notes
    -----
    Inputs (keyword arguments of :meth:`acceleration`, :meth:`step`, :meth:`rollout`), each
    of shape ``(width,)`` (same for every vessel), ``(B, width)`` (held) or, for rollouts,
    ``(B, n_steps, width)`` (one value per output step):

    * ``rpm``: shaft speed of each thruster [rpm], one column per command channel (K
      thrusters in vessel-file order, then R rudders, whose columns are ignored); width
      K alone is accepted too;
    * ``azimuth_rad``: thrust direction of each thruster [rad] (ignored for fixed-axis
      thrusters) and, in the rudder columns, the rudder angle delta [rad] (positive turns
      the ship to starboard); width K + R, or K (rudders then at 0 or from ``rudder_rad``);
    * ``rudder_rad``: rudder angles [rad], width R; when given they replace the rudder
      columns of ``azimuth_rad``;
    * ``wind``: ``[speed_m_s, dir_from_rad]`` true wind (direction it comes FROM), speed >= 0;
    * ``current``: ``[speed_m_s, dir_to_rad]`` (direction it flows TO), NED, speed >= 0;
    * ``tau_ext``: extra body-frame load ``[X_N, Y_N, N_Nm]``;
    * ``accel_ext``: extra acceleration ``[m/s^2, m/s^2, rad/s^2]`` added to nu_dot.
    """

    def __init__(self, vessel, *, true_vessel: bool = False):
        from ..vessel import Vessel, load_vessel

        check_flags(true_vessel=true_vessel)
        self.vessel = vessel if isinstance(vessel, Vessel) else load_vessel(vessel)
        self.true_vessel = bool(true_vessel)
        self.arrays = build_model_arrays(self.vessel, true_vessel=self.true_vessel)

    @property
    def n_channels(self) -> int:
        """Command channels K + R (thrusters, then rudders): the full width of ``rpm`` and ``azimuth_rad``."""
        return len(self.vessel.thrusters) + len(self.vessel.rudders)

    @property
    def n_actuators(self) -> int:
        """Actuators, thrusters and rudders: as :attr:`n_channels` (one command channel each)."""
        return self.n_channels

    @property
    def n_thrusters(self) -> int:
        """Thrusters and propellers K (rudders not included; see :attr:`n_channels`)."""
        return len(self.vessel.thrusters)

    @property
    def n_rudders(self) -> int:
        """Rudders R (each behind one propeller; its angle is the command ``rudder_rad``)."""
        return len(self.vessel.rudders)

    @property
    def mass_matrix(self) -> np.ndarray:
        """M = M_RB + M_A (3x3) [kg, kg m, kg m^2] by row and column DOF (surge, sway, yaw)."""
        return np.linalg.inv(self.arrays.m_inv)

    def _state(self, name, x):
        a = _as_float_array(name, x)
        if a.ndim == 1:
            a = a[None, :]
        if a.ndim != 2 or a.shape[1] != 3:
            raise ValueError(f"{name}: expected shape (3,) or (B, 3), got {np.shape(x)}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name}: contains NaN or inf")
        return np.ascontiguousarray(a)

    def _channels(self, name, value, B, S):
        """A per-channel command as ``(B, S_or_1, K + R)``; width K (thrusters only) is padded with zeros."""
        K, R = len(self.vessel.thrusters), self.n_rudders
        if R > 0 and value is not None and np.ndim(value) >= 1 and np.shape(value)[-1] == K:
            a = _as_input(name, value, B, S, K)
            return np.ascontiguousarray(np.concatenate([a, np.zeros(a.shape[:2] + (R,))], axis=2))
        return _as_input(name, value, B, S, K + R)

    def _inputs(self, B, S, rpm, azimuth_rad, wind, current, tau_ext, accel_ext, rudder_rad=None):
        K, R = len(self.vessel.thrusters), self.n_rudders
        az = self._channels("azimuth_rad", azimuth_rad, B, S)
        if rudder_rad is not None:
            if R == 0:
                raise ValueError(f"rudder_rad: vessel {self.vessel.name!r} has no rudders")
            rud = _as_input("rudder_rad", rudder_rad, B, S, R)
            steps = max(az.shape[1], rud.shape[1])
            az = np.array(np.broadcast_to(az, (B, steps, K + R)))
            az[:, :, K:] = rud
        ins = (self._channels("rpm", rpm, B, S), np.ascontiguousarray(az),
               _as_input("wind", wind, B, S, 2), _as_input("current", current, B, S, 2),
               _as_input("tau_ext", tau_ext, B, S, 3), _as_input("accel_ext", accel_ext, B, S, 3))
        # a rudder angle given among the channels of azimuth_rad is named there, not as rudder_rad
        self._check_commands(ins[0], ins[1], "rudder_rad" if rudder_rad is not None else
                             f"azimuth_rad[..., {K}:] (the rudder angles)")
        _check_flow_speeds(wind=ins[2], current=ins[3])
        return ins

    def _check_commands(self, rpm, angle_rad, rudder_field: str = "rudder_rad"):
        """Refuse commands the model is not meant for (it would return NaN or nonsense):
        non-finite values, ``|rpm|`` above :data:`RPM_LIMIT_FACTOR` times a thruster's
        ``max_rpm`` (a unit error), a rudder angle beyond 90 deg (degrees given as radians),
        named as ``rudder_field`` (the argument that carried the rudder angles)."""
        for name, x in (("rpm", rpm), ("azimuth_rad", angle_rad)):
            if not np.all(np.isfinite(x)):
                raise ValueError(f"{name}: contains NaN or inf")
        K = len(self.vessel.thrusters)
        peak = np.abs(rpm[..., :K]).reshape(-1, K).max(axis=0) if rpm.size and K else np.zeros(K)
        for k in np.flatnonzero(peak > RPM_LIMIT_FACTOR * self.arrays.thr[:K, THR_MAX_RPM]):
            th = self.vessel.thrusters[k]
            raise ValueError(f"rpm: {peak[k]:g} rpm for thruster {th.name!r} is above {RPM_LIMIT_FACTOR:g} x its "
                             f"max_rpm ({th.max_rpm:g}); expected rpm within the vessel file's range")
        if self.n_rudders and angle_rad.size and np.abs(angle_rad[..., K:]).max() > np.pi / 2:
            raise ValueError(f"{rudder_field}: {np.abs(angle_rad[..., K:]).max():g} rad is beyond 90 deg; expected "
                             f"a rudder angle in radians")

    def acceleration(self, eta, nu, *, rpm=None, azimuth_rad=None, wind=None, current=None,
                     tau_ext=None, accel_ext=None, rudder_rad=None, return_parts: bool = False):
        """nu_dot (B, 3) for states ``eta``, ``nu`` (each (3,) or (B, 3)).

        With ``return_parts`` also the loads ``(B, 4, 3)`` in the order of ``TAU_PARTS``
        (hull C and D terms, actuators incl. rudders, wind, external) and the delivered
        thrusts ``(B, K)`` [N] of the K thrusters.
        """
        check_flags(return_parts=return_parts)
        eta, nu = self._states("eta", eta, "nu", nu)
        B = eta.shape[0]
        ins = [np.ascontiguousarray(a[:, 0]) for a in
               self._inputs(B, None, rpm, azimuth_rad, wind, current, tau_ext, accel_ext, rudder_rad)]
        nu_dot = np.empty((B, 3))
        parts = np.empty((B, 4, 3))
        K = len(self.vessel.thrusters)
        thrusts = np.empty((B, max(K, 1)))
        dynamics_batch(eta, nu, *ins, self.arrays, nu_dot, parts, thrusts)
        if not np.all(np.isfinite(nu_dot)):         # as step() refuses a diverged step: never a silent NaN
            raise FloatingPointError("acceleration: not finite for these inputs: velocities, wind or loads beyond "
                                     "the model's valid range")
        if return_parts:
            return nu_dot, parts, thrusts[:, :K]
        return nu_dot

    def acceleration_unchecked(self, eta, nu, rpm, azimuth_rad, wind, current, tau_ext, accel_ext):
        """:meth:`acceleration` for inputs already checked by the caller: every argument a
        C-contiguous float array ``(B, width)`` of the model's widths (commands K + R).

        For inner loops that validated their inputs once at their boundary (the environment
        estimator); returns ``nu_dot (B, 3)`` and the loads ``(B, 4, 3)``.
        """
        B = eta.shape[0]
        nu_dot = np.empty((B, 3))
        parts = np.empty((B, 4, 3))
        thrusts = np.empty((B, max(len(self.vessel.thrusters), 1)))
        dynamics_batch(eta, nu, rpm, azimuth_rad, wind, current, tau_ext, accel_ext, self.arrays, nu_dot, parts,
                       thrusts)
        return nu_dot, parts

    def step_unchecked(self, eta, nu, rpm, azimuth_rad, wind, current, tau_ext, accel_ext, dt_s: float,
                       substeps: int = 1):
        """:meth:`step` for inputs already checked by the caller (as :meth:`acceleration_unchecked`)."""
        from .integrate import step_batch

        B = eta.shape[0]
        eta_next = np.empty((B, 3))
        nu_next = np.empty((B, 3))
        step_batch(eta, nu, rpm, azimuth_rad, wind, current, tau_ext, accel_ext, self.arrays, float(dt_s),
                   int(substeps), eta_next, nu_next)
        return eta_next, nu_next

    def step(self, eta, nu, *, dt_s: float = 1.0, substeps: int = 1, rpm=None, azimuth_rad=None,
             wind=None, current=None, tau_ext=None, accel_ext=None, rudder_rad=None):
        """Advance (B, 3) states by one step of ``dt_s`` with held inputs; returns ``(eta, nu)``.

        ``eta`` and ``nu`` are ``(3,)`` or ``(B, 3)``; one state is broadcast against a batch
        of the other, as in :meth:`acceleration`."""
        check_step(dt_s, substeps)
        eta, nu = self._states("eta", eta, "nu", nu)
        B = eta.shape[0]
        ins = [np.ascontiguousarray(a[:, 0]) for a in
               self._inputs(B, None, rpm, azimuth_rad, wind, current, tau_ext, accel_ext, rudder_rad)]
        eta_next = np.empty((B, 3))
        nu_next = np.empty((B, 3))
        step_batch(eta, nu, *ins, self.arrays, float(dt_s), int(substeps), eta_next, nu_next)
        if not (np.all(np.isfinite(eta_next)) and np.all(np.isfinite(nu_next))):
            raise FloatingPointError(f"step diverged (dt_s {dt_s:g}, substeps {substeps}): inputs beyond the "
                                     f"model's valid range, or a step too long")
        return eta_next, nu_next

    def _states(self, name_a, a, name_b, b):
        """Two (3,) or (B, 3) states checked and broadcast to one batch (refused when both are
        batches of different sizes)."""
        a, b = self._state(name_a, a), self._state(name_b, b)
        if a.shape[0] != b.shape[0] and min(a.shape[0], b.shape[0]) != 1:
            raise ValueError(f"{name_a}, {name_b}: batches of {a.shape[0]} and {b.shape[0]} states; expected "
                             f"the same number, or one state for all")
        B = max(a.shape[0], b.shape[0])
        return (np.ascontiguousarray(np.broadcast_to(a, (B, 3))), np.ascontiguousarray(np.broadcast_to(b, (B, 3))))

    def rollout(self, eta0, nu0, n_steps: int, *, dt_s: float = 1.0, substeps: int = 1, rpm=None,
                azimuth_rad=None, wind=None, current=None, tau_ext=None, accel_ext=None,
                rudder_rad=None) -> RolloutResult:
        """Integrate ``n_steps`` output steps of ``dt_s`` seconds (RK4, ``substeps`` per step).

        Inputs are held at their values (``(width,)`` or ``(B, width)``) or given per step
        (``(B, n_steps, width)``). See the class notes for the inputs.
        """
        check_step(dt_s, substeps)
        check_whole_number("n_steps", n_steps, 1)
        eta0 = self._state("eta0", eta0)
        nu0 = self._state("nu0", nu0)
        if eta0.shape != nu0.shape:
            raise ValueError(f"eta0 and nu0 must have the same shape, got {eta0.shape} and {nu0.shape}")
        B, S = eta0.shape[0], int(n_steps)
        ins = self._inputs(B, S, rpm, azimuth_rad, wind, current, tau_ext, accel_ext, rudder_rad)
        eta = np.empty((B, S + 1, 3))
        nu = np.empty((B, S + 1, 3))
        nu_dot = np.empty((B, S + 1, 3))
        rollout_batch(eta0, nu0, *ins, self.arrays, float(dt_s), S, int(substeps), eta, nu, nu_dot)
        if not (np.all(np.isfinite(eta)) and np.all(np.isfinite(nu))):
            b, j = np.argwhere(~np.isfinite(np.concatenate([eta, nu], axis=2)).any(axis=2))[0]
            raise FloatingPointError(f"rollout diverged at step {j} of batch {b} (dt_s {dt_s:g}, substeps "
                                     f"{substeps}): inputs beyond the model's valid range, or a step too long")
        return RolloutResult(np.arange(S + 1) * float(dt_s), eta, nu, nu_dot)
