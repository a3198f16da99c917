"""Physical checks for the simulator's environment: JONSWAP, wave drift, WF motion, wind, current.

Gunnerus: Lpp 33.9 m, B 9.6 m, T 2.5 m. Conventions: wave and wind directions are where
they come FROM, current where it flows TO, all clockwise from north; beta = wave
direction - heading (0 head seas, -pi/2 waves from port).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.stats import kstest

from hybridship.frames import speed_dir_to_vector
from hybridship.sim import environment
from hybridship.sim.environment import (
    GUNNERUS_HULL,
    HullDimensions,
    MotionRAOs,
    SeaState,
    WaveField,
    _gauss_markov,
    _jittered_components,
    _jonswap,
    beaufort_wave_height,
    beaufort_wind_speed,
    current_series,
    current_velocity_ned,
    davenport_spectrum,
    drift_coefficients,
    gust_wind,
    harris_spectrum,
    jonswap_gamma_dnv,
    jonswap_spectrum,
    make_wave_components,
    max_hs_m,
    mean_drift_loads,
    wave_drift_loads,
    wave_frequency_motion,
)
from hybridship.sim.scenario import DPLossConfig

GUNNERUS = dict(L_m=33.9, B_m=9.6, T_m=2.5)
RHO, G = 1025.0, 9.81
HEAD, FROM_PORT = 0.0, -np.pi / 2


# --------------------------------------------------------------------------- JONSWAP


@pytest.mark.parametrize("gamma", [1.0, 2.0, 3.3, 5.0, 7.0])
@pytest.mark.parametrize("hs_m, tp_s", [(1.0, 6.0), (0.5, 4.0), (3.0, 10.0)])
def test_jonswap_m0_gives_hs_within_2_percent(hs_m, tp_s, gamma):
    w = np.linspace(1e-3, 40.0, 400_001)
    m0 = np.trapezoid(jonswap_spectrum(w, hs_m, tp_s, gamma), w)
    assert 4.0 * math.sqrt(m0) == pytest.approx(hs_m, rel=0.02)


@pytest.mark.parametrize("gamma", [1.0, 3.3, 6.0])
def test_jonswap_peak_at_two_pi_over_tp(gamma):
    tp = 6.5
    w = np.linspace(0.2, 5.0, 200_001)
    s = jonswap_spectrum(w, 1.2, tp, gamma)
    assert w[np.argmax(s)] == pytest.approx(2.0 * np.pi / tp, abs=2 * (w[1] - w[0]))


@pytest.mark.parametrize("side, sigma", [(-1.0, 0.07), (1.0, 0.09)], ids=["below_peak", "above_peak"])
def test_jonswap_peak_width_is_0_07_below_and_0_09_above_the_peak(side, sigma):
    """One width ``sigma wp`` from the peak, JONSWAP / Pierson-Moskowitz (gamma = 1) is
    ``(1 - 0.287 ln gamma) gamma^exp(-1/2)``, with DNV-RP-C205's sigma 0.07 below and 0.09 above."""
    tp, gamma = 7.0, 3.3
    w = 2.0 * np.pi / tp * (1.0 + side * sigma)
    ratio = jonswap_spectrum(w, 1.0, tp, gamma) / jonswap_spectrum(w, 1.0, tp, 1.0)
    assert ratio == pytest.approx((1.0 - 0.287 * math.log(gamma)) * gamma ** math.exp(-0.5), rel=1e-9)


@pytest.mark.parametrize("ratio, gamma", [(3.0, 5.0), (4.2, math.exp(5.75 - 1.15 * 4.2)), (5.5, 1.0)])
def test_dnv_peak_enhancement_from_hs_and_tp(ratio, gamma):
    """DNV-RP-C205 3.5.5.5: gamma = 5 for ``Tp / sqrt(Hs) <= 3.6``, ``exp(5.75 - 1.15 Tp / sqrt(Hs))``
    up to 5, then 1."""
    hs = 2.0
    assert jonswap_gamma_dnv(hs, ratio * math.sqrt(hs)) == pytest.approx(gamma, rel=1e-12)


def test_jonswap_zero_for_nonpositive_frequency_and_scales_with_hs_squared():
    w = np.array([-1.0, 0.0, 0.8, 1.2])
    s1 = jonswap_spectrum(w, 1.0, 6.0)
    assert s1[0] == 0.0 and s1[1] == 0.0
    np.testing.assert_allclose(jonswap_spectrum(w, 2.0, 6.0), 4.0 * s1)


@pytest.mark.parametrize("kwargs, field", [(dict(hs_m=-1.0, tp_s=6.0), "hs_m"), (dict(hs_m=1.0, tp_s=0.0), "tp_s"),
                                           (dict(hs_m=1.0, tp_s=6.0, gamma=0.5), "gamma")])
def test_jonswap_validation_names_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        jonswap_spectrum(1.0, **kwargs)


# --------------------------------------------------------------------------- wave components


def test_components_deterministic_for_seed_and_differ_between_seeds():
    a = make_wave_components(1.0, 6.0, 0.3, rng=7)
    b = make_wave_components(1.0, 6.0, 0.3, rng=np.random.default_rng(7))
    c = make_wave_components(1.0, 6.0, 0.3, rng=8)
    np.testing.assert_array_equal(a.omega_rad_s, b.omega_rad_s)
    np.testing.assert_array_equal(a.phase_rad, b.phase_rad)
    assert not np.allclose(a.phase_rad, c.phase_rad)
    assert not np.allclose(a.omega_rad_s, c.omega_rad_s)


def test_rng_none_is_refused():
    with pytest.raises(TypeError, match="rng"):
        make_wave_components(1.0, 6.0, 0.0, rng=None)


def test_a_negative_seed_is_refused_naming_rng():
    """A seed below 0 failed in numpy's words ('expected non-negative integer'), naming no argument."""
    with pytest.raises(ValueError, match="^rng: expected a whole number >= 0, got -1"):
        make_wave_components(1.0, 6.0, 0.0, rng=-1)
    with pytest.raises(ValueError, match="^rng: "):
        SeaState.random(np.int64(-3))


@pytest.mark.parametrize("method", ["jittered", "equal_energy"])
def test_components_reproduce_hs_and_are_not_periodic(method):
    wf = make_wave_components(1.3, 7.0, 1.0, rng=3, n_components=50, method=method)
    assert wf.n_components == 50
    assert wf.hs_discrete_m == pytest.approx(1.3, rel=1e-12)
    if method == "jittered":
        # A_j = sqrt(2 S(omega_j) d_omega_j) up to one Hs-normalisation factor close to 1.
        ratio = wf.amplitude_m**2 / (2.0 * jonswap_spectrum(wf.omega_rad_s, 1.3, 7.0) * wf.d_omega_rad_s)
        np.testing.assert_allclose(ratio, ratio[0], rtol=1e-10)
        assert ratio[0] == pytest.approx(1.0, abs=0.1)
    spacing = np.diff(np.sort(wf.omega_rad_s))
    assert spacing.std() > 0.05 * spacing.mean()      # not a regular grid
    # Elevation of a 3 h record: 4 * std = Hs.
    t = np.arange(0.0, 3 * 3600.0, 0.5)
    assert 4.0 * wf.elevation(t).std() == pytest.approx(1.3, rel=0.05)


