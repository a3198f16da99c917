"""Figure of one simulated DP-loss scenario: track, velocities and thruster commands.

Usage::

    python benchmarks/plot_scenario.py                      # seed 7, full scenario (50 min DP + 15 min drift)
    python benchmarks/plot_scenario.py --seed 4 --out /tmp/s4.png

Writes ``docs/figures/scenario_dp_loss.png`` by default and prints the scenario's
conditions and drift statistics.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hybridship.fileio import atomic_write  # noqa: E402
from hybridship.sim.scenario import DPLossConfig, drift_statistics, simulate_dp_loss  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def plot(df, out: Path, title: str) -> None:
    """Draw the four panels of ``df`` (a DP-loss log) into ``out``."""
    t_min = df["time_s"].to_numpy() / 60.0
    t_sd = df["truth_t_shutdown_s"].iloc[0] / 60.0
    c = df.attrs.get("conditions", {})

    fig = plt.figure(figsize=(13, 8.5), constrained_layout=True)
    gs = fig.add_gridspec(3, 2, width_ratios=[1.0, 1.3])
    ax_tr = fig.add_subplot(gs[:, 0])
    ax_v = fig.add_subplot(gs[0, 1])
    ax_rpm = fig.add_subplot(gs[1, 1], sharex=ax_v)
    ax_az = fig.add_subplot(gs[2, 1], sharex=ax_v)

    # Track: east on x, north on y (a chart).
    dp = df["dp_active"].to_numpy() == 1
    ax_tr.plot(df["east_m"][dp], df["north_m"][dp], ".", ms=1.5, color="0.6", label="measured, DP on")
    ax_tr.plot(df["east_m"][~dp], df["north_m"][~dp], ".", ms=1.5, color="tab:orange", alpha=0.5,
               label="measured, drifting")
    ax_tr.plot(df["truth_east_lf_m"], df["truth_north_lf_m"], "-", lw=1.2, color="k", label="truth (LF)")
    i_sd = int(np.argmax(~dp))
    ax_tr.plot(df["truth_east_lf_m"].iloc[i_sd], df["truth_north_lf_m"].iloc[i_sd], "rX", ms=11,
               label=f"DP shutdown (t = {t_sd:.1f} min)")
    ax_tr.plot(0.0, 0.0, "b+", ms=14, mew=2, label="set-point")
    # Mark the heading every 2 minutes of drift with a short bow line.
    half = 0.03 * max(np.ptp(df["truth_east_lf_m"]), np.ptp(df["truth_north_lf_m"]), 20.0)  # not to scale
    for i in range(i_sd, len(df), 120):
        n0, e0 = df["truth_north_lf_m"].iloc[i], df["truth_east_lf_m"].iloc[i]
        psi = math.radians(df["truth_heading_lf_deg"].iloc[i])
        ds, dc = half * math.sin(psi), half * math.cos(psi)
        ax_tr.plot([e0 - ds, e0 + ds], [n0 - dc, n0 + dc], "-", color="tab:blue", lw=3, alpha=0.6,
                   solid_capstyle="round")
        ax_tr.plot(e0 + ds, n0 + dc, "o", color="tab:blue", ms=4)
    if c:
        span = max(np.ptp(df["truth_east_lf_m"]), np.ptp(df["truth_north_lf_m"]), 20.0)
        for name, ang, col in (("wind to", c["wind_dir_from_deg"] + 180.0, "tab:green"),
                               ("current to", c["current_dir_to_deg"], "tab:purple")):
            a = math.radians(ang)
            tip = (0.25 * span * math.sin(a), 0.25 * span * math.cos(a))
            ax_tr.annotate("", xy=tip, xytext=(0, 0), arrowprops=dict(arrowstyle="->", color=col, lw=2))
            ax_tr.text(1.08 * tip[0], 1.08 * tip[1], name, color=col, fontsize=9, ha="center", va="center")
            ax_tr.plot(1.2 * tip[0], 1.2 * tip[1], alpha=0.0)  # annotations do not widen the limits
    ax_tr.set_xlabel("east [m]")
    ax_tr.set_ylabel("north [m]")
    ax_tr.set_aspect("equal", adjustable="datalim")
    ax_tr.grid(alpha=0.3)
    ax_tr.legend(loc="best", fontsize=8)
    ax_tr.set_title("track (heading every 2 min of drift, dot = bow; not to scale)")

    ax_v.plot(t_min, df["u_m_s"], color="tab:blue", lw=0.5, alpha=0.4)
    ax_v.plot(t_min, df["v_m_s"], color="tab:red", lw=0.5, alpha=0.4)
    ax_v.plot(t_min, df["truth_u_lf_mps"], color="tab:blue", lw=1.3, label="u (LF truth; thin: measured)")
    ax_v.plot(t_min, df["truth_v_lf_mps"], color="tab:red", lw=1.3, label="v (LF truth; thin: measured)")
    sog = np.hypot(np.gradient(df["truth_north_lf_m"]), np.gradient(df["truth_east_lf_m"]))
    ax_v.plot(t_min, sog, color="k", lw=1.0, label="speed over ground (LF)")
    ax_v.set_ylabel("velocity [m/s]")
    ax_r = ax_v.twinx()
    ax_r.plot(t_min, df["truth_r_lf_degps"], color="tab:green", lw=0.9, label="r (LF truth)")
    ax_r.set_ylabel("yaw rate [deg/s]", color="tab:green")
    h1, l1 = ax_v.get_legend_handles_labels()
    h2, l2 = ax_r.get_legend_handles_labels()
    ax_v.legend(h1 + h2, l1 + l2, fontsize=7, loc="lower left", ncol=2)
    ax_v.set_title("velocities (body frame)")

    for name, col in (("tunnel", "tab:gray"), ("port", "tab:red"), ("stbd", "tab:green")):
        ax_rpm.plot(t_min, df[f"{name}_rpm"], lw=0.8, color=col, label=f"{name}_rpm")
    ax_rpm.set_ylabel("shaft speed [rpm]")
    ax_rpm.legend(fontsize=8, loc="upper left")
    ax_rpm.set_title("thruster rpm (feedback; decays with a 1.5 s time constant after the shutdown)")

    for name, col in (("port", "tab:red"), ("stbd", "tab:green")):
        ax_az.plot(t_min, df[f"{name}_azimuth_deg"], lw=0.8, color=col, label=f"{name}_azimuth_deg")
    ax_az.set_ylabel("azimuth [deg]")
    ax_az.set_xlabel("time [min]")
    ax_az.legend(fontsize=8, loc="upper left")
    ax_az.set_title("azimuth angles (frozen after the shutdown)")

    for ax in (ax_v, ax_rpm, ax_az):
        ax.axvline(t_sd, color="r", ls="--", lw=1)
        ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=11)
    out.parent.mkdir(parents=True, exist_ok=True)
    # atomically: a failed write leaves an earlier figure as it was
    atomic_write(out, lambda fh: fig.savefig(fh, format=out.suffix.lstrip(".").lower() or "png", dpi=110))
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--t-shutdown-s", type=float, default=3000.0)
    ap.add_argument("--drift-s", type=float, default=900.0)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "scenario_dp_loss.png")
    args = ap.parse_args(argv)

    try:
        cfg = DPLossConfig(seed=args.seed, t_shutdown_s=args.t_shutdown_s, drift_s=args.drift_s)
    except ValueError as exc:           # "drift_s: must be > 0 (got -5.0) [DPLossConfig]": name the option
        field, _, reason = str(exc).partition(":")
        ap.error(f"--{field.replace('_', '-')}:{reason}")
    df = simulate_dp_loss(cfg)
    c = df.attrs["conditions"]
    title = (f"Simulated RV Gunnerus DP loss, seed {args.seed}: wind {c['wind_mean_mps']:.1f} m/s from "
             f"{c['wind_dir_from_deg']:.0f} deg, Hs {c['hs_m']:.2f} m, Tp {c['tp_s']:.1f} s from "
             f"{c['wave_dir_from_deg']:.0f} deg, current {c['current_mps']:.2f} m/s to "
             f"{c['current_dir_to_deg']:.0f} deg, heading set-point {c['heading_sp_deg']:.0f} deg")
    plot(df, args.out, title)
    print(title)
    for k, v in drift_statistics(df).items():
        print(f"  {k}: {v:.3f}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
