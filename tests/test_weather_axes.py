"""benchmarks/weather_axes.py: which way the simulators' environment pushes a ship on station."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import load_benchmark


@pytest.fixture(scope="module")
def wa():
    return load_benchmark("weather_axes")


def _station_log(heading_deg: float, wave_drift_body_N, wind_from_deg: float, waves_from_deg: float,
                 current_to_deg: float, n: int = 400) -> pd.DataFrame:
    """Truth columns of a ship holding ``heading_deg`` in a steady wave drift (body frame),
    with the last row already drifting (its values must not count)."""
    df = pd.DataFrame({"time_s": np.arange(n, dtype=float), "truth_heading_deg": heading_deg,
                       "truth_tau_wave2_x_N": wave_drift_body_N[0], "truth_tau_wave2_y_N": wave_drift_body_N[1],
                       "truth_tau_wave2_n_Nm": 0.0,
                       "truth_wind_dir_from_deg": wind_from_deg, "truth_wave_dir_from_deg": waves_from_deg,
                       "truth_current_dir_to_deg": current_to_deg, "truth_wind_speed_mps": 8.0,
                       "truth_hs_m": 1.2, "truth_current_speed_mps": 0.3})
    df.loc[n - 1, ["truth_tau_wave2_x_N", "truth_wind_dir_from_deg"]] = (1e9, 0.0)
    return df


def test_the_angles_are_measured_from_the_axes_they_name(wa):
    """Heading 90 deg (east) with the wave drift along -x (the ship pushed west): the force points
    to 270 deg. Waves from 80 deg travel to 260 deg, so the force is 10 deg off them; wind from
    60 deg (to 240): the waves are 20 deg off it; a current to 330 deg is 90 deg off the wind.
    Directions average on the circle (359 and 1 deg give 0, not 180)."""
    df = _station_log(90.0, (-2000.0, 0.0), 60.0, 80.0, 330.0, n=400)
    row = wa.weather_axes("a", df, i_failure=399)
    assert row["wave_drift_kN"] == pytest.approx(2.0)
    assert row["wave_drift_vs_waves_deg"] == pytest.approx(10.0)
    assert row["waves_vs_wind_deg"] == pytest.approx(20.0)
    assert row["current_vs_wind_deg"] == pytest.approx(90.0)
    wrap = _station_log(0.0, (1000.0, 0.0), 0.0, 180.0, 0.0, n=400)
    wrap["truth_wind_dir_from_deg"] = np.where(np.arange(400) % 2 == 0, 359.0, 1.0)
    row = wa.weather_axes("b", wrap, i_failure=399)
    # 151 rows of 359 deg and 150 of 1 deg in the window: within 0.01 deg of north
    assert abs(row["waves_vs_wind_deg"]) == pytest.approx(180.0, abs=0.01)
    assert abs(row["current_vs_wind_deg"]) == pytest.approx(180.0, abs=0.01)
    assert row["wave_drift_vs_waves_deg"] == pytest.approx(0.0, abs=1e-9)


def test_the_summary_counts_either_sense_of_the_wind_axis(wa):
    """A current against the wind (180 deg off) is on the wind's axis; one across it (90 deg) is not."""
    table = pd.DataFrame({"data": ["s"] * 3, "wave_drift_vs_waves_deg": [10.0, -20.0, 30.0],
                          "waves_vs_wind_deg": [5.0, -170.0, 60.0], "current_vs_wind_deg": [180.0, 90.0, -40.0]})
    s = wa.summary(table).iloc[0]
    assert s.logs == 3 and s.wave_drift_vs_waves_deg == 20.0 and s.current_vs_wind_deg == 90.0
    assert s.waves_within_45_deg_of_wind_axis == pytest.approx(2 / 3)
    assert s.current_within_45_deg_of_wind_axis == pytest.approx(2 / 3)
