"""Sensor faults at forecast time: what is valid in the start window, and what was degraded.

A forecast starts from the state at its start time ``t0``: the position at ``t0`` and the
mean heading and velocities over the last ``window_s`` seconds (3 s, the paper's sliding
window). On board that window may hold faulty samples. The functions here are pure: they
never modify their inputs, and they decide for each forecast start which samples are
valid, compute the start values from those, and return a flag per fault so that the
forecast result (and the CLI) can say what was degraded. The predictors call them; see
``docs/reliability.md`` for the table of faults, behaviours and tests.

:func:`assess_start_window` is a short driver: one named detector per fault (in
:mod:`hybridship.forecast_inputs.faults`) looks at each start's window in turn, after
:mod:`hybridship.forecast_inputs.quiet_starts` has cleared, for all starts at once, those
whose window holds nothing any detector could flag (nearly all, on a healthy log).

Pipeline at forecast time::

    arrays = ingest(log, vessel, purpose="forecast")          # sort, repair, validate, convert
    window = assess_start_window(arrays, idx, 3.0)
    eta0, nu0, wind0 = window.eta0, window.nu0, window.wind  # use these as start values
    window.flags[FaultFlags.WIND_DROPPED]                    # (S,) bool per start

Faults and their behaviour (``FaultFlags`` names the flags):

``late_or_out_of_order``
    Samples whose ``time_s`` is earlier than a sample before them in the file (arrived
    late), or repeated times. :func:`~hybridship.logs.ingest.sort_samples` re-sorts by time (stable); an exact
    duplicate row is dropped; duplicates that disagree are all removed (neither is trusted;
    the time becomes a missing sample). Flagged for starts whose window contains
    such a time. Rows without a finite ``time_s`` cannot be placed and are dropped
    (counted in :attr:`~hybridship.logs.ingest.SortedLog.n_without_time`).
``nan_in_window``
    A missing (NaN) position, heading, logged velocity, wind or command sample, or a missing
    sample (fewer rows than ``window_s`` holds at the nominal rate) in the window. The start
    values use the valid samples only; the position is the latest valid one, moved to
    ``t0`` with the window's mean velocity; commands missing at the start hold their last
    logged values, and the note says from when.
``too_little_valid``
    Fewer than ``ceil(min_valid_fraction * n)`` valid samples of the heading or of a
    velocity component (``n`` = samples the window holds at the nominal rate), or no valid
    position in the window. The start is refused: :class:`StartWindowError` (default) or,
    with ``on_refuse="flag"``, NaN start values and this flag.
``frozen_sensor``
    A channel repeating the bit-identical value for at least ``frozen_s`` seconds (default
    3 s) while an independent logged channel says it must have changed: a position while the logged
    speed moves the ship by ``frozen_motion_m`` or more; a heading while the logged yaw
    rate turns it by ``frozen_turn_deg`` or more; a logged velocity (u, v or r) while the
    track (or the heading) disagrees with it by as much. The repeats after the first sample
    are stale (not valid). A stale logged velocity is replaced by the one derived from the
    valid positions (headings) in the window; a stale position or heading leaves no valid
    sample in the window, so the start is refused until live samples return (their return
    is a position jump: the first live sample is an unconfirmed outlier for one start).
    Until the contradiction reaches its threshold a freeze cannot be detected, which
    bounds the error of an undetected frozen position to about ``max(frozen_motion_m,
    speed * frozen_s)`` and of a heading to about ``max(frozen_turn_deg, |r| * frozen_s)``. Without the independent channel a
    constant value cannot be told from a vessel at rest (or a steady noise-free
    simulation) and is not flagged; a frozen wind sensor cannot be told from a steady
    wind and is not detected.
``position_jump``
    A step between consecutive positions that differs from what the velocity explains
    (logged velocities where both ends have them, else the median step velocity over the
    last ``lookback_s``) by more than ``jump_m``. A sample that jumps away and back (a
    spike) is invalid; a jump into the start sample is treated the same way (it cannot yet
    be told from a lasting shift); after a lasting shift (a datum change) the new
    positions are valid, and the flag stays set while the shift lies within ``lookback_s``
    before the window (as for ``heading_jump``). Velocities derived from positions across
    a jump are invalid; logged velocities flagged ``velocity_mismatch`` do not explain steps.
``velocity_mismatch``
    The logged ``u``, ``v``, rotated with the heading, disagree with the track by more than
    ``track_mismatch_m`` (8 m) over the trailing ``track_window_s`` (30 s)
    (:func:`~hybridship.forecast_inputs.faults.velocity_track_mismatch_m`; not judged
    while a position jump or a frozen receiver lies in that window, nor in the first 15 s
    of a segment, where the judgement of the past 30 s, also from before a gap, is
    carried): a biased or failed speed log, or a heading off by a lasting angle while
    under way. u and v are derived from the track instead. The environment estimator of a
    hybrid forecast leaves such samples out of its filter as well (with the default
    thresholds), so its start state stays on the track. A bias is found once it has moved
    the ship 8 m off the track (8 s at 1 m/s; a bias under 0.27 m/s never); until then it
    is in the start values.
``heading_jump``
    A step between consecutive valid headings (the smallest signed angle: a wrap across
    0/360 or +-180 deg is no step) that differs from what the yaw rate explains (the logged
    ``r_deg_s`` where both ends have it, else the median step rate of the recent history)
    by more than ``heading_jump_deg``. A heading that jumps away and back (a spike, or an
    excursion of several samples) is invalid; a jump into the start sample is treated the
    same way (it cannot yet be told from a lasting shift); after a lasting shift only the
    new headings are valid, and the flag stays set while the shift lies within
    ``lookback_s`` before the window. A yaw rate derived from headings across a jump is
    derived again. A real turn, however fast, is explained by its yaw rate and not flagged.
``heading_wrapped``
    The heading crosses 0/360 deg (or +-180 deg) in the window. Informational: the average
    is taken over the unwrapped heading, so the start heading is right (359, 0, 1 deg
    averages to 0 deg, not 120 deg).
``wind_dropped``
    The log has wind columns but no valid wind sample in the window (sensor dropped): the
    forecast falls back to no wind (speed 0) and is flagged. With a valid sample the
    latest one is used (as without faults).
``input_clipped``, ``out_of_envelope``
    Set by :func:`hybridship.forecast_inputs.limits.check_or_clip_inputs` and from the out-of-envelope
    guard's weight; named here so that every flag column comes from one list.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..logs.ingest import SortedLog, ingest_with_report
from ..logs.io import LogArrays
from ..messages import seconds_text
from .faults import (TRACK_MISMATCH_M, TRACK_WINDOW_S, VALID_USED, FaultFlags, LogView, StartWindowError, Window,
                     WindowSettings, detect_dropped_wind, detect_frozen_channels, detect_heading_jumps,
                     detect_heading_wrap, detect_late_samples, detect_missing_samples, detect_position_jumps,
                     detect_too_little_valid, detect_velocity_mismatch, rederive_velocities)
from .quiet_starts import quiet_starts

__all__ = [
    "StartWindow",
    "forecast_log_arrays",
    "assess_start_window",
]


def forecast_log_arrays(log, vessel, *, source: str | None = None) -> tuple[LogArrays, SortedLog | None]:
    """A log as :class:`LogArrays` for forecasting, tolerating sensor faults.

    :func:`hybridship.logs.ingest.ingest` with ``purpose="forecast"``: re-sorted with
    :func:`~hybridship.logs.ingest.sort_samples`, checked against the vessel
    (:func:`hybridship.logs.io.check_log_against_vessel`) with missing positions and
    headings allowed, and converted. Format errors (units, names, ranges, thruster
    columns) are still refused; only sensor faults pass, for :func:`assess_start_window`
    to judge per start.

    Parameters
    ----------
    log : path, pandas.DataFrame or LogArrays
        LogArrays are checked too (see :func:`~hybridship.logs.ingest.ingest`).
    vessel : hybridship.vessel.Vessel or str
        Vessel, or a packaged name or vessel-file path (see :func:`hybridship.vessel.load_vessel`).
    source : str, optional
        Quoted in messages (default: the file name or "log").

    Returns
    -------
    arrays : LogArrays
    order : SortedLog or None
        The sort report (None when already-checked LogArrays were passed through).
    """
    return ingest_with_report(log, vessel, purpose="forecast", name=source)


# --------------------------------------------------------------------------------------
# The start window
# --------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class StartWindow:
    """Start values and fault flags of a batch of forecast starts.

    Attributes
    ----------
    start_time_s : ndarray, shape (S,)
    eta0 : ndarray, shape (S, 3)
        ``[north_m, east_m, psi_rad]`` at the start (NaN for refused starts).
    nu0 : ndarray, shape (S, 3)
        ``[u_m_s, v_m_s, r_rad_s]``, mean of the valid samples in the window.
    wind : ndarray, shape (S, 2)
        ``[speed_m_s, dir_from_rad]`` to hold over the forecast (zeros after a dropped
        wind sensor, or when the log has no wind).
    flags : dict of str to ndarray of bool, shape (S,)
        One entry per name in :attr:`FaultFlags.START_WINDOW`.
    notes : tuple of str
        Per start, what was found and done ("" when nothing).
    """

    start_time_s: np.ndarray
    eta0: np.ndarray
    nu0: np.ndarray
    wind: np.ndarray
    flags: dict = field(default_factory=dict)
    notes: tuple = ()

    @property
    def refused(self) -> np.ndarray:
        """(S,) True where the start was refused (too little valid data)."""
        return self.flags[FaultFlags.TOO_LITTLE_VALID]

    @property
    def degraded(self) -> np.ndarray:
        """(S,) True where any flag other than the informational ones is set."""
        out = np.zeros(self.start_time_s.shape, dtype=bool)
        for k, v in self.flags.items():
            if k not in FaultFlags.INFORMATIONAL:
                out |= v
        return out

    def to_frame(self) -> pd.DataFrame:
        """One row per start: ``start_time_s``, a bool column per flag, and ``notes``."""
        cols = {"start_time_s": self.start_time_s}
        cols.update({k: self.flags[k] for k in FaultFlags.START_WINDOW})
        cols["notes"] = list(self.notes)
        return pd.DataFrame(cols)

    def flag_columns(self, repeat: int) -> dict[str, np.ndarray]:
        """Flag columns for a tidy forecast table with ``repeat`` rows per start."""
        return {k: np.repeat(self.flags[k], repeat) for k in FaultFlags.START_WINDOW}


def assess_start_window(
    arrays: LogArrays,
    idx,
    window_s: float = 3.0,
    *,
    order: SortedLog | None = None,
    frozen_s: float = 3.0,
    frozen_motion_m: float = 2.0,
    frozen_turn_deg: float = 1.0,
    jump_m: float = 5.0,
    lookback_s: float = 10.0,
    min_valid_fraction: float = 0.5,
    heading_jump_deg: float = 10.0,
    track_window_s: float = TRACK_WINDOW_S,
    track_mismatch_m: float = TRACK_MISMATCH_M,
    on_refuse: str = "raise",
) -> StartWindow:
    """Validate the start window of each forecast start and compute its start values.

    Without faults the result equals the predictors' plain rule: position at the start
    row, heading and velocities averaged over the rows within ``window_s`` (the last
    ``round(window_s / dt)`` samples), wind of the start row.

    Parameters
    ----------
    arrays : LogArrays
        The log, e.g. from :func:`forecast_log_arrays` (may hold NaN positions/headings).
    idx : array_like of int, shape (S,)
        Start rows (e.g. :func:`hybridship.predictors.start_indices`); fractional rows and
        boolean masks are refused (TypeError naming ``idx``).
    window_s : float, default 3.0
        Start window [s]: rows with ``t0 - window_s < time_s <= t0`` (half a sample of slack).
    order : SortedLog, optional
        The sort report of the log, to flag ``late_or_out_of_order`` (default: the times
        the ingest re-sorted or dropped, :attr:`LogArrays.resorted_time_s`).
    frozen_s : float, default 3.0
        A channel bit-identical for at least this long [s] is checked for being frozen
        (it counts as frozen only if the independent channel contradicts it, so a short
        duration is safe; the default equals the start window, so an undetected frozen
        position is off by at most about ``max(frozen_motion_m, speed * frozen_s)``).
    frozen_motion_m, frozen_turn_deg : float
        Motion [m] / turn [deg] over the frozen run that the independent channel must show
        for the run to count as frozen (> 0: with 0 a ship at rest would count as frozen).
    jump_m : float, default 5.0
        Position step error [m] beyond which a step is a jump.
    lookback_s : float, default 10.0
        History before the window used for the jump reference velocity [s] (>= 0).
    min_valid_fraction : float, default 0.5
        Fraction of the window's nominal samples that must be valid (heading and each
        velocity component); at least one valid position is always needed.
    heading_jump_deg : float, default 10.0
        Heading step error [deg] beyond which a step is a jump (``0 < heading_jump_deg <
        180``). With a logged yaw rate a real turn's step is explained to within the yaw
        acceleration's effect over one sample, well under 1 deg at 1 Hz (at most 1.0 deg in
        the packaged Gunnerus scenarios and the truthsim-dev logs, whose yaw rates reach
        4 deg/s); without it the reference is the median step rate, which at the onset of a
        turn leaves up to ``|r| * dt`` unexplained: 10 deg covers yaw rates up to 10 deg/s at
        1 Hz, more than twice the Gunnerus's fastest. A log sampled slower than 1 Hz without
        ``r_deg_s`` may need a larger value; a gyro or compass fault (a wrong heading source,
        a spike) is typically tens of degrees.
    track_window_s, track_mismatch_m : float, default 30.0 and 8.0
        ``velocity_mismatch`` above ``track_mismatch_m`` [m] over ``track_window_s`` [s].
    on_refuse : {"raise", "flag"}
        Raise :class:`StartWindowError` for a refused start, or return it flagged with
        NaN start values.

    Returns
    -------
    StartWindow

    Raises
    ------
    StartWindowError
        If a start has too little valid data and ``on_refuse == "raise"``.
    """
    if on_refuse not in ("raise", "flag"):
        raise ValueError(f"on_refuse must be 'raise' or 'flag', got {on_refuse!r}")
    settings = WindowSettings(window_s, frozen_s, frozen_motion_m, frozen_turn_deg, jump_m, lookback_s,
                              min_valid_fraction, heading_jump_deg, track_window_s, track_mismatch_m)
    idx = _start_rows(idx, len(arrays))
    affected = order.affected_time_s if order is not None else arrays.resorted_time_s
    view = LogView.build(arrays, settings, affected, int(idx.min()) if idx.size else 0)
    # the starts no detector can flag at once, the others one by one
    quiet, out_eta, out_nu, out_wind = quiet_starts(view, idx, settings)
    flags = {k: np.zeros(idx.size, dtype=bool) for k in FaultFlags.START_WINDOW}
    notes = [""] * idx.size
    for k in np.flatnonzero(~quiet):
        win, start = _assess_start(view, int(idx[k]), settings)
        if start is not None:
            out_eta[k], out_nu[k], out_wind[k] = start
        for name in win.flags:
            flags[name][k] = True
        notes[k] = "; ".join(win.notes)
    result = StartWindow(start_time_s=arrays.time_s[idx].copy(), eta0=out_eta, nu0=out_nu, wind=out_wind,
                         flags=flags, notes=tuple(notes))
    if on_refuse == "raise" and result.refused.any():
        raise _refusal(result)
    return result


def _start_rows(idx, n: int) -> np.ndarray:
    """``idx`` as int start rows within ``0..n - 1``: a TypeError for fractions, infinities, text
    or a boolean mask (int() would read row 100.7 as 100 and a mask as rows 0 and 1), a
    ValueError for more than one axis, an IndexError for rows outside the log, each naming
    ``idx``."""
    raw = np.atleast_1d(np.asarray(idx))
    if raw.ndim != 1:
        raise ValueError(f"idx: expected start rows of shape (S,), got shape {raw.shape}")
    whole = np.isfinite(raw) & (raw == np.round(raw)) if raw.dtype.kind == "f" else True
    if raw.size and (raw.dtype.kind not in "iuf" or not np.all(whole)):
        raise TypeError(f"idx: expected start rows as whole numbers, got {raw.dtype} values {raw.ravel()[:3].tolist()}")
    rows = raw.astype(int)
    if np.any((rows < 0) | (rows >= n)):
        raise IndexError(f"idx: start rows must lie in 0..{n - 1}, got {rows[(rows < 0) | (rows >= n)][0]}")
    return rows


def _assess_start(view: LogView, i: int, settings: WindowSettings):
    """Run the detectors on the window of start row ``i``.

    Returns the window (flags, notes) and ``(eta0, nu0, wind)``, or None when refused.
    """
    win = Window.at(view, i, settings.window_s)
    detect_missing_samples(view, win)
    detect_late_samples(view, win, settings)
    detect_frozen_channels(view, win, settings)
    detect_velocity_mismatch(view, win, settings)
    detect_position_jumps(view, win, settings)
    detect_heading_jumps(view, win, settings)
    detect_heading_wrap(view, win)
    nu_w = rederive_velocities(view, win)
    if detect_too_little_valid(view, win, settings):
        # the refusal first; the other findings as what led to it (no "valid samples used")
        win.notes[:] = [win.notes[-1]] + [n.replace(VALID_USED, "") for n in win.notes[:-1]]
        return win, None
    eta0, nu0 = _start_values(view, win, nu_w)
    return win, (eta0, nu0, detect_dropped_wind(view, win))


def _start_values(view: LogView, win: Window, nu_w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``eta0``: the latest valid position, moved to the start time with the mean velocity
    when it is older, and the mean valid heading; ``nu0``: the mean valid velocities."""
    t, W = view.t, win.rows
    psi0 = float(np.mean(view.psi[W][win.head_ok]))
    nu0 = np.array([np.mean(nu_w[win.vel_ok[:, j], j]) for j in range(3)])
    last = int(W[np.flatnonzero(win.pos_ok)[-1]])
    p0 = view.pos[last].copy()
    if last != win.start:
        c, s = math.cos(psi0), math.sin(psi0)
        p0 += (t[win.start] - t[last]) * np.array([c * nu0[0] - s * nu0[1], s * nu0[0] + c * nu0[1]])
        win.notes.append(f"position from time_s {seconds_text(t[last])} moved to the start with the mean velocity")
    return np.array([p0[0], p0[1], psi0]), nu0


def _refusal(result: StartWindow) -> StartWindowError:
    """The error for the first refused start, listing (up to five of) the others."""
    refused = result.refused
    k = int(np.argmax(refused))
    reason = result.notes[k]
    t_refused = result.start_time_s[refused]
    more = (f" ({int(refused.sum())} of {refused.size} starts refused, at time_s "
            f"{', '.join(seconds_text(x) for x in t_refused[:5])}{', ...' if refused.sum() > 5 else ''})")
    t0 = result.start_time_s[k]
    return StartWindowError(f"start time_s {seconds_text(t0)}: refused, {reason}{more if refused.sum() > 1 else ''}",
                            start_time_s=float(t0), reason=reason, refused_start_times_s=t_refused)
