"""The default hybrid's forecasts during station keeping, leave one log out: errors and spread.

The drift benchmark scores forecasts after a failure; this one scores the forecasts a DP
operator gets while the vessel is still station keeping (commands held at the start, the
``forecast`` default). For every log the default :class:`~hybridship.predictors.HybridPredictor`
is fitted on the other logs (its spread calibrated on their held-back station keeping, as
``fit`` does) and forecasts from a start every ``--every-s`` seconds of the log's own
station keeping, from the end of the hybrid's warm-up (``warm_up_s``: the estimator's
30 min, so that every start's filter has run at least that long) to the last start whose forecast
ends before the failure. Reported per log and lead time:

* the mean distance [m] and heading [deg] errors of the hybrid, of the same model with the
  nets off (physics + environment estimator), of the physics alone and of dead reckoning,
  at 15, 30, 45 and 60 s, and how many log x lead cells the hybrid is worse than each;
* the share of north and east errors within 1 and 2 calibrated standard deviations (a
  calibrated Gaussian band covers 0.683 and 0.954), the errors' RMS, and the median
  calibrated and raw (ensemble) spreads [m].

The errors are against the logged positions and headings (what an operator can check;
on truthsim-dev they carry the simulated GNSS noise, 0.10 m white plus 0.15 m
Gauss-Markov, a large share of the calm logs' errors at short leads). Writes
``errors.csv`` (``model,log,lead_s,distance_m,heading_deg``), ``spread.csv``
(``log,lead_s,coverage_1sigma,coverage_2sigma,rms_error_m,median_std_m,median_raw_std_m,``
``heading_coverage_1sigma,heading_coverage_2sigma,spread_exponent``,
with a ``log = all`` row pooling the starts of every log; ``spread_exponent`` is the exponent
of the model that forecast the log, position and held commands) and ``station_keeping.md``.

``--station-keeping-spread`` sets
:attr:`~hybridship.residual.calibration.CalibrationConfig.station_keeping_spread`: the
spread of the load's variability in the station keeping before each start (``held_load``,
the default) or the members' spread (``ensemble``).

``--spread-exponent`` sets :attr:`~hybridship.residual.calibration.CalibrationConfig.spread_exponent`
(default 1, the ``fit`` default; ``likelihood`` chooses it per lead time on the held-back
part).

Examples::

    python benchmarks/station_keeping_coverage.py --out docs/results/station-keeping-truthsim-dev
    python benchmarks/station_keeping_coverage.py --station-keeping-spread ensemble \
        --out docs/results/station-keeping-truthsim-dev-ensemble
    python benchmarks/station_keeping_coverage.py --station-keeping-spread ensemble \
        --spread-exponent likelihood --out docs/results/station-keeping-truthsim-dev-likelihood
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.frames import wrap_pi
from hybridship.logs.ingest import ingest
from hybridship.predictors import DeadReckoning, DynamicPredictor, HybridPredictor
from hybridship.residual.calibration import GAUSS_COVERAGE, CalibrationConfig, coverage_of
from hybridship.vessel import load_vessel

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"
REPORT_LEADS_S = (15.0, 30.0, 45.0, 60.0)     # errors
SPREAD_LEADS_S = (15.0, 60.0)                 # coverage and spreads


def _lead_columns(lead_s, leads) -> list[int]:
    """Indices of ``lead_s`` [s] nearest to each of ``leads`` within the horizon."""
    return [int(np.argmin(np.abs(lead_s - L))) for L in leads if L <= lead_s[-1] + 1e-9]


class NoStationKeeping(ValueError):
    """A log without a start whose forecast fits in its station keeping."""


def station_keeping_starts(a, every_s: float, horizon_s: float, warm_up_s: float) -> np.ndarray:
    """Start times [s] every ``every_s`` from ``warm_up_s`` into the log, each with
    ``horizon_s`` of station keeping after it (none of the forecast reaches the failure)."""
    off = np.flatnonzero(a.dp_active == 0)
    t_end = a.time_s[off[0]] if off.size else a.time_s[-1]
    starts = np.arange(a.time_s[0] + warm_up_s, t_end - horizon_s - a.dt_s / 2, every_s)
    rows = np.unique(np.searchsorted(a.time_s, starts))
    t = a.time_s[rows[rows < len(a)]]            # on samples: a start moved past a gap is checked again
    return t[t + horizon_s < t_end]


def score_log(hybrid, references: dict, a, starts, horizon_s: float):
    """Errors and spreads of one log's forecasts: ``(errors, abs_err_ne, std, raw_std, lead_s,
    abs_err_heading, std_heading)`` with ``errors`` a dict model -> (distance (S, H+1) [m],
    heading (S, H+1) [rad]) for the hybrid, the hybrid with its nets off and each of
    ``references`` (name -> predictor), the hybrid's north and east absolute errors and
    spreads stacked on the first axis, (2 S, H+1) [m], the lead times (H+1,) [s], and the
    hybrid's absolute heading errors and heading spreads (S, H+1) [rad]."""
    forecasts = {"hybrid": hybrid.forecast(a, starts, horizon_s=horizon_s),
                 "hybrid_nets_off": hybrid.forecast(a, starts, horizon_s=horizon_s, nets=False)}
    forecasts |= {name: p.forecast(a, starts, horizon_s=horizon_s) for name, p in references.items()}
    raw = hybrid.forecast(a, starts, horizon_s=horizon_s, calibrated=False).eta_std
    f = forecasts["hybrid"]
    rows = np.searchsorted(a.time_s, f.start_time_s[:, None] + f.lead_s[None, :])
    truth = a.eta[rows]
    errors = {}
    for name, g in forecasts.items():
        d = g.eta - truth
        errors[name] = (np.hypot(d[..., 0], d[..., 1]), np.abs(wrap_pi(d[..., 2])))
    d = f.eta - truth
    abs_ne = np.concatenate([np.abs(d[..., 0]), np.abs(d[..., 1])])
    std = np.concatenate([f.eta_std[..., 0], f.eta_std[..., 1]])
    raw_std = np.concatenate([raw[..., 0], raw[..., 1]])
    return errors, abs_ne, std, raw_std, f.lead_s, np.abs(wrap_pi(d[..., 2])), f.eta_std[..., 2]