def test_the_batched_spectrum_is_the_scalar_one_per_row():
    """The one JONSWAP kernel, given a peak period per row (and frequencies at or below 0),
    gives each row the public scalar function's values: the batch uses the same formula."""
    tp = np.array([1.0, 4.4, 9.0, 17.0, 30.0])
    w = np.outer(2.0 * np.pi / tp, np.linspace(-0.5, 4.0, 46))          # each row around its own peak
    batch = _jonswap(w, 1.0, tp[:, None], 3.3)
    in_band = w >= 0.5 * (2.0 * np.pi / tp)[:, None]
    assert batch.shape == w.shape and np.all(batch[w <= 0.0] == 0.0) and np.all(batch[in_band] > 0.0)
    for i in range(tp.size):
        np.testing.assert_allclose(batch[i], jonswap_spectrum(w[i], 1.0, tp[i], 3.3), rtol=1e-13, atol=0.0)
    # and Hs and gamma broadcast too
    np.testing.assert_allclose(_jonswap(w[2], np.array([[0.5], [2.0]]), tp[2], np.array([[1.0], [7.0]])),
                               [jonswap_spectrum(w[2], 0.5, tp[2], 1.0), jonswap_spectrum(w[2], 2.0, tp[2], 7.0)],
                               rtol=1e-13, atol=0.0)


@pytest.mark.parametrize("normalize_hs", [True, False])
def test_batched_jittered_seas_are_make_wave_components_seas_for_the_same_jitter(normalize_hs):
    """Seas built at once (each its own Hs and Tp, a calm among them) equal those of
    make_wave_components one by one, given the jitter each seed draws: frequencies and bin
    widths bit for bit, amplitudes to rounding (a power of an array may differ in the last bit
    from that of a scalar)."""
    hs = np.array([1.3, 0.0, 4.0, 0.2, 2.5])
    tp = np.array([7.0, 6.0, 11.5, 2.2, 16.0])
    n = 24
    u = np.stack([np.random.default_rng(10 + i).uniform(0.0, 1.0, n) for i in range(hs.size)])
    omega, d_omega, amp = _jittered_components(hs, tp, 3.3, u, (0.5, 3.5), normalize_hs)
    assert omega.shape == d_omega.shape == amp.shape == (hs.size, n)
    for i in range(hs.size):
        wf = make_wave_components(hs[i], tp[i], 0.0, 10 + i, n, normalize_hs=normalize_hs)
        np.testing.assert_array_equal(omega[i], wf.omega_rad_s)
        np.testing.assert_array_equal(d_omega[i], wf.d_omega_rad_s)
        np.testing.assert_allclose(amp[i], wf.amplitude_m, rtol=1e-12, atol=0.0)
    assert np.all(amp[1] == 0.0) and np.all(amp[[0, 2, 3, 4]] > 0.0)
    hs_components = 4.0 * np.sqrt(0.5 * np.sum(amp**2, axis=1))
    if normalize_hs:
        np.testing.assert_allclose(hs_components, hs, rtol=1e-13, atol=0.0)
    else:       # about Hs (24 jittered frequencies), not exactly
        assert np.all(np.abs(hs_components - hs) <= 0.1 * hs) and np.all(np.abs(hs_components - hs)[hs > 0] > 1e-6)


@pytest.mark.parametrize("method", ["jittered", "equal_energy"])
def test_components_stay_in_the_requested_band(method):
    """``omega_range_factor=(0.8, 2.0)`` at Tp = 2 pi s (omega_p = 1 rad/s): the bins tile
    [0.8, 2.0] rad/s (widths summing to 1.2 rad/s) and every frequency lies in it."""
    wf = make_wave_components(1.0, 2.0 * np.pi, 0.0, rng=4, n_components=30, method=method,
                              omega_range_factor=(0.8, 2.0))
    assert np.sum(wf.d_omega_rad_s) == pytest.approx(1.2, rel=1e-12)
    assert 0.8 <= wf.omega_rad_s.min() and wf.omega_rad_s.max() <= 2.0


def test_equal_energy_components_have_equal_amplitudes():
    wf = make_wave_components(1.0, 6.0, 0.0, rng=1, method="equal_energy")
    np.testing.assert_allclose(wf.amplitude_m, wf.amplitude_m[0])


def test_equal_energy_bins_hold_equal_shares_of_the_spectrum():
    """The bins tile ``[0.5, 3.5] omega_p`` [rad/s], each frequency lies in its own bin, and
    the JONSWAP area (gamma 5) over every bin (quad) is the same ``m0 / n``."""
    tp, n = 6.0, 20
    wp = 2.0 * np.pi / tp
    wf = make_wave_components(1.0, tp, 0.0, rng=1, n_components=n, method="equal_energy", gamma=5.0)
    edges = 0.5 * wp + np.concatenate([[0.0], np.cumsum(wf.d_omega_rad_s)])
    assert edges[-1] == pytest.approx(3.5 * wp, rel=1e-12)
    assert np.all((edges[:-1] <= wf.omega_rad_s) & (wf.omega_rad_s <= edges[1:]))
    share = [quad(lambda w: float(jonswap_spectrum(w, 1.0, tp, 5.0)), a, b)[0] for a, b in zip(edges[:-1], edges[1:])]
    np.testing.assert_allclose(share, np.sum(share) / n, rtol=1e-3)


def test_long_crested_and_spread_directions():
    lc = make_wave_components(1.0, 6.0, 0.5, rng=2)
    np.testing.assert_allclose(lc.dir_from_rad, 0.5)
    sp = make_wave_components(1.0, 6.0, 0.5, rng=2, spreading=2.0)
    dev = np.angle(np.exp(1j * (sp.dir_from_rad - 0.5)))
    assert np.all(np.abs(dev) <= np.pi / 2 + 1e-12)
    assert dev.std() > math.radians(10)


@pytest.mark.parametrize("n_exp", [2.0, 6.0])
def test_spread_directions_follow_the_cos_power_distribution(n_exp):
    """With spreading ``n`` the directions' deviations from the mean [rad] have the density
    ``cos^n(theta)`` on ``[-pi/2, pi/2]`` (DNV-RP-C205 3.5.8): Kolmogorov-Smirnov against its
    distribution function, integrated here with quad, for 2000 components."""
    wf = make_wave_components(1.0, 6.0, 0.5, rng=2, n_components=2000, spreading=n_exp)
    dev = np.angle(np.exp(1j * (wf.dir_from_rad - 0.5)))
    total = quad(lambda a: math.cos(a) ** n_exp, -0.5 * np.pi, 0.5 * np.pi)[0]

    def cdf(theta_rad):
        return np.array([quad(lambda a: math.cos(a) ** n_exp, -0.5 * np.pi, th)[0] / total
                         for th in np.clip(np.atleast_1d(theta_rad), -0.5 * np.pi, 0.5 * np.pi)])

    assert kstest(dev, cdf).pvalue > 0.01


def test_waves_propagate_away_from_where_they_come_from():
    # A single component from the north: a crest observed at the origin reaches a point
    # 10 m south later (it travels with the phase speed g / omega).
    w = 1.0
    wf = WaveField(omega_rad_s=[w], amplitude_m=[1.0], phase_rad=[0.0], dir_from_rad=[0.0])
    c = G / w
    t = np.array([10.0 / c])
    assert wf.elevation(t, position_ne_m=[[-10.0, 0.0]])[0] == pytest.approx(1.0)


@pytest.mark.parametrize("dir_from_deg", [90.0, 143.0, -115.0])
def test_a_crest_travels_away_from_any_direction_it_comes_from(dir_from_deg):
    """A 1 rad/s component from ``dir_from_deg``: the crest at the origin at t = 0 is 10 m
    downwave (towards ``dir_from + 180 deg``) 10 m / c later, c = g / omega [m/s], and at
    once 10 m across its direction, on the same crest line."""
    chi = np.radians(dir_from_deg)
    wf = WaveField(omega_rad_s=[1.0], amplitude_m=[1.0], phase_rad=[0.0], dir_from_rad=[chi])
    downwave = speed_dir_to_vector([10.0, chi + np.pi])               # [north_m, east_m]
    across = speed_dir_to_vector([10.0, chi + 0.5 * np.pi])
    assert wf.elevation([10.0 / G], position_ne_m=[downwave])[0] == pytest.approx(1.0, abs=1e-9)
    assert wf.elevation([0.0], position_ne_m=[across])[0] == pytest.approx(1.0, abs=1e-9)


