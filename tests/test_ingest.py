"""One ingest for fit, forecast and the benchmarks (issue 15, defects 2 and 3).

Every path a log takes into the package goes through :func:`hybridship.logs.ingest.ingest`:
the same log gets the same vessel checks and messages whether it is trained on or forecast
from, LogArrays are checked too, and a repeated time stamp is repaired and flagged rather
than turned into NaN deep inside a forecast.
"""

from __future__ import annotations

import warnings

from dataclasses import fields

import numpy as np
import pandas as pd
import pytest

from hybridship.evaluation import metrics
from hybridship.logs.ingest import ingest, ingest_with_report, sort_samples
from hybridship.logs.io import LogArrays, LogFormatError, log_to_arrays
from hybridship.physics.model import DynamicModel
from hybridship.predictors import DataOnlyPredictor, DynamicPredictor, HybridPredictor
from hybridship.predictors.forecast_setup import FORECAST_HISTORY_S
from hybridship.forecast_inputs import FaultFlags, StartWindowError
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import prepare_log
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=2, hidden=8, max_epochs=15, patience=5, seed=0)


@pytest.fixture(scope="module")
def log(model):
    return physics_log(model, seed=2, duration_s=300.0, t_shutdown_s=None, current=(0.2, 1.0))


@pytest.fixture(scope="module")
def hybrid(model, log):
    return HybridPredictor(model.vessel, ensemble_config=TINY).fit([log])


def _rpm_60x(log):
    bad = log.copy()
    bad["port_rpm"] = bad["port_rpm"] * 60.0          # rev/s mistaken for rpm, or motor rpm
    return bad


def _message(fn) -> str:
    with pytest.raises(LogFormatError) as err:
        fn()
    return str(err.value)


def test_fit_and_forecast_refuse_the_same_log_with_the_same_message(model, log, hybrid, tmp_path):
    bad = _rpm_60x(log)
    path = tmp_path / "bad.csv"
    bad.to_csv(path, index=False)
    for src in (bad, path):
        msgs = {
            "hybrid.fit": _message(lambda: HybridPredictor(model.vessel, ensemble_config=TINY).fit([src])),
            "data_only.fit": _message(lambda: DataOnlyPredictor(model.vessel, ensemble_config=TINY).fit([src])),
            "hybrid.forecast": _message(lambda: hybrid.forecast(src, [250.0], 10)),
            "dynamic.forecast": _message(lambda: DynamicPredictor(model.vessel).forecast(src, [250.0], 10)),
        }
        assert len(set(msgs.values())) == 1, msgs
        msg = next(iter(msgs.values()))
        assert msg.startswith("port_rpm: ") and "exceeds 1.25 x max_rpm" in msg


@pytest.mark.parametrize("learner", [HybridPredictor, DataOnlyPredictor])
def test_a_fault_in_one_of_several_training_frames_names_which(model, log, learner):
    """Several DataFrames: the message names the faulty one by its place, as a path names its
    file; it said "(in log)", which does not tell logs[0] from logs[1]."""
    bad = log.copy()
    bad.loc[100, "north_m"] = np.nan
    msg = _message(lambda: learner(model.vessel, ensemble_config=TINY).fit([log, bad]))
    assert msg.startswith("north_m: ") and msg.endswith("(in logs[1])"), msg
    assert bad["north_m"].isna().sum() == 1 and log["north_m"].notna().all()     # neither was changed


def test_a_start_time_outside_the_log_gives_the_logs_warnings_once(model, log, hybrid, tmp_path):
    """The whole log is read again to say its span in the error; its warnings (a column not in
    the format) were given twice."""
    path = tmp_path / "indexed.csv"
    log.to_csv(path)                                # with pandas' index: "Unnamed: 0"
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(ValueError, match=r"start_times_s: 9999.0 s is not a sample time of the log"):
            hybrid.forecast(path, [100.0, 9999.0], 10)
    unknown = [w for w in seen if "not in the log format: Unnamed: 0" in str(w.message)]
    assert len(unknown) == 1, [str(w.message) for w in seen]


