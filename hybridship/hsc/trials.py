"""Simulated sea trials of the high-speed craft, laid out like Ertogan et al.'s.

A trial is a straight-course run in head seas with persistently exciting inputs: the
engine speed command is swept (ramps) and stepped between idle (800 rpm) and full
(4000 rpm), and the trim device's PWM drive is switched periodically between 10 and
100 % duty. Two trials as in the paper (sec. 4):

* sea state 1 (WMO code 1, ripples, Hs below 0.1 m), interceptors: 3150 samples, the first
  2050 for training and the last 1100 for validation;
* sea state 2 (WMO code 2, wavelets, Hs 0.1-0.5 m), trim tabs: 13580 samples split 8600/4980.

Both splits are contiguous in time (training first).

Sensors as on the boat (0.1 s sampling): GPS speed over ground delayed by 2 s, IMU pitch
and heave acceleration with noise (and a pitch mounting bias), engine speed with noise,
and the PWM command as sent. **The GPS delay is handled by re-alignment**, as the paper
did ("the experimental data was revised taking into account the delay time of the GPS
receiver"): the logger records ``N + 20`` samples; the speed channel is shifted 20
samples earlier (``speed[k] = gps[k + 20]``) and the last 20 samples of the other
channels are dropped, which leaves ``N`` time-aligned samples. Every model is identified
and scored on the aligned data; :attr:`TrialData.raw` keeps the log as recorded.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Annotated, Literal

import numpy as np
import pandas as pd
from pydantic import Field, model_validator

from ..config import Float, Int, Seed, check_flags, check_number, check_whole_number, config_dataclass
from .simulator import KNOT_M_S, PlaningCraftModel, SeaConditions, TrueRecord
from .vessel import PlaningCraft, load_planing_craft

__all__ = ["TrialConfig", "TrialData", "paper_trial", "generate_trial", "input_schedule",
           "INPUTS", "OUTPUTS"]

#: Model inputs (aligned data columns), in the paper's order.
INPUTS = ("rpm", "pwm_pct", "heave_acc_m_s2")
#: Model outputs (aligned data columns).
OUTPUTS = ("speed_m_s", "pitch_rad")


@config_dataclass(frozen=True)
class TrialConfig:
    """One simulated sea trial (validated on creation).

    Attributes
    ----------
    sea_state : int
        WMO sea-state code of the trial (1 or 2); a label.
    n_samples, n_train : int
        Aligned samples in all and in the training part (the rest validate).
    actuator : {"interceptor", "trim_tab"}
        Trim device driven by the PWM input.
    sea : SeaConditions
        Head-sea wave conditions.
    seed : int
        Seed of the input schedule, the waves and the sensor noise.
    rpm_range : tuple of float
        Engine-speed command range (min, max) [rpm]; within the craft's engine range
        (``idle_rpm`` to ``max_rpm``), which :func:`generate_trial` checks.
    pwm_range_pct : tuple of float
        PWM duty range (min, max) [%].
    hold_s : tuple of float
        (min, max) duration of an engine-speed level [s].
    ramp_rpm_s : tuple of float
        (min, max) slew rate of the engine-speed sweeps [rpm/s].
    pwm_period_s : tuple of float
        (min, max) full period of the PWM switching [s].
    settle_s : float
        Simulated time before the logger starts [s].
    """

    sea_state: Literal[1, 2]
    n_samples: Annotated[Int, Field(ge=51)]        # a training part of at least 50, and a validation part
    n_train: Annotated[Int, Field(ge=50)]
    actuator: Literal["interceptor", "trim_tab"]
    sea: SeaConditions
    seed: Seed = 0
    rpm_range: tuple[Float, Float] = (800.0, 4000.0)
    pwm_range_pct: tuple[Float, Float] = (10.0, 100.0)
    hold_s: tuple[Float, Float] = (8.0, 30.0)
    ramp_rpm_s: tuple[Float, Float] = (60.0, 400.0)
    pwm_period_s: tuple[Float, Float] = (6.0, 24.0)
    settle_s: Annotated[Float, Field(ge=0)] = 30.0

    @model_validator(mode="after")
    def _ranges(self):
        if not self.n_train < self.n_samples:
            raise ValueError(f"n_train: must be < n_samples = {self.n_samples}, got {self.n_train}")
        if not 0 < self.rpm_range[0] < self.rpm_range[1]:
            raise ValueError(f"rpm_range: expected 0 < min < max, got {self.rpm_range}")
        if not 0 <= self.pwm_range_pct[0] < self.pwm_range_pct[1] <= 100:
            raise ValueError(f"pwm_range_pct: expected 0 <= min < max <= 100, got {self.pwm_range_pct}")
        for name in ("hold_s", "ramp_rpm_s", "pwm_period_s"):
            lo, hi = getattr(self, name)
            if not 0 < lo <= hi:
                raise ValueError(f"{name}: expected 0 < min <= max, got {(lo, hi)}")
        return self

    @property
    def n_validation(self) -> int:
        return self.n_samples - self.n_train


#: Largest ``seed`` of :func:`paper_trial`: its trials are seeded ``seed * 100 + sea_state``.
_MAX_TRIAL_SEED = (2**63 - 1 - 2) // 100


def paper_trial(sea_state: int, *, seed: int = 0, scale: float = 1.0) -> TrialConfig:
    """The paper's trial for sea state 1 or 2; ``scale < 1`` shortens it (quick runs, tests)."""
    if isinstance(sea_state, (bool, np.bool_)):       # True == 1 gave sea state 1
        raise ValueError(f"sea_state: expected 1 or 2, got {sea_state!r}")
    if sea_state == 1:
        n, n_tr, act, sea = 3150, 2050, "interceptor", SeaConditions(hs_m=0.05, tp_s=1.5)
    elif sea_state == 2:
        n, n_tr, act, sea = 13580, 8600, "trim_tab", SeaConditions(hs_m=0.10, tp_s=3.0)
    else:
        raise ValueError(f"sea_state: expected 1 or 2, got {sea_state!r}")
    scale = check_number("scale", scale, lo=0.0, lo_open=True, hi=1.0)      # a text was a TypeError unnamed
    # the trial's seed is seed * 100 + sea_state, which must stay a seed (below 2**63)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed <= _MAX_TRIAL_SEED:
        raise ValueError(f"seed: expected a whole number from 0 to {_MAX_TRIAL_SEED}, got {seed!r}")
    n_s, n_t = max(int(round(n * scale)), 200), max(int(round(n_tr * scale)), 130)
    return TrialConfig(sea_state=sea_state, n_samples=n_s, n_train=n_t, actuator=act, sea=sea,
                       seed=seed * 100 + sea_state)


