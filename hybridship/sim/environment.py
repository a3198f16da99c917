"""Environmental disturbances for the sea-trial simulator: waves, wave drift, wind gusts, current.

Everything here is pure numpy/scipy, vectorised over time, and seeded: every function
that draws random numbers takes ``rng`` (a :class:`numpy.random.Generator` or an integer
seed). SI units and radians inside; the unit is part of every argument name.

Conventions (same as :mod:`hybridship.frames`)
-----------------------------------------------
* NED earth frame (x north, y east); body frame x forward, y starboard.
* Heading ``psi_rad`` clockwise from north.
* Wave direction: where the waves come FROM, clockwise from north.
* Current direction: where the current flows TO, clockwise from north.
* Wind direction: where the wind comes FROM, clockwise from north.
* Relative wave angle ``beta_rad = wave_dir_from_rad - psi_rad`` (wrapped to [-pi, pi)):
  ``0`` head seas, ``pi`` following seas, ``+pi/2`` waves from STARBOARD (they push the
  ship to port, -y), ``-pi/2`` waves from PORT (they push the ship to starboard, +y).
* Deep water throughout: wave number ``k = omega**2 / g``.

Contents
--------
* :func:`jonswap_spectrum` - DNV-RP-C205 JONSWAP spectrum.
* :class:`WaveField`, :func:`make_wave_components` - random-phase wave components.
* :class:`HullDimensions`, :func:`drift_coefficients`, :func:`mean_drift_loads`,
  :func:`wave_drift_loads` - second-order slowly varying wave drift (Newman).
* :class:`MotionRAOs`, :func:`wave_frequency_motion` - first-order wave-frequency motion.
* :func:`harris_spectrum`, :func:`davenport_spectrum`, :func:`gust_wind` - gusting wind.
* :func:`current_series` - slowly varying current.
* :class:`SeaState` - a bundle of conditions with a Beaufort-consistent random draw.

Sources
-------
* DNV-RP-C205 (2010/2019). Environmental conditions and environmental loads, sec. 2.3
  (wind spectra), 3.5 (wave spectra, JONSWAP, directional spreading).
* Faltinsen, O. M. (1990). Sea Loads on Ships and Offshore Structures, Cambridge UP,
  ch. 2 (linear waves, energy flux) and ch. 5 (mean and slowly varying drift, Newman).
* Fossen, T. I. (2021). Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd
  ed., Wiley, ch. 10 (wind, wave and current models; wave drift; wave-frequency motion).
* Newman, J. N. (1974). Second-order, slowly-varying forces on vessels in irregular
  waves. Proc. Int. Symp. Dynamics of Marine Vehicles and Structures in Waves, London.
* Harris, R. I. (1971) and Davenport, A. G. (1961) wind gust spectra, as given in
  Fossen (2021) sec. 10.1 and DNV-RP-C205 sec. 2.3.
* WMO Beaufort scale: ``U10 = 0.836 B**1.5`` m/s and the "probable wave height" table.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Annotated

import numpy as np
from pydantic import Field, model_validator
from scipy.signal import lfilter

from hybridship.config import (Float, as_config, check_flags, check_number, check_whole_number, config_dataclass,
                               float_array, real_array)
from hybridship.frames import wrap_2pi, wrap_pi

__all__ = [
    "G_M_S2",
    "RHO_SEAWATER_KG_M3",
    "GUNNERUS_HULL",
    "jonswap_spectrum",
    "jonswap_gamma_dnv",
    "WaveField",
    "make_wave_components",
    "HullDimensions",
    "drift_coefficients",
    "mean_drift_loads",
    "wave_drift_loads",
    "MotionRAOs",
    "wave_frequency_motion",
    "harris_spectrum",
    "davenport_spectrum",
    "gust_wind",
    "current_series",
    "current_velocity_ned",
    "beaufort_wind_speed",
    "beaufort_wave_height",
    "SeaState",
    "MAX_STEEPNESS",
    "check_steepness",
    "max_hs_m",
]

#: Standard gravity [m/s^2].
G_M_S2 = 9.81
#: Sea-water density [kg/m^3].
RHO_SEAWATER_KG_M3 = 1025.0
#: Steepness ``2 pi Hs / (g Tp^2)`` beyond which no sea state exists: that at which a single
#: deep-water wave breaks (Miche, 1/7), about twice DNV-RP-C205's limiting steepness of the
#: significant wave. A larger Hs is two columns swapped or a period in another unit.
MAX_STEEPNESS = 1.0 / 7.0


def max_hs_m(tp_s):
    """Largest significant wave height [m] at peak period ``tp_s`` [s] (:data:`MAX_STEEPNESS`)."""
    return MAX_STEEPNESS * G_M_S2 * real_array("tp_s", tp_s) ** 2 / (2.0 * np.pi)


def check_steepness(hs_m: float, tp_s: float) -> None:
    """Refuse a sea steeper than :data:`MAX_STEEPNESS` (ValueError naming ``hs_m`` and ``tp_s``):
    no sea state, but two fields swapped or a period in another unit."""
    if hs_m > max_hs_m(tp_s):
        raise ValueError(f"hs_m {hs_m:g} m at tp_s {tp_s:g} s is steeper than waves can be (at most "
                         f"{float(max_hs_m(tp_s)):.2f} m at that period: 2 pi Hs / (g Tp^2) <= "
                         f"{MAX_STEEPNESS:.3f}); are hs_m and tp_s swapped, or tp_s in another unit?")

# Budget of elements (time samples x components) per vectorised block, to bound memory
# for long, finely sampled records (e.g. 1 h at 100 Hz x 50 components).
_BLOCK_ELEMENTS = 2_000_000


# --------------------------------------------------------------------------- validation helpers


def _as_rng(rng, name="rng"):
    """Return a Generator from a Generator or an int seed (>= 0); refuse None (non-reproducible)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        return np.random.default_rng(check_whole_number(name, rng))     # -1 failed in numpy's words
    raise TypeError(f"{name} must be a numpy.random.Generator or an int seed, got {type(rng).__name__}")


def _finite_scalar(name, value):
    """``value`` as a finite float; text and bools are refused (float() reads "10" and True)."""
    return check_number(name, value)


def _positive(name, value, *, allow_zero=False):
    v = _finite_scalar(name, value)
    if v < 0.0 or (v == 0.0 and not allow_zero):
        raise ValueError(f"{name} must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    return v


def _in_range(name, value, lo, hi, *, lo_open=False, hi_open=False):
    v = _finite_scalar(name, value)
    bad_lo = v <= lo if lo_open else v < lo
    bad_hi = v >= hi if hi_open else v > hi
    if bad_lo or bad_hi:
        lb, rb = ("(" if lo_open else "["), (")" if hi_open else "]")
        raise ValueError(f"{name} must be in {lb}{lo}, {hi}{rb}, got {value!r}")
    return v


def _pair(name, value):
    """``value`` as two finite floats ``(lo, hi)``, or an error naming ``name`` (a text such as
    ``"25"`` would otherwise pass as the pair of its characters)."""
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{name} must be a (lo, hi) pair of numbers, got {value!r}")
    try:
        items = list(value)
    except TypeError:
        raise TypeError(f"{name} must be a (lo, hi) pair of numbers, got {value!r}") from None
    if len(items) != 2:
        raise ValueError(f"{name} must be a (lo, hi) pair of numbers, got {value!r}")
    return tuple(_finite_scalar(f"{name}[{i}]", x) for i, x in enumerate(items))


_Pos = Annotated[Float, Field(gt=0.0)]
_NonNeg = Annotated[Float, Field(ge=0.0)]
_MaybeNaN = Annotated[float, Field(allow_inf_nan=True)]  # nan = unknown


def _time_vector(time_s, *, min_len=1):
    t = real_array("time_s", time_s)
    if t.ndim != 1:
        raise ValueError(f"time_s must be 1-D, got shape {t.shape}")
    if t.size < min_len:
        raise ValueError(f"time_s must have at least {min_len} samples, got {t.size}")
    if not np.all(np.isfinite(t)):
        raise ValueError("time_s must be finite")
    if t.size > 1 and np.any(np.diff(t) <= 0.0):
        raise ValueError("time_s must be strictly increasing")
    return t


def _per_time(name, value, n):
    """Broadcast a scalar or length-n array to shape (n,), naming the field on mismatch."""
    a = real_array(name, value)
    if a.ndim == 0:
        a = np.full(n, float(a))
    elif a.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have shape ({n},) like time_s, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def _broadcast(**named):
    """The named arrays (:func:`config.real_array`) broadcast together, or a ValueError naming
    them and their shapes (numpy's 'shape mismatch' named neither)."""
    arrays = [real_array(name, value) for name, value in named.items()]
    try:
        return np.broadcast_arrays(*arrays)
    except ValueError:
        shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(named, arrays))
        raise ValueError(f"{' and '.join(named)}: shapes that do not broadcast together ({shapes})") from None


