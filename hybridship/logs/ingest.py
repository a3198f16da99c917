"""One way in: every log that fit, forecast, the benchmarks or the CLI use passes :func:`ingest`.

:func:`ingest` reads a log (a path, a DataFrame in the log format, or :class:`LogArrays`),
re-sorts its samples by time, validates it once against the vessel
(:func:`hybridship.logs.io.check_log_against_vessel`: the log format, thruster columns,
rpm limits and sign conventions) and converts it to :class:`LogArrays`. So the same log
gets the same checks, and the same messages, whether it is trained on or forecast from.

``purpose`` decides what is repaired and what is refused:

``"fit"``
    Training data must be clean: missing positions or headings are refused (naming the
    column and row), and so are conflicting duplicates (two samples with one time and
    different values).
``"forecast"``
    Sensor faults pass, for :func:`hybridship.forecast_inputs.start_window.assess_start_window` to judge per
    forecast start: missing positions and headings stay NaN; conflicting duplicates are
    both removed (neither is trusted; the time becomes a missing sample).

In both, late (out-of-order) samples are re-sorted, exact duplicates dropped and rows
without a finite ``time_s`` dropped; the affected times travel with the arrays
(:attr:`LogArrays.resorted_time_s`) so that a forecast can flag them.

LogArrays are checked as well, through their :meth:`LogArrays.to_frame` view; arrays that
:func:`ingest` returned carry a mark (vessel fingerprint and purpose), so passing them in
again costs nothing. Nothing here modifies the caller's data.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from hybridship.logs.io import (REQUIRED_COLUMNS, LogArrays, LogFormatError, LogFormatWarning, _check_column_names,
                                _check_unique_names, _check_required_not_index,
                                _frame_to_arrays, _to_float,
                                check_log_against_vessel, check_units_on_whole_log, output_table_kind, read_log)
from hybridship.messages import seconds_text, warn_user

__all__ = ["PURPOSES", "SortedLog", "ingest", "ingest_with_report", "sort_samples"]

#: Values of ``ingest(..., purpose=)``.
PURPOSES = ("fit", "forecast")

#: Attribute of an ingested LogArrays: (vessel fingerprint, purpose).
_MARK = "_ingested_for"
#: Memo on the rows of a log read for a time range: the median step [s] of the whole log, so
#: that a forecast's step does not depend on which of its rows a call reads.
WHOLE_LOG_STEP = "_whole_log_step_s"


# --------------------------------------------------------------------------------------
# Late, out-of-order and duplicated samples
# --------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SortedLog:
    """A log re-sorted by time (see :func:`sort_samples`).

    Attributes
    ----------
    frame : pandas.DataFrame
        A new frame, sorted by ``time_s`` with unique times and a fresh ``RangeIndex``.
    late_time_s : ndarray
        Times of samples that came after a later sample in the input (arrived late).
    duplicate_time_s : ndarray
        Times that appeared more than once with identical rows (one kept).
    conflicting_time_s : ndarray
        Times that appeared more than once with differing rows (all of them removed:
        neither is trusted, the time becomes a missing sample).
    conflicting_rows : ndarray of int
        Input rows (0-based positions) of the first two samples of each conflicting time.
    n_without_time : int
        Rows dropped because ``time_s`` was missing or not finite.
    n_without_time_with_data : int
        Those of them that held a value in another column (a sample lost, not a blank row).
    source_rows : ndarray of int
        Input row (0-based position) of each row of ``frame``.
    """

    frame: pd.DataFrame
    late_time_s: np.ndarray
    duplicate_time_s: np.ndarray
    conflicting_time_s: np.ndarray
    n_without_time: int
    conflicting_rows: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=int))
    n_without_time_with_data: int = 0
    source_rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))

    @property
    def affected_time_s(self) -> np.ndarray:
        """Sorted unique times of late, duplicated or conflicting samples."""
        return np.unique(np.concatenate([self.late_time_s, self.duplicate_time_s, self.conflicting_time_s]))

    @property
    def changed(self) -> bool:
        """Whether anything was re-sorted, dropped or removed."""
        return bool(self.affected_time_s.size or self.n_without_time)


def _rows_equal(block: pd.DataFrame) -> bool:
    """Whether all rows of ``block`` are identical (NaN equal to NaN)."""
    first = block.iloc[0]
    for _, row in block.iloc[1:].iterrows():
        for a, b in zip(first.to_numpy(), row.to_numpy()):
            if a is b:
                continue
            # any missing value (float64, float32, pandas' nullable NA) equals another one
            a_nan, b_nan = bool(pd.isna(a)), bool(pd.isna(b))
            if a_nan and b_nan:
                continue
            if a_nan or b_nan or a != b:
                return False
    return True


def sort_samples(df: pd.DataFrame, *, source: str = "log") -> SortedLog:
    """Re-sort a log's samples by time; drop exact duplicates; remove conflicting ones.

    Parameters
    ----------
    df : pandas.DataFrame
        A log in the log format, possibly with samples out of order (never modified).
    source : str, default "log"
        Quoted in messages.

    Returns
    -------
    SortedLog

    Raises
    ------
    LogFormatError
        If ``time_s`` is missing or holds non-numeric values, or the header is not one row of
        unique column names.
    """
    if not isinstance(df, pd.DataFrame):
        raise TypeError(f"expected a pandas DataFrame, got {type(df).__name__}")
    _check_header(df, source)
    _check_required_not_index(df, source)
    cols = [str(c) for c in df.columns]
    if "time_s" not in cols or output_table_kind(cols):
        # the reader's message, with its hints; a table that hybridship wrote (a forecast's
        # repeats its times) is not a log, whatever its times say
        _check_column_names(cols, source)
        raise LogFormatError(f"time_s: required column missing (required: {', '.join(REQUIRED_COLUMNS)}) "
                             f"(in {source})", column="time_s")
    t = _to_float(df, "time_s", source, None, inf_is_missing=True)
    has_time = np.isfinite(t)
    n_without = int((~has_time).sum())
    with_data = int(df.iloc[np.flatnonzero(~has_time)].drop(columns="time_s").notna().any(axis=1).sum()) \
        if n_without else 0
    rows = np.flatnonzero(has_time)
    tt = t[rows]
    # arrived late: earlier than some sample before it in the input
    prev_max = np.maximum.accumulate(np.concatenate(([-np.inf], tt[:-1])))
    late = tt < prev_max
    order = np.argsort(tt, kind="stable")
    frame = df.iloc[rows[order]].reset_index(drop=True)
    ts = tt[order]
    dup_mask = np.zeros(ts.size, dtype=bool)
    dup_mask[1:] = ts[1:] == ts[:-1]
    source_rows = rows[order]
    duplicate, conflicting, conflicting_rows, drop = [], [], [], []
    if dup_mask.any():
        starts = np.flatnonzero(~dup_mask)
        ends = np.concatenate((starts[1:], [ts.size]))
        for a, b in zip(starts, ends):
            if b - a < 2:
                continue
            if _rows_equal(frame.iloc[a:b]):
                duplicate.append(ts[a])
                drop.extend(range(a + 1, b))
            else:
                conflicting.append(ts[a])
                conflicting_rows.append(rows[order[a:a + 2]])
                drop.extend(range(a, b))
        frame = frame.drop(index=drop).reset_index(drop=True)
        source_rows = np.delete(source_rows, drop)
    return SortedLog(frame=frame, late_time_s=np.unique(tt[late]), duplicate_time_s=np.asarray(duplicate, float),
                     conflicting_time_s=np.asarray(conflicting, float), n_without_time=n_without,
                     conflicting_rows=np.asarray(conflicting_rows, dtype=int).reshape(-1, 2),
                     n_without_time_with_data=with_data, source_rows=source_rows)


# --------------------------------------------------------------------------------------
# The ingest
# --------------------------------------------------------------------------------------


def _vessel(vessel):
    from hybridship.vessel import Vessel, load_vessel

    return vessel if isinstance(vessel, Vessel) else load_vessel(vessel)


def _refuse_conflicts(order: SortedLog, source: str) -> None:
    """Training data: two samples with one time and different values are refused."""
    if order.conflicting_time_s.size:
        t = float(order.conflicting_time_s[0])
        r0, r1 = (int(r) for r in order.conflicting_rows[0])
        raise LogFormatError(
            f"time_s: {seconds_text(t)} appears at rows {r0} and {r1} with different values (a repeated time stamp?); "
            f"training needs one sample per time: remove or correct one of them "
            f"({order.conflicting_time_s.size} such time(s) in all) (in {source})",
            column="time_s", row=r1, time_s=t)


def _from_arrays(arrays: LogArrays, v, purpose: str, key,
                 where: str = "LogArrays") -> tuple[LogArrays, SortedLog | None]:
    """Check LogArrays through their frame view; keep the caller's arrays when nothing moved."""
    mark = getattr(arrays, _MARK, None)
    if mark is not None and mark[0] == key[0] and (mark[1] == purpose or mark[1] == "fit"):
        return arrays, None
    if tuple(arrays.channel_names) != tuple(v.channel_names) or tuple(arrays.rotatable) != tuple(v.rotatable):
        raise LogFormatError(
            f"channel_names: the arrays carry command channels {list(arrays.channel_names)} (rotatable "
            f"{list(arrays.rotatable)}), vessel {v.name!r} has {list(v.channel_names)} (rotatable "
            f"{list(v.rotatable)}); build them for this vessel (in {where})", column="channel_names")
    out, order = _from_frame(arrays.to_frame(), v, purpose, where)
    if not order.changed and len(out) == len(arrays):
        out = arrays                                   # checked; the caller's values, unchanged
    else:
        # re-sorted: keep the caller's heading branch (the frame view wraps it to 0..360 deg)
        ok_in, ok_out = np.isfinite(arrays.eta[:, 2]), np.isfinite(out.eta[:, 2])
        if ok_in.any() and ok_out.any():
            k = round((arrays.eta[ok_in, 2][0] - out.eta[ok_out, 2][0]) / (2 * np.pi))
            if k:
                eta = out.eta.copy()
                eta[:, 2] += 2 * np.pi * k
                out = _replace_eta(out, eta)
    return out, order


