"""Spread coverage of forecasts started early and late in a drift, leave one log out.

For each truthsim-dev log: a hybrid with the default settings (``--members`` members, seed 0)
is fitted on the other five logs (its spread after a failure calibrated, as ``fit`` does, on
their failures' first 20 samples), then forecasts 60 s ahead on the held-out log from

* ``first 20 s``: the first 20 samples after the failure (the starts the calibration and
  the drift tables use);
* ``20 s and later``: every 10 s from 20 s after the failure to the last start with 60 s of
  log after it.

Later starts are scored twice: with the calibration ``fit`` makes for them on the other
logs' later starts (``after_stop_late``, the default since 2026-11-29), and with the first
starts' calibration alone (``after_stop`` only, as before). Prints (and with ``--out``
writes) per log and pooled, at 60 s: the share of the logged north/east positions (pooled)
and headings inside the calibrated 2-sigma band, the mean 1-sigma band and the
root-mean-square error [m], and how many starts carry the note that they lie beyond the
calibrated starts. A second table gives the later starts' 60-s mean absolute errors in north,
east [m] and heading [deg] for the hybrid, the physics alone and dead reckoning (pooled: the
mean over all later starts). A third gives the same, pooled, at every lead of
:data:`HORIZONS_S` (15, 30, 45 and 60 s), with the hybrid's 2-sigma coverage there: a
forecast that helps at 60 s but not at 15 s would show there.

Usage: ``python benchmarks/drift_late_coverage.py [--members N] [--station-keeping-walks] [--out FILE]``
(about ten minutes on one core with the default 10 members); the page's table:
``--out docs/results/drift-late-coverage/drift_late_coverage.md``, and with the estimator
before 2026-11-30 (the station keeping's load walks through the drift too)
``--station-keeping-walks --out docs/results/drift-late-coverage/station_keeping_walks.md``.
"""

from __future__ import annotations

import argparse
import copy
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out
from hybridship.fileio import markdown_table, write_text
from hybridship.frames import wrap_pi
from hybridship.predictors import DeadReckoning, DynamicPredictor, HybridPredictor
from hybridship.predictors.hybrid import AFTER_STOP_LATE
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import EnvironmentConfig

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_DATA = ROOT.parent / "shared" / "data" / "truthsim-dev" / "logs"
HORIZON_S = 60.0
#: Leads of the by-horizon table [s] (the drift tables' columns).
HORIZONS_S = (15.0, 30.0, 45.0, 60.0)
LATE_EVERY_S = 10.0
#: The counts the written text spells out (larger ones in digits).
COUNT_WORDS = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten")


def starts_after_failure(log: pd.DataFrame) -> dict[str, list[float]]:
    """The two groups of start times [s] after the log's first failure."""
    t, dp = log.time_s.to_numpy(float), log.dp_active.to_numpy()
    b = int(np.argmax(dp == 0))
    late = np.arange(t[b] + 20.0, t[-1] - HORIZON_S + 1e-9, LATE_EVERY_S)
    return {"first 20 s": [float(x) for x in t[b:b + 20]], "20 s and later": [float(x) for x in late]}


def truth_rows(log: pd.DataFrame, starts: list[float], lead_s: float = HORIZON_S) -> np.ndarray:
    """The rows of ``log`` logged ``lead_s`` [s] after each of ``starts`` [s]; a start without
    one (a gap in the log there) is refused rather than scored against a later row."""
    t = np.round(log.time_s.to_numpy(), 6)
    want = np.round(np.asarray(starts, dtype=float) + lead_s, 6)
    rows = np.minimum(np.searchsorted(t, want), len(t) - 1)
    missing = t[rows] != want
    if missing.any():
        raise ValueError(f"log: no sample at {want[missing][0]:g} s, {lead_s:g} s after a start")
    return rows


