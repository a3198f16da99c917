"""The drift benchmark (Skulstad et al. 2022, Tables 2 and 3) on the embedded scenarios or any folders.

Same as ``hybridship benchmark drift``; see :mod:`hybridship.evaluation.drift`.

Examples
--------
``python benchmarks/drift_table.py --out results/embedded``
    the embedded simulated Gunnerus DP-loss scenarios;
``python benchmarks/drift_table.py --train ../shared/data/truthsim-dev/logs --out results/truthsim-dev``
    trained on the DP parts of truthsim-dev, tested on its drifts.
"""

from __future__ import annotations

import sys

from hybridship.cli import main

if __name__ == "__main__":
    sys.exit(main(["benchmark", "drift", *sys.argv[1:]]))
