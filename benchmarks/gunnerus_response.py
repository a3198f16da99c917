"""Standard manoeuvres of the Gunnerus model beside the published magnitudes.

Runs the physics-only model ``DynamicModel("gunnerus")`` (no residual, no waves) through
four checks and prints the results as Markdown tables:

1. steady surge speed against the rpm of both azimuths at angle 0, with the delivered
   thrust and the shaft power, against the published 10 kn service and 12.6 kn maximum
   speeds;
2. turning circles with the starboard azimuth at +-20 and +-35 deg (both at the same rpm),
   started from the steady speed at 150 rpm, and the straight-line stability of the hull;
3. free decay from ``u = 2 m/s, v = 0.5 m/s, r = 1 deg/s`` with the thrusters stopped, and
   the drift of the stopped ship in a 10 m/s beam wind;
4. the derived hull coefficients beside the original-hull SIMVAL model (Hassani et al. 2015,
   OMAE2015-41789; ``shared/data/reference/gunnerus_published.md``).

and saves one figure with all of them. ``docs/gunnerus-model.md`` discusses the results.

Usage::

    python benchmarks/gunnerus_response.py                  # figure to docs/figures/
    python benchmarks/gunnerus_response.py --out docs/figures
    python benchmarks/gunnerus_response.py --no-plot        # tables only

Conventions (see ``hybridship.physics.thrusters``): azimuth angle 0 = thrust forward,
+90 deg = thrust to starboard; NED earth frame, body x forward, y starboard, r > 0 turns
the bow to starboard; wind direction = where the wind comes FROM.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from hybridship.physics.model import RPM_LIMIT_FACTOR, DynamicModel
from hybridship.physics.propeller import load_wageningen, thrust_torque

KNOT_M_S = 1852.0 / 3600.0
#: Published speeds (WIKI, see gunnerus_published.md): service and maximum [kn].
SERVICE_SPEED_KN = 10.0
MAX_SPEED_KN = 12.6
#: Rated power per azimuth [W]: two motors, 1000 kW in total (WIKI); vessels/gunnerus.toml
#: derives max_rpm = 217 from it at the bollard condition.
RATED_POWER_W = 500e3
#: Indices of the thrusters in the vessel file order [tunnel, port, stbd].
PORT, STBD = 1, 2
TURN_RPM = 150.0
TURN_ANGLES_DEG = (20.0, -20.0, 35.0, -35.0)
DRIFT_WIND_M_S = 10.0

#: Original-hull SIMVAL model (gunnerus_published.md), Lpp 28.9 m.
SIMVAL = {
    "m": 410931.81, "I_z": 2.1450896e7, "L_pp": 28.9,
    "X_udot": -79320.5895, "Y_vdot": -408192.6004, "Y_rdot": 331671.6384,
    "N_vdot": 331671.6384, "N_rdot": -12245783.9277,
    "X_uu": -2100.0,
    "Y_uv": -31000.2779, "Y_ur": 277765.7816, "Y_uur": 11112.4159, "Y_uuv": 777.3214,
    "N_uv": 309051.5592, "N_ur": -2413124.664, "N_uur": -187538.9302, "N_uuv": -14041.6851,
    "Y_|v|v": -21640.6686, "Y_|r|r": -1020386.1325,
    "N_|v|v": 116643.7578, "N_|r|r": -9397835.7612,
}


# --------------------------------------------------------------------------- helpers


def _rpm(model: DynamicModel, azimuth_rpm: float) -> list[float]:
    """Commands ``[tunnel, port, stbd]``: tunnel stopped, both azimuths at ``azimuth_rpm``."""
    return [0.0, float(azimuth_rpm), float(azimuth_rpm)]


def _first_crossing(t: np.ndarray, x: np.ndarray, level: float) -> float:
    """First time at which ``|x|`` falls to ``level`` (linear interpolation), or nan."""
    a = np.abs(x)
    idx = np.flatnonzero(a <= level)
    if idx.size == 0:
        return float("nan")
    i = int(idx[0])
    if i == 0:
        return float(t[0])
    f = (a[i - 1] - level) / (a[i - 1] - a[i])
    return float(t[i - 1] + f * (t[i] - t[i - 1]))


def earth_velocity(eta: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Velocity over ground ``[v_north, v_east]`` [m/s] from body velocities (..., 3)."""
    c, s = np.cos(eta[..., 2]), np.sin(eta[..., 2])
    return np.stack([c * nu[..., 0] - s * nu[..., 1], s * nu[..., 0] + c * nu[..., 1]], axis=-1)


# --------------------------------------------------------------------------- 1. speed


def steady_speed(model: DynamicModel, azimuth_rpm: float) -> float:
    """Steady surge speed [m/s] with both azimuths at angle 0 and ``azimuth_rpm`` (u_dot = 0)."""
    if azimuth_rpm <= 0.0:
        return 0.0

    def u_dot(u):
        return model.acceleration([0, 0, 0], [u, 0, 0], rpm=_rpm(model, azimuth_rpm),
                                  azimuth_rad=[0, 0, 0])[0, 0]

    return brentq(u_dot, 1e-6, 40.0, xtol=1e-10)


