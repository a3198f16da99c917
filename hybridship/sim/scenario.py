"""DP-loss scenarios: a vessel on dynamic positioning loses power and drifts.

Timeline of one scenario (all times from 0 s)::

    0 s ............ t_shutdown_s ............ t_shutdown_s + drift_s
    DP holds the set-point          | no thrust command: rpm decays (first order),
    (dp_active = 1)                 | azimuths frozen, the ship drifts (dp_active = 0)

The "real" ship is ``DynamicModel(vessel, true_vessel=True)`` (the vessel file's
``[true_vessel]`` perturbation), integrated with RK4 in a Python loop of ``sim_dt_s``
steps. Its inputs:

* gusting wind (:func:`hybridship.sim.environment.gust_wind`) through the ``wind`` input;
* slowly varying current (:func:`~hybridship.sim.environment.current_series`) through the
  ``current`` input (relative-velocity damping);
* second-order wave drift (:func:`~hybridship.sim.environment.wave_drift_loads`, Newman)
  through ``tau_ext``, at the low-frequency (LF) heading and position (Doppler);
* thruster rpm (first-order shaft lag) and azimuth angles from the DP system.

The DP system (:class:`~hybridship.sim.dp.DPController` and
:class:`~hybridship.sim.allocation.ThrustAllocator`) uses the NOMINAL model, as a real
DP system would, and sees only noisy measurements: GNSS position, gyro heading, speed
log and wind sensor. Positions and heading include first-order wave-frequency (WF)
motion (:func:`~hybridship.sim.environment.wave_frequency_motion`) superposed on the LF
track; a low-pass "wave filter" stands in for the DP observer, and the measured wind
is smoothed before the wind feed-forward.

The output is a DataFrame in the project log format (``shared/spec/log-format.md``),
1 row per ``dt_s``, with measured columns and noise-free ``truth_*`` columns named like
those of the independent truthsim-dev simulator (``shared/data/truthsim-dev``).

All randomness comes from one :class:`numpy.random.Generator` seeded by
``DPLossConfig.seed``: the same config gives an identical DataFrame.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Annotated, Literal
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..fileio import as_path, atomic_write, check_output_files, make_out_folder, record_outputs
import pandas as pd
from pydantic import Field, field_validator, model_validator
from scipy.signal import lfilter

from hybridship.frames import ned_to_body, wrap_pi
from hybridship.config import Float, Int, check_flags, check_number, check_whole_number, config_dataclass
from hybridship.physics.model import DynamicModel
from hybridship.sim import environment as env
from hybridship.sim.allocation import ThrustAllocator, bollard_thrust_limits, check_station_keeping
from hybridship.sim.dp import DPController

__all__ = [
    "SensorNoise",
    "DPLossConfig",
    "ScenarioConditions",
    "Scenario",
    "simulate_dp_loss",
    "drift_statistics",
    "sweep",
    "embedded_scenarios",
    "log_file_name",
    "LOG_FORMATS",
]

#: File formats :func:`sweep` writes (the extension of each log).
LOG_FORMATS = ("csv", "csv.gz", "parquet")

#: Time tolerance for grid alignment checks [s].
_EPS_S = 1e-9


# --------------------------------------------------------------------------- validation helpers




Positive = Annotated[Float, Field(gt=0)]
#: Longest station-keeping or drift phase of a scenario [s] (one day; a bound on the log's size).
MAX_PHASE_S = 86400.0
NonNeg = Annotated[Float, Field(ge=0)]


def _is_multiple(a, b):
    """Whether ``a`` is a whole multiple of ``b`` (both > 0) within float tolerance."""
    q = a / b
    return abs(q - round(q)) < 1e-6 and round(q) >= 1


# --------------------------------------------------------------------------- configuration


@config_dataclass(frozen=True, prefix="noise")
class SensorNoise:
    """Standard deviations of the sensor noise added to the measured log columns.

    Attributes
    ----------
    gnss_white_m : float
        GNSS white noise per axis (north, east) [m].
    gnss_markov_m, gnss_markov_tau_s : float
        GNSS first-order Gauss-Markov error per axis [m] and its time constant [s]
        (multipath / atmosphere: a slowly wandering offset).
    heading_white_deg : float
        Gyro compass white noise [deg].
    uv_white_m_s : float
        Surge and sway speed white noise [m/s].
    r_white_deg_s : float
        Yaw-rate white noise [deg/s].
    wind_speed_white_m_s, wind_dir_white_deg : float
        Anemometer white noise [m/s] and wind-vane white noise [deg].
    """

    gnss_white_m: NonNeg = 0.10
    gnss_markov_m: NonNeg = 0.15
    gnss_markov_tau_s: Positive = 60.0
    heading_white_deg: NonNeg = 0.05
    uv_white_m_s: NonNeg = 0.02
    r_white_deg_s: NonNeg = 0.03
    wind_speed_white_m_s: NonNeg = 0.3
    wind_dir_white_deg: NonNeg = 3.0

    @classmethod
    def none(cls) -> "SensorNoise":
        """No measurement noise at all (measured columns = truth)."""
        return cls(0.0, 0.0, 60.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    @classmethod
    def from_any(cls, value) -> "SensorNoise":
        """Accept a :class:`SensorNoise`, a mapping of its fields, or None (defaults)."""
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if isinstance(value, Mapping):
            allowed = {f.name for f in dataclasses.fields(cls)}
            unknown = sorted(set(value) - allowed)
            if unknown:
                raise ValueError(f"noise: unknown field(s) {unknown}; allowed: {sorted(allowed)}")
            return cls(**value)
        raise TypeError(f"noise: expected SensorNoise, a mapping or None, got {type(value).__name__}")


@config_dataclass(frozen=True)
class DPLossConfig:
    """Settings of one DP-loss scenario (seconds, degrees where named ``_deg``).

    Attributes
    ----------
    seed : int
        Seed of the single random generator behind everything random (conditions,
        waves, gusts, current, noise). Non-negative.
    sea_state : SeaState or None
        Environmental conditions; None draws them from ``seed`` with
        :meth:`SeaState.random` within ``beaufort``.
    beaufort : (float, float)
        Inclusive Beaufort range of the random sea state (ignored when ``sea_state`` is
        given). Default (2, 5): light to fresh breeze.
    t_shutdown_s : float
        Nominal time of the DP shutdown [s] (default 3000 s = 50 min; at most one day).
    t_shutdown_jitter_s : float or None
        The realised shutdown time is ``t_shutdown_s + U(-jitter, +jitter)`` drawn from
        the seed, rounded to a multiple of ``dt_s`` [s]. 0 gives exactly ``t_shutdown_s``;
        None (default) is 4 % of ``t_shutdown_s`` (+-120 s for 50 min, like truthsim-dev).
    drift_s : float
        Duration of the drift after the shutdown [s] (default 900 s; the 600 s drift
        statistics need at least 600 s; at most one day).
    dt_s : float
        Log sampling period [s] (1 Hz, as the log format's nominal rate).
    sim_dt_s : float
        Integration step [s] (one RK4 step; inputs such as wave drift and gusts are
        updated every step). ``dt_s`` and ``control_dt_s`` must be multiples of it.
    control_dt_s : float
        DP control and thrust-allocation period [s].
    heading_mode : {"weather", "random"}
        Heading set-point: bow to the mean wind direction +- ``heading_offset_max_deg``
        ("weather", how a DP operator heads a vessel) or uniformly random.
    heading_offset_max_deg : float
        Largest offset of a "weather" heading from the wind direction [deg].
    heading_sp_deg : float or None
        Explicit heading set-point [deg]; overrides ``heading_mode``.
    noise : SensorNoise
        Measurement noise (a mapping of its fields is accepted).
    rpm_time_constant_s : float
        First-order time constant of the shaft speed following its command [s]; after the
        shutdown the rpm decays with it to zero.
    n_wave_components : int
        Number of wave components (JONSWAP, random phases).
    wave_spreading : float or None
        cos^n directional spreading exponent; None = long-crested waves.
    wave_filter_time_constant_s : float
        Time constant of each of the two cascaded first-order low-pass stages through which the
        DP sees position, heading and velocities (suppresses WF motion and noise) [s].
    wind_filter_time_constant_s : float
        Time constant of the first-order smoothing of the measured wind vector used for
        the DP's wind feed-forward [s].
    """

    seed: Annotated[Int, Field(ge=0)] = 0
    sea_state: env.SeaState | None = None
    beaufort: tuple[Float, Float] = (2.0, 5.0)
    t_shutdown_s: Annotated[Float, Field(gt=0, le=MAX_PHASE_S)] = 3000.0
    t_shutdown_jitter_s: NonNeg | None = None
    drift_s: Annotated[Float, Field(gt=0, le=MAX_PHASE_S)] = 900.0
    dt_s: Positive = 1.0
    sim_dt_s: Annotated[Float, Field(gt=0, le=2.0)] = 0.5
    control_dt_s: Positive = 1.0
    heading_mode: Literal["weather", "random"] = "weather"
    heading_offset_max_deg: Annotated[Float, Field(ge=0, le=180.0)] = 20.0
    heading_sp_deg: Float | None = None
    noise: SensorNoise = field(default_factory=SensorNoise)
    rpm_time_constant_s: Positive = 1.5
    n_wave_components: Annotated[Int, Field(ge=1)] = 50
    wave_spreading: Positive | None = None
    wave_filter_time_constant_s: Positive = 2.0
    wind_filter_time_constant_s: Positive = 10.0

    @field_validator("noise", mode="before")
    @classmethod
    def _noise(cls, v):
        return SensorNoise() if v is None else v

    @field_validator("beaufort")
    @classmethod
    def _beaufort(cls, v):
        if not (0.0 <= v[0] <= v[1] <= 12.0):
            raise ValueError(f"must satisfy 0 <= lo <= hi <= 12, got {v!r}")
        return v

    @model_validator(mode="after")
    def _steps_and_times(self):
        # sim_dt_s <= 2 s resolves the DP loop and the thruster dynamics.
        for name in ("dt_s", "control_dt_s"):
            if not _is_multiple(getattr(self, name), self.sim_dt_s):
                raise ValueError(f"{name}: must be a whole multiple of sim_dt_s = {self.sim_dt_s:g}, "
                                 f"got {getattr(self, name)!r}")
        # frozen; remembered as the default so that replace() takes 4 % of the new t_shutdown_s
        object.__setattr__(self, "_default_jitter", self.t_shutdown_jitter_s is None)
        if self.t_shutdown_jitter_s is None:
            object.__setattr__(self, "t_shutdown_jitter_s", 0.04 * self.t_shutdown_s)
        # the earliest shutdown the jitter can draw, rounded to dt_s as _realise rounds it (t_shutdown_s 10 s
        # with dt_s 20 s was a shutdown at 0 s: no DP at all)
        earliest = round((self.t_shutdown_s - self.t_shutdown_jitter_s) / self.dt_s) * self.dt_s
        least = 10.0 * self.control_dt_s
        if self.t_shutdown_s - self.t_shutdown_jitter_s < least or earliest < least - _EPS_S:
            rounded = (f" (rounded to dt_s = {self.dt_s:g} s: {earliest:g} s)"
                       if earliest < self.t_shutdown_s - self.t_shutdown_jitter_s else "")
            jitter = " (by default 4 % of t_shutdown_s)" if self._default_jitter else ""
            raise ValueError(f"t_shutdown_s: the earliest shutdown, t_shutdown_s less its jitter t_shutdown_jitter_s"
                             f"{jitter}, must leave at least {least:g} s of DP (10 control steps), got "
                             f"{self.t_shutdown_s:g} - {self.t_shutdown_jitter_s:g}{rounded}")
        if not _is_multiple(self.drift_s, self.dt_s):
            raise ValueError(f"drift_s: must be a whole multiple of dt_s = {self.dt_s:g}, got {self.drift_s!r}")
        return self

    def replace(self, **changes) -> "DPLossConfig":
        """A copy with some fields changed (validated again); a jitter left at its default
        stays the default, 4 % of the copy's ``t_shutdown_s``."""
        if getattr(self, "_default_jitter", False):
            changes.setdefault("t_shutdown_jitter_s", None)
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class ScenarioConditions:
    """What one scenario realised from its config and seed.

    Attributes
    ----------
    sea_state : SeaState
    heading_sp_rad : float
        Heading set-point [rad] in [0, 2 pi).
    t_shutdown_s, t_end_s : float
        Realised shutdown time and end of the record [s].
    """

    sea_state: env.SeaState
    heading_sp_rad: float
    t_shutdown_s: float
    t_end_s: float

    def as_dict(self) -> dict:
        """Flat summary in the units of ``scenarios.csv`` (degrees, truthsim-like names)."""
        s = self.sea_state
        return {
            "wind_mean_mps": s.wind_speed_m_s,
            "wind_dir_from_deg": math.degrees(s.wind_dir_from_rad) % 360.0,
            "gust_intensity": s.gust_intensity,
            "hs_m": s.hs_m,
            "tp_s": s.tp_s,
            "wave_dir_from_deg": math.degrees(s.wave_dir_from_rad) % 360.0,
            "current_mps": s.current_speed_m_s,
            "current_dir_to_deg": math.degrees(s.current_dir_to_rad) % 360.0,
            "heading_sp_deg": math.degrees(self.heading_sp_rad) % 360.0,
            "t_shutdown_s": self.t_shutdown_s,
            "t_end_s": self.t_end_s,
        }


def _realise(config: DPLossConfig, rng: np.random.Generator) -> ScenarioConditions:
    """Draw the random conditions, always in the same order from ``rng``."""
    sea = config.sea_state if config.sea_state is not None else env.SeaState.random(rng, beaufort=config.beaufort)
    jitter = rng.uniform(-1.0, 1.0) * config.t_shutdown_jitter_s
    t_sd = round((config.t_shutdown_s + jitter) / config.dt_s) * config.dt_s
    offset = math.radians(config.heading_offset_max_deg) * rng.uniform(-1.0, 1.0)
    random_heading = rng.uniform(0.0, 2.0 * math.pi)
    if config.heading_sp_deg is not None:
        psi_sp = math.radians(config.heading_sp_deg)
    elif config.heading_mode == "weather":
        psi_sp = sea.wind_dir_from_rad + offset
    else:
        psi_sp = random_heading
    return ScenarioConditions(sea_state=sea, heading_sp_rad=float(psi_sp % (2.0 * math.pi)),
                              t_shutdown_s=float(t_sd), t_end_s=float(t_sd + config.drift_s))


@dataclass(frozen=True, eq=False)
class Scenario:
    """One generated scenario: a name, the config it came from and its log."""

    name: str
    config: DPLossConfig
    log: pd.DataFrame


# --------------------------------------------------------------------------- small signal blocks


def _gauss_markov(n: int, dt_s: float, sigma: float, tau_s: float, rng: np.random.Generator) -> np.ndarray:
    """Stationary first-order Gauss-Markov samples on a uniform grid (exact discretisation)."""
    z = rng.standard_normal(n)
    if sigma == 0.0 or n == 0:
        return np.zeros(n)
    a = math.exp(-dt_s / tau_s)
    x0 = sigma * z[0]
    w = sigma * math.sqrt(1.0 - a * a) * z[1:]
    return np.concatenate([[x0], lfilter([1.0], [1.0, -a], w, zi=[a * x0])[0]])


class _LowPass:
    """Cascade of ``stages`` identical first-order low-pass filters (exact for held input)."""

    def __init__(self, time_constant_s: float, dt_s: float, stages: int = 2):
        self.a = 1.0 - math.exp(-dt_s / time_constant_s)
        self.stages = stages
        self.y = None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, float)
        if self.y is None:
            self.y = [x.copy() for _ in range(self.stages)]  # start settled: no start-up transient
        inp = x
        for s in range(self.stages):
            self.y[s] = self.y[s] + self.a * (inp - self.y[s])
            inp = self.y[s]
        return inp.copy()


