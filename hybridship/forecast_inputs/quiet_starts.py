"""Starts whose window holds nothing for any detector, found for all starts at once.

:func:`~hybridship.forecast_inputs.start_window.assess_start_window` runs the detectors of
:mod:`hybridship.forecast_inputs.faults` start by start, which costs about a millisecond
each. On a healthy log nearly every start is *quiet*: every sample of its window is valid
and no detector can fire. This module finds those starts with array operations over all
starts, and their start values by the plain rule (the position at the start row, heading
and velocities averaged over the window, the wind of the start row); only the other starts
go through the detectors.

Each test here is conservative, a sufficient condition for "no detector fires": a start
that it cannot clear, or clears only within a relative margin of a threshold (where the
array arithmetic could round differently from the detectors'), goes to the detectors. A
quiet start therefore gets exactly what the detectors would give it (no flag, no note, the
same start values); ``tests/test_quality.py`` checks that on every injected fault.

What clears a start (``i``, its window ``W`` of exactly the nominal number of rows):

* every position, heading, velocity, wind (when logged) and command sample in ``W`` is
  finite and logged, and no late, duplicated or removed sample time lies in it;
* no channel (position, heading, u, v, r) repeats a bit-identical value for ``frozen_s``
  within ``W`` (whether or not an independent channel contradicts it);
* no row of ``W`` has its logged u, v contradicted by the track;
* every position step from ``lookback_s`` before ``W`` to ``i`` is explained by the logged
  velocities within ``jump_m`` (a step without logged velocities at both ends is not cleared);
* every heading step from ``3 lookback_s`` before ``W`` to ``i`` is explained by the logged
  yaw rate within ``heading_jump_deg`` (no step without it is cleared);
* the heading does not cross 0/360 or +-180 deg in ``W``, the log's wind sensor is not dead.
"""

from __future__ import annotations

import numpy as np

from ..frames import wrap_pi
from .faults import LogView, WindowSettings, _ned, window_nu

__all__ = ["quiet_starts"]

#: Relative margin on the thresholds within which a start is left to the detectors.
THRESHOLD_MARGIN = 1e-6
#: Margin [s] around a start window within which a late sample time leaves it to the detectors.
LATE_MARGIN_S = 1e-3


class _Rows:
    """The rows ``r0..r1`` the checks of a batch of starts read, and counts over them: a
    forecast's few starts on a long log read a few hundred rows, not the whole log."""

    def __init__(self, r0: int, r1: int):
        self.r0, self.rows = r0, np.arange(r0, r1 + 1)

    def none_in(self, bad: np.ndarray, first: np.ndarray, last: np.ndarray) -> np.ndarray:
        """Per span of global rows ``first..last`` (within ``r0..r1``; an empty span has none),
        True when ``bad`` (one entry per row of ``rows``) holds none of them."""
        counts = np.concatenate([[0], np.cumsum(bad, dtype=np.int64)])
        a, b = first - self.r0, last - self.r0
        return counts[b + 1] - counts[np.minimum(a, b + 1)] == 0


def _windows_valid(view: LogView, span: _Rows, lo: np.ndarray, idx: np.ndarray,
                   settings: WindowSettings) -> np.ndarray:
    """Every sample of rows ``lo..idx`` finite and logged, and no late sample time near them."""
    a, t, g = view.arrays, view.t, span.rows
    bad = ~np.all(np.isfinite(a.eta[g]), axis=1) | ~np.all(np.isfinite(a.nu[g]), axis=1) | ~a.commands_logged[g]
    bad |= np.any(a.nu_logged.any(axis=0) & ~a.nu_logged[g], axis=1)
    if a.has_wind:
        bad |= ~a.wind_logged[g]
    bad |= view.track_mismatch[g]          # the logged u, v contradicted by the track
    ok = span.none_in(bad, lo, idx)
    late = np.sort(np.asarray(view.affected_time_s, dtype=float))
    if late.size:
        # the detector's span (detect_late_samples), widened by a margin
        t_lo = np.minimum(t[lo], t[idx] - settings.window_s + 0.5 * view.dt_nom)
        ok &= (np.searchsorted(late, t[idx] + LATE_MARGIN_S, side="right")
               == np.searchsorted(late, t_lo - LATE_MARGIN_S, side="left"))
    return ok