def score(hp, log: pd.DataFrame, starts: list[float]) -> dict:
    """Coverage, band and error at 60 s of ``hp``'s forecasts from ``starts`` on ``log``."""
    fc = hp.forecast(log, starts, HORIZON_S)
    rows = truth_rows(log, starts)
    ne = fc.eta[:, -1, :2] - log[["north_m", "east_m"]].to_numpy()[rows]
    dpsi = np.abs(wrap_pi(fc.eta[:, -1, 2] - np.radians(log.heading_deg.to_numpy()[rows])))
    sd = fc.eta_std[:, -1, :]
    return {"starts": len(starts),
            "north/east in 2 sigma": float(np.mean(np.abs(ne) <= 2 * sd[:, :2])),
            "heading in 2 sigma": float(np.mean(dpsi <= 2 * sd[:, 2])),
            "mean 1-sigma [m]": float(sd[:, :2].mean()), "RMS error [m]": float(np.sqrt(np.mean(ne ** 2))),
            "noted as late": int(sum("within 20 s of a failure" in n for n in fc.notes))}


def _environment_config(station_keeping_walks: bool) -> EnvironmentConfig:
    """The default estimator's settings, or with the station keeping's load walks after a stop too."""
    c = EnvironmentConfig()
    if not station_keeping_walks:
        return c
    return EnvironmentConfig(load_walk_after_stop_m_s2=c.load_walk_m_s2,
                             load_yaw_walk_after_stop_rad_s2=c.load_yaw_walk_rad_s2)


def late_errors(models: dict, log: pd.DataFrame, starts: list[float]) -> dict:
    """The absolute errors (starts, len(HORIZONS_S), 3) [m, m, deg] of each of ``models`` (name
    -> predictor) from ``starts`` on ``log`` at the leads :data:`HORIZONS_S`: north, east and the
    wrapped heading; and, under ``"<name> in 2 sigma"``, (starts, len(HORIZONS_S), 3) whether
    each error lies inside the forecast's 2-sigma band (for a model that reports a spread)."""
    rows = np.stack([truth_rows(log, starts, h) for h in HORIZONS_S], axis=1)            # (S, H)
    truth = log[["north_m", "east_m"]].to_numpy()[rows]
    psi = np.radians(log.heading_deg.to_numpy()[rows])
    out = {}
    for name, model in models.items():
        fc = model.forecast(log, starts, HORIZON_S)
        lead = np.round(np.asarray(HORIZONS_S) / (HORIZON_S / (fc.eta.shape[1] - 1))).astype(int)
        eta = fc.eta[:, lead]
        err = np.concatenate([eta[..., :2] - truth, wrap_pi(eta[..., 2:] - psi[..., None])], axis=-1)
        out[name] = np.concatenate([np.abs(err[..., :2]), np.degrees(np.abs(err[..., 2:]))], axis=-1)
        if fc.eta_std is not None and np.any(fc.eta_std > 0):
            out[f"{name} in 2 sigma"] = np.abs(err) <= 2 * fc.eta_std[:, lead]
    return out


def error_table(errors: dict) -> pd.DataFrame:
    """Per log (and pooled over all starts) the 60-s mean of :func:`late_errors`: columns
    ``<model> north_m / east_m / yaw_deg``."""
    names = [m for m in next(iter(errors.values())) if not m.endswith(" in 2 sigma")]
    pooled = {m: np.concatenate([e[m] for e in errors.values()]) for m in names}
    rows = []
    for log, errs in {**errors, "pooled": pooled}.items():
        row = {"log": log, "starts": len(errs[names[0]])}
        for m in names:
            row[f"{m} north/east/heading"] = "/".join(f"{x:.2f}" for x in errs[m][:, -1].mean(axis=0))
        rows.append(row)
    return pd.DataFrame(rows)


