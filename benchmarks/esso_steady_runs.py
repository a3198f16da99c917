"""Esso Osaka: the published physics against the measured steady turns.

::

    python benchmarks/esso_steady_runs.py

For every turning run of ``../shared/data/esso-osaka-frt/data`` (all of them: no forecast
is made and nothing is fitted), finds the longest stretch with the rudder held beyond
15 deg at one propeller rate for at least 2 min, and compares its second half (the steady
part) with the steady state of the dynamic model under the same held commands (no wind,
no current): speed [m/s] and yaw rate [deg/s]. The model starts at 0.3 m/s and runs 300 s;
its last sample is the steady state. Measured values are medians over the steady part.
(The data hold no steady straight run to compare with the same way: no stretch with the
rudder amidships at one propeller rate lasts 30 s.) Prints the table and writes it to
``--out`` (``turns.csv``) when given.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from _results import check_out

ROOT = Path(__file__).resolve().parents[1]

#: A held turn: the rudder beyond this angle [rad] for at least TURN_MIN_S [s].
TURN_RUDDER_RAD = np.radians(15.0)
TURN_MIN_S = 120.0
#: Model run to its steady state: start speed [m/s], duration [s], step [s].
START_SPEED_M_S = 0.3
SETTLE_S = 300.0
DT_S = 0.1


def held_turn(rudder_rad: np.ndarray, rps: np.ndarray, dt_s: float) -> slice | None:
    """Second half of the longest stretch with the rudder held beyond :data:`TURN_RUDDER_RAD`
    at one angle (to 0.01 rad) and one propeller rate (to 0.1 rps); None when it is shorter
    than :data:`TURN_MIN_S`."""
    rudder_rad, rps = np.asarray(rudder_rad, dtype=float), np.asarray(rps, dtype=float)
    key = np.where(np.abs(rudder_rad) > TURN_RUDDER_RAD, np.round(rudder_rad, 2) * 1000 + np.round(rps, 1), np.nan)
    ok = np.isfinite(key)
    change = np.flatnonzero(np.r_[True, ~((key[1:] == key[:-1]) & ok[1:] & ok[:-1]), True])
    starts, ends = change[:-1], change[1:]
    runs = [(a, b) for a, b in zip(starts, ends) if ok[a]]
    if not runs:
        return None
    a, b = max(runs, key=lambda ab: ab[1] - ab[0])
    if (b - a) * dt_s < TURN_MIN_S:
        return None
    return slice((a + b) // 2, b)


def model_steady_state(model, rps: float, rudder_rad: float) -> tuple[float, float]:
    """Steady speed [m/s] and yaw rate [rad/s] of ``model`` at the held commands (no wind, no current)."""
    res = model.rollout([0.0, 0.0, 0.0], [START_SPEED_M_S, 0.0, 0.0], int(round(SETTLE_S / DT_S)), dt_s=DT_S,
                        rpm=[60.0 * rps, 0.0], rudder_rad=[rudder_rad])
    u, v, r = res.nu[0, -1]
    return float(np.hypot(u, v)), float(r)


def main(argv=None) -> int:
    import pandas as pd

    from hybridship.datasets.esso_osaka import list_runs, read_esso_raw
    from hybridship.fileio import atomic_write
    from hybridship.physics.model import DynamicModel

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data" / "esso-osaka-frt" / "data")
    ap.add_argument("--out", type=Path, default=None, help="folder for turns.csv (optional)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    if not args.data.is_dir():
        print(f"error: {args.data}: not found (the Esso Osaka data set)", file=sys.stderr)
        return 2
    model = DynamicModel("esso_osaka_model")
    rows = []
    for run in (r for r in list_runs(args.data) if r.kind == "turning"):
        raw = read_esso_raw(run.path)
        dt = float(np.median(np.diff(raw["t [s]"].to_numpy())))
        d, n = raw["delta_rudder [rad]"].to_numpy(), raw["n_prop [rps]"].to_numpy()
        part = held_turn(d, n, dt)
        if part is None:
            continue
        speed = np.hypot(raw["u_velo [m/s]"].to_numpy(), raw["vm_velo [m/s]"].to_numpy())[part]
        speed_model, r_model = model_steady_state(model, float(n[part][0]), float(d[part][0]))
        rate_data = np.degrees(np.median(raw["r_angvelo [rad/s]"].to_numpy()[part]))
        rows.append({"run": run.name, "rps": n[part][0], "rudder_deg": np.degrees(d[part][0]),
                     "held_s": (part.stop - part.start) * 2 * dt, "speed_data_m_s": np.median(speed),
                     "speed_model_m_s": speed_model, "rate_data_deg_s": rate_data,
                     "rate_model_deg_s": np.degrees(r_model), "rate_ratio": np.degrees(r_model) / rate_data})
    df = pd.DataFrame(rows)
    print(df.round(3).to_string(index=False) if len(df) else "(no held turn)")
    if args.out is not None and len(df):
        args.out.mkdir(parents=True, exist_ok=True)
        atomic_write(args.out / "turns.csv", lambda fh: fh.write(df.to_csv(index=False).encode()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
