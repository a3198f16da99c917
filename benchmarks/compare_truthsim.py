"""Compare our simulator's drift with the independent truthsim-dev simulator, scenario by scenario.

For every scenario in ``shared/data/truthsim-dev/scenarios.csv`` our simulator is run in
the SAME conditions: mean wind speed and direction, gust intensity, Hs, Tp and wave
direction (JONSWAP, gamma 3.3, long-crested), mean current speed and direction, heading
set-point, shutdown time and a 600 s drift. Everything random (gust, wave and current
realisations, noise) differs: it is drawn from our own generator seeded with the truthsim
seed. Both simulators' logs are then read with :func:`hybridship.logs.io.read_log` and
summarised with the same :func:`hybridship.sim.scenario.drift_statistics`.

Usage::

    python benchmarks/compare_truthsim.py
    python benchmarks/compare_truthsim.py --work-dir /tmp/matched   # keep our logs

Prints a Markdown table (also to ``--tables``, for the docs) and writes
``docs/figures/drift_comparison.png`` (``--out``).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from hybridship.fileio import atomic_write, write_text  # noqa: E402
from hybridship.logs.io import read_log, write_log  # noqa: E402
from hybridship.sim.environment import SeaState  # noqa: E402
from hybridship.sim.scenario import DPLossConfig, drift_statistics, simulate_dp_loss  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: ``../shared/data/truthsim-dev`` beside the repository (data never go into it).
TRUTHSIM = ROOT.parent / "shared" / "data" / "truthsim-dev"
DRIFT_S = 600.0


def matched_config(row: pd.Series) -> DPLossConfig:
    """Our scenario in the conditions of one row of truthsim-dev's ``scenarios.csv``."""
    sea = SeaState(hs_m=row["hs_m"], tp_s=row["tp_s"], wave_dir_from_rad=math.radians(row["wave_dir_from_deg"]),
                   wind_speed_m_s=row["wind_mean_mps"], wind_dir_from_rad=math.radians(row["wind_dir_from_deg"]),
                   gust_intensity=row["gust_intensity"], current_speed_m_s=row["current_mps"],
                   current_dir_to_rad=math.radians(row["current_dir_to_deg"]), gamma=3.3)
    return DPLossConfig(seed=int(row["seed"]), sea_state=sea, heading_sp_deg=float(row["heading_sp_deg"]),
                        t_shutdown_s=float(row["t_shutdown_s"]), t_shutdown_jitter_s=0.0, drift_s=DRIFT_S)


