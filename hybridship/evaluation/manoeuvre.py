"""Manoeuvring benchmark on free-running model tests (issue 6: the tanker Esso Osaka).

Train on the runs of one folder, test on the runs of another (never the same run), and
forecast from every start time (every ``start_every_s``; every sample with
``start_every_s=None``) ``horizons_s`` ahead. Two command modes:

* ``known``: the logged future propeller and rudder commands are fed to the forecast
  (a manoeuvring case: the helmsman's orders are known in advance);
* ``held``: commands held at their values at the start.

The wind's future is not known at a start: the physics, the data-only ensemble and dead
reckoning hold the wind at its start value, the hybrid uses its fitted wind forecast (a gust
decaying to the recent mean).
Errors: absolute ``x0_m``, ``y0_m`` (earth frame of the pond, used as north/east),
``heading_deg`` (wrapped) and the position ``distance_m``, averaged over all start times
of all test runs of a kind (``kind = all`` pools every start time).

Predictors: the hybrid (:class:`~hybridship.predictors.HybridPredictor`), the physics
alone (:class:`~hybridship.predictors.DynamicPredictor`), constant-velocity dead reckoning
(:class:`~hybridship.predictors.DeadReckoning`) and a data-only ensemble
(:class:`~hybridship.predictors.DataOnlyPredictor`), each through its
``forecast(..., commands="known" | "held")``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Annotated, Callable, Literal

import numpy as np
import pandas as pd
from pydantic import Field

from ..config import Bool, Float, Int, check_flags, check_number, check_whole_number, config_dataclass
from ..datasets.esso_osaka import EssoRun, RUN_KINDS, esso_log_arrays, list_runs
from ..fileio import as_path, atomic_write, check_output_files, earlier_run, lies_within, remove_stale, write_output_files
from ..frames import wrap_pi
from ..logs.ingest import ingest
from ..logs.io import LogArrays
from ..predictors.training_logs import samples_digest
from ..residual.calibration import GAUSS_COVERAGE, CalibrationConfig
from ..residual.ensemble import EnsembleConfig
from ..residual.multistep import MultiStepConfig
from ..residual.features import ALL_FEATURES, COMMAND_FEATURES, MEMORY_FEATURES, ResidualConfig
from .metrics import grouped_coverage_interval

#: Default forecast horizons [s] (model scale; x 10.4 at full scale).
HORIZONS_S = (5, 10, 20, 30)
#: Error states in ``errors.csv``.
STATES = ("x0_m", "y0_m", "heading_deg", "distance_m")
#: Exact columns of ``errors.csv``.
ERROR_COLUMNS = ("model", "kind", "state", "horizon_s", "mae", "commands")
#: Exact columns of ``coverage.csv`` (the drift benchmark's, plus kind and commands).
COVERAGE_COLUMNS = ("model", "kind", "commands", "horizon_s", "sigma", "coverage")
#: Models with a spread (a coverage row).
SPREAD_MODELS = ("hybrid", "data_only")
COMMAND_MODES = ("known", "held")
#: Order of the predictors in tables.
MODEL_ORDER = ("hybrid", "dynamic", "data_only", "dead_reckoning")

CITATION = (
    "Wakita K., Maki A., Umeda N., Miyauchi Y., Shimoji T., Rachman D.M., Akimoto Y. (2022). On neural "
    "network identification for low-speed ship maneuvering model. J. Mar. Sci. Technol. 27, 772-785. "
    "doi:10.1007/s00773-021-00867-1. Miyauchi Y., Maki A., Umeda N., Rachman D.M., Akimoto Y. (2022). "
    "System parameter exploration of ship maneuvering model for automatic docking/berthing using CMA-ES. "
    "J. Mar. Sci. Technol. 27, 1065-1083. doi:10.1007/s00773-022-00889-3. Data: "
    "github.com/NAOE-5thLab/FRT-DS-ESSO @e694dfd, CC BY-NC 4.0."
)


@config_dataclass(frozen=True)
class ManoeuvreConfig:
    """Settings of the manoeuvring benchmark (chosen before looking at test errors; validated).

    Attributes
    ----------
    start_every_s : float or None
        Spacing of forecast start times [s]; None = every sample.
    step_s : float or None
        Forecast and training step [s]; None = the data's own (0.1 s here). A larger
        step decimates the runs (every k-th sample, k = step / data step).
    residual : ResidualConfig
        Residual features and start-state windows. Chosen on a validation split of the
        training runs (never the test runs): the start state is the last sample (the
        logged velocities are already filtered and lag the positions by 0.6 s; any
        average adds lag); velocities are smoothed over 2 s for the targets (10-Hz
        differences are noise); the features are the model-predicted velocities and
        accelerations, without the paper's previous-residual input and without a
        running bias: at 10 Hz the previous residual correlates 0.98 with the next, the
        networks learn to hold it, and a held residual acceleration integrates into
        metres within 30 s. The command-aware features
        (:data:`~hybridship.residual.features.COMMAND_FEATURES`) are added: by the paper's
        sec. 3.3 criterion they change within a forecast when the commands are known, and
        on the validation split they lowered the pooled 30-s error of the multi-step hybrid
        (``benchmarks/esso_training.py``). So did the command-memory features
        (:data:`~hybridship.residual.features.MEMORY_FEATURES`, a 10-s low-pass of the rpm
        and the rudder angle minus their values), for each of three seeds, distance and heading.
    ensemble : EnsembleConfig
        Training of the residual and data-only ensembles.
    train_row_stride : int
        Train the hybrid on every k-th usable row (speed; 10-Hz rows are strongly
        correlated).
    data_only_row_stride : int
        The same for the data-only ensemble. Default 1 (every row): with every 2nd row
        its pooled 30-s error was 30 % larger, and a baseline should not be handicapped.
    guard_quantile : float
        Quantile of the training rows' Mahalanobis distances beyond which the hybrid's
        guard shrinks the learned correction (see
        :class:`~hybridship.residual.guard.EnvelopeGuard`).
    calibration : CalibrationConfig
        The hybrid's spread calibration (the last 20 % of each training run held back,
        both command modes; the benchmark sets its horizon to the longest forecast
        horizon).
    training : {"one_step", "multi_step"}
        How the hybrid's nets are trained (see :class:`~hybridship.predictors.HybridPredictor`);
        multi-step over the scored 30 s, chosen on the validation split.
    multistep : MultiStepConfig
        Settings of multi-step training: the absolute-error loss (the form of the scored
        mean errors) lowered the pooled 30-s heading error on the validation split without
        raising the distance error (``benchmarks/esso_multistep.py``).
    command_guard : bool
        Fit and apply the hybrid's command-regime guard
        (:class:`~hybridship.residual.guard.CommandRegime`); chosen on the validation split.
    hull_correction : bool
        Fit the hybrid's linear MMG-structured correction before the nets
        (:class:`~hybridship.residual.hull.HullCorrection`).
    hull_fit : {"one_step", "multi_step"}
        How that correction is identified (see :class:`~hybridship.predictors.HybridPredictor`).
    wind_samples : int
        Wind futures in the hybrid's spread (:class:`~hybridship.predictors.HybridPredictor`
        ``wind_samples``; 0: the members' spread alone). Default 8: on the validation split
        the same nets with them gave a 2-sigma band 20 % narrower at 30 s with a coverage of
        0.991 against 0.974 (interval score 2.75 m against 3.56 m; ``docs/esso-osaka.md``).
    """

    start_every_s: Annotated[Float, Field(gt=0)] | None = 1.0
    step_s: Annotated[Float, Field(gt=0)] | None = None
    residual: ResidualConfig = field(default_factory=lambda: ResidualConfig(
        features=ALL_FEATURES[:6] + COMMAND_FEATURES + MEMORY_FEATURES, deriv_window_s=2.0, start_average_s=0.1,
        bias_window_s=0.0, residual_step_s=None))        # 10-Hz rows: smoothed targets, multi-step training
    ensemble: EnsembleConfig = field(default_factory=lambda: EnsembleConfig(n_members=8, max_epochs=600))
    train_row_stride: Annotated[Int, Field(ge=1)] = 2
    data_only_row_stride: Annotated[Int, Field(ge=1)] = 1
    guard_quantile: Annotated[Float, Field(gt=0, lt=1)] = 0.99
    calibration: CalibrationConfig = field(default_factory=lambda: CalibrationConfig(horizon_s=30.0))
    training: Literal["one_step", "multi_step"] = "multi_step"
    multistep: MultiStepConfig = field(default_factory=lambda: MultiStepConfig(horizon_s=30.0, batch_starts=64,
                                                                               iterations=100, loss="absolute"))
    command_guard: Bool = True
    hull_correction: Bool = False
    hull_fit: Literal["one_step", "multi_step"] = "one_step"
    wind_samples: Annotated[Int, Field(ge=0)] = 8

    @classmethod
    def quick(cls, seed: int = 0) -> "ManoeuvreConfig":
        """A small configuration for smoke runs and tests (seconds, not minutes)."""
        base = cls()
        return replace(base, start_every_s=5.0, train_row_stride=10, data_only_row_stride=10,
                       ensemble=replace(base.ensemble, n_members=3, max_epochs=60, patience=20, seed=seed),
                       multistep=replace(base.multistep, horizon_s=5.0, iterations=5, batch_starts=16,
                                         start_every_s=5.0, val_every=5, max_val_starts=32))


@dataclass
class Run:
    """One run ready for the benchmark: its file, kind and arrays (possibly decimated)."""

    run: EssoRun
    arrays: LogArrays

    @property
    def kind(self) -> str:
        return self.run.kind

    @property
    def name(self) -> str:
        return self.run.name


# --------------------------------------------------------------------------------------
# Runs
# --------------------------------------------------------------------------------------


def _decimate(arrays: LogArrays, vessel, step_s: float | None, source=None) -> LogArrays:
    """Every k-th row of a run (``step_s`` = k data steps), with the velocities as converted;
    ``source`` (the run's file) is named in the errors."""
    if step_s is None:
        return arrays
    # the run is named: among a folder of runs, the one at another rate or too short was not
    run = "" if source is None else f" (run {source})"
    dt = arrays.dt_s
    k = int(round(step_s / dt))
    if k < 1 or abs(k * dt - step_s) > 0.01 * step_s:
        raise ValueError(f"step_s: {step_s} s is not a whole multiple of the data step {dt:g} s{run}")
    if k == 1:
        return arrays
    if len(arrays.time_s) <= k:
        raise ValueError(f"step_s: {step_s:g} s leaves fewer than two samples of a "
                         f"{arrays.time_s[-1] - arrays.time_s[0]:g}-s run{run}")
    return ingest(arrays.to_frame(derived_velocities=True).iloc[::k], vessel, purpose="fit")


def load_runs(folder, vessel, *, step_s: float | None = None) -> list[Run]:
    """Every run of the Esso Osaka format under ``folder`` (see :func:`~hybridship.datasets.esso_osaka.list_runs`).

    ``vessel`` is a Vessel or a packaged name / vessel file; ``step_s`` [s] decimates the
    runs to that step (a whole multiple of the data's; None keeps the data's own).
    """
    from ..vessel import Vessel, load_vessel

    vessel = vessel if isinstance(vessel, Vessel) else load_vessel(vessel)
    if step_s is not None:
        step_s = check_number("step_s", step_s, lo=0.0, lo_open=True)
    runs = [Run(r, ingest(_decimate(esso_log_arrays(r.path, vessel), vessel, step_s, r.path), vessel, purpose="fit"))
            for r in list_runs(folder)]
    if not runs:
        raise FileNotFoundError(f"{folder}: no runs (*.csv, *.csv.gz) found")
    return runs


def validation_split(benchmark_split_dir, out_dir, *, seed: int = 1) -> tuple[Path, Path]:
    """The developers' validation split: the benchmark's training runs
    (``benchmark_split_dir/train``, made by ``benchmarks/esso_osaka.py``) split again with
    :func:`split_runs` into fitting runs (``out_dir/train``) and validation runs
    (``out_dir/test``), so that choices never see the test runs.

    Raises
    ------
    FileNotFoundError
        Naming the missing folder when the benchmark's split has not been made.
    """
    train = Path(benchmark_split_dir) / "train"
    if not train.is_dir():
        raise FileNotFoundError(f"{train}: not found; run benchmarks/esso_osaka.py first")
    return split_runs(train, out_dir, seed=seed)


def split_runs(data_dir, out_dir, *, test_fraction: float = 0.3, seed: int = 0) -> tuple[Path, Path]:
    """Split the runs of ``data_dir`` into ``out_dir/train`` and ``out_dir/test`` (symbolic links).

    Whole recordings go to one side (the pieces of one long random recording stay
    together); per kind, ``round(test_fraction * recordings)`` (at least one) recordings,
    drawn with ``seed``, are test runs; a kind of a single recording has none (it stays a
    training kind). The data are linked, never copied.

    Links and folders left in ``out_dir/train`` and ``out_dir/test`` by an earlier split are
    removed first.

    Raises
    ------
    TypeError
        If ``test_fraction`` is not a number (text, a bool).
    ValueError
        If ``test_fraction`` is not in (0, 1), or ``out_dir/train`` or ``out_dir/test`` is,
        holds or lies inside ``data_dir`` (clearing it would remove the runs being split).
    FileExistsError
        If ``out_dir/train`` or ``out_dir/test`` holds a file that is not a link (not made
        by a split; kept).
    """
    data_dir, out_dir = Path(data_dir), Path(out_dir)
    # a text ("0.3") passed float() and failed in round()'s words; NaN too; > 1 failed inside numpy's choice
    if check_number("test_fraction", test_fraction, lo=0.0, lo_open=True) >= 1.0:
        raise ValueError(f"test_fraction: expected a share of the recordings between 0 and 1 (exclusive), "
                         f"got {test_fraction!r}")
    check_whole_number("seed", seed)
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"out_dir: {out_dir} is a file; expected a folder for the split")
    runs = list_runs(data_dir)
    if not runs:
        raise ValueError(f"data_dir: {data_dir} holds no runs to split")
    data_real = data_dir.resolve()
    for d in (out_dir / "train", out_dir / "test"):
        d_real = d.resolve()
        if d_real == data_real or data_real in d_real.parents or d_real in data_real.parents:
            # validation_split(d, d) replaced the benchmark's links by links to themselves
            raise ValueError(f"out_dir: {d} is, holds or lies inside data_dir {data_dir}; clearing it for the "
                             f"split would remove the runs being split: give another out_dir")
        if d.exists():
            mine = [p for p in d.rglob("*") if not p.is_symlink() and p.is_file()]
            if mine:
                raise FileExistsError(f"out_dir: {mine[0]} is a file, not a link of an earlier split; a split "
                                      f"would remove it: move it or give another out_dir")
    rng = np.random.default_rng(seed)
    test = set()
    for kind in RUN_KINDS:
        recs = sorted({r.recording for r in runs if r.kind == kind})
        if len(recs) < 2:
            continue
        n_test = max(1, int(round(test_fraction * len(recs))))
        test |= set(rng.choice(recs, size=n_test, replace=False).tolist())
    dirs = (out_dir / "train", out_dir / "test")
    for d in dirs:
        if d.exists():
            for p in sorted(d.rglob("*"), reverse=True):
                if p.is_symlink() or p.is_file():
                    p.unlink()
                elif p.is_dir():
                    p.rmdir()
        d.mkdir(parents=True, exist_ok=True)
    for r in runs:
        d = dirs[1] if r.recording in test else dirs[0]
        (d / r.kind).mkdir(exist_ok=True)
        (d / r.kind / r.path.name).symlink_to(r.path.resolve())
    return dirs