def spread_rows(log: str, lead_s, abs_ne, std, raw_std, leads=SPREAD_LEADS_S, abs_hdg=None,
                std_hdg=None) -> list[dict]:
    """Coverage, RMS error and median spreads at ``leads`` [s] for one log (or pooled); with
    ``abs_hdg, std_hdg`` also the heading's coverage."""
    cov = coverage_of(abs_ne, std)
    cov_h = None if abs_hdg is None else coverage_of(abs_hdg, std_hdg)
    out = []
    for j in _lead_columns(lead_s, leads):
        row = {"log": log, "lead_s": float(lead_s[j]), "coverage_1sigma": cov[j, 0],
               "coverage_2sigma": cov[j, 1], "rms_error_m": float(np.sqrt(np.mean(abs_ne[:, j] ** 2))),
               "median_std_m": float(np.median(std[:, j])), "median_raw_std_m": float(np.median(raw_std[:, j]))}
        if cov_h is not None:
            row |= {"heading_coverage_1sigma": cov_h[j, 0], "heading_coverage_2sigma": cov_h[j, 1]}
        out.append(row)
    return out


def run(logs: dict, vessel, every_s: float, horizon_s: float, hybrid_factory=None):
    """Leave-one-log-out scores of ``logs`` (name -> LogArrays): ``(errors, spread)`` DataFrames."""
    hybrid_factory = hybrid_factory or (lambda: HybridPredictor(vessel))
    references = {"dynamic": DynamicPredictor(vessel), "dead_reckoning": DeadReckoning(vessel)}
    err_rows, spread, pooled = [], [], []
    for name, a in logs.items():
        hybrid = hybrid_factory()
        hybrid.fit([b for k, b in logs.items() if k != name])
        starts = station_keeping_starts(a, every_s, horizon_s, hybrid.warm_up_s)
        if starts.size == 0:
            raise NoStationKeeping(f"{name}: no station keeping of {horizon_s:g} s after the hybrid's "
                                   f"{hybrid.warm_up_s:g} s of warm-up")
        errors, abs_ne, std, raw_std, lead_s, abs_hdg, std_hdg = score_log(hybrid, references, a, starts, horizon_s)
        for model, (dist, hdg) in errors.items():
            for j in _lead_columns(lead_s, REPORT_LEADS_S):
                err_rows.append({"model": model, "log": name, "lead_s": float(lead_s[j]),
                                 "distance_m": float(dist[:, j].mean()),
                                 "heading_deg": float(np.degrees(hdg[:, j].mean())), "n_starts": int(starts.size)})
        exponent = hybrid.calibration["held"]["position"].exponent if "held" in hybrid.calibration else np.nan
        spread += [r | {"spread_exponent": exponent}
                   for r in spread_rows(name, lead_s, abs_ne, std, raw_std, abs_hdg=abs_hdg, std_hdg=std_hdg)]
        pooled.append((abs_ne, std, raw_std, abs_hdg, std_hdg))
        print(f"{name}: {starts.size} starts", flush=True)
    ne, sd, raw, hd, sh = (np.concatenate(x) for x in zip(*pooled))
    spread += spread_rows("all", lead_s, ne, sd, raw, abs_hdg=hd, std_hdg=sh)
    return pd.DataFrame(err_rows), pd.DataFrame(spread)


def nominal_distance(spread: pd.DataFrame, prefix: str = "") -> dict:
    """Mean absolute distance of the per-log coverages (every log x lead row, not the pooled
    ``all`` rows) from the Gaussian nominal, at 1 and 2 sigma; ``prefix = "heading_"`` for
    the heading's."""
    per_log = spread[spread.log != "all"]
    return {k: float(np.mean(np.abs(per_log[f"{prefix}coverage_{k}sigma"] - GAUSS_COVERAGE[float(k)])))
            for k in (1, 2)}


