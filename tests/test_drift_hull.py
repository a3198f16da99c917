"""The hull's yaw moment in a drift, learned from earlier failures (hybridship.residual.drift_hull):
the choice and its out-of-sample check, identification where the answer is known, where
forecasts use it, and how the drift benchmark keeps it away from the drifts it scores."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridship.physics.hull import mass_matrices
from hybridship.physics.model import DynamicModel
from hybridship.predictors import HybridPredictor, as_log_arrays
from hybridship.residual.drift_hull import (KEEP_P_VALUE, MIN_FAILURES, MUNK_MULTIPLES, choose_coefficient,
                                            drift_start_rows, munk_coefficient)
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=3, hidden=8, max_epochs=20, patience=5, seed=0)
ZERO = int(np.flatnonzero(MUNK_MULTIPLES == 0.0)[0])


def _bowl(best: float, depth: float = 1.0) -> np.ndarray:
    """A failure's heading error [rad] over the candidates, lowest at the multiple ``best``."""
    return 0.05 + depth * 0.01 * (MUNK_MULTIPLES - best) ** 2


@settings(max_examples=30, deadline=None)
@given(best=st.sampled_from([float(m) for m in MUNK_MULTIPLES if m != 0.0]), n=st.integers(2, 8))
def test_failures_that_agree_give_their_coefficient_from_five_on(best, n):
    """Failures whose errors are lowest at the same multiple: that one is chosen, and every
    left-out failure gains, so the signed-rank test gives 2**-n. It is kept from five
    failures on (1/32 < 0.05); four that agree (1/16) are too few to tell from chance."""
    obj = np.column_stack([_bowl(best, 1.0 + 0.3 * j) for j in range(n)])
    c = choose_coefficient(obj, 0.005)
    assert c.munk_multiple == best and c.n_left_out_gains == n
    assert c.p_value == pytest.approx(2.0 ** -n)
    assert c.adopted == (n >= MIN_FAILURES) == (c.p_value < KEEP_P_VALUE)
    assert c.coefficient_rad_per_m2 == (pytest.approx(best * 0.005) if n >= MIN_FAILURES else 0.0)
    assert c.error_deg < c.error_zero_deg and c.n_failures == n


def test_a_mean_gain_that_half_the_failures_pay_for_is_not_kept():
    """Twenty failures, as on our own twenty of 2026-11-30: eleven gain a little from +1 and
    nine lose a little more each. Every fold chooses +1, and the left-out failures' mean error
    is below that of k = 0 (the check before the signed-rank test kept it), but the gains
    are no more often or larger than the losses, so it is not kept."""
    gain, loss = 0.01, 0.011
    e0 = 0.05 + 0.001 * np.arange(20)
    obj = np.vstack([e0 + 0.1, e0, e0 - np.r_[np.full(11, gain), np.full(9, -loss)]])     # rows: -1, 0, +1
    c = choose_coefficient(obj, 0.005, multiples=[-1.0, 0.0, 1.0])
    assert c.munk_multiple == 1.0 and c.error_left_out_deg < c.error_zero_deg
    assert c.n_left_out_gains == 11 and c.p_value > 0.5
    assert not c.adopted and c.coefficient_rad_per_m2 == 0.0


def test_a_fold_that_chooses_zero_is_dropped_from_the_test():
    """Five failures that all want +1, but the fifth is indifferent to it: its fold's choice
    gains it nothing (a zero gain), which is dropped, so four gains remain (p = 1/16, not
    kept), whatever scipy's version (before 1.15 its normal approximation gave 0.034)."""
    obj = np.array([[3.0, 3.0, 3.0, 3.0, 0.0],                       # rows: multiples -1, 0, +1
                    [2.0, 2.0, 2.0, 2.0, 1.0],
                    [1.0, 1.1, 1.2, 1.3, 1.0]])
    c = choose_coefficient(obj, 0.005, multiples=[-1.0, 0.0, 1.0])
    assert c.munk_multiple == 1.0 and c.n_failures == 5 and c.n_left_out_gains == 4
    assert c.p_value == 1 / 16 and not c.adopted
    flat = choose_coefficient(np.ones((3, 5)), 0.005, multiples=[-1.0, 0.0, 1.0])
    assert flat.p_value == 1.0 and flat.n_left_out_gains == 0 and not flat.adopted     # all gains 0


def test_a_signed_rank_pass_with_a_mean_loss_is_not_kept():
    """Nine failures gain a little (about g / 2) and the tenth loses much (10 g): the
    signed-rank test passes (T = 45 of 55, p = 43/1024) but the left-out mean error is above
    that of k = 0, so k stays 0: both checks are needed."""
    g = 0.001
    a = 0.05 + 0.001 * np.arange(10)
    small = g / 2 * (1 + 0.05 * np.arange(9))                            # distinct: no ties
    obj = np.vstack([np.r_[a[:9] - small, a[9] - g / 4], a, np.r_[a[:9] - g, a[9] + 10 * g]])   # -1, 0, +1
    c = choose_coefficient(obj, 0.005, multiples=[-1.0, 0.0, 1.0])
    assert c.munk_multiple == -1.0 and c.n_left_out_gains == 9 and c.p_value == pytest.approx(43 / 1024)
    assert c.error_left_out_deg > c.error_zero_deg and not c.adopted


