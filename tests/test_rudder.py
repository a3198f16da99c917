"""Rudder (MMG standard method) and main propeller: physics, vessel file and model interface."""

from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest

from hybridship.physics.model import DynamicModel
from hybridship.physics.propeller import load_wageningen, thrust_torque
from hybridship.physics.rudder import rudder_forces, rudder_inflow_scalar
from hybridship.vessel import VesselFileError, packaged_vessel_text, vessel_from_dict

RPM8 = 8.0 * 60.0  # 8 rev/s, the turning-test propeller speed of the Esso Osaka model


def esso_dict():
    return tomllib.loads(packaged_vessel_text("esso_osaka_model"))


@pytest.fixture(scope="module")
def esso():
    return DynamicModel("esso_osaka_model")


@pytest.fixture(scope="module")
def esso_symmetric():
    """The Esso model with equal flow straightening on both sides (a port/starboard symmetric rudder)."""
    d = esso_dict()
    d["rudders"][0]["flow_straightening_pos"] = d["rudders"][0]["flow_straightening_neg"]
    return DynamicModel(vessel_from_dict(d, "symmetric.toml"))


# ----------------------------------------------------------------------------- forces


def test_positive_rudder_angle_turns_to_starboard(esso):
    F = rudder_forces(esso, [0.3, 0.0, 0.0], [math.radians(20)], [2.0])[0, 0]
    assert F[1] < 0.0 < F[2]          # stern pushed to port, bow turns to starboard
    assert F[0] < 0.0                 # rudder drag
    F_neg = rudder_forces(esso, [0.3, 0.0, 0.0], [math.radians(-20)], [2.0])[0, 0]
    assert F_neg[1] > 0.0 > F_neg[2]
    # and the integrated ship: steady yaw rate has the sign of delta
    for deg in (20.0, -35.0):
        res = esso.rollout([0, 0, 0], [0.3, 0, 0], 1500, dt_s=0.1, rpm=[RPM8, 0.0],
                           rudder_rad=[math.radians(deg)])
        assert np.sign(res.nu[0, -1, 2]) == np.sign(deg)
        assert np.sign(res.eta[0, -1, 2]) == np.sign(deg)


@pytest.mark.parametrize("thrust", [0.0, 0.5, 5.0, -2.0])
@pytest.mark.parametrize("u", [0.0, 0.3, -0.1])
def test_zero_angle_and_symmetric_inflow_give_no_lateral_force(esso, thrust, u):
    F = rudder_forces(esso, [u, 0.0, 0.0], [0.0], [thrust])[0, 0]
    assert F == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)


def test_slipstream_increases_force_with_propeller_loading(esso):
    thrusts = np.linspace(0.0, 6.0, 13)
    delta = math.radians(15)
    for u in (0.0, 0.1, 0.4):
        F = rudder_forces(esso, np.tile([u, 0.0, 0.0], (13, 1)), np.full((13, 1), delta), thrusts[:, None])[:, 0]
        assert np.all(np.diff(F[:, 2]) > 0.0), u       # yaw moment grows with thrust
        assert np.all(np.diff(-F[:, 1]) > 0.0), u
    # at rest only the slipstream makes a force; without thrust there is none
    assert rudder_forces(esso, [0.0, 0.0, 0.0], [delta], [0.0])[0, 0] == pytest.approx([0, 0, 0], abs=1e-12)
    assert abs(rudder_forces(esso, [0.0, 0.0, 0.0], [delta], [3.0])[0, 0, 2]) > 1e-3
    # a reversing propeller's race runs forward: the rudder sees the plain wake
    np.testing.assert_allclose(rudder_forces(esso, [0.2, 0, 0], [delta], [-3.0]),
                               rudder_forces(esso, [0.2, 0, 0], [delta], [0.0]), rtol=1e-12)


