"""The project's vessel log format (version 1): read, validate, write, convert to arrays.

The format is specified in ``shared/spec/log-format.md``: one row per sample, units in
the column names, degrees at the file edge. This module is that edge: DataFrames and
degrees come in, :class:`LogArrays` in SI units and radians go out.

Containers (chosen by the file name's extension): ``.csv``, ``.csv.gz`` (gzip CSV) and
``.parquet`` / ``.pq``.

Each column's rules (unit, required or optional, finite, plausible range, bound to the
vessel file, angle in degrees) are declared once in :data:`hybridship.logs.columns.COLUMNS`;
small named checks here apply them. Validation (:func:`validate_log`) refuses, with a
:class:`LogFormatError` that names the column, the first offending row (0-based position
among the data rows, header excluded) and its ``time_s`` where relevant, and what was
expected:

* missing required columns (``time_s``, ``north_m``, ``east_m``, ``heading_deg``) or
  duplicated column names; when a column with the same quantity in another unit is
  present (``heading_rad``, ``time_ms``, ...), a name with spaces around it, a header
  separated by ``;`` or tabs, or the column is the DataFrame's index, the message says so;
* one of ``wind_speed_m_s`` and ``wind_dir_deg`` without the other;
* non-numeric values in a known numeric column; infinities anywhere in one;
* ``time_s`` not finite or not strictly increasing; a median sample spacing outside
  0.01..60 s (``time_s`` in milliseconds?); inside it, a ``time_s`` in minutes, hours or
  milliseconds, by the speeds against the track (below); NaN in a required column (unless
  ``allow_missing``, the forecast-time mode of :mod:`hybridship.forecast_inputs.start_window`);
* a heading, ``wind_dir_deg`` or ``<thruster>_azimuth_deg`` outside -360..720 deg
  (milliradians, centidegrees?); a heading that looks like
  radians (see :func:`heading_looks_like_radians` for the rule); the same radian rule for
  ``wind_dir_deg`` and every ``<thruster>_azimuth_deg`` (checked against the vessel, not a
  rudder's: in radians it stays within +-pi/2, where the rule finds nothing);
* ``|u_m_s|`` or ``|v_m_s|`` above 30 m/s (knots?), ``|r_deg_s|`` above 60 deg/s
  (rad/s vs deg/s mix-up?), ``wind_speed_m_s`` outside 0..80 m/s;
* ``u_m_s``/``v_m_s`` whose speed is not the speed of the track (see
  :func:`speed_scale_vs_track`): knots (1.94 x) and km/h (3.6 x) are named;
* ``r_deg_s`` that is 1/57.3 of the heading's rate of change (rad/s) or 57.3 x (converted
  twice), or whose sign is opposite to it (counter-clockwise convention); the message says
  that minutes in ``time_s`` give nearly the same 1/60, and when the speeds move the ship
  along the track only with ``time_s`` read in minutes, ``time_s`` is refused instead;
* thruster columns (``<name>_rpm``, ``<name>_azimuth_deg``) naming a thruster that is not
  in ``channel_names`` (when given);
* ``dp_active`` values other than 0/1.

Each column is checked on its own first, then against the others (yaw rate against
heading, speed against track), then the thruster columns. :func:`check_log_against_vessel`
adds the checks that need the vessel file: every
thruster column names a thruster of the vessel, an azimuth thruster with a logged rpm also
has its azimuth logged, all or none of the thrusters are logged (and none only when the
vessel is not station keeping), ``|rpm|`` within 1.25 x the thruster's ``max_rpm``, and the
rpm sign convention (an azimuth thruster that runs only "astern" for a minute or more
is taken to log its shaft rotation direction, not the thrust sign), and every rudder's
angle when thrusters are logged.

Optional columns may contain missing values (empty CSV cells / Parquet nulls). Columns
that are neither in the format nor ``truth_*`` are reported once per call with a
:class:`LogFormatWarning` and kept; when one looks like a format column in another unit
(``wind_speed_kn``) the warning says so.

Nothing here modifies the caller's DataFrame or file: validation reads, conversion copies.
"""

from __future__ import annotations

import dataclasses

import functools
import gzip
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd

from hybridship import frames
from hybridship.config import check_number
from hybridship.fileio import as_path, atomic_write, starts_with
from hybridship.logs.columns import (COLUMNS, MAX_SAMPLE_SPACING_S, MIN_SAMPLE_SPACING_S, OPTIONAL_COLUMNS,
                                     REQUIRED_COLUMNS, TRUTH_PREFIX, ColumnSpec, channel_column, column_spec)
from hybridship.logs.preprocess import segment_ids, segmentwise, split_segments
from hybridship.messages import seconds_text, warn_user

__all__ = [
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "LogFormatError",
    "LogFormatWarning",
    "LogArrays",
    "read_log",
    "write_log",
    "validate_log",
    "log_to_arrays",
    "heading_looks_like_radians",
    "angle_looks_like_radians",
    "speed_scale_vs_track",
    "SpeedScale",
    "check_log_against_vessel",
    "check_units_on_whole_log",
    "log_header",
    "output_table_kind",
]

#: Speed-vs-track check: displacements over this lag [s] are compared ...
SPEED_CHECK_LAG_S = 20.0
#: ... when their rms reaches this [m] (the correlation gate below keeps noise out) ...
SPEED_CHECK_MIN_DISPLACEMENT_M = 1.0
#: ... and the two agree in shape (complex correlation at least this).
SPEED_CHECK_MIN_CORRELATION = 0.8
#: Speed scale factors of common unit mix-ups (logged / true for a m/s column).
KNOTS_PER_M_S = 1.0 / 0.514444
KM_H_PER_M_S = 3.6
#: The logged speed may differ from the track's by at most this factor either way
#: (the geometric mean of 1 and 1.94: knots are refused, noise is not).
_SPEED_SCALE_SPLIT = float(np.sqrt(KNOTS_PER_M_S))
#: ... and its direction, turned into NED by the logged heading, from the track's by at most
#: this [deg] (median over windows that moved :data:`SPEED_CHECK_MISFIT_MIN_M` [m] both
#: ways): a heading and yaw rate both in radians (a heading of 186 deg logged as 3.24, read
#: as 3.24 deg) pass the angle-unit rules but turn the velocities by up to 180 deg.
SPEED_CHECK_MAX_MISFIT_DEG = 45.0
SPEED_CHECK_MISFIT_MIN_M = 2.0
#: ... and the heading is refused as radians only when, read as radians, it turns them onto
#: the track within this [deg]: a unit error fits one reading, a sensor fault neither.
SPEED_CHECK_RADIANS_FIT_DEG = 15.0
#: ... and north/east are refused as swapped, or u or v as of the other sign, when the velocities
#: leave the track by more than this [deg] and, read that way, follow it within
#: :data:`SPEED_CHECK_RADIANS_FIT_DEG` (how far a mirrored frame turns them depends on the course:
#: under 45 deg on many drifts).
SPEED_CHECK_CONVENTION_MISFIT_DEG = 30.0
#: An azimuth thruster negative in at least this many samples and never positive is taken
#: to log its rotation direction instead of the thrust sign.
RPM_SIGN_MIN_SAMPLES = 60

_EXTENSIONS = (".csv", ".csv.gz", ".parquet", ".pq")


class LogFormatError(ValueError):
    """A log does not follow the log format.

    The message names the column, the row (0-based, header excluded) and its ``time_s``
    where relevant, and what was expected. The same facts are kept as attributes.

    Attributes
    ----------
    column : str or None
    row : int or None
    time_s : float or None
    """

    def __init__(self, message: str, *, column: str | None = None, row: int | None = None,
                 time_s: float | None = None):
        super().__init__(message)
        self.column = column
        self.row = row
        self.time_s = time_s


class LogFormatWarning(UserWarning):
    """Something in a log is ignored (unknown columns, azimuth of a fixed thruster)."""


# --------------------------------------------------------------------------------------
# Heading unit rule
# --------------------------------------------------------------------------------------

#: Headings beyond this magnitude can only be degrees.
_RAD_LIMIT = 2.0 * np.pi + 0.1
#: Without other evidence, a heading confined to +-(2 pi + 0.1) that spans at least this
#: much (315 deg if radians, most of a turn) is taken to be radians.
RAD_SPREAD_LIMIT = 5.5
#: Ratio std(r_deg_s) / std(heading rate) splitting degrees (~1) from radians (~57.3).
_RATE_SCALE_SPLIT = float(np.sqrt(180.0 / np.pi))


def angle_looks_like_radians(time_s, angle, rate_deg_s=None) -> tuple[bool, str]:
    """Decide whether an angle column (heading, azimuth, wind direction) holds radians.

    The rule of :func:`heading_looks_like_radians`, which is this function; ``rate_deg_s``
    is the logged rate of change of the angle (``r_deg_s`` for the heading), if any.
    """
    return heading_looks_like_radians(time_s, angle, rate_deg_s)


def _rate_evidence(t: np.ndarray, h: np.ndarray, r: np.ndarray, wrap: float) -> tuple[float, float] | None:
    """Correlation and scale ``std(r) / std(dh/dt)`` of a logged rate against an angle series.

    Uses steps within 1.5 nominal periods, with finite ends, not wrapping (``|dh| <=
    wrap / 2``); None with fewer than 10 such steps or no variation.
    """
    ok = np.isfinite(h)
    t, h, r = t[ok], h[ok], r[ok]
    if t.size < 11:
        return None
    dt = np.diff(t)
    dh = np.diff(h)
    step_ok = (dt <= 1.5 * np.median(dt)) & np.isfinite(r[1:]) & np.isfinite(r[:-1]) & (np.abs(dh) <= 0.5 * wrap)
    if step_ok.sum() < 10:
        return None
    r_mid = 0.5 * (r[1:] + r[:-1])[step_ok]
    rate = (dh / dt)[step_ok]
    if not (np.std(rate) > 0.0 and np.std(r_mid) > 0.0):
        return None
    return float(np.corrcoef(rate, r_mid)[0, 1]), float(np.std(r_mid) / np.std(rate))


def _check_same_length(func: str, time_s: np.ndarray, **columns: np.ndarray) -> None:
    """ValueError naming the column of ``func`` that is not one value per ``time_s`` (numpy
    failed in its own words, naming no column)."""
    for name, x in columns.items():
        if x.shape != time_s.shape or time_s.ndim != 1:
            raise ValueError(f"{func}: {name}: expected one value per time_s {time_s.shape}, got shape {x.shape}")


