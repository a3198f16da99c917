"""Drift-off analysis: how long after a blackout the vessel takes to reach a limit radius.

Modules (one concept each): :mod:`.weather` (weather states, uncertainty, tables),
:mod:`.spread` (perturbed vessels), :mod:`.engine` (the batched blackout kernel),
:mod:`.planning` (Monte-Carlo blackouts of one state), :mod:`.live` (a blackout now, from
a station-keeping log), :mod:`.season` (sweeps over many states, optionally on Dask) and
:mod:`.report` (polar plot, exceedance curves, one-page summary).
"""

from .planning import DriftOffResult, DriftOffSettings, simulate_blackouts
from .weather import WeatherState, WeatherUncertainty, read_weather_table

__all__ = ["DriftOffResult", "DriftOffSettings", "simulate_blackouts", "WeatherState", "WeatherUncertainty",
           "read_weather_table"]
