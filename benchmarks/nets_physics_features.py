"""The nets' physics features with the environment estimator's current and thrust error: a measured variant.

A forecast of the default hybrid (``environment="estimator"``) steps the physics with the
estimator's current and thrust-model error, and gives the nets the velocities and
accelerations of that step (``nu_hat``, ``nu_dot_hat``). Its training rows take them from
the physics without either: the targets are the deviation from the estimator's environment
(:func:`~hybridship.residual.environment.environment_accel`), but the features are not.

``EnvironmentFeaturesHybrid`` below is the default hybrid with its training features taken
as the forecast takes them: one step of the physics from each row with the current and the
thrust-error acceleration the estimator had at that row (causal: the estimate uses the
samples up to the row). Targets, estimator, guard and calibration are the default's. This
script scores both, same members and seed:

* **after a DP failure**, the first 20 starts of each failure, 60-s forecasts, trained on
  the DP parts (the paper's protocol, ``drift_hull=False``), the nets always on
  (``guard=False, nets_after_stop=True``, the drift benchmark's ``hybrid_nets_unguarded``;
  the default's nets are off after a failure, so its forecasts there are the same with
  either): the embedded scenarios and truthsim-dev;
* **during station keeping** (truthsim-dev, leave one log out, a start every 20 s, the
  default hybrid with its guard), with
  :func:`station_keeping_coverage.run`: mean distance and heading errors and the 2-sigma
  coverage of the calibrated spread.

Writes ``nets_physics_features.md`` and ``nets_physics_features.csv``
(``part,data,variant,state,window_or_lead,value``) to ``--out``.

Example::

    python benchmarks/nets_physics_features.py --out docs/results/nets-physics-features
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
from hybridship.forecast_inputs.limits import forecast_substeps
from hybridship.logs.ingest import ingest
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import CUR, THR, current_input, thrust_error_accel
from hybridship.sim.scenario import embedded_scenarios
from hybridship.vessel import load_vessel
from station_keeping_coverage import TRUTHSIM, run as station_keeping_run


class EnvironmentFeaturesHybrid(HybridPredictor):
    """The default hybrid whose training features ``nu_hat``, ``nu_dot_hat`` are one physics
    step from each row with the estimator's current and thrust-error acceleration of that
    row, as a forecast's rollout takes them (the load stays out of the step there too)."""

    def _training_prep(self, log):
        prep, every = super()._training_prep(log)
        full_rate = as_log_arrays(log, self.model.vessel)
        est = self.estimator.run(full_rate)
        x = np.full((len(full_rate.time_s), est.x.shape[1]), np.nan)
        x[est.rows] = est.x
        x = x[::every]                          # the rows the nets learn from
        a, dt = prep.arrays, prep.dt_s
        eta, nu = np.nan_to_num(a.eta), np.nan_to_num(prep.nu_s)
        rpm, az, wind = (np.nan_to_num(v) for v in (a.rpm, a.azimuth_rad, a.wind))
        xe = np.nan_to_num(x)
        acc = thrust_error_accel(self.model, est.thrust_error_model, eta, nu, rpm, az, wind, xe[:, CUR], xe[:, THR])
        res = self.model.rollout(eta, nu, 1, dt_s=dt, substeps=forecast_substeps(dt), rpm=rpm, azimuth_rad=az,
                                 wind=wind, current=current_input(xe[:, CUR]), accel_ext=acc)
        # row i is predicted from row i - 1; rows without an estimate keep no feature (NaN:
        # not trainable, as their targets)
        good = np.isfinite(prep.nu_hat[1:]).all(1) & np.isfinite(x[:-1]).all(1)
        prep.nu_hat[1:] = np.where(good[:, None], res.nu[:-1, 1], np.nan)
        prep.nu_dot_hat[1:] = np.where(good[:, None], res.nu_dot[:-1, 1], np.nan)
        return prep, every


VARIANTS = {"default": HybridPredictor, "environment_features": EnvironmentFeaturesHybrid}


def after_failure(logs: list, ens: EnsembleConfig, data: str) -> list[dict]:
    """60-s mean absolute errors (first 5 / first 20 intervals) after each failure of
    ``logs`` (trained on their DP parts) of physics, of physics + the estimator (nets off)
    and of each variant with its nets unguarded."""
    dyn = DynamicPredictor("gunnerus")
    runs = {"physics": [metrics.drift_errors(dyn, a) for a in logs]}
    for name, cls in VARIANTS.items():
        hp = cls("gunnerus", ensemble_config=ens, drift_hull=False).fit(logs)
        runs[f"{name}, nets unguarded"] = [metrics.drift_errors(hp, a, guard=False, nets_after_stop=True)
                                           for a in logs]
        if name == "default":           # nets off, the variants are the same model
            runs["estimator, nets off"] = [metrics.drift_errors(hp, a, nets=False) for a in logs]
    rows = []
    for model, errs in runs.items():
        E = np.stack(errs)[:, :, -1, :]                 # (logs, intervals, north/east/yaw) at 60 s
        for window in (5, 20):
            for k, state in enumerate(("north_m", "east_m", "yaw_deg")):
                rows.append({"part": "after_failure", "data": data, "variant": model, "state": state,
                             "window_or_lead": window, "value": float(E[:, :window, k].mean())})
    return rows


