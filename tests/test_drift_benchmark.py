"""The drift benchmark on a tiny folder of physics-made logs (seconds)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hybridship.cli import main
from hybridship.evaluation import metrics
from hybridship.evaluation.drift import ratio_markdown, run_drift_benchmark
from hybridship.logs.io import write_log
from hybridship.physics.model import DynamicModel
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=3, max_epochs=40, patience=10, seed=0)


@pytest.fixture(scope="module")
def tiny_folder(tmp_path_factory):
    model = DynamicModel("gunnerus")
    folder = tmp_path_factory.mktemp("logs")
    for seed in (1, 2):
        write_log(physics_log(model, seed=seed), folder / f"physics_{seed}.csv")
    return folder


def test_tables_have_the_papers_layout_and_physics_is_exact_on_its_own_logs(tiny_folder, tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "trajectories.png").write_text("an earlier run's figure")
    (tmp_path / "out" / "tables.md").write_text("Drift benchmark. An earlier run's tables\n")
    res = run_drift_benchmark(tiny_folder, None, tmp_path / "out", ensemble_config=TINY, plots=False,
                              calibration_scenarios=1,
                              progress=False)
    errors = pd.read_csv(tmp_path / "out" / "errors.csv")
    assert not (tmp_path / "out" / "trajectories.png").exists()  # not beside tables it did not come from
    assert list(errors.columns) == ["model", "state", "window", "horizon_s", "mae"]
    assert set(errors.model) == {"hybrid", "hybrid_nets_unguarded", "hybrid_mean_bias", "dynamic", "dead_reckoning", "data_only"}
    assert set(errors.state) == {"north_m", "east_m", "yaw_deg"}
    assert set(errors.window) == {5, 20} and set(errors.horizon_s) == {15, 30, 45, 60}
    assert len(errors) == 6 * 3 * 2 * 4 and np.isfinite(errors.mae).all()
    cov = pd.read_csv(tmp_path / "out" / "coverage.csv")
    assert list(cov.columns) == ["model", "horizon_s", "sigma", "coverage"]
    assert {"hybrid", "hybrid_nets_unguarded", "data_only"} <= set(cov.model)
    assert cov.coverage.between(0, 1).all()
    ci = pd.read_csv(tmp_path / "out" / "coverage_intervals.csv")
    assert list(ci.columns) == ["model", "horizon_s", "sigma", "coverage", "low", "high", "n_failures"]
    two = cov[cov.sigma == 2].set_index(["model", "horizon_s"]).coverage
    ci = ci.set_index(["model", "horizon_s"])
    np.testing.assert_allclose(ci.coverage, two.loc[ci.index], atol=1e-6)
    assert set(ci.index.get_level_values(0)) >= {"hybrid", "data_only"}
    hc = pd.read_csv(tmp_path / "out" / "coverage_heading.csv")
    assert list(hc.columns) == ["model", "horizon_s", "sigma", "coverage", "low", "high", "n_failures"]
    assert set(hc.sigma) == {1.0, 2.0} and hc.coverage.between(0, 1).all()
    h = hc.set_index(["model", "horizon_s", "sigma"]).coverage
    assert (h.xs(2.0, level="sigma") >= h.xs(1.0, level="sigma")).all()      # a wider band covers at least as much
    dyn = errors[errors.model == "dynamic"]
    # the log was made by the same model: only the 3-s start average separates them
    assert dyn[dyn.state != "yaw_deg"].mae.max() < 0.15, dyn
    assert dyn[dyn.state == "yaw_deg"].mae.max() < 0.3, dyn
    dr = errors[errors.model == "dead_reckoning"]
    pos = ["north_m", "east_m"]
    at60 = lambda df: df[(df.horizon_s == 60) & df.state.isin(pos)].mae.to_numpy()  # noqa: E731
    assert np.all(at60(dyn) < 0.25 * at60(dr)), (at60(dyn), at60(dr))
    table = (tmp_path / "out" / "tables.md").read_text()
    assert "### Table 2: mean absolute error (first 5 / first 20 intervals)" in table
    assert "| hybrid_nets_unguarded | north_m |" in table and "/" in table.split("| hybrid | north_m |")[1].split("\n")[0]
    assert res.table2.shape == (18, 4)
    assert ratio_markdown(metrics.pooled_ratio_table(errors, "hybrid")) in table      # the targets' form, printed
    # per log: the same cells for each failure, whose mean over the logs is the pooled cell
    # (every log has the same number of starts)
    per = pd.read_csv(tmp_path / "out" / "errors_per_log.csv")
    assert list(per.columns) == ["model", "log", "state", "window", "horizon_s", "mae"]
    assert set(per.log) == {"physics_1.csv", "physics_2.csv"} and len(per) == 2 * len(errors)
    pooled = per.groupby(["model", "state", "window", "horizon_s"]).mae.mean()
    np.testing.assert_allclose(pooled.loc[errors.set_index(["model", "state", "window", "horizon_s"]).index],
                               errors.mae, rtol=1e-5)   # the csv keeps 6 digits
    assert per.groupby(["model", "state", "window", "horizon_s"]).mae.nunique().max() == 2   # logs differ
    section = table.split("### Per failure: `hybrid` as a ratio to `dynamic` at 60 s")[1]
    rows = [r for r in section.split("\n") if r.startswith("| physics_")]
    assert len(rows) == 2 and all(r.count("/") == 3 for r in rows), rows
    _check_group_script(tmp_path / "out", per, errors)


def _check_group_script(out, per, errors):
    """benchmarks/drift_groups.py: a group of one log gives that log's ratio, a group of all
    logs the pooled table's; bad groups are refused with a message."""
    from conftest import load_benchmark

    mod = load_benchmark("drift_groups")
    t = mod.group_ratios(per, {"one": ["physics_1*"], "all": ["physics_*"]})
    at = lambda df, m, s, w: float(df[(df.model == m) & (df.state == s) & (df.window == w)  # noqa: E731
                                      & (df.horizon_s == 60)].mae.iloc[0])
    one = per[per.log == "physics_1.csv"]
    for state in ("north_m", "yaw_deg"):
        np.testing.assert_allclose(t.loc[("one", state), 20], at(one, "hybrid", state, 20) / at(one, "dynamic", state, 20))
        np.testing.assert_allclose(t.loc[("all", state), 5], at(errors, "hybrid", state, 5) / at(errors, "dynamic", state, 5),
                                   rtol=1e-5)
    assert mod.main([str(out), "--group", "one=physics_1*", "--group", "all=*", "--out", str(out / "g.md")]) == 0
    assert "| one | 1 |" in (out / "g.md").read_text()
    above = mod.ratios_above_one(per, {"one": ["physics_1*"]})["one"]
    ratios = [at(one, "hybrid", s, w) / at(one, "dynamic", s, w) for s in ("north_m", "east_m", "yaw_deg")
              for w in (5, 20)]
    assert above == (sum(x > 1 for x in ratios), 6)
    assert f"| {above[0]} of 6 |" in (out / "g.md").read_text()
    assert mod.main([str(out), "--group", "none=calm_*"]) == 2
    assert mod.main([str(out), "--group", "nameonly"]) == 2
    assert mod.main([str(out), "--group", "a=physics_1*", "--group", "a=physics_2*"]) == 2
    for kw, argv, field in (({"horizon_s": 50.0}, ["--horizon-s", "50"], "--horizon-s 50"),
                            ({"model": "nope"}, ["--model", "nope"], "--model 'nope'"),
                            ({"reference": "nope"}, ["--reference", "nope"], "--reference 'nope'")):
        with pytest.raises(ValueError, match=field):
            mod.group_ratios(per, {"all": ["*"]}, **kw)
        assert mod.main([str(out), "--group", "all=*", *argv]) == 2
    # spaces after the commas of a pattern list are not part of the patterns
    t2 = mod.group_ratios(per, {"both": [q.strip() for q in "physics_1*, physics_2*".split(",")]})
    np.testing.assert_allclose(t2[20].to_numpy(), t.loc["all", 20].to_numpy())