def test_a_choice_that_does_not_carry_over_to_a_left_out_failure_is_not_kept():
    """Two failures want +1 and one, much more sensitive, wants -1: the pooled choice lowers
    the in-sample error, but left out in turn each failure gets a coefficient that hurts it
    more than 0 would, so k stays 0. Excluding a failure leaves it out of the choice."""
    obj = np.column_stack([_bowl(1.0), _bowl(1.0), _bowl(-1.0, 20.0)])
    c = choose_coefficient(obj, 0.005)
    assert c.error_deg < c.error_zero_deg
    assert not c.adopted and c.coefficient_rad_per_m2 == 0.0 and c.error_left_out_deg > c.error_zero_deg
    alone = choose_coefficient(obj, 0.005, exclude=2)
    assert alone.munk_multiple == 1.0 and alone.n_failures == 2 and alone.n_left_out_gains == 2
    assert not alone.adopted and alone.p_value == 0.25                  # two that agree are too few
    # its errors are those of the two failures used (each bowl 0.05 rad at +1 and 0.06 at 0, and
    # each left out gets the other's +1), not pooled with the excluded one (0.85 at +1, 0.25 at 0)
    assert alone.error_deg == pytest.approx(np.degrees(0.05), rel=1e-12)
    assert alone.error_zero_deg == pytest.approx(np.degrees(0.06), rel=1e-12)
    assert alone.error_left_out_deg == pytest.approx(np.degrees(0.05), rel=1e-12)
    one = choose_coefficient(obj[:, :1], 0.005)
    assert not one.adopted and one.error_left_out_deg is None and one.p_value is None    # no failure to check it on


def test_a_choice_that_only_ties_zero_out_of_sample_is_not_kept():
    """Kept only if the left-out error is *below* that of ``k = 0``: failure 0 wants +1, failure 1
    wants -1; pooled, +1 wins (3/16 against 3/8 at 0), but each left out gets the other's
    choice, 1/2 and 1/4, whose mean 3/8 only equals the error at 0 (binary fractions: exact)."""
    obj = np.array([[0.5, 0.125], [0.375, 0.375], [0.125, 0.25]])        # rows: multiples -1, 0, 1
    c = choose_coefficient(obj, 0.005, multiples=[-1.0, 0.0, 1.0])
    assert c.munk_multiple == 1.0 and c.error_left_out_deg == c.error_zero_deg == pytest.approx(np.degrees(0.375))
    assert not c.adopted and c.coefficient_rad_per_m2 == 0.0


def test_bad_objectives_are_refused():
    with pytest.raises(ValueError, match=r"objective_rad: expected shape \(81, n_failures\)"):
        choose_coefficient(np.zeros((5, 3)), 0.005)
    with pytest.raises(ValueError, match="finite errors"):
        choose_coefficient(np.full((81, 2), np.nan), 0.005)
    with pytest.raises(ValueError, match="must contain 0"):
        choose_coefficient(np.zeros((2, 3)), 0.005, multiples=[1.0, 2.0])
    with pytest.raises(ValueError, match="must contain 0"):
        choose_coefficient(np.zeros((3, 3)), 0.005, multiples=[0.0, 1.0, 0.0])
    for bad in (3, -1, 1.5, True):          # a failure the objective does not hold, or not a column number
        with pytest.raises(ValueError, match=r"exclude: expected a failure from 0 to 2"):
            choose_coefficient(np.zeros((81, 3)), 0.005, exclude=bad)


def test_the_coefficient_is_the_added_mass_yaw_moment_per_u_v_of_fossen(model):
    """``C_A(nu) nu`` in yaw is ``-(Y_vdot - X_udot) u v`` at ``r = 0`` (Fossen 2021, eq. 6.53);
    moved to the right-hand side and divided by the total yaw inertia ``M_33`` it is the yaw
    acceleration ``-c u v`` with ``c = (M_A22 - M_A11) / M_33``, positive for a hull longer
    than wide (the Munk moment turns it broadside to the flow)."""
    from hybridship.physics.hull import coriolis_added_mass

    M_RB, M_A = mass_matrices(model.vessel)
    X_udot, Y_vdot = -M_A[0, 0], -M_A[1, 1]
    u, v = 1.5, -0.4
    nu = np.array([u, v, 0.0])
    yaw = (coriolis_added_mass(nu, M_A) @ nu)[2]
    assert yaw == pytest.approx(-(Y_vdot - X_udot) * u * v, rel=1e-12)
    c = munk_coefficient(model)
    assert c > 0
    assert -yaw / (M_RB + M_A)[2, 2] == pytest.approx(-c * u * v, rel=1e-12)


