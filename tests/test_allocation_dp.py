"""Thrust allocation and DP control (sea-trial simulator, DP part).

Allocated commands are checked against the physics model's own thruster loads
(``DynamicModel.acceleration(..., return_parts=True)`` parts[:, 1]), and the DP loop is
closed around the nominal Gunnerus model in steady wind and current.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import null_space

from hybridship.frames import ned_to_body, wrap_pi
from hybridship.sim.allocation import (AllocationResult, ThrustAllocator, bollard_thrust_limits, extended_configuration,
                                       thrust_capacity)
from hybridship.sim.dp import DPController, ReferenceModel, pid_gains

# Body-frame load scale: forces in N, the yaw moment divided by a lever of 10 m.
LOAD_SCALE = np.array([1.0, 1.0, 10.0])


def thruster_load(model, nu, result):
    """Load the physics model computes for the allocated commands at velocity ``nu`` (no current)."""
    _, parts, _ = model.acceleration(np.zeros(3), nu, rpm=result.rpm, azimuth_rad=result.azimuth_rad,
                                     return_parts=True)
    return parts[0, 1]


# --------------------------------------------------------------------------- allocation


FEASIBLE = [
    [20e3, 0.0, 0.0],            # pure surge
    [-20e3, 0.0, 0.0],
    [0.0, 15e3, 0.0],            # pure sway
    [0.0, -15e3, 0.0],
    [0.0, 0.0, 100e3],           # pure yaw moment
    [15e3, -10e3, 80e3],         # combinations
    [-30e3, 12e3, -150e3],
]


@pytest.mark.parametrize("nu", [[0.0, 0.0, 0.0], [1.0, 0.3, 0.01], [0.0, 0.0, 0.1]],
                         ids=["zero_speed", "moving", "turning"])     # turning: inflow y r, x r at the thrusters
@pytest.mark.parametrize("tau", FEASIBLE)
def test_feasible_demand_reproduced_by_physics_model(model, tau, nu):
    alloc = ThrustAllocator(model.vessel, dt_s=0.5)
    res = alloc.allocate(tau, nu)
    assert not res.saturated
    tau = np.asarray(tau)
    load = thruster_load(model, nu, res)
    scale = np.linalg.norm(tau / LOAD_SCALE)
    assert np.all(np.abs(load - tau) / LOAD_SCALE <= 0.01 * scale), (load, tau)
    np.testing.assert_allclose(res.tau_achieved, load, rtol=1e-9, atol=1e-6)
    # the reported thrusts are the model's delivered thrusts
    _, _, thrusts = model.acceleration(np.zeros(3), nu, rpm=res.rpm, azimuth_rad=res.azimuth_rad,
                                       return_parts=True)
    np.testing.assert_allclose(res.thrust_N, thrusts[0], rtol=1e-9, atol=1e-6)


@pytest.mark.parametrize("tau", FEASIBLE)
def test_default_weights_minimise_the_sum_of_squared_utilisations(model, tau):
    """Default weights ``1 / F_max^2``: the feasible allocation minimises ``sum (f_i / F_max_i)^2``
    subject to ``T_e f = tau``, so the cost gradient ``f / F_max^2`` has no part along the
    null space of ``T_e`` (the optimality condition of the least-norm problem)."""
    T_e, owner = extended_configuration(model.vessel)
    f_max = bollard_thrust_limits(model.vessel).forward_N[owner]
    res = ThrustAllocator(model.vessel, dt_s=1.0).allocate(tau, np.zeros(3))
    f = []
    for i, t in enumerate(model.vessel.thrusters):      # extended forces from the delivered thrusts
        if t.type == "azimuth":
            f += [res.thrust_N[i] * math.cos(res.azimuth_rad[i]), res.thrust_N[i] * math.sin(res.azimuth_rad[i])]
        else:
            f.append(res.thrust_N[i])
    f = np.array(f)
    np.testing.assert_allclose(T_e @ f / LOAD_SCALE, np.asarray(tau) / LOAD_SCALE, atol=1.0)
    grad = f / f_max**2
    assert np.all(np.abs(null_space(T_e).T @ grad) <= 1e-6 * np.linalg.norm(grad))


@pytest.mark.parametrize("nu", [[0.0, 0.0, 0.0], [1.0, 0.3, 0.01]], ids=["zero_speed", "moving"])
@pytest.mark.parametrize("direction", [[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0.3, -2], [0.7, 0.7, 0]])
def test_infeasible_demand_saturates_gracefully(model, direction, nu):
    alloc = ThrustAllocator(model.vessel, dt_s=0.5)
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    tau = 10e6 * u
    res = alloc.allocate(tau, nu)
    max_rpm = np.array([t.max_rpm for t in model.vessel.thrusters])
    assert res.saturated
    assert np.all(np.isfinite(res.rpm)) and np.all(np.isfinite(res.azimuth_rad))
    assert np.all(np.abs(res.rpm) <= max_rpm + 1e-9)
    assert np.any(np.isclose(np.abs(res.rpm), max_rpm))  # at least one thruster at its limit
    assert 0.0 < res.demand_scale < 0.1
    load = thruster_load(model, nu, res)
    np.testing.assert_allclose(res.tau_achieved, load, rtol=1e-9, atol=1e-6)
    a = load / LOAD_SCALE
    d = tau / LOAD_SCALE
    cos = a @ d / (np.linalg.norm(a) * np.linalg.norm(d))
    # exactly the demanded direction at the bollard; inflow costs a little thrust when moving
    assert cos > (0.999999 if not any(nu) else 0.99), cos


def test_saturated_achieves_the_capacity(model):
    """Pure demands beyond capacity give the capacity (and exactly the demanded direction)."""
    cap = thrust_capacity(model.vessel)
    lim = bollard_thrust_limits(model.vessel)
    az = np.array([t.type == "azimuth" for t in model.vessel.thrusters])
    # surge: every azimuth at full thrust ahead (or turned astern); sway needs the bow tunnel
    assert cap[0] == pytest.approx(lim.forward_N[az].sum(), rel=1e-6)
    assert 0 < cap[1] < cap[0]
    alloc = ThrustAllocator(model.vessel, dt_s=1.0)
    res = alloc.allocate([0.0, 1e7, 0.0], np.zeros(3))
    np.testing.assert_allclose(res.tau_achieved / LOAD_SCALE, [0.0, res.tau_achieved[1], 0.0], atol=1.0)
    assert res.tau_achieved[1] >= cap[1] * (1 - 1e-6)


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["positive", "negative"])
@pytest.mark.parametrize("dof", [0, 1, 2], ids=["surge", "sway", "yaw"])
def test_demands_just_inside_the_capacity_are_met_in_both_directions(model, dof, sign):
    """The capacity is the smaller of the two signs, so 98 % of it is feasible either way: met in
    full (through the null space where the least-norm split overloads a thruster, e.g. the weaker
    astern tunnel), not scaled down."""
    cap = thrust_capacity(model.vessel)
    tau = np.zeros(3)
    tau[dof] = sign * 0.98 * cap[dof]
    res = ThrustAllocator(model.vessel, dt_s=1.0).allocate(tau, np.zeros(3))
    assert res.demand_scale == 1.0
    load = thruster_load(model, np.zeros(3), res)
    assert np.all(np.abs(load - tau) / LOAD_SCALE <= 0.01 * cap[dof] / LOAD_SCALE[dof]), (load, tau)


def test_an_azimuth_turns_round_rather_than_reverse_beyond_its_astern_thrust(model):
    """Reversing is the shorter way to thrust astern, but astern a propeller is weaker: a demand
    beyond the azimuths' astern thrust makes them turn aft (at their slew rate) and then meets it."""
    lim = bollard_thrust_limits(model.vessel)
    az = np.array([t.type == "azimuth" for t in model.vessel.thrusters])
    demand = -0.95 * lim.forward_N[az].sum()
    assert -demand / az.sum() > lim.reverse_N[az].max()
    alloc = ThrustAllocator(model.vessel, dt_s=1.0)
    alloc.allocate([20e3, 0.0, 0.0], np.zeros(3))
    for _ in range(40):                                     # 180 deg at 10 deg/s takes 18 s
        res = alloc.allocate([demand, 0.0, 0.0], np.zeros(3))
    np.testing.assert_allclose(np.cos(res.azimuth_rad[az]), -1.0, atol=1e-6)
    assert np.all(res.rpm[az] > 0)
    np.testing.assert_allclose(thruster_load(model, np.zeros(3), res) / LOAD_SCALE, [demand, 0.0, 0.0],
                               atol=0.01 * abs(demand))


