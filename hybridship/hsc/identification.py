"""The paper's identified models of surge and pitch: subspace state space, MIMO ARX, NARX ANN.

Every model maps the inputs ``u = [engine rpm, PWM %, heave acceleration]`` to the outputs
``y = [speed m/s, pitch rad]`` (SI inside) and offers the two scoring modes:

* :meth:`one_step` - one-step-ahead prediction: ``y_hat[k]`` from measured outputs up to
  ``k-1`` and inputs up to ``k-1``;
* :meth:`free_run` - simulation from the inputs alone: the first ``n_init`` samples of
  the measured outputs are the initial conditions (lagged outputs of ARX and NARX; for
  the state-space model a Kalman filter runs over them to estimate the state), after which
  the model feeds back its own outputs.

All models are strictly causal with one sample of input delay (``nk = 1``): ARX and NARX
regress on ``u[k-1], u[k-2], ...``; the state-space model is identified from the inputs
delayed by one sample, so its ``D`` term acts on ``u[k-1]``.

Linear models work on data standardised with the training means and standard deviations
(the constant levels are removed as MATLAB's ``detrend`` would); the NARX network scales
inputs and outputs to [-1, 1] with the training minima and maxima, as the paper did.

Orders as read from the paper (sec. 4): state-space order 4 for sea state 1 and 5 for
sea state 2 (subspace method, free parameterisation); ARX321 and ARX531 as MATLAB's
``[na nb nk]``: ``na`` = 3 (5) past outputs of every output in every equation, ``nb`` = 2
(3) past values of every input, delay ``nk`` = 1; NARX lags ``nout/nin`` = 5/3 (19
inputs) and 7/5 (29 inputs), hidden layers of 5 and 4 log-sigmoid neurons, linear output.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

import numpy as np
from pydantic import Field, model_validator

from ..config import Float, Int, NonEmpty, Seed, as_config, check_whole_number, config_dataclass
from .contract import check_free_run, check_record, require_fitted

__all__ = [
    "ARXParameters",
    "fit_arx",
    "ARXModel",
    "StateSpaceParameters",
    "fit_subspace",
    "StateSpaceModel",
    "NARXConfig",
    "NARXModel",
]


class _Standardiser:
    """Columns to zero mean and unit standard deviation (training statistics)."""

    def __init__(self, A):
        self.mean = A.mean(0)
        s = A.std(0)
        self.std = np.where(s > 1e-12, s, 1.0)

    def __call__(self, A):
        return (A - self.mean) / self.std

    def inverse(self, Z):
        return Z * self.std + self.mean


# --------------------------------------------------------------------------- ARX


@dataclass(frozen=True)
class ARXParameters:
    """``y[k] = sum_i A[i-1] y[k-i] + sum_j B[j] u[k-nk-j] + c``.

    Attributes
    ----------
    A : ndarray (na, ny, ny)
    B : ndarray (nb, ny, nu)
    c : ndarray (ny,)
    nk : int
    """

    A: np.ndarray
    B: np.ndarray
    c: np.ndarray
    nk: int

    @property
    def lag(self) -> int:
        """Samples of history a prediction needs."""
        return max(self.A.shape[0], self.nk + self.B.shape[0] - 1)

    def regressors(self, U, Y, k):
        na, nb = self.A.shape[0], self.B.shape[0]
        return np.concatenate([Y[k - na:k][::-1].ravel(), U[k - self.nk - nb + 1:k - self.nk + 1][::-1].ravel(), [1.0]])

    def theta(self):
        ny = self.c.size
        return np.concatenate([self.A.transpose(0, 2, 1).reshape(-1, ny),
                               self.B.transpose(0, 2, 1).reshape(-1, ny), self.c[None]])


def _arx_matrix(U, Y, na, nb, nk):
    p = max(na, nk + nb - 1)
    N = Y.shape[0]
    cols = [Y[p - i:N - i] for i in range(1, na + 1)]
    cols += [U[p - nk - j:N - nk - j] for j in range(nb)]
    cols.append(np.ones((N - p, 1)))
    return np.hstack(cols), Y[p:], p


def fit_arx(U, Y, na: int, nb: int, nk: int = 1) -> ARXParameters:
    """Least-squares MIMO ARX (every output regresses on ``na`` lags of all outputs and ``nb`` of all inputs).

    Parameters
    ----------
    U : ndarray (N, nu)
    Y : ndarray (N, ny)
    na, nb, nk : int
        Output order, input order and input delay (MATLAB's ``arx(data, [na nb nk])`` with
        the same orders in every entry).

    Raises
    ------
    ValueError
        Naming the argument: an order that is not a whole number (``na``, ``nb`` >= 1,
        ``nk`` >= 0), or ``U``/``Y`` not finite 2-D arrays of the same rows (NaN reached
        LAPACK before), fewer than ``max(na, nk + nb - 1)`` lag rows plus one regression
        row per coefficient of an output, ``na ny + nb nu + 1``.
    """
    na, nb, nk = check_whole_number("na", na, 1), check_whole_number("nb", nb, 1), check_whole_number("nk", nk, 0)
    U, Y = check_record(U, Y, min_rows=max(na, nk + nb - 1) + 2)      # as ARXModel.fit
    _check_arx_rows(U, Y, na, nb, nk)
    return _fit_arx(U, Y, na, nb, nk)


def _check_arx_rows(U, Y, na, nb, nk):
    """ValueError naming ``U`` when the record has fewer regression rows than an output has
    coefficients: least squares then returned a minimum-norm solution that fits any record."""
    lag, n_coef = max(na, nk + nb - 1), na * Y.shape[1] + nb * U.shape[1] + 1
    if U.shape[0] < lag + n_coef:
        raise ValueError(f"U: need at least {lag + n_coef} rows for ARX{na}{nb}{nk} with {U.shape[1]} inputs and "
                         f"{Y.shape[1]} outputs ({lag} lag rows and {n_coef} coefficients per output), "
                         f"got {U.shape[0]}")


def _fit_arx(U, Y, na, nb, nk) -> ARXParameters:
    """:func:`fit_arx` on checked arguments."""
    Phi, T, _ = _arx_matrix(U, Y, na, nb, nk)
    theta, *_ = np.linalg.lstsq(Phi, T, rcond=None)
    ny, nu = Y.shape[1], U.shape[1]
    A = theta[:na * ny].reshape(na, ny, ny).transpose(0, 2, 1)
    B = theta[na * ny:na * ny + nb * nu].reshape(nb, nu, ny).transpose(0, 2, 1)
    return ARXParameters(A=A, B=B, c=theta[-1], nk=nk)


class ARXModel:
    """MIMO ARX on standardised data (see :func:`fit_arx`)."""

    name = "arx"

    def __init__(self, na: int, nb: int, nk: int = 1):
        check_whole_number("na", na, 1), check_whole_number("nb", nb, 1), check_whole_number("nk", nk, 0)
        self.na, self.nb, self.nk = na, nb, nk
        self.n_init = max(na, nk + nb - 1)

    @property
    def label(self) -> str:
        return f"ARX{self.na}{self.nb}{self.nk}"

    def fit(self, U, Y):
        """Least squares on one record; returns self. All or nothing: the scalers and the
        coefficients replace the learned state together, so a fit that raises leaves it as it was."""
        U, Y = check_record(U, Y, min_rows=self.n_init + 2)
        _check_arx_rows(U, Y, self.na, self.nb, self.nk)
        su, sy = _Standardiser(U), _Standardiser(Y)
        params = _fit_arx(su(U), sy(Y), self.na, self.nb, self.nk)   # checked above
        self.shape = (U.shape[1], Y.shape[1])             # (inputs, outputs) of the predictions
        self.su, self.sy, self.params = su, sy, params
        return self

    def one_step(self, U, Y):
        require_fitted(self, "params")
        U, Y = check_record(U, Y, min_rows=self.n_init + 1, shape=self.shape)
        Zu, Zy = self.su(U), self.sy(Y)
        Phi, _, p = _arx_matrix(Zu, Zy, self.na, self.nb, self.nk)
        out = np.full(Y.shape, np.nan)
        out[p:] = self.sy.inverse(Phi @ self.params.theta())
        return out

    def free_run(self, U, Y_init, n_init: int):
        require_fitted(self, "params")
        U, Y_init, n_init = check_free_run(U, Y_init, n_init, self.n_init, self.shape)
        Zu = self.su(U)
        Z = np.zeros((U.shape[0], self.sy.mean.size))
        Z[:n_init] = self.sy(Y_init[:n_init])
        th = self.params.theta()
        for k in range(n_init, U.shape[0]):
            Z[k] = self.params.regressors(Zu, Z, k) @ th
        out = self.sy.inverse(Z)
        out[:n_init] = np.nan
        return out


# --------------------------------------------------------------------------- subspace state space


@dataclass(frozen=True)
class StateSpaceParameters:
    """``x[k+1] = A x[k] + B u[k] + K e[k]``, ``y[k] = C x[k] + D u[k] + e[k]`` and the noise covariances."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    S: np.ndarray

    @property
    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A)

    def kalman_gain(self) -> np.ndarray:
        """Steady-state predictor gain ``K`` from the discrete Riccati equation (zeros, the
        simulation predictor, if it has no solution: warned, as the one-step predictions then
        run without measurement feedback)."""
        from scipy.linalg import solve_discrete_are

        n, ny = self.A.shape[0], self.C.shape[0]
        R = self.R + 1e-9 * np.eye(ny)
        Q = self.Q + 1e-9 * np.eye(n)
        try:
            P = solve_discrete_are(self.A.T, self.C.T, Q, R, s=self.S)
            return (self.A @ P @ self.C.T + self.S) @ np.linalg.inv(self.C @ P @ self.C.T + R)
        except (np.linalg.LinAlgError, ValueError) as exc:
            from ..messages import warn_user

            warn_user(f"state-space model: the Riccati equation of the Kalman gain has no solution ({exc}); "
                      f"one-step predictions run without measurement feedback (K = 0)", RuntimeWarning)
            return np.zeros((n, ny))