def test_mirror_symmetry(esso, esso_symmetric):
    rng = np.random.default_rng(0)
    nu = np.column_stack([rng.uniform(-0.1, 0.5, 50), rng.uniform(-0.1, 0.1, 50), rng.uniform(-0.1, 0.1, 50)])
    delta = rng.uniform(-0.6, 0.6, (50, 1))
    T = rng.uniform(-1.0, 5.0, (50, 1))
    mirror = nu * [1, -1, -1]
    F = rudder_forces(esso_symmetric, nu, delta, T)
    Fm = rudder_forces(esso_symmetric, mirror, -delta, T)
    np.testing.assert_allclose(Fm, F * [1, -1, -1], atol=1e-12)
    # the KVLCC2 flow straightening differs by side, so only the straight-inflow case is symmetric
    straight = nu * [1, 0, 0]
    np.testing.assert_allclose(rudder_forces(esso, straight, -delta, T), rudder_forces(esso, straight, delta, T)
                               * [1, -1, -1], atol=1e-12)


def test_reproduces_the_mmg_standard_formulae_ahead(esso):
    """Independent transcription of Yasukawa & Yoshimura (2015) eqs. for u > 0, n > 0."""
    v = esso.vessel
    rd, pr = v.rudders[0], v.thrusters[0]
    L, rho = v.particulars.L_pp_m, v.particulars.rho_water_kg_m3
    u, vm, r, delta, n = 0.35, 0.02, 0.03, math.radians(12), 9.0
    w = pr.wake_fraction
    J = u * (1 - w) / (n * pr.diameter_m)
    T = 1.7  # open-water thrust [N]
    KT = T / (rho * n**2 * pr.diameter_m**4)
    eta = pr.diameter_m / rd.span_m
    kappa, eps = rd.slipstream_factor, rd.wake_ratio
    uR = eps * u * (1 - w) * math.sqrt(eta * (1 + kappa * (math.sqrt(1 + 8 * KT / (math.pi * J**2)) - 1))**2
                                       + (1 - eta))
    U = math.hypot(u, vm)
    beta = math.atan(-vm / u)
    beta_R = beta - (rd.l_R_m / L) * (r * L / U)
    gamma = rd.flow_straightening_neg if beta_R < 0 else rd.flow_straightening_pos
    vR = U * gamma * beta_R
    FN = 0.5 * rho * rd.area_m2 * (uR**2 + vR**2) * rd.f_alpha * math.sin(delta - math.atan(vR / uR))
    XR = -(1 - rd.steering_resistance_deduction) * FN * math.sin(delta)
    YR = -(1 + rd.hull_force_factor) * FN * math.cos(delta)
    NR = -(rd.x_m + rd.hull_force_factor * rd.x_H_m) * FN * math.cos(delta)
    F = rudder_forces(esso, [u, vm, r], [delta], [T])[0, 0]
    # the kernel uses v_R = -gamma (v + l_R r), the small-angle form of U gamma beta_R
    np.testing.assert_allclose(F, [XR, YR, NR], rtol=2e-3)


def test_rudder_forces_refuses_bad_shapes_and_non_finite_inputs_naming_them(esso):
    """numpy's broadcasting and indexing messages, and a silent NaN load, became named errors."""
    for args, match in ((([0.3, 0, 0], [0.1, 0.2]), r"^delta_rad: expected shape \(1,\) or \(1, 1\), got \(2,\)"),
                        (([0.3, 0], [0.1]), r"^nu_r: expected shape \(3,\) or \(B, 3\), got \(2,\)"),
                        (([np.nan, 0, 0], [0.1]), "^nu_r: contains NaN"),
                        (([0.3, 0, 0], [0.1], [np.inf]), "^thrust_open_N: contains NaN")):
        with pytest.raises(ValueError, match=match):
            rudder_forces(esso, *args)
    with pytest.raises(TypeError, match="^delta_rad: expected an array of real numbers"):
        rudder_forces(esso, [0.3, 0, 0], "ten")
    # one angle for every rudder and a batch of states: as before
    np.testing.assert_array_equal(rudder_forces(esso, [[0.3, 0, 0], [0.2, 0, 0]], 0.2)[:, 0],
                                  rudder_forces(esso, [[0.3, 0, 0], [0.2, 0, 0]], [[0.2], [0.2]])[:, 0])


