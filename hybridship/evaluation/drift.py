"""The drift benchmark: Skulstad et al. (2022) Tables 2 and 3 on any folder of logs.

Every predictor is trained on the logs of ``train`` (the DP part before the shutdown of
each, unless ``dp_only=False``) and forecasts, from each of the first ``n_intervals``
samples after the shutdown of every log in ``test``, ``horizon_s`` ahead. The outputs:

* ``errors.csv``: ``model,state,window,horizon_s,mae`` (``state`` in ``north_m, east_m,
  yaw_deg``; ``window`` 5 or 20 intervals), one row per cell of the paper's Table 2;
* ``errors_per_log.csv``: ``model,log,state,window,horizon_s,mae``: the same cells for
  each test log (failure) alone, so that a mean over logs can be taken apart (for
  example calm against rough weather);
* ``coverage.csv``: ``model,horizon_s,sigma,coverage`` for the ensemble models: the share
  of north and east errors within 1 and 2 standard deviations of the ensemble; with two
  or more test logs also ``<model>_loo_calibrated``: the spread scaled, per horizon, by the
  factor that gives 68.3 % coverage on the other test logs (leave one log out);
* ``coverage_intervals.csv``: ``model,horizon_s,sigma,coverage,low,high,n_failures``: the
  2-sigma coverage of the ensemble models with a 90 % bootstrap interval that resamples
  whole failures (:func:`~hybridship.evaluation.metrics.coverage_interval`): the starts
  after one failure share one outcome, so the number of failures sets how much a
  coverage figure can say;
* ``coverage_heading.csv``: ``model,horizon_s,sigma,coverage,low,high,n_failures``: the
  same for the heading's spread alone (heading errors wrapped to +-180 deg), at 1 and 2
  sigma, with the interval over failures;
* ``tables.md``: Table 2 (cells "first-5/first-20"), Table 3 (% error reduction of the
  hybrids relative to the dynamic model), coverage, the hybrid's error as a ratio to the
  dynamic model's per failure at the longest horizon (with two or more test logs and both
  windows), and wall times;
* ``timing.csv``: training and forecasting wall time per model;
* ``drift_hull.csv``: the hull's yaw coefficient in a drift each test log was forecast with
  and the evidence it was chosen on (the failures' heading errors with it, with 0 and left out);
* ``wave_yaw_load.csv``: whether each test log was forecast with the yaw load turned with the
  waves after the failure, and the evidence of the choice with
  ``EnvironmentConfig(wave_turned_yaw_load="auto")``, the default (the failures' heading
  errors held and turned, the signed-rank test's p-value);
* ``error_vs_horizon.png`` and ``trajectories.png`` (the paper's Fig. 6: the first five
  forecasts after the failure against the measured track).

Models: ``hybrid`` (the default :class:`~hybridship.predictors.HybridPredictor`: physics,
the environment estimator and the guarded nets), ``hybrid_nets_unguarded`` (the same model
with the guard off: the nets always on, as in the paper; its spread raw, since the spread
after a failure is calibrated on forecasts with the nets off), ``hybrid_mean_bias`` (the
same nets with the 900-s mean residual in place of the estimator, the default before the
estimator; its spread after a failure raw too with the default ``dp_only`` calibration),
``dynamic``, ``dead_reckoning`` and ``data_only`` (an ensemble of the same size and
architecture predicting the whole acceleration without physics).

With no folders it runs on the embedded simulated scenarios (train on their DP parts,
test on their drifts, as the paper did with its one failure).
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from . import metrics
from ..config import check_flags, check_number, check_whole_number
from ..fileio import (as_path, atomic_write, check_output_files, earlier_run, make_out_folder, markdown_table,
                      record_outputs, remove_stale, write_text)
from ..predictors import DataOnlyPredictor, DeadReckoning, DynamicPredictor, HybridPredictor, as_log_arrays
from ..predictors.forecast_setup import forecast_step_s, horizon_steps
from ..predictors.hybrid import AFTER_STOP, AFTER_STOP_LATE, after_stop_scales, logs_with_drift
from ..residual.drift_hull import MIN_FAILURES as DRIFT_HULL_MIN_FAILURES, choose_coefficient, munk_coefficient
from ..residual.ensemble import EnsembleConfig
from ..residual.environment import EnvironmentConfig
from ..residual.wave_direction import wave_yaw_choice

#: File endings read as logs from a folder.
LOG_SUFFIXES = (".csv", ".csv.gz", ".parquet", ".pq")

#: Models in table order; the ensemble models also get a coverage row.
MODELS = ("hybrid", "hybrid_nets_unguarded", "hybrid_mean_bias", "dynamic", "dead_reckoning", "data_only")
ENSEMBLE_MODELS = ("hybrid", "hybrid_nets_unguarded", "hybrid_mean_bias", "data_only")
#: Variants whose Table 3 (reduction against ``dynamic``) is written.
TABLE3_MODELS = ("hybrid", "hybrid_nets_unguarded", "hybrid_mean_bias")

#: Skulstad et al. (2022), Table 2 (RV Gunnerus, one DP failure): "first 5/first 20".
PAPER_TABLE2 = {
    ("hybrid", "north_m"): ("0.14/0.17", "0.22/0.76", "0.41/1.74", "0.70/2.93"),
    ("hybrid", "east_m"): ("0.06/0.07", "0.16/0.36", "0.38/1.07", "0.99/2.41"),
    ("hybrid", "yaw_deg"): ("0.14/0.21", "0.28/0.56", "0.37/0.99", "0.73/1.71"),
    ("dynamic", "north_m"): ("0.26/0.21", "0.73/0.56", "1.36/1.07", "2.12/1.78"),
    ("dynamic", "east_m"): ("0.11/0.12", "0.47/0.48", "1.05/1.01", "1.79/1.67"),
    ("dynamic", "yaw_deg"): ("0.25/0.23", "0.55/0.56", "0.89/0.71", "1.49/0.95"),
}


def log_files(folder: Path) -> list[Path]:
    """Log files in ``folder`` (sorted; extensions in any case, as a single log file's are
    read), skipping a ``scenarios.csv`` summary and hidden files (a ``._a.csv`` that macOS
    leaves beside ``a.csv`` on a foreign disk is not a log)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"{folder}: not a folder")
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.name.lower().endswith(LOG_SUFFIXES)
                   and p.name.lower() != "scenarios.csv" and not p.name.startswith("."))
    if not files:
        raise ValueError(f"{folder}: no log files ({', '.join('*' + s for s in LOG_SUFFIXES)})")
    return files


def looks_like_log(path: Path) -> bool:
    """Whether a file found among logs has the log format's ``time_s`` in its header (a
    weather table does not); Parquet files are taken as logs."""
    from ..logs.io import log_header

    if path.name.lower().endswith((".parquet", ".pq")):
        return True
    # empty, binary or damaged (no header): not a log to protect
    return "time_s" in [c.strip() for c in log_header(path) or ()]


def logs_held(folder, ours=()) -> list[Path]:
    """The logs in ``folder`` (none if it is not one), other than the files named ``ours``: a
    command whose CSV tables went there would have them read as logs by ``hybridship train``
    and the benchmarks."""
    if not Path(folder).is_dir():
        return []
    try:
        files = log_files(folder)
    except ValueError:
        return []
    return [f for f in files if f.name not in ours and looks_like_log(f)]


@dataclass
class DriftBenchmarkResult:
    """Everything the benchmark measured (tables as DataFrames, paths of written files)."""

    errors: pd.DataFrame
    coverage: pd.DataFrame
    timing: pd.DataFrame
    table2: pd.DataFrame
    table3: dict
    outputs: dict


