"""The hybrid forecaster: the dynamic model plus a residual ensemble and the out-of-envelope guard.

The hybrid (Skulstad et al. 2022, sec. 3.2) steps the dynamic model one second, asks the
ensemble for the acceleration residual from the model-predicted velocities,
accelerations and the previous residual, adds it, and repeats. Beyond the paper, an
:class:`~hybridship.residual.guard.EnvelopeGuard` shrinks the correction where the
inputs leave the training envelope, and the ensemble's spread is propagated to a
position uncertainty.
"""

from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path
from typing import Iterable

import numpy as np

from ..config import as_config, check_number, check_whole_number, real_array
from ..forecast_inputs import FaultFlags
from ..forecast_inputs.limits import forecast_substeps
from ..forecast_inputs.wind import HELD_WIND, WindForecast, fit_wind_forecast, wind_error_paths
from ..frames import speed_dir_to_vector, vector_to_speed_dir, wrap_pi
from ..logs.io import LogArrays
from ..messages import warn_user
from ..physics.model import DynamicModel, check_step
from ..residual.calibration import MIN_CALIBRATION_SAMPLES, CalibrationConfig, fit_spread_scale
from ..residual.ensemble import EnsembleConfig, MLPEnsemble, fit_ensemble, require_training_rows
from ..residual.features import (ALL_FEATURES, LOAD_FEATURES, MEMORY_FEATURES, MEMORY_HISTORY_TIME_CONSTANTS,
                                 ResidualConfig, actuator_acceleration, command_feature_columns, command_memory,
                                 command_pair, command_scales, log_command_memory, prepare_log)
from ..residual.load_variability import held_load_rows, held_load_spread, unexplained_load_std_windows
from ..residual.environment import (EnvironmentConfig, EnvironmentEstimate, EnvironmentEstimator, current_input,
                                    environment_accel, thrust_error_accel, thrust_error_prior_carries_over)
from ..residual.multistep import MultiStepConfig, collect_starts, train_multistep
from ..residual.guard import CommandRegime, EnvelopeGuard, ThrustRegime
from ..residual.wave_direction import wave_axis, wave_yaw_choice, yaw_load_factor
from ..residual.drift_hull import (MIN_FAILURES as DRIFT_HULL_MIN_FAILURES, MUNK_MULTIPLES,
                                   START_EVERY_S as DRIFT_HULL_START_EVERY_S, choose_coefficient,
                                   drift_start_rows, munk_coefficient)
from ..residual.hull import HullCorrection
from .after_failure import drift_end, drift_forecasts, has_drift, shutdown_index
from .forecast_setup import (AFTER_STOP, AFTER_STOP_LATE, FORECAST_HISTORY_S, MAX_HORIZON_S, _check_flags,
                             _check_row_stride, _forecast_setup, as_log_arrays, horizon_steps, join_notes,
                             keeps_state_on_error, log_list, start_indices)
from .model_file import load_model, save_model
from .result import ForecastResult
from .training_logs import (NO_WIND_FORECAST_WARNING, check_calibration_horizon, check_distinct_logs,
                            check_training_lengths, log_label, read_training_logs, training_log_facts,
                            warn_logs_without_wind, warn_no_wind, warn_other_rate)

__all__ = ["AFTER_STOP", "AFTER_STOP_LATE", "ENVIRONMENT_SOURCES", "HybridPredictor"]

#: First column of the command-memory features in the full feature vector.
_MEMORY_COL = ALL_FEATURES.index(MEMORY_FEATURES[0])
#: First column of the actuator-load features (the last ones).
_LOAD_COL = ALL_FEATURES.index(LOAD_FEATURES[0])
#: Start times after each failure that calibrate the spread after a failure (the paper's 20).
AFTER_STOP_INTERVALS = 20
#: Spacing [s] of the later starts that calibrate :data:`AFTER_STOP_LATE`.
LATE_START_EVERY_S = 10.0
#: Fewest held-back starts (pooled over the logs) that calibrate the spread of a command mode.
MIN_CALIBRATION_STARTS = 10

#: Most wind futures in the spread (``wind_samples``): each costs one more rollout per forecast.
MAX_WIND_SAMPLES = 256
#: Spacing of the starts the wind forecast's error paths are measured from [s].
WIND_ERROR_START_EVERY_S = 2.0
#: Most forecasts rolled out at once when the hull's yaw moment in a drift is chosen (memory).
DRIFT_HULL_BATCH = 4096

#: Failures the training logs must hold before the thrust-error prior learned at their stops is
#: checked: the signed-rank test of its left-out gains cannot pass with fewer (as for the hull's
#: yaw moment in a drift).
THRUST_PRIOR_MIN_FAILURES = DRIFT_HULL_MIN_FAILURES

#: Where the hybrid's slowly varying environment comes from (see :class:`HybridPredictor`).
ENVIRONMENT_SOURCES = ("estimator", "mean")
#: Grid of log time [s] on which the environment filter of a forecast starts (the last grid
#: time at least ``environment_window_s`` before the start): fixed by the start time alone,
#: so a start's forecast does not depend on the other starts of a call; a start reads at most
#: this much more than the window.
FILTER_START_GRID_S = 300.0


