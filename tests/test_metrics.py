"""The drift tables' metrics (hybridship.evaluation.metrics) on inputs whose answer is known
by hand: absolute errors with the heading wrapped, the first-5/first-20 means, the paper's
cell layout, and the spread's coverage."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hybridship.evaluation import metrics

def test_absolute_errors_are_absolute_and_yaw_is_wrapped_degrees():
    pred = np.array([[[1.0, -2.0, np.pi - 0.01]]])
    truth = np.array([[[0.0, 0.0, -np.pi + 0.01]]])
    np.testing.assert_allclose(metrics.absolute_errors(pred, truth)[0, 0], [1.0, 2.0, np.degrees(0.02)])


def test_error_table_cells_are_means_over_logs_and_the_first_w_intervals():
    k = np.arange(20.0) ** 2                            # error of interval k
    E = np.broadcast_to(k[:, None, None], (20, 1, 3)).copy()
    long = metrics.error_table({"m": [E, 2 * E]}, horizons_s=(15,))
    mae = long.set_index(["window", "state"]).mae
    np.testing.assert_allclose(mae.loc[(5, "north_m")], 1.5 * k[:5].mean())        # 9.0
    np.testing.assert_allclose(mae.loc[(20, "yaw_deg")], 1.5 * k.mean())


@pytest.mark.parametrize("pred_shape, truth_shape", [((20, 4, 3), (4, 3)), ((20, 1, 3), (1, 4, 3)),
                                                      ((20, 4, 2), (20, 4, 2))])
def test_absolute_errors_refuse_shapes_that_differ_or_lack_the_three_states(pred_shape, truth_shape):
    """Forecasts of 20 starts against the truth of one broadcast to 20 rows of errors, each
    against the same measurement; two columns failed on the heading's index, unnamed."""
    with pytest.raises(ValueError, match=r"pred, truth: expected equal shapes \(\.\.\., 3\)"):
        metrics.absolute_errors(np.zeros(pred_shape), np.ones(truth_shape))


@pytest.mark.parametrize("per_log, windows, message", [
    ([np.ones((20, 4, 3))], (), r"windows: expected one or more whole numbers >= 1 of intervals, got \(\)"),
    ([np.ones((20, 4, 3)), np.ones((5, 4, 3))], (5,), r"errors\['m'\]: expected one or more arrays of one shape "
                                                      r"\(n_intervals, n_horizons, 3\), got shapes \[\(5, 4, 3\), \(20"),
    ([], (5,), r"errors\['m'\]: expected one or more arrays"),
    ([np.ones((20, 4, 2))], (5,), r"errors\['m'\]: expected one or more arrays"),
])
def test_error_table_names_the_windows_or_the_errors_it_cannot_tabulate(per_log, windows, message):
    """No window, logs of different lengths, no log or errors without three states failed in
    numpy's or Python's words ("max() arg is an empty sequence", "all input arrays must have
    the same shape", "need at least one array to stack", an index out of bounds)."""
    with pytest.raises(ValueError, match=message):
        metrics.error_table({"m": per_log}, horizons_s=(15, 30, 45, 60), windows=windows)


def test_absolute_errors_of_whole_numbers_keep_the_fraction_of_a_degree():
    """Positions logged as whole metres are integer arrays: the heading error of 1 rad is
    57.2958 deg, not the 57 an integer result array truncated it to."""
    pred = np.array([[[3, 4, 1]]])
    truth = np.array([[[0, 0, 0]]])
    np.testing.assert_allclose(metrics.absolute_errors(pred, truth)[0, 0], [3.0, 4.0, 180.0 / np.pi])


def test_error_table_refuses_horizons_or_windows_that_do_not_fit_the_errors():
    """Errors at six lead times labelled with the four default horizons were written as the
    first four of them under the wrong lead times; a window of 0 gave NaN cells."""
    import pytest

    E = np.ones((20, 6, 3))
    with pytest.raises(ValueError, match=r"horizons_s: 4 lead times .* errors\['m'\] has 6"):
        metrics.error_table({"m": [E]})
    with pytest.raises(ValueError, match=r"horizons_s: 7 lead times"):
        metrics.error_table({"m": [E]}, horizons_s=tuple(range(10, 80, 10)))      # before: IndexError
    with pytest.raises(ValueError, match="windows: expected one or more whole numbers >= 1"):
        metrics.error_table({"m": [E]}, horizons_s=tuple(range(10, 70, 10)), windows=(0, 20))
    with pytest.raises(ValueError, match="windows: expected one or more whole numbers >= 1"):
        metrics.error_table({"m": [E]}, horizons_s=tuple(range(10, 70, 10)), windows=(5.5, 20))


