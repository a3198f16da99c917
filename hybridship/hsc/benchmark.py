"""The high-speed-craft benchmark: the paper's Tables 1 and 2 for SS, ARX, ANN and the hybrid.

:func:`run_benchmark` simulates the two sea trials, identifies every model on the
training part, scores it on both parts in both modes and writes, atomically, into
``out_dir``:

* ``table.csv`` - columns exactly ``model,sea_state,split,mode,output,R,MAE``;
* ``table.md`` - the paper's Table 1 (R) and Table 2 (MAE) layout, per scoring mode, with
  the paper's numbers beside ours, plus the grey box alone and the fitted parameters;
* ``speed_trim.csv`` - the calm-water equilibria (:func:`steady_curves`), also tabulated in
  ``table.md``;
* ``hsc_speed_trim.png``, ``hsc_validation_ss1.png``, ``hsc_validation_ss2.png``.

Scoring: every record (training or validation part) is scored on its own. The first
:data:`N_INIT` samples of the part give the initial conditions (measured outputs: the
lags of ARX and NARX, the Kalman filter's burn-in of the state-space model, the grey
box's starting speed and trim) and are left out of both modes' scores.
"""

from __future__ import annotations

import contextlib
import io
import time
from pathlib import Path

import numpy as np
import pandas as pd

from hybridship.config import check_flags, check_whole_number
from hybridship.fileio import (as_path, atomic_write, check_out_folder, check_output_files, earlier_run,
                               make_out_folder, record_outputs)
from hybridship.residual.ensemble import EnsembleConfig

from .contract import N_INPUTS, N_OUTPUTS, check_n_init, check_physical, check_record
from .hybrid import GreyBoxTables, HybridModel
from .identification import ARXModel, NARXConfig, NARXModel, StateSpaceModel
from .scoring import score
from .simulator import KNOT_M_S, PlaningCraftModel
from .trials import generate_trial, paper_trial
from .vessel import PlaningCraft, load_planing_craft

__all__ = ["run_benchmark", "models_for", "score_model", "steady_curves", "PAPER_R", "PAPER_MAE", "COLUMNS", "N_INIT"]

#: Columns of ``table.csv``.
COLUMNS = ["model", "sea_state", "split", "mode", "output", "R", "MAE"]
#: Samples of measured outputs used as initial conditions (not scored).
N_INIT = 10
MODELS = ("ss", "arx", "ann", "hybrid")
OUTPUTS = ("speed_kn", "pitch_deg")

#: The paper's Table 1 (R): (model, sea_state, output) -> (training, validation).
PAPER_R = {
    ("ss", 1, "speed_kn"): (0.93, 0.94), ("ss", 1, "pitch_deg"): (0.68, 0.57),
    ("ss", 2, "speed_kn"): (0.89, 0.85), ("ss", 2, "pitch_deg"): (0.73, 0.48),
    ("arx", 1, "speed_kn"): (0.95, 0.97), ("arx", 1, "pitch_deg"): (0.75, 0.68),
    ("arx", 2, "speed_kn"): (0.92, 0.93), ("arx", 2, "pitch_deg"): (0.88, 0.66),
    ("ann", 1, "speed_kn"): (0.99, 0.99), ("ann", 1, "pitch_deg"): (0.83, 0.80),
    ("ann", 2, "speed_kn"): (0.99, 0.96), ("ann", 2, "pitch_deg"): (0.96, 0.87),
}
#: The paper's Table 2 (MAE, kn and deg): (model, sea_state, output) -> (training, validation).
PAPER_MAE = {
    ("ss", 1, "speed_kn"): (0.94, 0.70), ("ss", 1, "pitch_deg"): (0.88, 0.78),
    ("ss", 2, "speed_kn"): (1.4, 1.1), ("ss", 2, "pitch_deg"): (1.2, 0.85),
    ("arx", 1, "speed_kn"): (0.85, 0.51), ("arx", 1, "pitch_deg"): (0.75, 0.67),
    ("arx", 2, "speed_kn"): (0.96, 0.88), ("arx", 2, "pitch_deg"): (0.83, 0.66),
    ("ann", 1, "speed_kn"): (0.30, 0.32), ("ann", 1, "pitch_deg"): (0.58, 0.56),
    ("ann", 2, "speed_kn"): (0.52, 0.56), ("ann", 2, "pitch_deg"): (0.47, 0.45),
}


