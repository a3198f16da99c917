"""benchmarks/drift_late_starts.py and drift_late_coverage.py: their tables on hand-made errors."""

import numpy as np
import pandas as pd
import pytest

from conftest import load_benchmark


def _errors(first: float, later: float, n_later: int = 4, per_state=(1.0, 1.0, 1.0)) -> dict:
    """:func:`drift_errors`-shaped errors: 20 first starts and ``n_later`` later ones, each state
    ``per_state`` times the value (by default every state the same)."""
    scale = np.asarray(per_state, dtype=float)
    return {"first": np.full((20, 3), first) * scale, "later": np.full((n_later, 3), later) * scale}


def test_a_late_starts_row_is_the_ratio_of_means_to_the_physics_and_dead_reckoning():
    """First 5/20 starts as a ratio of the means over failures to the physics'; the later starts
    pooled over all of them (a failure with more later starts weighs more), with their ratios."""
    ls = load_benchmark("drift_late_starts")
    per_state = (1.0, 2.0, 4.0)          # the variant's errors differ by state, the references' do not
    err = [_errors(1.0, 2.0, n_later=1, per_state=per_state),
           _errors(3.0, 8.0, n_later=3, per_state=per_state)]               # later pooled: (2 + 3 * 8) / 4 = 6.5
    err[0]["first"][:5] = 0.0                                                # first 5: (0 + 3) / 2 = 1.5
    phys = [_errors(2.0, 13.0, n_later=1), _errors(2.0, 13.0, n_later=3)]
    dr = [_errors(4.0, 6.5, n_later=1), _errors(4.0, 6.5, n_later=3)]
    row = ls.table_row("set", "v", "what", err, phys, dr)
    for state, f in zip(ls.STATES, per_state, strict=True):
        # first 20: ((15 * 1) / 20 + 3) / 2 = 1.875 over 2
        assert row[f"{state} first 5/20 (x physics)"] == f"{f * 1.5 / 2:.2f}/{f * 1.875 / 2:.2f}"
        assert row[f"{state} later (x physics, x DR)"] == f"{f * 6.5:.2f} ({f * 0.5:.2f}, {f * 1.0:.2f})"
    ref = ls.table_row("set", "physics", "what", phys, phys, dr)
    assert ref[f"{ls.STATES[0]} first 5/20 (x physics)"] == ""
    assert ref[f"{ls.STATES[0]} later (x physics, x DR)"] == "13.00 (1.00, 2.00)"


def _at_leads(errors_60s, n_leads: int = 4, earlier: float = -1.0) -> np.ndarray:
    """(starts, 3) errors at 60 s as :func:`late_errors` gives them, (starts, leads, 3): the
    earlier leads hold ``earlier``, so a table that reads them instead of 60 s shows it."""
    e = np.asarray(errors_60s, dtype=float)
    return np.concatenate([np.full((e.shape[0], n_leads - 1, 3), earlier), e[:, None, :]], axis=1)


def test_the_choice_summary_sums_the_later_ratios_per_set_and_over_the_choice_sets():
    """The default's load walks were chosen by the smallest sum of the later starts' three
    ratios to the physics over our own two sets; the table prints that sum, and the committed
    table is what the committed rows give."""
    from pathlib import Path

    from hybridship.fileio import markdown_table

    ls = load_benchmark("drift_late_starts")
    phys = [_errors(2.0, 4.0)]
    rows = [ls.table_row(d, v, "", [_errors(2.0, later)], phys, phys)
            for d in ("embedded", "truthsim-dev", "own 100-119") for v, later in (("a", 2.0), ("b", 1.0))]
    rows += [ls.table_row("embedded", "physics", "", phys, phys, phys)]
    md = ls.choice_summary(pd.DataFrame(rows))
    assert "| a | 1.50 | 1.50 | 1.50 | 3.00 |" in md and "| b | 0.75 | 0.75 | 0.75 | 1.50 |" in md
    assert "physics" not in md.split("\n", 2)[2]
    folder = Path(__file__).resolve().parents[1] / "docs" / "results" / "drift-late-starts"
    df = pd.read_csv(folder / "late_starts.csv", keep_default_na=False)
    assert (folder / "late_starts.md").read_text() == markdown_table(df) + "\n\n" + ls.choice_summary(df) + "\n"


