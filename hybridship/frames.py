"""Kinematics: rotation about z, body <-> NED transforms, angle wrapping, flat-earth positions,
and flows (wind, current) between ``[speed, direction]`` and vector form.

Conventions (Fossen 2021, ch. 2):

* NED frame: x north, y east, z down; heading ``psi`` clockwise from north, in radians.
* Body frame: x forward, y starboard, z down.
* ``eta = [north_m, east_m, psi_rad]``, ``nu = [u_m_s, v_m_s, r_rad_s]``.

All functions are pure and batch-first: they accept arrays with any leading batch
shape (``(..., 3)`` for 3-vectors, ``(...)`` for angles) and never modify their inputs.
"""

from __future__ import annotations

import numpy as np

#: WGS-84 semi-major axis [m] and flattening [-] for the flat-earth conversion.
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563


def wrap_pi(angle_rad):
    """Wrap angles to the half-open interval [-pi, pi).

    Parameters
    ----------
    angle_rad : array_like
        Angles in radians, any shape.

    Returns
    -------
    ndarray
        The same angles in [-pi, pi) ("smallest signed angle", Fossen's ``ssa``).
    """
    a = np.asarray(angle_rad, dtype=float)
    w = np.mod(a + np.pi, 2.0 * np.pi) - np.pi
    # np.mod rounds to 2 pi itself for an argument just below a multiple of 2 pi (pi - 1e-16
    # came back as pi); that end of the interval is open, its angle is -pi
    w = w - 2.0 * np.pi * (w >= np.pi)
    # an angle already in range is returned as it is: the round trip through + pi, mod and
    # - pi can move it by a rounding step (a rudder at its 35-deg stop came back beyond it)
    return np.where((a >= -np.pi) & (a < np.pi), a, w)[()]


def wrap_2pi(angle_rad):
    """Wrap angles to [0, 2 pi), the usual range of a compass heading in radians."""
    a = np.asarray(angle_rad, dtype=float)
    w = np.mod(a, 2.0 * np.pi)
    return w - 2.0 * np.pi * (w >= 2.0 * np.pi)  # np.mod(-1e-20, 2 pi) rounds to 2 pi: fold it onto 0


def rotation_z(psi_rad):
    """Rotation matrix R(psi) from body to NED for 3-DOF motion.

    Parameters
    ----------
    psi_rad : array_like, shape (...)
        Heading [rad].

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R = [[cos, -sin, 0], [sin, cos, 0], [0, 0, 1]]`` so that ``eta_dot = R(psi) nu``.
    """
    psi = np.asarray(psi_rad, dtype=float)
    c, s = np.cos(psi), np.sin(psi)
    R = np.zeros(psi.shape + (3, 3))
    R[..., 0, 0] = c
    R[..., 0, 1] = -s
    R[..., 1, 0] = s
    R[..., 1, 1] = c
    R[..., 2, 2] = 1.0
    return R


def body_to_ned(vec_body, psi_rad):
    """Rotate 3-DOF body-frame vectors ``[x, y, yaw]`` into NED: ``R(psi) @ vec``.

    Parameters
    ----------
    vec_body : array_like, shape (..., 3)
        Body-frame vectors, e.g. ``nu = [u_m_s, v_m_s, r_rad_s]``.
    psi_rad : array_like, shape (...)
        Heading [rad], broadcast against the leading shape of ``vec_body``.

    Returns
    -------
    ndarray, shape (..., 3)
        NED vectors, e.g. ``eta_dot = [north_dot_m_s, east_dot_m_s, psi_dot_rad_s]``.
    """
    v = np.asarray(vec_body, dtype=float)
    psi = np.asarray(psi_rad, dtype=float)
    c, s = np.cos(psi), np.sin(psi)
    out = np.empty(np.broadcast_shapes(v.shape, psi.shape + (3,)))
    out[..., 0] = c * v[..., 0] - s * v[..., 1]
    out[..., 1] = s * v[..., 0] + c * v[..., 1]
    out[..., 2] = v[..., 2]
    return out


def ned_to_body(vec_ned, psi_rad):
    """Rotate 3-DOF NED vectors into the body frame: ``R(psi)^T @ vec`` (inverse of :func:`body_to_ned`)."""
    v = np.asarray(vec_ned, dtype=float)
    psi = np.asarray(psi_rad, dtype=float)
    c, s = np.cos(psi), np.sin(psi)
    out = np.empty(np.broadcast_shapes(v.shape, psi.shape + (3,)))
    out[..., 0] = c * v[..., 0] + s * v[..., 1]
    out[..., 1] = -s * v[..., 0] + c * v[..., 1]
    out[..., 2] = v[..., 2]
    return out


