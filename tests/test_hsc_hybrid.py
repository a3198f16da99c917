"""The grey box of the hybrid surge/pitch model: propeller law, device rate, first-order pitch, unit checks."""

import dataclasses

import numpy as np
import pytest

from hybridship.hsc.hybrid import GreyBox, GreyBoxTables, HybridModel
from hybridship.hsc.simulator import PlaningCraftModel
from hybridship.hsc.vessel import load_planing_craft

#: Running trim of the hand-made tables [rad] for the device retracted, half and fully out.
TRIMS = (0.05, 0.04, 0.03)


@pytest.fixture(scope="module")
def craft():
    return load_planing_craft()


@pytest.fixture(scope="module")
def tables():
    """Hand-made equilibria: resistance 2 kN + 40 N s/m x V (+1 kN with the device out), trims :data:`TRIMS`."""
    v = np.arange(0.0, 26.25, 0.25)
    res = np.array([2000.0 + 40.0 * v + 1000.0 * a for a in (0.0, 0.5, 1.0)])
    trim = np.array([np.full(v.size, t) for t in TRIMS])
    return GreyBoxTables(0.0, 0.25, np.array([0.0, 0.5, 1.0]), res, trim)


@pytest.fixture(scope="module")
def grey(craft, tables):
    return GreyBox(craft, "interceptor", tables)


def test_grey_box_thrust_is_the_simulators_propeller_law(craft, grey):
    """``c1 n^2 - c2 n V`` (n in rpm) is the simulator's thrust, falling with speed to zero at J0."""
    model = PlaningCraftModel(craft, "interceptor")
    for rpm, v in ((1000.0, 0.0), (2500.0, 7.5), (4000.0, 20.0)):
        assert grey.c1 * rpm ** 2 - grey.c2 * rpm * v == pytest.approx(model.thrust_n(rpm, v), rel=1e-12)


def test_grey_box_device_moves_at_its_rate_from_the_commands_before_each_sample(craft, grey):
    """A PWM step 10 -> 100 % at sample 1: the fraction during sample k is ``(k - 1) dt / full_stroke_time``."""
    a = grey.actuator_fraction(np.r_[10.0, np.full(29, 100.0)])
    step = 0.1 / craft.interceptor.full_stroke_time_s
    np.testing.assert_allclose(a, np.r_[0.0, np.minimum(np.arange(29) * step, 1.0)], atol=1e-12)


def test_grey_box_pitch_approaches_the_device_trim_exponentially(grey):
    """At the nominal parameters the pitch tends to the table's trim at the device setting with
    the 0.5 s time constant: ``theta_k = theta_ss (1 - exp(-k dt / 0.5))``."""
    U = np.column_stack([np.full(20, 3000.0), np.full(20, 100.0), np.zeros(20)])    # device fully out
    sim = grey.simulate(U, (15.0, 0.0))
    k = np.arange(20)
    np.testing.assert_allclose(sim[:, 1], TRIMS[2] * (1 - np.exp(-k * 0.1 / 0.5)), atol=1e-12)
    U[:, 1] = 55.0                                                                  # half out
    assert grey.simulate(U, (15.0, TRIMS[1]))[-1, 1] == pytest.approx(TRIMS[1], abs=1e-12)


def test_grey_box_rates_by_hand(craft, grey):
    """``dV/dt = (T - R) / ((m + A11) p_m)`` with the surge added mass 5 % of the mass, and the
    trim's thrust-surplus term ``p_thT (T - R) / (m g)``."""
    p = np.array([1.0, 1.0, 1.0, 1.0, 2.0, 0.0, 1.0, 1.0, 0.5, 0.5])
    rpm, v = 3000.0, 10.0
    surplus = PlaningCraftModel(craft, "interceptor").thrust_n(rpm, v) - (2000.0 + 40.0 * v + 1000.0)
    dv, th_ss, got = grey.rates(v, 0.0, rpm, 1.0, p)
    m = craft.mass_kg
    assert got == pytest.approx(surplus, rel=1e-9)
    assert dv == pytest.approx(surplus / (1.05 * m * 2.0), rel=1e-9)
    assert th_ss == pytest.approx(TRIMS[2] + 0.5 * surplus / (m * 9.81), rel=1e-9)


