"""Forecasts started after a DP failure: the starts the drift benchmark scores and the
spread after a failure is calibrated on.

Forecasts start at successive samples after the shutdown (one "interval" per start time,
one second apart at 1 Hz), as in Skulstad et al. (2022); :mod:`hybridship.evaluation.metrics`
turns them into the paper's error tables.
"""

from __future__ import annotations

import numpy as np

from ..config import check_number, check_whole_number
from ..logs.ingest import ingest
from ..logs.io import LogArrays
from ..messages import seconds_text
from .forecast_setup import horizon_steps

__all__ = ["HORIZONS_S", "drift_end", "drift_forecasts", "has_drift", "shutdown_index"]

#: The paper's horizons [s].
HORIZONS_S = (15, 30, 45, 60)


def shutdown_index(arrays) -> int:
    """Row of the first ``dp_active == 0`` sample after station keeping (raises if none, and
    for a log that starts with ``dp_active == 0``, which :func:`has_drift` and
    :func:`~hybridship.residual.drift_hull.drift_start_rows` read as having no failure)."""
    off = np.flatnonzero(arrays.dp_active == 0)
    if off.size == 0:
        raise ValueError("log: no DP shutdown (dp_active never 0); cannot evaluate drift forecasts")
    if off[0] == 0:
        # its first rows are no drift after a failure (a transit, a manoeuvre): no station keeping before them
        raise ValueError("log: starts with dp_active 0 (no station keeping before its first dp_active 0 sample), "
                         "so it has no DP failure to start drift forecasts from; give a log that starts in "
                         "station keeping")
    return int(off[0])


def _gap_free_end(arrays, i0: int) -> int:
    """First row after ``i0`` that is not in ``i0``'s gap-free segment (``len`` without a gap):
    a measurement ``k`` rows after a start is ``k`` steps later only before it."""
    seg = np.asarray(arrays.segment_id)
    later = np.flatnonzero(seg[i0:] != seg[i0])
    return i0 + int(later[0]) if later.size else len(seg)


def drift_end(arrays, i0: int) -> int:
    """First row after the failure at ``i0`` that is not in its drift: the first row with
    ``dp_active`` on again or outside ``i0``'s gap-free segment (``len`` without either), as
    :func:`~hybridship.residual.drift_hull.drift_start_rows` bounds a drift. A forecast held at
    the failure's rpm 0 is not a drift forecast once DP thrust is back in the measured track."""
    end = _gap_free_end(arrays, i0)
    back = np.flatnonzero(np.asarray(arrays.dp_active[i0:end]) != 0)
    return i0 + int(back[0]) if back.size else end


def has_drift(arrays, n_intervals: int, horizon_s: float) -> bool:
    """Whether a log has a DP failure (station keeping, then ``dp_active`` 0) followed by enough
    drift for :func:`drift_forecasts` (``n_intervals`` starts, each with ``horizon_s`` of
    measurements after it in the failure's gap-free segment, before DP comes back on: see
    :func:`drift_end`). A log without station keeping before its first ``dp_active`` 0 (a
    manoeuvring log) has none. ``n_intervals`` is a whole number >= 1 and ``horizon_s`` a
    number > 0 [s], a ValueError or TypeError naming them otherwise (as :func:`drift_forecasts`),
    and a whole number of the log's steps (:class:`~hybridship.predictors.forecast_setup.HorizonError`
    otherwise, as a forecast refuses it)."""
    # a NaN horizon failed in int()'s words, text in an operator's, and a negative one found drift in any log
    check_whole_number("n_intervals", n_intervals, 1)
    horizon_s = check_number("horizon_s", horizon_s, lo=0.0, lo_open=True)
    off = np.flatnonzero(arrays.dp_active == 0)
    if off.size == 0 or off[0] == 0 or len(arrays.time_s) < 2:
        return False
    # the steps a forecast would take: a horizon between two of them was rounded here, unlike there
    H = horizon_steps(horizon_s, float(np.median(np.diff(arrays.time_s))))
    return drift_end(arrays, int(off[0])) - int(off[0]) - H >= n_intervals


