"""Planing-craft simulator and vessel file: steady speed/trim in the documented credible range."""

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from hybridship.hsc.simulator import KNOT_M_S, PlaningCraftModel, SeaConditions, savitsky_planing, smoothstep
from hybridship.hsc.trials import TrialConfig, generate_trial, input_schedule, paper_trial
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


@pytest.mark.parametrize("rpm,frac", [(1500.0, 0.0), (3000.0, 0.5), (4000.0, 1.0)])
def test_a_steady_state_is_an_equilibrium_of_the_forces_with_the_thrust_at_its_speed(craft, rpm, frac):
    """At the returned speed, heave and trim (no heave or pitch rate) the surge and heave forces and
    the pitch moment vanish, and the recorded thrust is the propeller's at that speed (the grey box's
    tables take it as the resistance)."""
    model = PlaningCraftModel(craft, "interceptor")
    s = model.steady_state(rpm, frac)
    forces = model.forces(s.speed_m_s, s.heave_m, 0.0, s.trim_rad, 0.0, rpm, frac)
    np.testing.assert_allclose(forces, 0.0, atol=1e-6 * craft.mass_kg * 9.81)
    assert s.thrust_n == pytest.approx(model.thrust_n(rpm, s.speed_m_s), rel=1e-12)
    assert (s.rpm, s.actuator_frac) == (rpm, frac)


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
    for not_a_table in ([data], None, "volcano71"):           # an AttributeError on .get before
        with pytest.raises(PlaningCraftFileError, match=r"^x.toml: expected a table"):
            planing_craft_from_dict(not_a_table, "x.toml")


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


class _StuckGuard:
    """A random generator that raises after many draws: a schedule that stops advancing fails instead of hanging."""

    def __init__(self):
        self.rng, self.draws = np.random.default_rng(0), 0

    def __getattr__(self, name):
        self.draws += 1
        if self.draws > 100_000:
            raise RuntimeError("input_schedule no longer advances")
        return getattr(self.rng, name)


def test_a_pwm_period_shorter_than_two_samples_is_refused(craft):
    """A half period below one sample (0.1 s) made no progress: input_schedule and generate_trial hung."""
    cfg = TrialConfig(sea_state=1, n_samples=300, n_train=200, actuator="interceptor", sea=SeaConditions(),
                      pwm_period_s=(0.1, 0.19))
    with pytest.raises(ValueError, match=r"^pwm_period_s: expected a shortest period of at least two samples"):
        input_schedule(cfg, 300, 0.1, _StuckGuard())
    with pytest.raises(ValueError, match=r"^pwm_period_s"):
        generate_trial(cfg, craft)                 # refused before the simulation
    with pytest.raises(ValueError, match=r"^dt_s"):
        input_schedule(cfg, 300, 0.0, _StuckGuard())
    # two samples exactly: the duty switches between its high and low halves at every sample
    _, pwm = input_schedule(dataclasses.replace(cfg, pwm_period_s=(0.2, 0.2)), 300, 0.1, _StuckGuard())
    assert np.all(np.diff(pwm >= 55.0))


def test_input_schedule_refuses_a_sample_count_that_is_not_a_whole_number_by_name():
    """``input_schedule(cfg, 300.0, ...)`` was numpy's 'expected a sequence of integers or a single
    integer', ``n = -1`` its 'negative dimensions are not allowed'; neither named ``n``."""
    cfg = paper_trial(1, scale=0.1)
    for n in (300.0, -1, "300", True):
        with pytest.raises(ValueError, match=r"^n: expected a whole number >= 0"):
            input_schedule(cfg, n, 0.1, np.random.default_rng(0))
    rpm, pwm = input_schedule(cfg, np.int64(300), 0.1, np.random.default_rng(0))
    assert rpm.shape == pwm.shape == (300,)
    assert [a.size for a in input_schedule(cfg, 0, 0.1, np.random.default_rng(0))] == [0, 0]
    with pytest.raises(TypeError, match=r"^config: expected a TrialConfig"):     # an AttributeError before
        input_schedule({"sea_state": 1}, 10, 0.1, np.random.default_rng(0))