# --------------------------------------------------------------------------- simulation


def _column_names(vessel):
    """Thruster log columns in vessel-file order: ``[(name, rpm_col, azimuth_col or None), ...]``."""
    out = []
    for t in vessel.thrusters:
        out.append((t.name, f"{t.name}_rpm", f"{t.name}_azimuth_deg" if t.type == "azimuth" else None))
    return out


def _acceleration_field(components: env.WaveField) -> env.WaveField:
    """Components whose WF "motion" is the second time derivative of the original's.

    ``d^2/dt^2 [A sin(theta)] = A w^2 sin(theta + pi)`` (same for cos), so scaling the
    amplitudes by ``w^2`` and shifting the phases by pi reuses
    :func:`~hybridship.sim.environment.wave_frequency_motion` for accelerations (with the
    same frozen-heading assumption as its rates).
    """
    return env.WaveField(omega_rad_s=components.omega_rad_s,
                         amplitude_m=components.amplitude_m * components.omega_rad_s**2,
                         phase_rad=components.phase_rad + math.pi, dir_from_rad=components.dir_from_rad,
                         d_omega_rad_s=components.d_omega_rad_s, hs_m=components.hs_m, tp_s=components.tp_s,
                         gamma=components.gamma, mean_dir_from_rad=components.mean_dir_from_rad,
                         g_m_s2=components.g_m_s2)


