"""What every forecast does first: the log through the one ingest, start rows, checked start
states and the commands (held or known) of each start.

:func:`_forecast_setup` runs the log through :func:`hybridship.logs.ingest.ingest`, the start
window through :func:`hybridship.forecast_inputs.assess_start_window` and the inputs through
:func:`hybridship.forecast_inputs.check_or_clip_inputs`; every forecaster of
:mod:`hybridship.predictors` starts from its result.
"""

from __future__ import annotations

import math

import functools
import numbers
import os
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..config import check_flags as _check_flags  # noqa: F401 (the predictors import it from here)
from ..forecast_inputs import FaultFlags, InputRangeError, assess_start_window, check_or_clip_inputs
from ..forecast_inputs.horizon import HorizonError, RequestError, horizon_steps
from ..forecast_inputs.wind import HELD_WIND, WindForecast
from ..logs.ingest import WHOLE_LOG_STEP, ingest
from ..logs.io import LogArrays
from ..messages import TIME_DECIMALS, seconds_text
from ..residual.features import ResidualConfig

__all__ = ["COMMAND_MODES", "FORECAST_HISTORY_S", "HorizonError", "RequestError", "as_log_arrays", "forecast_step_s",
           "start_indices"]

#: Seconds of log before the earliest start that a forecast reads (at least; the hybrid reads
#: more where its environment estimator needs it, see ``HybridPredictor.history_s``). The
#: start-window checks read far less, so they see the same samples whichever forecaster runs.
FORECAST_HISTORY_S = 1800.0
#: Longest forecast horizon [s] (one day): far beyond what the method is for, and a bound
#: on the memory of the rollout arrays (a horizon of 1e9 s would ask for gigabytes).
MAX_HORIZON_S = 86400.0
#: Most starts times steps one forecast call takes: each of its state, spread and rate arrays
#: (and each ensemble member's) holds 3 numbers per point, about 0.5 GB at this bound.
MAX_FORECAST_POINTS = 20_000_000
#: Extra seconds read at both ends of a forecast's time range, so that no filter or
#: derivative near a start sees the edge of what was read.
_RANGE_MARGIN_S = 60.0
#: Decimals [s] a forecast's step is rounded to: the log's time resolution (microseconds).
#: The median of float differences reads a 10-Hz log's 0.1 s as 0.10000000000000142.
_STEP_DECIMALS = TIME_DECIMALS
#: Decimals [s] lead times are rounded to, so that 600 steps of 0.1 s are 60.0 s.
_LEAD_DECIMALS = 9


def _in_log_terms(exc: InputRangeError, start_times_s: np.ndarray) -> InputRangeError:
    """A physics input out of range, said of the log: the value is the log's (the start state
    or an input held or read from it), so the start time names it, not the batch element."""
    if not exc.component or len(exc.index) < 2 or exc.index[0] >= len(start_times_s):
        return exc      # not one start's value (e.g. the step): the message stands as it is
    step = f", step {exc.index[1]}" if len(exc.index) == 3 else ""
    return InputRangeError(f"log: start time_s {seconds_text(start_times_s[exc.index[0]])}: {exc.field}"
                           f"[{exc.component}{step}]: {exc.value:g} is {exc.problem}; valid: {exc.valid} (a value "
                           f"the forecast takes from the log: a unit error?)", field=exc.field, index=exc.index,
                           value=exc.value, valid=exc.valid, component=exc.component, problem=exc.problem)


def as_log_arrays(log, vessel, *, purpose: str = "fit") -> LogArrays:
    """A path, a DataFrame in the log format or LogArrays, through :func:`hybridship.logs.ingest.ingest`
    (re-sorted, checked against ``vessel`` once; ``purpose`` "fit" or "forecast")."""
    return ingest(log, vessel, purpose=purpose)


def keeps_state_on_error(fit):
    """Make ``fit`` all or nothing: a call that raises leaves the predictor as it was.

    ``fit`` sets the learned state step by step (the environment estimator, the wind
    forecast, the nets, the spread); a failure half-way would leave a model that mixes a
    new environment with old nets and forecasts with it. Every step rebinds attributes
    rather than changing the objects they held, so restoring the attributes restores the
    model."""
    @functools.wraps(fit)
    def wrapper(self, *args, **kwargs):
        before = dict(self.__dict__)
        try:
            return fit(self, *args, **kwargs)
        except BaseException:
            self.__dict__.clear()
            self.__dict__.update(before)
            raise
    return wrapper


