"""Live mode: "a blackout now", from the station-keeping log up to now.

:func:`environment_from_log` is the one place that turns a log into the environment a
blackout would meet (:class:`EnvironmentEstimate`). By default (``method="estimator"``) it
runs the environment estimator (:mod:`hybridship.residual.environment`) over the last
``window_s`` of the log: the filtered state now, the current (acting through the relative
velocity) and the load, with members drawn from the estimator's posterior, the estimate
treated as the filter treats a logged thrust stop under the estimator's settings
(:meth:`~hybridship.residual.environment.EnvironmentEstimator.at_thrust_stop`: by default
it carries on; with the per-DOF settings the yaw environment restarts).
``method="mean"`` uses the residual scheme's causal bias instead
(:mod:`hybridship.residual.features`): the mean, over the last 900 s, of the acceleration
the physics model does not explain while the DP holds position (current, mean wave drift
and model error), held in NED, with its spread from
:meth:`~hybridship.residual.features.PreparedLog.bias_members`.

:func:`blackout_now` then runs the Monte-Carlo blackouts from the logged heading,
velocity, thruster rpm (spinning down) and azimuths, with the measured mean wind and its
gustiness, the estimated extra acceleration per sample (one bias member each) and
perturbed vessels. Only the last ``window_s`` (and ``wind_window_s``) of the log are read,
so an update costs the same at any log length (``benchmarks/driftoff_live.py`` measures it).
"""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..config import as_config, check_number, check_whole_number
from ..forecast_inputs.limits import check_or_clip_inputs
from ..frames import body_to_ned, vector_to_speed_dir, wrap_2pi
from ..logs.io import LogArrays
from ..residual.features import ResidualConfig, prepare_log
from . import engine, spread
from .planning import (MAX_SAMPLES, DriftOffResult, DriftOffSettings, _reals, get_model, hull_array, refuse_diverged,
                       state_rng)
from .weather import MAX_WIND_M_S
from ..messages import seconds_text, warn_user

__all__ = ["EnvironmentEstimate", "environment_from_log", "blackout_now", "MIN_WINDOW_S", "MIN_WIND_WINDOW_S"]

#: Shortest log window of the environment estimator [s]: what it reads of the station
#: keeping (a few seconds would take the last waves' motion for the current and load).
MIN_WINDOW_S = 60.0
#: Shortest window of the mean wind and its gustiness [s].
MIN_WIND_WINDOW_S = 10.0


@dataclass(frozen=True)
class EnvironmentEstimate:
    """What the log says about the environment now (SI units, radians).

    Attributes
    ----------
    time_s : float
        Time of the last row used [s].
    eta : ndarray (3,)
        ``[north_m, east_m, psi_rad]`` now.
    nu : ndarray (3,)
        ``[u_m_s, v_m_s, r_rad_s]`` now: the environment estimator's filtered velocity, or
        (``method="mean"``) the mean of the last 3 s.
    rpm, azimuth_rad : ndarray (K,) or (K + R,)
        Commands now per command channel: the K thrusters' rpm and azimuths [rad] (and,
        when the estimate comes from LogArrays of a vessel with rudders, the R rudders'
        angles packed after them in ``azimuth_rad``). The spin-down starts from the
        thrusters' commands; the rudders are left at 0.
    wind_speed_m_s, wind_dir_from_rad : float
        Mean measured wind over ``wind_window_s``.
    gust_intensity : float
        Standard deviation over mean of the measured wind speed, clipped to [0, 0.5].
    accel_ned : ndarray (3,)
        Estimated unexplained acceleration ``[a_north_m_s2, a_east_m_s2, r_dot_rad_s2]``.
    accel_members : ndarray (M, 3)
        Its members (the uncertainty); their mean is ``accel_ned``.
    current_members_ned_m_s : ndarray (M_c, 2) or None
        Current velocity members ``[north_m_s, east_m_s]`` when an estimator separates the
        current from the other loads (it then acts through the relative velocity); None
        (the residual mean) = the current is inside ``accel_ned``.
    wind_measured : bool
        False when the log had no valid wind sample in ``wind_window_s`` (the wind is then 0).
    vessel_name : str or None
        The vessel the log was read for; :func:`blackout_now` refuses another vessel
        (None: not known, not checked).
    notes : str
        What the forecast's start-window checks found at the last row (a sensor fault
        worked around, e.g. a position dropout bridged), "" when nothing; also warned.
    """

    time_s: float
    eta: np.ndarray
    nu: np.ndarray
    rpm: np.ndarray
    azimuth_rad: np.ndarray
    wind_speed_m_s: float
    wind_dir_from_rad: float
    gust_intensity: float
    accel_ned: np.ndarray
    accel_members: np.ndarray
    current_members_ned_m_s: np.ndarray | None = None
    wind_measured: bool = True
    vessel_name: str | None = None
    notes: str = ""


