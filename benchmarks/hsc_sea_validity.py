"""How far the planing-craft simulator's waves go before its motions stop being physical.

The quasi-static simulator (:mod:`hybridship.hsc.simulator`) runs the vessel file's "true"
Volcano71 (trim tabs at 50 % PWM) for 60 s in head-sea JONSWAP waves at three engine
speeds, and prints per wave height and period: the mean speed's change from calm water
[kn], the pitch range [deg] and the largest heave acceleration [g]. The benchmark's sea
states are Hs 0.05 m, Tp 1.5 s and Hs 0.10 m, Tp 3.0 s; :class:`~hybridship.hsc.simulator.SeaConditions`
refuses heights above :data:`~hybridship.hsc.simulator.MAX_HS_M` (the table's reason).

Example::

    python benchmarks/hsc_sea_validity.py --out docs/results/hsc-sea-validity
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from _results import check_out
from hybridship.fileio import atomic_write, markdown_table
from hybridship.hsc.simulator import MAX_HS_M, PlaningCraftModel, SeaConditions
from hybridship.hsc.vessel import load_planing_craft

RPMS = (1500.0, 2600.0, 3600.0)
HEIGHTS_M = (0.05, 0.1, 0.15, 0.2, 0.3)
PERIODS_S = (1.5, 3.0)
G = 9.81


def run(n: int = 600, seed: int = 2):
    """Rows of the table (one per period, height and engine speed); waves beyond the
    simulator's limit (``beyond_validity``) show why they are refused."""
    import pandas as pd

    model = PlaningCraftModel(load_planing_craft().perturbed(), "trim_tab")
    pwm = np.full(n, 50.0)
    calm = {rpm: model.simulate(np.full(n, rpm), pwm, rng=seed, settle_s=10.0).speed_m_s.mean() for rpm in RPMS}
    rows = []
    for tp in PERIODS_S:
        for hs in HEIGHTS_M:
            sea = SeaConditions(hs_m=hs, tp_s=tp, beyond_validity=hs > MAX_HS_M)
            for rpm in RPMS:
                r = model.simulate(np.full(n, rpm), pwm, sea=sea, rng=seed, settle_s=10.0)
                p = np.degrees(r.pitch_rad)
                rows.append({"tp_s": tp, "hs_m": hs, "rpm": rpm,
                             "speed_change_kn": (r.speed_m_s.mean() - calm[rpm]) * 3600 / 1852,
                             "pitch_min_deg": p.min(), "pitch_max_deg": p.max(),
                             "max_heave_acc_g": np.abs(r.heave_acc_m_s2).max() / G})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    df = run()
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "sea_validity.csv", lambda fh: fh.write(df.round(3).to_csv(index=False).encode()))
    text = markdown_table(df.round(2)) + "\n"
    atomic_write(args.out / "sea_validity.md", lambda fh: fh.write(text.encode()))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
