"""The drift-off command line: its options reach the computation unchanged (the report is the
API's on the same inputs), bad options are refused before any work with exit status 2 naming
the option, and failures while running end in one line with status 1, never a traceback or a
library's own words."""

from __future__ import annotations

import io
import math

import numpy as np
import pandas as pd
import pytest

from hybridship.cli import main
from hybridship.driftoff.planning import DriftOffSettings, simulate_blackouts
from hybridship.driftoff.weather import WeatherState, WeatherUncertainty, states_to_frame

RUN = ["drift-off", "planning", "--samples", "3", "--headings-deg", "0", "--horizon-s", "60", "--no-plots"]


def test_planning_report_is_the_apis_result_on_the_same_inputs(tmp_path, capsys):
    """Every weather, uncertainty and settings option reaches simulate_blackouts (degrees
    converted, the waves from the wind's direction when not given): times.csv is the API's
    table for the same state, spread, seed, step and settings; watch.csv holds the
    ``--quantile`` 0.5 circles, the 2nd smallest of the 4 samples' excursions (the smallest
    radius that at least half of them stay inside)."""
    out = tmp_path / "plan"
    assert main(["drift-off", "planning", "--samples", "4", "--headings-deg", "0,90", "--horizon-s", "60",
                 "--dt-s", "0.5", "--quantile", "0.5",
                 "--radii-m", "3,6", "--reaction-times-s", "20,40", "--wind-m-s", "11", "--wind-dir-deg", "70",
                 "--gust-intensity", "0.15", "--hs-m", "1.2", "--tp-s", "7", "--current-m-s", "0.3",
                 "--current-dir-deg", "200", "--wind-std-m-s", "1.5", "--wind-dir-std-deg", "10", "--hs-std-m", "0.3",
                 "--tp-std-s", "0.8", "--wave-dir-std-deg", "5", "--current-std-m-s", "0.05",
                 "--current-dir-std-deg", "20", "--vessel-spread", "0.5", "--seed", "9", "--no-plots",
                 "--out", str(out)]) == 0
    capsys.readouterr()
    w = WeatherState(11.0, math.radians(70.0), 1.2, 7.0, math.radians(70.0), 0.3, math.radians(200.0), 0.15)
    u = WeatherUncertainty(1.5, math.radians(10.0), 0.3, 0.8, math.radians(5.0), 0.05, math.radians(20.0))
    st = DriftOffSettings(radii_m=(3.0, 6.0), reaction_times_s=(20.0, 40.0), n_samples=4, horizon_s=60.0,
                          dt_s=0.5, vessel_spread=0.5, seed=9)
    res = simulate_blackouts("gunnerus", w, np.radians([0.0, 90.0]), uncertainty=u, settings=st)
    times, _ = res.summary_frames()
    # the report writes 6 significant digits
    want = pd.read_csv(io.StringIO(times.to_csv(index=False, float_format="%.6g")))
    pd.testing.assert_frame_equal(pd.read_csv(out / "times.csv"), want, check_exact=True)
    watch = pd.read_csv(out / "watch.csv")
    assert watch["quantile"].tolist() == [0.5] * 4
    second = np.sort(res.excursion_m, axis=1)[:, 1, :]          # (heading, reaction time)
    assert np.ptp(np.sort(res.excursion_m, axis=1)[:, 1:, :], axis=1).min() > 1e-3     # the 4 differ
    np.testing.assert_allclose(watch["watch_radius_m"].to_numpy(), second.ravel(), rtol=1e-5)