def fit_subspace(U, Y, order: int, block_rows: int = 10) -> StateSpaceParameters:
    """Subspace identification (N4SID/PO-MOESP as implemented by the ``nfoursid`` package).

    Parameters
    ----------
    U : ndarray (N, nu)
    Y : ndarray (N, ny)
    order : int
        State dimension.
    block_rows : int
        Block rows of the Hankel matrices (``>= order / ny``).

    Raises
    ------
    ValueError
        Naming the argument: ``U``/``Y`` not finite 2-D arrays of the same rows, fewer than
        ``2 block_rows (nu + ny + 1) - 1`` rows (the Hankel matrices need at least as many
        columns as rows), or ``order``/``block_rows`` not whole numbers >= 1 with
        ``block_rows * ny >= order``.
    """
    import pandas as pd
    from nfoursid.nfoursid import NFourSID

    U, Y = check_record(U, Y)          # finite, named (nfoursid's own words otherwise)
    check_whole_number("order", order, 1)
    check_whole_number("block_rows", block_rows, 1)
    if block_rows * Y.shape[1] < order:
        raise ValueError(f"fit_subspace: block_rows * ny = {block_rows * Y.shape[1]} < order {order}")
    # the 2 block_rows (nu + ny) rows of the stacked Hankel matrices need as many columns
    # (N - 2 block_rows + 1); a shorter record gave A = 0 (all poles at 0) without a word
    n_min = 2 * block_rows * (U.shape[1] + Y.shape[1] + 1) - 1
    if U.shape[0] < n_min:
        raise ValueError(f"U: need at least {n_min} rows for block_rows = {block_rows} with {U.shape[1]} inputs and "
                         f"{Y.shape[1]} outputs (2 block_rows (nu + ny + 1) - 1), got {U.shape[0]}")
    ucols = [f"u{i}" for i in range(U.shape[1])]
    ycols = [f"y{i}" for i in range(Y.shape[1])]
    df = pd.DataFrame(np.hstack([U, Y]), columns=ucols + ycols)
    sid = NFourSID(df, output_columns=ycols, input_columns=ucols, num_block_rows=block_rows)
    sid.subspace_identification()
    ss, cov = sid.system_identification(rank=order)
    ny = Y.shape[1]
    R, S, Q = cov[:ny, :ny], cov[ny:, :ny], cov[ny:, ny:]
    return StateSpaceParameters(A=np.asarray(ss.a), B=np.asarray(ss.b), C=np.asarray(ss.c),
                                D=np.asarray(ss.d), Q=Q, R=R, S=S)