def _arrays(log, model, window_s: float, name: str = "log") -> LogArrays:
    """The last ``window_s`` of ``log`` through the project's one ingest (``purpose="forecast"``):
    the same checks as a forecast's, so a log without a thruster's rpm or azimuth column is
    refused naming the column instead of taken as stopped, and so is a command column with
    no value in the window (an empty column is a missing one)."""
    from ..logs.ingest import ingest

    if isinstance(log, LogArrays):
        t_end = float(np.nanmax(log.time_s)) if log.time_s.size else 0.0
    elif isinstance(log, pd.DataFrame):
        if "time_s" not in log.columns:
            raise ValueError("log: missing column 'time_s'")
        if len(log) < 3:
            raise ValueError(f"log: need at least 3 rows, got {len(log)}")
        t = pd.to_numeric(log["time_s"], errors="coerce").to_numpy(float)
        if not np.isfinite(t).any():
            raise ValueError("log: column 'time_s' has no finite time")
        t_end = float(np.nanmax(t))
        _refuse_empty_commands(log, t >= t_end - window_s, window_s, t_end, name, model.vessel)
    else:
        raise TypeError(f"log: expected a pandas DataFrame or LogArrays, got {type(log).__name__}")
    return ingest(log, model.vessel, purpose="forecast", name=name, time_range_s=(t_end - window_s, t_end))


def _refuse_empty_commands(df: pd.DataFrame, inside: np.ndarray, window_s: float, t_end: float, name: str,
                           vessel) -> None:
    """Refuse a command column of the vessel (a thruster's ``<name>_rpm``, a rotatable
    channel's ``<name>_azimuth_deg``, ``dp_active``) with no value in the rows read: the reader
    would hold a default (a stopped thruster, DP on). Columns the reader ignores are not checked."""
    n_thr = len(vessel.thrusters)
    columns = ([f"{c}_rpm" for c in vessel.channel_names[:n_thr]]
               + [f"{c}_azimuth_deg" for c, rot in zip(vessel.channel_names, vessel.rotatable) if rot]
               + ["dp_active"])
    for col in columns:
        if col not in df.columns:
            continue            # a missing column is the ingest's to refuse, by its own rules
        values = pd.to_numeric(df.loc[inside, col], errors="coerce").to_numpy(float)
        if not np.isfinite(values).any():
            raise ValueError(f"{name}: column {col!r} has no value in the last {window_s:g} s up to time_s "
                             f"{seconds_text(t_end)}; an empty command column is not a stopped thruster (nor an active DP): "
                             f"give a log whose commands are logged in that window")


#: How :func:`environment_from_log` estimates the environment.
METHODS = ("estimator", "mean")