def check_log_items(logs) -> list:
    """The logs of a ``fit`` that reads none (the physics learns nothing), checked as one that
    reads them would take them: each a path to an existing file, a DataFrame or LogArrays
    (TypeError / FileNotFoundError naming ``logs``); ``()``, nothing given, is no log."""
    if isinstance(logs, tuple) and logs == ():
        return []
    out = log_list(logs)
    for i, log in enumerate(out):
        if isinstance(log, (str, os.PathLike)):
            if not os.path.isfile(log):
                raise FileNotFoundError(f"logs[{i}]: {os.fspath(log)}: no such file")
        elif not isinstance(log, (pd.DataFrame, LogArrays)):
            raise TypeError(f"logs[{i}]: expected a path, DataFrame or LogArrays, got {type(log).__name__}")
    return out


def log_list(logs) -> list:
    """The training logs as a list: one log (a path, a DataFrame or LogArrays) becomes a list of
    one; any other iterable is listed.

    Raises
    ------
    TypeError
        Naming what was given, when ``logs`` is neither a log nor an iterable of logs.
    ValueError
        When the iterable is empty.
    """
    if isinstance(logs, (str, os.PathLike, pd.DataFrame, LogArrays)):
        return [logs]
    try:
        out = list(logs)
    except TypeError:
        raise TypeError(f"logs: expected a log (path, DataFrame or LogArrays) or an iterable of logs, "
                        f"got {type(logs).__name__}") from None
    if not out:
        raise ValueError(f"logs: expected at least one log, got an empty {type(logs).__name__}")
    return out


def start_times_array(start_times_s) -> np.ndarray:
    """``start_times_s`` [s] as a 1-D float array: one number or a flat sequence of real
    numbers (lists, tuples, numpy arrays, pandas Series); text, booleans, nested sequences,
    mappings, sets and masked entries are refused naming ``start_times_s``."""
    def refuse(why):
        return RequestError(f"start_times_s: expected a number or a flat list of numbers of seconds; {why}")

    if start_times_s is None or isinstance(start_times_s, (str, bytes, dict, set, frozenset)):
        raise refuse(f"got {type(start_times_s).__name__} {start_times_s!r}")
    if np.ma.isMaskedArray(start_times_s) and np.ma.getmaskarray(start_times_s).any():
        raise refuse("got a masked array with masked entries")
    if hasattr(start_times_s, "__next__"):          # a generator or iterator: its values
        start_times_s = list(start_times_s)
    try:
        raw = np.asarray(start_times_s)
    except (TypeError, ValueError):
        raise refuse(f"got {type(start_times_s).__name__}") from None
    if raw.ndim > 1:
        raise refuse(f"got an array of shape {raw.shape}")
    real = raw.dtype.kind in "iuf" or (raw.dtype == object and all(
        isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)) for v in raw.ravel()))
    if not real:
        raise refuse(f"got {raw.dtype} values {raw.ravel()[:3].tolist()}")
    return np.atleast_1d(raw.astype(float))


def start_indices(arrays: LogArrays, start_times_s) -> np.ndarray:
    """Row index of each start time; every start time must be a sample time (within dt/4)."""
    t = arrays.time_s
    st = start_times_array(start_times_s)
    if st.size == 0:
        raise RequestError("start_times_s: at least one start time is needed")
    if not np.all(np.isfinite(st)):
        raise RequestError("start_times_s: contains NaN or inf")
    if np.unique(st).size < st.size:
        # a repeated start would come back as a second, identical forecast block
        u, n = np.unique(st, return_counts=True)
        raise RequestError(f"start_times_s: each start time at most once; {seconds_text(u[n > 1][0])} s is given "
                           f"{n[n > 1][0]} times")
    idx = np.clip(np.searchsorted(t, st), 0, len(t) - 1)
    prev = np.clip(idx - 1, 0, len(t) - 1)
    idx = np.where(np.abs(t[prev] - st) < np.abs(t[idx] - st), prev, idx)
    dt = forecast_step_s(arrays)
    bad = np.abs(t[idx] - st) > 0.25 * dt
    if bad.any():
        first = st[bad][0]
        if np.any(np.abs(arrays.resorted_time_s - first) <= 0.25 * dt):
            # a time no row keeps among the re-sorted ones: samples logged twice with different values
            raise RequestError(f"start_times_s: {seconds_text(first)} s is logged more than once with different values "
                               f"(a repeated time stamp?), so no sample of that time is used; give another start "
                               f"time or correct the log")
        raise RequestError(f"start_times_s: {first} s is not a sample time of the log "
                           f"(log spans {t[0]}..{t[-1]} s, dt {dt:g} s)")
    if np.unique(idx).size < idx.size:
        # two times within a quarter step of one sample: the same start, twice
        u, n = np.unique(idx, return_counts=True)
        same = st[idx == u[n > 1][0]]
        given = " and ".join(f"{seconds_text(x)} s" for x in same)
        raise RequestError(f"start_times_s: each start time at most once; {given} fall on one sample "
                           f"({seconds_text(t[u[n > 1][0]])} s)")
    return idx


