"""The environment estimator against the simulator's truth on truthsim-dev, before and after the failure.

For every log the estimator (default :class:`~hybridship.residual.environment.EnvironmentConfig`,
thrust-error prior mean 0) filters the last 30 min of station keeping and the drift. The truth
columns used:

* current: ``truth_current_speed_mps``, ``truth_current_dir_to_deg``;
* load: the second-order wave drift ``truth_tau_wave2_*`` plus the wind model's error
  (``truth_tau_wind_*`` less this project's wind model at the logged wind), i.e. what the
  estimator's load stands for, rotated to NED [N] (yaw [N m]);
* thrust error: ``truth_tau_thrust_*`` less the model's thrust load at the logged commands
  and states, as a body-frame force [N] (yaw [N m]); it compares with the estimate whatever
  the structure of ``theta`` (per thruster or per DOF).

The estimated load is a force ``M b`` (M with added mass), the estimated thrust error
``M T theta`` at each row's logged state and commands. Windows: ``dp`` = the last 300 s
before the failure, ``drift`` = 60..300 s after it (the estimate at each row uses the rows
up to it only). Writes ``environment_vs_truth.csv``/``.md`` and ``environment_vs_truth.png``.

Example::

    python benchmarks/environment_vs_truth.py --out docs/results/environment-vs-truth
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.frames import body_to_ned
from hybridship.evaluation.metrics import shutdown_index
from hybridship.physics.model import DynamicModel
from hybridship.predictors import as_log_arrays
from hybridship.residual.environment import EnvironmentEstimator

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"


def _truth(df, model, a):
    """Truth current (N, 2: speed, dir_to_rad), load in NED (N, 3) and the thrust model's error
    as a body-frame force (N, 3) [N, N, N m]: the simulator's thrust load less the model's."""
    psi = a.eta[:, 2]
    cur = np.column_stack([df.truth_current_speed_mps, np.radians(df.truth_current_dir_to_deg)])
    _, parts, _ = model.acceleration(a.eta, np.nan_to_num(a.nu), rpm=a.rpm, azimuth_rad=a.azimuth_rad,
                                     wind=a.wind, return_parts=True)
    wave2 = df[["truth_tau_wave2_x_N", "truth_tau_wave2_y_N", "truth_tau_wave2_n_Nm"]].to_numpy()
    wind_t = df[["truth_tau_wind_x_N", "truth_tau_wind_y_N", "truth_tau_wind_n_Nm"]].to_numpy()
    load = body_to_ned(wave2 + wind_t - parts[:, 2], psi)
    thr_t = df[["truth_tau_thrust_x_N", "truth_tau_thrust_y_N", "truth_tau_thrust_n_Nm"]].to_numpy()
    return cur, load, thr_t - parts[:, 1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--data", type=Path, default=TRUTHSIM)
    args = ap.parse_args(argv)
    if not args.data.is_dir():
        print(f"{args.data}: not found (the truthsim-dev data set is needed)", file=sys.stderr)
        return 2
    model = DynamicModel("gunnerus")
    M = model.mass_matrix
    rows, series = [], []
    for f in log_files(args.data):
        df = pd.read_csv(f)
        a = as_log_arrays(df, model.vessel)
        i0 = shutdown_index(a)
        first = max(0, i0 - 1800)
        last = min(len(a.time_s) - 1, i0 + 300)
        est = EnvironmentEstimator(model).run(a, np.arange(first, last + 1), first_row=first)
        cur_t, load_t, thr_t = _truth(df, model, a)
        # estimated load as a force: M b with b rotated to the body frame and back (M is body-fixed)
        psi = est.x[:, 2]
        b = est.load_accel
        c, s = np.cos(psi), np.sin(psi)
        b_body = np.column_stack([c * b[:, 0] + s * b[:, 1], -s * b[:, 0] + c * b[:, 1], b[:, 2]])
        load_e = body_to_ned(b_body @ M.T, psi)
        cur_e = est.current_speed_dir
        r = np.arange(first, last + 1)
        # the estimated thrust error as a force, at the logged states and commands of each row
        thr_e = est.thrust_error_accel(model, a.eta[r], np.nan_to_num(a.nu[r]), np.nan_to_num(a.rpm[r]),
                                       np.nan_to_num(a.azimuth_rad[r]), np.nan_to_num(a.wind[r])) @ M.T
        series.append((f.name, a.time_s[r] - a.time_s[i0], load_e, load_t[r], cur_e, cur_t[r]))
        for win, sel in (("dp", (r >= i0 - 300) & (r < i0)), ("drift", (r >= i0 + 60) & (r <= i0 + 300))):
            rows.append({
                "log": f.name, "window": win,
                "current_m_s_est": cur_e[sel, 0].mean(), "current_m_s_true": cur_t[r][sel, 0].mean(),
                "load_north_kN_est": load_e[sel, 0].mean() / 1e3, "load_north_kN_true": load_t[r][sel, 0].mean() / 1e3,
                "load_east_kN_est": load_e[sel, 1].mean() / 1e3, "load_east_kN_true": load_t[r][sel, 1].mean() / 1e3,
                "load_yaw_kNm_est": load_e[sel, 2].mean() / 1e3, "load_yaw_kNm_true": load_t[r][sel, 2].mean() / 1e3,
                "thrust_error_x_kN_est": thr_e[sel, 0].mean() / 1e3, "thrust_error_x_kN_true": thr_t[r][sel, 0].mean() / 1e3,
                "thrust_error_y_kN_est": thr_e[sel, 1].mean() / 1e3, "thrust_error_y_kN_true": thr_t[r][sel, 1].mean() / 1e3,
                "thrust_error_n_kNm_est": thr_e[sel, 2].mean() / 1e3,
                "thrust_error_n_kNm_true": thr_t[r][sel, 2].mean() / 1e3,
            })
    table = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "environment_vs_truth.csv",
                 lambda fh: fh.write(table.to_csv(index=False, float_format="%.4g").encode("utf-8")))
    md = [markdown_table(table.round(2))]
    atomic_write(args.out / "environment_vs_truth.md", lambda fh: fh.write(("\n".join(md) + "\n").encode("utf-8")))
    _plot(args.out / "environment_vs_truth.png", series)
    print("\n".join(md))
    return 0


def _plot(path, series):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(series), 3, figsize=(13, 2.3 * len(series)), sharex=True)
    for row, (name, t, le, lt, ce, ct) in zip(np.atleast_2d(axes), series):
        for j, (lab, unit, k) in enumerate((("load north", "kN", 0), ("load east", "kN", 1))):
            row[j].plot(t, lt[:, k] / 1e3, color="0.6", lw=0.6, label="truth (wave drift + wind-model error)")
            row[j].plot(t, le[:, k] / 1e3, color="tab:red", lw=1.2, label="estimate")
            row[j].set_ylabel(f"{lab} [{unit}]", fontsize=8)
        row[2].plot(t, ct[:, 0], color="0.6", lw=1.0, label="truth current")
        row[2].plot(t, ce[:, 0], color="tab:blue", lw=1.2, label="estimated current")
        row[2].set_ylabel("current [m/s]", fontsize=8)
        row[0].set_title(name, fontsize=8, loc="left")
        for ax in row:
            ax.axvline(0.0, color="k", lw=0.8, ls=":")
    for ax in np.atleast_2d(axes)[-1]:
        ax.set_xlabel("time since the failure [s]")
    np.atleast_2d(axes)[0, 0].legend(fontsize=7)
    np.atleast_2d(axes)[0, 2].legend(fontsize=7)
    fig.tight_layout()
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=100))
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
