"""One missing sample before a forecast's start: filtered across, or a restart of the estimator.

Simulates four DP scenarios of the Gunnerus (seeds 30-33; DP for 1800 s, then a 300-s drift),
trains a hybrid (3 members, seed 0) on three of them (seeds 31-33) and forecasts 60 s ahead
on the fourth from starts every 20 s between 1000 s and 1780 s (station keeping) and every
5 s from 1805 s to 1880 s (the drift after the failure at 1800 s). Each start is forecast
from the whole log and from the log without its one sample 4 s before the start, with the
environment estimator's ``max_bridged_gap_s`` at 10 s (the default: the gap is filtered
across) and at 0 (every gap restarts the filter's motion states, the earlier behaviour).
Prints (and with ``--out`` writes) how far the missing sample moves the 60-s forecast: the
end point [m] and the heading [deg], mean and maximum over the starts.

Usage: ``python benchmarks/gap_sensitivity.py [--out FILE]`` (about a minute on one core);
the page's table: ``--out docs/results/gap-sensitivity/gap_sensitivity.md``.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

from _results import check_out
from hybridship.fileio import markdown_table, write_text
from hybridship.frames import wrap_pi
from hybridship.predictors import HybridPredictor
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import EnvironmentConfig
from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

SEEDS = (30, 31, 32, 33)          # the first is not trained on
T_SHUTDOWN_S = 1800.0
STARTS_S = {"station keeping": [float(t) for t in range(1000, 1781, 20)],
            "after the failure": [float(t) for t in range(1805, 1881, 5)]}
MISSING_BEFORE_S = 4.0


def shifts(hp, log, starts) -> tuple[np.ndarray, np.ndarray]:
    """End-point [m] and heading [deg] moves of the 60-s forecasts from ``starts`` when the
    sample ``MISSING_BEFORE_S`` before each start is missing (one start at a time)."""
    full = hp.forecast(log, starts, 60.0)
    d_pos, d_psi = [], []
    for k, t0 in enumerate(starts):
        holed = log[np.round(log.time_s, 6) != round(t0 - MISSING_BEFORE_S, 6)]
        fc = hp.forecast(holed, [t0], 60.0)
        d_pos.append(float(np.hypot(*(fc.eta[0, -1, :2] - full.eta[k, -1, :2]))))
        d_psi.append(float(np.degrees(abs(wrap_pi(fc.eta[0, -1, 2] - full.eta[k, -1, 2])))))
    return np.array(d_pos), np.array(d_psi)


def main(argv=None) -> int:
    import pandas as pd

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="also write the table to this Markdown file")
    args = ap.parse_args(argv)
    check_out(ap, args.out, file=True)
    logs = {s: simulate_dp_loss(DPLossConfig(t_shutdown_s=T_SHUTDOWN_S, t_shutdown_jitter_s=0.0, drift_s=300.0,
                                             seed=s)) for s in SEEDS}
    rows = []
    for name, gap_s in (("filtered across (max_bridged_gap_s 10 s)", 10.0),
                        ("restart (max_bridged_gap_s 0, before)", 0.0)):
        hp = HybridPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=3, seed=0),
                             environment_config=EnvironmentConfig(max_bridged_gap_s=gap_s))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")         # the logs' fault notes are not the point here
            hp.fit([logs[s] for s in SEEDS[1:]])
            for part, starts in STARTS_S.items():
                d_pos, d_psi = shifts(hp, logs[SEEDS[0]], starts)
                rows.append({"missing sample": name, "starts": f"{part} ({len(starts)})",
                             "end point moved, mean / max [m]": f"{d_pos.mean():.2f} / {d_pos.max():.2f}",
                             "heading moved, mean / max [deg]": f"{d_psi.mean():.2f} / {d_psi.max():.2f}"})
                print(rows[-1], flush=True)
    text = (f"How far one missing sample, {MISSING_BEFORE_S:g} s before the start, moves the hybrid's 60-s "
            f"forecast (seed {SEEDS[0]}, not trained on):\n\n" + markdown_table(pd.DataFrame(rows)) + "\n")
    print(text)
    if args.out is not None:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
