"""benchmarks/drift_late_starts.py and drift_late_coverage.py: their tables on hand-made errors."""

import numpy as np
import pandas as pd

from conftest import load_benchmark


def _errors(first: float, later: float, n_later: int = 4) -> dict:
    """:func:`drift_errors`-shaped errors: 20 first starts and ``n_later`` later ones, every state the same."""
    return {"first": np.full((20, 3), first), "later": np.full((n_later, 3), later)}


def test_a_late_starts_row_is_the_ratio_of_means_to_the_physics_and_dead_reckoning():
    """First 5/20 starts as a ratio of the means over failures to the physics'; the later starts
    pooled over all of them (a failure with more later starts weighs more), with their ratios."""
    ls = load_benchmark("drift_late_starts")
    err = [_errors(1.0, 2.0, n_later=1), _errors(3.0, 8.0, n_later=3)]      # later pooled: (2 + 3 * 8) / 4 = 6.5
    err[0]["first"][:5] = 0.0                                                # first 5: (0 + 3) / 2 = 1.5
    phys = [_errors(2.0, 13.0, n_later=1), _errors(2.0, 13.0, n_later=3)]
    dr = [_errors(4.0, 6.5, n_later=1), _errors(4.0, 6.5, n_later=3)]
    row = ls.table_row("set", "v", "what", err, phys, dr)
    for state in ls.STATES:
        # first 20: ((15 * 1) / 20 + 3) / 2 = 1.875 over 2
        assert row[f"{state} first 5/20 (x physics)"] == f"{1.5 / 2:.2f}/{1.875 / 2:.2f}"
        assert row[f"{state} later (x physics, x DR)"] == "6.50 (0.50, 1.00)"
    ref = ls.table_row("set", "physics", "what", phys, phys, dr)
    assert ref[f"{ls.STATES[0]} first 5/20 (x physics)"] == ""
    assert ref[f"{ls.STATES[0]} later (x physics, x DR)"] == "13.00 (1.00, 2.00)"


def test_the_late_coverage_error_table_pools_every_start():
    """Per log the mean of each model's errors; pooled, the mean over all starts of all logs."""
    lc = load_benchmark("drift_late_coverage")
    errors = {"a": {"hybrid": np.array([[1.0, 2.0, 3.0]]), "physics": np.array([[2.0, 2.0, 2.0]])},
              "b": {"hybrid": np.array([[3.0, 4.0, 5.0], [5.0, 6.0, 7.0]]),
                    "physics": np.array([[2.0, 2.0, 2.0], [4.0, 4.0, 4.0]])}}
    table = lc.error_table(errors)
    assert list(table.log) == ["a", "b", "pooled"] and list(table.starts) == [1, 2, 3]
    got = table.set_index("log")
    assert got.loc["b", "hybrid north/east/heading"] == "4.00/5.00/6.00"
    assert got.loc["pooled", "hybrid north/east/heading"] == "3.00/4.00/5.00"
    assert got.loc["pooled", "physics north/east/heading"] == f"{8 / 3:.2f}/{8 / 3:.2f}/{8 / 3:.2f}"


def test_the_late_coverage_truth_is_the_sample_60_s_after_each_start():
    """The truth rows are those logged 60 s after the starts; a gap there is refused, not scored
    against a later sample."""
    import pytest

    lc = load_benchmark("drift_late_coverage")
    log = pd.DataFrame({"time_s": np.arange(0.0, 200.0)})
    np.testing.assert_array_equal(lc.truth_rows(log, [10.0, 100.0]), [70, 160])
    with pytest.raises(ValueError, match="no sample at 160 s"):
        lc.truth_rows(log.drop(index=160).reset_index(drop=True), [10.0, 100.0])