def propulsion_point(model: DynamicModel, azimuth_rpm: float) -> dict:
    """Steady speed, delivered thrust and shaft power of one azimuth at ``azimuth_rpm``."""
    u = steady_speed(model, azimuth_rpm)
    _, _, thrusts = model.acceleration([0, 0, 0], [u, 0, 0], rpm=_rpm(model, azimuth_rpm),
                                       azimuth_rad=[0, 0, 0], return_parts=True)
    t = model.vessel.thrusters[STBD]
    prop = load_wageningen(t.propeller_series, t.pitch_ratio)
    n = azimuth_rpm / 60.0
    va = (1.0 - t.wake_fraction) * u
    _, q = thrust_torque(n, va, t.diameter_m, prop, model.vessel.particulars.rho_water_kg_m3)
    return {"rpm": float(azimuth_rpm), "u_m_s": u, "u_kn": u / KNOT_M_S,
            "thrust_total_N": float(thrusts[0, PORT] + thrusts[0, STBD]),
            "power_per_unit_W": float(2.0 * math.pi * n * q),
            "J": va / (n * t.diameter_m) if n > 0 else float("nan")}


def speed_curve(model: DynamicModel, rpms) -> dict:
    """Steady speed [m/s] and total delivered thrust [N] for each azimuth rpm."""
    pts = [propulsion_point(model, r) for r in rpms]
    return {"rpm": np.asarray(rpms, float), "u_m_s": np.array([p["u_m_s"] for p in pts]),
            "thrust_total_N": np.array([p["thrust_total_N"] for p in pts]),
            "power_per_unit_W": np.array([p["power_per_unit_W"] for p in pts])}


def _rpm_hi(model: DynamicModel) -> float:
    """Upper end of the rpm searches: the largest rpm the model accepts (``RPM_LIMIT_FACTOR``
    times the azimuths' max_rpm)."""
    return RPM_LIMIT_FACTOR * model.vessel.thrusters[1].max_rpm


def rpm_for_speed(model: DynamicModel, speed_m_s: float, rpm_hi: float | None = None) -> float:
    """Azimuth rpm (both units, angle 0) whose steady speed is ``speed_m_s``."""
    return brentq(lambda n: steady_speed(model, n) - speed_m_s, 1.0, rpm_hi or _rpm_hi(model), xtol=1e-6)


def rpm_for_power(model: DynamicModel, power_W: float, rpm_hi: float | None = None) -> float:
    """Azimuth rpm at which each unit absorbs ``power_W`` in the steady straight run."""
    return brentq(lambda n: propulsion_point(model, n)["power_per_unit_W"] - power_W, 1.0,
                  rpm_hi or _rpm_hi(model), xtol=1e-6)


# --------------------------------------------------------------------------- 2. turning


def turning_test(model: DynamicModel, angle_deg: float, *, azimuth_rpm: float = TURN_RPM,
                 duration_s: float = 600.0, dt_s: float = 0.5) -> dict:
    """Turning circle: starboard azimuth slewed to ``angle_deg`` (port stays at 0).

    Starts on a straight course at the steady speed for ``azimuth_rpm``; the azimuth turns
    at the vessel file's ``max_azimuth_rate_deg_s``. Steady values are means over the
    last 60 s.
    """
    u0 = steady_speed(model, azimuth_rpm)
    n = int(round(duration_s / dt_s))
    t = np.arange(n) * dt_s
    rate = model.vessel.thrusters[STBD].max_azimuth_rate_deg_s or 1e9
    az = np.zeros((1, n, 3))
    az[0, :, STBD] = np.radians(np.sign(angle_deg) * np.minimum(rate * t, abs(angle_deg)))
    res = model.rollout([0, 0, 0], [u0, 0, 0], n, dt_s=dt_s, substeps=2, rpm=_rpm(model, azimuth_rpm),
                        azimuth_rad=az)
    eta, nu = res.eta[0], res.nu[0]
    tail = res.time_s >= res.time_s[-1] - 60.0
    r_ss = float(np.mean(nu[tail, 2]))
    U = np.hypot(nu[:, 0], nu[:, 1])
    U_ss = float(np.mean(U[tail]))
    L = model.vessel.particulars.L_pp_m
    dpsi = np.abs(eta[:, 2])
    i90 = int(np.argmax(dpsi >= math.pi / 2)) if np.any(dpsi >= math.pi / 2) else None
    i180 = int(np.argmax(dpsi >= math.pi)) if np.any(dpsi >= math.pi) else None
    return {
        "angle_deg": angle_deg, "u0_m_s": u0, "r_ss_deg_s": math.degrees(r_ss),
        "U_ss_m_s": U_ss, "radius_over_L": U_ss / abs(r_ss) / L,
        "speed_loss_pct": 100.0 * (1.0 - U_ss / u0),
        "drift_angle_deg": float(np.degrees(np.mean(np.arctan2(nu[tail, 1], nu[tail, 0])))),
        "advance_over_L": float(eta[i90, 0] / L) if i90 is not None else float("nan"),
        "tactical_diameter_over_L": float(abs(eta[i180, 1]) / L) if i180 is not None else float("nan"),
        "time_s": res.time_s, "eta": eta, "nu": nu,
    }


