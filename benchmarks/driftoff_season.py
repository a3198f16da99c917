"""Season drift-off sweep: hourly weather states x 8 headings x 100 samples, one process vs Dask.

There is no public hindcast in the shared data, so the script writes a **synthetic** hourly
year (``weather_year.csv``, the documented weather-table columns): wind speed with a
seasonal mean and day-scale log-normal variability, slowly wandering direction, fetch-limited
waves from the wind (plus swell), and a semidiurnal tidal current. It then sweeps the first
``--states`` states

1. in this process (``scheduler=None``), and
2. on a ``dask.distributed.LocalCluster`` of ``--workers`` single-threaded processes (started
   and warmed up before the clock starts; the start-up time is reported separately),

checks that both give identical tables (on the states both ran), and reports the wall
times. A run over fewer than 8 760 states has its full-year wall time **extrapolated**
linearly (and labelled so); ``--single-states`` limits the single-process run to its first
states, so that the cluster can do the whole year while the single process is extrapolated.

Usage::

    python benchmarks/driftoff_season.py --states 8760            # the full year (long)
    python benchmarks/driftoff_season.py --states 720             # 30 days, extrapolated
    python benchmarks/driftoff_season.py --states 8760 --single-states 720   # year on the cluster only
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from _results import check_out
from hybridship.driftoff.planning import DriftOffSettings  # noqa: E402
from hybridship.driftoff.report import markdown_table, write_frame, write_text  # noqa: E402
from hybridship.driftoff.season import require_dask, season_sweep  # noqa: E402
from hybridship.driftoff.weather import read_weather_table  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
HOURS = 8760


def synthetic_year(seed: int = 0, hours: int = HOURS) -> pd.DataFrame:
    """A synthetic hourly weather year in the weather-table format (see the module notes)."""
    rng = np.random.default_rng(seed)
    t = np.arange(hours, dtype=float)
    day = t / 24.0

    def ar1(tau_h, sigma):
        a = math.exp(-1.0 / tau_h)
        x = np.empty(hours)
        x[0] = sigma * rng.standard_normal()
        z = rng.standard_normal(hours) * sigma * math.sqrt(1 - a * a)
        for k in range(1, hours):
            x[k] = a * x[k - 1] + z[k]
        return x

    wind = (7.0 + 2.5 * np.cos(2 * np.pi * (day - 15) / 365.0)) * np.exp(ar1(24.0, 0.45) - 0.1)
    wind = np.clip(wind, 0.0, 30.0)
    wdir = np.mod(240.0 + np.degrees(ar1(48.0, 1.2)), 360.0)
    hs = 0.012 * wind**2 + 0.3 * np.exp(ar1(72.0, 0.4))
    tp = np.maximum(3.0, 4.5 * np.sqrt(hs) + 0.5 * ar1(12.0, 1.0))
    wave_dir = np.mod(wdir + 15.0 * rng.standard_normal(hours), 360.0)
    phase = 2 * np.pi * t / 12.42
    cur = 0.05 + 0.3 * np.abs(np.cos(phase))
    cur_dir = np.where(np.cos(phase) >= 0, 45.0, 225.0)
    times = pd.date_range("2025-01-01", periods=hours, freq="h").strftime("%Y-%m-%dT%H:%M")
    return pd.DataFrame({"time": times, "wind_speed_m_s": wind, "wind_dir_deg": wdir, "hs_m": hs, "tp_s": tp,
                         "wave_dir_deg": wave_dir, "current_m_s": cur, "current_dir_deg": cur_dir,
                         "gust_intensity": 0.1})


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--states", type=int, default=240, help="hourly states to sweep (default 240; 8760 = a year)")
    ap.add_argument("--single-states", type=int, default=None,
                    help="states of the single-process run (default: --states); fewer = that run is extrapolated")
    ap.add_argument("--samples", type=int, default=100, help="samples per state and heading (default 100)")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster workers (default 2)")
    ap.add_argument("--chunk-size", type=int, default=24, help="states per task (default 24)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results" / "driftoff-season")
    ap.add_argument("--data-out", type=Path, default=None,
                    help="folder for the large files weather_year.csv and season.csv (default: a temporary folder)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    for flag, value in (("--states", args.states), ("--single-states", args.single_states), ("--samples", args.samples),
                        ("--workers", args.workers), ("--chunk-size", args.chunk_size)):
        if value is not None and value < 1:     # a negative --states sliced from the end; no workers, a hang
            ap.error(f"{flag}: expected a positive integer, got {value}")
    if args.seed < 0:
        ap.error(f"--seed: expected a non-negative integer, got {args.seed}")
    dd = require_dask()
    data_out = args.data_out or Path(tempfile.mkdtemp(prefix="driftoff_season_"))

    table = synthetic_year(args.seed)
    write_frame(data_out / "weather_year.csv", table)
    print(f"weather table and per-state results go to {data_out}")
    states, labels = read_weather_table(data_out / "weather_year.csv")
    states, labels = states[: args.states], labels[: args.states]
    psi = np.radians(np.arange(0, 360, 45))
    st = DriftOffSettings(n_samples=args.samples, seed=args.seed)
    season_sweep("gunnerus", states[:1], psi[:1], settings=DriftOffSettings(n_samples=2), progress=False)  # compile

    n_one = len(states) if args.single_states is None else min(max(1, args.single_states), len(states))
    one = season_sweep("gunnerus", states[:n_one], psi, settings=st, labels=labels[:n_one], chunk_size=args.chunk_size,
                       progress=True)

    t0 = time.perf_counter()
    cluster = dd.LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                              env={"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"})
    client = dd.Client(cluster)
    # warm-up: every worker loads the compiled kernels once
    client.run(lambda: season_sweep("gunnerus", states[:1], psi[:1], settings=DriftOffSettings(n_samples=2),
                                    progress=False) and None)
    startup = time.perf_counter() - t0
    try:
        many = season_sweep("gunnerus", states, psi, settings=st, labels=labels, chunk_size=args.chunk_size,
                            scheduler=client, progress=True)
    finally:
        client.close()
        cluster.close()
    # identical on the states both runs did (rows are ordered by state)
    f_one, f_many = one.to_frame(), many.to_frame()
    equal = f_one.equals(f_many.iloc[: len(f_one)].reset_index(drop=True))
    rows = []
    for name, r, k in (("single process", one, n_one), (f"LocalCluster, {args.workers} workers", many, len(states))):
        n = k * psi.size * args.samples
        rows.append({"run": name, "states": k, "samples": n, "wall_s": r.wall_s, "samples_per_s": n / r.wall_s,
                     "year_wall_s": r.wall_s * HOURS / k,
                     "year": "measured" if k == HOURS else f"extrapolated x {HOURS / k:.1f}"})
    res = pd.DataFrame(rows)
    write_frame(args.out / "timing.csv", res)
    write_frame(data_out / "season.csv", f_many)
    write_frame(args.out / "operability.csv", many.operability(0.1))
    single_opt = "" if args.single_states is None else f" --single-states {args.single_states}"
    text = (f"# Drift-off season sweep (synthetic weather year)\n\nCommand: `python benchmarks/driftoff_season.py "
            f"--states {args.states}{single_opt} --samples {args.samples} --workers {args.workers} "
            f"--chunk-size {args.chunk_size}{f' --seed {args.seed}' if args.seed else ''}`\n\n"
            f"Hourly states x {psi.size} headings x {args.samples} samples. Cluster start-up and warm-up (not in the "
            f"wall times): {startup:.1f} s. Single-process and cluster tables identical on the {n_one} states both "
            f"ran: **{equal}**. `year_wall_s` is the wall time of 8 760 states: measured where `year` says so, "
            f"otherwise EXTRAPOLATED linearly from the states run. "
            f"Machine: {os.cpu_count()} logical cores, 1-min load average at the end {os.getloadavg()[0]:.1f} "
            f"(a load above the core count means other jobs competed for the cores).\n\n"
            + markdown_table(res, digits=1) + "\n")
    spaced = lambda x: f"{x:,.0f}".replace(",", " ")  # noqa: E731  (1 058, as the docs write numbers)
    text += (f"The cluster's {spaced(len(states))} states x {psi.size} headings x {args.samples} samples = "
             f"{spaced(len(states) * psi.size * args.samples)} blackouts took {spaced(many.wall_s)} s "
             f"({many.wall_s / 60:.0f} min).\n")
    write_text(args.out / "tables.md", text)
    print(text)
    return 0 if equal else 1


if __name__ == "__main__":
    sys.exit(main())
