"""Hull model of Skulstad et al. (2022) eq. 1 in Fossen's notation, 3 DOF (surge, sway, yaw).

.. math::

    M_{RB}\\dot\\nu + C_{RB}(\\nu)\\nu + M_A\\dot\\nu_r + C_A(\\nu_r)\\nu_r
    + D\\nu_r + D_n(\\nu_r)\\nu_r = \\tau

with ``nu = [u, v, r]`` (m/s, m/s, rad/s) and ``nu_r = nu - nu_c`` the velocity relative
to an irrotational current. Here ``M_A`` and ``D`` hold *positive* numbers (``M_A = -diag
of the derivatives``, e.g. ``M_A[0, 0] = -X_udot``), as in Fossen (2021, ch. 6).

This module has two parts:

* **Estimation** (numpy, run once per vessel): rigid-body mass, added mass by Clarke et
  al. (1983) and Soding (1982), linear damping from time constants, Hoerner's 2-D
  cross-flow drag coefficient and the ITTC-1957 surge resistance.
* **Kernels** (numba, called by the dynamic model for every vessel and RK4 stage):
  the Coriolis-centripetal and damping forces.

References
----------
Clarke, D., Gedling, P., Hine, G. (1983). The application of manoeuvring criteria in hull
design using linear theory. Trans. RINA 125, 45-68.
Fossen, T. I. (2021). Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd ed.
Hoerner, S. F. (1965). Fluid-Dynamic Drag.
Soding, H. (1982). Prediction of ship steering capabilities. Schiffstechnik 29, 3-29.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .compiled_cache import KERNEL_FASTMATH

# Hoerner's 2-D cross-flow drag coefficient against B/(2T), digitised curve as tabulated in
# Fossen (2021, fig. 6.x); these are published data points (numbers only).
_HOERNER_B_2T = np.array([
    0.0109, 0.1766, 0.3530, 0.4519, 0.4728, 0.4929, 0.4933, 0.5585, 0.6464, 0.8336,
    0.9880, 1.3081, 1.6392, 1.8600, 2.3129, 2.6000, 3.0088, 3.4508, 3.7379, 4.0031])
_HOERNER_CD = np.array([
    1.9661, 1.9657, 1.8976, 1.7872, 1.5837, 1.2786, 1.2108, 1.0836, 0.9986, 0.8796,
    0.8284, 0.7599, 0.6914, 0.6571, 0.6307, 0.5962, 0.5868, 0.5859, 0.5599, 0.5593])

#: Kinematic viscosity of sea water at 15 deg C [m^2/s] (ITTC 2011 fresh/sea water tables).
NU_SEAWATER_M2_S = 1.19e-6


# --------------------------------------------------------------------------- estimation


def rigid_body_mass(mass_kg: float, I_z_kg_m2: float, x_g_m: float = 0.0) -> np.ndarray:
    """Rigid-body inertia matrix M_RB (3x3) about the body origin (Fossen 2021, eq. 3.44).

    ``I_z_kg_m2`` is the yaw moment of inertia about the body origin.
    """
    m, xg = float(mass_kg), float(x_g_m)
    return np.array([[m, 0.0, 0.0], [0.0, m, m * xg], [0.0, m * xg, float(I_z_kg_m2)]])


def added_mass_surge_soding(mass_kg: float, L_m: float, rho_kg_m3: float = 1025.0) -> float:
    """Soding's (1982) surge added mass ``X_udot = -2.7 rho nabla^(5/3) / L^2`` [kg] (negative)."""
    nabla = mass_kg / rho_kg_m3
    return -2.7 * rho_kg_m3 * nabla ** (5.0 / 3.0) / L_m**2


