"""Physical facts of the 3-DOF model: analytic solutions, invariants, signs, published values."""

from __future__ import annotations

import copy
import tomllib

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridship import frames
from hybridship.physics import hull
from hybridship.physics.model import DynamicModel, TAU_PARTS
from hybridship.physics.propeller import ct_cq_star, kt_kq, load_wageningen, rpm_for_thrust, thrust_torque
from hybridship.physics.thrusters import configuration_matrix
from hybridship.vessel import VesselFileError, load_vessel, packaged_vessel_text, vessel_from_dict



def gunnerus_dict() -> dict:
    return tomllib.loads(packaged_vessel_text("gunnerus"))


def model_from(d: dict) -> DynamicModel:
    return DynamicModel(vessel_from_dict(d, "test"))


@pytest.fixture(scope="module")
def gunnerus():
    return DynamicModel("gunnerus")


# ----------------------------------------------------------------------------- frames


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3), st.floats(-20, 20))
def test_frame_round_trip_and_norm(vec, psi):
    v = np.array(vec)
    ned = frames.body_to_ned(v, psi)
    np.testing.assert_allclose(frames.ned_to_body(ned, psi), v, atol=1e-9)
    assert np.linalg.norm(ned[:2]) == pytest.approx(np.linalg.norm(v[:2]), rel=1e-12, abs=1e-9)
    np.testing.assert_allclose(frames.rotation_z(psi) @ v, ned, atol=1e-9)


def test_rotation_is_orthonormal_and_heading_convention():
    R = frames.rotation_z(np.linspace(-7, 7, 11))
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0)
    # heading east (90 deg), surging ahead -> moving east in NED
    np.testing.assert_allclose(frames.body_to_ned([1.0, 0, 0], np.pi / 2), [0, 1, 0], atol=1e-12)


def test_wrap_and_latlon_round_trip():
    a = np.array([-3 * np.pi, -np.pi, 0, np.pi, 2.5 * np.pi])
    w = frames.wrap_pi(a)
    assert np.all((w >= -np.pi) & (w < np.pi))
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-12)
    n, e = frames.latlon_to_north_east(63.44 + 0.01, 10.40 + 0.02, 63.44, 10.40)
    assert n == pytest.approx(1113.6, rel=2e-3)  # 0.01 deg latitude ~ 1.11 km
    assert e == pytest.approx(2 * 1113.2 * np.cos(np.radians(63.44)), rel=3e-3)
    # exactly: the WGS-84 meridian and prime-vertical radii at the reference latitude (Fossen 2021,
    # sec. 2.5.2); the rough figures above also pass a spherical earth of 6371 km
    a, f = 6378137.0, 1 / 298.257223563
    e2, s2 = f * (2 - f), np.sin(np.radians(63.44)) ** 2
    r_n = a / np.sqrt(1 - e2 * s2)
    r_m = a * (1 - e2) / (1 - e2 * s2) ** 1.5
    assert n == pytest.approx(np.radians(0.01) * r_m, rel=1e-9)
    assert e == pytest.approx(np.radians(0.02) * r_n * np.cos(np.radians(63.44)), rel=1e-9)
    lat, lon = frames.north_east_to_latlon(n, e, 63.44, 10.40)
    assert lat == pytest.approx(63.45, abs=1e-10) and lon == pytest.approx(10.42, abs=1e-10)


def test_flow_speed_and_direction_give_north_east_components():
    """``speed_dir_to_vector``: ``[speed, dir]`` -> ``[north, east] = speed [cos dir, sin dir]`` in NED
    (dir clockwise from north): a flow at 90 deg is all east, at 0 deg all north, at 180 deg south."""
    vec = frames.speed_dir_to_vector([[1.0, np.pi / 2], [2.0, 0.0], [3.0, np.pi]])
    np.testing.assert_allclose(vec, [[0.0, 1.0], [2.0, 0.0], [-3.0, 0.0]], atol=1e-15)
    np.testing.assert_allclose(frames.vector_to_speed_dir(vec)[:2], [[1.0, np.pi / 2], [2.0, 0.0]], atol=1e-15)


# ----------------------------------------------------------------------------- hull


def test_the_models_coriolis_terms_do_no_work():
    """Skew-symmetric C_RB(nu) and C_A(nu) (Fossen 2021, ch. 6) mean nu^T C(nu) nu = 0: checked on
    the hull load the dynamics use, with damping removed, at random velocities and an
    off-centre CG (the helpers' matrices alone are skew by construction)."""
    d = gunnerus_dict()
    d["damping"] = {"linear": {"method": "explicit", "D": [[0, 0, 0], [0, 0, 0], [0, 0, 0]]},
                    "nonlinear": {"method": "none"}}
    d["wind"] = {"method": "none"}
    d["thrusters"] = []
    d["rigid_body"]["x_g_m"] = 1.3
    m = model_from(d)
    nu = np.random.default_rng(0).normal(scale=[1.0, 0.5, 0.05], size=(50, 3))
    _, parts, _ = m.acceleration(np.zeros((50, 3)), nu, rpm=np.zeros((50, 0)), azimuth_rad=np.zeros((50, 0)),
                                 return_parts=True)
    tau_hull = parts[:, 0]
    assert np.abs(tau_hull).max() > 1e3                          # the terms are there ...
    power = np.einsum("bi,bi->b", nu, tau_hull)
    scale = np.einsum("bi,bi->b", np.abs(nu), np.abs(tau_hull))
    np.testing.assert_array_less(np.abs(power), 1e-12 * scale)   # ... and do no work


def test_crossflow_strips_can_span_the_hull_rather_than_centre_on_the_origin():
    """The strips run from the AP (``strips_x_aft_m`` from the origin) over L_pp; by default
    the hull is centred on the origin, where pure sway makes no yaw moment."""
    d = gunnerus_dict()
    centred = model_from(d)
    d["damping"]["nonlinear"]["strips_x_aft_m"] = -15.56
    shifted = model_from(d)
    np.testing.assert_allclose(centred.arrays.strip_x[[0, -1]], [-16.95, 16.95])
    np.testing.assert_allclose(shifted.arrays.strip_x[[0, -1]], [-15.56, 18.34])
    sway = dict(rpm=np.zeros(3), azimuth_rad=np.zeros(3), return_parts=True)
    _, p_c, _ = centred.acceleration([0, 0, 0], [0, 0.3, 0], **sway)
    _, p_s, _ = shifted.acceleration([0, 0, 0], [0, 0.3, 0], **sway)
    assert abs(p_c[0, 0, 2]) < 1e-6 and p_s[0, 0, 2] < -1e3     # more hull forward: the bow is pushed back
    np.testing.assert_allclose(p_s[0, 0, 1], p_c[0, 0, 1])      # same sway drag
    # a file without the field keeps its fingerprint (model files recorded it before)
    from hybridship.vessel import fingerprint
    assert fingerprint(centred.vessel) == fingerprint(load_vessel("gunnerus"))


def test_surge_decay_matches_analytic_exponential():
    d = gunnerus_dict()
    d["damping"]["nonlinear"] = {"method": "none"}
    d["wind"] = {"method": "none"}
    d["thrusters"] = []
    m = model_from(d)
    res = m.rollout([0, 0, 0], [2.0, 0, 0], 300, dt_s=1.0)
    M11 = m.mass_matrix[0, 0]
    D11 = m.arrays.d_lin[0, 0]
    t = res.time_s
    np.testing.assert_allclose(res.nu[0, :, 0], 2.0 * np.exp(-D11 / M11 * t), rtol=1e-8)
    # position is the integral of the velocity
    np.testing.assert_allclose(res.eta[0, :, 0], 2.0 * M11 / D11 * (1 - np.exp(-D11 / M11 * t)), rtol=1e-7)
    np.testing.assert_allclose(res.nu[0, :, 1:], 0.0, atol=1e-12)