def test_inflow_is_continuous_through_zero_and_astern_reverses_the_rudder(esso):
    args = (0.08, 1000.0, 1.09, 0.5, 0.66)
    for T in (0.0, 2.0):
        lo = rudder_inflow_scalar(-1e-9, T, *args)
        hi = rudder_inflow_scalar(1e-9, T, *args)
        assert abs(hi - lo) < 1e-6
    # going astern without thrust, the same rudder angle turns the other way
    ahead = rudder_forces(esso, [0.2, 0, 0], [0.3], [0.0])[0, 0]
    astern = rudder_forces(esso, [-0.2, 0, 0], [0.3], [0.0])[0, 0]
    assert np.sign(ahead[2]) == -np.sign(astern[2]) != 0


@pytest.mark.parametrize("u_p, thrust", [(-0.2, 0.0), (-0.2, -3.0), (0.0, 2.0), (-0.2, 2.0), (-0.6, 2.0),
                                         (0.3, 2.0)])
def test_inflow_at_the_bollard_and_astern_follows_the_documented_extension(u_p, thrust):
    """The module's extension of the MMG inflow beyond u > 0, transcribed here: ``c_T = 8 T /
    (pi rho D^2)`` (0 for a reversing propeller), ``u_jet = u_P + kappa sqrt(c_T)`` astern,
    ``X = eta u_jet |u_jet| + (1 - eta) u_P |u_P|`` and ``u_R = epsilon sgn(X) sqrt|X|``.
    The sign tests astern (and continuity at 0) passed with the plain wake's part of X
    squared without its sign, or the ahead jet formula used astern."""
    D, rho, eps, kappa, eta = 0.08, 1000.0, 1.09, 0.5, 0.66
    c_T = 8.0 * max(thrust, 0.0) / (math.pi * rho * D**2)
    if u_p >= 0.0:
        u_jet = (1 - kappa) * u_p + kappa * math.sqrt(u_p**2 + c_T)
    else:
        u_jet = u_p + kappa * math.sqrt(c_T)
    X = eta * u_jet * abs(u_jet) + (1 - eta) * u_p * abs(u_p)
    expected = eps * math.copysign(math.sqrt(abs(X)), X)
    assert rudder_inflow_scalar(u_p, thrust, D, rho, eps, kappa, eta) == pytest.approx(expected, rel=1e-12)
    if thrust <= 0.0:                       # no jet: the rudder sees the plain wake, either way
        assert expected == pytest.approx(eps * u_p, rel=1e-12)


def test_lateral_inflow_loads_an_unmoved_rudder_as_damping(esso):
    # the ship sliding to starboard: the rudder at 0 deg pushes the stern back to port
    F = rudder_forces(esso, [0.3, 0.05, 0.0], [0.0], [1.0])[0, 0]
    assert F[1] < 0.0
    # yawing to starboard: the stern moves to port, the rudder resists (moment < 0)
    F = rudder_forces(esso, [0.3, 0.0, 0.02], [0.0], [1.0])[0, 0]
    assert F[2] < 0.0


def test_the_rudder_sees_the_open_water_thrust_of_its_propeller(esso):
    """The slipstream (MMG, Yasukawa & Yoshimura 2015, eqs. 39-41) is set by the propeller's
    open-water thrust ``T = delivered / (1 - t_P)``, the thrust deduction being a hull force: inside
    the model the rudder load (actuator load less the propeller's ``[T_d, 0, -y_P T_d]``) equals
    :func:`rudder_forces` with that thrust."""
    nu, delta = [0.4, 0.02, 0.03], math.radians(15)
    _, parts, thrusts = esso.acceleration([0, 0, 0], nu, rpm=[RPM8], rudder_rad=[delta], return_parts=True)
    prop = esso_dict()["thrusters"][0]
    T_d = thrusts[0, 0]
    rudder = parts[0, 1] - [T_d, 0.0, -prop["y_m"] * T_d]
    expected = rudder_forces(esso, nu, [delta], [T_d / (1 - prop["thrust_deduction"])])[0, 0]
    np.testing.assert_allclose(rudder, expected, rtol=1e-9, atol=1e-9 * T_d)


