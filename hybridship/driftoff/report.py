"""What a DP operator reads at a glance: polar plot, exceedance curves, one-page summary.

* :func:`polar_plot`: time to reach each radius (median line, 10 % quantile dashed)
  against the wind direction relative to the bow (0 = head wind, 90 = from starboard);
* :func:`exceedance_plot`: P(radius reached by t) against t, one panel per radius, one
  line per heading, with the reaction times marked;
* :func:`write_report`: ``summary.md`` (one page), ``times.csv`` and ``watch.csv``
  (:meth:`~hybridship.driftoff.planning.DriftOffResult.summary_frames`) and the two
  figures, each written atomically;
* :func:`write_season_report`: a season sweep's ``summary.md``, ``season.csv`` and
  ``operability.csv``.

An output folder holds one report: each writer removes the files only the other one makes
(a season's tables beside a planning summary would read as its own).
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from ..config import check_whole_number
from ..fileio import as_path, atomic_write, starts_with, write_output_files, write_text
from .planning import DriftOffResult

__all__ = ["polar_plot", "exceedance_plot", "markdown_table", "write_report", "write_season_report", "write_text",
           "write_frame"]

#: The files only :func:`write_report` makes (planning and live), and only :func:`write_season_report`.
REPORT_ONLY_FILES = ("times.csv", "watch.csv", "polar.png", "exceedance.png")
SEASON_ONLY_FILES = ("season.csv", "operability.csv")


def _csv_bytes(df: pd.DataFrame) -> bytes:
    return df.to_csv(index=False, float_format="%.6g").encode("utf-8")


def write_frame(path, df: pd.DataFrame) -> Path:
    """Write a DataFrame as CSV atomically (no index)."""
    return atomic_write(path, lambda fh: fh.write(_csv_bytes(df)))


def _png_bytes(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight")
    return buf.getvalue()


def _check_result(result) -> None:
    """A TypeError naming ``result`` when it is not a :class:`DriftOffResult` (it failed on an attribute)."""
    if not isinstance(result, DriftOffResult):
        raise TypeError(f"result: expected a DriftOffResult, got {type(result).__name__}")


def polar_plot(result: DriftOffResult, ax=None, title: str | None = None):
    """Time to reach each radius against the wind direction relative to the bow (polar axes)."""
    import matplotlib.pyplot as plt

    _check_result(result)
    if ax is None:
        fig = plt.figure(figsize=(6, 6))
        ax = fig.add_subplot(projection="polar")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)           # clockwise, like a compass: 90 deg = from starboard
    order = np.argsort(result.weather_rel_rad)
    th = result.weather_rel_rad[order]
    tq = result.time_quantiles((0.1, 0.5))[order]
    tq = np.where(np.isfinite(tq), tq, np.nan)
    closed = lambda a: np.concatenate([a, a[:1]])  # noqa: E731
    for r, rad in enumerate(result.radii_m):
        line, = ax.plot(closed(th), closed(tq[:, r, 1]), marker="o", label=f"{rad:g} m, median")
        ax.plot(closed(th), closed(tq[:, r, 0]), ls="--", color=line.get_color(), label=f"{rad:g} m, 10 %")
    ax.set_title(title or "time to reach radius [s] vs wind direction off the bow", fontsize=10)
    if not np.isfinite(tq).any():       # an empty plot would read as a plotting fault
        ax.text(0.5, 0.5, f"no radius reached\nwithin {result.horizon_s:g} s\nat any heading",
                transform=ax.transAxes, ha="center", va="center", fontsize=11)
    else:
        ax.legend(loc="lower left", bbox_to_anchor=(1.05, 0.0), fontsize=8)
    return ax.figure


def exceedance_plot(result: DriftOffResult, n_times: int = 200):
    """P(radius reached by t) vs t: one panel per radius, one line per heading."""
    import matplotlib.pyplot as plt

    _check_result(result)
    # 0 drew empty panels and True one point, without a word; 2.5 failed in numpy's words
    t = np.linspace(0.0, result.horizon_s, check_whole_number("n_times", n_times, lo=2))
    p = result.exceedance_curves(t)
    R = len(result.radii_m)
    fig, axes = plt.subplots(1, R, figsize=(4 * R, 3.2), sharey=True, squeeze=False)
    for r, ax in enumerate(axes[0]):
        for h, psi in enumerate(result.headings_rad):
            ax.plot(t, p[h, r], label=f"hdg {math.degrees(psi) % 360:.0f}, wind {math.degrees(result.weather_rel_rad[h]) % 360:.0f} off bow")
        for tr in result.reaction_times_s:
            ax.axvline(tr, color="k", lw=0.8, ls=":")
        ax.set_title(f"radius {result.radii_m[r]:g} m", fontsize=10)
        ax.set_xlabel("time after blackout [s]")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("P(reached)")
    axes[0, -1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return fig


def _cell(v) -> str:
    """A table cell's text: a ``|`` (a log's path may hold one) written ``\\|``, so that it stays in its cell."""
    return str(v).replace("|", "\\|")


def markdown_table(df: pd.DataFrame, digits: int = 2) -> str:
    """A DataFrame as a Markdown table (numbers rounded; inf shown as "never"; a number that is
    not 0 but rounds to it as "<0.01" at ``digits=2``, so that a share of a few samples does
    not read as none)."""
    def fmt(v):
        if isinstance(v, (float, np.floating)):
            if np.isinf(v):
                return "never"
            if not math.isfinite(v):
                return "-"
            text = f"{v:.{digits}f}"
            text = text.rstrip("0").rstrip(".") if "." in text else text   # 100, not 1, without decimals
            if v != 0 and float(text) == 0:     # 4 samples in 1000 are not none: "<0.01", not "0"
                return f"<{10.0 ** -digits:g}" if v > 0 else f">-{10.0 ** -digits:g}"
            return text
        return _cell(v)

    head = "| " + " | ".join(_cell(c) for c in df.columns) + " |\n|" + "---|" * len(df.columns) + "\n"
    return head + "".join("| " + " | ".join(fmt(v) for v in row) + " |\n" for row in df.itertuples(index=False))


def write_report(result: DriftOffResult, out_dir, *, title: str = "Drift-off analysis", inputs: dict | None = None,
                 quantile: float = 0.9, plots: bool = True) -> dict:
    """Write ``summary.md``, ``times.csv``, ``watch.csv`` and (with ``plots``) ``polar.png``,
    ``exceedance.png`` to ``out_dir``; returns the paths by name. Every file is made before
    the first is written (a failure leaves no mix of two runs); without ``plots``, the two
    figures of an earlier run in ``out_dir`` are removed.

    Parameters
    ----------
    result : DriftOffResult
    out_dir : str or os.PathLike
        The output folder (made if missing).
    title : str
        The summary's heading.
    inputs : dict, optional
        Input names and values, listed as a table in the summary.
    quantile : float
        Watch-circle quantile, in (0, 1).
    plots : bool
        Write the two figures.
    """
    _check_result(result)
    out = as_path(out_dir, "out_dir")
    if not isinstance(title, str):
        raise TypeError(f"title: expected text, got {type(title).__name__}")
    if inputs is not None and not isinstance(inputs, Mapping):
        raise TypeError(f"inputs: expected a dict of input names and values (or None), got {type(inputs).__name__}")
    if not isinstance(plots, (bool, np.bool_)):    # a text "no" is truthy
        raise TypeError(f"plots: expected True or False, got {plots!r}")
    times, watch = result.summary_frames(quantile)
    lines = [f"# {title}", ""]
    if inputs:
        lines += (["| input | value |", "|---|---|"] + [f"| {_cell(k)} | {_cell(v)} |" for k, v in inputs.items()]
                  + [""])
    lines += [f"{result.n_samples} Monte-Carlo blackouts per heading; horizon {result.horizon_s:g} s "
              "(\"never\" = not reached within it). `_ci95_lo`/`_hi`: the exact binomial 95 % interval of each "
              "P(exceed) from this many samples (their sampling error, not the model's).", ""]
    lines += _over_capacity_lines(result)
    lines += [
              "## Time to reach each radius [s] and P(exceeded within the reaction time)", "",
              markdown_table(times), "",
              f"## Watch circles: excursion up to the reaction time at the {quantile:g} quantile [m]", "",
              markdown_table(watch), ""]
    contents = {"times.csv": _csv_bytes(times), "watch.csv": _csv_bytes(watch)}
    if plots:
        import matplotlib.pyplot as plt

        for name, plot in (("polar.png", polar_plot), ("exceedance.png", exceedance_plot)):
            fig = plot(result)
            contents[name] = _png_bytes(fig)
            plt.close(fig)
        lines += ["![time to reach vs wind direction](polar.png)", "", "![exceedance curves](exceedance.png)", ""]
    contents["summary.md"] = "\n".join(lines).encode("utf-8")
    # no figure of an earlier run (without plots), nor an earlier season's tables, beside these
    return write_output_files(out, contents, stale=SEASON_ONLY_FILES + (() if plots else ("polar.png", "exceedance.png")),
                              ours=earlier_report)


def _over_capacity_lines(result: DriftOffResult) -> list[str]:
    """A warning where the mean environment exceeds the thrusters' capacity (none otherwise)."""
    frac = result.over_capacity_frac
    if frac is None or not np.any(frac > 0):
        return []
    # a share is never rounded to none or all of the samples (1 of 1000 read "0% of the samples")
    share = lambda f: "<1%" if f < 0.01 else ">99%" if 0.99 < f < 1.0 else f"{f:.0%}"  # noqa: E731
    where = ", ".join(f"{math.degrees(h) % 360:.0f} deg ({share(f)} of the samples)"
                      for h, f in zip(result.headings_rad, frac) if f > 0)
    return [f"**DP capacity exceeded before the blackout** at heading(s) {where}: the mean wind, waves and current "
            "there need more than the thrusters' bollard force or moment in surge, sway or yaw alone, so the "
            "vessel would not be holding station when the blackout comes; the times there are optimistic "
            "(column `over_capacity_frac`).", ""]