# --------------------------------------------------------------------------------------
# Predictors
# --------------------------------------------------------------------------------------


def make_predictors(vessel, config: ManoeuvreConfig) -> dict[str, object]:
    """Unfitted predictors by table name."""
    from ..predictors import DataOnlyPredictor, DeadReckoning, DynamicPredictor, HybridPredictor

    rc, ec = config.residual, config.ensemble
    return {
        # The manoeuvre hybrid keeps the mean residual of its runs as its environment: the
        # environment estimator is built for station keeping and drift, and on the Esso
        # validation runs (Froude-scaled) it made the hybrid worse (docs/esso-osaka.md).
        "hybrid": HybridPredictor(vessel, residual_config=rc, ensemble_config=ec,
                                  guard_quantile=config.guard_quantile, environment="mean",
                                  calibration_config=config.calibration,
                                  training=config.training, multistep_config=config.multistep,
                                  command_guard=config.command_guard, hull_correction=config.hull_correction,
                                  hull_fit=config.hull_fit, wind_samples=config.wind_samples),
        "dynamic": DynamicPredictor(vessel, residual_config=rc),
        "data_only": DataOnlyPredictor(vessel, ensemble_config=ec, start_average_s=rc.start_average_s),
        "dead_reckoning": DeadReckoning(vessel, start_average_s=rc.start_average_s),
    }