def input_schedule(config: TrialConfig, n: int, dt_s: float, rng: np.random.Generator | int):
    """Engine-speed command [rpm] and PWM duty [%] for ``n`` samples, drawn from ``rng``
    (a numpy Generator, or a whole-number seed for one).

    The engine speed alternates between sweeps (ramps at a random slew rate) and holds at
    random levels spread over the whole range (a new level is at least a quarter of the
    range away from the last one, so every stretch of the record sees large changes);
    the PWM duty switches between random high and low levels with a random period.

    Raises
    ------
    ValueError
        ``n`` or a seed given as ``rng`` not a whole number >= 0, ``dt_s`` not positive, or
        ``config.pwm_period_s`` shorter than two steps (a half period, the time a PWM level is held, would round
        to no sample).
    TypeError
        ``config`` not a :class:`TrialConfig`.
    """
    if not isinstance(config, TrialConfig):          # an AttributeError on .pwm_period_s
        raise TypeError(f"config: expected a TrialConfig (paper_trial(...)), got {type(config).__name__}")
    n = check_whole_number("n", n, 0)          # numpy's shape errors named nothing (100.0, -1)
    if not hasattr(rng, "random"):              # a seed: 'int' object has no attribute 'random' before
        rng = np.random.default_rng(check_whole_number("rng", rng, 0))
    dt_s = check_number("dt_s", dt_s, lo=0.0, lo_open=True)
    # the step is the craft's, unknown to TrialConfig: a half period rounding to 0 samples never advanced
    if int(config.pwm_period_s[0] / 2 / dt_s) < 1:
        raise ValueError(f"pwm_period_s: expected a shortest period of at least two samples (2 x {dt_s:g} s), "
                         f"got {config.pwm_period_s}")
    lo, hi = config.rpm_range
    rpm = np.empty(n)
    level = lo + 0.3 * (hi - lo) * rng.random()
    k = 0
    while k < n:
        target = level
        while abs(target - level) < 0.25 * (hi - lo):
            target = lo + (hi - lo) * rng.random()
        rate = rng.uniform(*config.ramp_rpm_s) * (1 if rng.random() < 0.5 else 50.0)  # sweep or step
        n_ramp = max(int(abs(target - level) / rate / dt_s), 1)
        n_hold = int(rng.uniform(*config.hold_s) / dt_s)
        seg = np.concatenate([np.linspace(level, target, n_ramp + 1)[1:], np.full(n_hold, target)])
        m = min(seg.size, n - k)
        rpm[k:k + m] = seg[:m]
        k += m
        level = target
    plo, phi = config.pwm_range_pct
    pwm = np.empty(n)
    k, high = 0, bool(rng.random() < 0.5)
    while k < n:
        half = int(rng.uniform(*config.pwm_period_s) / 2 / dt_s)
        mid = 0.5 * (plo + phi)
        val = rng.uniform(mid, phi) if high else rng.uniform(plo, mid)
        if rng.random() < 0.3:
            val = phi if high else plo
        m = min(half, n - k)
        pwm[k:k + m] = val
        k += m
        high = not high
    return rpm, pwm