def test_input_schedule_takes_a_seed_as_its_generator_and_names_a_bad_one():
    """A seed was an AttributeError ('int' object has no attribute 'random')."""
    cfg = paper_trial(1, scale=0.1)
    by_seed = input_schedule(cfg, 300, 0.1, 7)
    by_generator = input_schedule(cfg, 300, 0.1, np.random.default_rng(7))
    for a, b in zip(by_seed, by_generator):
        np.testing.assert_array_equal(a, b)
    for bad in (-1, 1.5, "7", None):
        with pytest.raises(ValueError, match=r"^rng: expected a whole number >= 0"):
            input_schedule(cfg, 300, 0.1, bad)


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
        (lambda: model.simulate([3000.0], [50.0], rng=-1), "rng"),            # numpy's own words before
        (lambda: model.simulate([3000.0], [50.0], rng="a"), "rng"),           # a TypeError from SeedSequence
        (lambda: model.simulate([3000.0], [50.0], rng=True), "rng"),          # seed 1 before
        (lambda: model.simulate([3000.0], [50.0], rng=None), "rng"),          # a sea drawn afresh each call
    ]
    for call, field in cases:
        with pytest.raises(ValueError, match=rf"^{field}\b"):
            call()
    SeaConditions(hs_m=0.3, tp_s=3.0, beyond_validity=True)         # allowed when asked for
    with pytest.raises(ValueError, match=r"^hs_m\b"):                  # a mapping is read as SeaConditions
        model.simulate([3000.0], [50.0], sea={"hs_m": -1.0})
    with pytest.raises(TypeError, match=r"^sea: expected SeaConditions"):  # an AttributeError inside before
        model.simulate([3000.0], [50.0], sea=0.1)
    for rpm, pwm, field in ((["3000"], [50.0], "rpm_cmd"), ([3000.0], ["50"], "pwm_pct")):  # read as numbers before
        with pytest.raises(TypeError, match=rf"^{field}: expected an array of real numbers"):
            model.simulate(rpm, pwm)
    as_mapping = model.simulate([3000.0] * 5, [50.0] * 5, sea={"hs_m": 0.05, "tp_s": 1.5}, rng=1)
    np.testing.assert_array_equal(
        as_mapping.speed_m_s, model.simulate([3000.0] * 5, [50.0] * 5, sea=SeaConditions(hs_m=0.05, tp_s=1.5), rng=1).speed_m_s)


def test_a_paper_trial_seed_is_refused_in_the_users_own_numbers():
    """The trial's seed is ``seed * 100 + sea_state``: a seed of 2**62 was refused as 'seed: must
    be < 9223372036854775808 (got 461168601842738790401)', a value the caller never gave and
    below the bound it quoted."""
    top = (2**63 - 3) // 100
    for seed in (2**62, top + 1):
        with pytest.raises(ValueError, match=rf"^seed: expected a whole number from 0 to {top}, got {seed}$"):
            paper_trial(2, seed=seed)
    with pytest.raises(ValueError, match=rf"^seed: expected a whole number from 0 to {top}, got np.int64\({2**62}\)"):
        paper_trial(2, seed=np.int64(2**62))
    assert paper_trial(2, seed=top).seed == top * 100 + 2 < 2**63       # the largest one is a seed


def test_steady_curve_refuses_engine_speeds_that_are_not_a_sequence_of_numbers_by_name(craft):
    """``steady_curve(["3000"])`` read the text as 3000 rpm (steady_state refuses it), ``["a"]`` was
    float's 'could not convert string', a single number 'object is not iterable'."""
    model = PlaningCraftModel(craft, "interceptor")
    for rpms, err in ((["3000"], TypeError), (["a"], TypeError), (3000.0, ValueError), ([[3000.0]], ValueError)):
        with pytest.raises(err, match=r"^rpms: expected"):
            model.steady_curve(rpms)
    assert model.steady_curve(np.array([3000.0]))[0].speed_m_s == model.steady_state(3000.0).speed_m_s


def test_arguments_of_the_wrong_type_are_refused_by_name(craft):
    """A vessel name for the craft or a text for the trial's config was an AttributeError, a text
    for rpm, the sample period or the settling time a numpy TypeError naming nothing, a text scale
    a comparison TypeError, and ``paper_trial(True)`` gave sea state 1."""
    model = PlaningCraftModel(craft, "interceptor")
    cases = [
        (lambda: PlaningCraftModel("volcano71"), TypeError, "craft"),
        (lambda: generate_trial("sea state 1", craft), TypeError, "config"),
        (lambda: model.steady_state("3000"), TypeError, "rpm"),
        (lambda: model.steady_state(True), TypeError, "rpm"),
        (lambda: model.steady_state(3000.0, "0.5"), TypeError, "actuator_frac"),
        (lambda: model.simulate([3000.0], [50.0], sample_period_s="0.1"), TypeError, "sample_period_s"),
        (lambda: model.simulate([3000.0], [50.0], settle_s=None), TypeError, "settle_s"),
        (lambda: paper_trial(True), ValueError, "sea_state"),
        (lambda: paper_trial(1, scale="0.5"), TypeError, "scale"),
        (lambda: paper_trial(1, scale=1.5), ValueError, "scale"),
    ]
    for call, error, field in cases:
        with pytest.raises(error, match=rf"^{field}\b"):
            call()
    assert model.steady_state(np.float32(3000.0)).speed_m_s == pytest.approx(model.steady_state(3000).speed_m_s)