#: The benchmark's output files: tables, then the figures (removed when ``plots`` is off).
TABLE_FILES = ("errors.csv", "errors_per_log.csv", "coverage.csv", "coverage_intervals.csv", "coverage_heading.csv",
               "timing.csv", "drift_hull.csv", "wave_yaw_load.csv", "tables.md")
FIGURE_FILES = ("error_vs_horizon.png", "trajectories.png")


def check_output_folder(out_dir, plots: bool = True) -> None:
    """Refuse, before any work, an output folder where the benchmark would replace or remove a
    file that no hybridship command wrote, or one that holds logs (FileExistsError), or a
    read-only one (PermissionError); files of a benchmark run from before folders kept a
    record of their outputs (its ``tables.md`` beside them) are recognised; ``out_dir`` not a
    path (None) is a TypeError naming it."""
    out_dir = as_path(out_dir, "out_dir")
    check_output_files(out_dir, TABLE_FILES + (FIGURE_FILES if plots else ()), () if plots else FIGURE_FILES,
                       ours=earlier_run(TABLE_FILES + FIGURE_FILES, "tables.md", b"Drift benchmark"))
    logs = logs_held(out_dir, TABLE_FILES)
    if logs:
        more = f" and {len(logs) - 1} more" if len(logs) > 1 else ""
        raise FileExistsError(f"{out_dir}: holds logs ({logs[0].name}{more}); the benchmark's CSV tables would be "
                              f"read as logs from there: give a folder of its own")


def run_drift_benchmark(train=None, test=None, out_dir="drift-benchmark", *, vessel="gunnerus",
                        members: int = 10, seed: int = 0, n_intervals: int = 20, horizon_s: float = 60.0,
                        dp_only: bool = True, n_scenarios: int = 3, ensemble_config: EnsembleConfig | None = None,
                        plots: bool = True, progress: bool = True, training: str = "one_step",
                        calibration_scenarios: int = 6, drift_hull: bool = True,
                        environment_config: EnvironmentConfig | None = None) -> DriftBenchmarkResult:
    """Train, forecast after every failure, and write the tables and figures.

    Parameters
    ----------
    train, test : path of a folder of logs, a list of logs, or None
        None (both) runs on ``n_scenarios`` embedded simulated scenarios. ``test`` None
        with a ``train`` folder tests on the training logs' drifts.
    out_dir : path
        Folder for the outputs (created).
    vessel : str or path
        The logs' packaged vessel name or vessel file (TOML).
    members, seed : int
        Ensemble size and seed of every ensemble model.
    n_intervals : int
        Successive start times after each shutdown (the paper's 20).
    horizon_s : float
        Forecast length [s], at least 15; the table's horizons are 15, 30, 45, 60 s within it.
    dp_only : bool
        Train on the DP part (``dp_active == 1``) only. False (every row) is refused when the
        test logs are the training logs: every model would learn from the drifts it is scored on.
    ensemble_config : EnsembleConfig or None
        Overrides ``members``/``seed`` (e.g. fewer epochs in tests).
    plots, progress : bool
        Write the figures beside the tables; print what is being done as it runs.
    training : {"one_step", "multi_step"}
        How the hybrid's nets are trained (see :class:`~hybridship.predictors.HybridPredictor`).
    calibration_scenarios : int
        DP losses simulated by the project's simulator (:func:`~hybridship.sim.scenario.embedded_scenarios`,
        seeds from ``seed + 1000``, never the test scenarios) on which the hybrid's spread after a failure
        is calibrated (:meth:`~hybridship.predictors.HybridPredictor.calibrate_after_stop`) when the
        vessel's own failures are too few; 0: none, the raw spread. The simulator is set up for the
        Gunnerus only: other vessels keep the raw spread. The vessel's own failures are used instead when
        the training logs have at least ``CalibrationConfig.after_stop_min_failures`` (3) of them: as
        ``fit`` calibrated on them when the test logs are other logs, and per test log on the *other*
        logs' failures (leave one out) when the test logs are the training logs.
    drift_hull : bool
        Let the hybrid learn the hull's yaw moment in a drift from failures
        (:mod:`hybridship.residual.drift_hull`; chosen like the spread after a failure:
        by ``fit`` on the training logs' failures, or per test log on the other logs'
        failures when the test logs are the training logs). False: the paper's protocol in
        the strict sense, nothing learned from any failure.
    environment_config : EnvironmentConfig or None
        The hybrid's environment estimator settings (default: ``EnvironmentConfig()``); its
        ``wave_turned_yaw_load="auto"`` is chosen as ``drift_hull`` is (before it), or held.
    """
    check_flags(plots=plots, progress=progress)         # plots="no" is truthy: the figures were written
    say = (lambda msg: print(msg, flush=True)) if progress else (lambda msg: None)  # noqa: E731
    n_intervals, horizon_s, calibration_scenarios = _checked_lengths(n_intervals, horizon_s, calibration_scenarios)
    # members named as the argument is, before any log is read or scenario simulated (not "n_members")
    ens_cfg = ensemble_config or EnsembleConfig(n_members=check_whole_number("members", members, 1), seed=seed)
    check_output_folder(out_dir, plots)
    train_logs, train_names, test_logs, test_names = _benchmark_logs(train, test, n_scenarios, seed, say)
    horizons = tuple(h for h in metrics.HORIZONS_S if h <= horizon_s + 1e-9)

    hybrid = HybridPredictor(vessel, ensemble_config=ens_cfg, training=training, drift_hull=drift_hull,
                             environment_config=environment_config or EnvironmentConfig())
    train_arrays = [as_log_arrays(x, hybrid.model.vessel) for x in train_logs]
    test_arrays = _test_arrays(test_logs, test_names, hybrid.model.vessel, n_intervals, horizon_s, horizons)
    test_logs = train_logs if _same_samples(train_arrays, test_arrays, test_names) else test_logs   # given again
    _check_before_training(hybrid, dp_only, test_logs is train_logs, test_arrays, calibration_scenarios, n_intervals)
    out = make_out_folder(out_dir)
    data_only = DataOnlyPredictor(vessel, ensemble_config=ens_cfg)
    timing = _fit_ensembles({"hybrid": hybrid, "data_only": data_only}, train_arrays, dp_only, say)
    t_choices, (per_log_wave, per_log_hull, per_log_cal) = _choose_per_log(
        hybrid, test_arrays, test_logs is train_logs, calibration_scenarios, seed, n_intervals, horizon_s, test_names,
        say)
    timing += t_choices
    predictors = _benchmark_models(vessel, hybrid, data_only)

    fc, all_h, pick, fc_timing = _forecast_after_failures(predictors, test_arrays, n_intervals, horizon_s, horizons,
                                                          hybrid, per_log_cal, per_log_hull, per_log_wave)
    timing = pd.DataFrame(timing + fc_timing)

    errors = {name: [metrics.absolute_errors(p[:, pick], t[:, pick]) for p, t, _ in per_log]
              for name, per_log in fc.items()}
    windows = tuple(w for w in metrics.WINDOWS if w <= n_intervals) or (n_intervals,)
    long = metrics.error_table(errors, horizons_s=horizons, windows=windows)
    per_log_long = _per_log_errors(errors, test_names, horizons, windows)
    coverage, intervals, heading_cov = _coverage_tables(fc, pick, horizons, len(test_arrays), seed)

    tables = {"errors.csv": long, "errors_per_log.csv": per_log_long, "coverage.csv": coverage,
              "coverage_intervals.csv": intervals, "coverage_heading.csv": heading_cov, "timing.csv": timing,
              "drift_hull.csv": _drift_hull_table(hybrid, per_log_hull, test_names),
              "wave_yaw_load.csv": _wave_yaw_table(hybrid, per_log_wave, test_names)}
    outputs = {name: _write_csv(out / name, table) for name, table in tables.items()}
    table2, table3, ratio = _paper_tables(long, windows)
    md = _markdown(table2, table3, ratio, coverage, intervals, timing, test_names, len(train_arrays), ens_cfg,
                   n_intervals, windows, per_log_long, heading_cov)
    outputs["tables.md"] = _recorded(write_text(out / "tables.md", md))
    outputs.update(_figures(out, plots, fc, all_h, test_arrays, test_names))
    record_outputs(out, outputs, removed=() if plots else FIGURE_FILES)
    for k, v in outputs.items():
        say(f"wrote {k}: {v}")
    return DriftBenchmarkResult(long, coverage, timing, table2, table3, outputs)