def test_wavefield_validation_names_field():
    with pytest.raises(ValueError, match="amplitude_m"):
        WaveField(omega_rad_s=[1.0], amplitude_m=[-1.0], phase_rad=[0.0], dir_from_rad=[0.0])
    with pytest.raises(ValueError, match="phase_rad"):
        WaveField(omega_rad_s=[1.0, 2.0], amplitude_m=[1.0, 1.0], phase_rad=[0.0], dir_from_rad=[0.0, 0.0])
    with pytest.raises(ValueError, match="omega_rad_s"):
        WaveField(omega_rad_s=[0.0], amplitude_m=[1.0], phase_rad=[0.0], dir_from_rad=[0.0])


# --------------------------------------------------------------------------- wave drift


def test_beam_sea_mean_sway_drift_is_kilonewtons_and_pushes_to_starboard():
    # Hs 1 m, Tp 6 s from the west, heading north: waves from port.
    wf = make_wave_components(1.0, 6.0, 1.5 * np.pi, rng=11)
    x, y, n = mean_drift_loads(0.0, wf, GUNNERUS)
    assert 1e3 < y < 1e4
    assert abs(x) < 1e-6 * y and abs(n) < 1e-6 * y * 33.9
    # Time mean of the slowly varying force matches.
    t = np.arange(0.0, 3 * 3600.0, 1.0)
    f = wave_drift_loads(t, 0.0, wf, GUNNERUS)
    assert f[:, 1].mean() == pytest.approx(y, rel=0.1)


def test_head_seas_push_aft_and_following_seas_push_forward():
    wf_head = make_wave_components(1.0, 6.0, 0.7, rng=4)                # from 0.7 rad, heading 0.7
    x, y, _ = mean_drift_loads(0.7, wf_head, GUNNERUS)
    assert x < 0.0 and abs(y) < 1e-6 * abs(x)
    wf_follow = make_wave_components(1.0, 6.0, 0.7 + np.pi, rng=4)
    assert mean_drift_loads(0.7, wf_follow, GUNNERUS)[0] > 0.0


def test_waves_from_starboard_push_to_port():
    wf = make_wave_components(1.0, 6.0, np.pi / 2, rng=5)               # from the east, heading north
    assert mean_drift_loads(0.0, wf, GUNNERUS)[1] < 0.0


@pytest.mark.parametrize("beta", [np.radians(-45), np.radians(-135), np.radians(45), np.radians(135)])
def test_drift_yaw_moment_turns_the_ship_beam_on(beta):
    # A positive moment increases psi, i.e. decreases beta = chi - psi; beam-on is |beta| = pi/2.
    n = drift_coefficients(1.0, beta, GUNNERUS)[2]
    dbeta = -np.sign(n)
    assert abs(abs(beta + 0.01 * dbeta) - np.pi / 2) < abs(abs(beta) - np.pi / 2)


def test_drift_coefficient_limits():
    # Short waves: wall reflection 0.5 rho g L c_y (beam) and 0.5 rho g B c_x (head).
    h = HullDimensions(**GUNNERUS)
    d = drift_coefficients(20.0, FROM_PORT, h)
    assert d[1] == pytest.approx(0.5 * RHO * G * h.side_factor * 33.9, rel=1e-3)
    d = drift_coefficients(20.0, HEAD, h)
    assert d[0] == pytest.approx(-0.5 * RHO * G * h.bow_factor * 9.6, rel=1e-3)
    # Long waves are not reflected.
    assert np.all(np.abs(drift_coefficients(0.05, np.linspace(-3, 3, 7), h)) < 1e-3 * 0.5 * RHO * G * 33.9)


def test_short_wave_drift_at_60_deg_off_the_bow_by_hand():
    """Short waves 60 deg off the port bow (beta = -60 deg): the wall values scale with the
    squares ``cos^2 60 = 1/4`` (surge, pushing aft) and ``sin^2 60 = 3/4`` (sway, to
    starboard), and the sway force acts ``c_n L cos 60 = 0.2 * 33.9 m / 2 = 3.39 m`` forward."""
    wall = 0.5 * RHO * G                                                # [N/m^3]
    d = drift_coefficients(20.0, np.radians(-60.0), GUNNERUS)
    assert d[0] == pytest.approx(-wall * 0.6 * 9.6 * 0.25, rel=1e-3)
    assert d[1] == pytest.approx(wall * 33.9 * 0.75, rel=1e-3)
    assert d[2] == pytest.approx(3.39 * d[1], rel=1e-9)


def test_drift_coefficient_between_the_limits_follows_the_energy_flux_above_the_keel():
    """At ``2 k T = 1`` (half-way between the limits) the beam-sea coefficient is the wall value
    ``(rho g / 2) c_y L`` times the flux share above the keel ``1 - e^-2kT`` and ``(kB)^2 / (1 + (kB)^2)``."""
    h = HullDimensions(**GUNNERUS)
    k = 1.0 / (2.0 * h.T_m)
    d = drift_coefficients(math.sqrt(k * G), FROM_PORT, h)
    kb2 = (k * h.B_m) ** 2
    assert d[1] == pytest.approx(0.5 * RHO * G * h.side_factor * h.L_m * (1.0 - math.exp(-1.0)) * kb2 / (1 + kb2),
                                 rel=1e-9)


def test_mean_drift_scales_with_hs_squared():
    a = mean_drift_loads(0.0, make_wave_components(0.5, 6.0, -1.0, rng=1), GUNNERUS)
    b = mean_drift_loads(0.0, make_wave_components(1.5, 6.0, -1.0, rng=1), GUNNERUS)
    np.testing.assert_allclose(b, 9.0 * a, rtol=1e-12)


@pytest.mark.parametrize("newman", ["geometric", "arithmetic"])
def test_newman_time_mean_equals_sum_of_mean_drift_exactly(newman):
    # Frequencies on an exact grid j * d_omega: over one period 2 pi / d_omega all
    # difference-frequency terms average to zero, leaving sum_j A_j^2 D_j.
    rng = np.random.default_rng(0)
    period = 200.0
    j = np.arange(12, 45)
    wf = WaveField(omega_rad_s=j * 2 * np.pi / period, amplitude_m=rng.uniform(0.05, 0.2, j.size),
                   phase_rad=rng.uniform(0, 2 * np.pi, j.size), dir_from_rad=np.full(j.size, 2.0))
    t = np.linspace(0.0, period, 4000, endpoint=False)
    f = wave_drift_loads(t, 0.9, wf, GUNNERUS, newman=newman)
    np.testing.assert_allclose(f.mean(axis=0), mean_drift_loads(0.9, wf, GUNNERUS), rtol=1e-9)


def test_geometric_newman_force_is_one_signed_and_slowly_varying_around_mean():
    wf = make_wave_components(1.0, 6.0, -np.pi / 2, rng=9)
    t = np.arange(0.0, 3600.0, 0.5)
    y = wave_drift_loads(t, 0.0, wf, GUNNERUS)[:, 1]
    assert y.min() >= 0.0
    # Long-crested Newman drift is exponentially distributed: std ~ mean.
    assert y.std() == pytest.approx(y.mean(), rel=0.25)


def test_drift_loads_heading_per_time_matches_scalar_and_validates():
    wf = make_wave_components(1.0, 6.0, 1.0, rng=2)
    t = np.arange(0.0, 300.0, 1.0)
    np.testing.assert_allclose(wave_drift_loads(t, 0.4, wf, GUNNERUS),
                               wave_drift_loads(t, np.full(t.size, 0.4), wf, GUNNERUS))
    with pytest.raises(ValueError, match="psi_rad"):
        wave_drift_loads(t, np.zeros(3), wf, GUNNERUS)
    with pytest.raises(ValueError, match="T_m"):
        wave_drift_loads(t, 0.0, wf, dict(L_m=33.9, B_m=9.6))
    with pytest.raises(ValueError, match="B_m"):
        wave_drift_loads(t, 0.0, wf, dict(L_m=33.9, B_m=-9.6, T_m=2.5))
    with pytest.raises(ValueError, match="unknown"):
        wave_drift_loads(t, 0.0, wf, dict(L_m=33.9, B_m=9.6, T_m=2.5, draft=3.0))


