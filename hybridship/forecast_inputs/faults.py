"""Faults of the forecast inputs: their names, the two refusals, and the start-window detectors.

:class:`FaultFlags` names every flag a forecast can carry (the columns of forecast tables
and CLI output). A start window with too little valid data is refused with
:class:`StartWindowError`; a physics input that is non-finite or out of range (and not
clipped) with :class:`InputRangeError`, whose message names the input, the batch element
(and step), the component, the value and the valid range.

The start-window detectors each look for one fault in one forecast start's window
(:class:`Window`) of a log (:class:`LogView`), set its flag with a note saying what was
found and done, and mark the samples they find invalid. The driver,
:func:`hybridship.forecast_inputs.start_window.assess_start_window`, runs them in this
order, which the notes follow:

1. :func:`detect_missing_samples` (``nan_in_window``),
2. :func:`detect_late_samples` (``late_or_out_of_order``),
3. :func:`detect_frozen_channels` (``frozen_sensor``),
4. :func:`detect_velocity_mismatch` (``velocity_mismatch``),
5. :func:`detect_position_jumps` (``position_jump``),
6. :func:`detect_heading_jumps` (``heading_jump``),
7. :func:`detect_heading_wrap` (``heading_wrapped``, informational),
8. :func:`rederive_velocities` (the repair of frozen, mismatched or jump-spoilt velocities),
9. :func:`detect_too_little_valid` (``too_little_valid``: the start is refused),
10. :func:`detect_dropped_wind` (``wind_dropped``).

:func:`velocity_track_mismatch_m`, the evidence of ``velocity_mismatch``, is also what the
environment estimator uses to leave a logged velocity out of its filter
(:mod:`hybridship.residual.environment`), so that both read a log alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..config import check_number
from ..frames import ned_to_body, wrap_pi
from ..logs.ingest import WHOLE_LOG_STEP
from ..messages import seconds_text

__all__ = [
    "FaultFlags",
    "StartWindowError",
    "InputRangeError",
    "WindowSettings",
    "LogView",
    "Window",
    "detect_missing_samples",
    "detect_late_samples",
    "detect_frozen_channels",
    "velocity_track_mismatch_m",
    "detect_velocity_mismatch",
    "detect_position_jumps",
    "detect_heading_jumps",
    "detect_heading_wrap",
    "rederive_velocities",
    "start_row_nu",
    "window_nu",
    "detect_too_little_valid",
    "detect_dropped_wind",
]


#: Trailing window [s] and limit [m] of :func:`velocity_track_mismatch_m` above which a
#: logged velocity is not trusted (the start window's ``velocity_mismatch``, and the
#: environment estimator's filter, which then leaves it out).
TRACK_WINDOW_S = 30.0
TRACK_MISMATCH_M = 8.0
#: How the notes of ``wind_dropped`` begin (:func:`detect_dropped_wind`): in the window, in
#: every row read.
WIND_DROPPED_NOTES = ("no valid wind sample in the window", "the wind columns hold no valid sample")


class FaultFlags:
    """Names of the fault flags (column names in forecast tables and CLI output).

    Attributes
    ----------
    START_WINDOW : tuple of str
        The flags :func:`~hybridship.forecast_inputs.start_window.assess_start_window` sets.
    ALL : tuple of str
        Every flag, in the order of the forecast table's columns.
    INFORMATIONAL : tuple of str
        Flags that do not mean the forecast was degraded.
    """

    NAN_IN_WINDOW = "nan_in_window"
    TOO_LITTLE_VALID = "too_little_valid"
    FROZEN_SENSOR = "frozen_sensor"
    VELOCITY_MISMATCH = "velocity_mismatch"
    POSITION_JUMP = "position_jump"
    HEADING_JUMP = "heading_jump"
    HEADING_WRAPPED = "heading_wrapped"
    WIND_DROPPED = "wind_dropped"
    LATE_OR_OUT_OF_ORDER = "late_or_out_of_order"
    INPUT_CLIPPED = "input_clipped"
    OUT_OF_ENVELOPE = "out_of_envelope"

    START_WINDOW = (NAN_IN_WINDOW, TOO_LITTLE_VALID, FROZEN_SENSOR, VELOCITY_MISMATCH, POSITION_JUMP, HEADING_JUMP,
                    HEADING_WRAPPED, WIND_DROPPED, LATE_OR_OUT_OF_ORDER)
    ALL = START_WINDOW + (INPUT_CLIPPED, OUT_OF_ENVELOPE)
    INFORMATIONAL = (HEADING_WRAPPED,)


class StartWindowError(ValueError):
    """A forecast start has too little valid data in its start window.

    Attributes
    ----------
    start_time_s : float
        The first refused start.
    reason : str
        What was missing or invalid there.
    refused_start_times_s : ndarray
        Every refused start of the call.
    """

    def __init__(self, message: str, *, start_time_s: float, reason: str, refused_start_times_s):
        super().__init__(message)
        self.start_time_s = float(start_time_s)
        self.reason = reason
        self.refused_start_times_s = np.asarray(refused_start_times_s, dtype=float)


class InputRangeError(ValueError):
    """A physics input is non-finite or outside its valid range (and was not clipped).

    Attributes
    ----------
    field : str
        The input (``"rpm"``, ``"wind"``, ...).
    index : tuple of int
        Position of the offending value in the input array.
    value : float
    valid : str
        The valid range, as text.
    component : str
        The component's name (``"north_m"``, ``"thruster 'port'"``; "" when none).
    problem : str
        What is wrong with the value (``"outside the valid range"``, ...).
    """

    def __init__(self, message: str, *, field: str, index: tuple, value: float, valid: str,
                 component: str = "", problem: str = "outside the valid range"):
        super().__init__(message)
        self.field = field
        self.index = tuple(int(i) for i in index)
        self.value = float(value)
        self.valid = valid
        self.component = component
        self.problem = problem


#: Component names of the vector inputs, quoted in messages.
COMPONENTS = {
    "eta": ("north_m", "east_m", "psi_rad"),
    "nu": ("u_m_s", "v_m_s", "r_rad_s"),
    "wind": ("speed_m_s", "dir_from_rad"),
    "current": ("speed_m_s", "dir_to_rad"),
}


def _component(index: tuple, components) -> str:
    return components[index[-1]] if components and index[-1] < len(components) else f"component {index[-1]}"


def _where_text(name: str, a: np.ndarray, index: tuple, components) -> str:
    parts = []
    if a.ndim >= 2:
        parts.append(f"batch {index[0]}")
    if a.ndim == 3:
        parts.append(f"step {index[1]}")
    parts.append(_component(index, components))
    return f"{name}[{', '.join(parts)}]"


def refuse(name: str, a: np.ndarray, bad: np.ndarray, valid: str, components=None, why: str = ""):
    """Raise :class:`InputRangeError` for the first True entry of ``bad`` (same shape as ``a``).

    The message names the input, batch element (and step), component, value and ``valid``.
    """
    index = np.unravel_index(int(np.argmax(bad)), a.shape)
    value = a[index]
    problem = why or "outside the valid range"
    raise InputRangeError(
        f"{_where_text(name, a, index, components)}: {value:g} is {problem}; "
        f"valid: {valid} (hybridship.forecast_inputs.limits)",
        field=name, index=index, value=value, valid=valid, component=_component(index, components),
        problem=problem)


def batch_mask(a: np.ndarray, bad: np.ndarray, batch: int) -> np.ndarray:
    """(batch,) True for the batch elements of ``a`` where ``bad`` (``a``'s shape, or its
    shape without the last axis) holds; an unbatched input counts for every element."""
    m = bad.reshape(bad.shape[0], -1).any(axis=1) if a.ndim >= 2 else np.array([bad.any()])
    return np.broadcast_to(m, (batch,)).copy() if m.shape[0] in (1, batch) else m


def column_mask(a: np.ndarray, col: int, bad_col: np.ndarray) -> np.ndarray:
    """A bool array of ``a``'s shape, ``bad_col`` in column ``col`` and False elsewhere."""
    full = np.zeros(a.shape, dtype=bool)
    full[..., col] = bad_col
    return full


