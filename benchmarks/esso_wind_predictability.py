"""Esso Osaka: how much of the wind's future its own past predicts, on the validation split.

::

    python benchmarks/esso_wind_predictability.py --out out/esso-wind-predictability

Fed the logged future wind (an oracle), the hybrid's 30-s error on the validation runs
falls by about a quarter (``benchmarks/esso_error_sources.py --hybrid``). This script asks
whether a better *causal* wind forecast than the hybrid's could take part of that gain. It
splits the benchmark's training runs again, seed 1, as the other validation scripts do
(the test runs play no part), and forecasts the true-wind vector over 30 s from a start
every second of the validation runs with:

* ``held``: the start sample over the whole horizon (the paper's scheme);
* ``gust``: the hybrid's wind forecast, a gust decaying to the recent mean, fitted on the
  fitting runs' wind (:func:`~hybridship.forecast_inputs.wind.fit_wind_forecast`);
* ``linear``: a linear predictor of the wind at each lead time from its recent history,
  least squares on the fitting runs: the deviations of the start sample and of the
  trailing means over :data:`TRAILING_S` from the gust forecast's mean level, the same
  coefficients for both components (no preferred direction), a linear filter that can
  represent any stable second-order gust spectrum the gust forecast's first-order decay
  cannot;
* ``future_mean`` (non-causal, a bound): the logged mean of the next 30 s held over the
  horizon, the best a forecast of the wind's level could do; what it still misses is the
  turbulence within the horizon.

Writes ``errors.csv`` (``predictor,kind,lead_s,error_m_s,n_starts``: the mean distance
between forecast and logged wind vectors [m/s], over every step of the horizon for
``lead_s = all``) and ``tables.md`` (the tables it prints) to ``--out``, and copies the two
to ``--results`` when given (the folder ``--out`` also holds the split's links to the data,
which stay out of the repository)::

    python benchmarks/esso_wind_predictability.py --out out/esso-wind-predictability \
        --results docs/results/esso-wind-predictability
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: Trailing windows [s] of the linear predictor's features (besides the start sample).
TRAILING_S = (1.0, 3.0, 10.0, 30.0, 60.0, 120.0)
#: Forecast horizon [s] and spacing of the starts [s].
HORIZON_S = 30.0
START_EVERY_S = 1.0
#: Lead times [s] reported besides the mean over the horizon.
LEADS_S = (5.0, 10.0, 20.0, 30.0)


def trailing_means(a, rows: np.ndarray, windows_s) -> np.ndarray:
    """Causal mean wind vectors [m/s] over each of ``windows_s`` before ``rows``, over the
    samples the sensor logged (the wind forecast's own mean): (S, K, 2)."""
    from hybridship.forecast_inputs.wind import trailing_mean_vector

    wind = np.asarray(a.wind, dtype=float)
    logged = getattr(a, "wind_logged", None)
    return np.stack([trailing_mean_vector(wind, a.time_s, rows, w, logged) for w in windows_s], axis=1)


def linear_features(a, rows: np.ndarray, level: np.ndarray) -> np.ndarray:
    """The start sample and the trailing means, as deviations from ``level`` (S, 2): (S, 1 + K, 2) [m/s]."""
    from hybridship.frames import speed_dir_to_vector

    start = speed_dir_to_vector(np.asarray(a.wind, dtype=float)[rows])[:, None]
    return np.concatenate([start, trailing_means(a, rows, TRAILING_S)], axis=1) - level[:, None]


def fit_linear(features: np.ndarray, targets: np.ndarray, ridge: float = 1e-6) -> np.ndarray:
    """Least-squares coefficients (F, H) of ``targets`` (S, H, 2) on ``features`` (S, F, 2), shared by both components."""
    x = np.concatenate([features[..., 0], features[..., 1]])             # (2S, F)
    y = np.concatenate([targets[..., 0], targets[..., 1]])               # (2S, H)
    gram = x.T @ x
    return np.linalg.solve(gram + ridge * np.trace(gram) / len(gram) * np.eye(len(gram)), x.T @ y)


def sample_starts(runs, gust, horizon_steps: int, every: int):
    """Per run: ``(rows, level, features, future)``, the level being the gust forecast's mean [m/s]."""
    from hybridship.forecast_inputs.wind import wind_starts
    from hybridship.frames import speed_dir_to_vector

    out = []
    for a in runs:
        rows, _ = wind_starts(a, horizon_steps, every)
        wind = np.asarray(a.wind, dtype=float)
        level = trailing_means(a, rows, (gust.mean_window_s,))[:, 0]
        level = np.where(np.isfinite(level), level, speed_dir_to_vector(wind[rows]))
        feats = linear_features(a, rows, level)
        feats = np.where(np.isfinite(feats), feats, feats[:, :1])         # a window without logged wind: the start
        future = speed_dir_to_vector(wind[rows[:, None] + np.arange(1, horizon_steps + 1)[None]])
        out.append((rows, level, feats, future))
    return out


def forecasts(a, rows, level, feats, future, gust, coef, horizon_steps: int) -> dict:
    """The four wind forecasts (S, H, 2) [m/s] of one run's starts; step ``j`` is lead ``(j + 1) dt``."""
    from hybridship.frames import speed_dir_to_vector

    wind = np.asarray(a.wind, dtype=float)
    g = speed_dir_to_vector(gust.steps(wind, a.time_s, rows, wind[rows], horizon_steps + 1, a.dt_s,
                                       logged=getattr(a, "wind_logged", None)))
    return {"held": np.broadcast_to(feats[:, :1] + level[:, None], future.shape),
            "gust": g[:, 1:],
            "linear": level[:, None] + np.einsum("sfc,fh->shc", feats, coef),
            "future_mean": np.broadcast_to(future.mean(axis=1, keepdims=True), future.shape)}


def _f3(x: float) -> str:
    return f"{x:.3f}"


def main(argv=None) -> int:
    import pandas as pd

    from _results import check_out, command_line, publish, validation_dirs
    from hybridship.evaluation.manoeuvre import load_runs
    from hybridship.fileio import atomic_write, markdown_table
    from hybridship.forecast_inputs.wind import fit_wind_forecast
    from hybridship.vessel import load_vessel

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", type=Path, default=ROOT / "out" / "esso-osaka" / "split",
                    help="the benchmark's split (default out/esso-osaka/split)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-wind-predictability")
    ap.add_argument("--results", type=Path, help="also copy errors.csv and tables.md here (no data)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    check_out(ap, args.results, option="--results")
    if (dirs := validation_dirs(args.split, args.out / "split")) is None:
        return 2
    fit_dir, val_dir = dirs
    v = load_vessel("esso_osaka_model")
    fit_runs, val_runs = load_runs(fit_dir, v), load_runs(val_dir, v)
    dt = fit_runs[0].arrays.dt_s
    steps, every = int(round(HORIZON_S / dt)), int(round(START_EVERY_S / dt))
    gust, _ = fit_wind_forecast([r.arrays for r in fit_runs], HORIZON_S)
    print(f"gust forecast fitted on the fitting runs: {gust}")
    fitted = sample_starts([r.arrays for r in fit_runs], gust, steps, every)
    coef = fit_linear(np.concatenate([f[2] for f in fitted]),
                      np.concatenate([f[3] - f[1][:, None] for f in fitted]))
    leads = {f"{s:g}": int(round(s / dt)) - 1 for s in LEADS_S}
    records = []
    for r, (rows, level, feats, future) in zip(val_runs, sample_starts([r.arrays for r in val_runs], gust,
                                                                      steps, every)):
        for name, pred in forecasts(r.arrays, rows, level, feats, future, gust, coef, steps).items():
            err = np.hypot(*(pred - future).transpose(2, 0, 1))           # (S, H)
            records.append((name, r.kind, "all", err.sum(), err.size, len(rows)))
            records += [(name, r.kind, k, err[:, j].sum(), len(rows), len(rows)) for k, j in leads.items()]
    df = pd.DataFrame(records, columns=["predictor", "kind", "lead_s", "sum", "count", "n_starts"])
    pooled = df.assign(kind="all")
    table = (pd.concat([df, pooled]).groupby(["predictor", "kind", "lead_s"], sort=False)
             .agg(total=("sum", "sum"), count=("count", "sum"), n_starts=("n_starts", "sum")).reset_index())
    table["n_starts"] = np.where(table["lead_s"] == "all", table["n_starts"], table["count"])
    table["error_m_s"] = table["total"] / table["count"]
    out = table[["predictor", "kind", "lead_s", "error_m_s", "n_starts"]]
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "errors.csv", lambda fh: fh.write(out.to_csv(index=False, float_format="%.4f").encode()))
    wide = out[out["lead_s"] == "all"].pivot(index="predictor", columns="kind", values="error_m_s")
    by_lead = out[out["kind"] == "all"].pivot(index="predictor", columns="lead_s", values="error_m_s")
    order = ["held", "gust", "linear", "future_mean"]
    md = [f"Command: `{command_line('esso_wind_predictability.py', argv)}`", "",
          f"Gust forecast fitted on the fitting runs: `{gust}`.", "",
          "Mean wind-vector error over the 30-s horizon [m/s], validation runs, by kind:", "",
          markdown_table(wide.loc[order].map(_f3).reset_index()), "",
          "Pooled, by lead time [s] (`all`: every step of the horizon):", "",
          markdown_table(by_lead.loc[order, ["all", *leads]].map(_f3).reset_index()), "",
          f"Linear predictor's coefficients at 10 and 30 s (start sample, trailing means over "
          f"{', '.join(f'{s:g}' for s in TRAILING_S)} s):", "",
          markdown_table(pd.DataFrame(coef[:, [leads["10"], leads["30"]]].T,
                                      columns=["start", *(f"{s:g} s" for s in TRAILING_S)]).map(_f3)
                         .assign(lead_s=["10", "30"]).set_index("lead_s").reset_index())]
    text = "\n".join(md) + "\n"
    atomic_write(args.out / "tables.md", lambda fh: fh.write(text.encode()))
    publish(args.out, args.results, ("errors.csv", "tables.md"))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
