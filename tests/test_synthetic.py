"""Synthetic logs made by the dynamic model itself (hybridship.sim.synthetic) against the log format."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridship.frames import body_to_ned
from hybridship.sim.synthetic import physics_log


@pytest.fixture(scope="module")
def log(model):
    """Five minutes of random commands, power lost at 200 s, in a steady wind from 210 deg."""
    return physics_log(model, duration_s=300.0, t_shutdown_s=200.0, seed=3, wind=(7.0, math.radians(210.0)))


def test_angles_and_rates_are_in_degrees(log):
    """``heading_deg`` in degrees clockwise from north, ``r_deg_s`` its rate in deg/s, and the wind
    direction FROM in degrees, as the log format names them."""
    t = log["time_s"].to_numpy()
    heading = np.unwrap(np.radians(log["heading_deg"].to_numpy()))
    rate = np.gradient(np.degrees(heading), t)
    r = log["r_deg_s"].to_numpy()
    assert np.abs(r).max() > 0.1                       # the ship turns: the check below means something
    assert np.median(np.abs(rate - r)) < 0.1 * np.abs(r).std()
    np.testing.assert_allclose(log["wind_dir_deg"], 210.0)


def test_velocities_are_in_the_body_frame_and_the_truth_accelerations_are_their_rates(log):
    """``u_m_s``/``v_m_s`` turned into NED with the heading are the positions' rates, and the
    ``truth_*_dot`` columns are the rates of ``u``, ``v`` and ``r`` in the units their names
    give (``rad/s2`` for the yaw, where ``r_deg_s`` is in deg/s)."""
    t = log["time_s"].to_numpy()
    psi = np.radians(log["heading_deg"].to_numpy())
    u, v = log["u_m_s"].to_numpy(), log["v_m_s"].to_numpy()
    r = np.radians(log["r_deg_s"].to_numpy())
    eta_dot = body_to_ned(np.column_stack([u, v, r]), psi)
    pairs = [(np.gradient(log["north_m"].to_numpy(), t), eta_dot[:, 0]),
             (np.gradient(log["east_m"].to_numpy(), t), eta_dot[:, 1]),
             (np.gradient(u, t), log["truth_u_dot_m_s2"].to_numpy()),
             (np.gradient(v, t), log["truth_v_dot_m_s2"].to_numpy()),
             (np.gradient(r, t), log["truth_r_dot_rad_s2"].to_numpy())]
    for numeric, logged in pairs:
        assert logged.std() > 0                         # moving: the check below means something
        assert np.median(np.abs(numeric - logged)) < 0.05 * logged.std()


def test_power_is_lost_at_the_shutdown_time(log):
    """``dp_active`` is 1 before ``t_shutdown_s`` and 0 from the sample at it on; no rpm after it."""
    t = log["time_s"].to_numpy()
    np.testing.assert_array_equal(log["dp_active"].to_numpy(), (t < 200.0).astype(int))
    rpm = log[[c for c in log.columns if c.endswith("_rpm")]].to_numpy()
    assert np.all(rpm[t >= 200.0] == 0.0) and np.any(rpm[t < 200.0] != 0.0)


@pytest.mark.parametrize("dt_s, t_shutdown_s", [(0.3, 0.9), (0.7, 2.1), (1.0, 3.0)])
def test_power_is_lost_at_a_shutdown_sample_whose_time_is_not_exact_in_binary(model, dt_s, t_shutdown_s):
    """3 x 0.3 s is 0.8999999999999999 s, below a shutdown at 0.9 s: that sample stayed on DP
    with its rpm applied over the following step, one step of thrust after the power failure."""
    log = physics_log(model, duration_s=6 * dt_s, dt_s=dt_s, t_shutdown_s=t_shutdown_s, seed=1)
    np.testing.assert_array_equal(log["dp_active"].to_numpy(), [1, 1, 1, 0, 0, 0, 0])
    rpm = log[[c for c in log.columns if c.endswith("_rpm")]].to_numpy()
    assert np.all(rpm[3:] == 0.0) and np.all(rpm[:3] != 0.0)


def test_the_logged_commands_replay_the_logged_motion(model, log):
    """Read back by the log reader and fed to the same model, the logged rpm, azimuths (in
    degrees) and wind reproduce the logged motion: the command logged at a sample is the
    one applied over the step that follows it."""
    from hybridship.predictors import as_log_arrays

    a = as_log_arrays(log, model.vessel)
    res = model.rollout(a.eta[0], a.nu[0], len(a.time_s) - 1, dt_s=1.0, substeps=4, rpm=a.rpm[None, :-1],
                        azimuth_rad=a.azimuth_rad[None, :-1], wind=a.wind[None, :-1])
    assert np.ptp(a.eta[:, :2], axis=0).min() > 10.0                  # the ship moves: the check means something
    np.testing.assert_allclose(res.eta[0], a.eta, atol=1e-9)
    np.testing.assert_allclose(res.nu[0], a.nu, atol=1e-9)


@pytest.mark.parametrize("kwargs, match", [(dict(current=(0.3,)), "current: expected a pair"),
                                           (dict(wind=5.0), "wind: expected a pair"),
                                           (dict(hold_s=(10.0,)), "hold_s: expected a pair")])
def test_pairs_of_the_wrong_length_are_refused_naming_them(model, kwargs, match):
    with pytest.raises(ValueError, match=match):
        physics_log(model, duration_s=20.0, **kwargs)


@pytest.mark.parametrize("tau, error, match", [
    ("abc", TypeError, r"tau_ext_N: expected an array of real numbers"),
    ([1.0, 2.0], ValueError, r"tau_ext_N: expected \(3,\) or \(20, 3\)"),
    ([np.nan, 0.0, 0.0], ValueError, r"tau_ext_N: contains NaN or inf"),
])
def test_a_bad_external_load_is_refused_naming_tau_ext_N(model, tau, error, match):
    """Before, numpy's "could not convert string to float", or the rollout's "tau_ext" with a
    batch B the caller never gave."""
    with pytest.raises(error, match=match):
        physics_log(model, duration_s=20.0, tau_ext_N=tau)