def _not_frozen(view: LogView, span: _Rows, lo: np.ndarray, settings: WindowSettings) -> np.ndarray:
    """No run of bit-identical values of any channel lasting ``frozen_s`` within the windows
    (rows ``lo .. lo + n_nom - 1``): a run's length up to a row of the window is
    ``t[row] - t[first row of the run]``, largest at its last row in the window."""
    t, n, g = view.t, view.n_nom, span.rows
    limit = (settings.frozen_s - 1e-9) * (1.0 - THRESHOLD_MARGIN)
    ok = np.ones(lo.size, dtype=bool)
    for first, _ in (view.pos_runs, view.head_runs, *view.vel_runs):
        held = t[g] - t[first[g]]
        ok &= np.lib.stride_tricks.sliding_window_view(held, n).max(axis=1)[lo - span.r0] < limit
    return ok


def _steps_explained(view: LogView, span: _Rows, first: np.ndarray, idx: np.ndarray,
                     settings: WindowSettings) -> np.ndarray:
    """Every position step ending in rows ``first..idx`` (from ``lookback_s`` before the
    window to the start) explained by the logged velocities (the detector's rule where both
    ends have them) within ``jump_m``."""
    a, t, pos, psi, nu = view.arrays, view.t, view.pos, view.psi, view.nu
    r = span.rows[1:]                  # step r goes from row r - 1 to r (no start looks at step r0)
    same = (a.segment_id[r] == a.segment_id[r - 1]) & np.all(np.isfinite(pos[r]), axis=1) \
        & np.all(np.isfinite(pos[r - 1]), axis=1)
    both_logged = (a.nu_logged[r, 0] & a.nu_logged[r, 1] & a.nu_logged[r - 1, 0] & a.nu_logged[r - 1, 1]
                   & ~view.track_mismatch[r] & ~view.track_mismatch[r - 1])
    v_log = 0.5 * (_ned(nu[r, :2], psi[r]) + _ned(nu[r - 1, :2], psi[r - 1]))
    err = np.hypot(*(pos[r] - pos[r - 1] - v_log * (t[r] - t[r - 1])[:, None]).T)
    cleared = both_logged & np.all(np.isfinite(v_log), axis=1) & (err < settings.jump_m * (1.0 - THRESHOLD_MARGIN))
    unclear = np.zeros(span.rows.size, dtype=bool)
    unclear[r - span.r0] = same & ~cleared
    return span.none_in(unclear, first, idx)


def _turns_explained(view: LogView, span: _Rows, lb: np.ndarray, idx: np.ndarray,
                     settings: WindowSettings) -> np.ndarray:
    """Every heading step ending in rows ``lb..idx`` (from ``3 lookback_s`` before the window
    to the start) explained by the logged yaw rate within ``heading_jump_deg`` (the
    detector's rule where every row of the step has it; a start with a row without it is
    not cleared)."""
    a, t, psi, g = view.arrays, view.t, view.psi, span.rows
    first_of_run = view.head_runs[0]
    r = g[1:]                          # no start looks at step r0
    # a step goes from the first row of the run before (rows before r0 concern no start cleared here)
    prev = np.maximum(first_of_run[r - 1], span.r0)
    has_rate = a.nu_logged[g, 2] & np.isfinite(view.nu[g, 2])
    rate = np.where(has_rate, view.nu[g, 2], 0.0)
    turn = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t[g]))])
    step = (a.segment_id[r] == a.segment_id[prev]) & np.isfinite(psi[r]) & np.isfinite(psi[prev]) \
        & (first_of_run[r] == r)
    err = wrap_pi(wrap_pi(psi[r] - psi[prev]) - (turn[r - span.r0] - turn[prev - span.r0]))
    unclear = np.zeros(g.size, dtype=bool)
    unclear[r - span.r0] = step & ~(np.abs(err) < settings.heading_jump_rad * (1.0 - THRESHOLD_MARGIN))
    unclear[r - span.r0] |= ~has_rate[r - span.r0] | ~has_rate[r - 1 - span.r0]
    # the detector's steps start no earlier than the row before its span: a run of repeated
    # headings reaching back across that row would start them elsewhere
    return (first_of_run[lb - 1] == lb - 1) & span.none_in(unclear, lb, idx)


