"""Result tables shared by the Esso Osaka screening scripts.

:func:`command_line` is the command a result records. The scripts keep their working files under ``--out`` (the validation split there links to
the data, which stays out of the repository); :func:`publish` copies the result files
alone to a committed folder (``--results``).
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path


def command_line(script: str, argv=None) -> str:
    """The command that ran ``benchmarks/<script>`` with ``argv`` (None: this process's
    arguments), quoted as a shell would need it, for a result's first line."""
    return shlex.join(["python", f"benchmarks/{script}", *(sys.argv[1:] if argv is None else argv)])


def check_out(ap, path, *, file: bool = False, option: str = "--out") -> None:
    """Refuse an ``--out`` (or another ``option``) the run could not write, as a usage error
    (exit 2) naming the option, before the work (it failed when the first result was written,
    after it): for an output folder, a file there or on its way
    (:func:`hybridship.fileio.check_out_folder`); for an output ``file``, a folder there, or a
    path the file cannot be written at (:func:`hybridship.fileio.check_writable`). None (the
    option not given) passes."""
    from hybridship.fileio import check_out_folder, check_writable

    if path is None:
        return
    try:
        if not file:
            check_out_folder(path)
        elif Path(path).is_dir():
            raise IsADirectoryError(f"{path}: is a folder; expected the path of a file to write")
        else:
            check_writable(path)
    except OSError as exc:
        ap.error(f"{option}: {exc}")


def check_own_scenarios(ap, count_option: str, count: int, seed_option: str, seed: int) -> None:
    """Refuse a count of our own simulated scenarios outside 1-20 (the simulator's embedded
    scenarios) or a negative seed of the first, as a usage error naming the option (each
    ended in the simulator's traceback)."""
    if not 1 <= count <= 20:
        ap.error(f"{count_option}: expected 1-20, got {count}")
    if seed < 0:
        ap.error(f"{seed_option}: expected a non-negative integer, got {seed}")


def parse_horizons(ap, text: str) -> tuple[float, ...]:
    """``--horizons-s`` (comma-separated seconds) as finite horizons > 0 s, or a usage error
    (exit 2) naming the option."""
    try:
        horizons = tuple(float(h) for h in text.split(","))
    except ValueError:
        ap.error(f"--horizons-s: expected numbers like 5,10,20,30, got {text!r}")
    if not all(0 < h < float("inf") for h in horizons):
        ap.error(f"--horizons-s: horizons must be finite and > 0 s, got {text!r}")
    return horizons


def publish(out_dir: Path, results_dir: Path | None, names) -> None:
    """Copy ``names`` from ``out_dir`` to ``results_dir`` (atomically; nothing when it is None)."""
    from hybridship.fileio import atomic_write

    if results_dir is None:
        return
    results_dir.mkdir(parents=True, exist_ok=True)
    for name in names:
        atomic_write(results_dir / name, lambda fh, src=out_dir / name: fh.write(src.read_bytes()))


def validation_dirs(split_dir: Path, out_dir: Path) -> tuple[Path, Path] | None:
    """The fitting and validation folders of
    :func:`hybridship.evaluation.manoeuvre.validation_split`, or None, after its message on
    stderr, when the benchmark's split has not been made (the script then exits with 2)."""
    from hybridship.evaluation.manoeuvre import validation_split

    try:
        return validation_split(split_dir, out_dir)
    except FileNotFoundError as err:
        print(f"error: {err}", file=sys.stderr)
        return None


def tables_again(out_dir: Path, results_dir: Path | None, csv_names, render, names) -> int:
    """``--tables-only``: render ``out_dir/tables.md`` again, without a new run, as
    ``render(*frames, command)`` from the run's ``csv_names`` and the command its first line
    records, and :func:`publish` those of ``names`` that exist. Returns the exit code: 2, with
    a message, when the run's files are missing or the first line is not a command."""
    import pandas as pd

    from hybridship.fileio import write_text

    try:
        frames = [pd.read_csv(out_dir / name) for name in csv_names]
        first = (out_dir / "tables.md").read_text().splitlines()[0]
    except (FileNotFoundError, IndexError) as err:
        print(f"error: --tables-only needs {', '.join(csv_names)} and tables.md of a run in {out_dir}: {err}",
              file=sys.stderr)
        return 2
    if not (first.startswith("Command: `") and first.endswith("`")):
        print(f"error: {out_dir / 'tables.md'}: its first line is not the run's command", file=sys.stderr)
        return 2
    text = render(*frames, first[len("Command: `"):-1])
    write_text(out_dir / "tables.md", text)
    publish(out_dir, results_dir, [name for name in names if (out_dir / name).exists()])
    print(text)
    return 0


def cells_below(errors, model: str, reference: str = "dynamic") -> str:
    """``"n/total"``: the kind x horizon cells (commands known, distance) where ``model``'s
    mean error is below ``reference``'s."""
    e = errors[(errors["commands"] == "known") & (errors["state"] == "distance_m") & (errors["kind"] != "all")]
    t = e.pivot_table(index=["kind", "horizon_s"], columns="model", values="mae", sort=False)
    return f"{int((t[model] < t[reference]).sum())}/{len(t)}"


def kind_table(errors, reference: str, horizon_s: float = 30.0) -> str:
    """Markdown table of every model's distance [m] and heading [deg] error at ``horizon_s``
    per kind and pooled (logged commands known), with the pooled ratios to ``reference``."""
    import pandas as pd

    from hybridship.fileio import markdown_table

    e = errors[(errors["commands"] == "known") & (errors["horizon_s"] == horizon_s)]
    t = e.pivot_table(index="model", columns=["state", "kind"], values="mae", sort=False)
    kinds = list(dict.fromkeys(e["kind"]))
    rows = []
    for model in dict.fromkeys(e["model"]):
        rows.append([model, *(f"{t.loc[model, ('distance_m', k)]:.3f} / {t.loc[model, ('heading_deg', k)]:.2f}"
                              for k in kinds),
                     f"{t.loc[model, ('distance_m', 'all')] / t.loc[reference, ('distance_m', 'all')]:.2f} / "
                     f"{t.loc[model, ('heading_deg', 'all')] / t.loc[reference, ('heading_deg', 'all')]:.2f}"])
    return markdown_table(pd.DataFrame(rows, columns=["model", *kinds, f"pooled / {reference}"]))
