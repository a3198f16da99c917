"""Input validation of logs (issue 9): units, ranges, sign conventions, vessel match, no mutation.

Each bad input is a well-formed log with one realistic mistake injected; the test checks
that it is refused and that the message names the field, the row or time where there is
one, and what was expected (or which unit mix-up it looks like).
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pandas as pd
import pytest

from hybridship.forecast_inputs import forecast_log_arrays
from hybridship.frames import ned_to_body
from hybridship.logs.ingest import sort_samples
from hybridship.logs.io import (LogFormatError, LogFormatWarning, check_log_against_vessel, log_to_arrays,
                                read_log, speed_scale_vs_track, validate_log, write_log)
from hybridship.sim.synthetic import physics_log

THRUSTERS = ["tunnel", "port", "stbd"]
ROTATABLE = [False, True, True]


@pytest.fixture(scope="module")
def moving_log(model):
    """A noise-free log of a ship moving (rpm up to 60 % of max, no shutdown): 20-s
    displacements of several metres, so the velocity checks can decide."""
    return physics_log(model, seed=3, duration_s=400.0, t_shutdown_s=None, rpm_scale=0.6)


@pytest.fixture(scope="module")
def drift_log(model):
    """A log with a DP failure: after it the rpm decay to nearly zero for minutes."""
    return physics_log(model, seed=4, duration_s=400.0, t_shutdown_s=200.0)


def _refused(df, pattern, **kw):
    before = df.copy(deep=True)
    with pytest.raises(LogFormatError, match=pattern) as info:
        validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE, **kw)
    pd.testing.assert_frame_equal(df, before)  # never modified, also when refusing
    return info.value


# ----------------------------------------------------------------------------- units


def test_the_clean_log_passes(moving_log, model):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        validate_log(moving_log, channel_names=THRUSTERS, rotatable=ROTATABLE)
        check_log_against_vessel(moving_log, model.vessel)
    sc = speed_scale_vs_track(moving_log.time_s, moving_log.north_m, moving_log.east_m, moving_log.heading_deg,
                              moving_log.u_m_s, moving_log.v_m_s)
    assert sc.rms_displacement_m > 5.0 and sc.correlation > 0.99 and abs(sc.scale - 1.0) < 0.01


@pytest.mark.parametrize("factor, unit", [(1.0 / 0.514444, "knots"), (3.6, "km/h")])
def test_speeds_in_knots_or_km_h_are_refused_naming_the_unit(moving_log, factor, unit):
    df = moving_log.assign(u_m_s=moving_log.u_m_s * factor, v_m_s=moving_log.v_m_s * factor)
    assert df.u_m_s.abs().max() < 30.0          # the 30 m/s range check alone would not see it
    err = _refused(df, rf"u_m_s, v_m_s: the logged speed is {factor:.3g} times the speed of the track.*"
                       rf"looks like {unit}")
    assert err.column == "u_m_s"


def test_positions_in_degrees_are_refused(moving_log):
    df = moving_log.assign(north_m=63.4 + moving_log.north_m / 111_000.0, east_m=10.4 + moving_log.east_m / 50_000.0)
    _refused(df, r"u_m_s, v_m_s: .*north_m/east_m hardly move: positions in degrees of latitude/longitude\?")


def test_positions_in_feet_are_refused_as_too_slow_a_speed(moving_log):
    """A logged speed well below the track's (0.3 x: north_m, east_m in feet) is refused too."""
    df = moving_log.assign(north_m=moving_log.north_m / 0.3048, east_m=moving_log.east_m / 0.3048)
    err = _refused(df, r"u_m_s, v_m_s: the logged speed is 0\.30\d times the speed of the track.*positions in feet\?")
    assert err.column == "u_m_s"

def test_speed_check_stays_quiet_when_velocities_do_not_describe_the_track(moving_log):
    # A shuffled velocity column has nothing to do with the track: no unit can be
    # inferred, so no unit error is claimed (the check only speaks when shapes agree).
    rng = np.random.default_rng(0)
    df = moving_log.assign(u_m_s=rng.permutation(moving_log.u_m_s.to_numpy()) * 1.94)
    validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE)


