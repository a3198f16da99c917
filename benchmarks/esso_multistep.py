"""Esso Osaka: settings of the hybrid's multi-step training, screened on a validation split.

::

    python benchmarks/esso_multistep.py --out out/esso-multistep \\
        --variants "base:;it300:iterations=300"

splits the benchmark's *training* runs (``out/esso-osaka/split/train``, made by
``benchmarks/esso_osaka.py``) again, seed 1, as ``benchmarks/esso_training.py`` does (the
test runs play no part). The one-step nets are fitted once with the benchmark's features,
members and seed (on the same rows as :meth:`~hybridship.predictors.HybridPredictor.fit`:
the end of every run held back) and cached in ``--out``; every variant fine-tunes a copy of
them with :func:`~hybridship.residual.multistep.train_multistep` and the benchmark's
:class:`~hybridship.residual.multistep.MultiStepConfig` with the named fields replaced
(``name:field=value,field=value``; values are parsed as Python literals). Each variant is
scored on the validation runs from a start every ``--start-every-s`` with the logged
commands known, without the command-regime guard and with the raw ensemble spread (neither
changes the nets). Writes ``errors.csv`` (the manoeuvre benchmark's columns) and
``variants.csv`` (per variant: pooled 30-s distance and heading, their ratios to the
physics, the number of kind x horizon cells below the physics, training seconds, the
multi-step history) and prints them.

``--permutation`` also writes ``importance_<variant>.csv``: the rise of the pooled 30-s
errors when one feature is permuted across the starts at every rollout step (a documented
stand-in for the backward selection of Skulstad et al. sec. 3.3 that needs no retraining;
``tables.md`` then shows it, and ``--results`` copies it too);
``--drop-features`` retrains without the named features to confirm a removal, and
``--hidden`` / ``--members`` / ``--seed`` change the nets (screening only). ``--hull`` (with
``--hull-fit``) puts the linear hull correction in front of the nets
(:class:`~hybridship.residual.hull.HullCorrection`), ``--with-command-guard`` also scores
each variant with the command-regime guard fitted on its nets (``<variant>+cg``), and
``--save-models`` writes each variant's model file. ``--no-memory`` and ``--held-wind``
give the benchmark's hybrid as it was before the command-memory features and the wind
forecast (the screens quoted on the Esso Osaka page were made so). The fine-tuning
rollouts take the wind as the hybrid's forecasts do (held, or its fitted wind forecast).

Also writes ``tables.md`` (:func:`tables`: the command, the pooled 30-s figures of every
row of this run and its 30-s errors per kind); ``--results`` copies ``errors.csv``,
``variants.csv`` and ``tables.md`` to a committed folder (``--out`` holds the split's links to
the data and the cached nets, which stay out of the repository) and then needs an ``--out``
without an earlier run's ``errors.csv``, so that the copies come from this command alone.
``--tables-only`` writes ``tables.md`` again from ``--out``'s files, keeping its command.
The committed screens, one folder per command under ``docs/results/esso-multistep-screening``::

    python benchmarks/esso_multistep.py --no-memory --held-wind --out out/esso-ms-default \
        --variants "abs:loss='absolute';abs_hor40:loss='absolute',horizon_s=40.0;abs_b128:loss='absolute',\
batch_starts=128" --results docs/results/esso-multistep-screening/default
"""

from __future__ import annotations

import argparse
import ast
import copy
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def parse_variants(spec: str) -> dict:
    """``"a:x=1,y=2;b:"`` -> ``{"a": {"x": 1, "y": 2}, "b": {}}``; a value may be any Python
    literal (``steps=(5, 10)``), and an unquoted word is taken as text."""
    out = {}
    for part in filter(None, (s.strip() for s in spec.split(";"))):
        name, _, fields = part.partition(":")
        out[name.strip()] = _literal_fields(fields) or _text_fields(fields)
    return out


