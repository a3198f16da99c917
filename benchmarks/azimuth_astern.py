"""How often the simulated DP runs its azimuth thrusters astern, against truthsim-dev.

The simulator's allocator reverses an azimuth's shaft when that is the shorter turn, and
its hysteresis then favours the present shaft direction (``docs/simulator.md``). This
prints, for the embedded scenario sets the benchmarks use and for truthsim-dev, the share
of station-keeping samples (``dp_active == 1``) with an azimuth's rpm below zero, and the
number of logs in which one azimuth runs astern on more than 95 % of them.

Usage::

    python benchmarks/azimuth_astern.py                 # embedded (3, 0), (6, 1000), (20, 100) and truthsim-dev
    python benchmarks/azimuth_astern.py --no-embedded   # truthsim-dev only (seconds)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
TRUTHSIM = ROOT.parent / "shared" / "data" / "truthsim-dev" / "logs"
AZIMUTHS = ("port", "stbd")
EMBEDDED_SETS = ((3, 0), (6, 1000), (20, 100))


def astern_shares(log: pd.DataFrame) -> np.ndarray:
    """Per azimuth, the share of DP samples with rpm < 0."""
    dp = log[log.dp_active == 1]
    return np.array([float((dp[f"{a}_rpm"] < 0).mean()) for a in AZIMUTHS])


def summary(name: str, logs: list) -> str:
    shares = np.array([astern_shares(df) for df in logs])          # (logs, azimuths)
    locked = int(np.sum(shares.max(axis=1) > 0.95))
    return (f"{name}: {len(logs)} logs; azimuths astern on {shares.mean():.0%} of the DP samples; "
            f"one azimuth astern on more than 95 % of them in {locked} logs")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-embedded", action="store_true", help="skip simulating the embedded sets")
    args = ap.parse_args(argv)
    if not args.no_embedded:
        from hybridship.sim.scenario import embedded_scenarios

        logs = [s.log for n, seed in EMBEDDED_SETS for s in embedded_scenarios(n, seed)]
        print(summary("embedded " + ", ".join(f"({n}, {s})" for n, s in EMBEDDED_SETS), logs))
    files = sorted(TRUTHSIM.glob("*.csv*"))
    if files:
        print(summary("truthsim-dev", [pd.read_csv(f) for f in files]))
    else:
        print(f"truthsim-dev: skipped ({TRUTHSIM} not found)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