def _replace_eta(arrays: LogArrays, eta: np.ndarray) -> LogArrays:
    from dataclasses import fields

    kw = {f.name: getattr(arrays, f.name) for f in fields(arrays)}
    kw["eta"] = eta
    return LogArrays(**kw)


def _from_frame(df: pd.DataFrame, v, purpose: str, source: str,
                gap_step_s: float | None = None, unit_statistics: bool = True) -> tuple[LogArrays, SortedLog]:
    """Sort, check and convert a log frame; ``gap_step_s``: the nominal step [s] its gaps are
    judged by (default: its own median step); without ``unit_statistics`` the judgements of
    a column's unit are left to the caller's check of the whole log."""
    order = sort_samples(df, source=source)
    if purpose == "fit":
        _refuse_conflicts(order, source)
    if order.affected_time_s.size or (purpose == "fit" and order.n_without_time) or order.n_without_time_with_data:
        # say what was repaired: a forecast's flags see only its start window, while the
        # environment estimator reads the half hour before it (rows without any value at
        # all, such as the blank rows at the end of a spreadsheet export, hold no sample to lose)
        _warn_repaired(order, source)
    allow_missing = purpose == "forecast"
    try:
        check_log_against_vessel(order.frame, v, source=source, allow_missing=allow_missing,
                                 unit_statistics=unit_statistics)
    except LogFormatError as exc:
        raise _with_resort_hint(_with_input_row(exc, order), order) from None
    arrays = _frame_to_arrays(order.frame, tuple(v.channel_names), tuple(v.rotatable),
                              resorted_time_s=order.affected_time_s, gap_step_s=gap_step_s)
    return arrays, order