def clarke1983_derivatives(L_m: float, B_m: float, T_m: float, C_B: float,
                           rho_kg_m3: float = 1025.0) -> dict[str, float]:
    """Dimensional added-mass derivatives of Clarke et al. (1983) in sway and yaw.

    Prime-system regressions (scale factor ``pi (T/L)^2``) made dimensional with
    ``0.5 rho L^3`` (Y_vdot), ``0.5 rho L^4`` (Y_rdot, N_vdot) and ``0.5 rho L^5`` (N_rdot).

    Returns
    -------
    dict
        ``Y_vdot_kg``, ``Y_rdot_kg_m``, ``N_vdot_kg_m``, ``N_rdot_kg_m2`` (all negative for
        ordinary hulls), plus the speed-proportional linear manoeuvring derivatives per
        unit speed ``Y_v_per_U_kg_m``, ``Y_r_per_U_kg``, ``N_v_per_U_kg``, ``N_r_per_U_kg_m``
        for reference (they include the linearised Munk moment, so the dynamic model does
        not use them at low speed).
    """
    S = math.pi * (T_m / L_m) ** 2
    BL, BT, TL = B_m / L_m, B_m / T_m, T_m / L_m
    Yvdot = -S * (1.0 + 0.16 * C_B * BT - 5.1 * BL**2)
    Yrdot = -S * (0.67 * BL - 0.0033 * BT**2)
    Nvdot = -S * (1.1 * BL - 0.041 * BT)
    Nrdot = -S * (1.0 / 12.0 + 0.017 * C_B * BT - 0.33 * BL)
    Yv = -S * (1.0 + 0.4 * C_B * BT)
    Yr = -S * (-0.5 + 2.2 * BL - 0.08 * BT)
    Nv = -S * (0.5 + 2.4 * TL)
    Nr = -S * (0.25 + 0.039 * BT - 0.56 * BL)
    q = 0.5 * rho_kg_m3
    return {
        "Y_vdot_kg": Yvdot * q * L_m**3,
        "Y_rdot_kg_m": Yrdot * q * L_m**4,
        "N_vdot_kg_m": Nvdot * q * L_m**4,
        "N_rdot_kg_m2": Nrdot * q * L_m**5,
        "Y_v_per_U_kg_m": Yv * q * L_m**2,
        "Y_r_per_U_kg": Yr * q * L_m**3,
        "N_v_per_U_kg": Nv * q * L_m**3,
        "N_r_per_U_kg_m": Nr * q * L_m**4,
    }


def clarke1983_lift(derivs: dict[str, float], M_A: np.ndarray) -> np.ndarray:
    """Speed-proportional sway/yaw damping ``[d_vv, d_vr, d_rv, d_rr]`` per unit |u_r| [kg/m, kg, kg, kg m].

    Clarke's linear derivatives are *total* hydrodynamic forces at forward speed U,
    including the linearised added-mass Coriolis terms. Linearising our C_A(nu_r) nu_r at
    u_r = U and requiring ``-C_A nu_r - |u_r| D_lift [v_r, r] = Y_v v + Y_r r`` (and likewise
    for N) gives ``d_vv = -Y_v/U``, ``d_vr = -Y_r/U - M_A11``, ``d_rv = -N_v/U - (M_A22 - M_A11)``,
    ``d_rr = -N_r/U - M_A23``. The hull force is then ``-|u_r| [d_vv v + d_vr r, d_rv v + d_rr r]``.
    """
    xa, ya, yra = M_A[0, 0], M_A[1, 1], M_A[1, 2]
    return np.array([
        -derivs["Y_v_per_U_kg_m"],
        -derivs["Y_r_per_U_kg"] - xa,
        -derivs["N_v_per_U_kg"] - (ya - xa),
        -derivs["N_r_per_U_kg_m"] - yra,
    ])


def mmg_lift(Y_v: float, Y_r: float, N_v: float, N_r: float, L_m: float, d_m: float,
             M_A: np.ndarray, rho_kg_m3: float = 1025.0) -> np.ndarray:
    """Speed-proportional damping ``[d_vv, d_vr, d_rv, d_rr]`` per unit |u_r| from MMG derivatives.

    The MMG standard method (Yasukawa & Yoshimura 2015) normalises the hull force with
    ``(rho/2) L d U^2`` and the moment with ``(rho/2) L^2 d U^2``, with ``v' = v/U`` and
    ``r' = r L/U``; so per unit speed ``Y_v/U = Y'_v (rho/2) L d``, ``Y_r/U = Y'_r (rho/2) L^2 d``,
    ``N_v/U = N'_v (rho/2) L^2 d``, ``N_r/U = N'_r (rho/2) L^3 d``.

    MMG's equations of motion carry ``(m + m_x) u r`` in sway and ``(m + m_y) v r`` in surge
    on the left-hand side, exactly what ``C_RB`` and ``C_A`` give here, but no added-mass
    term in yaw: its N'_v contains the Munk moment ``-(m_y - m_x) u v`` that ``C_A`` already
    gives here, and likewise N'_r the ``-M_A23 u r`` part. Hence (compare
    :func:`clarke1983_lift`, whose derivatives also include the sway Coriolis term)
    ``d_vv = -Y_v/U``, ``d_vr = -Y_r/U``, ``d_rv = -N_v/U - (M_A22 - M_A11)``,
    ``d_rr = -N_r/U - M_A23``.
    """
    q = 0.5 * rho_kg_m3 * d_m
    xa, ya, yra = M_A[0, 0], M_A[1, 1], M_A[1, 2]
    return np.array([
        -Y_v * q * L_m,
        -Y_r * q * L_m**2,
        -N_v * q * L_m**2 - (ya - xa),
        -N_r * q * L_m**3 - yra,
    ])


