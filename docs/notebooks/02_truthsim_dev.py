# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # The shared Gunnerus-like data set (truthsim-dev)
#
# `shared/data/truthsim-dev/` holds six DP-shutdown drift logs of a Gunnerus-like vessel
# from an **independent** simulator (MCSimPython's Gunnerus manoeuvring model with its own
# wind, wave-drift, current, thruster and DP code; see the data set's `README.md`). None of
# hybridship's numbers came from it, so it plays the part of a ship that our model only
# approximates. This notebook:
#
# 1. finds and loads the logs (and skips with a message when the folder is absent);
# 2. maps the logged thrusters onto the vessel file's thrusters;
# 3. trains a hybrid on the DP part of the early cases;
# 4. forecasts the drift of a held-out case and plots it with uncertainty bands;
# 5. prints the 15/30/45/60 s error table of the held-out case.
#
# The data set is not part of the repository. The notebook reads it from
# `$HYBRIDSHIP_TRUTHSIM_DEV` when that is set (and only there); otherwise from
# `../shared/data/truthsim-dev` beside the checkout that hybridship is imported from, as
# the tests do, or from `shared/data/truthsim-dev` beside any parent folder of the working
# directory. Without it the notebook prints where it looked and skips the rest.
# `HYBRIDSHIP_SMALL=1` trains on one log, cut to the last 15 min of station keeping, with a
# small ensemble.

# %%
import os
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import torch

import hybridship
from hybridship.evaluation import metrics
from hybridship.logs.io import read_log
from hybridship.predictors import DeadReckoning, DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import prepare_log
from hybridship.sim.allocation import bollard_thrust_limits
from hybridship.vessel import load_vessel

torch.set_num_threads(1)
SMALL = os.environ.get("HYBRIDSHIP_SMALL", "0") == "1"
MEMBERS = 3 if SMALL else 10
MAX_EPOCHS = 150 if SMALL else 800


def truthsim_dev_candidates():
    """Where the truthsim-dev folder may be, in the order they are tried."""
    env = os.environ.get("HYBRIDSHIP_TRUTHSIM_DEV")
    if env:
        return [Path(env)]
    checkout = Path(hybridship.__file__).resolve().parents[1]     # the repository root
    here = Path.cwd().resolve()
    return list(dict.fromkeys(p / "shared" / "data" / "truthsim-dev" for p in (checkout.parent, here, *here.parents)))


def find_truthsim_dev():
    """The truthsim-dev folder, or None."""
    for c in truthsim_dev_candidates():
        if (c / "logs").is_dir() and any((c / "logs").glob("*.csv.gz")):
            return c
    return None


DATA = find_truthsim_dev()
HAVE_DATA = DATA is not None
if not HAVE_DATA:
    looked = truthsim_dev_candidates()
    print(f"SKIPPED: the shared truthsim-dev data set was not found (no logs/*.csv.gz in {looked[0]}"
          f"{' or beside the working directory' if len(looked) > 1 else ''}; set HYBRIDSHIP_TRUTHSIM_DEV to "
          "its folder). The rest of this notebook does nothing.")
else:
    print(f"data set: {DATA}")

# %% [markdown]
# ## 1. Load the logs
#
# `scenarios.csv` lists each case's conditions and shutdown time. The logs are in the
# project's [log format](../../reference/log-format/); `read_log` validates them.

# %%
if HAVE_DATA:
    scen = pd.read_csv(DATA / "scenarios.csv")
    print(scen[["file", "wind_mean_mps", "hs_m", "current_mps", "heading_mode", "t_shutdown_s",
                "drift_excursion_60s_m"]].to_string(index=False))
    files = sorted((DATA / "logs").glob("*.csv.gz"))
    # Early cases for training, the last case of each group (rough "dev_", calm "calm_dev_") held out.
    rough = [f for f in files if f.name.startswith("dev_")]
    calm = [f for f in files if f.name.startswith("calm_dev_")]
    held_out = rough[-1]
    train_files = rough[:1] if SMALL else rough[:-1] + calm[:-1]
    print("train on:", [f.name for f in train_files])
    print("held out:", held_out.name)

# %% [markdown]
# ## 2. Map the thrusters
#
# A log names its thrusters after the vessel file (`<name>_rpm`, `<name>_azimuth_deg`).
# Logs from a real ship usually need a column rename first; these already use the names
# `tunnel`, `port` and `stbd` of `vessels/gunnerus.toml`, so the rename below is the
# identity and only shows the step.
#
# The propellers differ, though. The data set's README gives its thrusters as
# `thrust ~ rpm |rpm|` with 20 kN at 360 rpm (tunnel) and 50 kN at 200 rpm (azimuths);
# the vessel file has Wageningen B4-70 propellers whose bollard thrust at `max_rpm` comes
# from `bollard_thrust_limits`. With both sides quadratic in rpm, the rpm that gives the
# model the same bollard thrust is a fixed factor per thruster:
# `rpm_model = rpm_log * (max_rpm_model / rpm_ref_log) * sqrt(T_ref_log / T_max_model)`.
# Without the mapping, the residual learner has to absorb the thrust mismatch during
# station keeping as well; after a failure the rpm are zero and the mapping no longer
# matters.

# %%
vessel = load_vessel("gunnerus")
RENAME = {"tunnel_rpm": "tunnel_rpm", "port_rpm": "port_rpm", "stbd_rpm": "stbd_rpm",
          "port_azimuth_deg": "port_azimuth_deg", "stbd_azimuth_deg": "stbd_azimuth_deg"}
