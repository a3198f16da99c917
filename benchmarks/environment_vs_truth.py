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
up to it only); ``heading_change_deg`` is the true heading's mean over the window less its
value at the failure (the ship turns while the environment's yaw moment, which depends on
the heading relative to waves and wind, changes); ``load_yaw_kNm_est_at_failure`` is the
estimated yaw load at the last row of station keeping (what a forecast started at the
failure holds; the same in both windows). Under the table, the yaw load's medians
(:func:`yaw_summary`) and the station keeping's yaw split (:func:`station_keeping_yaw_split`).
Writes ``environment_vs_truth.csv``/``.md``
and ``environment_vs_truth.png``, and each thruster's estimated thrust-error factor at the
last row of station keeping in ``thrust_error_factors.csv``/``.md``.

``--drift-hull CSV`` gives each log's filter the hull's yaw moment in a drift that a drift
benchmark chose for it on the *other* logs' failures (its ``drift_hull.csv``; see
:mod:`hybridship.residual.drift_hull`): after the failure the process model then adds
``k u v``, as the default hybrid's filter does, instead of leaving the hull's error to the
yaw load.

``--scenarios N --seed S`` reads the own simulator's DP-loss scenarios ``S .. S+N-1``
(:func:`hybridship.sim.scenario.embedded_scenarios`, the drift benchmark's own scenarios)
instead of truthsim-dev; their logs carry the same truth columns.

Examples::

    python benchmarks/environment_vs_truth.py --out docs/results/environment-vs-truth
    python benchmarks/environment_vs_truth.py --scenarios 20 --seed 100 --out docs/results/environment-vs-truth-own-20
    python benchmarks/environment_vs_truth.py --drift-hull docs/results/drift-truthsim-dev/drift_hull.csv \
        --out docs/results/environment-vs-truth-drift-hull
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table, record_inputs
from hybridship.frames import body_to_ned, ned_to_body
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


def current_yaw_at_rest(model, psi_rad, current) -> np.ndarray:
    """Our hull's yaw moment [N m] from the ``current`` (N, 2: speed [m/s], direction to [rad])
    on the ship at rest at headings ``psi_rad`` (N,): the Munk moment and cross-flow of the
    relative velocity ``-nu_c``, what station keeping sees of a current in yaw."""
    n = len(psi_rad)
    eta = np.column_stack([np.zeros(n), np.zeros(n), psi_rad])
    _, parts, _ = model.acceleration(eta, np.zeros((n, 3)), rpm=np.zeros((n, len(model.vessel.thrusters))),
                                     current=current, return_parts=True)
    return parts[:, 0, 2]


def _logs(args):
    """``(name, DataFrame)`` of every log: the own simulator's scenarios with ``--scenarios``,
    else the files of ``--data``."""
    if args.scenarios:
        from hybridship.sim.scenario import embedded_scenarios

        return [(s.name, s.log) for s in embedded_scenarios(args.scenarios, args.seed)]
    return [(f.name, pd.read_csv(f)) for f in log_files(args.data)]


def heading_change_deg(heading_deg: np.ndarray, i0: int, rows: np.ndarray) -> float:
    """Mean heading over ``rows`` less the heading at row ``i0`` [deg], through north
    (the heading unwrapped)."""
    psi = np.unwrap(np.radians(np.asarray(heading_deg, dtype=float)))
    return float(np.degrees(psi[rows].mean() - psi[i0]))


def yaw_summary(table: pd.DataFrame) -> str:
    """Medians over the logs of the yaw load's truth and of the estimate's error [kN m]: in
    station keeping, in the drift with the online estimate, and in the drift with the
    estimate at the failure held (what a forecast started at the failure holds)."""
    dp = table[table.window == "dp"].set_index("log")
    drift = table[table.window == "drift"].set_index("log")

    def med(x):
        return float(np.median(np.abs(x)))

    rows = [("station keeping (dp)", dp.heading_change_deg, dp.load_yaw_kNm_true,
             dp.load_yaw_kNm_est - dp.load_yaw_kNm_true),
            ("drift, online estimate", drift.heading_change_deg, drift.load_yaw_kNm_true,
             drift.load_yaw_kNm_est - drift.load_yaw_kNm_true),
            ("drift, estimate at the failure held", drift.heading_change_deg, drift.load_yaw_kNm_true,
             drift.load_yaw_kNm_est_at_failure - drift.load_yaw_kNm_true)]
    out = pd.DataFrame([{"window, estimate": name, "heading change [deg]": med(h), "true yaw load [kNm]": med(t),
                         "yaw-load error [kNm]": med(e)} for name, h, t, e in rows])
    return (f"Medians over the {len(dp)} logs of the absolute values:\n\n" + markdown_table(out.round(1)))


def station_keeping_yaw_split(dp: pd.DataFrame) -> str:
    """From the ``dp`` rows of the table: in station keeping, the yaw load's error, the thrust
    error's yaw moment's error and their sum's error [kN m] (medians of the absolute values
    over the logs), the correlation of the first two (Pearson), and the Spearman rank
    correlation of the sum's absolute error with the true current speed (both nan with fewer
    than three logs). The sum is what the thrust and the environment add up to, so its error
    is what the filter takes as yaw load or thrust error and the truth counts as neither (the
    current's yaw moment on the ship at rest). Beside it: our hull's yaw moment from the true
    current on the ship at rest (``current_yaw_at_rest_kNm``; the median of its absolute
    value), its Pearson correlation with the sum's signed error (nan with fewer than three
    logs), and the median absolute error left when it is taken off the sum's."""
    from scipy.stats import spearmanr

    load = dp.load_yaw_kNm_est - dp.load_yaw_kNm_true
    thrust = dp.thrust_error_n_kNm_est - dp.thrust_error_n_kNm_true
    total = np.abs(load + thrust)
    enough = len(dp) >= 3           # fewer logs have no correlation to speak of (nan, without a warning)
    current_yaw = dp.current_yaw_at_rest_kNm
    out = pd.DataFrame([{"yaw-load error [kNm]": float(np.median(np.abs(load))),
                         "thrust error's yaw-moment error [kNm]": float(np.median(np.abs(thrust))),
                         "their sum's error [kNm]": float(np.median(total)),
                         "correlation of the two errors": float(np.corrcoef(load, thrust)[0, 1]) if enough
                         else float("nan"),
                         "rank correlation, sum's error with true current": float(
                             spearmanr(total, dp.current_m_s_true).statistic) if enough else float("nan"),
                         "the current's yaw moment at rest [kNm]": float(np.median(np.abs(current_yaw))),
                         "correlation, sum's error with it": float(np.corrcoef(load + thrust, current_yaw)[0, 1])
                         if enough else float("nan"),
                         "sum's error less it [kNm]": float(np.median(np.abs(load + thrust - current_yaw)))}])
    return ("Station keeping (`dp`): the yaw load and the thrust error's yaw moment, whose sum the "
            "thrust and the environment fix (medians of the absolute errors over the logs):\n\n"
            + markdown_table(out.round(2)))


def add_log_source_arguments(ap: argparse.ArgumentParser) -> None:
    """``--out`` and the logs with truth columns: ``--data`` or ``--scenarios``/``--seed``."""
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--data", type=Path, default=None, help="folder of logs with truth columns (default truthsim-dev)")
    ap.add_argument("--scenarios", type=int, default=0,
                    help="use this many of the own simulator's DP-loss scenarios (1-20) instead of --data")
    ap.add_argument("--seed", type=int, default=100, help="seed of the first scenario with --scenarios")


def check_log_source(ap: argparse.ArgumentParser, args) -> bool:
    """Check the arguments of :func:`add_log_source_arguments` (``args.data`` defaults to
    truthsim-dev); False, with a message, when the data set is missing."""
    if not 0 <= args.scenarios <= 20:
        ap.error(f"--scenarios: expected 1-20 (or 0 to read --data), got {args.scenarios}")
    if args.seed < 0:
        ap.error(f"--seed: expected a non-negative integer, got {args.seed}")
    if args.scenarios and args.data is not None:
        ap.error("--data and --scenarios: give one source of logs, not both")
    args.data = TRUTHSIM if args.data is None else args.data
    if not args.scenarios and not args.data.is_dir():
        print(f"{args.data}: not found (the truthsim-dev data set is needed)", file=sys.stderr)
        return False
    return True


def parse_log_source(description: str, argv=None):
    """The arguments of a script that takes only ``--out`` and the logs with truth columns
    (:func:`add_log_source_arguments`), checked; None, with a message, when the data set is
    missing."""
    ap = argparse.ArgumentParser(description=description)
    add_log_source_arguments(ap)
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    return args if check_log_source(ap, args) else None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_log_source_arguments(ap)
    ap.add_argument("--drift-hull", type=Path, default=None,
                    help="a drift benchmark's drift_hull.csv: each log's coefficient of the hull's yaw moment in a "
                         "drift, used by its filter after the failure (default: none)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    if not check_log_source(ap, args):
        return 2
    model = DynamicModel("gunnerus")
    M = model.mass_matrix
    try:
        drift_yaw = _drift_hull_coefficients(args.drift_hull) if args.drift_hull is not None else {}
    except ValueError as exc:
        print(exc, file=sys.stderr)
        return 2
    rows, series, factors = [], [], []
    for name, df in _logs(args):
        a = as_log_arrays(df, model.vessel)
        i0 = shutdown_index(a)
        first = max(0, i0 - 1800)
        last = min(len(a.time_s) - 1, i0 + 300)
        if args.drift_hull is not None and name not in drift_yaw:
            print(f"--drift-hull {args.drift_hull}: no row for log {name}", file=sys.stderr)
            return 2
        est = EnvironmentEstimator(model).run(a, np.arange(first, last + 1), first_row=first,
                                              drift_yaw_uv_rad_per_m2=drift_yaw.get(name, 0.0))
        cur_t, load_t, thr_t = _truth(df, model, a)
        cur_yaw_t = current_yaw_at_rest(model, a.eta[:, 2], cur_t)
        # estimated load as a force: M b with b rotated to the body frame and back (M is body-fixed)
        psi = est.x[:, 2]
        load_e = body_to_ned(ned_to_body(est.load_accel, psi) @ M.T, psi)
        cur_e = est.current_speed_dir
        r = np.arange(first, last + 1)
        # the estimated thrust error as a force, at the logged states and commands of each row
        thr_e = est.thrust_error_accel(model, a.eta[r], np.nan_to_num(a.nu[r]), np.nan_to_num(a.rpm[r]),
                                       np.nan_to_num(a.azimuth_rad[r]), np.nan_to_num(a.wind[r])) @ M.T
        series.append((name, a.time_s[r] - a.time_s[i0], load_e, load_t[r], cur_e, cur_t[r]))
        at_failure = int(np.searchsorted(r, i0 - 1))       # the estimate a forecast at the failure starts from
        # one factor per thruster by default; per DOF [x, y, n] with thrust_error_model="per_dof"
        parts = ([t.name for t in model.vessel.thrusters] if est.thrust_error_model == "per_thruster"
                 else ["x", "y", "n"])
        factors.append({"log": name, **{f"thrust_error_{t}": f for t, f in
                                        zip(parts, est.thrust_error[at_failure], strict=True)}})
        for win, sel in (("dp", (r >= i0 - 300) & (r < i0)), ("drift", (r >= i0 + 60) & (r <= i0 + 300))):
            rows.append({
                "log": name, "window": win,
                "heading_change_deg": heading_change_deg(df.truth_heading_deg.to_numpy(), i0, r[sel]),
                "current_m_s_est": cur_e[sel, 0].mean(), "current_m_s_true": cur_t[r][sel, 0].mean(),
                "load_north_kN_est": load_e[sel, 0].mean() / 1e3, "load_north_kN_true": load_t[r][sel, 0].mean() / 1e3,
                "load_east_kN_est": load_e[sel, 1].mean() / 1e3, "load_east_kN_true": load_t[r][sel, 1].mean() / 1e3,
                "load_yaw_kNm_est": load_e[sel, 2].mean() / 1e3, "load_yaw_kNm_true": load_t[r][sel, 2].mean() / 1e3,
                "load_yaw_kNm_est_at_failure": load_e[at_failure, 2] / 1e3,
                "thrust_error_x_kN_est": thr_e[sel, 0].mean() / 1e3, "thrust_error_x_kN_true": thr_t[r][sel, 0].mean() / 1e3,
                "thrust_error_y_kN_est": thr_e[sel, 1].mean() / 1e3, "thrust_error_y_kN_true": thr_t[r][sel, 1].mean() / 1e3,
                "thrust_error_n_kNm_est": thr_e[sel, 2].mean() / 1e3,
                "thrust_error_n_kNm_true": thr_t[r][sel, 2].mean() / 1e3,
                "current_yaw_at_rest_kNm": cur_yaw_t[r][sel].mean() / 1e3,
            })
    table = pd.DataFrame(rows)
    write_table(args.out, "environment_vs_truth", table,
                yaw_summary(table) + "\n\n" + station_keeping_yaw_split(table[table.window == "dp"]))
    write_table(args.out, "thrust_error_factors", pd.DataFrame(factors),
                "Each thruster's estimated thrust-error factor `theta` at the last row of station keeping "
                "(it delivers `1 + theta` times the model's thrust).")
    _plot(args.out / "environment_vs_truth.png", series)
    if args.drift_hull is not None:     # made from another committed result: record which
        record_inputs(args.out / "environment_vs_truth.md", [args.drift_hull])
    return 0


def write_table(out: Path, stem: str, table: pd.DataFrame, summary_md: str) -> None:
    """``<stem>.csv`` and ``<stem>.md`` (the table, then ``summary_md``) in ``out``, atomically;
    prints the Markdown."""
    out.mkdir(parents=True, exist_ok=True)
    csv = table.to_csv(index=False, float_format="%.4g")
    atomic_write(out / f"{stem}.csv", lambda fh: fh.write(csv.encode("utf-8")))
    md = "\n".join([markdown_table(table.round(2)), "", summary_md])
    atomic_write(out / f"{stem}.md", lambda fh: fh.write((md + "\n").encode("utf-8")))
    print(md)


def _drift_hull_coefficients(path: Path) -> dict[str, float]:
    """Log name -> the coefficient of the hull's yaw moment in a drift [rad/m^2] of a drift
    benchmark's ``drift_hull.csv``."""
    try:
        t = pd.read_csv(path)
        k = dict(zip(t["log"], pd.to_numeric(t["coefficient_rad_per_m2"], errors="coerce")))
    except (OSError, ValueError, KeyError) as exc:
        raise ValueError(f"--drift-hull {path}: expected a drift benchmark's drift_hull.csv with columns log and "
                         f"coefficient_rad_per_m2 ({type(exc).__name__}: {exc})") from None
    bad = [name for name, v in k.items() if not np.isfinite(v)]
    if bad:
        raise ValueError(f"--drift-hull {path}: coefficient_rad_per_m2 is not a number for log {bad[0]}")
    return k


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
    # many logs make a tall figure: a lower resolution keeps the file small
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=100 if len(series) <= 8 else 60))
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
