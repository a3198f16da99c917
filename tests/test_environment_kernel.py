"""The environment estimator's compiled filter (hybridship.residual.environment_kernel) against
answers that follow from its documented equations: the process noise, the heading
innovation through north, the outlier gate's count, the priors' units, a thruster's lever
arm, the Jacobian, the stop's yaw restart and the posterior draws; and two run-level
identities (a restart across a long gap, a bridged gap) that hold exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridship.physics.model import DynamicModel
from hybridship.predictors import as_log_arrays
from hybridship.residual import environment_kernel as kernel
from hybridship.residual.environment import (ENV, EnvironmentConfig, EnvironmentEstimator, external_accel, load_map,
                                            thrust_error_accel)
from hybridship.sim.synthetic import physics_log


def test_process_noise_scales_as_documented():
    """Position noise fixed, velocity std growing with dt, random-walk variance with dt.
    Kills: random walks with dt^2 (E5), velocity noise with dt (E6); both equal at dt = 1 s."""
    q = np.arange(1.0, 15.0)
    Q = kernel.process_noise(4.0, q)
    want = np.concatenate([q[:3] ** 2, (4.0 * q[3:6]) ** 2, 4.0 * q[6:] ** 2])
    np.testing.assert_allclose(np.diag(Q), want, rtol=1e-15)
    assert np.count_nonzero(Q - np.diag(np.diag(Q))) == 0


def test_a_restart_after_a_long_gap_grows_the_environment_by_its_random_walk(model):
    """A 61-s gap (beyond max_bridged_gap_s) restarts the motion states and keeps the
    environment, whose covariance grows by exactly q^2 * gap. Kills: no growth (E11), growth
    with gap^2 (E5)."""
    cfg = EnvironmentConfig(current_walk_m_s=1e-3, load_walk_m_s2=1e-3, load_yaw_walk_rad_s2=1e-5,
                            thrust_error_walk=1e-3)
    log = physics_log(model, duration_s=400, t_shutdown_s=None, seed=9, tau_ext_N=(2000.0, 0.0, 0.0))
    a = as_log_arrays(log.drop(index=range(200, 260)).reset_index(drop=True), model.vessel)
    gap = a.time_s[200] - a.time_s[199]
    assert gap == 61.0 and a.segment_id[200] != a.segment_id[199]
    est = EnvironmentEstimator(model, cfg)
    e = est.run(a, np.array([199, 200]))
    q = est._process_noise_base()[ENV]
    np.testing.assert_allclose(e.P[1][ENV, ENV] - e.P[0][ENV, ENV], np.diag(q**2 * gap), rtol=1e-9, atol=1e-15)
    np.testing.assert_array_equal(e.x[1][ENV], e.x[0][ENV])
    # the motion states restart at the row's measurement [m, m, rad, m/s, m/s, rad/s]
    np.testing.assert_array_equal(e.x[1][:6], np.concatenate([a.eta[200], a.nu[200]]))


def test_a_bridged_gap_is_the_prediction_through_rows_without_measurements(model):
    """Filtering across a 6-s gap (5 rows missing) equals filtering the full-rate log whose
    5 rows have no measurement and the commands held: the gap is predicted in 1-s steps.
    Kills: one step over the whole gap (E10)."""
    log = physics_log(model, duration_s=400, t_shutdown_s=None, seed=9, tau_ext_N=(2000.0, 0.0, 0.0))
    meas = ["north_m", "east_m", "heading_deg", "u_m_s", "v_m_s", "r_deg_s"]
    held = [c for c in log.columns if c not in meas + ["time_s"]]
    holes = list(range(300, 305))
    blind = log.copy()
    blind.loc[holes, held] = log.loc[299, held].to_numpy()
    blind.loc[holes, meas] = np.nan
    dropped = blind.drop(index=holes).reset_index(drop=True)
    cfg = EnvironmentConfig(adaptive_measurement_std=False, use_velocity=False)
    a_blind = as_log_arrays(blind, model.vessel, purpose="forecast")
    a_gap = as_log_arrays(dropped, model.vessel, purpose="forecast")
    assert a_gap.time_s[300] - a_gap.time_s[299] == 6.0 and a_gap.segment_id[300] != a_gap.segment_id[299]
    want = EnvironmentEstimator(model, cfg).run(a_blind, np.array([305]))
    got = EnvironmentEstimator(model, cfg).run(a_gap, np.array([300]))
    np.testing.assert_allclose(got.x, want.x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(got.P, want.P, rtol=1e-9, atol=1e-15)


def _update(x, Pc, z, channel, gate=np.inf, max_gated=10, gate_state=None):
    z_ok = np.zeros(6, dtype=np.bool_)
    z_ok[channel] = True
    gate_state = np.zeros((2, 6)) if gate_state is None else gate_state
    return kernel.update(x, Pc, z, z_ok, np.full(6, 0.1), np.full(6, gate), max_gated, gate_state)


def test_the_heading_innovation_is_wrapped_through_north():
    """Filter at 179.4 deg, measured -179.4 deg: 1.2 deg on, the estimate moves up towards
    180 deg, not 358.8 deg down. Kills: the unwrapped innovation (E7)."""
    x = np.zeros(14)
    x[2] = math.pi - 0.01
    z = np.zeros(6)
    z[2] = -math.pi + 0.01
    x1, _ = _update(x, np.eye(14) * 0.01, z, 2, gate=8.0)
    assert 0.0 < x1[2] - x[2] < 0.02


def test_a_heading_innovation_of_half_a_turn_is_wrapped_to_minus_pi():
    """update's docstring gave the innovation's range as (-pi, pi]; it is [-pi, pi), as
    _wrap_pi makes it: a measurement half a turn off moves the estimate down, by the
    Kalman gain (0.01 / (0.01 + 0.1^2) = 1/2) times -pi."""
    assert "wrapped to [-pi, pi)" in kernel.update.__doc__
    x = np.zeros(14)
    z = np.zeros(6)
    z[2] = math.pi
    x1, _ = _update(x, np.eye(14) * 0.01, z, 2, gate=np.inf)
    assert x1[2] == pytest.approx(-0.5 * math.pi)


@pytest.mark.parametrize("z0, used", [(1.1, True), (1.2, False)])
def test_a_position_update_by_hand_and_the_gate_at_eight_standard_deviations(z0, used):
    """North spread 0.1 m (variance 0.01 m^2), measured with 0.1 m, correlated 0.004 m^2/s with
    the surge speed: gain 0.01 / 0.02 = 1/2, so a 1.1 m innovation moves north 0.55 m, surge
    0.004 / 0.02 * 1.1 = 0.22 m/s, and leaves variances 0.005 m^2 and 0.01 - 0.004^2 / 0.02.
    8 standard deviations of the innovation are 8 sqrt(0.02) = 1.131 m: a first jump of 1.2 m
    is an outlier and leaves the state and its covariance."""
    x = np.zeros(14)
    P = np.eye(14) * 0.01
    P[0, 3] = P[3, 0] = 0.004
    z = np.zeros(6)
    z[0] = z0
    x1, P1 = _update(x, P, z, 0, gate=8.0)
    if not used:
        np.testing.assert_array_equal(x1, x)
        np.testing.assert_array_equal(P1, P)
        return
    np.testing.assert_allclose(x1[[0, 3]], [0.55, 0.22], rtol=1e-12)
    np.testing.assert_array_equal(np.delete(x1, [0, 3]), 0.0)
    np.testing.assert_allclose([P1[0, 0], P1[0, 3], P1[3, 3]], [0.005, 0.002, 0.01 - 0.004**2 / 0.02], rtol=1e-12)


def test_the_gate_lets_the_measurement_in_after_exactly_max_gated_outliers():
    """With max_gated 3, three outliers in a row are gated and the fourth restarts the
    channel at the measurement. Kills: an off-by-one in the count (E14)."""
    x = np.zeros(14)
    P = np.eye(14) * 0.01
    z = np.zeros(6)
    z[0] = 100.0
    gate_state = np.zeros((2, 6))
    for k in range(3):
        x1, _ = _update(x, P, z, 0, gate=8.0, max_gated=3, gate_state=gate_state)
        np.testing.assert_array_equal(x1, x)
        assert gate_state[0, 0] == k + 1
    x1, P1 = _update(x, P, z, 0, gate=8.0, max_gated=3, gate_state=gate_state)
    assert x1[0] == 100.0 and gate_state[0, 0] == 0
    assert P1[0, 0] == pytest.approx(0.1**2, rel=1e-12) and np.all(np.delete(P1[0], 0) == 0.0)    # r^2 alone


def test_prior_standard_deviations_at_the_start_are_in_si_units(model):
    """At the filter's first row the covariance is the prior: heading and yaw-rate spreads in
    radians. Kills: the heading prior in degrees (E16)."""
    c = EnvironmentConfig()
    log = physics_log(model, duration_s=30, t_shutdown_s=None, seed=1)
    P0 = EnvironmentEstimator(model, c).run(as_log_arrays(log, model.vessel), np.array([0])).P[0]
    assert P0[2, 2] == pytest.approx(math.radians(c.heading_std_deg) ** 2, rel=1e-12)
    assert P0[5, 5] == pytest.approx(math.radians(c.yaw_rate_std_deg_s) ** 2, rel=1e-12)
    assert P0[0, 0] == pytest.approx(c.position_std_m ** 2, rel=1e-12)


def test_one_thrusters_efficiency_error_acts_through_its_own_lever_arm(model):
    """The port azimuth (y = -2 m) delivering 80 % of the model's thrust: the acceleration
    it loses is what thrust_error_accel gives for theta_port = -0.2, yaw included. Kills:
    the lever arm's sign (E4); the tunnel, on the centre line, cannot tell."""
    spec = model.vessel.model_dump()
    assert spec["thrusters"][1]["name"] == "port" and spec["thrusters"][1]["y_m"] != 0.0
    t0 = spec["thrusters"][1].get("thrust_deduction", 0.0)
    spec["thrusters"][1]["thrust_deduction"] = 1.0 - 0.8 * (1.0 - t0)
    true = DynamicModel(type(model.vessel).model_validate(spec))
    eta, nu = np.array([[0.0, 0.0, 0.4]]), np.array([[0.2, -0.1, 0.01]])
    rpm, az = np.array([[50.0, 120.0, 80.0]]), np.radians([[0.0, 20.0, -35.0]])
    wind, cur = np.array([[5.0, 1.0]]), np.zeros((1, 2))
    kw = dict(rpm=rpm, azimuth_rad=az, wind=wind)
    lost = true.acceleration(eta, nu, **kw) - model.acceleration(eta, nu, **kw)
    got = thrust_error_accel(model, "per_thruster", eta, nu, rpm, az, wind, cur, np.array([[0.0, -0.2, 0.0]]))
    assert abs(lost[0, 2]) > 1e-5
    np.testing.assert_allclose(got, lost, rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("load_model", ["acceleration", "force"])
def test_predicted_covariance_uses_the_transitions_own_jacobian(model, load_model):
    """predict builds F from the model's structure (load through R(psi)^T, or A R(psi)^T with
    the load a force; thrust error through T); at a heading of 1 rad it must equal central
    differences of the transition itself. Kills: the load's columns through R(psi) instead of
    R(psi)^T (E12); a force's columns without A."""
    P = model.arrays
    A = load_map(model, load_model)
    NO_MAP = np.zeros((0, 3)) if A is None else A
    n = 14
    x = np.array([1.0, 2.0, 1.0, 0.3, -0.1, 0.01, 0.2, -0.1, 0.01, -0.005, 1e-4, 0.05, -0.05, 0.1])
    rpm, az, wind = np.array([60.0, 100.0, 90.0]), np.radians([0.0, 30.0, -20.0]), np.array([6.0, 0.5])
    work = kernel._workspace(P)
    Pc = np.diag(np.linspace(1e-4, 1e-2, n))
    fd = np.array([1e-3, 1e-3, 1e-5, 1e-4, 1e-4, 1e-6, 1e-3, 1e-3, 1e-5, 1e-5, 1e-7, 1e-4, 1e-4, 1e-4])
    Q = np.zeros((n, n))
    _, P1 = kernel.predict(x, Pc, 1.0, rpm, az, wind, Q, fd, P, True, 0.0, NO_MAP, work)

    def step(xx):
        f, T, acc = np.empty(n), np.empty((3, n - 11)), np.empty(3)
        kernel._transition(xx, 1.0, rpm, az, wind, P, True, 0.0, NO_MAP, f, kernel._workspace(P), T, acc)
        return f
    F = np.empty((n, n))
    for j in range(n):
        h = np.zeros(n)
        h[j] = fd[j]
        F[:, j] = (step(x + h) - step(x - h)) / (2 * fd[j])
    want = F @ Pc @ F.T
    np.testing.assert_allclose(P1, want, rtol=1e-2, atol=1e-6 * np.abs(want).max())   # forward vs central differences


def test_at_a_stop_the_total_yaw_environment_keeps_its_configured_fraction(model):
    """at_thrust_stop with the yaw restart (reset_yaw_load_at_stop): the yaw load plus the current's yaw acceleration through the hull keeps
    ``yaw_load_kept_at_stop`` of its value, the yaw load's correlations are cut and its
    variance is prior^2 + (std * total)^2. Kills: the current's part left out (E9b), the
    variance without the part not kept (E9c)."""
    est = EnvironmentEstimator(model, EnvironmentConfig(reset_yaw_load_at_stop=True, yaw_load_kept_at_stop=0.5))
    work = kernel._workspace(model.arrays)
    x = np.zeros(len(est.state_names))
    x[2], x[3:6], x[6:8], x[10] = 0.3, [0.2, 0.1, 0.0], [0.25, 0.3], 2e-4
    cy = kernel.current_yaw_accel(x, model.arrays, work)
    assert abs(cy) > 1e-5
    total = x[10] + cy
    P = np.full((x.size, x.size), 1e-6) + np.eye(x.size) * 1e-4
    x1, P1 = est.at_thrust_stop(x, P)
    assert x1[10] + kernel.current_yaw_accel(x1, model.arrays, work) == pytest.approx(0.5 * total, rel=1e-9)
    assert P1[10, 10] == pytest.approx(est.config.load_yaw_prior_rad_s2 ** 2 + (0.5 * total) ** 2, rel=1e-12)
    assert np.all(np.delete(P1[10], 10) == 0.0)


def test_posterior_draws_are_centred_on_the_estimate(model):
    """sample_environment: the members' mean is the posterior mean whatever n. Kills: the
    centring dropped (E15)."""
    log = physics_log(model, duration_s=120, t_shutdown_s=None, seed=1)
    e = EnvironmentEstimator(model).run(as_log_arrays(log, model.vessel), np.array([60, 119]))
    for n in (3, 7):
        np.testing.assert_allclose(e.sample_environment(n, seed=4).mean(axis=0), e.x[:, ENV], rtol=0, atol=1e-15)


def _ned_force_log(model, force_ned_N, seed=5, duration_s=1000.0):
    """A physics_log's commands with the motion re-simulated under a force fixed in NED (turned
    into the body frame at every step's heading) and a 0.15 m/s current."""
    log = physics_log(model, duration_s=duration_s, t_shutdown_s=None, seed=seed, current=(0.15, 1.0))
    v = model.vessel
    rpm = log[[f"{t.name}_rpm" for t in v.thrusters]].to_numpy()
    az = np.column_stack([np.radians(log[f"{t.name}_azimuth_deg"]) if t.type == "azimuth" else np.zeros(len(log))
                          for t in v.thrusters])
    rud = np.column_stack([np.radians(log[f"{r.name}_azimuth_deg"]) for r in v.rudders]) if v.rudders else None
    eta, nu = np.array([0.0, 0.0, 0.3]), np.zeros(3)
    E, V = [eta], [nu]
    for i in range(len(log) - 1):
        c, s = math.cos(eta[2]), math.sin(eta[2])
        tau = np.array([c * force_ned_N[0] + s * force_ned_N[1], -s * force_ned_N[0] + c * force_ned_N[1], 0.0])
        e, q = model.step(eta, nu, dt_s=1.0, substeps=4, rpm=rpm[i], azimuth_rad=az[i], wind=np.array([6.0, 0.5]),
                          current=np.array([0.15, 1.0]), tau_ext=tau, rudder_rad=None if rud is None else rud[i])
        eta, nu = np.ravel(e), np.ravel(q)
        E.append(eta)
        V.append(nu)
    E, V = np.array(E), np.array(V)
    log["north_m"], log["east_m"], log["heading_deg"] = E[:, 0], E[:, 1], np.degrees(E[:, 2]) % 360.0
    log["u_m_s"], log["v_m_s"], log["r_deg_s"] = V[:, 0], V[:, 1], np.degrees(V[:, 2])
    return log.drop(columns=[c for c in log.columns if c.startswith("truth_")]), E[:, 2]


def test_a_force_fixed_in_ned_is_identified_by_the_force_load_model(model):
    """On a turning ship (about 80 deg of heading) pushed by a force fixed in NED, the load as a
    force (load_model "force") finds the force within 3 % and its body acceleration within
    3e-4 m/s^2; the load as an acceleration cannot follow the heading's effect through the
    anisotropic mass and misses by several times as much. Kills: the force's map left out of
    the process model or of its Jacobian."""
    F = np.array([12e3, -8e3])
    log, psi = _ned_force_log(model, F)
    assert np.ptp(psi) > np.radians(60)
    a = as_log_arrays(log, model.vessel)
    mi = model.arrays.m_inv
    m_ref = 2.0 / (mi[0, 0] + mi[1, 1])
    c, s = np.cos(psi), np.sin(psi)
    true_acc = np.column_stack([c * F[0] + s * F[1], -s * F[0] + c * F[1], np.zeros_like(psi)]) @ mi.T
    errs = {}
    for lm in ("acceleration", "force"):
        e = EnvironmentEstimator(model, EnvironmentConfig(load_model=lm)).run(a)
        late = e.time_s >= 600
        acc = external_accel(e.x[:, 2], e.x[:, 8:11], 0.0, 0.0, e.load_map)
        errs[lm] = np.sqrt(np.mean((acc - true_acc[e.rows])[late, :2] ** 2))
        if lm == "force":
            np.testing.assert_allclose(e.x[late, 8:10].mean(axis=0) * m_ref, F, rtol=0.03)
    assert errs["force"] < 3e-4 and errs["acceleration"] > 3 * errs["force"]


def test_the_force_load_model_keeps_the_acceleration_default_and_refuses_the_stop_options(model):
    assert EnvironmentConfig().load_model == "acceleration" and load_map(model, "acceleration") is None
    A = load_map(model, "force")
    mi = model.arrays.m_inv
    assert 0.5 * (A[0, 0] + A[1, 1]) == pytest.approx(1.0) and A[2, 2] == pytest.approx(1.0)
    assert A[0, 0] / A[1, 1] == pytest.approx(mi[0, 0] / mi[1, 1]) and A[2, 1] != 0.0
    for kw in (dict(reset_yaw_load_at_stop=True), dict(load_to_current_at_stop=0.5), dict(current_std_at_stop_m_s=0.1)):
        with pytest.raises(ValueError, match="load_model='force'"):
            EnvironmentConfig(load_model="force", **kw)


def test_the_forecasts_and_drift_off_turn_a_force_load_as_the_filter_does(model):
    """The held load of a forecast after a failure (hybrid's corrected step) and of drift-off
    live mode (a NED acceleration at the stop's heading) are the filter's body acceleration
    of the force. Kills: a forecast that holds the force's state as an acceleration."""
    from hybridship.driftoff.live import _force_as_ned_accel
    from hybridship.predictors.hybrid import _corrected_step
    A = load_map(model, "force")
    rng = np.random.default_rng(1)
    b = rng.normal(0.0, 0.02, (1, 4, 3))
    psi = np.array([0.0, 1.0, -2.0, 3.0])
    eta_1, nu_1 = np.column_stack([np.zeros((4, 2)), psi]), np.zeros((4, 3))
    d = np.zeros((1, 4, 3))
    _, nu, _ = _corrected_step(eta_1, nu_1, np.zeros((1, 4, 3)), b, 1.0, d.copy(), d.copy(), None, A)
    np.testing.assert_allclose(nu, external_accel(psi, b[0], 0.0, 0.0, A), rtol=1e-12)
    ned = _force_as_ned_accel(b[0, 1], 1.0, A)
    body = external_accel(np.array(1.0), b[0, 1], 0.0, 0.0, A)
    c, s = math.cos(1.0), math.sin(1.0)
    np.testing.assert_allclose([c * ned[0] + s * ned[1], -s * ned[0] + c * ned[1], ned[2]], body, rtol=1e-12)


def test_the_residual_package_docstring_names_every_physics_module_it_uses():
    """The package docstring said it uses the physics only through DynamicModel, while the
    estimator's filter, multi-step training and the drift hull import physics kernels
    directly; each physics module a residual module imports (other than physics.model) is
    now named there, beside the module that imports it."""
    import ast
    from pathlib import Path

    import hybridship.residual as residual

    doc = " ".join(residual.__doc__.split())
    for path in Path(residual.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 2 and (node.module or "").startswith("physics."):
                if node.module != "physics.model":
                    assert f"``{node.module}``" in doc and f":mod:`.{path.stem}`" in doc, (path.name, node.module)
