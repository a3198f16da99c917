"""Command-line interface: ``hybridship <command> ...``.

Each subcommand is two functions: ``_add_<name>(subparsers)`` declares its arguments and
sets ``func=_cmd_<name>``; ``_cmd_<name>(args) -> int`` runs it. Both are registered in
:func:`_build_parser`. Input errors are reported on stderr, one line per problem
(``hybridship <command>: error: <what is wrong>``), with exit status 2; failures while
running (I/O, bad data) exit with 1. No tracebacks for either. Output into a pipe whose
reader has left (``| head``) stops quietly with 141.

Commands
--------
simulate
    ``hybridship simulate --vessel gunnerus --scenario dp-loss --seed 3 --out sim.csv.gz``
    writes one DP-loss log (CSV, ``.csv.gz`` or Parquet by the extension);
    ``hybridship simulate --sweep --seeds 1-10 --out-dir DIR`` writes one log per seed
    and ``DIR/scenarios.csv``.
demo
    ``hybridship demo``: the main job on the embedded default. Simulates Gunnerus DP-loss
    scenarios, trains the hybrid on their station-keeping parts and prints the paper's
    15/30/45/60 s drift-error table for the hybrid, the dynamic model and dead reckoning.
train
    ``hybridship train --vessel gunnerus --logs DIR --out MODEL.npz`` trains a hybrid on the
    DP part of every log in DIR.
forecast
    ``hybridship forecast --model MODEL.npz --log FILE --start-time T --horizon-s 60 --out forecast.csv``
drift-off
    ``hybridship drift-off planning|live|season ...``: time to reach a limit radius after a
    blackout (:mod:`hybridship.driftoff.command`).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import warnings
from pathlib import Path

from .fileio import path_argument, vessel_argument
from .messages import problem_lines

__all__ = ["main", "parse_seeds"]

_PROG = "hybridship"


class UsageError(Exception):
    """Bad command-line input, exit status 2; the message has one line per problem."""


class _Parser(argparse.ArgumentParser):
    """ArgumentParser that raises instead of printing usage and exiting."""

    def error(self, message):  # noqa: D401 (argparse API)
        raise UsageError(f"{self.prog}: error: {message}")


# --------------------------------------------------------------------------- argument types


#: Most scenarios one sweep may ask for (each is a log of about an hour).
MAX_SWEEP_SEEDS = 100_000


def parse_seeds(text: str) -> list[int]:
    """Parse a seed list such as ``"1-10"``, ``"3"`` or ``"1,4,7-9"`` into ints (in order).

    Raises
    ------
    ValueError
        On malformed parts, negative seeds, reversed ranges or duplicates.
    """
    seeds: list[int] = []
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            raise ValueError(f"--seeds: empty entry in {text!r}")
        lo, sep, hi = part.partition("-")
        try:
            a = int(lo)
            b = int(hi) if sep else a
        except ValueError:
            raise ValueError(f"--seeds: {part!r} is not a seed or a range like 1-10") from None
        if a < 0 or b < a:
            raise ValueError(f"--seeds: {part!r} must be a non-negative seed or an increasing range")
        if b > MAX_SEED:
            raise ValueError(f"--seeds: {part!r}: seeds are at most {MAX_SEED}")
        if len(seeds) + b - a + 1 > MAX_SWEEP_SEEDS:
            raise ValueError(f"--seeds: {text!r} gives more than {MAX_SWEEP_SEEDS} scenarios")
        seeds.extend(range(a, b + 1))
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"--seeds: {text!r} repeats a seed")
    return seeds


#: Largest ``--seed``: every generator the commands seed (numpy, torch) takes it.
MAX_SEED = 2**32 - 1


def _whole_number_in(text: str, lo: int, hi: int) -> int:
    """``text`` as a whole number in ``lo..hi``, or argparse's error (which names the option)."""
    try:
        value = int(text)
    except ValueError:
        value = lo - 1
    if not lo <= value <= hi:
        raise argparse.ArgumentTypeError(f"expected a whole number in {lo}..{hi}, got {text!r}")
    return value


def _number_or_nan(text: str) -> float:
    """``text`` as a float, NaN where it is not a number (so that every range check fails)."""
    try:
        return float(text)
    except ValueError:
        return float("nan")


def _positive_number(text: str) -> float:
    """A finite number > 0, or argparse's error (which names the option)."""
    value = _number_or_nan(text)
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def _fraction(text: str) -> float:
    """A number in (0, 1], or argparse's error (which names the option)."""
    value = _number_or_nan(text)
    if not 0.0 < value <= 1.0:                           # NaN fails too
        raise argparse.ArgumentTypeError(f"expected a number in (0, 1], got {text!r}")
    return value


def _seed(text: str) -> int:
    """A ``--seed`` value: a whole number in 0..:data:`MAX_SEED` (argparse names the option)."""
    return _whole_number_in(text, 0, MAX_SEED)


def _members(text: str) -> int:
    """A ``--members`` value: a whole number in 1..:data:`~hybridship.residual.ensemble.MAX_MEMBERS`."""
    from .residual.ensemble import MAX_MEMBERS

    return _whole_number_in(text, 1, MAX_MEMBERS)


#: Most embedded scenarios of ``demo`` and ``benchmark drift`` (``embedded_scenarios`` makes 1..20).
MAX_EMBEDDED_SCENARIOS = 20


def _scenarios(text: str) -> int:
    """A ``--scenarios`` value: a whole number in 1..:data:`MAX_EMBEDDED_SCENARIOS`."""
    return _whole_number_in(text, 1, MAX_EMBEDDED_SCENARIOS)


