"""Esso Osaka manoeuvring benchmark (issue 6): split, train, forecast, tables and figures.

One command makes everything on ``docs/esso-osaka.md``::

    python benchmarks/esso_osaka.py --out out/esso-osaka

It splits the runs of ``../shared/data/esso-osaka-frt/data`` into train and test folders
(symbolic links, whole recordings per side, seed 0; the data are never copied), runs
:func:`hybridship.evaluation.manoeuvre.run_manoeuvre_benchmark` on them, writes ``errors.csv`` and
``README.md`` to ``--out``, the figures ``docs/figures/esso_*.png``, and replaces the
generated tables between the ``<!-- generated:... -->`` markers of ``docs/esso-osaka.md``,
and copies the result files (:data:`RESULT_FILES`) to ``docs/results/esso-osaka``.
With ``--quick`` it makes a smoke run (small ensembles, starts every 5 s) and leaves the
docs alone unless ``--docs`` is given.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The benchmark's result files that the full run copies to ``docs/results/esso-osaka``.
RESULT_FILES = ("README.md", "errors.csv", "coverage.csv", "coverage_heading.csv", "coverage_intervals.csv",
                "sharpness.csv")


def replace_generated(text: str, key: str, body: str) -> str:
    """Replace the block between ``<!-- generated:key -->`` and ``<!-- /generated:key -->``."""
    pat = re.compile(rf"(<!-- generated:{re.escape(key)} -->\n).*?(<!-- /generated:{re.escape(key)} -->)", re.S)
    if not pat.search(text):
        raise ValueError(f"docs: no generated block {key!r}")
    return pat.sub(lambda m: m.group(1) + body + m.group(2), text)


def _wind_text(hybrid) -> str:
    """How the fitted hybrid forecasts the wind (from its ``training_info``)."""
    info = hybrid.training_info.get("wind_forecast")
    if not info or info["held"]:
        return "held at its start value"
    return (f"a gust decaying to the {info['mean_window_s']:g}-s mean with {info['time_constant_s']:g} s "
            f"(fitted on the training runs' wind: {info['error_m_s']:.3f} m/s mean error over "
            f"{info['horizon_s']:g} s against {info['held_error_m_s']:.3f} m/s held)")


def main(argv=None) -> int:
    import torch

    from _results import check_out, command_line
    from hybridship.datasets.esso_osaka import RUN_KINDS, default_data_dir
    from hybridship.fileio import atomic_write, write_text
    from hybridship.evaluation.manoeuvre import (COMMAND_MODES, HORIZONS_S, _md_coverage, _md_table, pivot,
                                                 run_manoeuvre_benchmark, split_runs, wins,
                                                 md_coverage_intervals, md_ratio_to_physics, md_spread_by_kind)

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=default_data_dir() / "data", help="folder of the published runs")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-osaka")
    ap.add_argument("--seed", type=int, default=0, help="seed of the ensembles and of the training (default 0)")
    ap.add_argument("--split-seed", type=int, default=0,
                    help="seed that draws the test runs (default 0): the settings were chosen on a split of the "
                         "seed-0 training runs, so another split's test runs are not clean of that choice")
    ap.add_argument("--test-fraction", type=float, default=0.3,
                    help="share of the runs tested on, in (0, 1) (default 0.3)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--docs", action="store_true", help="update docs/ also with --quick")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    if not 0.0 < args.test_fraction < 1.0:      # NaN too
        ap.error(f"--test-fraction: expected a share of the runs between 0 and 1 (exclusive), got {args.test_fraction}")
    torch.set_num_threads(1)
    if not args.data.is_dir():
        print(f"error: {args.data}: data folder not found (see ../shared/data/esso-osaka-frt/README.md)",
              file=sys.stderr)
        return 2
    command = command_line("esso_osaka.py", argv)
    train_dir, test_dir = split_runs(args.data, args.out / "split", test_fraction=args.test_fraction,
                                     seed=args.split_seed)
    docs = (not args.quick) or args.docs
    t0 = time.perf_counter()
    res = run_manoeuvre_benchmark("esso_osaka_model", train_dir, test_dir, HORIZONS_S, args.out, seed=args.seed,
                                  quick=args.quick, command=command,
                                  figures_dir=(ROOT / "docs" / "figures") if docs else None, progress=True)
    print(f"benchmark: {time.perf_counter() - t0:.0f} s; {args.out / 'errors.csv'}")
    if docs:
        page = ROOT / "docs" / "esso-osaka.md"
        text = page.read_text(encoding="utf-8")
        e = res.errors
        runs = ("Train runs: " + ", ".join(f"`{r.name}`" for r in res.train) + ".\n\nTest runs: "
                + ", ".join(f"`{r.name}` ({r.kind})" for r in res.test) + ".\n")
        text = replace_generated(text, "runs", runs)
        for mode in COMMAND_MODES:
            for state, digits in (("distance_m", 3), ("heading_deg", 2)):
                body = f"Made by `{command}` (`errors.csv`, rows `state = {state}`, " \
                       f"`commands = {mode}`).\n\n" + _md_table(pivot(e, state, mode), digits)
                text = replace_generated(text, f"{state}-{mode}", body)
        lines = []
        kind_order = {k: i for i, k in enumerate(RUN_KINDS + ("all",))}
        for other in ("dynamic", "dead_reckoning", "data_only"):
            for mode in COMMAND_MODES:
                cells, total = wins(e, "hybrid", other, commands=mode)
                if not total:
                    continue
                tab = pivot(e, "distance_m", mode)
                lost = [(k, c) for k in tab.index.get_level_values(0).unique() for c in tab.columns
                        if (k, "hybrid") in tab.index and (k, other) in tab.index and (k, c) not in cells]
                lost.sort(key=lambda kc: (kind_order.get(kc[0], 99), float(kc[1].split()[0])))
                lines.append(f"- vs {other}, commands {mode}: hybrid lower in {len(cells)} of {total} cells"
                             + (f"; not in: {', '.join(f'{k} {c}' for k, c in lost)}" if lost else ""))
        text = replace_generated(text, "wins", "\n".join(lines) + "\n")
        text = replace_generated(text, "ratio", f"Made by `{command}` (`errors.csv`, commands known): the "
                                 "hybrid's error over the physics', distance / heading.\n\n"
                                 + md_ratio_to_physics(e, "known"))
        cov = (f"Made by `{command}` (`coverage.csv`, rows `kind = all`; `coverage_intervals.csv`; "
               f"`sharpness.csv`).\n\n"
               + _md_coverage(res.coverage) + "\n" + md_coverage_intervals(res.coverage_intervals)
               + "\n" + md_spread_by_kind(res.coverage, res.sharpness)
               + "\nThe heading's errors against its own spread (`coverage_heading.csv`, rows `kind = all`):\n\n"
               + _md_coverage(res.coverage_heading))
        text = replace_generated(text, "coverage", cov)
        cfg = res.config
        setup = (f"Made by `{command}`. Hybrid: features `{', '.join(cfg.residual.features)}`; "
                 f"training `{cfg.training}`"
                 + (f" (multi-step horizon {cfg.multistep.horizon_s:g} s, {cfg.multistep.iterations} iterations of "
                    f"{cfg.multistep.batch_starts} starts)" if cfg.training == "multi_step" else "")
                 + f"; command-regime guard {'on' if cfg.command_guard else 'off'}; spread calibrated on the last "
                 f"{cfg.calibration.fraction:.0%} of each training run"
                 + (f", with {cfg.wind_samples} wind futures in it" if cfg.wind_samples else "")
                 + "; wind forecast "
                 f"{_wind_text(res.predictors['hybrid'])}; {cfg.ensemble.n_members} members, seed "
                 f"{cfg.ensemble.seed}. Training took {res.timings_s['fit_hybrid']:.0f} s (wall time, one thread, "
                 "on a shared machine).\n")
        text = replace_generated(text, "setup", setup)
        write_text(page, text)             # atomically: a failed write leaves the page as it was
        print(f"updated {page.relative_to(ROOT)}")
        # the tables' files beside the page, so that every figure quoted on it can be traced
        # (the split's links to the data stay in --out)
        results = ROOT / "docs" / "results" / "esso-osaka"
        for name in RESULT_FILES:
            atomic_write(results / name, lambda fh, src=args.out / name: fh.write(src.read_bytes()))
        print(f"copied {', '.join(RESULT_FILES)} to {results.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