def test_off_centre_propeller_and_rudder_follow_the_mmg_formulae_while_turning():
    """An off-centre screw and rudder (y = 0.12 m) on a turning ship, against the module's MMG
    formulae (Yasukawa & Yoshimura 2015) transcribed here: propeller inflow ``u_P = (1 - w)(u - y_P r)``
    (the water velocity at the propeller), ``F_N = rho/2 A_R f_alpha U_R^2 sin(delta - atan2(v_R, u_R))``
    and the yaw moment ``N_R = -(x_R + a_H x_H) F_N cos(delta) - y_R X_R`` of the forces at (x_R, y_R)."""
    d = esso_dict()
    d["thrusters"][0]["y_m"] = 0.12
    d["rudders"][0]["y_m"] = 0.12
    m = DynamicModel(vessel_from_dict(d, "off_centre.toml"))
    u, v, r, delta = 0.4, 0.01, 0.05, math.radians(20)
    _, parts, thrusts = m.acceleration([0, 0, 0], [u, v, r], rpm=[RPM8], rudder_rad=[delta], return_parts=True)
    pr, rd, rho = m.vessel.thrusters[0], m.vessel.rudders[0], d["particulars"]["rho_water_kg_m3"]
    u_P = (1 - pr.wake_fraction) * (u - pr.y_m * r)
    T = thrust_torque(RPM8 / 60, u_P, pr.diameter_m, load_wageningen(pr.propeller_series, pr.pitch_ratio), rho)[0]
    T_d = (1 - pr.thrust_deduction) * T                               # open-water and delivered thrust
    assert thrusts[0, 0] == pytest.approx(T_d, rel=1e-9)
    c_T = 8 * T / (math.pi * rho * pr.diameter_m**2)
    kappa, eta = rd.slipstream_factor, min(pr.diameter_m / rd.span_m, 1.0)
    u_jet = (1 - kappa) * u_P + kappa * math.sqrt(u_P**2 + c_T)
    u_R = rd.wake_ratio * math.sqrt(eta * u_jet**2 + (1 - eta) * u_P**2)
    lat = v + rd.l_R_m * r
    v_R = -(rd.flow_straightening_neg if lat > 0 else rd.flow_straightening_pos) * lat
    F_N = 0.5 * rho * rd.area_m2 * rd.f_alpha * (u_R**2 + v_R**2) * math.sin(delta - math.atan2(v_R, u_R))
    X_R = -(1 - rd.steering_resistance_deduction) * F_N * math.sin(delta)
    Y_R = -(1 + rd.hull_force_factor) * F_N * math.cos(delta)
    N_R = -(rd.x_m + rd.hull_force_factor * rd.x_H_m) * F_N * math.cos(delta) - rd.y_m * X_R
    expected = np.array([T_d + X_R, Y_R, -pr.y_m * T_d + N_R])      # propeller at 0 deg, then the rudder
    np.testing.assert_allclose(parts[0, 1], expected, rtol=1e-9)


# ----------------------------------------------------------------------------- propeller


