"""Drift-off numerics against what the docs promise: steps of the horizon, the first passage of a
radius interpolated on the track, the farthest point as the excursion, the sampled weather (its
sea, gusts and defaults), the random streams, and the season sweep's per-state numbers."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hybridship.driftoff import engine
from hybridship.driftoff.live import EnvironmentEstimate, blackout_now
from hybridship.driftoff.planning import (DriftOffResult, DriftOffSettings, check_headings, simulate_blackouts,
                                          state_rng)
from hybridship.driftoff.season import season_sweep
from hybridship.frames import wrap_2pi
from hybridship.sim.environment import make_wave_components
from hybridship.driftoff.weather import (WeatherState, WeatherUncertainty, limiting_hs_m, read_weather_table,
                                         sample_environment, states_to_frame)

BEAM = WeatherState(wind_speed_m_s=12.0, wind_dir_from_rad=math.pi / 2, gust_intensity=0.0)


# -- settings ---------------------------------------------------------------------------------

def test_a_horizon_of_whole_steps_is_simulated_in_that_many_steps():
    """2.1 s in steps of 0.3 s is 7 steps (2.1 / 0.3 is 7.000000000000001 in floating point),
    not 8: the result's horizon is the one asked for and the track has 8 points."""
    st = DriftOffSettings(horizon_s=2.1, dt_s=0.3, reaction_times_s=(0.9,), n_samples=1)
    assert st.n_steps == 7
    r = simulate_blackouts("gunnerus", BEAM, [0.0], settings=st, keep_tracks=True)
    assert r.horizon_s == pytest.approx(2.1) and r.tracks.shape == (1, 1, 8, 3)


def test_a_horizon_accepted_as_whole_steps_is_simulated_in_that_many_steps_from_either_side():
    """100 s in steps of 0.333333333 s is 300.0000003 steps, which the settings accept as a
    whole number (to 1e-6): the drift is 300 steps long, as it is for 299.9999997 steps, not
    301 steps and a horizon of 100.33 s."""
    for dt in (0.333333333, 0.333333334):
        st = DriftOffSettings(horizon_s=100.0, dt_s=dt, reaction_times_s=(30.0,), n_samples=1)
        assert st.n_steps == 300
        r = simulate_blackouts("gunnerus", BEAM, [0.0], settings=st, keep_tracks=True)
        assert r.horizon_s == pytest.approx(100.0, abs=1e-6) and r.tracks.shape == (1, 1, 301, 3)


@pytest.mark.parametrize("deg", [(30.0, -330.0), (100.0, -260.0), (0.0, -1e-15)])
def test_one_heading_given_twice_a_turn_apart_is_refused(deg):
    """30 and -330 deg are one heading, as 0 and 360 are (the command line says so); in radians
    their remainders of 2 pi differ in the last bits, and both were run, giving repeated rows."""
    with pytest.raises(ValueError, match="headings: expected each heading once"):
        check_headings(np.radians(deg))
    assert check_headings(np.radians([0.0, 1e-3, 359.999])).size == 3


def test_radii_given_in_any_order_are_listed_outward():
    """The tables and the report's panels read from the smallest radius out."""
    assert DriftOffSettings(radii_m=(10.0, 3.0, 5.0)).radii_m == (3.0, 5.0, 10.0)


def test_a_radius_reached_exactly_at_the_reaction_time_counts_as_exceeded():
    """P(exceed r within t) is P(T_r <= t): a sample at the radius at the reaction time has
    exceeded it, in the table and on the exceedance curve alike."""
    res = DriftOffResult(np.zeros(1), np.zeros(1), np.array([5.0]), np.array([30.0]),
                         np.array([30.0, 31.0, np.inf, 12.0])[None, :, None], np.zeros((1, 4, 1)), 60.0)
    assert res.p_exceed()[0, 0, 0] == 0.5
    np.testing.assert_array_equal(res.exceedance_curves([12.0, 30.0, 31.0])[0, 0], [0.25, 0.5, 0.75])


