"""Weather for drift-off studies: one state with its uncertainty, or a table of states.

A :class:`WeatherState` holds means (SI units and radians inside); a
:class:`WeatherUncertainty` the standard deviations the Monte-Carlo samples draw from
(normal, clipped to the range a :class:`WeatherState` allows: speeds and heights to
``[0, max]``, periods to ``[1 s, MAX_TP_S]``, and heights to the limiting steepness of
:func:`limiting_hs_m`, or the state's own where it is steeper, so that a wide spread
cannot draw a sea the models are not meant for). :func:`read_weather_table`
reads an hourly hindcast (or any list of states) from CSV; its columns, degrees at this
edge as everywhere in the project's files:

==================  ========  ==============================================================
column              unit      meaning
==================  ========  ==============================================================
``time``            ISO 8601  optional label of the state (kept as text)
``wind_speed_m_s``  m/s       mean 10 m wind speed (0 to :data:`MAX_WIND_M_S`)
``wind_dir_deg``    deg       direction the wind comes FROM, clockwise from north
``hs_m``            m         significant wave height (0 to 20, at most :func:`max_hs_m`)
``tp_s``            s         spectral peak period (1 to 30)
``wave_dir_deg``    deg       direction the waves come FROM, clockwise from north
``current_m_s``     m/s       current speed (0 to :data:`MAX_CURRENT_M_S`)
``current_dir_deg`` deg       direction the current flows TO, clockwise from north
``gust_intensity``  -         optional turbulence intensity sigma_U / U in [0, 0.5] (default 0.1)
==================  ========  ==============================================================

:func:`sample_environment` turns a state, its uncertainty and a random generator into the
per-sample arrays the kernel reads (wind with gust harmonics, current, wave components).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Mapping, Set
from dataclasses import dataclass
from typing import Annotated
from pathlib import Path

import numpy as np
import pandas as pd
from pydantic import AfterValidator, Field, model_validator

from ..config import Float, check_number, check_whole_number, config_dataclass
from ..fileio import as_path
from ..frames import wrap_2pi
from ..logs.io import RAD_SPREAD_LIMIT, unit_variant
from ..messages import warn_user
from ..forecast_inputs.limits import Envelope
from ..sim import environment as env
from ..sim.environment import MAX_STEEPNESS, check_steepness, max_hs_m

__all__ = ["WeatherState", "WeatherUncertainty", "TABLE_COLUMNS", "read_weather_table", "states_to_frame",
           "SampledEnvironment", "sample_environment", "limiting_hs_m", "max_hs_m", "MAX_STEEPNESS"]

#: Required columns of a weather table (see the module notes), and the optional ones.
TABLE_COLUMNS = ("wind_speed_m_s", "wind_dir_deg", "hs_m", "tp_s", "wave_dir_deg", "current_m_s",
                 "current_dir_deg")
OPTIONAL_COLUMNS = ("time", "gust_intensity")
#: Each column's name without its unit, to point out one logged in another unit (``wind_speed_kn``).
_COLUMN_STEMS = {"wind_speed_m_s": ("wind_speed",), "wind_dir_deg": ("wind_dir",), "hs_m": ("hs",),
                 "tp_s": ("tp",), "wave_dir_deg": ("wave_dir",), "current_m_s": ("current",),
                 "current_dir_deg": ("current_dir",)}


def _table_column_of(name: str) -> str | None:
    """The table column that ``name`` looks like in another unit (``wind_speed_kn`` ->
    ``wind_speed_m_s``), by the log reader's rule (:func:`hybridship.logs.io.unit_variant`)."""
    return unit_variant(name.strip(), _COLUMN_STEMS, TABLE_COLUMNS + OPTIONAL_COLUMNS)


_NonNeg = Annotated[Float, Field(ge=0.0)]
def _direction(v: float) -> float:
    if abs(v) > 2.0 * math.pi + 0.1:
        raise ValueError(f"expected radians within +-2 pi, got {v!r} (degrees? convert with math.radians)")
    return v