def test_main_propeller_reverses_and_stops_the_ship(esso):
    # ahead at 0.3 m/s, propeller reversed to -10 rev/s: the ship stops and goes astern
    res = esso.rollout([0, 0, 0], [0.3, 0, 0], 1000, dt_s=0.1, rpm=[-600.0, 0.0])
    u = res.nu[0, :, 0]
    assert u[0] > 0.0 > u[-1]
    _, parts, thrust = esso.acceleration([0, 0, 0], [0.3, 0, 0], rpm=[-600.0, 0.0], return_parts=True)
    assert thrust[0, 0] < 0.0 and parts[0, 1, 0] < 0.0
    # steady ahead speed grows with the shaft speed
    speeds = [esso.rollout([0, 0, 0], [0.2, 0, 0], 2000, dt_s=0.1, rpm=[n * 60, 0.0]).nu[0, -1, 0]
              for n in (6.0, 10.0, 14.0)]
    assert 0.0 < speeds[0] < speeds[1] < speeds[2]


# ----------------------------------------------------------------------------- interface


def test_rudder_keyword_equals_angle_channel_and_per_step_equals_held(esso):
    eta0 = np.array([[0, 0, 0.1], [1, 2, -0.5]])
    nu0 = np.array([[0.3, 0.01, 0.0], [0.1, -0.02, 0.01]])
    delta = np.array([[0.2], [-0.4]])
    rpm = np.array([[RPM8, 0.0], [-300.0, 0.0]])
    a = esso.rollout(eta0, nu0, 50, dt_s=0.1, rpm=rpm, azimuth_rad=np.column_stack([np.zeros(2), delta]))
    b = esso.rollout(eta0, nu0, 50, dt_s=0.1, rpm=rpm[:, :1], rudder_rad=delta)
    c = esso.rollout(eta0, nu0, 50, dt_s=0.1, rpm=np.repeat(rpm[:, None], 50, 1),
                     rudder_rad=np.repeat(delta[:, None], 50, 1))
    np.testing.assert_allclose(a.eta, b.eta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.eta, c.eta, rtol=0, atol=1e-12)
    single = esso.rollout(eta0[1], nu0[1], 50, dt_s=0.1, rpm=rpm[1], rudder_rad=delta[1])
    np.testing.assert_allclose(single.eta[0], a.eta[1], rtol=0, atol=1e-12)
    # per-step rudder commands do act: a rudder put over halfway changes the end state
    steps = np.repeat(delta[:, None], 50, 1).copy()
    steps[:, 25:] = 0.0
    d = esso.rollout(eta0, nu0, 50, dt_s=0.1, rpm=rpm, rudder_rad=steps)
    assert np.abs(d.eta[:, -1] - a.eta[:, -1]).max() > 1e-4
    # the model's one-step acceleration sees the rudder too
    acc0 = esso.acceleration(eta0, nu0, rpm=rpm, rudder_rad=[[0.0], [0.0]])
    acc1 = esso.acceleration(eta0, nu0, rpm=rpm, rudder_rad=delta)
    assert np.all(np.abs(acc1[:, 2] - acc0[:, 2]) > 0.0)


