"""Vessel files: schema, loading and validation.

A vessel file (TOML) describes one ship for the 3-DOF model: main particulars, rigid
body, added mass, damping, thrusters, wind loads and, optionally, the perturbation that
turns it into the simulator's "true" vessel. Actuators are thrusters and propellers
(``[[thrusters]]``, four-quadrant propeller model) and rudders (``[[rudders]]``, MMG
standard method, each paired with the propeller whose slipstream reaches it).
Hydrodynamic coefficients are either given explicitly or derived by a named method (e.g.
``method = "clarke1983"``), so a reader can see where every number comes from. See
``docs/reference/vessel-file.md`` for every field.

Errors raise :class:`VesselFileError` naming the field, e.g.
``gunnerus.toml: thrusters[1].diameter_m: must be > 0 (got -1.9)``.
"""

from __future__ import annotations

import os
import tomllib
from importlib import resources
from pathlib import Path
from typing import Literal, Optional

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from hybridship.config import Float, Int, format_validation_error

#: Version of the vessel-file format this code reads.
VESSEL_FORMAT_VERSION = 1


class VesselFileError(ValueError):
    """A vessel file is missing, unreadable or invalid; the message names the field."""


class _Strict(BaseModel):
    # numbers are Float / Int (hybridship.config): pydantic's own would read TOML's
    # ``x_m = true`` as 1.0 m and ``mass_kg = "600000"`` as a number
    # inf and nan are refused at the file: they would surface only as a diverged simulation
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Particulars(_Strict):
    """Main particulars [m, -, kg/m^3]."""

    L_oa_m: Float = Field(gt=0, description="length overall [m]")
    L_pp_m: Float = Field(gt=0, description="length between perpendiculars [m]")
    B_m: Float = Field(gt=0, description="moulded breadth [m]")
    T_m: Float = Field(gt=0, description="draught [m]")
    C_B: Float = Field(gt=0, le=1, description="block coefficient [-]")
    rho_water_kg_m3: Float = Field(1025.0, gt=900, lt=1100, description="water density [kg/m^3]")

    @model_validator(mode="after")
    def _overall_not_shorter(self):
        # L_oa sets the wind moment (and the hull's extent for the actuator positions): the two
        # lengths swapped passed silently
        if self.L_oa_m < self.L_pp_m:
            raise ValueError(f"L_oa_m: {self.L_oa_m:g} m is shorter than L_pp_m = {self.L_pp_m:g} m; the length "
                             f"overall includes the overhangs beyond the perpendiculars (L_oa_m >= L_pp_m)")
        return self


class RigidBody(_Strict):
    """Mass and yaw inertia about the body origin (the CG when ``x_g_m = 0``)."""

    mass_kg: Float = Field(gt=0)
    I_z_kg_m2: Optional[Float] = Field(None, gt=0, description="yaw inertia [kg m^2]")
    r_z_m: Optional[Float] = Field(None, gt=0, description="yaw radius of gyration [m] about the centre of "
                                   "gravity (I_z = m (r_z^2 + x_g^2) about the body origin)")
    x_g_m: Float = Field(0.0, description="CG forward of the body origin [m]")

    @model_validator(mode="after")
    def _one_inertia(self):
        if (self.I_z_kg_m2 is None) == (self.r_z_m is None):
            raise ValueError("give exactly one of I_z_kg_m2 and r_z_m")
        return self

    @property
    def I_z(self) -> float:
        """Yaw inertia about the origin [kg m^2]."""
        if self.I_z_kg_m2 is not None:
            return self.I_z_kg_m2
        return self.mass_kg * (self.r_z_m**2 + self.x_g_m**2)


class AddedMass(_Strict):
    """Added mass: ``method = "clarke1983"`` (sway/yaw, Soding in surge) or ``"explicit"``.

    Explicit values are the (normally negative) derivatives X_udot [kg], Y_vdot [kg],
    Y_rdot [kg m], N_vdot [kg m], N_rdot [kg m^2].
    """

    method: Literal["clarke1983", "explicit"]
    X_udot_kg: Optional[Float] = None
    Y_vdot_kg: Optional[Float] = None
    Y_rdot_kg_m: Optional[Float] = None
    N_vdot_kg_m: Optional[Float] = None
    N_rdot_kg_m2: Optional[Float] = None

    @model_validator(mode="after")
    def _explicit_complete(self):
        names = ("X_udot_kg", "Y_vdot_kg", "Y_rdot_kg_m", "N_vdot_kg_m", "N_rdot_kg_m2")
        if self.method == "explicit":
            missing = [k for k in names if getattr(self, k) is None]
            if missing:
                raise ValueError(f"method 'explicit' needs {', '.join(missing)}")
        else:       # they would be ignored
            given = [k for k in names if getattr(self, k) is not None]
            if given:
                raise ValueError(f"{', '.join(given)}: given with method 'clarke1983', which derives them "
                                 f"(give method 'explicit' to use them)")
        return self