class StateSpaceModel:
    """Subspace state-space model on standardised data with inputs delayed one sample."""

    name = "ss"

    def __init__(self, order: int, block_rows: int = 10):
        check_whole_number("order", order, 1), check_whole_number("block_rows", block_rows, 1)
        self.order, self.block_rows = order, block_rows
        self.n_init = 2

    def _u(self, U, su=None):
        Z = (self.su if su is None else su)(U)
        return np.vstack([Z[:1], Z[:-1]])            # u[k-1] (the first sample repeated)

    def fit(self, U, Y):
        """Subspace identification on one record; returns self. All or nothing: the scalers, the
        matrices and the Kalman gain replace the learned state together, so a fit that raises
        leaves it as it was."""
        U, Y = check_record(U, Y, min_rows=2 * self.block_rows + 2)
        su, sy = _Standardiser(U), _Standardiser(Y)
        params = fit_subspace(self._u(U, su), sy(Y), self.order, self.block_rows)
        K = params.kalman_gain()
        self.shape = (U.shape[1], Y.shape[1])             # (inputs, outputs) of the predictions
        self.su, self.sy, self.params, self.K = su, sy, params, K
        return self

    def _filter(self, Zu, Zy, n_steps):
        """Kalman predictor over the first ``n_steps`` samples: (predictions, state at n_steps)."""
        p = self.params
        x = np.zeros(p.A.shape[0])
        pred = np.zeros((n_steps, Zy.shape[1]))
        for k in range(n_steps):
            yk = p.C @ x + p.D @ Zu[k]
            pred[k] = yk
            x = p.A @ x + p.B @ Zu[k] + self.K @ (Zy[k] - yk)
        return pred, x

    def one_step(self, U, Y):
        require_fitted(self, "params")
        U, Y = check_record(U, Y, min_rows=self.n_init + 1, shape=self.shape)
        Zu, Zy = self._u(U), self.sy(Y)
        pred, _ = self._filter(Zu, Zy, U.shape[0])
        out = self.sy.inverse(pred)
        out[:self.n_init] = np.nan
        return out

    def free_run(self, U, Y_init, n_init: int):
        require_fitted(self, "params")
        U, Y_init, n_init = check_free_run(U, Y_init, n_init, self.n_init, self.shape)
        Zu = self._u(U)
        _, x = self._filter(Zu, self.sy(Y_init[:n_init]), n_init)
        p = self.params
        Z = np.zeros((U.shape[0], p.C.shape[0]))
        for k in range(n_init, U.shape[0]):
            Z[k] = p.C @ x + p.D @ Zu[k]
            x = p.A @ x + p.B @ Zu[k]
        out = self.sy.inverse(Z)
        out[:n_init] = np.nan
        return out