def test_kinetic_energy_conserved_without_damping():
    d = gunnerus_dict()
    d["damping"] = {"linear": {"method": "explicit", "D": [[0, 0, 0], [0, 0, 0], [0, 0, 0]]},
                    "nonlinear": {"method": "none"}}
    d["wind"] = {"method": "none"}
    d["thrusters"] = []
    d["rigid_body"]["x_g_m"] = 1.5  # exercise the off-diagonal rigid-body terms too
    m = model_from(d)
    nu0 = np.array([[1.0, 0.4, 0.03], [0.2, -0.8, -0.05]])
    res = m.rollout(np.zeros((2, 3)), nu0, 2000, dt_s=0.5)
    M = m.mass_matrix
    E = 0.5 * np.einsum("bti,ij,btj->bt", res.nu, M, res.nu)
    np.testing.assert_allclose(E, np.broadcast_to(E[:, :1], E.shape), rtol=1e-6)
    assert np.ptp(res.nu[0, :, 1]) > 0.1  # the motion is not trivial: energy moves between DOFs


def test_current_gives_relative_velocity_drift_to_steady_state(gunnerus):
    """A ship with no forces but damping drifts with the current (nu_r -> 0)."""
    d = gunnerus_dict()
    d["wind"] = {"method": "none"}
    d["damping"]["linear"]["T_surge_s"] = 100.0  # shorter surge transient, same physics
    m = model_from(d)
    res = m.rollout([0, 0, 0.7], [0, 0, 0], 3000, dt_s=1.0, current=[0.5, np.radians(60)])
    eta_dot = frames.body_to_ned(res.nu[0, -1], res.eta[0, -1, 2])
    np.testing.assert_allclose(eta_dot[:2], 0.5 * np.array([np.cos(np.radians(60)), np.sin(np.radians(60))]),
                               atol=2e-3)


def test_hull_damping_dissipates(gunnerus):
    rng = np.random.default_rng(1)
    nu = rng.normal(scale=[1.0, 0.5, 0.02], size=(200, 3))
    _, parts, _ = gunnerus.acceleration(np.zeros((200, 3)), nu, return_parts=True)
    power = np.einsum("bi,bi->b", parts[:, TAU_PARTS.index("hull")], nu)
    # C terms do no work, damping removes energy (the |u| lift terms are small at these speeds)
    assert np.all(power < 0)


def test_lift_speed_signed_reverses_only_the_lift_astern():
    """``lift_speed = "signed"`` equals the default ahead; astern the lift force reverses:
    the hull force changes by exactly ``2 |u_r| D_lift [v_r, r]`` in sway and yaw."""
    d = gunnerus_dict()
    d["wind"] = {"method": "none"}
    m_abs = model_from(d)
    d["damping"]["nonlinear"]["lift_speed"] = "signed"
    m_sig = model_from(d)
    assert np.any(m_abs.arrays.d_lift[:4] != 0) and np.all(m_abs.arrays.d_lift[4:] == 0)
    np.testing.assert_array_equal(m_sig.arrays.d_lift[4:], m_abs.arrays.d_lift[:4])
    rng = np.random.default_rng(3)
    nu = rng.normal(scale=[1.0, 0.5, 0.02], size=(100, 3))
    nu[:50, 0] = np.abs(nu[:50, 0])
    nu[50:, 0] = -np.abs(nu[50:, 0]) - 0.01
    eta = np.zeros((100, 3))
    _, p_abs, _ = m_abs.acceleration(eta, nu, return_parts=True)
    _, p_sig, _ = m_sig.acceleration(eta, nu, return_parts=True)
    h = TAU_PARTS.index("hull")
    np.testing.assert_array_equal(p_sig[:50, h], p_abs[:50, h])
    dl = m_abs.arrays.d_lift
    lift = np.column_stack([dl[0] * nu[50:, 1] + dl[1] * nu[50:, 2], dl[2] * nu[50:, 1] + dl[3] * nu[50:, 2]])
    np.testing.assert_allclose(p_sig[50:, h, 1:] - p_abs[50:, h, 1:], 2 * np.abs(nu[50:, :1]) * lift,
                               rtol=1e-9, atol=1e-6)
    np.testing.assert_array_equal(p_sig[50:, h, 0], p_abs[50:, h, 0])


def test_clarke_lift_restores_clarkes_linear_derivatives_at_speed():
    """``clarke1983_lift``'s identity: at ``u_r = U`` the hydrodynamic sway force and yaw moment
    ``-C_A(nu_r) nu_r - |u_r| D_lift [v_r, r]`` have Clarke et al.'s (1983) derivatives,
    ``dY/dv = U Y_v/U``, ``dY/dr = U Y_r/U``, ``dN/dv = U N_v/U``, ``dN/dr = U N_r/U``: checked by
    central differences of the model's hull load (less the rigid-body ``-C_RB(nu) nu``) with no other
    damping, so the load is linear in (v, r)."""
    d = gunnerus_dict()
    d["damping"] = {"linear": {"method": "explicit", "D": [[0, 0, 0], [0, 0, 0], [0, 0, 0]]},
                    "nonlinear": {"method": "none", "lift": "clarke1983"}}
    d["wind"] = {"method": "none"}
    d["thrusters"] = []
    m = model_from(d)
    U, h = 2.0, 0.01
    nu = np.array([[U, h, 0], [U, -h, 0], [U, 0, h], [U, 0, -h]])
    _, parts, _ = m.acceleration(np.zeros((4, 3)), nu, rpm=np.zeros((4, 0)), azimuth_rad=np.zeros((4, 0)),
                                 return_parts=True)
    rb = m.vessel.rigid_body
    C_RB = hull.coriolis_rigid_body(nu, rb.mass_kg, rb.x_g_m)
    hydro = parts[:, TAU_PARTS.index("hull")] + np.einsum("bij,bj->bi", C_RB, nu)
    d_dv = (hydro[0] - hydro[1]) / (2 * h)
    d_dr = (hydro[2] - hydro[3]) / (2 * h)
    p = d["particulars"]
    c = hull.clarke1983_derivatives(p["L_pp_m"], p["B_m"], p["T_m"], p["C_B"], p["rho_water_kg_m3"])
    np.testing.assert_allclose([d_dv[1], d_dr[1], d_dv[2], d_dr[2]],
                               [U * c["Y_v_per_U_kg_m"], U * c["Y_r_per_U_kg"], U * c["N_v_per_U_kg"],
                                U * c["N_r_per_U_kg_m"]], rtol=1e-9)


# ----------------------------------------------------------------------------- thrusters


def test_configuration_matrix_hand_cases():
    T = configuration_matrix(np.array([np.pi / 2, 0.0, np.pi / 2]), [15.0, -14.0, -14.0], [0.0, -2.0, 2.0])
    # tunnel: [0, 1, l_x]; azimuth at 0: [1, 0, -l_y]; azimuth at 90 deg: [0, 1, l_x]
    np.testing.assert_allclose(T[:, 0], [0, 1, 15.0], atol=1e-12)
    np.testing.assert_allclose(T[:, 1], [1, 0, 2.0], atol=1e-12)
    np.testing.assert_allclose(T[:, 2], [0, 1, -14.0], atol=1e-12)
    a = np.radians(30)
    np.testing.assert_allclose(configuration_matrix(np.array([a]), [-10.0], [3.0])[:, 0],
                               [np.cos(a), np.sin(a), -10 * np.sin(a) - 3 * np.cos(a)], atol=1e-12)


def test_thruster_load_matches_configuration_matrix(gunnerus):
    rpm = np.array([200.0, 150.0, -120.0])
    az = np.array([0.0, np.radians(40), np.radians(-25)])
    _, parts, thrusts = gunnerus.acceleration([0, 0, 0], [0, 0, 0], rpm=rpm, azimuth_rad=az, return_parts=True)
    v = gunnerus.vessel
    alpha = np.array([t.fixed_angle_rad if t.type != "azimuth" else a for t, a in zip(v.thrusters, az)])
    T = configuration_matrix(alpha, [t.x_m for t in v.thrusters], [t.y_m for t in v.thrusters])
    np.testing.assert_allclose(parts[0, 1], T @ thrusts[0], rtol=1e-12)
    # bollard thrust of each unit from K_T0: (1 - t) K_T0 rho n^2 D^4
    p = load_wageningen()
    for t, n, f in zip(v.thrusters, rpm, thrusts[0]):
        if n > 0:
            assert f == pytest.approx((1 - t.thrust_deduction) * p.kt0 * 1025 * (n / 60) ** 2 * t.diameter_m**4,
                                      rel=1e-9)