def forecast_step_s(arrays: LogArrays) -> float:
    """The step of every forecast on ``arrays`` [s]: the median spacing of ``time_s``, rounded
    to the microsecond (1.0 without two samples).

    On an evenly sampled log this is the log's own step, so lead times and forecast times
    fall on its grid. On a log with jittered time stamps it is the median step, and a
    forecast runs whole steps of it from the start: its times are nominal, not the log's.
    On the rows of a log read for a time range (:func:`hybridship.logs.ingest.ingest`'s
    ``time_range_s``) it is the whole log's median step, so that a start's forecast does not
    depend on the other starts of its call.
    """
    whole = getattr(arrays, WHOLE_LOG_STEP, None)
    if whole is not None:       # rows read for a time range: the whole log's step, whatever the range
        return round(whole, _STEP_DECIMALS)
    t = arrays.time_s
    return round(float(np.median(np.diff(t))), _STEP_DECIMALS) if len(t) > 1 else 1.0


def _held_inputs(arrays: LogArrays, idx: np.ndarray, *, stop_after_failure: bool = True, wind=None):
    """Commands and wind at the start rows, shaped (S, 1, width) for the kernels.

    With ``stop_after_failure`` the rpm of a start where station keeping is off
    (``dp_active == 0``) is taken as 0: after a power failure no thrust is commanded, while
    the logged shaft speed is still running down for a second or two, and holding that
    value for a minute would push every forecast. Azimuth angles stay as logged (a
    stopped propeller still gives drag along its axis).
    """
    rpm = arrays.rpm[idx].copy()
    if stop_after_failure:
        rpm[arrays.dp_active[idx] == 0] = 0.0
    wind = arrays.wind[idx] if wind is None else wind
    return (np.ascontiguousarray(rpm[:, None]), np.ascontiguousarray(arrays.azimuth_rad[idx][:, None]),
            np.ascontiguousarray(wind[:, None]))


@dataclass
class _Setup:
    """Everything a forecast needs, after the log and start-window checks."""

    arrays: LogArrays
    idx: np.ndarray
    dt: float
    H: int
    eta0: np.ndarray
    nu0: np.ndarray
    rpm: np.ndarray
    az: np.ndarray
    wind: np.ndarray        # (S, 1, 2) held, or (S, H, 2) per step
    substeps: int
    flags: dict
    notes: tuple

    @property
    def lead_s(self) -> np.ndarray:
        """Lead time of every step, ``k dt`` for k = 0..H [s] (rounded to 1e-9 s, so that the
        leads read as whole multiples of the step)."""
        return np.round(np.arange(self.H + 1) * self.dt, _LEAD_DECIMALS)


#: Command modes of ``forecast(..., commands=)``.
COMMAND_MODES = ("held", "known")
#: Key of the spread calibration for forecasts that start after a failure
#: (:meth:`HybridPredictor.calibrate_after_stop`). Here beside the command modes, which the
#: model file reads too, so that it need not import the predictor.
AFTER_STOP = "after_stop"
#: Key of the spread calibration for forecasts that start later in a drift than those of
#: :data:`AFTER_STOP`: the drift has gathered speed, and its errors with it.
AFTER_STOP_LATE = "after_stop_late"


def _command_rows(arrays: LogArrays, idx: np.ndarray, H: int, dt: float) -> np.ndarray:
    """Rows (S, H) of the commands in force at each of the H steps after each start row: the
    last row logged by the step's time (within a quarter step), so that a gap or a change of
    the log's rate does not shift the commands in time (on an evenly sampled log, the rows
    ``idx + k``)."""
    t = arrays.time_s
    want = t[idx][:, None] + np.arange(H)[None, :] * dt
    late = want[:, -1] > t[-1] + 0.25 * dt
    if late.any():
        k = int(np.argmax(late))
        raise RequestError(f"commands='known': the log ends at {seconds_text(t[-1])} s, but the start at "
                           f"{seconds_text(t[idx[k]])} s needs logged commands up to time_s "
                           f"{seconds_text(want[k, -1])} s (the command of each of its {H} steps, logged at the "
                           "step's beginning); use commands='held' or an earlier start time")
    return np.searchsorted(t, want + 0.25 * dt, side="right") - 1


