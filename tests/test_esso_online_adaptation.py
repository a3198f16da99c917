"""benchmarks/esso_online_adaptation.py: the weighted mean of past one-step errors and the
correction it adds to the nets' output."""

import numpy as np
import pytest

from conftest import load_benchmark


@pytest.fixture(scope="module")
def oa():
    return load_benchmark("esso_online_adaptation")


def test_the_weighted_mean_is_causal_restarts_per_segment_and_skips_missing_rows(oa):
    seg = np.r_[np.zeros(50, int), np.ones(50, int)]
    e = np.ones((100, 3))
    e[5] = np.nan
    e[60:] = 3.0
    m = oa.ewma(e, seg, 0.1, 1.0)
    np.testing.assert_allclose(m[:60], 1.0)                   # a missing row changes nothing
    a = 1 - np.exp(-0.1)
    # the second segment starts at its own first row: weights normalised over rows 50..i
    w = (1 - a) ** np.arange(11)[::-1]
    np.testing.assert_allclose(m[60, 0], (w[:10].sum() + 3 * w[10]) / w.sum())
    before = oa.ewma(e[:55], seg[:55], 0.1, 1.0)
    np.testing.assert_array_equal(before, m[:55])             # later rows do not change earlier means


def test_shifted_moves_rows_within_their_segment(oa):
    x = np.arange(10.0)[:, None] * np.ones(3)
    seg = np.r_[np.zeros(6, int), np.ones(4, int)]
    np.testing.assert_array_equal(oa.shifted(x, seg, 2)[:, 0], [np.nan, np.nan, 0, 1, 2, 3, np.nan, np.nan, 6, 7])
    np.testing.assert_array_equal(oa.shifted(x, seg, -2)[:, 0], [2, 3, 4, 5, np.nan, np.nan, 8, 9, np.nan, np.nan])


def test_autocorrelation_of_an_autoregressive_error(oa):
    rng = np.random.default_rng(0)
    z = np.zeros((20000, 3))
    for i in range(1, len(z)):
        z[i] = 0.9 * z[i - 1] + rng.normal(size=3)
    acf = oa.autocorrelation([(z, np.zeros(len(z), int))], np.array([1, 5]), z.mean(0))
    np.testing.assert_allclose(acf, np.array([[0.9] * 3, [0.9 ** 5] * 3]), atol=0.03)


def test_a_constant_error_is_explained_and_white_noise_is_not(oa):
    rng = np.random.default_rng(1)
    seg = np.zeros(5000, int)
    const = oa.explained([(1.0 + 0.1 * rng.normal(size=(5000, 3)), seg)], 0.1, 5.0, 10, 300)
    noise = oa.explained([(rng.normal(size=(5000, 3)), seg)], 0.1, 5.0, 10, 300)
    assert np.all(const["ahead"] > 0.98) and np.all(const["mean"] > 0.99)
    assert np.all(noise["ahead"] < 0.0) and np.all(noise["ahead_best"] < 0.01)


def test_the_corrected_ensemble_adds_the_correction_held_or_decaying(oa):
    class Ens:
        n_members = 2

        def predict_members(self, X):
            return np.zeros((2, X.shape[1], 3))

    c = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, -1.0]])
    held = oa._CorrectedEnsemble(Ens(), c, 0.1, None)
    decaying = oa._CorrectedEnsemble(Ens(), c, 0.1, 1.0)
    assert held.n_members == 2
    for step in range(3):
        np.testing.assert_allclose(held.predict_members(np.zeros((2, 2, 4))), np.broadcast_to(c, (2, 2, 3)))
        np.testing.assert_allclose(decaying.predict_members(np.zeros((2, 2, 4))),
                                   np.broadcast_to(np.exp(-0.1 * step) * c, (2, 2, 3)))
    with pytest.raises(ValueError, match="3 starts"):
        held.predict_members(np.zeros((2, 3, 4)))


def test_the_choice_table_has_a_column_per_gain_and_names_the_lowest_distance(oa):
    import pandas as pd

    rows = [[False, "all", 5.0, 0.0, 0.45, 9.3]]
    for tau in (5.0, 10.0):
        for gain in (0.5, 1.0):
            rows.append([False, "all", tau, gain, 0.44 if (tau, gain) == (10.0, 0.5) else 0.46, 9.0])
    md = oa._choice_md(pd.DataFrame(rows, columns=["decay", "dof", "tau_s", "gain", "distance_m", "heading_deg"]))
    assert "| held | all | 10 | 0.4500 / 9.300 | 0.4400 / 9.000 | 0.4600 / 9.000 |" in md
    assert md.endswith("Chosen (lowest distance): held, all: tau 10 s, gain 0.5.")