def turning_test_perturbed(model: DynamicModel, azimuth_rpm: float = TURN_RPM, r0: float = 1e-3,
                           duration_s: float = 600.0) -> dict:
    """Both azimuths straight ahead; start with a small yaw rate ``r0`` [rad/s]."""
    u0 = steady_speed(model, azimuth_rpm)
    n = int(duration_s)
    res = model.rollout([0, 0, 0], [u0, 0, r0], n, dt_s=1.0, substeps=4, rpm=_rpm(model, azimuth_rpm),
                        azimuth_rad=[0, 0, 0])
    nu = res.nu[0]
    U = np.hypot(nu[-60:, 0], nu[-60:, 1]).mean()
    r = nu[-60:, 2].mean()
    return {"r_ss_deg_s": math.degrees(r), "radius_over_L": U / abs(r) / model.vessel.particulars.L_pp_m,
            "time_s": res.time_s, "eta": res.eta[0], "nu": nu}


def straight_line_stability(model: DynamicModel, azimuth_rpm: float, eps: float = 1e-5) -> np.ndarray:
    """Eigenvalues [1/s] of the linearised sway-yaw dynamics on a straight course at ``azimuth_rpm``.

    Central differences of nu_dot with respect to ``(v, r)`` around the steady straight run
    (thrusters included). A positive eigenvalue means the straight course is unstable.
    """
    u0 = steady_speed(model, azimuth_rpm)
    J = np.zeros((2, 2))
    for j in range(2):
        dp = np.zeros(3)
        dp[1 + j] = eps
        a_p = model.acceleration([0, 0, 0], [u0, 0, 0] + dp, rpm=_rpm(model, azimuth_rpm), azimuth_rad=[0, 0, 0])
        a_m = model.acceleration([0, 0, 0], [u0, 0, 0] - dp, rpm=_rpm(model, azimuth_rpm), azimuth_rad=[0, 0, 0])
        J[:, j] = (a_p[0, 1:] - a_m[0, 1:]) / (2 * eps)
    return np.sort(np.linalg.eigvals(J).real)


def stern_lift_for_neutral_stability(model: DynamicModel, azimuth_rpm: float) -> dict:
    """Lateral lift at the azimuths that would make the straight course neutrally stable.

    A foil (pod, strut, fin) at ``x_p`` adds the force ``-a (v + x_p r)`` and the moment
    ``-a x_p (v + x_p r)``, i.e. ``a [[1, x_p], [x_p, x_p^2]]`` (rank one) to the negative
    force Jacobian. With ``A = M J`` the force Jacobian of this model on the straight run,
    ``det(A - a u u^T) = det A - a u^T adj(A) u`` is linear in ``a``; its root is the lift
    slope that brings the unstable eigenvalue to zero. ``A C_L_alpha = 2 a / (rho U)`` is
    the equivalent foil area times lift-curve slope (thin-foil estimate, no wake).
    """
    u0 = steady_speed(model, azimuth_rpm)
    eps = 1e-5
    J = np.zeros((2, 2))
    for j in range(2):
        dp = np.zeros(3)
        dp[1 + j] = eps
        a_p = model.acceleration([0, 0, 0], [u0, 0, 0] + dp, rpm=_rpm(model, azimuth_rpm), azimuth_rad=[0, 0, 0])
        a_m = model.acceleration([0, 0, 0], [u0, 0, 0] - dp, rpm=_rpm(model, azimuth_rpm), azimuth_rad=[0, 0, 0])
        J[:, j] = (a_p[0, 1:] - a_m[0, 1:]) / (2 * eps)
    A = model.mass_matrix[1:, 1:] @ J
    x_p = model.vessel.thrusters[STBD].x_m
    u = np.array([1.0, x_p])
    adj = np.array([[A[1, 1], -A[0, 1]], [-A[1, 0], A[0, 0]]])
    a = np.linalg.det(A) / (u @ adj @ u)
    rho = model.vessel.particulars.rho_water_kg_m3
    return {"a_kg_s": float(a), "x_m": x_p, "U_m_s": u0, "A_CLalpha_m2": 2.0 * a / (rho * u0)}


def implied_resistance(model: DynamicModel, speed_m_s: float, power_per_unit_W: float = RATED_POWER_W) -> float:
    """Resistance [N] the published speed implies at the rated power with this model's propulsors.

    Finds the rpm at which one azimuth (B-series, wake and thrust deduction of the vessel
    file) absorbs ``power_per_unit_W`` at the inflow of ``speed_m_s``, and returns the
    delivered thrust of both units: the resistance that the ship must have if it reaches
    that speed at that power.
    """
    t = model.vessel.thrusters[STBD]
    prop = load_wageningen(t.propeller_series, t.pitch_ratio)
    rho = model.vessel.particulars.rho_water_kg_m3
    va = (1.0 - t.wake_fraction) * speed_m_s

    def excess(rpm):
        _, q = thrust_torque(rpm / 60.0, va, t.diameter_m, prop, rho)
        return 2.0 * math.pi * rpm / 60.0 * float(q) - power_per_unit_W

    rpm = brentq(excess, 1.0, 2000.0, xtol=1e-6)
    T, _ = thrust_torque(rpm / 60.0, va, t.diameter_m, prop, rho)
    return 2.0 * (1.0 - t.thrust_deduction) * float(T)


def simval_linear(U: float) -> dict:
    """Linear sway-yaw derivatives of the SIMVAL model at speed U (hydrodynamic part only).

    Collects the terms linear in v and r of the published polynomial sums, including the
    added-mass Coriolis terms X_udot u r (sway), (Y_vdot - X_udot) u v and
    (N_vdot + Y_rdot)/2 u r (yaw), i.e. everything except the rigid-body -m u r.
    """
    s = SIMVAL
    return {"Y_v": s["Y_uv"] * U + s["Y_uuv"] * U**2,
            "Y_r": s["Y_ur"] * U + s["Y_uur"] * U**2 + s["X_udot"] * U,
            "N_v": s["N_uv"] * U + s["N_uuv"] * U**2 + (s["Y_vdot"] - s["X_udot"]) * U,
            "N_r": s["N_ur"] * U + s["N_uur"] * U**2 + 0.5 * (s["N_vdot"] + s["Y_rdot"]) * U}


