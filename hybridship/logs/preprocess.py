"""Preprocessing of logged time series: segments at gaps, filtered derivatives, start averages.

A log is sampled at a nominal rate (1 Hz for the project's logs) but may contain gaps
(lost samples, a paused logger). Nothing here differentiates or filters across a gap:
:func:`split_segments` cuts the time axis into gap-free segments and :func:`segmentwise`
applies a function to each segment separately.

All functions are pure: they never modify their inputs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy import signal

from hybridship.config import check_number, check_whole_number, real_array

__all__ = [
    "split_segments",
    "segment_ids",
    "segmentwise",
    "filtered_derivative",
    "derivative_by_segment",
    "moving_average_start",
]


def _nominal_dt_s(time_s: np.ndarray, nominal_dt_s: float | None) -> float:
    if nominal_dt_s is not None:
        dt = check_number("split_segments: nominal_dt_s", nominal_dt_s, lo=0.0, lo_open=True)
    else:
        dt = float(np.median(np.diff(time_s)))
    if not np.isfinite(dt) or dt <= 0.0:
        raise ValueError(f"nominal sample period must be finite and > 0, got {dt!r} s")
    return dt


def split_segments(
    time_s, *, nominal_dt_s: float | None = None, gap_factor: float = 1.5
) -> list[slice]:
    """Cut a strictly increasing time axis into gap-free segments.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Sample times [s], finite and strictly increasing.
    nominal_dt_s : float, optional
        Nominal sample period [s]. Default: the median spacing of ``time_s``, which is
        robust to a few gaps (the log format says readers must not assume 1 Hz).
    gap_factor : float, default 1.5
        A step longer than ``gap_factor * nominal_dt_s`` is a gap (log format spec); > 1.

    Returns
    -------
    list of slice
        Consecutive slices ``slice(start, stop)`` with step ``None`` that together cover
        ``0..N``; empty list for ``N == 0``.

    Raises
    ------
    ValueError
        If ``time_s`` is not one-dimensional, not finite or not strictly increasing, or
        ``gap_factor`` is not a finite number > 1 (below 1 every step would be a gap), or
        ``nominal_dt_s`` not a finite number > 0.
    TypeError
        ``gap_factor`` or ``nominal_dt_s`` text or a bool, or ``time_s`` text or complex, naming it.
    """
    gap_factor = check_number("split_segments: gap_factor", gap_factor, lo=1.0, lo_open=True)
    t = real_array("split_segments: time_s", time_s)
    if t.ndim != 1:
        raise ValueError(f"time_s must be one-dimensional, got shape {t.shape}")
    n = t.size
    if n == 0:
        return []
    if not np.all(np.isfinite(t)):      # a single sample too
        raise ValueError("time_s must be finite")
    if n == 1:
        return [slice(0, 1)]
    dt = np.diff(t)
    if np.any(dt <= 0.0):
        i = int(np.argmax(dt <= 0.0)) + 1
        raise ValueError(f"time_s must be strictly increasing (row {i}: {t[i]} after {t[i - 1]})")
    period_s = _nominal_dt_s(t, nominal_dt_s)
    # A step index k separates sample k from k + 1.
    cuts = np.flatnonzero(dt > gap_factor * period_s) + 1
    bounds = np.concatenate(([0], cuts, [n]))
    return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def segment_ids(segments: Sequence[slice], n: int) -> np.ndarray:
    """Integer segment label per sample (``-1`` where no segment covers a sample).

    Parameters
    ----------
    segments : sequence of slice
        As returned by :func:`split_segments`.
    n : int
        Number of samples.

    Returns
    -------
    ndarray of int, shape (n,)
    """
    ids = np.full(n, -1, dtype=int)
    for k, seg in enumerate(segments):
        ids[seg] = k
    return ids


def segmentwise(
    fn: Callable[..., np.ndarray],
    arrays,
    segments: Sequence[slice],
) -> np.ndarray:
    """Apply ``fn`` to each segment separately and stitch the results together.

    Parameters
    ----------
    fn : callable
        Called as ``fn(*[a[seg] for a in arrays])`` for every segment; must return an
        array whose first axis has the segment's length.
    arrays : ndarray or sequence of array_like
        A single array, or a list/tuple of arrays passed to ``fn`` as positional
        arguments. All are sliced along axis 0, which must be the time axis.
    segments : sequence of slice
        Gap-free segments, e.g. from :func:`split_segments`.

    Returns
    -------
    ndarray of float, shape (N, ...)
        ``fn``'s results placed at their segments' rows; rows not covered by any segment
        are NaN.
    """
    if isinstance(arrays, np.ndarray):
        arrays = (arrays,)
    arrays = [np.asarray(a) for a in arrays]
    if not arrays:
        raise ValueError("segmentwise needs at least one array")
    n = arrays[0].shape[0]
    if any(a.shape[0] != n for a in arrays):
        raise ValueError(f"all arrays must share the time axis length {n}: {[a.shape for a in arrays]}")
    out = None
    for seg in segments:
        res = np.asarray(fn(*[a[seg] for a in arrays]), dtype=float)
        seg_len = len(range(*seg.indices(n)))
        if res.shape[:1] != (seg_len,):
            raise ValueError(f"fn returned shape {res.shape} for a segment of {seg_len} samples")
        if out is None:
            out = np.full((n,) + res.shape[1:], np.nan)
        out[seg] = res
    if out is None:  # no segments: nothing to evaluate, shape of fn's output unknown
        return np.full(arrays[0].shape, np.nan)
    return out


def _gradient(x: np.ndarray, dt_s: float, axis: int) -> np.ndarray:
    """``np.gradient`` that returns NaN (instead of raising) for a single sample."""
    if x.shape[axis] < 2:
        return np.full(x.shape, np.nan)
    return np.gradient(x, dt_s, axis=axis)


def filtered_derivative(
    x,
    dt_s: float,
    *,
    method: str = "savgol",
    window_s: float = 5.0,
    polyorder: int = 2,
    axis: int = 0,
    cutoff_hz: float | None = None,
    butter_order: int = 4,
) -> np.ndarray:
    """Low-noise time derivative of a uniformly sampled, gap-free series.

    Parameters
    ----------
    x : array_like
        Samples of one gap-free segment (use :func:`segmentwise` or
        :func:`derivative_by_segment` for a log with gaps), finite.
    dt_s : float
        Sample period [s].
    method : {"savgol", "butter"}
        ``"savgol"``: Savitzky-Golay derivative (:func:`scipy.signal.savgol_filter` with
        ``deriv=1``; the edges use its default ``mode="interp"`` polynomial fit).
        ``"butter"``: zero-phase Butterworth low-pass (:func:`scipy.signal.sosfiltfilt`,
        the numerically stable second-order-sections form of ``butter`` + ``filtfilt``)
        followed by :func:`numpy.gradient`.
    window_s : float, default 5.0
        Savitzky-Golay window length [s]; converted to ``round(window_s / dt_s)``
        samples, raised to the next odd number and to at least ``polyorder + 1``. For
        ``"butter"`` it sets the default cut-off ``1 / window_s`` [Hz]. Finite and > 0 where used.
    polyorder : int, default 2
        Savitzky-Golay polynomial order, >= 1 (order 0 has derivative 0).
    axis : int, default 0
        Time axis of ``x``.
    cutoff_hz : float, optional
        Butterworth cut-off frequency [Hz] (default ``1 / window_s``); must be below the
        Nyquist frequency ``0.5 / dt_s``.
    butter_order : int, default 4
        Butterworth filter order, >= 1.

    Returns
    -------
    ndarray of float, same shape as ``x``
        ``dx/dt`` in units of ``x`` per second.

    Raises
    ------
    ValueError
        ``dt_s``, ``window_s``, ``cutoff_hz``, the order of the chosen method or ``axis`` out
        of range (a single number has no time axis), or an unknown ``method``, naming the argument.
    TypeError
        ``dt_s``, ``window_s`` or ``cutoff_hz`` text or a bool, or ``x`` text or complex, naming it.

    Notes
    -----
    A segment shorter than the filter needs (the Savitzky-Golay window, or the
    Butterworth ``filtfilt`` padding) falls back to plain :func:`numpy.gradient`
    (second-order central differences inside, first-order at the ends), so short
    segments still get a (noisier) derivative instead of being dropped. A single-sample
    segment gives NaN: it carries no rate information.
    """
    x = real_array("filtered_derivative: x", x)      # text failed in float()'s words, complex lost its imaginary part
    dt_s = check_number("filtered_derivative: dt_s", dt_s, lo=0.0, lo_open=True)
    axis = check_whole_number("filtered_derivative: axis", axis, lo=-x.ndim)
    if axis >= x.ndim:      # numpy's "tuple index out of range" named neither axis nor x
        raise ValueError(f"filtered_derivative: axis: expected {-x.ndim}..{x.ndim - 1} for x of shape {x.shape}, "
                         f"got {axis}" if x.ndim else "filtered_derivative: axis: x is a single number, without "
                         "a time axis; expected samples")
    n = x.shape[axis]
    if method == "savgol" or (method == "butter" and cutoff_hz is None):
        window_s = check_number("filtered_derivative: window_s", window_s, lo=0.0, lo_open=True)
    if method == "savgol":
        polyorder = check_whole_number("filtered_derivative: polyorder", polyorder, lo=1)
        window = max(int(round(window_s / dt_s)), polyorder + 1)
        window += 1 - window % 2  # savgol needs an odd window
        if n < window:
            return _gradient(x, dt_s, axis)
        return signal.savgol_filter(x, window, polyorder, deriv=1, delta=dt_s, axis=axis)
    if method == "butter":
        butter_order = check_whole_number("filtered_derivative: butter_order", butter_order, lo=1)
        fc_hz = 1.0 / window_s if cutoff_hz is None else check_number("filtered_derivative: cutoff_hz", cutoff_hz)
        fs_hz = 1.0 / dt_s
        if not 0.0 < fc_hz < 0.5 * fs_hz:
            raise ValueError(
                f"cutoff_hz must lie in (0, {0.5 * fs_hz:g}) Hz (Nyquist for dt_s={dt_s:g} s), got {fc_hz:g}"
            )
        sos = signal.butter(butter_order, fc_hz, fs=fs_hz, output="sos")
        padlen = 3 * (2 * len(sos) + 1)  # scipy's default padding for sosfiltfilt
        if n <= padlen:
            return _gradient(x, dt_s, axis)
        smooth = signal.sosfiltfilt(sos, x, axis=axis, padlen=padlen)
        return np.gradient(smooth, dt_s, axis=axis)
    raise ValueError(f"method must be 'savgol' or 'butter', got {method!r}")


def derivative_by_segment(
    x,
    time_s,
    *,
    segments: Sequence[slice] | None = None,
    **kwargs,
) -> np.ndarray:
    """:func:`filtered_derivative` of a whole log, segment by segment (axis 0 is time).

    Parameters
    ----------
    x : array_like, shape (N, ...)
        Samples; axis 0 is time.
    time_s : array_like, shape (N,)
        Sample times [s].
    segments : sequence of slice, optional
        Gap-free segments; default ``split_segments(time_s)``.
    **kwargs
        Passed to :func:`filtered_derivative` (``method``, ``window_s``, ...; not
        ``axis``). Each segment uses its own median sample period as ``dt_s``.

    Returns
    -------
    ndarray of float, shape (N, ...)
        The derivative; nothing is differentiated across a gap.
    """
    t = real_array("derivative_by_segment: time_s", time_s)
    x = real_array("derivative_by_segment: x", x)
    if segments is None:
        segments = split_segments(t)

    def one(xs, ts):
        dt = float(np.median(np.diff(ts))) if ts.size > 1 else 1.0
        return filtered_derivative(xs, dt, axis=0, **kwargs)

    return segmentwise(one, [x, t], segments)


def moving_average_start(x, idx: int, window_samples: int = 3, *, segment_id=None) -> np.ndarray:
    """Mean of the ``window_samples`` samples ending at (and including) row ``idx``.

    This is the sliding-window average applied to the heading and velocities at the start
    of each forecast (Skulstad et al.: "a sliding window average of 3 seconds"; 3 samples
    at 1 Hz) to keep measurement noise out of the initial state.

    Parameters
    ----------
    x : array_like, shape (N, ...)
        Samples; axis 0 is time. Pass the heading UNWRAPPED (e.g. ``LogArrays.eta[:, 2]``):
        averaging wrapped angles across the +-pi seam gives nonsense.
    idx : int
        Start row (negative values count from the end, as in Python indexing).
    window_samples : int, default 3
        Window length in samples, >= 1.
    segment_id : array_like of int, shape (N,), optional
        Segment label per row; when given, the window is cut at the start of ``idx``'s
        segment so it never reaches back across a gap.

    Returns
    -------
    ndarray of float, shape ``x.shape[1:]``
        The average. Near the start of the log (or of the segment) the window is shorter:
        only the available samples are averaged.

    Raises
    ------
    ValueError
        ``idx`` or ``window_samples`` not a whole number (``window_samples`` < 1), ``x`` a
        single number, or ``segment_id`` not one label per row, naming the argument.
    TypeError
        ``x`` text or complex, naming it.
    IndexError
        ``idx`` outside the rows of ``x``.
    """
    a = real_array("moving_average_start: x", x)
    if a.ndim == 0:     # numpy's "tuple index out of range"
        raise ValueError("moving_average_start: x: a single number, without a time axis; expected samples")
    n = a.shape[0]
    window_samples = check_whole_number("moving_average_start: window_samples", window_samples, lo=1)
    if isinstance(idx, bool) or not isinstance(idx, (int, np.integer)):
        raise ValueError(f"moving_average_start: idx: expected a whole number (a row), got {idx!r}")
    if not -n <= idx < n:
        raise IndexError(f"idx {idx} out of range for {n} samples")
    idx = idx % n
    lo = max(0, idx - window_samples + 1)
    if segment_id is not None:
        sid = np.asarray(segment_id)
        if sid.shape != (n,):
            raise ValueError(f"moving_average_start: segment_id: expected one label per row ({n},), "
                             f"got shape {sid.shape}")
        # First row of idx's segment at or after lo: rows before it belong to earlier segments.
        same = sid[lo : idx + 1] == sid[idx]
        lo += int(np.argmax(same))
    return a[lo : idx + 1].mean(axis=0)
