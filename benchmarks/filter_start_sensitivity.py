"""How much a drift forecast depends on where its environment filter started.

A hybrid forecast with the environment estimator starts its filter at the last whole
multiple of 5 min (:data:`hybridship.predictors.hybrid.FILTER_START_GRID_S`) of log time at
least ``environment_window_s`` (30 min) before the start
(:meth:`hybridship.predictors.HybridPredictor._filter_groups`), so a start's forecast does
not depend on the other starts of a call. Where the filter starts still matters: its
start-up transient is not entirely forgotten by the start (the current, unobservable
during station keeping apart from the load, keeps part of it). This script measures that
part. Each test log is forecast at the drift benchmark's 20 starts after its failure with
its time axis shifted by ``0, 50, ..., 250 s`` (each shift moves the filter's first row
against the data by that much, or by that much less 300 s, and changes nothing else but
the members' draws, which are keyed by start time); it reports

* ``error``: the mean absolute error at 60 s over the 20 starts and all logs, per shift;
* ``spread_across_shifts``: per start, the standard deviation of the 60-s forecast mean
  across the shifts, averaged over starts and logs, against the error.

Example (the model from ``hybridship train``)::

    hybridship train --logs ../shared/data/truthsim-dev/logs --out out/truthsim-dev.npz
    python benchmarks/filter_start_sensitivity.py --model out/truthsim-dev.npz \
        --test ../shared/data/truthsim-dev/logs --out docs/results/filter-start-sensitivity
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.frames import wrap_pi
from hybridship.logs.io import read_log
from hybridship.predictors import HybridPredictor
from hybridship.predictors.after_failure import drift_forecasts

SHIFTS_S = (0.0, 50.0, 100.0, 150.0, 200.0, 250.0)
STATES = ("north_m", "east_m", "yaw_deg")


def forecasts_per_shift(hp, log: pd.DataFrame, shifts_s=SHIFTS_S) -> tuple[np.ndarray, np.ndarray]:
    """60-s forecast means and truths (n_shifts, 20, 3) of one log, its time axis shifted."""
    preds, truths = [], []
    for shift in shifts_s:
        moved = log.assign(time_s=log["time_s"] + shift)
        pred, truth, _ = drift_forecasts(hp, moved, n_intervals=20, horizons_s=(60.0,))
        preds.append(pred[:, 0])
        truths.append(truth[:, 0])
    return np.stack(preds), np.stack(truths)


def summary(preds: list[np.ndarray], truths: list[np.ndarray], shifts_s=SHIFTS_S) -> pd.DataFrame:
    """Rows per shift (the pooled error) and one row of the spread across shifts."""
    def in_units(d):
        return np.concatenate([d[..., :2], np.degrees(wrap_pi(d[..., 2:]))], axis=-1)

    err = np.concatenate([np.abs(in_units(p - t)) for p, t in zip(preds, truths)], axis=1)   # (n_shifts, S, 3)
    rows = [{"what": f"error, time shifted {s:g} s", **dict(zip(STATES, err[k].mean(axis=0)))}
            for k, s in enumerate(shifts_s)]
    spread = np.concatenate([in_units(p - p[:1]).std(axis=0) for p in preds])              # (S, 3)
    rows.append({"what": "spread of the forecast across the shifts (std per start)",
                 **dict(zip(STATES, spread.mean(axis=0)))})
    rows.append({"what": "largest change of a forecast across the shifts",
                 **dict(zip(STATES, np.concatenate([np.ptp(in_units(p - p[:1]), axis=0) for p in preds]).max(axis=0)))})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", required=True, help="hybrid model file (.npz)")
    ap.add_argument("--test", required=True, help="folder of DP-loss logs")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    hp = HybridPredictor.load(args.model)
    files = log_files(Path(args.test))
    preds, truths = zip(*(forecasts_per_shift(hp, read_log(f)) for f in files))
    table = summary(list(preds), list(truths))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv = table.to_csv(index=False, float_format="%.4f")
    atomic_write(out / "filter_start_sensitivity.csv", lambda fh: fh.write(csv.encode("utf-8")))
    text = (f"Model {Path(args.model).name}; {len(files)} test logs, 20 starts after each failure; 60-s forecast "
            f"mean; north and east in m, yaw in deg.\n\n" + markdown_table(table.round(3)) + "\n")
    atomic_write(out / "filter_start_sensitivity.md", lambda fh: fh.write(text.encode("utf-8")))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