def test_trial_arrays_refuse_an_unknown_part_by_name():
    """``arrays("val")`` was a KeyError: 'val'; the three parts are the split's rows in order."""
    from hybridship.hsc.trials import INPUTS, OUTPUTS, TrialData

    cfg = TrialConfig(sea_state=1, n_samples=60, n_train=50, actuator="interceptor", sea=SeaConditions())
    data = pd.DataFrame({c: np.arange(60.0) + j for j, c in enumerate(("time_s", *OUTPUTS, *INPUTS))})
    trial = TrialData(config=cfg, raw=data, data=data, truth=None, delay_samples=0)
    for part in ("val", "Train", None, 1):
        with pytest.raises(ValueError, match=r"^part: expected 'all', 'train' or 'validation'"):
            trial.arrays(part)
    for part, rows in (("all", slice(0, 60)), ("train", slice(0, 50)), ("validation", slice(50, 60))):
        U, Y = trial.arrays(part)
        np.testing.assert_array_equal(U[:, 0], np.arange(60.0)[rows] + 3)      # rpm, the fourth column
        np.testing.assert_array_equal(Y[:, 1], np.arange(60.0)[rows] + 2)      # pitch, the third


def test_a_trial_rpm_range_outside_the_engine_is_refused_by_name(craft):
    """The trial's engine-speed range is checked against the craft's engine before simulating
    (before: the simulator refused ``rpm_cmd``, a name the caller never gave, and only when
    the schedule happened to reach beyond the engine)."""
    cfg = TrialConfig(sea_state=1, n_samples=300, n_train=200, actuator="interceptor", sea=SeaConditions(),
                      rpm_range=(craft.engines.idle_rpm, craft.engines.max_rpm + 500.0))
    with pytest.raises(ValueError, match=r"^rpm_range: expected within the craft's engine range"):
        generate_trial(cfg, craft)


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


def test_a_knot_is_one_nautical_mile_an_hour():
    """1 kn = 1852 m / 3600 s; the steady state's knots and degrees are the SI values converted."""
    from hybridship.hsc.simulator import SteadyState

    assert KNOT_M_S == pytest.approx(0.514444, abs=1e-6)
    s = SteadyState(3000.0, 0.0, speed_m_s=20.5778, trim_rad=math.radians(3.5), heave_m=0.0, thrust_n=0.0)
    assert s.speed_kn == pytest.approx(40.0, abs=1e-3) and s.trim_deg == pytest.approx(3.5)


def test_savitsky_planing_follows_the_published_equations_by_hand():
    """Savitsky (1964) at V = 15 m/s, tau = 4 deg, d = 0.5 m, b = 2.9 m, beta = 20 deg, worked step by step."""
    b, d, rho, nu = 2.9, 0.5, 1025.0, 1.19e-6
    tau, beta = math.radians(4.0), math.radians(20.0)
    lk = d / math.sin(tau)                                          # keel wetted length, 7.1678 m
    lc = lk - b * math.tan(beta) / (math.pi * math.tan(tau))        # chine wetted length, 2.3630 m
    lam = (lk + lc) / (2 * b)                                       # mean wetted length / beam
    assert lam == pytest.approx(1.6432, abs=1e-4)
    cv = 15.0 / math.sqrt(9.81 * 2.9)                               # speed coefficient, 2.8122
    cl0 = 4.0 ** 1.1 * (0.0120 * lam ** 0.5 + 0.0055 * lam ** 2.5 / cv ** 2)   # tau in degrees
    clb = cl0 - 0.0065 * 20.0 * cl0 ** 0.6                          # beta in degrees
    lp = lam * b * (0.75 - 1 / (5.21 * cv ** 2 / lam ** 2 + 2.39))
    cl_dyn = 0.0120 * lam ** 0.5 * 4.0 ** 1.1
    cl_dyn -= 0.0065 * 20.0 * cl_dyn ** 0.6
    vm = 15.0 * math.sqrt(1 - cl_dyn / (lam * math.cos(tau)))       # mean bottom velocity
    cf = 0.075 / (math.log10(vm * lam * b / nu) - 2) ** 2 + 0.0004   # ITTC-1957 + Delta C_F
    lift, got_lp, friction, got_lam = savitsky_planing(15.0, tau, d, b, beta, rho, nu)
    assert got_lam == pytest.approx(lam, rel=1e-9)
    assert lift == pytest.approx(0.5 * rho * 15.0 ** 2 * b ** 2 * clb, rel=1e-9)
    assert got_lp == pytest.approx(lp, rel=1e-9)
    assert friction == pytest.approx(0.5 * rho * vm ** 2 * lam * b ** 2 * cf / math.cos(beta), rel=1e-9)
    # the trim is floored at 0.5 deg; a flow angle adds to the trim of the lift coefficient only
    assert savitsky_planing(15.0, math.radians(0.2), d, b, beta, rho, nu) == \
        savitsky_planing(15.0, math.radians(0.5), d, b, beta, rho, nu)
    tilted = savitsky_planing(15.0, tau, d, b, beta, rho, nu, flow_angle_rad=math.radians(1.0))
    cl0 = 5.0 ** 1.1 * (0.0120 * lam ** 0.5 + 0.0055 * lam ** 2.5 / cv ** 2)
    assert tilted[0] == pytest.approx(0.5 * rho * 15.0 ** 2 * b ** 2 * (cl0 - 0.13 * cl0 ** 0.6), rel=1e-9)
    assert tilted[3] == pytest.approx(lam, rel=1e-9)


