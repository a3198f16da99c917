"""Sensor faults at forecast time (hybridship.forecast_inputs.start_window): fault injection and replay.

A noise-free log made by the dynamic model itself is the reference: without faults the
start values are the predictors' plain rule; each fault is injected at a known time and
the log is replayed through :func:`assess_start_window` at every start time, checking the
documented behaviour (which starts are flagged, which refused, and that every accepted
start's values are finite and close to the fault-free ones).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from hybridship.forecast_inputs import FaultFlags, StartWindowError, assess_start_window, forecast_log_arrays
from hybridship.forecast_inputs.faults import velocity_track_mismatch_m
from hybridship.logs.ingest import SortedLog, sort_samples
from hybridship.logs.io import LogFormatError
from hybridship.sim.synthetic import physics_log

T_FAULT = 300  # fault time [s] = row (1 Hz log starting at 0)
F = FaultFlags


@pytest.fixture(scope="module")
def log(model):
    """Moving ship, rpm up to 60 % of max, never shut down, 1 Hz, 500 s."""
    return physics_log(model, seed=3, duration_s=500.0, t_shutdown_s=None, rpm_scale=0.6)


@pytest.fixture(scope="module")
def short_log(model):
    """The first 200 s of a moving ship's log, 1 Hz, for random fault injection."""
    return physics_log(model, seed=8, duration_s=200.0, t_shutdown_s=None, rpm_scale=0.6)


def _assess(model, df, starts, **kw):
    arrays, order = forecast_log_arrays(df, model.vessel)
    return arrays, assess_start_window(arrays, arrays.time_s.searchsorted(starts), 3.0, order=order, **kw)


def _plain_rule(df, rows):
    """Position at the start row; heading (unwrapped) and velocities averaged over 3 rows; wind at the row."""
    psi = np.unwrap(np.radians(df.heading_deg.to_numpy()))
    nu = np.column_stack([df.u_m_s, df.v_m_s, np.radians(df.r_deg_s)])
    eta0 = np.array([[df.north_m[i], df.east_m[i], psi[i - 2: i + 1].mean()] for i in rows])
    nu0 = np.array([nu[i - 2: i + 1].mean(axis=0) for i in rows])
    wind = np.column_stack([df.wind_speed_m_s[rows], np.radians(df.wind_dir_deg[rows])])
    return eta0, nu0, wind


# ----------------------------------------------------------------------------- no fault


def test_without_faults_the_start_values_are_the_plain_rule(model, log):
    starts = np.arange(3, 490, 7)
    _, sw = _assess(model, log, starts)
    eta0, nu0, wind = _plain_rule(log, starts)
    np.testing.assert_allclose(sw.eta0, eta0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sw.nu0, nu0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sw.wind, wind, rtol=0, atol=1e-12)
    degraded = {k: int(v.sum()) for k, v in sw.flags.items() if v.any() and k not in F.INFORMATIONAL}
    assert degraded == {}
    assert not sw.degraded.any() and set(sw.flags) == set(F.START_WINDOW)


def test_a_ship_at_rest_with_constant_noise_free_values_is_not_frozen(model):
    rest = physics_log(model, seed=4, duration_s=200.0, t_shutdown_s=None, rpm_scale=0.0, wind=(0.0, 0.0))
    assert rest.north_m.nunique() == 1 and rest.u_m_s.abs().max() == 0.0
    _, sw = _assess(model, rest, [100.0, 150.0])
    assert not sw.degraded.any()


@pytest.mark.parametrize("bad, pattern", [
    (dict(frozen_motion_m=0.0), r"frozen_motion_m: must be > 0, got 0.0"),
    (dict(frozen_motion_m=-1.0), r"frozen_motion_m: must be > 0, got -1.0"),
    (dict(frozen_turn_deg=-1.0), r"frozen_turn_deg: must be > 0, got -1.0"),
    (dict(frozen_turn_deg=float("nan")), r"frozen_turn_deg: must be finite"),
    (dict(lookback_s=-5.0), r"lookback_s: must be >= 0, got -5.0"),
    (dict(lookback_s=float("nan")), r"lookback_s: must be finite"),
])
def test_frozen_thresholds_and_lookback_out_of_range_are_refused_by_name(model, bad, pattern):
    """Before: a motion or turn threshold of 0 or less refused a ship at rest as frozen ("the
    logged speed says the ship moved"); NaN, or a negative lookback, turned checks off unseen."""
    rest = physics_log(model, seed=4, duration_s=200.0, t_shutdown_s=None, rpm_scale=0.0, wind=(0.0, 0.0))
    with pytest.raises(ValueError, match=pattern):
        _assess(model, rest, [100.0, 150.0], on_refuse="flag", **bad)


# ----------------------------------------------------------------------------- fault injection

def _nan(cols, rows):
    def inject(df):
        df.loc[rows, cols] = np.nan
        return df
    return inject


def _freeze(cols, first, last):
    def inject(df):
        df.loc[first:last, cols] = df.loc[first, cols].to_numpy()
        return df
    return inject


def _shift(col, rows, metres):
    def inject(df):
        df.loc[rows, col] += metres
        return df
    return inject


def _swap(a, b):
    def inject(df):
        order = list(range(len(df)))
        order[a], order[b] = order[b], order[a]
        return df.iloc[order].reset_index(drop=True)
    return inject


def _drop(rows):
    return lambda df: df.drop(index=rows).reset_index(drop=True)


def _duplicate(row, north_offset=0.0):
    def inject(df):
        extra = df.iloc[[row]].copy()
        extra["north_m"] += north_offset
        return pd.concat([df.iloc[: row + 1], extra, df.iloc[row + 1:]]).reset_index(drop=True)
    return inject


# name: dict(inject, flag, flagged = starts that must carry the flag, refused = starts refused,
#           pos_tol [m] / head_tol [deg] = largest error of accepted starts against the
#           fault-free values, span = last start that may carry other flags)
# "window(a, b)" = starts whose 3-s window holds a time in a..b = starts a..b+2.
def window(a, b):
    return set(range(a, b + 3))