def heading_looks_like_radians(time_s, heading, r_deg_s=None) -> tuple[bool, str]:
    """Decide whether a heading column holds radians instead of degrees.

    The rule, applied to the finite samples in order:

    1. **Range gate.** If any ``|heading| > 2 pi + 0.1`` the column is degrees: radians
       never get there. Otherwise the values are ambiguous and the next steps decide.
    2. **Wrap jump.** A single step between consecutive samples whose size is within
       1 of ``2 pi`` (a full turn if radians), while the typical (median) step is below
       0.25, is the signature of a radian heading wrapping at 0/2 pi or +-pi: refused. In
       degrees it would be a 5-7 deg one-sample jump in an otherwise smooth series.
    3. **Yaw rate evidence** (only if ``r_deg_s`` is given, with at least 10 usable
       steps, skipping steps across gaps > 1.5 nominal periods). The heading rate
       ``diff(heading) / diff(time_s)`` is compared with the logged rate averaged over each
       step. If the two are correlated (coefficient >= 0.3, i.e. the rate column describes
       this heading) their scale ratio ``k = std(r_deg_s) / std(heading rate)`` decides:
       ``k`` is about 1 for degrees and about 57.3 for radians, and the split is at the
       geometric mean ``sqrt(57.3) = 7.6``, which leaves a factor 7.6 of margin for noise
       either way (the project's logs give 0.5-1 in degrees and 28-55 in radians, also in
       calm DP). This catches a radian heading even when it barely moves, but cannot see a
       log whose heading AND rate are both in radian units (the log's validation refuses
       many of those by the track instead, when it has ``u_m_s``, ``v_m_s`` and the ship
       moves 2 m in 20 s: the heading read as radians turns them onto the track and read
       as degrees does not, by :func:`speed_scale_vs_track`'s ``misfit_deg``; not a heading
       that stays within about 45 deg of north, where both readings nearly agree).
    4. **Spread.** Otherwise the column is refused if it spans at least 5.5 (315 deg if
       radians, i.e. a turning vessel), and accepted if it spans less.

    So a log whose headings all lie in 0..3 deg is accepted (spread 3 < 5.5, no wrap
    jumps), and a turning log spanning 0..6.28 is refused (wrap jumps or spread). The
    known blind spot: a degree log that stays within +-6.28 deg of north in the -180..180
    convention for a whole recording, yet spans 5.5 deg or more (say -3 to +3 deg), and
    has no ``r_deg_s`` is refused as radians; logging ``r_deg_s``, or the heading as
    0..360 deg, resolves it.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Sample times [s], strictly increasing.
    heading : array_like, shape (N,)
        The heading column as logged (NaN samples are ignored).
    r_deg_s : array_like, shape (N,), optional
        Logged yaw rate [deg/s].

    Returns
    -------
    looks_like_radians : bool
    reason : str
        One sentence explaining the decision (used in error messages).
    """
    t = np.asarray(time_s, dtype=float)
    h = np.asarray(heading, dtype=float)
    _check_same_length("heading_looks_like_radians", t, heading=h,
                       r_deg_s=h if r_deg_s is None else np.asarray(r_deg_s, dtype=float))
    ok = np.isfinite(h)
    if ok.sum() < 2:
        return False, "fewer than two finite headings"
    if np.max(np.abs(h[ok])) > _RAD_LIMIT:
        return False, "values beyond 2 pi can only be degrees"

    t_ok, h_ok = t[ok], h[ok]
    dh = np.diff(h_ok)
    big = np.abs(dh) > np.pi
    wrap_like = big & (np.abs(np.abs(dh) - 2.0 * np.pi) < 1.0)
    typical_step = float(np.median(np.abs(dh[~big]))) if np.any(~big) else np.inf
    if wrap_like.any() and typical_step < 0.25:
        k = int(np.argmax(wrap_like))
        return True, (
            f"it jumps by {dh[k]:+.2f} in one sample (a full turn if radians) between "
            f"time_s {seconds_text(t_ok[k])} and {seconds_text(t_ok[k + 1])} while typical steps are "
            f"{typical_step:.3f}"
        )

    if r_deg_s is not None:
        ev = _rate_evidence(t, h, np.asarray(r_deg_s, dtype=float), 2.0 * np.pi)
        if ev is not None:
            corr, k = ev
            if corr >= 0.3:
                if k > _RATE_SCALE_SPLIT:
                    return True, (
                        f"r_deg_s is {k:.1f} times its rate of change (about 1 expected for "
                        f"degrees, 57.3 for radians)"
                    )
                return False, f"r_deg_s is {k:.2f} times its rate of change, as for degrees"

    spread = float(np.ptp(h_ok))
    if spread >= RAD_SPREAD_LIMIT:
        return True, (
            f"all values lie within +-2 pi yet span {spread:.2f} (a turn of "
            f"{np.degrees(spread):.0f} deg if radians, only {spread:.1f} deg if degrees)"
        )
    return False, f"values span only {spread:.2f} within +-2 pi, consistent with degrees"


# --------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------


def _where(source: str) -> str:
    return f" (in {source})"


def _row_at(time_s: np.ndarray | None, i: int) -> str:
    if time_s is None or not np.isfinite(time_s[i]):
        return f"row {i}"
    return f"row {i} (time_s {seconds_text(time_s[i])})"


def _to_float(df: pd.DataFrame, col: str, source: str, time_s: np.ndarray | None,
              *, inf_is_missing: bool = False) -> np.ndarray:
    """Column as a new float array; non-numeric entries are errors, blanks NaN.

    Infinities are errors too, unless ``inf_is_missing`` (then they become NaN).
    """
    s = df[col]
    # True/False beside a missing value make a column of objects, which to_numeric reads as 1/0
    bools = col != "dp_active" and s.dtype == object and s.map(lambda v: isinstance(v, (bool, np.bool_))).any()
    if pd.api.types.is_bool_dtype(s) or bools:
        if col == "dp_active":                  # a flag column: True/False is 1/0
            return s.to_numpy(dtype=float, copy=True, na_value=np.nan)
        raise LogFormatError(f"{col}: True/False values; expected numbers{_where(source)}", column=col)
    if pd.api.types.is_complex_dtype(s):        # pandas would drop the imaginary part with a warning
        raise LogFormatError(f"{col}: complex values; expected real numbers{_where(source)}", column=col)
    if (pd.api.types.is_datetime64_any_dtype(s) or pd.api.types.is_timedelta64_dtype(s)
            or isinstance(s.dtype, pd.PeriodDtype)):
        # pandas would turn these into nanoseconds (periods into counts of their own unit, minutes
        # or days read as seconds), and the message would then blame the unit, or none would
        period = ", after t = t.dt.to_timestamp()" if isinstance(s.dtype, pd.PeriodDtype) else ""
        raise LogFormatError(f"{col}: {s.dtype} values; expected plain numbers (seconds for time_s: "
                             f"convert with (t - t.iloc[0]).dt.total_seconds(){period}){_where(source)}", column=col)
    num = pd.to_numeric(s, errors="coerce")
    bad = num.isna().to_numpy() & s.notna().to_numpy()
    if bad.any():
        i = int(np.argmax(bad))
        raise LogFormatError(
            f"{col}: non-numeric value {s.iloc[i]!r} at {_row_at(time_s, i)}; expected a number "
            f"with '.' as decimal separator or an empty cell{_where(source)}",
            column=col, row=i, time_s=None if time_s is None else float(time_s[i]),
        )
    x = np.array(num.to_numpy(dtype=float, na_value=np.nan), dtype=float)  # a copy, never a view
    inf = np.isinf(x)
    if inf.any():
        if inf_is_missing:
            x[inf] = np.nan
            return x
        i = int(np.argmax(inf))
        raise LogFormatError(
            f"{col}: infinite value {x[i]} at {_row_at(time_s, i)}; expected a finite number{_where(source)}",
            column=col, row=i, time_s=None if time_s is None else float(time_s[i]),
        )
    return x


def _check_thruster_args(channel_names, rotatable) -> tuple[tuple[str, ...] | None, tuple[bool, ...] | None]:
    if channel_names is None:
        if rotatable is not None:
            raise ValueError("rotatable given without channel_names")
        return None, None
    if isinstance(channel_names, (str, bytes)):     # one name, not the letters of a name
        raise ValueError(f"channel_names: expected a sequence of names, got the string {channel_names!r} "
                         f"(for one channel: [{channel_names!r}])")
    names = tuple(str(n) for n in channel_names)
    if len(set(names)) != len(names):
        raise ValueError(f"channel_names contains duplicates: {names}")
    if rotatable is None:
        return names, None
    rot = tuple(bool(r) for r in rotatable)
    if len(rot) != len(names):
        raise ValueError(f"rotatable has {len(rot)} entries for {len(names)} channel_names {names}")
    return names, rot


def _limit_error(col: str, x: np.ndarray, bad: np.ndarray, t: np.ndarray, expected: str,
                 source: str) -> LogFormatError:
    i = int(np.argmax(bad))
    return LogFormatError(
        f"{col}: value {x[i]:g} at {_row_at(t, i)} {expected}{_where(source)}",
        column=col, row=i, time_s=float(t[i]),
    )


#: Name stems of each format column; a column ``<stem>`` or ``<stem>_<unit>`` with another
#: unit is pointed out (required: in the error; optional: in the unknown-column warning).
_UNIT_STEMS = {c.name: c.other_unit_stems for c in COLUMNS if c.other_unit_stems}


def unit_variant(col: str, stems: dict, known=()) -> str | None:
    """The column of ``stems`` (column -> its names without a unit) that ``col`` looks like in
    another unit (``heading_rad`` -> ``heading_deg``): ``col`` is a stem or ``<stem>_<unit>``,
    the longest stem wins; None for a name in ``known`` (or a stem itself in ``stems``) or no
    match. The log reader and the weather table point out such columns with it."""
    c = col.lower()
    if c in stems or c in known:
        return None
    best, best_len = None, -1
    for fmt, fmt_stems in stems.items():
        for stem in fmt_stems:
            if (c == stem or c.startswith(stem + "_")) and len(stem) > best_len:
                best, best_len = fmt, len(stem)
    return best


def _unit_variant_of(col: str) -> str | None:
    """The log-format column that ``col`` looks like in another unit (:func:`unit_variant`)."""
    return unit_variant(col, _UNIT_STEMS, REQUIRED_COLUMNS + OPTIONAL_COLUMNS)


class SpeedScale(NamedTuple):
    """Logged speed against the speed of the track (see :func:`speed_scale_vs_track`).

    Attributes
    ----------
    scale : float
        rms of the displacements integrated from ``u_m_s``/``v_m_s`` over the rms of the
        track's displacements (1 when both are in m/s and metres).
    correlation : float
        Magnitude of the complex correlation of the two displacement series (1 = same
        shape; small = the velocities do not describe this track).
    rms_displacement_m : float
        The larger of the two rms displacements [m].
    time_span_s : tuple of float
        First and last ``time_s`` of the samples used.
    misfit_deg : float
        Median angle [deg] between the velocities' displacements and the track's, over the
        windows in which both moved at least :data:`SPEED_CHECK_MISFIT_MIN_M` (near 0 when
        the heading and the velocities describe the track, a turning ship included, and
        position noise small against 2 m; tens of degrees on a slow drift with metres of
        GNSS noise); NaN with fewer such windows than three lags' worth.
    """

    scale: float
    correlation: float
    rms_displacement_m: float
    time_span_s: tuple[float, float]
    misfit_deg: float = float("nan")


