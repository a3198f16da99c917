"""Loader for the Esso Osaka free-running model tests (FRT-DS-ESSO) into the project's log format.

The data set (Osaka University; see ``shared/data/esso-osaka-frt/README.md``) holds one CSV
per run, plain or gzip-compressed, at 10 Hz, with the header

``t [s], x_position_mid [m], u_velo [m/s], y_position_mid [m], vm_velo [m/s], psi_hat [rad],
r_angvelo [rad/s], n_prop [rps], delta_rudder [rad], wind_velo_relative_mid [m/s],
wind_dir_relative_mid [rad], wind_velo_true [m/s], wind_dir_true [rad]``.

Mapping into the log format (``shared/spec/log-format.md``); every sign below is checked
against the data by :func:`convention_checks` and the tests:

==============================  =======================  ===============================
data                            log column               note
==============================  =======================  ===============================
``t``                           ``time_s``
``x_position_mid``              ``north_m``              x0 is used as north (not geographic)
``y_position_mid``              ``east_m``               y0 is 90 deg clockwise from x0
``psi_hat``                     ``heading_deg``          from +x0 towards +y0, as NED
``u_velo``, ``vm_velo``         ``u_m_s``, ``v_m_s``     midship = the body origin
``r_angvelo``                   ``r_deg_s``              clockwise
``n_prop`` [rev/s]              ``<propeller>_rpm``      x 60; + = ahead
``delta_rudder``                ``<rudder>_azimuth_deg`` + turns to starboard (MMG)
``wind_velo_true``              ``wind_speed_m_s``
``wind_dir_true``               ``wind_dir_deg``         where it comes FROM, from +x0 to +y0
==============================  =======================  ===============================

The apparent-wind columns are redundant (the true wind, heading and velocities give
them; :func:`convention_checks` verifies that) and are not carried into the log.

Known quirks handled here: all-empty trailing rows are dropped (one zigzag file ends with
327 of them); the ``turn_cut_<stamp>`` file whose uncut ``turn_<stamp>`` is present is a
duplicate and is skipped by :func:`list_runs`; ``random_<stamp>_<k>`` pieces are labelled
with one ``recording`` so that a train/test split can keep them together.

Timing: the logged u and vm lag the position derivative by about 0.6 s. The loader keeps
them as logged (a forecast at time t may only use data up to t); ``velocity_lead_s``
shifts them earlier, for analysis only.

Cite: Wakita et al. (2022), J. Mar. Sci. Technol. 27, 772-785, doi:10.1007/s00773-021-00867-1;
Miyauchi et al. (2022), J. Mar. Sci. Technol. 27, 1065-1083, doi:10.1007/s00773-022-00889-3.
"""

from __future__ import annotations

import os
import re
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..config import check_flags, check_number
from ..logs.io import LogArrays, LogFormatError, log_to_arrays, validate_log

__all__ = [
    "ESSO_COLUMNS",
    "RUN_KINDS",
    "EssoRun",
    "default_data_dir",
    "read_esso_raw",
    "esso_to_log",
    "read_esso_osaka",
    "esso_log_arrays",
    "run_kind",
    "list_runs",
    "convention_checks",
]

#: The header of every file in the data set, in order.
ESSO_COLUMNS = (
    "t [s]", "x_position_mid [m]", "u_velo [m/s]", "y_position_mid [m]", "vm_velo [m/s]", "psi_hat [rad]",
    "r_angvelo [rad/s]", "n_prop [rps]", "delta_rudder [rad]", "wind_velo_relative_mid [m/s]",
    "wind_dir_relative_mid [rad]", "wind_velo_true [m/s]", "wind_dir_true [rad]",
)

#: Run kinds of the data set, as the manifest names them.
RUN_KINDS = ("random", "turning", "zigzag", "berthing")

#: File-name prefixes of each kind (used when no manifest lists the file).
_PREFIX_KIND = {"random": "random", "turn": "turning", "zigzag": "zigzag", "berthing": "berthing"}

