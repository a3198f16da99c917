"""Drift-off: a scalar quantile keeps the (heading, radius) axes; a live estimate's bad wind
fields, and fields that are not numbers, are refused under their own names, and its members
may be any array-like."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hybridship.driftoff import spread
from hybridship.driftoff.live import EnvironmentEstimate, blackout_now
from hybridship.driftoff.planning import DriftOffSettings, simulate_blackouts
from hybridship.driftoff.weather import WeatherState, WeatherUncertainty, sample_environment

Z3 = np.zeros(3)
ESTIMATE = EnvironmentEstimate(time_s=0.0, eta=Z3, nu=Z3, rpm=Z3, azimuth_rad=Z3, wind_speed_m_s=10.0,
                               wind_dir_from_rad=0.0, gust_intensity=0.1, accel_ned=Z3,
                               accel_members=np.zeros((1, 3)))
SMALL = DriftOffSettings(n_samples=3, horizon_s=30.0, radii_m=(1.0, 2.0), reaction_times_s=(10.0,))


def test_a_single_quantile_is_given_per_heading_and_radius():
    """``time_quantiles(0.5)`` is the median per (heading, radius), shape (H, R): the same
    numbers as ``time_quantiles((0.5,))[..., 0]``, not their transpose (R, H)."""
    w = WeatherState.from_degrees(wind_speed_m_s=14.0, wind_dir_deg=80.0, hs_m=1.0, tp_s=6.0)
    r = simulate_blackouts("gunnerus", w, np.radians([0.0, 45.0, 90.0]), settings=SMALL)
    assert r.t_reach_s.shape == (3, 3, 2)
    np.testing.assert_array_equal(r.time_quantiles(0.5), r.time_quantiles((0.5,))[..., 0])
    with pytest.raises(ValueError, match="q: expected"):
        r.time_quantiles([[0.1, 0.5]])


@pytest.mark.parametrize("change, field", [
    (dict(wind_speed_m_s=80.0), "estimate.wind_speed_m_s"),
    (dict(wind_speed_m_s=-1.0), "estimate.wind_speed_m_s"),
    (dict(gust_intensity=0.9), "estimate.gust_intensity"),
    (dict(wind_dir_from_rad=200.0), "estimate.wind_dir_from_rad"),
])
def test_live_bad_wind_of_an_estimate_names_the_estimates_field(change, field):
    """Not ``weather.wind_speed_m_s ... [WeatherState]``, a class the caller never built."""
    with pytest.raises(ValueError, match=rf"^{field}: ") as info:
        blackout_now(dataclasses.replace(ESTIMATE, **change), "gunnerus", SMALL)
    assert "WeatherState" not in str(info.value)


def test_live_members_given_as_lists_are_taken_as_arrays():
    """_check_estimate accepts any array-like; the blackouts then read it as an array too
    (it raised AttributeError: 'list' object has no attribute 'shape')."""
    members, nu = [[2e-3, -1e-3, 1e-5]], [0.1, 0.05, 0.002]          # not zeros: read, not replaced
    as_list = blackout_now(dataclasses.replace(ESTIMATE, accel_members=members, nu=nu), "gunnerus", SMALL)
    as_array = blackout_now(dataclasses.replace(ESTIMATE, accel_members=np.array(members), nu=np.array(nu)),
                            "gunnerus", SMALL)
    np.testing.assert_array_equal(as_list.t_reach_s, as_array.t_reach_s)
    np.testing.assert_array_equal(as_list.excursion_m, as_array.excursion_m)
    for change in (dict(accel_members=np.zeros((1, 3))), dict(nu=Z3)):   # each of them moves the ship
        zero = blackout_now(dataclasses.replace(ESTIMATE, **{"accel_members": np.array(members),
                                                             "nu": np.array(nu), **change}), "gunnerus", SMALL)
        assert not np.allclose(zero.excursion_m, as_list.excursion_m)


def test_a_local_cluster_is_closed_when_its_client_cannot_start(monkeypatch):
    """``scheduler="local"``: if the Client on the new LocalCluster fails, the cluster (its
    worker processes) is closed before the error goes on."""
    from types import SimpleNamespace

    import hybridship.driftoff.season as season

    closed = []

    class Cluster:
        def __init__(self, **kw):
            pass

        def close(self):
            closed.append(True)

    def client(cluster):
        raise OSError("no client")

    monkeypatch.setattr(season, "require_dask", lambda: SimpleNamespace(LocalCluster=Cluster, Client=client))
    with pytest.raises(OSError, match="no client"):
        season._client("local", 2)
    assert closed == [True]


def test_live_current_members_of_the_wrong_shape_are_refused_by_name():
    """Current members are ``[north, east]`` pairs, (M, 2): two members of three columns were
    read as three pairs of other numbers (``reshape(-1, 2)``) and drifted in a current nobody
    gave; one pair (2,) is still one member."""
    for bad in (np.array([[0.3, 0.1, 0.0], [0.2, 0.0, 0.0]]), np.zeros((2, 2, 2)), np.zeros(4)):
        with pytest.raises(ValueError, match=r"^estimate\.current_members_ned_m_s: expected .*\(M, 2\).* got "
                                             r"shape"):
            blackout_now(dataclasses.replace(ESTIMATE, current_members_ned_m_s=bad), "gunnerus", SMALL)
    one = blackout_now(dataclasses.replace(ESTIMATE, current_members_ned_m_s=np.array([0.0, 0.5])), "gunnerus", SMALL)
    same = blackout_now(dataclasses.replace(ESTIMATE, current_members_ned_m_s=np.array([[0.0, 0.5]])), "gunnerus",
                        SMALL)
    np.testing.assert_array_equal(one.excursion_m, same.excursion_m)


@pytest.mark.parametrize("change, field", [
    (dict(wind_speed_m_s="ten"), "wind_speed_m_s"), (dict(wind_speed_m_s="10"), "wind_speed_m_s"),
    (dict(wind_speed_m_s=None), "wind_speed_m_s"), (dict(gust_intensity=True), "gust_intensity"),
    (dict(wind_dir_from_rad=[0.0, 1.0]), "wind_dir_from_rad"), (dict(eta=["a", 0.0, 0.0]), "eta"),
    (dict(nu=None), "nu"), (dict(rpm=["100", "0", "0"]), "rpm"),
    (dict(accel_members=[["x", 0.0, 0.0]]), "accel_members"),
    (dict(current_members_ned_m_s=[["a", 1.0]]), "current_members_ned_m_s"),
])
def test_live_fields_that_are_not_numbers_are_refused_by_name(change, field):
    """Text, bools and None in an estimate are refused naming the field, not in numpy's or
    float()'s words ("could not convert string to float: 'a'"), nor read as numbers ("10", True)."""
    with pytest.raises(TypeError, match=rf"^estimate\.{field}: expected (a number|an array of numbers), got "):
        blackout_now(dataclasses.replace(ESTIMATE, **change), "gunnerus", SMALL)
    with pytest.raises(ValueError, match=r"^estimate\.wind_speed_m_s: must be finite"):
        blackout_now(dataclasses.replace(ESTIMATE, wind_speed_m_s=float("nan")), "gunnerus", SMALL)