def speed_scale_vs_track(time_s, north_m, east_m, heading_deg, u_m_s, v_m_s, *,
                         lag_s: float = SPEED_CHECK_LAG_S) -> SpeedScale | None:
    """Compare the logged body velocities with the motion of the logged track.

    The body velocities ``(u, v)`` are rotated into NED with the logged heading and
    integrated (trapezoid) within each gap-free run of finite samples; their
    displacements over ``lag_s`` are compared with the track's displacements over the
    same windows, as complex numbers ``north + i east``. Over a 20-s lag GNSS noise
    (~1 m) is small against the displacement of a moving ship, and a constant heading
    offset does not change the scale.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Sample times [s], finite and strictly increasing.
    north_m, east_m, heading_deg, u_m_s, v_m_s : array_like, shape (N,)
        The log's columns (NaN samples split the runs).
    lag_s : float, default 20
        Displacement lag [s], > 0 (ValueError naming it otherwise; TypeError for text).

    Returns
    -------
    SpeedScale or None
        None when no run is longer than the lag.
    """
    lag_s = check_number("speed_scale_vs_track: lag_s", lag_s, lo=0.0, lo_open=True)  # NaN failed in int()
    t = np.asarray(time_s, dtype=float)
    cols = [np.asarray(c, dtype=float) for c in (north_m, east_m, heading_deg, u_m_s, v_m_s)]
    _check_same_length("speed_scale_vs_track", t, **dict(zip(("north_m", "east_m", "heading_deg", "u_m_s", "v_m_s"),
                                                             cols)))
    n = t.size
    if n < 3:
        return None
    finite = np.all(np.isfinite(np.vstack(cols)), axis=0)
    dt = float(np.median(np.diff(t)))
    lag = max(1, int(round(lag_s / dt)))
    zv_all, zt_all, used = [], [], []
    for seg in split_segments(t):
        ok = finite[seg]
        idx = np.arange(seg.start, seg.stop)
        # runs of finite samples inside the segment
        edges = np.flatnonzero(np.diff(np.concatenate(([0], ok.astype(int), [0]))))
        for a, b in zip(edges[::2], edges[1::2]):
            rows = idx[a:b]
            if rows.size <= lag:
                continue
            psi = np.radians(cols[2][rows])
            c, s = np.cos(psi), np.sin(psi)
            vn = c * cols[3][rows] - s * cols[4][rows]
            ve = s * cols[3][rows] + c * cols[4][rows]
            tr = t[rows]
            h = np.diff(tr)
            pn = np.concatenate(([0.0], np.cumsum(0.5 * h * (vn[1:] + vn[:-1]))))
            pe = np.concatenate(([0.0], np.cumsum(0.5 * h * (ve[1:] + ve[:-1]))))
            zv = (pn[lag:] - pn[:-lag]) + 1j * (pe[lag:] - pe[:-lag])
            zt = (cols[0][rows][lag:] - cols[0][rows][:-lag]) + 1j * (cols[1][rows][lag:] - cols[1][rows][:-lag])
            zv_all.append(zv)
            zt_all.append(zt)
            used.append((tr[0], tr[-1]))
    if not zv_all:
        return None
    zv = np.concatenate(zv_all)
    zt = np.concatenate(zt_all)
    # squared magnitudes by hand: np.linalg.norm's dot on the strided real and imaginary
    # parts took milliseconds on a long log
    p_v, p_t = zv.real ** 2 + zv.imag ** 2, zt.real ** 2 + zt.imag ** 2
    s_v = float(np.sqrt(np.mean(p_v)))
    s_t = float(np.sqrt(np.mean(p_t)))
    denom = float(np.sqrt(np.sum(p_v) * np.sum(p_t)))
    corr = float(np.abs(np.vdot(zv, zt)) / denom) if denom > 0 else 0.0
    scale = s_v / s_t if s_t > 0 else np.inf
    span = (float(min(u[0] for u in used)), float(max(u[1] for u in used)))
    # direction window by window (a constant offset and a turning ship alike); GNSS noise
    # stays below the displacement gate
    moved = (np.abs(zv) >= SPEED_CHECK_MISFIT_MIN_M) & (np.abs(zt) >= SPEED_CHECK_MISFIT_MIN_M)
    misfit = (float(np.degrees(np.median(np.abs(np.angle(np.conj(zv[moved]) * zt[moved])))))
              if moved.sum() >= 3 * lag else float("nan"))
    return SpeedScale(scale, corr, max(s_v, s_t), span, misfit)


def _speed_unit_guess(scale: float) -> str:
    for factor, unit in ((KNOTS_PER_M_S, "knots"), (KM_H_PER_M_S, "km/h")):
        if abs(np.log(scale / factor)) < np.log(1.15):
            return f"looks like {unit}"
    if scale > 1e3:
        return "north_m/east_m hardly move: positions in degrees of latitude/longitude?"
    if scale < 1.0:
        return "the velocities are too small for the track: another unit, or positions in feet?"
    return "another unit?"


#: Relative tolerance of the accepted sample spacing's ends (rounding of the logged times).
_SPACING_RTOL = 1e-3


def _check_time(t: np.ndarray, source: str) -> None:
    nonfinite = ~np.isfinite(t)
    if nonfinite.any():
        i = int(np.argmax(nonfinite))
        raise LogFormatError(f"time_s: non-finite value {t[i]} at row {i}; expected finite, strictly "
                             f"increasing times{_where(source)}", column="time_s", row=i)
    not_incr = np.diff(t) <= 0.0
    if not_incr.any():
        i = int(np.argmax(not_incr)) + 1
        raise LogFormatError(
            f"time_s: not strictly increasing at row {i} (time_s {seconds_text(t[i])} after "
            f"{seconds_text(t[i - 1])}); expected strictly increasing times{_where(source)}",
            column="time_s", row=i, time_s=float(t[i]),
        )
    if t.size >= 2:
        med = float(np.median(np.diff(t)))
        # with a tolerance: times of 100 Hz samples are not exact in binary (a median step of
        # 0.0099999999999998, or 0.00999999 in epoch seconds) and were refused as 0.01 s
        if not MIN_SAMPLE_SPACING_S * (1.0 - _SPACING_RTOL) <= med <= MAX_SAMPLE_SPACING_S * (1.0 + _SPACING_RTOL):
            hint = "milliseconds" if med > MAX_SAMPLE_SPACING_S else "minutes or hours"
            raise LogFormatError(
                f"time_s: median sample spacing {med:g} between time_s {seconds_text(t[0])} and "
                f"{seconds_text(t[-1])}; the log format expects seconds (nominal 1 Hz; spacing {MIN_SAMPLE_SPACING_S:g}..{MAX_SAMPLE_SPACING_S:g} s "
                f"accepted): is time_s in {hint}?{_where(source)}",
                column="time_s",
            )


def _check_angle_unit(col: str, t: np.ndarray, x: np.ndarray, source: str, rate=None) -> None:
    is_rad, reason = angle_looks_like_radians(t, x, rate)
    if is_rad:
        ok = np.isfinite(x)
        raise LogFormatError(
            f"{col}: values span {np.min(x[ok]):.2f}..{np.max(x[ok]):.2f}, which looks like radians ({reason}); "
            f"the log format expects degrees (column {col}; rows with time_s "
            f"{seconds_text(t[0])}..{seconds_text(t[-1])}){_where(source)}",
            column=col,
        )


def _validate(df: pd.DataFrame, channel_names, rotatable, source: str, warn_unknown: bool,
              allow_missing: bool = False, writing: bool = False, vessel_name: str | None = None,
              unit_statistics: bool = True, rudders=frozenset()) -> None:
    """Check ``df`` against the log format (:data:`hybridship.logs.columns.COLUMNS`).

    The checks run in this order, so that every message can quote ``time_s``: column
    names; ``time_s``; each fixed-name column parsed (and required ones finite); each
    column's own rules (range, allowed values, angle unit); the rules between columns
    (yaw rate against heading, speed against track); the per-channel columns. Without
    ``unit_statistics`` the judgements of :func:`check_units_on_whole_log` are left out,
    for a caller that makes them on the whole log. ``rudders``: the channels that are rudders
    (their angles are not judged for radians, see :func:`_check_channel_columns`).
    """
    if not isinstance(df, pd.DataFrame):
        raise TypeError(f"expected a pandas DataFrame, got {type(df).__name__}")
    names, rot = _check_thruster_args(channel_names, rotatable)
    cols = [str(c) for c in df.columns]
    _check_required_not_index(df, source)
    _check_column_names(cols, source)
    if len(df) == 0:
        raise LogFormatError(f"time_s: the log has no rows; expected at least one sample{_where(source)}",
                             column="time_s")
    t = _to_float(df, "time_s", source, None)
    _check_time(t, source)
    values = _parse_fixed_columns(df, cols, t, source, allow_missing)
    for name, x in values.items():
        _check_column_values(column_spec(name), x, t, source, values, unit_statistics)
    if "r_deg_s" in values and unit_statistics:
        _check_yaw_rate_vs_heading(t, values, source)
    if "u_m_s" in values and "v_m_s" in values and unit_statistics:
        _check_speed_vs_track(t, values, source)
    pair = [c for c in ("wind_speed_m_s", "wind_dir_deg") if c in cols]
    if len(pair) == 1:  # a speed without its direction (or the reverse) is no wind measurement
        other = ({"wind_speed_m_s", "wind_dir_deg"} - set(pair)).pop()
        unit = "".join(f"; found {c!r}, which looks like {other} in another unit: convert it and name it as "
                       f"the format says" for c in cols if _unit_variant_of(c) == other)
        raise LogFormatError(f"{other}: missing while {pair[0]} is logged; the wind needs both (or neither: "
                             f"a forecast without wind){unit}{_where(source)}", column=other)
    ignored = _check_channel_columns(df, cols, t, names, rot, source, vessel_name, unit_statistics, rudders)
    if ignored and warn_unknown:
        # writing keeps the user's columns in the file; reading leaves them out of the arrays
        what = "writing, though readers ignore them," if writing else "ignoring"
        # pandas names a header-less column "Unnamed: N": most often a DataFrame index saved with the data
        shown = [f"{c} (a column without a name: an index saved with to_csv?)" if re.fullmatch(r"Unnamed: \d+", c)
                 else c for c in ignored]
        warn_user(f"{source}: {what} {len(ignored)} column(s) not in the log format: {', '.join(shown)}",
                  LogFormatWarning)


def _check_required_not_index(df: pd.DataFrame, source: str) -> None:
    """Refuse a required column that is the frame's index (``df.set_index("time_s")``): it
    was said to be missing while the frame holds it."""
    cols = set(map(str, df.columns))
    indexed = [str(c) for c in df.index.names if str(c) in REQUIRED_COLUMNS and str(c) not in cols]
    if indexed:
        raise LogFormatError(f"{indexed[0]}: the DataFrame's index, not a column (a frame indexed by {indexed[0]} "
                             f"with set_index?); the log format expects it as a column: pass df.reset_index()"
                             f"{_where(source)}", column=indexed[0])


def _check_unique_names(cols: list[str], source: str) -> None:
    """Refuse a column name that appears more than once."""
    dup = sorted({c for c in cols if cols.count(c) > 1})
    if dup:
        raise LogFormatError(f"{dup[0]}: column appears more than once; column names must be unique{_where(source)}",
                             column=dup[0])


#: The first columns of a forecast table (``hybridship forecast --out``, ``ForecastResult.to_frame``).
FORECAST_TABLE_HEADER = ("start_time_s", "lead_s", "time_s")
#: Columns of the tables hybridship writes, by which one read as a log is recognised.
_OUTPUT_COLUMNS = {"start_time_s", "lead_s", "model", "horizon_s", "sigma", "coverage", "mae"}


def output_table_kind(cols: list[str]) -> str:
    """What a table with these columns is, if hybridship wrote it ("" if it may be a log)."""
    names = set(map(str, cols))
    if tuple(str(c) for c in cols[:3]) == FORECAST_TABLE_HEADER:
        return "a forecast table written by 'hybridship forecast'"
    if "time_s" not in names and {"model", "horizon_s"} <= names:
        return "a table written by a hybridship benchmark"
    return ""


