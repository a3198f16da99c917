"""Physics checked against what it must satisfy whatever the coefficients: invariants (current,
energy, dissipation, skew Coriolis matrices, angle ranges), closed-form solutions (free decay,
steady speed) and batching; the published-value checks are in ``test_physics_published.py``."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from hybridship import frames
from hybridship.physics import hull
from hybridship.physics.model import TAU_PARTS, DynamicModel
from hybridship.physics.propeller import load_wageningen, thrust_torque
from hybridship.physics import wind
from hybridship.physics.wind import relative_wind
from hybridship.vessel import VesselFileError, vessel_from_dict

from conftest import decoupled_model, model_from, vessel_dict

HULL = TAU_PARTS.index("hull")


def _no_wind(name, nonlinear=None, **rigid_body):
    d = vessel_dict(name)
    d["wind"] = {"method": "none"}
    d["rigid_body"].update(rigid_body)
    if nonlinear is not None:
        d["damping"]["nonlinear"] = nonlinear
    return model_from(d)


# Wind acts on the velocity over ground, everything else on the velocity through the water:
# without wind the current may only translate the solution (Galilean invariance).
NO_WIND = {"gunnerus": _no_wind("gunnerus", x_g_m=1.3),      # off-centre CG: the C_RB(nu) terms too
           "esso_osaka_model": _no_wind("esso_osaka_model"),  # propeller + rudder
           # explicit quadratic damping -d |x_r| x_r in every DOF (the packaged files use cross-flow strips)
           "gunnerus_quadratic": _no_wind("gunnerus", {"method": "quadratic", "d_uu": 3000.0, "d_vv": 2.0e4,
                                                       "d_rr": 2.0e7})}


# ----------------------------------------------------------------------------- current


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(sorted(NO_WIND)), psi=st.floats(-7, 7),
       nu_r=st.tuples(st.floats(-4, 4), st.floats(-2, 2), st.floats(-0.1, 0.1)),
       cur=st.tuples(st.floats(0, 2.5), st.floats(-7, 7)),
       cmd=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1), st.floats(-3.2, 3.2),
                     st.floats(-3.2, 3.2), st.floats(-0.6, 0.6)))
def test_an_irrotational_current_only_translates_the_dynamics(name, psi, nu_r, cur, cmd):
    """Fossen (2021, sec. 10.3): with nu = nu_r + nu_c and nu_c = R(psi)^T v_c,
    ``nu_dot(nu; current) = nu_dot(nu_r; no current) + d(nu_c)/dt``, ``d(nu_c)/dt = [r v_c, -r u_c, 0]``,
    with the thrusters, the propeller and the rudder working too (they see nu_r)."""
    m = NO_WIND[name]
    K, R = m.n_thrusters, m.n_rudders
    rpm = np.array(cmd[:K]) * [t.max_rpm for t in m.vessel.thrusters]
    kw = dict(rpm=rpm, azimuth_rad=np.array(cmd[3:3 + K]))
    if R:
        kw["rudder_rad"] = np.array(cmd[5:5 + R])
    v_c = np.array([cur[0] * np.cos(cur[1]), cur[0] * np.sin(cur[1]), 0.0])
    nu_c = frames.ned_to_body(v_c, psi)
    nu = np.array(nu_r) + nu_c
    eta = np.array([0.0, 0.0, psi])
    with_current = m.acceleration(eta, nu, current=list(cur), **kw)[0]
    in_still_water = m.acceleration(eta, np.array(nu_r), **kw)[0]
    nu_c_dot = np.array([nu[2] * nu_c[1], -nu[2] * nu_c[0], 0.0])
    # rounding only (the kernels compute nu_r = nu - nu_c themselves, fastmath reorders sums):
    # observed <= 2e-14 of the terms' size, and 2e-17 m/s^2 where nu_r = 0 (nu_c rounded by
    # 1e-16 m/s meets the damping); a missing M_A d(nu_c)/dt or C_RB(nu) nu written with nu_r
    # gives errors of the order of the terms themselves
    scale = np.abs(in_still_water) + np.abs(nu_c_dot) + 1e-3
    np.testing.assert_array_less(np.abs(with_current - in_still_water - nu_c_dot), 1e-11 * scale)


def test_a_ship_at_rest_in_the_water_drifts_exactly_with_the_current():
    """No velocity through the water (nu_r = 0, r = 0): no hull, propeller or rudder load,
    so nu_r stays 0 and the ship moves with the current, ``eta(t) = eta_0 + v_c t``."""
    for m in NO_WIND.values():
        psi0, speed, to = 0.7, 0.8, np.radians(250.0)
        v_c = np.array([speed * np.cos(to), speed * np.sin(to), 0.0])
        res = m.rollout([10.0, -5.0, psi0], frames.ned_to_body(v_c, psi0), 300, dt_s=1.0, current=[speed, to],
                        rpm=np.zeros(m.n_thrusters), azimuth_rad=np.zeros(m.n_thrusters))
        nu_r = res.nu[0] - frames.ned_to_body(v_c, res.eta[0, :, 2])
        np.testing.assert_allclose(nu_r, 0.0, atol=1e-12)            # rounding of u_c, v_c only
        np.testing.assert_allclose(res.eta[0, :, 2], psi0, atol=1e-12)
        np.testing.assert_allclose(res.eta[0, :, :2], [10.0, -5.0] + res.time_s[:, None] * v_c[:2], atol=1e-9)


# ----------------------------------------------------------------------------- energy, dissipation


def test_kinetic_energy_error_falls_at_the_integrators_order():
    """D = 0, tau = 0: T = nu^T M nu / 2 is conserved by the equations (C_RB, C_A skew,
    M symmetric), so RK4's energy error must fall at least as h^4 when the step is halved."""
    d = vessel_dict("gunnerus")
    d["damping"] = {"linear": {"method": "explicit", "D": np.zeros((3, 3)).tolist()},
                    "nonlinear": {"method": "none"}}
    d["wind"] = {"method": "none"}
    d["thrusters"] = []
    d["rigid_body"]["x_g_m"] = 1.5
    m = model_from(d)
    nu0 = np.array([[1.0, 0.4, 0.03], [0.2, -0.8, -0.05]])
    errs = []
    for dt in (2.0, 1.0, 0.5):
        nu = m.rollout(np.zeros((2, 3)), nu0, int(400 / dt), dt_s=dt).nu
        E = 0.5 * np.einsum("bti,ij,btj->bt", nu, m.mass_matrix, nu)
        errs.append(np.abs(E / E[:, :1] - 1).max())
    assert errs[1] < 1e-6                                   # observed 3.8e-7 at dt = 1 s
    # 2^4 = 16 for fourth order (observed 30, the energy error of RK4 here is O(h^5)); a
    # second-order scheme gives 4, an energy leak that is not a truncation error about 1
    assert errs[0] / errs[1] > 12 and errs[1] / errs[2] > 12