def test_yaw_rate_in_rad_s_is_refused(moving_log):
    df = moving_log.assign(r_deg_s=np.radians(moving_log.r_deg_s))
    err = _refused(df, r"r_deg_s: is 0\.01\d+ times the rate of change of heading_deg .*looks like rad/s")
    assert err.column == "r_deg_s"


def _turning_track(t_s, speed_m_s):
    """A ship heading 100 +- 20 deg (a slow sine) while moving north at ``speed_m_s``, sampled at
    ``t_s`` [s]: heading, yaw rate [deg/s] and body velocities [m/s] exactly consistent with the track."""
    psi_deg = 100.0 + 20.0 * np.sin(t_s / 40.0)
    vel_body = ned_to_body(np.column_stack([np.full_like(t_s, speed_m_s), 0.0 * t_s, 0.0 * t_s]), np.radians(psi_deg))
    return pd.DataFrame({"time_s": t_s, "north_m": speed_m_s * t_s, "east_m": 0.0, "heading_deg": psi_deg,
                         "u_m_s": vel_body[:, 0], "v_m_s": vel_body[:, 1], "r_deg_s": 0.5 * np.cos(t_s / 40.0),
                         "dp_active": 0})


@pytest.mark.parametrize("rate_hz, to_unit, unit", [(1.0, 1.0 / 60.0, "minutes"), (50.0, 1e3, "milliseconds")])
def test_time_in_minutes_or_milliseconds_is_refused_where_the_ship_moves(rate_hz, to_unit, unit):
    """time_s in minutes at 1 Hz or in milliseconds at 50 Hz (spacings 1/60 and 20, both inside the
    plausible range): every rate is off by the unit's factor. The yaw rate alone would read as
    rad/s in minutes (pi/180 is 5 % from 1/60); the speeds, which move the ship along the track
    only with time_s in seconds, decide that the time column is off."""
    df = _turning_track(np.arange(0.0, 400.0, 1.0 / rate_hz), speed_m_s=0.5)
    validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE)         # in seconds it passes
    bad = df.assign(time_s=df.time_s * to_unit)
    err = _refused(bad, rf"time_s: looks like {unit}: r_deg_s is {re.escape(f'{to_unit:.3g}')} times the rate of "
                        rf"change of heading_deg .*time_s x {re.escape(f'{1 / to_unit:g}')} \(as seconds\)")
    assert err.column == "time_s"
    # without a yaw rate the speed check names the time column: 400 samples in minutes hold no
    # 20-minute window; in milliseconds the track moves 1000 times too slowly for the speeds
    what = "no 20-s window of the track" if unit == "minutes" else r"u_m_s, v_m_s are 1e\+03 times the speed"
    err = _refused(bad.drop(columns="r_deg_s"), rf"time_s: looks like {unit}: {what}")
    assert err.column == "time_s"


def test_time_in_minutes_on_station_is_named_beside_rad_s():
    """On station the track does not move: the yaw rate alone cannot tell rad/s from minutes, and
    the message says both."""
    df = _turning_track(np.arange(400.0), speed_m_s=0.0)
    validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    err = _refused(df.assign(time_s=df.time_s / 60.0),
                   r"r_deg_s: is 0\.0167 times .*looks like rad/s.*or, if r_deg_s is in deg/s, time_s is in minutes")
    assert err.column == "r_deg_s"