def test_the_late_coverage_starts_are_the_first_20_samples_and_every_10_s_from_20_s_on():
    """After the failure at 50 s of a log that ends at 200 s: its first 20 samples, and every 10 s
    from 70 s to 140 s, the last start with its 60 s in the log."""
    lc = load_benchmark("drift_late_coverage")
    t = np.arange(0.0, 201.0)
    log = pd.DataFrame({"time_s": t, "dp_active": (t < 50.0).astype(int)})
    starts = lc.starts_after_failure(log)
    assert starts["first 20 s"] == list(np.arange(50.0, 70.0))
    assert starts["20 s and later"] == list(np.arange(70.0, 141.0, 10.0))


def test_the_late_coverage_score_reads_the_60_s_forecast_against_the_log():
    """score: at 60 s, the share of north/east errors (pooled) and of wrapped heading errors
    inside 2 sigma, the mean north/east 1-sigma band, the RMS north/east error and the starts
    noted as beyond the calibrated ones."""
    from types import SimpleNamespace

    lc = load_benchmark("drift_late_coverage")
    t = np.arange(0.0, 200.0)
    log = pd.DataFrame({"time_s": t, "north_m": t, "east_m": -t, "heading_deg": np.full(200, 179.0)})

    class Stub:
        def forecast(self, log_, starts, horizon_s):
            eta = np.zeros((2, 61, 3))
            std = np.zeros((2, 61, 3))
            end = np.asarray(starts) + 60.0
            eta[:, -1, 0] = end + [3.0, -1.0]                    # north errors 3, -1
            eta[:, -1, 1] = -end + [1.0, 5.0]                    # east errors 1, 5
            eta[:, -1, 2] = np.radians(-179.0)                   # 2 deg from the logged heading, across the wrap
            std[:, -1] = [[2.0, 2.4, np.radians(1.5)], [2.0, 2.4, np.radians(0.5)]]
            return SimpleNamespace(eta=eta, eta_std=std,
                                   notes=("forecast starts within 20 s of a failure: beyond the calibrated starts",
                                          "a gap in the log"))

    got = lc.score(Stub(), log, [10.0, 100.0])
    assert got["starts"] == 2
    assert got["north/east in 2 sigma"] == pytest.approx(0.75)         # 3 <= 4, 1 <= 4, 1 <= 4.8, not 5
    assert got["heading in 2 sigma"] == pytest.approx(0.5)             # 2 deg <= 3 deg, not <= 1 deg
    assert got["mean 1-sigma [m]"] == pytest.approx(2.2)
    assert got["RMS error [m]"] == pytest.approx(3.0)                  # sqrt((9 + 1 + 1 + 25) / 4)
    assert got["noted as late"] == 1


def test_the_late_coverage_error_table_pools_every_start():
    """Per log the mean of each model's 60-s errors; pooled, the mean over all starts of all logs."""
    lc = load_benchmark("drift_late_coverage")
    errors = {"a": {"hybrid": _at_leads([[1.0, 2.0, 3.0]]), "physics": _at_leads([[2.0, 2.0, 2.0]]),
                    "hybrid in 2 sigma": np.ones((1, 4, 3), bool)},
              "b": {"hybrid": _at_leads([[3.0, 4.0, 5.0], [5.0, 6.0, 7.0]]),
                    "physics": _at_leads([[2.0, 2.0, 2.0], [4.0, 4.0, 4.0]]),
                    "hybrid in 2 sigma": np.zeros((2, 4, 3), bool)}}
    table = lc.error_table(errors)
    assert list(table.columns) == ["log", "starts", "hybrid north/east/heading", "physics north/east/heading"]
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


