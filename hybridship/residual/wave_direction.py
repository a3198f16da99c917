"""The waves' direction from the ship's wave-frequency motion, and a yaw load that turns with it.

After a failure the ship turns, and the wave drift's yaw moment, which depends on the
heading relative to the waves, changes with it, often in sign. The environment estimator
holds the yaw load it found in station keeping; this module lets that load turn with the
ship. Two steps:

* **The waves' axis.** First-order waves move a ship back and forth along their direction
  of travel. Over the last ``window_s`` of station keeping, the body-frame velocity
  ``(u, v)`` band-passed to wave periods (``band_s``, 3.5-15 s: scipy's Butterworth filter,
  forward and backward) and turned into NED with each sample's heading is spread along one
  axis; its principal axis (the eigenvector of the larger eigenvalue of the 2 x 2
  covariance) is the waves' direction modulo 180 deg. This is the ship used as a wave buoy, in its
  simplest form. Where the spread is not elongated (``min_anisotropy``, the ratio of the
  two eigenvalues: calm water, or a cross sea) there is no axis.
* **The yaw load's shape.** A slender hull's mean wave-drift yaw moment is zero in head,
  following and beam seas and largest in between; the simplest shape with those zeros is
  ``sin(2 beta)``, with ``beta`` the relative wave direction, which modulo 180 deg the axis
  gives. The yaw load a forecast starts with, ``b_n`` (the estimator's at the start, which
  it follows through the drift), is taken as ``A sin(2 beta_0)`` with ``beta_0`` the
  relative wave direction at the start's heading ``psi_0``; at heading ``psi`` of the
  forecast it is ``b_n sin(2 (d - psi)) / sin(2 (d - psi_0))``, ``d`` the axis in NED. Where
  ``|sin(2 beta_0)|`` is small (``EnvironmentConfig.min_wave_sin2``) the amplitude cannot be
  told from the load, and the load is held, as without this option. (Until 2026-12-03
  ``beta_0`` was the station keeping's mean: for a start after the ship had turned that
  scaled a load the estimator had already followed, and along the drifts of truthsim-dev
  and of our own scenarios it made the heading error worse than holding the load;
  ``benchmarks/wave_yaw_choice.py``.)

What the shape leaves out: the part of the yaw load that is not wave drift (the wind
model's error, the current's moment) turns with it too, and the surge and sway loads stay
held in NED. ``benchmarks/wave_direction.py`` compares the axis and the turned load with the
simulators' truth; ``docs/concepts/environment.md`` reports it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfiltfilt

from ..frames import body_to_ned
from .drift_hull import MIN_FAILURES, gain_carries_over

__all__ = ["WaveAxis", "wave_axis", "wave_yaw_choice", "yaw_load_factor"]

#: Wave periods [s] whose motion gives the axis: above the 1-s sampling's Nyquist limit with
#: margin, below the slow drift and the DP's own oscillations.
WAVE_BAND_S = (3.5, 15.0)


@dataclass(frozen=True)
class WaveAxis:
    """The waves' axis found in station keeping.

    Attributes
    ----------
    axis_ned_rad : float
        Direction of the waves' axis in NED [rad], modulo pi.
    anisotropy : float
        Ratio of the larger to the smaller variance of the wave-frequency velocity [-].
    sin2_station : float
        Mean of ``sin(2 (axis - psi))`` over the station keeping's last ``average_s`` [-].
    """

    axis_ned_rad: float
    anisotropy: float
    sin2_station: float


def wave_axis(time_s: np.ndarray, psi_rad: np.ndarray, u_m_s: np.ndarray, v_m_s: np.ndarray, *,
              window_s: float = 600.0, average_s: float = 300.0, band_s=WAVE_BAND_S,
              min_anisotropy: float = 3.0) -> WaveAxis | None:
    """The waves' axis from the station keeping that ends at the last sample given.

    Parameters
    ----------
    time_s, psi_rad, u_m_s, v_m_s : ndarray, shape (N,)
        Times [s], heading [rad] and body-frame velocities [m/s] of the station keeping
        up to the failure, one segment (equally spaced); NaN velocities count as 0, and a
        sample without a heading (NaN) is left out of the axis and of ``sin2_station`` (its
        motion cannot be turned into NED).
    window_s : float
        Length of station keeping whose wave-frequency motion is used [s].
    average_s : float
        Length over which the heading enters ``sin2_station`` [s].
    band_s : (float, float)
        Shortest and longest wave period [s].
    min_anisotropy : float
        Least ratio of the two variances for an axis.

    Returns
    -------
    WaveAxis or None
        None when the window is shorter than ten of the longest periods, the sampling
        cannot resolve the band, the motion has no axis, or no heading is known in the
        last ``average_s``.
    """
    t = np.asarray(time_s, dtype=float)
    if t.size == 0:             # no station keeping: a window shorter than any
        return None
    keep = t >= t[-1] - window_s
    t, psi = t[keep], np.array(psi_rad, dtype=float)[keep]
    known = np.isfinite(psi)
    psi[known] = np.unwrap(psi[known])
    dt = float(np.median(np.diff(t))) if t.size > 1 else np.inf
    if t[-1] - t[0] < 10 * band_s[1] or not 2 * dt < band_s[0]:
        return None
    sos = butter(4, [1.0 / band_s[1], 1.0 / band_s[0]], btype="band", fs=1.0 / dt, output="sos")
    uv = np.zeros((t.size, 3))
    uv[:, :2] = sosfiltfilt(sos, np.nan_to_num(np.column_stack([u_m_s, v_m_s]).astype(float)[keep]), axis=0)
    # into NED at each sample: the waves' axis is fixed there while the ship may turn
    recent = (t >= t[-1] - average_s) & known
    if np.count_nonzero(known) < 2 or not recent.any():
        return None
    var, vec = np.linalg.eigh(np.cov(body_to_ned(uv, psi)[known, :2].T))
    if not var[1] > 0 or var[1] < min_anisotropy * max(var[0], 1e-12 * var[1]):
        return None
    axis = float(np.arctan2(vec[1, 1], vec[0, 1]))
    s2 = float(np.mean(np.sin(2.0 * (axis - psi[recent]))))
    return WaveAxis(axis % np.pi, float(var[1] / max(var[0], 1e-12 * var[1])), s2)


def yaw_load_factor(psi_rad: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The factor on the held yaw load at headings ``psi_rad`` (S,) [rad].

    ``axis`` (S, 2) holds each start's ``[axis_ned_rad, sin2_0]``, ``sin2_0`` the shape's
    value where the load is known (at the start's heading), NaN where the load is held (no
    axis, or ``|sin2_0|`` too small to give the amplitude: the caller decides). The factor is
    ``sin(2 (axis - psi)) / sin2_0``, and 1 where held.
    """
    d, s2 = axis[:, 0], axis[:, 1]
    ok = np.isfinite(d) & np.isfinite(s2) & (np.nan_to_num(s2) != 0.0)
    return np.where(ok, np.sin(2.0 * (np.nan_to_num(d) - psi_rad)) / np.where(ok, s2, 1.0), 1.0)


