"""The wind over a forecast: held at its start value, or a gust that decays towards the recent mean.

A forecast cannot know the wind's future, but it need not assume that the gust blowing at
its start lasts the whole horizon. :class:`WindForecast` gives the true-wind vector at
lead time ``tau`` after a start as

.. math::  \\mathbf{w}(\\tau) = \\bar{\\mathbf{w}} + (\\mathbf{w}_0 - \\bar{\\mathbf{w}})\\, e^{-\\tau / T_g},

where ``w_0`` is the wind at the start (as the start window gives it), ``w_bar`` the
causal mean of the logged wind vector over the ``mean_window_s`` before the start, and
``T_g`` (``time_constant_s``) the time over which a gust is forgotten: the conditional
mean of a wind whose fluctuation about a slowly moving mean is a first-order
(Ornstein-Uhlenbeck) process, the simplest model with a gust spectrum that falls off like
the measured ones at high frequency. ``time_constant_s = None`` is the paper's held wind.

:func:`fit_wind_forecast` chooses ``mean_window_s`` and ``time_constant_s`` on training
logs by the error of the wind forecast itself (the mean distance between forecast and
logged wind vectors over the forecast horizon): a property of the site's wind, found
without looking at any ship forecast. Directions are averaged as vectors, so a wind that
turns through north is handled. Each forecast uses logged wind samples up to its start
only (causal; samples the log filled in over a sensor gap do not count), and a start
whose window has no logged wind keeps its start value.

What the wind forecast gets wrong is measured by :func:`wind_error_paths`: the logged minus
forecast wind vector along the horizon from starts in training logs. Added to a forecast's
wind, each such path is one plausible future of the wind; the hybrid's spread can include
how much its forecast moves over a few of them
(:class:`~hybridship.predictors.hybrid.HybridPredictor` ``wind_samples``).
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from hybridship.config import Float, check_number, check_whole_number, config_dataclass
from hybridship.forecast_inputs.horizon import horizon_steps
from hybridship.frames import speed_dir_to_vector, vector_to_speed_dir

__all__ = ["HELD_WIND", "WindForecast", "fit_wind_forecast", "trailing_mean_vector", "wind_error_paths",
           "wind_starts"]

#: Candidate mean windows [s] and gust time constants [s] of :func:`fit_wind_forecast`
#: (``None`` is the held wind, always a candidate).
MEAN_WINDOWS_S = (30.0, 60.0, 120.0, 300.0, 600.0)
#: Longest mean window [s]: a forecast reads at least this much log before its earliest
#: start (:data:`hybridship.predictors.forecast_setup.FORECAST_HISTORY_S`).
MAX_MEAN_WINDOW_S = 1800.0
#: Relative improvement over the held wind that :func:`fit_wind_forecast` asks for (below
#: it, differences are noise and the paper's held wind is kept).
MIN_IMPROVEMENT = 0.01
TIME_CONSTANTS_S = (0.0, 2.0, 5.0, 10.0, 20.0, 30.0, 60.0, 120.0, None)


@config_dataclass(frozen=True, prefix="wind_forecast")
class WindForecast:
    """A forecast of the true wind over a horizon (validated; recorded in model files).

    Attributes
    ----------
    mean_window_s : float
        Length of the causal mean of the logged wind vector before a start [s] (the
        level a gust decays to).
    time_constant_s : float or None
        Decay time of the start's deviation from that mean [s]; None holds the start
        value over the whole horizon (the paper's scheme); 0 keeps the start value for
        the first step and uses the mean from the second on.
    """

    mean_window_s: Annotated[Float, Field(gt=0, le=MAX_MEAN_WINDOW_S)] = 120.0
    time_constant_s: Annotated[Float, Field(ge=0)] | None = None

    @property
    def held(self) -> bool:
        """True when the wind is held at its start value."""
        return self.time_constant_s is None

    def steps(self, wind: np.ndarray, time_s: np.ndarray, rows: np.ndarray, start_wind: np.ndarray,
              n_steps: int, dt_s: float, *, logged=None, hold=None) -> np.ndarray:
        """The wind ``[speed_m_s, dir_rad]`` at the ``n_steps`` steps of forecasts started at ``rows``.

        Parameters
        ----------
        wind : ndarray, shape (N, 2)
            The log's true wind, speed [m/s] and direction it comes from [rad].
        time_s : ndarray, shape (N,)
            The log's sample times [s], increasing.
        rows : ndarray of int, shape (S,)
            Start rows.
        start_wind : ndarray, shape (S, 2)
            The wind at each start as the forecast takes it (the start window's value).
        n_steps : int
            Steps of the forecast.
        dt_s : float
            Forecast step [s].
        logged : ndarray of bool, shape (N,), optional
            Rows whose wind was logged (``LogArrays.wind_logged``); rows the log filled in
            over a gap do not enter the mean. Default: every finite row.
        hold : ndarray of bool, shape (S,), optional
            Starts that keep their start value (for example a start flagged
            ``wind_dropped``, which forecasts without wind).

        Returns
        -------
        ndarray, shape (S, 1, 2) when held, else (S, n_steps, 2)
            Step ``j`` applies over ``[j dt, (j + 1) dt)`` after the start.
        """
        start_wind = np.asarray(start_wind, dtype=float)
        if self.held:
            return np.ascontiguousarray(start_wind[:, None])
        mean = trailing_mean_vector(wind, time_s, np.asarray(rows, dtype=int), self.mean_window_s, logged)
        w0 = speed_dir_to_vector(start_wind)
        keep = ~np.isfinite(mean).all(axis=1)                  # no logged wind in the window: hold
        if hold is not None:
            keep |= np.asarray(hold, dtype=bool)
        mean[keep] = w0[keep]
        decay = _decay(np.arange(n_steps) * dt_s, self.time_constant_s)
        return np.ascontiguousarray(vector_to_speed_dir(mean[:, None] + (w0 - mean)[:, None] * decay[None, :, None]))


#: The paper's scheme: the wind held at its start value.
HELD_WIND = WindForecast()


def _decay(lead_s: np.ndarray, time_constant_s) -> np.ndarray:
    """Share of the start's gust left at each lead time [s]: 1 held, ``exp(-lead / T_g)``."""
    if time_constant_s is None:
        return np.ones_like(lead_s, dtype=float)
    if time_constant_s == 0:
        return (lead_s <= 0).astype(float)
    return np.exp(-lead_s / time_constant_s)


def trailing_mean_vector(wind: np.ndarray, time_s: np.ndarray, rows: np.ndarray, window_s: float,
                         logged=None) -> np.ndarray:
    """Mean wind vector [m/s] over the logged samples in ``(t_row - window_s, t_row]`` of each
    row; NaN where the window holds none. (S, 2)."""
    vec = speed_dir_to_vector(np.asarray(wind, dtype=float))
    ok = np.isfinite(vec).all(axis=1)
    if logged is not None:
        ok &= np.asarray(logged, dtype=bool)
    cs = np.concatenate([np.zeros((1, 2)), np.cumsum(np.where(ok[:, None], vec, 0.0), axis=0)])
    cn = np.concatenate([[0], np.cumsum(ok)])
    first = np.searchsorted(time_s, time_s[rows] - window_s, side="right")
    count = cn[rows + 1] - cn[first]
    with np.errstate(invalid="ignore", divide="ignore"):
        return (cs[rows + 1] - cs[first]) / count[:, None]


def _usable_wind_rows(a, mask=None):
    """``(ok, segment_id)`` of log ``a``: rows whose wind is finite, logged (``wind_logged``,
    where present) and inside ``mask`` (when given), and each row's gap-free segment."""
    n = len(a.time_s)
    ok = np.isfinite(speed_dir_to_vector(np.asarray(a.wind, dtype=float))).all(axis=1)
    if getattr(a, "wind_logged", None) is not None:
        ok &= np.asarray(a.wind_logged, dtype=bool)
    if mask is not None:
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != (n,):
            raise ValueError(f"masks: expected one flag per row of the log ({n}), got shape {mask.shape}")
        ok &= mask
    seg = getattr(a, "segment_id", None)
    return ok, (np.zeros(n, dtype=int) if seg is None else np.asarray(seg))


def wind_starts(a, horizon_steps: int, every: int, mask=None) -> tuple[np.ndarray, np.ndarray]:
    """Start rows of log ``a``, one every ``every`` rows, whose start and ``horizon_steps``
    following rows all hold usable wind (logged, finite, inside ``mask``) in one gap-free
    segment; and the usable-row mask itself, shape (N,). ``horizon_steps`` and ``every`` are
    whole numbers >= 1 (a ValueError naming them)."""
    horizon_steps = check_whole_number("horizon_steps", horizon_steps, lo=1)
    every = check_whole_number("every", every, lo=1)
    ok, seg = _usable_wind_rows(a, mask)
    rows = np.arange(1, len(ok) - horizon_steps, every)
    bad = np.concatenate([[0], np.cumsum(~ok)])
    return rows[((bad[rows + horizon_steps + 1] - bad[rows]) == 0) & (seg[rows + horizon_steps] == seg[rows])], ok


def fit_wind_forecast(logs, horizon_s: float, *, masks=None, start_every_s: float = 10.0,
                      mean_windows_s=MEAN_WINDOWS_S, time_constants_s=TIME_CONSTANTS_S):
    """Choose the wind forecast that best predicts the logged wind over ``horizon_s``.

    From starts every ``start_every_s`` in each log (the start and every step of the
    horizon logged, usable and in one gap-free segment; the mean uses the logged, usable
    history there is, as a forecast does), every candidate ``(mean_window_s,
    time_constant_s)`` forecasts the wind vector from the start sample; the score is the
    mean distance [m/s] between forecast and logged vectors over the steps of the horizon.
    The held wind is always a candidate; another is chosen only when it beats the held
    wind's score by more than ``MIN_IMPROVEMENT`` (relative).

    Parameters
    ----------
    logs : sequence of LogArrays
        Only ``time_s``, ``wind`` and, where present, ``wind_logged`` and ``segment_id``
        are read.
    horizon_s : float
        Forecast horizon [s], a whole number of each log's steps (within a forecast's
        tolerance, :func:`~hybridship.forecast_inputs.horizon.horizon_steps`).
    masks : sequence of (ndarray of bool or None), optional
        Per log, the rows that may be used (for example station keeping before the part
        held back for calibration); default every row.
    start_every_s : float
        Spacing of the start times [s].
    mean_windows_s : sequence of float
        Candidate mean windows [s] (each at most ``MAX_MEAN_WINDOW_S``).
    time_constants_s : sequence of (float or None)
        Candidate gust decay times [s]; None (held) is added when missing.

    Returns
    -------
    forecast : WindForecast
    scores : dict
        ``{(mean_window_s, time_constant_s): mean error [m/s]}`` and ``"n_starts"``.

    Raises
    ------
    TypeError, ValueError
        An argument that is not what is described above, naming it (a horizon or spacing
        that is not a positive number, a horizon that is not a whole number of a log's steps
        (:class:`~hybridship.forecast_inputs.horizon.HorizonError`, naming the log: shorter
        than one step, or off a whole number by more than a quarter step and 0.5 %, as a
        forecast refuses it), a candidate out of range, one mask too few).
    """
    horizon_s = check_number("horizon_s", horizon_s, lo=0, lo_open=True)
    start_every_s = check_number("start_every_s", start_every_s, lo=0, lo_open=True)
    windows = tuple(check_number(f"mean_windows_s[{i}]", w, lo=0, lo_open=True, hi=MAX_MEAN_WINDOW_S)
                    for i, w in enumerate(_candidates("mean_windows_s", mean_windows_s)))
    if not windows:
        raise ValueError("mean_windows_s: expected at least one mean window [s], got none")
    taus = tuple(check_number(f"time_constants_s[{i}]", t, lo=0, allow_none=True)
                 for i, t in enumerate(_candidates("time_constants_s", time_constants_s)))
    if None not in taus:
        taus += (None,)
    logs = list(logs)
    masks = [None] * len(logs) if masks is None else list(masks)
    if len(masks) != len(logs):
        # zip would drop the logs without a mask, unseen
        raise ValueError(f"masks: expected one per log ({len(logs)}), got {len(masks)}")
    sums: dict = {}
    n_starts = 0
    for k, (a, mask) in enumerate(zip(logs, masks)):
        t = np.asarray(a.time_s, dtype=float)
        n = t.size
        if n < 3:
            continue
        wind = np.asarray(a.wind, dtype=float)
        vec = speed_dir_to_vector(wind)
        dt = float(np.median(np.diff(t)))
        H = horizon_steps(horizon_s, dt, where=f"logs[{k}]")      # as a forecast of that horizon counts them
        rows, ok = wind_starts(a, H, max(1, int(round(start_every_s / dt))), mask)
        if rows.size == 0:
            continue
        n_starts += rows.size
        fut = vec[rows[:, None] + np.arange(1, H + 1)[None, :]]             # (S, H, 2)
        w0 = vec[rows]
        lead = np.arange(1, H + 1) * dt
        for w in windows:
            mean = trailing_mean_vector(wind, t, rows, w, ok)
            mean = np.where(np.isfinite(mean), mean, w0)
            for tau in taus:
                pred = mean[:, None] + (w0 - mean)[:, None] * _decay(lead, tau)[None, :, None]
                err = np.hypot(*(pred - fut).transpose(2, 0, 1))
                s, c = sums.get((w, tau), (0.0, 0))
                sums[(w, tau)] = (s + float(err.sum()), c + err.size)
    if not n_starts:
        return HELD_WIND, {"n_starts": 0}
    scores = {k: s / c for k, (s, c) in sums.items()}
    held = min(v for (w, tau), v in scores.items() if tau is None)
    best = min(scores, key=scores.get)
    better = scores[best] < (1.0 - MIN_IMPROVEMENT) * held
    out = WindForecast(mean_window_s=best[0], time_constant_s=best[1]) if better else HELD_WIND
    return out, {**scores, "n_starts": n_starts}


def _candidates(name: str, values) -> tuple:
    """``values`` as a tuple of candidates, or a TypeError naming ``name``: a lone number or a
    text (whose characters a loop would read as candidates, "60" as 6 and 0 s) is refused."""
    if isinstance(values, (str, bytes)) or not np.iterable(values):
        raise TypeError(f"{name}: expected a sequence of candidate times [s], got {values!r}")
    return tuple(values)


def wind_error_paths(forecast: WindForecast, logs, horizon_steps: int, *, every: int = 20,
                     masks=None) -> np.ndarray:
    """What ``forecast`` gets wrong: logged minus forecast true-wind vector [m/s] over
    ``horizon_steps`` steps, from a start every ``every`` rows of each log.

    Only futures the log really measured are used: the start and every step of the horizon
    logged (``wind_logged``), finite, inside ``masks`` (when given) and in one gap-free
    segment. Step ``j`` of a path is the error over ``[j dt, (j + 1) dt)`` after its start,
    so step 0 is zero (the forecast starts from the logged wind).

    Parameters
    ----------
    forecast : WindForecast
        The wind forecast whose errors are wanted.
    logs : sequence of LogArrays
        ``time_s``, ``wind``, ``dt_s`` and, where present, ``wind_logged`` and ``segment_id``
        are read.
    horizon_steps : int
        Steps of each path (log rows).
    every : int
        Row spacing of the starts.
    masks : sequence of (ndarray of bool or None), optional
        Per log, the rows that may be used (for example those before the part held back
        for calibration); default every row.

    Returns
    -------
    ndarray, shape (P, horizon_steps, 2)
        North and east components of the error [m/s] (P may be 0).

    Raises
    ------
    ValueError
        Naming ``masks`` when they are not one per log, ``horizon_steps`` or ``every`` when
        not a whole number >= 1.
    """
    horizon_steps = check_whole_number("horizon_steps", horizon_steps, lo=1)
    every = check_whole_number("every", every, lo=1)
    paths = [np.zeros((0, horizon_steps, 2))]
    masks = [None] * len(logs) if masks is None else list(masks)
    if len(masks) != len(logs):
        # zip would drop the logs without a mask, unseen
        raise ValueError(f"masks: expected one per log ({len(logs)}), got {len(masks)}")
    for a, mask in zip(logs, masks):
        n = len(a.time_s)
        rows = np.arange(1, n - horizon_steps - 1, every)
        wind = np.asarray(a.wind, dtype=float)
        ok, seg = _usable_wind_rows(a, mask)
        bad = np.concatenate([[0], np.cumsum(~ok)])
        rows = rows[(bad[rows + horizon_steps] == bad[rows]) & (seg[rows + horizon_steps - 1] == seg[rows])]
        if rows.size == 0:
            continue
        fc = forecast.steps(wind, a.time_s, rows, wind[rows], horizon_steps, a.dt_s,
                            logged=getattr(a, "wind_logged", None))
        logged = speed_dir_to_vector(wind[rows[:, None] + np.arange(horizon_steps)[None]])
        paths.append(np.broadcast_to(logged - speed_dir_to_vector(fc), logged.shape))
    return np.concatenate(paths)
