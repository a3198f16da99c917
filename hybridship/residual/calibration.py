"""Spread calibration: a per-horizon scale of the ensemble's standard deviation.

An ensemble's spread measures how much its members disagree, not how large the forecast
error is; on the drift and manoeuvre benchmarks its raw 2-sigma band covered anywhere
between a third and nine tenths of the outcomes. The calibration fixes this on held-back
data (forecasts the model did not train on, made the way the model is used):

.. math::  s_{cal}(h) = k(h) \\, \\max(s(h), s_{floor}(h)),

with ``k(h)`` the split-conformal scale of the normalised error at lead ``h``: the
``coverage`` quantile of ``|e| / max(s, s_floor)`` divided by ``sigma``, so that exactly
``coverage`` of the held-back errors lie inside ``sigma`` calibrated standard deviations
(2 sigma, 95.45 % by default: the scored band). ``s_floor(h)`` is a low quantile of the
held-back spreads: where the guard has shrunk the correction the members agree and the raw
spread goes to zero while the physics still errs, and a scale on a zero spread is no
spread at all.

Optionally (``CalibrationConfig.spread_exponent``) the raw spread enters with an exponent
``b`` in [0, 1], ``s_cal = k(h) max(s, s_floor)^b``: 1 (the default) trusts the members'
disagreement as a measure of the error, 0 gives every start the same band, and values in
between keep the ranking of the starts while narrowing the band where the members
disagree most. ``"likelihood"`` chooses ``b`` from a grid by the Gaussian likelihood of the
held-back errors over all lead times (one ``b`` per calibration, so that ``k``, in the
spread's unit to the power ``1 - b``, interpolates between leads), each ``b`` with its own
conformal ``k``. The same held-back errors choose ``b`` and fit ``k``, so the finite-sample
level of the conformal quantile holds only approximately then (one of 11 candidates is
picked).

Why one scale per horizon and not a full set of conformal quantiles: the forecast reports
a standard deviation (and Gaussian quantiles from it), the scale is one number per lead
time that is easy to store and to check, and it keeps the ensemble's ranking of starts
(wide where the members disagree). With heavy-tailed errors a scale fitted at 2 sigma
gives more than 68 % at 1 sigma; both are reported by the benchmarks.

The functions here take plain arrays (absolute errors and spreads per horizon), so any
forecaster (the hybrid on manoeuvres, the drift forecasts) can use them.
"""

from __future__ import annotations

import numbers
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from hybridship.config import (Bool, Float, Int, NonEmpty, check_number,
                               check_whole_number, config_dataclass, float_array, real_array)

#: Two-sided coverage of +-1 and +-2 standard deviations of a Gaussian.
GAUSS_COVERAGE = {1.0: 0.6826894921370859, 2.0: 0.9544997361036416}