def test_drift_starts_lie_in_the_first_drift_and_its_gap_free_segment():
    dp, seg = np.r_[np.ones(100), np.zeros(200)], np.zeros(300, int)
    np.testing.assert_array_equal(drift_start_rows(dp, seg, 60, 10), np.arange(100, 240, 10))
    assert drift_start_rows(np.zeros(300), seg, 60, 10).size == 0      # a manoeuvring log
    restarted = np.r_[np.ones(100), np.zeros(100), np.ones(100)]          # DP back on after 100 s
    np.testing.assert_array_equal(drift_start_rows(restarted, seg, 60, 10), np.arange(100, 140, 10))
    assert drift_start_rows(np.ones(300), seg, 60, 10).size == 0
    gap = np.r_[np.zeros(180, int), np.ones(120, int)]                    # a gap in the log at row 180
    np.testing.assert_array_equal(drift_start_rows(dp, gap, 60, 10), np.arange(100, 120, 10))
    # a start every row: the last is the one whose horizon ends on the drift's last row
    # (299, 199 before DP comes back on, 179 before the gap), not one earlier
    np.testing.assert_array_equal(drift_start_rows(dp, seg, 60, 1), np.arange(100, 240))
    np.testing.assert_array_equal(drift_start_rows(restarted, seg, 60, 1), np.arange(100, 140))
    np.testing.assert_array_equal(drift_start_rows(dp, gap, 60, 1), np.arange(100, 120))


def test_drift_starts_refuse_counts_that_are_not_whole_numbers_and_flags_of_another_length():
    """A negative horizon gave starts up to the log's last row and beyond it (row 300 of 300),
    a fractional one float rows, a spacing of 0 or 2.7 rows became 1 or 2 without a word, and
    a segment label of another length than the flags failed in numpy's broadcasting words."""
    dp, seg = np.r_[np.ones(100), np.zeros(200)], np.zeros(300, int)
    for horizon in (-10, 60.5, "60", True):
        with pytest.raises(ValueError, match=r"^drift_start_rows: horizon_steps: expected a whole number >= 0"):
            drift_start_rows(dp, seg, horizon, 10)
    for every in (0, 2.7, -1):
        with pytest.raises(ValueError, match=r"^drift_start_rows: every_steps: expected a whole number >= 1"):
            drift_start_rows(dp, seg, 60, every)
    with pytest.raises(ValueError, match=r"^drift_start_rows: dp_active, segment_id: expected two 1-D arrays of "
                                         r"one length, got shapes \(300,\) and \(200,\)"):
        drift_start_rows(dp, seg[:200], 60, 10)
    np.testing.assert_array_equal(drift_start_rows(dp, seg, np.int64(60), np.int32(10)), np.arange(100, 240, 10))
    np.testing.assert_array_equal(drift_start_rows(dp, seg, 0, 100), [100, 200])


def _wind_drift_logs(model, sway_added_mass_scale: float, seeds=(20, 21, 22, 23, 24, 25)):
    """Failures of a ship whose sway added mass is the model's times the scale, under a steady
    wind the model knows: the only model error after a failure is in the hull."""
    spec = model.vessel.model_dump()
    spec["true_vessel"] = {"added_mass_scale": (1.0, sway_added_mass_scale, 1.0)}
    true = DynamicModel(type(model.vessel).model_validate(spec), true_vessel=True)
    return [physics_log(true, duration_s=1100, t_shutdown_s=800, seed=s, wind=(12.0, float(s))) for s in seeds]


@pytest.fixture(scope="module")
def heavy_sway(model):
    """Six failures of a ship with 1.6 times the model's sway added mass, and a hybrid fitted on them
    (the drift benchmark needs five others per scored failure)."""
    logs = _wind_drift_logs(model, 1.6)
    return logs, HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs)


@pytest.mark.parametrize("scale", [0.6, 1.6])
def test_a_sway_added_mass_error_is_learned_as_its_munk_moment(model, scale, heavy_sway):
    """The true ship's Munk moment in yaw is ``-(s m_22 - m_11) u v / m_33``: against the
    model's, the forecasts miss ``-(s - 1) m_22 / (m_22 - m_11)`` times the model's Munk
    coefficient. fit learns a multiple of that sign and size (0.4 to 1.25 times it: the sway
    inertia differs too, so the best yaw term is not the Munk difference alone), keeps it,
    and it lowers the failures' heading error."""
    _, M_A = mass_matrices(model.vessel)
    want = -(scale - 1.0) * M_A[1, 1] / (M_A[1, 1] - M_A[0, 0])
    # the lighter ship from five failures, the fewest fit chooses from
    hp = heavy_sway[1] if scale == 1.6 else \
        HybridPredictor(model.vessel, ensemble_config=TINY).fit(_wind_drift_logs(model, scale, (20, 21, 22, 23, 24)))
    info = hp.training_info["drift_hull"]
    assert info["adopted"] and 0.4 <= info["munk_multiple"] / want <= 1.25, (info, want)
    assert hp.drift_yaw_uv_rad_per_m2 == pytest.approx(info["munk_multiple"] * munk_coefficient(hp.model))
    assert info["error_deg"] < 0.8 * info["error_zero_deg"] and info["n_failures"] == (6 if scale == 1.6 else 5)
    assert info["n_left_out_gains"] == info["n_failures"] and info["p_value"] < KEEP_P_VALUE