def test_grey_box_rates_give_each_parameter_its_own_term(craft, grey):
    """Every parameter different from 1 and from the others, the device half out: a parameter
    dropped (``p_th0`` is 0 at nominal) or two swapped (``p_R``/``p_aR``, ``p_ths``/``p_ath``,
    ``p_T``/``p_J``) changes the rates. The propeller's two terms come from the simulator's
    thrust at rest and at speed, the resistance and trim from the hand-made tables."""
    p_T, p_J, p_R, p_aR, p_m, p_th0, p_ths, p_ath, p_thT = 1.2, 0.8, 1.1, 0.7, 2.0, 0.01, 0.9, 1.3, 0.5
    p = np.array([p_T, p_J, p_R, p_aR, p_m, p_th0, p_ths, p_ath, p_thT, 0.5])
    rpm, v, a = 3000.0, 10.0, 0.5
    model = PlaningCraftModel(craft, "interceptor")
    t_rest = model.thrust_n(rpm, 0.0)                         # c1 n^2
    t_speed = t_rest - model.thrust_n(rpm, v)                 # c2 n V
    R0, dR = 2000.0 + 40.0 * v, 1000.0 * a                    # retracted, and the device's change
    th0, dth = TRIMS[0], TRIMS[1] - TRIMS[0]
    surplus = p_T * (t_rest - p_J * t_speed) - (p_R * R0 + p_aR * dR)
    m = craft.mass_kg
    dv, th_ss, got = grey.rates(v, 0.0, rpm, a, p)
    assert got == pytest.approx(surplus, rel=1e-9)
    assert dv == pytest.approx(surplus / (1.05 * m * p_m), rel=1e-9)
    assert th_ss == pytest.approx(p_th0 + p_ths * th0 + p_ath * dth + p_thT * surplus / (m * 9.81), rel=1e-9)


def test_grey_box_one_step_by_hand_from_the_measured_outputs_and_inputs_before(craft, grey):
    """One step at the nominal parameters: ``V[k] = V[k-1] + dt (T - R) / (1.05 m)`` and the pitch
    relaxes from the measured ``theta[k-1]`` towards the table's trim, everything at ``k-1`` (engine
    speed, device fraction, measured outputs); the device moves at its rate after a PWM step at
    sample 1 (see the rate test above). A free run is the one-step predictor fed its own outputs."""
    n = 12
    model = PlaningCraftModel(craft, "interceptor")
    U = np.column_stack([np.linspace(2000.0, 3500.0, n), np.r_[10.0, np.full(n - 1, 100.0)], np.zeros(n)])
    Y = np.column_stack([np.linspace(9.0, 13.0, n) + 0.3 * np.sin(np.arange(n)),
                         0.04 + 0.01 * np.cos(np.arange(n))])
    a = np.r_[0.0, np.minimum(np.arange(n - 1) * 0.1 / craft.interceptor.full_stroke_time_s, 1.0)]
    got = grey.one_step(U, Y)
    assert np.isnan(got[0]).all()
    for k in range(1, n):
        v, th, rpm, ak = Y[k - 1, 0], Y[k - 1, 1], U[k - 1, 0], a[k - 1]
        surplus = model.thrust_n(rpm, v) - (2000.0 + 40.0 * v + 1000.0 * ak)
        th_ss = TRIMS[0] + (TRIMS[2] - TRIMS[0]) * ak
        assert got[k, 0] == pytest.approx(v + 0.1 * surplus / (1.05 * craft.mass_kg), rel=1e-12)
        assert got[k, 1] == pytest.approx(th_ss + (th - th_ss) * np.exp(-0.1 / 0.5), rel=1e-12)
    sim = grey.simulate(U, Y[0])
    np.testing.assert_allclose(grey.one_step(U, sim)[1:], sim[1:], rtol=1e-12)