def test_drift_loads_heading_change_rotates_the_force():
    # Turning the ship from head seas to beam seas moves the drift from -x to +-y.
    wf = make_wave_components(1.0, 6.0, 0.0, rng=2)
    psi = np.array([0.0, np.pi / 2])
    m = mean_drift_loads(psi, wf, GUNNERUS)
    assert m[0, 0] < 0 and abs(m[0, 1]) < 1e-9
    assert m[1, 1] > 0 and abs(m[1, 0]) < 1e-9        # heading east, waves from north = from port


# --------------------------------------------------------------------------- wave-frequency motion


def test_wf_motion_magnitudes_for_hs_1m():
    wf = make_wave_components(1.0, 6.0, np.radians(45), rng=21)        # bow-quartering from starboard
    t = np.arange(0.0, 3 * 3600.0, 0.5)
    off = wave_frequency_motion(t, 0.0, wf, MotionRAOs.from_hull(GUNNERUS))
    yaw_std_deg = np.degrees(off[:, 2].std())
    assert 0.05 < yaw_std_deg < 1.0
    pos_std = off[:, :2].std(axis=0)
    assert np.all((0.02 < pos_std) & (pos_std < 0.5))                  # decimetres
    assert np.all(np.abs(off.mean(axis=0)) < 0.05 * off.std(axis=0))   # zero-mean


def test_wf_motion_head_seas_only_surge_and_long_waves_follow_particles():
    wf = make_wave_components(1.0, 6.0, 0.0, rng=1)
    t = np.arange(0.0, 600.0, 0.5)
    off = wave_frequency_motion(t, 0.0, wf, GUNNERUS)
    assert off[:, 0].std() > 0.01
    np.testing.assert_allclose(off[:, 1:], 0.0, atol=1e-12)
    rao = MotionRAOs.from_hull(GUNNERUS).amplitudes(1e-3, [HEAD, FROM_PORT, np.radians(30)])
    np.testing.assert_allclose(rao[:, 0], [-1.0, 0.0, -math.cos(math.radians(30))], atol=1e-4)
    np.testing.assert_allclose(rao[:, 1], [0.0, 1.0, -0.5], atol=1e-4)
    np.testing.assert_allclose(rao[:, 2], 0.0, atol=1e-6)


@pytest.mark.parametrize("psi_deg", [60.0, 135.0, -100.0])
def test_wf_motion_of_long_crested_waves_is_along_their_direction_at_any_heading(psi_deg):
    """The hull follows the water's orbital motion, which is along the wave direction in NED
    whatever the heading (surge and sway share one RAO envelope): waves from the north move
    the ship north-south only."""
    wf = make_wave_components(1.0, 6.0, 0.0, rng=3)
    off = wave_frequency_motion(np.arange(0.0, 300.0, 0.5), np.radians(psi_deg), wf, GUNNERUS)
    assert off[:, 0].std() > 0.01
    np.testing.assert_allclose(off[:, 1], 0.0, atol=1e-9)


def test_wf_yaw_rao_peaks_at_the_documented_value_for_waves_as_long_as_the_ship():
    """``psi / A = -yaw_gain k sin(2 beta) H(k L)`` with ``H = 1`` at ``lambda = L``: bow-quartering
    seas from starboard (beta = 45 deg) give ``-yaw_gain k`` rad/m."""
    raos = MotionRAOs.from_hull(GUNNERUS)
    k = 2.0 * np.pi / GUNNERUS["L_m"]
    rao = raos.amplitudes(math.sqrt(k * G), np.radians(45.0))
    assert rao[2] == pytest.approx(-raos.yaw_gain * k, rel=1e-9)


def test_wf_surge_and_sway_raos_for_waves_as_long_as_the_ship_by_hand():
    """At ``lambda = L`` (k L = 2 pi) the envelope ``exp(-k T / 2) / sqrt(1 + (k l / 2)^2)`` has
    ``k T / 2 = pi T / L`` and ``k l / 2 = pi`` in head seas (l = L), ``pi B / L`` in beam seas
    (l = B); sway gain 0.5 halves the beam-sea RAO (waves from port move the hull to starboard)."""
    k = 2.0 * np.pi / GUNNERUS["L_m"]
    depth = math.exp(-math.pi * 2.5 / 33.9)
    raos = MotionRAOs.from_hull(GUNNERUS, sway_gain=0.5).amplitudes(math.sqrt(k * G), [HEAD, FROM_PORT])
    assert raos[0, 0] == pytest.approx(-depth / math.sqrt(1.0 + math.pi**2), rel=1e-9)
    assert raos[1, 1] == pytest.approx(0.5 * depth / math.sqrt(1.0 + (math.pi * 9.6 / 33.9) ** 2), rel=1e-9)


def test_wf_rates_are_time_derivatives_of_offsets():
    wf = make_wave_components(1.0, 6.0, 2.0, rng=1)
    t = np.arange(0.0, 200.0, 0.01)
    off, rate = wave_frequency_motion(t, 0.3, wf, dict(L_m=33.9, B_m=9.6, T_m=2.5), return_rates=True)
    num = np.gradient(off, t, axis=0)
    for col in range(3):
        np.testing.assert_allclose(rate[1:-1, col], num[1:-1, col], atol=2e-3 * np.abs(rate[:, col]).max())