class LinearDamping(_Strict):
    """Linear damping D: ``"time_constants"`` (D_ii = M_ii / T_i) or ``"explicit"`` (3x3 matrix, SI)."""

    method: Literal["time_constants", "explicit"]
    T_surge_s: Optional[Float] = Field(None, gt=0)
    T_sway_s: Optional[Float] = Field(None, gt=0)
    T_yaw_s: Optional[Float] = Field(None, gt=0)
    D: Optional[list[list[Float]]] = None

    @field_validator("D", mode="before")
    @classmethod
    def _three_by_three(cls, v):
        # checked before the numbers: a ragged or text D reached numpy ("setting an array
        # element with a sequence ...") or pydantic's "Input should be a valid list"
        rows = (list, tuple)
        if v is not None and not (isinstance(v, rows) and len(v) == 3
                                  and all(isinstance(r, rows) and len(r) == 3 for r in v)):
            raise ValueError(f"expected a 3x3 matrix (three rows of three numbers), got {v!r}")
        return v

    @model_validator(mode="after")
    def _complete(self):
        times = ("T_surge_s", "T_sway_s", "T_yaw_s")
        if self.method == "time_constants":
            if None in (self.T_surge_s, self.T_sway_s, self.T_yaw_s):
                raise ValueError("method 'time_constants' needs T_surge_s, T_sway_s and T_yaw_s")
            if self.D is not None:      # it would be ignored
                raise ValueError("D: given with method 'time_constants', which derives it (D_ii = M_ii / T_i); "
                                 "give method 'explicit' to use it")
        else:
            given = [k for k in times if getattr(self, k) is not None]
            if given:                   # they would be ignored
                raise ValueError(f"{', '.join(given)}: given with method 'explicit', which does not use "
                                 f"{'them' if len(given) > 1 else 'it'} (D is the damping)")
            if self.D is None or np.shape(self.D) != (3, 3):
                raise ValueError("method 'explicit' needs D as a 3x3 matrix")
            # Fossen (2021, sec. 6.4): damping is dissipative, nu^T D nu >= 0 for every nu; a
            # symmetric part with a negative eigenvalue feeds energy in (a sign typo: the
            # derivatives X_u < 0 go in as D = -X_u > 0)
            eig = np.linalg.eigvalsh(0.5 * (np.asarray(self.D) + np.asarray(self.D).T))
            if eig.min() < -1e-12 * max(np.abs(eig).max(), 1.0):
                raise ValueError(f"D: not dissipative (its symmetric part has eigenvalues "
                                 f"{np.array2string(eig, precision=3)}); D holds positive damping, "
                                 f"D = -[[X_u, X_v, X_r], ...] (Fossen 2021, sec. 6.4)")
        return self


class MMGLinearDerivatives(_Strict):
    """Linear hull derivatives of the MMG standard method (Yasukawa & Yoshimura 2015).

    Non-dimensional on the MMG basis: ``Y_H = (rho/2) L d U^2 (Y'_v v' + Y'_r r')`` and
    ``N_H = (rho/2) L^2 d U^2 (N'_v v' + N'_r r')`` with ``v' = v/U``, ``r' = r L/U``, L the
    length between perpendiculars and d the draught of ``[particulars]``. MMG writes the
    added-mass Coriolis force ``(m + m_x) u r`` on the left-hand side and has no Munk
    moment there, so its N'_v includes the Munk moment (see
    :func:`hybridship.physics.hull.mmg_lift`).
    """

    Y_v: Float
    Y_r: Float
    N_v: Float
    N_r: Float


