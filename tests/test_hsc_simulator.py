"""Planing-craft simulator and vessel file: steady speed/trim in the documented credible range."""

import math

import numpy as np
import pytest

from hybridship.hsc.simulator import KNOT_M_S, PlaningCraftModel, SeaConditions, savitsky_planing
from hybridship.hsc.trials import generate_trial, paper_trial
from hybridship.hsc.vessel import PlaningCraftFileError, load_planing_craft, planing_craft_from_dict

RPMS = np.linspace(800, 4000, 9)


@pytest.fixture(scope="module")
def craft():
    return load_planing_craft()


@pytest.fixture(scope="module", params=["nominal", "truth"])
def curve(request, craft):
    c = craft if request.param == "nominal" else craft.perturbed()
    return PlaningCraftModel(c, "interceptor").steady_curve(RPMS, 0.0)


def test_top_speed_near_40_kn_at_4000_rpm(curve):
    assert curve[-1].rpm == 4000
    assert 37.0 <= curve[-1].speed_kn <= 43.0


def test_speed_rises_with_rpm(curve):
    v = np.array([s.speed_kn for s in curve])
    assert np.all(np.diff(v) > 0)
    assert v[0] < 8.0                      # idle: displacement speed


def test_running_trim_2_to_6_deg_between_15_and_40_kn(curve):
    planing = [s for s in curve if 15.0 <= s.speed_kn <= 40.0]
    assert len(planing) >= 3
    for s in planing:
        assert 2.0 <= s.trim_deg <= 6.5, (s.speed_kn, s.trim_deg)
    # trim falls with speed once planing
    trims = [s.trim_deg for s in planing]
    assert trims[-1] < trims[0]


def test_interceptor_and_tabs_lower_the_trim(craft):
    for act in ("interceptor", "trim_tab"):
        m = PlaningCraftModel(craft, act)
        off = m.steady_state(3200, 0.0)
        on = m.steady_state(3200, 1.0, guess=off)
        assert on.trim_deg < off.trim_deg - 0.5


@pytest.mark.parametrize("rpm", [1500, 2600, 4000])
def test_no_porpoising(craft, rpm):
    """The linearised surge-heave-pitch motion about the equilibrium is stable."""
    m = PlaningCraftModel(craft.perturbed(), "trim_tab")
    s = m.steady_state(rpm, 0.5)
    y0 = np.array([0.0, s.speed_m_s, s.heave_m, 0.0, s.trim_rad, 0.0, float(rpm)])
    J = np.zeros((6, 6))
    for i in range(1, 7):
        e = np.zeros(7)
        e[i] = 1e-6 * max(1.0, abs(y0[i]))
        J[:, i - 1] = (np.array(m.derivatives(y0 + e, rpm, 0.5))[1:] - np.array(m.derivatives(y0 - e, rpm, 0.5))[1:]) / (2 * e[i])
    assert np.max(np.linalg.eigvals(J).real) < 0


def test_savitsky_lift_grows_with_trim_and_immersion():
    args = (2.9, math.radians(20), 1025.0, 1.19e-6)
    l1 = savitsky_planing(15.0, math.radians(3), 0.3, *args)[0]
    l2 = savitsky_planing(15.0, math.radians(4), 0.3, *args)[0]
    l3 = savitsky_planing(15.0, math.radians(3), 0.4, *args)[0]
    assert 0 < l1 < l2 and l1 < l3
    assert savitsky_planing(15.0, math.radians(3), -0.1, *args) == (0.0, 0.0, 0.0, 0.0)


def test_vessel_file_kind_and_field_errors(craft):
    data = craft.model_dump()
    data["kind"] = "ship"
    with pytest.raises(PlaningCraftFileError, match="kind"):
        planing_craft_from_dict(data, "x.toml")
    data = craft.model_dump()
    data["hull"]["deadrise_deg"] = -3
    with pytest.raises(PlaningCraftFileError, match="hull.deadrise_deg"):
        planing_craft_from_dict(data, "x.toml")