def _direction_std(v: float) -> float:
    if not 0.0 <= v <= math.pi:
        raise ValueError(f"expected a spread in radians from 0 to pi, got {v!r} (degrees? convert with "
                         f"math.radians; beyond pi every direction is as likely)")
    return v


#: A direction [rad], and the spread of one: a value in degrees is refused, not wrapped.
_Direction = Annotated[Float, AfterValidator(_direction)]
_DirectionStd = Annotated[Float, AfterValidator(_direction_std)]


def _check(name, value, lo=None, hi=None, lo_open=False):
    return check_number(name, value, lo=lo, hi=hi, lo_open=lo_open)


#: Largest mean wind [m/s] and current [m/s]: the physics inputs' valid range
#: (:class:`hybridship.forecast_inputs.limits.Envelope`).
MAX_WIND_M_S = Envelope().wind_speed_max_m_s
MAX_CURRENT_M_S = Envelope().current_speed_max_m_s
#: Largest significant wave height [m] and peak period [s] of a weather state: beyond the
#: sea states the wave and wave-drift models are meant for.
MAX_HS_M = 20.0
MAX_TP_S = 30.0
#: Shortest peak period [s]: shorter waves do not move a ship.
MIN_TP_S = 1.0


def limiting_hs_m(tp_s):
    """Largest significant wave height [m] at peak period ``tp_s`` [s]: the limiting
    steepness ``S_p = 2 pi Hs / (g Tp^2)`` of DNV-RP-C205 (sec. 3.5.5), 1/15 for Tp <= 8 s,
    1/25 for Tp >= 15 s, linear in between."""
    tp = np.asarray(tp_s, dtype=float)
    return np.interp(tp, [8.0, 15.0], [1.0 / 15.0, 1.0 / 25.0]) * env.G_M_S2 * tp**2 / (2.0 * np.pi)


@config_dataclass(frozen=True, prefix="weather")
class WeatherState:
    """Mean weather of one state (SI, radians; directions as in :mod:`hybridship.sim.environment`).

    Attributes
    ----------
    wind_speed_m_s : float
        Mean 10 m wind speed [m/s], at most :data:`MAX_WIND_M_S`.
    wind_dir_from_rad : float
        Direction the wind comes FROM [rad], clockwise from north.
    hs_m, tp_s : float
        Significant wave height [m] and peak period [s] (JONSWAP, gamma 3.3, long-crested),
        at most :data:`MAX_HS_M` and no steeper than :data:`MAX_STEEPNESS` (:func:`max_hs_m`);
        the period between :data:`MIN_TP_S` and :data:`MAX_TP_S`.
    wave_dir_from_rad : float
        Direction the waves come FROM [rad].
    current_speed_m_s : float
        Current speed [m/s], at most :data:`MAX_CURRENT_M_S`.
    current_dir_to_rad : float
        Direction the current flows TO [rad].
    gust_intensity : float
        Turbulence intensity sigma_U / U [-] in [0, 0.5].
    """

    # upper bounds: the physics inputs' valid range (hybridship.forecast_inputs.limits), and the
    # sea states the wave model is meant for; beyond them the drift diverges instead of failing
    wind_speed_m_s: Annotated[Float, Field(ge=0.0, le=MAX_WIND_M_S)] = 0.0
    wind_dir_from_rad: _Direction = 0.0
    hs_m: Annotated[Float, Field(ge=0.0, le=MAX_HS_M)] = 0.0
    tp_s: Annotated[Float, Field(ge=MIN_TP_S, le=MAX_TP_S)] = 6.0
    wave_dir_from_rad: _Direction = 0.0
    current_speed_m_s: Annotated[Float, Field(ge=0.0, le=MAX_CURRENT_M_S)] = 0.0
    current_dir_to_rad: _Direction = 0.0
    gust_intensity: Annotated[Float, Field(ge=0.0, le=0.5)] = 0.1

    @model_validator(mode="after")
    def _a_sea_that_can_exist(self):
        check_steepness(self.hs_m, self.tp_s)     # Miche's breaking limit (deep water: 1/7)
        return self

    @classmethod
    def from_degrees(cls, *, wind_speed_m_s=0.0, wind_dir_deg=0.0, hs_m=0.0, tp_s=6.0, wave_dir_deg=None,
                     current_m_s=0.0, current_dir_deg=0.0, gust_intensity=0.1) -> "WeatherState":
        """Build from degrees (the file and CLI edge); waves default to the wind direction."""
        # checked in degrees, as given: a wave direction that defaults to the wind's is not named again
        wind = _check("weather.wind_dir_deg", wind_dir_deg, lo=-360.0, hi=360.0)
        wave = wind if wave_dir_deg is None else _check("weather.wave_dir_deg", wave_dir_deg, lo=-360.0, hi=360.0)
        current = _check("weather.current_dir_deg", current_dir_deg, lo=-360.0, hi=360.0)
        return cls(wind_speed_m_s, math.radians(wind), hs_m, tp_s, math.radians(wave), current_m_s,
                   math.radians(current), gust_intensity)


