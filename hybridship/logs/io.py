"""The project's vessel log format (version 1): read, validate, write, convert to arrays.

The format is specified in ``shared/spec/log-format.md``: one row per sample, units in
the column names, degrees at the file edge. This module is that edge: DataFrames and
degrees come in, :class:`LogArrays` in SI units and radians go out.

Containers (chosen by the file name's extension): ``.csv``, ``.csv.gz`` (gzip CSV) and
``.parquet`` / ``.pq``.

Validation (:func:`validate_log`) refuses, with a :class:`LogFormatError` that names the
column, the first offending row (0-based position among the data rows, header excluded)
and its ``time_s`` where relevant, and what was expected:

* missing required columns (``time_s``, ``north_m``, ``east_m``, ``heading_deg``) or
  duplicated column names;
* non-numeric values in a known numeric column; infinities anywhere in one;
* ``time_s`` not finite or not strictly increasing; NaN in a required column;
* a heading that looks like radians (see :func:`heading_looks_like_radians` for the rule);
* ``|u_m_s|`` or ``|v_m_s|`` above 30 m/s (knots?), ``|r_deg_s|`` above 60 deg/s
  (rad/s vs deg/s mix-up?), ``wind_speed_m_s`` outside 0..80 m/s;
* thruster columns (``<name>_rpm``, ``<name>_azimuth_deg``) naming a thruster that is not
  in ``thruster_names`` (when given);
* ``dp_active`` values other than 0/1.

Optional columns may contain missing values (empty CSV cells / Parquet nulls). Columns
that are neither in the format nor ``truth_*`` are reported once per call with a
:class:`LogFormatWarning` and kept.
"""

from __future__ import annotations

import gzip
import os
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from hybridship import frames
from hybridship.fileio import atomic_write
from hybridship.logs.preprocess import segment_ids, segmentwise, split_segments

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
]

#: Columns every log must have.
REQUIRED_COLUMNS = ("time_s", "north_m", "east_m", "heading_deg")
#: Fixed-name optional columns of the format (thruster columns are matched by pattern).
OPTIONAL_COLUMNS = ("u_m_s", "v_m_s", "r_deg_s", "wind_speed_m_s", "wind_dir_deg", "dp_active")
TRUTH_PREFIX = "truth_"

#: Plausibility limits (a ship, not a missile): beyond these a unit mix-up is more likely.
MAX_SPEED_M_S = 30.0
MAX_YAW_RATE_DEG_S = 60.0
MAX_WIND_SPEED_M_S = 80.0

_THRUSTER_RE = re.compile(r"^(?P<name>.+)_(?P<kind>rpm|azimuth_deg)$")
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
_RAD_SPREAD_LIMIT = 5.5
#: Ratio std(r_deg_s) / std(heading rate) splitting degrees (~1) from radians (~57.3).
_RATE_SCALE_SPLIT = float(np.sqrt(180.0 / np.pi))


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
       log whose heading AND rate are both in radian units.
    4. **Spread.** Otherwise the column is refused if it spans at least 5.5 (315 deg if
       radians, i.e. a turning vessel), and accepted if it spans less.

    So a log whose headings all lie in 0..3 deg is accepted (spread 3 < 5.5, no wrap
    jumps), and a turning log spanning 0..6.28 is refused (wrap jumps or spread). The
    known blind spot: a degree log held within +-3.2 deg of north in the -180..180
    convention for a whole recording and without ``r_deg_s`` is refused as radians;
    logging ``r_deg_s`` resolves it.

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
            f"time_s {t_ok[k]:g} and {t_ok[k + 1]:g} while typical steps are {typical_step:.3f}"
        )

    if r_deg_s is not None:
        r = np.asarray(r_deg_s, dtype=float)[ok]
        dt = np.diff(t_ok)
        step_ok = (dt <= 1.5 * np.median(dt)) & np.isfinite(r[1:]) & np.isfinite(r[:-1]) & ~big
        if step_ok.sum() >= 10:
            r_mid = 0.5 * (r[1:] + r[:-1])[step_ok]
            rate = (dh / dt)[step_ok]
            if np.std(rate) > 0.0 and np.std(r_mid) > 0.0:
                corr = float(np.corrcoef(rate, r_mid)[0, 1])
                k = float(np.std(r_mid) / np.std(rate))
                if corr >= 0.3:
                    if k > _RATE_SCALE_SPLIT:
                        return True, (
                            f"r_deg_s is {k:.1f} times its rate of change (about 1 expected for "
                            f"degrees, 57.3 for radians)"
                        )
                    return False, f"r_deg_s is {k:.2f} times its rate of change, as for degrees"

    spread = float(np.ptp(h_ok))
    if spread >= _RAD_SPREAD_LIMIT:
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
    return f"row {i} (time_s {time_s[i]:g})"