def test_each_propeller_sees_the_water_velocity_at_its_own_position(gunnerus):
    """Turning ship: thruster i delivers ``(1 - t) T(n, V_a)``, T the open-water thrust, at
    ``V_a = (1 - w) [(u - y r) cos a + (v + x r) sin a]``, the inflow along its axis at its position
    (x, y) (rigid-body velocity ``[u - y r, v + x r]``), so port and starboard units differ."""
    u, v, r = 1.5, -0.3, 0.04
    rpm = np.array([250.0, 150.0, 150.0])
    az = np.radians([0.0, 25.0, -35.0])
    _, _, thrusts = gunnerus.acceleration([0, 0, 0], [u, v, r], rpm=rpm, azimuth_rad=az, return_parts=True)
    d = gunnerus_dict()
    for k, t in enumerate(d["thrusters"]):
        a = np.pi / 2 if t["type"] == "tunnel" else az[k]
        w, ded = t.get("wake_fraction", 0.0), t.get("thrust_deduction", 0.0)   # the file's defaults: 0
        va = (1 - w) * ((u - t["y_m"] * r) * np.cos(a) + (v + t["x_m"] * r) * np.sin(a))
        prop = load_wageningen(t.get("propeller_series", "B4-70"), t.get("pitch_ratio", 1.0))
        T, _ = thrust_torque(rpm[k] / 60.0, va, t["diameter_m"], prop, d["particulars"]["rho_water_kg_m3"])
        assert thrusts[0, k] == pytest.approx((1 - ded) * T, rel=1e-9), t["name"]
    assert thrusts[0, 1] != pytest.approx(thrusts[0, 2], rel=1e-3)   # same rpm, different inflow


def test_tunnel_thruster_pushes_the_bow_to_starboard_for_positive_rpm(gunnerus):
    """A tunnel's thrust axis is +y (positive rpm gives starboard thrust): the Gunnerus bow tunnel
    alone, at rest, gives ``Y = K_T0 rho n^2 D^4 > 0`` (bollard, t = 0), no surge force and
    ``N = x_tunnel Y`` (the bow turns to starboard)."""
    d = gunnerus_dict()
    tun = d["thrusters"][0]
    n = 300.0 / 60.0
    _, parts, _ = gunnerus.acceleration([0, 0, 0], [0, 0, 0], rpm=[300.0, 0, 0], azimuth_rad=[0, 0, 0],
                                        return_parts=True)
    Y = load_wageningen().kt0 * d["particulars"]["rho_water_kg_m3"] * n**2 * tun["diameter_m"] ** 4   # B4-70
    np.testing.assert_allclose(parts[0, TAU_PARTS.index("thrust")], [0.0, Y, tun["x_m"] * Y], rtol=1e-9,
                               atol=1e-9 * Y)


def test_fixed_thruster_angle_is_in_degrees_from_ahead_to_starboard():
    """``angle_deg`` of a ``fixed`` thruster is degrees, 0 forward, 90 starboard: at the tunnel's
    position, a fixed unit at 90 deg gives the tunnel's load, and one at 180 deg minus the load
    of one at 0 deg (at rest, where the bollard thrust does not depend on the direction)."""
    d = gunnerus_dict()
    kw = dict(rpm=[300.0, 0, 0], azimuth_rad=[0, 0, 0], return_parts=True)
    thrust = TAU_PARTS.index("thrust")
    loads = {"tunnel": model_from(d).acceleration([0, 0, 0], [0, 0, 0], **kw)[1][0, thrust]}
    for angle in (0.0, 90.0, 180.0):
        d["thrusters"][0].update(type="fixed", angle_deg=angle)
        loads[angle] = model_from(d).acceleration([0, 0, 0], [0, 0, 0], **kw)[1][0, thrust]
    T = loads["tunnel"][1]
    assert T > 0
    np.testing.assert_allclose(loads[0.0], [T, 0.0, 0.0], rtol=1e-12, atol=1e-9 * T)   # y = 0: no moment
    np.testing.assert_allclose(loads[90.0], loads["tunnel"], rtol=1e-12, atol=1e-9 * T)
    np.testing.assert_allclose(loads[180.0], -loads[0.0], rtol=1e-12, atol=1e-9 * T)


# ----------------------------------------------------------------------------- propeller


def test_propeller_reproduces_reference_bollard_coefficients():
    p = load_wageningen("B4-70", 1.0)
    assert p.kt0 == pytest.approx(0.4499, abs=5e-5)
    assert p.kq0 == pytest.approx(0.06607, abs=5e-6)


def test_propeller_against_shared_check_values(shared_data):
    f = shared_data("reference", "wageningen_b_series_4q_check_values.csv")
    chk = pd.read_csv(f)
    for (series, pd_ratio), g in chk.groupby(["series", "pitch_diameter_ratio"]):
        p = load_wageningen(series, pd_ratio)
        ct, cq = ct_cq_star(np.radians(g["beta_deg"].to_numpy()), p)
        np.testing.assert_allclose(ct, g["CT_star"], atol=6e-5, err_msg=f"{series} P/D {pd_ratio}")
        np.testing.assert_allclose(cq, g["CQ_star"], atol=6e-6, err_msg=f"{series} P/D {pd_ratio}")


def test_propeller_first_quadrant_close_to_oosterveld_polynomial():
    p = load_wageningen("B4-70", 1.0)
    kt, kq = kt_kq(np.array([0.2, 0.4, 0.6, 0.8]), p)
    np.testing.assert_allclose(kt, [0.392, 0.314, 0.226, 0.130], rtol=0.05)  # reference README table
    np.testing.assert_allclose(kq, [0.0594, 0.0492, 0.0373, 0.0240], rtol=0.12)


@pytest.mark.parametrize("n, va, sign", [(5.0, 0.5, +1), (-5.0, 0.5, -1), (-5.0, -0.5, -1), (5.0, -0.5, +1)])
def test_quadrant_thrust_signs(n, va, sign):
    """Low advance ratios in each quadrant: thrust follows the shaft direction."""
    t, q = thrust_torque(n, va, 1.9, load_wageningen())
    assert np.sign(t) == sign and np.sign(q) == sign


def test_stopped_propeller_gives_drag_opposing_inflow():
    p = load_wageningen()
    va = np.array([-2.0, -0.5, 0.5, 2.0])
    t, _ = thrust_torque(0.0, va, 1.9, p)
    assert np.all(np.sign(t) == -np.sign(va))
    # drag grows with V_a^2: C_T*(+-90 deg) 0.5 rho V_a^2 pi/4 D^2
    ct90, _ = ct_cq_star(np.radians([90.0, -90.0]), p)
    np.testing.assert_allclose(t[[2, 0]] / va[[2, 0]] ** 2, ct90 * 0.5 * 1025 * np.pi / 4 * 1.9**2, rtol=1e-12)


def test_propeller_continuous_across_quadrant_boundaries():
    p = load_wageningen()
    for b0 in (-180.0, -90.0, 0.0, 90.0, 180.0):
        ct, cq = ct_cq_star(np.radians([b0 - 1e-7, b0 + 1e-7]), p)
        assert abs(ct[1] - ct[0]) < 1e-6 and abs(cq[1] - cq[0]) < 1e-6
    # and the dimensional thrust is continuous through n = 0 and V_a = 0
    t, _ = thrust_torque(np.array([-1e-6, 1e-6]), 1.0, 1.9, p)
    assert abs(t[1] - t[0]) < 1e-5 * abs(t[0])
    t, _ = thrust_torque(3.0, np.array([-1e-6, 1e-6]), 1.9, p)
    assert abs(t[1] - t[0]) < 1e-5 * abs(t[0])


