"""Valid input ranges of the physics (hybridship.forecast_inputs.limits): clip or refuse, never propagate."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hybridship.forecast_inputs import KNOT_M_S, Envelope, InputRangeError, check_or_clip_inputs, envelope_for
from hybridship.physics.model import DynamicModel

MODEL = DynamicModel("gunnerus")
MAX_RPM = np.array([t.max_rpm for t in MODEL.vessel.thrusters])


def test_envelope_of_the_vessel():
    env = envelope_for(MODEL)
    assert env.max_rpm == tuple(MAX_RPM) and env.channel_names == ("tunnel", "port", "stbd")
    assert env.wind_speed_max_m_s == pytest.approx(100 * KNOT_M_S) and env.current_speed_max_m_s == 5.0
    assert envelope_for("gunnerus", surge_max_m_s=6.0).surge_max_m_s == 6.0


def test_envelope_for_overrides_the_vessels_channel_limits_too():
    # the docstring: "**overrides: Fields of Envelope to change"; before, max_rpm, channel_names or
    # max_angle_rad were a TypeError ("got multiple values for keyword argument 'max_rpm'")
    env = envelope_for(MODEL, max_rpm=(300.0, 200.0, 200.0), surge_max_m_s=6.0)
    assert env.max_rpm == (300.0, 200.0, 200.0) and env.surge_max_m_s == 6.0
    assert env.channel_names == ("tunnel", "port", "stbd")
    assert envelope_for(MODEL, channel_names=("a", "b", "c")).max_rpm == tuple(MAX_RPM)


def test_extremes_are_clipped_and_flagged_per_batch_element():
    nu = np.array([[9.0, 0.0, 0.0], [1.0, 1.0, 0.1]])
    rpm = np.array([[300.0, 100.0, -250.0], [0.0, 0.0, 0.0]])
    wind = np.array([[100.0 * KNOT_M_S * 1.2, 7.0], [5.0, 1.0]])          # 120 kn
    current = np.array([[1.0, 0.0], [6.0, -7.0]])
    before = [a.copy() for a in (nu, rpm, wind, current)]
    c = check_or_clip_inputs(MODEL, nu=nu, rpm=rpm, wind=wind, current=current, azimuth_rad=[4.0, 0.0, -4.0])
    for a, b in zip((nu, rpm, wind, current), before):
        np.testing.assert_array_equal(a, b)                                  # caller's arrays untouched
    np.testing.assert_allclose(c.nu[0], [8.0, 0.0, 0.0])
    np.testing.assert_allclose(c.rpm[0], [300.0, 100.0, -217.0])
    np.testing.assert_allclose(c.wind[:, 0], [100.0 * KNOT_M_S, 5.0])
    np.testing.assert_allclose(c.current[:, 0], [1.0, 5.0])
    # directions wrapped to [-pi, pi) by whole turns, so the same direction (7 rad is 7 - 2 pi,
    # -7 rad is -7 + 2 pi): a range check alone passed a wrap that turned them half a turn
    np.testing.assert_allclose(c.wind[:, 1], [7.0 - 2 * np.pi, 1.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.current[:, 1], [0.0, -7.0 + 2 * np.pi], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(c.clipped_fields["wind"], [True, False])
    np.testing.assert_allclose(np.cos(c.azimuth_rad), np.cos([4.0, 0.0, -4.0]))   # same direction
    np.testing.assert_array_equal(c.clipped, [True, True])
    np.testing.assert_array_equal(c.clipped_fields["nu"], [True, False])
    np.testing.assert_array_equal(c.clipped_fields["rpm"], [True, False])
    np.testing.assert_array_equal(c.clipped_fields["current"], [False, True])
    assert "wind clipped" in c.notes[0] and "current clipped" in c.notes[1]
    assert c.eta is None and c.substeps == 1


def test_inputs_within_range_pass_unchanged():
    rpm = np.array([[200.0, -100.0, 217.0]])
    c = check_or_clip_inputs(MODEL, eta=[1e3, -2e3, 40.0], nu=[5.0, -3.0, 0.2], rpm=rpm, wind=[30.0, 2.0],
                             current=[1.0, 0.5], dt_s=1.0)
    assert not c.clipped.any()
    np.testing.assert_array_equal(c.rpm, rpm)
    np.testing.assert_array_equal(c.nu, [5.0, -3.0, 0.2])
    # every input comes back as given: the heading too, unwrapped (40 rad, six turns on: the
    # rollout continues from it), and the wind and current already in [-pi, pi)
    np.testing.assert_array_equal(c.eta, [1e3, -2e3, 40.0])
    np.testing.assert_array_equal(c.wind, [30.0, 2.0])
    np.testing.assert_array_equal(c.current, [1.0, 0.5])
    assert c.substeps == 1 and c.notes == ("",)


@pytest.mark.parametrize("kwargs, pattern", [
    (dict(nu=[np.nan, 0, 0]), r"nu\[u_m_s\]: nan is not finite \(a fault, not an extreme\)"),
    (dict(wind=[[5.0, 0.0], [np.inf, 0.0]]), r"wind\[batch 1, speed_m_s\]: inf is not finite"),
    (dict(rpm=[0.0, 500.0, 0.0]), r"rpm\[thruster 'port'\]: 500 is more than 2 x max_rpm \(a unit error\?\)"),
    (dict(rpm=[0.0, -500.0, 0.0]), r"rpm\[thruster 'port'\]: -500 is more than 2 x max_rpm"),
    (dict(wind=[-1.0, 0.0]), r"wind\[speed_m_s\]: -1 is negative"),
    (dict(current=[-0.5, 0.0]), r"current\[speed_m_s\]: -0.5 is negative"),
    (dict(eta=[[0, 0, 0], [2e7, 0, 0]]), r"eta\[batch 1, north_m\]: 2e\+07 is outside .*\|north_m\|, \|east_m\| <= 1e\+07 m"),
    (dict(eta=[0, -2e7, 0]), r"eta\[east_m\]: -2e\+07 is outside .*\|east_m\| <= 1e\+07 m"),
    (dict(eta=[0, 0, 1e5]), r"eta\[psi_rad\]: 100000 is outside"),
])
def test_always_refused(kwargs, pattern):
    for mode in ("clip", "refuse"):
        with pytest.raises(InputRangeError, match=pattern):
            check_or_clip_inputs(MODEL, mode=mode, **kwargs)


def test_inputs_of_text_or_complex_numbers_are_refused_by_name():
    # before: nu=["9", "0", "0"] was read as 9 m/s (and clipped), complex numbers and other text failed
    # in numpy's words ("float() argument must be ...", "could not convert string to float")
    for kwargs, name in ((dict(nu=["9", "0", "0"]), "nu"), (dict(wind=[1 + 2j, 0.0]), "wind"),
                         (dict(rpm=["a", "b", "c"]), "rpm")):
        with pytest.raises(TypeError, match=rf"{name}: expected an array of real numbers"):
            check_or_clip_inputs(MODEL, **kwargs)


@pytest.mark.parametrize("kwargs, field_, pattern", [
    (dict(nu=np.zeros((2, 5, 3)) + [0, 5, 0]), "nu", r"nu\[batch 0, step 0, v_m_s\]: 5 is outside .*\|v_m_s\| <= 4 m/s"),
    (dict(rpm=[0.0, 0.0, 250.0]), "rpm", r"rpm\[thruster 'stbd'\]: 250 .*max_rpm"),
    (dict(wind=[60.0, 0.0]), "wind", r"wind\[speed_m_s\]: 60 is outside .*51\.4"),
    (dict(current=[5.5, 0.0]), "current", r"current\[speed_m_s\]: 5.5 is outside"),
    (dict(dt_s=2.0), "dt_s", r"RK4 step 2 s exceeds 1 s; use substeps >= 2"),
])
def test_refuse_mode_refuses_what_clip_mode_clips(kwargs, field_, pattern):
    with pytest.raises(InputRangeError, match=pattern) as info:
        check_or_clip_inputs(MODEL, mode="refuse", **kwargs)
    assert info.value.field == field_
    c = check_or_clip_inputs(MODEL, mode="clip", **kwargs)
    # clip mode clips it to the table's bound (a longer step gets substeps instead, unflagged)
    if field_ == "dt_s":
        assert c.substeps == 2 and not c.clipped.any()
    else:
        assert c.clipped.all() and c.clipped_fields[field_].all()
        got, bound = {"nu": lambda: (c.nu[..., 1], 4.0), "rpm": lambda: (c.rpm[2], 217.0),
                      "wind": lambda: (c.wind[0], 100.0 * KNOT_M_S), "current": lambda: (c.current[0], 5.0)}[field_]()
        np.testing.assert_allclose(got, bound, rtol=0, atol=1e-12)


def test_a_value_out_of_range_at_a_later_step_flags_its_own_batch_element():
    """Inputs of shape (B, S, width): a value out of range at step 3 of element 1 only is
    clipped there and flags element 1 alone."""
    nu = np.zeros((2, 5, 3))
    nu[1, 3, 1] = -5.0
    c = check_or_clip_inputs(MODEL, nu=nu)
    np.testing.assert_array_equal(c.clipped_fields["nu"], [False, True])
    assert c.nu[1, 3, 1] == -4.0 and np.count_nonzero(c.nu) == 1 and c.notes == ("", "nu clipped to its valid range")


def test_large_steps_get_substeps():
    """The RK4 step is at most ``rk4_step_max_s`` (1 s): a step just beyond it gets a substep
    (steps of 2 s and more alone could not tell a bound of 1 s from one of 1.9 s)."""
    assert check_or_clip_inputs(MODEL, dt_s=1.0).substeps == 1
    assert check_or_clip_inputs(MODEL, dt_s=1.2).substeps == 2
    assert check_or_clip_inputs(MODEL, dt_s=2.4, substeps=2).substeps == 3
    with pytest.raises(InputRangeError, match=r"RK4 step 1\.2 s exceeds 1 s; use substeps >= 2"):
        check_or_clip_inputs(MODEL, dt_s=1.2, mode="refuse")
    assert check_or_clip_inputs(MODEL, dt_s=2.5).substeps == 3
    assert check_or_clip_inputs(MODEL, dt_s=2.0, substeps=4).substeps == 4
    with pytest.raises(InputRangeError, match="dt_s"):
        check_or_clip_inputs(MODEL, dt_s=-1.0)
    # before: 1.5 substeps ran as 1 and 2.9 as 2, unseen; None and "1" failed inside int() / isfinite()
    for bad in (1.5, 2.9, None, "2", True):
        with pytest.raises(ValueError, match=r"substeps: expected a whole number >= 1, got "):
            check_or_clip_inputs(MODEL, dt_s=0.5, substeps=bad)
    # before: a list, a complex number or an array of two steps failed in math.isfinite's words
    # ("must be real number, not list"), not naming dt_s
    for bad in ("1", b"1", True, [1.0], 1 + 2j, np.array([2.0, 3.0])):
        with pytest.raises(TypeError, match=r"dt_s: expected a number of seconds, got "):
            check_or_clip_inputs(MODEL, dt_s=bad)
    assert check_or_clip_inputs(MODEL, dt_s=np.float64(2.0), substeps=np.int64(4)).substeps == 4


def test_arguments():
    with pytest.raises(ValueError, match="mode"):
        check_or_clip_inputs(MODEL, mode="ignore")
    with pytest.raises(ValueError, match="rpm needs the vessel"):
        check_or_clip_inputs(rpm=[0.0])
    with pytest.raises(ValueError, match="width 2 does not match"):
        check_or_clip_inputs(MODEL, rpm=[0.0, 0.0])
    check_or_clip_inputs(envelope=Envelope(), nu=[1.0, 0.0, 0.0])


@pytest.mark.parametrize("override, error, pattern", [
    (dict(surge_max_m_s=-8.0), ValueError, r"surge_max_m_s: must be > 0, got -8.0"),
    (dict(yaw_rate_max_rad_s=float("nan")), ValueError, r"yaw_rate_max_rad_s: must be finite"),
    (dict(sway_max_m_s=-np.inf), ValueError, r"sway_max_m_s: must be finite"),
    (dict(rk4_step_max_s=0.0), ValueError, r"rk4_step_max_s: must be > 0"),
    (dict(rpm_refuse_factor=0.5), ValueError, r"rpm_refuse_factor: must be >= 1"),
    (dict(wind_speed_max_m_s="50"), TypeError, r"wind_speed_max_m_s: expected a number, got '50'"),
])
def test_an_envelope_bound_that_is_no_bound_is_refused_by_name(override, error, pattern):
    # before: a surge bound of -8 turned u = 1 m/s into -8 m/s, a NaN bound clipped nothing, a step of 0
    # was a ZeroDivisionError, a factor of 0.5 refused as unit errors the rpm clip mode clips
    with pytest.raises(error, match=pattern):
        envelope_for(MODEL, **override)
    assert envelope_for(MODEL, wind_speed_max_m_s=np.inf).wind_speed_max_m_s == np.inf


@pytest.mark.parametrize("override, error, pattern", [
    (dict(max_rpm=(np.nan,)), ValueError, r"max_rpm\[0\]: must be finite"),
    (dict(max_rpm=(300.0, -100.0)), ValueError, r"max_rpm\[1\]: must be > 0, got -100.0"),
    (dict(max_rpm=("300",)), TypeError, r"max_rpm\[0\]: expected a number"),
    (dict(max_angle_rad=(np.inf, -0.5)), ValueError, r"max_angle_rad\[1\]: must be > 0, got -0.5"),
])
def test_a_channel_limit_that_is_no_limit_is_refused_by_name(override, error, pattern):
    # before: a NaN max_rpm let 500 rpm through unclipped and unflagged, a negative one refused 50 rpm as
    # "more than 2 x max_rpm (a unit error?)", a rudder stop of -0.5 rad turned an angle of 0.1 rad into -0.5
    with pytest.raises(error, match=pattern):
        Envelope(**override)
    env = Envelope(max_rpm=(300.0, np.inf), max_angle_rad=(np.inf, 0.5))     # inf: no limit on that channel
    assert env.max_rpm == (300.0, np.inf)


def test_inputs_of_different_batch_sizes_are_refused_by_name():
    # before: accepted while nothing was clipped, and a bare numpy broadcast error once something was
    for wind in (np.zeros((2, 2)), np.zeros((2, 2)) + [60.0, 0.0]):
        with pytest.raises(ValueError, match=r"wind: batch size 2 does not match nu's 3"):
            check_or_clip_inputs(MODEL, nu=np.zeros((3, 3)), wind=wind)
    c = check_or_clip_inputs(MODEL, nu=np.zeros((3, 3)), wind=np.zeros((1, 2)) + [60.0, 0.0])  # 1 broadcasts
    np.testing.assert_array_equal(c.clipped, [True, True, True])


@pytest.mark.parametrize("kwargs, pattern", [
    (dict(eta=[1.0, 0.0]), r"eta: expected width 3 \(north_m, east_m, psi_rad\), got shape \(2,\)"),
    (dict(nu=np.zeros((4, 2))), r"nu: expected width 3 \(u_m_s, v_m_s, r_rad_s\), got shape \(4, 2\)"),
    (dict(wind=[5.0]), r"wind: expected width 2 \(speed_m_s, dir_from_rad\), got shape \(1,\)"),
    (dict(current=[0.5, 0.0, 1.0]), r"current: expected width 2 \(speed_m_s, dir_to_rad\), got shape \(3,\)"),
])
def test_a_state_or_flow_of_the_wrong_width_is_refused_by_name(kwargs, pattern):
    # before: an IndexError from the column checks ("index 2 is out of bounds"), or a wider
    # current passed on unchecked
    with pytest.raises(ValueError, match=pattern):
        check_or_clip_inputs(MODEL, **kwargs)


def test_extremes_that_overflow_the_integrator_are_finite_after_clipping():
    """At |u| 20 m/s, v 8 m/s, full rpm, 51 m/s wind and 5 m/s current the 1-s RK4 rollout
    of Gunnerus overflowed (inf) when the envelope was chosen; clipped, it stays finite."""
    x = dict(eta=[0.0, 0.0, 0.0], nu=[20.0, 8.0, 0.5], rpm=MAX_RPM * 1.5, wind=[60.0, 0.0], current=[5.0, np.pi],
             azimuth_rad=[0.0, 0.0, 0.0])
    c = check_or_clip_inputs(MODEL, **x, dt_s=1.0)
    assert c.clipped.all() and set(k for k, v in c.clipped_fields.items() if v.any()) == {"nu", "rpm", "wind"}
    # each velocity to its own bound of the table (u 8, v 4 m/s, r 0.3 rad/s): "nu" flagged
    # by u alone passed a yaw rate clipped to the wrong bound, or not at all
    np.testing.assert_allclose(c.nu, [8.0, 4.0, 0.3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.rpm, MAX_RPM, rtol=0, atol=1e-12)
    res = MODEL.rollout(c.eta, c.nu, 120, rpm=c.rpm, wind=c.wind, current=c.current, azimuth_rad=c.azimuth_rad)
    assert np.isfinite(res.eta).all() and np.isfinite(res.nu).all()
    assert np.abs(res.nu[..., 0]).max() < 20.0


finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)
angles = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False, allow_infinity=False)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(nu=st.tuples(finite, finite, finite),
       rpm_factor=st.tuples(*[st.floats(-2.0, 2.0)] * 3),
       az=st.tuples(angles, angles, angles),
       wind=st.tuples(st.floats(0.0, 1e4), angles),
       current=st.tuples(st.floats(0.0, 1e3), angles),
       dt_s=st.sampled_from([0.1, 0.5, 1.0, 2.0]))
def test_any_finite_input_within_the_refusal_bounds_is_clipped_to_a_finite_forecast(nu, rpm_factor, az, wind, current, dt_s):
    rpm = np.asarray(rpm_factor) * MAX_RPM
    # Every input drawn is finite, speeds are >= 0 and |rpm| <= 2 x max_rpm (rpm_refuse_factor):
    # nothing here is a fault that clip mode refuses, so each example must be clipped and rolled
    # out (a refusal here would make the property hold for any input without testing it).
    assert envelope_for(MODEL).rpm_refuse_factor >= 2.0
    c = check_or_clip_inputs(MODEL, eta=[0.0, 0.0, 0.3], nu=nu, rpm=rpm, azimuth_rad=az, wind=wind,
                             current=current, dt_s=dt_s)
    res = MODEL.rollout(c.eta, c.nu, 60, dt_s=dt_s, substeps=c.substeps, rpm=c.rpm, azimuth_rad=c.azimuth_rad,
                        wind=c.wind, current=c.current)
    assert np.isfinite(res.eta).all() and np.isfinite(res.nu).all() and np.isfinite(res.nu_dot).all()


def test_rudder_channels_clip_the_angle_and_ignore_rpm():
    env = envelope_for("esso_osaka_model")
    assert env.channel_names == ("propeller", "rudder") and env.max_rpm[1] == np.inf
    lim = env.max_angle_rad[1]
    assert env.max_angle_rad[0] == np.inf and 0 < lim < np.pi / 2
    c = check_or_clip_inputs("esso_osaka_model", rpm=[600.0, 0.0], azimuth_rad=[[0.0, 0.3], [0.0, 1.2]])
    np.testing.assert_allclose(c.azimuth_rad[:, 1], [0.3, lim])
    np.testing.assert_array_equal(c.clipped_fields["azimuth_rad"], [False, True])
    with pytest.raises(InputRangeError, match=r"azimuth_rad\[batch 1, rudder 'rudder'\]: 1.2 is outside"):
        check_or_clip_inputs("esso_osaka_model", mode="refuse", azimuth_rad=[[0.0, 0.3], [0.0, 1.2]])


def test_a_rudder_beyond_either_stop_is_clipped_to_it():
    """The rudder limit is on the angle's magnitude: beyond the port stop (negative) it is
    clipped to -max_angle and flagged, as beyond the starboard one."""
    lim = envelope_for("esso_osaka_model").max_angle_rad[1]
    c = check_or_clip_inputs("esso_osaka_model", azimuth_rad=[[0.0, -1.2], [0.0, -0.3]])
    np.testing.assert_allclose(c.azimuth_rad[:, 1], [-lim, -0.3])
    np.testing.assert_array_equal(c.clipped_fields["azimuth_rad"], [True, False])
    with pytest.raises(InputRangeError, match=r"azimuth_rad\[batch 0, rudder 'rudder'\]: -1.2 is outside"):
        check_or_clip_inputs("esso_osaka_model", mode="refuse", azimuth_rad=[[0.0, -1.2], [0.0, -0.3]])


def test_commands_exactly_at_their_limits_pass_unflagged():
    """``max_rpm`` and the rudder's stop are allowed values (the fault is ``|x| > limit``), and
    ``rpm_refuse_factor x max_rpm`` is still clipped, not refused as a unit error."""
    env = envelope_for(MODEL)
    for mode in ("clip", "refuse"):
        c = check_or_clip_inputs(MODEL, mode=mode, rpm=[MAX_RPM, -MAX_RPM])
        np.testing.assert_array_equal(c.rpm, [MAX_RPM, -MAX_RPM])
        assert not c.clipped.any()
    c = check_or_clip_inputs(MODEL, rpm=env.rpm_refuse_factor * MAX_RPM)
    np.testing.assert_array_equal(c.rpm, MAX_RPM)
    assert c.clipped.all()
    lim = envelope_for("esso_osaka_model").max_angle_rad[1]
    for mode in ("clip", "refuse"):
        c = check_or_clip_inputs("esso_osaka_model", mode=mode, azimuth_rad=[[0.0, lim], [0.0, -lim]])
        np.testing.assert_array_equal(c.azimuth_rad[:, 1], [lim, -lim])
        assert not c.clipped.any()


def test_angles_are_wrapped_before_the_rudder_stop_is_judged():
    """A rudder angle one turn away from a small one is that angle (not beyond the stop), and a
    thruster direction comes back in [-pi, pi), the same direction, neither flagged."""
    c = check_or_clip_inputs("esso_osaka_model", mode="refuse", azimuth_rad=[4.0, 2 * np.pi + 0.1])
    np.testing.assert_allclose(c.azimuth_rad, [4.0 - 2 * np.pi, 0.1], rtol=1e-12)
    assert not c.clipped.any()
    with pytest.raises(ValueError, match="azimuth_rad: width 3 does not match the vessel's 2 command channels"):
        check_or_clip_inputs("esso_osaka_model", azimuth_rad=[0.0, 0.1, 0.2])


@pytest.mark.parametrize("value", ["60", b"60", True, np.bool_(True)])
def test_check_number_refuses_text_and_bools(value):
    """Review: ``float()`` read "60" (and True) as numbers, so a text setting passed every check."""
    from hybridship.config import check_number

    with pytest.raises(TypeError, match="^horizon_s: expected a number, got "):
        check_number("horizon_s", value)
    assert check_number("horizon_s", np.float32(60.0)) == 60.0 and check_number("horizon_s", np.int64(60)) == 60.0