def _sensor_noise(nz: SensorNoise, n: int, h: float, rng) -> dict:
    """Sensor noise on the integration grid (``n`` samples ``h`` apart; one draw each, in a
    fixed order); the DP and the log sample it. Angles in radians."""
    gnss = (nz.gnss_white_m * rng.standard_normal((n, 2))
            + np.column_stack([_gauss_markov(n, h, nz.gnss_markov_m, nz.gnss_markov_tau_s, rng)
                               for _ in range(2)]))
    n_head = math.radians(nz.heading_white_deg) * rng.standard_normal(n)
    n_uv = nz.uv_white_m_s * rng.standard_normal((n, 2))
    n_r = math.radians(nz.r_white_deg_s) * rng.standard_normal(n)
    n_ws = nz.wind_speed_white_m_s * rng.standard_normal(n)
    n_wd = math.radians(nz.wind_dir_white_deg) * rng.standard_normal(n)
    return dict(gnss=gnss, head=n_head, uv=n_uv, r=n_r, ws=n_ws, wd=n_wd)


class _DPSystem:
    """The DP system on the nominal model: sensors (LF + WF motion + noise), wave and wind
    filters, controller and thrust allocation, started at ``eta0``."""

    def __init__(self, nominal, ves, config: DPLossConfig, eta0, components, raos, noise: dict,
                 wind_speed, wind_dir):
        self.dp = DPController(nominal, dt_s=config.control_dt_s)
        self.alloc = ThrustAllocator(ves, dt_s=config.control_dt_s)
        self.dp.reset(eta0.copy())
        self.wave_filter = _LowPass(config.wave_filter_time_constant_s, config.control_dt_s)
        self.wind_filter = _LowPass(config.wind_filter_time_constant_s, config.control_dt_s, stages=1)
        self.psi_meas_prev = None
        self.components, self.raos, self.noise = components, raos, noise
        self.wind_speed, self.wind_dir = wind_speed, wind_dir

    def command(self, k: int, one, eta, nu):
        """``(rpm, azimuth_rad)`` commands from what the sensors give at integration step ``k``
        (time ``one[0]`` [s]) for the true state ``eta``, ``nu``."""
        nz = self.noise
        # What the sensors give now: LF + WF motion + noise (the log repeats it).
        off, rate = env.wave_frequency_motion(one, eta[2], self.components, self.raos,
                                              position_ne_m=eta[None, :2], return_rates=True)
        nu_wf = ned_to_body(rate[0], eta[2])
        psi_m = eta[2] + off[0, 2] + nz["head"][k]
        # Filter the heading continuously across the 0/2 pi wrap.
        prev = self.psi_meas_prev
        psi_m = psi_m if prev is None else prev + float(wrap_pi(psi_m - prev))
        self.psi_meas_prev = psi_m
        gnss, n_uv = nz["gnss"], nz["uv"]
        meas = np.array([eta[0] + off[0, 0] + gnss[k, 0], eta[1] + off[0, 1] + gnss[k, 1], psi_m,
                         nu[0] + nu_wf[0] + n_uv[k, 0], nu[1] + nu_wf[1] + n_uv[k, 1],
                         nu[2] + nu_wf[2] + nz["r"][k]])
        est = self.wave_filter(meas)
        ws_m = max(0.0, self.wind_speed[k] + nz["ws"][k])
        wd_m = self.wind_dir[k] + nz["wd"][k]
        # Smooth the wind as a vector (direction "from"), then back to speed and direction.
        wv = self.wind_filter(np.array([ws_m * math.cos(wd_m), ws_m * math.sin(wd_m)]))
        wind_est = np.array([math.hypot(wv[0], wv[1]), math.atan2(wv[1], wv[0])])
        tau_dp = self.dp.update(est[:3], est[3:], wind=wind_est)
        # The DP does not know the current: over-ground velocity stands in for the inflow.
        res = self.alloc.allocate(tau_dp, est[3:])
        return res.rpm, res.azimuth_rad