def test_reduction_and_ratio_tables_name_a_model_that_is_not_in_the_table():
    import pytest

    rows = [dict(model=m, state=s, window=w, horizon_s=60, mae=1.0)
            for m in ("hybrid", "dynamic") for s in metrics.STATES for w in (5, 20)]
    long = pd.DataFrame(rows)
    with pytest.raises(ValueError, match=r"model: 'hybird' is not in the table; it has \['hybrid', 'dynamic'\]"):
        metrics.reduction_table(long, "hybird")                                   # before: KeyError
    with pytest.raises(ValueError, match=r"reference: 'physics' is not in the table"):
        metrics.pooled_ratio_table(long, "hybrid", "physics")
    with pytest.raises(ValueError, match=r"windows: expected two windows"):
        metrics.reduction_table(long, "hybrid", windows=(5,))      # before: "not enough values to unpack"


def test_paper_reduction_and_ratio_tables_name_a_window_that_is_not_in_the_table():
    """A table of the first 5 and 10 intervals read with the default windows (5, 20): Table 2
    failed in pandas ("operation 'add' not supported for dtype 'str'"), Table 3 with a bare
    KeyError of the model's name."""
    import pytest

    long = metrics.error_table({"dynamic": [np.ones((20, 1, 3))], "hybrid": [np.ones((20, 1, 3))]},
                               horizons_s=(60,), windows=(5, 10))
    with pytest.raises(ValueError, match=r"windows: 20 is not in the table; it has windows \[5, 10\]"):
        metrics.paper_table(long)
    with pytest.raises(ValueError, match=r"windows: 20 is not in the table"):
        metrics.reduction_table(long, "hybrid")
    with pytest.raises(ValueError, match=r"windows: 20 is not in the table"):
        metrics.pooled_ratio_table(long, "hybrid")
    assert metrics.reduction_table(long, "hybrid", windows=(5, 10)).loc["east_m", "60 s"] == "0/0"


def test_error_table_keeps_each_state_and_horizon_in_its_own_cell():
    """Errors that differ by state (x1, x10, x100) and by horizon (x1, x2): every cell is its own
    state's and horizon's mean (with one horizon and equal states above, a cell read from the
    first horizon or the first state could not be told apart)."""
    k = np.arange(20.0) ** 2
    E = k[:, None, None] * np.array([1.0, 2.0])[None, :, None] * np.array([1.0, 10.0, 100.0])[None, None, :]
    long = metrics.error_table({"m": [E]}, horizons_s=(15, 60))
    mae = long.set_index(["window", "state", "horizon_s"]).mae
    assert len(mae) == 2 * 3 * 2
    for w in (5, 20):
        for i, state in enumerate(metrics.STATES):
            for j, h in enumerate((15, 60)):
                np.testing.assert_allclose(mae.loc[(w, state, h)], k[:w].mean() * (1, 2)[j] * (1, 10, 100)[i],
                                           err_msg=f"{w} {state} {h}")


def test_paper_and_reduction_tables_put_first_5_before_first_20():
    rows = [dict(model=m, state=s, window=w, horizon_s=60, mae=v)
            for m, vals in {"hybrid": {5: 1.0, 20: 3.0}, "dynamic": {5: 2.0, 20: 4.0}}.items()
            for s in metrics.STATES for w, v in vals.items()]
    long = pd.DataFrame(rows)
    assert metrics.paper_table(long).loc[("hybrid", "north_m"), "60 s"] == "1.00/3.00"
    assert metrics.reduction_table(long, "hybrid").loc["east_m", "60 s"] == "50/25"
    assert metrics.pooled_ratio_table(long, "hybrid").loc["yaw_deg", "60 s"] == "0.50/0.75"
    # a reference without error (a log the physics made) gives no ratio, not a crash or "inf"
    zero = long.assign(mae=np.where(long.model == "dynamic", 0.0, long.mae))
    assert metrics.reduction_table(zero, "hybrid").loc["east_m", "60 s"] == "n/a/n/a"
    assert metrics.pooled_ratio_table(zero, "hybrid").loc["east_m", "60 s"] == "n/a/n/a"


