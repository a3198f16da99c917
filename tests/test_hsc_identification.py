"""Identified models: ARX coefficients, subspace poles, NARX sizes, one-step and free-run modes."""

import numpy as np
import pytest

from hybridship.hsc.identification import (ARXModel, NARXConfig, NARXModel, StateSpaceModel, fit_arx,
                                           fit_subspace)
from hybridship.hsc.vessel import load_planing_craft


def _simulate_arx(A, B, U, nk=1):
    N, ny = U.shape[0], A.shape[1]
    Y = np.zeros((N, ny))
    for k in range(N):
        y = np.zeros(ny)
        for i in range(A.shape[0]):
            if k - 1 - i >= 0:
                y += A[i] @ Y[k - 1 - i]
        for j in range(B.shape[0]):
            if k - nk - j >= 0:
                y += B[j] @ U[k - nk - j]
        Y[k] = y
    return Y


def test_arx_recovers_known_mimo_coefficients():
    rng = np.random.default_rng(1)
    A = np.array([[[0.5, 0.1], [-0.05, 0.3]], [[0.2, 0.0], [0.05, -0.1]], [[-0.1, 0.02], [0.0, 0.05]]])
    B = np.array([[[1.0, 0.0, 0.3], [0.2, -0.5, 0.1]], [[0.4, 0.1, 0.0], [0.0, 0.3, -0.2]]])
    U = rng.standard_normal((600, 3))
    Y = _simulate_arx(A, B, U)
    p = fit_arx(U, Y, na=3, nb=2, nk=1)
    np.testing.assert_allclose(p.A, A, atol=1e-9)
    np.testing.assert_allclose(p.B, B, atol=1e-9)
    np.testing.assert_allclose(p.c, 0.0, atol=1e-9)


@pytest.mark.parametrize("args,name", [
    ({"Y": np.nan}, "Y"), ({"U": np.inf}, "U"),              # LinAlgError and LAPACK's DLASCL on stderr before
    ({"na": 1.5}, "na"), ({"nb": 0}, "nb"), ({"nk": True}, "nk"),
])
def test_fit_arx_refuses_nonfinite_data_and_non_integer_orders_by_name(args, name):
    rng = np.random.default_rng(3)
    U, Y = rng.standard_normal((60, 3)), rng.standard_normal((60, 2))
    kw = {"U": U, "Y": Y, "na": 2, "nb": 2, "nk": 1}
    for key, value in args.items():
        if key in ("U", "Y"):
            kw[key][7, 1] = value
        else:
            kw[key] = value
    with pytest.raises(ValueError, match=rf"^{name}: "):
        fit_arx(**kw)


def test_arx_model_modes_exact_on_noise_free_data():
    rng = np.random.default_rng(2)
    A = np.array([[[0.6, 0.1], [0.0, 0.4]]])
    B = np.array([[[0.5, 0.2, 0.0], [0.0, 0.3, 0.4]]])
    U = rng.standard_normal((400, 3))
    Y = _simulate_arx(A, B, U) + np.array([10.0, 0.05])    # offsets: the model standardises
    m = ARXModel(1, 1, 1).fit(U, Y)
    np.testing.assert_allclose(m.one_step(U, Y)[5:], Y[5:], atol=1e-8)
    np.testing.assert_allclose(m.free_run(U, Y, 5)[5:], Y[5:], atol=1e-8)
    assert m.label == "ARX111"


def _known_state_space(rng, N=3000):
    A = np.array([[0.9, 0.2, 0.0], [-0.2, 0.9, 0.0], [0.0, 0.0, 0.5]])
    B = np.array([[1.0, 0.0], [0.0, 0.5], [0.3, 1.0]])
    C = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, -1.0]])
    U = rng.standard_normal((N, 2))
    x = np.zeros(3)
    Y = np.zeros((N, 2))
    for k in range(N):
        Y[k] = C @ x
        x = A @ x + B @ U[k]
    return A, U, Y


def test_subspace_reproduces_known_poles():
    A, U, Y = _known_state_space(np.random.default_rng(3))
    p = fit_subspace(U, Y, order=3, block_rows=6)
    got = np.sort_complex(p.poles)
    want = np.sort_complex(np.linalg.eigvals(A))
    np.testing.assert_allclose(got, want, atol=1e-6)


