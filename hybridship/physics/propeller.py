"""Four-quadrant propeller model (Smogeli 2006) with Wageningen B-series Fourier coefficients.

The advance angle and the non-dimensional thrust and torque coefficients are

.. math::

    \\beta = \\operatorname{atan2}(V_a,\\ 0.7 \\pi n D), \\qquad
    C_T^*(\\beta) = \\sum_{k=0}^{N} A_T(k) \\cos k\\beta + B_T(k) \\sin k\\beta

    T = C_T^*(\\beta)\\ \\tfrac12 \\rho \\left(V_a^2 + (0.7 \\pi n D)^2\\right) \\tfrac{\\pi}{4} D^2, \\qquad
    Q = C_Q^*(\\beta)\\ \\tfrac12 \\rho \\left(V_a^2 + (0.7 \\pi n D)^2\\right) \\tfrac{\\pi}{4} D^3

with ``n`` the shaft speed [rev/s] and ``V_a`` the advance (inflow) speed [m/s] along the
propeller's positive-thrust axis. The four quadrants (Smogeli 2006, table 1):

=========  ========  =========  =========================================
quadrant   n         V_a        beta
=========  ========  =========  =========================================
1st        >= 0      >= 0       [0, 90 deg]    normal ahead operation
2nd        < 0       >= 0       (90, 180 deg]  crash-back while moving ahead
3rd        < 0       < 0        (-180, -90)    astern
4th        >= 0      < 0        [-90, 0)       ahead while moving astern
=========  ========  =========  =========================================

Sign conventions used throughout hybridship: positive rpm gives thrust along the
thruster's positive axis in open water (forward for a main propeller at azimuth 0,
starboard for a tunnel thruster); ``V_a`` is the speed of the propeller through the
water projected on that axis (positive when moving in the direction of positive thrust).
At ``n = 0`` a propeller moving through the water gives a drag opposing the motion
(``C_T^*(\\pm 90^\\circ)`` has the opposite sign to ``V_a``), never zero.

The Fourier tables (Roddy, Hess & Faller 2006) are packaged in ``hybridship/data``.
The coefficient sums use ``A(0)`` as listed (no ``A0/2`` factor).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numba
import numpy as np
import pandas as pd

from ..config import check_number, real_array
from .compiled_cache import KERNEL_FASTMATH

_TABLE_FILE = "wageningen_b_series_4q.csv"


@dataclass(frozen=True)
class PropellerCoefficients:
    """Four-quadrant Fourier coefficients of one propeller.

    Attributes
    ----------
    series : str
        Series name, e.g. ``"B4-70"`` (blades Z = 4, expanded area ratio 0.70).
    pitch_ratio : float
        Pitch-diameter ratio P/D [-].
    coef : ndarray, shape (4, N+1)
        Rows ``A_T, B_T, A_Q, B_Q`` for k = 0..N (read-only).
    """

    series: str
    pitch_ratio: float
    coef: np.ndarray

    @property
    def kt0(self) -> float:
        """Bollard thrust coefficient K_T at J = 0 [-]."""
        return float(kt_kq(0.0, self)[0])

    @property
    def kq0(self) -> float:
        """Bollard torque coefficient K_Q at J = 0 [-]."""
        return float(kt_kq(0.0, self)[1])


@lru_cache(maxsize=1)
def _table() -> pd.DataFrame:
    with resources.files("hybridship.data").joinpath(_TABLE_FILE).open("r") as fh:
        return pd.read_csv(fh)


def available_propellers() -> list[tuple[str, float]]:
    """List the ``(series, pitch_ratio)`` pairs in the packaged four-quadrant table."""
    t = _table()
    pairs = t[["series", "pitch_diameter_ratio"]].drop_duplicates()
    return [(str(s), float(p)) for s, p in pairs.itertuples(index=False)]


def load_wageningen(series: str = "B4-70", pitch_ratio: float = 1.0) -> PropellerCoefficients:
    """Load the Fourier coefficients of one Wageningen B-series propeller.

    Parameters
    ----------
    series : str
        Series name as in the table, e.g. ``"B4-70"``.
    pitch_ratio : float
        Pitch-diameter ratio P/D [-]; must match a tabulated value to 1e-6.

    Raises
    ------
    ValueError
        If the pair is not in the table (the message lists the available ones).
    TypeError
        If ``pitch_ratio`` is not a number (text, a bool or None).
    """
    pitch_ratio = check_number("pitch_ratio", pitch_ratio)     # float() read "1.0" and failed on None in its words
    t = _table()
    sel = t[(t["series"] == series) & (np.abs(t["pitch_diameter_ratio"] - pitch_ratio) < 1e-6)]
    if sel.empty:
        avail = ", ".join(f"{s} P/D {p:g}" for s, p in available_propellers())
        raise ValueError(
            f"propeller: no four-quadrant table for series {series!r} at P/D {pitch_ratio:g}; "
            f"available: {avail}"
        )
    sel = sel.sort_values("k")
    if not np.array_equal(sel["k"].to_numpy(), np.arange(len(sel))):
        raise ValueError(f"propeller: table for {series} P/D {pitch_ratio:g} has missing orders k")
    coef = np.ascontiguousarray(sel[["A_T", "B_T", "A_Q", "B_Q"]].to_numpy(dtype=float).T)
    coef.setflags(write=False)
    return PropellerCoefficients(series=series, pitch_ratio=float(pitch_ratio), coef=coef)


# --------------------------------------------------------------------------- kernels
# Scalar numba kernels: the dynamic model's compiled right-hand side calls these
# directly; the numpy-facing functions below loop over arrays in compiled code.


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def ct_cq_star_cs(c1, s1, coef):
    """C_T*, C_Q* from cos(beta), sin(beta) (cos/sin recurrences instead of 2N trig calls)."""
    ck = 1.0
    sk = 0.0
    ct = 0.0
    cq = 0.0
    for k in range(coef.shape[1]):
        ct += coef[0, k] * ck + coef[1, k] * sk
        cq += coef[2, k] * ck + coef[3, k] * sk
        ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
    return ct, cq


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def ct_star_cs(c1, s1, coef, i):
    """C_T* of propeller ``i`` of ``coef (K, 4, N)`` from cos(beta), sin(beta).

    The dynamics need thrust, not torque. Indexing the full coefficient array (no view
    per call) keeps the hot path free of array-reference bookkeeping.

    Four interleaved recurrences (orders k = 4j + m, each advanced by a rotation of 4 beta)
    instead of one: the same sum, but four independent dependency chains, which a CPU
    overlaps; this is the hot loop of every forecast.
    """
    c2 = 2.0 * c1 * c1 - 1.0
    s2 = 2.0 * s1 * c1
    c3 = c2 * c1 - s2 * s1
    s3 = s2 * c1 + c2 * s1
    c4 = 2.0 * c2 * c2 - 1.0
    s4 = 2.0 * s2 * c2
    a0, b0 = 1.0, 0.0
    a1, b1 = c1, s1
    a2, b2 = c2, s2
    a3, b3 = c3, s3
    t0 = 0.0
    t1 = 0.0
    t2 = 0.0
    t3 = 0.0
    n = coef.shape[2]
    n4 = n - n % 4
    for k in range(0, n4, 4):
        t0 += coef[i, 0, k] * a0 + coef[i, 1, k] * b0
        t1 += coef[i, 0, k + 1] * a1 + coef[i, 1, k + 1] * b1
        t2 += coef[i, 0, k + 2] * a2 + coef[i, 1, k + 2] * b2
        t3 += coef[i, 0, k + 3] * a3 + coef[i, 1, k + 3] * b3
        a0, b0 = a0 * c4 - b0 * s4, b0 * c4 + a0 * s4
        a1, b1 = a1 * c4 - b1 * s4, b1 * c4 + a1 * s4
        a2, b2 = a2 * c4 - b2 * s4, b2 * c4 + a2 * s4
        a3, b3 = a3 * c4 - b3 * s4, b3 * c4 + a3 * s4
    # remaining orders (n not a multiple of 4): a0..a3 now hold orders n4..n4+3
    if n4 < n:
        t0 += coef[i, 0, n4] * a0 + coef[i, 1, n4] * b0
    if n4 + 1 < n:
        t1 += coef[i, 0, n4 + 1] * a1 + coef[i, 1, n4 + 1] * b1
    if n4 + 2 < n:
        t2 += coef[i, 0, n4 + 2] * a2 + coef[i, 1, n4 + 2] * b2
    return (t0 + t1) + (t2 + t3)


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def thrust_scalar(n_rps, va_m_s, diameter_m, rho_kg_m3, coef, i):
    """Open-water thrust [N] of propeller ``i`` of ``coef (K, 4, N)`` (model of :func:`thrust_torque_scalar`)."""
    vr = 0.7 * math.pi * n_rps * diameter_m
    v2 = va_m_s * va_m_s + vr * vr
    if v2 == 0.0:
        return 0.0
    inv = 1.0 / math.sqrt(v2)
    return ct_star_cs(vr * inv, va_m_s * inv, coef, i) * 0.5 * rho_kg_m3 * v2 * 0.25 * math.pi * diameter_m * diameter_m


@numba.njit(cache=True)
def ct_cq_star_scalar(beta_rad, coef):
    """C_T*(beta), C_Q*(beta) for one advance angle [rad]."""
    return ct_cq_star_cs(math.cos(beta_rad), math.sin(beta_rad), coef)


@numba.njit(cache=True, fastmath=KERNEL_FASTMATH)
def thrust_torque_scalar(n_rps, va_m_s, diameter_m, rho_kg_m3, coef):
    """Open-water thrust [N] and torque [N m] for one propeller state (see module docstring)."""
    vr = 0.7 * math.pi * n_rps * diameter_m
    v2 = va_m_s * va_m_s + vr * vr
    if v2 == 0.0:
        return 0.0, 0.0
    # cos and sin of beta = atan2(V_a, 0.7 pi n D) without evaluating the angle itself
    inv = 1.0 / math.sqrt(v2)
    ct, cq = ct_cq_star_cs(vr * inv, va_m_s * inv, coef)
    q = 0.5 * rho_kg_m3 * v2 * 0.25 * math.pi * diameter_m * diameter_m
    return ct * q, cq * q * diameter_m


@numba.njit(cache=True)
def _ct_cq_star_flat(beta, coef, out):
    for i in range(beta.shape[0]):
        out[i, 0], out[i, 1] = ct_cq_star_scalar(beta[i], coef)


@numba.njit(cache=True)
def _thrust_torque_flat(n, va, diameter_m, rho, coef, out):
    for i in range(n.shape[0]):
        out[i, 0], out[i, 1] = thrust_torque_scalar(n[i], va[i], diameter_m, rho, coef)


# --------------------------------------------------------------------------- numpy API


def advance_angle(va_m_s, n_rps, diameter_m):
    """Advance angle beta = atan2(V_a, 0.7 pi n D) [rad] (broadcasting; text refused naming the argument)."""
    return np.arctan2(real_array("va_m_s", va_m_s), 0.7 * np.pi * real_array("n_rps", n_rps) * diameter_m)


def ct_cq_star(beta_rad, prop: PropellerCoefficients):
    """Four-quadrant coefficients C_T*(beta), C_Q*(beta) for an array of advance angles [rad]."""
    b = real_array("beta_rad", beta_rad)        # numpy read "0.3" as 0.3 rad
    flat = np.ascontiguousarray(b.ravel())
    out = np.empty((flat.size, 2))
    _ct_cq_star_flat(flat, prop.coef, out)
    return out[:, 0].reshape(b.shape), out[:, 1].reshape(b.shape)


def thrust_torque(n_rps, va_m_s, diameter_m: float, prop: PropellerCoefficients, rho_kg_m3: float = 1025.0):
    """Open-water thrust [N] and torque [N m] for shaft speeds and inflows broadcast together
    (element by element, as numpy broadcasts: not every combination of two 1-D arrays).

    Parameters
    ----------
    n_rps : array_like
        Shaft speed [rev/s], signed (positive gives positive thrust in open water).
    va_m_s : array_like
        Advance speed [m/s] along the positive-thrust axis (broadcast with ``n_rps``).
    diameter_m : float
        Propeller diameter D [m], > 0.
    prop : PropellerCoefficients
    rho_kg_m3 : float
        Water density [kg/m^3].

    Raises
    ------
    TypeError
        ``n_rps`` or ``va_m_s`` given as text or complex numbers.
    ValueError
        Non-finite states, shapes that do not broadcast, or a diameter or density that is
        not a number > 0 (each naming the argument).
    """
    _check_propeller_scalars(diameter_m, rho_kg_m3)
    n, va = _finite_pair("n_rps", n_rps, "va_m_s", va_m_s)
    out = np.empty((n.size, 2))
    _thrust_torque_flat(np.ascontiguousarray(n.ravel()), np.ascontiguousarray(va.ravel()),
                        float(diameter_m), float(rho_kg_m3), prop.coef, out)
    return out[:, 0].reshape(n.shape), out[:, 1].reshape(n.shape)


def _finite_pair(name_a, a, name_b, b):
    """Two state arrays as finite floats broadcast together, or an error naming them: text
    was parsed as a number ("100" as 100 rev/s), shapes that do not broadcast failed in
    numpy's words ("arg 0 ... arg 1"), and the compiled kernels assume finite numbers (a NaN
    shaft speed or inflow came back as 0 N)."""
    a, b = real_array(name_a, a), real_array(name_b, b)
    try:
        a, b = np.broadcast_arrays(a, b)
    except ValueError:
        raise ValueError(f"{name_a}, {name_b}: shapes {a.shape} and {b.shape} do not broadcast together") from None
    for name, x in ((name_a, a), (name_b, b)):
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{name}: contains NaN or inf")
    return a, b


def _check_propeller_scalars(diameter_m, rho_kg_m3, max_rpm=None) -> None:
    """Refuse a diameter, water density or rpm bound that is not a finite number > 0 (the
    kernels divided by them silently, or by zero)."""
    check_number("diameter_m", diameter_m, lo=0.0, lo_open=True)
    check_number("rho_kg_m3", rho_kg_m3, lo=0.0, lo_open=True)
    check_number("max_rpm", max_rpm, lo=0.0, lo_open=True, allow_none=True)


def kt_kq(J, prop: PropellerCoefficients):
    """First- and fourth-quadrant open-water K_T(J), K_Q(J) for n > 0.

    Uses K_T = C_T* (pi/8) (J^2 + (0.7 pi)^2) with beta = atan2(J, 0.7 pi), the identity
    between the four-quadrant and the classical open-water representation.
    """
    J = real_array("J", J)                      # numpy read "0.3" as J = 0.3
    beta = np.arctan2(J, 0.7 * np.pi)
    ct, cq = ct_cq_star(beta, prop)
    fac = np.pi / 8.0 * (J**2 + (0.7 * np.pi) ** 2)
    return ct * fac, cq * fac


def rpm_for_thrust(thrust_N, va_m_s, diameter_m: float, prop: PropellerCoefficients,
                   rho_kg_m3: float = 1025.0, max_rpm: float | None = None):
    """Shaft speed [rpm] that gives a demanded thrust at a given inflow (inverse model).

    Solved by bisection on the branch of T(n) for fixed V_a whose ends bracket the demand,
    vectorised over the inputs: the branch with the sign of the demanded thrust, unless
    the propeller at rest already gives more than the demand in that direction (its drag
    with inflow), when the shaft turns the other way. Demands beyond what ``max_rpm`` can
    deliver saturate at ``+-max_rpm``.

    Parameters
    ----------
    thrust_N, va_m_s : array_like
        Demanded thrust [N] and inflow speed [m/s] (broadcast together).
    diameter_m : float
    prop : PropellerCoefficients
    rho_kg_m3 : float
    max_rpm : float, optional
        Upper bound of |rpm|; default 3000 / D (a generous tip-speed bound).

    Raises
    ------
    TypeError, ValueError
        As :func:`thrust_torque`, naming ``thrust_N``, ``va_m_s`` or ``max_rpm``.
    """
    _check_propeller_scalars(diameter_m, rho_kg_m3, max_rpm)
    T, va = _finite_pair("thrust_N", thrust_N, "va_m_s", va_m_s)
    rpm_max = float(max_rpm) if max_rpm is not None else 3000.0 / diameter_m
    out = np.empty(T.size)
    _rpm_for_thrust_flat(np.ascontiguousarray(T.ravel()), np.ascontiguousarray(va.ravel()), float(diameter_m),
                         float(rho_kg_m3), prop.coef, rpm_max, out)
    return out.reshape(T.shape)


@numba.njit(cache=True)
def _rpm_for_thrust_flat(thrust_N, va_m_s, diameter_m, rho_kg_m3, coef, rpm_max, out):
    # Bisection on |rpm| between rest and rpm_max, on the branch whose ends bracket the
    # demand (T(n) is continuous, not monotonic near n = 0, so only the bracket matters).
    # Normally that is the branch with the sign of the demand. With inflow, a propeller at
    # rest already gives a force (its drag); when that force is past the demand in the
    # demand's direction, the shaft must turn the other way to take some of it back.
    for i in range(thrust_N.shape[0]):
        sign = 1.0 if thrust_N[i] >= 0.0 else -1.0
        t_rest, _q = thrust_torque_scalar(0.0, va_m_s[i], diameter_m, rho_kg_m3, coef)
        turn = -sign if sign * t_rest > sign * thrust_N[i] else sign
        lo = 0.0
        hi = rpm_max
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            t_mid, _q = thrust_torque_scalar(turn * mid / 60.0, va_m_s[i], diameter_m, rho_kg_m3, coef)
            # on the demand's own branch the thrust is below the demand near rest; on the
            # other branch it is above it
            if turn * t_mid < turn * thrust_N[i]:
                lo = mid
            else:
                hi = mid
        out[i] = turn * 0.5 * (lo + hi)
