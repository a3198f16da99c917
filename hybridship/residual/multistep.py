"""Multi-step training of the residual ensemble: the error of the hybrid's own rollout.

One-step training fits the residual at measured states; a forecast evaluates it at the
states the hybrid itself reaches, and what is scored is the position and heading after
many steps. Here the nets are trained on that: from many start times of the training
logs, the hybrid is unrolled ``horizon_s`` ahead exactly as
:meth:`hybridship.predictors.HybridPredictor.rollout` does it (the physics steps the
ensemble-mean state, every member predicts its residual from the model-predicted
velocities and accelerations, the mean residual corrects the state), and the loss is

.. math::  \\frac{1}{S H} \\sum_{s, j} (\\Delta x_{sj}^2 + \\Delta y_{sj}^2 + (\\tfrac{L}{2} \\Delta\\psi_{sj})^2),

the squared position and heading errors of the forecast (heading weighted by half the
ship length ``L``, so that a heading error counts like the displacement of the bow).
Gradients flow back through the unrolled steps. The physics step is the numba kernel;
its Jacobian with respect to the state (heading and velocities; the dynamics do not
depend on the position without a current) comes from forward finite differences, one
extra batched kernel call per step (:class:`PhysicsStep`). The nets start from the
one-step fit (warm start) and each member keeps its weights of the best validation loss
(the last part of every log's starts, in time order). Because the loss is that of the
ensemble mean, the members move together and keep the spread of the one-step bagging
(the spread is calibrated afterwards in any case).
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from hybridship.config import Bool, Float, Int, config_dataclass
from hybridship.forecast_inputs.wind import HELD_WIND, WindForecast


@config_dataclass(frozen=True)
class MultiStepConfig:
    """Settings of multi-step training (validated).

    Attributes
    ----------
    horizon_s : float
        Length of each unrolled forecast [s].
    iterations : int
        Adam steps (each on one batch of starts).
    batch_starts : int
        Start times per batch.
    start_every_s : float
        Spacing of candidate start times in the training logs [s].
    lr : float
        Adam learning rate (the nets are warm-started from the one-step fit).
    val_fraction : float
        Last fraction of each log's starts used for validation (early stopping).
    val_every : int
        Validate every this many iterations.
    max_val_starts : int
        Validation starts at most (evenly thinned).
    heading_length_m : float or None
        Length that turns the heading error into metres in the loss; None: half the
        vessel's L_pp.
    fd_step : float
        Relative finite-difference step of the physics Jacobian.
    loss : {"squared", "absolute"}
        ``squared``: the mean squared position and heading errors (above);
        ``absolute``: the mean of the distance error plus ``L |dpsi|``, the form of the
        scored mean absolute errors (large errors of a few starts then weigh less).
    lead_weighting : {"uniform", "lead"}
        Weight of each step's error in the loss: equal, or proportional to its lead time
        (the late, scored part of the forecast counts more).
    curriculum_start_s : float or None
        Horizon of the first iteration [s]; it grows linearly to ``horizon_s`` over the
        first ``curriculum_fraction`` of the iterations (short rollouts first). None: the
        full horizon throughout. Validation always uses the full horizon.
    curriculum_fraction : float
        Share of the iterations over which the curriculum reaches the full horizon.
    anchor_decay : float
        Weight of an L2 penalty pulling the weights towards their one-step (warm-start)
        values, per weight and relative to the loss [m^2]; 0 = none.
    tune_hull : bool
        With a hybrid's linear hull correction
        (:class:`~hybridship.residual.hull.HullCorrection`), fine-tune its coefficients
        together with the nets (a free-run fit of the grey-box part); otherwise it is held.
    output_init : {"one_step", "zero"}
        Start of the nets: the one-step fit as it is (warm start), or its hidden layers with
        the output layer set to give no correction (the rollout then starts from the physics,
        plus any hull correction, and the nets add only what lowers the rollout error).
    hull_iterations : int
        Adam steps of the free-run fit of the hull correction alone, before the nets
        (``HybridPredictor(hull_fit="multi_step")``).
    hull_lr : float
        Learning rate of that fit (its coefficients are in units of the residual's spread).
    member_loss : {"mean", "own"}
        What each training rollout is corrected with: the members' mean residual, as a
        forecast does (``mean``: the ensemble acts as one wide net, and its members may
        drift apart where only their mean matters), or one member's residual alone
        (``own``: the batch's starts are dealt out to the members in turn, each rolls out
        with its own correction, so that every member is a forecaster on its own and their
        mean averages independent fits). Validation (the kept weights) always scores the
        mean, as forecasts use it.
    weight_average : float
        Decay per iteration of an exponential moving average of the weights (Polyak
        averaging, as in stochastic weight averaging); 0 = none. The average, not the last
        iterate, is validated and kept: each Adam step follows one small batch of starts,
        and the average smooths that noise over about ``1 / (1 - weight_average)`` steps.
    """

    horizon_s: Annotated[Float, Field(gt=0)] = 10.0
    iterations: Annotated[Int, Field(ge=1)] = 150
    batch_starts: Annotated[Int, Field(ge=1)] = 128
    start_every_s: Annotated[Float, Field(gt=0)] = 1.0
    lr: Annotated[Float, Field(gt=0)] = 1e-3
    val_fraction: Annotated[Float, Field(gt=0, lt=0.9)] = 0.2
    val_every: Annotated[Int, Field(ge=1)] = 10
    max_val_starts: Annotated[Int, Field(ge=1)] = 256
    heading_length_m: Annotated[Float, Field(ge=0)] | None = None
    fd_step: Annotated[Float, Field(gt=0, lt=1e-2)] = 1e-6
    loss: Literal["squared", "absolute"] = "squared"
    lead_weighting: Literal["uniform", "lead"] = "uniform"
    curriculum_start_s: Annotated[Float, Field(gt=0)] | None = None
    curriculum_fraction: Annotated[Float, Field(gt=0, le=1)] = 0.5
    anchor_decay: Annotated[Float, Field(ge=0)] = 0.0
    tune_hull: Bool = False
    output_init: Literal["one_step", "zero"] = "one_step"
    hull_iterations: Annotated[Int, Field(ge=1)] = 100
    hull_lr: Annotated[Float, Field(gt=0)] = 1e-2
    member_loss: Literal["mean", "own"] = "mean"
    weight_average: Annotated[Float, Field(ge=0, lt=1)] = 0.0

    @model_validator(mode="after")
    def _curriculum_within_horizon(self):
        if self.curriculum_start_s is not None and self.curriculum_start_s > self.horizon_s:
            raise ValueError(f"curriculum_start_s: must be at most horizon_s = {self.horizon_s:g} s, "
                             f"got {self.curriculum_start_s:g}")
        return self


@dataclass
class Starts:
    """Start states of training rollouts with their commands and the measured tracks.

    Attributes
    ----------
    eta0, nu0, dev0 : ndarray, shape (S, 3)
        Start pose, velocities and previous residual deviation.
    bias0 : ndarray, shape (S, 3)
        Residual bias at the start (surge/sway in NED).
    rpm, az : ndarray, shape (S, H, K)
        Logged commands of the steps after each start.
    wind : ndarray, shape (S, 1, 2) or (S, H, 2)
        Wind held at its start value, or per step as the forecast's wind forecast gives it.
    truth : ndarray, shape (S, H, 3)
        Measured pose at steps 1..H.
    is_val : ndarray of bool, shape (S,)
        Validation starts.
    dt_s : float
    memory : ndarray, shape (S, H, 2), optional
        The command-memory features of the steps
        (:data:`~hybridship.residual.features.MEMORY_FEATURES`; None when not selected).
    """

    eta0: np.ndarray
    nu0: np.ndarray
    dev0: np.ndarray
    bias0: np.ndarray
    rpm: np.ndarray
    az: np.ndarray
    wind: np.ndarray
    truth: np.ndarray
    is_val: np.ndarray
    dt_s: float
    memory: np.ndarray | None = None

    def take(self, idx) -> "Starts":
        return Starts(*(getattr(self, k)[idx] for k in ("eta0", "nu0", "dev0", "bias0", "rpm", "az", "wind",
                                                        "truth", "is_val")), self.dt_s,
                      None if self.memory is None else self.memory[idx])


def collect_starts(preps, masks, config: MultiStepConfig, dp_only: bool = True,
                   wind_forecast: WindForecast | None = None) -> Starts:
    """Start times of the training rollouts from prepared logs.

    The wind of each rollout is what a forecast from that start would use: held, or per
    step from ``wind_forecast`` (:class:`~hybridship.forecast_inputs.wind.WindForecast`).

    ``preps``: :class:`~hybridship.residual.features.PreparedLog` per log; ``masks``: a
    boolean row mask per log (None: every row) of the rows that may be used (start and
    the whole horizon inside it, in one segment, with every command logged, and station
    keeping with ``dp_only``).
    """
    out = {k: [] for k in ("eta0", "nu0", "dev0", "bias0", "rpm", "az", "wind", "truth", "is_val")}
    memory = []
    dts = set()
    for prep, mask in zip(preps, masks):
        a = prep.arrays
        n = len(a.time_s)
        dt = prep.dt_s
        dts.add(round(dt, 9))
        H = int(round(config.horizon_s / dt))
        if H < 1:       # no step to roll out: the loss would have nothing to differentiate
            raise ValueError(f"multi-step training: horizon_s: expected at least half the logs' step ({dt:g} s), "
                             f"one rollout step; got {config.horizon_s:g} s")
        if n <= H + 2:
            continue
        ok = np.ones(n, bool) if mask is None else np.asarray(mask, bool).copy()
        if dp_only:
            ok &= a.dp_active.astype(bool)
        ok &= np.isfinite(a.eta).all(1) & np.isfinite(a.nu).all(1) & np.isfinite(a.rpm).all(1) \
            & np.isfinite(a.azimuth_rad).all(1) & a.commands_logged   # not a default of an empty cell
        bad = np.concatenate([[0], np.cumsum(~ok)])
        r = np.arange(1, n - H, max(1, int(round(config.start_every_s / dt))))
        r = r[((bad[r + H + 1] - bad[r]) == 0) & (a.segment_id[r + H] == a.segment_id[r])]
        if r.size == 0:
            continue
        st = [prep.start_state(int(i)) for i in r]
        out["eta0"].append(np.array([s[0] for s in st]))
        out["nu0"].append(np.array([s[1] for s in st]))
        out["dev0"].append(np.array([s[2] for s in st]))
        out["bias0"].append(np.array([s[3] for s in st]))
        rows = r[:, None] + np.arange(H)[None, :]
        out["rpm"].append(a.rpm[rows])
        out["az"].append(a.azimuth_rad[rows])
        wf = wind_forecast if wind_forecast is not None else HELD_WIND
        out["wind"].append(wf.steps(a.wind, a.time_s, r, a.wind[r], H, dt, logged=a.wind_logged))
        out["truth"].append(a.eta[rows + 1])
        if prep.command_memory is not None:         # the logged commands are the rollout's
            memory.append(prep.command_memory[rows])
        is_val = np.zeros(r.size, bool)
        n_val = int(round(config.val_fraction * r.size))
        if n_val > 0 and r.size - n_val >= 1:
            is_val[-n_val:] = True
        out["is_val"].append(is_val)
    if not out["eta0"]:
        raise ValueError(f"multi-step training: no start time with {config.horizon_s:g} s of usable data after it")
    if len(dts) != 1:
        raise ValueError(f"multi-step training: the logs have different steps {sorted(dts)} s")
    if memory and len(memory) != len(out["eta0"]):
        raise ValueError("multi-step training: the logs were prepared with different features "
                         "(command memory in some, not in others)")
    return Starts(*(np.concatenate(out[k]) for k in out), float(dts.pop()),
                  np.concatenate(memory) if memory else None)


def _torch_physics_step():
    import torch

    from ..physics.integrate import rollout_batch
    from ..physics.rhs import dynamics_batch
    from .features import actuator_acceleration

    class PhysicsStep(torch.autograd.Function):
        """One RK4 step of the numba kernel, ``x (S, 6) -> (eta1, nu1, nu_dot1) (S, 9)``, with
        ``loads`` also the actuators' acceleration at the new state (S, 12); the Jacobian with
        respect to heading and velocities by forward differences."""

        @staticmethod
        def forward(ctx, x, rpm, az, wind, P, dt, substeps, fd_step, loads=False):
            X = x.detach().numpy()
            S = X.shape[0]
            h = fd_step * np.array([1.0, 1.0, 1.0, 1.0, 1.0, 0.1])
            Xb = np.tile(X, (5, 1))
            for k, col in enumerate((2, 3, 4, 5)):
                Xb[(k + 1) * S:(k + 2) * S, col] += h[col]
            B = Xb.shape[0]
            e1 = np.empty((B, 2, 3))
            n1 = np.empty((B, 2, 3))
            a1 = np.empty((B, 2, 3))
            z3 = np.zeros((B, 1, 3))
            rollout_batch(np.ascontiguousarray(Xb[:, :3]), np.ascontiguousarray(Xb[:, 3:]),
                          np.ascontiguousarray(np.tile(rpm, (5, 1, 1))), np.ascontiguousarray(np.tile(az, (5, 1, 1))),
                          np.ascontiguousarray(np.tile(wind, (5, 1, 1))), np.zeros((B, 1, 2)), z3, z3, P, dt, 1,
                          int(substeps), e1, n1, a1)
            Y = [e1[:, 1], n1[:, 1], a1[:, 1]]
            if loads:       # the step's commands at the new state, as the forecast's features
                parts = np.empty((B, 4, 3))
                dynamics_batch(np.ascontiguousarray(e1[:, 1]), np.ascontiguousarray(n1[:, 1]),
                               np.ascontiguousarray(np.tile(rpm[:, 0], (5, 1))),
                               np.ascontiguousarray(np.tile(az[:, 0], (5, 1))),
                               np.ascontiguousarray(np.tile(wind[:, 0], (5, 1))), np.zeros((B, 2)), np.zeros((B, 3)),
                               np.zeros((B, 3)), P, np.empty((B, 3)), parts, np.empty((B, max(P.thr.shape[0], 1))))
                Y.append(actuator_acceleration(P, parts))
            Y = np.concatenate(Y, axis=1)                                       # (5S, 9 or 12)
            Y0 = Y[:S]
            J = np.zeros((S, Y.shape[1], 6))
            J[:, 0, 0] = 1.0                                                    # position shifts the pose only
            J[:, 1, 1] = 1.0
            for k, col in enumerate((2, 3, 4, 5)):
                J[:, :, col] = (Y[(k + 1) * S:(k + 2) * S] - Y0) / h[col]
            ctx.save_for_backward(torch.from_numpy(J))
            return torch.from_numpy(Y0.copy())

        @staticmethod
        def backward(ctx, grad_y):
            (J,) = ctx.saved_tensors
            return torch.einsum("so,sok->sk", grad_y, J), None, None, None, None, None, None, None, None

    return PhysicsStep


def _full_features(e1, n1, a1, r_prev, s: Starts, j: int, use_cmd: bool, scales: dict, loads=None):
    """Every feature of :data:`~hybridship.residual.features.ALL_FEATURES` at rollout step ``j``
    (torch, (E, S, F)) from the physics step ``e1, n1, a1`` (S, 3) and the members' previous
    residuals ``r_prev`` (E, S, 3); the command-aware ones are zeros unless ``use_cmd``, the
    command-memory ones unless the starts carry them, the actuator-load ones unless ``loads``
    (S, 3) are given."""
    import torch

    from .features import COMMAND_FEATURES, LOAD_FEATURES, MEMORY_FEATURES, command_feature_columns

    E, S = r_prev.shape[0], n1.shape[0]
    cols = [n1.expand(E, S, 3), a1.expand(E, S, 3), r_prev]
    if use_cmd:
        jp = max(j - 1, 0)
        cf = command_feature_columns(n1, e1[:, 2], s.rpm[:, j], s.rpm[:, jp], s.az[:, j], s.az[:, jp],
                                     s.wind[:, min(j, s.wind.shape[1] - 1)], s.dt_s, scales["rpm_scale"],
                                     scales["angle_channel"], lib=torch)
        cols.append(cf.expand(E, S, cf.shape[-1]))
    else:
        cols.append(torch.zeros((E, S, len(COMMAND_FEATURES)), dtype=n1.dtype))
    if s.memory is not None:
        cols.append(torch.as_tensor(s.memory[:, j], dtype=n1.dtype).expand(E, S, len(MEMORY_FEATURES)))
    else:
        cols.append(torch.zeros((E, S, len(MEMORY_FEATURES)), dtype=n1.dtype))
    cols.append(torch.zeros((E, S, len(LOAD_FEATURES)), dtype=n1.dtype) if loads is None
                else loads.expand(E, S, len(LOAD_FEATURES)))
    return torch.cat(cols, dim=2)


def _train_val_starts(starts: Starts, max_val_starts: int):
    """Indices of the training starts and of at most ``max_val_starts`` validation starts
    (spread evenly; the training starts when no start is held out)."""
    tr = np.flatnonzero(~starts.is_val)
    va = np.flatnonzero(starts.is_val)
    if va.size == 0:
        va = tr
    if va.size > max_val_starts:
        va = va[np.linspace(0, va.size - 1, max_val_starts).round().astype(int)]
    return tr, va


def _member_residuals(params, feats, x_mean, x_std, y_mean, y_std):
    """Every member's residual acceleration from its features (torch), ``(E, S, 3)``."""
    import torch

    z = (feats - x_mean) / x_std
    hdn = torch.tanh(torch.baddbmm(params[1], z, params[0]))
    hdn = torch.tanh(torch.baddbmm(params[3], hdn, params[2]))
    return torch.baddbmm(params[5], hdn, params[4]) * y_std + y_mean


def _corrected_step(e1, n1, r, bias, dt: float, member=None):
    """The physics step ``(e1, n1)`` corrected by the mean residual ``r`` (E, S, 3) (or, with
    ``member`` (S,), each start's own member's) plus the NED bias ``bias`` (rotated into the
    body frame), held over the step ``dt`` [s]: ``(eta, nu)`` (torch)."""
    import torch

    c, sn = torch.cos(e1[:, 2]), torch.sin(e1[:, 2])
    rb = torch.stack([c * bias[:, 0] + sn * bias[:, 1], -sn * bias[:, 0] + c * bias[:, 1], bias[:, 2]], 1)
    rm = (r.mean(0) if member is None else r[member, torch.arange(r.shape[1])]) + rb
    nu = n1 + dt * rm
    half = 0.5 * dt * dt
    eta = torch.stack([e1[:, 0] + half * (c * rm[:, 0] - sn * rm[:, 1]),
                       e1[:, 1] + half * (sn * rm[:, 0] + c * rm[:, 1]),
                       e1[:, 2] + half * rm[:, 2]], 1)
    return eta, nu


def _step_error(d, heading_length_m: float, loss: str):
    """Per-start error of one step from ``d = predicted - true [north, east, psi]`` (S, 3):
    squared distance plus ``(L dpsi)^2``, or distance plus ``L |dpsi|`` (a smoothed norm,
    so that the gradient stays finite at zero error)."""
    import torch

    dpsi = torch.atan2(torch.sin(d[:, 2]), torch.cos(d[:, 2]))
    if loss == "squared":
        return d[:, 0] ** 2 + d[:, 1] ** 2 + (heading_length_m * dpsi) ** 2
    return torch.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2 + 1e-8) + heading_length_m * torch.sqrt(dpsi ** 2 + 1e-8)


