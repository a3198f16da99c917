"""From a log to residual targets and network features (Skulstad et al. 2022, sec. 3.2-3.3).

For each sample ``t`` of a gap-free segment:

* the smoothed velocities ``nu_s(t)`` are a Savitzky-Golay smoothing of the logged ones
  (centred window ``deriv_window_s``); ``nu_dot(t)`` the matching derivative (kept for
  inspection);
* the dynamic model, started from ``(eta(t), nu_s(t))`` with the commands and wind of
  ``t`` held, predicts ``nu_hat(t+1)`` and ``nu_dot_hat(t+1)`` one step ahead;
* the residual target is the acceleration discrepancy averaged over the step,
  ``d_nu_dot(t+1) = (nu_s(t+1) - nu_hat(t+1)) / dt``. The paper differences a measured and a
  predicted acceleration; filtering a second derivative out of noisy 1 Hz data smears
  every command change over the filter window, and the networks then learn the filter.
  The velocity-increment form needs no differentiation, is zero on a log the model
  produced itself, and is exactly the constant acceleration the integrator must add over
  the step to land on the measured velocity;
* the features are chosen from ``nu_hat(t+1)``, ``nu_dot_hat(t+1)`` and the previous residual
  ``d_nu_dot(t)`` (the paper's choice, an ARX form).

Beyond the paper, the residual is split into a slowly varying **bias** ``b(t)``, the causal
mean of past residuals over ``bias_window_s`` (by default a few minutes: the unknown
current and mean wave drift), and a **deviation** ``d_nu_dot - b`` that the networks learn.
Averaging over minutes removes the thruster-model error that a short window of
station-keeping residuals carries, and the bias stays meaningful when the networks'
inputs leave their training envelope. ``bias_frame = "ned"`` keeps the surge/sway part of
the bias fixed in the earth frame (current and waves do not turn with the ship).

Forecasts must use only what is known at their start time. The centred filters above
look a few seconds ahead, so they are used for training targets only. At a forecast start
``t0`` the initial state is the causal 3-sample average of heading and velocities (the
paper's 3-s moving average); the bias and the "previous residual" come from *causal*
residual estimates (end-point Savitzky-Golay smoothing of the velocities, then the same
one-step comparison).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Annotated, Literal

import numpy as np
import pandas as pd
from pydantic import Field, field_validator
from scipy.signal import lfilter, savgol_coeffs, savgol_filter

from ..config import Float, Int, config_dataclass, start_time_rng
from ..forecast_inputs.limits import forecast_substeps
from ..logs.io import LogArrays

#: Optional command-aware features (appended after the paper's nine): the main
#: propeller's rpm over its maximum and its rate [1/s]; the first rotatable actuator's
#: angle (rudder or azimuth, wrapped to [-pi, pi)) [rad] and its rate [rad/s]; the ship's
#: velocity through the air in body axes (Fossen's ``u_rw, v_rw``, from the model-predicted
#: velocities and the wind of the step: logged in training, forecast in a rollout) [m/s];
#: the drift angle ``atan2(v_hat, |u_hat|)`` [rad].
#: The commands are those of the step being predicted, the rates their change over it.
COMMAND_FEATURES = ("rpm_main_rel", "rpm_main_rate_rel_s", "angle_main_rad", "angle_main_rate_rad_s",
                    "wind_rel_u_m_s", "wind_rel_v_m_s", "drift_angle_rad")

#: Optional command-memory features: how the main propeller's rpm (over its maximum) and
#: the first rotatable actuator's angle [rad] have moved over the last
#: ``ResidualConfig.command_memory_s``, as the first-order low-pass of the command minus the
#: command (zero for a command held that long). The state tells the nets how the ship
#: moves, not how long a command has acted on it (the rudder's history in a zigzag); the
#: commands are those of the step being predicted, as for :data:`COMMAND_FEATURES`.
MEMORY_FEATURES = ("rpm_main_memory_rel", "angle_main_memory_rad")

#: Optional actuator-load features: the actuators' share of the model-predicted
#: acceleration, ``M^-1 tau_thrust`` (propellers, thrusters and rudders; Fossen's ``tau``
#: through the inverse of ``M = M_RB + M_A``), at the model-predicted velocities with the
#: commands of the step being predicted [m/s^2, m/s^2, rad/s^2], without a current (as the
#: training rows, which do not know one, compute them; a forecast with the environment
#: estimator's current computes them so too). The physics' rudder and
#: propeller laws then reach the nets as inputs, so a scale error of those laws (a rudder
#: moment too strong at model scale) is a near-linear function of them; the other
#: features would have to rebuild the laws' nonlinearity from speed, rpm and angle.
LOAD_FEATURES = ("actuator_u_dot_hat_m_s2", "actuator_v_dot_hat_m_s2", "actuator_r_dot_hat_rad_s2")

#: Longest time constant of the command memory [s]: a third of the log a forecast reads
#: before its start (:data:`hybridship.predictors.forecast_setup.FORECAST_HISTORY_S`).
MAX_COMMAND_MEMORY_S = 600.0

#: Time constants of the command memory that a forecast reads before its earliest start (at
#: least): the memory starts at the first row read, and that start is then forgotten
#: (``exp(-20)``, 2e-9 of it left), as training's memory, run from the log's first row, has
#: forgotten it. Three time constants (1800 s of a 600-s memory) left 5 % of it, so a start's
#: memory depended on the other starts of its call.
MEMORY_HISTORY_TIME_CONSTANTS = 20.0

#: Every feature the hybrid can use, in a fixed order. ``_hat`` = model one-step prediction.
ALL_FEATURES = ("u_hat_m_s", "v_hat_m_s", "r_hat_rad_s",
                "u_dot_hat_m_s2", "v_dot_hat_m_s2", "r_dot_hat_rad_s2",
                "res_u_prev_m_s2", "res_v_prev_m_s2", "res_r_prev_rad_s2") + COMMAND_FEATURES + MEMORY_FEATURES \
    + LOAD_FEATURES

#: The paper's feature set (sec. 3.3): model-predicted velocities and accelerations plus
#: the previous residual.
PAPER_FEATURES = ALL_FEATURES[:9]

#: Residual target names (body-frame acceleration discrepancy).
TARGETS = ("res_u_m_s2", "res_v_m_s2", "res_r_rad_s2")


@config_dataclass(frozen=True)
class ResidualConfig:
    """How logs become residual targets and features (recorded in the model file).

    Attributes
    ----------
    features : tuple of str
        Names from :data:`ALL_FEATURES`, at least one, each at most once.
    deriv_window_s : float
        Savitzky-Golay window for smoothing the velocities [s]; 0 uses the logged
        velocities as they are (unbiased under white noise, and exact on a model-made log).
    polyorder : int
        Savitzky-Golay polynomial order.
    start_average_s : float
        Causal moving-average window of heading and velocities at a start [s].
    start_residual_window_s : float
        Window of the causal residual average that starts the
        autoregressive input [s]; 0 starts it at zero deviation (the bias already holds the
        recent mean, and a short window at a failure mixes in the thrusters' run-down). Used
        with the mean-residual environment only; a hybrid with the environment estimator
        refuses a value above 0.
    bias_window_s : float
        Window of the causal residual mean used as the bias [s]; 0 = no bias
        (the paper's scheme).
    bias_frame : {"ned", "body"}
        The frame in which the bias is held constant.
    bias_block_s : float
        Length of the residual blocks whose means spread the ensemble members'
        biases [s] (the forecast horizon is a good choice: the spread then reflects how much
        a one-minute mean of the unknown force varies around the long mean).
    residual_step_s : float or None
        Step of the one-step residual fit [s]: a training log sampled faster is thinned to
        every ``round(residual_step_s / dt)``-th row before its residual targets and features
        are formed (forecasts still run at the log's own step). A residual is a velocity
        difference over one step divided by that step, so its noise grows as the step
        shrinks; at 10 Hz the nets of the paper's features, which include the previous
        residual, then learned that noise and made station-keeping forecasts worse than the
        nets off. None: the log's own step (the manoeuvre benchmark's choice, with smoothed
        targets and multi-step training).
    command_memory_s : float
        Time constant of the low-pass behind :data:`MEMORY_FEATURES` [s], at most
        ``MAX_COMMAND_MEMORY_S`` (a forecast starts the memory at the first row it reads, at
        least ``FORECAST_HISTORY_S`` and ``MEMORY_HISTORY_TIME_CONSTANTS`` time constants
        before its earliest start, so that start is forgotten).
    """

    features: tuple[str, ...] = PAPER_FEATURES
    deriv_window_s: Annotated[Float, Field(ge=0)] = 0.0
    polyorder: Annotated[Int, Field(ge=1)] = 2
    start_average_s: Annotated[Float, Field(gt=0)] = 3.0
    start_residual_window_s: Annotated[Float, Field(ge=0)] = 0.0
    bias_window_s: Annotated[Float, Field(ge=0)] = 900.0
    bias_frame: Literal["ned", "body"] = "ned"
    bias_block_s: Annotated[Float, Field(gt=0)] = 60.0
    command_memory_s: Annotated[Float, Field(gt=0, le=MAX_COMMAND_MEMORY_S)] = 10.0
    residual_step_s: Annotated[Float, Field(gt=0)] | None = 1.0

    @field_validator("features")
    @classmethod
    def _known_features(cls, v):
        unknown = [f for f in v if f not in ALL_FEATURES]
        if not v:
            raise ValueError(f"expected at least one of {list(ALL_FEATURES)}")
        if unknown:
            raise ValueError(f"unknown {unknown}; choose from {list(ALL_FEATURES)}")
        twice = [f for i, f in enumerate(v) if f in v[:i]]
        if twice:       # a second, identical input of the nets
            raise ValueError(f"each at most once, got {twice[0]!r} more than once")
        return v

    @property
    def feature_index(self) -> np.ndarray:
        return np.array([ALL_FEATURES.index(f) for f in self.features])

    def thinning(self, dt_s: float) -> int:
        """Every how many rows a training log of step ``dt_s`` [s] is read for the one-step
        residual fit (``residual_step_s``; 1 for a log at or slower than it)."""
        if self.residual_step_s is None or not dt_s > 0:
            return 1
        return max(1, int(round(self.residual_step_s / dt_s)))

    @property
    def uses_command_features(self) -> bool:
        """Whether any feature of :data:`COMMAND_FEATURES` is selected."""
        return any(f in COMMAND_FEATURES for f in self.features)

    @property
    def uses_memory_features(self) -> bool:
        """Whether any feature of :data:`MEMORY_FEATURES` is selected."""
        return any(f in MEMORY_FEATURES for f in self.features)

    @property
    def uses_load_features(self) -> bool:
        """Whether any feature of :data:`LOAD_FEATURES` is selected."""
        return any(f in LOAD_FEATURES for f in self.features)


def command_feature_columns(nu_hat, psi_rad, rpm, rpm_prev, az, az_prev, wind, dt_s: float,
                            rpm_scale: float, angle_channel: int | None, lib=np):
    """The :data:`COMMAND_FEATURES` columns, shape (..., 7).

    ``nu_hat`` (..., 3) and ``psi_rad`` (...) may be torch tensors (``lib=torch``); the
    commands ``rpm``/``rpm_prev`` (..., K), ``az``/``az_prev`` (..., K) and ``wind``
    (..., 2: speed [m/s], direction it blows from [rad]) are numpy arrays.
    ``angle_channel`` is the command channel of the first rotatable actuator (None: none).
    """
    def wrap(a):
        return (a + np.pi) % (2 * np.pi) - np.pi

    rpm_rel = rpm[..., 0] / rpm_scale
    rpm_rate = (rpm[..., 0] - rpm_prev[..., 0]) / (rpm_scale * dt_s)
    if angle_channel is None:
        ang = np.zeros_like(rpm_rel)
        ang_rate = np.zeros_like(rpm_rel)
    else:
        ang = wrap(az[..., angle_channel])
        ang_rate = wrap(az[..., angle_channel] - az_prev[..., angle_channel]) / dt_s
    cmd = np.stack([rpm_rel, rpm_rate, ang, ang_rate], axis=-1)
    if lib is np:
        d = wind[..., 1] - psi_rad
        urw = nu_hat[..., 0] + wind[..., 0] * np.cos(d)
        vrw = nu_hat[..., 1] + wind[..., 0] * np.sin(d)
        drift = np.arctan2(nu_hat[..., 1], np.abs(nu_hat[..., 0]))
        return np.concatenate([cmd, np.stack([urw, vrw, drift], axis=-1)], axis=-1)
    t = lib.as_tensor
    d = t(wind[..., 1], dtype=nu_hat.dtype) - psi_rad
    V = t(wind[..., 0], dtype=nu_hat.dtype)
    urw = nu_hat[..., 0] + V * lib.cos(d)
    vrw = nu_hat[..., 1] + V * lib.sin(d)
    drift = lib.atan2(nu_hat[..., 1], lib.abs(nu_hat[..., 0]))
    return lib.cat([t(cmd, dtype=nu_hat.dtype), lib.stack([urw, vrw, drift], dim=-1)], dim=-1)


def command_memory(commands: np.ndarray, previous: np.ndarray, memory0: np.ndarray, dt_s: float,
                   time_constant_s: float) -> np.ndarray:
    """The :data:`MEMORY_FEATURES` over steps: low-passed commands minus the commands.

    With ``y`` the first-order low-pass of a command ``x`` (time constant ``T``, exact for a
    command held over each step), the memory ``m = y - x`` obeys
    ``m_j = exp(-dt / T) (m_{j-1} - (x_j - x_{j-1}))``: a command that steps by ``dx`` leaves
    ``-dx exp(-t / T)``. ``m_j`` is the low-pass at the end of step ``j`` (the command ``x_j``
    held over it) minus ``x_j``: the memory of the step being predicted. Angle increments are
    wrapped to [-pi, pi), so an azimuth that turns through 180 deg is one small step, not a
    jump.

    Parameters
    ----------
    commands : ndarray, shape (S, n, 2)
        ``[rpm / max rpm, angle_rad]`` of steps ``0 .. n-1``.
    previous : ndarray, shape (S, 2)
        The commands of the step before step 0.
    memory0 : ndarray, shape (S, 2)
        The memory at the step before step 0 (zeros: held long enough).
    dt_s, time_constant_s : float
        Step and low-pass time constant [s].

    Returns
    -------
    ndarray, shape (S, n, 2)
    """
    dx = np.diff(np.concatenate([np.asarray(previous, dtype=float)[:, None], commands], axis=1), axis=1)
    dx[..., 1] = (dx[..., 1] + np.pi) % (2 * np.pi) - np.pi
    c = np.exp(-dt_s / time_constant_s)
    # m_j = c m_{j-1} - c dx_j: one first-order recursion along the steps, from memory0
    return lfilter([-c], [1.0, -c], dx, axis=1, zi=(c * np.asarray(memory0, dtype=float))[:, None, :])[0]


def command_pair(rpm: np.ndarray, azimuth_rad: np.ndarray, rpm_scale: float, angle_channel: int | None) -> np.ndarray:
    """``[rpm / max rpm, angle_rad]`` (..., 2) of commands ``rpm`` [rpm] and ``azimuth_rad``
    [rad] (..., K): the main thruster's and the first rotatable actuator's (0 without one),
    the commands the :data:`MEMORY_FEATURES` remember."""
    rpm = np.asarray(rpm, dtype=float)
    out = np.zeros(rpm.shape[:-1] + (2,))
    out[..., 0] = rpm[..., 0] / rpm_scale
    if angle_channel is not None:
        out[..., 1] = np.asarray(azimuth_rad, dtype=float)[..., angle_channel]
    return out


def log_command_memory(arrays: LogArrays, dt_s: float, time_constant_s: float, rpm_scale: float,
                       angle_channel: int | None, stop_after_failure: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The :data:`MEMORY_FEATURES` at every row of a log (N, 2), row by row with its own
    commands: zero at the first row of each segment, a missing command holds the last valid
    one (0 before the first); row ``i`` is the memory of the step from row ``i`` to ``i + 1``.
    With ``stop_after_failure`` the rpm is 0 where station keeping is off (``dp_active == 0``),
    as a forecast takes it. Returns ``(memory, commands)``, the commands as used
    (N, 2: ``[rpm / max rpm, angle_rad]``)."""
    cmd = command_pair(arrays.rpm, arrays.azimuth_rad, rpm_scale, angle_channel)
    if stop_after_failure:
        cmd[arrays.dp_active == 0, 0] = 0.0
    out = np.zeros_like(cmd)
    for sl in arrays.segments:
        cmd[sl] = pd.DataFrame(cmd[sl]).ffill().fillna(0.0).to_numpy()
        out[sl] = command_memory(cmd[None, sl], cmd[sl][:1], np.zeros((1, 2)), dt_s, time_constant_s)[0]
    return out, cmd


def _window(window_s: float, dt_s: float, polyorder: int) -> int:
    w = max(int(round(window_s / dt_s)), polyorder + 2)
    return w + 1 if w % 2 == 0 else w


def _causal_savgol(x: np.ndarray, window: int, polyorder: int, deriv: int, dt_s: float) -> np.ndarray:
    """End-point Savitzky-Golay value/derivative using only past samples (shorter at the start)."""
    out = np.empty_like(x)
    n = x.shape[0]
    w = min(window, n)
    if w > polyorder:
        c = savgol_coeffs(w, polyorder, deriv=deriv, delta=dt_s, pos=w - 1, use="dot")
        # out[i] = sum_k c[k] x[i - w + 1 + k]: a correlation over the trailing window
        windows = np.lib.stride_tricks.sliding_window_view(x, w, axis=0)  # (n - w + 1, ..., w)
        out[w - 1:] = np.einsum("i...k,k->i...", windows, c)
        head = range(0, w - 1)
    else:
        head = range(0, n)
    for i in head:  # the first few samples: a shorter trailing window, or a difference
        m = i + 1
        if m > polyorder + 1:
            c = savgol_coeffs(m if m % 2 else m, polyorder, deriv=deriv, delta=dt_s, pos=m - 1, use="dot")
            out[i] = np.tensordot(c, x[:m], axes=(0, 0))
        elif deriv == 0:
            out[i] = x[i]
        else:
            out[i] = (x[i] - x[i - 1]) / dt_s if i > 0 else 0.0
    return out


@dataclass
class PreparedLog:
    """A log with smoothed states, one-step model predictions and residuals (arrays, SI).

    All arrays have N rows (one per sample). Row ``i`` of ``nu_hat``/``nu_dot_hat`` is the
    model's prediction FOR sample ``i`` made from sample ``i - 1`` (NaN where ``i - 1`` is
    in another segment or does not exist); ``residual[i] = (nu_s[i] - nu_hat[i]) / dt`` [m/s^2,
    m/s^2, rad/s^2], the acceleration the model did not explain over the step into row ``i``.
    The ``_c`` arrays are the causal counterparts used at forecast starts.
    ``env_body``, when set, is the environment estimator's acceleration at each row (body
    frame), which then replaces the bias in :meth:`deviation`.
    ``thrust_acc[i]`` is ``M^-1 tau_thrust`` [m/s^2, m/s^2, rad/s^2] at the state and
    commands of row ``i - 1`` (the thrusters' share of the model's acceleration; the guard
    uses it to tell the thruster regime of the training data from that of a forecast).
    ``actuator_hat[i]``, when the config selects :data:`LOAD_FEATURES`, is the same share at
    the predicted velocities ``nu_hat[i]`` with the commands of row ``i - 1``.
    """

    arrays: LogArrays
    dt_s: float
    nu_s: np.ndarray
    nu_dot: np.ndarray
    nu_hat: np.ndarray
    nu_dot_hat: np.ndarray
    residual: np.ndarray
    nu_c: np.ndarray
    residual_c: np.ndarray
    bias_ned: np.ndarray
    thrust_acc: np.ndarray
    config: ResidualConfig = field(default_factory=ResidualConfig)
    env_body: np.ndarray | None = None
    rpm_scale: float = 1.0
    angle_channel: int | None = None
    command_memory: np.ndarray | None = None
    actuator_hat: np.ndarray | None = None

    def bias_body(self, rows: np.ndarray, psi_rad=None) -> np.ndarray:
        """The bias known at ``rows`` (from data up to and including them) in the body frame.

        ``bias_ned`` stores surge/sway in NED (and yaw as is); ``psi_rad`` is the heading to
        rotate into (default: the logged heading at ``rows``; the body-frame option uses the
        heading at which each residual was observed).
        """
        rows = np.asarray(rows)
        b = self.bias_ned[rows]
        psi = self.arrays.eta[rows, 2] if psi_rad is None else np.asarray(psi_rad)
        c, s = np.cos(psi), np.sin(psi)
        out = b.copy()
        out[..., 0] = c * b[..., 0] + s * b[..., 1]
        out[..., 1] = -s * b[..., 0] + c * b[..., 1]
        return out

    def deviation(self, rows: np.ndarray) -> np.ndarray:
        """Residual minus the environment known one sample earlier, at ``rows``.

        The environment is ``env_body[rows - 1]`` when set (the environment estimator's
        acceleration, body frame), else the bias known one sample earlier.
        """
        rows = np.asarray(rows)
        if self.env_body is not None:
            return self.residual[rows] - self.env_body[rows - 1]
        return self.residual[rows] - self.bias_body(rows - 1, self.arrays.eta[rows, 2])

    def features(self, rows: np.ndarray) -> np.ndarray:
        """Feature matrix (len(rows), n_features) for predicting the residual deviation at ``rows``."""
        return self.full_features(rows)[:, self.config.feature_index]

    def full_features(self, rows: np.ndarray) -> np.ndarray:
        """Every feature of :data:`ALL_FEATURES` (len(rows), len(ALL_FEATURES)) at ``rows``; the
        command-aware ones are zeros unless the config selects one of them."""
        rows = np.asarray(rows)
        parts = [self.nu_hat[rows], self.nu_dot_hat[rows], self.deviation(rows - 1)]
        if self.config.uses_command_features:
            a = self.arrays
            # row i is predicted from row i - 1 with the commands of i - 1; their rate over (i - 2, i - 1)
            parts.append(command_feature_columns(self.nu_hat[rows], a.eta[rows - 1, 2], a.rpm[rows - 1],
                                                 a.rpm[rows - 2], a.azimuth_rad[rows - 1], a.azimuth_rad[rows - 2],
                                                 a.wind[rows - 1], self.dt_s, self.rpm_scale, self.angle_channel))
        else:
            parts.append(np.zeros((rows.size, len(COMMAND_FEATURES))))
        if self.config.uses_memory_features:
            parts.append(self.command_memory[rows - 1])
        else:
            parts.append(np.zeros((rows.size, len(MEMORY_FEATURES))))
        if self.config.uses_load_features:
            parts.append(self.actuator_hat[rows])
        else:
            parts.append(np.zeros((rows.size, len(LOAD_FEATURES))))
        return np.concatenate(parts, axis=1)

    def trainable_rows(self, mask: np.ndarray | None = None) -> np.ndarray:
        """Rows i whose target and features are all defined (i - 1 and i - 2 in i's segment),
        with every command logged at i, i - 1 and i - 2 (the target is the step from i - 1, the
        previous residual the step from i - 2, the command rate is over the two; before a
        command's first logged value the arrays hold a stopped thruster or a centred rudder,
        which the ship did not have)."""
        logged = self.arrays.commands_logged
        ok = np.isfinite(self.residual).all(1) & np.isfinite(self.thrust_acc).all(1) & logged
        ok[1:] &= ok[:-1]
        ok[0] = False
        ok[2:] &= logged[:-2]
        okb = np.isfinite(self.bias_ned if self.env_body is None else self.env_body).all(1)
        ok[2:] &= okb[1:-1] & okb[:-2]
        ok[:2] = False
        if mask is not None:
            ok &= mask
            ok[1:] &= mask[:-1]
        return np.flatnonzero(ok)

    def bias_members(self, idx: int, n_members: int, seed: int = 0) -> np.ndarray:
        """Per-member biases (n_members, 3; surge/sway in NED) at row ``idx``.

        Member ``k`` adds to the bias the difference between the mean residual over one
        randomly drawn ``bias_block_s`` block of the bias window and the mean over all
        drawn blocks: the members' spread is the variability of a block-long mean of the
        unknown force, which the one-minute forecast inherits. Zeros offsets when the
        window holds less than two blocks. Deterministic for a given ``seed`` and start
        time (the draws are keyed by the row's time, not its index: a forecast reads a
        window of the log that depends on its earliest start, and a start's members must
        not depend on the other starts of the batch).
        """
        bias = self.bias_ned[idx] if np.isfinite(self.bias_ned[idx]).all() else np.zeros(3)
        out = np.broadcast_to(bias, (n_members, 3)).copy()
        if self.config.bias_window_s == 0 or n_members < 2:
            return out
        a = self.arrays
        seg0 = int(np.flatnonzero(a.segment_id == a.segment_id[idx])[0])
        w = max(1, int(round(self.config.bias_window_s / self.dt_s)))
        lo = max(seg0, idx - w + 1)
        vals, use = _residual_ned(self.residual_c, a)
        v = vals[lo: idx + 1][use[lo: idx + 1]]
        nb = max(1, int(round(self.config.bias_block_s / self.dt_s)))
        if v.shape[0] < 2 * nb:
            return out
        rng = start_time_rng(seed, a.time_s[idx])
        starts = rng.integers(0, v.shape[0] - nb + 1, size=n_members)
        cs = np.vstack([np.zeros((1, 3)), np.cumsum(v, axis=0)])
        means = (cs[starts + nb] - cs[starts]) / nb
        return out + means - means.mean(axis=0)

    def start_state(self, idx: int):
        """Causal start state at row ``idx``: ``(eta0 (3,), nu0 (3,), deviation0 (3,), bias_ned0 (3,))``.

        Heading and velocities: mean over the last ``start_average_s`` (the paper's 3-s
        window), the rows ``t0 - start_average_s < time_s <= t0`` with half a sample of slack,
        as a forecast's start window takes them
        (:func:`hybridship.forecast_inputs.assess_start_window`); position: the sample at
        ``idx``; deviation: mean causal residual over the last ``start_residual_window_s`` (of
        the steps whose commands were logged) minus the bias known one sample earlier, turned
        with the heading at ``idx``, as :meth:`deviation` gives a training row's previous
        residual (the bias at ``idx`` on the first row of a segment; zeros if no residual is
        available); bias: the causal bias at ``idx`` (surge/sway in NED, yaw as is).
        """
        a = self.arrays
        seg = a.segment_id
        n_res = max(1, int(round(self.config.start_residual_window_s / self.dt_s)))
        # the forecast's start window by time (round(3 / 1.2) = 2 rows were 3 rows there)
        lo = min(int(np.searchsorted(a.time_s, a.time_s[idx] - self.config.start_average_s + 0.5 * self.dt_s,
                                     side="left")), idx)
        lo_seg = int(np.flatnonzero(seg == seg[idx])[0])
        lo = max(lo, lo_seg)
        eta0 = a.eta[idx].copy()
        eta0[2] = a.eta[lo: idx + 1, 2].mean()
        nu0 = a.nu[lo: idx + 1].mean(axis=0)
        lo_r = max(idx - n_res + 1, lo_seg)
        r = self.residual_c[lo_r: idx + 1] if self.config.start_residual_window_s > 0 else np.zeros((0, 3))
        # a residual counts when its step's commands (the row before) were logged, as in the bias
        step_logged = a.commands_logged[np.maximum(np.arange(lo_r, lo_r + r.shape[0]) - 1, 0)]
        r = r[np.isfinite(r).all(1) & step_logged]
        bias0 = self.bias_ned[idx] if np.isfinite(self.bias_ned[idx]).all() else np.zeros(3)
        res0 = r.mean(axis=0) if r.size else None
        # the bias before the last residual, as the nets' previous residual is taken in training (it was
        # the bias at idx, which holds that residual: half the deviation two rows into a segment)
        before = self.bias_ned[idx - 1] if idx > lo_seg and np.isfinite(self.bias_ned[idx - 1]).all() else bias0
        c, s = np.cos(a.eta[idx, 2]), np.sin(a.eta[idx, 2])
        bias_b = np.array([c * before[0] + s * before[1], -s * before[0] + c * before[1], before[2]])
        dev0 = res0 - bias_b if res0 is not None else np.zeros(3)
        return eta0, nu0, dev0, bias0


def _finite_runs(x: np.ndarray, segments) -> list[slice]:
    """The runs of rows of ``x`` (N, k) that are finite in every column, within each segment:
    a missing sample splits the smoothing and the derivative as a gap does, so it leaves
    the other samples' values as they are instead of spoiling its whole segment."""
    ok = np.isfinite(x).all(axis=1)
    runs = []
    for sl in segments:
        m = np.concatenate([[False], ok[sl], [False]])
        edges = np.flatnonzero(np.diff(m.astype(np.int8)))
        runs += [slice(sl.start + int(a), sl.start + int(b)) for a, b in zip(edges[::2], edges[1::2])]
    return runs


def prepare_log(model, arrays: LogArrays, config: ResidualConfig = ResidualConfig()) -> PreparedLog:
    """Smoothed states, measured accelerations, one-step model predictions and residuals.

    Parameters
    ----------
    model : hybridship.physics.model.DynamicModel
        The physics model that makes the one-step predictions.
    arrays : LogArrays
        A validated log (see :func:`hybridship.logs.io.log_to_arrays`).
    config : ResidualConfig
    """
    t = arrays.time_s
    if len(t) < 3:
        raise ValueError(f"log: need at least 3 samples, got {len(t)}")
    dt = float(np.median(np.diff(t)))
    N = len(t)
    nu_s = np.full((N, 3), np.nan)
    nu_dot = np.full((N, 3), np.nan)
    nu_c = np.full((N, 3), np.nan)
    for sl in _finite_runs(arrays.nu, arrays.segments):
        x = arrays.nu[sl]
        n = x.shape[0]
        w = _window(max(config.deriv_window_s, 5.0 * dt), dt, config.polyorder)
        if config.deriv_window_s == 0:
            nu_s[sl] = x
            nu_c[sl] = x
            if n >= w:
                nu_dot[sl] = savgol_filter(x, w, config.polyorder, deriv=1, delta=dt, axis=0)
            elif n >= 2:
                nu_dot[sl] = np.gradient(x, dt, axis=0)
            continue
        if n >= w:
            nu_s[sl] = savgol_filter(x, w, config.polyorder, axis=0)
            nu_dot[sl] = savgol_filter(x, w, config.polyorder, deriv=1, delta=dt, axis=0)
        elif n >= 2:
            nu_s[sl] = x
            nu_dot[sl] = np.gradient(x, dt, axis=0)
        nu_c[sl] = _causal_savgol(x, w, config.polyorder, 0, dt)

    # Rows whose state or inputs are missing (a sensor fault in a forecast log) give no
    # prediction: they are integrated from zeros and then masked, never propagated.
    eta_in = np.nan_to_num(arrays.eta)
    rpm_in, az_in, wind_in = (np.nan_to_num(x) for x in (arrays.rpm, arrays.azimuth_rad, arrays.wind))
    inputs_ok = (np.isfinite(arrays.eta).all(1) & np.isfinite(arrays.rpm).all(1)
                 & np.isfinite(arrays.azimuth_rad).all(1) & np.isfinite(arrays.wind).all(1))

    # One-step model predictions from every sample (all samples in one batch).
    def one_step(nu_start):  # -> predictions for row i made from row i - 1
        res = model.rollout(eta_in, np.nan_to_num(nu_start), 1, dt_s=dt, substeps=forecast_substeps(dt),
                            rpm=rpm_in, azimuth_rad=az_in, wind=wind_in)
        nh = np.full((N, 3), np.nan)
        ndh = np.full((N, 3), np.nan)
        same = ((arrays.segment_id[1:] == arrays.segment_id[:-1]) & inputs_ok[:-1]
                & np.isfinite(nu_start[:-1]).all(1))
        nh[1:][same] = res.nu[:-1, 1][same]
        ndh[1:][same] = res.nu_dot[:-1, 1][same]
        return nh, ndh

    # The thrusters' share of the model acceleration, from row i - 1 (stored at row i).
    _, parts, _ = model.acceleration(eta_in, np.nan_to_num(nu_s), rpm=rpm_in,
                                     azimuth_rad=az_in, wind=wind_in, return_parts=True)
    thrust_acc = np.full((N, 3), np.nan)
    same_seg = (arrays.segment_id[1:] == arrays.segment_id[:-1]) & inputs_ok[:-1]
    thrust_acc[1:][same_seg] = actuator_acceleration(model.arrays, parts)[:-1][same_seg]

    nu_hat, nu_dot_hat = one_step(nu_s)
    actuator_hat = None
    if config.uses_load_features:       # at the predicted velocities of row i, commands of row i - 1
        _, parts_hat, _ = model.acceleration(eta_in[:-1], np.nan_to_num(nu_hat[1:]), rpm=rpm_in[:-1],
                                             azimuth_rad=az_in[:-1], wind=wind_in[:-1], return_parts=True)
        actuator_hat = np.full((N, 3), np.nan)
        ok = np.isfinite(nu_hat[1:]).all(1)
        actuator_hat[1:][ok] = actuator_acceleration(model.arrays, parts_hat)[ok]
    nu_hat_c, _ = one_step(nu_c)
    residual = (nu_s - nu_hat) / dt
    residual_c = (nu_c - nu_hat_c) / dt
    scales = command_scales(model, arrays.rotatable)
    memory = (log_command_memory(arrays, dt, config.command_memory_s, **scales)[0]
              if config.uses_memory_features else None)
    return PreparedLog(arrays=arrays, dt_s=dt, nu_s=nu_s, nu_dot=nu_dot, nu_hat=nu_hat, nu_dot_hat=nu_dot_hat,
                       residual=residual, nu_c=nu_c, residual_c=residual_c,
                       bias_ned=causal_bias(residual_c, arrays, dt, config), thrust_acc=thrust_acc,
                       config=config, command_memory=memory, actuator_hat=actuator_hat, **scales)


def actuator_acceleration(model_arrays, parts):
    """The actuators' share ``M^-1 tau_thrust`` (..., 3) [m/s^2, m/s^2, rad/s^2] of the loads
    ``parts`` (..., 4, 3) in the order of :data:`hybridship.physics.model.TAU_PARTS`."""
    return parts[..., 1, :] @ model_arrays.m_inv.T


def command_scales(model, rotatable) -> dict:
    """``rpm_scale`` (the first thruster's max rpm) and ``angle_channel`` (the first rotatable
    command channel, or None) for :func:`command_feature_columns`."""
    thr = model.vessel.thrusters
    rpm_scale = float(thr[0].max_rpm) if thr and thr[0].max_rpm > 0 else 1.0
    rot = np.flatnonzero(np.asarray(rotatable, dtype=bool))
    return {"rpm_scale": rpm_scale, "angle_channel": int(rot[0]) if rot.size else None}


def _residual_ned(residual_c: np.ndarray, arrays: LogArrays):
    """Causal residuals with surge/sway rotated to NED, and the rows the bias may use: finite,
    in station keeping, and with every command logged at the row before (the step's commands;
    before a command's first logged value the arrays hold a stopped thruster or a centred
    rudder, whose residual is not the environment's)."""
    psi = arrays.eta[:, 2]
    c, s = np.cos(psi), np.sin(psi)
    r = residual_c
    vals = np.column_stack([c * r[:, 0] - s * r[:, 1], s * r[:, 0] + c * r[:, 1], r[:, 2]])
    use = np.isfinite(vals).all(1) & arrays.dp_active.astype(bool)
    use[1:] &= arrays.commands_logged[:-1]
    return vals, use


def causal_bias(residual_c: np.ndarray, arrays: LogArrays, dt_s: float, config: ResidualConfig) -> np.ndarray:
    """Trailing mean of causal residuals over ``bias_window_s``, per segment (N, 3).

    Surge/sway are averaged in NED when ``bias_frame == "ned"`` (rotated with the heading
    at which each residual was seen) and in the body frame otherwise; in both cases the
    result is stored with surge/sway in NED so that it can be rotated into any heading.
    Rows with no earlier finite residual in their segment are NaN. Only DP rows count
    when the log has them before (a failure does not change the environment estimate
    for a while, so the bias is frozen at its last station-keeping value), and only rows
    whose step's commands were logged (:func:`_residual_ned`).
    """
    N = residual_c.shape[0]
    out = np.full((N, 3), np.nan)
    if config.bias_window_s == 0:
        out[:] = 0.0
        return out
    psi = arrays.eta[:, 2]
    c, s = np.cos(psi), np.sin(psi)
    vals, use = _residual_ned(residual_c, arrays)
    if config.bias_frame == "body":
        vals = residual_c.copy()
    w = max(1, int(round(config.bias_window_s / dt_s)))
    for sl in arrays.segments:
        v = np.where(use[sl, None], vals[sl], 0.0)
        n = use[sl].astype(float)
        cv = np.cumsum(v, axis=0)
        cn = np.cumsum(n)
        lo_v = np.zeros_like(cv)
        lo_n = np.zeros_like(cn)
        if len(cn) > w:  # subtract the cumulative sums from w rows back: a trailing window
            lo_v = np.vstack([np.zeros((w, 3)), cv[:-w]])
            lo_n = np.concatenate([np.zeros(w), cn[:-w]])
        cnt = cn - lo_n
        mean = (cv - lo_v) / np.where(cnt > 0, cnt, np.nan)[:, None]
        # After station keeping ends, keep the last station-keeping estimate.
        seg_use = use[sl]
        last = np.maximum.accumulate(np.where(seg_use, np.arange(len(cnt)), -1))
        held = np.where(last[:, None] >= 0, mean[np.maximum(last, 0)], np.nan)
        if config.bias_frame == "body":
            # stored in NED: rotate the body-frame mean with the heading of its row
            hb = held.copy()
            cc, ss = c[sl], s[sl]
            hb[:, 0] = cc * held[:, 0] - ss * held[:, 1]
            hb[:, 1] = ss * held[:, 0] + cc * held[:, 1]
            held = hb
        out[sl] = held
    return out
