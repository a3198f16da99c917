"""The environment estimator: current, slowly varying load and thruster-model error from a log.

An extended Kalman filter in the spirit of the bias state of a DP observer (Fossen 2021,
ch. 13), with the unknown inputs given their physical structure instead of one lumped bias.
Its state (14) is

* ``eta = [north_m, east_m, psi_rad]`` and ``nu = [u_m_s, v_m_s, r_rad_s]`` (the filtered
  motion, measured by the log's position, heading and velocities);
* ``v_c = [north_m_s, east_m_s]``: an irrotational current, constant in NED. It acts
  through the relative velocity ``nu_r = nu - R(psi)^T v_c`` of the hull model, so a
  drifting ship is carried along by it rather than pushed by a constant force;
* ``b = [north_m_s2, east_m_s2, yaw_rad_s2]``: a slowly varying environmental load (wave
  drift, wind-model error) as an acceleration, surge/sway in NED (it does not turn with the
  ship), yaw as is;
* ``theta``: the thrust-model error, by default (``thrust_error_model="per_thruster"``) one
  efficiency factor per thruster (thruster ``i`` delivers ``(1 + theta_i)`` times the
  model's thrust, acting through its own lever arm: ``M^-1 sum_i theta_i tau_i``); with
  ``thrust_error_model="per_dof"`` one factor per degree of freedom on the model's thrust
  acceleration ``M^-1 tau_thr`` (componentwise).

The process model is the project's dynamic model (one RK4 step per sample) with the current
and with ``accel_ext = R(psi)^T b + T theta`` (``T``: the thrust-error basis, see
:mod:`.environment_kernel`); the filter loop is compiled there. ``v_c`` and ``b`` are random
walks, and so is ``theta`` unless ``thrust_error_walk`` is 0; while the thrusters are stopped
the load walks faster (``load_walk_after_stop_m_s2``, ``load_yaw_walk_after_stop_rad_s2``: a
drifting ship turns and moves relative to the weather). While the thrusters are stopped,
the yaw acceleration ``k u v`` of the hull's yaw moment in a drift (:mod:`.drift_hull`) is
added when :meth:`EnvironmentEstimator.run` is given ``k``, as the forecasts after a failure
add it; otherwise the yaw load ``b_yaw`` takes up the hull's error during the drift and the
forecasts would count it twice.

What the data can separate, and what the filter then does:

* **Load vs. thrust error.** While the thrusters hold the ship on station, the thrust
  answers the environment, so their mean effects add up to one observed offset. The filter
  splits that offset in proportion to the prior spreads (``load_prior_m_s2`` against
  ``thrust_error_prior`` times the thrust acceleration) and keeps the split's uncertainty as
  a correlation between ``b`` and ``theta``. Thrust that varies independently of the slow
  environment (command steps in a manoeuvre, the thrust step at a DP failure in a training
  log) identifies ``theta``; :meth:`EnvironmentEstimator.fit` carries such an estimate from
  training logs into the prior. When the thrusters stop, the ``theta`` term vanishes, and
  the first drift samples resolve the correlation: the residual is environment only.
* **Per thruster or per DOF.** By default ``theta`` holds one constant efficiency factor
  per thruster. A thruster's error acts through its own lever arm, so the station-keeping
  yaw offset is split between the thrusters' errors and the yaw load by how the allocation
  varies, not by a rule; the yaw load's prior (``load_yaw_prior_rad_s2`` = 1e-3 rad/s^2, the
  order of the wind's yaw moment on the Gunnerus at 10 m/s over its yaw inertia) is wide
  enough not to decide that split (results change little from 3e-4 up). At a stop the
  filter keeps its state (``reset_yaw_load_at_stop`` False): the thrust-error term
  vanishes with the thrust and the load carries on. What this cannot separate: with a
  wind feed-forward, the thrust follows the wind, so an error of the wind model looks
  like an error of the thrusters that answer it (on truthsim-dev the tunnel's error is
  found, while the azimuths take what the wind model gets wrong; figures in
  ``docs/concepts/environment.md``). The per-DOF structure (``thrust_error_model="per_dof"``,
  which was the default, with the yaw environment restarted at a stop) cannot describe
  one thruster's yaw error; ``docs/concepts/environment.md`` compares the two.
* **Current vs. load.** A ship at rest feels a current as a force; nothing in station-keeping
  data tells the two apart, and the split then follows the prior spreads. Once the ship moves
  through the water (a drift, a manoeuvre) the relative velocity changes, and the current is
  observable through the hull's damping.

All quantities are SI and radians inside.
"""

from __future__ import annotations

import numbers
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
import pandas as pd
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, model_validator

from ..config import (Bool, Float, Int, as_config, check_flags, check_number, check_whole_number, real_array,
                      settings_error, start_time_rng)
from ..frames import ned_to_body, vector_to_speed_dir
from ..forecast_inputs.faults import TRACK_MISMATCH_M, TRACK_WINDOW_S, velocity_track_mismatch_m
from ..logs.io import LogArrays
from ..physics.model import DynamicModel
from ..messages import seconds_text
from . import environment_kernel as kernel
from .drift_hull import gain_carries_over

#: Forward-difference steps of the filter's Jacobian, per state (SI units, radians).
_FD_STEP = np.array([1e-3, 1e-3, 1e-5, 1e-4, 1e-4, 1e-6, 1e-3, 1e-3, 1e-5, 1e-5, 1e-7])

#: State layout of the filter with one thrust-model error per degree of freedom
#: (``"per_dof"``; the default is one per thruster): :func:`state_names` gives the layout
#: for any setting.
STATE_NAMES = ("north_m", "east_m", "psi_rad", "u_m_s", "v_m_s", "r_rad_s",
               "current_north_m_s", "current_east_m_s",
               "load_north_m_s2", "load_east_m_s2", "load_yaw_rad_s2",
               "thrust_error_x", "thrust_error_y", "thrust_error_n")
ENV = slice(6, None)        # the environment part: current, load, thrust error
CUR, LOAD, THR = slice(6, 8), slice(8, 11), slice(11, None)
THRUST_ERROR_MODELS = ("per_dof", "per_thruster")
LOAD_MODELS = ("acceleration", "force")
_PositiveFloat = Annotated[Float, Field(gt=0)]


def _bool_or_auto(v):
    """True, False (numpy's too) or ``"auto"``; anything else refused in one message."""
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, str) and v == "auto":
        return v
    raise ValueError(f"expected True, False or 'auto', got {v!r}")


_BoolOrAuto = Annotated[bool | Literal["auto"], BeforeValidator(_bool_or_auto)]


