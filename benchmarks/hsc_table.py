"""The high-speed-craft benchmark (the paper's Tables 1 and 2 for SS, ARX, ANN and the hybrid).

    python benchmarks/hsc_table.py --out /tmp/hsc [--seed 0] [--quick]

writes ``table.csv``, ``table.md`` and the ``hsc_*.png`` figures into ``--out``; the same as
``hybridship benchmark hsc`` (its options and checks); see :mod:`hybridship.hsc.benchmark`
and ``docs/hsc.md``.
"""

from __future__ import annotations

import sys

from hybridship.cli import main

if __name__ == "__main__":
    sys.exit(main(["benchmark", "hsc", *sys.argv[1:]]))