def _lead_weights(config: MultiStepConfig, H: int) -> np.ndarray:
    """Weights (H,) of the steps' errors in the loss, summing to 1: equal, or proportional to
    the lead (``lead_weighting``)."""
    w = np.ones(H) if config.lead_weighting == "uniform" else np.arange(1, H + 1, dtype=float)
    return w / w.sum()


def _curriculum_horizon(config: MultiStepConfig, it: int, H: int, dt: float) -> int:
    """Rollout steps of iteration ``it``: the full ``H``, or growing from
    ``curriculum_start_s`` to ``H`` over the first ``curriculum_fraction`` of the iterations."""
    if config.curriculum_start_s is None:
        return H
    h0 = max(1, int(round(config.curriculum_start_s / dt)))
    ramp = max(1, int(round(config.curriculum_fraction * config.iterations)))
    return int(round(h0 + (H - h0) * min(1.0, it / ramp)))


def train_multistep(ensemble, model, starts: Starts, feature_index, config: MultiStepConfig, *,
                    substeps: int = 1, seed: int = 0, progress: bool = False, hull=None):
    """Fine-tune a one-step :class:`~hybridship.residual.ensemble.MLPEnsemble` on the multi-step loss.

    ``hull``: the hybrid's :class:`~hybridship.residual.hull.HullCorrection` (None: none),
    added to every step's residual, and fine-tuned too with ``config.tune_hull``. With
    ``ensemble=None`` only the hull correction is trained (a free-run fit of the grey-box
    part before the nets; the returned ensemble is then None).

    Returns a new ensemble (same normalisation, weights of the best validation loss) and a
    history dict (``train_loss``, ``val_loss``, ``best_val_loss``, ``iterations``, ``n_starts``;
    ``hull``, the tuned correction, when one was tuned).
    """
    import torch
    from tqdm.auto import tqdm

    from .ensemble import MLPEnsemble
    from .features import ALL_FEATURES, COMMAND_FEATURES, LOAD_FEATURES, command_scales

    PhysicsStep = _torch_physics_step()
    P = model.arrays
    dt = starts.dt_s
    H = starts.truth.shape[1]
    L = config.heading_length_m if config.heading_length_m is not None else 0.5 * model.vessel.particulars.L_pp_m
    fidx = torch.as_tensor(np.asarray(feature_index), dtype=torch.long)
    tr, va = _train_val_starts(starts, config.max_val_starts)
    rng = np.random.default_rng(seed)
    dd = torch.float64
    nets = ensemble is not None
    params, n_net, scale, tune_hull = _trainable_params(ensemble, hull, config)
    E = ensemble.n_members if nets else 1
    use_cmd, use_load = (any(ALL_FEATURES[i] in group for i in np.asarray(feature_index))
                         for group in (COMMAND_FEATURES, LOAD_FEATURES))
    scales = command_scales(model, model.vessel.rotatable)

    def rollout_loss(s: Starts, H=H, own=False):
        S = s.eta0.shape[0]
        member = torch.arange(S) % E if own else None       # "own": start k with member k mod E alone
        x = torch.as_tensor(np.concatenate([s.eta0, s.nu0], axis=1), dtype=dd)
        r_prev = torch.as_tensor(s.dev0, dtype=dd).expand(E, S, 3)
        bias = torch.as_tensor(s.bias0, dtype=dd)
        truth = torch.as_tensor(s.truth, dtype=dd)
        loss = torch.zeros((), dtype=dd)
        w = _lead_weights(config, H)
        for j in range(H):
            jw = min(j, s.wind.shape[1] - 1)
            y = PhysicsStep.apply(x, s.rpm[:, j:j + 1], s.az[:, j:j + 1], s.wind[:, jw:jw + 1], P, dt, substeps,
                                  config.fd_step, use_load)
            e1, n1, a1 = y[:, :3], y[:, 3:6], y[:, 6:9]
            full = _full_features(e1, n1, a1, r_prev, s, j, use_cmd, scales, y[:, 9:12] if use_load else None)
            r = r_prev = _step_residual(params, n_net, full, fidx, ensemble, hull, scale)     # (E, S, 3)
            eta, nu = _corrected_step(e1, n1, r, bias, dt, member)
            x = torch.cat([eta, nu], 1)
            loss = loss + w[j] * _step_error(eta - truth[:, j], L, config.loss).mean()
        return loss

    params0 = best_params = [p.detach().clone() for p in params]      # neither is changed in place
    n_weights = sum(p.numel() for p in params)
    opt = torch.optim.Adam([p for p in params if p.requires_grad], lr=config.lr)
    val_data = starts.take(va)
    with torch.no_grad():
        best = float(rollout_loss(val_data))
    averaged = [p.detach().clone() for p in params] if config.weight_average > 0 else None
    hist = {"train_loss": [], "val_loss": [best], "iterations": 0, "n_starts": int(tr.size),
            "n_val_starts": int(va.size)}
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        bar = tqdm(range(config.iterations), desc="multi-step training", disable=not progress, leave=False)
        for it in bar:
            batch = starts.take(rng.choice(tr, size=min(config.batch_starts, tr.size), replace=False))
            opt.zero_grad()
            loss = rollout_loss(batch, _curriculum_horizon(config, it, H, dt), own=config.member_loss == "own")
            if config.anchor_decay > 0:
                loss = loss + config.anchor_decay / n_weights * sum(((p - p0) ** 2).sum()
                                                                    for p, p0 in zip(params, params0))
            loss.backward()
            opt.step()
            _update_average(averaged, params, config.weight_average, it)
            hist["train_loss"].append(float(loss.detach()))
            hist["iterations"] = it + 1
            if (it + 1) % config.val_every == 0 or it + 1 == config.iterations:
                with torch.no_grad(), _weights_swapped(params, averaged):
                    v = float(rollout_loss(val_data))
                    if v < best:
                        best_params = [p.detach().clone() for p in params]
                hist["val_loss"].append(v)
                best = min(best, v)
                if progress:
                    bar.set_postfix(train=f"{hist['train_loss'][-1]:.4g}", val=f"{v:.4g}")
    finally:
        torch.set_num_threads(threads)
    hist["best_val_loss"] = best
    if tune_hull:
        hist["hull"] = replace(hull, theta=best_params[n_net].numpy() * scale,
                               offset=best_params[n_net + 1].numpy() * scale)
    if not nets:
        return None, hist
    return MLPEnsemble([p.numpy().astype(float) for p in best_params[:n_net]], ensemble.x_mean, ensemble.x_std,
                       ensemble.y_mean, ensemble.y_std, dict(ensemble.history)), hist