def test_a_first_demand_straight_astern_gives_angles_in_the_documented_range(model):
    """``azimuth_rad`` is in [-pi, pi): a fresh allocator pointed the azimuths at atan2's +pi."""
    res = ThrustAllocator(model.vessel, dt_s=1.0).allocate([-20e3, 0.0, 0.0], np.zeros(3))
    assert np.all((res.azimuth_rad >= -math.pi) & (res.azimuth_rad < math.pi)), res.azimuth_rad
    np.testing.assert_allclose(thruster_load(model, np.zeros(3), res), [-20e3, 0.0, 0.0], atol=200.0)


def test_fixed_thrusters_axes_are_given_in_the_documented_range(model):
    """A fixed propeller whose file gives angle_deg 180 or 270 (or -200) kept pi, 4.71 or -3.49 rad
    as its ``azimuth_rad``, outside the documented [-pi, pi); the same axes are now given there,
    and the load is unchanged."""
    tunnel, port, stbd = model.vessel.thrusters
    fixed = [tunnel.model_copy(update={"name": f"f{i}", "type": "fixed", "angle_deg": a, "x_m": x, "y_m": y})
             for i, (a, x, y) in enumerate([(180.0, -14.0, 0.0), (270.0, 10.0, 1.0), (-200.0, 0.0, 2.0)])]
    vessel = _with_thrusters(model.vessel, [port, stbd] + fixed)
    alloc = ThrustAllocator(vessel, dt_s=1.0)
    for _ in range(2):                          # the first call and a rate-limited one
        res = alloc.allocate([-5e3, 3e3, 20e3], np.zeros(3))
        assert np.all((res.azimuth_rad >= -math.pi) & (res.azimuth_rad < math.pi)), res.azimuth_rad
        np.testing.assert_allclose(res.azimuth_rad[2:], np.radians([-180.0, -90.0, 160.0]), rtol=1e-12)
        np.testing.assert_allclose(res.tau_achieved, [-5e3, 3e3, 20e3], atol=50.0)


