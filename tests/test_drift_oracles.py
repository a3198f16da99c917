"""benchmarks/drift_oracles.py: the physics given parts of the simulator's truth."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import load_benchmark
from hybridship.forecast_inputs.wind import WindForecast
from hybridship.frames import ned_to_body, wrap_pi
from hybridship.physics.model import TAU_PARTS, DynamicModel
from hybridship.sim.scenario import embedded_scenarios
from hybridship.vessel import load_vessel


@pytest.fixture(scope="module")
def oracles():
    return load_benchmark("drift_oracles")


@pytest.fixture(scope="module")
def scenario_log():
    return embedded_scenarios(1, 100)[0].log


def test_truth_given_to_the_model_that_made_it(oracles, scenario_log):
    """On our own simulator, whose hull is the model's, the true loads and current leave far
    less heading error than the model wind alone; every oracle row is there, with the logged
    wind's rows only when a wind forecast is given."""
    model = DynamicModel(load_vessel("gunnerus"))
    rows = oracles.failure_oracles(model, scenario_log, WindForecast(mean_window_s=300.0, time_constant_s=20.0))
    assert {"model wind", "model wind, logged held", "model wind, fitted forecast", "model wind, true future",
            "true loads and current"} <= set(rows)
    assert all(np.isfinite(v).all() and min(v) >= 0 for v in rows.values())
    assert rows["true loads and current"][0] < 0.5 * rows["model wind"][0]
    assert "model wind, logged held" not in oracles.failure_oracles(model, scenario_log)


def _model_made_drift(oracles, model, wind_speed_mps):
    """A drift log whose truth is ``model`` itself, stepped one second at a time with the
    commands at zero: in a current of 0.4 m/s to 060 deg, the wind ``wind_speed_mps`` (one value
    per row) from 200 deg, and a wave-drift acceleration constant in NED (logged as the body
    force that gives it at each row's heading). The logged wind load is the model's wind part at
    each row's state, as a simulator logs its whole air load: with the wind relative to the
    moving ship, so in still air the ship's own air drag. The ship turns through north (heading
    logged in [0, 360)). Returns the log and the true states (eta, nu), each (rows, 3)."""
    n_dp = 30
    n = n_dp + oracles.N_STARTS + oracles.HORIZON
    wave_ned = np.array([4e-3, -3e-3, 2e-5])                     # [m/s2, m/s2, rad/s2]
    current = np.array([[0.4, np.radians(60.0)]])
    wind = np.column_stack([wind_speed_mps, np.full(n, np.radians(200.0))])
    zeros = np.zeros((1, model.n_channels))
    eta, nu = np.zeros((n, 3)), np.zeros((n, 3))
    eta[0], nu[0] = [0.0, 0.0, np.radians(340.0)], [0.3, -0.1, 0.01]
    for k in range(n - 1):
        step = model.rollout(eta[k:k + 1], nu[k:k + 1], 1, rpm=zeros, azimuth_rad=zeros, wind=wind[k:k + 1],
                             current=current, accel_ext=ned_to_body(wave_ned, eta[k:k + 1, 2]))
        eta[k + 1], nu[k + 1] = step.eta[0, -1], step.nu[0, -1]
    wave_force = ned_to_body(wave_ned, eta[:, 2]) @ model.mass_matrix.T
    at_rows = np.zeros((n, model.n_channels))
    _, parts, _ = model.acceleration(eta, nu, rpm=at_rows, azimuth_rad=at_rows, wind=wind, current=current,
                                     return_parts=True)
    wind_force = parts[:, TAU_PARTS.index("wind")]
    log = pd.DataFrame({
        "dp_active": (np.arange(n) < n_dp).astype(int),
        "truth_north_lf_m": eta[:, 0], "truth_east_lf_m": eta[:, 1],
        "truth_heading_lf_deg": np.degrees(eta[:, 2]) % 360,
        "truth_u_lf_mps": nu[:, 0], "truth_v_lf_mps": nu[:, 1], "truth_r_lf_degps": np.degrees(nu[:, 2]),
        "truth_current_speed_mps": 0.4, "truth_current_dir_to_deg": 60.0,
        "truth_wind_speed_mps": wind_speed_mps, "truth_wind_dir_from_deg": 200.0,
        **{f"truth_tau_wind_{c}": wind_force[:, j] for j, c in enumerate(oracles.DOFS)},
        **{f"truth_tau_wave2_{c}": wave_force[:, j] for j, c in enumerate(oracles.DOFS)}})
    return log, eta, nu