def _fit(name, predictor, runs: list[Run], config: ManoeuvreConfig):
    """Fit on the training runs (the learned models on every k-th row, see :class:`ManoeuvreConfig`)."""
    import torch

    torch.set_num_threads(1)
    logs = [r.arrays for r in runs]
    stride = {"hybrid": config.train_row_stride, "data_only": config.data_only_row_stride}
    if name in stride:
        return predictor.fit(logs, row_stride=stride[name])
    return predictor.fit(logs)


# --------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------


def start_rows(arrays: LogArrays, horizon_steps: int, start_every_s: float | None, warmup_s: float = 3.0):
    """Start rows: every ``start_every_s`` after a warm-up, leaving ``horizon_steps`` of measurements.

    A start is kept only where its warm-up and its whole horizon lie in one gap-free
    segment of the log (``segment_id``), so that the measurement ``horizon_steps`` rows later
    is the one ``horizon_steps`` sample steps later (a gap of missing rows would otherwise
    score a forecast against the truth of a later time).
    """
    horizon_steps = check_whole_number("horizon_steps", horizon_steps, 1)
    if start_every_s is not None:
        start_every_s = check_number("start_every_s", start_every_s, lo=0.0, lo_open=True)
    warmup_s = check_number("warmup_s", warmup_s, lo=0.0)
    t = arrays.time_s
    if len(t) < 2:                      # no step to start from
        return np.zeros(0, int)
    dt = float(np.median(np.diff(t)))
    stride = 1 if start_every_s is None else max(1, int(round(start_every_s / dt)))
    first = int(round(warmup_s / dt))
    last = len(t) - 1 - horizon_steps
    if last < first:
        return np.zeros(0, int)
    rows = np.arange(first, last + 1, stride)
    seg = np.asarray(arrays.segment_id)
    same = (seg[rows] == seg[rows + horizon_steps]) & (seg[rows - first] == seg[rows])
    on_time = np.abs(t[rows + horizon_steps] - t[rows] - horizon_steps * dt) <= 0.5 * dt
    return rows[same & on_time]


def forecast_errors(forecast: Callable, arrays: LogArrays, rows: np.ndarray, steps: np.ndarray,
                    return_z: bool = False, return_std: bool = False, heading_z: bool = False):
    """Absolute errors ``(S, n_horizons, 4)``: |x0|, |y0| [m], |heading| [deg], distance [m].

    With ``return_z`` also the normalised errors ``|error| / std`` of x0 and y0,
    ``(S, n_horizons, 2)`` (None when the forecast has no spread), and with ``heading_z`` a
    third column, the heading's (wrapped error over its own spread); with ``return_std``
    also the reported standard deviations of x0 and y0 [m], ``(S, n_horizons, 2)`` (or None).

    Raises
    ------
    ValueError
        Naming the first start time whose forecast (or, when asked for, its spread) is NaN
        or infinite at a scored step: such a start would make every pooled mean NaN, or
        count as a miss of the band, without a word.
    """
    dt = float(np.median(np.diff(arrays.time_s)))
    fc = forecast(arrays, arrays.time_s[rows], float(steps.max() * dt))
    _check_finite(fc.eta[:, steps], arrays.time_s[rows], "forecast")
    if (return_z or return_std) and fc.eta_std is not None:     # the spreads that are read: x0, y0 (+ heading)
        _check_finite(fc.eta_std[:, steps, :3 if heading_z else 2], arrays.time_s[rows], "forecast spread (eta_std)")
    pred = fc.eta[:, steps]
    truth = arrays.eta[rows[:, None] + steps[None, :]]
    err = np.empty(pred.shape[:2] + (4,))
    err[..., :2] = np.abs(pred[..., :2] - truth[..., :2])
    err[..., 2] = np.degrees(np.abs(wrap_pi(pred[..., 2] - truth[..., 2])))
    err[..., 3] = np.hypot(err[..., 0], err[..., 1])
    if not (return_z or return_std):
        return err
    z = std = None
    if fc.eta_std is not None:
        std = fc.eta_std[:, steps, :2]
        e = err[..., :2] if not heading_z else np.concatenate([err[..., :2], np.radians(err[..., 2:3])], axis=-1)
        sd = fc.eta_std[:, steps, :e.shape[-1]]
        with np.errstate(divide="ignore", invalid="ignore"):
            # an exact forecast with no spread is inside its band (0/0 was NaN, a miss); an
            # error with no spread is outside it (inf)
            z = np.where(e == 0.0, 0.0, e / sd)
    return (err, z, std) if return_std else (err, z)


def _check_finite(x: np.ndarray, start_times_s: np.ndarray, what: str) -> None:
    """ValueError naming the first start whose values ``x`` (S, n_horizons, k) are not all finite."""
    bad = ~np.isfinite(x).all(axis=(1, 2))
    if bad.any():
        raise ValueError(f"{what}: NaN or inf from the start time_s {start_times_s[bad][0]:g} s "
                         f"({int(bad.sum())} of {bad.size} starts); leave such starts out before scoring")


def _check_horizon_count(horizons_s, arrays, name: str, key) -> None:
    """ValueError naming ``horizons_s`` when a per-run array of ``name[key]`` (``(S, n_horizons, k)``)
    holds another number of horizons: the first ones were labelled with the horizons given and
    the rest dropped without a word (or more horizons than errors failed in numpy's IndexError)."""
    for a in arrays:
        if a is not None and np.ndim(a) == 3 and np.shape(a)[1] != len(horizons_s):
            raise ValueError(f"horizons_s: {len(horizons_s)} lead times given, but {name}[{key!r}] has "
                             f"{np.shape(a)[1]} per forecast: pass the horizons_s the errors were taken at")


def _state_z(z: np.ndarray, state: str) -> np.ndarray:
    """The normalised errors a coverage of ``state`` counts: x0 and y0, or the heading's
    (the third column of :func:`forecast_errors` with ``heading_z``)."""
    if state == "position":
        return z[..., :2]
    if state == "heading" and z.shape[-1] == 3:
        return z[..., 2:]
    raise ValueError(f"state: expected 'position', or 'heading' with heading errors (z of 3 columns), got {state!r} "
                     f"and {z.shape[-1]} columns")