def nominal_distance_line(spread: pd.DataFrame) -> str:
    d = nominal_distance(spread)
    n = int((spread.log != "all").sum())
    line = (f"Mean distance of the {n} log x lead coverages from the nominal: north/east {d[2]:.3f} at 2 sigma "
            f"(nominal {GAUSS_COVERAGE[2.0]:.3f}), {d[1]:.3f} at 1 sigma (nominal {GAUSS_COVERAGE[1.0]:.3f})")
    if "heading_coverage_2sigma" in spread:
        h = nominal_distance(spread, "heading_")
        line += f"; heading {h[2]:.3f} and {h[1]:.3f}"
    return line + "."


def worse_cells(errors: pd.DataFrame) -> dict:
    """Reference model -> the number of log x lead x state (distance, heading) cells of
    ``errors`` where the hybrid's mean error is larger than that model's."""
    e = errors.set_index(["model", "log", "lead_s"])[["distance_m", "heading_deg"]]
    h = e.loc["hybrid"]
    return {m: int((h > e.loc[m]).to_numpy().sum()) for m in dict.fromkeys(errors.model) if m != "hybrid"}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=TRUTHSIM, help="folder of logs (default: truthsim-dev)")
    ap.add_argument("--vessel", default="gunnerus")
    ap.add_argument("--every-s", type=float, default=20.0, help="spacing of start times [s]")
    ap.add_argument("--horizon-s", type=float, default=60.0)
    ap.add_argument("--spread-exponent", default="1",
                    help="exponent of the raw spread in the calibrated one: a number in [0, 1] or 'likelihood'")
    ap.add_argument("--station-keeping-spread", default=CalibrationConfig().station_keeping_spread,
                    choices=("held_load", "ensemble"),
                    help="the raw spread calibrated during station keeping (CalibrationConfig.station_keeping_spread; "
                         "default: its default)")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    if not args.data.is_dir():
        if args.data == TRUTHSIM:
            print(f"skipped: {args.data} not found (the shared data sets are not in the repository)",
                  file=sys.stderr)
            return 0
        print(f"error: --data: {args.data} is not a folder", file=sys.stderr)
        return 2
    for flag, val in (("--every-s", args.every_s), ("--horizon-s", args.horizon_s)):
        if not val > 0:
            print(f"error: {flag}: must be > 0 s, got {val:g}", file=sys.stderr)
            return 2
    try:
        exponent = args.spread_exponent if args.spread_exponent == "likelihood" else float(args.spread_exponent)
        calibration = CalibrationConfig(spread_exponent=exponent, station_keeping_spread=args.station_keeping_spread)
    except ValueError:
        print(f"error: --spread-exponent: must be a number in [0, 1] or 'likelihood', got {args.spread_exponent!r}",
              file=sys.stderr)
        return 2
    try:
        vessel = load_vessel(args.vessel)
    except (ValueError, OSError) as err:
        print(f"error: --vessel: {err}", file=sys.stderr)
        return 2
    try:
        files = log_files(args.data)
    except ValueError as err:
        print(f"error: --data: {err}", file=sys.stderr)
        return 2
    if len(files) < 2:
        print(f"error: --data: leave one out needs at least 2 logs, found {len(files)} in {args.data}",
              file=sys.stderr)
        return 2
    logs = {f.name: ingest(f, vessel, purpose="fit") for f in files}
    try:
        errors, spread = run(logs, vessel, args.every_s, args.horizon_s,
                             hybrid_factory=lambda: HybridPredictor(vessel, calibration_config=calibration))
    except NoStationKeeping as err:
        print(f"error: --data / --horizon-s: {err}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    for fname, df in (("errors.csv", errors), ("spread.csv", spread)):
        atomic_write(args.out / fname, lambda fh, df=df: fh.write(df.to_csv(index=False).encode()))
    pooled_err = errors.groupby(["model", "lead_s"], sort=False)[["distance_m", "heading_deg"]].mean().reset_index()
    worse = worse_cells(errors)
    md = (f"{len(logs)} logs of `{args.data.parent.name}/{args.data.name}`, leave one log out; starts every "
          f"{args.every_s:g} s of station keeping, commands held, {args.horizon_s:g}-s forecasts; spread "
          f"exponent {calibration.spread_exponent}"
          + f"; the spread calibrated during station keeping: `{calibration.station_keeping_spread}`.\n\n"
          f"**Mean errors** (the logs' means averaged)\n\n"
          + markdown_table(pooled_err.round(3)) + "\n\nCells (log x lead x distance/heading, of "
          f"{2 * int((errors.model == 'hybrid').sum())}) where the hybrid's mean error is larger than: "
          + ", ".join(f"{m} {n}" for m, n in worse.items()) + "."
          + "\n\n**Spread of the hybrid** (north and east; the `all` rows "
          "pool the starts of every log)\n\n"
          + markdown_table(spread.round(3)) + "\n\n" + nominal_distance_line(spread) + "\n")
    atomic_write(args.out / "station_keeping.md", lambda fh: fh.write(md.encode()))
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
