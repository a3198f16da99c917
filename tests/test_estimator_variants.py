"""benchmarks/estimator_variants.py: the per-failure ratios to the physics."""

import numpy as np
import pytest

from conftest import load_benchmark
from hybridship.evaluation import metrics


def test_per_log_rows_are_each_failures_ratio_to_its_own_physics():
    """Each ratio is a ratio of means over the intervals (not a mean of ratios), of the same
    failure, state and intervals: the physics' errors differ by state (1, 2, 3 times) and
    double after the fifth interval, so a ratio read against another state's, another
    failure's or all 20 intervals' physics differs."""
    ev = load_benchmark("estimator_variants")
    phys = np.ones((2, 20, 3)) * np.array([1.0, 2.0, 3.0])
    phys[:, 5:] *= 2.0
    phys[1] *= 4.0
    err = phys.copy()
    err[0, :5] *= 3.0                 # log a: three times the physics over the first five intervals
    err[1, :, 2] *= 0.5               # log b: half the physics' heading error throughout
    rows = ev.per_log_rows("set", "variant", ["a", "b"], err, phys)
    assert len(rows) == 2 * len(metrics.STATES)
    got = {(r["log"], r["state"]): (r["ratio_5"], r["ratio_20"]) for r in rows}
    for state in metrics.STATES:
        # first 20, per unit of the state's physics: (5 * 3 + 15 * 2) / (5 * 1 + 15 * 2)
        np.testing.assert_allclose(got[("a", state)], (3.0, 45.0 / 35.0))
    np.testing.assert_allclose(got[("b", metrics.STATES[2])], (0.5, 0.5))
    np.testing.assert_allclose(got[("b", metrics.STATES[0])], (1.0, 1.0))
    np.testing.assert_allclose(got[("b", metrics.STATES[1])], (1.0, 1.0))
    assert {r["data"] for r in rows} == {"set"} and {r["variant"] for r in rows} == {"variant"}


def test_an_own_set_the_simulator_cannot_make_is_a_usage_error(tmp_path, capsys):
    """--own-n outside 1-20 or a negative --own-seed stop with argparse's usage error (exit 2,
    naming the option), before any work, not with the simulator's traceback."""
    import pytest

    ev = load_benchmark("estimator_variants")
    for bad in (["--own-n", "0"], ["--own-n", "21"], ["--own-seed", "-1"]):
        with pytest.raises(SystemExit) as exc:
            ev.main(["--out", str(tmp_path), "--data", "own", "--only", "default", *bad])
        assert exc.value.code == 2
        assert bad[0] in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("script", ["estimator_variants", "drift_late_starts"])
def test_only_truthsim_dev_asked_for_without_it_is_an_error_and_writes_nothing(script, tmp_path, monkeypatch, capsys):
    """--data truthsim-dev on a machine without it skipped the set with a message and then wrote
    empty tables (estimator_variants: variants.md of '|  |' over the results, exit 0;
    drift_late_starts: the two CSV files, then pandas' AttributeError); it is now an error (exit 2) naming
    --data, and nothing is written."""
    ev = load_benchmark("estimator_variants")
    monkeypatch.setattr(ev, "TRUTHSIM", tmp_path / "no_such_folder")
    mod = ev
    if script == "drift_late_starts":
        mod = load_benchmark("drift_late_starts")
        monkeypatch.setattr(mod, "sibling", lambda name: ev)
    out = tmp_path / "out"
    assert mod.main(["--data", "truthsim-dev", "--only", "default", "--out", str(out)]) == 2
    assert "error: --data: no data set to run" in capsys.readouterr().err
    assert not out.exists()


def test_logs_add_a_folder_as_a_data_set_named_by_it(tmp_path, capsys):
    """--logs adds each folder of logs as one more data set, named by the folder; a path that is
    not a folder of logs, or two folders of one name (whose rows would mix), is a usage error
    naming --logs, before any work."""
    from hybridship.sim.scenario import embedded_scenarios

    ev = load_benchmark("estimator_variants")
    folder = tmp_path / "calm"
    folder.mkdir()
    for s in embedded_scenarios(2, 0):
        s.log.to_csv(folder / f"{s.name}.csv", index=False)
    sets = ev.data_sets([], 20, 100, [folder])
    assert list(sets) == ["calm"] and sets["calm"][1] == ["embedded_seed0000", "embedded_seed0001"]
    (tmp_path / "empty").mkdir()
    (tmp_path / "other" / "calm").mkdir(parents=True)
    (folder / "embedded_seed0000.csv").replace(tmp_path / "other" / "calm" / "a.csv")
    for bad, said in (([tmp_path / "missing"], "not a folder"), ([tmp_path / "empty"], "no log files"),
                      ([folder, tmp_path / "other" / "calm"], "two folders named 'calm'")):
        with pytest.raises(SystemExit) as exc:
            ev.main(["--out", str(tmp_path / "out"), "--logs", *map(str, bad), "--only", "default"])
        assert exc.value.code == 2 and "--logs: " in (err := capsys.readouterr().err) and said in err, err
    assert not (tmp_path / "out").exists()