def _without_lift(name, true_vessel):
    d = vessel_dict(name)
    d["damping"]["nonlinear"]["lift"] = "none"
    d["damping"]["nonlinear"].pop("mmg", None)
    d["wind"] = {"method": "none"}
    return DynamicModel(vessel_from_dict(d, "test.toml"), true_vessel=true_vessel)


NO_LIFT = {(name, tv): _without_lift(name, tv) for name in ("gunnerus", "esso_osaka_model") for tv in (False, True)}


@settings(max_examples=60, deadline=None)
@given(key=st.sampled_from(sorted(NO_LIFT)),
       nu=st.tuples(st.floats(-6, 6), st.floats(-3, 3), st.floats(-0.3, 0.3)))
def test_mass_is_symmetric_positive_definite_and_damping_dissipative(key, nu):
    """M = M^T > 0 and, with the speed-proportional lift terms removed (they are manoeuvring
    forces, not damping), the hull load does negative work, -nu^T (D + D_n(nu)) nu < 0, at any
    velocity; C_RB and C_A do none. Nominal and the simulator's perturbed vessels."""
    m = NO_LIFT[key]
    M = m.mass_matrix
    np.testing.assert_allclose(M, M.T, rtol=0, atol=1e-9 * np.abs(M).max())   # inverse of the inverse
    assert np.linalg.eigvalsh(0.5 * (M + M.T)).min() > 0
    nu = np.array(nu)
    assume(np.abs(nu).max() > 1e-4)          # below that the cubic power underflows to 0
    _, parts, _ = m.acceleration([0, 0, 0], nu, rpm=np.zeros(m.n_thrusters),
                                 azimuth_rad=np.zeros(m.n_thrusters), return_parts=True)
    assert nu @ parts[0, HULL] < 0


