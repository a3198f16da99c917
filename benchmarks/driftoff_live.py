"""Live drift-off mode on the truthsim-dev logs: predicted vs actual time to reach 5 m and 10 m.

For each log of ``../shared/data/truthsim-dev/logs`` (an independent simulator): the
blackout time ``t_b`` is the first row where ``dp_active`` goes 1 -> 0. The prediction
uses only the rows before ``t_b`` (:func:`hybridship.driftoff.live.environment_from_log`:
the environment estimator, or with ``--method mean`` the 900-s residual mean; then
:func:`~hybridship.driftoff.live.blackout_now`). The actual
time to reach a radius is measured from ``t_b`` on

* the noise-free low-frequency track ``truth_north_lf_m``, ``truth_east_lf_m`` (distance
  from the position at ``t_b``), and
* the logged (GNSS, with wave-frequency motion and noise) track ``north_m``, ``east_m``,

and placed in the predicted distribution: the percentile is the share of predicted samples
that reach the radius no later than the actual time (50 = the median prediction; near 0 the
vessel got there sooner than almost every sample, i.e. drifted faster than predicted; near
100 more slowly). Each update is timed.

Usage::

    python benchmarks/driftoff_live.py                        # writes docs/results/driftoff-live/
    python benchmarks/driftoff_live.py --samples 200 --out /tmp/live
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from _results import check_out
from hybridship.driftoff.live import blackout_now, environment_from_log  # noqa: E402
from hybridship.driftoff.planning import DriftOffSettings  # noqa: E402
from hybridship.driftoff.report import markdown_table, write_frame, write_text  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "truthsim-dev" / "logs"
RADII = (5.0, 10.0)


def first_time(t, d, radius):
    """First time [s] the distance ``d`` reaches ``radius`` (linear interpolation), or inf."""
    i = np.flatnonzero(d >= radius)
    if i.size == 0:
        return np.inf
    k = int(i[0])
    if k == 0:
        return float(t[0])
    return float(t[k - 1] + (radius - d[k - 1]) / (d[k] - d[k - 1]) * (t[k] - t[k - 1]))


def evaluate(path: Path, settings: DriftOffSettings, repeats: int = 3, method: str = "estimator",
             environment_config=None) -> list[dict]:
    df = pd.read_csv(path)
    dp = df["dp_active"].to_numpy()
    starts = np.flatnonzero((dp[:-1] == 1) & (dp[1:] == 0))
    if starts.size == 0:
        return []
    b = int(starts[0]) + 1                      # first row without DP
    hist = df.iloc[:b]                          # what is known before the blackout
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        est = environment_from_log(hist, "gunnerus", n_members=settings.n_samples, method=method,
                                   environment_config=environment_config)
        res = blackout_now(est, "gunnerus", settings)
        times.append(time.perf_counter() - t0)
    t = df["time_s"].to_numpy(float)[b:] - df["time_s"].iloc[b]
    rows = []
    for track, (cn, ce) in {"truth_lf": ("truth_north_lf_m", "truth_east_lf_m"),
                            "logged": ("north_m", "east_m")}.items():
        n, e = df[cn].to_numpy(float)[b:], df[ce].to_numpy(float)[b:]
        d = np.hypot(n - n[0], e - e[0])
        for r, radius in enumerate(settings.radii_m):
            actual = first_time(t, d, radius)
            pred = res.t_reach_s[0, :, r]
            q = res.time_quantiles()[0, r]                           # inf = not reached
            rows.append({"log": path.name, "track": track, "radius_m": radius, "actual_s": actual,
                         "pred_p10_s": q[0], "pred_p50_s": q[1], "pred_p90_s": q[2],
                         "percentile": 100.0 * float(np.mean(pred <= actual)),
                         "update_s": float(np.median(times[1:] if len(times) > 1 else times))})
    return rows


def _option_number(x: float) -> str:
    """``x`` as the command line must repeat it: ``%g`` (1, 0.5) when that gives ``x`` back,
    else in full (``%g`` made 0.1234567 '0.123457', another spread)."""
    return f"{x:g}" if float(f"{x:g}") == x else repr(x)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA, help="folder of truthsim-dev logs")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results" / "driftoff-live")
    ap.add_argument("--samples", type=int, default=500, help="Monte-Carlo samples (default 500)")
    ap.add_argument("--vessel-spread", type=float, default=1.0, help="[true_vessel] spread multiplier (default 1)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--method", choices=("estimator", "mean"), default="estimator",
                    help="environment from the environment estimator (default) or the 900-s residual mean")
    ap.add_argument("--thrust-error-model", choices=("per_dof", "per_thruster"), default="per_thruster",
                    help="the estimator's thrust-model error: per thruster (the default) or per DOF (the "
                         "previous default, hybridship.residual.environment.PER_DOF)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    cfg = None
    if args.thrust_error_model == "per_dof":
        from hybridship.residual.environment import PER_DOF, EnvironmentConfig

        cfg = EnvironmentConfig(**PER_DOF)
    try:
        st = DriftOffSettings(n_samples=args.samples, radii_m=RADII, reaction_times_s=(30.0, 60.0),
                              horizon_s=300.0, vessel_spread=args.vessel_spread, seed=args.seed)
    except ValueError as exc:           # "n_samples: must be >= 1 (got 0) [DriftOffSettings]": name the option
        field, _, reason = str(exc).partition(":")
        ap.error({"n_samples": "--samples", "vessel_spread": "--vessel-spread"}.get(field, f"--{field}") + ":" + reason)
    files = sorted(args.data.glob("*.csv.gz")) if args.data.is_dir() else []
    if not files:
        print(f"no logs found in {args.data}; nothing to do", file=sys.stderr)
        return 1
    rows = []
    for f in files:
        rows += evaluate(f, st, method=args.method, environment_config=cfg)
    res = pd.DataFrame(rows)
    write_frame(args.out / "live.csv", res)
    lf = res[res.track == "truth_lf"]
    # the band as printed: the actual time between the predicted 10 % and 90 % times (a
    # percentile of exactly 90 can lie just beyond the interpolated 90 % time)
    inside = int(((lf.actual_s >= lf.pred_p10_s) & (lf.actual_s <= lf.pred_p90_s)).sum())
    text = (f"Command: `python benchmarks/driftoff_live.py --samples {args.samples}"
            f" --vessel-spread {_option_number(args.vessel_spread)} --seed {args.seed} --method {args.method}"
            + (" --thrust-error-model per_dof" if cfg is not None else "")
            + ("" if args.data == DEFAULT_DATA else f" --data {shlex.quote(str(args.data))}") + "`\n\n"
            f"{len(files)} logs, {args.samples} samples per prediction; update time (environment estimate + "
            f"blackouts) median {res.update_s.median():.3f} s, max {res.update_s.max():.3f} s.\n"
            f"Truth-track actual times inside the predicted 10-90 % band: {inside} of {len(lf)} (log x radius)"
            + (f", {100 * inside / len(lf):.0f} %" if len(lf) else "") + ".\n\n" + markdown_table(res.drop(columns=["update_s"]), digits=1) + "\n")
    write_text(args.out / "tables.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