def test_the_tables_give_each_headings_wind_and_each_radius_its_own_share():
    """times.csv and watch.csv give the wind's direction off the bow of each heading (the
    result's weather_rel_rad, not the heading), and reached_frac is each radius' own share."""
    t = np.full((2, 4, 2), np.inf)
    t[:, :, 0] = 20.0                        # 5 m: every sample; 10 m: one in four
    t[:, 0, 1] = 50.0
    res = DriftOffResult(np.radians([0.0, 30.0]), np.radians([90.0, 60.0]), np.array([5.0, 10.0]),
                         np.array([30.0]), t, np.zeros((2, 4, 1)), 60.0)
    times, watch = res.summary_frames()
    assert times["wind_rel_deg"].tolist() == pytest.approx([90.0, 90.0, 60.0, 60.0])
    assert watch["wind_rel_deg"].tolist() == pytest.approx([90.0, 60.0])
    assert times["reached_frac"].tolist() == [1.0, 0.25, 1.0, 0.25]


def test_thrusters_that_never_spin_down_keep_her_on_station():
    """The holding load decays with the thrusters' spin-down time constant: with one of 10^6 s
    the DP's load still balances a steady beam wind after a minute (she stays within 0.5 m);
    with the default 1.5 s she drifts off."""
    st = dict(n_samples=1, horizon_s=60.0, radii_m=(3.0,), reaction_times_s=(60.0,), vessel_spread=0.0)
    held = simulate_blackouts("gunnerus", BEAM, [0.0], settings=DriftOffSettings(rpm_time_constant_s=1e6, **st))
    lost = simulate_blackouts("gunnerus", BEAM, [0.0], settings=DriftOffSettings(**st))
    assert held.excursion_m[0, 0, 0] < 0.5 < 3.0 < lost.excursion_m[0, 0, 0]


def test_the_holding_load_fades_as_the_thrust_does_with_the_square_of_the_rpm():
    """At the blackout the holding load H cancels the environment (M a_env = -H at rest) and
    then fades as the thrust, (rpm / rpm0)^2 = exp(-2 t / tau) (engine notes): the net
    acceleration is a_env (1 - exp(-2 t / tau)), and while she barely moves (no damping yet)
    she is at a_env g(t), g(t) = t^2 / 2 - tau t / 2 + tau^2 (1 - exp(-2 t / tau)) / 4,
    after t; a_env from the model's own acceleration at rest in the same wind, thrusters
    off. A load fading as the rpm (exp(-t / tau)) leaves her about half as far."""
    from hybridship.driftoff.planning import get_model

    model = get_model("gunnerus")
    az = [t.fixed_angle_rad for t in model.vessel.thrusters]
    a_env = model.acceleration(np.zeros(3), np.zeros(3), rpm=np.zeros(len(az)), azimuth_rad=az,
                               wind=[BEAM.wind_speed_m_s, BEAM.wind_dir_from_rad])[0]
    assert a_env[1] < -0.01                           # a beam wind from starboard pushes her to port
    t, tau = 1.0, 10.0
    st = DriftOffSettings(n_samples=1, horizon_s=t, dt_s=0.05, radii_m=(100.0,), reaction_times_s=(t,),
                          vessel_spread=0.0, rpm_time_constant_s=tau)
    end = simulate_blackouts("gunnerus", BEAM, [0.0], settings=st, keep_tracks=True).tracks[0, 0, -1]
    g = t**2 / 2.0 - tau * t / 2.0 + tau**2 * (1.0 - math.exp(-2.0 * t / tau)) / 4.0
    np.testing.assert_allclose(end, a_env * g, rtol=0.02)      # north, east (heading 0: surge, sway), heading


def test_a_spread_of_zero_is_reported_as_the_nominal_model():
    """The report's vessel spread: "none" when it draws nothing, as for spread 0."""
    from hybridship.driftoff.planning import get_model
    from hybridship.driftoff.spread import spread_text

    vessel = get_model("gunnerus").vessel
    assert spread_text(vessel, 0.0) == "none (the nominal model)"
    assert spread_text(vessel, 2.0) == "2 x [true_vessel]"