def _seed_list(text: str) -> list[int]:
    try:
        return parse_seeds(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--seeds: ")) from None


# --------------------------------------------------------------------------- simulate

_SCENARIOS = ("dp-loss",)


def _add_simulate(sub) -> None:
    p = sub.add_parser(
        "simulate", help="simulate DP-loss drift scenarios and write logs",
        description="Simulate a vessel on DP that loses power and drifts; write the log(s) in the "
                    "project log format with truth_* columns. One scenario (--seed, --out) or a "
                    "sweep (--sweep --seeds, --out-dir).")
    p.add_argument("--vessel", type=vessel_argument, default="gunnerus",
                   help="packaged vessel name or vessel file (default gunnerus)")
    p.add_argument("--scenario", default="dp-loss", choices=_SCENARIOS, help="scenario type (default dp-loss)")
    p.add_argument("--seed", type=_seed, help="seed of a single scenario (non-negative)")
    p.add_argument("--out", type=path_argument, help="output log of a single scenario: .csv, .csv.gz, .parquet or .pq")
    p.add_argument("--sweep", action="store_true", help="simulate one scenario per seed of --seeds")
    p.add_argument("--seeds", type=_seed_list, help="seeds of a sweep, e.g. 1-10 or 1,3,5-7")
    p.add_argument("--out-dir", type=path_argument, help="output folder of a sweep")
    p.add_argument("--format", default=None, choices=("csv", "csv.gz", "parquet"),
                   help="log format of a sweep (default csv.gz)")
    p.add_argument("--beaufort", type=float, nargs=2, metavar=("LO", "HI"), default=(2.0, 5.0),
                   help="Beaufort range of the random sea state (default 2 5)")
    p.add_argument("--drift-s", type=float, default=900.0, help="drift duration after the shutdown [s] (default 900)")
    p.add_argument("--t-shutdown-s", type=float, default=3000.0,
                   help="nominal DP shutdown time [s] (default 3000; jittered by +-4 %% per seed)")
    p.add_argument("--heading-mode", default="weather", choices=("weather", "random"),
                   help="heading set-point: bow to weather +-20 deg, or random (default weather)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show a progress bar (default: when stderr is a terminal)")
    p.set_defaults(func=_cmd_simulate)


def _check_log_path(path: Path, option: str) -> None:
    """Refuse a log path whose extension no reader or writer knows (a missing folder of an
    output is made when it is written, as for every ``--out``)."""
    name = path.name.lower()
    if not name.endswith((".csv", ".csv.gz", ".parquet", ".pq")):
        raise UsageError(f"{option} {path}: unsupported extension; use .csv, .csv.gz, .parquet or .pq")


def _cmd_simulate(args) -> int:
    from hybridship.logs.io import write_log
    from hybridship.sim import scenario
    from hybridship.sim.allocation import check_station_keeping
    from hybridship.vessel import load_vessel

    prefix = f"{_PROG} simulate"
    if args.sweep:
        if args.seeds is None or args.out_dir is None:
            raise UsageError(f"{prefix}: error: --sweep needs --seeds and --out-dir")
        if args.seed is not None or args.out is not None:
            raise UsageError(f"{prefix}: error: --seed and --out are for a single scenario; a sweep takes "
                             f"--seeds and --out-dir")
        _check_out_folder(args.out_dir, prefix, option="--out-dir")
    else:
        if args.seeds is not None or args.out_dir is not None:
            raise UsageError(f"{prefix}: error: --seeds and --out-dir need --sweep")
        if args.format is not None:     # the extension of --out chooses a single log's format
            raise UsageError(f"{prefix}: error: --format is for a sweep; a single scenario's format is the "
                             f"extension of --out")
        if args.seed is None or args.out is None:
            raise UsageError(f"{prefix}: error: give --seed and --out (or --sweep --seeds --out-dir)")
        if args.seed < 0:
            raise UsageError(f"{prefix}: error: --seed must be non-negative, got {args.seed}")
        _check_log_path(args.out, f"{prefix}: error: --out")
        if args.out.is_dir():       # refused before simulating, not when the log is written
            raise UsageError(f"{prefix}: error: --out {args.out}: is a folder; expected the log file to write")
        _check_writable(args.out, prefix)       # a file on the way too: refused before simulating
        _check_replaceable(args.out, prefix)

    from hybridship.vessel import VesselFileError

    try:
        vessel = load_vessel(args.vessel)
    except VesselFileError as exc:
        raise UsageError(problem_lines(exc, f"{prefix}: error: --vessel: ")) from None
    try:
        overrides = dict(drift_s=args.drift_s, t_shutdown_s=args.t_shutdown_s, heading_mode=args.heading_mode)
        # Validate the settings and the vessel once before any (long) simulation starts.
        scenario.DPLossConfig(seed=0, beaufort=tuple(args.beaufort), **overrides)
    except (ValueError, TypeError) as exc:
        options = {"drift_s": "--drift-s", "t_shutdown_s": "--t-shutdown-s", "heading_mode": "--heading-mode",
                   "beaufort": "--beaufort"}
        raise UsageError(problem_lines(exc, f"{prefix}: error: ",
                                       lambda field: options.get(field.split("[", 1)[0], field))) from None
    try:
        check_station_keeping(vessel)
    except ValueError as exc:       # a valid vessel file of a ship without DP actuators
        raise UsageError(problem_lines(exc, f"{prefix}: error: --vessel: ")) from None
    progress = sys.stderr.isatty() if args.progress is None else args.progress

    if args.sweep:
        try:
            paths = scenario.sweep(args.out_dir, args.seeds, beaufort=tuple(args.beaufort), fmt=args.format or "csv.gz",
                                   vessel=vessel, progress=progress, **overrides)
        except (FileExistsError, PermissionError) as exc:      # checked before any simulation
            raise UsageError(f"{prefix}: error: --out-dir: {exc}") from None
        except ValueError as exc:
            if not str(exc).startswith("out_dir: "):    # a seed's log there in another format, before any work
                raise
            raise UsageError(problem_lines(exc, f"{prefix}: error: ", {"out_dir": "--out-dir"}.get)) from None
        print(f"wrote {len(paths)} log(s) and {args.out_dir / 'scenarios.csv'}")
        return 0

    cfg = scenario.DPLossConfig(seed=args.seed, beaufort=tuple(args.beaufort), **overrides)
    df = scenario.simulate_dp_loss(cfg, vessel=vessel, progress=progress)
    write_log(df, args.out, channel_names=vessel.channel_names, rotatable=vessel.rotatable)
    from .fileio import record_outputs

    record_outputs(args.out.parent, [args.out.name])    # a later simulate may replace it
    stats = scenario.drift_statistics(df)
    excursion = stats["drift_excursion_60s_m"]
    excursion = (f"drift excursion {excursion:.1f} m after 60 s" if math.isfinite(excursion)
                 else "drift shorter than 60 s (no 60-s excursion)")
    speed = stats["drift_mean_sog_mps"]
    print(f"wrote {args.out}: {len(df)} rows, DP shutdown at {stats['t_shutdown_s']:g} s, {excursion}"
          + (f", mean drift speed {speed:.2f} m/s" if math.isfinite(speed) else ""))
    return 0


# --------------------------------------------------------------------------- entry point


# --------------------------------------------------------------------------- demo / train / forecast


def _add_demo(sub) -> None:
    p = sub.add_parser("demo", help="simulate, train and print the drift-error table (embedded default)",
                       description="Simulate embedded Gunnerus DP-loss scenarios, train the hybrid on their "
                                   "DP parts and print the 15/30/45/60 s drift-error table.")
    p.add_argument("--scenarios", type=_scenarios, default=3,
                   help=f"number of embedded scenarios, 1..{MAX_EMBEDDED_SCENARIOS} (default 3)")
    p.add_argument("--seed", type=_seed, default=0, help="seed of the first scenario and of training (default 0)")
    p.add_argument("--members", type=_members, default=10, help="ensemble members (default 10)")
    p.set_defaults(func=_cmd_demo)


def _cmd_demo(args) -> int:
    import time

    from .evaluation import metrics
    from .predictors import DeadReckoning, DynamicPredictor, HybridPredictor, as_log_arrays
    from .residual.ensemble import EnsembleConfig
    from .sim.scenario import embedded_scenarios

    t0 = time.perf_counter()
    scen = embedded_scenarios(args.scenarios, args.seed)
    print(f"simulated {len(scen)} Gunnerus DP-loss scenarios ({time.perf_counter() - t0:.1f} s): "
          + ", ".join(s.name for s in scen))
    # scored on the training logs' own drifts: nothing is learned from them (drift_hull off)
    hybrid = HybridPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=args.members, seed=args.seed),
                             drift_hull=False)
    logs = [as_log_arrays(s.log, hybrid.model.vessel) for s in scen]
    t0 = time.perf_counter()
    hybrid.fit(logs)
    print(f"trained a {args.members}-member hybrid on {hybrid.training_info['n_rows']} DP samples "
          f"({time.perf_counter() - t0:.1f} s)")
    predictors = {"hybrid": (hybrid, {}), "dynamic": (DynamicPredictor("gunnerus"), {}),
                  "dead_reckoning": (DeadReckoning("gunnerus"), {})}
    errors = {name: [metrics.drift_errors(p, a, **kw) for a in logs] for name, (p, kw) in predictors.items()}
    long = metrics.error_table(errors)
    print("\nMean absolute error after the DP shutdown, first 5 / first 20 forecasts (m, m, deg):")
    print(metrics.paper_table(long).to_string())
    print("\n% error reduction of the hybrid relative to the dynamic model (5/20):")
    print(metrics.reduction_table(long, "hybrid").to_string())
    return 0