def models_for(sea_state: int, craft, actuator: str, *, seed: int = 0, quick: bool = False,
               tables: GreyBoxTables | None = None) -> dict:
    """The four models with the paper's structures for a sea state (unfitted).

    Raises
    ------
    ValueError
        ``sea_state`` not 1 or 2 (the paper has structures for these two only).
    TypeError
        ``quick`` not True or False.
    """
    if isinstance(sea_state, (bool, np.bool_)) or sea_state not in (1, 2):
        raise ValueError(f"sea_state: expected 1 or 2, got {sea_state!r}")
    check_flags(quick=quick)            # quick="no" gave the quick models (fewer iterations and members)
    ens = EnsembleConfig(seed=seed, n_members=4 if quick else 10, max_epochs=150 if quick else 600,
                         patience=60)
    narx = NARXConfig(n_out=5, n_in=3, seed=seed) if sea_state == 1 else NARXConfig(n_out=7, n_in=5, seed=seed)
    if quick:
        narx = NARXConfig(n_out=narx.n_out, n_in=narx.n_in, seed=seed, max_iter=60, restarts=1)
    return {
        "ss": StateSpaceModel(order=4 if sea_state == 1 else 5, block_rows=8 if quick else 10),
        "arx": ARXModel(3, 2, 1) if sea_state == 1 else ARXModel(5, 3, 1),
        "ann": NARXModel(narx),
        "hybrid": HybridModel(craft, actuator, ensemble=ens, tables=tables),
    }


def _to_table_units(Y):
    return np.column_stack([Y[:, 0] / KNOT_M_S, np.degrees(Y[:, 1])])


def score_model(model, U, Y, mode: str, n_init: int = N_INIT):
    """Predictions (table units) and ``{output: (R, MAE)}`` of one model on one record."""
    if mode not in ("one_step", "free_run"):
        raise ValueError(f"mode: expected 'one_step' or 'free_run', got {mode!r}")
    # the rows scored start at n_init in both modes: a one-step score checks it too
    n_rows = np.shape(U)[0] if np.ndim(U) else 0
    n_init = check_n_init(n_init, model.n_init, n_rows)
    if n_rows - n_init < 2:         # R needs two scored rows; scoring's own error did not name n_init
        raise ValueError(f"n_init: expected at most {n_rows - 2} (two rows of U left to score), got {n_init}")
    # a craft record, whatever the model; the checked arrays go on (a DataFrame's Y[:, 0] was
    # pandas' InvalidIndexError)
    U, Y = check_record(U, Y, shape=(N_INPUTS, N_OUTPUTS))
    check_physical(U, Y)
    P = model.one_step(U, Y) if mode == "one_step" else model.free_run(U, Y, n_init)
    Yt, Pt = _to_table_units(Y)[n_init:], _to_table_units(P)[n_init:]
    return Pt, {o: score(Yt[:, j], Pt[:, j]) for j, o in enumerate(OUTPUTS)}


def _fmt(x):
    return "n/a" if x is None or not np.isfinite(x) else f"{x:.2f}"


def _markdown_table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def paper_layout(table: pd.DataFrame, metric: str, mode: str) -> str:
    """Markdown of the paper's Table 1 (``R``) or 2 (``MAE``) layout, ours beside the paper's."""
    paper = PAPER_R if metric == "R" else PAPER_MAE
    header = ["model"] + [f"SS{s} {o.split('_')[0]} {sp}" for s in (1, 2) for o in OUTPUTS for sp in ("train", "val.")]
    t = table[table["mode"] == mode].set_index(["model", "sea_state", "output", "split"])[metric]
    rows = []
    for m in MODELS:
        cells = []
        for s in (1, 2):
            for o in OUTPUTS:
                for sp in ("train", "validation"):
                    key = (m, s, o, sp)
                    cells.append(_fmt(t.get(key)))
        rows.append([f"{m} (ours)"] + cells)
        if (m, 1, "speed_kn") in paper:
            rows.append([f"{m} (paper)"] + [_fmt(paper[(m, s, o)][i]) for s in (1, 2) for o in OUTPUTS for i in (0, 1)])
    return _markdown_table(header, rows)


