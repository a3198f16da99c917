"""Coverage of the hybrid's spread after a failure, calibrated on different sets of simulated DP losses.

The default hybrid (paper protocol: trained on the DP parts of the test logs, small nets,
which stay off after a stop) is calibrated with
:meth:`~hybridship.predictors.HybridPredictor.calibrate_after_stop` on ``--n`` DP losses
simulated by the project's simulator, and its 2-sigma (and 1-sigma) coverage of the
north/east errors of the first 20 forecasts after every failure is printed at 15, 30 and
60 s, on the embedded scenarios and on truthsim-dev, each with a 90 % interval that resamples
whole failures (:func:`hybridship.evaluation.metrics.coverage_interval`). The calibration set is varied:
weather (``--beaufort``), station-keeping time before the failure (``--dp-s``) and the
"real" ship (``--vessel-spread``: each scenario's hull drawn log-normally around the model
with the vessel file's ``[true_vessel]`` spread, see :mod:`hybridship.driftoff.spread`;
0 = the file's own true vessel for every scenario).

``--source own`` calibrates each log's spread on the data set's *other* failures instead
(leave one out), as :meth:`~hybridship.predictors.HybridPredictor.fit` does with the
training logs' failures and the drift benchmark does when its test logs are its training
logs; ``--own N`` adds N fresh scenarios of our own (seeds 100 on).

``--thrust-error-model per_dof`` runs the estimator with the per-DOF thrust error (the
previous default, :data:`hybridship.residual.environment.PER_DOF`) instead of the default
one per thruster.

Examples::

    python benchmarks/after_stop_calibration.py                                   # the drift benchmark's set
    python benchmarks/after_stop_calibration.py --n 8 --vessel-spread 1
    python benchmarks/after_stop_calibration.py --n 8 --vessel-spread 1 --beaufort 2 6 --dp-s 1800
    python benchmarks/after_stop_calibration.py --n 8 --heading-mode mixed
    python benchmarks/after_stop_calibration.py --n 8 --vessel-spread 1 --beaufort 3 7 --dp-s 1800
    python benchmarks/after_stop_calibration.py --own 20 --source own
    python benchmarks/after_stop_calibration.py --out docs/results/after-stop-calibration/default.md

``--out FILE`` also writes the printed table, headed by its command, to a Markdown file (the
runs the docs quote are in ``docs/results/after-stop-calibration``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out, command_line
from hybridship.driftoff.spread import draw_scales
from hybridship.evaluation import metrics
from hybridship.evaluation.drift import log_files
from hybridship.fileio import write_text
from hybridship.predictors import AFTER_STOP, HybridPredictor, as_log_arrays
from hybridship.predictors.hybrid import leave_one_out_after_stop_scales
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import PER_DOF, EnvironmentConfig
from hybridship.sim.scenario import DPLossConfig, embedded_scenarios, simulate_dp_loss
from hybridship.vessel import load_vessel

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"
SMALL = EnsembleConfig(n_members=10, hidden=4, max_epochs=1, patience=1, seed=0)
HORIZONS_S = (15.0, 30.0, 60.0)


def calibration_logs(n: int, seed: int, beaufort, dp_s: float, vessel_spread: float,
                     heading_mode: str = "weather") -> list:
    """``n`` simulated DP losses (600 s of drift each) for the calibration; ``heading_mode``
    "mixed" alternates bow-to-weather and random heading set-points."""
    v = load_vessel("gunnerus")
    scales = draw_scales(v, n, np.random.default_rng(seed), vessel_spread) if vessel_spread > 0 else None
    logs = []
    for i in range(n):
        vi = v
        if scales is not None:
            spec = v.model_dump()
            spec["true_vessel"] = {"added_mass_scale": scales.added_mass[i].tolist(),
                                   "linear_damping_scale": scales.linear_damping[i].tolist(),
                                   "nonlinear_damping_scale": scales.nonlinear_damping[i].tolist(),
                                   "wind_coefficient_scale": scales.wind_coefficient[i].tolist(),
                                   "thrust_scale": float(scales.thrust[i])}
            vi = type(v).model_validate(spec)
        mode = ("random" if i % 2 else "weather") if heading_mode == "mixed" else heading_mode
        cfg = DPLossConfig(seed=seed + i, beaufort=tuple(beaufort), t_shutdown_s=dp_s, t_shutdown_jitter_s=30.0,
                           drift_s=600.0, heading_mode=mode)
        logs.append(simulate_dp_loss(cfg, vessel=vi))
    return logs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=6, help="simulated DP losses in the calibration set (default 6)")
    ap.add_argument("--seed", type=int, default=1000, help="seed of the first one (default 1000, as the benchmark)")
    ap.add_argument("--beaufort", type=float, nargs=2, default=(2.0, 5.0), help="weather range (default 2 5)")
    ap.add_argument("--dp-s", type=float, default=600.0, help="station keeping before the failure [s] (default 600)")
    ap.add_argument("--vessel-spread", type=float, default=0.0, help="hull spread (default 0: the file's true vessel)")
    ap.add_argument("--thrust-error-model", choices=("per_dof", "per_thruster"), default="per_thruster",
                    help="the estimator's thrust-model error: per thruster (the default) or per DOF (the "
                         "previous default, hybridship.residual.environment.PER_DOF)")
    ap.add_argument("--heading-mode", choices=("weather", "random", "mixed"), default="weather",
                    help="heading set-points of the calibration losses: bow to weather (default), random, or "
                         "alternating")
    ap.add_argument("--source", choices=("simulated", "own"), default="simulated",
                    help="calibrate on the simulated DP losses (default) or, per log, on the data set's other "
                         "failures (leave one out: what a model trained on the other logs gets from fit)")
    ap.add_argument("--own", type=int, default=0,
                    help="also score this many fresh scenarios of our own (seeds 100 on; default 0)")
    ap.add_argument("--held-load-window-s", type=float, default=EnvironmentConfig().held_load_window_s,
                    help="station keeping read for the held-load term of the spread [s] (0: no such term)")
    ap.add_argument("--out", type=Path, default=None,
                    help="also write the table, headed by its command, to this Markdown file")
    args = ap.parse_args(argv)
    _check_options(ap, args)
    lines = [f"Command: `{command_line('after_stop_calibration.py', argv)}`", ""]

    def say(line: str) -> None:
        print(line, flush=True)
        lines.append(line)

    cfg = _environment_config(args)
    cal = calibration_logs(args.n, args.seed, args.beaufort, args.dp_s, args.vessel_spread, args.heading_mode) \
        if args.source == "simulated" else None
    data = {"embedded": [s.log for s in embedded_scenarios(3, 0)]}
    if args.own:
        data[f"own 100-{99 + args.own}"] = [s.log for s in embedded_scenarios(args.own, 100)]
    if TRUTHSIM.is_dir():
        data["truthsim-dev"] = [pd.read_csv(f) for f in log_files(TRUTHSIM)]
    else:
        print(f"skipping truthsim-dev: {TRUTHSIM} not found", file=sys.stderr)
    source = (f"{args.n} simulated DP losses, Beaufort {args.beaufort[0]:g}-{args.beaufort[1]:g}, "
              f"{args.dp_s:g} s of DP, hull spread {args.vessel_spread:g}" if args.source == "simulated"
              else "each log on the data set's other failures (leave one out)")
    say(f"calibration: {source}; thrust error {args.thrust_error_model}; "
        f"held-load window {args.held_load_window_s:g} s; coverage of the north/east errors of the first 20 "
        f"starts after each failure, with a 90 % interval that resamples whole failures")
    say("")
    say("| data | sigma | " + " | ".join(f"{h:g} s" for h in HORIZONS_S) + " |")
    say("| --- | --- | " + " | ".join("---" for _ in HORIZONS_S) + " |")
    for name, logs in data.items():
        arrays = [as_log_arrays(x, "gunnerus") for x in logs]
        # scored on the training logs' own drifts: nothing is learned from them (drift_hull off)
        hp = HybridPredictor("gunnerus", ensemble_config=SMALL, environment_config=cfg,
                             drift_hull=False).fit(arrays, dp_only=True)
        if args.source == "simulated":
            hp.calibrate_after_stop(cal)
            fc = [metrics.drift_forecasts(hp, a, n_intervals=20, horizons_s=HORIZONS_S) for a in arrays]
        elif len(arrays) < 3:
            say(f"| {name} | | too few failures ({len(arrays)}) to leave one out |")
            continue
        else:
            fc = _leave_one_out(hp, arrays)
        P, T, S = (np.stack([f[i] for f in fc]) for i in range(3))       # (logs, starts, horizons, 3)
        for k in (1, 2):
            ci = metrics.coverage_interval(P, T, S, k, seed=args.seed)
            say(f"| {name} | {k} | " + " | ".join(f"{c:.2f} [{lo:.2f}, {hi:.2f}]" for c, lo, hi in ci) + " |")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        write_text(args.out, "\n".join(lines) + "\n")
    return 0


OPTIONS = {"seed": "--seed", "beaufort": "--beaufort", "t_shutdown_s": "--dp-s",
           "held_load_window_s": "--held-load-window-s"}


def _environment_config(args) -> EnvironmentConfig:
    return EnvironmentConfig(**(PER_DOF if args.thrust_error_model == "per_dof" else {}),
                             held_load_window_s=args.held_load_window_s)


def _check_options(ap, args) -> None:
    """Refuse, as a usage error (exit 2) naming the option, what the library would refuse in
    its own words only after the calibration losses were simulated or the hybrid trained."""
    if args.source == "simulated" and args.n < 1:
        ap.error(f"--n: expected a positive integer, got {args.n}")
    if not 0 <= args.own <= 20:         # the simulator's embedded scenarios: 1-20 of them
        ap.error(f"--own: expected 0-20, got {args.own}")
    if not 0 <= args.vessel_spread < float("inf"):      # a negative or NaN spread was read as none
        ap.error(f"--vessel-spread: expected a finite number >= 0, got {args.vessel_spread}")
    check_out(ap, args.out, file=True)     # the check every benchmark script makes of its --out
    try:
        _environment_config(args)
        DPLossConfig(seed=args.seed, beaufort=tuple(args.beaufort), t_shutdown_s=args.dp_s,
                     t_shutdown_jitter_s=30.0, drift_s=600.0)
    except ValueError as exc:           # "t_shutdown_s: must be > 0 (got -5.0) [DPLossConfig]": name the option
        field, _, reason = str(exc).partition(":")
        ap.error(OPTIONS.get(field, f"--{field.replace('_', '-')}") + ":" + reason)


def _leave_one_out(hp, arrays) -> list:
    """Each log's forecasts after its failure with the spread calibrated on the other logs' failures."""
    scales = leave_one_out_after_stop_scales(hp.after_stop_errors(arrays), hp.calibration_config)
    out = []
    for a, cal in zip(arrays, scales):
        hp.calibration[AFTER_STOP] = cal
        out.append(metrics.drift_forecasts(hp, a, n_intervals=20, horizons_s=HORIZONS_S))
    return out


if __name__ == "__main__":
    sys.exit(main())