#: Environment variable that overrides :func:`default_data_dir`.
DATA_DIR_ENV = "HYBRIDSHIP_ESSO_OSAKA_DIR"


def default_data_dir() -> Path:
    """Where the data set is expected: ``$HYBRIDSHIP_ESSO_OSAKA_DIR``, else ``../shared/data/esso-osaka-frt``
    beside the source checkout (the path may not exist)."""
    env = os.environ.get(DATA_DIR_ENV)
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[3] / "shared" / "data" / "esso-osaka-frt"


# --------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------


def read_esso_raw(path) -> pd.DataFrame:
    """Read one run (``.csv`` or ``.csv.gz``) as published, dropping all-empty rows.

    Raises
    ------
    LogFormatError
        If the header differs from :data:`ESSO_COLUMNS`, a value is missing, not a number or
        infinite in a kept row,
        or time does not increase strictly (the message names the column, row and file).
    """
    path = Path(path)
    name = path.name.lower()
    if not (name.endswith(".csv") or name.endswith(".csv.gz")):
        raise LogFormatError(f"{path}: expected a .csv or .csv.gz file of the Esso Osaka data set")
    try:
        # blank lines kept (as empty rows, dropped below) so that row numbers match the file's lines
        df = pd.read_csv(path, compression="gzip" if name.endswith(".gz") else None, skip_blank_lines=False)
    except FileNotFoundError:
        raise
    except (OSError, EOFError, zlib.error, UnicodeDecodeError, ValueError) as exc:   # damaged or not a CSV
        raise LogFormatError(f"{path}: cannot be read as a{' gzip-compressed' if name.endswith('.gz') else ''} "
                             f"CSV file ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
                             ) from None
    cols = [str(c).strip() for c in df.columns]
    if tuple(cols) != ESSO_COLUMNS:
        missing = [c for c in ESSO_COLUMNS if c not in cols]
        extra = [c for c in cols if c not in ESSO_COLUMNS]
        raise LogFormatError(f"{path}: not the Esso Osaka column layout (missing: {missing or 'none'}; "
                             f"unexpected: {extra or 'none'}; order must be {list(ESSO_COLUMNS)})",
                             column=(missing or extra or [None])[0])
    df.columns = cols
    # empty before the numbers are read: a row of text (a second header line) became all NaN
    # and was dropped as empty, without a word
    empty = df.isna()
    for c in df.columns:
        if not pd.api.types.is_numeric_dtype(df[c]):      # text: a field of spaces is empty too
            empty[c] |= df[c].astype(str).str.strip().eq("")
    df = df.apply(pd.to_numeric, errors="coerce")
    df = df[~empty.all(axis=1)]     # the index keeps each row's place in the file (data row, from 0)
    bad = ~np.isfinite(df.to_numpy(float))    # an 'inf' wind direction became a NaN one (not logged) in the log
    if bad.any():
        i, j = np.argwhere(bad)[0]
        row = int(df.index[i])
        raise LogFormatError(f"{ESSO_COLUMNS[j]}: missing, non-numeric or infinite value at row {row} (file line "
                             f"{row + 2}{_at_time(df, i)}; in {path})", column=ESSO_COLUMNS[j], row=row)
    t = df["t [s]"].to_numpy()
    if len(t) > 1 and np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0)) + 1
        row = int(df.index[i])
        raise LogFormatError(f"t [s]: not strictly increasing at row {row} (file line {row + 2}, t = {t[i]:g} s "
                             f"after {t[i - 1]:g} s; in {path})", column="t [s]", row=row)
    return df.reset_index(drop=True)


def _at_time(df: pd.DataFrame, i: int) -> str:
    """``", t = ... s"`` of row ``i`` when its time is known."""
    t = df["t [s]"].iloc[i]
    return f", t = {t:g} s" if np.isfinite(t) else ""