def test_explicit_linear_damping_that_feeds_energy_in_is_refused():
    d = vessel_dict("gunnerus")
    for D in ([[5e3, 0, 0], [0, -1e4, 0], [0, 0, 1e6]],            # a sign typo
              [[5e3, 0, 0], [0, 1e4, 3e5], [0, 3e5, 1e6]]):         # positive diagonal, indefinite
        d["damping"]["linear"] = {"method": "explicit", "D": D}
        with pytest.raises(VesselFileError, match=r"damping.linear: D: not dissipative"):
            vessel_from_dict(copy.deepcopy(d), "bad.toml")
    d["damping"]["linear"]["D"] = [[5e3, 0, 0], [0, 1e4, 1e5], [0, -1e5, 1e6]]   # skew part: no work
    vessel_from_dict(d, "ok.toml")


@settings(max_examples=50, deadline=None)
@given(nu=st.tuples(st.floats(-5, 5), st.floats(-3, 3), st.floats(-0.3, 0.3)),
       x_g=st.floats(-3, 3))
def test_coriolis_matrices_are_skew_and_are_what_the_model_integrates(nu, x_g):
    """The numpy views C_RB(nu), C_A(nu) are skew-symmetric (Fossen 2021, eq. 6.43, 6.53) and
    ``-(C_RB + C_A) nu`` is the hull load of the compiled model without damping."""
    d = vessel_dict("gunnerus")
    d["damping"] = {"linear": {"method": "explicit", "D": np.zeros((3, 3)).tolist()},
                    "nonlinear": {"method": "none"}}
    d["wind"] = {"method": "none"}
    d["thrusters"] = []
    d["rigid_body"]["x_g_m"] = x_g
    m = model_from(d)
    mass = m.vessel.rigid_body.mass_kg
    C = hull.coriolis_rigid_body(nu, mass, x_g) + hull.coriolis_added_mass(nu, m.arrays.m_a)
    np.testing.assert_allclose(C, -C.T, atol=0)
    _, parts, _ = m.acceleration([0, 0, 0], nu, rpm=np.zeros((1, 0)), azimuth_rad=np.zeros((1, 0)),
                                 return_parts=True)
    scale = np.abs(C) @ np.abs(nu) + 1e-9
    np.testing.assert_array_less(np.abs(parts[0, HULL] + C @ np.array(nu)), 1e-12 * scale)


def test_mmg_lift_gives_the_mmg_hull_derivatives_in_mmgs_own_equations_of_motion():
    """``lift = "mmg"`` against the MMG equations of motion (Yasukawa & Yoshimura 2015, eq. 4), not
    against the inverse of :func:`hull.mmg_lift`: MMG keeps ``(m + m_x) u r`` (sway) and ``x_G m u r``
    (yaw) on the left-hand side, so its hull force and moment are ``Y_H = tau_Y + (m + m_x) u r`` and
    ``N_H = tau_N + x_G m u r`` with ``tau`` the model's hull load, and at ``u = U`` they must have
    ``dY_H/dv = (rho/2) L d U Y'_v``, ``dY_H/dr = (rho/2) L^2 d U Y'_r``, ``dN_H/dv = (rho/2) L^2 d U N'_v``,
    ``dN_H/dr = (rho/2) L^3 d U N'_r`` (the Esso Osaka file, its CG off the origin, nothing else acting)."""
    d = vessel_dict("esso_osaka_model")
    mmg = d["damping"]["nonlinear"]["mmg"]
    d["damping"] = {"linear": {"method": "explicit", "D": np.zeros((3, 3)).tolist()},
                    "nonlinear": {"method": "none", "lift": "mmg", "mmg": mmg}}
    d.update(wind={"method": "none"}, thrusters=[], rudders=[])
    m = model_from(d)
    U, h = 0.5, 1e-4
    nu = np.array([[U, h, 0], [U, -h, 0], [U, 0, h], [U, 0, -h]])
    _, parts, _ = m.acceleration(np.zeros((4, 3)), nu, return_parts=True)
    rb, m_x = d["rigid_body"], -d["added_mass"]["X_udot_kg"]
    assert rb["x_g_m"] != 0.0 and m_x > 0.0
    Y_H = parts[:, HULL, 1] + (rb["mass_kg"] + m_x) * nu[:, 0] * nu[:, 2]
    N_H = parts[:, HULL, 2] + rb["x_g_m"] * rb["mass_kg"] * nu[:, 0] * nu[:, 2]
    p = d["particulars"]
    L, q = p["L_pp_m"], 0.5 * p["rho_water_kg_m3"] * p["L_pp_m"] * p["T_m"] * U
    got = [(Y_H[0] - Y_H[1]) / (2 * h), (Y_H[2] - Y_H[3]) / (2 * h), (N_H[0] - N_H[1]) / (2 * h),
           (N_H[2] - N_H[3]) / (2 * h)]
    # linear in (v, r) at fixed u: central differences are exact to rounding (observed 1e-12); a Munk
    # moment counted twice or left out moves N'_v by (m_y - m_x) / ((rho/2) L^2 d) = 0.20 (N'_v is -0.137)
    np.testing.assert_allclose(got, [q * mmg["Y_v"], q * L * mmg["Y_r"], q * L * mmg["N_v"], q * L**2 * mmg["N_r"]],
                               rtol=1e-8)


