"""Vessel logs: the project log format (read, write, validate) and conversion to arrays.

Every log that fit, forecast, the benchmarks and the CLI use goes through
:func:`hybridship.logs.ingest.ingest` (module :mod:`hybridship.logs.ingest`; the function
is not re-exported here, where its name would hide the module).
"""

from hybridship.logs.io import (
    LogArrays,
    LogFormatError,
    LogFormatWarning,
    log_to_arrays,
    read_log,
    validate_log,
    write_log,
)
from hybridship.logs.preprocess import (
    derivative_by_segment,
    filtered_derivative,
    moving_average_start,
    segmentwise,
    split_segments,
)

__all__ = [
    "LogArrays",
    "LogFormatError",
    "LogFormatWarning",
    "derivative_by_segment",
    "filtered_derivative",
    "log_to_arrays",
    "moving_average_start",
    "read_log",
    "segmentwise",
    "split_segments",
    "validate_log",
    "write_log",
]
