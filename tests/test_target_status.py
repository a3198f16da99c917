"""benchmarks/target_status.py: the status against the issues' targets is read from the
committed results, judges each target as stated, and the committed page is its output."""

import itertools

import pandas as pd
import pytest

from conftest import load_benchmark

HORIZONS = (15, 30, 45, 60)


@pytest.fixture(scope="module")
def ts():
    return load_benchmark("target_status")


def _drift_errors(ratio) -> pd.DataFrame:
    """Pooled drift errors whose hybrid/dynamic ratio is ``ratio(state, window, horizon)``."""
    rows = []
    for s, w, h in itertools.product(("north_m", "east_m", "yaw_deg"), (5, 20), HORIZONS):
        rows += [("dynamic", s, w, h, 2.0), ("hybrid", s, w, h, 2.0 * ratio(s, w, h))]
    return pd.DataFrame(rows, columns=["model", "state", "window", "horizon_s", "mae"])


def test_drift_targets_met_at_the_thresholds(ts):
    st = ts.drift_status(_drift_errors(lambda s, w, h: 0.7 if s == "yaw_deg" else 0.5), 0.95)
    assert st["missed"] == [] and st["worse"] == 0 and st["cells"] == 24
    assert st["ratios"][("yaw_deg", 20)] == pytest.approx(0.7) and st["horizon_s"] == 60


def test_drift_targets_missed_name_the_state_window_and_worse_cells(ts):
    def ratio(s, w, h):
        if s == "east_m" and h == 30:
            return 1.2                                  # worse than physics at 30 s only
        return 0.71 if (s == "yaw_deg" and w == 20) else 0.3

    st = ts.drift_status(_drift_errors(ratio), 0.85)
    assert st["worse"] == 2
    assert st["missed"] == ["heading (20)", "never worse: east at 30 s (5/20)", "coverage"]


def test_drift_coverage_not_measured_is_not_a_miss(ts):
    st = ts.drift_status(_drift_errors(lambda s, w, h: 0.3), None)
    assert st["missed"] == [] and st["coverage"] is None


def _esso(ratio_30, below=True, coverage=0.95):
    kinds = ("random", "turning", "zigzag", "berthing", "all")
    rows = []
    for k, h in itertools.product(kinds, (5.0, 10.0, 20.0, 30.0)):
        for state in ("distance_m", "heading_deg"):
            r = ratio_30 if (k == "all" and h == 30.0) else (0.9 if below else 1.1)
            rows += [("dynamic", k, state, h, 1.0, "known"), ("hybrid", k, state, h, r, "known")]
    errors = pd.DataFrame(rows, columns=["model", "kind", "state", "horizon_s", "mae", "commands"])
    cov = pd.DataFrame([("hybrid", "all", "known", h, 2, coverage) for h in (5.0, 10.0, 20.0, 30.0)],
                       columns=["model", "kind", "commands", "horizon_s", "sigma", "coverage"])
    return errors, cov


def test_manoeuvre_targets(ts):
    st = ts.manoeuvre_status(*_esso(0.7), "known")
    assert st["missed"] == [] and st["below"] == st["cells"] == 20 and st["coverage"] == {10.0: 0.95, 30.0: 0.95}
    st = ts.manoeuvre_status(*_esso(0.71, below=False, coverage=0.99), "known")
    assert st["missed"] == ["every cell", "distance", "heading", "coverage"] and st["below"] == 1


def test_the_committed_page_is_the_scripts_output_of_the_committed_results(ts):
    page = ts.RESULTS / "targets.md"
    text, inputs = ts.render()
    assert page.read_text(encoding="utf-8") == text, (
        "docs/results/targets.md is not what benchmarks/target_status.py makes of the committed "
        "results: run `python benchmarks/target_status.py --out docs/results/targets.md`")
    assert all(p.is_relative_to(ts.RESULTS) for p in inputs)


def test_a_missing_result_is_a_clear_error(ts, tmp_path, capsys):
    assert ts.main(["--results", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "drift-embedded/errors_per_log.csv: not found" in err and "Traceback" not in err
