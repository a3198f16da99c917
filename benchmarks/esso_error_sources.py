"""Esso Osaka: where the physics' forecast error comes from, on the validation split.

::

    python benchmarks/esso_error_sources.py --out out/esso-error-sources

splits the benchmark's *training* runs (``out/esso-osaka/split/train``) again, seed 1, as
``benchmarks/esso_multistep.py`` does (the test runs play no part), and forecasts the
validation runs with the physics alone (commands known) under changed inputs:

* ``lead<s>``: the logged ``u`` and ``vm`` shifted ``s`` seconds earlier (they lag the
  positions by about 0.6 s; non-causal, an upper bound of what a better start velocity
  could give);
* ``wind_zero``: no wind; ``wind_trail<s>``: the wind vector averaged over the last ``s``
  seconds (causal) in place of the last sample;
* ``wind_forecast``: the hybrid's wind forecast (a gust decaying to the recent mean,
  :mod:`hybridship.forecast_inputs.wind`), fitted on the fitting runs' wind (causal);
* ``wind_future``: the logged wind of every step after the start (non-causal: how much of
  the physics' error the wind's unknown future makes).

Writes ``errors.csv`` (the manoeuvre benchmark's columns) and prints the distance and
heading tables.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def trailing_wind(wind: np.ndarray, n: int) -> np.ndarray:
    """Causal mean over ``n`` samples of the wind vector; ``wind`` (N, 2): speed [m/s], direction [rad]."""
    from hybridship.frames import speed_dir_to_vector, vector_to_speed_dir

    vec = speed_dir_to_vector(wind)

    def mean(z):
        return np.convolve(np.r_[np.full(n - 1, z[0]), z], np.ones(n) / n, mode="valid")

    return vector_to_speed_dir(np.column_stack([mean(vec[:, 0]), mean(vec[:, 1])]))


def _future_wind_predictor():
    """The physics fed the logged wind of every step after the start (a non-causal oracle)."""
    import dataclasses

    from hybridship.predictors import DynamicPredictor
    from hybridship.predictors.forecast_setup import _forecast_setup
    from hybridship.predictors.result import ForecastResult

    class FutureWind(DynamicPredictor):
        name = "wind_future"

        def forecast(self, log, start_times_s, horizon_s=60.0, *, commands="held"):
            st = _forecast_setup(self.model, self.residual_config, log, start_times_s, horizon_s,
                                 self.stop_after_failure, commands)
            rows = st.idx[:, None] + np.arange(st.H)[None, :]
            wind = np.ascontiguousarray(st.arrays.wind[np.minimum(rows, len(st.arrays.time_s) - 1)])
            st = dataclasses.replace(st, wind=wind)
            res = self.model.rollout(st.eta0, st.nu0, st.H, dt_s=st.dt, substeps=st.substeps, rpm=st.rpm,
                                     azimuth_rad=st.az, wind=st.wind)
            return ForecastResult(st.arrays.time_s[st.idx], res.time_s, res.eta, res.nu)

    return FutureWind


def main(argv=None) -> int:
    from hybridship.datasets.esso_osaka import esso_log_arrays
    from hybridship.evaluation.manoeuvre import (ManoeuvreConfig, Run, error_table, forecast_errors, load_runs,
                                                 split_runs, start_rows)
    from hybridship.fileio import atomic_write
    from hybridship.forecast_inputs.wind import fit_wind_forecast
    from hybridship.logs.ingest import ingest
    from hybridship.predictors import DynamicPredictor
    from hybridship.vessel import load_vessel

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", type=Path, default=ROOT / "out" / "esso-osaka" / "split",
                    help="the benchmark's split (default out/esso-osaka/split)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-error-sources")
    args = ap.parse_args(argv)
    if not (args.split / "train").is_dir():
        print(f"error: {args.split / 'train'}: not found; run benchmarks/esso_osaka.py first", file=sys.stderr)
        return 2
    fit_dir, val_dir = split_runs(args.split / "train", args.out / "split", seed=1)
    v = load_vessel("esso_osaka_model")
    cfg = ManoeuvreConfig()
    runs = load_runs(val_dir, v)
    p = DynamicPredictor(v, residual_config=cfg.residual)
    FutureWind = _future_wind_predictor()
    horizons = (5.0, 10.0, 20.0, 30.0)
    steps = np.array([int(round(h / runs[0].arrays.dt_s)) for h in horizons])

    def score(rr, p=p):
        return [forecast_errors(lambda a, st, h: p.forecast(a, st, horizon_s=h, commands="known"), r.arrays,
                                start_rows(r.arrays, int(steps.max()), cfg.start_every_s), steps) for r in rr]

    def with_wind(fn):
        return [Run(r.run, dataclasses.replace(r.arrays, wind=fn(r.arrays.wind))) for r in runs]

    per = {("as_logged", "known"): score(runs)}
    for lead in (0.3, 0.6):
        per[(f"lead{lead:g}", "known")] = score([Run(r.run, ingest(esso_log_arrays(r.run.path, v, velocity_lead_s=lead),
                                                                   v, purpose="fit")) for r in runs])
    per[("wind_zero", "known")] = score(with_wind(lambda w: np.column_stack([np.zeros(len(w)), w[:, 1]])))
    wf, _ = fit_wind_forecast([r.arrays for r in load_runs(fit_dir, v)], max(horizons))
    print(f"wind forecast fitted on the fitting runs: {wf}")
    per[("wind_forecast", "known")] = score(runs, DynamicPredictor(v, residual_config=cfg.residual, wind_forecast=wf))
    per[("wind_future", "known")] = score(runs, FutureWind(v, residual_config=cfg.residual))
    for secs in (10, 30, 60):
        n = int(round(secs / runs[0].arrays.dt_s))
        per[(f"wind_trail{secs}", "known")] = score(with_wind(lambda w, n=n: trailing_wind(w, n)))
    errors = error_table(per, runs, horizons)
    atomic_write(args.out / "errors.csv", lambda fh: fh.write(errors.to_csv(index=False).encode()))
    for state in ("distance_m", "heading_deg"):
        d = errors[errors.state == state].pivot_table(index=["kind", "model"], columns="horizon_s", values="mae",
                                                      sort=False)
        print(f"{state}:\n{d.round(3).to_string()}")
    print(f"wrote {args.out / 'errors.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