class _Record:
    """Logged samples of the true state and loads: ``n`` rows, ``K`` thrusters."""

    def __init__(self, n: int, K: int):
        self.eta, self.nu, self.nu_dot = (np.empty((n, 3)) for _ in range(3))
        self.parts = np.empty((n, 4, 3))
        self.thrust, self.rpm, self.az = (np.empty((n, K)) for _ in range(3))
        self.k = np.empty(n, dtype=int)


def _simulate(config: DPLossConfig, vessel, progress: bool):
    """The scenario as ``(DataFrame, ScenarioConditions)``; see :func:`simulate_dp_loss`."""
    true_model = DynamicModel(vessel, true_vessel=True)
    ves = true_model.vessel
    nominal = DynamicModel(ves)
    K = true_model.n_thrusters
    if K == 0:
        raise ValueError(f"vessel: {ves.name!r} has no thrusters; a DP scenario needs some")
    rho = ves.particulars.rho_water_kg_m3
    p = ves.particulars
    hull = env.HullDimensions(L_m=p.L_pp_m, B_m=p.B_m, T_m=p.T_m)
    raos = env.MotionRAOs.from_hull(hull)

    rng = np.random.default_rng(config.seed)
    cond = _realise(config, rng)
    sea = cond.sea_state

    # Time grids: integration (sim), control and log are nested uniform grids.
    h = config.sim_dt_s
    n_sim = int(round(cond.t_end_s / h))
    every_log = int(round(config.dt_s / h))
    every_ctrl = int(round(config.control_dt_s / h))
    k_shutdown = int(round(cond.t_shutdown_s / h))
    t_sim = np.arange(n_sim + 1) * h

    # Environment on the integration grid (one draw each, fixed order).
    components = sea.wave_components(rng, config.n_wave_components, config.wave_spreading)
    wind_speed, wind_dir = sea.wind(t_sim, rng)
    cur_speed, cur_dir = sea.current(t_sim, rng)

    noise = _sensor_noise(config.noise, n_sim + 1, h, rng)

    eta = np.array([0.0, 0.0, cond.heading_sp_rad])
    nu = np.zeros(3)
    dp = _DPSystem(nominal, ves, config, eta, components, raos, noise, wind_speed, wind_dir)

    rpm_cmd = np.zeros(K)
    rpm = np.zeros(K)
    azimuth = np.array([t.fixed_angle_rad for t in ves.thrusters], float)
    rpm_decay = math.exp(-h / config.rpm_time_constant_s)
    # The DP commands thrusters only: rudders stay amidships, given explicitly so that
    # the physics and the log's <rudder>_azimuth_deg columns are the same numbers.
    rudder = np.zeros(true_model.n_rudders) if true_model.n_rudders else None
    rec = _Record(n_sim // every_log + 1, K)

    one = np.empty(1)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n_sim, unit="step", desc=f"dp-loss seed {config.seed}", leave=False)
    try:
        for k in range(n_sim + 1):
            t = k * h
            one[0] = t
            wind_k = (wind_speed[k], wind_dir[k])
            cur_k = (cur_speed[k], cur_dir[k])
            tau_wave = env.wave_drift_loads(one, eta[2], components, hull, rho, position_ne_m=eta[None, :2])[0]

            if k < k_shutdown:
                if k % every_ctrl == 0:
                    rpm_cmd, azimuth = dp.command(k, one, eta, nu)
            else:
                rpm_cmd = np.zeros(K)  # power lost: no command; azimuths stay where they were
            rpm = rpm_cmd + (rpm - rpm_cmd) * rpm_decay

            if k % every_log == 0:
                i = k // every_log
                nu_dot, parts, thrusts = true_model.acceleration(eta, nu, rpm=rpm, azimuth_rad=azimuth,
                                                                 wind=wind_k, current=cur_k, tau_ext=tau_wave,
                                                                 rudder_rad=rudder, return_parts=True)
                rec.eta[i], rec.nu[i], rec.nu_dot[i] = eta, nu, nu_dot[0]
                rec.parts[i], rec.thrust[i] = parts[0], thrusts[0]
                rec.rpm[i], rec.az[i], rec.k[i] = rpm, azimuth, k
                if bar is not None and k > 0:
                    bar.update(every_log)
            if k == n_sim:
                break
            e1, n1 = true_model.step(eta, nu, dt_s=h, substeps=1, rpm=rpm, azimuth_rad=azimuth, wind=wind_k,
                                     current=cur_k, tau_ext=tau_wave, rudder_rad=rudder)
            eta, nu = e1[0], n1[0]
            if not (np.all(np.isfinite(eta)) and np.all(np.isfinite(nu))):
                raise FloatingPointError(f"simulation diverged at t = {t + h:g} s (seed {config.seed})")
    finally:
        if bar is not None:
            bar.close()

    df = _assemble_log(config, ves, cond, components, raos, rec.k, h, rec.eta, rec.nu, rec.nu_dot, rec.parts,
                       rec.thrust, rec.rpm, rec.az, dict(speed=wind_speed, dir=wind_dir, cur=cur_speed,
                                                         cur_dir=cur_dir), noise, rudder)
    df.attrs["conditions"] = cond.as_dict()
    df.attrs["seed"] = config.seed
    df.attrs["vessel"] = ves.name
    return df, cond


