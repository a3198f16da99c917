"""The hybrid surge/pitch model: a grey-box physics model plus a residual ensemble.

Grey box
--------
Surge is a force balance and pitch a first-order approach to a speed-dependent running
trim, both built from the *nominal* vessel file's calm-water physics (Savitsky planing
equilibria of :class:`~hybridship.hsc.simulator.PlaningCraftModel`, tabulated once over
engine speed and actuator setting):

* ``(m + A11) p_m dV/dt = p_T (c1 n^2 - p_J c2 n V) - [p_R R0(V) + p_aR (R(V, a) - R0(V))]``
  (propeller thrust falling with speed; calm-water resistance at the running trim;
  the trim device's change of resistance);
* ``theta_ss = p_th0 + p_ths theta0(V) + p_ath (theta(V, a) - theta0(V)) + p_thT (T - R) / (m g)``
  (running trim, the device's trim change, and the extra bow-up trim of the thrust-line
  moment while accelerating); ``dtheta/dt = (theta_ss - theta) / tau_theta``;
* ``a`` is the device's stroke/deflection fraction from the PWM input through the vessel
  file's linear PWM map and actuator rate limit.

The ten parameters ``p`` (nominal 1 or 0, and 0.5 s for ``tau_theta_s``; ``_NOMINAL``)
are fitted to the training data by nonlinear least squares on the free-run (simulation)
error of both outputs, so the grey box learns
the "true" boat's thrust, resistance, trim and device effectiveness that the nominal file
gets wrong (see ``[truth_perturbation]`` in ``vessels/volcano71.toml``).

Residual
--------
A residual ensemble (:func:`hybridship.residual.ensemble.fit_ensemble`, 10 members of
2 x 20 tanh) learns what the grey box misses, separately for the two scoring modes:

* free run: ``y[k] - y_gb[k]`` from the grey box's own simulated state and the inputs
  (lags of engine speed, PWM, heave acceleration); no measured output enters, so the
  correction never feeds back and cannot make the simulation unstable;
* one step: ``y[k] - y_gb1[k]``, where ``y_gb1`` is the grey box's one-step prediction from
  the measured outputs at ``k-1``, from the measured outputs and the inputs up to ``k-1``.

The prediction is the grey box plus the ensemble mean.
"""

from __future__ import annotations

import bisect
import copy
import math
import os
from dataclasses import dataclass

import numpy as np

from hybridship.config import as_config, check_flags, check_number, check_whole_number, real_array
from hybridship.residual.ensemble import MIN_TRAINING_ROWS, EnsembleConfig, fit_ensemble

from .contract import _finite, _matrix, check_free_run, check_physical, check_record, require_fitted
from .simulator import PlaningCraftModel
from .vessel import PlaningCraft, load_planing_craft

__all__ = ["GreyBoxTables", "GreyBox", "HybridModel", "PARAM_NAMES"]

#: Grey-box parameters and their nominal values.
PARAM_NAMES = ("p_T", "p_J", "p_R", "p_aR", "p_m", "p_th0", "p_ths", "p_ath", "p_thT", "tau_theta_s")
_NOMINAL = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.5])
_LOWER = np.array([0.5, 0.0, 0.3, -1.0, 0.3, -0.1, 0.3, -1.0, -1.0, 0.05])
_UPPER = np.array([2.0, 3.0, 3.0, 4.0, 5.0, 0.1, 2.0, 4.0, 1.0, 5.0])


