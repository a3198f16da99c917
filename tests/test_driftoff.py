"""Drift-off analysis: physics facts, statistics, seeds, cluster equality, input errors."""

from __future__ import annotations

import importlib.util
import math
import re
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import solve_ivp

from hybridship.driftoff import engine, spread
from hybridship.driftoff.live import blackout_now, environment_from_log
from hybridship.driftoff.planning import DriftOffSettings, get_model, hull_array, simulate_blackouts
from hybridship.driftoff.season import season_sweep
from hybridship.driftoff.weather import (WeatherState, WeatherUncertainty, read_weather_table,
                                         states_to_frame)
from hybridship.physics.model import build_model_arrays
from hybridship.sim import environment as env

ROOT = Path(__file__).resolve().parents[1]
TRUTHSIM_DEV = ROOT.parent / "shared" / "data" / "truthsim-dev" / "logs"

CALM_FAST = dict(n_samples=4, horizon_s=120.0, radii_m=(3.0, 5.0, 10.0), reaction_times_s=(30.0, 60.0))


def test_no_environment_never_reaches_any_radius():
    calm = WeatherState(gust_intensity=0.0)
    r = simulate_blackouts("gunnerus", calm, np.radians([0, 90, 200]), settings=DriftOffSettings(**CALM_FAST))
    assert np.all(np.isinf(r.t_reach_s))
    assert np.all(r.excursion_m < 1e-9)
    assert np.all(r.p_exceed() == 0.0)
    from hybridship.driftoff.report import polar_plot

    fig = polar_plot(r)             # says so, instead of an empty plot
    assert any("no radius reached" in t.get_text() for t in fig.axes[0].texts)


def _scipy_time_to_reach(wind_m_s, radii, tau_rpm_s=1.5):
    """Independent adaptive solve of the nominal model's drift equation with a constant beam wind."""
    model = get_model("gunnerus")
    K = model.n_actuators
    az = np.array([t.fixed_angle_rad for t in model.vessel.thrusters])
    wind = [wind_m_s, math.pi / 2]           # from starboard (heading 0)
    nu_dot0 = model.acceleration(np.zeros(3), np.zeros(3), rpm=np.zeros(K), azimuth_rad=az, wind=wind)[0]
    hold = -model.mass_matrix @ nu_dot0      # the DP's thrust at the blackout, spinning down

    def rhs(t, x):
        nd = model.acceleration(x[:3], x[3:], rpm=np.zeros(K), azimuth_rad=az, wind=wind,
                                tau_ext=hold * math.exp(-2.0 * t / tau_rpm_s))[0]
        c, s = math.cos(x[2]), math.sin(x[2])
        return [c * x[3] - s * x[4], s * x[3] + c * x[4], x[5], *nd]

    events = []
    for R in radii:
        ev = lambda t, x, R=R: math.hypot(x[0], x[1]) - R  # noqa: E731
        ev.terminal = R == max(radii)
        ev.direction = 1
        events.append(ev)
    sol = solve_ivp(rhs, (0.0, 200.0), np.zeros(6), method="DOP853", rtol=1e-8, atol=1e-9, events=events)
    return np.array([e[0] if len(e) else np.inf for e in sol.t_events])


def test_constant_beam_wind_matches_independent_ode_solve():
    radii = (3.0, 5.0, 10.0)
    st = DriftOffSettings(n_samples=1, horizon_s=200.0, dt_s=0.5, radii_m=radii, reaction_times_s=(30.0,),
                          vessel_spread=0.0)
    w = WeatherState(wind_speed_m_s=12.0, wind_dir_from_rad=math.pi / 2, gust_intensity=0.0)
    r = simulate_blackouts("gunnerus", w, [0.0], settings=st)
    expected = _scipy_time_to_reach(12.0, radii)
    assert np.all(np.isfinite(expected))
    np.testing.assert_allclose(r.t_reach_s[0, 0], expected, rtol=0.01)


def test_time_to_reach_decreases_with_wind_speed():
    st = DriftOffSettings(n_samples=12, horizon_s=240.0, radii_m=(3.0, 5.0), reaction_times_s=(30.0,), seed=3)
    med = []
    for u in (5.0, 8.0, 11.0, 14.0):
        w = WeatherState.from_degrees(wind_speed_m_s=u, wind_dir_deg=60.0, hs_m=0.5, tp_s=5.0, current_m_s=0.1,
                                      current_dir_deg=240.0)
        med.append(np.median(simulate_blackouts("gunnerus", w, [0.0], settings=st).t_reach_s[0], axis=0))
    med = np.array(med)
    assert np.all(np.isfinite(med))
    assert np.all(np.diff(med, axis=0) < 0), med


def test_larger_reaction_time_gives_larger_watch_circle():
    st = DriftOffSettings(n_samples=16, horizon_s=120.0, reaction_times_s=(10.0, 20.0, 40.0, 80.0))
    w = WeatherState.from_degrees(wind_speed_m_s=9.0, wind_dir_deg=30.0, hs_m=1.0, tp_s=6.0, current_m_s=0.2)
    r = simulate_blackouts("gunnerus", w, np.radians([0, 90]), settings=st)
    for q in (0.5, 0.9):
        wc = r.watch_circle(q)
        assert np.all(np.diff(wc, axis=1) > 0), wc
    # consistency: P(exceed r within t) is the share of samples whose excursion up to t reaches r
    pe = r.p_exceed()
    for k, tr in enumerate(r.reaction_times_s):
        frac = (r.excursion_m[:, :, k, None] >= r.radii_m[None, None, :] - 1e-9).mean(axis=1)
        np.testing.assert_allclose(pe[:, :, k], frac)


def test_scaled_arrays_reproduce_the_true_vessel():
    model = get_model("gunnerus")
    st = spread.scaled_arrays(model.arrays, spread.true_vessel_scales(model.vessel, 2))
    true = build_model_arrays(model.vessel, true_vessel=True)
    for name in ("m_inv", "m_a", "d_lin", "d_quad", "d_lift", "strip_w", "thr"):
        np.testing.assert_allclose(getattr(st, name)[1], getattr(true, name), rtol=1e-12, atol=1e-12, err_msg=name)
    # wind: the model's wind kernel gives the same loads from the scaled areas and arm
    from hybridship.physics.model import wind_force_scalar

    for ang in np.linspace(-3.0, 3.0, 13):
        f_st = wind_force_scalar(0.1, -0.2, 1.0, 0.0, 8 * math.cos(ang), 8 * math.sin(ang), st.wind_p[1],
                                 model.arrays.wind_table)
        f_true = wind_force_scalar(0.1, -0.2, 1.0, 0.0, 8 * math.cos(ang), 8 * math.sin(ang), true.wind_p,
                                   true.wind_table)
        np.testing.assert_allclose(f_st, f_true, rtol=1e-9, atol=1e-9)


def test_spread_zero_is_the_nominal_model():
    model = get_model("gunnerus")
    sc = spread.draw_scales(model.vessel, 3, np.random.default_rng(0), 0.0)
    st = spread.scaled_arrays(model.arrays, sc)
    np.testing.assert_allclose(st.m_inv[2], model.arrays.m_inv)
    np.testing.assert_allclose(st.wind_p[2], model.arrays.wind_p)


def test_vessel_spread_scales_the_log_normal_spread_of_every_factor():
    """``factor = exp(spread |ln f_true| z)``: at spread 0.5 the log of each drawn factor has
    half the file's |ln f_true| as its standard deviation, mean 0, one z per factor and DOF.
    A spread 0 or 1 alone cannot tell spread from spread**2 (or from the file's factors
    taken at spread 1 whatever the setting)."""
    ves = get_model("gunnerus").vessel
    n = 20000
    drawn = spread.draw_scales(ves, n, np.random.default_rng(3), 0.5)
    for name, f_true, f in zip(drawn._fields, spread.true_vessel_scales(ves, 1), drawn):
        log_f = np.log(f).reshape(n, -1)
        sigma = 0.5 * np.abs(np.log(f_true[0])).reshape(-1)
        # the standard error of a standard deviation from 20000 draws is 0.5 %
        np.testing.assert_allclose(log_f.std(axis=0), sigma, rtol=0.03, err_msg=name)
        assert np.all(np.abs(log_f.mean(axis=0)) < 0.05 * sigma), name
        if log_f.shape[1] > 1:                  # the DOFs drawn independently, not one z for all
            corr = np.corrcoef(log_f.T)[np.triu_indices(log_f.shape[1], 1)]
            assert np.all(np.abs(corr) < 0.05), (name, corr)


def test_kernel_wave_drift_matches_the_simulator():
    comps = env.make_wave_components(1.2, 6.5, 0.7, np.random.default_rng(5), 15)
    ves = get_model("gunnerus").vessel
    hull = hull_array(ves)
    p = ves.particulars
    hd = env.HullDimensions(L_m=p.L_pp_m, B_m=p.B_m, T_m=p.T_m)
    out = np.empty(3)
    for t, n, e, psi in ((0.0, 0.0, 0.0, 0.1), (37.0, 3.0, -8.0, 1.9), (120.5, -20.0, 5.0, -2.5)):
        engine._wave_drift(t, n, e, psi, comps.omega_rad_s, comps.amplitude_m, comps.phase_rad, comps.dir_from_rad,
                           hull, False, out)
        ref = env.wave_drift_loads([t], psi, comps, hd, p.rho_water_kg_m3, position_ne_m=[[n, e]])[0]
        np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-6)
        engine._wave_drift(t, n, e, psi, comps.omega_rad_s, comps.amplitude_m, comps.phase_rad, comps.dir_from_rad,
                           hull, True, out)
        np.testing.assert_allclose(out, env.mean_drift_loads(psi, comps, hd, p.rho_water_kg_m3), rtol=1e-9, atol=1e-6)


def test_same_seed_same_result_and_index_selects_the_stream():
    import dataclasses

    st = DriftOffSettings(n_samples=5, horizon_s=90.0, seed=7)
    w = WeatherState.from_degrees(wind_speed_m_s=8.0, hs_m=0.8, tp_s=6.0, current_m_s=0.2, current_dir_deg=90.0)
    a = simulate_blackouts("gunnerus", w, [0.3], settings=st, index=4)
    b = simulate_blackouts("gunnerus", w, [0.3], settings=st, index=4)
    c = simulate_blackouts("gunnerus", w, [0.3], settings=st, index=5)
    np.testing.assert_array_equal(a.t_reach_s, b.t_reach_s)
    np.testing.assert_array_equal(a.excursion_m, b.excursion_m)
    assert not np.array_equal(a.excursion_m, c.excursion_m)
    # the seed selects the stream too: another seed, same index, other draws (the spread and
    # the sampled sea make every sample's excursion differ)
    d = simulate_blackouts("gunnerus", w, [0.3], settings=dataclasses.replace(st, seed=8), index=4)
    assert not np.array_equal(a.excursion_m, d.excursion_m)


def test_weather_uncertainty_widens_the_distribution():
    st = DriftOffSettings(n_samples=40, horizon_s=150.0, radii_m=(5.0,), reaction_times_s=(30.0,), vessel_spread=0.0)
    w = WeatherState.from_degrees(wind_speed_m_s=10.0, wind_dir_deg=90.0, gust_intensity=0.0)
    sharp = simulate_blackouts("gunnerus", w, [0.0], settings=st).t_reach_s[0, :, 0]
    wide = simulate_blackouts("gunnerus", w, [0.0], uncertainty=WeatherUncertainty(wind_speed_m_s=2.0),
                              settings=st).t_reach_s[0, :, 0]
    assert np.ptp(sharp) < 1e-9 < np.ptp(wide)


