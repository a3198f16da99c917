"""The spread of a drift forecast from the load the environment estimator does not follow.

After a failure the hybrid holds the estimated environment (current, slowly varying load)
over the forecast. The real load does not hold still: wave drift and gusts vary on the
scale of the forecast, more in rough weather than in calm. The ensemble's spread (the
posterior of the estimate) knows nothing of that variation, so a spread calibrated in one
weather is too narrow in another.

The station keeping before the failure shows how much the load varies. Over a window of
station keeping (the ``window_s`` of log time before the last station-keeping sample), the
filter's low-frequency motion (the estimator treats wave-frequency motion as measurement
noise) is cut into blocks of ``block_s`` of log time (a block across a gap in the log is
left out, not stretched); in each block, the change of the low-frequency velocity
less what the model, with the environment estimated there, explains is the mean
acceleration the estimate missed. The standard deviation of these block means,
``sigma_b``, is how far a held load may be off over about that time. Held over the
forecast, an acceleration error ``sigma_b`` moves the ship by ``0.5 sigma_b t^2``. That
term is added to the ensemble's spread (in quadrature) before the spread after a failure
is calibrated (:meth:`hybridship.predictors.HybridPredictor.calibrate_after_stop`), so the
calibrated spread grows with the variability of the weather the ship is in.

Only samples before the start are used (the filter's estimates are causal).
"""

from __future__ import annotations

import numpy as np

from ..config import check_number, check_whole_number, real_array
from .environment import CUR, LOAD, THR, current_input, external_accel, thrust_error_accel

__all__ = ["held_load_rows", "unexplained_load_std", "unexplained_load_std_windows", "held_load_std_ned",
           "held_load_spread"]


def held_load_rows(dp_active: np.ndarray, time_s: np.ndarray, start: int, step: int, window_s: float,
                   dt_s: float) -> np.ndarray:
    """Station-keeping rows on the filter's grid whose estimates measure the load's variability
    for a forecast starting at row ``start``: every ``step``-th row back from the last
    ``dp_active`` row before ``start``, over the last ``window_s`` [s] of log time up to it
    (increasing).

    Each row stands for one step ``dt_s`` [s] of the log (its nominal step), so the window holds
    the rows less than ``window_s - dt_s / 2`` before the last one: ``round(window_s / dt_s)``
    rows of an evenly sampled log, and fewer across a gap (a gap does not stretch the window
    back in time). Empty when there is no station keeping before ``start``.

    Raises
    ------
    TypeError, ValueError
        ``start`` (a row, at most the log's length) or ``step`` (>= 1) not a whole number,
        ``window_s`` not a time >= 0 or ``dt_s`` not > 0, or ``dp_active`` and ``time_s`` not
        1-D of one length, naming the argument.
    """
    dp_active, t = np.asarray(dp_active), np.asarray(time_s, dtype=float)
    if dp_active.ndim != 1 or t.shape != dp_active.shape:
        raise ValueError(f"held_load_rows: dp_active, time_s: expected two 1-D arrays of one length, got shapes "
                         f"{dp_active.shape} and {t.shape}")
    start = check_whole_number("held_load_rows: start", start, lo=0)
    if start > dp_active.size:
        raise ValueError(f"held_load_rows: start: expected a row of the log, at most {dp_active.size}, got {start}")
    step = check_whole_number("held_load_rows: step", step, lo=1)
    window_s = check_number("held_load_rows: window_s", window_s, lo=0.0)
    dt_s = check_number("held_load_rows: dt_s", dt_s, lo=0.0, lo_open=True)
    dp = np.flatnonzero(dp_active[:start] != 0)
    if dp.size == 0:
        return dp
    last = int(dp[-1])
    first = int(np.searchsorted(t, t[last] - window_s + 0.5 * dt_s, side="right"))
    rows = np.arange(last, first - 1, -step)[::-1]
    return rows[dp_active[rows] != 0]