@dataclass(frozen=True)
class GreyBoxTables:
    """Calm-water equilibria of the nominal craft on a uniform speed grid.

    Attributes
    ----------
    v0_m_s, dv_m_s : float
        First speed and spacing of the grid [m/s].
    act : ndarray, shape (na,)
        Actuator fractions of the rows.
    resistance_n : ndarray, shape (na, nv)
        Resistance at the equilibrium (= thrust) [N].
    trim_rad : ndarray, shape (na, nv)
        Running trim [rad].
    actuator : {"interceptor", "trim_tab"} or None
        The trim device the equilibria were computed for (set by :meth:`from_craft`; None,
        unknown, for hand-made tables). :class:`GreyBox` refuses tables of another device.
    """

    v0_m_s: float
    dv_m_s: float
    act: np.ndarray
    resistance_n: np.ndarray
    trim_rad: np.ndarray
    actuator: str | None = None

    @classmethod
    def from_craft(cls, craft: PlaningCraft, actuator: str, *, n_rpm: int = 25,
                   act=(0.0, 0.5, 1.0), dv_m_s: float = 0.25) -> "GreyBoxTables":
        n_rpm = check_whole_number("n_rpm", n_rpm, 2)       # the extrapolation above the top needs two
        dv_m_s = check_number("dv_m_s", dv_m_s, lo=0.0, lo_open=True)
        _check_act_rows(act)
        model = PlaningCraftModel(craft, actuator)
        lo, hi = craft.engines.idle_rpm, craft.engines.max_rpm
        rpms = np.linspace(lo, hi * 1.05, n_rpm)
        grid = np.arange(0.0, 26.0 + dv_m_s, dv_m_s)
        R, TH = [], []
        for a in act:
            curve = model.steady_curve(rpms, a)
            v = np.array([s.speed_m_s for s in curve])
            r = np.array([s.thrust_n for s in curve])
            th = np.array([s.trim_rad for s in curve])
            order = np.argsort(v)
            v, r, th = v[order], r[order], th[order]
            # below idle speed: R ~ V^2 and trim ~ V to zero at rest; above the top: linear
            rr = np.interp(grid, v, r)
            below = grid < v[0]
            rr[below] = r[0] * (grid[below] / v[0]) ** 2
            above = grid > v[-1]
            rr[above] = r[-1] + (r[-1] - r[-2]) / (v[-1] - v[-2]) * (grid[above] - v[-1])
            tt = np.interp(grid, v, th)
            tt[below] = th[0] * grid[below] / v[0]
            tt[above] = th[-1] + (th[-1] - th[-2]) / (v[-1] - v[-2]) * (grid[above] - v[-1])
            R.append(rr)
            TH.append(tt)
        return cls(float(grid[0]), float(dv_m_s), np.asarray(act, float), np.array(R), np.array(TH), actuator)