# -- random streams ---------------------------------------------------------------------------

def test_each_seed_and_state_index_has_a_stream_of_its_own():
    """The module notes' SeedSequence(seed, spawn_key=(index,)): run seed 1's first state must
    not replay run seed 0's second one (as seed + index would)."""
    draw = lambda seed, index: state_rng(seed, index).standard_normal(4)  # noqa: E731
    want = np.random.default_rng(np.random.SeedSequence(7, spawn_key=(3,))).standard_normal(4)
    np.testing.assert_array_equal(draw(7, 3), want)
    assert not np.array_equal(draw(1, 0), draw(0, 1))



@pytest.mark.parametrize("seed, index, field", [(1.7, 0, "seed"), (True, 0, "seed"), ("3", 0, "seed"), (-1, 0, "seed"),
                                                (0, 2.5, "index"), (0, False, "index"), (0, -1, "index")])
def test_a_stream_is_chosen_by_whole_numbers_only(seed, index, field):
    """state_rng read a seed of 1.7 or True as 1 and "3" as 3 (another run's stream, without a
    word), and failed in numpy's words on a negative one; each is refused naming it."""
    np.testing.assert_array_equal(state_rng(np.int64(3), 2).standard_normal(2), state_rng(3, 2).standard_normal(2))
    with pytest.raises(ValueError, match=rf"^{field}: expected a whole number >= 0"):
        state_rng(seed, index)


# -- the kernel's passages and excursions ---------------------------------------------------------

def test_time_to_reach_is_the_linear_interpolation_of_the_track_between_steps():
    """First passage of each radius: the step whose end is first at or beyond it, the time
    interpolated linearly in the distance over that step (module notes of the engine). In
    steps of 0.5 s, so that a time counted in steps (or a fraction not scaled by the step)
    shows."""
    radii, dt = (3.0, 5.0, 10.0), 0.5
    st = DriftOffSettings(n_samples=1, horizon_s=90.0, dt_s=dt, radii_m=radii, reaction_times_s=(30.0,),
                          vessel_spread=0.0)
    r = simulate_blackouts("gunnerus", BEAM, [0.0], settings=st, keep_tracks=True)
    rad = np.hypot(r.tracks[0, 0, :, 0], r.tracks[0, 0, :, 1])
    for k, radius in enumerate(radii):
        j = int(np.argmax(rad >= radius))          # first step end at or beyond the radius
        assert 0 < j and rad[j - 1] < radius
        want = dt * ((j - 1) + (radius - rad[j - 1]) / (rad[j] - rad[j - 1]))
        assert r.t_reach_s[0, 0, k] == pytest.approx(want, rel=1e-9)
        assert dt * (j - 1) < r.t_reach_s[0, 0, k] <= dt * j


def test_the_drift_is_integrated_to_fourth_order_in_the_step():
    """RK4 with the spin-down evaluated at the stage times: in a steady beam wind (inputs
    constant over a step) halving the step cuts the change of the position at 10 s about 16
    times (2^4); a stage taken at the wrong time leaves a first-order error (about 2 times)."""
    ne = []
    for dt in (1.0, 0.5, 0.25):
        st = DriftOffSettings(n_samples=1, horizon_s=10.0, dt_s=dt, radii_m=(500.0,), reaction_times_s=(10.0,),
                              vessel_spread=0.0)
        ne.append(simulate_blackouts("gunnerus", BEAM, [0.0], settings=st, keep_tracks=True).tracks[0, 0, -1, :2])
    change = np.linalg.norm(np.diff(ne, axis=0), axis=1)
    assert change[0] / change[1] > 10.0, change


