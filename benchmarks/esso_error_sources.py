"""Esso Osaka: where the physics' forecast error comes from, on the validation split.

::

    python benchmarks/esso_error_sources.py --out out/esso-error-sources

splits the benchmark's *training* runs (``out/esso-osaka/split/train``) again, seed 1, as
``benchmarks/esso_multistep.py`` does (the test runs play no part), and forecasts the
validation runs with the physics alone (commands known) under changed inputs:

* ``lead<s>``: the logged ``u`` and ``vm`` shifted ``s`` seconds earlier (they lag the
  positions by about 0.6 s; non-causal, an upper bound of what a better start velocity
  could give);
* ``r_fit<s>``: the start yaw rate from a quadratic fit of the logged heading over the
  last ``s`` seconds (causal; its slope at the start) in place of the logged yaw rate, and
  ``r_heading``: from a centred 4-s Savitzky-Golay fit (non-causal): whether the logged yaw
  rate, which is not quite the heading's rate, is the right start;
* ``wind_zero``: no wind; ``wind_trail<s>``: the wind vector averaged over the last ``s``
  seconds (causal) in place of the last sample;
* ``wind_forecast``: the hybrid's wind forecast (a gust decaying to the recent mean,
  :mod:`hybridship.forecast_inputs.wind`), fitted on the fitting runs' wind (causal);
* ``wind_future``: the logged wind of every step after the start (non-causal: how much of
  the physics' error the wind's unknown future makes);
* ``wind_future_mean``: the mean of that logged wind over the horizon, held (non-causal: a
  perfect forecast of the wind's level without its gusts; how much of that error a better
  forecast of the level could remove).

With ``--hybrid`` the benchmark's hybrid (:func:`~hybridship.evaluation.manoeuvre.make_predictors`,
calibrated over 30 s) is also fitted on the fitting runs (about 3 min) and scored as
``hybrid`` (its fitted wind forecast), ``hybrid_wind_future`` (the same nets fed the
logged wind of every step after the start: how much of the hybrid's own error the wind's
unknown future makes), ``hybrid_wind_future_mean`` (the same nets fed the logged mean
wind over the horizon: how much of that a perfect forecast of the wind's level would take)
and ``hybrid_wind_sampled`` (causal: the mean of 8 forecasts, each
with the wind forecast plus the error path of the wind forecast from a random start of the
fitting runs, heading averaged on the circle: whether averaging over plausible wind
futures, rather than forecasting at the expected wind, lowers the error) and
``hybrid_error_feedback`` (causal: each forecast corrected by ``alpha (tau / 30 s)^2`` times
the error that the forecast started 30 s earlier made at its 30-s lead, known at the start,
turned with the heading since then; ``alpha`` chosen from :data:`FEEDBACK_ALPHAS` on the
held-back ends of the fitting runs, which the nets did not train on: whether the hybrid's
error persists from one forecast to the next) and ``hybrid_scaled<w>`` (the physics'
forecast plus ``w`` times the hybrid's correction to it, heading on the circle, for ``w``
in :data:`CORRECTION_SCALES`; a diagnostic, not a causal choice: whether the nets correct
too little or too much). With ``--seed-average`` also
``hybrid_seed1`` (the same hybrid fitted with seed 1: a second fit, as long as the first) and
``hybrid_seed_mean`` (the mean of the two hybrids' forecasts, heading on the circle:
whether the hybrid's error is the variance of its fit, which averaging independent fits
would lower, or a bias they share). With ``--structure-average`` also hybrids of another
structure, each alone and averaged with the benchmark's forecast by forecast (heading on
the circle): ``hybrid_one_step`` (the nets without the multi-step fine-tuning) and
``hybrid_hull`` (the linear MMG-structured hull correction before the nets, fitted free-run
and tuned with them: ``hull_correction``, ``hull_fit="multi_step"``, ``tune_hull``), and
``hybrid_mean_one_step`` and ``hybrid_mean_hull``: whether models whose errors differ more
than two seeds' do average to a lower error.

Writes ``errors.csv`` (the manoeuvre benchmark's columns) and ``tables.md`` (:func:`tables`:
the pooled errors, each row as a ratio to the physics, per kind at 30 s, and the share of
the 30-s error that the wind's future makes) to ``--out`` and prints them; ``--results``
also copies the two there (``--out`` holds the split's links to the data, which stay out
of the repository). The committed run::

    python benchmarks/esso_error_sources.py --hybrid --seed-average --structure-average \
        --out out/esso-error-sources --results docs/results/esso-error-sources
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
from scipy.signal import savgol_filter

ROOT = Path(__file__).resolve().parents[1]


def trailing_wind(wind: np.ndarray, n: int) -> np.ndarray:
    """Causal mean over ``n`` samples of the wind vector; ``wind`` (N, 2): speed [m/s], direction [rad]."""
    from hybridship.frames import speed_dir_to_vector, vector_to_speed_dir

    vec = speed_dir_to_vector(wind)

    def mean(z):
        return np.convolve(np.r_[np.full(n - 1, z[0]), z], np.ones(n) / n, mode="valid")

    return vector_to_speed_dir(np.column_stack([mean(vec[:, 0]), mean(vec[:, 1])]))


def _logged_future_wind():
    """A wind "forecast" that is the logged wind of every step after the start (a non-causal oracle)."""
    from hybridship.forecast_inputs.wind import WindForecast

    class LoggedFutureWind(WindForecast):
        def steps(self, wind, time_s, rows, start_wind, n_steps, dt_s, *, logged=None, hold=None):
            idx = np.asarray(rows, dtype=int)[:, None] + np.arange(n_steps)[None, :]
            return np.ascontiguousarray(wind[np.minimum(idx, len(wind) - 1)])

    # a time constant of 0 marks it as not held; the one-sample mean window reads no history
    return LoggedFutureWind(mean_window_s=0.1, time_constant_s=0.0)


def _logged_future_mean_wind():
    """A wind "forecast" that holds the mean of the logged wind vector over the forecast's
    steps (a non-causal oracle: a perfect forecast of the wind's level, none of its gusts)."""
    from hybridship.forecast_inputs.wind import WindForecast
    from hybridship.frames import speed_dir_to_vector, vector_to_speed_dir

    class LoggedFutureMeanWind(WindForecast):
        def steps(self, wind, time_s, rows, start_wind, n_steps, dt_s, *, logged=None, hold=None):
            idx = np.asarray(rows, dtype=int)[:, None] + np.arange(n_steps)[None, :]
            mean = speed_dir_to_vector(wind[np.minimum(idx, len(wind) - 1)]).mean(axis=1)
            return np.ascontiguousarray(np.repeat(vector_to_speed_dir(mean)[:, None], n_steps, axis=1))

    return LoggedFutureMeanWind(mean_window_s=0.1, time_constant_s=0.0)


def _sampled_wind(forecast, logs, horizon_steps: int, seed: int = 0, every: int = 20):
    """The wind forecast ``forecast`` plus, per start, one of its error paths in ``logs``
    (:func:`~hybridship.forecast_inputs.wind.wind_error_paths`), drawn at random: one draw
    of a plausible future."""
    from hybridship.forecast_inputs.wind import WindForecast, wind_error_paths
    from hybridship.frames import speed_dir_to_vector, vector_to_speed_dir

    paths = wind_error_paths(forecast, logs, horizon_steps, every=every).copy()
    if len(paths) == 0:
        raise ValueError(f"no start in the logs has {horizon_steps} steps of logged wind after it")
    paths[:, 0] = 0.0                    # the first step keeps the start value
    rng = np.random.default_rng(seed)

    class SampledWind(WindForecast):
        def steps(self, wind, time_s, rows, start_wind, n_steps, dt_s, *, logged=None, hold=None):
            base = forecast.steps(wind, time_s, rows, start_wind, n_steps, dt_s, logged=logged, hold=hold)
            draw = paths[rng.integers(0, len(paths), len(rows)), :n_steps]
            return np.ascontiguousarray(vector_to_speed_dir(speed_dir_to_vector(base) + draw))

    return SampledWind(mean_window_s=forecast.mean_window_s, time_constant_s=forecast.time_constant_s)


def _mean_forecast(predictors, n: int = 1):
    """A forecaster that averages ``n`` forecasts of each of ``predictors`` (one predictor or
    a list; heading on the circle): ``n`` calls of each predictor, each call with its own
    draws (a forecast takes each start time once, so the copies cannot share a batch)."""
    from hybridship.predictors.result import ForecastResult

    predictors = predictors if isinstance(predictors, (list, tuple)) else [predictors]

    def forecast(a, start_times_s, horizon_s, **kw):
        st = np.asarray(start_times_s, dtype=float)
        fcs = [p.forecast(a, st, horizon_s=horizon_s, **kw) for p in predictors for _ in range(n)]
        eta = np.stack([fc.eta for fc in fcs])
        nu = np.stack([fc.nu for fc in fcs])
        mean = eta.mean(axis=0)
        mean[..., 2] = np.arctan2(np.sin(eta[..., 2]).mean(axis=0), np.cos(eta[..., 2]).mean(axis=0))
        return ForecastResult(st, fcs[0].lead_s, mean, nu.mean(axis=0))

    return forecast


#: Candidate gains of the error feedback (``hybrid_error_feedback``); 0 is no feedback.
FEEDBACK_ALPHAS = (0.0, 0.1, 0.2, 0.3, 0.5)


def _error_feedback(predictor, alpha: float, lag_s: float = 30.0):
    """A forecaster that adds to ``predictor``'s forecast ``alpha (tau / lag_s)^2`` times the
    error of its forecast started ``lag_s`` earlier at lead ``lag_s`` (measured minus forecast
    north, east and heading at the start, known then), the position error turned by the heading
    change since that start. Starts with no forecast ``lag_s`` before them in the log keep the
    plain forecast. The shape ``tau^2`` is that of a constant acceleration error."""
    from hybridship.frames import body_to_ned, wrap_pi
    from hybridship.predictors.result import ForecastResult

    def forecast(a, start_times_s, horizon_s, **kw):
        st = np.asarray(start_times_s, dtype=float)
        fc = predictor.forecast(a, st, horizon_s=horizon_s, **kw)
        eta = fc.eta.copy()
        earlier = st - lag_s
        has = earlier >= a.time_s[0]
        if alpha and has.any():
            prev = predictor.forecast(a, earlier[has], horizon_s=lag_s, **kw)
            rows = np.searchsorted(a.time_s, st[has])
            err = a.eta[rows] - prev.eta[:, -1]
            err[:, 2] = wrap_pi(err[:, 2])
            # the miss seen from the earlier start, turned with the heading since then
            err = body_to_ned(err, wrap_pi(a.eta[rows, 2] - prev.eta[:, 0, 2]))
            shape = alpha * (fc.lead_s / lag_s) ** 2
            eta[has] += shape[None, :, None] * err[:, None, :]
            eta[..., 2] = wrap_pi(eta[..., 2])
        return ForecastResult(st, fc.lead_s, eta, fc.nu)

    return forecast


#: Scales of the hybrid's correction to the physics (``hybrid_scaled<w>``).
CORRECTION_SCALES = (0.8, 1.2, 1.5)


def _scaled_correction(hybrid, physics, scale: float):
    """A forecaster: ``physics`` plus ``scale`` times (``hybrid`` minus ``physics``), the
    heading difference wrapped (``scale`` 1 is the hybrid, 0 the physics)."""
    from hybridship.frames import wrap_pi
    from hybridship.predictors.result import ForecastResult

    def forecast(a, start_times_s, horizon_s, **kw):
        h = hybrid.forecast(a, start_times_s, horizon_s=horizon_s, **kw)
        p = physics.forecast(a, start_times_s, horizon_s=horizon_s, **kw)
        d = h.eta - p.eta
        d[..., 2] = wrap_pi(d[..., 2])
        eta = p.eta + scale * d
        eta[..., 2] = wrap_pi(eta[..., 2])
        return ForecastResult(h.start_time_s, h.lead_s, eta, p.nu + scale * (h.nu - p.nu))

    return forecast


def heading_fit_rate(time_s: np.ndarray, psi_rad: np.ndarray, window_s: float) -> np.ndarray:
    """Yaw rate [rad/s] at each row from a least-squares quadratic fit of the unwrapped heading
    over the last ``window_s`` seconds (causal; the fit's slope at the row), on a uniformly
    sampled log (step: the median spacing of ``time_s`` [s]). It is a fixed filter, the
    Savitzky-Golay derivative at the window's last point; the first rows, without a whole
    window behind them, are NaN (callers keep the logged yaw rate there)."""
    from numpy.lib.stride_tricks import sliding_window_view
    from scipy.signal import savgol_coeffs

    psi = np.unwrap(psi_rad)
    dt = float(np.median(np.diff(time_s)))
    k = max(3, int(round(window_s / dt)))
    out = np.full(len(time_s), np.nan)
    if len(psi) >= k:
        out[k - 1:] = sliding_window_view(psi, k) @ savgol_coeffs(k, 2, deriv=1, delta=dt, pos=k - 1, use="dot")
    return out


def held_back_errors(predictor, logs, steps: np.ndarray, start_every_s: float, make, skip_s: float = 0.0):
    """The errors ``(S, n_horizons, 4)`` (:func:`~hybridship.evaluation.manoeuvre.forecast_errors`,
    logged commands known) of the forecaster ``make(arrays, cut)`` on the held-back end of
    each of ``logs`` (the rows from ``cut``, which the nets did not train on; the first start
    ``skip_s`` after it), one start every ``start_every_s``."""
    from hybridship.evaluation.manoeuvre import forecast_errors

    dp_only = bool(predictor.training_info["calibration"]["dp_only"])
    errs = []
    for a in logs:
        cut = predictor._calibration_cut(a, predictor.calibration_config, dp_only)
        dt = float(np.median(np.diff(a.time_s)))
        first = cut + int(round(skip_s / dt))
        rows = np.arange(first, len(a.time_s) - int(steps.max()), max(1, int(round(start_every_s / dt))))
        if rows.size:
            fc = make(a, cut)
            errs.append(forecast_errors(lambda x, st, h: fc(x, st, h, commands="known"), a, rows, steps))
    return np.concatenate(errs)


def _choose_feedback(predictor, logs, steps: np.ndarray, start_every_s: float, lag_s: float = 30.0):
    """The :data:`FEEDBACK_ALPHAS` gain with the lowest mean distance error at the longest lead,
    scored on the held-back end of each log (the rows the nets did not train on, starting at
    least ``lag_s`` into it, so that the earlier forecast is held back too). Returns
    ``(alpha, {alpha: (distance [m], heading [deg])})``."""
    scores = {}
    for alpha in FEEDBACK_ALPHAS:
        fb = _error_feedback(predictor, alpha, lag_s)
        e = held_back_errors(predictor, logs, steps, start_every_s, lambda a, cut: fb, lag_s)[:, -1]
        scores[alpha] = (float(e[:, 3].mean()), float(e[:, 2].mean()))
    return min(scores, key=lambda k: scores[k][0]), scores


def _tables_only(out: Path, results: Path | None) -> int:
    """Render ``out/tables.md`` again from ``out/errors.csv``, with the command of the run that
    wrote them (its first line), so that a change of the tables needs no new run."""
    from _results import tables_again

    return tables_again(out, results, ["errors.csv"], tables, ("errors.csv", "tables.md"))


#: Pairs (model, the same model fed the logged future wind) whose 30-s errors give the
#: share of the error that the wind's unknown future makes.
WIND_SHARES = (("as_logged", "wind_future", "wind_future_mean"),
               ("hybrid", "hybrid_wind_future", "hybrid_wind_future_mean"))


def tables(errors, command: str) -> str:
    """``tables.md``: the pooled errors at every horizon with the 30-s ratios to the physics
    (``as_logged``), the 30-s distance per kind as a ratio to the physics of the same runs,
    the 30-s errors per kind, and the share of the 30-s error that the logged future wind,
    and its mean held, remove."""
    import pandas as pd

    from _results import kind_table
    from hybridship.fileio import markdown_table

    e = errors[errors["commands"] == "known"]
    at30 = e[e["horizon_s"] == 30.0].pivot_table(index="model", columns=["state", "kind"], values="mae", sort=False)
    models = list(dict.fromkeys(e["model"]))
    pooled = e[e["kind"] == "all"].pivot_table(index="model", columns=["state", "horizon_s"], values="mae",
                                               sort=False).loc[models]
    ref = at30.loc["as_logged"]
    rows = [[m, *(f"{pooled.loc[m, ('distance_m', h)]:.3f}" for h in (5.0, 10.0, 20.0, 30.0)),
             f"{pooled.loc[m, ('heading_deg', 30.0)]:.2f}",
             f"{at30.loc[m, ('distance_m', 'all')] / ref[('distance_m', 'all')]:.2f}",
             f"{at30.loc[m, ('heading_deg', 'all')] / ref[('heading_deg', 'all')]:.2f}"] for m in models]
    pooled_md = markdown_table(pd.DataFrame(rows, columns=["model", "5 s (m)", "10 s (m)", "20 s (m)", "30 s (m)",
                                                           "heading 30 s (deg)", "30-s distance / physics",
                                                           "30-s heading / physics"]))
    kinds = [k for k in dict.fromkeys(e["kind"]) if k != "all"]
    per_kind = pd.DataFrame([[m, *(f"{at30.loc[m, ('distance_m', k)] / ref[('distance_m', k)]:.2f}" for k in kinds)]
                             for m in models], columns=["model", *kinds])
    physics = pd.DataFrame([["as_logged (m)", *(f"{ref[('distance_m', k)]:.3f}" for k in kinds)]],
                           columns=["model", *kinds])
    shares = []
    for base, future, level in WIND_SHARES:
        if base in at30.index and future in at30.index:
            for state in ("distance_m", "heading_deg"):
                b, f, lv = (at30.loc[x, (state, "all")] for x in (base, future, level))
                shares.append([base, state, f"{1.0 - f / b:.0%}", f"{1.0 - lv / b:.0%}", f"{(b - lv) / (b - f):.0%}"])
    share_md = markdown_table(pd.DataFrame(shares, columns=[
        "model", "state", "removed by the logged future wind", "removed by its 30-s mean held",
        "the mean's part of the future wind's gain"]))
    md = [f"Command: `{command}`", "", "Validation runs, logged commands known. Pooled mean distance error, the "
          "heading error at 30 s, and the 30-s errors as ratios to the physics with the logged wind (`as_logged`):",
          "", pooled_md, "", "30-s distance per kind as a ratio to `as_logged` on the same runs:", "",
          markdown_table(pd.concat([physics, per_kind], ignore_index=True)), "",
          "30-s distance [m] / heading [deg] per kind and pooled, with the pooled ratios to `as_logged`:", "",
          kind_table(errors, "as_logged"), "",
          "Share of the 30-s error (pooled) that the wind's future makes: the fraction removed when the "
          "same model is fed the logged future wind (non-causal), or the logged mean of that wind over the "
          "horizon held (non-causal: the wind's level known, not its gusts):", "", share_md]
    return "\n".join(md) + "\n"


def _arguments(argv):
    """The command line's arguments."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", type=Path, default=ROOT / "out" / "esso-osaka" / "split",
                    help="the benchmark's split (default out/esso-osaka/split)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-error-sources")
    ap.add_argument("--hybrid", action="store_true",
                    help="also fit the benchmark's hybrid on the fitting runs and score it with its wind "
                         "forecast and with the logged future wind")
    ap.add_argument("--seed-average", action="store_true",
                    help="with --hybrid: also fit the same hybrid with seed 1 and score it alone and the mean "
                         "of the two hybrids' forecasts")
    ap.add_argument("--structure-average", action="store_true",
                    help="with --hybrid: also fit the one-step hybrid and the hybrid with the free-run hull "
                         "correction, and score each alone and averaged with the benchmark's hybrid")
    ap.add_argument("--results", type=Path, help="also copy errors.csv and tables.md here (no data)")
    ap.add_argument("--tables-only", action="store_true",
                    help="write tables.md again from --out's errors.csv (and copy both to --results), "
                         "keeping the command line it records; nothing is forecast")
    args = ap.parse_args(argv)
    from _results import check_out

    check_out(ap, args.out)
    check_out(ap, args.results, option="--results")
    if (args.seed_average or args.structure_average) and not args.hybrid:
        ap.error("--seed-average and --structure-average need --hybrid")
    return args


def _physics_scores(runs, v, cfg, fit_dir, score, horizons) -> dict:
    """The physics' errors per variant of its inputs: the logged velocities led, the yaw rate
    from the heading, the wind zeroed, forecast, known in advance or trailed."""
    from hybridship.datasets.esso_osaka import esso_log_arrays
    from hybridship.evaluation.manoeuvre import Run, load_runs
    from hybridship.forecast_inputs.wind import fit_wind_forecast
    from hybridship.logs.ingest import ingest
    from hybridship.predictors import DynamicPredictor

    def with_wind(fn):
        return [Run(r.run, dataclasses.replace(r.arrays, wind=fn(r.arrays.wind))) for r in runs]

    per = {("as_logged", "known"): score(runs)}
    for lead in (0.3, 0.6):
        per[(f"lead{lead:g}", "known")] = score([Run(r.run, ingest(esso_log_arrays(r.run.path, v, velocity_lead_s=lead),
                                                                   v, purpose="fit")) for r in runs])

    def with_yaw_rate(fn):
        out = []
        for r in runs:
            nu = r.arrays.nu.copy()
            new = fn(r.arrays)
            ok = np.isfinite(new)
            nu[ok, 2] = new[ok]
            out.append(Run(r.run, dataclasses.replace(r.arrays, nu=nu)))
        return out

    for secs in (2, 4):
        per[(f"r_fit{secs}", "known")] = score(with_yaw_rate(
            lambda a, s=secs: heading_fit_rate(a.time_s, a.eta[:, 2], s)))
    per[("r_heading", "known")] = score(with_yaw_rate(
        lambda a: savgol_filter(np.unwrap(a.eta[:, 2]), int(round(4.0 / a.dt_s)) + 1, 3, deriv=1, delta=a.dt_s)))
    per[("wind_zero", "known")] = score(with_wind(lambda w: np.column_stack([np.zeros(len(w)), w[:, 1]])))
    wf, wind_scores = fit_wind_forecast([r.arrays for r in load_runs(fit_dir, v)], max(horizons))
    held = min(e for k, e in wind_scores.items() if k != "n_starts" and k[1] is None)
    print(f"wind forecast fitted on the fitting runs: {wf}; mean wind error over {max(horizons):g} s "
          f"{wind_scores.get((wf.mean_window_s, wf.time_constant_s), held):.2f} m/s against {held:.2f} m/s held")
    per[("wind_forecast", "known")] = score(runs, DynamicPredictor(v, residual_config=cfg.residual, wind_forecast=wf))
    per[("wind_future", "known")] = score(runs, DynamicPredictor(v, residual_config=cfg.residual,
                                                                 wind_forecast=_logged_future_wind()))
    per[("wind_future_mean", "known")] = score(runs, DynamicPredictor(v, residual_config=cfg.residual,
                                                                      wind_forecast=_logged_future_mean_wind()))
    for secs in (10, 30, 60):
        n = int(round(secs / runs[0].arrays.dt_s))
        per[(f"wind_trail{secs}", "known")] = score(with_wind(lambda w, n=n: trailing_wind(w, n)))
    return per


def _hybrid_scores(args, runs, v, cfg, fit_dir, score, steps, horizons, physics) -> dict:
    """The benchmark's hybrid fitted on the fitting runs, scored with each wind input and each
    correction of its output (and, as asked, averaged over seeds or structures)."""
    import torch

    from hybridship.evaluation.manoeuvre import load_runs, make_predictors

    torch.set_num_threads(1)
    # the spread is not scored here: no wind futures in it (they leave the forecasts as they are)
    cfg = dataclasses.replace(cfg, calibration=dataclasses.replace(cfg.calibration, horizon_s=max(horizons)),
                              wind_samples=0)
    fit_logs = [r.arrays for r in load_runs(fit_dir, v)]
    hyb = make_predictors(v, cfg)["hybrid"].fit(fit_logs, row_stride=cfg.train_row_stride)
    wf = hyb.wind_forecast
    print(f"hybrid fitted; its wind forecast: {wf}")
    per = {("hybrid", "known"): score(runs, hyb)}
    hyb.wind_forecast = _logged_future_wind()      # the same nets, the wind's future known
    per[("hybrid_wind_future", "known")] = score(runs, hyb)
    hyb.wind_forecast = _logged_future_mean_wind()
    per[("hybrid_wind_future_mean", "known")] = score(runs, hyb)
    hyb.wind_forecast = _sampled_wind(wf, fit_logs, int(steps.max()))
    per[("hybrid_wind_sampled", "known")] = score(runs, forecast=_mean_forecast(hyb, 8))
    hyb.wind_forecast = wf
    alpha, fb_scores = _choose_feedback(hyb, fit_logs, steps, cfg.start_every_s)
    print("error feedback on the fitting runs' held-back ends (30-s distance [m], heading [deg]): "
          + ", ".join(f"alpha {k:g}: {d:.3f}, {h:.2f}" for k, (d, h) in fb_scores.items())
          + f"; chosen {alpha:g}")
    per[("hybrid_error_feedback", "known")] = score(runs, forecast=_error_feedback(hyb, alpha))
    for w in CORRECTION_SCALES:
        per[(f"hybrid_scaled{w:g}", "known")] = score(runs, forecast=_scaled_correction(hyb, physics, w))
    if args.seed_average:
        cfg1 = dataclasses.replace(cfg, ensemble=dataclasses.replace(cfg.ensemble, seed=1))
        hyb1 = make_predictors(v, cfg1)["hybrid"].fit(fit_logs, row_stride=cfg.train_row_stride)
        per[("hybrid_seed1", "known")] = score(runs, hyb1)
        per[("hybrid_seed_mean", "known")] = score(runs, forecast=_mean_forecast([hyb, hyb1]))
    if args.structure_average:
        others = {"one_step": dataclasses.replace(cfg, training="one_step"),
                  "hull": dataclasses.replace(cfg, hull_correction=True, hull_fit="multi_step",
                                              multistep=dataclasses.replace(cfg.multistep, tune_hull=True))}
        for name, other_cfg in others.items():
            other = make_predictors(v, other_cfg)["hybrid"].fit(fit_logs, row_stride=cfg.train_row_stride)
            per[(f"hybrid_{name}", "known")] = score(runs, other)
            per[(f"hybrid_mean_{name}", "known")] = score(runs, forecast=_mean_forecast([hyb, other]))
    return per


def main(argv=None) -> int:
    from _results import command_line, publish, validation_dirs
    from hybridship.evaluation.manoeuvre import (ManoeuvreConfig, error_table, forecast_errors, load_runs,
                                                 start_rows)
    from hybridship.fileio import atomic_write
    from hybridship.predictors import DynamicPredictor
    from hybridship.vessel import load_vessel

    args = _arguments(argv)
    if args.tables_only:
        return _tables_only(args.out, args.results)
    if (dirs := validation_dirs(args.split, args.out / "split")) is None:
        return 2
    fit_dir, val_dir = dirs
    v = load_vessel("esso_osaka_model")
    cfg = ManoeuvreConfig()
    runs = load_runs(val_dir, v)
    p = DynamicPredictor(v, residual_config=cfg.residual)
    horizons = (5.0, 10.0, 20.0, 30.0)
    steps = np.array([int(round(h / runs[0].arrays.dt_s)) for h in horizons])

    def score(rr, p=p, forecast=None):
        fc = forecast or p.forecast
        return [forecast_errors(lambda a, st, h: fc(a, st, horizon_s=h, commands="known"), r.arrays,
                                start_rows(r.arrays, int(steps.max()), cfg.start_every_s), steps) for r in rr]

    per = _physics_scores(runs, v, cfg, fit_dir, score, horizons)
    if args.hybrid:
        per.update(_hybrid_scores(args, runs, v, cfg, fit_dir, score, steps, horizons, p))
    errors = error_table(per, runs, horizons)
    command = command_line("esso_error_sources.py", argv)
    text = tables(errors, command)
    atomic_write(args.out / "errors.csv", lambda fh: fh.write(errors.to_csv(index=False).encode()))
    atomic_write(args.out / "tables.md", lambda fh: fh.write(text.encode()))
    publish(args.out, args.results, ("errors.csv", "tables.md"))
    print(text)
    print(f"wrote {args.out / 'errors.csv'} and tables.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
