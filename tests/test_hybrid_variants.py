"""benchmarks/hybrid_variants.py: its options."""

import pytest

from conftest import load_benchmark


@pytest.mark.parametrize("bad", [["--members", "0"], ["--seed", "-1"]])
def test_an_ensemble_it_cannot_build_is_a_usage_error(bad, tmp_path, capsys):
    """--members below 1 or a negative --seed ended in EnsembleConfig's traceback after the
    logs were read and the physics scored; now a usage error (exit 2) naming the option."""
    hv = load_benchmark("hybrid_variants")
    with pytest.raises(SystemExit) as exc:
        hv.main([*bad, "--data", str(tmp_path), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"error: {bad[0]}: must be" in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("where", ["missing", "empty"])
def test_a_data_folder_named_without_logs_is_a_usage_error(where, tmp_path, capsys):
    """A --data folder given on the command line (a typo, or one without logs) printed that the
    shared truthsim-dev data set was not on this machine and exited 0, as if the run had been
    skipped for want of the shared data; it is now a usage error (exit 2) naming --data."""
    hv = load_benchmark("hybrid_variants")
    data = tmp_path / ("no_such_folder" if where == "missing" else "")
    with pytest.raises(SystemExit) as exc:
        hv.main(["--data", str(data), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert "error: --data: no logs" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