def test_thrust_by_hand_and_zero_at_the_zero_thrust_advance_ratio(craft):
    """``T = n_eng rho n_p^2 D^4 K_T0 (1 - J / J0) (1 - t)``, ``n_p = rpm / 60 / gear``, ``J = V (1 - w) / (n_p D)``."""
    model = PlaningCraftModel(craft, "interceptor")
    pr = craft.propellers
    n_p = 3000.0 / 60.0 / pr.gear_ratio                            # 33.3 rev/s
    static = 2 * 1025.0 * n_p ** 2 * pr.diameter_m ** 4 * pr.kt0 * (1 - pr.thrust_deduction)
    assert model.thrust_n(3000.0, 0.0) == pytest.approx(static, rel=1e-12)
    v_zero = pr.j0 * n_p * pr.diameter_m / (1 - pr.wake_fraction)   # J = J0: no thrust
    assert model.thrust_n(3000.0, v_zero) == pytest.approx(0.0, abs=1e-6 * static)
    assert model.thrust_n(3000.0, 0.5 * v_zero) == pytest.approx(0.5 * static, rel=1e-12)


def test_trim_devices_forces_and_levers_by_hand(craft):
    """Interceptor ``C 0.5 rho V^2 (n span stroke)`` at the transom; trim tabs after Savitsky & Brown
    (1976): ``0.046 (l_f / b) delta sigma 0.5 rho V^2 b^2``, drag ``0.0052 L (tau + delta)`` (degrees),
    0.6 b forward of the trailing edge."""
    q = 0.5 * 1025.0 * 15.0 ** 2
    ic, tt, h = craft.interceptor, craft.trim_tabs, craft.hull
    lift, drag, lever = PlaningCraftModel(craft, "interceptor").actuator_forces(15.0, math.radians(3.0), 0.5)
    area = ic.count * ic.span_m * 0.5 * ic.max_stroke_m
    assert (lift, drag, lever) == pytest.approx((ic.lift_coefficient * q * area, ic.drag_coefficient * q * area,
                                                 -h.lcg_m))
    lift, drag, lever = PlaningCraftModel(craft, "trim_tab").actuator_forces(15.0, math.radians(3.0), 0.5)
    b, delta = h.chine_beam_m, 0.5 * tt.max_deflection_deg
    want = 0.046 * (tt.chord_m / b) * delta * (tt.count * tt.span_m / b) * q * b ** 2
    assert lift == pytest.approx(want, rel=1e-12)
    assert drag == pytest.approx(0.0052 * want * (3.0 + delta), rel=1e-12)
    assert lever == pytest.approx(-h.lcg_m - tt.chord_m + 0.6 * b, rel=1e-12)


@pytest.fixture(scope="module")
def step_record(craft):
    """60 samples (0.1 s) of the nominal craft: engine command 2000 -> 2600 rpm and PWM 10 -> 100 % after the first."""
    return PlaningCraftModel(craft, "interceptor").simulate(np.r_[2000.0, np.full(59, 2600.0)],
                                                            np.r_[10.0, np.full(59, 100.0)])


def test_engine_speed_follows_a_step_with_its_first_order_lag(craft, step_record):
    """A step of the rpm command gives ``rpm(t) = cmd + (rpm0 - cmd) exp(-t / time_constant)``."""
    t = np.arange(1, 60) * 0.1
    want = 2600.0 - 600.0 * np.exp(-t / craft.engines.time_constant_s)
    np.testing.assert_allclose(step_record.rpm[1:], want, atol=1e-4)
    assert step_record.rpm[0] == pytest.approx(2000.0)


def test_settling_is_the_record_of_the_first_commands_held_before_it_with_its_samples_dropped(craft):
    """``settle_s = 0.3`` (three samples of 0.1 s; 0.3 / 0.1 is 2.9999... in floating point) runs the
    first commands for 0.3 s first: the record is the tail of one with those samples prepended, in a
    sea, so the waves met keep their time too; its clock and commands start at the record's first."""
    model = PlaningCraftModel(craft, "interceptor")
    rpm, pwm = np.r_[2000.0, np.full(9, 2600.0)], np.r_[10.0, np.full(9, 100.0)]
    sea = SeaConditions(hs_m=0.05, tp_s=2.0)
    settled = model.simulate(rpm, pwm, sea=sea, rng=4, settle_s=0.3)
    longer = model.simulate(np.r_[np.full(3, rpm[0]), rpm], np.r_[np.full(3, pwm[0]), pwm], sea=sea, rng=4)
    for name in ("speed_m_s", "heave_m", "pitch_rad", "rpm", "actuator_frac", "heave_acc_m_s2", "wave_elevation_m"):
        np.testing.assert_array_equal(getattr(settled, name), getattr(longer, name)[3:], err_msg=name)
    np.testing.assert_allclose(settled.time_s, np.arange(10) * 0.1)
    np.testing.assert_array_equal(settled.rpm_cmd, rpm)
    np.testing.assert_array_equal(settled.pwm_pct, pwm)