class NonlinearDamping(_Strict):
    """Nonlinear damping D_n(nu_r).

    ``"crossflow"``: ITTC-1957 surge resistance ``d_uu = 0.5 rho S ((1+k) C_F + C_R)`` and
    Hoerner cross-flow drag by strip theory in sway and yaw. ``"quadratic"``: explicit
    positive ``d_uu`` [kg/m], ``d_vv`` [kg/m], ``d_rr`` [kg m^2] (force ``-d |x| x``).
    ``"none"``: no nonlinear damping. With ``surge_resistance = "explicit"`` the cross-flow
    method takes the surge resistance from ``d_uu`` alone (no ITTC line, no wetted surface).

    ``lift = "clarke1983"`` adds the manoeuvring (lift) forces that grow with forward speed:
    Clarke's linear derivatives Y_v, Y_r, N_v, N_r divided by U, less the parts that
    C_A(nu_r) already represents, times |u_r| (see :func:`hybridship.physics.hull.clarke1983_lift`).
    ``lift = "mmg"`` takes the same four derivatives from the ``[damping.nonlinear.mmg]``
    table (MMG standard-method normalisation, :class:`MMGLinearDerivatives`).

    ``lift_speed`` says which speed the lift terms grow with. ``"abs"`` (default): |u_r|, so
    the sway damping stays dissipative astern and the hull's lift moment keeps its sign
    while the Munk moment of C_A reverses (a hull going astern is the less stable one).
    ``"signed"``: u_r, the form of Abkowitz-type polynomial models identified ahead
    (``N_uv u v``, as in Hassani et al. 2015 for RV Gunnerus), in which every lift term
    reverses astern. The two agree for u_r >= 0.
    """

    method: Literal["crossflow", "quadratic", "none"]
    wetted_surface_m2: Optional[Float] = Field(None, gt=0)
    form_factor_k: Float = Field(0.0, ge=0, le=1)
    C_R: Float = Field(0.0, ge=0, le=0.05, description="residuary resistance coefficient [-]")
    speed_ref_m_s: Float = Field(5.0, gt=0, description="speed at which C_F is frozen [m/s]")
    cd_2d: Optional[Float] = Field(None, gt=0, description="2-D cross-flow drag coefficient; default Hoerner(B, T)")
    strips: Int = Field(20, ge=2, le=200)
    strips_x_aft_m: Optional[Float] = Field(
        None, description="x of the strips' aft end (the AP) from the body origin [m]; default -L_pp/2, the "
                          "hull centred on the origin")
    d_uu: Float = Field(0.0, ge=0)
    d_vv: Float = Field(0.0, ge=0)
    d_rr: Float = Field(0.0, ge=0)
    lift: Literal["clarke1983", "mmg", "none"] = Field(
        "none", description="speed-proportional sway/yaw terms |u_r| [v_r, r] (Clarke et al. 1983 or MMG)")
    lift_speed: Literal["abs", "signed"] = Field(
        "abs", description="speed the lift terms grow with: |u_r| (dissipative astern) or u_r (Abkowitz form)")
    surge_resistance: Literal["ittc1957", "explicit"] = Field(
        "ittc1957", description="crossflow method: surge resistance from the ITTC line or from d_uu alone")
    mmg: Optional[MMGLinearDerivatives] = None

    @model_validator(mode="after")
    def _complete(self):
        if (self.method == "crossflow" and self.surge_resistance == "ittc1957"
                and self.wetted_surface_m2 is None):
            raise ValueError("method 'crossflow' needs wetted_surface_m2 (or surge_resistance = 'explicit')")
        if self.lift == "mmg" and self.mmg is None:
            raise ValueError("lift 'mmg' needs a [damping.nonlinear.mmg] table (Y_v, Y_r, N_v, N_r)")
        if self.lift != "mmg" and self.mmg is not None:     # it would be ignored
            raise ValueError(f"[damping.nonlinear.mmg]: given with lift {self.lift!r}, which does not use it "
                             f"(give lift 'mmg' to use it)")
        if self.lift == "none" and self.lift_speed != "abs":    # it would be ignored
            raise ValueError(f"lift_speed: {self.lift_speed!r} given with lift 'none', which has no lift terms to "
                             f"grow with the speed (give lift 'clarke1983' or 'mmg' to use it)")
        given = [k for k in ("d_uu", "d_vv", "d_rr") if getattr(self, k) != 0.0]
        if self.method == "none" and given:       # they would be ignored
            raise ValueError(f"{', '.join(given)}: given with method 'none', which has no nonlinear damping "
                             f"(give method 'quadratic' to use them)")
        # the ITTC line and the strips are the cross-flow method's; they would be ignored
        ittc = ["wetted_surface_m2", "form_factor_k", "C_R", "speed_ref_m_s"]
        if self.method != "crossflow":
            unused, by = ittc + ["cd_2d", "strips"], f"method {self.method!r}"
            why = "the ITTC-1957 surge resistance and the strips of method 'crossflow'"
        else:
            unused, by = (ittc if self.surge_resistance == "explicit" else []), "surge_resistance 'explicit'"
            why = "the surge resistance is d_uu"
        given = [k for k in unused if getattr(self, k) != type(self).model_fields[k].default]
        if given:
            raise ValueError(f"{', '.join(given)}: given with {by}, which does not use "
                             f"{'them' if len(given) > 1 else 'it'} ({why})")
        return self


class Damping(_Strict):
    linear: LinearDamping
    nonlinear: NonlinearDamping


