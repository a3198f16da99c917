"""The high-speed-craft benchmark (the paper's Tables 1 and 2 for SS, ARX, ANN and the hybrid).

    python benchmarks/hsc_table.py --out /tmp/hsc [--seed 0] [--quick]

writes ``table.csv``, ``table.md`` and the ``hsc_*.png`` figures into ``--out``; see
:mod:`hybridship.hsc.benchmark` and ``docs/hsc.md``.
"""

from __future__ import annotations

import argparse

from hybridship.hsc.benchmark import run_benchmark


def _seed(text: str) -> int:
    """A whole number >= 0 (a negative one gave a traceback)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return value


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--seed", type=_seed, default=0, help="seed of trials and training (default 0)")
    ap.add_argument("--quick", action="store_true", help="small smoke run (not the benchmark's numbers)")
    args = ap.parse_args(argv)
    run_benchmark(args.out, seed=args.seed, quick=args.quick)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