# --------------------------------------------------------------------------------------
# Start-window detectors
# --------------------------------------------------------------------------------------
#
# Each detector looks at one forecast start's window (a Window) in one log (a LogView),
# sets its flag with a note, and marks the samples it finds invalid; the driver is
# hybridship.forecast_inputs.start_window.assess_start_window.


@dataclass(frozen=True)
class WindowSettings:
    """Thresholds of the start-window detectors (see
    :func:`~hybridship.forecast_inputs.start_window.assess_start_window` for each)."""

    window_s: float = 3.0
    frozen_s: float = 3.0
    frozen_motion_m: float = 2.0
    frozen_turn_deg: float = 1.0
    jump_m: float = 5.0
    lookback_s: float = 10.0
    min_valid_fraction: float = 0.5
    heading_jump_deg: float = 10.0
    track_window_s: float = TRACK_WINDOW_S
    track_mismatch_m: float = TRACK_MISMATCH_M

    def __post_init__(self):
        # each by name: text was a bare comparison TypeError, NaN a message naming four settings, and an
        # infinite window an OverflowError
        for name in ("window_s", "frozen_s", "jump_m", "track_window_s", "track_mismatch_m"):
            check_number(name, getattr(self, name), lo=0, lo_open=True)
        check_number("min_valid_fraction", self.min_valid_fraction, lo=0, lo_open=True, hi=1)
        try:
            heading_ok = 0 < check_number("heading_jump_deg", self.heading_jump_deg) < 180    # TypeError: no number
        except ValueError:                                                                     # NaN, inf
            heading_ok = False
        if not heading_ok:
            raise ValueError(f"heading_jump_deg must be > 0 and < 180 (a step is at most 180 deg), "
                             f"got {self.heading_jump_deg!r}")
        # a threshold of 0 (or less) calls every held value of a ship at rest frozen; NaN never
        check_number("frozen_motion_m", self.frozen_motion_m, lo=0, lo_open=True)
        check_number("frozen_turn_deg", self.frozen_turn_deg, lo=0, lo_open=True)
        check_number("lookback_s", self.lookback_s, lo=0)

    @property
    def frozen_turn_rad(self) -> float:
        """``frozen_turn_deg`` [rad]."""
        return math.radians(self.frozen_turn_deg)

    @property
    def heading_jump_rad(self) -> float:
        """``heading_jump_deg`` [rad]."""
        return math.radians(self.heading_jump_deg)


@dataclass(frozen=True, eq=False)
class LogView:
    """What the detectors need of a log, computed once for all starts.

    Attributes
    ----------
    arrays : LogArrays
    dt_nom : float
        Nominal sample period [s]: the median spacing of the whole log, also when only some
        of its rows were read (:func:`hybridship.logs.ingest.ingest`'s ``time_range_s``),
        so that a start is judged alike whichever other starts share the call; 1 for a
        single sample. Where the log's rate changes, a stretch logged slower than this
        holds missing samples.
    n_nom : int
        Samples a full start window holds at the nominal rate.
    n_min : int
        Valid samples needed of the heading and of each velocity component.
    affected_time_s : ndarray
        Times of late, duplicated or removed samples.
    pos_runs, head_runs, vel_runs
        First and last row of each row's run of bit-identical values (position, heading,
        and each of u, v, r).
    track_mismatch : ndarray of bool, shape (N,)
        Rows whose logged u, v disagree with the track (:func:`velocity_track_mismatch_m`
        above ``track_mismatch_m`` over ``track_window_s``); judged from the row
        ``first_row`` of :meth:`build` on, False before it.
    """

    arrays: object
    dt_nom: float
    n_nom: int
    n_min: int
    affected_time_s: np.ndarray
    pos_runs: tuple
    head_runs: tuple
    vel_runs: tuple
    track_mismatch: np.ndarray

    @classmethod
    def build(cls, arrays, settings: WindowSettings, affected_time_s, first_start: int = 0) -> "LogView":
        """The view of ``arrays``; ``affected_time_s`` from the sort report (or the arrays).
        ``first_start``: the earliest start row to be assessed (the velocity check is
        computed only as far back as its windows reach)."""
        t = arrays.time_s
        # the step the forecast takes too (forecast_step_s), not the rows read, which the
        # other starts of the call decide
        dt_nom = getattr(arrays, WHOLE_LOG_STEP, None)
        if dt_nom is None:
            dt_nom = float(np.median(np.diff(t))) if len(arrays) > 1 else 1.0
        n_nom = max(1, int(round(settings.window_s / dt_nom)))
        n_min = max(1, math.ceil(settings.min_valid_fraction * n_nom))
        first = _track_check_first_row(arrays, settings, first_start)
        mismatch = np.zeros(len(t), dtype=bool)
        mismatch[first:] = velocity_track_mismatch_m(arrays, settings.track_window_s, first,
                                                     step_limit_m=settings.jump_m,
                                                     frozen_s=settings.frozen_s) > settings.track_mismatch_m
        return cls(arrays, dt_nom, n_nom, n_min, np.asarray(affected_time_s), _runs(arrays.eta[:, :2]),
                   _runs(arrays.eta[:, 2]), tuple(_runs(arrays.nu[:, j]) for j in range(3)), mismatch)

    @property
    def t(self) -> np.ndarray:
        return self.arrays.time_s

    @property
    def pos(self) -> np.ndarray:
        return self.arrays.eta[:, :2]

    @property
    def psi(self) -> np.ndarray:
        return self.arrays.eta[:, 2]

    @property
    def nu(self) -> np.ndarray:
        return self.arrays.nu