def write_season_report(out_dir, season: pd.DataFrame, operability: pd.DataFrame, summary: str) -> dict:
    """Write a season sweep's ``season.csv``, ``operability.csv`` and ``summary.md`` to
    ``out_dir`` (each atomically, all made before the first is written) and remove the files
    only :func:`write_report` makes; returns the paths by name."""
    out = as_path(out_dir, "out_dir")
    for name, value, kind in (("season", season, pd.DataFrame), ("operability", operability, pd.DataFrame),
                              ("summary", summary, str)):
        if not isinstance(value, kind):     # it failed in the writing, with "has no attribute 'to_csv'"
            raise TypeError(f"{name}: expected {'a pandas DataFrame' if kind is pd.DataFrame else 'text'} (as "
                            f"SeasonResult.to_frame, .operability and a summary give), got {type(value).__name__}")
    contents = {"season.csv": _csv_bytes(season), "operability.csv": _csv_bytes(operability),
                "summary.md": summary.encode("utf-8")}
    return write_output_files(out, contents, stale=REPORT_ONLY_FILES, ours=earlier_report)


def earlier_report(name: str, path: Path) -> bool:
    """Whether ``path`` is a drift-off report's file written before output folders kept a
    record of their files: its tables' and summary's first bytes, or a figure beside
    such a summary."""
    heads = {"times.csv": b"heading_deg,", "watch.csv": b"heading_deg,", "season.csv": b"state,",
             "operability.csv": b"heading_deg,", "summary.md": b"# Drift-off "}
    if name.endswith(".png"):
        return (starts_with(path, b"\x89PNG") and starts_with(path.with_name("summary.md"), heads["summary.md"])
                and (path.with_name("times.csv").is_file() or path.with_name("season.csv").is_file()))
    return name in heads and starts_with(path, heads[name])