def _record(n=40):
    U = np.column_stack([np.linspace(2000.0, 3000.0, n), np.full(n, 60.0), np.zeros(n)])
    Y = np.column_stack([np.linspace(8.0, 12.0, n), np.full(n, 0.05)])
    return U, Y


class _Residual:
    """A stand-in for a fitted residual ensemble: ``offset + X @ W`` with a spread of zero
    (``W`` None: the offset alone), so the hybrid's predictions can be checked without training."""

    def __init__(self, offset, W=None):
        self.offset, self.W = np.asarray(offset, float), W

    def predict(self, X):
        mean = np.broadcast_to(self.offset, (X.shape[0], 2)).copy()
        if self.W is not None:
            mean += X @ self.W[:X.shape[1]]
        return mean, np.zeros_like(mean)


def _hybrid_with(tables, craft, free, one):
    h = HybridModel(craft, "interceptor", tables=tables)
    h.free_ens, h.one_ens = free, one
    return h


def _varied_record(n=40, seed=0):
    rng = np.random.default_rng(seed)
    U = np.column_stack([rng.uniform(2000.0, 3500.0, n), rng.uniform(20.0, 90.0, n), rng.normal(0.0, 0.3, n)])
    Y = np.column_stack([rng.uniform(8.0, 12.0, n), rng.uniform(0.02, 0.06, n)])
    return U, Y


def test_the_hybrid_is_the_grey_box_plus_the_residual_mean(craft, tables):
    """Free run: the grey box's free run from ``Y_init[n_init - 1]`` plus the free-run residual;
    one step: the grey box's one-step prediction plus the one-step residual (none before ``n_init``)."""
    U, Y = _varied_record()
    h = _hybrid_with(tables, craft, _Residual([0.5, 0.01]), _Residual([-0.25, 0.002]))
    grey = h.grey.simulate(U, Y[4], k0=4)
    free = h.free_run(U, Y[:5], 5)
    assert np.isnan(free[:5]).all()
    np.testing.assert_allclose(free[5:], grey[5:] + [0.5, 0.01], rtol=1e-12)
    np.testing.assert_allclose(h.grey_free_run(U, Y[:5], 5)[5:], grey[5:], rtol=1e-12)
    one = h.one_step(U, Y)
    assert np.isnan(one[:2]).all()
    np.testing.assert_allclose(one[2:], h.grey.one_step(U, Y)[2:] + [-0.25, 0.002], rtol=1e-12)


def test_the_hybrids_residual_reads_nothing_after_the_sample_it_predicts(craft, tables):
    """With a residual that weighs every feature, the prediction of sample ``k`` is unchanged when
    the inputs from ``k`` on (free run), or the inputs and outputs from ``k`` on (one step), change;
    it changes with the inputs just before ``k`` (so the check has teeth)."""
    U, Y = _varied_record()
    rng = np.random.default_rng(1)
    W = rng.normal(0.0, 1e-4, (64, 2))
    h = _hybrid_with(tables, craft, _Residual([0.0, 0.0], W), _Residual([0.0, 0.0], W))
    k = 20
    U2, Y2 = _varied_record(seed=2)
    later_U = np.vstack([U[:k], U2[k:]])
    later_Y = np.vstack([Y[:k], Y2[k:]])
    free = h.free_run(U, Y[:5], 5)
    np.testing.assert_array_equal(h.free_run(later_U, Y[:5], 5)[:k + 1], free[:k + 1])
    one = h.one_step(U, Y)
    np.testing.assert_array_equal(h.one_step(later_U, later_Y)[:k + 1], one[:k + 1])
    # teeth: each input column, and the measured outputs, changed just before k moves the prediction of k
    for col in range(3):
        before = U.copy()
        before[k - 1, col] = U2[k - 1, col]
        assert np.abs(h.free_run(before, Y[:5], 5)[k] - free[k]).max() > 1e-9, col
        assert np.abs(h.one_step(before, Y)[k] - one[k]).max() > 1e-9, col
    Yb = Y.copy()
    Yb[k - 1] = Y2[k - 1]
    assert np.abs(h.one_step(U, Yb)[k] - one[k]).max() > 1e-9