def _add_train(sub) -> None:
    p = sub.add_parser("train", help="train a hybrid on the DP part of a folder of logs",
                       description="Train a hybrid predictor (physics of --vessel plus a residual ensemble) on "
                                   "a folder of logs and write it as one model file, which carries the vessel "
                                   "description: forecasting from it needs no vessel file.")
    p.add_argument("--vessel", type=vessel_argument, default="gunnerus",
                   help="packaged vessel name or vessel TOML file of the ship that made the logs (default "
                        "gunnerus; the physics the nets correct)")
    p.add_argument("--logs", required=True, type=path_argument, help="folder of logs (*.csv, *.csv.gz, *.parquet, *.pq)")
    p.add_argument("--out", required=True, type=path_argument, help="model file to write (.npz)")
    p.add_argument("--members", type=_members, default=10, help="ensemble members (default 10)")
    p.add_argument("--seed", type=_seed, default=0, help="seed of the initial weights and bootstrap draws (default 0)")
    p.add_argument("--all-rows", action="store_true", help="train on every row, not only dp_active == 1")
    p.add_argument("--manoeuvre", action="store_true",
                   help="logs of manoeuvres, not station keeping: train with the settings of 'hybridship benchmark "
                        "manoeuvre' (multi-step training, the runs' mean residual as environment, the command "
                        "guard; every row; docs/esso-osaka.md) instead of the station-keeping and drift ones")
    _add_wave_yaw_load(p, "the training logs' failures (five or more) show")
    p.set_defaults(func=_cmd_train)


def _cmd_train(args) -> int:
    from .predictors import HybridPredictor
    from .residual.ensemble import EnsembleConfig
    from .vessel import VesselFileError, load_vessel

    try:
        vessel = load_vessel(args.vessel)
    except VesselFileError as exc:
        raise UsageError(problem_lines(exc, f"{_PROG} train: error: --vessel: ")) from None
    from .evaluation.drift import log_files

    try:    # the benchmark's listing: any extension case, no summary or hidden files
        files = log_files(args.logs)
    except ValueError as exc:
        raise UsageError(f"{_PROG} train: error: --logs {exc}") from None
    if args.out.suffix.lower() != ".npz":      # also keeps it from replacing a training log
        raise UsageError(f"{_PROG} train: error: --out {args.out}: expected a .npz model file")
    if args.out.exists() and not args.out.is_file():
        raise UsageError(f"{_PROG} train: error: --out {args.out}: exists and is not a file")
    from .predictors.model_file import is_model_file

    if args.out.is_file() and args.out.stat().st_size and not is_model_file(args.out):
        raise UsageError(f"{_PROG} train: error: --out {args.out}: exists and is not a hybridship model file "
                         f"(its arrays would be lost); give another path or remove it")
    _check_writable(args.out, f"{_PROG} train")
    if args.manoeuvre and args.wave_yaw_load not in (None, "off"):
        raise UsageError(f"{_PROG} train: error: --wave-yaw-load {args.wave_yaw_load}: not used with --manoeuvre "
                         f"(its environment is the runs' mean residual, and runs have no failure); expected one "
                         f"or the other")
    if args.manoeuvre:
        from dataclasses import replace

        from .evaluation.manoeuvre import ManoeuvreConfig, make_predictors

        cfg = ManoeuvreConfig()
        cfg = replace(cfg, ensemble=replace(cfg.ensemble, n_members=args.members, seed=args.seed))
        hp = make_predictors(vessel, cfg)["hybrid"]
        hp.fit(files, dp_only=False, row_stride=cfg.train_row_stride, progress=sys.stderr.isatty())
    else:
        from .logs.io import REQUIRED_COLUMNS, log_header, output_table_kind

        headers = [log_header(f) or [] for f in files]          # unreadable: refused by fit
        # only what may be a log (the rest is refused by fit, saying why)
        logs = [h for h in headers if set(REQUIRED_COLUMNS) <= set(h) and not output_table_kind(h)]
        if logs and not any("dp_active" in h for h in logs):
            print(f"{_PROG} train: note: no log has a dp_active column; trained with the station-keeping and drift "
                  f"settings (the default). Logs of manoeuvres train with --manoeuvre (docs/esso-osaka.md)",
                  file=sys.stderr)
        from .residual.environment import EnvironmentConfig

        environment = EnvironmentConfig(wave_turned_yaw_load=_WAVE_YAW_LOAD[args.wave_yaw_load or "auto"])
        hp = HybridPredictor(vessel, ensemble_config=EnsembleConfig(n_members=args.members, seed=args.seed),
                             environment_config=environment)
        hp.fit(files, dp_only=not args.all_rows, progress=sys.stderr.isatty())
    hp.save(args.out)
    print(f"trained on {hp.training_info['n_rows']} samples from {len(files)} logs with the physics of vessel "
          f"{vessel.name!r}; wrote {args.out}")
    for line in _learned_from_failures(hp.training_info) + _after_stop_spread(hp):
        print(line)
    return 0