def fault(inject, flag, flagged, refused=(), pos_tol=0.0, head_tol=1.0, span=T_FAULT + 20, nu_tol=0.05):
    return dict(inject=inject, flag=flag, flagged=set(flagged), refused=set(refused), pos_tol=pos_tol,
                head_tol=head_tol, span=span, nu_tol=nu_tol)


T = T_FAULT
FAULTS = {
    "nan position, one sample": fault(_nan(["north_m"], [T]), F.NAN_IN_WINDOW, window(T, T), pos_tol=0.05),
    "nan heading, one sample": fault(_nan(["heading_deg"], [T]), F.NAN_IN_WINDOW, window(T, T)),
    "nan heading, three samples": fault(_nan(["heading_deg"], [T, T + 1, T + 2]), F.NAN_IN_WINDOW,
                                        window(T, T + 2), refused=range(T + 1, T + 4)),
    "missing sample": fault(_drop([T]), F.NAN_IN_WINDOW, window(T - 1, T) - {T - 1, T}),
    "two missing samples": fault(_drop([T, T + 1]), F.NAN_IN_WINDOW, window(T, T + 1) - {T, T + 1},
                                 refused={T + 2}),
    # detected once frozen for 3 s while the logged speed (0.30 m/s here) moved the ship
    # 2 m, i.e. from 307; refused until live positions return at 321 (an unconfirmed jump
    # at 321 itself); before 307 the error is at most 2 m (the documented bound)
    # (the live positions' return is a lasting shift, flagged position_jump until T + 33)
    "frozen gnss": fault(_freeze(["north_m", "east_m"], T, T + 20), F.FROZEN_SENSOR, range(T + 7, T + 23),
                         refused=range(T + 7, T + 22), pos_tol=2.0, span=T + 33),
    "frozen gyro": fault(_freeze(["heading_deg"], T, T + 20), F.FROZEN_SENSOR, range(T + 3, T + 23),
                         refused=range(T + 3, T + 22), head_tol=1.5),
    "gnss spike": fault(_shift("north_m", [T], 25.0), F.POSITION_JUMP, window(T, T + 1), pos_tol=0.05),
    # flagged while the shift lies within lookback_s (10 s) before the window, but for the
    # first step looked at, which could be a spike's return
    "gnss datum shift": fault(_shift("north_m", slice(T, None), 25.0), F.POSITION_JUMP, range(T, T + 13),
                              pos_tol=25.05),
    # a heading spike (60 deg, one sample): dropped; flagged while the spike is in the window
    "gyro spike": fault(_shift("heading_deg", [T], 60.0), F.HEADING_JUMP, window(T, T)),
    # a lasting heading shift: unconfirmed (dropped) at T, then the new headings are used;
    # flagged while the shift lies within lookback_s (10 s) before the window. The logged
    # velocity, rotated with the shifted heading, then disagrees with the track (by 0.3 m/s
    # here): velocity_mismatch once that reaches 8 m over 30 s, from T + 29 on, and u, v
    # derived from the track with that heading (which moves the forecast along the track)
    # then differ from the logged ones by up to the ship's speed
    "gyro shift": fault(_shift("heading_deg", slice(T, None), 60.0), F.HEADING_JUMP, range(T, T + 14),
                        head_tol=61.0, span=T + 40, nu_tol=0.35),
    # a speed log biased by 1 m/s in sway from T on (the ship makes 0.3 m/s): detected once
    # the logged velocity has moved the ship 8 m off the track within 30 s, at T + 8; u and
    # v are then derived from the track (within 1 mm/s of the fault-free values here,
    # test_a_biased_speed_log_is_replaced_by_the_track); before, the bias is in the start
    "biased speed log": fault(_shift("v_m_s", slice(T, None), 1.0), F.VELOCITY_MISMATCH, range(T + 8, T + 40),
                              span=T + 40, nu_tol=1.01),
    # away for five samples and back: a lasting shift until the return (at T + 5 the return
    # into the start row leaves one valid heading: refused), then the excursion is dropped
    "gyro excursion": fault(_shift("heading_deg", slice(T, T + 4), 60.0), F.HEADING_JUMP, range(T, T + 7),
                            refused={T + 5}, head_tol=61.0),
    "wind sensor dropped": fault(_nan(["wind_speed_m_s", "wind_dir_deg"], list(range(T, T + 30))),
                                 F.WIND_DROPPED, range(T + 2, T + 30), span=T + 31),
    # the flag marks the windows holding the late arrivals: 300 in the first case, 300..305
    # (all came after 306) in the second
    "samples out of order": fault(_swap(T, T + 1), F.LATE_OR_OUT_OF_ORDER, window(T, T)),
    "late sample": fault(_swap(T, T + 6), F.LATE_OR_OUT_OF_ORDER, window(T, T + 5)),
    "exact duplicate": fault(_duplicate(T), F.LATE_OR_OUT_OF_ORDER, window(T, T)),
    # both samples of the conflicting time are removed: T is no longer a sample time
    "conflicting duplicate": fault(_duplicate(T, north_offset=3.0), F.LATE_OR_OUT_OF_ORDER, window(T, T) - {T},
                                   pos_tol=0.05),
}