def _track_check_first_row(arrays, settings: WindowSettings, first_start: int) -> int:
    """The row from which :func:`velocity_track_mismatch_m` gives, at every row the detectors
    read for starts from ``first_start`` on, what it gives on the whole log: a second before
    the earliest lookback, less two track windows (one judged, one carried) and a frozen run
    (judged by its length so far), and at least the two valid fixes before that (a jump is
    judged against them)."""
    t = arrays.time_s
    if not len(t):
        return 0
    reach = settings.window_s + settings.lookback_s + 2.0 * settings.track_window_s + settings.frozen_s + 1.0
    r0 = int(np.searchsorted(t, t[first_start] - reach, side="left"))
    valid = np.flatnonzero(np.all(np.isfinite(arrays.eta[:r0]), axis=1))
    return int(valid[-2]) if valid.size >= 2 else 0


def start_row_nu(arrays, rows) -> np.ndarray:
    """``nu`` [m/s, m/s, rad/s] at forecast start rows ``rows`` (S,) as a log that ends there
    gives it, (S, 3).

    The log's derived (not logged) velocities are central differences
    (:func:`numpy.gradient`), so at a start row they read the sample after the start, which
    a forecast may not use. Here they are the one-sided difference to the row before (NaN
    at a segment's first row); logged components stay as logged.
    """
    i = np.asarray(rows, dtype=int).ravel()
    t, pos, psi = arrays.time_s, arrays.eta[:, :2], arrays.eta[:, 2]
    p = np.maximum(i - 1, 0)
    same = (i > 0) & (arrays.segment_id[p] == arrays.segment_id[i])
    with np.errstate(invalid="ignore", divide="ignore"):
        dt = np.where(same, t[i] - t[p], np.nan)
        rates = np.column_stack([(pos[i] - pos[p]) / dt[:, None], (psi[i] - psi[p]) / dt])
    return np.where(arrays.nu_logged[i], arrays.nu[i], ned_to_body(rates, psi[i]))


def window_nu(view: LogView, W: np.ndarray) -> np.ndarray:
    """``nu`` of start windows ``W`` (rows, shape (..., w), the start row last), a copy whose
    start row is :func:`start_row_nu` (it does not read the sample after the start).
    Returns shape (..., w, 3)."""
    nu = view.nu[W].copy()
    starts = np.asarray(W)[..., -1]
    if view.arrays.nu_logged[starts].all():
        # as logged, nothing derived: the detectors' path costs no more than before
        return nu
    last = nu[..., -1, :]
    nu[..., -1, :] = start_row_nu(view.arrays, starts).reshape(last.shape)
    return nu


@dataclass(eq=False)
class Window:
    """One forecast start's window and what is valid in it (the detectors update it).

    Attributes
    ----------
    start : int
        The start row ``i``.
    lo : int
        First row of the window.
    rows : ndarray of int, shape (w,)
        ``lo .. start``.
    pos_ok, head_ok, wind_ok : ndarray of bool, shape (w,)
        Valid position / heading / wind samples.
    vel_ok : ndarray of bool, shape (w, 3)
        Valid u, v, r samples.
    vel_replace : ndarray of bool, shape (3,)
        Components to derive again from the valid positions (headings).
    shift_from : int
        First row after a lasting position shift (``lo`` without one).
    flags : set of str
    notes : list of str
    """

    start: int
    lo: int
    rows: np.ndarray
    pos_ok: np.ndarray
    head_ok: np.ndarray
    vel_ok: np.ndarray
    wind_ok: np.ndarray
    vel_replace: np.ndarray
    shift_from: int
    flags: set = field(default_factory=set)
    notes: list = field(default_factory=list)

    @classmethod
    def at(cls, view: LogView, i: int, window_s: float) -> "Window":
        """The rows with ``t0 - window_s < time_s <= t0`` (half a sample of slack), always
        holding the start row; every finite sample valid."""
        t = view.t
        lo = min(int(np.searchsorted(t, t[i] - window_s + 0.5 * view.dt_nom, side="left")), i)
        W = np.arange(lo, i + 1)
        return cls(start=i, lo=lo, rows=W, pos_ok=np.all(np.isfinite(view.pos[W]), axis=1),
                   head_ok=np.isfinite(view.psi[W]), vel_ok=np.isfinite(window_nu(view, W)),
                   wind_ok=view.arrays.wind_logged[W], vel_replace=np.zeros(3, dtype=bool), shift_from=lo)

    def flag(self, name: str, note: str) -> None:
        """Set flag ``name`` and say what was found and done."""
        self.flags.add(name)
        self.notes.append(note)


#: The end of :func:`detect_missing_samples`' note: the repair, dropped when the start is refused.
VALID_USED = ": valid samples used"


def detect_missing_samples(view: LogView, win: Window) -> None:
    """Missing samples in the window.

    Fault: a NaN position, heading, logged velocity, wind or command sample, or fewer rows
    than the window holds at the nominal rate (a gap). Evidence: non-finite values
    (:attr:`LogArrays.commands_logged` for the commands); the row count against
    :attr:`LogView.n_nom`. Flags ``nan_in_window``; nothing to repair: the start values use
    the valid samples only, and a command missing at the start holds its last logged value
    (the note says since when).
    """
    a, W = view.arrays, win.rows
    n_missing = max(0, view.n_nom - W.size)
    cols = [] if win.pos_ok.all() else ["position"]
    if not win.head_ok.all():
        cols.append("heading")
    has_col = a.nu_logged.any(axis=0)
    cols += [name for j, name in enumerate(("u", "v", "r")) if has_col[j] and not a.nu_logged[W, j].all()]
    if a.has_wind and not win.wind_ok.all():
        cols.append("wind")
    if not a.commands_logged[W].all():
        logged = np.flatnonzero(a.commands_logged[: win.start + 1])
        # commands_logged is per row (every channel logged), while each channel holds its own
        # last value: a row missing one channel does not make the others' values 0
        cols.append("commands" if a.commands_logged[win.start] else
                    "commands (at the start: each channel's last logged value held, "
                    + (f"all logged together last at time_s {seconds_text(view.t[logged[-1]])})" if logged.size
                       else "0 for a channel not logged yet; no earlier row logs all of them)"))
    if cols or n_missing:
        what = f"missing {', '.join(cols)}" if cols else ""
        gap = f"{n_missing} missing sample(s)" if n_missing else ""
        win.flag(FaultFlags.NAN_IN_WINDOW, f"{'; '.join(x for x in (what, gap) if x)} in the window{VALID_USED}")