def _channel_names(vessel) -> tuple[str, str]:
    """(propeller, rudder) channel names of a vessel: its first forward fixed thruster and first rudder."""
    if vessel is None:
        return "propeller", "rudder"
    from ..vessel import Vessel, load_vessel

    v = vessel if isinstance(vessel, Vessel) else load_vessel(vessel)
    props = [t.name for t in v.thrusters if t.type == "fixed" and abs(t.fixed_angle_rad) < 1e-9]
    if not props or not v.rudders:
        raise ValueError(f"vessel {v.name!r}: the Esso Osaka logs need a forward 'fixed' thruster (main "
                         f"propeller) and a rudder in the vessel file")
    return props[0], v.rudders[0].name


#: The raw columns :func:`esso_to_log` reads (the relative wind it does not).
_CONVERTED_COLUMNS = ("t [s]", "x_position_mid [m]", "y_position_mid [m]", "psi_hat [rad]", "u_velo [m/s]",
                      "vm_velo [m/s]", "r_angvelo [rad/s]", "wind_velo_true [m/s]", "wind_dir_true [rad]",
                      "n_prop [rps]", "delta_rudder [rad]")


def esso_to_log(raw: pd.DataFrame, *, vessel=None, velocity_lead_s: float = 0.0) -> pd.DataFrame:
    """Convert a raw run (:func:`read_esso_raw`) into a log-format DataFrame (10 Hz, as logged).

    Parameters
    ----------
    raw : DataFrame
        Columns :data:`ESSO_COLUMNS`.
    vessel : Vessel or str, optional
        Names the propeller and rudder channels (default ``propeller`` and ``rudder``, as
        in ``vessels/esso_osaka_model.toml``).
    velocity_lead_s : float
        Shift u and vm this much earlier (they lag the positions by about 0.6 s); the last
        rows are then held. Default 0: as logged, causal.

    Raises
    ------
    ValueError
        If ``velocity_lead_s`` is negative or not finite.
    """
    # a negative lead was ignored without a word, NaN and inf failed inside numpy, True was
    # read as 1 s
    lead = check_number("velocity_lead_s", velocity_lead_s, lo=0.0)
    if not isinstance(raw, pd.DataFrame):
        raise TypeError(f"raw: expected a DataFrame of a raw run (read_esso_raw), got {type(raw).__name__}")
    missing = [c for c in _CONVERTED_COLUMNS if c not in raw.columns]
    if missing:     # (a KeyError before)
        raise LogFormatError(f"{missing[0]}: missing from the raw run (missing: {missing}; the conversion reads "
                             f"{list(_CONVERTED_COLUMNS)} of read_esso_raw's columns)", column=missing[0])
    prop, rud = _channel_names(vessel)
    wind_dir = np.degrees(raw["wind_dir_true [rad]"].to_numpy(float))
    # wrapped where finite: inf % 360 is NaN, which the log reads as the wind not logged (the
    # log's checks refuse an infinite value, as they do in the other columns)
    with np.errstate(invalid="ignore"):
        wind_dir = np.where(np.isinf(wind_dir), wind_dir, wind_dir % 360.0)
    t = raw["t [s]"].to_numpy(float)
    u = raw["u_velo [m/s]"].to_numpy(float)
    v = raw["vm_velo [m/s]"].to_numpy(float)
    if lead and len(t) > 1:
        dt = float(np.median(np.diff(t)))
        k = int(round(lead / dt))
        # row i takes row i + k, the last row held (also for a lead longer than the run)
        src = np.minimum(np.arange(len(t)) + k, len(t) - 1)
        u, v = u[src], v[src]
    return pd.DataFrame({
        "time_s": t,
        "north_m": raw["x_position_mid [m]"].to_numpy(float),
        "east_m": raw["y_position_mid [m]"].to_numpy(float),
        "heading_deg": np.degrees(raw["psi_hat [rad]"].to_numpy(float)),
        "u_m_s": u,
        "v_m_s": v,
        "r_deg_s": np.degrees(raw["r_angvelo [rad/s]"].to_numpy(float)),
        "wind_speed_m_s": raw["wind_velo_true [m/s]"].to_numpy(float),
        "wind_dir_deg": wind_dir,
        f"{prop}_rpm": 60.0 * raw["n_prop [rps]"].to_numpy(float),
        f"{rud}_azimuth_deg": np.degrees(raw["delta_rudder [rad]"].to_numpy(float)),
    })


