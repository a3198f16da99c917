"""The waves' axis from the wave-frequency motion, and the yaw load turned with it, against the simulators' truth.

For every log with a failure (truthsim-dev by default, or the own simulator's scenarios with
``--scenarios N --seed S``), :func:`hybridship.residual.wave_direction.wave_axis` finds the
waves' axis in the station keeping before the failure (default settings of
:class:`~hybridship.residual.environment.EnvironmentConfig`). The table compares:

* the axis relative to the heading at the failure with the simulator's wave direction
  (``truth_wave_dir_from_deg``) relative to it, both modulo 180 deg;
* the true yaw load (second-order wave drift plus the wind model's error, as in
  ``benchmarks/environment_vs_truth.py``) after the failure, over 0-80 s (what the first
  twenty 60-s forecasts span) and 60-300 s, with two forecasts of it that know the true
  station-keeping load (its mean over the last 300 s before the failure), so that only the
  shape is compared: held (the default), and turned with the axis along the ship's true
  heading from its value at the heading at the failure, as a forecast started there turns
  it (``EnvironmentConfig.wave_turned_yaw_load``; held where the option holds it).

Writes ``wave_direction.csv`` and ``wave_direction.md``::

    python benchmarks/wave_direction.py --out docs/results/wave-direction
    python benchmarks/wave_direction.py --scenarios 20 --seed 100 --out docs/results/wave-direction-own-20
"""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd

from hybridship.evaluation.metrics import shutdown_index
from hybridship.physics.model import DynamicModel
from hybridship.predictors import as_log_arrays
from hybridship.residual.environment import EnvironmentConfig
from hybridship.residual.wave_direction import wave_axis, yaw_load_factor

from _siblings import sibling  # benchmarks/ is on sys.path when a script runs

WINDOWS_S = ((0.0, 80.0), (60.0, 300.0))


def axis_error_deg(axis_rel_deg: float, true_rel_deg: float) -> float:
    """Difference of two axes [deg], modulo 180, in [-90, 90)."""
    return float((axis_rel_deg - true_rel_deg + 90.0) % 180.0 - 90.0)


def log_rows(name: str, df: pd.DataFrame, a, load_yaw_true: np.ndarray, config: EnvironmentConfig) -> list[dict]:
    """One row per window of one log (see the module docstring)."""
    i0 = shutdown_index(a)
    dt = a.dt_s
    dp = np.arange(max(0, i0 - int(round(config.wave_axis_window_s / dt))), i0)
    dp = dp[a.dp_active[dp] != 0]
    psi = np.unwrap(a.eta[:, 2])
    axis = wave_axis(a.time_s[dp], a.eta[dp, 2], a.nu[dp, 0], a.nu[dp, 1], window_s=config.wave_axis_window_s,
                     min_anisotropy=config.min_wave_anisotropy) if dp.size > 1 else None
    # as a forecast started at the failure turns it: the shape referred to the heading there
    sin2_0 = np.nan if axis is None else float(np.sin(2.0 * (axis.axis_ned_rad - psi[i0 - 1])))
    used = axis is not None and abs(sin2_0) >= config.min_wave_sin2
    axis_arr = np.array([[axis.axis_ned_rad, sin2_0] if used else [np.nan, np.nan]])
    true_rel = float((df.truth_wave_dir_from_deg.to_numpy()[i0] - np.degrees(psi[i0 - 1])) % 180.0)
    axis_rel = np.nan if axis is None else float(np.degrees(axis.axis_ned_rad - psi[i0 - 1]) % 180.0)
    held = float(np.mean(load_yaw_true[np.arange(max(0, i0 - int(round(300.0 / dt))), i0)]))
    rows = []
    for lo, hi in WINDOWS_S:
        w = np.arange(i0 + int(round(lo / dt)), min(len(psi), i0 + int(round(hi / dt)) + 1))
        turned = held * yaw_load_factor(psi[w], np.repeat(axis_arr, w.size, axis=0))
        rows.append({
            "log": name, "window": f"{lo:g}-{hi:g} s",
            "anisotropy": np.nan if axis is None else axis.anisotropy,
            "sin2_station": np.nan if axis is None else axis.sin2_station, "turned": used,
            "axis_rel_deg": axis_rel, "true_rel_deg": true_rel,
            "axis_error_deg": np.nan if axis is None else axis_error_deg(axis_rel, true_rel),
            "heading_change_deg": float(np.degrees(psi[w].mean() - psi[i0 - 1])),
            "load_yaw_kNm_true": load_yaw_true[w].mean() / 1e3, "load_yaw_kNm_held": held / 1e3,
            "error_held_kNm": np.abs(load_yaw_true[w] - held).mean() / 1e3,
            "error_turned_kNm": np.abs(load_yaw_true[w] - turned).mean() / 1e3,
        })
    return rows


def summary(table: pd.DataFrame) -> str:
    """Median axis error where an axis was found, and the mean errors of the two load forecasts per window."""
    first = table.drop_duplicates("log")
    found = first.dropna(subset=["axis_error_deg"])
    lines = [f"Axis found in {len(found)} of {len(first)} station keepings (median |error| "
             f"{found.axis_error_deg.abs().median():.1f} deg, largest {found.axis_error_deg.abs().max():.1f} deg); "
             f"the load turned in {int(first.turned.sum())}.", "",
             "| window | yaw load error, held [kN m] | turned [kN m] |", "| --- | --- | --- |"]
    for win, g in table.groupby("window", sort=False):
        lines.append(f"| {win} | {g.error_held_kNm.mean():.2f} | {g.error_turned_kNm.mean():.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    evt = sibling("environment_vs_truth")      # its truth loads and log sources
    args = evt.parse_log_source(__doc__.split("\n")[0], argv)
    if args is None:
        return 2
    model = DynamicModel("gunnerus")
    config = EnvironmentConfig(wave_turned_yaw_load=True)
    rows = []
    for name, df in evt._logs(args):
        a = as_log_arrays(df, model.vessel)
        _, load_t, _ = evt._truth(df, model, a)
        rows += log_rows(name, df, a, load_t[:, 2], config)
    table = pd.DataFrame(rows)
    evt.write_table(args.out, "wave_direction", table, summary(table))
    return 0


if __name__ == "__main__":
    sys.exit(main())