def _known_command_steps(arrays: LogArrays, rows: np.ndarray, rpm0: np.ndarray, az0: np.ndarray,
                         stop_after_failure: bool = True):
    """Logged commands of the steps after each start, (S, H, K) each, from their rows ``rows``
    (S, H) (:func:`_command_rows`).

    Step 0 is the start's command as the held mode uses it (``rpm0``, ``az0``, (S, K));
    later steps take the command logged by their time; a missing (NaN) command holds the
    last valid one (a dropped sample, not a new order). With ``stop_after_failure`` the rpm
    of steps where ``dp_active == 0`` is 0, as in :func:`_held_inputs`.
    """
    rpm, az = arrays.rpm[rows], arrays.azimuth_rad[rows]          # (S, H, K), copies
    rpm[:, 0], az[:, 0] = rpm0, az0
    if stop_after_failure:
        rpm[arrays.dp_active[rows] == 0] = 0.0
    return _hold_last_valid(rpm), _hold_last_valid(az)


def join_notes(*per_start) -> tuple:
    """Per start, the non-empty notes of each sequence joined with "; " (sequences of equal length)."""
    return tuple("; ".join(n for n in notes if n) for notes in zip(*per_start))


def _missing_command_notes(arrays: LogArrays, rows: np.ndarray) -> list[str]:
    """Per start, a note when commands of its H known steps (their rows ``rows`` (S, H),
    :func:`_command_rows`) were not logged (the reader holds the last logged value,
    :attr:`LogArrays.commands_logged`), "" otherwise."""
    H = rows.shape[1]
    # a step with no sample of its own (a gap, a slower log) holds the last one too
    missing = (~arrays.commands_logged[rows[:, 1:]] | (rows[:, 1:] == rows[:, :-1])).sum(axis=1)
    return [f"commands known: {n} of {H - 1} future command samples missing, the last valid one held" if n else ""
            for n in missing]


def _hold_last_valid(steps: np.ndarray) -> np.ndarray:
    """Replace NaN entries of ``steps`` (S, H, K) by the last finite value before them in H."""
    pos = np.where(np.isfinite(steps), np.arange(steps.shape[1])[None, :, None], 0)
    np.maximum.accumulate(pos, axis=1, out=pos)                 # index of the last valid step so far
    return np.take_along_axis(steps, pos, axis=1)


def _forecast_time_range(st: np.ndarray, horizon_s: float, history_s: float):
    """``(first_s, last_s)`` of the log a forecast reads from the start times ``st`` [s]
    (:func:`start_times_array`), or None when they are not finite (then the start checks
    report them)."""
    if st.size == 0 or not np.all(np.isfinite(st)):
        return None
    return (float(st.min()) - history_s - _RANGE_MARGIN_S, float(st.max()) + horizon_s + _RANGE_MARGIN_S)


