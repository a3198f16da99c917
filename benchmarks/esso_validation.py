"""Esso Osaka: the hybrid's guard quantile on a validation split of the training runs.

The validation study of the envelope guard's quantile that ``docs/esso-osaka.md`` cites
(its "Caveats": a stricter envelope did not fix berthing) comes from::

    python benchmarks/esso_validation.py --out out/esso-validation

It splits the *training* runs of the benchmark (``out/esso-osaka/split/train``, made by
``benchmarks/esso_osaka.py``) again, seed 1, into a fitting part and a validation part;
the benchmark's test runs play no part. The hybrid is trained once; for each guard
quantile only the envelope guard is refitted (the ensemble does not depend on it), and
the physics alone is the reference. Writes ``errors.csv`` (the manoeuvre benchmark's
columns, the model named ``hybrid_q<quantile>``) and prints the distance errors.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    import torch

    from _results import check_out, parse_horizons
    from hybridship.fileio import atomic_write
    from hybridship.evaluation.manoeuvre import (COMMAND_MODES, ManoeuvreConfig, _fit, error_table, forecast_errors,
                                      load_runs, make_predictors, split_runs, start_rows)
    from hybridship.residual.guard import EnvelopeGuard
    from hybridship.vessel import load_vessel

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train", type=Path, default=ROOT / "out" / "esso-osaka" / "split" / "train",
                    help="the benchmark's training runs (default out/esso-osaka/split/train)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-validation")
    ap.add_argument("--quantiles", default="0.99,0.95,0.9,0.8", help="guard quantiles to compare")
    ap.add_argument("--horizons-s", default="5,10,20,30")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    # checked before the hybrid is trained (a bad quantile ended in the guard's traceback after it)
    try:
        quantiles = [float(q) for q in args.quantiles.split(",")]
    except ValueError:
        ap.error(f"--quantiles: expected numbers like 0.99,0.95, got {args.quantiles!r}")
    if not all(0.5 <= q < 1.0 for q in quantiles):
        ap.error(f"--quantiles: each must lie in [0.5, 1) (EnvelopeGuard.fit), got {args.quantiles!r}")
    horizons = parse_horizons(ap, args.horizons_s)
    torch.set_num_threads(1)
    if not args.train.is_dir():
        print(f"error: {args.train}: not found; run benchmarks/esso_osaka.py first", file=sys.stderr)
        return 2

    fit_dir, val_dir = split_runs(args.train, args.out / "split", seed=1)
    v = load_vessel("esso_osaka_model")
    cfg = ManoeuvreConfig()
    fit_runs, val_runs = load_runs(fit_dir, v), load_runs(val_dir, v)
    preds = make_predictors(v, cfg)
    hyb, dyn = preds["hybrid"], preds["dynamic"]
    _fit("hybrid", hyb, fit_runs, cfg)
    X, _, _ = hyb.training_data([r.arrays for r in fit_runs])
    Z = (X[::cfg.train_row_stride] - hyb.ensemble.x_mean) / hyb.ensemble.x_std

    dt = float(np.median(np.diff(val_runs[0].arrays.time_s)))
    steps = np.array([int(round(h / dt)) for h in horizons])
    models = {"dynamic": (dyn, None)} | {f"hybrid_q{q:g}": (hyb, q) for q in quantiles}
    per = {}
    for name, (p, q) in models.items():
        if q is not None:
            hyb.guard = EnvelopeGuard.fit(Z, quantile=q)
        for mode in COMMAND_MODES:
            per[(name, mode)] = [forecast_errors(lambda a, st, h: p.forecast(a, st, horizon_s=h, commands=mode),
                                                 r.arrays, start_rows(r.arrays, int(steps.max()), cfg.start_every_s),
                                                 steps) for r in val_runs]
    errors = error_table(per, val_runs, horizons)
    atomic_write(args.out / "errors.csv", lambda fh: fh.write(errors.to_csv(index=False).encode()))
    d = errors[errors.state == "distance_m"].pivot_table(index=["commands", "kind", "model"], columns="horizon_s",
                                                         values="mae", sort=False)
    print(f"validation runs: {', '.join(r.name for r in val_runs)}")
    print("distance error [m]:")
    print(d.round(3).to_string())
    print(f"wrote {args.out / 'errors.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