def _after_stop_spread(hp) -> list[str]:
    """Whether the spread of forecasts after a failure is calibrated, and on what."""
    if not hp.stop_after_failure or hp.environment != "estimator":
        return []
    info = hp.training_info.get("calibration", {}).get("after_stop")
    if info is not None:
        within = info.get("starts_within_s", 20.0)
        late = hp.training_info["calibration"].get("after_stop_late")
        later = (f"; starts later in a drift on {late['n_logs']} of them ({late['n_starts']} starts)" if late else
                 f"; starts more than {within:g} s into a drift are not calibrated (the drifts are too short) and "
                 f"say so")
        return [f"spread after a failure: calibrated on {info['n_logs']} failures of the training logs "
                f"({info['n_starts']} starts within {within:g} s of them; few failures give a rough scale){later}"]
    n_min = hp.calibration_config.after_stop_min_failures
    return [f"spread after a failure: not calibrated (the training logs hold fewer than {n_min} failures with a "
            f"drift to calibrate on); forecasts after a failure report the raw spread and say so"]


def _learned_from_failures(info: dict) -> list[str]:
    """What ``fit`` learned from the training logs' failures, and whether it was kept."""
    lines = []
    hull = info.get("drift_hull")
    if hull is not None:
        kept = "kept" if hull["adopted"] else "not kept"
        left_out, p = hull["error_left_out_deg"], hull.get("p_value")     # no p in files before 2026-11-30
        test = "" if p is None else (f", {hull['n_left_out_gains']} of {hull['n_failures']} better, "
                                     f"signed-rank p = {p:.3g}")
        lines.append(f"hull's yaw moment in a drift: {hull['munk_multiple']:g} x Munk on {hull['n_failures']} "
                     f"failures, {kept} (heading {hull['error_deg']:.2f} deg against {hull['error_zero_deg']:.2f} "
                     f"without; left-out failures {'-' if left_out is None else f'{left_out:.2f}'} deg{test})")
    prior = info.get("thrust_error_prior")
    if prior is not None:
        mean = ", ".join(f"{m:+.2f}" for m in prior["learned_mean"])
        if "position_error_m" in prior:
            (pc, pl), (hc, hl) = prior["position_error_m"], prior["heading_error_deg"]
            check = (f"left-out failures: position {pl:.3f} m against {pc:.3f} m, heading {hl:.2f} deg "
                     f"against {hc:.2f} deg with the configured prior")
            if "position_p_value" in prior:         # no p in files before 2026-11-30
                check += (f", signed-rank p = {prior['position_p_value']:.3g} and "
                          f"{prior['heading_p_value']:.3g}")
        else:
            from .predictors.hybrid import THRUST_PRIOR_MIN_FAILURES

            check = f"{prior['n_failures']} failures, fewer than the {THRUST_PRIOR_MIN_FAILURES} the check needs"
        lines.append(f"thrust error learned at the thrust stops ({mean}): {'kept' if prior['kept'] else 'not kept'} "
                     f"({check})")
    wave = info.get("wave_yaw_load")
    if wave is not None:
        choice = "turned with the waves" if wave["turned"] else "held"
        if "p_value" in wave:
            lines.append(f"yaw load after a failure: {choice}, chosen on {wave['n_failures']} failures "
                         f"(heading {wave['turned_deg']:.2f} deg turned against {wave['held_deg']:.2f} deg held, "
                         f"{wave['n_gains']} of {wave['n_failures']} better, signed-rank p = {wave['p_value']:.3g})")
        else:
            from .residual.drift_hull import MIN_FAILURES

            lines.append(f"yaw load after a failure: held ({wave['n_failures']} failures, fewer than the "
                         f"{MIN_FAILURES} the choice needs)")
    return lines


def _add_forecast(sub) -> None:
    p = sub.add_parser("forecast", help="forecast from one or more start times of a log",
                       description="Forecast the vessel's motion from each --start-time of --log with a model "
                                   "file from 'hybridship train' (the vessel comes from the model file), and "
                                   "write the forecast table with its spread and fault flags to --out.")
    p.add_argument("--model", required=True, type=path_argument, help="model file from 'hybridship train'")
    p.add_argument("--log", required=True, type=path_argument, help="log file")
    p.add_argument("--start-time", required=True, type=float, nargs="+", help="start time(s) [s] (sample times)")
    p.add_argument("--horizon-s", type=float, default=60.0,
                   help="forecast horizon [s], a whole number of the log's steps (default 60)")
    p.add_argument("--commands", choices=("held", "known"), default="held",
                   help="held: commands stay at their start values (default); known: use the log's future "
                        "commands (the log must extend --horizon-s past each start)")
    p.add_argument("--no-guard", action="store_true",
                   help="do not shrink the correction outside the envelope (after a DP failure the nets stay off "
                        "all the same)")
    p.add_argument("--quantiles", default="", metavar="Q1,Q2,...",
                   help="also write these quantiles of north, east and heading (probabilities in (0, 1), e.g. "
                        "0.05,0.95), from the calibrated spread")
    p.add_argument("--out", required=True, type=path_argument, help="forecast table to write (.csv)")
    p.set_defaults(func=_cmd_forecast)