def _recording_objective(monkeypatch) -> list:
    """The objectives HybridPredictor.drift_hull_objective returns from now on (computed once, kept)."""
    seen, original = [], HybridPredictor.drift_hull_objective

    def recorded(self, logs, horizon_s=60.0):
        seen.append(original(self, logs, horizon_s))
        return seen[-1]

    monkeypatch.setattr(HybridPredictor, "drift_hull_objective", recorded)
    return seen


def test_a_hull_without_error_gets_none(model, monkeypatch):
    """The model's own hull (five failures): the forecasts' heading error is lowest at k = 0 and
    the fit keeps none."""
    logs = _wind_drift_logs(model, 1.0, (20, 21, 22, 23, 24))
    seen = _recording_objective(monkeypatch)
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs)
    info = hp.training_info["drift_hull"]
    assert not info["adopted"] and hp.drift_yaw_uv_rad_per_m2 == 0.0
    objective = seen[0].mean(axis=1)                    # the one fit chose on
    assert objective.argmin() == ZERO and objective[ZERO] < 0.5 * objective[[ZERO - 10, ZERO + 10]].min()


def test_the_batched_choice_scores_what_forecasts_give(model, heavy_sway):
    """Each candidate's objective is the mean heading error of ordinary forecasts from the same
    starts with that coefficient (the batch over candidates and starts changes nothing)."""
    import copy

    from hybridship.frames import wrap_pi

    logs, fitted = heavy_sway
    hp = copy.deepcopy(fitted)
    a = as_log_arrays(logs[0], model.vessel)
    objective = hp.drift_hull_objective([a])[:, 0]
    rows = drift_start_rows(a.dp_active, a.segment_id, 60, 10)
    truth = a.eta[rows[:, None] + np.arange(1, 61)[None, :], 2]
    for j in (ZERO - 12, ZERO + 7):
        hp.drift_yaw_uv_rad_per_m2 = MUNK_MULTIPLES[j] * munk_coefficient(hp.model)
        fc = hp.forecast(a, a.time_s[rows], 60.0)
        assert objective[j] == pytest.approx(np.abs(wrap_pi(fc.eta[:, 1:, 2] - truth)).mean(), rel=1e-12)


def test_the_objective_takes_one_log_as_a_list_of_one_and_refuses_none(model, heavy_sway):
    """One DataFrame was iterated as its column names ("time_s: unsupported file extension"),
    one path as its characters, and no log gave an empty objective without a word."""
    import copy

    logs, fitted = heavy_sway
    hp = copy.deepcopy(fitted)
    np.testing.assert_array_equal(hp.drift_hull_objective(logs[0], 30.0), hp.drift_hull_objective([logs[0]], 30.0))
    with pytest.raises(ValueError, match="^logs: expected at least one log"):
        hp.drift_hull_objective([], 30.0)


def test_the_objective_refuses_a_horizon_that_is_not_whole_steps_of_the_log(model, heavy_sway):
    """drift_hull_objective rounded the horizon to the log's step itself (60.4 s scored 60 s, 0.6 s
    one step of 1 s); it now counts the steps with the forecast's own horizon_steps."""
    from hybridship.predictors.forecast_setup import HorizonError

    logs, hp = heavy_sway
    for horizon in (60.4, 0.6):
        with pytest.raises(HorizonError, match=rf"^horizon_s: {horizon:g} s is not a whole number of the log's "
                                               rf"steps \(1 s\)"):
            hp.drift_hull_objective(logs[0], horizon)