def _forecast_setup(model, config: ResidualConfig, log, start_times_s, horizon_s: float,
                    stop_after_failure: bool = True, commands: str = "held",
                    history_s: float = FORECAST_HISTORY_S, wind_forecast: WindForecast = HELD_WIND) -> _Setup:
    """Checked log arrays, start rows, step, horizon, start states and commands.

    With ``commands="held"`` the commands are the start's, shaped (S, 1, K); with
    ``commands="known"`` they are the logged commands of the H steps after each start,
    (S, H, K) (see :func:`_known_command_steps`). The wind's future is not known at a
    start in either mode: it is held at its start value (S, 1, 2), or forecast by
    ``wind_forecast`` from its start value and its recent mean (S, H, 2)
    (:class:`~hybridship.forecast_inputs.wind.WindForecast`).

    The log goes through :func:`hybridship.logs.ingest.ingest` with ``purpose="forecast"``
    (re-sorted, checked against the vessel; sensor faults tolerated, format errors refused),
    restricted to the rows from ``history_s`` before the earliest start to the horizon after
    the last (so a forecast costs what it reads, not what the log holds), the start
    values through :func:`hybridship.forecast_inputs.assess_start_window` (valid samples of the
    window used, faults flagged, a start with too little valid data refused), and the held
    inputs through :func:`hybridship.forecast_inputs.check_or_clip_inputs` (clipped to the
    documented envelope and flagged).

    The step is :func:`forecast_step_s` and the horizon ``H = round(horizon_s / step)``
    whole steps; a horizon that rounds to no step at all, or lies more than a quarter step
    (the tolerance of a start time) and more than
    :data:`~hybridship.forecast_inputs.horizon.HORIZON_TOLERANCE` of itself
    from a whole number of steps, is refused
    (:class:`HorizonError`, a ValueError naming ``horizon_s`` and the step).
    """
    if isinstance(horizon_s, (str, bytes, bool, np.bool_)) or np.ndim(horizon_s) != 0:
        raise TypeError(f"horizon_s: expected a number of seconds, got {type(horizon_s).__name__} {horizon_s!r}")
    try:
        horizon_s = float(horizon_s)
    except (TypeError, ValueError):
        raise TypeError(f"horizon_s: expected a number of seconds, got {type(horizon_s).__name__} "
                        f"{horizon_s!r}") from None
    except OverflowError:       # an int beyond any float (10**400): Python's 'int too large to convert'
        horizon_s = math.inf
    if not 0 < horizon_s <= MAX_HORIZON_S:
        raise ValueError(f"horizon_s: must be > 0 and at most {MAX_HORIZON_S:g} s (one day), got {horizon_s}")
    if commands not in COMMAND_MODES:
        raise ValueError(f"commands: expected one of {COMMAND_MODES}, got {commands!r}")
    start_times_s = start_times_array(start_times_s)
    arrays = ingest(log, model.vessel, purpose="forecast",
                    time_range_s=_forecast_time_range(start_times_s, horizon_s,
                                                      max(history_s, wind_forecast.mean_window_s)))
    try:
        idx = start_indices(arrays, start_times_s)
    except ValueError as exc:
        # say it with the whole log's span, not the window read for the forecast
        try:
            with warnings.catch_warnings():     # the first read gave its warnings (unknown columns) once
                warnings.simplefilter("ignore")
                whole = ingest(log, model.vessel, purpose="forecast")
        except ValueError:
            # a fault outside the rows read does not matter to a forecast: the request's error stands
            raise exc from None
        start_indices(whole, start_times_s)
        raise
    dt = forecast_step_s(arrays)
    H = horizon_steps(horizon_s, dt)
    if len(idx) * (H + 1) > MAX_FORECAST_POINTS:
        raise RequestError(f"start_times_s, horizon_s: {len(idx)} starts x {H + 1} steps is more than "
                           f"{MAX_FORECAST_POINTS:.0e} forecast points (gigabytes of arrays): forecast the starts "
                           f"in smaller batches")
    sw = assess_start_window(arrays, idx, config.start_average_s)
    rpm, az, wind = _held_inputs(arrays, idx, stop_after_failure=stop_after_failure, wind=sw.wind)
    extra_notes = [""] * len(idx)
    if commands == "known":
        rows = _command_rows(arrays, idx, H, dt)
        rpm, az = _known_command_steps(arrays, rows, rpm[:, 0], az[:, 0], stop_after_failure)
        extra_notes = _missing_command_notes(arrays, rows)
    # the wind of every step: held (S, 1, 2) or forecast (S, H, 2); a start without wind
    # (sensor dropped) keeps its start value; at least the start's step, which the guards read
    wind = wind_forecast.steps(arrays.wind, arrays.time_s, idx, wind[:, 0], max(H, 1), dt, logged=arrays.wind_logged,
                               hold=sw.flags.get(FaultFlags.WIND_DROPPED))
    try:
        chk = check_or_clip_inputs(model.vessel, eta=sw.eta0, nu=sw.nu0, rpm=rpm, azimuth_rad=az,
                                   wind=wind, dt_s=dt)
    except InputRangeError as exc:
        raise _in_log_terms(exc, arrays.time_s[idx]) from None
    flags = {name: np.zeros(len(idx), dtype=bool) for name in FaultFlags.ALL}
    flags.update({k: np.asarray(v, dtype=bool) for k, v in sw.flags.items()})
    flags[FaultFlags.INPUT_CLIPPED] = np.asarray(chk.clipped, dtype=bool)
    notes = tuple(sw.notes) if len(sw.notes) == len(idx) else ("",) * len(idx)
    notes = join_notes(notes, extra_notes, chk.notes)       # what was clipped, which the flag alone does not say
    return _Setup(arrays, idx, dt, H, chk.eta, chk.nu, np.ascontiguousarray(chk.rpm),
                  np.ascontiguousarray(chk.azimuth_rad), np.ascontiguousarray(chk.wind), int(chk.substeps),
                  flags, notes)

def _check_row_stride(row_stride) -> int:
    if isinstance(row_stride, bool) or not isinstance(row_stride, (int, np.integer)) or row_stride < 1:
        raise ValueError(f"row_stride: expected an integer >= 1, got {row_stride!r}")
    return int(row_stride)