def test_season_single_process_equals_cluster():
    if importlib.util.find_spec("distributed") is None:
        pytest.skip("dask.distributed is not installed (pip install -e '.[cluster]')")
    from dask.distributed import Client, LocalCluster

    rng = np.random.default_rng(1)
    states = [WeatherState.from_degrees(wind_speed_m_s=rng.uniform(3, 14), wind_dir_deg=rng.uniform(0, 360),
                                        hs_m=rng.uniform(0, 1.5), tp_s=rng.uniform(4, 8), current_m_s=rng.uniform(0, 0.3),
                                        current_dir_deg=rng.uniform(0, 360)) for _ in range(5)]
    st = DriftOffSettings(n_samples=4, horizon_s=90.0, seed=11)
    psi = np.radians([0, 120])
    one = season_sweep("gunnerus", states, psi, settings=st, chunk_size=2, progress=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        many = season_sweep("gunnerus", states, psi, settings=st, chunk_size=3, scheduler=client, progress=False)
        assert client.status == "running"                  # the caller's client is left to the caller
        # by the scheduler's address: the client made for it is closed afterwards
        by_address = season_sweep("gunnerus", states[:2], psi, settings=st, scheduler=cluster.scheduler_address,
                                  progress=False)
        assert len(cluster.scheduler.clients) == 2         # the test's own, and the scheduler's bookkeeping one
    pd.testing.assert_frame_equal(one.to_frame(), many.to_frame(), check_exact=True)
    np.testing.assert_array_equal(by_address.p_exceed, one.p_exceed[:2])
    # and the same as the states run one by one
    r3 = simulate_blackouts("gunnerus", states[3], psi, settings=st, index=3)
    np.testing.assert_array_equal(one.p_exceed[3], r3.p_exceed())


def test_a_season_of_one_state_given_alone_is_a_sweep_of_one():
    """``season_sweep(states=state)`` failed with "'WeatherState' object is not iterable": one
    state is taken as a list of one (as simulate_blackouts takes it); what is neither a state
    nor an ordered collection of them is refused naming ``states``."""
    w = WeatherState(wind_speed_m_s=8.0)
    st = DriftOffSettings(n_samples=2, horizon_s=30.0, reaction_times_s=(10.0,))
    one = season_sweep("gunnerus", w, [0.0], settings=st, progress=False)
    np.testing.assert_array_equal(one.p_exceed, season_sweep("gunnerus", [w], [0.0], settings=st,
                                                             progress=False).p_exceed)
    assert one.labels == ["0"]
    for states in ({w}, None, 3.0, {"a": w}):
        with pytest.raises(TypeError, match=r"^states: expected a WeatherState or a list of them"):
            season_sweep("gunnerus", states, [0.0], settings=st, progress=False)


def test_weather_table_round_trip_and_errors(tmp_path):
    states = [WeatherState.from_degrees(wind_speed_m_s=5.0, wind_dir_deg=10.0, hs_m=1.0, tp_s=7.0, wave_dir_deg=20.0,
                                        current_m_s=0.3, current_dir_deg=200.0)]
    df = states_to_frame(states, ["2024-01-01T00:00"])
    path = tmp_path / "w.csv"
    df.to_csv(path, index=False)
    back, labels = read_weather_table(path)
    assert labels == ["2024-01-01T00:00"]
    assert math.isclose(back[0].wave_dir_from_rad, states[0].wave_dir_from_rad)
    bad = df.copy()
    bad.loc[0, "tp_s"] = -1.0
    with pytest.raises(ValueError, match="tp_s.*row 0"):
        read_weather_table(bad)
    with pytest.raises(ValueError, match="hs_m"):
        read_weather_table(df.drop(columns=["hs_m"]))
    with pytest.raises(ValueError, match="found ' hs_m', which is hs_m with spaces around the name"):
        read_weather_table(df.rename(columns={"hs_m": " hs_m"}))
    # a column in another unit, and a header separated by ';', pointed out as the log reader does
    with pytest.raises(ValueError, match=r"missing column\(s\) \['wind_speed_m_s', 'current_dir_deg'\].*found "
                                         r"'wind_speed_kn', which looks like wind_speed_m_s in another unit.*found "
                                         r"'current_dir_rad', which looks like current_dir_deg"):
        read_weather_table(df.rename(columns={"wind_speed_m_s": "wind_speed_kn", "current_dir_deg": "current_dir_rad"}))
    df.to_csv(path, index=False, sep=";")
    with pytest.raises(ValueError, match="the header is one name holding ';': the weather table separates columns"):
        read_weather_table(path)
    # above a WeatherState's range: the column, the row and the file's line, not the field's
    # name inside WeatherState
    bad = pd.concat([df, df], ignore_index=True)
    bad.loc[1, "current_m_s"] = 7.0
    bad.to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"column 'current_m_s', row 1 \(line 3 of the file\): 7.0, expected a "
                                         r"number in \[0, 5\]"):
        read_weather_table(path)
    bad.loc[1, "current_m_s"] = 0.3
    bad.loc[1, "wind_dir_deg"] = 1000.0               # degrees out of range, named in degrees
    bad.to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"column 'wind_dir_deg', row 1 \(line 3 of the file\): 1000.0, expected a "
                                         r"number in \[-360, 360\]"):
        read_weather_table(path)
    with pytest.warns(UserWarning, match="column\\(s\\) gust_intensty not used"):    # a misspelt optional column
        read_weather_table(df.assign(gust_intensty=0.4))
    bad.loc[1, "wind_dir_deg"] = 10.0
    bad.loc[1, "current_m_s"] = np.nan              # an empty cell
    bad.to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"row 1 \(line 3 of the file\): a missing value, expected"):
        read_weather_table(path)
    # a sea steeper than waves can be (Hs and Tp swapped): the row and line, both columns
    bad.loc[1, ["current_m_s", "hs_m", "tp_s"]] = [0.3, 8.0, 3.0]
    bad.to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"row 1 \(line 3 of the file\): hs_m 8 m at tp_s 3 s is steeper than "
                                         r"waves can be"):
        read_weather_table(path)
    # a state without a label of its own: the time column and the line
    twice = pd.concat([df, df], ignore_index=True)
    twice.to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"column 'time', row 1 \(line 3 of the file\): '2024-01-01T00:00' again"):
        read_weather_table(path)
    twice.loc[1, "time"] = np.nan
    with pytest.raises(ValueError, match=r"column 'time', row 1: empty"):
        read_weather_table(twice)
    # one field more than the header in every row: not read with the columns shifted
    lines = df.to_csv(index=False).splitlines()
    path.write_text(lines[0] + "\n" + lines[1] + ",99\n")
    with pytest.raises(ValueError, match="w.csv: line 2 has 10 fields, the header line 9"):
        read_weather_table(path)
    path.write_text("")
    with pytest.raises(ValueError, match="w.csv: not a readable CSV weather table .*the file is empty"):
        read_weather_table(path)
    path.write_bytes(b"PK\x03\x04\xff\xfe\x00binary")
    with pytest.raises(ValueError, match=r"not text \(a binary file\?\)") as info:
        read_weather_table(path)
    assert "codec" not in str(info.value)


def test_a_weather_table_with_a_repeated_column_is_refused_naming_it(tmp_path):
    """A DataFrame with ``hs_m`` twice failed in pandas' to_numeric words; a CSV file's second
    ``hs_m`` (renamed ``hs_m.1`` by pandas) was only warned about as unused."""
    df = states_to_frame([WeatherState(wind_speed_m_s=5.0)])
    twice = pd.concat([df, df[["hs_m"]]], axis=1)
    before = twice.copy()
    with pytest.raises(ValueError, match=r"^weather table: column 'hs_m' appears more than once"):
        read_weather_table(twice)
    pd.testing.assert_frame_equal(twice, before)
    path = tmp_path / "w.csv"
    twice.to_csv(path, index=False)
    with pytest.raises(ValueError, match=r"w.csv: column 'hs_m' appears more than once"):
        read_weather_table(path)


def test_a_weather_table_with_directions_in_radians_is_warned_about():
    """200 directions drawn over a turn in radians were read as 0-6.3 deg without a word;
    the same directions in degrees, and a short table, are read as they are."""
    import warnings

    rng = np.random.default_rng(0)
    rad = states_to_frame([WeatherState(wind_speed_m_s=5.0, wind_dir_from_rad=a)
                           for a in rng.uniform(0, 2 * np.pi, 200)])
    rad["wind_dir_deg"] = np.radians(rad["wind_dir_deg"])
    with pytest.warns(UserWarning, match="column 'wind_dir_deg' spans .* looks like radians"):
        read_weather_table(rad)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_weather_table(rad.assign(wind_dir_deg=np.degrees(rad["wind_dir_deg"])))
        read_weather_table(rad.iloc[:10])