def wave_yaw_choice(errors_rad: np.ndarray, exclude: int | None = None) -> dict:
    """Whether the yaw load should turn with the waves after a failure, by the rule of what
    ``fit`` learns from failures (:func:`~hybridship.residual.drift_hull.gain_carries_over`).

    Parameters
    ----------
    errors_rad : ndarray, shape (2, L)
        Per failure, the mean heading error [rad] of the forecasts along its drift with the
        yaw load held (row 0) and turned with the waves (row 1).
    exclude : int or None
        A failure left out of the choice (the one a benchmark then scores), or None.

    Returns
    -------
    dict
        ``n_failures`` (those it was chosen on) and ``turned``; with at least
        :data:`~hybridship.residual.drift_hull.MIN_FAILURES` failures also their mean errors
        ``held_deg`` and ``turned_deg`` [deg], ``n_gains`` (failures with a lower error turned)
        and the signed-rank test's ``p_value``. Fewer failures: held (``turned`` False).
    """
    errors_rad = np.asarray(errors_rad, dtype=float)
    keep = [j for j in range(errors_rad.shape[1]) if j != exclude]
    held, turned = errors_rad[0, keep], errors_rad[1, keep]
    info = {"n_failures": len(keep), "turned": False}
    if len(keep) < MIN_FAILURES:
        return info
    chosen, p_value = gain_carries_over(held, turned)
    info.update(held_deg=float(np.degrees(held.mean())), turned_deg=float(np.degrees(turned.mean())),
                n_gains=int(np.sum(turned < held)), p_value=p_value, turned=bool(chosen))
    return info