@pytest.fixture(scope="module")
def noise_free_ss():
    """(model, U, Y): a state-space model fitted to a noise-free third-order system."""
    A, U, Y = _known_state_space(np.random.default_rng(4), N=1500)
    # the model delays its inputs by one sample: feed it inputs advanced by one
    U1 = np.vstack([U[1:], U[-1:]])
    return StateSpaceModel(order=3, block_rows=6).fit(U1, Y), U1, Y


def test_state_space_model_free_run_follows_noise_free_system(noise_free_ss):
    m, U1, Y = noise_free_ss
    P = m.free_run(U1, Y, 20)
    # the error of the 20-sample state estimate dies out with the poles (|z| <= 0.92); what is
    # left is the subspace estimate's own small bias (about 0.1 % here)
    assert np.max(np.abs(P[300:] - Y[300:])) < 5e-3 * np.abs(Y).max()
    assert np.mean(np.abs(P[20:] - Y[20:])) < 0.05 * np.mean(np.abs(Y))


@pytest.mark.parametrize("sea_state,lags,n_inputs", [(1, (5, 3), 19), (2, (7, 5), 29)])
def test_narx_sizes_as_in_the_paper(sea_state, lags, n_inputs):
    """The benchmark's ANN for each sea state has the paper's lags, and the network it fits
    takes 19 (29) inputs into 5 then 4 hidden neurons (the fitted weights, not a formula)."""
    from hybridship.hsc.benchmark import models_for

    m = models_for(sea_state, load_planing_craft(), "interceptor", quick=True)["ann"]
    assert (m.config.n_out, m.config.n_in) == lags
    rng = np.random.default_rng(0)
    U, Y = rng.uniform(-1, 1, (300, 3)), rng.uniform(-1, 1, (300, 2))
    W = NARXModel(NARXConfig(n_out=m.config.n_out, n_in=m.config.n_in, max_iter=5, restarts=1)).fit(U, Y).weights
    assert [w.shape for w in W if w.ndim == 2] == [(5, n_inputs), (4, 5), (2, 4)]