def station_keeping(logs: dict, ens: EnsembleConfig) -> list[dict]:
    """Mean distance [m] and heading [deg] errors and 2-sigma coverage of each variant's
    forecasts during station keeping, leave one log out."""
    rows = []
    for name, cls in VARIANTS.items():
        errors, spread = station_keeping_run(logs, "gunnerus", 20.0, 60.0,
                                             hybrid_factory=lambda cls=cls: cls("gunnerus", ensemble_config=ens))
        mean = errors[errors.model == "hybrid"].groupby("lead_s")[["distance_m", "heading_deg"]].mean()
        pooled = spread[spread.log == "all"].set_index("lead_s")
        for lead, r in mean.iterrows():
            # the coverage is reported at the spread's leads only (SPREAD_LEADS_S)
            cov = pooled.coverage_2sigma.get(lead, np.nan)
            for state, value in (("distance_m", r.distance_m), ("heading_deg", r.heading_deg),
                                 ("coverage_2sigma", cov)):
                rows.append({"part": "station_keeping", "data": "truthsim-dev", "variant": name, "state": state,
                             "window_or_lead": lead, "value": float(value)})
    return rows


def markdown(df: pd.DataFrame) -> str:
    """The two tables: after a failure as ratios to physics (first 5 / first 20), station
    keeping as errors per lead."""
    out = ["The nets' physics features with (`environment_features`) and without (`default`) the estimator's "
           "current and thrust error in training.", "",
           "**After a DP failure**: mean absolute error at 60 s as a ratio to physics alone, first 5 / first 20 "
           "intervals (trained on the DP parts, `drift_hull=False`).", ""]
    af = df[df.part == "after_failure"]
    lines = []
    for (data, variant), g in af[af.variant != "physics"].groupby(["data", "variant"], sort=False):
        cells = {}
        for state in ("north_m", "east_m", "yaw_deg"):
            ref = af[(af.data == data) & (af.variant == "physics") & (af.state == state)]
            r = [g[(g.state == state) & (g.window_or_lead == w)].value.iloc[0]
                 / ref[ref.window_or_lead == w].value.iloc[0] for w in (5, 20)]
            cells[state] = f"{r[0]:.2f}/{r[1]:.2f}"
        lines.append({"data": data, "variant": variant, **cells})
    out += [markdown_table(pd.DataFrame(lines)), ""]
    sk = df[df.part == "station_keeping"]
    if len(sk):
        out += ["**During station keeping** (truthsim-dev, leave one log out, a start every 20 s; the default "
                "hybrid with its guard): mean errors of the logs' means and pooled 2-sigma coverage.", ""]
        wide = sk.pivot_table(index=["variant", "window_or_lead"], columns="state", values="value", sort=False)
        wide = wide.reset_index().rename(columns={"window_or_lead": "lead_s"})
        out += [markdown_table(wide[["variant", "lead_s", "distance_m", "heading_deg", "coverage_2sigma"]]
                               .round(3).astype(object).where(wide.notna(), "")), ""]
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=TRUTHSIM, help="folder of logs (default: truthsim-dev)")
    ap.add_argument("--members", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-station-keeping", action="store_true", help="skip the station-keeping part (about 20 min)")
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    if args.members < 1 or args.seed < 0:
        ap.error("--members: must be >= 1; --seed: must be >= 0")
    ens = EnsembleConfig(n_members=args.members, seed=args.seed)
    vessel = load_vessel("gunnerus")
    rows = after_failure([s.log for s in embedded_scenarios(3)], ens, "embedded")
    if args.data.is_dir():
        files = log_files(args.data)
        rows += after_failure([as_log_arrays(f, vessel) for f in files], ens, "truthsim-dev")
        if not args.no_station_keeping:
            rows += station_keeping({f.name: ingest(f, vessel, purpose="fit") for f in files}, ens)
    else:
        print(f"{args.data} not found (the shared data sets are not in the repository): embedded scenarios only",
              file=sys.stderr)
    df = pd.DataFrame(rows)
    text = markdown(df)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "nets_physics_features.md", lambda fh: fh.write(text.encode("utf-8")))
    atomic_write(args.out / "nets_physics_features.csv", lambda fh: fh.write(df.to_csv(index=False).encode("utf-8")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