def test_oracles_given_all_the_truth_are_exact_on_a_drift_the_model_made(oracles):
    """Where the model made the drift, the rows that give it every part of the truth it was
    made with (current in the hull, the wave drift held in NED, the wind as it was) forecast it
    exactly, and a row without one of them does not; the model wind row is the 60-s error of
    the bare model from each true start, in degrees and the mean of north's and east's [m]."""
    model = DynamicModel(load_vessel("gunnerus"))
    n = 30 + oracles.N_STARTS + oracles.HORIZON
    calm_log, eta, nu = _model_made_drift(oracles, model, np.zeros(n))
    calm = oracles.failure_oracles(model, calm_log)
    assert np.ptp(eta[:, 2]) > np.radians(30.0)                  # the held wave drift turns with the ship
    for given in ("current in the hull + wave drift held", "current in the hull + wave drift held, true future wind"):
        np.testing.assert_allclose(calm[given], (0.0, 0.0), atol=1e-6, err_msg=given)
    # the logged loads are held over each 1-s step, while the air drag of the model's ship
    # changes with its speed within the step; adding the model's own still-air drag on top
    # (the logged load counted twice) would leave about 0.05 deg and 0.02 m
    np.testing.assert_allclose(calm["true loads and current"], (0.0, 0.0), atol=1e-3)
    for given in ("model wind", "current in the hull", "wave drift held"):
        assert min(calm[given]) > 0.01, given

    # the bare model from each of the 20 true starts after the failure, against the truth 60 s on
    st = 30 + np.arange(oracles.N_STARTS)
    zeros = np.zeros((st.size, model.n_channels))
    end = model.rollout(eta[st], nu[st], oracles.HORIZON, rpm=zeros, azimuth_rad=zeros).eta[:, -1]
    truth = eta[st + oracles.HORIZON]
    heading_deg = np.degrees(np.abs(wrap_pi(end[:, 2] - truth[:, 2]))).mean()
    north_east_m = (np.abs(end[:, 0] - truth[:, 0]).mean() + np.abs(end[:, 1] - truth[:, 1]).mean()) / 2
    np.testing.assert_allclose(calm["model wind"], (heading_deg, north_east_m), rtol=1e-6)

    # a wind that rises from 4 to 14 m/s: only the row with its true future stays exact
    windy = oracles.failure_oracles(model, _model_made_drift(oracles, model, np.linspace(4.0, 14.0, n))[0])
    np.testing.assert_allclose(windy["current in the hull + wave drift held, true future wind"], (0.0, 0.0),
                               atol=1e-6)
    assert min(windy["current in the hull + wave drift held"]) > 0.01


def test_yaw_damping_variant_and_bad_vessel(oracles, tmp_path, capsys):
    """The yaw-damping variant file differs from the packaged one in its linear yaw damping
    only (twice it); an unreadable --vessel is refused by name."""
    packaged = load_vessel("gunnerus")
    variant = load_vessel(oracles.Path(oracles.__file__).parent / "vessel_variants" / "gunnerus_yaw_damping_x2.toml")
    d_packaged, d_variant = (DynamicModel(v).arrays.d_lin.copy() for v in (packaged, variant))
    assert d_variant[2, 2] == pytest.approx(2 * d_packaged[2, 2])
    d_variant[2, 2] = d_packaged[2, 2]
    np.testing.assert_array_equal(d_variant, d_packaged)
    np.testing.assert_array_equal(DynamicModel(variant).mass_matrix, DynamicModel(packaged).mass_matrix)
    assert oracles.main(["--vessel", str(tmp_path / "missing.toml"), "--own", "1", "--out", str(tmp_path)]) == 2
    assert "--vessel" in capsys.readouterr().err


def test_per_log_table_written(oracles, tmp_path, monkeypatch):
    """One row per log and oracle beside the pooled table; of one log, the pooled rows are
    its own errors (to the tables' 2 decimals) and their ratios to its model wind row."""
    monkeypatch.setattr(oracles, "TRUTHSIM", tmp_path / "absent")
    assert oracles.main(["--own", "1", "--own-seed", "100", "--out", str(tmp_path)]) == 0
    per_log = pd.read_csv(tmp_path / "drift_oracles_per_log.csv")
    pooled = pd.read_csv(tmp_path / "drift_oracles.csv")
    assert set(per_log.log) == {"embedded_seed0100"} and len(per_log) == len(pooled)
    per_log, pooled = per_log.set_index("given"), pooled.set_index("given")
    assert list(per_log.index) == list(pooled.index)
    for col, ratio in (("heading_deg", "heading_ratio"), ("north_east_m", "north_east_ratio")):
        np.testing.assert_allclose(pooled[col], per_log[col], atol=0.006, err_msg=col)
        np.testing.assert_allclose(pooled[ratio], per_log[col] / per_log.loc["model wind", col], atol=0.01,
                                   err_msg=ratio)


def test_an_own_set_the_simulator_cannot_make_is_a_usage_error(oracles, tmp_path, capsys):
    """--own outside 1-20 or a negative --own-seed stop with a usage error (exit 2) naming the
    option, not with the simulator's traceback, and nothing is written."""
    for bad in (["--own", "0"], ["--own", "21"], ["--own-seed", "-1"]):
        with pytest.raises(SystemExit) as exc:
            oracles.main([*bad, "--out", str(tmp_path)])
        assert exc.value.code == 2
        assert bad[0] in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
