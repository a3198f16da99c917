"""The log format's columns, declared once.

Every column of the log format (version 1, ``docs/reference/log-format.md``) is one
:class:`ColumnSpec` in :data:`COLUMNS`: its name (or, for per-channel columns, a pattern
with ``<thruster>``), unit, whether it is required, its type, whether every sample must be
finite, its plausible range (fixed, or bound to the vessel file), whether it is an angle in
degrees (checked for radians), and what a value outside the range suggests. The checks in
:mod:`hybridship.logs.io` are driven by this table, so a column's rule and its error
message live in one place.

Everything here is data: no checks run at import.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Bound",
    "ColumnSpec",
    "COLUMNS",
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "TRUTH_PREFIX",
    "CHANNEL",
    "column_spec",
    "channel_column",
    "MAX_SPEED_M_S",
    "MAX_YAW_RATE_DEG_S",
    "MAX_WIND_SPEED_M_S",
    "HEADING_RANGE_DEG",
    "MIN_SAMPLE_SPACING_S",
    "MAX_SAMPLE_SPACING_S",
    "RPM_UNIT_FACTOR",
]

#: Plausibility limits (a ship, not a missile): beyond these a unit mix-up is more likely.
MAX_SPEED_M_S = 30.0
MAX_YAW_RATE_DEG_S = 60.0
MAX_WIND_SPEED_M_S = 80.0
#: Plausible median sample spacing [s]; outside it ``time_s`` is in another unit.
MIN_SAMPLE_SPACING_S = 0.01
MAX_SAMPLE_SPACING_S = 60.0
#: A heading in degrees lies in this range in every wrap convention (with slack for a
#: logger that wraps late); beyond it the column is in another unit.
HEADING_RANGE_DEG = (-360.0, 720.0)
#: ``|rpm|`` beyond this multiple of a thruster's ``max_rpm`` is a unit error (refused).
RPM_UNIT_FACTOR = 1.25

#: What an angle column (other than the heading) beyond ``HEADING_RANGE_DEG`` suggests.
_ANGLE_EXPECTS = "the log format expects degrees (0..360 or -180..180): is it in centidegrees or milliradians?"

#: Placeholder for the command channel (thruster or rudder) in per-channel column names.
CHANNEL = "<thruster>"
#: Prefix of simulator ground-truth columns, which readers never interpret.
TRUTH_PREFIX = "truth_"


@dataclass(frozen=True)
class Bound:
    """A plausible range: ``lo <= x <= hi``, or ``|x| <= hi`` with ``magnitude``.

    Missing (NaN) samples never violate a bound. None leaves that side open.
    """

    lo: float | None = None
    hi: float | None = None
    magnitude: bool = False

    def violated(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """(N,) bool, True where ``x`` lies outside the bound (both ends times ``scale``)."""
        v = np.abs(x) if self.magnitude else x
        bad = np.zeros(np.shape(x), dtype=bool)
        if self.hi is not None:
            bad |= v > self.hi * scale
        if self.lo is not None:
            bad |= v < self.lo * scale
        return bad

    def text(self, unit: str) -> str:
        """What a violating value does, for messages: ``"exceeds 30 m/s in magnitude"``."""
        u = f" {unit}" if unit else ""
        if self.magnitude:
            return f"exceeds {self.hi:g}{u} in magnitude"
        return f"is outside {self.lo:g}..{self.hi:g}{u}"


@dataclass(frozen=True)
class ColumnSpec:
    """One column of the log format.

    Attributes
    ----------
    name : str
        The column name, or a pattern with ``<thruster>`` for one column per command
        channel (``<thruster>_rpm``).
    unit : str
        Unit of the values ("" for a flag).
    quantity : str
        What it holds (one line, for documentation).
    required : bool
        Every log has it.
    dtype : {"float", "flag"}
        A number, or a 0/1 flag (see ``allowed``).
    finite : bool
        Every sample must be a finite number (required columns; forecast-time ingest
        accepts missing samples and judges them per start).
    bound : Bound, optional
        Plausible range; beyond it the column is refused as being in another unit.
    allowed : tuple of float
        The only values a flag may take (missing samples aside).
    vessel_factor : float, optional
        Per-channel bound from the vessel file: ``|x| <= vessel_factor x max_rpm`` of the
        channel's thruster.
    expects : str
        What the format expects and what a violation suggests, quoted after the value in
        the error message.
    angle : bool
        An angle in degrees: refused when it looks like radians (see
        :func:`hybridship.logs.io.heading_looks_like_radians`).
    rate_column : str, optional
        The column logging this angle's rate of change (evidence for the radian rule).
    rotatable_only : bool
        Per-channel column that only rotatable channels have (a fixed thruster's is
        ignored with a warning).
    other_unit_stems : tuple of str
        Names of the same quantity in another unit (``heading`` for ``heading_rad``),
        pointed out in messages.
    """

    name: str
    unit: str
    quantity: str
    required: bool = False
    dtype: str = "float"
    finite: bool = False
    bound: Bound | None = None
    allowed: tuple[float, ...] = ()
    vessel_factor: float | None = None
    expects: str = ""
    angle: bool = False
    rate_column: str | None = None
    rotatable_only: bool = False
    other_unit_stems: tuple[str, ...] = ()

    @property
    def per_channel(self) -> bool:
        """One column per command channel (the name is a pattern)."""
        return CHANNEL in self.name

    def for_channel(self, channel: str) -> str:
        """The column name of ``channel`` (``port`` -> ``port_rpm``)."""
        return self.name.replace(CHANNEL, channel)

    @property
    def suffix(self) -> str:
        """What follows ``<thruster>_`` in a per-channel name ("" for fixed names)."""
        return self.name.split(CHANNEL + "_", 1)[1] if self.per_channel else ""


COLUMNS: tuple[ColumnSpec, ...] = (
    ColumnSpec("time_s", "s", "sample time, strictly increasing", required=True, finite=True,
               other_unit_stems=("time", "t", "timestamp")),
    ColumnSpec("north_m", "m", "position north of the local origin", required=True, finite=True,
               other_unit_stems=("north",)),
    ColumnSpec("east_m", "m", "position east of the local origin", required=True, finite=True,
               other_unit_stems=("east",)),
    ColumnSpec("heading_deg", "deg", "true heading, clockwise from north", required=True, finite=True,
               bound=Bound(*HEADING_RANGE_DEG),
               expects="the log format expects degrees (0..360 or -180..180): is it in milliradians or "
                       "centidegrees?",
               angle=True, rate_column="r_deg_s", other_unit_stems=("heading", "hdg", "psi", "yaw")),
    ColumnSpec("u_m_s", "m/s", "surge velocity over ground (body frame)", bound=Bound(hi=MAX_SPEED_M_S, magnitude=True),
               expects="the log format expects m/s; is the column in knots (or another unit)?",
               other_unit_stems=("u", "surge", "surge_speed")),
    ColumnSpec("v_m_s", "m/s", "sway velocity over ground (body frame)", bound=Bound(hi=MAX_SPEED_M_S, magnitude=True),
               expects="the log format expects m/s; is the column in knots (or another unit)?",
               other_unit_stems=("v", "sway", "sway_speed")),
    ColumnSpec("r_deg_s", "deg/s", "yaw rate, positive clockwise seen from above",
               bound=Bound(hi=MAX_YAW_RATE_DEG_S, magnitude=True),
               expects="implausible for a ship; the log format expects deg/s; check the rad/s vs deg/s "
                       "conversion (converted twice?)",
               other_unit_stems=("r", "yaw_rate", "rot")),
    ColumnSpec("wind_speed_m_s", "m/s", "true wind speed", bound=Bound(0.0, MAX_WIND_SPEED_M_S),
               expects="the log format expects a non-negative true wind speed in m/s (knots?)",
               other_unit_stems=("wind_speed", "windspeed", "wind")),
    ColumnSpec("wind_dir_deg", "deg", "true direction the wind comes from", bound=Bound(*HEADING_RANGE_DEG),
               expects=_ANGLE_EXPECTS, angle=True, other_unit_stems=("wind_dir", "wind_direction", "winddir")),
    ColumnSpec("dp_active", "", "1 while the station-keeping controller is active", dtype="flag",
               allowed=(0.0, 1.0),
               expects="the log format expects 1 while the station-keeping controller is active, else 0"),
    ColumnSpec(f"{CHANNEL}_rpm", "rpm", "propeller speed command, signed", vessel_factor=RPM_UNIT_FACTOR,
               expects="the log format expects the propeller shaft speed in rpm: is it the motor speed before "
                       "the gear, or another unit?"),
    ColumnSpec(f"{CHANNEL}_azimuth_deg", "deg", "azimuth (thruster) or angle (rudder), positive to starboard",
               bound=Bound(*HEADING_RANGE_DEG), expects=_ANGLE_EXPECTS, angle=True, rotatable_only=True),
)

_BY_NAME = {c.name: c for c in COLUMNS}
_PER_CHANNEL = tuple(c for c in COLUMNS if c.per_channel)
_CHANNEL_RE = re.compile(r"^(?P<name>.+)_(?P<kind>" + "|".join(re.escape(c.suffix) for c in _PER_CHANNEL) + r")$")

#: Columns every log must have.
REQUIRED_COLUMNS = tuple(c.name for c in COLUMNS if c.required)
#: Fixed-name optional columns of the format (per-channel columns are matched by pattern).
OPTIONAL_COLUMNS = tuple(c.name for c in COLUMNS if not c.required and not c.per_channel)


def column_spec(name: str) -> ColumnSpec:
    """The spec of a fixed-name column, or of a per-channel pattern (``"<thruster>_rpm"``)."""
    return _BY_NAME[name]


def channel_column(column: str) -> tuple[ColumnSpec, str] | None:
    """``(spec, channel)`` when ``column`` is a per-channel column (``port_rpm`` ->
    (the ``<thruster>_rpm`` spec, ``"port"``)), else None."""
    m = _CHANNEL_RE.match(column)
    if m is None:
        return None
    return next(c for c in _PER_CHANNEL if c.suffix == m.group("kind")), m.group("name")
