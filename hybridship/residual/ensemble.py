"""An ensemble of small feed-forward networks, trained as one batched model.

Each member is ``n_in -> 20 tanh -> 20 tanh -> n_out linear`` (Skulstad et al. 2022,
sec. 3.2). All members share one set of batched weight tensors ``(E, fan_in, fan_out)``:
training is one PyTorch model (``torch.bmm`` over members), inference is plain numpy
(``np.matmul`` over members), so neither loops over members in Python.

Inputs and outputs are standardised with statistics stored beside the weights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Annotated

import numpy as np
from pydantic import Field

from hybridship.config import Bool, Float, Int, Seed, as_config, check_flags, config_dataclass, real_array


#: Most networks an ensemble may have (a bound on memory and training time).
MAX_MEMBERS = 1000


@config_dataclass(frozen=True)
class EnsembleConfig:
    """Training configuration of an :class:`MLPEnsemble` (validated on creation).

    Attributes
    ----------
    n_members : int
        Number of networks E (at most 1000).
    hidden : int
        Units of each hidden layer (two layers; at most 10 000).
    lr : float
        Adam learning rate.
    max_epochs : int
        Full-batch Adam iterations at most.
    patience : int
        Epochs without validation improvement before a member stops improving.
    weight_decay : float
        L2 penalty on the weights.
    input_noise_std : float
        Standard deviation of Gaussian noise added to the standardised training inputs,
        drawn anew at every epoch, in units of each input's spread; 0 = none. It penalises
        the fit's slope with respect to its inputs (training with noise is, to first order,
        Tikhonov regularisation), so the nets change less where the inputs leave the
        training data. Validation rows are not perturbed.
    val_fraction : float
        Last fraction of each time-ordered segment used for validation.
    bootstrap : bool
        Train each member on a bootstrap resample of the training rows (bagging),
        which spreads the members where data are thin and so calibrates the spread.
    seed : int
        Seed of the initial weights and the bootstrap draws.
    """

    n_members: Annotated[Int, Field(ge=1, le=MAX_MEMBERS)] = 10
    hidden: Annotated[Int, Field(ge=1, le=10_000)] = 20
    lr: Annotated[Float, Field(gt=0)] = 1e-2
    max_epochs: Annotated[Int, Field(ge=1)] = 800
    patience: Annotated[Int, Field(ge=1)] = 100
    weight_decay: Annotated[Float, Field(ge=0)] = 1e-5
    input_noise_std: Annotated[Float, Field(ge=0, le=10)] = 0.0
    val_fraction: Annotated[Float, Field(gt=0, lt=0.9)] = 0.2
    bootstrap: Bool = True
    seed: Seed = 0


@dataclass
class MLPEnsemble:
    """Weights and normalisation of a trained ensemble; numpy inference.

    Attributes
    ----------
    weights : list of ndarray
        ``[W1 (E, n_in, H), b1 (E, 1, H), W2 (E, H, H), b2 (E, 1, H), W3 (E, H, n_out), b3 (E, 1, n_out)]``.
    x_mean, x_std : ndarray, shape (n_in,)
        Input standardisation.
    y_mean, y_std : ndarray, shape (n_out,)
        Output standardisation.
    """

    weights: list
    x_mean: np.ndarray
    x_std: np.ndarray
    y_mean: np.ndarray
    y_std: np.ndarray
    history: dict = field(default_factory=dict)

    @property
    def n_members(self) -> int:
        return self.weights[0].shape[0]

    @property
    def n_in(self) -> int:
        return self.weights[0].shape[1]

    @property
    def n_out(self) -> int:
        return self.weights[4].shape[2]

    def predict_members(self, X: np.ndarray) -> np.ndarray:
        """Outputs of every member.

        Parameters
        ----------
        X : ndarray, shape (N, n_in) or (E, N, n_in)
            Inputs: shape (N, n_in) gives the same input to all members, shape (E, N, n_in)
            one input per member.

        Returns
        -------
        ndarray, shape (E, N, n_out)

        Raises
        ------
        TypeError, ValueError
            ``X`` is not numbers, or not of one of the shapes above.
        """
        X = real_array("X", X)
        if X.ndim not in (2, 3) or X.shape[-1] != self.n_in or (X.ndim == 3 and X.shape[0] != self.n_members):
            # numpy would broadcast a wrong width into its own message, or a 1-D row into (E, n_out)
            raise ValueError(f"X: expected shape (N, {self.n_in}) or ({self.n_members}, N, {self.n_in}) "
                             f"({self.n_in} inputs, {self.n_members} members), got {X.shape}")
        Z = (X - self.x_mean) / self.x_std
        if Z.ndim == 2:
            Z = Z[None]
        W1, b1, W2, b2, W3, b3 = self.weights
        h = np.tanh(np.matmul(Z, W1) + b1)
        h = np.tanh(np.matmul(h, W2) + b2)
        return (np.matmul(h, W3) + b3) * self.y_std + self.y_mean

    def predict(self, X: np.ndarray):
        """Ensemble mean and standard deviation over members, each ``(N, n_out)``."""
        Y = self.predict_members(X)
        return Y.mean(axis=0), Y.std(axis=0)


def _time_ordered_split(segment_id: np.ndarray, val_fraction: float) -> np.ndarray:
    """Boolean mask of validation rows: the last ``val_fraction`` of every segment."""
    is_val = np.zeros(segment_id.shape[0], dtype=bool)
    for s in np.unique(segment_id):
        idx = np.flatnonzero(segment_id == s)
        n_val = int(round(val_fraction * idx.size))
        if n_val > 0 and idx.size - n_val >= 2:
            is_val[idx[-n_val:]] = True
    return is_val


#: Fewest training rows (samples) an ensemble is fitted on.
MIN_TRAINING_ROWS = 20


def require_training_rows(n_rows: int, n_logs: int, dp_only: bool, held_back: bool = False) -> None:
    """Refuse, in the words of the logs, training data too short for the nets (``held_back``:
    part of the logs was kept back for calibration)."""
    if n_rows < MIN_TRAINING_ROWS:
        which = ("station-keeping rows (dp_active = 1) only" if dp_only else "all rows") + \
            (", after what is kept back for calibration" if held_back else "")
        raise ValueError(f"logs: {n_rows} usable training row(s) in {n_logs} log(s) ({which}); the nets need at "
                         f"least {MIN_TRAINING_ROWS}: give longer logs" + (" or train on all rows" if dp_only else ""))


def _training_rows(X, Y) -> tuple[np.ndarray, np.ndarray]:
    """``X`` (N, n_in) and ``Y`` (N, n_out) as float arrays: N >= 20 finite rows, or an error."""
    X = real_array("fit_ensemble: X", X)
    Y = real_array("fit_ensemble: Y", Y)
    if (X.ndim != 2 or Y.ndim != 2 or X.shape[0] != Y.shape[0]
            or X.shape[1] == 0 or Y.shape[1] == 0):
        raise ValueError(f"fit_ensemble: X and Y must be (N, n_in) and (N, n_out) with n_in, n_out >= 1, "
                         f"got {X.shape} and {Y.shape}")
    if X.shape[0] < MIN_TRAINING_ROWS:
        raise ValueError(f"fit_ensemble: need at least {MIN_TRAINING_ROWS} training rows, got {X.shape[0]}")
    for name, A in (("X", X), ("Y", Y)):
        if not np.all(np.isfinite(A)):
            raise ValueError(f"fit_ensemble: {name} contains NaN or inf (row {np.argwhere(~np.isfinite(A))[0, 0]})")
    return X, Y


def _segment_ids(segment_id, n_rows: int) -> np.ndarray:
    """``segment_id`` as one whole number per training row, or an error naming it: a shorter
    array would split (and train on) only its first rows, and NaN would make each row a segment."""
    seg = np.asarray(segment_id)
    if seg.dtype.kind not in "iub" and not (seg.dtype.kind == "f" and np.all(np.isfinite(seg))
                                             and np.all(seg == np.round(seg))):
        raise TypeError(f"fit_ensemble: segment_id: expected whole numbers, one per row, got dtype {seg.dtype}"
                        + (" with NaN, inf or fractions" if seg.dtype.kind == "f" else ""))
    if seg.shape != (n_rows,):
        raise ValueError(f"fit_ensemble: segment_id: expected one per row of X ({n_rows},), got shape {seg.shape}")
    return seg


def _standardise(A: np.ndarray, rows: np.ndarray):
    """``(mean, std, standardised A)`` with the statistics of ``A[rows]`` (a constant column keeps std 1)."""
    mean, std = A[rows].mean(0), A[rows].std(0)
    std = np.where(std > 1e-12, std, 1.0)
    return mean, std, (A - mean) / std


def _initial_weights(E: int, n_in: int, H: int, n_out: int, gen) -> list:
    """Batched weights and biases of ``E`` members ``n_in -> H tanh -> H tanh -> n_out``, trainable.

    Glorot-uniform weights, as Keras (the paper's toolkit) uses for dense layers, drawn from
    ``gen`` layer by layer; zero biases.
    """
    import torch

    def init(fan_in, fan_out):
        a = math.sqrt(6.0 / (fan_in + fan_out))
        return (torch.rand(E, fan_in, fan_out, generator=gen) * 2 - 1) * a

    params = [init(n_in, H), torch.zeros(E, 1, H), init(H, H), torch.zeros(E, 1, H),
              init(H, n_out), torch.zeros(E, 1, n_out)]
    for p in params:
        p.requires_grad_(True)
    return params


def _forward(params, Z):
    """Batched forward pass of the members, ``Z`` (E, n, n_in) -> (E, n, n_out) (torch)."""
    import torch

    h = torch.tanh(torch.baddbmm(params[1], Z, params[0]))
    h = torch.tanh(torch.baddbmm(params[3], h, params[2]))
    return torch.baddbmm(params[5], h, params[4])


def fit_ensemble(X: np.ndarray, Y: np.ndarray, config: EnsembleConfig = EnsembleConfig(), *,
                 segment_id: np.ndarray | None = None, progress: bool = False) -> MLPEnsemble:
    """Train an ensemble on rows ``X (N, n_in) -> Y (N, n_out)``.

    Full-batch Adam on all members at once, with early stopping on a time-ordered
    validation split (the last part of every segment, so validation data lie after the
    training data in time): each member keeps its weights from its best validation epoch;
    training stops when every member has gone ``patience`` epochs without a better one (a
    member past it trains on, keeping a later epoch only where it validates better).

    Parameters
    ----------
    X, Y : ndarray
        Finite training rows in time order.
    config : EnsembleConfig or dict
        Training settings (a dict of its fields is validated into one).
    segment_id : ndarray of int, optional
        Segment (or log) of each row; the split is made within each segment.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    MLPEnsemble

    Raises
    ------
    TypeError, ValueError
        An argument of the wrong kind or shape (text or complex rows, no input or output
        column, a ``segment_id`` not one whole number per row, a flag that is not a bool),
        naming it.
    """
    import torch
    from tqdm.auto import tqdm

    config = as_config(config, EnsembleConfig, "config")
    check_flags(progress=progress)
    X, Y = _training_rows(X, Y)
    seg = np.zeros(X.shape[0], int) if segment_id is None else _segment_ids(segment_id, X.shape[0])
    is_val = _time_ordered_split(seg, config.val_fraction)
    tr, va = np.flatnonzero(~is_val), np.flatnonzero(is_val)
    if va.size == 0:
        va = tr
    (x_mean, x_std, Zx), (y_mean, y_std, Zy) = _standardise(X, tr), _standardise(Y, tr)

    E, H, n_in, n_out = config.n_members, config.hidden, X.shape[1], Y.shape[1]
    rng = np.random.default_rng(config.seed)
    gen = torch.Generator().manual_seed(int(config.seed))
    torch_threads = torch.get_num_threads()
    torch.set_num_threads(1)  # tiny matrices: threads cost more than they give
    try:
        # Per-member training rows: bootstrap resamples (bagging) or all rows.
        if config.bootstrap:
            idx = rng.integers(0, tr.size, size=(E, tr.size))
            rows = tr[idx]
        else:
            rows = np.broadcast_to(tr, (E, tr.size))
        Xt = torch.as_tensor(Zx[rows], dtype=torch.float32)          # (E, n, n_in)
        Yt = torch.as_tensor(Zy[rows], dtype=torch.float32)          # (E, n, n_out)
        Xv = torch.as_tensor(Zx[va], dtype=torch.float32).expand(E, -1, -1)
        Yv = torch.as_tensor(Zy[va], dtype=torch.float32).expand(E, -1, -1)

        params = _initial_weights(E, n_in, H, n_out, gen)
        opt = torch.optim.Adam(params, lr=config.lr)

        best = torch.full((E,), float("inf"))
        best_params = [p.detach().clone() for p in params]
        since_best = torch.zeros(E, dtype=torch.long)
        train_curve, val_curve = [], []
        bar = tqdm(range(config.max_epochs), desc="training ensemble", disable=not progress, leave=False)
        for _epoch in bar:
            opt.zero_grad()
            # the generator is drawn from only with noise, so that none gives the same bits as before
            Xin = Xt if config.input_noise_std == 0 else (
                Xt + config.input_noise_std * torch.randn(Xt.shape, generator=gen, dtype=Xt.dtype))
            mse = ((_forward(params, Xin) - Yt) ** 2).mean(dim=(1, 2))  # per member
            l2 = sum((params[i] ** 2).sum(dim=(1, 2)) for i in (0, 2, 4))
            loss = (mse + config.weight_decay * l2).sum()
            loss.backward()
            opt.step()
            with torch.no_grad():
                v = ((_forward(params, Xv) - Yv) ** 2).mean(dim=(1, 2))
                improved = v < best
                best = torch.where(improved, v, best)
                since_best = torch.where(improved, torch.zeros_like(since_best), since_best + 1)
                for bp, p in zip(best_params, params):
                    bp[improved] = p.detach()[improved]
            train_curve.append(float(mse.detach().mean()))
            val_curve.append(float(v.mean()))
            if progress:
                bar.set_postfix(train=f"{train_curve[-1]:.3f}", val=f"{val_curve[-1]:.3f}")
            if bool((since_best > config.patience).all()):
                break
    finally:
        torch.set_num_threads(torch_threads)

    weights = [bp.numpy().astype(float) for bp in best_params]
    history = {"train_mse": train_curve, "val_mse": val_curve, "best_val_mse": best.numpy().tolist(),
               "epochs": len(train_curve), "n_train": int(tr.size), "n_val": int(va.size)}
    return MLPEnsemble(weights, x_mean, x_std, y_mean, y_std, history)