def unexplained_load_std(model, arrays, estimate, block_rows: int, step: int = 1) -> np.ndarray:
    """Standard deviation of the block-mean acceleration that the estimate leaves unexplained.

    Parameters
    ----------
    model : hybridship.physics.model.DynamicModel
    arrays : LogArrays
        The log (commands and wind at the estimate's rows).
    estimate : EnvironmentEstimate
        The filter's estimates at increasing station-keeping rows, every ``step``-th row of
        the log (see :func:`held_load_rows`).
    block_rows : int
        Estimates per block (>= 1): a block is ``block_rows * step * arrays.dt_s`` [s] of log
        time.
    step : int
        Rows of the log from one estimate to the next (>= 1), each row one ``arrays.dt_s``.

    Returns
    -------
    ndarray, shape (3,)
        ``[surge_m_s2, sway_m_s2, yaw_rad_s2]``; zeros with fewer than two pairs of
        consecutive whole blocks (three blocks of a window without a gap).

    Raises
    ------
    ValueError
        ``block_rows`` or ``step`` not a whole number >= 1.
    """
    block_rows = check_whole_number("unexplained_load_std: block_rows", block_rows, lo=1)
    step = check_whole_number("unexplained_load_std: step", step, lo=1)
    n = len(estimate.rows)
    return unexplained_load_std_windows(model, arrays, estimate, np.array([0]), np.array([n]), block_rows, step)[0]


