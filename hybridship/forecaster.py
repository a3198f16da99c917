"""The forecaster contract: what every forecaster of hybridship offers.

:class:`Forecaster` is a :class:`typing.Protocol` (checked at run time with ``isinstance``):
:class:`~hybridship.predictors.DeadReckoning`, :class:`~hybridship.predictors.DynamicPredictor`,
:class:`~hybridship.predictors.DataOnlyPredictor` and :class:`~hybridship.predictors.HybridPredictor`
follow it, and ``tests/test_forecaster_contract.py`` runs all four through the same checks.

The contract, beyond the signatures:

* ``fit(logs)`` learns from logs (paths, DataFrames or LogArrays, read through
  :func:`hybridship.logs.ingest.ingest`) and returns the forecaster itself; learned state is
  set by ``fit`` (or by loading a model file), never by ``forecast``.
* ``forecast(log, start_times_s, horizon_s, commands=)`` returns a
  :class:`~hybridship.predictors.ForecastResult` with one forecast per start time, all
  computed as one batch. A learning forecaster that was not fitted raises
  :class:`RuntimeError`; bad inputs raise :class:`ValueError` (or a subclass such as
  :class:`~hybridship.logs.io.LogFormatError`), or :class:`TypeError` for an argument of
  the wrong type (a horizon given as text, a list given as the log), whose message starts
  with the name of the field at fault.
* Causal: with ``commands="held"`` a forecast uses nothing logged after its start time.
* Deterministic: the same call on the same fitted forecaster gives the same numbers.

The high-speed-craft models (:mod:`hybridship.hsc`) predict surge and pitch from records
rather than ship motion from logs; their contract is
:class:`hybridship.hsc.contract.SurgePitchModel`, checked by the same test module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Iterable, Protocol, runtime_checkable

if TYPE_CHECKING:  # pragma: no cover
    from .predictors import ForecastResult

__all__ = ["Forecaster"]


@runtime_checkable
class Forecaster(Protocol):
    """Anything with ``name``, ``fit(logs) -> self`` and ``forecast(...) -> ForecastResult``.

    Attributes
    ----------
    name : str
        Short identifier used in result tables (``"hybrid"``, ``"dynamic"``, ...).
    """

    name: str

    def fit(self, logs: Iterable, **kwargs) -> "Forecaster":
        """Learn from ``logs`` (path, DataFrame or LogArrays each); returns self."""
        ...

    def forecast(self, log, start_times_s, horizon_s: float = 60.0, *,
                 commands: str = "held") -> "ForecastResult":
        """Forecast ``horizon_s`` seconds ahead from every start time of ``log`` (one batch).

        Parameters
        ----------
        log : path, DataFrame or LogArrays
        start_times_s : float or sequence of float
            Sample times of the log [s].
        horizon_s : float
            Forecast horizon [s]; the step is the log's.
        commands : {"held", "known"}
            Commands held at their start values, or the logged future ones.
        """
        ...
