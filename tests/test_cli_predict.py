"""CLI train / forecast round trip and error exits; the metrics table layout."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from hybridship.evaluation import metrics
from hybridship.cli import main
from hybridship.logs.io import write_log
from hybridship.physics.model import DynamicModel
from hybridship.predictors import DynamicPredictor, as_log_arrays
from hybridship.sim.synthetic import physics_log


@pytest.fixture(scope="module")
def log_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("logs")
    m = DynamicModel("gunnerus")
    for s in (1, 2):
        write_log(physics_log(m, seed=s, current=(0.2, 2.0)), d / f"log{s}.csv.gz")
    return d


def test_train_replaces_a_model_file_but_never_other_arrays(log_dir, tmp_path, capsys):
    """--out may replace an earlier model file (or an empty file); an .npz of the user's own
    arrays is refused before training and left as it was."""
    import numpy as np

    from hybridship.predictors import HybridPredictor
    from hybridship.predictors.model_file import is_model_file

    model = tmp_path / "m.npz"
    argv = ["train", "--logs", str(log_dir), "--members", "2", "--out"]
    assert main(argv[:-2] + ["1", "--out", str(model)]) == 0 and is_model_file(model)
    assert main(argv + [str(model)]) == 0
    assert HybridPredictor.load(model).ensemble_config.n_members == 2      # the earlier model replaced
    empty = tmp_path / "empty.npz"
    empty.write_bytes(b"")
    assert main(argv[:-2] + ["1", "--out", str(empty)]) == 0 and is_model_file(empty)
    mine = tmp_path / "mine.npz"
    np.savez(mine, a=np.arange(3))
    before = mine.read_bytes()
    assert main(argv + [str(mine)]) == 2
    assert "is not a hybridship model file" in capsys.readouterr().err
    assert mine.read_bytes() == before and not is_model_file(mine)


def test_train_then_forecast_writes_a_table(log_dir, tmp_path, capsys, monkeypatch):
    model = tmp_path / "m.npz"
    assert main(["train", "--logs", str(log_dir), "--out", str(model), "--members", "2"]) == 0
    # two logs hold fewer failures than the after-failure calibration needs: train says so
    assert "spread after a failure: not calibrated (the training logs hold fewer than 3" in capsys.readouterr().out
    out = tmp_path / "fc.csv"
    assert main(["forecast", "--model", str(model), "--log", str(log_dir / "log1.csv.gz"),
                 "--start-time", "900", "905", "--horizon-s", "30", "--out", str(out)]) == 0
    df = pd.read_csv(out)
    assert len(df) == 2 * 31 and {"north_m", "east_m", "heading_deg", "guard_weight"} <= set(df)
    # the table and the summary hold the model's forecast: the same one through the API, read
    # from its arrays (not through the table writer), each column and each start where it belongs
    import numpy as np

    from hybridship.logs.io import read_log
    from hybridship.predictors import HybridPredictor

    fc = HybridPredictor.load(model).forecast(read_log(log_dir / "log1.csv.gz"), [900.0, 905.0], 30.0)
    lead = np.arange(31.0)
    np.testing.assert_array_equal(df.start_time_s, np.repeat([900.0, 905.0], 31))
    np.testing.assert_array_equal(df.lead_s, np.tile(lead, 2))
    np.testing.assert_array_equal(df.time_s, np.concatenate([900.0 + lead, 905.0 + lead]))
    heading_deg = np.degrees(np.mod(fc.eta[..., 2], 2 * np.pi))
    for column, expected in (("north_m", fc.eta[..., 0]), ("east_m", fc.eta[..., 1]), ("heading_deg", heading_deg),
                             ("north_std_m", fc.eta_std[..., 0]), ("east_std_m", fc.eta_std[..., 1]),
                             ("guard_weight", fc.guard_weight)):
        np.testing.assert_allclose(df[column], expected.ravel(), rtol=1e-12, atol=1e-12, err_msg=column)
    assert np.ptp(fc.eta[:, -1, 0]) > 0 or np.ptp(fc.eta[:, -1, 1]) > 0     # the two starts differ
    printed = capsys.readouterr().out
    for i, start in enumerate((900, 905)):
        north, east, _ = fc.eta[i, -1]
        assert (f"start {start} s -> +30 s: north {north:.1f} m, east {east:.1f} m, "
                f"heading {heading_deg[i, -1]:.1f} deg (1-sigma {fc.eta_std[i, -1, 0]:.1f}/"
                f"{fc.eta_std[i, -1, 1]:.1f} m)") in printed, printed
    # without the guard there is no guard weight to report: the summary says so
    assert main(["forecast", "--model", str(model), "--log", str(log_dir / "log1.csv.gz"),
                 "--start-time", "900", "--horizon-s", "30", "--no-guard", "--out", str(tmp_path / "ng.csv")]) == 0
    assert "guard off" in capsys.readouterr().out
    assert "guard_weight" not in pd.read_csv(tmp_path / "ng.csv")
    # a model saved without the guard forecasts without it, as its forecast() does
    unguarded = HybridPredictor.load(model)
    unguarded.use_guard = False
    unguarded.save(tmp_path / "unguarded.npz")
    assert main(["forecast", "--model", str(tmp_path / "unguarded.npz"), "--log", str(log_dir / "log1.csv.gz"),
                 "--start-time", "900", "--horizon-s", "30", "--out", str(tmp_path / "ug.csv")]) == 0
    assert "guard off" in capsys.readouterr().out
    assert "guard_weight" not in pd.read_csv(tmp_path / "ug.csv")
    _a_full_disk_keeps_the_earlier_table(monkeypatch, capsys, ["forecast", "--model", str(model), "--log",
                                                               str(log_dir / "log1.csv.gz"), "--start-time", "910",
                                                               "--horizon-s", "30", "--out", str(out)])
    # the forecast never replaces the log it reads, nor writes onto a folder
    log_copy = tmp_path / "log1.csv.gz"
    log_copy.write_bytes((log_dir / "log1.csv.gz").read_bytes())
    assert main(["forecast", "--model", str(model), "--log", str(log_copy), "--start-time", "900",
                 "--out", str(log_copy)]) == 2
    assert "is the --log file" in capsys.readouterr().err
    assert log_copy.read_bytes() == (log_dir / "log1.csv.gz").read_bytes()
    assert main(["forecast", "--model", str(model), "--log", str(log_copy), "--start-time", "900",
                 "--out", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err
    # nor the model it uses, nor writes plain CSV under another extension
    model_bytes = model.read_bytes()
    assert main(["forecast", "--model", str(model), "--log", str(log_copy), "--start-time", "900",
                 "--out", str(model)]) == 2
    assert "is the --model file" in capsys.readouterr().err and model.read_bytes() == model_bytes
    assert main(["forecast", "--model", str(model), "--log", str(log_copy), "--start-time", "900",
                 "--out", str(tmp_path / "fc.csv.gz")]) == 2
    assert "expected a .csv file" in capsys.readouterr().err
    # train never replaces a training log with the model
    logs = tmp_path / "own-logs"
    logs.mkdir()
    (logs / "a.csv.gz").write_bytes((log_dir / "log1.csv.gz").read_bytes())
    assert main(["train", "--logs", str(logs), "--out", str(logs / "a.csv.gz"), "--members", "2"]) == 2
    assert "expected a .npz model file" in capsys.readouterr().err
    assert (logs / "a.csv.gz").read_bytes() == (log_dir / "log1.csv.gz").read_bytes()


def _a_full_disk_keeps_the_earlier_table(monkeypatch, capsys, argv):
    """The disk fills up after 100 bytes of the new table: the command fails with status 1
    naming the file, and the earlier table at ``--out`` is whole (written beside it, then
    renamed), with no partial file left."""
    import builtins
    import errno
    import io

    out = Path(argv[-1])
    before = out.read_bytes()
    real_open = builtins.open

    class Full:
        def __init__(self, fh):
            self.fh = fh

        def write(self, data):
            self.fh.write(bytes(data)[:100])
            raise OSError(errno.ENOSPC, "No space left on device")

        def __getattr__(self, name):
            return getattr(self.fh, name)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

    def full_disk(file, mode="r", *args, **kwargs):
        fh = real_open(file, mode, *args, **kwargs)
        return Full(fh) if out.name in str(file) and mode[:1] in "wx" else fh
    capsys.readouterr()
    with monkeypatch.context() as m:
        m.setattr(builtins, "open", full_disk)
        m.setattr(io, "open", full_disk)
        assert main(argv) == 1
    err = capsys.readouterr().err
    assert f"{out}: cannot be written" in err and "Traceback" not in err, err
    assert out.read_bytes() == before and sorted(p.name for p in out.parent.glob(f"*{out.name}*")) == [out.name]


def test_train_help_names_every_log_extension_it_reads(capsys):
    """``--logs`` reads .pq files too; its help left them out."""
    from hybridship.logs.io import _EXTENSIONS

    assert main(["train", "--help"]) == 0
    help_text = " ".join(capsys.readouterr().out.split())
    assert all(f"*{ext}" in help_text for ext in _EXTENSIONS), help_text


def test_every_option_with_a_default_says_it_in_its_help():
    """An option that takes a value unless given one says which in its help ("(default ...)"):
    ``benchmark drift --scenarios``, ``benchmark manoeuvre --out`` and ``drift-off season
    --scheduler`` did not (3, manoeuvre-benchmark and a LocalCluster)."""
    import argparse

    from hybridship.cli import _build_parser

    silent = []

    def walk(parser, words):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, words + [name])
            elif (action.option_strings and action.default not in (None, False, "", argparse.SUPPRESS)
                  and "default" not in (action.help or "")):
                silent.append(f"{' '.join(words)} {action.option_strings[-1]} (default {action.default})")

    walk(_build_parser(), ["hybridship"])
    assert not silent, silent


def test_output_into_a_closed_pipe_stops_quietly(capsys, monkeypatch):
    """``hybridship ... | head -1``: the reader leaves, the next print fails; that ended with
    "error: [Errno 32] Broken pipe" and status 1, as if the command had failed."""
    class ClosedPipe:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            pass

    def demo(args):                                 # a command that prints its result
        print("start 400 s -> +60 s: ...")
        return 0

    monkeypatch.setattr("hybridship.cli._cmd_demo", demo)
    monkeypatch.setattr("sys.stdout", ClosedPipe())
    assert main(["demo"]) == 141
    assert capsys.readouterr().err == ""


def test_cli_errors_are_one_line_and_non_zero(log_dir, tmp_path, capsys):
    assert main(["forecast", "--model", str(tmp_path / "missing.npz"), "--log", str(log_dir / "log1.csv.gz"),
                 "--start-time", "900", "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "model file not found" in err and "\n" not in err
    assert err == f"hybridship forecast: error: --model {tmp_path / 'missing.npz'}: model file not found"
    assert main(["forecast", "--model", str(log_dir), "--log", str(log_dir / "log1.csv.gz"),      # a folder
                 "--start-time", "900", "--out", str(tmp_path / "x.csv")]) == 2
    assert capsys.readouterr().err.startswith(f"hybridship forecast: error: --model {log_dir}: is a folder")
    capsys.readouterr()
    assert main(["train", "--vessel", "no_such_ship", "--logs", str(log_dir), "--out", str(tmp_path / "m.npz")]) == 2
    assert "train: error: --vessel: " in capsys.readouterr().err     # the option named, whatever the file's fault
    assert main(["train", "--logs", str(tmp_path / "nope"), "--out", str(tmp_path / "m.npz")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("hybridship train: error: --logs ") and "not a folder" in err and "\n" not in err, err


def test_a_forecast_request_the_log_cannot_serve_is_a_usage_error(log_dir, tmp_path, capsys):
    """Start times that are not samples, and known commands beyond the log's end, are the
    user's input (exit 2), though only the log's contents reveal them."""
    model = tmp_path / "m.npz"
    assert main(["train", "--logs", str(log_dir), "--out", str(model), "--members", "2"]) == 0
    capsys.readouterr()
    log = log_dir / "log1.csv.gz"
    end = float(pd.read_csv(log).time_s.iloc[-1])
    for extra, needle in ((["--start-time", "900.5"], "--start-time: 900.5 s is not a sample time"),
                          (["--start-time", f"{end - 10:g}", "--commands", "known"], "--commands known: the log ends")):
        assert main(["forecast", "--model", str(model), "--log", str(log), "--out", str(tmp_path / "f.csv")]
                    + extra) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("hybridship forecast: error: ") and needle in err and "\n" not in err
        assert "start_times_s" not in err and "commands='" not in err     # the options' names, not Python's
    assert not (tmp_path / "f.csv").exists()
    # a log whose extension no reader knows is the user's input too, refused before reading
    (tmp_path / "ship.toml").write_text("[particulars]\n")
    assert main(["forecast", "--model", str(model), "--log", str(tmp_path / "ship.toml"), "--start-time", "900",
                 "--out", str(tmp_path / "f.csv")]) == 2
    assert "--log" in capsys.readouterr().err and not (tmp_path / "f.csv").exists()


def test_forecast_of_a_10_hz_log_is_on_its_grid_and_a_horizon_under_a_step_is_a_usage_error(tmp_path, capsys):
    """``lead_s == 60`` selects the last row of each start and every ``time_s`` is a log time
    (the step was the median float difference, 0.10000000000000142 s); ``--horizon-s 0.4``
    on a 1-Hz log exits 2 with one line (it wrote a forecast of zero steps)."""
    from hybridship.predictors import HybridPredictor
    from hybridship.residual.calibration import CalibrationConfig
    from hybridship.residual.ensemble import EnsembleConfig

    m = DynamicModel("gunnerus")
    one_hz = physics_log(m, seed=1, duration_s=400.0, t_shutdown_s=None)
    HybridPredictor(m.vessel, ensemble_config=EnsembleConfig(n_members=2, hidden=8, max_epochs=15, patience=5),
                    calibration_config=CalibrationConfig(fraction=0.0)).fit([one_hz]).save(tmp_path / "m.npz")
    write_log(one_hz, tmp_path / "1hz.csv")
    write_log(physics_log(m, seed=2, duration_s=400.0, dt_s=0.1, t_shutdown_s=None), tmp_path / "10hz.csv")
    log = pd.read_csv(tmp_path / "10hz.csv")
    out = tmp_path / "fc.csv"
    assert main(["forecast", "--model", str(tmp_path / "m.npz"), "--log", str(tmp_path / "10hz.csv"),
                 "--start-time", "301", "302.5", "--out", str(out)]) == 0
    df = pd.read_csv(out)
    assert len(df) == 2 * 601 and (df.lead_s == 60).sum() == 2 and df.lead_s.max() == 60.0
    assert df.time_s.isin(log.time_s.round(9)).all() and df.time_s.max() == 362.5
    capsys.readouterr()
    assert main(["forecast", "--model", str(tmp_path / "m.npz"), "--log", str(tmp_path / "1hz.csv"),
                 "--start-time", "301", "--horizon-s", "0.4", "--out", str(tmp_path / "short.csv")]) == 2
    assert capsys.readouterr().err == ("hybridship forecast: error: --horizon-s: 0.4 s is shorter than one step of "
                                       "the log (1 s)\n")
    assert not (tmp_path / "short.csv").exists()
    for horizon in ("inf", "1e9"):              # refused before any array is made for it
        assert main(["forecast", "--model", str(tmp_path / "m.npz"), "--log", str(tmp_path / "1hz.csv"),
                     "--start-time", "301", "--horizon-s", horizon, "--out", str(tmp_path / "long.csv")]) == 2
        assert "--horizon-s must be > 0 and at most 86400 s (one day)" in capsys.readouterr().err


def test_train_with_manoeuvre_uses_the_manoeuvre_benchmarks_hybrid(log_dir, tmp_path, monkeypatch, capsys):
    """--manoeuvre trains the manoeuvre benchmark's hybrid (multi-step, the runs' mean residual,
    every row at its stride); without it, logs with no dp_active column get a note."""
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig
    from hybridship.predictors import HybridPredictor

    seen = {}

    def fit(self, logs, **kw):          # what would be trained, not the minutes of training
        seen.update(training=self.training, environment=self.environment, kw=kw,
                    members=self.ensemble_config.n_members)
        self.training_info = {"n_rows": 1}
        return self
    monkeypatch.setattr(HybridPredictor, "fit", fit)
    monkeypatch.setattr(HybridPredictor, "save", lambda self, path: None)
    assert main(["train", "--logs", str(log_dir), "--out", str(tmp_path / "m.npz"), "--members", "3",
                 "--manoeuvre"]) == 0
    assert seen["training"] == "multi_step" and seen["environment"] == "mean" and seen["members"] == 3
    assert seen["kw"].get("row_stride") == ManoeuvreConfig().train_row_stride and seen["kw"]["dp_only"] is False
    assert "note" not in capsys.readouterr().err
    runs = tmp_path / "runs"
    runs.mkdir()
    for f in log_dir.iterdir():
        pd.read_csv(f).drop(columns="dp_active").to_csv(runs / f.name, index=False)
    assert main(["train", "--logs", str(runs), "--out", str(tmp_path / "d.npz")]) == 0
    assert seen["training"] == "one_step" and "no log has a dp_active column" in capsys.readouterr().err


def test_train_refuses_one_recording_twice(log_dir, tmp_path, capsys):
    """A log and its copy in another format are one recording: training on both would count it
    twice (and the leave-one-failure-out choices would see the left-out failure's copy)."""
    from hybridship.logs.io import read_log

    logs = tmp_path / "logs"
    logs.mkdir()
    for name in ("log1.csv.gz", "log2.csv.gz"):
        (logs / name).write_bytes((log_dir / name).read_bytes())
    write_log(read_log(log_dir / "log1.csv.gz"), logs / "log1_copy.parquet")
    model = tmp_path / "m.npz"
    assert main(["train", "--logs", str(logs), "--out", str(model), "--members", "2"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("hybridship train: error: ") and "\n" not in err
    assert f"{logs / 'log1_copy.parquet'} has the same samples as {logs / 'log1.csv.gz'}" in err
    assert not model.exists()


def test_fit_compares_samples_not_names():
    from hybridship.predictors import HybridPredictor
    from hybridship.predictors.training_logs import samples_digest
    from hybridship.residual.ensemble import EnsembleConfig

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=1, current=(0.2, 2.0))
    a = as_log_arrays(log, m.vessel)
    assert samples_digest(a) == samples_digest(as_log_arrays(log.copy(), m.vessel))
    nudged = log.copy()
    nudged.loc[10, "north_m"] += 1e-3                 # similar is not identical
    assert samples_digest(as_log_arrays(nudged, m.vessel)) != samples_digest(a)
    hp = HybridPredictor(m.vessel, ensemble_config=EnsembleConfig(n_members=2, hidden=8, max_epochs=15))
    with pytest.raises(ValueError, match=r"logs\[2\] has the same samples as logs\[0\]"):
        hp.fit([log, nudged, log.copy()])


def test_drift_table_layout_and_physics_log_error_near_zero():
    m = DynamicModel("gunnerus")
    arrays = as_log_arrays(physics_log(m, seed=5, duration_s=1100.0, t_shutdown_s=900.0), m.vessel)
    errs = {"dynamic": [metrics.drift_errors(DynamicPredictor(m.vessel), arrays)]}
    long = metrics.error_table(errs)
    assert list(long.columns) == ["model", "state", "window", "horizon_s", "mae"]
    assert len(long) == 1 * 3 * 2 * 4
    # the model made this log: errors near zero (the 3-s start average lags a turning heading a little)
    assert long[long.state != "yaw_deg"]["mae"].max() < 0.2
    assert long[long.state == "yaw_deg"]["mae"].max() < 1.0
    table = metrics.paper_table(long)
    assert list(table.columns) == ["15 s", "30 s", "45 s", "60 s"]
    assert all("/" in c for c in table.to_numpy().ravel())


def test_own_vessel_model_forecasts_where_no_vessel_file_is(tmp_path, monkeypatch, capsys):
    """Defect 1 of issue 15: ``train --vessel my_ship.toml`` then ``forecast --model`` in a folder
    without the vessel file. The model file carries its vessel, so the forecast needs none."""
    import re

    from hybridship.vessel import load_vessel, packaged_vessel_text

    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    (work / "logs").mkdir(parents=True)
    elsewhere.mkdir()
    text = packaged_vessel_text("gunnerus")
    text = re.sub(r'(?m)^name = "gunnerus"', 'name = "my_ship"', text, count=1)
    text = re.sub(r"(?m)^mass_kg = [0-9.]+", "mass_kg = 630000.0", text, count=1)   # not gunnerus any more
    (work / "my_ship.toml").write_text(text)
    vessel = load_vessel(work / "my_ship.toml")
    assert vessel.name == "my_ship" and vessel.rigid_body.mass_kg == 630000.0
    write_log(physics_log(DynamicModel(vessel), seed=1, duration_s=240.0, t_shutdown_s=None, current=(0.2, 2.0)),
              work / "logs" / "a.csv", channel_names=vessel.channel_names, rotatable=vessel.rotatable)
    monkeypatch.chdir(work)
    assert main(["train", "--vessel", "my_ship.toml", "--logs", "logs", "--out", "m.npz", "--members", "2"]) == 0
    monkeypatch.chdir(elsewhere)                     # no my_ship.toml here, and it is not packaged
    out = elsewhere / "fc.csv"
    rc = main(["forecast", "--model", str(work / "m.npz"), "--log", str(work / "logs" / "a.csv"),
               "--start-time", "200", "--horizon-s", "20", "--out", str(out)])
    assert rc == 0, capsys.readouterr().err
    df = pd.read_csv(out)
    assert len(df) == 21 and df[["north_m", "east_m", "heading_deg"]].notna().all().all()


def test_train_reports_what_it_learned_from_failures():
    """`hybridship train` prints, after the model file, what fit learned from the training
    logs' failures and whether each part was kept, with the errors that decided it."""
    from hybridship.cli import _learned_from_failures

    assert _learned_from_failures({}) == []
    hull = {"munk_multiple": 0.65, "adopted": True, "n_failures": 6, "error_deg": 2.25, "error_zero_deg": 3.64,
            "error_left_out_deg": 2.42}
    prior = {"learned_mean": [0.5, -0.36, -0.24], "kept": False, "n_failures": 6,
             "position_error_m": [2.111, 2.117], "heading_error_deg": [3.64, 3.72]}
    hull_line, prior_line = _learned_from_failures({"drift_hull": hull, "thrust_error_prior": prior})
    assert "0.65 x Munk on 6 failures, kept" in hull_line and "left-out failures 2.42 deg)" in hull_line
    tested, = _learned_from_failures({"drift_hull": {**hull, "adopted": False, "n_left_out_gains": 3,
                                                     "p_value": 0.2188}})
    assert tested.endswith("not kept (heading 2.25 deg against 3.64 without; left-out failures 2.42 deg, "
                           "3 of 6 better, signed-rank p = 0.219)")
    assert "(+0.50, -0.36, -0.24): not kept" in prior_line
    assert "position 2.117 m against 2.111 m, heading 3.72 deg against 3.64 deg" in prior_line
    assert "signed-rank" not in prior_line                      # a file from before the test
    tested, = _learned_from_failures({"thrust_error_prior": {**prior, "position_p_value": 0.0312,
                                                             "heading_p_value": 0.2188}})
    assert tested.endswith("with the configured prior, signed-rank p = 0.0312 and 0.219)")
    few = _learned_from_failures({"thrust_error_prior": {"learned_mean": [0.1, 0.0, 0.0], "kept": False,
                                                         "n_failures": 2}})
    assert few == ["thrust error learned at the thrust stops (+0.10, +0.00, +0.00): not kept "
                   "(2 failures, fewer than the 5 the check needs)"]


def test_train_reports_the_yaw_load_its_failures_chose():
    """With ``--wave-yaw-load auto`` (the default) `hybridship train` prints whether the training
    logs' failures turned the yaw load with the waves, with the errors and test that decided it."""
    from hybridship.cli import _learned_from_failures

    wave = {"n_failures": 20, "turned": True, "held_deg": 1.54, "turned_deg": 1.42, "n_gains": 12, "p_value": 0.0012}
    line, = _learned_from_failures({"wave_yaw_load": wave})
    assert line == ("yaw load after a failure: turned with the waves, chosen on 20 failures (heading 1.42 deg "
                    "turned against 1.54 deg held, 12 of 20 better, signed-rank p = 0.0012)")
    held, = _learned_from_failures({"wave_yaw_load": {**wave, "turned": False, "p_value": 0.2}})
    assert held.startswith("yaw load after a failure: held, chosen on 20 failures (heading 1.42 deg ")
    few, = _learned_from_failures({"wave_yaw_load": {"n_failures": 3, "turned": False}})
    assert few == "yaw load after a failure: held (3 failures, fewer than the 5 the choice needs)"


def test_train_takes_the_yaw_load_option_into_the_model_file(log_dir, tmp_path, capsys, monkeypatch):
    """``train --wave-yaw-load auto`` writes a model that chooses it (two failures, too few:
    held, said); with --manoeuvre, whose environment is not the estimator, it is refused by name
    before any training."""
    from hybridship.predictors import HybridPredictor

    out = tmp_path / "m.npz"
    assert main(["train", "--logs", str(log_dir), "--out", str(out), "--members", "2", "--wave-yaw-load", "auto"]) == 0
    hp = HybridPredictor.load(out)
    assert hp.environment_config.wave_turned_yaw_load == "auto" and not hp.turns_yaw_load
    assert "yaw load after a failure: held (2 failures, fewer than the 5 the choice needs)" in capsys.readouterr().out
    def no_training(*args, **kwargs):
        raise AssertionError("trained")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    rc = main(["train", "--logs", str(log_dir), "--out", str(tmp_path / "n.npz"), "--manoeuvre", "--wave-yaw-load"])
    assert rc == 2 and not (tmp_path / "n.npz").exists()
    err = capsys.readouterr().err
    assert err.startswith("hybridship train: error: --wave-yaw-load on: not used with --manoeuvre"), err


def _benchmark_drift_environment(monkeypatch, tmp_path, given):
    """The EnvironmentConfig that ``hybridship benchmark drift ... given`` passes to the
    benchmark, which is stopped before any work."""
    from hybridship.evaluation import drift

    seen = []

    class Stop(Exception):
        pass

    def run(*args, environment_config=None, **kwargs):
        seen.append(environment_config)
        raise Stop      # before any work

    monkeypatch.setattr(drift, "run_drift_benchmark", run)
    with pytest.raises(Stop):
        main(["benchmark", "drift", "--out", str(tmp_path / "out"), *given])
    return seen[0]


@pytest.mark.parametrize("given, wanted", [([], "auto"), (["--wave-yaw-load"], True),
                                            (["--wave-yaw-load", "on"], True), (["--wave-yaw-load", "off"], False),
                                            (["--wave-yaw-load", "auto"], "auto")])
def test_benchmark_drift_passes_the_yaw_load_option_as_the_config_takes_it(tmp_path, monkeypatch, given, wanted):
    """``benchmark drift --wave-yaw-load``: alone or ``on`` True, ``off`` False, ``auto`` (the
    default) "auto", as ``EnvironmentConfig.wave_turned_yaw_load`` takes them."""
    got = _benchmark_drift_environment(monkeypatch, tmp_path, given).wave_turned_yaw_load
    assert got == wanted and type(got) is type(wanted)


_POSITIVE = ("0", "-3", "nan", "inf", "fast"), "expected a finite number > 0"


@pytest.mark.parametrize("option, field, given, expected, bad", [
    ("--current-prior-wind-ref", "current_prior_wind_ref_m_s", "8", 8.0, _POSITIVE),
    ("--current-prior", "current_prior_m_s", "0.05", 0.05, _POSITIVE),
    ("--yaw-load-prior", "load_yaw_prior_rad_s2", "1e-4", 1e-4, _POSITIVE),
    ("--load-prior-across-wind", "load_prior_across_wind", "0.1", 0.1,
     (("0", "-0.5", "1.5", "nan", "narrow"), "expected a number in (0, 1]"))])
def test_benchmark_drift_passes_the_estimators_priors_and_refuses_bad_ones(tmp_path, monkeypatch, capsys, option,
                                                                           field, given, expected, bad):
    """Each ``benchmark drift`` prior option reaches its ``EnvironmentConfig`` field (the
    config's default without it); a value out of its range is a usage error naming the option,
    before any work."""
    from hybridship.residual.environment import EnvironmentConfig

    default = getattr(EnvironmentConfig(), field)
    assert getattr(_benchmark_drift_environment(monkeypatch, tmp_path, []), field) == default
    assert getattr(_benchmark_drift_environment(monkeypatch, tmp_path, [option, given]), field) == expected != default
    values, message = bad
    for value in values:
        assert main(["benchmark", "drift", "--out", str(tmp_path / "out"), option, value]) == 2
        assert f"{option}: {message}" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_cli_warnings_and_short_logs_speak_the_users_words(log_dir, tmp_path, capsys):
    """A log-format warning is one line in the command's words (not the library's source
    line); training data too short names the logs, not an internal function."""
    df = pd.read_csv(log_dir / "log1.csv.gz")
    logs = tmp_path / "logs"
    logs.mkdir()
    df.assign(extra=1.0).iloc[:25].to_csv(logs / "short.csv", index=False)
    assert main(["train", "--logs", str(logs), "--out", str(tmp_path / "m.npz"), "--members", "2"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith("hybridship train: warning: ") and "ignoring 1 column(s)" in err[0]
    assert err[1].startswith("hybridship train: error: logs: ") and "need at least 20" in err[1]
    assert len(err) == 2 and ".py:" not in "".join(err) and "fit_ensemble" not in err[1]
    assert not (tmp_path / "m.npz").exists()


def test_bad_options_are_refused_before_any_work(log_dir, tmp_path, capsys):
    """--members 0 names the option (exit 2, no model file); a benchmark whose --out is its
    --train folder is refused before the tables land among the logs."""
    model = tmp_path / "m.npz"
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    assert main(["train", "--logs", str(log_dir), "--out", str(a_file / "m.npz")]) == 2   # a file on the way
    assert f"--out {a_file / 'm.npz'}: {a_file} exists and is not a folder" in capsys.readouterr().err
    # simulate named the file on the way as if it were --out ('--out a_file: exists and is not a folder')
    assert main(["simulate", "--seed", "1", "--out", str(a_file / "s.csv"), "--no-progress"]) == 2
    assert f"--out {a_file / 's.csv'}: {a_file} exists and is not a folder" in capsys.readouterr().err
    for members in ("0", "100000000"):
        assert main(["train", "--logs", str(log_dir), "--out", str(model), "--members", members]) == 2
        assert f"--members: expected a whole number in 1..1000, got '{members}'" in capsys.readouterr().err
        assert not model.exists()
    before = sorted(p.name for p in log_dir.iterdir())
    assert main(["benchmark", "drift", "--train", str(log_dir), "--out", str(log_dir)]) == 2
    assert "is the --train folder" in capsys.readouterr().err
    assert sorted(p.name for p in log_dir.iterdir()) == before


def test_scenarios_beyond_the_embedded_set_name_the_option(tmp_path, capsys):
    """demo and benchmark drift simulate 1..20 embedded scenarios: --scenarios 21 is a usage
    error naming the option (it failed with exit 1 naming the library's argument n)."""
    for argv in (["demo"], ["benchmark", "drift", "--out", str(tmp_path / "b")]):
        for n in ("0", "21"):
            assert main([*argv, "--scenarios", n]) == 2
            err = capsys.readouterr().err
            assert f"--scenarios: expected a whole number in 1..20, got '{n}'" in err, err
    assert not (tmp_path / "b").exists()


def test_an_empty_path_is_refused_not_read_as_the_current_folder(log_dir, tmp_path, capsys, monkeypatch):
    """An empty --logs, --model, --log, --train, --test or --out-dir was read as the current
    folder (a sweep written there, the logs found there trained on), as --out is not."""
    monkeypatch.chdir(tmp_path)
    logs, out = str(log_dir), str(tmp_path / "o")
    for option, argv in (
            ("--out-dir", ["simulate", "--sweep", "--seeds", "1", "--out-dir", "", "--drift-s", "nan"]),
            ("--logs", ["train", "--logs", "", "--out", str(tmp_path / "m.npz")]),
            ("--model", ["forecast", "--model", "", "--log", logs, "--start-time", "900", "--out", "f.csv"]),
            ("--log", ["forecast", "--model", "m.npz", "--log", "", "--start-time", "900", "--out", "f.csv"]),
            ("--train", ["benchmark", "drift", "--train", "", "--out", out]),
            ("--test", ["benchmark", "drift", "--train", logs, "--test", "", "--out", out]),
            ("--train", ["benchmark", "manoeuvre", "--train", "", "--test", logs, "--out", out]),
            ("--test", ["benchmark", "manoeuvre", "--train", logs, "--test", "", "--out", out])):
        assert main(argv) == 2, argv
        assert f"error: argument {option}: expected a path, got ''" in capsys.readouterr().err, argv
    assert list(tmp_path.iterdir()) == []


def test_version(capsys):
    import hybridship

    assert main(["--version"]) == 0
    assert capsys.readouterr().out == f"hybridship {hybridship.__version__}\n"


def test_train_on_a_folder_holding_only_a_forecast_table_says_what_it_is(tmp_path, capsys):
    """Review: a forecast table (two starts share their times) was refused for a repeated
    time stamp, after a note on manoeuvre logs that did not apply; it is refused as a
    forecast table, without the note."""
    import pandas as pd

    rows = [{"start_time_s": s, "lead_s": k, "time_s": s + k, "north_m": 0.0, "east_m": 0.0, "heading_deg": 0.0}
            for s in (10.0, 20.0) for k in range(30)]
    folder = tmp_path / "outputs"
    folder.mkdir()
    pd.DataFrame(rows).to_csv(folder / "forecast.csv", index=False)
    assert main(["train", "--logs", str(folder), "--out", str(tmp_path / "m.npz")]) == 1
    err = capsys.readouterr().err
    assert "not a log: a forecast table written by 'hybridship forecast'" in err
    assert "note:" not in err and "appears at rows" not in err


def test_forecast_api_names_repeated_starts_and_missing_known_commands(log_dir):
    """The same start twice is refused by name (not silently forecast twice); known commands
    with missing samples say so in the start's note."""
    from hybridship.logs.io import read_log
    from hybridship.predictors.forecast_setup import RequestError

    df = read_log(log_dir / "log1.csv.gz")
    p = DynamicPredictor("gunnerus")
    with pytest.raises(RequestError, match=r"start_times_s: each start time at most once; 900 s is given 2 times"):
        p.forecast(df, [900.0, 905.0, 900.0], 10.0)
    gap = df.copy()
    rpm = [c for c in gap.columns if c.endswith("_rpm")][0]
    gap.loc[(gap.time_s > 803) & (gap.time_s < 808), rpm] = float("nan")
    fc = p.forecast(gap, [800.0, 830.0], 20.0, commands="known")
    assert fc.notes[0].startswith("commands known: 4 of 19 future command samples missing") and fc.notes[1] == ""
    assert p.forecast(df, [800.0], 20.0, commands="known").notes == ("",)


def test_forecast_on_epoch_time_stamps_names_each_start_exactly(model, tmp_path, capsys):
    """A log stamped in Unix time: the summary said "start 1.7e+09 s" for every start, and the
    errors named a start time that way too."""
    import numpy as np

    from hybridship.predictors import HybridPredictor
    from hybridship.residual.ensemble import EnsembleConfig

    log = physics_log(model, seed=2, duration_s=300.0, t_shutdown_s=None, current=(0.2, 1.0))
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=5, patience=2, seed=0)
    path = HybridPredictor(model.vessel, ensemble_config=tiny).fit([log]).save(tmp_path / "m.npz")
    t0 = 1_700_000_000.5
    epoch = log.assign(time_s=log.time_s + t0)
    write_log(epoch, tmp_path / "epoch.csv")
    argv = ["forecast", "--model", str(path), "--log", str(tmp_path / "epoch.csv"), "--horizon-s", "10",
            "--out", str(tmp_path / "fc.csv"), "--start-time"]
    assert main(argv + [f"{t0 + 200:.1f}", f"{t0 + 210:.1f}"]) == 0
    out = capsys.readouterr().out
    assert "start 1700000200.5 s -> +10 s" in out and "start 1700000210.5 s -> +10 s" in out
    np.testing.assert_allclose(pd.read_csv(tmp_path / "fc.csv").start_time_s.unique(), [t0 + 200, t0 + 210])
    assert main(argv + [f"{t0 + 200:.1f}", f"{t0 + 200:.1f}"]) == 2
    assert "1700000200.5 s is given 2 times" in capsys.readouterr().err


def test_messages_write_epoch_times_in_full():
    from hybridship.messages import seconds_text

    assert seconds_text(1_700_000_000.5) == "1700000000.5"
    assert seconds_text(1_700_000_000.0) == "1700000000"
    assert seconds_text(0.1 + 0.2) == "0.3"
    assert seconds_text(-0.0000001) == "0"
    assert seconds_text(-12.25) == "-12.25"


def test_train_says_on_how_many_failures_the_after_failure_spread_is_calibrated():
    from types import SimpleNamespace

    from hybridship.cli import _after_stop_spread

    info = {"after_stop": {"n_logs": 4, "n_starts": 80, "starts_within_s": 20.0}}
    hp = SimpleNamespace(stop_after_failure=True, environment="estimator", training_info={"calibration": info})
    assert _after_stop_spread(hp) == ["spread after a failure: calibrated on 4 failures of the training logs "
                                      "(80 starts within 20 s of them; few failures give a rough scale); starts "
                                      "more than 20 s into a drift are not calibrated (the drifts are too short) "
                                      "and say so"]
    info["after_stop_late"] = {"n_logs": 3, "n_starts": 120}
    assert _after_stop_spread(hp)[0].endswith("; starts later in a drift on 3 of them (120 starts)")
    assert _after_stop_spread(SimpleNamespace(stop_after_failure=True, environment="mean", training_info={})) == []


def test_a_read_only_out_is_refused_before_training_or_forecasting(log_dir, tmp_path, capsys, monkeypatch):
    """A read-only --out (an earlier model or forecast table the user protected) is a usage
    error named with its option before any work: train refused it only once the model had
    been trained, forecast once the forecast had been made (exit 1, without the option)."""
    import stat

    import numpy as np

    from hybridship.predictors import HybridPredictor

    model = tmp_path / "m.npz"
    assert main(["train", "--logs", str(log_dir), "--out", str(model), "--members", "1"]) == 0
    kept = tmp_path / "kept.npz"
    kept.write_bytes(model.read_bytes())
    kept.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)
    table = tmp_path / "kept.csv"
    table.write_bytes(b"")
    table.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)
    capsys.readouterr()

    def no_work(*args, **kwargs):
        raise AssertionError("the work started before --out was checked")

    monkeypatch.setattr(HybridPredictor, "fit", no_work)
    monkeypatch.setattr(HybridPredictor, "forecast", no_work)
    before = kept.read_bytes()
    assert main(["train", "--logs", str(log_dir), "--out", str(kept), "--members", "1"]) == 2
    assert f"hybridship train: error: --out {kept}: is read-only" in capsys.readouterr().err
    assert kept.read_bytes() == before
    log = sorted(log_dir.iterdir())[0]
    t0 = float(np.floor(pd.read_csv(log).time_s.iloc[200]))
    assert main(["forecast", "--model", str(model), "--log", str(log), "--start-time", f"{t0:g}",
                 "--horizon-s", "5", "--out", str(table)]) == 2
    assert f"hybridship forecast: error: --out {table}: is read-only" in capsys.readouterr().err
    assert table.read_bytes() == b""


def test_a_sweep_over_a_log_of_another_format_names_the_out_dir_option(tmp_path, capsys, monkeypatch):
    """The refusal of a seed whose log is in --out-dir in another format named the library's
    argument out_dir and exited with 1 (a run failure), though it is the user's folder,
    checked before any simulation."""
    from hybridship.sim import scenario

    monkeypatch.setattr(scenario, "_simulate", lambda *a, **k: pytest.fail("simulated before the check"))
    out = tmp_path / "sweep"
    out.mkdir()
    (out / scenario.log_file_name(1, "parquet")).write_bytes(b"PAR1")
    assert main(["simulate", "--sweep", "--seeds", "1", "--out-dir", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("hybridship simulate: error: --out-dir: seed 1 has a log there in another format"), err


def test_simulate_with_a_vessel_that_cannot_keep_station_names_the_vessel_option(tmp_path, capsys):
    """A vessel without DP actuators (the Esso Osaka model: one fixed propeller) was refused
    as "vessel 'esso_osaka_model' cannot hold station ...", naming no option."""
    assert main(["simulate", "--vessel", "esso_osaka_model", "--seed", "1", "--out", str(tmp_path / "s.csv"),
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("hybridship simulate: error: --vessel: vessel 'esso_osaka_model' cannot hold station"), err
    assert not (tmp_path / "s.csv").exists()