def _positions(position_ne_m, n):
    if position_ne_m is None:
        return None
    p = real_array("position_ne_m", position_ne_m)
    if p.shape != (n, 2):
        raise ValueError(f"position_ne_m must have shape ({n}, 2) [north_m, east_m], got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("position_ne_m must be finite")
    return p


def _blocks(n_time, n_comp):
    """Slices over the time axis so that each block holds about _BLOCK_ELEMENTS elements."""
    step = max(1, _BLOCK_ELEMENTS // max(1, n_comp))
    return [slice(s, min(n_time, s + step)) for s in range(0, n_time, step)]


# --------------------------------------------------------------------------- wave spectrum


def jonswap_gamma_dnv(hs_m, tp_s):
    """Peak-enhancement factor from Hs and Tp (DNV-RP-C205 sec. 3.5.5.5).

    ``gamma = 5`` for ``Tp/sqrt(Hs) <= 3.6``, ``exp(5.75 - 1.15 Tp/sqrt(Hs))`` in between,
    ``1`` (Pierson-Moskowitz) for ``Tp/sqrt(Hs) >= 5`` (Tp in s, Hs in m).
    """
    hs = _positive("hs_m", hs_m)
    tp = _positive("tp_s", tp_s)
    r = tp / math.sqrt(hs)
    if r <= 3.6:
        return 5.0
    if r >= 5.0:
        return 1.0
    return math.exp(5.75 - 1.15 * r)


def jonswap_spectrum(omega_rad_s, hs_m, tp_s, gamma=3.3):
    """JONSWAP wave spectrum S(omega) [m^2 s/rad] in the DNV-RP-C205 form.

    ``S(w) = A_g * (5/16) Hs^2 wp^4 w^-5 exp(-5/4 (w/wp)^-4) * gamma^exp(-(w-wp)^2 / (2 s^2 wp^2))``
    with ``wp = 2 pi / Tp``, ``s = 0.07`` for ``w <= wp`` and ``0.09`` above, and the
    normalising factor ``A_g = 1 - 0.287 ln(gamma)`` (DNV-RP-C205 sec. 3.5.5, eqs. 3.5.5.1-4)
    which keeps ``4 sqrt(m0)`` within about 1 % of Hs for ``1 <= gamma <= 7``.

    Parameters
    ----------
    omega_rad_s : array_like
        Wave frequencies [rad/s]; ``S = 0`` for ``omega <= 0``; NaN is refused.
    hs_m : float
        Significant wave height [m] (>= 0).
    tp_s : float
        Peak period [s] (> 0); the spectrum peaks at ``omega = 2 pi / tp_s``.
    gamma : float
        Peak-enhancement factor [-], 1 (Pierson-Moskowitz) to 7.

    Returns
    -------
    ndarray
        Spectral density [m^2 s/rad], the shape of ``omega_rad_s``.
    """
    hs = _positive("hs_m", hs_m, allow_zero=True)
    tp = _positive("tp_s", tp_s)
    g = _in_range("gamma", gamma, 1.0, 7.0)
    w = real_array("omega_rad_s", omega_rad_s)
    if np.isnan(w).any():       # it would fail omega > 0 and come out as S = 0
        raise ValueError("omega_rad_s: contains NaN")
    return _jonswap(w, hs, tp, g)


def _jonswap(omega_rad_s, hs_m, tp_s, gamma):
    """The JONSWAP spectrum of :func:`jonswap_spectrum` [m^2 s/rad], unchecked and broadcasting.

    The one implementation of the formula: :func:`jonswap_spectrum` calls it with scalars,
    the batched components of :func:`_jittered_components` with one peak period per sea.

    Parameters
    ----------
    omega_rad_s : array_like
        Wave frequencies [rad/s]; ``S = 0`` for ``omega <= 0``.
    hs_m, tp_s, gamma : float or ndarray
        Significant wave height [m], peak period [s] and peak-enhancement factor [-], each a
        scalar or an array that broadcasts against ``omega_rad_s`` (e.g. tp_s of shape (m, 1)
        against frequencies (m, n)). A scalar stays a scalar, so that one sea's powers are
        those of a scalar: numpy's power of an array can differ from a scalar's in the last
        bit, and :func:`make_wave_components` keeps its outputs for a seed.

    Returns
    -------
    ndarray
        Spectral density [m^2 s/rad], the broadcast shape.
    """
    w = np.asarray(omega_rad_s, dtype=float)
    shape = np.broadcast_shapes(w.shape, np.shape(hs_m), np.shape(tp_s), np.shape(gamma))
    pos = np.broadcast_to(w > 0.0, shape)

    def at_pos(x):      # the values where omega > 0, an array's broadcast (a scalar stays one)
        return np.broadcast_to(x, shape)[pos] if np.ndim(x) else x

    wq, hs, g = at_pos(w), at_pos(hs_m), at_pos(gamma)
    wp = at_pos(2.0 * np.pi / tp_s)
    out = np.zeros(shape)
    s_pm = (5.0 / 16.0) * hs**2 * wp**4 * wq**-5.0 * np.exp(-1.25 * (wq / wp) ** -4.0)
    sigma = np.where(wq <= wp, 0.07, 0.09)
    peak = g ** np.exp(-0.5 * ((wq - wp) / (sigma * wp)) ** 2)
    out[pos] = (1.0 - 0.287 * np.log(g)) * s_pm * peak
    return out


# --------------------------------------------------------------------------- wave components


@config_dataclass(frozen=True, eq=False, arbitrary_types=True)
class WaveField:
    """A discretised wave field: a sum of regular deep-water components.

    Surface elevation at NED position ``p = (north_m, east_m)``::

        zeta(t, p) = sum_j A_j cos(theta_j),
        theta_j = omega_j t + k_j (cos(chi_j) p_n + sin(chi_j) p_e) + eps_j

    where ``chi_j`` is the direction component j comes FROM (it propagates towards
    ``chi_j + pi``) and ``k_j = omega_j^2 / g``.

    Attributes
    ----------
    omega_rad_s : ndarray (n,)
        Component frequencies [rad/s], positive.
    amplitude_m : ndarray (n,)
        Component amplitudes [m], ``sqrt(2 S(omega_j) d_omega_j)``.
    phase_rad : ndarray (n,)
        Random phases ``eps_j`` [rad].
    dir_from_rad : ndarray (n,)
        Direction each component comes from [rad], clockwise from north.
    d_omega_rad_s : ndarray (n,)
        Frequency bin widths [rad/s] (for bookkeeping; not used by the load models).
    hs_m, tp_s, gamma, mean_dir_from_rad : float
        The sea state the components were drawn from (``nan`` if unknown).
    g_m_s2 : float
        Gravity used for the dispersion relation [m/s^2].
    """

    omega_rad_s: float_array(flat=True, lo=0.0, lo_open=True, readonly=True)
    amplitude_m: float_array(flat=True, lo=0.0, readonly=True)
    phase_rad: float_array(flat=True, readonly=True)
    dir_from_rad: float_array(flat=True, readonly=True)
    d_omega_rad_s: float_array(flat=True, finite=False, readonly=True) | None = None
    hs_m: _MaybeNaN = float("nan")
    tp_s: _MaybeNaN = float("nan")
    gamma: _MaybeNaN = float("nan")
    mean_dir_from_rad: _MaybeNaN = float("nan")
    g_m_s2: _Pos = G_M_S2

    @model_validator(mode="after")
    def _components(self):
        n = self.omega_rad_s.size
        if n == 0:
            raise ValueError("omega_rad_s: must hold at least one component")
        if self.d_omega_rad_s is None:
            dw = np.full(n, np.nan)
            dw.setflags(write=False)
            object.__setattr__(self, "d_omega_rad_s", dw)  # frozen
        for name in ("amplitude_m", "phase_rad", "dir_from_rad", "d_omega_rad_s"):
            if getattr(self, name).size != n:
                raise ValueError(f"{name}: must have {n} elements like omega_rad_s, got {getattr(self, name).size}")
        return self

    @property
    def n_components(self) -> int:
        """Number of components."""
        return int(self.omega_rad_s.size)

    @property
    def wavenumber_rad_m(self) -> np.ndarray:
        """Deep-water wave numbers ``k = omega^2 / g`` [rad/m]."""
        return self.omega_rad_s**2 / self.g_m_s2

    @property
    def m0_m2(self) -> float:
        """Zeroth spectral moment of the discretised field, ``sum A_j^2 / 2`` [m^2]."""
        return float(0.5 * np.sum(self.amplitude_m**2))

    @property
    def hs_discrete_m(self) -> float:
        """Significant wave height of the components, ``4 sqrt(m0)`` [m]."""
        return 4.0 * math.sqrt(self.m0_m2)

    def phases(self, time_s, position_ne_m=None) -> np.ndarray:
        """Total phases ``theta_j(t)`` [rad], shape (N, n), at the origin or along a track.

        Parameters
        ----------
        time_s : array_like (N,)
            Time [s].
        position_ne_m : array_like (N, 2), optional
            Where the ship is ``[north_m, east_m]`` at each time; including it makes the
            encounter frequency (Doppler shift of a drifting ship) come out by itself.
        """
        t = real_array("time_s", time_s).reshape(-1)
        theta = np.multiply.outer(t, self.omega_rad_s) + self.phase_rad
        p = _positions(position_ne_m, t.size)
        if p is not None:
            k = self.wavenumber_rad_m
            theta += k * (np.multiply.outer(p[:, 0], np.cos(self.dir_from_rad))
                          + np.multiply.outer(p[:, 1], np.sin(self.dir_from_rad)))
        return theta

    def elevation(self, time_s, position_ne_m=None) -> np.ndarray:
        """Surface elevation ``zeta`` [m] (positive up), shape (N,)."""
        t = _time_vector(time_s)
        p = _positions(position_ne_m, t.size)
        out = np.empty(t.size)
        for sl in _blocks(t.size, self.n_components):
            theta = self.phases(t[sl], None if p is None else p[sl])
            out[sl] = np.cos(theta) @ self.amplitude_m
        return out


def _spreading_directions(mean_dir_rad, n_exp, size, rng):
    """Directions drawn from D(theta) ~ cos^n(theta - mean) on |theta - mean| <= pi/2.

    DNV-RP-C205 sec. 3.5.8 (cos-power spreading); sampled by inverting the numerical CDF.
    """
    grid = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2001)
    pdf = np.cos(grid) ** n_exp
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(grid))])
    cdf /= cdf[-1]
    return mean_dir_rad + np.interp(rng.uniform(0.0, 1.0, size), cdf, grid)