def test_the_filter_uses_the_coefficient_after_a_failure_so_the_yaw_load_does_not_absorb_it(model, heavy_sway):
    """Given the true ship's Munk difference, the environment estimator's yaw load moves less
    during the drift than without it (it no longer takes up the hull's error); before the
    failure nothing changes. The fitted hybrid's filter uses its own coefficient."""
    from hybridship.residual.environment import LOAD

    logs, hp = heavy_sway
    _, M_A = mass_matrices(model.vessel)
    k = -0.6 * M_A[1, 1] / (M_A[1, 1] - M_A[0, 0]) * munk_coefficient(model)
    moved = {0.0: [], k: []}
    for log in logs:
        a = as_log_arrays(log, model.vessel)
        i0 = int(np.flatnonzero(a.dp_active == 0)[0])
        rows = np.array([i0 - 1, i0 + 60, i0 + 120, i0 + 240])
        yaw_load = {c: hp.estimator.run(a, rows, drift_yaw_uv_rad_per_m2=c).x[:, LOAD.start + 2] for c in moved}
        assert yaw_load[k][0] == yaw_load[0.0][0]                   # on station: the same filter
        for c in moved:
            moved[c].append(np.abs(yaw_load[c][1:] - yaw_load[c][0]))
    assert np.mean(moved[k]) < 0.5 * np.mean(moved[0.0])
    a = as_log_arrays(logs[1], model.vessel)
    rows = np.arange(500, 1000, 7)
    alone = [hp.estimator.run(a, rows, drift_yaw_uv_rad_per_m2=c) for c in (k, 0.0, -k)]
    with hp.estimator.sharing_station_keeping():    # the station keeping filtered once: the same estimates
        for c, e in zip((k, 0.0, -k, k), alone + alone[:1]):
            shared = hp.estimator.run(a, rows, drift_yaw_uv_rad_per_m2=c)
            np.testing.assert_array_equal(shared.x, e.x)
            np.testing.assert_array_equal(shared.P, e.P)
        with hp.estimator.sharing_station_keeping():         # nested: the outer context decides
            pass
        assert hp.estimator._shared_runs is not None
    assert hp._filter_drift_yaw() == hp.drift_yaw_uv_rad_per_m2 != 0.0
    with pytest.raises(ValueError, match=r"drift_yaw_uv_rad_per_m2: expected a finite number"):
        hp.estimator.run(as_log_arrays(logs[0], model.vessel), [10], drift_yaw_uv_rad_per_m2=float("nan"))


def test_a_gap_in_a_training_drift_is_not_scored_across(model, heavy_sway):
    """A training log missing 20 s of its drift: fit still chooses, from the drift before the
    gap; five failures are enough to choose."""
    logs = [log.copy() for log in heavy_sway[0][:5]]
    logs[0] = logs[0].drop(index=range(900, 920)).reset_index(drop=True)
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs)
    assert hp.training_info["drift_hull"]["n_failures"] == 5 and hp.drift_yaw_uv_rad_per_m2 != 0.0


def test_fit_needs_five_failures_and_the_option(model, heavy_sway):
    logs = heavy_sway[0][:5]
    four = HybridPredictor(model.vessel, ensemble_config=TINY).fit(logs[:4])
    off = HybridPredictor(model.vessel, ensemble_config=TINY, drift_hull=False).fit(logs)
    held = HybridPredictor(model.vessel, ensemble_config=TINY, stop_after_failure=False).fit(logs)
    for hp in (four, off, held):        # with five failures and the option, it does: the tests above
        assert "drift_hull" not in hp.training_info and hp.drift_yaw_uv_rad_per_m2 == 0.0


def test_only_forecasts_that_start_after_a_failure_use_it(model):
    """A start during station keeping is forecast as without the coefficient; one after the
    failure is not; each start gets the same forecast alone and in a batch."""
    log = _wind_drift_logs(model, 1.6, seeds=(30,))[0]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit([log])
    assert hp.drift_yaw_uv_rad_per_m2 == 0.0
    starts = [700.0, 820.0]
    before = hp.forecast(log, starts, 60.0)
    hp.drift_yaw_uv_rad_per_m2 = -0.5 * munk_coefficient(hp.model)
    after = hp.forecast(log, starts, 60.0)
    np.testing.assert_array_equal(after.eta[0], before.eta[0])
    assert np.abs(after.eta[1, -1, 2] - before.eta[1, -1, 2]) > 1e-4
    np.testing.assert_allclose(hp.forecast(log, starts[1:], 60.0).eta[0], after.eta[1], rtol=0, atol=1e-12)
    import copy                                  # the 900-s mean environment (hybrid_mean_bias) never uses it

    mean = copy.copy(hp)
    mean.environment = "mean"
    with_k = mean.forecast(log, starts, 60.0).eta
    mean.drift_yaw_uv_rad_per_m2 = 0.0
    np.testing.assert_array_equal(with_k, mean.forecast(log, starts, 60.0).eta)


@pytest.fixture(scope="module")
def left_out_choices(model, heavy_sway):
    """The drift benchmark's coefficient for each failure of ``heavy_sway`` (chosen on the other
    failures), computed once for the tests below: the predictor after the choice (the benchmark
    leaves it at 0), the logs, the objectives computed on the way, and the choices."""
    import copy

    from hybridship.evaluation.drift import _drift_hull_per_log

    logs = [as_log_arrays(x, model.vessel) for x in heavy_sway[0]]
    hp = copy.deepcopy(heavy_sway[1])                 # the benchmark changes the coefficient
    with pytest.MonkeyPatch.context() as mp:
        seen = _recording_objective(mp)
        _, per_log = _drift_hull_per_log(hp, logs, True, 60.0, list("abcdef"), lambda m: None)
    return hp, logs, seen, per_log