def _checked_lengths(n_intervals, horizon_s, calibration_scenarios) -> tuple[int, float, int]:
    """``(n_intervals, horizon_s, calibration_scenarios)`` checked before any work.

    Raises
    ------
    ValueError, TypeError
        Naming the argument: ``n_intervals`` not a whole number >= 1, ``horizon_s`` [s] not a
        finite number of at least the table's shortest horizon (15 s; a shorter one leaves no
        table cell), ``calibration_scenarios`` not a whole number >= 0. Each failed after the
        training, inside numpy or pandas, or was truncated without a word.
    """
    shortest = min(metrics.HORIZONS_S)
    return (check_whole_number("n_intervals", n_intervals, 1),
            check_number("horizon_s", horizon_s, lo=shortest),
            check_whole_number("calibration_scenarios", calibration_scenarios, 0))


def _benchmark_logs(train, test, n_scenarios: int, seed: int, say):
    """``(train_logs, train_names, test_logs, test_names)``: the folders or lists given, or the
    embedded scenarios when both are None (train on their DP parts, test on their drifts)."""
    if train is None and test is None:
        from ..sim.scenario import embedded_scenarios

        # embedded_scenarios named its own argument ("n: expected an int in 1..20")
        if check_whole_number("n_scenarios", n_scenarios, 1) > 20:
            raise ValueError(f"n_scenarios: expected a whole number in 1..20 (the embedded scenarios), "
                             f"got {n_scenarios!r}")
        scen = embedded_scenarios(n_scenarios, seed)
        train_logs = test_logs = [s.log for s in scen]
        train_names = test_names = [s.name for s in scen]
        say(f"embedded scenarios: {', '.join(train_names)} (train on DP parts, test on drifts)")
    else:
        if train is None:
            raise ValueError("train: a folder of training logs is needed when test is given")
        train_logs, train_names = _logs(train, "train")
        test_logs, test_names = (train_logs, train_names) if test is None else _logs(test, "test")
        test_logs, test_names = _same_logs_as_training(train_logs, train_names, test_logs, test_names)
    return train_logs, train_names, test_logs, test_names


def _same_logs_as_training(train_logs, train_names, test_logs, test_names):
    """The training logs themselves when ``test`` names the same files (so every failure is
    scored leave one out); a ValueError when it shares only some of them (their drifts would
    be scored with what ``fit`` learned from them). Logs given as data, not files, are not
    compared."""
    def key(x):
        return Path(x).resolve() if isinstance(x, (str, Path)) else None

    train_keys = {key(x) for x in train_logs} - {None}
    test_keys = [key(x) for x in test_logs]
    shared = [n for k, n in zip(test_keys, test_names) if k is not None and k in train_keys]
    if not shared:
        return test_logs, test_names
    if len(shared) == len(test_logs) == len(train_logs):
        return train_logs, train_names
    raise ValueError(f"test: {len(shared)} of the test logs are also training logs ({', '.join(shared[:5])}"
                     f"{', ...' if len(shared) > 5 else ''}); give the same folder to score every failure "
                     f"leave one out, or folders without common logs")


def _same_samples(train_arrays, test_arrays, test_names) -> bool:
    """Whether the test logs hold the samples of the training logs, all of them (then every
    failure is scored leave one out, as for the same folder); a ValueError when only some do.
    Catches what comparing paths cannot: logs given as DataFrames or LogArrays (a list is
    copied, so the same list twice was two), or copies under other names, whose failures
    would be scored with the spread calibrated and the hull coefficient chosen on them."""
    from ..predictors.training_logs import samples_digest

    trained = [samples_digest(a) for a in train_arrays]
    tested = [samples_digest(a) for a in test_arrays]
    trained_set = set(trained)
    shared = [n for d, n in zip(tested, test_names) if d in trained_set]
    if not shared:
        return False
    if sorted(tested) == sorted(trained):
        return True
    raise ValueError(f"test: {len(shared)} of the test logs hold the samples of training logs ({', '.join(shared[:5])}"
                     f"{', ...' if len(shared) > 5 else ''}); give the same logs to score every failure leave one "
                     f"out, or test logs that are not training logs")


#: Where the spread after a failure is calibrated, as the refusal of too few forecasts names it,
#: and what to change: the other test logs' failures, or the simulated DP losses.
_OTHER_LOGS = ("the other logs' failures", "more intervals, or more logs with a failure")
_SIMULATED = ("calibration_scenarios", "more intervals or calibration scenarios, or none for the raw spread")


def _check_before_training(hybrid, dp_only: bool, test_is_train: bool, test_arrays, calibration_scenarios: int,
                           n_intervals: int) -> None:
    """Refuse, before any training, what the run would refuse after it when the test logs are
    the training logs: training on every row (:func:`_check_rows_not_scored`), and too few
    forecasts per lead to calibrate the spread after a failure on (the other logs' failures
    or the simulated DP losses, as :func:`_calibrate_after_stop` chooses). With other test
    logs the choice depends on the failures ``fit`` finds, and is checked after it."""
    _check_rows_not_scored(dp_only, test_is_train)
    if not test_is_train:
        return
    n_min, n_other = hybrid.calibration_config.after_stop_min_failures, len(test_arrays) - 1
    if n_min > 0 and n_other >= n_min:
        _check_calibration_count(n_other, n_intervals, *_OTHER_LOGS)
    elif calibration_scenarios > 0 and _is_packaged_gunnerus(hybrid.model.vessel):
        _check_calibration_count(calibration_scenarios, n_intervals, *_SIMULATED)


def _check_rows_not_scored(dp_only: bool, test_is_train: bool) -> None:
    """Refuse (before any training) to train on every row when the test logs are the training
    logs (no ``test``, the same logs again, or the embedded scenarios).

    Parameters
    ----------
    dp_only : bool
        The benchmark's ``dp_only``: False trains on every row, the drift after each failure too.
    test_is_train : bool
        Whether the failures scored are those of the training logs.

    Raises
    ------
    ValueError
        With ``dp_only`` False on the training logs' own drifts: the nets, the data-only
        ensemble, the wind forecast, the thrust-error prior and the held-back calibration
        would all learn from the drifts that are then scored (only the spread after a failure
        and the hull's yaw moment are chosen leave one out).
    """
    if not dp_only and test_is_train:
        raise ValueError("test: the test logs are the training logs, and training on every row (dp_only=False, "
                         "--all-rows) would learn from the drifts that are scored; give test logs other than the "
                         "training logs, or train on the station-keeping parts")