def test_a_run_too_large_for_memory_says_so_in_the_commands_words(monkeypatch, tmp_path, capsys):
    """Out of memory: the number of blackouts named and what to ask for instead, not numpy's
    traceback; and the result keeps its own copy of the headings it was given."""
    from hybridship.cli import main
    from hybridship.driftoff import planning

    def no_memory(*args, **kwargs):
        raise MemoryError("Unable to allocate 80.0 GiB for an array")
    monkeypatch.setattr(planning, "_blackouts", no_memory)
    assert main(["drift-off", "planning", "--samples", "1000000", "--no-plots", "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err
    assert "out of memory: settings.n_samples: 1000000 samples x 8 heading(s)" in err and "Traceback" not in err
    # what each blackout holds is named too: the samples are not always what fills the memory
    with pytest.raises(MemoryError, match=r"^settings.n_samples: 2 samples x 1 heading\(s\) = 2 blackouts at once, "
                                          r"each with 1000 wave components and 20 gust harmonics, .*"
                                          r"settings.n_wave_components"):
        simulate_blackouts("gunnerus", WeatherState(), [0.0], settings=dict(CALM_FAST, n_samples=2,
                                                                            n_wave_components=1000))
    monkeypatch.undo()
    h = np.array([0.0, 1.0])
    r = simulate_blackouts("gunnerus", WeatherState(), h, settings=DriftOffSettings(**CALM_FAST))
    h[0] = 3.0
    assert r.headings_rad[0] == 0.0


def test_a_beam_storm_beyond_the_thrusters_is_flagged(tmp_path):
    """Where the mean environment needs more than the thrusters' bollard capacity, the DP was
    not holding station: flagged per heading, in times.csv and the summary; not in a calm."""
    from hybridship.driftoff.report import write_report

    st = DriftOffSettings(n_samples=8, horizon_s=30.0, radii_m=(5.0,), reaction_times_s=(10.0,))
    # 30 m/s: at 25 m/s some samples need less than the 64 kN the thrusters give to starboard
    storm = WeatherState.from_degrees(wind_speed_m_s=30.0, wind_dir_deg=90.0, hs_m=3.0, tp_s=9.0, current_m_s=0.5,
                                      current_dir_deg=90.0)
    r = simulate_blackouts("gunnerus", storm, np.radians([0.0, 90.0]), settings=st)
    assert r.over_capacity_frac[0] == 1.0 and r.over_capacity_frac[1] == 0.0     # beam-on, head-on
    text = write_report(r, tmp_path / "storm", plots=False)["summary.md"].read_text()
    assert "DP capacity exceeded before the blackout** at heading(s) 0 deg (100% of the samples)" in text
    assert pd.read_csv(tmp_path / "storm" / "times.csv")["over_capacity_frac"].tolist() == [1.0, 0.0]
    calm = simulate_blackouts("gunnerus", WeatherState(wind_speed_m_s=5.0), [0.0], settings=st)
    assert calm.over_capacity_frac.tolist() == [0.0]
    assert "DP capacity" not in write_report(calm, tmp_path / "calm", plots=False)["summary.md"].read_text()


def test_a_sea_steeper_than_waves_can_be_is_refused():
    """Beyond the steepness at which a single wave breaks (1/7): refused naming both fields;
    DNV's limiting steepness, about half of it, is accepted."""
    from hybridship.driftoff.weather import MAX_HS_M, limiting_hs_m, max_hs_m

    with pytest.raises(ValueError, match=r"weather.hs_m 8 m at tp_s 3 s is steeper than waves can be \(at most 2.01 m"):
        WeatherState(hs_m=8.0, tp_s=3.0)
    for tp in (3.0, 6.0, 12.0):
        WeatherState(hs_m=float(limiting_hs_m(tp)), tp_s=tp)
        WeatherState(hs_m=min(float(max_hs_m(tp)), MAX_HS_M), tp_s=tp)


def test_weather_samples_stay_in_the_range_of_a_weather_state():
    """A wide spread must not draw a storm the models are not meant for (the drift would
    diverge and be counted as a result)."""
    from hybridship.driftoff.weather import MAX_CURRENT_M_S, MAX_WIND_M_S, sample_environment

    w = WeatherState(wind_speed_m_s=40.0, hs_m=15.0, tp_s=10.0, current_speed_m_s=4.0)
    u = WeatherUncertainty(wind_speed_m_s=1e6, hs_m=50.0, tp_s=100.0, current_speed_m_s=100.0)
    e = sample_environment(w, u, 200, np.random.default_rng(0), duration_s=60.0, dt_s=1.0, n_wave=3)
    assert e.wind_mean_m_s.max() == MAX_WIND_M_S and e.wind_mean_m_s.min() == 0.0
    assert e.current[:, 0].max() == MAX_CURRENT_M_S
    assert np.all(e.waves[1] >= 0) and np.isfinite(e.waves[1]).all()
    r = simulate_blackouts("gunnerus", WeatherState(hs_m=19.0, tp_s=10.0), [0.0],
                           uncertainty=WeatherUncertainty(hs_m=50.0, tp_s=100.0),
                           settings=DriftOffSettings(n_samples=10, horizon_s=60.0, radii_m=(5.0,)))
    assert np.isfinite(r.excursion_m).all()
    # drawn heights no steeper than waves get (DNV-RP-C205), or than the state itself
    from hybridship.driftoff.weather import limiting_hs_m

    assert math.isclose(float(limiting_hs_m(8.0)), 9.81 * 64 / (2 * np.pi * 15)) and float(limiting_hs_m(20.0)) > 20.0
    state = WeatherState(hs_m=2.0, tp_s=10.0)
    steep = sample_environment(state, WeatherUncertainty(hs_m=50.0, tp_s=100.0), 400, np.random.default_rng(1),
                               duration_s=60.0, dt_s=1.0, n_wave=20)
    w, amp = steep.waves[0], steep.waves[1]
    hs = 4.0 * np.sqrt(0.5 * (amp**2).sum(axis=1))                # the components' Hs, per sample
    tp = 2 * np.pi / w[np.arange(len(w)), np.argmax(amp, axis=1)]  # about the drawn Tp
    assert hs.max() > 2.0 and np.all(hs <= 1.5 * limiting_hs_m(tp) + 1e-9)


@pytest.mark.parametrize("kwargs, field", [
    (dict(radii_m=(-1.0,)), "radii_m"), (dict(n_samples=0), "n_samples"), (dict(dt_s=0.0), "dt_s"),
    (dict(reaction_times_s=(500.0,)), "reaction_times_s"), (dict(vessel_spread=float("nan")), "vessel_spread"),
    (dict(seed=-1), "seed"), (dict(dt_s=20.0), "dt_s"), (dict(seed=2**32), "seed"),
    (dict(radii_m=(3.0, 3.0)), "radii_m: expected each value once"),
    (dict(reaction_times_s=(30.0, 30.0)), "reaction_times_s: expected each value once"),
    (dict(reaction_times_s=(30.0, 30.00001)), "reaction_times_s: expected each value once"),
    (dict(horizon_s=60.5), "horizon_s: must be a whole number of steps of"),
    (dict(horizon_s=1e9), "horizon_s: must be <= 86400"), (dict(n_samples=10**9), "n_samples: must be <= 1000000"),
    # beyond them: a MemoryError blaming n_samples, or overflow warnings and numpy's LinAlgError
    (dict(n_wave_components=10**12), "n_wave_components: must be <= 1000"),
    (dict(n_gust_harmonics=10**12), "n_gust_harmonics: must be <= 1000"),
    (dict(vessel_spread=1e9), "vessel_spread: must be <= 5"),
    # 3e8 steps per sample were accepted: days of computing for one command
    (dict(dt_s=1e-6), "dt_s: expected at least 0.00347222 s"),
    (dict(horizon_s=86400.0, dt_s=0.5), "dt_s: expected at least 1 s")])
def test_bad_settings_name_the_field(kwargs, field):
    with pytest.raises((ValueError, TypeError), match=field):
        DriftOffSettings(**kwargs)


def test_bad_weather_names_the_field():
    with pytest.raises(ValueError, match="weather.hs_m"):
        WeatherState(hs_m=-0.5)
    with pytest.raises(ValueError, match="weather.gust_intensity"):
        WeatherState(gust_intensity=0.9)
    with pytest.raises(ValueError, match="weather.tp_s"):  # the samples would run it as 1 s
        WeatherState(tp_s=0.5)
    # beyond the physics' valid inputs and the wave model's sea states the drift would diverge
    for field, value in (("wind_speed_m_s", 500.0), ("current_speed_m_s", 30.0), ("hs_m", 40.0), ("tp_s", 60.0)):
        with pytest.raises(ValueError, match=f"weather.{field}"):
            WeatherState(**{field: value})
    with pytest.raises(ValueError, match="uncertainty.wind_speed_m_s"):
        WeatherUncertainty(wind_speed_m_s=-1.0)
    # directions in degrees where radians are expected: refused, not wrapped or read as a huge spread
    with pytest.raises(ValueError, match=r"weather.wind_dir_from_rad: expected radians within \+-2 pi, got 400"):
        WeatherState(wind_dir_from_rad=400.0)
    with pytest.raises(ValueError, match="uncertainty.wind_dir_rad: expected a spread in radians from 0 to pi"):
        WeatherUncertainty(wind_dir_rad=30.0)
    with pytest.raises(TypeError, match="weather"):
        simulate_blackouts("gunnerus", {"wind": 3}, [0.0])
    with pytest.raises(ValueError, match="headings"):
        simulate_blackouts("gunnerus", WeatherState(), [float("nan")])


def test_cli_reports_bad_input_naming_the_option(tmp_path, capsys):
    from hybridship.cli import main

    assert main(["drift-off", "planning", "--out", str(tmp_path), "--radii-m", "-3"]) == 2
    assert "--radii-m" in capsys.readouterr().err
    for typo in ("3,,10", "3,5,"):      # a number left out is refused, not skipped
        assert main(["drift-off", "planning", "--out", str(tmp_path), "--radii-m", typo]) == 2
        assert "--radii-m" in (err := capsys.readouterr().err) and "an empty item" in err, err
    assert main(["drift-off", "planning", "--out", str(tmp_path), "--hs-m", "-1"]) == 2
    assert "--hs-m:" in capsys.readouterr().err
    assert main(["drift-off", "season", "--out", str(tmp_path), "--weather-table", str(tmp_path / "nope.csv")]) == 2
    assert "--weather-table" in capsys.readouterr().err
    # an --out that is a file is refused before the work, by the benchmarks too
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    for argv in (["drift-off", "planning", "--samples", "3"], ["benchmark", "drift"],
                 ["benchmark", "manoeuvre", "--train", str(tmp_path), "--test", str(tmp_path)]):
        assert main(argv + ["--out", str(a_file)]) == 2, argv
        assert "exists and is not a folder" in capsys.readouterr().err
        assert main(argv + ["--out", str(a_file / "sub")]) == 2, argv   # a file on the way
        assert f"{a_file} exists and is not a folder" in capsys.readouterr().err
        assert main(argv + ["--out", ""]) == 2, argv                     # not the current folder
        assert "--out: expected a path, got ''" in capsys.readouterr().err
    assert main(["drift-off", "planning", "--out", str(tmp_path / "p"), "--headings-deg", "nan"]) == 2
    assert "--headings-deg: expected finite numbers" in capsys.readouterr().err
    # degree options are judged in degrees, naming the option (not radians, nor numpy.radians)
    for opts, message in ((["--headings-deg", "400"], "--headings-deg: expected headings from -360 to 360 deg"),
                          (["--headings-deg", "0,360"], "--headings-deg: expected each heading once"),
                          (["--wind-dir-std-deg", "-5"], "--wind-dir-std-deg: expected a spread from 0 to 180 deg"),
                          (["--wind-dir-deg", "1000"], "--wind-dir-deg: must be <= 360, got 1000"),
                          (["--current-dir-deg", "-1000"], "--current-dir-deg: must be >= -360, got -1000")):
        assert main(["drift-off", "planning", "--samples", "3", "--out", str(tmp_path / "p")] + opts) == 2
        err = capsys.readouterr().err
        assert message in err and "radians" not in err and err.count("error:") == 1, err
    table = tmp_path / "w.csv"
    states_to_frame([WeatherState()]).to_csv(table, index=False)
    assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", "lcoal",
                 "--out", str(tmp_path / "s")]) == 2
    assert "--scheduler: expected 'local', 'none' or a scheduler address" in capsys.readouterr().err
    assert not (tmp_path / "p").exists() and not (tmp_path / "s").exists()


def test_p_exceed_carries_its_exact_binomial_monte_carlo_interval():
    """P(exceed) from N samples has a sampling error: its interval is scipy's exact
    (Clopper-Pearson) binomial interval of k in N, 0 and 1 at the ends, and is written beside
    it in times.csv."""
    from scipy.stats import binomtest

    from hybridship.driftoff.planning import DriftOffResult

    n = 100
    t = np.full((1, n, 3), np.inf)
    t[0, :10, 0] = 5.0                                  # 10 of 100 within 30 s at radius 0
    t[0, :, 1] = 5.0                                    # all at radius 1; none at radius 2
    res = DriftOffResult(np.zeros(1), np.zeros(1), np.array([3.0, 5.0, 10.0]), np.array([30.0]), t,
                         np.zeros((1, n, 1)), 60.0)
    ci = res.p_exceed_interval(0.95)
    want = binomtest(10, n).proportion_ci(0.95, method="exact")
    np.testing.assert_allclose(ci[0, 0, 0], [want.low, want.high], rtol=1e-9)
    assert ci[0, 0, 0].round(2).tolist() == [0.05, 0.18]
    assert ci[0, 1, 0, 1] == 1.0 and ci[0, 2, 0, 0] == 0.0
    np.testing.assert_allclose([ci[0, 1, 0, 0], ci[0, 2, 0, 1]], [0.025 ** (1 / n), 1 - 0.025 ** (1 / n)])
    times, _ = res.summary_frames()
    assert times[["p_exceed_30s_ci95_lo", "p_exceed_30s_ci95_hi"]].to_numpy()[0].tolist() == ci[0, 0, 0].tolist()
    for bad in (1.0, "0.9", True):
        with pytest.raises(ValueError, match=r"^confidence: expected a number in \(0, 1\)"):
            res.p_exceed_interval(bad)


