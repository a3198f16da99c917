"""Forecast errors after a DP failure, in the layout of Skulstad et al. (2022), Table 2.

Forecasts start at successive samples after the shutdown (one "interval" per start time,
one second apart at 1 Hz). For each start and horizon the absolute error in north [m],
east [m] and yaw [deg] against the logged (measured) track is taken; a table cell is the
mean over the first 5 and the first 20 intervals, written "5/20".
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from ..config import check_number, check_whole_number, real_array
from ..frames import wrap_pi
from ..predictors.after_failure import HORIZONS_S, drift_forecasts, shutdown_index

#: The paper's averaging windows [intervals] (its horizons, HORIZONS_S, come with the forecasts).
WINDOWS = (5, 20)
STATES = ("north_m", "east_m", "yaw_deg")

__all__ = ["HORIZONS_S", "WINDOWS", "STATES", "drift_forecasts", "shutdown_index", "drift_errors",
           "absolute_errors", "COVERAGE_STATES", "coverage", "coverage_interval", "grouped_coverage_interval",
           "error_table", "paper_table", "reduction_table", "pooled_ratio_table"]


def drift_errors(predictor, arrays, *, n_intervals: int = 20, horizons_s=HORIZONS_S, **forecast_kw) -> np.ndarray:
    """Absolute forecast errors after the shutdown of one log.

    Parameters
    ----------
    predictor : object
        Any object with a ``forecast(log, start_times_s, horizon_s)`` method.
    arrays : LogArrays, path or DataFrame
        The log (a path or DataFrame is read for the predictor's vessel).
    n_intervals : int
        Number of successive start times from the shutdown.
    horizons_s : sequence of float
        Lead times at which errors are taken [s].
    **forecast_kw
        Passed on to ``predictor.forecast`` (for example ``nets=False``).

    Returns
    -------
    ndarray, shape (n_intervals, len(horizons_s), 3)
        ``|north error| [m], |east error| [m], |yaw error| [deg]``.
    """
    pred, truth, _ = drift_forecasts(predictor, arrays, n_intervals=n_intervals, horizons_s=horizons_s,
                                     **forecast_kw)
    return absolute_errors(pred, truth)


def absolute_errors(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """``|north|, |east| [m]`` and ``|yaw| [deg]`` (heading difference wrapped to +-180 deg).

    ``pred`` and ``truth`` are ``[north_m, east_m, psi_rad]`` of one shape ``(..., 3)``; a
    ValueError naming them otherwise (a mismatch broadcast, pairing a forecast with the
    wrong measurement)."""
    pred, truth = real_array("pred", pred), real_array("truth", truth)   # an integer result truncated the degrees
    if pred.shape != truth.shape or pred.ndim < 1 or pred.shape[-1] != 3:
        raise ValueError(f"pred, truth: expected equal shapes (..., 3), got {pred.shape} and {truth.shape}")
    err = np.abs(pred - truth)
    err[..., 2] = np.degrees(np.abs(wrap_pi(pred[..., 2] - truth[..., 2])))
    return err


def _checked_forecasts(pred, truth, std, min_ndim: int = 2):
    """``pred, truth, std`` as float arrays of one shape ``(..., n_horizons, 3)`` with finite
    north and east and finite, non-negative spreads; ValueError naming the argument otherwise
    (a NaN would count as a miss, a mismatched shape broadcast silently)."""
    pred, truth, std = (real_array(name, x) for name, x in (("pred", pred), ("truth", truth), ("std", std)))
    if not pred.shape == truth.shape == std.shape or pred.ndim < min_ndim or pred.shape[-1] != 3:
        raise ValueError(f"pred, truth, std: expected equal shapes (..., n_horizons, 3), got {pred.shape}, "
                         f"{truth.shape}, {std.shape}")
    for name, a in (("pred", pred), ("truth", truth)):
        if not np.all(np.isfinite(a[..., :2])):
            raise ValueError(f"{name}: NaN or inf in north or east; leave such forecasts out before scoring")
    if not np.all(np.isfinite(std[..., :2]) & (std[..., :2] >= 0)):
        raise ValueError("std: expected finite, non-negative standard deviations")
    return pred, truth, std


#: What a coverage counts: the north and east errors pooled, or the heading's alone.
COVERAGE_STATES = ("position", "heading")


def _band_errors(pred: np.ndarray, truth: np.ndarray, std: np.ndarray, state: str):
    """``(|error|, std)``, shape ``(..., n_horizons, k)``, of the components ``state`` counts:
    north and east [m] (k = 2), or the heading [rad] wrapped to +-pi (k = 1)."""
    if state == "position":
        return np.abs(pred - truth)[..., :2], std[..., :2]
    if state != "heading":
        raise ValueError(f"state: expected one of {COVERAGE_STATES}, got {state!r}")
    for name, a in (("pred", pred), ("truth", truth)):
        if not np.all(np.isfinite(a[..., 2])):
            raise ValueError(f"{name}: NaN or inf in the heading; leave such forecasts out before scoring")
    if not np.all(np.isfinite(std[..., 2]) & (std[..., 2] >= 0)):
        raise ValueError("std: expected finite, non-negative heading standard deviations")
    return np.abs(wrap_pi(pred[..., 2:] - truth[..., 2:])), std[..., 2:]


def coverage(pred: np.ndarray, truth: np.ndarray, std: np.ndarray, sigmas=(1.0, 2.0), *,
             state: str = "position") -> np.ndarray:
    """Fraction of errors within ``k`` standard deviations.

    Parameters
    ----------
    pred, truth, std : ndarray, shape (..., n_horizons, 3)
        North [m], east [m] and heading [rad]; pooled over all leading axes.
    sigmas : sequence of float
        Band half-widths in standard deviations.
    state : {"position", "heading"}
        Count the north and east errors pooled (default), or the heading's (wrapped) alone.

    Returns
    -------
    ndarray, shape (n_horizons, len(sigmas))
        Observed coverage; a calibrated Gaussian forecast gives 0.683 and 0.954 for 1 and 2 sigma.
    """
    pred, truth, std = _checked_forecasts(pred, truth, std)
    sig = real_array("sigmas", sigmas)
    if sig.ndim != 1 or sig.size == 0 or not np.all(np.isfinite(sig) & (sig > 0)):
        # a single number read as a list of them, which the result's shape needs
        one = ", e.g. (2.0,) for one" if sig.ndim == 0 else ""
        raise ValueError(f"sigmas: expected positive finite band half-widths (a sequence{one}), got {sigmas!r}")
    err, s = _band_errors(pred, truth, std, state)
    nh = err.shape[-2]
    e = np.moveaxis(err, -2, 0).reshape(nh, -1)
    s = np.moveaxis(s, -2, 0).reshape(nh, -1)
    return np.stack([(e <= k * s).mean(axis=1) for k in sig], axis=1)


def coverage_interval(pred: np.ndarray, truth: np.ndarray, std: np.ndarray, sigma: float = 2.0, *,
                      confidence: float = 0.90, n_resamples: int = 4000, seed: int = 0,
                      state: str = "position") -> np.ndarray:
    """Coverage at ``sigma`` with a bootstrap interval that resamples whole failures.

    Forecasts started one second apart after one failure share most of their future, so
    their errors are nearly one draw: a coverage pooled over six failures rests on about
    six independent outcomes per component, not on hundreds of starts. The interval
    resamples the failures (the first axis), with all their starts and components
    (percentile bootstrap, :func:`scipy.stats.bootstrap`).

    Parameters
    ----------
    pred, truth, std : ndarray, shape (G, ..., n_horizons, 3)
        One group per failure (log) on the first axis.
    sigma : float
        Width of the band in standard deviations.
    confidence : float
        Confidence level of the interval.
    n_resamples : int
    seed : int
        Seed of the resampling (the same call gives the same interval).
    state : {"position", "heading"}
        As in :func:`coverage`.

    Returns
    -------
    ndarray, shape (n_horizons, 3)
        ``coverage, low, high`` per horizon; ``low`` and ``high`` are NaN with fewer than two
        groups.
    """
    pred, truth, std = _checked_forecasts(pred, truth, std, min_ndim=3)
    sigma = check_number("sigma", sigma, lo=0.0, lo_open=True)
    err, s = _band_errors(pred, truth, std, state)
    inside = err <= sigma * s                                            # (G, ..., nh, k)
    inside = np.moveaxis(inside, -2, 1).reshape(inside.shape[0], inside.shape[-2], -1)
    return grouped_coverage_interval(inside.sum(axis=2), np.full(inside.shape[0], inside.shape[2]),
                                     confidence=confidence, n_resamples=n_resamples, seed=seed)


def grouped_coverage_interval(hits: np.ndarray, counts: np.ndarray, *, confidence: float = 0.90,
                              n_resamples: int = 4000, seed: int = 0) -> np.ndarray:
    """Pooled coverage ``sum(hits) / sum(counts)`` and its percentile bootstrap interval over groups.

    Parameters
    ----------
    hits : ndarray, shape (G, n_horizons)
        Errors inside the band, per group (a failure, a run) and horizon.
    counts : ndarray, shape (G,)
        Errors counted per group (groups may differ in size).
    confidence, n_resamples, seed
        As in :func:`coverage_interval`.

    Returns
    -------
    ndarray, shape (n_horizons, 3)
        ``coverage, low, high``; ``low`` and ``high`` NaN with fewer than two groups.

    Notes
    -----
    With few groups the interval is narrower than its confidence claims: a resample of G
    groups takes at most ``C(2G - 1, G)`` distinct values (10 for three), all within the
    range of the groups' own coverages, so it cannot show how a fourth group might differ.
    Read an interval over fewer than about ten groups as a lower bound on the uncertainty.

    Raises
    ------
    TypeError, ValueError
        Text instead of numbers, ``hits`` not (G, n_horizons) with G >= 1 or ``counts`` not
        (G,), a count not > 0, hits outside ``0 .. count``, or a bad ``confidence``,
        ``n_resamples`` or ``seed``, naming the argument (an empty group list gave NaN).
    """
    hits, counts = real_array("hits", hits), real_array("counts", counts)
    if hits.ndim != 2 or hits.shape[0] == 0 or counts.shape != hits.shape[:1]:
        raise ValueError(f"hits, counts: expected shapes (G, n_horizons) and (G,) with G >= 1 groups, got "
                         f"{hits.shape} and {counts.shape}")
    if not (np.all(np.isfinite(counts) & (counts > 0)) and np.all((hits >= 0) & (hits <= counts[:, None]))):
        raise ValueError("hits, counts: expected counts > 0 and 0 <= hits <= count in every group")
    confidence = check_number("confidence", confidence, lo=0.0, lo_open=True)
    if confidence >= 1:
        raise ValueError(f"confidence: must be < 1, got {confidence!r}")
    n_resamples = check_whole_number("n_resamples", n_resamples, lo=1)
    seed = check_whole_number("seed", seed)
    counts = np.broadcast_to(counts[:, None], hits.shape)
    cov = hits.sum(axis=0) / counts.sum(axis=0)
    out = np.column_stack([cov, np.full_like(cov, np.nan), np.full_like(cov, np.nan)])
    if hits.shape[0] < 2:
        return out
    res = stats.bootstrap((hits, counts), lambda h, c, axis: h.sum(axis=axis) / c.sum(axis=axis), paired=True,
                          confidence_level=confidence, n_resamples=n_resamples, method="percentile", axis=0,
                          rng=np.random.default_rng(seed))
    out[:, 1], out[:, 2] = res.confidence_interval.low, res.confidence_interval.high
    return out


def error_table(errors: dict, *, horizons_s=HORIZONS_S, windows=WINDOWS) -> pd.DataFrame:
    """Long table ``model, state, window, horizon_s, mae`` from per-log error arrays.

    ``errors`` maps a model name to a list of :func:`drift_errors` arrays (one per log);
    a cell is the mean over logs and over the first ``window`` intervals. A window or
    horizon given twice is a ValueError naming it (two rows of one cell).
    """
    windows, horizons_s = tuple(windows), tuple(horizons_s)
    if not windows or not all(isinstance(w, (int, np.integer)) and not isinstance(w, bool) and w >= 1
                              for w in windows):
        raise ValueError(f"windows: expected one or more whole numbers >= 1 of intervals, got {windows!r}")
    # two rows of one cell: paper_table failed in pandas' words ("Index contains duplicate entries")
    for name, values in (("windows", windows), ("horizons_s", horizons_s)):
        if len(set(values)) != len(values):
            raise ValueError(f"{name}: {values!r} gives one twice; expected each once")
    rows = []
    for model, per_log in errors.items():
        shapes = sorted({np.shape(a) for a in per_log})
        if len(shapes) != 1 or len(shapes[0]) != 3 or shapes[0][2] != 3:    # numpy's stack named nothing
            raise ValueError(f"errors[{model!r}]: expected one or more arrays of one shape (n_intervals, "
                             f"n_horizons, 3), got shapes {shapes}")
        E = np.stack(per_log)                                   # (L, S, nh, 3)
        if len(horizons_s) != E.shape[2]:
            raise ValueError(f"horizons_s: {len(horizons_s)} lead times given, but errors[{model!r}] has "
                             f"{E.shape[2]} per forecast: pass the horizons_s the errors were taken at")
        if not np.all(np.isfinite(E)):
            raise ValueError(f"errors[{model!r}]: NaN or inf errors; leave such forecasts out before the table")
        if max(windows) > E.shape[1]:
            raise ValueError(f"windows: {max(windows)} intervals asked, but errors[{model!r}] has {E.shape[1]} "
                             f"per log (a mean over fewer would be labelled as over {max(windows)})")
        for w in windows:
            m = E[:, :w].mean(axis=(0, 1))                      # (nh, 3)
            for k, state in enumerate(STATES):
                for j, h in enumerate(horizons_s):
                    rows.append({"model": model, "state": state, "window": w, "horizon_s": h, "mae": float(m[j, k])})
    return pd.DataFrame(rows)


def paper_table(long: pd.DataFrame, *, windows=WINDOWS) -> pd.DataFrame:
    """The paper's Table 2 layout: rows model x state, columns horizons, cells "first5/first20"
    (one error per cell with one window, as a benchmark of fewer than 20 intervals has)."""
    _check_windows(long, windows)
    maes = [long[long.window == w].set_index(["model", "state", "horizon_s"])["mae"].map("{:.2f}".format)
            for w in windows]
    cells = maes[0]
    for m in maes[1:]:
        cells = cells + "/" + m
    cells = cells.unstack("horizon_s")
    cells.columns = [f"{c:g} s" for c in cells.columns]
    order = list(dict.fromkeys(long["model"]))
    return cells.reindex(pd.MultiIndex.from_product([order, list(STATES)], names=["model", "state"]))


def _check_windows(long: pd.DataFrame, windows) -> None:
    """ValueError naming a window of ``windows`` [intervals] that the long table has no rows of."""
    have = sorted(set(long["window"]))
    for w in windows:
        if w not in have:
            raise ValueError(f"windows: {w} is not in the table; it has windows {have}: pass those")


def reduction_table(long: pd.DataFrame, model: str, reference: str = "dynamic", *, windows=WINDOWS) -> pd.DataFrame:
    """The paper's Table 3: % error reduction of ``model`` relative to ``reference``, "5/20"."""
    def pct(r):
        return (100.0 * (1.0 - r)).map(lambda x: str(int(round(x))) if np.isfinite(x) else "n/a")
    return _two_window_cells(long, model, reference, windows, pct)


def pooled_ratio_table(long: pd.DataFrame, model: str, reference: str = "dynamic", *,
                       windows=WINDOWS) -> pd.DataFrame:
    """The mean absolute error (pooled over the logs) of ``model`` over that of ``reference``,
    to two decimals, "5/20" (below 1: better than the reference; Table 3's reduction is
    100 (1 - ratio) %)."""
    return _two_window_cells(long, model, reference, windows,
                             lambda r: r.map(lambda x: f"{x:.2f}" if np.isfinite(x) else "n/a"))


def _two_window_cells(long: pd.DataFrame, model: str, reference: str, windows, fmt) -> pd.DataFrame:
    """``fmt`` of the error ratio ``model / reference`` per state and horizon, the two windows
    as "a/b" (states as rows, horizons as columns); a zero reference error gives a
    non-finite ratio, which ``fmt`` prints as "n/a"."""
    for name, m in (("model", model), ("reference", reference)):
        if m not in set(long["model"]):
            raise ValueError(f"{name}: {m!r} is not in the table; it has {list(dict.fromkeys(long['model']))}")
    if len(windows) != 2:
        raise ValueError(f"windows: expected two windows (first 5 / first 20), got {tuple(windows)!r}")
    _check_windows(long, windows)

    def cell(w):
        s = long[long.window == w].set_index(["model", "state", "horizon_s"])["mae"]
        return fmt(s[model] / s[reference])
    lo, hi = windows
    cells = (cell(lo) + "/" + cell(hi)).unstack("horizon_s")
    cells.columns = [f"{c:g} s" for c in cells.columns]
    return cells.reindex(list(STATES))