# Decimals kept per column group: a logger's resolution for measured values; enough
# for ground truth not to lose information (e.g. accelerations ~1e-3 m/s^2).
_DECIMALS = {"pos": 4, "deg": 4, "vel": 5, "acc": 7, "rpm": 3, "load": 2, "frac": 6, "env": 5}


def _assemble_log(config, ves, cond, components, raos, rec_k, h, eta, nu, nu_dot, parts, thrust, rpm, az,
                  envs, noise, rudder=None):
    """Build the log DataFrame from the recorded LF samples, WF motion and noise (``rudder``:
    the rudder angles [rad] the physics held through the whole run, or None without rudders)."""
    t = rec_k * h
    pos = eta[:, :2]
    # WF motion along the LF track, vectorised (same function as the DP's measurements).
    off, rate = env.wave_frequency_motion(t, eta[:, 2], components, raos, position_ne_m=pos, return_rates=True)
    acc = env.wave_frequency_motion(t, eta[:, 2], _acceleration_field(components), raos, position_ne_m=pos)
    nu_wf = ned_to_body(rate, eta[:, 2])
    nu_dot_wf = ned_to_body(acc, eta[:, 2])
    eta_tot = eta + off
    nu_tot = nu + nu_wf
    nu_dot_tot = nu_dot + nu_dot_wf

    k = rec_k
    dp_active = (k < int(round(cond.t_shutdown_s / h))).astype(np.int64)
    ws_true, wd_true = envs["speed"][k], envs["dir"][k]
    d = _DECIMALS
    deg = np.degrees
    cols: dict[str, np.ndarray] = {}
    cols["time_s"] = np.round(t, 6)
    cols["north_m"] = np.round(eta_tot[:, 0] + noise["gnss"][k, 0], 3)
    cols["east_m"] = np.round(eta_tot[:, 1] + noise["gnss"][k, 1], 3)
    cols["heading_deg"] = np.round(deg(eta_tot[:, 2] + noise["head"][k]) % 360.0, 3)
    cols["u_m_s"] = np.round(nu_tot[:, 0] + noise["uv"][k, 0], 4)
    cols["v_m_s"] = np.round(nu_tot[:, 1] + noise["uv"][k, 1], 4)
    cols["r_deg_s"] = np.round(deg(nu_tot[:, 2] + noise["r"][k]), 4)
    cols["wind_speed_m_s"] = np.round(np.maximum(0.0, ws_true + noise["ws"][k]), 3)
    cols["wind_dir_deg"] = np.round(deg(wd_true + noise["wd"][k]) % 360.0, 2)
    limits = bollard_thrust_limits(ves).forward_N
    thr_cols = _column_names(ves)
    for j, (_, rpm_col, az_col) in enumerate(thr_cols):
        cols[rpm_col] = np.round(rpm[:, j], 2)
        if az_col is not None:
            cols[az_col] = np.round(deg(wrap_pi(az[:, j])), 2)
    for r, rud in enumerate(ves.rudders):  # a rudder's angle is logged in its azimuth column
        cols[f"{rud.name}_azimuth_deg"] = np.full(t.size, np.round(deg(rudder[r]), 2))
    cols["dp_active"] = dp_active

    # Ground truth, named like truthsim-dev's columns.
    for j, (name, _, _) in enumerate(thr_cols):
        cols[f"truth_{name}_thrust_frac"] = np.round(thrust[:, j] / limits[j], d["frac"])
    cols["truth_north_m"] = np.round(eta_tot[:, 0], d["pos"])
    cols["truth_east_m"] = np.round(eta_tot[:, 1], d["pos"])
    cols["truth_heading_deg"] = np.round(deg(eta_tot[:, 2]) % 360.0, d["deg"])
    cols["truth_north_lf_m"] = np.round(eta[:, 0], d["pos"])
    cols["truth_east_lf_m"] = np.round(eta[:, 1], d["pos"])
    cols["truth_heading_lf_deg"] = np.round(deg(eta[:, 2]) % 360.0, d["deg"])
    cols["truth_u_mps"] = np.round(nu_tot[:, 0], d["vel"])
    cols["truth_v_mps"] = np.round(nu_tot[:, 1], d["vel"])
    cols["truth_r_degps"] = np.round(deg(nu_tot[:, 2]), d["vel"])
    cols["truth_u_lf_mps"] = np.round(nu[:, 0], d["vel"])
    cols["truth_v_lf_mps"] = np.round(nu[:, 1], d["vel"])
    cols["truth_r_lf_degps"] = np.round(deg(nu[:, 2]), d["vel"])
    cols["truth_udot_mps2"] = np.round(nu_dot_tot[:, 0], d["acc"])
    cols["truth_vdot_mps2"] = np.round(nu_dot_tot[:, 1], d["acc"])
    cols["truth_rdot_degps2"] = np.round(deg(nu_dot_tot[:, 2]), d["acc"])
    cols["truth_udot_lf_mps2"] = np.round(nu_dot[:, 0], d["acc"])
    cols["truth_vdot_lf_mps2"] = np.round(nu_dot[:, 1], d["acc"])
    cols["truth_rdot_lf_degps2"] = np.round(deg(nu_dot[:, 2]), d["acc"])
    cols["truth_wind_speed_mps"] = np.round(ws_true, d["env"])
    cols["truth_wind_dir_from_deg"] = np.round(deg(wd_true) % 360.0, d["deg"])
    cols["truth_current_speed_mps"] = np.round(envs["cur"][k], d["env"])
    cols["truth_current_dir_to_deg"] = np.round(deg(envs["cur_dir"][k]) % 360.0, d["deg"])
    s = cond.sea_state
    n = t.size
    cols["truth_hs_m"] = np.full(n, round(s.hs_m, 4))
    cols["truth_tp_s"] = np.full(n, round(s.tp_s, 4))
    cols["truth_wave_dir_from_deg"] = np.full(n, round(math.degrees(s.wave_dir_from_rad) % 360.0, d["deg"]))
    for part, label in ((1, "thrust"), (2, "wind"), (3, "wave2"), (0, "hull")):
        for c, suffix in enumerate(("x_N", "y_N", "n_Nm")):
            cols[f"truth_tau_{label}_{suffix}"] = np.round(parts[:, part, c], d["load"])
    cols["truth_heading_sp_deg"] = np.full(n, round(math.degrees(cond.heading_sp_rad) % 360.0, d["deg"]))
    cols["truth_t_shutdown_s"] = np.full(n, cond.t_shutdown_s)
    return pd.DataFrame(cols)