def _is_forecast_table(path: Path) -> bool:
    """Whether ``path`` starts as a table written by ``forecast`` does (an earlier forecast,
    which a new one may replace), or is empty."""
    from .logs.io import FORECAST_TABLE_HEADER

    try:
        with open(path, "rb") as fh:
            head = fh.read(64)
    except OSError:
        return False
    return head == b"" or head.startswith(",".join(FORECAST_TABLE_HEADER).encode() + b",")


def _cmd_forecast(args) -> int:
    from .fileio import atomic_write
    from .predictors import HybridPredictor, ModelFileError
    from .predictors.forecast_setup import MAX_HORIZON_S, RequestError

    if not 0 < args.horizon_s <= MAX_HORIZON_S:
        raise UsageError(f"{_PROG} forecast: error: --horizon-s must be > 0 and at most {MAX_HORIZON_S:g} s "
                         f"(one day), got {args.horizon_s}")
    from .predictors.result import checked_quantiles

    try:
        parts = args.quantiles.split(",")
        if args.quantiles.strip() and not all(q.strip() for q in parts):
            raise ValueError("an empty item")   # ",,," or "0.05,,0.95": not the same as leaving it out
        quantiles = [float(q) for q in parts if q.strip()]
        if quantiles:
            checked_quantiles(quantiles)
    except ValueError:
        raise UsageError(f"{_PROG} forecast: error: --quantiles: expected comma-separated distinct probabilities "
                         f"in (0, 1), e.g. 0.05,0.95; got {args.quantiles!r}") from None
    try:
        hp = HybridPredictor.load(args.model)
    except ModelFileError as exc:       # its message starts with the path: named with the option, as --log is
        raise UsageError(problem_lines(ModelFileError(f"--model {exc}"), f"{_PROG} forecast: error: ")) from None
    if not args.log.is_file():
        raise UsageError(f"{_PROG} forecast: error: --log {args.log}: "
                         f"{'is a folder; expected a log file' if args.log.is_dir() else 'file not found'}")
    _check_log_path(args.log, f"{_PROG} forecast: error: --log")
    for opt, given in (("--log", args.log), ("--model", args.model)):
        if args.out.resolve() == given.resolve():
            raise UsageError(f"{_PROG} forecast: error: --out {args.out}: is the {opt} file; the forecast would "
                             f"replace it, give another path")
    if args.out.is_dir():
        raise UsageError(f"{_PROG} forecast: error: --out {args.out}: is a folder; give a .csv file")
    if not args.out.name.lower().endswith(".csv"):
        raise UsageError(f"{_PROG} forecast: error: --out {args.out}: expected a .csv file (the forecast is "
                         f"written as plain CSV)")
    if args.out.is_file() and not _is_forecast_table(args.out):
        raise UsageError(f"{_PROG} forecast: error: --out {args.out}: exists and is not a forecast table (another "
                         f"log or table would be lost); give another path or remove it")
    _check_writable(args.out, f"{_PROG} forecast")
    shown = warnings.showwarning
    try:
        with warnings.catch_warnings():     # a warning naming a Python argument names the option
            warnings.showwarning = lambda message, *a, **k: shown(_in_option_names(str(message)), *a, **k)
            fc = hp.forecast(args.log, args.start_time, args.horizon_s, commands=args.commands,
                             guard=False if args.no_guard else None)     # None: as the model was saved
    except RequestError as exc:     # known only once the log is read: still the user's input
        raise UsageError(_in_option_names(problem_lines(exc, f"{_PROG} forecast: error: "))) from None
    df = fc.to_frame(quantiles=quantiles)
    atomic_write(args.out, lambda fh: fh.write(df.to_csv(index=False).encode("utf-8")))
    from .forecast_inputs import FaultFlags
    from .messages import seconds_text

    last = df[df.lead_s == df.lead_s.max()]
    for _, row in last.iterrows():
        flags = [name for name in FaultFlags.ALL if name != FaultFlags.OUT_OF_ENVELOPE and bool(row.get(name, False))]
        if "guard_weight" in df:
            ooe = "yes" if bool(row.get(FaultFlags.OUT_OF_ENVELOPE, False)) else "no"
            guard = (f"{FaultFlags.OUT_OF_ENVELOPE}: {ooe} (min guard weight "
                     f"{df[df.start_time_s == row.start_time_s].guard_weight.min():.2f})")
        else:
            guard = "guard off"
        print(f"start {seconds_text(row.start_time_s)} s -> +{seconds_text(row.lead_s)} s: north {row.north_m:.1f} m, "
              f"east {row.east_m:.1f} m, "
              f"heading {row.heading_deg:.1f} deg (1-sigma {row.north_std_m:.1f}/{row.east_std_m:.1f} m); "
              f"{guard}; other flags: {', '.join(flags) if flags else 'none'}")
        if isinstance(row.get("notes"), str) and row["notes"]:
            print(f"  notes: {row['notes']}")
    print(f"wrote {args.out}")
    return 0


#: The forecast's Python arguments (as whole words) as its options are named (errors found once
#: the log is read).
_FORECAST_OPTIONS = ((r"start_times_s:", "--start-time:"), (r"horizon_s:", "--horizon-s:"),
                     (r"commands='known'", "--commands known"), (r"commands='held'", "--commands held"))


def _in_option_names(message: str) -> str:
    """``message`` with the forecast's Python argument names replaced by its options'."""
    for python_name, option in _FORECAST_OPTIONS:
        message = re.sub(r"(?<![\w.])" + python_name, option, message)
    return message


#: ``--wave-yaw-load``'s values as ``EnvironmentConfig.wave_turned_yaw_load`` takes them.
_WAVE_YAW_LOAD = {"on": True, "off": False, "auto": "auto"}


def _add_wave_yaw_load(parser, who: str, extra: str = "") -> None:
    """``--wave-yaw-load [on|off|auto]`` (alone: on; not given: None, auto), ``who`` naming what
    decides with auto, ``extra`` when it holds."""
    parser.add_argument("--wave-yaw-load", nargs="?", const="on", default=None, choices=tuple(_WAVE_YAW_LOAD),
                        help="after a failure, turn the held yaw load with the waves' axis found in the station "
                             "keeping's wave-frequency motion (EnvironmentConfig.wave_turned_yaw_load): on (the "
                             f"option alone), off, or auto (default): where {who} it lowers the heading "
                             f"error{extra}")