def test_a_yaw_rate_converted_to_deg_s_twice_is_refused():
    """A slow turn (at most 0.5 deg/s) whose rate was converted from rad/s to deg/s once too
    often (57.3 x) stays below the 60 deg/s range check: the rate of change of the heading
    refuses it. (The moving log turns faster, so the range check sees it there first.)"""
    t = np.arange(400.0)
    df = pd.DataFrame({"time_s": t, "north_m": 0.5 * t, "east_m": 0.0,
                       "heading_deg": 100.0 + 20.0 * np.sin(t / 40.0), "r_deg_s": 0.5 * np.cos(t / 40.0),
                       "dp_active": 0})
    validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE)         # the exact derivative passes
    twice = df.assign(r_deg_s=np.degrees(df.r_deg_s))
    assert twice.r_deg_s.abs().max() < 30.0
    err = _refused(twice, r"r_deg_s: is 57\.3 times the rate of change of heading_deg .*converted from rad/s twice\?")
    assert err.column == "r_deg_s"


def test_yaw_rate_sign_convention_is_checked(moving_log):
    _refused(moving_log.assign(r_deg_s=-moving_log.r_deg_s),
             r"r_deg_s: has the opposite sign .*positive clockwise.*counter-clockwise / ENU")



def test_a_noisy_yaw_rate_with_the_opposite_sign_is_refused(moving_log):
    """A reversed yaw rate is refused also when sensor noise weakens its correlation with the
    heading's rate well below -1 (about -0.6 here)."""
    r = moving_log.r_deg_s.to_numpy()
    noise = np.random.default_rng(7).normal(0.0, 1.3 * np.std(r), r.size)
    _refused(moving_log.assign(r_deg_s=-r + noise), r"r_deg_s: has the opposite sign .*\(correlation -0\.[3-8]\d\)")

@pytest.mark.parametrize("scale, hint", [(1000.0 * np.pi / 180.0, "milliradians"), (100.0, "centidegrees")])
def test_heading_out_of_degree_range_is_refused(moving_log, scale, hint):
    df = moving_log.assign(heading_deg=moving_log.heading_deg * scale)
    err = _refused(df, rf"heading_deg: value [\d.e+]+ at row \d+ \(time_s [\d.]+\) is outside -360\.\.720.*{hint}")
    assert err.row is not None and err.time_s == df.time_s[err.row]


def test_heading_in_radians_is_refused(moving_log):
    _refused(moving_log.assign(heading_deg=np.radians(moving_log.heading_deg)),
             r"heading_deg: .*looks like radians.*expects degrees")


def test_heading_and_yaw_rate_both_in_radians_are_refused_by_the_track(moving_log):
    """A heading and its rate both converted to radians agree with each other, so the angle
    rules cannot see it; the logged velocities turned by that heading leave the track, and
    turned by the same values read as radians they follow it: refused as radians, naming
    heading_deg. A ship on a heading of 186 deg, logged as 3.25 (rad), was forecast with a
    heading of 3.25 deg."""
    df = moving_log.assign(heading_deg=np.radians(np.mod(moving_log.heading_deg + 186.0, 360.0)),
                           r_deg_s=np.radians(moving_log.r_deg_s))
    c, s = np.cos(np.radians(186.0)), np.sin(np.radians(186.0))          # the track turned with it
    df = df.assign(north_m=c * moving_log.north_m - s * moving_log.east_m,
                   east_m=s * moving_log.north_m + c * moving_log.east_m)
    _refused(df, r"^heading_deg: looks like radians \(with r_deg_s in rad/s too\?\): u_m_s, v_m_s turned into "
                 r"north/east with heading_deg as degrees move \d+ deg away from the track .*, as radians [0-9] deg")
    ok = df.assign(heading_deg=np.mod(moving_log.heading_deg + 186.0, 360.0), r_deg_s=moving_log.r_deg_s)
    sc = speed_scale_vs_track(ok.time_s, ok.north_m, ok.east_m, ok.heading_deg, ok.u_m_s, ok.v_m_s)
    assert sc.misfit_deg < 1.0 and sc.correlation > 0.99                # in degrees: on the track
    validate_log(ok, channel_names=THRUSTERS, rotatable=ROTATABLE)
    # a sensor fault over most of the log (a biased sway log) fits neither reading: left to the
    # forecasts' velocity_mismatch flag, not refused for the whole log
    validate_log(ok.assign(v_m_s=np.where(ok.time_s >= 100.0, ok.v_m_s + 1.0, ok.v_m_s)),
                 channel_names=THRUSTERS, rotatable=ROTATABLE)