def detect_late_samples(view: LogView, win: Window, settings: WindowSettings) -> None:
    """Late, out-of-order or duplicated samples in the window.

    Fault: samples that arrived after a later one, repeated, or conflicting (removed).
    Evidence: their times (the ingest's sort report) within the nominal window, which
    also covers a removed sample that left no row. Flags ``late_or_out_of_order``; the
    ingest already re-sorted them.
    """
    t, affected = view.t, view.affected_time_s
    t0 = t[win.start]
    lo_t = min(t[win.lo], t0 - settings.window_s + 0.5 * view.dt_nom)
    if affected.size and np.any((affected >= lo_t - 1e-9) & (affected <= t0 + 1e-9)):
        win.flag(FaultFlags.LATE_OR_OUT_OF_ORDER,
                 "late, out-of-order or duplicated samples in the window: re-sorted by time")


def _stale_rows(view: LogView, win: Window, runs, contradicted, frozen_s: float) -> np.ndarray:
    """Rows of the window that repeat the first sample of a run of bit-identical values
    lasting ``frozen_s`` or more (up to the start row only: causal) that an independent
    channel contradicts (``contradicted(a, b)`` over the run's rows ``a..b``)."""
    first, last = runs
    t, W, i = view.t, win.rows, win.start
    stale = np.zeros(W.size, dtype=bool)
    for a in np.unique(first[W]):
        b = min(int(last[a]), i)
        if b <= a or t[b] - t[a] < frozen_s - 1e-9:
            continue
        if contradicted(a, b):
            stale |= (W > a) & (W <= b)
    return stale


def _uv_logged(view: LogView, a: int, b: int) -> bool:
    return view.arrays.nu_logged[a:b + 1, 0].all() and view.arrays.nu_logged[a:b + 1, 1].all()


def _position_contradicted(view: LogView, a: int, b: int, motion_m: float) -> bool:
    """The logged u, v move the ship by ``motion_m`` or more over rows ``a..b``."""
    if not _uv_logged(view, a, b):
        return False
    v_ned = _ned(view.nu[a:b + 1, :2], view.psi[a:b + 1])
    if not np.all(np.isfinite(v_ned)):
        return False
    return float(np.hypot(*_trapz(v_ned, view.t[a:b + 1], axis=0))) >= motion_m


def _heading_contradicted(view: LogView, a: int, b: int, turn_rad: float) -> bool:
    """The logged yaw rate turns the ship by ``turn_rad`` or more over rows ``a..b``."""
    if not view.arrays.nu_logged[a:b + 1, 2].all():
        return False
    return abs(float(_trapz(view.nu[a:b + 1, 2], view.t[a:b + 1]))) >= turn_rad


def _velocity_contradicted(view: LogView, j: int, a: int, b: int, settings: WindowSettings) -> bool:
    """A logged u or v (``j`` = 0, 1) disagrees with the track, or r (``j`` = 2) with the
    heading, by ``frozen_motion_m`` / ``frozen_turn_deg`` or more over rows ``a..b``."""
    nu, psi, pos, t = view.nu, view.psi, view.pos, view.t
    if not view.arrays.nu_logged[a:b + 1, j].all():
        return False
    if j == 2:
        if not (np.isfinite(psi[a]) and np.isfinite(psi[b])):
            return False
        return abs((psi[b] - psi[a]) - nu[a, 2] * (t[b] - t[a])) >= settings.frozen_turn_rad
    if not (np.all(np.isfinite(pos[[a, b]])) and np.isfinite(psi[a:b + 1]).all()):
        return False
    if not view.arrays.nu_logged[a:b + 1, 1 - j].all():
        return False
    disp_log = _trapz(_ned(nu[a:b + 1, :2], psi[a:b + 1]), t[a:b + 1], axis=0)
    return float(np.hypot(*(disp_log - (pos[b] - pos[a])))) >= settings.frozen_motion_m


def detect_frozen_channels(view: LogView, win: Window, settings: WindowSettings) -> None:
    """Sensors repeating one value while an independent channel says it changed.

    Fault: a position, heading or logged velocity bit-identical for ``frozen_s`` or more.
    Evidence: a position while the logged speed moves the ship by ``frozen_motion_m``; a
    heading while the logged yaw rate turns it by ``frozen_turn_deg``; u, v (r) while the
    track (heading) disagrees by as much. Without that evidence a constant value cannot
    be told from a ship at rest and is not flagged. Flags ``frozen_sensor``. Repair: the
    repeats are invalid; a frozen velocity is derived from the track instead.
    """
    s = settings
    found = []
    stale = _stale_rows(view, win, view.pos_runs, lambda a, b: _position_contradicted(view, a, b, s.frozen_motion_m),
                        s.frozen_s)
    if stale.any():
        win.pos_ok &= ~stale
        found.append("position (the logged speed says the ship moved)")
    stale = _stale_rows(view, win, view.head_runs, lambda a, b: _heading_contradicted(view, a, b, s.frozen_turn_rad),
                        s.frozen_s)
    if stale.any():
        win.head_ok &= ~stale
        found.append("heading (the logged yaw rate says it turned)")
    for j, name in enumerate(("u_m_s", "v_m_s", "r_deg_s")):
        stale = _stale_rows(view, win, view.vel_runs[j],
                            lambda a, b, j=j: _velocity_contradicted(view, j, a, b, s), s.frozen_s)
        if stale.any():
            win.vel_ok[:, j] = False
            win.vel_replace[j] = True
            found.append(f"{name} (disagrees with the track): derived from the track instead")
    if found:
        win.flag(FaultFlags.FROZEN_SENSOR, f"frozen for >= {s.frozen_s:g} s: {'; '.join(found)}")