def _weighted_mean_by_hand(err, seg, dt_s, tau_s, i):
    """The weighted mean of the finite rows of row ``i``'s segment up to ``i``: weight
    ``(1 - a)^(i - j)`` on row ``j``, ``a = 1 - exp(-dt / tau)`` (NaN without such a row)."""
    q = np.exp(-dt_s / tau_s)
    js = [j for j in range(i + 1) if seg[j] == seg[i] and np.isfinite(err[j]).all()]
    if not js:
        return np.full(3, np.nan)
    w = q ** (i - np.array(js, float))
    return (w[:, None] * err[js]).sum(0) / w.sum()


def test_explained_and_autocorrelation_match_a_row_by_row_count(oa):
    """Every fraction of :func:`explained` (and the pooled autocorrelation) against a plain loop
    over the rows, on two logs with two segments and missing rows: the mean is the one known
    ``delay`` rows before the row (in its segment), each future row is in the segment too."""
    rng = np.random.default_rng(4)
    logs = []
    for n, cut in ((70, 30), (45, 20)):
        e = 0.3 + np.cumsum(rng.normal(size=(n, 3)), axis=0) * 0.2 + rng.normal(size=(n, 3))
        e[[7, cut + 3]] = np.nan
        logs.append((e, (np.arange(n) >= cut).astype(int)))
    dt, tau, delay, horizon = 0.5, 2.0, 3, 4
    got = oa.explained(logs, dt, tau, delay, horizon)

    nxt, fut = [], []                   # pairs (next row, mean) and (future rows, mean)
    for e, seg in logs:
        n = len(e)
        for i in range(n):
            if i - delay < 0 or seg[i - delay] != seg[i]:
                continue
            m = _weighted_mean_by_hand(e, seg, dt, tau, i - delay)
            if not np.isfinite(m).all():
                continue
            if i + 1 < n and seg[i + 1] == seg[i] and np.isfinite(e[i + 1]).all():
                nxt.append((e[i + 1], m))
            rows = np.arange(i + 1, i + horizon + 1)
            if rows[-1] < n and (seg[rows] == seg[i]).all() and np.isfinite(e[rows]).all():
                fut.append((e[rows], m))
    e1 = np.array([p for p, _ in nxt])
    m1 = np.array([m for _, m in nxt])
    f = np.array([p for p, _ in fut])                                # (starts, H, 3)
    m = np.array([m for _, m in fut])                                # (starts, 3)
    fbar = f.mean(1)
    em, mm = (f * m[:, None]).sum((0, 1)), horizon * (m ** 2).sum(0)
    want = {"next": 1 - ((e1 - m1) ** 2).sum(0) / (e1 ** 2).sum(0),
            "ahead": 1 - ((f - m[:, None]) ** 2).sum((0, 1)) / (f ** 2).sum((0, 1)),
            "ahead_best": em ** 2 / (mm * (f ** 2).sum((0, 1))), "gain": em / mm,
            "mean": 1 - ((fbar - m) ** 2).sum(0) / (fbar ** 2).sum(0),
            "mean_best": (fbar * m).sum(0) ** 2 / ((m ** 2).sum(0) * (fbar ** 2).sum(0)),
            "mean_rms": np.sqrt((fbar ** 2).mean(0))}
    assert sorted(got) == sorted(want)
    for key in want:
        np.testing.assert_allclose(got[key], want[key], rtol=1e-10, err_msg=key)

    c = np.array([0.1, -0.2, 0.3])
    num, a2, b2 = np.zeros(3), np.zeros(3), np.zeros(3)
    for e, seg in logs:
        for i in range(len(e) - 2):                     # lag 2: pairs (i, i + 2) in one segment
            if seg[i] == seg[i + 2] and np.isfinite(e[[i, i + 2]]).all():
                num += (e[i] - c) * (e[i + 2] - c)
                a2 += (e[i] - c) ** 2
                b2 += (e[i + 2] - c) ** 2
    np.testing.assert_allclose(oa.autocorrelation(logs, np.array([2]), c)[0], num / np.sqrt(a2 * b2), rtol=1e-10)


def test_the_correction_is_added_to_each_members_own_output_per_dof(oa):
    """The members' outputs are kept (the correction is added, not substituted) and each DOF
    decays with its own time constant."""
    members = np.arange(2 * 2 * 3, dtype=float).reshape(2, 2, 3)

    class Ens:
        n_members = 2

        def predict_members(self, X):
            return members

    c = np.array([[1.0, 2.0, 3.0], [0.0, 0.5, -1.0]])
    decay = np.array([1.0, 2.0, 4.0])
    ens = oa._CorrectedEnsemble(Ens(), c, 0.5, decay)
    for step in range(3):
        want = members + np.exp(-0.5 * step / decay) * c[None]
        np.testing.assert_allclose(ens.predict_members(np.zeros((2, 2, 4))), want)