def test_paper_table_with_one_window_has_one_cell_per_horizon():
    """Fewer than 20 forecasts after a failure leave one window: Table 2 keeps its layout,
    one two-decimal error per cell (it was refused by ``paper_table``, so the benchmark wrote
    the long table, with its index and every digit)."""
    rows = [dict(model=m, state=s, window=3, horizon_s=h, mae=v + h / 1000.0)
            for m, v in {"hybrid": 1.0, "dynamic": 2.0}.items() for s in metrics.STATES for h in (15, 60)]
    table = metrics.paper_table(pd.DataFrame(rows), windows=(3,))
    assert list(table.columns) == ["15 s", "60 s"]
    assert table.loc[("dynamic", "yaw_deg"), "60 s"] == "2.06"
    assert list(table.index) == [(m, s) for m in ("hybrid", "dynamic") for s in metrics.STATES]


def test_every_committed_drift_table_states_its_ratio_from_its_own_errors():
    """The `hybrid`/`dynamic` ratios quoted in the docs are each folder's tables.md, and that
    block and Table 3 are what its errors.csv gives (a re-rendered block cannot drift)."""
    from pathlib import Path

    from hybridship.fileio import markdown_table
    from hybridship.evaluation.drift import ratio_markdown

    folders = [p.parent for p in sorted((Path(__file__).resolve().parents[1] / "docs" / "results").glob(
        "drift-*/tables.md")) if "### Table 3: % error reduction of `hybrid` relative" in p.read_text()]
    assert len(folders) >= 17
    for folder in folders:
        long = pd.read_csv(folder / "errors.csv")
        text = (folder / "tables.md").read_text()
        # as the benchmark writes it: a blank line before the next heading (else it renders as a table row)
        assert ratio_markdown(metrics.pooled_ratio_table(long, "hybrid")) + "\n\n### Coverage" in text, folder.name
        red = metrics.reduction_table(long, "hybrid").reset_index()
        assert markdown_table(red) in text, folder.name


def test_coverage_counts_north_and_east_and_the_band_edge():
    truth = np.zeros((4, 1, 3))
    pred = truth.copy()
    pred[:, 0, 0] = 0.5                 # north inside 1 sigma
    pred[:, 0, 1] = 2.0                 # east exactly on the 2-sigma edge, outside 1 sigma
    std = np.ones_like(truth)
    np.testing.assert_allclose(metrics.coverage(pred, truth, std), [[0.5, 1.0]])
    # an exact forecast with zero spread is inside its band
    np.testing.assert_allclose(metrics.coverage(truth, truth, np.zeros_like(std)), [[1.0, 1.0]])


def test_coverage_interval_uses_its_sigma():
    """The interval's coverage is :func:`coverage`'s at its sigma, the band edge included: random
    errors never sit on the edge, so a quarter of the errors here lie exactly on 1 or 2 sigma."""
    rng = np.random.default_rng(0)
    pred = rng.normal(size=(5, 10, 2, 3))
    pred[:, ::4, :, :2] = rng.choice([-2.0, -1.0, 1.0, 2.0], size=pred[:, ::4, :, :2].shape)
    truth, std = np.zeros_like(pred), np.ones_like(pred)
    for sigma in (1.0, 2.0):
        k = {1.0: 0, 2.0: 1}[sigma]
        np.testing.assert_allclose(metrics.coverage_interval(pred, truth, std, sigma, n_resamples=100)[:, 0],
                                   metrics.coverage(pred, truth, std)[:, k])


