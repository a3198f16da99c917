"""The environment estimator's design choices, measured: drift forecasts with one choice changed at a time.

Paper protocol (trained on DP parts only), forecasts from the first 20 samples after each
failure, 60 s ahead, nets off (``forecast(nets=False)``: physics + environment estimator),
on the embedded scenarios and on truthsim-dev. Each row changes one setting of the
default :class:`~hybridship.residual.environment.EnvironmentConfig`; ``mean_bias`` is the
scheme before the estimator (900-s mean residual, 3-s start window).

Writes ``variants.csv`` and ``variants.md`` (60-s MAE as a ratio to physics alone, first
5 / first 20 intervals) to ``--out``.

Example::

    python benchmarks/estimator_variants.py --out docs/results/estimator-variants
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
from hybridship.residual.environment import EnvironmentConfig

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"

#: name -> (HybridPredictor keyword arguments, what the row shows)
PER_THRUSTER = dict(thrust_error_model="per_thruster", yaw_load_kept_at_stop=1.0, thrust_error_walk=0.0)
VARIANTS = {
    "default": ({}, "the default estimator (thrust error per DOF, yaw environment restarted at the stop)"),
    "keep_dp_yaw_load": ({"environment_config": EnvironmentConfig(yaw_load_kept_at_stop=1.0)},
                         "the yaw load of station keeping kept after the stop"),
    "half_dp_yaw_load": ({"environment_config": EnvironmentConfig(yaw_load_kept_at_stop=0.5)},
                         "half of it kept"),
    "per_thruster": ({"environment_config": EnvironmentConfig(**PER_THRUSTER)},
                     "thrust error per thruster (constant), DP yaw load kept at the stop"),
    "per_thruster_reset_yaw": ({"environment_config": EnvironmentConfig(**{**PER_THRUSTER,
                                                                          "yaw_load_kept_at_stop": 0.0})},
                               "thrust error per thruster, yaw environment restarted at the stop"),
    "per_thruster_yaw_spread": ({"environment_config": EnvironmentConfig(**PER_THRUSTER, yaw_load_std_at_stop=1.0)},
                                "per thruster, yaw kept with a spread of 100 % of it"),
    "per_thruster_walk": ({"environment_config": EnvironmentConfig(**{**PER_THRUSTER, "thrust_error_walk": 2e-3})},
                          "per thruster, thrust error a random walk (2e-3 per sqrt(s))"),
    "per_thruster_tight_prior": ({"environment_config": EnvironmentConfig(
        **PER_THRUSTER, thrust_error_prior_per_thruster=0.1)}, "per thruster, prior 0.1 instead of 0.2"),
    "per_thruster_wide_prior": ({"environment_config": EnvironmentConfig(
        **PER_THRUSTER, thrust_error_prior_per_thruster=0.4)}, "per thruster, prior 0.4 instead of 0.2"),
    "current_prior_0.1": ({"environment_config": EnvironmentConfig(current_prior_m_s=0.1)},
                          "current prior 0.1 m/s instead of 0.02 m/s"),
    "wide_current_prior": ({"environment_config": EnvironmentConfig(current_prior_m_s=0.3)},
                           "current prior 0.3 m/s instead of 0.02 m/s"),
    "tight_yaw_thrust_prior": ({"environment_config": EnvironmentConfig(thrust_error_prior=(0.2, 0.2, 0.1))},
                               "yaw thrust-error prior 0.1 instead of 0.5"),
    "fixed_noise": ({"environment_config": EnvironmentConfig(adaptive_measurement_std=False)},
                    "no wave-motion noise estimate (configured sensor noise only)"),
    "mean_bias": ({"environment": "mean"}, "900-s mean residual, no estimator"),
}
TINY = EnsembleConfig(n_members=2, hidden=4, max_epochs=1, patience=1, seed=0)


def _errors(pred, arrays, **kw):
    all_h = tuple(float(h) for h in range(1, 61))
    p, t, _ = metrics.drift_forecasts(pred, arrays, n_intervals=20, horizons_s=all_h, **kw)
    return metrics.absolute_errors(p[:, [59]], t[:, [59]])[:, 0]       # (20, 3) at 60 s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--only", nargs="+", choices=list(VARIANTS), default=list(VARIANTS),
                    help="the variants to run (default: all)")
    args = ap.parse_args(argv)
    from hybridship.sim.scenario import embedded_scenarios

    data = {"embedded": [s.log for s in embedded_scenarios(3, 0)]}
    if TRUTHSIM.is_dir():
        data["truthsim-dev"] = [pd.read_csv(f) for f in log_files(TRUTHSIM)]
    else:
        print(f"skipping truthsim-dev: {TRUTHSIM} not found", file=sys.stderr)
    rows = []
    for dname, logs in data.items():
        dyn = DynamicPredictor("gunnerus")
        arrays = [as_log_arrays(x, dyn.model.vessel) for x in logs]
        phys = np.stack([_errors(dyn, a) for a in arrays])                       # (L, 20, 3)
        for vname in args.only:
            kw, what = VARIANTS[vname]
            hp = HybridPredictor("gunnerus", ensemble_config=TINY, **kw).fit(arrays, dp_only=True)
            e = np.stack([_errors(hp, a, nets=False) for a in arrays])
            row = {"data": dname, "variant": vname, "what": what}
            for j, state in enumerate(metrics.STATES):
                r5 = e[:, :5, j].mean() / phys[:, :5, j].mean()
                r20 = e[:, :, j].mean() / phys[:, :, j].mean()
                row[state] = f"{r5:.2f}/{r20:.2f}"
            rows.append(row)
            print(row, flush=True)
    df = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "variants.csv", lambda fh: fh.write(df.to_csv(index=False).encode("utf-8")))
    md = [markdown_table(df)]
    atomic_write(args.out / "variants.md", lambda fh: fh.write(("\n".join(md) + "\n").encode("utf-8")))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
