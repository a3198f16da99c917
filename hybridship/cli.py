"""Command-line interface: ``hybridship <command> ...``.

Each subcommand is two functions: ``_add_<name>(subparsers)`` declares its arguments and
sets ``func=_cmd_<name>``; ``_cmd_<name>(args) -> int`` runs it. Both are registered in
:func:`_build_parser`. Input errors are reported as one line on stderr
(``hybridship <command>: error: <what is wrong>``) with exit status 2; failures while
running (I/O, bad data) exit with 1. No tracebacks for either.

Commands
--------
simulate
    ``hybridship simulate --vessel gunnerus --scenario dp-loss --seed 3 --out sim.csv.gz``
    writes one DP-loss log (CSV, ``.csv.gz`` or Parquet by the extension);
    ``hybridship simulate --sweep --seeds 1-10 --out-dir DIR`` writes one log per seed
    and ``DIR/scenarios.csv``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["main", "parse_seeds"]

_PROG = "hybridship"


class UsageError(Exception):
    """Bad command-line input; the message is shown as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    """ArgumentParser that raises instead of printing usage and exiting."""

    def error(self, message):  # noqa: D401 (argparse API)
        raise UsageError(f"{self.prog}: error: {message}")


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


# --------------------------------------------------------------------------- argument types


def parse_seeds(text: str) -> list[int]:
    """Parse a seed list such as ``"1-10"``, ``"3"`` or ``"1,4,7-9"`` into ints (in order).

    Raises
    ------
    ValueError
        On malformed parts, negative seeds, reversed ranges or duplicates.
    """
    seeds: list[int] = []
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            raise ValueError(f"--seeds: empty entry in {text!r}")
        lo, sep, hi = part.partition("-")
        try:
            a = int(lo)
            b = int(hi) if sep else a
        except ValueError:
            raise ValueError(f"--seeds: {part!r} is not a seed or a range like 1-10") from None
        if a < 0 or b < a:
            raise ValueError(f"--seeds: {part!r} must be a non-negative seed or an increasing range")
        seeds.extend(range(a, b + 1))
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"--seeds: {text!r} repeats a seed")
    return seeds


