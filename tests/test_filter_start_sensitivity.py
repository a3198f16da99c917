"""The filter-start sensitivity benchmark's summary (benchmarks/filter_start_sensitivity.py)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import load_benchmark


def test_summary_reports_each_shifts_error_and_the_spread_across_shifts():
    fss = load_benchmark("filter_start_sensitivity")
    truth = np.zeros((3, 2, 3))
    pred = np.zeros((3, 2, 3))
    pred[:, :, 0] = [[1.0, 1.0], [1.0, 1.0], [4.0, 1.0]]       # north: one start moves by 3 m at the last shift
    pred[:, :, 2] = 2 * np.pi + np.radians(2.0)                 # yaw: 2 deg once wrapped, at every shift
    table = fss.summary([pred], [truth], shifts_s=(0.0, 300.0, 600.0)).set_index("what")
    assert table.loc["error, time shifted 0 s", "north_m"] == pytest.approx(1.0)
    assert table.loc["error, time shifted 600 s", "north_m"] == pytest.approx(2.5)
    assert table.loc["error, time shifted 600 s", "yaw_deg"] == pytest.approx(2.0)
    spread = table.loc["spread of the forecast across the shifts (std per start)"]
    assert spread["north_m"] == pytest.approx(np.std([1.0, 1.0, 4.0]) / 2)
    assert spread["yaw_deg"] == pytest.approx(0.0, abs=1e-9)
    assert table.loc["largest change of a forecast across the shifts", "north_m"] == pytest.approx(3.0)