def test_logs_of_one_name_stay_apart_and_one_log_has_no_per_failure_table(tmp_path):
    """Two files of one name in two folders are two failures in the per-log outputs, not
    one averaged; with a single test log the per-failure table says why it is missing."""
    model = DynamicModel("gunnerus")
    paths = []
    for seed in (1, 2):
        (tmp_path / f"f{seed}").mkdir()
        paths.append(tmp_path / f"f{seed}" / "same.csv")
        write_log(physics_log(model, seed=seed), paths[-1])
    tiny = EnsembleConfig(n_members=2, max_epochs=5, patience=5, seed=0)
    run_drift_benchmark(paths, None, tmp_path / "two", ensemble_config=tiny, plots=False, progress=False,
                        calibration_scenarios=0)
    per = pd.read_csv(tmp_path / "two" / "errors_per_log.csv")
    assert sorted(per.log.unique()) == ["same.csv#0", "same.csv#1"]
    assert "| same.csv#1 |" in (tmp_path / "two" / "tables.md").read_text()
    run_drift_benchmark(paths[:1], None, tmp_path / "one", ensemble_config=tiny, plots=False, progress=False,
                        calibration_scenarios=0)
    one = (tmp_path / "one" / "tables.md").read_text()
    assert "No per-failure table" in one
    # one failure has no interval over the failures: said so, not "[nan, nan]"
    assert "nan" not in one and "[n/a]" in one
    # fewer than 20 forecasts after a failure: one window, and Table 2's title says which
    run_drift_benchmark(paths, None, tmp_path / "short", ensemble_config=tiny, plots=False, progress=False,
                        calibration_scenarios=0, n_intervals=10)
    short = (tmp_path / "short" / "tables.md").read_text()
    assert "### Table 2: mean absolute error (first 5 intervals)" in short and "first 20" not in short
    # in the paper's layout, one two-decimal cell per horizon (it was the long table, with its
    # index and every digit)
    assert "| model | state | 15 s | 30 s | 45 s | 60 s |" in short and "| index |" not in short


