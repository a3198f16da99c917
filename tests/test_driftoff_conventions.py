"""Drift-off analysis against known answers: the meaning of each statistic's column (10/50/90 %
times, the watch circle, operability at its limit), the direction conventions of wind,
current and load (radii alone are blind to direction on a mirror-symmetric hull, so tracks
are checked), that each source of randomness reaches the samples, and what live mode takes
from a log.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from hybridship.driftoff import engine
from hybridship.driftoff.live import EnvironmentEstimate, blackout_now, environment_from_log
from hybridship.driftoff.planning import DriftOffResult, DriftOffSettings, simulate_blackouts
from hybridship.driftoff.season import SeasonResult, run_chunk
from hybridship.driftoff.weather import WeatherState, read_weather_table, states_to_frame

NOMINAL = dict(n_samples=1, horizon_s=60.0, radii_m=(5.0,), reaction_times_s=(30.0,), vessel_spread=0.0)


def _result(t_reach, excursion=None):
    """A hand-made one-heading, one-radius, one-reaction-time result."""
    t = np.asarray(t_reach, float)[None, :, None]
    exc = np.zeros((1, t.shape[1], 1)) if excursion is None else np.asarray(excursion, float)[None, :, None]
    return DriftOffResult(np.zeros(1), np.zeros(1), np.array([5.0]), np.array([30.0]), t, exc, 100.0)


# -- statistics and tables ---------------------------------------------------------------

def test_summary_columns_hold_the_10_50_90_percent_times():
    """Kills: planning.summary_frames with t_p10 / t_p90 swapped (P4)."""
    times, _ = _result(np.arange(1.0, 11.0)).summary_frames()
    assert times[["t_p10_s", "t_p50_s", "t_p90_s"]].to_numpy()[0].tolist() == [1.0, 5.0, 9.0]


def test_season_quantiles_are_the_states_own_10_50_90_percent_times():
    """Kills: season.run_chunk asking for (0.9, 0.5, 0.1) (Se2): the season table's t_p10 is
    the 10 % time of simulate_blackouts for that state."""
    st = DriftOffSettings(n_samples=6, horizon_s=120.0, radii_m=(3.0,), reaction_times_s=(30.0,), seed=2)
    w = WeatherState.from_degrees(wind_speed_m_s=12.0, wind_dir_deg=90.0)
    out = run_chunk("gunnerus", [w], [0], np.array([0.0]), None, st, 0.9)
    want = simulate_blackouts("gunnerus", w, [0.0], settings=st, index=0).time_quantiles((0.1, 0.5, 0.9))
    assert np.all(np.isfinite(want)) and want[0, 0, 0] < want[0, 0, 2]
    np.testing.assert_array_equal(out["t_quantiles_s"][0], want)


def test_watch_circle_is_the_upper_quantile_of_the_excursion():
    """Kills: watch_circle taking the (1 - q) quantile (P7): 90 % of the samples stay inside."""
    res = _result(np.full(101, np.inf), excursion=np.arange(101.0))
    assert res.watch_circle(0.9)[0, 0] == pytest.approx(90.0)
    assert res.watch_circle(0.5)[0, 0] == pytest.approx(50.0)


@pytest.mark.parametrize("n", [7, 15, 25, 101])
def test_at_least_the_watch_circles_share_of_the_samples_stays_inside_it(n):
    """An interpolated quantile (numpy's default) put the 0.9 watch circle of 7 samples between
    the 6th and 7th excursion: 6 of 7 (86 %) inside a circle said to hold 90 %."""
    exc = np.arange(1.0, n + 1.0)
    for q in (0.5, 0.9, 0.95):
        w = _result(np.full(n, np.inf), excursion=exc).watch_circle(q)[0, 0]
        assert np.mean(exc <= w) >= q
        assert np.mean(exc < w) < q            # and the smallest such circle


def test_operability_counts_a_p_exceed_equal_to_the_limit_as_operable():
    """Kills: operability with ``<`` instead of the documented ``<=`` (Se4)."""
    pe = np.array([0.1, 0.2]).reshape(2, 1, 1, 1)
    s = SeasonResult(labels=["a", "b"], headings_rad=np.zeros(1), radii_m=np.array([5.0]),
                     reaction_times_s=np.array([30.0]), quantile=0.9, t_quantiles_s=np.ones((2, 1, 1, 3)),
                     p_exceed=pe, watch_radius_m=np.ones((2, 1, 1)), weather_rel_rad=np.zeros((2, 1)),
                     wall_s=0.0, n_samples=10)
    assert s.operability(0.1)["operable_frac"].tolist() == [0.5]


def test_p_exceed_counts_a_radius_reached_at_the_reaction_time():
    """Five samples reach the radius at 10, 20, 30 and 40 s and never: within the 30 s
    reaction time three of five (the one at 30 s included: ``T_r <= t_react``)."""
    assert _result([10.0, 20.0, 30.0, 40.0, np.inf]).p_exceed()[0, 0, 0] == pytest.approx(0.6)


def test_times_table_has_each_radius_p_exceed_per_reaction_time():
    """Two radii (3, 6 m) and two reaction times (30, 60 s), four samples reaching 3 m at 10,
    20, 40 s and never, 6 m at 50, 70 s and never: by hand, 3 m is exceeded by 2 of 4 within
    30 s and 3 of 4 within 60 s; 6 m by none within 30 s and 1 of 4 within 60 s."""
    t = np.array([[10.0, 50.0], [20.0, 70.0], [40.0, np.inf], [np.inf, np.inf]])[None]
    res = DriftOffResult(np.zeros(1), np.zeros(1), np.array([3.0, 6.0]), np.array([30.0, 60.0]), t,
                         np.zeros((1, 4, 2)), 100.0)
    times, _ = res.summary_frames()
    assert times["radius_m"].tolist() == [3.0, 6.0]
    assert times["p_exceed_30s"].tolist() == [0.5, 0.0]
    assert times["p_exceed_60s"].tolist() == [0.75, 0.25]


def test_p_exceed_interval_is_the_exact_binomial_one():
    """Clopper-Pearson by its definition, through the binomial tails (not the beta quantiles):
    with k of n samples over the radius, P(X >= k) = 2.5 % at the lower bound and
    P(X <= k) = 2.5 % at the upper one; 0 and 1 where none or all reached it."""
    from scipy.stats import binom

    t = np.where(np.arange(20) < 6, 10.0, np.inf)         # 6 of 20 within the 30 s
    lo, hi = _result(t).p_exceed_interval(0.95)[0, 0, 0]
    assert lo < 0.3 < hi
    assert binom.sf(5, 20, lo) == pytest.approx(0.025, rel=1e-6)
    assert binom.cdf(6, 20, hi) == pytest.approx(0.025, rel=1e-6)
    none, every = (_result(np.full(20, v)).p_exceed_interval(0.95)[0, 0, 0] for v in (np.inf, 10.0))
    assert none[0] == 0.0 and binom.cdf(0, 20, none[1]) == pytest.approx(0.025, rel=1e-6)
    assert every[1] == 1.0 and binom.sf(19, 20, every[0]) == pytest.approx(0.025, rel=1e-6)


def test_operability_median_is_of_the_states_10_percent_times():
    """Three states whose 10 % times are 10, 40 and 20 s (50 % and 90 % times far above):
    the median 10 % time is 20 s."""
    tq = np.array([[10.0, 100.0, 200.0], [40.0, 400.0, 800.0], [20.0, 300.0, 500.0]]).reshape(3, 1, 1, 3)
    s = SeasonResult(labels=["a", "b", "c"], headings_rad=np.zeros(1), radii_m=np.array([5.0]),
                     reaction_times_s=np.array([30.0]), quantile=0.9, t_quantiles_s=tq,
                     p_exceed=np.zeros((3, 1, 1, 1)), watch_radius_m=np.ones((3, 1, 1)),
                     weather_rel_rad=np.zeros((3, 1)), wall_s=0.0, n_samples=10)
    assert s.operability(0.1)["median_t_p10_s"].tolist() == [20.0]


def test_wind_direction_off_the_bow():
    """Kills: weather_rel_rad = psi - wind (P5). Wind from 090 at heading 000 is from
    starboard (90 deg off the bow); at heading 030 it is 60 deg off the bow."""
    st = DriftOffSettings(n_samples=1, horizon_s=10.0, reaction_times_s=(5.0,), vessel_spread=0.0)
    r = simulate_blackouts("gunnerus", WeatherState.from_degrees(wind_speed_m_s=3.0, wind_dir_deg=90.0),
                           np.radians([0.0, 30.0]), settings=st)
    np.testing.assert_allclose(np.degrees(r.weather_rel_rad), [90.0, 60.0])



def test_wind_direction_off_the_bow_is_below_a_full_turn():
    """weather_rel_rad is documented in [0, 2 pi): wind from north at a heading of 1e-17 rad
    (the wind a hair off the bow to port) gave np.mod's 2 pi, which the polar plot sorted
    after every other heading; it is 0, in planning and live mode alike."""
    st = DriftOffSettings(n_samples=1, horizon_s=10.0, reaction_times_s=(5.0,), vessel_spread=0.0)
    r = simulate_blackouts("gunnerus", WeatherState(wind_speed_m_s=3.0), [1e-17, math.pi], settings=st)
    assert np.all((r.weather_rel_rad >= 0.0) & (r.weather_rel_rad < 2.0 * math.pi)), r.weather_rel_rad
    assert r.weather_rel_rad.tolist() == [0.0, math.pi]
    z3 = np.zeros(3)
    est = EnvironmentEstimate(time_s=0.0, eta=np.array([0.0, 0.0, 1e-17]), nu=z3, rpm=z3, azimuth_rad=z3,
                              wind_speed_m_s=3.0, wind_dir_from_rad=0.0, gust_intensity=0.0, accel_ned=z3,
                              accel_members=np.zeros((1, 3)))
    assert blackout_now(est, "gunnerus", st).weather_rel_rad.tolist() == [0.0]


def test_weather_table_round_trip_keeps_every_field():
    """Kills: the wind direction read from the wave column (W3); the existing round trip
    checks the wave direction only. Every field goes through, each with a value of its own
    (none the default): an optional gust_intensity column left unread gave the default 0.1,
    which a state with the default did not show."""
    s = [WeatherState.from_degrees(wind_speed_m_s=5.0, wind_dir_deg=10.0, hs_m=1.0, tp_s=7.0, wave_dir_deg=20.0,
                                   current_m_s=0.3, current_dir_deg=200.0, gust_intensity=0.25)]
    back, _ = read_weather_table(states_to_frame(s))
    fields = [f.name for f in dataclasses.fields(WeatherState)]
    assert len(fields) == 8 and len({getattr(s[0], f) for f in fields}) == 8
    assert all(getattr(s[0], f) != getattr(WeatherState(), f) for f in fields)
    for f in fields:
        assert math.isclose(getattr(back[0], f), getattr(s[0], f), abs_tol=1e-12), f


def test_weather_table_labels_are_one_per_state():
    """``states_to_frame`` with another number of labels than states is refused naming the
    labels (it was pandas' "Length of values (1) does not match length of index (2)")."""
    s = [WeatherState(), WeatherState(wind_speed_m_s=5.0)]
    with pytest.raises(ValueError, match=r"^labels: expected 2 labels, one per state, got 1"):
        states_to_frame(s, ["a"])
    assert states_to_frame(iter(s), ("a", "b"))["time"].tolist() == ["a", "b"]


# -- direction conventions of the drift -----------------------------------------------------

def test_the_ship_drifts_downwind_and_with_the_current():
    """Kills: the current's direction taken as FROM (W2). Radii are blind to direction, so
    the tracks are checked: wind FROM north (beam on at heading 090) drives her south; a
    current flowing TO east (no wind) carries her east."""
    st = DriftOffSettings(**NOMINAL)
    wind = simulate_blackouts("gunnerus", WeatherState(wind_speed_m_s=12.0, gust_intensity=0.0), [math.pi / 2],
                              settings=st, keep_tracks=True).tracks[0, 0, -1]
    assert wind[0] < -2.0 and abs(wind[1]) < 0.5 * abs(wind[0]), wind
    cur = simulate_blackouts("gunnerus", WeatherState(current_speed_m_s=0.5, current_dir_to_rad=math.pi / 2,
                                                      gust_intensity=0.0), [0.0],
                             settings=st, keep_tracks=True).tracks[0, 0, -1]
    assert cur[1] > 2.0 and abs(cur[0]) < 0.5 * cur[1], cur


def test_the_ship_drifts_away_from_where_the_waves_come_from():
    """Waves FROM north (beam on at heading 090; no wind, no current) push her south: the
    mean wave drift acts in the direction the waves travel."""
    st = DriftOffSettings(**NOMINAL)
    end = simulate_blackouts("gunnerus", WeatherState(hs_m=2.0, tp_s=7.0, wave_dir_from_rad=0.0, gust_intensity=0.0),
                             [math.pi / 2], settings=st, keep_tracks=True).tracks[0, 0, -1]
    assert end[0] < -1.0 and abs(end[1]) < 0.5 * abs(end[0]), end


def _live(monkeypatch, **change):
    """blackout_now on a hand-made estimate, with the kernel's tracks captured."""
    tracks = []
    real = engine.run_kernel

    def keep(*args, **kw):
        t, e, tr = real(*args, **{**kw, "keep_tracks": True})
        tracks.append(tr)
        return t, e, None
    monkeypatch.setattr(engine, "run_kernel", keep)
    z3 = np.zeros(3)
    est = EnvironmentEstimate(time_s=0.0, eta=z3, nu=z3, rpm=z3, azimuth_rad=z3, wind_speed_m_s=0.0,
                              wind_dir_from_rad=0.0, gust_intensity=0.0, accel_ned=z3,
                              accel_members=np.zeros((1, 3)))
    est = dataclasses.replace(est, **change)
    st = DriftOffSettings(n_samples=change.get("accel_members", np.zeros((1, 3))).shape[0], horizon_s=60.0,
                          radii_m=(5.0,), reaction_times_s=(30.0,), vessel_spread=0.0)
    res = blackout_now(est, "gunnerus", st)
    return res, tracks[0]


def test_live_current_members_flow_towards_their_direction(monkeypatch):
    """Kills: live current members passed as FROM (L1): a member [0, 0.5] m/s carries her east."""
    _, tr = _live(monkeypatch, current_members_ned_m_s=np.array([[0.0, 0.5]]))
    end = tr[0, -1]
    assert end[1] > 2.0 and abs(end[0]) < 0.5 * end[1], end


def test_live_load_is_a_ned_acceleration_at_any_heading(monkeypatch):
    """Kills: the kernel's NED -> body rotation transposed (D8). A 0.01 m/s^2 northward load
    at heading 045 moves her north (mutated: east); radii alone are blind to it (mirror-symmetric hull)."""
    _, tr = _live(monkeypatch, eta=np.array([0.0, 0.0, math.pi / 4]), accel_members=np.array([[0.01, 0.0, 0.0]]))
    end = tr[0, -1]
    assert end[0] > 5.0 and abs(end[1]) < 0.3 * end[0], end


# -- each source of randomness reaches the samples ---------------------------------------------

def test_live_samples_each_take_their_own_member(monkeypatch):
    """Kills: every live sample given member 0 (L2): four members, four different drifts."""
    members = np.array([[0.0, 0.002 * k, 0.0] for k in range(1, 5)])
    res, _ = _live(monkeypatch, accel_members=members)
    assert np.unique(np.round(res.excursion_m[0, :, 0], 9)).size == 4


@pytest.mark.parametrize("what, weather, spread", [
    ("wave phases", dict(hs_m=1.5, tp_s=7.0, wave_dir_from_rad=1.0, gust_intensity=0.0), 0.0),      # W4
    ("gusts", dict(wind_speed_m_s=10.0, wind_dir_from_rad=1.0, gust_intensity=0.2), 0.0),          # D9
    ("vessel", dict(wind_speed_m_s=10.0, wind_dir_from_rad=1.0, gust_intensity=0.0), 1.0),         # S1
])
def test_each_source_of_randomness_makes_the_samples_differ(what, weather, spread):
    """With one source of randomness on at a time, the samples' excursions differ. Kills:
    one wave seed for all samples (W4), the gusts dropped from the kernel's wind (D9), one
    vessel draw for all samples (S1)."""
    st = DriftOffSettings(n_samples=4, horizon_s=60.0, radii_m=(5.0,), reaction_times_s=(60.0,),
                          vessel_spread=spread, seed=1)
    r = simulate_blackouts("gunnerus", WeatherState(**weather), [0.0], settings=st)
    exc = r.excursion_m[0, :, 0]
    assert np.ptp(exc) > 1e-3 * exc.max() > 0, (what, exc)


# -- the excursion up to a reaction time --------------------------------------------------------

def test_excursion_up_to_a_reaction_time_inside_a_step_is_interpolated():
    """Kills: the excursion taken at the end of the step that holds the reaction time (D4).
    With dt 1 s and a reaction time of 30.5 s on a steadily growing drift, the excursion is
    the mean of the radii at 30 s and 31 s of the track."""
    st = DriftOffSettings(n_samples=1, horizon_s=60.0, radii_m=(500.0,), reaction_times_s=(30.5,), vessel_spread=0.0)
    r = simulate_blackouts("gunnerus", WeatherState(wind_speed_m_s=12.0, wind_dir_from_rad=math.pi / 2,
                                                    gust_intensity=0.0), [0.0], settings=st, keep_tracks=True)
    rad = np.hypot(r.tracks[0, 0, :, 0], r.tracks[0, 0, :, 1])
    assert np.all(np.diff(rad[25:35]) > 0)
    assert r.excursion_m[0, 0, 0] == pytest.approx(0.5 * (rad[30] + rad[31]), rel=1e-9)


def test_time_to_reach_a_radius_inside_a_step_is_interpolated():
    """Kills: the passage time taken at the end of the step that crosses the radius. With dt
    1 s on a steadily growing drift, the time the track's radius reaches 2.5 m, read by
    linear interpolation between the two track points around it."""
    st = DriftOffSettings(n_samples=1, horizon_s=60.0, radii_m=(2.5,), reaction_times_s=(30.0,), vessel_spread=0.0)
    r = simulate_blackouts("gunnerus", WeatherState(wind_speed_m_s=12.0, wind_dir_from_rad=math.pi / 2,
                                                    gust_intensity=0.0), [0.0], settings=st, keep_tracks=True)
    rad = np.hypot(r.tracks[0, 0, :, 0], r.tracks[0, 0, :, 1])
    j = int(np.argmax(rad >= 2.5)) - 1                      # rad[j] < 2.5 <= rad[j + 1]
    assert j > 0 and rad[j] < 2.5 < rad[j + 1] and rad[j + 1] - rad[j] > 0.05
    want = j + (2.5 - rad[j]) / (rad[j + 1] - rad[j])      # [s], dt = 1 s
    assert r.t_reach_s[0, 0, 0] == pytest.approx(want, rel=1e-9)
    assert not want == pytest.approx(j + 1.0, abs=0.05)       # a passage inside the step, not at its end


# -- live estimate from a log ---------------------------------------------------------------

def test_live_estimate_takes_the_wind_direction_and_the_stop_handling_from_the_log():
    """A station-keeping log with a steady wind FROM 060 and a current: the live estimate's
    mean wind comes from 060, and the estimate is the filter's at a thrust stop
    (EnvironmentEstimator.at_thrust_stop): with the per-DOF settings, which restart the yaw
    environment there with none of it kept, the yaw load cancels the current's yaw
    acceleration through the hull."""
    from hybridship.physics.model import DynamicModel
    from hybridship.residual import environment_kernel as kernel
    from hybridship.residual.environment import PER_DOF, EnvironmentConfig
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    log = physics_log(model, duration_s=300.0, t_shutdown_s=None, seed=3, wind=(8.0, math.radians(60.0)),
                      current=(0.3, 1.0))
    est = environment_from_log(log, model, window_s=240.0, n_members=20,
                               environment_config=EnvironmentConfig(**PER_DOF))
    assert math.degrees(est.wind_dir_from_rad) == pytest.approx(60.0, abs=1e-6)
    x = np.zeros(14)
    x[:3], x[3:6], x[6:8] = est.eta, est.nu, est.current_members_ned_m_s.mean(axis=0)
    cy = kernel.current_yaw_accel(x, model.arrays, kernel._workspace(model.arrays))
    assert abs(cy) > 1e-6
    assert est.accel_ned[2] == pytest.approx(-cy, rel=1e-6)