class Thruster(_Strict):
    """One thruster or propeller. Sign conventions: see :mod:`hybridship.physics.thrusters`."""

    name: str = Field(pattern=r"^[a-z][a-z0-9_]*$")
    type: Literal["tunnel", "azimuth", "fixed"]
    x_m: Float
    y_m: Float = 0.0
    diameter_m: Float = Field(gt=0)
    max_rpm: Float = Field(gt=0)
    angle_deg: Optional[Float] = Field(None, description="fixed thrust direction for type 'fixed' [deg]")
    wake_fraction: Float = Field(0.0, ge=0, lt=1)
    thrust_deduction: Float = Field(0.0, ge=0, lt=1)
    propeller_series: str = "B4-70"
    pitch_ratio: Float = Field(1.0, gt=0)
    max_azimuth_rate_deg_s: Optional[Float] = Field(None, gt=0)

    @model_validator(mode="after")
    def _angle(self):
        if self.type == "fixed" and self.angle_deg is None:
            raise ValueError("type 'fixed' needs angle_deg")
        if self.type != "fixed" and self.angle_deg is not None:     # it would be ignored
            direction = ("the body y axis (positive rpm pushes to starboard)" if self.type == "tunnel"
                         else "its logged azimuth")
            raise ValueError(f"angle_deg: a {self.type} thruster's direction is {direction}; a thruster fixed "
                             f"at another angle is type 'fixed' with angle_deg")
        if self.type != "azimuth" and self.max_azimuth_rate_deg_s is not None:     # it would be ignored
            raise ValueError(f"max_azimuth_rate_deg_s: a {self.type} thruster does not turn; the slew rate is "
                             f"for type 'azimuth'")
        return self

    @model_validator(mode="after")
    def _tabulated_propeller(self):
        from .physics.propeller import available_propellers   # the packaged four-quadrant table

        avail = available_propellers()
        if not any(s == self.propeller_series and abs(p - self.pitch_ratio) < 1e-6 for s, p in avail):
            raise ValueError(f"propeller_series/pitch_ratio: no four-quadrant table for {self.propeller_series!r} "
                             f"at P/D {self.pitch_ratio:g}; available: "
                             + ", ".join(f"{s} P/D {p:g}" for s, p in avail))
        return self

    @property
    def fixed_angle_rad(self) -> float:
        """Thrust direction of a non-rotatable thruster [rad] (tunnel: +pi/2, to starboard)."""
        if self.type == "tunnel":
            return float(np.pi / 2)
        if self.type == "fixed":
            return float(np.radians(self.angle_deg))
        return 0.0


class Rudder(_Strict):
    """A rudder (MMG standard method, Yasukawa & Yoshimura 2015; see :mod:`hybridship.physics.rudder`).

    Its command is the rudder angle delta [rad], carried in the vessel's per-actuator angle
    array (log column ``<name>_azimuth_deg``): positive delta deflects the trailing edge to
    starboard, which turns the ship to starboard (the MMG convention). Positions are from
    the body origin (x forward, y starboard) [m]. The rudder sits in the slipstream of the
    paired ``propeller`` (a ``fixed`` thruster pointing forward), or in the plain wake
    when ``propeller`` is omitted.

    Attributes (MMG symbol in brackets)
    ----------
    area_m2 : movable rudder area [A_R].
    span_m : rudder span [H_R]; sets eta = min(D_P / H_R, 1) and the aspect ratio H_R^2 / A_R.
    lift_gradient : normal-force gradient [f_alpha, 1/rad]; default Fujii's
        ``6.13 Lambda / (Lambda + 2.25)`` from the aspect ratio Lambda.
    wake_ratio : (1 - w_R) / (1 - w_P) [epsilon]; for a rudder without a propeller, 1 - w_R.
    slipstream_factor : propeller slipstream amplification at the rudder [kappa].
    flow_straightening_neg, flow_straightening_pos : [gamma_R] for beta_R < 0 and > 0.
    l_R_m : effective longitudinal position in the flow-straightening angle [l_R = l'_R L].
    steering_resistance_deduction : [t_R].
    hull_force_factor : extra hull lateral force per unit rudder force [a_H].
    x_H_m : position of that extra hull force [x_H = x'_H L].
    """

    name: str = Field(pattern=r"^[a-z][a-z0-9_]*$")
    propeller: Optional[str] = Field(None, description="name of the fixed thruster ahead of the rudder")
    x_m: Float = Field(description="rudder position x_R [m] from the body origin (negative aft)")
    y_m: Float = 0.0
    area_m2: Float = Field(gt=0)
    span_m: Float = Field(gt=0)
    lift_gradient: Optional[Float] = Field(None, gt=0, le=2 * np.pi)
    wake_ratio: Float = Field(1.0, gt=0, le=3)
    slipstream_factor: Float = Field(0.5, ge=0, le=2)
    flow_straightening_neg: Float = Field(0.5, ge=0, le=2)
    flow_straightening_pos: Float = Field(0.5, ge=0, le=2)
    l_R_m: Optional[Float] = Field(None, description="default: x_m")
    steering_resistance_deduction: Float = Field(0.0, ge=0, lt=1)
    hull_force_factor: Float = Field(0.0, ge=0, le=2)
    x_H_m: Optional[Float] = Field(None, description="default: x_m")
    max_angle_deg: Float = Field(35.0, gt=0, le=90, description="mechanical limit [deg]: the forecasts' input "
                                 "check clips (or refuses) a rudder command beyond it; synthetic trials draw "
                                 "within it")

    @model_validator(mode="after")
    def _slipstream_needs_a_propeller(self):
        # without a propeller eta = 0: the slipstream factor would be ignored
        if self.propeller is None and self.slipstream_factor != type(self).model_fields["slipstream_factor"].default:
            raise ValueError(f"slipstream_factor: {self.slipstream_factor:g} given for a rudder without a propeller, "
                             f"which sees no slipstream (give propeller, the fixed thruster ahead of it, to use it)")
        return self

    @property
    def aspect_ratio(self) -> float:
        """Geometric aspect ratio Lambda = H_R^2 / A_R [-]."""
        return self.span_m**2 / self.area_m2

    @property
    def f_alpha(self) -> float:
        """Normal-force gradient [1/rad]: the given one, else Fujii's formula."""
        if self.lift_gradient is not None:
            return self.lift_gradient
        lam = self.aspect_ratio
        return 6.13 * lam / (lam + 2.25)


