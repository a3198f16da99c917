"""Wind-load coefficient curves, relative-wind geometry and the lookup table for the force kernel.

The 3-DOF wind load (Fossen 2021, sec. 10.1; Skulstad et al., eq. 3) is::

    tau_wind = 0.5 * rho_a * V_rw**2 * [C_X(gamma_rw) * A_F,
                                        C_Y(gamma_rw) * A_L,
                                        C_N(gamma_rw) * A_L * L_oa]

This module provides the dimensionless curves ``C_X, C_Y, C_N`` and the geometry that
feeds them. The numba force kernel lives elsewhere and consumes the uniform table built
by :func:`coefficient_table`.

Conventions (all functions, exactly)
------------------------------------
* ``gamma_rw`` [rad] is Fossen's relative wind angle ``gamma_rw = -atan2(v_rw, u_rw)``
  where ``(u_rw, v_rw)`` is the ship's velocity over ground in body axes minus the wind
  velocity in body axes. ``gamma = 0`` is a head wind; ``gamma > 0`` is wind from PORT,
  which pushes the ship to starboard (+y).
* Angles returned lie in ``(-pi, pi]``; curves accept any real angle and wrap it.
* All coefficients are signed functions of ``gamma``: ``C_X`` is even, ``C_Y`` and
  ``C_N`` are odd. A head wind gives ``C_X < 0`` (force aft) and ``C_Y = C_N = 0``.
* True wind direction is the direction the wind comes FROM, clockwise from north.
* SI units and radians inside; tables given in degrees are converted on entry.

Sources
-------
* Isherwood, R. M. (1972/73). Wind resistance of merchant ships. Trans. RINA 115,
  327-338. Regression coefficients in ``hybridship/data/isherwood_1972_wind.csv``.
* Blendermann, W. (1994). Parameter identification of wind loads on ships. J. Wind Eng.
  Ind. Aerodyn. 51, 339-351, as tabulated in Fossen (2021) sec. 10.1.2. Parameters in
  ``hybridship/data/blendermann_1994_wind.csv``.
* Fossen, T. I. (2021). Handbook of Marine Craft Hydrodynamics and Motion Control,
  2nd ed., Wiley, sec. 10.1 (relative wind, sign conventions).
"""

from __future__ import annotations

import functools
from importlib import resources

import numpy as np
import pandas as pd

from ..config import check_number, check_whole_number, real_array

__all__ = [
    "relative_wind",
    "isherwood_coefficients",
    "blendermann_coefficients",
    "blendermann_vessel_types",
    "tabulated_coefficients",
    "coefficient_table",
    "interpolate_table",
]

_TWO_PI = 2.0 * np.pi


# --------------------------------------------------------------------------- helpers


def _wrap_gamma(gamma_rad):
    """Wrap angles to (-pi, pi] so that sgn(gamma) is well defined at +-pi (text is refused
    naming gamma_rad: numpy read "0.5" as 0.5 rad)."""
    g = real_array("gamma_rad", gamma_rad)
    # pi - mod(pi - g, 2 pi) maps onto (-pi, pi] (upper end closed on purpose); angles
    # already in range are passed through bit-exactly so that odd/even symmetry is exact.
    inside = (g > -np.pi) & (g <= np.pi)
    w = np.pi - np.mod(np.pi - g, _TWO_PI)
    # np.mod rounds to 2 pi for an angle just above pi (pi + 4e-16 came back as -pi, outside
    # the range): that end is open, its angle is pi
    return np.where(inside, g, np.where(w <= -np.pi, np.pi, w))


def _check_positive(name, value, *, allow_zero=False):
    v = check_number(name, value)       # text, bools and None refused naming the field
    if not np.isfinite(v) or v < 0.0 or (v == 0.0 and not allow_zero):
        need = "finite and >= 0" if allow_zero else "finite and > 0"
        raise ValueError(f"{name}: must be {need}, got {value!r}")
    return v


def _check_finite(name, value):
    v = check_number(name, value)
    if not np.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    return v


# ------------------------------------------------------------------ relative wind