def simulate_dp_loss(config: DPLossConfig | None = None, vessel="gunnerus", progress: bool = False) -> pd.DataFrame:
    """Simulate one DP-loss scenario and return its log.

    Parameters
    ----------
    config : DPLossConfig, optional
        Scenario settings; default ``DPLossConfig()`` (seed 0, Beaufort 2-5, 50 min DP,
        15 min drift).
    vessel : str, path or hybridship.vessel.Vessel
        Packaged vessel name, vessel file, or a loaded vessel.
    progress : bool
        Show a tqdm progress bar (on stderr).

    Returns
    -------
    pandas.DataFrame
        One row per ``config.dt_s`` from 0 to ``t_shutdown + drift_s`` inclusive, in the
        project log format:

        * measured: ``time_s``, ``north_m``, ``east_m``, ``heading_deg`` (LF + WF motion +
          noise; heading in [0, 360], 360.0 where the rounding to the log's
          decimals reaches it, as ``truth_heading*_deg`` and ``wind_dir_deg``), ``u_m_s``,
          ``v_m_s``, ``r_deg_s`` (LF + WF + noise),
          ``wind_speed_m_s``, ``wind_dir_deg`` (true wind + noise), ``<thruster>_rpm``
          (shaft speed feedback), ``<azimuth>_azimuth_deg`` (in [-180, 180], likewise),
          ``<rudder>_azimuth_deg`` for each rudder (0: the DP commands thrusters only and
          the simulated rudders stay amidships), ``dp_active`` (1 before the shutdown, 0
          from the first sample at or after it);
        * truth (noise-free): ``truth_{north,east}_m``, ``truth_heading_deg``,
          ``truth_{u,v}_mps``, ``truth_r_degps`` (LF + WF), the LF-only
          ``truth_{north,east}_lf_m``, ``truth_heading_lf_deg``,
          ``truth_{u,v}_lf_mps``, ``truth_r_lf_degps``; body-frame accelerations
          ``truth_{u,v}dot_mps2``, ``truth_rdot_degps2`` (LF model + WF) and their
          ``_lf_`` parts (the true model's nu_dot); ``truth_wind_speed_mps``,
          ``truth_wind_dir_from_deg``, ``truth_current_speed_mps``,
          ``truth_current_dir_to_deg``, ``truth_hs_m``, ``truth_tp_s``,
          ``truth_wave_dir_from_deg``; body-frame loads on the LF model
          ``truth_tau_{thrust,wind,wave2,hull}_{x_N,y_N,n_Nm}``;
          ``truth_<thruster>_thrust_frac`` (delivered thrust / bollard thrust);
          ``truth_heading_sp_deg`` and ``truth_t_shutdown_s`` (constants).

        ``DataFrame.attrs["conditions"]`` holds the realised conditions (see
        :meth:`ScenarioConditions.as_dict`).

    Raises
    ------
    ValueError
        Bad vessel (a :class:`hybridship.vessel.VesselFileError`) or config, or a vessel
        whose thrusters cannot hold station in surge, sway and yaw
        (:func:`hybridship.sim.allocation.check_station_keeping`), refused before any work.
    """
    config = DPLossConfig() if config is None else config
    if not isinstance(config, DPLossConfig):
        raise TypeError(f"config: expected a DPLossConfig, got {type(config).__name__}")
    check_flags(progress=progress)      # a text "no" is truthy
    check_station_keeping(vessel)  # before any work: a DP that cannot hold all three DOF is no DP
    df, _ = _simulate(config, vessel, progress)
    return df


# --------------------------------------------------------------------------- statistics


def _shutdown_time(log: pd.DataFrame) -> float:
    if "truth_t_shutdown_s" in log.columns:
        t_sd = float(log["truth_t_shutdown_s"].iloc[0])
        if not math.isfinite(t_sd):         # every statistic came out NaN
            raise ValueError(f"log: truth_t_shutdown_s is {t_sd} in the first row; expected the shutdown time [s] "
                             "(or drop the column to take the first row with dp_active 0)")
        return t_sd
    if "dp_active" in log.columns:
        off = np.flatnonzero(log["dp_active"].to_numpy() == 0)
        if off.size:
            return float(log["time_s"].iloc[off[0]])
    raise ValueError("log: cannot find the shutdown (no truth_t_shutdown_s and dp_active never 0)")


def _check_statistics_input(log, dp_settle_s) -> None:
    """Refuse what :func:`drift_statistics` cannot summarise, naming the argument or column."""
    if not isinstance(log, pd.DataFrame):
        raise TypeError(f"log: expected a pandas DataFrame (see hybridship.logs.io.read_log), got "
                        f"{type(log).__name__}")
    track = (("truth_north_lf_m", "truth_east_lf_m", "truth_heading_lf_deg") if "truth_north_lf_m" in log.columns
             else ("north_m", "east_m", "heading_deg"))
    missing = [c for c in ("time_s", *track) if c not in log.columns]
    if missing:
        raise ValueError(f"log: missing column(s) {', '.join(missing)}; the statistics need time_s and the track "
                         f"{', '.join(track)}")
    check_number("dp_settle_s", dp_settle_s, lo=0.0)
    # the statistics search the times (searchsorted): a shuffled log gave wrong numbers or NaN
    env._time_vector(log["time_s"].to_numpy(float))