def test_long_records_are_evaluated_at_every_sample_across_memory_blocks(monkeypatch):
    """With memory blocks of 1000 elements (20 samples of 50 components), 107 samples span
    six blocks, the last one short: elevation equals the sum ``sum A cos(omega t + k x . d +
    eps)`` written out, and drift loads and wave-frequency motion along a turning, moving track
    equal those of each sample alone."""
    monkeypatch.setattr(environment, "_BLOCK_ELEMENTS", 1000)
    wf = make_wave_components(1.0, 6.0, 0.4, rng=6, spreading=2.0)
    t = np.arange(107) * 0.5                                            # [s]
    psi = 0.3 + 0.01 * t                                                # [rad]
    pos = np.column_stack([0.3 * t, -0.2 * t])                         # [north_m, east_m]
    k = wf.omega_rad_s**2 / G                                           # [rad/m]
    along = k * (np.outer(pos[:, 0], np.cos(wf.dir_from_rad)) + np.outer(pos[:, 1], np.sin(wf.dir_from_rad)))
    direct = np.cos(np.outer(t, wf.omega_rad_s) + along + wf.phase_rad) @ wf.amplitude_m
    np.testing.assert_allclose(wf.elevation(t, position_ne_m=pos), direct, rtol=0.0, atol=1e-12)
    drift = wave_drift_loads(t, psi, wf, GUNNERUS, position_ne_m=pos)
    motion = wave_frequency_motion(t, psi, wf, GUNNERUS, position_ne_m=pos)
    for i in range(t.size):
        one = slice(i, i + 1)
        np.testing.assert_allclose(drift[i],
                                   wave_drift_loads(t[one], psi[one], wf, GUNNERUS, position_ne_m=pos[one])[0],
                                   rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(motion[i],
                                   wave_frequency_motion(t[one], psi[one], wf, GUNNERUS, position_ne_m=pos[one])[0],
                                   rtol=1e-12, atol=1e-14)


# --------------------------------------------------------------------------- wind


def test_harris_variance_and_davenport_shape():
    u, kappa = 10.0, 0.0026
    var, _ = quad(lambda f: harris_spectrum(f, u, kappa), 0.0, np.inf, limit=500)
    assert var == pytest.approx(6.68 * kappa * u**2, rel=0.01)
    f = np.geomspace(1e-4, 1.0, 1000)
    # f S(f) ~ x^2 / (1 + x^2)^(4/3) peaks at x = f L / U = sqrt(3).
    assert f[np.argmax(f * davenport_spectrum(f, u))] == pytest.approx(math.sqrt(3.0) * u / 1200.0, rel=0.02)


def test_harris_spectrum_has_the_1800_m_length_scale_of_its_formula():
    """``S(f) = 4 kappa U L / (2 + (f L / U)^2)^(5/6)``, L = 1800 m: its low-frequency plateau
    ``4 kappa U L / 2^(5/6)`` and the value at ``f L / U = sqrt(2)`` pin L and the 2 of the
    denominator (the variance, ``6.68 kappa U^2``, does not depend on L)."""
    u, kappa, length = 10.0, 0.0026, 1800.0
    s = harris_spectrum(np.array([1e-9, math.sqrt(2.0) * u / length]), u, kappa)
    np.testing.assert_allclose(s, 4.0 * kappa * u * length / np.array([2.0, 4.0]) ** (5.0 / 6.0), rtol=1e-6)


def test_davenport_variance_is_six_kappa_u_squared():
    """``int S df = 4 kappa U^2 int_0^inf x (1 + x^2)^(-4/3) dx = 4 kappa U^2 * 3/2`` (x = f L / U)."""
    u, kappa = 10.0, 0.0026
    var, _ = quad(lambda f: davenport_spectrum(f, u, kappa), 0.0, np.inf, limit=500)
    assert var == pytest.approx(6.0 * kappa * u**2, rel=1e-3)


@pytest.mark.parametrize("spectrum", ["harris", "davenport"])
def test_gust_mean_and_intensity_match_request(spectrum):
    t = np.arange(0.0, 3600.0, 1.0)
    intensities, means = [], []
    for seed in range(5):
        speed, direction = gust_wind(t, 9.0, np.radians(250), seed, intensity=0.12, spectrum=spectrum)
        assert speed.shape == direction.shape == t.shape
        assert np.all(speed >= 0) and np.all((direction >= 0) & (direction < 2 * np.pi))
        means.append(speed.mean())
        intensities.append(speed.std() / 9.0)
        wander = np.angle(np.exp(1j * (direction - np.radians(250))))
        assert 0.1 < np.degrees(wander.std()) < 10.0                   # a few degrees
    assert np.all(np.abs(np.array(means) / 9.0 - 1.0) < 0.03)
    assert np.all(np.abs(np.array(intensities) / 0.12 - 1.0) < 0.15)
    assert np.mean(intensities) == pytest.approx(0.12, rel=0.05)


def test_gusts_carry_energy_down_to_the_record_length():
    """Gust frequencies start at ``1 / duration``: the variance left after a 10 min moving average is
    the Harris spectrum's share through that filter, ``int S sinc^2(f W) df / int S df`` over
    ``[1 / T, 0.5 Hz]`` (about 4 %; random records scatter around it, so half of it is required)."""
    duration, u, intensity, window = 3600.0, 9.0, 0.12, 600
    t = np.arange(0.0, duration, 1.0)

    def share(weight):
        return quad(lambda f: harris_spectrum(f, u) * weight(f), 1.0 / duration, 0.5, limit=500)[0]

    expected = share(lambda f: np.sinc(f * window) ** 2) / share(lambda f: 1.0)
    got = []
    for seed in range(6):
        speed, _ = gust_wind(t, u, 0.0, seed, intensity=intensity)
        slow = np.convolve(speed - speed.mean(), np.ones(window) / window, "valid")
        got.append(slow.var() / (intensity * u) ** 2)
    assert 0.5 * expected < np.mean(got) < 1.5 * expected


def test_gusts_of_a_long_record_are_one_series_across_memory_blocks(monkeypatch):
    """Evaluated in blocks of 5 samples (1000 elements of 200 harmonics), the gust speed [m/s]
    of a seed is that of one block: every harmonic keeps its phase from the record's start."""
    t = np.arange(0.0, 600.0, 1.0) + 1000.0
    whole, _ = gust_wind(t, 8.0, 1.0, 42)
    monkeypatch.setattr(environment, "_BLOCK_ELEMENTS", 1000)
    np.testing.assert_allclose(gust_wind(t, 8.0, 1.0, 42)[0], whole, rtol=1e-12, atol=0.0)


def test_gust_deterministic_and_seed_dependent():
    t = np.arange(0.0, 600.0, 0.5)
    a = gust_wind(t, 8.0, 1.0, 42)
    b = gust_wind(t, 8.0, 1.0, np.random.default_rng(42))
    c = gust_wind(t, 8.0, 1.0, 43)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.allclose(a[0], c[0])


def test_gust_direction_wanders_with_the_requested_spread_and_time_constant():
    """The direction's wander is Gauss-Markov: standard deviation ``dir_std_rad`` (0.1 rad here,
    not the 3 deg default) and lag-``dir_tau_s`` autocorrelation ``e^-1`` (120 s, not 300 s)."""
    t = np.arange(0.0, 200_000.0, 10.0)
    _, direction = gust_wind(t, 8.0, 1.0, 3, dir_std_rad=0.1, dir_tau_s=120.0)
    wander = np.angle(np.exp(1j * (direction - 1.0)))                  # [rad]
    assert wander.std() == pytest.approx(0.1, rel=0.1)
    lag = 12                                                            # 120 s
    assert np.corrcoef(wander[:-lag], wander[lag:])[0, 1] == pytest.approx(math.exp(-1.0), abs=0.05)


def test_gust_zero_intensity_is_steady_and_validation():
    t = np.arange(0.0, 100.0, 1.0)
    speed, direction = gust_wind(t, 6.0, 0.0, 1, intensity=0.0, dir_std_rad=0.0)
    np.testing.assert_allclose(speed, 6.0)
    np.testing.assert_array_equal(direction, 0.0)
    with pytest.raises(ValueError, match="mean_speed_m_s"):
        gust_wind(t, -1.0, 0.0, 1)
    with pytest.raises(ValueError, match="intensity"):
        gust_wind(t, 5.0, 0.0, 1, intensity=-0.1)
    with pytest.raises(ValueError, match="time_s"):
        gust_wind(t[::-1], 5.0, 0.0, 1)


@pytest.mark.parametrize("call", [
    lambda c: wave_drift_loads([0.0, 1.0], 0.0, c, GUNNERUS_HULL),
    lambda c: environment.mean_drift_loads(0.0, c, GUNNERUS_HULL),
    lambda c: wave_frequency_motion([0.0, 1.0], 0.0, c, GUNNERUS_HULL),
], ids=["wave_drift_loads", "mean_drift_loads", "wave_frequency_motion"])
def test_wave_components_that_are_not_a_wave_field_are_refused_naming_them(call):
    """Components given as something else (a sea state, a list) failed with an AttributeError
    ("'SeaState' object has no attribute 'amplitude_m'"); a TypeError now names components."""
    sea = SeaState(hs_m=1.0, tp_s=6.0, wave_dir_from_rad=0.0, wind_speed_m_s=5.0, wind_dir_from_rad=0.0)
    for bad in (sea, [1.0, 2.0]):
        with pytest.raises(TypeError, match="^components: expected an instance of WaveField"):
            call(bad)
    assert np.all(np.isfinite(call(sea.wave_components(1))))


def test_arrays_that_do_not_broadcast_are_refused_naming_them():
    """Frequencies and angles (or current speeds and directions) of shapes that do not broadcast
    failed in numpy's words ('shape mismatch', 'operands could not be broadcast'), naming neither."""
    for call, names in ((lambda: drift_coefficients([0.5, 1.0], [0.0, 1.0, 2.0], GUNNERUS_HULL),
                         "omega_rad_s and beta_rad"),
                        (lambda: MotionRAOs.from_hull(GUNNERUS_HULL).amplitudes([0.5, 1.0], [0.0, 1.0, 2.0]),
                         "omega_rad_s and beta_rad"),
                        (lambda: environment.current_velocity_ned([0.2, 0.3], [0.0, 1.0, 2.0]),
                         "speed_m_s and dir_to_rad")):
        with pytest.raises(ValueError, match=f"^{names}: shapes that do not broadcast together"):
            call()
    np.testing.assert_allclose(environment.current_velocity_ned([0.2, 0.3], 0.0), [[0.2, 0.0], [0.3, 0.0]])


def test_gust_frequencies_stay_within_f_max_and_nyquist(monkeypatch):
    """The gusts' frequencies lie between 1 / duration and min(f_max_hz, Nyquist), as documented:
    the band was widened to 2 / duration, so a low f_max_hz got gusts above it and a short record
    gusts beyond its Nyquist frequency (aliased). A band that holds no frequency is refused by name."""
    seen, harris = [], environment.harris_spectrum

    def spy(f_hz, *args, **kwargs):         # the gust frequencies, as gust_wind asks the spectrum for them
        seen.append(np.asarray(f_hz, float).copy())
        return harris(f_hz, *args, **kwargs)

    monkeypatch.setattr(environment, "harris_spectrum", spy)
    t = np.arange(0.0, 600.0)
    gust_wind(t, 8.0, 0.0, 1, f_max_hz=0.0025)              # 1 / duration = 0.00167 Hz
    assert seen[-1].min() >= 1.0 / 599.0 and seen[-1].max() <= 0.0025
    gust_wind(np.arange(5.0), 8.0, 0.0, 1)                 # 4 s: 0.25 .. 0.5 Hz
    assert seen[-1].max() <= 0.5
    with pytest.raises(ValueError, match="^f_max_hz: 0.0001 Hz is not above"):
        gust_wind(t, 8.0, 0.0, 1, f_max_hz=1e-4)
    with pytest.raises(ValueError, match="^time_s: 3 samples over 2 s hold no gust frequency"):
        gust_wind(np.arange(3.0), 8.0, 0.0, 1)


# --------------------------------------------------------------------------- current


def test_current_statistics_and_non_negative_speed():
    t = np.arange(0.0, 20 * 3600.0, 2.0)
    speed, direction = current_series(t, 0.3, np.radians(80), 3, speed_var=0.1, dir_var_rad=np.radians(5), tau_s=600)
    assert speed.mean() == pytest.approx(0.3, rel=0.03)
    assert speed.std() / 0.3 == pytest.approx(0.1, rel=0.2)
    assert np.degrees(np.angle(np.exp(1j * (direction - np.radians(80)))).std()) == pytest.approx(5.0, rel=0.2)
    # Large relative variation: speed is clipped at zero, never negative.
    s2, _ = current_series(t[:5000], 0.05, 0.0, 4, speed_var=0.9)
    assert np.all(s2 >= 0.0)


def test_current_correlation_time_and_velocity_components():
    # Lag-tau autocorrelation of a first-order Gauss-Markov process is exp(-1).
    x = _gauss_markov(np.arange(0.0, 200_000.0, 10.0), 1.0, 600.0, np.random.default_rng(0))
    lag = 60
    rho = np.corrcoef(x[:-lag], x[lag:])[0, 1]
    assert rho == pytest.approx(math.exp(-1.0), abs=0.05)
    # and the current itself: its speed and direction wander with tau_s
    speed, direction = current_series(np.arange(0.0, 200_000.0, 10.0), 1.0, 0.0, np.random.default_rng(1),
                                      speed_var=0.1, dir_var_rad=0.1, tau_s=600.0)
    for series in (speed, np.angle(np.exp(1j * direction))):
        assert np.corrcoef(series[:-lag], series[lag:])[0, 1] == pytest.approx(math.exp(-1.0), abs=0.05)
    np.testing.assert_allclose(current_velocity_ned(2.0, np.pi / 2), [0.0, 2.0], atol=1e-12)  # flowing east
    np.testing.assert_allclose(current_velocity_ned(2.0, np.radians(210.0)), [-math.sqrt(3.0), -1.0], atol=1e-12)


def test_gauss_markov_nonuniform_grid_matches_recursion():
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.uniform(0.1, 40.0, 3000))
    sigma, tau = 0.7, 25.0
    x = _gauss_markov(t, sigma, tau, np.random.default_rng(1))
    z = np.random.default_rng(1).standard_normal(t.size)
    ref = np.empty(t.size)
    ref[0] = sigma * z[0]
    for k in range(1, t.size):
        a = math.exp(-(t[k] - t[k - 1]) / tau)
        ref[k] = a * ref[k - 1] + sigma * math.sqrt(1 - a * a) * z[k]
    np.testing.assert_allclose(x, ref, rtol=1e-9, atol=1e-12)
    tu = np.arange(0.0, 500.0, 0.5)
    np.testing.assert_allclose(_gauss_markov(tu, sigma, tau, np.random.default_rng(2), method="lfilter"),
                               _gauss_markov(tu, sigma, tau, np.random.default_rng(2), method="blocks"), atol=1e-12)