@pytest.mark.parametrize("mistake, column, hint", [
    ("swap", "north_m", r"are they swapped \(an east/north or ENU frame\)\?"),
    ("u", "u_m_s", r"u_m_s positive forward: is its sign reversed\?"),
    ("v", "v_m_s", r"v_m_s positive to starboard: is its sign reversed \(positive to port\)\?")])
def test_positions_swapped_or_a_velocity_sign_reversed_are_refused_by_the_track(moving_log, drift_log, model,
                                                                                   mistake, column, hint):
    """North and east swapped (an ENU or x-east frame) or u or v logged with the other sign:
    the velocities turned into north/east leave the track (tens of degrees), and read the
    other way they follow it. Passed before, to be forecast (and trained) in a mirrored
    frame: on a drift of 0.2 m/s the start window's velocity_mismatch (8 m in 30 s) never
    fired, and a 30-s forecast missed by 6-8 m where the clean log's missed by 1 m."""
    for log in (moving_log, drift_log):
        if mistake == "swap":
            df = log.assign(north_m=log.east_m, east_m=log.north_m)
        else:
            df = log.assign(**{column: -log[column]})
        err = _refused(df, rf"^{'north_m, east_m' if mistake == 'swap' else column}: u_m_s, v_m_s turned into "
                           rf"north/east with heading_deg move \d+ deg away from the track .*, but [0-9] deg "
                           rf"with .* read the other way .*{hint}")
        assert err.column == column
        with pytest.raises(LogFormatError, match=hint):
            check_log_against_vessel(df, model.vessel)


def test_azimuth_and_wind_direction_in_radians_are_refused(moving_log):
    _refused(moving_log.assign(port_azimuth_deg=np.radians(moving_log.port_azimuth_deg)),
             r"port_azimuth_deg: values span .*looks like radians.*expects degrees")
    t = moving_log.time_s.to_numpy()
    veering = np.radians(np.mod(200.0 + 1.0 * t, 360.0))  # a wind veering through north, in radians
    _refused(moving_log.assign(wind_dir_deg=veering), r"wind_dir_deg: values span .*looks like radians")


def test_time_in_milliseconds_is_refused(moving_log):
    err = _refused(moving_log.assign(time_s=moving_log.time_s * 1000.0),
                   r"time_s: median sample spacing 1000 .*expects seconds.*milliseconds")
    assert err.column == "time_s"
    # the other side of the accepted spacing: a 1-Hz log's time in hours (1/3600 per sample)
    # is not called milliseconds
    err = _refused(moving_log.assign(time_s=moving_log.time_s / 3600.0),
                   r"time_s: median sample spacing 0\.000277778 .*expects seconds.*is time_s in minutes or hours\?")
    assert err.column == "time_s"


def test_missing_required_column_points_at_a_unit_variant(moving_log):
    df = moving_log.rename(columns={"heading_deg": "heading_rad"})
    df["heading_rad"] = np.radians(df["heading_rad"])
    _refused(df, r"heading_deg: required column missing .*found 'heading_rad', which looks like heading_deg "
                 r"in another unit")


def test_a_table_hybridship_wrote_is_not_read_as_a_log(moving_log):
    """A forecast table (it has time_s, north_m, ... besides start_time_s and lead_s) or a
    benchmark's table left in a folder of logs is refused as what it is, not for a missing
    thruster column or time_s."""
    forecast = moving_log[["time_s", "north_m", "east_m", "heading_deg"]].assign(start_time_s=0.0, lead_s=0.0)
    forecast = forecast[["start_time_s", "lead_s", *forecast.columns[:-2]]]            # its header, as written
    _refused(forecast, r"not a log: a forecast table written by 'hybridship forecast' \(its header has lead_s, "
                       r"start_time_s\); keep such outputs out of a folder of logs")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LogFormatWarning)                 # columns the format does not know
        validate_log(moving_log.assign(start_time_s=0.0, lead_s=0.0), channel_names=THRUSTERS, rotatable=ROTATABLE)
    coverage = pd.DataFrame({"model": ["hybrid"], "horizon_s": [60], "sigma": [2], "coverage": [0.95]})
    _refused(coverage, r"not a log: a table written by a hybridship benchmark")