def test_grouped_interval_resamples_groups_not_rows_and_is_seeded():
    """The interval depends on the groups' coverages, not on how many rows each holds (rows
    of one failure share one outcome), and the same seed gives the same interval."""
    cov = np.array([1.0, 0.9, 0.6, 1.0, 0.8])[:, None]
    small = metrics.grouped_coverage_interval(cov * 10, np.full(5, 10), n_resamples=500, seed=3)
    large = metrics.grouped_coverage_interval(cov * 1000, np.full(5, 1000), n_resamples=500, seed=3)
    np.testing.assert_allclose(small, large)
    assert small[0, 1] < 0.8 < 0.95 < small[0, 2]          # five groups: a wide interval
    np.testing.assert_array_equal(small, metrics.grouped_coverage_interval(cov * 10, np.full(5, 10),
                                                                           n_resamples=500, seed=3))
    # and the seed is what draws the resamples: another seed, another interval (the point
    # estimate is the pooled coverage whatever the seed)
    other = metrics.grouped_coverage_interval(cov * 10, np.full(5, 10), n_resamples=500, seed=4)
    assert other[0, 0] == small[0, 0] and not np.array_equal(other[0, 1:], small[0, 1:])
    assert np.isnan(metrics.grouped_coverage_interval(cov[:1] * 10, [10])[0, 1:]).all()


def test_coverage_functions_refuse_bad_input_by_name():
    import pytest

    with pytest.raises(ValueError, match="hits, counts: expected shapes"):
        metrics.grouped_coverage_interval(np.zeros((0, 2)), np.zeros(0))      # before: NaN with a warning
    with pytest.raises(ValueError, match="hits, counts: expected shapes"):
        metrics.grouped_coverage_interval(np.ones((3, 2)), np.ones(2))       # before: numpy's broadcast error
    with pytest.raises(ValueError, match="hits, counts: expected counts > 0"):
        metrics.grouped_coverage_interval(np.full((2, 1), 5.0), [4, 10])
    with pytest.raises(TypeError, match="hits: expected an array of real numbers"):
        metrics.grouped_coverage_interval([["1"], ["2"]], [2, 2])
    with pytest.raises(ValueError, match="confidence: must be < 1"):
        metrics.grouped_coverage_interval(np.ones((2, 1)), [2, 2], confidence=90)
    with pytest.raises(ValueError, match="n_resamples: expected a whole number"):
        metrics.grouped_coverage_interval(np.ones((2, 1)), [2, 2], n_resamples=10.5)
    x = np.zeros((2, 3, 1, 3))
    with pytest.raises(TypeError, match="sigma: expected a number"):
        metrics.coverage_interval(x, x, x, "2")          # before: numpy's "ufunc 'isfinite' not supported"
    with pytest.raises(TypeError, match="pred: expected an array of real numbers"):
        metrics.coverage(x.astype(str), x, x)            # before: text read as numbers
    with pytest.raises(TypeError, match="sigmas: expected an array of real numbers"):
        metrics.coverage(x, x, x, sigmas=("a",))


def test_drift_forecasts_refuse_a_horizon_across_a_gap():
    """The truth is taken by rows: with 10 s of rows missing after the shutdown, the 15-s
    forecast was scored against the measurement at 25 s. Such starts are refused, and a log
    whose drift has too few gap-free starts has no drift to score."""
    import pytest

    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DeadReckoning, as_log_arrays
    from hybridship.predictors.after_failure import has_drift
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=330.0, t_shutdown_s=200.0)
    whole = as_log_arrays(log, m.vessel)
    holed = as_log_arrays(log[~log.time_s.between(205.5, 215.0)].reset_index(drop=True), m.vessel)
    dr = DeadReckoning(m.vessel)
    assert has_drift(whole, 20, 60.0) and not has_drift(holed, 20, 60.0)
    pred, truth, _ = metrics.drift_forecasts(dr, whole, n_intervals=3, horizons_s=(15, 30))
    np.testing.assert_array_equal(truth[0], whole.eta[[215, 230]])
    with pytest.raises(ValueError, match="only 0 start times .* before the gap at time_s 205 s"):
        metrics.drift_forecasts(dr, holed, n_intervals=3, horizons_s=(15, 30))
    # the starts before the gap whose horizon ends before it are still scored
    p, t, _ = metrics.drift_forecasts(dr, holed, n_intervals=2, horizons_s=(1, 2))
    np.testing.assert_array_equal(t[:, 1], whole.eta[[202, 203]])