def _check_drift_request(n_intervals, horizons_s, first, every) -> None:
    """The starts and horizons of :func:`drift_forecasts`, checked before any forecast: a
    negative horizon or start indexed the forecast and the truth from their ends (scored
    silently), ``every = 0`` divided by zero and a fractional count failed in numpy."""
    if n_intervals is not None:
        check_whole_number("n_intervals", n_intervals, 1)
    check_whole_number("first", first, 0)
    check_whole_number("every", every, 1)
    if isinstance(horizons_s, (str, bytes)) or np.ndim(horizons_s) != 1 or np.size(horizons_s) == 0:
        raise ValueError(f"horizons_s: expected a list of lead times [s], got {horizons_s!r}")
    for h in horizons_s:
        check_number("horizons_s", h, lo=0.0, lo_open=True)


def drift_forecasts(predictor, arrays, *, n_intervals: int | None = 20, horizons_s=HORIZONS_S, first: int = 0,
                    every: int = 1, **forecast_kw):
    """Forecasts from successive start times after the shutdown of one log, at the horizons.

    ``arrays`` is LogArrays, or a path or DataFrame in the log format (read through
    :func:`~hybridship.logs.ingest.ingest` for the predictor's vessel, as a forecast reads it).
    The starts are the samples ``first, first + every, ...`` after the shutdown's row,
    ``n_intervals`` of them, or (None) as many as leave the longest horizon in the log. The
    truth is taken by rows, so every start and its horizon must lie in the shutdown's gap-free
    segment (a gap of missing rows would pair a forecast with a later measurement) and before
    DP comes back on (:func:`drift_end`): starts that would reach past either are refused.

    Returns
    -------
    pred, truth : ndarray, shape (n_intervals, len(horizons_s), 3)
        Forecast and logged ``[north_m, east_m, psi_rad]``.
    std : ndarray of the same shape, or None
        The forecast's spread, its ``eta_std`` (None for point forecasters): for the hybrid
        the calibrated spread (the ensemble's standard deviation with ``calibrated=False``
        among ``forecast_kw``, or where it was fitted without calibration), for the
        data-only baseline the ensemble's standard deviation.

    Raises
    ------
    ValueError, TypeError
        Naming ``n_intervals`` (a whole number >= 1, or None), ``first`` (>= 0), ``every``
        (>= 1) or ``horizons_s`` (at least one finite lead time > 0 [s], each a whole number
        of the log's steps, within a quarter step or 0.5 % as a forecast's horizon) when it is
        not that.
    """
    _check_drift_request(n_intervals, horizons_s, first, every)
    if not isinstance(arrays, LogArrays):          # a path or DataFrame: read as a forecast reads it
        model = getattr(predictor, "model", None)
        if model is None:
            raise TypeError("arrays: expected LogArrays (a path or DataFrame needs a predictor with a vessel model)")
        arrays = ingest(arrays, model.vessel, purpose="forecast")
    i0 = shutdown_index(arrays)
    dt = float(np.median(np.diff(arrays.time_s)))
    # as a forecast refuses such a horizon: it was scored at the nearest step (lead 0 below half a step)
    steps = np.array([horizon_steps(h, dt, "horizons_s") for h in horizons_s])
    H = int(steps.max())
    end = drift_end(arrays, i0)
    available = max(0, -(-(end - H - i0 - first) // every))     # starts that leave H steps before a gap
    n = available if n_intervals is None else n_intervals
    if available < n or n == 0:
        gap = "" if end == len(arrays.time_s) else (
            f" before the gap at time_s {seconds_text(arrays.time_s[end - 1])} s" if end == _gap_free_end(arrays, i0)
            else f" before DP comes back on at time_s {seconds_text(arrays.time_s[end])} s")
        raise ValueError(f"log: only {available} start times after the shutdown leave {H * dt:g} s of "
                         f"measurements{gap}; {max(n, 1)} are needed")
    starts = i0 + first + every * np.arange(n)
    fc = predictor.forecast(arrays, arrays.time_s[starts], horizon_s=H * dt, **forecast_kw)
    truth = arrays.eta[starts[:, None] + steps[None, :]]        # (S, nh, 3)
    std = None if fc.eta_std is None else fc.eta_std[:, steps]
    return fc.eta[:, steps], truth, std