class WindTable(_Strict):
    """Tabulated wind coefficients; 0..180 deg means a port/starboard symmetric vessel."""

    angle_deg: list[Float]
    C_X: list[Float]
    C_Y: list[Float]
    C_N: list[Float]

    @model_validator(mode="after")
    def _same_angles(self):
        n = len(self.angle_deg)
        if n < 2 or np.any(np.diff(self.angle_deg) <= 0):
            raise ValueError(f"angle_deg: need at least two strictly increasing angles [deg], got {self.angle_deg}")
        for name in ("C_X", "C_Y", "C_N"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"{name}: {len(getattr(self, name))} coefficients for the {n} angles of angle_deg")
        # the span and symmetry rules the wind model applies, when the file is read, not at
        # the first simulation (a table in radians, 0..3.14, is found here)
        from hybridship.physics.wind import _validate_table

        try:
            _validate_table(self.angle_deg, self.C_X, self.C_Y, self.C_N, name="table")
        except ValueError as exc:
            raise ValueError(str(exc).removeprefix("table.")) from None
        return self


class BlendermannParams(_Strict):
    vessel_type: str
    s_L_m: Float = Field(description="centroid of A_L forward of midships [m]")

    @field_validator("vessel_type")
    @classmethod
    def _known_type(cls, v):
        # when the file is read, not at the first model built from it (a message without the file)
        from hybridship.physics.wind import _blendermann_params

        try:
            _blendermann_params(v)
        except ValueError as exc:
            raise ValueError(str(exc).removeprefix("vessel_type: ")) from None
        return v


class IsherwoodParams(_Strict):
    A_SS_m2: Float = Field(ge=0)
    S_m: Float = Field(gt=0)
    C_m: Float = Field(gt=0)
    M: Int = Field(ge=0)


class Wind(_Strict):
    """Wind loads (Skulstad et al. eq. 3)."""

    method: Literal["table", "isherwood", "blendermann", "none"]
    A_F_m2: Float = Field(0.0, ge=0, description="frontal projected area [m^2]")
    A_L_m2: Float = Field(0.0, ge=0, description="lateral projected area [m^2]")
    L_oa_m: Optional[Float] = Field(None, gt=0, description="default: particulars.L_oa_m")
    rho_air_kg_m3: Float = Field(1.225, gt=0.9, lt=1.5)
    table: Optional[WindTable] = None
    blendermann: Optional[BlendermannParams] = None
    isherwood: Optional[IsherwoodParams] = None

    @model_validator(mode="after")
    def _complete(self):
        if self.method != "none" and not (self.A_F_m2 > 0 and self.A_L_m2 > 0):
            raise ValueError(f"method {self.method!r} needs A_F_m2 > 0 and A_L_m2 > 0")
        if self.method in ("table", "blendermann", "isherwood") and getattr(self, self.method) is None:
            raise ValueError(f"method {self.method!r} needs a [wind.{self.method}] section")
        unused = [f"[wind.{k}]" for k in ("table", "blendermann", "isherwood")
                  if k != self.method and getattr(self, k) is not None]
        if unused:      # it would be ignored
            raise ValueError(f"{', '.join(unused)}: given with method {self.method!r}, which does not use "
                             f"{'them' if len(unused) > 1 else 'it'}")
        return self


class TrueVesselPerturbation(_Strict):
    """How the simulator's "true" vessel differs from the model (scale factors per DOF)."""

    added_mass_scale: tuple[Float, Float, Float] = (1.0, 1.0, 1.0)
    linear_damping_scale: tuple[Float, Float, Float] = (1.0, 1.0, 1.0)
    nonlinear_damping_scale: tuple[Float, Float, Float] = (1.0, 1.0, 1.0)
    wind_coefficient_scale: tuple[Float, Float, Float] = (1.0, 1.0, 1.0)
    thrust_scale: Float = 1.0

    @model_validator(mode="after")
    def _positive(self):
        for k in ("added_mass_scale", "linear_damping_scale", "nonlinear_damping_scale",
                  "wind_coefficient_scale"):
            if any(not (0.1 <= s <= 10.0) for s in getattr(self, k)):
                raise ValueError(f"{k}: every factor must lie in [0.1, 10], got {getattr(self, k)}")
        if not 0.1 <= self.thrust_scale <= 10.0:
            raise ValueError(f"thrust_scale must lie in [0.1, 10], got {self.thrust_scale}")
        return self