def relative_wind(wind_speed_m_s, wind_dir_from_rad, psi_rad, u_m_s, v_m_s):
    """Relative wind speed and Fossen's relative wind angle.

    Parameters
    ----------
    wind_speed_m_s : array_like
        True wind speed over ground [m/s], >= 0.
    wind_dir_from_rad : array_like
        True wind direction [rad]: where the wind comes FROM, clockwise from north.
    psi_rad : array_like
        Ship heading [rad], clockwise from north.
    u_m_s, v_m_s : array_like
        Ship velocity over ground in body axes [m/s] (surge forward, sway starboard).

    Returns
    -------
    V_rw_m_s : ndarray
        Relative wind speed ``sqrt(u_rw**2 + v_rw**2)`` [m/s].
    gamma_rw_rad : ndarray
        ``-atan2(v_rw, u_rw)`` wrapped to (-pi, pi] [rad]; 0 = head wind, > 0 = wind
        from port. 0 when ``V_rw = 0``.

    Raises
    ------
    TypeError
        An input given as text or complex numbers (named).
    ValueError
        A negative wind speed.

    Notes
    -----
    All inputs broadcast against each other (any shapes).

    The wind blows towards ``beta + pi``, so in NED its velocity is
    ``-V_w [cos beta, sin beta]``; rotating into body axes gives
    ``u_w = -V_w cos(beta - psi)`` and ``v_w = -V_w sin(beta - psi)``
    (Fossen 2021, sec. 10.1). Then ``u_rw = u - u_w`` and ``v_rw = v - v_w``.
    """
    # text refused naming the argument (numpy read "10" as 10 m/s)
    V_w = real_array("wind_speed_m_s", wind_speed_m_s)
    if np.any(V_w < 0.0):       # the direction carries the way it blows: -10 m/s from north acted as from south
        raise ValueError(f"wind_speed_m_s: {np.min(V_w):g} m/s is negative; expected a speed >= 0 (the direction "
                         f"wind_dir_from_rad says where it comes from)")
    rel_dir = real_array("wind_dir_from_rad", wind_dir_from_rad) - real_array("psi_rad", psi_rad)
    u_rw = real_array("u_m_s", u_m_s) + V_w * np.cos(rel_dir)
    v_rw = real_array("v_m_s", v_m_s) + V_w * np.sin(rel_dir)
    V_rw = np.hypot(u_rw, v_rw)
    # -atan2 can give exactly -pi (v_rw = +0, u_rw < 0); the wrap sends it to +pi.
    gamma = _wrap_gamma(-np.arctan2(v_rw, u_rw))
    # no relative wind: 0, as documented (atan2 of signed zeros gave pi for u_rw = -0.0)
    return V_rw, np.where(V_rw == 0.0, 0.0, gamma)


# ---------------------------------------------------------------------- Isherwood


@functools.lru_cache(maxsize=1)
def _isherwood_table():
    path = resources.files("hybridship.data").joinpath("isherwood_1972_wind.csv")
    with path.open("r", encoding="utf-8") as fh:
        df = pd.read_csv(fh)
    angle_deg = df["gamma_deg"].to_numpy(dtype=float)
    A = df[[f"A{i}" for i in range(7)]].to_numpy(dtype=float)
    B = df[[f"B{i}" for i in range(7)]].to_numpy(dtype=float)
    C = df[[f"C{i}" for i in range(6)]].to_numpy(dtype=float)
    for arr in (angle_deg, A, B, C):
        arr.setflags(write=False)
    return angle_deg, A, B, C


