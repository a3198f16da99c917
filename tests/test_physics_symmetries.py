"""The whole model (hull, thrusters, propeller, rudder, wind, current, RK4 kinematics) against
closed-form solutions and the symmetries of the problem: linear plus quadratic free decay and the
steady velocity under a constant load, rotating or mirroring the whole problem, reversing time in
the conservative motion, and the steady turn being a circle of radius U / |r|.

The other closed forms (linear and quadratic decay alone, steady speed under thrust) and the
current's Galilean invariance are in ``test_physics_invariants.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybridship import frames
from hybridship.physics.model import DynamicModel

from conftest import decoupled_model, model_from, vessel_dict


LIN = {"method": "time_constants", "T_surge_s": 200.0, "T_sway_s": 100.0, "T_yaw_s": 50.0}
QUAD = {"method": "quadratic", "d_uu": 3000.0, "d_vv": 2.0e4, "d_rr": 2.0e7}


# ----------------------------------------------------------------------------- closed forms


def _decoupled_by_hand() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The inertia and damping of ``decoupled_model(LIN, QUAD)`` from the Gunnerus file, by hand.

    Returns
    -------
    M : ndarray, shape (3,)
        ``M_ii`` [kg, kg, kg m^2]: ``m - X_udot``, ``m - Y_vdot``, ``m r_z^2 - N_rdot`` (CG at the
        origin, so ``I_z = m r_z^2``; no sway-yaw coupling).
    d_l : ndarray, shape (3,)
        Linear damping ``M_ii / T_i`` [kg/s, kg/s, kg m^2/s] from LIN's time constants.
    d_q : ndarray, shape (3,)
        Quadratic damping [kg/m, kg/m, kg m^2] from QUAD.
    """
    d = vessel_dict("gunnerus")
    rb, am = d["rigid_body"], d["added_mass"]
    assert "I_z_kg_m2" not in rb and am["method"] == "explicit"
    m = rb["mass_kg"]
    M = np.array([m - am["X_udot_kg"], m - am["Y_vdot_kg"], m * rb["r_z_m"] ** 2 - am["N_rdot_kg_m2"]])
    T = np.array([LIN["T_surge_s"], LIN["T_sway_s"], LIN["T_yaw_s"]])
    return M, M / T, np.array([QUAD["d_uu"], QUAD["d_vv"], QUAD["d_rr"]])


def test_linear_plus_quadratic_free_decay_has_its_closed_form():
    """``M x_dot = -d_l x - d_q |x| x`` (a = d_l / M, b = d_q / M) has, for either sign of x_0,
    ``x(t) = a x_0 e^(-a t) / (a + b |x_0| (1 - e^(-a t)))`` and the travelled distance
    ``sgn(x_0) ln(1 + b |x_0| (1 - e^(-a t)) / a) / b``; in surge, sway and yaw alike."""
    m = decoupled_model(LIN, QUAD)
    M, d_l, d_q = _decoupled_by_hand()     # the file's numbers, not the model's arrays
    for i, x0 in enumerate((3.0, 1.0, 0.05)):
        nu0 = np.zeros((2, 3))
        nu0[:, i] = [x0, -x0]
        res = m.rollout(np.zeros((2, 3)), nu0, 300, dt_s=1.0)
        a, b, t = d_l[i] / M[i], d_q[i] / M[i], res.time_s
        assert 0.5 < b * x0 / a < 20         # both terms matter over the run
        decay = 1.0 - np.exp(-a * t)
        x = a * x0 * np.exp(-a * t) / (a + b * x0 * decay)
        dist = np.log1p(b * x0 * decay / a) / b
        for k, s in enumerate((1.0, -1.0)):
            # RK4 with 1 s steps: observed relative error <= 7e-8; a wrong mass, a time constant
            # turned into D_ii with another mass than M_ii, a missing linear or quadratic term, or
            # a |x| x written x^2 are off by far more
            np.testing.assert_allclose(res.nu[k, :, i], s * x, rtol=1e-6)
            np.testing.assert_allclose(res.eta[k, :, i], s * dist, rtol=1e-6, atol=1e-12)
            np.testing.assert_array_equal(np.delete(res.nu[k], i, axis=1), 0.0)
            # the acceleration recorded at sample j is the equation's right-hand side at sample j's
            # velocity (rounding only, observed 4e-16 of it); one recorded after the step would
            # belong to sample j + 1 and miss by (a + b |x|) dt, up to 3 % here
            xs = res.nu[k, :, i]
            np.testing.assert_allclose(res.nu_dot[k, :, i], -(d_l[i] * xs + d_q[i] * np.abs(xs) * xs) / M[i],
                                       rtol=1e-12)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_constant_load_gives_the_steady_velocity_of_the_damping_balance(sign):
    """A constant external load tau in one DOF: ``d_l x* + d_q |x*| x* = tau``, so
    ``x* = sgn(tau) (-d_l + sqrt(d_l^2 + 4 d_q |tau|)) / (2 d_q)``, and the acceleration is 0 there.
    The same load given as the external acceleration ``accel_ext = tau / M_ii`` (the hybrid's
    correction, added to nu_dot after M^-1) settles at the same x*."""
    m = decoupled_model(LIN, QUAD)
    M, d_l, d_q = _decoupled_by_hand()
    for i, load in enumerate((2.0e4, 1.0e4, 5.0e5)):
        tau = np.zeros(3)
        tau[i] = sign * load
        x_star = sign * (-d_l[i] + math.sqrt(d_l[i] ** 2 + 4 * d_q[i] * load)) / (2 * d_q[i])
        expected = np.zeros(3)
        expected[i] = x_star
        # an acceleration taken for a load (multiplied by M^-1 again) is M_ii times too weak: x* near 0
        for kw in (dict(tau_ext=tau), dict(accel_ext=tau / M)):
            res = m.rollout(np.zeros(3), np.zeros(3), 1, dt_s=3000.0, substeps=3000, **kw)
            np.testing.assert_allclose(res.nu[0, -1], expected, rtol=1e-10, atol=1e-14)
            np.testing.assert_allclose(res.nu_dot[0, -1], 0.0, atol=1e-12)


