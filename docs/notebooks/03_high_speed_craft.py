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
# # High-speed craft: SS, ARX, NARX-ANN and the hybrid
#
# Ertogan et al. identified surge/pitch models of the planing craft Volcano71 from sea
# trials. No Volcano71 data are public, so hybridship simulates the trials
# (`hybridship.hsc.trials`), then identifies each model on the training part and scores
# it on the validation part: one-step-ahead and in free run. This notebook looks at one
# simulated trial and then runs the whole benchmark, the same code as
# `hybridship benchmark hsc` (results and discussion: [high-speed craft](../../hsc/)).
#
# `HYBRIDSHIP_SMALL=1` runs the benchmark's quick configuration (trials 12 % as long, fewer
# iterations): its numbers are not the benchmark's.

# %%
import os
import shutil
import tempfile

import matplotlib.pyplot as plt
import numpy as np
import torch

from hybridship.hsc.benchmark import run_benchmark
from hybridship.hsc.trials import INPUTS, OUTPUTS, generate_trial, paper_trial
from hybridship.hsc.vessel import load_planing_craft

torch.set_num_threads(1)
SMALL = os.environ.get("HYBRIDSHIP_SMALL") == "1"
craft = load_planing_craft()
print("small run:", SMALL)

# %% [markdown]
# ## One simulated sea trial (sea state 1)
#
# Engine rpm is swept and stepped between 800 and 4000 rpm while the interceptor or tab is
# driven between 10 and 100 % PWM; the logged outputs are speed (GPS, re-aligned for its
# 2-s delay) and pitch. The arrays are in SI units and radians (`INPUTS`, `OUTPUTS`); the
# plot shows speed in knots and pitch in degrees, the units of the benchmark's tables.

# %%
trial = generate_trial(paper_trial(1, seed=0, scale=0.12 if SMALL else 1.0), craft)
U, Y = trial.arrays("train")
print("training inputs", INPUTS, U.shape, "outputs", OUTPUTS, Y.shape)
from hybridship.hsc.simulator import KNOT_M_S  # noqa: E402
labels = ["engine speed [rpm]", "PWM [%]", "heave acc. [m/s2]", "speed [kn]", "pitch [deg]"]
series = np.hstack([U, Y[:, :1] / KNOT_M_S, np.degrees(Y[:, 1:])])
fig, axes = plt.subplots(len(labels), 1, figsize=(9, 7), sharex=True)
for k, ax in enumerate(axes):
    ax.plot(np.arange(len(series)) * 0.1, series[:, k], lw=0.8)
    ax.set_ylabel(labels[k], fontsize=8)
axes[-1].set_xlabel("time [s]")
fig.tight_layout()

# %% [markdown]
# ## The benchmark: R and MAE for every model, sea state, split and scoring mode

# %%
out = tempfile.mkdtemp(prefix="hsc-")
table = run_benchmark(out, seed=0, quick=SMALL, progress=False)
free_val = table[(table["split"] == "validation") & (table["mode"] == "free_run")]
print(free_val.pivot_table(index=["sea_state", "model"], columns="output", values="MAE").round(3))

# %% [markdown]
# The validation MAE in free run, speed in knots and pitch in degrees. At the default size
# (not `HYBRIDSHIP_SMALL=1`) these are the "val." columns of the Table 2 layout on
# [the high-speed craft page](../../hsc/): the hybrid has the lowest error of the four
# models for both outputs in both sea states.

# %%
assert set(table["model"]) == {"ss", "arx", "ann", "hybrid"}
assert np.isfinite(table[["R", "MAE"]].to_numpy()).all()
print("outputs in", out)

# %%
# The benchmark's files were for this notebook only: remove them (comment out to keep them).
shutil.rmtree(out)