def _to_float(df: pd.DataFrame, col: str, source: str, time_s: np.ndarray | None) -> np.ndarray:
    """Column as float array; non-numeric entries and infinities are errors, blanks NaN."""
    s = df[col]
    if s.dtype == bool:
        return s.to_numpy(dtype=float)
    num = pd.to_numeric(s, errors="coerce")
    bad = num.isna().to_numpy() & s.notna().to_numpy()
    if bad.any():
        i = int(np.argmax(bad))
        raise LogFormatError(
            f"{col}: non-numeric value {s.iloc[i]!r} at {_row_at(time_s, i)}; expected a number "
            f"with '.' as decimal separator or an empty cell{_where(source)}",
            column=col, row=i, time_s=None if time_s is None else float(time_s[i]),
        )
    x = num.to_numpy(dtype=float, na_value=np.nan)
    inf = np.isinf(x)
    if inf.any():
        i = int(np.argmax(inf))
        raise LogFormatError(
            f"{col}: infinite value {x[i]} at {_row_at(time_s, i)}; expected a finite number "
            f"or an empty cell{_where(source)}",
            column=col, row=i, time_s=None if time_s is None else float(time_s[i]),
        )
    return x


def _check_thruster_args(thruster_names, rotatable) -> tuple[tuple[str, ...] | None, tuple[bool, ...] | None]:
    if thruster_names is None:
        if rotatable is not None:
            raise ValueError("rotatable given without thruster_names")
        return None, None
    names = tuple(str(n) for n in thruster_names)
    if len(set(names)) != len(names):
        raise ValueError(f"thruster_names contains duplicates: {names}")
    if rotatable is None:
        return names, None
    rot = tuple(bool(r) for r in rotatable)
    if len(rot) != len(names):
        raise ValueError(f"rotatable has {len(rot)} entries for {len(names)} thruster_names {names}")
    return names, rot


def _limit_error(col: str, x: np.ndarray, bad: np.ndarray, t: np.ndarray, expected: str,
                 source: str) -> LogFormatError:
    i = int(np.argmax(bad))
    return LogFormatError(
        f"{col}: value {x[i]:g} at {_row_at(t, i)} {expected}{_where(source)}",
        column=col, row=i, time_s=float(t[i]),
    )