def _test_arrays(test_logs, test_names, vessel, n_intervals: int, horizon_s: float, horizons=()) -> list:
    """The test logs as LogArrays, refused (before any training) where a log has no failure to
    score: station keeping, then ``dp_active`` 0, then ``n_intervals`` starts with
    ``horizon_s`` of drift after each; where ``horizon_s`` is not a whole number of the log's
    steps (:func:`~hybridship.forecast_inputs.horizon.horizon_steps`, as a forecast refuses
    it); or where a table's horizon is not a whole number of the
    log's steps (15 s of a 2-s log), or not of the lead times, which step at the coarsest test
    log's step (a 0.6-s log beside a 1-s one)."""
    from ..predictors.after_failure import has_drift

    test_arrays = [as_log_arrays(x, vessel) for x in test_logs]
    lead_step = _lead_step_s(test_arrays)
    for a, name in zip(test_arrays, test_names):
        dt = forecast_step_s(a)         # a 10-Hz log's 0.1 s, not 0.10000000000002274
        horizon_steps(horizon_s, dt, where=f"test log {name}")   # as the forecasts count it (60.4 s was scored as 60 s)
        off = [h for h in horizons if abs(h / dt - round(h / dt)) > 1e-6]
        if off:
            raise ValueError(f"test: log {name} has a step of {dt:g} s, and the table's horizons "
                             f"{', '.join(f'{h:g}' for h in off)} s are not whole numbers of it; "
                             f"expected logs whose step divides {', '.join(f'{h:g}' for h in horizons)} s")
        if abs(lead_step / dt - round(lead_step / dt)) > 1e-6:
            raise ValueError(f"test: log {name} has a step of {dt:g} s, which does not divide the coarsest test "
                             f"log's step of {lead_step:g} s (the lead times of every log's forecasts); expected "
                             f"test logs whose steps divide one another, or logs resampled to one rate")
    bad = [name for a, name in zip(test_arrays, test_names) if not has_drift(a, n_intervals, horizon_s)]
    if bad:
        raise ValueError(f"test: {len(bad)} log(s) have no DP failure to score ({', '.join(bad[:5])}"
                         f"{', ...' if len(bad) > 5 else ''}): each needs station keeping, then dp_active 0, "
                         f"then {n_intervals} start times with {horizon_s:g} s of drift after each, before DP comes "
                         f"back on and before any gap in the log's time stamps")
    return test_arrays


def _lead_step_s(test_arrays) -> float:
    """The step of the lead times every test log is forecast and scored at [s]: the coarsest
    test log's (a finer log has a sample at each of them; the first log's 0.5 s asked a 1-s
    log for a 0.5-s lead after the training)."""
    return max(forecast_step_s(a) for a in test_arrays)


def _fit_ensembles(models: dict, train_arrays, dp_only: bool, say) -> list[dict]:
    """Fit each model on the training logs, in order; timing rows."""
    timing = []
    for name, pred in models.items():
        t0 = time.perf_counter()
        pred.fit(train_arrays, dp_only=dp_only)
        timing.append({"model": name, "what": "train", "seconds": time.perf_counter() - t0})
        say(f"trained {name} on {len(train_arrays)} logs ({timing[-1]['seconds']:.1f} s)")
    return timing


def _choose_per_log(hybrid, test_arrays, test_is_train: bool, calibration_scenarios: int, seed: int,
                    n_intervals: int, horizon_s: float, names, say):
    """What the fitted hybrid learned from failures, chosen again per test log where ``fit``
    chose it on the scored drifts, in the order each needs the one before: the yaw load
    turned with the waves (:func:`_wave_yaw_per_log`), the hull's yaw moment in a drift
    (:func:`_drift_hull_per_log`) and the spread after a failure
    (:func:`_calibrate_after_stop`). Returns timing rows and the three per-log lists (None:
    the hybrid's own for every log)."""
    t_wave, wave = _wave_yaw_per_log(hybrid, test_arrays, test_is_train, horizon_s, names, say)
    t_hull, hull = _drift_hull_per_log(hybrid, test_arrays, test_is_train, horizon_s, names, say, wave)
    t_cal, cal = _calibrate_after_stop(hybrid, test_arrays, test_is_train, calibration_scenarios, seed, n_intervals,
                                       horizon_s, say, hull, wave)
    return t_wave + t_hull + t_cal, (wave, hull, cal)


def _wave_yaw_per_log(hybrid, test_arrays, test_is_train: bool, horizon_s: float, names, say):
    """Whether each test log is forecast with the yaw load turned with the waves, with
    ``EnvironmentConfig(wave_turned_yaw_load="auto")``.

    When the test logs are other logs, or with another setting, ``fit``'s choice or the
    setting applies (returns None). When they are the training logs, ``fit`` chose on the
    drifts that are scored: each test log gets the choice made on the *other* logs' failures
    (:func:`~hybridship.residual.wave_direction.wave_yaw_choice`, on
    :meth:`~hybridship.predictors.HybridPredictor.wave_yaw_errors`), held with fewer than
    :data:`~hybridship.residual.drift_hull.MIN_FAILURES` of them. Returns timing rows and the
    list of choices (dicts).
    """
    if not (test_is_train and hybrid.chooses_wave_yaw_load):
        return [], None
    t0 = time.perf_counter()
    hybrid.wave_yaw_turned = False          # never a choice that saw the scored drifts
    usable = logs_with_drift(test_arrays, horizon_s)
    errors = hybrid.wave_yaw_errors([test_arrays[k] for k in usable], horizon_s) \
        if len(usable) >= DRIFT_HULL_MIN_FAILURES else np.empty((2, len(usable)))   # fewer: held, not read
    column = {k: i for i, k in enumerate(usable)}
    choices = [wave_yaw_choice(errors, exclude=column.get(k)) for k in range(len(test_arrays))]
    what = f"choose the yaw load turned with the waves on the other logs' failures ({len(usable)} in all), per test log"
    say(f"{what}: turned for {sum(c['turned'] for c in choices)} of {len(choices)}")
    return [{"model": "hybrid", "what": what, "seconds": time.perf_counter() - t0}], choices


def _wave_yaw_table(hybrid, per_log, names) -> pd.DataFrame:
    """``log,source,turned,n_failures,held_deg,turned_deg,n_gains,p_value``: whether each test
    log was forecast with the yaw load turned with the waves after the failure, and the
    evidence of the choice (:func:`~hybridship.residual.wave_direction.wave_yaw_choice`):
    ``source`` is ``setting`` (``wave_turned_yaw_load`` True or False), ``training logs'
    failures`` (``fit``'s choice) or ``other logs' failures`` (per test log); ``"auto"``
    where nothing is learned from failures (``drift_hull`` off) is a ``setting`` too: held."""
    cols = ["log", "source", "turned", "n_failures", "held_deg", "turned_deg", "n_gains", "p_value"]
    if per_log is None and not hybrid.chooses_wave_yaw_load:
        rows = [{"log": n, "source": "setting", "turned": hybrid.turns_yaw_load} for n in names]
    elif per_log is None:
        info = hybrid.training_info.get("wave_yaw_load") or {}
        rows = [{**info, "log": n, "source": "training logs' failures", "turned": hybrid.turns_yaw_load}
                for n in names]
    else:
        rows = [{**c, "log": n, "source": "other logs' failures"} for n, c in zip(names, per_log)]
    return pd.DataFrame(rows, columns=cols).astype({"turned": bool, "n_failures": "Int64", "n_gains": "Int64",
                                                    "held_deg": float, "turned_deg": float, "p_value": float})