def _literal_fields(fields: str) -> dict | None:
    """``x=1, y=(2, 3), loss=absolute`` as keyword arguments of literals (commas inside
    brackets kept), an unquoted word as its text; None when a value is neither."""
    try:
        call = ast.parse(f"f({fields})", mode="eval").body
        return {kw.arg: kw.value.id if isinstance(kw.value, ast.Name) else ast.literal_eval(kw.value)
                for kw in call.keywords} if not call.args else None
    except (ValueError, SyntaxError):
        return None


def _text_fields(fields: str) -> dict:
    """``x=1, loss=absolute``: fields split at every comma, each value a literal where it is one."""
    kw = {}
    for item in filter(None, (f.strip() for f in fields.split(","))):
        k, _, v = item.partition("=")
        try:
            kw[k.strip()] = ast.literal_eval(v.strip())
        except (ValueError, SyntaxError):
            kw[k.strip()] = v.strip()
    return kw


def one_step_hybrid(cfg, fit_runs, cache: Path, wind_forecast="fit"):
    """The benchmark's hybrid with one-step nets fitted on ``fit_runs`` (cached as a model file)."""
    from hybridship.predictors import HybridPredictor

    p = HybridPredictor("esso_osaka_model", residual_config=cfg.residual, ensemble_config=cfg.ensemble,
                        guard_quantile=cfg.guard_quantile, environment="mean", calibration_config=cfg.calibration,
                        training="one_step", multistep_config=cfg.multistep, command_guard=False,
                        hull_correction=cfg.hull_correction, hull_fit=cfg.hull_fit, wind_forecast=wind_forecast)
    logs = [r.arrays for r in fit_runs]
    if cache.exists():
        q = HybridPredictor.load(cache)
        if tuple(q.residual_config.features) == tuple(cfg.residual.features) and \
                q.hull_correction == cfg.hull_correction and q.hull_fit == cfg.hull_fit:
            return q, logs
    cal = p.calibration_config
    p.fit(logs, row_stride=cfg.train_row_stride, calibration=replace(cal, commands=("known",), start_every_s=30.0))
    p.save(cache)
    return p, logs


def cache_file(out: Path, cfg, held_wind: bool) -> Path:
    """The model file in ``out`` that caches the one-step nets of ``cfg`` (named by what changes them)."""
    return out / (f"one_step_m{cfg.ensemble.n_members}_h{cfg.ensemble.hidden}_f{len(cfg.residual.features)}"
                  f"{'_s%d' % cfg.ensemble.seed if cfg.ensemble.seed else ''}"
                  f"{'_hull_' + cfg.hull_fit if cfg.hull_correction else ''}"
                  f"{cfg.multistep.hull_iterations if cfg.hull_fit == 'multi_step' else ''}"
                  f"{'_held_wind' if held_wind else ''}.npz")


def fine_tune(p, logs, ms_cfg, row_stride):
    """A copy of the one-step hybrid ``p`` with its nets fine-tuned by ``ms_cfg``; (copy, history)."""
    from hybridship.residual.features import prepare_log
    from hybridship.residual.multistep import collect_starts, train_multistep

    q = copy.deepcopy(p)
    q.multistep_config = ms_cfg
    q.training = "multi_step"
    cal = q.calibration_config
    cuts, masks = q._held_back(logs, cal, True)
    preps = [prepare_log(q.model, a, q.residual_config) for a in logs]
    # the rollouts take the wind as the hybrid's forecasts do (HybridPredictor.fit does the same)
    starts = collect_starts(preps, masks, ms_cfg, dp_only=True,
                            wind_forecast=None if q.wind_forecast.held else q.wind_forecast)
    q.ensemble, hist = train_multistep(q.ensemble, q.model, starts, q.residual_config.feature_index, ms_cfg,
                                       seed=q.ensemble_config.seed, hull=q.hull)
    q.hull = hist.pop("hull", q.hull)
    return q, hist


#: Files ``--results`` copies from ``--out``.
RESULT_FILES = ("errors.csv", "variants.csv", "tables.md")


def importance_name(variant: str) -> str:
    """The file of ``variant``'s permutation importance (``--permutation``) in ``--out``."""
    return f"importance_{variant}.csv"


