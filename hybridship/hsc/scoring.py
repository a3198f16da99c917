"""Scores of the paper's Tables 1 and 2: correlation coefficient R and mean absolute error.

``MAE = mean |y_hat - y|`` (the paper's eq. 19) and ``R`` the Pearson correlation between
prediction and measurement (eq. 20). Scores are taken in table units: ship speed in
knots and pitch in degrees.
"""

from __future__ import annotations

import numpy as np

from ..config import real_array

__all__ = ["correlation", "mean_absolute_error", "score"]


def _pair(y_true, y_pred):
    # text such as "1.5" was parsed as a number, other text failed in numpy's words
    a = real_array("y_true", y_true).ravel()
    b = real_array("y_pred", y_pred).ravel()
    if a.shape != b.shape:
        raise ValueError(f"y_true and y_pred differ in size: {a.size} vs {b.size}")
    shapes = np.squeeze(y_true).shape, np.squeeze(y_pred).shape
    if shapes[0] != shapes[1]:
        # flattened, a transposed array pairs samples that do not belong together
        raise ValueError(f"y_true and y_pred differ in shape: {shapes[0]} vs {shapes[1]}; expected the same "
                         f"samples in the same layout (one output's series)")
    if a.size < 2:
        raise ValueError("need at least two samples")
    if not np.all(np.isfinite(a)):
        # a measurement gap is the caller's to cut out; scored through, it would hide as NaN
        raise ValueError(f"y_true: {int((~np.isfinite(a)).sum())} NaN or inf value(s); expected finite measurements")
    return a, b


def mean_absolute_error(y_true, y_pred) -> float:
    """``mean(|y_pred - y_true|)``; NaN if the prediction has non-finite values."""
    a, b = _pair(y_true, y_pred)
    if not np.all(np.isfinite(b)):
        return float("nan")
    return float(np.mean(np.abs(b - a)))


def correlation(y_true, y_pred) -> float:
    """Pearson correlation coefficient ``R`` (NaN for a constant or non-finite series)."""
    a, b = _pair(y_true, y_pred)
    if not np.all(np.isfinite(b)):
        return float("nan")
    da, db = a - a.mean(), b - b.mean()
    den = np.sqrt((da * da).sum() * (db * db).sum())
    return float((da * db).sum() / den) if den > 0 else float("nan")


def score(y_true, y_pred) -> tuple[float, float]:
    """``(R, MAE)`` of one output."""
    return correlation(y_true, y_pred), mean_absolute_error(y_true, y_pred)