class EnvironmentConfig(BaseModel):
    """Noise and prior settings of :class:`EnvironmentEstimator` (recorded in model files).

    Measurement standard deviations include the wave-frequency motion the filter does not
    model; the process noise on ``nu`` covers unmodelled fast loads (first-order waves,
    gusts beyond the wind model). The random-walk intensities set how fast ``b``, ``v_c``
    and ``theta`` may move [unit per sqrt(s)].

    With ``reset_yaw_load_at_stop`` (off by default), the yaw environment restarts at a
    thrust stop: it keeps ``yaw_load_kept_at_stop`` of its station-keeping value, with a
    spread of ``yaw_load_std_at_stop`` times that value on top of its prior (default: the
    part not kept). Off, the filter's state simply carries on.

    ``held_load_window_s`` and ``held_load_block_s`` set how the variability of the load
    is measured in the station keeping before a failure, for the spread of the forecasts
    after it (:mod:`hybridship.residual.load_variability`; a window of 0 switches it off,
    any other must hold at least three blocks).

    A position or heading measurement whose innovation exceeds ``innovation_gate_sigma``
    standard deviations of its predicted spread, and jumped there from the innovation of the
    sample before, is an outlier and is not used (a GNSS spike in the history of a forecast
    would otherwise throw the estimate off); so are the samples after it whose innovation
    stays beyond the gate, until ``max_gated_samples`` in a row of the same channel were: a
    lasting shift (a datum change) is then followed by restarting that channel at the
    measurement, which leaves the velocities and the environment as they were. An
    innovation that grows past the gate without a jump (a drifting ship turning faster
    than the model predicts) is the ship's motion, and is used. The logged velocities are
    not gated: they carry the wave-frequency motion, whose innovations in rough seas reach
    any gate that would catch a spike.

    With ``wave_turned_yaw_load``, forecasts after a failure turn the held yaw load with the
    waves: their axis comes from the wave-frequency motion of the last ``wave_axis_window_s``
    of station keeping (where the motion's variance ratio reaches ``min_wave_anisotropy``),
    and the load follows ``sin(2 beta)`` of the relative wave direction from its value at the
    start's heading, where that ``|sin(2 beta)|`` reaches ``min_wave_sin2``
    (:mod:`hybridship.residual.wave_direction`).

    ``load_model`` chooses what the slowly varying load ``b`` is: ``"acceleration"`` (the
    default) an acceleration fixed in NED, ``accel = [R(psi)^T b_ne; b_yaw]``; ``"force"`` a
    force fixed in NED and a yaw moment, ``accel = M^-1 [R(psi)^T F; N]``, with the state kept
    in acceleration units by a reference mass and inertia: ``F = m_ref b_ne``, ``N = I_ref
    b_yaw``, ``m_ref = 2 / (M^-1_uu + M^-1_vv)``, ``I_ref = 1 / M^-1_rr`` (:func:`load_map`). A
    fixed force then gives a turning ship a body acceleration that changes with the heading
    (the surge and sway masses differ) and a yaw acceleration through ``M^-1``'s sway-yaw
    coupling. The stop options that move the load (``reset_yaw_load_at_stop``,
    ``load_to_current_at_stop``, ``current_std_at_stop_m_s``) take it as an acceleration and
    are not available with ``"force"``.

    ``thrust_error_model`` chooses the structure of ``theta``: ``"per_dof"`` (three
    efficiency factors on the surge, sway and yaw thrust, prior ``thrust_error_prior``) or
    ``"per_thruster"`` (one efficiency factor per thruster, acting through that thruster's
    lever arm, prior ``thrust_error_prior_per_thruster`` each).

    Attributes
    ----------
    position_std_m, heading_std_deg, velocity_std_m_s, yaw_rate_std_deg_s : float
        Measurement standard deviations of north/east [m], heading [deg], surge/sway speed
        [m/s] and yaw rate [deg/s]; with ``adaptive_measurement_std`` the floor under the
        wave-motion estimate (positions keep theirs: a GNSS error is slow, not wave-like).
    accel_noise_m_s2, yaw_accel_noise_rad_s2 : float
        Process noise on the surge/sway [m/s^2] and yaw [rad/s^2] accelerations.
    current_prior_m_s, load_prior_m_s2, load_yaw_prior_rad_s2 : float
        Prior standard deviations of each current component [m/s] and of the load in
        north/east [m/s^2] and yaw [rad/s^2] (all with mean 0).
    current_prior_wind_ref_m_s, current_prior_max_m_s : float or None, float
        With a reference wind speed ``U_ref`` [m/s] (default None: the prior is
        ``current_prior_m_s`` whatever the weather), the current's prior standard deviation
        at a filter start is ``current_prior_m_s (U_ref / U)^2``, clipped to
        ``[current_prior_m_s, max(current_prior_m_s, current_prior_max_m_s)]`` [m/s], where
        ``U`` is the logged wind speed at the filter's first row (held from the last logged
        sample; a log without wind keeps ``current_prior_m_s``): see
        :func:`current_prior_std_m_s`.
    load_prior_across_wind : float
        The NED load's prior across the wind's axis, as a fraction of ``load_prior_m_s2``
        (its prior along the axis) [-]; the axis is the wind's direction logged at the
        filter's first row. 1 (default): the same in every direction. See
        :func:`load_prior_ne`.
    current_walk_m_s, load_walk_m_s2, load_yaw_walk_rad_s2, thrust_error_walk : float
        Random-walk intensities of the current, the load and the thrust errors [unit per
        sqrt(s)]; 0 keeps the state constant.
    load_walk_after_stop_m_s2, load_yaw_walk_after_stop_rad_s2 : float
        The load's random-walk intensities while the thrusters are stopped [m/s^2 and
        rad/s^2 per sqrt(s)], in place of ``load_walk_m_s2`` and ``load_yaw_walk_rad_s2``.
        A drifting ship turns and moves relative to the waves, the wind and the current,
        so its environment load changes within a minute, while on station it changes
        slowly. With the station-keeping walks the filter kept the station keeping's load
        through the whole drift, and forecasts started later in a drift held it
        (``benchmarks/drift_late_starts.py``). Equal to the station-keeping walks: the
        filter before 2026-11-30 (model files of format 17 and older).
    thrust_error_prior : tuple of 3 float
        Prior standard deviations (each > 0) of the per-DOF efficiency factors (``"per_dof"``) [-].
    thrust_error_model : {"per_dof", "per_thruster"}
        Structure of the thrust errors (above).
    load_model : {"acceleration", "force"}
        What the load ``b`` is (above).
    thrust_error_prior_per_thruster : float
        Prior standard deviation of each thruster's efficiency factor (``"per_thruster"``) [-].
    use_velocity : bool
        Also use the logged surge/sway speeds and yaw rate as measurements (when logged).
    adaptive_measurement_std : bool
        Raise each measurement's standard deviation to the spread of its wave-frequency part:
        the signal less its centred ``wave_window_s`` [s] moving mean, over the
        ``variance_window_s`` [s] before the row (causal).
    wave_window_s, variance_window_s : float
        See ``adaptive_measurement_std`` [s].
    reset_yaw_load_at_stop, yaw_load_kept_at_stop, yaw_load_std_at_stop : bool, float, float or None
        The yaw environment at a thrust stop (above).
    current_std_at_stop_m_s : float
        At a thrust stop, widen the current's uncertainty by this much [m/s] per NED axis
        along the ridge on which station keeping cannot tell a current from a load (each
        current change paired with the load change that keeps the hull's acceleration), so
        that the drift, in which the ship starts to move through the water, decides the
        split; the estimate itself does not change at the stop. 0 (default): not.
    load_to_current_at_stop : float
        At a thrust stop, re-explain this fraction of the NED load's surge/sway acceleration
        as a current (the current whose hull response at the stop adds that much), the load
        giving up what the current takes over, in yaw too; the acceleration at the stop is
        unchanged, the drift after it is not (a current carries the ship, a force pushes it).
        0 (default): the station keeping's split is kept.
    filter_step_s : float
        Longest filter step [s]: a faster log is filtered on every ``m``-th row.
    held_load_window_s, held_load_block_s : float
        Window and block length [s] over which the load's variability is measured (above).
    settle_s : float
        For this long [s] after the filter starts (and after a gap restarts the motion
        states from the measurement), the measurements settle the motion states only and
        leave the environment as it was (the cross-covariance is cut before each update):
        otherwise the start-up transient of motion states started from one sample moves
        the current-load split, which station keeping cannot correct afterwards, so that an
        estimate depends on where its filter started. 0: no settling.
    max_bridged_gap_s : float
        A gap in the log (a step over 1.5 times the log's own, which starts a new segment) up
        to this long [s] (between the rows the filter steps on; at most 300 s) is filtered across: the process model predicts through it with the
        commands before it, as a Kalman filter does without measurements, and the samples
        after it update the estimate. A longer gap restarts the motion states from the
        measurement. (Restarting at a single missing sample took the velocity from one
        wave-disturbed sample, and every forecast of the next seconds with it.) 0: every gap
        restarts.
    innovation_gate_sigma, max_gated_samples : float, int
        Outlier gate on position and heading (above).
    wave_turned_yaw_load, wave_axis_window_s, min_wave_anisotropy, min_wave_sin2 : bool or "auto", float, float, float
        The held yaw load turned with the waves after a failure (above; window in [s]).
        ``"auto"`` (the default): :meth:`HybridPredictor.fit <hybridship.predictors.HybridPredictor.fit>`
        turns it only where the training logs' failures (five or more) show that it lowers
        the heading error (``training_info["wave_yaw_load"]``); held where ``fit`` learns
        nothing from failures (``HybridPredictor(drift_hull=False)``, the paper's protocol).
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    def __init__(self, **settings):
        # built directly, pydantic's own text ('1 validation error for ...', a web link); named
        # field by field as every config_dataclass is
        try:
            super().__init__(**settings)
        except ValidationError as err:
            raise settings_error(err, "EnvironmentConfig") from None

    position_std_m: Float = Field(0.5, gt=0)
    heading_std_deg: Float = Field(0.3, gt=0)
    velocity_std_m_s: Float = Field(0.05, gt=0)
    yaw_rate_std_deg_s: Float = Field(0.1, gt=0)
    accel_noise_m_s2: Float = Field(0.01, gt=0)
    yaw_accel_noise_rad_s2: Float = Field(3e-4, gt=0)
    current_prior_m_s: Float = Field(0.02, gt=0)
    current_walk_m_s: Float = Field(0.0, ge=0)
    current_prior_wind_ref_m_s: Float | None = Field(None, gt=0)
    current_prior_max_m_s: Float = Field(0.3, gt=0)
    load_prior_m_s2: Float = Field(0.02, gt=0)
    load_prior_across_wind: Float = Field(1.0, gt=0, le=1)
    load_yaw_prior_rad_s2: Float = Field(1e-3, gt=0)
    load_walk_m_s2: Float = Field(2e-5, ge=0)
    load_yaw_walk_rad_s2: Float = Field(1e-6, ge=0)
    thrust_error_prior: tuple[_PositiveFloat, _PositiveFloat, _PositiveFloat] = (0.2, 0.2, 0.5)
    thrust_error_model: Literal["per_dof", "per_thruster"] = "per_thruster"
    thrust_error_prior_per_thruster: Float = Field(0.2, gt=0)
    thrust_error_walk: Float = Field(0.0, ge=0)
    load_walk_after_stop_m_s2: Float = Field(3e-4, ge=0)
    load_yaw_walk_after_stop_rad_s2: Float = Field(1e-5, ge=0)
    use_velocity: Bool = True
    adaptive_measurement_std: Bool = True
    wave_window_s: Float = Field(30.0, gt=0)
    variance_window_s: Float = Field(600.0, gt=0)
    reset_yaw_load_at_stop: Bool = False
    filter_step_s: Float = Field(1.0, gt=0)
    yaw_load_kept_at_stop: Float = Field(0.0, ge=0.0, le=1.0)
    yaw_load_std_at_stop: Float | None = Field(None, ge=0.0)
    current_std_at_stop_m_s: Float = Field(0.0, ge=0.0)
    load_to_current_at_stop: Float = Field(0.0, ge=0.0, le=1.0)
    held_load_window_s: Float = Field(600.0, ge=0.0)
    held_load_block_s: Float = Field(30.0, gt=0.0)
    settle_s: Float = Field(0.0, ge=0.0)
    max_bridged_gap_s: Float = Field(10.0, ge=0.0, le=300.0)
    innovation_gate_sigma: Float = Field(8.0, gt=0.0)
    max_gated_samples: Int = Field(10, ge=0)
    wave_turned_yaw_load: _BoolOrAuto = "auto"
    wave_axis_window_s: Float = Field(600.0, gt=0.0)
    min_wave_anisotropy: Float = Field(3.0, ge=1.0)
    min_wave_sin2: Float = Field(0.3, gt=0.0, le=1.0)
    load_model: Literal["acceleration", "force"] = "acceleration"

    @model_validator(mode="after")
    def _force_without_stop_options(self):
        if self.load_model == "force" and (self.reset_yaw_load_at_stop or self.load_to_current_at_stop > 0
                                           or self.current_std_at_stop_m_s > 0):
            raise ValueError("load_model='force': reset_yaw_load_at_stop, load_to_current_at_stop and "
                             "current_std_at_stop_m_s take the load as an acceleration; leave them off")
        return self

    @model_validator(mode="after")
    def _held_load_window_of_three_blocks(self):
        # the variability is the spread of at least three block means: a shorter window never gave one
        if 0 < self.held_load_window_s < 3 * self.held_load_block_s:
            raise ValueError(f"held_load_window_s: must be 0 (off) or at least three held_load_block_s = "
                             f"{3 * self.held_load_block_s:g} s, got {self.held_load_window_s:g}")
        return self


#: The per-DOF structure with its own settings (the default before the per-thruster one):
#: three thrust-error factors that drift slowly, and the yaw environment restarted at a stop,
#: with the tight yaw-load prior it was measured with. ``EnvironmentConfig(**PER_DOF)``.
PER_DOF = dict(thrust_error_model="per_dof", thrust_error_walk=2e-3, reset_yaw_load_at_stop=True,
               load_yaw_prior_rad_s2=3e-5)


@dataclass(frozen=True)
class EnvironmentEstimate:
    """Filtered state at chosen rows of a log (each estimate uses only rows up to its own).

    Attributes
    ----------
    rows : ndarray of int, shape (S,)
        Log rows of the estimates.
    time_s : ndarray, shape (S,)
    x : ndarray, shape (S, 11 + n_theta)
        State means in the order of :func:`state_names` (SI, radians).
    P : ndarray, shape (S, 11 + n_theta, 11 + n_theta)
        State covariances.
    thrust_error_model : {"per_dof", "per_thruster"}
        Structure of the thrust errors ``x[:, 11:]``.
    load_map : ndarray (3, 3) or None
        With the load a force (``load_model="force"``), ``A`` of :func:`load_map`: the load's
        body acceleration is ``A [R(psi)^T b_ne; b_yaw]``; None: the load is an acceleration.
    """

    rows: np.ndarray
    time_s: np.ndarray
    x: np.ndarray
    P: np.ndarray
    thrust_error_model: str = "per_dof"
    load_map: np.ndarray | None = None

    @property
    def current_ned_m_s(self) -> np.ndarray:
        """Current velocity ``[north, east]`` [m/s], (S, 2)."""
        return self.x[:, CUR]

    @property
    def current_speed_dir(self) -> np.ndarray:
        """Current as the model takes it: ``[speed_m_s, dir_to_rad]``, (S, 2)."""
        c = self.x[:, CUR]
        return vector_to_speed_dir(c)

    @property
    def load_accel(self) -> np.ndarray:
        """Environmental load ``[north_m_s2, east_m_s2, yaw_rad_s2]``, (S, 3) (with
        :attr:`load_map`, a NED force and yaw moment per reference mass and inertia)."""
        return self.x[:, LOAD]

    @property
    def thrust_error(self) -> np.ndarray:
        """Thrust-model error (fractions of the thrust), (S, n_theta): per DOF or per thruster
        as :attr:`thrust_error_model` says."""
        return self.x[:, THR]

    def thrust_error_accel(self, model, eta, nu, rpm, az, wind) -> np.ndarray:
        """Acceleration (S, 3) [m/s^2, m/s^2, rad/s^2] of the estimated thrust-model error at
        the states ``eta, nu`` (S, 3) and commands ``rpm, az`` (S, K + R), ``wind`` (S, 2)."""
        return thrust_error_accel(model, self.thrust_error_model, eta, nu, rpm, az, wind,
                                  self.current_ned_m_s, self.thrust_error)

    def take(self, which) -> "EnvironmentEstimate":
        """The estimates at ``which`` (a slice or an index array into :attr:`rows`)."""
        return EnvironmentEstimate(self.rows[which], self.time_s[which], self.x[which], self.P[which],
                                   self.thrust_error_model, self.load_map)

    @classmethod
    def concatenate(cls, parts: list["EnvironmentEstimate"], order=None) -> "EnvironmentEstimate":
        """The estimates of ``parts`` one after another, then taken at ``order`` (an index array
        into the concatenation; default: as they come)."""
        est = cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in ("rows", "time_s", "x", "P")),
                  parts[0].thrust_error_model, parts[0].load_map)
        return est if order is None else est.take(np.asarray(order, dtype=int))

    def sample_environment(self, n: int, seed: int = 0) -> np.ndarray:
        """Draws of ``[v_c (2), b (3), theta (n_theta)]`` from the posterior, shape (n, S, 5 + n_theta).

        The draws are centred: their mean is the posterior mean whatever ``n``, so an
        ensemble forecast's mean does not depend on the sampling.
        Deterministic for a given ``seed`` and start time: a start's draws do not depend on
        which other starts are forecast with it, nor on how much log before it was read.
        ``n`` and ``seed`` are whole numbers >= 0.
        """
        n, seed = check_whole_number("n", n), check_whole_number("seed", seed)
        S, m = self.x.shape[0], self.x.shape[1] - ENV.start
        out = np.broadcast_to(self.x[:, ENV], (n, S, m)).copy()
        if n < 2 or S == 0:         # no start (run with no rows): nothing to draw for
            return out
        Pe = self.P[:, ENV, ENV]
        L = np.linalg.cholesky(Pe + 1e-18 * np.eye(m))                  # (S, m, m)
        z = np.stack([start_time_rng(seed, t).standard_normal((n - 1, m)) for t in self.time_s],
                     axis=1)                                             # (n - 1, S, m)
        dev = np.concatenate([np.zeros((1, S, m)), np.einsum("sij,nsj->nsi", L, z)])
        return out + dev - dev.mean(axis=0)     # centred: the members' mean is the posterior mean


def state_names(model, config: "EnvironmentConfig") -> tuple[str, ...]:
    """The filter's state layout for ``model`` and ``config``: :data:`STATE_NAMES` with the
    thrust-model error per degree of freedom, or ``thrust_error_<thruster>`` per thruster."""
    if config.thrust_error_model == "per_dof":
        return STATE_NAMES
    return STATE_NAMES[:THR.start] + tuple(f"thrust_error_{t.name}" for t in model.vessel.thrusters)


def thrust_error_accel(model, thrust_error_model, eta, nu, rpm, az, wind, current_ned, theta) -> np.ndarray:
    """Acceleration (B, 3) [m/s^2, m/s^2, rad/s^2] of the thrust-model error ``theta``.

    Per DOF, ``theta * M^-1 tau_thr`` componentwise; per thruster, ``M^-1 sum_i theta_i
    tau_i`` with each thruster's generalised force ``tau_i``. At states ``eta, nu`` (B, 3),
    commands ``rpm, az`` (B, K + R), ``wind`` (B, 2) and current ``current_ned`` (B, 2) [m/s].
    """
    B = len(eta)
    args = [np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=float), (B,) + np.shape(a)[-1:]))
            for a in (eta, nu, model._channels("rpm", rpm, B, None)[:, 0],
                      model._channels("azimuth_rad", az, B, None)[:, 0], wind, current_ned, theta)]
    out = np.empty((B, 3))
    kernel.thrust_error_accel_batch(*args, model.arrays, thrust_error_model == "per_thruster", out)
    return out


def current_input(v_c_ned: np.ndarray) -> np.ndarray:
    """NED current velocity (..., 2) -> the model's ``[speed_m_s, dir_to_rad]`` (..., 2)."""
    return vector_to_speed_dir(v_c_ned)