@pytest.mark.parametrize("name", list(FAULTS))
def test_fault_replay(model, log, name):
    spec = FAULTS[name]
    flag = spec["flag"]
    df = spec["inject"](log.copy())
    ingested = forecast_log_arrays(df, model.vessel)[0].time_s
    starts = np.intersect1d(np.arange(T - 25, T + 40), ingested).astype(float)  # sample times only
    arrays, sw = _assess(model, df, starts, on_refuse="flag")
    got_flagged = set(sw.start_time_s[sw.flags[flag]].astype(int))
    got_refused = set(sw.start_time_s[sw.refused].astype(int))
    assert got_flagged == spec["flagged"], f"{name}: {flag} at {sorted(got_flagged ^ spec['flagged'])} differs"
    assert got_refused == spec["refused"], f"{name}: refused {sorted(got_refused)}"
    # starts away from the fault carry no degradation flag at all
    near = spec["flagged"] | spec["refused"] | set(range(T - 2, spec["span"] + 1))
    quiet = ~np.isin(sw.start_time_s.astype(int), sorted(near))
    assert quiet.sum() >= 20 and not sw.degraded[quiet].any()
    # accepted starts: finite, and close to the fault-free start values
    ok = ~sw.refused
    assert np.isfinite(sw.eta0[ok]).all() and np.isfinite(sw.nu0[ok]).all() and np.isfinite(sw.wind[ok]).all()
    rows = starts[ok].astype(int)
    eta_ref, nu_ref, wind_ref = _plain_rule(log, rows)
    err_pos = np.hypot(*(sw.eta0[ok, :2] - eta_ref[:, :2]).T)
    assert err_pos.max() <= spec["pos_tol"] + 1e-9, f"{name}: position off by {err_pos.max():.3f} m"
    err_head = np.degrees(np.abs(sw.eta0[ok, 2] - eta_ref[:, 2])).max()
    assert err_head <= spec["head_tol"], f"{name}: heading off by {err_head:.2f} deg"
    assert np.abs(sw.nu0[ok] - nu_ref).max() < spec["nu_tol"]
    # refused starts: NaN start values and a reason in the notes
    assert np.isnan(sw.eta0[sw.refused]).all()
    assert all("too little valid data" in sw.notes[k] for k in np.flatnonzero(sw.refused))
    if flag == F.WIND_DROPPED:
        assert np.all(sw.wind[sw.flags[flag]] == 0.0)   # falls back to no wind



def _each_start_alone(monkeypatch):
    """Make assess_start_window clear no start at once: every start goes through the detectors."""
    from hybridship.forecast_inputs import start_window

    def none_quiet(view, idx, settings):
        S = idx.size
        return np.zeros(S, dtype=bool), np.full((S, 3), np.nan), np.full((S, 3), np.nan), np.zeros((S, 2))
    monkeypatch.setattr(start_window, "quiet_starts", none_quiet)


