"""Forecasts started later in a drift: the environment load's random walks after a failure, measured.

The drift tables score the first 20 starts after each failure. A user forecasting through a
drift also starts forecasts later, when the ship has turned and gathered speed and its
environment load has changed. This benchmark scores both, with the protocol of
``benchmarks/estimator_variants.py``: trained on the DP parts of all logs of a set, nets off
(``forecast(nets=False)``: physics + environment estimator), no hull's yaw moment in a
drift, each row changing one setting of the default
:class:`~hybridship.residual.environment.EnvironmentConfig`:

* ``first 5/20``: the 60-s mean absolute error over the first 5 / first 20 starts after each
  failure as a ratio to the physics alone (as the drift tables and the estimator variants);
* ``later``: the 60-s mean absolute error of starts every 10 s from 20 s after each failure
  to the last start with 60 s of log after it [m, deg], and its ratio to the physics alone
  and to dead reckoning on the same starts (rows ``physics`` and ``dead_reckoning`` give
  their own errors).

Writes ``late_starts.csv``, ``late_starts.md`` and ``late_starts_per_log.csv`` (the later
starts' 60-s error of every failure, per variant, state and predictor) to ``--out``.

Example (about 15 min on the 2-core machine)::

    python benchmarks/drift_late_starts.py --data embedded truthsim-dev own --out docs/results/drift-late-starts
"""

from __future__ import annotations

import sys
import time

import numpy as np
import pandas as pd

from hybridship.evaluation import metrics
from hybridship.fileio import markdown_table, write_text
from hybridship.predictors import DeadReckoning, DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.predictors.hybrid import AFTER_STOP_INTERVALS, LATE_START_EVERY_S
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import EnvironmentConfig

from _siblings import sibling  # benchmarks/ is on sys.path when a script runs

HORIZON_S = 60.0
C = EnvironmentConfig
_ON_STATION = dict(load_walk_after_stop_m_s2=C().load_walk_m_s2,
                   load_yaw_walk_after_stop_rad_s2=C().load_yaw_walk_rad_s2)
#: name -> (EnvironmentConfig fields, what the row shows)
VARIANTS = {
    "default": ({}, f"the default: load walks after a stop {C().load_walk_after_stop_m_s2:g} m/s2 and "
                    f"{C().load_yaw_walk_after_stop_rad_s2:g} rad/s2 per sqrt(s)"),
    "station_keeping_walks": (_ON_STATION, "the station keeping's load walks through the drift too "
                                           "(the filter before 2026-11-30)"),
    "ned_1e-4": ({**_ON_STATION, "load_walk_after_stop_m_s2": 1e-4}, "north/east load walk 1e-4 after a stop"),
    "ned_3e-4": ({**_ON_STATION, "load_walk_after_stop_m_s2": 3e-4}, "north/east load walk 3e-4 after a stop"),
    "ned_1e-3": ({**_ON_STATION, "load_walk_after_stop_m_s2": 1e-3}, "north/east load walk 1e-3 after a stop"),
    "yaw_1e-5": ({**_ON_STATION, "load_yaw_walk_after_stop_rad_s2": 1e-5}, "yaw load walk 1e-5 after a stop"),
    "ned_1e-4_yaw_1e-5": (dict(load_walk_after_stop_m_s2=1e-4, load_yaw_walk_after_stop_rad_s2=1e-5),
                          "both: 1e-4 and 1e-5"),
    "ned_1e-3_yaw_1e-5": (dict(load_walk_after_stop_m_s2=1e-3, load_yaw_walk_after_stop_rad_s2=1e-5),
                          "both: 1e-3 and 1e-5"),
    "ned_3e-4_yaw_3e-6": (dict(load_walk_after_stop_m_s2=3e-4, load_yaw_walk_after_stop_rad_s2=3e-6),
                          "both: 3e-4 and 3e-6"),
    "ned_3e-4_yaw_3e-5": (dict(load_walk_after_stop_m_s2=3e-4, load_yaw_walk_after_stop_rad_s2=3e-5),
                          "both: 3e-4 and 3e-5"),
}
TINY = EnsembleConfig(n_members=2, hidden=4, max_epochs=1, patience=1, seed=0)
STATES = ("north_m", "east_m", "yaw_deg")


def drift_errors(pred, arrays, **forecast_kw) -> dict[str, np.ndarray]:
    """60-s absolute errors (starts, 3) [m, m, deg] of ``pred`` on one log: ``"first"``, the first
    20 starts after its failure; ``"later"``, starts every 10 s from 20 s after it to the last
    start with 60 s of log after it."""
    dt = float(np.median(np.diff(arrays.time_s)))
    out = {}
    for group, kw in (("first", dict(n_intervals=AFTER_STOP_INTERVALS)),
                      ("later", dict(n_intervals=None, first=AFTER_STOP_INTERVALS,
                                     every=max(1, int(round(LATE_START_EVERY_S / dt)))))):
        p, t, _ = metrics.drift_forecasts(pred, arrays, horizons_s=(HORIZON_S,), **kw, **forecast_kw)
        out[group] = metrics.absolute_errors(p, t)[:, 0]
    return out