@dataclass
class TrialData:
    """A simulated trial: the raw log, the GPS-aligned data and the split.

    Attributes
    ----------
    config : TrialConfig
    raw : DataFrame
        As logged (``N + delay`` samples): ``time_s, gps_speed_m_s`` (delayed),
        ``pitch_rad, heave_acc_m_s2, rpm, pwm_pct``.
    data : DataFrame
        Aligned (``N`` samples): ``time_s``, the :data:`OUTPUTS` and the :data:`INPUTS`.
    truth : TrueRecord
        Noise-free, undelayed states over the aligned samples.
    delay_samples : int
        GPS delay removed by the alignment [samples].
    """

    config: TrialConfig
    raw: pd.DataFrame
    data: pd.DataFrame
    truth: TrueRecord
    delay_samples: int
    dt_s: float = field(default=0.1)

    @property
    def train(self) -> pd.DataFrame:
        return self.data.iloc[: self.config.n_train].reset_index(drop=True)

    @property
    def validation(self) -> pd.DataFrame:
        return self.data.iloc[self.config.n_train:].reset_index(drop=True)

    def arrays(self, part: str = "all"):
        """``(U, Y)`` arrays, inputs ``(N, 3)`` and outputs ``(N, 2)`` (SI), of ``all``, ``train`` or ``validation``.

        Raises
        ------
        ValueError
            ``part`` not one of the three.
        """
        parts = {"all": lambda: self.data, "train": lambda: self.train, "validation": lambda: self.validation}
        if not isinstance(part, str) or part not in parts:
            raise ValueError(f"part: expected 'all', 'train' or 'validation', got {part!r}")
        df = parts[part]()
        return df[list(INPUTS)].to_numpy(float), df[list(OUTPUTS)].to_numpy(float)


