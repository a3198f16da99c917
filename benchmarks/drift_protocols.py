"""What the nets add to the environment estimator after a DP failure, under four training protocols.

For every test log, forecasts start at each of the first 20 samples after the shutdown
(the drift benchmark's protocol) and run 60 s with the commands held (rpm 0). Rows:

* ``physics``: the dynamic model alone (:class:`~hybridship.predictors.DynamicPredictor`);
* ``estimator``: physics + the environment estimator (+ the hull's yaw moment in a drift
  where ``fit`` learned one), nets off (``forecast(nets=False)``);
* ``hybrid``: the default hybrid (estimator + guarded nets, which stay off after a failure);
* ``hybrid_nets_after_stop``: the same model with its nets allowed after the failure (the
  guard still applies: nets trained on station keeping alone are off once the thrust stops).

Protocols:

* ``paper``: trained on the DP parts of all logs, tested on their drifts; nothing of a
  failure is seen (``drift_hull=False``: the forecasts learn nothing from the drifts they
  are scored on);
* ``fleet_default``: leave one log out; the default ``fit`` on the other logs: the nets and
  the estimator on their DP parts, the hull's yaw moment in a drift
  (:mod:`hybridship.residual.drift_hull`) and the spread after a failure from their
  failures; tested on the held-out log's drift;
* ``fleet``: leave one log out; trained on the *whole* other logs (their earlier failures
  and drifts included: the nets see the drift regime, the estimator learns the thrust
  error at their thrust stops (kept only where it carries over to their failures left out
  of the learning), and the hull's yaw moment in a drift is learned from their failures),
  tested on the held-out log's drift;
* ``sim_pretrain``: trained on the whole logs of ``--sim-scenarios`` drifts simulated by the
  project's own simulator (perturbed true vessel, weather varied by seed) together with the
  DP parts of the test set's own logs (joint training: the ensemble has no warm start, so
  "pre-training then fine-tuning" is done as one fit on both), tested on the drifts; the
  hull's yaw moment in a drift is learned from the simulated failures.

Writes ``protocols.csv`` (``data,protocol,model,state,window,horizon_s,mae``),
``protocols.md`` (the 60-s cells as ratios to physics) and ``decisions.md`` (per fit: the
fold's held-out log, and what ``fit`` learned from the training logs' failures and whether
it kept it, as ``training_info`` records it: the hull's yaw moment in a drift and the thrust
error at the thrust stops; then per data set how many fits kept each) to ``--out``.

Example::

    python benchmarks/drift_protocols.py --out docs/results/drift-protocols
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out
from hybridship.evaluation import metrics
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.predictors.hybrid import THRUST_PRIOR_MIN_FAILURES
from hybridship.residual.drift_hull import MIN_FAILURES as DRIFT_HULL_MIN_FAILURES
from hybridship.residual.ensemble import EnsembleConfig

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"
HORIZONS = (15, 30, 45, 60)


def _errors(pred, arrays, **kw):
    all_h = tuple(float(h) for h in range(1, 61))
    pick = [all_h.index(float(h)) for h in HORIZONS]
    p, t, _ = metrics.drift_forecasts(pred, arrays, n_intervals=20, horizons_s=all_h, **kw)
    return metrics.absolute_errors(p[:, pick], t[:, pick])


def _score(rows, data, protocol, hybrid, tests):
    dyn = DynamicPredictor(hybrid.model.vessel)
    for name, pred, kw in (("physics", dyn, {}), ("estimator", hybrid, {"nets": False}), ("hybrid", hybrid, {}),
                           ("hybrid_nets_after_stop", hybrid, {"nets_after_stop": True})):
        errs = {name: [_errors(pred, a, **kw) for a in tests]}
        long = metrics.error_table(errs, horizons_s=HORIZONS)
        long.insert(0, "protocol", protocol)
        long.insert(0, "data", data)
        rows.append(long)


def run(data: str, logs, sim_logs, ens: EnsembleConfig, rows: list, say=print, names=None,
        decisions: list | None = None):
    """Fit and score the four protocols on one data set.

    Parameters
    ----------
    data : str
        Name of the data set (the ``data`` column).
    logs : list of DataFrame
        Its logs, each with a failure.
    sim_logs : list of DataFrame
        The simulated logs of ``sim_pretrain``.
    ens : EnsembleConfig
        The nets' ensemble.
    rows : list
        Receives the error tables (long format, one DataFrame per fit and model).
    say : callable
        Progress and what each fit learned from the training logs' failures.
    names : list of str, optional
        The logs' names, for the held-out log of each fold (default: their indices).
    decisions : list, optional
        Receives one :func:`decision` per fit, in the order of the fits.
    """
    vessel = "gunnerus"
    names = [str(k) for k in range(len(logs))] if names is None else list(names)
    decisions = [] if decisions is None else decisions
    arrays = [as_log_arrays(x, HybridPredictor(vessel).model.vessel) for x in logs]
    say(f"[{data}] paper protocol: train on the DP parts of {len(arrays)} logs")
    hp = HybridPredictor(vessel, ensemble_config=ens, drift_hull=False).fit(arrays, dp_only=True)
    decisions.append(decision(data, "paper", "all", hp))
    _score(rows, data, "paper", hp, arrays)
    for protocol, dp_only in (("fleet_default", True), ("fleet", False)):
        say(f"[{data}] {protocol} protocol: leave one log out, train on the other logs (dp_only={dp_only})")
        for k in range(len(arrays)):
            train = [a for i, a in enumerate(arrays) if i != k]
            hp = HybridPredictor(vessel, ensemble_config=ens).fit(train, dp_only=dp_only)
            _say_learned(say, f"  {k}: ", hp)
            decisions.append(decision(data, protocol, names[k], hp))
            _score(rows, data, protocol, hp, [arrays[k]])
    say(f"[{data}] sim_pretrain protocol: {len(sim_logs)} simulated drifts + own DP parts")
    own_dp = [a for a in arrays]
    hp = HybridPredictor(vessel, ensemble_config=ens)
    # whole simulated logs, DP rows only of the own logs: mark the own logs' drift rows unusable
    # by fitting on the simulated logs whole and on the own logs' DP part (dp_only per log).
    sim_arrays = [as_log_arrays(x, hp.model.vessel) for x in sim_logs]
    hp.fit(sim_arrays + [_dp_part(a) for a in own_dp], dp_only=False)
    _say_learned(say, "  ", hp)
    decisions.append(decision(data, "sim_pretrain", "all", hp))
    _score(rows, data, "sim_pretrain", hp, arrays)


def _say_learned(say, prefix: str, hp):
    """What the fit learned from the training logs' failures, and whether it was kept."""
    say(f"{prefix}hull's yaw moment in a drift {hp.training_info.get('drift_hull', 'not fitted')}")
    if "wave_yaw_load" in hp.training_info:
        say(f"{prefix}yaw load turned with the waves {hp.training_info['wave_yaw_load']}")
    if "thrust_error_prior" in hp.training_info:
        say(f"{prefix}thrust error learned at the stops {hp.training_info['thrust_error_prior']}")


