"""The hull's yaw moment in a drift, learned from the vessel's earlier failures.

A ship on station does not move through the water, so station keeping cannot show how the
hull answers the relative velocity; after a DP failure the ship drifts, and a hull model that
answers it wrongly turns the heading forecast away within a minute. On the independent
simulator's Gunnerus the largest part of that error is a yaw moment that grows with
``u_r v_r``, the form of the Munk moment of ``C_A(nu_r) nu_r`` (Fossen 2021, sec. 6.3;
``benchmarks/hull_yaw_residual.py``). A vessel's logs of earlier failures show it.

One coefficient ``k`` [rad/m^2] is learned: forecasts that start after a failure add the yaw
acceleration ``k u v`` to the physics at every step, and the environment estimator's process
model adds it after the failure too (otherwise its yaw load takes up the same hull error
during the drift, and a forecast started later in the drift counts it twice). ``u, v`` [m/s] are the body-frame
velocity over ground, not relative to the estimated current: after a failure the
estimator's current absorbs part of the same hull error, and with it the choice below was
less consistent from failure to failure (``docs/concepts/drift-hull.md``).

``k`` is chosen on the training logs' failures by the forecasts' own error, not by a
one-step fit (a drift's one-step residual is dominated by the estimator's adaptation and by
noise): forecasts started every :data:`START_EVERY_S` along each drift are rolled out once
for every candidate, each from the estimator run with that candidate (the station keeping
filtered once for all of them), the rollouts in batches per log, and ``k`` minimises their
mean absolute heading error over the horizon (:func:`choose_coefficient`). The candidates are multiples
:data:`MUNK_MULTIPLES` of the model's own Munk coefficient (:func:`munk_coefficient`), so a
multiple of 1 cancels the model's Munk moment in yaw.

The coefficient is kept only where it measurably helps out of sample: with one failure
left out at a time, the coefficient chosen on the others must lower the left-out failures'
error on average, compared with ``k = 0``, and the per-failure gains must pass a one-sided
Wilcoxon signed-rank test at :data:`KEEP_P_VALUE` (``scipy.stats.wilcoxon``); otherwise
``k`` stays 0 (:attr:`DriftHullChoice.adopted`). A few failures in different weather give
noisy choices: the mean alone once kept a coefficient that gained 0.3 % on average while
half the left-out failures lost (``docs/concepts/drift-hull.md``). The test can pass only
with :data:`MIN_FAILURES` failures or more (all five gaining gives p = 1/32).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..config import check_whole_number

__all__ = ["KEEP_P_VALUE", "MIN_FAILURES", "MUNK_MULTIPLES", "START_EVERY_S", "DriftHullChoice",
           "choose_coefficient", "gain_carries_over", "signed_rank_p", "munk_coefficient", "drift_start_rows"]

#: Candidate coefficients as multiples of the model's Munk coefficient (-2 to 2 in steps of 0.05).
MUNK_MULTIPLES = np.round(np.linspace(-2.0, 2.0, 81), 6)
#: Spacing of the forecast starts along each drift that the coefficient is chosen on [s].
START_EVERY_S = 10.0
#: Significance level of the out-of-sample check: the one-sided signed-rank test's p-value of
#: the left-out failures' gains must be below it.
KEEP_P_VALUE = 0.05
#: Failures the training logs must hold before a coefficient is chosen: the fewest whose
#: left-out gains can pass the check (p = 2**-n when all n gain; 1/16 for four).
MIN_FAILURES = 5


def munk_coefficient(model) -> float:
    """``c = (M_A22 - M_A11) / M_33`` [rad/m^2] of a dynamic model (added masses ``M_A``, total
    yaw inertia ``M_33``).

    The model's Munk moment gives the yaw acceleration ``-c u_r v_r``; a correction
    ``k u v`` with ``k = c`` cancels it, which is why the candidates are multiples of ``c``.
    """
    from ..physics.hull import mass_matrices

    M_RB, M_A = mass_matrices(model.vessel)
    return float((M_A[1, 1] - M_A[0, 0]) / (M_RB + M_A)[2, 2])


def drift_start_rows(dp_active: np.ndarray, segment_id: np.ndarray, horizon_steps: int,
                     every_steps: int) -> np.ndarray:
    """Forecast starts along a log's first drift.

    Parameters
    ----------
    dp_active, segment_id : array (N,)
        The log's station-keeping flag and gap-free segment label.
    horizon_steps, every_steps : int
        Rows of log each start needs after it (>= 0), and the spacing of the starts (>= 1) [rows].

    Returns
    -------
    ndarray of int
        Rows from the first ``dp_active == 0`` after station keeping, every ``every_steps``,
        whose next ``horizon_steps`` rows are all in that drift (before DP comes back on)
        and in the failure's gap-free segment; empty without a failure, and for a log that
        starts with ``dp_active == 0``.

    Raises
    ------
    ValueError
        A count that is not a whole number in its range (a negative horizon gave starts
        beyond the log's end, a fractional one rows that are not integers), or ``dp_active``
        and ``segment_id`` not 1-D of one length, naming the argument.
    """
    horizon_steps = check_whole_number("drift_start_rows: horizon_steps", horizon_steps, lo=0)
    every_steps = check_whole_number("drift_start_rows: every_steps", every_steps, lo=1)
    dp = np.asarray(dp_active)
    seg = np.asarray(segment_id)
    if dp.ndim != 1 or seg.shape != dp.shape:
        raise ValueError(f"drift_start_rows: dp_active, segment_id: expected two 1-D arrays of one length, got "
                         f"shapes {dp.shape} and {seg.shape}")
    off = np.flatnonzero(dp == 0)
    if off.size == 0 or off[0] == 0:
        return np.zeros(0, int)
    first = int(off[0])
    leaves = np.flatnonzero((dp[first:] != 0) | (seg[first:] != seg[first]))
    end = first + int(leaves[0]) if leaves.size else dp.size      # first row not in this drift
    return np.arange(first, end - horizon_steps, every_steps)


@dataclass(frozen=True)
class DriftHullChoice:
    """The coefficient chosen on a set of failures, and the evidence for it.

    Attributes
    ----------
    coefficient_rad_per_m2 : float
        ``k`` the forecasts use (0 when not adopted).
    munk_multiple : float
        The chosen candidate as a multiple of the model's Munk coefficient (before the check).
    adopted : bool
        Whether the out-of-sample check kept it.
    n_failures : int
        Failures it was chosen on (one drift per log: each log's first).
    error_deg : float
        Mean absolute heading error of the failures' forecasts with the chosen candidate [deg].
    error_zero_deg : float
        The same with ``k = 0`` [deg].
    error_left_out_deg : float or None
        Mean over failures of the error of the candidate chosen without that failure [deg]
        (None with fewer than two failures: no check, not adopted).
    p_value : float or None
        One-sided Wilcoxon signed-rank p-value of the left-out failures' gains (error with
        ``k = 0`` minus error with the left-out choice; zero gains dropped), None where
        ``error_left_out_deg`` is; kept only below :data:`KEEP_P_VALUE`.
    n_left_out_gains : int or None
        Left-out failures whose error the left-out choice lowered.
    """

    coefficient_rad_per_m2: float
    munk_multiple: float
    adopted: bool
    n_failures: int
    error_deg: float
    error_zero_deg: float
    error_left_out_deg: float | None
    p_value: float | None = None
    n_left_out_gains: int | None = None

    def as_dict(self) -> dict:
        return asdict(self)


def choose_coefficient(objective_rad: np.ndarray, munk_rad_per_m2: float, multiples=MUNK_MULTIPLES,
                       exclude: int | None = None) -> DriftHullChoice:
    """Choose ``k`` from the failures' heading errors at every candidate.

    Parameters
    ----------
    objective_rad : ndarray, shape (K, L)
        Mean absolute heading error [rad] of failure ``l``'s forecasts with candidate ``k``.
    munk_rad_per_m2 : float
        The model's Munk coefficient (:func:`munk_coefficient`).
    multiples : array (K,)
        The candidates as multiples of it (must contain 0).
    exclude : int, optional
        A failure (column) not to use: the one a benchmark scores (a whole number from 0 to
        ``L - 1``).

    Returns
    -------
    DriftHullChoice
        The candidate with the lowest mean error over the failures used, kept (non-zero
        ``coefficient_rad_per_m2``) only if leaving each failure out in turn, the candidate
        chosen on the others lowers the left-out failures' mean error below that of ``k = 0``
        and their gains pass the signed-rank test at :data:`KEEP_P_VALUE`.
    """
    obj = np.asarray(objective_rad, dtype=float)
    multiples = np.asarray(multiples, dtype=float)
    if obj.ndim != 2 or obj.shape[0] != multiples.size:
        raise ValueError(f"objective_rad: expected shape ({multiples.size}, n_failures), got {obj.shape}")
    zero = np.flatnonzero(multiples == 0.0)
    if zero.size != 1:
        raise ValueError("multiples: must contain 0 exactly once")
    if exclude is not None and (isinstance(exclude, bool) or not isinstance(exclude, (int, np.integer))
                                or not 0 <= exclude < obj.shape[1]):
        # a float 1.5 matched no column (every failure used), True was column 1
        raise ValueError(f"exclude: expected a failure from 0 to {obj.shape[1] - 1}, got {exclude!r}")
    used = [j for j in range(obj.shape[1]) if j != exclude]
    if not used or not np.all(np.isfinite(obj[:, used])):
        raise ValueError("objective_rad: needs finite errors of at least one failure")
    best = int(obj[:, used].mean(axis=1).argmin())
    err_zero = float(obj[zero[0], used].mean())
    left_out = p_value = n_gains = None
    carries_over = False
    if len(used) >= 2:
        errors = np.array([obj[int(obj[:, [i for i in used if i != j]].mean(axis=1).argmin()), j] for j in used])
        left_out = float(errors.mean())
        n_gains = int(np.sum(obj[zero[0], used] > errors))
        carries_over, p_value = gain_carries_over(obj[zero[0], used], errors)
    adopted = carries_over and multiples[best] != 0.0
    return DriftHullChoice(coefficient_rad_per_m2=float(multiples[best] * munk_rad_per_m2) if adopted else 0.0,
                           munk_multiple=float(multiples[best]), adopted=bool(adopted), n_failures=len(used),
                           error_deg=float(np.degrees(obj[best, used].mean())),
                           error_zero_deg=float(np.degrees(err_zero)),
                           error_left_out_deg=None if left_out is None else float(np.degrees(left_out)),
                           p_value=p_value, n_left_out_gains=n_gains)


def gain_carries_over(errors_without, errors_with) -> tuple[bool, float]:
    """The out-of-sample rule for what ``fit`` learns from failures (this coefficient, and the
    thrust-error prior of :func:`hybridship.residual.environment.thrust_error_prior_carries_over`):
    with it, the left-out failures' errors ``errors_with`` (L,) must be lower than
    ``errors_without`` (L,) on average, and their gains must pass the one-sided signed-rank
    test at :data:`KEEP_P_VALUE`. Returns whether it carries over and the p-value."""
    without, with_ = np.asarray(errors_without, dtype=float), np.asarray(errors_with, dtype=float)
    p_value = signed_rank_p(without - with_)
    return bool(with_.mean() < without.mean() and p_value < KEEP_P_VALUE), p_value


def signed_rank_p(gains: np.ndarray) -> float:
    """One-sided (gains > 0) Wilcoxon signed-rank p-value. A zero gain (a fold whose choice was
    0) is no evidence either way and is dropped, which leaves fewer failures to pass; 1 when
    all are 0.

    The zeros are dropped here rather than by ``zero_method="wilcox"``: with a zero in the
    sample, scipy before 1.15 switches to the normal approximation (and warns), which gives
    four gains and a zero p = 0.034, and scipy 1.15 on does the same above 13 failures;
    without zeros (and ties) every version computes the exact distribution up to 50."""
    from scipy import stats

    nonzero = np.asarray(gains, dtype=float)
    nonzero = nonzero[nonzero != 0.0]
    if nonzero.size == 0:
        return 1.0
    return float(stats.wilcoxon(nonzero, alternative="greater").pvalue)