def simval_stability(U: float) -> np.ndarray:
    """Eigenvalues [1/s] of the SIMVAL sway-yaw model linearised at speed U (x_g = 0)."""
    s = SIMVAL
    d = simval_linear(U)
    M = np.array([[s["m"] - s["Y_vdot"], -s["Y_rdot"]], [-s["N_vdot"], s["I_z"] - s["N_rdot"]]])
    A = np.array([[d["Y_v"], d["Y_r"] - s["m"] * U], [d["N_v"], d["N_r"]]])
    return np.sort(np.linalg.eigvals(np.linalg.solve(M, A)).real)


def model_linear(model: DynamicModel, U: float, eps: float = 1e-5) -> dict:
    """Hydrodynamic linear sway-yaw derivatives of this model at speed U (hull only).

    Central differences of the hull load (the "hull" part of ``return_parts``: C and D
    terms, no thrusters) with respect to v and r at ``u = U``, plus ``m U`` in Y_r to remove
    the rigid-body Coriolis term ``-m u r``.
    """
    m = model.vessel.rigid_body.mass_kg
    out = {}
    for j, name in ((1, "v"), (2, "r")):
        dp = np.zeros(3)
        dp[j] = eps
        _, pp, _ = model.acceleration([0, 0, 0], [U, 0, 0] + dp, return_parts=True)
        _, pm, _ = model.acceleration([0, 0, 0], [U, 0, 0] - dp, return_parts=True)
        d = (pp[0, 0] - pm[0, 0]) / (2 * eps)
        out["Y_" + name] = d[1] + (m * U if name == "r" else 0.0)
        out["N_" + name] = d[2]
    return out


# --------------------------------------------------------------------------- 3. decay / drift


def free_decay(model: DynamicModel, nu0=(2.0, 0.5, math.radians(1.0)), duration_s: float = 1800.0,
               dt_s: float = 0.5) -> dict:
    """Free decay with all thrusters at 0 rpm (stopped propellers still drag)."""
    n = int(round(duration_s / dt_s))
    res = model.rollout([0, 0, 0], list(nu0), n, dt_s=dt_s, substeps=2, rpm=[0, 0, 0], azimuth_rad=[0, 0, 0])
    nu = res.nu[0]
    halves = {k: _first_crossing(res.time_s, nu[:, i], 0.5 * abs(nu0[i])) if nu0[i] != 0 else float("nan")
              for i, k in enumerate(("u", "v", "r"))}
    speed = np.hypot(nu[:, 0], nu[:, 1])
    ke = 0.5 * np.einsum("ti,ij,tj->t", nu, model.mass_matrix, nu)
    return {"time_s": res.time_s, "nu": nu, "t_half": halves, "speed": speed, "kinetic_energy_J": ke,
            "t_half_speed": _first_crossing(res.time_s, speed, 0.5 * speed[0])}


def drift_test(model: DynamicModel, wind_speed_m_s: float = DRIFT_WIND_M_S, from_port: bool = True,
               duration_s: float = 3600.0, dt_s: float = 1.0) -> dict:
    """Ship at rest, heading north, thrusters stopped, in a steady beam wind.

    ``from_port``: the wind comes from the west (port beam at the start), i.e. blows to
    the east. Steady values are means over the last 300 s.
    """
    n = int(round(duration_s / dt_s))
    dir_from = -math.pi / 2 if from_port else math.pi / 2
    res = model.rollout([0, 0, 0], [0, 0, 0], n, dt_s=dt_s, substeps=2, rpm=[0, 0, 0], azimuth_rad=[0, 0, 0],
                        wind=[wind_speed_m_s, dir_from])
    eta, nu = res.eta[0], res.nu[0]
    vel = earth_velocity(eta, nu)
    tail = res.time_s >= res.time_s[-1] - 300.0
    v_ss = vel[tail].mean(axis=0)
    leeward = np.array([-math.cos(dir_from), -math.sin(dir_from)])  # the way the wind blows
    psi_ss = float(np.mean(eta[tail, 2]))
    gamma = math.degrees((dir_from - psi_ss + math.pi) % (2 * math.pi) - math.pi)  # true wind off the bow
    return {"time_s": res.time_s, "eta": eta, "nu": nu, "vel_ne": vel,
            "drift_speed_m_s": float(np.hypot(*v_ss)), "leeward_m_s": float(v_ss @ leeward),
            "heading_deg": math.degrees(psi_ss), "wind_off_bow_deg": gamma,
            "u_ss": float(nu[tail, 0].mean()), "v_ss": float(nu[tail, 1].mean()),
            "t_90pct_s": float(res.time_s[np.argmax(np.hypot(vel[:, 0], vel[:, 1]) >= 0.9 * np.hypot(*v_ss))])}


# --------------------------------------------------------------------------- 4. coefficients