def load_map(model, load_model: str):
    """``A = M^-1 diag(m_ref, m_ref, I_ref)`` (3, 3) of a load that is a force
    (``load_model="force"``), with ``m_ref = 2 / (M^-1_uu + M^-1_vv)`` and ``I_ref = 1 / M^-1_rr``:
    the load's body acceleration is ``A [R(psi)^T b_ne; b_yaw]``. None for ``"acceleration"``."""
    if load_model == "acceleration":
        return None
    if load_model != "force":
        raise ValueError(f"load_model: expected one of {LOAD_MODELS}, got {load_model!r}")
    mi = np.asarray(model.arrays.m_inv, dtype=float)
    m_ref = 2.0 / (mi[0, 0] + mi[1, 1])
    return np.ascontiguousarray(mi @ np.diag([m_ref, m_ref, 1.0 / mi[2, 2]]))


def external_accel(psi_rad, load_ned, theta, a_thr, load_map=None) -> np.ndarray:
    """``R(psi)^T b + theta * a_thr``: the estimator's extra body-frame acceleration (..., 3)
    (per-DOF thrust error; ``theta = 0`` gives the load alone). With ``load_map`` ``A`` (the
    load a force, :func:`load_map`): ``A [R(psi)^T b_ne; b_yaw] + theta * a_thr``."""
    c, s = np.cos(psi_rad), np.sin(psi_rad)
    out = np.zeros(np.shape(load_ned)) + theta * np.asarray(a_thr)
    if load_map is not None:
        return out + ned_to_body(load_ned, psi_rad) @ np.asarray(load_map).T
    out[..., 0] += c * load_ned[..., 0] + s * load_ned[..., 1]
    out[..., 1] += -s * load_ned[..., 0] + c * load_ned[..., 1]
    out[..., 2] += load_ned[..., 2]
    return out


