"""hybridship: ship motion forecasting with a 3-DOF Fossen model and neural residual ensembles.

The public API is importable from the package itself::

    from hybridship import HybridPredictor, DynamicModel, read_log

Names are resolved on first use (PEP 562), so ``import hybridship`` stays cheap: numpy,
numba, pandas and torch load only with the part of the package that needs them.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: Public name -> module that defines it.
_EXPORTS = {
    # forecasters and their results
    "Forecaster": "hybridship.forecaster",
    "HybridPredictor": "hybridship.predictors",
    "DynamicPredictor": "hybridship.predictors",
    "DataOnlyPredictor": "hybridship.predictors",
    "DeadReckoning": "hybridship.predictors",
    "ForecastResult": "hybridship.predictors",
    "ModelFileError": "hybridship.predictors",
    "FaultFlags": "hybridship.forecast_inputs",
    "EnsembleConfig": "hybridship.residual.ensemble",
    "ResidualConfig": "hybridship.residual.features",
    # physics
    "DynamicModel": "hybridship.physics.model",
    # logs
    "ingest": "hybridship.logs.ingest",
    "read_log": "hybridship.logs.io",
    "write_log": "hybridship.logs.io",
    "validate_log": "hybridship.logs.io",
    "LogArrays": "hybridship.logs.io",
    "LogFormatError": "hybridship.logs.io",
    # vessels
    "Vessel": "hybridship.vessel",
    "VesselFileError": "hybridship.vessel",
    "load_vessel": "hybridship.vessel",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'hybridship' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value          # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
