"""Esso Osaka: does the hybrid's one-step error persist within a run, and does a causal
online correction of the nets' output (a disturbance observer) lower its forecast error?

::

    python benchmarks/esso_online_adaptation.py --out out/esso-online-adaptation

fits the benchmark's hybrid on the validation split's fitting runs, as
``benchmarks/esso_error_sources.py --hybrid`` does (seed 1 split of the benchmark's
training runs; the test runs play no part), then:

1. **Diagnostic.** On the validation runs, the hybrid's one-step acceleration error: the
   residual target the nets are trained on (:meth:`PreparedLog.deviation`, from the
   velocities smoothed over 2 s) minus the ensemble-mean output of the nets at the same
   rows (their logged features; the guards do not act), per body DOF (u, v, r). Its
   autocorrelation at :data:`LAGS_S` (pooled over the runs, each pair within one segment,
   about the pooled mean), and the fraction of its mean square that an exponentially
   weighted mean of its past (time constants :data:`TAUS_S`) explains: at the next
   sample (the mean up to the sample before, and up to 1 s before, when the smoothed
   target of a sample is first known), at every sample of the next 30 s (gain 1 and the
   least-squares gain) and for the 30-s mean of the error (what a constant correction
   removes from the drift).
2. **Variant** (``--variant``; the diagnostic decides whether it is worth running). At
   each forecast start, the exponentially weighted mean of the one-step errors known then
   (smoothed targets of samples at least :data:`KNOWN_AFTER_S` before the start), times a
   gain, added to the nets' output as a body-frame acceleration over the rollout (before
   the guards' weight, which scales it with the nets' output), held
   (``hybrid_observer``) or decaying with the same time constant
   (``hybrid_observer_decay``), one time constant and gain for the three DOFs; and held,
   with each DOF's own time constant and gain, each chosen with the correction on that DOF
   alone (``hybrid_observer_dof``). The time constants and gains are chosen from
   :data:`TAUS_S` and :data:`GAINS` by the pooled 30-s distance on the held-back ends of
   the fitting runs (the rows the nets did not train on; the mean starts there, the first
   start 30 s after), as ``esso_error_sources.py`` chooses its error feedback's gain, then
   scored on the validation runs against the hybrid without it and the physics alone
   (``physics``), logged commands known. The held correction on every DOF with the fixed
   settings of :data:`FIXED` is scored too (``observer_tau<s>_g<gain>``: how the result
   depends on them, not a choice).

Writes ``persistence.csv`` (the diagnostic), ``choice.csv`` (the held-back scores, with
``--variant``), ``errors.csv`` (the manoeuvre benchmark's columns, with ``--variant``) and
``tables.md`` to ``--out``; ``--results`` also copies them there. ``--model FILE`` reads
the fitted hybrid from ``FILE`` when it exists, else fits it and writes it there;
``--tables-only`` writes ``tables.md`` again from ``--out``'s CSV files. The committed run::

    python benchmarks/esso_online_adaptation.py --variant --out out/esso-online-adaptation \
        --results docs/results/esso-online-adaptation
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

#: Lags of the autocorrelation [s].
LAGS_S = (1, 2, 5, 10, 20, 30, 60)
#: Time constants of the exponentially weighted mean [s].
TAUS_S = (5.0, 10.0, 30.0)
#: Candidate gains of the correction; 0 is the hybrid as it is.
GAINS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: Fixed (time constant [s], gain) of the held correction on every DOF, scored on the
#: validation runs beside the chosen ones (not a choice: how the result depends on them).
FIXED = ((10.0, 0.25), (30.0, 0.5), (30.0, 1.0))
#: A sample's smoothed target (centred 2-s Savitzky-Golay) is known this long after it [s].
KNOWN_AFTER_S = 1.0
#: Horizon of the diagnostic's "next 30 s" and of the scored forecasts [s].
HORIZON_S = 30.0
DOFS = ("u", "v", "r")


def one_step_errors(hybrid, arrays) -> np.ndarray:
    """The nets' one-step error (N, 3) at every row of ``arrays``: the residual deviation
    they are trained on minus the ensemble's mean output from the logged features, in body
    axes [m/s^2, m/s^2, rad/s^2] (NaN at rows without a target)."""
    from hybridship.residual.features import prepare_log

    prep = prepare_log(hybrid.model, arrays, hybrid.residual_config)
    rows = prep.trainable_rows()
    out = np.full((len(arrays.time_s), 3), np.nan)
    if rows.size:
        mean, _ = hybrid.ensemble.predict(prep.features(rows))
        out[rows] = prep.deviation(rows) - mean
    return out


def ewma(err: np.ndarray, segment_id: np.ndarray, dt_s: float, tau_s: float) -> np.ndarray:
    """Causal exponentially weighted mean (N, 3) of ``err`` up to and including each row,
    time constant ``tau_s``, restarted in each segment; NaN rows are skipped (the weights of
    the finite ones are normalised, so the first rows are their plain mean; NaN before any)."""
    from scipy.signal import lfilter

    a = 1.0 - np.exp(-dt_s / tau_s)
    ok = np.isfinite(err).all(axis=1)
    out = np.full(err.shape, np.nan)
    for seg in np.unique(segment_id):
        idx = np.flatnonzero(segment_id == seg)
        num = lfilter([a], [1.0, a - 1.0], np.where(ok[idx, None], err[idx], 0.0), axis=0)
        den = lfilter([a], [1.0, a - 1.0], ok[idx].astype(float))
        with np.errstate(invalid="ignore", divide="ignore"):
            out[idx] = np.where(den[:, None] > 0, num / den[:, None], np.nan)
    return out


def shifted(x: np.ndarray, segment_id: np.ndarray, k: int) -> np.ndarray:
    """``x`` moved ``k`` rows later (row ``i`` holds ``x[i - k]``; NaN where ``i - k`` is
    before the row's segment, or beyond the log for a negative ``k``)."""
    out = np.full(x.shape, np.nan)
    n = len(x)
    src = np.arange(n) - k
    ok = (src >= 0) & (src < n)
    ok[ok] &= segment_id[src[ok]] == segment_id[ok]
    out[ok] = x[src[ok]]
    return out


def autocorrelation(errors, lags: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """Pooled autocorrelation (len(lags), 3) of ``errors`` (a list of (err, segment_id)),
    about ``mean`` (3,), each pair within one segment."""
    out = np.empty((len(lags), 3))
    for j, k in enumerate(lags):
        num, a2, b2 = np.zeros(3), np.zeros(3), np.zeros(3)
        for err, seg in errors:
            x = err - mean
            y = shifted(x, seg, -int(k))            # row i holds x[i + k]
            ok = np.isfinite(x).all(1) & np.isfinite(y).all(1)
            num += (x[ok] * y[ok]).sum(0)
            a2 += (x[ok] ** 2).sum(0)
            b2 += (y[ok] ** 2).sum(0)
        out[j] = num / np.sqrt(a2 * b2)
    return out


def explained(errors, dt_s: float, tau_s: float, delay: int, horizon: int) -> dict:
    """Fractions (each (3,)) of the one-step error's mean square that the weighted mean of
    its past (time constant ``tau_s``, up to ``delay`` rows before the row after a start)
    explains, pooled over ``errors`` (a list of (err, segment_id)): ``next`` (the next row,
    gain 1), ``ahead`` (every row of the next ``horizon``, gain 1), ``ahead_best`` (the same
    with the least-squares gain ``gain``) and ``mean`` (the mean error over those rows,
    gain 1, and ``mean_best`` with the least-squares gain, which is ``gain`` too), and
    ``mean_rms``, the RMS of that mean error."""
    s = {k: np.zeros(3) for k in ("e1", "r1", "e2", "r2", "em", "mm", "ebar2", "rbar2", "ebarm", "m2")}
    for err, seg in errors:
        m = shifted(ewma(err, seg, dt_s, tau_s), seg, delay)     # row i: the mean up to row i - delay
        nxt = shifted(err, seg, -1)                                # row i holds err[i + 1]
        ok = np.isfinite(m).all(1) & np.isfinite(nxt).all(1)
        s["e1"] += (nxt[ok] ** 2).sum(0)
        s["r1"] += ((nxt[ok] - m[ok]) ** 2).sum(0)
        fut = np.stack([shifted(err, seg, -k) for k in range(1, horizon + 1)])    # (H, N, 3)
        ok = np.isfinite(m).all(1) & np.isfinite(fut).all(axis=(0, 2))
        f, mm = fut[:, ok], m[ok][None]
        s["e2"] += (f ** 2).sum((0, 1))
        s["r2"] += ((f - mm) ** 2).sum((0, 1))
        s["em"] += (f * mm).sum((0, 1))
        s["mm"] += (np.broadcast_to(mm, f.shape) ** 2).sum((0, 1))
        s["ebar2"] += (f.mean(0) ** 2).sum(0)
        s["rbar2"] += ((f.mean(0) - m[ok]) ** 2).sum(0)
        s["ebarm"] += (f.mean(0) * m[ok]).sum(0)
        s["m2"] += (m[ok] ** 2).sum(0)
        s["n"] = s.get("n", 0) + int(ok.sum())
    return {"next": 1 - s["r1"] / s["e1"], "ahead": 1 - s["r2"] / s["e2"],
            "ahead_best": s["em"] ** 2 / (s["mm"] * s["e2"]), "gain": s["em"] / s["mm"],
            "mean": 1 - s["rbar2"] / s["ebar2"], "mean_best": s["ebarm"] ** 2 / (s["m2"] * s["ebar2"]),
            "mean_rms": np.sqrt(s["ebar2"] / s["n"])}


class _CorrectedEnsemble:
    """The hybrid's ensemble with ``correction`` (S, 3) added to every member's output,
    times ``exp(-t / decay_s)`` at the step's lead ``t`` (``decay_s`` (3,), one per DOF; held
    with None): the rollout calls :meth:`predict_members` once a step, for all starts at once."""

    def __init__(self, ensemble, correction: np.ndarray, dt_s: float, decay_s=None):
        self._ens, self._c, self._dt, self._decay, self._step = ensemble, correction, dt_s, decay_s, 0

    def __getattr__(self, name):
        return getattr(self._ens, name)

    def predict_members(self, X):
        out = self._ens.predict_members(X)
        if out.shape[1] != self._c.shape[0]:
            raise ValueError(f"the rollout has {out.shape[1]} starts, the correction {self._c.shape[0]}")
        f = 1.0 if self._decay is None else np.exp(-self._step * self._dt / np.asarray(self._decay, dtype=float))
        self._step += 1
        return out + f * self._c[None]


def observer_forecast(hybrid, tau_s, gain, decay: bool, first_row: int = 0):
    """A forecaster: ``hybrid``'s forecast with ``gain`` times the weighted mean (time
    constant ``tau_s``) of its one-step errors known at each start (rows from ``first_row``
    and at least :data:`KNOWN_AFTER_S` before the start) added to the nets' output, held over
    the forecast or decaying with ``tau_s`` (``decay``). ``tau_s`` and ``gain``: one for all
    DOFs or one per DOF (u, v, r). A start with no known error gets none; gain 0 is the
    hybrid."""
    taus = np.broadcast_to(np.asarray(tau_s, dtype=float), (3,))
    gains = np.broadcast_to(np.asarray(gain, dtype=float), (3,))

    def forecast(a, start_times_s, horizon_s, **kw):
        st = np.asarray(start_times_s, dtype=float)
        if not np.any(gains):
            return hybrid.forecast(a, st, horizon_s=horizon_s, **kw)
        err = one_step_errors(hybrid, a)
        err[:first_row] = np.nan
        dt = float(np.median(np.diff(a.time_s)))
        rows = np.searchsorted(a.time_s, st)
        c = np.zeros((rows.size, 3))
        for tau in np.unique(taus):
            m = shifted(ewma(err, a.segment_id, dt, tau), a.segment_id, int(round(KNOWN_AFTER_S / dt)))[rows]
            c[:, taus == tau] = np.nan_to_num(gains * m)[:, taus == tau]
        ens = hybrid.ensemble
        corrected = hybrid.ensemble = _CorrectedEnsemble(ens, c, dt, taus if decay else None)
        try:
            out = hybrid.forecast(a, st, horizon_s=horizon_s, **kw)
        finally:
            hybrid.ensemble = ens
        # the decay counts calls: the rollout must have asked the nets once a step
        if corrected._step != int(round(horizon_s / dt)):
            raise RuntimeError(f"the rollout called the nets {corrected._step} times for "
                               f"{int(round(horizon_s / dt))} steps")
        return out

    return forecast


def choose(hybrid, logs, steps: np.ndarray, start_every_s: float, decay: bool, dof: int | None = None):
    """The (time constant, gain) of :data:`TAUS_S` x :data:`GAINS` with the lowest mean
    30-s distance on the held-back ends of ``logs`` (the weighted mean starts at the cut,
    the first start ``HORIZON_S`` after it: :func:`esso_error_sources.held_back_errors`),
    the correction on every DOF or on DOF ``dof`` (0, 1, 2: u, v, r) alone. Returns
    ``(choice, rows)``, each row ``[decay, dof, tau, gain, distance, heading]``."""
    from esso_error_sources import held_back_errors

    rows = []
    for tau in TAUS_S:
        for gain in GAINS:
            if gain == 0 and tau != TAUS_S[0]:
                continue                        # gain 0 is the hybrid whatever the time constant
            g = gain if dof is None else gain * (np.arange(3) == dof)
            e = held_back_errors(hybrid, logs, steps, start_every_s,
                                 lambda a, cut, t=tau, g=g: observer_forecast(hybrid, t, g, decay, cut),
                                 HORIZON_S)[:, -1]
            name = "all" if dof is None else DOFS[dof]
            rows.append([decay, name, tau, gain, float(e[:, 3].mean()), float(e[:, 2].mean())])
            print(f"held back, {'decaying' if decay else 'held'}, {name}, tau {tau:g} s, gain {gain:g}: "
                  f"{rows[-1][4]:.4f} m, {rows[-1][5]:.3f} deg", flush=True)
    best = min(rows, key=lambda r: r[4])
    return (best[2], best[3]), rows


def _variants(hyb, fit_logs, steps, start_every_s):
    """The observer's variants, each chosen on the held-back ends: ``{name: forecaster}``
    and the held-back scores (rows of :func:`choose`). ``hybrid_observer`` and
    ``hybrid_observer_decay``: one time constant and gain for the three DOFs, the correction
    held or decaying; ``hybrid_observer_dof``: held, each DOF's time constant and gain chosen
    with the correction on that DOF alone."""
    out, rows = {}, []
    for decay in (False, True):
        (tau, gain), r = choose(hyb, fit_logs, steps, start_every_s, decay)
        rows += r
        name = "hybrid_observer_decay" if decay else "hybrid_observer"
        print(f"{name}: tau {tau:g} s, gain {gain:g}", flush=True)
        out[name] = observer_forecast(hyb, tau, gain, decay)
    taus, gains = np.zeros(3), np.zeros(3)
    for d in range(3):
        (taus[d], gains[d]), r = choose(hyb, fit_logs, steps, start_every_s, False, d)
        rows += r
    print(f"hybrid_observer_dof: tau {taus} s, gain {gains}", flush=True)
    out["hybrid_observer_dof"] = observer_forecast(hyb, taus, gains, False)
    for tau, gain in FIXED:
        out[f"observer_tau{tau:g}_g{gain:g}"] = observer_forecast(hyb, tau, gain, False)
    return out, rows


def persistence(errors, dt_s: float):
    """The diagnostic's table: per DOF, the one-step error's RMS and mean (columns ``rms``,
    ``mean``, ``rms_30s_mean``: m/s^2 for u and v, rad/s^2 for r), its autocorrelation at
    :data:`LAGS_S`, and per time constant the fractions of :func:`explained` (the next row
    from the mean up to that row and up to :data:`KNOWN_AFTER_S` before it; the rest with
    the latter)."""
    import pandas as pd

    ok = np.concatenate([e[np.isfinite(e).all(1)] for e, _ in errors])
    mean = ok.mean(0)
    acf = autocorrelation(errors, np.round(np.array(LAGS_S) / dt_s).astype(int), mean)
    delay, horizon = int(round(KNOWN_AFTER_S / dt_s)), int(round(HORIZON_S / dt_s))
    rows = []
    for tau in TAUS_S:
        now = explained(errors, dt_s, tau, 0, 1)
        known = explained(errors, dt_s, tau, delay, horizon)
        for d, dof in enumerate(DOFS):
            rows.append({"dof": dof, "rms": float(np.sqrt((ok[:, d] ** 2).mean())), "mean": float(mean[d]),
                         **{f"acf_{k}s": float(acf[j, d]) for j, k in enumerate(LAGS_S)}, "tau_s": tau,
                         "next_from_last": float(now["next"][d]), "next_known": float(known["next"][d]),
                         "ahead_30s": float(known["ahead"][d]), "ahead_30s_best": float(known["ahead_best"][d]),
                         "best_gain": float(known["gain"][d]), "mean_30s": float(known["mean"][d]),
                         "mean_30s_best": float(known["mean_best"][d]), "rms_30s_mean": float(known["mean_rms"][d])})
    return pd.DataFrame(rows)


def tables(persist, choice, errors, command: str) -> str:
    """``tables.md``: the diagnostic and, when run, the held-back choice and the validation
    runs' 30-s errors per kind and pooled."""
    import pandas as pd

    from _results import kind_table
    from hybridship.fileio import markdown_table

    first = persist[persist["tau_s"] == persist["tau_s"].iloc[0]]
    acf = markdown_table(pd.DataFrame([[r.dof, f"{r.rms:.4g}", f"{r['mean']:.3g}", f"{r.rms_30s_mean:.3g}",
                                        *(f"{r[f'acf_{k}s']:.2f}" for k in LAGS_S)] for _, r in first.iterrows()],
                                      columns=["DOF", "RMS", "mean", "RMS of its 30-s mean",
                                               *(f"{k} s" for k in LAGS_S)]))
    cols = ("next_from_last", "next_known", "ahead_30s", "ahead_30s_best", "mean_30s", "mean_30s_best")
    frac = markdown_table(pd.DataFrame(
        [[r.dof, f"{r.tau_s:g}", *(f"{r[c]:.0%}" for c in cols), f"{r.best_gain:.2f}"] for _, r in persist.iterrows()],
        columns=["DOF", "tau (s)", "next sample, mean to the sample before",
                 f"next sample, mean to {KNOWN_AFTER_S:g} s before (known)", "every sample of the next 30 s",
                 "the same, least-squares gain", "the 30-s mean", "the 30-s mean, least-squares gain",
                 "least-squares gain"]))
    md = [f"Command: `{command}`", "",
          "Validation runs: the hybrid's one-step acceleration error (the nets' residual target minus the "
          "ensemble-mean output; u, v in m/s^2, r in rad/s^2), its RMS, mean and autocorrelation at each lag "
          "(about the pooled mean):", "", acf, "",
          "Fraction of its mean square that the exponentially weighted mean of its past (time constant tau) "
          "explains (1 - mean square of the error minus that mean / mean square of the error; gain 1 unless "
          f"said; 'known': the mean of the samples whose smoothed target is known, {KNOWN_AFTER_S:g} s and more "
          "before the step's start):", "", frac, ""]
    if choice is not None and len(choice):
        md += ["Held-back ends of the fitting runs: 30-s distance [m] / heading [deg], pooled, commands known, "
               "by the correction's gain (gain 0: the hybrid):", "", _choice_md(choice), ""]
    if errors is not None and len(errors):
        md += ["Validation runs, logged commands known: 30-s distance [m] / heading [deg] per kind and pooled, "
               "with the pooled ratios to the physics:", "", kind_table(errors, "physics"), ""]
    return "\n".join(md)


def _choice_md(choice) -> str:
    """The held-back scores as a table: a row per correction, DOF and time constant, a column
    per gain, and the chosen (lowest-distance) setting of each correction and DOF."""
    import pandas as pd

    from hybridship.fileio import markdown_table

    gains = sorted(choice["gain"].unique())
    zero = choice[choice["gain"] == 0.0]
    rows, chosen = [], []
    for (decay, dof), g in choice.groupby(["decay", "dof"], sort=False):
        label = "decaying" if decay else "held"
        best = g.loc[g["distance_m"].idxmin()]
        chosen.append(f"{label}, {dof}: tau {best.tau_s:g} s, gain {best.gain:g}")
        for tau, t in g[g["gain"] > 0].groupby("tau_s", sort=False):
            cells = pd.concat([zero[(zero["decay"] == decay) & (zero["dof"] == dof)], t]).set_index("gain")
            rows.append([label, dof, f"{tau:g}", *(f"{cells.loc[k, 'distance_m']:.4f} / "
                                                    f"{cells.loc[k, 'heading_deg']:.3f}" for k in gains)])
    table = pd.DataFrame(rows, columns=["correction", "DOF", "tau (s)", *(f"gain {k:g}" for k in gains)])
    return markdown_table(table) + "\n\nChosen (lowest distance): " + "; ".join(chosen) + "."


def _hybrid(model_file, fit_dir, v, cfg):
    """The benchmark's hybrid fitted on the fitting runs (read from ``model_file`` when it
    exists, else fitted and, with a ``model_file``, written there)."""
    from hybridship.evaluation.manoeuvre import load_runs, make_predictors
    from hybridship.predictors import HybridPredictor

    if model_file is not None and model_file.exists():
        return HybridPredictor.load(model_file)
    import torch

    torch.set_num_threads(1)
    hyb = make_predictors(v, cfg)["hybrid"].fit([r.arrays for r in load_runs(fit_dir, v)],
                                                 row_stride=cfg.train_row_stride)
    if model_file is not None:
        hyb.save(model_file)
    return hyb


def _tables_only(out: Path, results: Path | None) -> int:
    """Render ``out/tables.md`` again from the run's CSV files, keeping its command."""
    import pandas as pd

    from _results import tables_again

    names = [n for n in ("choice.csv", "errors.csv") if (out / n).exists()]
    if len(names) == 1:
        print(f"error: {out} has {names[0]} without the other of choice.csv and errors.csv", file=sys.stderr)
        return 2

    def render(persist, *rest):
        return tables(persist, *(rest[:-1] if names else (pd.DataFrame(), pd.DataFrame())), rest[-1])

    return tables_again(out, results, ["persistence.csv", *names], render,
                        ("persistence.csv", "choice.csv", "errors.csv", "tables.md"))


def main(argv=None) -> int:
    import pandas as pd

    from _results import check_out, command_line, publish, validation_dirs
    from hybridship.evaluation.manoeuvre import (ManoeuvreConfig, error_table, forecast_errors, load_runs,
                                                 start_rows)
    from hybridship.fileio import atomic_write
    from hybridship.predictors import DynamicPredictor
    from hybridship.vessel import load_vessel

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", type=Path, default=ROOT / "out" / "esso-osaka" / "split",
                    help="the benchmark's split (default out/esso-osaka/split)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-online-adaptation")
    ap.add_argument("--variant", action="store_true",
                    help="also choose the correction on the held-back ends and score it on the validation runs")
    ap.add_argument("--model", type=Path, help="read the fitted hybrid from this file if it exists, else write it")
    ap.add_argument("--results", type=Path, help="also copy the CSV files and tables.md here (no data)")
    ap.add_argument("--tables-only", action="store_true",
                    help="write tables.md again from --out's CSV files, keeping the command it records")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    check_out(ap, args.results, option="--results")
    if args.tables_only:
        return _tables_only(args.out, args.results)
    if (dirs := validation_dirs(args.split, args.out / "split")) is None:
        return 2
    fit_dir, val_dir = dirs
    v = load_vessel("esso_osaka_model")
    cfg = ManoeuvreConfig()
    # as esso_error_sources.py --hybrid: calibrated over the scored 30 s, no wind futures in the spread
    cfg = dataclasses.replace(cfg, calibration=dataclasses.replace(cfg.calibration, horizon_s=HORIZON_S),
                              wind_samples=0)
    runs = load_runs(val_dir, v)
    dt = runs[0].arrays.dt_s
    hyb = _hybrid(args.model, fit_dir, v, cfg)
    persist = persistence([(one_step_errors(hyb, r.arrays), r.arrays.segment_id) for r in runs], dt)
    choice = errors = pd.DataFrame()
    if args.variant:
        horizons = (5.0, 10.0, 20.0, HORIZON_S)
        steps = np.array([int(round(h / dt)) for h in horizons])
        fit_logs = [r.arrays for r in load_runs(fit_dir, v)]

        def score(fc):
            return [forecast_errors(lambda a, st, h: fc(a, st, horizon_s=h, commands="known"), r.arrays,
                                    start_rows(r.arrays, int(steps.max()), cfg.start_every_s), steps) for r in runs]

        per = {("physics", "known"): score(DynamicPredictor(v, residual_config=cfg.residual).forecast),
               ("hybrid", "known"): score(hyb.forecast)}
        variants, chosen = _variants(hyb, fit_logs, steps, cfg.start_every_s)
        per.update({(name, "known"): score(fc) for name, fc in variants.items()})
        choice = pd.DataFrame(chosen, columns=["decay", "dof", "tau_s", "gain", "distance_m", "heading_deg"])
        errors = error_table(per, runs, horizons)
    command = command_line("esso_online_adaptation.py", argv)
    text = tables(persist, choice, errors, command)
    names = ["persistence.csv", *(["choice.csv", "errors.csv"] if args.variant else []), "tables.md"]
    for name, df in (("persistence.csv", persist), ("choice.csv", choice), ("errors.csv", errors)):
        if name in names:
            atomic_write(args.out / name, lambda fh, df=df: fh.write(df.to_csv(index=False).encode()))
    atomic_write(args.out / "tables.md", lambda fh: fh.write(text.encode()))
    publish(args.out, args.results, names)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