def current_prior_std_m_s(config: EnvironmentConfig, wind_speed_m_s: float | None) -> float:
    """The current's prior standard deviation [m/s] at a filter start where the wind speed
    ``wind_speed_m_s`` [m/s] was logged (None: not known).

    Station keeping sees a current only as the force it puts on the ship at rest, the same
    offset a load gives, and the filter splits that offset by the two priors. The load it
    stands for (wave drift, the wind model's error) grows with the wind, roughly as its
    dynamic pressure, while a current does not. With ``config.current_prior_wind_ref_m_s``
    the current's prior therefore scales as ``(U_ref / U)^2``: in light wind a steady offset
    is taken more as a current, which carries a drifting ship instead of pushing it. Clipped
    to ``[current_prior_m_s, max(current_prior_m_s, current_prior_max_m_s)]``; without a
    reference speed, or without a logged wind, ``current_prior_m_s``.
    """
    base = config.current_prior_m_s
    if config.current_prior_wind_ref_m_s is None or wind_speed_m_s is None:
        return base
    ratio = config.current_prior_wind_ref_m_s / max(wind_speed_m_s, 1e-6)
    return float(min(max(base * ratio ** 2, base), max(base, config.current_prior_max_m_s)))


def load_prior_ne(config: EnvironmentConfig, wind_dir_from_rad: float | None) -> np.ndarray:
    """The NED load's prior covariance (2, 2) [(m/s^2)^2] at a filter start where the wind
    was logged from ``wind_dir_from_rad`` [rad] (None: no wind logged); a first entry of -1
    where it is ``load_prior_m_s2`` in every direction (the filter then keeps its diagonal).

    The load stands for the wave drift and the wind model's error. Both push along the
    weather's axis: the wave drift along the waves' (within about 35 deg of it in our
    simulator's and in truthsim-dev's scenarios), the waves mostly from near the wind. A
    current comes from anywhere. With ``config.load_prior_across_wind`` ``rho < 1`` the
    load's prior is ``s^2 (a a^T + rho^2 (I - a a^T))``, ``s = load_prior_m_s2`` and ``a``
    the wind's axis, so that station keeping takes an offset across the wind more as a
    current (or a thruster's error) than as a load.
    """
    rho = config.load_prior_across_wind
    if rho == 1.0 or wind_dir_from_rad is None:
        return np.full((2, 2), -1.0)
    a = np.array([np.cos(wind_dir_from_rad), np.sin(wind_dir_from_rad)])
    along = np.outer(a, a)
    return config.load_prior_m_s2 ** 2 * (along + rho ** 2 * (np.eye(2) - along))


def _wind_dir_at(arrays: LogArrays, row: int) -> float | None:
    """The logged wind direction [rad, from] at ``row`` (as :func:`_wind_speed_at`)."""
    return float(arrays.wind[row, 1]) if arrays.wind_logged[:row + 1].any() else None


def _wind_speed_at(arrays: LogArrays, row: int) -> float | None:
    """The logged wind speed [m/s] at ``row`` (the log's own hold of the last logged sample), None
    where no wind was logged at or before it."""
    return float(arrays.wind[row, 0]) if arrays.wind_logged[:row + 1].any() else None