def _seed_list(text: str) -> list[int]:
    try:
        return parse_seeds(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--seeds: ")) from None


# --------------------------------------------------------------------------- simulate

_SCENARIOS = ("dp-loss",)


def _add_simulate(sub) -> None:
    p = sub.add_parser(
        "simulate", help="simulate DP-loss drift scenarios and write logs",
        description="Simulate a vessel on DP that loses power and drifts; write the log(s) in the "
                    "project log format with truth_* columns. One scenario (--seed, --out) or a "
                    "sweep (--sweep --seeds, --out-dir).")
    p.add_argument("--vessel", default="gunnerus", help="packaged vessel name or vessel file (default gunnerus)")
    p.add_argument("--scenario", default="dp-loss", choices=_SCENARIOS, help="scenario type (default dp-loss)")
    p.add_argument("--seed", type=int, help="seed of a single scenario (non-negative)")
    p.add_argument("--out", type=Path, help="output log of a single scenario: .csv, .csv.gz, .parquet or .pq")
    p.add_argument("--sweep", action="store_true", help="simulate one scenario per seed of --seeds")
    p.add_argument("--seeds", type=_seed_list, help="seeds of a sweep, e.g. 1-10 or 1,3,5-7")
    p.add_argument("--out-dir", type=Path, help="output folder of a sweep")
    p.add_argument("--format", default="csv.gz", choices=("csv", "csv.gz", "parquet"),
                   help="log format of a sweep (default csv.gz)")
    p.add_argument("--beaufort", type=float, nargs=2, metavar=("LO", "HI"), default=(2.0, 5.0),
                   help="Beaufort range of the random sea state (default 2 5)")
    p.add_argument("--drift-s", type=float, default=900.0, help="drift duration after the shutdown [s] (default 900)")
    p.add_argument("--t-shutdown-s", type=float, default=3000.0,
                   help="nominal DP shutdown time [s] (default 3000; jittered by +-4 %% per seed)")
    p.add_argument("--heading-mode", default="weather", choices=("weather", "random"),
                   help="heading set-point: bow to weather +-20 deg, or random (default weather)")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show a progress bar (default: when stderr is a terminal)")
    p.set_defaults(func=_cmd_simulate)


def _check_log_path(path: Path, option: str) -> None:
    name = path.name.lower()
    if not name.endswith((".csv", ".csv.gz", ".parquet", ".pq")):
        raise UsageError(f"{option} {path}: unsupported extension; use .csv, .csv.gz, .parquet or .pq")
    if not path.parent.is_dir():
        raise UsageError(f"{option} {path}: folder {path.parent} does not exist")


def _cmd_simulate(args) -> int:
    from hybridship.logs.io import write_log
    from hybridship.sim import scenario
    from hybridship.vessel import load_vessel

    prefix = f"{_PROG} simulate"
    if args.sweep:
        if args.seeds is None or args.out_dir is None:
            raise UsageError(f"{prefix}: error: --sweep needs --seeds and --out-dir")
        if args.seed is not None or args.out is not None:
            raise UsageError(f"{prefix}: error: --seed and --out are for a single scenario; a sweep takes "
                             f"--seeds and --out-dir")
    else:
        if args.seeds is not None or args.out_dir is not None:
            raise UsageError(f"{prefix}: error: --seeds and --out-dir need --sweep")
        if args.seed is None or args.out is None:
            raise UsageError(f"{prefix}: error: give --seed and --out (or --sweep --seeds --out-dir)")
        if args.seed < 0:
            raise UsageError(f"{prefix}: error: --seed must be non-negative, got {args.seed}")
        _check_log_path(args.out, f"{prefix}: error: --out")

    try:
        vessel = load_vessel(args.vessel)
        overrides = dict(drift_s=args.drift_s, t_shutdown_s=args.t_shutdown_s, heading_mode=args.heading_mode)
        # Validate the settings once before any (long) simulation starts.
        scenario.DPLossConfig(seed=0, beaufort=tuple(args.beaufort), **overrides)
    except (ValueError, TypeError) as exc:
        raise UsageError(f"{prefix}: error: {_one_line(exc)}") from None
    progress = sys.stderr.isatty() if args.progress is None else args.progress

    if args.sweep:
        paths = scenario.sweep(args.out_dir, args.seeds, beaufort=tuple(args.beaufort), fmt=args.format,
                               vessel=vessel, progress=progress, **overrides)
        print(f"wrote {len(paths)} log(s) and {args.out_dir / 'scenarios.csv'}")
        return 0

    cfg = scenario.DPLossConfig(seed=args.seed, beaufort=tuple(args.beaufort), **overrides)
    df = scenario.simulate_dp_loss(cfg, vessel=vessel, progress=progress)
    write_log(df, args.out, thruster_names=[t.name for t in vessel.thrusters],
              rotatable=[t.type == "azimuth" for t in vessel.thrusters])
    stats = scenario.drift_statistics(df)
    print(f"wrote {args.out}: {len(df)} rows, DP shutdown at {stats['t_shutdown_s']:g} s, "
          f"drift excursion {stats['drift_excursion_60s_m']:.1f} m after 60 s, "
          f"mean drift speed {stats['drift_mean_sog_mps']:.2f} m/s")
    return 0


# --------------------------------------------------------------------------- entry point


def _build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every subcommand registered."""
    parser = _Parser(prog=_PROG, description="Ship drift forecasting with a 3-DOF Fossen model and "
                                               "neural residuals.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    _add_simulate(sub)
    return parser


def main(argv=None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    parser = _build_parser()
    args = None
    try:
        args = parser.parse_args(argv)
        if getattr(args, "func", None) is None:
            raise UsageError(f"{_PROG}: error: a command is required (try '{_PROG} --help')")
        return int(args.func(args))
    except UsageError as exc:
        print(_one_line(exc), file=sys.stderr)
        return 2
    except SystemExit as exc:  # --help / --version from argparse
        return exc.code if isinstance(exc.code, int) else 0
    except KeyboardInterrupt:
        print(f"{_PROG}: interrupted", file=sys.stderr)
        return 130
    except (OSError, ValueError, TypeError, FloatingPointError) as exc:
        cmd = getattr(args, "command", None)
        print(f"{_PROG}{' ' + cmd if cmd else ''}: error: {_one_line(exc)}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