def test_heave_acceleration_is_up_positive(step_record):
    """The record's heave acceleration is minus the second derivative of the CG depth (z down)."""
    rec = step_record
    acc = -np.diff(rec.heave_m, 2) / 0.1 ** 2                # up positive, centred on samples 1..N-2
    mean_acc = 0.5 * (rec.heave_acc_m_s2[1:-1] + rec.heave_acc_m_s2[2:])  # each averaged over its sample
    assert np.ptp(acc) > 0.02                                # the CG rises as the craft speeds up
    assert np.corrcoef(acc, mean_acc)[0, 1] > 0.99
    # the size too, not only the sign and shape: a factor (e.g. the sub-steps' sum not averaged) is caught
    np.testing.assert_allclose(mean_acc, acc, atol=0.05 * np.ptp(acc))


def test_wave_elevation_rate_and_slope_are_those_of_the_surface_met(craft):
    """``zeta_dot`` is the rate of the elevation met by the craft moving at ``u`` and ``slope`` its
    gradient forward (head seas, encounter frequency ``omega + k u``): checked by finite differences."""
    model = PlaningCraftModel(craft, "interceptor")
    wave = model.make_wave_function(SeaConditions(hs_m=0.1, tp_s=3.0), 3)
    u, h = 15.0, 1e-5
    for X0, t0 in ((0.0, 0.0), (37.0, 4.2)):
        model._t = t0
        _, zeta_dot, slope = wave(X0, u)
        z_back = wave(X0 - h, u)[0]
        z_fwd = wave(X0 + h, u)[0]
        model._t = t0 + h
        z_later = wave(X0 + u * h, u)[0]
        model._t = t0 - h
        z_earlier = wave(X0 - u * h, u)[0]
        assert slope == pytest.approx((z_fwd - z_back) / (2 * h), rel=1e-5, abs=1e-9)
        assert zeta_dot == pytest.approx((z_later - z_earlier) / (2 * h), rel=1e-5, abs=1e-9)
        assert abs(zeta_dot) > 1e-3


def test_pwm_maps_linearly_and_the_device_moves_at_its_rate(craft, step_record):
    """PWM 10 % -> 0 and 100 % -> 1 (linear between); a full-drive step moves the interceptor
    ``dt / full_stroke_time`` per sample."""
    model = PlaningCraftModel(craft, "interceptor")
    np.testing.assert_allclose(model.pwm_to_fraction([0.0, 10.0, 55.0, 100.0]), [0.0, 0.0, 0.5, 1.0])
    step = 0.1 / craft.interceptor.full_stroke_time_s
    np.testing.assert_allclose(step_record.actuator_frac, np.minimum(np.arange(60) * step, 1.0), atol=1e-12)


def test_the_true_boat_applies_each_perturbation_once(craft):
    """``perturbed()`` adds the LCG offset and multiplies the five factors, then clears the perturbation."""
    tp, t = craft.truth_perturbation, craft.perturbed()
    assert t.hull.lcg_m == pytest.approx(craft.hull.lcg_m + tp.lcg_offset_m)
    assert t.propellers.kt0 == pytest.approx(craft.propellers.kt0 * tp.kt0_factor)
    assert t.hull.friction_factor == pytest.approx(craft.hull.friction_factor * tp.friction_factor)
    assert t.interceptor.lift_coefficient == pytest.approx(craft.interceptor.lift_coefficient
                                                           * tp.interceptor_lift_factor)
    assert t.trim_tabs.lift_factor == pytest.approx(craft.trim_tabs.lift_factor * tp.trim_tab_lift_factor)
    assert t.mass_kg == pytest.approx(craft.mass_kg * tp.displacement_factor)
    assert t.perturbed() == t                                    # nothing left to apply


@pytest.mark.parametrize("section,field,value", [("hull", "lcg_m", 9.5), ("hull", "chine_beam_m", 3.4),
                                                 ("interceptor", "span_m", 4.3), ("trim_tabs", "span_m", 1.5)])