def test_current_deterministic_and_seed_dependent():
    t = np.arange(0.0, 3600.0, 1.0)
    a, b, c = (current_series(t, 0.2, 1.0, s) for s in (1, 1, 2))
    for k in (0, 1):        # the speed and the direction (the speed alone passed a direction from another stream)
        np.testing.assert_array_equal(a[k], b[k])
        assert not np.allclose(a[k], c[k])


# --------------------------------------------------------------------------- sea state


@pytest.mark.parametrize("field, value", [("hs_m", -0.1), ("tp_s", 0.0), ("wind_speed_m_s", -2.0),
                                          ("gust_intensity", 0.9), ("current_speed_m_s", -0.1),
                                          ("wave_dir_from_rad", float("nan")), ("gamma", 9.0)])
def test_sea_state_validation_names_field(field, value):
    kwargs = dict(hs_m=1.0, tp_s=6.0, wave_dir_from_rad=0.0, wind_speed_m_s=8.0, wind_dir_from_rad=0.0,
                  gust_intensity=0.1, current_speed_m_s=0.2, current_dir_to_rad=1.0)
    kwargs[field] = value
    with pytest.raises(ValueError, match=field):
        SeaState(**kwargs)


@pytest.mark.parametrize("hs_m, tp_s", [(7.0, 1.5), (2.0, 0.5), (8.0, 6.0 / 60.0)])
def test_sea_state_steeper_than_waves_can_be_is_refused(hs_m, tp_s):
    # e.g. Hs and Tp swapped, or Tp in minutes: the simulator drove the ship off at metres per second
    with pytest.raises(ValueError, match="hs_m .* tp_s .* steeper than waves can be"):
        SeaState(hs_m=hs_m, tp_s=tp_s, wave_dir_from_rad=0.0, wind_speed_m_s=8.0, wind_dir_from_rad=0.0)
    with pytest.raises(ValueError, match="sea_state.*steeper"):
        DPLossConfig(sea_state=dict(hs_m=hs_m, tp_s=tp_s, wave_dir_from_rad=0.0, wind_speed_m_s=8.0,
                                    wind_dir_from_rad=0.0))
    SeaState(hs_m=0.9 * float(max_hs_m(tp_s)), tp_s=tp_s, wave_dir_from_rad=0.0, wind_speed_m_s=8.0,
             wind_dir_from_rad=0.0)