def _update_average(averaged, params, decay: float, it: int):
    """Move the moving average ``averaged`` of the weights towards ``params`` (in place; none
    without an average). The decay is ``min(decay, (1 + it) / (10 + it))``, so that the first
    iterations do not leave the average near the warm start (as TensorFlow's moving averages
    do with ``num_updates``)."""
    if averaged is None:
        return
    import torch

    d = min(decay, (1.0 + it) / (10.0 + it))
    with torch.no_grad():
        for a, p in zip(averaged, params):
            a.mul_(d).add_(p.detach(), alpha=1.0 - d)


@contextmanager
def _weights_swapped(params, averaged):
    """Within the block the tensors ``params`` hold the averaged weights (unchanged without
    an average); the trained weights come back after it."""
    if averaged is None:
        yield
        return
    saved = [p.detach().clone() for p in params]
    for p, a in zip(params, averaged):
        p.data.copy_(a)
    try:
        yield
    finally:
        for p, w in zip(params, saved):
            p.data.copy_(w)


def _step_residual(params, n_net: int, full, fidx, ensemble, hull, scale):
    """The members' residuals (E, S, 3) of one rollout step from the full features (E, S, F):
    the nets' (none without an ensemble) plus the hull correction's (see :func:`_trainable_params`)."""
    import torch

    dd = full.dtype
    if ensemble is not None:
        r = _member_residuals(params, full[..., fidx], *(torch.as_tensor(a, dtype=dd) for a in (
            ensemble.x_mean, ensemble.x_std, ensemble.y_mean, ensemble.y_std)))
    else:
        r = torch.zeros(full.shape[:2] + (3,), dtype=dd)
    if hull is not None:
        sc = torch.as_tensor(scale, dtype=dd)
        r = r + hull.predict_torch(full[0], params[n_net] * sc, params[n_net + 1] * sc)
    return r