def read_esso_osaka(path, *, vessel=None, velocity_lead_s: float = 0.0) -> pd.DataFrame:
    """Read one run into a validated log-format DataFrame (see :func:`esso_to_log`)."""
    log = esso_to_log(read_esso_raw(path), vessel=vessel, velocity_lead_s=velocity_lead_s)
    prop, rud = _channel_names(vessel)
    validate_log(log, channel_names=[prop, rud], rotatable=[False, True], source=str(path))
    return log


def esso_log_arrays(run, vessel="esso_osaka_model", *, velocity_lead_s: float = 0.0) -> LogArrays:
    """A run (path, raw DataFrame or log DataFrame) as :class:`LogArrays` for ``vessel``.

    ``velocity_lead_s`` (see :func:`esso_to_log`) applies to a raw run; a log DataFrame is
    already converted and is taken as it is.

    Raises
    ------
    ValueError
        ``velocity_lead_s`` not a finite time >= 0, or not 0 with a log DataFrame.
    """
    from ..vessel import Vessel, load_vessel

    v = vessel if isinstance(vessel, Vessel) else load_vessel(vessel)
    if isinstance(run, EssoRun):
        run = run.path
    if isinstance(run, (str, os.PathLike)):       # any path object
        log = read_esso_osaka(run, vessel=v, velocity_lead_s=velocity_lead_s)
    elif isinstance(run, pd.DataFrame) and "t [s]" in run.columns:
        log = esso_to_log(run, vessel=v, velocity_lead_s=velocity_lead_s)
    elif isinstance(run, pd.DataFrame):
        # the lead was ignored here without a word (and a negative one accepted)
        if check_number("velocity_lead_s", velocity_lead_s, lo=0.0):
            raise ValueError(f"velocity_lead_s: applies to a raw run (a path or read_esso_raw's DataFrame); a log "
                             f"DataFrame is taken as converted, expected 0, got {velocity_lead_s!r}")
        log = run
    else:
        raise TypeError(f"run: expected a path, EssoRun or DataFrame, got {type(run).__name__}")
    return log_to_arrays(log, channel_names=v.channel_names, rotatable=v.rotatable)


# --------------------------------------------------------------------------------------
# Runs and kinds
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class EssoRun:
    """One run file.

    Attributes
    ----------
    path : Path
        Path of the run file.
    name : str
        File name without ``.csv``/``.csv.gz``.
    kind : str
        One of :data:`RUN_KINDS`.
    recording : str
        The recording the file belongs to (pieces ``_<k>`` of one recording share it).
    """

    path: Path
    name: str
    kind: str
    recording: str


def _stem(path: Path) -> str:
    n = path.name
    for ext in (".csv.gz", ".csv"):
        if n.lower().endswith(ext):
            return n[: -len(ext)]
    return path.stem


def _manifest_kind(path: Path) -> str | None:
    """Kind listed for ``path`` in a ``MANIFEST.csv`` of the data set (searched upwards from the real file)."""
    real = path.resolve()
    for parent in list(real.parents)[:4]:
        man = parent / "MANIFEST.csv"
        if man.is_file():
            try:
                m = pd.read_csv(man)
            except Exception:  # an unreadable manifest is not fatal: fall back to the name
                return None
            if {"file", "kind"} <= set(m.columns):
                rel = real.relative_to(parent).as_posix()
                hit = m.loc[m["file"] == rel, "kind"]
                if len(hit):
                    return str(hit.iloc[0])
            return None
    return None