def excursion_curve(df: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time since shutdown [s], north and east of the LF track relative to the shutdown position."""
    t_sd = drift_statistics(df)["t_shutdown_s"]
    sel = df["time_s"].to_numpy() >= t_sd - 1e-9
    n = df["truth_north_lf_m"].to_numpy()[sel]
    e = df["truth_east_lf_m"].to_numpy()[sel]
    return df["time_s"].to_numpy()[sel] - t_sd, n - n[0], e - e[0]


def comparison_markdown(res: pd.DataFrame) -> str:
    """The printed comparison: per scenario our drift statistics / truthsim-dev's, the median
    ratios, and the 600-s drift direction's difference [deg]."""
    def pair(r, key, fmt):
        return f"{format(r[key + '|ours'], fmt)} / {format(r[key + '|truthsim'], fmt)}"

    lines = ["Our simulator / truthsim-dev in matched conditions (drift statistics of the LF track; "
             "excursion = distance from the position at the shutdown):\n",
             "| scenario | wind m/s | Hs m | Tp s | current m/s | excursion 60 s [m] | excursion 600 s [m] "
             "| mean drift SOG [m/s] | heading change 600 s [deg] | DP position std [m] |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in res.iterrows():
        lines.append(f"| {r['scenario']} | {r['wind']:.1f} | {r['hs']:.2f} | {r['tp']:.1f} | {r['cur']:.2f} "
                     f"| {pair(r, 'drift_excursion_60s_m', '.1f')} | {pair(r, 'drift_excursion_600s_m', '.0f')} "
                     f"| {pair(r, 'drift_mean_sog_mps', '.2f')} | {pair(r, 'drift_dheading_600s_deg', '.0f')} "
                     f"| {pair(r, 'dp_pos_std_m', '.2f')} |")
    ratio = {k: res[f"{k}|ours"] / res[f"{k}|truthsim"] for k in
             ("drift_excursion_60s_m", "drift_excursion_600s_m", "drift_mean_sog_mps", "dp_pos_std_m")}
    lines.append(f"| **ratio ours/truthsim (median)** | | | | | {ratio['drift_excursion_60s_m'].median():.2f} "
                 f"| {ratio['drift_excursion_600s_m'].median():.2f} | {ratio['drift_mean_sog_mps'].median():.2f} | "
                 f"| {ratio['dp_pos_std_m'].median():.2f} |")
    ang = [(r["drift_dir_to_deg|ours"] - r["drift_dir_to_deg|truthsim"] + 180.0) % 360.0 - 180.0
           for _, r in res.iterrows()]
    lines.append("\nDirection of the 600 s net drift, ours minus truthsim [deg]: "
                 + ", ".join(f"{a:+.0f}" for a in ang))
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--truthsim", type=Path, default=TRUTHSIM, help="truthsim-dev folder")
    ap.add_argument("--work-dir", type=Path, default=None, help="where to write our matched logs (default: temporary)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "drift_comparison.png")
    ap.add_argument("--tables", type=Path, default=None,
                    help="also write the printed comparison to this Markdown file (atomically)")
    args = ap.parse_args(argv)
    if not (args.truthsim / "scenarios.csv").is_file():
        ap.error(f"--truthsim: expected a truthsim-dev folder with scenarios.csv, not found at {args.truthsim}")

    summary = pd.read_csv(args.truthsim / "scenarios.csv")
    tmp = None
    work = args.work_dir
    if work is None:
        tmp = tempfile.TemporaryDirectory()
        work = Path(tmp.name)
    work.mkdir(parents=True, exist_ok=True)

    rows, curves = [], []
    for _, row in summary.iterrows():
        name = row["file"].removesuffix(".csv.gz")
        truth = read_log(args.truthsim / "logs" / row["file"])
        ours_path = work / f"ours_{name}.csv.gz"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            write_log(simulate_dp_loss(matched_config(row)), ours_path)
        ours = read_log(ours_path)
        s_t, s_o = drift_statistics(truth), drift_statistics(ours)
        rows.append(dict(scenario=name, wind=row["wind_mean_mps"], hs=row["hs_m"], tp=row["tp_s"],
                         cur=row["current_mps"], **{f"{k}|truthsim": v for k, v in s_t.items()},
                         **{f"{k}|ours": v for k, v in s_o.items()}))
        curves.append((name, excursion_curve(truth), excursion_curve(ours)))
    if tmp is not None:
        tmp.cleanup()
    res = pd.DataFrame(rows)

    text = comparison_markdown(res)
    print(text)
    if args.tables is not None:
        args.tables.parent.mkdir(parents=True, exist_ok=True)
        write_text(args.tables, text + "\n")

    # ---- figure
    fig, axes = plt.subplots(1, 3, figsize=(16, 5.4), constrained_layout=True)
    colors = plt.cm.tab10(np.arange(len(curves)))
    ax = axes[0]
    for (name, (tt, nt, et), (to, no, eo)), col in zip(curves, colors):
        ax.plot(et, nt, "-", color=col, lw=1.5, label=f"{name}")
        ax.plot(eo, no, "--", color=col, lw=1.5)
        ax.plot(et[-1], nt[-1], "o", color=col, ms=4)
        ax.plot(eo[-1], no[-1], "s", color=col, ms=4)
    ax.plot(0, 0, "k+", ms=12)
    ax.set_xlabel("east from shutdown position [m]")
    ax.set_ylabel("north from shutdown position [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("600 s drift tracks: solid truthsim-dev, dashed ours")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax = axes[1]
    for (name, (tt, nt, et), (to, no, eo)), col in zip(curves, colors):
        ax.plot(tt, np.hypot(nt, et), "-", color=col, lw=1.5)
        ax.plot(to, np.hypot(no, eo), "--", color=col, lw=1.5)
    ax.set_xlabel("time since shutdown [s]")
    ax.set_ylabel("excursion [m]")
    ax.set_title("excursion from the shutdown position")
    ax.grid(alpha=0.3)
    ax = axes[2]
    x = res["drift_mean_sog_mps|truthsim"]
    y = res["drift_mean_sog_mps|ours"]
    ax.scatter(x, y, c=colors[: len(res)], s=40, zorder=3)
    for _, r in res.iterrows():
        ax.annotate(r["scenario"], (r["drift_mean_sog_mps|truthsim"], r["drift_mean_sog_mps|ours"]), fontsize=7,
                    xytext=(3, 3), textcoords="offset points")
    lim = [0, 1.1 * max(x.max(), y.max())]
    ax.plot(lim, lim, "k-", lw=0.8, label="1:1")
    ax.set_xlim(lim)
    ax.set_ylim(lim)
    ax.set_xlabel("truthsim-dev mean drift SOG [m/s]")
    ax.set_ylabel("our mean drift SOG [m/s]")
    ax.set_title("mean drift speed over 600 s")
    ax.legend()
    ax.grid(alpha=0.3)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    # atomically: a failed write leaves an earlier figure as it was
    atomic_write(args.out, lambda fh: fig.savefig(fh, format=args.out.suffix.lstrip(".").lower() or "png", dpi=110))
    plt.close(fig)
    print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