def coefficient_rows(model: DynamicModel) -> list[tuple[str, str, float, float | None, str]]:
    """Rows ``(name, unit, this model, SIMVAL or None, how derived)``."""
    from hybridship.physics import hull

    v, A = model.vessel, model.arrays
    p = v.particulars
    cl = hull.clarke1983_derivatives(p.L_pp_m, p.B_m, p.T_m, p.C_B, p.rho_water_kg_m3)
    w, x = A.strip_w, A.strip_x
    U = SERVICE_SPEED_KN * KNOT_M_S
    lin = model_linear(model, U)
    sl = simval_linear(U)
    s = SIMVAL
    rows = [
        ("m", "kg", v.rigid_body.mass_kg, s["m"], "VERES displacement"),
        ("I_z", "kg m^2", v.rigid_body.I_z, s["I_z"], "m r_z^2, r_z = 0.25 Lpp (VERES r66)"),
        ("X_udot", "kg", -A.m_a[0, 0], s["X_udot"], "Soding (1982)"),
        ("Y_vdot", "kg", -A.m_a[1, 1], s["Y_vdot"], "Clarke et al. (1983)"),
        ("Y_rdot (Clarke's regression)", "kg m", cl["Y_rdot_kg_m"], s["Y_rdot"],
         "not used: M_A not positive definite with it"),
        ("N_vdot (Clarke's regression)", "kg m", cl["N_vdot_kg_m"], s["N_vdot"],
         "not used: M_A not positive definite with it"),
        ("-M_A[1,2] = (Y_rdot+N_vdot)/2", "kg m", -A.m_a[1, 2], 0.5 * (s["Y_rdot"] + s["N_vdot"]),
         "used: the vessel file's (SIMVAL's)"),
        ("N_rdot", "kg m^2", -A.m_a[2, 2], s["N_rdot"], "Clarke et al. (1983)"),
        ("D_11 (linear surge)", "kg/s", A.d_lin[0, 0], None, "M_11 / T_surge, T = 1000 s"),
        ("D_22 (linear sway)", "kg/s", A.d_lin[1, 1], None, "M_22 / T_sway, T = 100 s"),
        ("D_33 (linear yaw)", "kg m^2/s", A.d_lin[2, 2], None, "M_33 / T_yaw, T = 50 s"),
        ("X_uu = -d_uu", "kg/m", -A.d_quad[0], s["X_uu"], "ITTC-57 (1+k) C_F + C_R at 10 kn"),
        ("Y_|v|v = -sum w", "kg/m", -w.sum(), s["Y_|v|v"], "cross-flow strips, Hoerner C_d"),
        ("N_|r|r = -sum w |x|^3", "kg m^2", -(w * np.abs(x) ** 3).sum(), s["N_|r|r"], "cross-flow strips"),
        ("Y_|r|r = -sum w x|x|", "kg", -(w * x * np.abs(x)).sum(), s["Y_|r|r"], "cross-flow strips (fore-aft symmetric)"),
        ("N_|v|v = -sum w x", "kg", -(w * x).sum(), s["N_|v|v"], "cross-flow strips (fore-aft symmetric)"),
        ("Y_uv = -d_lift[0]", "kg/m", -A.d_lift[0], s["Y_uv"], "Clarke Y_v / U"),
        ("Y_ur = -d_lift[1]", "kg", -A.d_lift[1], s["Y_ur"], "Clarke Y_r / U + M_A11"),
        ("N_uv = -d_lift[2]", "kg", -A.d_lift[2], s["N_uv"], "Clarke N_v / U + M_A22 - M_A11"),
        ("N_ur = -d_lift[3]", "kg m", -A.d_lift[3], s["N_ur"], "Clarke N_r / U + M_A23"),
        ("Y_v at 10 kn", "kg/s", lin["Y_v"], sl["Y_v"], "all linear terms (SIMVAL: + Y_uuv U^2)"),
        ("Y_r at 10 kn", "kg m/s", lin["Y_r"], sl["Y_r"], "all linear terms, without -m U"),
        ("N_v at 10 kn", "kg m/s", lin["N_v"], sl["N_v"], "incl. Munk moment (Y_vdot - X_udot) U"),
        ("N_r at 10 kn", "kg m^2/s", lin["N_r"], sl["N_r"], "all linear terms"),
        ("surge resistance at 10 kn", "N", A.d_quad[0] * U**2 + A.d_lin[0, 0] * U, -s["X_uu"] * U**2,
         "d_uu U^2 + D_11 U (SIMVAL: -X_uu U^2)"),
    ]
    return rows


# --------------------------------------------------------------------------- report


def _f(x: float, nd: int = 2) -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.{nd}f}"


def _g(x: float | None) -> str:
    """Coefficient format: 4 significant digits."""
    if x is None or not np.isfinite(x):
        return "—"
    if x == 0.0 or abs(x) < 1e-6:
        return "0"
    return f"{x:.4g}"