def test_missing_required_column_suggests_a_misspelt_or_bare_name_and_lists_a_few_columns(moving_log):
    _refused(moving_log.rename(columns={"north_m": "nort_m"}), r"found 'nort_m': did you mean 'north_m'\?")
    _refused(moving_log.rename(columns={"heading_deg": "Heading_deg"}),
             r"found 'Heading_deg': did you mean 'heading_deg'")
    _refused(moving_log.rename(columns={"heading_deg": "heading"}),
             r"found 'heading', which may be heading_deg: name it so if it is in degrees, else convert it")
    wide = moving_log.drop(columns=["north_m"]).assign(**{f"extra_{i}": 0.0 for i in range(30)})
    err = _refused(wide, r"found: time_s, .*\.\.\. \(\d+ more\)\)")
    assert "extra_29" not in str(err)


def test_optional_column_in_another_unit_is_named_in_the_warning(moving_log):
    # a wind speed in knots beside the direction: refused (read as no wind it would be calm)
    df = moving_log.rename(columns={"wind_speed_m_s": "wind_speed_kn"})
    _refused(df, r"wind_speed_m_s: missing while wind_dir_deg is logged.*found 'wind_speed_kn', which looks like "
                 r"wind_speed_m_s in another unit")
    # an optional column alone in another unit is named in the warning
    df = moving_log.drop(columns=["wind_speed_m_s", "wind_dir_deg"]).rename(columns={"u_m_s": "u_kn"})
    with pytest.warns(LogFormatWarning, match=r"u_kn \(looks like u_m_s in another unit"):
        validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE)


def test_strictly_increasing_time_names_row_and_time(moving_log):
    df = moving_log.copy()
    df.loc[40, "time_s"] = 38.5
    err = _refused(df, r"time_s: not strictly increasing at row 40 \(time_s 38\.5 after 39\)")
    assert (err.column, err.row, err.time_s) == ("time_s", 40, 38.5)


def test_missing_required_values_refused_unless_allowed(moving_log):
    df = moving_log.copy()
    df.loc[12, "east_m"] = np.nan
    df.loc[13, "heading_deg"] = np.inf
    err = _refused(df, r"east_m: missing or non-finite value \(nan\) at row 12 \(time_s 12\)")
    assert (err.row, err.time_s) == (12, 12.0)
    validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE, allow_missing=True)
    arr = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE, allow_missing=True)
    assert np.isnan(arr.eta[12, 1]) and np.isnan(arr.eta[13, 2])
    # the heading is unwrapped over the finite samples: a NaN does not poison the rest
    assert np.isfinite(arr.eta[14:, 2]).all()
    np.testing.assert_allclose(np.diff(arr.eta[14:, 2]), np.radians(np.diff(moving_log.heading_deg[14:])
                                                                     + 180.0) % (2 * np.pi) - np.pi, atol=1e-9)
    # other formats errors are still refused in that mode
    bad = df.assign(u_m_s=df.u_m_s * 3.6)
    with pytest.raises(LogFormatError, match="km/h"):
        validate_log(bad, channel_names=THRUSTERS, rotatable=ROTATABLE, allow_missing=True)


# ----------------------------------------------------------------------------- vessel


def test_check_log_against_vessel_accepts_good_logs(model, moving_log, tmp_path):
    check_log_against_vessel(moving_log, model.vessel)
    check_log_against_vessel(moving_log, "gunnerus")
    path = tmp_path / "log.csv"
    write_log(moving_log, path)
    check_log_against_vessel(path, model.vessel)
    drift = moving_log[["time_s", "north_m", "east_m", "heading_deg"]].assign(dp_active=0)
    check_log_against_vessel(drift, model.vessel)     # no thrusters logged, none running


