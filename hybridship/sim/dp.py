"""Dynamic-positioning (DP) controller: third-order reference model and nonlinear PID.

Reference model (Fossen 2021, sec. 12.1.1): the set-point ``r`` is low-pass filtered, per
DOF in NED, by a critically damped (``zeta_ref = 1`` by default) third-order filter

.. math::

    \\eta_d^{(3)} + (2\\zeta + 1)\\omega\\,\\ddot\\eta_d + (2\\zeta + 1)\\omega^2\\dot\\eta_d
        + \\omega^3 \\eta_d = \\omega^3 r

whose velocity state is saturated (``max_speed_m_s``, ``max_yaw_rate_rad_s``) so that big
set-point changes are approached at a constant speed. The heading reference takes the
shortest way round (``wrap_pi``).

Control law (Fossen 2021, sec. 12.2, nonlinear PID in the body frame):

.. math::

    \\tau = -R(\\psi)^T\\left(K_p^n \\tilde\\eta + K_d^n \\dot{\\tilde\\eta}
        + K_i^n \\int \\tilde\\eta\\,dt\\right) + \\tau_{ff}

with ``eta~ = eta - eta_d`` (heading error wrapped), ``eta~_dot = R nu - eta_d_dot`` and the
NED gains ``K^n = R K R^T`` of body-frame gains ``K``. The body-frame gains place the poles
of ``M x'' + K_d x' + K_p x = 0`` at ``omega_n``, ``zeta`` per DOF (``M = M_RB + M_A``; the
small low-speed hull damping is left out, it only adds damping):

* ``K_p = M diag(omega_n^2)``, ``K_d = M diag(2 zeta omega_n)``,
* ``K_i = K_p diag(omega_n / 10)`` (Fossen's rule of thumb, ``ki_ratio = 0.1``).

The integral is kept as a NED force so that it holds a fixed environmental load while the
vessel turns; it is clamped (anti-windup) in the body frame to ``integral_limit`` (default:
the pure surge, sway and yaw capacity of the thrusters, :func:`.allocation.thrust_capacity`).

Feed-forward ``tau_ff``: the reference acceleration ``M R^T eta_d_ddot`` and, when a wind
measurement is passed to :meth:`DPController.update`, minus the modelled wind load (the
wind kernel of :class:`hybridship.physics.model.DynamicModel`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hybridship.config import check_flags, check_number, config_dataclass, float_array, real_array
from hybridship.frames import ned_to_body, rotation_z, wrap_pi
from hybridship.physics.model import DynamicModel

__all__ = ["DPController", "DPGains", "ReferenceState", "ReferenceModel", "pid_gains"]

#: Largest Euler substep of the reference model [s] (its poles are ~0.05 rad/s).
_REF_SUBSTEP_S = 0.1


def _vec3(name, value, *, positive=False):
    """``value`` broadcast to a finite float (3,) array, or ValueError naming ``name``
    (TypeError for text or anything else that is not real numbers)."""
    a = real_array(name, value)
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,):
        raise ValueError(f"{name}: expected a scalar or shape (3,), got {np.shape(value)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    if positive and np.any(a <= 0):
        raise ValueError(f"{name}: every entry must be > 0, got {a}")
    return a.copy()


_Matrix3 = float_array((3, 3))
_Vector3 = float_array((3,))


@config_dataclass(frozen=True, arbitrary_types=True)
class DPGains:
    """Body-frame PID gain matrices (3x3) [N/m, N s/m, N/(m s); yaw rows in N m per rad].

    Attributes
    ----------
    Kp, Kd, Ki : ndarray, shape (3, 3)
    omega_n_rad_s : ndarray, shape (3,)
        Natural frequencies the gains were placed at [rad/s].
    zeta : ndarray, shape (3,)
        Relative damping.
    """

    Kp: _Matrix3
    Kd: _Matrix3
    Ki: _Matrix3
    omega_n_rad_s: _Vector3
    zeta: _Vector3


def pid_gains(mass_matrix, omega_n_rad_s, zeta, ki_ratio: float = 0.1) -> DPGains:
    """PID gains from the mass matrix by pole placement (see module docstring).

    Parameters
    ----------
    mass_matrix : array_like, shape (3, 3)
        ``M = M_RB + M_A`` [kg, kg, kg m^2].
    omega_n_rad_s, zeta : float or (3,)
        Closed-loop natural frequency [rad/s] and relative damping per DOF (surge, sway, yaw).
    ki_ratio : float
        ``K_i = K_p omega_n * ki_ratio``; 0 gives a PD controller.
    """
    M = real_array("mass_matrix", mass_matrix)
    if M.shape != (3, 3) or not np.all(np.isfinite(M)):
        raise ValueError(f"mass_matrix: expected a finite (3, 3) matrix, got shape {M.shape}")
    w = _vec3("omega_n_rad_s", omega_n_rad_s, positive=True)
    z = _vec3("zeta", zeta, positive=True)
    ki_ratio = check_number("ki_ratio", ki_ratio, lo=0.0)
    Kp = M @ np.diag(w**2)
    Kd = M @ np.diag(2.0 * z * w)
    Ki = Kp @ np.diag(w * ki_ratio)
    return DPGains(Kp=Kp, Kd=Kd, Ki=Ki, omega_n_rad_s=w, zeta=z)


@dataclass(frozen=True)
class ReferenceState:
    """Desired motion in NED: ``eta_d`` [m, m, rad], its first and second time derivatives."""

    eta_d: np.ndarray
    eta_dot_d: np.ndarray
    eta_ddot_d: np.ndarray


class ReferenceModel:
    """Third-order, velocity-saturated set-point filter, decoupled per NED DOF.

    Parameters
    ----------
    omega_rad_s : float or (3,)
        Filter natural frequency per DOF [rad/s].
    zeta : float or (3,)
        Relative damping (1 = critically damped: no overshoot).
    max_rate : (3,)
        Saturation of the reference velocity ``[m/s, m/s, rad/s]``.
    """

    def __init__(self, omega_rad_s, zeta, max_rate):
        self.omega_rad_s = _vec3("reference_omega_rad_s", omega_rad_s, positive=True)
        self.zeta = _vec3("reference_zeta", zeta, positive=True)
        self.max_rate = _vec3("max_rate", max_rate, positive=True)
        # Euler substep: _REF_SUBSTEP_S, or a quarter of the stability bound -2 Re(p) / |p|^2 of
        # the filter's fastest pole p when that is shorter (a fast filter diverged to NaN)
        poles = np.concatenate([np.roots([1.0, (2 * z + 1) * w, (2 * z + 1) * w**2, w**3])
                                for w, z in zip(self.omega_rad_s, self.zeta)])
        self._substep_s = min(_REF_SUBSTEP_S, 0.5 * float(np.min(-poles.real / np.abs(poles) ** 2)))
        self.reset(np.zeros(3))

    def reset(self, eta_d) -> None:
        """Start at rest at ``eta_d`` (3,)."""
        self.x = _vec3("eta_d", eta_d)
        self.x[2] = float(wrap_pi(self.x[2]))
        self.v = np.zeros(3)
        self.a = np.zeros(3)

    @property
    def state(self) -> ReferenceState:
        eta = self.x.copy()
        eta[2] = float(wrap_pi(eta[2]))
        return ReferenceState(eta, self.v.copy(), self.a.copy())

    def step(self, setpoint_eta, dt_s: float) -> None:
        """Advance by ``dt_s`` [s] (> 0) towards ``setpoint_eta`` (3,) [m, m, rad], held over the step."""
        r = _vec3("setpoint_eta", setpoint_eta)
        dt_s = check_number("dt_s", dt_s, lo=0.0, lo_open=True)
        r[2] = self.x[2] + float(wrap_pi(r[2] - self.x[2]))  # shortest way round
        w, z = self.omega_rad_s, self.zeta
        n = max(1, math.ceil(dt_s / self._substep_s))
        h = dt_s / n
        for _ in range(n):
            jerk = w**3 * (r - self.x) - (2 * z + 1) * w**2 * self.v - (2 * z + 1) * w * self.a
            self.x = self.x + h * self.v
            self.v = self.v + h * self.a
            self.a = self.a + h * jerk
            # Velocity saturation; stop accelerating further into the limit (reference anti-windup).
            over = np.abs(self.v) > self.max_rate
            if np.any(over):
                self.v = np.where(over, np.sign(self.v) * self.max_rate, self.v)
                self.a = np.where(over & (self.a * self.v > 0), 0.0, self.a)


class DPController:
    """DP station keeping: reference model + body-frame nonlinear PID + feed-forward.

    Parameters
    ----------
    vessel : hybridship.vessel.Vessel or str
        The vessel (or packaged name); its nominal model gives ``M`` and the wind kernel.
    dt_s : float
        Control period [s] (time between :meth:`update` calls).
    omega_n_rad_s : float or (3,)
        Closed-loop natural frequencies (surge, sway, yaw) [rad/s].
    zeta : float or (3,)
        Closed-loop relative damping.
    ki_ratio : float
        Integral gain as a fraction of ``K_p omega_n``.
    reference_omega_rad_s : float or (3,)
        Reference-model natural frequencies [rad/s] (slower than the loop).
    reference_zeta : float or (3,)
        Reference-model damping (1: critically damped).
    max_speed_m_s, max_yaw_rate_rad_s : float
        Reference velocity saturation.
    integral_limit : (3,), optional
        Clamp of the integral action in the body frame ``[X_N, Y_N, N_Nm]``; default the
        thrusters' pure surge, sway and yaw capacity.
    reference_feedforward : bool
        Add ``M R^T eta_d_ddot``.
    wind_feedforward_gain : float
        Fraction of the modelled wind load compensated when ``wind`` is given (0 disables).
    """

    def __init__(self, vessel, *, dt_s: float, omega_n_rad_s=(0.07, 0.07, 0.09), zeta=0.9,
                 ki_ratio: float = 0.1, reference_omega_rad_s=(0.03, 0.03, 0.04), reference_zeta=1.0,
                 max_speed_m_s: float = 0.5, max_yaw_rate_rad_s: float = math.radians(2.0),
                 integral_limit=None, reference_feedforward: bool = True,
                 wind_feedforward_gain: float = 1.0):
        self.model = vessel if isinstance(vessel, DynamicModel) else DynamicModel(vessel)
        self.vessel = self.model.vessel
        if isinstance(dt_s, (bool, np.bool_)) or not isinstance(dt_s, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(dt_s) and dt_s > 0):
            raise ValueError(f"dt_s: must be finite and > 0, got {dt_s!r}")
        check_flags(reference_feedforward=reference_feedforward)     # a text "no" is truthy
        wind_feedforward_gain = check_number("wind_feedforward_gain", wind_feedforward_gain, lo=0.0, hi=2.0)
        for name, val in (("max_speed_m_s", max_speed_m_s), ("max_yaw_rate_rad_s", max_yaw_rate_rad_s)):
            check_number(name, val, lo=0.0, lo_open=True)
        self.dt_s = float(dt_s)
        self.mass_matrix = self.model.mass_matrix
        self.gains = pid_gains(self.mass_matrix, omega_n_rad_s, zeta, ki_ratio)
        self.reference_model = ReferenceModel(reference_omega_rad_s, reference_zeta,
                                              (max_speed_m_s, max_speed_m_s, max_yaw_rate_rad_s))
        if integral_limit is None:
            from .allocation import thrust_capacity

            cap = thrust_capacity(self.vessel)
            # no thrust in a direction: nothing to wind up against there, the integral is left free
            integral_limit = np.where(cap > 0.0, cap, 1e12)
        self.integral_limit = _vec3("integral_limit", integral_limit, positive=True)
        self.reference_feedforward = bool(reference_feedforward)
        self.wind_feedforward_gain = float(wind_feedforward_gain)
        self.reset(np.zeros(3))

    # ----------------------------------------------------------------- state

    def reset(self, setpoint_eta, eta_measured=None) -> None:
        """Engage DP: clear the integral and start the reference.

        Parameters
        ----------
        setpoint_eta : (3,)
            Target ``[north_m, east_m, psi_rad]``.
        eta_measured : (3,), optional
            Present position; the reference starts there and moves smoothly to the
            set-point. Default: the reference starts at the set-point.
        """
        self._setpoint = _vec3("setpoint_eta", setpoint_eta)
        start = self._setpoint if eta_measured is None else _vec3("eta_measured", eta_measured)
        self.reference_model.reset(start)
        self._integral_ned = np.zeros(3)

    def set_setpoint(self, setpoint_eta) -> None:
        """Change the target without resetting; the reference model smooths the change."""
        self._setpoint = _vec3("setpoint_eta", setpoint_eta)

    @property
    def setpoint_eta(self) -> np.ndarray:
        return self._setpoint.copy()

    @property
    def reference(self) -> ReferenceState:
        """Reference the next :meth:`update` tracks."""
        return self.reference_model.state

    @property
    def integral_ned(self) -> np.ndarray:
        """Integral action as a NED load ``[N_N, E_N, N_Nm]`` (the controller adds minus its body projection)."""
        return self._integral_ned.copy()

    # ----------------------------------------------------------------- control

    def wind_feedforward(self, eta, nu, wind) -> np.ndarray:
        """Minus the modelled wind load (body frame) for ``wind = [speed_m_s, dir_from_rad]``."""
        _, parts, _ = self.model.acceleration(eta, nu, wind=wind, return_parts=True)
        return -parts[0, 2]

    def update(self, eta_measured, nu_measured, wind=None) -> np.ndarray:
        """One control step: the body-frame force demand, then advance the reference by ``dt_s``.

        Parameters
        ----------
        eta_measured : (3,)
            ``[north_m, east_m, psi_rad]``.
        nu_measured : (3,)
            ``[u_m_s, v_m_s, r_rad_s]`` (over ground).
        wind : (2,), optional
            Measured ``[speed_m_s, dir_from_rad]`` for the wind feed-forward.

        Returns
        -------
        tau_desired_N : ndarray, shape (3,)
            ``[X_N, Y_N, N_Nm]`` for the thrust allocation.
        """
        eta = _vec3("eta_measured", eta_measured)
        nu = _vec3("nu_measured", nu_measured)
        if wind is not None:
            wind = real_array("wind", wind)
            if wind.shape != (2,) or not np.all(np.isfinite(wind)):
                raise ValueError(f"wind: expected finite [speed_m_s, dir_from_rad], got {np.shape(wind)}")
        psi = eta[2]
        R = rotation_z(psi)
        ref = self.reference_model.state
        g = self.gains

        e_ned = eta - ref.eta_d
        e_ned[2] = float(wrap_pi(e_ned[2]))
        e_b = ned_to_body(e_ned, psi)
        e_dot_b = nu - ned_to_body(ref.eta_dot_d, psi)

        tau = -(g.Kp @ e_b + g.Kd @ e_dot_b) - ned_to_body(self._integral_ned, psi)
        if self.reference_feedforward:
            tau = tau + self.mass_matrix @ ned_to_body(ref.eta_ddot_d, psi)
        if wind is not None and self.wind_feedforward_gain > 0:
            tau = tau + self.wind_feedforward_gain * self.wind_feedforward(eta, nu, wind)

        # Integral as a NED load (holds a fixed environmental load while turning), clamped
        # in the body frame where the thruster capacity is defined.
        integ_b = ned_to_body(self._integral_ned, psi) + self.dt_s * (g.Ki @ e_b)
        integ_b = np.clip(integ_b, -self.integral_limit, self.integral_limit)
        self._integral_ned = R @ integ_b

        self.reference_model.step(self._setpoint, self.dt_s)
        return tau