def environment_from_log(log, vessel="gunnerus", *, window_s: float = 900.0, wind_window_s: float = 120.0,
                         n_members: int = 100, seed: int = 0, method: str = "estimator",
                         environment_config=None, name: str = "log") -> EnvironmentEstimate:
    """The environment a blackout at the log's last row would meet (see the module notes).

    Parameters
    ----------
    log : pandas.DataFrame or LogArrays
        Station-keeping log up to now (project log format); only its last ``window_s``
        and ``wind_window_s`` seconds are read, with a forecast's checks
        (:func:`hybridship.logs.ingest.ingest`). Never modified.
    vessel : str, Vessel or DynamicModel
    window_s : float
        Log read by the environment estimator, or the residual-mean window [s] (the bias
        window of the residual scheme); at least :data:`MIN_WINDOW_S`.
    wind_window_s : float
        Window of the mean wind and its gustiness [s], at least :data:`MIN_WIND_WINDOW_S`;
        only samples the wind sensor logged count (not values held over a gap).
    n_members : int
        Members of the environment estimate (draws of the load and current from the
        estimator's posterior, or of the residual mean). Each blackout sample of
        :func:`blackout_now` takes one member, cycling through them when there are fewer
        (warned, unless there is one: an environment taken as known):
        give at least the samples' ``n_samples`` (default 100, as :class:`DriftOffSettings`'s),
        or the spread of the times rests on fewer independent draws than it has samples. At
        most :data:`~hybridship.driftoff.planning.MAX_SAMPLES` (10^6), the most samples:
        members beyond the samples are never used, and each costs memory.
    seed : int
    method : {"estimator", "mean"}
        The environment estimator (default) or the residual mean (see the module notes).
    environment_config : hybridship.residual.environment.EnvironmentConfig or dict, optional
        Settings of the environment estimator, or a dict of its fields (default: its defaults).
    name : str
        What messages and warnings call the log (the CLI gives its file's path).
    """
    if method not in METHODS:
        raise ValueError(f"method: expected one of {METHODS}, got {method!r}")
    for arg, v, least in (("window_s", window_s, MIN_WINDOW_S), ("wind_window_s", wind_window_s, MIN_WIND_WINDOW_S)):
        if isinstance(v, bool) or not (isinstance(v, (int, float, np.integer, np.floating)) and math.isfinite(v)
                                       and v >= least):
            raise ValueError(f"{arg}: expected a number of seconds >= {least:g}, got {v!r}")
    if isinstance(n_members, bool) or not isinstance(n_members, (int, np.integer)) or not 1 <= n_members <= MAX_SAMPLES:
        raise ValueError(f"n_members: expected a whole number from 1 to {MAX_SAMPLES} (the most samples a "
                         f"blackout runs, one member each), got {n_members!r}")
    check_whole_number("seed", seed)
    if environment_config is not None:
        from ..residual.environment import EnvironmentConfig

        environment_config = as_config(environment_config, EnvironmentConfig, "environment_config")
    model = get_model(vessel)
    # one read serves both windows: the wind's, and the estimator's rows at its end
    aw = _arrays(log, model, max(window_s, wind_window_s), name)
    a = aw if window_s >= wind_window_s else aw.rows(slice(int(np.searchsorted(
        aw.time_s, aw.time_s[-1] - window_s, side="left")), None))
    idx = len(a.time_s) - 1
    # within a step of the minimum: the window's rows start at the first sample inside it
    if idx == 0 or a.time_s[idx] - a.time_s[0] < MIN_WINDOW_S - a.dt_s:
        raise ValueError(f"log: only {a.time_s[idx] - a.time_s[0]:g} s of log up to the blackout at time_s "
                         f"{seconds_text(a.time_s[idx])}; the environment estimate needs at least "
                         f"{MIN_WINDOW_S:g} s of station keeping")
    if a.dp_active[idx] == 0:
        raise ValueError(f"log: dp_active is 0 at time_s {seconds_text(a.time_s[idx])} (the last row used): a "
                         f"blackout is predicted from station keeping; give a time while the DP is active")
    # the wind has its own window, whatever the estimator's; only samples the sensor logged
    # (the reader holds the last value over a gap, which is not a measurement of now)
    sel = aw.wind_logged & (aw.time_s >= a.time_s[idx] - wind_window_s)
    wind_measured = bool(aw.has_wind and sel.any())
    notes = _start_checks(a, idx, name, wind_measured)
    if wind_measured:
        ws, wd = aw.wind[sel, 0], aw.wind[sel, 1]
        # the mean speed is the speed's mean (as the gust intensity's denominator is, and as
        # a 10-min mean wind is defined); the direction is the mean velocity's, so that
        # 350 and 10 deg average to north. The vector mean's length reads low whenever the
        # direction wavers.
        vn, ve = np.mean(ws * np.cos(wd)), np.mean(ws * np.sin(wd))
        w_speed, w_dir = float(np.mean(ws)), float(math.atan2(ve, vn))
        gi = float(np.clip(np.std(ws) / w_speed, 0.0, 0.5)) if w_speed > 0 else 0.0
        if w_speed > MAX_WIND_M_S:       # before the estimator's work, in the log's words
            raise ValueError(f"{name}: column 'wind_speed_m_s': the mean wind over the last {wind_window_s:g} s up "
                             f"to time_s {seconds_text(a.time_s[idx])} is {w_speed:.1f} m/s, beyond the "
                             f"{MAX_WIND_M_S:.1f} m/s the wind model is meant for; the log format expects m/s "
                             f"(knots?)")
    else:
        w_speed, w_dir, gi = 0.0, 0.0, 0.0
    current_members = None
    if method == "estimator":
        eta0, nu0, bias0, members, current_members = _estimated(model, a, idx, int(n_members), seed,
                                                                environment_config)
    else:
        prep = prepare_log(model, a, ResidualConfig(bias_window_s=float(window_s)))
        members = prep.bias_members(idx, int(n_members), seed=seed)
        eta0, nu0, _, bias0 = prep.start_state(idx)
    return EnvironmentEstimate(time_s=float(a.time_s[idx]), eta=eta0, nu=nu0, rpm=np.nan_to_num(a.rpm[idx]).copy(),
                               azimuth_rad=np.nan_to_num(a.azimuth_rad[idx]).copy(), wind_speed_m_s=w_speed,
                               wind_dir_from_rad=w_dir, gust_intensity=gi, accel_ned=np.asarray(bias0, float),
                               accel_members=members, current_members_ned_m_s=current_members,
                               wind_measured=wind_measured, vessel_name=model.vessel.name, notes=notes)