def test_bollard_limits_are_what_the_model_delivers_at_full_rpm_ahead_and_astern(model):
    """``forward_N`` / ``reverse_N``: the delivered (after thrust deduction) force of the physics model
    at +max_rpm / -max_rpm at rest, each thruster alone."""
    lim = bollard_thrust_limits(model.vessel)
    max_rpm = np.array([t.max_rpm for t in model.vessel.thrusters])
    for sign, expected in ((1.0, lim.forward_N), (-1.0, -lim.reverse_N)):
        _, _, thrusts = model.acceleration(np.zeros(3), np.zeros(3), rpm=sign * max_rpm,
                                           azimuth_rad=np.zeros(len(max_rpm)), return_parts=True)
        np.testing.assert_allclose(thrusts[0], expected, rtol=1e-9)


def test_a_direction_without_thrust_has_no_capacity():
    """A single fixed propeller (the Esso Osaka model) pushes in surge only: its sway and yaw
    capacity is 0, not the search's bound (the least-squares allocation of a pure sway
    demand is no force at all, which once passed for the demand met in full)."""
    cap = thrust_capacity("esso_osaka_model")
    assert cap[0] > 0 and cap[1] == 0.0 and cap[2] == 0.0


def test_a_demand_the_thrusters_cannot_make_is_met_in_part_without_saturation():
    """The docstrings said the demand is met by the pseudo-inverse and ``saturated`` flags a cut
    demand: on a single propeller (the Esso Osaka model, rank 1) the sway and yaw of a demand
    are left out with ``saturated`` False and ``demand_scale`` 1, as they now say; only
    ``tau_achieved`` shows it."""
    import hybridship.sim.allocation as allocation

    alloc = ThrustAllocator("esso_osaka_model", dt_s=1.0)
    res = alloc.allocate([1.0, 0.5, 0.3], np.zeros(3))         # a model ship: 5 N at most
    assert not res.saturated and res.demand_scale == 1.0
    np.testing.assert_allclose(res.tau_achieved, [1.0, 0.0, 0.0], atol=1e-6)
    for doc in (allocation.__doc__, AllocationResult.__doc__):
        assert "station_keeping_rank` < 3" in " ".join(doc.split())