def test_log_arrays_get_the_vessel_checks_and_the_sorting(model, log):
    names, rot = model.vessel.channel_names, model.vessel.rotatable
    drift = physics_log(model, seed=4, duration_s=300.0, t_shutdown_s=200.0)
    unchecked = log_to_arrays(_rpm_60x(drift), channel_names=names, rotatable=rot)   # no vessel checks here
    with pytest.raises(LogFormatError, match="port_rpm: .*exceeds 1.25 x max_rpm"):
        metrics.drift_forecasts(DynamicPredictor(model.vessel), unchecked, n_intervals=2)
    with pytest.raises(LogFormatError, match="port_rpm"):
        ingest(unchecked, model.vessel, purpose="forecast")
    # arrays whose rows are out of order (built by hand) are re-sorted, and say so
    good = log_to_arrays(log, channel_names=names, rotatable=rot)
    perm = np.arange(len(good))
    perm[[100, 101]] = [101, 100]
    kw = {f.name: getattr(good, f.name) for f in fields(good)}
    kw.update({k: v[perm] for k, v in kw.items() if isinstance(v, np.ndarray) and v.shape[:1] == (len(good),)})
    shuffled = LogArrays(**kw)
    out = ingest(shuffled, model.vessel, purpose="forecast")
    assert np.all(np.diff(out.time_s) > 0) and list(out.resorted_time_s) == [100.0]
    np.testing.assert_allclose(out.eta, good.eta, atol=1e-9)
    # the caller's heading branch is kept (the frame view wraps headings to 0..360 deg): arrays
    # whose unwrapped heading is one turn on come back one turn on, not on the frame's branch
    kw["eta"] = kw["eta"] + [0.0, 0.0, 2 * np.pi]
    out = ingest(LogArrays(**kw), model.vessel, purpose="forecast")
    np.testing.assert_allclose(out.eta, good.eta + [0.0, 0.0, 2 * np.pi], atol=1e-9)
    # another vessel's arrays are refused, naming the mismatch
    esso = DynamicModel("esso_osaka_model").vessel
    with pytest.raises(LogFormatError, match="channel_names: .*vessel 'esso_osaka_model'"):
        ingest(good, esso)


def test_checked_arrays_pass_through_and_round_trip(model, log):
    arrays = ingest(log, model.vessel, purpose="fit")
    assert ingest(arrays, model.vessel, purpose="forecast") is arrays      # already checked: no work
    assert ingest(arrays, model.vessel, purpose="fit") is arrays
    assert arrays.dt_s == 1.0 and np.isnan(ingest(log.iloc[:1], model.vessel, purpose="forecast").dt_s)
    back = ingest(arrays.to_frame(), model.vessel)
    for name in ("time_s", "eta", "nu", "nu_logged", "rpm", "azimuth_rad", "wind", "dp_active", "segment_id"):
        np.testing.assert_allclose(getattr(back, name), getattr(arrays, name), atol=1e-9, err_msg=name)
    assert (back.channel_names, back.rotatable, back.channel_logged, back.has_wind) == \
        (arrays.channel_names, arrays.rotatable, arrays.channel_logged, arrays.has_wind)


def test_ingest_checks_its_arguments_and_never_modifies_the_input(model, log, tmp_path):
    before = log.copy(deep=True)
    shuffled = pd.concat([log.iloc[:50], log.iloc[[51, 50]], log.iloc[52:]])
    before_shuffled = shuffled.copy(deep=True)
    arrays, order = ingest_with_report(shuffled, model.vessel, purpose="forecast")
    pd.testing.assert_frame_equal(log, before)
    pd.testing.assert_frame_equal(shuffled, before_shuffled)
    assert order.changed and list(arrays.resorted_time_s) == [50.0]
    with pytest.raises(ValueError, match="purpose: expected one of"):
        ingest(log, model.vessel, purpose="train")
    with pytest.raises(TypeError, match="log: expected a path, a DataFrame or LogArrays"):
        ingest([1, 2, 3], model.vessel)


def _repeated_time(log, row):
    """Row ``row`` stamped with the time of the row before it (a logger hiccup)."""
    df = log.copy()
    df.loc[row, "time_s"] = df.loc[row - 1, "time_s"]
    return df