# ----------------------------------------------------------------------------- symmetries


def _random_problem(m: DynamicModel, B: int, seed: int) -> tuple[np.ndarray, np.ndarray, dict]:
    rng = np.random.default_rng(seed)
    K, R = m.n_thrusters, m.n_rudders
    eta = rng.normal(scale=[50.0, 50.0, 3.0], size=(B, 3))
    scale = [1.5, 0.4, 0.03] if m.vessel.particulars.L_pp_m > 10 else [0.4, 0.08, 0.05]
    nu = rng.normal(scale=scale, size=(B, 3))
    kw = dict(rpm=rng.uniform(-1, 1, (B, K)) * [t.max_rpm for t in m.vessel.thrusters],
              azimuth_rad=rng.uniform(-np.pi, np.pi, (B, K)),
              wind=np.column_stack([rng.uniform(0, 20, B), rng.uniform(-np.pi, np.pi, B)]),
              current=np.column_stack([rng.uniform(0, 1.0, B) * scale[0], rng.uniform(-np.pi, np.pi, B)]))
    if R:
        kw["rudder_rad"] = rng.uniform(-0.6, 0.6, (B, R))
    return eta, nu, kw


@pytest.mark.parametrize("name", ["gunnerus", "esso_osaka_model"])
def test_rotating_the_whole_problem_rotates_the_solution(name):
    """Turn the NED frame by theta: positions rotate, the heading and the directions of wind and
    current grow by theta, and the body-frame motion is unchanged (the loads depend on the
    velocities in body axes only). Catches a flow direction or a heading used with the wrong
    sign, or an NED component used where a body one belongs."""
    m = DynamicModel(name)
    eta, nu, kw = _random_problem(m, 12, seed=7)
    theta = 1.234
    Rz = frames.rotation_z(theta)[:2, :2]
    eta_rot = np.column_stack([eta[:, :2] @ Rz.T, eta[:, 2] + theta])
    kw_rot = dict(kw, wind=kw["wind"] + [0.0, theta], current=kw["current"] + [0.0, theta])
    a = m.acceleration(eta, nu, **kw)
    a_rot = m.acceleration(eta_rot, nu, **kw_rot)
    np.testing.assert_array_less(np.abs(a_rot - a), np.broadcast_to(1e-12 * np.abs(a).max(axis=0), a.shape))
    res = m.rollout(eta, nu, 40, dt_s=0.5, **kw)
    res_rot = m.rollout(eta_rot, nu, 40, dt_s=0.5, **kw_rot)
    np.testing.assert_allclose(res_rot.eta[..., :2], res.eta[..., :2] @ Rz.T, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res_rot.eta[..., 2], res.eta[..., 2] + theta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res_rot.nu, res.nu, rtol=0, atol=1e-12)


def _mirror_symmetric(name: str) -> DynamicModel:
    """A port/starboard symmetric version of a packaged vessel: Gunnerus without its tunnel
    thruster (a B-series propeller is not odd in (n, V_a), so a lateral thruster is not mirror
    symmetric), the Esso Osaka model with equal flow straightening on both sides."""
    d = vessel_dict(name)
    if name == "gunnerus":
        d["thrusters"] = [t for t in d["thrusters"] if t["type"] != "tunnel"]
    else:
        d["rudders"][0]["flow_straightening_pos"] = d["rudders"][0]["flow_straightening_neg"]
    return model_from(d)