def test_a_load_the_thrusters_make_only_with_another_has_no_capacity(model):
    """A lone bow tunnel makes sway only with a yaw moment, a lone azimuth off the centre line
    no pure load at all (:func:`check_station_keeping` says so): every pure capacity is 0. The
    tunnel's sway counted as its full 23 kN, and the azimuth was given 446 kN of sway and
    64 kN of surge: the least-squares answer passed for the demand met, the check's tolerance
    being a millionth of the 1e12 N search bound."""
    from hybridship.sim.allocation import thrust_capacity_by_sign

    tunnel, port, _ = model.vessel.thrusters
    for thrusters in ([tunnel], [port]):
        np.testing.assert_array_equal(thrust_capacity_by_sign(_with_thrusters(model.vessel, thrusters)), 0.0)


def test_azimuth_and_rpm_rate_limits(model):
    dt = 0.5
    alloc = ThrustAllocator(model.vessel, dt_s=dt, rpm_rate_limit_rpm_s=20.0)
    az_rate = np.radians([t.max_azimuth_rate_deg_s or np.inf for t in model.vessel.thrusters])
    az = np.array([t.type == "azimuth" for t in model.vessel.thrusters])
    alloc.allocate([30e3, 0.0, 0.0], np.zeros(3))
    prev = alloc.azimuth_rad, alloc.rpm
    seen_limit = False
    # a demand swinging round the compass, including 90 deg jumps
    for k in range(80):
        ang = math.radians(90.0 * (k // 10))
        res = alloc.allocate([30e3 * math.cos(ang), 20e3 * math.sin(ang), 50e3 * (-1) ** k], np.zeros(3))
        step = np.abs(wrap_pi(res.azimuth_rad - prev[0]))
        assert np.all(step[az] <= az_rate[az] * dt + 1e-9)
        assert np.all(np.abs(res.rpm - prev[1]) <= 20.0 * dt + 1e-9)
        seen_limit |= res.rate_limited
        prev = res.azimuth_rad, res.rpm
    assert seen_limit


def test_reverses_thrust_instead_of_turning_round(model):
    alloc = ThrustAllocator(model.vessel, dt_s=1.0)
    first = alloc.allocate([20e3, 0.0, 0.0], np.zeros(3))
    for _ in range(30):
        res = alloc.allocate([-20e3, 0.0, 0.0], np.zeros(3))
    az = np.array([t.type == "azimuth" for t in model.vessel.thrusters])
    np.testing.assert_allclose(res.azimuth_rad[az], first.azimuth_rad[az], atol=1e-12)  # no turn
    assert np.all(res.rpm[az] < 0)
    np.testing.assert_allclose(thruster_load(model, np.zeros(3), res), [-20e3, 0.0, 0.0], atol=200.0)


def test_allocator_validation_names_the_field(model):
    with pytest.raises(ValueError, match="dt_s"):
        ThrustAllocator(model.vessel, dt_s=0.0)
    with pytest.raises(ValueError, match="weights"):
        ThrustAllocator(model.vessel, dt_s=1.0, weights=[1.0, 2.0])
    with pytest.raises(ValueError, match="rpm_rate_limit_rpm_s"):
        ThrustAllocator(model.vessel, dt_s=1.0, rpm_rate_limit_rpm_s=-1.0)
    for bad in ("1", None, True):
        with pytest.raises(ValueError, match="dt_s"):
            ThrustAllocator(model.vessel, dt_s=bad)
        with pytest.raises(ValueError, match="dt_s"):
            DPController(model, dt_s=bad)
    alloc = ThrustAllocator(model.vessel, dt_s=1.0)
    with pytest.raises(ValueError, match="tau_desired_N"):
        alloc.allocate([1.0, 2.0], np.zeros(3))
    with pytest.raises(ValueError, match="nu_r"):
        alloc.allocate(np.zeros(3), [np.nan, 0.0, 0.0])
    with pytest.raises(ValueError, match="azimuth_rad"):
        alloc.reset(azimuth_rad=[0.0])



@pytest.mark.parametrize("setting, field", [
    (dict(reverse_hysteresis_rad=None), "reverse_hysteresis_rad"),
    (dict(reverse_hysteresis_rad="0.1"), "reverse_hysteresis_rad"),
    (dict(rpm_rate_limit_rpm_s="fast"), "rpm_rate_limit_rpm_s"),
    (dict(weights=["1", "1", "1"]), "weights"),
])
def test_allocator_settings_that_are_not_numbers_are_refused_by_name(model, setting, field):
    """They reached numpy: "ufunc 'isfinite' not supported ..." or "could not convert string
    to float", neither naming the setting; so did a demand given as text."""
    with pytest.raises(TypeError, match=field):
        ThrustAllocator(model.vessel, dt_s=1.0, **setting)
    with pytest.raises(TypeError, match="tau_desired_N"):
        ThrustAllocator(model.vessel, dt_s=1.0).allocate(["1", "0", "0"], np.zeros(3))

# --------------------------------------------------------------------------- DP


def test_gains_place_poles_from_mass_matrix(model):
    g = pid_gains(model.mass_matrix, (0.07, 0.07, 0.09), 0.9)
    A = np.linalg.solve(model.mass_matrix, g.Kp)
    np.testing.assert_allclose(A, np.diag([0.07, 0.07, 0.09]) ** 2, atol=1e-12)
    with pytest.raises(ValueError, match="omega_n_rad_s"):
        pid_gains(model.mass_matrix, (0.07, -1.0, 0.09), 0.9)


def test_damping_and_integral_gains_follow_the_pole_placement_rules(model):
    """``K_d = M diag(2 zeta omega_n)`` and ``K_i = K_p diag(omega_n ki_ratio)`` (module docstring)."""
    w, z = np.array([0.07, 0.08, 0.09]), np.array([0.9, 0.8, 0.7])
    g = pid_gains(model.mass_matrix, w, z, ki_ratio=0.1)
    np.testing.assert_allclose(np.linalg.solve(model.mass_matrix, g.Kd), np.diag(2.0 * z * w), atol=1e-12)
    np.testing.assert_allclose(np.linalg.solve(model.mass_matrix, g.Ki), np.diag(0.1 * w**3), atol=1e-12)


def test_unsaturated_reference_follows_the_critically_damped_third_order_step_response():
    """With zeta = 1 the filter is ``(s + w)^3``: a step r gives ``r (1 - e^-wt (1 + wt + (wt)^2 / 2))``."""
    w = 0.05
    ref = ReferenceModel(w, 1.0, (10.0, 10.0, 1.0))       # limits far above what a 1 m step needs
    ref.reset(np.zeros(3))
    target = np.array([1.0, -2.0, 0.3])
    for k in range(1, 1201):
        ref.step(target, 0.5)
        q = w * 0.5 * k
        expected = target * (1.0 - math.exp(-q) * (1.0 + q + 0.5 * q * q))
        assert np.all(np.abs(ref.state.eta_d - expected) <= 0.005 * np.abs(target)), (k, ref.state.eta_d, expected)


def test_tracking_the_reference_exactly_demands_its_acceleration_in_the_body_frame(model):
    """On the reference (no error, PD only) the demand is the force that accelerates the hull
    along it: ``M R(psi)^T eta_d_ddot``; heading east, a northward acceleration is to port."""
    dp = DPController(model, dt_s=1.0, ki_ratio=0.0)
    psi = math.pi / 2
    dp.reset([20.0, 0.0, psi], eta_measured=[0.0, 0.0, psi])
    for _ in range(40):
        ref = dp.reference
        c, s = math.cos(psi), math.sin(psi)
        to_body = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        tau = dp.update(ref.eta_d, to_body @ ref.eta_dot_d)
        np.testing.assert_allclose(tau, model.mass_matrix @ to_body @ ref.eta_ddot_d, atol=1e-6)
    assert tau[1] != 0.0 and abs(ref.eta_ddot_d[0]) > 0.0
    # without the feed-forward, the PD loop on the reference demands nothing
    dp = DPController(model, dt_s=1.0, ki_ratio=0.0, reference_feedforward=False)
    dp.reset([20.0, 0.0, psi], eta_measured=[0.0, 0.0, psi])
    for _ in range(40):
        ref = dp.reference
        np.testing.assert_allclose(dp.update(ref.eta_d, to_body @ ref.eta_dot_d), 0.0, atol=1e-9)
    assert abs(ref.eta_ddot_d[0]) > 0.0


def test_integral_is_kept_in_ned_and_pushes_back_in_the_body_frame(model):
    """Heading east, 1 m east of the set-point (an error straight ahead): the integral grows to the
    east in NED, and the next demand is ``dt K_i`` more astern (opposing the error)."""
    dt = 1.0
    dp = DPController(model, dt_s=dt)
    psi = math.pi / 2
    dp.reset([0.0, 0.0, psi])
    eta = np.array([0.0, 1.0, psi])
    tau1 = dp.update(eta, np.zeros(3))
    np.testing.assert_allclose(dp.integral_ned, [0.0, dt * dp.gains.Ki[0, 0], 0.0], atol=1e-9)
    tau2 = dp.update(eta, np.zeros(3))
    np.testing.assert_allclose(tau2 - tau1, -dt * dp.gains.Ki[:, 0], rtol=1e-9, atol=1e-9)
    assert tau2[0] < tau1[0]


def test_heading_error_across_south_is_the_short_way_round(model):
    """Set-point 179.5 deg, heading -179.5 deg: 1 deg to starboard of it, the same demand as 1 deg
    to starboard of north (not a 359 deg error the other way)."""
    d = math.radians(1.0)
    taus = []
    for sp in (math.pi - d / 2, 0.0):
        dp = DPController(model, dt_s=1.0)
        dp.reset([0.0, 0.0, sp])
        taus.append(dp.update([0.0, 0.0, float(wrap_pi(sp + d))], np.zeros(3)))
    np.testing.assert_allclose(taus[0], taus[1], rtol=1e-9, atol=1e-6)
    assert taus[0][2] < 0.0                                  # turns back to port


def test_integral_windup_is_clamped_at_the_thrust_capacity(model):
    """A large persistent error cannot wind the integral beyond the pure surge/sway/yaw capacity."""
    dp = DPController(model, dt_s=1.0)
    dp.reset([0.0, 0.0, 0.3])
    for _ in range(1500):                                  # the yaw integral needs about 1000 s to wind up
        dp.update([40.0, -30.0, 0.5], np.zeros(3))
    integ_b = ned_to_body(dp.integral_ned, 0.5)
    assert np.all(np.abs(integ_b) <= thrust_capacity(model.vessel) * (1 + 1e-9))
    np.testing.assert_allclose(np.abs(integ_b), dp.integral_limit, rtol=1e-9)   # every axis wound up to its stop


def test_a_fast_reference_model_settles_instead_of_diverging():
    """The Euler substep was 0.1 s whatever the filter: at 12 rad/s (or 6 rad/s with zeta = 2)
    the reference went to NaN. The substep now follows the fastest pole."""
    for omega, zeta in ((12.0, 1.0), (6.0, 2.0)):
        ref = ReferenceModel(omega, zeta, (10.0, 10.0, 1.0))
        for _ in range(20):
            ref.step([1.0, 1.0, 0.1], 1.0)
        np.testing.assert_allclose(ref.state.eta_d, [1.0, 1.0, 0.1], atol=1e-6)


def test_reference_model_no_overshoot_and_speed_limit():
    ref = ReferenceModel(0.05, 1.0, (0.2, 0.2, math.radians(2)))
    ref.reset([0.0, 0.0, math.radians(170)])
    xs, vs = [], []
    for _ in range(2400):
        ref.step([100.0, 0.0, math.radians(-170)], 0.5)  # heading: 20 deg the short way
        xs.append(ref.state.eta_d.copy())
        vs.append(ref.state.eta_dot_d.copy())
    xs, vs = np.array(xs), np.array(vs)
    assert xs[:, 0].max() <= 100.0 + 1e-6 and xs[-1, 0] == pytest.approx(100.0, abs=1e-3)
    assert np.abs(vs[:, 0]).max() <= 0.2 + 1e-12
    assert np.all(vs[:, 2] >= -1e-12)  # turned to starboard through 180 deg
    assert math.degrees(wrap_pi(xs[-1, 2] - math.radians(-170))) == pytest.approx(0.0, abs=1e-3)


@pytest.mark.parametrize("setpoint, dt_s, field", [
    ([math.nan, 0.0, 0.0], 1.0, "setpoint_eta"),
    ([1.0, 0.0], 1.0, "setpoint_eta"),
    ([0.0, 0.0, 0.0], -5.0, "dt_s"),
    ([0.0, 0.0, 0.0], math.nan, "dt_s"),
])
def test_reference_model_step_refuses_a_bad_setpoint_or_step(setpoint, dt_s, field):
    """A NaN set-point made the whole reference NaN, and a negative step pushed it away from
    the set-point (the acceleration 5 s * omega^3 * 10 m the wrong way), without a message."""
    ref = ReferenceModel(0.05, 1.0, (0.5, 0.5, 0.03))
    ref.reset([10.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=field):
        ref.step(setpoint, dt_s)
    assert np.all(ref.state.eta_d == [10.0, 0.0, 0.0]) and not np.any(ref.state.eta_ddot_d)


DT_S = 1.0
WIND = np.array([8.0, math.radians(300.0)])     # from WNW: pushes to starboard and yaws
CURRENT = np.array([0.3, math.radians(60.0)])   # towards ENE
STEP_AT_S = 1200.0
END_S = 1800.0


@pytest.fixture(scope="module")
def dp_run(model):
    """Station keeping at the origin, then a 10 m step north at STEP_AT_S."""
    dp = DPController(model.vessel, dt_s=DT_S)
    alloc = ThrustAllocator(model.vessel, dt_s=DT_S)
    eta, nu = np.zeros(3), np.zeros(3)
    dp.reset(np.zeros(3))
    v_c = np.array([CURRENT[0] * math.cos(CURRENT[1]), CURRENT[0] * math.sin(CURRENT[1]), 0.0])
    log = []
    for k in range(int(END_S / DT_S)):
        if k * DT_S == STEP_AT_S:
            dp.set_setpoint([10.0, 0.0, 0.0])
        tau = dp.update(eta, nu, wind=WIND)
        res = alloc.allocate(tau, nu - ned_to_body(v_c, eta[2]))
        e, v = model.step(eta, nu, dt_s=DT_S, rpm=res.rpm, azimuth_rad=res.azimuth_rad, wind=WIND,
                          current=CURRENT)
        eta, nu = e[0], v[0]
        log.append(np.r_[(k + 1) * DT_S, eta, float(res.saturated)])
    return np.array(log)


def test_dp_station_keeping_in_wind_and_current(dp_run):
    t, n, e, psi = dp_run[:, 0], dp_run[:, 1], dp_run[:, 2], dp_run[:, 3]
    assert np.all(np.isfinite(dp_run))
    # whole record before the step, transients included
    before = t <= STEP_AT_S
    assert np.hypot(n, e)[before].max() < 3.0
    assert np.degrees(np.abs(psi[before])).max() < 3.0
    settled = (t > 300.0) & before
    assert np.hypot(n, e)[settled].max() < 1.0
    assert np.degrees(np.abs(psi[settled])).max() < 1.0


def test_dp_setpoint_change_without_overshoot(dp_run):
    t, n, e, psi = dp_run[:, 0], dp_run[:, 1], dp_run[:, 2], dp_run[:, 3]
    after = t > STEP_AT_S
    # no overshoot (observed 9.9992 m at most): the 20 % once allowed here passed the default
    # reference filter made underdamped (zeta 0.5, 0.83 m past the set-point)
    assert n[after].max() < 10.0 + 0.05
    assert abs(n[-1] - 10.0) < 0.5 and abs(e[-1]) < 0.5
    assert np.degrees(np.abs(psi[after])).max() < 3.0


def test_dp_validation_names_the_field(model):
    with pytest.raises(ValueError, match="dt_s"):
        DPController(model, dt_s=-1.0)
    dp = DPController(model, dt_s=1.0)
    with pytest.raises(ValueError, match="setpoint_eta"):
        dp.reset([0.0, 0.0])
    with pytest.raises(ValueError, match="eta_measured"):
        dp.update([0.0, np.inf, 0.0], np.zeros(3))
    with pytest.raises(ValueError, match="wind"):
        dp.update(np.zeros(3), np.zeros(3), wind=[1.0, 2.0, 3.0])



@pytest.mark.parametrize("setting", [dict(wind_feedforward_gain="1"), dict(max_speed_m_s=None),
                                     dict(max_yaw_rate_rad_s="0.03"), dict(ki_ratio=None)])
def test_dp_settings_that_are_not_numbers_are_refused_by_name(model, setting):
    """Text or None reached numpy's isfinite ("ufunc 'isfinite' not supported for the input types")."""
    (field, _), = setting.items()
    with pytest.raises(TypeError, match=f"{field}: expected a number"):
        DPController(model, dt_s=1.0, **setting)

def test_flags_given_as_text_are_refused_by_name(model):
    """A text "no" is truthy: ``reference_feedforward="no"`` kept the feed-forward on and
    ``warn_unlimited_slew="no"`` the warning."""
    with pytest.raises(TypeError, match="reference_feedforward"):
        DPController(model, dt_s=1.0, reference_feedforward="no")
    with pytest.raises(TypeError, match="warn_unlimited_slew"):
        ThrustAllocator(model.vessel, dt_s=1.0, warn_unlimited_slew="no")


@pytest.mark.parametrize("setting", [dict(omega_n_rad_s="fast"), dict(zeta="0.9"), dict(reference_zeta="1"),
                                     dict(integral_limit=["1e5", "1e5", "1e5"])])
def test_dp_vectors_given_as_text_are_refused_by_name(model, setting):
    """Text reached numpy: "fast" failed in its words ("could not convert string to float"),
    and "0.9" or a set-point of strings was read as the number, where the allocator and the
    scalar settings refuse text by name."""
    (field, _), = setting.items()
    with pytest.raises(TypeError, match=field):
        DPController(model, dt_s=1.0, **setting)
    dp = DPController(model, dt_s=1.0)
    with pytest.raises(TypeError, match="setpoint_eta"):
        dp.reset(["10", "0", "0"])
    with pytest.raises(TypeError, match="wind"):
        dp.update(np.zeros(3), np.zeros(3), wind=["8", "1"])
    with pytest.raises(TypeError, match="mass_matrix"):
        pid_gains([["1", "0", "0"]] * 3, 0.07, 0.9)
    with pytest.raises(TypeError, match="setpoint_eta"):
        ReferenceModel(0.05, 1.0, (0.5, 0.5, 0.03)).step("ab", 1.0)


@pytest.mark.parametrize("gain", [1.0, 0.5, 0.0])
def test_dp_wind_feedforward_opposes_wind(model, gain):
    """The feed-forward is ``gain`` times minus the model's wind load at the measured heading
    and velocity: at 0.5 half of it, at 0 none. At heading 0 and at rest the gain (or the
    measured state) left out passed unnoticed; here the ship heads 60 deg and moves."""
    eta, nu = np.array([0.0, 0.0, math.radians(60.0)]), np.array([0.4, -0.1, 0.01])
    dp = DPController(model, dt_s=1.0, wind_feedforward_gain=gain)
    dp.reset(eta)
    tau_wind = dp.update(eta, nu, wind=WIND)
    dp.reset(eta)
    tau_calm = dp.update(eta, nu)
    _, parts, _ = model.acceleration(eta, nu, wind=WIND, return_parts=True)
    _, parts_at_north, _ = model.acceleration(np.zeros(3), np.zeros(3), wind=WIND, return_parts=True)
    assert np.all(np.abs(parts[0, 2] - parts_at_north[0, 2]) > 0.1 * np.abs(parts[0, 2]))  # the heading matters
    np.testing.assert_allclose(tau_wind - tau_calm, -gain * parts[0, 2], rtol=1e-12, atol=1e-9)


# --------------------------------------------------------------------------- station keeping (DP capability)


def _with_thrusters(vessel, thrusters):
    return vessel.model_copy(update={"thrusters": thrusters})


def test_extended_configuration_of_a_vessel_without_thrusters_has_three_rows(model):
    """Documented shape (3, n): with no thrusters it was (0,), so ``T_e @ f`` failed."""
    T_e, owner = extended_configuration(_with_thrusters(model.vessel, []))
    assert T_e.shape == (3, 0) and owner.shape == (0,)
    np.testing.assert_array_equal(T_e @ np.zeros(0), np.zeros(3))


def test_station_keeping_rank_counts_the_loads_the_thrusters_can_make(model):
    from hybridship.sim.allocation import check_station_keeping, station_keeping_rank

    v = model.vessel
    tunnel, port, stbd = v.thrusters
    stern_tunnel = tunnel.model_copy(update={"name": "stern", "x_m": -10.0})
    assert station_keeping_rank(v) == 3
    assert station_keeping_rank(_with_thrusters(v, [port, stbd])) == 3   # differential surge turns the ship
    assert station_keeping_rank(_with_thrusters(v, [port])) == 2          # one azimuth: sway and yaw coupled
    assert station_keeping_rank(_with_thrusters(v, [tunnel, stern_tunnel])) == 2
    assert station_keeping_rank("esso_osaka_model") == 1                  # one screw, one rudder
    check_station_keeping(v)
    with pytest.raises(ValueError, match=r"'gunnerus' cannot hold station .* no pure surge force .*rank 2 < 3"):
        check_station_keeping(_with_thrusters(v, [tunnel, stern_tunnel]))
    with pytest.raises(ValueError, match=r"'esso_osaka_model' .*propeller: fixed.* no pure sway force or pure yaw "
                                         r"moment .*rank 1 < 3; rudders are not DP actuators"):
        check_station_keeping("esso_osaka_model")