def _with_input_row(exc: LogFormatError, order: SortedLog) -> LogFormatError:
    """``exc`` naming the input row of its sample: the checks count the rows of the re-sorted
    frame, which a dropped row without a time or a re-sorted sample shifts (the message
    named the row before the faulty one, which holds a valid sample)."""
    if exc.row is None or not 0 <= exc.row < order.source_rows.size:
        return exc
    row = int(order.source_rows[exc.row])
    text = str(exc)
    if row == exc.row or f"row {exc.row} (" not in text:
        return exc
    return LogFormatError(text.replace(f"row {exc.row} (", f"row {row} (", 1), column=exc.column, row=row,
                          time_s=exc.time_s)


def _with_resort_hint(exc: LogFormatError, order: SortedLog) -> LogFormatError:
    """``exc``, saying also that most samples were re-sorted when a rate check failed: a
    ``time_s`` column that runs backwards against the other columns reverses the heading's
    and the track's rates, and the sort made them look like a sign or unit fault."""
    if exc.column not in ("r_deg_s", "u_m_s", "v_m_s") or order.late_time_s.size <= 0.5 * len(order.frame):
        return exc
    return LogFormatError(f"{exc}; note: {order.late_time_s.size} of the {len(order.frame)} samples came after a "
                          f"later one and were re-sorted by time_s: if time_s runs backwards against the other "
                          f"columns, that reverses these rates too", column=exc.column, row=exc.row,
                          time_s=exc.time_s)