def tables(errors, table, command: str, importance: dict | None = None) -> str:
    """``tables.md``: the command that made ``errors`` and ``table`` (the rows of :func:`summary`),
    every row's pooled 30-s distance and heading with their ratios to the physics and the
    kind x horizon cells below it, and the 30-s errors per kind (validation runs, logged
    commands known); then each variant's permutation importance in ``importance`` (variant:
    the frame of :func:`permutation_importance`), if any."""
    from _results import kind_table
    from hybridship.fileio import markdown_table

    cols = ["variant", "settings", "dist30_m", "head30_deg", "dist_ratio", "head_ratio", "cells_below", "train_s"]
    md = [f"Command: `{command}`", "", "Validation runs, logged commands known, raw spread. Pooled 30-s distance "
          "[m] and heading [deg] error, their ratios to the physics (`dynamic`), the kind x horizon cells where "
          "the distance error is below the physics, and the fine-tuning's seconds (`+cg`: the same nets with the "
          "command-regime guard fitted on them):", "", markdown_table(table[cols]), "",
          "30-s distance [m] / heading [deg] per kind and pooled, with the pooled ratios to the physics:", "",
          kind_table(errors, "dynamic")]
    for name, imp in (importance or {}).items():
        imp = imp.assign(dist30_m=imp.dist30_m.round(4), head30_deg=imp.head30_deg.round(3),
                         d_dist30_m=imp.d_dist30_m.round(4), d_head30_deg=imp.d_head30_deg.round(3))
        md += ["", f"Permutation importance of `{name}` (`{importance_name(name)}`): the pooled 30-s distance [m] "
               "and heading [deg] error with one feature permuted across the starts at every rollout step "
               "(guard off), and their rise over the row `(none)` (nothing permuted):", "", markdown_table(imp)]
    return "\n".join(md) + "\n"


def tables_only(out: Path, results: Path | None) -> int:
    """Render ``out/tables.md`` again from ``out/errors.csv`` and ``out/variants.csv``, with the
    command of the run that wrote them (its first line), and copy them to ``results``; no new run."""
    import pandas as pd

    from _results import tables_again

    try:
        names = [importance_name(v) for v in pd.read_csv(out / "variants.csv").variant]
    except FileNotFoundError:
        names = []   # tables_again says what is missing
    found = [n for n in names if (out / n).exists()]
    importance = {n[len("importance_"):-len(".csv")]: pd.read_csv(out / n) for n in found}
    return tables_again(out, results, ["errors.csv", "variants.csv"],
                        lambda e, t, command: tables(e, t, command, importance), RESULT_FILES + tuple(found))


def screening_config(args, horizons):
    """The benchmark's :class:`~hybridship.evaluation.manoeuvre.ManoeuvreConfig` with the
    command line's changes of the nets, the hull correction and the features."""
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig
    from hybridship.residual.features import MEMORY_FEATURES

    cfg = ManoeuvreConfig()
    cfg = replace(cfg, calibration=replace(cfg.calibration, horizon_s=max(horizons)))
    if args.members:
        cfg = replace(cfg, ensemble=replace(cfg.ensemble, n_members=args.members))
    if args.seed is not None:
        cfg = replace(cfg, ensemble=replace(cfg.ensemble, seed=args.seed))
    if args.hidden:
        cfg = replace(cfg, ensemble=replace(cfg.ensemble, hidden=args.hidden))
    if args.hull:
        cfg = replace(cfg, hull_correction=True, hull_fit=args.hull_fit)
        if args.hull_iterations:
            cfg = replace(cfg, multistep=replace(cfg.multistep, hull_iterations=args.hull_iterations))
    drop = [f for f in args.drop_features.split(",") if f] + (list(MEMORY_FEATURES) if args.no_memory else [])
    if drop:
        cfg = replace(cfg, residual=replace(cfg.residual, features=tuple(f for f in cfg.residual.features
                                                                         if f not in drop)))
    return cfg