def test_the_drift_benchmark_chooses_it_without_the_scored_failure(heavy_sway, left_out_choices):
    """Scored on its own training logs, each failure is forecast with the coefficient chosen
    on the other failures (never one that saw it); with fewer than five others, with none;
    scored on other logs, with fit's."""
    from hybridship.evaluation.drift import _drift_hull_per_log

    import copy

    hp, logs, seen, per_log = left_out_choices
    hp = copy.deepcopy(hp)
    fitted = heavy_sway[1].drift_yaw_uv_rad_per_m2
    assert len(seen) == 1 and seen[0].shape[1] == 6     # one objective over all six failures
    objective = seen[0]
    for k, c in enumerate(per_log):
        assert c == choose_coefficient(objective, munk_coefficient(hp.model), exclude=k)
        assert c.n_failures == 5 and c.adopted
    from hybridship.evaluation.drift import _drift_hull_table

    table = _drift_hull_table(hp, per_log, list("abcdef"))      # drift_hull.csv: what each failure got, and why
    np.testing.assert_array_equal(table.error_left_out_deg, [c.error_left_out_deg for c in per_log])
    np.testing.assert_array_equal(table.coefficient_rad_per_m2, [c.coefficient_rad_per_m2 for c in per_log])
    np.testing.assert_array_equal(table.p_value, [c.p_value for c in per_log])
    assert list(table.n_failures) == [5] * 6 and set(table.source) == {"other logs' failures"}
    assert hp.drift_yaw_uv_rad_per_m2 == 0.0
    _, few = _drift_hull_per_log(hp, logs[:5], True, 60.0, list("abcde"), lambda m: None)
    assert few == [None] * 5
    hp.drift_yaw_uv_rad_per_m2 = fitted
    _, other = _drift_hull_per_log(hp, logs[:1], False, 60.0, ["a"], lambda m: None)
    assert other is None and hp.drift_yaw_uv_rad_per_m2 == fitted


def test_the_drift_benchmarks_table_gives_fits_choice_to_every_other_test_log():
    """Scored on other logs (no per-log choice), drift_hull.csv gives every test log fit's
    coefficient and fit's evidence, from the training logs' failures; where fit chose none
    (too few failures, or the option off), "none", 0 and no evidence."""
    from types import SimpleNamespace

    from hybridship.evaluation.drift import _drift_hull_table

    choice = choose_coefficient(np.column_stack([_bowl(1.0, 1.0 + 0.3 * j) for j in range(5)]), 0.005)
    info = {**choice.as_dict(), "horizon_s": 60.0, "start_every_s": 10.0}          # as fit records it
    fitted = SimpleNamespace(training_info={"drift_hull": info}, drift_yaw_uv_rad_per_m2=0.005)
    table = _drift_hull_table(fitted, None, ["a", "b"])
    assert list(table.log) == ["a", "b"] and set(table.source) == {"training logs' failures"}
    assert list(table.coefficient_rad_per_m2) == [0.005, 0.005] and list(table.munk_multiple) == [1.0, 1.0]
    assert table.adopted.all() and list(table.n_failures) == [5, 5] and list(table.n_left_out_gains) == [5, 5]
    np.testing.assert_allclose(table.p_value, 1 / 32)
    np.testing.assert_allclose(table.error_deg, np.degrees(0.05))                  # every bowl at +1
    none = _drift_hull_table(SimpleNamespace(training_info={}, drift_yaw_uv_rad_per_m2=0.0), None, ["a"])
    assert list(none.source) == ["none"] and list(none.coefficient_rad_per_m2) == [0.0] and not none.adopted[0]
    assert none[["munk_multiple", "n_failures", "error_deg", "p_value"]].isna().all().all()


def test_the_drift_benchmark_forecasts_each_failure_with_its_own_coefficient(left_out_choices):
    """The benchmark's forecasts of failure k use per_log_hull[k] (and 0 for None), the spread
    after a failure is calibrated on errors with that coefficient, and the model is left at 0."""
    import copy

    from hybridship.evaluation import drift

    hp, arrays, _, per_log = left_out_choices
    hp, per_log = copy.deepcopy(hp), list(per_log)
    per_log[1] = None
    seen = []
    real = hp.after_stop_errors

    def spy(logs_, **kw):
        seen.append(hp.drift_yaw_uv_rad_per_m2)
        return real(logs_, **kw)

    hp.after_stop_errors = spy
    _, per_log_cal = drift._calibrate_after_stop(hp, arrays, True, 0, 0, 20, 60.0, lambda m: None, per_log)
    assert hp.drift_yaw_uv_rad_per_m2 == 0.0
    want = [0.0 if c is None else c.coefficient_rad_per_m2 for c in per_log]
    assert want[1] == 0.0 and sum(w != 0.0 for w in want) >= 2          # the wiring is tested with both
    assert sorted(set(seen)) == sorted(set(want)) and len(per_log_cal) == 6
    fc, _, pick, _ = drift._forecast_after_failures({"hybrid": (hp, {})}, arrays, 20, 60.0, (60,), hp,
                                                    per_log_cal, per_log)
    for k, a in enumerate(arrays):
        hp.drift_yaw_uv_rad_per_m2 = want[k]
        hp.calibration["after_stop"] = per_log_cal[k]
        p, _, _ = drift.metrics.drift_forecasts(hp, a, n_intervals=20, horizons_s=tuple(range(1, 61)))
        np.testing.assert_array_equal(fc["hybrid"][k][0], p)