def _warn_repaired(order: SortedLog, source: str) -> None:
    """A LogFormatWarning saying which samples of a log were re-sorted or dropped."""
    parts = [f"{n} {what}" for n, what in ((order.late_time_s.size, "late sample(s) re-sorted"),
                                           (order.duplicate_time_s.size, "exact duplicate(s) dropped"),
                                           (order.conflicting_time_s.size,
                                            "time(s) logged more than once with different values, all their "
                                            "samples removed"),
                                           (order.n_without_time, "row(s) without a finite time_s dropped"))
             if n]
    warn_user(f"{source}: time_s is not strictly increasing: {', '.join(parts)}", LogFormatWarning)


def _check_header(df: pd.DataFrame, source: str) -> None:
    """One row of column names, each once: what every later step indexes by (a repeated
    ``time_s`` would otherwise reach pandas as a frame where a column is expected)."""
    if isinstance(df.columns, pd.MultiIndex):
        raise LogFormatError(f"columns: expected one row of column names, got {df.columns.nlevels} levels (a "
                             f"MultiIndex); flatten them to the log format's names (in {source})", column="columns")
    _check_unique_names([str(c) for c in df.columns], source)


def _time_range_frame(df: pd.DataFrame, time_range_s) -> pd.DataFrame:
    """The rows of ``df`` whose ``time_s`` lies in ``time_range_s`` (rows whose time is not a
    number are kept, so that the checks still report them; with no row in the range, all)."""
    if time_range_s is None or "time_s" not in df.columns:
        return df
    t = pd.to_numeric(df["time_s"], errors="coerce").to_numpy(dtype=float)
    inside = (t >= time_range_s[0]) & (t <= time_range_s[1])
    if not inside.any():
        return df           # nothing in range: the whole log, so that the start checks say why
    keep = ~np.isfinite(t) | inside
    return df if keep.all() else df[keep]


def _between(arrays: LogArrays, time_range_s) -> LogArrays:
    """The rows of sorted, checked ``arrays`` whose time lies in ``time_range_s`` (the check's memo kept)."""
    if time_range_s is None:
        return arrays
    t = arrays.time_s
    lo, hi = int(np.searchsorted(t, time_range_s[0], "left")), int(np.searchsorted(t, time_range_s[1], "right"))
    if (lo == 0 and hi == len(t)) or lo >= hi:
        return arrays
    out = arrays.rows(slice(lo, hi))
    object.__setattr__(out, _MARK, getattr(arrays, _MARK, None))
    object.__setattr__(out, WHOLE_LOG_STEP, getattr(arrays, WHOLE_LOG_STEP, _median_step_s(t)))
    return out


def _median_step_s(time_s) -> float | None:
    """Median spacing [s] of sorted times (None below two samples)."""
    return float(np.median(np.diff(time_s))) if len(time_s) > 1 else None


def _time_range(time_range_s) -> tuple[float, float]:
    """``time_range_s`` as two finite seconds ``first_s <= last_s``; else a ValueError naming it."""
    try:
        first, last = (float(x) for x in time_range_s)
        ok = not isinstance(time_range_s, (str, bytes)) and math.isfinite(first) and math.isfinite(last)
    except (TypeError, ValueError):
        ok = False
    if not ok or first > last:
        raise ValueError(f"time_range_s: expected (first_s, last_s), two finite numbers of seconds with "
                         f"first_s <= last_s, got {time_range_s!r}")
    return first, last


