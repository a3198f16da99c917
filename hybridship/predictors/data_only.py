"""A data-only baseline: an ensemble that predicts the whole acceleration, no physics."""

from __future__ import annotations

from typing import Iterable

import numpy as np

from ..config import as_config
from ..forecast_inputs.faults import start_row_nu
from ..physics.model import DynamicModel
from ..residual.ensemble import EnsembleConfig, MLPEnsemble, fit_ensemble, require_training_rows
from ..residual.features import ResidualConfig
from .forecast_setup import (_check_flags, _check_row_stride, _forecast_setup,
                             keeps_state_on_error, log_list)
from .training_logs import (check_distinct_logs, check_training_lengths, read_training_logs, training_log_facts,
                            warn_logs_without_wind, warn_no_wind, warn_other_rate)
from .result import ForecastResult

__all__ = ["DataOnlyPredictor"]

#: Time stamps within this much [s] of a whole number of the log's step are that number of
#: steps: a clock written with round-off (10-Hz stamps off 0.1 s by 1e-13 s) is evenly sampled
#: (the forecast's step is the median rounded to the microsecond, as here).
STEP_ROUND_OFF_S = 1e-6


def _row_steps_s(time_s: np.ndarray, dt_s: float) -> np.ndarray:
    """The time from each row to the next [s] (N - 1,): each pair of rows' own, or the log's
    nominal step ``dt_s`` [s] where they differ from it by round-off only (:data:`STEP_ROUND_OFF_S`)."""
    d = np.diff(np.asarray(time_s, dtype=float))
    return np.where(np.abs(d - dt_s) <= STEP_ROUND_OFF_S, dt_s, d)


