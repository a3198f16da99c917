"""Which part of the hybrid helps after a DP failure? A comparison on truthsim-dev.

Trains on the DP part of every log in ``../shared/data/truthsim-dev/logs`` and forecasts
60 s ahead from the first 20 start times after each shutdown. Prints the mean absolute
60-s error in north and east over the first 5 and the first 20 intervals, averaged over
the logs, for:

* ``dynamic``: the physics alone (thrusters stopped after the failure);
* ``paper``: the paper's scheme (no bias; previous residual from the last 10 s);
* ``bias+nn``: the default hybrid (900-s residual bias + learned deviation), with and
  without the guard (Mahalanobis envelope of the nets' features times the thrust regime:
  nets trained on station keeping are switched off once the thrusters stop);
* ``bias only``: the default hybrid with the learned deviation switched off.

Usage: ``python benchmarks/hybrid_variants.py [--data DIR] [--members 10] [--seed 0]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from hybridship import metrics
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import ResidualConfig

DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "truthsim-dev" / "logs"


def _summary(errors):
    E = np.stack(errors)[:, :, -1, :2]          # (logs, intervals, N/E) at 60 s
    return E[:, :5].mean(axis=(0, 1)), E[:, :20].mean(axis=(0, 1))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--members", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    files = sorted(args.data.glob("*.csv.gz"))
    if not files:
        print(f"no logs in {args.data}: the shared truthsim-dev data set is not on this machine")
        return 0
    dyn = DynamicPredictor("gunnerus")
    logs = [as_log_arrays(f, dyn.model.vessel) for f in files]
    ens = EnsembleConfig(n_members=args.members, seed=args.seed)
    rows = [("dynamic", _summary([metrics.drift_errors(dyn, a) for a in logs]), 0.0)]
    variants = {
        "paper": ResidualConfig(bias_window_s=0.0, start_residual_window_s=10.0, deriv_window_s=11.0),
        "bias+nn": ResidualConfig(),
    }
    for name, rc in variants.items():
        hp = HybridPredictor("gunnerus", residual_config=rc, ensemble_config=ens)
        t0 = time.perf_counter()
        hp.fit(logs)
        fit_s = time.perf_counter() - t0
        rows.append((name, _summary([metrics.drift_errors(hp, a, guard=False) for a in logs]), fit_s))
        rows.append((name + " guarded", _summary([metrics.drift_errors(hp, a, guard=True) for a in logs]), fit_s))
        if name == "bias+nn":
            hp.guard.d0 = -np.inf   # weight 0 everywhere: the learned deviation is switched off
            rows.append(("bias only", _summary([metrics.drift_errors(hp, a, guard=True) for a in logs]), fit_s))
    ref5, ref20 = rows[0][1]
    print(f"truthsim-dev, {len(files)} logs, 60-s mean absolute error [m] (first 5 / first 20 intervals)")
    print("| variant | north 5/20 | east 5/20 | north change 5/20 | east change 5/20 | fit [s] |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, (e5, e20), fit_s in rows:
        ch5 = 100 * (e5 / ref5 - 1)
        ch20 = 100 * (e20 / ref20 - 1)
        print(f"| {name} | {e5[0]:.2f}/{e20[0]:.2f} | {e5[1]:.2f}/{e20[1]:.2f} | "
              f"{ch5[0]:+.0f}%/{ch20[0]:+.0f}% | {ch5[1]:+.0f}%/{ch20[1]:+.0f}% | {fit_s:.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