def run_kind(path) -> str:
    """Kind of a run: from the data set's ``MANIFEST.csv`` when it lists the file, else from its name.

    Raises
    ------
    ValueError
        If neither the manifest nor the file-name prefix (``random_``, ``turn_``,
        ``zigzag_``, ``berthing_``) nor the parent folder name tells the kind.
    """
    path = Path(path)
    kind = _manifest_kind(path)
    if kind is None:
        prefix = _stem(path).split("_", 1)[0].lower()
        kind = _PREFIX_KIND.get(prefix) or _PREFIX_KIND.get(path.parent.name.lower().rstrip("s"))
        if kind is None and path.parent.name.lower() in RUN_KINDS:
            kind = path.parent.name.lower()
    if kind not in RUN_KINDS:
        raise ValueError(f"{path}: cannot tell the run kind from the manifest, the name's prefix or the folder's "
                         f"name; expected one of {list(RUN_KINDS)}"
                         + (f" (got {kind!r})" if kind is not None else ""))
    return kind


def uncut_name(stem: str) -> str:
    """The name of the run ``stem`` is cut from (``<kind>_cut_<stamp>`` -> ``<kind>_<stamp>``;
    other names unchanged)."""
    return re.sub(r"^(\w+?)_cut_", r"\1_", stem)


def _recording(stem: str) -> str:
    s = uncut_name(stem)
    # a piece number follows the whole stamp DD-Mon-YYYY_HH_MM_SS (not the year's last digits)
    return re.sub(r"_\d+$", "", s) if re.search(r"\d{4}_\d{2}_\d{2}_\d{2}_\d+$", s) else s


def list_runs(folder, *, include_duplicates: bool = False) -> list[EssoRun]:
    """All runs (``*.csv``, ``*.csv.gz``, searched recursively) under ``folder``, sorted by name.

    A ``<kind>_cut_<stamp>`` file is a truncated copy of ``<kind>_<stamp>`` in this data set
    and is skipped when that file is present too, unless ``include_duplicates``.

    Raises
    ------
    ValueError
        If two files hold one run name (``x.csv`` beside ``x.csv.gz``, or one name in two
        sub-folders): the run would count twice.
    TypeError
        ``include_duplicates`` not True or False.
    """
    check_flags(include_duplicates=include_duplicates)    # "no" listed the cut copies as runs of their own
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"{folder}: run folder not found")
    files = sorted({p for pat in ("*.csv", "*.csv.gz") for p in folder.rglob(pat)
                    if p.name != "MANIFEST.csv"}, key=lambda p: (_stem(p), str(p)))
    for a, b in zip(files, files[1:]):
        if _stem(a) == _stem(b):
            # twice the weight in training, its starts twice in the test tables (and one
            # entry of the starts per run name)
            raise ValueError(f"{folder}: run {_stem(a)} has two files ({a.relative_to(folder)} and "
                             f"{b.relative_to(folder)}); keep one")
    stems = {_stem(p) for p in files}
    runs = []
    for p in files:
        stem = _stem(p)
        uncut = uncut_name(stem)
        if not include_duplicates and uncut != stem and uncut in stems:
            continue
        runs.append(EssoRun(path=p, name=stem, kind=run_kind(p), recording=_recording(stem)))
    return runs


# --------------------------------------------------------------------------------------
# Convention checks
# --------------------------------------------------------------------------------------


