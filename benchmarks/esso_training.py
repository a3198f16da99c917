"""Esso Osaka: hybrid variants (training mode, features, guard) on a validation split or the test runs.

Selection (the test runs play no part)::

    python benchmarks/esso_training.py --out out/esso-training-val

splits the benchmark's *training* runs (``out/esso-osaka/split/train``, made by
``benchmarks/esso_osaka.py``) again, seed 1, as ``benchmarks/esso_validation.py`` does,
trains every variant on the fitting part and scores it on the validation part. The
comparison on the benchmark's own split (after the choice was made)::

    python benchmarks/esso_training.py --test-split --out out/esso-training-test

Variants share the ensemble size, seed, calibration and features (the six model-predicted
velocities and accelerations) unless their name says otherwise:
``one_step`` / ``multi_step`` (training mode), ``_h<s>``, ``_b<n>``, ``_i<n>``, ``_v<n>``
(multi-step horizon, batch of starts, iterations, validation starts; ``_lr<x>``: Adam's step;
``_ema<x>``: the weights' moving average, ``MultiStepConfig.weight_average``; otherwise
``MultiStepConfig()``), ``_m<n>`` / ``_sd<n>`` (ensemble members / seed; otherwise the
benchmark's), ``_wd<x>`` / ``_in<x>`` (the one-step fit's weight decay,
``EnsembleConfig.weight_decay``, and the noise on its standardised inputs,
``EnsembleConfig.input_noise_std``; otherwise the benchmark's), ``+cmd`` (all command-aware features added), ``+mem`` / ``+mem<s>`` (the command-memory
features added, with the default time constant or ``<s>`` seconds; ``+memang`` /
``+memang<s>``: the angle's alone),
``_abs`` (absolute-error loss), ``_lead`` (loss weighted by lead time), ``_own`` (each member
trained on its own rollouts, ``MultiStepConfig.member_loss``), ``_hl<m>`` (heading
length of the loss), ``_c<s>`` (curriculum from a ``<s>``-second horizon), ``_ad<x>`` (the
weights pulled towards their one-step values, ``MultiStepConfig.anchor_decay``),
``+rate`` (only the command rates added), ``+cg`` (command-regime guard; off otherwise, whatever
the benchmark default), ``+ws`` (with ``--with-wind-spread``: the same nets with 8 wind
futures in the spread, recalibrated; ``HybridPredictor(wind_samples=8)``), ``+hull`` / ``+hullms`` (the linear hull correction before the nets,
identified on the one-step residual / by a free-run fit), ``_th`` (the hull correction tuned
with the nets in multi-step training), ``+refit`` (after calibrating, the nets refitted on all
the training rows, ``CalibrationConfig.refit``), ``+wind`` (the wind forecast fitted on the
training runs' wind, ``wind_forecast="fit"``; held otherwise), ``+mirror`` (every fitting run
also trained on mirrored port to starboard, :func:`mirror_log`: a symmetry prior for the nets),
``+env`` (the environment estimator in place of the mean residual, its station-keeping
settings Froude-scaled to the model, :func:`froude_scaled_environment`), ``+prev`` (the
paper's previous-residual inputs added, the rest of its nine features), ``+load`` (the
actuator-load features added, :data:`~hybridship.residual.features.LOAD_FEATURES`).
Writes ``errors.csv``, ``coverage.csv`` and ``sharpness.csv`` (the manoeuvre benchmark's columns),
``timing.csv`` (training seconds) and ``tables.md`` (:func:`tables`: the command, the pooled
errors with commands known and the 30-s errors per kind), and prints the distance and
heading tables. ``--results`` also copies the five there (``--out`` holds the split's links
to the data, which stay out of the repository); ``--tables-only`` writes ``tables.md``
again from ``--out``'s ``errors.csv``, keeping the command it records. The committed runs::

    python benchmarks/esso_training.py --out out/esso-env-val --commands known \
        --variants "multi_step_h30_b64_i100_abs+cmd+cg+wind+mem,multi_step_h30_b64_i100_abs+cmd+cg+wind+mem+env,\
one_step+cmd+cg+wind+mem,one_step+cmd+cg+wind+mem+env" --results docs/results/esso-environment-estimator
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def mirror_log(a, vessel):
    """The log ``a`` (LogArrays) of ``vessel`` mirrored port to starboard about the body x axis.

    East, heading, sway, yaw rate, every angle command and the wind's direction change
    sign; north, surge and propeller speeds stay. That is the ship's motion seen in a
    mirror only when every actuator lies on the centre line and every fixed thruster
    pushes fore or aft (one off the line, or a tunnel thruster, would change sides or
    direction); such vessels are refused. The rest is assumed, not checked: a hull
    without coupling between surge and sway or yaw, wind coefficients symmetric about
    the centre line, and rudders with equal flow straightening on both sides. The Esso
    model's MMG rudder is not quite symmetric (gamma_R 0.395 / 0.640, the single screw's
    swirl), so a mirrored run is that of a symmetric ship, the assumption the variant tests.
    """
    import dataclasses

    for act in list(vessel.thrusters) + list(vessel.rudders):
        if act.y_m != 0.0:
            raise ValueError(f"mirror_log: {act.name}: y_m must be 0 (on the centre line) to mirror, "
                             f"got {act.y_m:g} m")
    for th in vessel.thrusters:
        if th.type == "tunnel" or (th.type == "fixed" and th.angle_deg % 180.0 != 0.0):
            raise ValueError(f"mirror_log: {th.name}: a thruster must push fore or aft or be an azimuth "
                             f"thruster to mirror, got type {th.type!r}"
                             + (f" at angle_deg {th.angle_deg:g}" if th.type == "fixed" else ""))
    eta, nu, wind = a.eta.copy(), a.nu.copy(), a.wind.copy()
    eta[:, 1:] *= -1.0
    nu[:, 1:] *= -1.0
    wind[:, 1] *= -1.0
    return dataclasses.replace(a, eta=eta, nu=nu, azimuth_rad=-a.azimuth_rad, wind=wind)


def froude_scaled_environment(vessel, reference="gunnerus", defaults=None):
    """The environment estimator's settings ``defaults`` (the package's when None; made for the
    ``reference`` vessel at full scale) Froude-scaled to ``vessel`` by the ratio of their Lpp:
    lengths by 1/lambda, speeds (the wind's too, as in the current prior's reference wind speed)
    and times by 1/sqrt(lambda), accelerations kept, yaw rates by
    sqrt(lambda), yaw accelerations by lambda; a random walk's intensity [per sqrt(s)] gains
    lambda^(1/4). The filter steps at 0.3 s on the Esso model (1 s scaled to 0.29 s, rounded to
    the 10-Hz rows). Settings without units (fractions, priors of thrust errors, the outlier
    gate) are kept."""
    from hybridship.residual.environment import EnvironmentConfig
    from hybridship.vessel import load_vessel

    lam = load_vessel(reference).particulars.L_pp_m / vessel.particulars.L_pp_m
    s = np.sqrt(lam)
    d = EnvironmentConfig() if defaults is None else defaults
    return EnvironmentConfig(**{**d.model_dump(), **dict(
        position_std_m=d.position_std_m / lam, velocity_std_m_s=d.velocity_std_m_s / s,
        yaw_rate_std_deg_s=d.yaw_rate_std_deg_s * s, yaw_accel_noise_rad_s2=d.yaw_accel_noise_rad_s2 * lam,
        current_prior_m_s=d.current_prior_m_s / s, load_yaw_prior_rad_s2=d.load_yaw_prior_rad_s2 * lam,
        current_walk_m_s=d.current_walk_m_s / np.sqrt(s), current_std_at_stop_m_s=d.current_std_at_stop_m_s / s,
        load_walk_m_s2=d.load_walk_m_s2 * np.sqrt(s), load_yaw_walk_rad_s2=d.load_yaw_walk_rad_s2 * lam * np.sqrt(s),
        load_walk_after_stop_m_s2=d.load_walk_after_stop_m_s2 * np.sqrt(s),
        load_yaw_walk_after_stop_rad_s2=d.load_yaw_walk_after_stop_rad_s2 * lam * np.sqrt(s),
        thrust_error_walk=d.thrust_error_walk * np.sqrt(s),
        wave_window_s=d.wave_window_s / s, variance_window_s=d.variance_window_s / s,
        filter_step_s=round(d.filter_step_s / s, 1), held_load_window_s=d.held_load_window_s / s,
        held_load_block_s=d.held_load_block_s / s, wave_axis_window_s=d.wave_axis_window_s / s,
        settle_s=d.settle_s / s, max_bridged_gap_s=d.max_bridged_gap_s / s,
        current_prior_max_m_s=d.current_prior_max_m_s / s,
        current_prior_wind_ref_m_s=None if d.current_prior_wind_ref_m_s is None else d.current_prior_wind_ref_m_s / s)})


_UNDERSCORE_TOKEN = r"_(?:(?:hl|h|b|in|i|v|c|ad|lr|ema|wd)\d+(?:\.\d+)?|(?:m|sd)\d+|abs|lead|own|th)"
_PLUS_TOKEN = r"\+(?:cmd|cg|wind|mirror|refit|hullms|hull|env|prev|rate|load|mem(?:ang)?(?:\d+(?:\.\d+)?)?)"


def check_variant_name(name: str) -> None:
    """Refuse a variant name with a token this script does not know (a typo would otherwise run
    another variant under the name asked for)."""
    import re

    head = re.match(r"(one_step|multi_step)(?=[_+]|$)", name)
    if head is None:
        raise SystemExit(f"error: variant {name!r}: must start with one_step or multi_step")
    rest = name[head.end():]
    tokens = re.findall(r"[_+][^_+]*", rest)
    bad = [t for t in tokens if not re.fullmatch(_UNDERSCORE_TOKEN if t[0] == "_" else _PLUS_TOKEN, t)]
    if bad:
        raise SystemExit(f"error: variant {name!r}: unknown token(s) {', '.join(bad)} (see the module docstring)")


def variants(cfg, names):
    """Unfitted hybrids by variant name."""
    from hybridship.forecast_inputs.wind import HELD_WIND
    from hybridship.predictors import HybridPredictor
    from hybridship.residual.features import (ALL_FEATURES, COMMAND_FEATURES, LOAD_FEATURES, MEMORY_FEATURES,
                                              PAPER_FEATURES)
    from hybridship.residual.multistep import MultiStepConfig
    from hybridship.vessel import load_vessel

    # a fixed base, whatever the benchmark's defaults are now: the six model-predicted
    # velocities and accelerations, one-step training, MultiStepConfig(), no command guard
    # and the wind held
    base_rc = replace(cfg.residual, features=ALL_FEATURES[:6])
    out = {}
    for name in names:
        check_variant_name(name)
        # environment="mean" as in the benchmark (the estimator's default is for station keeping)
        kw = dict(residual_config=base_rc, ensemble_config=cfg.ensemble, guard_quantile=cfg.guard_quantile,
                  environment="mean",
                  calibration_config=cfg.calibration, training="one_step", multistep_config=MultiStepConfig(),
                  command_guard="+cg" in name)
        if name.startswith("one_step"):
            kw["training"] = "one_step"
        elif name.startswith("multi_step"):
            kw["training"] = "multi_step"
        import re

        ms = {}
        for key, field, conv in (("h", "horizon_s", float), ("b", "batch_starts", int), ("i", "iterations", int),
                                 ("v", "max_val_starts", int), ("hl", "heading_length_m", float),
                                 ("c", "curriculum_start_s", float), ("ad", "anchor_decay", float),
                                 ("lr", "lr", float), ("ema", "weight_average", float)):
            m = re.search(rf"_{key}(\d+(?:\.\d+)?)", name)
            if m:
                ms[field] = conv(m.group(1))
        if "_abs" in name:
            ms["loss"] = "absolute"
        if "_lead" in name:
            ms["lead_weighting"] = "lead"
        if "_own" in name:
            ms["member_loss"] = "own"
        if "_th" in name:
            ms["tune_hull"] = True
        if "+refit" in name:
            kw["calibration_config"] = replace(cfg.calibration, refit=True)
        if "+hull" in name:
            kw["hull_correction"] = True
            kw["hull_fit"] = "multi_step" if "+hullms" in name else "one_step"
        if ms:
            kw["multistep_config"] = replace(MultiStepConfig(), **ms)
        for key, field in (("wd", "weight_decay"), ("in", "input_noise_std")):
            m = re.search(rf"_{key}(\d+(?:\.\d+)?)", name)
            if m:
                kw["ensemble_config"] = replace(kw["ensemble_config"], **{field: float(m.group(1))})
        for key, field in (("m", "n_members"), ("sd", "seed")):
            found = re.findall(rf"_{key}(\d+)(?=_|\+|$)", name)
            if len(found) > 1 or re.search(rf"_{key}\d+[^\d_+]", name):
                raise SystemExit(f"error: variant {name!r}: _{key}<n> needs one whole number, once")
            if found:
                kw["ensemble_config"] = replace(kw["ensemble_config"], **{field: int(found[0])})
        kw["wind_forecast"] = "fit" if "+wind" in name else HELD_WIND
        if "+cmd" in name:
            extra = tuple(f for f in COMMAND_FEATURES if f not in base_rc.features)
            kw["residual_config"] = replace(base_rc, features=tuple(base_rc.features) + extra)
        if "+rate" in name:
            kw["residual_config"] = replace(base_rc, features=tuple(base_rc.features)
                                            + tuple(f for f in COMMAND_FEATURES if "rate" in f))
        if "+prev" in name:
            rc = kw["residual_config"]
            kw["residual_config"] = replace(rc, features=tuple(rc.features) + PAPER_FEATURES[6:])
        mem = re.search(r"\+mem(ang)?(\d+(?:\.\d+)?)?", name)
        if mem:
            rc = kw["residual_config"]
            added = MEMORY_FEATURES[1:] if mem.group(1) else MEMORY_FEATURES
            kw["residual_config"] = replace(rc, features=tuple(rc.features) + added,
                                            **({"command_memory_s": float(mem.group(2))} if mem.group(2) else {}))
        if "+load" in name:
            rc = kw["residual_config"]
            kw["residual_config"] = replace(rc, features=tuple(rc.features) + LOAD_FEATURES)
        if "+env" in name:
            env = froude_scaled_environment(load_vessel("esso_osaka_model"))
            kw.update(environment="estimator", environment_config=env,
                      environment_window_s=3.0 * env.held_load_window_s)
        out[name] = HybridPredictor("esso_osaka_model", **kw)
    return out


def with_command_guard(p, logs, stride):
    """A copy of the fitted hybrid ``p`` with the command-regime guard fitted and the spread recalibrated."""
    import copy

    q = copy.deepcopy(p)
    q.command_guard = True
    cal = q.calibration_config
    cuts, masks = q._held_back(logs, cal, True)
    folds, split_info = q._fit_command_guard(logs, cuts, masks, cal, True, stride)   # as fit cross-fits them
    old = {k: v for k, v in q.training_info.get("calibration", {}).items()
           if k not in ("command_regime_split", "cross_fit_rows")}
    q.training_info["calibration"] = {**old, **split_info,
                                      "n_starts": q._calibrate_modes(logs, folds, cal, True)}
    if q.command_regime is not None:
        print("command-regime weights:", np.round(q.command_regime.weights, 2).tolist(),
              "held-back rows:", q.command_regime.n_held.tolist(), flush=True)
    return q


def with_wind_spread(p, logs, samples: int = 8):
    """A copy of the fitted hybrid ``p`` with ``samples`` wind futures in its spread (the wind
    forecast's error paths on its training rows) and the spread recalibrated: the same nets."""
    import copy

    q = copy.deepcopy(p)
    q.wind_samples = samples
    cal = q.calibration_config
    cuts, masks = q._held_back(logs, cal, True)
    q.training_info["wind_spread"] = q._fit_wind_error_paths(logs, cuts, cal, True)
    # as fit: with the command guard, each part's starts with the weights of the other part
    folds, _ = q._fit_command_guard(logs, cuts, masks, cal, True, q.training_info["row_stride"])
    q._calibrate_modes(logs, folds, cal, True)
    return q


#: Files a run writes to ``--out`` and ``--results`` copies.
RESULT_FILES = ("errors.csv", "coverage.csv", "sharpness.csv", "timing.csv", "tables.md")


def tables(errors, command: str) -> str:
    """``tables.md``: the command that made ``errors``, the pooled distance error at every
    horizon and the 30-s heading error per model with the kind x horizon cells below the
    physics (``dynamic``), and the 30-s errors per kind with the pooled ratios to the
    physics; logged commands known."""
    import pandas as pd

    from _results import cells_below, kind_table
    from hybridship.fileio import markdown_table

    e = errors[(errors["commands"] == "known") & (errors["kind"] == "all")]
    if e.empty:
        return f"Command: `{command}`\n\nNo rows with the logged commands known (see errors.csv).\n"
    pooled = e.pivot_table(index="model", columns=["state", "horizon_s"], values="mae", sort=False)
    horizons = sorted(e["horizon_s"].unique())
    rows = [[m, *(f"{pooled.loc[m, ('distance_m', h)]:.3f}" for h in horizons),
             f"{pooled.loc[m, ('heading_deg', horizons[-1])]:.2f}",
             "" if m == "dynamic" else cells_below(errors, m)] for m in dict.fromkeys(e["model"])]
    pooled_md = markdown_table(pd.DataFrame(rows, columns=[
        "model", *(f"{h:g} s (m)" for h in horizons), f"heading {horizons[-1]:g} s (deg)",
        "cells below physics"]))
    md = [f"Command: `{command}`", "", "Validation runs (or the test runs with `--test-split`), logged commands "
          "known. Pooled mean distance error at every horizon, the heading error at the last, and the kind x "
          "horizon cells where the distance error is below the physics (`dynamic`):", "", pooled_md, "",
          "30-s distance [m] / heading [deg] per kind and pooled, with the pooled ratios to the physics:", "",
          kind_table(errors, "dynamic")]
    return "\n".join(md) + "\n"


def tables_only(out: Path, results: Path | None) -> int:
    """Render ``out/tables.md`` again from ``out/errors.csv``, with the command of the run that
    wrote them (its first line), and copy the result files to ``results``; no new run."""
    from _results import tables_again

    return tables_again(out, results, ["errors.csv"], tables, RESULT_FILES)


def print_tables(errors, coverage, sharpness, modes) -> None:
    """Print the distance and heading errors per kind, the 2-sigma coverage and the interval score."""
    for state in ("distance_m", "heading_deg"):
        d = errors[errors.state == state].pivot_table(index=["commands", "kind", "model"], columns="horizon_s",
                                                      values="mae", sort=False)
        print(f"{state}:\n{d.round(3).to_string()}")
    c = coverage[coverage.kind == "all"].pivot_table(index=["commands", "model", "sigma"], columns="horizon_s",
                                                     values="coverage", sort=False)
    print(f"coverage (all kinds):\n{c.round(3).to_string()}")
    sh = sharpness[sharpness.commands == modes[0]].pivot_table(index=["kind", "model"], columns="horizon_s",
                                                              values="interval_score_m", sort=False)
    print(f"2-sigma interval score [m], commands {modes[0]}:\n{sh.round(3).to_string()}")


def main(argv=None) -> int:
    import pandas as pd
    import torch

    from _results import check_out, command_line, parse_horizons, publish, validation_dirs
    from hybridship.fileio import atomic_write
    from hybridship.evaluation.manoeuvre import (COMMAND_MODES, ManoeuvreConfig, coverage_table, error_table, forecast_errors,
                                      load_runs, make_predictors, sharpness_table, start_rows)
    from hybridship.vessel import load_vessel

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", type=Path, default=ROOT / "out" / "esso-osaka" / "split",
                    help="the benchmark's split (default out/esso-osaka/split)")
    ap.add_argument("--test-split", action="store_true",
                    help="score on the benchmark's test runs (after selection) instead of a validation split")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "esso-training-val")
    ap.add_argument("--variants", default="one_step,multi_step")
    ap.add_argument("--commands", default="known", help="command modes to score (comma-separated)")
    ap.add_argument("--horizons-s", default="5,10,20,30")
    ap.add_argument("--with-command-guard", action="store_true",
                    help="also score every variant with the command-regime guard fitted on its nets (suffix +cg)")
    ap.add_argument("--with-wind-spread", action="store_true",
                    help="also score every variant with 8 wind futures in its spread, recalibrated, the same nets "
                         "(suffix +ws)")
    ap.add_argument("--results", type=Path, help="also copy the result files (no data) here: " + ", ".join(RESULT_FILES))
    ap.add_argument("--tables-only", action="store_true",
                    help="write tables.md again from --out's errors.csv (and copy the result files to --results), "
                         "keeping the command line it records; nothing is trained")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    check_out(ap, args.results, option="--results")
    if args.tables_only:
        return tables_only(args.out, args.results)
    horizons = parse_horizons(ap, args.horizons_s)
    modes = args.commands.split(",")
    if not set(modes) <= set(COMMAND_MODES):        # a misspelt mode was dropped without a word
        ap.error(f"--commands: expected modes among {', '.join(COMMAND_MODES)}, got {args.commands!r}")
    torch.set_num_threads(1)
    if not (args.split / "train").is_dir():          # checked before any variant is built
        print(f"error: {args.split / 'train'}: not found; run benchmarks/esso_osaka.py first", file=sys.stderr)
        return 2
    if args.test_split:
        fit_dir, val_dir = args.split / "train", args.split / "test"
    elif (dirs := validation_dirs(args.split, args.out / "split")) is None:
        return 2
    else:
        fit_dir, val_dir = dirs
    v = load_vessel("esso_osaka_model")
    cfg = ManoeuvreConfig()
    cfg = replace(cfg, calibration=replace(cfg.calibration, horizon_s=max(horizons)))
    fit_runs, val_runs = load_runs(fit_dir, v), load_runs(val_dir, v)
    models = {"dynamic": make_predictors(v, cfg)["dynamic"]} | variants(cfg, args.variants.split(","))
    dt = float(np.median(np.diff(val_runs[0].arrays.time_s)))
    steps = np.array([int(round(h / dt)) for h in horizons])
    if args.with_command_guard:
        # the same nets with the command-regime guard fitted afterwards (no retraining)
        models = {k: models[k] for k in models} | {f"{k}+cg": None for k in models
                                                   if k != "dynamic" and "+cg" not in k}
    if args.with_wind_spread:
        models = models | {f"{k}+ws": None for k in models if k != "dynamic" and "+ws" not in k}

    def training_logs(name):
        logs = [r.arrays for r in fit_runs]
        return logs + [mirror_log(a, v) for a in logs] if "+mirror" in name else logs

    per, per_z, per_sd, timing = {}, {}, {}, []
    for name, p in models.items():
        t0 = time.perf_counter()
        if p is None and name.endswith("+ws"):
            p = models[name] = with_wind_spread(models[name[:-3]], training_logs(name))
        elif p is None:
            p = models[name] = with_command_guard(models[name[:-3]], training_logs(name), cfg.train_row_stride)
        elif name != "dynamic":
            p.fit(training_logs(name), row_stride=cfg.train_row_stride)
        timing.append({"model": name, "train_s": time.perf_counter() - t0})
        print(f"{name}: trained in {timing[-1]['train_s']:.0f} s", flush=True)
        for mode in modes:
            res = [forecast_errors(lambda a, st, h: p.forecast(a, st, horizon_s=h, commands=mode), r.arrays,
                                   start_rows(r.arrays, int(steps.max()), cfg.start_every_s), steps, return_std=True)
                   for r in val_runs]
            per[(name, mode)] = [e for e, _, _ in res]
            if name != "dynamic":
                per_z[(name, mode)] = [z for _, z, _ in res]
                per_sd[(name, mode)] = [sd for _, _, sd in res]
    errors = error_table(per, val_runs, horizons)
    coverage = coverage_table(per_z, val_runs, horizons)
    sharpness = sharpness_table(per, per_sd, val_runs, horizons)
    args.out.mkdir(parents=True, exist_ok=True)
    text = tables(errors, command_line("esso_training.py", argv))
    for fname, df in (("errors.csv", errors), ("coverage.csv", coverage), ("sharpness.csv", sharpness),
                      ("timing.csv", pd.DataFrame(timing))):
        atomic_write(args.out / fname, lambda fh, df=df: fh.write(df.to_csv(index=False).encode()))
    atomic_write(args.out / "tables.md", lambda fh: fh.write(text.encode()))
    publish(args.out, args.results, RESULT_FILES)
    print(f"scored on: {', '.join(r.name for r in val_runs)}")
    print_tables(errors, coverage, sharpness, modes)
    print(text)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