def velocity_track_mismatch_m(arrays, window_s: float, first_row: int = 0, last_row: int | None = None, *,
                              step_limit_m: float = 5.0, frozen_s: float = 3.0) -> np.ndarray:
    """How far the logged ``u``, ``v`` disagree with the track [m], per row.

    For row ``i`` of ``first_row .. last_row`` (default: to the end), with ``j`` the first
    row of the trailing ``window_s`` seconds: the length of the difference between the
    position's change from ``j`` to ``i`` and the logged velocity's travel over the same
    steps, each step rotated into NED with the logged heading (exactly for a steady turn:
    the mean velocity turned to the mid heading and shortened by ``sinc`` of half the
    turn). A biased or corrupt velocity log grows it by its bias times the window; so does
    a heading off by a lasting angle while the ship is under way (the velocity derived from
    the track with that heading is then the one that moves a forecast along the track).
    Only the window's end positions enter, so position noise does not add up; each end is
    a fresh fix (one that differs from the row before: the window starts at the first such
    row in it), so a receiver that holds its fix between updates does not count either.

    A row whose window says nothing of the velocity carries the last value from the past
    ``window_s``, also from before a gap (NaN if there is none). A window says nothing when it covers
    less than half of ``window_s``; when a step in it lacks a logged finite velocity or
    heading; when the row's position is missing or not a fresh fix; when a position in it
    has repeated bit for bit for ``frozen_s`` or more up to then (a frozen receiver); or
    when a position in it jumps (a spike, an excursion, a datum shift): its change from the
    previous valid position, as a mean velocity over the step in the body frame (turned
    with the headings, exactly for a steady turn), departs from the step before it by more
    than ``step_limit_m`` over its step. That test reads the positions and headings alone,
    so a velocity fault, however large, is not taken for a position jump, and a ship in a
    steady turn makes none at any sample rate. The window stays within the row's segment
    and does not reach before ``first_row``, so the value depends on those rows alone
    (causal). Clean logs stay below 1.1 m over 30 s (GNSS noise 0.5 m).

    Returns
    -------
    ndarray, shape (last_row + 1 - first_row,)
    """
    last = len(arrays.time_s) - 1 if last_row is None else int(last_row)
    sl = slice(max(int(first_row), 0), last + 1)
    t, pos, psi, nu = arrays.time_s[sl], arrays.eta[sl, :2], arrays.eta[sl, 2], arrays.nu[sl, :2]
    n = t.size
    if n == 0:
        return np.zeros(0)
    seg = arrays.segment_id[sl]
    new_seg = np.concatenate([[True], seg[1:] != seg[:-1]])
    idx = np.arange(n)
    seg_first = np.maximum.accumulate(np.where(new_seg, idx, 0))
    # the logged velocity's travel over each step, exact for a steady turn
    mid, shrink = _steady_turn(psi[:-1], psi[1:])
    step = _ned(0.5 * (nu[1:] + nu[:-1]), mid) * (np.diff(t) * shrink)[:, None]
    logged = arrays.nu_logged[sl, 0] & arrays.nu_logged[sl, 1]
    step_ok = np.all(np.isfinite(step), axis=1) & logged[1:] & logged[:-1] & ~new_seg[1:]
    travelled = np.concatenate([np.zeros((1, 2)), np.cumsum(np.where(step_ok[:, None], step, 0.0), axis=0)])
    n_bad = np.concatenate([[0], np.cumsum(~step_ok)])                 # bad steps ending at rows <= k
    # position faults, from positions and headings alone: jumps, frozen fixes
    pos_ok = np.all(np.isfinite(pos), axis=1)
    valid = np.flatnonzero(pos_ok & np.isfinite(psi))
    jump = pos_ok & ~np.isfinite(psi)                   # a position without a heading cannot be judged
    if valid.size > 2:
        a, b = valid[:-1], valid[1:]
        dt_ab = t[b] - t[a]
        mid_ab, shrink_ab = _steady_turn(psi[a], psi[b])
        moved = np.column_stack([(pos[b] - pos[a]) / (dt_ab * shrink_ab)[:, None], np.zeros(a.size)])
        body = ned_to_body(moved, mid_ab)[:, :2]                         # the mean body velocity of each step
        change = np.hypot(*(body[1:] - body[:-1]).T) * dt_ab[1:]
        jump[b[1:]] |= (seg[a[1:]] == seg[a[:-1]]) & (change > step_limit_m)
    run_first, _ = _runs(pos)
    fresh = pos_ok & ((run_first == idx) | new_seg)
    stale = pos_ok & (t - t[run_first] >= frozen_s - 1e-9)              # so far: causal
    n_jump, n_stale = (np.concatenate([[0], np.cumsum(x)]) for x in (jump, stale))
    next_fresh = np.minimum.accumulate(np.where(fresh, idx, n)[::-1])[::-1]
    j = np.minimum(next_fresh[np.maximum(np.searchsorted(t, t - window_s, side="left"), seg_first)], idx)
    d = np.hypot(*((pos - pos[j]) - (travelled - travelled[j])).T)
    evidence = ((t - t[j] >= 0.5 * window_s) & fresh & fresh[j] & (n_bad[idx] == n_bad[j])
                & (n_stale[idx + 1] == n_stale[j]) & (n_jump[idx + 1] == n_jump[j]))
    # a row that cannot be judged (a held fix, a jump in its window, the first half window
    # after a gap) carries the last judgement of the past window_s, also from before a gap:
    # a speed log's bias outlasts a few missing samples
    judged = np.maximum.accumulate(np.where(evidence, idx, -1))
    keep = (judged >= 0) & (t - t[np.maximum(judged, 0)] <= window_s)
    return np.where(keep, d[np.maximum(judged, 0)], np.nan)


def _steady_turn(psi0_rad, psi1_rad):
    """Mid heading [rad] of steps from ``psi0_rad`` to ``psi1_rad`` and ``sinc`` of half their
    turn: over a steady turn a constant body velocity ``v`` travels ``R(mid) v dt`` times
    that factor."""
    half = 0.5 * wrap_pi(psi1_rad - psi0_rad)
    return psi0_rad + half, np.sinc(half / np.pi)


