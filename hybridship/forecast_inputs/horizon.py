"""A forecast horizon in whole steps of a log, and the refusals of a forecast request.

:func:`horizon_steps` is the one rule by which a horizon [s] becomes a number of a log's
steps: every forecast (:mod:`hybridship.predictors.forecast_setup`) and everything that
measures over a forecast's horizon (the wind forecast's fit,
:func:`hybridship.forecast_inputs.wind.fit_wind_forecast`) counts them with it, so that a
horizon one of them refuses is refused by all.
"""

from __future__ import annotations

__all__ = ["HORIZON_TOLERANCE", "HorizonError", "RequestError", "horizon_steps"]


#: A horizon within a quarter step, or this share of itself, of a whole number of steps is
#: that number of steps: the median step of a log with jittered time stamps is off its
#: nominal step by a fraction of a percent.
HORIZON_TOLERANCE = 0.005


def horizon_steps(horizon_s: float, dt_s: float, name: str = "horizon_s", where: str | None = None) -> int:
    """Whole steps of ``dt_s`` [s] in ``horizon_s`` [s]; :class:`HorizonError` naming ``name``
    (and the log ``where``, when given) when it rounds to no step, or lies more than a quarter
    step and more than :data:`HORIZON_TOLERANCE` of itself from a whole number of steps."""
    H = int(round(horizon_s / dt_s))
    in_log = f", in {where}" if where is not None else ""
    if H < 1:
        raise HorizonError(f"{name}: {horizon_s:g} s is shorter than one step of the log ({dt_s:g} s){in_log}")
    if abs(H * dt_s - horizon_s) > max(0.25 * dt_s, HORIZON_TOLERANCE * horizon_s):
        # a start time's tolerance, or the median step's own uncertainty on a jittered log
        # (120 s is 120 steps of 0.9976 s): a forecast of 63 s asked as 60 s is not an answer
        raise HorizonError(f"{name}: {horizon_s:g} s is not a whole number of the log's steps ({dt_s:g} s); "
                           f"the nearest is {H * dt_s:g} s{in_log}")
    return H


class RequestError(ValueError):
    """A forecast request the log cannot serve (start times that are not its samples, a
    horizon shorter than its step, known commands beyond its end): the caller's input, not
    the data, is wrong, and the command line reports it as a usage error (exit status 2)."""


class HorizonError(RequestError):
    """A forecast horizon the log's step cannot give (shorter than one step, or not within a
    quarter step or 0.5 % of a whole number of steps)."""
