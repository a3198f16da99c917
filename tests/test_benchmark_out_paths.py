"""The benchmark scripts' paths: an --out the run cannot write, or a --data folder without
logs, is a usage error before the work.

Each script failed only when its first result was written, after its run (minutes to tens of
minutes): an output folder given as a file, or below one, in mkdir's FileExistsError or
NotADirectoryError traceback; an output Markdown file given as a folder in atomic_write's
IsADirectoryError; the Esso scripts' --results folder given as a file after the results were
written to --out.
"""

import pytest

from conftest import load_benchmark

FOLDER_OUTS = ["drift_late_starts", "drift_oracles", "drift_protocols", "estimator_variants", "hybrid_variants",
               "station_keeping_coverage", "environment_vs_truth", "hsc_sea_validity", "hull_lift_convention",
               "hull_yaw_residual", "wave_direction", "driftoff_live", "driftoff_season",
               "filter_start_sensitivity", "esso_steady_runs", "nets_physics_features"]
FILE_OUTS = ["drift_late_coverage", "gap_sensitivity", "sample_rates", "rpm_inversion_cases",
             "after_stop_calibration"]
#: The Esso Osaka scripts: an output folder --out, and (all but two) a --results folder.
ESSO_OUTS = ["esso_error_sources", "esso_multistep", "esso_online_adaptation", "esso_physics_fit", "esso_training",
             "esso_wind_predictability", "esso_validation", "esso_osaka"]
WITH_RESULTS = ESSO_OUTS[:6]
REQUIRED = {"filter_start_sensitivity": ["--model", "model.npz", "--test", "logs"]}


@pytest.mark.parametrize("name", FOLDER_OUTS + ESSO_OUTS)
@pytest.mark.parametrize("where", ["a file", "below a file"])
def test_an_output_folder_that_is_a_file_is_a_usage_error(name, where, tmp_path, capsys):
    script = load_benchmark(name)
    (tmp_path / "a_file").write_text("x")
    out = tmp_path / "a_file" if where == "a file" else tmp_path / "a_file" / "results"
    with pytest.raises(SystemExit) as exc:
        script.main([*REQUIRED.get(name, []), "--out", str(out)])
    assert exc.value.code == 2
    assert "error: --out:" in capsys.readouterr().err
    assert (tmp_path / "a_file").read_text() == "x"


@pytest.mark.parametrize("name", FILE_OUTS)
@pytest.mark.parametrize("where", ["a folder", "below a file"])
def test_an_output_file_that_is_a_folder_is_a_usage_error(name, where, tmp_path, capsys):
    script = load_benchmark(name)
    (tmp_path / "a_file").write_text("x")
    out = tmp_path if where == "a folder" else tmp_path / "a_file" / "table.md"
    with pytest.raises(SystemExit) as exc:
        script.main(["--out", str(out)])
    assert exc.value.code == 2
    assert "error: --out:" in capsys.readouterr().err


@pytest.mark.parametrize("name", WITH_RESULTS)
def test_a_results_folder_that_is_a_file_is_a_usage_error(name, tmp_path, capsys):
    """--results, where the Esso scripts copy their result files, was made only after the run
    (the files were written to --out, then mkdir's FileExistsError)."""
    script = load_benchmark(name)
    (tmp_path / "a_file").write_text("x")
    with pytest.raises(SystemExit) as exc:
        script.main(["--out", str(tmp_path / "out"), "--results", str(tmp_path / "a_file")])
    assert exc.value.code == 2
    assert "error: --results:" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("name", FOLDER_OUTS + FILE_OUTS + ESSO_OUTS)
def test_a_new_output_path_passes(name, tmp_path, monkeypatch):
    """The check refuses nothing a run may write: a path not made yet (its folders included)."""
    import hybridship.fileio as fileio

    script = load_benchmark(name)

    class Checked(Exception):
        pass

    for check in ("check_out_folder", "check_writable"):
        def passed(path, _check=getattr(fileio, check)):
            _check(path)
            raise Checked
        monkeypatch.setattr(fileio, check, passed)
    with pytest.raises(Checked):
        script.main([*REQUIRED.get(name, []), "--out", str(tmp_path / "new" / "out.md")])


@pytest.mark.parametrize("name", ["hull_yaw_residual", "hybrid_variants"])
@pytest.mark.parametrize("where", ["missing", "empty"])
def test_a_data_folder_named_without_logs_is_a_usage_error(name, where, tmp_path, capsys):
    """A --data folder given on the command line that does not exist (a typo) or holds no logs
    was taken as the shared data set missing ('skipping', exit status 0), or failed in
    log_files' ValueError traceback; each is now a usage error (exit 2) naming --data."""
    script = load_benchmark(name)
    data = tmp_path / ("no_such_folder" if where == "missing" else "")
    with pytest.raises(SystemExit) as exc:
        script.main(["--data", str(data), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert "error: --data: no logs" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
