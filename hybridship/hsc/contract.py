"""The contract of the surge/pitch models: SS, ARX, NARX (``"ann"``) and the hybrid.

The ship forecasters follow :class:`hybridship.forecaster.Forecaster` (logs in, NED
trajectories from chosen start times out). The high-speed-craft models of the paper work
on records instead: inputs ``U = [engine rpm, PWM %, heave acceleration m/s^2]``, shape
``(N, 3)``, and outputs ``Y = [speed m/s, pitch rad]``, shape ``(N, 2)``, sampled at one
rate. :class:`SurgePitchModel` is their contract, checked by
``tests/test_forecaster_contract.py`` with the same checks as the ship forecasters where
they carry over:

* ``fit(U, Y)`` learns from a record and returns the model itself; learned state is set by
  ``fit`` only, never by a prediction, and all or nothing: a fit that raises leaves the
  model as it was.
* ``one_step(U, Y)`` predicts ``y[k]`` from the measured outputs and the inputs up to
  ``k - 1``; ``free_run(U, Y_init, n_init)`` simulates from the inputs, the first
  ``n_init`` rows of ``Y_init`` being the initial conditions (no later measured output
  enters). Both return ``(N, 2)``; rows without a prediction (the first ``n_init``) are
  NaN, every other row is finite.
* Causal: a prediction for row ``k`` does not change when rows ``k`` and later of ``U``
  and ``Y`` change.
* An unfitted model raises :class:`RuntimeError`; bad inputs raise :class:`ValueError`
  whose message starts with the argument at fault (``U``, ``Y``, ``Y_init``, ``n_init``);
  the grey-box hybrid also refuses values no craft record holds (a negative rpm or
  speed, PWM outside 0-100 %, :func:`check_physical`).
* Deterministic: the same call, and a refit on the same record, give the same numbers.

None of them has a model file (the benchmark fits them afresh from its seed).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ..config import real_array

__all__ = ["SurgePitchModel", "N_INPUTS", "N_OUTPUTS", "check_free_run", "check_n_init", "check_physical",
           "check_record", "require_fitted"]

#: Columns of ``U`` (engine rpm, PWM %, heave acceleration m/s^2) and of ``Y`` (speed m/s, pitch rad).
N_INPUTS, N_OUTPUTS = 3, 2


@runtime_checkable
class SurgePitchModel(Protocol):
    """Anything with ``name``, ``n_init``, ``fit``, ``one_step`` and ``free_run`` (see the module notes).

    Attributes
    ----------
    name : str
        Short identifier used in the benchmark table (``"ss"``, ``"arx"``, ``"ann"``, ``"hybrid"``).
    n_init : int
        Fewest initial rows a free run needs (lags of the outputs).
    """

    name: str
    n_init: int

    def fit(self, U, Y) -> "SurgePitchModel":
        """Learn from one record (``U`` (N, 3), ``Y`` (N, 2)); returns self."""
        ...

    def one_step(self, U, Y) -> np.ndarray:
        """One-step-ahead predictions, (N, 2)."""
        ...

    def free_run(self, U, Y_init, n_init: int) -> np.ndarray:
        """Simulation from the inputs after ``n_init`` measured rows, (N, 2)."""
        ...


def _matrix(name: str, A, columns: int | None, rows: int | None = None) -> np.ndarray:
    want = f"(N, {'n' if columns is None else columns})"
    try:                                        # text such as "800" was parsed as a number
        A = np.array(real_array(name, A), dtype=float)      # a copy: the caller's array is never touched
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a numeric array of shape {want}") from None
    if A.ndim != 2 or A.shape[1] < 1 or (columns is not None and A.shape[1] != columns):
        raise ValueError(f"{name}: expected shape {want}, got {A.shape}")
    if rows is not None and A.shape[0] != rows:
        raise ValueError(f"{name}: expected {rows} rows like U, got {A.shape[0]}")
    return A


def _finite(name: str, A: np.ndarray):
    bad = ~np.isfinite(A)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise ValueError(f"{name}: NaN or inf at row {row}, column {col} ({int(bad.any(1).sum())} bad row(s))")


def check_record(U, Y, *, min_rows: int = 2, shape: tuple[int, int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``U`` (N, nu) and ``Y`` (N, ny) as finite float copies, ``N >= min_rows``; errors name the argument.

    ``shape = (nu, ny)`` fixes the column counts (the fitted model's; the paper's records
    have (3, 2)); None accepts any (the identified models are general MIMO models).
    """
    nu, ny = shape if shape is not None else (None, None)
    U = _matrix("U", U, nu)
    if U.shape[0] < min_rows:
        raise ValueError(f"U: need at least {min_rows} rows, got {U.shape[0]}")
    Y = _matrix("Y", Y, ny, U.shape[0])
    _finite("U", U)
    _finite("Y", Y)
    return U, Y


def check_physical(U: np.ndarray, Y: np.ndarray, y_name: str = "Y") -> None:
    """Signs and ranges of a craft record's columns (checked arrays, 3 inputs, 2 outputs):
    engine rpm >= 0, PWM duty in [0, 100] %, speed >= 0 m/s. A record with a negated rpm
    was forecast at 17-81 kn by every model, without a word.

    The grey-box hybrid and the benchmark's scoring check their records with it; the
    identified models are general MIMO models and take any finite numbers.
    """
    for name, A, col, what, lo, hi in (("U", U, 0, "engine speed [rpm]", 0.0, np.inf),
                                       ("U", U, 1, "PWM duty [%]", 0.0, 100.0),
                                       (y_name, Y, 0, "speed [m/s]", 0.0, np.inf)):
        bad = (A[:, col] < lo) | (A[:, col] > hi)
        if bad.any():
            row = int(np.argmax(bad))
            span = f"in [{lo:g}, {hi:g}]" if np.isfinite(hi) else f">= {lo:g}"
            raise ValueError(f"{name}: column {col} ({what}) is {A[row, col]:g} at row {row} "
                             f"({int(bad.sum())} row(s) outside); expected {span}")


def check_free_run(U, Y_init, n_init, model_n_init: int,
                   shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, int]:
    """Inputs of a free run: ``U`` (N, nu) finite, ``model_n_init <= n_init < N`` and the first
    ``n_init`` rows of ``Y_init`` (at least that many rows, ny columns) finite; ``shape = (nu, ny)``."""
    U = _matrix("U", U, shape[0])
    _finite("U", U)
    n_init = check_n_init(n_init, model_n_init, U.shape[0])
    Y_init = _matrix("Y_init", Y_init, shape[1])
    if Y_init.shape[0] < n_init:
        raise ValueError(f"Y_init: need at least n_init = {n_init} rows, got {Y_init.shape[0]}")
    Y_init = Y_init[:n_init]
    _finite("Y_init", Y_init)
    return U, Y_init, n_init


def check_n_init(n_init, model_n_init: int, n_rows: int) -> int:
    """``n_init`` as an int with ``model_n_init <= n_init < n_rows`` (the rows of ``U``)."""
    if isinstance(n_init, bool) or not isinstance(n_init, (int, np.integer)):
        raise ValueError(f"n_init: expected an integer, got {n_init!r}")
    n_init = int(n_init)
    if not model_n_init <= n_init < n_rows:
        raise ValueError(f"n_init: expected {model_n_init} <= n_init < {n_rows} (the rows of U), got {n_init}")
    return n_init


def require_fitted(model, attribute: str):
    """Raise :class:`RuntimeError` unless ``fit`` has set ``attribute`` on ``model``."""
    if not hasattr(model, attribute):
        raise RuntimeError(f"{model.name}: not fitted; call fit() first")