def _no_wrap(view: LogView, rows: np.ndarray) -> np.ndarray:
    """The headings of each window (S, n) within one turn and one half-turn (no 0/360 or +-180 crossing)."""
    two_pi = 2.0 * np.pi
    hv = view.psi[rows]
    return (np.ptp(np.floor(hv / two_pi), axis=1) == 0) & (np.ptp(np.floor((hv + np.pi) / two_pi), axis=1) == 0)


def quiet_starts(view: LogView, idx: np.ndarray, settings: WindowSettings):
    """The starts (rows ``idx``, (S,)) no detector can flag, and their start values.

    Returns
    -------
    quiet : ndarray of bool, shape (S,)
    eta0, nu0 : ndarray, shape (S, 3)
        The plain rule's start values (NaN where not quiet).
    wind : ndarray, shape (S, 2)
        The start row's wind (zeros without wind, or where not quiet).
    """
    a, t, S = view.arrays, view.t, idx.size
    eta0, nu0, wind = np.full((S, 3), np.nan), np.full((S, 3), np.nan), np.zeros((S, 2))
    quiet = np.zeros(S, dtype=bool)
    if not S or len(t) < view.n_nom or (a.wind_columns and not a.has_wind):
        return quiet, eta0, nu0, wind
    lo = np.minimum(np.searchsorted(t, t[idx] - settings.window_s + 0.5 * view.dt_nom, side="left"), idx)
    quiet = idx - lo + 1 == view.n_nom
    if not quiet.any():
        return quiet, eta0, nu0, wind
    idx, lo = idx[quiet], lo[quiet]
    # the first step each start's position and heading checks look at (_first_step, _heading_jump_rows)
    first = np.maximum(np.searchsorted(t, t[idx] - settings.window_s - settings.lookback_s, side="left"), 1)
    lb = np.maximum(np.searchsorted(t, t[idx] - settings.window_s - 3 * settings.lookback_s, side="left"), 1)
    span = _Rows(max(int(min(lo.min(), first.min(), lb.min())) - 1, 0), int(idx.max()))
    W = lo[:, None] + np.arange(view.n_nom)
    ok = _windows_valid(view, span, lo, idx, settings) & _not_frozen(view, span, lo, settings)
    ok &= _steps_explained(view, span, first, idx, settings) & _turns_explained(view, span, lb, idx, settings)
    ok &= _no_wrap(view, W)
    # the start row's derived velocities look back only (window_nu); where they cannot, the detectors judge
    nu_w = window_nu(view, W)
    ok &= np.all(np.isfinite(nu_w[:, -1]), axis=1)
    quiet[quiet] = ok
    q, W, nu_w = idx[ok], W[ok], nu_w[ok]
    # the means as the detectors' path takes them: over a contiguous row of samples each
    eta0[quiet] = np.column_stack([view.pos[q], np.mean(np.ascontiguousarray(view.psi[W]), axis=1)])
    nu0[quiet] = np.column_stack([np.mean(np.ascontiguousarray(nu_w[..., j]), axis=1) for j in range(3)])
    if a.has_wind:
        wind[quiet] = a.wind[q]
    return quiet, eta0, nu0, wind