def test_a_hull_outside_the_main_particulars_is_refused(craft, section, field, value):
    """The CG must lie within the waterline length (9.4 m), the chine beam within the beam (3.3 m),
    and the two interceptor blades or tab plates side by side within the chine beam (2.9 m; a
    4.3 m blade, a slip for 430 mm, was accepted and lifted ten times as much)."""
    data = craft.model_dump()
    data[section][field] = value
    with pytest.raises(PlaningCraftFileError, match=f"{section}.{field}"):
        planing_craft_from_dict(data, "x.toml")


def test_the_blend_is_a_c1_smooth_cubic():
    """``3 t^2 - 2 t^3`` between the two speeds: 0 and 1 outside, 5/32 at a quarter, flat at both ends."""
    assert smoothstep(6.0, 7.0, 13.0) == 0.0 and smoothstep(14.0, 7.0, 13.0) == 1.0
    assert smoothstep(8.5, 7.0, 13.0) == pytest.approx(5 / 32)
    assert smoothstep(11.5, 7.0, 13.0) == pytest.approx(27 / 32)
    h = 1e-4
    for x in (7.0, 13.0):
        assert abs(smoothstep(x + h, 7.0, 13.0) - smoothstep(x - h, 7.0, 13.0)) < 1e-6


def test_trials_have_the_papers_sizes_the_imu_bias_in_radians_and_the_speed_realigned(craft):
    """Sec. 4 of the paper: 3150 samples (2050 training) in sea state 1, 13580 (8600) in sea state 2;
    the logged pitch is the true pitch plus the vessel file's mounting bias and noise, given in degrees,
    and the GPS speed re-aligned to the sample it was measured at."""
    assert (paper_trial(1).n_samples, paper_trial(1).n_train) == (3150, 2050)
    assert (paper_trial(2).n_samples, paper_trial(2).n_train) == (13580, 8600)
    trial = generate_trial(paper_trial(1, scale=0.03), craft)
    err = trial.data.pitch_rad.to_numpy() - trial.truth.pitch_rad
    s = craft.sensors
    assert np.mean(err) == pytest.approx(math.radians(s.imu_pitch_bias_deg), abs=4 * math.radians(0.1) / 14)
    assert np.std(err) == pytest.approx(math.radians(s.imu_pitch_noise_deg), rel=0.2)
    # the re-aligned speed's error is noise alone: a sample off would leave minus the speed change in it
    change = np.diff(trial.truth.speed_m_s)
    err = trial.data.speed_m_s.to_numpy()[1:] - trial.truth.speed_m_s[1:]
    assert np.std(change) > s.gps_speed_noise_m_s and abs(err @ change / (change @ change)) < 0.3


def _tilted_drives(craft, shaft_deg=4.0):
    data = craft.model_dump()
    data["propellers"]["shaft_angle_deg"] = shaft_deg
    return planing_craft_from_dict(data)


@pytest.mark.parametrize("zeta,slope", [(0.0, 0.0), (0.05, 0.02)])
def test_planing_forces_and_moment_from_their_points_of_application(craft, zeta, slope):
    """Steady planing (w = q = 0, 15 m/s, trim 4 deg): each force where the module notes put it, summed
    with ``M = z_F F_x - x_F F_z`` (body axes, x forward, z down) and turned to earth axes with gravity.
    A sea surface (elevation ``zeta`` up at mid wetted length, rising forward with ``slope``) raises the
    transom immersion by its height at the transom and lowers the trim seen by the bottom by the slope."""
    c = _tilted_drives(craft)
    model = PlaningCraftModel(c, "interceptor")
    h, pr, u, z, th, rpm = c.hull, c.propellers, 15.0, -0.45, math.radians(4.0), 3000.0
    lcg, vcg, b = h.lcg_m, h.vcg_m, h.chine_beam_m
    x_mid = -lcg + h.added_mass_length_m / 2                         # mid wetted length
    d = z + vcg * math.cos(th) + lcg * math.sin(th) + zeta + slope * (-lcg - x_mid)   # keel depth at the transom
    tau = th - slope
    lift, lp, fric, _ = savitsky_planing(u, tau, d, b, h.deadrise_rad, 1025.0, 1.19e-6, h.correlation_allowance)
    assert lift > 0 and d > 0
    la, da, xa = model.actuator_forces(u, tau, 0.5)
    T, eps = model.thrust_n(rpm, u), math.radians(4.0)
    a = vcg - b * math.tan(h.deadrise_rad) / 4                       # friction line below the CG
    x_prop, z_prop = -lcg - pr.x_aft_of_transom_m, vcg + pr.z_below_keel_m
    forces = [((lp - lcg, vcg), (0.0, -lift / math.cos(tau))),      # normal force on the bottom
              ((0.0, a), (-fric, 0.0)),                               # friction along the keel
              ((x_prop, z_prop), (T * math.cos(eps), -T * math.sin(eps))),   # thrust line, bow-up
              ((xa, vcg), (-da, -la))]                               # the device at the transom
    fxb = sum(f[0] for _, f in forces)
    fzb = sum(f[1] for _, f in forces)
    moment = sum(p[1] * f[0] - p[0] * f[1] for p, f in forces)
    mg = c.mass_kg * 9.81
    fx, fz, m = model.forces(u, z, 0.0, th, 0.0, rpm, 0.5, zeta=zeta, slope=slope)
    assert fx == pytest.approx(fxb * math.cos(th) + fzb * math.sin(th), rel=1e-9)
    assert fz == pytest.approx(-fxb * math.sin(th) + fzb * math.cos(th) + mg, rel=1e-9)
    assert m == pytest.approx(moment, rel=1e-9)


