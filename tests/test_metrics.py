"""The drift tables' metrics (hybridship.evaluation.metrics) on inputs whose answer is known
by hand: absolute errors with the heading wrapped, the first-5/first-20 means, the paper's
cell layout, and the spread's coverage."""

from __future__ import annotations

import numpy as np
import pandas as pd

from hybridship.evaluation import metrics

def test_absolute_errors_are_absolute_and_yaw_is_wrapped_degrees():
    pred = np.array([[[1.0, -2.0, np.pi - 0.01]]])
    truth = np.array([[[0.0, 0.0, -np.pi + 0.01]]])
    np.testing.assert_allclose(metrics.absolute_errors(pred, truth)[0, 0], [1.0, 2.0, np.degrees(0.02)])


def test_error_table_cells_are_means_over_logs_and_the_first_w_intervals():
    k = np.arange(20.0) ** 2                            # error of interval k
    E = np.broadcast_to(k[:, None, None], (20, 1, 3)).copy()
    long = metrics.error_table({"m": [E, 2 * E]}, horizons_s=(15,))
    mae = long.set_index(["window", "state"]).mae
    np.testing.assert_allclose(mae.loc[(5, "north_m")], 1.5 * k[:5].mean())        # 9.0
    np.testing.assert_allclose(mae.loc[(20, "yaw_deg")], 1.5 * k.mean())


def test_paper_and_reduction_tables_put_first_5_before_first_20():
    rows = [dict(model=m, state=s, window=w, horizon_s=60, mae=v)
            for m, vals in {"hybrid": {5: 1.0, 20: 3.0}, "dynamic": {5: 2.0, 20: 4.0}}.items()
            for s in metrics.STATES for w, v in vals.items()]
    long = pd.DataFrame(rows)
    assert metrics.paper_table(long).loc[("hybrid", "north_m"), "60 s"] == "1.00/3.00"
    assert metrics.reduction_table(long, "hybrid").loc["east_m", "60 s"] == "50/25"


def test_coverage_counts_north_and_east_and_the_band_edge():
    truth = np.zeros((4, 1, 3))
    pred = truth.copy()
    pred[:, 0, 0] = 0.5                 # north inside 1 sigma
    pred[:, 0, 1] = 2.0                 # east exactly on the 2-sigma edge, outside 1 sigma
    std = np.ones_like(truth)
    np.testing.assert_allclose(metrics.coverage(pred, truth, std), [[0.5, 1.0]])
    # an exact forecast with zero spread is inside its band
    np.testing.assert_allclose(metrics.coverage(truth, truth, np.zeros_like(std)), [[1.0, 1.0]])


def test_coverage_interval_uses_its_sigma():
    rng = np.random.default_rng(0)
    pred = rng.normal(size=(5, 10, 2, 3))
    truth, std = np.zeros_like(pred), np.ones_like(pred)
    for sigma in (1.0, 2.0):
        k = {1.0: 0, 2.0: 1}[sigma]
        np.testing.assert_allclose(metrics.coverage_interval(pred, truth, std, sigma, n_resamples=100)[:, 0],
                                   metrics.coverage(pred, truth, std)[:, k])