def test_rpm_for_thrust_inverts_the_propeller_model_in_every_quadrant():
    p = load_wageningen()
    T = np.array([40e3, -25e3, 5e3, -5e3, 0.0, 30e3])
    va = np.array([0.5, 0.5, -1.0, -1.0, 0.0, 2.0])
    rpm = rpm_for_thrust(T, va, 1.9, p, max_rpm=217.0)
    t_back, _ = thrust_torque(rpm / 60.0, va, 1.9, p)
    np.testing.assert_allclose(t_back, T, atol=1.0)
    assert np.all(np.sign(rpm[T != 0]) == np.sign(T[T != 0]))
    big = rpm_for_thrust([1e7, -1e7], [0.0, 0.0], 1.9, p, max_rpm=217.0)  # infeasible: saturates
    np.testing.assert_allclose(big, [217.0, -217.0], atol=1e-6)
    with pytest.raises(ValueError, match="^thrust_N: contains NaN or inf"):
        rpm_for_thrust([np.nan], [0.0], 1.9, p)


def test_rpm_for_thrust_meets_a_small_demand_beyond_the_drag_of_a_propeller_at_rest():
    """With inflow a propeller at rest already gives a force (its drag); a smaller demand of
    that sign, or any demand of the other, needs the shaft turned the other way."""
    p = load_wageningen()
    D = 1.9
    for va in (1.0, -1.0, 0.5, -2.0):
        t_rest, _ = thrust_torque(0.0, va, D, p)
        t_rest = float(t_rest)
        # between the rest force and zero, and just past zero on the other side
        demands = np.array([0.7 * t_rest, 0.3 * t_rest, 0.0, -0.2 * t_rest])
        rpm = rpm_for_thrust(demands, np.full(4, va), D, p, max_rpm=217.0)
        t_back, _ = thrust_torque(rpm / 60.0, np.full(4, va), D, p)
        np.testing.assert_allclose(t_back, demands, atol=1e-6 * abs(t_rest) + 1e-6)
        # turning against the rest force: the shaft turns the way that opposes it
        assert np.all(np.sign(rpm) == -np.sign(t_rest))


def test_drifting_ship_with_stopped_thrusters_feels_drag(gunnerus):
    """A ship drifting astern with rpm 0 gets a forward (opposing) force from its azimuths."""
    _, parts, thrusts = gunnerus.acceleration([0, 0, 0], [-0.8, 0, 0], rpm=[0, 0, 0], azimuth_rad=[0, 0, 0],
                                              return_parts=True)
    assert parts[0, 1, 0] > 0 and np.all(thrusts[0, 1:] > 0)


# ----------------------------------------------------------------------------- wind


def test_head_wind_gives_aft_force_and_no_sway(gunnerus):
    _, parts, _ = gunnerus.acceleration([0, 0, np.radians(30)], [0, 0, 0], wind=[10.0, np.radians(30)],
                                        return_parts=True)
    w = parts[0, TAU_PARTS.index("wind")]
    assert w[0] < 0 and abs(w[1]) < 1e-9 and abs(w[2]) < 1e-9
    q = 0.5 * 1.225 * 100.0
    assert w[0] == pytest.approx(q * -0.53 * 81.0 * 1.0, rel=1e-9)  # C_X(0) A_F from the vessel table


def test_beam_wind_from_port_pushes_to_starboard_symmetrically(gunnerus):
    psi = 0.0
    _, p_port, _ = gunnerus.acceleration([0, 0, psi], [0, 0, 0], wind=[12.0, np.radians(270)], return_parts=True)
    _, p_stbd, _ = gunnerus.acceleration([0, 0, psi], [0, 0, 0], wind=[12.0, np.radians(90)], return_parts=True)
    wp, ws = p_port[0, 2], p_stbd[0, 2]
    assert wp[1] > 0 and ws[1] < 0
    np.testing.assert_allclose(wp, ws * np.array([1, -1, -1]), rtol=1e-12)


def test_ship_speed_enters_relative_wind(gunnerus):
    """Moving at 5 m/s into a 5 m/s tail wind: no relative wind, no load."""
    _, parts, _ = gunnerus.acceleration([0, 0, 0], [5.0, 0, 0], wind=[5.0, np.pi], return_parts=True)
    np.testing.assert_allclose(parts[0, 2], 0.0, atol=1e-9)


def test_beam_wind_loads_are_the_files_coefficients_times_the_areas(gunnerus):
    """Eq. 3 for a beam wind from port (gamma = 90 deg): ``[X, Y, N] = q [C_X A_F, C_Y A_L, C_N A_L L]``,
    ``q = rho_a V^2 / 2``, with the coefficients, areas and moment length of the vessel file."""
    w = gunnerus_dict()["wind"]
    i = w["table"]["angle_deg"].index(90)
    V = 12.0
    q = 0.5 * w["rho_air_kg_m3"] * V**2
    _, parts, _ = gunnerus.acceleration([0, 0, 0], [0, 0, 0], wind=[V, np.radians(270)], return_parts=True)
    expected = [q * w["table"]["C_X"][i] * w["A_F_m2"], q * w["table"]["C_Y"][i] * w["A_L_m2"],
                q * w["table"]["C_N"][i] * w["A_L_m2"] * w["L_oa_m"]]
    np.testing.assert_allclose(parts[0, TAU_PARTS.index("wind")], expected, rtol=1e-9)


def test_wind_coefficients_between_table_angles_are_interpolated_linearly(gunnerus):
    """Between the file's 10-deg angles the wind load is ``q A`` times the linear interpolation of
    the table (mirrored for wind from starboard, gamma < 0: C_X even, C_Y and C_N odd)."""
    w = gunnerus_dict()["wind"]
    tab = w["table"]
    gamma = np.radians([45.3, 117.8, -133.35, 4.1])
    psi = 0.3
    V = 10.0
    B = len(gamma)
    eta = np.column_stack([np.zeros(B), np.zeros(B), np.full(B, psi)])
    wind = np.column_stack([np.full(B, V), psi - gamma])     # gamma > 0: wind from port of the bow
    _, parts, _ = gunnerus.acceleration(eta, np.zeros((B, 3)), wind=wind, return_parts=True)
    g = np.degrees(np.abs(gamma))
    s = np.sign(gamma)
    C = np.column_stack([np.interp(g, tab["angle_deg"], tab["C_X"]), s * np.interp(g, tab["angle_deg"], tab["C_Y"]),
                         s * np.interp(g, tab["angle_deg"], tab["C_N"])])
    q = 0.5 * w["rho_air_kg_m3"] * V**2
    area = np.array([w["A_F_m2"], w["A_L_m2"], w["A_L_m2"] * w["L_oa_m"]])
    np.testing.assert_allclose(parts[:, TAU_PARTS.index("wind")], q * C * area, rtol=1e-9)


def test_wind_acts_on_the_velocity_over_ground_not_through_the_water(gunnerus):
    """The relative wind is air velocity minus ship velocity over ground (Fossen 2021, sec. 10.1):
    a ship carried by the current (at rest in the water) in air moving with it feels no wind,
    although it moves over ground."""
    psi, speed, to = 0.4, 1.2, np.radians(40.0)
    nu = frames.ned_to_body([speed * np.cos(to), speed * np.sin(to), 0.0], psi)
    _, parts, _ = gunnerus.acceleration([0, 0, psi], nu, current=[speed, to], wind=[speed, to + np.pi],
                                        return_parts=True)              # the wind comes FROM to + pi
    np.testing.assert_allclose(parts[0, TAU_PARTS.index("wind")], 0.0, atol=1e-9)