def test_a_random_sea_too_steep_from_its_tp_coefficient_names_tp_coefficient():
    """A small tp_coefficient draws a Tp too short for the drawn Hs: the refusal asked whether
    hs_m and tp_s were swapped, fields the caller never gave; it now names tp_coefficient."""
    with pytest.raises(ValueError, match=r"tp_coefficient: \(1, 1\) drew Tp = max\(2, 1 sqrt\(Hs\)\) = 2 s.*"
                                         r"steeper than waves can be.*at least 2\.12") as info:
        SeaState.random(0, beaufort=(6, 8), tp_coefficient=(1, 1))
    assert "swapped" not in str(info.value)
    SeaState.random(0, beaufort=(6, 8), tp_coefficient=(2.2, 2.2))     # just above the limit: a sea


def test_the_highest_sea_at_a_6_s_peak_is_a_seventh_of_its_wavelength():
    """Miche's limit: at Tp = 6 s the deep-water wavelength ``g Tp^2 / (2 pi)`` is 56.21 m, a
    seventh of which, 8.03 m, is the highest Hs accepted."""
    assert max_hs_m(6.0) == pytest.approx(56.21 / 7.0, rel=1e-3)
    SeaState(hs_m=8.0, tp_s=6.0, wave_dir_from_rad=0.0, wind_speed_m_s=8.0, wind_dir_from_rad=0.0)
    with pytest.raises(ValueError, match="steeper than waves can be"):
        SeaState(hs_m=8.1, tp_s=6.0, wave_dir_from_rad=0.0, wind_speed_m_s=8.0, wind_dir_from_rad=0.0)


def test_sea_state_random_is_consistent_and_deterministic():
    lo, hi = beaufort_wind_speed(1.5), beaufort_wind_speed(5.5)
    for seed in range(50):
        s = SeaState.random(np.random.default_rng(seed), beaufort=(2, 5))
        assert lo <= s.wind_speed_m_s <= hi
        assert 0.0 < s.hs_m <= beaufort_wave_height(5.5)
        assert s.tp_s >= 2.0
        assert abs(np.angle(np.exp(1j * (s.wave_dir_from_rad - s.wind_dir_from_rad)))) <= np.radians(30) + 1e-12
        assert 0.05 <= s.current_speed_m_s <= 0.4
        assert 0.08 <= s.gust_intensity <= 0.15
    assert SeaState.random(3) == SeaState.random(3)
    assert SeaState.random(3) != SeaState.random(4)
    with pytest.raises(ValueError, match="beaufort"):
        SeaState.random(1, beaufort=(5, 2))


def test_beaufort_wind_speed_falls_in_the_wmo_class_limits():
    """``0.836 B^1.5`` lies inside the WMO 10 m wind-speed range of each Beaufort class [m/s]."""
    wmo = [(0.3, 1.5), (1.6, 3.3), (3.4, 5.4), (5.5, 7.9), (8.0, 10.7), (10.8, 13.8), (13.9, 17.1),
           (17.2, 20.7), (20.8, 24.4), (24.5, 28.4), (28.5, 32.6), (32.7, 40.0)]
    speeds = beaufort_wind_speed(np.arange(1.0, 13.0))
    for b, (speed, (lo, hi)) in enumerate(zip(speeds, wmo), start=1):
        assert lo <= speed <= hi, b


def test_beaufort_wave_height_is_the_wmo_probable_height():
    """The WMO probable open-sea wave height [m] of Beaufort 3 to 12, linear in between."""
    wmo = [0.6, 1.0, 2.0, 3.0, 4.0, 5.5, 7.0, 9.0, 11.5, 14.0]
    np.testing.assert_allclose(beaufort_wave_height(np.arange(3.0, 13.0)), wmo, rtol=1e-12)
    assert beaufort_wave_height(4.5) == pytest.approx(1.5, rel=1e-12)


def test_random_sea_state_peak_period_scales_with_the_root_of_hs():
    """``Tp = c sqrt(Hs)`` with ``c`` in ``tp_coefficient`` (s/m^0.5), unless held at the 2 s floor."""
    for seed in range(30):
        s = SeaState.random(seed, beaufort=(3, 6), tp_coefficient=(4.0, 6.0))
        if s.tp_s > 2.0:
            assert 4.0 - 1e-9 <= s.tp_s / math.sqrt(s.hs_m) <= 6.0 + 1e-9


def test_random_sea_state_draws_beaufort_half_a_class_wide_and_hs_from_the_fetch_factor():
    """The Beaufort number behind each draw, ``(U / 0.836)^(2/3)`` from the wind [m/s], covers
    half a class beyond both ends of ``beaufort=(2, 5)``; Hs is the WMO height at it [m] times
    a factor in ``hs_fetch_factor``; ``gamma=None`` is DNV's ``exp(5.75 - 1.15 Tp / sqrt(Hs))``
    clipped to [1, 5]."""
    numbers = []
    for seed in range(60):
        s = SeaState.random(seed, beaufort=(2, 5), hs_fetch_factor=(0.2, 0.3), gamma=None)
        b = (s.wind_speed_m_s / 0.836) ** (2.0 / 3.0)
        numbers.append(b)
        assert 0.2 - 1e-9 <= s.hs_m / beaufort_wave_height(b) <= 0.3 + 1e-9
        assert s.gamma == pytest.approx(min(5.0, max(1.0, math.exp(5.75 - 1.15 * s.tp_s / math.sqrt(s.hs_m)))))
    assert min(numbers) < 1.75 and max(numbers) > 5.25


def test_sea_state_hs_grows_with_wind():
    calm = [SeaState.random(s, beaufort=(1, 2)).hs_m for s in range(30)]
    rough = [SeaState.random(s, beaufort=(5, 6)).hs_m for s in range(30)]
    assert np.mean(rough) > 3 * np.mean(calm)


def test_sea_state_helpers_produce_series():
    s = SeaState(hs_m=1.0, tp_s=6.0, wave_dir_from_rad=0.2, wind_speed_m_s=8.0, wind_dir_from_rad=0.1,
                 current_speed_m_s=0.2, current_dir_to_rad=2.0)
    t = np.arange(0.0, 600.0, 1.0)
    wf = s.wave_components(1)
    assert wf.hs_discrete_m == pytest.approx(1.0)
    assert s.wind(t, 1)[0].shape == t.shape
    assert s.current(t, 1)[0].shape == t.shape
    assert GUNNERUS_HULL.L_m == 33.9


def test_sea_state_helpers_pass_on_its_own_gamma_gusts_and_current():
    """A sea state's helpers are the module functions called with its gamma (1, not the 3.3
    default), gust intensity (0.2) and current (0.2 m/s to 2 rad)."""
    s = SeaState(hs_m=1.0, tp_s=6.0, wave_dir_from_rad=0.2, wind_speed_m_s=8.0, wind_dir_from_rad=0.1,
                 gust_intensity=0.2, current_speed_m_s=0.2, current_dir_to_rad=2.0, gamma=1.0)
    t = np.arange(0.0, 600.0, 1.0)
    wf = s.wave_components(1)
    assert wf.gamma == 1.0
    np.testing.assert_array_equal(wf.amplitude_m, make_wave_components(1.0, 6.0, 0.2, 1, gamma=1.0).amplitude_m)
    # speed and direction alike (the speed alone does not see the wind's direction, nor the
    # direction the current's speed: a helper passing either wrong passed)
    for got, want in ((s.wind(t, 1), gust_wind(t, 8.0, 0.1, 1, intensity=0.2)),
                      (s.current(t, 1), current_series(t, 0.2, 2.0, 1))):
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])