def added_mass_matrix(X_udot_kg: float, Y_vdot_kg: float, Y_rdot_kg_m: float,
                      N_vdot_kg_m: float, N_rdot_kg_m2: float) -> np.ndarray:
    """Added-mass matrix M_A (3x3, positive definite) from the (negative) derivatives.

    The off-diagonal term is symmetrised, ``-(Y_rdot + N_vdot)/2``: for an ideal fluid
    M_A is symmetric, and symmetry is what makes C_A(nu_r) skew-symmetric so that the
    model conserves kinetic energy without damping (Fossen 2021, sec. 6.3).
    """
    off = -0.5 * (Y_rdot_kg_m + N_vdot_kg_m)
    return np.array([[-X_udot_kg, 0.0, 0.0], [0.0, -Y_vdot_kg, off], [0.0, off, -N_rdot_kg_m2]])


def mass_matrices(vessel, added_mass_scale=(1.0, 1.0, 1.0)):
    """``(M_RB, M_A)`` (3x3 each, [kg, kg m, kg m^2] by row and column DOF) for a vessel, with
    optional per-DOF scaling of the added mass."""
    p, rb, am = vessel.particulars, vessel.rigid_body, vessel.added_mass
    M_RB = rigid_body_mass(rb.mass_kg, rb.I_z, rb.x_g_m)
    if am.method == "clarke1983":
        c = clarke1983_derivatives(p.L_pp_m, p.B_m, p.T_m, p.C_B, p.rho_water_kg_m3)
        X_udot = added_mass_surge_soding(rb.mass_kg, p.L_pp_m, p.rho_water_kg_m3)
        M_A = added_mass_matrix(X_udot, c["Y_vdot_kg"], c["Y_rdot_kg_m"], c["N_vdot_kg_m"], c["N_rdot_kg_m2"])
    else:
        M_A = added_mass_matrix(am.X_udot_kg, am.Y_vdot_kg, am.Y_rdot_kg_m, am.N_vdot_kg_m, am.N_rdot_kg_m2)
    s = np.sqrt(np.asarray(added_mass_scale, float))
    return M_RB, M_A * np.outer(s, s)  # keeps M_A symmetric; diagonal scaled by the factors


def linear_damping_from_time_constants(M: np.ndarray, T_surge_s: float, T_sway_s: float,
                                       T_yaw_s: float) -> np.ndarray:
    """Diagonal low-speed linear damping ``D = diag(M11/T1, M22/T2, M33/T3)`` [SI].

    Fossen (2021, sec. 6.4): each time constant is the e-folding time of a free decay
    of that DOF under linear damping alone.
    """
    T = np.array([T_surge_s, T_sway_s, T_yaw_s], dtype=float)
    if np.any(~(T > 0)):
        raise ValueError(f"damping time constants must be > 0 s, got {T.tolist()}")
    return np.diag(np.diag(M) / T)


def hoerner_cd(B_m: float, T_m: float) -> float:
    """Hoerner's 2-D cross-flow drag coefficient for a section of beam B and draught T [-]."""
    return float(np.interp(B_m / (2.0 * T_m), _HOERNER_B_2T, _HOERNER_CD))


def crossflow_strips(L_m: float, T_m: float, cd_2d: float, n_strips: int = 20,
                     rho_kg_m3: float = 1025.0, x_aft_m: float | None = None):
    """Strip positions and weights for the cross-flow drag integrals (Fossen 2021, eq. 6.105).

    ``Y = -sum_i w_i |v + x_i r| (v + x_i r)`` and ``N = -sum_i w_i x_i |v + x_i r| (v + x_i r)``
    with ``w_i = 0.5 rho T C_d dx`` (trapezoidal rule over ``x`` from ``x_aft`` to
    ``x_aft + L``; default the hull centred on the origin).

    Returns
    -------
    x_m, w_kg_m : ndarray, shape (n_strips + 1,)
    """
    if n_strips < 2:
        raise ValueError(f"damping.nonlinear.strips: need at least 2 strips, got {n_strips}")
    x0 = -0.5 * L_m if x_aft_m is None else float(x_aft_m)
    x = np.linspace(x0, x0 + L_m, n_strips + 1)
    dx = L_m / n_strips
    w = np.full(x.shape, 0.5 * rho_kg_m3 * T_m * cd_2d * dx)
    w[0] *= 0.5
    w[-1] *= 0.5
    return x, w


def ittc1957_cf(speed_m_s: float, L_m: float, nu_m2_s: float = NU_SEAWATER_M2_S) -> float:
    """ITTC-1957 model-ship correlation line, ``C_F = 0.075 / (log10 Re - 2)^2``."""
    Re = max(speed_m_s * L_m / nu_m2_s, 1e5)
    return 0.075 / (math.log10(Re) - 2.0) ** 2


