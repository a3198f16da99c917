"""Property-based tests (hypothesis) of the physics, the frames and the log readers.

* random valid states and commands (within :mod:`hybridship.forecast_inputs.limits`' envelope) give finite
  accelerations, and finite rollouts over a minute;
* frame rotations preserve norms and invert each other;
* random valid logs survive write -> read unchanged in every container.

Example counts are explicit (``max_examples``); ``docs/reliability.md`` quotes the counts
of an actual run (``pytest --hypothesis-show-statistics``).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from hybridship import frames
from hybridship.forecast_inputs.limits import envelope_for
from hybridship.logs.io import LogFormatError, log_to_arrays, read_log, validate_log, write_log
from hybridship.physics.model import DynamicModel

MODEL = DynamicModel("gunnerus")
ENV = envelope_for(MODEL)
MAX_RPM = np.asarray(ENV.max_rpm)
THRUSTERS = list(ENV.channel_names)
ROTATABLE = MODEL.vessel.rotatable
B = 8  # vessels per example (the kernels are batched)


def _col(lo, hi):
    return hnp.arrays(np.float64, (B,), elements=st.floats(lo, hi, allow_nan=False, allow_infinity=False))


@st.composite
def valid_inputs(draw):
    """States and held commands anywhere inside the documented envelope (edges included)."""
    eta = np.column_stack([draw(_col(-ENV.position_max_m, ENV.position_max_m)),
                           draw(_col(-ENV.position_max_m, ENV.position_max_m)),
                           draw(_col(-ENV.heading_max_rad, ENV.heading_max_rad))])
    nu = np.column_stack([draw(_col(-ENV.surge_max_m_s, ENV.surge_max_m_s)),
                          draw(_col(-ENV.sway_max_m_s, ENV.sway_max_m_s)),
                          draw(_col(-ENV.yaw_rate_max_rad_s, ENV.yaw_rate_max_rad_s))])
    rpm = np.column_stack([draw(_col(-1.0, 1.0)) for _ in MAX_RPM]) * MAX_RPM
    az = np.column_stack([draw(_col(-np.pi, np.pi)) for _ in MAX_RPM])
    wind = np.column_stack([draw(_col(0.0, ENV.wind_speed_max_m_s)), draw(_col(-np.pi, np.pi))])
    current = np.column_stack([draw(_col(0.0, ENV.current_speed_max_m_s)), draw(_col(-np.pi, np.pi))])
    return dict(eta=eta, nu=nu, rpm=rpm, azimuth_rad=az, wind=wind, current=current)


@settings(max_examples=80, deadline=None)
@given(x=valid_inputs())
def test_valid_states_and_commands_give_finite_accelerations(x):
    nu_dot, parts, thrusts = MODEL.acceleration(x["eta"], x["nu"], rpm=x["rpm"], azimuth_rad=x["azimuth_rad"],
                                                wind=x["wind"], current=x["current"], return_parts=True)
    assert np.isfinite(nu_dot).all() and np.isfinite(parts).all() and np.isfinite(thrusts).all()


@settings(max_examples=50, deadline=None)
@given(x=valid_inputs(), dt_s=st.sampled_from([0.1, 0.5, 1.0]))
def test_rollouts_inside_the_envelope_stay_finite(x, dt_s):
    res = MODEL.rollout(x["eta"], x["nu"], int(round(60 / dt_s)), dt_s=dt_s, rpm=x["rpm"],
                        azimuth_rad=x["azimuth_rad"], wind=x["wind"], current=x["current"])
    assert np.isfinite(res.eta).all() and np.isfinite(res.nu).all() and np.isfinite(res.nu_dot).all()


@settings(max_examples=60, deadline=None)
@given(x=valid_inputs(), turn_rad=st.floats(-np.pi, np.pi), shift_m=st.floats(-1e4, 1e4))
def test_accelerations_do_not_change_when_heading_wind_and_current_turn_together(x, turn_rad, shift_m):
    """The body-frame loads see only the wind and current relative to the heading: turning the
    heading and both flow directions by the same angle [rad], and moving the ship by
    ``shift_m`` north and east [m], leaves ``nu_dot`` unchanged."""
    kw = dict(rpm=x["rpm"], azimuth_rad=x["azimuth_rad"])
    nu_dot = MODEL.acceleration(x["eta"], x["nu"], wind=x["wind"], current=x["current"], **kw)
    turn = np.array([0.0, turn_rad])
    moved = MODEL.acceleration(x["eta"] + np.array([shift_m, shift_m, turn_rad]), x["nu"], wind=x["wind"] + turn,
                               current=x["current"] + turn, **kw)
    scale = max(1.0, float(np.abs(nu_dot).max()))
    np.testing.assert_allclose(moved, nu_dot, rtol=1e-7, atol=1e-9 * scale)


@settings(max_examples=40, deadline=None)
@given(x=valid_inputs(), turn_rad=st.floats(-np.pi, np.pi))
def test_a_rollout_turned_with_its_wind_and_current_is_the_same_path_turned(x, turn_rad):
    """Turning the start heading, the wind and the current by ``turn_rad`` [rad] turns the whole
    20-s path about its start point by that angle [m]; body velocities are unchanged and the
    heading is shifted by the angle."""
    kw = dict(rpm=x["rpm"], azimuth_rad=x["azimuth_rad"], dt_s=0.5)
    turn = np.array([0.0, turn_rad])
    a = MODEL.rollout(x["eta"], x["nu"], 40, wind=x["wind"], current=x["current"], **kw)
    b = MODEL.rollout(x["eta"] + np.array([0.0, 0.0, turn_rad]), x["nu"], 40, wind=x["wind"] + turn,
                      current=x["current"] + turn, **kw)
    moved = a.eta - a.eta[:, :1]
    want = frames.body_to_ned(np.concatenate([moved[..., :2], np.zeros(moved.shape[:2] + (1,))], -1), turn_rad)
    scale = max(1.0, float(np.abs(moved[..., :2]).max()))
    np.testing.assert_allclose(b.eta[..., :2] - b.eta[:, :1, :2], want[..., :2], rtol=1e-6, atol=1e-7 * scale)
    np.testing.assert_allclose(b.eta[..., 2] - a.eta[..., 2], turn_rad, rtol=0, atol=1e-7 * max(1.0, abs(turn_rad)))
    np.testing.assert_allclose(b.nu, a.nu, rtol=1e-6, atol=1e-7 * max(1.0, float(np.abs(a.nu).max())))


vec = hnp.arrays(np.float64, st.tuples(st.integers(1, 6), st.just(3)),
                 elements=st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False))


@settings(max_examples=100, deadline=None)
@given(v=vec, psi=st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False))
def test_frame_rotations_preserve_norms_and_invert(v, psi):
    ned = frames.body_to_ned(v, psi)
    scale = max(1.0, float(np.abs(v).max()))
    np.testing.assert_allclose(np.hypot(ned[:, 0], ned[:, 1]), np.hypot(v[:, 0], v[:, 1]), rtol=1e-12,
                               atol=1e-9 * scale)
    np.testing.assert_array_equal(ned[:, 2], v[:, 2])        # the yaw component is not rotated
    np.testing.assert_allclose(frames.ned_to_body(ned, psi), v, rtol=1e-12, atol=1e-9 * scale)
    R = frames.rotation_z(psi)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert abs(np.linalg.det(R) - 1.0) < 1e-12
    np.testing.assert_allclose(ned, v @ R.T, rtol=1e-12, atol=1e-9 * scale)


@st.composite
def valid_logs(draw):
    """A physically consistent log: positions are the integral of the body velocities
    rotated with the heading, the heading the integral of the yaw rate."""
    n = draw(st.integers(2, 40))
    dt = draw(st.sampled_from([0.5, 1.0, 2.0]))
    jitter = draw(hnp.arrays(np.float64, (n,), elements=st.floats(0.0, 0.2)))
    t = draw(st.floats(0.0, 1e5)) + np.arange(n) * dt + jitter          # strictly increasing
    u = draw(hnp.arrays(np.float64, (n,), elements=st.floats(-8.0, 8.0)))
    v = draw(hnp.arrays(np.float64, (n,), elements=st.floats(-4.0, 4.0)))
    r_deg_s = draw(hnp.arrays(np.float64, (n,), elements=st.floats(-5.0, 5.0)))
    h0 = draw(st.floats(0.0, 359.0))
    dtt = np.diff(t)
    psi_deg = h0 + np.concatenate(([0.0], np.cumsum(0.5 * dtt * (r_deg_s[1:] + r_deg_s[:-1]))))
    psi = np.radians(psi_deg)
    vn, ve = np.cos(psi) * u - np.sin(psi) * v, np.sin(psi) * u + np.cos(psi) * v
    north = draw(st.floats(-1e5, 1e5)) + np.concatenate(([0.0], np.cumsum(0.5 * dtt * (vn[1:] + vn[:-1]))))
    east = draw(st.floats(-1e5, 1e5)) + np.concatenate(([0.0], np.cumsum(0.5 * dtt * (ve[1:] + ve[:-1]))))
    cols = {"time_s": t, "north_m": north, "east_m": east, "heading_deg": np.mod(psi_deg, 360.0),
            "u_m_s": u, "v_m_s": v, "r_deg_s": r_deg_s}
    if draw(st.booleans()):
        speed = draw(hnp.arrays(np.float64, (n,), elements=st.floats(0.0, 51.0) | st.just(np.nan)))
        cols["wind_speed_m_s"] = speed
        cols["wind_dir_deg"] = draw(hnp.arrays(np.float64, (n,), elements=st.floats(90.0, 350.0)))
    for name, mx, rot in zip(THRUSTERS, MAX_RPM, ROTATABLE):
        if draw(st.booleans()):
            cols[f"{name}_rpm"] = draw(hnp.arrays(np.float64, (n,), elements=st.floats(-mx, mx) | st.just(np.nan)))
            if rot:
                cols[f"{name}_azimuth_deg"] = draw(hnp.arrays(np.float64, (n,), elements=st.floats(-180.0, -10.0)
                                                              | st.floats(10.0, 180.0)))
    cols["dp_active"] = draw(hnp.arrays(np.int64, (n,), elements=st.integers(0, 1)))
    df = pd.DataFrame(cols)
    try:
        validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    except LogFormatError:
        assume(False)  # the rare draw that breaks a plausibility rule (e.g. ambiguous degrees)
    return df


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(df=valid_logs())
def test_readers_round_trip_random_valid_logs(df):
    before = df.copy(deep=True)
    ref = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("log.csv", "log.csv.gz", "log.parquet"):
            path = Path(tmp) / name
            write_log(df, path, channel_names=THRUSTERS, rotatable=ROTATABLE)
            back = read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)
            pd.testing.assert_frame_equal(back, df, check_exact=True, check_dtype=False)
            arr = log_to_arrays(back, channel_names=THRUSTERS, rotatable=ROTATABLE)
            for field in ("time_s", "eta", "nu", "rpm", "azimuth_rad", "wind", "dp_active", "wind_logged"):
                np.testing.assert_array_equal(getattr(arr, field), getattr(ref, field), err_msg=f"{name}: {field}")
        assert sorted(p.name for p in Path(tmp).iterdir()) == ["log.csv", "log.csv.gz", "log.parquet"]
    pd.testing.assert_frame_equal(df, before, check_exact=True)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(df=valid_logs())
def test_log_arrays_hold_random_valid_logs_in_si_units_and_radians(df):
    """The arrays of a log are its columns in SI units and radians: the heading is unwrapped
    (its steps [rad] are the trapezoid integral of the logged yaw rate the log was built
    from, never a 2 pi jump), ``r`` is in rad/s, wind and azimuth directions in radians."""
    arr = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    t, r_rad_s = df["time_s"].to_numpy(), np.radians(df["r_deg_s"].to_numpy())
    np.testing.assert_array_equal(arr.eta[:, :2], df[["north_m", "east_m"]].to_numpy())
    np.testing.assert_allclose(np.diff(arr.eta[:, 2]), 0.5 * np.diff(t) * (r_rad_s[1:] + r_rad_s[:-1]), atol=1e-9)
    np.testing.assert_allclose(np.cos(arr.eta[:, 2]), np.cos(np.radians(df["heading_deg"].to_numpy())), atol=1e-12)
    np.testing.assert_allclose(arr.nu, np.column_stack([df["u_m_s"], df["v_m_s"], r_rad_s]), rtol=1e-15)
    if "wind_speed_m_s" in df:
        ok = np.isfinite(df["wind_speed_m_s"].to_numpy())
        np.testing.assert_array_equal(arr.wind[ok, 0], df["wind_speed_m_s"].to_numpy()[ok])
        np.testing.assert_allclose(arr.wind[ok, 1], np.radians(df["wind_dir_deg"].to_numpy()[ok]), rtol=1e-15)
    for j, name in enumerate(THRUSTERS):
        if f"{name}_rpm" in df:
            ok = np.isfinite(df[f"{name}_rpm"].to_numpy())
            np.testing.assert_array_equal(arr.rpm[ok, j], df[f"{name}_rpm"].to_numpy()[ok])
        if f"{name}_azimuth_deg" in df:
            np.testing.assert_allclose(arr.azimuth_rad[:, j], np.radians(df[f"{name}_azimuth_deg"]), rtol=1e-15)
