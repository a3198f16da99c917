"""Planning mode: Monte-Carlo blackouts for one weather state and a set of headings.

:func:`simulate_blackouts` draws ``n_samples`` perturbed vessels and environment samples
(common to all headings, so that headings are compared on the same draws), integrates all
``headings x samples`` blackouts in one kernel call (:mod:`hybridship.driftoff.engine`)
and returns a :class:`DriftOffResult`:

* the time to reach each radius, per heading and sample (``inf`` when not reached within
  the horizon);
* the probability of exceeding each radius within each reaction time,
  ``P(T_r <= t_react)``;
* the watch-circle radius: the largest distance from the blackout position reached up to
  the reaction time, at a chosen quantile (a circle the vessel stays inside, with that
  probability, until the operator has reacted).

Randomness: one :class:`numpy.random.SeedSequence` ``(seed, spawn_key=(index,))`` per
weather state, so a state's samples depend on its index in a sweep, never on how the
sweep is chunked.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field, field_validator, model_validator

from ..config import Float, Int, NonEmpty, as_config, check_whole_number, config_dataclass
from ..frames import wrap_2pi
from ..physics.model import DynamicModel
from ..sim import environment as env
from . import engine, spread
from .weather import WeatherState, WeatherUncertainty, sample_environment

__all__ = ["DriftOffSettings", "DriftOffResult", "simulate_blackouts", "state_rng", "get_model", "hull_array"]

#: Most Monte-Carlo samples per heading (:attr:`DriftOffSettings.n_samples`); also the most
#: environment members a live estimate needs (each sample takes one).
MAX_SAMPLES = 1_000_000
#: Most wave components and gust harmonics per sample: the simulator uses 50 and 200; each
#: one is evaluated for every sample at every step (time and memory grow with it).
MAX_COMPONENTS = 1000
#: Largest vessel spread: at 5 a one-sigma draw of Gunnerus already has 3.7 times its linear
#: surge damping; beyond, the draws are no ship an identification would give and their
#: drifts diverge (at 1e9 the factors overflow).
MAX_VESSEL_SPREAD = 5.0
#: Most steps of one drift (:attr:`DriftOffSettings.horizon_s` over ``dt_s``): one day at 1 s.
#: Each step is taken by every sample; a tiny ``dt_s`` would otherwise make a run of days.
MAX_STEPS = 86_400


@lru_cache(maxsize=8)
def _model_by_name(name: str) -> DynamicModel:
    return DynamicModel(name)


def get_model(vessel) -> DynamicModel:
    """A nominal :class:`DynamicModel` from a model, a vessel, or a packaged name / file path (cached)."""
    if isinstance(vessel, DynamicModel):
        return vessel
    if isinstance(vessel, str):
        return _model_by_name(vessel)
    return DynamicModel(vessel)


def hull_array(vessel) -> np.ndarray:
    """The wave-drift hull constants (``engine.HULL_FIELDS``) of a vessel, as the simulator builds them."""
    p = vessel.particulars
    h = env.HullDimensions(L_m=p.L_pp_m, B_m=p.B_m, T_m=p.T_m)
    return np.array([h.L_m, h.B_m, h.T_m, h.bow_factor, h.side_factor, h.yaw_lever_factor,
                     p.rho_water_kg_m3, env.G_M_S2])


def state_rng(seed: int, index: int = 0) -> np.random.Generator:
    """The random generator of weather state ``index`` of a run seeded with ``seed``."""
    # int() read a seed of 1.7 or True as 1, and "3" as 3: another run's stream, without a word
    seed, index = check_whole_number("seed", seed), check_whole_number("index", index)
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(index,)))


def _reals(value) -> np.ndarray | None:
    """``value`` (a number, or a list, tuple or array of numbers) as a float array of its own,
    or None when it is something else: numpy would read text ("0.9"), bools and complex
    numbers as numbers or fail in its own words, and a set or generator has no order."""
    if isinstance(value, (np.ndarray, pd.Series)) and value.dtype.kind in "iuf":
        return np.array(value, dtype=float)
    if isinstance(value, (str, bytes, bool, np.bool_)) or not isinstance(
            value, (numbers.Real, Sequence, np.ndarray, pd.Series, pd.Index)):
        return None
    items = np.array(value, dtype=object)
    if not all(isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_)) for x in items.flat):
        return None
    return items.astype(float)


@config_dataclass(frozen=True)
class DriftOffSettings:
    """Numerical settings of a drift-off study (validated; errors name the field).

    Attributes
    ----------
    radii_m : tuple of float
        Limit radii from the blackout position [m], each once.
    reaction_times_s : tuple of float
        Operator reaction times [s], each once.
    n_samples : int
        Monte-Carlo samples per heading (at most :data:`MAX_SAMPLES`, 10^6).
    horizon_s : float
        Longest simulated drift [s] (at most one day), a whole number of ``dt_s`` steps;
        radii not reached by then count as never reached.
    dt_s : float
        Output step [s] (RK4, inputs held over a step), at most 1 s (the RK4 step the physics
        inputs' envelope allows: longer steps diverge in a fast drift), and at least
        ``horizon_s`` / :data:`MAX_STEPS`.
    rpm_time_constant_s : float
        First-order spin-down time constant of the thrusters [s].
    vessel_spread : float
        Multiplier of the ``[true_vessel]`` spread (0 = nominal model, see :mod:`.spread`), at
        most :data:`MAX_VESSEL_SPREAD` (5): beyond, the drawn vessels are no ship and their
        drifts diverge.
    n_wave_components, n_gust_harmonics : int
        Wave components and gust harmonics per sample, at most :data:`MAX_COMPONENTS` (1000;
        the simulator uses 50 and 200): each costs every sample at every step, in time and memory.
    seed : int
        Seed of the run, 0 to 2**32 - 1 as in every command (each weather state uses
        ``SeedSequence(seed, spawn_key=(index,))``).
    """

    radii_m: Annotated[tuple[Annotated[Float, Field(gt=0)], ...], NonEmpty] = (3.0, 5.0, 10.0)
    reaction_times_s: Annotated[tuple[Annotated[Float, Field(ge=0)], ...], NonEmpty] = (30.0, 60.0)
    n_samples: Annotated[Int, Field(ge=1, le=MAX_SAMPLES)] = 100
    horizon_s: Annotated[Float, Field(gt=0, le=86400.0)] = 300.0
    dt_s: Annotated[Float, Field(gt=0, le=1.0)] = 1.0
    rpm_time_constant_s: Annotated[Float, Field(gt=0)] = 1.5
    vessel_spread: Annotated[Float, Field(ge=0, le=MAX_VESSEL_SPREAD)] = 1.0
    n_wave_components: Annotated[Int, Field(ge=1, le=MAX_COMPONENTS)] = 20
    n_gust_harmonics: Annotated[Int, Field(ge=1, le=MAX_COMPONENTS)] = 20
    seed: Annotated[Int, Field(ge=0, le=2**32 - 1)] = 0

    @field_validator("radii_m", "reaction_times_s", mode="before")
    @classmethod
    def _one_or_many(cls, v):
        return tuple(np.atleast_1d(v).tolist()) if np.ndim(v) == 0 or isinstance(v, np.ndarray) else v

    @field_validator("radii_m")
    @classmethod
    def _sorted(cls, v):
        return tuple(sorted(v))

    @field_validator("radii_m", "reaction_times_s")
    @classmethod
    def _each_once(cls, v):
        # a repeated one (or two that print alike in the tables' column names and rows, 30 and
        # 30.00001) would give repeated rows and merged columns
        if len({f"{x:g}" for x in v}) != len(v):
            raise ValueError(f"expected each value once (as printed to 6 digits), got {', '.join(map(repr, v))}")
        return v

    @model_validator(mode="after")
    def _within_horizon(self):
        if self.dt_s > self.horizon_s:
            raise ValueError(f"dt_s: must be <= the horizon ({self.horizon_s:g} s), got {self.dt_s!r}")
        steps = self.horizon_s / self.dt_s
        if steps > MAX_STEPS + 1e-6:
            raise ValueError(f"dt_s: expected at least {self.horizon_s / MAX_STEPS:g} s ({MAX_STEPS} steps over "
                             f"the {self.horizon_s:g}-s horizon at most), got {self.dt_s!r}")
        if abs(steps - round(steps)) > 1e-6:
            raise ValueError(f"horizon_s: must be a whole number of steps of {self.dt_s:g} s, got "
                             f"{self.horizon_s!r} (a drift is simulated in whole steps)")
        if max(self.reaction_times_s) > self.horizon_s:
            raise ValueError(f"reaction_times_s: must be <= the horizon ({self.horizon_s:g} s), "
                             f"got {', '.join(f'{t:g}' for t in self.reaction_times_s)}")
        return self

    @property
    def n_steps(self) -> int:
        """Steps of ``dt_s`` over the horizon: the whole number the validation found
        ``horizon_s / dt_s`` to be (to 1e-6), rounded to it from either side."""
        return int(round(self.horizon_s / self.dt_s))


@dataclass(frozen=True)
class DriftOffResult:
    """Monte-Carlo blackouts of one weather state (SI units; see the module notes).

    Attributes
    ----------
    headings_rad : ndarray (H,)
        Vessel headings at the blackout [rad].
    weather_rel_rad : ndarray (H,)
        Mean wind direction (from) relative to the bow [rad] in [0, 2 pi): 0 = head wind,
        pi/2 = wind from starboard.
    radii_m : ndarray (R,)
    reaction_times_s : ndarray (Q,)
    t_reach_s : ndarray (H, N, R)
        Time to reach each radius [s]; ``inf`` if not reached within ``horizon_s``.
    excursion_m : ndarray (H, N, Q)
        Largest distance from the blackout position up to each reaction time [m].
    horizon_s : float
    tracks : ndarray (H, N, S + 1, 3) or None
        ``[north_m, east_m, psi_rad]`` per step when asked for.
    over_capacity_frac : ndarray (H,) or None
        Share of the samples whose holding load before the blackout (the mean environment
        at rest) exceeds the thrusters' bollard capacity in its direction in surge, sway or
        yaw alone (:func:`hybridship.sim.allocation.thrust_capacity_by_sign`): the DP could
        not have held station there, so the blackout's start, at rest on station, is optimistic. A load
        within each capacity alone may still exceed what the thrusters give combined.
    """

    headings_rad: np.ndarray
    weather_rel_rad: np.ndarray
    radii_m: np.ndarray
    reaction_times_s: np.ndarray
    t_reach_s: np.ndarray
    excursion_m: np.ndarray
    horizon_s: float
    tracks: np.ndarray | None = None
    over_capacity_frac: np.ndarray | None = None

    @property
    def n_samples(self) -> int:
        return int(self.t_reach_s.shape[1])

    def time_quantiles(self, q=(0.1, 0.5, 0.9)) -> np.ndarray:
        """Quantiles of the time to reach each radius, (H, R, len(q)) [s], or (H, R) for a single
        number ``q``; ``inf`` where not reached.

        The inverse of the samples' distribution (the smallest time by which a share ``q``
        of the samples reached the radius), so a quantile is finite only when that share did
        reach it: with 7 samples of which 6 reached, the 0.9 quantile is ``inf`` ("never").
        """
        qs = _reals(q)
        if qs is None or qs.ndim > 1 or not np.all((qs >= 0.0) & (qs <= 1.0)):
            raise ValueError(f"q: expected quantiles in [0, 1], got {q!r}")
        out = np.quantile(self.t_reach_s, qs, axis=1, method="inverted_cdf")
        return out if qs.ndim == 0 else np.moveaxis(out, 0, -1)     # a single q has no axis to move

    def p_exceed(self) -> np.ndarray:
        """P(radius exceeded within the reaction time), (H, R, Q)."""
        return (self.t_reach_s[:, :, :, None] <= self.reaction_times_s[None, None, None, :]).mean(axis=1)

    def p_exceed_interval(self, confidence: float = 0.95) -> np.ndarray:
        """The Monte-Carlo error of :meth:`p_exceed`: exact binomial (Clopper-Pearson)
        intervals at ``confidence``, (H, R, Q, 2) [lower, upper].

        With ``k`` of ``N`` samples over the radius, ``[B(a/2; k, N-k+1), B(1-a/2; k+1, N-k)]``
        (``B`` the beta quantile, ``a = 1 - confidence``; 0 and 1 at the ends): the
        probability the model gives lies in it with at least that confidence. It says how
        many samples are enough (10 of 100 gives 0.05-0.18), not how good the model is.
        """
        from scipy.stats import beta

        if isinstance(confidence, (bool, str, bytes)) or not isinstance(confidence, numbers.Real) \
                or not 0.0 < float(confidence) < 1.0:
            raise ValueError(f"confidence: expected a number in (0, 1), got {confidence!r}")
        c = float(confidence)
        n = self.n_samples
        k = np.rint(self.p_exceed() * n)
        a = 1.0 - c
        with np.errstate(invalid="ignore"):
            lo = np.where(k > 0, beta.ppf(a / 2, np.maximum(k, 1), n - k + 1), 0.0)
            hi = np.where(k < n, beta.ppf(1 - a / 2, k + 1, np.maximum(n - k, 1)), 1.0)
        return np.stack([lo, hi], axis=-1)

    def watch_circle(self, quantile: float = 0.9) -> np.ndarray:
        """Watch-circle radii (H, Q) [m]: the ``quantile`` of the excursion up to each reaction time.

        The inverse of the samples' distribution, as :meth:`time_quantiles`: the smallest radius
        that at least a share ``quantile`` of the samples stay inside up to the reaction time
        (an interpolated quantile would leave fewer inside: 6 of 7 at 0.9).
        """
        if isinstance(quantile, (bool, np.bool_)) or not isinstance(quantile, numbers.Real) \
                or not 0.0 < float(quantile) < 1.0:        # "0.9" and True are not quantiles
            raise ValueError(f"quantile: expected a number in (0, 1), got {quantile!r}")
        return np.quantile(self.excursion_m, float(quantile), axis=1, method="inverted_cdf")

    def exceedance_curves(self, time_s) -> np.ndarray:
        """P(T_r <= t) on the times ``time_s`` (T,) [s], shape (H, R, T)."""
        t = _reals(time_s)
        if t is None or np.ndim(t) > 1 or not np.all(np.isfinite(t) & (t >= 0.0)):
            raise ValueError(f"time_s: expected finite times >= 0 s, got {time_s!r}")
        t = np.atleast_1d(t)
        return (self.t_reach_s[:, :, :, None] <= t[None, None, None, :]).mean(axis=1)

    def summary_frames(self, quantile: float = 0.9) -> tuple[pd.DataFrame, pd.DataFrame]:
        """Two tidy tables: time to reach per (heading, radius), with P(exceed) and its 95 %
        Monte-Carlo interval (:meth:`p_exceed_interval`) per reaction time, and watch circles
        per (heading, reaction time)."""
        wc = self.watch_circle(quantile)        # first: checks ``quantile`` before the tables' work
        tq = self.time_quantiles((0.1, 0.5, 0.9))
        pe = self.p_exceed()
        ci = self.p_exceed_interval(0.95)
        rows = []
        for h, psi in enumerate(self.headings_rad):
            for r, rad in enumerate(self.radii_m):
                row = {"heading_deg": math.degrees(psi) % 360.0,
                       "wind_rel_deg": math.degrees(self.weather_rel_rad[h]) % 360.0, "radius_m": rad,
                       "t_p10_s": tq[h, r, 0], "t_p50_s": tq[h, r, 1], "t_p90_s": tq[h, r, 2],
                       "reached_frac": float(np.isfinite(self.t_reach_s[h, :, r]).mean())}
                if self.over_capacity_frac is not None:
                    row["over_capacity_frac"] = float(self.over_capacity_frac[h])
                for q, tr in enumerate(self.reaction_times_s):
                    row[f"p_exceed_{tr:g}s"] = pe[h, r, q]
                    row[f"p_exceed_{tr:g}s_ci95_lo"], row[f"p_exceed_{tr:g}s_ci95_hi"] = ci[h, r, q]
                rows.append(row)
        times = pd.DataFrame(rows)
        rows = [{"heading_deg": math.degrees(psi) % 360.0,
                 "wind_rel_deg": math.degrees(self.weather_rel_rad[h]) % 360.0, "reaction_time_s": tr,
                 "quantile": quantile, "watch_radius_m": wc[h, q]}
                for h, psi in enumerate(self.headings_rad) for q, tr in enumerate(self.reaction_times_s)]
        return times, pd.DataFrame(rows)


def check_headings(headings_rad) -> np.ndarray:
    """Headings [rad] as a 1-D array (a copy: the result keeps it), refused when empty, not
    finite, in degrees or repeated, and, as a TypeError, when not a number or a list, tuple or
    array of numbers (text and bools would read as angles; a set has no order)."""
    a = _reals(headings_rad)
    if a is None:
        raise TypeError(f"headings: expected a number or a list of numbers (angles in radians, in order), got "
                        f"{type(headings_rad).__name__} {headings_rad!r}")
    a = np.atleast_1d(a)
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"headings: expected a non-empty list of finite angles, got {headings_rad!r}")
    if np.any(np.abs(a) > 2.0 * np.pi + 0.1):
        raise ValueError(f"headings: expected radians (within +-2 pi), got {a.tolist()} (degrees? convert with "
                         f"numpy.radians)")
    # on the circle: 30 and -330 deg are one heading, whose float remainders differ in the last bits
    w = np.sort(np.mod(a, 2.0 * np.pi))
    if np.min(np.diff(np.append(w, w[0] + 2.0 * np.pi))) < 1e-9:
        raise ValueError(f"headings: expected each heading once, got {a.tolist()}")
    return a


def refuse_diverged(excursion_m: np.ndarray, reaction_times_s, what: str) -> None:
    """Raise FloatingPointError when a drift diverged (the kernel marks a sample whose
    excursion outran :data:`~hybridship.driftoff.engine.MAX_DRIFT_SPEED_M_S` or turned NaN
    while it was integrated, up to its early stop, with a NaN excursion; an excursion beyond
    it up to a reaction time is refused too): no result, not "never reached"."""
    with np.errstate(invalid="ignore"):
        bad = ~(excursion_m <= engine.MAX_DRIFT_SPEED_M_S * np.asarray(reaction_times_s, float) + 1.0)
    if bad.any():
        n_bad = int(bad.reshape(bad.shape[0], -1).any(axis=-1).sum())
        raise FloatingPointError(f"{n_bad} of {bad.shape[0]} drifts diverged ({what}): beyond what the models "
                                 f"are meant for")


def simulate_blackouts(vessel, weather: WeatherState, headings_rad, *, uncertainty: WeatherUncertainty | None = None,
                       settings: DriftOffSettings | None = None, index: int = 0,
                       keep_tracks: bool = False) -> DriftOffResult:
    """Monte-Carlo blackouts of one weather state at each heading (planning mode).

    Parameters
    ----------
    vessel : str, Vessel or DynamicModel
        The vessel (nominal model; samples perturb it, see :mod:`.spread`).
    weather : WeatherState
        Mean weather.
    headings_rad : array_like (H,)
        Headings at the blackout [rad], clockwise from north.
    uncertainty : WeatherUncertainty, optional
        Standard deviations of the weather (default: known exactly).
    settings : DriftOffSettings, optional
    index : int
        Index of this weather state in a sweep (selects its random stream).
    keep_tracks : bool
        Keep the drift tracks (disables the early stop; memory H x N x steps).
    """
    if not isinstance(weather, WeatherState):
        raise TypeError(f"weather: expected a WeatherState, got {type(weather).__name__}")
    if uncertainty is not None and not isinstance(uncertainty, WeatherUncertainty):
        raise TypeError(f"uncertainty: expected a WeatherUncertainty or None, got {type(uncertainty).__name__}")
    st = as_config(settings, DriftOffSettings, "settings") if settings is not None else DriftOffSettings()
    if isinstance(index, (bool, np.bool_)) or not isinstance(index, (int, np.integer)) or index < 0:
        raise ValueError(f"index: expected a whole number >= 0 (a weather state's place in a sweep), got {index!r}")
    if not isinstance(keep_tracks, (bool, np.bool_)):    # a text "no" is truthy
        raise TypeError(f"keep_tracks: expected True or False, got {keep_tracks!r}")
    psi = check_headings(headings_rad)
    model = get_model(vessel)
    rng = state_rng(st.seed, index)
    N, H = st.n_samples, psi.size
    try:
        return _blackouts(model, weather, uncertainty, st, psi, rng, index, keep_tracks)
    except MemoryError:
        # each blackout holds its wave components, gust harmonics (and track): named, as they
        # may weigh more than the samples' count
        each = f"{st.n_wave_components} wave components and {st.n_gust_harmonics} gust harmonics" + (
            f" and a track of {st.n_steps} steps (keep_tracks)" if keep_tracks else "")
        raise MemoryError(f"settings.n_samples: {N} samples x {H} heading(s) = {N * H} blackouts at once, each with "
                          f"{each}, need more memory than this machine has; give fewer samples or headings, or "
                          f"fewer settings.n_wave_components or n_gust_harmonics (a season run splits its states "
                          f"into chunks)") from None


def _blackouts(model, weather, uncertainty, st, psi, rng, index: int, keep_tracks: bool) -> "DriftOffResult":
    """:func:`simulate_blackouts` after its checks: the batch of ``n_samples x headings`` drifts."""
    ves = model.vessel
    N, H = st.n_samples, psi.size
    scales = spread.draw_scales(ves, N, rng, st.vessel_spread)
    envs = sample_environment(weather, uncertainty, N, rng, duration_s=st.horizon_s, dt_s=st.dt_s,
                              n_gust=st.n_gust_harmonics, n_wave=st.n_wave_components)
    stack = spread.scaled_arrays(model.arrays, scales)
    tile = lambda a: np.concatenate([a] * H, axis=0)  # noqa: E731  (heading-major: b = h * N + n)
    stack_b = spread.StackedArrays(*(tile(a) for a in stack))
    K = model.n_actuators
    az0 = np.zeros(K)
    az0[: len(ves.thrusters)] = [t.fixed_angle_rad for t in ves.thrusters]
    hold = np.empty((H * N, 3))
    t_reach, exc, track = engine.run_kernel(
        np.repeat(psi, N), model.arrays, stack_b, np.broadcast_to(az0, (H * N, K)), np.zeros((H * N, K)),
        st.rpm_time_constant_s, True, tile(envs.wind_mean_m_s), tile(envs.wind_dir_from_rad),
        tile(envs.gust_f_hz), tile(envs.gust_amp_m_s), tile(envs.gust_phase_rad), tile(envs.current),
        np.zeros((H * N, 3)), tuple(tile(w) for w in envs.waves), hull_array(ves), st.dt_s, st.n_steps,
        np.asarray(st.radii_m), np.asarray(st.reaction_times_s), keep_tracks, holding_load=hold)
    cap = _thrust_capacity(ves)         # (2, 3): towards +, towards - (a DOF's two signs may differ)
    over = np.where(hold >= 0.0, hold > cap[0], -hold > cap[1]).any(axis=1).reshape(H, N).mean(axis=1)
    refuse_diverged(exc, st.reaction_times_s, f"weather: the state of index {index} or its spread")
    R, Q = len(st.radii_m), len(st.reaction_times_s)
    rel = wrap_2pi(weather.wind_dir_from_rad - psi)         # [0, 2 pi): np.mod gave 2 pi for -1e-17
    return DriftOffResult(headings_rad=psi, weather_rel_rad=rel, radii_m=np.asarray(st.radii_m),
                          reaction_times_s=np.asarray(st.reaction_times_s), t_reach_s=t_reach.reshape(H, N, R),
                          excursion_m=exc.reshape(H, N, Q), horizon_s=st.n_steps * st.dt_s,
                          tracks=None if track is None else track.reshape(H, N, st.n_steps + 1, 3),
                          over_capacity_frac=over)


#: Bollard capacity per vessel fingerprint (an allocation each; a season run asks per state).
_CAPACITY: dict = {}


def _thrust_capacity(vessel) -> np.ndarray:
    """The thrusters' bollard capacity ``[X_N, Y_N, N_Nm]`` towards + (row 0) and towards -
    (row 1) (one allocation per vessel file)."""
    from hybridship.sim.allocation import thrust_capacity_by_sign
    from hybridship.vessel import fingerprint

    key = fingerprint(vessel)
    if key not in _CAPACITY:
        _CAPACITY[key] = thrust_capacity_by_sign(vessel)
    return _CAPACITY[key]
