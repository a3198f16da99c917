"""Sensor faults at forecast time: what is valid in the start window, and what was degraded.

A forecast starts from the state at its start time ``t0``: the position at ``t0`` and the
mean heading and velocities over the last ``window_s`` seconds (3 s, the paper's sliding
window). On board that window may hold faulty samples. The functions here are pure: they
never modify their inputs, and they decide for each forecast start which samples are
valid, compute the start values from those, and return a flag per fault so that the
forecast result (and the CLI) can say what was degraded. The predictors call them; see
``docs/reliability.md`` for the table of faults, behaviours and tests.

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
    A missing (NaN) position, heading, logged velocity or wind sample, or a missing sample
    (fewer rows than ``window_s`` holds at the nominal rate) in the window. The start
    values use the valid samples only; the position is the latest valid one, moved to
    ``t0`` with the window's mean velocity.
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
    positions are valid. Velocities derived from positions across a jump are invalid.
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
from .faults import FaultFlags, StartWindowError

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
    c, s = np.cos(psi), np.sin(psi)
    return np.stack([c * vel_body[..., 0] - s * vel_body[..., 1], s * vel_body[..., 0] + c * vel_body[..., 1]], -1)


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
        Start rows (e.g. :func:`hybridship.predictors.start_indices`).
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
        for the run to count as frozen.
    jump_m : float, default 5.0
        Position step error [m] beyond which a step is a jump.
    lookback_s : float, default 10.0
        History before the window used for the jump reference velocity [s].
    min_valid_fraction : float, default 0.5
        Fraction of the window's nominal samples that must be valid (heading and each
        velocity component); at least one valid position is always needed.
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
    if not window_s > 0 or not frozen_s > 0 or not jump_m > 0 or not 0 < min_valid_fraction <= 1:
        raise ValueError("window_s, frozen_s and jump_m must be > 0 and min_valid_fraction in (0, 1]")
    idx = np.atleast_1d(np.asarray(idx, dtype=int))
    t = arrays.time_s
    n = len(arrays)
    if np.any((idx < 0) | (idx >= n)):
        raise IndexError(f"idx: start rows must lie in 0..{n - 1}, got {idx[(idx < 0) | (idx >= n)][0]}")
    S = idx.size
    dt_nom = float(np.median(np.diff(t))) if n > 1 else 1.0
    n_nom = max(1, int(round(window_s / dt_nom)))
    n_min = max(1, math.ceil(min_valid_fraction * n_nom))
    eta, nu, psi = arrays.eta, arrays.nu, arrays.eta[:, 2]
    pos = eta[:, :2]
    has_col = arrays.nu_logged.any(axis=0)           # which velocity columns the log has
    affected = order.affected_time_s if order is not None else arrays.resorted_time_s

    pos_first, pos_last = _runs(pos)
    head_first, head_last = _runs(psi)
    vel_runs = [_runs(nu[:, j]) for j in range(3)]

    out_eta = np.full((S, 3), np.nan)
    out_nu = np.full((S, 3), np.nan)
    out_wind = np.zeros((S, 2))
    flags = {k: np.zeros(S, dtype=bool) for k in FaultFlags.START_WINDOW}
    notes: list[str] = []
    turn_rad = math.radians(frozen_turn_deg)

    for k, i in enumerate(idx):
        t0 = t[i]
        # the window always holds the start row (a window shorter than half a step would not)
        lo = min(int(np.searchsorted(t, t0 - window_s + 0.5 * dt_nom, side="left")), int(i))
        W = np.arange(lo, i + 1)
        note: list[str] = []

        pos_ok = np.all(np.isfinite(pos[W]), axis=1)
        head_ok = np.isfinite(psi[W])
        vel_ok = np.isfinite(nu[W])                      # (w, 3)
        wind_ok = arrays.wind_logged[W]

        # ---- missing samples / NaN
        n_missing = max(0, n_nom - W.size)
        nan_cols = []
        if not pos_ok.all():
            nan_cols.append("position")
        if not head_ok.all():
            nan_cols.append("heading")
        for j, name in enumerate(("u", "v", "r")):
            if has_col[j] and not arrays.nu_logged[W, j].all():
                nan_cols.append(name)
        if arrays.has_wind and not wind_ok.all():
            nan_cols.append("wind")
        if nan_cols or n_missing:
            flags[FaultFlags.NAN_IN_WINDOW][k] = True
            what = f"missing {', '.join(nan_cols)}" if nan_cols else ""
            gap = f"{n_missing} missing sample(s)" if n_missing else ""
            note.append(f"{'; '.join(x for x in (what, gap) if x)} in the window: valid samples used")

        # ---- late / out of order
        # the nominal window: a removed (conflicting) sample leaves no row but is still in it
        if affected.size and np.any((affected >= min(t[lo], t0 - window_s + 0.5 * dt_nom) - 1e-9)
                                    & (affected <= t0 + 1e-9)):
            flags[FaultFlags.LATE_OR_OUT_OF_ORDER][k] = True
            note.append("late, out-of-order or duplicated samples in the window: re-sorted by time")

        # ---- frozen channels (runs up to the start row only: causal)
        def stale_rows(first, last, contradicted) -> np.ndarray:
            """Rows of W that repeat the first sample of a frozen, contradicted run."""
            stale = np.zeros(W.size, dtype=bool)
            for a in np.unique(first[W]):
                b = min(int(last[a]), i)
                if b <= a or t[b] - t[a] < frozen_s - 1e-9:
                    continue
                if contradicted(a, b):
                    stale |= (W > a) & (W <= b)
            return stale

        def logged_uv(a, b):
            return arrays.nu_logged[a:b + 1, 0].all() and arrays.nu_logged[a:b + 1, 1].all()

        def pos_contradicted(a, b):
            if not logged_uv(a, b):
                return False
            v_ned = _ned(nu[a:b + 1, :2], psi[a:b + 1])
            if not np.all(np.isfinite(v_ned)):
                return False
            disp = _trapz(v_ned, t[a:b + 1], axis=0)
            return float(np.hypot(*disp)) >= frozen_motion_m

        def head_contradicted(a, b):
            if not arrays.nu_logged[a:b + 1, 2].all():
                return False
            return abs(float(_trapz(nu[a:b + 1, 2], t[a:b + 1]))) >= turn_rad

        def vel_contradicted(j):
            def check(a, b):
                if not arrays.nu_logged[a:b + 1, j].all():
                    return False
                if j == 2:
                    if not (np.isfinite(psi[a]) and np.isfinite(psi[b])):
                        return False
                    return abs((psi[b] - psi[a]) - nu[a, 2] * (t[b] - t[a])) >= turn_rad
                if not (np.all(np.isfinite(pos[[a, b]])) and np.isfinite(psi[a:b + 1]).all()):
                    return False
                v_body = nu[a:b + 1, :2].copy()
                other = 1 - j
                if not arrays.nu_logged[a:b + 1, other].all():
                    return False
                disp_log = _trapz(_ned(v_body, psi[a:b + 1]), t[a:b + 1], axis=0)
                disp_track = pos[b] - pos[a]
                return float(np.hypot(*(disp_log - disp_track))) >= frozen_motion_m
            return check

        frozen_what = []
        st = stale_rows(pos_first, pos_last, pos_contradicted)
        if st.any():
            pos_ok &= ~st
            frozen_what.append("position (the logged speed says the ship moved)")
        st = stale_rows(head_first, head_last, head_contradicted)
        if st.any():
            head_ok &= ~st
            frozen_what.append("heading (the logged yaw rate says it turned)")
        vel_replace = np.zeros(3, dtype=bool)
        for j, name in enumerate(("u_m_s", "v_m_s", "r_deg_s")):
            st = stale_rows(*vel_runs[j], vel_contradicted(j))
            if st.any():
                vel_ok[:, j] = False
                vel_replace[j] = True
                frozen_what.append(f"{name} (disagrees with the track): derived from the track instead")
        if frozen_what:
            flags[FaultFlags.FROZEN_SENSOR][k] = True
            note.append(f"frozen for >= {frozen_s:g} s: {'; '.join(frozen_what)}")

        # ---- position jumps (steps ending in the window)
        shift_from = lo
        lb = int(np.searchsorted(t, t0 - window_s - lookback_s, side="left"))
        rows = np.arange(max(lb, 1), i + 1)               # step r goes from row r-1 to r
        if rows.size:
            p_ok = np.all(np.isfinite(pos[rows]), axis=1) & np.all(np.isfinite(pos[rows - 1]), axis=1)
            dts = t[rows] - t[rows - 1]
            same = (arrays.segment_id[rows] == arrays.segment_id[rows - 1]) & p_ok
            steps = pos[rows] - pos[rows - 1]
            step_v = steps / dts[:, None]
            both_logged = (arrays.nu_logged[rows, 0] & arrays.nu_logged[rows, 1]
                           & arrays.nu_logged[rows - 1, 0] & arrays.nu_logged[rows - 1, 1])
            v_log = 0.5 * (_ned(nu[rows, :2], psi[rows]) + _ned(nu[rows - 1, :2], psi[rows - 1]))
            v_med = np.median(step_v[same], axis=0) if same.any() else np.zeros(2)
            v_ref = np.where((both_logged & np.all(np.isfinite(v_log), axis=1))[:, None], v_log, v_med)
            err = np.hypot(*(steps - v_ref * dts[:, None]).T)
            jump = same & (err > jump_m)
            jump_end = rows[jump]
            in_w = jump_end[jump_end >= lo]
            if in_w.size:
                flags[FaultFlags.POSITION_JUMP][k] = True
                jump_set = set(int(r) for r in jump_end)
                bad_pos = set()
                for r in sorted(jump_set):
                    if (r - 1) in bad_pos:               # the return from a spike
                        continue
                    if r == i or (r + 1) in jump_set:   # unconfirmed jump into the start, or a spike
                        bad_pos.add(r)
                for r in bad_pos:
                    pos_ok &= W != r
                # derived velocities next to a jump are invalid
                touched = set()
                for r in jump_end:
                    touched.update((int(r) - 1, int(r)))
                for r in bad_pos:
                    touched.update((r - 1, r, r + 1))
                for j in range(2):
                    hit = ~arrays.nu_logged[W, j] & np.isin(W, list(touched))
                    if hit.any():
                        vel_ok[:, j] &= ~hit
                        vel_replace[j] = True  # derived velocity: re-derive from the valid positions
                lasting = [int(r) for r in in_w if int(r) not in bad_pos and int(r) - 1 not in bad_pos]
                if lasting:
                    shift_from = max(lasting)
                note.append(f"position jump of more than {jump_m:g} m at time_s "
                            f"{', '.join(f'{t[int(r)]:g}' for r in in_w)}: "
                            f"{'outlier(s) dropped' if bad_pos else 'lasting shift, new positions used'}")

        # ---- heading wrap (informational)
        hv = psi[W][head_ok]
        if hv.size > 1:
            two_pi = 2.0 * np.pi
            if np.ptp(np.floor(hv / two_pi)) > 0 or np.ptp(np.floor((hv + np.pi) / two_pi)) > 0:
                flags[FaultFlags.HEADING_WRAPPED][k] = True
                note.append("heading crosses 0/360 deg (or +-180 deg): averaged unwrapped")

        # ---- replacement of frozen logged velocities by track-derived ones
        # (end points of the valid samples in the window; positions after a lasting shift)
        nu_w = nu[W].copy()
        if vel_replace[:2].any() and head_ok.any():
            ok_rows = W[pos_ok & (W >= shift_from)]
            if ok_rows.size >= 2:
                a, b = ok_rows[0], ok_rows[-1]
                v_ned = (pos[b] - pos[a]) / (t[b] - t[a])
                psi_m = float(np.mean(psi[W][head_ok]))
                c, s = math.cos(psi_m), math.sin(psi_m)
                track = (c * v_ned[0] + s * v_ned[1], -s * v_ned[0] + c * v_ned[1])
                for j in np.flatnonzero(vel_replace[:2]):
                    nu_w[:, j] = track[j]
                    vel_ok[:, j] = True
        if vel_replace[2]:
            ok_rows = W[head_ok]
            if ok_rows.size >= 2:
                a, b = ok_rows[0], ok_rows[-1]
                nu_w[:, 2] = (psi[b] - psi[a]) / (t[b] - t[a])
                vel_ok[:, 2] = True

        # ---- enough valid data?
        counts = {"heading": int(head_ok.sum()), "u": int(vel_ok[:, 0].sum()), "v": int(vel_ok[:, 1].sum()),
                  "r": int(vel_ok[:, 2].sum())}
        short = [f"{name}: {c} valid of {n_nom}" for name, c in counts.items() if c < n_min]
        if not pos_ok.any():
            short.insert(0, "position: no valid sample")
        if short:
            flags[FaultFlags.TOO_LITTLE_VALID][k] = True
            note.append(f"too little valid data in the {window_s:g}-s window (time_s {t[lo]:g}..{t0:g}): "
                        f"{'; '.join(short)}; need at least {n_min} valid sample(s) of each and one position")
            notes.append("; ".join(note))
            continue

        psi0 = float(np.mean(psi[W][head_ok]))
        nu0 = np.array([np.mean(nu_w[vel_ok[:, j], j]) for j in range(3)])
        last = int(W[np.flatnonzero(pos_ok)[-1]])
        p0 = pos[last].copy()
        if last != i:
            c, s = math.cos(psi0), math.sin(psi0)
            p0 += (t0 - t[last]) * np.array([c * nu0[0] - s * nu0[1], s * nu0[0] + c * nu0[1]])
            note.append(f"position from time_s {t[last]:g} moved to the start with the mean velocity")
        out_eta[k] = [p0[0], p0[1], psi0]
        out_nu[k] = nu0

        # ---- wind
        if arrays.has_wind:
            w_rows = W[wind_ok]
            if w_rows.size:
                out_wind[k] = arrays.wind[w_rows[-1]]
            else:
                flags[FaultFlags.WIND_DROPPED][k] = True
                note.append("no valid wind sample in the window (sensor dropped): forecast without wind")
        notes.append("; ".join(note))

    result = StartWindow(start_time_s=t[idx].copy(), eta0=out_eta, nu0=out_nu, wind=out_wind, flags=flags,
                         notes=tuple(notes))
    refused = result.refused
    if on_refuse == "raise" and refused.any():
        k = int(np.argmax(refused))
        reason = notes[k]
        more = f" ({int(refused.sum())} of {S} starts refused, at time_s " \
               f"{', '.join(f'{x:g}' for x in result.start_time_s[refused][:5])}{', ...' if refused.sum() > 5 else ''})"
        raise StartWindowError(
            f"start time_s {t[idx[k]]:g}: refused, {reason}{more if refused.sum() > 1 else ''}",
            start_time_s=float(t[idx[k]]), reason=reason, refused_start_times_s=result.start_time_s[refused])
    return result