def detect_velocity_mismatch(view: LogView, win: Window, settings: WindowSettings) -> None:
    """Logged velocities that the track contradicts.

    Fault: the logged ``u``, ``v`` (a biased or failed speed log, a wrong lever arm or
    frame) move the ship differently from the positions. Evidence: over the trailing
    ``track_window_s`` of a row of the window, the two disagree by more than
    ``track_mismatch_m`` (:func:`velocity_track_mismatch_m`; not a frozen velocity, which
    :func:`detect_frozen_channels` reports). Flags ``velocity_mismatch``. Repair: u and v
    are derived from the track instead, and the position-jump check does not judge the
    positions by them.
    """
    hit = view.track_mismatch[win.rows]
    if not hit.any() or win.vel_replace[:2].any():
        return
    for j in range(2):
        win.vel_ok[:, j] &= ~hit
        win.vel_replace[j] = True
    win.flag(FaultFlags.VELOCITY_MISMATCH,
             f"u_m_s, v_m_s disagree with the track by more than {settings.track_mismatch_m:g} m over "
             f"{settings.track_window_s:g} s: derived from the track instead")


def _jump_rows(view: LogView, win: Window, settings: WindowSettings) -> np.ndarray:
    """Rows ending a position step (from the row before) that the velocity does not
    explain within ``jump_m``: logged velocities where both ends have them, else the median
    step velocity; steps ending from ``lookback_s`` before the window up to the start."""
    a, t, pos, psi, nu = view.arrays, view.t, view.pos, view.psi, view.nu
    rows = np.arange(_first_step(view, win, settings), win.start + 1)     # step r goes from row r-1 to r
    if not rows.size:
        return rows
    p_ok = np.all(np.isfinite(pos[rows]), axis=1) & np.all(np.isfinite(pos[rows - 1]), axis=1)
    dts = t[rows] - t[rows - 1]
    same = (a.segment_id[rows] == a.segment_id[rows - 1]) & p_ok
    steps = pos[rows] - pos[rows - 1]
    step_v = steps / dts[:, None]
    both_logged = (a.nu_logged[rows, 0] & a.nu_logged[rows, 1]
                   & a.nu_logged[rows - 1, 0] & a.nu_logged[rows - 1, 1]
                   & ~view.track_mismatch[rows] & ~view.track_mismatch[rows - 1])
    v_log = 0.5 * (_ned(nu[rows, :2], psi[rows]) + _ned(nu[rows - 1, :2], psi[rows - 1]))
    v_med = np.median(step_v[same], axis=0) if same.any() else np.zeros(2)
    v_ref = np.where((both_logged & np.all(np.isfinite(v_log), axis=1))[:, None], v_log, v_med)
    err = np.hypot(*(steps - v_ref * dts[:, None]).T)
    return rows[same & (err > settings.jump_m)]


def _first_step(view: LogView, win: Window, settings: WindowSettings) -> int:
    """The first step (row) the position-jump check looks at: ``lookback_s`` before the window."""
    t = view.t
    return max(int(np.searchsorted(t, t[win.start] - settings.window_s - settings.lookback_s, side="left")), 1)


def _outliers(jump_rows: np.ndarray, start: int) -> set:
    """Rows of a spike (a jump away and back) or of an unconfirmed jump into the start row."""
    jump_set = set(int(r) for r in jump_rows)
    bad = set()
    for r in sorted(jump_set):
        if (r - 1) in bad:                       # the return from a spike
            continue
        if r == start or (r + 1) in jump_set:    # unconfirmed jump into the start, or a spike
            bad.add(r)
    return bad


def detect_position_jumps(view: LogView, win: Window, settings: WindowSettings) -> None:
    """Position steps the velocity does not explain.

    Fault: a step between consecutive positions off by more than ``jump_m`` from what
    the velocity explains. Evidence: see :func:`_jump_rows`; a jump away and back is a
    spike, a jump into the start row cannot yet be told from a lasting shift, anything
    else is a lasting shift (a datum change). Flags ``position_jump`` when a jump ends in
    the window, and while a lasting shift lies within ``lookback_s`` before it (as
    ``heading_jump`` does): the positions the start follows changed a moment ago, which may
    yet turn out to be an excursion. Repair: spike (and unconfirmed) positions are invalid,
    velocities derived across any jump are derived again, and after a lasting shift only
    the new positions count.
    """
    jump_end = _jump_rows(view, win, settings)
    bad_pos = _outliers(jump_end, win.start)
    # a shift at the first step looked at may be the return of a spike before it: not judged
    first = _first_step(view, win, settings)
    shifts = [int(r) for r in jump_end if int(r) not in bad_pos and int(r) - 1 not in bad_pos and int(r) > first]
    in_w = jump_end[jump_end >= win.lo]
    if not in_w.size:
        if shifts:
            win.flag(FaultFlags.POSITION_JUMP,
                     f"position jump of more than {settings.jump_m:g} m at time_s "
                     f"{', '.join(seconds_text(view.t[r]) for r in shifts)}, before the window: lasting shift, "
                     f"new positions used")
        return
    W = win.rows
    for r in bad_pos:
        win.pos_ok &= W != r
    touched = set()                              # derived velocities next to a jump are invalid
    for r in jump_end:
        touched.update((int(r) - 1, int(r)))
    for r in bad_pos:
        touched.update((r - 1, r, r + 1))
    for j in range(2):
        hit = ~view.arrays.nu_logged[W, j] & np.isin(W, list(touched))
        if hit.any():
            win.vel_ok[:, j] &= ~hit
            win.vel_replace[j] = True
    lasting = [int(r) for r in in_w if int(r) not in bad_pos and int(r) - 1 not in bad_pos]
    if lasting:
        win.shift_from = max(lasting)
    win.flag(FaultFlags.POSITION_JUMP,
             f"position jump of more than {settings.jump_m:g} m at time_s "
             f"{', '.join(seconds_text(view.t[int(r)]) for r in in_w)}: "
             f"{'outlier(s) dropped' if bad_pos else 'lasting shift, new positions used'}")