def test_benchmark_is_deterministic_and_the_cli_reports_bad_folders(tiny_folder, tmp_path, capsys):
    a = run_drift_benchmark(tiny_folder, None, tmp_path / "a", ensemble_config=TINY, plots=False, progress=False,
                            calibration_scenarios=0)
    b = run_drift_benchmark(tiny_folder, None, tmp_path / "b", ensemble_config=TINY, plots=False, progress=False,
                            calibration_scenarios=0)
    pd.testing.assert_frame_equal(a.errors, b.errors)
    assert main(["benchmark", "drift", "--train", str(tmp_path / "missing"), "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("hybridship benchmark drift: error: --train") and "not a folder" in err
    assert main(["benchmark"]) == 2


def test_benchmark_never_replaces_or_removes_a_users_file(tiny_folder, tmp_path, capsys):
    """The output folder is checked before any work: a file of the user's under one of the
    benchmark's names (a table, or a figure that --no-plots would remove) is refused by name
    and kept; the benchmark's own earlier files are replaced."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "errors.csv").write_text("mine\n")
    assert main(["benchmark", "drift", "--train", str(tiny_folder), "--out", str(out), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "errors.csv" in err and "was not written by hybridship" in err
    (out / "errors.csv").unlink()
    (out / "trajectories.png").write_bytes(b"my figure")
    with pytest.raises(FileExistsError, match="trajectories.png.*removed"):
        run_drift_benchmark(tiny_folder, None, out, ensemble_config=TINY, plots=False, progress=False,
                            calibration_scenarios=0)
    assert (out / "trajectories.png").read_bytes() == b"my figure" and not (out / "errors.csv").exists()
    (out / "trajectories.png").unlink()
    for _ in range(2):      # its own files, recorded, are replaced
        run_drift_benchmark(tiny_folder, None, out, ensemble_config=TINY, plots=False, progress=False,
                            calibration_scenarios=0)
    assert (out / "tables.md").read_text().startswith("Drift benchmark")


def test_a_run_interrupted_before_its_last_file_leaves_files_a_rerun_replaces(tiny_folder, tmp_path, monkeypatch):
    """Each file is recorded as the benchmark's as it is written: the record was made after the
    last file only, and a run interrupted between (Ctrl-C while writing the tables) left its
    CSV tables unrecorded, so the rerun refused them as a user's files."""
    from hybridship.evaluation import drift
    from hybridship.evaluation.drift import check_output_folder

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    out = tmp_path / "out"
    with monkeypatch.context() as m:
        m.setattr(drift, "_markdown", interrupted)
        with pytest.raises(KeyboardInterrupt):
            run_drift_benchmark(tiny_folder, None, out, ensemble_config=TINY, plots=False, progress=False,
                                calibration_scenarios=0)
    assert (out / "errors.csv").is_file() and not (out / "tables.md").exists()
    check_output_folder(out, plots=False)       # the interrupted run's files are replaced, not refused
    run_drift_benchmark(tiny_folder, None, out, ensemble_config=TINY, plots=False, progress=False,
                        calibration_scenarios=0)
    assert (out / "tables.md").read_text().startswith("Drift benchmark")


def test_a_failure_is_never_scored_with_a_spread_calibrated_on_it(tmp_path):
    """Test logs that are the training logs: with enough failures each log's spread after the
    failure is calibrated on the other logs' failures (leave one out); with too few, on
    simulated DP losses (or raw), never on the fit's calibration that saw the scored drift."""
    from hybridship.evaluation.drift import _calibrate_after_stop
    from hybridship.predictors import HybridPredictor, as_log_arrays
    from hybridship.predictors.hybrid import after_stop_scales

    model = DynamicModel("gunnerus")
    logs = [as_log_arrays(physics_log(model, duration_s=900, t_shutdown_s=700, seed=s, current=(0.2, 1.0 + s),
                                      tau_ext_N=(2000.0, 1000.0, 0.0)), model.vessel) for s in range(4)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY, drift_hull=False).fit(logs)
    assert hp.training_info["calibration"]["after_stop"]["n_logs"] == 4
    _, per_log = _calibrate_after_stop(hp, logs, True, 0, 0, 20, 60.0, lambda m: None)
    errors = hp.after_stop_errors(logs)
    for k in range(4):
        expect = after_stop_scales(errors[:k] + errors[k + 1:], hp.calibration_config)
        np.testing.assert_allclose(per_log[k]["position"].scale, expect["position"].scale)
        # log k's own errors change the scale: it is left out
        with_k = after_stop_scales(errors, hp.calibration_config)
        assert not np.allclose(per_log[k]["position"].scale, with_k["position"].scale)
    # separate test logs: the fit's own calibration stands
    _, none = _calibrate_after_stop(hp, logs[:1], False, 0, 0, 20, 60.0, lambda m: None)
    assert none is None and "after_stop" in hp.calibration
    # three test logs leave two for each: too few, and no simulated losses asked for -> raw
    hp3 = HybridPredictor(model.vessel, ensemble_config=TINY, drift_hull=False).fit(logs[:3])
    _, none = _calibrate_after_stop(hp3, logs[:3], True, 0, 0, 20, 60.0, lambda m: None)
    assert none is None and "after_stop" not in hp3.calibration


def test_ratio_table_keeps_log_order_and_marks_ratios_without_a_reference():
    """The per-failure ratio: hybrid / dynamic per log and state at the longest horizon, logs
    in their order; a zero reference error gives n/a, not a number or a silent inf."""
    from hybridship.evaluation.drift import _per_log_markdown, ratio_cells, ratio_table

    rows = []
    for log, (hyb, dyn) in {"b_log": (1.0, 2.0), "a_log": (3.0, 0.0)}.items():
        for state in ("north_m", "east_m", "yaw_deg"):
            for window in (5, 20):
                for h, scale in ((30.0, 0.5), (60.0, 1.0)):
                    # the ratio differs by window (x 1.5 over 20 intervals) and horizon (x 4 at
                    # 30 s): a table of the wrong horizon, or with its windows swapped, shows
                    worse = (1.5 if window == 20 else 1.0) * (4.0 if h == 30.0 else 1.0)
                    rows += [dict(model="hybrid", log=log, state=state, window=window, horizon_s=h,
                                  mae=hyb * scale * worse),
                             dict(model="dynamic", log=log, state=state, window=window, horizon_s=h, mae=dyn * scale)]
    per = pd.DataFrame(rows)
    r = ratio_table(per)
    assert list(dict.fromkeys(r.index.get_level_values("log"))) == ["b_log", "a_log"]
    assert list(r.columns) == [5, 20]
    np.testing.assert_allclose(r.loc[("b_log", "yaw_deg")].to_numpy(), [0.5, 0.75])      # the longest: 60 s
    np.testing.assert_allclose(ratio_table(per, horizon_s=30.0).loc[("b_log", "yaw_deg")].to_numpy(), [2.0, 3.0])
    assert np.isinf(r.loc[("a_log", "north_m")]).all()
    cells = ratio_cells(r)
    assert cells.loc["b_log", "east_m"] == "0.50/0.75" and cells.loc["a_log", "east_m"] == "n/a"
    assert ratio_cells(r[[5]]).loc["b_log", "north_m"] == "0.50"          # one window: one number
    md = _per_log_markdown(per)
    assert "(0 of 6 log/state/window ratios; 6 without a ratio (n/a)" in md


def test_ratio_table_names_a_horizon_or_model_the_table_does_not_have():
    """A horizon the table lacks failed as a pandas KeyError naming the model ("'hybrid'")."""
    from hybridship.evaluation.drift import ratio_table

    per = pd.DataFrame([dict(model=m, log="a", state=st, window=w, horizon_s=h, mae=1.0)
                        for m in ("hybrid", "dynamic") for st in ("north_m", "east_m", "yaw_deg")
                        for w in (5, 20) for h in (30.0, 60.0)])
    assert ratio_table(per, horizon_s=30).shape == (3, 2)
    with pytest.raises(ValueError, match=r"^horizon_s: 45\.0 s is not in the table; it has 30, 60 s"):
        ratio_table(per, horizon_s=45.0)
    with pytest.raises(ValueError, match=r"^model: 'hybrdi' is not in the table; it has \['hybrid', 'dynamic'\]"):
        ratio_table(per, model="hybrdi")
    with pytest.raises(ValueError, match=r"^reference: 'physics' is not in the table"):
        ratio_table(per, reference="physics")


def test_too_few_calibration_forecasts_are_refused_with_the_counts():
    from hybridship.evaluation.drift import _check_calibration_count

    _check_calibration_count(6, 4, "calibration_scenarios", "advice")          # 24 per lead: enough
    with pytest.raises(ValueError, match=r"n_intervals: 3 forecasts after each of 6 failures .* give 18 per lead"
                                         r".* to calibrate \(more logs\)"):
        _check_calibration_count(6, 3, "the other logs' failures", "more logs")
    # the limit is the calibration's own: the heading's scale fits on 20 forecasts per lead (one
    # error each) and not on 19, so 5 x 4 pass the check and 1 x 19 do not
    from hybridship.residual.calibration import fit_spread_scale

    err, lead = np.abs(np.random.default_rng(0).normal(size=(20, 3))), np.array([15.0, 30.0, 60.0])
    fit_spread_scale(err, np.ones_like(err), lead)
    with pytest.raises(ValueError, match="19 finite samples"):
        fit_spread_scale(err[:19], np.ones((19, 3)), lead)
    _check_calibration_count(5, 4, "calibration_scenarios", "advice")
    with pytest.raises(ValueError, match=r"give 19 per lead; the spread after a failure needs at least 20"):
        _check_calibration_count(1, 19, "calibration_scenarios", "advice")


def test_a_test_log_without_a_failure_is_refused_before_training(tiny_folder, tmp_path, monkeypatch, capsys):
    from hybridship.predictors import HybridPredictor

    def no_training(*args, **kwargs):
        raise AssertionError("trained before the test logs were checked")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    model = DynamicModel("gunnerus")
    test = tmp_path / "test"
    test.mkdir()
    write_log(physics_log(model, duration_s=300.0, t_shutdown_s=None, seed=3), test / "station_keeping.csv")
    with pytest.raises(ValueError, match=r"test: 1 log\(s\) have no DP failure to score \(station_keeping"):
        run_drift_benchmark(tiny_folder, test, tmp_path / "out", progress=False, plots=False)
    assert not (tmp_path / "out").exists()
    # the command line names its option (it said "test:"), as for other input the logs reveal
    assert main(["benchmark", "drift", "--train", str(tiny_folder), "--test", str(test), "--out",
                 str(tmp_path / "out"), "--no-plots"]) == 2
    assert capsys.readouterr().err.startswith("hybridship benchmark drift: error: --test: 1 log(s) have no DP failure")


def test_too_few_calibration_forecasts_on_the_training_logs_drifts_are_refused_before_training(tiny_folder, tmp_path,
                                                                                              monkeypatch, capsys):
    """With the test logs the training logs, 3 starts after each of 6 simulated DP losses (18
    per lead, 20 needed) were refused only after both ensembles were trained, and the
    output folder was left behind empty; the counts are known before, and refused there."""
    from hybridship.predictors import HybridPredictor

    def no_training(*args, **kwargs):
        raise AssertionError("trained before the calibration's count was checked")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    with pytest.raises(ValueError, match=r"^n_intervals: 3 forecasts after each of 6 failures \(calibration_scenarios\) "
                                         r"give 18 per lead"):
        run_drift_benchmark(tiny_folder, None, tmp_path / "out", n_intervals=3, progress=False, plots=False)
    assert not (tmp_path / "out").exists()
    # the command line names its options (it said "n_intervals", "calibration_scenarios", exit 1)
    assert main(["benchmark", "drift", "--train", str(tiny_folder), "--intervals", "3", "--out",
                 str(tmp_path / "out"), "--no-plots"]) == 2
    assert capsys.readouterr().err.startswith("hybridship benchmark drift: error: --intervals: 3 forecasts after each "
                                              "of 6 failures (--calibration-scenarios) give 18 per lead")
    with pytest.raises(AssertionError, match="trained before"):     # 7 starts: 42 per lead, enough
        run_drift_benchmark(tiny_folder, None, tmp_path / "out", n_intervals=7, progress=False, plots=False)


@pytest.mark.parametrize("kw, message", [
    ({"n_intervals": 0}, r"^n_intervals: expected a whole number >= 1, got 0"),
    ({"n_intervals": 2.5}, r"^n_intervals: expected a whole number >= 1, got 2\.5"),
    ({"horizon_s": 10.0}, r"^horizon_s: must be >= 15, got 10\.0"),
    ({"horizon_s": float("nan")}, r"^horizon_s: must be finite"),
    ({"calibration_scenarios": 1.5}, r"^calibration_scenarios: expected a whole number >= 0, got 1\.5"),
])
def test_counts_and_the_forecast_length_are_refused_before_training(tiny_folder, tmp_path, monkeypatch, kw, message):
    """No start after a failure, a fraction of one, a forecast shorter than the table's 15 s
    (no cell) or NaN failed after the training inside numpy or pandas ("KeyError: ['model',
    ...] not in index"); a fraction of a calibration scenario was truncated without a word."""
    from hybridship.predictors import HybridPredictor

    def no_training(*args, **kwargs):
        raise AssertionError("trained before the arguments were checked")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    with pytest.raises(ValueError, match=message):
        run_drift_benchmark(tiny_folder, None, tmp_path / "out", progress=False, plots=False, **kw)
    assert not (tmp_path / "out").exists()


def test_every_row_on_the_training_logs_own_drifts_is_refused_before_training(tiny_folder, tmp_path, monkeypatch,
                                                                              capsys):
    """Training on every row (``dp_only=False``, ``--all-rows``) puts the drift after each failure
    into the nets' rows, the wind forecast's and the held-back calibration's: scored on those
    same drifts (no ``--test``, the same logs again, or the embedded scenarios), it is refused
    before any training; with other test logs it runs as before."""
    from hybridship.predictors import DataOnlyPredictor, HybridPredictor

    def no_training(*args, **kwargs):
        raise AssertionError("trained on the drifts it would score")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    monkeypatch.setattr(DataOnlyPredictor, "fit", no_training)
    model = DynamicModel("gunnerus")
    dfs = [physics_log(model, duration_s=300, t_shutdown_s=200, seed=s) for s in (1, 2)]
    for train, test in ((tiny_folder, None), (tiny_folder, tiny_folder), (dfs, list(dfs))):
        with pytest.raises(ValueError, match=r"^test: the test logs are the training logs, and training on every "
                                             r"row \(dp_only=False, --all-rows\)"):
            run_drift_benchmark(train, test, tmp_path / "out", dp_only=False, progress=False, plots=False)
    assert not (tmp_path / "out").exists()
    assert main(["benchmark", "drift", "--train", str(tiny_folder), "--all-rows", "--out", str(tmp_path / "out"),
                 "--no-plots"]) == 2
    assert capsys.readouterr().err.startswith("hybridship benchmark drift: error: --test: the test logs are the "
                                              "training logs")
    # other test logs: trained (on every row of the training logs) as before
    with pytest.raises(AssertionError, match="trained on the drifts"):
        run_drift_benchmark(tiny_folder, dfs[:1], tmp_path / "out", dp_only=False, progress=False, plots=False)


def test_a_yaw_load_chosen_per_failure_is_not_refused_before_training(tiny_folder, tmp_path, monkeypatch):
    """``wave_turned_yaw_load = "auto"`` scored on the training logs' own failures was refused
    before training (fit chose on the scored drifts); the benchmark now chooses it per test log
    on the other failures (tests/test_drift_hull.py), so both runs go on to train."""
    from hybridship.predictors import DataOnlyPredictor, HybridPredictor
    from hybridship.residual.environment import EnvironmentConfig

    def no_training(*args, **kwargs):
        raise AssertionError("trained")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    monkeypatch.setattr(DataOnlyPredictor, "fit", no_training)
    auto = EnvironmentConfig(wave_turned_yaw_load="auto")
    model = DynamicModel("gunnerus")
    other = [physics_log(model, duration_s=300, t_shutdown_s=200, seed=9)]
    for test in (None, other):
        with pytest.raises(AssertionError, match="trained"):
            run_drift_benchmark(tiny_folder, test, tmp_path / "out", environment_config=auto, progress=False,
                                plots=False)


def test_one_log_given_without_a_list_is_refused_naming_the_argument(tiny_folder, tmp_path):
    """A DataFrame was iterated by its column names, each read as a log file ("time_s:
    unsupported file extension"); a LogArrays or a number failed as "... is not iterable"."""
    from hybridship.predictors import as_log_arrays

    model = DynamicModel("gunnerus")
    df = physics_log(model, duration_s=300, t_shutdown_s=200, seed=1)
    for one in (df, as_log_arrays(df, model.vessel), 3):
        with pytest.raises(TypeError, match=r"^train: expected a folder of logs or a list of logs .* a list of one"):
            run_drift_benchmark(one, None, tmp_path / "out", progress=False, plots=False)
        with pytest.raises(TypeError, match=r"^test: expected a folder of logs or a list of logs"):
            run_drift_benchmark(tiny_folder, one, tmp_path / "out", progress=False, plots=False)
    assert not (tmp_path / "out").exists()


def test_an_empty_list_of_logs_is_refused_naming_the_argument(tiny_folder, tmp_path):
    """train=[] or test=[] failed in max()'s words ("max() arg is an empty sequence"), and
    train=[] beside test logs in fit's ("logs: ...") after the output folder was made."""
    for train, test, field in (([], None, "train"), (tiny_folder, [], "test"),
                               ([], [tiny_folder / "physics_1.csv"], "train")):
        with pytest.raises(ValueError, match=rf"^{field}: expected one or more logs, got an empty list"):
            run_drift_benchmark(train, test, tmp_path / "out", progress=False, plots=False)
    assert not (tmp_path / "out").exists()


def test_log_files_take_any_case_and_skip_hidden_and_summary_files(tmp_path):
    """A folder's logs are found as a single log file is read (extension in any case); the
    sweep's summary and hidden files (macOS ``._`` companions) are not logs."""
    from hybridship.evaluation.drift import log_files

    for name in ("A.CSV", "b.csv.gz", "c.Parquet", "._A.CSV", ".hidden.csv", "scenarios.csv", "notes.txt"):
        (tmp_path / name).write_text("x")
    (tmp_path / "folder.csv").mkdir()
    assert [p.name for p in log_files(tmp_path)] == ["A.CSV", "b.csv.gz", "c.Parquet"]
    with pytest.raises(ValueError, match="no log files"):
        log_files(tmp_path / "folder.csv")


def test_an_out_folder_that_holds_logs_is_refused(tmp_path, capsys):
    """The benchmark's CSV tables in a folder of logs would be read as logs by a later train
    there: refused before any work, naming the log; the folder is left as it was."""
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "run1.csv").write_text("time_s,north_m,east_m,heading_deg\n0,0,0,0\n")
    assert main(["benchmark", "drift", "--no-plots", "--out", str(logs)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "holds logs (run1.csv)" in err
    assert sorted(p.name for p in logs.iterdir()) == ["run1.csv"]


def test_the_tables_horizons_are_found_at_any_rate_and_other_steps_refused_before_training(tiny_folder, tmp_path,
                                                                                         monkeypatch):
    """At 10 Hz the median step is 0.10000000000002274 s: the lead times k * dt missed 15 s
    exactly and the benchmark crashed after training ("tuple.index(x): x not in tuple"); a
    log whose step does not divide the horizons (2 s against 15 s) is refused before training."""
    from hybridship.evaluation.drift import _forecast_after_failures, _test_arrays
    from hybridship.predictors import DeadReckoning, HybridPredictor

    model = DynamicModel("gunnerus")
    fast = physics_log(model, duration_s=240.0, t_shutdown_s=150.0, dt_s=0.1, seed=4)
    fast["time_s"] += 1000.0 / 3.0          # times whose differences are not exactly 0.1 s
    a = _test_arrays([fast], ["fast"], model.vessel, 20, 60.0, (15.0, 30.0, 45.0, 60.0))
    fc, all_h, pick, _ = _forecast_after_failures({"dead_reckoning": (DeadReckoning(model.vessel), {})}, a, 20,
                                                  60.0, (15.0, 30.0, 45.0, 60.0))
    assert [all_h[i] for i in pick] == [15.0, 30.0, 45.0, 60.0] and len(all_h) == 600

    def no_training(*args, **kwargs):
        raise AssertionError("trained before the test logs were checked")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    test = tmp_path / "test"
    test.mkdir()
    write_log(physics_log(model, duration_s=400.0, t_shutdown_s=200.0, dt_s=2.0, seed=3), test / "slow.csv")
    with pytest.raises(ValueError, match=r"test: log slow\.csv has a step of 2 s, and the table's horizons 15, 45 s "
                                         r"are not whole numbers of it"):
        run_drift_benchmark(tiny_folder, test, tmp_path / "out", progress=False, plots=False)
    assert not (tmp_path / "out").exists()


def test_loo_calibrated_spread_gives_one_sigma_coverage_on_the_other_logs():
    from hybridship.evaluation.drift import _loo_calibrated_spread

    rng = np.random.default_rng(1)
    P = np.abs(rng.normal(size=(3, 200, 2, 3)))
    P[0] *= 10.0                                      # one log far worse: it must not set its own scale
    # spreads that differ from forecast to forecast: the errors count in units of their own
    # spread, and each forecast's spread is scaled (a spread of 1 everywhere hid both)
    T, S = np.zeros_like(P), rng.uniform(0.5, 2.0, size=P.shape)
    Scal = _loo_calibrated_spread(P, T, S, 2)
    for i in range(3):
        factor = Scal[i] / S[i]                       # one per horizon: every start and state alike
        np.testing.assert_allclose(factor, np.broadcast_to(factor[:1, :, :1], factor.shape), rtol=1e-12)
        k = factor[0, :, 0]                           # (n_horizons,)
        others = np.delete(P / S, i, axis=0)[..., :2]
        cov = (others <= k[None, None, :, None]).mean(axis=(0, 1, 3))
        np.testing.assert_allclose(cov, 0.6827, atol=0.01)


def test_has_drift_accepts_exactly_enough_drift_as_drift_forecasts_does():
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DynamicPredictor, as_log_arrays
    from hybridship.predictors.after_failure import drift_forecasts, has_drift
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    a = as_log_arrays(physics_log(m, duration_s=1000, t_shutdown_s=800, seed=14), m.vessel)
    h = float(len(a.time_s) - 1 - 800 - 20 + 1)          # leaves exactly 20 starts
    drift_forecasts(DynamicPredictor(m.vessel), a, n_intervals=20, horizons_s=(h,))
    assert has_drift(a, 20, h) and not has_drift(a, 20, h + 1)
    # a horizon between two steps is refused by name, as drift_forecasts refuses it: it was
    # rounded to a whole number of steps here (60.4 s read as 60 s on this 1-Hz log)
    from hybridship.predictors.forecast_setup import HorizonError

    for fn in (lambda: has_drift(a, 20, 60.4),
               lambda: drift_forecasts(DynamicPredictor(m.vessel), a, n_intervals=20, horizons_s=(60.4,))):
        with pytest.raises(HorizonError, match=r"^horizons?_s: 60.4 s is not a whole number of the log's steps"):
            fn()


def test_training_logs_given_again_as_data_are_scored_leave_one_out():
    """Paths name a log, DataFrames and LogArrays do not: the same list of DataFrames as
    ``train`` and ``test`` was taken as other logs (the list is copied), and their failures were
    scored with the spread calibrated on them. Their samples say they are the training logs."""
    from hybridship.evaluation.drift import _benchmark_logs, _same_samples
    from hybridship.predictors import as_log_arrays

    model = DynamicModel("gunnerus")
    dfs = [physics_log(model, duration_s=300, t_shutdown_s=200, seed=s) for s in (1, 2, 3)]
    train, _, test, names = _benchmark_logs(dfs[:2], dfs[:2], 3, 0, lambda m: None)
    assert test is not train                             # what the identity test saw
    arrays = [as_log_arrays(x, model.vessel) for x in dfs]
    assert _same_samples(arrays[:2], arrays[1::-1], ["b", "a"])
    assert not _same_samples(arrays[:2], arrays[2:], ["c"])
    with pytest.raises(ValueError, match=r"test: 1 of the test logs hold the samples of training logs \(b\)"):
        _same_samples(arrays[:2], arrays[1:], ["b", "c"])


def test_the_unguarded_row_keeps_its_raw_spread_after_a_failure():
    """The after-stop scale is fitted on forecasts with the nets off after a failure: the row
    with the nets on after it (the paper's scheme) is not rescaled by it."""
    from hybridship.evaluation.drift import _benchmark_models
    from hybridship.predictors import HybridPredictor, as_log_arrays
    from hybridship.predictors.after_failure import shutdown_index

    model = DynamicModel("gunnerus")
    logs = [as_log_arrays(physics_log(model, duration_s=900, t_shutdown_s=700, seed=s, current=(0.2, 1.0 + s),
                                      tau_ext_N=(2000.0, 1000.0, 0.0)), model.vessel) for s in range(4)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY, drift_hull=False).fit(logs)
    assert "after_stop" in hp.calibration
    pred, kw = _benchmark_models(model.vessel, hp, None)["hybrid_nets_unguarded"]
    starts = logs[0].time_s[shutdown_index(logs[0]) + np.arange(3)]
    row = pred.forecast(logs[0], starts, 30.0, **kw)
    calibrated = hp.forecast(logs[0], starts, 30.0, guard=False, nets_after_stop=True)
    raw = hp.forecast(logs[0], starts, 30.0, guard=False, nets_after_stop=True, calibrated=False)
    np.testing.assert_array_equal(row.eta, calibrated.eta)
    np.testing.assert_array_equal(row.eta_std, raw.eta_std)
    assert not np.allclose(row.eta_std[:, 1:], calibrated.eta_std[:, 1:])


def test_coverage_table_counts_the_raw_and_the_leave_one_out_calibrated_bands():
    """coverage.csv by hand. Two logs of four starts, spread 1 m, north and east errors at the
    two leads the table picks: at the first 0.5 m on log 0 and 0.8 m on log 1 (the raw band
    covers all at 1 and 2 sigma; calibrated on the other log, log 0's spread becomes 0.8 m, which
    covers, and log 1's 0.5 m, which covers its 0.8 m at 2 sigma only: 1/2 and 1), at the last
    0.5 m and 1.5 m (raw: 1/2 and 1; calibrated: 1.5 m covers log 0, 0.5 m leaves out log 1 at both:
    1/2 and 1/2). The lead between them (100 m) is not picked. The data-only model misses by
    10 m everywhere (raw 0, calibrated to 10 m: 1), the others not at all (1). The heading's
    table counts the heading's errors."""
    from hybridship.evaluation.drift import ENSEMBLE_MODELS, _coverage_table, _coverage_tables

    def forecasts(errors_m, heading_rad=0.0):
        """Per log ``(pred, truth, std)`` of four starts whose north/east errors at the three
        leads are ``errors_m[log]``, and the heading's ``heading_rad``."""
        out = []
        for e in errors_m:
            p = np.full((4, 3, 3), heading_rad)
            p[..., :2] = np.asarray(e, float)[None, :, None]
            out.append((p, np.zeros_like(p), np.ones_like(p)))
        return out

    fc = {name: forecasts([[0.0] * 3, [0.0] * 3]) for name in ENSEMBLE_MODELS}
    fc["hybrid"] = forecasts([[0.5, 100.0, 0.5], [0.8, 100.0, 1.5]], heading_rad=1.5)
    fc["data_only"] = forecasts([[10.0] * 3, [10.0] * 3])
    got = _coverage_table(fc, [0, 2], (15, 60), 2).set_index(["model", "horizon_s", "sigma"]).coverage
    want = {("hybrid", 15, 1): 1.0, ("hybrid", 15, 2): 1.0, ("hybrid", 60, 1): 0.5, ("hybrid", 60, 2): 1.0,
            ("hybrid_loo_calibrated", 15, 1): 0.5, ("hybrid_loo_calibrated", 15, 2): 1.0,
            ("hybrid_loo_calibrated", 60, 1): 0.5, ("hybrid_loo_calibrated", 60, 2): 0.5}
    for h in (15, 60):
        for sigma in (1, 2):
            want[("data_only", h, sigma)], want[("data_only_loo_calibrated", h, sigma)] = 0.0, 1.0
            for name in ("hybrid_nets_unguarded", "hybrid_mean_bias"):
                want[(name, h, sigma)] = want[(name + "_loo_calibrated", h, sigma)] = 1.0
    assert sorted(got.index) == sorted(want)
    for key, value in want.items():
        assert got[key] == value, key
    # one log has no other to calibrate on: the raw rows only
    one = _coverage_table({name: f[:1] for name, f in fc.items()}, [0, 2], (15, 60), 1)
    assert set(one.model) == set(ENSEMBLE_MODELS)
    # coverage_heading.csv counts the heading's own errors: the hybrid's miss by 1.5 rad (outside
    # 1 sigma where its position is inside at the first lead, inside 2), the others' not at all
    heading = _coverage_tables(fc, [0, 2], (15, 60), 2, 0)[2].set_index(["model", "horizon_s", "sigma"])
    for name in ENSEMBLE_MODELS:
        for h in (15, 60):
            assert heading.coverage[(name, h, 1.0)] == (0.0 if name == "hybrid" else 1.0), (name, h)
            assert heading.coverage[(name, h, 2.0)] == 1.0 and heading.n_failures[(name, h, 2.0)] == 2


def test_coverage_tables_round_one_coverage_alike():
    """117 of 120 outcomes inside the band is 0.975 as a float just below it: the coverage
    table and the table with the interval print it alike (pandas' round gave 0.98, the
    interval's format 0.97)."""
    from hybridship.evaluation.drift import _coverage_markdown

    cov = pd.DataFrame(dict(model="hybrid", sigma=[1, 2], horizon_s=60.0, coverage=[0.525, 117 / 120]))
    md = _coverage_markdown(cov)
    assert f"{117 / 120:.2f}" == "0.97"                        # the interval table's cell
    assert "| hybrid | 2 | 0.97 |" in md and "| hybrid | 1 | 0.53 |" in md


def _failure_logs(model, seeds, duration_s=600.0, t_shutdown_s=450.0) -> list:
    """Logs with a DP failure followed by ``duration_s - t_shutdown_s`` of drift (150 s: enough
    for 20 starts 60 s ahead and for the later starts' calibration), each in its own current
    and load."""
    return [physics_log(model, duration_s=duration_s, t_shutdown_s=t_shutdown_s, seed=s, current=(0.2, 1.0 + s),
                        tau_ext_N=(2000.0, 1000.0 * (s % 3 - 1), 0.0)) for s in seeds]


def _changed_after(log: pd.DataFrame, t_s: float, seed: int = 0) -> pd.DataFrame:
    """``log`` with every measured column changed after ``t_s`` [s]: positions, heading,
    velocities, commands and wind moved at random, and the DP switched back on."""
    out = log.copy()
    after = out.time_s > t_s
    rng = np.random.default_rng(seed)
    for col in ("north_m", "east_m", "u_m_s", "v_m_s", "r_deg_s", "wind_speed_m_s", "heading_deg", "wind_dir_deg"):
        out.loc[after, col] = out.loc[after, col] + rng.normal(0.0, 3.0, int(after.sum()))
    for col in [c for c in out.columns if c.endswith(("_rpm", "_azimuth_deg"))]:
        out.loc[after, col] = -0.5 * out.loc[after, col]
    out.loc[after, "wind_speed_m_s"] = out.loc[after, "wind_speed_m_s"].abs()
    out.loc[after, ["heading_deg", "wind_dir_deg"]] %= 360.0
    out.loc[after, "dp_active"] = 1
    return out


def test_every_models_forecast_after_a_failure_reads_no_sample_after_its_start():
    """Causality of what the drift benchmark scores: for every model of the table (the hybrid
    with a hull's yaw moment in a drift and its spread calibrated after a failure, unguarded,
    with the mean residual, the physics, dead reckoning and the data-only ensemble), the
    forecast from a start after the failure, the estimator's online update over the drift up
    to it included, is bit for bit the same when every sample after the start changes (the
    DP even back on) and when the log ends at the start."""
    from hybridship.evaluation.drift import _benchmark_models
    from hybridship.predictors import DataOnlyPredictor, HybridPredictor
    from hybridship.residual.drift_hull import munk_coefficient

    model = DynamicModel("gunnerus")
    logs = _failure_logs(model, (1, 2, 3, 4))
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs[:3])
    assert {"after_stop", "after_stop_late"} <= set(hp.calibration)
    hp.drift_yaw_uv_rad_per_m2 = 0.5 * munk_coefficient(hp.model)      # as fit may choose with five failures
    data_only = DataOnlyPredictor(model.vessel, ensemble_config=TINY).fit(logs[:3])
    test = logs[3]
    i0 = int(np.flatnonzero(test.dp_active.to_numpy() == 0)[0])
    for k in (0, 7, 19):                        # the first and the last start the tables score
        t = float(test.time_s[i0 + k])
        changed, cut = _changed_after(test, t, seed=k), test[test.time_s <= t]
        for name, (pred, kw) in _benchmark_models(model.vessel, hp, data_only).items():
            base = pred.forecast(test, [t], 60.0, **kw)
            for other in (changed, cut):
                fc = pred.forecast(other, [t], 60.0, **kw)
                np.testing.assert_array_equal(fc.eta, base.eta, err_msg=f"{name}, start {k}")
                np.testing.assert_array_equal(fc.nu, base.nu, err_msg=f"{name}, start {k}")
                if base.eta_std is not None:
                    np.testing.assert_array_equal(fc.eta_std, base.eta_std, err_msg=f"{name}, start {k}")


def test_a_test_logs_drift_changes_nothing_the_benchmark_learns(tmp_path, monkeypatch):
    """With test logs other than the training logs, what the benchmark learns (the nets, the
    station-keeping and after-failure spread calibrations, the hull's yaw coefficient, the
    wind forecast) comes from the training logs alone: the test log's drift changed, every
    model forecasts a probe log exactly as before, while the scored errors move. Changing a
    training log's drift changes the probe (the after-failure calibration learns from it)."""
    from hybridship.evaluation import drift

    model = DynamicModel("gunnerus")
    # five failures (fit chooses the hull's yaw moment too), with shorter drifts (a shorter choice)
    train = _failure_logs(model, (1, 2, 3, 4, 5), 560.0, 430.0)
    test, probe = _failure_logs(model, (6, 7), 560.0, 430.0)
    i0 = int(np.flatnonzero(test.dp_active.to_numpy() == 0)[0])
    starts = probe.time_s.to_numpy()[[300, 429, 435, 450]]        # two on station, two in the drift
    seen, original = [], drift._forecast_after_failures

    def probed(predictors, *args, **kwargs):
        hybrid = predictors["hybrid"][0]
        seen.append({"coefficient": hybrid.drift_yaw_uv_rad_per_m2, "per_log": args[-2:],
                     "hull": hybrid.training_info["drift_hull"],
                     "wind": hybrid.wind_forecast, **{name: pred.forecast(probe, starts, 60.0, **kw)
                                                      for name, (pred, kw) in predictors.items()}})
        return original(predictors, *args, **kwargs)

    monkeypatch.setattr(drift, "_forecast_after_failures", probed)

    def run(train_logs, test_log, out):
        return pd.read_csv(run_drift_benchmark(train_logs, [test_log], tmp_path / out, ensemble_config=TINY,
                                               plots=False, progress=False, calibration_scenarios=0
                                               ).outputs["errors.csv"])

    errors = run(train, test, "a")
    changed = test.copy()
    after = changed.time_s > changed.time_s[i0]
    changed.loc[after, ["north_m", "east_m"]] += np.outer(np.arange(int(after.sum())), [0.05, -0.03])
    assert not errors.equals(run(train, changed, "b"))
    first, second = seen
    assert first["per_log"] == second["per_log"] == (None, None)       # no per-log choice: fit's stands
    for key, value in first.items():
        if hasattr(value, "eta"):
            for field in ("eta", "nu", "eta_std"):
                np.testing.assert_array_equal(getattr(value, field), getattr(second[key], field), err_msg=key)
        else:
            assert value == second[key], key
    # the probe sees what is learned from failures: a training log's drift changed moves it
    moved = list(train)
    moved[0] = moved[0].copy()
    after = moved[0].time_s > moved[0].time_s[i0]
    moved[0].loc[after, ["north_m", "east_m"]] += np.outer(np.arange(int(after.sum())), [0.05, -0.03])
    run(moved, test, "c")
    assert not np.array_equal(seen[2]["hybrid"].eta_std, first["hybrid"].eta_std)
    np.testing.assert_array_equal(seen[2]["hybrid"].eta[:2], first["hybrid"].eta[:2])     # on station: no


def test_test_logs_at_two_rates_are_scored_at_the_coarser_steps_or_refused_before_training():
    """The lead times stepped at the first test log's step: a 0.5-s log before a 1-s one asked
    the 1-s log for a 0.5-s lead, and the benchmark ended after the training in "horizons_s: 0.5
    s is shorter than one step of the log". They step at the coarsest log's step, in either
    order; a step that does not divide it (0.6 s beside 1 s) is refused, naming the log."""
    from hybridship.evaluation.drift import _forecast_after_failures, _test_arrays
    from hybridship.predictors import DeadReckoning

    model = DynamicModel("gunnerus")
    horizons = (15.0, 30.0, 45.0, 60.0)
    logs = {dt: physics_log(model, duration_s=300.0, t_shutdown_s=150.0, dt_s=dt, seed=4) for dt in (0.5, 0.6, 1.0)}
    for order in ((0.5, 1.0), (1.0, 0.5)):
        a = _test_arrays([logs[dt] for dt in order], ["a", "b"], model.vessel, 20, 60.0, horizons)
        fc, all_h, pick, _ = _forecast_after_failures({"dead_reckoning": (DeadReckoning(model.vessel), {})}, a, 20,
                                                      60.0, horizons)
        assert all_h == tuple(float(k) for k in range(1, 61)) and [all_h[i] for i in pick] == list(horizons)
        assert all(p.shape == (20, 60, 3) for p, _, _ in fc["dead_reckoning"])
    with pytest.raises(ValueError, match=r"test: log fine has a step of 0\.6 s, which does not divide the coarsest "
                                         r"test log's step of 1 s"):
        _test_arrays([logs[0.6], logs[1.0]], ["fine", "coarse"], model.vessel, 20, 60.0, horizons)


@pytest.mark.parametrize("flag", ["plots", "progress"])
def test_a_flag_given_as_text_is_refused_before_any_work(tiny_folder, tmp_path, monkeypatch, flag):
    """plots="no" is truthy: the whole benchmark ran and wrote the figures it was asked not to;
    now a TypeError naming the flag, before the output folder is made or anything is trained."""
    from hybridship.predictors import HybridPredictor

    def no_training(*args, **kwargs):
        raise AssertionError("trained before the flags were checked")

    monkeypatch.setattr(HybridPredictor, "fit", no_training)
    kw = {"plots": False, "progress": False, flag: "no"}
    with pytest.raises(TypeError, match=rf"^{flag}: expected True or False, got 'no'"):
        run_drift_benchmark(tiny_folder, None, tmp_path / "out", **kw)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("n, message", [(0, r"^n_scenarios: expected a whole number >= 1, got 0"),
                                        (1.5, r"^n_scenarios: expected a whole number >= 1, got 1\.5"),
                                        (21, r"^n_scenarios: expected a whole number in 1\.\.20")])
def test_a_bad_number_of_embedded_scenarios_is_refused_by_its_name(tmp_path, n, message):
    """The simulator's own check named its argument ``n``, which run_drift_benchmark has not."""
    with pytest.raises(ValueError, match=message):
        run_drift_benchmark(out_dir=tmp_path / "out", n_scenarios=n, progress=False, plots=False)
    assert not (tmp_path / "out").exists()


def test_an_out_dir_that_is_not_a_path_is_refused_by_name():
    """out_dir=None ended in pathlib's 'expected str, bytes or os.PathLike object, not NoneType'."""
    with pytest.raises(TypeError, match=r"^out_dir: expected a file path \(str or os.PathLike\), got NoneType"):
        run_drift_benchmark(out_dir=None, progress=False, plots=False)


def test_the_module_docstring_names_every_output_file():
    """``drift_hull.csv`` was written by every run but missing from the list of outputs."""
    from hybridship.evaluation import drift

    assert [f for f in drift.TABLE_FILES + drift.FIGURE_FILES if f"``{f}``" not in drift.__doc__] == []


@pytest.mark.parametrize("members, message", [(0, r"^members: expected a whole number >= 1, got 0"),
                                              (2.5, r"^members: expected a whole number >= 1, got 2\.5")])
def test_members_is_refused_by_its_name_before_any_log_is_read(tmp_path, monkeypatch, members, message):
    """members=0 was refused as 'n_members: must be >= 1 [EnsembleConfig]', an argument
    run_drift_benchmark does not have, after the logs were read or the scenarios simulated."""
    from hybridship.evaluation import drift

    def no_logs(*args, **kwargs):
        raise AssertionError("logs read before members was checked")

    monkeypatch.setattr(drift, "_benchmark_logs", no_logs)
    with pytest.raises(ValueError, match=message):
        run_drift_benchmark(out_dir=tmp_path / "out", members=members, progress=False, plots=False)
    assert not (tmp_path / "out").exists()


def test_a_horizon_that_is_not_whole_steps_of_a_test_log_is_refused_before_training():
    """The benchmark counted its horizon's steps with a rounding of its own: 60.4 s on a 1-s log
    was forecast, scored and plotted to 60 s without a word (the failures with enough drift
    and those the hull's yaw moment is chosen on picked by that rounding too). A horizon that is
    not a whole number of a test log's steps is now refused before any training, as a forecast
    refuses it (naming horizon_s and the log); 60.2 s, within the forecast's tolerance, is 60 s."""
    from hybridship.evaluation.drift import _forecast_after_failures, _test_arrays
    from hybridship.forecast_inputs.horizon import HorizonError
    from hybridship.predictors import DeadReckoning

    model = DynamicModel("gunnerus")
    horizons = (15.0, 30.0, 45.0, 60.0)
    logs = [physics_log(model, duration_s=300.0, t_shutdown_s=150.0, dt_s=dt, seed=4) for dt in (0.1, 1.0)]
    with pytest.raises(HorizonError, match=r"^horizon_s: 60.4 s is not a whole number of the log's steps \(1 s\); "
                                           r"the nearest is 60 s, in test log coarse$"):
        _test_arrays(logs, ["fine", "coarse"], model.vessel, 20, 60.4, horizons)
    a = _test_arrays(logs, ["fine", "coarse"], model.vessel, 20, 60.2, horizons)
    _, all_h, _, _ = _forecast_after_failures({"dead_reckoning": (DeadReckoning(model.vessel), {})}, a, 20, 60.2,
                                              horizons)
    assert all_h == tuple(float(k) for k in range(1, 61))
