"""Physical facts of the Gunnerus model against published magnitudes (docs/gunnerus-model.md).

The computations mirror ``benchmarks/gunnerus_response.py`` but are written out here so the
tests depend only on the library; the last test runs the script itself (tables only).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from conftest import ROOT, load_benchmark


KNOT = 1852.0 / 3600.0
TUNNEL, PORT, STBD = 0, 1, 2


def steady_speed(model, rpm):
    """Steady surge speed [m/s] with both azimuths at angle 0 and ``rpm`` (tunnel stopped)."""
    def u_dot(u):
        return model.acceleration([0, 0, 0], [u, 0, 0], rpm=[0, rpm, rpm], azimuth_rad=[0, 0, 0])[0, 0]

    return brentq(u_dot, 1e-6, 40.0, xtol=1e-10)


def turn(model, angle_deg, rpm=150.0, duration_s=600.0, dt_s=0.5):
    """Starboard azimuth slewed (10 deg/s) to ``angle_deg`` from a straight run at ``rpm``."""
    u0 = steady_speed(model, rpm)
    n = int(duration_s / dt_s)
    t = np.arange(n) * dt_s
    az = np.zeros((1, n, 3))
    az[0, :, STBD] = np.radians(np.sign(angle_deg) * np.minimum(10.0 * t, abs(angle_deg)))
    res = model.rollout([0, 0, 0], [u0, 0, 0], n, dt_s=dt_s, substeps=2, rpm=[0, rpm, rpm], azimuth_rad=az)
    return u0, res


# ----------------------------------------------------------------------------- speed


def test_speed_at_max_rpm_near_published(model):
    """Published: service 10 kn, maximum 12.6 kn; the model reaches 10-13 kn at 217 rpm."""
    max_rpm = model.vessel.thrusters[STBD].max_rpm
    assert max_rpm == 217.0
    u = steady_speed(model, max_rpm)
    assert 10.0 < u / KNOT < 13.0
    # the steady state really is one: thrust balances resistance, no sway or yaw
    nu_dot = model.acceleration([0, 0, 0], [u, 0, 0], rpm=[0, max_rpm, max_rpm], azimuth_rad=[0, 0, 0])
    np.testing.assert_allclose(nu_dot, 0.0, atol=1e-9)


def test_speed_increases_with_rpm_and_service_speed_below_max_rpm(model):
    speeds = [steady_speed(model, r) for r in (50, 100, 150, 200, 217)]
    assert np.all(np.diff(speeds) > 0)
    rpm_10kn = brentq(lambda r: steady_speed(model, r) - 10 * KNOT, 1.0, 217.0)
    assert 150.0 < rpm_10kn < 217.0


# ----------------------------------------------------------------------------- turning


def test_thrust_to_starboard_at_stern_turns_bow_to_port(model):
    """Azimuth +20 deg pushes the stern to starboard: yaw moment < 0 and r < 0 (bow to port)."""
    u0 = steady_speed(model, 150.0)
    _, parts, _ = model.acceleration([0, 0, 0], [u0, 0, 0], rpm=[0, 150, 150],
                                     azimuth_rad=[0, 0, math.radians(20)], return_parts=True)
    assert parts[0, 1, 1] > 0  # thrust: sway force to starboard
    assert parts[0, 1, 2] < 0  # thrust: yaw moment bow to port
    for angle, sign in ((20.0, -1.0), (-20.0, 1.0), (35.0, -1.0), (-35.0, 1.0)):
        _, res = turn(model, angle)
        r_ss = res.nu[0, -120:, 2].mean()
        assert sign * r_ss > math.radians(1.0), (angle, math.degrees(r_ss))
        assert np.sign(res.eta[0, -1, 2]) == sign  # heading keeps turning that way
        U = np.hypot(res.nu[0, -1, 0], res.nu[0, -1, 1])
        assert U < u0  # speed loss in the turn


def test_larger_azimuth_angle_turns_tighter(model):
    r20 = abs(turn(model, 20.0)[1].nu[0, -120:, 2].mean())
    r35 = abs(turn(model, 35.0)[1].nu[0, -120:, 2].mean())
    assert r35 > r20


# ----------------------------------------------------------------------------- free decay


def test_free_decay_monotonic_in_speed(model):
    """Thrusters at 0 rpm: no energy input, so speed and kinetic energy only decrease."""
    nu0 = [2.0, 0.5, math.radians(1.0)]
    res = model.rollout([0, 0, 0], nu0, 3600, dt_s=0.5, substeps=2, rpm=[0, 0, 0], azimuth_rad=[0, 0, 0])
    nu = res.nu[0]
    speed = np.hypot(nu[:, 0], nu[:, 1])
    assert np.all(np.diff(speed) <= 1e-12)
    ke = 0.5 * np.einsum("ti,ij,tj->t", nu, model.mass_matrix, nu)
    assert np.all(np.diff(ke) <= 1e-9)
    assert speed[-1] < 0.05 * speed[0]
    # surge halves on a time scale of minutes, not seconds or hours
    t_half = res.time_s[np.argmax(nu[:, 0] <= 1.0)]
    assert 30.0 < t_half < 300.0
    assert np.all(nu[:, 0] > 0)  # never reverses in surge


# ----------------------------------------------------------------------------- beam-wind drift


@pytest.mark.parametrize("dir_from", [-math.pi / 2, math.pi / 2], ids=["from_west", "from_east"])
def test_beam_wind_drift_is_a_few_percent_to_leeward(model, dir_from):
    """Stopped ship in a 10 m/s beam wind: drift 1-6 % of the wind speed (rule of thumb 2-4 %), to leeward."""
    wind = 10.0
    res = model.rollout([0, 0, 0], [0, 0, 0], 3600, dt_s=1.0, substeps=2, rpm=[0, 0, 0], azimuth_rad=[0, 0, 0],
                        wind=[wind, dir_from])
    eta, nu = res.eta[0, -300:], res.nu[0, -300:]
    c, s = np.cos(eta[:, 2]), np.sin(eta[:, 2])
    vel = np.column_stack([c * nu[:, 0] - s * nu[:, 1], s * nu[:, 0] + c * nu[:, 1]]).mean(axis=0)
    drift = np.hypot(*vel)
    assert 0.01 * wind < drift < 0.06 * wind
    leeward = np.array([-math.cos(dir_from), -math.sin(dir_from)])  # the way the wind blows
    assert vel @ leeward > 0.8 * drift
    np.testing.assert_allclose(res.nu[0, -1], res.nu[0, -300], atol=1e-4)  # steady


# ----------------------------------------------------------------------------- the script


def test_benchmark_script_runs(capsys, tmp_path):
    mod = load_benchmark("gunnerus_response")
    assert mod.main(["--no-plot", "--tables", str(tmp_path / "tables.md")]) == 0
    text = capsys.readouterr().out
    # the committed tables the model page includes are what the script writes today
    committed = ROOT / "docs" / "results" / "gunnerus-response" / "tables.md"
    assert (tmp_path / "tables.md").read_text() == committed.read_text()
    assert committed.read_text() in text + "\n"
    assert "Speed at max rpm (217)" in text
    assert "Sign check: positive azimuth (thrust to starboard at the stern) gives r < 0 (bow to port): True" in text