def test_channels_and_errors(esso):
    v = esso.vessel
    assert v.channel_names == ["propeller", "rudder"] and v.rotatable == [False, True]
    assert esso.n_actuators == esso.n_channels == 2 and esso.n_rudders == 1
    assert esso.n_thrusters == 1                  # thrusters and propellers only, as Fossen and MMG count them
    with pytest.raises(ValueError, match="rudder_rad"):
        esso.acceleration([0, 0, 0], [0.3, 0, 0], rpm=[RPM8], rudder_rad=[0.1, 0.2])
    with pytest.raises(ValueError, match="rudder_rad"):
        DynamicModel("gunnerus").acceleration([0, 0, 0], [0, 0, 0], rudder_rad=[0.1])
    with pytest.raises(ValueError, match="rpm"):
        esso.acceleration([0, 0, 0], [0.3, 0, 0], rpm=[RPM8, 0.0, 0.0])
    # a rudder angle in degrees among azimuth_rad's channels: named as the argument given, not rudder_rad
    with pytest.raises(ValueError, match=r"^azimuth_rad\[\.\.\., 1:\] \(the rudder angles\): 20 rad is beyond 90 deg"):
        esso.rollout([0, 0, 0], [0.3, 0, 0], 5, rpm=[RPM8, 0.0], azimuth_rad=[0.0, 20.0])
    with pytest.raises(ValueError, match=r"^rudder_rad: 20 rad is beyond 90 deg"):
        esso.rollout([0, 0, 0], [0.3, 0, 0], 5, rpm=[RPM8], rudder_rad=[20.0])


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["rudders"][0].__setitem__("propeller", "nope"), r"rudders\[0\].propeller"),
    (lambda d: d["rudders"][0].__setitem__("area_m2", -0.01), r"rudders\[0\].area_m2"),
    (lambda d: d["rudders"][0].__setitem__("name", "propeller"), "rudders: duplicate"),
    (lambda d: d["thrusters"][0].__setitem__("angle_deg", 90.0), r"rudders\[0\].propeller"),
    (lambda d: d["damping"]["nonlinear"].pop("mmg"), "lift 'mmg'"),
    # x measured aft as positive (a sign slip): a rudder ahead of its propeller was accepted
    (lambda d: d["rudders"][0].__setitem__("x_m", 1.5), r"rudders\[0\].x_m: 1.5 m is not aft of its propeller "
                                                       r"'propeller' \(x_m = -1.44 m\)"),
    # without a propeller eta = 0 and the slipstream factor was ignored
    (lambda d: d["rudders"][0].update(propeller=None, slipstream_factor=0.8),
     r"rudders\[0\]: slipstream_factor: 0.8 given for a rudder without a propeller"),
])
def test_invalid_rudder_files_name_the_field(edit, field):
    d = copy.deepcopy(esso_dict())
    edit(d)
    with pytest.raises(VesselFileError, match=field):
        vessel_from_dict(d, "bad.toml")


def test_rudder_without_propeller_and_mixed_actuators():
    """A vessel with thrusters, a propeller and two rudders (one without propeller)."""
    d = copy.deepcopy(esso_dict())
    d["thrusters"].append({"name": "bow", "type": "tunnel", "x_m": 1.2, "diameter_m": 0.05, "max_rpm": 3000.0})
    d["rudders"].append(dict(d["rudders"][0], name="aux", propeller=None, y_m=0.1))
    d["rudders"][1].pop("propeller")
    m = DynamicModel(vessel_from_dict(d, "mixed.toml"))
    assert m.vessel.channel_names == ["propeller", "bow", "rudder", "aux"]
    assert m.vessel.rotatable == [False, False, True, True]
    acc = m.acceleration([0, 0, 0], [0.3, 0, 0], rpm=[RPM8, 600.0, 0, 0], azimuth_rad=[0, 0, 0.2, 0.2])
    acc_off = m.acceleration([0, 0, 0], [0.3, 0, 0], rpm=[RPM8, 600.0, 0, 0], azimuth_rad=[0, 0, 0.0, 0.0])
    assert acc[0, 2] > acc_off[0, 2]
    F = rudder_forces(m, [0.3, 0, 0], [0.2, 0.2], [3.0, 3.0])[0]
    assert abs(F[1, 2]) < abs(F[0, 2])  # no slipstream on the auxiliary rudder


def test_a_vessel_with_a_rudder_and_no_thrusters_is_integrated():
    """A valid vessel file with one rudder in the plain wake and no thruster: the command
    checks read the rudder angle and no shaft speeds (they failed in numpy's reshape)."""
    d = copy.deepcopy(esso_dict())
    d["thrusters"] = []
    d["rudders"][0].pop("propeller")
    m = DynamicModel(vessel_from_dict(d, "rudder_only.toml"))
    assert (m.n_thrusters, m.n_rudders) == (0, 1)
    acc = m.acceleration([0, 0, 0], [0.5, 0, 0], rudder_rad=[0.2])
    assert acc[0, 2] > m.acceleration([0, 0, 0], [0.5, 0, 0], rudder_rad=[0.0])[0, 2] and np.all(np.isfinite(acc))
    res = m.rollout([0, 0, 0], [0.5, 0, 0], 5, azimuth_rad=[0.2])
    np.testing.assert_allclose(res.nu[0, 1], m.step([0, 0, 0], [0.5, 0, 0], rudder_rad=[0.2])[1][0], rtol=1e-12)
    with pytest.raises(ValueError, match="rudder_rad: .* beyond 90 deg"):
        m.acceleration([0, 0, 0], [0.5, 0, 0], rudder_rad=[2.0])