def test_a_repeated_time_stamp_early_in_a_log_is_repaired_and_flagged(model, log, hybrid):
    """Defect 3: it used to end in scipy's 'array must not contain infs or NaNs'."""
    df = _repeated_time(log, 10)
    starts = [12.0, 20.0, 250.0]
    mean_env = HybridPredictor(model.vessel, ensemble_config=TINY, environment="mean").fit([log])  # the path that failed
    for pred in (hybrid, mean_env, DynamicPredictor(model.vessel)):
        fc = pred.forecast(df, starts, 20)
        assert np.isfinite(fc.eta).all() and np.isfinite(fc.nu).all()
        np.testing.assert_array_equal(fc.flags[FaultFlags.NAN_IN_WINDOW], [True, False, False])  # 10 missing
        # the repair is the log without both samples of the repeated time
        ref = pred.forecast(log.drop(index=[9, 10]), starts, 20)
        np.testing.assert_allclose(fc.eta, ref.eta, rtol=0, atol=1e-12)
        # the start right after it has one valid sample of three in its window: refused, saying why
        with pytest.raises(StartWindowError, match="start time_s 11: refused, .*late, out-of-order or duplicated"):
            pred.forecast(df, [11.0], 20)
    # neither sample of time 9 is trusted: 9 and 10 are missing samples now
    arrays = ingest(df, model.vessel, purpose="forecast")
    assert 9.0 not in arrays.time_s and 10.0 not in arrays.time_s and list(arrays.resorted_time_s) == [9.0]
    # training data must be clean: refused, naming the column and the rows
    msg = _message(lambda: HybridPredictor(model.vessel, ensemble_config=TINY).fit([df]))
    assert msg.startswith("time_s: 9 appears at rows 9 and 10 with different values")


def test_training_says_which_samples_it_re_sorted_or_dropped(model, log):
    """A training log whose time runs backwards in places is repaired as a forecast's is, but
    with a warning that counts what was changed (training data should be clean)."""
    from hybridship.logs.io import LogFormatWarning

    # a swap and a repeat at the end (both late), and a row without a time
    messy = pd.concat([log.iloc[:50], log.iloc[[51, 50]], log.iloc[52:], log.iloc[[70]]])
    messy = messy.reset_index(drop=True)
    messy.loc[len(messy)] = messy.iloc[0]
    messy.loc[len(messy) - 1, "time_s"] = np.nan
    with pytest.warns(LogFormatWarning, match=r"time_s is not strictly increasing: 2 late sample\(s\) re-sorted, "
                                              r"1 exact duplicate\(s\) dropped, 1 row\(s\) without a finite time_s"):
        out = ingest(messy, model.vessel, purpose="fit")
    assert len(out.time_s) == len(log) and np.all(np.diff(out.time_s) > 0)