@config_dataclass(frozen=True, prefix="uncertainty")
class WeatherUncertainty:
    """Standard deviations of the weather the samples draw from (0 = known exactly).

    Attributes
    ----------
    wind_speed_m_s, wind_dir_rad, hs_m, tp_s, wave_dir_rad, current_speed_m_s, current_dir_rad : float
        One standard deviation of the corresponding :class:`WeatherState` field
        [m/s, rad, m, s, rad, m/s, rad].
    """

    wind_speed_m_s: _NonNeg = 0.0
    wind_dir_rad: _DirectionStd = 0.0
    hs_m: _NonNeg = 0.0
    tp_s: _NonNeg = 0.0
    wave_dir_rad: _DirectionStd = 0.0
    current_speed_m_s: _NonNeg = 0.0
    current_dir_rad: _DirectionStd = 0.0

    @classmethod
    def typical(cls) -> "WeatherUncertainty":
        """A forecast-like default: 1.5 m/s, 15 deg wind; 0.25 m, 1 s, 20 deg waves; 0.1 m/s, 30 deg current."""
        return cls(1.5, math.radians(15.0), 0.25, 1.0, math.radians(20.0), 0.1, math.radians(30.0))


#: The range of each bounded column of a weather table (those of :class:`WeatherState`).
_TABLE_RANGES = {"wind_speed_m_s": (0.0, MAX_WIND_M_S), "hs_m": (0.0, MAX_HS_M), "tp_s": (MIN_TP_S, MAX_TP_S),
                 "current_m_s": (0.0, MAX_CURRENT_M_S), "gust_intensity": (0.0, 0.5),
                 **{f"{x}_dir_deg": (-360.0, 360.0) for x in ("wind", "wave", "current")}}