def isherwood_coefficients(gamma_rad, *, L_oa_m, B_m, A_L_m2, A_F_m2, A_SS_m2, S_m, C_m, M):
    """Isherwood (1972) wind coefficients for merchant ships.

    Parameters
    ----------
    gamma_rad : array_like
        Relative wind angle ``gamma_rw`` [rad], any shape (wrapped to (-pi, pi]).
    L_oa_m : float
        Length overall [m].
    B_m : float
        Beam [m].
    A_L_m2 : float
        Lateral projected wind area [m^2].
    A_F_m2 : float
        Frontal (transverse) projected wind area [m^2].
    A_SS_m2 : float
        Lateral projected area of the superstructure only [m^2].
    S_m : float
        Perimeter of the lateral projection, excluding the waterline and slender items
        such as masts and ventilators [m].
    C_m : float
        Distance from the bow to the centroid of ``A_L`` [m].
    M : float
        Number of distinct groups of masts or king posts seen in side view [-].

    Returns
    -------
    C_X, C_Y, C_N : ndarray
        Signed coefficients, same shape as ``gamma_rad``: ``C_X`` (on ``A_F``) even,
        ``C_Y`` (on ``A_L``) and ``C_N`` (on ``A_L * L_oa``) odd in gamma.

    Notes
    -----
    The regression is evaluated at the 10-deg grid points of the table and linearly
    interpolated in ``|gamma|``; since the regression is linear in the tabulated
    coefficients this equals interpolating the coefficients themselves. Isherwood's
    ``C_Y`` and ``C_N`` are magnitudes for ``|gamma|`` and take the sign of gamma.
    """
    L = _check_positive("L_oa_m", L_oa_m)
    B = _check_positive("B_m", B_m)
    A_L = _check_positive("A_L_m2", A_L_m2)
    A_F = _check_positive("A_F_m2", A_F_m2)
    A_SS = _check_positive("A_SS_m2", A_SS_m2, allow_zero=True)
    S = _check_positive("S_m", S_m)
    C = _check_finite("C_m", C_m)
    M_ = _check_positive("M", M, allow_zero=True)

    angle_deg, A, Bc, Cc = _isherwood_table()
    aL = 2.0 * A_L / L**2
    aF = 2.0 * A_F / B**2
    x_terms = np.array([1.0, aL, aF, L / B, S / L, C / L, M_])
    y_terms = np.array([1.0, aL, aF, L / B, S / L, C / L, A_SS / A_L])
    n_terms = np.array([1.0, aL, aF, L / B, S / L, C / L])
    cx_nodes = -(A @ x_terms)
    cy_nodes = Bc @ y_terms
    cn_nodes = Cc @ n_terms

    g = _wrap_gamma(gamma_rad)
    abs_deg = np.degrees(np.abs(g))
    sgn = np.sign(g)
    C_X = np.interp(abs_deg, angle_deg, cx_nodes)
    C_Y = sgn * np.interp(abs_deg, angle_deg, cy_nodes)
    C_N = sgn * np.interp(abs_deg, angle_deg, cn_nodes)
    return C_X, C_Y, C_N


# ------------------------------------------------------------------- Blendermann


@functools.lru_cache(maxsize=1)
def _blendermann_table():
    path = resources.files("hybridship.data").joinpath("blendermann_1994_wind.csv")
    with path.open("r", encoding="utf-8") as fh:
        df = pd.read_csv(fh)
    rows = {}
    for rec in df.itertuples(index=False):
        rows[str(rec.vessel_type)] = (
            float(rec.CD_t),
            float(rec.CD_lAF_bow),
            float(rec.CD_lAF_stern),
            float(rec.delta),
            float(rec.kappa),
        )
    return rows


def blendermann_vessel_types():
    """Names of the 17 Blendermann (1994) vessel types, in the table's order.

    Returns
    -------
    list of str
        Valid values for ``vessel_type`` in :func:`blendermann_coefficients`.
    """
    return list(_blendermann_table())


def _normalise_name(name):
    return " ".join(str(name).replace(",", " ").split()).lower()


def _blendermann_params(vessel_type):
    table = _blendermann_table()
    if vessel_type in table:
        return table[vessel_type]
    # Forgive case, commas and spacing ("tanker loaded" == "Tanker, loaded").
    key = _normalise_name(vessel_type)
    for name, params in table.items():
        if _normalise_name(name) == key:
            return params
    valid = ", ".join(repr(n) for n in table)
    raise ValueError(f"vessel_type: unknown Blendermann vessel type {vessel_type!r}; valid names are: {valid}")