def test_the_excursion_is_the_farthest_point_even_when_the_ship_comes_back():
    """A ship moving north at 1 m/s at the blackout with a load of 0.05 m/s^2 pushing her south
    goes out about 9.5 m by 20 s and is back within about 1 m of the start at 40 s: the excursion
    up to 40 s is the farthest she went, not where she is then."""
    z3 = np.zeros(3)
    est = EnvironmentEstimate(time_s=0.0, eta=z3, nu=np.array([1.0, 0.0, 0.0]), rpm=z3, azimuth_rad=z3,
                              wind_speed_m_s=0.0, wind_dir_from_rad=0.0, gust_intensity=0.0,
                              accel_ned=np.array([-0.05, 0.0, 0.0]), accel_members=np.array([[-0.05, 0.0, 0.0]]))
    st = DriftOffSettings(n_samples=1, horizon_s=60.0, radii_m=(5.0,), reaction_times_s=(10.0, 40.0),
                          vessel_spread=0.0)
    r = blackout_now(est, "gunnerus", st)
    exc = r.excursion_m[0, 0]
    assert r.t_reach_s[0, 0, 0] < 10.0 and exc[0] >= 5.0
    assert exc[1] > max(exc[0], 9.0)      # 1 m/s against 0.05 m/s^2 turns at most 10 m out


def test_the_excursion_up_to_a_reaction_time_agrees_with_the_passage_times():
    """The farthest point up to a reaction time inside a step is the farthest before the step or
    the track interpolated in it (as the passage times are): 10 m so far, back at 5 m when the
    step starts and out at 12 m when it ends, the track is at 8.5 m halfway, so the excursion
    up to then is 10 m, and 11 m is first passed later in the step (it was 11 m, "reached"
    before the radius was). The step is 0.5 s from 3 s, not 1 s from 0: fractions of it
    taken as seconds, or times counted from 0, show."""
    def step(farthest_before, radius, t0=3.0, dt=0.5):
        """The step from ``t0`` to ``t0 + dt`` (5 m to 12 m), reaction time halfway through it."""
        reached, done = np.zeros(1, dtype=bool), np.zeros(1, dtype=bool)
        t_reach, exc = np.full(1, np.inf), np.zeros(1)
        engine._record_passages(12.0, 5.0, farthest_before, t0, dt, np.array([radius]), np.array([t0 + 0.5 * dt]),
                                reached, done, t_reach, exc)
        assert reached[0] and done[0]
        return t_reach[0], exc[0]

    t_reach, exc = step(10.0, 11.0)
    assert t_reach == pytest.approx(3.0 + 0.5 * 6.0 / 7.0) and t_reach > 3.25
    assert exc == 10.0
    # the step is 0.5 s long, starting at 3 s: the passage of 7 m is 2/7 of it in, and with
    # 6 m the farthest before, the track halfway (8.5 m) is the excursion
    t_reach, exc = step(6.0, 7.0)
    assert t_reach == pytest.approx(3.0 + 0.5 * 2.0 / 7.0)
    assert exc == pytest.approx(8.5)


def test_keeping_the_tracks_changes_no_number():
    """Tracks switch the early stop off; the early stop must not cut the excursion up to a
    reaction time that comes after every radius is reached."""
    st = DriftOffSettings(n_samples=3, horizon_s=120.0, radii_m=(1.0, 2.0), reaction_times_s=(10.0, 100.0), seed=4)
    w = WeatherState.from_degrees(wind_speed_m_s=14.0, wind_dir_deg=80.0, hs_m=1.0, tp_s=6.0)
    fast = simulate_blackouts("gunnerus", w, [0.0], settings=st)
    kept = simulate_blackouts("gunnerus", w, [0.0], settings=st, keep_tracks=True)
    assert np.all(fast.t_reach_s < 100.0)             # every radius reached before the last reaction time
    np.testing.assert_array_equal(fast.t_reach_s, kept.t_reach_s)
    np.testing.assert_array_equal(fast.excursion_m, kept.excursion_m)


# -- the sampled weather ---------------------------------------------------------------------------

def test_a_state_steeper_than_dnvs_limit_is_sampled_at_its_own_height():
    """Hs 19 m at Tp 10 s is steeper than DNV's limiting steepness (9.2 m) yet a valid state:
    known exactly, every sample's sea has the state's Hs (4 sqrt(m0) of its components), not
    the limit's; a spread adds no constraint."""
    state = WeatherState(hs_m=19.0, tp_s=10.0)
    assert float(limiting_hs_m(10.0)) < 10.0
    e = sample_environment(state, None, 3, np.random.default_rng(0), duration_s=60.0, dt_s=1.0, n_wave=20)
    hs = 4.0 * np.sqrt(0.5 * (e.waves[1] ** 2).sum(axis=1))
    np.testing.assert_allclose(hs, 19.0, rtol=1e-9)


