"""Command checks: the propeller speeds and angles a forecast holds, clipped or refused.

Each function takes one command array (shape ``(K,)``, ``(B, K)`` or ``(B, S, K)``, K
command channels: thrusters, then rudders), a copy the caller may change, and the
:class:`~hybridship.forecast_inputs.limits.Envelope` of the vessel;
:func:`~hybridship.forecast_inputs.limits.check_or_clip_inputs` composes them.
"""

from __future__ import annotations

import numpy as np

from ..frames import wrap_pi
from .faults import batch_mask, refuse

__all__ = ["clip_rpm", "wrap_and_clip_angles"]


def clip_rpm(rpm: np.ndarray, env, clip: bool, batch: int) -> np.ndarray:
    """Propeller speeds beyond the thrusters' ``max_rpm``.

    Fault: a command beyond what the propeller can turn. Evidence: ``|rpm| > max_rpm``
    per channel (``inf`` for a rudder, which has no rpm). Beyond ``rpm_refuse_factor x
    max_rpm`` it is a unit error (motor rpm, rev/s), refused in every mode; below that it is
    clipped to ``+-max_rpm`` in place and flagged (``mode="clip"``) or refused.

    Parameters
    ----------
    rpm : ndarray, shape (..., K)
        Commands [rpm]; clipped in place.
    env : Envelope
    clip : bool
        Clip (True) or refuse (False) values between ``max_rpm`` and the refuse factor.
    batch : int
        Batch size B of the call.

    Returns
    -------
    ndarray of bool, shape (B,)
        Where something was clipped.
    """
    max_rpm = np.asarray(env.max_rpm, dtype=float)
    if rpm.shape[-1] != max_rpm.size:
        raise ValueError(f"rpm: width {rpm.shape[-1]} does not match the vessel's {max_rpm.size} thrusters")
    comps = [f"thruster {n!r}" for n in env.channel_names] if len(env.channel_names) == max_rpm.size \
        else [f"thruster {i}" for i in range(max_rpm.size)]
    far = np.abs(rpm) > env.rpm_refuse_factor * max_rpm
    if far.any():
        refuse("rpm", rpm, far, f"|rpm| <= max_rpm {max_rpm.tolist()} (clipped up to "
               f"{env.rpm_refuse_factor:g} x max_rpm)", comps,
               f"more than {env.rpm_refuse_factor:g} x max_rpm (a unit error?)")
    bad = np.abs(rpm) > max_rpm
    if bad.any():
        if not clip:
            refuse("rpm", rpm, bad, f"|rpm| <= max_rpm {max_rpm.tolist()}", comps)
        rpm[...] = np.clip(rpm, -max_rpm, max_rpm)
    return batch_mask(rpm, bad, batch)


def wrap_and_clip_angles(azimuth_rad: np.ndarray, env, clip: bool, batch: int):
    """Thruster directions and rudder angles: wrapped, and rudders held to their stops.

    Fault: a rudder angle beyond its mechanical limit. Evidence: ``|angle| >
    max_angle_rad`` of the channel after wrapping to [-pi, pi) (a thruster's limit is
    ``inf``: any direction; wrapping keeps the direction and is not flagged). Repair:
    clipped to the stop and flagged (``mode="clip"``) or refused.

    Parameters
    ----------
    azimuth_rad : ndarray, shape (..., K)
        Angles [rad].
    env : Envelope
    clip : bool
    batch : int

    Returns
    -------
    angles : ndarray, shape (..., K)
        A new, wrapped (and clipped) array.
    clipped : ndarray of bool, shape (B,), or None
        Where something was clipped; None when the envelope has no angle limits.
    """
    a = wrap_pi(azimuth_rad)
    if not env.max_angle_rad:
        return a, None
    lim = np.asarray(env.max_angle_rad, dtype=float)
    if a.shape[-1] != lim.size:
        raise ValueError(f"azimuth_rad: width {a.shape[-1]} does not match the vessel's {lim.size} "
                         "command channels")
    bad = np.abs(a) > lim
    if bad.any():
        if not clip:
            comps = [f"rudder {n!r}" for n in env.channel_names] or None
            refuse("azimuth_rad", a, bad, f"|rudder angle| <= {np.degrees(lim[np.isfinite(lim)]).tolist()} "
                   "deg (the rudders' max_angle_deg)", comps)
        a[...] = np.clip(a, -lim, lim)
    return a, batch_mask(a, bad, batch)
