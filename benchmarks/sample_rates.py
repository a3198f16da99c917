"""Station-keeping forecasts from logs sampled at 10 Hz and at 1 Hz: the step of the residual fit.

Simulates four DP scenarios of the Gunnerus (seeds 20-23; 10-Hz logs, DP for 600 s, then a
300-s drift), keeps every 10th row for the 1-Hz copies, trains a hybrid (2 members, seed 0) on
three of them (seeds 21-23) and forecasts 60 s ahead from starts every 10 s between 200 s and
590 s (station keeping) on all four. Prints (and with ``--out`` writes) the root-mean-square
position error at 60 s with the nets on and off, for

* ``1 Hz``: the 1-Hz logs (read as they are);
* ``10 Hz, residual_step_s 1 s``: the 10-Hz logs, their one-step fit on every 10th row (the
  default, :attr:`hybridship.residual.features.ResidualConfig.residual_step_s`);
* ``10 Hz, residual_step_s None``: the 10-Hz logs, every row (before the default).

Usage: ``python benchmarks/sample_rates.py [--out FILE]`` (about 2 minutes on one core); the page's
table: ``--out docs/results/sample-rates/sample_rates.md``.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

from _results import check_out
from hybridship.fileio import markdown_table, write_text
from hybridship.predictors import HybridPredictor
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import ResidualConfig
from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

SEEDS = (20, 21, 22, 23)          # the first is not trained on
STARTS_S = [float(t) for t in range(200, 591, 10)]


def position_rms_m(hp, log, nets: bool) -> float:
    """60-s position error (RMS over the starts) of ``hp`` on ``log`` against its true track."""
    fc = hp.forecast(log, STARTS_S, 60.0, nets=nets)
    t = np.round(log.time_s.to_numpy(), 6)
    rows = np.searchsorted(t, np.round(np.array(STARTS_S) + 60.0, 6))
    d = fc.eta[:, -1, :2] - log[["truth_north_m", "truth_east_m"]].to_numpy()[rows]
    return float(np.sqrt(np.mean((d ** 2).sum(axis=1))))


def main(argv=None) -> int:
    import pandas as pd

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="also write the table to this Markdown file")
    args = ap.parse_args(argv)
    check_out(ap, args.out, file=True)
    fast = {s: simulate_dp_loss(DPLossConfig(dt_s=0.1, sim_dt_s=0.1, control_dt_s=1.0, t_shutdown_s=600.0,
                                             t_shutdown_jitter_s=0.0, drift_s=300.0, seed=s)) for s in SEEDS}
    slow = {s: log.iloc[::10].reset_index(drop=True) for s, log in fast.items()}
    rows = []
    for name, logs, step in (("1 Hz", slow, 1.0), ("10 Hz, residual_step_s 1 s", fast, 1.0),
                             ("10 Hz, residual_step_s None", fast, None)):
        hp = HybridPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=2, seed=0),
                             residual_config=ResidualConfig(residual_step_s=step))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")         # the logs' fault notes are not the point here
            hp.fit([logs[s] for s in SEEDS[1:]])
            row = {"logs, fit": name}
            for s in SEEDS:
                on, off = position_rms_m(hp, logs[s], True), position_rms_m(hp, logs[s], False)
                row[f"seed {s}{'' if s in SEEDS[1:] else ' (not trained on)'}"] = f"{on:.2f} / {off:.2f}"
        rows.append(row)
        print(row, flush=True)
    text = ("60-s position error [m], RMS over starts every 10 s from 200 to 590 s (station keeping), "
            "nets on / nets off:\n\n" + markdown_table(pd.DataFrame(rows)) + "\n")
    print(text)
    if args.out is not None:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