def read_weather_table(path_or_frame) -> tuple[list[WeatherState], list[str]]:
    """Weather states from a CSV file (or DataFrame) with the columns of the module notes.

    Returns the states and their labels (the ``time`` column, or the row numbers). Errors
    name the file, the column and the first bad row.
    """
    if isinstance(path_or_frame, pd.DataFrame):
        df, src = path_or_frame, "weather table"
        names = [str(c) for c in df.columns]
    else:
        src = str(as_path(path_or_frame, "path_or_frame"))    # not "no such file 'None'", nor '' as the folder .
        if Path(src).is_dir():
            raise IsADirectoryError(f"weather table: {src!r} is a folder; expected a CSV file")
        if not Path(src).is_file():
            raise FileNotFoundError(f"weather table: no such file {src!r}")
        try:
            with warnings.catch_warnings():
                # a row with more fields than the header: pandas would take the first column
                # as the index and shift every other one (index_col=False), or drop the last
                warnings.simplefilter("error", pd.errors.ParserWarning)
                # the labels as written: 0100 is not the number 100, nor 1.10 the same as 1.1
                df = pd.read_csv(src, index_col=False, dtype={"time": str})
        except pd.errors.ParserWarning:
            raise ValueError(f"{src}: {_field_count_problem(src)}; a weather table's rows have one field per "
                             f"header column") from None
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
            what = ("the file is empty" if isinstance(exc, pd.errors.EmptyDataError) else
                    "it is not text (a binary file?)" if isinstance(exc, UnicodeDecodeError) else
                    ' '.join(str(exc).split()))
            raise ValueError(f"{src}: not a readable CSV weather table (expected a header line with "
                             f"{list(TABLE_COLUMNS)}; {what})") from None
        # pandas renames a repeated name (hs_m, hs_m.1): the header as written
        header = pd.read_csv(src, header=None, nrows=1, dtype=str, keep_default_na=False)
        names = [str(c) for c in header.iloc[0]] if len(header) else []
    dup = next((c for c in names if c.strip() and names.count(c) > 1), None)
    if dup is not None:     # which of the two would be read is pandas' choice, not the user's
        raise ValueError(f"{src}: column {dup!r} appears more than once; a weather table names each column once")
    missing = [c for c in TABLE_COLUMNS if c not in df.columns]
    if missing:
        cols = [str(c) for c in df.columns]
        spaced = [c for c in cols if c != c.strip() and c.strip() in missing][:1]
        hint = "".join(f"; found {c!r}, which is {c.strip()} with spaces around the name (a header written with "
                       f"', ' between names?)" for c in spaced)
        hint += "".join(f"; found {c!r}, which looks like {_table_column_of(c)} in another unit: convert it and "
                        f"name it {_table_column_of(c)}" for c in cols if _table_column_of(c) in missing)
        hint += "".join([f"; the header is one name holding {sep!r}: the weather table separates columns with "
                         f"',' (and writes decimals with '.')" for sep in (";", "\t")
                         if len(cols) == 1 and sep in cols[0]][:1])
        raise ValueError(f"{src}: missing column(s) {missing}; expected {list(TABLE_COLUMNS)} "
                         f"(optional {list(OPTIONAL_COLUMNS)}){hint}")
    if len(df) == 0:
        raise ValueError(f"{src}: no rows")
    unknown = [str(c) for c in df.columns if c not in TABLE_COLUMNS + OPTIONAL_COLUMNS]
    if unknown:      # a misspelt optional column would otherwise be replaced by its default unseen
        warn_user(f"{src}: column(s) {', '.join(unknown)} not used; the weather table's columns are "
                  f"{', '.join(TABLE_COLUMNS + OPTIONAL_COLUMNS)}", UserWarning)
    cols = {}
    for c in TABLE_COLUMNS + ("gust_intensity",):
        if c not in df.columns:
            continue
        v = pd.to_numeric(df[c], errors="coerce").to_numpy(float)
        lo, hi = _TABLE_RANGES.get(c, (-np.inf, np.inf))
        with np.errstate(invalid="ignore"):
            bad = ~(np.isfinite(v) & (v >= lo) & (v <= hi))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            expected = "a finite number" if c not in _TABLE_RANGES else f"a number in [{lo:g}, {hi:g}]"
            line = "" if isinstance(path_or_frame, pd.DataFrame) else f" (line {_line_of_row(src, i)} of the file)"
            raw = df[c].iloc[i]
            got = ("a missing value" if pd.isna(raw) else
                   f"{raw.item() if isinstance(raw, np.generic) else raw!r}")    # 99, not np.int64(99)
            raise ValueError(f"{src}: column {c!r}, row {i}{line}: {got}, expected {expected} "
                             f"({int(bad.sum())} bad row(s))")
        cols[c] = v
    _warn_directions_like_radians(cols, src)
    gi = cols.get("gust_intensity", np.full(len(df), 0.1))
    states = []
    for i in range(len(df)):
        try:
            states.append(WeatherState(cols["wind_speed_m_s"][i], math.radians(cols["wind_dir_deg"][i]),
                                       cols["hs_m"][i], cols["tp_s"][i], math.radians(cols["wave_dir_deg"][i]),
                                       cols["current_m_s"][i], math.radians(cols["current_dir_deg"][i]), gi[i]))
        except ValueError as exc:       # a combination of columns (a sea steeper than waves can be)
            line = "" if isinstance(path_or_frame, pd.DataFrame) else f" (line {_line_of_row(src, i)} of the file)"
            raise ValueError(f"{src}: row {i}{line}: {str(exc).removeprefix('weather.')}") from None
    labels = [str(i) for i in range(len(df))]
    if "time" in df.columns:
        labels = [str(x) for x in df["time"]]
        t = df["time"]
        bad = t.isna() | t.duplicated(keep="first")      # a season table's row must say which state it is
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            line = "" if isinstance(path_or_frame, pd.DataFrame) else f" (line {_line_of_row(src, i)} of the file)"
            got = "empty" if pd.isna(t.iloc[i]) else f"{labels[i]!r} again (first in row {labels.index(labels[i])})"
            raise ValueError(f"{src}: column 'time', row {i}{line}: {got}; each state needs a label of its own "
                             f"(or leave the column out to number the rows)")
    return states, labels