def test_a_rudder_without_propeller_follows_the_mmg_formulae_in_its_own_inflow():
    """The auxiliary rudder of the mixed vessel (no propeller, y_R = 0.1 m) on a turning ship,
    against the MMG formulae transcribed here: no slipstream and no propeller wake, so
    ``u_R = epsilon (u - y_R r)`` (the water speed at the rudder), and the forces as for any
    rudder. In the model, the actuator load less the propeller's and the bow tunnel's is the
    two rudders' load. A turn rate is needed: straight ahead the rudder's own y_R drops out
    of its inflow."""
    d = copy.deepcopy(esso_dict())
    d["thrusters"].append({"name": "bow", "type": "tunnel", "x_m": 1.2, "diameter_m": 0.05, "max_rpm": 3000.0})
    d["rudders"].append(dict(d["rudders"][0], name="aux", propeller=None, y_m=0.1))
    d["rudders"][1].pop("propeller")
    m = DynamicModel(vessel_from_dict(d, "mixed.toml"))
    u, v, r = 0.3, 0.01, 0.08
    d_main, d_aux = math.radians(12), math.radians(-20)
    rd, rho = m.vessel.rudders[1], d["particulars"]["rho_water_kg_m3"]
    u_R = rd.wake_ratio * (u - rd.y_m * r)
    lat = v + rd.l_R_m * r
    v_R = -(rd.flow_straightening_neg if lat > 0 else rd.flow_straightening_pos) * lat
    F_N = 0.5 * rho * rd.area_m2 * rd.f_alpha * (u_R**2 + v_R**2) * math.sin(d_aux - math.atan2(v_R, u_R))
    X_R = -(1 - rd.steering_resistance_deduction) * F_N * math.sin(d_aux)
    aux = [X_R, -(1 + rd.hull_force_factor) * F_N * math.cos(d_aux),
           -(rd.x_m + rd.hull_force_factor * rd.x_H_m) * F_N * math.cos(d_aux) - rd.y_m * X_R]
    np.testing.assert_allclose(rudder_forces(m, [u, v, r], [d_main, d_aux], [3.0, 3.0])[0, 1], aux, rtol=1e-9)
    # the model's kernel: the same aux load beside the main rudder behind its propeller
    _, parts, thrusts = m.acceleration([0, 0, 0], [u, v, r], rpm=[RPM8, 600.0], rudder_rad=[d_main, d_aux],
                                       return_parts=True)
    prop, bow = m.vessel.thrusters
    T_d, T_bow = thrusts[0]
    a = bow.fixed_angle_rad
    rudders = parts[0, 1] - [T_d, 0.0, -prop.y_m * T_d] - T_bow * np.array(
        [math.cos(a), math.sin(a), bow.x_m * math.sin(a) - bow.y_m * math.cos(a)])
    main = rudder_forces(m, [u, v, r], [d_main, 0.0], [T_d / (1 - prop.thrust_deduction), 0.0])[0, 0]
    np.testing.assert_allclose(rudders, main + aux, rtol=1e-9, atol=1e-9 * abs(T_d))


