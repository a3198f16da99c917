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
