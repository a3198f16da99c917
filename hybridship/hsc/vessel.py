"""Planing-craft vessel files (``kind = "planing_craft"``): schema, loading and validation.

A planing-craft file (TOML) describes one high-speed craft for the surge/heave/pitch
simulator of :mod:`hybridship.hsc.simulator`: main particulars, the assumed prismatic
planing hull that Savitsky's (1964) method needs, the displacement-mode (pre-planing)
model, engines and propellers, the interceptor and trim-tab actuators, the sensors, and
a *truth perturbation*: the factors that turn the nominal file into the simulator's
"true" boat, so that a grey-box model that starts from the nominal file has something
to identify.

The Gunnerus-style loader :func:`hybridship.vessel.load_vessel` does not read these
files; :func:`load_planing_craft` does. Errors raise :class:`PlaningCraftFileError`
naming the field.

Units are SI and radians inside; the file uses degrees where a name says ``_deg``
(the file is an edge), and the model exposes radians through properties.
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from hybridship.config import Float, Int, format_validation_error
from hybridship.vessel import VesselFileError, packaged_vessel_text

__all__ = [
    "PlaningCraftFileError",
    "PlaningCraft",
    "load_planing_craft",
    "planing_craft_from_dict",
]

#: Version of the planing-craft file format this code reads.
PLANING_CRAFT_FORMAT_VERSION = 1


class PlaningCraftFileError(VesselFileError):
    """A planing-craft file is missing, unreadable or invalid; the message names the field."""


class _Strict(BaseModel):
    # NaN and inf refused in every field: a NaN in the file gave all-NaN trials, no error;
    # numbers are Float / Int (hybridship.config), which refuse booleans and quoted text
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Particulars(_Strict):
    """Main particulars as published (Ertogan et al., Appendix A)."""

    loa_m: Float = Field(gt=0, description="length overall [m]")
    lwl_m: Float = Field(gt=0, description="length on the waterline [m]")
    beam_m: Float = Field(gt=0, description="maximum beam [m]")
    depth_m: Float = Field(gt=0, description="moulded depth [m]")
    displacement_kg: Float = Field(gt=0, description="displacement (mass) [kg]")
    draft_m: Float = Field(gt=0, description="draft at rest [m]")
    gm_m: Float = Field(gt=0, description="transverse metacentric height [m]")
    roll_period_s: Float = Field(gt=0, description="natural roll period [s]")
    rho_water_kg_m3: Float = Field(1025.0, gt=900, lt=1100)
    nu_water_m2_s: Float = Field(1.19e-6, gt=0, lt=1e-4, description="kinematic viscosity [m^2/s]")


class Hull(_Strict):
    """Prismatic planing hull for Savitsky's method (all assumed: the paper gives none)."""

    chine_beam_m: Float = Field(gt=0, description="mean beam over the chines b [m]")
    deadrise_deg: Float = Field(ge=0, lt=35, description="deadrise angle beta [deg]")
    lcg_m: Float = Field(gt=0, description="CG forward of the transom [m]")
    vcg_m: Float = Field(gt=0, description="CG above the keel [m]")
    pitch_gyration_radius_m: Float = Field(gt=0, description="radius of gyration in pitch [m]")
    correlation_allowance: Float = Field(0.0004, ge=0, le=0.002, description="Delta C_F [-]")
    added_mass_length_m: Float = Field(gt=0, description="wetted length used for the added mass [m]")
    min_damping_speed_m_s: Float = Field(3.0, gt=0, description="speed floor of the U a33 damping [m/s]")
    friction_factor: Float = Field(1.0, gt=0, description="multiplies C_F (fouling); 1 = ITTC-1957")

    @property
    def deadrise_rad(self) -> float:
        return math.radians(self.deadrise_deg)


class DisplacementMode(_Strict):
    """Forces below planing speed; blended into Savitsky's between two speeds."""

    waterplane_area_m2: Float = Field(gt=0, description="heave restoring C33 = rho g A_wp")
    long_metacentric_height_m: Float = Field(gt=0, description="pitch restoring C55 = rho g nabla GM_L")
    hump_speed_kn: Float = Field(gt=0, description="speed of the resistance hump [kn]")
    hump_resistance_ratio: Float = Field(gt=0, lt=1, description="R / (m g) at the hump [-]")
    hump_trim_deg: Float = Field(gt=0, lt=15, description="bow-up trim at the hump [deg]")
    blend_start_kn: Float = Field(gt=0, description="below this speed: displacement forces only [kn]")
    blend_end_kn: Float = Field(gt=0, description="above this speed: Savitsky forces only [kn]")

    @model_validator(mode="after")
    def _order(self):
        if not self.blend_start_kn < self.blend_end_kn:
            raise ValueError("blend_start_kn must be below blend_end_kn")
        return self