@pytest.mark.parametrize("which,col,value,limit,match", [
    ("U", 0, 8100.0, 8000.0, r"^U: column 0 \(engine speed\) reaches 8100 rpm, beyond twice the craft's max_rpm"),
    ("Y", 1, 0.6, 0.5, r"^Y: column 1 \(pitch\) reaches 0.6; expected radians"),
])
def test_the_hybrid_refuses_rpm_beyond_twice_max_and_pitch_beyond_half_a_radian(craft, tables, which, col, value,
                                                                                 limit, match):
    """Twice ``max_rpm`` (8000 rpm) and 0.5 rad are the documented limits of a craft record."""
    U, Y = _record()
    A = U if which == "U" else Y
    A[5, col] = value
    with pytest.raises(ValueError, match=match):
        HybridModel(craft, "interceptor", tables=tables).fit(U, Y)
    A[5, col] = limit
    GreyBox(craft, "interceptor", tables).fit(U, Y, max_nfev=1)        # at the limit: accepted


def test_tables_extend_below_idle_speed_as_v_squared_and_v_to_rest(craft):
    """Below the idle-speed equilibrium (about 2.1 m/s) the resistance falls as ``V^2`` and the trim as
    ``V``, both to zero at rest; above the top speed they continue along the last segment."""
    t = GreyBoxTables.from_craft(craft, "interceptor", n_rpm=3, act=(0.0, 1.0), dv_m_s=0.5)
    v = t.v0_m_s + t.dv_m_s * np.arange(t.resistance_n.shape[1])
    R, TH = t.resistance_n[0], t.trim_rad[0]
    assert R[0] == 0.0 and TH[0] == 0.0
    below = (v > 0) & (v < 2.0)
    np.testing.assert_allclose(R[below] / v[below] ** 2, R[1] / v[1] ** 2, rtol=1e-12)
    np.testing.assert_allclose(TH[below] / v[below], TH[1] / v[1], rtol=1e-12)
    top = v >= 24.0                                    # beyond the speed at 1.05 max_rpm (about 22 m/s)
    assert np.ptp(np.diff(R[top])) < 1e-9 * R[-1] and np.ptp(np.diff(TH[top])) < 1e-12


def test_every_table_row_holds_the_equilibria_of_its_own_device_setting(craft):
    """Between the idle and the top equilibrium each row is its device setting's calm-water
    equilibria (thrust = resistance, running trim), linearly interpolated in speed; the device
    out changes both (the test above reads the retracted row alone)."""
    model = PlaningCraftModel(craft, "interceptor")
    t = GreyBoxTables.from_craft(craft, "interceptor", n_rpm=3, act=(0.0, 1.0), dv_m_s=0.5)
    v = t.v0_m_s + t.dv_m_s * np.arange(t.resistance_n.shape[1])
    rpms = np.linspace(craft.engines.idle_rpm, 1.05 * craft.engines.max_rpm, 3)
    for row, a in enumerate((0.0, 1.0)):
        eq = model.steady_curve(rpms, a)
        speed = np.array([s.speed_m_s for s in eq])
        thrust = [model.thrust_n(r, s.speed_m_s) for r, s in zip(rpms, eq)]      # = resistance there
        inside = (v >= speed[0]) & (v <= speed[-1])
        assert inside.sum() > 10
        np.testing.assert_allclose(t.resistance_n[row, inside], np.interp(v[inside], speed, thrust), rtol=1e-6)
        np.testing.assert_allclose(t.trim_rad[row, inside], np.interp(v[inside], speed, [s.trim_rad for s in eq]),
                                   rtol=1e-6)
    assert np.abs(t.trim_rad[1] - t.trim_rad[0]).max() > 1e-3