@config_dataclass(frozen=True)
class CalibrationConfig:
    """How :meth:`hybridship.predictors.HybridPredictor.fit` calibrates the spread (validated).

    Attributes
    ----------
    fraction : float
        Share of each training log held back for calibration, 0 <= fraction < 0.6: the
        last part in time order of the rows the nets may train on (with ``dp_only``, of
        the station-keeping rows; the scale then applies only to forecasts that start
        while station keeping is on, and a start after a failure keeps the raw spread).
        0 switches calibration off (the raw ensemble spread).
    commands : tuple of str
        Command modes to calibrate (``"held"``, ``"known"``): the calibration forecasts are
        made in each mode and a forecast uses the scale of its own mode.
    horizon_s : float
        Longest calibrated lead time [s]; beyond it the last scale is held. The held-back
        part of a log is made at least ``horizon_s`` plus 10 % long when the log allows
        (at most half of it). A whole number of each training log's steps (within a
        forecast's tolerance): :meth:`~hybridship.predictors.HybridPredictor.fit` refuses
        another before any training.
    start_every_s : float or None
        Spacing of calibration start times [s]; None picks one that gives about
        ``max_starts`` starts per mode.
    max_starts : int
        Upper bound of calibration starts per mode when ``start_every_s`` is None.
    sigma, coverage : float
        Fit the scale so that ``coverage`` of held-back errors lie within ``sigma``
        calibrated standard deviations (default: 2 sigma, 95.45 %).
    floor_quantile : float
        Quantile of the held-back spreads used as the spread floor at each lead time.
    refit : bool
        After calibrating, refit the nets on all the training rows (the held-back part
        included) and keep the scale. Off by default: the scale is then exact for the
        nets that are shipped (a refit model is a little better than the one calibrated,
        so its band would be a little wide), and training costs half.
    spread_exponent : float in [0, 1] or "likelihood"
        Exponent of the raw spread in the calibrated one (module docstring): 1 (default)
        scales the members' spread; ``"likelihood"`` chooses it on the held-back errors,
        from :data:`EXPONENT_GRID`. It applies to the station-keeping (or manoeuvre)
        calibration and to the calibration after a failure alike.
    station_keeping_spread : {"held_load", "ensemble"}
        The raw spread that is calibrated for forecasts starting during station keeping
        (with the environment estimator and ``held_load_window_s > 0``; otherwise the
        members' spread). ``"held_load"`` (default): the spread ``0.5 sigma_b t^2`` of the
        load's variability over the station keeping before the start
        (:func:`~hybridship.residual.load_variability.held_load_spread`, the term the spread
        after a failure adds), which grows with the weather the ship is in;
        ``forecast(..., calibrated=False)`` then reports that spread for such starts.
        ``"ensemble"``: the members' spread, which, amplified by each member's own previous
        residual, does not rank the weathers (measured in ``docs/concepts/residual.md``).
        Model files written before this option read as ``"ensemble"``, what they were
        calibrated on.
    after_stop_min_failures : int
        With at least this many DP failures in the training logs (a thrust stop followed by
        ``horizon_s`` of drift after each of 20 start times), :meth:`fit` also calibrates
        the spread of forecasts after a failure on them
        (:meth:`~hybridship.predictors.HybridPredictor.calibrate_after_stop`): the vessel's
        own failures, not simulated ones. 0: never.
    """

    fraction: Annotated[Float, Field(ge=0, lt=0.6)] = 0.2
    commands: Annotated[tuple[Literal["held", "known"], ...], NonEmpty] = ("held", "known")
    horizon_s: Annotated[Float, Field(gt=0)] = 60.0
    start_every_s: Annotated[Float, Field(gt=0)] | None = None
    max_starts: Annotated[Int, Field(ge=10)] = 2000
    sigma: Annotated[Float, Field(gt=0)] = 2.0
    coverage: Annotated[Float, Field(gt=0, lt=1)] = GAUSS_COVERAGE[2.0]
    floor_quantile: Annotated[Float, Field(ge=0, lt=0.5)] = 0.1
    refit: Bool = False
    spread_exponent: float | str = 1.0
    station_keeping_spread: Literal["held_load", "ensemble"] = "held_load"
    after_stop_min_failures: Annotated[Int, Field(ge=0)] = 3

    @property
    def fit_kwargs(self) -> dict:
        """The keywords of :func:`fit_spread_scale` that this configuration sets."""
        return dict(sigma=self.sigma, coverage=self.coverage, floor_quantile=self.floor_quantile,
                    exponent=self.spread_exponent)

    @field_validator("spread_exponent", mode="before")
    @classmethod
    def _exponent(cls, v):
        return _checked_exponent(v)

    @field_validator("commands")
    @classmethod
    def _distinct(cls, v):
        if len(set(v)) != len(v):
            raise ValueError(f"each mode at most once, got {v!r}")
        return v


_NonNegVector = float_array(flat=True, lo=0.0)


@config_dataclass(arbitrary_types=True)
class SpreadCalibration:
    """Per-lead-time scale and floor of a standard deviation.

    Attributes
    ----------
    lead_s : ndarray, shape (H,)
        Lead times [s] (increasing, > 0).
    scale : ndarray, shape (H,)
        Multiplier of the (floored) raw spread.
    floor : ndarray, shape (H,)
        Lower bound of the raw spread, in its unit.
    exponent : float
        Exponent of the (floored) raw spread, in [0, 1], one for every lead; default 1 (the
        spread scaled). Below 1 the scale carries the spread's unit to the power
        ``1 - exponent``.
    """

    lead_s: _NonNegVector
    scale: _NonNegVector
    floor: _NonNegVector
    exponent: Annotated[Float, Field(ge=0, le=1)] = 1.0

    @model_validator(mode="after")
    def _aligned(self):
        n = self.lead_s.size
        if n == 0 or self.scale.size != n or self.floor.size != n:
            raise ValueError(f"lead_s: lead_s, scale and floor need one equal non-zero length, "
                             f"got {self.lead_s.size}, {self.scale.size}, {self.floor.size}")
        if np.any(self.lead_s <= 0):
            # the start has no error to scale; its entry set the scale of the leads before the first
            raise ValueError(f"lead_s: expected lead times > 0 [s] (leave out the start, lead 0), "
                             f"got {self.lead_s.tolist()}")
        if np.any(np.diff(self.lead_s) <= 0):
            raise ValueError("lead_s: must increase")
        return self

    def apply(self, std: np.ndarray, lead_s: np.ndarray) -> np.ndarray:
        """Calibrated spread ``scale(h) * max(std, floor(h)) ** exponent``.

        ``std`` has the lead time on its last axis, matching ``lead_s`` [s] (held constant
        beyond the calibrated leads); lead 0 (the start) and a spread that is not finite are
        returned unchanged.

        Raises
        ------
        TypeError, ValueError
            ``std`` or ``lead_s`` not real numbers (text), a negative spread, lead times that
            are not finite and >= 0, or a last axis of ``std`` other than ``len(lead_s)``, naming
            the argument.
        """
        std = real_array("SpreadCalibration.apply: std", std)
        lead_s = real_array("SpreadCalibration.apply: lead_s", lead_s)
        if lead_s.ndim != 1 or not np.all(np.isfinite(lead_s) & (lead_s >= 0)):
            raise ValueError(f"SpreadCalibration.apply: lead_s: expected a 1-D array of finite lead times >= 0 [s], "
                             f"got shape {lead_s.shape}")
        if std.ndim == 0 or std.shape[-1] != lead_s.size:
            raise ValueError(f"SpreadCalibration.apply: std: expected the lead time on the last axis, of length "
                             f"len(lead_s) = {lead_s.size}; got shape {std.shape}")
        if np.any(std < 0):         # a NaN is passed on unchanged; a negative spread was floored silently
            raise ValueError("SpreadCalibration.apply: std: expected standard deviations >= 0")
        k = np.interp(lead_s, self.lead_s, self.scale)
        f = np.interp(lead_s, self.lead_s, self.floor)
        out = k * np.maximum(std, f) ** self.exponent
        return np.where((lead_s > 0) & np.isfinite(std), out, std)