def _heading_jump_rows(view: LogView, win: Window, settings: WindowSettings) -> tuple[np.ndarray, np.ndarray]:
    """Rows ending a heading step that the yaw rate does not explain within
    ``heading_jump_deg``, and each one's error [rad] (signed).

    A step ends where the heading value changes and goes from the previous value (the
    first row of the bit-identical run before, within the span below, so that live
    headings returning after a frozen gyro step from where it froze; a repeat is no step).
    It is the smallest signed angle between the two (a wrap across 0/360 or +-180 deg is no
    step). The yaw rate's turn is the logged ``r`` integrated (trapezoid) where every row
    of the step has it, else the median rate of the consecutive steps times the step's
    time (a derived ``r`` holds the jump itself). Steps end from ``3 * lookback_s`` before
    the window up to the start (three times the span of :func:`_jump_rows`: an excursion
    is told from two lasting shifts while its jump away lies in that span, which holds one
    up to ``2 * lookback_s`` long for as long as its return is named).
    """
    a, t, psi = view.arrays, view.t, view.psi
    lb = int(np.searchsorted(t, t[win.start] - settings.window_s - 3 * settings.lookback_s, side="left"))
    rows = np.arange(max(lb, 1), win.start + 1)
    if not rows.size:
        return rows, np.zeros(0)
    prev = np.maximum(view.head_runs[0][rows - 1], rows[0] - 1)   # step r goes from row prev to r
    same = (a.segment_id[rows] == a.segment_id[prev]) & np.isfinite(psi[rows]) & np.isfinite(psi[prev])
    same &= view.head_runs[0][rows] == rows                  # a repeat is no step (frozen: detected apart)
    steps = wrap_pi(psi[rows] - psi[prev])
    span = np.arange(int(prev.min()), win.start + 1)          # the yaw rate's turn over every step
    r_ok = a.nu_logged[span, 2] & np.isfinite(view.nu[span, 2])
    r = np.where(r_ok, view.nu[span, 2], 0.0)
    turn = np.concatenate([[0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * np.diff(t[span]))])
    n_ok = np.concatenate([[0], np.cumsum(r_ok)])
    k0, k1 = prev - span[0], rows - span[0]
    logged = n_ok[k1 + 1] - n_ok[k0] == k1 - k0 + 1
    dts = t[rows] - t[prev]
    fin = (a.segment_id[rows] == a.segment_id[rows - 1]) & np.isfinite(psi[rows]) & np.isfinite(psi[rows - 1])
    rates = wrap_pi(psi[rows] - psi[rows - 1])[fin] / (t[rows] - t[rows - 1])[fin]
    r_med = float(np.median(rates)) if rates.size else 0.0
    err = wrap_pi(steps - np.where(logged, turn[k1] - turn[k0], r_med * dts))
    jump = same & (np.abs(err) > settings.heading_jump_rad)
    return rows[jump], err[jump]


def _heading_outliers(jump_rows: np.ndarray, err: np.ndarray, start: int, tol: float) -> tuple[set, list, list]:
    """Rows of excursions (a jump away and one back that undoes it within ``tol`` [rad]: the
    rows in between, one for a spike) and of an unconfirmed jump into the start row; and
    the remaining jumps but one into the start row (lasting shifts), and the excursions as
    ``(jump away, jump back)`` rows: ``(bad rows, lasting, excursions)``."""
    bad, open_jumps, excursions = set(), [], []
    for r, e in zip(jump_rows.tolist(), err.tolist()):
        if open_jumps and abs(open_jumps[-1][1] + e) <= tol:        # back from the last jump away
            r0 = open_jumps.pop()[0]
            bad.update(range(r0, r))
            excursions.append((r0, r))
        else:
            open_jumps.append((r, e))
    lasting = [r for r, _ in open_jumps if r != start]
    if any(r == start for r, _ in open_jumps):                       # unconfirmed: treated as a spike
        bad.add(start)
    return bad, lasting, excursions


def detect_heading_jumps(view: LogView, win: Window, settings: WindowSettings) -> None:
    """Heading steps the yaw rate does not explain.

    Fault: a step between consecutive valid headings (the smallest signed angle, so a wrap
    across 0/360 or +-180 deg is no step) off by more than ``heading_jump_deg`` from what
    the yaw rate explains. Evidence: see :func:`_heading_jump_rows`; a jump away and one
    back that undoes it is an excursion (a spike when one sample long), a jump into the
    start row cannot yet be told from a lasting shift, anything else is a lasting shift.
    Flags ``heading_jump`` when a jump ends in the window, an excursion reaches into it, or
    a lasting shift ended in the ``lookback_s`` before it (the window then holds only
    shifted headings). Repair: excursion (and unconfirmed) headings are invalid, a yaw rate
    derived across any jump is derived again, and after a lasting shift only the new
    headings count.
    """
    jump_end, err = _heading_jump_rows(view, win, settings)
    if not jump_end.size:
        return
    W, t = win.rows, view.t
    bad, lasting, excursions = _heading_outliers(jump_end, err, win.start, settings.heading_jump_rad)
    first = int(np.searchsorted(t, t[win.start] - settings.window_s - settings.lookback_s, side="left"))
    lasting = [r for r in lasting if r >= first]   # shifts more than lookback_s before the window are history
    bad_w = sorted(r for r in bad if r >= win.lo)
    named = set(lasting) | ({win.start} if win.start in bad else set())
    named |= {r for pair in excursions if pair[1] > win.lo for r in pair}
    if not named:                                  # excursions wholly before the window
        return
    for r in bad_w:
        win.head_ok &= W != r
    touched = {r for j in jump_end.tolist() for r in (j - 1, j)} | {r for b in bad for r in (b - 1, b, b + 1)}
    hit = ~view.arrays.nu_logged[W, 2] & np.isin(W, list(touched))
    if hit.any():                                  # a derived r next to a jump holds the jump
        win.vel_ok[:, 2] &= ~hit
        win.vel_replace[2] = True
    done = []
    if bad_w:
        done.append(f"outlier(s) dropped (time_s {_rows_text(t, bad_w)})")
    if lasting:
        win.head_ok &= W >= max(lasting)
        done.append(f"lasting shift, headings from time_s {seconds_text(t[max(lasting)])} used")
    win.flag(FaultFlags.HEADING_JUMP,
             f"heading jump of more than {settings.heading_jump_deg:g} deg (not explained by the yaw rate) at "
             f"time_s {', '.join(seconds_text(t[r]) for r in sorted(named))}: {'; '.join(done)}")


def _rows_text(t: np.ndarray, rows: list) -> str:
    """The times of ``rows`` (sorted): ``a..b`` for three or more consecutive rows, else a list."""
    if len(rows) > 2 and rows[-1] - rows[0] == len(rows) - 1:
        return f"{seconds_text(t[rows[0]])}..{seconds_text(t[rows[-1]])}"
    return ", ".join(seconds_text(t[r]) for r in rows)