def generate_trial(config: TrialConfig, craft: PlaningCraft | str | os.PathLike | None = None, *,
                   progress: bool = False) -> TrialData:
    """Simulate one sea trial on the "true" boat (``craft.perturbed()``) and log it.

    Parameters
    ----------
    config : TrialConfig
    craft : PlaningCraft, str or path, optional
        The nominal vessel file, or its packaged name or path (default: packaged
        ``volcano71``); the simulator runs its
        :meth:`~hybridship.hsc.vessel.PlaningCraft.perturbed` version.
    progress : bool
        Print a line when done.
    """
    check_flags(progress=progress)
    if not isinstance(config, TrialConfig):          # an AttributeError on .rpm_range before
        raise TypeError(f"config: expected a TrialConfig (paper_trial(...)), got {type(config).__name__}")
    if craft is None or isinstance(craft, (str, os.PathLike)):     # a name or file, as load_planing_craft takes
        craft = load_planing_craft(*(() if craft is None else (craft,)))
    if not isinstance(craft, PlaningCraft):
        raise TypeError(f"craft: expected a PlaningCraft, a packaged name or a file, got {type(craft).__name__}")
    eng = craft.engines
    if not eng.idle_rpm <= config.rpm_range[0] < config.rpm_range[1] <= eng.max_rpm:
        raise ValueError(f"rpm_range: expected within the craft's engine range, idle_rpm {eng.idle_rpm:g} to "
                         f"max_rpm {eng.max_rpm:g} rpm, got {config.rpm_range}")
    sens = craft.sensors
    dt = sens.sample_period_s
    d = int(round(sens.gps_delay_s / dt))
    rng = np.random.default_rng(config.seed)
    n_raw = config.n_samples + d
    # d extra samples before the log starts give the first delayed GPS readings
    rpm_cmd, pwm = input_schedule(config, n_raw + d, dt, rng)
    model = PlaningCraftModel(craft.perturbed(), config.actuator)
    rec = model.simulate(rpm_cmd, pwm, sample_period_s=dt, sea=config.sea, rng=rng, settle_s=config.settle_s)
    noise = np.random.default_rng(rng.integers(2**32))
    n_all = rec.time_s.size                              # n_raw + d
    gps_true = rec.speed_m_s[:n_all - d]                 # what the receiver reports d samples later
    sl = slice(d, n_all)                                 # the logged window
    raw = pd.DataFrame({
        "time_s": np.arange(n_raw) * dt,
        "gps_speed_m_s": gps_true + sens.gps_speed_noise_m_s * noise.standard_normal(n_raw),
        "pitch_rad": rec.pitch_rad[sl] + np.radians(sens.imu_pitch_bias_deg
                                                   + sens.imu_pitch_noise_deg * noise.standard_normal(n_raw)),
        "heave_acc_m_s2": rec.heave_acc_m_s2[sl] + sens.imu_acc_noise_m_s2 * noise.standard_normal(n_raw),
        "rpm": np.round(rec.rpm[sl] + sens.rpm_noise * noise.standard_normal(n_raw)),
        "pwm_pct": rec.pwm_pct[sl],
    })
    # re-alignment of the GPS delay: speed[k] = gps[k + d]; the last d samples go
    N = config.n_samples
    data = pd.DataFrame({
        "time_s": raw["time_s"].to_numpy()[:N],
        "speed_m_s": raw["gps_speed_m_s"].to_numpy()[d:d + N],
        "pitch_rad": raw["pitch_rad"].to_numpy()[:N],
        "rpm": raw["rpm"].to_numpy()[:N],
        "pwm_pct": raw["pwm_pct"].to_numpy()[:N],
        "heave_acc_m_s2": raw["heave_acc_m_s2"].to_numpy()[:N],
    })
    idx = slice(d, d + N)
    truth = TrueRecord(**{k: (v[idx] if isinstance(v, np.ndarray) else v) for k, v in vars(rec).items()})
    truth.time_s = data["time_s"].to_numpy()
    if progress:
        print(f"  sea state {config.sea_state}: {N} samples simulated, speed "
              f"{data.speed_m_s.min() / KNOT_M_S:.1f}-{data.speed_m_s.max() / KNOT_M_S:.1f} kn")
    return TrialData(config=config, raw=raw, data=data, truth=truth, delay_samples=d, dt_s=dt)