class HybridPredictor:
    """Dynamic model + residual ensemble (+ out-of-envelope guard).

    Parameters
    ----------
    vessel : Vessel or str
        The vessel, or a packaged name / vessel file. Every ``*_config`` below takes an
        instance of its class or a dict of its fields (validated here, a misspelt key named).
    residual_config : ResidualConfig
        Features, derivative filter and start-state windows.
    ensemble_config : EnsembleConfig
        Ensemble size, training settings, seed.
    guard : bool
        Apply the out-of-envelope guard by default in :meth:`forecast`.
    guard_quantile : float
        Quantile of training Mahalanobis distances where shrinking starts.
    stop_after_failure : bool
        Take the thrusters as stopped (rpm 0) in a forecast that starts where station keeping
        is off (``dp_active == 0``: a power failure), instead of holding the logged rpm (the
        shaft is still running down, and holding that for a minute would push every forecast).
    environment : {"estimator", "mean"}
        The slowly varying part of the residual. ``"estimator"`` (default): the
        environment estimator (:mod:`hybridship.residual.environment`: current, load and
        thrust-model error, run causally over the log up to each start, including the drift
        samples after a failure); the forecast starts from its filtered state and the
        ensemble members draw the environment from its posterior. ``"mean"``: the causal
        ``bias_window_s`` mean residual of station keeping (the scheme before the estimator).
    environment_config : EnvironmentConfig
    environment_window_s : float
        The estimator's window ``W`` [s]: a start's filter starts at the last whole multiple of
        :data:`FILTER_START_GRID_S` (5 min) of log time at least ``W`` before it (it reads
        between ``W`` and ``W`` + 5 min of log, whatever the other starts of the batch); at least
        ``environment_config.held_load_window_s`` (so that every start's held-load window lies
        inside the filtered rows).
    nets_after_stop : bool
        Let the nets correct forecasts that start after a failure (``dp_active == 0``).
        Off by default: on drift, the nets did not improve on the environment estimator
        alone under any training protocol we measured, including training on logs with
        earlier failures (``benchmarks/drift_protocols.py``, see the drift results).
    calibration_config : CalibrationConfig
        How :meth:`fit` holds back the end of each training log and calibrates the
        spread on it (see :mod:`hybridship.residual.calibration`); ``fraction=0`` keeps
        the raw ensemble spread.
    training : {"one_step", "multi_step"}
        ``one_step``: the nets fit the one-step residual (Skulstad et al.);
        ``multi_step``: then they are fine-tuned on the error of the hybrid's own
        rollouts (:mod:`hybridship.residual.multistep`, commands known).
    multistep_config : MultiStepConfig
        Settings of the multi-step training.
    command_guard : bool
        Also fit a :class:`~hybridship.residual.guard.CommandRegime` on the held-back
        calibration rows (needs ``calibration_config.fraction > 0``) and apply it with the guard.
        The spread is then cross-fitted: each log's held-back rows are split in two in time
        order at the middle one of its calibration starts (:meth:`_calibration_split`), and
        the calibration forecasts starting in one part use weights fitted on the other
        (``training_info["calibration"]["cross_fit_rows"]`` records the parts); the model keeps
        the weights of all held-back rows.
    hull_correction : bool
        Before the nets, fit a linear-in-parameters, MMG-structured correction of the
        acceleration (:class:`~hybridship.residual.hull.HullCorrection`, ridge regression on
        the one-step residual); the nets learn what remains. It is part of the model, not
        shrunk by the guards (only switched off after a failure with the nets).
    hull_ridge : float
        Ridge penalty of that fit (per row, on standardised regressors).
    hull_fit : {"one_step", "multi_step"}
        How the hull correction is identified: ridge regression on the one-step residual,
        or a free-run fit alone (from zero, the multi-step loss, ``multistep_config``'s
        ``hull_iterations`` and ``hull_lr``) before the nets are fitted to what remains.
    wind_forecast : WindForecast or "fit"
        The wind over a forecast (:mod:`hybridship.forecast_inputs.wind`). ``"fit"``
        (default): :meth:`fit` chooses how fast the start's gust decays to the recent mean
        wind by how well that predicts the training logs' own wind over
        ``calibration_config.horizon_s`` (station keeping only with ``dp_only``); the
        held wind when nothing predicts better. A :class:`~hybridship.forecast_inputs.wind.WindForecast`
        is used as given (``HELD_WIND``: the paper's held wind). Stored in the model file;
        multi-step training and the spread calibration use the same wind forecast.
    wind_samples : int
        Wind futures whose effect enters the spread (0, the default: none; at most
        :data:`MAX_WIND_SAMPLES`). With ``N > 0``, :meth:`fit` draws ``N`` of the wind
        forecast's error paths on the training rows
        (:func:`~hybridship.forecast_inputs.wind.wind_error_paths`, the part held back for
        calibration excluded; the training logs must share one sample step), and every
        forecast is also rolled out ``N`` times, each with the forecast wind plus one of those
        paths (the same paths for every start). The root-mean-square deviation of those
        rollouts from the forecast, its sensitivity to the wind's unknown future, is added in
        quadrature to the members' spread before the calibration (which is fitted with it).
        The forecast itself (``eta``) stays the one at the forecast wind. The paths are
        stored in the model file. A start during station keeping with the held load's
        spread (``environment="estimator"``) reports that spread alone, without this term.
    drift_hull : bool
        Learn the hull's yaw moment in a drift from the training logs' failures (the
        default). With at least five failures in the training logs (``environment =
        "estimator"``), :meth:`fit` chooses one coefficient ``k`` [rad/m^2] by the heading
        error of forecasts along those drifts, and forecasts that start after a failure add
        the yaw acceleration ``k u v`` (the environment estimator, after the failure, too);
        it is kept only if it measurably lowers the error of failures left out of the choice
        (a one-sided signed-rank test at 5 %; :mod:`hybridship.residual.drift_hull`,
        ``training_info["drift_hull"]``). With fewer failures nothing changes. It also lets
        ``environment_config.wave_turned_yaw_load = "auto"`` (the default) choose from the
        failures whether the yaw load turns with the waves after a failure
        (:meth:`_choose_wave_yaw_load`). False: :meth:`fit` learns nothing about the drift
        from the failures (the paper's protocol, strictly), and ``"auto"`` holds the yaw load.
    """

    #: Training modes of the nets.
    TRAINING_MODES = ("one_step", "multi_step")

    name = "hybrid"

    def __init__(self, vessel="gunnerus", *, residual_config: ResidualConfig = ResidualConfig(),
                 ensemble_config: EnsembleConfig = EnsembleConfig(), guard: bool = True,
                 guard_quantile: float = 0.99, stop_after_failure: bool = True,
                 environment: str = "estimator", environment_config: EnvironmentConfig = EnvironmentConfig(),
                 environment_window_s: float = 1800.0, nets_after_stop: bool = False,
                 calibration_config: CalibrationConfig = CalibrationConfig(), training: str = "one_step",
                 multistep_config: MultiStepConfig = MultiStepConfig(), command_guard: bool = False,
                 hull_correction: bool = False, hull_ridge: float = 1e-3, hull_fit: str = "one_step",
                 wind_forecast: WindForecast | str = "fit", wind_samples: int = 0, drift_hull: bool = True):
        # settings objects (or dicts of their fields), validated here once
        residual_config = as_config(residual_config, ResidualConfig, "residual_config")
        ensemble_config = as_config(ensemble_config, EnsembleConfig, "ensemble_config")
        environment_config = as_config(environment_config, EnvironmentConfig, "environment_config")
        calibration_config = as_config(calibration_config, CalibrationConfig, "calibration_config")
        multistep_config = as_config(multistep_config, MultiStepConfig, "multistep_config")
        _check_flags(guard=guard, stop_after_failure=stop_after_failure, nets_after_stop=nets_after_stop,
                     command_guard=command_guard, hull_correction=hull_correction, drift_hull=drift_hull)
        if not (isinstance(wind_forecast, WindForecast) or wind_forecast == "fit"):
            raise ValueError(f"wind_forecast: expected a WindForecast or 'fit', got {wind_forecast!r}")
        #: as given: a WindForecast, or "fit" (chosen by :meth:`fit` on the training logs' wind)
        self.wind_forecast_option = wind_forecast
        #: the wind forecast the forecasts use (set by :meth:`fit` with "fit")
        self.wind_forecast: WindForecast = wind_forecast if isinstance(wind_forecast, WindForecast) else HELD_WIND
        if isinstance(wind_samples, bool) or not isinstance(wind_samples, (int, np.integer)) \
                or not 0 <= wind_samples <= MAX_WIND_SAMPLES:
            raise ValueError(f"wind_samples: expected a whole number from 0 to {MAX_WIND_SAMPLES}, got {wind_samples!r}")
        self.wind_samples = int(wind_samples)
        #: the wind forecast's error paths of the spread (wind_samples, L, 2) [m/s], north/east,
        #: set by :meth:`fit` with ``wind_samples > 0``; their step is ``wind_error_dt_s`` [s]
        self.wind_error_paths: np.ndarray | None = None
        self.wind_error_dt_s: float = 1.0
        self.drift_hull = bool(drift_hull)
        #: the hull's yaw acceleration per u v (over ground) in a drift [rad/m^2] (0: none), learned by
        #: :meth:`fit` from the training logs' failures (:mod:`hybridship.residual.drift_hull`)
        self.drift_yaw_uv_rad_per_m2: float = 0.0
        #: whether the environment estimator's process model uses it after a failure too (off
        #: only for model files of format 10, whose coefficient was chosen without it)
        self._drift_yaw_in_filter = True
        #: with ``environment_config.wave_turned_yaw_load == "auto"``: whether :meth:`fit` found that
        #: the training logs' failures gain from the yaw load turned with the waves
        #: (``training_info["wave_yaw_load"]``)
        self.wave_yaw_turned: bool = False
        if training not in self.TRAINING_MODES:
            raise ValueError(f"training: expected one of {self.TRAINING_MODES}, got {training!r}")
        self.training = training
        self.multistep_config = multistep_config
        self.command_guard = bool(command_guard)
        hull_ridge = check_number("hull_ridge", hull_ridge, lo=0.0)
        self.hull_correction = bool(hull_correction)
        self.hull_ridge = float(hull_ridge)
        if hull_fit not in self.TRAINING_MODES:
            raise ValueError(f"hull_fit: expected one of {self.TRAINING_MODES}, got {hull_fit!r}")
        self.hull_fit = hull_fit
        self.hull: HullCorrection | None = None
        self.command_regime: CommandRegime | None = None
        if environment not in ENVIRONMENT_SOURCES:
            raise ValueError(f"environment: expected one of {ENVIRONMENT_SOURCES}, got {environment!r}")
        environment_window_s = check_number("environment_window_s", environment_window_s, lo=0.0, lo_open=True)
        if environment == "estimator" and residual_config.start_residual_window_s > 0:
            # the estimator's state starts every forecast: its autoregressive input starts at zero
            raise ValueError(f"residual_config.start_residual_window_s: must be 0 with environment='estimator' "
                             f"(the estimator's state starts the forecasts; a recent residual mean applies only "
                             f"with environment='mean'), got {residual_config.start_residual_window_s:g}")
        if environment == "estimator" and environment_window_s < environment_config.held_load_window_s:
            # a shorter filter window could cut a start's held-load window at the filter's first row
            raise ValueError(f"environment_window_s: must be at least environment_config.held_load_window_s = "
                             f"{environment_config.held_load_window_s:g} s, got {environment_window_s:g}")
        self.environment = environment
        self.environment_config = environment_config
        self.environment_window_s = float(environment_window_s)
        self.nets_after_stop = bool(nets_after_stop)
        self.estimator: EnvironmentEstimator | None = None
        self.model = DynamicModel(vessel)
        self.stop_after_failure = bool(stop_after_failure)
        self.residual_config = residual_config
        self.ensemble_config = ensemble_config
        self.use_guard = bool(guard)
        if isinstance(guard_quantile, (bool, np.bool_)) or not isinstance(guard_quantile, (int, float, np.number)) \
                or not 0.5 <= float(guard_quantile) < 1.0:
            raise ValueError(f"guard_quantile: expected a number in [0.5, 1), got {guard_quantile!r}")
        self.guard_quantile = float(guard_quantile)
        self.ensemble: MLPEnsemble | None = None
        self.guard: EnvelopeGuard | None = None
        self.thrust_regime: ThrustRegime | None = None
        self.calibration_config = calibration_config
        #: command mode -> {"position": SpreadCalibration, "heading": SpreadCalibration}
        self.calibration: dict = {}
        self.training_info: dict = {}

    # ------------------------------------------------------------------ training

    def training_data(self, logs: Iterable, *, dp_only: bool = True, row_masks=None):
        """Features X, targets Y and a per-log segment label from the given logs (a path,
        DataFrame or LogArrays, or an iterable of them).

        The targets are the residual deviations from the environment the forecast will use:
        with ``environment="estimator"`` the acceleration that the (fitted) estimator's
        causal state explains at each row (:func:`~hybridship.residual.environment.environment_accel`),
        otherwise the ``bias_window_s`` mean residual. ``row_masks`` (one boolean array per
        log, or None) limits the rows that may be used (for example to leave out the part
        held back for calibration). With ``environment="estimator"`` it needs the fitted (or
        loaded) estimator: a RuntimeError before :meth:`fit`.
        """
        if self.environment == "estimator" and self.estimator is None:
            # the targets are taken from the estimator's environment (it was "'NoneType' object has no attribute 'run'")
            raise RuntimeError("HybridPredictor.training_data: with environment='estimator' the targets are the "
                               "fitted environment estimator's; call fit() or load() first")
        Xs, Ys, segs, thr, full = [], [], [], [], []
        for k, log in enumerate(log_list(logs)):        # one log (a path, a DataFrame) is a list of one
            prep, every = self._training_prep(log)
            arrays = prep.arrays
            mask = arrays.dp_active.astype(bool) if dp_only else None
            if row_masks is not None and row_masks[k] is not None:
                mask = row_masks[k][::every] if mask is None else (mask & row_masks[k][::every])
            rows = prep.trainable_rows(mask)
            if rows.size == 0:
                continue
            full.append(prep.full_features(rows))
            Xs.append(full[-1][:, self.residual_config.feature_index])
            Ys.append(prep.deviation(rows))
            segs.append(arrays.segment_id[rows] + 10_000 * k)
            thr.append(prep.thrust_acc[rows])
        if not Xs:
            raise ValueError("fit: no usable training rows in the logs (need dp_active == 1 samples "
                             "in gap-free segments longer than the derivative window)")
        self._training_thrust_acc = np.concatenate(thr)
        self._training_full = np.concatenate(full)
        return np.concatenate(Xs), np.concatenate(Ys), np.concatenate(segs)

    def _training_prep(self, log):
        """A training log prepared as the nets learn from it: ``(prep, every)``, the rows every
        ``every``-th (:meth:`ResidualConfig.thinning`) and, with ``environment="estimator"``,
        the estimator's environment as the one the deviations are taken from."""
        full_rate = as_log_arrays(log, self.model.vessel)
        every = self.residual_config.thinning(full_rate.dt_s)      # a fast log: its rows about 1 s apart
        arrays = full_rate.rows(slice(None, None, every)) if every > 1 else full_rate
        prep = prepare_log(self.model, arrays, self.residual_config)
        if self.environment == "estimator":         # the estimator runs at the log's rate, as forecasts run it
            est = self.estimator.run(full_rate)
            # at the velocities each residual is taken at (smoothed with deriv_window_s), thinned or not
            nu = np.array(full_rate.nu, dtype=float)
            nu[::every] = prep.nu_s
            prep.env_body = environment_accel(self.model, full_rate, est, nu)[::every]
        return prep, every

    @keeps_state_on_error
    def fit(self, logs: Iterable, *, dp_only: bool = True, progress: bool = False,
            row_stride: int = 1, calibration: CalibrationConfig | None = None) -> "HybridPredictor":
        """Learn the acceleration residual from logs (by default only their DP part), then
        calibrate the spread on the held-back end of each log.

        Parameters
        ----------
        logs : path, DataFrame or LogArrays, or an iterable of them
        dp_only : bool
            Train only on rows with ``dp_active == 1`` (the part before a failure).
        progress : bool
            Show a progress bar.
        row_stride : int
            Train on every ``row_stride``-th trainable row (for high-rate logs, whose
            neighbouring rows carry almost the same information); the guard is fitted on
            the same rows.
        calibration : CalibrationConfig, optional
            Overrides the ``calibration_config`` given at construction (for example
            ``CalibrationConfig(commands=("known",))`` for a manoeuvring model, or
            ``fraction=0`` for none) and becomes the model's ``calibration_config``, so that
            forecasts (and the model file) use the spread it was calibrated on.

        Raises
        ------
        ValueError
            A log that breaks the format or does not fit the vessel, or two logs with
            identical samples (one recording twice, e.g. a CSV and a Parquet copy; see
            :func:`~hybridship.predictors.training_logs.check_distinct_logs`), before any training.
        HorizonError
            A ``calibration.horizon_s`` that is not a whole number of a training log's steps
            (:func:`~hybridship.predictors.training_logs.check_calibration_horizon`), before any
            training.

        Notes
        -----
        With ``calibration.fraction > 0`` the last part (in time order) of each log's usable
        rows is not trained on; forecasts from start times in it, made in each of the
        ``calibration.commands`` modes over ``calibration.horizon_s``, give the per-lead
        scale of the spread (:func:`hybridship.residual.calibration.fit_spread_scale`,
        north and east pooled for the position, the heading on its own). Every later
        forecast's ``eta_std`` is calibrated with it. With ``command_guard`` the held-back rows
        also choose the command-regime weights, and each calibration forecast uses weights
        chosen on the part of them it does not lie in (:meth:`_fit_command_guard`). With ``dp_only`` the nets
        never see a failure, so a forecast that starts after one keeps the raw spread, unless the
        training logs hold at least ``calibration.after_stop_min_failures`` failures with
        enough drift after them: then the spread after a failure is calibrated on those
        (:meth:`calibrate_after_stop`; ``training_info["calibration"]["after_stop"]``).
        Without ``dp_only`` the environment estimator also learns the thrust-model error at
        the logs' thrust stops (:meth:`EnvironmentEstimator.fit`), kept only where it carries
        over to failures left out of the learning (:meth:`_check_thrust_error_prior`,
        ``training_info["thrust_error_prior"]``). With ``wave_turned_yaw_load = "auto"`` the failures
        choose whether the yaw load turns with the waves (:meth:`_choose_wave_yaw_load`).
        """
        stride = _check_row_stride(row_stride)
        _check_flags(dp_only=dp_only, progress=progress)
        cal = self.calibration_config if calibration is None else \
            as_config(calibration, CalibrationConfig, "calibration")
        self.calibration_config = cal
        given = log_list(logs)
        logs, labels = read_training_logs(given, self.model.vessel)
        check_training_lengths(logs, labels)
        check_calibration_horizon(logs, labels, cal.horizon_s)
        check_distinct_logs(logs, labels)  # before any training
        warn_logs_without_wind(logs, labels)
        self.estimator = EnvironmentEstimator(self.model, self.environment_config)
        if self.environment == "estimator":
            self.estimator.fit(logs, dp_only=dp_only)
        cuts, masks = self._held_back(logs, cal, dp_only)
        wind_info = self._fit_wind_forecast(logs, cuts, cal, dp_only)
        wind_spread_info = self._fit_wind_error_paths(logs, cuts, cal, dp_only)
        prior_info = self._check_thrust_error_prior(logs, cal.horizon_s)
        self._fit_nets(logs, dp_only=dp_only, progress=progress, stride=stride, row_masks=masks)
        folds, split_info = self._fit_command_guard(logs, cuts, masks, cal, dp_only, stride)
        wave_yaw_info = self._choose_wave_yaw_load(logs, cal.horizon_s)      # before the hull: it forecasts with it
        drift_hull_info = self._fit_drift_hull(logs, cal.horizon_s)
        self.calibration = {}
        cal_info = {"fraction": cal.fraction, "commands": list(cal.commands), "horizon_s": cal.horizon_s,
                    "refit": cal.refit, "n_starts": {}, "dp_only": bool(dp_only), **split_info}
        with warnings.catch_warnings():
            # said once per training log above, not by each calibration forecast on it
            warnings.filterwarnings("ignore", message=NO_WIND_FORECAST_WARNING)
            if cal.fraction > 0:
                cal_info["n_starts"] = self._calibrate_modes(logs, folds, cal, dp_only)
                if cal.refit:
                    self._fit_nets(logs, dp_only=dp_only, progress=progress, stride=stride, row_masks=None)
        self.training_info["calibration"] = cal_info
        if wind_info is not None:
            self.training_info["wind_forecast"] = wind_info
        if wind_spread_info is not None:
            self.training_info["wind_spread"] = wind_spread_info
        if drift_hull_info is not None:
            self.training_info["drift_hull"] = drift_hull_info
        if wave_yaw_info is not None:
            self.training_info["wave_yaw_load"] = wave_yaw_info
        if prior_info is not None:
            self.training_info["thrust_error_prior"] = prior_info
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=NO_WIND_FORECAST_WARNING)
            self._calibrate_after_stop_on_training_logs(logs, cal)
        return self

    def _choose_wave_yaw_load(self, logs, horizon_s: float):
        """Where :attr:`chooses_wave_yaw_load` (``"auto"`` with :attr:`uses_drift_hull`) and at least
        :data:`~hybridship.residual.drift_hull.MIN_FAILURES` failures in the training logs: turn
        the yaw load with the waves after a failure (:attr:`wave_yaw_turned`) only where it
        carries over, by the rule of what else ``fit`` learns from failures
        (:func:`~hybridship.residual.drift_hull.gain_carries_over`): the failures' mean heading
        error of the estimator's forecasts along their drifts (:meth:`_drift_errors`, starts
        every :data:`~hybridship.residual.drift_hull.START_EVERY_S`) must be lower turned than
        held and the per-failure gains must pass the one-sided signed-rank test. Nothing is
        fitted to them, so no failure is left out. Returns what ``training_info["wave_yaw_load"]``
        records (None when not ``"auto"``)."""
        self.wave_yaw_turned = False
        if not self.chooses_wave_yaw_load:
            return None
        failed = [logs[k] for k in logs_with_drift(logs, horizon_s)]
        errors = self.wave_yaw_errors(failed, horizon_s) if len(failed) >= DRIFT_HULL_MIN_FAILURES \
            else np.empty((2, len(failed)))
        info = wave_yaw_choice(errors)
        self.wave_yaw_turned = info["turned"]
        return {**info, "horizon_s": float(horizon_s), "start_every_s": DRIFT_HULL_START_EVERY_S}

    def wave_yaw_errors(self, logs, horizon_s: float = 60.0) -> np.ndarray:
        """Per failure, the mean heading error [rad] (2, L) of the estimator's forecasts along
        its drift (:meth:`_drift_errors`) with the yaw load held (row 0) and turned with the
        waves (row 1): what :func:`~hybridship.residual.wave_direction.wave_yaw_choice` decides
        on.

        Parameters
        ----------
        logs : path, DataFrame or LogArrays, or an iterable of them
            Logs with a failure followed by ``horizon_s`` of drift in one gap-free segment
            (at least one; a log without is refused, named).
        horizon_s : float
            Length of each forecast [s], a whole number of each log's steps.
        """
        self._check_fitted()
        horizon_s = check_number("horizon_s", horizon_s, lo=0.0, hi=MAX_HORIZON_S, lo_open=True)
        given = log_list(logs)              # one log (a path, a DataFrame) is a list of one; none is refused
        return np.array([[self._drift_errors(log, horizon_s, turned, log_label(log, k) if len(given) > 1 else "log")[1]
                          for k, log in enumerate(given)] for turned in (False, True)])

    def _fit_drift_hull(self, logs, horizon_s: float):
        """With ``drift_hull`` and at least :data:`~hybridship.residual.drift_hull.MIN_FAILURES`
        failures in the training logs: the hull's yaw
        coefficient in a drift (:func:`~hybridship.residual.drift_hull.choose_coefficient` on
        :meth:`drift_hull_objective`). Returns what ``training_info["drift_hull"]`` records
        (None when nothing was chosen)."""
        self.drift_yaw_uv_rad_per_m2 = 0.0
        self._drift_yaw_in_filter = True        # a refit of a format-10 model chooses as it now forecasts
        if not self.uses_drift_hull:
            return None
        failed = [logs[k] for k in logs_with_drift(logs, horizon_s)]
        if len(failed) < DRIFT_HULL_MIN_FAILURES:
            return None
        choice = choose_coefficient(self.drift_hull_objective(failed, horizon_s), munk_coefficient(self.model))
        self.drift_yaw_uv_rad_per_m2 = choice.coefficient_rad_per_m2
        return {**choice.as_dict(), "horizon_s": float(horizon_s), "start_every_s": DRIFT_HULL_START_EVERY_S}

    def drift_hull_objective(self, logs, horizon_s: float = 60.0) -> np.ndarray:
        """The failures' heading errors with every candidate coefficient of the hull's yaw moment
        in a drift (:mod:`hybridship.residual.drift_hull`).

        Parameters
        ----------
        logs : path, DataFrame or LogArrays, or an iterable of them
            Logs with a failure followed by ``horizon_s`` of drift in one gap-free segment
            (at least one).
        horizon_s : float
            Length of each forecast [s], a whole number of each log's steps (within the
            forecast's tolerance; :class:`~hybridship.predictors.forecast_setup.HorizonError`
            otherwise, as a forecast refuses it).

        Returns
        -------
        ndarray, shape (K, L)
            Mean absolute heading error [rad], over every lead and over starts every
            :data:`~hybridship.residual.drift_hull.START_EVERY_S` along the log's first drift
            (:func:`~hybridship.residual.drift_hull.drift_start_rows`), of forecasts with each
            of the K candidates :data:`~hybridship.residual.drift_hull.MUNK_MULTIPLES` times
            the model's Munk coefficient, each from the environment estimator run with that
            candidate (as the forecasts would run it). The starts and candidates of a log are
            rolled out in batches of at most :data:`DRIFT_HULL_BATCH` forecasts.
        """
        self._check_fitted()
        horizon_s = check_number("horizon_s", horizon_s, lo=0.0, hi=MAX_HORIZON_S, lo_open=True)
        ks = MUNK_MULTIPLES * munk_coefficient(self.model)
        out = np.empty((ks.size, 0))
        given = log_list(logs)              # one log (a path, a DataFrame) is a list of one; none is refused
        for k, log in enumerate(given):
            st, truth = self._drift_starts(log, horizon_s, log_label(log, k) if len(given) > 1 else "log")
            truth = truth[..., 2]                                                        # (S, H)
            per_batch = max(1, DRIFT_HULL_BATCH // len(st.idx))
            with self.estimator.sharing_station_keeping():     # filtered once for all candidates
                errors = [self._drift_heading_errors(st, ks[i:i + per_batch], truth)
                          for i in range(0, ks.size, per_batch)]
            out = np.column_stack([out, np.concatenate(errors)])
        return out

    def _drift_starts(self, log, horizon_s: float, label: str = "log"):
        """Forecast setup of the starts every :data:`~hybridship.residual.drift_hull.START_EVERY_S`
        along a log's first drift (:func:`~hybridship.residual.drift_hull.drift_start_rows`), and
        the logged ``eta`` (S, H, 3) at every lead after them (``label`` names the log in the
        refusal of one without such a drift)."""
        a = as_log_arrays(log, self.model.vessel)
        H = horizon_steps(horizon_s, a.dt_s)
        rows = drift_start_rows(a.dp_active, a.segment_id, H, max(1, int(round(DRIFT_HULL_START_EVERY_S / a.dt_s))))
        if rows.size == 0:
            # "logs: a log without ..." did not say which of the logs
            raise ValueError(f"{label}: no failure followed by {horizon_s:g} s of drift in one gap-free segment")
        st = _forecast_setup(self.model, self.residual_config, a, a.time_s[rows], H * a.dt_s,
                             self.stop_after_failure, "held", history_s=self.history_s,
                             wind_forecast=self.wind_forecast)
        return st, a.eta[rows[:, None] + np.arange(1, st.H + 1)[None, :]]

    def _check_thrust_error_prior(self, logs, horizon_s: float):
        """Keep the thrust-model error that :meth:`EnvironmentEstimator.fit` learned at the
        training logs' thrust stops only where it carries over: with one failure left out at
        a time, the prior learned at the other logs' stops must lower both the mean position
        and the mean heading error of the left-out failure's forecasts (starts every
        :data:`~hybridship.residual.drift_hull.START_EVERY_S` along its drift, ``horizon_s``
        ahead, physics and estimator as after any failure, without the nets or the hull's yaw
        moment in a drift) against the configured prior
        (:func:`~hybridship.residual.environment.thrust_error_prior_carries_over`: both means
        lower and the per-failure gains through a signed-rank test). With fewer than
        :data:`THRUST_PRIOR_MIN_FAILURES` such failures nothing can be checked and the
        configured prior is restored. Returns what ``training_info["thrust_error_prior"]``
        records (None when no stop was read: ``dp_only``, or no stop with enough drift
        after it)."""
        configured = EnvironmentEstimator(self.model, self.environment_config)
        learned = self.estimator
        if (np.array_equal(learned.thrust_error_mean, configured.thrust_error_mean)
                and np.array_equal(learned.thrust_error_std, configured.thrust_error_std)):
            return None
        failed = logs_with_drift(logs, horizon_s)
        info = {"learned_mean": learned.thrust_error_mean.tolist(), "learned_std": learned.thrust_error_std.tolist(),
                "n_failures": len(failed), "horizon_s": float(horizon_s), "kept": False}
        if len(failed) >= THRUST_PRIOR_MIN_FAILURES:
            errors = np.empty((2, len(failed), 2))
            for j, k in enumerate(failed):
                others = EnvironmentEstimator(self.model, self.environment_config).fit(
                    [a for i, a in enumerate(logs) if i != k])
                for m, estimator in enumerate((configured, others)):
                    self.estimator = estimator
                    # "auto" is chosen later, on the prior kept here: held until then
                    errors[m, j] = self._drift_errors(logs[k], horizon_s,
                                                      self.environment_config.wave_turned_yaw_load is True)
            kept, (p_position, p_heading) = thrust_error_prior_carries_over(errors[0], errors[1])
            info.update(position_error_m=errors[:, :, 0].mean(axis=1).tolist(),
                        heading_error_deg=np.degrees(errors[:, :, 1].mean(axis=1)).tolist(),
                        position_p_value=p_position, heading_p_value=p_heading, kept=kept)
        self.estimator = learned if info["kept"] else configured
        return info

    def _drift_errors(self, log, horizon_s: float, turned: bool | None = None, label: str = "log") -> np.ndarray:
        """Mean position error [m] and heading error [rad] of the forecasts along a log's drift
        (:meth:`_drift_starts`, ``label`` naming the log in its refusal) with the estimator
        alone: no nets (as after a failure by default) and no hull's yaw moment in a drift; the
        yaw load turned with the waves as the forecasts turn it, or as ``turned`` says when given."""
        st, truth = self._drift_starts(log, horizon_s, label)
        eta0, nu0, dev0, bias0, current, acc_ext, _ = self._estimated_start(st, 1, drift_yaw_uv=0.0)
        eta, _, _, _ = self.rollout(eta0, nu0, dev0, bias0, st.rpm, st.az, st.wind, st.H, st.dt, guard=False,
                                    substeps=st.substeps, current=current, accel_ext=acc_ext, nets=False,
                                    wave_axis=self._wave_axes(st, turned))
        d = eta[:, 1:] - truth
        return np.array([np.hypot(d[..., 0], d[..., 1]).mean(), np.abs(wrap_pi(d[..., 2])).mean()])

    def _drift_heading_errors(self, st, ks, truth) -> np.ndarray:
        """Mean absolute heading error [rad] (K,) of the starts of ``st`` with each coefficient
        ``ks`` (K,), against ``truth`` (S, H) [rad]. Each coefficient has its own filter run
        (the filter uses it after the failure as the forecasts do); the K x S forecasts are
        rolled out together."""
        K, S = ks.size, truth.shape[0]
        per_k = [self._estimated_start(st, self.ensemble.n_members, drift_yaw_uv=k)[:6] for k in ks]
        # block after block, as _tile_starts: starts along axis 0, the members' loads (E, S, 3) along 1
        eta0, nu0, dev0, bias0, current, acc_ext = (
            None if z[0] is None else np.concatenate(z, axis=1 if i == 3 else 0) for i, z in enumerate(zip(*per_k)))
        weight = self._after_stop_weight(st, None)
        eta, _, _, _ = self.rollout(
            eta0, nu0, dev0, bias0, _tile_starts(st.rpm, K), _tile_starts(st.az, K), _tile_starts(st.wind, K), st.H,
            st.dt, substeps=st.substeps, current=current, accel_ext=acc_ext, nets_weight=_tile_starts(weight, K),
            guard=self.use_guard, drift_yaw_uv=np.repeat(ks, S),
            command_memory=_tile_starts(self._command_memory(st), K), wave_axis=_tile_starts(self._wave_axes(st), K))
        return np.abs(wrap_pi(eta[:, 1:, 2].reshape(K, S, st.H) - truth[None])).mean(axis=(1, 2))

    def _fit_wind_forecast(self, logs, cuts, cal: CalibrationConfig, dp_only: bool):
        """With ``wind_forecast="fit"``: the wind forecast that best predicts the training
        logs' own wind over ``cal.horizon_s`` (:func:`~hybridship.forecast_inputs.wind.fit_wind_forecast`),
        from the rows before each log's calibration cut and, with ``dp_only``, in station
        keeping (the nets' own rows). Returns what ``training_info["wind_forecast"]`` records."""
        if self.wind_forecast_option != "fit":
            return None
        self.wind_forecast, scores = fit_wind_forecast(logs, cal.horizon_s, masks=_training_masks(logs, cuts, dp_only))
        held = [v for k, v in scores.items() if k != "n_starts" and k[1] is None]
        wf = self.wind_forecast
        return {"held": wf.held, "mean_window_s": None if wf.held else wf.mean_window_s,
                "time_constant_s": wf.time_constant_s,
                "error_m_s": None if wf.held else scores[(wf.mean_window_s, wf.time_constant_s)],
                "held_error_m_s": min(held) if held else None, "n_starts": scores["n_starts"],
                "horizon_s": cal.horizon_s}

    def _fit_nets(self, logs, *, dp_only, progress, stride, row_masks):
        X, Y, seg = self.training_data(logs, dp_only=dp_only, row_masks=row_masks)
        X, Y, seg, thr = X[::stride], Y[::stride], seg[::stride], self._training_thrust_acc[::stride]
        require_training_rows(X.shape[0], len(logs), dp_only, held_back=row_masks is not None and any(
            m is not None for m in row_masks))
        if np.all(X.std(0) <= 1e-12):       # nothing to learn from, and the guard's covariance is singular
            raise ValueError(f"features: every feature of {list(self.residual_config.features)} is constant over "
                             f"the {X.shape[0]} training rows; choose features that vary in the logs (the "
                             f"paper's nine, the default)")
        residual_std = Y.std(0).tolist()
        self.hull = None
        starts = None
        if self.hull_correction:
            full = self._training_full[::stride]
            self.hull = HullCorrection.fit(full, Y, self.model.vessel.particulars.L_pp_m, self.hull_ridge)
            if self.hull_fit == "multi_step":
                starts = self._multistep_starts(logs, row_masks, dp_only)
                ms = self.multistep_config
                _, hist = train_multistep(None, self.model, starts, self.residual_config.feature_index,
                                          replace(ms, iterations=ms.hull_iterations, lr=ms.hull_lr),
                                          substeps=forecast_substeps(starts.dt_s), seed=self.ensemble_config.seed,
                                          progress=progress, hull=self.hull.zeroed())
                self.hull = hist["hull"]
                hull_info = {k: hist[k] for k in ("iterations", "val_loss", "best_val_loss")}
            Y = Y - self.hull.predict(full)
        self.ensemble = fit_ensemble(X, Y, self.ensemble_config, segment_id=seg, progress=progress)
        self.guard = EnvelopeGuard.fit((X - self.ensemble.x_mean) / self.ensemble.x_std,
                                       quantile=self.guard_quantile)
        self.thrust_regime = ThrustRegime.fit(thr)
        self.training_info = {"n_rows": int(X.shape[0]), "row_stride": stride,
                              **training_log_facts(logs),
                              "epochs": self.ensemble.history["epochs"],
                              "best_val_mse": self.ensemble.history["best_val_mse"],
                              "residual_std": residual_std, "training": self.training}
        if self.hull is not None:
            self.training_info["hull_residual_std"] = Y.std(0).tolist()
            if self.hull_fit == "multi_step":
                self.training_info["hull_multi_step"] = hull_info
        if self.training == "multi_step":
            starts = starts if starts is not None else self._multistep_starts(logs, row_masks, dp_only)
            self.ensemble, hist = train_multistep(self.ensemble, self.model, starts,
                                                  self.residual_config.feature_index, self.multistep_config,
                                                  substeps=forecast_substeps(starts.dt_s),
                                                  seed=self.ensemble_config.seed, progress=progress, hull=self.hull)
            self.hull = hist.pop("hull", self.hull)
            self.training_info["multi_step"] = {k: hist[k] for k in ("iterations", "n_starts", "n_val_starts",
                                                                     "val_loss", "best_val_loss")}

    def _multistep_starts(self, logs, row_masks, dp_only):
        preps = [prepare_log(self.model, a, self.residual_config) for a in logs]
        return collect_starts(preps, row_masks if row_masks is not None else [None] * len(logs),
                              self.multistep_config, dp_only=dp_only, wind_forecast=self.wind_forecast)

    def _regime_inputs(self, prep, rows):
        """(rpm / max rpm, model-predicted u [m/s], first rotatable angle [rad]) of rows predicted from row - 1."""
        sc = command_scales(self.model, self.model.vessel.rotatable)
        a = prep.arrays
        ang = a.azimuth_rad[rows - 1, sc["angle_channel"]] if sc["angle_channel"] is not None else np.zeros(rows.size)
        return a.rpm[rows - 1, 0] / sc["rpm_scale"], prep.nu_hat[rows, 0], ang

    def _fit_command_guard(self, logs, cuts, masks, cal: CalibrationConfig, dp_only: bool, stride: int):
        """With ``command_guard`` (and a held-back part): fit the command-regime weights on all
        held-back rows (``self.command_regime``) and cross-fit the spread's calibration: each
        log's held-back rows are split in two in time order (:meth:`_calibration_split`),
        weights are fitted on each part alone, and the calibration forecasts starting in one
        part (with their horizons) use the weights of the other, so that the spread is
        calibrated on rows that chose none of the weights in its forecasts.

        Returns
        -------
        folds : list of (CommandRegime or None, list of ndarray)
            The calibration's folds (:meth:`_calibrate`): the weights its forecasts use and,
            per log, its start rows; one fold of ``self.command_regime`` and every held-back
            start without the split.
        info : dict
            What ``training_info["calibration"]`` records of the split (empty without the guard):
            per log, the half-open row ranges ``[first, end)`` of the two parts (with
            ``dp_only``, their station-keeping rows).
        """
        self.command_regime = None
        if not (self.command_guard and cal.fraction > 0):
            return self._calibration_folds(logs, cuts, cal, dp_only), {}
        splits = self._calibration_splits(logs, cuts, cal, dp_only)
        if splits is None:
            self.command_regime = self._fit_command_regime(logs, masks, dp_only, stride)
            return self._calibration_folds(logs, cuts, cal, dp_only), {"command_regime_split": False}
        early = self._fit_command_regime(logs, masks, dp_only, stride, ranges=[(0, s) for s in splits])
        late = self._fit_command_regime(logs, masks, dp_only, stride,
                                        ranges=[(s, len(a)) for a, s in zip(logs, splits)])
        self.command_regime = self._fit_command_regime(logs, masks, dp_only, stride)
        if early is None or late is None:
            # a part without a trainable row would calibrate its fold without any weights
            warn_user("fit: one part of the held-back rows has no row the command-regime weights can be "
                      "fitted on, so the spread cannot be cross-fitted; the weights and the spread share "
                      "the held-back rows (hold back more with calibration_config.fraction)",
                      UserWarning)
            return self._calibration_folds(logs, cuts, cal, dp_only), {"command_regime_split": False}
        starts = [self._calibration_start_rows(a, c, cal, dp_only) for a, c in zip(logs, cuts)]
        folds = [(early, [r[r >= s] for r, s in zip(starts, splits)]),
                 (late, [r[r + self._horizon_rows(a, cal) < s] for a, r, s in zip(logs, starts, splits)])]
        return folds, {"command_regime_split": True,
                       "cross_fit_rows": [[[int(c), int(s)], [int(s), len(a)]] for a, c, s in zip(logs, cuts, splits)]}

    def _calibration_folds(self, logs, cuts, cal: CalibrationConfig, dp_only: bool) -> list:
        """One calibration fold: the model's own weights and every held-back start from ``cuts``."""
        return [(self.command_regime, [self._calibration_start_rows(a, c, cal, dp_only) for a, c in zip(logs, cuts)])]

    def _calibration_splits(self, logs, cuts, cal: CalibrationConfig, dp_only: bool) -> list[int] | None:
        """Per log, the row where the command guard splits the held-back rows from ``cuts`` on
        (:meth:`_calibration_split`); None, with a warning, when the later halves of the logs'
        calibration starts would hold fewer than :data:`MIN_CALIBRATION_STARTS` together (the
        spread would go uncalibrated): the weights and the spread then share the held-back rows."""
        starts = [self._calibration_start_rows(a, c, cal, dp_only) for a, c in zip(logs, cuts)]
        if sum(r.size - r.size // 2 for r in starts) >= MIN_CALIBRATION_STARTS:
            return [self._calibration_split(a, r) for a, r in zip(logs, starts)]
        warn_user(f"fit: the held-back rows give {sum(r.size for r in starts)} calibration starts, too few to "
                  f"cross-fit the spread against the command-regime weights (the later half must hold "
                  f"{MIN_CALIBRATION_STARTS}): the weights and the spread share them; hold back more "
                  f"(calibration_config.fraction) for a spread calibrated on rows that chose none of its weights",
                  UserWarning)
        return None

    def _calibration_start_rows(self, a: LogArrays, cut: int, cal: CalibrationConfig, dp_only: bool) -> np.ndarray:
        """The rows from ``cut`` on where a calibration forecast of ``cal.horizon_s`` can start
        (:meth:`_calibration_starts` at the log's median step), before any thinning."""
        if cut >= len(a):
            return np.zeros(0, int)
        return self._calibration_starts(a, cut, self._horizon_rows(a, cal), dp_only)

    @staticmethod
    def _horizon_rows(a: LogArrays, cal: CalibrationConfig) -> int:
        """Rows in the calibration horizon ``cal.horizon_s`` at log ``a``'s median step (0 for one row)."""
        return int(round(cal.horizon_s / float(np.median(np.diff(a.time_s))))) if len(a) > 1 else 0

    @staticmethod
    def _calibration_split(a: LogArrays, starts: np.ndarray) -> int:
        """Where the command guard splits log ``a``'s held-back rows: at the middle one of its
        calibration start rows ``starts`` (:meth:`_calibration_start_rows`). The later half of
        its starts is calibrated with the weights of the rows before the split, the earlier
        starts whose horizons end before it with the weights of the rows after it
        (:meth:`_fit_command_guard`). Halving the starts rather than the rows keeps the short
        logs in the calibration: a held-back part shorter than two horizons would leave none
        of its starts after the middle row (its earlier part, shorter than a horizon, then
        calibrates nothing). ``len(a)`` when the log has no start (its held-back rows then
        all go to the earlier part)."""
        return int(starts[starts.size // 2]) if starts.size else len(a)

    def _fit_command_regime(self, logs, masks, dp_only, stride, ranges=None) -> CommandRegime | None:
        """Command-regime weights from the held-back rows in ``ranges`` (per log, a half-open
        row range ``(first, end)``; None: all held-back rows), see :class:`CommandRegime`; their
        targets and features are those the nets were trained on (:meth:`_training_prep`)."""
        tr_in, he_in, T, Pm = [], [], [], []
        for k, (log, m) in enumerate(zip(logs, masks)):
            prep, every = self._training_prep(log)
            a = prep.arrays
            held = None if m is None else ~np.asarray(m, dtype=bool)
            if held is not None and ranges is not None:
                held &= (np.arange(held.size) >= ranges[k][0]) & (np.arange(held.size) < ranges[k][1])
            m = None if m is None else np.asarray(m, dtype=bool)[::every]
            dp = a.dp_active.astype(bool) if dp_only else np.ones(len(a), bool)
            held = dp & held[::every] if held is not None else np.zeros(len(a), bool)
            rows_t = prep.trainable_rows(dp & m if m is not None else dp)[::stride]
            rows_h = prep.trainable_rows(held)
            if rows_t.size:
                tr_in.append(self._regime_inputs(prep, rows_t))
            if rows_h.size:
                he_in.append(self._regime_inputs(prep, rows_h))
                dev = prep.deviation(rows_h)
                if self.hull is not None:
                    dev = dev - self.hull.predict(prep.full_features(rows_h))
                T.append(dev / self.ensemble.y_std)
                Pm.append(self.ensemble.predict(prep.features(rows_h))[0] / self.ensemble.y_std)
        if not tr_in or not he_in:
            return None
        cat = lambda parts: tuple(np.concatenate([p[k] for p in parts]) for k in range(3))  # noqa: E731
        return CommandRegime.fit(cat(tr_in), cat(he_in), np.concatenate(T), np.concatenate(Pm),
                                 length_m=self.model.vessel.particulars.L_pp_m)

    def _fit_wind_error_paths(self, logs, cuts, cal: CalibrationConfig, dp_only: bool):
        """With ``wind_samples = N > 0``: ``N`` error paths of the wind forecast over
        ``cal.horizon_s``, drawn at random (the ensemble's seed) from those of the training rows
        (before each log's calibration cut; station keeping only with ``dp_only``).

        Returns
        -------
        dict or None
            What ``training_info["wind_spread"]`` records (None with ``wind_samples = 0``).
        """
        self.wind_error_paths = None
        if not self.wind_samples:
            return None
        steps = {round(float(np.median(np.diff(a.time_s))), 9) for a in logs if len(a) > 1}
        if len(steps) != 1:
            raise ValueError(f"wind_samples: the training logs have different sample steps {sorted(steps)} s; "
                             f"resample them to one step or use wind_samples=0")
        dt = steps.pop()
        paths = wind_error_paths(self.wind_forecast, logs, max(2, int(round(cal.horizon_s / dt))),
                                 every=max(1, int(round(WIND_ERROR_START_EVERY_S / dt))),
                                 masks=_training_masks(logs, cuts, dp_only))
        if len(paths) < self.wind_samples:
            raise ValueError(f"wind_samples: {len(paths)} training start(s) have {cal.horizon_s:g} s of logged wind "
                             f"after them to measure the wind forecast's error on; need {self.wind_samples}: the "
                             f"training logs are too short for that horizon (the calibration's, the longest "
                             f"forecast horizon); give longer logs or a shorter horizon, or wind_samples=0 in the "
                             f"Python API")
        pick = np.random.default_rng(self.ensemble_config.seed).choice(len(paths), self.wind_samples, replace=False)
        self.wind_error_paths = np.ascontiguousarray(paths[np.sort(pick)], dtype=float)
        self.wind_error_dt_s = dt
        return {"samples": self.wind_samples, "candidate_paths": int(len(paths)), "horizon_s": cal.horizon_s}

    def _wind_spread(self, st, eta0, nu0, dev0, bias0, current, acc_ext, eta, **rollout_kw) -> np.ndarray:
        """Root-mean-square deviation (S, H+1, 3) [m, m, rad] from the forecast ``eta`` (at the
        forecast wind) of the rollouts from the same starts, each with the forecast wind plus
        one of the stored error paths (the path's last step held beyond its length; heading on
        the circle). Every start uses the same paths (common random numbers: the starts'
        spreads differ by how much each forecast answers the wind, not by which futures were
        drawn, and a start gets the same spread in any batch)."""
        paths = self.wind_error_paths
        N, S, H = len(paths), eta0.shape[0], st.H
        # path step k holds over [k dt_p, (k + 1) dt_p): the forecast step starting at j dt falls in floor(j dt / dt_p)
        k = np.minimum(np.floor(np.arange(H) * st.dt / self.wind_error_dt_s + 1e-9).astype(int), paths.shape[1] - 1)
        draw = np.repeat(paths[:, k], S, axis=0)                                    # (N S, H, 2), path-major
        base = np.broadcast_to(speed_dir_to_vector(st.wind), (S, H, 2))
        wind = np.ascontiguousarray(vector_to_speed_dir(np.tile(base, (N, 1, 1)) + draw))

        def tile(x):
            return _tile_starts(x, N)

        per_start = {k: tile(rollout_kw.pop(k))
                     for k in ("nets_weight", "drift_yaw_uv", "command_memory", "wave_axis")}
        eta_w, _, _, _ = self.rollout(tile(eta0), tile(nu0), tile(dev0), np.tile(bias0, (1, N, 1)), tile(st.rpm),
                                      tile(st.az), wind, H, st.dt, current=tile(current), accel_ext=tile(acc_ext),
                                      **per_start, **rollout_kw)
        d = eta_w.reshape(N, S, H + 1, 3) - eta[None]
        d[..., 2] = wrap_pi(d[..., 2])
        return np.sqrt((d ** 2).mean(axis=0))

    @staticmethod
    def _calibration_cut(a: LogArrays, cal: CalibrationConfig, dp_only: bool) -> int:
        """First row of the held-back part of log ``a`` (``len(a)`` when nothing is held back)."""
        n = len(a)
        if cal.fraction == 0 or n < 4:
            return n
        usable = np.flatnonzero(a.dp_active.astype(bool)) if dp_only else np.arange(n)
        if usable.size < 4:
            return n
        dt = float(np.median(np.diff(a.time_s)))
        n_cal = max(int(round(cal.fraction * usable.size)), int(np.ceil(1.1 * cal.horizon_s / dt)))
        n_cal = min(n_cal, usable.size // 2)
        return int(usable[-n_cal]) if n_cal > 0 else n

    @staticmethod
    def _held_back(logs, cal: CalibrationConfig, dp_only: bool) -> tuple[list[int], list]:
        """Per log, the first held-back row (:meth:`_calibration_cut`) and the mask of the rows
        before it that train the nets (None where nothing is held back)."""
        cuts = [HybridPredictor._calibration_cut(a, cal, dp_only) for a in logs]
        return cuts, [None if c >= len(a) else (np.arange(len(a)) < c) for a, c in zip(logs, cuts)]

    def _calibration_starts(self, a: LogArrays, cut: int, H: int, dp_only: bool) -> np.ndarray:
        """Rows >= ``cut`` whose next H rows are in the same segment (and station keeping with ``dp_only``)."""
        n = len(a)
        if cut >= n - H:
            return np.zeros(0, int)
        r = np.arange(cut, n - H)
        seg = a.segment_id
        ok = seg[r + H] == seg[r]
        ok &= np.isfinite(a.eta[r]).all(1) & np.isfinite(a.nu[r]).all(1)
        if dp_only:
            bad = np.concatenate([[0], np.cumsum(a.dp_active == 0)])
            ok &= (bad[r + H + 1] - bad[r]) == 0
        return r[ok]

    def _calibrate_modes(self, logs, folds, cal: CalibrationConfig, dp_only: bool) -> dict:
        """Calibrate the spread of every mode of ``cal.commands`` on the held-back starts of
        ``folds`` (:meth:`_fit_command_guard`; replacing ``self.calibration``); returns the
        starts used per mode."""
        self.calibration = {}
        n_starts = {}
        for mode in cal.commands:
            fitted, n_starts[mode] = self._calibrate(logs, folds, cal, dp_only, mode)
            if fitted is not None:
                self.calibration[mode] = fitted
            else:
                warn_user(f"fit: the spread with commands {mode!r} is not calibrated: {n_starts[mode]} held-back "
                          f"starts, {MIN_CALIBRATION_STARTS} needed; its forecasts keep the ensemble's raw "
                          f"spread (hold back more with calibration_config.fraction, or use longer logs)",
                          UserWarning)
        return n_starts

    def _calibrate(self, logs, folds, cal: CalibrationConfig, dp_only: bool, mode: str):
        """Calibration of one command mode from the held-back starts of ``folds`` (each fold's
        forecasts with its own command-regime weights); (None, 0) without any start."""
        from ..frames import wrap_pi

        total = sum(r.size for _, rows in folds for r in rows)
        if total == 0:
            return None, 0
        pos_e, pos_s, hdg_e, hdg_s, leads = [], [], [], [], []
        final = self.command_regime
        try:
            for regime, a, rows in ((g, a, r) for g, rows_ in folds for a, r in zip(logs, rows_)):
                if rows.size == 0:
                    continue
                self.command_regime = regime
                dt = float(np.median(np.diff(a.time_s)))
                every = max(1, int(np.ceil(total / cal.max_starts))) if cal.start_every_s is None \
                    else max(1, int(round(cal.start_every_s / dt)))
                rows = rows[::every]
                fc = self.forecast(a, a.time_s[rows], cal.horizon_s, commands=mode, calibrated=False)
                H = fc.eta.shape[1] - 1
                truth = a.eta[rows[:, None] + np.arange(1, H + 1)[None, :]]          # (S, H, 3)
                e = np.abs(fc.eta[:, 1:] - truth)
                pos_e.append(np.concatenate([e[..., 0], e[..., 1]]))               # north and east pooled
                pos_s.append(np.concatenate([fc.eta_std[:, 1:, 0], fc.eta_std[:, 1:, 1]]))
                hdg_e.append(np.abs(wrap_pi(fc.eta[:, 1:, 2] - truth[..., 2])))
                hdg_s.append(fc.eta_std[:, 1:, 2])
                leads.append(fc.lead_s[1:])
        finally:
            self.command_regime = final
        lead, cols = _common_leads(leads)
        kw = cal.fit_kwargs
        n = sum(x.shape[0] for x in hdg_e)
        if n < MIN_CALIBRATION_STARTS:
            return None, n
        cat = lambda xs: np.concatenate([x[:, c] for x, c in zip(xs, cols)])  # noqa: E731
        return ({"position": fit_spread_scale(cat(pos_e), cat(pos_s), lead, min_samples=MIN_CALIBRATION_STARTS, **kw),
                 "heading": fit_spread_scale(cat(hdg_e), cat(hdg_s), lead, min_samples=MIN_CALIBRATION_STARTS,
                                             **kw)}, n)

    # ------------------------------------------------------------------ forecasting

    def _check_fitted(self):
        if self.ensemble is None:
            raise RuntimeError("HybridPredictor: not fitted; call fit() or load() first")

    def forecast(self, log, start_times_s, horizon_s: float = 60.0, *, guard: bool | None = None,
                 commands: str = "held", nets: bool = True, nets_after_stop: bool | None = None,
                 calibrated: bool = True) -> ForecastResult:
        """Forecast from every start time (one batch).

        Parameters
        ----------
        log, start_times_s, horizon_s, commands
            As in :meth:`DynamicPredictor.forecast` (commands held or known); the wind
            follows the model's ``wind_forecast``.
        guard : bool, optional
            Shrink the learned correction outside the training envelope (default: the
            ``guard`` given at construction).
        nets : bool
            Use the nets' learned deviation; False gives physics + environment alone (to
            measure what the nets add).
        nets_after_stop : bool, optional
            Override the model's ``nets_after_stop`` for this call.
        calibrated : bool
            Report the calibrated spread (the default, when :meth:`fit` calibrated the
            mode ``commands``); False gives the raw spread: the members' (with the
            estimator's posterior and, after a failure, the held load's), or for a start
            during station keeping the held load's alone
            (``CalibrationConfig.station_keeping_spread``).
        """
        self._check_fitted()
        _check_flags(optional=("guard", "nets_after_stop"), guard=guard, nets=nets, nets_after_stop=nets_after_stop,
                     calibrated=calibrated)
        st = _forecast_setup(self.model, self.residual_config, log, start_times_s, horizon_s,
                             self.stop_after_failure, commands, history_s=self.history_s,
                             wind_forecast=self.wind_forecast)
        warn_other_rate(self.training_info, st.dt)
        warn_no_wind(self.training_info, st.arrays)
        E = self.ensemble.n_members
        sigma_b = None
        if self.environment == "estimator":
            eta0, nu0, dev0, bias0, current, acc_ext, sigma_b = self._estimated_start(st, E)
        else:
            prep = prepare_log(self.model, st.arrays, self.residual_config)
            dev0 = np.array([prep.start_state(int(i))[2] for i in st.idx])
            bias0 = np.stack([prep.bias_members(int(i), E, self.ensemble_config.seed) for i in st.idx], axis=1)
            eta0, nu0, current, acc_ext = st.eta0, st.nu0, None, None
        rollout_kw = dict(guard=self.use_guard if guard is None else guard, substeps=st.substeps, nets=nets,
                          nets_weight=self._after_stop_weight(st, nets_after_stop),
                          drift_yaw_uv=self._drift_yaw_uv(st), command_memory=self._command_memory(st),
                          wave_axis=self._wave_axes(st))
        eta, nu, std, wgt = self.rollout(eta0, nu0, dev0, bias0, st.rpm, st.az, st.wind, st.H, st.dt,
                                         current=current, accel_ext=acc_ext, **rollout_kw)
        if self.wind_samples and self.wind_error_paths is not None and st.H > 0:
            # what the wind's unknown future adds: the members do not see it
            std = np.sqrt(std ** 2 + self._wind_spread(st, eta0, nu0, dev0, bias0, current, acc_ext, eta,
                                                       **rollout_kw) ** 2)
        after_stop = st.arrays.dp_active[st.idx] == 0
        if sigma_b is not None and np.any(sigma_b):
            # the load held over the forecast varies as it did in the station keeping before;
            # during station keeping that variability is the spread itself (the default), where
            # there was enough station keeping to measure it (else the members' spread)
            held = held_load_spread(sigma_b, st.lead_s)
            on_station = ~after_stop & self._held_load_on_station & np.any(sigma_b > 0, axis=1)
            std = np.where(on_station[:, None, None], held, np.sqrt(std ** 2 + held ** 2))
        flags = dict(st.flags)
        if wgt is not None:
            flags[FaultFlags.OUT_OF_ENVELOPE] = np.any(wgt < 1.0, axis=1)
        notes = self._short_station_keeping_notes(st, sigma_b, after_stop)
        if self.environment == "estimator":
            notes = join_notes(notes, _estimator_heading_notes(st, eta0))
        if calibrated:
            since, late, within = self._late_in_drift(st)
            late &= after_stop
            std, raw = self._calibrated_forecast_std(std, st.lead_s, commands, after_stop, late)
            notes = join_notes(notes, self._uncalibrated_notes(raw, after_stop, commands),
                               self._late_in_drift_notes(since, within, late & ~raw))
        return ForecastResult(st.arrays.time_s[st.idx], st.lead_s, eta, nu, std, wgt, flags=flags, notes=notes)

    def _uncalibrated_notes(self, raw, after_stop, commands) -> list[str]:
        """Per start, a note when no calibration applied to its spread (``raw``, (S,)), so that
        it is the raw one although a calibrated spread was asked for; "" otherwise."""
        n_min = self.calibration_config.after_stop_min_failures
        after = (f"spread: not calibrated for a start after a failure (training calibrates it on the training "
                 f"logs' failures when they hold at least {n_min}, HybridPredictor.calibrate_after_stop on other "
                 f"logs): the raw spread, which may be far narrower than the error")
        other = f"spread: not calibrated (the model has no calibration for commands {commands!r}): the raw spread"
        return [(after if a else other) if r else "" for r, a in zip(raw, after_stop)]

    def _late_in_drift(self, st) -> tuple[np.ndarray, np.ndarray, float]:
        """Per start: seconds since the failure before it (from the rows read; ``inf`` when
        none of them had the DP on), whether that is later than the starts the after-failure
        calibration was fitted on (the first 20 samples after each failure), and their span [s]."""
        info = self.training_info.get("calibration", {}).get("after_stop", {})
        within = float(info.get("starts_within_s", AFTER_STOP_INTERVALS * st.dt))
        t, dp = st.arrays.time_s, st.arrays.dp_active
        # the failure before each start: the first row after the last one with the DP on
        last_on = np.maximum.accumulate(np.where(dp != 0, np.arange(len(t)), -1))[st.idx]
        since = np.where(last_on < 0, np.inf, t[st.idx] - t[np.clip(last_on + 1, 0, len(t) - 1)])
        # the calibrated starts lie 0 .. within - dt after the failure; the later ones from within on
        return since, since > within - 0.75 * st.dt, within

    def _late_in_drift_notes(self, since, within: float, late_uncalibrated) -> list[str]:
        """Per start, a note when it starts later in a drift (``since`` [s] after the failure,
        :meth:`_late_in_drift`) than the starts the model's after-failure calibration covers
        (``within`` [s]) and no calibration of later starts applies (a model whose failures'
        drifts were too short for one, or a file from before it): there the errors outgrow
        that band; "" otherwise."""
        if AFTER_STOP_LATE in self.calibration:
            return [""] * len(since)
        return [f"spread: calibrated on forecasts that start within {within:g} s of a failure; this one starts "
                f"{'more than the log read, ' if not np.isfinite(since[k]) else f'{since[k]:.0f} s '}after it, where "
                f"drift forecasts have erred by several times that band (docs/results-drift.md)"
                if late_uncalibrated[k] else "" for k in range(len(since))]

    def _short_station_keeping_notes(self, st, sigma_b, after_stop) -> tuple:
        """``st.notes`` with a note on each start during station keeping whose spread could
        not be the held load's (``CalibrationConfig.station_keeping_spread``) because fewer
        than three complete blocks of station keeping precede it (a log that begins shortly
        before, or gaps or rows without station keeping that break the blocks, which count
        only whole: see :func:`~hybridship.residual.load_variability.unexplained_load_std`):
        its spread then comes from the members' (scaled by the calibration fitted on the held
        load's when calibrated), which on station is far wider than the error."""
        if not (self._held_load_on_station and sigma_b is not None):
            return st.notes
        short = ~after_stop & ~np.any(sigma_b > 0, axis=1)
        block = self.environment_config.held_load_block_s
        note = (f"spread: the held load's needs three whole {block:g}-s blocks of station keeping before the start "
                f"and this start has fewer, so its spread comes from the members' and on station is far wider than "
                f"the error (start {3 * block:g} s or more into the station keeping, after any gap in the log that "
                f"breaks the blocks: a block counts only with every sample and all of it on station)")
        return join_notes(st.notes, [note if k else "" for k in short])

    @property
    def warm_up_s(self) -> float:
        """Seconds of log a start needs before it to have its environment from a full window
        [s]: the estimator's window (its filter then reads at least that much, see
        :meth:`_filter_groups`), or the mean residual's windows."""
        c = self.residual_config
        return float(self.environment_window_s if self.environment == "estimator"
                     else c.bias_window_s + c.start_residual_window_s + c.deriv_window_s)

    @property
    def history_s(self) -> float:
        """Seconds of log before the earliest start that :meth:`forecast` reads [s]: the
        estimator's window and one step of its start grid (its filter starts up to that far
        back, see :meth:`_filter_groups`), or the mean residual's windows, with the command
        memory :data:`~hybridship.residual.features.MEMORY_HISTORY_TIME_CONSTANTS` of its time
        constants, and at least :data:`~hybridship.predictors.forecast_setup.FORECAST_HISTORY_S`."""
        own = self.warm_up_s + (FILTER_START_GRID_S if self.environment == "estimator" else 0.0)
        rc = self.residual_config
        if rc.uses_memory_features:     # the memory starts at the first row read: forgotten by each start
            own = max(own, MEMORY_HISTORY_TIME_CONSTANTS * rc.command_memory_s)
        return max(FORECAST_HISTORY_S, own)

    @property
    def turns_yaw_load(self) -> bool:
        """Whether forecasts after a failure turn the yaw load with the waves: the environment
        config's ``wave_turned_yaw_load`` True, or ``"auto"`` where :meth:`fit` chose it; with
        the environment estimator and ``stop_after_failure`` only."""
        c = self.environment_config.wave_turned_yaw_load
        return (c is True or (c == "auto" and self.wave_yaw_turned)) and self.environment == "estimator" \
            and self.stop_after_failure

    @property
    def chooses_wave_yaw_load(self) -> bool:
        """Whether :meth:`fit` chooses from the training logs' failures if the yaw load turns with
        the waves: ``environment_config.wave_turned_yaw_load == "auto"`` where it learns the drift
        from failures (:attr:`uses_drift_hull`); elsewhere ``"auto"`` holds the load."""
        return self.environment_config.wave_turned_yaw_load == "auto" and self.uses_drift_hull

    @property
    def uses_drift_hull(self) -> bool:
        """Whether the hull's yaw moment in a drift is learned and used: ``drift_hull`` with the
        environment estimator and ``stop_after_failure`` (without it a drift is forecast with
        the thrust held, not as a drift)."""
        return self.drift_hull and self.environment == "estimator" and self.stop_after_failure

    def _drift_yaw_uv(self, st):
        """Per start, the hull's yaw coefficient in a drift [rad/m^2]: the learned one for starts
        after a failure, 0 before (None when there is none)."""
        if self.drift_yaw_uv_rad_per_m2 == 0.0 or not self.uses_drift_hull:
            return None
        return np.where(st.arrays.dp_active[st.idx] == 0, self.drift_yaw_uv_rad_per_m2, 0.0)

    def _after_stop_weight(self, st, nets_after_stop):
        """Per start, 0 where the nets must stay off because the start is after a failure."""
        allow = self.nets_after_stop if nets_after_stop is None else bool(nets_after_stop)
        if allow:
            return None
        return (st.arrays.dp_active[st.idx] != 0).astype(float)

    def environment_estimate(self, log, start_times_s):
        """The environment estimator's state at each start time (causal), see
        :class:`hybridship.residual.environment.EnvironmentEstimate`. The log is read as
        :meth:`forecast` reads it (sensor faults tolerated, format errors refused)."""
        self._check_fitted()
        arrays = as_log_arrays(log, self.model.vessel, purpose="forecast")
        return self._run_estimator(arrays, start_indices(arrays, start_times_s))

    def _filter_groups(self, arrays, idx) -> list[tuple[int, np.ndarray]]:
        """The starts ``idx`` (rows) by the row at which their filter starts: ``[(first_row,
        positions in idx), ...]``.

        A start's filter starts at the last whole multiple of :data:`FILTER_START_GRID_S` of
        log time that lies at least ``environment_window_s`` before it (so it has filtered
        between one window and one window plus the grid step, and never before the log's
        first row). Its estimate therefore depends on the log and its own start time only,
        not on the other starts of the batch or on how much log before them was read;
        starts with the same first row share one filter run.
        """
        first_s = np.floor((arrays.time_s[idx] - self.environment_window_s) / FILTER_START_GRID_S) * FILTER_START_GRID_S
        first = np.searchsorted(arrays.time_s, first_s - 1e-6, side="left")
        return [(int(f), np.flatnonzero(first == f)) for f in np.unique(first)]

    def _filter_drift_yaw(self) -> float:
        """The hull's yaw coefficient in a drift [rad/m^2] the filter's process model uses after a
        failure: the forecasts' own (0 when they use none, and in files of format 10 and older,
        whose coefficient was chosen with the forecasts alone)."""
        return self.drift_yaw_uv_rad_per_m2 if self.uses_drift_hull and self._drift_yaw_in_filter else 0.0

    def _wave_axes(self, st, turned: bool | None = None) -> np.ndarray | None:
        """Per start after a failure, the waves' axis found in the station keeping before it and
        the shape's value at the start's heading, ``[axis_ned_rad, sin(2 (axis - psi_0))]``
        (S, 2), NaN where there is no axis or the shape's value there is under
        ``min_wave_sin2`` (the load is then held; see :mod:`hybridship.residual.wave_direction`);
        None unless the yaw load is turned (:attr:`turns_yaw_load`, or ``turned`` when given).

        The shape is referred to the start's heading ``psi_0``, not to the station keeping's:
        the estimator follows the yaw load through the drift, so the load a forecast starts
        with is its estimate at ``psi_0`` (after a turn, referring it to the station keeping's
        heading scaled a load already turned; along the drifts of truthsim-dev and of our own
        scenarios that made the heading error worse than holding the load).

        A start's window is the last ``wave_axis_window_s`` of log time of that station
        keeping within the rows its own filter reads (from its first row of
        :meth:`_filter_groups`): it depends on the log and the start alone, not on the other
        starts of the batch (which set how much log before them is read). A start more than
        ``environment_window_s - wave_axis_window_s`` after the failure has a shorter window.
        """
        c = self.environment_config
        if not (self.turns_yaw_load if turned is None else turned):
            return None
        a = st.arrays
        first = np.zeros(len(st.idx), dtype=int)
        for f, pos in self._filter_groups(a, st.idx):
            first[pos] = f
        out = np.full((len(st.idx), 2), np.nan)
        found = {}
        for k, i in enumerate(st.idx):
            on = np.flatnonzero(a.dp_active[first[k]:i + 1] != 0)
            if a.dp_active[i] != 0 or not on.size:
                continue
            stop = first[k] + int(on[-1]) + 1      # the first row after the station keeping
            # by time (the rows wave_axis keeps), not by a count of the log's median step
            lo = max(first[k], int(np.searchsorted(a.time_s, a.time_s[stop - 1] - c.wave_axis_window_s)))
            if (lo, stop) not in found:
                rows = np.arange(lo, stop)
                rows = rows[(a.segment_id[rows] == a.segment_id[stop - 1]) & (a.dp_active[rows] != 0)]
                axis = None if rows.size < 2 else wave_axis(
                    a.time_s[rows], a.eta[rows, 2], a.nu[rows, 0], a.nu[rows, 1], window_s=c.wave_axis_window_s,
                    min_anisotropy=c.min_wave_anisotropy)
                found[lo, stop] = np.nan if axis is None else axis.axis_ned_rad
            out[k] = found[lo, stop], np.sin(2.0 * (found[lo, stop] - st.eta0[k, 2]))
        # the amplitude is known only where the start's heading gives the shape weight
        out[~(np.abs(np.nan_to_num(out[:, 1])) >= c.min_wave_sin2)] = np.nan
        return out

    def _run_estimator(self, arrays, idx, extra_rows=None, drift_yaw_uv: float | None = None, first_row=None):
        """The filter's estimates at the start rows ``idx`` (one run per group of
        :meth:`_filter_groups`) and, when given, also at those of ``extra_rows`` that it can
        estimate (not before the log's first valid position), from the same run, which then
        starts at ``first_row`` (default: that of the starts, which must share one).
        ``drift_yaw_uv``: the filter's coefficient of the hull's yaw moment in a drift
        (default :meth:`_filter_drift_yaw`)."""
        k = self._filter_drift_yaw() if drift_yaw_uv is None else float(drift_yaw_uv)
        if extra_rows is not None and first_row is None:
            (first_row, _), = self._filter_groups(arrays, idx)      # the starts of one group
        if extra_rows is None:
            groups = self._filter_groups(arrays, idx)
            parts = [self.estimator.run(arrays, idx[pos], first_row=f, drift_yaw_uv_rad_per_m2=k) for f, pos in groups]
            return EnvironmentEstimate.concatenate(parts, np.argsort(np.concatenate([pos for _, pos in groups])))
        est = self.estimator.run(arrays, np.concatenate([idx, extra_rows]), first_row=first_row, required=len(idx),
                                 drift_yaw_uv_rad_per_m2=k)
        return est.take(slice(0, len(idx))), est.take(slice(len(idx), None))

    def _estimated_start(self, st, n_members: int, drift_yaw_uv: float | None = None):
        """Start states and environment from the estimator at every start row (``drift_yaw_uv``:
        see :meth:`_run_estimator`).

        Returns ``eta0, nu0`` (S, 3) (the filtered state), ``dev0`` (S, 3) zeros, the
        members' loads (E, S, 3) (surge/sway in NED, member 0 the mean), the mean current
        ``(S, 1, 2)``, the thrust-error acceleration of the commands, ``(S, 1, 3)`` with held
        commands and ``(S, H, 3)`` with the logged commands of every step (body; at the
        start's state; near 0 where the thrusters have stopped: an idle propeller's drag
        only) and the held-load variability ``(S, 3)``
        of :mod:`hybridship.residual.load_variability` (zeros when ``held_load_window_s``
        is 0, for starts during station keeping unless :attr:`_held_load_on_station`, and
        where fewer than three blocks of station keeping precede the start).
        """
        est, sigma_b = self._estimate_with_held_load(st, drift_yaw_uv)
        eta0, nu0 = est.x[:, 0:3].copy(), est.x[:, 3:6].copy()
        draws = est.sample_environment(n_members, self.ensemble_config.seed)      # (E, S, 5 + n_theta)
        current = np.ascontiguousarray(current_input(est.current_ned_m_s)[:, None, :])
        # the thrust error acts on the thrust of each step's commands: with the logged commands
        # known it follows them (and ends with a failure inside the horizon)
        S, n_cmd = eta0.shape[0], st.rpm.shape[1]
        wind = st.wind[:, np.minimum(np.arange(n_cmd), st.wind.shape[1] - 1)]      # (S, n_cmd, 2)

        def steps(a):           # a start's value for each of its steps, starts after one another
            return np.repeat(a, n_cmd, axis=0)

        acc_ext = thrust_error_accel(self.model, est.thrust_error_model, steps(eta0), steps(nu0),
                                     st.rpm.reshape(S * n_cmd, -1), st.az.reshape(S * n_cmd, -1),
                                     wind.reshape(S * n_cmd, -1), steps(est.current_ned_m_s),
                                     steps(est.thrust_error)).reshape(S, n_cmd, 3)
        return eta0, nu0, np.zeros_like(eta0), draws[..., 2:5], current, acc_ext, sigma_b

    @property
    def _held_load_on_station(self) -> bool:
        """Whether starts during station keeping report the held-load spread
        (``CalibrationConfig.station_keeping_spread``)."""
        return (self.calibration_config.station_keeping_spread == "held_load" and self.environment == "estimator"
                and self.environment_config.held_load_window_s > 0)

    def _estimate_with_held_load(self, st, drift_yaw_uv: float | None = None):
        """The estimates at the start rows and the held-load variability (S, 3) of the
        station keeping before each start after a failure, and before each start during
        station keeping when :attr:`_held_load_on_station` (one filter run per group of
        :meth:`_filter_groups`, for its starts and their windows)."""
        c = self.environment_config
        sigma_b = np.zeros((len(st.idx), 3))
        on = st.arrays.dp_active[st.idx] != 0
        wanted = (~on & self.stop_after_failure) | (on & self._held_load_on_station)
        if c.held_load_window_s == 0 or not np.any(wanted):
            return self._run_estimator(st.arrays, st.idx, drift_yaw_uv=drift_yaw_uv), sigma_b
        groups = self._filter_groups(st.arrays, st.idx)
        parts = []
        for first, pos in groups:
            est, sigma_b[pos] = self._held_load_group(st, pos, first, wanted[pos], on[pos], drift_yaw_uv)
            parts.append(est)
        return EnvironmentEstimate.concatenate(parts, np.argsort(np.concatenate([pos for _, pos in groups]))), sigma_b

    def _held_load_group(self, st, pos, first: int, wanted, on, drift_yaw_uv):
        """:meth:`_estimate_with_held_load` for the starts ``st.idx[pos]``, whose filter starts
        at ``first``: their estimates and held-load variability (len(pos), 3)."""
        c = self.environment_config
        idx = st.idx[pos]
        sigma_b = np.zeros((len(idx), 3))
        if not np.any(wanted):
            return self._run_estimator(st.arrays, idx, drift_yaw_uv=drift_yaw_uv), sigma_b
        dt = st.arrays.dt_s
        step = max(1, int(round(c.filter_step_s / dt)))
        windows = {}        # starts with the same window (after one stop) share it: (rows, starts)
        for k in np.flatnonzero(wanted):
            # on station the window ends on the start's own filter grid (one filter pass on a
            # 10-Hz log); after a stop, at the last station-keeping row
            # (not below 0: a negative end sliced the rows before it from the log's end, after the start)
            end = max(0, int(idx[k]) - (step - 1 if on[k] else 0))
            rows = held_load_rows(st.arrays.dp_active, st.arrays.time_s, end, step, c.held_load_window_s, dt)
            rows = rows[rows >= first]
            windows.setdefault(tuple(rows[[0, -1]]) if rows.size else (), (rows, []))[1].append(k)
        windows = list(windows.values())
        # overlapping windows of starts during station keeping: filter each row once
        all_rows = np.unique(np.concatenate([w[0] for w in windows]))
        est, est_w = self._run_estimator(st.arrays, idx, all_rows, drift_yaw_uv, first_row=first)
        block = max(1, int(round(c.held_load_block_s / (step * dt))))
        # a window is a run of consecutive estimates on its own filter grid (the last row's
        # residue modulo the step): batch all windows of one grid
        by_grid = {}
        for rows, starts in windows:
            rows = rows[np.isin(rows, est_w.rows)]          # not before the log's first valid position
            if rows.size:
                by_grid.setdefault(int(rows[-1]) % step, []).append((rows, starts))
        for grid, group in by_grid.items():
            on_grid = est_w.take(np.flatnonzero(est_w.rows % step == grid))
            w_first = np.searchsorted(on_grid.rows, [rows[0] for rows, _ in group])
            w_stop = np.searchsorted(on_grid.rows, [rows[-1] for rows, _ in group]) + 1
            sb = unexplained_load_std_windows(self.model, st.arrays, on_grid, w_first, w_stop, block, step)
            for (_, starts), s_k in zip(group, sb):
                sigma_b[starts] = s_k
        return est, sigma_b

    def _calibrated_forecast_std(self, std, lead_s, commands, after_stop, late=None):
        """The spread each start reports: starts after a failure (``after_stop``, (S,)) use the
        ``"after_stop"`` calibration when :meth:`calibrate_after_stop` made one (those later in
        the drift, ``late``, its ``"after_stop_late"`` one where it made that too), others the
        calibration of their command mode; where none applies, the raw spread. Returns the
        spread and the (S,) mask of the starts that kept the raw one."""
        out, applied = std, {}          # calibration -> (S,) mask of the starts it calibrated
        if commands in self.calibration:
            out = self.calibrated_std(std, lead_s, commands)
            applied[commands] = np.ones(len(after_stop), dtype=bool)
            if self.training_info.get("calibration", {}).get("dp_only", False) and self.stop_after_failure:
                # calibrated on station-keeping starts only: a start after a failure (a drift) is
                # another regime, whose spread keeps the raw ensemble value unless calibrated below
                out[after_stop] = std[after_stop]
                applied[commands] = ~after_stop
        if AFTER_STOP in self.calibration and self.stop_after_failure and np.any(after_stop):
            out = out.copy()
            out[after_stop] = self.calibrated_std(std[after_stop], lead_s, AFTER_STOP)
            applied[AFTER_STOP] = after_stop
            if AFTER_STOP_LATE in self.calibration and late is not None and np.any(late):
                out[late] = self.calibrated_std(std[late], lead_s, AFTER_STOP_LATE)
                applied[AFTER_STOP_LATE] = late
        self._warn_beyond_calibration(lead_s, [mode for mode, m in applied.items() if m.any()])
        raw = ~np.any(list(applied.values()), axis=0) if applied else np.ones(len(after_stop), dtype=bool)
        return out, raw

    def _warn_beyond_calibration(self, lead_s, modes) -> None:
        """Warn when the forecast runs past the longest lead that a calibration it applied
        (``modes``) was fitted for: beyond it the scale of that lead is held
        (:meth:`SpreadCalibration.apply`), so the spread is no longer calibrated there."""
        if not modes or np.size(lead_s) == 0:
            return
        last = min(float(c.lead_s[-1]) for mode in modes for c in self.calibration[mode].values())
        # within half a step of it is the same lead: a calibration fitted on logs with jittered
        # time stamps ends at 59.95 s for a 60-s horizon
        half_step = 0.5 * float(lead_s[1] - lead_s[0]) if np.size(lead_s) > 1 else 0.0
        if float(lead_s[-1]) > last + half_step + 1e-9 * last:
            warn_user(f"horizon_s: the spread is calibrated up to {last:g} s; beyond, the scale fitted at "
                      f"{last:g} s is held, so the spread (*_std, quantiles) past {last:g} s is not calibrated",
                      UserWarning)

    def calibrate_after_stop(self, logs, *, n_intervals: int = 20, horizon_s: float = 60.0,
                             cal: CalibrationConfig | None = None) -> "HybridPredictor":
        """Calibrate the spread of forecasts that start after a failure, on logs that contain one
        (and, where their drifts are long enough, of forecasts that start later in a drift).

        Station-keeping logs hold no drift, so the spread of a drift forecast cannot be
        calibrated on them. Logs with failures can: the vessel's own earlier ones (a fleet)
        or DP losses simulated for the vessel by the project's simulator
        (:func:`hybridship.sim.scenario.embedded_scenarios` for the Gunnerus). Forecasts from
        the first ``n_intervals`` samples after each failure (commands held: rpm 0) give a
        per-lead scale of the spread (:func:`~hybridship.residual.calibration.fit_spread_scale`,
        north and east pooled; heading on its own), kept as ``calibration["after_stop"]``
        (stored in the model file) and used by every later forecast that starts within
        ``n_intervals`` samples of a failure. Forecasts from later starts, every
        :data:`LATE_START_EVERY_S` to the end of each drift, give ``calibration["after_stop_late"]``
        the same way, for the starts later in a drift, whose errors grow with its speed (a
        log whose drift is too short gives none; without any, such starts keep the first
        one and say so). The logs must not be the ones the coverage is then judged on.

        Parameters
        ----------
        logs : iterable of path, DataFrame or LogArrays
            Logs with a DP failure (``dp_active`` 1 -> 0) and ``horizon_s`` of drift after
            the first ``n_intervals`` samples.
        n_intervals : int
            Start times after each failure (1 s apart at 1 Hz).
        horizon_s : float
            Longest calibrated lead time [s], a whole number of each log's steps (within the
            forecast's tolerance; :class:`~hybridship.predictors.forecast_setup.HorizonError`
            otherwise, as a forecast refuses it).
        cal : CalibrationConfig, optional
            Settings of the fit (`CalibrationConfig.fit_kwargs`: sigma, coverage, floor quantile and spread
            exponent; default: the model's).
        """
        self._check_fitted()
        cal = self.calibration_config if cal is None else as_config(cal, CalibrationConfig, "cal")
        errors = self.after_stop_errors(logs, n_intervals=n_intervals, horizon_s=horizon_s)
        late = self.after_stop_errors(logs, n_intervals=n_intervals, horizon_s=horizon_s, late=True)
        calibration = {**self.calibration, AFTER_STOP: after_stop_scales(errors, cal)}
        # the pooled lead times are the coarsest log's (logs of other steps are pooled at them),
        # so the window and horizon do not depend on the logs' order
        lead, _ = _common_leads([x[2] for x in errors])
        info = {**self.training_info.get("calibration", {}), "after_stop": {
            "n_logs": len(errors), "n_starts": int(sum(e.shape[0] for e, _, _ in errors)),
            "horizon_s": float(lead[-1]),
            # the starts it was fitted on lie within this long [s] of a failure
            "starts_within_s": float(n_intervals * lead[0])}}
        calibration.pop(AFTER_STOP_LATE, None)
        info.pop(AFTER_STOP_LATE, None)
        # drifts too short for enough later starts (three logs of 110 s gave 12 per lead, and
        # fit raised): no calibration of later starts, whose forecasts then say so in a note
        if late and _fewest_finite_starts(late) >= MIN_CALIBRATION_SAMPLES:
            calibration[AFTER_STOP_LATE] = after_stop_scales(late, cal)
            info[AFTER_STOP_LATE] = {"n_logs": len(late), "n_starts": int(sum(e.shape[0] for e, _, _ in late)),
                                     "horizon_s": float(_common_leads([x[2] for x in late])[0][-1])}
        self.calibration = calibration
        self.training_info = {**self.training_info, "calibration": info}
        return self

    def after_stop_errors(self, logs, *, n_intervals: int = 20, horizon_s: float = 60.0, late: bool = False) -> list:
        """Per log with a failure: the raw (uncalibrated) forecasts' absolute errors and spreads
        after it, ``(err, std, lead_s)`` with ``err, std`` (n_intervals, H, 3) [m, m, rad] at
        every lead ``lead_s`` (H,) [s] up to ``horizon_s``; what :meth:`calibrate_after_stop`
        fits (see :func:`after_stop_scales`). With ``late``, the starts every
        :data:`LATE_START_EVERY_S` after those ``n_intervals`` samples, as many as leave
        ``horizon_s`` of the failure's gap-free stretch of log (logs whose drift leaves none
        are left out). A ``horizon_s`` that is not a whole number of a log's steps is refused
        as a forecast refuses it (:class:`~hybridship.predictors.forecast_setup.HorizonError`)."""
        self._check_fitted()
        check_whole_number("n_intervals", n_intervals, 1)
        horizon_s = check_number("horizon_s", horizon_s, lo=0.0, hi=MAX_HORIZON_S, lo_open=True)
        _check_flags(late=late)
        given = log_list(logs)
        arrays = [as_log_arrays(x, self.model.vessel) for x in given]
        if not arrays:
            raise ValueError("logs: at least one log with a DP failure is needed")
        out = []
        for k, a in enumerate(arrays):
            try:
                errors = self._after_stop_errors_of(a, n_intervals, horizon_s, late)
            except ValueError as err:
                # among several logs, "log: no DP shutdown" did not say which
                if type(err) is not ValueError or not str(err).startswith("log: ") or len(arrays) == 1:
                    raise
                raise ValueError(f"{log_label(given[k], k)}: {str(err)[len('log: '):]}") from None
            if errors is not None:
                out.append(errors)
        return out

    def _after_stop_errors_of(self, a: LogArrays, n_intervals: int, horizon_s: float, late: bool):
        """:meth:`after_stop_errors` of one log, ``(err, std, lead_s)``, or None (``late``, a drift
        too short for a later start)."""
        lead = np.arange(1, horizon_steps(horizon_s, a.dt_s) + 1) * a.dt_s
        if late:
            # starts every LATE_START_EVERY_S within the failure's gap-free stretch of drift
            every = max(1, int(round(LATE_START_EVERY_S / a.dt_s)))
            i0 = shutdown_index(a)
            end = drift_end(a, i0)          # before a gap, and before DP comes back on
            room = end - i0 - n_intervals - lead.size
            if room <= 0:
                return None
            p, t, sd = drift_forecasts(self, a, n_intervals=-(-room // every), first=n_intervals, every=every,
                                       horizons_s=tuple(lead), calibrated=False)
        else:
            p, t, sd = drift_forecasts(self, a, n_intervals=n_intervals, horizons_s=tuple(lead), calibrated=False)
        e = np.abs(p - t)
        e[..., 2] = np.abs(wrap_pi(p[..., 2] - t[..., 2]))
        return e, sd, lead

    def _calibrate_after_stop_on_training_logs(self, logs, cal: CalibrationConfig):
        """With at least ``cal.after_stop_min_failures`` failures in the training logs, the
        spread after a failure is calibrated on them (the vessel's own failures)."""
        if cal.after_stop_min_failures == 0 or self.environment != "estimator":
            return
        failed = [a for a in logs if has_drift(a, AFTER_STOP_INTERVALS, cal.horizon_s)]
        if len(failed) < cal.after_stop_min_failures:
            return
        self.calibrate_after_stop(failed, n_intervals=AFTER_STOP_INTERVALS, horizon_s=cal.horizon_s, cal=cal)
        self.training_info["calibration"]["after_stop"]["source"] = "the training logs' failures"

    def calibrated_std(self, std: np.ndarray, lead_s: np.ndarray, commands: str) -> np.ndarray:
        """Raw ensemble spread (S, H+1, 3) [m, m, rad] at lead times (H+1,) [s] -> calibrated
        spread (float, same shape) with the calibration of ``commands`` (a key of
        :attr:`calibration`).

        Raises
        ------
        TypeError, ValueError
            ``std`` or ``lead_s`` not real numbers, ``std`` not of shape (..., H+1, 3) with
            H+1 = ``len(lead_s)``, a negative spread, lead times that are not a 1-D array of
            finite times >= 0, or ``commands`` without a calibration, naming the argument.
        """
        if not isinstance(commands, str) or commands not in self.calibration:
            raise ValueError(f"commands: expected one of {sorted(self.calibration)}, got {commands!r}")
        std = real_array("calibrated_std: std", std)
        lead_s = real_array("calibrated_std: lead_s", lead_s)
        if lead_s.ndim != 1 or not np.all(np.isfinite(lead_s) & (lead_s >= 0)):
            raise ValueError(f"calibrated_std: lead_s: expected a 1-D array of finite lead times >= 0 [s], got "
                             f"{lead_s.tolist()}")
        if std.ndim < 2 or std.shape[-2:] != (lead_s.size, 3):
            raise ValueError(f"calibrated_std: std: expected the shape (..., len(lead_s), 3) = (..., {lead_s.size}, 3) "
                             f"[m, m, rad], got shape {std.shape}")
        if np.any(std < 0):         # a NaN is passed on, as SpreadCalibration.apply does
            raise ValueError("calibrated_std: std: expected standard deviations >= 0")
        c = self.calibration[commands]
        out = np.empty(std.shape)
        out[..., 0] = c["position"].apply(std[..., 0], lead_s)
        out[..., 1] = c["position"].apply(std[..., 1], lead_s)
        out[..., 2] = c["heading"].apply(std[..., 2], lead_s)
        return out

    def _thrust_weight(self, eta, nu, rpm, az, wind):
        """Thrust-regime weight (S,) of commands (S, K) at states (S, 3) (1 without a regime)."""
        _, parts, _ = self.model.acceleration(eta, nu, rpm=rpm, azimuth_rad=az, wind=wind, return_parts=True)
        return self.thrust_regime.weight(parts[:, 1] @ np.linalg.inv(self.model.mass_matrix).T)

    def _command_memory(self, st) -> np.ndarray | None:
        """The command-memory features (S, H, 2) of the steps of the forecasts of ``st``, from each
        start's logged memory and the commands the forecast uses (held or known); None when the
        nets do not use them."""
        rc = self.residual_config
        if not rc.uses_memory_features:
            return None
        sc = command_scales(self.model, self.model.vessel.rotatable)
        a, idx, n = st.arrays, st.idx, max(st.H, 1)
        logged, filled = log_command_memory(a, st.dt, rc.command_memory_s, **sc,
                                            stop_after_failure=self.stop_after_failure)
        before = np.maximum(idx - 1, 0)
        first = (idx == 0) | (a.segment_id[before] != a.segment_id[idx])
        steps = command_pair(np.broadcast_to(st.rpm, (idx.size, n, st.rpm.shape[2])),
                             np.broadcast_to(st.az, (idx.size, n, st.az.shape[2])), **sc)
        previous = np.where(first[:, None], steps[:, 0], filled[before])
        memory0 = np.where(first[:, None], 0.0, logged[before])
        return command_memory(steps, previous, memory0, st.dt, rc.command_memory_s)

    @property
    def _load_map(self):
        """``A`` of the estimator's load when it is a NED force (``EnvironmentConfig.load_model``
        "force"; its body acceleration at a heading is ``A [R(psi)^T b_ne; b_yaw]``), else None."""
        return self.estimator.load_map if self.environment == "estimator" and self.estimator is not None else None

    def rollout(self, eta0, nu0, dev0, bias0_ned, rpm, az, wind, n_steps: int, dt_s: float, *, guard: bool = True,
                substeps: int = 1, current=None, accel_ext=None, nets: bool = True, nets_weight=None,
                drift_yaw_uv=None, command_memory=None, wave_axis=None):
        """Batched hybrid rollout from states (S, 3), previous residual deviations (S, 3), biases (S, 3)
        or per member (E, S, 3) (surge/sway in NED), commands held (S, 1, K) or per step (S, n_steps, K),
        wind held (S, 1, 2) or per step (S, n_steps, 2), and optionally a held current ``[speed_m_s, dir_to_rad]``
        (S, 1, 2) and a body-frame extra acceleration (S, 1 or n_steps, 3) for the physics, and optionally per start
        the hull's yaw coefficient in a drift ``drift_yaw_uv`` (S,) [rad/m^2] (:func:`_with_drift_yaw`). ``nets=False``
        with ``guard=False`` needs no ensemble (the guard is fitted with the nets); ``nets_weight`` (S,): 0 where the
        nets stay off (after a failure), with the guard on or off. ``command_memory`` (S, >= n_steps, 2): the
        command-memory features of the steps (:meth:`_command_memory`), needed when the nets use them. ``wave_axis``
        (S, 2): the waves' axis per start (:meth:`_wave_axes`); the held yaw load then turns with them.

        Every step: the physics advances the ensemble-mean state one step (RK4, through
        :meth:`DynamicModel.step_unchecked` with the extra acceleration ``accel_ext``) and predicts the
        acceleration there; each member predicts its residual deviation from those and its own previous
        deviation; the residual is the bias (rotated into the current heading) plus the guard-weighted
        mean deviation. It corrects the mean state, ``nu += dt r``, ``eta += 0.5 dt^2 R(psi) r`` (a
        constant residual acceleration over the step); members' deviations from the mean residual are
        integrated the same way to give the spread. Physics runs once per start time, not per member.

        Returns
        -------
        eta (S, H+1, 3), nu (S, H+1, 3), eta_std (S, H+1, 3), guard_weight (S, H+1)
        """
        eta0, nu0, dev0, bias0_ned = _rollout_start(eta0, nu0, dev0, bias0_ned, (nets or guard) and self._check_fitted)
        rpm, az, wind = _check_rollout_batch(S := eta0.shape[0], n_steps, dt_s, substeps, self.model.n_channels,
                                             nu0=nu0, dev0=dev0, rpm=rpm, az=az, wind=wind, current=current,
                                             accel_ext=accel_ext, per_start=(nets_weight, drift_yaw_uv, wave_axis))
        ens, fidx = self.ensemble, self.residual_config.feature_index
        E = ens.n_members if nets else (np.shape(bias0_ned)[0] if np.ndim(bias0_ned) == 3 else 1)
        acc_phys = np.zeros((S, 1, 3)) if accel_ext is None else np.ascontiguousarray(accel_ext, dtype=float)
        current = np.zeros((S, 1, 2)) if current is None else np.ascontiguousarray(current, dtype=float)
        eta, nu, std = np.empty((S, n_steps + 1, 3)), np.empty((S, n_steps + 1, 3)), np.zeros((S, n_steps + 1, 3))
        wgt = np.ones((S, n_steps + 1))
        eta[:, 0], nu[:, 0] = eta0, nu0
        bias0_ned = np.broadcast_to(bias0_ned, (E, S, 3))
        use_mem = self.residual_config.uses_memory_features and command_memory is not None
        per_step, wind_per_step = _check_rollout_steps(rpm, az, wind, command_memory,
                                                       self.residual_config.uses_memory_features and nets, S, n_steps,
                                                       self.residual_config.features)
        thrust_guard = guard and self.thrust_regime is not None
        w_thrust = np.ones(S)
        w_start = np.ones(S) if nets_weight is None else np.asarray(nets_weight, dtype=float)
        if thrust_guard:
            # thrust regime of the commands at the start; re-judged every step when they change
            w_thrust = self._thrust_weight(eta0, nu0, rpm[:, 0], az[:, 0], wind[:, 0])
            wgt[:, 0] = w_thrust * w_start
        r_prev = np.broadcast_to(dev0, (E, S, 3)).copy()
        d_nu, d_eta = np.zeros((E, S, 3)), np.zeros((E, S, 3))   # members' velocity and NED position deviations
        model = self.model
        wind_s, current_s, acc_s = (np.ascontiguousarray(np.broadcast_to(a[:, 0], (S, a.shape[-1])))
                                    for a in (wind, current, acc_phys))
        acc_per_step, zeros_s = _per_step("accel_ext", acc_phys, n_steps), np.zeros((S, 3))
        use_cmd = self.residual_config.uses_command_features
        use_load = self.residual_config.uses_load_features
        has_current, zeros_c = bool(np.any(current_s)), np.zeros((S, 2))
        feats = np.zeros((E, S, len(ALL_FEATURES)))
        cmd_guard = guard and self.command_regime is not None
        scales = command_scales(self.model, self.model.vessel.rotatable)
        for j in range(n_steps):
            rpm_j, az_j = (np.ascontiguousarray(rpm[:, j:j + 1]), np.ascontiguousarray(az[:, j:j + 1])) \
                if per_step else (rpm, az)
            if wind_per_step:
                wind_s = np.ascontiguousarray(wind[:, j])
            acc_s = np.ascontiguousarray(acc_phys[:, j]) if acc_per_step else acc_s
            if thrust_guard and per_step and j > 0:
                w_thrust = self._thrust_weight(eta[:, j], nu[:, j], rpm_j[:, 0], az_j[:, 0], wind_s)
            # physics: one public model step with the estimator's extra acceleration, and the
            # model's acceleration at the new state (the nets' inputs)
            rpm_s, az_s = np.ascontiguousarray(rpm_j[:, 0]), np.ascontiguousarray(az_j[:, 0])
            eta_1, nu_1 = model.step_unchecked(np.ascontiguousarray(eta[:, j]), np.ascontiguousarray(nu[:, j]),
                                               rpm_s, az_s, wind_s, current_s, zeros_s, acc_s, dt_s, int(substeps))
            a_1, parts_1 = model.acceleration_unchecked(eta_1, nu_1, rpm_s, az_s, wind_s, current_s, zeros_s, acc_s)
            if use_load and has_current:    # the loads at the velocity over ground, as training saw them
                _, parts_1 = model.acceleration_unchecked(eta_1, nu_1, rpm_s, az_s, wind_s, zeros_c, zeros_s, acc_s)
            jp = max(j - 1, 0) if per_step else 0
            _fill_step_features(feats, eta_1, nu_1, a_1, r_prev, (rpm_j[:, 0], rpm[:, jp], az_j[:, 0], az[:, jp]),
                                wind_s, dt_s, scales, command_memory[:, j] if use_mem else None,
                                actuator_acceleration(model.arrays, parts_1) if use_load else None, use_cmd)
            X = feats[..., fidx]
            r = ens.predict_members(X) * w_start[None, :, None] if nets else np.zeros((E, S, 3))   # (E, S, 3)
            if guard:
                z = (X.mean(axis=0) - ens.x_mean) / ens.x_std
                w = self.guard.weight(z) * w_thrust   # (S,)
                if cmd_guard:
                    ch = scales["angle_channel"]
                    w = w * self.command_regime.weight(rpm_j[:, 0, 0] / scales["rpm_scale"], nu_1[:, 0],
                                                       az_j[:, 0, ch] if ch is not None else np.zeros(S))
                r = r * w[None, :, None]
                wgt[:, j + 1] = w * w_start
            if nets and self.hull is not None:
                r = r + (self.hull.predict(feats[0]) * w_start[:, None])[None]
            r_prev = r
            if drift_yaw_uv is not None:        # after r_prev: not a net output, so not a next-step feature
                r = _with_drift_yaw(r, nu_1, drift_yaw_uv)
            eta[:, j + 1], nu[:, j + 1], std[:, j + 1] = _corrected_step(eta_1, nu_1, r, bias0_ned, dt_s, d_nu, d_eta,
                                                                         wave_axis, self._load_map)
            _check_finite_step(eta[:, j + 1], nu[:, j + 1], (j + 1) * dt_s)
        return eta, nu, std, (wgt if guard else None)

    # ------------------------------------------------------------------ model files

    def save(self, path) -> Path:
        """Write the model as one ``.npz`` (arrays only, no pickle) with JSON metadata, atomically
        (see :mod:`hybridship.predictors.model_file`)."""
        self._check_fitted()
        return save_model(self, path)

    @classmethod
    def load(cls, path, vessel=None) -> "HybridPredictor":
        """Load a model file written by :meth:`save` (never executes code from the file).

        Parameters
        ----------
        path : str or path-like
            The ``.npz`` model file.
        vessel : Vessel or str, optional
            The vessel to forecast for (a :class:`~hybridship.vessel.Vessel`, a packaged
            name or a vessel TOML file); it must be the one the model was trained for
            (same validated description). Default: the vessel description embedded in
            the file, so no vessel file is needed.

        Raises
        ------
        ModelFileError
            For an unreadable, truncated or tampered file, another format version, or a
            vessel that differs from the one the model was trained for.
        """
        return load_model(cls, path, vessel)


def _rollout_start(eta0, nu0, dev0, bias0_ned, check_fitted=None):
    """A rollout's start states ``eta0, nu0`` and deviations ``dev0`` as finite (S, 3) float
    arrays and the biases (S, 3) or (E, S, 3); else a ValueError naming the argument
    (``check_fitted`` first, when given: the nets and the guard need a fitted ensemble)."""
    if check_fitted:
        check_fitted()
    out = []
    for name, a in (("eta0", eta0), ("nu0", nu0), ("dev0", dev0), ("bias0_ned", bias0_ned)):
        shapes = "(S, 3) or (E, S, 3)" if name == "bias0_ned" else "(S, 3)"
        a = real_array(name, a)
        if a.ndim not in ((2, 3) if name == "bias0_ned" else (2,)) or a.shape[-1] != 3:
            raise ValueError(f"{name}: expected shape {shapes}, got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name}: contains NaN or inf")
        out.append(a)
    return out


#: Width of each command and load input of a rollout (None: the model's command channels).
_ROLLOUT_INPUT_WIDTHS = {"rpm": None, "az": None, "wind": 2, "current": 2, "accel_ext": 3}


def _check_rollout_batch(S: int, n_steps, dt_s, substeps, n_channels: int, per_start=(None, None, None),
                         **arrays):
    """Every per-start input of a rollout has one row per start (the compiled step reads
    ``S`` rows of each), the commands one column per command channel (``n_channels``), the
    wind and current 2 and the extra acceleration 3, all finite real numbers (the compiled
    step read past a narrower array), ``per_start`` (``nets_weight`` and ``drift_yaw_uv``, (S,)
    finite, and ``wave_axis``, (S, 2); each may be None) one value or row per start, and the
    step settings are valid: ValueError naming the argument. Returns ``rpm``, ``az`` and ``wind``
    as float arrays."""
    check_step(dt_s, substeps)
    check_whole_number("n_steps", n_steps, 1)
    for name, a, shape in zip(("nets_weight", "drift_yaw_uv", "wave_axis"), per_start, ((S,), (S,), (S, 2))):
        # numpy's words ("operands could not be broadcast together") named none of them
        if a is not None and real_array(name, a).shape != shape:
            raise ValueError(f"{name}: expected shape {shape}, one per start, got {np.shape(a)}")
        if a is not None and name != "wave_axis" and not np.all(np.isfinite(real_array(name, a))):
            raise ValueError(f"{name}: contains NaN or inf")          # (a wave axis is NaN where none was found)
    for name, a in arrays.items():
        if a is not None and (np.ndim(a) < 2 or np.shape(a)[0] != S):
            raise ValueError(f"{name}: expected one row per start ({S}, ...), got shape {np.shape(a)}")
        if a is not None and name in _ROLLOUT_INPUT_WIDTHS:
            width = _ROLLOUT_INPUT_WIDTHS[name] or n_channels
            arrays[name] = a = real_array(name, a)
            if a.ndim != 3 or a.shape[1] < 1 or a.shape[2] != width:
                raise ValueError(f"{name}: expected shape ({S}, 1 or n_steps, {width}), got {a.shape}")
            if name == "current" and a.shape[1] != 1:
                # the current is held: every step took the first step's (a silent wrong rollout)
                raise ValueError(f"current: expected a held current, shape ({S}, 1, 2), got {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{name}: contains NaN or inf")
    return arrays["rpm"], arrays["az"], arrays["wind"]


def _per_step(name: str, a: np.ndarray, n_steps: int) -> bool:
    """Whether a rollout input ``a`` (S, 1 or >= n_steps, ...) is per step, else held."""
    if 1 < a.shape[1] < n_steps:
        raise ValueError(f"{name}: a per-step input needs {n_steps} steps, got {a.shape[1]}")
    return a.shape[1] > 1


def _check_rollout_steps(rpm, az, wind, command_memory, use_memory: bool, S: int, n_steps: int,
                         features) -> tuple[bool, bool]:
    """Whether a rollout's commands and wind are per step (else held), after checking that
    per-step inputs cover ``n_steps``, and the command memory too when the nets use it."""
    per_step = rpm.shape[1] > 1
    if not per_step and az.shape[1] > 1:
        # the held rpm held the angles too: every step took az's first (a silent wrong rollout)
        raise ValueError(f"rpm, az: commands are both held (1 step) or both per step ({n_steps} steps); got rpm "
                         f"held and az of {az.shape[1]} steps")
    if per_step and (rpm.shape[1] < n_steps or az.shape[1] < n_steps):
        raise ValueError(f"rpm, az: per-step commands need {n_steps} steps, got {rpm.shape[1]}, {az.shape[1]}")
    wind_per_step = wind.shape[1] > 1
    if wind_per_step and wind.shape[1] < n_steps:
        raise ValueError(f"wind: per-step wind needs {n_steps} steps, got {wind.shape[1]}")
    shape = None if command_memory is None else np.shape(command_memory)
    if (use_memory and shape is None) or (shape is not None and (
            len(shape) != 3 or shape[0] != S or shape[1] < n_steps or shape[2] != len(MEMORY_FEATURES))):
        raise ValueError(f"command_memory: the nets use {features}, which need the command memory of every step, "
                         f"shape ({S}, {n_steps}, {len(MEMORY_FEATURES)}); got {shape}")
    return per_step, wind_per_step


def _training_masks(logs, cuts, dp_only: bool) -> list:
    """Per log, its training rows: before its calibration cut and, with ``dp_only``, in
    station keeping."""
    masks = []
    for a, cut in zip(logs, cuts):
        m = np.arange(len(a)) < cut
        masks.append(m & (a.dp_active != 0) if dp_only else m)
    return masks


def _common_leads(leads: list) -> tuple[np.ndarray, list]:
    """The lead times [s] on which calibration errors of several logs are pooled, and per log
    the columns of its own leads nearest to them: those of the log with the fewest (the
    coarsest step). On logs of one step every log keeps its own columns; on logs of
    different steps a column of the 10-Hz log is not pooled with the 1-Hz log's column of the
    same index, ten times later."""
    lead = min(leads, key=len)
    return lead, [np.abs(np.asarray(x)[None, :] - lead[:, None]).argmin(axis=1) for x in leads]


def _fewest_finite_starts(errors: list) -> int:
    """The fewest starts with a finite heading error and spread at any pooled lead of
    :meth:`HybridPredictor.after_stop_errors`' ``errors`` (the heading's scale, fitted on
    one sample per start, needs the most)."""
    lead, cols = _common_leads([x[2] for x in errors])
    n = np.zeros(lead.size, dtype=int)
    for (e, sd, _), c in zip(errors, cols):
        n += (np.isfinite(e[:, c, 2]) & np.isfinite(sd[:, c, 2])).sum(axis=0)
    return int(n.min())


def after_stop_scales(errors: list, cal: CalibrationConfig) -> dict:
    """The spread calibration after a failure from :meth:`HybridPredictor.after_stop_errors`
    of some logs: a per-lead scale (:func:`~hybridship.residual.calibration.fit_spread_scale`)
    for the position (north and east pooled) and for the heading. ValueError without any
    log's errors."""
    if len(errors) == 0:
        raise ValueError("after_stop_scales: errors: expected the errors after a failure of at least one log "
                         "(after_stop_errors), got none")
    lead, cols = _common_leads([x[2] for x in errors])
    e = np.concatenate([x[0][:, c] for x, c in zip(errors, cols)])
    sd = np.concatenate([x[1][:, c] for x, c in zip(errors, cols)])
    kw = cal.fit_kwargs
    pos = fit_spread_scale(np.concatenate([e[..., 0], e[..., 1]]), np.concatenate([sd[..., 0], sd[..., 1]]),
                           lead, **kw)
    return {"position": pos, "heading": fit_spread_scale(e[..., 2], sd[..., 2], lead, **kw)}


def leave_one_out_after_stop_scales(errors: list, cal: CalibrationConfig) -> list:
    """For each log of :meth:`HybridPredictor.after_stop_errors`, the calibration of
    :func:`after_stop_scales` fitted on the *other* logs' failures (so no failure is scored
    with a spread calibrated on it). ValueError with fewer than two logs' errors (one left
    out leaves none to calibrate on)."""
    if len(errors) < 2:
        raise ValueError(f"leave_one_out_after_stop_scales: errors: expected the errors after a failure of at least "
                         f"two logs (after_stop_errors; each log's calibration is fitted on the others), got "
                         f"{len(errors)}")
    return [after_stop_scales(errors[:k] + errors[k + 1:], cal) for k in range(len(errors))]


def _with_drift_yaw(r, nu, coeff_rad_per_m2):
    """Members' residuals ``r`` (E, S, 3) plus the hull's yaw acceleration in a drift
    ``coeff u v`` [rad/s^2] per start (``coeff_rad_per_m2`` (S,); ``u, v`` [m/s] the
    body-frame velocity over ground of ``nu`` (S, 3); :mod:`hybridship.residual.drift_hull`)."""
    out = r.copy()
    out[..., 2] += coeff_rad_per_m2 * nu[:, 0] * nu[:, 1]
    return out


def _tile_starts(x, n: int):
    """``x`` (S, ...) repeated ``n`` times along the starts, block after block (n S, ...); None stays None."""
    return None if x is None else np.ascontiguousarray(np.tile(x, (n,) + (1,) * (np.ndim(x) - 1)))


def _fill_step_features(feats, eta_1, nu_1, a_1, r_prev, commands, wind, dt_s: float, scales: dict, memory,
                        actuator, use_cmd: bool):
    """Write one rollout step's features into ``feats`` (E, S, len(ALL_FEATURES)): the
    model-predicted velocities and accelerations at the new state ``eta_1, nu_1``, the
    members' previous deviations ``r_prev``, and, when selected, the command-aware ones
    (``commands``: rpm and angles of the step and of the one before), the command memory
    (S, 2) and the actuators' acceleration (S, 3); the others stay as they are (zeros)."""
    feats[:, :, 0:3] = nu_1
    feats[:, :, 3:6] = a_1
    feats[:, :, 6:9] = r_prev
    if use_cmd:
        feats[:, :, 9:_MEMORY_COL] = command_feature_columns(nu_1, eta_1[:, 2], *commands, wind, dt_s,
                                                             scales["rpm_scale"], scales["angle_channel"])
    if memory is not None:
        feats[:, :, _MEMORY_COL:_LOAD_COL] = memory
    if actuator is not None:
        feats[:, :, _LOAD_COL:] = actuator


def _check_finite_step(eta, nu, lead_s: float):
    """Stop a rollout whose state left the finite numbers, with a message that says why."""
    bad = ~(np.isfinite(eta).all(axis=1) & np.isfinite(nu).all(axis=1))
    if np.any(bad):
        raise FloatingPointError(
            f"forecast: the hybrid's rollout diverged at lead {lead_s:g} s for {int(bad.sum())} of {bad.size} "
            f"start(s): the learned correction (nets or hull correction) drove the state to non-finite values. "
            f"Retrain without the hull correction, with the guard on, or on data that covers this regime")


def logs_with_drift(logs, horizon_s: float) -> list[int]:
    """Indices of the logs (LogArrays) with a failure followed by ``horizon_s`` [s] of drift in one
    gap-free segment (:func:`~hybridship.residual.drift_hull.drift_start_rows`): the failures
    that what ``fit`` learns from failures is chosen and checked on."""
    return [k for k, a in enumerate(logs)
            if drift_start_rows(a.dp_active, a.segment_id, int(round(horizon_s / a.dt_s)), 1).size]


def _corrected_step(eta_1, nu_1, r, bias0_ned, dt_s: float, d_nu, d_eta, wave_axis=None, load_map=None):
    """The physics step ``eta_1, nu_1`` (S, 3) corrected by the residual: the members' learned
    deviations ``r`` (E, S, 3) plus the bias ``bias0_ned`` (E, S, 3, surge/sway in NED)
    rotated into the new heading (its yaw part turned with the waves' axis ``wave_axis``
    (S, 2) when given: :func:`~hybridship.residual.wave_direction.yaw_load_factor`; with
    ``load_map`` ``A``, a force: ``A`` times the rotated bias, see
    :func:`~hybridship.residual.environment.load_map`), as a
    constant acceleration over the step (``nu += dt r``,
    ``eta += 0.5 dt^2 R(psi) r`` with the members' mean). The members' deviations from that
    mean are integrated the same way into ``d_nu``, ``d_eta`` (E, S, 3, updated in place).

    Returns the corrected ``eta``, ``nu`` and the members' standard deviation of position
    (each (S, 3)).
    """
    psi = eta_1[:, 2]
    c, s = np.cos(psi), np.sin(psi)
    yaw = bias0_ned[..., 2] if wave_axis is None else bias0_ned[..., 2] * yaw_load_factor(psi, wave_axis)[None]
    bias_b = np.stack([c * bias0_ned[..., 0] + s * bias0_ned[..., 1],
                       -s * bias0_ned[..., 0] + c * bias0_ned[..., 1], yaw], axis=-1)
    if load_map is not None:
        bias_b = bias_b @ load_map.T
    r = r + bias_b
    r_mean = r.mean(axis=0)
    nu = nu_1 + dt_s * r_mean
    half = 0.5 * dt_s * dt_s
    eta = np.column_stack([eta_1[:, 0] + half * (c * r_mean[:, 0] - s * r_mean[:, 1]),
                           eta_1[:, 1] + half * (s * r_mean[:, 0] + c * r_mean[:, 1]),
                           eta_1[:, 2] + half * r_mean[:, 2]])
    dr = r - r_mean
    v_mid = d_nu + 0.5 * dt_s * dr
    d_eta[..., 0] += dt_s * (c * v_mid[..., 0] - s * v_mid[..., 1])
    d_eta[..., 1] += dt_s * (s * v_mid[..., 0] + c * v_mid[..., 1])
    d_eta[..., 2] += dt_s * v_mid[..., 2]
    d_nu += dt_s * dr
    return eta, nu, d_eta.std(axis=0)


def _estimator_heading_notes(st, eta0: np.ndarray) -> list[str]:
    """Per start flagged ``heading_jump``, a note naming the heading this forecast starts from:
    the environment estimator's filtered one (its outlier gate leaves out headings that
    jump, up to ``max_gated_samples`` in a row), which can differ from the start window's
    that the flag's note describes; "" for the other starts."""
    jumped = st.flags[FaultFlags.HEADING_JUMP]
    own, window = (np.round(np.degrees(psi[:, 2]), 1) % 360.0 for psi in (eta0, st.eta0))
    return [f"heading: starts from the environment estimator's {h:.1f} deg (the start window's: {w:.1f} deg)"
            if j else "" for j, h, w in zip(jumped, own, window)]