# --------------------------------------------------------------------------- NARX network


@config_dataclass(frozen=True)
class NARXConfig:
    """The paper's NARX network (validated on creation).

    Attributes
    ----------
    n_out, n_in : int
        Lags of the outputs and of the inputs (``2 n_out + 3 n_in`` network inputs).
    hidden : tuple of int
        Neurons of the hidden layers (log-sigmoid); the output layer is linear.
    max_iter : int
        L-BFGS iterations at most (full batch; a quasi-Newton stand-in for Levenberg-Marquardt).
    restarts : int
        Random initialisations; the one with the lowest held-out error is kept.
    val_fraction : float
        Last fraction of the training data held out for early stopping.
    seed : int
        Seed of the initial weights; restart ``r`` is seeded ``seed * 1000 + r``, which must
        stay below 2**64 (torch's range of seeds).
    """

    n_out: Annotated[Int, Field(ge=1)] = 5
    n_in: Annotated[Int, Field(ge=1)] = 3
    hidden: Annotated[tuple[Annotated[Int, Field(ge=1)], ...], NonEmpty] = (5, 4)
    max_iter: Annotated[Int, Field(ge=1)] = 400
    restarts: Annotated[Int, Field(ge=1)] = 3
    val_fraction: Annotated[Float, Field(gt=0, lt=0.5)] = 0.15
    seed: Seed = 0

    @model_validator(mode="after")
    def _restart_seeds(self):
        # a seed above this failed in fit, after the other models' work, with torch's "Overflow" only
        top = (2**64 - self.restarts) // 1000
        if self.seed > top:
            raise ValueError(f"seed: expected at most {top} (restart r is seeded seed * 1000 + r, below 2**64), "
                             f"got {self.seed}")
        return self