class Engines(_Strict):
    count: Int = Field(ge=1, le=4)
    power_bhp: Float = Field(gt=0, description="brake power of each engine [BHP]")
    idle_rpm: Float = Field(gt=0)
    max_rpm: Float = Field(gt=0)
    time_constant_s: Float = Field(gt=0, description="first-order lag of engine speed [s]")

    @model_validator(mode="after")
    def _order(self):
        if not self.idle_rpm < self.max_rpm:
            raise ValueError("idle_rpm must be below max_rpm")
        return self


class Propellers(_Strict):
    """One propeller per engine: ``K_T = K_T0 (1 - J / J0)`` (thrust falls with speed)."""

    diameter_m: Float = Field(gt=0)
    gear_ratio: Float = Field(gt=0, description="engine rpm / propeller rpm")
    kt0: Float = Field(gt=0, description="thrust coefficient at J = 0 [-]")
    j0: Float = Field(gt=0, description="advance ratio of zero thrust [-]")
    wake_fraction: Float = Field(0.0, ge=0, lt=0.5)
    thrust_deduction: Float = Field(0.0, ge=0, lt=0.5)
    x_aft_of_transom_m: Float = Field(ge=0, description="propeller aft of the transom [m]")
    z_below_keel_m: Float = Field(description="propeller centre below the keel at the transom [m]")
    shaft_angle_deg: Float = Field(description="thrust line angle to the keel, bow-up positive [deg]")


class Interceptor(_Strict):
    """Interceptor blades: force = C 0.5 rho V^2 (span x stroke) per blade, at the transom."""

    count: Int = Field(ge=1, le=4)
    span_m: Float = Field(gt=0)
    max_stroke_m: Float = Field(gt=0)
    lift_coefficient: Float = Field(gt=0, description="lift on span x stroke (tunable) [-]")
    drag_coefficient: Float = Field(ge=0, description="drag on span x stroke [-]")
    full_stroke_time_s: Float = Field(gt=0, description="actuator rate limit: 0 to full stroke [s]")


class TrimTabs(_Strict):
    """Trim-tab plates: Savitsky & Brown (1976) flap lift, centre 0.6 b forward of the trailing edge."""

    count: Int = Field(ge=1, le=4)
    span_m: Float = Field(gt=0)
    chord_m: Float = Field(gt=0)
    max_deflection_deg: Float = Field(gt=0, le=30)
    full_travel_time_s: Float = Field(gt=0, description="actuator rate limit: 0 to full deflection [s]")
    lift_factor: Float = Field(1.0, gt=0, description="multiplies the Savitsky & Brown flap lift")


class Actuation(_Strict):
    """PWM duty cycle [%] -> stroke or deflection fraction: linear between the two duties."""

    pwm_min_pct: Float = Field(10.0, ge=0, lt=100)
    pwm_max_pct: Float = Field(100.0, gt=0, le=100)

    @model_validator(mode="after")
    def _order(self):
        if not self.pwm_min_pct < self.pwm_max_pct:
            raise ValueError("pwm_min_pct must be below pwm_max_pct")
        return self


class Sensors(_Strict):
    sample_period_s: Float = Field(gt=0)
    gps_delay_s: Float = Field(ge=0, description="GPS speed latency [s]")
    gps_speed_noise_m_s: Float = Field(ge=0)
    imu_pitch_noise_deg: Float = Field(ge=0)
    imu_pitch_bias_deg: Float = Field(0.0, description="mounting misalignment [deg]")
    imu_acc_noise_m_s2: Float = Field(ge=0)
    rpm_noise: Float = Field(ge=0)

    @model_validator(mode="after")
    def _whole_delay(self):
        # the delay shifts the record by whole samples; another value would be rounded silently
        k = self.gps_delay_s / self.sample_period_s
        if abs(k - round(k)) > 1e-9 * max(1.0, k):
            raise ValueError(f"gps_delay_s ({self.gps_delay_s:g} s) must be a whole number of samples of "
                             f"sample_period_s ({self.sample_period_s:g} s)")
        return self


class TruthPerturbation(_Strict):
    """Factors and offsets from the nominal file to the simulator's "true" boat."""

    lcg_offset_m: Float = 0.0
    kt0_factor: Float = Field(1.0, gt=0)
    friction_factor: Float = Field(1.0, gt=0, description="hull fouling on C_F")
    interceptor_lift_factor: Float = Field(1.0, gt=0)
    trim_tab_lift_factor: Float = Field(1.0, gt=0)
    displacement_factor: Float = Field(1.0, gt=0, description="fuel, crew and gear on board")