def ingest_with_report(source, vessel, *, purpose: str = "fit", name: str | None = None,
                       time_range_s=None) -> tuple[LogArrays, SortedLog | None]:
    """:func:`ingest`, also returning the sort report (None when LogArrays were passed through)."""
    from hybridship.vessel import fingerprint

    if purpose not in PURPOSES:
        raise ValueError(f"purpose: expected one of {PURPOSES}, got {purpose!r}")
    if time_range_s is not None:
        time_range_s = _time_range(time_range_s)
    v = _vessel(vessel)
    key = (fingerprint(v), purpose)
    if isinstance(source, LogArrays):
        arrays, order = _from_arrays(source, v, purpose, key, name or "LogArrays")
        arrays = _between(arrays, time_range_s)
    elif isinstance(source, (str, os.PathLike, pd.DataFrame)):
        df = read_log(Path(source), validate=False) if not isinstance(source, pd.DataFrame) else source
        where = name or (str(source) if not isinstance(source, pd.DataFrame) else "log")
        _check_header(df, where)
        try:
            part = _time_range_frame(df, time_range_s)
            whole = sort_samples(df, source=where).frame if part is not df else None
            # the whole log's step: the gaps of the rows read (their segments) are judged by it,
            # as on LogArrays converted whole, not by the rows read, which other starts decide
            whole_step_s = None if whole is None else _median_step_s(
                pd.to_numeric(whole["time_s"], errors="coerce").dropna().to_numpy(float))
            # a column's unit is judged on the whole log, as training judges it, and not again
            # on the rows read: the whole log's judgement is the one that counts
            arrays, order = _from_frame(part, v, purpose, where, gap_step_s=whole_step_s,
                                        unit_statistics=whole is None)
            if whole is not None:
                check_units_on_whole_log(whole, v, source=where)
                object.__setattr__(arrays, WHOLE_LOG_STEP, whole_step_s)
        except LogFormatError:
            if time_range_s is None:
                raise
            # report the fault as the whole log's check would (its rows, its first fault); a
            # check on the whole log's statistics (an azimuth thruster's rpm never positive) can
            # fail on a short range alone: when the whole log passes, its rows in the range are used
            arrays, order = _from_frame(df, v, purpose, where)
            arrays = _between(arrays, time_range_s)
    else:
        raise TypeError(f"log: expected a path, a DataFrame or LogArrays, got {type(source).__name__}")
    if order is not None or getattr(arrays, _MARK, None) is None:
        object.__setattr__(arrays, _MARK, key)       # a memo of the check, not data: values unchanged
    return arrays, order


def ingest(source, vessel, *, purpose: str = "fit", name: str | None = None, time_range_s=None) -> LogArrays:
    """Read, re-sort, validate once against the vessel, and convert a log to :class:`LogArrays`.

    Parameters
    ----------
    source : path, pandas.DataFrame or LogArrays
        A log file (``.csv``, ``.csv.gz``, ``.parquet``, ``.pq``), a DataFrame in the log
        format, or arrays (checked through :meth:`LogArrays.to_frame` unless
        :func:`ingest` made them for this vessel). Never modified.
    vessel : hybridship.vessel.Vessel or str or path
        The vessel, or a packaged name / vessel file.
    purpose : {"fit", "forecast"}
        ``"fit"`` refuses missing positions/headings and conflicting duplicates;
        ``"forecast"`` keeps sensor faults for the start-window checks (see the module
        docstring).
    name : str, optional
        Quoted in messages (default: the file name, "log" or "LogArrays").
    time_range_s : (first_s, last_s), optional
        Keep only the samples with ``first_s <= time_s <= last_s``, before the checks: a
        forecast reads what it uses, so its cost does not grow with the log's length. A
        fault inside the range is reported as the whole log's check would report it (its
        rows; the whole log's first fault); faults outside it do not matter, but a column's
        unit is judged on the whole log (:func:`hybridship.logs.io.check_units_on_whole_log`),
        so a forecast refuses a unit error that training refuses.

    Returns
    -------
    LogArrays
        Sorted, checked; :attr:`LogArrays.resorted_time_s` lists what was repaired.

    Raises
    ------
    LogFormatError
        Naming the column, row and time where relevant (the row as the input holds it, before
        rows without a time were dropped and late samples re-sorted).
    hybridship.vessel.VesselFileError
        If ``vessel`` names an invalid vessel file.
    """
    return ingest_with_report(source, vessel, purpose=purpose, name=name, time_range_s=time_range_s)[0]
