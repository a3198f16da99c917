"""Training logs that are one recording twice (a copy in another format, a file copied by hand).

A model trained on a recording twice weighs it twice, and the choices ``fit`` makes by
leaving one failure out at a time (the hull's yaw moment in a drift, the thrust-error
prior) would still see the left-out failure in its copy. Copies are recognised by the
content of the parsed samples, not by their file names or containers: the same samples
give the same digest whether they were read from CSV, ``.csv.gz`` or Parquet.
"""

from __future__ import annotations

import hashlib
import os

import numpy as np

__all__ = ["samples_digest", "check_distinct_logs", "check_training_lengths", "log_label", "read_training_logs",
           "warn_logs_without_wind", "warn_other_rate", "warn_no_wind", "training_log_facts", "NO_WIND_FORECAST_WARNING"]

#: The start of a forecast's warning on a log without wind columns for a model trained with
#: wind (:func:`warn_no_wind`); ``fit`` says it once per training log instead.
NO_WIND_FORECAST_WARNING = "log: no wind columns"


def samples_digest(arrays) -> str:
    """sha256 of a log's parsed samples: times, position and heading, velocities, commands,
    wind and ``dp_active`` (shape, dtype and bytes of each).

    Parameters
    ----------
    arrays : hybridship.logs.io.LogArrays

    Returns
    -------
    str
        64 hex digits; equal only for bit-identical samples (two separate recordings never
        share their sensor noise, so equal digests mean one recording twice).
    """
    h = hashlib.sha256()
    for name in ("time_s", "eta", "nu", "rpm", "azimuth_rad", "wind", "dp_active"):
        a = np.ascontiguousarray(getattr(arrays, name))
        h.update(f"{name}:{a.dtype.str}:{a.shape};".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def log_label(log, index: int) -> str:
    """How a message names training log ``index``: its path, else its position ``logs[i]``."""
    return os.fspath(log) if isinstance(log, (str, os.PathLike)) else f"logs[{index}]"


def read_training_logs(given, vessel) -> tuple[list, list[str]]:
    """The training logs ``given`` (paths, DataFrames or LogArrays) through
    :func:`hybridship.logs.ingest.ingest`, and their labels (:func:`log_label`).

    A fault in one of several DataFrames is named by its place, ``logs[i]``, not as "log",
    which would not say which of them; a lone log is named as a forecast names it, so that
    fit and forecast refuse it with the same message.

    Parameters
    ----------
    given : list
        The logs, as :func:`hybridship.predictors.forecast_setup.log_list` returns them.
    vessel : hybridship.vessel.Vessel

    Returns
    -------
    arrays : list of LogArrays
    labels : list of str
    """
    from ..logs.ingest import ingest

    labels = [log_label(x, i) for i, x in enumerate(given)]
    names = labels if len(given) > 1 else [None] * len(given)
    return [ingest(x, vessel, purpose="fit", name=n) for x, n in zip(given, names)], labels


#: Fewest samples of a training log (the filtered derivatives need a neighbour on each side).
MIN_TRAINING_SAMPLES = 3


def check_training_lengths(arrays, labels) -> None:
    """Refuse a training log with fewer than :data:`MIN_TRAINING_SAMPLES` samples, naming it."""
    for a, label in zip(arrays, labels):
        if len(a.time_s) < MIN_TRAINING_SAMPLES:
            raise ValueError(f"{label}: a training log needs at least {MIN_TRAINING_SAMPLES} samples, "
                             f"got {len(a.time_s)}")


def check_calibration_horizon(arrays, labels, horizon_s: float) -> None:
    """Refuse a calibration horizon ``horizon_s`` [s] that is not a whole number of a training
    log's steps, naming ``calibration_config.horizon_s`` and the log: every length ``fit``
    measures over it (calibration starts, the wind forecast's fit and error paths, the
    failures with enough drift) counts its steps, as a forecast does, with
    :func:`~hybridship.forecast_inputs.horizon.horizon_steps` (a
    :class:`~hybridship.forecast_inputs.horizon.HorizonError` when it is shorter than one
    step, or off a whole number by more than a quarter step and 0.5 %)."""
    from ..forecast_inputs.horizon import horizon_steps

    for a, label in zip(arrays, labels):
        if len(a.time_s) > 1:
            horizon_steps(horizon_s, a.dt_s, "calibration_config.horizon_s", where=label)


def warn_logs_without_wind(arrays, labels) -> None:
    """Warn, naming them, about training logs without wind columns beside logs with them.

    Their wind is read as none, so the nets learn the wind's force there as part of the
    residual, unlike on the others (the format makes wind optional, so this is no fault).

    Parameters
    ----------
    arrays : sequence of LogArrays
    labels : sequence of str
        Names of the logs for the message (file paths where known).
    """
    from ..messages import warn_user

    with_wind = [label for a, label in zip(arrays, labels) if a.wind_columns]
    if not with_wind:
        return
    for a, label in zip(arrays, labels):
        if not a.wind_columns:
            warn_user(f"{label}: no wind columns (wind_speed_m_s, wind_dir_deg), while {with_wind[0]}"
                      f"{' and others have' if len(with_wind) > 1 else ' has'} them: its wind is taken as "
                      f"none, so the nets learn the wind's force there as part of the residual; give its "
                      f"wind columns or train without it", UserWarning)



def training_log_facts(arrays) -> dict:
    """What the forecast warnings compare a forecast log with: the training logs' steps
    [s] (``log_step_s``) and whether any had wind (``trained_with_wind``)."""
    from .forecast_setup import forecast_step_s

    return {"log_step_s": sorted({forecast_step_s(a) for a in arrays}),
            "trained_with_wind": any(a.has_wind for a in arrays)}


def warn_other_rate(training_info: dict, dt_s: float) -> None:
    """Warn when a forecast log's step ``dt_s`` [s] is not one the nets were trained at (more
    than 10 % off ``training_info["log_step_s"]``): their inputs (rates, filtered
    derivatives) and the step they predict then differ. A ``training_info`` without the
    entry (model files from before it was recorded) gives no warning."""
    from ..messages import warn_user

    trained = training_info.get("log_step_s")
    # near one of the steps, not merely between the shortest and the longest (0.5 s is neither 0.1 nor 1 s)
    if trained and not any(0.9 * x <= dt_s <= 1.1 * x for x in trained):
        warn_user(f"log: its step is {dt_s:g} s, but the model was trained on logs with a step of "
                  f"{', '.join(f'{x:g}' for x in trained)} s; forecasts at another rate are less "
                  f"accurate: train on logs at this rate", UserWarning)


def warn_no_wind(training_info: dict, arrays) -> None:
    """Warn when a forecast log has no wind columns but the model was trained on logs with
    wind (``training_info["trained_with_wind"]``): the format makes wind optional, so this is
    no fault, yet the forecast then leaves out the wind's force, which the nets were never
    trained to make up for. (Wind columns without a valid sample are a dead sensor, flagged
    ``wind_dropped`` instead.)"""
    from ..messages import warn_user

    if training_info.get("trained_with_wind") and not arrays.wind_columns:
        warn_user(f"{NO_WIND_FORECAST_WARNING} (wind_speed_m_s, wind_dir_deg), but the model was trained "
                  "on logs with wind; the forecast leaves out the wind's force: give the wind columns",
                  UserWarning)


def check_distinct_logs(arrays, labels) -> None:
    """Refuse training logs with identical samples (:func:`samples_digest`).

    Parameters
    ----------
    arrays : sequence of LogArrays
    labels : sequence of str
        Names of the logs for the message (file paths where known).

    Raises
    ------
    ValueError
        Naming every pair of identical logs (one line each).
    """
    first: dict[str, str] = {}
    pairs = []
    for a, label in zip(arrays, labels):
        key = samples_digest(a)
        if key in first:
            pairs.append((first[key], label))
        else:
            first[key] = label
    if pairs:
        raise ValueError("\n".join(f"logs: {b} has the same samples as {a} (one recording twice would be trained "
                                   f"on twice); remove one of them" for a, b in pairs))