def run(model: DynamicModel) -> dict:
    rpms = np.arange(50.0, 218.0, 1.0)
    rpms[-1] = 217.0
    out = {"curve": speed_curve(model, rpms)}
    max_rpm = model.vessel.thrusters[STBD].max_rpm
    out["at_max"] = propulsion_point(model, max_rpm)
    out["rpm_service"] = rpm_for_speed(model, SERVICE_SPEED_KN * KNOT_M_S)
    out["at_service"] = propulsion_point(model, out["rpm_service"])
    out["rpm_max_speed"] = rpm_for_speed(model, MAX_SPEED_KN * KNOT_M_S)
    out["at_max_speed"] = propulsion_point(model, out["rpm_max_speed"])
    out["rpm_rated"] = rpm_for_power(model, RATED_POWER_W)
    out["at_rated"] = propulsion_point(model, out["rpm_rated"])
    out["at_turn_rpm"] = propulsion_point(model, TURN_RPM)
    out["turns"] = [turning_test(model, a) for a in TURN_ANGLES_DEG]
    # Straight ahead, both azimuths at 0, with a yaw-rate disturbance of 0.001 rad/s.
    out["straight_perturbed"] = turning_test_perturbed(model)
    out["eig_model_150"] = straight_line_stability(model, TURN_RPM)
    out["eig_model_10kn"] = straight_line_stability(model, out["rpm_service"])
    out["eig_simval_10kn"] = simval_stability(SERVICE_SPEED_KN * KNOT_M_S)
    out["stern_lift_10kn"] = stern_lift_for_neutral_stability(model, out["rpm_service"])
    U12 = MAX_SPEED_KN * KNOT_M_S
    out["res_12_6"] = {"implied": implied_resistance(model, U12),
                       "model": model.arrays.d_quad[0] * U12**2 + model.arrays.d_lin[0, 0] * U12,
                       "simval": -SIMVAL["X_uu"] * U12**2}
    out["decay"] = free_decay(model)
    out["decay_single"] = {k: free_decay(model, nu0) for k, nu0 in
                           (("u", (2.0, 0.0, 0.0)), ("v", (0.0, 0.5, 0.0)), ("r", (0.0, 0.0, math.radians(1.0))))}
    out["drift"] = drift_test(model, from_port=True)
    out["drift_stbd"] = drift_test(model, from_port=False)
    out["coef"] = coefficient_rows(model)
    return out


