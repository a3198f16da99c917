"""How often the simulator's thrusters met a demand that needs the shaft turned against the
demand's sign: the propeller at rest already gives more than the demand in its direction.

Until 2026-11-30 the rpm inversion (:func:`hybridship.physics.propeller.rpm_for_thrust`)
searched only the branch with the sign of the demand and answered such a demand with zero
rpm, delivering the propeller's drag instead. This script simulates the sets behind the
result pages (the embedded sets of the drift benchmarks, the sweeps of seeds 300-305 and of
the calm twenty, the sample-rate and gap scenarios) and counts, over every thruster command
the allocator inverts, the commands where the force at rest is past the demand, and the
largest gap between the two [N]. Only the sets with such commands change with the fix.

Usage: ``python benchmarks/rpm_inversion_cases.py [--out FILE]`` (about 5 min on one core).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from _results import check_out
import hybridship.sim.allocation as allocation
from hybridship.fileio import markdown_table, write_text
from hybridship.physics.propeller import thrust_torque
from hybridship.sim.scenario import DPLossConfig, _simulate, embedded_scenarios, simulate_dp_loss
from hybridship.vessel import load_vessel

from _siblings import sibling  # benchmarks/ is on sys.path when a script runs


def _counting(counts: dict):
    """A wrapper of the allocator's rpm inversion that counts the commands whose force at
    rest [N] is past the demand [N] in the demand's direction (the inversion is unchanged)."""
    inner = allocation.rpm_for_thrust

    def wrapped(thrust_N, va_m_s, diameter_m, prop, rho_kg_m3=1025.0, max_rpm=None):
        T = np.asarray(thrust_N, float)
        rest, _ = thrust_torque(np.zeros_like(T), np.asarray(va_m_s, float), diameter_m, prop, rho_kg_m3)
        sign = np.where(T >= 0.0, 1.0, -1.0)
        past = sign * rest > sign * T
        counts["commands"] += T.size
        counts["past"] += int(past.sum())
        if past.any():
            counts["gap_N"] = max(counts["gap_N"], float(np.abs(rest - T)[past].max()))
        return inner(thrust_N, va_m_s, diameter_m, prop, rho_kg_m3, max_rpm)

    return wrapped


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="also write the table to this Markdown file")
    args = ap.parse_args(argv)
    check_out(ap, args.out, file=True)
    gunnerus = load_vessel("gunnerus")
    rates = sibling("sample_rates")             # their seeds, as those scripts simulate them
    gaps = sibling("gap_sensitivity")
    sets = {
        "embedded, seeds 0-2": lambda: embedded_scenarios(3, 0),
        "embedded, seeds 100-119": lambda: embedded_scenarios(20, 100),
        "embedded, seeds 200-219": lambda: embedded_scenarios(20, 200),
        "embedded, seeds 1000-1019": lambda: embedded_scenarios(20, 1000),
        "sweep, seeds 300-305": lambda: [_simulate(DPLossConfig(seed=s), gunnerus, False) for s in range(300, 306)],
        "sweep, seeds 500-519, Beaufort 1.5-3": lambda: [
            _simulate(DPLossConfig(seed=s, beaufort=(1.5, 3.0)), gunnerus, False) for s in range(500, 520)],
        "sample rates, seeds 20-23": lambda: [simulate_dp_loss(DPLossConfig(
            dt_s=0.1, sim_dt_s=0.1, control_dt_s=1.0, t_shutdown_s=600.0, t_shutdown_jitter_s=0.0, drift_s=300.0,
            seed=s)) for s in rates.SEEDS],
        "gap sensitivity, seeds 30-33": lambda: [simulate_dp_loss(DPLossConfig(
            t_shutdown_s=gaps.T_SHUTDOWN_S, t_shutdown_jitter_s=0.0, drift_s=300.0, seed=s)) for s in gaps.SEEDS],
    }
    rows = []
    original = allocation.rpm_for_thrust
    try:
        for name, simulate in sets.items():
            counts = {"commands": 0, "past": 0, "gap_N": 0.0}
            allocation.rpm_for_thrust = _counting(counts)
            simulate()
            rows.append([name, counts["commands"], counts["past"], f"{counts['gap_N']:.2f}"])
            print(" | ".join(str(c) for c in rows[-1]), file=sys.stderr, flush=True)
    finally:
        allocation.rpm_for_thrust = original
    import pandas as pd

    table = markdown_table(pd.DataFrame(rows, columns=["set", "thruster commands", "force at rest past the demand",
                                                       "largest gap [N]"]))
    print(table)
    if args.out is not None:
        write_text(args.out, table + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