def _drift_hull_per_log(hybrid, test_arrays, test_is_train: bool, horizon_s: float, names, say, per_log_wave=None):
    """The hull's yaw coefficient in a drift (:mod:`hybridship.residual.drift_hull`) per test log.

    When the test logs are other logs, the one ``fit`` chose on the training logs' failures
    applies (returns None). When they are the training logs, that one has seen the drifts it
    would be scored on: each test log gets the coefficient chosen (and checked) on the
    *other* logs' failures whose drift can be scored
    (:func:`~hybridship.residual.drift_hull.drift_start_rows`), or 0 when they are fewer than
    :data:`~hybridship.residual.drift_hull.MIN_FAILURES`. Returns timing rows and the list of
    :class:`~hybridship.residual.drift_hull.DriftHullChoice` (None entries: 0). Each log's
    coefficient is chosen with the yaw load it is forecast with (``per_log_wave``, from
    :func:`_wave_yaw_per_log`, else the hybrid's own).
    """
    if not (test_is_train and hybrid.uses_drift_hull):
        return [], None
    t0 = time.perf_counter()
    hybrid.drift_yaw_uv_rad_per_m2 = 0.0                # never a coefficient that saw the scored drifts
    usable = logs_with_drift(test_arrays, horizon_s)
    if len(usable) - 1 < DRIFT_HULL_MIN_FAILURES:
        say(f"hull's yaw moment in a drift: off (fewer than {DRIFT_HULL_MIN_FAILURES} other failures per test log)")
        return [], [None] * len(test_arrays)
    turned, before = _turned_per_log(hybrid, per_log_wave, len(test_arrays)), hybrid.wave_yaw_turned
    objectives = {}
    for value in sorted(set(turned)):       # the failures' errors with the yaw load held, or turned
        hybrid.wave_yaw_turned = value
        objectives[value] = hybrid.drift_hull_objective([test_arrays[k] for k in usable], horizon_s)
    hybrid.wave_yaw_turned = before             # each log's own is set when it is forecast
    munk = munk_coefficient(hybrid.model)
    column = {k: i for i, k in enumerate(usable)}
    choices = [choose_coefficient(objectives[turned[k]], munk, exclude=column.get(k)) for k in range(len(test_arrays))]
    what = f"choose the hull's yaw moment in a drift on the other logs' failures ({len(usable)} in all), per test log"
    say(f"{what}: " + ", ".join(f"{n} {c.munk_multiple:g}x Munk{'' if c.adopted else ' (not kept)'}"
                                 for n, c in zip(names, choices)))
    return [{"model": "hybrid", "what": what, "seconds": time.perf_counter() - t0}], choices


def _turned_per_log(hybrid, per_log_wave, n_logs: int) -> list[bool]:
    """Per test log, the hybrid's :attr:`~hybridship.predictors.HybridPredictor.wave_yaw_turned`
    to forecast it with: its choice in ``per_log_wave``, else the hybrid's own."""
    return [hybrid.wave_yaw_turned] * n_logs if per_log_wave is None else [c["turned"] for c in per_log_wave]


def _drift_hull_table(hybrid, per_log, names) -> pd.DataFrame:
    """``log,source,munk_multiple,adopted,coefficient_rad_per_m2,n_failures,error_deg,
    error_zero_deg,error_left_out_deg,n_left_out_gains,p_value``: the hull's yaw coefficient in
    a drift each test log was forecast with, and the evidence it was chosen on (the failures'
    mean heading errors along their drifts with it, with 0 and left out, the left-out
    failures it helped and the signed-rank test's p-value; see
    :class:`~hybridship.residual.drift_hull.DriftHullChoice`)."""
    evidence = ("munk_multiple", "adopted", "n_failures", "error_deg", "error_zero_deg", "error_left_out_deg",
                "n_left_out_gains", "p_value")
    cols = ["log", "source", "munk_multiple", "adopted", "coefficient_rad_per_m2", *evidence[2:]]

    def row(name, source, choice: dict | None, coefficient):
        out = {"log": name, "source": source if choice else "none", "coefficient_rad_per_m2": coefficient}
        out.update({k: (choice or {}).get(k) for k in evidence})
        out["adopted"] = bool(out["adopted"])
        return out

    if per_log is None:
        info = hybrid.training_info.get("drift_hull")
        rows = [row(n, "training logs' failures", info, hybrid.drift_yaw_uv_rad_per_m2) for n in names]
    else:
        rows = [row(n, "other logs' failures", None if c is None else c.as_dict(),
                    0.0 if c is None else c.coefficient_rad_per_m2) for n, c in zip(names, per_log)]
    return pd.DataFrame(rows, columns=cols).astype({"n_failures": "Int64", "n_left_out_gains": "Int64",
                                                    "p_value": float})


def _calibrate_after_stop(hybrid, test_arrays, test_is_train: bool, calibration_scenarios: int, seed: int,
                          n_intervals: int, horizon_s: float, say, per_log_hull=None,
                          per_log_wave=None) -> tuple[list[dict], list | None]:
    """The hybrid's spread after a failure, calibrated on the vessel's own failures where the
    training logs have enough of them, else on simulated DP losses (Gunnerus only).

    ``fit`` calibrates on the training logs' failures itself (``after_stop_min_failures``);
    when the test logs are the training logs, that calibration has seen the drifts it is
    scored on, so each test log gets one fitted on the *other* logs' failures instead
    (returned per log; None: one calibration for all), from forecasts with the hull's yaw
    coefficient and the yaw load that log is scored with (``per_log_hull``, ``per_log_wave``);
    on simulated DP losses, one per yaw load of the test logs. Returns timing rows and that list.
    """
    timing, t0 = [], time.perf_counter()
    n_min = hybrid.calibration_config.after_stop_min_failures
    own = hybrid.training_info.get("calibration", {}).get("after_stop", {}).get("source")
    if own and not test_is_train:
        n_own = hybrid.training_info["calibration"]["after_stop"]["n_logs"]
        say(f"spread after a failure calibrated on the training logs' {n_own} failures")
        return timing, None
    if test_is_train:
        # the calibration of later starts that fit made on the training logs has seen the
        # scored drifts (the benchmark scores the first intervals, which it does not calibrate)
        hybrid.calibration.pop(AFTER_STOP_LATE, None)
    if test_is_train and n_min > 0 and len(test_arrays) - 1 >= n_min:
        _check_calibration_count(len(test_arrays) - 1, n_intervals, *_OTHER_LOGS)
        coefficients = [hybrid.drift_yaw_uv_rad_per_m2 if c is None else c.coefficient_rad_per_m2
                        for c in (per_log_hull or [None] * len(test_arrays))]
        settings = list(zip(coefficients, _turned_per_log(hybrid, per_log_wave, len(test_arrays))))
        errors, per_log, before = {}, [], hybrid.wave_yaw_turned
        for k, setting in enumerate(settings):
            if setting not in errors:           # the logs' errors with this log's coefficient and yaw load
                hybrid.drift_yaw_uv_rad_per_m2, hybrid.wave_yaw_turned = setting
                errors[setting] = hybrid.after_stop_errors(test_arrays, n_intervals=n_intervals, horizon_s=horizon_s)
            per_log.append(after_stop_scales(errors[setting][:k] + errors[setting][k + 1:], hybrid.calibration_config))
        # each log's own is set when it is forecast
        hybrid.drift_yaw_uv_rad_per_m2, hybrid.wave_yaw_turned = 0.0, before
        what = f"calibrate after stop on the other {len(test_arrays) - 1} logs' failures, per test log"
        timing.append({"model": "hybrid", "what": what, "seconds": time.perf_counter() - t0})
        say(f"{what} ({timing[-1]['seconds']:.1f} s)")
        return timing, per_log
    hybrid.calibration.pop("after_stop", None)      # never a calibration that saw the scored drifts
    if calibration_scenarios > 0 and _is_packaged_gunnerus(hybrid.model.vessel):
        from ..sim.scenario import embedded_scenarios

        _check_calibration_count(int(calibration_scenarios), n_intervals, *_SIMULATED)

        sims = embedded_scenarios(int(calibration_scenarios), seed + 1000)
        turned, before = _turned_per_log(hybrid, per_log_wave, len(test_arrays)), hybrid.wave_yaw_turned
        per_setting = {}
        for value in sorted(set(turned)):       # with the yaw load each test log is forecast with
            hybrid.wave_yaw_turned = value
            hybrid.calibrate_after_stop([s.log for s in sims], n_intervals=n_intervals, horizon_s=horizon_s)
            per_setting[value] = hybrid.calibration[AFTER_STOP]
        hybrid.wave_yaw_turned = before
        what = f"calibrate after stop on {len(sims)} simulated DP losses"
        timing.append({"model": "hybrid", "what": what + (", per yaw load" if len(per_setting) > 1 else ""),
                       "seconds": time.perf_counter() - t0})
        say(f"calibrated the hybrid's spread after a failure on {len(sims)} simulated DP losses "
            f"({timing[-1]['seconds']:.1f} s)")
        return timing, None if len(per_setting) == 1 else [per_setting[t] for t in turned]
    if calibration_scenarios > 0:
        say(f"no simulated DP losses for vessel {hybrid.model.vessel.name!r} (they are made for the packaged "
            f"Gunnerus): the spread after a failure is raw")
    return timing, None