@pytest.mark.parametrize("change, error, field", [
    (dict(duration_s=float("nan")), ValueError, "duration_s"), (dict(duration_s=0.0), ValueError, "duration_s"),
    (dict(dt_s=-1.0), ValueError, "dt_s"), (dict(dt_s=0.0), ValueError, "dt_s"), (dict(dt_s="1"), TypeError, "dt_s"),
    (dict(n=-1), ValueError, "n"), (dict(n=2.5), ValueError, "n"), (dict(n_gust=-2), ValueError, "n_gust"),
    (dict(n_wave=3.0), ValueError, "n_wave"), (dict(rng=5), TypeError, "rng"), (dict(state=None), TypeError, "state"),
    (dict(uncertainty=dict(hs_m=1.0)), TypeError, "uncertainty")])
def test_sampling_arguments_it_cannot_use_are_refused_by_name(change, error, field):
    """sample_environment gave NaN gusts for a NaN duration and gusts on a band from a negative
    step without a word, and failed in Python's or numpy's words on a zero step ('float division
    by zero'), a negative or fractional count or a seed given as the generator."""
    args = dict(state=WeatherState(wind_speed_m_s=5.0), uncertainty=WeatherUncertainty(), n=3,
                rng=np.random.default_rng(0), duration_s=30.0, dt_s=1.0, n_gust=4, n_wave=2)
    ok = sample_environment(**args)
    assert ok.gust_f_hz.shape == (3, 4) and np.all(np.isfinite(ok.gust_amp_m_s))
    args.update(change)
    with pytest.raises(error, match=rf"^{field}: "):
        sample_environment(**args)


@pytest.mark.parametrize("change, error, field", [
    (dict(spread=True), TypeError, "vessel_spread"), (dict(spread="1"), TypeError, "vessel_spread"),
    (dict(spread=None), TypeError, "vessel_spread"), (dict(spread=float("nan")), ValueError, "vessel_spread"),
    (dict(spread=-0.5), ValueError, "vessel_spread"), (dict(n=-1), ValueError, "n"), (dict(n=2.5), ValueError, "n"),
    (dict(rng=3), TypeError, "rng")])
def test_vessel_draws_it_cannot_make_are_refused_by_name(change, error, field):
    """draw_scales read a spread of True as 1 and drew vessels with it; a text or None spread
    failed in numpy's words ("ufunc 'isfinite' not supported"), and so did a negative or
    fractional count or a seed given as the generator."""
    from hybridship.driftoff.planning import get_model

    args = dict(vessel=get_model("gunnerus").vessel, n=3, rng=np.random.default_rng(0), spread=1.0)
    assert spread.draw_scales(**args).thrust.shape == (3,)
    args.update(change)
    with pytest.raises(error, match=rf"^{field}: "):
        spread.draw_scales(**args)
