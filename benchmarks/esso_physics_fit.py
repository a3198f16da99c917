"""Esso Osaka: does identifying a few physical coefficients first help the hybrid?

::

    python benchmarks/esso_physics_fit.py --out out/esso-physics-fit

splits the benchmark's *training* runs (``out/esso-osaka/split/train``) again, seed 1, as
``benchmarks/esso_error_sources.py`` does (the test runs play no part). On the fitting runs
it identifies twelve coefficients of ``vessels/esso_osaka_model.toml`` by a free-run fit:
each is the published value times ``exp(theta)``, and ``theta`` minimises the mean 30-s
forecast error of the physics alone, ``distance [m] + (L_pp/2) |heading error| [rad]``
(L_pp = 3 m), from a start every 5 s with the logged commands and the wind forecast fitted on
the fitting runs (scipy's Powell method, 600 evaluations; the MMG coefficients carrying
scale effects: wake fraction, flow straightening on both sides, slipstream factor, a_H,
rudder area, N'_r, Y'_v, the straight-ahead resistance, the yaw radius of gyration and the
wind areas). It then fits the benchmark's hybrid
(:func:`~hybridship.evaluation.manoeuvre.make_predictors`) on the fitting runs twice, on
the published coefficients and on the identified ones, and scores on the validation runs,
commands known, a start every second:

* ``dynamic``, ``dynamic_fitted``: the physics alone on the published and the identified
  coefficients (the wind held, as the benchmark's physics);
* ``hybrid``, ``hybrid_fitted``: the hybrid on each;
* with ``--average``, ``hybrid_average``: the mean of the two hybrids' forecasts (heading on
  the circle), a two-model ensemble whose members differ in their physics, not only in
  their seed (``benchmarks/esso_error_sources.py --seed-average`` is the seed's).

Writes ``theta.csv`` (coefficient, published value, identified value), ``errors.csv`` (the
manoeuvre benchmark's columns) and ``tables.md`` (the fit's objective, the 30-s errors per
kind, pooled ratios to ``dynamic``) to ``--out`` and prints them; ``--results`` also copies
the three there (``--out`` holds the split's links to the data, which stay out of the
repository). About 16 min on one core, twice that with ``--average``. The committed run::

    python benchmarks/esso_physics_fit.py --average --out out/esso-physics-fit \
        --results docs/results/esso-physics-fit
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import sys
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: Dotted paths in the vessel file of the coefficients identified.
COEFFICIENTS = ("thrusters.0.wake_fraction", "rudders.0.flow_straightening_neg",
                "rudders.0.flow_straightening_pos", "rudders.0.slipstream_factor",
                "rudders.0.hull_force_factor", "damping.nonlinear.mmg.N_r", "damping.nonlinear.mmg.Y_v",
                "damping.nonlinear.d_uu", "rigid_body.r_z_m", "wind.A_L_m2", "wind.A_F_m2",
                "rudders.0.area_m2")


def _node(d: dict, path: str):
    """The container of ``path``'s last key in the vessel dictionary, and that key."""
    keys = path.split(".")
    for k in keys[:-1]:
        d = d[int(k)] if isinstance(d, list) else d[k]
    return d, keys[-1]


def vessel_with_factors(base: dict, theta: np.ndarray):
    """The vessel of ``base`` (the parsed vessel file) with every :data:`COEFFICIENTS` times ``exp(theta)``."""
    from hybridship.vessel import vessel_from_dict

    d = copy.deepcopy(base)
    for path, t in zip(COEFFICIENTS, theta):
        node, key = _node(d, path)
        node[key] = node[key] * float(np.exp(t))
    return vessel_from_dict(d)