def _is_packaged_gunnerus(vessel) -> bool:
    """The packaged Gunnerus file, by its parameters (a user's file that kept the name is not)."""
    from ..vessel import fingerprint, load_vessel

    return fingerprint(vessel) == fingerprint(load_vessel("gunnerus"))


def _check_calibration_count(n_failures: int, n_intervals: int, source: str, advice: str) -> None:
    """Refuse (before the calibration's forecasts) too few forecasts per lead to fit a scale on."""
    from ..residual.calibration import MIN_CALIBRATION_SAMPLES

    if n_failures * n_intervals < MIN_CALIBRATION_SAMPLES:
        raise ValueError(f"n_intervals: {n_intervals} forecasts after each of {n_failures} failures ({source}) "
                         f"give {n_failures * n_intervals} per lead; the spread after a failure needs at least "
                         f"{MIN_CALIBRATION_SAMPLES} to calibrate ({advice})")


def _benchmark_models(vessel, hybrid, data_only) -> dict:
    """Table name -> (forecaster, forecast keyword arguments), in table order."""
    # The same fitted nets with the earlier environment (the 900-s mean residual): a shallow
    # copy that differs only in where the environment comes from, so no second training.
    mean_bias = copy.copy(hybrid)
    mean_bias.environment = "mean"
    # its spread after a failure stays raw: the after-stop scale was fitted for the estimator
    mean_bias.calibration = {k: v for k, v in hybrid.calibration.items() if k not in (AFTER_STOP, AFTER_STOP_LATE)}
    # the paper's scheme: the nets unguarded, and on after the failure too; its spread stays
    # raw: the after-stop scale was fitted on forecasts with the nets off after a failure
    unguarded = {"guard": False, "nets_after_stop": True, "calibrated": False}
    return {"hybrid": (hybrid, {"guard": True}), "hybrid_nets_unguarded": (hybrid, unguarded),
            "hybrid_mean_bias": (mean_bias, {"guard": True}),
            "dynamic": (DynamicPredictor(vessel), {}), "dead_reckoning": (DeadReckoning(vessel), {}),
            "data_only": (data_only, {})}


def _forecast_after_failures(predictors: dict, test_arrays, n_intervals: int, horizon_s: float, horizons,
                             hybrid=None, per_log_cal=None, per_log_hull=None, per_log_wave=None):
    """Every model's forecasts after the failure of every test log (the ``hybrid`` object with
    the after-stop calibration ``per_log_cal[k]``, the hull's yaw coefficient in a drift of
    ``per_log_hull[k]`` and the yaw load turned with the waves as ``per_log_wave[k]`` chose
    for log ``k`` when given).

    Returns ``fc`` (name -> per log ``(pred, truth, std)``), every lead time ``all_h`` [s], the
    indices ``pick`` of the table's ``horizons`` among them, and timing rows.
    """
    dt = _lead_step_s(test_arrays)
    all_h = tuple(round(k * dt, 9) for k in range(1, int(round(horizon_s / dt)) + 1))
    pick = [int(round(h / dt)) - 1 for h in horizons]       # whole steps (_test_arrays checked)
    fc, timing = {}, []
    for name, (pred, kw) in predictors.items():
        t0 = time.perf_counter()
        fc[name] = []
        for k, a in enumerate(test_arrays):
            if per_log_cal is not None and pred is hybrid:
                pred.calibration[AFTER_STOP] = per_log_cal[k]
            if per_log_hull is not None and pred is hybrid:
                c = per_log_hull[k]
                pred.drift_yaw_uv_rad_per_m2 = 0.0 if c is None else c.coefficient_rad_per_m2
            if per_log_wave is not None and pred is hybrid:
                pred.wave_yaw_turned = per_log_wave[k]["turned"]
            fc[name].append(metrics.drift_forecasts(pred, a, n_intervals=n_intervals, horizons_s=all_h, **kw))
        sec = time.perf_counter() - t0
        timing.append({"model": name, "what": f"forecast {len(test_arrays) * n_intervals} x {horizon_s:g} s",
                       "seconds": sec})
    return fc, all_h, pick, timing


def _coverage_tables(fc: dict, pick, horizons, n_logs: int, seed: int):
    """``coverage.csv``, ``coverage_intervals.csv`` and ``coverage_heading.csv`` (the heading
    at 1 and 2 sigma, each with its interval over the failures)."""
    heading = pd.concat([_coverage_intervals(fc, pick, horizons, seed, sigma=k, state="heading")
                         for k in (1.0, 2.0)], ignore_index=True)
    return _coverage_table(fc, pick, horizons, n_logs), _coverage_intervals(fc, pick, horizons, seed), heading


def _coverage_table(fc: dict, pick, horizons, n_logs: int) -> pd.DataFrame:
    """Coverage of the ensemble models' spread at 1 and 2 sigma (north and east pooled), and with
    two or more test logs the leave-one-log-out calibrated spread's (``<model>_loo_calibrated``)."""
    cov_rows = []
    for name in ENSEMBLE_MODELS:
        P = np.stack([p[:, pick] for p, _, _ in fc[name]])
        T = np.stack([t[:, pick] for _, t, _ in fc[name]])
        S = np.stack([s[:, pick] for _, _, s in fc[name]])
        cov_rows += _coverage_rows(name, metrics.coverage(P, T, S), horizons)
        if n_logs >= 2:
            cov_rows += _coverage_rows(name + "_loo_calibrated",
                                       metrics.coverage(P, T, _loo_calibrated_spread(P, T, S, len(horizons))),
                                       horizons)
    return pd.DataFrame(cov_rows)


def _coverage_intervals(fc: dict, pick, horizons, seed: int, sigma: float = 2.0,
                        state: str = "position") -> pd.DataFrame:
    """Coverage at ``sigma`` (default 2) of the ensemble models' spread of ``state`` (north and
    east pooled, or the heading) with a 90 % interval over the failures (one per log)."""
    rows = []
    for name in ENSEMBLE_MODELS:
        P = np.stack([p[:, pick] for p, _, _ in fc[name]])
        T = np.stack([t[:, pick] for _, t, _ in fc[name]])
        S = np.stack([s[:, pick] for _, _, s in fc[name]])
        ci = metrics.coverage_interval(P, T, S, sigma, seed=seed, state=state)
        rows += [{"model": name, "horizon_s": h, "sigma": sigma, "coverage": ci[j, 0], "low": ci[j, 1],
                  "high": ci[j, 2], "n_failures": P.shape[0]} for j, h in enumerate(horizons)]
    return pd.DataFrame(rows)


