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
# # Drift-off: how long until the limit after a blackout?
#
# Before a DP operation close to a platform the crew must know how long after a blackout
# the vessel takes to reach the limit of the operation, and where to set the watch
# circles. This notebook uses `hybridship.driftoff` ([the page](../../drift-off/)):
#
# 1. planning mode: Monte-Carlo blackouts of Gunnerus in one weather state, with stated
#    uncertainty, at eight headings; the polar plot and the exceedance curves;
# 2. the watch circles and the probability of exceeding each radius within the reaction time;
# 3. live mode on a simulated station-keeping log: "a blackout now", compared with what the
#    vessel did after its own failure;
# 4. a small season sweep over a table of weather states.
#
# `HYBRIDSHIP_SMALL=1` uses fewer samples and states (the test suite runs it that way).

# %%
import math
import os
import time

import matplotlib.pyplot as plt
import numpy as np

from hybridship.driftoff.live import blackout_now, environment_from_log
from hybridship.driftoff.planning import DriftOffSettings, simulate_blackouts
from hybridship.driftoff.report import exceedance_plot, polar_plot
from hybridship.driftoff.season import season_sweep
from hybridship.driftoff.weather import WeatherState, WeatherUncertainty
from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

SMALL = os.environ.get("HYBRIDSHIP_SMALL", "0") == "1"
N_SAMPLES = 30 if SMALL else 200
N_STATES = 4 if SMALL else 48
print(f"HYBRIDSHIP_SMALL={int(SMALL)}: {N_SAMPLES} samples per heading, {N_STATES} states in the sweep")

# %% [markdown]
# ## 1. Planning mode
#
# Wind 10 m/s from north (1.5 m/s, 15 deg uncertainty), Hs 1.2 m, Tp 6.5 s from the wind
# direction, current 0.25 m/s towards east. The vessel's parameters are drawn with the
# `[true_vessel]` spread of `vessels/gunnerus.toml`.

# %%
weather = WeatherState.from_degrees(wind_speed_m_s=10.0, wind_dir_deg=0.0, hs_m=1.2, tp_s=6.5,
                                    current_m_s=0.25, current_dir_deg=90.0)
unc = WeatherUncertainty(wind_speed_m_s=1.5, wind_dir_rad=math.radians(15.0), hs_m=0.2, tp_s=0.5,
                         current_speed_m_s=0.1, current_dir_rad=math.radians(30.0))
settings = DriftOffSettings(n_samples=N_SAMPLES, radii_m=(3.0, 5.0, 10.0), reaction_times_s=(20.0, 40.0, 60.0))
headings = np.radians(np.arange(0, 360, 45))
t0 = time.perf_counter()
res = simulate_blackouts("gunnerus", weather, headings, uncertainty=unc, settings=settings)
print(f"{headings.size} headings x {N_SAMPLES} samples in {time.perf_counter() - t0:.2f} s")
times, watch = res.summary_frames(quantile=0.9)
times.round(2)

# %% [markdown]
# The polar plot: time to reach each radius (median, and the 10 % quantile dashed)
# against the direction the wind comes from, relative to the bow. Beam wind (90, 270)
# pushes the large side area and the sway-damped hull away fastest.

# %%
fig = polar_plot(res)
plt.show()

# %%
fig = exceedance_plot(res)
plt.show()

# %% [markdown]
# ## 2. Watch circles
#
# The 90 % watch circle for a reaction time is the distance that 90 % of the sampled
# blackouts have not exceeded when the operator has reacted.

# %%
watch.pivot(index="heading_deg", columns="reaction_time_s", values="watch_radius_m").round(2)

# %% [markdown]
# ## 3. Live mode: a blackout now
#
# A simulated station-keeping log (`simulate_dp_loss`), cut just before its DP failure. The
# environment comes from the log only: the mean measured wind and its gustiness over the
# last 120 s, and the [environment estimator](../../concepts/environment/) run over the last
# 900 s (the current, acting through the relative velocity, and the load, with members
# drawn from its posterior). `environment_from_log(..., method="mean")` uses the 900-s mean
# of the residual acceleration the model does not explain instead.

# %%
cfg = DPLossConfig(seed=5, t_shutdown_s=1200.0 if SMALL else 2400.0, drift_s=300.0)
log = simulate_dp_loss(cfg)
b = int(np.flatnonzero(log["dp_active"].to_numpy() == 0)[0])
t0 = time.perf_counter()
est = environment_from_log(log.iloc[:b], "gunnerus", n_members=N_SAMPLES)   # one environment draw per sample
live = blackout_now(est, "gunnerus", DriftOffSettings(n_samples=N_SAMPLES, radii_m=(5.0, 10.0)))
print(f"live update: {time.perf_counter() - t0:.3f} s")
d = np.hypot(log["truth_north_lf_m"].to_numpy()[b:] - log["truth_north_lf_m"].iloc[b],
             log["truth_east_lf_m"].to_numpy()[b:] - log["truth_east_lf_m"].iloc[b])
t = log["time_s"].to_numpy()[b:] - log["time_s"].iloc[b]
for r, radius in enumerate(live.radii_m):
    actual = t[np.argmax(d >= radius)] if (d >= radius).any() else np.inf
    pred = live.t_reach_s[0, :, r]
    print(f"{radius:4.0f} m: actual {actual:6.1f} s; predicted 10/50/90 % "
          f"{live.time_quantiles()[0, r].round(1)} s; "
          f"actual at the {100 * np.mean(pred <= actual):.0f}th percentile")

# %% [markdown]
# ## 4. A small season sweep
#
# Random weather states stand in for an hourly hindcast (a CSV in the documented columns
# is read with `read_weather_table`). `scheduler=None` runs in this process;
# `scheduler="local"` or a scheduler address runs the same chunks on Dask with identical
# results.

# %%
rng = np.random.default_rng(0)
states = [WeatherState.from_degrees(wind_speed_m_s=rng.uniform(3, 15), wind_dir_deg=rng.uniform(0, 360),
                                    hs_m=rng.uniform(0.2, 2.0), tp_s=rng.uniform(4, 8),
                                    current_m_s=rng.uniform(0, 0.4), current_dir_deg=rng.uniform(0, 360))
          for _ in range(N_STATES)]
season = season_sweep("gunnerus", states, headings, settings=DriftOffSettings(n_samples=max(10, N_SAMPLES // 4)),
                      chunk_size=8, progress=False)
print(f"{len(states)} states in {season.wall_s:.1f} s")
season.operability(max_p_exceed=0.1).query("reaction_time_s == 30 and radius_m == 5").round(2)