@pytest.mark.parametrize("name", ["gunnerus", "esso_osaka_model"])
def test_compiled_wind_load_is_eq_3_at_any_heading_velocity_and_wind(name):
    """The compiled kernel's wind load against eq. 3 evaluated with the numpy reference
    (``wind.relative_wind`` and the vessel's coefficient curve, not the kernel's table) at random
    headings, velocities over ground (sway and yaw rate too) and winds: a table vessel (exact at
    the 0.5-deg table, which holds the file's 10-deg nodes) and a Blendermann one (the kernel
    interpolates the smooth curve linearly between 0.5-deg samples: observed 5e-5 of the largest load)."""
    from hybridship.physics.model import wind_coefficient_curve
    from hybridship.physics.wind import relative_wind

    m = DynamicModel(name)
    rng = np.random.default_rng(5)
    B = 300
    eta = np.column_stack([np.zeros((B, 2)), rng.uniform(-7, 7, B)])
    nu = rng.normal(scale=[3.0, 1.0, 0.05], size=(B, 3))
    wind = np.column_stack([rng.uniform(0, 20, B), rng.uniform(-7, 7, B)])
    _, parts, _ = m.acceleration(eta, nu, wind=wind, return_parts=True)
    V, gamma = relative_wind(wind[:, 0], wind[:, 1], eta[:, 2], nu[:, 0], nu[:, 1])
    w = m.vessel.wind
    area = np.array([w.A_F_m2, w.A_L_m2, w.A_L_m2 * (w.L_oa_m or m.vessel.particulars.L_oa_m)])
    expected = 0.5 * w.rho_air_kg_m3 * V[:, None] ** 2 * np.column_stack(wind_coefficient_curve(m.vessel)(gamma)) * area
    tol = (1e-12 if w.method == "table" else 2e-4) * np.abs(expected).max(axis=0)
    np.testing.assert_array_less(np.abs(parts[:, TAU_PARTS.index("wind")] - expected), np.broadcast_to(tol, (B, 3)))


# ----------------------------------------------------------------------------- integrator


def test_rollout_batch_equals_single_and_held_equals_per_step(gunnerus):
    rng = np.random.default_rng(3)
    B = 7
    eta0 = rng.normal(size=(B, 3))
    nu0 = rng.normal(scale=[0.5, 0.2, 0.01], size=(B, 3))
    rpm = rng.uniform(-100, 200, size=(B, 3))
    az = rng.uniform(-np.pi, np.pi, size=(B, 3))
    wind = np.column_stack([rng.uniform(0, 15, B), rng.uniform(0, 2 * np.pi, B)])
    batch = gunnerus.rollout(eta0, nu0, 60, rpm=rpm, azimuth_rad=az, wind=wind)
    per_step = gunnerus.rollout(eta0, nu0, 60, rpm=np.repeat(rpm[:, None], 60, 1),
                                azimuth_rad=np.repeat(az[:, None], 60, 1), wind=np.repeat(wind[:, None], 60, 1))
    np.testing.assert_array_equal(batch.eta, per_step.eta)
    one = gunnerus.rollout(eta0[3], nu0[3], 60, rpm=rpm[3], azimuth_rad=az[3], wind=wind[3])
    np.testing.assert_allclose(one.eta[0], batch.eta[3], rtol=0, atol=1e-12)
    # step() reproduces rollout()
    e, n = gunnerus.step(eta0, nu0, rpm=rpm, azimuth_rad=az, wind=wind)
    np.testing.assert_allclose(e, batch.eta[:, 1], atol=1e-12)


def test_rk4_converges_at_fourth_order():
    # |x|x damping and the piecewise-linear wind table are not smooth enough to show the
    # order; the smooth part of the model (Coriolis, linear damping, propellers) is.
    d = gunnerus_dict()
    d["damping"]["nonlinear"] = {"method": "none"}
    d["wind"] = {"method": "none"}
    gunnerus = model_from(d)
    kw = dict(rpm=[100, 150, 150], azimuth_rad=[0, 0.4, 0.4])
    ref = gunnerus.rollout([0, 0, 0], [1, 0, 0], 1, dt_s=60.0, substeps=1920, **kw).eta[0, -1]
    errs = [np.abs(gunnerus.rollout([0, 0, 0], [1, 0, 0], 1, dt_s=60.0, substeps=s, **kw).eta[0, -1] - ref).max()
            for s in (16, 64)]
    assert 150 < errs[0] / errs[1] < 450  # 4x smaller steps: 4^4 = 256 for fourth order


def test_bad_inputs_are_refused_with_the_field_named(gunnerus):
    with pytest.raises(ValueError, match="rpm"):
        gunnerus.rollout([0, 0, 0], [0, 0, 0], 10, rpm=[1, 2])
    with pytest.raises(ValueError, match="wind: contains NaN"):
        gunnerus.acceleration([0, 0, 0], [0, 0, 0], wind=[np.nan, 0])
    with pytest.raises(ValueError, match="nu0"):
        gunnerus.rollout([0, 0, 0], [0, np.inf, 0], 10)


def test_negative_wind_or_current_speeds_are_refused(gunnerus):
    """A flow's direction says which way it goes; a negative speed silently turned it round (a
    -10 m/s north wind pushed the ship ahead, as a south wind)."""
    for kw, match in ((dict(wind=[-10.0, 0.0]), r"^wind: speed -10 m/s is negative; expected \[speed_m_s >= 0, "
                                                 r"dir_from_rad\]"),
                      (dict(current=[[0.5, 0.0], [-0.5, 1.0]]), r"^current: speed -0.5 m/s is negative; expected "
                                                                r"\[speed_m_s >= 0, dir_to_rad\]")):
        for call in (gunnerus.acceleration, gunnerus.step):
            with pytest.raises(ValueError, match=match):
                call(np.zeros((2, 3)), np.zeros((2, 3)), **kw)
        with pytest.raises(ValueError, match=match):
            gunnerus.rollout(np.zeros((2, 3)), np.zeros((2, 3)), 3, **kw)
    gunnerus.acceleration([0, 0, 0], [0, 0, 0], wind=[0.0, 0.0], current=[0.0, 0.0])      # calm: fine


def test_propeller_functions_refuse_what_their_kernels_cannot_compute():
    """The compiled propeller kernels assume finite numbers and positive sizes: a NaN shaft speed
    or inflow came back as 0 N, a zero diameter as ZeroDivisionError, a negative water density or
    rpm bound as a silently wrong shaft speed."""
    p = load_wageningen()
    for args, match in (((np.nan, 1.0, 1.9), "^n_rps: contains NaN"), ((1.0, [0.0, np.nan], 1.9), "^va_m_s: contains"),
                        ((1.0, 1.0, 0.0), "^diameter_m: must be > 0"),
                        ((1.0, 1.0, np.nan), "^diameter_m: must be")):
        with pytest.raises(ValueError, match=match):
            thrust_torque(*args, p)
    with pytest.raises(ValueError, match="^rho_kg_m3: must be > 0, got -1025"):
        thrust_torque(1.0, 1.0, 1.9, p, rho_kg_m3=-1025.0)
    for kw, match in ((dict(diameter_m=0.0), "^diameter_m: "), (dict(diameter_m=-1.9), "^diameter_m: "),
                      (dict(rho_kg_m3=np.nan), "^rho_kg_m3: "), (dict(max_rpm=-100.0), "^max_rpm: must be")):
        args = dict(diameter_m=1.9, prop=p) | kw
        with pytest.raises(ValueError, match=match):
            rpm_for_thrust(1e4, 0.0, **args)
    with pytest.raises(ValueError, match=r"^alpha_rad, x_m, y_m: expected one entry per thruster"):
        configuration_matrix([0.0, 1.0], [1.0, 2.0, 3.0], [0.0, 0.0, 0.0])


def test_propeller_states_given_as_text_or_in_shapes_that_do_not_broadcast_are_refused_by_name():
    """A shaft speed of "100" was read as 100 rev/s (73.8 MN of thrust) and a demand of "1e4" as
    the number; shapes that do not broadcast failed in numpy's words ("arg 0 ... arg 1")."""
    p = load_wageningen()
    for args, match in ((("100", 0.0), "^n_rps: expected an array of real numbers"),
                        ((1.0, ["0.5"]), "^va_m_s: expected an array of real numbers"),
                        ((1.0 + 0j, 0.0), "^n_rps: expected an array of real numbers")):
        with pytest.raises(TypeError, match=match):
            thrust_torque(*args, 1.9, p)
    with pytest.raises(TypeError, match="^thrust_N: expected an array of real numbers"):
        rpm_for_thrust("1e4", 0.0, 1.9, p)
    with pytest.raises(ValueError, match=r"^n_rps, va_m_s: shapes \(3,\) and \(4,\) do not broadcast"):
        thrust_torque(np.ones(3), np.ones(4), 1.9, p)
    with pytest.raises(ValueError, match=r"^thrust_N, va_m_s: shapes \(3,\) and \(2,\) do not broadcast"):
        rpm_for_thrust(np.ones(3), np.ones(2), 1.9, p)
    with pytest.raises(ValueError, match="^thrust_N: contains NaN"):
        rpm_for_thrust([1e4, np.nan], 0.0, 1.9, p)
    t, q = thrust_torque(np.array([[1.0], [2.0]]), np.array([0.0, 1.0, 2.0]), 1.9, p)
    assert t.shape == q.shape == (2, 3)