def table_row(data: str, variant: str, what: str, err: list, phys: list, dr: list) -> dict:
    """One row: per state, the first 5/20 starts' ratio to the physics and the later starts'
    mean error with its ratios to the physics and dead reckoning (lists of :func:`drift_errors`
    per log; the first-start means are over failures, as the drift tables')."""
    row = {"data": data, "variant": variant, "what": what}
    for j, state in enumerate(STATES):
        if err is not phys:
            r5 = np.mean([e["first"][:5, j].mean() for e in err]) / np.mean([e["first"][:5, j].mean() for e in phys])
            r20 = np.mean([e["first"][:, j].mean() for e in err]) / np.mean([e["first"][:, j].mean() for e in phys])
            row[f"{state} first 5/20 (x physics)"] = f"{r5:.2f}/{r20:.2f}"
        else:
            row[f"{state} first 5/20 (x physics)"] = ""
        late = [np.concatenate([e["later"][:, j] for e in x]).mean() for x in (err, phys, dr)]
        row[f"{state} later (x physics, x DR)"] = f"{late[0]:.2f} ({late[0] / late[1]:.2f}, {late[0] / late[2]:.2f})"
    return row


#: The data sets the default's load walks were chosen on (truthsim-dev played no part).
CHOICE_SETS = ("embedded", "own 100-119")


def later_ratio_sum(row: pd.Series) -> float:
    """The sum of a row's later-start ratios to the physics (north, east, heading), as printed
    to two decimals in its ``later (x physics, x DR)`` cells."""
    return sum(float(row[c].split("(")[1].split(",")[0]) for c in row.index if c.endswith("later (x physics, x DR)"))


def choice_summary(df: pd.DataFrame, choice_sets=CHOICE_SETS) -> str:
    """Markdown of the criterion the default was chosen by: per variant, the sum of the later
    starts' three ratios to the physics on each data set and over ``choice_sets`` (the
    smallest sum over those wins; the other sets played no part)."""
    rows = df[~df.variant.isin(["physics", "dead_reckoning"])]
    sums = rows.assign(s=rows.apply(later_ratio_sum, axis=1)).pivot_table(index="variant", columns="data", values="s",
                                                                         sort=False)
    sets = [c for c in choice_sets if c in sums.columns]
    if sets:
        sums[" + ".join(sets)] = sums[sets].sum(axis=1, skipna=False)
    table = sums.map(lambda x: f"{x:.2f}" if np.isfinite(x) else "").reset_index()
    return markdown_table(table.rename(columns={"variant": "variant (sum of the later starts' 3 ratios to physics)"}))


def main(argv=None) -> int:
    ev = sibling("estimator_variants")         # its data sets and shared arguments
    args = ev.parse_args(argv, __doc__.split("\n")[0], VARIANTS)
    rows, per_log = [], []
    sets = ev.data_sets(args.data, args.own_n, args.own_seed, args.logs)
    if not sets:                # --data truthsim-dev without it: no table to write
        print("error: --data: no data set to run (truthsim-dev is not on this machine)", file=sys.stderr)
        return 2
    for dname, (logs, names) in sets.items():
        dyn, dr = DynamicPredictor("gunnerus").fit(), DeadReckoning("gunnerus").fit()
        arrays = [as_log_arrays(x, dyn.model.vessel) for x in logs]
        base = {"physics": [drift_errors(dyn, a) for a in arrays],
                "dead_reckoning": [drift_errors(dr, a) for a in arrays]}
        results = dict(base)
        for vname in args.only:
            t0 = time.perf_counter()
            fields, what = VARIANTS[vname]
            hp = HybridPredictor("gunnerus", ensemble_config=TINY, drift_hull=False,
                                 environment_config=C(**fields)).fit(arrays, dp_only=True)
            results[vname] = [drift_errors(hp, a, nets=False) for a in arrays]
            rows.append(table_row(dname, vname, what, results[vname], base["physics"], base["dead_reckoning"]))
            print(rows[-1], f"({time.perf_counter() - t0:.0f} s)", flush=True)
        for ref, what in (("physics", "the physics alone"), ("dead_reckoning", "constant velocity")):
            rows.append(table_row(dname, ref, what, base[ref], base["physics"], base["dead_reckoning"]))
        per_log += [{"data": dname, "predictor": name, "log": log, "state": state,
                     "later_mae": float(e["later"][:, j].mean()), "later_starts": int(e["later"].shape[0])}
                    for name, errs in results.items() for log, e in zip(names, errs) for j, state in enumerate(STATES)]
    df = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    write_text(args.out / "late_starts.csv", df.to_csv(index=False))
    write_text(args.out / "late_starts_per_log.csv", pd.DataFrame(per_log).round({"later_mae": 3}).to_csv(index=False))
    md = markdown_table(df) + "\n\n" + choice_summary(df) + "\n"
    write_text(args.out / "late_starts.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