def _warn_directions_like_radians(cols: dict, src: str) -> None:
    """Warn when a direction column of 20 rows or more lies within one turn in radians yet
    spreads over most of it (the spread rule of the logs' angles): read as degrees, every
    direction would be squeezed into the first 6.3 deg."""
    for c in ("wind_dir_deg", "wave_dir_deg", "current_dir_deg"):
        v = cols[c]
        within_a_turn = v.min() >= 0.0 and v.max() <= 2.0 * math.pi + 1e-6
        if v.size >= 20 and within_a_turn and np.ptp(v) >= RAD_SPREAD_LIMIT:
            warn_user(f"{src}: column {c!r} spans {v.min():.2f} to {v.max():.2f}, which looks like radians; "
                      f"the table expects degrees (convert with numpy.degrees)", UserWarning)


def _open_text(src: str):
    """The file ``src`` opened as text for the csv module (a .csv.gz as its text, as pandas reads it)."""
    import gzip

    from ..fileio import starts_with

    opener = gzip.open if starts_with(src, b"\x1f\x8b") else open
    return opener(src, "rt", newline="", encoding="utf-8", errors="replace")


def _line_of_row(src: str, i: int) -> int:
    """The line of the file on which data row ``i`` starts, counted as the reader counts rows:
    blank lines (empty or spaces only) are no rows, yet lines of the file."""
    import csv

    with _open_text(src) as fh:
        rows = csv.reader(fh)
        start, k = 1, -2                # -2: the header line comes first
        for row in rows:
            if len(row) > 1 or "".join(row).strip():
                k += 1
                if k == i:
                    return start
            start = rows.line_num + 1
    return i + 2


def _field_count_problem(src: str) -> str:
    """Which line of a CSV file first has another number of fields than its header line."""
    import csv

    with _open_text(src) as fh:       # a .csv.gz's lines, not its compressed bytes
        rows = csv.reader(fh)
        n = len(next(rows, []))
        for k, row in enumerate(rows, start=2):
            if row and len(row) != n:
                return f"line {k} has {len(row)} fields, the header line {n}"
    return f"a line has another number of fields than the header line ({n})"


def label_list(labels, n: int) -> list:
    """``labels`` as a list of ``n`` state labels, refused naming ``labels`` when it is text
    (whose characters would be the labels: "ab" for two states, or one state's "2024-01-01"
    as 10), has no order (a set) or holds another number of labels."""
    if isinstance(labels, (str, bytes, Set, Mapping)) or not isinstance(labels, Iterable):
        raise TypeError(f"labels: expected a list of labels, one per state, got {type(labels).__name__} {labels!r}")
    labels = list(labels)
    if len(labels) != n:      # pandas would say "Length of values ... index", naming neither
        raise ValueError(f"labels: expected {n} labels, one per state, got {len(labels)}")
    return labels