def blendermann_coefficients(gamma_rad, *, vessel_type: str, A_F_m2, A_L_m2, L_oa_m, s_L_m):
    """Blendermann (1994) wind coefficients for 17 vessel types.

    Parameters
    ----------
    gamma_rad : array_like
        Relative wind angle ``gamma_rw`` [rad], any shape (wrapped to (-pi, pi]).
    vessel_type : str
        One of :func:`blendermann_vessel_types` (case, commas and spacing ignored),
        e.g. ``"Research vessel"``.
    A_F_m2 : float
        Frontal projected wind area [m^2].
    A_L_m2 : float
        Lateral projected wind area [m^2].
    L_oa_m : float
        Length overall [m].
    s_L_m : float
        Longitudinal position of the ``A_L`` centroid from midship, positive forward [m].

    Returns
    -------
    C_X, C_Y, C_N : ndarray
        Signed coefficients, same shape as ``gamma_rad``: ``C_X`` (on ``A_F``) even,
        ``C_Y`` (on ``A_L``) and ``C_N`` (on ``A_L * L_oa``) odd in gamma.

    Raises
    ------
    ValueError
        Unknown ``vessel_type`` (the message lists the valid names) or bad geometry.

    Notes
    -----
    With ``CD_l = CD_lAF * A_F / A_L`` and
    ``den = 1 - delta/2 * (1 - CD_l/CD_t) * sin(2 gamma)**2``::

        C_X = -CD_lAF cos(gamma) / den       (bow CD_lAF for |gamma| <= 90 deg, else stern)
        C_Y =  CD_t   sin(gamma) / den
        C_N = (s_L/L_oa - 0.18 (|gamma| - pi/2)) C_Y

    ``|gamma|`` in the ``C_N`` bracket keeps ``C_N`` odd; some published code uses the
    signed gamma there, which gives e.g. -0.50 instead of -0.023 at -90 deg for the
    research vessel.
    """
    CD_t, CD_bow, CD_stern, delta, _kappa = _blendermann_params(vessel_type)
    A_F = _check_positive("A_F_m2", A_F_m2)
    A_L = _check_positive("A_L_m2", A_L_m2)
    L = _check_positive("L_oa_m", L_oa_m)
    s_L = _check_finite("s_L_m", s_L_m)

    g = _wrap_gamma(gamma_rad)
    abs_g = np.abs(g)
    CD_lAF = np.where(abs_g <= 0.5 * np.pi, CD_bow, CD_stern)
    CD_l = CD_lAF * A_F / A_L
    den = 1.0 - 0.5 * delta * (1.0 - CD_l / CD_t) * np.sin(2.0 * g) ** 2
    C_X = -CD_lAF * np.cos(g) / den
    C_Y = CD_t * np.sin(g) / den
    C_N = (s_L / L - 0.18 * (abs_g - 0.5 * np.pi)) * C_Y
    return C_X, C_Y, C_N


# --------------------------------------------------------------- user tables


def _as_1d_finite(field, values):
    try:        # text refused, also text that reads as a number (numpy read "90" as 90)
        arr = real_array(field, values)
    except TypeError:
        raise ValueError(f"{field}: must be a list of numbers, got {values!r}") from None
    if arr.ndim != 1:
        raise ValueError(f"{field}: must be one-dimensional, got shape {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{field}: must be finite, got {arr[i]!r} at index {i}")
    return arr