def coverage_table(per_run_z: dict, runs: list[Run], horizons_s, sigmas=(1, 2),
                   state: str = "position") -> pd.DataFrame:
    """``coverage.csv`` rows: the share of x0 and y0 errors (pooled) within ``sigma`` reported
    standard deviations, per model, kind (``all`` pools) and command mode; with
    ``state="heading"`` the heading's errors against its own spread instead
    (``coverage_heading.csv``).

    ``per_run_z`` maps ``(model, commands)`` to per-run normalised errors ``(S, nh, 2)``
    (``(S, nh, 3)`` for the heading: :func:`forecast_errors` with ``heading_z``). ``sigmas``
    are band half-widths > 0 in standard deviations (an error naming sigmas otherwise).
    """
    # a sigma of 0, below 0 or NaN gave a coverage of 0 without a word, a text one numpy's error
    sigmas = tuple(check_number("sigmas", sig, lo=0.0, lo_open=True) for sig in sigmas)
    rows = []
    for (model, commands), zs in per_run_z.items():
        _check_horizon_count(horizons_s, zs, "per_run_z", (model, commands))
        kinds = {}
        for run, z in zip(runs, zs):
            if z is not None and z.size:
                kinds.setdefault(run.kind, []).append(_state_z(z, state))
        groups = {k: np.concatenate(v) for k, v in kinds.items()}
        if groups:
            groups["all"] = np.concatenate(list(groups.values()))
        for kind, z in groups.items():
            for h, horizon in enumerate(horizons_s):
                for sig in sigmas:      # an int when it is one (1.5 was written as 1)
                    label = int(sig) if float(sig).is_integer() else float(sig)
                    rows.append((model, kind, commands, float(horizon), label, float((z[:, h] <= sig).mean())))
    df = pd.DataFrame(rows, columns=list(COVERAGE_COLUMNS))
    korder = {k: i for i, k in enumerate(RUN_KINDS + ("all",))}
    return df.sort_values(by=["commands", "model", "kind", "sigma", "horizon_s"],
                          key=lambda c: c.map(korder) if c.name == "kind" else c).reset_index(drop=True)


def sharpness_table(per_run: dict, per_run_std: dict, runs: list[Run], horizons_s,
                    sigma: float = 2.0) -> pd.DataFrame:
    """``sharpness.csv`` rows: how wide the reported band is, and what it costs, per model,
    kind (``all`` pools) and command mode: the mean reported standard deviation of x0 and y0
    [m] and the mean interval score [m] of the +-``sigma`` band (Gneiting & Raftery 2007,
    eq. 43, with the band's nominal miss rate ``alpha``: ``2 sigma s + (2 / alpha) max(|e| -
    sigma s, 0)``, lower is better). Coverage says whether a band is honest; the interval
    score also rewards a narrow one, so two spreads of equal coverage can be compared.

    ``per_run`` maps ``(model, commands)`` to per-run errors ``(S, nh, 4)`` (as
    :func:`forecast_errors`), ``per_run_std`` to per-run standard deviations ``(S, nh, 2)``.
    """
    sigma = check_number("sigma", sigma)     # "2" passed float() and failed in numpy's words, True was 1
    if sigma not in GAUSS_COVERAGE:
        raise ValueError(f"sigma: expected 1 or 2 (a band of known nominal coverage), got {sigma!r}")
    alpha = 1.0 - GAUSS_COVERAGE[float(sigma)]
    rows = []
    for key, sds in per_run_std.items():
        _check_horizon_count(horizons_s, per_run[key], "per_run", key)
        _check_horizon_count(horizons_s, sds, "per_run_std", key)
        kinds: dict = {}
        for run, err, sd in zip(runs, per_run[key], sds):
            if sd is not None and sd.size:
                kinds.setdefault(run.kind, []).append((err[..., :2], sd))
        groups = {k: (np.concatenate([e for e, _ in v]), np.concatenate([d for _, d in v])) for k, v in kinds.items()}
        if groups:
            groups["all"] = tuple(np.concatenate([g[i] for g in groups.values()]) for i in (0, 1))
        for kind, (e, sd) in groups.items():
            score = 2 * sigma * sd + (2 / alpha) * np.maximum(e - sigma * sd, 0.0)
            for h, horizon in enumerate(horizons_s):
                rows.append((key[0], kind, key[1], float(horizon), int(sigma), float(sd[:, h].mean()),
                             float(score[:, h].mean())))
    df = pd.DataFrame(rows, columns=["model", "kind", "commands", "horizon_s", "sigma", "mean_std_m",
                                     "interval_score_m"])
    korder = {k: i for i, k in enumerate(RUN_KINDS + ("all",))}
    return df.sort_values(by=["commands", "model", "kind", "horizon_s"],
                          key=lambda c: c.map(korder) if c.name == "kind" else c).reset_index(drop=True)


def coverage_intervals(per_run_z: dict, horizons_s, sigma: float = 2.0, seed: int = 0,
                       state: str = "position") -> pd.DataFrame:
    """``coverage_intervals.csv`` rows: the pooled coverage at ``sigma`` (all kinds) with a 90 %
    bootstrap interval that resamples whole runs
    (:func:`~hybridship.evaluation.metrics.grouped_coverage_interval`): the starts of one run
    share its conditions, so the number of runs, not of starts, sets what a coverage can say.
    ``sigma`` > 0 (an error naming it otherwise)."""
    sigma = check_number("sigma", sigma, lo=0.0, lo_open=True)     # 0, < 0 or NaN gave a coverage of 0
    rows = []
    for (model, commands), zs in per_run_z.items():
        _check_horizon_count(horizons_s, zs, "per_run_z", (model, commands))
        zs = [_state_z(z, state) for z in zs if z is not None and z.size]
        if not zs:
            continue
        hits = np.stack([(z <= sigma).sum(axis=(0, 2)) for z in zs])          # (runs, horizons)
        ci = grouped_coverage_interval(hits, np.array([z.shape[0] * z.shape[2] for z in zs]), seed=seed)
        # sigma written as coverage.csv writes it: an int when it is one
        sig = int(sigma) if float(sigma).is_integer() else float(sigma)
        rows += [(model, commands, float(h), sig, *ci[j], len(zs)) for j, h in enumerate(horizons_s)]
    return pd.DataFrame(rows, columns=["model", "commands", "horizon_s", "sigma", "coverage", "low", "high",
                                       "n_runs"])


def error_table(per_run: dict, runs: list[Run], horizons_s) -> pd.DataFrame:
    """``errors.csv`` rows from per-run errors ``{(model, commands): [errors (S, nh, 4) per run]}``."""
    rows = []
    for (model, commands), errs in per_run.items():
        _check_horizon_count(horizons_s, errs, "per_run", (model, commands))
        kinds = {}
        for run, e in zip(runs, errs):
            if e is not None and e.size:
                kinds.setdefault(run.kind, []).append(e)
        groups = {k: np.concatenate(v) for k, v in kinds.items()}
        if groups:
            groups["all"] = np.concatenate(list(groups.values()))
        for kind, e in groups.items():
            mae = e.mean(axis=0)
            for h, horizon in enumerate(horizons_s):
                for s, state in enumerate(STATES):
                    rows.append((model, kind, state, float(horizon), float(mae[h, s]), commands))
    df = pd.DataFrame(rows, columns=list(ERROR_COLUMNS))
    order = {m: i for i, m in enumerate(MODEL_ORDER)}
    korder = {k: i for i, k in enumerate(RUN_KINDS + ("all",))}
    df = df.sort_values(by=["commands", "model", "kind", "state", "horizon_s"],
                        key=lambda c: c.map(order) if c.name == "model" else
                        (c.map(korder) if c.name == "kind" else
                         (c.map({m: i for i, m in enumerate(COMMAND_MODES)}) if c.name == "commands" else c)))
    return df.reset_index(drop=True)


# --------------------------------------------------------------------------------------
# Benchmark
# --------------------------------------------------------------------------------------


@dataclass
class BenchmarkResult:
    """Everything the benchmark computed (for figures and docs)."""

    errors: pd.DataFrame
    train: list[Run]
    test: list[Run]
    predictors: dict
    horizons_s: tuple
    config: ManoeuvreConfig
    timings_s: dict
    n_starts: dict
    coverage: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=list(COVERAGE_COLUMNS)))
    coverage_intervals: pd.DataFrame = field(default_factory=pd.DataFrame)
    sharpness: pd.DataFrame = field(default_factory=pd.DataFrame)
    coverage_heading: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=list(COVERAGE_COLUMNS)))