def write_outputs(out: Path, results: Path | None, run_errors, rows, command: str, importance: dict | None = None):
    """Write ``errors.csv`` and ``variants.csv`` to ``out`` (keeping earlier variants of the same
    ``out``: the same split and one-step nets), ``tables.md`` of this run's rows alone (and of its
    permutation importance, ``importance``: variant -> frame, written to ``out`` already), and copy
    the three and the importance files to ``results``; the merged (errors, variants) tables."""
    import pandas as pd

    from _results import publish
    from hybridship.fileio import atomic_write

    errors = run_errors
    if (out / "errors.csv").exists():
        old = pd.read_csv(out / "errors.csv")
        errors = pd.concat([old[~old.model.isin(errors.model.unique())], errors], ignore_index=True)
    atomic_write(out / "errors.csv", lambda fh: fh.write(errors.to_csv(index=False).encode()))
    table = run_table = pd.DataFrame(rows)
    if (out / "variants.csv").exists():
        oldv = pd.read_csv(out / "variants.csv")
        table = pd.concat([oldv[~oldv.variant.isin(table.variant)], table], ignore_index=True)
    atomic_write(out / "variants.csv", lambda fh: fh.write(table.to_csv(index=False).encode()))
    text = tables(run_errors, run_table, command, importance)
    atomic_write(out / "tables.md", lambda fh: fh.write(text.encode()))
    publish(out, results, RESULT_FILES + tuple(importance_name(v) for v in (importance or {})))
    print(text)
    return errors, table


def parse_args(argv=None) -> argparse.Namespace:
    """The command line (``argv``; None: this process's arguments)."""
    from _results import parse_horizons

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", type=Path, default=ROOT / "out" / "esso-osaka" / "split",
                    help="the benchmark's split (default out/esso-osaka/split)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-multistep")
    ap.add_argument("--variants", default="base:", help="name:field=value,...;name:... (MultiStepConfig fields)")
    ap.add_argument("--start-every-s", type=float, default=1.0)
    ap.add_argument("--members", type=int, default=None, help="ensemble members (screening; default the benchmark's)")
    ap.add_argument("--seed", type=int, default=None, help="seed of the nets (default the benchmark's)")
    ap.add_argument("--hidden", type=int, default=None, help="units per hidden layer (default the benchmark's)")
    ap.add_argument("--hull", action="store_true",
                    help="with the linear MMG-structured correction before the nets (HullCorrection)")
    ap.add_argument("--hull-fit", choices=("one_step", "multi_step"), default="one_step",
                    help="with --hull: identify the correction by ridge regression or by a free-run fit")
    ap.add_argument("--hull-iterations", type=int, default=None, help="with --hull-fit multi_step: Adam steps")
    ap.add_argument("--drop-features", default="", help="comma-separated features to leave out of the benchmark's")
    ap.add_argument("--no-memory", action="store_true",
                    help="without the command-memory features (the benchmark's before they were added)")
    ap.add_argument("--held-wind", action="store_true",
                    help="the wind held at its start value in training and forecasts (before the wind forecast)")
    ap.add_argument("--horizons-s", default="5,10,20,30")
    ap.add_argument("--save-models", action="store_true", help="also write each variant's model file to --out")
    ap.add_argument("--with-command-guard", action="store_true",
                    help="also score each variant with the command-regime guard fitted on its nets (suffix +cg)")
    ap.add_argument("--permutation", action="store_true",
                    help="also the permutation importance of every feature of each variant (validation rollouts)")
    ap.add_argument("--results", type=Path, help="also copy errors.csv, variants.csv and tables.md here (no data)")
    ap.add_argument("--tables-only", action="store_true",
                    help="write tables.md again from --out's files (and copy them to --results), keeping the "
                         "command line it records; nothing is trained")
    args = ap.parse_args(argv)
    from _results import check_out

    check_out(ap, args.out)
    check_out(ap, args.results, option="--results")
    if args.tables_only:
        return args
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig

    parse_horizons(ap, args.horizons_s)        # a usage error now, not after the one-step nets
    try:        # a misspelt field stopped the run with a traceback after the one-step nets were trained
        for name, kw in parse_variants(args.variants).items():
            replace(ManoeuvreConfig().multistep, **kw)
    except (TypeError, ValueError) as exc:
        ap.error(f"--variants: {name}: {exc}")
    features = ManoeuvreConfig().residual.features
    unknown = [f for f in args.drop_features.split(",") if f and f not in features]
    if unknown:         # a misspelt name left every feature in, without a word
        ap.error(f"--drop-features: {', '.join(unknown)}: not among the benchmark's features ({', '.join(features)})")
    return args