class PlaningCraft(_Strict):
    """A validated planing-craft file."""

    kind: Literal["planing_craft"]
    format_version: Int = Field(PLANING_CRAFT_FORMAT_VERSION)
    name: str
    description: str = ""
    particulars: Particulars
    hull: Hull
    displacement_mode: DisplacementMode
    engines: Engines
    propellers: Propellers
    interceptor: Interceptor
    trim_tabs: TrimTabs
    actuation: Actuation = Actuation()
    sensors: Sensors
    truth_perturbation: TruthPerturbation = TruthPerturbation()

    @model_validator(mode="after")
    def _checks(self):
        if self.format_version != PLANING_CRAFT_FORMAT_VERSION:
            raise ValueError(f"format_version {self.format_version} is not supported "
                             f"(this code reads {PLANING_CRAFT_FORMAT_VERSION})")
        if self.hull.lcg_m >= self.particulars.lwl_m:
            raise ValueError("hull.lcg_m must lie within the waterline length")
        if self.hull.chine_beam_m > self.particulars.beam_m:
            raise ValueError("hull.chine_beam_m cannot exceed particulars.beam_m")
        for name, dev in (("interceptor", self.interceptor), ("trim_tabs", self.trim_tabs)):
            # the blades and plates sit side by side on the planing bottom's transom: a wider set
            # (sigma = span / beam above 1 in Savitsky & Brown's flap lift) is a typing slip
            if dev.count * dev.span_m > self.hull.chine_beam_m:
                raise ValueError(f"{name}.span_m: {dev.count} x {dev.span_m:g} m exceeds hull.chine_beam_m "
                                 f"({self.hull.chine_beam_m:g} m)")
        return self

    @property
    def mass_kg(self) -> float:
        return self.particulars.displacement_kg

    def perturbed(self) -> "PlaningCraft":
        """The simulator's "true" boat: this file with :attr:`truth_perturbation` applied."""
        tp = self.truth_perturbation
        data = self.model_dump()
        data["hull"]["lcg_m"] += tp.lcg_offset_m
        data["propellers"]["kt0"] *= tp.kt0_factor
        data["hull"]["friction_factor"] *= tp.friction_factor
        data["interceptor"]["lift_coefficient"] *= tp.interceptor_lift_factor
        data["trim_tabs"]["lift_factor"] *= tp.trim_tab_lift_factor
        data["particulars"]["displacement_kg"] *= tp.displacement_factor
        data["truth_perturbation"] = TruthPerturbation().model_dump()
        try:
            return PlaningCraft.model_validate(data)
        except ValidationError as err:      # the file's perturbation makes an impossible boat
            raise PlaningCraftFileError(format_validation_error(err, "truth_perturbation applied to the file")
                                        + " (check [truth_perturbation])") from None


def planing_craft_from_dict(data: dict, source: str = "<dict>") -> PlaningCraft:
    """Validate a parsed planing-craft file; errors name the field."""
    if not isinstance(data, Mapping):       # an AttributeError on .get before
        raise PlaningCraftFileError(f"{source}: expected a table of the file's fields (a dict), "
                                    f"got {type(data).__name__}")
    if data.get("kind") != "planing_craft":
        raise PlaningCraftFileError(f"{source}: kind: expected 'planing_craft', got {data.get('kind')!r}")
    try:
        return PlaningCraft.model_validate(data)
    except ValidationError as err:
        raise PlaningCraftFileError(format_validation_error(err, source)) from None


def load_planing_craft(name_or_path: str | Path = "volcano71") -> PlaningCraft:
    """Load a planing craft by packaged name (``"volcano71"``) or TOML file path.

    Raises
    ------
    TypeError
        ``name_or_path`` not a non-empty str or path (None or a number failed in pathlib's
        words, naming nothing; an empty name read the current folder).
    PlaningCraftFileError
        The file is missing, unreadable or invalid; the message names the field.
    """
    if not isinstance(name_or_path, (str, os.PathLike)) or not str(name_or_path):
        raise TypeError(f"name_or_path: expected a packaged planing-craft name or a file path, got "
                        f"{type(name_or_path).__name__} {name_or_path!r}")
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        if not p.is_file():     # a folder exists: "not found" sent the user looking for it
            problem = "is a folder; expected a planing-craft file (.toml)" if p.is_dir() else \
                "planing-craft file not found"
            raise PlaningCraftFileError(f"{p}: {problem}")
        try:
            text = p.read_text(encoding="utf-8")
        except UnicodeDecodeError:      # the codec's own words named no file
            raise PlaningCraftFileError(f"{p}: not a planing-craft file (TOML text) but a binary file") from None
        source = p.name
    else:
        try:
            text = packaged_vessel_text(str(name_or_path))
        except VesselFileError as err:
            raise PlaningCraftFileError(str(err)) from None
        source = f"{name_or_path}.toml"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise PlaningCraftFileError(f"{source}: not valid TOML: {err}") from None
    return planing_craft_from_dict(data, source)
