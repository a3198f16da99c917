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


def test_manoeuvre_targets_read_their_own_rows(ts):
    """Only the hybrid's and the physics' rows of the command mode count, the heading ratio is
    the heading's, and the coverage is the one at 10 and 30 s, not at 5 or 20 s."""
    errors, cov = _esso(0.6)
    errors.loc[(errors.model == "hybrid") & (errors.state == "heading_deg") & (errors.kind == "all")
               & (errors.horizon_s == 30.0), "mae"] = 0.75
    other = errors.assign(commands="held", mae=errors.mae * 3)
    dr = errors[errors.model == "dynamic"].assign(model="dead_reckoning", mae=0.1)
    cov.loc[cov.horizon_s.isin([5.0, 20.0]), "coverage"] = 0.5
    cov = pd.concat([cov, cov.assign(sigma=1, coverage=0.99), cov.assign(commands="held", coverage=0.5)])
    st = ts.manoeuvre_status(pd.concat([errors, other, dr]), cov, "known")
    assert st["ratios"] == {"distance_m": pytest.approx(0.6), "heading_deg": pytest.approx(0.75)}
    assert st["missed"] == ["heading"] and st["below"] == 20 and st["coverage"] == {10.0: 0.95, 30.0: 0.95}


@pytest.mark.parametrize("coverage", [0.90, 0.98])
def test_the_targets_edges_are_judged_as_stated(ts, coverage):
    """The targets as the module states them, at their edges: a hybrid *equal* to the physics
    is not worse than it (``never worse``), but not *below* it in an Esso cell (``below the
    physics'``); a coverage of exactly 0.90 or 0.98 is in the band (``covers 0.90-0.98``)."""
    st = ts.drift_status(_drift_errors(lambda s, w, h: 1.0 if h == 15 else 0.3), coverage)
    assert st["worse"] == 0 and st["missed"] == []
    errors, cov = _esso(0.6, coverage=coverage)
    tie = (errors.model == "hybrid") & (errors.kind == "random") & (errors.state == "distance_m") \
        & (errors.horizon_s == 5.0)
    errors.loc[tie, "mae"] = 1.0                                   # the physics' 1.0: a tie, not below
    st = ts.manoeuvre_status(errors, cov, "known")
    assert st["below"] == 19 and st["missed"] == ["every cell"]


@pytest.mark.parametrize("change", ["nan", "zero", "cell", "model"])
def test_a_result_that_cannot_be_judged_is_an_error_naming_it(ts, change):
    e = _drift_errors(lambda s, w, h: 0.3)
    hybrid_15 = (e.model == "hybrid") & (e.horizon_s == 15)
    e = {"nan": e.assign(mae=e.mae.where(~hybrid_15)),
         "zero": e.assign(mae=e.mae.where(~hybrid_15, 0.0)),      # a ratio of 0 would meet every target
         "cell": e[~hybrid_15], "model": e[e.model != "hybrid"]}[change]
    with pytest.raises(ValueError, match="some/errors.csv: "):
        ts.drift_status(e, 0.95, "some/errors.csv")
    errors, cov = _esso(0.6)
    with pytest.raises(ValueError, match="cov.csv: 0 rows .* at 10 s"):
        ts.manoeuvre_status(errors, cov[cov.horizon_s != 10.0], "known", "err.csv", "cov.csv")


def test_the_committed_page_is_the_scripts_output_of_the_committed_results(ts):
    page = ts.RESULTS / "targets.md"
    text, inputs = ts.render()
    assert page.read_text(encoding="utf-8") == text, (
        "docs/results/targets.md is not what benchmarks/target_status.py makes of the committed "
        "results: run `python benchmarks/target_status.py --out docs/results/targets.md`")
    assert {p.name for p in inputs} >= {"errors.csv", "coverage.csv", "errors_per_log.csv", "protocols.csv"}


def _copy_inputs(ts, tmp_path):
    """The committed files the page is made of, copied under ``tmp_path``."""
    _, inputs = ts.render()
    for p in inputs:
        (tmp_path / p.relative_to(ts.RESULTS)).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / p.relative_to(ts.RESULTS)).write_bytes(p.read_bytes())
    return tmp_path


def _row(text, label):
    return next(line for line in text.splitlines() if line.startswith(f"| {label} |"))


def test_the_drift_coverage_is_the_hybrids_at_2_sigma_and_60_s(ts, tmp_path):
    results = _copy_inputs(ts, tmp_path)
    path = results / "drift-embedded" / "coverage.csv"
    cov = pd.read_csv(path)
    others = ~((cov.model == "hybrid") & (cov.sigma == 2) & (cov.horizon_s == 60))
    cov.loc[others, "coverage"] = 0.5                        # no other row may count
    cov.to_csv(path, index=False)
    assert "| 0.958 | none |" in _row(ts.render(results)[0], "embedded")
    cov.loc[~others, "coverage"] = 0.99
    cov.to_csv(path, index=False)
    assert _row(ts.render(results)[0], "embedded").endswith("| 0.990 | coverage |")
    cov[others].to_csv(path, index=False)                    # not measured is an error, not "n/a"
    assert ts.main(["--results", str(results)]) == 2


def test_the_protocol_rows_are_the_mean_over_their_folds(ts, tmp_path):
    """``protocols.csv`` holds one row per held-out log in the fleet protocol: the row is
    their mean, and the physics' rows are named ``physics`` there."""
    text = ts.render()[0]
    p = pd.read_csv(ts.RESULTS / "drift-protocols" / "protocols.csv")
    sel = p[(p.data == "truthsim-dev") & (p.protocol == "fleet") & (p.state == "yaw_deg") & (p.horizon_s == 60)]
    m = sel.groupby(["model", "window"]).mae.mean()
    want = "/".join(f"{m[('hybrid', w)] / m[('physics', w)]:.2f}" for w in (5, 20))
    assert _row(text, "truthsim-dev, fleet protocol").split(" | ")[4] == want


def test_a_missing_result_is_a_clear_error(ts, tmp_path, capsys):
    assert ts.main(["--results", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "drift-embedded/errors_per_log.csv: not found" in err and "Traceback" not in err


def test_a_nan_error_in_one_fold_or_log_is_an_error_not_skipped_by_the_mean(ts, tmp_path, capsys):
    """The protocol rows are a mean over folds and the weather groups' a mean over logs: a NaN
    error in one of them made the others' mean the row's, which passed every target."""
    folds = pd.concat([_drift_errors(lambda s, w, h: 0.3)] * 3, ignore_index=True)
    folds.loc[(folds.model == "hybrid") & (folds.horizon_s == 60) & (folds.index < 48), "mae"] = float("nan")
    with pytest.raises(ValueError, match="protocols.csv: no finite positive"):
        ts.drift_status(folds, None, "protocols.csv")
    results = _copy_inputs(ts, tmp_path)
    path = results / "drift-truthsim-dev" / "errors_per_log.csv"
    per_log = pd.read_csv(path)
    calm = per_log.log.str.startswith("calm_")
    first_calm = per_log.log[calm].iloc[0]
    per_log.loc[(per_log.log == first_calm) & (per_log.model == "hybrid"), "mae"] = float("nan")
    per_log.to_csv(path, index=False)
    assert ts.main(["--results", str(results)]) == 2
    assert "errors_per_log.csv (logs calm_*): no finite positive" in capsys.readouterr().err
