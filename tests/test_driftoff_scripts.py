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


def test_season_command_records_the_seed(tmp_path, monkeypatch):
    """The command on tables.md repeats --seed when it is not the default (it drew the weather
    year and the samples, and was left out: the recorded command made another table)."""
    from types import SimpleNamespace

    season = load_benchmark("driftoff_season")
    seeds = []

    def sweep(model, states, psi, settings, **kw):
        seeds.append(settings.seed)
        frame = season.pd.DataFrame({"state": range(len(states))})
        return SimpleNamespace(to_frame=lambda: frame, wall_s=1.0, operability=lambda _: frame)

    idle = SimpleNamespace(run=lambda f: None, close=lambda: None)
    monkeypatch.setattr(season, "require_dask", lambda: SimpleNamespace(LocalCluster=lambda **kw: idle,
                                                                         Client=lambda cluster: idle))
    monkeypatch.setattr(season, "season_sweep", sweep)
    argv = ["--states", "2", "--samples", "2", "--out", str(tmp_path / "out"), "--data-out", str(tmp_path / "d")]
    assert season.main([*argv, "--seed", "3"]) == 0
    assert 3 in seeds
    command = (tmp_path / "out" / "tables.md").read_text().splitlines()[2]
    assert command.endswith("--chunk-size 24 --seed 3`"), command
    assert season.main(argv) == 0           # the default seed: the command as committed
    command = (tmp_path / "out" / "tables.md").read_text().splitlines()[2]
    assert command.endswith("--workers 2 --chunk-size 24`"), command