def test_drift_forecasts_name_the_gap_and_dp_times_of_an_epoch_log_in_full():
    """A log in epoch seconds: the refusal gave the gap's time (and DP's return) with %g,
    'before the gap at time_s 1.7e+09 s', which locates no row; it is written in full."""
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DeadReckoning
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=330.0, t_shutdown_s=200.0)
    log["time_s"] += 1.7e9
    dr = DeadReckoning(m.vessel)
    holed = log[~(log.time_s - 1.7e9).between(205.5, 215.0)].reset_index(drop=True)
    with pytest.raises(ValueError, match=r"before the gap at time_s 1700000205 s"):
        metrics.drift_forecasts(dr, holed, n_intervals=3, horizons_s=(15, 30))
    back = log.copy()
    back.loc[back.time_s >= 1.7e9 + 230.0, "dp_active"] = 1
    with pytest.raises(ValueError, match=r"before DP comes back on at time_s 1700000230 s"):
        metrics.drift_forecasts(dr, back, n_intervals=20, horizons_s=(15,))


def test_has_drift_names_a_bad_count_or_horizon():
    """has_drift read a negative horizon as more room (a drift in any log with a failure) and
    failed on a NaN one in int()'s words ('cannot convert float NaN to integer') and on text
    in an operator's; each is now refused naming it, as drift_forecasts refuses them."""
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import as_log_arrays
    from hybridship.predictors.after_failure import has_drift
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    a = as_log_arrays(physics_log(m, seed=3, duration_s=330.0, t_shutdown_s=200.0), m.vessel)
    assert has_drift(a, 20, 60.0) and not has_drift(a, 200, 60.0)
    for args, err, match in (((20, float("nan")), ValueError, "^horizon_s: "),
                             ((20, -60.0), ValueError, "^horizon_s: "), ((20, "60"), TypeError, "^horizon_s: "), (("20", 60.0), ValueError, "^n_intervals: "),
                             ((0, 60.0), ValueError, "^n_intervals: "), ((20.5, 60.0), ValueError, "^n_intervals: ")):
        with pytest.raises(err, match=match):
            has_drift(a, *args)


def test_drift_forecasts_end_where_dp_comes_back_on():
    """A drift ends where DP comes back on, as drift_start_rows bounds it: with DP on again
    10 s after the failure, the 20 "drift" starts were scored (10 of them with DP on, every
    60-s horizon across DP thrust) and the log counted as having a drift to score."""
    import pytest

    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DeadReckoning, as_log_arrays
    from hybridship.predictors.after_failure import drift_end, has_drift
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=330.0, t_shutdown_s=200.0)
    whole = as_log_arrays(log, m.vessel)
    back = log.copy()
    back.loc[back.time_s >= 230.0, "dp_active"] = 1
    back = as_log_arrays(back, m.vessel)
    assert drift_end(whole, 200) == len(whole.time_s) and drift_end(back, 200) == 230
    assert has_drift(whole, 20, 60.0) and not has_drift(back, 20, 60.0)
    dr = DeadReckoning(m.vessel)
    with pytest.raises(ValueError, match="only 0 start times .* before DP comes back on at time_s 230 s"):
        metrics.drift_forecasts(dr, back, n_intervals=20, horizons_s=(15, 60))
    # starts whose horizon ends before DP is back are scored as before
    p, t, _ = metrics.drift_forecasts(dr, back, n_intervals=15, horizons_s=(15,))
    p0, t0, _ = metrics.drift_forecasts(dr, whole, n_intervals=15, horizons_s=(15,))
    np.testing.assert_array_equal(p, p0)
    np.testing.assert_array_equal(t, t0)


def test_drift_forecasts_refuse_a_log_that_starts_with_dp_off():
    """A log whose first rows have DP off (a transit before the station keeping and its
    failure) had its shutdown at row 0: its transit was scored as the drift after a failure,
    although has_drift reads such a log as having none."""
    import pytest

    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DeadReckoning, as_log_arrays
    from hybridship.predictors.after_failure import has_drift, shutdown_index
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=600.0, t_shutdown_s=500.0)
    log.loc[log.time_s < 150.0, "dp_active"] = 0
    a = as_log_arrays(log, m.vessel)
    assert not has_drift(a, 20, 60.0)
    with pytest.raises(ValueError, match="log: starts with dp_active 0"):
        shutdown_index(a)
    with pytest.raises(ValueError, match="log: starts with dp_active 0"):
        metrics.drift_forecasts(DeadReckoning(m.vessel), a, n_intervals=20, horizons_s=(15, 60), first=3)