def _assert_same_windows(a, b):
    for name in ("eta0", "nu0", "wind"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert {k: v.tolist() for k, v in a.flags.items()} == {k: v.tolist() for k, v in b.flags.items()}
    assert a.notes == b.notes


@pytest.mark.parametrize("variant", ["faults", "no logged velocities", "at rest", "10 Hz"])
def test_starts_cleared_at_once_get_exactly_what_the_detectors_give(model, log, monkeypatch, variant):
    """The quiet starts found with array operations (quiet_starts) carry the flags, notes and
    start values, bit for bit, that the detectors give them one by one: on every injected
    fault, without logged velocities, at rest (long runs of repeated values) and at 10 Hz
    (30-sample windows). Most starts of a healthy log are cleared at once."""
    from hybridship.forecast_inputs.faults import LogView, WindowSettings
    from hybridship.forecast_inputs.quiet_starts import quiet_starts

    if variant == "faults":
        logs = [log] + [spec["inject"](log.copy()) for spec in FAULTS.values()]
    elif variant == "no logged velocities":
        logs = [_shift("north_m", [T], 25.0)(log.drop(columns=["u_m_s", "v_m_s", "r_deg_s"]))]
    elif variant == "at rest":
        logs = [physics_log(model, seed=4, duration_s=200.0, t_shutdown_s=None, rpm_scale=0.0, wind=(0.0, 0.0))]
    else:
        logs = [_shift("heading_deg", [1000], 40.0)(physics_log(model, seed=5, duration_s=200.0, dt_s=0.1,
                                                                t_shutdown_s=None, rpm_scale=0.6))]
    results = []
    for df in logs:
        arrays, order = forecast_log_arrays(df, model.vessel)
        rows = np.arange(len(arrays))
        results.append((arrays, rows, order, assess_start_window(arrays, rows, 3.0, order=order, on_refuse="flag")))
    cleared = [quiet_starts(LogView.build(a, WindowSettings(), o.affected_time_s), r, WindowSettings())[0].mean()
               for a, r, o, _ in results]
    with monkeypatch.context() as m:
        _each_start_alone(m)
        for arrays, rows, order, at_once in results:
            _assert_same_windows(at_once, assess_start_window(arrays, rows, 3.0, order=order, on_refuse="flag"))
    if variant in ("faults", "10 Hz"):     # the fault-free log, and the 10-Hz one but near its jump
        assert cleared[0] > (0.95 if variant == "faults" else 0.8), cleared[0]


_FAULT_KINDS = {
    "nan": lambda df, r, col, size: _nan([col], list(range(r, r + 1 + size % 3)))(df),
    "freeze": lambda df, r, col, size: _freeze([col], r, r + 2 + size % 6)(df),
    "spike": lambda df, r, col, size: _shift(col, [r], float(size))(df),
    "shift": lambda df, r, col, size: _shift(col, slice(r, None), float(size))(df),
    "swap": lambda df, r, col, size: _swap(r, r + 1 + size % 5)(df),
    "drop": lambda df, r, col, size: _drop(list(range(r, r + 1 + size % 3)))(df),
}


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(faults=st.lists(st.tuples(st.sampled_from(sorted(_FAULT_KINDS)), st.integers(20, 170),
                                 st.sampled_from(["north_m", "east_m", "heading_deg", "u_m_s", "v_m_s", "r_deg_s"]),
                                 st.integers(1, 40)), min_size=1, max_size=3),
       with_velocities=st.booleans())
def test_starts_cleared_at_once_agree_with_the_detectors_on_random_faults(model, short_log, faults, with_velocities):
    """Random faults (missing, frozen, spiked, shifted, late and dropped samples, of any
    channel, up to three): every start's flags, notes and start values are the same whether
    it is cleared at once or goes through the detectors."""
    df = short_log.copy() if with_velocities else short_log.drop(columns=["u_m_s", "v_m_s"])
    for kind, row, col, size in faults:
        if col in df:
            df = _FAULT_KINDS[kind](df, row, col, size)
    try:
        arrays, order = forecast_log_arrays(df, model.vessel)
    except LogFormatError:          # a fault the ingest refuses as a unit or sign error: no start to judge
        assume(False)
    rows = np.arange(len(arrays))
    at_once = assess_start_window(arrays, rows, 3.0, order=order, on_refuse="flag")
    with pytest.MonkeyPatch.context() as m:
        _each_start_alone(m)
        _assert_same_windows(at_once, assess_start_window(arrays, rows, 3.0, order=order, on_refuse="flag"))

def test_refusal_raises_a_clear_error_by_default(model, log):
    df = _nan(["heading_deg"], [T_FAULT, T_FAULT - 1])(log.copy())
    with pytest.raises(StartWindowError, match=r"start time_s 300: refused, .*too little valid data in the 3-s "
                                               r"window \(time_s 298\.\.300\): heading: 1 valid of 3") as info:
        _assess(model, df, [250.0, 300.0])
    assert info.value.start_time_s == 300.0 and list(info.value.refused_start_times_s) == [300.0]
    # the refusal leads; what led to it follows, without "valid samples used" (nothing was)
    assert str(info.value).startswith("start time_s 300: refused, too little valid data")
    assert "missing heading in the window" in str(info.value) and "valid samples used" not in str(info.value)


def test_a_start_at_the_logs_beginning_is_refused_saying_so(model, log):
    """Review: a start within one window of the log's first sample was refused for too
    little valid data without saying why there was too little."""
    with pytest.raises(StartWindowError, match=r"start time_s 0: refused, too little valid data .*the window "
                                               r"reaches back before the log's first sample \(time_s 0\): start "
                                               r"later"):
        _assess(model, log, [0.0])
    with pytest.raises(StartWindowError) as info:      # a fault later in a log: no such hint
        _assess(model, _nan(["heading_deg"], [T_FAULT, T_FAULT - 1])(log.copy()), [300.0])
    assert "first sample" not in str(info.value)


def test_frozen_gnss_refusal_names_the_frozen_sensor(model, log):
    df = _freeze(["north_m", "east_m"], T_FAULT, T_FAULT + 20)(log.copy())
    with pytest.raises(StartWindowError, match=r"refused, too little valid data .*position: no valid sample.*"
                                               r"frozen for >= 3 s: position \(the logged speed says the ship "
                                               r"moved\)"):
        _assess(model, df, [T_FAULT + 15.0])


def test_frozen_logged_velocity_is_replaced_by_the_track(model, log):
    u = log.u_m_s.to_numpy()
    i = int(np.argmax(np.abs(u[20:400] - u[:380]))) + 20     # where u changes most over 20 s
    df = _freeze(["u_m_s"], i - 20, i)(log.copy())
    _, sw = _assess(model, df, [float(i)])
    assert sw.flags[F.FROZEN_SENSOR][0] and "u_m_s (disagrees with the track)" in sw.notes[0]
    _, nu_ref, _ = _plain_rule(log, [i])
    stale_error = abs(df.u_m_s[i] - nu_ref[0, 0])
    assert stale_error > 0.2                                 # the frozen value is far off ...
    assert abs(sw.nu0[0, 0] - nu_ref[0, 0]) < 0.1 * stale_error  # ... the track-derived one is not


def test_a_biased_speed_log_is_replaced_by_the_track(model, log):
    """A speed log that reads 1 m/s too much in sway: once detected, u and v come from the
    track (within 1 mm/s), and the positions are not judged by it (no position jump), also
    at a start 25 s after the bias, whose jump check would otherwise see a step it does
    not explain at every row."""
    starts = [T_FAULT + 8.0, T_FAULT + 25.0]
    _, clean = _assess(model, log.copy(), starts)
    _, sw = _assess(model, _shift("v_m_s", slice(T_FAULT, None), 1.0)(log.copy()), starts)
    assert sw.flags[F.VELOCITY_MISMATCH].all() and not sw.flags[F.POSITION_JUMP].any()
    assert "u_m_s, v_m_s disagree with the track" in sw.notes[0]
    np.testing.assert_allclose(sw.nu0, clean.nu0, atol=1e-3)
    np.testing.assert_array_equal(sw.eta0, clean.eta0)


def test_a_biased_speed_log_stays_found_across_a_gap(model, log):
    """A gap of a few samples starts a new segment, whose first half window cannot judge
    the speed log on its own: the judgement from before the gap is carried (within the
    track window), so a start 5 s after the gap does not take the 1-m/s bias back."""
    biased = _shift("v_m_s", slice(T_FAULT, None), 1.0)(log.copy())
    gap = list(range(T_FAULT + 40, T_FAULT + 43))
    start = [float(T_FAULT + 48)]
    _, clean = _assess(model, log.drop(index=gap), start)
    _, sw = _assess(model, biased.drop(index=gap), start)
    assert sw.flags[F.VELOCITY_MISMATCH].all()
    np.testing.assert_allclose(sw.nu0, clean.nu0, atol=1e-3)

def test_velocity_track_mismatch_is_causal_and_ignores_position_faults(model, log):
    """The mismatch at a row depends on the rows before it only; a GNSS spike or datum
    shift (a step beyond jump_m), a frozen receiver and a receiver that holds its fix
    between 1-Hz updates of a 10-Hz log add nothing to it; a bias does, also a bias of
    several m/s that moves every position step beyond jump_m, and so does a steady turn's
    exact travel at 0.2 Hz not."""
    a = forecast_log_arrays(log, model.vessel)[0]
    full = velocity_track_mismatch_m(a, 30.0)
    assert np.nanmax(full) < 1.0                                  # clean: noise only
    cut = forecast_log_arrays(log.iloc[:T_FAULT + 1], model.vessel)[0]
    np.testing.assert_array_equal(velocity_track_mismatch_m(cut, 30.0), full[:T_FAULT + 1])
    np.testing.assert_array_equal(velocity_track_mismatch_m(a, 30.0, first_row=100, last_row=200),
                                  velocity_track_mismatch_m(cut, 30.0, first_row=100, last_row=200))
    for inject in (_shift("north_m", [T_FAULT], 25.0), _shift("north_m", slice(T_FAULT, None), 25.0),
                   _freeze(["north_m", "east_m"], T_FAULT, T_FAULT + 20)):
        faulty_log = inject(log.copy())
        faulty = velocity_track_mismatch_m(forecast_log_arrays(faulty_log, model.vessel)[0], 30.0)
        assert np.nanmax(faulty) < 1.0
        cut_faulty = forecast_log_arrays(faulty_log.iloc[:T_FAULT + 6], model.vessel)[0]   # mid-fault
        np.testing.assert_array_equal(velocity_track_mismatch_m(cut_faulty, 30.0), faulty[:T_FAULT + 6])
    for bias, at_29_s in ((0.5, 14.5), (6.0, 174.0)):
        biased = forecast_log_arrays(_shift("u_m_s", slice(T_FAULT, None), bias)(log.copy()), model.vessel)[0]
        m = velocity_track_mismatch_m(biased, 30.0)
        np.testing.assert_array_equal(m[:T_FAULT], full[:T_FAULT])
        assert m[T_FAULT + 29] == pytest.approx(at_29_s, rel=0.05)      # the bias over the 29 s since
    fast = physics_log(model, seed=3, duration_s=300.0, t_shutdown_s=None, rpm_scale=0.6, dt_s=0.1)
    held = fast.copy()
    held[["north_m", "east_m"]] = fast[["north_m", "east_m"]].to_numpy()[np.arange(len(fast)) // 10 * 10]
    assert np.nanmax(velocity_track_mismatch_m(forecast_log_arrays(held, model.vessel)[0], 30.0)) < 1.0
    t = np.arange(0.0, 600.0, 5.0)                                    # 0.2 Hz, 12 m/s turning at 5 deg/s
    psi = np.radians(5.0) * t
    turning = forecast_log_arrays(pd.DataFrame({
        "time_s": t, "north_m": 12.0 / np.radians(5.0) * np.sin(psi),
        "east_m": 12.0 / np.radians(5.0) * (1 - np.cos(psi)),
        "heading_deg": np.degrees(psi) % 360.0, "u_m_s": 12.0, "v_m_s": 0.0, "r_deg_s": 5.0, "dp_active": 0}),
        model.vessel)[0]
    assert np.nanmax(velocity_track_mismatch_m(turning, 30.0)) < 1e-6


def test_a_start_window_does_not_depend_on_the_other_starts_of_the_call(model, log):
    """The velocity check is computed only as far back as the earliest start's windows reach;
    faults just before that (a GNSS spike, then an outage, then a biased speed log) give each
    start the same flags and start values whichever other starts share the call."""
    faulty = log.copy()
    s, f0 = T_FAULT, T_FAULT - 47
    faulty.loc[f0, "north_m"] += 25.0
    faulty.loc[f0 + 1:f0 + 16, ["north_m", "east_m"]] = np.nan
    faulty.loc[f0 + 17:, "v_m_s"] += 1.5
    arrays, order = forecast_log_arrays(faulty, model.vessel)
    alone = assess_start_window(arrays, arrays.time_s.searchsorted([s]), 3.0, order=order, on_refuse="flag")
    for others in ([s - 3], [0], [s - 40, s - 20]):
        rows = arrays.time_s.searchsorted([*others, s])
        sw = assess_start_window(arrays, rows, 3.0, order=order, on_refuse="flag")
        assert {k: bool(v[-1]) for k, v in sw.flags.items()} == {k: bool(v[0]) for k, v in alone.flags.items()}
        np.testing.assert_array_equal(sw.nu0[-1], alone.nu0[0])
        np.testing.assert_array_equal(sw.eta0[-1], alone.eta0[0])


def test_gnss_spike_without_logged_velocities_is_rederived(model, log):
    df = log.drop(columns=["u_m_s", "v_m_s"])
    clean = _assess(model, df, [T_FAULT + 1.0])[1]
    spiked = _assess(model, _shift("north_m", [T_FAULT], 25.0)(df.copy()), [T_FAULT + 1.0])[1]
    assert spiked.flags[F.POSITION_JUMP][0] and not clean.degraded[0]
    np.testing.assert_allclose(spiked.eta0, clean.eta0, atol=1e-9)     # the start sample itself is fine
    np.testing.assert_allclose(spiked.nu0[0, :2], clean.nu0[0, :2], atol=0.05)  # 25 m would give 12 m/s


def test_heading_wrap_in_the_window_averages_unwrapped(model, log):
    df = log.copy()
    df.loc[T_FAULT - 2: T_FAULT, "heading_deg"] = [359.0, 0.0, 1.0]
    df.loc[: T_FAULT - 3, "heading_deg"] = 359.0           # no other turn: no heading jump into the wrap
    df.loc[T_FAULT + 1:, "heading_deg"] = 1.0
    # the velocities go too: the replaced heading no longer turns them onto the track
    df = df.drop(columns=["r_deg_s", "u_m_s", "v_m_s"])
    _, sw = _assess(model, df, [float(T_FAULT)])
    assert sw.flags[F.HEADING_WRAPPED][0] and not sw.degraded[0] and not sw.flags[F.HEADING_JUMP][0]
    assert abs(np.degrees(sw.eta0[0, 2]) % 360.0 - 0.0) < 1e-9 or abs(np.degrees(sw.eta0[0, 2]) % 360.0 - 360) < 1e-9


def test_heading_wrap_with_a_logged_yaw_rate_is_no_heading_jump(model, log):
    """A heading crossing 0/360 and then +-180 deg while the logged yaw rate turns the ship:
    no jump, also when the heading handed to the check is wrapped (not unwrapped)."""
    df = log.copy()
    r = np.where(df.time_s >= 200, 3.0, 0.0)                       # deg/s: through 0 at 300, 180 at 360
    df["r_deg_s"] += r
    df["heading_deg"] = (df.heading_deg - df.heading_deg[300] + np.cumsum(r) - r[:301].sum()) % 360.0
    starts = np.arange(280.0, 380.0)
    arrays, sw = _assess(model, df, starts)
    assert sw.flags[F.HEADING_WRAPPED].any() and not sw.flags[F.HEADING_JUMP].any()
    wrapped = dataclasses.replace(arrays, eta=np.column_stack([arrays.eta[:, :2], np.radians(df.heading_deg)]))
    assert np.ptp(np.diff(wrapped.eta[280:380, 2])) > 6.0          # holds the 2 pi steps
    sw = assess_start_window(wrapped, arrays.time_s.searchsorted(starts), 3.0)
    assert not sw.flags[F.HEADING_JUMP].any()


@pytest.mark.parametrize("logged_r", [True, False])
def test_a_fast_real_turn_is_no_heading_jump(model, log, logged_r):
    """A 14 deg/s turn (beyond any Gunnerus turn; within the envelope's 17 deg/s) steps 14 deg
    per sample: explained by the logged yaw rate from its onset, and without it by the median
    step rate once the turn fills most of the history (its onset is then flagged: documented)."""
    df = log.copy()
    r = np.clip((df.time_s.to_numpy() - 200.0) * 7.0, 0.0, 14.0)   # ramps up over 2 s at 200 s
    df["r_deg_s"] += r
    df["heading_deg"] = (df.heading_deg + np.concatenate([[0.0], np.cumsum(0.5 * (r[1:] + r[:-1]))])) % 360.0
    if not logged_r:
        df = df.drop(columns="r_deg_s")
    starts = np.arange(200.0, 300.0) if logged_r else np.arange(240.0, 300.0)
    _, sw = _assess(model, df, starts)
    assert not sw.flags[F.HEADING_JUMP].any(), sw.notes[int(np.argmax(sw.flags[F.HEADING_JUMP]))]
    if not logged_r:
        _, onset = _assess(model, df, [203.0], on_refuse="flag")
        assert onset.flags[F.HEADING_JUMP][0]


def test_heading_jump_note_names_the_times_and_the_repair(model, log):
    df = _shift("heading_deg", [T_FAULT], 60.0)(log.copy())
    _, sw = _assess(model, df, [T_FAULT + 1.0])
    assert sw.flags[F.HEADING_JUMP][0] and sw.degraded[0]
    assert sw.notes[0] == ("heading jump of more than 10 deg (not explained by the yaw rate) at time_s 300, 301: "
                           "outlier(s) dropped (time_s 300)")
    _, sw = _assess(model, df, [T_FAULT + 1.0], heading_jump_deg=70.0)
    assert not sw.flags[F.HEADING_JUMP][0]
    for bad in (0.0, -1.0, 180.0, np.nan):
        with pytest.raises(ValueError, match="heading_jump_deg must be > 0 and < 180"):
            _assess(model, df, [T_FAULT + 1.0], heading_jump_deg=bad)


def test_one_missing_wind_sample_holds_the_latest_valid_one(model, log):
    """A wind sample is its speed and direction: either missing leaves the latest sample with
    both (a missing direction alone is not the speed of that row with an older direction)."""
    windy = log.assign(wind_speed_m_s=np.linspace(5, 10, len(log)), wind_dir_deg=np.linspace(10, 80, len(log)))
    for col in ("wind_speed_m_s", "wind_dir_deg"):
        df = _nan([col], [T_FAULT])(windy.copy())
        _, sw = _assess(model, df, [float(T_FAULT)])
        assert sw.flags[F.NAN_IN_WINDOW][0] and not sw.flags[F.WIND_DROPPED][0], col
        latest = [df.wind_speed_m_s[T_FAULT - 1], np.radians(df.wind_dir_deg[T_FAULT - 1])]
        np.testing.assert_allclose(sw.wind[0], latest, rtol=0, atol=1e-12, err_msg=col)


def test_commands_missing_at_the_start_are_flagged_with_the_time_they_are_held_from(model, log):
    """Commands not logged since well before the start are held (as the log format says), and
    the start says so: nan_in_window, with the time of the last logged values."""
    cmd = [c for c in log.columns if c.endswith("_rpm") or c.endswith("_azimuth_deg")]
    df = log.copy()
    df.loc[(df.time_s > T_FAULT - 50) & (df.time_s <= T_FAULT), cmd] = np.nan
    _, sw = _assess(model, df, [float(T_FAULT), float(T_FAULT - 60)])
    assert sw.flags[F.NAN_IN_WINDOW][0] and not sw.flags[F.NAN_IN_WINDOW][1]
    assert f"last logged value held, all logged together last at time_s {T_FAULT - 50:g}" in sw.notes[0]


def test_dp_active_missing_at_the_start_is_flagged_like_a_command(model, log):
    """A start whose dp_active was not logged holds the last logged state (as for commands)
    and says so: nan_in_window with the time it is held from."""
    df = log.assign(dp_active=log["dp_active"].astype(float))
    df.loc[df.time_s == T_FAULT, "dp_active"] = np.nan
    _, sw = _assess(model, df, [float(T_FAULT), float(T_FAULT - 60)])
    assert sw.flags[F.NAN_IN_WINDOW][0] and not sw.flags[F.NAN_IN_WINDOW][1]
    assert f"last logged value held, all logged together last at time_s {T_FAULT - 1:g}" in sw.notes[0]


def test_a_log_without_wind_is_not_a_dropped_sensor(model, log):
    _, sw = _assess(model, log.drop(columns=["wind_speed_m_s", "wind_dir_deg"]), [float(T_FAULT)])
    assert not sw.flags[F.WIND_DROPPED][0] and np.all(sw.wind == 0.0)


def test_a_wind_sensor_dead_over_the_whole_log_is_flagged(model, log):
    """Wind columns without one valid sample are a dead sensor, not a log without wind."""
    _, sw = _assess(model, log.assign(wind_speed_m_s=np.nan, wind_dir_deg=np.nan), [float(T_FAULT)])
    assert sw.flags[F.WIND_DROPPED][0] and np.all(sw.wind == 0.0)
    assert "no valid sample" in sw.notes[0]


def test_first_sample_of_a_log_is_refused(model, log):
    _, sw = _assess(model, log, [0.0, 1.0, 2.0], on_refuse="flag")
    np.testing.assert_array_equal(sw.refused, [True, False, False])
    assert sw.flags[F.NAN_IN_WINDOW][:2].all()             # fewer samples than the window holds


# ----------------------------------------------------------------------------- sort_samples


def test_sort_samples_reports_and_repairs():
    df = pd.DataFrame({"time_s": [0.0, 1.0, 3.0, 2.0, 3.0, 4.0, 4.0, np.nan, 5.0],
                       "north_m": [0.0, 1.0, 3.0, 2.0, 3.0, 4.0, 4.5, 9.0, 5.0],
                       "east_m": 0.0, "heading_deg": 10.0, "dp_active": 1})
    before = df.copy(deep=True)
    out = sort_samples(df)
    assert isinstance(out, SortedLog) and out.changed
    pd.testing.assert_frame_equal(df, before)
    np.testing.assert_array_equal(out.frame.time_s, [0, 1, 2, 3, 5])   # 4 removed: neither value trusted
    np.testing.assert_array_equal(out.late_time_s, [2.0])   # 2 came after 3; the second 3 is a duplicate
    np.testing.assert_array_equal(out.duplicate_time_s, [3.0])
    np.testing.assert_array_equal(out.conflicting_time_s, [4.0])
    np.testing.assert_array_equal(out.conflicting_rows, [[5, 6]])
    assert out.n_without_time == 1
    np.testing.assert_array_equal(out.frame.north_m, [0, 1, 2, 3, 5])
    assert list(out.affected_time_s) == [2.0, 3.0, 4.0]
    clean = sort_samples(df.iloc[:3])
    assert not clean.changed


def test_start_window_table_and_flag_names(model, log):
    _, sw = _assess(model, _nan(["north_m"], [T_FAULT])(log.copy()), [250.0, float(T_FAULT)])
    table = sw.to_frame()
    assert list(table.columns) == ["start_time_s", *F.START_WINDOW, "notes"]
    assert table.nan_in_window.tolist() == [False, True] and table.notes[1]
    cols = sw.flag_columns(61)
    assert set(cols) == set(F.START_WINDOW) and cols[F.NAN_IN_WINDOW].shape == (122,)
    assert cols[F.NAN_IN_WINDOW][:61].sum() == 0 and cols[F.NAN_IN_WINDOW][61:].all()
    assert set(F.START_WINDOW) < set(F.ALL) and {F.INPUT_CLIPPED, F.OUT_OF_ENVELOPE} <= set(F.ALL)
    assert len(set(F.ALL)) == len(F.ALL)


def test_arguments_are_checked(model, log):
    arrays, _ = forecast_log_arrays(log, model.vessel)
    with pytest.raises(ValueError, match="on_refuse"):
        assess_start_window(arrays, [5], on_refuse="ignore")
    with pytest.raises(IndexError, match="idx"):
        assess_start_window(arrays, [len(arrays)])
    with pytest.raises(ValueError, match="window_s"):
        assess_start_window(arrays, [5], window_s=0.0)
    # before: row 100.7 was read as row 100, and a boolean mask of the starts as rows 0 and 1
    mask = np.zeros(len(arrays), dtype=bool)
    mask[[100, 200]] = True
    for bad in ([100.7], mask, ["100"]):
        with pytest.raises(TypeError, match="idx: expected start rows as whole numbers"):
            assess_start_window(arrays, bad)
    np.testing.assert_array_equal(assess_start_window(arrays, np.array([100.0])).start_time_s, arrays.time_s[[100]])


def test_start_rows_that_are_infinite_or_not_one_axis_are_refused_naming_idx(model, log):
    """Before: row inf was read as row -9223372036854775808 ("start rows must lie in 0..499, got
    -9223372036854775808"), and rows of shape (1, 2) failed in numpy's boolean indexing."""
    arrays, _ = forecast_log_arrays(log, model.vessel)
    with pytest.raises(TypeError, match=r"idx: expected start rows as whole numbers, got float64 values \[inf\]"):
        assess_start_window(arrays, [np.inf])
    with pytest.raises(ValueError, match=r"idx: expected start rows of shape \(S,\), got shape \(1, 2\)"):
        assess_start_window(arrays, [[100, 200]])


def test_the_refusal_lists_epoch_start_times_in_full(model):
    """Before: the list of refused starts was written with ``:g``, so starts on an epoch clock all
    read "1.7e+09" ("3 of 3 starts refused, at time_s 1.7e+09, 1.7e+09, 1.7e+09")."""
    df = _at_rest(time_s=1.7e9 + np.arange(60.0))
    df.loc[20:40, "north_m"] = np.nan
    arrays, order = forecast_log_arrays(df, model.vessel)
    with pytest.raises(StartWindowError, match=r"\(3 of 3 starts refused, at time_s 1700000025, 1700000030, "
                                               r"1700000035\)"):
        assess_start_window(arrays, [25, 30, 35], order=order)


def _at_rest(n: int = 60, **columns) -> pd.DataFrame:
    """A 1-Hz log of a ship at rest heading north (adrift, no thrust), every value exact; ``columns`` overrides."""
    df = pd.DataFrame({"time_s": np.arange(float(n)), "north_m": 0.0, "east_m": 0.0, "heading_deg": 0.0,
                       "u_m_s": 0.0, "v_m_s": 0.0, "r_deg_s": 0.0, "dp_active": 0})
    for name, values in columns.items():
        df[name] = values
    return df


def test_a_position_step_of_exactly_jump_m_is_no_jump(model):
    """The fault is a step the velocity misses by *more than* ``jump_m`` (5 m): a ship at rest whose
    position steps 5 m north (exact in binary) is not flagged; 5.5 m is."""
    for step, flagged in ((5.0, False), (5.5, True)):
        north = np.where(np.arange(60) >= 30, step, 0.0)
        arrays, order = forecast_log_arrays(_at_rest(north_m=north), model.vessel)
        sw = assess_start_window(arrays, [31, 45], 3.0, order=order, on_refuse="flag")
        assert list(sw.flags[F.POSITION_JUMP]) == [flagged, False], step


def test_a_fix_is_frozen_once_the_logged_speed_moves_the_ship_frozen_motion_m(model):
    """Position contradicted by the logged speed *by 2 m or more* (``frozen_motion_m``): 0.5 m/s
    over rows 20..23 integrates (trapezoid) to exactly 2 m, and the unchanged fix is frozen; over
    rows 20..22 to 1.5 m, and it is not. The note names the position, and the logged v,
    bit-identical meanwhile, which the track contradicts by as much."""
    for last, frozen in ((23, True), (22, False)):
        u = np.where((np.arange(60) >= 20) & (np.arange(60) <= last), 0.5, 0.0)
        arrays, order = forecast_log_arrays(_at_rest(u_m_s=u), model.vessel)
        sw = assess_start_window(arrays, [30], 3.0, order=order, on_refuse="flag")
        assert ("position (the logged speed says the ship moved)" in sw.notes[0]) == frozen, sw.notes
        assert ("v_m_s (disagrees with the track)" in sw.notes[0]) == frozen          # v: 0 m/s for 30 s


def test_a_frozen_yaw_rate_is_derived_from_the_headings(model):
    """A ship turning on the spot at 1 deg/s whose logged ``r`` stays at 0: r is frozen (the
    headings say it turned), and the start's r is the headings' turn over the window's time."""
    t = np.arange(60.0)
    arrays, order = forecast_log_arrays(_at_rest(heading_deg=t, r_deg_s=0.0), model.vessel)
    sw = assess_start_window(arrays, [30], 3.0, order=order, on_refuse="flag")
    assert sw.flags[F.FROZEN_SENSOR][0] and "r_deg_s" in sw.notes[0]
    assert sw.nu0[0, 2] == pytest.approx(np.radians(1.0), rel=1e-12)


def test_a_heading_excursion_twice_the_lookback_long_is_not_a_lasting_shift(model, log):
    """A gyro away by 60 deg for 15 s (more than ``lookback_s``, less than twice it) and back:
    once the return lies before the window, the pair is still seen as one excursion (the span
    looked at reaches back ``3 lookback_s``), so no start after it is flagged as shifted."""
    df = _shift("heading_deg", slice(T, T + 14), 60.0)(log.copy())
    _, sw = _assess(model, df, np.arange(T + 18, T + 30, dtype=float), on_refuse="flag")
    assert not sw.flags[F.HEADING_JUMP].any()


def test_window_settings_accept_their_documented_edges():
    """``min_valid_fraction`` in (0, 1]: every sample valid may be asked for; ``heading_jump_deg``
    in (0, 180): a step is at most 180 deg."""
    from hybridship.forecast_inputs.faults import WindowSettings

    assert WindowSettings(min_valid_fraction=1.0).min_valid_fraction == 1.0
    for bad in (dict(min_valid_fraction=0.0), dict(min_valid_fraction=1.5), dict(heading_jump_deg=180.0)):
        with pytest.raises(ValueError):
            WindowSettings(**bad)


@pytest.mark.parametrize("bad, error, pattern", [
    (dict(window_s="3"), TypeError, r"window_s: expected a number, got '3'"),
    (dict(window_s=float("inf")), ValueError, r"window_s: must be finite"),
    (dict(jump_m=float("nan")), ValueError, r"jump_m: must be finite"),
    (dict(track_mismatch_m=-1.0), ValueError, r"track_mismatch_m: must be > 0, got -1.0"),
    (dict(min_valid_fraction=None), TypeError, r"min_valid_fraction: expected a number, got None"),
    (dict(heading_jump_deg="10"), TypeError, r"heading_jump_deg: expected a number, got '10'"),
])
def test_window_settings_name_the_setting_that_is_not_a_valid_number(bad, error, pattern):
    """Before: text or None was a bare comparison TypeError ("'>' not supported between ..."), a NaN
    threshold a message naming four settings at once, and an infinite window an OverflowError."""
    from hybridship.forecast_inputs.faults import WindowSettings

    with pytest.raises(error, match=pattern):
        WindowSettings(**bad)


@pytest.mark.parametrize("drop", [["u_m_s", "v_m_s", "r_deg_s"], []])
def test_derived_start_velocities_do_not_read_the_sample_after_the_start(model, log, drop):
    """Velocities the log derives (no column, or a logged sample missing at the start) are
    central differences; at the start row they would read the next position and heading.
    The start values are those of the log cut at the start, whatever follows it."""
    df = log.drop(columns=drop)
    if not drop:                                           # a dropped speed-log and gyro-rate sample at the start
        df.loc[T_FAULT, ["u_m_s", "r_deg_s"]] = np.nan
    later = df.copy()
    later.loc[T_FAULT + 1:, ["north_m", "east_m"]] += 3.0
    later.loc[T_FAULT + 1:, "heading_deg"] = (later.loc[T_FAULT + 1:, "heading_deg"] + 5.0) % 360.0
    cut = _assess(model, df.loc[:T_FAULT], [float(T_FAULT)])[1]
    for other in (df, later):
        sw = _assess(model, other, [float(T_FAULT)])[1]
        np.testing.assert_allclose(sw.nu0, cut.nu0, rtol=0, atol=1e-12)
        np.testing.assert_allclose(sw.eta0, cut.eta0, rtol=0, atol=1e-12)


def test_logged_start_velocities_are_not_derived_again(model, log, monkeypatch):
    """The start row's one-sided difference is for derived velocities only: where u, v and r
    are logged at the start (every benchmark's log) the detectors' path takes them as logged
    and does not derive them (it cost ~80 us a start, +20 % on a 400-start forecast)."""
    import hybridship.forecast_inputs.faults as faults

    df = log.copy()
    df.loc[T_FAULT - 1, "north_m"] = np.nan             # no start is quiet: the detectors judge them
    starts = [float(T_FAULT), float(T_FAULT + 1)]
    expected = _assess(model, df, starts)[1]

    def derive(*args, **kw):
        raise AssertionError("start_row_nu called on logged velocities")

    monkeypatch.setattr(faults, "start_row_nu", derive)
    sw = _assess(model, df, starts)[1]
    np.testing.assert_array_equal(sw.nu0, expected.nu0)
    np.testing.assert_array_equal(sw.eta0, expected.eta0)