def test_physics_inputs_with_rows_of_different_lengths_are_refused_by_name(gunnerus):
    """Ragged rows failed in numpy's words ("setting an array element with a sequence ...
    inhomogeneous shape"), naming no argument."""
    from hybridship.physics.rudder import rudder_forces

    m = gunnerus
    for kw, name in ((dict(rpm=[[100.0, 0.0, 0.0], [100.0]]), "rpm"), (dict(wind=[[5.0, 0.0], [5.0]]), "wind"),
                     (dict(current=[0.5, [0.0]]), "current")):
        with pytest.raises(ValueError, match=f"^{name}: expected an array of numbers, got rows of different"):
            m.acceleration(np.zeros((2, 3)), np.zeros(3), **kw)
    with pytest.raises(ValueError, match="^eta0: expected an array of numbers, got rows of different lengths"):
        m.rollout([[0.0, 0.0, 0.0], [0.0, 0.0]], np.zeros(3), 2)
    esso = DynamicModel("esso_osaka_model")
    with pytest.raises(ValueError, match="^nu_r: expected an array of numbers, got rows of different lengths"):
        rudder_forces(esso, [[0.3, 0.0, 0.0], [0.3]], [0.1])
    # the settings' array fields convert through the same function: the field is named once
    from hybridship.residual.calibration import SpreadCalibration

    with pytest.raises(ValueError, match="^scale: expected an array of numbers, got rows of different lengths"):
        SpreadCalibration(lead_s=[0.0, 1.0], scale=[[1.0, 1.0], [1.0]], floor=[0.0, 0.0])


def test_propeller_coefficients_and_the_configuration_matrix_refuse_text_naming_the_argument():
    """numpy read text as the number: kt_kq("0.3") gave K_T at J = 0.3, an advance angle "1"
    was 1 rad, a thrust direction "1.57" was 1.57 rad."""
    from hybridship.physics.propeller import advance_angle

    p = load_wageningen()
    for call, name in ((lambda: kt_kq("0.3", p), "J"), (lambda: ct_cq_star(["1.0"], p), "beta_rad"),
                       (lambda: advance_angle("1.0", 5.0, 1.9), "va_m_s"),
                       (lambda: advance_angle(1.0, "5", 1.9), "n_rps"),
                       (lambda: configuration_matrix(["1.57"], [1.0], [0.0]), "alpha_rad"),
                       (lambda: configuration_matrix([1.57], ["1"], [0.0]), "x_m"),
                       (lambda: configuration_matrix([1.57], [1.0], [0j]), "y_m")):
        with pytest.raises(TypeError, match=f"^{name}: expected an array of real numbers"):
            call()
    np.testing.assert_allclose(kt_kq(np.float32(0.3), p), kt_kq(0.3, p), rtol=1e-6)   # numpy numbers are taken


def test_thrust_torque_pairs_its_inputs_element_by_element_as_its_docstring_says():
    """The docstring promised 'every combination of shaft speed and inflow' (an outer product);
    the arrays are broadcast, so two 1-D arrays of one length give one thrust per pair."""
    p = load_wageningen()
    n, va = np.array([2.0, 3.0, 4.0]), np.array([0.0, 1.0, 2.0])
    t, _ = thrust_torque(n, va, 1.9, p)
    assert t.shape == (3,)
    np.testing.assert_array_equal(t, [thrust_torque(a, b, 1.9, p)[0] for a, b in zip(n, va)])
    assert "every combination of shaft speed" not in thrust_torque.__doc__
    assert "broadcast together" in thrust_torque.__doc__.splitlines()[0]


def test_load_wageningen_refuses_a_pitch_ratio_that_is_not_a_number_naming_it():
    for bad in ("1.0", None, "x", True):
        with pytest.raises(TypeError, match="^pitch_ratio: expected a number"):
            load_wageningen("B4-70", bad)
    assert load_wageningen("B4-70", np.float32(0.8)).pitch_ratio == pytest.approx(0.8)


def test_step_broadcasts_one_state_and_refuses_mismatched_batches_and_bad_steps(gunnerus):
    """The compiled step reads B rows of every state: a batch of the other size is refused
    (it used to read memory past the array), one state is broadcast as in acceleration, and
    the step settings are checked as rollout's are."""
    eta = np.array([[0.0, 0.0, 0.0], [100.0, 100.0, 1.0]])
    nu = np.array([1.0, 0.5, 0.01])
    _, nu_next = gunnerus.step(eta, nu)
    np.testing.assert_array_equal(nu_next[0], nu_next[1])         # heading does not enter the hull's loads
    np.testing.assert_array_equal(nu_next[0], gunnerus.step(eta[0], nu)[1][0])
    with pytest.raises(ValueError, match="eta, nu: batches of 2 and 3 states"):
        gunnerus.step(eta, np.zeros((3, 3)))
    for kw, field in ((dict(dt_s=np.nan), "dt_s"), (dict(dt_s="1"), "dt_s"), (dict(dt_s=0.0), "dt_s"),
                      (dict(substeps=0), "substeps"), (dict(substeps=-2), "substeps"), (dict(substeps=1.5), "substeps")):
        with pytest.raises(ValueError, match=f"^{field}: "):
            gunnerus.step(eta, nu, **kw)
    for n_steps in (2.7, "10", 0, True):
        with pytest.raises(ValueError, match="^n_steps: "):
            gunnerus.rollout(eta, np.zeros((2, 3)), n_steps)