#: Exponents tried by ``fit_spread_scale(..., exponent="likelihood")``.
EXPONENT_GRID = np.linspace(0.0, 1.0, 11)


def _checked_exponent(v):
    """``v`` as a float in [0, 1], or ``"likelihood"``; ValueError saying what was expected."""
    if isinstance(v, str) and v == "likelihood":
        return v
    if isinstance(v, numbers.Real) and not isinstance(v, bool) and 0 <= v <= 1:
        return float(v)
    raise ValueError(f"must be a number in [0, 1] or 'likelihood', got {v!r}")


#: Fewest finite forecast errors per lead that :func:`fit_spread_scale` fits a scale on.
MIN_CALIBRATION_SAMPLES = 20


def fit_spread_scale(abs_err, std, lead_s, *, sigma: float = 2.0, coverage: float = GAUSS_COVERAGE[2.0],
                     floor_quantile: float = 0.1, min_samples: int = MIN_CALIBRATION_SAMPLES,
                     exponent: float | str = 1.0) -> SpreadCalibration:
    """Fit a per-lead-time spread scale from held-back forecasts.

    Parameters
    ----------
    abs_err : ndarray, shape (N, H)
        Absolute forecast errors (N samples, e.g. starts x north/east, pooled) at H lead times.
    std : ndarray, shape (N, H)
        The forecaster's raw standard deviations for the same samples, same unit.
    lead_s : ndarray, shape (H,)
        Lead times [s], increasing, > 0.
    sigma, coverage : float
        Fraction ``coverage`` of the samples shall lie within ``sigma`` calibrated spreads.
    floor_quantile : float
        The spread floor at each lead is this quantile of ``std`` there.
    min_samples : int
        Fewest finite samples per lead time.
    exponent : float in [0, 1] or "likelihood"
        Exponent ``b`` of the floored raw spread; ``"likelihood"``: the one of
        :data:`EXPONENT_GRID` whose calibrated spreads give the held-back errors the largest
        Gaussian likelihood, summed over the lead times.

    Returns
    -------
    SpreadCalibration
        ``scale[h]`` is the split-conformal quantile (the ``k``-th smallest of the ``n``
        finite samples, ``k = min(n, ceil((n + 1) coverage))``) of ``abs_err / max(std, floor) ** b``
        divided by ``sigma``. With fewer than ``coverage / (1 - coverage)`` samples (21 at
        95.45 %) ``k`` is ``n``, the largest, which holds only ``n / (n + 1)``.

    Raises
    ------
    TypeError, ValueError
        An argument of the wrong kind, shape or range (text, negative errors or spreads,
        a lead time that is not > 0, fewer than ``min_samples`` finite samples at a lead),
        naming it.
    """
    e, s, lead = (real_array(f"fit_spread_scale: {name}", a)
                  for name, a in (("abs_err", abs_err), ("std", std), ("lead_s", lead_s)))
    lead = lead.ravel()
    if e.ndim != 2 or e.shape != s.shape or e.shape[1] != lead.size:
        raise ValueError(f"fit_spread_scale: abs_err and std must be (N, H) with H = len(lead_s); got "
                         f"{e.shape}, {s.shape}, {lead.size}")
    if not np.all(np.isfinite(lead) & (lead > 0)):
        # the start's column (no error, no spread) chose the exponent and scaled the leads after it
        raise ValueError(f"fit_spread_scale: lead_s: expected finite lead times > 0 [s] (leave out the start, "
                         f"lead 0), got {lead.tolist()}")
    if lead.size == 0 or np.any(np.diff(lead) <= 0):
        # checked here, not after the fit by SpreadCalibration (in words of its scale and floor)
        raise ValueError(f"fit_spread_scale: lead_s: expected at least one lead time, increasing, got {lead.tolist()}")
    sigma = check_number("fit_spread_scale: sigma", sigma, lo=0, lo_open=True)
    coverage = check_number("fit_spread_scale: coverage", coverage, lo=0, lo_open=True)
    if coverage >= 1:
        raise ValueError(f"fit_spread_scale: coverage: must be < 1, got {coverage!r}")
    floor_quantile = check_number("fit_spread_scale: floor_quantile", floor_quantile, lo=0)
    if floor_quantile >= 0.5:
        raise ValueError(f"fit_spread_scale: floor_quantile: must be < 0.5, got {floor_quantile!r}")
    # 0 would let a lead without a single sample through to an empty quantile (IndexError)
    min_samples = check_whole_number("fit_spread_scale: min_samples", min_samples, lo=1)
    if np.any(e < 0):
        raise ValueError("fit_spread_scale: abs_err must be >= 0 (absolute errors)")
    if np.any(s < 0):
        # a negative spread fell to the 1e-12 floor and came out as a scale of about 1e12
        raise ValueError("fit_spread_scale: std must be >= 0 (standard deviations)")
    try:
        exponent = _checked_exponent(exponent)
    except ValueError as err:
        raise ValueError(f"fit_spread_scale: exponent {err}") from None
    grid = EXPONENT_GRID if exponent == "likelihood" else np.array([exponent])
    H = lead.size
    floor = np.empty(H)
    tiny = 1e-12
    samples = []
    for h in range(H):
        ok = np.isfinite(e[:, h]) & np.isfinite(s[:, h])
        n = int(ok.sum())
        if n < min_samples:
            raise ValueError(f"fit_spread_scale: {n} finite samples at lead {lead[h]:g} s; need {min_samples}")
        floor[h] = max(float(np.quantile(s[ok, h], floor_quantile)), tiny)
        # the k-th smallest of n, k = ceil((n + 1) coverage): the split-conformal quantile
        # (np.quantile(x, k / n, method="higher") is the (k + 1)-th: one order statistic too high)
        samples.append((e[ok, h], np.maximum(s[ok, h], floor[h]), min(n, int(np.ceil((n + 1) * coverage)))))
    best = None
    for b in grid:
        scale = np.empty(H)
        nll = 0.0
        for h, (eh, sh, k) in enumerate(samples):
            base = sh ** b
            scale[h] = float(np.partition(eh / base, k - 1)[k - 1]) / sigma
            # Gaussian negative log-likelihood of the held-back errors under this spread
            sd = max(scale[h], tiny) * base
            nll += float(np.mean(np.log(sd) + 0.5 * (eh / sd) ** 2))
        if best is None or nll < best[0]:
            best = (nll, scale, b)
    _, scale, b = best
    return SpreadCalibration(lead, scale, floor, float(b))


