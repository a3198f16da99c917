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

Writes ``protocols.csv`` (``data,protocol,model,state,window,horizon_s,mae``) and
``protocols.md`` (the 60-s cells as ratios to physics) to ``--out``.

Example::

    python benchmarks/drift_protocols.py --out docs/results/drift-protocols
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from hybridship.evaluation import metrics
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
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


def run(data: str, logs, sim_logs, ens: EnsembleConfig, rows: list, say=print):
    vessel = "gunnerus"
    arrays = [as_log_arrays(x, HybridPredictor(vessel).model.vessel) for x in logs]
    say(f"[{data}] paper protocol: train on the DP parts of {len(arrays)} logs")
    hp = HybridPredictor(vessel, ensemble_config=ens, drift_hull=False).fit(arrays, dp_only=True)
    _score(rows, data, "paper", hp, arrays)
    for protocol, dp_only in (("fleet_default", True), ("fleet", False)):
        say(f"[{data}] {protocol} protocol: leave one log out, train on the other logs (dp_only={dp_only})")
        for k in range(len(arrays)):
            train = [a for i, a in enumerate(arrays) if i != k]
            hp = HybridPredictor(vessel, ensemble_config=ens).fit(train, dp_only=dp_only)
            _say_learned(say, f"  {k}: ", hp)
            _score(rows, data, protocol, hp, [arrays[k]])
    say(f"[{data}] sim_pretrain protocol: {len(sim_logs)} simulated drifts + own DP parts")
    own_dp = [a for a in arrays]
    hp = HybridPredictor(vessel, ensemble_config=ens)
    # whole simulated logs, DP rows only of the own logs: mark the own logs' drift rows unusable
    # by fitting on the simulated logs whole and on the own logs' DP part (dp_only per log).
    sim_arrays = [as_log_arrays(x, hp.model.vessel) for x in sim_logs]
    hp.fit(sim_arrays + [_dp_part(a) for a in own_dp], dp_only=False)
    _say_learned(say, "  ", hp)
    _score(rows, data, "sim_pretrain", hp, arrays)


def _say_learned(say, prefix: str, hp):
    """What the fit learned from the training logs' failures, and whether it was kept."""
    say(f"{prefix}hull's yaw moment in a drift {hp.training_info.get('drift_hull', 'not fitted')}")
    if "thrust_error_prior" in hp.training_info:
        say(f"{prefix}thrust error learned at the stops {hp.training_info['thrust_error_prior']}")


def _dp_part(a):
    """The rows of a log before its first shutdown (LogArrays)."""
    from dataclasses import replace

    off = np.flatnonzero(a.dp_active == 0)
    end = int(off[0]) if off.size else len(a.time_s)
    cut = {f: getattr(a, f)[:end] for f in ("time_s", "eta", "nu", "nu_logged", "rpm", "azimuth_rad", "wind",
                                              "dp_active", "segment_id", "wind_logged")}
    return replace(a, **cut)


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
    ap.add_argument("--sim-scenarios", type=int, default=6)
    ap.add_argument("--embedded", type=int, default=3, help="embedded scenarios as a second data set (0: none)")
    args = ap.parse_args(argv)
    from hybridship.sim.scenario import embedded_scenarios

    ens = EnsembleConfig(n_members=args.members, seed=args.seed)
    sim_logs = [s.log for s in embedded_scenarios(args.sim_scenarios, args.seed + 1000)]
    rows: list = []
    if TRUTHSIM.is_dir():
        run("truthsim-dev", [pd.read_csv(f) for f in log_files(TRUTHSIM)], sim_logs, ens, rows)
    else:
        print(f"skipping truthsim-dev: {TRUTHSIM} not found", file=sys.stderr)
    if args.embedded:
        run("embedded", [s.log for s in embedded_scenarios(args.embedded, args.seed)], sim_logs, ens, rows)
    df = pd.concat(rows, ignore_index=True)
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "protocols.csv",
                 lambda fh: fh.write(df.to_csv(index=False, float_format="%.6g").encode("utf-8")))
    tab = ratio_table(df)
    md = ["What the nets add after a DP failure, by training protocol.", "",
          "Mean absolute error at 60 s as a ratio to physics alone, first 5 / first 20 intervals "
          "(below 1: better than physics).", "", markdown_table(tab)]
    atomic_write(args.out / "protocols.md", lambda fh: fh.write(("\n".join(md) + "\n").encode("utf-8")))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