def unwrap_heading(psi_rad, axis=-1):
    """Remove 2 pi jumps from a heading series (thin wrapper over :func:`numpy.unwrap`)."""
    return np.unwrap(np.asarray(psi_rad, dtype=float), axis=axis)


def _check_latitude(name: str, value) -> None:
    """ValueError naming ``name`` when a latitude [deg] in ``value`` is beyond +-90 deg."""
    with np.errstate(invalid="ignore"):
        if np.any(np.abs(np.asarray(value, dtype=float)) > 90.0):
            raise ValueError(f"{name}: a latitude is within +-90 deg, got {np.nanmax(np.abs(value)):g} in magnitude "
                             f"(latitude and longitude swapped?)")


def latlon_to_north_east(lat_deg, lon_deg, lat0_deg, lon0_deg):
    """Flat-earth conversion of geodetic latitude/longitude to local north/east [m].

    Uses the WGS-84 meridian and prime-vertical radii of curvature at the reference
    latitude (Fossen 2021, sec. 2.5.2). Accurate to centimetres within a few km of the
    reference point, which covers a one-minute forecast.

    Parameters
    ----------
    lat_deg, lon_deg : array_like
        Latitude and longitude [deg].
    lat0_deg, lon0_deg : float
        Reference point (origin of the local frame) [deg].

    Returns
    -------
    north_m, east_m : ndarray
    """
    _check_latitude("lat_deg", lat_deg)
    _check_latitude("lat0_deg", lat0_deg)
    lat = np.radians(np.asarray(lat_deg, dtype=float))
    lon = np.radians(np.asarray(lon_deg, dtype=float))
    lat0, lon0 = np.radians(lat0_deg), np.radians(lon0_deg)
    e2 = WGS84_F * (2.0 - WGS84_F)
    s0 = np.sin(lat0)
    r_n = WGS84_A_M / np.sqrt(1.0 - e2 * s0**2)  # prime vertical
    r_m = r_n * (1.0 - e2) / (1.0 - e2 * s0**2)  # meridian
    dlon = wrap_pi(lon - lon0)
    north = (lat - lat0) * r_m
    east = dlon * r_n * np.cos(lat0)
    return north, east


def north_east_to_latlon(north_m, east_m, lat0_deg, lon0_deg):
    """Inverse of :func:`latlon_to_north_east` (flat-earth) returning ``(lat_deg, lon_deg)``;
    a reference latitude ``lat0_deg`` beyond +-90 deg is refused as there."""
    _check_latitude("lat0_deg", lat0_deg)
    lat0, lon0 = np.radians(lat0_deg), np.radians(lon0_deg)
    e2 = WGS84_F * (2.0 - WGS84_F)
    s0 = np.sin(lat0)
    r_n = WGS84_A_M / np.sqrt(1.0 - e2 * s0**2)
    r_m = r_n * (1.0 - e2) / (1.0 - e2 * s0**2)
    lat = lat0 + np.asarray(north_m, dtype=float) / r_m
    lon = lon0 + np.asarray(east_m, dtype=float) / (r_n * np.cos(lat0))
    return np.degrees(lat), np.degrees(wrap_pi(lon))


def speed_dir_to_vector(speed_dir):
    """A flow ``[speed, dir_rad]`` (..., 2) -> its vector ``[speed cos dir, speed sin dir]`` (..., 2).

    The direction keeps its own convention (wind: where it comes from; current: where it
    goes to); in NED, ``[north, east]`` components. Averaging flows as vectors handles a
    direction that turns through north.
    """
    a = np.asarray(speed_dir, dtype=float)
    return np.stack([a[..., 0] * np.cos(a[..., 1]), a[..., 0] * np.sin(a[..., 1])], axis=-1)


def vector_to_speed_dir(vec):
    """A flow vector (..., 2) -> ``[speed, dir_rad]`` (..., 2), direction in [-pi, pi] (``arctan2``:
    -pi for a vector pointing south with east component -0.0), the inverse of :func:`speed_dir_to_vector`."""
    v = np.asarray(vec, dtype=float)
    return np.stack([np.hypot(v[..., 0], v[..., 1]), np.arctan2(v[..., 1], v[..., 0])], axis=-1)