class DataOnlyPredictor:
    """A data-only baseline: an ensemble of the hybrid's size that predicts the whole acceleration.

    No physics: each member maps the present velocities, commands, wind and the previous
    acceleration to the next one-step acceleration ``(nu(t+1) - nu(t)) / dt`` (``dt`` the
    time between those two rows, on a log with uneven steps too) and is iterated ``H``
    steps of the forecast's step; positions follow by integrating the velocities. Each
    member runs its own trajectory (one batched array operation over members and start
    times); the forecast is the member mean and the spread their standard deviation.

    Features, in order: ``u, v, r`` [m/s, m/s, rad/s]; each thruster's rpm / max rpm; cos
    and sin of each rotatable thruster's angle; ``u, v`` minus the wind speed along its FROM
    direction in the body frame, ``V [cos, sin](dir - psi)`` [m/s] (the hull's velocity
    through the air has the wind term with the other sign; the net, which has ``u, v`` too,
    can learn either, and the baseline's published figures were made with this one); the
    previous acceleration.

    It has no model file (no ``save`` / ``load``, unlike
    :class:`~hybridship.predictors.HybridPredictor`): a benchmark baseline, fitted again from
    the logs each time it is compared. Like the hybrid, it warns about training logs with and
    without wind columns, and about a forecast log at another rate than its training logs'
    (``training_info["log_step_s"]``) or without wind columns when they had them
    (``training_info["trained_with_wind"]``).
    """

    name = "data_only"

    def __init__(self, vessel="gunnerus", *, ensemble_config: EnsembleConfig = EnsembleConfig(),
                 start_average_s: float = 3.0, stop_after_failure: bool = True):
        self.model = DynamicModel(vessel)
        self.ensemble_config = as_config(ensemble_config, EnsembleConfig, "ensemble_config")
        self.config = ResidualConfig(start_average_s=start_average_s)
        _check_flags(stop_after_failure=stop_after_failure)
        self.stop_after_failure = bool(stop_after_failure)
        self.ensemble: MLPEnsemble | None = None
        self.training_info: dict = {}
        # one scale per command channel: thrusters by their max rpm, rudders (no rpm) by 1
        v = self.model.vessel
        self._rpm_scale = np.array([t.max_rpm for t in v.thrusters] + [1.0] * len(v.rudders), dtype=float)
        self._rot = np.array(self.model.vessel.rotatable, dtype=bool)

    def _features(self, nu, rpm, az, wind, psi, acc_prev):
        """Feature rows (..., F) from arrays with matching leading shapes."""
        rel = wind[..., 0:1] * np.stack([np.cos(wind[..., 1] - psi), np.sin(wind[..., 1] - psi)], axis=-1)
        rel = nu[..., :2] - rel      # u, v less the wind along its FROM direction, body axes (see the class notes)
        a = az[..., self._rot]
        return np.concatenate([nu, rpm / self._rpm_scale, np.cos(a), np.sin(a), rel, acc_prev], axis=-1)

    @keeps_state_on_error
    def fit(self, logs: Iterable, *, dp_only: bool = True, progress: bool = False,
            row_stride: int = 1) -> "DataOnlyPredictor":
        """Learn one-step accelerations from logs (by default their DP part only), from every
        ``row_stride``-th usable row (see :meth:`HybridPredictor.fit`); a call that raises
        leaves the predictor as it was."""
        stride = _check_row_stride(row_stride)
        _check_flags(dp_only=dp_only, progress=progress)
        Xs, Ys, segs = [], [], []
        given = log_list(logs)
        arrays, labels = read_training_logs(given, self.model.vessel)
        check_training_lengths(arrays, labels)
        check_distinct_logs(arrays, labels)
        warn_logs_without_wind(arrays, labels)
        for k, a in enumerate(arrays):
            step = _row_steps_s(a.time_s, float(np.median(np.diff(a.time_s))))    # step[i]: row i to i + 1
            seg = a.segment_id
            ok = np.zeros(len(a.time_s), bool)
            ok[2:] = (seg[2:] == seg[1:-1]) & (seg[1:-1] == seg[:-2])
            if dp_only:
                ok[1:] &= a.dp_active[:-1].astype(bool) & a.dp_active[1:].astype(bool)
            rows = np.flatnonzero(ok)               # predict row i from row i - 1
            if rows.size == 0:
                continue
            acc_prev = (a.nu[rows - 1] - a.nu[rows - 2]) / step[rows - 2, None]
            Xs.append(self._features(a.nu[rows - 1], a.rpm[rows - 1], a.azimuth_rad[rows - 1],
                                     a.wind[rows - 1], a.eta[rows - 1, 2], acc_prev))
            Ys.append((a.nu[rows] - a.nu[rows - 1]) / step[rows - 1, None])
            segs.append(seg[rows] + 10_000 * k)
        X, Y, seg = (np.concatenate(z)[::stride] if z else np.zeros((0, 1)) for z in (Xs, Ys, segs))
        require_training_rows(X.shape[0], len(arrays), dp_only)
        self.ensemble = fit_ensemble(X, Y, self.ensemble_config, segment_id=seg, progress=progress)
        self.training_info = training_log_facts(arrays)
        return self

    def forecast(self, log, start_times_s, horizon_s: float = 60.0, *, commands: str = "held") -> ForecastResult:
        """Iterate the ensemble from every start time; wind held, commands held or known
        (see :meth:`DynamicPredictor.forecast`)."""
        if self.ensemble is None:
            raise RuntimeError("DataOnlyPredictor: call fit() before forecast()")
        st = _forecast_setup(self.model, self.config, log, start_times_s, horizon_s, self.stop_after_failure,
                             commands)
        warn_other_rate(self.training_info, st.dt)
        warn_no_wind(self.training_info, st.arrays)
        arrays, idx, dt, H, eta0, nu0 = st.arrays, st.idx, st.dt, st.H, st.eta0, st.nu0
        rpm, az, wind = st.rpm, st.az, st.wind[:, 0]          # commands (S, 1 or H, K)
        n_avg = max(1, int(round(self.config.start_average_s / dt)))
        lo = np.maximum(idx - n_avg, 0)
        same = arrays.segment_id[lo] == arrays.segment_id[idx]
        # the start row's velocity as a log ending there gives it: a derived one must not read the next sample
        nu_start = start_row_nu(arrays, idx)
        # over the rows' own time (on an evenly sampled log, idx - lo steps of the forecast's step)
        nominal = np.maximum(idx - lo, 1) * dt
        elapsed = np.where(idx > lo, arrays.time_s[idx] - arrays.time_s[lo], dt)
        elapsed = np.where(np.abs(elapsed - nominal) <= STEP_ROUND_OFF_S * np.maximum(idx - lo, 1), nominal, elapsed)
        acc0 = np.where(same[:, None], (nu_start - arrays.nu[lo]) / elapsed[:, None], 0.0)
        acc0 = np.nan_to_num(acc0)      # a missing sample at either end: start from zero acceleration
        E, S = self.ensemble.n_members, len(idx)
        eta = np.broadcast_to(eta0, (E, S, 3)).copy()
        nu = np.broadcast_to(nu0, (E, S, 3)).copy()
        acc = np.broadcast_to(acc0, (E, S, 3)).copy()
        out = np.empty((E, S, H + 1, 3))
        out_nu = np.empty((E, S, H + 1, 3))
        out[:, :, 0], out_nu[:, :, 0] = eta, nu
        rpm_e, az_e, wind_e = (np.broadcast_to(x, (E,) + x.shape) for x in (rpm, az, wind))
        for j in range(H):
            jc = j if rpm.shape[1] > 1 else 0
            X = self._features(nu, rpm_e[:, :, jc], az_e[:, :, jc], wind_e, eta[..., 2], acc)
            acc = self.ensemble.predict_members(X)                 # (E, S, 3), member e on its own path
            nu_mid = nu + 0.5 * dt * acc
            psi_mid = eta[..., 2] + 0.5 * dt * nu_mid[..., 2]
            c, s = np.cos(psi_mid), np.sin(psi_mid)
            eta[..., 0] += dt * (c * nu_mid[..., 0] - s * nu_mid[..., 1])
            eta[..., 1] += dt * (s * nu_mid[..., 0] + c * nu_mid[..., 1])
            eta[..., 2] += dt * nu_mid[..., 2]
            nu = nu + dt * acc
            out[:, :, j + 1], out_nu[:, :, j + 1] = eta, nu
        return ForecastResult(arrays.time_s[idx], st.lead_s, out.mean(axis=0), out_nu.mean(axis=0),
                              out.std(axis=0), flags=st.flags, notes=st.notes)