def test_the_observer_adds_the_mean_of_the_errors_known_a_second_before_each_start(oa, monkeypatch):
    """:func:`observer_forecast` with a stand-in hybrid whose rollout returns the nets' output at
    each step: every start gets ``gain`` times the weighted mean of the one-step errors from
    ``first_row`` up to :data:`KNOWN_AFTER_S` (2 rows at 0.5 s) before it, in its segment (none
    when that row is in the previous segment), held or decaying per DOF; gain 0 is the hybrid."""
    from types import SimpleNamespace

    dt, n = 0.5, 40
    seg = (np.arange(n) >= 20).astype(int)
    err = np.random.default_rng(5).normal(size=(n, 3)) + 1.0
    monkeypatch.setattr(oa, "one_step_errors", lambda hybrid, a: err.copy())

    class Ens:
        n_members = 1

        def predict_members(self, X):
            return np.zeros((1, X.shape[1], 3))

    class Hybrid:
        ensemble = Ens()

        def forecast(self, a, st, horizon_s):
            return np.stack([self.ensemble.predict_members(np.zeros((1, len(st), 4)))[0]
                             for _ in range(int(round(horizon_s / dt)))], axis=1)     # (S, steps, 3)

    hyb, plain = Hybrid(), Hybrid.ensemble
    a = SimpleNamespace(time_s=np.arange(n) * dt, segment_id=seg)
    rows = np.array([10, 25, 21])                         # row 21: 2 rows before is in segment 0
    first_row = 4
    known = np.where(np.arange(n)[:, None] >= first_row, err, np.nan)

    def expected(tau):
        out = np.zeros((rows.size, 3))
        for i, r in enumerate(rows):
            if seg[r - 2] == seg[r]:
                out[i] = _weighted_mean_by_hand(known, seg, dt, tau, r - 2)
        return out

    held = oa.observer_forecast(hyb, 1.0, 0.5, False, first_row)(a, rows * dt, 2.0)
    assert held.shape == (3, 4, 3) and hyb.ensemble is plain
    np.testing.assert_allclose(held, np.broadcast_to(0.5 * expected(1.0)[:, None], held.shape), rtol=1e-12)
    assert np.all(held[2] == 0.0)

    taus, gains = np.array([1.0, 2.0, 4.0]), np.array([0.5, 0.0, 2.0])
    decaying = oa.observer_forecast(hyb, taus, gains, True, first_row)(a, rows * dt, 2.0)
    c = np.column_stack([gains[d] * expected(taus[d])[:, d] for d in range(3)])
    lead = np.exp(-np.arange(4)[:, None] * dt / taus)                       # (steps, 3)
    np.testing.assert_allclose(decaying, c[:, None] * lead[None], rtol=1e-12)
    assert np.all(oa.observer_forecast(hyb, 1.0, 0.0, False)(a, rows * dt, 2.0) == 0.0)


def test_the_persistence_table_takes_its_lags_and_delays_in_seconds(oa):
    """At 0.5 s a row, :func:`persistence`'s lag of 1 s is 2 rows, the known mean is the one up to
    2 rows before, the horizon 60 rows; its RMS and mean skip the missing rows."""
    rng = np.random.default_rng(6)
    logs = []
    for n in (300, 260):
        e = np.zeros((n, 3))
        for i in range(1, n):
            e[i] = 0.8 * e[i - 1] + rng.normal(size=3)
        e += 0.5
        e[[3, 150]] = np.nan
        logs.append((e, np.zeros(n, int)))
    dt = 0.5
    table = oa.persistence(logs, dt)
    assert list(table.tau_s) == [t for t in oa.TAUS_S for _ in oa.DOFS]
    row = table[table.tau_s == oa.TAUS_S[0]].set_index("dof")
    ok = np.concatenate([e[np.isfinite(e).all(1)] for e, _ in logs])
    np.testing.assert_allclose(row["mean"], ok.mean(0), rtol=1e-12)
    np.testing.assert_allclose(row["rms"], np.sqrt((ok ** 2).mean(0)), rtol=1e-12)
    x = [e - ok.mean(0) for e, _ in logs]
    pairs = np.concatenate([np.stack([xi[:-2], xi[2:]]) for xi in x], axis=1)     # (2, pairs, 3): lag 2 rows
    pairs = pairs[:, np.isfinite(pairs).all(axis=(0, 2))]
    acf1 = (pairs[0] * pairs[1]).sum(0) / np.sqrt((pairs[0] ** 2).sum(0) * (pairs[1] ** 2).sum(0))
    np.testing.assert_allclose(row["acf_1s"], acf1, rtol=1e-10)
    tau = oa.TAUS_S[0]
    for col, key, delay, horizon in (("next_from_last", "next", 0, 1), ("next_known", "next", 2, 60),
                                     ("ahead_30s", "ahead", 2, 60), ("mean_30s", "mean", 2, 60),
                                     ("best_gain", "gain", 2, 60), ("rms_30s_mean", "mean_rms", 2, 60)):
        np.testing.assert_allclose(row[col], oa.explained(logs, dt, tau, delay, horizon)[key], rtol=1e-12,
                                   err_msg=col)
