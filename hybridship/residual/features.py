"""From a log to residual targets and network features (Skulstad et al. 2022, sec. 3.2-3.3).

For each sample ``t`` of a gap-free segment:

* the *measured* acceleration ``nu_dot(t)`` is a Savitzky-Golay derivative of the logged
  velocities (centred window, ``deriv_window_s``) and the smoothed state ``nu_s(t)`` the
  matching Savitzky-Golay smoothing;
* the dynamic model, started from ``(eta(t), nu_s(t))`` with the commands and wind of
  ``t`` held, predicts ``nu_hat(t+1)`` and ``nu_dot_hat(t+1)`` one step ahead;
* the residual target is ``d_nu_dot(t+1) = nu_dot(t+1) - nu_dot_hat(t+1)``;
* the features are chosen from ``nu_hat(t+1)``, ``nu_dot_hat(t+1)`` and the previous residual
  ``d_nu_dot(t)`` (the paper's choice, an ARX form).

Forecasts must use only what is known at their start time. The centred filters above
look a few seconds ahead, so they are used for training targets only. At a forecast start
``t0`` the initial state is the causal 3-sample average of heading and velocities (the
paper's 3-s moving average) and the "previous residual" is the mean of *causal* residual
estimates (end-point Savitzky-Golay derivative minus the model's one-step prediction from
the causally smoothed state) over the last ``start_residual_window_s`` seconds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import savgol_coeffs, savgol_filter

from ..logs.io import LogArrays

#: Every feature the hybrid can use, in a fixed order. ``_hat`` = model one-step prediction.
ALL_FEATURES = ("u_hat_m_s", "v_hat_m_s", "r_hat_rad_s",
                "u_dot_hat_m_s2", "v_dot_hat_m_s2", "r_dot_hat_rad_s2",
                "res_u_prev_m_s2", "res_v_prev_m_s2", "res_r_prev_rad_s2")

#: The paper's feature set (sec. 3.3): model-predicted velocities and accelerations plus
#: the previous residual.
PAPER_FEATURES = ALL_FEATURES

#: Residual target names (body-frame acceleration discrepancy).
TARGETS = ("res_u_m_s2", "res_v_m_s2", "res_r_rad_s2")


@dataclass(frozen=True)
class ResidualConfig:
    """How logs become residual targets and features (recorded in the model file).

    Attributes
    ----------
    features : names from :data:`ALL_FEATURES`.
    deriv_window_s : Savitzky-Golay window for velocities and accelerations [s].
    polyorder : Savitzky-Golay polynomial order.
    start_average_s : causal moving-average window of heading and velocities at a start [s].
    start_residual_window_s : window of the causal residual average at a start [s].
    """

    features: tuple[str, ...] = PAPER_FEATURES
    deriv_window_s: float = 11.0
    polyorder: int = 2
    start_average_s: float = 3.0
    start_residual_window_s: float = 10.0

    def __post_init__(self):
        unknown = [f for f in self.features if f not in ALL_FEATURES]
        if unknown or not self.features:
            raise ValueError(f"ResidualConfig.features: unknown {unknown}; choose from {list(ALL_FEATURES)}")
        if not self.deriv_window_s > 0 or not self.start_average_s > 0 or not self.start_residual_window_s > 0:
            raise ValueError("ResidualConfig: windows must be > 0 s")
        if self.polyorder < 1:
            raise ValueError(f"ResidualConfig.polyorder must be >= 1, got {self.polyorder}")

    @property
    def feature_index(self) -> np.ndarray:
        return np.array([ALL_FEATURES.index(f) for f in self.features])


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
    in another segment or does not exist); ``residual[i] = nu_dot[i] - nu_dot_hat[i]``.
    The ``_c`` arrays are the causal counterparts used at forecast starts.
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
    config: ResidualConfig = field(default_factory=ResidualConfig)

    def features(self, rows: np.ndarray) -> np.ndarray:
        """Feature matrix (len(rows), n_features) for predicting the residual at ``rows``."""
        rows = np.asarray(rows)
        full = np.concatenate([self.nu_hat[rows], self.nu_dot_hat[rows], self.residual[rows - 1]], axis=1)
        return full[:, self.config.feature_index]

    def trainable_rows(self, mask: np.ndarray | None = None) -> np.ndarray:
        """Rows i whose target and features are all defined (i - 1 and i - 2 in i's segment)."""
        ok = np.isfinite(self.residual).all(1)
        ok[1:] &= ok[:-1]
        ok[0] = False
        if mask is not None:
            ok &= mask
            ok[1:] &= mask[:-1]
        return np.flatnonzero(ok)

    def start_state(self, idx: int):
        """Causal start state at row ``idx``: ``(eta0 (3,), nu0 (3,), residual0 (3,))``.

        Heading and velocities: mean over the last ``start_average_s`` (the paper's 3-s
        window); position: the sample at ``idx``; residual: mean causal residual over the
        last ``start_residual_window_s`` (zeros if none is available).
        """
        a = self.arrays
        seg = a.segment_id
        n_avg = max(1, int(round(self.config.start_average_s / self.dt_s)))
        n_res = max(1, int(round(self.config.start_residual_window_s / self.dt_s)))
        lo = idx - n_avg + 1
        lo = max(lo, int(np.flatnonzero(seg == seg[idx])[0]))
        eta0 = a.eta[idx].copy()
        eta0[2] = a.eta[lo: idx + 1, 2].mean()
        nu0 = a.nu[lo: idx + 1].mean(axis=0)
        lo_r = max(idx - n_res + 1, int(np.flatnonzero(seg == seg[idx])[0]))
        r = self.residual_c[lo_r: idx + 1]
        r = r[np.isfinite(r).all(1)]
        res0 = r.mean(axis=0) if r.size else np.zeros(3)
        return eta0, nu0, res0


def prepare_log(model, arrays: LogArrays, config: ResidualConfig = ResidualConfig()) -> PreparedLog:
    """Smoothed states, measured accelerations, one-step model predictions and residuals.

    Parameters
    ----------
    model : hybridship.physics.model.DynamicModel
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
    nu_dot_c = np.full((N, 3), np.nan)
    for sl in arrays.segments:
        x = arrays.nu[sl]
        n = x.shape[0]
        w = _window(config.deriv_window_s, dt, config.polyorder)
        if n >= w:
            nu_s[sl] = savgol_filter(x, w, config.polyorder, axis=0)
            nu_dot[sl] = savgol_filter(x, w, config.polyorder, deriv=1, delta=dt, axis=0)
        elif n >= 2:
            nu_s[sl] = x
            nu_dot[sl] = np.gradient(x, dt, axis=0)
        nu_c[sl] = _causal_savgol(x, w, config.polyorder, 0, dt)
        nu_dot_c[sl] = _causal_savgol(x, w, config.polyorder, 1, dt)

    # One-step model predictions from every sample (all samples in one batch).
    def one_step(nu_start):
        res = model.rollout(arrays.eta, np.nan_to_num(nu_start), 1, dt_s=dt, rpm=arrays.rpm,
                            azimuth_rad=arrays.azimuth_rad, wind=arrays.wind)
        nh = np.full((N, 3), np.nan)
        ndh = np.full((N, 3), np.nan)
        same = arrays.segment_id[1:] == arrays.segment_id[:-1]
        nh[1:][same] = res.nu[:-1, 1][same]
        ndh[1:][same] = res.nu_dot[:-1, 1][same]
        return nh, ndh

    nu_hat, nu_dot_hat = one_step(nu_s)
    _, nu_dot_hat_c = one_step(nu_c)
    return PreparedLog(arrays=arrays, dt_s=dt, nu_s=nu_s, nu_dot=nu_dot, nu_hat=nu_hat, nu_dot_hat=nu_dot_hat,
                       residual=nu_dot - nu_dot_hat, nu_c=nu_c, residual_c=nu_dot_c - nu_dot_hat_c,
                       config=config)
