"""The fault vocabulary of the forecast inputs: flag names, the two refusals, and how a
refused value is named.

:class:`FaultFlags` names every flag a forecast can carry (the columns of forecast tables
and CLI output). A start window with too little valid data is refused with
:class:`StartWindowError`; a physics input that is non-finite or out of range (and not
clipped) with :class:`InputRangeError`, whose message names the input, the batch element
(and step), the component, the value and the valid range.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FaultFlags", "StartWindowError", "InputRangeError"]


class FaultFlags:
    """Names of the fault flags (column names in forecast tables and CLI output).

    Attributes
    ----------
    START_WINDOW : tuple of str
        The flags :func:`~hybridship.forecast_inputs.start_window.assess_start_window` sets.
    ALL : tuple of str
        Every flag, in the order of the forecast table's columns.
    INFORMATIONAL : tuple of str
        Flags that do not mean the forecast was degraded.
    """

    NAN_IN_WINDOW = "nan_in_window"
    TOO_LITTLE_VALID = "too_little_valid"
    FROZEN_SENSOR = "frozen_sensor"
    POSITION_JUMP = "position_jump"
    HEADING_WRAPPED = "heading_wrapped"
    WIND_DROPPED = "wind_dropped"
    LATE_OR_OUT_OF_ORDER = "late_or_out_of_order"
    INPUT_CLIPPED = "input_clipped"
    OUT_OF_ENVELOPE = "out_of_envelope"

    START_WINDOW = (NAN_IN_WINDOW, TOO_LITTLE_VALID, FROZEN_SENSOR, POSITION_JUMP, HEADING_WRAPPED,
                    WIND_DROPPED, LATE_OR_OUT_OF_ORDER)
    ALL = START_WINDOW + (INPUT_CLIPPED, OUT_OF_ENVELOPE)
    INFORMATIONAL = (HEADING_WRAPPED,)


class StartWindowError(ValueError):
    """A forecast start has too little valid data in its start window.

    Attributes
    ----------
    start_time_s : float
        The first refused start.
    reason : str
        What was missing or invalid there.
    refused_start_times_s : ndarray
        Every refused start of the call.
    """

    def __init__(self, message: str, *, start_time_s: float, reason: str, refused_start_times_s):
        super().__init__(message)
        self.start_time_s = float(start_time_s)
        self.reason = reason
        self.refused_start_times_s = np.asarray(refused_start_times_s, dtype=float)


class InputRangeError(ValueError):
    """A physics input is non-finite or outside its valid range (and was not clipped).

    Attributes
    ----------
    field : str
        The input (``"rpm"``, ``"wind"``, ...).
    index : tuple of int
        Position of the offending value in the input array.
    value : float
    valid : str
        The valid range, as text.
    """

    def __init__(self, message: str, *, field: str, index: tuple, value: float, valid: str):
        super().__init__(message)
        self.field = field
        self.index = tuple(int(i) for i in index)
        self.value = float(value)
        self.valid = valid


#: Component names of the vector inputs, quoted in messages.
COMPONENTS = {
    "eta": ("north_m", "east_m", "psi_rad"),
    "nu": ("u_m_s", "v_m_s", "r_rad_s"),
    "wind": ("speed_m_s", "dir_from_rad"),
    "current": ("speed_m_s", "dir_to_rad"),
}


def _where_text(name: str, a: np.ndarray, index: tuple, components) -> str:
    parts = []
    if a.ndim >= 2:
        parts.append(f"batch {index[0]}")
    if a.ndim == 3:
        parts.append(f"step {index[1]}")
    comp = components[index[-1]] if components and index[-1] < len(components) else f"component {index[-1]}"
    parts.append(comp)
    return f"{name}[{', '.join(parts)}]"


def refuse(name: str, a: np.ndarray, bad: np.ndarray, valid: str, components=None, why: str = ""):
    """Raise :class:`InputRangeError` for the first True entry of ``bad`` (same shape as ``a``).

    The message names the input, batch element (and step), component, value and ``valid``.
    """
    index = np.unravel_index(int(np.argmax(bad)), a.shape)
    value = a[index]
    raise InputRangeError(
        f"{_where_text(name, a, index, components)}: {value:g} is {why or 'outside the valid range'}; "
        f"valid: {valid} (hybridship.forecast_inputs.limits)",
        field=name, index=index, value=value, valid=valid)


def batch_mask(a: np.ndarray, bad: np.ndarray, batch: int) -> np.ndarray:
    """(batch,) True for the batch elements of ``a`` where ``bad`` (``a``'s shape, or its
    shape without the last axis) holds; an unbatched input counts for every element."""
    m = bad.reshape(bad.shape[0], -1).any(axis=1) if a.ndim >= 2 else np.array([bad.any()])
    return np.broadcast_to(m, (batch,)).copy() if m.shape[0] in (1, batch) else m


def column_mask(a: np.ndarray, col: int, bad_col: np.ndarray) -> np.ndarray:
    """A bool array of ``a``'s shape, ``bad_col`` in column ``col`` and False elsewhere."""
    full = np.zeros(a.shape, dtype=bool)
    full[..., col] = bad_col
    return full