def _trainable_params(ensemble, hull, config: MultiStepConfig):
    """``(params, n_net, scale, tune_hull)``: the torch tensors of the nets' weights (trained),
    then the hull correction's coefficients and offset (trained with ``config.tune_hull``, or
    when there are no nets) in units of ``scale`` (the nets' output spread, else the hull's
    target spread), so that one Adam step size suits both."""
    import torch

    nets = ensemble is not None
    if not nets and hull is None:
        raise ValueError("train_multistep: nothing to train (no ensemble and no hull correction)")
    weights = [np.array(w, dtype=float) for w in ensemble.weights] if nets else []
    if nets and config.output_init == "zero":       # output layer: exactly no correction
        weights[4][:] = 0.0
        weights[5][:] = -ensemble.y_mean / ensemble.y_std
    params = [torch.tensor(w, dtype=torch.float64, requires_grad=True) for w in weights]
    n_net = len(params)
    scale = ensemble.y_std if nets else hull.scale
    tune_hull = hull is not None and (config.tune_hull or not nets)
    if hull is not None:
        params += [torch.tensor(hull.theta / scale, dtype=torch.float64, requires_grad=tune_hull),
                   torch.tensor(hull.offset / scale, dtype=torch.float64, requires_grad=tune_hull)]
    return params, n_net, scale, tune_hull