def _score_runs(predictors: dict, test: list[Run], steps: np.ndarray, start_every_s, timings: dict,
                progress: bool):
    """Every predictor's forecasts from the start rows of every test run, in both command
    modes: per-run errors, normalised errors and standard deviations by ``(model, commands)``
    (the last two for :data:`SPREAD_MODELS`), and the starts per run. Adds the forecast
    times to ``timings``."""
    per_run: dict = {}
    per_run_z: dict = {}
    per_run_std: dict = {}
    n_starts = {}
    for run in test:
        rows = start_rows(run.arrays, int(steps.max()), start_every_s)
        n_starts[run.name] = int(rows.size)
        for name, p in predictors.items():
            for mode in COMMAND_MODES:
                t0 = time.perf_counter()
                err, z, sd = (None, None, None) if rows.size == 0 else forecast_errors(
                    lambda a, st, h: p.forecast(a, st, horizon_s=h, commands=mode), run.arrays, rows, steps,
                    return_std=True, heading_z=True)
                per_run.setdefault((name, mode), []).append(err)
                if name in SPREAD_MODELS:
                    per_run_z.setdefault((name, mode), []).append(z)
                    per_run_std.setdefault((name, mode), []).append(sd)
                timings[f"forecast_{name}_{mode}"] = timings.get(f"forecast_{name}_{mode}", 0.0) + \
                    time.perf_counter() - t0
        if progress:
            print(f"  {run.name}: {rows.size} starts", flush=True)
    per_run = {k: v_ for k, v_ in per_run.items() if any(e is not None for e in v_)}
    return per_run, per_run_z, per_run_std, n_starts


def _test_step_s(test: list[Run]) -> float:
    """The test runs' one sample step [s]: the horizons are counted in it, so runs at another
    rate would be scored at other horizons under the same labels (refused, naming them)."""
    steps = {r.name: r.arrays.dt_s for r in test if len(r.arrays) > 1}
    if not steps:
        raise ValueError("test_dir: no test run has two samples")
    dt = next(iter(steps.values()))
    other = {name: s for name, s in steps.items() if abs(s - dt) > 1e-6 * dt}
    if other:
        name, s = next(iter(other.items()))
        raise ValueError(f"test_dir: the test runs have different sample steps ({next(iter(steps))}: {dt:g} s, "
                         f"{name}: {s:g} s); the horizons are counted in steps of one rate: resample them to "
                         f"one rate (load_runs' step_s)")
    return dt


def _checked_steps(train: list[Run], test: list[Run], horizons_s: tuple, cfg: ManoeuvreConfig) -> np.ndarray:
    """The horizons in steps of the test runs, after refusing (before any training) test runs
    that are training runs, horizons off the step grid and test runs without any start; test
    runs too short to be scored, or cut copies of training runs, are warned about."""
    both = {r.run.path.resolve() for r in train} & {r.run.path.resolve() for r in test}
    if both:
        raise ValueError(f"test_dir: {len(both)} run(s) are also in train_dir (e.g. {sorted(both)[0].name}); "
                         "train and test runs must differ")
    # a copy of a training run under another path would score the nets on what they saw. (Other
    # pieces of one recording may be split on purpose: published test sets do so.)
    same = {r.run.name for r in train} & {r.run.name for r in test}
    if same:
        raise ValueError(f"test_dir: {len(same)} run(s) have the name of a train_dir run (e.g. {sorted(same)[0]}): "
                         "a copy of a training run cannot test it; train and test runs must differ")
    from ..messages import warn_user

    for test_name, train_name in cut_copies(train, test):     # run, but said now (and in README.md)
        warn_user(f"test run {test_name} and training run {train_name} are one run, cut and uncut: its errors "
                  f"are not out-of-sample", UserWarning)
    # the same samples under another name (a copy renamed): equal digests of the parsed samples
    trained = {samples_digest(r.arrays): r.name for r in train}
    copies = [(r.name, trained[d]) for r in test if (d := samples_digest(r.arrays)) in trained]
    if copies:
        raise ValueError(f"test_dir: {len(copies)} run(s) hold the samples of a train_dir run (e.g. test run "
                         f"{copies[0][0]} is training run {copies[0][1]}): a copy of a training run cannot test it")
    dt = _test_step_s(test)
    steps = np.array([int(round(h / dt)) for h in horizons_s])
    if np.any(steps < 1):
        raise ValueError(f"horizons_s: every horizon must be at least one step ({dt:g} s)")
    for h, k in zip(horizons_s, steps):
        if abs(k * dt - h) > 1e-6 * max(h, 1.0):    # scored at k steps, it would be labelled h
            lo, hi = max(int(np.floor(h / dt)), 1), int(np.ceil(h / dt))
            raise ValueError(f"horizons_s: {h:g} s is not a whole number of steps of {dt:g} s "
                             f"(the nearest are {lo * dt:g} and {hi * dt:g} s)")
    if not any(start_rows(r.arrays, int(steps.max()), cfg.start_every_s).size for r in test):
        # checked before training: the tables would be empty
        raise ValueError(f"test_dir: no start times: no test run has a gap-free stretch as long as the 3-s "
                         f"warm-up plus the longest horizon ({max(horizons_s):g} s)")
    short = [r.run.name for r in test if not start_rows(r.arrays, int(steps.max()), cfg.start_every_s).size]
    if short:       # left out of every table: said before the work, not only as "0 starts"
        warn_user(f"{len(short)} test run(s) shorter than the 3-s warm-up plus the longest horizon "
                  f"({max(horizons_s):g} s) are not scored: {', '.join(short)}", UserWarning)
    return steps