def convention_checks(raw: pd.DataFrame, *, diff_s: float = 1.0, lag_s: float = 0.6) -> dict[str, float]:
    """Numbers that test the sign conventions of one raw run against its own data.

    Returns
    -------
    dict
        * ``rms_north_m_s``, ``rms_east_m_s``: rms of the ``diff_s`` central-difference
          position rates minus ``R(psi) [u, vm]`` (u, vm taken ``lag_s`` later, their lag;
          a negative ``lag_s`` takes them earlier);
        * ``rms_north_flipped_psi_m_s``, ``rms_east_flipped_psi_m_s``: the same with psi's
          sign flipped (should be much larger);
        * ``rms_v_m_s``, ``rms_v_flipped_m_s``: the sway velocity from the position rates
          against vm, and against -vm;
        * ``corr_r_dpsi``: correlation of r with the 0.1-s heading rate;
        * ``corr_delta_r5``: correlation of delta with r 5 s later (> 0: + turns to starboard);
        * ``rms_apparent_wind_m_s``: rms error of the apparent wind rebuilt from the true wind,
          heading and (u, vm) as ``true wind velocity in body axes - (u, vm)``.

    Raises
    ------
    ValueError
        ``diff_s`` not a positive time, ``lag_s`` not finite, or a run too short for one
        central difference with its lagged velocities.
    """
    diff_s = check_number("diff_s", diff_s, lo=0.0, lo_open=True)
    lag_s = check_number("lag_s", lag_s)
    t = raw["t [s]"].to_numpy(float)
    if len(t) < 2:
        raise ValueError(f"raw: {len(t)} row(s); expected a run of several rows")
    dt = float(np.median(np.diff(t)))
    k = max(1, int(round(0.5 * diff_s / dt)))
    lag = int(round(lag_s / dt))
    x, y = raw["x_position_mid [m]"].to_numpy(float), raw["y_position_mid [m]"].to_numpy(float)
    psi = raw["psi_hat [rad]"].to_numpy(float)
    u, vm = raw["u_velo [m/s]"].to_numpy(float), raw["vm_velo [m/s]"].to_numpy(float)
    r = raw["r_angvelo [rad/s]"].to_numpy(float)
    n = len(t)
    # rows whose differences (i +- k) and lagged velocities (i + lag) all lie in the run; a
    # negative lag (earlier velocities) indexed past the end before
    i = np.arange(k + max(0, -lag), n - k - max(0, lag))
    if i.size == 0:
        raise ValueError(f"raw: {n} rows hold no central difference over diff_s = {diff_s:g} s with the velocities "
                         f"lag_s = {lag_s:g} s away; expected a run of at least {(2 * k + abs(lag)) * dt:g} s")
    xd = (x[i + k] - x[i - k]) / (t[i + k] - t[i - k])
    yd = (y[i + k] - y[i - k]) / (t[i + k] - t[i - k])
    c, s = np.cos(psi[i]), np.sin(psi[i])
    ul, vl = u[i + lag], vm[i + lag]

    def rms(a):
        return float(np.sqrt(np.mean(np.square(a))))

    out = {
        "rms_north_m_s": rms(xd - (c * ul - s * vl)),
        "rms_east_m_s": rms(yd - (s * ul + c * vl)),
        "rms_north_flipped_psi_m_s": rms(xd - (c * ul + s * vl)),
        "rms_east_flipped_psi_m_s": rms(yd - (-s * ul + c * vl)),
    }
    v_pos = -s * xd + c * yd
    out["rms_v_m_s"] = rms(v_pos - vl)
    out["rms_v_flipped_m_s"] = rms(v_pos + vl)
    dpsi = np.angle(np.exp(1j * np.diff(psi))) / np.diff(t)
    out["corr_r_dpsi"] = float(np.corrcoef(0.5 * (r[1:] + r[:-1]), dpsi)[0, 1])
    d5 = int(round(5.0 / dt))
    delta = raw["delta_rudder [rad]"].to_numpy(float)
    out["corr_delta_r5"] = (float(np.corrcoef(delta[:-d5], r[d5:])[0, 1])
                            if n > d5 + 2 and np.std(delta[:-d5]) > 0 else float("nan"))
    UT, gT = raw["wind_velo_true [m/s]"].to_numpy(float), raw["wind_dir_true [rad]"].to_numpy(float)
    # true wind velocity (the way it blows) in earth axes, then in body axes, minus the ship's
    wn, we = -UT * np.cos(gT), -UT * np.sin(gT)
    c, s = np.cos(psi), np.sin(psi)
    wu = c * wn + s * we - u
    wv = -s * wn + c * we - vm
    UA = raw["wind_velo_relative_mid [m/s]"].to_numpy(float)
    gA = raw["wind_dir_relative_mid [rad]"].to_numpy(float)
    # apparent wind coming FROM gamma_A (bow towards starboard): velocity -(cos, sin) * U_A
    out["rms_apparent_wind_m_s"] = rms(np.hypot(wu + UA * np.cos(gA), wv + UA * np.sin(gA)))
    return out