def snippet(name: str, lines: list[str]) -> list[str]:
    """``lines`` between the markers of a named section, so a page of the docs can include
    that part of ``table.md`` and never quote a number the run did not write."""
    return [f"<!-- --8<-- [start:{name}] -->", *lines, f"<!-- --8<-- [end:{name}] -->"]


def comparisons(table: pd.DataFrame, grey: pd.DataFrame) -> list[str]:
    """``table.md``'s comparisons, computed from its tables (the figures the discussion quotes).

    * the paper's one-step MAE over ours, per model and cell (how far below the paper's our
      one-step errors are: the hint that the paper's tables are free-run scores);
    * the fraction of the grey box's free-run validation MAE that the residual removes;
    * the hybrid's free-run validation MAE against every identified model, its margin to
      the best of them (``1 - hybrid / best``) and whether the target holds (at most the
      ANN's, and below SS's and ARX's, in every sea state and output).
    """
    t = table.set_index(["model", "sea_state", "output", "split", "mode"])["MAE"]
    cells = [(s, o, sp) for s in (1, 2) for o in OUTPUTS for sp in ("train", "validation")]
    header = ["model"] + [f"SS{s} {o.split('_')[0]} {'val.' if sp == 'validation' else sp}" for s, o, sp in cells]
    rows, spans = [], []
    for m in ("ss", "arx", "ann", "hybrid"):
        if (m, 1, "speed_kn") not in PAPER_MAE:
            continue
        r = [PAPER_MAE[(m, s, o)][sp == "validation"] / t[(m, s, o, sp, "one_step")] for s, o, sp in cells]
        rows.append([m] + [f"{x:.1f}" for x in r])
        spans.append(f"{m} {min(r):.1f}-{max(r):.1f}")
    out = ["### The paper's MAE over ours, one step ahead", "",
           *snippet("one-step-ratio", [_markdown_table(header, rows), "",
                                       "Range per model: " + "; ".join(spans) + "."]), ""]
    g = grey.set_index(["sea_state", "output", "split"])["MAE"]
    removed = [[f"{s}", o, _fmt(g[(s, o, "validation")]), _fmt(t[("hybrid", s, o, "validation", "free_run")]),
                f"{1 - t[('hybrid', s, o, 'validation', 'free_run')] / g[(s, o, 'validation')]:.2f}"]
               for s in (1, 2) for o in OUTPUTS]
    out += ["### What the residual removes from the grey box (free run, validation MAE)", "",
            *snippet("grey-box-removed", [_markdown_table(
                ["sea state", "output", "grey box", "hybrid", "fraction removed"], removed)]), ""]
    others = ("ss", "arx", "ann")
    rows, met, margins = [], True, []
    for s in (1, 2):
        for o in OUTPUTS:
            val = {m: t[(m, s, o, "validation", "free_run")] for m in ("hybrid", *others)}
            rank = {m: val[m] if np.isfinite(val[m]) else np.inf for m in others}      # a diverged run last
            best = min(others, key=rank.get)
            margin = 1 - val["hybrid"] / val[best]
            # a NaN (diverged) SS came out of min() as the bound when listed first, failing the target
            met &= bool(np.isfinite(val["hybrid"]) and val["hybrid"] <= rank["ann"]
                        and val["hybrid"] < min(rank["ss"], rank["arx"]))
            margins.append((margin, s, o, best))
            rows.append([f"{s}", o] + [f"{val[m]:.3f}" if np.isfinite(val[m]) else "n/a" for m in ("hybrid", *others)]
                        + [best, _fmt(margin)])
    # the first in table order on a tie; a diverged hybrid's (NaN) cell is the narrowest (min()
    # skipped it, or took it only when listed first, whatever the other cells)
    narrow = min(margins, key=lambda m: m[0] if np.isfinite(m[0]) else -np.inf)
    out += ["### The hybrid against the identified models (free run, validation MAE)", "",
            *snippet("hybrid-vs-identified", [
                _markdown_table(["sea state", "output", "hybrid", "ss", "arx", "ann", "best other", "margin"],
                                rows), "",
                f"Target (hybrid at most the ANN's and below SS's and ARX's in every sea state and output): "
                f"{'met' if met else 'not met'}. Narrowest margin: sea state {narrow[1]} {narrow[2]}, "
                f"{_fmt(narrow[0])} against {narrow[3]}."]), ""]
    return out