def thrust_error_prior_carries_over(errors_configured, errors_learned) -> tuple[bool, list[float]]:
    """Whether a thrust-error prior learned at thrust stops (:meth:`EnvironmentEstimator.fit`)
    is kept: on failures left out of the learning, one at a time, it must lower both the
    mean position error and the mean heading error of the forecasts after the failure,
    against the configured prior, and the per-failure gains in each must pass a one-sided
    Wilcoxon signed-rank test at :data:`~hybridship.residual.drift_hull.KEEP_P_VALUE`, the
    rule of the hull's yaw moment in a drift (a mean gain carried by one or two failures is
    not kept; with fewer than five failures none can pass).

    Parameters
    ----------
    errors_configured, errors_learned : array, shape (L, 2)
        Per left-out failure, the mean position error [m] and heading error [rad] of its
        forecasts with the configured prior, and with the prior learned on the other failures.

    Returns
    -------
    kept : bool
    p_values : list of float
        The signed-rank p-values of the position and of the heading gains.
    """
    c = np.asarray(errors_configured, dtype=float)
    g = np.asarray(errors_learned, dtype=float)
    if c.ndim != 2 or c.shape[1] != 2 or c.shape != g.shape or c.shape[0] == 0:
        raise ValueError(f"errors: expected two arrays of shape (n_failures, 2), got {c.shape} and {g.shape}")
    if not (np.all(np.isfinite(c)) and np.all(np.isfinite(g))):
        raise ValueError("errors: must be finite")
    (kept_position, p_position), (kept_heading, p_heading) = (gain_carries_over(c[:, j], g[:, j])
                                                               for j in range(2))
    return kept_position and kept_heading, [p_position, p_heading]


def environment_accel(model, arrays, estimate: EnvironmentEstimate, nu=None) -> np.ndarray:
    """The acceleration (N, 3) [m/s^2, m/s^2, rad/s^2] that the estimate explains at every row.

    ``a(current, accel_ext) - a(no environment)`` of the dynamic model at each row's logged
    state and commands (``nu`` overrides the logged velocities), where the estimate at that
    row (an :class:`EnvironmentEstimate` over all rows) gives the current, the load and the
    thrust error. NaN where the row has no estimate or input (a state or command that is
    not finite).
    """
    given = [arrays.eta, arrays.nu if nu is None else nu, arrays.rpm, arrays.azimuth_rad, arrays.wind]
    eta, nu, rpm, az, wind = (np.nan_to_num(v) for v in given)
    n = len(arrays.time_s)
    x = np.full((n, estimate.x.shape[1]), np.nan)
    x[estimate.rows] = estimate.x
    ok = np.isfinite(x).all(1)
    for v in given:         # a missing input was taken as 0 (a stopped ship, no wind) and gave a value
        ok &= np.isfinite(np.asarray(v, dtype=float)).all(1)
    xe = np.nan_to_num(x)
    acc = external_accel(eta[:, 2], xe[:, LOAD], 0.0, 0.0, estimate.load_map) + thrust_error_accel(
        model, estimate.thrust_error_model, eta, nu, rpm, az, wind, xe[:, CUR], xe[:, THR])
    a_env = model.acceleration(eta, nu, rpm=rpm, azimuth_rad=az, wind=wind,
                               current=current_input(xe[:, CUR]), accel_ext=acc)
    out = a_env - model.acceleration(eta, nu, rpm=rpm, azimuth_rad=az, wind=wind)
    out[~ok] = np.nan
    return out


def _checked_rows(n: int, rows, first_row, required) -> tuple[np.ndarray, int, int]:
    """The arguments of :meth:`EnvironmentEstimator.run` on a log of ``n`` rows: ``rows``
    (default: all from ``first_row``) as a 1-D int array, ``first_row`` as an int and the
    number of rows that must have an estimate; an error naming the argument otherwise."""
    if isinstance(first_row, bool) or not isinstance(first_row, (int, np.integer)) or not 0 <= first_row < n:
        raise ValueError(f"first_row: expected a whole number in [0, {n - 1}], got {first_row!r}")
    first_row = int(first_row)
    if rows is None:
        rows = np.arange(first_row, n)
    else:
        rows = np.asarray(rows)
        if rows.ndim != 1 or (rows.size and rows.dtype.kind not in "iu"):
            raise ValueError(f"rows: expected a 1-D array of whole row numbers, got shape {rows.shape} "
                             f"and dtype {rows.dtype}")
        rows = rows.astype(int)
    if rows.size and (rows.min() < first_row or rows.max() >= n):
        raise ValueError(f"rows: must lie in [{first_row}, {n - 1}]")
    n_req = rows.size if required is None else check_whole_number("required", required)
    if n_req > rows.size:
        raise ValueError(f"required: expected at most the {rows.size} rows given, got {required!r}")
    return rows, first_row, n_req