def _start_checks(a: LogArrays, idx: int, name: str, wind_measured: bool) -> str:
    """A forecast's start-window checks at the blackout row: refused with too little valid
    position, heading or velocity (:class:`~hybridship.forecast_inputs.StartWindowError`), a
    worked-around fault warned and returned as a note. With ``wind_measured`` (the estimate's
    own, longer wind window has samples) the start window's dropped wind is not one."""

    from ..forecast_inputs import FaultFlags, assess_start_window
    from ..forecast_inputs.faults import WIND_DROPPED_NOTES
    from ..logs.io import LogFormatWarning

    try:
        sw = assess_start_window(a, np.array([idx]))
    except ValueError as exc:
        raise ValueError(f"{name}: at the blackout row: {exc}") from None
    # with wind in the estimate's own, longer window, the start window's "no valid wind
    # sample" (3 s) does not apply: the summary says which wind was used
    ignore = (FaultFlags.WIND_DROPPED,) if wind_measured else ()
    note = "; ".join(part for part in (sw.notes[0] if sw.notes else "").split("; ")
                     if part and not (ignore and part.startswith(WIND_DROPPED_NOTES)))
    degraded = any(bool(sw.flags[k][0]) for k in FaultFlags.START_WINDOW
                   if k not in (*ignore, *FaultFlags.INFORMATIONAL))
    if note and degraded:
        warn_user(f"{name}: at the blackout row (time_s {seconds_text(a.time_s[idx])}): {note}", LogFormatWarning)
        return note
    return ""


def _estimated(model, a: LogArrays, idx: int, n_members: int, seed: int, config=None):
    """(eta, nu, load, load members, current members) from the environment estimator at row
    ``idx``, as if the thrusters stopped there."""
    from ..residual.environment import CUR, LOAD, EnvironmentEstimator
    from ..residual.environment import EnvironmentEstimate as FilterEstimate
    from ..residual.load_variability import held_load_rows, held_load_std_ned, unexplained_load_std

    est = EnvironmentEstimator(model) if config is None else EnvironmentEstimator(model, config)
    c = est.config
    step = max(1, int(round(c.filter_step_s / a.dt_s)))
    window = held_load_rows(a.dp_active, a.time_s, idx + 1, step, c.held_load_window_s, a.dt_s) \
        if c.held_load_window_s > 0 else np.zeros(0, dtype=int)
    run = est.run(a, np.concatenate([[idx], window[window != idx]]))
    at = run.take(slice(0, 1))
    x, P = est.at_thrust_stop(at.x[0], at.P[0])
    draws = FilterEstimate(at.rows, at.time_s, x[None], P[None], at.thrust_error_model).sample_environment(
        n_members, seed)[:, 0]
    off = CUR.start                                   # draws hold [current (2), load (3), thrust error]
    loads = draws[:, LOAD.start - off:LOAD.stop - off].copy()
    if window.size and n_members > 1:
        # the load held over the blackout varies as it did in the station keeping before
        # (hybridship.residual.load_variability), a centred draw per member
        sigma_b = unexplained_load_std(model, a, run.take(slice(1, None)),
                                       max(1, int(round(c.held_load_block_s / (step * a.dt_s)))), step)
        z = np.random.default_rng([seed, 7]).standard_normal((n_members, 3))
        loads += (z - z.mean(axis=0)) * held_load_std_ned(sigma_b)
    load = x[LOAD].copy()
    if est.load_map is not None:
        # a force (load_model "force"): the drift-off simulation takes a NED acceleration,
        # here that of the force at the heading of the stop (it does not follow the turn)
        load, loads = (_force_as_ned_accel(v, x[2], est.load_map) for v in (load, loads))
    return x[0:3].copy(), x[3:6].copy(), load, loads, draws[:, CUR.start - off:CUR.stop - off].copy()


