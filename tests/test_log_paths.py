"""One path for one log: training and forecasting read a log alike, and bad input is named.

The same log goes through :func:`hybridship.logs.ingest.ingest` for ``fit`` and for
``forecast`` (whole, or the time range a forecast reads); the arrays they see must agree,
and a held-command forecast must not see commands logged after its start.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hybridship.logs.ingest import ingest
from hybridship.logs.io import LogFormatError, read_log
from hybridship.predictors import DynamicPredictor
from hybridship.sim.synthetic import physics_log


@pytest.fixture(scope="module")
def log(model):
    return physics_log(model, seed=5, duration_s=120.0, t_shutdown_s=None)


def test_a_command_logged_after_a_start_is_not_held_at_it(model, log):
    """A command column empty at the log's start: the rows before its first value take the
    default (0 rpm, angle 0), not the later value (a forecast from them would use the future)."""
    late = log.copy()
    late.loc[late.time_s <= 40.0, ["port_rpm", "port_azimuth_deg"]] = np.nan
    late.loc[late.time_s > 40.0, "port_rpm"] = 150.0
    late.loc[late.time_s > 40.0, "port_azimuth_deg"] = 30.0
    for purpose in ("fit", "forecast"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = ingest(late, model.vessel, purpose=purpose)
        j = list(a.channel_names).index("port")
        assert np.all(a.rpm[a.time_s <= 40.0, j] == 0.0) and np.all(a.rpm[a.time_s > 40.0, j] == 150.0)
        assert np.all(a.azimuth_rad[a.time_s <= 40.0, j] == 0.0)
        np.testing.assert_allclose(a.azimuth_rad[a.time_s > 40.0, j], np.radians(30.0))
    p = DynamicPredictor(model.vessel)
    whole, cut = p.forecast(late, [30.0], 20.0), p.forecast(late[late.time_s <= 30.0], [30.0], 20.0)
    np.testing.assert_array_equal(whole.eta, cut.eta)
    # only port had no value yet: the others hold theirs, and the note says so (it read "none
    # logged: 0", as if every channel were taken as 0)
    assert "each channel's last logged value held, 0 for a channel not logged yet" in whole.notes[0]


def test_dp_active_logged_after_a_start_is_not_held_at_it(model, log):
    """dp_active empty at the log's start: the rows before its first value take the default
    (1, station keeping) and are marked as commands not logged, not the later value."""
    late = log.assign(dp_active=np.where(log.time_s <= 20.0, np.nan, 0.0))
    a = ingest(late, model.vessel, purpose="forecast")
    early = a.time_s <= 20.0
    assert np.all(a.dp_active[early] == 1) and np.all(a.dp_active[~early] == 0)
    assert not a.commands_logged[early].any() and a.commands_logged[~early].all()


def test_a_time_range_of_one_instant_is_accepted(model, log):
    """time_range_s = (t, t) is valid (first_s <= last_s): the one sample at t."""
    a = ingest(log, model.vessel, purpose="forecast", time_range_s=(50.0, 50.0))
    assert list(a.time_s) == [50.0]


@pytest.mark.parametrize("column", ["wind_dir_deg", "port_azimuth_deg"])
def test_an_angle_in_centidegrees_is_refused_naming_the_column(model, log, column):
    """Wind direction and azimuth get the heading's degree range: 100 x degrees (centidegrees)
    is refused, for training and forecasting alike, not read as many turns."""
    bad = log.copy()
    bad[column] = (bad[column] % 360.0 + 100.0) * 100.0
    for purpose in ("fit", "forecast"):
        with pytest.raises(LogFormatError, match=rf"^{column}: value .* is outside -360..720 deg; .*centidegrees"):
            ingest(bad, model.vessel, purpose=purpose)
    ok = log.copy()
    ok[column] = ok[column] % 360.0 - 360.0            # any wrap within the range is accepted
    ingest(ok, model.vessel)


@pytest.mark.parametrize("bad", ["ab", (np.nan, 10.0), ("0", "x"), (5.0, 1.0), (1.0,), 3.0])
def test_a_bad_time_range_is_refused_naming_it(model, log, bad):
    with pytest.raises(ValueError, match=r"^time_range_s: expected \(first_s, last_s\)"):
        ingest(log, model.vessel, purpose="forecast", time_range_s=bad)
    assert len(ingest(log, model.vessel, purpose="forecast", time_range_s=(10, 20.0))) == 11


@pytest.mark.parametrize("names", [("lat", "lon"), ("latitude_deg", "longitude_deg"), ("Lat [deg]", "Lon [deg]")])
def test_latitude_and_longitude_instead_of_north_and_east_are_named(model, log, names):
    geo = log.rename(columns={"north_m": names[0], "east_m": names[1]})
    for purpose in ("fit", "forecast"):
        with pytest.raises(LogFormatError, match=r"^north_m: required column missing .*latitude/longitude; the log "
                                                 r"format expects north_m and east_m in metres"):
            ingest(geo, model.vessel, purpose=purpose)


def test_text_in_another_encoding_is_not_called_binary(tmp_path, log):
    csv = log.iloc[:5].to_csv(index=False)
    cases = {"latin1.csv": ("# Bjørnøya\n" + csv).encode("latin-1"), "utf16.csv": csv.encode("utf-16"),
             "binary.csv": b"\x00\x01\xff\xfe\x00" * 50}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
    msg = {name: str(pytest.raises(LogFormatError, read_log, tmp_path / name).value) for name in cases}
    assert "not UTF-8 text (Latin-1 or another encoding?)" in msg["latin1.csv"]
    assert "UTF-16 text: save the file as UTF-8" in msg["utf16.csv"]
    assert "binary data" in msg["binary.csv"]


def _radian_heading_log(n: int = 2600) -> pd.DataFrame:
    """A drifting vessel whose heading is logged in radians: it turns in the first minutes
    (the evidence), then holds about 1 rad (which alone reads as a plausible 1 deg)."""
    t = np.arange(n, dtype=float)
    head = np.where(t < 300.0, t / 300.0 * 6.0, 1.0 + 0.1 * np.sin(t / 50.0))
    return pd.DataFrame({"time_s": t, "north_m": 0.01 * t, "east_m": 0.0, "heading_deg": head, "dp_active": 0})


def test_a_forecast_judges_a_columns_unit_on_the_whole_log_as_training_does(model):
    """The rows a forecast reads may hold no evidence of a unit error that the whole log shows:
    the forecast refuses the log as training does, with the same message."""
    df = _radian_heading_log()
    with pytest.raises(LogFormatError, match="^heading_deg: .*looks like radians") as fit_err:
        ingest(df, model.vessel, purpose="fit")
    with pytest.raises(LogFormatError) as window_err:
        ingest(df, model.vessel, purpose="forecast", time_range_s=(2000.0, 2599.0))
    assert str(window_err.value) == str(fit_err.value)
    with pytest.raises(LogFormatError, match="^heading_deg: .*looks like radians"):
        DynamicPredictor(model.vessel).forecast(df, [2590.0], 5.0)
    ok = df.assign(heading_deg=np.degrees(df.heading_deg))
    assert len(ingest(ok, model.vessel, purpose="forecast", time_range_s=(2000.0, 2599.0))) == 600


def test_a_unit_fault_in_the_rows_read_is_judged_once_on_the_whole_log(model):
    """A forecast leaves the statistical unit checks of the rows it reads to the whole log's
    check (not made twice): a log in knots throughout is still refused with training's
    message, and ``check_log_against_vessel(unit_statistics=False)`` leaves out exactly those
    judgements."""
    from hybridship.logs.io import check_log_against_vessel

    t = np.arange(2600, dtype=float)
    df = pd.DataFrame({"time_s": t, "north_m": 0.5 * t, "east_m": 0.0, "heading_deg": 0.0,
                       "u_m_s": 0.5 * 1.943844, "v_m_s": 0.0, "dp_active": 0})
    with pytest.raises(LogFormatError, match=r"^u_m_s, v_m_s: the logged speed is 1.94 times") as fit_err:
        ingest(df, model.vessel, purpose="fit")
    with pytest.raises(LogFormatError) as window_err:
        ingest(df, model.vessel, purpose="forecast", time_range_s=(2000.0, 2599.0))
    assert str(window_err.value) == str(fit_err.value)
    with pytest.raises(LogFormatError, match=r"^u_m_s, v_m_s: the logged speed"):
        check_log_against_vessel(df, model.vessel)
    check_log_against_vessel(df, model.vessel, unit_statistics=False)
    with pytest.raises(LogFormatError, match=r"^north_m: missing"):     # the other checks stay
        check_log_against_vessel(df.assign(north_m=np.nan), model.vessel, unit_statistics=False)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_training_and_forecasting_see_the_same_arrays(model, log, data):
    """Property: with any heading wrap, gaps and missing optional samples, ``fit`` and
    ``forecast`` read the same arrays, and the rows a forecast reads (``time_range_s``) agree
    with the whole log's: positions, heading (up to whole turns), segments, logged velocities,
    and commands and wind once logged in the rows read."""
    x = log.drop(columns=[c for c in log.columns if c.startswith("truth_")]).iloc[:100].copy()
    x["port_rpm"] = np.linspace(-80.0, 80.0, len(x))
    x["heading_deg"] = x["heading_deg"] + data.draw(st.sampled_from([0.0, 200.0, 345.0]))
    x["heading_deg"] = (x["heading_deg"] % 360.0) - (180.0 if data.draw(st.booleans()) else 0.0)
    for c in ("u_m_s", "r_deg_s", "port_rpm", "wind_speed_m_s"):
        x.loc[data.draw(st.lists(st.integers(0, len(x) - 1), max_size=4, unique=True)), c] = np.nan
    x = x.drop(index=data.draw(st.lists(st.integers(1, len(x) - 2), max_size=4, unique=True))).reset_index(drop=True)
    a, b = ingest(x, model.vessel, purpose="fit"), ingest(x, model.vessel, purpose="forecast")
    for f in ("time_s", "eta", "nu", "rpm", "azimuth_rad", "wind", "dp_active", "segment_id", "commands_logged"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
    lo = data.draw(st.floats(0.0, 60.0))
    w = ingest(x, model.vessel, purpose="forecast", time_range_s=(lo, lo + 30.0))
    sl = slice(int(np.searchsorted(a.time_s, w.time_s[0])), int(np.searchsorted(a.time_s, w.time_s[0])) + len(w))
    np.testing.assert_array_equal(a.time_s[sl], w.time_s)
    np.testing.assert_array_equal(np.diff(a.segment_id[sl]) != 0, np.diff(w.segment_id) != 0)
    d = a.eta[sl] - w.eta
    np.testing.assert_allclose(np.column_stack([d[:, :2], np.angle(np.exp(1j * d[:, 2]))]), 0.0, atol=1e-9)
    np.testing.assert_array_equal(a.nu[sl][a.nu_logged[sl]], w.nu[w.nu_logged])
    for f, col in (("rpm", "port_rpm"), ("wind", "wind_speed_m_s")):
        first = int(np.argmax(np.isfinite(x[col].to_numpy()[sl])))
        np.testing.assert_array_equal(getattr(a, f)[sl][first:], getattr(w, f)[first:], err_msg=f)


def _port_rpm_from_40_s(model, log):
    """The log ingested for fitting with ``port_rpm`` first logged after 40 s, and as it is."""
    late = log.copy()
    late.loc[late.time_s <= 40.0, "port_rpm"] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ingest(late, model.vessel, purpose="fit"), ingest(log, model.vessel, purpose="fit")


def test_rows_before_a_command_is_first_logged_are_not_trained_on(model, log):
    """The nets never learn from the rows whose commands are the default of an empty cell
    (a thruster taken as stopped while it ran): only rows with every command logged at i,
    i - 1 and i - 2 are trainable, and whose bias (known at i - 2) has a residual of a
    logged step (here the first at 42 s) in it."""
    from hybridship.residual.features import prepare_log

    a, whole = _port_rpm_from_40_s(model, log)
    rows = prepare_log(model, a).trainable_rows()
    assert rows.size and a.time_s[rows].min() > 43.0
    np.testing.assert_array_equal(rows, [r for r in prepare_log(model, whole).trainable_rows()
                                         if a.time_s[r] > 43.0])


def test_trainable_rows_have_the_features_of_a_log_with_every_command_logged(model, log):
    """Every trainable row's features and target are those of the same log with the command
    logged from its start: the previous residual of the first rows after a command's first
    value was computed with the stopped thruster of the empty cells (and the command rate
    jumped from 0), and such a row was trained on."""
    from hybridship.residual.features import ResidualConfig, prepare_log

    a, whole = _port_rpm_from_40_s(model, log)
    cfg = ResidualConfig(bias_window_s=0.0, features=ResidualConfig().features + ("rpm_main_rate_rel_s",))
    p, w = prepare_log(model, a, cfg), prepare_log(model, whole, cfg)
    rows = p.trainable_rows()
    assert rows.size
    np.testing.assert_allclose(p.features(rows), w.features(rows), rtol=0, atol=1e-12)
    np.testing.assert_allclose(p.deviation(rows), w.deviation(rows), rtol=0, atol=1e-12)


def test_the_bias_leaves_out_residuals_of_steps_with_a_command_not_logged(model, log):
    """The causal bias (the mean residual of the last ``bias_window_s``) of a log the model made
    is zero where the commands were logged: the residuals of the steps before a command's
    first value, made with the stopped thruster of the empty cells, are no part of it (they
    shifted the bias, and the training targets and forecasts with it, for the whole window)."""
    from hybridship.residual.features import prepare_log

    a, whole = _port_rpm_from_40_s(model, log)
    p, w = prepare_log(model, a), prepare_log(model, whole)
    after = a.time_s > 41.0
    assert np.abs(w.bias_ned[after]).max() < 1e-6
    assert np.isfinite(p.bias_ned[after]).all()
    np.testing.assert_allclose(p.bias_ned[after], 0.0, atol=1e-6)


def test_the_start_deviation_leaves_out_residuals_of_steps_with_a_command_not_logged(model, log):
    """``start_residual_window_s``: the start's previous deviation of a log the model made is
    zero where the commands were logged, not the residual of a step run with the stopped
    thruster of a command's empty cells."""
    from hybridship.residual.features import ResidualConfig, prepare_log

    late = log.copy()
    late.loc[late.time_s <= 40.0, "port_rpm"] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = ingest(late, model.vessel, purpose="fit")
    p = prepare_log(model, a, ResidualConfig(bias_window_s=0.0, start_residual_window_s=10.0))
    for t in (41.0, 45.0, 60.0):
        np.testing.assert_allclose(p.start_state(int(np.flatnonzero(a.time_s == t)[0]))[2], 0.0, atol=1e-6)