def _check_column_names(cols: list[str], source: str) -> None:
    """Unique column names, and every required column present (pointing out one that
    looks like it in another unit, ``heading_rad``)."""
    _check_unique_names(cols, source)
    ours = output_table_kind(cols)
    if ours:
        raise LogFormatError(f"not a log: {ours} (its header has {', '.join(sorted(set(cols) & _OUTPUT_COLUMNS))}); "
                             f"keep such outputs out of a folder of logs{_where(source)}")
    missing = [c for c in REQUIRED_COLUMNS if c not in cols]
    if missing:
        one_name = len(cols) == 1 and any(sep in cols[0] for sep in (";", "\t"))
        # a name with spaces around it is said as such below, not as another unit
        like = {c: _unit_variant_of(c) for c in cols if _unit_variant_of(c) in missing and not one_name
                and c.strip() not in missing}
        typo = _misspelt(missing, cols, like)
        like = {c: f for c, f in like.items() if c not in typo}
        units = [f"found {c!r}, which looks like {f} in another unit" for c, f in like.items()
                 if c.lower() not in _UNIT_STEMS[f]]
        hints = [f"{'; '.join(units)}: convert it and name it as the format says"] if units else []
        hints += [f"found {c!r}, which may be {f}: name it so if it is in "
                  f"{_UNIT_WORDS.get(f.rsplit('_', 1)[-1], 'its unit')}, else convert it"
                  for c, f in like.items() if c.lower() in _UNIT_STEMS[f]]
        hints += [f"found {c!r}: did you mean {m!r}?" for c, m in typo.items()]
        hints += [f"found {c!r}, which is {c.strip()} with spaces around the name (a header written with "
                  f"', ' between names?)" for c in cols if c != c.strip() and c.strip() in missing][:1]
        hints += [f"the header is one name holding {sep!r}: the log format separates columns with ',' (and "
                  f"writes decimals with '.')" for sep in (";", "\t") if len(cols) == 1 and sep in cols[0]][:1]
        geo = [c for c in cols if _LATLON.fullmatch(c.strip().lower())]
        if geo and ({"north_m", "east_m"} & set(missing)):
            hints.append(f"found {', '.join(map(repr, geo))}: positions as latitude/longitude; the log format expects "
                         f"north_m and east_m in metres in a local north-east frame: convert them (for example "
                         f"to metres north and east of the first position)")
        if {"psi_hat [rad]", "n_prop [rps]"} <= set(map(str, cols)):    # the raw Esso Osaka FRT layout
            hints = ["an Esso Osaka free-running test file in its own layout: read it with "
                     "hybridship.datasets.esso_osaka.read_esso_osaka (it converts to the log format), or give the "
                     "folder to 'hybridship benchmark manoeuvre'"]
        hint = "".join(f"; {h}" for h in hints)
        shown = ", ".join(cols[:_FOUND_SHOWN]) + (f", ... ({len(cols) - _FOUND_SHOWN} more)"
                                                  if len(cols) > _FOUND_SHOWN else "")
        raise LogFormatError(
            f"{missing[0]}: required column missing (missing: {', '.join(missing)}; required: "
            f"{', '.join(REQUIRED_COLUMNS)}; found: {shown or 'none'}){hint}{_where(source)}",
            column=missing[0],
        )


#: A latitude or longitude column name (positions in geographic coordinates, not metres).
_LATLON = re.compile(r"(lat|latitude|lon|lng|long|longitude)([ _\[(]*(deg|degrees|rad)?[\])]*)?")
#: How many of a log's columns a missing-column error lists.
_FOUND_SHOWN = 12
#: The unit suffixes of the required columns, in words.
_UNIT_WORDS = {"s": "seconds", "m": "metres", "deg": "degrees"}


def _misspelt(missing: list[str], cols: list[str], unit_variants: dict) -> dict:
    """Column -> the missing format column it looks like a misspelling of (another case, or a
    letter or two off; :func:`difflib.get_close_matches`). A column that also looks like the
    format column in another unit (``unit_variants``, ``heading_rad``) counts only when it is
    closer still (``heading_dg``), and one that differs by spaces around it is left to that hint."""
    import difflib

    lower = {c.lower(): c for c in cols}
    out = {}
    for m in missing:
        for low in difflib.get_close_matches(m, list(lower), n=1, cutoff=0.8):
            c = lower[low]
            if c.strip() != m and (c not in unit_variants or difflib.SequenceMatcher(None, low, m).ratio() >= 0.9):
                out[c] = m
    return out


def _parse_fixed_columns(df: pd.DataFrame, cols: list[str], t: np.ndarray, source: str,
                         allow_missing: bool) -> dict[str, np.ndarray]:
    """The fixed-name columns present besides ``time_s``, as floats, in spec order.

    Non-numeric values and infinities are refused; a missing sample in a column whose spec
    says ``finite`` too, unless ``allow_missing`` (then infinities are missing samples).
    """
    values: dict[str, np.ndarray] = {}
    for spec in COLUMNS:
        if spec.per_channel or spec.name == "time_s" or spec.name not in cols:
            continue
        x = _to_float(df, spec.name, source, t, inf_is_missing=spec.finite and allow_missing)
        bad = ~np.isfinite(x)
        if spec.finite and bad.any() and not allow_missing:
            i = int(np.argmax(bad))
            raise LogFormatError(
                f"{spec.name}: missing or non-finite value ({x[i]}) at {_row_at(t, i)}, {int(bad.sum())} such "
                f"row(s) in all; required columns must be finite{_where(source)}",
                column=spec.name, row=i, time_s=float(t[i]),
            )
        values[spec.name] = x
    return values


def _check_column_values(spec: ColumnSpec, x: np.ndarray, t: np.ndarray, source: str,
                         values: dict[str, np.ndarray], unit_statistics: bool = True) -> None:
    """One column's own rules from its spec: the plausible range, the allowed values, and
    (for an angle, with ``unit_statistics``) that it is not in radians. Missing samples pass."""
    if spec.bound is not None:
        bad = spec.bound.violated(x)
        if bad.any():
            raise _limit_error(spec.name, x, bad, t, f"{spec.bound.text(spec.unit)}; {spec.expects}", source)
    if spec.allowed:
        bad = np.isfinite(x) & ~np.isin(x, spec.allowed)
        if bad.any():
            allowed = " or ".join(f"{a:g}" for a in spec.allowed)
            raise _limit_error(spec.name, x, bad, t, f"is not {allowed}; {spec.expects}", source)
    if spec.angle and unit_statistics:
        _check_angle_unit(spec.name, t, x, source, values.get(spec.rate_column) if spec.rate_column else None)


def _check_yaw_rate_vs_heading(t: np.ndarray, values: dict[str, np.ndarray], source: str) -> None:
    """``r_deg_s`` against the rate of change of ``heading_deg``: refused when its sign is
    reversed (counter-clockwise convention), or its scale says rad/s or deg/s converted
    twice (see :func:`heading_looks_like_radians` for the correlation and scale rule). When
    another time unit fits the yaw rate and moves the ship along the track with ``u_m_s`` and
    ``v_m_s``, ``time_s`` is refused instead (minutes read as seconds make every rate 1/60
    of the logged one)."""
    ev = _rate_evidence(t, values["heading_deg"], values["r_deg_s"], 360.0)
    if ev is None:
        return
    corr, k = ev
    span = f"between time_s {seconds_text(t[0])} and {seconds_text(t[-1])}"
    if corr >= 0.3 and not 1.0 / _RATE_SCALE_SPLIT <= k <= _RATE_SCALE_SPLIT:
        _check_time_unit_by_rates(t, values, k, span, source)
    if corr <= -0.3:
        raise LogFormatError(
            f"r_deg_s: has the opposite sign of the rate of change of heading_deg {span} "
            f"(correlation {corr:.2f}); the log format expects the yaw rate positive clockwise seen "
            f"from above (NED): is the sign reversed (counter-clockwise / ENU convention)?{_where(source)}",
            column="r_deg_s")
    if corr >= 0.3 and k < 1.0 / _RATE_SCALE_SPLIT:
        raise LogFormatError(
            f"r_deg_s: is {k:.4f} times the rate of change of heading_deg {span} (about 1 expected "
            f"for deg/s, 0.0175 for rad/s): looks like rad/s; the log format expects deg/s (or, if r_deg_s is in "
            f"deg/s, time_s is in minutes: 1/60 is as close){_where(source)}",
            column="r_deg_s")
    if corr >= 0.3 and k > _RATE_SCALE_SPLIT:
        raise LogFormatError(
            f"r_deg_s: is {k:.1f} times the rate of change of heading_deg {span} (about 1 expected "
            f"for deg/s): converted from rad/s twice?; the log format expects deg/s{_where(source)}",
            column="r_deg_s")


#: Other time units than seconds, as the factor that turns them into seconds.
_OTHER_TIME_UNITS = ((60.0, "minutes"), (3600.0, "hours"), (1e-3, "milliseconds"))


def _time_unit_by_track(t: np.ndarray, values: dict[str, np.ndarray]) -> tuple[str, float] | None:
    """The other time unit (and its factor to seconds) under which ``u_m_s``, ``v_m_s`` move the
    ship along the track (north_m, east_m) as they should, when they do not in seconds; None
    when no unit does, or the track does not move enough to tell."""
    if "u_m_s" not in values or "v_m_s" not in values:
        return None
    for factor, unit in _OTHER_TIME_UNITS:
        sc = speed_scale_vs_track(t * factor, values["north_m"], values["east_m"], values["heading_deg"],
                                  values["u_m_s"], values["v_m_s"])
        if (sc is not None and sc.rms_displacement_m >= SPEED_CHECK_MIN_DISPLACEMENT_M
                and sc.correlation >= SPEED_CHECK_MIN_CORRELATION
                and 1.0 / _SPEED_SCALE_SPLIT <= sc.scale <= _SPEED_SCALE_SPLIT):
            return unit, factor
    return None


def _time_unit_error(unit: str, factor: float, why: str, source: str) -> LogFormatError:
    """The refusal of ``time_s`` in ``unit`` (``factor`` to seconds), saying ``why``."""
    return LogFormatError(
        f"time_s: looks like {unit}: {why}; with time_s x {factor:g} (as seconds) u_m_s, v_m_s move the ship "
        f"along the track (north_m, east_m); the log format expects seconds{_where(source)}", column="time_s")


def _check_time_unit_by_rates(t: np.ndarray, values: dict[str, np.ndarray], k: float, span: str,
                              source: str) -> None:
    """Refuse ``time_s`` when the yaw rate is ``k`` times the heading's rate of change (far
    from 1) and in another time unit both the yaw rate and the speeds fit: two columns in
    other units are less likely than one time column. The yaw rate alone cannot tell
    minutes from rad/s (1/60 and pi/180 are 5 % apart); the speeds along a moving track can."""
    found = _time_unit_by_track(t, values)
    if found is not None and 1.0 / _RATE_SCALE_SPLIT <= k * found[1] <= _RATE_SCALE_SPLIT:
        raise _time_unit_error(*found, f"r_deg_s is {k:.3g} times the rate of change of heading_deg {span}", source)