class _MinMax:
    """Columns to [-1, 1] with the training minima and maxima (MATLAB's mapminmax)."""

    def __init__(self, A):
        self.lo, hi = A.min(0), A.max(0)
        self.span = np.where(hi - self.lo > 1e-12, hi - self.lo, 1.0)

    def __call__(self, A):
        return 2.0 * (A - self.lo) / self.span - 1.0

    def inverse(self, Z):
        return (Z + 1.0) / 2.0 * self.span + self.lo


def _narx_net(sizes, seed: int):
    """The network (log-sigmoid hidden layers, linear output, float64), its initial weights
    drawn as ``torch.nn.Linear`` draws them but from a generator of its own seeded with
    ``seed``, so torch's global random state, the caller's, is left as it was."""
    import math

    import torch

    gen = torch.Generator().manual_seed(int(seed))
    layers = []
    for i in range(len(sizes) - 1):
        lin = torch.nn.utils.skip_init(torch.nn.Linear, sizes[i], sizes[i + 1])
        with torch.no_grad():                  # Linear.reset_parameters, drawing from gen
            torch.nn.init.kaiming_uniform_(lin.weight, a=math.sqrt(5), generator=gen)
            bound = 1 / math.sqrt(sizes[i])
            torch.nn.init.uniform_(lin.bias, -bound, bound, generator=gen)
        layers.append(lin.double())
        if i < len(sizes) - 2:
            layers.append(torch.nn.Sigmoid())
    return torch.nn.Sequential(*layers)