def _coverage_rows(name: str, c: np.ndarray, horizons) -> list[dict]:
    """Rows ``model, horizon_s, sigma, coverage`` from coverages ``c`` (horizon, sigma 1 and 2)."""
    return [{"model": name, "horizon_s": h, "sigma": sig, "coverage": float(c[j, k])}
            for j, h in enumerate(horizons) for k, sig in enumerate((1, 2))]


def _loo_calibrated_spread(P, T, S, n_horizons: int) -> np.ndarray:
    """Leave-one-log-out spread calibration: scale each log's spread by the factor that gives
    1-sigma coverage on the OTHER logs' drifts (per horizon)."""
    z = np.abs(P - T)[..., :2] / np.maximum(S[..., :2], 1e-12)          # (L, S, nh, 2)
    Scal = np.empty_like(S)
    for i in range(P.shape[0]):
        others = np.delete(z, i, axis=0)
        k = np.quantile(np.moveaxis(others, 2, 0).reshape(n_horizons, -1), 0.6827, axis=1)
        Scal[i] = S[i] * k[None, :, None]
    return Scal


def _logs(spec, field: str):
    """(logs, names) from a folder path or a list of paths/DataFrames/LogArrays; a TypeError
    naming ``field`` for anything else (a DataFrame was iterated by its column names, each
    read as a file: "time_s: unsupported file extension"), a ValueError for an empty list."""
    if isinstance(spec, (str, Path)):
        files = log_files(Path(spec))
        return list(files), [f.name for f in files]
    if isinstance(spec, pd.DataFrame) or not np.iterable(spec):
        raise TypeError(f"{field}: expected a folder of logs or a list of logs (paths, DataFrames or LogArrays), "
                        f"got {type(spec).__name__}; give one log as a list of one")
    items = list(spec)
    if not items:       # failed in max()'s words ("arg is an empty sequence"), or fit's after the folder was made
        raise ValueError(f"{field}: expected one or more logs, got an empty list")
    names = [str(getattr(x, "name", f"log{i}")) for i, x in enumerate(items)]
    # per-log outputs are keyed by name: two logs of one name (files of one name in two
    # folders) get their position appended rather than being merged
    return items, [f"{n}#{i}" if names.count(n) > 1 else n for i, n in enumerate(names)]


def _recorded(path: Path) -> Path:
    """``path``, just written, added to its folder's record of hybridship's outputs: a run
    interrupted before its last file leaves files a rerun may replace, not ones it refuses
    as a user's."""
    record_outputs(path.parent, [path.name])
    return path


def _write_csv(path: Path, df: pd.DataFrame) -> Path:
    return _recorded(atomic_write(path, lambda fh: fh.write(df.to_csv(index=False, float_format="%.6g")
                                                            .encode("utf-8"))))


def _md_table(df: pd.DataFrame) -> str:
    return markdown_table(df.reset_index())


def _per_log_errors(errors: dict, test_names, horizons, windows) -> pd.DataFrame:
    """Table 2's cells for each test log alone: ``model,log,state,window,horizon_s,mae``."""
    tables = [metrics.error_table({m: [per_log[k]] for m, per_log in errors.items()}, horizons_s=horizons,
                                  windows=windows).assign(log=name) for k, name in enumerate(test_names)]
    return pd.concat(tables, ignore_index=True)[["model", "log", "state", "window", "horizon_s", "mae"]]


def ratio_table(per_log: pd.DataFrame, model: str = "hybrid", reference: str = "dynamic",
                horizon_s: float | None = None) -> pd.DataFrame:
    """``model``'s error as a ratio to ``reference``'s for each log of an ``errors_per_log.csv``
    table, at ``horizon_s`` [s] (default: the longest).

    Returns a frame indexed by ``(log, state)`` (logs in their order) with one column per
    window (number of intervals); NaN or inf where the reference error is zero or missing.
    Averaging the rows of several logs into one ``log`` first gives the ratio of a group.

    Raises
    ------
    ValueError
        Naming ``model``, ``reference`` or ``horizon_s`` when the table has no rows of it
        (a pandas KeyError naming the model, even for a horizon that was missing).
    """
    for name, m in (("model", model), ("reference", reference)):
        if m not in set(per_log["model"]):
            raise ValueError(f"{name}: {m!r} is not in the table; it has {list(dict.fromkeys(per_log['model']))}")
    if horizon_s is not None and horizon_s not in set(per_log["horizon_s"]):
        raise ValueError(f"horizon_s: {horizon_s!r} s is not in the table; it has "
                         f"{', '.join(f'{x:g}' for x in sorted(set(per_log['horizon_s'])))} s")
    h = per_log.horizon_s.max() if horizon_s is None else horizon_s
    d = per_log[per_log.horizon_s == h].pivot_table(index=["log", "state", "window"], columns="model",
                                                    values="mae", sort=False)
    ratio = (d[model] / d[reference]).unstack("window")
    return ratio.reindex(pd.MultiIndex.from_product([list(dict.fromkeys(per_log.log)), list(metrics.STATES)],
                                                    names=["log", "state"])).dropna(how="all")


def ratio_cells(ratio: pd.DataFrame) -> pd.DataFrame:
    """A :func:`ratio_table` as text cells ``"first/last window"`` (one window: one number;
    ``n/a`` without a finite ratio), rows log, columns state."""
    fmt = lambda x: f"{x:.2f}" if np.isfinite(x) else "n/a"  # noqa: E731
    lo, hi = ratio.columns[0], ratio.columns[-1]
    text = ratio[lo].map(fmt) if lo == hi else (ratio[lo].map(fmt) + "/" + ratio[hi].map(fmt)).replace("n/a/n/a", "n/a")
    cells = text.unstack("state")
    return cells.reindex(index=list(dict.fromkeys(ratio.index.get_level_values("log"))),
                         columns=[s for s in metrics.STATES if s in cells.columns])


def _per_log_markdown(per_log: pd.DataFrame, model: str = "hybrid", reference: str = "dynamic") -> str:
    """``model``'s error as a ratio to ``reference``'s for each log, at the longest horizon."""
    ratio = ratio_table(per_log, model, reference)
    lo, hi = ratio.columns[0], ratio.columns[-1]
    finite = np.isfinite(ratio.to_numpy())
    worse = int((ratio.to_numpy()[finite] > 1).sum())
    na = "" if finite.all() else f"; {int((~finite).sum())} without a ratio (n/a)"
    return (f"\n### Per failure: `{model}` as a ratio to `{reference}` at {per_log.horizon_s.max():g} s "
            f"(first {lo} / first {hi} intervals)\n\nAbove 1: worse than `{reference}` on that failure ({worse} of "
            f"{int(finite.sum())} log/state/window ratios{na}; errors of every log and cell in "
            f"`errors_per_log.csv`).\n\n" + _md_table(ratio_cells(ratio)))


def _paper_tables(long: pd.DataFrame, windows) -> tuple:
    """``(table2, table3, ratio)``: the paper's Table 2, its Table 3 per model of
    :data:`TABLE3_MODELS` and the hybrid's ratio to the physics; with one window, Table 2
    with one error per cell, no Table 3 and no ratio."""
    if len(windows) != 2:
        return metrics.paper_table(long, windows=windows), {}, None
    return (metrics.paper_table(long, windows=windows),
            {m: metrics.reduction_table(long, m, windows=windows) for m in TABLE3_MODELS},
            metrics.pooled_ratio_table(long, "hybrid", windows=windows))