def test_rollout_with_per_step_inputs_equals_chained_steps(gunnerus):
    """Inputs are held within an output step and change between steps: a rollout whose current,
    wind, shaft speeds and azimuths change every step equals ``step`` called once per step with
    that step's inputs."""
    rng = np.random.default_rng(11)
    S = 12
    rpm = rng.uniform(-100, 200, (1, S, 3))
    az = rng.uniform(-np.pi, np.pi, (1, S, 3))
    wind = np.stack([rng.uniform(0, 15, (1, S)), rng.uniform(-np.pi, np.pi, (1, S))], axis=-1)
    current = np.stack([rng.uniform(0, 1.5, (1, S)), rng.uniform(-np.pi, np.pi, (1, S))], axis=-1)
    eta, nu = np.array([[5.0, -3.0, 0.4]]), np.array([[1.0, 0.2, 0.01]])
    kw = dict(dt_s=2.0, substeps=2)
    res = gunnerus.rollout(eta, nu, S, rpm=rpm, azimuth_rad=az, wind=wind, current=current, **kw)
    for j in range(S):
        eta, nu = gunnerus.step(eta, nu, rpm=rpm[:, j], azimuth_rad=az[:, j], wind=wind[:, j],
                                current=current[:, j], **kw)
        np.testing.assert_allclose(res.eta[:, j + 1], eta, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(res.nu[:, j + 1], nu, rtol=1e-12, atol=1e-14)


# ----------------------------------------------------------------------------- vessel files


def test_gunnerus_coefficients_close_to_published_original_hull():
    """Derived added mass has the published (original, 15 % shorter hull) magnitudes."""
    m = DynamicModel("gunnerus")
    M_A = m.arrays.m_a
    assert 0.5 < M_A[0, 0] / 79320.6 < 2.0      # X_udot
    assert 0.7 < M_A[1, 1] / 408192.6 < 1.5     # Y_vdot
    assert 0.7 < M_A[2, 2] / 12245783.9 < 1.5   # N_rdot
    # cross-flow drag per |v|v vs published Y_|v|v (original hull), same order
    assert 0.8 < m.arrays.strip_w.sum() / 21640.7 < 2.5


#: Linear hull derivatives on the MMG basis (those of the KVLCC2 in the Esso Osaka file).
MMG_TABLE = {"Y_v": -0.315, "Y_r": 0.083, "N_v": -0.137, "N_r": -0.049}


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["particulars"].pop("B_m"), "particulars.B_m"),
    # L_oa and L_pp swapped: the wind moment's default length would be the shorter one
    (lambda d: d["particulars"].update(L_oa_m=33.9, L_pp_m=36.25), r"particulars: L_oa_m: 33.9 m is shorter than "
                                                                  r"L_pp_m = 36.25 m"),
    (lambda d: d["thrusters"][1].__setitem__("diameter_m", -1.9), r"thrusters\[1\].diameter_m"),
    (lambda d: d.__setitem__("added_mass", {"method": "explicit", "X_udot_kg": 1e7, "Y_vdot_kg": -1e5,
                                            "Y_rdot_kg_m": 0, "N_vdot_kg_m": 0, "N_rdot_kg_m2": -1e6}),
     "not positive definite"),
    (lambda d: d["damping"]["linear"].pop("T_yaw_s"), "T_yaw_s"),
    (lambda d: d["thrusters"][0].__setitem__("type", "propeller"), r"thrusters\[0\].type"),
    (lambda d: d.__setitem__("format_version", 99), "format_version"),
    (lambda d: d["particulars"].__setitem__("L_pp_m", "long"), "particulars.L_pp_m"),
    (lambda d: d["thrusters"][2].__setitem__("name", "port"), "duplicate"),
    (lambda d: d["damping"]["nonlinear"].__setitem__("lift_speed", "sign"), "damping.nonlinear.lift_speed"),
    # with no lift terms the option was ignored (the file said 'signed', the model was the default)
    (lambda d: d["damping"]["nonlinear"].update(lift="none", lift_speed="signed"),
     r"damping.nonlinear: lift_speed: 'signed' given with lift 'none', which has no lift terms"),
    (lambda d: d["thrusters"][0].__setitem__("x_m", 1444.0), r"thrusters\[0\].x_m: 1444 m lies outside the hull"),
    (lambda d: d["thrusters"][1].__setitem__("y_m", -27.0), r"thrusters\[1\].y_m: -27 m lies outside the hull"),
    # beyond the side (half the beam, 9.6 m on the Gunnerus) and beyond the bow: refused too
    (lambda d: d["thrusters"][1].__setitem__("y_m", -7.0), r"thrusters\[1\].y_m: -7 m lies outside the hull \(at "
                                                          r"most half of particulars.B_m"),
    (lambda d: d["thrusters"][0].__setitem__("x_m", 20.0), r"thrusters\[0\].x_m: 20 m lies outside the hull \(from"),
    (lambda d: d["thrusters"][0].__setitem__("diameter_m", 1900.0), r"thrusters\[0\].diameter_m: 1900 m is wider"),
    (lambda d: d["thrusters"][0].__setitem__("propeller_series", "B4-75"), r"thrusters\[0\].*B4-75.*available"),
    (lambda d: d["rigid_body"].__setitem__("mass_kg", float("inf")), "rigid_body.mass_kg: .*finite"),
    (lambda d: d["rigid_body"].__setitem__("mass_kg", 500.0), r"rigid_body.mass_kg: .*a mass in tonnes"),
    # a yaw inertia no mass within the hull gives (a slipped decimal point), or one in t m^2: accepted
    (lambda d: d["rigid_body"].__setitem__("r_z_m", 84.75), r"rigid_body.r_z_m: .*84.75 m, more than "
                                                           r"0.5 sqrt\(L_oa_m\^2 \+ B_m\^2\) = 18.75 m"),
    (lambda d: d["rigid_body"].update(r_z_m=None, I_z_kg_m2=574130.0 * 8.475**2 / 1000),  # kg m^2 / 1000
     r"rigid_body.I_z_kg_m2: .*radius of gyration of 0.268 m, less than 0.1 L_pp .*t m\^2"),
    (lambda d: d["rigid_body"].update(r_z_m=None, I_z_kg_m2=1e6, x_g_m=2.0),
     r"rigid_body.I_z_kg_m2: .*is below m x_g\^2"),
    # Clarke's regressions on Gunnerus's beamy hull: an added-mass matrix that stores negative energy
    (lambda d: d.__setitem__("added_mass", {"method": "clarke1983"}),
     r"added_mass: M_A is not positive definite .*method 'explicit'"),
    (lambda d: d["wind"]["table"].__setitem__("C_X", d["wind"]["table"]["C_X"][:-1]), "C_X: .* coefficients for"),
    (lambda d: d["thrusters"][0].__setitem__("angle_deg", -90.0), r"thrusters\[0\]: angle_deg: a tunnel thruster's"),
    # angles in radians (0..3.14): found when the file is read, not at the first simulation
    (lambda d: d["wind"]["table"].__setitem__("angle_deg", list(np.radians(d["wind"]["table"]["angle_deg"]))),
     r"wind.table: angle_deg: must span 0..180"),
    # booleans and quoted numbers were read as numbers (x_m = true as 1.0 m), silently
    (lambda d: d["thrusters"][0].__setitem__("x_m", True), r"thrusters\[0\].x_m: expected a number, got True"),
    (lambda d: d["rigid_body"].__setitem__("mass_kg", "600000"), r"rigid_body.mass_kg: expected a number, got '600000'"),
    (lambda d: d.__setitem__("format_version", "1"), r"format_version: expected an integer, got '1'"),
    (lambda d: d["damping"]["linear"].__setitem__("T_surge_s", "1000"), r"damping.linear.T_surge_s: expected a number"),
    # a ragged or text D: numpy's "setting an array element with a sequence", pydantic's "valid list"
    (lambda d: d["damping"].__setitem__("linear", {"method": "explicit", "D": [[1e4, 0, 0], [0, 1e4]]}),
     r"damping.linear.D: expected a 3x3 matrix"),
    (lambda d: d["damping"].__setitem__("linear", {"method": "explicit", "D": "diag(1e4)"}),
     r"damping.linear.D: expected a 3x3 matrix"),
    # an unknown Blendermann type was accepted here and refused only when a model was built
    (lambda d: d.__setitem__("wind", {"method": "blendermann", "A_F_m2": 81.0, "A_L_m2": 180.0,
                                      "blendermann": {"vessel_type": "trawler", "s_L_m": 0.0}}),
     r"bad.toml: wind.blendermann.vessel_type: unknown Blendermann vessel type 'trawler'; valid names"),
    # an empty name was accepted and then named nothing in messages and model files
    (lambda d: d.__setitem__("name", "  "), r"bad.toml: name: must not be empty"),
    (lambda d: d["thrusters"][0].__setitem__("name", "Bow 1"),
     r"thrusters\[0\].name: expected text matching \^\[a-z\]"),
    # values the chosen method does not use were accepted and ignored
    (lambda d: d["added_mass"].__setitem__("method", "clarke1983"),
     r"bad.toml: added_mass: X_udot_kg, Y_vdot_kg, Y_rdot_kg_m, N_vdot_kg_m, N_rdot_kg_m2: given with method "
     r"'clarke1983', which derives them"),
    (lambda d: d["damping"]["linear"].__setitem__("D", [[1e4, 0, 0], [0, 1e4, 0], [0, 0, 1e6]]),
     r"bad.toml: damping.linear: D: given with method 'time_constants', which derives it"),
    (lambda d: d["damping"].__setitem__("linear", {"method": "explicit", "D": [[1e4, 0, 0], [0, 1e4, 0], [0, 0, 1e6]],
                                                   "T_yaw_s": 50.0}),
     r"bad.toml: damping.linear: T_yaw_s: given with method 'explicit', which does not use it"),
    (lambda d: d["damping"].__setitem__("nonlinear", {"method": "none", "d_uu": 5000.0, "d_rr": 1e8}),
     r"bad.toml: damping.nonlinear: d_uu, d_rr: given with method 'none', which has no nonlinear damping"),
    (lambda d: d["wind"].update(method="isherwood", isherwood={"A_SS_m2": 60.0, "S_m": 80.0, "C_m": 15.0, "M": 1}),
     r"bad.toml: wind: \[wind.table\]: given with method 'isherwood', which does not use it"),
    (lambda d: d["thrusters"][0].__setitem__("max_azimuth_rate_deg_s", 10.0),
     r"bad.toml: thrusters\[0\]: max_azimuth_rate_deg_s: a tunnel thruster does not turn"),
    # an MMG table without lift = "mmg" (lift left at its default "none") gave no lift at all
    (lambda d: d["damping"]["nonlinear"].update(mmg=MMG_TABLE),
     r"bad.toml: damping.nonlinear: \[damping.nonlinear.mmg\]: given with lift 'clarke1983', which does not use it"),
    (lambda d: d["damping"]["nonlinear"].update(lift="none", mmg=MMG_TABLE),
     r"bad.toml: damping.nonlinear: \[damping.nonlinear.mmg\]: given with lift 'none', which does not use it"),
    # the packaged file switched to method 'quadratic' kept its ITTC and strip fields: no nonlinear damping at all
    (lambda d: d["damping"]["nonlinear"].update(method="quadratic"),
     r"bad.toml: damping.nonlinear: wetted_surface_m2, form_factor_k, C_R, speed_ref_m_s: given with method "
     r"'quadratic', which does not use them \(the ITTC-1957 surge resistance and the strips of method 'crossflow'\)"),
    (lambda d: d["damping"].__setitem__("nonlinear", {"method": "none", "cd_2d": 0.7}),
     r"bad.toml: damping.nonlinear: cd_2d: given with method 'none', which does not use it"),
    (lambda d: d["damping"]["nonlinear"].update(surge_resistance="explicit", d_uu=1000.0),
     r"bad.toml: damping.nonlinear: wetted_surface_m2, form_factor_k, C_R, speed_ref_m_s: given with "
     r"surge_resistance 'explicit', which does not use them \(the surge resistance is d_uu\)"),
])
def test_invalid_vessel_files_name_the_field(edit, field):
    d = copy.deepcopy(gunnerus_dict())
    edit(d)
    with pytest.raises(VesselFileError, match=field):
        vessel_from_dict(d, "bad.toml")