def _check_speed_vs_track(t: np.ndarray, values: dict[str, np.ndarray], source: str) -> None:
    """``u_m_s``/``v_m_s`` against the motion of the track (:func:`speed_scale_vs_track`):
    refused when the two agree in shape but not in scale (knots, km/h); ``heading_deg``
    refused as radians when, read as radians, it turns them onto the track and read as
    degrees it does not; likewise north/east swapped (an ENU frame) and ``u_m_s`` or
    ``v_m_s`` with the opposite sign."""
    sc = speed_scale_vs_track(t, values["north_m"], values["east_m"], values["heading_deg"], values["u_m_s"],
                              values["v_m_s"])
    if sc is None or not 1.0 / _SPEED_SCALE_SPLIT <= sc.scale <= _SPEED_SCALE_SPLIT:
        # in minutes a short log has no 20-unit window, and a long one gives speeds 1/60 of the track's
        found = _time_unit_by_track(t, values)
        if found is not None:
            what = ("no 20-s window of the track" if sc is None else
                    f"u_m_s, v_m_s are {sc.scale:.3g} times the speed of the track")
            raise _time_unit_error(*found, what, source)
    if (sc is not None and sc.rms_displacement_m >= SPEED_CHECK_MIN_DISPLACEMENT_M
            and sc.correlation >= SPEED_CHECK_MIN_CORRELATION
            and not 1.0 / _SPEED_SCALE_SPLIT <= sc.scale <= _SPEED_SCALE_SPLIT):
        raise LogFormatError(
            f"u_m_s, v_m_s: the logged speed is {sc.scale:.3g} times the speed of the track "
            f"(north_m, east_m) over {SPEED_CHECK_LAG_S:g}-s windows between time_s {seconds_text(sc.time_span_s[0])} "
            f"and {seconds_text(sc.time_span_s[1])} (correlation {sc.correlation:.2f}); expected 1 for m/s "
            f"({KNOTS_PER_M_S:.2f} would be knots, {KM_H_PER_M_S:g} km/h): {_speed_unit_guess(sc.scale)}"
            f"{_where(source)}",
            column="u_m_s")
    h = values["heading_deg"]
    if (sc is not None and sc.misfit_deg > SPEED_CHECK_MAX_MISFIT_DEG and np.isfinite(h).any()
            and np.nanmax(np.abs(h)) <= _RAD_LIMIT):
        # a unit error, not a sensor fault: read as radians the same heading turns the
        # velocities onto the track (a fault in part of the log, or GNSS noise on a slow
        # drift, leaves both readings off the track and is left to the forecasts' flags)
        as_rad = speed_scale_vs_track(t, values["north_m"], values["east_m"], np.degrees(h), values["u_m_s"],
                                      values["v_m_s"])
        if as_rad.misfit_deg <= SPEED_CHECK_RADIANS_FIT_DEG:
            raise LogFormatError(
                f"heading_deg: looks like radians (with r_deg_s in rad/s too?): u_m_s, v_m_s turned into "
                f"north/east with heading_deg as degrees move {sc.misfit_deg:.0f} deg away from the track (north_m, "
                f"east_m), as radians {as_rad.misfit_deg:.0f} deg (medians over {SPEED_CHECK_LAG_S:g}-s windows "
                f"between time_s {seconds_text(sc.time_span_s[0])} and {seconds_text(sc.time_span_s[1])}); the log "
                f"format expects degrees{_where(source)}",
                column="heading_deg")
    if sc is not None and sc.misfit_deg > SPEED_CHECK_CONVENTION_MISFIT_DEG:
        # a frame or sign convention, not a sensor fault: read the other way, the velocities
        # follow the track (the start window's velocity check cannot see this on a slow drift)
        n, e, u, v = (values[c] for c in ("north_m", "east_m", "u_m_s", "v_m_s"))
        for column, other, expected in (
                ("north_m, east_m", (e, n, u, v), "north_m the northward and east_m the eastward position (NED): "
                                                  "are they swapped (an east/north or ENU frame)?"),
                ("u_m_s", (n, e, -u, v), "u_m_s positive forward: is its sign reversed?"),
                ("v_m_s", (n, e, u, -v), "v_m_s positive to starboard: is its sign reversed (positive to port)?")):
            alt = speed_scale_vs_track(t, other[0], other[1], h, other[2], other[3])
            if alt is not None and alt.misfit_deg <= SPEED_CHECK_RADIANS_FIT_DEG:
                raise LogFormatError(
                    f"{column}: u_m_s, v_m_s turned into north/east with heading_deg move {sc.misfit_deg:.0f} deg "
                    f"away from the track (north_m, east_m), but {alt.misfit_deg:.0f} deg with {column} read the "
                    f"other way (medians over {SPEED_CHECK_LAG_S:g}-s windows between time_s "
                    f"{seconds_text(sc.time_span_s[0])} and {seconds_text(sc.time_span_s[1])}); the log format "
                    f"expects {expected}{_where(source)}",
                    column=column.split(",")[0])


def _check_channel_columns(df: pd.DataFrame, cols: list[str], t: np.ndarray, names, rot, source: str,
                           vessel_name: str | None = None, unit_statistics: bool = True,
                           rudders=frozenset()) -> list[str]:
    """The per-channel columns (``<thruster>_rpm``, ``<thruster>_azimuth_deg``), matched by
    pattern: each names a known channel (when ``names`` is given), is numeric, and an angle
    is not in radians (with ``unit_statistics``; not a channel in ``rudders``: a rudder's
    angle in radians stays within +-pi/2, where the radian rule finds nothing, so the rule
    could only refuse a rudder held within a few degrees of amidships in degrees). Returns
    the columns to ignore (unknown names; angles of fixed thrusters), with a note each;
    ``truth_*`` columns are never interpreted."""
    ignored: list[str] = []
    for col in cols:
        if col in REQUIRED_COLUMNS or col in OPTIONAL_COLUMNS or col.startswith(TRUTH_PREFIX):
            continue
        match = channel_column(col)
        if match is None:
            variant = _unit_variant_of(col)
            ignored.append(col if variant is None else
                           f"{col} (looks like {variant} in another unit; the format expects {variant})")
            continue
        spec, name = match
        if names is not None and name not in names:
            # a log of another vessel, read with the default one: say which vessel was used
            other = "" if vessel_name is None else (f"; the vessel used is {vessel_name!r}: is the log from another "
                                                    f"vessel? use its vessel file (--vessel, where a command takes "
                                                    f"one) or a model trained on that vessel's logs")
            raise LogFormatError(
                f"{col}: names unknown thruster or rudder '{name}'; the vessel's thrusters and rudders: "
                f"{', '.join(names) or 'none'} "
                f"(expected columns <thruster>_rpm, <thruster>_azimuth_deg and <rudder>_azimuth_deg){_where(source)}"
                f"{other}",
                column=col,
            )
        x = _to_float(df, col, source, t)  # numeric, no infinities
        if spec.rotatable_only and rot is not None and not rot[names.index(name)]:
            ignored.append(f"{col} (thruster '{name}' is not rotatable)")
            continue
        if spec.bound is not None and spec.bound.violated(x).any():
            raise _limit_error(col, x, spec.bound.violated(x), t, f"{spec.bound.text(spec.unit)}; {spec.expects}",
                               source)
        if spec.angle and unit_statistics and name not in rudders:
            _check_angle_unit(col, t, x, source)
    return ignored


def validate_log(
    df: pd.DataFrame,
    *,
    channel_names: Sequence[str] | None = None,
    rotatable: Sequence[bool] | None = None,
    source: str = "log",
    allow_missing: bool = False,
) -> None:
    """Check a log DataFrame against the log format; raise on the first problem.

    Parameters
    ----------
    df : pandas.DataFrame
        The log, one row per sample (never modified).
    channel_names : sequence of str, optional
        Command channels of the vessel file (thrusters, then rudders). When given, every ``<name>_rpm`` /
        ``<name>_azimuth_deg`` column must name one of them.
    rotatable : sequence of bool, optional
        Per thruster, whether it is an azimuth thruster; an azimuth column of a fixed
        thruster is reported (warning) and ignored.
    source : str, default "log"
        Where the data come from (a file name), quoted in messages.
    allow_missing : bool, default False
        Accept missing (empty, NaN) or infinite values in ``north_m``, ``east_m`` and
        ``heading_deg`` as missing samples (forecast-time mode: :mod:`hybridship.forecast_inputs.start_window`
        decides per forecast start whether enough valid samples remain). ``time_s`` must
        still be finite and strictly increasing (:func:`hybridship.logs.ingest.sort_samples`
        repairs late and duplicated samples first).

    Raises
    ------
    LogFormatError
        On the first violation found; see the module docstring for the checks and
        :func:`heading_looks_like_radians` for the heading unit rule.
    ValueError
        If ``rotatable`` does not match ``channel_names``.

    Warns
    -----
    LogFormatWarning
        Once, listing every column that is neither in the format nor ``truth_*``.
    """
    _validate(df, channel_names, rotatable, source, warn_unknown=True, allow_missing=allow_missing)


def log_header(path) -> list[str] | None:
    """A log file's column names from its header alone (Parquet: its schema), without reading
    the rows; None when the file cannot be read as a log (empty, binary, damaged)."""
    path = Path(path)
    try:
        if path.name.lower().endswith((".parquet", ".pq")):
            import pyarrow.parquet as pq

            return [str(c) for c in pq.read_schema(path).names]
        return [str(c) for c in pd.read_csv(path, nrows=0).columns]    # gzip by extension
    except Exception:       # any reader's failure: not readable as a log here
        return None


def check_log_against_vessel(log, vessel, *, source: str | None = None, allow_missing: bool = False,
                             unit_statistics: bool = True) -> None:
    """Validate a log and check it against a vessel file's thrusters.

    Besides :func:`validate_log` with the vessel's thruster names, refuses (with a
    :class:`LogFormatError` naming the column, row and time where relevant):

    * ``|<name>_rpm|`` above ``RPM_UNIT_FACTOR`` (1.25) times the thruster's ``max_rpm``:
      a unit error (motor rpm before the gear, rev/s x 60 twice, ...);
    * an azimuth thruster whose ``<name>_rpm`` is logged but not its ``<name>_azimuth_deg``
      (the forecast would take its thrust as pointing forward);
    * some thrusters' ``<name>_rpm`` logged and others' not (the forecast would take the
      missing ones as stopped);
    * no ``<name>_rpm`` at all while ``dp_active`` is 1 somewhere, or absent (the
      forecast would take a station-keeping vessel as drifting without thrust);
    * a rudder's ``<name>_azimuth_deg`` missing while thruster rpm are logged, or a
      ``<rudder>_rpm`` column (a rudder has no rpm);
    * without ``allow_missing`` (training), a thruster or rudder column (or ``dp_active``)
      that holds no value in any row counts as missing in the rules above (a dead channel
      exported as an empty column would otherwise be trained on as a stopped thruster or a
      centred rudder);
    * every logged thruster's rpm within +-1 in ``RPM_SIGN_MIN_SAMPLES`` (60) or more samples
      of station keeping with thrust (for thrusters whose ``max_rpm`` is at least 20): a
      fraction of ``max_rpm`` or of full thrust logged as rpm;
    * an azimuth thruster whose rpm is negative in at least ``RPM_SIGN_MIN_SAMPLES`` (60)
      samples and never positive: the log format's sign is that of the thrust along the
      thruster axis, and an azimuth thruster turns rather than reverses, so such a log most
      likely carries the shaft's rotation direction (a counter-rotating propeller). Tunnel
      thrusters push either way and fixed propellers may back for a whole log: not checked.

    Parameters
    ----------
    log : pandas.DataFrame or path
        The log (never modified); a path is read with :func:`read_log`.
    vessel : hybridship.vessel.Vessel or str or path
        A validated vessel, or a packaged vessel name / vessel file.
    source : str, optional
        Quoted in messages (default: the file name, or "log").
    allow_missing : bool, default False
        As in :func:`validate_log`.
    unit_statistics : bool, default True
        False leaves out the judgements of a column's unit that rest on its statistics
        (the angle units, the yaw rate against the heading, the speed against the track,
        rpm as fractions, an azimuth thruster's rpm sign), for a caller that makes them on
        the whole log with :func:`check_units_on_whole_log` (a forecast that reads part of
        a log).

    Raises
    ------
    LogFormatError
    hybridship.vessel.VesselFileError
        If ``vessel`` names an invalid vessel file.
    """
    from hybridship.vessel import Vessel, load_vessel

    v = vessel if isinstance(vessel, Vessel) else load_vessel(vessel)
    if isinstance(log, (str, os.PathLike)):
        source = source or str(log)
        df = read_log(log, validate=False)
    else:
        df = log
    source = source or "log"
    _validate(df, v.channel_names, v.rotatable, source, warn_unknown=True, allow_missing=allow_missing,
              vessel_name=v.name, unit_statistics=unit_statistics, rudders=_rudder_names(v))
    t = _to_float(df, "time_s", source, None)
    # a command column without one value logs nothing: in training it counts as absent (its
    # thruster would be taken as stopped, its angle as 0); a forecast judges it per start
    blank = set() if allow_missing else _blank_channel_columns(v, df, t, source)
    cols = set(map(str, df.columns)) - blank
    _check_all_or_no_rpm(v, cols, source, blank)
    _check_no_rudder_rpm(v, cols, source)
    _check_rudder_angles_logged(v, cols, source, blank)
    _check_rpm_while_station_keeping(v, df, cols, t, source, blank)
    if unit_statistics:
        _check_rpm_not_fractions(v, lambda c: _to_float(df, c, source, t), cols, len(df), source)
    for th in v.thrusters:
        if column_spec("<thruster>_rpm").for_channel(th.name) in cols:
            _check_thruster_columns(v, th, df, cols, t, source, rpm_sign=unit_statistics, blank=blank)


def _rudder_names(v) -> frozenset:
    """The names of the vessel's rudders (channels whose angle is not judged for radians)."""
    return frozenset(r.name for r in getattr(v, "rudders", None) or [])