def main(argv=None) -> int:
    import torch

    from _results import command_line, validation_dirs
    from hybridship.evaluation.manoeuvre import error_table, forecast_errors, load_runs, start_rows
    from hybridship.fileio import atomic_write
    from hybridship.forecast_inputs.wind import HELD_WIND
    from hybridship.predictors import DynamicPredictor
    from hybridship.vessel import load_vessel

    args = parse_args(argv)
    if args.tables_only:
        return tables_only(args.out, args.results)
    if args.results is not None and (args.out / "errors.csv").exists():
        print(f"error: --results: {args.out} holds an earlier run's errors.csv; use a new --out so that the "
              "copied files come from this command alone", file=sys.stderr)
        return 2
    torch.set_num_threads(1)
    if (dirs := validation_dirs(args.split, args.out / "split")) is None:
        return 2
    fit_dir, val_dir = dirs
    horizons = tuple(float(h) for h in args.horizons_s.split(","))
    v = load_vessel("esso_osaka_model")
    cfg = screening_config(args, horizons)
    fit_runs, val_runs = load_runs(fit_dir, v), load_runs(val_dir, v)
    args.out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    base, logs = one_step_hybrid(cfg, fit_runs, cache_file(args.out, cfg, args.held_wind),
                                  wind_forecast=HELD_WIND if args.held_wind else "fit")
    print(f"one-step nets: {time.perf_counter() - t0:.0f} s", flush=True)
    dt = float(np.median(np.diff(val_runs[0].arrays.time_s)))
    steps = np.array([int(round(h / dt)) for h in horizons])

    def score(p, **kw):
        kw = kw | ({"calibrated": False} if hasattr(p, "calibration") else {})
        return [forecast_errors(lambda a, st, h: p.forecast(a, st, horizon_s=h, commands="known", **kw),
                                r.arrays, start_rows(r.arrays, int(steps.max()), args.start_every_s), steps)
                for r in val_runs]

    per = {("dynamic", "known"): score(DynamicPredictor(v, residual_config=cfg.residual)),
           ("one_step", "known"): score(base)}
    if base.hull is not None:  # the physics with the hull correction alone (the nets' output set to zero)
        z = copy.deepcopy(base)
        z.ensemble.weights[4][:] = 0.0
        z.ensemble.weights[5][:] = 0.0
        z.ensemble.y_mean = np.zeros(3)
        per[("hull_only", "known")] = score(z)
    rows, importance = [], {}
    for name, kw in parse_variants(args.variants).items():
        ms = replace(cfg.multistep, **kw)
        t0 = time.perf_counter()
        q, hist = fine_tune(base, logs, ms, cfg.train_row_stride)
        secs = time.perf_counter() - t0
        if args.save_models:
            q.save(args.out / f"model_{name}.npz")
        per[(name, "known")] = score(q)
        e = error_table(per, val_runs, horizons)
        rows.append(summary(e, name, secs, hist, kw))
        print(json.dumps(rows[-1]), flush=True)
        if args.with_command_guard:
            with_command_regime(q, logs, cfg.train_row_stride)
            per[(name + "+cg", "known")] = score(q)
            e = error_table(per, val_runs, horizons)
            rows.append(summary(e, name + "+cg", secs, hist, kw))
            print(json.dumps(rows[-1]), flush=True)
            q.command_regime, q.command_guard = None, False
        if args.permutation:
            imp = importance[name] = permutation_importance(q, score, horizons, val_runs)
            atomic_write(args.out / importance_name(name), lambda fh: fh.write(imp.to_csv(index=False).encode()))
            print(imp.round(4).to_string(), flush=True)
    run_errors = error_table(per, val_runs, horizons)
    rows = [summary(run_errors, m, 0.0, {}, {}) for m in ("one_step", "hull_only") if (m, "known") in per] + rows
    errors, table = write_outputs(args.out, args.results, run_errors, rows, command_line("esso_multistep.py", argv),
                                  importance)
    d = errors[(errors.state == "distance_m")].pivot_table(index=["kind", "model"], columns="horizon_s",
                                                           values="mae", sort=False)
    print(d.round(3).to_string(), table.drop(columns=["history"]).to_string(), sep="\n")
    return 0