def _vessel_refused(model, df, pattern):
    before = df.copy(deep=True)
    with pytest.raises(LogFormatError, match=pattern) as info:
        check_log_against_vessel(df, model.vessel)
    pd.testing.assert_frame_equal(df, before)
    return info.value


def test_a_repeated_time_s_or_a_two_level_header_is_refused_by_fit_and_forecast(model, moving_log):
    """Review: a second ``time_s`` column reached pandas in fit and forecast ("arg must be a
    list, tuple, 1-d array, or Series"), and a MultiIndex header pandas' to_numeric."""
    from hybridship.logs.ingest import ingest

    twice = pd.concat([moving_log, moving_log[["time_s"]]], axis=1)
    levels = moving_log.set_axis(pd.MultiIndex.from_tuples([(c, "") for c in moving_log.columns]), axis=1)
    for df, pattern in ((twice, r"time_s: column appears more than once"),
                        (levels, r"columns: expected one row of column names, got 2 levels")):
        before = df.copy(deep=True)
        for purpose in ("fit", "forecast"):
            with pytest.raises(LogFormatError, match=pattern):
                ingest(df, model.vessel, purpose=purpose)
            with pytest.raises(LogFormatError, match=pattern):
                ingest(df, model.vessel, purpose=purpose, time_range_s=(10.0, 50.0))
        pd.testing.assert_frame_equal(df, before)


def test_channel_names_must_match_the_vessel(model, moving_log):
    _vessel_refused(model, moving_log.rename(columns={"port_rpm": "ps_rpm"}),
                    r"ps_rpm: names unknown thruster or rudder 'ps'; the vessel's thrusters and rudders: tunnel, port, "
                    r"stbd .*the vessel "
                    r"used is 'gunnerus': is the log from another vessel\? use its vessel file")


def test_rpm_beyond_max_is_refused_as_a_unit_error(model, moving_log):
    df = moving_log.copy()
    df.loc[77, "stbd_rpm"] = 1000.0
    err = _vessel_refused(model, df, r"stbd_rpm: value 1000 at row 77 \(time_s 77\) exceeds 1\.25 x max_rpm "
                                     r"\(217 rpm\) of thruster 'stbd' of vessel 'gunnerus'")
    assert (err.column, err.row, err.time_s) == ("stbd_rpm", 77, 77.0)
    # the bound is on the magnitude: a thruster reversed at motor rpm is as wrong (an azimuth
    # thruster may push astern, so a negative value alone is no fault)
    df.loc[77, "stbd_rpm"] = -1000.0
    err = _vessel_refused(model, df, r"stbd_rpm: value -1000 at row 77 \(time_s 77\) exceeds 1\.25 x max_rpm "
                                     r"\(217 rpm\) of thruster 'stbd' of vessel 'gunnerus' in magnitude")
    assert (err.column, err.row) == ("stbd_rpm", 77)


def test_rpm_logged_as_a_fraction_is_refused(model, moving_log, drift_log):
    """Every thruster's rpm within +-1 over station keeping with thrust is a fraction of
    max_rpm, not rpm; the decay towards zero after a failure is not counted."""
    fractions = moving_log.assign(**{f"{t.name}_rpm": moving_log[f"{t.name}_rpm"] / t.max_rpm
                                     for t in model.vessel.thrusters})
    _vessel_refused(model, fractions, r"tunnel_rpm: every thruster's rpm is within \+-1 .* not a fraction of max_rpm")
    check_log_against_vessel(drift_log, model.vessel)
    assert (drift_log.dp_active == 0).sum() >= 60
    # the simulated decay reaches exactly 0 rpm (no thrust: never counted), so the drift alone
    # with its rpm spinning down through +-1 (a sensor's residual reading) is what tells
    # "station keeping only" from "every sample": not refused, though every value is within +-1
    drift = drift_log[drift_log.dp_active == 0].reset_index(drop=True)
    spin_down = 0.9 * np.exp(-(drift.time_s - drift.time_s[0]) / 60.0)
    drift = drift.assign(**{f"{t.name}_rpm": spin_down for t in model.vessel.thrusters})
    assert len(drift) >= 60 and (drift[[f"{t.name}_rpm" for t in model.vessel.thrusters]] != 0).all().all()
    check_log_against_vessel(drift, model.vessel)