def detect_heading_wrap(view: LogView, win: Window) -> None:
    """The heading crossing 0/360 deg (or +-180 deg) in the window.

    Not a fault (informational). Evidence: the valid unwrapped headings fall in more than
    one turn (or half-turn). Flags ``heading_wrapped``; the mean is taken unwrapped.
    """
    hv = view.psi[win.rows][win.head_ok]
    if hv.size > 1:
        two_pi = 2.0 * np.pi
        if np.ptp(np.floor(hv / two_pi)) > 0 or np.ptp(np.floor((hv + np.pi) / two_pi)) > 0:
            win.flag(FaultFlags.HEADING_WRAPPED, "heading crosses 0/360 deg (or +-180 deg): averaged unwrapped")


def rederive_velocities(view: LogView, win: Window) -> np.ndarray:
    """The window's ``nu`` with the components marked for replacement derived again.

    Repair (no flag of its own): u, v from the end points of the valid positions (after
    a lasting shift, the new ones) rotated with the mean valid heading; r from the end
    points of the valid headings. Those components become valid. Returns (w, 3).
    """
    t, pos, psi, W = view.t, view.pos, view.psi, win.rows
    nu_w = window_nu(view, W)
    if win.vel_replace[:2].any() and win.head_ok.any():
        ok_rows = W[win.pos_ok & (W >= win.shift_from)]
        if ok_rows.size >= 2:
            a, b = ok_rows[0], ok_rows[-1]
            v_ned = (pos[b] - pos[a]) / (t[b] - t[a])
            psi_m = float(np.mean(psi[W][win.head_ok]))
            c, s = math.cos(psi_m), math.sin(psi_m)
            track = (c * v_ned[0] + s * v_ned[1], -s * v_ned[0] + c * v_ned[1])
            for j in np.flatnonzero(win.vel_replace[:2]):
                nu_w[:, j] = track[j]
                win.vel_ok[:, j] = True
    if win.vel_replace[2]:
        ok_rows = W[win.head_ok]
        if ok_rows.size >= 2:
            a, b = ok_rows[0], ok_rows[-1]
            nu_w[:, 2] = (psi[b] - psi[a]) / (t[b] - t[a])
            win.vel_ok[:, 2] = True
    return nu_w


def detect_too_little_valid(view: LogView, win: Window, settings: WindowSettings) -> bool:
    """Too little valid data left to start from.

    Fault: fewer than :attr:`LogView.n_min` valid samples of the heading or of a velocity
    component, or no valid position. Evidence: the counts after the other detectors.
    Flags ``too_little_valid`` and returns True: the start is refused.
    """
    counts = {"heading": int(win.head_ok.sum()), "u": int(win.vel_ok[:, 0].sum()),
              "v": int(win.vel_ok[:, 1].sum()), "r": int(win.vel_ok[:, 2].sum())}
    short = [f"{name}: {c} valid of {view.n_nom}" for name, c in counts.items() if c < view.n_min]
    if not win.pos_ok.any():
        short.insert(0, "position: no valid sample")
    if short:
        t = view.t
        # a start within one window of the log's first sample: say so, the usual cause
        early = ("" if win.lo > 0 or t[win.start] - t[0] >= settings.window_s else
                 f"; the window reaches back before the log's first sample (time_s {seconds_text(t[0])}): start later")
        win.flag(FaultFlags.TOO_LITTLE_VALID,
                 f"too little valid data in the {settings.window_s:g}-s window (time_s {seconds_text(t[win.lo])}.."
                 f"{seconds_text(t[win.start])}): {'; '.join(short)}; need at least {view.n_min} valid "
                 f"sample(s) of each and one position{early}")
    return bool(short)


def detect_dropped_wind(view: LogView, win: Window) -> np.ndarray:
    """The wind to hold over the forecast: the latest valid sample in the window.

    Fault: the log has wind columns but no valid wind sample in the window (sensor
    dropped), or none in all the rows read for the forecast (sensor dead). Evidence:
    :attr:`LogArrays.wind_logged` and :attr:`LogArrays.wind_columns`. Flags ``wind_dropped``;
    repair: no wind (zeros). Returns ``[speed_m_s, dir_from_rad]``.
    """
    a = view.arrays
    if not a.has_wind:
        if a.wind_columns:       # the columns are there, but not one valid sample in the rows read
            span = f"{seconds_text(a.time_s[0])}..{seconds_text(a.time_s[-1])}"
            win.flag(FaultFlags.WIND_DROPPED, f"{WIND_DROPPED_NOTES[1]} in the rows read for the "
                                              f"forecast (time_s {span}; sensor dead): forecast without wind")
        return np.zeros(2)
    w_rows = win.rows[win.wind_ok]
    if w_rows.size:
        return a.wind[w_rows[-1]]
    win.flag(FaultFlags.WIND_DROPPED, f"{WIND_DROPPED_NOTES[0]} (sensor dropped): forecast without wind")
    return np.zeros(2)


def _runs(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and last row of the run of bit-identical finite values containing each row.

    A non-finite row forms a run of its own. ``x`` has shape (N,) or (N, m).
    """
    x2 = x.reshape(x.shape[0], -1)
    n = x2.shape[0]
    fin = np.all(np.isfinite(x2), axis=1)
    change = np.ones(n, dtype=bool)
    if n > 1:
        change[1:] = np.any(x2[1:] != x2[:-1], axis=1) | ~fin[1:] | ~fin[:-1]
    idx = np.arange(n)
    first = np.maximum.accumulate(np.where(change, idx, 0))
    end_change = np.ones(n, dtype=bool)
    end_change[:-1] = change[1:]
    last = np.minimum.accumulate(np.where(end_change, idx, n - 1)[::-1])[::-1]
    return first, last


def _trapz(y: np.ndarray, x: np.ndarray, axis: int = 0) -> np.ndarray:
    """Trapezoid integral of ``y`` over ``x`` along ``axis`` (``np.trapezoid`` needs numpy 2)."""
    y = np.moveaxis(np.asarray(y, dtype=float), axis, 0)
    h = np.diff(np.asarray(x, dtype=float))
    return np.tensordot(h, 0.5 * (y[1:] + y[:-1]), axes=(0, 0))


def _ned(vel_body: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Body ``[u, v]`` rotated into NED ``[north, east]`` (the R(psi) of :func:`hybridship.frames.body_to_ned`)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.stack([c * vel_body[..., 0] - s * vel_body[..., 1], s * vel_body[..., 0] + c * vel_body[..., 1]], -1)