class NARXModel:
    """NARX network ``y[k] = f(y[k-1..k-n_out], u[k-1..k-n_in])`` trained series-parallel."""

    name = "ann"

    def __init__(self, config: NARXConfig = NARXConfig()):
        self.config = config = as_config(config, NARXConfig, "config")
        self.n_init = max(config.n_out, config.n_in)

    @property
    def n_inputs(self) -> int:
        """Network inputs: ``n_out`` lags of every output and ``n_in`` of every input, so
        ``2 n_out + 3 n_in`` on the paper's records (before a fit, and after a fit on them)."""
        nu, ny = getattr(self, "shape", (3, 2))         # the fitted record's columns
        return ny * self.config.n_out + nu * self.config.n_in

    def _features(self, Zu, Zy, k0):
        c = self.config
        N = Zu.shape[0]
        cols = [Zy[k0 - i:N - i] for i in range(1, c.n_out + 1)]
        cols += [Zu[k0 - i:N - i] for i in range(1, c.n_in + 1)]
        return np.hstack(cols)

    def fit(self, U, Y):
        import torch

        c = self.config
        U, Y = check_record(U, Y, min_rows=self.n_init + 10)
        # all or nothing: the scalers and the weights replace the learned state together at the end
        su, sy = _MinMax(U), _MinMax(Y)
        Zu, Zy = su(U), sy(Y)
        X = self._features(Zu, Zy, self.n_init)
        T = Zy[self.n_init:]
        n_val = max(1, int(round(c.val_fraction * X.shape[0])))     # early stopping needs a held-out row
        Xt, Tt = torch.as_tensor(X[:-n_val], dtype=torch.float64), torch.as_tensor(T[:-n_val], dtype=torch.float64)
        Xv, Tv = torch.as_tensor(X[-n_val:], dtype=torch.float64), torch.as_tensor(T[-n_val:], dtype=torch.float64)
        threads = torch.get_num_threads()
        torch.set_num_threads(1)
        try:
            best, best_state = np.inf, None
            for r in range(c.restarts):
                net = _narx_net([X.shape[1], *c.hidden, T.shape[1]], c.seed * 1000 + r)
                opt = torch.optim.LBFGS(net.parameters(), lr=1.0, max_iter=20, history_size=20,
                                        line_search_fn="strong_wolfe")
                r_best, r_state, since = np.inf, None, 0

                def closure():
                    opt.zero_grad()
                    loss = torch.mean((net(Xt) - Tt) ** 2)
                    loss.backward()
                    return loss

                for done in range(0, c.max_iter, 20):      # steps of 20 iterations, the last one shorter
                    # max_iter 5 ran 20 iterations and 30 ran 20: at most max_iter now
                    n = min(20, c.max_iter - done)
                    opt.param_groups[0].update(max_iter=n, max_eval=n * 5 // 4)
                    opt.step(closure)
                    with torch.no_grad():
                        v = float(torch.mean((net(Xv) - Tv) ** 2))
                    if v < r_best - 1e-12:
                        r_best, since = v, 0
                        r_state = [p.detach().clone() for p in net.parameters()]
                    else:
                        since += 1
                        if since >= 3:          # early stopping on the held-out tail
                            break
                if r_best < best:
                    best, best_state = r_best, r_state
        finally:
            torch.set_num_threads(threads)
        self.shape = (U.shape[1], Y.shape[1])             # (inputs, outputs) of the predictions
        self.su, self.sy = su, sy
        self.weights = [p.numpy().copy() for p in best_state]
        self.val_mse = best
        return self

    def _net(self, X):
        h = X
        W = self.weights
        n_layers = len(W) // 2
        for i in range(n_layers):
            h = h @ W[2 * i].T + W[2 * i + 1]
            if i < n_layers - 1:
                h = 1.0 / (1.0 + np.exp(-h))
        return h

    def one_step(self, U, Y):
        require_fitted(self, "weights")
        U, Y = check_record(U, Y, min_rows=self.n_init + 1, shape=self.shape)
        Zu, Zy = self.su(U), self.sy(Y)
        out = np.full(Y.shape, np.nan)
        out[self.n_init:] = self.sy.inverse(self._net(self._features(Zu, Zy, self.n_init)))
        return out

    def free_run(self, U, Y_init, n_init: int):
        require_fitted(self, "weights")
        U, Y_init, n_init = check_free_run(U, Y_init, n_init, self.n_init, self.shape)
        c = self.config
        Zu = self.su(U)
        Z = np.zeros((U.shape[0], Y_init.shape[1]))
        Z[:n_init] = self.sy(Y_init[:n_init])
        for k in range(n_init, U.shape[0]):
            x = np.concatenate([Z[k - c.n_out:k][::-1].ravel(), Zu[k - c.n_in:k][::-1].ravel()])
            Z[k] = self._net(x[None])[0]
        out = self.sy.inverse(Z)
        out[:n_init] = np.nan
        return out