def decision(data: str, protocol: str, test_log: str, hp) -> dict:
    """What a fit learned from its training logs' failures: the fit's ``training_info``
    entries ``drift_hull``, ``thrust_error_prior`` and ``wave_yaw_load`` (None where absent),
    whether the hull's yaw moment in a drift was on (``uses_drift_hull``), whether the yaw load
    turns with the waves after a failure (``turns_yaw_load``) and whether only the DP parts were
    read; ``test_log`` is the log it is scored on (``all``: every log of the set)."""
    info = hp.training_info
    return {"data": data, "protocol": protocol, "test_log": test_log, "drift_hull_on": bool(hp.uses_drift_hull),
            "dp_only": bool(info.get("calibration", {}).get("dp_only", False)),
            "drift_hull": info.get("drift_hull"), "thrust_error_prior": info.get("thrust_error_prior"),
            "wave_yaw_load": info.get("wave_yaw_load"), "turns_yaw_load": bool(hp.turns_yaw_load)}


def _hull_cell(d: dict) -> str:
    """The hull's yaw moment in a drift of a :func:`decision`, as one table cell."""
    hull = d["drift_hull"]
    if hull is None:
        return "off (`drift_hull=False`)" if not d["drift_hull_on"] else \
            f"not chosen (fewer than {DRIFT_HULL_MIN_FAILURES} failures)"
    cell = (f"{hull['munk_multiple']:g} x Munk on {hull['n_failures']} failures, "
            f"{'kept' if hull['adopted'] else 'not kept'}: heading {hull['error_zero_deg']:.2f} deg without it, "
            f"{hull['error_deg']:.2f} with it, ")
    if hull["error_left_out_deg"] is None:
        return cell + "no left-out check"
    cell += f"{hull['error_left_out_deg']:.2f} with it chosen on the others (left out)"
    if hull.get("p_value") is not None:
        cell += f", {hull['n_left_out_gains']} of {hull['n_failures']} better, signed-rank p = {hull['p_value']:.3g}"
    return cell


