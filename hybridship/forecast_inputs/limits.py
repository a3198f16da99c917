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
:class:`InputRangeError` naming the input, the batch element (and step), the component,
the value and the valid range.

The ranges were verified for the packaged ``gunnerus`` vessel; for another vessel file,
run ``tests/test_limits.py``'s envelope test with it (or pass a narrower
:class:`Envelope`). The lead wires :func:`check_or_clip_inputs` into the predictors, whose
forecast carries the ``input_clipped`` flag (:attr:`hybridship.forecast_inputs.FaultFlags.INPUT_CLIPPED`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "Envelope",
    "envelope_for",
    "InputRangeError",
    "CheckedInputs",
    "check_or_clip_inputs",
    "KNOT_M_S",
]

#: One knot [m/s].
KNOT_M_S = 1852.0 / 3600.0



def check_number(name: str, value, *, lo=None, hi=None, lo_open: bool = False, allow_none: bool = False):
    """``value`` as a finite float within ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``), or an
    error naming ``name`` and what was expected (TypeError for a non-number, ValueError
    otherwise). ``allow_none`` passes None through."""
    if value is None and allow_none:
        return None
    if isinstance(value, bool):
        raise TypeError(f"{name}: expected a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {value!r}")
    if lo is not None and (v <= lo if lo_open else v < lo):
        raise ValueError(f"{name}: must be {'>' if lo_open else '>='} {lo:g}, got {value!r}")
    if hi is not None and v > hi:
        raise ValueError(f"{name}: must be <= {hi:g}, got {value!r}")
    return v

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
    thruster_names : tuple of str
        Per command channel, its name (quoted in messages).
    max_angle_rad : tuple of float
        Per command channel, largest ``|angle|`` [rad]: ``inf`` for thrusters
        (any direction), a rudder's ``max_angle_deg`` (mechanical limit).
    rpm_refuse_factor : float
        ``|rpm|`` beyond this multiple of ``max_rpm`` is refused even when
        clipping (a unit error).
    rk4_step_max_s : float
        Largest RK4 step ``dt_s / substeps`` [s].
    """

    position_max_m: float = 1e7
    heading_max_rad: float = 1e4
    surge_max_m_s: float = 8.0
    sway_max_m_s: float = 4.0
    yaw_rate_max_rad_s: float = 0.3
    wind_speed_max_m_s: float = 100.0 * KNOT_M_S
    current_speed_max_m_s: float = 5.0
    max_rpm: tuple[float, ...] = field(default_factory=tuple)
    thruster_names: tuple[str, ...] = field(default_factory=tuple)
    max_angle_rad: tuple[float, ...] = field(default_factory=tuple)
    rpm_refuse_factor: float = 2.0
    rk4_step_max_s: float = 1.0


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
    return Envelope(max_rpm=tuple(float(t.max_rpm) for t in v.thrusters) + (math.inf,) * len(rudders),
                    thruster_names=tuple(t.name for t in v.thrusters) + tuple(r.name for r in rudders),
                    max_angle_rad=(math.inf,) * len(v.thrusters)
                    + tuple(math.radians(r.max_angle_deg) for r in rudders), **overrides)


class InputRangeError(ValueError):
    """A physics input is non-finite or outside its valid range (and was not clipped).

    Attributes
    ----------
    field : str
        The input (``"rpm"``, ``"wind"``, ...).
    index : tuple of int
        Position of the offending value in the input array.
    value : float
    valid : str
        The valid range, as text.
    """

    def __init__(self, message: str, *, field: str, index: tuple, value: float, valid: str):
        super().__init__(message)
        self.field = field
        self.index = tuple(int(i) for i in index)
        self.value = float(value)
        self.valid = valid


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


def _wrap(a):
    return np.mod(a + np.pi, 2.0 * np.pi) - np.pi


def _loc(a: np.ndarray, flat: int) -> tuple:
    return np.unravel_index(flat, a.shape)


def _where_text(name: str, a: np.ndarray, index: tuple, components) -> str:
    parts = []
    if a.ndim >= 2:
        parts.append(f"batch {index[0]}")
    if a.ndim == 3:
        parts.append(f"step {index[1]}")
    comp = components[index[-1]] if components and index[-1] < len(components) else f"component {index[-1]}"
    parts.append(comp)
    return f"{name}[{', '.join(parts)}]"


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
    ``(width,)``, ``(B, width)`` or ``(B, S, width)``. None means "not given" (not checked,
    returned as None). The caller's arrays are never modified.

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
    """
    if mode not in ("clip", "refuse"):
        raise ValueError(f"mode must be 'clip' or 'refuse', got {mode!r}")
    if envelope is None:
        if vessel is None:
            if rpm is not None:
                raise ValueError("check_or_clip_inputs: rpm needs the vessel (for max_rpm) or an envelope")
            envelope = Envelope()
        else:
            envelope = envelope_for(vessel)
    env = envelope
    clip = mode == "clip"

    given = {k: (None if v is None else np.array(v, dtype=float))
             for k, v in dict(eta=eta, nu=nu, rpm=rpm, azimuth_rad=azimuth_rad, wind=wind, current=current).items()}
    B = max([a.shape[0] for a in given.values() if a is not None and a.ndim >= 2] or [1])
    fields: dict[str, np.ndarray] = {}
    notes = [[] for _ in range(B)]

    def batch_mask(a: np.ndarray, bad: np.ndarray) -> np.ndarray:
        m = bad.reshape(bad.shape[0], -1).any(axis=1) if a.ndim >= 2 else np.array([bad.any()])
        return np.broadcast_to(m, (B,)).copy() if m.shape[0] in (1, B) else m

    def refuse(name, a, bad, valid, components, why=""):
        flat = int(np.argmax(bad))
        index = _loc(a, flat)
        value = a[index]
        raise InputRangeError(
            f"{_where_text(name, a, index, components)}: {value:g} is {why or 'outside the valid range'}; "
            f"valid: {valid} (hybridship.forecast_inputs.limits)",
            field=name, index=index, value=value, valid=valid)

    def limit(name, a, col, hi, valid, components, lo=None):
        """Clip ``a[..., col]`` to [-hi, hi] (or [lo, hi]); returns the batch mask."""
        x = a[..., col]
        lower = -hi if lo is None else lo
        bad = (x > hi) | (x < lower)
        if not bad.any():
            return np.zeros(B, dtype=bool)
        if not clip:
            refuse(name, a, np.zeros(a.shape, bool) | _expand(bad, a, col), valid, components)
        a[..., col] = np.clip(x, lower, hi)
        return batch_mask(a, bad)

    def _expand(bad_col, a, col):
        full = np.zeros(a.shape, dtype=bool)
        full[..., col] = bad_col
        return full

    for name, a in given.items():
        if a is None:
            continue
        if a.ndim not in (1, 2, 3):
            raise ValueError(f"{name}: expected shape (width,), (B, width) or (B, S, width), got {a.shape}")
        nonfinite = ~np.isfinite(a)
        if nonfinite.any():
            refuse(name, a, nonfinite, "finite values", _COMPONENTS.get(name), "not finite (a fault, not an extreme)")

    a = given["eta"]
    if a is not None:
        comps = _COMPONENTS["eta"]
        bad = np.zeros(a.shape, dtype=bool)
        bad[..., :2] = np.abs(a[..., :2]) > env.position_max_m
        if bad.any():
            refuse("eta", a, bad, f"|north_m|, |east_m| <= {env.position_max_m:g} m", comps)
        bad = _expand(np.abs(a[..., 2]) > env.heading_max_rad, a, 2)
        if bad.any():
            refuse("eta", a, bad, f"|psi_rad| <= {env.heading_max_rad:g}", comps)

    a = given["nu"]
    if a is not None:
        comps = _COMPONENTS["nu"]
        m = np.zeros(B, dtype=bool)
        for col, hi, unit in ((0, env.surge_max_m_s, "m/s"), (1, env.sway_max_m_s, "m/s"),
                              (2, env.yaw_rate_max_rad_s, "rad/s")):
            m |= limit("nu", a, col, hi, f"|{comps[col]}| <= {hi:g} {unit}", comps)
        fields["nu"] = m

    a = given["rpm"]
    if a is not None:
        max_rpm = np.asarray(env.max_rpm, dtype=float)
        if a.shape[-1] != max_rpm.size:
            raise ValueError(f"rpm: width {a.shape[-1]} does not match the vessel's {max_rpm.size} thrusters")
        comps = [f"thruster {n!r}" for n in env.thruster_names] if len(env.thruster_names) == max_rpm.size \
            else [f"thruster {i}" for i in range(max_rpm.size)]
        far = np.abs(a) > env.rpm_refuse_factor * max_rpm
        if far.any():
            refuse("rpm", a, far, f"|rpm| <= max_rpm {max_rpm.tolist()} (clipped up to "
                   f"{env.rpm_refuse_factor:g} x max_rpm)", comps,
                   f"more than {env.rpm_refuse_factor:g} x max_rpm (a unit error?)")
        bad = np.abs(a) > max_rpm
        if bad.any():
            if not clip:
                refuse("rpm", a, bad, f"|rpm| <= max_rpm {max_rpm.tolist()}", comps)
            a[...] = np.clip(a, -max_rpm, max_rpm)
        fields["rpm"] = batch_mask(a, bad)

    a = given["azimuth_rad"]
    if a is not None:
        a = _wrap(a)
        given["azimuth_rad"] = a
        if env.max_angle_rad:
            lim = np.asarray(env.max_angle_rad, dtype=float)
            if a.shape[-1] != lim.size:
                raise ValueError(f"azimuth_rad: width {a.shape[-1]} does not match the vessel's {lim.size} "
                                 "command channels")
            bad = np.abs(a) > lim
            if bad.any():
                if not clip:
                    comps = [f"rudder {n!r}" for n in env.thruster_names] or None
                    refuse("azimuth_rad", a, bad, f"|rudder angle| <= {np.degrees(lim[np.isfinite(lim)]).tolist()} "
                           "deg (the rudders' max_angle_deg)", comps)
                a[...] = np.clip(a, -lim, lim)
            fields["azimuth_rad"] = batch_mask(a, bad)

    for name, hi in (("wind", env.wind_speed_max_m_s), ("current", env.current_speed_max_m_s)):
        a = given[name]
        if a is None:
            continue
        comps = _COMPONENTS[name]
        neg = _expand(a[..., 0] < 0.0, a, 0)
        if neg.any():
            refuse(name, a, neg, f"0 <= speed_m_s <= {hi:g}", comps, "negative (a speed is >= 0)")
        fields[name] = limit(name, a, 0, hi, f"0 <= speed_m_s <= {hi:g}", comps, lo=0.0)
        a[..., 1] = _wrap(a[..., 1])

    steps = int(substeps)
    if steps < 1:
        raise ValueError(f"substeps must be >= 1, got {substeps}")
    if dt_s is not None:
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

    clipped = np.zeros(B, dtype=bool)
    for name, m in fields.items():
        clipped |= m
        for b in np.flatnonzero(m):
            notes[b].append(f"{name} clipped to its valid range")
    return CheckedInputs(eta=given["eta"], nu=given["nu"], rpm=given["rpm"], azimuth_rad=given["azimuth_rad"],
                         wind=given["wind"], current=given["current"], substeps=steps, clipped=clipped,
                         clipped_fields=fields, notes=tuple("; ".join(n) for n in notes))


_COMPONENTS = {
    "eta": ("north_m", "east_m", "psi_rad"),
    "nu": ("u_m_s", "v_m_s", "r_rad_s"),
    "wind": ("speed_m_s", "dir_from_rad"),
    "current": ("speed_m_s", "dir_to_rad"),
}