# ----------------------------------------------------------------------------- closed forms


def test_linear_sway_and_yaw_free_decay_have_the_files_time_constants():
    """D_ii = M_ii / T_i: a free decay in one DOF is ``x_0 exp(-t / T_i)`` with T_i from the
    file, and its position (heading) ``x_0 T_i (1 - exp(-t / T_i))``."""
    T = dict(T_surge_s=1000.0, T_sway_s=100.0, T_yaw_s=50.0)
    m = decoupled_model({"method": "time_constants", **T}, {"method": "none"})
    res = m.rollout(np.zeros((2, 3)), [[0.0, 0.8, 0.0], [0.0, 0.0, -0.04]], 300, dt_s=1.0)
    t = res.time_s
    # RK4's relative error on exp(-t/T) is (h/T)^5 / 120 per step: over 300 steps of 1 s at T = 50 s
    # 300 * 2.7e-11 = 8e-9; a damping or mass entry off by 1e-6 of itself would exceed it
    for b, (i, x0, Ti, pos) in enumerate(((1, 0.8, T["T_sway_s"], 1), (2, -0.04, T["T_yaw_s"], 2))):
        np.testing.assert_allclose(res.nu[b, :, i], x0 * np.exp(-t / Ti), rtol=2e-8, atol=0)
        np.testing.assert_allclose(res.eta[b, :, pos], x0 * Ti * (1 - np.exp(-t / Ti)), rtol=2e-8, atol=1e-15)
        np.testing.assert_array_equal(np.delete(res.nu[b], i, axis=1), 0.0)   # stays in its DOF


def test_quadratic_damping_free_decay_is_x0_over_1_plus_k_x0_t():
    """``M_ii x_dot = -d |x| x`` gives ``x(t) = x_0 / (1 + k |x_0| t)``, ``k = d / M_ii``, and
    the travelled distance ``sgn(x_0) ln(1 + k |x_0| t) / k``, either sign of x_0."""
    d_quad = dict(d_uu=3000.0, d_vv=2.0e4, d_rr=2.0e7)
    m = decoupled_model({"method": "explicit", "D": np.zeros((3, 3)).tolist()}, {"method": "quadratic", **d_quad})
    M = np.diag(m.mass_matrix)
    for i, (x0, d) in enumerate(zip((3.0, 1.0, 0.05), d_quad.values())):
        nu0 = np.zeros((2, 3))
        nu0[:, i] = [x0, -x0]
        res = m.rollout(np.zeros((2, 3)), nu0, 300, dt_s=1.0)
        k, t = d / M[i], res.time_s
        assert 0.005 < k * x0 < 0.05          # 1 s steps resolve the decay (k x0 t reaches 1.5-15)
        # RK4 at k x0 h <= 0.05: observed relative error <= 2e-9; a wrong |x| x (x^2, or |x| on
        # the wrong factor) or a wrong M_ii is off by orders more
        for b, s in enumerate((1.0, -1.0)):
            np.testing.assert_allclose(res.nu[b, :, i], s * x0 / (1 + k * x0 * t), rtol=1e-7)
            np.testing.assert_allclose(res.eta[b, :, i], s * np.log1p(k * x0 * t) / k, rtol=1e-7, atol=1e-12)
            np.testing.assert_array_equal(np.delete(res.nu[b], i, axis=1), 0.0)