class Vessel(_Strict):
    """A validated vessel description (see module docstring)."""

    format_version: Int
    name: str = Field(description="shown in messages, tables and model files")
    description: str = ""
    particulars: Particulars
    rigid_body: RigidBody
    added_mass: AddedMass
    damping: Damping
    thrusters: list[Thruster] = Field(default_factory=list)
    rudders: list[Rudder] = Field(default_factory=list)
    wind: Wind
    true_vessel: TrueVesselPerturbation = TrueVesselPerturbation()

    @field_validator("name")
    @classmethod
    def _named(cls, v: str) -> str:
        if not v.strip():
            raise ValueError("must not be empty (it names the vessel in messages, tables and model files)")
        return v

    @model_validator(mode="after")
    def _consistent(self):
        if self.format_version != VESSEL_FORMAT_VERSION:
            raise ValueError(f"format_version: this hybridship reads version {VESSEL_FORMAT_VERSION}, "
                             f"the file says {self.format_version}")
        names = [t.name for t in self.thrusters]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"thrusters: duplicate names {sorted(dup)}")
        rnames = [r.name for r in self.rudders]
        dup = {n for n in rnames if rnames.count(n) > 1 or n in names}
        if dup:
            raise ValueError(f"rudders: duplicate names {sorted(dup)} (names must differ from each other "
                             "and from the thrusters')")
        # a position beyond the hull is a typo (1444 for 14.44) or a sign or axis mix-up, not a
        # layout. Along: with damping.nonlinear's strips_x_aft_m (the AP) given, the hull runs
        # from the AP to the FP and overhangs by at most L_oa - L_pp at either end; without it,
        # L_oa centred on the CG (x_g_m), give or take 0.05 L_pp (the CG lies near midships).
        # Across: half the beam.
        part = self.particulars
        L, B = part.L_oa_m, part.B_m
        x_ap = self.damping.nonlinear.strips_x_aft_m
        if x_ap is not None:
            overhang = max(L - part.L_pp_m, 0.0)
            x_lo, x_hi = x_ap - overhang, x_ap + part.L_pp_m + overhang
            where = ("damping.nonlinear.strips_x_aft_m (the AP), particulars.L_pp_m and the overhang "
                     "L_oa_m - L_pp_m")
        else:
            half = 0.5 * L + 0.05 * part.L_pp_m
            x_lo, x_hi = self.rigid_body.x_g_m - half, self.rigid_body.x_g_m + half
            where = ("particulars.L_oa_m centred on rigid_body.x_g_m, give or take 0.05 L_pp; with the origin "
                     "elsewhere, give damping.nonlinear.strips_x_aft_m, the AP")
        for kind, acts in (("thrusters", self.thrusters), ("rudders", self.rudders)):
            for i, a in enumerate(acts):
                if not x_lo <= a.x_m <= x_hi:
                    raise ValueError(f"{kind}[{i}].x_m: {a.x_m:g} m lies outside the hull (from {x_lo:g} to "
                                     f"{x_hi:g} m from the body origin: {where})")
                if abs(a.y_m) > 0.5 * B:
                    raise ValueError(f"{kind}[{i}].y_m: {a.y_m:g} m lies outside the hull (at most half of "
                                     f"particulars.B_m = {B:g} m from the centre line)")
        for i, t in enumerate(self.thrusters):
            if t.diameter_m > B:          # a diameter in mm, not m
                raise ValueError(f"thrusters[{i}].diameter_m: {t.diameter_m:g} m is wider than the hull "
                                 f"(particulars.B_m = {B:g} m); diameters are in metres")
        forward = [t.name for t in self.thrusters if t.type == "fixed" and abs(t.fixed_angle_rad) < 1e-9]
        for i, r in enumerate(self.rudders):
            if r.propeller is not None and r.propeller not in forward:
                raise ValueError(f"rudders[{i}].propeller: {r.propeller!r} is not a thruster of type 'fixed' "
                                 f"with angle_deg = 0 (candidates: {forward or 'none'})")
            x_p = next((t.x_m for t in self.thrusters if t.name == r.propeller), None)
            if x_p is not None and r.x_m >= x_p:
                # ahead of its propeller: out of the slipstream, and a sign slip turns the ship the other way
                raise ValueError(f"rudders[{i}].x_m: {r.x_m:g} m is not aft of its propeller {r.propeller!r} "
                                 f"(x_m = {x_p:g} m); the rudder sits in the propeller's slipstream, and x is "
                                 f"positive forward")
        # Imported here: numba (behind physics) is only needed once a vessel is validated.
        from .physics.hull import mass_matrices

        part = self.particulars
        displacement_kg = part.rho_water_kg_m3 * part.C_B * part.L_pp_m * part.B_m * part.T_m
        ratio = self.rigid_body.mass_kg / displacement_kg
        if not 0.5 <= ratio <= 2.0:
            raise ValueError(f"rigid_body.mass_kg: {self.rigid_body.mass_kg:g} kg is {ratio:.3g} times the "
                             f"displacement rho C_B L_pp B T = {displacement_kg:.4g} kg; expected 0.5-2 times "
                             f"(a mass in tonnes is 1000 times too small)")
        inertia = _yaw_inertia_problem(self.rigid_body, part)
        if inertia is not None:
            raise ValueError(inertia)
        M_RB, M_A = mass_matrices(self)
        eig_a = np.linalg.eigvalsh(0.5 * (M_A + M_A.T))
        if not np.all(eig_a > 0):
            # Fossen (2021, ch. 6): M_A = M_A^T > 0; an indefinite one stores negative energy
            raise ValueError("added_mass: M_A is not positive definite (eigenvalues "
                             f"{np.array2string(eig_a, precision=3)}): the sway-yaw coupling (Y_rdot, N_vdot) is "
                             "too large for Y_vdot and N_rdot; Clarke's regressions (method 'clarke1983') leave "
                             "their hull range for beamy hulls: give method 'explicit' with a measured coupling")
        eig = np.linalg.eigvalsh(0.5 * (M_RB + M_A + (M_RB + M_A).T))
        if not np.all(eig > 0):
            raise ValueError("rigid_body/added_mass: M = M_RB + M_A is not positive definite "
                             f"(eigenvalues {np.array2string(eig, precision=3)}); masses are in kg and inertias "
                             "in kg m^2 (a mass in tonnes is 1000 times too small), added-mass terms as "
                             "Fossen's negative derivatives (X_udot_kg < 0)")
        return self

    @property
    def actuator_names(self) -> list[str]:
        """Names of the command channels: the thrusters in file order, then the rudders."""
        return [t.name for t in self.thrusters] + [r.name for r in self.rudders]

    @property
    def channel_names(self) -> list[str]:
        """Command channels as the logs name them (:attr:`actuator_names`).

        A log carries ``<name>_rpm`` for every thruster and ``<name>_azimuth_deg`` for every
        azimuth thruster and every rudder (the rudder angle, positive to starboard).
        """
        return self.actuator_names

    @property
    def rotatable(self) -> list[bool]:
        """Per command channel, whether it has an angle command (azimuth thrusters, rudders)."""
        return [t.type == "azimuth" for t in self.thrusters] + [True] * len(self.rudders)

    @property
    def n_actuators(self) -> int:
        """Number of command channels (width of the ``rpm`` and ``azimuth_rad`` arrays)."""
        return len(self.thrusters) + len(self.rudders)


