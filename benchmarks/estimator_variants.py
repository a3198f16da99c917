"""The environment estimator's design choices, measured: drift forecasts with one choice changed at a time.

Paper protocol (trained on DP parts only), forecasts from the first 20 samples after each
failure, 60 s ahead, nets off (``forecast(nets=False)``: physics + environment estimator),
on the embedded scenarios and on truthsim-dev. Each row changes one setting of the
default :class:`~hybridship.residual.environment.EnvironmentConfig`; ``mean_bias`` is the
scheme before the estimator (900-s mean residual, 3-s start window); ``held_wind`` holds
the wind at its start value instead of the fitted wind forecast
(:mod:`hybridship.forecast_inputs.wind`), and ``physics_wind_forecast`` is the physics
alone with that fitted wind forecast (what the wind forecast does without the estimator).

Writes ``variants.csv`` and ``variants.md`` (60-s MAE as a ratio to physics alone, first
5 / first 20 intervals) to ``--out``, and ``variants_per_log.csv`` (the same ratio for each
failure on its own: ``data, variant, log, state, ratio_5, ratio_20``), which shows whether a
pooled change comes from every failure or from one.

``--data own`` runs on ``--own-n`` fresh simulated scenarios of our own (seeds from
``--own-seed``) instead; ``--logs`` adds folders of logs (for example the calm scenarios of
``hybridship simulate --sweep --beaufort 1.5 3``), each a data set named by its folder.

Examples::

    python benchmarks/estimator_variants.py --out docs/results/estimator-variants
    python benchmarks/estimator_variants.py --data own --only default held_wind physics_wind_forecast \
        current_prior_0.1 current_prior_0.3 yaw_load_prior_3e-5 yaw_load_prior_1e-4 yaw_load_walk_1e-5 \
        yaw_load_walk_1e-4 restart_yaw_at_stop per_dof mean_bias --out docs/results/estimator-variants-own-20
    python benchmarks/estimator_variants.py --data own --own-seed 200 --only default held_wind \
        physics_wind_forecast yaw_load_prior_3e-5 yaw_load_prior_1e-4 --out docs/results/estimator-variants-own-20-seed200
    python benchmarks/estimator_variants.py --data truthsim-dev own --only default tight_thrust_prior \
        thrust_prior_0.05 wide_thrust_prior --out docs/results/estimator-variants-thrust-prior
    python benchmarks/estimator_variants.py --data embedded truthsim-dev own --only default \
        current_at_stop_0.1 current_at_stop_0.3 --out docs/results/estimator-variants-current-at-stop
    python benchmarks/estimator_variants.py --data embedded truthsim-dev own --only default \
        load_to_current_0.5 load_to_current_1 --out docs/results/estimator-variants-load-to-current
    python benchmarks/estimator_variants.py --data embedded truthsim-dev own --only default settle_120 settle_300 \
        current_walk_3e-4 --out docs/results/estimator-variants-filter-start
    hybridship simulate --sweep --seeds 500-519 --beaufort 1.5 3 --out-dir calm-20
    python benchmarks/estimator_variants.py --data embedded truthsim-dev own --logs calm-20 --only default \
        current_prior_0.1 current_by_wind_6 current_by_wind_8 current_by_wind_10 \
        --out docs/results/estimator-variants-current-by-wind
    python benchmarks/estimator_variants.py --data own --own-seed 200 --only default current_prior_0.1 \
        current_by_wind_6 current_by_wind_8 current_by_wind_10 \
        --out docs/results/estimator-variants-current-by-wind-seed200
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out, check_own_scenarios
from hybridship.evaluation import metrics
from hybridship.evaluation.drift import log_files
from hybridship.forecast_inputs.wind import HELD_WIND
from hybridship.fileio import atomic_write, markdown_table
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import PER_DOF, EnvironmentConfig

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"

#: name -> (HybridPredictor keyword arguments, what the row shows)
C = EnvironmentConfig
#: The physics alone, with the wind forecast the default hybrid fitted (what the wind forecast does by itself).
PHYSICS_WIND = "physics_wind_forecast"
VARIANTS = {
    "default": ({}, "the default estimator (thrust error per thruster, constant; the filter carries on at the stop; "
                    "wind forecast fitted on the training logs' wind)"),
    "yaw_load_prior_3e-5": ({"environment_config": C(load_yaw_prior_rad_s2=3e-5)},
                            "yaw-load prior 3e-5 rad/s2 instead of 1e-3 (it then decides the yaw split)"),
    "yaw_load_prior_1e-4": ({"environment_config": C(load_yaw_prior_rad_s2=1e-4)},
                            "yaw-load prior 1e-4 rad/s2"),
    "yaw_load_prior_3e-4": ({"environment_config": C(load_yaw_prior_rad_s2=3e-4)},
                            "yaw-load prior 3e-4 rad/s2"),
    "yaw_load_walk_1e-5": ({"environment_config": C(load_yaw_walk_rad_s2=1e-5)},
                           "yaw-load random walk 1e-5 rad/s2/sqrt(s) instead of 1e-6 (follows the drift's yaw faster)"),
    "yaw_load_walk_1e-4": ({"environment_config": C(load_yaw_walk_rad_s2=1e-4)},
                           "yaw-load random walk 1e-4 rad/s2/sqrt(s)"),
    "restart_yaw_at_stop": ({"environment_config": C(reset_yaw_load_at_stop=True, yaw_load_kept_at_stop=0.0)},
                            "yaw environment restarted from zero at the stop"),
    "thrust_error_walk": ({"environment_config": C(thrust_error_walk=2e-3)},
                          "thrust error a random walk (2e-3 per sqrt(s)) instead of constant"),
    "tight_thrust_prior": ({"environment_config": C(thrust_error_prior_per_thruster=0.1)},
                           "thrust-error prior 0.1 per thruster instead of 0.2"),
    "thrust_prior_0.05": ({"environment_config": C(thrust_error_prior_per_thruster=0.05)},
                          "thrust-error prior 0.05 per thruster instead of 0.2"),
    "wide_thrust_prior": ({"environment_config": C(thrust_error_prior_per_thruster=0.4)},
                          "thrust-error prior 0.4 per thruster instead of 0.2"),
    "current_prior_0.1": ({"environment_config": C(current_prior_m_s=0.1)}, "current prior 0.1 m/s instead of 0.02 m/s"),
    "current_prior_0.3": ({"environment_config": C(current_prior_m_s=0.3)}, "current prior 0.3 m/s instead of 0.02 m/s"),
    **{f"current_by_wind_{ref:g}": ({"environment_config": C(current_prior_wind_ref_m_s=ref)},
                                    f"current prior 0.02 m/s x ({ref:g} m/s / wind at the filter's start)^2, "
                                    "0.02-0.3 m/s") for ref in (6.0, 8.0, 10.0)},
    **{f"load_across_wind_{rho:g}" + ("" if cur == 0.02 else f"_current_{cur:g}"): (
        {"environment_config": C(load_prior_across_wind=rho, current_prior_m_s=cur)},
        f"the load's prior across the wind {rho:g} times that along it, current prior {cur:g} m/s")
       for rho, cur in ((0.3, 0.02), (0.3, 0.05), (0.3, 0.1), (0.1, 0.02), (0.1, 0.05), (0.1, 0.1))},
    **{f"load_across_wind_0.1_current_0.05_yaw_prior_{name}": (
        {"environment_config": C(load_prior_across_wind=0.1, current_prior_m_s=0.05, load_yaw_prior_rad_s2=yaw)},
        f"the load's prior across the wind 0.1 times that along it, current prior 0.05 m/s, the yaw load's "
        f"prior {name} rad/s^2 instead of 1e-3 (the yaw offset on station, mostly the current's moment at "
        "rest, then speaks for the current)") for name, yaw in (("1e-4", 1e-4), ("3e-5", 3e-5))},
    "current_at_stop_0.1": ({"environment_config": C(current_std_at_stop_m_s=0.1)},
                            "current's uncertainty widened by 0.1 m/s along the current-load ridge at the stop"),
    "load_to_current_0.5": ({"environment_config": C(load_to_current_at_stop=0.5)},
                            "half the NED load re-explained as a current at the stop"),
    "load_to_current_1": ({"environment_config": C(load_to_current_at_stop=1.0)},
                          "the whole NED load re-explained as a current at the stop"),
    "current_at_stop_0.3": ({"environment_config": C(current_std_at_stop_m_s=0.3)},
                            "current's uncertainty widened by 0.3 m/s along the current-load ridge at the stop"),
    "settle_120": ({"environment_config": C(settle_s=120.0)},
                   "the environment left alone for the first 120 s of a filter run, while the motion states settle"),
    "settle_300": ({"environment_config": C(settle_s=300.0)}, "the same for 300 s"),
    "current_walk_3e-4": ({"environment_config": C(current_walk_m_s=3e-4)},
                          "current random walk 3e-4 m/s/sqrt(s) instead of constant (forgets the filter's start)"),
    "fixed_noise": ({"environment_config": C(adaptive_measurement_std=False)},
                    "no wave-motion noise estimate (configured sensor noise only)"),
    "per_dof": ({"environment_config": C(**PER_DOF)},
                "thrust error per DOF, yaw environment restarted at the stop (the previous default)"),
    "per_dof_keep_yaw": ({"environment_config": C(**{**PER_DOF, "yaw_load_kept_at_stop": 1.0})},
                         "per DOF, the station-keeping yaw load kept at the stop"),
    "per_dof_wide_yaw_prior": ({"environment_config": C(**{**PER_DOF, "load_yaw_prior_rad_s2": 1e-3,
                                                          "reset_yaw_load_at_stop": False})},
                               "per DOF with the default's yaw-load prior, carrying on at the stop"),
    "mean_bias": ({"environment": "mean"}, "900-s mean residual, no estimator"),
    "held_wind": ({"wind_forecast": HELD_WIND},
                  "wind held at its start value over the forecast (the paper's scheme) instead of the fitted gust decay"),
    PHYSICS_WIND: ({}, "physics alone with the default's fitted wind forecast (no estimator)"),
}
TINY = EnsembleConfig(n_members=2, hidden=4, max_epochs=1, patience=1, seed=0)


def _errors(pred, arrays, **kw):
    all_h = tuple(float(h) for h in range(1, 61))
    p, t, _ = metrics.drift_forecasts(pred, arrays, n_intervals=20, horizons_s=all_h, **kw)
    return metrics.absolute_errors(p[:, [59]], t[:, [59]])[:, 0]       # (20, 3) at 60 s


def per_log_rows(data: str, variant: str, names, errors: np.ndarray, physics: np.ndarray) -> list[dict]:
    """``variants_per_log.csv`` rows: each failure's 60-s MAE as a ratio to the physics' on the
    same failure, over the first 5 and the first 20 intervals; ``errors`` and ``physics`` are
    (logs, 20 intervals, states) absolute errors."""
    return [{"data": data, "variant": variant, "log": name, "state": state,
             "ratio_5": errors[k, :5, j].mean() / physics[k, :5, j].mean(),
             "ratio_20": errors[k, :, j].mean() / physics[k, :, j].mean()}
            for j, state in enumerate(metrics.STATES) for k, name in enumerate(names)]


def parse_args(argv, description: str, variants) -> argparse.Namespace:
    """The arguments this script and ``drift_late_starts.py`` share: ``--out``, ``--only`` (of
    ``variants``), ``--data``, ``--own-n`` (1-20) and ``--own-seed`` (from 0); a usage error
    (exit 2) for a count or seed the simulator does not take."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--only", nargs="+", choices=list(variants), default=list(variants),
                    help="the variants to run (default: all)")
    ap.add_argument("--data", nargs="+", choices=("embedded", "truthsim-dev", "own"),
                    default=("embedded", "truthsim-dev"), help="data sets (default: embedded truthsim-dev)")
    ap.add_argument("--own-n", type=int, default=20, help="scenarios of the 'own' set (default 20)")
    ap.add_argument("--own-seed", type=int, default=100, help="seed of its first scenario (default 100)")
    ap.add_argument("--logs", type=Path, nargs="+", default=(),
                    help="folders of DP-loss logs, each one more data set named by its folder (after --data)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    check_own_scenarios(ap, "--own-n", args.own_n, "--own-seed", args.own_seed)
    for folder in args.logs:
        try:
            log_files(folder)
        except ValueError as exc:           # not a folder, or none of its files a log
            ap.error(f"--logs: {exc}")
    names = [folder.name for folder in args.logs]
    if len(set(names)) != len(names):       # one data set would replace the other in the tables
        ap.error(f"--logs: two folders named {next(n for n in names if names.count(n) > 1)!r}")
    return args


def data_sets(names, own_n: int, own_seed: int, folders=()) -> dict:
    """``{data set: (logs, log names)}`` for ``names`` among ``embedded`` (the three embedded
    scenarios), ``truthsim-dev`` (skipped with a message when absent) and ``own`` (``own_n``
    fresh scenarios of our own from seed ``own_seed``), in that order, then one set per folder
    of logs in ``folders`` (named by the folder)."""
    from hybridship.sim.scenario import embedded_scenarios

    data = {}
    if "embedded" in names:
        scen = embedded_scenarios(3, 0)
        data["embedded"] = ([s.log for s in scen], [s.name for s in scen])
    if "truthsim-dev" in names and TRUTHSIM.is_dir():
        files = log_files(TRUTHSIM)
        data["truthsim-dev"] = ([pd.read_csv(f) for f in files], [f.name.split(".")[0] for f in files])
    elif "truthsim-dev" in names:
        print(f"skipping truthsim-dev: {TRUTHSIM} not found", file=sys.stderr)
    if "own" in names:
        scen = embedded_scenarios(own_n, own_seed)
        data[f"own {own_seed}-{own_seed + own_n - 1}"] = ([s.log for s in scen], [s.name for s in scen])
    for folder in folders:
        files = log_files(folder)
        data[folder.name] = ([pd.read_csv(f) for f in files], [f.name.split(".")[0] for f in files])
    return data


def main(argv=None) -> int:
    args = parse_args(argv, __doc__.split("\n")[0], VARIANTS)
    rows, per_log = [], []
    sets = data_sets(args.data, args.own_n, args.own_seed, args.logs)
    if not sets:                # --data truthsim-dev without it: empty tables were written over the results
        print("error: --data: no data set to run (truthsim-dev is not on this machine)", file=sys.stderr)
        return 2
    for dname, (logs, names) in sets.items():
        dyn = DynamicPredictor("gunnerus")
        arrays = [as_log_arrays(x, dyn.model.vessel) for x in logs]
        phys = np.stack([_errors(dyn, a) for a in arrays])                       # (L, 20, 3)
        for vname in args.only:
            kw, what = VARIANTS[vname]
            # scored on the training logs' own drifts: nothing is learned from them (drift_hull off)
            hp = HybridPredictor("gunnerus", ensemble_config=TINY, drift_hull=False, **kw).fit(arrays, dp_only=True)
            if vname == PHYSICS_WIND:
                dw = DynamicPredictor("gunnerus", wind_forecast=hp.wind_forecast)
                e = np.stack([_errors(dw, a) for a in arrays])
            else:
                e = np.stack([_errors(hp, a, nets=False) for a in arrays])
            row = {"data": dname, "variant": vname, "what": what}
            for j, state in enumerate(metrics.STATES):
                r5 = e[:, :5, j].mean() / phys[:, :5, j].mean()
                r20 = e[:, :, j].mean() / phys[:, :, j].mean()
                row[state] = f"{r5:.2f}/{r20:.2f}"
            rows.append(row)
            per_log += per_log_rows(dname, vname, names, e, phys)
            print(row, flush=True)
    df = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "variants.csv", lambda fh: fh.write(df.to_csv(index=False).encode("utf-8")))
    pl = pd.DataFrame(per_log).round({"ratio_5": 3, "ratio_20": 3})
    atomic_write(args.out / "variants_per_log.csv", lambda fh: fh.write(pl.to_csv(index=False).encode("utf-8")))
    md = [markdown_table(df)]
    atomic_write(args.out / "variants.md", lambda fh: fh.write(("\n".join(md) + "\n").encode("utf-8")))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