def test_the_late_coverage_horizon_table_pools_each_lead_and_the_coverage():
    """Per lead, the mean over all later starts of all logs, and the share inside 2 sigma
    (north and east together, heading apart)."""
    lc = load_benchmark("drift_late_coverage")
    assert lc.HORIZONS_S == (15.0, 30.0, 45.0, 60.0)
    lead = np.arange(1.0, 5.0)[None, :, None]                       # errors 1, 2, 3, 4 at the four leads
    inside_a = np.zeros((1, 4, 3), bool)
    inside_a[0, :, 0] = True                                         # north inside at every lead
    inside_b = np.zeros((3, 4, 3), bool)
    inside_b[:, 1, 2] = True                                         # heading inside at 30 s
    errors = {"a": {"hybrid": np.ones((1, 1, 3)) * lead, "hybrid in 2 sigma": inside_a},
              "b": {"hybrid": np.full((3, 1, 3), 3.0) * lead, "hybrid in 2 sigma": inside_b}}
    table = lc.horizon_table(errors).set_index("lead [s]")
    assert list(table.index) == ["15", "30", "45", "60"]
    assert table.loc["15", "hybrid north/east/heading"] == "2.50/2.50/2.50"       # (1 + 3 * 3) / 4
    assert table.loc["60", "hybrid north/east/heading"] == "10.00/10.00/10.00"
    assert table.loc["15", "hybrid in 2 sigma (north/east, heading)"] == "0.12, 0.00"   # 1 of 8 north/east
    assert table.loc["30", "hybrid in 2 sigma (north/east, heading)"] == "0.12, 0.75"


def test_the_late_coverage_scores_each_lead_against_its_own_sample():
    """late_errors reads the forecast at 15, 30, 45 and 60 s against the samples logged then,
    wraps the heading and marks the errors inside twice the spread; a model without a spread
    gets no coverage entry."""
    from types import SimpleNamespace

    lc = load_benchmark("drift_late_coverage")
    t = np.arange(0.0, 200.0)
    log = pd.DataFrame({"time_s": t, "north_m": t, "east_m": -t, "heading_deg": np.full(200, 179.0)})

    class Constant:
        def __init__(self, std):
            self.std = std

        def forecast(self, log_, starts, horizon_s):
            eta = np.zeros((len(starts), 61, 3))
            eta[..., 2] = np.radians(-179.0)                         # 2 deg from the logged heading, across the wrap
            std = None if self.std is None else np.full_like(eta, self.std)
            return SimpleNamespace(eta=eta, eta_std=std)

    out = lc.late_errors({"hybrid": Constant(20.0), "physics": Constant(None)}, log, [10.0, 100.0])
    assert set(out) == {"hybrid", "physics", "hybrid in 2 sigma"}
    np.testing.assert_allclose(out["hybrid"][:, :, 0], [[25, 40, 55, 70], [115, 130, 145, 160]])
    np.testing.assert_allclose(out["hybrid"][:, :, 2], 2.0)
    np.testing.assert_array_equal(out["hybrid in 2 sigma"][0, :, 0], [True, True, False, False])    # 25, 40 <= 40


@pytest.mark.parametrize("dt", [1.0, 0.5])
def test_the_late_coverage_reads_each_lead_from_its_own_forecast_row(dt):
    """The forecast's row of each lead (lead / step, the start at row 0), on logs of 1 and
    0.5 s: a model that forecasts north exactly is exact at every lead, and its spread, a
    third of the lead, gives a 2-sigma band that grows with the row it is read from."""
    from types import SimpleNamespace

    lc = load_benchmark("drift_late_coverage")
    t = np.arange(0.0, 200.0, dt)
    log = pd.DataFrame({"time_s": t, "north_m": t, "east_m": np.zeros_like(t), "heading_deg": np.zeros_like(t)})

    class Exact:
        def forecast(self, log_, starts, horizon_s):
            steps = np.arange(int(round(horizon_s / dt)) + 1)
            eta = np.zeros((len(starts), steps.size, 3))
            eta[..., 0] = np.asarray(starts)[:, None] + steps * dt          # north = the log's
            eta[..., 1] = 15.0                                               # east 15 m off
            return SimpleNamespace(eta=eta, eta_std=np.broadcast_to(steps[None, :, None] * dt / 3.0, eta.shape))

    out = lc.late_errors({"hybrid": Exact()}, log, [10.0, 100.0])
    np.testing.assert_allclose(out["hybrid"][..., 0], 0.0, atol=1e-9)
    # east error 15 m against 2 sigma = 2 lead / 3: outside at 15 s, inside from 30 s on
    np.testing.assert_array_equal(out["hybrid in 2 sigma"][0, :, 1], [False, True, True, True])