#: Smallest plausible yaw radius of gyration about the CG, as a fraction of L_pp (ships give
#: 0.2-0.3, a uniform box 0.29); as the mass's 0.5-2 times the displacement, a unit check.
MIN_YAW_RADIUS_PER_LPP = 0.1


def _yaw_inertia_problem(rb: RigidBody, part: Particulars) -> str | None:
    """What is wrong with the yaw inertia, or None.

    The radius of gyration about the CG, ``r_z`` (given, or ``sqrt(I_z / m - x_g^2)`` from
    ``I_z`` about the origin), is at most ``0.5 sqrt(L_oa^2 + B^2)``: the variance of a mass
    within an interval is at most a quarter of its width squared (Popoviciu's inequality),
    in x over L_oa and in y over B. Below :data:`MIN_YAW_RADIUS_PER_LPP` L_pp it is a unit
    slip (an inertia in t m^2). Both passed before: ``r_z_m = 84.75`` for 8.475 m gave a
    yaw inertia 100 times too large, with no message.

    Parameters
    ----------
    rb : RigidBody
    part : Particulars

    Returns
    -------
    str or None
        The message, naming the field given (``rigid_body.r_z_m`` or ``rigid_body.I_z_kg_m2``).
    """
    r2 = rb.I_z / rb.mass_kg - rb.x_g_m**2          # r_z^2 about the CG
    if rb.r_z_m is not None:
        what = f"rigid_body.r_z_m: a radius of gyration of {rb.r_z_m:g} m"
    elif r2 > 0:
        what = f"rigid_body.I_z_kg_m2: {rb.I_z_kg_m2:g} kg m^2 gives a radius of gyration of {np.sqrt(r2):.4g} m"
    else:
        what = (f"rigid_body.I_z_kg_m2: {rb.I_z_kg_m2:g} kg m^2 is below m x_g^2 = {rb.mass_kg * rb.x_g_m**2:.4g} "
                f"kg m^2 (I_z is about the origin) and gives no radius of gyration")
    r_max = 0.5 * float(np.hypot(part.L_oa_m, part.B_m))
    r_min = MIN_YAW_RADIUS_PER_LPP * part.L_pp_m
    typical = f"ships give 0.2-0.3 L_pp, {0.25 * part.L_pp_m:.4g} m at 0.25"
    if r2 > r_max**2:
        return (f"{what}, more than 0.5 sqrt(L_oa_m^2 + B_m^2) = {r_max:.4g} m, which no mass within the hull "
                f"reaches ({typical})")
    if r2 < r_min**2:
        return (f"{what}, less than {MIN_YAW_RADIUS_PER_LPP:g} L_pp = {r_min:.4g} m ({typical}; an inertia in "
                f"t m^2 is 1000 times too small)")
    return None