def _scale_to_hs(amp_1m, hs_m, normalize_hs):
    """Amplitudes [m] of seas of height ``hs_m`` from those of 1 m (``S ~ Hs^2``, so a calm of
    Hs = 0 is valid and has zero amplitudes).

    Parameters
    ----------
    amp_1m : ndarray (..., n)
        Component amplitudes [m] of each sea at Hs = 1 m, the last axis the components.
    hs_m : float or ndarray (..., 1)
        Significant wave height [m] (>= 0) of each sea, broadcasting against ``amp_1m``.
    normalize_hs : bool
        Rescale each sea with Hs > 0 so that ``4 sqrt(sum A_j^2 / 2)`` equals its Hs exactly.

    Returns
    -------
    ndarray
        Amplitudes [m], the shape of ``amp_1m``.
    """
    amp = amp_1m * hs_m
    if normalize_hs:
        root_m0 = np.sqrt(0.5 * np.sum(amp**2, axis=-1, keepdims=True))
        with np.errstate(divide="ignore", invalid="ignore"):       # a calm's 0 / 0, not used
            amp = amp * np.where(np.asarray(hs_m) > 0.0, hs_m / (4.0 * root_m0), 1.0)
    return amp


def _jittered_components(hs_m, tp_s, gamma, u, omega_range_factor=(0.5, 3.5), normalize_hs=True):
    """Frequencies, bin widths and amplitudes of JONSWAP seas, jittered, batched.

    The ``method="jittered"`` discretisation of :func:`make_wave_components`, which calls it
    for one sea (and adds phases and directions), and
    :func:`hybridship.driftoff.weather.sample_environment` for many at once:
    ``n`` equal-width bins on ``omega_range_factor * omega_p`` (each sea its own
    ``omega_p = 2 pi / tp_s``), one frequency a fraction ``u`` into each bin, and amplitudes
    ``sqrt(2 S(omega) d_omega)`` (:func:`_jonswap`; :func:`_scale_to_hs`). Unchecked: the
    callers check their arguments.

    Parameters
    ----------
    hs_m, tp_s : float or ndarray (m,)
        Significant wave height [m] (>= 0) and peak period [s] (> 0) of each sea.
    gamma : float
        JONSWAP peak-enhancement factor [-].
    u : ndarray (n,) or (m, n)
        Where each frequency lies in its bin, in [0, 1): (n,) for one sea, (m, n) for m.
    omega_range_factor : (float, float)
        Frequency band relative to each sea's peak frequency.
    normalize_hs : bool
        Rescale each sea's amplitudes to its Hs exactly (:func:`_scale_to_hs`).

    Returns
    -------
    omega_rad_s, d_omega_rad_s, amplitude_m : ndarray, each the shape of ``u``
        Component frequencies [rad/s], bin widths [rad/s] and amplitudes [m].
    """
    def per_sea(x):     # one value per row of u (a scalar stays one: the single sea's bits)
        return x if np.ndim(x) == 0 else np.asarray(x, dtype=float)[..., None]

    lo_f, hi_f = omega_range_factor
    wp = 2.0 * np.pi / (tp_s if np.ndim(tp_s) == 0 else np.asarray(tp_s, dtype=float))
    edges = np.linspace(lo_f * wp, hi_f * wp, u.shape[-1] + 1, axis=-1)
    d_omega = np.diff(edges, axis=-1)
    omega = edges[..., :-1] + u * d_omega
    amp_1m = np.sqrt(2.0 * _jonswap(omega, 1.0, per_sea(tp_s), gamma) * d_omega)
    return omega, d_omega, _scale_to_hs(amp_1m, per_sea(hs_m), normalize_hs)