def run_manoeuvre_benchmark(vessel, train_dir, test_dir, horizons_s=HORIZONS_S, out_dir="manoeuvre-benchmark",
                            seed: int = 0, quick: bool = False, *, config: ManoeuvreConfig | None = None,
                            command: str | None = None, figures_dir=None, progress: bool = False):
    """Train on the runs in ``train_dir``, forecast every run in ``test_dir``, write tables.

    Parameters
    ----------
    vessel : Vessel or str
        Vessel file or packaged name (``"esso_osaka_model"``).
    train_dir, test_dir : path
        Folders of runs in the Esso Osaka CSV format (searched recursively). A run found
        in both is refused (train and test must differ).
    horizons_s : sequence of float
        Forecast horizons [s].
    out_dir : path
        Where ``errors.csv`` (columns :data:`ERROR_COLUMNS`), ``coverage.csv`` (columns
        :data:`COVERAGE_COLUMNS`, the models with a spread), ``coverage_intervals.csv``,
        ``coverage_heading.csv`` (the heading's spread, the same columns), ``sharpness.csv`` (:func:`sharpness_table`) and ``README.md`` go; refused when it is
        or lies inside ``train_dir`` or ``test_dir`` (its tables would be read as runs).
    seed : int
        Seed of the ensembles.
    quick : bool
        Use :meth:`ManoeuvreConfig.quick` (a smoke run).
    config : ManoeuvreConfig, optional
        Overrides ``quick``.
    command : str, optional
        The command line to quote in the Markdown.
    figures_dir : path, optional
        Also write the figures (``esso_*.png``) there.
    progress : bool
        Print each model's training time, the starts of each test run, the pooled distance
        errors with commands known and the output folder with the total time.

    Returns
    -------
    BenchmarkResult
    """
    from ..vessel import Vessel, load_vessel

    v = vessel if isinstance(vessel, Vessel) else load_vessel(vessel)
    check_flags(quick=quick, progress=progress)
    if config is not None and not isinstance(config, ManoeuvreConfig):
        raise TypeError(f"config: expected a ManoeuvreConfig or None, got {type(config).__name__}")
    cfg = config or (ManoeuvreConfig.quick(seed) if quick else ManoeuvreConfig())
    cfg = replace(cfg, ensemble=replace(cfg.ensemble, seed=seed))
    if isinstance(horizons_s, (str, bytes)) or not np.iterable(horizons_s):
        # a text was read character by character ("15": horizons of 1 and 5 s); a number failed in the loop
        raise TypeError(f"horizons_s: expected a sequence of horizons [s], got {horizons_s!r}")
    horizons_s = tuple(check_number("horizons_s", h, lo=0.0, lo_open=True) for h in horizons_s)
    if not horizons_s:
        raise ValueError("horizons_s: need finite positive horizons [s], got none")
    if len(set(horizons_s)) != len(horizons_s):
        raise ValueError(f"horizons_s: a horizon is given twice in {horizons_s}")
    cfg = replace(cfg, calibration=replace(cfg.calibration, horizon_s=max(horizons_s)))
    check_output_folder(out_dir)
    _check_out_outside_runs(out_dir, train_dir=train_dir, test_dir=test_dir)
    train = load_runs(train_dir, v, step_s=cfg.step_s)
    test = load_runs(test_dir, v, step_s=cfg.step_s)
    steps = _checked_steps(train, test, horizons_s, cfg)

    predictors = make_predictors(v, cfg)
    timings = {}
    t_start = time.perf_counter()
    for name, p in predictors.items():
        t0 = time.perf_counter()
        _fit(name, p, train, cfg)
        timings[f"fit_{name}"] = time.perf_counter() - t0
        if progress:
            print(f"{name}: trained in {timings[f'fit_{name}']:.0f} s on {len(train)} runs", flush=True)

    per_run, per_run_z, per_run_std, n_starts = _score_runs(predictors, test, steps, cfg.start_every_s, timings,
                                                            progress)
    errors = error_table(per_run, test, horizons_s)
    coverage = coverage_table({k: v_ for k, v_ in per_run_z.items() if any(z is not None for z in v_)},
                              test, horizons_s)

    intervals = coverage_intervals({k: v_ for k, v_ in per_run_z.items() if any(z is not None for z in v_)},
                                   horizons_s, seed=cfg.ensemble.seed)
    heading = coverage_table({k: v_ for k, v_ in per_run_z.items() if any(z is not None for z in v_)},
                             test, horizons_s, state="heading")
    sharpness = sharpness_table(per_run, {k: v_ for k, v_ in per_run_std.items() if any(d is not None for d in v_)},
                                test, horizons_s)
    result = BenchmarkResult(errors, train, test, predictors, horizons_s, cfg, timings, n_starts, coverage,
                             intervals, sharpness, heading)
    _write_outputs(result, Path(out_dir), command, figures_dir)
    if progress:
        _print_summary(errors, out_dir, time.perf_counter() - t_start)
    return result


def _print_summary(errors: pd.DataFrame, out_dir, seconds: float) -> None:
    """The pooled distance errors with commands known, the output folder and the time taken."""
    pooled = errors[(errors.kind == "all") & (errors.state == "distance_m") & (errors.commands == "known")]
    print("pooled distance error [m], commands known:\n"
          + pooled.pivot_table(index="model", columns="horizon_s", values="mae").round(3).to_string(), flush=True)
    print(f"wrote {out_dir} ({seconds:.0f} s in all)", flush=True)


#: The benchmark's files in its output folder.
OUTPUT_FILES = ("errors.csv", "coverage.csv", "coverage_intervals.csv", "coverage_heading.csv", "sharpness.csv",
                "README.md")
#: A run's files from before output folders kept a record of them: its README beside them.
_EARLIER_RUN = earlier_run(OUTPUT_FILES, "README.md", b"# Manoeuvring benchmark")


def check_output_folder(out_dir) -> None:
    """Refuse, before any work, an output folder where the benchmark would replace a file no
    hybridship command wrote (FileExistsError) or a read-only one (PermissionError); a run's
    files from before folders kept a record of their outputs (its README beside them) are
    recognised; ``out_dir`` not a path (None) is a TypeError naming it."""
    check_output_files(as_path(out_dir, "out_dir"), OUTPUT_FILES, ours=_EARLIER_RUN)


def _check_out_outside_runs(out_dir, **inputs) -> None:
    """Refuse (before any work) an ``out_dir`` that is, or lies inside, one of the run folders
    ``inputs`` (name -> folder): runs are searched with their sub-folders, so its CSV tables
    would be read as runs by the next benchmark on that folder."""
    for name, folder in inputs.items():
        if lies_within(out_dir, folder):
            raise ValueError(f"out_dir: {out_dir} is or lies inside {name} {folder}, whose sub-folders are read "
                             f"for runs: its CSV tables would be read as runs; give a folder outside it")


def _write_outputs(result: BenchmarkResult, out_dir: Path, command: str | None, figures_dir) -> None:
    """The benchmark's tables, its README and (optionally) its figures."""
    md = markdown_report(result, command=command)
    tables = {"errors.csv": result.errors, "coverage.csv": result.coverage,
              "coverage_intervals.csv": result.coverage_intervals, "coverage_heading.csv": result.coverage_heading,
              "sharpness.csv": result.sharpness}
    # every file is made before the first is written: a failure leaves no mix of old and new files
    write_output_files(out_dir, {**{name: t.to_csv(index=False).encode() for name, t in tables.items()},
                                 "README.md": md.encode()}, ours=_EARLIER_RUN)
    if figures_dir is not None:
        write_figures(result, figures_dir)


# --------------------------------------------------------------------------------------
# Markdown
# --------------------------------------------------------------------------------------


def pivot(errors: pd.DataFrame, state: str, commands: str) -> pd.DataFrame:
    """MAE table: rows (kind, model), columns horizons [s]."""
    sel = errors[(errors.state == state) & (errors.commands == commands)]
    if sel.empty:
        return pd.DataFrame()
    tab = sel.pivot_table(index=["kind", "model"], columns="horizon_s", values="mae", sort=False)
    tab.columns = [f"{h:g} s" for h in tab.columns]
    return tab