def fingerprint(vessel: Vessel) -> str:
    """A stable hash of the validated vessel description (16 hex digits).

    Two vessels with the same fingerprint have the same parameters; model files and
    checked logs (:func:`hybridship.logs.ingest.ingest`) record it.
    """
    import hashlib
    import json

    return hashlib.sha256(json.dumps(portable_description(vessel), sort_keys=True).encode()).hexdigest()[:16]


def portable_description(vessel: Vessel) -> dict:
    """The validated description as JSON-ready data, without the fields added after model
    files and checked logs first recorded vessels, where they are at their default: the
    fingerprint of such a vessel is the one recorded before, and a model file that embeds
    it can be read by a hybridship from before those fields."""
    d = vessel.model_dump(mode="json")
    for path, default in _LATER_FIELDS:
        *parents, key = path
        node = d
        for p in parents:
            node = node[p]
        if node.get(key) == default:
            del node[key]
    return d


#: (path in the description, default) of fields added after fingerprints were first recorded.
_LATER_FIELDS = ((("damping", "nonlinear", "lift_speed"), "abs"),
                 (("damping", "nonlinear", "strips_x_aft_m"), None))


def vessel_from_dict(data: dict, source: str = "vessel") -> Vessel:
    """Validate a dictionary (e.g. parsed TOML) into a :class:`Vessel`."""
    try:
        return Vessel.model_validate(data)
    except ValidationError as err:
        raise VesselFileError(format_validation_error(err, source)) from None


def vessels_dir():
    """Folder of the packaged vessel files.

    Installed, they are the ``hybridship.vessels`` package (mapped from the top-level
    ``vessels/`` folder); run from a source checkout, ``hybridship`` is the source tree and
    the files are in ``vessels/`` beside it.
    """
    try:
        return resources.files("hybridship.vessels")
    except ModuleNotFoundError:
        return Path(__file__).resolve().parent.parent / "vessels"


def packaged_vessel_text(name: str) -> str:
    """Text of the packaged vessel file ``<name>.toml`` (raises :class:`VesselFileError`)."""
    res = vessels_dir().joinpath(f"{name}.toml")
    if not res.is_file():
        raise VesselFileError(f"vessel {name!r} is neither a file nor a packaged vessel "
                              f"(packaged: {', '.join(packaged_vessels())})")
    return res.read_text(encoding="utf-8")


def packaged_vessels() -> list[str]:
    """Names of the vessel files shipped with hybridship (``vessels/*.toml``)."""
    return sorted(p.name.removesuffix(".toml") for p in vessels_dir().iterdir() if p.name.endswith(".toml"))


def load_vessel(name_or_path: str | Path) -> Vessel:
    """Load and validate a vessel by packaged name (``"gunnerus"``) or TOML file path."""
    if not isinstance(name_or_path, (str, os.PathLike)) or not str(name_or_path):
        raise TypeError(f"vessel: expected a packaged vessel name or a vessel file path, got "
                        f"{type(name_or_path).__name__} {name_or_path!r}")
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        if not p.is_file():     # a folder exists: "not found" sent the user looking for it
            problem = "is a folder; expected a vessel file (.toml)" if p.is_dir() else "vessel file not found"
            raise VesselFileError(f"{p}: {problem}")
        try:
            text = p.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            raise VesselFileError(f"{p}: not a vessel file (TOML text) but a binary file; a model file (.npz) "
                                  f"carries its vessel inside (HybridPredictor.load(path).model.vessel): give "
                                  f"the vessel's TOML file") from None
        source = p.name
    else:
        text = packaged_vessel_text(str(name_or_path))
        source = f"{name_or_path}.toml"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise VesselFileError(f"{source}: not valid TOML: {err}") from None
    if data.get("kind") == "planing_craft":
        raise VesselFileError(f"{source}: a planing-craft file (kind = \"planing_craft\") for the high-speed-craft "
                              "model (hybridship benchmark hsc; hybridship.hsc.vessel.load_planing_craft), not a "
                              "3-DOF vessel file")
    return vessel_from_dict(data, source)
