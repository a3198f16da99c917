"""Drift-off analysis: how long after a blackout the vessel takes to reach a limit radius.

Modules (one concept each): :mod:`.weather` (weather states, uncertainty, tables),
:mod:`.spread` (perturbed vessels), :mod:`.engine` (the batched blackout kernel),
:mod:`.planning` (Monte-Carlo blackouts of one state), :mod:`.live` (a blackout now, from
a station-keeping log), :mod:`.season` (sweeps over many states, optionally on Dask),
:mod:`.report` (polar plot, exceedance curves, one-page summary) and :mod:`.command`
(the ``hybridship drift-off`` command line).

The names below are imported on first use, so that the command line starts quickly.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "DriftOffResult": "planning", "DriftOffSettings": "planning", "simulate_blackouts": "planning",
    "WeatherState": "weather", "WeatherUncertainty": "weather", "read_weather_table": "weather",
    "EnvironmentEstimate": "live", "environment_from_log": "live", "blackout_now": "live",
    "SeasonResult": "season", "season_sweep": "season", "write_report": "report",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