def _markdown(table2, table3, ratio, coverage, intervals, timing, test_names, n_train, ens_cfg, n_intervals,
              windows, per_log=None, heading_cov=None) -> str:
    # No top-level heading: the file reads on its own and is also included in the docs pages.
    parts = [f"Drift benchmark. Test logs: {', '.join(test_names)}; trained on {n_train} logs; "
             f"{ens_cfg.n_members}-member ensembles, seed {ens_cfg.seed}; {n_intervals} forecasts after each "
             f"failure.\n",
             f"### Table 2: mean absolute error ({' / '.join(f'first {w}' for w in windows)} intervals)\n\n"
             "North and east in m, yaw in deg.\n",
             _md_table(table2)]
    for m, t in table3.items():
        parts += [f"\n### Table 3: % error reduction of `{m}` relative to `dynamic` (5/20)\n", _md_table(t)]
    if ratio is not None:
        parts.append(ratio_markdown(ratio))
    parts.append(_coverage_markdown(coverage))
    ci = intervals.assign(cell=[_interval_cell(c, lo, hi) for c, lo, hi in
                                zip(intervals.coverage, intervals.low, intervals.high)])
    ci = ci.pivot_table(index="model", columns="horizon_s", values="cell", aggfunc="first")
    ci.columns = [f"{c:g} s" for c in ci.columns]
    parts += [f"\n2-sigma coverage with a 90 % interval that resamples whole failures "
              f"({int(intervals.n_failures.iloc[0])} here; the starts after one failure share one outcome):\n",
              _md_table(ci)]
    if heading_cov is not None:
        parts.append(_heading_coverage_markdown(heading_cov))
    if per_log is not None and per_log.log.nunique() > 1 and {"hybrid", "dynamic"} <= set(per_log.model) \
            and per_log.window.nunique() > 1:
        parts.append(_per_log_markdown(per_log))
    elif per_log is not None:
        parts.append("\n(No per-failure table: it needs two or more test logs and both windows; the cells of "
                     "each log are in `errors_per_log.csv`.)\n")
    parts += ["\n### Wall time [s]\n", _md_table(timing.assign(seconds=timing.seconds.round(2)).set_index("model"))]
    return "\n".join(parts) + "\n"


def ratio_markdown(ratio: pd.DataFrame) -> str:
    """``tables.md``'s block of :func:`~hybridship.evaluation.metrics.pooled_ratio_table` for ``hybrid``."""
    return ("\n### `hybrid` as a ratio to `dynamic` (5/20)\n\nMean absolute error of `hybrid` over that of "
            "`dynamic` on the same starts; below 1 is better than the physics alone.\n\n" + _md_table(ratio))


def _coverage_markdown(coverage: pd.DataFrame) -> str:
    """The coverage at 1 and 2 sigma for each model and horizon, to two decimals."""
    cov = coverage.pivot_table(index=["model", "sigma"], columns="horizon_s", values="coverage")
    cov.columns = [f"{c:g} s" for c in cov.columns]
    # Python's round, as the f-strings of the interval tables below round: pandas' round
    # scales by 100 first and gave 0.98 where the interval table showed the same 0.975 as 0.97.
    return ("\n### Coverage of the ensemble spread (north and east pooled)\n\nA calibrated Gaussian forecast "
            "covers 0.683 (1 sigma) and 0.954 (2 sigma).\n\n" + _md_table(cov.map(lambda x: round(x, 2))))


def _interval_cell(coverage: float, low: float, high: float) -> str:
    """A coverage with its interval over the failures, "0.95 [0.90, 1.00]", or "0.95 [n/a]" where
    there is no interval (one failure: nothing to resample)."""
    if np.isfinite(low) and np.isfinite(high):
        return f"{coverage:.2f} [{low:.2f}, {high:.2f}]"
    return f"{coverage:.2f} [n/a]"


def _heading_coverage_markdown(heading_cov: pd.DataFrame) -> str:
    """The heading's coverage at 1 and 2 sigma, each with its interval over the failures."""
    hc = heading_cov.assign(cell=[_interval_cell(c, lo, hi) for c, lo, hi in
                                  zip(heading_cov.coverage, heading_cov.low, heading_cov.high)])
    hc = hc.pivot_table(index=["model", "sigma"], columns="horizon_s", values="cell", aggfunc="first")
    hc.columns = [f"{c:g} s" for c in hc.columns]
    return ("\n### Coverage of the ensemble's heading spread\n\nThe heading's errors (wrapped to +-180 deg) "
            "against its own spread, with the same 90 % interval over the failures:\n\n" + _md_table(hc))


def _figures(out: Path, plots: bool, fc: dict, all_h, test_arrays, test_names) -> dict:
    """The figures; without ``plots`` none, and an earlier run's removed from ``out`` (they
    would sit beside these tables as if they belonged to them)."""
    if not plots:
        remove_stale(out, FIGURE_FILES)
        return {}
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colors = {"hybrid": "tab:red", "hybrid_nets_unguarded": "tab:orange", "hybrid_mean_bias": "tab:purple",
              "dynamic": "tab:blue", "dead_reckoning": "tab:gray", "data_only": "tab:green"}
    lead = np.asarray(all_h)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharex=True)
    for name, per_log in fc.items():
        err = np.concatenate([np.hypot(*(p - t)[..., :2].transpose(2, 0, 1)) for p, t, _ in per_log])  # (starts, H)
        for row in err:
            axes[0].plot(lead, row, color=colors[name], alpha=0.08, lw=0.6)
        axes[0].plot(lead, err.mean(0), color=colors[name], lw=2, label=name)
        axes[1].plot(lead, np.median(err, 0), color=colors[name], lw=2, label=name)
    axes[0].set(xlabel="lead time [s]", ylabel="position error [m]", title="every start time (thin) and mean")
    axes[1].set(xlabel="lead time [s]", ylabel="median position error [m]", title="median over start times")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    p1 = _recorded(atomic_write(out / "error_vs_horizon.png", lambda fh: fig.savefig(fh, format="png", dpi=110)))
    plt.close(fig)

    a = test_arrays[0]
    i0 = metrics.shutdown_index(a)
    H = int(round(all_h[-1] / forecast_step_s(a)))     # the longest lead in this log's rows
    fig, ax = plt.subplots(figsize=(6.5, 6))
    track = a.eta[i0: i0 + H + 5]
    ax.plot(track[:, 1], track[:, 0], "k-", lw=2, label="measured")
    for name in ("hybrid", "dynamic", "data_only"):
        p, _, s = fc[name][0]
        for k in range(min(5, p.shape[0])):
            ax.plot(p[k, :, 1], p[k, :, 0], color=colors[name], lw=1, label=name if k == 0 else None)
            if s is not None and name == "hybrid":
                ax.errorbar(p[k, -1, 1], p[k, -1, 0], xerr=s[k, -1, 1], yerr=s[k, -1, 0], color=colors[name],
                            capsize=2, lw=0.8)
    ax.plot(track[0, 1], track[0, 0], "ko")
    ax.set(xlabel="east [m]", ylabel="north [m]", title=f"first 5 forecasts after the failure: {test_names[0]}")
    ax.axis("equal")
    ax.legend(fontsize=8)
    fig.tight_layout()
    p2 = _recorded(atomic_write(out / "trajectories.png", lambda fh: fig.savefig(fh, format="png", dpi=110)))
    plt.close(fig)
    return {"error_vs_horizon.png": p1, "trajectories.png": p2}