def test_heave_and_pitch_damping_and_added_mass_of_a_hull_clear_of_the_water(craft):
    """Out of the water (no Savitsky forces) at 15 m/s only the 2D+t terms change with ``w`` and ``q``:
    transom force ``-U a33 v_T`` (``v_T = w + lcg q``) with its moment, and ``U (A33 w - S1 q)`` of the
    sections ahead; the accelerations divide by mass plus ``A33 = a33 L`` and ``I55 + A55``."""
    model = PlaningCraftModel(craft, "interceptor")
    h, u = craft.hull, 15.0
    a33 = 1025.0 * math.pi / 2 * (h.chine_beam_m / 2) ** 2           # wedge added mass per metre
    L, lcg = h.added_mass_length_m, h.lcg_m
    xT = -lcg
    A33, S1 = a33 * L, a33 * ((xT + L) ** 2 - xT ** 2) / 2
    A55 = a33 * ((xT + L) ** 3 - xT ** 3) / 3
    base = np.array(model.forces(u, -1.0, 0.0, 0.0, 0.0, 3000.0, 0.0))
    for w, q in ((0.2, 0.0), (0.0, 0.1)):
        got = np.array(model.forces(u, -1.0, w, 0.0, q, 3000.0, 0.0)) - base
        f_transom = -u * a33 * (w + lcg * q)
        np.testing.assert_allclose(got, [0.0, f_transom, lcg * f_transom + u * (A33 * w - S1 * q)], atol=1e-6)
    y = [0.0, u, -1.0, 0.2, 0.0, 0.1, 3000.0]
    fx, fz, m = model.forces(u, -1.0, 0.2, 0.0, 0.1, 3000.0, 0.0)
    dy = model.derivatives(y, 3000.0, 0.0)
    I55 = craft.mass_kg * h.pitch_gyration_radius_m ** 2
    assert dy[3] == pytest.approx(fz / (craft.mass_kg + A33)) and dy[5] == pytest.approx(m / (I55 + A55))
    assert dy[1] == pytest.approx(fx / (1.05 * craft.mass_kg))


def test_below_planing_speed_only_the_displacement_model_acts(craft):
    """At 3 m/s (under ``blend_start_kn``), floating at its draft and at the dynamic trim
    ``hump_trim (V / V_hump)^2``: buoyancy balances the weight, no pitch restoring moment is left, and
    the resistance is ``hump_resistance_ratio m g (V / V_hump)^2``."""
    model = PlaningCraftModel(craft, "interceptor")
    dm, u, rpm = craft.displacement_mode, 3.0, 1200.0
    ratio = (u / (dm.hump_speed_kn * KNOT_M_S)) ** 2
    th = math.radians(dm.hump_trim_deg) * ratio
    z = craft.particulars.draft_m - craft.hull.vcg_m * math.cos(th)
    T = model.thrust_n(rpm, u)
    fx, fz, m = model.forces(u, z, 0.0, th, 0.0, rpm, 0.0)
    assert fx == pytest.approx(T * math.cos(th) - dm.hump_resistance_ratio * craft.mass_kg * 9.81 * ratio, rel=1e-9)
    assert fz == pytest.approx(-T * math.sin(th), rel=1e-9)
    assert m == pytest.approx((craft.hull.vcg_m + craft.propellers.z_below_keel_m) * T, rel=1e-9)


def test_the_documented_limits_of_engine_speed_and_wave_height(craft):
    """Equilibria up to twice ``max_rpm`` (8000 rpm); waves up to ``MAX_HS_M`` = 0.1 m unless asked for."""
    model = PlaningCraftModel(craft, "interceptor")
    for call, field in ((lambda: model.steady_state(8000.5), "rpm"), (lambda: SeaConditions(hs_m=0.11), "hs_m")):
        with pytest.raises(ValueError, match=rf"^{field}\b"):
            call()
    assert SeaConditions(hs_m=0.1).hs_m == 0.1 and SeaConditions(hs_m=0.11, beyond_validity=True).hs_m == 0.11