def test_physics_log_commands_the_rudder(esso):
    """A synthetic log of a rudder vessel: rudder angles commanded, logged in the rudder's angle
    column, and read back into the rudder channel (a known-command forecast follows the log
    more closely with them than with the rudder at midships)."""
    from hybridship.predictors import DynamicPredictor
    from hybridship.sim.synthetic import physics_log

    log = physics_log(esso, duration_s=300.0, t_shutdown_s=None, rpm_scale=0.6, wind=(0.0, 0.0),
                      hold_s=(30.0, 60.0), rudder_scale=0.5)
    delta = log["rudder_azimuth_deg"].to_numpy()
    assert np.abs(delta).max() <= 0.5 * esso.vessel.rudders[0].max_angle_deg and np.abs(delta).max() > 5.0
    starts = [100.0, 150.0]

    def end_error(frame):
        fc = DynamicPredictor(esso.vessel).forecast(frame, starts, 60.0, commands="known")
        truth = log.set_index("time_s").loc[[s + 60.0 for s in starts], ["north_m", "east_m"]].to_numpy()
        return np.hypot(*(fc.eta[:, -1, :2] - truth).T).max()

    midships = log.assign(rudder_azimuth_deg=0.0)
    assert end_error(log) < 0.5 * end_error(midships)


def test_max_angle_deg_is_the_limit_of_the_forecasts_rudder_commands_as_its_description_says(esso):
    """The field was described as 'mechanical limit (for reference)', as if nothing used it; the
    forecasts' input check clips a rudder command beyond it (and refuses it in refuse mode), and
    synthetic trials draw within it."""
    from pathlib import Path

    from hybridship.forecast_inputs import InputRangeError, check_or_clip_inputs
    from hybridship.vessel import Rudder

    limit = math.radians(esso.vessel.rudders[0].max_angle_deg)
    out = check_or_clip_inputs(esso, azimuth_rad=[0.0, limit + 0.1])
    assert out.azimuth_rad[-1] == pytest.approx(limit) and out.clipped.all()
    with pytest.raises(InputRangeError, match=r"azimuth_rad\[rudder .rudder.\]: .*the rudders. max_angle_deg"):
        check_or_clip_inputs(esso, azimuth_rad=[0.0, limit + 0.1], mode="refuse")
    described = Rudder.model_fields["max_angle_deg"].description
    row = next(line for line in (Path(__file__).parents[1] / "docs" / "reference" / "vessel-file.md")
               .read_text(encoding="utf-8").splitlines() if line.startswith("| `max_angle_deg`"))
    for text in (described, row):
        assert "for reference" not in text and "clips" in text and "synthetic trials" in text


def test_a_span_shorter_than_the_propeller_diameter_puts_all_of_it_in_the_slipstream_as_documented():
    """eta was documented as D_P / H_R; the model caps it at 1 (all of the span in the
    slipstream; above 1 the plain-wake share 1 - eta would be negative), which the rudder
    docstring, the schema and the vessel-file reference now say."""
    from pathlib import Path

    from hybridship.physics import rudder as rudder_module
    from hybridship.vessel import Rudder

    d = esso_dict()
    d["rudders"][0]["span_m"] = 0.5 * d["thrusters"][0]["diameter_m"]
    m = DynamicModel(vessel_from_dict(d, "short_span.toml"))
    assert m.arrays.rud[0, rudder_module.RUD_ETA] == 1.0
    r = m.vessel.rudders[0]
    u_p, thrust, dia, rho = 0.3, 2.0, d["thrusters"][0]["diameter_m"], m.vessel.particulars.rho_water_kg_m3
    u_jet = (1 - r.slipstream_factor) * u_p + r.slipstream_factor * math.sqrt(
        u_p**2 + 8 * thrust / (math.pi * rho * dia**2))
    assert rudder_inflow_scalar(u_p, thrust, dia, rho, r.wake_ratio, r.slipstream_factor, 1.0) == pytest.approx(
        r.wake_ratio * u_jet, rel=1e-12)
    reference = (Path(__file__).parents[1] / "docs" / "reference" / "vessel-file.md").read_text(encoding="utf-8")
    for text in (rudder_module.__doc__, Rudder.__doc__, reference):
        assert "D_P / H_R" in text and "min(D_P / H_R" in text.replace("\\min", "min")