def _fig_bytes(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return buf.getvalue()


def steady_curves(craft, n_rpm: int = 17) -> pd.DataFrame:
    """Calm-water equilibria of the nominal file and the simulated true boat, devices retracted
    and fully out, from idle to full engine speed.

    Parameters
    ----------
    craft : PlaningCraft
        The nominal vessel file (:func:`~hybridship.hsc.vessel.load_planing_craft`).
    n_rpm : int
        Engine speeds from ``idle_rpm`` to ``max_rpm`` (at least 1).

    Returns
    -------
    DataFrame
        Columns ``boat`` ("nominal" or "truth"), ``device`` ("none", "interceptor",
        "trim_tab"), ``rpm``, ``speed_kn`` and ``trim_deg``.

    Raises
    ------
    TypeError, ValueError
        Naming ``craft`` (not a PlaningCraft) or ``n_rpm`` (not a whole number >= 1).
    """
    if not isinstance(craft, PlaningCraft):
        raise TypeError(f"craft: expected a PlaningCraft (load_planing_craft(...)), got {type(craft).__name__}")
    n_rpm = check_whole_number("n_rpm", n_rpm, 1)
    rpms = np.linspace(craft.engines.idle_rpm, craft.engines.max_rpm, n_rpm)
    rows = []
    for boat, c in (("nominal", craft), ("truth", craft.perturbed())):
        for device, act, a in (("none", "interceptor", 0.0), ("interceptor", "interceptor", 1.0),
                               ("trim_tab", "trim_tab", 1.0)):
            for r, st in zip(rpms, PlaningCraftModel(c, act).steady_curve(rpms, a)):
                rows.append({"boat": boat, "device": device, "rpm": float(r), "speed_kn": st.speed_kn,
                             "trim_deg": st.trim_deg})
    return pd.DataFrame(rows)


def _steady_markdown(curves: pd.DataFrame) -> list[str]:
    """``table.md``'s section of the calm-water equilibria: speed and trim per engine speed,
    boat and device (the numbers behind ``hsc_speed_trim.png``)."""
    wide = curves.pivot_table(index="rpm", columns=["boat", "device"], values=["speed_kn", "trim_deg"])
    cols = [(b, d) for b in ("nominal", "truth") for d in ("none", "interceptor", "trim_tab")]
    header = ["rpm"] + [f"{b} {d.replace('_', ' ')} kn / deg" for b, d in cols]
    rows = [[f"{r:.0f}"] + [f"{wide.loc[r, ('speed_kn', b, d)]:.2f} / {wide.loc[r, ('trim_deg', b, d)]:.2f}"
                            for b, d in cols] for r in wide.index]
    return ["## Calm-water equilibria (devices retracted: none; fully out: interceptor, trim tab)", "",
            _markdown_table(header, rows), ""]


def _speed_trim_figure(curves: pd.DataFrame):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for boat, label, ls in (("nominal", "nominal file", "-"), ("truth", "simulated 'true' boat", "--")):
        for device in ("none", "interceptor", "trim_tab"):
            c = curves[(curves.boat == boat) & (curves.device == device)]
            tag = "devices retracted" if device == "none" else f"{device.replace('_', ' ')} full"
            ax[0].plot(c.rpm, c.speed_kn, ls, label=f"{label}, {tag}")
            ax[1].plot(c.speed_kn, c.trim_deg, ls, label=f"{label}, {tag}")
    ax[0].set(xlabel="engine speed [rpm]", ylabel="steady speed [kn]", title="Calm-water speed")
    ax[0].axhline(40, color="grey", lw=0.8)
    ax[1].add_patch(plt.Rectangle((15, 2), 25, 4, color="green", alpha=0.1, label="credible range"))
    ax[1].set(xlabel="steady speed [kn]", ylabel="running trim [deg]", title="Running trim")
    ax[1].legend(fontsize=6)
    fig.tight_layout()
    data = _fig_bytes(fig)
    plt.close(fig)
    return data


def _validation_figure(trial, preds, sea_state):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    val = trial.validation
    t = val["time_s"].to_numpy()[N_INIT:]
    Y = _to_table_units(val[["speed_m_s", "pitch_rad"]].to_numpy())[N_INIT:]
    fig, ax = plt.subplots(2, 1, figsize=(11, 6), sharex=True)
    for j, (o, unit) in enumerate((("ship speed", "kn"), ("pitch", "deg"))):
        ax[j].plot(t, Y[:, j], color="k", lw=0.8, label="measured (GPS re-aligned)" if j == 0 else "measured (IMU)")
        for m in MODELS:
            ax[j].plot(t, preds[m][:, j], lw=0.8, label=m)
        ax[j].set_ylabel(f"{o} [{unit}]")
    ax[0].legend(fontsize=7, ncol=5)
    ax[0].set_title(f"Sea state {sea_state}: validation data, free-run simulation from the inputs")
    ax[1].set_xlabel("time [s]")
    fig.tight_layout()
    data = _fig_bytes(fig)
    plt.close(fig)
    return data


#: The benchmark's files in its output folder.
OUTPUT_FILES = ("table.csv", "table.md", "speed_trim.csv", "hsc_speed_trim.png", "hsc_validation_ss1.png",
                "hsc_validation_ss2.png")


def _checked_arguments(out_dir, seed, quick, progress) -> Path:
    """The output folder as a Path; ValueError/TypeError naming ``seed``, ``out_dir`` or a flag;
    FileExistsError/PermissionError for a file there under one of the benchmark's names that
    no hybridship command wrote (an earlier run's recognised by its ``table.md``) or that is
    read-only."""
    check_flags(quick=quick, progress=progress)      # quick="no" ran the quick configuration
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed: expected a non-negative integer, got {seed!r}")
    NARXConfig(seed=seed)                            # its restarts' seeds must fit: checked by name, before the work
    out = check_out_folder(as_path(out_dir, "out_dir"))
    check_output_files(out, OUTPUT_FILES, ours=earlier_run(OUTPUT_FILES, "table.md", b"# High-speed craft"))
    return out


def run_benchmark(out_dir, *, seed: int = 0, quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Run the whole high-speed-craft benchmark and write its table and figures.

    Parameters
    ----------
    out_dir : path
        Output folder (created).
    seed : int
        Seed of the trials (inputs, waves, sensor noise) and of every model's training.
    quick : bool
        A small run (trials 12 % as long, fewer iterations) for tests and smoke checks;
        its numbers are not the benchmark's.
    progress : bool
        Print progress and where each output went.

    Returns
    -------
    DataFrame
        The table (columns :data:`COLUMNS`).
    """
    out = _checked_arguments(out_dir, seed, quick, progress)      # before minutes of work
    with _one_torch_thread():
        return _run(out, seed, quick, progress)


@contextlib.contextmanager
def _one_torch_thread():
    """Torch on one thread while the benchmark runs (its timings and results are of one
    thread), and the caller's thread count back afterwards, also after an error."""
    try:
        import torch
    except ImportError:  # pragma: no cover
        yield
        return
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before)


def _run(out: Path, seed: int, quick: bool, progress: bool) -> pd.DataFrame:
    """:func:`run_benchmark` after its arguments were checked."""
    make_out_folder(out)
    say = print if progress else (lambda *a, **k: None)
    t_start = time.perf_counter()
    craft = load_planing_craft()
    rows, extra, grey_rows, params, val_preds, trials = [], [], [], {}, {}, {}
    for sea_state in (1, 2):
        cfg = paper_trial(sea_state, seed=seed, scale=0.12 if quick else 1.0)
        trial = generate_trial(cfg, craft, progress=progress)
        trials[sea_state] = trial
        tables = GreyBoxTables.from_craft(craft, cfg.actuator, n_rpm=13 if quick else 25)
        models = models_for(sea_state, craft, cfg.actuator, seed=seed, quick=quick, tables=tables)
        Ut, Yt = trial.arrays("train")
        parts = {"train": trial.arrays("train"), "validation": trial.arrays("validation")}
        val_preds[sea_state] = {}
        for name, model in models.items():
            t0 = time.perf_counter()
            model.fit(Ut, Yt)
            fit_s = time.perf_counter() - t0
            for split, (U, Y) in parts.items():
                for mode in ("one_step", "free_run"):
                    P, sc = score_model(model, U, Y, mode)
                    if split == "validation" and mode == "free_run":
                        val_preds[sea_state][name] = P
                    for o, (r, mae) in sc.items():
                        rows.append({"model": name, "sea_state": sea_state, "split": split, "mode": mode,
                                     "output": o, "R": r, "MAE": mae})
            say(f"  sea state {sea_state}: {name} identified in {fit_s:.1f} s")
            if name == "hybrid":
                params[sea_state] = model.grey.parameters()
                for split, (U, Y) in parts.items():
                    P = model.grey_free_run(U, Y, N_INIT)
                    Yt_, Pt_ = _to_table_units(Y)[N_INIT:], _to_table_units(P)[N_INIT:]
                    for j, o in enumerate(OUTPUTS):
                        r, mae = score(Yt_[:, j], Pt_[:, j])
                        grey_rows.append({"sea_state": sea_state, "split": split, "output": o, "R": r, "MAE": mae})
            if name == "ss":
                extra.append(f"SS{sea_state} state-space poles |z|: "
                             + ", ".join(f"{abs(p):.3f}" for p in model.params.poles))
    table = pd.DataFrame(rows, columns=COLUMNS)
    elapsed = time.perf_counter() - t_start

    # ---------------------------------------------------------------- outputs
    csv_path = atomic_write(out / "table.csv", lambda fh: fh.write(table.to_csv(index=False, float_format="%.4f").encode()))
    say(f"wrote {csv_path}")
    md = [f"# High-speed craft (Volcano71): identified models vs the hybrid{' (QUICK RUN)' if quick else ''}", "",
          f"seed {seed}; sea state 1: {trials[1].config.n_samples} samples ({trials[1].config.n_train} training), "
          f"sea state 2: {trials[2].config.n_samples} samples ({trials[2].config.n_train} training); "
          f"run time {elapsed:.0f} s.", ""]
    for mode, title in (("free_run", "free-run simulation from the inputs"), ("one_step", "one-step-ahead prediction")):
        md += [f"## Table 1 layout: correlation coefficient R, {title}", "",
               *snippet(f"r-{mode}", [paper_layout(table, "R", mode)]), "",
               f"## Table 2 layout: MAE (speed kn, pitch deg), {title}", "",
               *snippet(f"mae-{mode}", [paper_layout(table, "MAE", mode)]), ""]
    g = pd.DataFrame(grey_rows)
    md += ["## Grey box alone (free run), the hybrid without its residual", "",
           *snippet("grey-box", [_markdown_table(["sea state", "split", "output", "R", "MAE"], [
               [str(r.sea_state), r.split, r.output, _fmt(r.R), _fmt(r.MAE)] for r in g.itertuples()])]), ""]
    md += ["## Comparisons (computed from the tables above)", ""] + comparisons(table, g)
    md += ["## Fitted grey-box parameters", ""]
    for s, p in params.items():
        md.append(f"- sea state {s}: " + ", ".join(f"{k} = {v:.3g}" for k, v in p.items()))
    md += [""] + [f"- {e}" for e in extra] + [""]
    curves = steady_curves(craft, 9 if quick else 17)
    md += _steady_markdown(curves)
    md_path = atomic_write(out / "table.md", lambda fh: fh.write("\n".join(md).encode()))
    say(f"wrote {md_path}")
    curves_path = atomic_write(out / "speed_trim.csv",
                               lambda fh: fh.write(curves.to_csv(index=False, float_format="%.4f").encode()))
    say(f"wrote {curves_path}")
    say(f"wrote {atomic_write(out / 'hsc_speed_trim.png', lambda fh: fh.write(_speed_trim_figure(curves)))}")
    for s in (1, 2):
        p = atomic_write(out / f"hsc_validation_ss{s}.png",
                         lambda fh, s=s: fh.write(_validation_figure(trials[s], val_preds[s], s)))
        say(f"wrote {p}")
    record_outputs(out, OUTPUT_FILES)
    say(f"high-speed-craft benchmark done in {time.perf_counter() - t_start:.0f} s")
    return table