def test_cli_planning_writes_the_report(tmp_path, capsys):
    from hybridship.cli import main

    out = tmp_path / "plan"
    out.mkdir()
    for name in ("polar.png", "season.csv", "notes.txt"):  # an earlier run's figure and season; a user's file
        (out / name).write_text("earlier")
    (out / ".hybridship-outputs.json").write_text('["polar.png", "season.csv"]')   # as the earlier run left it
    assert main(["drift-off", "planning", "--out", str(out), "--samples", "3", "--headings-deg", "0,90",
                 "--horizon-s", "90", "--no-plots"]) == 0
    times = pd.read_csv(out / "times.csv")
    assert len(times) == 2 * 3 and (out / "summary.md").is_file() and (out / "watch.csv").is_file()
    # no figure of the earlier run, nor its season, beside the new tables; other files untouched
    assert not (out / "polar.png").exists() and not (out / "season.csv").exists()
    assert (out / "notes.txt").read_text() == "earlier"
    first = capsys.readouterr().out
    assert "Time to reach" in first and "| vessel spread | 1 x [true_vessel] |" in first
    # a vessel file without [true_vessel] factors has no spread to draw, and the summary says so
    text = (ROOT / "vessels" / "gunnerus.toml").read_text()
    plain = tmp_path / "plain.toml"
    plain.write_text(text[:text.index("[true_vessel]")])
    assert main(["drift-off", "planning", "--vessel", str(plain), "--out", str(out), "--samples", "2",
                 "--headings-deg", "0", "--horizon-s", "60", "--no-plots"]) == 0
    assert "| vessel spread | none: the vessel file has no [true_vessel] factors" in (out / "summary.md").read_text()


def _failure_log():
    files = sorted(TRUTHSIM_DEV.glob("dev_*.csv.gz")) if TRUTHSIM_DEV.is_dir() else []
    if not files:
        pytest.skip(f"truthsim-dev logs not found under {TRUTHSIM_DEV}")
    df = pd.read_csv(files[0])
    dp = df["dp_active"].to_numpy()
    i = int(np.flatnonzero((dp[:-1] == 1) & (dp[1:] == 0))[0])
    return df, i


def test_live_update_is_fast_and_does_not_touch_the_log():
    df, i = _failure_log()
    hist = df.iloc[: i + 1]
    before = hist.copy()
    st = DriftOffSettings(n_samples=100, radii_m=(5.0, 10.0))
    blackout_now(environment_from_log(hist, "gunnerus"), "gunnerus", st)       # compile / warm up
    t0 = time.perf_counter()
    est = environment_from_log(hist, "gunnerus")
    res = blackout_now(est, "gunnerus", st)
    dt = time.perf_counter() - t0
    pd.testing.assert_frame_equal(hist, before)
    assert dt < 1.0, f"live update took {dt:.2f} s"
    assert np.all(np.isfinite(est.accel_ned)) and est.accel_members.shape == (100, 3)
    assert res.t_reach_s.shape == (1, 100, 2) and np.isfinite(res.t_reach_s).mean() > 0.5


def test_live_samples_each_draw_their_own_environment_or_are_warned():
    """The environment's spread dominates a live prediction: 500 samples cycling through the
    20 members of the earlier default had the quantiles of 20 draws. The default members cover
    the default samples,
    and fewer members than samples are warned."""
    import warnings

    df, i = _failure_log()
    hist = df.iloc[: i + 1]
    st = DriftOffSettings(radii_m=(5.0,), horizon_s=120.0)       # the default samples, not a count of its own
    est = environment_from_log(hist, "gunnerus")
    assert np.unique(est.accel_members, axis=0).shape[0] == st.n_samples
    assert np.unique(est.current_members_ned_m_s, axis=0).shape[0] == st.n_samples
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        blackout_now(est, "gunnerus", st)
    few = environment_from_log(hist, "gunnerus", n_members=20)
    with pytest.warns(UserWarning, match=r"^estimate: 20 environment members for 100 samples: .* n_members >= "):
        blackout_now(few, "gunnerus", st)


def test_live_refuses_a_time_without_station_keeping_and_bad_estimates():
    """A blackout is predicted from station keeping: a log whose last row used is in the drift
    is refused; an estimate with NaN, missing or absurd fields names the field, never reads
    as "never reached"."""
    import dataclasses

    df, i = _failure_log()
    with pytest.raises(ValueError, match="dp_active is 0"):
        environment_from_log(df.iloc[: i + 30], "gunnerus")
    est = environment_from_log(df.iloc[: i + 1], "gunnerus")
    assert est.wind_measured and not environment_from_log(
        df.iloc[: i + 1].drop(columns=["wind_speed_m_s", "wind_dir_deg"]), "gunnerus").wind_measured
    st = DriftOffSettings(n_samples=3, horizon_s=60.0)
    for change, field in ((dict(accel_members=np.full((20, 3), np.nan)), "estimate.accel_members"),
                          (dict(accel_members=np.zeros(3)), "estimate.accel_members"),
                          (dict(eta=np.array([0.0, np.nan, 0.0])), "estimate.eta"),
                          (dict(rpm=np.array([100.0])), "estimate.rpm"),
                          (dict(rpm=np.array([0.0, 1e6, 0.0])), r"rpm\[batch 0, thruster 'port'\]")):
        with pytest.raises(ValueError, match=field):
            blackout_now(dataclasses.replace(est, **change), "gunnerus", st)
    with pytest.raises(TypeError, match="settings"):
        blackout_now(est, "gunnerus", [3])