def _validate_table(angle_deg, C_X, C_Y, C_N, name):
    """Check a user wind table; return (angles, CX, CY, CN, symmetric)."""
    ang = _as_1d_finite(f"{name}.angle_deg", angle_deg)
    cols = {
        "C_X": _as_1d_finite(f"{name}.C_X", C_X),
        "C_Y": _as_1d_finite(f"{name}.C_Y", C_Y),
        "C_N": _as_1d_finite(f"{name}.C_N", C_N),
    }
    if ang.size < 2:
        raise ValueError(f"{name}.angle_deg: needs at least 2 angles, got {ang.size}")
    steps = np.diff(ang)
    if np.any(steps <= 0.0):
        i = int(np.flatnonzero(steps <= 0.0)[0])
        raise ValueError(
            f"{name}.angle_deg: must be strictly increasing, got {ang[i]:g} then {ang[i + 1]:g} at index {i + 1}"
        )
    for key, col in cols.items():
        if col.size != ang.size:
            raise ValueError(f"{name}.{key}: must have the same length as {name}.angle_deg ({ang.size}), got {col.size}")

    tol = 1e-9
    first, last = ang[0], ang[-1]
    if abs(first) <= tol and abs(last - 180.0) <= tol:
        for key in ("C_Y", "C_N"):
            for idx, where in ((0, 0), (-1, 180)):
                val = cols[key][idx]
                if abs(val) > tol:
                    raise ValueError(
                        f"{name}.{key}: must be 0 at {where} deg for a symmetric table, got {val:g}"
                    )
        return ang, cols["C_X"], cols["C_Y"], cols["C_N"], True

    if abs((last - first) - 360.0) <= tol and first >= -180.0 - tol and last <= 360.0 + tol:
        # The closing point duplicates the first one; a mismatch is a typo, not a jump.
        for key, col in cols.items():
            if abs(col[-1] - col[0]) > tol:
                raise ValueError(
                    f"{name}.{key}: a full-circle table must end with its first value "
                    f"({col[0]:g} at {first:g} deg), got {col[-1]:g} at {last:g} deg"
                )
        return ang, cols["C_X"], cols["C_Y"], cols["C_N"], False

    raise ValueError(
        f"{name}.angle_deg: must span 0..180 (port/starboard symmetric) or a full circle "
        f"such as 0..360 or -180..180, got {first:g}..{last:g}"
    )


def tabulated_coefficients(gamma_rad, *, angle_deg, C_X, C_Y, C_N, name="wind"):
    """Wind coefficients from a user table (e.g. a vessel file), linearly interpolated.

    Parameters
    ----------
    gamma_rad : array_like
        Relative wind angle ``gamma_rw`` [rad], any shape.
    angle_deg : sequence of float
        Table angles [deg] in the ``gamma_rw`` convention (0 = head wind, positive =
        wind from port), strictly increasing. Either

        * ``0 .. 180``: the vessel is taken as port/starboard symmetric; ``C_X`` is
          mirrored as an even function and ``C_Y``, ``C_N`` as odd functions
          (``sgn(gamma) * C(|gamma|)``), so ``C_Y`` and ``C_N`` must be 0 at 0 and 180 deg;
        * a full circle, ``first .. first + 360`` within ``-180 .. 360`` (e.g. ``0 .. 360``
          or ``-180 .. 180``): interpolated periodically with no symmetry assumed; the
          last row must repeat the first.
    C_X, C_Y, C_N : sequence of float
        Coefficients at ``angle_deg`` (``C_X`` on ``A_F``, ``C_Y`` on ``A_L``, ``C_N`` on
        ``A_L * L_oa``), same length as ``angle_deg``.
    name : str, optional
        Prefix for field names in error messages (default ``"wind"``).

    Returns
    -------
    C_X, C_Y, C_N : ndarray
        Coefficients at ``gamma_rad``, same shape.

    Raises
    ------
    ValueError
        Text or non-finite values, non-increasing angles, unequal lengths, an unsupported
        angle span, non-zero ``C_Y``/``C_N`` at 0 or 180 deg of a symmetric table, or a
        full-circle table whose last row differs from its first. The message names
        the field, e.g. ``"wind.C_Y: must be 0 at 0 deg for a symmetric table, got 0.1"``.
    """
    ang, cx, cy, cn, symmetric = _validate_table(angle_deg, C_X, C_Y, C_N, name)
    g = _wrap_gamma(gamma_rad)
    if symmetric:
        abs_deg = np.degrees(np.abs(g))
        sgn = np.sign(g)
        return (
            np.interp(abs_deg, ang, cx),
            sgn * np.interp(abs_deg, ang, cy),
            sgn * np.interp(abs_deg, ang, cn),
        )
    deg = np.degrees(g)
    # Drop the closing duplicate; np.interp's period argument closes the circle.
    xp = ang[:-1]
    return (
        np.interp(deg, xp, cx[:-1], period=360.0),
        np.interp(deg, xp, cy[:-1], period=360.0),
        np.interp(deg, xp, cn[:-1], period=360.0),
    )


