"""benchmarks/environment_vs_truth.py: the estimate against the simulator's truth on the own scenarios."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import load_benchmark
from hybridship.frames import body_to_ned
from hybridship.physics.model import DynamicModel
from hybridship.predictors import as_log_arrays
from hybridship.sim.scenario import embedded_scenarios
from hybridship.sim.synthetic import physics_log


@pytest.fixture(scope="module")
def evt():
    return load_benchmark("environment_vs_truth")


def test_yaw_summary_medians(evt):
    """The held row compares the estimate at the failure with the drift's truth, log by log
    (the drift rows in another order than the station-keeping rows)."""
    table = pd.DataFrame({
        "log": ["a", "b", "c", "c", "a", "b"],
        "window": ["dp"] * 3 + ["drift"] * 3,
        "heading_change_deg": [0.1, -0.2, 0.0, 10.0, 40.0, -60.0],
        "load_yaw_kNm_true": [10.0, 2.0, -3.0, 1.0, -5.0, 2.0],
        "load_yaw_kNm_est": [11.0, 1.0, -3.5, 1.0, 0.0, 4.0],
        "load_yaw_kNm_est_at_failure": [11.0, 1.0, -3.5, -3.5, 11.0, 1.0],
    })
    md = evt.yaw_summary(table)
    rows = {line.split(" | ")[0].strip("| "): [float(v) for v in line.strip(" |").split(" | ")[1:]]
            for line in md.splitlines()[4:]}
    # headings 0.1, 0.2, 0; truths 10, 2, 3; errors 1, 1, 0.5
    assert rows["station keeping (dp)"] == [0.1, 3.0, 1.0]
    assert rows["drift, online estimate"] == [40.0, 2.0, 2.0]          # errors 5, 2, 0
    assert rows["drift, estimate at the failure held"] == [40.0, 2.0, 4.5]   # 16, 1, 4.5
    assert "Medians over the 3 logs" in md


def test_station_keeping_yaw_split(evt):
    """The yaw load's and the thrust error's errors, their sum's, how the two correlate, how
    the sum's error ranks with the true current, and the current's yaw moment at rest beside
    it: its size, its correlation with the sum's error and what is left without it, over the
    logs (nan for two logs, without a warning)."""
    dp = pd.DataFrame({
        "load_yaw_kNm_est": [11.0, 1.0, -3.5, 0.0], "load_yaw_kNm_true": [10.0, 2.0, -3.0, 4.0],    # 1, -1, -0.5, -4
        "thrust_error_n_kNm_est": [0.0, 3.0, 1.0, 2.0], "thrust_error_n_kNm_true": [2.0, 0.0, 0.0, 0.0],  # -2, 3, 1, 2
        "current_m_s_true": [0.1, 0.3, 0.05, 0.4],
        "current_yaw_at_rest_kNm": [-1.5, 2.0, 0.0, -1.0],          # the sums less these: 0.5, 0, 0.5, -1
    })
    md = evt.station_keeping_yaw_split(dp)
    values = [float(v) for v in md.splitlines()[-1].strip(" |").split(" | ")]
    # sums -1, 2, 0.5, -2: |.| 1, 2, 0.5, 2 rank with the currents 0.1, 0.3, 0.05, 0.4 (ties averaged)
    assert values[:3] == [1.0, 2.0, 1.5]
    assert values[3] == pytest.approx(np.corrcoef([1, -1, -0.5, -4], [-2, 3, 1, 2])[0, 1], abs=0.005)
    assert values[4] == pytest.approx(0.95, abs=0.005)
    assert values[5] == 1.25
    assert values[6] == pytest.approx(np.corrcoef([-1, 2, 0.5, -2], [-1.5, 2, 0, -1])[0, 1], abs=0.005)
    assert values[7] == 0.5
    two = [float(v) for v in evt.station_keeping_yaw_split(dp.iloc[:2]).splitlines()[-1].strip(" |").split(" | ")]
    assert np.isnan(two[3:5]).all() and np.isnan(two[6]) and two[2] == 1.5    # medians still; no correlation of two
    assert two[5] == 1.75 and two[7] == 0.25


def test_own_scenarios_written(evt, tmp_path):
    """--scenarios reads the own simulator's logs: one row per window, the ship has not turned
    on station, and the summary is written."""
    assert evt.main(["--scenarios", "1", "--seed", "100", "--out", str(tmp_path)]) == 0
    table = pd.read_csv(tmp_path / "environment_vs_truth.csv")
    assert list(table.window) == ["dp", "drift"] and set(table.log) == {"embedded_seed0100"}
    assert abs(table.heading_change_deg[0]) < 5.0
    assert np.isfinite(table.drop(columns=["log", "window"]).to_numpy()).all()
    # the windows, from the log itself: the last 300 s before the failure and 60..300 s after it
    log = embedded_scenarios(1, 100)[0].log
    i0 = int(np.flatnonzero(log.dp_active.to_numpy() == 0)[0])
    heading = np.degrees(np.unwrap(np.radians(log.truth_heading_deg.to_numpy())))
    for k, rows in enumerate((np.arange(i0 - 300, i0), np.arange(i0 + 60, i0 + 301))):
        assert table.heading_change_deg[k] == pytest.approx(heading[rows].mean() - heading[i0], rel=1e-3, abs=1e-3)
        assert table.current_m_s_true[k] == pytest.approx(log.truth_current_speed_mps.to_numpy()[rows].mean(),
                                                          rel=1e-3)
    assert abs(table.heading_change_deg[1]) > 5.0                  # the drift turns: a window off by 60 s shows
    # the estimate at the failure is one value, held through both windows
    assert table.load_yaw_kNm_est_at_failure[0] == table.load_yaw_kNm_est_at_failure[1]
    md = (tmp_path / "environment_vs_truth.md").read_text()
    assert "drift, estimate at the failure held" in md
    assert (tmp_path / "environment_vs_truth.png").stat().st_size > 0
    factors = pd.read_csv(tmp_path / "thrust_error_factors.csv")
    # one factor per thruster of the packaged Gunnerus, from the filter's per-thruster state
    assert list(factors.columns) == ["log", "thrust_error_tunnel", "thrust_error_port", "thrust_error_stbd"]
    assert list(factors.log) == ["embedded_seed0100"] and factors.iloc[0, 1:].abs().lt(1.0).all()


def test_heading_change_through_north(evt):
    """359 -> 1 deg is a turn of 2 deg, not of -358."""
    heading = np.array([358.0, 359.0, 359.5, 0.5, 1.0, 1.5])
    assert evt.heading_change_deg(heading, 2, np.array([3, 4, 5])) == pytest.approx(1.5)
    assert evt.heading_change_deg(heading[::-1], 2, np.array([3, 4, 5])) == pytest.approx(-5.0 / 3.0)


def test_truth_is_the_simulators_loads_less_the_models(evt):
    """_truth: the current as (speed, direction to [rad]); the load the estimator stands for,
    the wave drift plus the wind model's error (the logged wind load less the model's at the
    logged wind), rotated to NED; and the thrust model's error, the logged thrust load less the
    model's at the logged commands, left in the body frame. On a moving, turning ship with
    wind and changing commands, so that a wrong sign, part or frame shows."""
    m = DynamicModel("gunnerus")
    df = physics_log(m, seed=3, duration_s=200.0, t_shutdown_s=150.0)
    rng = np.random.default_rng(0)
    logged = {part: rng.normal(0.0, 1.0, (len(df), 3)) * [2e4, 1e4, 1e5] for part in ("wave2", "wind", "thrust")}
    df = df.assign(truth_current_speed_mps=0.3, truth_current_dir_to_deg=200.0,
                   **{f"truth_tau_{part}_{c}": v[:, j] for part, v in logged.items()
                      for j, c in enumerate(("x_N", "y_N", "n_Nm"))})
    a = as_log_arrays(df, m.vessel)
    cur, load, thrust_error = evt._truth(df, m, a)

    # the model's loads by part (hull, actuators, wind, external) at the logged states and inputs
    _, parts, _ = m.acceleration(a.eta, np.nan_to_num(a.nu), rpm=a.rpm, azimuth_rad=a.azimuth_rad, wind=a.wind,
                                 return_parts=True)
    wind_model, thrust_model = parts[:, 2], parts[:, 1]
    assert np.abs(wind_model[:, :2]).max() > 1e3 and np.abs(thrust_model[:100, :2]).max() > 1e3   # both matter
    psi = a.eta[:, 2]
    assert np.ptp(np.degrees(np.unwrap(psi))) > 5.0                               # the rotation turns
    body = logged["wave2"] + logged["wind"] - wind_model
    np.testing.assert_allclose(load, body_to_ned(body, psi), rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(thrust_error, logged["thrust"] - thrust_model, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(cur, np.tile([0.3, np.radians(200.0)], (len(df), 1)))


@pytest.mark.parametrize("argv, message", [(["--scenarios", "21"], "--scenarios: expected 1-20"),
                                           (["--scenarios", "1", "--seed", "-1"], "--seed: expected a non-negative"),
                                           (["--scenarios", "1", "--data", "x"], "give one source of logs")])
def test_bad_arguments(evt, tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as e:
        evt.main(argv + ["--out", str(tmp_path)])
    assert e.value.code == 2
    assert message in capsys.readouterr().err


def test_drift_hull_coefficients_reach_the_filter(evt, tmp_path, capsys):
    """--drift-hull gives each log's filter its coefficient from a drift benchmark's
    drift_hull.csv: the station keeping is the same, the drift's yaw load differs; a log
    without a row is refused by name."""
    csv = tmp_path / "drift_hull.csv"
    csv.write_text("log,coefficient_rad_per_m2\nembedded_seed0100,0.004\n")
    assert evt.main(["--scenarios", "1", "--seed", "100", "--out", str(tmp_path / "k")]) == 0
    assert evt.main(["--scenarios", "1", "--seed", "100", "--drift-hull", str(csv), "--out", str(tmp_path / "h")]) == 0
    plain, with_k = (pd.read_csv(tmp_path / d / "environment_vs_truth.csv").set_index("window") for d in "kh")
    assert plain.loc["dp", "load_yaw_kNm_est"] == with_k.loc["dp", "load_yaw_kNm_est"]
    assert plain.loc["drift", "load_yaw_kNm_est"] != with_k.loc["drift", "load_yaw_kNm_est"]
    csv.write_text("log,coefficient_rad_per_m2\nother,0.004\n")
    assert evt.main(["--scenarios", "1", "--seed", "100", "--drift-hull", str(csv), "--out", str(tmp_path)]) == 2
    assert "no row for log embedded_seed0100" in capsys.readouterr().err
    for text, message in (("log,k\nembedded_seed0100,0.004\n", "expected a drift benchmark's drift_hull.csv"),
                          ("log,coefficient_rad_per_m2\nembedded_seed0100,\n", "is not a number for log")):
        csv.write_text(text)
        assert evt.main(["--scenarios", "1", "--drift-hull", str(csv), "--out", str(tmp_path)]) == 2
        assert message in capsys.readouterr().err
    assert evt.main(["--scenarios", "1", "--drift-hull", str(tmp_path / "none.csv"), "--out", str(tmp_path)]) == 2
    assert "expected a drift benchmark's drift_hull.csv" in capsys.readouterr().err


def test_the_currents_yaw_moment_at_rest_keeps_the_hulls_symmetry(evt):
    """A current along the ship puts no yaw moment on her at rest; mirrored to the other side of
    the bow, the moment changes sign and keeps its size (the hull is symmetric port and
    starboard), and it grows with the current."""
    model = DynamicModel("gunnerus")
    psi = np.radians([30.0, 30.0, 30.0, 30.0, 30.0])
    cur = np.array([[0.3, psi[0]], [0.3, psi[0] + np.pi], [0.3, psi[0] + 0.6], [0.3, psi[0] - 0.6],
                    [0.6, psi[0] + 0.6]])
    n = evt.current_yaw_at_rest(model, psi, cur)
    assert abs(n[0]) < 1e-6 * abs(n[2]) and abs(n[1]) < 1e-6 * abs(n[2])
    assert n[2] != 0.0 and n[3] == pytest.approx(-n[2], rel=1e-9)
    assert abs(n[4]) > 3.0 * abs(n[2])