def test_pwm_given_as_a_fraction_up_to_full_drive_is_refused(craft, tables):
    """A PWM column of fractions 0.1..1 (1 = full drive, 100 %) is a unit slip: the device starts at 10 %."""
    U, Y = _record()
    U[:, 1] = np.linspace(0.1, 1.0, U.shape[0])
    with pytest.raises(ValueError, match=r"^U: column 1 \(PWM\) lies within 0..1; .* look like a fraction"):
        HybridModel(craft, "interceptor", tables=tables).fit(U, Y)


@pytest.mark.parametrize("call,name", [
    (lambda g, U, Y: g.simulate(np.where(np.arange(40)[:, None] == 3, np.nan, U), Y[0]), "U"),
    (lambda g, U, Y: g.simulate(U, (np.nan, 0.05)), "y0"),
    (lambda g, U, Y: g.one_step(U, np.where(np.arange(40)[:, None] == 3, np.nan, Y)), "Y"),
    (lambda g, U, Y: g.simulate(U, Y[0], k0=10 ** 6), "k0"),         # an IndexError before
    (lambda g, U, Y: g.simulate(U, Y[0], k0=-3), "k0"),              # counted from the end before
    (lambda g, U, Y: g.simulate(U, Y[0], k0=1.5), "k0"),
    (lambda g, U, Y: g.fit(U, Y, k0=-1, max_nfev=1), "k0"),          # fitted from Y[-1] before
    (lambda g, U, Y: g.fit(U, Y, k0=39, max_nfev=1), "k0"),          # no row after k0 to fit
    (lambda g, U, Y: g.fit(U, Y, max_nfev="5"), "max_nfev"),         # scipy's "'<=' not supported" before
    (lambda g, U, Y: g.fit(U, Y, max_nfev=True), "max_nfev"),        # one evaluation before
    (lambda g, U, Y: g.fit(U, Y, max_nfev=0), "max_nfev"),           # scipy's "`max_nfev` must be" before
])
def test_grey_box_refuses_nan_and_k0_out_of_range_by_name(grey, call, name):
    """NaN inputs gave "cannot convert float NaN to integer"."""
    U, Y = _record()
    with pytest.raises(ValueError, match=rf"^{name}: "):
        call(grey, U, Y)


def test_grey_box_k0_at_the_ends_of_the_record(grey):
    U, Y = _record()
    sim = grey.simulate(U, Y[39], k0=39)
    np.testing.assert_array_equal(sim, np.tile(Y[39], (40, 1)))
    GreyBox(grey.craft, "interceptor", grey.tables).fit(U, Y, k0=38, max_nfev=1)


def test_tables_of_the_other_trim_device_are_refused(craft, tables):
    """Tables carry the device they were computed for; interceptor tables with trim tabs were accepted."""
    t = GreyBoxTables.from_craft(craft, "interceptor", n_rpm=3, act=(0.0, 1.0))
    assert t.actuator == "interceptor"
    with pytest.raises(ValueError, match=r"^tables: computed for the 'interceptor' actuator, expected .* 'trim_tab'"):
        HybridModel(craft, "trim_tab", tables=t)
    with pytest.raises(TypeError, match=r"^tables: expected GreyBoxTables"):
        GreyBox(craft, "interceptor", {"act": [0.0]})
    HybridModel(craft, "interceptor", tables=t)
    assert tables.actuator is None
    HybridModel(craft, "trim_tab", tables=tables)           # hand-made tables: the device is unknown


def test_grey_box_refuses_a_craft_that_is_not_a_planing_craft_by_name(tables):
    """``GreyBox("volcano71", ...)`` was an AttributeError ('str' object has no attribute
    'sensors'); HybridModel loads a name, the grey box takes the loaded file, as the simulator."""
    for craft in ("volcano71", None):
        with pytest.raises(TypeError, match=r"^craft: expected a PlaningCraft"):
            GreyBox(craft, "interceptor", tables)


