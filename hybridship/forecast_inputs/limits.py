"""Valid ranges of the physics inputs, and a guard that clips or refuses the rest.

The dynamic model (:class:`hybridship.physics.model.DynamicModel`) integrates with a
fixed-step RK4. Within the ranges below its results are finite for every combination of
finite inputs (``tests/test_limits.py`` and ``tests/test_hypothesis_physics.py`` search
them with hypothesis; the corners were also checked with 20 000 random corner
combinations over 120 one-second steps). Beyond them the explicit integrator can go
unstable (at ``|u| + current`` of about 15 m/s, 1-s steps, the Gunnerus rollout overflows
to inf within two minutes) or the inputs are not physical for a ship.

================================  ===========================  ==============================
input                             valid range                  outside it (``mode="clip"``)
================================  ===========================  ==============================
``eta`` north, east [m]           ``|x| <= 1e7``               refused (no meaningful clip)
``eta`` heading [rad]             ``|psi| <= 1e4`` (unwrapped)  refused
``nu`` u (surge) [m/s]            ``|u| <= 8`` (15.6 kn)        clipped, flagged
``nu`` v (sway) [m/s]             ``|v| <= 4``                  clipped, flagged
``nu`` r (yaw rate) [rad/s]       ``|r| <= 0.3`` (17 deg/s)     clipped, flagged
``rpm`` per thruster [rpm]        ``|rpm| <= max_rpm``          clipped, flagged; refused
                                                               beyond 2 x max_rpm (a unit
                                                               error, not a saturating
                                                               command)
``azimuth_rad`` [rad]             any finite                   wrapped to [-pi, pi) (same
                                                               direction, not flagged); a
                                                               rudder's angle beyond its
                                                               ``max_angle_deg``: clipped,
                                                               flagged
``wind`` speed [m/s]              ``0 <= U <= 51.44`` (100 kn)  clipped, flagged; < 0 refused
``wind`` direction [rad]          any finite                   wrapped
``current`` speed [m/s]           ``0 <= U <= 5``               clipped, flagged; < 0 refused
``current`` direction [rad]       any finite                   wrapped
RK4 step ``dt_s / substeps`` [s]  ``<= 1``                      substeps raised (not flagged)
================================  ===========================  ==============================

Non-finite values (NaN, inf) are always refused: they are faults, not extremes. With
``mode="refuse"`` every out-of-range value is refused. Refusal raises
:class:`~hybridship.forecast_inputs.faults.InputRangeError` naming the input, the batch element (and step), the component,
the value and the valid range.

The ranges were verified for the packaged ``gunnerus`` vessel; for another vessel file,
run ``tests/test_limits.py``'s envelope test with it (or pass a narrower
:class:`Envelope`). The predictors pass the inputs they hold through
:func:`check_or_clip_inputs`, and their forecast carries the ``input_clipped`` flag
(:attr:`hybridship.forecast_inputs.faults.FaultFlags.INPUT_CLIPPED`).

:func:`check_or_clip_inputs` is a short driver over one named check per kind of input:
:func:`refuse_non_finite`, :func:`refuse_far_states`, :func:`clip_velocities`, the command
checks of :mod:`hybridship.forecast_inputs.commands` (``clip_rpm``,
``wrap_and_clip_angles``), :func:`clip_flow` (wind, current) and :func:`rk4_substeps`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..config import check_number, check_whole_number, real_array
from ..frames import wrap_pi
from .commands import clip_rpm, wrap_and_clip_angles
from .faults import COMPONENTS, InputRangeError, batch_mask, column_mask, refuse

__all__ = [
    "Envelope",
    "envelope_for",
    "CheckedInputs",
    "check_or_clip_inputs",
    "refuse_non_finite",
    "refuse_far_states",
    "clip_velocities",
    "clip_flow",
    "rk4_substeps",
    "forecast_substeps",
    "KNOT_M_S",
]

#: One knot [m/s].
KNOT_M_S = 1852.0 / 3600.0


@dataclass(frozen=True)
class Envelope:
    """Valid ranges of the physics inputs (see the module table).

    Attributes
    ----------
    position_max_m : float
        Largest ``|north|``, ``|east|`` [m].
    heading_max_rad : float
        Largest ``|psi|`` (unwrapped) [rad].
    surge_max_m_s, sway_max_m_s : float
        Largest ``|u|``, ``|v|`` [m/s].
    yaw_rate_max_rad_s : float
        Largest ``|r|`` [rad/s].
    wind_speed_max_m_s : float
        Largest true wind speed [m/s] (100 kn).
    current_speed_max_m_s : float
        Largest current speed [m/s].
    max_rpm : tuple of float
        Per command channel (thrusters, then rudders), largest ``|rpm|`` (the vessel
        file's ``max_rpm``; ``inf`` for a rudder, which has no rpm).
    channel_names : tuple of str
        Per command channel, its name (quoted in messages).
    max_angle_rad : tuple of float
        Per command channel, largest ``|angle|`` [rad]: ``inf`` for thrusters
        (any direction), a rudder's ``max_angle_deg`` (mechanical limit).
    rpm_refuse_factor : float
        ``|rpm|`` beyond this multiple of ``max_rpm`` is refused even when
        clipping (a unit error); at least 1.
    rk4_step_max_s : float
        Largest RK4 step ``dt_s / substeps`` [s].

    Raises
    ------
    TypeError, ValueError
        Naming a bound (also one channel's ``max_rpm`` or ``max_angle_rad``) that is not a
        number, or not finite and > 0 (``inf`` is no bound; the refuse factor at least 1).
    """

    position_max_m: float = 1e7
    heading_max_rad: float = 1e4
    surge_max_m_s: float = 8.0
    sway_max_m_s: float = 4.0
    yaw_rate_max_rad_s: float = 0.3
    wind_speed_max_m_s: float = 100.0 * KNOT_M_S
    current_speed_max_m_s: float = 5.0
    max_rpm: tuple[float, ...] = field(default_factory=tuple)
    channel_names: tuple[str, ...] = field(default_factory=tuple)
    max_angle_rad: tuple[float, ...] = field(default_factory=tuple)
    rpm_refuse_factor: float = 2.0
    rk4_step_max_s: float = 1.0

    def __post_init__(self):
        # a bound of 0 or below clips every value to the wrong sign, NaN clips nothing, a step of 0 divides
        for name in ("position_max_m", "heading_max_rad", "surge_max_m_s", "sway_max_m_s", "yaw_rate_max_rad_s",
                     "wind_speed_max_m_s", "current_speed_max_m_s", "rk4_step_max_s", "rpm_refuse_factor"):
            v = getattr(self, name)
            if not (isinstance(v, float) and v == math.inf):        # inf: no bound
                check_number(name, v, **(dict(lo=1.0) if name == "rpm_refuse_factor" else dict(lo=0.0, lo_open=True)))
        # per channel too: a NaN max_rpm clipped and refused nothing, a negative one refused every command
        for name in ("max_rpm", "max_angle_rad"):
            for i, v in enumerate(np.atleast_1d(np.asarray(getattr(self, name), dtype=object)).tolist()):
                if not (isinstance(v, float) and v == math.inf):    # inf: a rudder's rpm, a thruster's angle
                    check_number(f"{name}[{i}]", v, lo=0.0, lo_open=True)


def envelope_for(vessel, **overrides) -> Envelope:
    """The default :class:`Envelope` with the vessel's thruster ``max_rpm``.

    Parameters
    ----------
    vessel : Vessel, DynamicModel or str
        A validated vessel, a model (its ``.vessel``), or a packaged name / file path.
    **overrides
        Fields of :class:`Envelope` to change.
    """
    from ..vessel import Vessel, load_vessel

    v = getattr(vessel, "vessel", vessel)
    if not isinstance(v, Vessel):
        v = load_vessel(v)
    rudders = list(getattr(v, "rudders", None) or [])
    # the vessel's channels, then the overrides (which may change them too: passed twice, they were a TypeError)
    channels = dict(max_rpm=tuple(float(t.max_rpm) for t in v.thrusters) + (math.inf,) * len(rudders),
                    channel_names=tuple(t.name for t in v.thrusters) + tuple(r.name for r in rudders),
                    max_angle_rad=(math.inf,) * len(v.thrusters)
                    + tuple(math.radians(r.max_angle_deg) for r in rudders))
    return Envelope(**{**channels, **overrides})


@dataclass(frozen=True, eq=False)
class CheckedInputs:
    """Inputs after :func:`check_or_clip_inputs` (new arrays; None where not given).

    Attributes
    ----------
    eta, nu, rpm, azimuth_rad, wind, current : ndarray or None
        The inputs with the caller's shapes, clipped/wrapped where needed.
    substeps : int
        RK4 substeps per output step, raised so that ``dt_s / substeps <= rk4_step_max_s``.
    clipped : ndarray of bool, shape (B,)
        Per batch element, whether any input was clipped (the ``input_clipped`` flag).
    clipped_fields : dict of str to ndarray of bool, shape (B,)
        The same per input name.
    notes : tuple of str
        Per batch element, what was clipped ("" when nothing).
    """

    eta: np.ndarray | None
    nu: np.ndarray | None
    rpm: np.ndarray | None
    azimuth_rad: np.ndarray | None
    wind: np.ndarray | None
    current: np.ndarray | None
    substeps: int
    clipped: np.ndarray
    clipped_fields: dict
    notes: tuple


def check_or_clip_inputs(
    vessel=None,
    *,
    eta=None,
    nu=None,
    rpm=None,
    azimuth_rad=None,
    wind=None,
    current=None,
    dt_s: float | None = None,
    substeps: int = 1,
    mode: str = "clip",
    envelope: Envelope | None = None,
) -> CheckedInputs:
    """Check physics inputs against their valid ranges; clip (and flag) or refuse.

    Inputs have the shapes :class:`~hybridship.physics.model.DynamicModel` accepts:
    ``(width,)``, ``(B, width)`` or ``(B, S, width)``, one batch size ``B`` (or 1) for all.
    None means "not given" (not checked, returned as None). The caller's arrays are never
    modified.

    Parameters
    ----------
    vessel : Vessel, DynamicModel or str, optional
        Gives the thrusters' ``max_rpm`` (needed when ``rpm`` is given and ``envelope`` is
        not).
    eta, nu : array_like, optional
        States ``[north_m, east_m, psi_rad]`` and ``[u_m_s, v_m_s, r_rad_s]``.
    rpm, azimuth_rad : array_like, optional
        Thruster commands [rpm], [rad], width K.
    wind, current : array_like, optional
        ``[speed_m_s, dir_rad]`` (wind: direction it comes from; current: goes to).
    dt_s : float, optional
        Output step [s]; with ``substeps`` checks the RK4 step.
    substeps : int, default 1
    mode : {"clip", "refuse"}
        What to do with finite out-of-range values (see the module table).
    envelope : Envelope, optional
        Default: :func:`envelope_for` the vessel.

    Returns
    -------
    CheckedInputs

    Raises
    ------
    InputRangeError
        For non-finite values, for values that are refused in every mode (positions,
        headings, negative speeds, rpm beyond ``rpm_refuse_factor * max_rpm``), and for
        every out-of-range value with ``mode="refuse"``.
    TypeError
        Naming an input that is not an array of real numbers (text, complex numbers).
    """
    if mode not in ("clip", "refuse"):
        raise ValueError(f"mode must be 'clip' or 'refuse', got {mode!r}")
    env = envelope if envelope is not None else _default_envelope(vessel, rpm_given=rpm is not None)
    clip = mode == "clip"
    # copies, clipped in place; text and complex numbers refused by name (np.array read "1.5" as 1.5)
    given = {k: (None if v is None else np.array(real_array(k, v), dtype=float))
             for k, v in dict(eta=eta, nu=nu, rpm=rpm, azimuth_rad=azimuth_rad, wind=wind, current=current).items()}
    B = max([a.shape[0] for a in given.values() if a is not None and a.ndim >= 2] or [1])
    for name, a in given.items():
        if a is not None and a.ndim >= 2 and a.shape[0] not in (1, B):
            longest = next(k for k, b in given.items() if b is not None and b.ndim >= 2 and b.shape[0] == B)
            raise ValueError(f"{name}: batch size {a.shape[0]} does not match {longest}'s {B} (expected one "
                             f"batch size B, or 1, for every batched input)")

    refuse_non_finite(given)
    fields: dict[str, np.ndarray] = {}
    if given["eta"] is not None:
        refuse_far_states(given["eta"], env)
    if given["nu"] is not None:
        fields["nu"] = clip_velocities(given["nu"], env, clip, B)
    if given["rpm"] is not None:
        fields["rpm"] = clip_rpm(given["rpm"], env, clip, B)
    if given["azimuth_rad"] is not None:
        given["azimuth_rad"], clipped_angles = wrap_and_clip_angles(given["azimuth_rad"], env, clip, B)
        if clipped_angles is not None:
            fields["azimuth_rad"] = clipped_angles
    for name, hi in (("wind", env.wind_speed_max_m_s), ("current", env.current_speed_max_m_s)):
        if given[name] is not None:
            fields[name] = clip_flow(name, given[name], hi, clip, B)
    steps = rk4_substeps(dt_s, substeps, env, clip)

    clipped = np.zeros(B, dtype=bool)
    notes = [[] for _ in range(B)]
    for name, m in fields.items():
        clipped |= m
        for b in np.flatnonzero(m):
            notes[b].append(f"{name} clipped to its valid range")
    return CheckedInputs(**given, substeps=steps, clipped=clipped, clipped_fields=fields,
                         notes=tuple("; ".join(n) for n in notes))


def _default_envelope(vessel, *, rpm_given: bool) -> Envelope:
    """The vessel's envelope; without a vessel the default one (which has no thrusters)."""
    if vessel is not None:
        return envelope_for(vessel)
    if rpm_given:
        raise ValueError("check_or_clip_inputs: rpm needs the vessel (for max_rpm) or an envelope")
    return Envelope()


# --------------------------------------------------------------------------------------
# Number checks (the commands' are in hybridship.forecast_inputs.commands)
# --------------------------------------------------------------------------------------


def refuse_non_finite(given: dict) -> None:
    """NaN or inf in any input.

    Fault: a missing or overflowed value (a fault, not an extreme: there is nothing to
    clip it to). Evidence: ``~isfinite``, checked for every input (and its shape, and the
    width of ``eta``, ``nu``, ``wind`` and ``current``) before any range. Refused in every
    mode.
    """
    for name, a in given.items():
        if a is None:
            continue
        if a.ndim not in (1, 2, 3):
            raise ValueError(f"{name}: expected shape (width,), (B, width) or (B, S, width), got {a.shape}")
        if name in COMPONENTS and a.shape[-1] != len(COMPONENTS[name]):
            raise ValueError(f"{name}: expected width {len(COMPONENTS[name])} ({', '.join(COMPONENTS[name])}), "
                             f"got shape {a.shape}")
        nonfinite = ~np.isfinite(a)
        if nonfinite.any():
            refuse(name, a, nonfinite, "finite values", COMPONENTS.get(name), "not finite (a fault, not an extreme)")


def refuse_far_states(eta: np.ndarray, env: Envelope) -> None:
    """Positions or headings far outside any voyage.

    Fault: a position beyond ``position_max_m`` (latitude/longitude in degrees times a
    wrong factor, a datum error) or an unwrapped heading beyond ``heading_max_rad``.
    Evidence: the magnitudes. Refused in every mode: there is no meaningful clip.
    """
    comps = COMPONENTS["eta"]
    bad = np.zeros(eta.shape, dtype=bool)
    bad[..., :2] = np.abs(eta[..., :2]) > env.position_max_m
    if bad.any():
        refuse("eta", eta, bad, f"|north_m|, |east_m| <= {env.position_max_m:g} m", comps)
    bad = column_mask(eta, 2, np.abs(eta[..., 2]) > env.heading_max_rad)
    if bad.any():
        refuse("eta", eta, bad, f"|psi_rad| <= {env.heading_max_rad:g}", comps)


def _clip_column(name, a, col, lo, hi, valid, comps, clip: bool, batch: int) -> np.ndarray:
    """Clip ``a[..., col]`` to [lo, hi] in place, or refuse; (batch,) mask of what was clipped."""
    x = a[..., col]
    bad = (x > hi) | (x < lo)
    if not bad.any():
        return np.zeros(batch, dtype=bool)
    if not clip:
        refuse(name, a, column_mask(a, col, bad), valid, comps)
    a[..., col] = np.clip(x, lo, hi)
    return batch_mask(a, bad, batch)


def clip_velocities(nu: np.ndarray, env: Envelope, clip: bool, batch: int) -> np.ndarray:
    """Body velocities beyond the range where the integrator stays stable.

    Fault: ``|u|``, ``|v|`` or ``|r|`` beyond ``surge_max_m_s``, ``sway_max_m_s``,
    ``yaw_rate_max_rad_s`` (RK4 overflows near 15 m/s with 1-s steps). Evidence: the
    magnitudes. Repair: clipped in place and flagged (``mode="clip"``) or refused.
    Returns the (B,) mask of clipped batch elements.
    """
    comps = COMPONENTS["nu"]
    m = np.zeros(batch, dtype=bool)
    for col, hi, unit in ((0, env.surge_max_m_s, "m/s"), (1, env.sway_max_m_s, "m/s"),
                          (2, env.yaw_rate_max_rad_s, "rad/s")):
        m |= _clip_column("nu", nu, col, -hi, hi, f"|{comps[col]}| <= {hi:g} {unit}", comps, clip, batch)
    return m


def clip_flow(name: str, a: np.ndarray, hi: float, clip: bool, batch: int) -> np.ndarray:
    """Wind or current ``[speed_m_s, dir_rad]`` out of range.

    Fault: a negative speed (refused in every mode: a speed is >= 0, the sign is a
    convention error) or a speed beyond ``hi`` (clipped in place and flagged, or refused).
    The direction is wrapped to [-pi, pi) (same direction, not flagged). Returns the (B,)
    mask of clipped batch elements.
    """
    comps = COMPONENTS[name]
    neg = column_mask(a, 0, a[..., 0] < 0.0)
    if neg.any():
        refuse(name, a, neg, f"0 <= speed_m_s <= {hi:g}", comps, "negative (a speed is >= 0)")
    m = _clip_column(name, a, 0, 0.0, hi, f"0 <= speed_m_s <= {hi:g}", comps, clip, batch)
    a[..., 1] = wrap_pi(a[..., 1])
    return m


def rk4_substeps(dt_s: float | None, substeps: int, env: Envelope, clip: bool) -> int:
    """RK4 substeps per output step, raised until ``dt_s / substeps <= rk4_step_max_s``.

    Fault: an integration step too long for the explicit integrator. Evidence: ``dt_s /
    substeps``. Repair: more substeps (not flagged: the forecast is the same, only finer),
    or refused with ``mode="refuse"``; a non-positive or non-finite ``dt_s`` is refused, and so
    are ``substeps`` that are not a whole number >= 1 and a ``dt_s`` that is not a number.
    """
    steps = check_whole_number("substeps", substeps, lo=1)
    if dt_s is None:
        return steps
    if isinstance(dt_s, (bool, np.bool_, str, bytes)):
        raise TypeError(f"dt_s: expected a number of seconds, got {dt_s!r}")
    try:
        dt_s = float(dt_s)          # a list or complex number failed in math.isfinite's words, not naming dt_s
    except (TypeError, ValueError):
        raise TypeError(f"dt_s: expected a number of seconds, got {dt_s!r}") from None
    if not (math.isfinite(dt_s) and dt_s > 0):
        raise InputRangeError(f"dt_s: {dt_s!r} is not a positive finite step; valid: 0 < dt_s",
                              field="dt_s", index=(), value=float(dt_s), valid="0 < dt_s")
    h = dt_s / steps
    if h > env.rk4_step_max_s * (1 + 1e-12):
        if not clip:
            raise InputRangeError(
                f"dt_s / substeps: RK4 step {h:g} s exceeds {env.rk4_step_max_s:g} s; use substeps >= "
                f"{math.ceil(dt_s / env.rk4_step_max_s)}", field="dt_s", index=(), value=h,
                valid=f"dt_s / substeps <= {env.rk4_step_max_s:g} s")
        steps = math.ceil(dt_s / env.rk4_step_max_s - 1e-12)
    return steps


def forecast_substeps(dt_s: float) -> int:
    """RK4 substeps of one forecast step of ``dt_s`` [s]: those :func:`rk4_substeps` gives with
    the default envelope (steps of at most ``rk4_step_max_s``, 1 s), as every forecast takes
    them. The training's one-step and multi-step predictions take as many, so that the nets
    learn the residual of the integration the forecast makes (a 2-s log was trained on one
    2-s RK4 step and forecast in two 1-s steps)."""
    return rk4_substeps(dt_s, 1, Envelope(), clip=True)