@pytest.mark.parametrize("mode, opts, message", [
    ("planning", ["--quantile", "1.5"], "--quantile must be in (0, 1), got 1.5"),
    ("planning", ["--vessel", "no_such_vessel.toml"], "--vessel: no_such_vessel.toml: vessel file not found"),
    ("planning", ["--hs-m", "3", "--tp-s", "3"],
     "--hs-m 3 m at --tp-s 3 s is steeper than waves can be (at most 2.01 m at that period: 2 pi Hs / (g Tp^2) <= "
     "0.143); are --hs-m and --tp-s swapped, or --tp-s in another unit?"),
    ("season", ["--chunk-size", "0"], "--chunk-size must be >= 1, got 0"),
    ("season", ["--max-p-exceed", "1.5"], "--max-p-exceed must be in [0, 1], got 1.5"),
])
def test_a_bad_option_is_refused_by_name_before_any_work(tmp_path, monkeypatch, capsys, mode, opts, message):
    """Exit status 2, one line naming the option as typed, and no --out made: not a library's
    message about its argument (``quantile:``, ``chunk_size:``) after the sweep has run."""
    from hybridship.driftoff import planning, season

    def no_work(*args, **kwargs):          # the run is tiny: only this tells "before" from "after"
        raise AssertionError("the drifts were simulated before the option was checked")

    monkeypatch.setattr(planning, "simulate_blackouts", no_work)
    monkeypatch.setattr(season, "season_sweep", no_work)
    argv = ["drift-off", mode, "--samples", "2", "--horizon-s", "30", "--reaction-times-s", "10"]
    if mode == "season":
        table = tmp_path / "w.csv"
        states_to_frame([WeatherState(wind_speed_m_s=5.0)]).to_csv(table, index=False)
        argv += ["--weather-table", str(table), "--scheduler", "none", "--no-progress"]
    assert main(argv + opts + ["--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err == f"hybridship drift-off {mode}: error: {message}\n", err
    assert not (tmp_path / "o").exists()


def test_the_scheduler_none_is_taken_in_any_case(tmp_path, capsys):
    """``--scheduler None`` runs in this process, as ``none`` does."""
    table = tmp_path / "w.csv"
    states_to_frame([WeatherState(wind_speed_m_s=5.0)]).to_csv(table, index=False)
    assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", "None", "--samples", "2",
                 "--headings-deg", "0", "--horizon-s", "30", "--reaction-times-s", "10", "--no-progress",
                 "--out", str(tmp_path / "s")]) == 0
    assert "scheduler None" in capsys.readouterr().out and (tmp_path / "s" / "season.csv").is_file()


def test_season_operability_is_at_the_max_p_exceed_given(tmp_path, capsys):
    """``--max-p-exceed 1``: every state is operable (a probability is at most 1), the windy
    one too, whose P(exceed) is 1 (the default 0.1 would count only the calm one)."""
    table = tmp_path / "w.csv"
    states_to_frame([WeatherState(), WeatherState.from_degrees(wind_speed_m_s=15.0, wind_dir_deg=90.0)]).to_csv(
        table, index=False)
    assert main(["drift-off", "season", "--weather-table", str(table), "--scheduler", "none", "--samples", "2",
                 "--headings-deg", "0", "--horizon-s", "30", "--radii-m", "1", "--reaction-times-s", "30",
                 "--max-p-exceed", "1", "--no-progress", "--out", str(tmp_path / "s")]) == 0
    capsys.readouterr()
    assert pd.read_csv(tmp_path / "s" / "season.csv")["p_exceed_30s"].tolist() == [0.0, 1.0]
    assert pd.read_csv(tmp_path / "s" / "operability.csv")["operable_frac"].tolist() == [1.0]


