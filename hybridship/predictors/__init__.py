"""Forecasters with one interface: dead reckoning, the dynamic model, a data-only ensemble, and the hybrid.

All four have ``fit(logs)`` and ``forecast(log, start_times_s, horizon_s=60,
commands="held")``; the forecast is a :class:`ForecastResult` (arrays, batch-first over
start times) with a ``to_frame()`` tidy pandas view. Many start times are integrated as
one batch. ``commands="known"`` feeds the logged future commands to the forecast (a
manoeuvre whose orders are known); ``"held"`` keeps them at their start values (a DP loss,
or a forecast whose future orders are unknown). The wind's future is unknown in both
modes: the hybrid carries it over the forecast with its fitted wind forecast (a gust
decaying to the recent mean), the other forecasters hold it at its start value.

The hybrid (Skulstad et al. 2022, sec. 3.2) steps the dynamic model one second, asks the
ensemble for the acceleration residual from the model-predicted velocities,
accelerations and the previous residual, adds it, and repeats. Beyond the paper, an
:class:`~hybridship.residual.guard.EnvelopeGuard` shrinks the correction where the
inputs leave the training envelope, and the ensemble's spread is propagated to a
position uncertainty.

One module per forecaster, plus what they share:

* :mod:`~hybridship.predictors.result`: :class:`ForecastResult`, what every forecast returns;
* :mod:`~hybridship.predictors.forecast_setup`: the log through the one ingest, start rows,
  checked start states and the held or known commands;
* :mod:`~hybridship.predictors.dead_reckoning`, :mod:`~hybridship.predictors.dynamic`,
  :mod:`~hybridship.predictors.data_only`, :mod:`~hybridship.predictors.hybrid`: the forecasters;
* :mod:`~hybridship.predictors.model_file`: the hybrid's model file (format version, checksum,
  the embedded vessel).

The names below are re-exported here, so ``from hybridship.predictors import HybridPredictor``
works.
"""

from __future__ import annotations

from .data_only import DataOnlyPredictor
from .dead_reckoning import DeadReckoning
from .dynamic import DynamicPredictor
from .forecast_setup import COMMAND_MODES, as_log_arrays, start_indices
from .hybrid import AFTER_STOP, ENVIRONMENT_SOURCES, HybridPredictor
from .model_file import MODEL_FORMAT_VERSION, ModelFileError
from .result import ForecastResult

__all__ = [
    "AFTER_STOP", "COMMAND_MODES", "ENVIRONMENT_SOURCES", "MODEL_FORMAT_VERSION",
    "DataOnlyPredictor", "DeadReckoning", "DynamicPredictor", "ForecastResult", "HybridPredictor",
    "ModelFileError", "as_log_arrays", "start_indices",
]