def _blank_channel_columns(v, df: pd.DataFrame, t: np.ndarray, source: str) -> set[str]:
    """The vessel's command columns (``<name>_rpm``, ``<name>_azimuth_deg``, ``dp_active``)
    that are in ``df`` without a single finite value (a dead channel exported as an empty
    column; an empty ``dp_active`` is read as its default, 1, as an absent one)."""
    names = [column_spec(s).for_channel(c) for c in v.channel_names for s in ("<thruster>_rpm",
                                                                             "<thruster>_azimuth_deg")]
    names.append("dp_active")
    return {c for c in names if c in df.columns and not np.isfinite(_to_float(df, c, source, t)).any()}


def _absent(col: str, blank: set) -> str:
    """How a required command column is absent, for messages."""
    return "without a value in any row" if col in blank else "missing"


def _rpm_columns(v) -> list[str]:
    """The vessel's thruster rpm columns, in vessel-file order (rudders have no rpm)."""
    return [column_spec("<thruster>_rpm").for_channel(th.name) for th in v.thrusters]


def _check_all_or_no_rpm(v, cols: set, source: str, blank: set = frozenset()) -> None:
    """Some thrusters' rpm logged and others' not (absent, or in ``blank``: no value): the
    forecast would take the missing ones as stopped."""
    rpm_cols = _rpm_columns(v)
    miss = [c for c in rpm_cols if c not in cols]
    have = [c for c in rpm_cols if c in cols]
    if have and miss:
        raise LogFormatError(
            f"{miss[0]}: {_absent(miss[0], blank)} while {', '.join(have)} are logged; expected the rpm of every "
            f"thruster of vessel {v.name!r} ({', '.join(rpm_cols)}), else the forecast would take "
            f"{', '.join(miss)} as stopped{_where(source)}", column=miss[0])


def _check_no_rudder_rpm(v, cols: set, source: str) -> None:
    """A ``<rudder>_rpm`` column: a rudder has no propeller, and its values would be taken
    as the rudder channel's rpm (documented as 0 in :attr:`LogArrays.rpm`)."""
    for rud in getattr(v, "rudders", None) or []:
        col = column_spec("<thruster>_rpm").for_channel(rud.name)
        if col in cols:
            raise LogFormatError(
                f"{col}: {rud.name!r} is a rudder of vessel {v.name!r} and has no rpm; expected <thruster>_rpm "
                f"for the thrusters ({', '.join(_rpm_columns(v)) or 'none'}) and {rud.name}_azimuth_deg for the "
                f"rudder's angle{_where(source)}", column=col)


def _check_rudder_angles_logged(v, cols: set, source: str, blank: set = frozenset()) -> None:
    """A rudder's angle missing (or in ``blank``: no value) while thruster rpm are logged:
    the forecast would take the rudder as amidships."""
    if not any(c in cols for c in _rpm_columns(v)):
        return
    for rud in getattr(v, "rudders", None) or []:
        col = column_spec("<thruster>_azimuth_deg").for_channel(rud.name)
        if col not in cols:
            raise LogFormatError(
                f"{col}: {_absent(col, blank)} while thruster rpm are logged; expected the angle of rudder "
                f"{rud.name!r} of vessel {v.name!r} in degrees (positive to starboard), else the forecast would "
                f"take it as amidships{_where(source)}", column=col)


def _check_rpm_not_fractions(v, column, cols: set, n_rows: int, source: str) -> None:
    """Every logged thruster's rpm within +-1 in ``RPM_SIGN_MIN_SAMPLES`` or more samples of
    station keeping with thrust: a fraction of ``max_rpm`` (or of full thrust), not rpm. Only
    station keeping counts: after a failure the rpm decays towards zero. ``column(name)``
    gives a column of the ``n_rows`` rows as floats."""
    logged = [(th, c) for th, c in zip(v.thrusters, _rpm_columns(v)) if c in cols]
    if not logged or min(th.max_rpm for th, _ in logged) < 20.0:
        return
    dp = column("dp_active") == 1.0 if "dp_active" in cols else np.ones(n_rows, bool)
    x = np.column_stack([column(c) for _, c in logged])[dp]
    with_thrust = np.isfinite(x).all(axis=1) & (x != 0.0).any(axis=1)
    if with_thrust.sum() >= RPM_SIGN_MIN_SAMPLES and np.nanmax(np.abs(x)) <= 1.0:
        col = logged[0][1]
        raise LogFormatError(
            f"{col}: every thruster's rpm is within +-1 (largest {np.nanmax(np.abs(x)):.3g}) in all "
            f"{int(with_thrust.sum())} samples of station keeping with thrust; expected rpm (max_rpm of "
            f"thruster {logged[0][0].name!r} is {logged[0][0].max_rpm:g}), not a fraction of max_rpm or of "
            f"full thrust{_where(source)}", column=col)
    _warn_some_rpm_fractions(logged, x, source)


def _warn_some_rpm_fractions(logged, x: np.ndarray, source: str) -> None:
    """A LogFormatWarning for each thruster whose rpm stays within +-1 in ``RPM_SIGN_MIN_SAMPLES``
    or more of its non-zero samples of station keeping (``x``, one column per thruster of
    ``logged``) while another thruster's reaches more: a fraction of ``max_rpm`` logged
    for some thrusters only. A warning, not a refusal: a stopped thruster whose sensor reads
    noise looks the same."""
    big = np.abs(np.where(np.isfinite(x), x, 0.0)).max(axis=0, initial=0.0)      # largest |rpm| per thruster
    for k, (th, col) in enumerate(logged):
        on = np.isfinite(x[:, k]) & (x[:, k] != 0.0)
        other = int(np.argmax(np.where(np.arange(len(logged)) == k, -1.0, big)))
        if on.sum() >= RPM_SIGN_MIN_SAMPLES and big[k] <= 1.0 and big[other] > 1.0:
            warn_user(
                f"{col}: within +-1 (largest {big[k]:.3g}) in all {int(on.sum())} of its non-zero samples of "
                f"station keeping, while {logged[other][1]} reaches {big[other]:.4g} rpm; expected rpm (max_rpm "
                f"of thruster {th.name!r} is {th.max_rpm:g}): a fraction of max_rpm? (a stopped thruster whose "
                f"sensor reads noise looks the same; the values are used as rpm){_where(source)}",
                LogFormatWarning)


def _check_rpm_while_station_keeping(v, df: pd.DataFrame, cols: set, t: np.ndarray, source: str,
                                     blank: set = frozenset()) -> None:
    """No thruster rpm at all (absent, or in ``blank``: no value) while ``dp_active`` is 1
    somewhere, or absent (taken as 1): the forecast would take a station-keeping vessel as
    drifting without thrust."""
    rpm_cols = _rpm_columns(v)
    if not rpm_cols or any(c in cols for c in rpm_cols):
        return
    dp = _to_float(df, "dp_active", source, t) if "dp_active" in cols else None
    if dp is None or np.any(dp == 1.0):
        i = 0 if dp is None else int(np.argmax(dp == 1.0))
        what = "columns" if not blank & set(rpm_cols) else "values (the columns hold no value in any row)"
        raise LogFormatError(
            f"{rpm_cols[0]}: no thruster rpm {what} while dp_active is "
            f"{'absent (taken as 1)' if dp is None else f'1 at {_row_at(t, i)}'}; expected "
            f"{', '.join(rpm_cols)} for vessel {v.name!r}, or dp_active = 0 for a vessel "
            f"drifting without thrust{_where(source)}", column=rpm_cols[0])


def _check_thruster_columns(v, th, df: pd.DataFrame, cols: set, t: np.ndarray, source: str,
                            rpm_sign: bool = True, blank: set = frozenset()) -> None:
    """A logged thruster's rpm within its spec's bound on the vessel's ``max_rpm``; an
    azimuth thruster's angle logged with it, and (with ``rpm_sign``) its rpm sign that of
    the thrust (not the shaft's rotation direction: negative in ``RPM_SIGN_MIN_SAMPLES``
    samples and never positive); ``blank``: columns without a value, named so when missing."""
    spec = column_spec("<thruster>_rpm")
    col = spec.for_channel(th.name)
    x = _to_float(df, col, source, t)
    bad = np.abs(x) > spec.vessel_factor * th.max_rpm
    if bad.any():
        raise _limit_error(col, x, bad, t, f"exceeds {spec.vessel_factor:g} x max_rpm ({th.max_rpm:g} rpm) of "
                           f"thruster {th.name!r} of vessel {v.name!r} in magnitude; {spec.expects}", source)
    if th.type != "azimuth":
        return
    az_col = column_spec("<thruster>_azimuth_deg").for_channel(th.name)
    if az_col not in cols:
        raise LogFormatError(
            f"{az_col}: {_absent(az_col, blank)} while {col} is logged; thruster {th.name!r} of vessel {v.name!r} "
            f"is an azimuth thruster and its thrust direction is needed (expected column {az_col} "
            f"in degrees, 0 = forward, positive to starboard){_where(source)}",
            column=az_col)
    if rpm_sign:
        _check_rpm_sign(col, x, t, source)


def _check_rpm_sign(col: str, x: np.ndarray, t: np.ndarray, source: str) -> None:
    """An azimuth thruster's rpm negative in ``RPM_SIGN_MIN_SAMPLES`` samples and never
    positive: the shaft's rotation direction, not the sign of the thrust."""
    neg = np.isfinite(x) & (x < 0.0)
    pos = np.isfinite(x) & (x > 0.0)
    if neg.sum() >= RPM_SIGN_MIN_SAMPLES and not pos.any():
        i = int(np.argmax(neg))
        raise LogFormatError(
            f"{col}: negative in all {int(neg.sum())} non-zero samples (first at {_row_at(t, i)}) and "
            f"never positive; the log format expects signed rpm with positive = thrust forward along "
            f"the thruster axis: does the column carry the shaft's rotation direction (e.g. a "
            f"counter-rotating propeller) instead?{_where(source)}",
            column=col, row=i, time_s=float(t[i]))