def main(argv=None) -> int:
    import torch
    from scipy.optimize import minimize

    from _results import check_out, command_line, kind_table, publish, validation_dirs
    from hybridship.evaluation.manoeuvre import (ManoeuvreConfig, error_table, forecast_errors, load_runs,
                                                 make_predictors, start_rows)
    from hybridship.fileio import atomic_write
    from hybridship.forecast_inputs.wind import fit_wind_forecast
    from hybridship.predictors import DynamicPredictor
    from hybridship.vessel import VesselFileError, vessels_dir

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", type=Path, default=ROOT / "out" / "esso-osaka" / "split",
                    help="the benchmark's split (default out/esso-osaka/split)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-physics-fit")
    ap.add_argument("--evaluations", type=int, default=600, help="Powell's function evaluations (default 600)")
    ap.add_argument("--average", action="store_true",
                    help="also score the mean of the forecasts of the hybrids on both physics")
    ap.add_argument("--results", type=Path, help="also copy theta.csv, errors.csv and tables.md here (no data)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    check_out(ap, args.results, option="--results")
    if args.evaluations < 1:        # scipy's Powell stopped with its own error after the split was made
        ap.error(f"--evaluations: expected a positive integer, got {args.evaluations}")
    if (dirs := validation_dirs(args.split, args.out / "split")) is None:
        return 2
    fit_dir, val_dir = dirs
    torch.set_num_threads(1)
    base = tomllib.loads((vessels_dir() / "esso_osaka_model.toml").read_text())
    cfg = ManoeuvreConfig()
    v0 = vessel_with_factors(base, np.zeros(len(COEFFICIENTS)))
    fit_logs = [r.arrays for r in load_runs(fit_dir, v0)]
    wf, _ = fit_wind_forecast(fit_logs, 30.0)
    horizons = (5.0, 10.0, 20.0, 30.0)
    dt = fit_logs[0].dt_s
    steps = np.array([int(round(h / dt)) for h in horizons])

    def errors(p, arrays, every_s):
        rows = start_rows(arrays, int(steps.max()), every_s)
        return forecast_errors(lambda a, st, h: p.forecast(a, st, horizon_s=h, commands="known"), arrays, rows,
                               steps)

    # the heading error in metres as the multi-step loss weighs it (MultiStepConfig.heading_length_m)
    half_length_m = 0.5 * v0.particulars.L_pp_m

    def objective(theta):
        try:
            v = vessel_with_factors(base, theta)
        except VesselFileError:      # a coefficient outside its allowed range
            return 10.0
        p = DynamicPredictor(v, residual_config=cfg.residual, wind_forecast=wf)
        e = np.concatenate([errors(p, a, 5.0)[:, -1] for a in fit_logs])
        return float(e[:, 3].mean() + half_length_m * np.radians(e[:, 2]).mean())

    res = minimize(objective, np.zeros(len(COEFFICIENTS)), method="Powell",
                   options=dict(maxfev=args.evaluations, xtol=0.02, ftol=1e-4))
    start = objective(np.zeros(len(COEFFICIENTS)))
    fit_line = (f"Free-run fit on the fitting runs: objective {start:.4f} -> {res.fun:.4f} "
                f"({1.0 - res.fun / start:.0%} lower; {res.nfev} evaluations).")
    print(fit_line)
    rows = []
    for path, t in zip(COEFFICIENTS, res.x):
        node, key = _node(base, path)
        rows.append(f"{path},{node[key]:.6g},{node[key] * np.exp(t):.6g}")
        print(f"  {path}: {node[key]:.4g} -> {node[key] * np.exp(t):.4g}")
    atomic_write(args.out / "theta.csv", lambda fh: fh.write(
        ("coefficient,published,identified\n" + "\n".join(rows) + "\n").encode()))

    vf = vessel_with_factors(base, res.x)
    cfg = dataclasses.replace(cfg, calibration=dataclasses.replace(cfg.calibration, horizon_s=max(horizons)),
                              wind_samples=0)   # the spread is not scored here
    per, runs, hybrids = {}, None, []
    for suffix, v in (("", v0), ("_fitted", vf)):
        runs = load_runs(val_dir, v)
        logs = [r.arrays for r in load_runs(fit_dir, v)]
        hyb = make_predictors(v, cfg)["hybrid"].fit(logs, row_stride=cfg.train_row_stride)
        hybrids.append(hyb)
        for name, p in ((f"dynamic{suffix}", DynamicPredictor(v, residual_config=cfg.residual)),
                        (f"hybrid{suffix}", hyb)):
            per[(name, "known")] = [errors(p, r.arrays, cfg.start_every_s) for r in runs]
    if args.average:
        from esso_error_sources import _mean_forecast

        mean = _mean_forecast(hybrids)
        per[("hybrid_average", "known")] = [
            forecast_errors(lambda a, st, h: mean(a, st, h, commands="known"), r.arrays,
                            start_rows(r.arrays, int(steps.max()), cfg.start_every_s), steps) for r in runs]
    table = error_table(per, runs, horizons)
    atomic_write(args.out / "errors.csv", lambda fh: fh.write(table.to_csv(index=False).encode()))
    command = command_line("esso_physics_fit.py", argv)
    md = [f"Command: `{command}`", "", fit_line, "", "Identified coefficients in `theta.csv`. Validation runs, "
          "logged commands known: 30-s distance [m] / heading [deg] per kind and pooled, and the pooled ratios "
          "to the physics on the published coefficients (`dynamic`):", "", kind_table(table, "dynamic")]
    text = "\n".join(md) + "\n"
    atomic_write(args.out / "tables.md", lambda fh: fh.write(text.encode()))
    publish(args.out, args.results, ("theta.csv", "errors.csv", "tables.md"))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