def test_drift_forecasts_refuse_bad_starts_and_horizons_by_name():
    """A negative horizon or first start indexed the forecast and the truth from their ends
    and was scored without a word; every=0 divided by zero, a fractional count or no horizon
    failed with numpy's message."""
    import pytest

    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DeadReckoning, as_log_arrays
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    whole = as_log_arrays(physics_log(m, seed=3, duration_s=330.0, t_shutdown_s=200.0), m.vessel)
    dr = DeadReckoning(m.vessel)
    for kw, field in ((dict(horizons_s=(-15, 30)), "horizons_s"), (dict(horizons_s=(0, 15)), "horizons_s"),
                      (dict(horizons_s=()), "horizons_s"), (dict(horizons_s=(np.nan,)), "horizons_s"),
                      (dict(horizons_s=15), "horizons_s"), (dict(first=-50), "first"), (dict(every=0), "every"),
                      (dict(n_intervals=2.5), "n_intervals"), (dict(n_intervals=-3), "n_intervals")):
        with pytest.raises((TypeError, ValueError), match=f"^{field}: "):
            metrics.drift_forecasts(dr, whole, **{"n_intervals": 3, "horizons_s": (15,), **kw})
    p, t, _ = metrics.drift_forecasts(dr, whole, n_intervals=3, horizons_s=(15, 30), first=np.int64(2), every=2)
    np.testing.assert_array_equal(t[:, 0], whole.eta[[217, 219, 221]])


def test_drift_forecasts_refuse_horizons_that_are_not_whole_steps_of_the_log():
    """On a 2-s log a 1-s horizon was scored at lead 0 (an error of exactly 0) and a 15-s one
    at 16 s, while a forecast refuses such horizons."""
    import pytest

    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DeadReckoning, as_log_arrays
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=400.0, t_shutdown_s=200.0)
    a = as_log_arrays(log.iloc[::2].reset_index(drop=True), m.vessel)          # a 2-s log
    dr = DeadReckoning(m.vessel)
    for horizons, why in (((1, 30), "shorter than one step"), ((15, 30), "not a whole number")):
        with pytest.raises(ValueError, match=rf"^horizons_s: {horizons[0]} s is {why} .*\(2 s\)"):
            metrics.drift_errors(dr, a, n_intervals=3, horizons_s=horizons)
    p, t, _ = metrics.drift_forecasts(dr, a, n_intervals=3, horizons_s=(2, 30))
    np.testing.assert_array_equal(t[:, 0], a.eta[[101, 102, 103]])


def test_grouped_interval_over_three_groups_stays_within_their_own_coverages():
    """The documented limit of few groups: the interval never leaves the groups' range."""
    from hybridship.evaluation.metrics import grouped_coverage_interval

    hits, counts = np.array([[18.0], [19.0], [20.0]]), np.array([20.0, 20.0, 20.0])
    cov, lo, hi = grouped_coverage_interval(hits, counts)[0]
    assert np.isclose(cov, 0.95) and 0.9 <= lo <= cov <= hi <= 1.0


def test_error_table_refuses_a_window_or_horizon_given_twice():
    """Windows (5, 5) or horizons (15, 15, 45, 60) wrote two rows of one cell, and the paper's
    table of them failed in pandas' words ("Index contains duplicate entries, cannot reshape")."""
    E = {"m": [np.ones((20, 4, 3))]}
    with pytest.raises(ValueError, match=r"^windows: \(5, 5\) gives one twice"):
        metrics.error_table(E, windows=(5, 5))
    with pytest.raises(ValueError, match=r"^horizons_s: \(15, 15, 45, 60\) gives one twice"):
        metrics.error_table(E, horizons_s=(15, 15, 45, 60))
    # a horizon list given as a generator is read once (len() of it failed)
    long = metrics.error_table(E, horizons_s=(h for h in (15, 30, 45, 60)))
    assert metrics.paper_table(long).shape == (3, 4)


def test_coverage_given_one_sigma_as_a_number_says_a_sequence_is_expected():
    """sigmas=2 was refused as 'expected positive finite band half-widths, got 2', which 2 is."""
    from hybridship.evaluation.metrics import coverage

    z = np.zeros((2, 4, 3))
    with pytest.raises(ValueError, match=r"^sigmas: expected positive finite band half-widths \(a sequence, e.g. \(2.0,\) for one\), got 2$"):
        coverage(z, z, np.ones_like(z), sigmas=2)
    assert coverage(z, z, np.ones_like(z), sigmas=(2.0,)).shape == (4, 1)