class GreyBox:
    """The grey-box surge/pitch model of one craft and trim device (see the module docstring)."""

    def __init__(self, craft: PlaningCraft, actuator: str, tables: GreyBoxTables | None = None,
                 dt_s: float | None = None):
        self.craft, self.actuator = craft, actuator
        # checks the craft (read for its sensors below) and the actuator before the tables are
        # judged by it
        pm = PlaningCraftModel(craft, actuator)
        # the step of the records: by default the craft's sample period (a fixed 0.1 s ran the
        # dynamics at half speed on a craft logged at 0.2 s)
        dt_s = craft.sensors.sample_period_s if dt_s is None else dt_s
        self.dt = dt_s = check_number("dt_s", dt_s, lo=0.0, lo_open=True)
        if tables is not None and not isinstance(tables, GreyBoxTables):
            raise TypeError(f"tables: expected GreyBoxTables (GreyBoxTables.from_craft(...)), "
                            f"got {type(tables).__name__}")
        if tables is not None and tables.actuator not in (None, actuator):
            # the other device's resistance and trim changes, accepted without a word before
            raise ValueError(f"tables: computed for the {tables.actuator!r} actuator, expected tables for {actuator!r} "
                             f"(GreyBoxTables.from_craft(craft, {actuator!r}))")
        if tables is not None:
            _check_act_rows(tables.act, "tables.act")
            check_number("tables.v0_m_s", tables.v0_m_s)
            check_number("tables.dv_m_s", tables.dv_m_s, lo=0.0, lo_open=True)      # the lookup divides by it
            shapes = []
            for name in ("resistance_n", "trim_rad"):
                arr = real_array(f"tables.{name}", getattr(tables, name))
                if arr.ndim != 2 or arr.shape[0] != len(tables.act) or not np.all(np.isfinite(arr)):
                    raise ValueError(f"tables.{name}: expected finite values, one row per actuator fraction of "
                                     f"tables.act ({len(tables.act)}) and one column per speed, got shape "
                                     f"{arr.shape}{'' if np.all(np.isfinite(arr)) else ' with NaN or inf'}")
                shapes.append(arr.shape)
            if shapes[0] != shapes[1]:           # the lookup reads both on the speed grid of resistance_n
                raise ValueError(f"tables.trim_rad: expected the shape of tables.resistance_n {shapes[0]} (the same "
                                 f"speed grid), got {shapes[1]}")
        self.tables = tables or GreyBoxTables.from_craft(craft, actuator)
        self._pwm_to_frac = pm.pwm_to_fraction
        self.pwm_range_pct = tuple(map(float, pm.pwm_range))
        self.act_step = pm.act_rate * dt_s
        self.mass = pm.m + pm.A11
        self.weight = pm.m * 9.81
        pr = craft.propellers
        k = pm.n_eng * pm.rho * pr.diameter_m ** 4 * pr.kt0 * (1 - pr.thrust_deduction)
        self.c1 = k / (60.0 * pr.gear_ratio) ** 2                    # T = c1 n^2 - c2 n V (n in rpm)
        self.c2 = k * (1 - pr.wake_fraction) / (60.0 * pr.gear_ratio * pr.diameter_m * pr.j0)
        self.params = _NOMINAL.copy()
        t = self.tables
        self._nv = np.shape(t.resistance_n)[1]
        self._R = [list(r) for r in t.resistance_n]
        self._TH = [list(r) for r in t.trim_rad]
        self._act = [float(x) for x in t.act]

    # -------------------------------------------------------------- pieces

    def actuator_fraction(self, pwm_pct):
        """Stroke/deflection fraction from the PWM record (linear map, rate limit).

        Raises
        ------
        TypeError, ValueError
            Naming ``pwm_pct``: not a 1-D sequence of finite numbers (a NaN made every later
            fraction NaN, an empty record or a single number an IndexError).
        """
        pwm = real_array("pwm_pct", pwm_pct)
        if pwm.ndim != 1 or not np.all(np.isfinite(pwm)):
            raise ValueError(f"pwm_pct: expected a 1-D sequence of finite duties [%], got shape {pwm.shape}"
                             f"{'' if np.all(np.isfinite(pwm)) else ' with NaN or inf'}")
        cmd = self._pwm_to_frac(pwm)
        if cmd.size == 0:
            return cmd
        a = np.empty_like(cmd)
        x = float(cmd[0])
        for k, c in enumerate(cmd):
            a[k] = x                          # the fraction during sample k (set by commands before k)
            x += min(max(c - x, -self.act_step), self.act_step)
        return a

    def _lookup(self, table, v, a):
        t = self.tables
        f = (v - t.v0_m_s) / t.dv_m_s
        i = min(max(int(f), 0), self._nv - 2)
        w = min(max(f - i, 0.0), 1.0) if f < self._nv - 1 else f - i
        rows = self._act
        # the interval of the actuator rows holding a (any number of rows; only the first
        # three were used before, so a finer grid stopped at its third row)
        j = min(max(bisect.bisect_left(rows, a) - 1, 0), len(rows) - 2)     # a on a row: the interval below it, as before
        wa = min(max((a - rows[j]) / (rows[j + 1] - rows[j]), 0.0), 1.0)
        r0 = table[j][i] + w * (table[j][i + 1] - table[j][i])
        r1 = table[j + 1][i] + w * (table[j + 1][i + 1] - table[j + 1][i])
        base = table[0][i] + w * (table[0][i + 1] - table[0][i])
        return base, r0 + wa * (r1 - r0)

    def rates(self, v, th, rpm, a, p=None):
        """``(dV/dt, theta_ss, T - R)`` at a state."""
        p = self.params if p is None else p
        v = max(v, 0.0)
        R0, Ra = self._lookup(self._R, v, a)
        T0, Ta = self._lookup(self._TH, v, a)
        thrust = p[0] * (self.c1 * rpm * rpm - p[1] * self.c2 * rpm * v)
        res = p[2] * R0 + p[3] * (Ra - R0)
        surplus = thrust - res
        th_ss = p[5] + p[6] * T0 + p[7] * (Ta - T0) + p[8] * surplus / self.weight
        return surplus / (self.mass * p[4]), th_ss, surplus

    # -------------------------------------------------------------- runs

    def simulate(self, U, y0, k0: int = 0, p=None):
        """Free run from ``y0 = (V, theta)`` at sample ``k0``; returns ``(N, 2)`` (held at ``y0`` before ``k0``).

        Raises
        ------
        ValueError
            Naming the argument: ``U`` not a finite (N, 3) record, ``y0`` not two finite
            numbers, ``k0`` not a whole number in ``[0, N)``.
        """
        U = _matrix("U", U, 3)
        _finite("U", U)
        try:                        # text such as "10" was read as a number
            y = np.array(real_array("y0", y0), dtype=float)
        except (TypeError, ValueError):
            y = None
        if y is None or y.shape != (2,) or not np.isfinite(y).all():
            raise ValueError(f"y0: expected (speed m/s, pitch rad), two finite numbers, got {y0!r}")
        k0 = _check_k0(k0, U.shape[0], 0)
        return self._simulate(U, y, k0, p)

    def _simulate(self, U, y0, k0, p=None):
        """:meth:`simulate` on checked arguments (the fit calls it at every step)."""
        p = self.params if p is None else p
        a = self.actuator_fraction(U[:, 1])
        rpm = U[:, 0]
        N = U.shape[0]
        out = np.empty((N, 2))
        v, th = float(y0[0]), float(y0[1])
        out[:k0] = (v, th)
        decay = math.exp(-self.dt / max(p[9], 1e-3))
        dt = self.dt
        out[k0] = (v, th)
        for k in range(k0 + 1, N):
            dv, th_ss, _ = self.rates(v, th, rpm[k - 1], a[k - 1], p)
            v = max(v + dt * dv, 0.0)
            th = th_ss + (th - th_ss) * decay
            out[k] = (v, th)
        return out

    def one_step(self, U, Y, p=None):
        """One-step predictions ``y_hat[k]`` from the measured ``Y[k-1]`` (row 0 is NaN).

        Raises
        ------
        ValueError
            Naming ``U`` or ``Y``: not finite (N, 3) and (N, 2) records of two or more rows.
        """
        return self._one_step(*check_record(U, Y, shape=(3, 2)), p)

    def _one_step(self, U, Y, p=None):
        """:meth:`one_step` on checked arguments."""
        p = self.params if p is None else p
        a = self.actuator_fraction(U[:, 1])
        decay = math.exp(-self.dt / max(p[9], 1e-3))
        out = np.full(Y.shape, np.nan)
        for k in range(1, Y.shape[0]):
            v, th = Y[k - 1]
            dv, th_ss, _ = self.rates(v, th, U[k - 1, 0], a[k - 1], p)
            out[k] = (max(v + self.dt * dv, 0.0), th_ss + (th - th_ss) * decay)
        return out

    def fit(self, U, Y, k0: int = 0, *, max_nfev: int = 60):
        """Fit the parameters to minimise the free-run error of both outputs (each over its spread).

        The free runs start from the measured ``Y[k0]``; ``k0`` is a whole number with at least
        one row after it (a ValueError naming it otherwise: ``k0 = -1`` started from the last row);
        ``max_nfev``, the most residual evaluations of the least squares, a whole number >= 1.
        """
        from scipy.optimize import least_squares

        U, Y = check_record(U, Y, shape=(3, 2))
        k0 = _check_k0(k0, U.shape[0], 1)
        max_nfev = check_whole_number("max_nfev", max_nfev, 1)    # text failed in scipy's words, True was 1
        _check_units(U, Y, self)
        scale = Y[k0:].std(0)
        scale = np.where(scale > 1e-9, scale, 1.0)

        def resid(p):
            sim = self._simulate(U, Y[k0], k0, p)
            r = (sim[k0 + 1:] - Y[k0 + 1:]) / scale
            return np.nan_to_num(r, nan=1e3).ravel()

        # from the nominal parameters, never from an earlier fit: fit sets the learned state alone
        sol = least_squares(resid, _NOMINAL, bounds=(_LOWER, _UPPER), x_scale="jac",
                            max_nfev=max_nfev, diff_step=1e-3)
        self.params = sol.x
        self.fit_cost = float(sol.cost)
        return self

    def parameters(self) -> dict:
        return dict(zip(PARAM_NAMES, map(float, self.params)))