def test_text_flags_and_a_bad_step_are_refused_by_name():
    """Review: ``generate_trial(progress="no")`` and ``HybridModel.fit(progress="no")`` took
    the text as True; ``GreyBox(dt_s=0)`` was accepted."""
    from hybridship.hsc.simulator import SeaConditions
    from hybridship.hsc.trials import TrialConfig, generate_trial

    craft = load_planing_craft()
    with pytest.raises(ValueError, match="^dt_s: "):
        GreyBox(craft, "interceptor", dt_s=0.0)
    with pytest.raises(TypeError, match="^progress: expected True or False"):
        generate_trial(TrialConfig(sea_state=1, n_samples=300, n_train=200, actuator="interceptor",
                                   sea=SeaConditions()), craft, progress="no")
    with pytest.raises(TypeError, match="^progress: expected True or False"):
        HybridModel(craft, "interceptor").fit(np.zeros((60, 3)), np.zeros((60, 2)), progress="no")


def test_tables_with_more_actuator_rows_are_interpolated_over_all_of_them(craft):
    """Review: the lookup used only the first three rows of ``tables.act``: with five rows
    (0, 0.25, ..., 1) the device's effect stopped growing at 0.5 out (its third row)."""
    v = np.arange(0.0, 26.25, 0.25)
    act = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
    res = np.array([2000.0 + 40.0 * v + 1000.0 * a for a in act])
    trim = np.array([np.full(v.size, 0.05 - 0.02 * a) for a in act])
    grey = GreyBox(craft, "interceptor", GreyBoxTables(0.0, 0.25, act, res, trim))
    for a in (0.0, 0.1, 0.5, 0.6, 0.75, 0.9, 1.0):
        base, r = grey._lookup(grey._R, 10.0, a)
        assert base == pytest.approx(2400.0) and r == pytest.approx(2400.0 + 1000.0 * a)
        assert grey._lookup(grey._TH, 10.0, a)[1] == pytest.approx(0.05 - 0.02 * a)


@pytest.mark.parametrize("act", [(0.0,), (0.5, 1.0), (0.0, 1.0, 0.5), (0.0, 1.5), (0.0, float("nan"))])
def test_actuator_rows_that_cannot_be_interpolated_are_refused_by_name(craft, act):
    """One row (an IndexError at the first lookup), a first row that is not the retracted device
    (the base of the device's changes), unsorted rows or fractions beyond 1 are refused."""
    with pytest.raises(ValueError, match="^act: "):
        GreyBoxTables.from_craft(craft, "interceptor", n_rpm=3, act=act)
    v = np.arange(0.0, 1.0, 0.25)
    t = GreyBoxTables(0.0, 0.25, np.array(act), np.ones((len(act), v.size)), np.zeros((len(act), v.size)))
    with pytest.raises(ValueError, match="^tables.act: "):
        GreyBox(craft, "interceptor", t)


def test_table_grid_arguments_are_refused_by_name(craft):
    """``n_rpm=1`` was an IndexError, ``dv_m_s=0`` a ZeroDivisionError."""
    with pytest.raises(ValueError, match="^n_rpm: "):
        GreyBoxTables.from_craft(craft, "interceptor", n_rpm=1)
    with pytest.raises(ValueError, match="^dv_m_s: "):
        GreyBoxTables.from_craft(craft, "interceptor", n_rpm=3, dv_m_s=0.0)


def test_the_grey_box_steps_at_the_crafts_sample_period(craft, tables):
    """Review: the step defaulted to 0.1 s whatever the craft's sample period: on a craft logged
    at 0.2 s the grey box (and the hybrid) integrated half the time per sample."""
    from hybridship.hsc.vessel import planing_craft_from_dict

    d = craft.model_dump()
    d["sensors"]["sample_period_s"] = 0.2
    slow = planing_craft_from_dict(d)
    assert GreyBox(craft, "interceptor", tables).dt == 0.1
    assert GreyBox(slow, "interceptor", tables).dt == 0.2
    assert GreyBox(slow, "interceptor", tables, dt_s=0.1).dt == 0.1
    assert HybridModel(slow, "interceptor", tables=tables).grey.dt == 0.2
    # the device's rate limit per sample follows: full stroke in 2 s = 10 samples of 0.2 s
    a = GreyBox(slow, "interceptor", tables).actuator_fraction(np.r_[10.0, np.full(14, 100.0)])
    np.testing.assert_allclose(a[1:12], np.minimum(np.arange(11) * 0.2 / craft.interceptor.full_stroke_time_s, 1.0))