def test_steady_speed_under_constant_shaft_speed_balances_thrust_and_resistance():
    """Two azimuths at 0 deg and fixed rpm: the ship accelerates to the speed u* where the
    delivered thrust ``2 (1 - t) T(n, (1 - w) u*)`` of the four-quadrant model equals the
    resistance ``M_11 / T_surge u* + d_uu u*^2`` (time constant and ITTC-1957 line of the file)."""
    d = vessel_dict("gunnerus")
    d["wind"] = {"method": "none"}
    d["thrusters"] = d["thrusters"][1:]      # the tunnel's axis is not exactly lateral (cos 90 deg
    m = model_from(d)                        # = 6e-17) and the hull is course-unstable: keep symmetry
    rpm = 150.0
    res = m.rollout([0, 0, 0], [0, 0, 0], 1, dt_s=3000.0, substeps=3000, rpm=[rpm, rpm], azimuth_rad=[0, 0])
    th, p, nl = m.vessel.thrusters[0], m.vessel.particulars, m.vessel.damping.nonlinear
    prop = load_wageningen(th.propeller_series, th.pitch_ratio)
    d_uu = hull.surge_quadratic_resistance(nl.wetted_surface_m2, p.L_pp_m, nl.speed_ref_m_s, nl.form_factor_k,
                                           nl.C_R, p.rho_water_kg_m3)
    d_u = m.mass_matrix[0, 0] / m.vessel.damping.linear.T_surge_s

    def surplus(u):
        thrust, _ = thrust_torque(rpm / 60.0, (1 - th.wake_fraction) * u, th.diameter_m, prop, p.rho_water_kg_m3)
        return 2 * (1 - th.thrust_deduction) * thrust - d_u * u - d_uu * u * u

    u_star = brentq(surplus, 0.1, 10.0, xtol=1e-12)
    assert 3.0 < u_star < 5.0                                   # about 8 kn: a real operating point
    # 3000 s is 15 e-folding times of the linearised approach (about 200 s): settled to rounding
    np.testing.assert_allclose(res.nu[0, -1], [u_star, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(res.nu_dot[0, -1], 0.0, atol=1e-12)


# ----------------------------------------------------------------------------- batching


@st.composite
def batches(draw):
    name = draw(st.sampled_from(["gunnerus", "esso_osaka_model"]))
    n = draw(st.integers(1, 5))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    return name, dict(eta=rng.normal(scale=[50, 50, 3], size=(n, 3)),
                      nu=rng.normal(scale=[2, 0.5, 0.03], size=(n, 3)),
                      rpm_frac=rng.uniform(-1, 1, (n, 3)), az=rng.uniform(-np.pi, np.pi, (n, 3)),
                      rudder=rng.uniform(-0.6, 0.6, (n, 1)),
                      wind=np.column_stack([rng.uniform(0, 20, n), rng.uniform(-np.pi, np.pi, n)]),
                      current=np.column_stack([rng.uniform(0, 1.5, n), rng.uniform(-np.pi, np.pi, n)]),
                      # external load [N, N, N m] per unit M_ii and external acceleration [m/s^2, rad/s^2]
                      load_per_M=rng.normal(scale=[0.01, 0.01, 1e-4], size=(n, 3)),
                      accel=rng.normal(scale=[0.01, 0.01, 1e-4], size=(n, 3)))


FULL = {name: DynamicModel(name) for name in ("gunnerus", "esso_osaka_model")}


@settings(max_examples=40, deadline=None)
@given(batch=batches())
def test_a_batch_is_evaluated_as_its_samples_one_by_one(batch):
    """Batch-first kernels: sample b of a batched acceleration, step and rollout depends on row b
    alone (the rollout's held inputs too: a wind or current read from another row leaves the
    symmetry tests' rotated and mirrored rollouts alike, so only a one-sample run shows it), its
    external load and acceleration included."""
    name, x = batch
    m = FULL[name]
    K = m.n_thrusters
    kw = dict(rpm=x["rpm_frac"][:, :K] * [t.max_rpm for t in m.vessel.thrusters], azimuth_rad=x["az"][:, :K],
              wind=x["wind"], current=x["current"], tau_ext=x["load_per_M"] * np.diag(m.mass_matrix),
              accel_ext=x["accel"])
    if m.n_rudders:
        kw["rudder_rad"] = x["rudder"]
    acc, parts, thrusts = m.acceleration(x["eta"], x["nu"], return_parts=True, **kw)
    eta1, nu1 = m.step(x["eta"], x["nu"], dt_s=0.5, substeps=2, **kw)
    roll = m.rollout(x["eta"], x["nu"], 3, dt_s=0.5, substeps=2, **kw)
    for b in range(len(x["eta"])):
        one = {k: v[b] for k, v in kw.items()}
        a_b, p_b, t_b = m.acceleration(x["eta"][b], x["nu"][b], return_parts=True, **one)
        e_b, n_b = m.step(x["eta"][b], x["nu"][b], dt_s=0.5, substeps=2, **one)
        # the same compiled arithmetic on the same numbers: bit-identical
        np.testing.assert_array_equal(acc[b], a_b[0])
        np.testing.assert_array_equal(parts[b], p_b[0])
        np.testing.assert_array_equal(thrusts[b], t_b[0])
        np.testing.assert_array_equal(eta1[b], e_b[0])
        np.testing.assert_array_equal(nu1[b], n_b[0])
        r_b = m.rollout(x["eta"][b], x["nu"][b], 3, dt_s=0.5, substeps=2, **one)
        for got, alone in ((roll.eta, r_b.eta), (roll.nu, r_b.nu), (roll.nu_dot, r_b.nu_dot)):
            np.testing.assert_array_equal(got[b], alone[0])


# ----------------------------------------------------------------------------- angles

EDGES = [np.nextafter(-np.pi, -4), -np.pi, np.nextafter(np.pi, 4), np.pi, -3 * np.pi, 3 * np.pi, -1e-20, 0.0,
         2 * np.pi, np.nextafter(2 * np.pi, 0)]


@settings(max_examples=200, deadline=None)
@given(a=st.one_of(st.sampled_from(EDGES), st.floats(-1e3, 1e3)))
def test_wrapped_angles_lie_in_their_half_open_ranges_and_keep_the_angle(a):
    """wrap_pi in [-pi, pi), wrap_2pi in [0, 2 pi), the wind curves' angle in (-pi, pi], each the
    same direction as the input (np.mod alone returned pi, 2 pi and -pi at the edges); wrap_pi
    returns an angle already in its range unchanged."""
    for w, lo_ok, hi_ok in ((frames.wrap_pi(a), lambda w: w >= -np.pi, lambda w: w < np.pi),
                            (frames.wrap_2pi(a), lambda w: w >= 0.0, lambda w: w < 2 * np.pi)):
        assert lo_ok(w) and hi_ok(w), (a, w)
        # same direction, for every angle and both wraps: cos and sin agree to the rounding of a
        # (|a| <= 1e3: 1e-13 rad); checking cos alone, or in-range angles alone, let a wrap that
        # mirrored angles beyond pi (-w for w) pass
        assert abs(np.cos(w) - np.cos(a)) < 1e-12 and abs(np.sin(w) - np.sin(a)) < 1e-12, (a, w)
    # an angle already in range comes back exactly (not moved by the wrap's rounding)
    if -np.pi <= a < np.pi:
        assert frames.wrap_pi(a) == a, a
    g = wind._wrap_gamma(a)                         # the wind curves' wrap: (-pi, pi]
    assert -np.pi < g <= np.pi and abs(np.cos(g) - np.cos(a)) < 1e-12 and abs(np.sin(g) - np.sin(a)) < 1e-12
    # relative wind of a ship heading a: moving ahead in still air is a head wind (0), a wind
    # from straight astern is +-pi inside (-pi, pi]
    assert relative_wind(0.0, 0.0, a, 1.0, 0.0)[1] == 0.0
    gamma = relative_wind(1.0, a + np.pi, a, 0.0, 0.0)[1]
    assert -np.pi < gamma <= np.pi and abs(abs(gamma) - np.pi) < 1e-12