def test_a_failure_while_running_is_one_line_in_the_commands_words(monkeypatch, tmp_path, capsys):
    """Drifts that diverge (FloatingPointError) end with status 1 and the message; numpy's own
    "Unable to allocate ..." is replaced by what to ask for instead. No traceback either way,
    and nothing written."""
    from hybridship.driftoff import planning

    def diverged(*args, **kwargs):
        raise FloatingPointError("2 of 8 drifts diverged (weather: the state of index 0 or its spread)")
    monkeypatch.setattr(planning, "simulate_blackouts", diverged)
    assert main(RUN + ["--out", str(tmp_path / "a")]) == 1
    err = capsys.readouterr().err
    assert err == "hybridship drift-off planning: error: 2 of 8 drifts diverged (weather: the state of index 0 or " \
                  "its spread)\n", err

    def no_memory(*args, **kwargs):
        raise MemoryError("Unable to allocate 80.0 GiB for an array with shape (100000, 300, 3) and data type float64")
    monkeypatch.setattr(planning, "simulate_blackouts", no_memory)
    assert main(RUN + ["--out", str(tmp_path / "b")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("hybridship drift-off planning: error: out of memory: ") and err.count("\n") == 1, err
    assert "Unable to allocate" not in err and "fewer samples" in err
    assert not (tmp_path / "a" / "times.csv").exists() and not (tmp_path / "b" / "times.csv").exists()

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(planning, "simulate_blackouts", interrupted)       # Ctrl-C: 128 + SIGINT, as a shell
    assert main(RUN + ["--out", str(tmp_path / "c")]) == 130
    assert capsys.readouterr().err == "hybridship: interrupted\n"


def test_live_blackout_is_at_the_row_of_the_time_given(tmp_path, capsys):
    """``--time-s 500`` on a 1-Hz log: the blackout is at 500 s, that row included, not at
    the row before."""
    from hybridship.logs.io import write_log
    from hybridship.physics.model import DynamicModel
    from hybridship.sim.synthetic import physics_log

    write_log(physics_log(DynamicModel("gunnerus"), seed=2, duration_s=600.0, t_shutdown_s=None), tmp_path / "log.csv")
    assert main(["drift-off", "live", "--time-s", "500", "--samples", "3", "--radii-m", "5", "--no-plots",
                 "--log", str(tmp_path / "log.csv"), "--out", str(tmp_path / "out")]) == 0
    capsys.readouterr()
    assert "| blackout at [s] | 500 |" in (tmp_path / "out" / "summary.md").read_text()


@pytest.mark.parametrize("argv", [
    ["drift-off", "planning", "--out", "o"], ["drift-off", "season", "--out", "o", "--weather-table", "w.csv"],
    ["simulate", "--seed", "1", "--out", "o.csv"], ["train", "--logs", ".", "--out", "m.npz"],
    ["benchmark", "drift"], ["benchmark", "manoeuvre", "--train", "a", "--test", "b"]])
def test_an_empty_vessel_is_refused_as_bad_input(tmp_path, monkeypatch, capsys, argv):
    """``--vessel ''`` is the user's input: exit status 2 naming the option, not the library's
    "vessel: expected ..." with the status of a failure while running (1)."""
    monkeypatch.chdir(tmp_path)
    assert main(argv + ["--vessel", ""]) == 2
    err = capsys.readouterr().err
    assert err.endswith("error: argument --vessel: expected a packaged vessel name or a vessel file, got ''\n"), err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv, option", [
    (["drift-off", "live", "--out", "o", "--log="], "--log"),
    (["drift-off", "season", "--out", "o", "--weather-table="], "--weather-table")])
def test_an_empty_input_path_is_refused_not_read_as_the_current_folder(tmp_path, monkeypatch, capsys, argv, option):
    """An empty path is the current folder to pathlib: refused as bad input (exit 2) naming the option."""
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"error: argument {option}: expected a path, got ''" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_live_and_forecast_end_alike_on_a_log_without_a_required_column(tmp_path, capsys):
    """Review: a log without ``heading_deg`` ended ``drift-off live`` with status 2 (a bad
    option) and ``forecast`` with 1 (bad data); live now ends with 1 too, naming the column."""
    from hybridship.physics.model import DynamicModel
    from hybridship.sim.synthetic import physics_log

    log = tmp_path / "log.csv"
    physics_log(DynamicModel("gunnerus"), seed=2, duration_s=200.0, t_shutdown_s=None).drop(
        columns=["heading_deg"]).to_csv(log, index=False)
    assert main(["drift-off", "live", "--log", str(log), "--out", str(tmp_path / "out"), "--no-plots"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("hybridship drift-off live: error: heading_deg: required column missing")
    assert "Traceback" not in err


def test_a_season_summary_warns_of_states_beyond_the_thrusters_capacity(tmp_path, capsys):
    """docs/drift-off.md: over capacity is flagged in planning and season, with a warning in
    summary.md. A season's summary had none: a storm beyond the thrusters counted as operable
    or not with no word that the DP could not have held station there. One storm of two states
    is named; a calm season has no warning."""
    table = tmp_path / "w.csv"
    storm = WeatherState.from_degrees(wind_speed_m_s=30.0, wind_dir_deg=90.0, hs_m=3.0, tp_s=9.0, current_m_s=0.5,
                                      current_dir_deg=90.0)
    run = ["drift-off", "season", "--weather-table", str(table), "--scheduler", "none", "--samples", "2",
           "--headings-deg", "0,90", "--horizon-s", "30", "--reaction-times-s", "10", "--no-progress"]
    states_to_frame([WeatherState(wind_speed_m_s=5.0), storm]).to_csv(table, index=False)
    assert main(run + ["--out", str(tmp_path / "s")]) == 0
    capsys.readouterr()
    text = (tmp_path / "s" / "summary.md").read_text()
    assert "**DP capacity exceeded before the blackout** in 1 of 2 weather states at one heading or more" in text
    states_to_frame([WeatherState(wind_speed_m_s=5.0)]).to_csv(table, index=False)
    assert main(run + ["--out", str(tmp_path / "c")]) == 0
    assert "DP capacity" not in (tmp_path / "c" / "summary.md").read_text()