def _force_as_ned_accel(load, psi_rad: float, load_map) -> np.ndarray:
    """The NED acceleration (..., 3) of the estimator's force load (..., 3) at the heading ``psi_rad``."""
    from ..residual.environment import external_accel
    return body_to_ned(external_accel(psi_rad, np.asarray(load, float), 0.0, 0.0, load_map), psi_rad)


def _estimate_array(estimate: EnvironmentEstimate, name: str) -> np.ndarray:
    """Field ``name`` of ``estimate`` as a float array; a TypeError naming the field when it
    is not numbers (text, bools and None would read as numbers, or fail in numpy's words)."""
    value = getattr(estimate, name)
    x = _reals(value)
    if x is None:
        raise TypeError(f"estimate.{name}: expected an array of numbers, got {type(value).__name__} "
                        f"{reprlib.repr(value)}")
    return x


def _check_estimate(estimate: EnvironmentEstimate, n_thrusters: int) -> None:
    """Types, shapes and finiteness of the fields :func:`blackout_now` reads (errors name the field)."""
    shapes = {"eta": (3,), "nu": (3,)}
    for name, shape in shapes.items():
        x = _estimate_array(estimate, name)
        if x.shape != shape or not np.all(np.isfinite(x)):
            raise ValueError(f"estimate.{name}: expected {shape[0]} finite values, got {x.tolist()!r}")
    for name in ("rpm", "azimuth_rad"):
        x = _estimate_array(estimate, name)
        if x.ndim != 1 or x.size < n_thrusters or not np.all(np.isfinite(x)):
            raise ValueError(f"estimate.{name}: expected one finite value per command channel (at least "
                             f"{n_thrusters}, the thrusters), got shape {x.shape}")
    m = _estimate_array(estimate, "accel_members")
    if m.ndim != 2 or m.shape[0] < 1 or m.shape[1] != 3 or not np.all(np.isfinite(m)):
        raise ValueError(f"estimate.accel_members: expected finite members of shape (M >= 1, 3), got shape "
                         f"{m.shape}" + ("" if m.ndim != 2 or np.all(np.isfinite(m)) else " with NaN or inf"))
    for name in ("wind_speed_m_s", "wind_dir_from_rad", "gust_intensity"):
        check_number(f"estimate.{name}", getattr(estimate, name))     # text, bools and None refused too
    # the ranges of the WeatherState the blackouts build from them, in the estimate's names
    for name, lo, hi, what in (("wind_speed_m_s", 0.0, MAX_WIND_M_S, "m/s"),
                               ("wind_dir_from_rad", -2.0 * math.pi - 0.1, 2.0 * math.pi + 0.1, "rad"),
                               ("gust_intensity", 0.0, 0.5, "")):
        v = float(getattr(estimate, name))
        if not lo <= v <= hi:
            raise ValueError(f"estimate.{name}: expected a number from {lo:.4g} to {hi:.4g}{' ' + what if what else ''}"
                             f", got {v!r}" + (" (degrees? convert with math.radians)" if what == "rad" else ""))