def _before_the_waves(seed, n, n_gust):
    """A generator of ``seed`` after the draws sample_environment makes before its waves, in
    its documented order (the weather's normal deviates (n, 7), the gusts' jitter and phases
    (n, n_gust) each), and those deviates."""
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((n, 7))
    rng.uniform(0.0, 1.0, (n, n_gust))
    rng.uniform(0.0, 2.0 * np.pi, (n, n_gust))
    return rng, z


def test_every_sample_has_a_sea_of_its_own_height_in_bins_of_its_own_period():
    """With Hs, Tp and the wave direction uncertain, each sample's components have its drawn
    Hs exactly (4 sqrt(m0)), a calm (Hs clipped to 0) zero amplitudes, one frequency inside
    each of the n equal bins on [0.5, 3.5] times its own peak frequency, jittered over the
    bin, and its own direction. Kills: one Tp or Hs for all samples, bins of the state's
    period, a lost normalisation, calm samples with waves."""
    state = WeatherState(hs_m=0.6, tp_s=9.0, wave_dir_from_rad=2.0)
    unc = WeatherUncertainty(hs_m=0.5, tp_s=1.5, wave_dir_rad=0.3)
    n, n_gust, n_wave = 400, 7, 12
    e = sample_environment(state, unc, n, np.random.default_rng(5), duration_s=60.0, dt_s=1.0, n_gust=n_gust,
                           n_wave=n_wave)
    _, z = _before_the_waves(5, n, n_gust)
    tp = np.clip(9.0 + 1.5 * z[:, 3], 1.0, 30.0)
    hs = np.maximum(0.6 + 0.5 * z[:, 2], 0.0)
    assert np.all(hs <= limiting_hs_m(tp))          # no steepness clip: these are the drawn heights
    w, a, _, d = e.waves
    calm = hs == 0.0
    assert 20 < calm.sum() < n / 2 and np.ptp(tp) > 5.0
    np.testing.assert_allclose(4.0 * np.sqrt(0.5 * np.sum(a**2, axis=1)), hs, rtol=1e-12, atol=0.0)
    assert np.all(a[calm] == 0.0) and np.all(a[~calm] > 0.0)
    edges = np.linspace(0.5, 3.5, n_wave + 1) * (2.0 * np.pi / tp)[:, None]
    where = (w - edges[:, :-1]) / np.diff(edges, axis=1)     # place in its own bin, 0 to 1
    assert np.all(where > -1e-9) and np.all(where < 1.0 + 1e-9)
    assert where.std() == pytest.approx(math.sqrt(1.0 / 12.0), rel=0.05)     # uniform over the bin
    np.testing.assert_array_equal(d, np.repeat(wrap_2pi(2.0 + 0.3 * z[:, 4])[:, None], n_wave, axis=1))


def test_the_sampled_seas_are_make_wave_components_seas_for_the_same_jitter():
    """Each sample's sea is the one make_wave_components draws with its defaults (gamma 3.3,
    jittered bins on [0.5, 3.5] omega_p, long-crested, Hs normalised) from the same jitter:
    drawn for all samples at once after the gusts, the jitter (n, n_wave) then the phases
    (n, n_wave), as the docstring says. Frequencies and directions bit for bit, amplitudes to
    rounding (powers of an array and of a scalar may differ in the last bit)."""
    state = WeatherState(hs_m=1.8, tp_s=7.5, wave_dir_from_rad=-1.0)
    n, n_gust, n_wave = 6, 5, 16
    e = sample_environment(state, None, n, np.random.default_rng(8), duration_s=60.0, dt_s=1.0, n_gust=n_gust,
                           n_wave=n_wave)
    rng, _ = _before_the_waves(8, n, n_gust)
    at_the_waves = rng.bit_generator.state
    rng.uniform(0.0, 1.0, (n, n_wave))
    np.testing.assert_array_equal(e.waves[2], rng.uniform(0.0, 2.0 * np.pi, (n, n_wave)))
    for i in range(n):
        g = np.random.default_rng(0)
        g.bit_generator.state = at_the_waves
        g.bit_generator.advance(i * n_wave)           # make_wave_components' first draw: row i of the jitter
        wf = make_wave_components(state.hs_m, state.tp_s, state.wave_dir_from_rad, g, n_wave)
        np.testing.assert_array_equal(e.waves[0][i], wf.omega_rad_s)
        np.testing.assert_allclose(e.waves[1][i], wf.amplitude_m, rtol=1e-12, atol=0.0)
        np.testing.assert_array_equal(e.waves[3][i], wf.dir_from_rad)