def test_trial_gps_delay_realigned_and_reproducible(craft):
    cfg = paper_trial(2, scale=0.03)
    a = generate_trial(cfg, craft)
    b = generate_trial(cfg, "volcano71")           # the packaged name, as HybridModel takes it
    pd_equal = np.array_equal(a.data.to_numpy(), b.data.to_numpy())
    assert pd_equal
    with pytest.raises(TypeError, match="^craft: expected a PlaningCraft"):
        generate_trial(cfg, 71)
    d = a.delay_samples
    assert d == 20 and len(a.data) == cfg.n_samples and len(a.raw) == cfg.n_samples + d
    truth = a.truth.speed_m_s
    # aligned speed matches the true speed at the same time (noise only) ...
    assert np.std(a.data.speed_m_s - truth) < 2 * craft.sensors.gps_speed_noise_m_s
    # ... while the raw GPS channel lags it by 2 s
    raw = a.raw.gps_speed_m_s.to_numpy()[d:d + cfg.n_samples - d]
    assert np.max(np.abs(raw - truth[:cfg.n_samples - d])) < 6 * craft.sensors.gps_speed_noise_m_s
    assert np.std(a.raw.gps_speed_m_s.to_numpy()[:cfg.n_samples] - truth) > 2 * craft.sensors.gps_speed_noise_m_s
    assert a.data.rpm.between(700, 4100).all() and a.data.pwm_pct.between(10, 100).all()
    assert (truth.max() - truth.min()) / KNOT_M_S > 5          # the inputs excite the speed


def test_simulator_refuses_bad_arguments_by_name(craft):
    model = PlaningCraftModel(craft, "interceptor")
    cases = [
        (lambda: model.simulate([], []), "rpm_cmd"),
        (lambda: model.simulate([3000.0, np.nan], [50.0, 50.0]), "rpm_cmd"),
        (lambda: model.simulate([3000.0], [np.inf]), "pwm_pct"),
        (lambda: model.simulate([3000.0], [50.0], sample_period_s=0.0), "sample_period_s"),
        (lambda: model.simulate([3000.0], [50.0], substeps=0), "substeps"),
        (lambda: model.simulate([3000.0], [50.0], settle_s=-1.0), "settle_s"),
        (lambda: model.steady_state(np.nan), "rpm"),
        (lambda: model.steady_state(3000.0, np.nan), "actuator_frac"),
        (lambda: model.steady_state(3000.0, 5.0), "actuator_frac"),              # an OverflowError before
        (lambda: model.steady_state(3000.0, -1.0), "actuator_frac"),             # 28.4 kn before
        (lambda: model.steady_state(1e5), "rpm"),                                # "math domain error" before
        (lambda: model.simulate([3000.0, 9000.0], [50.0, 50.0]), "rpm_cmd"),      # overflowed inside before
        (lambda: model.simulate([3000.0, -500.0], [50.0, 50.0]), "rpm_cmd"),      # accepted silently before
        (lambda: model.simulate([3000.0], [500.0]), "pwm_pct"),                   # clipped silently before
        (lambda: SeaConditions(hs_m=0.3, tp_s=3.0), "hs_m"),                      # the model slams there
        (lambda: SeaConditions(hs_m=0.1, tp_s=0.5, beyond_validity=True), "hs_m"),  # steeper than waves can be
        (lambda: paper_trial(1, seed=-1), "seed"),
    ]
    for call, field in cases:
        with pytest.raises(ValueError, match=rf"^{field}\b"):
            call()
    SeaConditions(hs_m=0.3, tp_s=3.0, beyond_validity=True)         # allowed when asked for


def test_a_vessel_file_with_nan_or_an_impossible_true_boat_is_refused_by_name(craft):
    data = craft.model_dump()
    data["particulars"]["displacement_kg"] = float("inf")
    with pytest.raises(PlaningCraftFileError, match="particulars.displacement_kg"):
        planing_craft_from_dict(data, "x.toml")
    data = craft.model_dump()
    data["truth_perturbation"]["lcg_offset_m"] = -10.0
    with pytest.raises(PlaningCraftFileError, match=r"truth_perturbation"):
        planing_craft_from_dict(data, "x.toml").perturbed()


def test_gps_delay_must_be_whole_samples(craft):
    data = craft.model_dump()
    data["sensors"]["gps_delay_s"] = 2.05
    with pytest.raises(PlaningCraftFileError, match="gps_delay_s"):
        planing_craft_from_dict(data, "x.toml")