def test_rpm_logged_as_a_fraction_reaching_full_thrust_is_refused(model, moving_log):
    """Fractions of max_rpm that reach full thrust (exactly +-1) are still fractions."""
    frac = moving_log.assign(**{f"{t.name}_rpm": moving_log[f"{t.name}_rpm"] / moving_log[f"{t.name}_rpm"].abs().max()
                                for t in model.vessel.thrusters})
    assert frac[[f"{t.name}_rpm" for t in model.vessel.thrusters]].abs().max().max() == 1.0
    _vessel_refused(model, frac, r"tunnel_rpm: every thruster's rpm is within \+-1 \(largest 1\)")

def test_some_thrusters_rpm_logged_as_fractions_are_warned_about(model, moving_log):
    """Port and stbd logged as fractions of max_rpm, the tunnel in rpm: the all-thrusters rule
    cannot see it (the tunnel exceeds 1), and a 60-s forecast after a failure went wrong
    without a word. Each such thruster is named in a warning (a stopped thruster's sensor
    noise looks the same, so it is not refused); the clean log warns of nothing."""
    df = moving_log.assign(**{f"{t.name}_rpm": moving_log[f"{t.name}_rpm"] / t.max_rpm
                              for t in model.vessel.thrusters if t.name != "tunnel"})
    assert df.tunnel_rpm.abs().max() > 1.0
    with pytest.warns(LogFormatWarning) as record:
        check_log_against_vessel(df, model.vessel)
    said = [str(w.message) for w in record if issubclass(w.category, LogFormatWarning)]
    for name in ("port", "stbd"):
        assert any(re.match(rf"{name}_rpm: within \+-1 \(largest 0\.\d+\) in all \d+ of its non-zero samples "
                            rf"of station keeping, while tunnel_rpm reaches .*a fraction of max_rpm\?", m)
                   for m in said), said
    with warnings.catch_warnings():
        warnings.simplefilter("error", LogFormatWarning)
        check_log_against_vessel(moving_log, model.vessel)


def test_rpm_sign_convention_is_checked(model, moving_log):
    df = moving_log.assign(port_rpm=-moving_log.port_rpm.abs() - 1.0)
    _vessel_refused(model, df, r"port_rpm: negative in all \d+ non-zero samples .*rotation direction")
    # a tunnel thruster may push one way for a whole log: not checked
    check_log_against_vessel(moving_log.assign(tunnel_rpm=-moving_log.tunnel_rpm.abs() - 1.0), model.vessel)


def test_incomplete_thruster_logging_is_refused(model, moving_log, drift_log):
    _vessel_refused(model, moving_log.drop(columns="stbd_azimuth_deg"),
                    r"stbd_azimuth_deg: missing while stbd_rpm is logged; .*azimuth thruster")
    _vessel_refused(model, moving_log.drop(columns="tunnel_rpm"),
                    r"tunnel_rpm: missing while port_rpm, stbd_rpm are logged")
    no_rpm = moving_log.drop(columns=[c for c in moving_log if c.endswith(("_rpm", "_azimuth_deg"))])
    _vessel_refused(model, no_rpm, r"tunnel_rpm: no thruster rpm columns while dp_active is 1 at row 0")
    _vessel_refused(model, no_rpm.drop(columns="dp_active"), r"dp_active is absent \(taken as 1\)")
    # station keeping in part of the log is enough (here rows 30..199, a drift before and after):
    # the message names its first row
    part = drift_log.drop(columns=[c for c in drift_log if c.endswith(("_rpm", "_azimuth_deg"))])
    part.loc[:29, "dp_active"] = 0
    assert (part.dp_active == 0).sum() > (part.dp_active == 1).sum() > 0
    _vessel_refused(model, part, r"tunnel_rpm: no thruster rpm columns while dp_active is 1 at row 30 \(time_s 30\)")