def test_live_mean_wind_is_the_mean_speed_towards_the_mean_direction():
    """A steady 10 m/s whose direction swings 30 deg either side of north, 20 s each way:
    the mean wind is 10 m/s from north, with no gusts. The vector mean's length, used
    before, read 8.66 m/s (10 cos 30 deg)."""
    df, i = _failure_log()
    hist = df.iloc[: i + 1].copy()
    n = len(hist)
    hist["wind_speed_m_s"] = 10.0
    hist["wind_dir_deg"] = np.where((np.arange(n) // 20) % 2 == 0, 30.0, 330.0)
    est = environment_from_log(hist, "gunnerus")
    assert est.wind_speed_m_s == pytest.approx(10.0, abs=1e-12)
    assert abs(np.degrees(est.wind_dir_from_rad)) < 1.0 and est.gust_intensity == 0.0


def test_live_reads_the_log_as_a_forecast_does():
    """The live estimate takes the log through the forecasts' ingest: a thruster's missing
    rpm column is refused (not taken as stopped); a dead wind sensor is no wind measurement
    (not its last value held); the wind's window does not shrink with the estimator's."""
    from hybridship.logs.io import LogFormatError

    df, i = _failure_log()
    hist = df.iloc[: i + 1]
    with pytest.raises(LogFormatError, match="port_rpm"):
        environment_from_log(hist.drop(columns=["port_rpm"]), "gunnerus")
    dead = hist.copy()
    dead.loc[dead.index[-150:], ["wind_speed_m_s", "wind_dir_deg"]] = np.nan
    with pytest.warns(UserWarning, match="no valid wind sample"):
        assert not environment_from_log(dead, "gunnerus").wind_measured
    full, short = environment_from_log(hist, "gunnerus"), environment_from_log(hist, "gunnerus", window_s=60.0)
    assert (short.wind_speed_m_s, short.gust_intensity) == (full.wind_speed_m_s, full.gust_intensity)
    assert full.gust_intensity > 0
    for kw in (dict(window_s=2.0), dict(wind_window_s=1.0)):
        with pytest.raises(ValueError, match=f"{next(iter(kw))}: expected a number of seconds >= "):
            environment_from_log(hist, "gunnerus", **kw)


def test_live_refuses_empty_commands_and_faulty_sensors_at_the_blackout_row():
    """An empty command column is not a stopped thruster (nor an active DP): refused naming
    the column. The blackout row goes through a forecast's start-window checks: a position
    dropout over the window is refused, a last position missing is bridged, warned, and
    noted in the estimate."""
    from hybridship.logs.io import LogFormatWarning

    df, i = _failure_log()
    hist = df.iloc[: i + 1]
    for col in ("tunnel_rpm", "port_azimuth_deg", "dp_active"):
        with pytest.raises(ValueError, match=f"column '{col}' has no value in the last 900 s"):
            environment_from_log(hist.assign(**{col: np.nan}), "gunnerus")
    # a column the reader ignores (a tunnel has no azimuth) is not checked; commands logged on
    # different rows are held by the reader, as in a forecast
    with pytest.warns(UserWarning, match="tunnel_azimuth_deg .thruster 'tunnel' is not rotatable"):
        environment_from_log(hist.assign(tunnel_azimuth_deg=np.nan), "gunnerus")
    alternate = hist.copy()
    alternate.loc[alternate.index[1::2], ["tunnel_rpm", "port_rpm", "stbd_rpm"]] = np.nan
    alternate.loc[alternate.index[::2], ["port_azimuth_deg", "stbd_azimuth_deg"]] = np.nan
    with pytest.warns(UserWarning, match=r"missing commands"):
        held = environment_from_log(alternate, "gunnerus")
    last = alternate[["tunnel_rpm", "port_rpm", "stbd_rpm", "port_azimuth_deg", "stbd_azimuth_deg"]].ffill().iloc[-1]
    np.testing.assert_array_equal(held.rpm, last.iloc[:3])                     # each channel's last logged value
    np.testing.assert_allclose(held.azimuth_rad[1:], np.radians(last.iloc[3:]), rtol=1e-12)
    gap = hist.copy()
    gap.loc[gap.index[-300:], ["north_m", "east_m"]] = np.nan
    with pytest.raises(ValueError, match="at the blackout row: .*too little valid data.*position"):
        environment_from_log(gap, "gunnerus")
    last = hist.copy()
    last.loc[last.index[-1], "north_m"] = np.nan
    with pytest.warns(LogFormatWarning, match="at the blackout row .*missing position"):
        est = environment_from_log(last, "gunnerus")
    assert "missing position" in est.notes and environment_from_log(hist, "gunnerus").notes == ""
    knots = hist.assign(wind_speed_m_s=60.0)
    with pytest.raises(ValueError, match=r"column 'wind_speed_m_s': the mean wind over the last 120 s .* is 60.0 m/s"):
        environment_from_log(knots, "gunnerus")


def test_live_empty_command_message_gives_an_epoch_time_as_the_log_has_it():
    """The time up to which a command column is empty was written with %g, so a log in epoch
    seconds read 'up to time_s 1.7e+09', which locates no row; it is the log's time in full."""
    t0 = 1_700_000_000.0
    log = pd.DataFrame({"time_s": t0 + np.arange(5.0), "tunnel_rpm": np.nan})
    with pytest.raises(ValueError, match=r"column 'tunnel_rpm' has no value in the last 900 s up to time_s "
                                         r"1700000004; "):
        environment_from_log(log, "gunnerus")


def test_live_bad_input_names_the_field():
    with pytest.raises(TypeError, match="log"):
        environment_from_log([1, 2, 3], "gunnerus")
    with pytest.raises(ValueError, match="window_s"):
        environment_from_log(pd.DataFrame({"time_s": [0.0, 1.0, 2.0]}), "gunnerus", window_s=-5)
    # refused before the log is read (it was numpy's "Unable to allocate 21.8 TiB", after the work)
    with pytest.raises(ValueError, match=r"^n_members: expected a whole number from 1 to 1000000"):
        environment_from_log(pd.DataFrame({"time_s": [0.0, 1.0, 2.0]}), "gunnerus", n_members=10**12)


def _still_estimate(**change):
    """An estimate of a still vessel in a 5 m/s wind (no log needed)."""
    from hybridship.driftoff.live import EnvironmentEstimate

    return EnvironmentEstimate(0.0, np.zeros(3), np.array([0.1, 0.0, 0.0]), np.zeros(3), np.zeros(3), 5.0, 0.0, 0.1,
                               np.zeros(3), np.zeros((1, 3)), vessel_name="gunnerus", **change)


def test_live_refuses_a_start_at_rest_that_is_not_true_or_false():
    """``start_at_rest="no"`` was read as True (a text is truthy)."""
    est, st = _still_estimate(), DriftOffSettings(n_samples=2, horizon_s=30.0, reaction_times_s=(10.0,))
    for flag in ("no", "False", 0, None):
        with pytest.raises(TypeError, match=r"^start_at_rest: expected True or False, got"):
            blackout_now(est, "gunnerus", st, start_at_rest=flag)
    np.testing.assert_array_equal(blackout_now(est, "gunnerus", st, start_at_rest=np.bool_(True)).excursion_m,
                                  blackout_now(est, "gunnerus", st, start_at_rest=True).excursion_m)


def test_live_takes_settings_and_the_estimators_config_as_dicts():
    """As simulate_blackouts does: ``settings={"n_samples": 4}`` was a TypeError and
    ``environment_config={...}`` an AttributeError deep in the estimator; a misspelt key is
    refused naming the argument and the field, before the log is read."""
    from hybridship.residual.environment import EnvironmentConfig

    est = _still_estimate()
    kw = dict(n_samples=3, horizon_s=30.0, reaction_times_s=(10.0,))
    np.testing.assert_array_equal(blackout_now(est, "gunnerus", kw).excursion_m,
                                  blackout_now(est, "gunnerus", DriftOffSettings(**kw)).excursion_m)
    assert blackout_now(est, "gunnerus", {}).n_samples == DriftOffSettings().n_samples   # as simulate_blackouts
    with pytest.raises(ValueError, match=r"^settings: n_sample: not a known field"):
        blackout_now(est, "gunnerus", {"n_sample": 3})
    with pytest.raises(TypeError, match=r"^settings: expected an instance of DriftOffSettings"):
        blackout_now(est, "gunnerus", "fast")
    tiny = pd.DataFrame({"time_s": [0.0, 1.0, 2.0]})
    with pytest.raises(ValueError, match=r"^environment_config: filter_stepp_s: not a known field"):
        environment_from_log(tiny, "gunnerus", environment_config={"filter_stepp_s": 1.0})
    with pytest.raises(TypeError, match=r"^environment_config: expected an instance of EnvironmentConfig"):
        environment_from_log(tiny, "gunnerus", environment_config="default")
    df, i = _failure_log()
    hist = df.iloc[: i + 1]
    by_dict = environment_from_log(hist, "gunnerus", environment_config={"held_load_window_s": 0.0})
    by_config = environment_from_log(hist, "gunnerus", environment_config=EnvironmentConfig(held_load_window_s=0.0))
    np.testing.assert_array_equal(by_dict.accel_members, by_config.accel_members)


def test_live_refuses_a_few_seconds_of_log():
    df, i = _failure_log()
    with pytest.raises(ValueError, match=r"log: only 4 s of log up to the blackout .* at least 60 s"):
        environment_from_log(df.iloc[:5], "gunnerus")
    # the shortest window on a log whose times do not fall on whole seconds: accepted
    jittered = df.iloc[: i + 1].assign(time_s=df["time_s"].iloc[: i + 1] + 0.25)
    jittered.loc[jittered.index[-1], "time_s"] += 0.1
    environment_from_log(jittered, "gunnerus", window_s=60.0)


def test_cli_refuses_an_out_where_the_report_would_replace_an_input(tmp_path, capsys):
    from hybridship.cli import main

    folder = tmp_path / "inputs"
    folder.mkdir()
    table = folder / "season.csv"                  # season writes season.csv there
    states_to_frame([WeatherState()]).to_csv(table, index=False)
    log = folder / "times.csv"                     # live writes times.csv there
    log.write_text("time_s\n0\n")
    before = {p: p.read_bytes() for p in (table, log)}
    assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", "none",
                 "--out", str(folder)]) == 2
    assert "season.csv there is the --weather-table file" in capsys.readouterr().err
    assert main(["drift-off", "live", "--log", str(log), "--out", str(folder)]) == 2
    assert "times.csv there is the --log file" in capsys.readouterr().err
    assert all(p.read_bytes() == b for p, b in before.items())
    assert sorted(p.name for p in folder.iterdir()) == ["season.csv", "times.csv"]


def test_cli_season_in_this_process(tmp_path):
    from hybridship.cli import main

    states = [WeatherState.from_degrees(wind_speed_m_s=u, wind_dir_deg=40.0, hs_m=0.5, tp_s=5.0) for u in (6.0, 12.0)]
    table = tmp_path / "weather.csv"
    states_to_frame(states, ["h0", "h1"]).to_csv(table, index=False)
    out = tmp_path / "season"
    out.mkdir()
    for name in ("times.csv", "watch.csv", "notes.txt"):    # an earlier planning report; a user's file
        (out / name).write_text("earlier")
    (out / ".hybridship-outputs.json").write_text('["times.csv", "watch.csv"]')
    assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", "none", "--samples", "3",
                 "--headings-deg", "0,90", "--horizon-s", "90", "--no-progress", "--out", str(out)]) == 0
    season = pd.read_csv(out / "season.csv")
    assert len(season) == 2 * 2 * 3 and list(season["label"].unique()) == ["h0", "h1"]
    assert season["reached_frac"].between(0.0, 1.0).all() and (season["over_capacity_frac"] == 0.0).all()
    assert (out / "operability.csv").is_file() and (out / "summary.md").is_file()
    # the planning tables would read as the season's: gone; the user's file untouched
    assert not (out / "times.csv").exists() and not (out / "watch.csv").exists()
    assert (out / "notes.txt").read_text() == "earlier"


def test_cli_season_workers_only_with_a_local_cluster(tmp_path, capsys):
    from hybridship.cli import main

    table = tmp_path / "weather.csv"
    states_to_frame([WeatherState()]).to_csv(table, index=False)
    assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", "none", "--workers", "4",
                 "--out", str(tmp_path / "o")]) == 2
    assert "--workers 4 is for --scheduler local" in capsys.readouterr().err and not (tmp_path / "o").exists()
    # the keyword in another case is the same keyword: this process, not "the cluster"
    assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", "None", "--workers", "4",
                 "--out", str(tmp_path / "o")]) == 2
    assert "the workers are this process" in capsys.readouterr().err


def test_cli_live_on_a_truthsim_log(tmp_path, capsys):
    files = sorted(TRUTHSIM_DEV.glob("dev_*.csv.gz")) if TRUTHSIM_DEV.is_dir() else []
    if not files:
        pytest.skip(f"truthsim-dev logs not found under {TRUTHSIM_DEV}")
    from hybridship.cli import main

    out = tmp_path / "live"
    assert main(["drift-off", "live", "--log", str(files[0]), "--time-s", "2900", "--samples", "10",
                 "--radii-m", "5,10", "--no-plots", "--out", str(out)]) == 0
    times = pd.read_csv(out / "times.csv")
    assert len(times) == 2
    capsys.readouterr()
    assert main(["drift-off", "live", "--log", str(files[0]), "--time-s", "1e9", "--out", str(out)]) == 2
    assert "--time-s 1000000000 is outside the log" in capsys.readouterr().err


def test_cli_refuses_an_out_folder_that_holds_logs(tmp_path, capsys):
    """The report's CSV tables would be read as logs by a later train in that folder: a
    folder with a log is refused before the work; other CSV files (a weather table) are not logs."""
    from hybridship.cli import main

    argv = ["drift-off", "planning", "--samples", "3", "--radii-m", "5", "--no-plots", "--out"]
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "run1.csv").write_text("time_s,north_m,east_m,heading_deg\n0,0,0,0\n")
    assert main(argv + [str(logs)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "holds logs (run1.csv)" in err and not (logs / "times.csv").exists()
    other = tmp_path / "other"
    other.mkdir()
    (other / "hindcast.csv").write_text("wind_speed_m_s,wind_dir_deg\n5,10\n")
    assert main(argv + [str(other)]) == 0 and (other / "times.csv").is_file()


def test_cli_live_reads_a_log_as_forecast_and_train_do(tmp_path):
    """Rows out of time order are re-sorted, and a fault after --time-s does not matter: the
    one ingest checks the rows the estimate uses; the result is that of the clean log."""
    from hybridship.cli import main
    from hybridship.logs.io import write_log
    from hybridship.physics.model import DynamicModel
    from hybridship.sim.synthetic import physics_log

    df = physics_log(DynamicModel("gunnerus"), seed=2, duration_s=600.0, t_shutdown_s=None)
    argv = ["drift-off", "live", "--time-s", "500", "--samples", "5", "--radii-m", "5", "--no-plots"]
    write_log(df, tmp_path / "clean.csv")
    messy = df.iloc[::-1].copy()
    messy.loc[messy.time_s > 550, "north_m"] = np.nan
    messy.to_csv(tmp_path / "messy.csv", index=False)
    for name in ("clean", "messy"):
        assert main(argv + ["--log", str(tmp_path / f"{name}.csv"), "--out", str(tmp_path / name)]) == 0
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "clean" / "times.csv"),
                                  pd.read_csv(tmp_path / "messy" / "times.csv"))


def test_cli_live_refuses_a_time_in_a_gap_of_the_log(tmp_path, capsys):
    """A --time-s with no sample within 1.5 steps before it (in a gap of the log) is refused
    naming --time-s and the samples around the gap; before, the blackout silently started
    from the last sample before the gap, a state 19 s old. A time between two samples is
    the earlier sample, as before."""
    from hybridship.cli import main
    from hybridship.physics.model import DynamicModel
    from hybridship.sim.synthetic import physics_log

    df = physics_log(DynamicModel("gunnerus"), seed=2, duration_s=600.0, t_shutdown_s=None)
    df[(df.time_s < 481) | (df.time_s > 510)].to_csv(tmp_path / "gap.csv", index=False)
    argv = ["drift-off", "live", "--log", str(tmp_path / "gap.csv"), "--samples", "3", "--radii-m", "5",
            "--no-plots", "--out"]
    assert main(argv + [str(tmp_path / "in_gap"), "--time-s", "500"]) == 2
    err = capsys.readouterr().err
    assert "--time-s 500" in err and "a gap of the log" in err and "480 s" in err and "511 s" in err, err
    assert not (tmp_path / "in_gap").exists()
    assert main(argv + [str(tmp_path / "between"), "--time-s", "450.5"]) == 0
    assert "| blackout at [s] | 450 |" in capsys.readouterr().out