def test_a_seed_gives_the_same_samples():
    """The same seed, the same arrays bit for bit (weather, gusts, waves); another seed, others."""
    state = WeatherState(wind_speed_m_s=9.0, hs_m=1.5, tp_s=7.0, current_speed_m_s=0.3)
    draw = lambda seed: sample_environment(state, WeatherUncertainty.typical(), 30,  # noqa: E731
                                           np.random.default_rng(seed), duration_s=120.0, dt_s=0.5, n_wave=9)
    a, b, c = draw(11), draw(11), draw(12)
    arrays = lambda e: [e.wind_mean_m_s, e.wind_dir_from_rad, e.gust_f_hz, e.gust_amp_m_s,  # noqa: E731
                        e.gust_phase_rad, e.current, *e.waves]
    for x, y, other in zip(arrays(a), arrays(b), arrays(c)):
        np.testing.assert_array_equal(x, y)
        assert not np.array_equal(x, other)


def test_gusts_have_the_states_intensity_within_the_resolved_band():
    """The gust harmonics lie between 1 / duration and the Nyquist frequency of the step, and
    their sum has standard deviation gust_intensity x U (a harmonic of amplitude a has
    variance a^2 / 2): checked on the kernel's own gust speed over a long record too."""
    state = WeatherState(wind_speed_m_s=10.0, gust_intensity=0.2)
    e = sample_environment(state, None, 4, np.random.default_rng(3), duration_s=300.0, dt_s=0.5, n_gust=20)
    assert e.gust_f_hz.min() >= 1.0 / 300.0 and e.gust_f_hz.max() <= 0.5 / 0.5
    np.testing.assert_allclose(np.sqrt(0.5 * (e.gust_amp_m_s ** 2).sum(axis=1)), 0.2 * 10.0, rtol=1e-12)
    t = np.arange(0.0, 200_000.0, 0.5)
    u = [engine._gust_speed(10.0, e.gust_f_hz[0], e.gust_amp_m_s[0], e.gust_phase_rad[0], x) for x in t[::7]]
    assert np.std(u) == pytest.approx(2.0, rel=0.05)
    # frequencies in Hz: at t the speed is U + sum a cos(2 pi f t + phase)
    f, a, ph = e.gust_f_hz[1], e.gust_amp_m_s[1], e.gust_phase_rad[1]
    for x in (0.0, 13.0, 77.5):
        assert engine._gust_speed(10.0, f, a, ph, x) == pytest.approx(10.0 + np.sum(a * np.cos(2 * np.pi * f * x + ph)))
    # and a lull deeper than the mean wind is calm, not a wind from the other side
    assert engine._gust_speed(1.0, np.array([0.01]), np.array([5.0]), np.array([np.pi]), 0.0) == 0.0


