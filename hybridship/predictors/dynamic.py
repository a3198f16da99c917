"""The dynamic model alone as a forecaster (Skulstad et al. 2022, sec. 3.1)."""

from __future__ import annotations

from ..config import as_config
from ..forecast_inputs.wind import HELD_WIND, WindForecast
from ..physics.model import DynamicModel
from ..residual.features import ResidualConfig
from .forecast_setup import _check_flags, _check_row_stride, _forecast_setup, check_log_items
from .result import ForecastResult

__all__ = ["DynamicPredictor"]


class DynamicPredictor:
    """The dynamic model alone (Skulstad et al. sec. 3.1): wind held at its start value, commands
    held (``commands="held"``) or the logged future ones (``commands="known"``).

    ``wind_forecast`` replaces the held wind by a decaying gust
    (:class:`~hybridship.forecast_inputs.wind.WindForecast`), for example the one a hybrid
    fitted, to show what the wind forecast alone does to the physics.
    """

    name = "dynamic"

    def __init__(self, vessel="gunnerus", *, residual_config: ResidualConfig = ResidualConfig(),
                 stop_after_failure: bool = True, wind_forecast: WindForecast = HELD_WIND):
        if not isinstance(wind_forecast, WindForecast):
            raise TypeError(f"wind_forecast: expected a WindForecast, got {type(wind_forecast).__name__}")
        self.wind_forecast = wind_forecast
        self.model = DynamicModel(vessel)
        self.residual_config = as_config(residual_config, ResidualConfig, "residual_config")
        _check_flags(stop_after_failure=stop_after_failure)
        self.stop_after_failure = bool(stop_after_failure)

    def fit(self, logs=(), *, dp_only: bool = True, progress: bool = False, row_stride: int = 1):
        """The physics has nothing to learn from logs here; returns self (the logs and the
        learners' options, when given, are checked as a fitting predictor checks them:
        :func:`~.forecast_setup.check_log_items`)."""
        # the learners' options, checked as they check them (a text 'no' is refused, not read as True)
        _check_flags(dp_only=dp_only, progress=progress)
        _check_row_stride(row_stride)
        check_log_items(logs)
        return self

    def forecast(self, log, start_times_s, horizon_s: float = 60.0, *, commands: str = "held") -> ForecastResult:
        """Integrate the model from every start time (one batch).

        Parameters
        ----------
        log : path, DataFrame or LogArrays
        start_times_s : float or sequence of float
            Sample times of the log [s].
        horizon_s : float
            Forecast horizon [s], a whole number of the log's steps (the median spacing of its
            time stamps to the microsecond: lead times ``k * step`` read 0.1, 0.2, ..., 60.0 on
            a 10-Hz log), to within a quarter step or 0.5 % of itself, and taken as that whole
            number; one that rounds to no step, or lies further from a whole number of steps
            (60.4 s on a 1-Hz log), is refused (ValueError naming ``horizon_s``). On a
            log with jittered time stamps the forecast still runs whole median steps from the
            start, so its times are nominal and not the log's own.
        commands : {"held", "known"}
            ``held``: commands stay at their start values; ``known``: the logged commands
            of the steps after each start are used (a manoeuvre whose orders are known).
            Each step takes the command logged at its beginning, so the log must extend
            ``horizon_s`` less one step past every start (a RequestError otherwise).
        """
        st = _forecast_setup(self.model, self.residual_config, log, start_times_s, horizon_s,
                             self.stop_after_failure, commands, wind_forecast=self.wind_forecast)
        res = self.model.rollout(st.eta0, st.nu0, st.H, dt_s=st.dt, substeps=st.substeps, rpm=st.rpm,
                                 azimuth_rad=st.az, wind=st.wind)
        return ForecastResult(st.arrays.time_s[st.idx], st.lead_s, res.eta, res.nu, flags=st.flags, notes=st.notes)