def make_wave_components(hs_m, tp_s, wave_dir_from_rad, rng, n_components=50, spreading=None, *,
                         gamma=3.3, omega_range_factor=(0.5, 3.5), method="jittered",
                         normalize_hs=True, g_m_s2=G_M_S2) -> WaveField:
    """Draw random-phase wave components from a JONSWAP spectrum.

    Amplitudes ``A_j = sqrt(2 S(omega_j) d_omega_j)`` (Faltinsen 1990 sec. 2.5; Fossen 2021
    sec. 10.2.1); phases uniform on [0, 2 pi). To avoid the record repeating itself with
    period ``2 pi / d_omega``, frequencies are not on a regular grid:

    * ``method="jittered"`` (default): ``n`` equal-width bins on
      ``[omega_range_factor[0], omega_range_factor[1]] * omega_p``, one frequency drawn
      uniformly inside each bin.
    * ``method="equal_energy"``: bins holding equal shares of m0 (equal area under S),
      one frequency drawn uniformly inside each; all amplitudes then equal
      ``sqrt(2 m0 / n)``.

    The default band [0.5, 3.5] omega_p holds about 99.5 % of m0.

    Parameters
    ----------
    hs_m : float
        Significant wave height [m] (>= 0).
    tp_s : float
        Peak period [s] (> 0).
    wave_dir_from_rad : float
        Mean direction the waves come FROM [rad], clockwise from north.
    rng : numpy.random.Generator or int
        Random source (or seed).
    n_components : int
        Number of frequency components (about 50 is plenty for 3-DOF loads).
    spreading : float, optional
        ``None`` for long-crested waves; otherwise the exponent ``n`` of the cos^n
        directional spreading (DNV-RP-C205 sec. 3.5.8; 2-4 for wind sea). Each frequency
        component then gets its own random direction (single-summation model, which
        avoids phase-locked standing patterns).
    gamma : float
        JONSWAP peak-enhancement factor [-].
    omega_range_factor : (float, float)
        Frequency band relative to the peak frequency ``omega_p = 2 pi / tp_s``.
    method : {"jittered", "equal_energy"}
        Frequency discretisation (above).
    normalize_hs : bool
        Rescale amplitudes so that ``4 sqrt(sum A_j^2 / 2)`` equals ``hs_m`` exactly
        (compensates the truncated tails and the random frequency sampling).
    g_m_s2 : float
        Gravity [m/s^2].

    Returns
    -------
    WaveField
    """
    hs = _positive("hs_m", hs_m, allow_zero=True)
    tp = _positive("tp_s", tp_s)
    chi = _finite_scalar("wave_dir_from_rad", wave_dir_from_rad)
    gam = _in_range("gamma", gamma, 1.0, 7.0)
    rng = _as_rng(rng)
    if not isinstance(n_components, (int, np.integer)) or isinstance(n_components, bool) or n_components < 1:
        raise ValueError(f"n_components must be a positive int, got {n_components!r}")
    n = int(n_components)
    lo_f, hi_f = _pair("omega_range_factor", omega_range_factor)
    if not 0.0 < lo_f < 1.0 < hi_f:
        raise ValueError(f"omega_range_factor must satisfy 0 < lo < 1 < hi, got {omega_range_factor!r}")
    if spreading is not None:
        spreading = _positive("spreading", spreading)
    if method not in ("jittered", "equal_energy"):
        raise ValueError(f"method must be 'jittered' or 'equal_energy', got {method!r}")
    check_flags(normalize_hs=normalize_hs)      # a text "no" is truthy
    u = rng.uniform(0.0, 1.0, n)
    phase = rng.uniform(0.0, 2.0 * np.pi, n)

    if method == "jittered":
        omega, d_omega, amp = _jittered_components(hs, tp, gam, u, (lo_f, hi_f), normalize_hs)
    else:
        wp = 2.0 * np.pi / tp
        grid = np.linspace(lo_f * wp, hi_f * wp, 4001)
        s = _jonswap(grid, 1.0, tp, gam)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (s[1:] + s[:-1]) * np.diff(grid))])
        edges = np.interp(np.linspace(0.0, cum[-1], n + 1), cum, grid)
        omega = edges[:-1] + u * np.diff(edges)
        d_omega = np.diff(edges)
        amp = _scale_to_hs(np.full(n, math.sqrt(2.0 * cum[-1] / n)), hs, normalize_hs)

    if spreading is None:
        dirs = np.full(n, chi)
    else:
        dirs = _spreading_directions(chi, spreading, n, rng)
    return WaveField(omega_rad_s=omega, amplitude_m=amp, phase_rad=phase, dir_from_rad=wrap_2pi(dirs),
                     d_omega_rad_s=d_omega, hs_m=hs, tp_s=tp, gamma=gam,
                     mean_dir_from_rad=float(wrap_2pi(chi)), g_m_s2=g_m_s2)


# --------------------------------------------------------------------------- wave drift


