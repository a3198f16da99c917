"""``hybridship drift-off planning|live|season``: the drift-off command line.

Registered by :mod:`hybridship.cli`; heavy imports happen inside the commands so that
``hybridship --help`` stays fast. Degrees and comma-separated lists at this edge; SI and
radians inside. Bad input raises :class:`hybridship.cli.UsageError` naming the option.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

from ..fileio import check_out_folder, path_argument, vessel_argument
from ..messages import problem_lines, seconds_text

__all__ = ["add_parser"]

_PROG = "hybridship drift-off"


def _floats(text: str) -> list[float]:
    parts = str(text).split(",")
    if len(parts) > 1 and not all(x.strip() for x in parts):    # "3,,5" or "3,5,": a number left out?
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r} (an empty item)")
    try:
        vals = [float(x) for x in parts if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
    if not all(math.isfinite(v) for v in vals):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    if not vals:
        raise argparse.ArgumentTypeError(f"expected at least one number, got {text!r}")
    return vals


def _common(p, plots: bool = True) -> None:
    p.add_argument("--vessel", type=vessel_argument, default="gunnerus",
                   help="packaged vessel name or vessel TOML file (default gunnerus)")
    p.add_argument("--radii-m", type=_floats, default=[3.0, 5.0, 10.0],
                   help="limit radii [m], comma-separated (default 3,5,10)")
    p.add_argument("--reaction-times-s", type=_floats, default=[30.0, 60.0],
                   help="operator reaction times [s], comma-separated (default 30,60)")
    p.add_argument("--samples", type=int, default=100, help="Monte-Carlo samples per heading (default 100)")
    p.add_argument("--horizon-s", type=float, default=300.0, help="longest simulated drift [s] (default 300)")
    p.add_argument("--dt-s", type=float, default=1.0, help="integration output step [s] (default 1)")
    p.add_argument("--quantile", type=float, default=0.9, help="watch-circle quantile (default 0.9)")
    p.add_argument("--vessel-spread", type=float, default=1.0,
                   help="multiplier of the vessel file's [true_vessel] spread; 0 = nominal model (default 1)")
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    p.add_argument("--out", type=path_argument, required=True, help="output folder")
    if plots:
        p.add_argument("--no-plots", action="store_true",
                       help="skip the figures (and remove those of an earlier run from --out)")


def _weather(p, table: bool) -> None:
    g = p.add_argument_group("weather (means; directions in degrees, wind and waves FROM, current TO)")
    g.add_argument("--wind-m-s", type=float, default=10.0, help="mean wind speed [m/s] (default 10)")
    g.add_argument("--wind-dir-deg", type=float, default=0.0, help="wind direction, from [deg] (default 0)")
    g.add_argument("--gust-intensity", type=float, default=0.1, help="turbulence intensity (default 0.1)")
    g.add_argument("--hs-m", type=float, default=1.0, help="significant wave height [m] (default 1)")
    g.add_argument("--tp-s", type=float, default=6.0, help="peak period [s] (default 6)")
    g.add_argument("--wave-dir-deg", type=float, default=None, help="wave direction, from [deg] (default: the wind's)")
    g.add_argument("--current-m-s", type=float, default=0.2, help="current speed [m/s] (default 0.2)")
    g.add_argument("--current-dir-deg", type=float, default=0.0, help="current direction, to [deg] (default 0)")
    u = p.add_argument_group("weather uncertainty (one standard deviation each; default 0 = known)")
    u.add_argument("--wind-std-m-s", type=float, default=0.0, help="wind speed [m/s]")
    u.add_argument("--wind-dir-std-deg", type=float, default=0.0, help="wind direction [deg]")
    u.add_argument("--hs-std-m", type=float, default=0.0, help="significant wave height [m]")
    u.add_argument("--tp-std-s", type=float, default=0.0, help="peak period [s]")
    u.add_argument("--wave-dir-std-deg", type=float, default=0.0, help="wave direction [deg]")
    u.add_argument("--current-std-m-s", type=float, default=0.0, help="current speed [m/s]")
    u.add_argument("--current-dir-std-deg", type=float, default=0.0, help="current direction [deg]")


_USAGE_ERROR = ValueError

#: The fields of WeatherState and WeatherUncertainty that the planning options fill (the
#: directions' spreads are checked in degrees before, by the options themselves).
_WEATHER_OPTIONS = {
    "weather.wind_speed_m_s": "--wind-m-s", "weather.wind_dir_deg": "--wind-dir-deg",
    "weather.gust_intensity": "--gust-intensity", "weather.hs_m": "--hs-m", "weather.tp_s": "--tp-s",
    "weather.wave_dir_deg": "--wave-dir-deg", "weather.current_speed_m_s": "--current-m-s",
    "weather.current_dir_deg": "--current-dir-deg", "uncertainty.wind_speed_m_s": "--wind-std-m-s",
    "uncertainty.hs_m": "--hs-std-m", "uncertainty.tp_s": "--tp-std-s",
    "uncertainty.current_speed_m_s": "--current-std-m-s",
}


def _in_option_words(text: str) -> str:
    """A planning error in the options' words: the fields a check names inside its message (a
    sea steeper than waves can be names ``hs_m`` and ``tp_s``) become ``--hs-m`` and ``--tp-s``."""
    for field, option in _WEATHER_OPTIONS.items():
        text = re.sub(rf"\b{re.escape(field)}\b", option, text)
    return re.sub(r"(?<![\w.-])(hs_m|tp_s)\b", lambda m: _WEATHER_OPTIONS[f"weather.{m.group(1)}"], text)


def add_parser(sub, parser_class, usage_error=None) -> None:
    """Register ``drift-off`` and its three modes on the subparsers ``sub``.

    ``usage_error`` is the exception class the caller reports as a usage error (exit 2).
    """
    global _USAGE_ERROR
    if usage_error is not None:
        _USAGE_ERROR = usage_error
    p = sub.add_parser("drift-off", help="time to reach a limit radius after a blackout (planning, live, season)",
                       description="Monte-Carlo blackouts: rpm to zero with spin-down, the physics model plus wind "
                                   "gusts, wave drift and current, perturbed vessels. Writes summary.md, CSV tables "
                                   "and figures to --out.")
    dsub = p.add_subparsers(dest="mode", metavar="MODE", parser_class=parser_class)
    p.set_defaults(func=_missing_mode)

    a = dsub.add_parser("planning", help="one weather state (means with uncertainty) at several headings",
                        description="Monte-Carlo blackouts of one weather state at each heading.")
    a.add_argument("--headings-deg", type=_floats, default=[0, 45, 90, 135, 180, 225, 270, 315],
                   help="vessel headings [deg], comma-separated (default every 45 deg)")
    _weather(a, table=False)
    _common(a)
    a.set_defaults(func=_cmd_planning)

    b = dsub.add_parser("live", help="a blackout now, from a station-keeping log",
                        description="Estimate the environment from the log up to --time-s (mean wind; current "
                                    "and load from the environment estimator over --window-s) and run blackouts "
                                    "from the state and thruster rpm at that time.")
    b.add_argument("--log", type=path_argument, required=True, help="station-keeping log (.csv, .csv.gz, .parquet)")
    b.add_argument("--time-s", type=float, default=None, help="time of the blackout [s] (default: the last row)")
    b.add_argument("--window-s", type=float, default=900.0,
                   help="log read before --time-s by the environment estimator [s] (default 900, at least 60)")
    _common(b)
    b.set_defaults(func=_cmd_live)

    c = dsub.add_parser("season", help="sweep a table of weather states (e.g. hourly hindcast) on Dask",
                        description="Blackouts for every weather state x heading x sample; chunks of states run "
                                    "as Dask futures on a LocalCluster, a given scheduler, or in this process.")
    c.add_argument("--weather-table", type=path_argument, required=True,
                   help="CSV of weather states (columns: see docs/drift-off.md)")
    c.add_argument("--headings-deg", type=_floats, default=[0, 45, 90, 135, 180, 225, 270, 315],
                   help="vessel headings [deg], comma-separated (default every 45 deg)")
    c.add_argument("--scheduler", default="local",
                   help="'local' (a LocalCluster; default), a scheduler address tcp://host:8786, or 'none' "
                        "(this process)")
    c.add_argument("--workers", type=int, default=None, help="LocalCluster workers (default 2; only with "
                                                               "--scheduler local)")
    c.add_argument("--chunk-size", type=int, default=24, help="weather states per task (default 24)")
    c.add_argument("--max-p-exceed", type=float, default=0.1,
                   help="a state is operable when P(exceed) <= this (default 0.1)")
    c.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show a progress bar (default: when stderr is a terminal)")
    _common(c, plots=False)
    c.set_defaults(func=_cmd_season)


def _usage(msg):
    return _USAGE_ERROR(msg)


def _missing_mode(args) -> int:
    raise _usage(f"{_PROG}: error: choose a mode: planning, live or season (try '{_PROG} --help')")


def _settings(args, mode):
    from .planning import DriftOffSettings

    if not 0.0 < args.quantile < 1.0:
        raise _usage(f"{_PROG} {mode}: error: --quantile must be in (0, 1), got {args.quantile}")
    try:
        check_out_folder(args.out)
    except NotADirectoryError as exc:
        raise _usage(f"{_PROG} {mode}: error: --out {exc}") from None
    _refuse_inputs_in_out(args, mode)
    names = {"radii_m": "--radii-m", "reaction_times_s": "--reaction-times-s", "n_samples": "--samples",
             "horizon_s": "--horizon-s", "dt_s": "--dt-s", "vessel_spread": "--vessel-spread", "seed": "--seed"}
    try:
        return DriftOffSettings(radii_m=tuple(args.radii_m), reaction_times_s=tuple(args.reaction_times_s),
                                n_samples=args.samples, horizon_s=args.horizon_s, dt_s=args.dt_s,
                                vessel_spread=args.vessel_spread, seed=args.seed)
    except (ValueError, TypeError) as exc:
        # radii_m[0] -> --radii-m: the option the user typed, on each problem's line
        raise _usage(problem_lines(exc, f"{_PROG} {mode}: error: ",
                                   lambda field: names.get(field.split("[", 1)[0], field))) from None


def _refuse_inputs_in_out(args, mode) -> None:
    """Refuse an ``--out`` where a file this command writes or removes (the report's tables,
    figures and summary, of any mode) is one of its input files: the user's log, weather
    table or vessel file would be replaced or deleted."""
    from .report import REPORT_ONLY_FILES, SEASON_ONLY_FILES

    inputs = {opt: Path(v) for opt, v in (("--log", getattr(args, "log", None)),
                                          ("--weather-table", getattr(args, "weather_table", None)),
                                          ("--vessel", args.vessel)) if v is not None and Path(v).is_file()}
    for name in ("summary.md", *REPORT_ONLY_FILES, *SEASON_ONLY_FILES):
        target = Path(args.out) / name
        for opt, given in inputs.items():
            if target.exists() and target.resolve() == given.resolve():
                raise _usage(f"{_PROG} {mode}: error: --out {args.out}: the report's {name} there is the {opt} "
                             f"file; it would be replaced or removed, give another folder")
    from hybridship.fileio import check_output_files

    from .report import earlier_report
    try:   # any other file of the user's there, before the work
        mine, others = (SEASON_ONLY_FILES, REPORT_ONLY_FILES) if mode == "season" else (REPORT_ONLY_FILES,
                                                                                         SEASON_ONLY_FILES)
        check_output_files(args.out, ("summary.md", *mine), others, ours=earlier_report)
    except OSError as exc:
        raise _usage(f"{_PROG} {mode}: error: --out {exc}") from None
    from hybridship.evaluation.drift import logs_held

    # the report's CSV tables would be taken for logs by train and the benchmarks
    logs = logs_held(args.out, (*REPORT_ONLY_FILES, *SEASON_ONLY_FILES))
    if logs:
        raise _usage(f"{_PROG} {mode}: error: --out {args.out}: holds logs ({logs[0].name}"
                     f"{f' and {len(logs) - 1} more' if len(logs) > 1 else ''}); the report's CSV tables would be "
                     f"read as logs from there: give a folder of its own")


def _model(args, mode):
    from hybridship.vessel import VesselFileError

    from .planning import get_model

    try:
        return get_model(args.vessel)
    except (VesselFileError, ValueError, FileNotFoundError) as exc:
        raise _usage(problem_lines(exc, f"{_PROG} {mode}: error: --vessel: ")) from None


def _headings_rad(args, mode) -> list[float]:
    """``--headings-deg`` in radians, refused in the option's own terms: each within +-360 deg
    and each heading once (0 and 360 are one heading)."""
    h = list(args.headings_deg)
    if not all(math.isfinite(x) and abs(x) <= 360.0 for x in h):
        raise _usage(f"{_PROG} {mode}: error: --headings-deg: expected headings from -360 to 360 deg, got "
                     f"{', '.join(f'{x:g}' for x in h)}")
    if len({round(x % 360.0, 9) % 360.0 for x in h}) != len(h):
        raise _usage(f"{_PROG} {mode}: error: --headings-deg: expected each heading once (0 and 360 are one), got "
                     f"{', '.join(f'{x:g}' for x in h)}")
    return [math.radians(x) for x in h]


def _cmd_planning(args) -> int:
    from .planning import simulate_blackouts
    from .report import write_report
    from .spread import spread_text
    from .weather import WeatherState, WeatherUncertainty

    st = _settings(args, "planning")
    for opt in ("wind", "wave", "current"):     # checked in degrees, as typed
        std = getattr(args, f"{opt}_dir_std_deg")
        if not 0.0 <= std <= 180.0:
            raise _usage(f"{_PROG} planning: error: --{opt}-dir-std-deg: expected a spread from 0 to 180 deg, "
                         f"got {std:g}")
    try:
        w = WeatherState.from_degrees(wind_speed_m_s=args.wind_m_s, wind_dir_deg=args.wind_dir_deg, hs_m=args.hs_m,
                                      tp_s=args.tp_s, wave_dir_deg=args.wave_dir_deg, current_m_s=args.current_m_s,
                                      current_dir_deg=args.current_dir_deg, gust_intensity=args.gust_intensity)
        u = WeatherUncertainty(args.wind_std_m_s, math.radians(args.wind_dir_std_deg), args.hs_std_m, args.tp_std_s,
                               math.radians(args.wave_dir_std_deg), args.current_std_m_s,
                               math.radians(args.current_dir_std_deg))
    except (ValueError, TypeError) as exc:
        # the option the user typed, not the field it fills
        raise _usage(_in_option_words(problem_lines(exc, f"{_PROG} planning: error: ",
                                                    lambda field: _WEATHER_OPTIONS.get(field, field)))) from None
    model = _model(args, "planning")
    res = simulate_blackouts(model, w, _headings_rad(args, "planning"), uncertainty=u, settings=st)
    inputs = {"vessel": model.vessel.name, "wind": f"{args.wind_m_s:g} +- {args.wind_std_m_s:g} m/s from "
              f"{args.wind_dir_deg:g} +- {args.wind_dir_std_deg:g} deg, gust intensity {args.gust_intensity:g}",
              "waves": f"Hs {args.hs_m:g} +- {args.hs_std_m:g} m, Tp {args.tp_s:g} +- {args.tp_std_s:g} s, from "
              f"{args.wind_dir_deg if args.wave_dir_deg is None else args.wave_dir_deg:g} +- "
              f"{args.wave_dir_std_deg:g} deg",
              "current": f"{args.current_m_s:g} +- {args.current_std_m_s:g} m/s to {args.current_dir_deg:g} +- "
              f"{args.current_dir_std_deg:g} deg", "vessel spread": spread_text(model.vessel, st.vessel_spread),
              "seed": st.seed}
    paths = write_report(res, args.out, title="Drift-off analysis (planning)", inputs=inputs, quantile=args.quantile,
                         plots=not args.no_plots)
    print(paths["summary.md"].read_text())
    return 0


def _cmd_live(args) -> int:
    import time

    import numpy as np

    from hybridship.logs.io import LogFormatError, read_log

    from .live import blackout_now, environment_from_log
    from .report import write_report

    st = _settings(args, "live")
    model = _model(args, "live")
    if not args.log.is_file():
        raise _usage(f"{_PROG} live: error: --log {args.log}: "
                     f"{'is a folder; expected a log file' if args.log.is_dir() else 'no such file'}")
    # read as forecast and train read a log: the one ingest checks (and re-sorts) the rows it uses
    df = read_log(args.log, validate=False)
    if args.time_s is not None and "time_s" in df.columns:
        import pandas as pd

        t = pd.to_numeric(df["time_s"], errors="coerce").to_numpy(float)
        first, last = (np.nanmin(t), np.nanmax(t)) if np.isfinite(t).any() else (np.nan, np.nan)
        if not (first <= args.time_s <= last):
            raise _usage(f"{_PROG} live: error: --time-s {seconds_text(args.time_s)} is outside the log "
                         f"({seconds_text(first)} to {seconds_text(last)} s)")
        _refuse_a_time_in_a_gap(t, args.time_s)
        df = df[t <= args.time_s]
    t0 = time.perf_counter()
    try:
        est = environment_from_log(df, model, window_s=args.window_s, n_members=st.n_samples, seed=args.seed,
                                   name=str(args.log))
    except LogFormatError:
        raise                   # the log's content, not the request: exit 1, as forecast and train
    except ValueError as exc:
        raise _usage(problem_lines(exc, f"{_PROG} live: error: ",
                                   lambda field: {"window_s": "--window-s", "log": "--log"}.get(field, field))) from None
    res = blackout_now(est, model, st)
    dt = time.perf_counter() - t0
    inputs = {"vessel": model.vessel.name, "log": str(args.log), "blackout at [s]": seconds_text(est.time_s),
              "heading [deg]": f"{math.degrees(est.eta[2]) % 360:.1f}",
              "mean wind": (f"{est.wind_speed_m_s:.2f} m/s from {math.degrees(est.wind_dir_from_rad) % 360:.0f} deg, "
                            f"gust intensity {est.gust_intensity:.2f}") if est.wind_measured else
                           "no wind measurement in the log's last 120 s: the blackouts run without wind",
              "estimated current [m/s, to deg]": _current_text(est),
              "estimated load (N, E) [m/s^2]": f"{est.accel_ned[0]:.4f}, {est.accel_ned[1]:.4f}",
              **({"log checks at the blackout row": est.notes} if est.notes else {}),
              "update time [s]": f"{dt:.3f}",
              # the table's band reads as a calibrated 80 % one; on simulated failures it is not
              "spread": "not calibrated: on the independent simulator's failures the actual times fell outside "
                        "the p10-p90 band more often than 1 in 5 (docs/drift-off.md, live mode); read the band "
                        "as too narrow"}
    paths = write_report(res, args.out, title="Drift-off analysis (live: blackout now)", inputs=inputs,
                         quantile=args.quantile, plots=not args.no_plots)
    print(paths["summary.md"].read_text())
    return 0


def _refuse_a_time_in_a_gap(t, time_s: float) -> None:
    """Refuse a ``--time-s`` in a gap of the log: the blackout starts from the last sample at or
    before it, which must lie within 1.5 of the log's median steps (the gap rule of the
    estimator's segments), not from a state logged before the gap.

    Parameters
    ----------
    t : ndarray
        The log's ``time_s`` column [s], in file order, NaN where a row has no time.
    time_s : float
        ``--time-s`` [s], within the log's first and last time.
    """
    import numpy as np

    times = np.unique(t[np.isfinite(t)])
    if times.size < 2:
        return                  # too short for a step: the estimate refuses it by its own rule
    step = float(np.median(np.diff(times)))
    i = int(np.searchsorted(times, time_s, side="right")) - 1
    if time_s - times[i] > 1.5 * step:
        raise _usage(f"{_PROG} live: error: --time-s {seconds_text(time_s)} falls in a gap of the log: no sample "
                     f"from {seconds_text(times[i])} s to {seconds_text(times[i + 1])} s (the log's step is "
                     f"{seconds_text(step)} s), so the blackout would start from the state of "
                     f"{seconds_text(time_s - times[i])} s before it; give {seconds_text(times[i])} s or a time from "
                     f"{seconds_text(times[i + 1])} s on")


def _current_text(est) -> str:
    """The estimator's mean current as speed and direction (or why there is none)."""
    import numpy as np

    if est.current_members_ned_m_s is None:
        return "inside the load (residual mean)"
    c = np.asarray(est.current_members_ned_m_s, dtype=float).reshape(-1, 2).mean(axis=0)
    return f"{float(np.hypot(*c)):.3f} to {math.degrees(math.atan2(c[1], c[0])) % 360:.0f}"