def test_unknown_vessel_and_bad_toml(tmp_path):
    with pytest.raises(VesselFileError, match="packaged"):
        load_vessel("no_such_ship")
    f = tmp_path / "x.toml"
    f.write_text("name = [")
    with pytest.raises(VesselFileError, match="not valid TOML"):
        load_vessel(f)
    with pytest.raises(VesselFileError, match="planing-craft file"):
        load_vessel("volcano71")
    model_file = tmp_path / "m.npz"                 # a model file given where a vessel file goes
    model_file.write_bytes(b"PK\x03\x04\x8a\xff binary")
    with pytest.raises(VesselFileError, match="not a vessel file .* a model file .* carries its vessel"):
        load_vessel(model_file)
    # a folder (named like a file or not) exists: it was reported as 'vessel file not found'
    for folder in (tmp_path, tmp_path / "ship.toml"):
        folder.mkdir(exist_ok=True)
        with pytest.raises(VesselFileError, match=r": is a folder; expected a vessel file \(\.toml\)$"):
            load_vessel(folder)
    with pytest.raises(VesselFileError, match="other.toml: vessel file not found$"):
        load_vessel(tmp_path / "other.toml")


def test_rollout_refuses_commands_it_is_not_meant_for_and_never_returns_nan():
    """The public physics API checks what the forecasts check: a unit error in rpm, a rudder
    angle in degrees, NaN commands; and a rollout that diverges raises instead of
    returning NaN."""
    m = DynamicModel("gunnerus")
    zeros = np.zeros((1, 3))
    for rpm, match in (([[2e4, 0, 0]], r"rpm: 20000 rpm for thruster 'tunnel' is above 2 x its max_rpm"),
                       ([[np.nan, 0, 0]], "rpm: contains NaN")):
        with pytest.raises(ValueError, match=match):
            m.rollout(zeros, zeros, 5, rpm=rpm, azimuth_rad=[[0, 0, 0]])
    with pytest.raises(ValueError, match="rudder_rad: 20 rad is beyond 90 deg"):
        DynamicModel("esso_osaka_model").rollout(zeros, zeros, 5, rudder_rad=[[20.0]])
    with pytest.raises(FloatingPointError, match="rollout diverged at step"):
        m.rollout(zeros, [[3.0, 1.0, 0.1]], 20, dt_s=50.0, rpm=[[400, 400, 400]], azimuth_rad=[[0, 0, 0]])
    ok = m.rollout(zeros, zeros, 20, rpm=[[400, 400, 400]], azimuth_rad=[[0, 0, 0]])   # at max_rpm: fine
    assert np.isfinite(ok.eta).all()
    # review: acceleration returned NaN for velocities beyond the model's range, and took
    # per-step commands, using the first step alone
    with pytest.raises(FloatingPointError, match="acceleration: not finite for these inputs"):
        m.acceleration(np.zeros(3), [1e155, 1e155, 0.0])
    for call in (m.acceleration, m.step):
        with pytest.raises(ValueError, match=r"rpm: expected shape \(3,\), \(B, 3\) with B = 1, got \(1, 5, 3\)"):
            call(np.zeros(3), np.zeros(3), rpm=np.zeros((1, 5, 3)))


def test_a_validator_message_that_names_its_field_is_not_put_under_top_level():
    d = copy.deepcopy(gunnerus_dict())
    d["added_mass"] = {"method": "clarke1983"}
    with pytest.raises(VesselFileError) as err:
        vessel_from_dict(d, "bad.toml")
    assert str(err.value).startswith("bad.toml: added_mass: M_A is not positive definite")


def test_yaw_inertia_from_the_radius_of_gyration_includes_the_cg_offset():
    """``r_z_m`` is the radius of gyration about the CG, so about the body origin (parallel axes)
    ``I_z = m (r_z^2 + x_g^2)`` (vessel-file reference) and ``M_RB`` has ``m x_g`` off the diagonal
    (Fossen 2021, eq. 3.44): the Esso Osaka model, CG 0.094 m forward of its origin."""
    rb = tomllib.loads(packaged_vessel_text("esso_osaka_model"))["rigid_body"]
    m = DynamicModel("esso_osaka_model")
    mass, xg = rb["mass_kg"], rb["x_g_m"]
    assert xg != 0.0
    np.testing.assert_allclose(m.mass_matrix - m.arrays.m_a,
                               [[mass, 0, 0], [0, mass, mass * xg], [0, mass * xg, mass * (rb["r_z_m"]**2 + xg**2)]],
                               rtol=1e-9, atol=1e-9)


def test_true_vessel_scales_thrust_and_lift_by_the_files_factors(gunnerus):
    """``[true_vessel]``: every delivered thrust is ``thrust_scale`` times the model's (bollard:
    ``s (1 - t) K_T0 rho n^2 D^4``), and the lift terms of the sway equation (d_vv, d_vr) scale
    with the sway factor, those of the yaw equation (d_rv, d_rr) with the yaw factor of
    ``nonlinear_damping_scale`` (vessel-file reference)."""
    d = gunnerus_dict()
    tv = d["true_vessel"]
    true = DynamicModel("gunnerus", true_vessel=True)
    rpm = np.array([300.0, 150.0, 120.0])
    _, _, thrusts = true.acceleration([0, 0, 0], [0, 0, 0], rpm=rpm, azimuth_rad=[0, 0.5, -1.0], return_parts=True)
    kt0, rho = load_wageningen().kt0, d["particulars"]["rho_water_kg_m3"]     # B4-70 P/D 1 (the file's default)
    for k, t in enumerate(d["thrusters"]):
        bollard = (1 - t.get("thrust_deduction", 0.0)) * kt0 * rho * (rpm[k] / 60) ** 2 * t["diameter_m"] ** 4
        assert thrusts[0, k] == pytest.approx(tv["thrust_scale"] * bollard, rel=1e-9), t["name"]
    s = tv["nonlinear_damping_scale"]
    np.testing.assert_allclose(true.arrays.d_lift[:4], gunnerus.arrays.d_lift[:4] * [s[1], s[1], s[2], s[2]],
                               rtol=1e-12)