@config_dataclass(frozen=True)
class HullDimensions:
    """Main dimensions and drift-model factors of a ship hull.

    Attributes
    ----------
    L_m, B_m, T_m : float
        Length between perpendiculars, beam and draught [m].
    bow_factor : float
        ``c_x`` [-]: effective fraction of the beam that reflects head (or following)
        seas. Faltinsen's short-wave wall estimate gives ``sin^2(alpha)`` for a bow of
        half-entrance angle ``alpha``; the default 0.6 (a full bow) also lumps in the
        heave/pitch amplification near ``lambda ~ L`` and puts the spectrum-averaged
        head-sea drift coefficient ``X_mean / (2 m0)`` of Gunnerus at about 10-15 kN/m^2 in
        6-7 s waves, the order of strip-theory results for a vessel of this size.
    side_factor : float
        ``c_y`` [-]: effective fraction of the length that reflects beam seas (1 = wall-sided).
    yaw_lever_factor : float
        ``c_n`` [-]: the sway drift force acts at ``x = c_n L cos(beta)`` forward of the
        origin (centre of pressure moves towards the weather end). Gives the
        observed tendency of a drifting ship to turn beam-on to the waves.
    """

    L_m: _Pos
    B_m: _Pos
    T_m: _Pos
    bow_factor: Annotated[Float, Field(ge=0.0, le=2.0)] = 0.6
    side_factor: Annotated[Float, Field(ge=0.0, le=2.0)] = 1.0
    yaw_lever_factor: Annotated[Float, Field(ge=-0.5, le=0.5)] = 0.2

    @classmethod
    def from_any(cls, hull) -> "HullDimensions":
        """Accept a :class:`HullDimensions` or a mapping ``dict(L_m=..., B_m=..., T_m=...)``."""
        if isinstance(hull, cls):
            return hull
        if isinstance(hull, Mapping):
            allowed = {f.name for f in dataclasses.fields(cls)}
            unknown = set(hull) - allowed
            if unknown:
                raise ValueError(f"hull has unknown field(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
            missing = {"L_m", "B_m", "T_m"} - set(hull)
            if missing:
                raise ValueError(f"hull is missing field(s) {sorted(missing)}")
            return cls(**hull)
        raise TypeError(f"hull must be a HullDimensions or a mapping, got {type(hull).__name__}")


#: RV Gunnerus main dimensions (Lpp 33.9 m, B 9.6 m, T 2.5 m) with the default drift factors.
GUNNERUS_HULL = HullDimensions(L_m=33.9, B_m=9.6, T_m=2.5)


def drift_coefficients(omega_rad_s, beta_rad, hull, rho_kg_m3=RHO_SEAWATER_KG_M3, g_m_s2=G_M_S2):
    """Mean wave drift force coefficients ``D = F_mean / A^2`` in the body frame.

    A parametric wall-reflection model (built on the short-wave asymptote of Faltinsen
    1990, ch. 5: ``F_i = (rho g / 2) A^2 int_{L1} sin^2(theta + beta) n_i dl`` over the
    non-shadowed waterline, with frequency-dependent reflection)::

        k      = omega^2 / g                                  (deep water)
        p(k)   = 1 - exp(-2 k T)       share of the incident energy flux above the keel
                                       (flux density ~ exp(2 k z), Faltinsen 1990 ch. 2)
        f(k,l) = (k l)^2 / (1 + (k l)^2)   waves much longer than the body dimension l
                                       are not reflected (the hull rides them)
        D_x = -(rho g / 2) c_x B p(k) f(k, L) cos(beta) |cos(beta)|      [N/m^2]
        D_y = -(rho g / 2) c_y L p(k) f(k, B) sin(beta) |sin(beta)|      [N/m^2]
        D_n =  c_n L cos(beta) D_y                                       [N m/m^2]

    Short waves give the full-reflection limits ``(rho g / 2) A^2 c_x B`` (head seas) and
    ``(rho g / 2) A^2 c_y L`` (beam seas); long waves give zero. Signs: the force points
    along the wave propagation, so head seas (beta = 0) push aft, waves from port
    (beta = -pi/2) push to starboard. In irregular seas the mean drift is
    ``F_mean = 2 int S(omega) D(omega) d omega = sum_j A_j^2 D_j``.

    Parameters
    ----------
    omega_rad_s : array_like
        Wave frequency [rad/s].
    beta_rad : array_like
        Relative wave angle [rad] (direction the waves come from minus heading),
        broadcast against ``omega_rad_s``.
    hull : HullDimensions or mapping
        ``dict(L_m, B_m, T_m)`` plus optional ``bow_factor``, ``side_factor``, ``yaw_lever_factor``.
    rho_kg_m3, g_m_s2 : float
        Water density [kg/m^3] and gravity [m/s^2].

    Returns
    -------
    ndarray, shape (..., 3)
        ``[D_x N/m^2, D_y N/m^2, D_n N m/m^2]``.
    """
    h = HullDimensions.from_any(hull)
    rho = _positive("rho_kg_m3", rho_kg_m3)
    g = _positive("g_m_s2", g_m_s2)
    w, beta = _broadcast(omega_rad_s=omega_rad_s, beta_rad=beta_rad)
    k = w**2 / g
    p = -np.expm1(-2.0 * k * h.T_m)
    kl, kb = (k * h.L_m) ** 2, (k * h.B_m) ** 2
    fx, fy = kl / (1.0 + kl), kb / (1.0 + kb)
    cb, sb = np.cos(beta), np.sin(beta)
    half_rho_g = 0.5 * rho * g
    out = np.empty(w.shape + (3,))
    out[..., 0] = -half_rho_g * h.bow_factor * h.B_m * p * fx * cb * np.abs(cb)
    out[..., 1] = -half_rho_g * h.side_factor * h.L_m * p * fy * sb * np.abs(sb)
    out[..., 2] = h.yaw_lever_factor * h.L_m * cb * out[..., 1]
    return out


def mean_drift_loads(psi_rad, components: WaveField, hull, rho_kg_m3=RHO_SEAWATER_KG_M3):
    """Expected (mean) wave drift loads ``sum_j A_j^2 D(omega_j, beta_j)`` in the body frame.

    Parameters
    ----------
    psi_rad : float or array_like (N,)
        Heading [rad].
    components : WaveField
    hull : HullDimensions or mapping
        Hull dimensions (see :func:`drift_coefficients`).
    rho_kg_m3 : float

    Returns
    -------
    ndarray, shape (3,) or (N, 3)
        ``[X_N, Y_N, N_Nm]``.
    """
    psi = real_array("psi_rad", psi_rad)
    if not np.all(np.isfinite(psi)):
        raise ValueError("psi_rad must be finite")
    components = as_config(components, WaveField, "components")     # another object: an AttributeError
    beta = wrap_pi(components.dir_from_rad - psi[..., None])
    d = drift_coefficients(components.omega_rad_s, beta, hull, rho_kg_m3, components.g_m_s2)
    return np.einsum("...jc,j->...c", d, components.amplitude_m**2)


def wave_drift_loads(time_s, psi_rad, components: WaveField, hull, rho=RHO_SEAWATER_KG_M3, *,
                     position_ne_m=None, newman="geometric"):
    """Second-order slowly varying wave drift loads (Newman's approximation), body frame.

    With ``a_j = A_j sqrt(|D_j|)`` per DOF, ``D_j = D(omega_j, beta_j(t))`` from
    :func:`drift_coefficients`, and ``theta_j(t)`` the component phases at the ship
    (:meth:`WaveField.phases`):

    * ``newman="geometric"`` (default; Newman 1974, Fossen 2021 sec. 10.2, QTF
      ``T_jk = sqrt(T_jj T_kk)``)::

          F(t) = |Z_+(t)|^2 - |Z_-(t)|^2,    Z_s(t) = sum_{j: sign D_j = s} a_j exp(i theta_j(t))
               = (sum a_j cos theta_j)^2 + (sum a_j sin theta_j)^2   (one-signed D)

      This is Fossen's ``2 (sum_j A_j sqrt(D_j) cos theta_j)^2`` with the sum-frequency
      (2 omega) part removed, i.e. only difference frequencies ``omega_j - omega_k``
      remain. Components with drift of opposite sign (possible only with directional
      spreading) are summed separately; their cross terms have no real geometric mean.
    * ``newman="arithmetic"`` (Newman 1974; Faltinsen 1990 ch. 5, ``T_jk = (T_jj + T_kk)/2``)::

          F(t) = Re[ (sum_j A_j D_j e^{i theta_j}) conj(sum_k A_k e^{i theta_k}) ].

    In both forms the time mean of ``F`` (the ``j = k`` terms) is ``sum_j A_j^2 D_j`` =
    the mean drift :func:`mean_drift_loads`; the cross terms average out.
    Zero forward speed is assumed in the coefficients; a drifting ship's Doppler shift
    enters through ``position_ne_m`` if given.

    Parameters
    ----------
    time_s : array_like (N,)
        Time [s], strictly increasing.
    psi_rad : float or array_like (N,)
        Heading [rad] (scalar or per time, e.g. the low-frequency heading).
    components : WaveField
        The wave components.
    hull : HullDimensions or mapping
        ``dict(L_m, B_m, T_m)`` (see :class:`HullDimensions` for optional factors).
    rho : float
        Water density [kg/m^3].
    position_ne_m : array_like (N, 2), optional
        Ship position ``[north_m, east_m]`` (low-frequency track) for the wave phases.
    newman : {"geometric", "arithmetic"}
        QTF off-diagonal approximation (above).

    Returns
    -------
    ndarray, shape (N, 3)
        ``[X_N, Y_N, N_Nm]`` surge force, sway force, yaw moment in the body frame.
    """
    t = _time_vector(time_s)
    n = t.size
    psi = _per_time("psi_rad", psi_rad, n)
    pos = _positions(position_ne_m, n)
    h = HullDimensions.from_any(hull)
    rho = _positive("rho", rho)
    if newman not in ("geometric", "arithmetic"):
        raise ValueError(f"newman must be 'geometric' or 'arithmetic', got {newman!r}")
    components = as_config(components, WaveField, "components")     # another object: an AttributeError
    amp = components.amplitude_m
    out = np.empty((n, 3))
    for sl in _blocks(n, components.n_components):
        theta = components.phases(t[sl], None if pos is None else pos[sl])      # (m, n_c)
        c, s = np.cos(theta), np.sin(theta)
        beta = wrap_pi(components.dir_from_rad[None, :] - psi[sl, None])
        d = drift_coefficients(components.omega_rad_s, beta, h, rho, components.g_m_s2)  # (m, n_c, 3)
        if newman == "geometric":
            a = amp[None, :, None] * np.sqrt(np.abs(d))
            a_pos = np.where(d > 0.0, a, 0.0)
            a_neg = a - a_pos
            f = (np.einsum("mj,mjc->mc", c, a_pos) ** 2 + np.einsum("mj,mjc->mc", s, a_pos) ** 2
                 - np.einsum("mj,mjc->mc", c, a_neg) ** 2 - np.einsum("mj,mjc->mc", s, a_neg) ** 2)
        else:
            wd = amp[None, :, None] * d
            z_c, z_s = c @ amp, s @ amp
            f = (np.einsum("mj,mjc->mc", c, wd) * z_c[:, None]
                 + np.einsum("mj,mjc->mc", s, wd) * z_s[:, None])
        out[sl] = f
    return out


# --------------------------------------------------------------------------- wave-frequency motion


@config_dataclass(frozen=True)
class MotionRAOs:
    """Parametric first-order motion RAOs for surge, sway and yaw of a free-floating ship.

    With ``k = omega^2 / g``, relative wave angle ``beta`` and the ship's extent along the
    wave propagation ``l(beta) = L |cos beta| + B |sin beta|``::

        h(k, beta) = exp(-k T / 2) / sqrt(1 + (k l(beta) / 2)^2)
        x_b / A    = -surge_gain cos(beta) h(k, beta)          [m/m]  (body x, forward)
        y_b / A    = -sway_gain  sin(beta) h(k, beta)          [m/m]  (body y, starboard)
        psi / A    = -yaw_gain k sin(2 beta) H(k L)            [rad/m]
        H(q)       = (q / 2 pi) exp(1 - q / 2 pi)              (= 1 at lambda = L)

    Long waves: a free-floating hull follows the horizontal orbital displacement of the
    water (amplitude A at the surface, deep water, Faltinsen 1990 ch. 2), so the
    horizontal RAO tends to 1 along the propagation direction. ``exp(-kT/2)``
    approximates the depth average of ``exp(kz)`` over the draught;
    ``1/sqrt(1 + (kl/2)^2)`` is the smooth envelope of the length-averaging factor
    ``sinc(k l / 2)`` (pressure integrated over the hull's extent along the wave).
    Yaw is driven by the wave slope ``kA`` through the Froude-Krylov yaw moment of a
    slender hull, which vanishes in head, beam and following seas (``sin 2 beta``) and
    peaks for wavelengths near the ship length.

    The horizontal motions are in phase with the orbital displacement (``sin theta``);
    yaw is taken in quadrature (``cos theta``).

    Attributes
    ----------
    L_m, B_m, T_m : float
        Hull length, beam, draught [m].
    surge_gain, sway_gain : float
        Long-wave RAO asymptotes [-] (1 = follows the water particles).
    yaw_gain : float
        Peak yaw amplitude per unit wave slope [rad/rad].
    """

    L_m: _Pos
    B_m: _Pos
    T_m: _Pos
    surge_gain: Annotated[Float, Field(ge=0.0, le=5.0)] = 1.0
    sway_gain: Annotated[Float, Field(ge=0.0, le=5.0)] = 1.0
    yaw_gain: Annotated[Float, Field(ge=0.0, le=5.0)] = 0.2

    @classmethod
    def from_hull(cls, hull, **gains) -> "MotionRAOs":
        """RAOs for a :class:`HullDimensions` or ``dict(L_m, B_m, T_m)`` with optional gains."""
        h = HullDimensions.from_any(hull)
        return cls(L_m=h.L_m, B_m=h.B_m, T_m=h.T_m, **gains)

    @classmethod
    def from_any(cls, raos) -> "MotionRAOs":
        """Accept :class:`MotionRAOs`, :class:`HullDimensions`, or a mapping of fields."""
        if isinstance(raos, cls):
            return raos
        if isinstance(raos, HullDimensions):
            return cls.from_hull(raos)
        if isinstance(raos, Mapping):
            allowed = {f.name for f in dataclasses.fields(cls)}
            unknown = set(raos) - allowed
            if unknown:
                raise ValueError(f"raos has unknown field(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
            return cls(**raos)
        raise TypeError(f"raos must be MotionRAOs, HullDimensions or a mapping, got {type(raos).__name__}")

    def amplitudes(self, omega_rad_s, beta_rad, g_m_s2=G_M_S2) -> np.ndarray:
        """Signed RAOs ``[x_b/A m/m, y_b/A m/m, psi/A rad/m]``, shape (..., 3)."""
        w, beta = _broadcast(omega_rad_s=omega_rad_s, beta_rad=beta_rad)
        k = w**2 / g_m_s2
        cb, sb = np.cos(beta), np.sin(beta)
        extent = self.L_m * np.abs(cb) + self.B_m * np.abs(sb)
        h = np.exp(-0.5 * k * self.T_m) / np.sqrt(1.0 + (0.5 * k * extent) ** 2)
        q = k * self.L_m / (2.0 * np.pi)
        out = np.empty(w.shape + (3,))
        out[..., 0] = -self.surge_gain * cb * h
        out[..., 1] = -self.sway_gain * sb * h
        out[..., 2] = -self.yaw_gain * k * np.sin(2.0 * beta) * q * np.exp(1.0 - q)
        return out


def wave_frequency_motion(time_s, psi_rad, components: WaveField, raos, *, position_ne_m=None,
                          return_rates=False):
    """First-order wave-frequency (WF) motion to superpose on the low-frequency track.

    For each component ``x_wf(t) = sum_j A_j RAO(omega_j, beta_j) * [sin, sin, cos](theta_j)``
    (see :class:`MotionRAOs`), with the body-frame surge/sway offsets rotated to NED by
    the heading: ``[dN, dE] = R(psi) [x_b, y_b]``. The offsets are zero-mean sums of
    sinusoids (Fossen 2021 sec. 10.2.2, superposition of WF and LF motion).

    Parameters
    ----------
    time_s : array_like (N,)
        Time [s].
    psi_rad : float or array_like (N,)
        (Low-frequency) heading [rad].
    components : WaveField
    raos : MotionRAOs, HullDimensions or mapping
        Motion RAO model; ``dict(L_m=..., B_m=..., T_m=...)`` gives the default gains.
    position_ne_m : array_like (N, 2), optional
        Low-frequency position for the wave phases (Doppler shift).
    return_rates : bool
        Also return the time derivatives (frozen heading and RAO, i.e. ``d theta/dt = omega``).

    Returns
    -------
    offsets : ndarray (N, 3)
        ``[north_m, east_m, psi_rad]`` WF offsets.
    rates : ndarray (N, 3), only if ``return_rates``
        ``[north_dot_m_s, east_dot_m_s, psi_dot_rad_s]``.
    """
    t = _time_vector(time_s)
    n = t.size
    psi = _per_time("psi_rad", psi_rad, n)
    pos = _positions(position_ne_m, n)
    model = MotionRAOs.from_any(raos)
    check_flags(return_rates=return_rates)      # a text "no" is truthy
    components = as_config(components, WaveField, "components")     # another object: an AttributeError
    amp, w = components.amplitude_m, components.omega_rad_s
    body = np.empty((n, 3))
    body_rate = np.empty((n, 3)) if return_rates else None
    for sl in _blocks(n, components.n_components):
        theta = components.phases(t[sl], None if pos is None else pos[sl])
        c, s = np.cos(theta), np.sin(theta)
        beta = wrap_pi(components.dir_from_rad[None, :] - psi[sl, None])
        r = model.amplitudes(w, beta, components.g_m_s2) * amp[None, :, None]   # (m, n_c, 3)
        body[sl, 0] = np.einsum("mj,mj->m", s, r[..., 0])
        body[sl, 1] = np.einsum("mj,mj->m", s, r[..., 1])
        body[sl, 2] = np.einsum("mj,mj->m", c, r[..., 2])
        if return_rates:
            body_rate[sl, 0] = np.einsum("mj,mj->m", c * w, r[..., 0])
            body_rate[sl, 1] = np.einsum("mj,mj->m", c * w, r[..., 1])
            body_rate[sl, 2] = -np.einsum("mj,mj->m", s * w, r[..., 2])
    cp, sp = np.cos(psi), np.sin(psi)

    def to_ned(b):
        return np.column_stack([cp * b[:, 0] - sp * b[:, 1], sp * b[:, 0] + cp * b[:, 1], b[:, 2]])

    if return_rates:
        return to_ned(body), to_ned(body_rate)
    return to_ned(body)


# --------------------------------------------------------------------------- Gauss-Markov


def _gauss_markov(time_s, sigma, tau_s, rng, *, method="auto"):
    """Stationary first-order Gauss-Markov process, exact discretisation on any time grid.

    ``x_{k+1} = a_k x_k + sigma sqrt(1 - a_k^2) n_k``, ``a_k = exp(-dt_k / tau)``, started
    from the stationary distribution ``x_0 ~ N(0, sigma^2)`` (Fossen 2021 sec. 10.3;
    Brown & Hwang). Uniform grids use ``scipy.signal.lfilter``; non-uniform grids use a
    block-wise closed-form sum ``x_k = e^{-s_k} (x_start + sum_j e^{s_j} w_j)``.
    """
    t = np.asarray(time_s, dtype=float)
    z = rng.standard_normal(t.size)
    if sigma == 0.0:
        return np.zeros(t.size)
    x = np.empty(t.size)
    x[0] = sigma * z[0]
    if t.size == 1:
        return x
    dt = np.diff(t)
    w = sigma * np.sqrt(-np.expm1(-2.0 * dt / tau_s)) * z[1:]
    uniform = np.allclose(dt, dt[0], rtol=1e-9, atol=0.0)
    if method == "lfilter" or (method == "auto" and uniform):
        a = math.exp(-dt[0] / tau_s)
        x[1:] = lfilter([1.0], [1.0, -a], w, zi=[a * x[0]])[0]
        return x
    s = np.cumsum(dt / tau_s)               # s[k-1] = (t_k - t_0) / tau, for x[k]
    start, prev, s_prev = 1, x[0], 0.0
    while start < t.size:
        rel = s[start - 1:] - s[start - 1]   # exponent relative to the block's first sample
        m = max(1, int(np.searchsorted(rel, 30.0, side="right")))
        r = rel[:m]
        decay0 = np.exp(-(s[start - 1:start - 1 + m] - s_prev))
        x[start:start + m] = decay0 * prev + np.exp(-r) * np.cumsum(np.exp(r) * w[start - 1:start - 1 + m])
        prev, s_prev = x[start + m - 1], s[start + m - 2]
        start += m
    return x


# --------------------------------------------------------------------------- wind


def harris_spectrum(f_hz, mean_speed_m_s, kappa=0.0026, length_scale_m=1800.0):
    """Harris (1971) longitudinal gust spectrum S(f) [m^2/s^2 per Hz], one-sided.

    ``S(f) = 4 kappa U L / (2 + (f L / U)^2)^(5/6)`` with ``U`` the 10 m mean wind speed,
    surface drag coefficient ``kappa`` and length scale ``L = 1800 m`` (Fossen 2021
    sec. 10.1.3; DNV-RP-C205 sec. 2.3.4). Its variance is ``6.68 kappa U^2``.
    """
    u = _positive("mean_speed_m_s", mean_speed_m_s)
    f = real_array("f_hz", f_hz)
    if np.isnan(f).any():       # it would fail f > 0 and come out as S = 0
        raise ValueError("f_hz: contains NaN")
    kappa, length_scale_m = _positive("kappa", kappa), _positive("length_scale_m", length_scale_m)
    x = f * length_scale_m / u
    return np.where(f > 0.0, 4.0 * kappa * u * length_scale_m / (2.0 + x**2) ** (5.0 / 6.0), 0.0)


def davenport_spectrum(f_hz, mean_speed_m_s, kappa=0.0026, length_scale_m=1200.0):
    """Davenport (1961) longitudinal gust spectrum S(f) [m^2/s^2 per Hz], one-sided.

    ``S(f) = 4 kappa U^2 x^2 / (f (1 + x^2)^(4/3))``, ``x = f L / U``, ``L = 1200 m``
    (DNV-RP-C205 sec. 2.3.4; Fossen 2021 sec. 10.1.3).
    """
    u = _positive("mean_speed_m_s", mean_speed_m_s)
    f = real_array("f_hz", f_hz)
    if np.isnan(f).any():       # it would fail f > 0 and come out as S = 0
        raise ValueError("f_hz: contains NaN")
    kappa, length_scale_m = _positive("kappa", kappa), _positive("length_scale_m", length_scale_m)
    fs = np.where(f > 0.0, f, 1.0)
    x = fs * length_scale_m / u
    return np.where(f > 0.0, 4.0 * kappa * u**2 * x**2 / (fs * (1.0 + x**2) ** (4.0 / 3.0)), 0.0)


def gust_wind(time_s, mean_speed_m_s, mean_dir_from_rad, rng, intensity=0.1, *, spectrum="harris",
              n_harmonics=200, f_max_hz=1.0, dir_std_rad=math.radians(3.0), dir_tau_s=300.0):
    """Gusting wind speed and slowly wandering direction at 10 m.

    Speed: ``U(t) = U_mean + sum_i a_i cos(2 pi f_i t + phi_i)`` with ``a_i = sqrt(2 S(f_i) df_i)``
    from the Harris or Davenport spectrum, random phases, and ``n_harmonics`` frequencies
    drawn one per logarithmically spaced bin between ``1 / duration`` and
    ``min(f_max_hz, Nyquist)`` (no periodicity). The spectrum only sets the shape: the
    amplitudes are rescaled so that the gust standard deviation is ``intensity * U_mean``
    (turbulence intensity over the record; gust energy at periods longer than the record
    belongs to the mean wind). Speed is clipped at 0.

    Direction: ``mean_dir_from_rad`` plus a first-order Gauss-Markov wander (standard
    deviation ``dir_std_rad``, time constant ``dir_tau_s``), exact discretisation.

    Parameters
    ----------
    time_s : array_like (N,)
        Time [s], strictly increasing, N >= 2.
    mean_speed_m_s : float
        Mean wind speed [m/s] (>= 0; 0 gives calm).
    mean_dir_from_rad : float
        Mean direction the wind comes FROM [rad], clockwise from north.
    rng : numpy.random.Generator or int
        Random source (or seed).
    intensity : float
        Turbulence intensity ``sigma_U / U_mean`` [-], in [0, 0.5].
    spectrum : {"harris", "davenport"}
    n_harmonics : int
    f_max_hz : float
        Highest gust frequency [Hz] (capped at the Nyquist frequency of ``time_s``); above
        ``1 / duration``, as the record must be long enough to hold a gust below Nyquist.
    dir_std_rad, dir_tau_s : float
        Direction wander standard deviation [rad] and time constant [s].

    Returns
    -------
    speed_m_s : ndarray (N,)
    dir_from_rad : ndarray (N,)
        In [0, 2 pi).
    """
    t = _time_vector(time_s, min_len=2)
    u = _positive("mean_speed_m_s", mean_speed_m_s, allow_zero=True)
    chi = _finite_scalar("mean_dir_from_rad", mean_dir_from_rad)
    ti = _in_range("intensity", intensity, 0.0, 0.5)
    rng = _as_rng(rng)
    if spectrum not in ("harris", "davenport"):
        raise ValueError(f"spectrum must be 'harris' or 'davenport', got {spectrum!r}")
    if not isinstance(n_harmonics, (int, np.integer)) or isinstance(n_harmonics, bool) or n_harmonics < 1:
        raise ValueError(f"n_harmonics must be a positive int, got {n_harmonics!r}")
    f_max = _positive("f_max_hz", f_max_hz)
    sd_dir = _positive("dir_std_rad", dir_std_rad, allow_zero=True)
    tau_dir = _positive("dir_tau_s", dir_tau_s)

    duration = t[-1] - t[0]
    f_lo = 1.0 / duration
    nyquist = 0.5 / float(np.min(np.diff(t)))
    f_hi = min(f_max, nyquist)
    if f_hi <= f_lo:        # it was widened to 2 / duration: gusts above f_max_hz, or aliased beyond Nyquist
        if f_max < nyquist:
            raise ValueError(f"f_max_hz: {f_max:g} Hz is not above the record's lowest gust frequency, 1 / duration "
                             f"= {f_lo:g} Hz (gusts slower than the record belong to the mean wind)")
        raise ValueError(f"time_s: {t.size} samples over {duration:g} s hold no gust frequency between 1 / duration "
                         f"= {f_lo:g} Hz and the Nyquist frequency {nyquist:g} Hz")
    edges = np.geomspace(f_lo, f_hi, n_harmonics + 1)
    freq = edges[:-1] + rng.uniform(0.0, 1.0, n_harmonics) * np.diff(edges)
    phase = rng.uniform(0.0, 2.0 * np.pi, n_harmonics)
    spec_fn = harris_spectrum if spectrum == "harris" else davenport_spectrum
    # Shape only (kappa cancels in the rescaling below); evaluated at U = max(U, 1) to allow calm.
    amp = np.sqrt(2.0 * spec_fn(freq, max(u, 1.0)) * np.diff(edges))
    amp *= ti * u / math.sqrt(0.5 * np.sum(amp**2))
    speed = np.full(t.size, u)
    for sl in _blocks(t.size, n_harmonics):
        speed[sl] += np.cos(2.0 * np.pi * np.multiply.outer(t[sl] - t[0], freq) + phase) @ amp
    direction = chi + _gauss_markov(t, sd_dir, tau_dir, rng)
    return np.maximum(speed, 0.0), wrap_2pi(direction)


# --------------------------------------------------------------------------- current


def current_series(time_s, mean_speed_m_s, mean_dir_to_rad, rng, speed_var=0.1,
                   dir_var_rad=math.radians(5.0), tau_s=600.0):
    """Slowly varying current: speed and direction with first-order Gauss-Markov variations.

    ``V(t) = max(0, V_mean (1 + x_V(t)))`` and ``beta_c(t) = beta_mean + x_b(t)``, where
    ``x_V`` and ``x_b`` are independent stationary Gauss-Markov processes with standard
    deviations ``speed_var`` (relative) and ``dir_var_rad`` and time constant ``tau_s``,
    discretised exactly (Fossen 2021 sec. 10.3: current as a first-order Gauss-Markov
    process).

    Parameters
    ----------
    time_s : array_like (N,)
        Time [s], strictly increasing.
    mean_speed_m_s : float
        Mean current speed [m/s] (>= 0).
    mean_dir_to_rad : float
        Mean direction the current flows TO [rad], clockwise from north.
    rng : numpy.random.Generator or int
        Random source (or seed).
    speed_var : float
        Standard deviation of the speed as a fraction of the mean [-] (0.1 = +-10 %).
    dir_var_rad : float
        Standard deviation of the direction [rad].
    tau_s : float
        Time constant [s] of both processes.

    Returns
    -------
    speed_m_s : ndarray (N,)
        Non-negative.
    dir_to_rad : ndarray (N,)
        In [0, 2 pi).
    """
    t = _time_vector(time_s)
    v = _positive("mean_speed_m_s", mean_speed_m_s, allow_zero=True)
    beta = _finite_scalar("mean_dir_to_rad", mean_dir_to_rad)
    sv = _in_range("speed_var", speed_var, 0.0, 1.0)
    sd = _positive("dir_var_rad", dir_var_rad, allow_zero=True)
    tau = _positive("tau_s", tau_s)
    rng = _as_rng(rng)
    speed = v * (1.0 + _gauss_markov(t, sv, tau, rng))
    direction = beta + _gauss_markov(t, sd, tau, rng)
    return np.maximum(speed, 0.0), wrap_2pi(direction)


def current_velocity_ned(speed_m_s, dir_to_rad):
    """Current velocity ``[V_north_m_s, V_east_m_s]``, shape (..., 2), from speed and direction TO."""
    v, b = _broadcast(speed_m_s=speed_m_s, dir_to_rad=dir_to_rad)
    return np.stack([v * np.cos(b), v * np.sin(b)], axis=-1)


# --------------------------------------------------------------------------- sea state

# WMO "probable wave height" [m] in the open sea for Beaufort numbers 0..12.
_BEAUFORT_HS_M = np.array([0.0, 0.1, 0.2, 0.6, 1.0, 2.0, 3.0, 4.0, 5.5, 7.0, 9.0, 11.5, 14.0])


def beaufort_wind_speed(beaufort):
    """Mean 10 m wind speed [m/s] for a (fractional) Beaufort number: ``0.836 B^1.5`` (WMO)."""
    b = real_array("beaufort", beaufort)
    if not np.all((b >= 0.0) & (b <= 12.5)):        # NaN too
        raise ValueError(f"beaufort must be in [0, 12.5], got {beaufort!r}")
    return 0.836 * b**1.5


def beaufort_wave_height(beaufort):
    """WMO probable (open-sea) wave height [m] for a (fractional) Beaufort number, interpolated."""
    b = real_array("beaufort", beaufort)
    if not np.all((b >= 0.0) & (b <= 12.5)):        # NaN too
        raise ValueError(f"beaufort must be in [0, 12.5], got {beaufort!r}")
    return np.interp(b, np.arange(13.0), _BEAUFORT_HS_M)


def _refuse_own(name: str, kwargs: dict, field: str | None = None) -> None:
    """A TypeError naming a setting the sea state gives itself (Python's 'got multiple values
    for keyword argument' named no way out)."""
    if name in kwargs:
        field = field or name
        raise TypeError(f"{name}: the sea state's own ({field} = ...); give it to SeaState, or a copy with "
                        f"dataclasses.replace(sea_state, {field}=...)")


@config_dataclass(frozen=True)
class SeaState:
    """Environmental conditions of one scenario (all SI, radians).

    Attributes
    ----------
    hs_m : float
        Significant wave height [m] (>= 0).
    tp_s : float
        Peak period [s] (> 0).
    wave_dir_from_rad : float
        Direction the waves come FROM [rad], clockwise from north.
    wind_speed_m_s : float
        Mean 10 m wind speed [m/s] (>= 0).
    wind_dir_from_rad : float
        Direction the wind comes FROM [rad], clockwise from north.
    gust_intensity : float
        Turbulence intensity [-], in [0, 0.5].
    current_speed_m_s : float
        Mean current speed [m/s] (>= 0).
    current_dir_to_rad : float
        Direction the current flows TO [rad], clockwise from north.
    gamma : float
        JONSWAP peak-enhancement factor [-], in [1, 7].
    """

    hs_m: _NonNeg
    tp_s: _Pos
    wave_dir_from_rad: Float
    wind_speed_m_s: _NonNeg
    wind_dir_from_rad: Float
    gust_intensity: Annotated[Float, Field(ge=0.0, le=0.5)] = 0.1
    current_speed_m_s: _NonNeg = 0.0
    current_dir_to_rad: Float = 0.0
    gamma: Annotated[Float, Field(ge=1.0, le=7.0)] = 3.3

    @model_validator(mode="after")
    def _a_sea_that_can_exist(self):
        # the simulator would drive the ship off at metres per second on DP
        check_steepness(self.hs_m, self.tp_s)
        return self

    @classmethod
    def random(cls, rng, beaufort=(2, 5), *, hs_fetch_factor=(0.5, 1.0), tp_coefficient=(4.0, 6.0),
               wave_spread_rad=math.radians(30.0), current_speed_m_s=(0.05, 0.4),
               gust_intensity=(0.08, 0.15), gamma=3.3) -> "SeaState":
        """Draw consistent conditions from a Beaufort range.

        * Beaufort number ``b ~ U(b_lo - 0.5, b_hi + 0.5)`` (so each class is covered),
          wind speed ``0.836 b^1.5`` m/s (WMO), wind direction uniform.
        * ``Hs`` = WMO probable open-sea wave height at ``b`` times a fetch factor drawn
          from ``hs_fetch_factor`` (coastal waters are fetch-limited).
        * ``Tp = c sqrt(Hs)`` with ``c ~ U(tp_coefficient)`` s/m^0.5 (DNV-RP-C205 sec.
          3.5.5: wind seas have ``3.6 < Tp/sqrt(Hs) < 5``; the upper part allows some
          swell), and ``Tp >= 2 s``.
        * Wave direction = wind direction + ``U(-wave_spread_rad, wave_spread_rad)``.
        * Current speed ``U(current_speed_m_s)``, direction uniform.
        * ``gamma``: fixed value, or ``None`` for the DNV-RP-C205 Hs-Tp relation.

        Parameters
        ----------
        rng : numpy.random.Generator or int
            Random source (or seed).
        beaufort : (int, int)
            Inclusive Beaufort range, 0 <= lo <= hi <= 12.

        Raises
        ------
        ValueError
            Naming ``tp_coefficient`` when its draw gives a sea steeper than waves can be
            (:data:`MAX_STEEPNESS`; only a coefficient below about 2.12 s/m^0.5 can).
        """
        rng = _as_rng(rng)
        try:
            b_lo, b_hi = _pair("beaufort", beaufort)
        except TypeError as exc:
            raise ValueError(str(exc)) from None
        if not (0.0 <= b_lo <= b_hi <= 12.0):
            raise ValueError(f"beaufort must satisfy 0 <= lo <= hi <= 12, got {beaufort!r}")
        for name, pair in (("hs_fetch_factor", hs_fetch_factor), ("tp_coefficient", tp_coefficient),
                           ("current_speed_m_s", current_speed_m_s), ("gust_intensity", gust_intensity)):
            lo, hi = _pair(name, pair)
            if not 0.0 <= lo <= hi:
                raise ValueError(f"{name} must be a (lo, hi) range with 0 <= lo <= hi, got {pair!r}")
        _in_range("wave_spread_rad", wave_spread_rad, 0.0, math.pi)
        b = rng.uniform(max(0.0, b_lo - 0.5), b_hi + 0.5)
        wind = float(beaufort_wind_speed(b))
        wind_dir = rng.uniform(0.0, 2.0 * np.pi)
        hs = float(beaufort_wave_height(b)) * rng.uniform(*hs_fetch_factor)
        c_tp = rng.uniform(*tp_coefficient)
        tp = max(2.0, c_tp * math.sqrt(hs))
        if hs > float(max_hs_m(tp)):        # only with c_tp below sqrt(2 pi / (MAX_STEEPNESS g))
            raise ValueError(f"tp_coefficient: {tuple(tp_coefficient)!r} drew Tp = max(2, {c_tp:g} sqrt(Hs)) = "
                             f"{tp:g} s at the drawn Hs {hs:g} m, steeper than waves can be "
                             f"(2 pi Hs / (g Tp^2) <= {MAX_STEEPNESS:.3f}): give a tp_coefficient of at least "
                             f"{math.sqrt(2.0 * math.pi / (MAX_STEEPNESS * G_M_S2)):.2f} s/m^0.5 (wind seas: "
                             f"3.6 to 5)")
        wave_dir = wind_dir + rng.uniform(-wave_spread_rad, wave_spread_rad)
        cur = rng.uniform(*current_speed_m_s)
        cur_dir = rng.uniform(0.0, 2.0 * np.pi)
        gi = rng.uniform(*gust_intensity)
        if gamma is None:
            gam = jonswap_gamma_dnv(hs, tp) if hs > 0.0 else 3.3
        else:
            gam = gamma
        return cls(hs_m=hs, tp_s=tp, wave_dir_from_rad=float(wrap_2pi(wave_dir)), wind_speed_m_s=wind,
                   wind_dir_from_rad=float(wind_dir), gust_intensity=gi, current_speed_m_s=cur,
                   current_dir_to_rad=float(cur_dir), gamma=gam)

    def wave_components(self, rng, n_components=50, spreading=None, **kwargs) -> WaveField:
        """Wave components of this sea state (:func:`make_wave_components`; its ``gamma`` is
        the sea state's own)."""
        _refuse_own("gamma", kwargs)
        return make_wave_components(self.hs_m, self.tp_s, self.wave_dir_from_rad, rng, n_components,
                                    spreading, gamma=self.gamma, **kwargs)

    def wind(self, time_s, rng, **kwargs):
        """Gusting wind ``(speed_m_s, dir_from_rad)`` of this sea state (:func:`gust_wind`; its
        ``intensity`` is the sea state's ``gust_intensity``)."""
        _refuse_own("intensity", kwargs, "gust_intensity")
        return gust_wind(time_s, self.wind_speed_m_s, self.wind_dir_from_rad, rng, self.gust_intensity, **kwargs)

    def current(self, time_s, rng, **kwargs):
        """Slowly varying current ``(speed_m_s, dir_to_rad)`` of this sea state (:func:`current_series`)."""
        return current_series(time_s, self.current_speed_m_s, self.current_dir_to_rad, rng, **kwargs)