def drift_statistics(log: pd.DataFrame, *, dp_settle_s: float = 600.0) -> dict:
    """Drift and station-keeping statistics of one DP-loss log.

    Uses the noise-free low-frequency track (``truth_north_lf_m``, ``truth_east_lf_m``,
    ``truth_heading_lf_deg``) when present, else the measured columns; works on our logs
    and truthsim-dev's alike. The shutdown time is ``truth_t_shutdown_s`` or the first
    sample with ``dp_active == 0``.

    Parameters
    ----------
    log : pandas.DataFrame
        A log whose ``time_s`` is finite and strictly increasing (as :func:`hybridship.logs.io.read_log` gives).
    dp_settle_s : float
        Start-up time excluded from the DP statistics [s] (at most half the DP phase).

    Returns
    -------
    dict
        ``t_shutdown_s``; ``drift_excursion_{60,600}s_m``: distance from the position at the
        shutdown after 60 and 600 s [m] (NaN if the drift is shorter; every drift statistic
        is NaN when no sample lies within 0.5 s of the shutdown);
        ``drift_dheading_{60,600}s_deg``: heading change [deg]; ``drift_mean_sog_mps``:
        mean speed over ground over the first 600 s of drift (or all of it if shorter);
        ``drift_net_speed_mps``: straight-line excursion over that window / its duration;
        ``drift_dir_to_deg``: direction of that net displacement; ``dp_pos_std_m``:
        ``sqrt(var(north) + var(east))`` on DP after the start-up; ``dp_pos_max_m``:
        largest distance from the set-point (origin) there; ``dp_heading_std_deg``.
    """
    _check_statistics_input(log, dp_settle_s)
    t = log["time_s"].to_numpy(float)
    lf = "truth_north_lf_m" in log.columns
    n = log["truth_north_lf_m" if lf else "north_m"].to_numpy(float)
    e = log["truth_east_lf_m" if lf else "east_m"].to_numpy(float)
    psi = np.unwrap(np.radians(log["truth_heading_lf_deg" if lf else "heading_deg"].to_numpy(float)))
    t_sd = _shutdown_time(log)
    out = {"t_shutdown_s": t_sd}

    def at(dt):
        i = int(np.searchsorted(t, t_sd + dt - _EPS_S))
        return i if i < t.size and abs(t[i] - (t_sd + dt)) < 0.5 else None

    # the drift is measured from the sample at the shutdown; a log that starts after it has none
    # (its first sample stood in for it, and the 600-s excursion was measured from there)
    i0 = at(0)
    i0 = t.size if i0 is None else i0
    for dt in (60, 600):
        i = at(dt) if i0 < t.size else None
        out[f"drift_excursion_{dt}s_m"] = float(np.hypot(n[i] - n[i0], e[i] - e[i0])) if i is not None else np.nan
        out[f"drift_dheading_{dt}s_deg"] = float(np.degrees(psi[i] - psi[i0])) if i is not None else np.nan
    i_end = at(600)
    i_end = t.size - 1 if i_end is None else i_end
    sl = slice(i0, i_end + 1)
    if i_end > i0:
        sog = np.hypot(np.gradient(n[sl], t[sl]), np.gradient(e[sl], t[sl]))
        dur = t[i_end] - t[i0]
        out["drift_mean_sog_mps"] = float(sog.mean())
        out["drift_net_speed_mps"] = float(np.hypot(n[i_end] - n[i0], e[i_end] - e[i0]) / dur)
        out["drift_dir_to_deg"] = float(np.degrees(np.arctan2(e[i_end] - e[i0], n[i_end] - n[i0])) % 360.0)
    else:
        out.update(drift_mean_sog_mps=np.nan, drift_net_speed_mps=np.nan, drift_dir_to_deg=np.nan)
    settle = min(dp_settle_s, 0.5 * (t_sd - t[0]))
    dp = (t >= t[0] + settle) & (t < t_sd - _EPS_S)
    if dp.sum() >= 2:
        out["dp_pos_std_m"] = float(np.sqrt(n[dp].var() + e[dp].var()))
        out["dp_pos_max_m"] = float(np.hypot(n[dp], e[dp]).max())
        out["dp_heading_std_deg"] = float(np.degrees(psi[dp].std()))
    else:
        out.update(dp_pos_std_m=np.nan, dp_pos_max_m=np.nan, dp_heading_std_deg=np.nan)
    return out


# --------------------------------------------------------------------------- sweeps


def log_file_name(seed: int, fmt: str = "csv.gz") -> str:
    """File name of a sweep's log, e.g. ``sim_dp_loss_seed0001.csv.gz``.

    Raises
    ------
    ValueError
        ``seed`` not a whole number >= 0 (a float or text, a negative number), or an
        unknown ``fmt``, naming the argument.
    """
    seed = check_whole_number("seed", seed)
    if fmt not in LOG_FORMATS:
        raise ValueError(f"fmt: expected one of {', '.join(LOG_FORMATS)}, got {fmt!r}")
    return f"sim_dp_loss_seed{seed:04d}.{fmt}"