def test_the_drift_benchmark_refuses_test_logs_that_are_partly_training_logs(tmp_path, model):
    """The same files as the training logs are scored leave one out (the same list); a test
    folder sharing only some of them is refused, naming how many."""
    from hybridship.evaluation.drift import _benchmark_logs

    files = []
    for s in (1, 2, 3):
        f = tmp_path / f"log{s}.csv"
        f.write_text("x")
        files.append(f)
    train, _, test, _ = _benchmark_logs(files, [tmp_path / "log1.csv", files[1], files[2]], 3, 0, print)
    assert test is train
    with pytest.raises(ValueError, match="test: 1 of the test logs are also training logs"):
        _benchmark_logs(files[:2], [files[1], tmp_path / "other.csv"], 3, 0, print)
    other = [tmp_path / "a.csv"]
    assert _benchmark_logs(files, other, 3, 0, print)[2] == other


def test_the_drift_benchmark_chooses_for_a_failure_without_reading_its_drift(model, heavy_sway, left_out_choices):
    """Proof by change, scored on the training logs: failure k's drift (every sample after its
    shutdown) moved, the hull's yaw coefficient and the spread after a failure that k is scored
    with stay exactly as they were, while those of the other failures, chosen with k's drift
    among theirs, move."""
    import copy

    from hybridship.evaluation.drift import _calibrate_after_stop, _drift_hull_per_log

    hp, logs, _, per_log = left_out_choices
    k = 2
    frame = heavy_sway[0][k].copy()
    after = frame.dp_active.to_numpy() == 0
    frame.loc[after, "heading_deg"] = (frame.loc[after, "heading_deg"]
                                       + 0.2 * np.arange(int(after.sum()))) % 360.0
    frame.loc[after, ["north_m", "east_m"]] += np.outer(np.arange(int(after.sum())), [0.04, -0.02])
    changed = list(logs)
    changed[k] = as_log_arrays(frame, model.vessel)
    hull = per_log                                      # chosen on the logs as logged (the fixture)
    _, cal = _calibrate_after_stop(copy.deepcopy(hp), logs, True, 0, 0, 20, 60.0, lambda m: None, hull)
    hp_changed = copy.deepcopy(hp)
    _, hull_changed = _drift_hull_per_log(hp_changed, changed, True, 60.0, list("abcdef"), lambda m: None)
    _, cal_changed = _calibrate_after_stop(hp_changed, changed, True, 0, 0, 20, 60.0, lambda m: None, hull_changed)
    assert hull_changed[k] == hull[k]
    for part in ("position", "heading"):
        np.testing.assert_array_equal(cal_changed[k][part].scale, cal[k][part].scale)
    others = [j for j in range(len(logs)) if j != k]
    assert all(hull_changed[j] != hull[j] for j in others)
    assert all(not np.array_equal(cal_changed[j]["heading"].scale, cal[j]["heading"].scale) for j in others)


