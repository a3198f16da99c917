"""The drift benchmark's errors by group of failures (for example calm against rough weather).

``hybridship benchmark drift`` pools every failure of its test logs into one table. The
independent evaluation reports calm and rough weather apart, and a pooled ratio can hide a
group in which the hybrid is worse than the physics. This script reads the benchmark's
``errors_per_log.csv`` and prints, for each group of logs (named by shell-style patterns),
the error of ``--model`` as a ratio to ``--reference`` (first 5 / first 20 intervals), the
mean over the group's logs as in Table 2::

    python benchmarks/drift_groups.py docs/results/drift-truthsim-dev \\
        --group "calm=calm_*" --group "rough=dev_*"

``--out FILE`` also writes the table as Markdown; ``--horizon-s`` picks the horizon
(default: the longest).
"""

from __future__ import annotations

import argparse
import fnmatch
import sys
from pathlib import Path

import numpy as np
import pandas as pd


def group_logs(per_log: pd.DataFrame, groups: dict) -> dict:
    """Group name -> the logs of ``per_log`` that match any of its shell-style patterns."""
    out = {}
    for name, patterns in groups.items():
        logs = [lg for lg in dict.fromkeys(per_log.log) if any(fnmatch.fnmatch(lg, p) for p in patterns)]
        if not logs:
            raise ValueError(f"--group {name}: no log matches {', '.join(patterns)}")
        out[name] = logs
    return out


def group_ratios(per_log: pd.DataFrame, groups: dict, model: str = "hybrid", reference: str = "dynamic",
                 horizon_s: float | None = None) -> pd.DataFrame:
    """Rows ``(group, state)``, columns window: mean error of ``model`` over the group's logs
    divided by that of ``reference``, at ``horizon_s`` [s] (default the longest): the
    benchmark's per-failure ratio (:func:`hybridship.evaluation.drift.ratio_table`) with
    each group's logs averaged into one, as Table 2 averages all of them."""
    from hybridship.evaluation.drift import ratio_table

    missing = {"model", "log", "state", "window", "horizon_s", "mae"} - set(per_log.columns)
    if missing:
        raise ValueError(f"errors_per_log.csv: columns {sorted(missing)} missing")
    for field, name in (("--model", model), ("--reference", reference)):
        if name not in set(per_log.model):
            raise ValueError(f"{field} {name!r}: not in the results (models: {', '.join(dict.fromkeys(per_log.model))})")
    if horizon_s is not None and horizon_s not in set(per_log.horizon_s):
        raise ValueError(f"--horizon-s {horizon_s:g}: not in the results (horizons: "
                         f"{', '.join(f'{x:g}' for x in sorted(per_log.horizon_s.unique()))} s)")
    means = [per_log[per_log.log.isin(logs)].groupby(["model", "state", "window", "horizon_s"], as_index=False)
             .mae.mean().assign(log=name) for name, logs in group_logs(per_log, groups).items()]
    ratio = ratio_table(pd.concat(means, ignore_index=True), model, reference, horizon_s)
    return ratio.rename_axis(index=["group", "state"])


def ratios_above_one(per_log: pd.DataFrame, groups: dict, model: str = "hybrid", reference: str = "dynamic",
                     horizon_s: float | None = None) -> dict:
    """Group name -> ``(k, n)``: ``k`` of the group's ``n`` finite per-failure ratios
    (:func:`hybridship.evaluation.drift.ratio_table`, every log, state and window at
    ``horizon_s``) are above 1."""
    from hybridship.evaluation.drift import ratio_table

    out = {}
    for name, logs in group_logs(per_log, groups).items():
        r = ratio_table(per_log[per_log.log.isin(logs)], model, reference, horizon_s).to_numpy()
        r = r[np.isfinite(r)]
        out[name] = (int((r > 1.0).sum()), int(r.size))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a drift benchmark's output folder (with errors_per_log.csv)")
    ap.add_argument("--group", action="append", required=True,
                    help="NAME=PATTERN[,PATTERN...]: the logs of one group (repeat for each group)")
    ap.add_argument("--model", default="hybrid")
    ap.add_argument("--reference", default="dynamic")
    ap.add_argument("--horizon-s", type=float, default=None)
    ap.add_argument("--out", type=Path, default=None, help="also write the table to this Markdown file")
    args = ap.parse_args(argv)
    path = args.results / "errors_per_log.csv"
    if not path.is_file():
        print(f"error: {path}: not found; run `hybridship benchmark drift --out {args.results}` first",
              file=sys.stderr)
        return 2
    groups = {}
    for g in args.group:
        name, sep, pats = g.partition("=")
        if not sep or not name or not pats:
            print(f"error: --group {g!r}: expected NAME=PATTERN[,PATTERN...]", file=sys.stderr)
            return 2
        if name in groups:
            print(f"error: --group {name!r}: given twice", file=sys.stderr)
            return 2
        groups[name] = [q.strip() for q in pats.split(",") if q.strip()]
    per_log = pd.read_csv(path)
    try:
        t = group_ratios(per_log, groups, args.model, args.reference, args.horizon_s)
        counts = {k: len(v) for k, v in group_logs(per_log, groups).items()}
        above = ratios_above_one(per_log, groups, args.model, args.reference, args.horizon_s)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    from hybridship.evaluation.drift import ratio_cells
    from hybridship.fileio import markdown_table, record_inputs, write_text

    cells = ratio_cells(t.rename_axis(index=["log", "state"]))
    cells.insert(0, "logs", [counts[g] for g in cells.index])
    cells["ratios above 1"] = [f"{above[g][0]} of {above[g][1]}" for g in cells.index]
    h = per_log.horizon_s.max() if args.horizon_s is None else args.horizon_s
    lo, hi = t.columns[0], t.columns[-1]
    windows = f"first {lo}" if lo == hi else f"first {lo} / first {hi}"
    text = (f"`{args.model}` / `{args.reference}` at {h:g} s, {windows} intervals "
            f"(mean over each group's logs):\n\n" + markdown_table(cells.rename_axis("group").reset_index()) + "\n")
    print(text, end="")
    if args.out is not None:
        write_text(args.out, text)
        record_inputs(args.out, [path])
    return 0


if __name__ == "__main__":
    sys.exit(main())