def states_to_frame(states, labels=None) -> pd.DataFrame:
    """The inverse of :func:`read_weather_table` (degrees at the edge); ``labels``, when
    given, one per state (the ``time`` column)."""
    if isinstance(states, (WeatherState, str, bytes, Set, Mapping)) or not isinstance(states, Iterable):
        raise TypeError(f"states: expected a list of WeatherState (as read_weather_table gives), got "
                        f"{type(states).__name__}")
    states = list(states)
    for i, s in enumerate(states):      # each row's fields are read from it: 'int' has no attribute ...
        if not isinstance(s, WeatherState):
            raise TypeError(f"states[{i}]: expected a WeatherState, got {type(s).__name__}")
    labels = None if labels is None else label_list(labels, len(states))
    rows = [{"wind_speed_m_s": s.wind_speed_m_s, "wind_dir_deg": math.degrees(s.wind_dir_from_rad) % 360.0,
             "hs_m": s.hs_m, "tp_s": s.tp_s, "wave_dir_deg": math.degrees(s.wave_dir_from_rad) % 360.0,
             "current_m_s": s.current_speed_m_s, "current_dir_deg": math.degrees(s.current_dir_to_rad) % 360.0,
             "gust_intensity": s.gust_intensity} for s in states]
    df = pd.DataFrame(rows)
    if labels is not None:
        df.insert(0, "time", list(labels))
    return df


@dataclass(frozen=True)
class SampledEnvironment:
    """Per-sample environment arrays for the kernel (N samples).

    Attributes
    ----------
    wind_mean_m_s, wind_dir_from_rad : ndarray (N,)
    gust_f_hz, gust_amp_m_s, gust_phase_rad : ndarray (N, n_gust)
        Gust harmonics added to the mean speed.
    current : ndarray (N, 2)
        ``[speed_m_s, dir_to_rad]``.
    waves : tuple of 4 ndarrays (N, n_wave)
        Component frequency [rad/s], amplitude [m], phase [rad], direction from [rad]
        (a sample with Hs = 0 has zero amplitudes).
    """

    wind_mean_m_s: np.ndarray
    wind_dir_from_rad: np.ndarray
    gust_f_hz: np.ndarray
    gust_amp_m_s: np.ndarray
    gust_phase_rad: np.ndarray
    current: np.ndarray
    waves: tuple


#: JONSWAP peak enhancement [-] and frequency band [x omega_p] of the sampled seas: those of
#: :func:`~hybridship.sim.environment.make_wave_components` by default (a test holds them equal).
_WAVE_GAMMA = 3.3
_WAVE_BAND = (0.5, 3.5)


def _harris_shape(f_hz, u_m_s, length_scale_m=1800.0):
    """Harris (1971) spectrum up to a constant (as :func:`hybridship.sim.environment.harris_spectrum`)."""
    return u_m_s * length_scale_m / (2.0 + (f_hz * length_scale_m / u_m_s) ** 2) ** (5.0 / 6.0)


def _check_sampling(state, uncertainty, n, rng, n_gust, n_wave) -> tuple[int, int, int]:
    """:func:`sample_environment`'s arguments other than the times, refused naming them (they
    failed in numpy's words, or read a text or a float as a count)."""
    if not isinstance(state, WeatherState):
        raise TypeError(f"state: expected a WeatherState, got {type(state).__name__}")
    if uncertainty is not None and not isinstance(uncertainty, WeatherUncertainty):
        raise TypeError(f"uncertainty: expected a WeatherUncertainty or None, got {type(uncertainty).__name__}")
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng: expected a numpy.random.Generator (numpy.random.default_rng(seed)), got "
                        f"{type(rng).__name__}")
    return tuple(check_whole_number(name, v) for name, v in (("n", n), ("n_gust", n_gust), ("n_wave", n_wave)))