def _cmd_season(args) -> int:
    from .report import markdown_table, write_season_report
    from .season import require_dask, season_sweep
    from .weather import read_weather_table

    st = _settings(args, "season")
    for opt, v in (("--workers", args.workers), ("--chunk-size", args.chunk_size)):
        if v is not None and v < 1:
            raise _usage(f"{_PROG} season: error: {opt} must be >= 1, got {v}")
    # the two keywords in any case ('None', 'LOCAL'); an address as given
    keyword = args.scheduler.lower() if args.scheduler.lower() in ("local", "none") else args.scheduler
    if keyword != "local" and args.workers is not None:
        raise _usage(f"{_PROG} season: error: --workers {args.workers} is for --scheduler local (a LocalCluster); "
                     f"with --scheduler {args.scheduler} the workers are "
                     f"{'this process' if keyword == 'none' else 'those of the cluster'}")
    if not 0.0 <= args.max_p_exceed <= 1.0:
        raise _usage(f"{_PROG} season: error: --max-p-exceed must be in [0, 1], got {args.max_p_exceed}")
    try:
        states, labels = read_weather_table(args.weather_table)
    except (ValueError, FileNotFoundError, IsADirectoryError) as exc:
        raise _usage(problem_lines(exc, f"{_PROG} season: error: --weather-table: ")) from None
    scheduler = None if keyword == "none" else keyword
    if scheduler is not None and scheduler != "local" and ":" not in scheduler:
        raise _usage(f"{_PROG} season: error: --scheduler: expected 'local', 'none' or a scheduler address such "
                     f"as tcp://host:8786, got {args.scheduler!r}")
    if scheduler is not None:
        try:
            require_dask()
        except ImportError as exc:
            raise _usage(f"{_PROG} season: error: {exc}") from None
    model = _model(args, "season")
    progress = sys.stderr.isatty() if args.progress is None else args.progress
    res = season_sweep(args.vessel, states, _headings_rad(args, "season"), settings=st,
                       labels=labels, quantile=args.quantile, scheduler=scheduler,
                       n_workers=2 if args.workers is None else args.workers,
                       chunk_size=args.chunk_size, progress=progress)
    op = res.operability(args.max_p_exceed)
    n = len(states) * len(args.headings_deg) * st.n_samples
    text = (f"# Drift-off season sweep\n\n{len(states)} weather states x {len(args.headings_deg)} headings x "
            f"{st.n_samples} samples = {n} blackouts of {model.vessel.name} in {res.wall_s:.1f} s "
            f"({n / res.wall_s:.0f} samples/s; scheduler {args.scheduler}).\n\n" + _over_capacity_text(res) +
            f"## Share of states with P(exceed) <= {args.max_p_exceed:g}, per heading, radius and reaction time\n\n"
            + markdown_table(op) + "\n")
    write_season_report(Path(args.out), res.to_frame(), op, text)
    print(text)
    return 0


def _over_capacity_text(res) -> str:
    """A season summary's warning where states' mean environment exceeds the thrusters' capacity
    (as a planning summary warns; none otherwise)."""
    over = res.over_capacity_frac.max(axis=1) > 0       # per state: at any heading, any sample
    if not over.any():
        return ""
    return (f"**DP capacity exceeded before the blackout** in {int(over.sum())} of {over.size} weather states at "
            "one heading or more: the mean wind, waves and current there need more than the thrusters' bollard "
            "force or moment in surge, sway or yaw alone, so the vessel would not be holding station when the "
            "blackout comes; their times and operable shares are optimistic (column `over_capacity_frac` in "
            "season.csv).\n\n")