def sweep(out_dir, seeds: Iterable[int], *, beaufort=(2, 5), fmt: str = "csv.gz", vessel="gunnerus",
          progress: bool = False, **config_overrides) -> list[Path]:
    """Simulate one scenario per seed; write the logs and a ``scenarios.csv`` summary.

    Parameters
    ----------
    out_dir : str or path-like
        Output folder (created if missing).
    seeds : iterable of int
        One scenario per seed (distinct, non-negative).
    beaufort : (float, float)
        Beaufort range of the random sea states.
    fmt : {"csv", "csv.gz", "parquet"}
        Log container (file extension).
    vessel : str, path or Vessel
    progress : bool
        A progress bar over the seeds (on stderr).
    **config_overrides
        Further :class:`DPLossConfig` fields (e.g. ``drift_s=600``).

    Returns
    -------
    list of Path
        The log files, in the order of ``seeds``. ``out_dir / "scenarios.csv"`` (written
        atomically, after all logs) has one row per log: file, seed, the realised
        conditions (truthsim-dev's column names), and :func:`drift_statistics`. A sweep
        into a folder that already has one keeps its rows of other seeds (a rewritten
        seed's row is replaced: one row per seed), sorted by seed, so sweeps of several
        seed ranges add up.

    Raises
    ------
    TypeError
        Before any simulation: ``out_dir`` not a path (None).
    ValueError
        Before any simulation: an empty ``out_dir``; bad seeds, format or config; a vessel that cannot hold
        station (:func:`hybridship.sim.allocation.check_station_keeping`); an unreadable
        ``scenarios.csv``; or a seed whose log is already in ``out_dir`` in another format
        (the folder would hold the same scenario twice, and training on it would count it
        twice). A log of the same seed and format is rewritten.
    """
    check_flags(progress=progress)      # a text "no" is truthy
    out = as_path(out_dir, "out_dir")   # None failed in pathlib's words, after the vessel was loaded
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Iterable):     # one int: "not iterable"
        raise TypeError(f"seeds: expected an iterable of non-negative ints (e.g. [1, 2] or range(1, 11)), "
                        f"got {seeds!r}")
    seeds = [s for s in seeds]
    if not seeds:
        raise ValueError("seeds: expected at least one seed")
    for s in seeds:
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 0:
            raise ValueError(f"seeds: expected non-negative ints, got {s!r}")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds: duplicates in {seeds}")
    if fmt not in LOG_FORMATS:
        raise ValueError(f"fmt: expected one of {', '.join(LOG_FORMATS)}, got {fmt!r}")
    for bad in ("seed", "beaufort"):
        if bad in config_overrides:
            raise ValueError(f"{bad}: pass it as the sweep's own argument, not as a config override")
    configs = [DPLossConfig(seed=int(s), beaufort=beaufort, **config_overrides) for s in seeds]  # validate first
    model = DynamicModel(vessel)  # fail early on a bad vessel; reuse the loaded file
    ves = model.vessel
    check_station_keeping(ves)

    from hybridship.logs.io import write_log

    _refuse_other_formats(out, seeds, fmt)
    earlier = _earlier_summary(out / "scenarios.csv")  # before the work: a damaged file stops it here
    # never replace a file of the user's under a log's name; a sweep's own (recorded, or
    # listed in the folder's scenarios.csv from before the record) are rewritten
    swept = set() if earlier is None else set(earlier["file"].astype(str))
    check_output_files(out, [log_file_name(c.seed, fmt) for c in configs] + ["scenarios.csv"],
                       ours=lambda name, _: name in swept or (name == "scenarios.csv" and earlier is not None))
    make_out_folder(out)
    paths, rows = [], []
    it = configs
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(configs, unit="scenario", desc="sweep")
    for cfg in it:
        df, cond = _simulate(cfg, ves, progress=False)
        path = out / log_file_name(cfg.seed, fmt)
        write_log(df, path, channel_names=ves.channel_names, rotatable=ves.rotatable)
        record_outputs(out, [path.name])        # as it is written: an interrupted sweep's logs are ours too
        paths.append(path)
        heading_mode = "fixed" if cfg.heading_sp_deg is not None else cfg.heading_mode
        rows.append({"file": path.name, "seed": cfg.seed, **cond.as_dict(), "heading_mode": heading_mode,
                     "beaufort_lo": cfg.beaufort[0], "beaufort_hi": cfg.beaufort[1],
                     **{k: v for k, v in drift_statistics(df).items() if k != "t_shutdown_s"}})
    summary = pd.DataFrame(rows)
    if earlier is not None:
        # keyed by seed, not file: a seed rewritten in another format must not keep its old row
        kept = earlier[~earlier["seed"].isin(summary["seed"]) & ~earlier["file"].isin(summary["file"])]
        summary = pd.concat([kept, summary], ignore_index=True).sort_values("seed", kind="stable")
    atomic_write(out / "scenarios.csv", lambda fh: fh.write(summary.round(4).to_csv(index=False).encode("utf-8")))
    record_outputs(out, ["scenarios.csv"])
    return paths


def _refuse_other_formats(out: Path, seeds, fmt: str) -> None:
    """Refuse seeds whose log already exists in ``out`` in a format other than ``fmt``.

    Refused rather than replaced: the sweep was not asked to delete a file (it may be the
    only copy someone converted by hand), and the fix is one ``rm`` away.
    """
    clashes = [(s, other) for s in seeds for other in LOG_FORMATS
               if other != fmt and (out / log_file_name(s, other)).exists()]
    if clashes:
        shown = ", ".join(str(out / log_file_name(s, other)) for s, other in clashes[:3])
        more = f" and {len(clashes) - 3} more" if len(clashes) > 3 else ""
        hit = sorted({s for s, _ in clashes})
        which = f"seed {hit[0]} has" if len(hit) == 1 else f"{len(hit)} seeds have"
        raise ValueError(f"out_dir: {which} a log there in another format already ({shown}{more}); a {fmt} copy "
                         f"as well would be the same scenario twice (trained on twice): remove the old "
                         f"file(s), sweep in their format, or use another folder")


def _earlier_summary(path: Path) -> pd.DataFrame | None:
    """The rows of an earlier sweep's ``scenarios.csv`` in the same folder (None if there is none)."""
    if not path.exists():
        return None
    try:
        earlier = pd.read_csv(path)
    except (OSError, ValueError) as exc:  # pandas' parser errors are ValueErrors
        why = ("it is empty" if isinstance(exc, pd.errors.EmptyDataError) else
               "it is not text" if isinstance(exc, UnicodeDecodeError) else " ".join(str(exc).split()))
        raise ValueError(f"{path}: an earlier sweep's summary that cannot be read ({why}); move it away "
                         "or sweep into another folder") from None
    missing = {"file", "seed"} - set(earlier.columns)
    if missing:
        raise ValueError(f"{path}: not a sweep summary (no column {', '.join(sorted(missing))}); move it away "
                         "or sweep into another folder")
    return earlier


# --------------------------------------------------------------------------- embedded set

#: Settings of the embedded scenarios: 10 min DP (enough to settle), 10 min drift.
EMBEDDED_OVERRIDES = dict(t_shutdown_s=600.0, t_shutdown_jitter_s=30.0, drift_s=600.0)


@lru_cache(maxsize=8)
def _embedded(n: int, seed: int) -> tuple:
    out = []
    for i in range(n):
        cfg = DPLossConfig(seed=seed + i, **EMBEDDED_OVERRIDES)
        df, _ = _simulate(cfg, "gunnerus", progress=False)
        out.append((f"embedded_seed{seed + i:04d}", cfg, df))
    return tuple(out)


def embedded_scenarios(n: int = 3, seed: int = 0) -> list[Scenario]:
    """A small default set of Gunnerus DP-loss scenarios, generated on the fly.

    Each is ``DPLossConfig(seed=seed + i, t_shutdown_s=600, t_shutdown_jitter_s=30,
    drift_s=600)`` (Beaufort 2-5, bow to weather): 10 min on DP, then 10 min of
    drift, about one second of computing each. Results are cached per ``(n, seed)``; each call returns
    fresh copies of the logs.

    Parameters
    ----------
    n : int
        Number of scenarios (1-20).
    seed : int
        Seed of the first scenario; the others follow.

    Returns
    -------
    list of Scenario
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= 20:
        raise ValueError(f"n: expected an int in 1..20, got {n!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed: expected a non-negative int, got {seed!r}")
    return [Scenario(name, cfg, df.copy(deep=True)) for name, cfg, df in _embedded(int(n), int(seed))]