def test_the_re_sort_warning_is_placed_at_the_users_line(model, log):
    """The warning named a line of ingest.py as its place (a fixed stack level counted one
    frame, the library's own caller), so a filter on the user's module missed it; it is
    now placed at the first line outside the package, here this test, through ingest and
    through a fit."""
    messy = pd.concat([log.iloc[:50], log.iloc[[51, 50]], log.iloc[52:]]).reset_index(drop=True)
    for call in (lambda: ingest(messy, model.vessel, purpose="fit"),
                 lambda: DynamicPredictor(model.vessel).forecast(messy, [log.time_s.iloc[-61]], 10)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            call()
        places = {w.filename for w in caught if "not strictly increasing" in str(w.message)}
        assert places == {__file__}


def test_a_forecast_says_which_samples_it_removed_outside_its_start_window(model, log, hybrid):
    """Review: a time column that jumps back removed the repeated times from a forecast's
    log without a word (the flags see only the start window, the estimator the half hour
    before it); it now warns as training does, counting the conflicting times."""
    from hybridship.logs.io import LogFormatWarning

    back = pd.concat([log.iloc[:150], log.iloc[150:].assign(time_s=log.time_s.iloc[150:] - 20.0)])
    back = back.reset_index(drop=True)                     # times 130-149 logged twice, other values
    before = back.copy()
    with pytest.warns(LogFormatWarning, match=r"20 time\(s\) logged more than once with different values, "
                                              r"all their samples removed"):
        fc = hybrid.forecast(back, [250.0], 20)
    assert not fc.flags[FaultFlags.LATE_OR_OUT_OF_ORDER].any()   # far from the start window
    pd.testing.assert_frame_equal(back, before)                 # the caller's frame is not touched
    # blank rows at the end (a spreadsheet export) hold no sample: no warning at forecast time
    blank = pd.concat([log, pd.DataFrame(np.nan, index=[0, 1], columns=log.columns)], ignore_index=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error", LogFormatWarning)
        hybrid.forecast(blank, [250.0], 20)
    # a sample whose time is missing is lost: said at forecast time too (it was dropped silently)
    lost = log.copy()
    lost.loc[100, "time_s"] = np.nan
    with pytest.warns(LogFormatWarning, match=r"1 row\(s\) without a finite time_s dropped"):
        hybrid.forecast(lost, [250.0], 20)


def test_a_time_column_that_runs_backwards_says_the_samples_were_re_sorted(model, log):
    """A log written backwards is re-sorted into the right log; a time_s column reversed
    against the other columns cannot be told from it by time alone, and the re-sorted log's
    yaw rate then contradicts its heading: the refusal also says that most samples were
    re-sorted, so that the reader does not look for a sign convention only."""
    from hybridship.logs.io import LogFormatWarning

    out = ingest(log.iloc[::-1].reset_index(drop=True), model.vessel, purpose="forecast")
    np.testing.assert_array_equal(out.time_s, ingest(log, model.vessel, purpose="forecast").time_s)
    r = 2.0 * np.sin(log.time_s.to_numpy() / 30.0)                     # a zigzag [deg/s]
    turning = log.assign(heading_deg=np.mod(10.0 + np.cumsum(r), 360.0), r_deg_s=r)
    reversed_time = turning.assign(time_s=turning.time_s.to_numpy()[::-1])
    with pytest.raises(LogFormatError, match=r"r_deg_s: has the opposite sign .*; note: \d+ of the \d+ samples "
                                             r"came after a later one and were re-sorted by time_s") as e:
        ingest(reversed_time, model.vessel, purpose="forecast")
    assert e.value.column == "r_deg_s"
    # a yaw rate of the other sign in a log with one late sample: the note would mislead
    # (the time column is fine), so it is not given
    one_late = turning.assign(r_deg_s=-r).iloc[[*range(50), 51, 50, *range(52, len(turning))]]
    with pytest.warns(LogFormatWarning, match=r"1 late sample\(s\) re-sorted"):
        msg = _message(lambda: ingest(one_late, model.vessel, purpose="forecast"))
    assert msg.startswith("r_deg_s: has the opposite sign") and "re-sorted" not in msg, msg


@pytest.mark.parametrize("environment", ["estimator", "mean"])
def test_a_missing_velocity_at_the_start_of_a_log_does_not_break_a_later_hybrid_forecast(log, model, environment):
    hybrid = HybridPredictor(model.vessel, ensemble_config=TINY, environment=environment).fit([log])
    df = log.copy()
    df.loc[0, ["north_m", "u_m_s"]] = np.nan
    fc = hybrid.forecast(df, [250.0], 20)
    assert np.isfinite(fc.eta).all()


def test_a_whole_log_statistic_is_judged_on_the_whole_log(model, log):
    """An azimuth thruster whose rpm is negative throughout a short range (DP reversing it
    for a while) but positive elsewhere passes: the rpm-sign check is a statistic of the
    whole log, and the range's rows are the whole log's."""
    reverse = log.copy()
    window = (reverse.time_s >= 100.0) & (reverse.time_s <= 200.0)
    reverse.loc[window, "port_rpm"] = -np.abs(reverse.loc[window, "port_rpm"]) - 1.0
    assert (reverse.loc[~window, "port_rpm"] > 0).any()
    part = ingest(reverse, model.vessel, purpose="forecast", time_range_s=(100.0, 200.0))
    whole = ingest(reverse, model.vessel, purpose="forecast")
    keep = (whole.time_s >= 100.0) & (whole.time_s <= 200.0)
    np.testing.assert_array_equal(part.rpm, whole.rpm[keep])
    np.testing.assert_array_equal(part.time_s, whole.time_s[keep])
    alone = reverse[window].reset_index(drop=True)     # the same rows alone: the check applies
    assert _message(lambda: ingest(alone, model.vessel, purpose="forecast")).startswith("port_rpm: negative")


def test_the_segments_of_the_rows_read_are_the_whole_logs(model):
    """A gap was a step longer than 1.5 median steps of the rows read, so the rows a call read
    decided it: on a log at 1 Hz to 300 s and 10 Hz after, the 1-Hz rows from 200 s were one
    segment when the rows read ended at 305 s (median step 1 s), and each a segment of its own
    (no velocity derived) when they reached 390 s (0.1 s). The gaps are now judged at the whole
    log's step (0.1 s), as for LogArrays, which are converted whole."""
    log = physics_log(model, seed=1, dt_s=0.1, duration_s=400.0, t_shutdown_s=None)
    log["time_s"] = log.time_s.round(6)
    log = log[(log.time_s >= 300.0) | (log.time_s % 1.0 == 0)].drop(columns=["u_m_s", "v_m_s", "r_deg_s"])
    whole = ingest(log, model.vessel, purpose="forecast")
    for time_range_s in ((200.0, 305.0), (200.0, 390.0)):
        part = ingest(log, model.vessel, purpose="forecast", time_range_s=time_range_s)
        rows = (whole.time_s >= time_range_s[0]) & (whole.time_s <= time_range_s[1])
        np.testing.assert_array_equal(part.time_s, whole.time_s[rows])
        np.testing.assert_array_equal(np.diff(part.segment_id) != 0, np.diff(whole.segment_id[rows]) != 0)
        # inside the rows read (np.gradient is one-sided at their ends) the derived velocities
        # agree, to the rounding of a heading unwrapped from another first sample
        np.testing.assert_allclose(part.nu[1:-1], whole.nu[rows][1:-1], rtol=1e-9, atol=1e-12)
        assert np.isnan(part.nu[:100]).all()     # 200..299 s: 1-Hz rows in a 10-Hz log, each a gap


@pytest.mark.parametrize("environment", ["estimator", "mean"])
def test_a_forecast_reads_only_its_time_range(log, model, environment):
    """A forecast reads the log from ``history_s`` (+ a margin) before its earliest start to
    its horizon after the last: what lies outside that range (here a sensor fault and an
    absurd rpm 1500 s before the start) changes nothing, and a fault inside it is refused
    with the row and time the whole log's check names."""
    hybrid = HybridPredictor(model.vessel, ensemble_config=TINY, environment=environment).fit([log])
    long = physics_log(model, seed=7, duration_s=5500.0, t_shutdown_s=None, current=(0.2, 1.0))
    start = [5400.0, 5410.0]
    assert 5400.0 - hybrid.history_s - 60.0 > 1000.0
    ref = hybrid.forecast(long, start, 30)
    bad = long.copy()
    bad.loc[bad.time_s < 1000.0, "north_m"] = np.nan
    bad.loc[bad.time_s < 1000.0, "port_rpm"] = 60 * 217.0
    fc = hybrid.forecast(bad, start, 30)
    np.testing.assert_array_equal(fc.eta, ref.eta)
    np.testing.assert_array_equal(fc.eta_std, ref.eta_std)
    inside = long.copy()
    inside.loc[4000, "port_rpm"] = 60 * 217.0
    msg = _message(lambda: hybrid.forecast(inside, start, 30))
    assert msg.startswith("port_rpm") and "row 4000" in msg, msg


def test_sort_samples_names_conflicts_by_their_input_rows_in_input_order():
    """conflicting_rows are the input positions (rows without a time counted) of the first two
    samples of a repeated time, in input order: the sort keeps equal times in input order, also
    in a long log written backwards."""
    n = 1000
    df = pd.DataFrame({"time_s": np.arange(n, dtype=float)[::-1], "north_m": np.arange(n, dtype=float)})
    df.loc[n // 2, "time_s"] = df.loc[n // 2 - 1, "time_s"]        # a repeated stamp, other values
    order = sort_samples(df)
    np.testing.assert_array_equal(order.conflicting_rows, [[n // 2 - 1, n // 2]])
    assert list(order.conflicting_time_s) == [df.loc[n // 2, "time_s"]] and len(order.frame) == n - 2
    blank = pd.concat([df.iloc[:1].assign(time_s=np.nan), df], ignore_index=True)
    np.testing.assert_array_equal(sort_samples(blank).conflicting_rows, [[n // 2, n // 2 + 1]])


def test_sort_samples_refuses_a_repeated_time_s_or_a_two_level_header_naming_it():
    """sort_samples took a second ``time_s`` column to pandas ("arg must be a list, tuple,
    1-d array, or Series") and called a two-level header's time_s missing; ingest refused both."""
    df = pd.DataFrame({"time_s": [0.0, 1.0], "north_m": 0.0, "east_m": 0.0, "heading_deg": 0.0})
    twice = pd.concat([df, df[["time_s"]]], axis=1)
    levels = df.set_axis(pd.MultiIndex.from_tuples([(c, "") for c in df.columns]), axis=1)
    for bad, pattern in ((twice, r"^time_s: column appears more than once.*\(in my log\)$"),
                         (levels, r"^columns: expected one row of column names, got 2 levels")):
        with pytest.raises(LogFormatError, match=pattern):
            sort_samples(bad, source="my log")


def test_an_exact_duplicate_is_dropped_not_late_and_missing_values_compare_equal():
    """A sample repeated in order (NaN where the first is NaN) is an exact duplicate: one kept,
    nothing counted as late or conflicting."""
    df = pd.DataFrame({"time_s": [0.0, 1.0, 1.0, 2.0], "north_m": [0.0, 1.0, 1.0, 2.0],
                       "wind_speed_m_s": [np.nan, np.nan, np.nan, 3.0]})
    order = sort_samples(df)
    assert order.late_time_s.size == 0 and order.conflicting_time_s.size == 0
    assert list(order.duplicate_time_s) == [1.0] and list(order.frame.time_s) == [0.0, 1.0, 2.0]


def test_arrays_ingested_for_a_forecast_are_checked_again_for_training(model, log):
    """Arrays ingested for a forecast may hold missing positions; passed to training they are
    checked again (not passed through) and refused, naming the column and row."""
    df = log.copy()
    df.loc[30, "north_m"] = np.nan
    arrays = ingest(df, model.vessel, purpose="forecast")
    assert np.isnan(arrays.eta[30, 0]) and ingest(arrays, model.vessel, purpose="forecast") is arrays
    with pytest.raises(LogFormatError, match=r"north_m: missing or non-finite value \(nan\) at row 30"):
        ingest(arrays, model.vessel, purpose="fit")


@pytest.mark.parametrize("dtype", ["float32", "Float64"])
def test_an_exact_duplicate_with_a_missing_value_is_one_sample_in_any_float_type(model, dtype):
    """A repeated row that is identical, a missing value included, is an exact duplicate also
    when the columns are float32 or pandas' nullable Float64 (whose missing values are not
    Python floats): one copy is kept, and training does not refuse it as a conflict."""
    log = physics_log(model, seed=5, duration_s=120.0, t_shutdown_s=None).astype(dtype)
    log.loc[10, "u_m_s"] = np.nan
    doubled = pd.concat([log.iloc[:11], log.iloc[[10]], log.iloc[11:]], ignore_index=True)
    arrays = ingest(doubled, model.vessel, purpose="forecast")
    assert 10.0 in arrays.time_s and len(arrays.time_s) == len(log)
    with pytest.warns(UserWarning, match="exact duplicate"):
        ingest(doubled, model.vessel, purpose="fit")


def test_training_refuses_a_command_column_without_any_value(model, log):
    """A dead channel exported as an empty column was trained on as a stopped thruster (or a
    centred azimuth): training refuses it as it refuses the column missing; a forecast keeps
    it, for its start-window flags."""
    for col, says in (("port_rpm", "port_rpm: without a value in any row while tunnel_rpm, stbd_rpm are logged"),
                      ("port_azimuth_deg", "port_azimuth_deg: without a value in any row while port_rpm is logged")):
        dead = log.assign(**{col: np.nan})
        with pytest.raises(LogFormatError, match=says):
            ingest(dead, model.vessel, purpose="fit")
        assert not ingest(dead, model.vessel, purpose="forecast").commands_logged.any()
    dead = log.assign(tunnel_rpm=np.nan, port_rpm=np.nan, stbd_rpm=np.nan)
    with pytest.raises(LogFormatError, match="tunnel_rpm: no thruster rpm values .* while dp_active is 1 at row 0"):
        ingest(dead, model.vessel, purpose="fit")
    with pytest.raises(LogFormatError, match="tunnel_rpm: no thruster rpm values .* while dp_active is absent"):
        ingest(dead.assign(dp_active=np.nan), model.vessel, purpose="fit")      # read as 1, as when absent
    # a drift without thrust may carry empty rpm columns, as it may leave them out
    ingest(dead.assign(dp_active=0), model.vessel, purpose="fit")


def test_fit_and_forecast_read_a_log_into_the_same_arrays_and_features(model, log, hybrid, tmp_path):
    """Training reads a whole log; a forecast reads the rows around its starts from a file: the
    rows both read carry the same samples, derived velocities, segments and residual
    features (away from the edges of what the forecast read, where a derivative is one-sided)."""
    df = log.drop(columns=["u_m_s", "v_m_s", "r_deg_s"]).drop(index=range(150, 153))     # derived nu, a gap
    df["heading_deg"] = (df["heading_deg"] + 170.0) % 360.0 - 180.0                        # the other wrap
    path = tmp_path / "log.csv.gz"
    df.iloc[::-1].to_csv(path, index=False)                                                # late rows too
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        fit = ingest(df, model.vessel, purpose="fit")
        part = ingest(path, model.vessel, purpose="forecast", time_range_s=(100.0, 250.0))
    rows = np.searchsorted(fit.time_s, part.time_s)
    np.testing.assert_array_equal(fit.time_s[rows], part.time_s)
    inner = slice(1, -1)
    for name in ("eta", "nu", "nu_logged", "rpm", "azimuth_rad", "wind", "dp_active"):
        np.testing.assert_allclose(getattr(part, name)[inner], getattr(fit, name)[rows][inner], rtol=0, atol=1e-9,
                                   err_msg=name)
    cut = np.flatnonzero(np.diff(part.segment_id)) + 1
    np.testing.assert_array_equal(cut, np.flatnonzero(np.diff(fit.segment_id[rows])) + 1)
    assert part.time_s[cut].tolist() == [153.0]
    # the nets' inputs: a forecast reads FORECAST_HISTORY_S before its start (the bias is a
    # causal mean over bias_window_s of it), here all of this short log, and stops short of its end
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        part = ingest(path, model.vessel, purpose="forecast", time_range_s=(0.0, 250.0))
    assert FORECAST_HISTORY_S >= hybrid.residual_config.bias_window_s
    cfg = hybrid.residual_config
    k = np.arange(5, len(part) - 2)
    np.testing.assert_allclose(prepare_log(model, part, cfg).full_features(k),
                               prepare_log(model, fit, cfg).full_features(k), rtol=1e-9, atol=1e-12)


def test_a_fault_is_named_by_its_input_row_after_rows_were_dropped_or_re_sorted(model, log):
    """The checks count the rows of the re-sorted frame: after a row without a time was
    dropped, a missing north_m at input row 20 was named as row 19, a valid sample; the
    message and the error's row now give the input row (and its time, as before)."""
    df = log.copy()
    df.loc[5, "time_s"] = np.nan
    df.loc[20, "north_m"] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(LogFormatError, match=rf"^north_m: missing or non-finite value \(nan\) at row 20 "
                                                 rf"\(time_s {df.time_s[20]:g}\)") as err:
            ingest(df, model.vessel)
    assert err.value.row == 20
    late = pd.concat([log.iloc[[40]], log.drop(index=40)]).reset_index(drop=True)    # row 40 came first
    late.loc[10, "north_m"] = np.nan                                                # its time: 9 s
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(LogFormatError, match=rf"at row 10 \(time_s {late.time_s[10]:g}\)") as err:
            ingest(late, model.vessel)
    assert err.value.row == 10