LOG_THRUSTERS = {"tunnel": (360.0, 20e3), "port": (200.0, 50e3), "stbd": (200.0, 50e3)}  # rpm, N (README)
t_max_model = dict(zip(vessel.channel_names, bollard_thrust_limits(vessel).forward_N))
RPM_FACTOR = {}
for th in vessel.thrusters:
    rpm_ref, t_ref = LOG_THRUSTERS[th.name]
    RPM_FACTOR[th.name] = th.max_rpm / rpm_ref * np.sqrt(t_ref / t_max_model[th.name])
    print(f"{th.name:6s}: model {t_max_model[th.name] / 1e3:5.1f} kN at {th.max_rpm:g} rpm, "
          f"log {t_ref / 1e3:4.1f} kN at {rpm_ref:g} rpm -> rpm factor {RPM_FACTOR[th.name]:.3f}")


def load_mapped(path, *, map_rpm=True, last_dp_s=None):
    """Read a truthsim-dev log, rename thruster columns and (optionally) map the rpm."""
    df = read_log(path).rename(columns=RENAME)
    if map_rpm:
        for name, f in RPM_FACTOR.items():
            df[f"{name}_rpm"] = df[f"{name}_rpm"] * f
    if last_dp_s is not None:  # keep only the last part of station keeping (a small run)
        t_sd = df.time_s[df.dp_active == 0].iloc[0]
        df = df[df.time_s >= t_sd - last_dp_s].reset_index(drop=True)
    return df


# %% [markdown]
# How much does the mapping change what the physics misses? The one-step residual on the
# station-keeping part of one training log, without and with the rpm mapping (its rms also
# holds the wave-frequency motion and the sensor noise, which no mapping removes):

# %%
if HAVE_DATA:
    dyn = DynamicPredictor("gunnerus")
    last = 900.0 if SMALL else None
    for map_rpm in (False, True):
        a = as_log_arrays(load_mapped(train_files[0], map_rpm=map_rpm, last_dp_s=last), vessel)
        prep = prepare_log(dyn.model, a)
        r = prep.residual[prep.trainable_rows(a.dp_active.astype(bool))]
        print(f"rpm mapped: {map_rpm!s:5s}  residual mean {np.round(r.mean(0), 4)}  rms {np.round(np.sqrt((r**2).mean(0)), 4)}"
              "  [m/s2, m/s2, rad/s2]")

# %% [markdown]
# ## 3. Train on the early cases

# %%
if HAVE_DATA:
    train = [load_mapped(f, last_dp_s=900.0 if SMALL else None) for f in train_files]
    hybrid = HybridPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=MEMBERS, max_epochs=MAX_EPOCHS))
    t0 = time.perf_counter()
    hybrid.fit(train)
    print(f"trained {MEMBERS} members on {hybrid.training_info['n_rows']} DP rows from {len(train)} logs "
          f"in {time.perf_counter() - t0:.1f} s")

# %% [markdown]
# ## 4. Forecast the held-out drift
#
# One-minute forecasts from the shutdown and every 15 s after it (ensemble mean and
# +-2 sigma), beside the dynamic model alone and the measured track.

# %%
if HAVE_DATA:
    test = as_log_arrays(load_mapped(held_out), vessel)
    i0 = metrics.shutdown_index(test)
    starts = test.time_s[i0: i0 + 61: 15]
    fc = hybrid.forecast(test, starts, horizon_s=60.0)
    fc_dyn = DynamicPredictor("gunnerus").forecast(test, starts, horizon_s=60.0)
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    lo, hi = i0 - 30, min(i0 + 130, len(test))
    for j, name in enumerate(("north_m", "east_m")):
        a = ax[j]
        a.plot(test.time_s[lo:hi], test.eta[lo:hi, j], "k.", ms=2, label="measured")
        for s in range(len(starts)):
            tt = starts[s] + fc.lead_s
            m, sd = fc.eta[s, :, j], fc.eta_std[s, :, j]
            a.plot(tt, m, color="C0", label="hybrid" if s == 0 else None)
            a.fill_between(tt, m - 2 * sd, m + 2 * sd, color="C0", alpha=0.2,
                           label="hybrid +-2 sigma" if s == 0 else None)
            a.plot(tt, fc_dyn.eta[s, :, j], "C1--", label="dynamic model" if s == 0 else None)
        a.axvline(test.time_s[i0], color="k", ls=":", lw=0.8)
        a.set(xlabel="time [s]", ylabel=f"{name[:-2]} [m]", title=f"{held_out.name}: {name[:-2]}")
        a.legend(fontsize=8)
    fig.tight_layout()

# %% [markdown]
# ## 5. The 15/30/45/60 s table of the held-out case

# %%
if HAVE_DATA:
    paper_scheme = {"guard": False, "nets_after_stop": True}     # nets unguarded, on after the failure too
    predictors = {"hybrid": (hybrid, {}), "hybrid_nets_unguarded": (hybrid, paper_scheme),
                  "dynamic": (DynamicPredictor("gunnerus"), {}), "dead_reckoning": (DeadReckoning("gunnerus"), {})}
    errors = {name: [metrics.drift_errors(p, test, **kw)] for name, (p, kw) in predictors.items()}
    print(f"{held_out.name}: mean absolute error, first 5 / first 20 forecasts (m, m, deg)")
    print(metrics.paper_table(metrics.error_table(errors)).to_string())
