"""The environment estimator: identification on logs where the answer is known, causality, online update."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from hybridship.physics.model import DynamicModel
from hybridship.predictors import HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import ENV, EnvironmentConfig, EnvironmentEstimator, external_accel
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=3, hidden=8, max_epochs=20, patience=5, seed=0)


def _last(est_obj, log, model):
    a = as_log_arrays(log, model.vessel)
    return est_obj.run(a, np.array([len(a.time_s) - 1]))


def test_constant_force_alone_is_identified_as_a_load(model):
    """A constant surge load on a ship with idle thrusters (so she keeps her heading and the
    load is constant in NED too), no current: the estimated load, rotated into the body frame,
    equals M^-1 tau within 10 %, and nothing is put into current or thrust error.

    With the default current prior (0.02 m/s) a current could not take the load; with one of
    0.5 m/s it could, and the drift through the water must still leave it near zero (a filter
    that explains the ship's motion by a current carrying her fails here). With the thrusters
    idle the thrust error has nothing to act on: that split is checked where the thrust varies
    (the deficit tests below)."""
    tau = np.array([4000.0, 0.0, 0.0])
    log = physics_log(model, duration_s=600, t_shutdown_s=None, seed=3, tau_ext_N=tau, wind=(0.0, 0.0),
                      rpm_scale=0.0)
    want = model.arrays.m_inv @ tau
    for current_prior in (EnvironmentConfig().current_prior_m_s, 0.5):
        est = _last(EnvironmentEstimator(model, EnvironmentConfig(current_prior_m_s=current_prior)), log, model)
        psi = est.x[0, 2]
        load_body = external_accel(np.array([psi]), est.load_accel, np.zeros((1, 3)), np.zeros((1, 3)))[0]
        assert abs(load_body[0] - want[0]) < 0.1 * want[0]
        assert abs(load_body[1]) < 0.3 * want[0]
        assert np.abs(est.current_ned_m_s).max() < 0.02          # not mistaken for a current
        assert np.abs(est.thrust_error).max() < 0.05               # nor for thrust error


def test_current_alone_is_identified_as_a_current(model):
    """A steady 0.3 m/s current on a ship manoeuvring under random commands: with a prior wide
    enough to admit it, the filter finds the current (speed within 0.05 m/s, direction within
    15 deg) and leaves the load near zero, because the hull's response to the relative
    velocity changes as the ship moves through the water."""
    log = physics_log(model, duration_s=1500, t_shutdown_s=None, seed=4, current=(0.3, 1.0), wind=(0.0, 0.0),
                      rpm_scale=0.5)
    cfg = EnvironmentConfig(current_prior_m_s=0.5, current_walk_m_s=0.0)
    est = _last(EnvironmentEstimator(model, cfg), log, model)
    speed, direction = est.current_speed_dir[0]
    assert abs(speed - 0.3) < 0.05
    assert abs(np.degrees(np.angle(np.exp(1j * (direction - 1.0))))) < 15.0
    assert np.abs(est.load_accel[0, :2]).max() < 2e-3
    assert np.abs(est.thrust_error).max() < 0.1               # nor taken for a thrust error


def test_twenty_percent_thrust_deficit_is_identified(model):
    """The true ship delivers 80 % of the model's thrust; commands vary independently of the
    (absent) environment, so the thrust error is found near -0.2 in every factor, per degree
    of freedom and per thruster, and neither the load nor the current takes the deficit."""
    spec = model.vessel.model_dump()
    spec["true_vessel"] = {"thrust_scale": 0.8}
    true_model = DynamicModel(type(model.vessel).model_validate(spec), true_vessel=True)
    log = physics_log(true_model, duration_s=1500, t_shutdown_s=None, seed=5, wind=(0.0, 0.0), rpm_scale=0.5)
    for structure in ("per_dof", "per_thruster"):
        est = _last(EnvironmentEstimator(model, EnvironmentConfig(thrust_error_model=structure)), log, model)
        assert est.thrust_error_model == structure and est.thrust_error.shape == (1, 3)
        np.testing.assert_allclose(est.thrust_error[0], [-0.2, -0.2, -0.2], atol=0.05)
        # a filter that put the deficit into the load leaves 4e-4 m/s^2, 1e-4 rad/s^2 there
        assert np.abs(est.load_accel[0, :2]).max() < 1e-4
        assert np.abs(est.load_accel[0, 2]) < 2e-5
        assert np.abs(est.current_ned_m_s).max() < 0.01


def test_a_deficit_of_one_thruster_is_found_on_that_thruster(model):
    """The true ship's tunnel thruster delivers 80 % of the model's thrust, the azimuths 100 %:
    with one efficiency factor per thruster (acting through its own lever arm), the filter
    puts -0.2 on the tunnel and about 0 on the others, and no load."""
    spec = model.vessel.model_dump()
    spec["thrusters"][0]["thrust_deduction"] = 0.2          # tunnel: (1 - 0.2) of the model's thrust
    assert spec["thrusters"][0]["name"] == "tunnel"
    true_model = DynamicModel(type(model.vessel).model_validate(spec))
    log = physics_log(true_model, duration_s=1500, t_shutdown_s=None, seed=5, wind=(0.0, 0.0), rpm_scale=0.5)
    estimator = EnvironmentEstimator(model, EnvironmentConfig(thrust_error_model="per_thruster"))
    assert estimator.state_names[-3:] == ("thrust_error_tunnel", "thrust_error_port", "thrust_error_stbd")
    est = _last(estimator, log, model)
    np.testing.assert_allclose(est.thrust_error[0], [-0.2, 0.0, 0.0], atol=0.05)
    assert np.abs(est.load_accel[0, :2]).max() < 2e-3


def test_estimate_is_causal(model):
    """The estimate at a row does not change when later rows of the log change."""
    log = physics_log(model, duration_s=600, t_shutdown_s=400, seed=6, tau_ext_N=(2000.0, 0.0, 0.0))
    a = as_log_arrays(log, model.vessel)
    rows = np.array([350, 420])
    before = EnvironmentEstimator(model).run(a, rows)
    changed = log.copy()
    changed.loc[421:, ["north_m", "east_m"]] += 50.0
    changed.loc[421:, "u_m_s"] += 1.0
    after = EnvironmentEstimator(model).run(as_log_arrays(changed, model.vessel), rows)
    np.testing.assert_array_equal(before.x, after.x)
    np.testing.assert_array_equal(before.P, after.P)
    # the same with the hull's yaw moment in a drift in the process model, shared or not
    est = EnvironmentEstimator(model)
    before = est.run(a, rows, drift_yaw_uv_rad_per_m2=0.004)
    with est.sharing_station_keeping():
        est.run(a, rows, drift_yaw_uv_rad_per_m2=0.002)
        after = est.run(as_log_arrays(changed, model.vessel), rows, drift_yaw_uv_rad_per_m2=0.004)
    np.testing.assert_array_equal(before.x, after.x)
    np.testing.assert_array_equal(before.P, after.P)


def test_shared_station_keeping_is_not_shared_across_first_rows(model):
    """On a 10-Hz log the filter steps every 10th row; two first rows can give the same grid
    while the wave motion's noise is measured over different spans: a run inside
    sharing_station_keeping gives what a run of its own does."""
    log = physics_log(model, duration_s=250, t_shutdown_s=150, dt_s=0.1, seed=8, tau_ext_N=(2000.0, 0.0, 0.0))
    a = as_log_arrays(log, model.vessel)
    rows = np.arange(1205, 2400, 10)
    est = EnvironmentEstimator(model)
    alone = est.run(a, rows, first_row=3, drift_yaw_uv_rad_per_m2=0.004)
    with est.sharing_station_keeping():
        est.run(a, rows, first_row=0, drift_yaw_uv_rad_per_m2=0.002)
        shared = est.run(a, rows, first_row=3, drift_yaw_uv_rad_per_m2=0.004)
    np.testing.assert_array_equal(shared.x, alone.x)
    np.testing.assert_array_equal(shared.P, alone.P)
    # any real number type is a coefficient: an integer 0 is no term, as 0.0 is
    np.testing.assert_array_equal(est.run(a, rows, drift_yaw_uv_rad_per_m2=np.int64(0)).x,
                                  est.run(a, rows, drift_yaw_uv_rad_per_m2=0.0).x)
    # a flag or a text is not one (True would have been taken as 1 rad/m^2): refused by name
    for bad in (True, "0.004"):
        with pytest.raises(ValueError, match=r"drift_yaw_uv_rad_per_m2: expected a finite number"):
            est.run(a, rows, drift_yaw_uv_rad_per_m2=bad)
    assert not np.array_equal(alone.x, est.run(a, rows, first_row=3).x)       # and k = 0.004 is one


def test_shared_station_keeping_carries_the_outlier_count_across_the_failure(model):
    """A position spike that starts before the failure and lasts past it: a run inside
    sharing_station_keeping goes on from the failure with the outliers counted so far, so
    it lets the spike in where a run of its own does (after max_gated_samples in a row),
    not ten samples later (it gave a north 39 m apart)."""
    log = physics_log(model, duration_s=600, t_shutdown_s=400, seed=6, tau_ext_N=(2000.0, 0.0, 0.0))
    log.loc[395:410, "north_m"] += 300.0
    a = as_log_arrays(log, model.vessel, purpose="forecast")
    assert a.dp_active[399] == 1 and a.dp_active[400] == 0
    rows = np.array([420, 500])
    est = EnvironmentEstimator(model)
    _assert_sharing_changes_nothing(est, a, rows)


def _assert_sharing_changes_nothing(est, a, rows) -> None:
    """A run inside sharing_station_keeping, after one with another drift coefficient, gives
    the estimates of a run of its own, bit for bit."""
    alone = est.run(a, rows, drift_yaw_uv_rad_per_m2=0.004)
    with est.sharing_station_keeping():
        est.run(a, rows, drift_yaw_uv_rad_per_m2=0.002)
        shared = est.run(a, rows, drift_yaw_uv_rad_per_m2=0.004)
    np.testing.assert_array_equal(shared.x, alone.x)
    np.testing.assert_array_equal(shared.P, alone.P)


def test_settling_leaves_the_environment_alone_until_the_motion_states_have_settled(model):
    """With ``settle_s`` the environment keeps its prior for that long after the filter's
    start and its value at a gap for that long after the restart, then learns; a run that
    shares the station keeping settles as a run of its own does (even when the failure,
    where sharing branches, falls inside the settling); 0 changes nothing."""
    from hybridship.residual.environment import ENV

    log = physics_log(model, duration_s=700, t_shutdown_s=130, seed=6, tau_ext_N=(3000.0, -1000.0, 2e4))
    gap = log[(log.time_s < 400) | (log.time_s >= 430)].reset_index(drop=True)     # a 30-s gap at 400 s
    a = as_log_arrays(gap, model.vessel)
    t = a.time_s
    settled = EnvironmentEstimator(model, EnvironmentConfig(settle_s=150.0))
    est = settled.run(a)
    prior = est.x[0, ENV]
    inside = (t <= 150.0)
    np.testing.assert_array_equal(est.x[inside][:, ENV], np.broadcast_to(prior, (inside.sum(), prior.size)))
    assert np.all(np.abs(est.x[(t > 160.0) & (t < 400.0)][:, ENV][:, 2] - prior[2]) > 0)      # then it learns
    before_gap = est.x[np.flatnonzero(t < 400.0)[-1], ENV]
    after = (t >= 430.0) & (t <= 580.0)
    np.testing.assert_array_equal(est.x[after][:, ENV], np.broadcast_to(before_gap, (after.sum(), prior.size)))
    assert not np.array_equal(est.x[np.flatnonzero(t > 600.0)[0], ENV], before_gap)
    rows = np.arange(100, len(t), 13)
    _assert_sharing_changes_nothing(settled, a, rows)
    # 0 (the default) settles nothing: every environment state moves at the first update after
    # the start and after the gap's restart (comparing settle_s=0 with the default alone ran
    # one configuration twice, and passed a 0 that still held the environment for seconds)
    plain = EnvironmentEstimator(model, EnvironmentConfig(settle_s=0.0)).run(a).x[:, ENV]
    np.testing.assert_array_equal(EnvironmentEstimator(model, EnvironmentConfig()).run(a).x[:, ENV], plain)
    restart = int(np.flatnonzero(t >= 430.0)[0])
    for i in (0, 1, restart, restart + 1):
        assert np.all(plain[i + 1] != plain[i]), (i, t[i])


def test_a_position_or_heading_spike_is_gated_and_a_lasting_shift_is_followed(model):
    """One corrupted position sample (300 m east) or heading sample (90 deg) in the history
    leaves the later estimate as it is without it (the heading's only through the
    wave-motion noise level it raises a little); without the gate it does not. A lasting
    20-m shift of the position (a datum change) is followed once ``max_gated_samples``
    samples in a row were gated."""
    log = physics_log(model, duration_s=600, t_shutdown_s=400, seed=6, tau_ext_N=(2000.0, 0.0, 0.0))
    rows = np.array([390, 450])
    clean = EnvironmentEstimator(model).run(as_log_arrays(log, model.vessel), rows)
    ungated_cfg = EnvironmentConfig(innovation_gate_sigma=1e9)
    clean_ungated = EnvironmentEstimator(model, ungated_cfg).run(as_log_arrays(log, model.vessel), rows)
    for col, delta in (("east_m", 300.0), ("heading_deg", 90.0)):
        spiked = log.copy()
        spiked.loc[300, col] += delta
        gated = np.abs(EnvironmentEstimator(model).run(as_log_arrays(spiked, model.vessel), rows).x - clean.x)
        ungated = np.abs(EnvironmentEstimator(model, ungated_cfg).run(
            as_log_arrays(spiked, model.vessel), rows).x - clean_ungated.x)
        assert ungated.max() > 0.05, col                               # what the spike does unchecked
        assert gated.max() < 0.1 * ungated.max(), col
        if col == "east_m":
            assert gated.max() < 1e-5
    shifted = log.copy()
    shifted.loc[300:, "north_m"] += 20.0
    est = EnvironmentEstimator(model).run(as_log_arrays(shifted, model.vessel), rows)
    assert est.x[0, 0] == pytest.approx(shifted.north_m[390], abs=1.0)


def test_a_shift_that_outlasts_the_gate_restarts_its_component_and_leaves_the_environment(model):
    """A position offset that outlasts ``max_gated_samples`` (a 30-sample excursion of 300 m,
    or a lasting datum shift) restarts the position at the measurement. Before, the sample
    that ended the gating went through a Kalman update, whose gain put most of the 300 m into
    the velocities and the load: minutes later the north load was still off by 1e-3 m/s^2
    and more, and a lasting shift was followed only after about two minutes."""
    log = physics_log(model, duration_s=900, t_shutdown_s=None, seed=6, tau_ext_N=(2000.0, 0.0, 0.0))
    rows = np.array([300, 340, 400, 600, 899])
    clean = EnvironmentEstimator(model).run(as_log_arrays(log, model.vessel, purpose="forecast"), rows)
    for length in (30, None):                           # an excursion, then a lasting shift
        shifted = log.copy()
        shifted.loc[250:(None if length is None else 250 + length - 1), "north_m"] += 300.0
        est = EnvironmentEstimator(model).run(as_log_arrays(shifted, model.vessel, purpose="forecast"), rows)
        # (the gated samples still count in the wave-motion noise level: not bit for bit)
        np.testing.assert_allclose(est.x[:, 3:6], clean.x[:, 3:6], atol=1e-3)      # before: 0.03-0.08 m/s
        np.testing.assert_allclose(est.x[:, 8:11], clean.x[:, 8:11], atol=1e-5)    # load; before: 1e-3-2e-2
        offset = 300.0 if length is None else 0.0
        np.testing.assert_allclose(est.x[:, 0], clean.x[:, 0] + offset, atol=0.01)


def test_a_biased_speed_log_does_not_pull_the_estimate_off_the_track(model, monkeypatch):
    """A speed log reading 1 m/s too much in sway for the last 100 s before a start: the
    filter leaves the logged u, v out once they disagree with the track (8 m within 30 s,
    as the start window's ``velocity_mismatch``), so its position stays within 1 m of the
    clean log's estimate. Trusted, the velocity (0.05 m/s noise against 0.5 m for the
    position) would pull the estimate metres off the GNSS."""
    from hybridship.residual import environment

    log = physics_log(model, duration_s=600, t_shutdown_s=None, seed=6, tau_ext_N=(2000.0, 0.0, 0.0))
    biased = log.copy()
    biased.loc[400:500, "v_m_s"] += 1.0
    row = np.array([500])
    clean = EnvironmentEstimator(model).run(as_log_arrays(log, model.vessel), row)
    checked = EnvironmentEstimator(model).run(as_log_arrays(biased, model.vessel), row)
    assert np.hypot(*(checked.x[0, :2] - clean.x[0, :2])) < 1.0
    monkeypatch.setattr(environment, "TRACK_MISMATCH_M", np.inf)
    trusted = EnvironmentEstimator(model).run(as_log_arrays(biased, model.vessel), row)
    assert np.hypot(*(trusted.x[0, :2] - clean.x[0, :2])) > 3.0


def test_a_biased_speed_log_is_left_out_also_where_the_fix_is_held(model):
    """A 10-Hz log whose GNSS fix is held for 1 s between updates: the filter, which steps
    once a second, may read held rows only; the last judgement of the track is carried to
    them, so the biased velocity is left out there too."""
    log = physics_log(model, duration_s=600, t_shutdown_s=None, seed=6, tau_ext_N=(2000.0, 0.0, 0.0), dt_s=0.1)
    held = log.copy()
    held[["north_m", "east_m"]] = log[["north_m", "east_m"]].to_numpy()[np.arange(len(log)) // 10 * 10]
    biased = held.copy()
    biased.loc[4000:5000, "v_m_s"] += 1.0
    rows = np.array([4995])                                    # on the held rows' grid
    clean = EnvironmentEstimator(model).run(as_log_arrays(held, model.vessel, purpose="forecast"), rows)
    checked = EnvironmentEstimator(model).run(as_log_arrays(biased, model.vessel, purpose="forecast"), rows)
    assert np.hypot(*(checked.x[0, :2] - clean.x[0, :2])) < 1.0


def test_a_segment_whose_first_row_has_no_position_restarts_at_its_next(model):
    """After a gap, a new segment whose first row lacks a position restarts at the next row
    with one (velocities from the measurement), not by predicting across the gap."""
    log = physics_log(model, duration_s=600, t_shutdown_s=None, seed=9, tau_ext_N=(2000.0, 0.0, 0.0))
    gap = log.drop(index=range(300, 420)).reset_index(drop=True)
    gap.loc[300, ["north_m", "east_m"]] = np.nan              # the new segment's first row
    a = as_log_arrays(gap, model.vessel, purpose="forecast")       # forecasts accept missing positions
    assert a.segment_id[300] != a.segment_id[299]
    est = EnvironmentEstimator(model).run(a, [301])
    np.testing.assert_allclose(est.x[0, 3:6], a.nu[301], atol=1e-9)    # restarted from the measurement
    assert est.P[0, 0, 0] == pytest.approx(EnvironmentEstimator(model)._prior_sd()[0] ** 2)


def test_a_short_gap_is_filtered_across_and_a_long_one_restarts(model):
    """One missing sample restarted the motion states from the single wave-disturbed sample
    after it, which moved the filtered velocity and every forecast started a few seconds
    later, without a flag: a gap up to ``max_bridged_gap_s`` is now predicted across, so the
    estimate 4 s after it stays near that of the full log, its uncertainty grown over the
    gap; a gap over it restarts."""
    from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

    log = simulate_dp_loss(DPLossConfig(seed=5, t_shutdown_s=900.0, drift_s=60.0))   # waves, noise
    full = as_log_arrays(log, model.vessel)
    restart = EnvironmentEstimator(model, EnvironmentConfig(max_bridged_gap_s=0.0))
    for drop in (496, 596, 696):
        holed = as_log_arrays(log.drop(index=[drop]).reset_index(drop=True), model.vessel)
        assert holed.segment_id[drop] != holed.segment_id[drop - 1]
        t = full.time_s[drop + 4]
        ref = EnvironmentEstimator(model).run(full, [drop + 4]).x[0, 3:5]
        row = int(np.flatnonzero(holed.time_s == t)[0])
        d_bridged = np.abs(EnvironmentEstimator(model).run(holed, [row]).x[0, 3:5] - ref).max()
        d_restarted = np.abs(restart.run(holed, [row]).x[0, 3:5] - ref).max()
        assert d_bridged < 0.005 and d_bridged < d_restarted / 3, (drop, d_bridged, d_restarted)
    # beyond the limit: restarted from the measurement at the first row after the gap
    long_gap = as_log_arrays(log.drop(index=range(300, 320)).reset_index(drop=True), model.vessel)
    est = EnvironmentEstimator(model, EnvironmentConfig(max_bridged_gap_s=10.0)).run(long_gap, [300])
    np.testing.assert_allclose(est.x[0, 3:6], long_gap.nu[300], atol=1e-9)
    # across a bridged 5-s gap the filter predicts without measurements: at the first row
    # after it the position is less certain than where every sample came
    short_gap = as_log_arrays(log.drop(index=range(400, 404)).reset_index(drop=True), model.vessel)
    after = EnvironmentEstimator(model).run(short_gap, [400])
    assert short_gap.time_s[400] - short_gap.time_s[399] == 5.0
    assert after.P[0, 0, 0] > 1.2 * EnvironmentEstimator(model).run(full, [404]).P[0, 0, 0]


def test_drift_samples_update_the_estimate_online(model):
    """After the thrusters stop, every new drift sample moves the estimate (and the forecast
    from that start): the estimator keeps running on the drift. With the station keeping's
    load walks the load's uncertainty shrinks as samples arrive; with the faster walks after a
    stop (the default) it grows towards where the walk and the drift samples balance, far
    below the load's prior."""
    log = physics_log(model, duration_s=1000, t_shutdown_s=800, seed=7, tau_ext_N=(3000.0, 3000.0, 0.0))
    a = as_log_arrays(log, model.vessel)
    i0 = int(np.flatnonzero(a.dp_active == 0)[0])
    rows = i0 + np.arange(1, 20)
    default = EnvironmentConfig()
    on_station = EnvironmentConfig(load_walk_after_stop_m_s2=default.load_walk_m_s2,
                                   load_yaw_walk_after_stop_rad_s2=default.load_yaw_walk_rad_s2)
    sds = []
    for config in (default, on_station):
        est = EnvironmentEstimator(model, config).run(a, rows)
        steps = np.abs(np.diff(est.x[:, 8:11], axis=0)).max(axis=1)
        assert np.all(steps > 0)
        sds.append(np.sqrt(np.einsum("sii->si", est.P[:, 8:10, 8:10])).max(axis=1))
    fast, slow = sds
    assert slow[-1] < slow[0]
    assert fast[0] < fast[-1] < 0.25 * default.load_prior_m_s2


def test_thrust_the_log_stops_recording_after_a_failure_is_not_held_in_the_drift(model):
    """A log whose rpm columns stop at the power failure (the thrusters' feedback dies with
    it): the log's reader holds the last rpm, the station keeping's. The filter takes no
    thrust there, as the forecasts do, so its drift estimates are those of the log that
    recorded the stopped thrusters (0 rpm); with the held rpm the process model pushed the
    drifting ship and the load took up the difference (about 5e-3 m/s^2 after 100 s on truthsim-dev,
    forecasts started then off by metres)."""
    log = physics_log(model, duration_s=600, t_shutdown_s=400, seed=6, tau_ext_N=(2000.0, 0.0, 0.0))
    stopped = log["dp_active"] == 0
    rpm_cols = [c for c in log.columns if c.endswith("_rpm")]
    assert stopped.any() and (log.loc[stopped, rpm_cols] == 0.0).all().all()
    lost = log.copy()
    lost.loc[stopped, rpm_cols] = np.nan
    rows = np.array([390, 450, 550])
    clean = EnvironmentEstimator(model).run(as_log_arrays(log, model.vessel, purpose="forecast"), rows)
    got = EnvironmentEstimator(model).run(as_log_arrays(lost, model.vessel, purpose="forecast"), rows)
    np.testing.assert_array_equal(got.x, clean.x)
    np.testing.assert_array_equal(got.P, clean.P)


def test_commands_missing_while_the_thrusters_run_teach_the_environment_nothing(model):
    """A minute of station keeping whose rpm the log does not record: the log's reader holds
    the last logged rpm, a guess of the thrust. The filter's motion states follow the
    measurements through it and the environment estimate stays as it was (bit for bit);
    at the failure, 740 s later, it is within half a posterior standard deviation of the
    complete log's. Learning from the held rpm had moved the current and a thruster's error
    by 0.8 to 1.6 standard deviations there."""
    log = physics_log(model, duration_s=1500, t_shutdown_s=1300, seed=12, tau_ext_N=(3000.0, -2000.0, 3000.0),
                      current=(0.2, 1.0))
    rng = np.random.default_rng(0)
    for column, sd in (("north_m", 0.3), ("east_m", 0.3), ("heading_deg", 0.2), ("u_m_s", 0.03), ("v_m_s", 0.03),
                       ("r_deg_s", 0.05)):
        log[column] += rng.normal(0.0, sd, len(log))
    rpm_cols = [c for c in log.columns if c.endswith("_rpm")]
    lost = log.copy()
    lost.loc[500:560, rpm_cols] = np.nan
    a = as_log_arrays(lost, model.vessel, purpose="forecast")
    assert not a.commands_logged[500:561].any() and a.dp_active[500:562].all()
    failure = int(np.flatnonzero(a.dp_active == 0)[0]) - 1
    got = EnvironmentEstimator(model).run(a, np.array([500, 561, failure]))
    np.testing.assert_array_equal(got.x[1, ENV], got.x[0, ENV])      # nothing learned from the guess
    assert np.abs(got.x[1, :2] - a.eta[561, :2]).max() < 1.5          # the motion follows the fixes
    clean = EnvironmentEstimator(model).run(as_log_arrays(log, model.vessel, purpose="forecast"), np.array([failure]))
    sd = np.sqrt(np.diag(clean.P[0])[ENV])
    assert np.all(np.abs(got.x[2, ENV] - clean.x[0, ENV]) < 0.5 * sd)


def test_a_load_that_changes_in_the_drift_is_followed_with_the_after_stop_walks(model):
    """The environment load changes 60 s after a failure (as it does when a drifting ship turns
    to the weather). The filter's load walks while the thrusters are stopped
    (``load_walk_after_stop_*``) let it follow: three minutes later the estimated load (in the
    body frame) is within 25 % of the new one, and less than half as far from it as with the
    station-keeping walks. Before the stop the two filters are the same to the bit: only
    stopped steps use the after-stop walks."""
    t_stop, dt = 900.0, 1.0
    n = int(1200 / dt)
    tau = np.tile([3000.0, 0.0, 0.0], (n, 1))
    tau[int((t_stop + 60.0) / dt):] = [-2000.0, 2500.0, 0.0]
    log = physics_log(model, duration_s=1200, t_shutdown_s=t_stop, seed=7, tau_ext_N=tau, wind=(0.0, 0.0))
    a = as_log_arrays(log, model.vessel)
    i0 = int(np.flatnonzero(a.dp_active == 0)[0])
    rows = np.array([i0 - 1, i0 + 240])
    default = EnvironmentConfig()
    on_station = EnvironmentConfig(load_walk_after_stop_m_s2=default.load_walk_m_s2,
                                   load_yaw_walk_after_stop_rad_s2=default.load_yaw_walk_rad_s2)
    new, old = (EnvironmentEstimator(model, c).run(a, rows) for c in (default, on_station))
    np.testing.assert_array_equal(new.x[0], old.x[0])
    np.testing.assert_array_equal(new.P[0], old.P[0])
    want = (model.arrays.m_inv @ tau[-1])[:2]

    def miss(est):
        load = external_accel(est.x[1:, 2], est.load_accel[1:], np.zeros((1, 3)), np.zeros((1, 3)))[0, :2]
        return np.linalg.norm(load - want)

    assert miss(new) < 0.25 * np.linalg.norm(want)
    assert miss(new) < 0.5 * miss(old)



def test_a_long_gap_in_a_drift_grows_the_load_with_the_after_stop_walks(model):
    """A gap in a drift longer than ``max_bridged_gap_s`` restarts the motion states and keeps
    the environment, its covariance grown over the gap: with the after-stop walks, as across a
    bridged gap, not the station keeping's (an 11-s gap then left the load less uncertain
    than a bridged 9-s one)."""
    log = physics_log(model, duration_s=1000, t_shutdown_s=800, seed=7, tau_ext_N=(3000.0, 3000.0, 0.0))
    i0 = int(np.flatnonzero(as_log_arrays(log, model.vessel).dp_active == 0)[0])
    lo = i0 + 60
    a = as_log_arrays(log.drop(index=range(lo, lo + 59)).reset_index(drop=True), model.vessel)
    gap = a.time_s[lo] - a.time_s[lo - 1]
    assert a.dp_active[lo - 1] == 0 and gap > EnvironmentConfig().max_bridged_gap_s
    c = EnvironmentConfig()
    est = EnvironmentEstimator(model, c).run(a, [lo - 1, lo])
    np.testing.assert_allclose(est.x[1, 3:6], a.nu[lo], atol=1e-9)        # restarted
    grown = np.diag(est.P[1])[8:11] - np.diag(est.P[0])[8:11]
    want = np.array([c.load_walk_after_stop_m_s2] * 2 + [c.load_yaw_walk_after_stop_rad_s2]) ** 2 * gap
    np.testing.assert_allclose(grown, want, rtol=1e-6)

def test_current_widened_at_the_stop_keeps_the_estimate_and_lets_the_drift_find_the_current(model):
    """A 0.3 m/s current alone, station keeping, then a failure. Widened along the
    current-load ridge at the stop (``current_std_at_stop_m_s``), the estimate at the stop is
    the default's, with the current's spread raised to the width given, and the hull's
    acceleration predicted with the current and load (no thrust) stays the same to first
    order; the drift then brings the current nearer the truth than the default filter, which
    keeps the split station keeping gave it."""
    log = physics_log(model, duration_s=1400, t_shutdown_s=1000, seed=7, current=(0.3, 1.0), wind=(0.0, 0.0))
    a = as_log_arrays(log, model.vessel)
    i0 = int(np.flatnonzero(a.dp_active == 0)[0])
    rows = np.array([i0, len(a.time_s) - 1])
    base = EnvironmentEstimator(model).run(a, rows)
    wide_est = EnvironmentEstimator(model, EnvironmentConfig(current_std_at_stop_m_s=0.3))
    wide = wide_est.run(a, rows)
    np.testing.assert_allclose(wide.x[0], base.x[0])
    assert np.allclose(np.sqrt(np.diag(wide.P[0])[6:8]), 0.3, rtol=0.01)
    # along the widened directions the no-thrust acceleration is unchanged to first order,
    # while the same current change without its paired load change moves it
    x0 = base.x[0]
    ridge = np.linalg.eigh(wide.P[0] - base.P[0])[1][:, -2:]

    def accel(x):
        cur = np.hypot(x[6], x[7]), np.arctan2(x[7], x[6])
        ext = external_accel(x[2], x[8:11], 0.0, 0.0)
        return model.acceleration(x[:3], x[3:6], rpm=np.zeros(model.n_channels), current=cur, accel_ext=ext)[0]
    for k in range(2):
        step = 0.005 * ridge[:, k] / np.linalg.norm(ridge[6:8, k])     # 0.005 m/s of current
        current_only = np.where(np.arange(x0.size) < 8, step, 0.0)
        moved = np.abs(accel(x0 + current_only) - accel(x0)).max()
        assert moved > 0
        assert np.abs(accel(x0 + step) - accel(x0)).max() < 0.05 * moved
    truth = 0.3 * np.array([np.cos(1.0), np.sin(1.0)])
    err_base = np.linalg.norm(base.current_ned_m_s[1] - truth)
    err_wide = np.linalg.norm(wide.current_ned_m_s[1] - truth)
    assert err_wide < 0.8 * err_base


def test_the_current_prior_scales_with_the_wind_at_the_filter_start():
    """``current_prior_m_s (U_ref / U)^2``, clipped to [current_prior_m_s, current_prior_max_m_s];
    the configured prior without a reference speed or a logged wind."""
    from hybridship.residual.environment import current_prior_std_m_s

    c = EnvironmentConfig(current_prior_wind_ref_m_s=10.0)
    assert current_prior_std_m_s(c, 5.0) == pytest.approx(0.02 * 4.0)
    assert current_prior_std_m_s(c, 10.0) == current_prior_std_m_s(c, 25.0) == 0.02
    assert current_prior_std_m_s(c, 1.0) == current_prior_std_m_s(c, 0.0) == 0.3
    assert current_prior_std_m_s(c, None) == 0.02
    assert current_prior_std_m_s(EnvironmentConfig(), 1.0) == 0.02
    # a maximum below the configured prior leaves the configured prior
    assert current_prior_std_m_s(EnvironmentConfig(current_prior_wind_ref_m_s=10.0, current_prior_max_m_s=0.01),
                                 1.0) == 0.02
    with pytest.raises(ValueError, match="current_prior_wind_ref_m_s"):
        EnvironmentConfig(current_prior_wind_ref_m_s=0.0)


def test_a_current_in_light_wind_is_found_with_the_prior_scaled_by_the_wind(model):
    """A 0.3 m/s current in a 2 m/s wind, station keeping, then a failure. With the prior scaled
    by the wind at the filter's start, the current at the stop and after 300 s of drift is
    nearer the truth than the default filter's, whose narrow prior takes the offset as a load;
    in a wind at or above the reference speed, and on the same log without its wind, the
    option's estimates are the default's, bit for bit."""
    truth = 0.3 * np.array([np.cos(1.0), np.sin(1.0)])
    scaled = EnvironmentConfig(current_prior_wind_ref_m_s=10.0)
    for wind, better in ((2.0, True), (12.0, False)):
        log = physics_log(model, duration_s=1300, t_shutdown_s=1000, seed=7, current=(0.3, 1.0), wind=(wind, 0.5))
        a = as_log_arrays(log, model.vessel)
        rows = np.array([int(np.flatnonzero(a.dp_active == 0)[0]), len(a.time_s) - 1])
        base = EnvironmentEstimator(model).run(a, rows)
        est = EnvironmentEstimator(model, scaled).run(a, rows)
        if better:
            err_base = np.linalg.norm(base.current_ned_m_s - truth, axis=1)
            err = np.linalg.norm(est.current_ned_m_s - truth, axis=1)
            assert np.all(err < 0.8 * err_base), (err, err_base)
        else:
            np.testing.assert_array_equal(est.x, base.x)
            np.testing.assert_array_equal(est.P, base.P)
    windless = log.drop(columns=["wind_speed_m_s", "wind_dir_deg"])
    a = as_log_arrays(windless, model.vessel)
    np.testing.assert_array_equal(EnvironmentEstimator(model, scaled).run(a, rows).x,
                                  EnvironmentEstimator(model).run(a, rows).x)


def test_the_load_prior_narrowed_across_the_wind():
    """``s^2 (a a^T + rho^2 (I - a a^T))`` with ``a`` the wind's axis; the filter's own
    diagonal (a first entry of -1) at ``rho = 1`` or without a logged wind."""
    from hybridship.residual.environment import load_prior_ne

    c = EnvironmentConfig(load_prior_across_wind=0.1)
    P = load_prior_ne(c, np.radians(30.0))
    a = np.array([np.cos(np.radians(30.0)), np.sin(np.radians(30.0))])
    across = np.array([-a[1], a[0]])
    assert a @ P @ a == pytest.approx(0.02 ** 2) and across @ P @ across == pytest.approx((0.1 * 0.02) ** 2)
    assert a @ P @ across == pytest.approx(0.0, abs=1e-20) and np.array_equal(P, P.T)
    # the wind's axis, not its sense: from the opposite side the prior is the same
    np.testing.assert_allclose(load_prior_ne(c, np.radians(210.0)), P, rtol=1e-12)
    for config, direction in ((c, None), (EnvironmentConfig(), 0.5)):
        assert load_prior_ne(config, direction)[0, 0] == -1.0
    for bad in (0.0, 1.5):
        with pytest.raises(ValueError, match="load_prior_across_wind"):
            EnvironmentConfig(load_prior_across_wind=bad)


def test_an_offset_across_the_wind_is_taken_less_as_a_load_with_the_load_prior_narrowed_across_it(model):
    """Station keeping in a 6 m/s wind from the north with a 0.3 m/s current to the east,
    then a failure (the project's simulator). With the load's prior narrowed across the wind
    (0.1) the load across it at the stop is smaller than with the prior alike in every
    direction: the offset goes to the thrusters' errors and the current. With a current prior
    of 0.05 m/s the current at the stop is nearer the truth too. At 1, and on the same log
    without its wind, the estimates are the default's, bit for bit."""
    from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

    sea = dict(hs_m=0.8, tp_s=6.0, wave_dir_from_rad=0.0, wind_speed_m_s=6.0, wind_dir_from_rad=0.0,
               current_speed_m_s=0.3, current_dir_to_rad=np.pi / 2)
    log = simulate_dp_loss(DPLossConfig(seed=1, sea_state=sea, heading_sp_deg=0.0, t_shutdown_s=600.0,
                                        t_shutdown_jitter_s=0.0, drift_s=300.0))
    a = as_log_arrays(log, model.vessel)
    rows = np.array([int(np.flatnonzero(a.dp_active == 0)[0]) - 1])

    def run(**kw):
        return EnvironmentEstimator(model, EnvironmentConfig(**kw)).run(a, rows)

    base, narrowed = run(), run(load_prior_across_wind=0.1)
    assert 0.0 < narrowed.x[0, 9] < 0.95 * base.x[0, 9]             # the load east, across the wind
    wide, wide_narrowed = run(current_prior_m_s=0.05), run(current_prior_m_s=0.05, load_prior_across_wind=0.1)
    assert 0.0 < wide_narrowed.x[0, 9] < 0.9 * wide.x[0, 9]
    err = [np.linalg.norm(e.current_ned_m_s[0] - [0.0, 0.3]) for e in (wide, wide_narrowed)]
    assert err[1] < 0.9 * err[0], err
    one = run(load_prior_across_wind=1.0)
    np.testing.assert_array_equal(one.x, base.x)
    np.testing.assert_array_equal(one.P, base.P)
    windless = as_log_arrays(log.drop(columns=["wind_speed_m_s", "wind_dir_deg"]), model.vessel)
    np.testing.assert_array_equal(
        EnvironmentEstimator(model, EnvironmentConfig(load_prior_across_wind=0.1)).run(windless, rows).x,
        EnvironmentEstimator(model).run(windless, rows).x)


def test_load_re_explained_as_a_current_at_the_stop_finds_the_current_that_makes_it(model):
    """A load equal to the hull's response at rest to a 0.3 m/s current, re-explained as a
    current at the stop (``load_to_current_at_stop=1``): that current is found and the load
    left is zero; half of it leaves the current's share at the same acceleration."""
    from hybridship.residual import environment_kernel as kernel

    est = EnvironmentEstimator(model, EnvironmentConfig(load_to_current_at_stop=1.0))
    x = np.zeros(len(est.state_names))
    x[2] = 0.3
    a_c = model.acceleration(x[:3], x[3:6], rpm=np.zeros(model.n_channels), current=(0.3, 1.2))[0]
    c, s = np.cos(0.3), np.sin(0.3)
    x[8:11] = c * a_c[0] - s * a_c[1], s * a_c[0] + c * a_c[1], a_c[2]
    work = kernel._workspace(model.arrays)
    x1 = kernel.load_to_current_at_stop(x, 1.0, model.arrays, work)
    assert np.hypot(*x1[6:8]) == pytest.approx(0.3, abs=1e-4)
    assert np.arctan2(x1[7], x1[6]) == pytest.approx(1.2, abs=1e-3)
    assert np.abs(x1[8:11]).max() < 1e-6
    # the estimator's own stop (live mode) applies it too
    assert np.hypot(*est.at_thrust_stop(x, np.eye(x.size) * 1e-4)[0][6:8]) == pytest.approx(0.3, abs=1e-4)
    half = kernel.load_to_current_at_stop(x, 0.5, model.arrays, work)

    def accel(xx):
        ext = external_accel(xx[2], xx[8:11], 0.0, 0.0)
        return model.acceleration(xx[:3], xx[3:6], rpm=np.zeros(model.n_channels),
                                  current=(np.hypot(*xx[6:8]), np.arctan2(xx[7], xx[6])), accel_ext=ext)[0]
    np.testing.assert_allclose(accel(half), accel(x), atol=1e-9)
    assert 0.1 < np.hypot(*half[6:8]) < 0.3


@pytest.fixture(scope="module")
def drift_forecasts(model):
    """A hybrid fitted on one log's station keeping, and its forecasts from the 1..19 s after
    another log's failure: ``(hp, test_log, t_failure_s, starts_s, forecast)``."""
    logs = [physics_log(model, duration_s=1100, t_shutdown_s=900, seed=s, tau_ext_N=(3000.0, -2000.0, 0.0))
            for s in (8, 9)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs[:1])
    test = logs[1]
    t0 = float(test.time_s[np.flatnonzero(test.dp_active.to_numpy() == 0)[0]])
    starts = t0 + np.arange(1, 20)
    return hp, test, t0, starts, hp.forecast(test, starts, 60.0)


def test_hybrid_forecasts_after_a_failure_use_the_drift_samples(drift_forecasts):
    """Forecasts started 1..19 s after the failure use the estimate at their own start: a
    forecast from start k equals the one made from a log cut right after k, and differs from
    the one made without the drift samples since the failure."""
    hp, test, t0, starts, full = drift_forecasts
    k = 10
    # cut at the start itself (a cut 60 s later passed a forecast that read the drift past its start)
    cut = test[test.time_s <= starts[k]].reset_index(drop=True)
    again = hp.forecast(cut, [starts[k]], 60.0)
    np.testing.assert_allclose(again.eta[0], full.eta[k], atol=1e-9)
    est = hp.environment_estimate(test, starts)
    assert not np.allclose(est.load_accel[0], est.load_accel[-1])


def test_every_forecast_after_a_failure_reads_its_drift_up_to_its_start_and_nothing_after(drift_forecasts):
    """For each start 1..19 s after the failure: changing every measured channel after the
    start (positions, heading, velocities, wind; some positions missing) leaves its forecast
    and spread bit for bit; moving the drift's positions between the failure and the start by
    0.5 m moves the forecast, and withholding the drift samples changes the environment the
    forecast starts from (the estimate at the start is not the station keeping's held)."""
    hp, test, t0, starts, full = drift_forecasts
    env = hp.environment_estimate(test, starts).x[:, ENV]
    measured = ["north_m", "east_m", "heading_deg", "u_m_s", "v_m_s", "r_deg_s", "wind_speed_m_s", "wind_dir_deg"]
    for k, start in enumerate(starts):
        later = test.copy()
        after = later.time_s > start
        later.loc[after, measured] = later.loc[after, measured].to_numpy() * 1.5 + 7.0
        later.loc[after & (later.index % 4 == 0), ["north_m", "east_m"]] = np.nan
        alone = hp.forecast(later, [start], 60.0)
        np.testing.assert_array_equal(alone.eta[0], full.eta[k])
        np.testing.assert_array_equal(alone.eta_std[0], full.eta_std[k])
        drift = (test.time_s >= t0) & (test.time_s < start)
        moved = test.copy()
        moved.loc[drift, "north_m"] += 0.5
        assert np.abs(hp.forecast(moved, [start], 60.0).eta[0] - full.eta[k]).max() > 1e-4
        blind = test.copy()
        blind.loc[drift, measured[:6]] = np.nan
        assert np.abs(hp.environment_estimate(blind, [start]).x[0, ENV] - env[k]).max() > 1e-6


def test_config_rejects_bad_values():
    with pytest.raises(ValueError, match="position_std_m"):
        EnvironmentConfig(position_std_m=0.0)
    # an infinite setting passes a lower bound; it is refused by name, not used
    for field in ("settle_s", "held_load_window_s", "load_walk_m_s2"):
        with pytest.raises(ValueError, match=rf"{field}[\s\S]*finite number"):
            EnvironmentConfig(**{field: float("inf")})
    with pytest.raises(ValueError, match="environment"):
        HybridPredictor("gunnerus", environment="nets")


def test_config_refuses_a_held_load_window_shorter_than_three_blocks():
    """A held-load window under three blocks can never give the variability (it needs three
    block means), so every spread silently went without it; 0 switches it off on purpose."""
    for window, block in ((60.0, 30.0), (1.0, 30.0), (600.0, 250.0)):
        with pytest.raises(ValueError, match=rf"^held_load_window_s: must be 0 \(off\) or at least three "
                                             rf"held_load_block_s = {3 * block:g} s, got {window:g} \[EnvironmentConfig\]"):
            EnvironmentConfig(held_load_window_s=window, held_load_block_s=block)
    assert EnvironmentConfig(held_load_window_s=0.0).held_load_window_s == 0.0
    assert EnvironmentConfig(held_load_window_s=90.0).held_load_window_s == 90.0
    assert EnvironmentConfig().held_load_window_s == 600.0 and EnvironmentConfig().held_load_block_s == 30.0


@pytest.mark.parametrize("field, value", [("settle_s", True), ("settle_s", "30"), ("max_gated_samples", True),
                                          ("max_gated_samples", "10"), ("yaw_load_std_at_stop", False),
                                          ("thrust_error_prior", (0.2, 0.2, -0.5)),
                                          ("thrust_error_prior", (0.2, 0.0, 0.5))])
def test_config_refuses_flags_text_and_a_per_dof_prior_that_is_not_a_spread(field, value):
    """As the other configs: a bool is not read as 1 or 0 nor a text as a number, and the
    per-DOF prior standard deviations must be > 0 as the per-thruster one must (a negative
    one was accepted and squared)."""
    with pytest.raises(ValueError, match=field):
        EnvironmentConfig(**{field: value})
    assert EnvironmentConfig(settle_s=np.float32(30.0), max_gated_samples=np.int64(3)).max_gated_samples == 3


def test_estimator_refuses_a_model_that_is_not_a_dynamic_model_by_name():
    """A vessel name given for the model failed in Python's words ('str' object has no
    attribute 'vessel'); it is now a TypeError naming model, as physics_log's."""
    with pytest.raises(TypeError, match=r"^model: expected a DynamicModel, got str \(DynamicModel\('gunnerus'\)\?\)"):
        EnvironmentEstimator("gunnerus")


def test_estimator_takes_its_settings_as_a_config_or_a_dict_of_its_fields(model):
    """A dict of settings is validated as an EnvironmentConfig (it failed as an attribute
    error on dict); a misspelt key or another type is refused by name."""
    est = EnvironmentEstimator(model, {"thrust_error_model": "per_dof", "settle_s": 30.0})
    assert est.config == EnvironmentConfig(thrust_error_model="per_dof", settle_s=30.0)
    assert est.state_names[-1] == "thrust_error_n"
    with pytest.raises(ValueError, match="config: .*setle_s"):
        EnvironmentEstimator(model, {"setle_s": 30.0})
    with pytest.raises(TypeError, match="config: expected an instance of EnvironmentConfig"):
        EnvironmentEstimator(model, "per_dof")


def test_nets_stay_off_after_a_failure_unless_allowed(model):
    """Trained on whole logs (drift included), the thrust regime alone would keep the nets on
    after a failure; by default they are off there (guard weight 0), and nets_after_stop
    turns them back on."""
    logs = [physics_log(model, duration_s=1000, t_shutdown_s=800, seed=s, tau_ext_N=(2000.0, 0.0, 0.0))
            for s in (10, 11)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs[:1], dp_only=False)
    t0 = float(logs[1].time_s[np.flatnonzero(logs[1].dp_active.to_numpy() == 0)[0]])
    starts = t0 + np.arange(2, 6)
    off = hp.forecast(logs[1], starts, 30.0)
    on = hp.forecast(logs[1], starts, 30.0, nets_after_stop=True)
    assert np.all(off.guard_weight[:, 1:] == 0.0)
    assert np.any(on.guard_weight[:, 1:] > 0.0)
    assert not np.allclose(off.eta, on.eta)
    before = hp.forecast(logs[1], [t0 - 100.0], 30.0)          # station keeping: nets on as before
    assert np.any(before.guard_weight[:, 1:] > 0.0)
    # without the guard the nets stay off after the failure too: the switch is not the guard's
    unguarded = hp.forecast(logs[1], starts, 30.0, guard=False)
    np.testing.assert_allclose(unguarded.eta, hp.forecast(logs[1], starts, 30.0, nets=False).eta)
    assert not np.allclose(hp.forecast(logs[1], starts, 30.0, guard=False, nets_after_stop=True).eta, unguarded.eta)


def test_spread_after_a_stop_is_calibrated_on_logs_with_failures(model, tmp_path):
    """calibrate_after_stop scales the spread of starts after a failure only: on its own
    calibration logs the calibrated 2-sigma band then covers at least 95.45 % of the
    north/east errors at every lead (split-conformal), a start after the failure is
    calibrated whatever other starts it is forecast with, and the scale survives a
    model-file round trip."""
    from hybridship.evaluation import metrics

    train = [physics_log(model, duration_s=1000, t_shutdown_s=800, seed=s, tau_ext_N=(3000.0, -2000.0, 0.0))
             for s in (12, 13)]
    cal_logs = [physics_log(model, duration_s=1000, t_shutdown_s=800, seed=s, current=(0.2, 2.0),
                            tau_ext_N=(2000.0, 1000.0, 0.0)) for s in (14, 15, 16)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit(train)
    hp.calibrate_after_stop(cal_logs, n_intervals=20, horizon_s=60.0)
    assert "after_stop" in hp.calibration
    cov = []
    for log in cal_logs:
        a = as_log_arrays(log, model.vessel)
        p, t, sd = metrics.drift_forecasts(hp, a, n_intervals=20, horizons_s=tuple(range(1, 61)))
        cov.append(np.abs(p - t)[..., :2] <= 2.0 * sd[..., :2])
    per_lead = np.concatenate(cov).mean(axis=(0, 2))          # 3 logs x 20 starts x north/east: 120 a lead
    assert per_lead.min() >= 0.95
    # and not more: the split-conformal scale covers k = ceil(121 x 0.9545) = 116 of them (0.967) at
    # most; a scale one order statistic too high covers 117, one twice too wide all 120
    assert per_lead.max() <= 0.97
    log = cal_logs[0]
    t0 = float(log.time_s[np.flatnonzero(log.dp_active.to_numpy() == 0)[0]])
    raw = hp.forecast(log, [t0 - 50.0, t0 + 5.0], 60.0, calibrated=False)
    cal = hp.forecast(log, [t0 - 50.0, t0 + 5.0], 60.0)
    assert not np.allclose(raw.eta_std[1, 1:], cal.eta_std[1, 1:])
    np.testing.assert_allclose(hp.forecast(log, [t0 + 5.0], 60.0).eta_std[0], cal.eta_std[1])
    path = hp.save(tmp_path / "m.npz")
    again = HybridPredictor.load(path).forecast(log, [t0 - 50.0, t0 + 5.0], 60.0)
    np.testing.assert_allclose(again.eta_std, cal.eta_std)
    # later in the drift the errors grow with its speed: starts from 20 s after the failures on
    # have a calibration of their own, which a start 100 s into the drift uses
    import copy

    from hybridship.predictors.hybrid import AFTER_STOP_LATE

    assert AFTER_STOP_LATE in hp.calibration and hp.training_info["calibration"][AFTER_STOP_LATE]["n_logs"] == 3
    starts = [t0 - 50.0, t0 + 19.0, t0 + 100.0]
    fc, raw = hp.forecast(log, starts, 60.0), hp.forecast(log, starts, 60.0, calibrated=False)
    np.testing.assert_allclose(fc.eta_std[2], hp.calibrated_std(raw.eta_std[2:], raw.lead_s, AFTER_STOP_LATE)[0])
    np.testing.assert_allclose(fc.eta_std[1], hp.calibrated_std(raw.eta_std[1:2], raw.lead_s, "after_stop")[0])
    assert not any(fc.notes)
    assert AFTER_STOP_LATE in HybridPredictor.load(path).calibration          # kept in the model file
    # without it (a model from before, or drifts too short for it) such a start says so
    early_only = copy.copy(hp)
    early_only.calibration = {k: v for k, v in hp.calibration.items() if k != AFTER_STOP_LATE}
    notes = early_only.forecast(log, starts, 60.0).notes
    assert "within 20 s of a failure" not in notes[0] + notes[1]
    assert "calibrated on forecasts that start within 20 s of a failure; this one starts 100 s after it" in notes[2]



def test_drifts_too_short_for_enough_later_starts_fit_without_their_calibration(model):
    """Three failures whose drifts last 110 s leave 3 later starts each (12 samples per lead
    pooled with the first starts' logs): fit raised fit_spread_scale's "12 finite samples at
    lead 1 s; need 20". It now fits the first starts' calibration only, and a start later in
    such a drift says that its band is the first starts'."""
    from hybridship.predictors.hybrid import AFTER_STOP, AFTER_STOP_LATE

    logs = [physics_log(model, seed=s, duration_s=1200.0, t_shutdown_s=1090.0, current=(0.2, 1.0)) for s in (1, 2, 3)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs)
    assert AFTER_STOP in hp.calibration and AFTER_STOP_LATE not in hp.calibration
    assert AFTER_STOP_LATE not in hp.training_info["calibration"]
    note = hp.forecast(logs[0], [1090.0 + 30.0], 60.0).notes[0]
    assert "calibrated on forecasts that start within 20 s of a failure; this one starts 30 s after it" in note


def test_fit_calibrates_the_spread_after_a_failure_on_the_training_logs_own_failures(model):
    """With three failures in the training logs, fit calibrates the spread after a failure on
    them (the scale calibrate_after_stop gives on the same logs); with two, or with the
    option off, the spread after a failure stays raw."""
    from hybridship.residual.calibration import CalibrationConfig

    logs = [physics_log(model, duration_s=1000, t_shutdown_s=800, seed=s, current=(0.2, 2.0),
                        tau_ext_N=(2000.0, 1000.0, 0.0)) for s in (14, 15, 16)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY, drift_hull=False).fit(logs)
    assert "after_stop" in hp.calibration
    info = hp.training_info["calibration"]["after_stop"]
    assert info["n_logs"] == 3 and info["source"] == "the training logs' failures"
    off = HybridPredictor(model.vessel, ensemble_config=TINY, drift_hull=False).fit(
        logs, calibration=CalibrationConfig(after_stop_min_failures=0))
    assert "after_stop" not in off.calibration
    off.calibrate_after_stop(logs)
    for what in ("position", "heading"):
        np.testing.assert_allclose(off.calibration["after_stop"][what].scale, hp.calibration["after_stop"][what].scale)
    two = HybridPredictor(model.vessel, ensemble_config=TINY, drift_hull=False).fit(logs[:2])
    assert "after_stop" not in two.calibration


def test_a_failure_needs_station_keeping_before_it_and_enough_drift_after_it(model):
    from hybridship.predictors.after_failure import has_drift

    log = physics_log(model, duration_s=1000, t_shutdown_s=800, seed=14)     # 200 s of drift
    a = as_log_arrays(log, model.vessel)
    assert has_drift(a, 20, 60.0) and has_drift(a, 20, 180.0) and not has_drift(a, 20, 182.0)
    manoeuvring = log.assign(dp_active=0)          # never on station: no failure to calibrate on
    assert not has_drift(as_log_arrays(manoeuvring, model.vessel), 20, 60.0)


def test_run_leaves_out_optional_rows_before_the_first_valid_position(model):
    """``required`` rows must have an estimate (else the clear error); later rows that come
    before the log's first valid position are left out."""
    from hybridship.logs.ingest import ingest

    log = physics_log(model, duration_s=300.0, t_shutdown_s=None, seed=4)
    log.loc[0, ["north_m", "u_m_s"]] = np.nan                # a missing first sample (as a forecast reads it)
    a = ingest(log, model.vessel, purpose="forecast")
    est = EnvironmentEstimator(model).run(a, np.array([200, 0, 60, 120]), required=1)
    assert list(est.rows) == [200, 60, 120]
    with pytest.raises(ValueError, match="no valid position/heading at or before row 0"):
        EnvironmentEstimator(model).run(a, np.array([200, 0]), required=2)
    # a row past the log's end, or before the filter's first row, is refused as such (not
    # taken for a row without a position, nor left to an index error)
    n = len(a.time_s)
    for rows, first_row in (([120, n], 0), ([120, 5], 10)):
        with pytest.raises(ValueError, match=rf"rows: must lie in \[{first_row}, {n - 1}\]"):
            EnvironmentEstimator(model).run(a, np.array(rows), first_row=first_row, required=1)


def test_run_refuses_rows_first_row_and_required_that_are_not_rows_of_the_log(model):
    """run's rows are whole row numbers of a 1-D array (10.7 was read as row 10, a 2-D array
    failed in numpy's words), its first_row a row of the log (a negative one failed in a
    broadcast, one past the end as a command-shape error) and required at most the rows
    given (more, or a negative number, passed unnoticed); an empty rows gives an empty
    estimate, not a numpy error."""
    a = as_log_arrays(physics_log(model, duration_s=120.0, t_shutdown_s=None, seed=4), model.vessel)
    n = len(a.time_s)
    est = EnvironmentEstimator(model)
    for rows in ([10.7], [[10, 20]], np.array([True, False])):
        with pytest.raises(ValueError, match="rows: expected a 1-D array of whole row numbers"):
            est.run(a, rows)
    for first_row in (-5, n, 2.0, True):
        with pytest.raises(ValueError, match=rf"first_row: expected a whole number in \[0, {n - 1}\]"):
            est.run(a, [100], first_row=first_row)
    with pytest.raises(ValueError, match="required: expected at most the 2 rows given, got 3"):
        est.run(a, [10, 20], required=3)
    with pytest.raises(ValueError, match="required: expected a whole number >= 0"):
        est.run(a, [10, 20], required=-1)
    empty = est.run(a, [])
    assert empty.rows.shape == (0,) and empty.x.shape == (0, 14) and empty.P.shape == (0, 14, 14)
    np.testing.assert_array_equal(est.run(a, np.array([10, 20], dtype=np.int32), first_row=np.int64(5)).x,
                                  est.run(a, [10, 20], first_row=5).x)


def _tunnel_deficit_logs(model, seeds, *, t_shutdown_s=700.0, duration_s=900.0):
    """Logs of a true ship whose tunnel thruster delivers 80 % of the model's thrust, each
    with a thrust stop at ``t_shutdown_s`` followed by a drift."""
    spec = model.vessel.model_dump()
    spec["thrusters"][0]["thrust_deduction"] = 0.2          # tunnel: (1 - 0.2) of the model's thrust
    true_model = DynamicModel(type(model.vessel).model_validate(spec))
    return [physics_log(true_model, duration_s=duration_s, t_shutdown_s=t_shutdown_s, seed=s, wind=(0.0, 0.0),
                        rpm_scale=0.5, tau_ext_N=(1500.0, -1000.0, 0.0)) for s in seeds]


def test_fit_carries_the_thrust_error_seen_at_stops_into_the_prior(model):
    """EnvironmentEstimator.fit reads the filter 60 s after every thrust stop of its logs and
    makes their precision-weighted mean the prior: the tunnel's 20 % deficit on that thruster,
    the azimuths near 0, with a spread tighter than the configured one; with dp_only, or
    without a stop, the prior stays as configured."""
    logs = [as_log_arrays(x, model.vessel) for x in _tunnel_deficit_logs(model, (30, 31))]
    est = EnvironmentEstimator(model).fit(logs)
    np.testing.assert_allclose(est.thrust_error_mean, [-0.2, 0.0, 0.0], atol=0.06)
    assert np.all(est.thrust_error_std < 0.2)
    # by hand from the filter read 60 s after each stop: the precision-weighted mean, and a
    # spread no smaller than the stops' pooled uncertainty (here it is that: the two stops
    # agree within it), nor than their scatter
    theta, prec = [], []
    for a in logs:
        stop = int(np.flatnonzero(a.dp_active == 0)[0])
        at = EnvironmentEstimator(model).run(a, [int(np.searchsorted(a.time_s, a.time_s[stop] + 60.0))])
        theta.append(at.x[0, 11:])
        prec.append(1.0 / np.diag(at.P[0])[11:])
    theta, prec = np.array(theta), np.array(prec)
    mean = (prec * theta).sum(axis=0) / prec.sum(axis=0)
    pooled = 1.0 / np.sqrt(prec.sum(axis=0))
    scatter = np.sqrt((prec * (theta - mean) ** 2).sum(axis=0) / prec.sum(axis=0))
    assert np.all(scatter < pooled)
    np.testing.assert_allclose(est.thrust_error_mean, mean, rtol=1e-9)
    np.testing.assert_allclose(est.thrust_error_std, np.maximum(pooled, scatter), rtol=1e-9)
    # the docstring said "at least each stop's own uncertainty", which is wider than this
    assert np.all(pooled < 1.0 / np.sqrt(prec.max(axis=0)))
    assert "at least the pooled uncertainty of the mean" in " ".join(EnvironmentEstimator.fit.__doc__.split())
    # the stops above agree within their uncertainty, so the scatter was never the spread (a fit
    # that left it out passed): two stops read as -0.3 and -0.1 on the tunnel, 0 and 0 on port,
    # 0.1 and -0.1 on starboard, each +- 0.01, have a scatter of 0.1 on the tunnel and starboard
    # (wider than the pooled 0.01 / sqrt(2)) and none on port
    read = iter([[-0.3, 0.0, 0.1], [-0.1, 0.0, -0.1]])

    def stop_read(a, rows, first_row=0):
        x = np.zeros((1, 14))
        x[0, 11:] = next(read)
        return SimpleNamespace(x=x, P=1e-4 * np.eye(14)[None])

    by_hand = EnvironmentEstimator(model)
    by_hand.run = stop_read
    by_hand.fit(logs)
    np.testing.assert_allclose(by_hand.thrust_error_mean, [-0.2, 0.0, 0.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(by_hand.thrust_error_std, [0.1, 0.01 / np.sqrt(2.0), 0.1], rtol=1e-9)
    no_stop = as_log_arrays(physics_log(model, duration_s=600, t_shutdown_s=None, seed=30), model.vessel)
    for unchanged in (EnvironmentEstimator(model).fit(logs, dp_only=True), EnvironmentEstimator(model).fit([no_stop])):
        np.testing.assert_array_equal(unchanged.thrust_error_mean, 0.0)
        np.testing.assert_array_equal(unchanged.thrust_error_std, 0.2)


def test_fit_learns_afresh_each_time_from_the_configured_prior(model):
    """A second fit on the same logs learns what the first did (its runs start from the
    configured prior, not from the one learned before, which would count the logs twice and
    narrow the spread); a fit without a stop, or with dp_only, leaves the configured prior,
    whatever an earlier fit learned."""
    logs = [as_log_arrays(x, model.vessel) for x in _tunnel_deficit_logs(model, (30,), duration_s=800.0)]
    est = EnvironmentEstimator(model).fit(logs)
    mean, std = est.thrust_error_mean.copy(), est.thrust_error_std.copy()
    assert np.all(std < 0.2)
    est.fit(logs)
    np.testing.assert_array_equal(est.thrust_error_mean, mean)
    np.testing.assert_array_equal(est.thrust_error_std, std)
    no_stop = as_log_arrays(physics_log(model, duration_s=300, t_shutdown_s=None, seed=30), model.vessel)
    for refit in (lambda: est.fit([no_stop]), lambda: est.fit(logs, dp_only=True)):
        est.fit(logs)
        refit()
        np.testing.assert_array_equal(est.thrust_error_mean, 0.0)
        np.testing.assert_array_equal(est.thrust_error_std, 0.2)


def test_fit_refuses_a_dp_only_that_is_not_a_flag_and_a_drift_time_that_is_not_one(model):
    """fit's dp_only must be True or False (a text "no" was read as True and nothing was
    learned) and after_stop_s a finite time >= 0 (NaN skipped every stop unnoticed, a
    negative one read the station keeping before the stop as its drift)."""
    a = as_log_arrays(physics_log(model, duration_s=120.0, t_shutdown_s=None, seed=4), model.vessel)
    est = EnvironmentEstimator(model)
    with pytest.raises(TypeError, match="dp_only: expected True or False, got 'no'"):
        est.fit([a], dp_only="no")
    for bad in (float("nan"), -50.0):
        with pytest.raises(ValueError, match="after_stop_s: must be"):
            est.fit([a], after_stop_s=bad)
    with pytest.raises(TypeError, match="after_stop_s: expected a number"):
        est.fit([a], after_stop_s="60")


def test_fit_and_run_refuse_a_log_that_is_not_log_arrays_by_name(model):
    """A DataFrame given to fit was read without a word and nothing was learned (its
    dp_active is a Series, whose shifted slices align by index and never show the stop), and
    run failed in Python's words ('DataFrame' object has no attribute 'eta'); both now name
    the argument. The same log as LogArrays moves the prior."""
    log = physics_log(model, duration_s=300.0, t_shutdown_s=200.0, seed=4)
    est = EnvironmentEstimator(model)
    learned = est.fit([as_log_arrays(log, model.vessel)], after_stop_s=20.0).thrust_error_mean
    assert np.any(learned != 0.0)
    with pytest.raises(TypeError, match=r"logs_arrays\[1\]: expected LogArrays .*got DataFrame"):
        est.fit([as_log_arrays(log, model.vessel), log], after_stop_s=20.0)
    with pytest.raises(TypeError, match="arrays: expected LogArrays .*got DataFrame"):
        est.run(log)


def test_environment_accel_is_nan_where_a_row_has_no_input(model):
    """As documented: NaN at a row whose wind, velocity or rpm is missing (it was computed with
    the missing value taken as 0: a velocity of 0, no wind), finite at the rows around it."""
    import dataclasses

    from hybridship.residual.environment import environment_accel

    log = physics_log(model, duration_s=200, t_shutdown_s=None, seed=6, current=(0.3, 1.0))
    a = as_log_arrays(log, model.vessel)
    est = EnvironmentEstimator(model, EnvironmentConfig(current_prior_m_s=0.5)).run(a)
    wind, nu, rpm = a.wind.copy(), a.nu.copy(), a.rpm.copy()
    wind[100], nu[120], rpm[140, 0] = np.nan, np.nan, np.nan
    out = environment_accel(model, dataclasses.replace(a, wind=wind, rpm=rpm), est, nu)
    assert np.all(np.isnan(out[[100, 120, 140]]))
    assert np.all(np.isfinite(np.delete(out, [100, 120, 140], axis=0)))
    np.testing.assert_array_equal(np.delete(out, [100, 120, 140], axis=0),
                                  np.delete(environment_accel(model, a, est), [100, 120, 140], axis=0))


def test_the_default_thrust_error_is_one_factor_per_thruster(model):
    """The module notes said theta is by default one factor per degree of freedom; the
    default is one per thruster (as the notes further down and EnvironmentConfig say)."""
    import hybridship.residual.environment as environment

    est = EnvironmentEstimator(model)
    assert est.config.thrust_error_model == "per_thruster"
    assert est.state_names[11:] == tuple(f"thrust_error_{t.name}" for t in model.vessel.thrusters)
    notes = " ".join(environment.__doc__.split())
    assert 'thrust-model error, by default (``thrust_error_model="per_thruster"``) one efficiency factor per ' \
           'thruster' in notes


def test_the_prior_learned_at_stops_is_kept_only_where_it_lowers_both_errors():
    from hybridship.residual.environment import thrust_error_prior_carries_over as keep

    configured = np.array([[2.0, 0.05], [1.0, 0.02], [3.0, 0.10], [1.5, 0.04], [2.5, 0.08], [1.2, 0.03]])
    kept, p = keep(configured, configured * 0.9)
    assert kept and p == [1 / 64, 1 / 64]                              # all six gain in both
    assert not keep(configured, configured)[0]                          # no gain: not kept
    assert keep(configured, configured)[1] == [1.0, 1.0]
    assert not keep(configured, configured * [0.5, 1.1])[0]             # position better, heading worse
    assert not keep(configured, configured * [1.1, 0.5])[0]
    # both means lower, but carried by two failures: the signed-rank test refuses it
    two = configured.copy()
    two[:2] *= 0.5
    two[2:] *= 1.01
    assert np.all(two.mean(axis=0) < configured.mean(axis=0))
    kept, p = keep(configured, two)
    assert not kept and min(p) > 0.05
    # three failures can never pass (p >= 1/8), however large their gains
    assert not keep(configured[:3], configured[:3] * 0.5)[0]
    with pytest.raises(ValueError, match="shape"):
        keep(configured, configured[:2])
    with pytest.raises(ValueError, match="finite"):
        keep(configured, np.where(configured > 2.5, np.nan, configured))


def test_hybrid_fit_checks_the_prior_learned_at_stops_on_left_out_failures(model):
    """fit(dp_only=False) learns the thrust error at the training logs' stops and keeps it only
    if the failures left out of the learning, one at a time, are forecast better in position
    and in heading, in the mean and by a signed-rank test of the per-failure gains
    (training_info["thrust_error_prior"]); the estimator then carries the learned prior, else
    the configured one. With fewer than five failures nothing can be checked and the
    configured prior is restored; with dp_only nothing is learned. Here every log's tunnel
    delivers 80 % of the model's thrust: the prior learned at the stops finds it, and the
    estimator carries whichever prior the left-out check chose. (Which it chooses is close
    here: the tunnel stops with the failure, and the learned prior moves these 60-s drift
    forecasts by millimetres and hundredths of a degree either way.)"""
    from hybridship.predictors.hybrid import THRUST_PRIOR_MIN_FAILURES
    from hybridship.residual.drift_hull import KEEP_P_VALUE

    assert THRUST_PRIOR_MIN_FAILURES == 5
    logs = _tunnel_deficit_logs(model, (32, 33, 34, 35, 36), duration_s=820.0)
    nets = EnsembleConfig(n_members=2, hidden=4, max_epochs=1, patience=1, seed=0)    # nets are off after a failure
    hp = HybridPredictor(model.vessel, ensemble_config=nets, drift_hull=False).fit(logs, dp_only=False)
    info = hp.training_info["thrust_error_prior"]
    assert info["n_failures"] == 5
    pos, head = np.array(info["position_error_m"]), np.array(info["heading_error_deg"])
    p = max(info["position_p_value"], info["heading_p_value"])
    assert info["kept"] == bool(pos[1] < pos[0] and head[1] < head[0] and p < KEEP_P_VALUE)
    assert abs(pos[1] - pos[0]) < 0.05 and abs(head[1] - head[0]) < 0.1
    want = info["learned_mean"] if info["kept"] else [0.0, 0.0, 0.0]
    np.testing.assert_allclose(hp.estimator.thrust_error_mean, want)
    np.testing.assert_allclose(info["learned_mean"], [-0.2, 0.0, 0.0], atol=0.06)

    few = HybridPredictor(model.vessel, ensemble_config=nets, drift_hull=False).fit(logs[:4], dp_only=False)
    assert few.training_info["thrust_error_prior"]["n_failures"] == 4
    assert not few.training_info["thrust_error_prior"]["kept"]
    assert "position_error_m" not in few.training_info["thrust_error_prior"]       # not checked
    np.testing.assert_array_equal(few.estimator.thrust_error_mean, 0.0)
    np.testing.assert_array_equal(few.estimator.thrust_error_std, 0.2)
    assert "thrust_error_prior" not in HybridPredictor(model.vessel, ensemble_config=nets, drift_hull=False).fit(logs).training_info


def test_estimate_is_causal_where_the_wave_motion_sets_the_measurement_noise(model):
    log = physics_log(model, duration_s=900, t_shutdown_s=None, seed=6)
    w = 2 * np.pi / 8.0                                     # 8-s wave yaw, 1 deg amplitude
    t = log.time_s.to_numpy()
    log["heading_deg"] = (log.heading_deg + np.sin(w * t)) % 360.0
    log["r_deg_s"] += w * np.cos(w * t)
    rows = np.array([420, 600])                             # a later row too: the run reads past 420
    est = EnvironmentEstimator(model)
    sd = est._wave_motion_std(as_log_arrays(log, model.vessel), 0, len(log) - 1)
    assert sd[420, 2] > est._measurement_std()[2]          # the adaptive noise is what the filter uses here
    before = est.run(as_log_arrays(log, model.vessel), rows)
    changed = log.copy()
    changed.loc[421:, "heading_deg"] = (changed.loc[421:, "heading_deg"] + 5.0) % 360.0
    after = est.run(as_log_arrays(changed, model.vessel), rows)
    np.testing.assert_array_equal(before.x[0], after.x[0])
    np.testing.assert_array_equal(before.P[0], after.P[0])


def test_the_wave_motion_noise_at_a_row_does_not_depend_on_how_far_past_it_the_run_reads(model):
    """A log logged every second up to row 420 and every 2 s after it (no gap: the log's step
    is 2 s): the estimate at row 420 is the same whether the run stops there or also reports
    the last row. The wave windows' lengths took the median step of the rows read, so reading
    on into the 2-s part changed the measurement noise at row 420 (P by 4e-5)."""
    log = physics_log(model, duration_s=1800, t_shutdown_s=None, seed=6)
    log = log.iloc[np.r_[0:421, 422:len(log):2]].reset_index(drop=True)
    a = as_log_arrays(log, model.vessel)
    assert np.unique(a.segment_id).size == 1
    est = EnvironmentEstimator(model)
    alone = est.run(a, np.array([420]))
    with_later = est.run(a, np.array([420, len(a.time_s) - 1]))
    np.testing.assert_array_equal(alone.x[0], with_later.x[0])
    np.testing.assert_array_equal(alone.P[0], with_later.P[0])


def test_after_stop_errors_wrap_the_heading(model, monkeypatch):
    import hybridship.predictors.hybrid as hybrid

    log = physics_log(model, duration_s=1000, t_shutdown_s=800, seed=14)
    hp = HybridPredictor(model.vessel)
    hp.ensemble = object()                                   # only "fitted" is checked

    def fake(pred, a, *, n_intervals, horizons_s, **kw):
        shape = (n_intervals, len(horizons_s), 3)
        p, t = np.zeros(shape), np.zeros(shape)
        p[..., 2], t[..., 2] = np.pi - 0.01, -np.pi + 0.01
        return p, t, np.ones(shape)

    monkeypatch.setattr(hybrid, "drift_forecasts", fake)
    (e, _, _), = hp.after_stop_errors([log], n_intervals=3, horizon_s=5.0)
    np.testing.assert_allclose(e[..., 2], 0.02, atol=1e-12)


def test_after_stop_errors_and_calibration_refuse_a_horizon_that_is_not_whole_steps(model, monkeypatch):
    """after_stop_errors (and calibrate_after_stop through it) rounded the horizon to the log's
    step themselves: 60.4 s was calibrated up to 60 s, and 0.6 s as one step of 1 s, without a
    word. They now count the steps with the forecast's own horizon_steps, which refuses both
    by name and keeps its tolerance (60.2 s is 60 steps)."""
    import hybridship.predictors.hybrid as hybrid
    from hybridship.predictors.forecast_setup import HorizonError

    log = physics_log(model, duration_s=1000, t_shutdown_s=800, seed=14)
    hp = HybridPredictor(model.vessel)
    hp.ensemble = object()                                   # only "fitted" is checked

    def fake(pred, a, *, n_intervals, horizons_s, **kw):
        shape = (n_intervals, len(horizons_s), 3)
        return np.zeros(shape), np.ones(shape), np.ones(shape)

    monkeypatch.setattr(hybrid, "drift_forecasts", fake)
    for horizon in (60.4, 0.6):
        for call in (hp.after_stop_errors, hp.calibrate_after_stop):
            with pytest.raises(HorizonError, match=rf"^horizon_s: {horizon:g} s is not a whole number of the log's "
                                                   rf"steps \(1 s\)"):
                call([log], n_intervals=3, horizon_s=horizon)
    (_, _, lead), = hp.after_stop_errors([log], n_intervals=3, horizon_s=60.2)
    np.testing.assert_array_equal(lead, np.arange(1, 61))


@pytest.mark.parametrize("settings", [{}, "per_dof", {"load_to_current_at_stop": 0.5, "current_std_at_stop_m_s": 0.1}])
def test_a_blackout_now_is_what_the_filter_does_at_a_logged_stop(model, settings):
    """Drift-off live mode's stop (at_thrust_stop) equals the filter's own handling of a
    logged stop under the same settings: the estimate at the row where the DP stops equals
    that of the same log with the DP still on at that row, passed through at_thrust_stop.
    By default that is no change (the filter carries on); per DOF the yaw environment restarts."""
    from hybridship.residual.environment import PER_DOF

    log = physics_log(model, duration_s=700, t_shutdown_s=600, seed=3, current=(0.2, 1.0))
    k = int(np.flatnonzero(log.dp_active.to_numpy() == 0)[0])
    on = log.copy()
    on.loc[k, "dp_active"] = 1
    est = EnvironmentEstimator(model, EnvironmentConfig(**(PER_DOF if settings == "per_dof" else settings)))
    stopped = est.run(as_log_arrays(log, model.vessel), [k])
    held = est.run(as_log_arrays(on, model.vessel), [k])
    x, P = est.at_thrust_stop(held.x[0], held.P[0])
    np.testing.assert_allclose(x, stopped.x[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(P, stopped.P[0], rtol=0, atol=1e-15)
    if settings == {}:        # no change: the mean and the covariance alike
        np.testing.assert_array_equal(x, held.x[0])
        np.testing.assert_array_equal(P, held.P[0])
    else:
        assert not np.array_equal(x, held.x[0]) or not np.array_equal(P, held.P[0])


def test_a_blackout_now_refuses_a_state_that_is_not_the_filters(model):
    """at_thrust_stop takes a state of the estimator's layout: one of another length (which
    the compiled stop would index past its end) or with NaN is refused by name; the caller's
    arrays are not changed."""
    from hybridship.residual.environment import PER_DOF

    est = EnvironmentEstimator(model, EnvironmentConfig(**PER_DOF))
    n = len(est.state_names)
    x, P = np.full(n, 0.01), 0.01 * np.eye(n)
    x0, P0 = x.copy(), P.copy()
    est.at_thrust_stop(x, P)
    np.testing.assert_array_equal(x, x0)
    np.testing.assert_array_equal(P, P0)
    for bad_x, bad_P in ((x[:5], P[:5, :5]), (x, P[:, :5]), (x[:, None], P)):
        with pytest.raises(ValueError, match=rf"x, P: expected shapes \({n},\) and \({n}, {n}\)"):
            est.at_thrust_stop(bad_x, bad_P)
    with pytest.raises(ValueError, match="x, P: must be finite"):
        est.at_thrust_stop(np.where(np.arange(n) == 10, np.nan, x), P)
    with pytest.raises(TypeError, match="x: expected an array of real numbers"):
        est.at_thrust_stop(["a"] * n, P)


def test_draws_of_an_estimate_without_starts_are_empty(model):
    """run with no rows gives an estimate of none; its draws are (n, 0, 5 + n_theta), where
    numpy's 'need at least one array to stack' stopped them."""
    a = as_log_arrays(physics_log(model, duration_s=200, t_shutdown_s=None, seed=6), model.vessel)
    est = EnvironmentEstimator(model).run(a, np.array([], dtype=int))
    assert est.x.shape == (0, 14)
    for n in (0, 1, 5):
        assert est.sample_environment(n, seed=3).shape == (n, 0, 8)


def test_draws_refuse_a_count_or_seed_that_is_not_a_whole_number():
    """sample_environment's n and seed are whole numbers >= 0, refused by name (a negative n
    failed in numpy's broadcast, 2.5 as a float that 'cannot be interpreted as an integer')."""
    from hybridship.residual.environment import EnvironmentEstimate

    est = EnvironmentEstimate(np.array([5]), np.array([5.0]), np.zeros((1, 14)), np.eye(14)[None] * 1e-4)
    assert est.sample_environment(4, seed=np.int64(2)).shape == (4, 1, 8)
    for kw, name in ((dict(n=-1), "n"), (dict(n=2.5), "n"), (dict(n=True), "n"), (dict(n=3, seed=-1), "seed")):
        with pytest.raises(ValueError, match=f"{name}: expected a whole number >= 0"):
            est.sample_environment(**kw)


def test_with_known_commands_the_thrust_error_follows_each_steps_commands(model):
    """The estimated thrust-model error acts on the thrust that is delivered. With the logged
    commands known it was computed from the start's commands and held over the horizon, so a
    failure inside the horizon kept pushing the ship with an error of thrust that no longer
    existed; it now follows each step's commands: as held while they are the start's,
    nearly 0 once the thrusters have stopped."""
    from hybridship.predictors.forecast_setup import _forecast_setup

    log = as_log_arrays(_tunnel_deficit_logs(model, (37,), t_shutdown_s=400.0, duration_s=480.0)[0], model.vessel)
    hp = HybridPredictor(model.vessel, ensemble_config=EnsembleConfig(n_members=2, max_epochs=3, seed=0)).fit([log])
    known = _forecast_setup(hp.model, hp.residual_config, log, [390.0], 30.0, hp.stop_after_failure, "known",
                            history_s=hp.history_s)
    held = _forecast_setup(hp.model, hp.residual_config, log, [390.0], 30.0, hp.stop_after_failure, "held",
                           history_s=hp.history_s)
    acc_known, acc_held = hp._estimated_start(known, 2)[5], hp._estimated_start(held, 2)[5]
    assert acc_held.shape == (1, 1, 3) and acc_known.shape == (1, known.H, 3)
    assert np.abs(acc_held).max() > 0.0
    stopped = np.all(known.rpm[0, :known.H] == 0.0, axis=-1)
    same = np.all(known.rpm[0, :known.H] == held.rpm[0, 0], axis=-1) & np.all(
        known.az[0, :known.H] == held.az[0, 0], axis=-1)
    assert stopped.any() and same[0]
    # stopped: only the idle propellers' drag is left for the error to act on
    assert np.abs(acc_known[0, stopped]).max() < 0.1 * np.abs(acc_held).max()
    np.testing.assert_allclose(acc_known[0, same], np.broadcast_to(acc_held[0, 0], (same.sum(), 3)), rtol=1e-12)


def test_the_gate_stops_a_jump_and_follows_an_innovation_that_grows_without_one():
    """The outlier gate of the update: a heading innovation beyond the gate that jumped there
    from the sample before is not used, nor are the ones after it while they stay beyond it;
    after ``max_gated`` in a row the heading restarts at the measurement. The same innovation
    reached by steps within the gate (a drifting ship turning faster than the model) is used:
    before, it was gated too and the filter ran open-loop while the turn went on."""
    from hybridship.residual.environment_kernel import update

    x, P = np.zeros(6), np.diag(np.full(6, 1e-4))
    z_ok = np.array([False, False, True, False, False, False])
    r_std, gate = np.full(6, 0.01), np.array([8.0, 8.0, 8.0, np.inf, np.inf, np.inf])
    bound = 8.0 * np.sqrt(2e-4)                                  # 0.113 rad
    z = np.zeros(6)
    z[2] = 1.2 * bound
    grown = np.zeros((2, 6))
    grown[1, 2] = 0.9 * bound                                    # the innovation of the sample before
    x_grown, _ = update(x, P, z, z_ok, r_std, gate, 2, grown)
    assert x_grown[2] > 0.0 and grown[0, 2] == 0                 # used
    jumped = np.zeros((2, 6))
    for k in range(2):                                           # a jump, then one more beyond the gate
        x_jumped, P_jumped = update(x, P, z, z_ok, r_std, gate, 2, jumped)
        np.testing.assert_array_equal(x_jumped, x)               # not used
        assert jumped[0, 2] == k + 1
    x_shift, P_shift = update(x, P, z, z_ok, r_std, gate, 2, jumped)
    assert x_shift[2] == pytest.approx(z[2], abs=1e-15) and P_shift[2, 2] == pytest.approx(1e-4) and jumped[0, 2] == 0
    np.testing.assert_array_equal(x_shift[[0, 1, 3, 4, 5]], 0.0)  # nothing else moved


def test_the_wave_motion_windows_are_spans_of_log_time_across_a_gap(model):
    """20 s missing from a 1-Hz log (rows 600-619): the wave-motion noise at a row depends on
    the 630 s of log time before it only (the 600-s spread of fast parts whose centred 31-s
    mean has ended), across the gap too. Counted in rows, the windows of a row after the gap
    reached 20 s further back than that (at 1000 s the sway velocity's noise was 0.0080 m/s,
    against 0.0046 m/s from the 630 s before it)."""
    log = physics_log(model, duration_s=1800, t_shutdown_s=900, seed=6)
    w = 2 * np.pi / 8.0                                     # an 8-s wave yaw growing with time
    t = log.time_s.to_numpy()
    log["heading_deg"] = (log.heading_deg + (t / 900.0) * np.sin(w * t)) % 360.0
    log["r_deg_s"] += (t / 900.0) * w * np.cos(w * t)
    gap = log.drop(index=range(600, 620)).reset_index(drop=True)
    est = EnvironmentEstimator(model)
    gapped = est._wave_motion_std(as_log_arrays(gap, model.vessel), 0, len(gap) - 1)
    assert np.all(np.isfinite(gapped)) and np.all(gapped[100:, 5] > 0)
    whole = est._wave_motion_std(as_log_arrays(log, model.vessel), 0, len(log) - 1)
    np.testing.assert_array_equal(gapped[:600], whole[:600])        # rows before the gap never see it
    for t_row in (640.0, 1000.0, 1240.0):
        i = int(np.flatnonzero(gap.time_s.to_numpy() == t_row)[0])
        recent = gap[gap.time_s.between(t_row - 630.0, t_row)].reset_index(drop=True)
        alone = est._wave_motion_std(as_log_arrays(recent, model.vessel), 0, len(recent) - 1)
        # the same to rounding (pandas' rolling sums carry the rows before a window)
        np.testing.assert_allclose(gapped[i], alone[-1], rtol=1e-9, atol=1e-15, err_msg=f"row at {t_row:g} s")