def _validate(df: pd.DataFrame, thruster_names, rotatable, source: str, warn_unknown: bool) -> None:
    if not isinstance(df, pd.DataFrame):
        raise TypeError(f"expected a pandas DataFrame, got {type(df).__name__}")
    names, rot = _check_thruster_args(thruster_names, rotatable)
    cols = [str(c) for c in df.columns]

    dup = sorted({c for c in cols if cols.count(c) > 1})
    if dup:
        raise LogFormatError(f"{dup[0]}: column appears more than once; column names must be unique{_where(source)}",
                             column=dup[0])
    missing = [c for c in REQUIRED_COLUMNS if c not in cols]
    if missing:
        raise LogFormatError(
            f"{missing[0]}: required column missing (missing: {', '.join(missing)}; required: "
            f"{', '.join(REQUIRED_COLUMNS)}; found: {', '.join(cols) or 'none'}){_where(source)}",
            column=missing[0],
        )
    if len(df) == 0:
        raise LogFormatError(f"time_s: the log has no rows; expected at least one sample{_where(source)}",
                             column="time_s")

    # time_s first: every other message quotes it.
    t = _to_float(df, "time_s", source, None)
    nonfinite = ~np.isfinite(t)
    if nonfinite.any():
        i = int(np.argmax(nonfinite))
        raise LogFormatError(f"time_s: non-finite value {t[i]} at row {i}; expected finite, strictly "
                             f"increasing times{_where(source)}", column="time_s", row=i)
    not_incr = np.diff(t) <= 0.0
    if not_incr.any():
        i = int(np.argmax(not_incr)) + 1
        raise LogFormatError(
            f"time_s: not strictly increasing at row {i} (time_s {t[i]:g} after {t[i - 1]:g}); expected "
            f"strictly increasing times{_where(source)}",
            column="time_s", row=i, time_s=float(t[i]),
        )

    values: dict[str, np.ndarray] = {}
    for col in REQUIRED_COLUMNS[1:]:
        x = _to_float(df, col, source, t)
        bad = ~np.isfinite(x)
        if bad.any():
            i = int(np.argmax(bad))
            raise LogFormatError(
                f"{col}: missing or non-finite value ({x[i]}) at {_row_at(t, i)}, {int(bad.sum())} such "
                f"row(s) in all; required columns must be finite{_where(source)}",
                column=col, row=i, time_s=float(t[i]),
            )
        values[col] = x
    for col in OPTIONAL_COLUMNS:
        if col in cols:
            values[col] = _to_float(df, col, source, t)

    is_rad, reason = heading_looks_like_radians(t, values["heading_deg"], values.get("r_deg_s"))
    if is_rad:
        h = values["heading_deg"]
        raise LogFormatError(
            f"heading_deg: values span {h.min():.2f}..{h.max():.2f}, which looks like radians ({reason}); "
            f"the log format expects degrees (column heading_deg){_where(source)}",
            column="heading_deg",
        )

    for col in ("u_m_s", "v_m_s"):
        if col in values:
            x = values[col]
            bad = np.abs(x) > MAX_SPEED_M_S
            if bad.any():
                raise _limit_error(col, x, bad, t, f"exceeds {MAX_SPEED_M_S:g} m/s in magnitude; the log "
                                   "format expects m/s; is the column in knots (or another unit)?", source)
    if "r_deg_s" in values:
        x = values["r_deg_s"]
        bad = np.abs(x) > MAX_YAW_RATE_DEG_S
        if bad.any():
            raise _limit_error("r_deg_s", x, bad, t, f"exceeds {MAX_YAW_RATE_DEG_S:g} deg/s in magnitude, "
                               "implausible for a ship; the log format expects deg/s; check the rad/s vs "
                               "deg/s conversion (converted twice?)", source)
    if "wind_speed_m_s" in values:
        x = values["wind_speed_m_s"]
        bad = (x < 0.0) | (x > MAX_WIND_SPEED_M_S)
        if bad.any():
            raise _limit_error("wind_speed_m_s", x, bad, t, f"is outside 0..{MAX_WIND_SPEED_M_S:g} m/s; the "
                               "log format expects a non-negative true wind speed in m/s (knots?)", source)
    if "dp_active" in values:
        x = values["dp_active"]
        bad = np.isfinite(x) & (x != 0.0) & (x != 1.0)
        if bad.any():
            raise _limit_error("dp_active", x, bad, t, "is not 0 or 1; the log format expects 1 while the "
                               "station-keeping controller is active, else 0", source)

    # Thruster columns, matched by name pattern; truth_* columns are never interpreted.
    ignored: list[str] = []
    for col in cols:
        if col in REQUIRED_COLUMNS or col in OPTIONAL_COLUMNS or col.startswith(TRUTH_PREFIX):
            continue
        m = _THRUSTER_RE.match(col)
        if m is None:
            ignored.append(col)
            continue
        name, kind = m.group("name"), m.group("kind")
        if names is not None and name not in names:
            raise LogFormatError(
                f"{col}: names unknown thruster '{name}'; known thrusters: {', '.join(names) or 'none'} "
                f"(expected columns <thruster>_rpm and <thruster>_azimuth_deg){_where(source)}",
                column=col,
            )
        _to_float(df, col, source, t)  # numeric, no infinities
        if kind == "azimuth_deg" and rot is not None and not rot[names.index(name)]:
            ignored.append(f"{col} (thruster '{name}' is not rotatable)")

    if ignored and warn_unknown:
        warnings.warn(
            f"{source}: ignoring {len(ignored)} column(s) not in the log format: {', '.join(ignored)}",
            LogFormatWarning,
            stacklevel=3,
        )