def test_a_record_too_short_for_the_residual_ensembles_is_refused_by_name_and_changes_nothing(craft, tables):
    """A 14-row record passed the hybrid's own check and failed in the ensemble's fit ("fit_ensemble:
    need at least 20 training rows"), after the grey box had taken the new record's parameters."""
    from hybridship.hsc.trials import generate_trial, paper_trial

    trial = generate_trial(paper_trial(1, scale=0.05), craft)
    U, Y = trial.arrays("train")
    hybrid = HybridModel(craft, "interceptor", tables=tables, ensemble={"n_members": 2, "max_epochs": 5})
    hybrid.fit(U, Y)
    before = hybrid.grey.parameters()
    with pytest.raises(ValueError, match=r"^U: need at least 22 rows, got 14"):
        hybrid.fit(U[40:54], Y[40:54])
    assert hybrid.grey.parameters() == before


@pytest.mark.parametrize("change, name", [
    (dict(dv_m_s=0.0), "tables.dv_m_s"),                                    # ZeroDivisionError in rates before
    (dict(v0_m_s=np.nan), "tables.v0_m_s"),                                 # NaN rates before
    (dict(trim_rad=np.ones((3, 5))), "tables.trim_rad"),                    # IndexError in rates before
    (dict(resistance_n=np.full((3, 105), np.nan)), "tables.resistance_n"),  # NaN rates before
    (dict(resistance_n=np.ones(3)), "tables.resistance_n"),                 # IndexError at construction before
])
def test_hand_made_tables_the_lookup_cannot_read_are_refused_by_name(craft, tables, change, name):
    bad = dataclasses.replace(tables, **change)
    with pytest.raises(ValueError, match=rf"^{name}: "):
        GreyBox(craft, "interceptor", bad)
    # lists are tables too: they were an AttributeError on .shape
    listed = dataclasses.replace(tables, resistance_n=tables.resistance_n.tolist(), trim_rad=tables.trim_rad.tolist())
    assert GreyBox(craft, "interceptor", listed).rates(10.0, 0.05, 3000.0, 0.5) == \
        GreyBox(craft, "interceptor", tables).rates(10.0, 0.05, 3000.0, 0.5)


@pytest.mark.parametrize("pwm,err,match", [([10.0, np.nan, 50.0], ValueError, "with NaN or inf"),
                                           (50.0, ValueError, r"got shape \(\)"),
                                           ([[10.0, 20.0]], ValueError, r"got shape \(1, 2\)"),
                                           (["10", "20"], TypeError, "real numbers")])
def test_grey_box_actuator_fraction_refuses_a_bad_pwm_record_by_name(grey, pwm, err, match):
    """A NaN duty made that and every later fraction NaN without a word; a single number,
    a 2-D array or text failed with an IndexError or numpy's words, naming nothing."""
    with pytest.raises(err, match=f"^pwm_pct: .*{match}"):
        grey.actuator_fraction(pwm)


def test_grey_box_actuator_fraction_of_an_empty_record_is_empty(grey):
    """No samples, no fractions (an IndexError on cmd[0] before)."""
    assert grey.actuator_fraction(np.array([])).shape == (0,)


def test_grey_box_simulate_refuses_a_starting_state_of_text_by_name(grey):
    """y0 = ("10", "0.05") was read as 10 m/s and 0.05 rad, as the records' text no longer is."""
    U = np.column_stack([np.full(20, 3000.0), np.full(20, 50.0), np.zeros(20)])
    with pytest.raises(ValueError, match=r"^y0: expected \(speed m/s, pitch rad\), two finite numbers"):
        grey.simulate(U, ("10", "0.05"))
    assert grey.simulate(U, (10.0, 0.05)).shape == (20, 2)