def _add_benchmark(sub) -> None:
    p = sub.add_parser("benchmark", help="reproducible benchmark tables (drift, ...)",
                       description="Reproducible benchmarks that write Markdown and CSV tables.")
    bsub = p.add_subparsers(dest="benchmark", metavar="BENCHMARK", parser_class=_Parser)
    d = bsub.add_parser("drift", help="the paper's 15/30/45/60 s drift-error tables after a DP failure",
                        description="Train on --train (DP parts), forecast after every failure in --test, and "
                                    "write errors.csv, errors_per_log.csv, coverage.csv, coverage_intervals.csv, "
                                    "coverage_heading.csv, drift_hull.csv, wave_yaw_load.csv, "
                                    "timing.csv, tables.md and figures "
                                    "to --out. Without --train/--test: the embedded simulated scenarios.")
    d.add_argument("--train", type=path_argument, help="folder of training logs")
    d.add_argument("--test", type=path_argument, help="folder of test logs (default: the training logs' drifts)")
    d.add_argument("--out", type=path_argument, default=Path("drift-benchmark"), help="output folder (default drift-benchmark)")
    d.add_argument("--vessel", type=vessel_argument, default="gunnerus",
                   help="packaged vessel name or vessel TOML file (default gunnerus)")
    d.add_argument("--members", type=_members, default=10, help="ensemble members (default 10)")
    d.add_argument("--seed", type=_seed, default=0, help="seed of scenarios and training (default 0)")
    d.add_argument("--intervals", type=int, default=20, help="start times after each failure (default 20)")
    d.add_argument("--scenarios", type=_scenarios, default=3,
                   help=f"embedded scenarios when no folders are given, 1..{MAX_EMBEDDED_SCENARIOS} (default 3)")
    d.add_argument("--all-rows", action="store_true", help="train on every row, not only dp_active == 1")
    d.add_argument("--training", choices=("one_step", "multi_step"), default="one_step",
                   help="how the hybrid's nets are trained (default one_step)")
    d.add_argument("--calibration-scenarios", type=int, default=6,
                   help="simulated DP losses that calibrate the hybrid's spread after a failure when the "
                        "training logs hold too few failures of their own (default 6; 0: none)")
    d.add_argument("--no-drift-hull", action="store_true",
                   help="learn nothing about the drift from failures: neither the hull's yaw moment nor (with "
                        "--wave-yaw-load auto) the yaw load's turn (the paper's protocol, strictly)")
    _add_wave_yaw_load(d, "the other failures show", " (held with --no-drift-hull)")
    d.add_argument("--current-prior-wind-ref", type=_positive_number, default=None, metavar="M_S",
                   help="widen the environment estimator's current prior in light wind: 0.02 m/s x (M_S / the "
                        "wind at the filter's start)^2, 0.02-0.3 m/s (EnvironmentConfig.current_prior_wind_ref_m_s; "
                        "default: 0.02 m/s whatever the wind)")
    d.add_argument("--current-prior", type=_positive_number, default=0.02, metavar="M_S",
                   help="the environment estimator's current prior at the filter's start "
                        "(EnvironmentConfig.current_prior_m_s; default 0.02 m/s)")
    d.add_argument("--yaw-load-prior", type=_positive_number, default=1e-3, metavar="RAD_S2",
                   help="the environment estimator's yaw-load prior at the filter's start "
                        "(EnvironmentConfig.load_yaw_prior_rad_s2; default 0.001 rad/s^2)")
    d.add_argument("--load-prior-across-wind", type=_fraction, default=1.0, metavar="RHO",
                   help="narrow the environment estimator's NED load prior across the wind's axis at the "
                        "filter's start to RHO times that along it (EnvironmentConfig.load_prior_across_wind; "
                        "default 1: the same in every direction)")
    d.add_argument("--load-model", choices=("acceleration", "force"), default="acceleration",
                   help="the environment estimator's slowly varying load: an acceleration fixed in NED "
                        "(default) or a NED force and yaw moment (EnvironmentConfig.load_model)")
    d.add_argument("--no-plots", action="store_true",
                   help="skip the figures (and remove those of an earlier run from --out)")
    d.set_defaults(func=_cmd_benchmark_drift)
    h = bsub.add_parser("hsc", help="high-speed craft: SS, ARX, NARX-ANN and hybrid on simulated sea trials",
                        description="Simulate Volcano71 sea trials (sea states 1 and 2), identify SS, ARX, "
                                    "NARX-ANN and hybrid models on the training parts and write table.csv "
                                    "(model,sea_state,split,mode,output,R,MAE), table.md and figures to --out.")
    h.add_argument("--out", type=path_argument, default=Path("hsc-benchmark"), help="output folder (default hsc-benchmark)")
    h.add_argument("--seed", type=_seed, default=0, help="seed of the trials and of training (default 0)")
    h.add_argument("--quick", action="store_true", help="a small, fast configuration (for tests)")
    h.set_defaults(func=_cmd_benchmark_hsc)
    m = bsub.add_parser("manoeuvre", help="manoeuvring forecasts on free-running runs (e.g. Esso Osaka)",
                        description="Train on the runs in --train, forecast every start time of the runs in "
                                    "--test at the given horizons (future commands known and held) and write "
                                    "errors.csv (model,kind,state,horizon_s,mae,commands), coverage.csv "
                                    "(model,kind,commands,horizon_s,sigma,coverage), coverage_intervals.csv, "
                                    "coverage_heading.csv (the heading's spread), sharpness.csv and README.md to "
                                    "--out.")
    m.add_argument("--vessel", type=vessel_argument, default="esso_osaka_model",
                   help="packaged vessel name or vessel TOML file (default esso_osaka_model)")
    m.add_argument("--train", required=True, type=path_argument, help="folder of training runs")
    m.add_argument("--test", required=True, type=path_argument, help="folder of test runs (never the training runs)")
    m.add_argument("--horizons-s", default="5,10,20,30", help="comma-separated horizons [s] (default 5,10,20,30)")
    m.add_argument("--out", type=path_argument, default=Path("manoeuvre-benchmark"),
                   help="output folder (default manoeuvre-benchmark)")
    m.add_argument("--step-s", type=float, default=None,
                   help="forecast and training step [s], a whole multiple of the data's (default: the data's own)")
    m.add_argument("--seed", type=_seed, default=0, help="seed of training (default 0)")
    m.add_argument("--quick", action="store_true", help="a small, fast configuration (for tests)")
    m.set_defaults(func=_cmd_benchmark_manoeuvre)
    p.set_defaults(func=_cmd_benchmark_missing)