def with_command_regime(q, logs, stride):
    """Fit the command-regime guard of the fine-tuned hybrid ``q`` on the held-back end of its logs (in place),
    as :meth:`HybridPredictor.fit` does (the weights of all the held-back rows; the spread itself is not
    recalibrated here: the screen scores errors only). Sets ``q.command_guard``, without which the fit
    leaves the weights out; the caller turns both off again."""
    cal = q.calibration_config
    cuts, masks = q._held_back(logs, cal, True)
    q.command_guard = True
    q._fit_command_guard(logs, cuts, masks, cal, True, stride)
    if q.command_regime is None:
        raise RuntimeError("with_command_regime: no command-regime weights were fitted")


def permutation_importance(p, score, horizons, runs, seed: int = 0):
    """Rise of the pooled validation errors when one feature's values are permuted across the
    starts at every step of the rollouts (guard off, so that only the nets see the permuted
    input). A feature whose permutation does not raise the error is a candidate for removal."""
    import pandas as pd

    from hybridship.evaluation.manoeuvre import error_table

    def pooled(per):
        e = error_table({("m", "known"): per}, runs, horizons)
        e = e[(e.kind == "all") & (e.horizon_s == max(horizons))]
        return {s: float(e[e.state == s].mae.iloc[0]) for s in ("distance_m", "heading_deg")}

    ref = pooled(score(p, guard=False))
    out = [{"feature": "(none)", "dist30_m": ref["distance_m"], "head30_deg": ref["heading_deg"],
            "d_dist30_m": 0.0, "d_head30_deg": 0.0}]
    ens = p.ensemble
    orig = type(ens).predict_members
    for k, f in enumerate(p.residual_config.features):
        rng = np.random.default_rng(seed)

        def permuted(X, k=k, rng=rng):
            X = np.array(X, copy=True)
            X[..., k] = X[:, rng.permutation(X.shape[1]), k]
            return orig(ens, X)

        ens.predict_members = permuted
        try:
            r = pooled(score(p, guard=False))
        finally:
            del ens.predict_members
        out.append({"feature": f, "dist30_m": r["distance_m"], "head30_deg": r["heading_deg"],
                    "d_dist30_m": r["distance_m"] - ref["distance_m"],
                    "d_head30_deg": r["heading_deg"] - ref["heading_deg"]})
    return pd.DataFrame(out)


def summary(e, name, secs, hist, kw) -> dict:
    """Pooled 30-s figures of one variant against the physics (validation runs, logged
    commands known, as :func:`_results.cells_below` counts them)."""
    from _results import cells_below

    def mae(model, state):
        s = e[(e.model == model) & (e.state == state) & (e.kind == "all") & (e.commands == "known")]
        return float(s[s.horizon_s == s.horizon_s.max()].mae.iloc[0])

    d, hd = mae(name, "distance_m"), mae(name, "heading_deg")
    return {"variant": name, "settings": json.dumps(kw), "dist30_m": round(d, 4), "head30_deg": round(hd, 3),
            "dist_ratio": round(d / mae("dynamic", "distance_m"), 3),
            "head_ratio": round(hd / mae("dynamic", "heading_deg"), 3), "cells_below": cells_below(e, name),
            "train_s": round(secs, 1),
            "history": json.dumps({k: hist[k] for k in ("iterations", "best_val_loss") if k in hist}
                                  | {"val_loss": [round(x, 5) for x in hist.get("val_loss", [])]})}


if __name__ == "__main__":
    sys.exit(main())