def test_the_weathers_draws_are_independent_of_each_other():
    """Each uncertain quantity has a normal draw of its own: wind speed and direction, current
    speed and direction are uncorrelated over many samples."""
    state = WeatherState(wind_speed_m_s=10.0, current_speed_m_s=1.0)
    unc = WeatherUncertainty(wind_speed_m_s=1.0, wind_dir_rad=0.2, current_speed_m_s=0.1, current_dir_rad=0.2)
    e = sample_environment(state, unc, 2000, np.random.default_rng(2), duration_s=60.0, dt_s=1.0, n_wave=2)
    draws = np.column_stack([e.wind_mean_m_s, e.wind_dir_from_rad, e.current[:, 0], e.current[:, 1]])
    assert np.all(draws.std(axis=0) > 0)
    c = np.corrcoef(draws, rowvar=False)
    assert np.max(np.abs(c - np.eye(4))) < 0.1, c


def test_drawn_peak_periods_stay_at_or_above_one_second():
    """A wide period spread is clipped to [1 s, 30 s] (module notes): no sample's components
    go beyond 3.5 times the peak frequency of a 1-s sea."""
    e = sample_environment(WeatherState(hs_m=0.2, tp_s=2.0), WeatherUncertainty(tp_s=5.0), 200,
                           np.random.default_rng(4), duration_s=60.0, dt_s=1.0, n_wave=10)
    waves = e.waves[1].sum(axis=1) > 0
    assert waves.sum() > 50 and e.waves[0][waves].max() <= 3.5 * 2.0 * np.pi / 1.0


def test_a_weather_table_without_gusts_takes_the_documented_intensity():
    """The optional gust_intensity column defaults to 0.1, as a WeatherState does."""
    df = states_to_frame([WeatherState(wind_speed_m_s=5.0)]).drop(columns=["gust_intensity"])
    states, _ = read_weather_table(df)
    assert states[0].gust_intensity == WeatherState().gust_intensity == 0.1


# -- season sweeps ------------------------------------------------------------------------------------

def _two_states():
    return [WeatherState.from_degrees(wind_speed_m_s=u, wind_dir_deg=70.0, hs_m=0.5, tp_s=5.0) for u in (5.0, 13.0)]


def test_season_numbers_are_each_states_own_planning_numbers():
    """Per state and heading the sweep's reached share, P(exceed) and watch circle (at the
    quantile asked for, in the column of its reaction time) are those of simulate_blackouts on
    that state with its index and the sweep's uncertainty, and the operability's median 10 %
    time is over the states' 10 % times; two headings, three samples, so a mixed-up axis shows."""
    states = _two_states()
    st = DriftOffSettings(n_samples=3, horizon_s=60.0, radii_m=(3.0, 20.0), reaction_times_s=(20.0, 60.0), seed=5)
    psi = np.radians([0.0, 90.0])
    unc = WeatherUncertainty(wind_speed_m_s=1.0)
    sw = season_sweep("gunnerus", states, psi, settings=st, uncertainty=unc, quantile=0.5, progress=False)
    for i, w in enumerate(states):
        one = simulate_blackouts("gunnerus", w, psi, settings=st, uncertainty=unc, index=i)
        np.testing.assert_array_equal(sw.reached_frac[i], np.isfinite(one.t_reach_s).mean(axis=1))
        np.testing.assert_array_equal(sw.watch_radius_m[i], one.watch_circle(0.5))
        np.testing.assert_array_equal(sw.p_exceed[i], one.p_exceed())
    frame = sw.to_frame()
    assert frame["watch_60s_m"].tolist() == [sw.watch_radius_m[s, h, 1] for s in range(2) for h in range(2)
                                             for _ in range(2)]
    op = sw.operability(0.5)
    first = op[(op.heading_deg == 0.0) & (op.radius_m == 3.0)]["median_t_p10_s"].iloc[0]
    assert first == np.median(sw.t_quantiles_s[:, 0, 0, 0])


class _ReversedClient:
    """A stand-in Dask client whose tasks finish in the reverse order of submission."""

    class _Done:
        def __init__(self, value):
            self.value = value

        def result(self):
            return self.value

    def submit(self, fn, *args, pure=True):
        return self._Done(fn(*args))