def _check_replaceable(out: Path, prefix: str, option: str = "--out") -> None:
    """Refuse an existing file at ``out`` that no hybridship command wrote there (a user's log
    would be lost): only files in the folder's record of outputs are replaced."""
    from .fileio import check_output_files

    try:
        check_output_files(out.parent, [out.name])
    except (FileExistsError, PermissionError) as exc:
        raise UsageError(f"{prefix}: error: {option} {exc}") from None


def _check_writable(out: Path, prefix: str, option: str = "--out") -> None:
    """Refuse an ``--out`` that this process may not write, before any work is done."""
    from .fileio import check_writable

    try:
        check_writable(out)
    except (PermissionError, NotADirectoryError) as exc:
        raise UsageError(f"{prefix}: error: {option} {exc}") from None


def _check_out_folder(out: Path, prefix: str, inputs: dict | None = None, option: str = "--out",
                      searched_below: bool = False) -> None:
    """Refuse an ``--out`` that exists and is not a folder, that may not be written, or that
    is one of the input folders ``inputs`` (option -> folder; the tables would land among
    the logs), or, with ``searched_below`` (inputs read with their sub-folders), lies inside
    one, before any work is done."""
    from .fileio import check_out_folder, lies_within

    try:
        check_out_folder(out)
    except NotADirectoryError as exc:
        raise UsageError(f"{prefix}: error: {option} {exc}") from None
    _check_writable(out, prefix, option)
    for opt, folder in (inputs or {}).items():
        if folder is not None and out.resolve() == Path(folder).resolve():
            raise UsageError(f"{prefix}: error: --out {out}: is the {opt} folder; the results would land among "
                             f"its logs, give another folder")
        if searched_below and folder is not None and lies_within(out, folder):
            # its tables would be read as runs by the next run on that folder
            raise UsageError(f"{prefix}: error: --out {out}: lies inside the {opt} folder, whose sub-folders are "
                             f"read for runs; give a folder outside it")


def _cmd_benchmark_manoeuvre(args) -> int:
    from dataclasses import replace

    from .evaluation.manoeuvre import ManoeuvreConfig, check_output_folder, run_manoeuvre_benchmark
    from .vessel import VesselFileError, load_vessel

    _check_out_folder(args.out, f"{_PROG} benchmark manoeuvre", {"--train": args.train, "--test": args.test},
                      searched_below=True)
    try:
        check_output_folder(args.out)
    except (FileExistsError, PermissionError) as exc:
        raise UsageError(f"{_PROG} benchmark manoeuvre: error: --out {exc}") from None

    try:
        horizons = tuple(float(h) for h in args.horizons_s.split(","))
    except ValueError:
        raise UsageError(f"{_PROG} benchmark manoeuvre: error: --horizons-s: expected numbers like 5,10,20,30, "
                         f"got {args.horizons_s!r}") from None
    if not horizons or any(not (0 < h < math.inf) for h in horizons):
        raise UsageError(f"{_PROG} benchmark manoeuvre: error: --horizons-s: horizons must be finite and > 0 s")
    if len(set(horizons)) != len(horizons):
        raise UsageError(f"{_PROG} benchmark manoeuvre: error: --horizons-s: a horizon is given twice "
                         f"({args.horizons_s})")
    for opt, folder in (("--train", args.train), ("--test", args.test)):
        if not folder.is_dir():
            raise UsageError(f"{_PROG} benchmark manoeuvre: error: {opt} {folder}: not a folder")
    if args.step_s is not None and not 0 < args.step_s < math.inf:
        raise UsageError(f"{_PROG} benchmark manoeuvre: error: --step-s must be finite and > 0 s, got {args.step_s}")
    try:
        vessel = load_vessel(args.vessel)
    except VesselFileError as exc:
        raise UsageError(problem_lines(exc, f"{_PROG} benchmark manoeuvre: error: --vessel: ")) from None
    cfg = ManoeuvreConfig.quick(args.seed) if args.quick else ManoeuvreConfig()
    options = {"horizons_s": "--horizons-s", "step_s": "--step-s", "test_dir": "--test", "train_dir": "--train"}
    try:
        run_manoeuvre_benchmark(vessel, args.train, args.test, horizons, args.out, seed=args.seed,
                                config=replace(cfg, step_s=args.step_s), progress=True)
    except ValueError as exc:
        field = str(exc).partition(":")[0]
        if field not in options:        # a problem of the data, not of the options
            raise
        message = re.sub(r"\b(train_dir|test_dir)\b", lambda m: options[m.group(1)], str(exc))
        raise UsageError(problem_lines(ValueError(message), f"{_PROG} benchmark manoeuvre: error: ",
                                       lambda f: options.get(f, f))) from None
    return 0


def _cmd_benchmark_hsc(args) -> int:
    from .hsc.benchmark import run_benchmark

    _check_out_folder(args.out, f"{_PROG} benchmark hsc")
    try:
        run_benchmark(args.out, seed=args.seed, quick=args.quick, progress=True)
    except (FileExistsError, PermissionError) as exc:   # checked before any work
        raise UsageError(f"{_PROG} benchmark hsc: error: --out {exc}") from None
    return 0


def _cmd_benchmark_missing(args) -> int:
    raise UsageError(f"{_PROG} benchmark: error: choose a benchmark (try '{_PROG} benchmark --help')")


