"""Planing-craft simulator: surge, heave and pitch of a high-speed craft at sea.

Quasi-static Savitsky (1964) planing forces evaluated at the instantaneous speed, trim
and transom immersion relative to the local sea surface, plus the dynamic terms that
the quasi-static method lacks (added mass and the ``U a33`` transom damping of the
2D+t theory, Faltinsen 2005 ch. 9), engine and propeller thrust, interceptor or trim-tab
forces, a displacement-mode model blended in below planing speed, and head-sea
irregular waves met at the encounter frequency.

Coordinates and signs
---------------------
* ``x`` forward, ``z`` down (body frame origin at the CG); pitch ``theta_rad`` bow-up
  positive; heave ``z_m`` = depth of the CG below the calm-water level (so it is
  negative when the CG is above the water).
* Transom at ``x = -lcg``; keel depth at the transom ``d = z + vcg cos(theta) + lcg sin(theta)``.
* Pitch moment about the CG ``M = z_F F_x - x_F F_z`` (body frame, bow-up positive).
* Head seas: the wave phase at body position ``x`` is ``omega t + k (X_ship + x) + eps``
  (waves travel towards -x), so the encounter frequency is ``omega + k U``.

Forces (body frame unless said otherwise)
-----------------------------------------
* Savitsky planing lift ``Delta = 0.5 rho V^2 b^2 C_Lbeta`` with
  ``C_L0 = tau^1.1 (0.0120 lambda^0.5 + 0.0055 lambda^2.5 / C_v^2)`` and
  ``C_Lbeta = C_L0 - 0.0065 beta C_L0^0.6`` (tau, beta in degrees), applied as a normal
  force ``N = Delta / cos(tau)`` at ``l_p = lambda b (0.75 - 1 / (5.21 C_v^2 / lambda^2 + 2.39))``
  forward of the transom; the mean wetted length-beam ratio follows from the transom
  immersion ``lambda = (2 d / sin(tau) - b tan(beta) / (pi tan(tau))) / (2 b)``.
* Friction ``D_f = 0.5 rho V_m^2 lambda b^2 C_F / cos(beta)`` along the keel at
  ``a = vcg - b tan(beta) / 4`` below the CG, ITTC-1957 ``C_F`` plus ``Delta C_F`` at the
  mean bottom velocity ``V_m``.
* Thrust ``T = n_eng rho n_p^2 D^4 K_T0 (1 - J / J0) (1 - t)`` with
  ``J = V (1 - w) / (n_p D)``: it falls with speed. Engine speed follows its command with a
  first-order lag. The thrust line acts at the sterndrive propellers (below and aft of
  the transom) at ``shaft_angle`` to the keel: the thrust-line moment.
* Interceptor: lift ``C_L 0.5 rho V^2 (span h)`` and drag ``C_D 0.5 rho V^2 (span h)`` per
  blade at the transom (``C_L`` documented and tunable, see the vessel file).
* Trim tabs (Savitsky & Brown 1976): ``Delta L_f = 0.046 (l_f / b) delta sigma 0.5 rho V^2 b^2``
  (delta in degrees, sigma = flap span / beam), centred 0.6 b forward of the flap trailing
  edge, drag ``0.0052 Delta L_f (tau + delta)`` (degrees).
* Displacement mode (below ``blend_end_kn``): buoyancy ``rho g nabla + rho g A_wp (d_cg - T)``,
  pitch restoring ``-rho g nabla GM_L (theta - theta_dyn(V))`` about a dynamic trim that
  rises as ``V^2`` to ``hump_trim`` at the hump speed, and resistance
  ``hump_resistance_ratio m g (V / V_hump)^2``. It is blended with the planing forces by a
  smoothstep in speed between ``blend_start_kn`` and ``blend_end_kn``.
* Dynamic terms: heave/pitch added mass of a wedge ``a33 = rho pi / 2 (b / 2)^2`` per metre
  over ``added_mass_length_m`` from the transom (coupling added mass neglected), and the
  2D+t damping terms: the transom force ``-U a33 v_T`` (``v_T`` = vertical velocity of the
  transom keel point relative to the sea surface) with its moment, and the pitch moment
  ``U (A33 w - S1 q)`` of the sections ahead (``S1`` = first moment of a33 about the CG);
  the lift also sees the flow angle of the vertical velocity at mid wetted length. Without
  these terms the quasi-static Savitsky model porpoises at every speed; with them it is
  stable from 800 to 4000 rpm (checked by a test). Surge added mass 5 % of the mass.
* Waves: long-crested JONSWAP components (:func:`hybridship.sim.environment.make_wave_components`),
  averaged over the wetted length (each component scaled by ``sinc(k L_w / 2)``); the local
  surface is the plane through the mean elevation and slope, so waves change both the
  transom immersion and the relative trim.

Sources
-------
* Savitsky, D. (1964). Hydrodynamic design of planing hulls. Marine Technology 1, 71-95.
* Savitsky, D., Brown, P. W. (1976). Procedures for hydrodynamic evaluation of planing
  hulls in smooth and rough water. Marine Technology 13(4), 381-400.
* Faltinsen, O. M. (2005). Hydrodynamics of High-Speed Marine Vehicles, Cambridge UP, ch. 9.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from ..config import Float, Int, check_number, check_whole_number, config_dataclass, real_array

from hybridship.sim.environment import G_M_S2, MAX_STEEPNESS, make_wave_components, max_hs_m

from .vessel import PlaningCraft

__all__ = [
    "KNOT_M_S",
    "Actuator",
    "SeaConditions",
    "PlaningCraftModel",
    "SteadyState",
    "TrueRecord",
    "savitsky_planing",
    "smoothstep",
]

#: One knot [m/s].
KNOT_M_S = 1852.0 / 3600.0

Actuator = Literal["interceptor", "trim_tab"]


def smoothstep(x: float, lo: float, hi: float) -> float:
    """0 below ``lo``, 1 above ``hi``, C1-smooth cubic in between."""
    t = min(max((x - lo) / (hi - lo), 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def savitsky_planing(speed_m_s: float, tau_rad: float, transom_draft_m: float, beam_m: float,
                     deadrise_rad: float, rho: float, nu: float, delta_cf: float = 0.0004,
                     friction_factor: float = 1.0, flow_angle_rad: float = 0.0):
    """Savitsky (1964) lift, centre of pressure and friction of a prismatic planing hull.

    Parameters
    ----------
    speed_m_s : float
        Forward speed V [m/s] (> 0).
    tau_rad : float
        Trim relative to the water surface [rad]; floored at 0.5 deg.
    transom_draft_m : float
        Immersion of the keel at the transom d [m]; no wetted surface for d <= 0.
    beam_m, deadrise_rad : float
        Chine beam b [m] and deadrise beta [rad].
    rho, nu : float
        Water density [kg/m^3] and kinematic viscosity [m^2/s].
    delta_cf, friction_factor : float
        Correlation allowance added to ITTC-1957 C_F, and a factor on the total C_F.
    flow_angle_rad : float
        Extra angle of attack from the vertical motion of the hull (down positive); it
        adds to the trim in the lift coefficient but not in the wetted-length geometry.

    Returns
    -------
    lift_n, lp_m, friction_n, lam : float
        Lift (vertical load) [N], centre of pressure forward of the transom [m],
        frictional drag along the keel [N] and mean wetted length-beam ratio [-].

    Raises
    ------
    ValueError
        An argument that is not finite (beyond the dry-hull and low-speed cases, which give
        zeros), naming it: it gave NaN loads without a word.
    """
    b = beam_m
    tau = max(tau_rad, math.radians(0.5))
    d = transom_draft_m
    if d <= 0.0 or speed_m_s <= 0.1:
        return 0.0, 0.0, 0.0, 0.0
    given = (speed_m_s, tau_rad, transom_draft_m, beam_m, deadrise_rad, rho, nu, delta_cf, friction_factor,
             flow_angle_rad)
    if not math.isfinite(sum(given)):         # one test on the simulator's path; each only when it fails
        names = ("speed_m_s", "tau_rad", "transom_draft_m", "beam_m", "deadrise_rad", "rho", "nu", "delta_cf",
                 "friction_factor", "flow_angle_rad")
        for name, value in zip(names, given):
            if not math.isfinite(value):
                raise ValueError(f"savitsky_planing: {name}: expected a finite number, got {value}")
    lk = d / math.sin(tau)
    lc = max(lk - b * math.tan(deadrise_rad) / (math.pi * math.tan(tau)), 0.0)
    lam = min((lk + lc) / (2.0 * b), 8.0)
    if lam <= 1e-3:
        return 0.0, 0.0, 0.0, 0.0
    tau_deg = math.degrees(max(tau + flow_angle_rad, math.radians(0.5)))
    beta_deg = math.degrees(deadrise_rad)
    cv = speed_m_s / math.sqrt(G_M_S2 * b)
    t11 = tau_deg ** 1.1
    cl0 = t11 * (0.0120 * math.sqrt(lam) + 0.0055 * lam ** 2.5 / cv ** 2)
    clb = max(cl0 - 0.0065 * beta_deg * cl0 ** 0.6, 0.0)
    q = 0.5 * rho * speed_m_s ** 2
    lift = q * b * b * clb
    lp = lam * b * (0.75 - 1.0 / (5.21 * cv ** 2 / lam ** 2 + 2.39))
    # mean bottom velocity (Savitsky 1964): the dynamic-lift part of the pressure slows the flow
    cl0_dyn = 0.0120 * math.sqrt(lam) * t11
    cl_dyn = max(cl0_dyn - 0.0065 * beta_deg * cl0_dyn ** 0.6, 0.0)
    vm = speed_m_s * math.sqrt(max(1.0 - cl_dyn / (lam * math.cos(tau)), 0.25))
    re = max(vm * lam * b / nu, 1e5)
    cf = (0.075 / (math.log10(re) - 2.0) ** 2 + delta_cf) * friction_factor
    friction = 0.5 * rho * vm * vm * lam * b * b * cf / math.cos(deadrise_rad)
    return lift, lp, friction, lam


#: Largest significant wave height [m] the quasi-static simulator is meant for: the
#: benchmark's sea state 2. Beyond it the boat slams (pitch swings of 10-30 deg, heave
#: accelerations of 1-3 g, speed gained in waves): ``python benchmarks/hsc_sea_validity.py``.
MAX_HS_M = 0.10


@config_dataclass(frozen=True)
class SeaConditions:
    """Head-sea irregular waves (JONSWAP); ``hs_m = 0`` gives calm water.

    Heights above :data:`MAX_HS_M` are refused unless ``beyond_validity`` is set (to study
    where the quasi-static model fails); a sea steeper than :data:`MAX_STEEPNESS` always.
    """

    hs_m: Annotated[Float, Field(ge=0)] = 0.0
    tp_s: Annotated[Float, Field(gt=0)] = 2.0
    gamma: Annotated[Float, Field(ge=1, le=7)] = 3.3
    n_components: Annotated[Int, Field(ge=1)] = 40
    beyond_validity: bool = False

    @model_validator(mode="after")
    def _a_sea_the_model_is_meant_for(self):
        if self.hs_m > max_hs_m(self.tp_s):
            raise ValueError(f"hs_m {self.hs_m:g} m at tp_s {self.tp_s:g} s is steeper than waves can be (at most "
                             f"{max_hs_m(self.tp_s):.2f} m at that period: 2 pi Hs / (g Tp^2) <= {MAX_STEEPNESS:.3f})")
        if self.hs_m > MAX_HS_M and not self.beyond_validity:
            raise ValueError(f"hs_m: {self.hs_m:g} m is above the {MAX_HS_M:g} m the quasi-static planing "
                             f"simulator is meant for (beyond it the boat slams: docs/hsc.md); set "
                             f"beyond_validity=True to study that")
        return self


@dataclass(frozen=True)
class SteadyState:
    """Calm-water equilibrium at constant engine speed and actuator setting."""

    rpm: float
    actuator_frac: float
    speed_m_s: float
    trim_rad: float
    heave_m: float
    thrust_n: float

    @property
    def speed_kn(self) -> float:
        return self.speed_m_s / KNOT_M_S

    @property
    def trim_deg(self) -> float:
        return math.degrees(self.trim_rad)


@dataclass
class TrueRecord:
    """True (noise-free, undelayed) time series at the sample times of a simulation.

    Attributes
    ----------
    time_s, speed_m_s, heave_m, pitch_rad, pitch_rate_rad_s, rpm, rpm_cmd, pwm_pct,
    actuator_frac, heave_acc_m_s2, wave_elevation_m : ndarray (N,)
        ``heave_acc_m_s2`` is the vertical acceleration of the CG, *up* positive, averaged
        over the sample period (as an IMU's anti-alias filter would); ``wave_elevation_m``
        is the surface elevation at the planing area.
    """

    time_s: np.ndarray
    speed_m_s: np.ndarray
    heave_m: np.ndarray
    pitch_rad: np.ndarray
    pitch_rate_rad_s: np.ndarray
    rpm: np.ndarray
    rpm_cmd: np.ndarray
    pwm_pct: np.ndarray
    actuator_frac: np.ndarray
    heave_acc_m_s2: np.ndarray
    wave_elevation_m: np.ndarray


class PlaningCraftModel:
    """Surge-heave-pitch model of one planing craft with one trim actuator.

    Parameters
    ----------
    craft : PlaningCraft
        The vessel (use ``craft.perturbed()`` for the simulator's "true" boat).
    actuator : {"interceptor", "trim_tab"}
        Which trim device the PWM input drives.
    """

    def __init__(self, craft: PlaningCraft, actuator: Actuator = "interceptor"):
        if not isinstance(craft, PlaningCraft):       # an AttributeError on .particulars before
            raise TypeError(f"craft: expected a PlaningCraft (load_planing_craft(...)), got {type(craft).__name__}")
        if actuator not in ("interceptor", "trim_tab"):
            raise ValueError(f"actuator must be 'interceptor' or 'trim_tab', got {actuator!r}")
        self.craft = craft
        self.actuator = actuator
        p, h, dm = craft.particulars, craft.hull, craft.displacement_mode
        self.rho, self.nu = p.rho_water_kg_m3, p.nu_water_m2_s
        self.m = p.displacement_kg
        self.b, self.beta = h.chine_beam_m, h.deadrise_rad
        self.lcg, self.vcg = h.lcg_m, h.vcg_m
        self.I55 = self.m * h.pitch_gyration_radius_m ** 2
        self.a33 = self.rho * math.pi / 2.0 * (self.b / 2.0) ** 2
        xT, L = -self.lcg, h.added_mass_length_m
        self.A33 = self.a33 * L
        self.A55 = self.a33 * ((xT + L) ** 3 - xT ** 3) / 3.0
        self.S1 = self.a33 * ((xT + L) ** 2 - xT ** 2) / 2.0
        self.A11 = 0.05 * self.m
        self.x_wave = xT + 0.5 * L
        self.L_wet = L
        self.u_floor = h.min_damping_speed_m_s
        self.friction_a = self.vcg - self.b * math.tan(self.beta) / 4.0
        # displacement mode
        nabla = self.m / self.rho
        self.C33 = self.rho * G_M_S2 * dm.waterplane_area_m2
        self.C55 = self.rho * G_M_S2 * nabla * dm.long_metacentric_height_m
        self.draft = p.draft_m
        self.v_hump = dm.hump_speed_kn * KNOT_M_S
        self.r_hump = dm.hump_resistance_ratio * self.m * G_M_S2
        self.trim_hump = math.radians(dm.hump_trim_deg)
        self.blend = (dm.blend_start_kn * KNOT_M_S, dm.blend_end_kn * KNOT_M_S)
        # engines and propellers
        e, pr = craft.engines, craft.propellers
        self.n_eng, self.tau_e = e.count, e.time_constant_s
        self.rpm_range = (e.idle_rpm, e.max_rpm)
        self.D, self.gear, self.kt0, self.j0 = pr.diameter_m, pr.gear_ratio, pr.kt0, pr.j0
        self.wake, self.tded = pr.wake_fraction, pr.thrust_deduction
        self.x_prop = -self.lcg - pr.x_aft_of_transom_m
        self.z_prop = self.vcg + pr.z_below_keel_m
        self.eps = math.radians(pr.shaft_angle_deg)
        # actuators
        ic, tt, act = craft.interceptor, craft.trim_tabs, craft.actuation
        self.int_area = ic.count * ic.span_m * ic.max_stroke_m
        self.int_cl, self.int_cd = ic.lift_coefficient, ic.drag_coefficient
        self.tab_chord, self.tab_sigma = tt.chord_m, tt.count * tt.span_m / self.b
        self.tab_max_deg, self.tab_lift_factor = tt.max_deflection_deg, tt.lift_factor
        self.pwm_range = (act.pwm_min_pct, act.pwm_max_pct)
        self.act_rate = 1.0 / (ic.full_stroke_time_s if actuator == "interceptor" else tt.full_travel_time_s)
        self._waves = None

    # ------------------------------------------------------------------ pieces

    def pwm_to_fraction(self, pwm_pct):
        """PWM duty [%] -> commanded stroke/deflection fraction in [0, 1] (linear)."""
        lo, hi = self.pwm_range
        return np.clip((np.asarray(pwm_pct, dtype=float) - lo) / (hi - lo), 0.0, 1.0)

    def thrust_n(self, rpm: float, speed_m_s: float) -> float:
        """Total propeller thrust [N] (net of thrust deduction) at engine speed and forward speed."""
        n_p = max(rpm, 1.0) / 60.0 / self.gear
        J = max(speed_m_s, 0.0) * (1.0 - self.wake) / (n_p * self.D)
        kt = self.kt0 * (1.0 - J / self.j0)
        return self.n_eng * self.rho * n_p * n_p * self.D ** 4 * kt * (1.0 - self.tded)

    def actuator_forces(self, speed_m_s: float, tau_rad: float, frac: float):
        """Lift [N] (up), drag [N] (aft) and lever forward of the CG [m, negative] of the trim device."""
        q = 0.5 * self.rho * speed_m_s * speed_m_s
        if self.actuator == "interceptor":
            area = self.int_area * frac
            return self.int_cl * q * area, self.int_cd * q * area, -self.lcg
        delta_deg = self.tab_max_deg * frac
        lift = 0.046 * (self.tab_chord / self.b) * delta_deg * self.tab_sigma * q * self.b ** 2 * self.tab_lift_factor
        drag = 0.0052 * lift * (math.degrees(max(tau_rad, 0.0)) + delta_deg)
        return lift, drag, -self.lcg - self.tab_chord + 0.6 * self.b

    # ------------------------------------------------------------------ dynamics

    def forces(self, u, z, w, th, q, rpm, frac, zeta=0.0, zeta_dot=0.0, slope=0.0):
        """Horizontal force [N] (forward), vertical force [N] (down, gravity included) and pitch moment [N m].

        ``zeta`` [m, up], ``zeta_dot`` [m/s] and ``slope`` [-] describe the local sea surface
        at the planing area as seen from the moving craft (all 0 in calm water).
        """
        cth, sth = math.cos(th), math.sin(th)
        V = max(u, 0.0)
        tau = th - slope
        zeta_T = zeta + slope * (-self.lcg - self.x_wave)
        d_rel = z + self.vcg * cth + self.lcg * sth + zeta_T
        wb = smoothstep(V, *self.blend)
        # body-frame forces and moment of the planing hull
        fxb = fzb = m = 0.0
        if wb > 0.0:
            # angle of attack seen by the planing surface: the trim relative to the sea plus the
            # flow angle of the vertical velocity (down, relative to the surface) at mid wetted length
            v_mid = w - self.x_wave * cth * q + zeta_dot
            flow = math.atan2(v_mid, max(V, self.u_floor))
            lift, lp, fric, _lam = savitsky_planing(
                V, tau, d_rel, self.b, self.beta, self.rho, self.nu,
                self.craft.hull.correlation_allowance, self.craft.hull.friction_factor, flow)
            N = wb * lift / math.cos(max(tau, math.radians(0.5)))
            fric *= wb
            fzb -= N
            m += N * (lp - self.lcg)
            fxb -= fric
            m -= self.friction_a * fric
        # thrust
        T = self.thrust_n(rpm, V)
        fxb += T * math.cos(self.eps)
        fzb -= T * math.sin(self.eps)
        m += self.z_prop * T * math.cos(self.eps) + self.x_prop * T * math.sin(self.eps)
        # trim device
        la, da, xa = self.actuator_forces(V, tau, frac)
        fzb -= la
        fxb -= da
        m += -xa * (-la) + self.vcg * (-da)
        # transom damping relative to the sea surface (Faltinsen 2005, 2D+t)
        v_T = w + self.lcg * cth * q + zeta_dot
        Ud = max(V, self.u_floor)
        f_damp = -Ud * self.a33 * v_T
        fzb += f_damp
        m += self.lcg * f_damp
        # and the moment of the sections ahead of it: U * integral of a33 (w - x q) dx
        m += Ud * (self.A33 * (w + zeta_dot) - self.S1 * q)
        # to earth axes, then displacement-mode terms (earth axes) and gravity
        fx = fxb * cth + fzb * sth
        fz = -fxb * sth + fzb * cth + self.m * G_M_S2
        if wb < 1.0:
            r = 1.0 - wb
            d_cg = z + self.vcg * cth + zeta
            fz -= r * (self.m * G_M_S2 + self.C33 * (d_cg - self.draft))
            theta_dyn = self.trim_hump * (V / self.v_hump) ** 2
            m -= r * self.C55 * (th - slope - theta_dyn)
            fx -= r * self.r_hump * (V / self.v_hump) ** 2
        return fx, fz, m

    def derivatives(self, y, rpm_cmd, frac, wave=None):
        """Time derivative of ``y = [X_m, u_m_s, z_m, w_m_s, theta_rad, q_rad_s, rpm]``."""
        X, u, z, w, th, q, rpm = y
        zeta = zeta_dot = slope = 0.0
        if wave is not None:
            zeta, zeta_dot, slope = wave(X, u)
        fx, fz, m = self.forces(u, z, w, th, q, rpm, frac, zeta, zeta_dot, slope)
        return (u, fx / (self.m + self.A11), w, fz / (self.m + self.A33), q, m / (self.I55 + self.A55),
                (rpm_cmd - rpm) / self.tau_e)

    # ------------------------------------------------------------------ equilibrium

    def steady_state(self, rpm: float, actuator_frac: float = 0.0, guess=None) -> SteadyState:
        """Calm-water equilibrium at a constant engine speed and actuator setting.

        Solves for the fixed point with :func:`scipy.optimize.root` from ``guess`` (a nearby
        equilibrium, e.g. at a slightly lower rpm); without a guess, or if that fails, first
        marches the equations in time for 150 s so that the motion settles.

        Raises
        ------
        TypeError, ValueError
            Naming ``rpm`` or ``actuator_frac``: not a number, or out of range; a ValueError
            naming ``rpm`` also when the motion diverges and there is no equilibrium (above
            ``max_rpm`` with the device far out).
        """
        from scipy.optimize import root

        hi = 2.0 * self.rpm_range[1]
        for name, x in (("rpm", rpm), ("actuator_frac", actuator_frac)):
            # a text was a TypeError from numpy that named no argument, True a speed of 1 rpm
            if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
                raise TypeError(f"{name}: expected a number, got {x!r}")
        if not (np.isfinite(rpm) and 0 < rpm <= hi):
            # twice max_rpm, as the ship models refuse a unit slip; beyond it the planing
            # equations leave their domain (a math error, not an equilibrium)
            raise ValueError(f"rpm: expected a positive engine speed [rpm] up to twice max_rpm ({hi:g}), got {rpm!r}")
        if not (np.isfinite(actuator_frac) and 0.0 <= actuator_frac <= 1.0):
            raise ValueError(f"actuator_frac: expected a fraction in [0, 1] (device retracted to fully out), "
                             f"got {actuator_frac!r}")

        def resid(v):
            u, z, th = v
            fx, fz, m = self.forces(u, z, 0.0, th, 0.0, rpm, actuator_frac)
            return [fx / (self.m * G_M_S2), fz / (self.m * G_M_S2), m / (self.m * G_M_S2 * self.lcg)]

        def polish(x0):
            try:
                sol = root(resid, x0, method="hybr")
                ok = sol.success and np.max(np.abs(resid(sol.x))) < 1e-8 and sol.x[0] > 0
            except (ValueError, OverflowError):      # a math error of the forces far from any equilibrium
                return None
            return sol.x if ok else None

        x = None
        if guess is not None:           # continuation: a nearby equilibrium is a good start
            x = polish([guess.speed_m_s, guess.heave_m, guess.trim_rad])
            if x is not None and abs(x[0] - guess.speed_m_s) > 3.0:
                x = None                # jumped to another branch: march instead
        if x is None:
            y = [0.0, 1.0, self.draft - self.vcg, 0.0, 0.0, 0.0, float(rpm)]
            if guess is not None:
                y = [0.0, guess.speed_m_s, guess.heave_m, 0.0, guess.trim_rad, 0.0, float(rpm)]
            dt = 0.02
            try:
                for _ in range(int(150.0 / dt)):
                    y = _rk4(self.derivatives, y, dt, rpm, actuator_frac)
            except (ValueError, OverflowError):      # math domain error or overflow of a diverging motion
                y = [math.nan] * 7
            x = polish([y[1], y[2], y[4]]) if np.all(np.isfinite(y)) else None
            if x is None:
                x = (y[1], y[2], y[4])
        if not np.all(np.isfinite(x)):
            # a NaN equilibrium was returned, or a math error raised, without a word
            raise ValueError(f"rpm: no calm-water equilibrium at {rpm:g} rpm with actuator_frac {actuator_frac:g} "
                             f"(the motion diverges); expected a lower engine speed or actuator setting")
        u, z, th = x
        return SteadyState(float(rpm), float(actuator_frac), float(u), float(th), float(z),
                           float(self.thrust_n(rpm, u)))

    def steady_curve(self, rpms, actuator_frac: float = 0.0) -> list[SteadyState]:
        """Equilibria along increasing engine speeds (each starts from the previous one).

        Raises
        ------
        TypeError, ValueError
            Naming ``rpms`` (not a 1-D sequence of numbers), or as :meth:`steady_state`.
        """
        rpms = real_array("rpms", rpms)          # text such as "3000" is refused, as steady_state does
        if rpms.ndim != 1:
            raise ValueError(f"rpms: expected a 1-D sequence of engine speeds [rpm], got shape {rpms.shape}")
        out, guess = [], None
        for r in rpms:
            guess = self.steady_state(float(r), actuator_frac, guess)
            out.append(guess)
        return out

    # ------------------------------------------------------------------ waves

    def make_wave_function(self, sea: SeaConditions, rng):
        """Closure ``(X_m, u_m_s) -> (zeta, zeta_dot, slope)`` at the planing area, for time ``self._t``."""
        if sea.hs_m <= 0.0:
            return None
        field = make_wave_components(sea.hs_m, sea.tp_s, 0.0, rng, n_components=sea.n_components,
                                     gamma=sea.gamma, omega_range_factor=(0.6, 3.0))
        om = np.asarray(field.omega_rad_s, float)
        k = om ** 2 / G_M_S2
        # average over the wetted length: short waves hardly move a 4 m planing surface
        amp = np.asarray(field.amplitude_m, float) * np.sinc(k * self.L_wet / (2.0 * np.pi))
        eps = np.asarray(field.phase_rad, float)
        xw = self.x_wave
        model = self

        def wave(X, u):
            ph = om * model._t + k * (X + xw) + eps
            s, c = np.sin(ph), np.cos(ph)
            return float(amp @ c), float(-(amp * (om + k * u)) @ s), float(-(amp * k) @ s)

        return wave

    # ------------------------------------------------------------------ simulation

    def simulate(self, rpm_cmd, pwm_pct, *, sample_period_s: float = 0.1, substeps: int = 5,
                 sea: SeaConditions = SeaConditions(), rng=0, settle_s: float = 0.0) -> TrueRecord:
        """Simulate a record with one command sample per output sample.

        Parameters
        ----------
        rpm_cmd, pwm_pct : array_like (N,)
            Engine-speed command [rpm] and trim-device PWM duty [%] held over each sample.
        sample_period_s : float
            Output sampling period [s].
        substeps : int
            RK4 steps per sample.
        sea : SeaConditions or mapping
            The waves; a mapping is read as :class:`SeaConditions` fields.
        rng : numpy.random.Generator or int
            Random source of the wave phases, or its seed (a whole number >= 0).
        settle_s : float
            Time at the first commands before the record starts (its samples are dropped),
            so that the record starts from a settled motion.

        Returns
        -------
        TrueRecord

        Raises
        ------
        TypeError, ValueError
            Naming the argument at fault; a ValueError naming ``sea`` when the motion diverges
            in waves beyond the simulator's validity (``beyond_validity``), ``sample_period_s``
            when it diverges in calm water (too long a step).
        """
        # text such as "3000" is refused (numpy read it as a number)
        rpm_cmd, pwm_pct = real_array("rpm_cmd", rpm_cmd), real_array("pwm_pct", pwm_pct)
        if rpm_cmd.shape != pwm_pct.shape or rpm_cmd.ndim != 1 or rpm_cmd.size == 0:
            raise ValueError("rpm_cmd and pwm_pct must be non-empty 1-D arrays of the same length")
        for name, x in (("rpm_cmd", rpm_cmd), ("pwm_pct", pwm_pct)):
            if not np.all(np.isfinite(x)):
                raise ValueError(f"{name}: NaN or inf at sample {int(np.argmax(~np.isfinite(x)))}; expected finite values")
        lo, hi = self.rpm_range
        for name, x, a, b, unit in (("rpm_cmd", rpm_cmd, lo, hi, "rpm (the engine's idle_rpm to max_rpm)"),
                                    ("pwm_pct", pwm_pct, 0.0, 100.0, "% duty")):
            bad = (x < a) | (x > b)
            if bad.any():
                k = int(np.argmax(bad))
                raise ValueError(f"{name}: {x[k]:g} at sample {k} ({int(bad.sum())} sample(s) outside); expected "
                                 f"{a:g} to {b:g} {unit}")
        # a text or None was a TypeError from numpy that named no argument
        sample_period_s = check_number("sample_period_s", sample_period_s, lo=0.0, lo_open=True)
        if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
            raise ValueError(f"substeps: expected an integer >= 1, got {substeps!r}")
        settle_s = check_number("settle_s", settle_s, lo=0.0)
        if isinstance(sea, Mapping):
            sea = SeaConditions(**sea)
        elif not isinstance(sea, SeaConditions):
            raise TypeError(f"sea: expected SeaConditions or a mapping of its fields, got {type(sea).__name__}")
        if not isinstance(rng, np.random.Generator):
            # a seed of True, -1, "a" or None (a sea drawn afresh each call) is refused by name
            rng = np.random.default_rng(check_whole_number("rng", rng, 0))
        wave = self.make_wave_function(sea, rng)
        n_settle = int(round(settle_s / sample_period_s))
        rc = np.concatenate([np.full(n_settle, rpm_cmd[0]), rpm_cmd])
        pw = np.concatenate([np.full(n_settle, pwm_pct[0]), pwm_pct])
        frac_cmd = self.pwm_to_fraction(pw)
        ss = self.steady_state(rc[0], float(frac_cmd[0]))
        y = [0.0, ss.speed_m_s, ss.heave_m, 0.0, ss.trim_rad, 0.0, float(rc[0])]
        frac = float(frac_cmd[0])
        dt = sample_period_s / substeps
        dmax = self.act_rate * dt
        N = rc.size
        out = np.zeros((N, 9))
        self._t = 0.0
        for i in range(N):
            acc = 0.0
            try:
                for _ in range(substeps):
                    frac += min(max(frac_cmd[i] - frac, -dmax), dmax)
                    w0 = y[3]
                    y = _rk4(self.derivatives, y, dt, rc[i], frac, wave, self)
                    acc += -(y[3] - w0) / dt       # up positive
            except (ValueError, OverflowError):      # math domain error or overflow of a diverging motion
                y = [math.nan] * 7
            if not np.all(np.isfinite(y)):      # a record of NaN came out without a word
                where = (f"the motion diverged at {self._t:.1f} s of simulated time (sample {i - n_settle}, "
                         f"Runge-Kutta step {dt:g} s)")
                if wave is None:            # in calm water only too long a step does that
                    raise ValueError(f"sample_period_s: {where}; expected a shorter step (or more substeps)")
                raise ValueError(f"sea: {where} in waves of hs_m {sea.hs_m:g} m, tp_s {sea.tp_s:g} s; the "
                                 f"quasi-static planing simulator is meant for hs_m up to {MAX_HS_M:g} m (docs/hsc.md)")
            zeta = wave(y[0], y[1])[0] if wave is not None else 0.0
            out[i] = (y[1], y[2], y[4], y[5], y[6], frac, acc / substeps, zeta, self._t)
        out = out[n_settle:]
        t = np.arange(out.shape[0]) * sample_period_s
        return TrueRecord(time_s=t, speed_m_s=out[:, 0], heave_m=out[:, 1], pitch_rad=out[:, 2],
                          pitch_rate_rad_s=out[:, 3], rpm=out[:, 4], rpm_cmd=rc[n_settle:],
                          pwm_pct=pw[n_settle:], actuator_frac=out[:, 5], heave_acc_m_s2=out[:, 6],
                          wave_elevation_m=out[:, 7])


def _rk4(f, y, dt, rpm_cmd, frac, wave=None, clock=None):
    """One classical Runge-Kutta step of ``f(y, rpm_cmd, frac, wave)`` (advances ``clock._t``)."""
    t0 = clock._t if clock is not None else 0.0
    k1 = f(y, rpm_cmd, frac, wave)
    y2 = [a + 0.5 * dt * b for a, b in zip(y, k1)]
    if clock is not None:
        clock._t = t0 + 0.5 * dt
    k2 = f(y2, rpm_cmd, frac, wave)
    y3 = [a + 0.5 * dt * b for a, b in zip(y, k2)]
    k3 = f(y3, rpm_cmd, frac, wave)
    y4 = [a + dt * b for a, b in zip(y, k3)]
    if clock is not None:
        clock._t = t0 + dt
    k4 = f(y4, rpm_cmd, frac, wave)
    return [a + dt / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4) for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)]