@pytest.mark.parametrize("name", ["gunnerus", "esso_osaka_model"])
def test_mirroring_the_problem_mirrors_the_solution(name):
    """Reflect the problem in the north axis: east, heading, sway, yaw rate, the flow directions,
    the azimuth and rudder angles change sign and the port and starboard thrusters swap. A
    symmetric ship must then move as the mirror image, ``nu_dot -> [u_dot, -v_dot, -r_dot]``.
    This checks the parity of every load (C_X even, C_Y and C_N odd in the wind angle; a rudder,
    thruster or hull term odd or even as it must be), e.g. the Blendermann C_N written with the
    signed angle in its bracket; a sign convention applied consistently on both sides (which way
    is starboard) is the hand-case tests' job."""
    m = _mirror_symmetric(name)
    ys = np.array([t.y_m for t in m.vessel.thrusters])
    swap = np.array([int(np.flatnonzero(np.isclose(ys, -y))[0]) for y in ys])   # the mirror twin
    eta, nu, kw = _random_problem(m, 30, seed=11)
    flip = np.array([1.0, -1.0, -1.0])
    kw_m = dict(rpm=kw["rpm"][:, swap], azimuth_rad=-kw["azimuth_rad"][:, swap],
                wind=kw["wind"] * [1.0, -1.0], current=kw["current"] * [1.0, -1.0])
    if "rudder_rad" in kw:
        kw_m["rudder_rad"] = -kw["rudder_rad"]
    a = m.acceleration(eta, nu, **kw)
    a_m = m.acceleration(eta * flip, nu * flip, **kw_m)
    assert np.all(np.abs(a).max(axis=0) > 1e-3)                   # every DOF is exercised
    np.testing.assert_array_less(np.abs(a_m - a * flip), np.broadcast_to(1e-12 * np.abs(a).max(axis=0), a.shape))
    res = m.rollout(eta, nu, 40, dt_s=0.5, **kw)
    res_m = m.rollout(eta * flip, nu * flip, 40, dt_s=0.5, **kw_m)
    np.testing.assert_allclose(res_m.eta, res.eta * flip, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res_m.nu, res.nu * flip, rtol=0, atol=1e-12)


def test_the_conservative_motion_retraces_its_path_when_time_is_reversed():
    """No damping, no actuators, no wind: ``nu_dot = -M^-1 C(nu) nu`` is quadratic in nu and
    ``eta_dot = R(psi) nu`` linear, so (eta, nu, t) -> (eta, -nu, -t) maps solutions onto
    solutions. Run forward, reverse the velocity, run forward again: the ship retraces its
    path and returns to its start with the velocity reversed (to RK4's error)."""
    d = vessel_dict("gunnerus")
    d["damping"] = {"linear": {"method": "explicit", "D": np.zeros((3, 3)).tolist()},
                    "nonlinear": {"method": "none"}}
    d.update(wind={"method": "none"}, thrusters=[])
    d["rigid_body"]["x_g_m"] = 1.5          # the off-diagonal C_RB terms too
    m = model_from(d)
    eta0, nu0 = np.array([[3.0, -4.0, 0.3]]), np.array([[1.0, 0.4, 0.03]])
    fwd = m.rollout(eta0, nu0, 400, dt_s=0.5)
    assert np.ptp(fwd.nu[0, :, 1]) > 0.1 and np.ptp(fwd.eta[0, :, 2]) > 0.5     # not a trivial motion
    back = m.rollout(fwd.eta[:, -1], -fwd.nu[:, -1], 400, dt_s=0.5)
    # observed 5e-7 m after 400 m of track, 5e-9 m/s; a C(nu) nu that is not even in nu
    # (a term linear in nu) or a kinematics sign error misses by metres
    np.testing.assert_allclose(back.eta[0, ::-1], fwd.eta[0], rtol=0, atol=1e-5)
    np.testing.assert_allclose(back.nu[0, ::-1], -fwd.nu[0], rtol=0, atol=1e-7)


def test_a_steady_turn_is_a_circle_of_radius_speed_over_yaw_rate():
    """Gunnerus at 150 rpm with the starboard azimuth at +20 deg settles into a steady turn
    (the bow to port, r < 0); then nu is constant and the track is a circle of radius U / |r|
    about a fixed centre ``p + (U / r) [-sin chi, cos chi]``, chi = psi + atan2(v, u) the course."""
    m = DynamicModel("gunnerus")
    res = m.rollout([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], 900, dt_s=1.0, substeps=2, rpm=[0.0, 150.0, 150.0],
                    azimuth_rad=[0.0, 0.0, math.radians(20.0)])
    nu = res.nu[0, -300:]
    assert np.ptp(nu, axis=0).max() < 1e-8                        # steady (observed 1e-10)
    u, v, r = nu[-1]
    assert r < -0.01 and u > 1.0                                   # a real turn, to port
    U = math.hypot(u, v)
    eta = res.eta[0, -300:]
    chi = eta[:, 2] + math.atan2(v, u)
    centre = eta[:, :2] + (U / r) * np.column_stack([-np.sin(chi), np.cos(chi)])
    assert np.ptp(centre, axis=0).max() < 1e-6                     # a fixed centre (observed 8e-9 m)
    radius = np.hypot(*(eta[:, :2] - centre.mean(axis=0)).T)
    np.testing.assert_allclose(radius, U / abs(r), rtol=1e-8)
    # and the heading grows at the yaw rate
    np.testing.assert_allclose(np.diff(eta[:, 2]), r * 1.0, rtol=1e-8)
