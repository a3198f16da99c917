"""Where the drift's heading error comes from on truthsim-dev: the hull model's yaw response.

For every truthsim-dev log, the hull model is given the simulator's own truth: the
low-frequency motion (velocities low-passed at 0.04 Hz, zero phase), the true current and
the true loads (thrust, wind and second-order wave drift, ``truth_tau_*``). What is then
left of the measured yaw acceleration is the hull model's own yaw error. Over the drift
(after the failure) it is regressed on hull terms of the relative velocity
``nu_r = nu - R(psi)^T v_c``: the Munk term ``u_r v_r``, ``abs(v_r) v_r``, ``r`` and ``v_r``.
The printout gives each fit's coefficient and R^2, and the model's own Munk coefficient
``(m_22 - m_11) / m_33`` (added masses, the acceleration per (m/s)^2 that the model's
``C_A(nu_r) nu_r`` puts into yaw) for comparison.

No environment estimate is involved: this measures what no estimate from station keeping
can correct, because station keeping does not move the ship through the water.

Writes ``hull_yaw_residual.md`` to ``--out``. Example::

    python benchmarks/hull_yaw_residual.py --out docs/results/hull-yaw-residual
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.signal import butter, filtfilt

from _results import check_out
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.frames import ned_to_body
from hybridship.physics.model import DynamicModel

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"
LOADS = ("thrust", "wind", "wave2")


def drift_residual(model, d: pd.DataFrame, cutoff_hz: float) -> pd.DataFrame:
    """Per drift sample: the yaw-acceleration residual [rad/s^2] and the hull terms."""
    fs = 1.0 / float(np.median(np.diff(d.time_s)))
    if not 0 < cutoff_hz < fs / 2:      # scipy's 'Digital filter critical frequencies must be 0 < Wn < fs/2'
        raise ValueError(f"cutoff_hz: expected a frequency between 0 and half the log's sample rate "
                         f"({fs / 2:g} Hz), got {cutoff_hz:g} Hz")
    b, a = butter(2, cutoff_hz, fs=fs)
    lp = lambda x: filtfilt(b, a, np.asarray(x, float))
    dt = float(np.median(np.diff(d.time_s)))
    u, v, r = lp(d.truth_u_mps), lp(d.truth_v_mps), np.radians(lp(d.truth_r_degps))
    psi = np.unwrap(np.radians(d.truth_heading_lf_deg.to_numpy(float)))
    nu = np.column_stack([u, v, r])
    eta = np.column_stack([d.truth_north_lf_m, d.truth_east_lf_m, psi])
    cur = np.column_stack([d.truth_current_speed_mps, np.radians(d.truth_current_dir_to_deg)])
    tau = np.column_stack([sum(d[f"truth_tau_{p}_{k}"].to_numpy(float) for p in LOADS)
                           for k in ("x_N", "y_N", "n_Nm")])
    z = np.zeros((len(d), model.n_channels))
    res = np.gradient(nu, dt, axis=0) - model.acceleration(eta, nu, rpm=z, azimuth_rad=z, current=cur, tau_ext=tau)
    v_c = np.column_stack([cur[:, 0] * np.cos(cur[:, 1]), cur[:, 0] * np.sin(cur[:, 1]), np.zeros(len(d))])
    ur, vr = (nu - ned_to_body(v_c, psi))[:, :2].T          # velocity relative to the current (body)
    stop = int(np.flatnonzero(d.dp_active.to_numpy()[:-1] > d.dp_active.to_numpy()[1:])[0]) + 1
    sl = slice(stop, len(d) - 5)
    return pd.DataFrame({"res_r": res[sl, 2], "u_r v_r": (ur * vr)[sl], "abs(v_r) v_r": (np.abs(vr) * vr)[sl],
                         "r": r[sl], "v_r": vr[sl]})


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=TRUTHSIM)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--cutoff-hz", type=float, default=0.04, help="low-pass of the velocities (default 0.04 Hz)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    try:
        files = log_files(args.data)
    except ValueError:                  # no folder, or no logs in it (log_files' traceback for an empty one)
        files = []
    if not files:
        if args.data != TRUTHSIM:       # a folder named on the command line: not the shared data set missing
            ap.error(f"--data: no logs in {args.data}")
        print(f"skipping: no truthsim-dev logs in {args.data}", file=sys.stderr)
        return 0
    if not 0 < args.cutoff_hz < float("inf"):
        ap.error(f"--cutoff-hz: expected a frequency > 0 Hz, got {args.cutoff_hz:g}")
    model = DynamicModel("gunnerus")
    try:
        df = pd.concat([drift_residual(model, pd.read_csv(f), args.cutoff_hz) for f in files], ignore_index=True)
    except ValueError as exc:
        if not str(exc).startswith("cutoff_hz:"):
            raise
        ap.error(f"--cutoff-hz: {str(exc).partition(': ')[2]}")
    y = df.res_r.to_numpy()
    rows, munk_fits = [], []
    for cols in (["u_r v_r"], ["abs(v_r) v_r"], ["r"], ["v_r"], ["u_r v_r", "abs(v_r) v_r", "r", "v_r"]):
        X = np.column_stack([df[c].to_numpy() for c in cols] + [np.ones(len(df))])
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        r2 = 1.0 - np.var(y - X @ coef) / np.var(y)
        rows.append({"terms": " + ".join(cols), "coefficients": ", ".join(f"{c:.3g}" for c in coef[:-1]),
                     "R^2": f"{r2:.2f}"})
        if cols[0] == "u_r v_r":
            munk_fits.append(("alone" if len(cols) == 1 else "with the other terms", coef[0]))
    M, m_a = model.mass_matrix, model.arrays.m_a
    munk = (m_a[1, 1] - m_a[0, 0]) / M[2, 2]
    lines = [f"{len(files)} truthsim-dev logs, {len(df)} drift samples: the yaw-acceleration residual of the hull "
             f"model given the simulator's motion, current and loads [rad/s^2], regressed on hull terms.", "",
             markdown_table(pd.DataFrame(rows)), "",
             f"The model's Munk coefficient (m_22 - m_11) / m_33 (added masses): "
             f"{munk:.3g} rad/s^2 per (m/s)^2. The u_r v_r coefficient as a multiple of it: "
             + "; ".join(f"{c / munk:.2f} {how}" for how, c in munk_fits) + "."]
    text = "\n".join(lines) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "hull_yaw_residual.md", lambda fh: fh.write(text.encode("utf-8")))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