def test_live_vessel_spread_is_the_settings_spread():
    """A steady beam wind, no gusts, one environment member: the vessel draws are the only
    randomness, so ``vessel_spread=0`` gives every sample the same drift and the default
    spread makes them differ (a live prediction that drew at spread 1 whatever the settings
    said passed every other test)."""
    from hybridship.driftoff.live import EnvironmentEstimate

    z3 = np.zeros(3)
    est = EnvironmentEstimate(time_s=0.0, eta=z3, nu=z3, rpm=z3, azimuth_rad=z3, wind_speed_m_s=12.0,
                              wind_dir_from_rad=math.pi / 2, gust_intensity=0.0, accel_ned=z3,
                              accel_members=np.zeros((1, 3)))
    kw = dict(n_samples=4, horizon_s=60.0, radii_m=(5.0,), reaction_times_s=(60.0,))
    exc = {s: blackout_now(est, "gunnerus", DriftOffSettings(vessel_spread=s, **kw)).excursion_m[0, :, 0]
           for s in (0.0, 1.0)}
    assert exc[0.0].max() > 1.0                                 # a drift to compare, not zeros
    assert np.ptp(exc[0.0]) < 1e-9 * exc[0.0].max(), exc[0.0]
    assert np.ptp(exc[1.0]) > 1e-3 * exc[1.0].max(), exc[1.0]


def _scipy_time_carried_by_current(current, psi0, radii):
    """Independent adaptive solve of the nominal model's drift from rest with the thrusters
    stopped, in a constant current ``[speed_m_s, dir_to_rad]`` only, from heading ``psi0``
    [rad]: the times [s] at which the ship first reaches each of ``radii`` [m] (inf if not
    within 300 s)."""
    model = get_model("gunnerus")
    K = model.n_actuators
    az = np.array([t.fixed_angle_rad for t in model.vessel.thrusters])

    def rhs(t, x):
        nd = model.acceleration(x[:3], x[3:], rpm=np.zeros(K), azimuth_rad=az, current=current)[0]
        c, s = math.cos(x[2]), math.sin(x[2])
        return [c * x[3] - s * x[4], s * x[3] + c * x[4], x[5], *nd]

    events = []
    for R in radii:
        ev = lambda t, x, R=R: math.hypot(x[0], x[1]) - R  # noqa: E731
        ev.direction = 1
        events.append(ev)
    sol = solve_ivp(rhs, (0.0, 300.0), [0.0, 0.0, psi0, 0.0, 0.0, 0.0], method="DOP853", rtol=1e-8, atol=1e-9,
                    events=events)
    return np.array([e[0] if len(e) else np.inf for e in sol.t_events])


def test_live_current_members_carry_the_vessel_along():
    """A still ship, no wind, the thrusters stopped: nothing moves her without a current; a
    current member of 0.5 m/s towards east ([north, east] in NED) carries her as an
    independent solve of the model in that current does, at headings 0 and 0.6 rad (a
    current read as coming FROM east, or turned with the heading as if given in the body
    frame, reaches the radii at other times; at heading 0 a mirror image hides both)."""
    from hybridship.driftoff.live import EnvironmentEstimate

    z3 = np.zeros(3)
    az = np.array([t.fixed_angle_rad for t in get_model("gunnerus").vessel.thrusters])
    est = EnvironmentEstimate(time_s=0.0, eta=z3, nu=z3, rpm=z3, azimuth_rad=az, wind_speed_m_s=0.0,
                              wind_dir_from_rad=0.0, gust_intensity=0.0, accel_ned=z3, accel_members=np.zeros((1, 3)))
    radii = (5.0, 50.0)
    st = DriftOffSettings(n_samples=2, horizon_s=300.0, radii_m=radii, reaction_times_s=(300.0,),
                          vessel_spread=0.0)
    assert np.all(np.isinf(blackout_now(est, "gunnerus", st).t_reach_s))
    import dataclasses

    for psi0 in (0.0, 0.6):
        moving = dataclasses.replace(est, eta=np.array([0.0, 0.0, psi0]),
                                     current_members_ned_m_s=np.array([[0.0, 0.5]]))   # 0.5 m/s towards east
        r = blackout_now(moving, "gunnerus", st)
        expected = _scipy_time_carried_by_current([0.5, math.pi / 2], psi0, radii)
        assert np.all(np.isfinite(expected)) and 100.0 < expected[1] < 200.0      # carried along, not at once
        np.testing.assert_allclose(r.t_reach_s[0, :], np.broadcast_to(expected, (2, 2)), rtol=0.01,
                                   err_msg=f"heading {psi0} rad")