def _check_act_rows(act, name: str = "act") -> None:
    """Actuator fractions of the table rows: at least two, finite, strictly increasing in [0, 1],
    the first 0 (the device retracted: the base the device's changes are taken from)."""
    a = real_array(name, act)
    if a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)) or a[0] != 0.0 or a[-1] > 1.0 \
            or np.any(np.diff(a) <= 0):
        raise ValueError(f"{name}: expected two or more increasing fractions from 0 (retracted) up to at most 1, "
                         f"got {act!r}")


def _check_k0(k0, n_rows: int, after: int) -> int:
    """``k0`` as an int with ``after`` rows of ``U`` after it (before: a negative ``k0`` counted
    from the end, a large one was an IndexError)."""
    k0 = check_whole_number("k0", k0, 0)
    if k0 > n_rows - 1 - after:
        raise ValueError(f"k0: expected 0 <= k0 <= {n_rows - 1 - after} (U has {n_rows} rows"
                         f"{f', {after} needed after k0' if after else ''}), got {k0}")
    return k0


#: A planing craft's pitch stays well inside this [rad] (about 29 deg); beyond it the column is degrees.
_PITCH_LIMIT_RAD = 0.5


def _check_units(U, Y, grey: "GreyBox", y_name: str = "Y") -> None:
    """Refuse the unit slips the grey box cannot survive: pitch in degrees (every parameter
    would end at a bound), PWM as a fraction (the device would never move) and an engine
    speed beyond twice the craft's ``max_rpm`` (40 000 rpm was forecast at 475 kn)."""
    check_physical(U, Y, y_name)
    pwm_range_pct, hi = grey.pwm_range_pct, 2.0 * grey.craft.engines.max_rpm
    rpm = U[:, 0]
    if rpm.size and rpm.max() > hi:
        raise ValueError(f"U: column 0 (engine speed) reaches {rpm.max():.6g} rpm, beyond twice the craft's "
                         f"max_rpm ({hi:g}); expected rpm (a unit slip?)")
    pitch = np.abs(Y[:, 1])
    if pitch.size and pitch.max() > _PITCH_LIMIT_RAD:
        raise ValueError(f"{y_name}: column 1 (pitch) reaches {pitch.max():.3g}; expected radians (|pitch| below "
                         f"{_PITCH_LIMIT_RAD} rad); the values look like degrees")
    pwm_max = float(np.max(U[:, 1])) if U.shape[0] else 0.0
    lo = pwm_range_pct[0]
    if 0.0 < pwm_max <= 1.0 < lo:
        raise ValueError(f"U: column 1 (PWM) lies within 0..{pwm_max:.3g}; expected duty in % (the device "
                         f"moves from {lo:g} %); the values look like a fraction")


