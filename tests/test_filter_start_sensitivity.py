"""The filter-start sensitivity benchmark's summary (benchmarks/filter_start_sensitivity.py)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import load_benchmark


def test_summary_reports_each_shifts_error_and_the_spread_across_shifts():
    """Errors against a non-zero truth, pooled over every start of every log (two logs with
    2 and 1 starts: a mean of the logs' means would differ), and a yaw forecast that crosses
    +-180 deg between shifts: its spread is the 2 deg it moved, not the 358 deg of the
    unwrapped values."""
    fss = load_benchmark("filter_start_sensitivity")
    shifts = (0.0, 300.0, 600.0)
    # log a: 2 starts, north truths 10 and 20 m, yaw 179 deg
    truth_a = np.zeros((3, 2, 3))
    truth_a[:, :, 0] = [10.0, 20.0]
    truth_a[:, :, 2] = np.radians(179.0)
    pred_a = truth_a.copy()
    pred_a[:, :, 0] += [[1.0, 1.0], [1.0, 1.0], [4.0, 1.0]]   # north: one start moves by 3 m at the last shift
    pred_a[1, 0, 2] = np.radians(-179.0)                        # yaw: 2 deg past 180 at the middle shift
    # log b: 1 start, 2 m short in north and 0.5 m off in east at every shift, yaw exact
    truth_b = np.full((3, 1, 3), 5.0)
    pred_b = truth_b + np.array([-2.0, 0.5, 0.0])
    table = fss.summary([pred_a, pred_b], [truth_a, truth_b], shifts_s=shifts).set_index("what")
    # pooled over the 3 starts: north (1 + 1 + 2) / 3 and (4 + 1 + 2) / 3, east 0.5 / 3
    assert table.loc["error, time shifted 0 s", "north_m"] == pytest.approx(4.0 / 3.0)
    assert table.loc["error, time shifted 600 s", "north_m"] == pytest.approx(7.0 / 3.0)
    for s in shifts:
        assert table.loc[f"error, time shifted {s:g} s", "east_m"] == pytest.approx(0.5 / 3.0)
    assert table.loc["error, time shifted 0 s", "yaw_deg"] == pytest.approx(0.0, abs=1e-9)
    assert table.loc["error, time shifted 300 s", "yaw_deg"] == pytest.approx(2.0 / 3.0)
    spread = table.loc["spread of the forecast across the shifts (std per start)"]
    assert spread["north_m"] == pytest.approx(np.std([1.0, 1.0, 4.0]) / 3)
    assert spread["east_m"] == pytest.approx(0.0, abs=1e-9)
    assert spread["yaw_deg"] == pytest.approx(np.std([0.0, 2.0, 0.0]) / 3)
    largest = table.loc["largest change of a forecast across the shifts"]
    assert largest["north_m"] == pytest.approx(3.0)
    assert largest["yaw_deg"] == pytest.approx(2.0)