def test_cli_error_names_the_whole_command(monkeypatch, capsys):
    import hybridship.driftoff.command as command
    from hybridship.cli import main

    def refuse(args):
        raise ValueError("rpm: expected at most 200 rpm, got 1e+06")

    monkeypatch.setattr(command, "_cmd_live", refuse)
    assert main(["drift-off", "live", "--log", "x.csv", "--out", "o"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("hybridship drift-off live: error: rpm:"), err
    # an unknown option is named with the command it was given to
    assert main(["drift-off", "live", "--log", "x.csv", "--out", "o", "--bogus"]) == 2
    assert capsys.readouterr().err == "hybridship drift-off live: error: unrecognized arguments: --bogus\n"
    assert main(["--bogus", "drift-off", "live", "--log", "x.csv", "--out", "o"]) == 2    # given to the top level
    assert capsys.readouterr().err == "hybridship: error: unrecognized arguments: --bogus\n"


@pytest.mark.parametrize("seed, ok", [("0", True), ("4294967295", True), ("4294967296", False), ("-1", False)])
def test_cli_seed_bounds(seed, ok):
    import argparse

    from hybridship.cli import _seed

    if ok:
        assert _seed(seed) == int(seed)
    else:
        with pytest.raises(argparse.ArgumentTypeError, match="0..4294967295"):
            _seed(seed)


def test_headings_in_degrees_or_repeated_are_refused():
    w = WeatherState()
    st = DriftOffSettings(n_samples=2, horizon_s=30.0, reaction_times_s=(10.0,))
    for headings, why in (([0.0, 90.0, 180.0], "expected radians"), ([0.0, 0.0], "expected each heading once"),
                          ([0.0, 2 * math.pi], "expected each heading once"), ([], "expected a non-empty")):
        with pytest.raises(ValueError, match=f"headings: {why}"):
            simulate_blackouts("gunnerus", w, headings, settings=st)
    with pytest.raises(ValueError, match="headings: expected radians"):
        season_sweep("gunnerus", [w], [0.0, 90.0], settings=st, scheduler=None)


def test_headings_that_are_not_numbers_in_order_are_refused_by_name():
    """A set, a generator or a complex number failed in float()'s words; "0" and [True] were
    read as 0 and 1 rad. Numbers in a list, tuple or array are taken, as a copy."""
    from hybridship.driftoff.planning import check_headings

    for headings in ({0.0, 1.0}, (h for h in [0.0]), 1j, [1j], "0", b"0", ["0", "1"], [True], True,
                     np.array([True]), {"a": 1.0}, None):
        with pytest.raises(TypeError, match=r"^headings: expected a number or a list of numbers \(angles in radians"):
            check_headings(headings)
    for ok in (0.5, np.float32(0.5), [0, 1], (0.0, np.int64(1)), pd.Series([0.0, 1.0])):
        assert check_headings(ok).dtype == float
    given = np.array([0.0, 1.0])
    check_headings(given)[0] = 3.0
    assert given[0] == 0.0
    with pytest.raises(TypeError, match="^headings: "):
        simulate_blackouts("gunnerus", WeatherState(), {0.0, 1.0})


def test_live_blackout_refuses_a_diverging_drift():
    import dataclasses

    df, i = _failure_log()
    est = environment_from_log(df.iloc[: i + 1], "gunnerus")
    st = DriftOffSettings(n_samples=4, horizon_s=60.0, reaction_times_s=(30.0,))
    with pytest.raises(FloatingPointError, match="drifts diverged \\(estimate"):
        blackout_now(dataclasses.replace(est, accel_members=np.full((4, 3), 10.0)), "gunnerus", st)
    assert est.vessel_name == "gunnerus"
    with pytest.raises(ValueError, match="estimate: made from a log of vessel 'gunnerus', not of 'esso_osaka_model'"):
        blackout_now(est, "esso_osaka_model", st)


def test_the_report_never_replaces_or_removes_a_file_of_the_users(tmp_path, capsys):
    """A weather table named season.csv and notes named summary.md in --out were deleted and
    overwritten; now refused before the work, and an earlier report (with or without the
    folder's record of its files) is still replaced, read-only files refused up front."""
    from hybridship.cli import main

    run = ["drift-off", "planning", "--samples", "3", "--headings-deg", "0", "--horizon-s", "60", "--no-plots"]
    out = tmp_path / "mine"
    out.mkdir()
    (out / "season.csv").write_text("time,wind_speed_m_s\n0,10\n")
    (out / "summary.md").write_text("my notes")
    assert main(run + ["--out", str(out)]) == 2
    assert "summary.md: exists and was not written by hybridship" in capsys.readouterr().err
    (out / "summary.md").unlink()
    assert main(run + ["--out", str(out)]) == 2
    assert "season.csv: exists and was not written by hybridship; it would be removed" in capsys.readouterr().err
    assert (out / "season.csv").read_text() == "time,wind_speed_m_s\n0,10\n"
    report = tmp_path / "report"
    assert main(run + ["--out", str(report)]) == 0
    (report / ".hybridship-outputs.json").unlink()          # a report from before the record
    assert main(run + ["--out", str(report), "--seed", "3"]) == 0
    before = (report / "times.csv").read_bytes()
    (report / "watch.csv").chmod(0o444)
    assert main(run + ["--out", str(report), "--seed", "4"]) == 2
    assert "watch.csv: is read-only" in capsys.readouterr().err and (report / "times.csv").read_bytes() == before


def test_a_drift_that_diverges_after_the_reaction_times_is_refused_too():
    """A spinning start state blows the drift up within seconds, after the 1-s reaction time:
    its samples "reached" every radius on the way and were counted as results."""
    from hybridship.driftoff.live import EnvironmentEstimate

    est = EnvironmentEstimate(0.0, np.zeros(3), np.array([0.0, 0.0, 3.0]), np.zeros(3), np.zeros(3), 10.0, 0.0,
                              0.1, np.zeros(3), np.zeros((1, 3)))
    st = DriftOffSettings(n_samples=20, radii_m=(5.0, 50.0, 500.0, 5000.0), reaction_times_s=(1.0,), horizon_s=300.0)
    up_to_reaction = blackout_now(est, "gunnerus", DriftOffSettings(n_samples=20, radii_m=(5.0,), reaction_times_s=(1.0,),
                                                                    horizon_s=1.0))
    assert np.all(up_to_reaction.excursion_m < 31.0)      # nothing wrong yet at the reaction time ...
    with pytest.raises(FloatingPointError, match="drifts diverged"):
        blackout_now(est, "gunnerus", st)                  # ... the blow-up comes after it


def test_a_season_state_that_diverges_is_named_by_its_label(monkeypatch):
    """The sweep stops at a state whose drifts diverge and names it by its label; the chunk
    returns the error rather than raising it, so a Dask worker does not log a crash."""
    from hybridship.driftoff import season
    from hybridship.driftoff.season import run_chunk, season_sweep

    real = season.simulate_blackouts

    def diverging(vessel, state, headings, **kw):
        if kw["index"] == 1:
            raise FloatingPointError("3 of 8 drifts diverged (weather: the state of index 1 or its spread)")
        return real(vessel, state, headings, **kw)
    monkeypatch.setattr(season, "simulate_blackouts", diverging)
    st = DriftOffSettings(**CALM_FAST)
    out = run_chunk("gunnerus", [WeatherState()] * 2, [0, 1], [0.0], None, st, 0.9, ["h0", "h1"])
    assert out["error"].endswith("(label 'h1')")
    with pytest.raises(FloatingPointError, match=r"state of index 1 or its spread\) \(label 'h1'\)"):
        season_sweep("gunnerus", [WeatherState()] * 3, [0.0], settings=st, labels=["h0", "h1", "h2"],
                     chunk_size=2, progress=False)


def test_result_queries_and_the_state_index_refuse_values_that_would_read_as_zero():
    w = WeatherState()
    st = DriftOffSettings(n_samples=2, horizon_s=30.0, reaction_times_s=(10.0,))
    res = simulate_blackouts("gunnerus", w, [0.0], settings={"n_samples": 2, "horizon_s": 30.0,
                                                              "reaction_times_s": (10.0,)})
    assert res.n_samples == 2                              # settings as a dict of their fields
    for index in (-1, 1.5, "a", True):
        with pytest.raises(ValueError, match="index: expected a whole number >= 0"):
            simulate_blackouts("gunnerus", w, [0.0], settings=st, index=index)
    with pytest.raises(ValueError, match="time_s: expected finite times >= 0 s"):
        res.exceedance_curves([-1.0, np.nan])
    with pytest.raises(ValueError, match="q: expected quantiles in"):
        res.time_quantiles((2.0,))
    # the 0.9 quantile of 7 samples of which one never reached is "never" (6/7 < 0.9), and
    # with 10 samples the 10th smallest, as the inverse of the samples' distribution
    import dataclasses
    seven = dataclasses.replace(res, t_reach_s=np.array([10.0, 20, 30, 40, 50, 60, np.inf])[None, :, None])
    np.testing.assert_array_equal(seven.time_quantiles((0.5, 0.9))[0, 0], [40.0, np.inf])
    ten = dataclasses.replace(res, t_reach_s=np.arange(1.0, 11.0)[None, :, None])
    np.testing.assert_array_equal(ten.time_quantiles((0.1, 0.5, 0.9))[0, 0], [1.0, 5.0, 9.0])
    season = season_sweep("gunnerus", [w], [0.0], settings=st, scheduler=None)
    for p in (np.nan, 2.0, -1.0, None, "0.1", True):
        with pytest.raises(ValueError, match="max_p_exceed: expected a probability"):
            season.operability(p)


def test_result_queries_refuse_text_and_lists_where_numbers_go():
    """``time_quantiles("a")``, ``exceedance_curves("abc")`` and ``summary_frames("x")`` failed
    with "could not convert string to float", ``watch_circle([0.5, 0.9])`` in float()'s words,
    and ``watch_circle("0.9")`` was taken."""
    res = simulate_blackouts("gunnerus", WeatherState(wind_speed_m_s=8.0), [0.0],
                             settings=DriftOffSettings(n_samples=2, horizon_s=30.0, reaction_times_s=(10.0,)))
    for q in ("a", "0.5", True, [True, 0.5], {0.5}):
        with pytest.raises(ValueError, match=r"^q: expected quantiles in \[0, 1\]"):
            res.time_quantiles(q)
    for t in ("abc", "10", True, [10.0, "20"]):
        with pytest.raises(ValueError, match=r"^time_s: expected finite times >= 0 s"):
            res.exceedance_curves(t)
    for quantile in ("x", "0.9", [0.5, 0.9], None):
        with pytest.raises(ValueError, match=r"^quantile: expected a number in \(0, 1\)"):
            res.watch_circle(quantile)
        with pytest.raises(ValueError, match=r"^quantile: expected a number in \(0, 1\)"):
            res.summary_frames(quantile)
    np.testing.assert_array_equal(res.watch_circle(np.float64(0.5)), res.watch_circle(0.5))
    assert res.exceedance_curves(np.arange(3)).shape == (1, 3, 3)


def test_report_arguments_are_refused_by_name(tmp_path):
    """``write_report(r, None)`` failed in os' words, ``inputs="x"`` with an AttributeError and
    ``plots="no"`` drew the figures; nothing is written."""
    from hybridship.driftoff.report import write_report, write_season_report

    res = simulate_blackouts("gunnerus", WeatherState(wind_speed_m_s=8.0), [0.0],
                             settings=DriftOffSettings(n_samples=2, horizon_s=30.0, reaction_times_s=(10.0,)))
    out = tmp_path / "d"
    for args, kwargs, message in (((res, None), {}, "out_dir: expected a file path"), ((res, out), dict(inputs="x"),
                                  "inputs: expected a dict"), ((res, out), dict(plots="no"), "plots: expected True or "
                                  "False"), ((res, out), dict(title=None), "title: expected text"),
                                  (({}, out), {}, "result: expected a DriftOffResult")):
        with pytest.raises(TypeError, match=f"^{message}"):
            write_report(*args, **kwargs)
    with pytest.raises(ValueError, match="^out_dir: expected a file path, got an empty one"):
        write_report(res, "", plots=False)
    with pytest.raises(TypeError, match="^out_dir: "):
        write_season_report(None, pd.DataFrame(), pd.DataFrame(), "")
    # a SeasonResult, a dict or bytes where the tables and the summary go: named, not "no attribute 'to_csv'"
    for args, name in (((res, pd.DataFrame(), ""), "season"), ((pd.DataFrame(), {"a": [1]}, ""), "operability"),
                       ((pd.DataFrame(), pd.DataFrame(), b"x"), "summary")):
        with pytest.raises(TypeError, match=f"^{name}: expected "):
            write_season_report(out, *args)
    assert not out.exists()
    assert write_report(res, str(out), inputs={"vessel": "gunnerus"}, plots=False)["summary.md"].is_file()


def test_cli_takes_a_list_that_starts_with_a_negative_value(tmp_path, capsys):
    """``--headings-deg -90,0`` is a list, not an option: argparse used to refuse it with
    "expected one argument"; a negative radius gets the option's own message."""
    from hybridship.cli import main

    argv = ["drift-off", "planning", "--samples", "3", "--radii-m", "5", "--no-plots", "--out"]
    assert main(argv + [str(tmp_path / "a"), "--headings-deg", "-90,0"]) == 0
    assert pd.read_csv(tmp_path / "a" / "times.csv").heading_deg.tolist() == [270, 0]
    assert main(["drift-off", "planning", "--samples", "3", "--no-plots", "--out", str(tmp_path / "b"),
                 "--radii-m", "-3,5"]) == 2
    assert "--radii-m: must be > 0" in capsys.readouterr().err


def test_live_summary_does_not_deny_the_wind_it_used(tmp_path):
    """The wind sensor silent for the last 70 s before the blackout: the estimate takes the
    mean wind of its own 120-s window and says so; the forecast start window's "no valid
    wind sample ... forecast without wind" (3 s) is not repeated in its summary."""
    from hybridship.cli import main
    from hybridship.logs.io import write_log
    from hybridship.physics.model import DynamicModel
    from hybridship.sim.synthetic import physics_log

    df = physics_log(DynamicModel("gunnerus"), seed=2, duration_s=600.0, t_shutdown_s=None)
    df.loc[df.time_s > 430, ["wind_speed_m_s", "wind_dir_deg"]] = np.nan
    write_log(df, tmp_path / "log.csv")
    argv = ["drift-off", "live", "--time-s", "500", "--samples", "3", "--radii-m", "5", "--no-plots",
            "--log", str(tmp_path / "log.csv"), "--out", str(tmp_path / "out")]
    assert main(argv) == 0
    summary = (tmp_path / "out" / "summary.md").read_text()
    assert "mean wind" in summary and "no valid wind sample" not in summary


def test_a_scheduler_address_where_another_service_answers_is_refused_by_name(tmp_path, capsys):
    """Something that is not a Dask scheduler answering at the address (here a web server's
    reply) made dask allocate exabytes and the CLI report "out of memory"; it is a failed
    connection to that scheduler."""
    pytest.importorskip("distributed")
    import socket
    import threading

    from hybridship.cli import main

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    srv.settimeout(20.0)

    def answer():
        try:
            while True:
                conn, _ = srv.accept()
                conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nok" * 4)
                conn.close()
        except OSError:             # the listening socket closed by the test
            pass
    threading.Thread(target=answer, daemon=True).start()
    address = f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    table = tmp_path / "w.csv"
    states_to_frame([WeatherState()]).to_csv(table, index=False)
    try:
        assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", address,
                     "--out", str(tmp_path / "s")]) != 0
    finally:
        srv.close()
    err = capsys.readouterr().err
    assert f"scheduler '{address}': could not connect" in err and "memory" not in err, err
    assert not (tmp_path / "s").exists()


def test_a_markdown_table_without_decimals_keeps_the_whole_numbers_zeros():
    """``digits=0`` gives 100 as "100" and 30 as "30" (the trailing zeros of a whole number
    were stripped as if they were decimals: "1" and "3"); decimals lose their trailing zeros."""
    from hybridship.driftoff.report import markdown_table

    df = pd.DataFrame({"radius_m": [100.0, 30.0], "t_p50_s": [120.4, np.inf]})
    assert markdown_table(df, digits=0).splitlines()[2:] == ["| 100 | 120 |", "| 30 | never |"]
    assert markdown_table(df, digits=2).splitlines()[2:] == ["| 100 | 120.4 |", "| 30 | never |"]