def _lags(A, lags):
    """Columns ``A[k - l]`` for each lag ``l`` (edge-padded at the start)."""
    A = np.asarray(A, float)
    if A.ndim == 1:
        A = A[:, None]
    pad = max(lags)
    P = np.vstack([np.repeat(A[:1], pad, 0), A])
    N = A.shape[0]
    return np.hstack([P[pad - l:pad - l + N] for l in lags])


class HybridModel:
    """Grey box + residual ensembles (one per scoring mode); same interface as the identified models.

    Parameters
    ----------
    craft : PlaningCraft
        The *nominal* vessel file.
    actuator : {"interceptor", "trim_tab"}
        The trim device.
    ensemble : EnsembleConfig
    acc_lags : int
        Lags of the heave acceleration in the residual features.
    tables : GreyBoxTables, optional
        Pre-computed equilibria (they depend only on the craft and device).
    dt_s : float, optional
        Sample period of the records [s]; default the craft's ``sensors.sample_period_s``.
    """

    name = "hybrid"

    def __init__(self, craft: PlaningCraft, actuator: str, *, ensemble: EnsembleConfig = EnsembleConfig(),
                 acc_lags: int = 4, tables: GreyBoxTables | None = None, dt_s: float | None = None):
        if isinstance(craft, (str, os.PathLike)):    # a name or file, as load_planing_craft takes
            craft = load_planing_craft(craft)
        if not isinstance(craft, PlaningCraft):
            raise TypeError(f"craft: expected a PlaningCraft (load_planing_craft(...)), got {type(craft).__name__}")
        check_number("dt_s", dt_s, lo=0.0, lo_open=True, allow_none=True)    # None: the craft's sample period
        check_whole_number("acc_lags", acc_lags, 1)
        self.grey = GreyBox(craft, actuator, tables, dt_s)
        self.ensemble_config = as_config(ensemble, EnsembleConfig, "ensemble")
        self.acc_lags = acc_lags
        self.n_init = 2
        self.shape = (3, 2)              # U: rpm, PWM %, heave acceleration; Y: speed, pitch

    def _input_features(self, U, a):
        lags = list(range(1, self.acc_lags + 1))
        rpm1 = _lags(U[:, 0], [1])
        d_rpm = rpm1 - _lags(U[:, 0], [11])                 # engine speed change over 10 samples (1 s at 0.1 s)
        return np.hstack([rpm1, d_rpm, _lags(U[:, 1], [1]), _lags(a, [0, 5]), _lags(U[:, 2], lags)])

    def _free_features(self, U, sim):
        a = self.grey.actuator_fraction(U[:, 1])
        d_v = sim[:, :1] - _lags(sim[:, 0], [10])
        return np.hstack([sim, d_v, self._input_features(U, a)])

    def _one_features(self, U, Y, phys):
        a = self.grey.actuator_fraction(U[:, 1])
        return np.hstack([_lags(Y, [1, 2]), phys, self._input_features(U, a)])

    def fit(self, U, Y, *, progress: bool = False):
        """Fit the grey box, then the two residual ensembles, on one record; returns self.

        All or nothing: the grey box and the ensembles are fitted on the side and replace the
        learned state together, so a fit that raises leaves the model as it was (a refit that
        failed in the ensemble kept the new grey box with the old ensembles).

        Raises
        ------
        ValueError
            Naming ``U`` or ``Y``: not finite (N, 3) and (N, 2) records of at least
            ``n_init`` + 20 rows (the ensembles' fewest training rows), or values no craft
            record holds.
        """
        check_flags(progress=progress)
        U, Y = check_record(U, Y, min_rows=self.n_init + MIN_TRAINING_ROWS, shape=self.shape)
        k0 = self.n_init                 # the grey box's fit checks the units
        grey = copy.copy(self.grey).fit(U, Y, k0 - 1)     # fit assigns new parameters, shared tables stay
        sim = grey._simulate(U, Y[k0 - 1], k0 - 1)
        X = self._free_features(U, sim)[k0:]
        free_ens = fit_ensemble(X, (Y - sim)[k0:], self.ensemble_config, progress=progress)
        phys = grey._one_step(U, Y)
        X1 = self._one_features(U, Y, phys)[k0:]
        one_ens = fit_ensemble(X1, (Y - phys)[k0:], self.ensemble_config, progress=progress)
        self.grey, self.free_ens, self.one_ens = grey, free_ens, one_ens
        return self

    def one_step(self, U, Y):
        require_fitted(self, "one_ens")
        U, Y = check_record(U, Y, min_rows=self.n_init + 1, shape=self.shape)
        _check_units(U, Y, self.grey)
        phys = self.grey._one_step(U, Y)
        out = np.full(Y.shape, np.nan)
        k0 = self.n_init
        mean, _ = self.one_ens.predict(self._one_features(U, Y, phys)[k0:])
        out[k0:] = phys[k0:] + mean
        return out

    def free_run(self, U, Y_init, n_init: int):
        require_fitted(self, "free_ens")
        U, Y_init, n_init = check_free_run(U, Y_init, n_init, self.n_init, self.shape)
        _check_units(U, Y_init, self.grey, "Y_init")
        sim = self.grey._simulate(U, Y_init[n_init - 1], n_init - 1)
        out = np.full(sim.shape, np.nan)
        mean, _ = self.free_ens.predict(self._free_features(U, sim)[n_init:])
        out[n_init:] = sim[n_init:] + mean
        return out

    def grey_free_run(self, U, Y_init, n_init: int):
        """The grey box alone (for the documentation's ablation)."""
        require_fitted(self, "free_ens")
        U, Y_init, n_init = check_free_run(U, Y_init, n_init, self.n_init, self.shape)
        _check_units(U, Y_init, self.grey, "Y_init")
        sim = self.grey._simulate(U, Y_init[n_init - 1], n_init - 1)
        sim[:n_init] = np.nan
        return sim