def horizon_table(errors: dict) -> pd.DataFrame:
    """Pooled over every log's later starts, per lead of :data:`HORIZONS_S`: the mean absolute
    error ``north / east [m] / heading [deg]`` of each model and the hybrid's 2-sigma coverage
    (north and east pooled, heading)."""
    keys = list(next(iter(errors.values())))
    pooled = {m: np.concatenate([e[m] for e in errors.values()]) for m in keys}
    rows = []
    for j, h in enumerate(HORIZONS_S):
        row = {"lead [s]": f"{h:g}"}
        for m in keys:
            if m.endswith(" in 2 sigma"):
                inside = pooled[m][:, j]
                row[f"{m} (north/east, heading)"] = f"{inside[:, :2].mean():.2f}, {inside[:, 2].mean():.2f}"
            else:
                row[f"{m} north/east/heading"] = "/".join(f"{x:.2f}" for x in pooled[m][:, j].mean(axis=0))
        rows.append(row)
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA, help="folder of truthsim-dev logs")
    ap.add_argument("--members", type=int, default=10, help="ensemble members (default 10, the default)")
    ap.add_argument("--out", type=Path, default=None, help="also write the table to this Markdown file")
    ap.add_argument("--station-keeping-walks", action="store_true",
                    help="filter the drift with the station keeping's load walks (the estimator before 2026-11-30)")
    args = ap.parse_args(argv)
    check_out(ap, args.out, file=True)
    if args.members < 1:        # EnsembleConfig's traceback came after the logs were read
        ap.error(f"--members: expected a positive integer, got {args.members}")
    files = sorted(args.data.glob("*.csv.gz")) if args.data.is_dir() else []
    if not files:
        print(f"no logs found in {args.data}; nothing to do", file=sys.stderr)
        return 1
    if len(files) < 2:          # the hybrid was fitted on no log: fit()'s traceback after the logs were read
        print(f"error: --data: leave one log out needs at least 2 logs, found 1 in {args.data}", file=sys.stderr)
        return 2
    logs = {f.name.split("_seed")[0]: pd.read_csv(f) for f in files}
    rows, errors = [], {}
    baselines = {"physics": DynamicPredictor("gunnerus").fit(), "dead_reckoning": DeadReckoning("gunnerus").fit()}
    for name, log in logs.items():
        hp = HybridPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=args.members, seed=0),
                             environment_config=_environment_config(args.station_keeping_walks))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")         # the logs' fault notes are not the point here
            hp.fit([other for n, other in logs.items() if n != name])
            early_only = copy.copy(hp)          # the same fit, without the later starts' calibration
            early_only.calibration = {k: v for k, v in hp.calibration.items() if k != AFTER_STOP_LATE}
            groups = starts_after_failure(log)
            for group, model, starts in (("first 20 s", hp, groups["first 20 s"]),
                                         ("20 s and later", hp, groups["20 s and later"]),
                                         ("20 s and later, first starts' calibration", early_only,
                                          groups["20 s and later"])):
                rows.append({"log": name, "starts after the failure": group, **score(model, log, starts)})
                print(rows[-1], flush=True)
            errors[name] = late_errors({"hybrid": hp, **baselines}, log, groups["20 s and later"])
    res = pd.DataFrame(rows)
    for group, g in res.groupby("starts after the failure", sort=False):
        w = g["starts"].to_numpy(float)
        pooled = {"log": "pooled", "starts after the failure": group, "starts": int(w.sum())}
        for col in ("north/east in 2 sigma", "heading in 2 sigma", "mean 1-sigma [m]"):
            pooled[col] = float(np.average(g[col], weights=w))
        pooled["RMS error [m]"] = float(np.sqrt(np.average(g["RMS error [m]"] ** 2, weights=w)))
        pooled["noted as late"] = int(g["noted as late"].sum())
        res = pd.concat([res, pd.DataFrame([pooled])], ignore_index=True)
    res = res.round({"north/east in 2 sigma": 2, "heading in 2 sigma": 2, "mean 1-sigma [m]": 2, "RMS error [m]": 2})
    others = COUNT_WORDS[len(logs) - 1] if len(logs) <= len(COUNT_WORDS) else len(logs) - 1
    text = (f"60-s forecasts after the failure of each truthsim-dev log, the hybrid fitted on the other {others} "
            f"({args.members} members); nominal 2-sigma coverage 0.954:\n\n" + markdown_table(res) + "\n\n"
            "Mean absolute 60-s error of the starts 20 s and later after the failure, north / east [m] / "
            "heading [deg]:\n\n" + markdown_table(error_table(errors)) + "\n\n"
            "The same starts pooled over the logs at each lead, with the hybrid's 2-sigma coverage "
            "(nominal 0.954):\n\n" + markdown_table(horizon_table(errors)) + "\n")
    print(text)
    if args.out is not None:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