def coverage_of(abs_err, std, sigmas=(1.0, 2.0)) -> np.ndarray:
    """Share of samples with ``abs_err <= k * std`` per lead time, (H, len(sigmas)); inputs (N, H).

    Raises
    ------
    TypeError, ValueError
        Text instead of numbers, ``abs_err`` and ``std`` not of one shape (N, H) with N >= 1,
        a NaN or infinite value (it would count as a miss without a word: leave such samples
        out first), a negative error or spread, or ``sigmas`` not positive finite band
        half-widths, naming the argument.
    """
    e = real_array("coverage_of: abs_err", abs_err)
    s = real_array("coverage_of: std", std)
    if e.ndim != 2 or e.shape != s.shape or e.shape[0] == 0:
        raise ValueError(f"coverage_of: abs_err and std: expected one shape (N, H) with N >= 1; got {e.shape} "
                         f"and {s.shape}")
    for name, a in (("abs_err", e), ("std", s)):
        if not np.all(np.isfinite(a)):
            raise ValueError(f"coverage_of: {name}: NaN or inf; leave such samples out before counting")
        if np.any(a < 0):
            raise ValueError(f"coverage_of: {name}: expected values >= 0")
    k = real_array("coverage_of: sigmas", sigmas)
    if k.ndim != 1 or k.size == 0 or not np.all(np.isfinite(k) & (k > 0)):
        raise ValueError(f"coverage_of: sigmas: expected a list of positive finite band half-widths, got {sigmas!r}")
    return np.stack([(e <= x * s).mean(axis=0) for x in k], axis=1)
