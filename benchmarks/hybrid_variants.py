"""Which part of the hybrid helps after a DP failure? A comparison on truthsim-dev.

Trains on the DP part of every log in ``../shared/data/truthsim-dev/logs`` (the paper's
protocol) and forecasts 60 s ahead from the first 20 start times after each shutdown.
Writes (and prints) the 60-s mean absolute error in north, east and heading over the first
5 / first 20 intervals, averaged over the logs, with the change against physics alone, for:

* ``physics``: the dynamic model alone (thrusters stopped after the failure);
* ``paper scheme``: no environment term, the previous residual from the last 10 s, nets
  always on (Skulstad et al. 2022);
* ``mean bias + nets (guarded)``: the 900-s mean residual and the guarded nets (the
  default before the environment estimator);
* ``estimator alone``: physics + the environment estimator, nets off;
* ``hybrid (default, no hull yaw moment in a drift)``: the estimator and the guarded nets (off after a
  failure); scored on the training logs' own drifts, so the hull's yaw moment in a drift, which
  is learned from failures, is off;
* ``estimator + nets, unguarded``: the nets always on.

Usage: ``python benchmarks/hybrid_variants.py [--data DIR] [--members 10] [--seed 0] [--out DIR]``
(``--out`` writes ``hybrid_variants.md``, included in ``docs/hybrid.md``, and ``timing.csv``,
each variant's training time ``variant,fit_s``, kept apart so that the table does not change
from run to run).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from _results import check_out
from hybridship.evaluation import metrics
from hybridship.fileio import atomic_write
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import ResidualConfig

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "truthsim-dev" / "logs"


def _summary(errors):
    E = np.stack(errors)[:, :, -1, :]          # (logs, intervals, N/E/yaw) at 60 s
    return E[:, :5].mean(axis=(0, 1)), E[:, :20].mean(axis=(0, 1))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--members", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, help="folder for hybrid_variants.md")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    try:                # before the logs are read (EnsembleConfig's traceback came after)
        ens = EnsembleConfig(n_members=args.members, seed=args.seed)
    except ValueError as exc:           # "n_members: must be >= 1 (got 0) [EnsembleConfig]": name the option
        field, _, reason = str(exc).partition(":")
        ap.error({"n_members": "--members"}.get(field, f"--{field}") + ":" + reason)
    files = sorted(args.data.glob("*.csv.gz"))
    if not files:
        if args.data != DEFAULT_DATA:   # a folder named on the command line: not the shared data set missing
            ap.error(f"--data: no logs (*.csv.gz) in {args.data}")
        print(f"no logs in {args.data}: the shared truthsim-dev data set is not on this machine")
        return 0
    dyn = DynamicPredictor("gunnerus")
    logs = [as_log_arrays(f, dyn.model.vessel) for f in files]
    rows = [("physics", _summary([metrics.drift_errors(dyn, a) for a in logs]), 0.0)]

    def fitted(**kw):
        # scored on the training logs' own drifts: nothing is learned from them (drift_hull off)
        hp = HybridPredictor("gunnerus", ensemble_config=ens, drift_hull=False, **kw)
        t0 = time.perf_counter()
        hp.fit(logs)
        return hp, time.perf_counter() - t0

    paper, t_paper = fitted(residual_config=ResidualConfig(bias_window_s=0.0, start_residual_window_s=10.0,
                                                           deriv_window_s=11.0), environment="mean")
    paper_kw = dict(guard=False, nets_after_stop=True)         # the paper's scheme: nets everywhere, unguarded
    rows.append(("paper scheme", _summary([metrics.drift_errors(paper, a, **paper_kw) for a in logs]), t_paper))
    mean, t_mean = fitted(environment="mean")
    rows.append(("mean bias + nets (guarded)", _summary([metrics.drift_errors(mean, a) for a in logs]), t_mean))
    hp, t_hp = fitted()
    rows.append(("estimator alone", _summary([metrics.drift_errors(hp, a, nets=False) for a in logs]), t_hp))
    rows.append(("hybrid (default, no hull yaw moment in a drift)",
                 _summary([metrics.drift_errors(hp, a) for a in logs]), t_hp))
    rows.append(("estimator + nets, unguarded",
                 _summary([metrics.drift_errors(hp, a, **paper_kw) for a in logs]), t_hp))
    ref5, ref20 = rows[0][1]
    lines = [f"truthsim-dev, {len(files)} logs, trained on their DP parts; 60-s mean absolute error "
             f"(first 5 / first 20 intervals) and change against physics alone.", "",
             "| variant | north [m] | east [m] | heading [deg] | north change | east change | heading change |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for name, (e5, e20), _ in rows:
        ch5 = 100 * (e5 / ref5 - 1)
        ch20 = 100 * (e20 / ref20 - 1)
        lines.append(f"| {name} | {e5[0]:.2f}/{e20[0]:.2f} | {e5[1]:.2f}/{e20[1]:.2f} | {e5[2]:.2f}/{e20[2]:.2f} | "
                     f"{ch5[0]:+.0f}%/{ch20[0]:+.0f}% | {ch5[1]:+.0f}%/{ch20[1]:+.0f}% | "
                     f"{ch5[2]:+.0f}%/{ch20[2]:+.0f}% |")
    text = "\n".join(lines) + "\n"
    # training times apart from the table, so that the same command gives the same table
    timing = "variant,fit_s\n" + "".join(f"{name},{fit_s:.1f}\n" for name, _, fit_s in rows)
    print(text)
    print(timing)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        atomic_write(args.out / "hybrid_variants.md", lambda fh: fh.write(text.encode("utf-8")))
        atomic_write(args.out / "timing.csv", lambda fh: fh.write(timing.encode("utf-8")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