@pytest.mark.parametrize("call, error, match", [
    (lambda: make_wave_components(1.0, 6.0, 0.0, 1, omega_range_factor=(0.5,)), ValueError,
     r"omega_range_factor must be a \(lo, hi\) pair"),
    (lambda: make_wave_components(1.0, 6.0, 0.0, 1, omega_range_factor=None), TypeError, "omega_range_factor"),
    (lambda: gust_wind(np.arange(10.0), 5.0, 0.0, 1, n_harmonics=True), ValueError, "n_harmonics"),
    (lambda: SeaState.random(1, beaufort="25"), ValueError, "beaufort must be a"),
    (lambda: SeaState.random(1, hs_fetch_factor=(0.5,)), ValueError, "hs_fetch_factor"),
    (lambda: SeaState.random(1, tp_coefficient=(4.0, float("inf"))), ValueError, r"tp_coefficient\[1\]"),
    (lambda: SeaState.random(1, wave_spread_rad=float("nan")), ValueError, "wave_spread_rad"),
    (lambda: beaufort_wind_speed(float("nan")), ValueError, "beaufort"),
    (lambda: beaufort_wave_height([1.0, float("nan")]), ValueError, "beaufort"),
], ids=["band_short", "band_none", "harmonics_bool", "beaufort_text", "fetch_short", "tp_inf", "spread_nan",
        "wind_nan", "wave_nan"])
def test_bad_arguments_are_refused_naming_them(call, error, match):
    """A pair given as one number or a text, a bool for a count, a NaN Beaufort number: refused
    with the argument's name, not numpy's unpacking message or a NaN result."""
    with pytest.raises(error, match=match):
        call()


@pytest.mark.parametrize("call, match", [
    (lambda: jonswap_spectrum(1.0, "2", 6.0), "hs_m"),
    (lambda: jonswap_spectrum(1.0, True, 6.0), "hs_m"),
    (lambda: make_wave_components(1.0, "6", 0.0, 1), "tp_s"),
    (lambda: gust_wind(np.arange(10.0), "10", 0.0, 1), "mean_speed_m_s"),
    (lambda: current_series(np.arange(10.0), 0.5, "1.2", 1), "mean_dir_to_rad"),
    (lambda: SeaState.random(1, hs_fetch_factor=("0.5", "1")), r"hs_fetch_factor\[0\]"),
], ids=["hs_text", "hs_bool", "tp_text", "wind_text", "current_dir_text", "pair_text"])
def test_text_and_bools_are_not_numbers(call, match):
    """A number given as text or a bool is refused naming the argument (float() read "10" as 10
    and True as 1), as the package's other number checks do."""
    with pytest.raises(TypeError, match=match):
        call()


@pytest.mark.parametrize("call, match", [
    (lambda: gust_wind("0123", 5.0, 0.0, 1), "time_s"),
    (lambda: current_series(["0", "1"], 0.5, 0.0, 1), "time_s"),
    (lambda: wave_drift_loads(np.arange(3.0), "0.1", make_wave_components(1.0, 6.0, 0.0, 1), GUNNERUS_HULL),
     "psi_rad"),
    (lambda: wave_frequency_motion(np.arange(2.0), 0.0, make_wave_components(1.0, 6.0, 0.0, 1), GUNNERUS_HULL,
                                   position_ne_m=[["0", "0"], ["1", "1"]]), "position_ne_m"),
    (lambda: jonswap_spectrum("1.0", 1.0, 6.0), "omega_rad_s"),
    (lambda: harris_spectrum("0.1", 10.0), "f_hz"),
    (lambda: davenport_spectrum(["x"], 10.0), "f_hz"),
    (lambda: drift_coefficients("1.0", 0.0, GUNNERUS_HULL), "omega_rad_s"),
    (lambda: MotionRAOs.from_hull(GUNNERUS_HULL).amplitudes(1.0, "0.5"), "beta_rad"),
    (lambda: current_velocity_ned("0.5", 0.0), "speed_m_s"),
    (lambda: beaufort_wind_speed("3"), "beaufort"),
    (lambda: beaufort_wave_height(["3"]), "beaufort"),
    (lambda: max_hs_m("6"), "tp_s"),
    (lambda: make_wave_components(1.0, 6.0, 0.0, 1).phases("0"), "time_s"),
], ids=["gust_time", "current_time", "drift_heading", "motion_position", "jonswap_omega", "harris_f",
        "davenport_f", "drift_omega", "rao_beta", "current_speed", "beaufort_wind", "beaufort_wave", "max_hs",
        "phases_time"])
def test_text_arrays_are_refused_naming_them(call, match):
    """An array argument given as text is refused naming it, not parsed ("1.0" read as 1 rad/s)
    nor failed in numpy's words ("could not convert string to float")."""
    with pytest.raises(TypeError, match=match):
        call()


@pytest.mark.parametrize("call, match", [
    (lambda: jonswap_spectrum([0.8, np.nan], 1.0, 6.0), "omega_rad_s"),
    (lambda: harris_spectrum([np.nan, 0.1], 10.0), "f_hz"),
    (lambda: davenport_spectrum(np.nan, 10.0), "f_hz"),
], ids=["jonswap", "harris", "davenport"])
def test_spectra_refuse_a_nan_frequency(call, match):
    """A NaN frequency is refused naming it: it failed the ``> 0`` test and came out as a
    spectral density of 0, hiding the NaN."""
    with pytest.raises(ValueError, match=match):
        call()


@pytest.mark.parametrize("call, match", [
    (lambda: harris_spectrum(0.1, 10.0, kappa=-0.0026), "kappa"),
    (lambda: harris_spectrum(0.1, 10.0, length_scale_m=-1800.0), "length_scale_m"),
    (lambda: davenport_spectrum(0.1, 10.0, kappa=0.0), "kappa"),
    (lambda: davenport_spectrum(0.1, 10.0, length_scale_m=float("nan")), "length_scale_m"),
], ids=["harris_kappa", "harris_length", "davenport_kappa", "davenport_length"])
def test_gust_spectra_refuse_a_nonpositive_drag_or_length(call, match):
    """A drag coefficient or length scale <= 0 (or NaN) is refused naming it: it gave a
    negative, zero or NaN spectral density, which no gust spectrum is."""
    with pytest.raises(ValueError, match=match):
        call()


def test_mean_drift_refuses_a_nan_heading_as_the_slowly_varying_drift_does():
    """A NaN heading is refused naming psi_rad (as wave_drift_loads refuses it), not turned
    into NaN loads."""
    wf = make_wave_components(1.0, 6.0, 0.0, 1)
    with pytest.raises(ValueError, match="psi_rad"):
        mean_drift_loads(float("nan"), wf, GUNNERUS_HULL)
    with pytest.raises(ValueError, match="psi_rad"):
        mean_drift_loads([0.0, np.inf], wf, GUNNERUS_HULL)
    assert mean_drift_loads([0.0, 0.5], wf, GUNNERUS_HULL).shape == (2, 3)


@pytest.mark.parametrize("call, match", [
    (lambda: make_wave_components(1.0, 6.0, 0.0, 1, normalize_hs="no"), "normalize_hs"),
    (lambda: wave_frequency_motion(np.arange(3.0), 0.0, make_wave_components(1.0, 6.0, 0.0, 1), GUNNERUS_HULL,
                                   return_rates="no"), "return_rates"),
], ids=["normalize_hs", "return_rates"])
def test_flags_that_are_not_bools_are_refused(call, match):
    """A text "no" is truthy: it normalised the sea and returned the rates; refused naming the flag."""
    with pytest.raises(TypeError, match=f"{match}: expected True or False"):
        call()


def test_a_sea_states_own_setting_given_again_is_refused_by_name():
    """wave_components(rng, gamma=...) and wind(..., intensity=...) ended in Python's 'got
    multiple values for keyword argument'."""
    import dataclasses

    from hybridship.sim.environment import SeaState

    sea = SeaState.random(3)
    with pytest.raises(TypeError, match=r"^gamma: the sea state's own .*dataclasses.replace\(sea_state, gamma=...\)"):
        sea.wave_components(0, gamma=2.0)
    with pytest.raises(TypeError, match=r"^intensity: the sea state's own \(gust_intensity = ...\)"):
        sea.wind(np.arange(100.0), 0, intensity=0.2)
    assert dataclasses.replace(sea, gamma=2.0).wave_components(0).n_components == 50