def validate_log(
    df: pd.DataFrame,
    *,
    thruster_names: Sequence[str] | None = None,
    rotatable: Sequence[bool] | None = None,
    source: str = "log",
) -> None:
    """Check a log DataFrame against the log format; raise on the first problem.

    Parameters
    ----------
    df : pandas.DataFrame
        The log, one row per sample (never modified).
    thruster_names : sequence of str, optional
        Thruster names of the vessel file. When given, every ``<name>_rpm`` /
        ``<name>_azimuth_deg`` column must name one of them.
    rotatable : sequence of bool, optional
        Per thruster, whether it is an azimuth thruster; an azimuth column of a fixed
        thruster is reported (warning) and ignored.
    source : str, default "log"
        Where the data come from (a file name), quoted in messages.

    Raises
    ------
    LogFormatError
        On the first violation found; see the module docstring for the checks and
        :func:`heading_looks_like_radians` for the heading unit rule.
    ValueError
        If ``rotatable`` does not match ``thruster_names``.

    Warns
    -----
    LogFormatWarning
        Once, listing every column that is neither in the format nor ``truth_*``.
    """
    _validate(df, thruster_names, rotatable, source, warn_unknown=True)


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


def read_log(
    path: str | os.PathLike,
    *,
    thruster_names: Sequence[str] | None = None,
    rotatable: Sequence[bool] | None = None,
) -> pd.DataFrame:
    """Read and validate a log file (CSV, ``.csv.gz`` or Parquet, by extension).

    Parameters
    ----------
    path : str or path-like
        The file; ``.csv``, ``.csv.gz``, ``.parquet`` or ``.pq``.
    thruster_names, rotatable : optional
        As in :func:`validate_log`.

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
    path = Path(path)
    kind = _container(path)
    if kind == "parquet":
        df = pd.read_parquet(path)
    else:
        df = pd.read_csv(path, compression="gzip" if kind == "csv.gz" else None)
    df = df.reset_index(drop=True)
    _validate(df, thruster_names, rotatable, str(path), warn_unknown=True)
    return df


def write_log(
    df: pd.DataFrame,
    path: str | os.PathLike,
    *,
    thruster_names: Sequence[str] | None = None,
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
    thruster_names, rotatable : optional
        As in :func:`validate_log`.

    Raises
    ------
    LogFormatError
        If ``df`` breaks the format (nothing is written).
    """
    path = Path(path)
    kind = _container(path)
    _validate(df, thruster_names, rotatable, str(path), warn_unknown=True)
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
    rpm : ndarray, shape (N, K)
        Propeller speed commands [rpm] in ``thruster_names`` order.
    azimuth_rad : ndarray, shape (N, K)
        Azimuth angle commands [rad]; 0 for fixed thrusters and missing columns.
    wind : ndarray, shape (N, 2)
        ``[wind_speed_m_s, wind_dir_from_rad]``; zeros when the log has no wind.
    has_wind : bool
        Whether the log has (any finite) wind speed and direction.
    dp_active : ndarray of int, shape (N,)
        1 while station keeping is active; all ones when the column is absent.
    segment_id : ndarray of int, shape (N,)
        Gap-free segment label per row, 0, 1, ... (see :func:`split_segments`).
    thruster_names : tuple of str
    rotatable : tuple of bool
    thruster_logged : tuple of bool
        Per thruster, whether its ``<name>_rpm`` column was in the log.
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
    thruster_names: tuple[str, ...]
    rotatable: tuple[bool, ...]
    thruster_logged: tuple[bool, ...]

    def __post_init__(self):
        for v in vars(self).values():
            if isinstance(v, np.ndarray):
                v.flags.writeable = False

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    @property
    def segments(self) -> list[slice]:
        """Gap-free segments as slices, in order."""
        if len(self) == 0:
            return []
        starts = np.flatnonzero(np.diff(self.segment_id) != 0) + 1
        bounds = np.concatenate(([0], starts, [len(self)]))
        return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def _held(x: np.ndarray, default: float) -> np.ndarray:
    """Fill NaNs by holding the last logged value (a logger logs commands that persist),
    then the first one backwards, then ``default`` if the column is empty."""
    return pd.Series(x).ffill().bfill().fillna(default).to_numpy(dtype=float)


