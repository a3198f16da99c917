"""benchmarks/driftoff_live.py and driftoff_season.py: their options."""

import pytest

from conftest import load_benchmark


@pytest.mark.parametrize("bad", [["--samples", "0"], ["--vessel-spread", "-1"], ["--vessel-spread", "nan"],
                                 ["--seed", "-1"]])
def test_live_settings_it_cannot_use_are_usage_errors(bad, tmp_path, capsys):
    """Settings the drift-off model refuses stop with a usage error (exit 2) naming the option
    and the reason, before any log is read (they ended in DriftOffSettings' traceback)."""
    live = load_benchmark("driftoff_live")
    with pytest.raises(SystemExit) as exc:
        live.main([*bad, "--data", str(tmp_path), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"error: {bad[0]}: " in err and ("must be" in err or "expected" in err), err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("bad", [["--states", "-3"], ["--states", "0"], ["--single-states", "0"], ["--samples", "0"],
                                 ["--workers", "0"], ["--chunk-size", "0"], ["--seed", "-1"]])
def test_season_counts_it_cannot_use_are_usage_errors(bad, tmp_path, monkeypatch, capsys):
    """A count below 1 or a negative seed stops with a usage error (exit 2) naming the option
    before any work: a negative --states swept the year less its last states, --workers 0
    waited for ever on a cluster without workers, the others ended in a traceback."""
    season = load_benchmark("driftoff_season")

    def no_work():
        raise AssertionError("the work started")

    monkeypatch.setattr(season, "require_dask", no_work)
    with pytest.raises(SystemExit) as exc:
        season.main([*bad, "--out", str(tmp_path / "out"), "--data-out", str(tmp_path / "data")])
    assert exc.value.code == 2
    assert f"error: {bad[0]}: expected" in capsys.readouterr().err


def _season_without_sweeps(monkeypatch, seeds=None):
    """driftoff_season with its sweep and cluster stubbed (tables from empty frames); the
    seeds the sweeps were given are appended to ``seeds``."""
    from types import SimpleNamespace

    season = load_benchmark("driftoff_season")

    def sweep(model, states, psi, settings, **kw):
        if seeds is not None:
            seeds.append(settings.seed)
        frame = season.pd.DataFrame({"state": range(len(states))})
        return SimpleNamespace(to_frame=lambda: frame, wall_s=1.0, operability=lambda _: frame)

    idle = SimpleNamespace(run=lambda f: None, close=lambda: None)
    monkeypatch.setattr(season, "require_dask", lambda: SimpleNamespace(LocalCluster=lambda **kw: idle,
                                                                         Client=lambda cluster: idle))
    monkeypatch.setattr(season, "season_sweep", sweep)
    return season


def test_season_command_records_the_seed(tmp_path, monkeypatch):
    """The command on tables.md repeats --seed when it is not the default (it drew the weather
    year and the samples, and was left out: the recorded command made another table)."""
    seeds = []
    season = _season_without_sweeps(monkeypatch, seeds)
    argv = ["--states", "2", "--samples", "2", "--out", str(tmp_path / "out"), "--data-out", str(tmp_path / "d")]
    assert season.main([*argv, "--seed", "3"]) == 0
    assert 3 in seeds
    command = (tmp_path / "out" / "tables.md").read_text().splitlines()[2]
    assert command.endswith("--chunk-size 24 --seed 3`"), command
    assert season.main(argv) == 0           # the default seed: the command as committed
    command = (tmp_path / "out" / "tables.md").read_text().splitlines()[2]
    assert command.endswith("--workers 2 --chunk-size 24`"), command


def _live_with_one_result(data, monkeypatch):
    """driftoff_live.py loaded with its evaluation replaced by one hand-made row, and a folder
    ``data`` holding one (empty) log for it to find: ``(module, data)``."""
    live = load_benchmark("driftoff_live")
    data.mkdir()
    (data / "a_seed1.csv.gz").write_bytes(b"")
    row = {"log": "a", "track": "truth_lf", "radius_m": 5.0, "actual_s": 1.0, "pred_p10_s": 0.5,
           "pred_p50_s": 1.0, "pred_p90_s": 2.0, "percentile": 50.0, "update_s": 0.1}
    monkeypatch.setattr(live, "evaluate", lambda *a, **kw: [dict(row)])
    return live, data


def test_live_command_records_a_data_folder_other_than_the_default(tmp_path, monkeypatch):
    """The command on tables.md repeats --data when it is not the default folder (it was left
    out: the recorded command read the default logs, not those the table came from); with the
    default folder the command is as committed."""
    live, data = _live_with_one_result(tmp_path / "my logs", monkeypatch)
    out = tmp_path / "out"
    assert live.main(["--data", str(data), "--out", str(out)]) == 0
    command = (out / "tables.md").read_text().splitlines()[0]
    assert command.endswith(f"--method estimator --data '{data}'`"), command
    monkeypatch.setattr(live, "DEFAULT_DATA", data)
    for argv in ([], ["--data", str(data)]):
        assert live.main([*argv, "--out", str(out)]) == 0
        command = (out / "tables.md").read_text().splitlines()[0]
        assert command == ("Command: `python benchmarks/driftoff_live.py --samples 500 --vessel-spread 1 --seed 0"
                           " --method estimator`"), command


def test_season_load_legend_says_what_a_load_above_the_cores_means(tmp_path, monkeypatch):
    """tables.md wrote "load average at the end X (above the core count = other jobs competed
    for the cores)" whatever X was, which reads as a statement about this run; the legend now
    says what a load above the core count would mean, and the committed table has that legend."""
    from pathlib import Path

    season = _season_without_sweeps(monkeypatch)
    monkeypatch.setattr(season.os, "cpu_count", lambda: 2)
    monkeypatch.setattr(season.os, "getloadavg", lambda: (2.1, 0.0, 0.0))
    assert season.main(["--states", "2", "--samples", "2", "--out", str(tmp_path / "out"),
                        "--data-out", str(tmp_path / "d")]) == 0
    machine = (tmp_path / "out" / "tables.md").read_text().splitlines()[4].partition("Machine: ")[2]
    assert machine == ("2 logical cores, 1-min load average at the end 2.1 "
                       "(a load above the core count means other jobs competed for the cores).")
    committed = Path(__file__).resolve().parents[1] / "docs" / "results" / "driftoff-season" / "tables.md"
    assert committed.read_text().splitlines()[4].partition("Machine: ")[2] == machine


def test_live_command_records_the_vessel_spread_given(tmp_path, monkeypatch):
    """The command on tables.md wrote --vessel-spread with %g: 0.1234567 was recorded as
    0.123457, a command that draws other vessels than the table's; it now gives the spread
    in full when %g does not (1 and 0.5 read as before)."""
    live, data = _live_with_one_result(tmp_path / "logs", monkeypatch)
    monkeypatch.setattr(live, "DEFAULT_DATA", data)
    out = tmp_path / "out"
    for spread, recorded in (("0.1234567", "0.1234567"), ("0.5", "0.5"), ("1", "1"), ("2e-07", "2e-07")):
        assert live.main(["--vessel-spread", spread, "--out", str(out)]) == 0
        command = (out / "tables.md").read_text().splitlines()[0]
        assert f" --vessel-spread {recorded} --seed 0 " in command, command