def test_a_share_of_a_few_samples_is_not_written_as_none_in_the_summary(tmp_path):
    """4 of 1000 samples over capacity (or over a radius) were written "0" in summary.md's
    table, under a warning that the same heading had "<1% of the samples" over capacity; a
    number that is not 0 but rounds to it reads "<0.01" (and a true 0 stays "0")."""
    from hybridship.driftoff.planning import DriftOffResult
    from hybridship.driftoff.report import markdown_table, write_report

    n = 1000
    t = np.full((1, n, 1), np.inf)
    t[0, :4, 0] = 5.0                           # 4 of 1000 reach 5 m within the 10-s reaction time
    r = DriftOffResult(np.zeros(1), np.zeros(1), np.array([5.0]), np.array([10.0]), t, np.zeros((1, n, 1)), 30.0,
                       over_capacity_frac=np.array([4.0 / n]))
    text = write_report(r, tmp_path / "o", plots=False)["summary.md"].read_text()
    assert "0 deg (<1% of the samples)" in text
    row = next(line for line in text.splitlines() if line.startswith("| 0 | 0 | 5 |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    head = next(line for line in text.splitlines() if line.startswith("| heading_deg | wind_rel_deg | radius_m"))
    col = dict(zip([c.strip() for c in head.strip("|").split("|")], cells))
    assert col["over_capacity_frac"] == "<0.01" and col["p_exceed_10s"] == "<0.01" and col["reached_frac"] == "<0.01"
    assert col["t_p10_s"] == "never" and col["p_exceed_10s_ci95_lo"] == "<0.01"
    df = pd.DataFrame({"a": [0.0, 0.004, -0.004, 0.04]})
    assert markdown_table(df, digits=1).splitlines()[2:] == ["| 0 |", "| <0.1 |", "| >-0.1 |", "| <0.1 |"]
    assert markdown_table(df, digits=2).splitlines()[2:] == ["| 0 |", "| <0.01 |", "| >-0.01 |", "| 0.04 |"]


def test_a_bar_in_an_input_or_a_table_stays_in_its_cell(tmp_path):
    """A log whose path holds a '|' (the live summary lists it as an input) split its row of
    summary.md's input table into three cells; a '|' in a name or value is written '\\|'."""
    from hybridship.driftoff.planning import DriftOffResult
    from hybridship.driftoff.report import markdown_table, write_report

    r = DriftOffResult(np.zeros(1), np.zeros(1), np.array([5.0]), np.array([10.0]), np.full((1, 2, 1), np.inf),
                       np.zeros((1, 2, 1)), 30.0)
    text = write_report(r, tmp_path / "o", inputs={"log": "runs|a.csv", "a|b": 1}, plots=False)["summary.md"].read_text()
    assert "| log | runs\\|a.csv |" in text.splitlines() and "| a\\|b | 1 |" in text.splitlines()
    table = markdown_table(pd.DataFrame({"log|name": ["x|y"], "t_s": [1.5]}))
    assert table.splitlines() == ["| log\\|name | t_s |", "|---|---|", "| x\\|y | 1.5 |"]


@pytest.mark.parametrize("n_times, error", [(0, ValueError), (1, ValueError), (True, ValueError), (2.5, ValueError),
                                            ("100", ValueError)])
def test_the_plots_refuse_what_they_cannot_draw_by_name(n_times, error):
    """exceedance_plot drew empty panels for n_times 0 (and a point for True) without a word,
    and failed in numpy's words on 2.5 or "100"; either plot failed on an attribute of a
    result that is not a DriftOffResult."""
    import matplotlib.pyplot as plt

    from hybridship.driftoff.planning import DriftOffResult
    from hybridship.driftoff.report import exceedance_plot, polar_plot

    r = DriftOffResult(np.zeros(1), np.zeros(1), np.array([5.0]), np.array([10.0]), np.full((1, 2, 1), 20.0),
                       np.zeros((1, 2, 1)), 30.0)
    plt.close(exceedance_plot(r, 2))
    with pytest.raises(error, match=r"^n_times: expected a whole number >= 2"):
        exceedance_plot(r, n_times)
    for plot in (exceedance_plot, polar_plot):
        with pytest.raises(TypeError, match=r"^result: expected a DriftOffResult, got str"):
            plot("times.csv")


def test_a_weather_tables_time_labels_are_kept_as_written(tmp_path):
    """The ``time`` column is text (docs/drift-off.md: "kept as text"): hours written 0000,
    0100 are those labels, not the numbers 0 and 100, and 1.10 and 1.1 are two labels (they
    were read as one number and refused as a repeated label)."""
    head = "time,wind_speed_m_s,wind_dir_deg,hs_m,tp_s,wave_dir_deg,current_m_s,current_dir_deg\n"
    row = ",5,0,1,6,0,0.1,0\n"
    path = tmp_path / "hours.csv"
    path.write_text(head + "".join(t + row for t in ("0000", "0100", "1.10", "1.1")))
    states, labels = read_weather_table(path)
    assert labels == ["0000", "0100", "1.10", "1.1"] and len(states) == 4
    path.write_text(head + "0000" + row + row)
    with pytest.raises(ValueError, match=r"column 'time', row 1 \(line 3 of the file\): empty"):
        read_weather_table(path)


def test_a_weather_tables_errors_name_the_line_the_bad_row_is_on(tmp_path):
    """Blank lines (before the header, between rows, holding only spaces) are skipped by the
    reader but are lines of the file: a bad row after them is named by its own line, not by
    its row number plus two (which pointed at the line before it). A row quoted over two
    lines starts on the first."""
    head = "time,wind_speed_m_s,wind_dir_deg,hs_m,tp_s,wave_dir_deg,current_m_s,current_dir_deg\n"
    path = tmp_path / "gaps.csv"
    path.write_text("\n" + head + "a,5,0,1,6,0,0.1,0\n\n  \n" + '"b\n",5,0,1,6,0,0.1,0\n' + "c,99,0,1,6,0,0.1,0\n")
    with pytest.raises(ValueError, match=r"column 'wind_speed_m_s', row 2 \(line 8 of the file\): 99"):
        read_weather_table(path)
    path.write_text(head + "\na,5,0,5,2,0,0.1,0\n")          # a sea steeper than waves can be
    with pytest.raises(ValueError, match=r"row 0 \(line 3 of the file\): hs_m 5 m at tp_s 2 s"):
        read_weather_table(path)
    path.write_text(head + "a,5,0,1,6,0,0.1,0\n\na,5,0,1,6,0,0.1,0\n")
    with pytest.raises(ValueError, match=r"column 'time', row 1 \(line 4 of the file\): 'a' again"):
        read_weather_table(path)
    import gzip

    with gzip.open(tmp_path / "gaps.csv.gz", "wt") as fh:       # a compressed table: the lines of its text
        fh.write(head + "a,5,0,1,6,0,0.1,0\n\n\nb,99,0,1,6,0,0.1,0\n")
    with pytest.raises(ValueError, match=r"row 1 \(line 5 of the file\): 99"):
        read_weather_table(tmp_path / "gaps.csv.gz")


def test_a_compressed_weather_tables_row_with_more_fields_is_named_by_its_line(tmp_path):
    """The line with more fields than the header was looked for in a .csv.gz's compressed bytes,
    so the message read 'a line has another number of fields than the header line (1)' (the
    header has 7); the compressed table's line is named as the plain one's."""
    import gzip

    text = ("wind_speed_m_s,wind_dir_deg,hs_m,tp_s,wave_dir_deg,current_m_s,current_dir_deg\n"
            "5,0,1,6,0,0.1,0,7\n5,0,1,6,0,0.1,0,9\n")
    (tmp_path / "w.csv").write_text(text)
    with gzip.open(tmp_path / "w.csv.gz", "wt") as fh:
        fh.write(text)
    for name in ("w.csv", "w.csv.gz"):
        with pytest.raises(ValueError, match=rf"^{re.escape(str(tmp_path / name))}: line 2 has 8 fields, the header line 7; "):
            read_weather_table(tmp_path / name)


def test_states_to_frame_refuses_what_is_not_a_list_of_states_by_name():
    """A list holding something else failed with "'int' object has no attribute
    'wind_speed_m_s'", one state alone with "'WeatherState' object is not iterable"; a set has
    no order for the rows. Each is refused naming ``states`` (or the item)."""
    w = WeatherState(wind_speed_m_s=8.0)
    assert len(states_to_frame((w, w))) == 2 and len(states_to_frame(iter([w]))) == 1
    with pytest.raises(TypeError, match=r"^states\[1\]: expected a WeatherState, got dict"):
        states_to_frame([w, {"wind_speed_m_s": 8.0}])
    for bad in (w, None, 3.0, "w", {w}, {"a": w}):
        with pytest.raises(TypeError, match=r"^states: expected a list of WeatherState"):
            states_to_frame(bad)


def test_labels_given_as_text_are_refused_not_split_into_characters():
    """``labels="ab"`` labelled two states "a" and "b", and one state's ``labels="2024-01-01"``
    was refused as 10 labels for 1 state; text (or a set, with no order) is refused naming
    ``labels``, in a sweep and in a weather table written from states."""
    w = WeatherState(wind_speed_m_s=8.0)
    st = DriftOffSettings(n_samples=2, horizon_s=30.0, reaction_times_s=(10.0,))
    for bad in ("ab", "2024-01-01", b"ab", {"a", "b"}, 7):
        with pytest.raises(TypeError, match=r"^labels: expected a list of labels, one per state"):
            season_sweep("gunnerus", [w, w], [0.0], settings=st, labels=bad, progress=False)
        with pytest.raises(TypeError, match=r"^labels: expected a list of labels, one per state"):
            states_to_frame([w, w], bad)
    assert states_to_frame([w, w], ("a", "b"))["time"].tolist() == ["a", "b"]
    assert season_sweep("gunnerus", w, [0.0], settings=st, labels=np.array(["x"]), progress=False).labels == ["x"]


def test_the_capacity_warning_never_rounds_a_share_to_none_or_all_of_the_samples(tmp_path):
    """One sample of 1000 over capacity was reported as "0% of the samples" (and 999 of 1000 as
    "100%"): a heading flagged with none of its samples; the share now reads <1% and >99%."""
    import dataclasses

    from hybridship.driftoff.planning import DriftOffResult
    from hybridship.driftoff.report import write_report

    n = 1000
    r = DriftOffResult(np.radians([0.0, 90.0, 180.0]), np.zeros(3), np.array([5.0]), np.array([10.0]),
                       np.full((3, n, 1), np.inf), np.zeros((3, n, 1)), 30.0,
                       over_capacity_frac=np.array([1.0 / n, 1.0 - 1.0 / n, 0.5]))
    text = write_report(r, tmp_path / "o", plots=False)["summary.md"].read_text()
    assert ("at heading(s) 0 deg (<1% of the samples), 90 deg (>99% of the samples), 180 deg (50% of the "
            "samples)") in text
    r = dataclasses.replace(r, over_capacity_frac=np.array([0.005, 0.995, 0.01]))    # 0.5 % rounds to 0 %
    text = write_report(r, tmp_path / "o", plots=False)["summary.md"].read_text()
    assert "0 deg (<1% of the samples), 90 deg (>99% of the samples), 180 deg (1% of the samples)" in text


def test_a_weather_table_that_is_no_path_is_refused_naming_the_argument():
    """``read_weather_table(None)`` said "no such file 'None'", and an empty path "'' is a
    folder" (the current one); each is refused as no path, naming ``path_or_frame``."""
    for bad, err in ((None, TypeError), (5, TypeError), (b"w.csv", TypeError), ("", ValueError)):
        with pytest.raises(err, match=r"^path_or_frame: expected a file path"):
            read_weather_table(bad)


def test_a_season_with_an_uncertainty_of_the_wrong_type_is_refused_before_any_state_runs(monkeypatch):
    """``season_sweep(uncertainty=...)`` was checked only by each state's simulate_blackouts:
    on a cluster, after the cluster had started, in every worker (logged there as a crash);
    in this process after the sweep had begun. It is refused before any state runs."""
    from hybridship.driftoff import season

    def no_simulation_yet(*args, **kwargs):
        raise RuntimeError("a state was simulated before the arguments were checked")
    monkeypatch.setattr(season, "simulate_blackouts", no_simulation_yet)
    for bad in ({"wind_speed_m_s": 1.0}, "typical", WeatherState()):
        with pytest.raises(TypeError, match=r"^uncertainty: expected a WeatherUncertainty or None, got"):
            season_sweep("gunnerus", [WeatherState()], [0.0], uncertainty=bad, progress=False)