# ---------------------------------------------------------- table for the kernel


def coefficient_table(curve_fn, n=721):
    """Sample a coefficient curve on a uniform gamma grid for the force kernel.

    Parameters
    ----------
    curve_fn : callable
        ``curve_fn(gamma_rad) -> (C_X, C_Y, C_N)`` accepting a 1-D array, e.g.
        ``functools.partial(blendermann_coefficients, vessel_type=..., ...)``.
    n : int, optional
        Number of grid points, >= 3 (default 721: 0.5-deg spacing, which contains the
        10-deg nodes of the Isherwood and 0..180 tables exactly).

    Returns
    -------
    gamma_grid_rad : ndarray, shape (n,)
        ``np.linspace(-pi, pi, n)`` [rad]; the first and last rows describe the same
        angle and hold the same values.
    table : ndarray, shape (n, 3), float64, C-contiguous
        Columns ``[C_X, C_Y, C_N]``.

    Raises
    ------
    ValueError
        ``n`` not a whole number >= 3, a curve returning the wrong shape, or non-finite values.
    TypeError
        A curve returning text.
    """
    n = check_whole_number("n", n, lo=3)     # int(3.7) silently made 3 points
    grid = np.linspace(-np.pi, np.pi, n)
    out = curve_fn(grid)
    n_items = len(out) if isinstance(out, (tuple, list, np.ndarray)) else None
    if n_items != 3:
        got = f"{n_items} items" if n_items is not None else type(out).__name__
        raise ValueError(f"curve_fn: must return (C_X, C_Y, C_N), got {got}")
    cols = []
    for key, col in zip(("C_X", "C_Y", "C_N"), out):
        col = real_array(f"curve_fn: {key}", col)       # text failed in float()'s words
        try:        # a wrong shape failed in numpy's words ('could not be broadcast ... remapped shapes')
            arr = np.broadcast_to(col, grid.shape)
        except ValueError:
            raise ValueError(f"curve_fn: {key} has shape {col.shape}; expected one value per angle of the "
                             f"{grid.size}-point grid (or one value)") from None
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"curve_fn: {key} is not finite on the gamma grid")
        cols.append(arr)
    table = np.ascontiguousarray(np.stack(cols, axis=1), dtype=np.float64)
    # -pi and +pi are the same angle; curves wrap -pi to +pi, but force equality anyway
    # so the kernel's periodic lookup has no seam.
    table[0] = table[-1]
    return grid, table


def interpolate_table(gamma_rad, table):
    """Periodic linear interpolation in a table from :func:`coefficient_table`.

    Pure-numpy reference for the compiled kernel's lookup.

    Parameters
    ----------
    gamma_rad : array_like
        Relative wind angle [rad], any shape and any real value.
    table : array_like, shape (n, 3)
        ``[C_X, C_Y, C_N]`` on ``np.linspace(-pi, pi, n)``.

    Returns
    -------
    C_X, C_Y, C_N : ndarray
        Interpolated coefficients, same shape as ``gamma_rad``.
    """
    tab = real_array("table", table)
    if tab.ndim != 2 or tab.shape[1] != 3 or tab.shape[0] < 3:
        raise ValueError(f"table: must have shape (n >= 3, 3), got {tab.shape}")
    n = tab.shape[0]
    h = _TWO_PI / (n - 1)
    g = real_array("gamma_rad", gamma_rad)
    # Position along the grid in cells, wrapped into [0, n - 1).
    with np.errstate(invalid="ignore"):  # inf angles become NaN below, as intended
        pos = np.mod(g + np.pi, _TWO_PI) / h
    # NaN/inf angles: use a valid index and let the weight carry the NaN through.
    pos_safe = np.where(np.isfinite(pos), pos, 0.0)
    i = np.minimum(np.floor(pos_safe).astype(np.intp), n - 2)
    w = pos - i
    lo = tab[i]
    hi = tab[i + 1]
    vals = lo + w[..., None] * (hi - lo)
    return vals[..., 0], vals[..., 1], vals[..., 2]