def blackout_now(estimate: EnvironmentEstimate, vessel="gunnerus", settings: DriftOffSettings | None = None,
                 *, start_at_rest: bool = False) -> DriftOffResult:
    """Monte-Carlo blackouts from the state and environment of ``estimate`` (one heading: now's).

    The spin-down starts from the logged rpm and azimuths (no holding load); each sample
    draws a perturbed vessel, gust harmonics of the measured gustiness and one member of
    the acceleration estimate (cycled). Distances are measured from the position now.

    Parameters
    ----------
    estimate : EnvironmentEstimate
        From :func:`environment_from_log`.
    vessel : str, Vessel or DynamicModel
        The vessel of the log (nominal model; samples perturb it).
    settings : DriftOffSettings or dict, optional
        Numerical settings, or a dict of their fields (as
        :func:`~hybridship.driftoff.planning.simulate_blackouts` takes them).
    start_at_rest : bool
        Start the drift at rest instead of at the estimate's velocity.
    """
    if not isinstance(estimate, EnvironmentEstimate):
        raise TypeError(f"estimate: expected an EnvironmentEstimate, got {type(estimate).__name__}")
    st = as_config(settings, DriftOffSettings, "settings") if settings is not None else DriftOffSettings()
    if not isinstance(start_at_rest, (bool, np.bool_)):    # a text "no" is truthy
        raise TypeError(f"start_at_rest: expected True or False, got {start_at_rest!r}")
    model = get_model(vessel)
    if estimate.vessel_name is not None and estimate.vessel_name != model.vessel.name:
        raise ValueError(f"estimate: made from a log of vessel {estimate.vessel_name!r}, not of "
                         f"{model.vessel.name!r}; its commands and loads belong to that vessel")
    _check_estimate(estimate, len(model.vessel.thrusters))
    # the logged commands now, as a forecast takes them: beyond twice max_rpm refused (a unit
    # error), above max_rpm clipped
    k = len(model.vessel.thrusters)
    rpm_now = np.zeros(model.n_actuators)
    rpm_now[:k] = np.asarray(estimate.rpm, dtype=float)[:k]
    rpm_now = check_or_clip_inputs(model, rpm=rpm_now[None]).rpm[0]
    ves = model.vessel
    N = st.n_samples
    rng = state_rng(st.seed, 0)
    scales = spread.draw_scales(ves, N, rng, st.vessel_spread)
    stack = spread.scaled_arrays(model.arrays, scales)
    from .weather import WeatherState, sample_environment

    w = WeatherState(estimate.wind_speed_m_s, estimate.wind_dir_from_rad, gust_intensity=estimate.gust_intensity)
    envs = sample_environment(w, None, N, rng, duration_s=st.horizon_s, dt_s=st.dt_s,
                              n_gust=st.n_gust_harmonics, n_wave=1)
    K = model.n_actuators
    rpm = np.zeros(K)
    az = np.zeros(K)
    rpm[:k] = rpm_now[:k]
    az[:k] = estimate.azimuth_rad[:k]
    members = np.asarray(estimate.accel_members, dtype=float)      # checked above as array-like
    if 1 < members.shape[0] < N:

        # the environment's spread dominates a live prediction: N samples cycling through
        # fewer members have the quantiles of that many draws, not of N (one member is an
        # environment taken as known, which every sample meets)
        warn_user(f"estimate: {members.shape[0]} environment members for {N} samples: the samples cycle "
                  f"through them, so the times' spread rests on {members.shape[0]} draws of the environment; "
                  f"give environment_from_log n_members >= n_samples", UserWarning)
    acc = members[np.arange(N) % members.shape[0]]
    cur = np.zeros((N, 2))
    if estimate.current_members_ned_m_s is not None:
        c = _estimate_array(estimate, "current_members_ned_m_s")
        if c.shape != (2,) and (c.ndim != 2 or c.shape[1] != 2):     # reshaped, (M, 3) would read as other pairs
            raise ValueError(f"estimate.current_members_ned_m_s: expected (M, 2) [north, east] m/s, got shape "
                             f"{c.shape}")
        c = c.reshape(-1, 2)
        if c.shape[0] == 0 or not np.all(np.isfinite(c)):
            raise ValueError("estimate.current_members_ned_m_s: expected finite (M, 2) [north, east] m/s")
        c = c[np.arange(N) % c.shape[0]]
        cur = vector_to_speed_dir(c)                                   # speed, dir TO
    nu0 = np.zeros(3) if start_at_rest else estimate.nu
    t_reach, exc, _ = engine.run_kernel(
        np.full(N, estimate.eta[2]), model.arrays, stack, np.broadcast_to(az, (N, K)), np.broadcast_to(rpm, (N, K)),
        st.rpm_time_constant_s, False, envs.wind_mean_m_s, envs.wind_dir_from_rad, envs.gust_f_hz,
        envs.gust_amp_m_s, envs.gust_phase_rad, cur, acc, envs.waves, hull_array(ves), st.dt_s,
        st.n_steps, np.asarray(st.radii_m), np.asarray(st.reaction_times_s), nu0=nu0)
    refuse_diverged(exc, st.reaction_times_s, "estimate: its velocity, load or current")
    psi = np.array([estimate.eta[2]])
    rel = wrap_2pi(estimate.wind_dir_from_rad - psi)        # [0, 2 pi), as in planning
    return DriftOffResult(headings_rad=psi, weather_rel_rad=rel, radii_m=np.asarray(st.radii_m),
                          reaction_times_s=np.asarray(st.reaction_times_s), t_reach_s=t_reach[None],
                          excursion_m=exc[None], horizon_s=st.n_steps * st.dt_s)