def test_season_rows_follow_the_states_whatever_order_the_chunks_finish(monkeypatch):
    """Chunks gathered as they complete (last first here): the table is in the states' order."""
    import types

    from hybridship.driftoff import season

    fake = types.SimpleNamespace(as_completed=lambda futs: list(reversed(futs)))
    monkeypatch.setattr(season, "require_dask", lambda: fake)
    states = _two_states() + [WeatherState()]
    st = DriftOffSettings(n_samples=2, horizon_s=30.0, radii_m=(3.0,), reaction_times_s=(10.0,))
    here = season_sweep("gunnerus", states, [0.0], settings=st, chunk_size=1, progress=False)
    there = season_sweep("gunnerus", states, [0.0], settings=st, chunk_size=1, scheduler=_ReversedClient(),
                         progress=False)
    np.testing.assert_array_equal(there.watch_radius_m, here.watch_radius_m)
    assert there.watch_radius_m[1, 0, 0] > there.watch_radius_m[2, 0, 0]    # not all alike


def test_the_capacity_flag_takes_the_thrusters_capacity_in_the_loads_own_direction():
    """Gunnerus' thrusters give about 64 kN to starboard but 52 kN to port. A 24 m/s beam wind
    needs about 54 kN of holding force: within capacity when it blows from starboard (the
    thrusters push to starboard), beyond it from port. The flag compared every load with the
    smaller of the two signs and called both over capacity."""
    from hybridship.sim.allocation import thrust_capacity, thrust_capacity_by_sign

    both = thrust_capacity_by_sign("gunnerus")
    np.testing.assert_array_equal(thrust_capacity("gunnerus"), both.min(axis=0))
    assert both[0, 1] > 1.1 * both[1, 1]
    st = DriftOffSettings(n_samples=1, horizon_s=10.0, radii_m=(100.0,), reaction_times_s=(10.0,), vessel_spread=0.0)
    frac = {d: simulate_blackouts("gunnerus", WeatherState.from_degrees(wind_speed_m_s=24.0, wind_dir_deg=d,
                                                                         gust_intensity=0.0), [0.0],
                                  settings=st).over_capacity_frac[0] for d in (90.0, 270.0)}
    assert frac == {90.0: 0.0, 270.0: 1.0}


_FRESH_OR_CACHED = """
import hashlib, numpy as np
from hybridship.driftoff import engine
from hybridship.driftoff.planning import DriftOffSettings, simulate_blackouts
from hybridship.driftoff.weather import WeatherState, WeatherUncertainty
w = WeatherState.from_degrees(wind_speed_m_s=8, wind_dir_deg=30, hs_m=2.0, tp_s=8, current_m_s=0.2,
                              current_dir_deg=200)
r = simulate_blackouts("gunnerus", w, np.radians([0.0, 90.0]), uncertainty=WeatherUncertainty.typical(),
                       settings=DriftOffSettings(n_samples=40, reaction_times_s=(15.5, 60.3)))
stats = engine._kernel.stats           # the drift-off kernel: compiled (a miss) or read from the cache (a hit)
print(hashlib.sha1(r.t_reach_s.tobytes() + r.excursion_m.tobytes()).hexdigest(), sum(stats.cache_hits.values()),
      sum(stats.cache_misses.values()))
"""


def test_one_seed_gives_the_same_bits_from_a_fresh_kernel_and_from_the_cached_one(tmp_path):
    """Two processes with an empty kernel cache: the first compiles the drift-off kernels, the
    second reads them from the cache. With LLVM free to fuse multiply-adds ("contract"), the
    two gave times 1e-13 s apart, so a table could differ between a first run and the next,
    or between a cluster's workers. The same bits say so only if the second process did read
    the kernel the first one compiled (both compiling would agree whatever the flags)."""
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), PYTHONPATH=str(root))
    runs = [subprocess.run([sys.executable, "-c", _FRESH_OR_CACHED], env=env, capture_output=True, text=True,
                           check=True).stdout.split() for _ in range(2)]
    (fresh, fresh_hits, fresh_misses), (cached, cached_hits, cached_misses) = runs
    assert (fresh_hits, cached_misses) == ("0", "0") and int(fresh_misses) > 0 and int(cached_hits) > 0, runs
    assert len(fresh) == 40 and fresh == cached