def check_units_on_whole_log(df: pd.DataFrame, vessel, *, source: str = "log") -> None:
    """The judgements of a column's unit or convention that rest on its statistics, on the
    whole of a sorted log (``time_s`` finite, strictly increasing): an angle in radians
    (heading, wind direction, azimuths), ``r_deg_s`` against the heading, ``u_m_s``/``v_m_s``
    against the track, rpm logged as fractions, an azimuth thruster's rpm sign.

    A forecast checks only the rows it reads; the evidence on a column's unit lies anywhere
    in the log, so these run on the whole log too, and refuse what training refuses, with
    the same message. Samples that are missing, not numbers or infinite are left out here:
    such faults outside the rows read do not matter to a forecast.
    """
    cols = set(map(str, df.columns))
    num = {}

    def column(name: str) -> np.ndarray:
        """The column as new floats, missing, text and infinities as NaN (made once)."""
        if name not in num:
            x = pd.to_numeric(df[name], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
            num[name] = np.where(np.isinf(x), np.nan, x)
        return num[name]

    t = column("time_s")
    values = {c: column(c) for c in REQUIRED_COLUMNS + OPTIONAL_COLUMNS if c in cols}
    for name in ("heading_deg", "wind_dir_deg"):
        if name in values:
            _check_angle_unit(name, t, values[name], source, values.get(column_spec(name).rate_column or ""))
    for th_name, rot in zip(vessel.channel_names, vessel.rotatable):
        col = column_spec("<thruster>_azimuth_deg").for_channel(th_name)
        if rot and col in cols and th_name not in _rudder_names(vessel):
            _check_angle_unit(col, t, column(col), source)
    if "r_deg_s" in values:
        _check_yaw_rate_vs_heading(t, values, source)
    if "u_m_s" in values and "v_m_s" in values:
        _check_speed_vs_track(t, values, source)
    _check_rpm_not_fractions(vessel, column, cols, len(df), source)
    for th in vessel.thrusters:
        col = column_spec("<thruster>_rpm").for_channel(th.name)
        if th.type == "azimuth" and col in cols:
            _check_rpm_sign(col, column(col), t, source)


# --------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------


def _container(path: Path) -> str:
    name = path.name.lower()
    if name.endswith(".csv.gz"):
        return "csv.gz"
    if name.endswith(".csv"):
        return "csv"
    if name.endswith((".parquet", ".pq")):
        return "parquet"
    raise LogFormatError(f"{path}: unsupported file extension; expected one of {', '.join(_EXTENSIONS)}")


def _read_problem(kind: str, exc: BaseException) -> str:
    """What the parser's ``exc`` means for a log file, in plain words (not its internals)."""
    text = " ".join(str(exc).split())
    fields = re.search(r"Expected (\d+) fields in line (\d+), saw (\d+)", text)
    if fields:
        return (f"line {fields.group(2)} has {fields.group(3)} fields where the lines before it have "
                f"{fields.group(1)}; is the separator a comma?")
    quote = re.search(r"EOF inside string starting at row (\d+)", text)
    if quote:
        return (f"a quote (\") opened in data row {quote.group(1)} is never closed, so the rest of the file "
                f"reads as one text cell")
    if isinstance(exc, pd.errors.EmptyDataError):
        return "the file is empty: no header line"
    if isinstance(exc, UnicodeDecodeError):
        return _not_utf8(bytes(exc.object[:4096]))
    if kind == "parquet":
        return "not a Parquet file, or a damaged one"
    if kind == "csv.gz" and isinstance(exc, (EOFError, OSError)):
        return "not a complete gzip file: damaged or cut short"
    return f"unreadable: {text}" if text else "unreadable"


def _not_utf8(head: bytes) -> str:
    """Why bytes that are not UTF-8 are no log: text in another encoding, or binary data."""
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        return "UTF-16 text: save the file as UTF-8"
    if b"\x00" in head:
        return "not text: the file holds binary data"
    return "not UTF-8 text (Latin-1 or another encoding?): save the file as UTF-8"


#: Bytes read from a CSV log's end to find its last line (:func:`_cut_short_last_line`).
_TAIL_BYTES = 65536


def _cut_short_last_line(path: Path, n_fields: int) -> int | None:
    """The number of fields of a plain CSV file's last line when it was cut short, else None.

    Cut short: the file does not end with a line end and its last line has fewer fields than
    the header's ``n_fields``. pandas fills such a row's missing fields with NaN and reads its
    last, cut value as a number ("3" of "336.45"); a writer of the log format writes every
    field (empty cells for missing values), so a short last line is a file still being
    written or a copy interrupted. Only the file's last :data:`_TAIL_BYTES` are read.
    """
    import csv

    with open(path, "rb") as fh:
        size = fh.seek(0, os.SEEK_END)
        fh.seek(max(0, size - _TAIL_BYTES))
        tail = fh.read()
    if not tail or tail.endswith((b"\n", b"\r")):
        return None
    cut = max(tail.rfind(b"\n"), tail.rfind(b"\r"))     # a file with CR line ends, which pandas reads
    if cut < 0 and size > len(tail):
        return None                         # a line longer than the tail: not judged
    last = tail[cut + 1:].decode("utf-8", errors="replace")
    fields = next(csv.reader([last]), [])
    return len(fields) if len(fields) < n_fields else None


def read_log(
    path: str | os.PathLike,
    *,
    channel_names: Sequence[str] | None = None,
    rotatable: Sequence[bool] | None = None,
    validate: bool = True,
    allow_missing: bool = False,
) -> pd.DataFrame:
    """Read and validate a log file (CSV, ``.csv.gz`` or Parquet, by extension).

    Parameters
    ----------
    path : str or path-like
        The file; ``.csv``, ``.csv.gz``, ``.parquet`` or ``.pq``.
    channel_names, rotatable, allow_missing : optional
        As in :func:`validate_log`.
    validate : bool, default True
        False only parses the container (for repair tools such as
        :func:`hybridship.logs.ingest.sort_samples`, which validate afterwards).

    Returns
    -------
    pandas.DataFrame
        A new frame with all columns of the file (``truth_*`` and unknown ones included)
        and a fresh ``RangeIndex``.

    Raises
    ------
    LogFormatError
        If the file breaks the format (message names the file).
    FileNotFoundError
        If the file does not exist.
    """
    path = as_path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a folder; expected a log file")
    kind = _container(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: log file not found")
    if kind == "csv" and starts_with(path, b"\x1f\x8b"):
        raise LogFormatError(f"{path}: is gzip-compressed; name it {path.name}.gz (a .csv.gz log) or "
                             f"decompress it")
    if kind == "csv.gz" and path.stat().st_size and not starts_with(path, b"\x1f\x8b"):
        raise LogFormatError(f"{path}: cannot be read as a csv.gz log file (not gzip-compressed: plain text? "
                             f"name it {path.name[:-3]}, a .csv log, or compress it)")
    try:
        if kind == "parquet":
            df = pd.read_parquet(path)
        else:
            compression = "gzip" if kind == "csv.gz" else None
            df = pd.read_csv(path, compression=compression)
            # pandas renames a repeated name (north_m, north_m.1): the header as written
            # (empty names kept empty, not NaN: pandas gives each its own "Unnamed: N")
            header = pd.read_csv(path, compression=compression, header=None, nrows=1, dtype=str,
                                 keep_default_na=False)
            names = [str(c) for c in header.iloc[0]] if len(header) else []
    except PermissionError:
        raise
    except (pd.errors.EmptyDataError, pd.errors.ParserError, EOFError, OSError, UnicodeDecodeError,
            ValueError) as exc:
        # a truncated archive, a plain file named .csv.gz, an empty or binary file: name the
        # file and say what it should be, not the parser's internals
        raise LogFormatError(f"{path}: cannot be read as a {kind} log file ({_read_problem(kind, exc)})") from None
    indexed = [str(c) for c in df.index.names if str(c) in REQUIRED_COLUMNS and str(c) not in map(str, df.columns)]
    if kind == "parquet" and indexed:   # else "required column missing" while the file holds it
        raise LogFormatError(f"{indexed[0]}: stored as the Parquet file's index, not as a column (a DataFrame "
                             f"indexed by {indexed[0]} saved with to_parquet?); the log format expects it as a "
                             f"column: save the frame with index=False after reset_index(){_where(str(path))}",
                             column=indexed[0])
    if kind != "parquet":
        _check_unique_names([c for c in names if c], str(path))
        if len(names) > 1 and not isinstance(df.index, pd.RangeIndex):
            # pandas takes the first fields of rows longer than the header as their index,
            # and every column would hold the next one's values (a header of one name, with
            # ';' in it, is said as such by the column check)
            raise LogFormatError(f"{path}: cannot be read as a {kind} log file (its data rows have "
                                 f"{len(names) + df.index.nlevels} fields where the header has {len(names)}: a ',' "
                                 f"at the end of each line, or a column without a name?)")
    if kind == "csv" and len(df):
        got = _cut_short_last_line(path, len(names))
        if got is not None:
            warn_user(f"{path}: the last line has {got} of the header's {len(names)} fields and no line end: "
                      f"cut short (a file still being written, or a copy interrupted); its row (row "
                      f"{len(df) - 1}) is left out", LogFormatWarning)
            df = df.iloc[:-1]
    df = df.reset_index(drop=True)
    if validate:
        _validate(df, channel_names, rotatable, str(path), warn_unknown=True, allow_missing=allow_missing)
    return df



def write_log(
    df: pd.DataFrame,
    path: str | os.PathLike,
    *,
    channel_names: Sequence[str] | None = None,
    rotatable: Sequence[bool] | None = None,
) -> None:
    """Validate a log and write it atomically (CSV, ``.csv.gz`` or Parquet, by extension).

    The data go to a temporary file in the destination directory, are flushed to disk,
    and only then replace ``path`` with :func:`os.replace`: readers never see a partial
    file, and an existing file stays untouched if validation or writing fails.

    Parameters
    ----------
    df : pandas.DataFrame
        The log (never modified). The index is not written.
    path : str or path-like
        Destination; ``.csv``, ``.csv.gz``, ``.parquet`` or ``.pq``.
    channel_names, rotatable : optional
        As in :func:`validate_log`.

    Raises
    ------
    LogFormatError
        If ``df`` breaks the format (nothing is written).
    """
    path = as_path(path)
    kind = _container(path)
    _validate(df, channel_names, rotatable, str(path), warn_unknown=True, writing=True)

    def write(fh):
        if kind == "parquet":
            df.to_parquet(fh, index=False)
        elif kind == "csv.gz":
            # No file name and mtime 0 in the gzip header: the same data give
            # byte-identical files (and the temp file's name does not leak into it).
            with gzip.GzipFile(filename="", mode="wb", fileobj=fh, mtime=0) as gz:
                df.to_csv(gz, index=False)
        else:
            df.to_csv(fh, index=False)

    atomic_write(path, write)


# --------------------------------------------------------------------------------------
# Arrays
# --------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class LogArrays:
    """A validated log as arrays in SI units and radians (the arrays are read-only).

    Attributes
    ----------
    time_s : ndarray, shape (N,)
        Sample times [s].
    eta : ndarray, shape (N, 3)
        ``[north_m, east_m, psi_rad]``; heading unwrapped over the whole log (across a gap
        the smaller of the possible turns is assumed).
    nu : ndarray, shape (N, 3)
        ``[u_m_s, v_m_s, r_rad_s]``: logged values where present, derived elsewhere (see
        :func:`log_to_arrays`).
    nu_logged : ndarray of bool, shape (N, 3)
        True where the ``nu`` entry comes from the log, False where it was derived.
    rpm : ndarray, shape (N, K + R)
        Propeller speed commands [rpm] in ``channel_names`` order (0 in rudder channels).
    azimuth_rad : ndarray, shape (N, K + R)
        Angle commands per channel [rad]: a thruster's azimuth (0 for fixed thrusters and
        missing columns), then each rudder's angle delta (positive to starboard).
    wind : ndarray, shape (N, 2)
        ``[wind_speed_m_s, wind_dir_from_rad]``; zeros when the log has no wind. Missing
        samples are filled by holding the last logged value (see ``wind_logged``).
    has_wind : bool
        Whether the log has (any finite) wind speed and direction.
    dp_active : ndarray of int, shape (N,)
        1 while station keeping is active; all ones when the column is absent.
    segment_id : ndarray of int, shape (N,)
        Gap-free segment label per row, 0, 1, ... (see :func:`split_segments`).
    channel_names : tuple of str
        The vessel's command channels: its K thrusters in file order, then its R rudders.
    rotatable : tuple of bool
        Per channel, whether it has an angle (azimuth thruster or rudder).
    channel_logged : tuple of bool
        Per channel, whether its ``<name>_rpm`` column was in the log.
    wind_logged : ndarray of bool, shape (N,)
        True where both wind speed and direction were logged (finite) at that row, False
        where ``wind`` holds an earlier value or zeros (a dropped wind sensor). Default:
        ``has_wind`` everywhere.
    commands_logged : ndarray of bool, shape (N,)
        True where every command column the log has (``<name>_rpm``, ``<name>_azimuth_deg``,
        ``dp_active``) was finite at that row, False where ``rpm``, ``azimuth_rad`` or
        ``dp_active`` hold an earlier value (or a default before the first). Default: True
        everywhere.
    wind_columns : bool
        Whether the log had the wind columns, even without one valid sample in its rows (a
        dead wind sensor: ``has_wind`` is then False and a forecast flags ``wind_dropped``).
        Default: ``has_wind``.
    resorted_time_s : ndarray, shape (M,)
        Times of samples that arrived late, were duplicated or conflicted in the source
        and were re-sorted, dropped or removed by :func:`hybridship.logs.ingest.ingest`
        (flagged ``late_or_out_of_order`` at forecast time). Default: none.

    Notes
    -----
    ``eta`` may contain NaN only when built with ``allow_missing=True`` (forecast-time
    mode); ``nu`` is NaN where it could not be derived (single-sample segments, next to a
    missing position).
    """

    time_s: np.ndarray
    eta: np.ndarray
    nu: np.ndarray
    nu_logged: np.ndarray
    rpm: np.ndarray
    azimuth_rad: np.ndarray
    wind: np.ndarray
    has_wind: bool
    dp_active: np.ndarray
    segment_id: np.ndarray
    channel_names: tuple[str, ...]
    rotatable: tuple[bool, ...]
    channel_logged: tuple[bool, ...]
    wind_logged: np.ndarray | None = None
    resorted_time_s: np.ndarray | None = None
    commands_logged: np.ndarray | None = None
    wind_columns: bool = False

    def __post_init__(self):
        if self.has_wind:
            object.__setattr__(self, "wind_columns", True)
        if self.wind_logged is None:
            object.__setattr__(self, "wind_logged", np.full(self.time_s.shape[0], bool(self.has_wind)))
        if self.commands_logged is None:
            object.__setattr__(self, "commands_logged", np.ones(self.time_s.shape[0], dtype=bool))
        if self.resorted_time_s is None:
            object.__setattr__(self, "resorted_time_s", np.zeros(0))
        for name, v in list(vars(self).items()):
            if isinstance(v, np.ndarray) and v.flags.writeable:
                # a read-only copy: the caller's own array stays writeable, and what a check
                # (ingest's memo) has seen cannot change under it
                v = v.copy()
                v.flags.writeable = False
                object.__setattr__(self, name, v)

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    def rows(self, sl: slice) -> "LogArrays":
        """The samples ``sl`` (a slice of rows) as new LogArrays; repairs listed in
        :attr:`resorted_time_s` are kept where their time lies in the rows kept."""
        n = len(self)
        kw = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        for k, v in kw.items():
            if isinstance(v, np.ndarray) and k != "resorted_time_s" and v.shape[:1] == (n,):
                kw[k] = v[sl]
        t = kw["time_s"]
        r = self.resorted_time_s
        kw["resorted_time_s"] = r[(r >= t[0]) & (r <= t[-1])] if len(t) else r[:0]
        return LogArrays(**kw)

    @property
    def segments(self) -> list[slice]:
        """Gap-free segments as slices, in order."""
        if len(self) == 0:
            return []
        starts = np.flatnonzero(np.diff(self.segment_id) != 0) + 1
        bounds = np.concatenate(([0], starts, [len(self)]))
        return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]

    @functools.cached_property
    def dt_s(self) -> float:
        """Nominal sample period [s]: the median spacing of ``time_s`` (NaN below 2 samples)."""
        if len(self) < 2:
            return float("nan")
        return float(np.median(np.diff(self.time_s)))

    def to_frame(self, *, derived_velocities: bool = False) -> pd.DataFrame:
        """The log as a new DataFrame in the log format (degrees at this edge).

        Velocities are written where they were logged and left missing where they were
        derived (so converting the frame back derives them again), unless
        ``derived_velocities``. Wind is written where it was logged, the thrusters' rpm
        when their column was logged, and the angle of every rotatable command channel
        (azimuth thrusters and rudders). Heading is written in 0..360 deg.

        Parameters
        ----------
        derived_velocities : bool, default False
            Write the full ``nu`` (logged and derived) in ``u_m_s``, ``v_m_s``, ``r_deg_s``.
        """
        cols = {"time_s": self.time_s, "north_m": self.eta[:, 0], "east_m": self.eta[:, 1],
                "heading_deg": np.degrees(frames.wrap_2pi(self.eta[:, 2]))}
        for j, (name, scale) in enumerate((("u_m_s", 1.0), ("v_m_s", 1.0), ("r_deg_s", 180.0 / np.pi))):
            if derived_velocities:
                cols[name] = self.nu[:, j] * scale
            elif self.nu_logged[:, j].any():
                cols[name] = np.where(self.nu_logged[:, j], self.nu[:, j] * scale, np.nan)
        if self.has_wind or self.wind_columns:
            cols["wind_speed_m_s"] = np.where(self.wind_logged, self.wind[:, 0], np.nan)
            cols["wind_dir_deg"] = np.where(self.wind_logged, np.degrees(frames.wrap_2pi(self.wind[:, 1])), np.nan)
        for j, (name, rot) in enumerate(zip(self.channel_names, self.rotatable)):
            if self.channel_logged[j]:
                cols[f"{name}_rpm"] = self.rpm[:, j]
            if rot:
                cols[f"{name}_azimuth_deg"] = np.degrees(self.azimuth_rad[:, j])
        cols["dp_active"] = self.dp_active
        return pd.DataFrame({k: np.array(v) for k, v in cols.items()})


def _unwrap_finite(psi_rad: np.ndarray) -> np.ndarray:
    """Unwrap a heading series over its finite samples; NaN samples stay NaN (``np.unwrap``
    alone would turn everything after the first NaN into NaN)."""
    out = np.array(psi_rad, dtype=float)
    ok = np.isfinite(out)
    out[ok] = frames.unwrap_heading(out[ok])
    return out


def _held(x: np.ndarray, default: float, *, backwards: bool = True) -> np.ndarray:
    """Fill NaNs by holding the last logged value (a logger logs commands that persist),
    then (with ``backwards``) the first one backwards, then ``default``.

    Commands are filled without ``backwards``: a command logged after a row was not known
    at that row, and a held-command forecast must not use it (before the first logged
    value a command is ``default``, as :attr:`LogArrays.commands_logged` says)."""
    s = pd.Series(x).ffill()
    return (s.bfill() if backwards else s).fillna(default).to_numpy(dtype=float)


def log_to_arrays(
    df: pd.DataFrame,
    *,
    channel_names: Sequence[str],
    rotatable: Sequence[bool],
    allow_missing: bool = False,
) -> LogArrays:
    """Validate a log DataFrame and convert it to :class:`LogArrays` (SI units, radians).

    Parameters
    ----------
    df : pandas.DataFrame
        The log (never modified).
    channel_names : sequence of str
        Thruster names of the vessel file, in the order of the ``rpm`` / ``azimuth_rad``
        columns.
    rotatable : sequence of bool
        Per thruster, whether it is an azimuth thruster.
    allow_missing : bool, default False
        Accept missing positions and headings (as in :func:`validate_log`); they stay NaN
        in ``eta`` (the heading is unwrapped over the finite samples) and the velocities
        derived next to them are NaN. For forecast-time use with
        :func:`hybridship.forecast_inputs.start_window.assess_start_window`.

    Returns
    -------
    LogArrays

    Notes
    -----
    Derived quantities, used where the log has no column or a missing value, are computed
    within each gap-free segment with :func:`numpy.gradient` against ``time_s``
    (second-order central differences inside, first-order one-sided at segment ends; a
    single-sample segment gives NaN):

    * ``u, v``: the NED velocity ``d(north, east)/dt`` rotated into the body frame with
      the logged heading, ``[u, v] = R(psi)^T [dN/dt, dE/dt]``;
    * ``r``: the derivative of the unwrapped heading.

    Plain differences amplify position noise; filter with
    :func:`hybridship.logs.preprocess.derivative_by_segment` where that matters. Missing
    values in thruster, wind and ``dp_active`` columns are filled by holding the last
    logged value; before the first one, wind takes the first logged value (see
    ``wind_logged``) and commands their default (0 rpm, angle 0, ``dp_active`` 1: causal,
    see ``commands_logged``).
    """
    names, rot = _check_thruster_args(channel_names, rotatable)
    if names is None or rot is None:
        raise ValueError("log_to_arrays needs channel_names and rotatable")
    _validate(df, names, rot, "log", warn_unknown=False, allow_missing=allow_missing)
    return _frame_to_arrays(df, names, rot)


def _frame_to_arrays(df: pd.DataFrame, names: tuple, rot: tuple, resorted_time_s=None,
                     gap_step_s: float | None = None) -> LogArrays:
    """Convert a validated log frame (see :func:`log_to_arrays`; no checks here).

    ``gap_step_s``: the nominal step [s] by which gaps cut the segments (default: the median
    step of ``df``; the whole log's when ``df`` holds only some of its rows)."""
    cols = set(map(str, df.columns))

    def col(name: str) -> np.ndarray:
        # A copy: LogArrays must not alias the caller's DataFrame. Infinities (only possible
        # in required columns with allow_missing) are missing samples.
        x = np.array(pd.to_numeric(df[name], errors="coerce").to_numpy(dtype=float, na_value=np.nan))
        x[np.isinf(x)] = np.nan
        return x

    t = col("time_s")
    n = t.size
    segments = split_segments(t, nominal_dt_s=gap_step_s)
    seg_id = segment_ids(segments, n)

    psi = _unwrap_finite(np.radians(col("heading_deg")))
    eta = np.column_stack([col("north_m"), col("east_m"), psi])

    def grad(x, ts):
        return np.gradient(x, ts, axis=0) if ts.size > 1 else np.full(x.shape, np.nan)

    ne_dot = segmentwise(grad, [eta[:, :2], t], segments)
    r_derived = segmentwise(grad, [psi, t], segments)
    nu_derived = frames.ned_to_body(np.column_stack([ne_dot, r_derived]), psi)

    nu = nu_derived.copy()
    nu_logged = np.zeros((n, 3), dtype=bool)
    for j, (name, scale) in enumerate((("u_m_s", 1.0), ("v_m_s", 1.0), ("r_deg_s", np.pi / 180.0))):
        if name in cols:
            x = col(name) * scale
            nu_logged[:, j] = np.isfinite(x)
            nu[nu_logged[:, j], j] = x[nu_logged[:, j]]

    k = len(names)
    rpm = np.zeros((n, k))
    azimuth = np.zeros((n, k))
    logged = []
    commands_logged = np.ones(n, dtype=bool)
    for j, name in enumerate(names):
        logged.append(f"{name}_rpm" in cols)
        if logged[-1]:
            commands_logged &= np.isfinite(col(f"{name}_rpm"))
            rpm[:, j] = _held(col(f"{name}_rpm"), 0.0, backwards=False)
        if rot[j] and f"{name}_azimuth_deg" in cols:
            commands_logged &= np.isfinite(col(f"{name}_azimuth_deg"))
            azimuth[:, j] = np.radians(_held(col(f"{name}_azimuth_deg"), 0.0, backwards=False))

    wind = np.zeros((n, 2))
    has_wind = False
    wind_logged = np.zeros(n, dtype=bool)
    wind_columns = {"wind_speed_m_s", "wind_dir_deg"} <= cols
    if wind_columns:
        speed, direction = col("wind_speed_m_s"), col("wind_dir_deg")
        wind_logged = np.isfinite(speed) & np.isfinite(direction)
        if np.isfinite(speed).any() and np.isfinite(direction).any():
            has_wind = True
            wind[:, 0] = _held(speed, 0.0)
            wind[:, 1] = np.radians(_held(direction, 0.0))

    dp = np.ones(n, dtype=int)
    if "dp_active" in cols:
        commands_logged &= np.isfinite(col("dp_active"))    # the DP's state is commanded too
        dp = _held(col("dp_active"), 1.0, backwards=False).astype(int)

    return LogArrays(
        time_s=t,
        eta=eta,
        nu=nu,
        nu_logged=nu_logged,
        rpm=rpm,
        azimuth_rad=azimuth,
        wind=wind,
        has_wind=has_wind,
        dp_active=dp,
        segment_id=seg_id,
        channel_names=names,
        rotatable=rot,
        channel_logged=tuple(logged),
        wind_logged=wind_logged,
        resorted_time_s=resorted_time_s,
        commands_logged=commands_logged,
        wind_columns=wind_columns,
    )