def test_the_drift_benchmark_turns_the_yaw_load_per_failure_on_the_other_failures(heavy_sway, left_out_choices,
                                                                                   monkeypatch):
    """``wave_turned_yaw_load="auto"`` scored on the training logs: each failure gets the yaw load
    chosen on the other failures' errors (its own play no part), the hull's yaw moment is chosen
    from the objective with that yaw load, the spread after a failure is calibrated per setting
    of both, and each failure is forecast with its own; the model is left held."""
    import copy
    from types import SimpleNamespace

    from hybridship.evaluation import drift
    from hybridship.residual.environment import EnvironmentConfig

    hp, logs, _, _ = left_out_choices
    hp = copy.deepcopy(hp)
    hp.environment_config = EnvironmentConfig(wave_turned_yaw_load="auto")
    hp.wave_yaw_turned = True                           # fit's choice, made on the scored drifts
    held = np.full(6, 0.05)
    turned = held - np.array([-0.5, 0.01, 0.02, 0.03, 0.04, 0.05])     # all gain but the first, which loses much
    monkeypatch.setattr(HybridPredictor, "wave_yaw_errors", lambda self, logs_, h: np.stack([held, turned]))
    _, wave = drift._wave_yaw_per_log(hp, logs, True, 60.0, list("abcdef"), lambda m: None)
    assert [c["turned"] for c in wave] == [True] + [False] * 5 and not hp.wave_yaw_turned
    assert wave[0]["p_value"] == pytest.approx(1 / 32) and {c["n_failures"] for c in wave} == {5}
    table = drift._wave_yaw_table(hp, wave, list("abcdef"))     # wave_yaw_load.csv
    assert list(table.turned) == [True] + [False] * 5 and set(table.source) == {"other logs' failures"}
    np.testing.assert_allclose(table.turned_deg[0], np.degrees(turned[1:].mean()))
    # the hull's objective of each yaw load (made-up bowls: best at +1 Munk held, -1 turned)
    asked = []

    def objective(self, logs_, horizon_s=60.0):
        asked.append(self.wave_yaw_turned)
        return np.column_stack([_bowl(-1.0 if self.wave_yaw_turned else 1.0, 1.0 + 0.1 * j) for j in range(6)])

    monkeypatch.setattr(HybridPredictor, "drift_hull_objective", objective)
    _, hull = drift._drift_hull_per_log(hp, logs, True, 60.0, list("abcdef"), lambda m: None, wave)
    assert sorted(asked) == [False, True] and not hp.wave_yaw_turned
    assert [c.munk_multiple for c in hull] == [-1.0] + [1.0] * 5
    # the spread after a failure: the other failures' errors with each failure's own settings
    seen, real = [], hp.after_stop_errors
    errors = real(logs, n_intervals=20, horizon_s=60.0)

    def spy(logs_, **kw):
        seen.append((hp.drift_yaw_uv_rad_per_m2, hp.wave_yaw_turned))
        return errors

    hp.after_stop_errors = spy
    _, cal = drift._calibrate_after_stop(hp, logs, True, 0, 0, 20, 60.0, lambda m: None, hull, wave)
    want = [(c.coefficient_rad_per_m2, w["turned"]) for c, w in zip(hull, wave)]
    assert sorted(seen) == sorted(set(want)) and len(cal) == 6
    assert hp.drift_yaw_uv_rad_per_m2 == 0.0 and not hp.wave_yaw_turned
    used = []

    def forecasts(pred, a, **kw):
        used.append((pred.drift_yaw_uv_rad_per_m2, pred.wave_yaw_turned))
        return None

    monkeypatch.setattr(drift.metrics, "drift_forecasts", forecasts)
    drift._forecast_after_failures({"hybrid": (hp, {})}, logs, 20, 60.0, (60,), hp, cal, hull, wave)
    assert used == want
    # too few other failures for the spread: simulated DP losses calibrate it, once per yaw load
    from dataclasses import replace

    from hybridship.sim import scenario

    hp.calibration_config = replace(hp.calibration_config, after_stop_min_failures=10)
    monkeypatch.setattr(scenario, "embedded_scenarios", lambda n, seed: [SimpleNamespace(log=None)] * n)
    calibrated = []

    def calibrate(sims, **kw):
        calibrated.append(hp.wave_yaw_turned)
        hp.calibration["after_stop"] = {"turned": hp.wave_yaw_turned}

    hp.calibrate_after_stop = calibrate
    _, sim_cal = drift._calibrate_after_stop(hp, logs, True, 6, 0, 20, 60.0, lambda m: None, hull, wave)
    assert calibrated == [False, True] and not hp.wave_yaw_turned
    assert sim_cal == [{"turned": w["turned"]} for w in wave]
    _, one = drift._calibrate_after_stop(hp, logs, True, 6, 0, 20, 60.0, lambda m: None, hull,
                                         [{**w, "turned": False} for w in wave])
    assert one is None and calibrated[2:] == [False]
    # scored on other logs, or with the setting: fit's choice, or the setting, for every test log
    hp.wave_yaw_turned = True
    assert drift._wave_yaw_per_log(hp, logs, False, 60.0, list("abcdef"), lambda m: None) == ([], None)
    hp.training_info["wave_yaw_load"] = {"n_failures": 6, "turned": True, "p_value": 0.01}
    fits = drift._wave_yaw_table(hp, None, ["a", "b"])
    assert list(fits.turned) == [True, True] and set(fits.source) == {"training logs' failures"}
    assert list(fits.p_value) == [0.01, 0.01]
    hp.environment_config = EnvironmentConfig(wave_turned_yaw_load=True)
    setting = drift._wave_yaw_table(hp, None, ["a"])
    assert list(setting.source) == ["setting"] and setting.turned[0] and setting.p_value.isna().all()
    # "auto" (the default) where nothing is learned from failures (the strict protocol): held
    hp.environment_config, hp.drift_hull, hp.wave_yaw_turned = EnvironmentConfig(), False, False
    assert drift._wave_yaw_per_log(hp, logs, True, 60.0, list("abcdef"), lambda m: None) == ([], None)
    strict = drift._wave_yaw_table(hp, None, ["a"])
    assert list(strict.source) == ["setting"] and not strict.turned[0]