def unexplained_load_std_windows(model, arrays, estimate, first, stop, block_rows: int, step: int = 1) -> np.ndarray:
    """:func:`unexplained_load_std` of many windows of one run of estimates, batched.

    The model's acceleration is evaluated once per estimate, and each window's block means
    come from cumulative sums, so overlapping windows (a start every few seconds during
    station keeping, each with its own ten minutes) cost little more than one.

    Parameters
    ----------
    model, arrays : as :func:`unexplained_load_std`
    estimate : EnvironmentEstimate
        Estimates at increasing rows on one filter grid (every ``step``-th row).
    first, stop : array of int, shape (K,)
        Window ``k`` is the estimates ``first[k]:stop[k]`` (consecutive positions in
        ``estimate``; each one a window of :func:`held_load_rows`).
    block_rows : int
        Estimates per block (>= 1). Blocks are spans of ``block_rows`` grid steps
        (``step * arrays.dt_s`` [s] each) of log time, ending at each window's last estimate;
        each estimate is in the block of its time, rounded to whole grid steps. Only pairs of
        consecutive blocks that both hold all their estimates count: a block across a gap in
        the log (or across rows without station keeping) is left out, not stretched over
        more time than the others.
    step : int
        Rows of the log from one estimate to the next on the grid (>= 1).

    Returns
    -------
    ndarray, shape (K, 3)
        ``[surge_m_s2, sway_m_s2, yaw_rad_s2]`` per window; zeros where a window holds
        fewer than two pairs of consecutive whole blocks (three blocks of a window without
        a gap).

    Raises
    ------
    ValueError
        ``block_rows`` or ``step`` not a whole number >= 1, or ``first`` and ``stop`` not
        whole numbers of one 1-D shape with ``0 <= first <= stop <= len(estimate.rows)``.
    """
    block_rows = check_whole_number("unexplained_load_std_windows: block_rows", block_rows, lo=1)
    step = check_whole_number("unexplained_load_std_windows: step", step, lo=1)
    first, stop = np.asarray(first), np.asarray(stop)
    if first.dtype.kind not in "iu" or stop.dtype.kind not in "iu":
        raise ValueError(f"unexplained_load_std_windows: first, stop: expected whole numbers (positions in the "
                         f"estimate), got dtypes {first.dtype} and {stop.dtype}")
    if first.ndim != 1 or stop.shape != first.shape:
        raise ValueError(f"unexplained_load_std_windows: first, stop: expected two 1-D arrays of one length, got "
                         f"shapes {first.shape} and {stop.shape}")
    n = len(estimate.rows)
    if np.any((first < 0) | (first > stop) | (stop > n)):
        raise ValueError(f"unexplained_load_std_windows: first, stop: expected 0 <= first <= stop <= {n} (the "
                         f"estimate's length)")
    first, stop = first.astype(int), stop.astype(int)
    out = np.zeros((len(first), 3))
    if not np.any(stop > first):
        return out
    rows = estimate.rows
    t = arrays.time_s[rows]
    # each estimate's grid step counted from the first: its time in whole steps of the grid,
    # so that a gap leaves its steps empty (without a gap, the estimate's position)
    slot = np.rint((t - t[0]) / (step * float(arrays.dt_s))).astype(np.int64)
    B = block_rows
    last = np.clip(stop - 1, 0, len(slot) - 1)
    # block pairs counted back from each window's end that its time span could hold
    n_pairs = np.where(stop > first, (slot[last] - slot[np.minimum(first, last)] + 1) // B - 1, 0)
    m = np.arange(max(int(n_pairs.max()), 0))
    end_slot = slot[last][:, None] - B * m[None, :]     # the later block's last step
    end = np.clip(np.searchsorted(slot, end_slot), 0, len(slot) - 1)   # its estimate, if there
    lo = end - 2 * B + 1                                # the earlier block's first estimate, if whole
    # both blocks whole: their 2 B steps all hold an estimate of the window
    valid = ((m[None, :] < n_pairs[:, None]) & (lo >= first[:, None]) & (end < stop[:, None])
             & (slot[end] == end_slot) & (slot[end] - slot[np.maximum(lo, 0)] == 2 * B - 1))
    n_valid = valid.sum(axis=1)
    use = n_valid >= 2
    if not np.any(use):
        return out
    x = estimate.x
    eta, nu = x[:, 0:3], x[:, 3:6]
    ext = external_accel(eta[:, 2], x[:, LOAD], 0.0, 0.0, estimate.load_map) + thrust_error_accel(
        model, estimate.thrust_error_model, eta, nu, arrays.rpm[rows], arrays.azimuth_rad[rows],
        arrays.wind[rows], x[:, CUR], x[:, THR])
    acc = model.acceleration(eta, nu, rpm=arrays.rpm[rows], azimuth_rad=arrays.azimuth_rad[rows],
                             wind=arrays.wind[rows], current=current_input(x[:, CUR]), accel_ext=ext)
    cum = np.concatenate([np.zeros((1, 3)), np.cumsum(acc, axis=0)])
    valid = valid[use][:, :int(n_pairs[use].max())]     # (K', pairs)
    end = np.where(valid, end[use][:, :valid.shape[1]], stop[use][:, None] - 1)  # padding: masked below
    prev = np.where(valid, end - B, end)
    # a block's velocity change from the previous block's end, less the model's mean acceleration
    dt = np.where(valid, t[end] - t[prev], 1.0)
    dnu = (nu[end] - nu[prev]) / dt[..., None]
    mean_acc = (cum[end + 1] - cum[end + 1 - B]) / B
    missed = np.where(valid[..., None], dnu - mean_acc, np.nan)   # padding out of the statistics
    out[use] = np.nanstd(missed, axis=1, ddof=1)
    return out


def held_load_std_ned(sigma_b: np.ndarray) -> np.ndarray:
    """``sigma_b`` (..., 3) in the body frame [m/s^2, m/s^2, rad/s^2] as a spread in
    ``[north, east, yaw]``: north and east both take the RMS of surge and sway (the ship
    turns during a drift, so neither body axis stays with one NED axis)."""
    sigma_b = np.asarray(sigma_b, dtype=float)
    pos = np.sqrt(0.5 * (sigma_b[..., 0] ** 2 + sigma_b[..., 1] ** 2))
    return np.stack([pos, pos, sigma_b[..., 2]], axis=-1)


def held_load_spread(sigma_b: np.ndarray, lead_s: np.ndarray) -> np.ndarray:
    """Position and heading spread ``0.5 sigma_b t^2`` of an acceleration error held over the
    forecast: ``sigma_b`` (S, 3) [m/s^2, m/s^2, rad/s^2] at leads (H,) [s] -> (S, H, 3)
    [m, m, rad] (north and east as :func:`held_load_std_ned`).

    Raises
    ------
    TypeError, ValueError
        ``sigma_b`` or ``lead_s`` not real numbers, ``sigma_b`` not of shape (S, 3) or not
        finite and >= 0, ``lead_s`` not a 1-D array of finite lead times >= 0, naming the
        argument.
    """
    sigma_b = real_array("held_load_spread: sigma_b", sigma_b)
    lead_s = real_array("held_load_spread: lead_s", lead_s)
    if sigma_b.ndim != 2 or sigma_b.shape[1] != 3:
        raise ValueError(f"held_load_spread: sigma_b: expected the shape (S, 3) [m/s^2, m/s^2, rad/s^2], got "
                         f"shape {sigma_b.shape}")
    if not np.all(np.isfinite(sigma_b) & (sigma_b >= 0)):
        raise ValueError("held_load_spread: sigma_b: expected finite values >= 0 (standard deviations)")
    if lead_s.ndim != 1 or not np.all(np.isfinite(lead_s) & (lead_s >= 0)):
        raise ValueError(f"held_load_spread: lead_s: expected a 1-D array of finite lead times >= 0 [s], got "
                         f"{lead_s.tolist()}")
    return 0.5 * held_load_std_ned(sigma_b)[:, None, :] * lead_s[None, :, None] ** 2