def surge_quadratic_resistance(wetted_surface_m2: float, L_m: float, speed_ref_m_s: float,
                               form_factor_k: float, C_R: float,
                               rho_kg_m3: float = 1025.0) -> float:
    """Quadratic surge damping coefficient ``d_uu`` [kg/m], surge force ``-d_uu |u_r| u_r``.

    ``d_uu = 0.5 rho S ((1 + k) C_F(U_ref) + C_R)``: ITTC-1957 friction with a form factor
    and a residuary-resistance coefficient, frozen at a reference speed (Fossen 2021,
    sec. 6.4.1).
    """
    C_T = (1.0 + form_factor_k) * ittc1957_cf(speed_ref_m_s, L_m) + C_R
    return 0.5 * rho_kg_m3 * wetted_surface_m2 * C_T


# --------------------------------------------------------------------------- numpy views


def coriolis_rigid_body(nu, mass_kg: float, x_g_m: float = 0.0):
    """C_RB(nu) (Fossen 2021, eq. 6.43 for 3 DOF), batched: ``nu (..., 3) -> (..., 3, 3)``."""
    nu = np.asarray(nu, float)
    u, v, r = nu[..., 0], nu[..., 1], nu[..., 2]
    C = np.zeros(nu.shape[:-1] + (3, 3))
    C[..., 0, 2] = -mass_kg * (x_g_m * r + v)
    C[..., 1, 2] = mass_kg * u
    C[..., 2, 0] = -C[..., 0, 2]
    C[..., 2, 1] = -C[..., 1, 2]
    return C


def coriolis_added_mass(nu_r, M_A: np.ndarray):
    """C_A(nu_r) for a symmetric 3-DOF M_A (Fossen 2021, eq. 6.53), batched ``(..., 3) -> (..., 3, 3)``."""
    nu_r = np.asarray(nu_r, float)
    u, v, r = nu_r[..., 0], nu_r[..., 1], nu_r[..., 2]
    a = M_A[1, 1] * v + M_A[1, 2] * r
    C = np.zeros(nu_r.shape[:-1] + (3, 3))
    C[..., 0, 2] = -a
    C[..., 1, 2] = M_A[0, 0] * u
    C[..., 2, 0] = a
    C[..., 2, 1] = -M_A[0, 0] * u
    return C


# --------------------------------------------------------------------------- kernels


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def hull_forces_scalar(u, v, r, ur, vr, m, xg, m_a, d_lin, d_quad, d_lift, strip_x, strip_w):
    """Hull forces on the right-hand side of eq. 1 for one vessel, returned as a 3-tuple.

    ``out = -C_RB(nu) nu - C_A(nu_r) nu_r - D nu_r - D_n(nu_r) nu_r`` [N, N, N m].
    ``d_quad = [d_uu, d_vv, d_rr]`` are positive quadratic coefficients (force
    ``-d |x| x``); ``d_lift`` (8,) speed-proportional terms ``[d_vv, d_vr, d_rv, d_rr]`` per
    unit |u_r| and then per unit u_r (force ``-|u_r| D_lift [v_r, r] - u_r D'_lift [v_r, r]``);
    ``strip_x, strip_w`` the cross-flow drag strips (may be empty).
    """
    rr = r  # irrotational current: relative yaw rate equals yaw rate
    # C_RB(nu) nu
    crb0 = -m * (xg * r + v) * r
    crb1 = m * u * r
    crb2 = m * (xg * r + v) * u - m * u * v
    # C_A(nu_r) nu_r with symmetric M_A
    a = m_a[1, 1] * vr + m_a[1, 2] * rr
    ca0 = -a * rr
    ca1 = m_a[0, 0] * ur * rr
    ca2 = a * ur - m_a[0, 0] * ur * vr
    # linear damping D nu_r
    dl0 = d_lin[0, 0] * ur + d_lin[0, 1] * vr + d_lin[0, 2] * rr
    dl1 = d_lin[1, 0] * ur + d_lin[1, 1] * vr + d_lin[1, 2] * rr
    dl2 = d_lin[2, 0] * ur + d_lin[2, 1] * vr + d_lin[2, 2] * rr
    # nonlinear damping: quadratic terms and cross-flow drag
    dn0 = d_quad[0] * abs(ur) * ur
    dn1 = d_quad[1] * abs(vr) * vr
    dn2 = d_quad[2] * abs(rr) * rr
    au = abs(ur)
    dn1 += au * (d_lift[0] * vr + d_lift[1] * rr) + ur * (d_lift[4] * vr + d_lift[5] * rr)
    dn2 += au * (d_lift[2] * vr + d_lift[3] * rr) + ur * (d_lift[6] * vr + d_lift[7] * rr)
    for i in range(strip_x.shape[0]):
        vx = vr + strip_x[i] * rr
        f = strip_w[i] * abs(vx) * vx
        dn1 += f
        dn2 += strip_x[i] * f
    return -crb0 - ca0 - dl0 - dn0, -crb1 - ca1 - dl1 - dn1, -crb2 - ca2 - dl2 - dn2