def test_late_coverage_without_members_is_a_usage_error(tmp_path, capsys):
    """drift_late_coverage.py --members 0 ended in EnsembleConfig's traceback after the logs
    were read; it is now a usage error (exit 2) naming the option, before any work."""
    lc = load_benchmark("drift_late_coverage")
    with pytest.raises(SystemExit) as exc:
        lc.main(["--members", "0", "--data", str(tmp_path), "--out", str(tmp_path / "t.md")])
    assert exc.value.code == 2
    assert "error: --members: expected a positive integer" in capsys.readouterr().err


def test_late_coverage_with_one_log_is_a_usage_error_before_it_reads_the_log(tmp_path, capsys):
    """With one log the hybrid was fitted on none: fit()'s traceback after the log was read."""
    lc = load_benchmark("drift_late_coverage")
    (tmp_path / "only_seed1.csv.gz").write_bytes(b"not a log")
    assert lc.main(["--data", str(tmp_path)]) == 2
    assert "error: --data: leave one log out needs at least 2 logs, found 1 in" in capsys.readouterr().err


@pytest.mark.parametrize("n_logs, others", [(3, "two"), (6, "five"), (12, "11")])
def test_late_coverage_text_counts_the_logs_each_hybrid_is_fitted_on(n_logs, others, tmp_path, monkeypatch):
    """The written text said the hybrid was fitted on "the other five" logs whatever --data held;
    it now gives the count of the other logs (five, as committed, for the six truthsim-dev logs)."""
    lc = load_benchmark("drift_late_coverage")
    data = tmp_path / "logs"
    data.mkdir()
    for k in range(n_logs):
        pd.DataFrame({"time_s": [0.0, 1.0]}).to_csv(data / f"log{k}_seed{k}.csv.gz", index=False)
    fitted_on = []

    class Hybrid:
        def __init__(self, *a, **kw):
            self.calibration = {}

        def fit(self, logs):
            fitted_on.append(len(logs))
            return self

    class Reference(Hybrid):
        def fit(self, logs=None):
            return self

    monkeypatch.setattr(lc, "HybridPredictor", Hybrid)
    monkeypatch.setattr(lc, "DynamicPredictor", Reference)
    monkeypatch.setattr(lc, "DeadReckoning", Reference)
    monkeypatch.setattr(lc, "starts_after_failure", lambda log: {"first 20 s": [0.0], "20 s and later": [1.0]})
    monkeypatch.setattr(lc, "score", lambda model, log, starts: {
        "starts": 1, "north/east in 2 sigma": 1.0, "heading in 2 sigma": 1.0, "mean 1-sigma [m]": 1.0,
        "RMS error [m]": 1.0, "noted as late": 0})
    monkeypatch.setattr(lc, "late_errors", lambda models, log, starts: {
        **{m: np.ones((1, 4, 3)) for m in models}, "hybrid in 2 sigma": np.ones((1, 4, 3), bool)})
    out = tmp_path / "t.md"
    assert lc.main(["--data", str(data), "--out", str(out)]) == 0
    assert fitted_on == [n_logs - 1] * n_logs
    assert out.read_text().splitlines()[0] == (
        f"60-s forecasts after the failure of each truthsim-dev log, the hybrid fitted on the other {others} "
        "(10 members); nominal 2-sigma coverage 0.954:")
