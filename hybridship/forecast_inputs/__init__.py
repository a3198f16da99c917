"""Forecast inputs: what a forecast starts from and what it holds, checked before the physics runs.

The log itself is read, re-sorted and validated once, at the boundary, by
:func:`hybridship.logs.ingest.ingest`. What remains is judged per forecast:

* :mod:`~hybridship.forecast_inputs.start_window`: sensor faults in each start window
  (missing, frozen, jumping, late samples; a dropped wind sensor), the start values
  computed from the valid samples, and a flag per fault;
  :mod:`~hybridship.forecast_inputs.quiet_starts` clears at once the starts no detector
  could flag;
* :mod:`~hybridship.forecast_inputs.limits`: valid ranges of the physics inputs (states,
  wind, current, step), clipped and flagged or refused, with the command checks of
  :mod:`~hybridship.forecast_inputs.commands` (propeller speeds, thruster and rudder angles);
* :mod:`~hybridship.forecast_inputs.faults`: the flag names and the two refusals;
* :mod:`~hybridship.forecast_inputs.wind`: the wind over a forecast, held or a gust that
  decays to the recent mean (:class:`~hybridship.forecast_inputs.wind.WindForecast`).
"""

from hybridship.config import check_number
from hybridship.forecast_inputs.faults import FaultFlags, InputRangeError, StartWindowError
from hybridship.forecast_inputs.limits import (
    KNOT_M_S,
    CheckedInputs,
    Envelope,
    check_or_clip_inputs,
    envelope_for,
)
from hybridship.forecast_inputs.wind import HELD_WIND, WindForecast, fit_wind_forecast
from hybridship.forecast_inputs.start_window import (
    StartWindow,
    assess_start_window,
    forecast_log_arrays,
)

__all__ = [
    "HELD_WIND",
    "KNOT_M_S",
    "CheckedInputs",
    "Envelope",
    "FaultFlags",
    "InputRangeError",
    "StartWindow",
    "StartWindowError",
    "WindForecast",
    "assess_start_window",
    "check_number",
    "check_or_clip_inputs",
    "envelope_for",
    "fit_wind_forecast",
    "forecast_log_arrays",
]