def test_narx_learns_a_nonlinear_system_and_runs_free():
    rng = np.random.default_rng(5)
    N = 1500
    U = np.repeat(rng.uniform(-1, 1, (N // 15, 3)), 15, axis=0)
    Y = np.zeros((N, 2))
    for k in range(1, N):
        Y[k, 0] = 0.8 * Y[k - 1, 0] + 0.3 * np.tanh(2 * U[k - 1, 0])
        Y[k, 1] = 0.6 * Y[k - 1, 1] + 0.4 * np.sin(2 * U[k - 1, 1]) + 0.2 * U[k - 1, 2]
    m = NARXModel(NARXConfig(n_out=2, n_in=2, max_iter=200, restarts=1)).fit(U[:1000], Y[:1000])
    one = m.one_step(U[1000:], Y[1000:])
    free = m.free_run(U[1000:], Y[1000:], 5)
    for P in (one, free):
        err = np.abs(P[5:] - Y[1005:]).mean(0)
        assert np.all(err < 0.35 * np.abs(Y[1005:] - Y[1005:].mean(0)).mean(0)), err


def test_narx_holds_out_at_least_one_row_for_early_stopping():
    """A held-out share that rounds to no row would have trained on an empty set."""
    rng = np.random.default_rng(2)
    U = rng.uniform(-1, 1, (30, 3))
    Y = np.cumsum(rng.normal(size=(30, 2)), axis=0) * 0.1
    m = NARXModel(NARXConfig(n_out=2, n_in=2, val_fraction=0.01, max_iter=40, restarts=1)).fit(U, Y)
    err = np.abs(m.one_step(U, Y)[2:] - Y[2:]).mean()
    assert np.isfinite(err) and err < np.abs(Y[2:] - Y[2:].mean(0)).mean()


def test_records_of_text_are_refused_naming_the_argument():
    """numpy parsed a record of text such as "800" as numbers, which every model then fitted
    and predicted from; text is refused as the ship forecasters refuse it."""
    U = np.column_stack([np.linspace(800, 3000, 40), np.full(40, 50.0), np.zeros(40)])
    Y = np.column_stack([np.linspace(5, 15, 40), np.full(40, 0.05)])
    with pytest.raises(ValueError, match=r"^U: expected a numeric array of shape \(N, n\)"):
        ARXModel(1, 1).fit(U.astype(str), Y)
    m = ARXModel(1, 1).fit(U, Y)
    with pytest.raises(ValueError, match=r"^Y: expected a numeric array of shape \(N, 2\)"):
        m.one_step(U, Y.astype(str))
    with pytest.raises(ValueError, match=r"^Y_init: expected a numeric array"):
        m.free_run(U, Y.astype(str), 2)


def test_narx_fit_leaves_the_callers_global_torch_random_state_alone():
    """The restarts' initial weights come from a generator of the fit's own: a caller's
    seeded torch draws after a fit are those it would have had without it, and a second fit
    after other draws gives the same weights."""
    import torch

    rng = np.random.default_rng(3)
    U = rng.uniform(-1, 1, (60, 3))
    Y = np.cumsum(rng.normal(size=(60, 2)), axis=0) * 0.1
    cfg = NARXConfig(n_out=2, n_in=2, max_iter=20, restarts=2, seed=4)
    torch.manual_seed(123)
    want = torch.rand(3)
    torch.manual_seed(123)
    first = NARXModel(cfg).fit(U, Y)
    assert torch.equal(torch.rand(3), want)
    second = NARXModel(cfg).fit(U, Y)
    assert all(np.array_equal(a, b) for a, b in zip(first.weights, second.weights))


def test_narx_config_refuses_a_seed_whose_restart_seeds_overflow_by_name():
    """Restart r is seeded seed * 1000 + r, and torch takes seeds below 2**64: a seed of
    2 * 10**16 (a valid seed otherwise) failed in fit with torch's "Overflow when unpacking
    long long", naming nothing."""
    top = (2**64 - 3) // 1000
    assert NARXConfig(seed=top).seed == top
    with pytest.raises(ValueError, match=r"^seed: expected at most 18446744073709551 .* got 20000000000000000"):
        NARXConfig(seed=2 * 10**16)


def test_narx_initial_weights_are_those_torch_linear_draws_after_seeding():
    """The generator of the fit's own gives the weights that ``torch.manual_seed(seed)`` and
    ``torch.nn.Linear`` gave (the benchmark's figures were made with those)."""
    import torch

    from hybridship.hsc.identification import _narx_net

    sizes, seed = [19, 5, 4, 2], 1002
    with torch.random.fork_rng():
        torch.manual_seed(seed)
        want = [torch.nn.Linear(sizes[i], sizes[i + 1]).double() for i in range(len(sizes) - 1)]
    got = [m for m in _narx_net(sizes, seed) if isinstance(m, torch.nn.Linear)]
    assert len(got) == 3
    for a, b in zip(got, want):
        assert a.weight.dtype == torch.float64
        assert torch.equal(a.weight, b.weight) and torch.equal(a.bias, b.bias)


def test_arx_model_free_run_exact_with_several_lags_and_a_longer_delay():
    """Higher orders (ARX321, as in the paper) and a delay of 2 samples: the lags are taken newest
    first and the model needs ``max(na, nk + nb - 1)`` initial rows; noise-free data are reproduced."""
    rng = np.random.default_rng(6)
    A = np.array([[[0.5, 0.1], [-0.05, 0.3]], [[0.2, 0.0], [0.05, -0.1]], [[-0.1, 0.02], [0.0, 0.05]]])
    B = np.array([[[1.0, 0.0, 0.3], [0.2, -0.5, 0.1]], [[0.4, 0.1, 0.0], [0.0, 0.3, -0.2]]])
    U = rng.standard_normal((400, 3))
    for nk in (1, 2):
        Y = _simulate_arx(A, B, U, nk=nk)
        m = ARXModel(3, 2, nk).fit(U, Y)
        assert m.n_init == 3 and ARXModel(1, 3, nk).n_init == nk + 2
        np.testing.assert_allclose(m.free_run(U, Y, 10)[10:], Y[10:], atol=1e-8)
        np.testing.assert_allclose(m.one_step(U, Y)[10:], Y[10:], atol=1e-8)


def test_kalman_gain_of_a_scalar_system_by_hand():
    """``x+ = 0.8 x + w``, ``y = x + v`` with ``Q = 1``, ``R = 1``, ``S = E[w v] = 0.5``: the
    predictor Riccati equation ``P = a^2 P + Q - (a P + S)^2 / (P + R)`` reduces to
    ``P^2 + 0.16 P - 0.75 = 0``, and ``K = (a P + S) / (P + R)``."""
    from hybridship.hsc.identification import StateSpaceParameters

    one = np.ones((1, 1))
    p = StateSpaceParameters(A=0.8 * one, B=one, C=one, D=0 * one, Q=one, R=one, S=0.5 * one)
    P = (-0.16 + np.sqrt(0.16 ** 2 + 3.0)) / 2.0                  # 0.7897
    assert p.kalman_gain()[0, 0] == pytest.approx((0.8 * P + 0.5) / (P + 1.0), rel=1e-6)


def test_state_space_one_step_locks_onto_a_noise_free_system(noise_free_ss):
    """The Kalman predictor's measurement feedback brings the one-step predictions onto the data within
    25 samples (without it the state error would only die out with the poles, |z| <= 0.92: hundreds)."""
    m, U1, Y = noise_free_ss
    P = m.one_step(U1, Y)
    assert np.max(np.abs(P[25:] - Y[25:])) < 5e-3 * np.abs(Y).max()


def test_narx_with_more_input_than_output_lags_starts_after_the_longest():
    """``n_in > n_out``: the first prediction needs ``n_in`` rows of history."""
    rng = np.random.default_rng(7)
    U, Y = rng.uniform(-1, 1, (60, 3)), rng.uniform(-1, 1, (60, 2))
    m = NARXModel(NARXConfig(n_out=1, n_in=3, max_iter=5, restarts=1)).fit(U, Y)
    assert m.n_init == 3
    P = m.one_step(U, Y)
    assert np.isnan(P[:3]).all() and np.isfinite(P[3:]).all()


def test_a_constant_input_column_is_standardised_without_dividing_by_zero():
    """A record with the trim device held (a constant PWM column) still gives exact ARX predictions."""
    rng = np.random.default_rng(9)
    U = rng.standard_normal((300, 3))
    U[:, 1] = 55.0
    Y = _simulate_arx(np.array([[[0.6, 0.1], [0.0, 0.4]]]), np.array([[[0.5, 0.0, 0.0], [0.0, 0.0, 0.4]]]), U)
    m = ARXModel(1, 1, 1).fit(U, Y)
    np.testing.assert_allclose(m.one_step(U, Y)[5:], Y[5:], atol=1e-8)


def test_subspace_block_rows_need_only_cover_the_order_with_all_outputs():
    """``block_rows * ny >= order``: 2 block rows of 2 outputs identify a third-order system; 1 is refused."""
    A, U, Y = _known_state_space(np.random.default_rng(3), N=600)
    p = fit_subspace(U, Y, order=3, block_rows=2)
    assert p.A.shape == (3, 3)
    with pytest.raises(ValueError, match="block_rows"):
        fit_subspace(U, Y, order=3, block_rows=1)


def test_fit_subspace_names_nan_data_and_bad_orders():
    """Review: NaN reached nfoursid ("Output data cannot contain nulls")."""
    from hybridship.hsc.identification import fit_subspace

    rng = np.random.default_rng(4)
    U, Y = rng.standard_normal((80, 3)), rng.standard_normal((80, 2))
    Y[5, 0] = np.nan
    with pytest.raises(ValueError, match="^Y: "):
        fit_subspace(U, Y, order=2)
    with pytest.raises((TypeError, ValueError), match="^order: "):
        fit_subspace(U, np.nan_to_num(Y), order=0)


@pytest.mark.parametrize("make", [lambda: ARXModel(3, 2, 2), lambda: ARXModel(1, 2, 0),
                                  lambda: StateSpaceModel(order=3, block_rows=6),
                                  lambda: NARXModel(NARXConfig(n_out=2, n_in=3, max_iter=20, restarts=1))],
                         ids=["ARX322", "ARX120", "ss", "ann"])
def test_a_free_run_is_the_one_step_predictor_fed_its_own_predictions(make):
    """On noisy data (where neither mode is exact): the free run from ``n_init`` rows equals the
    one-step predictions of a record whose rows from ``n_init`` on are the free run's own output
    (the state-space predictor's innovations are then zero). The two modes build their regressors
    separately; a lag taken in the wrong order or the wrong delay in one of them breaks this."""
    rng = np.random.default_rng(11)
    U = rng.standard_normal((200, 3))
    Y = _simulate_arx(np.array([[[0.6, 0.1], [0.0, 0.4]]]), np.array([[[0.5, 0.2, -0.3], [0.1, 0.3, 0.4]]]), U)
    Y += 0.3 * rng.standard_normal(Y.shape)
    m = make().fit(U, Y)
    n = m.n_init + 4
    free = m.free_run(U, Y[:n], n)
    fed = np.vstack([Y[:n], free[n:]])
    np.testing.assert_allclose(m.one_step(U, fed)[n:], free[n:], rtol=1e-9, atol=1e-9)
    assert np.isnan(free[:n]).all()
    assert np.abs(m.one_step(U, Y)[n + 5:] - free[n + 5:]).max() > 1e-3     # the data's noise does matter


def test_subspace_refuses_a_record_shorter_than_its_hankel_matrices_need():
    """Fewer rows than ``2 block_rows (nu + ny + 1) - 1`` leave the Hankel matrices with fewer
    columns than rows: 60 rows of a second-order system (block_rows 10, 3 inputs, 2 outputs)
    came back as A = 0, every pole at 0, without a word; 119 rows identify it."""
    rng = np.random.default_rng(0)
    A = np.array([[0.9, 0.2], [-0.2, 0.8]])
    B = 0.5 * rng.standard_normal((2, 3))
    U = rng.standard_normal((119, 3))
    x, Y = np.zeros(2), np.zeros((119, 2))
    for k in range(119):
        Y[k] = x
        x = A @ x + B @ U[k]
    with pytest.raises(ValueError, match=r"^U: need at least 119 rows for block_rows = 10.*got 60"):
        fit_subspace(U[:60], Y[:60], order=2, block_rows=10)
    with pytest.raises(ValueError, match=r"^U: need at least 119 rows"):
        StateSpaceModel(order=2, block_rows=10).fit(U[:60], Y[:60])
    got = np.sort_complex(fit_subspace(U, Y, order=2, block_rows=10).poles)
    np.testing.assert_allclose(got, np.sort_complex(np.linalg.eigvals(A)), atol=1e-6)


def test_arx_refuses_a_record_with_fewer_regression_rows_than_coefficients():
    """ARX321 with 3 inputs and 2 outputs has 13 coefficients per output and 3 lag rows: on 12
    rows (9 equations) least squares returned a minimum-norm fit of the record, without a word,
    not the system; 16 rows are taken."""
    rng = np.random.default_rng(12)
    U = rng.standard_normal((16, 3))
    Y = _simulate_arx(np.array([[[0.6, 0.1], [0.0, 0.4]]]), np.array([[[0.5, 0.2, -0.3], [0.1, 0.3, 0.4]]]), U)
    for fit in (lambda U, Y: fit_arx(U, Y, 3, 2, 1), lambda U, Y: ARXModel(3, 2, 1).fit(U, Y)):
        with pytest.raises(ValueError, match=r"^U: need at least 16 rows for ARX321 .*got 12"):
            fit(U[:12], Y[:12])
        assert fit(U, Y) is not None


def test_narx_n_inputs_counts_the_fitted_records_columns():
    """The NARX takes any MIMO record; n_inputs gave the paper's 2 n_out + 3 n_in (10 here)
    for a network fitted on one input and one output, which takes 2 + 2 = 4."""
    rng = np.random.default_rng(0)
    m = NARXModel(NARXConfig(n_out=2, n_in=2, max_iter=5, restarts=1))
    assert m.n_inputs == 2 * 2 + 3 * 2                  # unfitted: the paper's records
    m.fit(rng.uniform(-1, 1, (200, 1)), rng.uniform(-1, 1, (200, 1)))
    assert m.n_inputs == m.weights[0].shape[1] == 4


@pytest.mark.parametrize("max_iter", [5, 60])
def test_narx_runs_at_most_max_iter_lbfgs_iterations(monkeypatch, max_iter):
    """max_iter is 'L-BFGS iterations at most': 5 ran up to 20 iterations (one step of 20); a
    multiple of 20, as the benchmark's 60 and 400, runs in steps of 20 as before."""
    import torch

    made = []

    class Counting(torch.optim.LBFGS):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(torch.optim, "LBFGS", Counting)
    rng = np.random.default_rng(0)
    U = rng.uniform(-1, 1, (300, 3))
    Y = np.column_stack([np.sin(3 * U[:, 0]), U[:, 1] * U[:, 2]])
    NARXModel(NARXConfig(n_out=2, n_in=2, max_iter=max_iter, restarts=1, val_fraction=0.4)).fit(U, Y)
    (opt,) = made
    n_iter = opt.state[opt.param_groups[0]["params"][0]]["n_iter"]
    assert 0 < n_iter <= max_iter
