"""What limits a drift forecast: the physics given parts of the simulator's truth.

After every failure of a set of simulated DP losses, the dynamic model (the project's hull,
the model's wind) forecasts 60 s ahead from the first 20 samples, starting from the
simulator's true low-frequency state, and is given one piece of the truth at a time:

* ``model wind``: nothing else (no current, no load), the true wind held at its start value;
* ``model wind, logged held`` and ``model wind, fitted forecast``: the logged (noisy) wind
  held at its start value, as the benchmark's physics does, and the hybrid's wind forecast
  (a gust decaying to the recent mean, :func:`~hybridship.forecast_inputs.wind.fit_wind_forecast`
  fitted on the set's station keeping) from it;
* ``model wind, true future``: the model's wind load at the simulator's true wind sample by
  sample over the forecast (a perfect wind forecast; the model's wind coefficients);
* ``current in the hull``: the true current, acting through the relative velocity;
* ``current as a held force``: the force the true current puts on the ship at rest
  (computed with the model's hull over the last 10 minutes of station keeping, its mean
  held in NED), which is all station keeping can show of a current;
* ``wave drift held``: the mean second-order wave load of the last 10 minutes of station
  keeping (``truth_tau_wave2_*``), held in NED;
* both held rows hold the load as the estimator's default load model does: its
  acceleration ``M^-1 tau`` turned into NED at the window's headings, averaged, and turned
  back along the path (not the force held in NED, whose body acceleration would change by
  up to +-18 % with a turn on the Gunnerus and gain a yaw part through ``M^-1``'s sway-yaw
  coupling; ``load_model="force"`` in :mod:`hybridship.residual.environment`);
* the two combinations of those, and the first with the true future wind, and
* ``true loads and current``: the simulator's own wind and wave-drift loads and current
  sample by sample over the forecast (a ceiling: what is left is the hull model's error);
  the model's own wind part is off, as the logged wind load already holds the air drag of
  the ship's motion.

No estimate is involved: the rows show how much each part of the environment is worth, and
what a perfect estimate of the held quantities could give. Station keeping cannot tell a
current from a force (the ship does not move through the water), so the difference between
the ``current in the hull`` and ``current as a held force`` rows is what the estimator
cannot know before the ship drifts.

Writes ``drift_oracles.csv`` and ``drift_oracles.md`` to ``--out``: 60-s mean absolute
heading error [deg] and the mean of the north and east errors [m], pooled over the first 20
starts of every failure; and ``drift_oracles_per_log.csv``, the same per failure.
``--vessel`` replaces the model's vessel file (the simulated scenarios stay those of the
packaged Gunnerus). Examples::

    python benchmarks/drift_oracles.py --out docs/results/drift-oracles
    python benchmarks/drift_oracles.py --vessel benchmarks/vessel_variants/gunnerus_yaw_damping_x2.toml \
        --out docs/results/drift-oracles-yaw-damping-x2
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.signal import butter, filtfilt

from _results import check_out, check_own_scenarios
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.frames import body_to_ned, ned_to_body, wrap_pi
from hybridship.forecast_inputs.wind import fit_wind_forecast
from hybridship.physics.model import DynamicModel
from hybridship.predictors import as_log_arrays
from hybridship.sim.scenario import embedded_scenarios
from hybridship.vessel import Wind, load_vessel

TRUTHSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "truthsim-dev" / "logs"
DOFS = ("x_N", "y_N", "n_Nm")
N_STARTS, HORIZON, WINDOW = 20, 60, 600


def _lf_velocities(d: pd.DataFrame) -> np.ndarray:
    """Low-frequency body velocities [m/s, m/s, rad/s]: the simulator's own if logged, else the
    total ones low-passed at 0.04 Hz (zero phase)."""
    if "truth_u_lf_mps" in d:
        return np.column_stack([d.truth_u_lf_mps, d.truth_v_lf_mps, np.radians(d.truth_r_lf_degps)])
    b, a = butter(2, 0.04, fs=1.0)
    return np.column_stack([filtfilt(b, a, d.truth_u_mps), filtfilt(b, a, d.truth_v_mps),
                            np.radians(filtfilt(b, a, d.truth_r_degps))])


def failure_oracles(model: DynamicModel, d: pd.DataFrame, wind_forecast=None) -> dict:
    """Heading [deg] and mean north/east [m] absolute errors at 60 s per oracle, for one log;
    with ``wind_forecast`` (a :class:`~hybridship.forecast_inputs.wind.WindForecast`) also the
    rows of the logged wind, held and forecast."""
    i0 = int(np.flatnonzero(d.dp_active.to_numpy() == 0)[0])          # the first sample of the drift
    nu = _lf_velocities(d)
    psi = np.unwrap(np.radians(d.truth_heading_lf_deg.to_numpy(float)))
    north, east = d.truth_north_lf_m.to_numpy(float), d.truth_east_lf_m.to_numpy(float)
    current = np.column_stack([d.truth_current_speed_mps, np.radians(d.truth_current_dir_to_deg)])
    wind = np.column_stack([d.truth_wind_speed_mps, np.radians(d.truth_wind_dir_from_deg)])
    tau = {k: np.column_stack([d[f"truth_tau_{k}_{c}"].to_numpy(float) for c in DOFS]) for k in ("wind", "wave2")}
    m_inv = np.linalg.inv(model.mass_matrix)
    still_air = DynamicModel(model.vessel.model_copy(update={"wind": Wind(method="none")}))

    st = i0 + np.arange(N_STARTS)
    path = np.stack([np.arange(s, s + HORIZON) for s in st])           # rows of each forecast step
    psi_path = psi[path]                                                # heading along the true path
    w = slice(max(i0 - WINDOW, 0), i0)
    eta_w = np.column_stack([north[w], east[w], psi[w]])
    zeros_w = np.zeros((eta_w.shape[0], model.n_channels))
    rest = np.zeros_like(eta_w)
    force_at_rest = (model.acceleration(eta_w, rest, rpm=zeros_w, azimuth_rad=zeros_w, current=current[w])
                     - model.acceleration(eta_w, rest, rpm=zeros_w, azimuth_rad=zeros_w))
    current_force = ned_to_body(body_to_ned(force_at_rest, psi[w]).mean(0), psi_path)
    wave_held = ned_to_body(body_to_ned(tau["wave2"][w] @ m_inv.T, psi[w]).mean(0), psi_path)

    eta0 = np.column_stack([north[st], east[st], psi[st]])
    zeros = np.zeros((N_STARTS, model.n_channels))
    truth = np.column_stack([north[st + HORIZON], east[st + HORIZON], psi[st + HORIZON]])

    def run(rollout_model=model, **kw):
        kw.setdefault("wind", wind[st])
        end = rollout_model.rollout(eta0, nu[st], HORIZON, rpm=zeros, azimuth_rad=zeros, **kw).eta[:, -1]
        return (float(np.degrees(np.abs(wrap_pi(end[:, 2] - truth[:, 2]))).mean()),
                float(0.5 * np.abs(end[:, :2] - truth[:, :2]).mean(axis=0).sum()))

    logged = {}
    if wind_forecast is not None:
        a = as_log_arrays(d, model.vessel)
        logged = {"model wind, logged held": run(wind=a.wind[st]),
                  "model wind, fitted forecast": run(wind=wind_forecast.steps(a.wind, a.time_s, st, a.wind[st],
                                                                              HORIZON, a.dt_s,
                                                                              logged=a.wind_logged))}
    return {
        "model wind": run(),
        **logged,
        "model wind, true future": run(wind=wind[path]),
        "current in the hull": run(current=current[st]),
        "current as a held force": run(accel_ext=current_force),
        "wave drift held": run(accel_ext=wave_held),
        "current in the hull + wave drift held": run(current=current[st], accel_ext=wave_held),
        "current in the hull + wave drift held, true future wind": run(wind=wind[path], current=current[st],
                                                                       accel_ext=wave_held),
        "current as a held force + wave drift held": run(accel_ext=current_force + wave_held),
        # the logged wind load is the simulator's whole air load (its wind relative to the moving
        # ship): in still air the model's wind part would add the ship's own air drag a second time
        "true loads and current": run(still_air, current=current[path], tau_ext=(tau["wind"] + tau["wave2"])[path]),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--own", type=int, default=20, help="simulated DP losses of our own, 1-20 (default 20)")
    ap.add_argument("--own-seed", type=int, default=100, help="seed of the first (default 100)")
    ap.add_argument("--vessel", default="gunnerus", help="the model's vessel (name or TOML file; default gunnerus)")
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    check_own_scenarios(ap, "--own", args.own, "--own-seed", args.own_seed)
    try:
        model = DynamicModel(load_vessel(args.vessel))
    except (OSError, ValueError) as exc:
        print(f"--vessel {args.vessel}: {exc}", file=sys.stderr)
        return 2
    own = f"own {args.own_seed}-{args.own_seed + args.own - 1}"
    data = {own: [(s.name, s.log) for s in embedded_scenarios(args.own, args.own_seed)]}
    if TRUTHSIM.is_dir():
        data["truthsim-dev"] = [(f.name, pd.read_csv(f)) for f in log_files(TRUTHSIM)]
    else:
        print(f"skipping truthsim-dev: {TRUTHSIM} not found", file=sys.stderr)
    rows, per_log_rows = [], []
    for name, logs in data.items():
        arrays = [as_log_arrays(d, model.vessel) for _, d in logs]
        wind_forecast, _ = fit_wind_forecast(arrays, float(HORIZON), masks=[a.dp_active == 1 for a in arrays])
        per_log = [failure_oracles(model, d, wind_forecast) for _, d in logs]
        per_log_rows += [{"data": name, "log": log, "given": k, "heading_deg": v[0], "north_east_m": v[1]}
                         for (log, _), r in zip(logs, per_log) for k, v in r.items()]
        base = np.mean([r["model wind"] for r in per_log], axis=0)
        for oracle in per_log[0]:
            h, ne = np.mean([r[oracle] for r in per_log], axis=0)
            rows.append({"data": name, "given": oracle, "heading_deg": round(float(h), 2),
                         "heading_ratio": round(float(h / base[0]), 2), "north_east_m": round(float(ne), 2),
                         "north_east_ratio": round(float(ne / base[1]), 2)})
            print(rows[-1], flush=True)
    df = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out / "drift_oracles.csv", lambda fh: fh.write(df.to_csv(index=False).encode("utf-8")))
    per_log_csv = pd.DataFrame(per_log_rows).to_csv(index=False, float_format="%.3f")
    atomic_write(args.out / "drift_oracles_per_log.csv", lambda fh: fh.write(per_log_csv.encode("utf-8")))
    md = markdown_table(df) + "\n"
    atomic_write(args.out / "drift_oracles.md", lambda fh: fh.write(md.encode("utf-8")))
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