def _cmd_benchmark_drift(args) -> int:
    from .evaluation.drift import check_output_folder, log_files, run_drift_benchmark
    from .residual.environment import EnvironmentConfig
    from .vessel import VesselFileError, load_vessel

    if args.intervals < 1:
        raise UsageError(f"{_PROG} benchmark drift: error: --intervals must be >= 1")
    _check_out_folder(args.out, f"{_PROG} benchmark drift", {"--train": args.train, "--test": args.test})
    try:
        check_output_folder(args.out, plots=not args.no_plots)
    except (FileExistsError, PermissionError) as exc:
        raise UsageError(f"{_PROG} benchmark drift: error: --out {exc}") from None
    if not 0 <= args.calibration_scenarios <= 20:
        raise UsageError(f"{_PROG} benchmark drift: error: --calibration-scenarios must be in 0..20, "
                         f"got {args.calibration_scenarios}")
    if args.test is not None and args.train is None:
        raise UsageError(f"{_PROG} benchmark drift: error: --test needs --train")
    for opt, folder in (("--train", args.train), ("--test", args.test)):
        if folder is not None:
            try:
                log_files(folder)
            except ValueError as exc:
                raise UsageError(problem_lines(exc, f"{_PROG} benchmark drift: error: {opt} ")) from None
    try:
        vessel = load_vessel(args.vessel)
    except VesselFileError as exc:
        raise UsageError(problem_lines(exc, f"{_PROG} benchmark drift: error: --vessel: ")) from None
    try:
        res = run_drift_benchmark(args.train, args.test, args.out, vessel=vessel, members=args.members,
                                  seed=args.seed, n_intervals=args.intervals, dp_only=not args.all_rows,
                                  n_scenarios=args.scenarios, plots=not args.no_plots, training=args.training,
                                  calibration_scenarios=args.calibration_scenarios,
                                  drift_hull=not args.no_drift_hull,
                                  environment_config=EnvironmentConfig(
                                      wave_turned_yaw_load=_WAVE_YAW_LOAD[args.wave_yaw_load or "auto"],
                                      load_model=args.load_model,
                                      current_prior_m_s=args.current_prior,
                                      load_yaw_prior_rad_s2=args.yaw_load_prior,
                                      current_prior_wind_ref_m_s=args.current_prior_wind_ref,
                                      load_prior_across_wind=args.load_prior_across_wind))
    except ValueError as exc:
        if not str(exc).startswith(("test: ", "train: ", "n_intervals: ")):
            raise
        # the folders' logs do not fit the request (no failure to score, a test log trained on), or
        # --intervals gives too few forecasts to calibrate on: still the input, named as typed
        option = {"test": "--test", "train": "--train", "n_intervals": "--intervals"}
        raise UsageError(problem_lines(exc, f"{_PROG} benchmark drift: error: ", lambda field: option.get(field, field))
                         .replace("(calibration_scenarios)", "(--calibration-scenarios)")) from None
    print()
    print(res.outputs["tables.md"].read_text())
    return 0


def _add_drift_off(sub) -> None:
    from .driftoff.command import add_parser

    add_parser(sub, _Parser, UsageError)


def _build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every subcommand registered."""
    parser = _Parser(prog=_PROG, description="Ship drift forecasting with a 3-DOF Fossen model and "
                                               "neural residuals.")
    from . import __version__

    parser.add_argument("--version", action="version", version=f"{_PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    _add_simulate(sub)
    _add_demo(sub)
    _add_train(sub)
    _add_benchmark(sub)
    _add_forecast(sub)
    _add_drift_off(sub)
    return parser


def _negative_values_attached(argv) -> list:
    """``--opt -90,0`` as ``--opt=-90,0``: argparse takes a word that starts with '-' for an
    option unless it is a plain negative number, so a list such as ``--headings-deg -90,0``
    was refused with "expected one argument". No option name starts with '-' and a digit."""
    words = [str(w) for w in argv]
    out = []
    i = 0
    while i < len(words):
        w = words[i]
        if (w.startswith("--") and "=" not in w and i + 1 < len(words)
                and re.match(r"-[0-9.]", words[i + 1]) and "," in words[i + 1]):
            out.append(f"{w}={words[i + 1]}")
            i += 2
            continue
        out.append(w)
        i += 1
    return out


def main(argv=None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    parser = _build_parser()
    args = None
    try:
        args, extra = parser.parse_known_args(_negative_values_attached(sys.argv[1:] if argv is None else argv))
        if extra:   # named with the command they were given to (argparse names the top level)
            words = list(sys.argv[1:] if argv is None else argv)
            command = getattr(args, "command", None)
            before = command in words and extra[0] in words and words.index(extra[0]) < words.index(command)
            raise UsageError(f"{_PROG if before else _command(args)}: error: unrecognized arguments: "
                             f"{' '.join(extra)}")
        if getattr(args, "func", None) is None:
            raise UsageError(f"{_PROG}: error: a command is required (try '{_PROG} --help')")
        with warnings.catch_warnings():
            # a warning in the command's words, not with the library's file and source line
            warnings.showwarning = lambda message, *_, **__: print(
                problem_lines(message, f"{_command(args)}: warning: "), file=sys.stderr)
            return int(args.func(args))
    except UsageError as exc:
        print(str(exc), file=sys.stderr)
        return 2
    except SystemExit as exc:  # --help / --version from argparse
        return exc.code if isinstance(exc.code, int) else 0
    except KeyboardInterrupt:
        print(f"{_PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of the output left (``| head``): stop quietly, as other tools do, not with
        # "error: [Errno 32] Broken pipe"; the output files were written before the printing
        _discard_stdout()
        return 141
    except (OSError, ValueError, TypeError, FloatingPointError) as exc:
        print(problem_lines(exc, f"{_command(args)}: error: "), file=sys.stderr)
        return 1
    except MemoryError as exc:      # numpy's _ArrayMemoryError, with a traceback, otherwise
        ours = str(exc) and "Unable to allocate" not in str(exc)       # said in the command's words
        what = str(exc) if ours else ("the arrays this run needs do not fit in memory; ask for less (fewer "
                                      "samples, headings, start times or logs)")
        print(f"{_command(args)}: error: out of memory: {what}", file=sys.stderr)
        return 1


def _discard_stdout() -> None:
    """Send what is left on stdout to the null device, so that the interpreter's flush at exit
    does not fail on the closed pipe again (a stdout without a file descriptor is left as is)."""
    import os

    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (AttributeError, OSError, ValueError):
        pass


def _command(args) -> str:
    """The whole command, e.g. "hybridship drift-off live" (the subcommands' dests)."""
    words = [getattr(args, dest, None) for dest in ("command", "benchmark", "mode")]
    return " ".join([_PROG] + [w for w in words if w])


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