def log_to_arrays(
    df: pd.DataFrame,
    *,
    thruster_names: Sequence[str],
    rotatable: Sequence[bool],
) -> LogArrays:
    """Validate a log DataFrame and convert it to :class:`LogArrays` (SI units, radians).

    Parameters
    ----------
    df : pandas.DataFrame
        The log (never modified).
    thruster_names : sequence of str
        Thruster names of the vessel file, in the order of the ``rpm`` / ``azimuth_rad``
        columns.
    rotatable : sequence of bool
        Per thruster, whether it is an azimuth thruster.

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
    logged value (then the first one backwards).
    """
    names, rot = _check_thruster_args(thruster_names, rotatable)
    if names is None or rot is None:
        raise ValueError("log_to_arrays needs thruster_names and rotatable")
    _validate(df, names, rot, "log", warn_unknown=False)
    cols = set(map(str, df.columns))

    def col(name: str) -> np.ndarray:
        # A copy: LogArrays must not alias the caller's DataFrame.
        return np.array(pd.to_numeric(df[name], errors="coerce").to_numpy(dtype=float, na_value=np.nan))

    t = col("time_s")
    n = t.size
    segments = split_segments(t)
    seg_id = segment_ids(segments, n)

    psi = frames.unwrap_heading(np.radians(col("heading_deg")))
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
    for j, name in enumerate(names):
        logged.append(f"{name}_rpm" in cols)
        if logged[-1]:
            rpm[:, j] = _held(col(f"{name}_rpm"), 0.0)
        if rot[j] and f"{name}_azimuth_deg" in cols:
            azimuth[:, j] = np.radians(_held(col(f"{name}_azimuth_deg"), 0.0))

    wind = np.zeros((n, 2))
    has_wind = False
    if {"wind_speed_m_s", "wind_dir_deg"} <= cols:
        speed, direction = col("wind_speed_m_s"), col("wind_dir_deg")
        if np.isfinite(speed).any() and np.isfinite(direction).any():
            has_wind = True
            wind[:, 0] = _held(speed, 0.0)
            wind[:, 1] = np.radians(_held(direction, 0.0))

    dp = np.ones(n, dtype=int)
    if "dp_active" in cols:
        dp = _held(col("dp_active"), 1.0).astype(int)

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
        thruster_names=names,
        rotatable=rot,
        thruster_logged=tuple(logged),
    )
