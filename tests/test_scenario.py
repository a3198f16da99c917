"""DP-loss scenario simulator (hybridship.sim.scenario) and the ``simulate`` CLI.

Scenarios are shortened (10 min DP, 5 min drift) to keep the module at a few seconds.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest

from hybridship.cli import main, parse_seeds
from hybridship.logs.io import read_log, validate_log, write_log
from hybridship.physics.model import DynamicModel
from hybridship.sim.allocation import bollard_thrust_limits
from hybridship.sim.environment import SeaState
from hybridship.sim.scenario import (DPLossConfig, SensorNoise, drift_statistics,
                                     embedded_scenarios, log_file_name, simulate_dp_loss, sweep)

THRUSTERS = dict(channel_names=["tunnel", "port", "stbd"], rotatable=[False, True, True])
SHORT = dict(t_shutdown_s=600.0, drift_s=300.0)
TINY = dict(t_shutdown_s=120.0, drift_s=60.0)  # for checks that need no physics


@pytest.fixture(scope="module", params=[0, 4], ids=lambda s: f"seed{s}")
def moderate(request):
    """A Beaufort 3-4 scenario: 10 +- 0.4 min on DP, then 5 min of drift."""
    cfg = DPLossConfig(seed=request.param, beaufort=(3, 4), **SHORT)
    return cfg, simulate_dp_loss(cfg)


# --------------------------------------------------------------------------- config


@pytest.mark.parametrize("changes, field", [
    (dict(drift_s=-1.0), "drift_s"),
    (dict(drift_s=100.5), "drift_s"),
    (dict(seed=-3), "seed"),
    (dict(sim_dt_s=0.3), "dt_s"),
    (dict(control_dt_s=0.75), "control_dt_s"),
    (dict(heading_mode="downwind"), "heading_mode"),
    (dict(beaufort=(5, 2)), "beaufort"),
    (dict(t_shutdown_s=float("nan")), "t_shutdown_s"),
    (dict(t_shutdown_s=100.0, t_shutdown_jitter_s=95.0), "t_shutdown_s"),
    (dict(noise={"gnss_white": 0.1}), "noise"),
    (dict(noise={"uv_white_m_s": -0.1}), "noise.uv_white_m_s"),
    (dict(rpm_time_constant_s=0.0), "rpm_time_constant_s"),
    (dict(n_wave_components=0), "n_wave_components"),
])
def test_config_validation_names_the_field(changes, field):
    with pytest.raises((ValueError, TypeError), match=field):
        DPLossConfig(**changes)


def test_a_shutdown_that_rounds_to_less_dp_than_the_least_is_refused():
    """The shutdown time is rounded to dt_s: t_shutdown_s 10 s with dt_s 20 s passed the check of
    10 s of DP and shut down at 0 s, a log without a single row on DP."""
    with pytest.raises(ValueError, match=r"^t_shutdown_s: .*at least 10 s of DP.*rounded to dt_s = 20 s: 0 s"):
        DPLossConfig(t_shutdown_s=10.0, t_shutdown_jitter_s=0.0, dt_s=20.0, drift_s=40.0)
    with pytest.raises(ValueError, match=r"^t_shutdown_s: .*rounded to dt_s = 30 s: 0 s"):
        DPLossConfig(t_shutdown_s=100.0, t_shutdown_jitter_s=88.0, dt_s=30.0, drift_s=60.0)     # as early as 12 s
    cfg = DPLossConfig(t_shutdown_s=25.0, t_shutdown_jitter_s=0.0, dt_s=10.0, drift_s=40.0, control_dt_s=2.0)
    assert simulate_dp_loss(cfg)["dp_active"].iloc[:2].tolist() == [1, 1]


def test_a_shutdown_too_early_says_the_jitter_is_4_percent_by_default():
    """The message named t_shutdown_jitter_s, which `hybridship simulate` has no option for,
    without saying where its value came from."""
    with pytest.raises(ValueError, match=r"^t_shutdown_s: the earliest shutdown, t_shutdown_s less its jitter "
                                         r"t_shutdown_jitter_s \(by default 4 % of t_shutdown_s\), must leave at "
                                         r"least 10 s of DP \(10 control steps\), got 10 - 0.4 \[DPLossConfig\]$"):
        DPLossConfig(t_shutdown_s=10.0)
    with pytest.raises(ValueError, match=r"jitter t_shutdown_jitter_s, must leave at least 10 s of DP .*got 12 - 5 "):
        DPLossConfig(t_shutdown_s=12.0, t_shutdown_jitter_s=5.0)


def test_config_defaults():
    cfg = DPLossConfig()
    assert cfg.t_shutdown_s == 3000.0 and cfg.t_shutdown_jitter_s == pytest.approx(120.0)
    assert cfg.drift_s >= 600.0 and cfg.dt_s == 1.0
    assert cfg.noise == SensorNoise()
    assert DPLossConfig(noise={"gnss_white_m": 0.0}).noise.gnss_white_m == 0.0


def test_replace_keeps_a_default_jitter_at_4_percent_of_the_new_shutdown_time():
    """A jitter left at its default is 4 % of the shutdown time the copy has: 240 s at 6000 s,
    4 s at 100 s (not the original's 120 s, which left no DP before a 100-s shutdown)."""
    cfg = DPLossConfig()
    assert cfg.replace(t_shutdown_s=6000.0).t_shutdown_jitter_s == pytest.approx(240.0)
    assert cfg.replace(t_shutdown_s=100.0).t_shutdown_jitter_s == pytest.approx(4.0)
    assert cfg.replace(drift_s=600.0).t_shutdown_jitter_s == pytest.approx(120.0)
    given = DPLossConfig(t_shutdown_jitter_s=50.0)
    assert given.replace(t_shutdown_s=6000.0).t_shutdown_jitter_s == 50.0


# --------------------------------------------------------------------------- physics and timeline


def test_dp_holds_position_in_moderate_weather(moderate):
    cfg, df = moderate
    dp = df[df["dp_active"] == 1]
    lf = np.hypot(dp["truth_north_lf_m"], dp["truth_east_lf_m"])
    measured = np.hypot(dp["north_m"], dp["east_m"])
    assert lf.max() < 3.0, "LF position off the set-point by more than 3 m while on DP"
    assert measured.max() < 4.0
    settled = dp["time_s"] > 300.0
    assert lf[settled].max() < 2.0
    sp = df["truth_heading_sp_deg"].iloc[0]
    dpsi = (dp["truth_heading_lf_deg"] - sp + 180.0) % 360.0 - 180.0
    assert np.abs(dpsi).max() < 10.0
    assert np.abs(dpsi[settled]).max() < 5.0


def test_drift_speed_and_direction_follow_wind_and_current(moderate):
    cfg, df = moderate
    c = df.attrs["conditions"]
    drift = df[df["dp_active"] == 0]
    dn = drift["truth_north_lf_m"].iloc[-1] - drift["truth_north_lf_m"].iloc[0]
    de = drift["truth_east_lf_m"].iloc[-1] - drift["truth_east_lf_m"].iloc[0]
    speed = math.hypot(dn, de) / (drift["time_s"].iloc[-1] - drift["time_s"].iloc[0])
    assert 0.05 < speed < 1.0
    # Expected push: current plus a leeway of ~3 % of the wind speed, downwind.
    w_to = math.radians(c["wind_dir_from_deg"] + 180.0)
    c_to = math.radians(c["current_dir_to_deg"])
    push = (c["current_mps"] * np.array([math.cos(c_to), math.sin(c_to)])
            + 0.03 * c["wind_mean_mps"] * np.array([math.cos(w_to), math.sin(w_to)]))
    cos_angle = push @ [dn, de] / (np.linalg.norm(push) * math.hypot(dn, de))
    assert math.degrees(math.acos(np.clip(cos_angle, -1, 1))) < 90.0


def test_dp_active_switches_exactly_at_shutdown(moderate):
    cfg, df = moderate
    t_sd = df["truth_t_shutdown_s"].iloc[0]
    assert abs(t_sd - cfg.t_shutdown_s) <= cfg.t_shutdown_jitter_s + 0.5
    t = df["time_s"].to_numpy()
    np.testing.assert_array_equal(df["dp_active"].to_numpy(), (t < t_sd).astype(int))
    assert t[-1] == pytest.approx(t_sd + cfg.drift_s) and np.all(np.diff(t) == 1.0)
    after = df[t >= t_sd]
    # Azimuths frozen; rpm decays to (almost) nothing within a few time constants.
    for col in ("port_azimuth_deg", "stbd_azimuth_deg"):
        assert after[col].nunique() == 1
        assert after[col].iloc[0] == df.loc[t == t_sd - 1, col].iloc[0]
    rpm = after[["tunnel_rpm", "port_rpm", "stbd_rpm"]].abs().to_numpy()
    assert np.all(rpm[10:] < 0.01 * df[["tunnel_rpm", "port_rpm", "stbd_rpm"]].abs().max().max() + 0.01)
    # Left: the drag of the windmilling propellers in the drift flow, a few hundred newtons.
    frac = after[["truth_tunnel_thrust_frac", "truth_port_thrust_frac", "truth_stbd_thrust_frac"]].iloc[30:]
    assert np.abs(frac.to_numpy()).max() < 0.03


def test_measurements_are_truth_plus_configured_noise(moderate):
    cfg, df = moderate
    nz = cfg.noise

    def std(measured, truth, wrap=False):
        d = df[measured] - df[truth]
        if wrap:
            d = (d + 180.0) % 360.0 - 180.0
        return d.std()

    assert std("heading_deg", "truth_heading_deg", wrap=True) == pytest.approx(nz.heading_white_deg, rel=0.15)
    assert std("u_m_s", "truth_u_mps") == pytest.approx(nz.uv_white_m_s, rel=0.1)
    assert std("v_m_s", "truth_v_mps") == pytest.approx(nz.uv_white_m_s, rel=0.1)
    assert std("r_deg_s", "truth_r_degps") == pytest.approx(nz.r_white_deg_s, rel=0.1)
    gnss = math.hypot(nz.gnss_white_m, nz.gnss_markov_m)
    assert std("north_m", "truth_north_m") == pytest.approx(gnss, rel=0.5)  # GM error: few correlation times
    assert std("east_m", "truth_east_m") == pytest.approx(gnss, rel=0.5)
    assert std("wind_speed_m_s", "truth_wind_speed_mps") == pytest.approx(nz.wind_speed_white_m_s, rel=0.15)
    assert std("wind_dir_deg", "truth_wind_dir_from_deg", wrap=True) == pytest.approx(nz.wind_dir_white_deg, rel=0.15)
    # each axis has a noise of its own: u and v (white, ~900 samples: |corr| ~ 0.03) and
    # north and east (the slow Gauss-Markov part leaves a chance correlation, but not 1)
    for (a, truth_a), (b, truth_b), most in ((("u_m_s", "truth_u_mps"), ("v_m_s", "truth_v_mps"), 0.15),
                                             (("north_m", "truth_north_m"), ("east_m", "truth_east_m"), 0.8)):
        assert abs(np.corrcoef(df[a] - df[truth_a], df[b] - df[truth_b])[0, 1]) < most, (a, b)
    # Wave-frequency motion: total minus LF is present and zero-mean (mm to dm: short
    # waves hardly move a 34 m hull).
    for axis in ("north", "east"):
        wf = df[f"truth_{axis}_m"] - df[f"truth_{axis}_lf_m"]
        assert wf.std() > 1e-3 and abs(wf.mean()) < 0.2 * wf.std() + 1e-3


def test_truth_accelerations_match_velocities(moderate):
    _, df = moderate
    t = df["time_s"].to_numpy()
    for vel, acc in (("truth_u_lf_mps", "truth_udot_lf_mps2"), ("truth_v_lf_mps", "truth_vdot_lf_mps2")):
        fd = np.gradient(df[vel].to_numpy(), t)
        a = df[acc].to_numpy()
        assert np.corrcoef(fd, a)[0, 1] > 0.9
        assert np.median(np.abs(fd - a)) < 0.3 * np.std(a)


def test_weather_heading_points_the_bow_into_the_wind(moderate):
    """``heading_mode="weather"``: the heading set-point is the direction the wind comes FROM
    within +- heading_offset_max_deg (bow to weather, not stern)."""
    cfg, df = moderate
    c = df.attrs["conditions"]
    off = (c["heading_sp_deg"] - c["wind_dir_from_deg"] + 180.0) % 360.0 - 180.0
    assert abs(off) <= cfg.heading_offset_max_deg + 1e-9


def test_shaft_speed_decays_with_its_time_constant_after_the_shutdown(moderate):
    """With no command the rpm decays as ``exp(-t / rpm_time_constant_s)``: one log step later it
    is ``exp(-dt_s / tau)`` of what it was (the largest shaft, so the 0.01 rpm rounding is negligible)."""
    cfg, df = moderate
    t = df["time_s"].to_numpy()
    i = int(np.flatnonzero(t == df["truth_t_shutdown_s"].iloc[0])[0])
    rpm = df[["tunnel_rpm", "port_rpm", "stbd_rpm"]].to_numpy()
    j = int(np.argmax(np.abs(rpm[i])))
    assert abs(rpm[i, j]) > 10.0
    assert rpm[i + 1, j] / rpm[i, j] == pytest.approx(math.exp(-cfg.dt_s / cfg.rpm_time_constant_s), rel=0.01)


def test_truth_wave_frequency_velocity_and_acceleration_are_derivatives_of_the_motion(moderate):
    """The wave-frequency parts (total minus LF) of the truth columns are consistent: body velocity =
    time derivative of the NED offset turned into the body frame, acceleration = derivative of that
    velocity (finite differences at 1 Hz, so compared by correlation)."""
    _, df = moderate
    t = df["time_s"].to_numpy()
    psi = np.radians(df["truth_heading_lf_deg"].to_numpy())
    dn = np.gradient((df["truth_north_m"] - df["truth_north_lf_m"]).to_numpy(), t)
    de = np.gradient((df["truth_east_m"] - df["truth_east_lf_m"]).to_numpy(), t)
    body = {"u": np.cos(psi) * dn + np.sin(psi) * de, "v": -np.sin(psi) * dn + np.cos(psi) * de}
    for ax in ("u", "v"):
        vel = (df[f"truth_{ax}_mps"] - df[f"truth_{ax}_lf_mps"]).to_numpy()
        acc = (df[f"truth_{ax}dot_mps2"] - df[f"truth_{ax}dot_lf_mps2"]).to_numpy()
        assert np.corrcoef(body[ax], vel)[0, 1] > 0.8, ax
        assert np.corrcoef(np.gradient(vel, t), acc)[0, 1] > 0.8, ax


def test_truth_wind_load_is_the_true_models_wind_load_at_the_logged_state(moderate):
    """``truth_tau_wind_*`` is the wind part of the true vessel's loads at the logged LF state and
    the logged true wind (FROM direction), and not another part of the load."""
    _, df = moderate
    true_model = DynamicModel("gunnerus", true_vessel=True)
    for r in (10, len(df) // 2, len(df) - 5):
        row = df.iloc[r]
        eta = [row["truth_north_lf_m"], row["truth_east_lf_m"], math.radians(row["truth_heading_lf_deg"])]
        nu = [row["truth_u_lf_mps"], row["truth_v_lf_mps"], math.radians(row["truth_r_lf_degps"])]
        wind = (row["truth_wind_speed_mps"], math.radians(row["truth_wind_dir_from_deg"]))
        current = (row["truth_current_speed_mps"], math.radians(row["truth_current_dir_to_deg"]))
        _, parts, _ = true_model.acceleration(np.array(eta), np.array(nu), wind=wind, current=current,
                                              return_parts=True)
        logged = row[["truth_tau_wind_x_N", "truth_tau_wind_y_N", "truth_tau_wind_n_Nm"]].to_numpy(float)
        np.testing.assert_allclose(logged, parts[0, 2], rtol=1e-3, atol=5.0)


def test_thrust_fractions_and_azimuths_reproduce_the_thrust_load(moderate):
    """``truth_<thruster>_thrust_frac`` is the delivered thrust over that thruster's own bollard
    thrust ahead: summed along the logged azimuths (the tunnel along its 90 deg axis) they give
    ``truth_tau_thrust_*``."""
    _, df = moderate
    ves = DynamicModel("gunnerus", true_vessel=True).vessel
    limits = bollard_thrust_limits(ves).forward_N
    thrust = np.column_stack([df[f"truth_{t.name}_thrust_frac"] * f for t, f in zip(ves.thrusters, limits)])
    angle = np.column_stack([np.radians(df[f"{t.name}_azimuth_deg"]) if t.type == "azimuth"
                             else np.full(len(df), t.fixed_angle_rad) for t in ves.thrusters])
    x, y = np.array([t.x_m for t in ves.thrusters]), np.array([t.y_m for t in ves.thrusters])
    load = np.column_stack([(thrust * np.cos(angle)).sum(axis=1), (thrust * np.sin(angle)).sum(axis=1),
                            (thrust * (x * np.sin(angle) - y * np.cos(angle))).sum(axis=1)])
    logged = df[["truth_tau_thrust_x_N", "truth_tau_thrust_y_N", "truth_tau_thrust_n_Nm"]].to_numpy()
    np.testing.assert_allclose(load, logged, atol=20.0)


def test_wind_feedforward_cancels_a_steady_wind_from_the_start():
    """Calm sea, no current, steady wind, no noise: from the first seconds (before the integral
    builds up) the thrusters cancel the wind load, and the ship hardly moves."""
    sea = SeaState(hs_m=0.0, tp_s=5.0, wave_dir_from_rad=0.0, wind_speed_m_s=12.0, wind_dir_from_rad=math.radians(60),
                   gust_intensity=0.0, current_speed_m_s=0.0)
    df = simulate_dp_loss(DPLossConfig(seed=1, sea_state=sea, heading_sp_deg=30.0, t_shutdown_jitter_s=0.0,
                                       noise=SensorNoise.none(), **TINY))
    early = df[(df["time_s"] >= 10.0) & (df["time_s"] <= 40.0)]
    wind = early[["truth_tau_wind_x_N", "truth_tau_wind_y_N", "truth_tau_wind_n_Nm"]].to_numpy().mean(axis=0)
    thrust = early[["truth_tau_thrust_x_N", "truth_tau_thrust_y_N", "truth_tau_thrust_n_Nm"]].to_numpy().mean(axis=0)
    assert np.all(np.abs(thrust + wind) <= 0.2 * np.abs(wind)), (thrust, wind)
    dp = df[df["dp_active"] == 1]
    assert np.hypot(dp["truth_north_lf_m"], dp["truth_east_lf_m"]).max() < 0.5


def test_same_seed_same_log_different_seed_different_log():
    a = simulate_dp_loss(DPLossConfig(seed=21, **TINY))
    b = simulate_dp_loss(DPLossConfig(seed=21, **TINY))
    c = simulate_dp_loss(DPLossConfig(seed=22, **TINY))
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    assert a.attrs["conditions"] == b.attrs["conditions"]
    n = min(len(a), len(c))  # the shutdown jitter may change the length
    assert not a.iloc[:n].equals(c.iloc[:n])
    assert not np.allclose(a["north_m"].iloc[:n], c["north_m"].iloc[:n])


def test_given_sea_state_and_heading_are_used():
    """The given sea state drives the simulation, not only the log's truth_hs_m / truth_tp_s
    labels: the second-order wave load the physics took (truth_tau_wave2_*) is there, pushes
    her aft in waves 10 deg off the bow, and scales with Hs^2 (at the first row, where both
    runs are at the same state with the same seed's sea, exactly 4 times for twice the Hs)."""
    waves = ["truth_tau_wave2_x_N", "truth_tau_wave2_y_N", "truth_tau_wave2_n_Nm"]
    runs = {}
    for hs in (0.8, 1.6):
        sea = SeaState(hs_m=hs, tp_s=6.0, wave_dir_from_rad=math.radians(90), wind_speed_m_s=8.0,
                       wind_dir_from_rad=math.radians(80), current_speed_m_s=0.2,
                       current_dir_to_rad=math.radians(200))
        runs[hs] = simulate_dp_loss(DPLossConfig(seed=1, sea_state=sea, heading_sp_deg=100.0,
                                                 t_shutdown_jitter_s=0.0, **TINY))
    df = runs[0.8]
    assert df["truth_hs_m"].iloc[0] == pytest.approx(0.8)
    assert df["truth_tp_s"].iloc[0] == pytest.approx(6.0)
    assert df["truth_heading_sp_deg"].iloc[0] == pytest.approx(100.0)
    assert df["truth_t_shutdown_s"].iloc[0] == 120.0
    assert df["truth_wind_speed_mps"].mean() == pytest.approx(8.0, rel=0.15)
    first = df[waves].iloc[0].to_numpy()
    assert np.all(np.abs(first) > 50.0), first          # hundreds of N (N m): well above the log's rounding
    assert df["truth_tau_wave2_x_N"].mean() < 0.0        # near head seas: the mean drift is astern
    np.testing.assert_allclose(runs[1.6][waves].iloc[0].to_numpy(), 4.0 * first, rtol=1e-3)


# --------------------------------------------------------------------------- log format


@pytest.mark.parametrize("ext", ["csv.gz", "parquet"])
def test_log_validates_and_round_trips(moderate, tmp_path, ext):
    _, df = moderate
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no unknown-column warnings either
        validate_log(df, **THRUSTERS)
        path = tmp_path / f"log.{ext}"
        write_log(df, path, **THRUSTERS)
        back = read_log(path, **THRUSTERS)
    assert list(back.columns) == list(df.columns)
    pd.testing.assert_frame_equal(back, df, check_exact=False, rtol=1e-12, atol=1e-12)
    assert set(df.columns) >= {"time_s", "north_m", "east_m", "heading_deg", "u_m_s", "v_m_s", "r_deg_s",
                               "wind_speed_m_s", "wind_dir_deg", "tunnel_rpm", "port_rpm", "port_azimuth_deg",
                               "stbd_rpm", "stbd_azimuth_deg", "dp_active"}
    assert "tunnel_azimuth_deg" not in df.columns


def test_drift_statistics_of_a_ship_drifting_east_at_a_known_speed():
    """A made-up log, still on DP (3 m off only during the start-up, half the DP phase), then
    drifting due east at 0.1 m/s from t = 100 s: the excursions are 6 m and 60 m, the net speed
    0.1 m/s, the drift goes TO 90 deg, and the settled DP statistics are zero."""
    t = np.arange(0.0, 801.0)
    east = np.where(t < 100.0, 0.0, 0.1 * (t - 100.0))
    north = np.where(t < 40.0, 3.0, 0.0)
    log = pd.DataFrame({"time_s": t, "north_m": north, "east_m": east, "heading_deg": 30.0,
                        "dp_active": (t < 100.0).astype(int)})
    st = drift_statistics(log)
    assert st["t_shutdown_s"] == 100.0
    assert st["drift_excursion_60s_m"] == pytest.approx(6.0)
    assert st["drift_excursion_600s_m"] == pytest.approx(60.0)
    assert st["drift_net_speed_mps"] == pytest.approx(0.1)
    assert st["drift_dir_to_deg"] == pytest.approx(90.0)
    assert st["drift_dheading_600s_deg"] == pytest.approx(0.0)
    assert st["dp_pos_max_m"] == 0.0 and st["dp_pos_std_m"] == 0.0


def test_drift_statistics_of_a_turning_ship_with_a_bent_track():
    """A made-up log in which every statistic differs from its neighbours' formulas: on DP
    (after the start-up, t = 100..199 s) east swings as cos(2 pi t / 20 s), north 0, and
    the heading alternates 359 / 1 deg, so the position spread is sqrt(0.5) m, the largest
    offset 1 m and the heading spread 1 deg across north. From the shutdown at 200 s she
    turns 0.05 deg/s through north and drifts 300 s east at 0.1 m/s, then 300 s north at
    0.05 m/s: 30 m east and 15 m north, a net 33.5 m towards atan2(30, 15) = 63.4 deg, a
    path of 45 m (mean speed over ground 0.075 m/s, net 0.056 m/s)."""
    t = np.arange(0.0, 801.0)
    dp = t < 200.0
    s = t - 200.0
    east = np.where(dp, np.cos(2 * np.pi * t / 20.0), 1.0 + 0.1 * np.clip(s, 0.0, 300.0))
    north = np.where(dp, 0.0, 0.05 * np.clip(s - 300.0, 0.0, 300.0))
    heading = np.where(dp, np.where(t % 2 == 0, 359.0, 1.0), (359.0 + 0.05 * s) % 360.0)
    log = pd.DataFrame({"time_s": t, "north_m": north, "east_m": east, "heading_deg": heading,
                        "dp_active": dp.astype(int)})
    st = drift_statistics(log)
    assert st["t_shutdown_s"] == 200.0
    assert st["drift_excursion_60s_m"] == pytest.approx(6.0)
    assert st["drift_excursion_600s_m"] == pytest.approx(math.hypot(30.0, 15.0))
    assert st["drift_net_speed_mps"] == pytest.approx(math.hypot(30.0, 15.0) / 600.0)
    assert st["drift_dir_to_deg"] == pytest.approx(math.degrees(math.atan2(30.0, 15.0)))
    assert st["drift_mean_sog_mps"] == pytest.approx(45.0 / 600.0, abs=2e-4)   # the corner's one sample aside
    assert st["drift_dheading_60s_deg"] == pytest.approx(3.0)                   # through north: not -357
    assert st["drift_dheading_600s_deg"] == pytest.approx(30.0)
    assert st["dp_pos_std_m"] == pytest.approx(math.sqrt(0.5))
    assert st["dp_pos_max_m"] == pytest.approx(1.0)
    assert st["dp_heading_std_deg"] == pytest.approx(1.0)


def test_drift_statistics_refuses_what_it_cannot_summarise():
    """A log without its time or track, or a settling time that is not a number of seconds, is
    refused naming it (not a KeyError, nor NaN statistics from a NaN settling time)."""
    t = np.arange(0.0, 200.0)
    log = pd.DataFrame({"time_s": t, "north_m": 0.0, "east_m": 0.0, "heading_deg": 10.0,
                        "dp_active": (t < 100.0).astype(int)})
    assert drift_statistics(log, dp_settle_s=20)["dp_pos_std_m"] == 0.0
    with pytest.raises(ValueError, match="missing column.*time_s"):
        drift_statistics(log.drop(columns="time_s"))
    with pytest.raises(ValueError, match="missing column.*heading_deg"):
        drift_statistics(log.drop(columns="heading_deg"))
    for bad in (float("nan"), -1.0, "600"):
        with pytest.raises((TypeError, ValueError), match="^dp_settle_s: "):
            drift_statistics(log, dp_settle_s=bad)
    with pytest.raises(TypeError, match="log: expected a pandas DataFrame"):
        drift_statistics(log.to_dict())


def test_drift_statistics_of_a_log_that_starts_after_the_shutdown_are_nan():
    """The drift is measured from the sample at the shutdown. A log cut after it (its
    truth_t_shutdown_s before the first row) took its first row for that sample: the excursions
    and the drift speed were measured from the wrong place (3 m after 60 s where the ship had
    drifted 6 m); every drift statistic is now NaN, as for a log that ends before the shutdown."""
    t = np.arange(0.0, 800.0)
    east = np.where(t < 100.0, 0.0, 0.1 * (t - 100.0))
    log = pd.DataFrame({"time_s": t, "north_m": 0.0, "east_m": east, "heading_deg": 10.0,
                        "truth_t_shutdown_s": 100.0})
    assert drift_statistics(log)["drift_excursion_600s_m"] == pytest.approx(60.0)
    st = drift_statistics(log[t >= 130.0])
    assert st["t_shutdown_s"] == 100.0
    for key in ("drift_excursion_60s_m", "drift_excursion_600s_m", "drift_dheading_600s_deg",
                "drift_mean_sog_mps", "drift_net_speed_mps", "drift_dir_to_deg"):
        assert np.isnan(st[key]), (key, st[key])


def test_drift_statistics_refuses_times_out_of_order_and_an_unknown_shutdown_time():
    """The statistics search the times: a shuffled log gave a wrong shutdown time and NaN
    statistics without a word, as did a truth_t_shutdown_s left empty; both are refused by name."""
    t = np.arange(0.0, 800.0)
    log = pd.DataFrame({"time_s": t, "north_m": 0.0, "east_m": 0.01 * t, "heading_deg": 10.0,
                        "dp_active": (t < 100.0).astype(int)})
    assert drift_statistics(log)["t_shutdown_s"] == 100.0
    with pytest.raises(ValueError, match="time_s must be strictly increasing"):
        drift_statistics(log.sample(frac=1.0, random_state=0))
    with pytest.raises(ValueError, match="time_s must be strictly increasing"):
        drift_statistics(pd.concat([log, log.iloc[-1:]], ignore_index=True))     # a repeated row
    with pytest.raises(ValueError, match="time_s must be finite"):
        drift_statistics(log.assign(time_s=np.where(t == 5.0, np.nan, t)))
    with pytest.raises(ValueError, match="truth_t_shutdown_s is nan"):
        drift_statistics(log.assign(truth_t_shutdown_s=np.nan))


def test_drift_statistics_reproduce_truthsim_summary(shared_data):
    truthsim = shared_data("truthsim-dev")
    for _, summary in pd.read_csv(shared_data("truthsim-dev", "scenarios.csv")).iterrows():
        st = drift_statistics(read_log(truthsim / "logs" / summary["file"]))
        assert st["t_shutdown_s"] == summary["t_shutdown_s"]
        for key in ("drift_excursion_60s_m", "drift_excursion_600s_m", "dp_pos_std_m"):
            assert st[key] == pytest.approx(summary[key], rel=0.05), (summary["file"], key)
        # truthsim's "drift_mean_sog_mps" is the net drift speed (600-s excursion over 600 s),
        # ours the mean of the speed over ground, higher where the drift wanders
        assert st["drift_net_speed_mps"] == pytest.approx(summary["drift_mean_sog_mps"], abs=1e-3), summary["file"]
        assert st["drift_mean_sog_mps"] >= st["drift_net_speed_mps"]


# --------------------------------------------------------------------------- sweep and embedded set


def test_sweep_writes_logs_and_summary(tmp_path):
    paths = sweep(tmp_path / "out", [3, 5], beaufort=(2, 3), fmt="csv", **TINY)
    assert [p.name for p in paths] == ["sim_dp_loss_seed0003.csv", "sim_dp_loss_seed0005.csv"]
    summary = pd.read_csv(tmp_path / "out" / "scenarios.csv")
    assert summary["seed"].tolist() == [3, 5]
    assert summary["file"].tolist() == [p.name for p in paths]
    for col in ("hs_m", "wind_mean_mps", "t_shutdown_s", "drift_excursion_60s_m", "drift_mean_sog_mps",
                "dp_pos_std_m"):
        assert summary[col].notna().all(), col
    assert summary["drift_excursion_600s_m"].isna().all()  # a 60 s drift has no 600 s statistic
    for p in paths:
        read_log(p, **THRUSTERS)
    assert not list((tmp_path / "out").glob(".*tmp"))
    # a second sweep into the folder adds its rows (and replaces a rewritten log's row)
    first = summary.set_index("seed")
    sweep(tmp_path / "out", [4, 5], beaufort=(2, 3), fmt="csv", **TINY)
    both = pd.read_csv(tmp_path / "out" / "scenarios.csv")
    assert both["seed"].tolist() == [3, 4, 5]
    assert both.set_index("seed").loc[3].equals(first.loc[3])
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "scenarios.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="not a sweep summary"):
        sweep(tmp_path / "bad", [1], **TINY)
    assert not list((tmp_path / "bad").glob("sim_*"))  # refused before any simulation
    (tmp_path / "bad" / "scenarios.csv").write_text("")
    with pytest.raises(ValueError, match=r"cannot be read \(it is empty\)"):
        sweep(tmp_path / "bad", [1], **TINY)
    with pytest.raises(ValueError, match="seeds"):
        sweep(tmp_path, [1, 1], **TINY)
    with pytest.raises(ValueError, match="fmt"):
        sweep(tmp_path, [1], fmt="xlsx", **TINY)


def test_sweep_refuses_an_out_dir_that_is_not_a_path_by_name(tmp_path, monkeypatch):
    """out_dir=None failed in pathlib's words ('expected str, bytes or os.PathLike object, not
    NoneType'), and an empty one swept into the working folder."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TypeError, match=r"^out_dir: expected a file path \(str or os.PathLike\), got NoneType"):
        sweep(None, [1], **TINY)
    with pytest.raises(ValueError, match="^out_dir: expected a file path, got an empty one"):
        sweep("", [1], **TINY)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("seeds", [5, "12", None])
def test_sweep_refuses_seeds_that_are_not_a_list_of_seeds_by_name(tmp_path, seeds):
    """One seed given as an int failed with "'int' object is not iterable" (None likewise), and a text
    was refused for its first character ("got '1'"); a TypeError now names seeds, before any work."""
    with pytest.raises(TypeError, match="^seeds: expected an iterable of non-negative ints"):
        sweep(tmp_path / "out", seeds, **TINY)
    assert not (tmp_path / "out").exists()


def test_log_file_name_refuses_a_seed_that_is_not_a_whole_number_at_least_0():
    """A seed of 1.5 was truncated to seed 1's file name, -1 gave "seed-001", "7" was read as 7."""
    assert log_file_name(1) == log_file_name(np.int64(1)) == "sim_dp_loss_seed0001.csv.gz"
    for bad in (1.5, -1, "7", True):
        with pytest.raises(ValueError, match="^seed: expected a whole number >= 0"):
            log_file_name(bad)


def test_sweep_refuses_a_seed_already_there_in_another_format(tmp_path):
    out = tmp_path / "out"
    sweep(out, [1], beaufort=(2, 3), fmt="csv.gz", **TINY)
    before = (out / "scenarios.csv").read_bytes()
    with pytest.raises(ValueError, match=r"seed 1 has a log there in another format already "
                                         r"\(.*sim_dp_loss_seed0001\.csv\.gz\)"):
        sweep(out, [1, 2], beaufort=(2, 3), fmt="parquet", **TINY)
    # refused before any simulation: nothing new, the summary untouched
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [
        "scenarios.csv", "sim_dp_loss_seed0001.csv.gz"]
    assert (out / "scenarios.csv").read_bytes() == before
    # the same format is rewritten in place, with one summary row per seed
    sweep(out, [1], beaufort=(2, 3), fmt="csv.gz", **TINY)
    assert pd.read_csv(out / "scenarios.csv")["seed"].tolist() == [1]
    # an old row of a seed whose file is gone is replaced, not kept beside the new one
    (out / "sim_dp_loss_seed0001.csv.gz").unlink()
    sweep(out, [1], beaufort=(2, 3), fmt="parquet", **TINY)
    summary = pd.read_csv(out / "scenarios.csv")
    assert summary["seed"].tolist() == [1] and summary["file"].tolist() == ["sim_dp_loss_seed0001.parquet"]


def test_sweep_never_replaces_a_users_file_and_its_own_stay_replaceable(tmp_path, capsys):
    """A file of the user's under a log's name is refused before any simulation and left as it
    was; the sweep's own logs are recorded as they are written, so a single ``simulate`` may
    replace them, and a sweep folder from before the record is recognised by its summary."""
    out = tmp_path / "out"
    out.mkdir()
    mine = out / "sim_dp_loss_seed0002.csv"
    mine.write_text("my own log\n")
    with pytest.raises(FileExistsError, match="sim_dp_loss_seed0002.csv: exists and was not written by hybridship"):
        sweep(out, [1, 2], beaufort=(2, 3), fmt="csv", **TINY)
    assert mine.read_text() == "my own log\n" and not (out / "sim_dp_loss_seed0001.csv").exists()
    mine.unlink()
    sweep(out, [1], beaufort=(2, 3), fmt="csv", **TINY)
    assert main(["simulate", "--seed", "1", "--out", str(out / "sim_dp_loss_seed0001.csv"), "--t-shutdown-s", "120",
                 "--drift-s", "60", "--no-progress"]) == 0
    (out / ".hybridship-outputs.json").unlink()            # a folder swept before the record
    sweep(out, [1], beaufort=(2, 3), fmt="csv", **TINY)
    capsys.readouterr()
    mine.write_text("my own log\n")
    assert main(["simulate", "--sweep", "--seeds", "2", "--out-dir", str(out), "--format", "csv",
                 "--t-shutdown-s", "120", "--drift-s", "60", "--no-progress"]) == 2
    assert "--out-dir: " in capsys.readouterr().err and mine.read_text() == "my own log\n"


def test_cli_sweep_in_another_format_names_the_existing_log(tmp_path, capsys):
    args = ["simulate", "--sweep", "--seeds", "1", "--out-dir", str(tmp_path), "--t-shutdown-s", "120",
            "--drift-s", "60", "--no-progress"]
    assert main(args) == 0
    capsys.readouterr()
    assert main(args + ["--format", "parquet"]) != 0
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "sim_dp_loss_seed0001.csv.gz" in err
    assert not list(tmp_path.glob("*.parquet"))


def _vessel_file(tmp_path, packaged: str, name: str, rudder: bool = False):
    """A packaged vessel file renamed, optionally with the Esso model's rudder block added
    (without its propeller, which Gunnerus does not have: a rudder in the plain wake)."""
    from hybridship.vessel import packaged_vessel_text

    text = packaged_vessel_text(packaged)
    text = text.replace(f'name = "{packaged}"', f'name = "{name}"', 1)
    if rudder:
        esso = packaged_vessel_text("esso_osaka_model")
        block = esso[esso.index("[[rudders]]"):esso.index("# Bow and stern tunnel")]
        block = "\n".join(line for line in block.splitlines() if not line.startswith("propeller ="))
        text = text.replace("\n[wind]\n", f"\n{block}\n\n[wind]\n", 1)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def test_a_vessel_that_cannot_hold_station_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    import hybridship.sim.scenario as scenario

    tanker = _vessel_file(tmp_path, "esso_osaka_model", "my_tanker")

    def no_dp(*args, **kwargs):
        raise AssertionError("the DP system was started")

    monkeypatch.setattr(scenario, "_DPSystem", no_dp)
    with pytest.raises(ValueError, match="'my_tanker' cannot hold station in surge, sway and yaw"):
        simulate_dp_loss(DPLossConfig(seed=1, **TINY), vessel=tanker)
    with pytest.raises(ValueError, match="'my_tanker' cannot hold station"):
        sweep(tmp_path / "sw", [1], vessel=tanker, **TINY)
    assert not (tmp_path / "sw").exists()
    out = tmp_path / "t1.csv"
    rc = main(["simulate", "--vessel", str(tanker), "--seed", "1", "--t-shutdown-s", "200", "--drift-s", "60",
               "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and len(err.strip().splitlines()) == 1
    assert "hybridship simulate: error: --vessel: vessel 'my_tanker' cannot hold station" in err and "rank 1 < 3" in err
    assert not out.exists()


def test_a_dp_vessel_with_a_rudder_logs_the_rudder_amidships_and_trains(tmp_path):
    from hybridship.predictors import HybridPredictor, as_log_arrays
    from hybridship.residual.ensemble import EnsembleConfig
    from hybridship.vessel import load_vessel

    vessel = load_vessel(_vessel_file(tmp_path, "gunnerus", "gunnerus_rudder", rudder=True))
    assert [r.name for r in vessel.rudders] == ["rudder"]
    df = simulate_dp_loss(DPLossConfig(seed=1, **TINY), vessel=vessel)
    assert (df["rudder_azimuth_deg"] == 0.0).all()   # the angle the physics held: amidships
    assert "rudder_rpm" not in df
    path = tmp_path / "g1.csv"
    write_log(df, path, channel_names=vessel.channel_names, rotatable=vessel.rotatable)
    arrays = as_log_arrays(path, vessel)             # what 'train' reads; refused before
    assert np.all(arrays.azimuth_rad[:, vessel.channel_names.index("rudder")] == 0.0)
    paths = sweep(tmp_path / "sw", [2], vessel=vessel, fmt="csv", **TINY)
    cfg = EnsembleConfig(n_members=2, hidden=8, max_epochs=15)
    hp = HybridPredictor(vessel, ensemble_config=cfg).fit([path, *paths])
    assert hp.training_info["n_rows"] > 0


def test_embedded_scenarios_are_valid_and_copied():
    a = embedded_scenarios(n=3, seed=0)
    assert len(a) == 3 and len({s.name for s in a}) == 3
    for s in a:
        validate_log(s.log, **THRUSTERS)
        assert s.log["dp_active"].iloc[0] == 1 and s.log["dp_active"].iloc[-1] == 0
    a[0].log.loc[0, "north_m"] = 1e3
    b = embedded_scenarios(n=3, seed=0)
    assert b[0].log.loc[0, "north_m"] != 1e3
    with pytest.raises(ValueError, match=r"^n: expected an int in 1\.\.20"):
        embedded_scenarios(n=0)


# --------------------------------------------------------------------------- CLI


def test_parse_seeds():
    assert parse_seeds("1-3,7") == [1, 2, 3, 7]
    for bad in ("3-1", "a", "1,,2", "1,1", "0-100000000000", "4294967296", "0-99999,100000-100001"):
        with pytest.raises(ValueError, match="--seeds"):
            parse_seeds(bad)


def test_cli_simulate_refuses_phases_longer_than_a_day_before_simulating(tmp_path, capsys, monkeypatch):
    from hybridship.sim import scenario

    def no_simulation(*args, **kwargs):
        raise AssertionError("simulated before the options were checked")

    monkeypatch.setattr(scenario, "simulate_dp_loss", no_simulation)
    monkeypatch.setattr(scenario, "sweep", no_simulation)
    for opt in ("--drift-s", "--t-shutdown-s"):
        assert main(["simulate", "--seed", "1", "--out", str(tmp_path / "s.csv"), opt, "1e12", "--no-progress"]) == 2
        assert f"{opt}: must be <= 86400" in capsys.readouterr().err
    assert not (tmp_path / "s.csv").exists()
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    for out_dir in (a_file, a_file / "sub"):
        assert main(["simulate", "--sweep", "--seeds", "0-1", "--out-dir", str(out_dir), "--no-progress"]) == 2
        assert f"--out-dir {out_dir}:" in capsys.readouterr().err


def test_cli_simulate_refuses_an_out_that_is_a_folder_before_simulating(tmp_path, capsys, monkeypatch):
    """A folder at --out was found only when the log was written, after the simulation
    (half a minute), and reported as a run failure (exit 1)."""
    from hybridship.sim import scenario

    def no_simulation(*args, **kwargs):
        raise AssertionError("simulated before the options were checked")

    monkeypatch.setattr(scenario, "simulate_dp_loss", no_simulation)
    folder = tmp_path / "sim.csv"
    folder.mkdir()
    assert main(["simulate", "--seed", "1", "--out", str(folder), "--no-progress"]) == 2
    assert (f"hybridship simulate: error: --out {folder}: is a folder; expected the log file to write"
            in capsys.readouterr().err)
    assert list(folder.iterdir()) == []


def test_cli_simulate_refuses_format_for_a_single_scenario(tmp_path, capsys, monkeypatch):
    """--format is a sweep's; with --seed and --out it was ignored and the log written in the
    format of --out's extension (a .csv for --format parquet), without a word."""
    from hybridship.sim import scenario

    def no_simulation(*args, **kwargs):
        raise AssertionError("simulated before the options were checked")

    monkeypatch.setattr(scenario, "simulate_dp_loss", no_simulation)
    out = tmp_path / "sim.csv"
    assert main(["simulate", "--seed", "1", "--out", str(out), "--format", "parquet", "--no-progress"]) == 2
    assert ("hybridship simulate: error: --format is for a sweep; a single scenario's format is the extension "
            "of --out") in capsys.readouterr().err
    assert not out.exists()


def test_cli_simulate_writes_a_readable_log(tmp_path, capsys):
    out = tmp_path / "new" / "sim.csv.gz"     # a missing folder is made, as for every --out
    rc = main(["simulate", "--vessel", "gunnerus", "--scenario", "dp-loss", "--seed", "5", "--out", str(out),
               "--t-shutdown-s", "120", "--drift-s", "60", "--no-progress"])
    assert rc == 0
    df = read_log(out, **THRUSTERS)
    assert df["dp_active"].iloc[-1] == 0 and len(df) == df["time_s"].iloc[-1] + 1
    assert "wrote" in capsys.readouterr().out
    # a file where a folder of --out would be is refused before the simulation
    assert main(["simulate", "--seed", "5", "--out", str(out / "x.csv"), "--no-progress"]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err


def test_cli_simulate_replaces_its_own_log_but_never_a_users_file(tmp_path, capsys):
    """--out replaces a log an earlier simulate wrote there (the folder's record of outputs),
    and refuses, before simulating, a file no hybridship command wrote."""
    argv = ["simulate", "--seed", "5", "--t-shutdown-s", "120", "--drift-s", "30", "--no-progress", "--out"]
    own = tmp_path / "sim.csv"
    assert main(argv + [str(own)]) == 0 and main(argv + [str(own)]) == 0
    mine = tmp_path / "mylog.csv"
    mine.write_text("time_s,north_m\n0,1\n")
    assert main(argv + [str(mine)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "was not written by hybridship" in err
    assert mine.read_text() == "time_s,north_m\n0,1\n"


def test_cli_sweep(tmp_path):
    rc = main(["simulate", "--sweep", "--seeds", "1-2", "--out-dir", str(tmp_path), "--t-shutdown-s", "120",
               "--drift-s", "60", "--format", "parquet", "--no-progress"])
    assert rc == 0
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == [
        "scenarios.csv", "sim_dp_loss_seed0001.parquet", "sim_dp_loss_seed0002.parquet"]


@pytest.mark.parametrize("argv, needle", [
    (["simulate", "--vessel", "no_such_ship", "--seed", "1", "--out", "{tmp}/x.csv"], "no_such_ship"),
    (["simulate", "--seed", "1", "--out", "{tmp}/x.txt"], ".txt"),
    (["simulate", "--seed", "1"], "--out"),
    (["simulate", "--seed", "1", "--out", "{tmp}/x.csv", "--drift-s", "-5"], "--drift-s: must be > 0"),
    (["simulate", "--sweep", "--seeds", "5-2", "--out-dir", "{tmp}"], "--seeds"),
    (["simulate", "--scenario", "capsize", "--seed", "1", "--out", "{tmp}/x.csv"], "capsize"),
    ([], "command"),
])
def test_cli_bad_input_gives_one_line_and_nonzero(tmp_path, capsys, argv, needle):
    rc = main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    err = capsys.readouterr().err
    assert rc != 0
    assert needle in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


def test_cli_prints_each_problem_of_a_vessel_file_on_a_line_of_its_own(tmp_path, capsys):
    from hybridship.vessel import packaged_vessel_text

    text = packaged_vessel_text("gunnerus")
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("mass_kg = 574130.0", "mass_kg = -5", 1)
                   .replace("rho_air_kg_m3 = 1.225", 'rho_air_kg_m3 = "x"', 1))
    assert bad.read_text() != text
    rc = main(["simulate", "--vessel", str(bad), "--seed", "1", "--out", str(tmp_path / "x.csv")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(lines) == 2
    assert all(line.startswith("hybridship simulate: error: ") and "bad.toml: " in line for line in lines)
    assert "rigid_body.mass_kg" in lines[0] and "wind.rho_air_kg_m3" in lines[1]
    assert not (tmp_path / "x.csv").exists()


def test_drift_off_settings_problems_name_their_options_line_by_line(tmp_path, capsys):
    rc = main(["drift-off", "planning", "--radii-m", "-5", "--samples", "0", "--out", str(tmp_path / "o")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(lines) == 2
    assert lines[0].startswith("hybridship drift-off planning: error: --radii-m: ")
    assert lines[1].startswith("hybridship drift-off planning: error: --samples: ")
    assert not (tmp_path / "o").exists()


def test_compare_truthsim_table_pairs_ours_with_theirs_and_wraps_the_drift_direction():
    """The simulator page's comparison table (benchmarks/compare_truthsim.py): ours / theirs
    per cell, the median ratio over the scenarios, and direction differences within +-180 deg."""
    from conftest import load_benchmark

    keys = ("drift_excursion_60s_m", "drift_excursion_600s_m", "drift_mean_sog_mps", "drift_dheading_600s_deg",
            "dp_pos_std_m", "drift_dir_to_deg")
    rows = []
    for k, (ours, theirs, d_ours, d_theirs) in enumerate([(2.0, 1.0, 350.0, 10.0), (3.0, 1.0, 10.0, 350.0),
                                                           (1.0, 1.0, 90.0, 80.0)]):
        rows.append(dict(scenario=f"s{k}", wind=5.0, hs=1.0, tp=6.0, cur=0.2,
                         **{f"{key}|ours": ours for key in keys}, **{f"{key}|truthsim": theirs for key in keys}))
        rows[-1].update({"drift_dir_to_deg|ours": d_ours, "drift_dir_to_deg|truthsim": d_theirs})
    text = load_benchmark("compare_truthsim").comparison_markdown(pd.DataFrame(rows))
    assert "| s0 | 5.0 | 1.00 | 6.0 | 0.20 | 2.0 / 1.0 | 2 / 1 | 2.00 / 1.00 | 2 / 1 | 2.00 / 1.00 |" in text
    assert "| **ratio ours/truthsim (median)** | | | | | 2.00 | 2.00 | 2.00 | | 2.00 |" in text
    assert text.endswith("ours minus truthsim [deg]: -20, +20, +10")


@pytest.mark.parametrize("call", [lambda: simulate_dp_loss(DPLossConfig(**TINY), progress="no"),
                                  lambda: sweep("never-made", [1], progress="false", **TINY)],
                         ids=["simulate", "sweep"])
def test_a_progress_flag_that_is_not_a_bool_is_refused(call, tmp_path, monkeypatch):
    """progress="no" is a truthy text: it switched the progress bar on; refused naming it,
    before any work, as the package's other flags are."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TypeError, match="progress: expected True or False"):
        call()
    assert not (tmp_path / "never-made").exists()