def _time_windows(t, first_s, last_s, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """``(start, end)``: for each row, the rows ``start <= k < end`` of the sorted times ``t``
    [s] from ``first_s`` to ``last_s`` [s] (arrays of the rows' length), within half a log
    step ``dt`` [s] at either end, so that on an evenly sampled log a window of ``m`` log
    steps holds ``m + 1`` rows whatever the times' rounding."""
    return (np.searchsorted(t, first_s - 0.5 * dt, side="right").astype(np.int64),
            np.searchsorted(t, last_s + 0.5 * dt, side="left").astype(np.int64))


class _Windows(pd.api.indexers.BaseIndexer):
    """Rolling windows given as the rows ``start[i] <= k < end[i]`` of each row ``i``, for
    pandas' rolling aggregations (on an evenly sampled log, the bounds of its fixed windows)."""

    def __init__(self, start: np.ndarray, end: np.ndarray):
        super().__init__()
        self._start, self._end = start, end

    def get_window_bounds(self, num_values=0, min_periods=None, center=None, closed=None, step=None):
        return self._start, self._end


class EnvironmentEstimator:
    """Causal environment estimation over a log (see the module notes).

    Parameters
    ----------
    model : hybridship.physics.model.DynamicModel
    config : EnvironmentConfig or dict
        Its settings (a dict of its fields is validated as one).
    """

    def __init__(self, model, config: EnvironmentConfig = EnvironmentConfig()):
        if not isinstance(model, DynamicModel):     # a vessel name failed on model.vessel, in Python's words
            raise TypeError(f"model: expected a DynamicModel, got {type(model).__name__} (DynamicModel({model!r})?)")
        self.model = model
        self.config = config = as_config(config, EnvironmentConfig, "config")
        #: The filter's state layout (:func:`state_names`).
        self.state_names = state_names(model, config)
        #: Prior mean and standard deviation of ``theta``; :meth:`fit` may replace them.
        self.thrust_error_mean, self.thrust_error_std = self._configured_thrust_error_prior()
        self._shared_runs = None        # see sharing_station_keeping
        #: ``A`` of :func:`load_map` with the load a force; None with the load an acceleration.
        self.load_map = load_map(model, config.load_model)

    def _configured_thrust_error_prior(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation (n_theta,) of ``theta``'s prior as configured: 0 and
        ``thrust_error_prior`` (per DOF) or ``thrust_error_prior_per_thruster`` (per thruster)."""
        c = self.config
        n_theta = len(self.state_names) - THR.start
        std = (np.asarray(c.thrust_error_prior, dtype=float) if c.thrust_error_model == "per_dof"
               else np.full(n_theta, c.thrust_error_prior_per_thruster))
        return np.zeros(n_theta), std

    # ------------------------------------------------------------------ learning

    def fit(self, logs_arrays, *, dp_only: bool = False, after_stop_s: float = 60.0) -> "EnvironmentEstimator":
        """Carry the thrust-model error seen at thrust stops in training logs into the prior.

        Station keeping alone cannot separate thrust error from load: the thrust answers the
        environment, and a regression of the residual on the thrust is biased by that loop.
        A thrust stop (a DP failure: ``dp_active`` 1 -> 0) can: the environment is the same
        just before and just after it, so what changes in the residual is the thrust
        model's error. For every stop with ``after_stop_s`` of samples after it, the filter
        runs to that point and its ``theta`` (resolved by the drift samples through the
        load/thrust-error correlation it carried) is kept. The precision-weighted mean over
        the stops becomes the prior mean; the precision-weighted spread between stops, but at
        least the pooled uncertainty of the mean (``1 / sqrt`` of the stops' summed
        precisions, below any one stop's own), its standard deviation. Without stops, or with ``dp_only`` (the paper's
        protocol, in which nothing of a failure is seen), the prior is the configured one:
        0 +- ``thrust_error_prior_per_thruster`` (or ``thrust_error_prior`` per DOF). Each call
        learns afresh from the configured prior: what an earlier call learned is neither
        kept nor used as the prior of the runs (which would count its logs twice).

        Not learned here: how much of the station-keeping yaw environment survives a stop
        (``yaw_load_kept_at_stop``). With the per-DOF thrust error, learning it as the ratio
        of the drift's yaw environment 60 s after each training stop to the one before it was
        tried: it helped on our own scenarios and made truthsim-dev's heading 1.4-1.9x worse
        than physics under the fleet protocol, because the drift's yaw residual there also
        holds the hull model's yaw error at drift speeds, which the ratio then mistakes for
        environment. With the per-thruster error (the default) the filter needs no such rule:
        it keeps its state at a stop.

        :meth:`hybridship.predictors.HybridPredictor.fit` keeps what is learned here only
        where it carries over to failures it was not learned on
        (:func:`thrust_error_prior_carries_over`); otherwise it restores the configured prior.

        What a stop does not resolve: the first minute of drift moves the ship too little to
        undo the confusion of the azimuths' error with the wind model's error (module
        notes). On our own scenarios, whose thrusters deliver 0.95 of the model's thrust,
        the learned azimuth errors are -0.2 to -0.3, as in station keeping, whether 10, 20
        or 60 s of drift are read.

        Parameters
        ----------
        logs_arrays : iterable of LogArrays
            The training logs as :class:`~hybridship.logs.io.LogArrays`
            (:func:`hybridship.predictors.as_log_arrays` reads a DataFrame or file); anything
            else is a TypeError naming it.
        dp_only : bool
            Training sees only station keeping: nothing to learn here.
        after_stop_s : float
            Drift time after a stop that the filter reads before its estimate is taken [s],
            finite and >= 0.
        """
        check_flags(dp_only=dp_only)
        after_stop_s = check_number("after_stop_s", after_stop_s, lo=0.0)
        self.thrust_error_mean, self.thrust_error_std = self._configured_thrust_error_prior()
        if dp_only:
            return self
        means, precs = [], []
        for k, a in enumerate(logs_arrays):
            if not isinstance(a, LogArrays):
                # a DataFrame's dp_active is a Series, whose shifted slices align by index and
                # so never show a stop: nothing was learned, without a word
                raise TypeError(f"logs_arrays[{k}]: expected LogArrays (as_log_arrays reads a DataFrame or "
                                f"file), got {type(a).__name__}")
            dp = a.dp_active.astype(bool)
            stops = np.flatnonzero(dp[:-1] & ~dp[1:]) + 1
            for i in stops:
                end = int(np.searchsorted(a.time_s, a.time_s[i] + after_stop_s))
                if end >= len(a.time_s) or a.segment_id[end] != a.segment_id[i]:
                    continue
                first = int(np.searchsorted(a.time_s, a.time_s[i] - 1800.0))
                est = self.run(a, np.array([end]), first_row=first)
                means.append(est.x[0, THR])
                precs.append(1.0 / np.diag(est.P[0])[THR])
        if not means:
            return self
        means, precs = np.array(means), np.array(precs)
        m = np.sum(precs * means, axis=0) / precs.sum(axis=0)
        between = np.sqrt(np.sum(precs * (means - m) ** 2, axis=0) / precs.sum(axis=0))
        self.thrust_error_mean = m
        self.thrust_error_std = np.maximum(between, 1.0 / np.sqrt(precs.sum(axis=0)))
        return self

    # ------------------------------------------------------------------ filtering

    def _prior_sd(self, wind_speed_m_s: float | None = None) -> np.ndarray:
        """Prior standard deviations of the states at a filter start (SI, radians); the wind
        speed [m/s] logged there (None: not known) sets the current's
        (:func:`current_prior_std_m_s`)."""
        c = self.config
        return np.concatenate([[c.position_std_m] * 2, [np.radians(c.heading_std_deg)],
                               [c.velocity_std_m_s] * 2, [np.radians(c.yaw_rate_std_deg_s)],
                               [current_prior_std_m_s(c, wind_speed_m_s)] * 2, [c.load_prior_m_s2] * 2,
                               [c.load_yaw_prior_rad_s2],
                               self.thrust_error_std])

    def _process_noise_base(self, stopped: bool = False) -> np.ndarray:
        """Process-noise intensities (11 + n_theta,) that :func:`.environment_kernel.process_noise` scales by
        the step: position [m], velocity per second [m/s^2, rad/s^2], random walks per sqrt(s);
        with ``stopped``, those of a step while the thrusters are stopped (the load's walks
        ``load_walk_after_stop_m_s2``, ``load_yaw_walk_after_stop_rad_s2``)."""
        c = self.config
        load, yaw = ((c.load_walk_after_stop_m_s2, c.load_yaw_walk_after_stop_rad_s2) if stopped
                     else (c.load_walk_m_s2, c.load_yaw_walk_rad_s2))
        return np.concatenate([[1e-6] * 3, [c.accel_noise_m_s2] * 2, [c.yaw_accel_noise_rad_s2],
                               [c.current_walk_m_s] * 2, [load] * 2, [yaw],
                               [c.thrust_error_walk] * len(self.thrust_error_mean)])

    def _yaw_std_at_stop(self) -> float:
        """Spread of the yaw environment just after a stop, as a fraction of its
        station-keeping value: as configured, or the part not kept (``1 - kept``)."""
        c = self.config
        return float(1.0 - c.yaw_load_kept_at_stop if c.yaw_load_std_at_stop is None else c.yaw_load_std_at_stop)

    def _gate(self) -> np.ndarray:
        """Innovation gate [standard deviations] per measured channel ``[eta, nu]`` (6,): the
        position and heading; the velocities are not gated (see :class:`EnvironmentConfig`)."""
        return np.array([self.config.innovation_gate_sigma] * 3 + [np.inf] * 3)

    def _measurement_std(self):
        c = self.config
        return np.array([c.position_std_m, c.position_std_m, np.radians(c.heading_std_deg),
                         c.velocity_std_m_s, c.velocity_std_m_s, np.radians(c.yaw_rate_std_deg_s)])

    def _wave_motion_std(self, arrays, lo: int, hi: int) -> np.ndarray:
        """Per row, the standard deviation of the fast part of each measured channel (n, 6).

        The fast part is the signal less its centred ``wave_window_s`` moving mean: the
        wave-frequency motion and sensor noise, which the filter treats as measurement noise
        (a DP observer's wave filter in its simplest form). The value at row ``i`` is the
        spread over the ``variance_window_s`` before it, from fast parts whose centred
        window ends at or before ``i``, so it uses rows up to ``i`` only (causal). The windows'
        lengths follow the log's step, as the filter's grid does (:meth:`_filter_every`),
        not the step of the rows ``lo .. hi`` read, which would make row ``i``'s value depend
        on how far past it the run reads. The windows are spans of log time, each row placed
        by its time (:func:`_time_windows`): across a gap they hold fewer rows rather than
        stretch over more time, and a centred mean counts only where its window is sampled up
        to both of its ends. Positions keep the configured value (a GNSS error is slow, not
        wave-like).
        """
        n = len(arrays.time_s)
        out = np.zeros((n, 6))
        if hi + 1 - lo < 10:
            return out
        dt = self._filter_every(arrays)[1]
        w = max(3, int(round(self.config.wave_window_s / dt)))
        w += 1 - w % 2                                   # odd: a centred window
        h = w // 2
        nv = max(2 * w, int(round(self.config.variance_window_s / dt)))
        t = arrays.time_s[lo: hi + 1]
        x = pd.DataFrame(np.column_stack([arrays.eta[lo: hi + 1], arrays.nu[lo: hi + 1]]))
        # the centred mean: rows within h log steps of each row's time, all of them finite and
        # the window sampled to both ends (on an even log: the w rows around it)
        start, end = _time_windows(t, t - h * dt, t + h * dt, dt)
        centred = x.rolling(_Windows(start, end), min_periods=1)
        ends_sampled = (end > start) & (t[start] <= t - (h - 0.5) * dt) \
            & (t[np.maximum(end - 1, 0)] >= t + (h - 0.5) * dt)
        full = (centred.count().to_numpy() == (end - start)[:, None]) & ends_sampled[:, None]
        fast = x - centred.mean().where(full)
        # the spread of the fast parts of the nv log steps up to each row (at least w of them)
        s_start, s_end = _time_windows(t, t - (nv - 1) * dt, t, dt)
        sd = fast.rolling(_Windows(s_start, s_end), min_periods=w).std().to_numpy()
        # row i takes the spread at the last row j whose centred window has ended: its rows are
        # all at or before i, and its time h log steps or more before i's (on an even log j = i - h)
        ended = np.minimum(np.searchsorted(end, np.arange(1, len(t) + 1), side="right"),
                           np.searchsorted(t + h * dt, t + 0.5 * dt, side="right")) - 1
        sd = np.where((ended >= 0)[:, None], sd[np.maximum(ended, 0)], np.nan)
        sd[:, 0:2] = 0.0
        out[lo: hi + 1] = np.nan_to_num(sd)
        return out

    def at_thrust_stop(self, x, P):
        """State and covariance at a thrust stop, as the filter treats a logged one (where
        ``dp_active`` goes 1 -> 0) with these settings; for "a blackout now" (drift-off live mode).

        By default nothing changes: the filter carries on, and the drift samples correct the
        environment. With ``reset_yaw_load_at_stop`` (:data:`PER_DOF`) the yaw environment's
        estimate restarts: under station keeping the yaw offset is the small difference of
        large thruster moments, so the yaw load's estimate is tied to the thrust error by a
        correlation that no longer applies once the thrusters stop. The total environmental yaw moment
        (current through the hull plus load) then keeps the fraction ``yaw_load_kept_at_stop`` of
        its station-keeping value (none by default: with the per-DOF thrust error the yaw load
        holds much of the thrusters' error); its correlations are cut and its variance becomes
        the prior's plus the square of the part not kept (or ``yaw_load_std_at_stop``), so
        the drift samples identify it. The
        current keeps acting through the hull as the ship starts to move. With
        ``load_to_current_at_stop`` part of the load then becomes a current
        (:func:`hybridship.residual.environment_kernel.load_to_current_at_stop`), and with
        ``current_std_at_stop_m_s`` the current's uncertainty is widened along the
        current-load ridge (:func:`hybridship.residual.environment_kernel.current_ridge_at_stop`),
        as the filter does at a stop.

        Parameters
        ----------
        x : array, shape (n,)
            State mean in the order of :attr:`state_names` (``n`` entries; SI, radians).
        P : array, shape (n, n)
            Its covariance.

        Returns
        -------
        x, P : ndarray
            New arrays (the caller's are not changed).
        """
        c = self.config
        n = len(self.state_names)
        x, P = np.array(real_array("x", x)), np.array(real_array("P", P))
        if x.shape != (n,) or P.shape != (n, n):
            raise ValueError(f"x, P: expected shapes ({n},) and ({n}, {n}) (the state of state_names), "
                             f"got {x.shape} and {P.shape}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(P))):
            raise ValueError("x, P: must be finite (no NaN or inf)")
        work = kernel._workspace(self.model.arrays)
        if c.reset_yaw_load_at_stop:        # the filter's order at a stop (environment_kernel.filter_grid)
            x, P = kernel.at_thrust_stop(x, P, float(c.yaw_load_kept_at_stop), self._yaw_std_at_stop(),
                                         float(c.load_yaw_prior_rad_s2), self.model.arrays, work)
        if c.load_to_current_at_stop > 0:
            x = kernel.load_to_current_at_stop(x, float(c.load_to_current_at_stop), self.model.arrays, work)
        if c.current_std_at_stop_m_s > 0:
            x, P = kernel.current_ridge_at_stop(x, P, float(c.current_std_at_stop_m_s), self.model.arrays, work)
        return x, P

    def run(self, arrays, rows=None, *, first_row: int = 0, required: int | None = None,
            drift_yaw_uv_rad_per_m2: float = 0.0) -> EnvironmentEstimate:
        """Filter the log from ``first_row`` and return the estimates at ``rows`` (default: all).

        The estimate at row ``i`` uses the samples ``first_row .. i`` only (causal). A gap
        (a new segment) up to ``max_bridged_gap_s`` is predicted across; a longer one
        restarts the motion states from the measurement and keeps the environment states,
        whose uncertainty grows over the gap. On a log sampled faster
        than ``filter_step_s`` the filter steps over every ``m``-th row (commands held over
        the step), on a grid that passes through each requested row; the slow environment
        loses nothing by it and a 10-Hz log costs what a 1-Hz one does.

        Parameters
        ----------
        arrays : LogArrays
            The log (:func:`hybridship.predictors.as_log_arrays` reads a DataFrame or file);
            anything else is a TypeError naming it.
        rows : array of int, optional
            Rows at which to report (sorted or not), in ``[first_row, N - 1]`` (``N`` rows of
            log); all rows >= ``first_row`` by default.
        first_row : int
            Row at which the filter starts (its prior applies there), in ``[0, N - 1]``.
        required : int, optional
            Only the first ``required`` (at most ``len(rows)``) of ``rows`` must have an
            estimate; later rows before
            the first valid position and heading are left out of the result (default: all
            rows are required).
        drift_yaw_uv_rad_per_m2 : float
            The hull's yaw moment in a drift, ``k`` [rad/m^2] (:mod:`.drift_hull`): while the
            thrusters are stopped (``dp_active`` 0) the process model adds the yaw acceleration
            ``k u v``, as the forecasts after a failure do, so that the yaw load does not
            absorb it. 0 (default): none.
        """
        if not (isinstance(drift_yaw_uv_rad_per_m2, numbers.Real) and not isinstance(drift_yaw_uv_rad_per_m2, bool)
                and np.isfinite(drift_yaw_uv_rad_per_m2)):
            raise ValueError(f"drift_yaw_uv_rad_per_m2: expected a finite number [rad/m^2], got "
                             f"{drift_yaw_uv_rad_per_m2!r}")
        if not isinstance(arrays, LogArrays):
            raise TypeError(f"arrays: expected LogArrays (as_log_arrays reads a DataFrame or file), "
                            f"got {type(arrays).__name__}")
        rows, first_row, n_req = _checked_rows(len(arrays.time_s), rows, first_row, required)
        last = int(rows.max()) if rows.size else first_row
        m, _ = self._filter_every(arrays)
        inputs = self._shared_inputs(arrays, first_row, last)
        out_x, out_P = {}, {}
        for c in np.unique(rows % m):       # one pass per grid through the requested rows
            grid = np.arange(first_row + (c - first_row) % m, last + 1, m)
            self._filter(arrays, grid, set(int(r) for r in rows if r % m == c), inputs, out_x, out_P,
                         float(drift_yaw_uv_rad_per_m2))
        miss = [int(r) for r in rows[:n_req] if int(r) not in out_P]
        if miss:
            raise ValueError(f"log: no valid position/heading at or before row {miss[0]} "
                             f"(time {seconds_text(arrays.time_s[miss[0]])} s) to start the environment estimate")
        rows = rows[np.array([int(r) in out_P for r in rows], dtype=bool)] if rows.size > n_req else rows
        k = len(self.state_names)
        return EnvironmentEstimate(rows, arrays.time_s[rows], np.reshape([out_x[int(r)] for r in rows], (-1, k)),
                                   np.reshape([out_P[int(r)] for r in rows], (-1, k, k)),
                                   self.config.thrust_error_model, self.load_map)

    def _log_inputs(self, arrays, first_row: int, last: int) -> dict:
        """Measurements, their noise and the model's inputs at the rows ``first_row .. last`` (zero elsewhere)."""
        n = len(arrays.time_s)
        r_std = np.broadcast_to(self._measurement_std(), (n, 6))
        if self.config.adaptive_measurement_std:
            r_std = np.maximum(r_std, self._wave_motion_std(arrays, first_row, last))
        model = self.model
        sl = slice(first_row, last + 1)     # only the rows the filter reads are converted
        w = last + 1 - first_row

        def rows(a):
            """A window's values (w, ...) placed at their log rows (n, ...); zero elsewhere."""
            out = np.zeros((n,) + a.shape[1:], dtype=a.dtype)
            out[sl] = a
            return out

        nu_ok = np.isfinite(arrays.nu[sl]) & (arrays.nu_logged[sl] if self.config.use_velocity else False)
        # a logged u, v that the track contradicts (a biased speed log) would pull the filtered
        # position off the GNSS: left out, as the start window leaves it out
        nu_ok[:, :2] &= ~(velocity_track_mismatch_m(arrays, TRACK_WINDOW_S, first_row, last)
                          > TRACK_MISMATCH_M)[:, None]
        dp = arrays.dp_active[sl].astype(bool)
        rpm = np.nan_to_num(arrays.rpm[sl])
        # after a failure, commands the log no longer records are not held at their last
        # (station-keeping) rpm: that thrust would push the drift in the process model, and
        # the load would take up its difference, while the forecasts take no thrust there
        rpm[~dp & ~arrays.commands_logged[sl]] = 0.0
        return {
            "z": rows(np.column_stack([arrays.eta[sl], arrays.nu[sl]])),
            "z_ok": rows(np.column_stack([np.isfinite(arrays.eta[sl]), nu_ok])),
            "r_std": r_std,
            # command channels padded to the model's width once (thrusters, then rudders)
            "rpm": rows(model._channels("rpm", rpm, w, None)[:, 0]),
            "az": rows(model._channels("azimuth_rad", np.nan_to_num(arrays.azimuth_rad[sl]), w, None)[:, 0]),
            "wind": rows(np.nan_to_num(arrays.wind[sl])),
            "dp": rows(dp),
            # while the thrusters run, a row whose commands are not logged holds the last
            # logged ones: its thrust is a guess, from which the environment learns nothing
            "cmd_known": rows(arrays.commands_logged[sl] | ~dp),
            "span": (int(first_row), int(last)),        # what the noise above was measured over
        }

    @contextmanager
    def sharing_station_keeping(self):
        """Within this context, runs over the same log, rows and first row that differ only in
        ``drift_yaw_uv_rad_per_m2`` share the filter up to the failure, where that coefficient
        starts to act: the station keeping is filtered once, and each run goes on from there
        (with the same result as a run of its own). The log and the estimator's settings must
        not change inside the context. Nested, the outermost context decides."""
        if self._shared_runs is not None:
            yield self
            return
        self._shared_runs = {}
        try:
            yield self
        finally:
            self._shared_runs = None

    def _shared(self, key: tuple, arrays, make):
        """``make()``, made once per ``key`` (which holds ``id(arrays)``) inside
        :meth:`sharing_station_keeping`; the log is kept with it, so no other log can take its id."""
        if key not in self._shared_runs:
            self._shared_runs[key] = (arrays, make())
        return self._shared_runs[key][1]

    def _shared_inputs(self, arrays, first_row: int, last: int) -> dict:
        """:meth:`_log_inputs`, made once per log and span inside :meth:`sharing_station_keeping`."""
        if self._shared_runs is None:
            return self._log_inputs(arrays, first_row, last)
        return self._shared(("inputs", id(arrays), int(first_row), int(last)), arrays,
                            lambda: self._log_inputs(arrays, first_row, last))

    def _station_keeping_run(self, arrays, grid, want, inputs) -> tuple[dict, dict, tuple]:
        """The estimates at ``want`` (all at or before the last row of ``grid``) of a run
        without the hull's yaw moment in a drift, and the loop state it ends with (see
        :meth:`_filter_grid`)."""
        x, P = {}, {}
        end = self._filter_grid(arrays, grid, want, inputs, x, P, 0.0)
        return x, P, end

    def _filter(self, arrays, grid, want, inputs, out_x, out_P, drift_yaw_uv: float):
        """Run the filter over the rows ``grid`` (increasing), storing the estimates at ``want``."""
        want = sorted(want)
        stopped = np.flatnonzero(~inputs["dp"][grid]) if drift_yaw_uv != 0.0 and self._shared_runs is not None \
            else np.zeros(0, dtype=int)
        if stopped.size == 0:
            self._filter_grid(arrays, grid, want, inputs, out_x, out_P, drift_yaw_uv)
            return
        # the coefficient acts from the first step out of a stopped row on: the estimate at
        # that row b is the same for every coefficient
        branch = int(stopped[0])
        b = int(grid[branch])
        before = [w for w in want if w <= b]
        shared_x, shared_P, end = self._shared(
            (id(arrays), inputs["span"], int(grid[0]), int(grid[-1]), b, tuple(before)), arrays,
            lambda: self._station_keeping_run(arrays, grid[:branch + 1], sorted(set(before) | {b}), inputs))
        if b not in shared_x:           # the filter could not start before b: nothing to share
            self._filter_grid(arrays, grid, want, inputs, out_x, out_P, drift_yaw_uv)
            return
        for w in before:
            if w in shared_x:
                out_x[w], out_P[w] = shared_x[w], shared_P[w]
        self._filter_grid(arrays, grid[branch:], [w for w in want if w > b], inputs, out_x, out_P, drift_yaw_uv,
                          resume=(shared_x[b], shared_P[b], *end))

    def _filter_every(self, arrays) -> tuple[int, float]:
        """``(m, dt_log)``: the filter steps over every ``m``-th row of a log whose step is
        ``dt_log`` [s] (the median spacing), ``m`` the whole log steps nearest ``filter_step_s``."""
        dt_log = float(np.median(np.diff(arrays.time_s))) if len(arrays.time_s) > 1 else 1.0
        return max(1, int(round(self.config.filter_step_s / dt_log))), dt_log

    def _filter_grid(self, arrays, grid, want, inputs, out_x, out_P, drift_yaw_uv: float, resume=None) -> tuple:
        """One run of the compiled filter over ``grid`` (from the estimate, settling time and
        outlier gate's state ``resume = (x, P, settle_until_s, gate_state)`` at ``grid[0]`` when
        given), storing the estimates at the sorted rows ``want``; returns ``(settle_until_s, gate_state)``
        at its last row, what a run resumed there needs."""
        slot = np.full(len(arrays.time_s), -1, dtype=np.int64)
        slot[want] = np.arange(len(want))
        n = len(self.state_names)
        xs, Ps = np.empty((len(want), n)), np.empty((len(want), n, n))
        done = np.zeros(len(want), dtype=np.bool_)
        x_resume, P_resume, settle_until, gate_state = resume if resume is not None else (
            np.zeros(n), np.zeros((n, n)), 0.0, np.zeros((2, 6)))
        settle_io = np.array([settle_until], dtype=float)
        gate_io = np.array(gate_state, dtype=float)
        c = self.config
        kernel.filter_grid(np.ascontiguousarray(grid, dtype=np.int64), slot, arrays.time_s, arrays.segment_id,
                           inputs["z"], inputs["z_ok"], inputs["r_std"], inputs["rpm"], inputs["az"],
                           inputs["wind"], inputs["dp"], inputs["cmd_known"], self.model.arrays,
                           c.thrust_error_model == "per_thruster",
                           np.asarray(self.thrust_error_mean, float),
                           self._prior_sd(_wind_speed_at(arrays, int(grid[0]))), self._process_noise_base(),
                           self._process_noise_base(stopped=True),
                           _FD_STEP,
                           bool(c.reset_yaw_load_at_stop), float(c.yaw_load_kept_at_stop), self._yaw_std_at_stop(),
                           float(c.load_yaw_prior_rad_s2), float(c.current_std_at_stop_m_s),
                           float(c.load_to_current_at_stop), drift_yaw_uv,
                           self._gate(),
                           int(c.max_gated_samples), float(c.settle_s), float(c.max_bridged_gap_s),
                           float(np.prod(self._filter_every(arrays))), resume is not None,
                           np.ascontiguousarray(x_resume, dtype=float), np.ascontiguousarray(P_resume, dtype=float),
                           settle_io, gate_io, xs, Ps, done,
                           np.zeros((0, 3)) if self.load_map is None else self.load_map,
                           load_prior_ne(c, _wind_dir_at(arrays, int(grid[0]))))
        for k, i in enumerate(want):
            if done[k]:
                out_x[i], out_P[i] = xs[k], Ps[k]
        return float(settle_io[0]), gate_io.copy()
