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
turns through north is handled. Everything here uses rows up to the start only (causal).
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from hybridship.config import Float, config_dataclass

__all__ = ["HELD_WIND", "WindForecast", "fit_wind_forecast"]

#: Candidate mean windows [s] and gust time constants [s] of :func:`fit_wind_forecast`
#: (``None`` is the held wind, always a candidate).
MEAN_WINDOWS_S = (30.0, 60.0, 120.0, 300.0, 600.0)
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
        value over the whole horizon (the paper's scheme), 0 uses the mean at once.
    """

    mean_window_s: Annotated[Float, Field(gt=0)] = 120.0
    time_constant_s: Annotated[Float, Field(ge=0)] | None = None

    @property
    def held(self) -> bool:
        """True when the wind is held at its start value."""
        return self.time_constant_s is None

    def steps(self, wind: np.ndarray, time_s: np.ndarray, rows: np.ndarray, start_wind: np.ndarray,
              n_steps: int, dt_s: float) -> np.ndarray:
        """The wind ``[speed_m_s, dir_rad]`` at the ``n_steps`` steps of forecasts started at ``rows``.

        Parameters
        ----------
        wind : ndarray, shape (N, 2)
            The log's true wind, speed [m/s] and direction [rad] (NaN where missing).
        time_s : ndarray, shape (N,)
            The log's sample times [s].
        rows : ndarray of int, shape (S,)
            Start rows.
        start_wind : ndarray, shape (S, 2)
            The wind at each start as the forecast takes it (the start window's value).
        n_steps : int
        dt_s : float
            Forecast step [s].

        Returns
        -------
        ndarray, shape (S, 1, 2) when held, else (S, n_steps, 2)
            Step ``j`` applies over ``[j dt, (j + 1) dt)`` after the start.
        """
        start_wind = np.asarray(start_wind, dtype=float)
        if self.held:
            return np.ascontiguousarray(start_wind[:, None])
        mean = _trailing_mean_vector(wind, time_s, np.asarray(rows, dtype=int), self.mean_window_s)
        w0 = _to_vector(start_wind)
        mean = np.where(np.isfinite(mean), mean, w0)           # no valid wind in the window: hold
        decay = _decay(np.arange(n_steps) * dt_s, self.time_constant_s)
        return np.ascontiguousarray(_from_vector(mean[:, None] + (w0 - mean)[:, None] * decay[None, :, None]))


#: The paper's scheme: the wind held at its start value.
HELD_WIND = WindForecast()


def _decay(lead_s: np.ndarray, time_constant_s) -> np.ndarray:
    if time_constant_s is None:
        return np.ones_like(lead_s, dtype=float)
    if time_constant_s == 0:
        return (lead_s <= 0).astype(float)
    return np.exp(-lead_s / time_constant_s)


def _to_vector(wind: np.ndarray) -> np.ndarray:
    """``[speed, dir]`` (..., 2) -> the wind vector (..., 2) [m/s] (the direction's own frame)."""
    return np.stack([wind[..., 0] * np.cos(wind[..., 1]), wind[..., 0] * np.sin(wind[..., 1])], axis=-1)


def _from_vector(vec: np.ndarray) -> np.ndarray:
    return np.stack([np.hypot(vec[..., 0], vec[..., 1]), np.arctan2(vec[..., 1], vec[..., 0])], axis=-1)


def _trailing_mean_vector(wind: np.ndarray, time_s: np.ndarray, rows: np.ndarray, window_s: float) -> np.ndarray:
    """Mean wind vector over the samples in ``(t_row - window_s, t_row]`` of each row, NaNs
    skipped; NaN where the window holds no valid sample. (S, 2)."""
    vec = _to_vector(np.asarray(wind, dtype=float))
    ok = np.isfinite(vec).all(axis=1)
    cs = np.concatenate([np.zeros((1, 2)), np.cumsum(np.where(ok[:, None], vec, 0.0), axis=0)])
    cn = np.concatenate([[0], np.cumsum(ok)])
    first = np.searchsorted(time_s, time_s[rows] - window_s, side="right")
    count = cn[rows + 1] - cn[first]
    with np.errstate(invalid="ignore", divide="ignore"):
        return (cs[rows + 1] - cs[first]) / count[:, None]


def fit_wind_forecast(logs, horizon_s: float, *, ends=None, start_every_s: float = 10.0,
                      mean_windows_s=MEAN_WINDOWS_S, time_constants_s=TIME_CONSTANTS_S):
    """Choose the wind forecast that best predicts the logged wind over ``horizon_s``.

    From starts every ``start_every_s`` in each log (with the horizon inside the log and a
    valid wind at the start; the mean uses the history there is, as a forecast does), every candidate
    ``(mean_window_s, time_constant_s)`` forecasts the wind vector from the start sample;
    the score is the mean distance [m/s] between forecast and logged vectors over the
    steps of the horizon. The held wind is always a candidate and wins ties.

    Parameters
    ----------
    logs : sequence of LogArrays
        (only ``time_s`` and ``wind`` are read).
    horizon_s : float
        Forecast horizon [s].
    ends : sequence of int, optional
        Per log, the number of leading rows that may be used (for example up to the part
        held back for calibration); default all.

    Returns
    -------
    forecast : WindForecast
    scores : dict
        ``{(mean_window_s, time_constant_s): mean error [m/s]}`` and ``"n_starts"``.
    """
    sums: dict = {}
    n_starts = 0
    windows = tuple(float(w) for w in mean_windows_s)
    taus = tuple(None if t is None else float(t) for t in time_constants_s)
    if None not in taus:
        taus += (None,)
    ends = [None] * len(logs) if ends is None else list(ends)
    for a, end in zip(logs, ends):
        t = np.asarray(a.time_s, dtype=float)[:end]
        wind = np.asarray(a.wind, dtype=float)[:end]
        if t.size < 3:
            continue
        dt = float(np.median(np.diff(t)))
        H = int(round(horizon_s / dt))
        rows = np.arange(1, t.size - H, max(1, int(round(start_every_s / dt))))
        vec = _to_vector(wind)
        if rows.size == 0:
            continue
        fut = vec[rows[:, None] + np.arange(1, H + 1)[None, :]]             # (S, H, 2)
        ok = np.isfinite(vec[rows]).all(axis=1) & np.isfinite(fut).all(axis=(1, 2))
        rows, fut = rows[ok], fut[ok]
        if rows.size == 0:
            continue
        n_starts += rows.size
        w0 = vec[rows]
        lead = np.arange(1, H + 1) * dt
        for w in windows:
            mean = _trailing_mean_vector(wind, t, rows, w)
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
    out = HELD_WIND if scores[best] >= held else WindForecast(mean_window_s=best[0], time_constant_s=best[1])
    return out, {**scores, "n_starts": n_starts}
