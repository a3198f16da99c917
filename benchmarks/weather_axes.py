"""Which way the environment pushes a ship on station, against the wind's axis (the simulators' truth).

For every log, over the last 300 s of station keeping: the mean second-order wave drift
force (``truth_tau_wave2_x_N``, ``_y_N`` rotated to NED by the true heading), its direction
against the waves' (``truth_wave_dir_from_deg``, the direction they travel to), the waves'
direction against the wind's (``truth_wind_dir_from_deg``), and the current's
(``truth_current_dir_to_deg``) against the wind's, each as an angle in [-180, 180) deg; the
wind speed, the significant wave height and the current speed. Under the table, per data
set the medians of the absolute angles, and the share of logs within 45 deg of the wind's
axis (either sense: a prior on an axis does not know the sense).

This is what :attr:`~hybridship.residual.environment.EnvironmentConfig.load_prior_across_wind`
assumes: the load (wave drift, the wind model's error) pushes along the weather's axis, a
current comes from anywhere.

Examples::

    python benchmarks/weather_axes.py --out docs/results/weather-axes
    python benchmarks/weather_axes.py --scenarios 20 --seed 100 --out docs/results/weather-axes-own-20
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from _siblings import sibling
from hybridship.evaluation.metrics import shutdown_index
from hybridship.fileio import markdown_table, write_text
from hybridship.frames import body_to_ned, wrap_pi
from hybridship.predictors import as_log_arrays
from hybridship.vessel import load_vessel

WINDOW_S = 300.0


def _wrap_deg(angle_deg) -> float:
    """An angle in [-180, 180) [deg] (:func:`hybridship.frames.wrap_pi`)."""
    return float(np.degrees(wrap_pi(np.radians(angle_deg))))


def _mean_dir_deg(dir_deg: pd.Series) -> float:
    """Circular mean of directions [deg]."""
    rad = np.radians(dir_deg.to_numpy(dtype=float))
    return float(np.degrees(np.arctan2(np.sin(rad).mean(), np.cos(rad).mean())))


def weather_axes(name: str, df: pd.DataFrame, i_failure: int) -> dict:
    """One log's row of the table (see the module's docstring); ``i_failure`` is the first row
    after station keeping."""
    t = df.time_s.to_numpy(dtype=float)
    w = df.iloc[:i_failure][t[:i_failure] >= t[i_failure - 1] - WINDOW_S]
    body = w[["truth_tau_wave2_x_N", "truth_tau_wave2_y_N", "truth_tau_wave2_n_Nm"]].to_numpy(dtype=float)
    f_n, f_e, _ = body_to_ned(body, np.radians(w.truth_heading_deg.to_numpy(dtype=float))).mean(axis=0)
    wind_to = _mean_dir_deg(w.truth_wind_dir_from_deg) + 180.0
    wave_to = _mean_dir_deg(w.truth_wave_dir_from_deg) + 180.0
    return {"log": name, "wind_m_s": w.truth_wind_speed_mps.mean(), "hs_m": w.truth_hs_m.mean(),
            "current_m_s": w.truth_current_speed_mps.mean(), "wave_drift_kN": np.hypot(f_n, f_e) / 1e3,
            "wave_drift_vs_waves_deg": _wrap_deg(np.degrees(np.arctan2(f_e, f_n)) - wave_to),
            "waves_vs_wind_deg": _wrap_deg(wave_to - wind_to),
            "current_vs_wind_deg": _wrap_deg(_mean_dir_deg(w.truth_current_dir_to_deg) - wind_to)}


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Medians of the absolute angles [deg] and the share of logs within 45 deg of the wind's
    axis (either sense), per data set."""
    rows = []
    for data, d in table.groupby("data", sort=False):
        off_axis = lambda col: np.minimum(np.abs(d[col]), 180.0 - np.abs(d[col]))     # noqa: E731
        rows.append({"data": data, "logs": len(d),
                     "wave_drift_vs_waves_deg": np.abs(d.wave_drift_vs_waves_deg).median(),
                     "waves_vs_wind_deg": np.abs(d.waves_vs_wind_deg).median(),
                     "current_vs_wind_deg": np.abs(d.current_vs_wind_deg).median(),
                     "waves_within_45_deg_of_wind_axis": float((off_axis("waves_vs_wind_deg") <= 45.0).mean()),
                     "current_within_45_deg_of_wind_axis": float((off_axis("current_vs_wind_deg") <= 45.0).mean())})
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    evt = sibling("environment_vs_truth")
    args = evt.parse_log_source(__doc__.split("\n")[0], argv)
    if args is None:
        return 2
    vessel = load_vessel("gunnerus")
    data = (f"own {args.seed}-{args.seed + args.scenarios - 1}" if args.scenarios
            else "truthsim-dev" if args.data == evt.TRUTHSIM else args.data.name)
    rows = [{"data": data, **weather_axes(name, df, shutdown_index(as_log_arrays(df, vessel)))}
            for name, df in evt._logs(args)]
    table = pd.DataFrame(rows)
    args.out.mkdir(parents=True, exist_ok=True)
    write_text(args.out / "weather_axes.csv", table.to_csv(index=False, float_format="%.4g"))
    text = (markdown_table(table.round(2)) + "\n\nMedians of the absolute angles [deg], and the share of logs "
            "within 45 deg of the wind's axis (either sense):\n\n" + markdown_table(summary(table).round(2)) + "\n")
    write_text(args.out / "weather_axes.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