def sample_environment(state: WeatherState, uncertainty: WeatherUncertainty | None, n: int,
                       rng: np.random.Generator, *, duration_s: float, dt_s: float, n_gust: int = 20,
                       n_wave: int = 20) -> SampledEnvironment:
    """Draw ``n`` environment samples of a weather state (see :class:`SampledEnvironment`).

    Weather means are drawn from ``uncertainty`` (normal, clipped to the range of
    :class:`WeatherState`); each sample then gets its own
    gust harmonics (Harris shape, log-spaced jittered frequencies between ``1 / duration_s``
    and the Nyquist frequency of ``dt_s``, rescaled to ``gust_intensity * U``) and its own
    random-phase JONSWAP components, drawn as
    :func:`~hybridship.sim.environment.make_wave_components` draws one sea with its defaults
    (long-crested from the sample's wave direction, gamma 3.3, ``n_wave`` equal bins on
    [0.5, 3.5] times the sample's own peak frequency with one jittered frequency in each,
    amplitudes rescaled to the sample's Hs exactly; a sample with Hs = 0 has zero amplitudes).

    All samples are drawn at once from ``rng``, in a fixed order: the weather's normal
    deviates (n, 7), the gust frequencies' jitter and phases (n, n_gust) each, then the
    wave frequencies' jitter and phases (n, n_wave) each; so a seed gives the same samples.

    Parameters
    ----------
    state : WeatherState
        The weather's means.
    uncertainty : WeatherUncertainty or None
        Standard deviations of the means (None: known exactly).
    n : int
        Number of samples.
    rng : numpy.random.Generator
        Random source.
    duration_s, dt_s : float
        Length [s] and time step [s] of the drift the gusts must resolve.
    n_gust, n_wave : int
        Gust harmonics and wave components per sample.

    Returns
    -------
    SampledEnvironment
    """
    n, n_gust, n_wave = _check_sampling(state, uncertainty, n, rng, n_gust, n_wave)
    # a NaN duration or step gave NaN gusts without a word, a negative step gusts at a made-up band
    duration_s = check_number("duration_s", duration_s, lo=0.0, lo_open=True)
    dt_s = check_number("dt_s", dt_s, lo=0.0, lo_open=True)
    u = uncertainty or WeatherUncertainty()
    s = state
    z = rng.standard_normal((n, 7))
    # clipped to the range a WeatherState allows (beyond it the drift would diverge)
    wind = np.clip(s.wind_speed_m_s + u.wind_speed_m_s * z[:, 0], 0.0, MAX_WIND_M_S)
    wind_dir = s.wind_dir_from_rad + u.wind_dir_rad * z[:, 1]
    tp = np.clip(s.tp_s + u.tp_s * z[:, 3], MIN_TP_S, MAX_TP_S)
    # and no steeper than waves get (a spread drew Hs 20 m at Tp 2 s, and the drift
    # diverged), or than the state itself where it is steeper: a spread adds no constraint
    steepest = max(1.0, s.hs_m / float(limiting_hs_m(s.tp_s)))
    hs = np.clip(s.hs_m + u.hs_m * z[:, 2], 0.0, np.minimum(MAX_HS_M, steepest * limiting_hs_m(tp)))
    wave_dir = s.wave_dir_from_rad + u.wave_dir_rad * z[:, 4]
    cur = np.clip(s.current_speed_m_s + u.current_speed_m_s * z[:, 5], 0.0, MAX_CURRENT_M_S)
    cur_dir = s.current_dir_to_rad + u.current_dir_rad * z[:, 6]

    f_lo = 1.0 / duration_s
    f_hi = max(0.5 / dt_s, 2.0 * f_lo)
    edges = np.geomspace(f_lo, f_hi, n_gust + 1)
    freq = edges[:-1] + rng.uniform(0.0, 1.0, (n, n_gust)) * np.diff(edges)
    phase = rng.uniform(0.0, 2.0 * np.pi, (n, n_gust))
    u_ref = np.maximum(wind, 1.0)[:, None]
    amp = np.sqrt(2.0 * _harris_shape(freq, u_ref) * np.diff(edges))
    amp *= (s.gust_intensity * wind)[:, None] / np.sqrt(0.5 * np.sum(amp**2, axis=1, keepdims=True))

    # make_wave_components' defaults (jittered, long-crested, gamma 3.3), all samples at once
    u_wave = rng.uniform(0.0, 1.0, (n, n_wave))
    wave_phase = rng.uniform(0.0, 2.0 * np.pi, (n, n_wave))
    ww, _, wa = env._jittered_components(hs, tp, _WAVE_GAMMA, u_wave, _WAVE_BAND)
    wd = np.repeat(wrap_2pi(wave_dir)[:, None], n_wave, axis=1)
    return SampledEnvironment(wind, wind_dir, freq, amp, phase, np.column_stack([cur, cur_dir]),
                              (ww, wa, wave_phase, wd))
