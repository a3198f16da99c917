"""The result of every forecaster: :class:`ForecastResult` (arrays, batch-first over start times)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..forecast_inputs import FaultFlags
from ..frames import wrap_2pi

__all__ = ["ForecastResult"]


def quantile_label(q: float) -> str:
    """The probability as written in a quantile column's name: its shortest exact decimal
    (``0.05``, ``0.9999999``), so that distinct probabilities never share a column."""
    return np.format_float_positional(float(q), trim="-")


def checked_quantiles(q) -> np.ndarray:
    """``q`` as a 1-D array of distinct probabilities in (0, 1); ValueError naming
    ``quantiles`` otherwise (a number, or a list of them)."""
    try:
        arr = np.atleast_1d(np.asarray(q, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"quantiles: expected probabilities in (0, 1) (a number or a list), got {q!r}") from None
    if isinstance(q, (str, bytes)) or arr.ndim != 1 or arr.size == 0 or not np.all((arr > 0) & (arr < 1)):
        raise ValueError(f"quantiles: expected probabilities in (0, 1) (a number or a list), got {q!r}")
    labels = [quantile_label(x) for x in arr]
    if len(set(labels)) != len(labels):
        raise ValueError(f"quantiles: each probability once, got {', '.join(labels)}")
    return arr


@dataclass
class ForecastResult:
    """Forecasts from S start times over H steps (index 0 = the start).

    Attributes
    ----------
    start_time_s : ndarray, shape (S,)
        Start times [s].
    lead_s : ndarray, shape (H+1,)
        Time since the start [s]: ``k`` steps of the log's step, rounded to 1e-9 s (see
        :func:`hybridship.predictors.forecast_setup.forecast_step_s`).
    eta : ndarray, shape (S, H+1, 3)
        ``[north_m, east_m, psi_rad]`` (the ensemble mean for the hybrid). ``psi_rad`` runs
        continuously along each forecast, on the branch where the start's heading lies in
        [0, 2 pi): a start's forecast does not depend on the other starts of the call (the
        log's unwrapped heading, whose branch depends on where the read began, does).
    nu : ndarray, shape (S, H+1, 3)
        ``[u_m_s, v_m_s, r_rad_s]``.
    eta_std : ndarray, shape (S, H+1, 3), or None
        One-sigma spread of ``eta`` [m, m, rad]: for the hybrid the calibrated spread by
        default (see :meth:`HybridPredictor.forecast`, ``calibrated``), otherwise the
        ensemble's standard deviation; None for forecasters without a spread.
    guard_weight : ndarray, shape (S, H+1), or None
        The guard's shrink factor applied at each step (0..1).
    flags : dict of str to ndarray of bool, shape (S,), or None
        Keys :attr:`hybridship.forecast_inputs.FaultFlags.ALL`: what was degraded at each start
        (sensor faults in the start window, clipped inputs, the hybrid's correction
        shrunk by the guard).
    notes : tuple of str, length S, or None
        What was done about each start's faults ("" when clean).

    Raises
    ------
    TypeError, ValueError
        On construction, parts that do not fit together (an array of another shape than
        its start and lead times give, a flag missing, a note per start too few), naming it.
    """

    start_time_s: np.ndarray
    lead_s: np.ndarray
    eta: np.ndarray
    nu: np.ndarray
    eta_std: np.ndarray | None = None
    guard_weight: np.ndarray | None = None
    flags: dict | None = None
    notes: tuple | None = None

    def __post_init__(self):
        # checked once here: a mismatch surfaced only in to_frame, as pandas' "All arrays must
        # be of the same length", an AttributeError for lists or a KeyError for a missing flag
        for name in ("start_time_s", "lead_s", "eta", "nu", "eta_std", "guard_weight"):
            value = getattr(self, name)
            if value is None and name in ("eta_std", "guard_weight"):
                continue
            arr = np.asarray(value)
            if arr.dtype.kind not in "iuf":
                raise TypeError(f"ForecastResult: {name}: expected an array of real numbers, got dtype {arr.dtype}")
            setattr(self, name, arr)
        self.eta = _on_start_branch(self.eta)
        S, H1 = self.start_time_s.size, self.lead_s.size
        if self.start_time_s.ndim != 1 or self.lead_s.ndim != 1:
            raise ValueError(f"ForecastResult: start_time_s and lead_s: expected 1-D arrays, got shapes "
                             f"{self.start_time_s.shape} and {self.lead_s.shape}")
        shapes = {"eta": (S, H1, 3), "nu": (S, H1, 3), "eta_std": (S, H1, 3), "guard_weight": (S, H1)}
        for name, shape in shapes.items():
            value = getattr(self, name)
            if value is not None and value.shape != shape:
                raise ValueError(f"ForecastResult: {name}: expected shape {shape} (S = {S} start times, "
                                 f"H+1 = {H1} lead times), got {value.shape}")
        if self.flags is not None:
            missing = [k for k in FaultFlags.ALL if k not in self.flags]
            bad = [k for k in FaultFlags.ALL if k in self.flags and np.shape(self.flags[k]) != (S,)]
            if missing or bad:
                raise ValueError(f"ForecastResult: flags: expected one flag per start time ({S},) for each of "
                                 f"{', '.join(FaultFlags.ALL)}; missing {missing or 'none'}, of another shape "
                                 f"{bad or 'none'}")
        if self.notes is not None and (isinstance(self.notes, str) or len(self.notes) != S):
            got = repr(self.notes) if isinstance(self.notes, str) else len(self.notes)
            raise ValueError(f"ForecastResult: notes: expected one note per start time ({S}), got {got}")

    def quantiles(self, q) -> np.ndarray:
        """Gaussian quantiles of ``eta`` from ``eta_std``: shape (len(q), S, H+1, 3) [m, m, rad].

        With a calibrated spread (the hybrid's default) these are the calibrated bands;
        ``q`` are probabilities in (0, 1). The calibration fits one level (by default that
        95.45 % of the absolute errors lie within 2 standard deviations: the quantiles 0.02275
        and 0.97725); the bands at other levels follow from the Gaussian shape, not from the
        held-back errors (with heavy-tailed errors the 1-sigma band covers more than 68 %),
        and a one-sided quantile assumes errors symmetric about the forecast.
        """
        from scipy.stats import norm

        q = checked_quantiles(q)
        if self.eta_std is None:
            raise ValueError("quantiles: this forecast has no spread (eta_std is None)")
        z = norm.ppf(q)[:, None, None, None]
        return self.eta[None] + z * self.eta_std[None]

    def to_frame(self, quantiles=()) -> pd.DataFrame:
        """Tidy table: one row per start time and lead time, degrees at this edge.

        ``quantiles`` (probabilities) add columns ``north_q<q>_m``, ``east_q<q>_m`` and
        ``heading_q<q>_deg`` (see :meth:`quantiles`). ``heading_deg`` is wrapped to [0, 360);
        the heading quantiles are that wrapped heading plus their offsets from it, so a band
        that crosses north reads, for example, -3 to 7 deg around a heading of 2 deg.
        """
        S, H1, _ = self.eta.shape
        psi_wrapped = wrap_2pi(self.eta[..., 2])
        cols = {
            "start_time_s": np.repeat(self.start_time_s, H1),
            "lead_s": np.tile(self.lead_s, S),
            "time_s": (self.start_time_s[:, None] + self.lead_s[None, :]).ravel(),
            "north_m": self.eta[..., 0].ravel(),
            "east_m": self.eta[..., 1].ravel(),
            "heading_deg": np.degrees(psi_wrapped).ravel(),
            "u_m_s": self.nu[..., 0].ravel(),
            "v_m_s": self.nu[..., 1].ravel(),
            "r_deg_s": np.degrees(self.nu[..., 2]).ravel(),
        }
        if self.eta_std is not None:
            cols["north_std_m"] = self.eta_std[..., 0].ravel()
            cols["east_std_m"] = self.eta_std[..., 1].ravel()
            cols["heading_std_deg"] = np.degrees(self.eta_std[..., 2]).ravel()
        if np.size(quantiles):
            Q = self.quantiles(quantiles)
            for q, eq in zip(checked_quantiles(quantiles), Q):
                label = quantile_label(q)
                cols[f"north_q{label}_m"] = eq[..., 0].ravel()
                cols[f"east_q{label}_m"] = eq[..., 1].ravel()
                cols[f"heading_q{label}_deg"] = np.degrees(psi_wrapped + (eq[..., 2] - self.eta[..., 2])).ravel()
        if self.guard_weight is not None:
            cols["guard_weight"] = self.guard_weight.ravel()
        if self.flags is not None:
            for name in FaultFlags.ALL:
                cols[name] = np.repeat(np.asarray(self.flags[name], dtype=bool), H1)
        if self.notes is not None:
            cols["notes"] = np.repeat(np.asarray(self.notes, dtype=object), H1)
        return pd.DataFrame(cols)


def _on_start_branch(eta: np.ndarray) -> np.ndarray:
    """``eta`` with each forecast's heading shifted by whole turns so that its start lies in
    [0, 2 pi) (a copy; shapes other than (S, H+1, 3), or a NaN start, are left alone)."""
    if eta.ndim != 3 or eta.shape[-1] != 3 or eta.shape[1] == 0:
        return eta
    psi0 = eta[:, 0, 2]
    turns = np.where(np.isfinite(psi0), np.floor((psi0 - wrap_2pi(psi0)) / (2.0 * np.pi) + 0.5), 0.0)
    if not turns.any():
        return eta
    out = np.array(eta, dtype=float)
    out[..., 2] -= 2.0 * np.pi * turns[:, None]
    return out