def _thrust_cell(d: dict) -> str:
    """The thrust error learned at the thrust stops of a :func:`decision`, as one table cell."""
    prior = d["thrust_error_prior"]
    if prior is None:
        return "not learned (DP parts only)" if d["dp_only"] else "not learned (no thrust stop read)"
    mean = ", ".join(f"{m:+.2f}" for m in prior["learned_mean"])
    cell = f"{'kept' if prior['kept'] else 'not kept'}: learned ({mean}) with {prior['n_failures']} failures; "
    if "position_error_m" not in prior:
        return cell + f"fewer than the {THRUST_PRIOR_MIN_FAILURES} the check needs"
    (pc, pl), (hc, hl) = prior["position_error_m"], prior["heading_error_deg"]
    return cell + (f"left-out failures: position {pl:.3f} m against {pc:.3f} m, heading {hl:.2f} deg against "
                   f"{hc:.2f} deg with the configured prior, signed-rank p = {prior['position_p_value']:.3g} "
                   f"and {prior['heading_p_value']:.3g}")


def _wave_yaw_cell(d: dict) -> str:
    """The yaw load after a failure of a :func:`decision` (held, or turned with the waves), as one
    table cell, with the evidence where the fit chose it."""
    what = "turned with the waves" if d.get("turns_yaw_load") else "held"
    wave = d.get("wave_yaw_load")
    if wave is None:
        return what + ("" if d["drift_hull_on"] else " (`drift_hull=False`: nothing learned from failures)")
    if wave.get("p_value") is None:
        return f"{what} ({wave['n_failures']} failures, fewer than {DRIFT_HULL_MIN_FAILURES})"
    return (f"{what}: heading {wave['held_deg']:.2f} deg held, {wave['turned_deg']:.2f} turned on "
            f"{wave['n_failures']} failures, {wave['n_gains']} gain, signed-rank p = {wave['p_value']:.3g}")


def decisions_markdown(decisions: list) -> str:
    """The :func:`decision` of every fit as a Markdown table, then per data set how many fits
    kept the thrust error learned at the stops and the hull's yaw moment in a drift."""
    tab = pd.DataFrame([{"data": d["data"], "protocol": d["protocol"], "fold: test log": d["test_log"],
                         "hull's yaw moment in a drift": _hull_cell(d),
                         "thrust error learned at the thrust stops": _thrust_cell(d),
                         "yaw load after a failure": _wave_yaw_cell(d)} for d in decisions])
    md = ["What each fit learned from its training logs' failures, and whether it kept it "
          "(`training_info`; `all`: one fit, scored on every log of the set).", "", markdown_table(tab), ""]
    for data in dict.fromkeys(d["data"] for d in decisions):
        mine = [d for d in decisions if d["data"] == data]
        prior = [d["thrust_error_prior"] for d in mine if d["thrust_error_prior"] is not None]
        hull = [d["drift_hull"] for d in mine if d["drift_hull"] is not None]
        md.append(f"* {data}: thrust error kept in {sum(p['kept'] for p in prior)} of {_fits(len(prior))} that "
                  f"learned it; hull's yaw moment in a drift kept in {sum(h['adopted'] for h in hull)} of "
                  f"{_fits(len(hull))} that chose one; yaw load turned with the waves in "
                  f"{sum(bool(d.get('turns_yaw_load')) for d in mine)} of {_fits(len(mine))}.")
    return "\n".join(md) + "\n"