def test_waves_are_averaged_over_the_wetted_length(craft):
    """One wave component seen by a 4 m planing surface has ``|sinc(k L / 2)| = |sin(k L / 2) / (k L / 2)|``
    of the amplitude seen at a point; ``omega`` and ``k`` follow from the elevation, its rate and slope."""
    data = craft.model_dump()
    data["hull"]["added_mass_length_m"] = 1e-3
    point = PlaningCraftModel(planing_craft_from_dict(data), "interceptor")
    model = PlaningCraftModel(craft, "interceptor")
    sea = SeaConditions(hs_m=0.05, tp_s=6.0, n_components=1)
    amp = []
    for m in (model, point):
        m._t = 0.3
        zeta, zeta_dot, slope = m.make_wave_function(sea, 5)(0.0, 0.0)     # at rest: zeta_dot / slope = g / omega
        omega = 9.81 * slope / zeta_dot
        k = omega ** 2 / 9.81
        amp.append(math.hypot(zeta, slope / k))
    x = k * craft.hull.added_mass_length_m / 2
    assert 0.5 < amp[0] / amp[1] == pytest.approx(abs(math.sin(x) / x), rel=1e-6)


@pytest.mark.parametrize("actuator, rpm", [("interceptor", 5000.0), ("interceptor", 6500.0), ("trim_tab", 6500.0)])
def test_an_engine_speed_without_an_equilibrium_is_refused_by_name(craft, actuator, rpm):
    """With the device fully out, well above max_rpm the motion diverges: a SteadyState of NaN
    (6500 rpm, interceptor) or a bare 'math domain error' / OverflowError came out before."""
    model = PlaningCraftModel(craft, actuator)
    with pytest.raises(ValueError, match=r"^rpm: no calm-water equilibrium"):
        model.steady_state(rpm, 1.0)
    assert math.isfinite(model.steady_state(rpm, 0.0).speed_m_s)       # retracted, the same rpm has one


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
def test_a_motion_that_diverges_is_refused_naming_the_sea_or_the_step(craft):
    """Hs 0.5 m (the top of the paper's sea state 2) at 1500 rpm: the quasi-static model's motion
    blows up within a minute; a record of NaN (pitch 1e25 deg before it) came out with only
    numpy's RuntimeWarnings. In calm water a 2 s Runge-Kutta step does the same."""
    model = PlaningCraftModel(craft.perturbed(), "interceptor")
    sea = SeaConditions(hs_m=0.5, tp_s=3.0, beyond_validity=True)
    with pytest.raises(ValueError, match=r"^sea: the motion diverged at .* hs_m 0.5 m"):
        model.simulate(np.full(600, 1500.0), np.full(600, 100.0), sea=sea)
    with pytest.raises(ValueError, match=r"^sample_period_s: the motion diverged at .* step 2 s"):   # calm water
        model.simulate(np.full(5, 3000.0), np.full(5, 50.0), sample_period_s=10.0)


@pytest.mark.parametrize("name_or_path", [None, 5, ""])
def test_load_planing_craft_refuses_what_is_not_a_name_or_path_by_name(name_or_path):
    """None or a number failed in pathlib's words ('expected str, bytes or os.PathLike
    object, not NoneType'), naming nothing; an empty name read the current folder and said
    '.: planing-craft file not found'."""
    with pytest.raises(TypeError, match="^name_or_path: expected a packaged planing-craft name or a file path"):
        load_planing_craft(name_or_path)


def test_load_planing_craft_names_a_folder_or_a_binary_file(tmp_path):
    """A folder was 'planing-craft file not found' although it exists, and a binary file a
    UnicodeDecodeError in the codec's words naming no file."""
    with pytest.raises(PlaningCraftFileError, match="is a folder; expected a planing-craft file"):
        load_planing_craft(tmp_path)
    binary = tmp_path / "craft.toml"
    binary.write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(PlaningCraftFileError, match=r"craft\.toml: not a planing-craft file \(TOML text\) but a binary"):
        load_planing_craft(binary)
    with pytest.raises(PlaningCraftFileError, match="planing-craft file not found"):
        load_planing_craft(tmp_path / "missing.toml")


@pytest.mark.parametrize("k, name", [(0, "speed_m_s"), (1, "tau_rad"), (2, "transom_draft_m"), (9, "flow_angle_rad")])
def test_savitsky_planing_names_an_argument_that_is_not_finite(k, name):
    """A NaN speed, trim or draft (or an infinite flow angle) gave NaN loads without a word."""
    args = [15.0, math.radians(3), 0.3, 2.0, math.radians(20), 1025.0, 1.19e-6, 0.0004, 1.0, 0.0]
    assert all(math.isfinite(x) for x in savitsky_planing(*args))
    args[k] = math.inf if k == 9 else math.nan
    with pytest.raises(ValueError, match=rf"^savitsky_planing: {name}: expected a finite number"):
        savitsky_planing(*args)
    # a dry hull gives no load whatever the rest
    assert savitsky_planing(15.0, math.nan, -0.1, *args[3:]) == (0.0, 0.0, 0.0, 0.0)