def _md_table(tab: pd.DataFrame, digits: int = 3) -> str:
    if tab.empty:
        return "(no rows)\n"
    cols = ["kind", "model"] + list(tab.columns)
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    best = tab.groupby(level=0, sort=False).transform("min")
    for (kind, model), row in tab.iterrows():
        cells = []
        for c in tab.columns:
            val = f"{row[c]:.{digits}f}"
            cells.append(f"**{val}**" if np.isclose(row[c], best.loc[(kind, model), c]) else val)
        lines.append(f"| {kind} | {model} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _md_coverage(coverage: pd.DataFrame, kind: str = "all") -> str:
    """Markdown table of coverage: rows (commands, model, sigma), columns horizons."""
    sel = coverage[coverage.kind == kind]
    if sel.empty:
        return "(no rows)\n"
    tab = sel.pivot_table(index=["commands", "model", "sigma"], columns="horizon_s", values="coverage", sort=False)
    cols = ["commands", "model", "sigma"] + [f"{h:g} s" for h in tab.columns]
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for (cmd, model, sig), row in tab.iterrows():
        lines.append(f"| {cmd} | {model} | {sig} | " + " | ".join(f"{v:.3f}" for v in row.values) + " |")
    return "\n".join(lines) + "\n"


def md_spread_by_kind(coverage: pd.DataFrame, sharpness: pd.DataFrame, model: str = "hybrid",
                      commands: str = "known", sigma: int = 2) -> str:
    """Markdown of one model's spread per kind: the ``sigma`` coverage, the mean reported
    standard deviation [m] and the interval score [m] (:func:`sharpness_table`) per horizon."""
    cov = coverage[(coverage.model == model) & (coverage.commands == commands) & (coverage.sigma == sigma)]
    sh = sharpness[(sharpness.model == model) & (sharpness.commands == commands)]
    if cov.empty or sh.empty:
        return "(no rows)\n"
    horizons = sorted(cov.horizon_s.unique())
    lines = [f"{model}, commands {commands}: {sigma}-sigma coverage / mean standard deviation [m] / interval "
             f"score [m], per kind:", "",
             "| kind | " + " | ".join(f"{h:g} s" for h in horizons) + " |", "|---|" + "---|" * len(horizons)]
    c = cov.set_index(["kind", "horizon_s"]).coverage
    m = sh.set_index(["kind", "horizon_s"])
    for kind in [k for k in RUN_KINDS + ("all",) if k in set(cov.kind) & set(sh.kind)]:
        cells = [f"{c[(kind, h)]:.3f} / {m.mean_std_m[(kind, h)]:.3f} / {m.interval_score_m[(kind, h)]:.2f}"
                 for h in horizons]
        lines.append(f"| {kind} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def md_coverage_intervals(ci: pd.DataFrame) -> str:
    """Markdown of :func:`coverage_intervals`: rows (commands, model), columns horizons; a
    coverage without an interval (one test run) as "0.950 [n/a]"."""
    # the sigma the intervals were taken at (a 1-sigma table was headed "2-sigma coverage")
    sigmas = "/".join(str(s) for s in dict.fromkeys(ci.sigma))
    lines = [f"{sigmas}-sigma coverage with a 90 % interval that resamples whole runs "
             f"({int(ci.n_runs.max())} test runs; the starts of one run share its conditions):", "",
             "| commands | model | " + " | ".join(f"{h:g} s" for h in sorted(ci.horizon_s.unique())) + " |",
             "|---|---|" + "---|" * ci.horizon_s.nunique()]
    for (cmd, model), g in ci.groupby(["commands", "model"], sort=False):
        # "n/a" without an interval (one test run: nothing to resample), as the drift benchmark writes it
        cells = [f"{r.coverage:.3f} [{r.low:.2f}, {r.high:.2f}]" if np.isfinite(r.low) and np.isfinite(r.high)
                 else f"{r.coverage:.3f} [n/a]" for r in g.sort_values("horizon_s").itertuples()]
        lines.append(f"| {cmd} | {model} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def wins(errors: pd.DataFrame, model: str, other: str, state: str = "distance_m", commands: str = "known"):
    """(kind, horizon) cells where ``model`` has a lower MAE than ``other``, and the total cell count."""
    a = pivot(errors, state, commands)
    if a.empty:
        return [], 0
    cells, total = [], 0
    for kind in a.index.get_level_values(0).unique():
        if (kind, model) not in a.index or (kind, other) not in a.index:
            continue
        for c in a.columns:
            total += 1
            if a.loc[(kind, model), c] < a.loc[(kind, other), c]:
                cells.append((kind, c))
    return cells, total


def md_ratio_to_physics(errors: pd.DataFrame, commands: str = "known", model: str = "hybrid",
                        reference: str = "dynamic") -> str:
    """Markdown of ``model``'s mean error as a ratio to ``reference``'s, per kind and horizon,
    as "distance / heading" (two decimals; below 1: better than the physics alone), the form
    of the targets; "(no rows)" when either model is missing."""
    dist, head = pivot(errors, "distance_m", commands), pivot(errors, "heading_deg", commands)
    if dist.empty or head.empty:
        return "(no rows)\n"
    kinds = [k for k in dist.index.get_level_values(0).unique()
             if {(k, model), (k, reference)} <= set(dist.index) and {(k, model), (k, reference)} <= set(head.index)]
    if not kinds:
        return "(no rows)\n"
    lines = ["| kind | " + " | ".join(dist.columns) + " |", "|" + "---|" * (len(dist.columns) + 1)]
    def ratio(tab, k, c):           # "n/a" where the reference error is zero
        r = tab.loc[(k, model), c] / tab.loc[(k, reference), c] if tab.loc[(k, reference), c] > 0 else np.nan
        return f"{r:.2f}" if np.isfinite(r) else "n/a"

    for k in kinds:
        lines.append(f"| {k} | " + " | ".join(f"{ratio(dist, k, c)} / {ratio(head, k, c)}" for c in dist.columns)
                     + " |")
    return "\n".join(lines) + "\n"


def cut_copies(train: list[Run], test: list[Run]) -> list[tuple[str, str]]:
    """``(test name, train name)`` pairs that are one run cut and uncut (``<kind>_cut_<stamp>``
    is a truncated copy of ``<kind>_<stamp>`` in the Esso data set). Not refused, only reported:
    a published test set might hold such a pair, and the benchmark must still run on it."""
    from ..datasets.esso_osaka import uncut_name

    by_uncut = {uncut_name(r.run.name): r.run.name for r in train}
    return [(r.run.name, by_uncut[uncut_name(r.run.name)]) for r in test
            if by_uncut.get(uncut_name(r.run.name), r.run.name) != r.run.name]


def _unscored(result, name: str) -> str:
    """``"; not scored: ..."`` for a test run without a start time (too short), else ""."""
    return "" if result.n_starts.get(name, 0) else "; not scored: shorter than the warm-up plus the longest horizon"


def _start_spacing(start_every_s) -> str:
    """``"every 1.0 s"``, or ``"every sample"`` for ``start_every_s=None`` (not "every None s")."""
    return "every sample" if start_every_s is None else f"every {start_every_s} s"


def is_quick(config: ManoeuvreConfig) -> bool:
    """Whether ``config`` is :meth:`ManoeuvreConfig.quick` (whatever its step and calibration horizon)."""
    return config == replace(ManoeuvreConfig.quick(config.ensemble.seed), step_s=config.step_s,
                             calibration=config.calibration)


def markdown_report(result: BenchmarkResult, *, command: str | None = None) -> str:
    """The benchmark's Markdown summary (tables of MAE by kind, model and horizon)."""
    e = result.errors
    lines = ["# Manoeuvring benchmark: Esso Osaka free-running model tests", ""]
    cfg = result.config
    seed = cfg.ensemble.seed
    if is_quick(cfg):
        lines += ["**QUICK RUN** (`--quick`: a small configuration for smoke tests; these are not the "
                  "benchmark's figures).", ""]
    if command:
        lines += ["Made by:", "", "```", command, "```", ""]
    step = "the data's own" if cfg.step_s is None else f"{cfg.step_s:g} s"
    lines += [f"Seed {seed}; sample step {step}; {cfg.ensemble.n_members} ensemble members; "
              f"{cfg.training} training.", ""]
    for test_name, train_name in cut_copies(result.train, result.test):
        lines += [f"**Note:** test run `{test_name}` and training run `{train_name}` are one run, cut and uncut "
                  "(the data set's README): its errors are not out-of-sample.", ""]
    lines += [f"Train runs: {len(result.train)} ({', '.join(sorted({r.kind for r in result.train}))}); "
              f"test runs: {len(result.test)}; start times: {sum(result.n_starts.values())} "
              f"({_start_spacing(result.config.start_every_s)}); "
              f"horizons {', '.join(f'{h:g}' for h in result.horizons_s)} s.",
              "", "Test runs: " + ", ".join(f"`{r.name}` ({r.kind}{_unscored(result, r.name)})" for r in result.test),
              ""]
    for commands in COMMAND_MODES:
        for state, unit in (("distance_m", "m"), ("heading_deg", "deg")):
            lines += [f"## {state.split('_')[0]} error [{unit}], commands {commands}", "",
                      _md_table(pivot(e, state, commands), 3 if unit == "m" else 2), ""]
    for other in ("dynamic", "dead_reckoning", "data_only"):
        cells, total = wins(e, "hybrid", other)
        if total:
            lines.append(f"- hybrid below {other} (distance, known commands): {len(cells)} of {total} "
                         "kind x horizon cells")
    lines += ["", "## hybrid as a ratio to dynamic, commands known (distance / heading)", "",
              md_ratio_to_physics(e, "known").rstrip("\n")]
    if not result.coverage.empty:
        lines += ["", "## spread coverage (x0 and y0 within 1 / 2 reported standard deviations, all kinds)", "",
                  _md_coverage(result.coverage), ""]
    if not result.coverage_intervals.empty:
        lines += [md_coverage_intervals(result.coverage_intervals)]
    if not result.coverage_heading.empty:
        lines += ["", "## heading spread coverage (the heading's error within 1 / 2 of its reported standard "
                  "deviations, all kinds)", "", _md_coverage(result.coverage_heading), ""]
    if not result.sharpness.empty:
        lines += ["", md_spread_by_kind(result.coverage, result.sharpness)]
    lines += ["", "All states (x0, y0, heading, distance) are in `errors.csv`; coverage per kind in "
              "`coverage.csv`; the band's width and interval score in `sharpness.csv`.", "", "Cite: " + CITATION, ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------

_COLOURS = {"hybrid": "tab:red", "dynamic": "tab:blue", "data_only": "tab:green", "dead_reckoning": "tab:grey"}


def learned_residual(hybrid, runs: list[Run]) -> pd.DataFrame:
    """The hybrid's residual on the training rows, beside speed and rudder angle.

    Returns one row per trainable sample: ``u_m_s``, ``rudder_deg`` (the first rudder's
    angle), the measured residual ``res_*`` (body-frame acceleration the physics misses)
    and the ensemble's prediction of it ``pred_*`` (learned deviation plus bias).
    """
    from ..residual.features import prepare_log

    out = []
    K = len(hybrid.model.vessel.thrusters)
    for run in runs:
        prep = prepare_log(hybrid.model, run.arrays, hybrid.residual_config)
        rows = prep.trainable_rows()
        if rows.size == 0:
            continue
        mean, _ = hybrid.ensemble.predict(prep.features(rows))
        bias = prep.bias_body(rows - 1, run.arrays.eta[rows, 2])
        pred = mean + bias
        res = prep.residual[rows]
        delta = run.arrays.azimuth_rad[rows, K] if run.arrays.azimuth_rad.shape[1] > K else np.zeros(rows.size)
        out.append(pd.DataFrame({
            "kind": run.kind, "u_m_s": run.arrays.nu[rows, 0], "rudder_deg": np.degrees(delta),
            "res_u_m_s2": res[:, 0], "res_v_m_s2": res[:, 1], "res_r_rad_s2": res[:, 2],
            "pred_u_m_s2": pred[:, 0], "pred_v_m_s2": pred[:, 1], "pred_r_rad_s2": pred[:, 2]}))
    return pd.concat(out, ignore_index=True) if out else pd.DataFrame()


def _savefig(fig, path):
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=110, bbox_inches="tight"))


def write_figures(result: BenchmarkResult, figures_dir) -> list[Path]:
    """Figures ``esso_tracks.png``, ``esso_error_vs_horizon.png`` and ``esso_residual.png``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures_dir = Path(figures_dir)
    paths = []
    H = float(max(result.horizons_s))

    # 1. measured tracks with forecasts (known commands) overlaid, one test run per kind
    kinds = [k for k in RUN_KINDS if any(r.kind == k for r in result.test)]
    fig, axes = plt.subplots(1, len(kinds), figsize=(4.2 * len(kinds), 4.4), squeeze=False)
    for ax, kind in zip(axes[0], kinds):
        run = max((r for r in result.test if r.kind == kind), key=lambda r: len(r.arrays.time_s))
        a = run.arrays
        ax.plot(a.eta[:, 1], a.eta[:, 0], color="k", lw=1.0, label="measured")
        dt = float(np.median(np.diff(a.time_s)))
        rows = start_rows(a, int(round(H / dt)), None)
        span = rows[-1] - rows[0] if rows.size else 0
        pick = rows[np.unique(np.linspace(0, rows.size - 1, 12).round().astype(int))] if span else rows
        for name in ("dynamic", "hybrid"):
            p = result.predictors.get(name)
            if p is None or pick.size == 0:
                continue
            fc = p.forecast(a, a.time_s[pick], horizon_s=H, commands="known")
            for k in range(len(pick)):
                ax.plot(fc.eta[k, :, 1], fc.eta[k, :, 0], color=_COLOURS[name], lw=1.0, alpha=0.8,
                        label=name if k == 0 else None)
            ax.plot(fc.eta[:, 0, 1], fc.eta[:, 0, 0], "o", color="k", ms=2.5)
        ax.set_title(f"{kind}: {run.name}", fontsize=8)
        ax.set_xlabel("y0 [m]")
        ax.set_ylabel("x0 [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize=7)
    fig.suptitle(f"Measured tracks and {H:g}-s forecasts (logged commands known) from 12 starts spread over "
                 "each run", fontsize=9)
    paths.append(figures_dir / "esso_tracks.png")
    _savefig(fig, paths[-1])
    plt.close(fig)

    # 2. error vs horizon per kind
    e = result.errors
    panels = [k for k in RUN_KINDS + ("all",) if k in set(e.kind)]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.3 * len(panels), 3.2), squeeze=False, sharey=False)
    for ax, kind in zip(axes[0], panels):
        for model in MODEL_ORDER:
            for mode, ls in (("known", "-"), ("held", "--")):
                sel = e[(e.kind == kind) & (e.model == model) & (e.commands == mode) & (e.state == "distance_m")]
                if not sel.empty:
                    ax.plot(sel.horizon_s, sel.mae, ls, marker="o", ms=3, color=_COLOURS.get(model, "k"),
                            label=f"{model} ({mode})")
        ax.set_title(kind, fontsize=9)
        ax.set_xlabel("horizon [s]")
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("mean distance error [m]")
    axes[0, -1].legend(fontsize=6)
    paths.append(figures_dir / "esso_error_vs_horizon.png")
    _savefig(fig, paths[-1])
    plt.close(fig)

    # 3. learned residual against speed and rudder angle
    hyb = result.predictors.get("hybrid")
    if hyb is not None and hyb.ensemble is not None:
        df = learned_residual(hyb, result.train)
        if not df.empty:
            u_edges = np.linspace(-0.1, 0.6, 15)
            d_edges = np.linspace(-36, 36, 13)
            fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharex=True, sharey=True)
            comps = (("u_m_s2", "surge [m/s²]"), ("v_m_s2", "sway [m/s²]"), ("r_rad_s2", "yaw [rad/s²]"))
            for col, (c, label) in enumerate(comps):
                lim = None
                for row, (prefix, what) in enumerate((("res_", "measured residual"), ("pred_", "learned"))):
                    stat = _binned_mean(df["u_m_s"], df["rudder_deg"], df[prefix + c], u_edges, d_edges)
                    if lim is None:
                        lim = np.nanpercentile(np.abs(stat), 95) or 1.0
                    im = axes[row, col].pcolormesh(u_edges, d_edges, stat.T, cmap="RdBu_r", vmin=-lim, vmax=lim)
                    axes[row, col].set_title(f"{what}, {label}", fontsize=9)
                    fig.colorbar(im, ax=axes[row, col])
                axes[1, col].set_xlabel("u [m/s]")
            axes[0, 0].set_ylabel("rudder angle [deg]")
            axes[1, 0].set_ylabel("rudder angle [deg]")
            fig.suptitle("Acceleration the published physics misses on the training runs (bin means)", fontsize=10)
            paths.append(figures_dir / "esso_residual.png")
            _savefig(fig, paths[-1])
            plt.close(fig)
    if figures_dir / "esso_residual.png" not in paths:  # not an earlier run's residual beside these tracks
        remove_stale(figures_dir, ("esso_residual.png",))
    return paths


def _binned_mean(x, y, z, x_edges, y_edges, min_count: int = 20):
    """Mean of z in (x, y) bins (NaN where fewer than ``min_count`` samples)."""
    x, y, z = (np.asarray(a, float) for a in (x, y, z))
    ix = np.digitize(x, x_edges) - 1
    iy = np.digitize(y, y_edges) - 1
    ok = (ix >= 0) & (ix < len(x_edges) - 1) & (iy >= 0) & (iy < len(y_edges) - 1) & np.isfinite(z)
    shape = (len(x_edges) - 1, len(y_edges) - 1)
    s = np.zeros(shape)
    n = np.zeros(shape)
    np.add.at(s, (ix[ok], iy[ok]), z[ok])
    np.add.at(n, (ix[ok], iy[ok]), 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n >= min_count, s / n, np.nan)