def _fits(n: int) -> str:
    """``"1 fit"``, ``"2 fits"``."""
    return f"{n} fit" if n == 1 else f"{n} fits"


def _dp_part(a):
    """The rows of a log before its first shutdown (LogArrays; every per-row array cut,
    :meth:`~hybridship.logs.io.LogArrays.rows`)."""
    off = np.flatnonzero(a.dp_active == 0)
    end = int(off[0]) if off.size else len(a.time_s)
    return a.rows(slice(0, end))


def ratio_table(df: pd.DataFrame) -> pd.DataFrame:
    """60-s cells (first 5 / first 20) as ratios to physics, per data set, protocol and model."""
    d = df[df.horizon_s == 60].groupby(["data", "protocol", "model", "state", "window"]).mae.mean()
    out = []
    for (data, protocol), g in d.groupby(level=[0, 1]):
        phys = g.xs("physics", level=2)
        for model in ("estimator", "hybrid", "hybrid_nets_after_stop"):
            r = (g.xs(model, level=2) / phys).droplevel([0, 1])
            row = {"data": data, "protocol": protocol, "model": model}
            for state in metrics.STATES:
                row[state] = f"{r[(state, 5)]:.2f}/{r[(state, 20)]:.2f}"
            out.append(row)
    return pd.DataFrame(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--members", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sim-scenarios", type=int, default=6, help="simulated drifts of sim_pretrain, 1-20 (default 6)")
    ap.add_argument("--embedded", type=int, default=3,
                    help="embedded scenarios as a second data set, 0 or 2-20 (0: none; default 3)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    from hybridship.sim.scenario import embedded_scenarios

    for flag, value, low in (("--sim-scenarios", args.sim_scenarios, 1), ("--embedded", args.embedded, 0)):
        if not low <= value <= 20:          # the simulator's embedded scenarios: at most 20
            ap.error(f"{flag}: expected {low}-20, got {value}")
    if args.embedded == 1:      # its leave-one-out folds were fitted on no log: fit()'s traceback mid-run
        ap.error("--embedded: expected 0 or 2-20 (leave one log out needs two logs), got 1")
    if not args.embedded and not TRUTHSIM.is_dir():     # nothing to score: pandas' 'No objects to concatenate'
        ap.error(f"--embedded: expected 2-20, as {TRUTHSIM} is not found, got 0")
    try:
        ens = EnsembleConfig(n_members=args.members, seed=args.seed)
    except ValueError as exc:
        ap.error(f"--members / --seed: {exc}")
    sim_logs = [s.log for s in embedded_scenarios(args.sim_scenarios, args.seed + 1000)]
    rows: list = []
    decisions: list = []
    if TRUTHSIM.is_dir():
        files = log_files(TRUTHSIM)
        run("truthsim-dev", [pd.read_csv(f) for f in files], sim_logs, ens, rows, names=[f.name for f in files],
            decisions=decisions)
    else:
        print(f"skipping truthsim-dev: {TRUTHSIM} not found", file=sys.stderr)
    if args.embedded:
        scen = embedded_scenarios(args.embedded, args.seed)
        run("embedded", [s.log for s in scen], sim_logs, ens, rows, names=[s.name for s in scen],
            decisions=decisions)
    df = pd.concat(rows, ignore_index=True)
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "protocols.csv",
                 lambda fh: fh.write(df.to_csv(index=False, float_format="%.6g").encode("utf-8")))
    tab = ratio_table(df)
    md = ["What the nets add after a DP failure, by training protocol.", "",
          "Mean absolute error at 60 s as a ratio to physics alone, first 5 / first 20 intervals "
          "(below 1: better than physics).", "", markdown_table(tab)]
    atomic_write(args.out / "protocols.md", lambda fh: fh.write(("\n".join(md) + "\n").encode("utf-8")))
    dec = decisions_markdown(decisions)
    atomic_write(args.out / "decisions.md", lambda fh: fh.write(dec.encode("utf-8")))
    print("\n".join(md))
    print(dec, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