# ----------------------------------------------------------------------------- no mutation


def test_no_function_modifies_the_callers_data(model, moving_log, tmp_path):
    df = moving_log.copy()
    df.loc[5, "north_m"] = np.nan                 # a sensor fault, tolerated at forecast time
    df = pd.concat([df.iloc[:50], df.iloc[[51, 50]], df.iloc[52:]])  # out of order
    before = df.copy(deep=True)
    path = tmp_path / "log.csv"
    moving_log.to_csv(path, index=False)
    file_before = path.read_bytes()

    order = sort_samples(df)
    arr, _ = forecast_log_arrays(df, model.vessel)
    arr2, _ = forecast_log_arrays(path, model.vessel)
    check_log_against_vessel(path, model.vessel)
    clean = order.frame.copy()
    clean_before = clean.copy(deep=True)
    validate_log(clean, channel_names=THRUSTERS, rotatable=ROTATABLE, allow_missing=True)
    arr3 = log_to_arrays(clean, channel_names=THRUSTERS, rotatable=ROTATABLE, allow_missing=True)
    write_log(moving_log, tmp_path / "out.csv")
    read_log(path)

    pd.testing.assert_frame_equal(df, before, check_exact=True)
    pd.testing.assert_frame_equal(clean, clean_before, check_exact=True)
    assert path.read_bytes() == file_before
    # the arrays are copies: writing to the frame afterwards does not change them
    eta = arr3.eta.copy()
    clean.loc[:, "north_m"] = 0.0
    np.testing.assert_array_equal(arr3.eta, eta)
    assert not np.shares_memory(arr.eta, df["north_m"].to_numpy())
    assert arr2.eta.flags.writeable is False
    # LogArrays built from the caller's arrays hold read-only copies: the caller's stay writeable
    # (review: they were frozen in place), and a change to them cannot reach checked data
    from dataclasses import fields

    mine = {f.name: getattr(arr3, f.name).copy() if isinstance(getattr(arr3, f.name), np.ndarray)
            else getattr(arr3, f.name) for f in fields(arr3)}
    built = type(arr3)(**mine)
    assert all(v.flags.writeable for v in mine.values() if isinstance(v, np.ndarray))
    assert built.eta.flags.writeable is False and not np.shares_memory(built.eta, mine["eta"])


def test_read_log_without_validation_returns_the_raw_frame(tmp_path, moving_log):
    df = moving_log.copy()
    df.loc[3, "time_s"] = 1.0  # repeated time: refused by validation
    path = tmp_path / "raw.csv"
    df.to_csv(path, index=False)
    with pytest.raises(LogFormatError, match="time_s: not strictly increasing at row 3"):
        read_log(path)
    raw = read_log(path, validate=False)
    assert raw.loc[3, "time_s"] == 1.0


def test_rudder_angles_are_command_channels():
    from hybridship.vessel import load_vessel

    v = load_vessel("esso_osaka_model")
    t = np.arange(100.0)
    df = pd.DataFrame(dict(time_s=t, north_m=3.0 * t, east_m=0.0, heading_deg=10.0 + 0.01 * t, propeller_rpm=600.0,
                           rudder_azimuth_deg=np.linspace(-20.0, 20.0, 100)))
    check_log_against_vessel(df, v)                      # a rudder has no rpm column: not "missing"
    with pytest.raises(LogFormatError, match=r"rudder_azimuth_deg: missing while thruster rpm are logged"):
        check_log_against_vessel(df.drop(columns="rudder_azimuth_deg"), v)