def report(out: dict, model: DynamicModel) -> str:
    L = model.vessel.particulars.L_pp_m
    lines = []
    P = lines.append
    P("## 1. Steady speed, both azimuths at angle 0 (tunnel stopped)\n")
    P("| case | rpm | speed [m/s] | speed [kn] | total thrust [kN] | shaft power per unit [kW] | J |")
    P("| --- | --- | --- | --- | --- | --- | --- |")
    for name, key, rpm_key in (("max rpm", "at_max", None), ("published service speed 10 kn", "at_service", "rpm_service"),
                               ("published max speed 12.6 kn", "at_max_speed", "rpm_max_speed"),
                               ("rated 500 kW per unit", "at_rated", "rpm_rated"),
                               ("turning-test start", "at_turn_rpm", None)):
        p = out[key]
        P(f"| {name} | {p['rpm']:.1f} | {p['u_m_s']:.3f} | {p['u_kn']:.2f} | {p['thrust_total_N'] / 1e3:.2f} "
          f"| {p['power_per_unit_W'] / 1e3:.1f} | {p['J']:.3f} |")
    c = out["curve"]
    P("\nSpeed curve (selected rpm):\n")
    P("| rpm | speed [kn] | total thrust [kN] | shaft power per unit [kW] |")
    P("| --- | --- | --- | --- |")
    for r in (50, 75, 100, 125, 150, 175, 200, 217):
        i = int(np.argmin(np.abs(c["rpm"] - r)))
        P(f"| {c['rpm'][i]:.0f} | {c['u_m_s'][i] / KNOT_M_S:.2f} | {c['thrust_total_N'][i] / 1e3:.2f} "
          f"| {c['power_per_unit_W'][i] / 1e3:.1f} |")
    P(f"\nSpeed at max rpm ({out['at_max']['rpm']:.0f}): {out['at_max']['u_kn']:.2f} kn "
      f"(published max {MAX_SPEED_KN} kn); rpm for {SERVICE_SPEED_KN:.0f} kn: {out['rpm_service']:.1f}.")
    rr = out["res_12_6"]
    P(f"\nResistance at {MAX_SPEED_KN} kn: this model {rr['model'] / 1e3:.1f} kN; SIMVAL -X_uu U^2 (shorter hull) "
      f"{rr['simval'] / 1e3:.1f} kN; implied by reaching {MAX_SPEED_KN} kn at 2 x {RATED_POWER_W / 1e3:.0f} kW "
      f"with this model's propulsors {rr['implied'] / 1e3:.1f} kN.")

    P(f"\n## 2. Turning, both azimuths at {TURN_RPM:.0f} rpm, starboard azimuth turned "
      f"(start at {out['at_turn_rpm']['u_m_s']:.3f} m/s = {out['at_turn_rpm']['u_kn']:.2f} kn)\n")
    P("| stbd azimuth [deg] | steady r [deg/s] | turning radius / Lpp | steady speed [m/s] | speed loss [%] "
      "| drift angle [deg] | advance / Lpp | tactical diameter / Lpp |")
    P("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for t in out["turns"]:
        P(f"| {t['angle_deg']:+.0f} | {t['r_ss_deg_s']:.3f} | {t['radius_over_L']:.2f} | {t['U_ss_m_s']:.3f} "
          f"| {t['speed_loss_pct']:.1f} | {t['drift_angle_deg']:.1f} | {_f(t['advance_over_L'])} "
          f"| {_f(t['tactical_diameter_over_L'])} |")
    sp = out["straight_perturbed"]
    P(f"\nSign check: positive azimuth (thrust to starboard at the stern) gives r < 0 (bow to port): "
      f"{all((t['angle_deg'] > 0) == (t['r_ss_deg_s'] < 0) for t in out['turns'])}.")
    P(f"\nStraight-line stability: both azimuths at 0 deg, start r = 0.001 rad/s -> steady "
      f"r = {sp['r_ss_deg_s']:.3f} deg/s, radius / Lpp = {sp['radius_over_L']:.2f}.")
    P("\n| linearised sway-yaw eigenvalues [1/s] | lambda_1 | lambda_2 | e-folding time of the unstable mode [s] |")
    P("| --- | --- | --- | --- |")
    for name, key in ((f"this model, {TURN_RPM:.0f} rpm", "eig_model_150"),
                      (f"this model, 10 kn ({out['rpm_service']:.1f} rpm)", "eig_model_10kn"),
                      ("SIMVAL original hull, 10 kn (hull only)", "eig_simval_10kn")):
        e = out[key]
        P(f"| {name} | {e[0]:.4f} | {e[1]:.4f} | {_f(1.0 / e[1], 1) if e[1] > 0 else '— (stable)'} |")
    sl = out["stern_lift_10kn"]
    P(f"\nStern lift for neutral stability at 10 kn: a lateral force -a (v + x r) at x = {sl['x_m']:.2f} m with "
      f"a = {sl['a_kg_s']:.4g} kg/s, i.e. A C_L_alpha = {sl['A_CLalpha_m2']:.1f} m^2 for both pods together.")

    d = out["decay"]
    P("\n## 3. Free decay, all thrusters at 0 rpm, from u = 2 m/s, v = 0.5 m/s, r = 1 deg/s\n")
    P("| t [s] | u [m/s] | v [m/s] | r [deg/s] | speed [m/s] |")
    P("| --- | --- | --- | --- | --- |")
    for tt in (0, 5, 10, 20, 30, 60, 120, 300, 600, 1200, 1800):
        i = int(np.argmin(np.abs(d["time_s"] - tt)))
        nu = d["nu"][i]
        P(f"| {tt} | {nu[0]:.3f} | {nu[1]:.3f} | {math.degrees(nu[2]):.3f} | {d['speed'][i]:.3f} |")
    r_min = np.degrees(d["nu"][:, 2].min())
    t_rmin = d["time_s"][int(np.argmin(d["nu"][:, 2]))]
    P(f"\nTime to halve: u {d['t_half']['u']:.1f} s, v {d['t_half']['v']:.1f} s, |r| {d['t_half']['r']:.1f} s "
      f"(r changes sign: minimum {r_min:.3f} deg/s at {t_rmin:.1f} s), speed {d['t_half_speed']:.1f} s. "
      f"Speed monotonic: {bool(np.all(np.diff(d['speed']) <= 1e-12))}; kinetic energy monotonic: "
      f"{bool(np.all(np.diff(d['kinetic_energy_J']) <= 1e-9))}.")
    ds = out["decay_single"]
    P(f"\nSingle-DOF decays (the other velocities 0): u from 2 m/s halves in {ds['u']['t_half']['u']:.1f} s; "
      f"v from 0.5 m/s in {ds['v']['t_half']['v']:.1f} s; r from 1 deg/s in {ds['r']['t_half']['r']:.1f} s.")

    P(f"\n### Drift in a {DRIFT_WIND_M_S:.0f} m/s beam wind, thrusters stopped, start at rest heading north\n")
    P("| wind from | drift speed [m/s] | % of wind | leeward component [m/s] | steady heading [deg] "
      "| wind off the bow [deg] | u [m/s] | v [m/s] | 90 % of drift speed after [s] |")
    P("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, key in (("west (port beam)", "drift"), ("east (starboard beam)", "drift_stbd")):
        dr = out[key]
        P(f"| {name} | {dr['drift_speed_m_s']:.3f} | {100 * dr['drift_speed_m_s'] / DRIFT_WIND_M_S:.2f} "
          f"| {dr['leeward_m_s']:.3f} | {dr['heading_deg']:.1f} | {dr['wind_off_bow_deg']:.1f} "
          f"| {dr['u_ss']:.3f} | {dr['v_ss']:.3f} | {dr['t_90pct_s']:.0f} |")

    P(f"\n## 4. Derived coefficients (lengthened hull, Lpp {L:.1f} m) beside SIMVAL "
      f"(original hull, Lpp {SIMVAL['L_pp']} m)\n")
    P("| coefficient | unit | this model | SIMVAL | ratio | how derived |")
    P("| --- | --- | --- | --- | --- | --- |")
    for name, unit, ours, pub, how in out["coef"]:
        ratio = (0.0 if abs(ours) < 1e-6 else ours / pub) if pub not in (None, 0.0) else None
        name = name.replace("|", "\\|")  # Markdown table cell
        P(f"| {name} | {unit} | {_g(ours)} | {_g(pub)} | {_f(ratio) if ratio is not None else '—'} | {how} |")
    return "\n".join(lines)


# --------------------------------------------------------------------------- figure


def plot(out: dict, model: DynamicModel, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from hybridship.fileio import atomic_write

    L = model.vessel.particulars.L_pp_m
    fig, ax = plt.subplots(2, 3, figsize=(16, 9.5))

    a = ax[0, 0]
    c = out["curve"]
    a.plot(c["rpm"], c["u_m_s"] / KNOT_M_S, "C0", label="steady speed")
    a.axhline(SERVICE_SPEED_KN, color="C2", ls="--", lw=1, label="published service 10 kn")
    a.axhline(MAX_SPEED_KN, color="C3", ls="--", lw=1, label="published max 12.6 kn")
    a.axvline(out["at_max"]["rpm"], color="0.5", ls=":", lw=1)
    a.plot([out["rpm_service"]], [SERVICE_SPEED_KN], "o", color="C2")
    a.plot([out["at_max"]["rpm"]], [out["at_max"]["u_kn"]], "o", color="C0")
    a.set_xlabel("azimuth rpm (both, angle 0)")
    a.set_ylabel("speed [kn]")
    a.set_title("(a) steady speed and delivered thrust")
    b = a.twinx()
    b.plot(c["rpm"], c["thrust_total_N"] / 1e3, "C1", label="total delivered thrust")
    b.set_ylabel("thrust [kN]", color="C1")
    h1, l1 = a.get_legend_handles_labels()
    h2, l2 = b.get_legend_handles_labels()
    a.legend(h1 + h2, l1 + l2, loc="upper left", fontsize=8)
    a.grid(alpha=0.3)

    a = ax[0, 1]
    for i, t in enumerate(out["turns"]):
        a.plot(t["eta"][:, 1] / L, t["eta"][:, 0] / L, color=f"C{i}", label=f"stbd azimuth {t['angle_deg']:+.0f} deg")
    sp = out["straight_perturbed"]
    a.plot(sp["eta"][:, 1] / L, sp["eta"][:, 0] / L, "k:", lw=1, label="0 deg, r0 = 0.001 rad/s")
    a.set_aspect("equal", adjustable="datalim")
    a.set_xlabel("east / Lpp")
    a.set_ylabel("north / Lpp")
    a.set_title(f"(b) turning tracks at {TURN_RPM:.0f} rpm (start heading north)")
    a.legend(fontsize=8)
    a.grid(alpha=0.3)

    a = ax[0, 2]
    for i, t in enumerate(out["turns"]):
        a.plot(t["time_s"], np.degrees(t["nu"][:, 2]), color=f"C{i}", label=f"{t['angle_deg']:+.0f} deg")
    a.plot(sp["time_s"], np.degrees(sp["nu"][:, 2]), "k:", lw=1, label="0 deg, perturbed")
    a.axhline(0, color="0.5", lw=0.5)
    a.set_xlabel("time [s]")
    a.set_ylabel("yaw rate r [deg/s]")
    a.set_title("(c) yaw rate in the turns (r < 0: bow to port)")
    a.legend(fontsize=8)
    a.grid(alpha=0.3)

    a = ax[1, 0]
    d = out["decay"]
    t = d["time_s"]
    a.plot(t, d["nu"][:, 0], label="u [m/s]")
    a.plot(t, d["nu"][:, 1], label="v [m/s]")
    a.plot(t, d["speed"], "k--", lw=1, label="speed [m/s]")
    a.plot(t, np.degrees(d["nu"][:, 2]), label="r [deg/s]")
    a.axhline(0, color="0.5", lw=0.5)
    a.set_xlim(0, 600)
    a.set_xlabel("time [s]")
    a.set_title("(d) free decay, thrusters at 0 rpm")
    a.legend(fontsize=8)
    a.grid(alpha=0.3)

    a = ax[1, 1]
    dr = out["drift"]
    w = DRIFT_WIND_M_S
    a.plot(dr["time_s"], np.hypot(*dr["vel_ne"].T), label="speed over ground")
    a.plot(dr["time_s"], dr["vel_ne"][:, 1], label="leeward (east) component")
    a.axhspan(0.02 * w, 0.04 * w, color="C2", alpha=0.15, label="2-4 % of wind speed")
    a.set_xlim(0, 1800)
    a.set_xlabel("time [s]")
    a.set_ylabel("[m/s]")
    a.set_title(f"(e) drift in a {w:.0f} m/s wind from the west (port beam)")
    a.legend(fontsize=8, loc="lower right")
    a.grid(alpha=0.3)

    a = ax[1, 2]
    a.plot(dr["time_s"], np.degrees(dr["eta"][:, 2]), "C4")
    a.set_xlim(0, 1800)
    a.set_xlabel("time [s]")
    a.set_ylabel("heading [deg]", color="C4")
    a.set_title("(f) heading while drifting (bow turns to leeward)")
    a.grid(alpha=0.3)

    fig.suptitle("RV Gunnerus 3-DOF model (hybridship, physics only): standard responses", fontsize=13)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    # atomically: a failed write leaves an earlier figure as it was
    atomic_write(path, lambda fh: fig.savefig(fh, format=path.suffix.lstrip(".").lower() or "png", dpi=110))
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "figures",
                    help="folder for gunnerus_response.png (default: docs/figures of the repository)")
    ap.add_argument("--no-plot", action="store_true", help="print the tables only")
    ap.add_argument("--tables", type=Path, default=None,
                    help="also write the printed tables to this Markdown file (atomically)")
    args = ap.parse_args(argv)
    model = DynamicModel("gunnerus")
    out = run(model)
    text = report(out, model)
    print(text)
    if args.tables is not None:
        from hybridship.fileio import write_text

        args.tables.parent.mkdir(parents=True, exist_ok=True)
        write_text(args.tables, text + "\n")
    if not args.no_plot:
        path = args.out / "gunnerus_response.png"
        plot(out, model, path)
        print(f"\nFigure: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
