"""benchmarks/esso_multistep.py: its committed tables."""

from __future__ import annotations

import pandas as pd
import pytest

from conftest import load_benchmark, screening_errors


@pytest.fixture(scope="module")
def em():
    return load_benchmark("esso_multistep")


def test_the_summary_and_the_tables_give_each_rows_pooled_30_s_figures(em):
    e = screening_errors((("dynamic", 0.5, 10.0), ("abs", 0.4, 6.0)), held=False)
    row = em.summary(e, "abs", 12.0, {}, {"loss": "absolute"})
    assert (row["dist30_m"], row["head30_deg"], row["dist_ratio"], row["cells_below"]) == (0.8, 12.0, 0.8, "4/4")
    lines = em.tables(e, pd.DataFrame([row]), "python benchmarks/esso_multistep.py --variants abs:").splitlines()
    assert lines[0] == "Command: `python benchmarks/esso_multistep.py --variants abs:`"
    assert '| abs | {"loss": "absolute"} | 0.8 | 12.0 | 0.8 | 0.6 | 4/4 | 12.0 |' in lines
    assert "| abs | 0.400 / 6.00 | 1.200 / 18.00 | 0.800 / 12.00 | 0.80 / 0.60 |" in lines


def test_the_summary_reads_the_commands_known_rows_whatever_their_order(em):
    """A table with commands-held rows too (99 m), those first: the summary's figures are the
    known rows' (0.8 m pooled, 0.8 x the physics), not the first row it meets."""
    e = screening_errors((("dynamic", 0.5, 10.0), ("abs", 0.4, 6.0)), held=True)
    row = em.summary(e.iloc[::-1].reset_index(drop=True), "abs", 12.0, {}, {})
    assert (row["dist30_m"], row["dist_ratio"], row["cells_below"]) == (0.8, 0.8, "4/4")


def test_results_need_an_out_without_an_earlier_run(em, tmp_path, capsys):
    (tmp_path / "errors.csv").write_text("model\n")
    assert em.main(["--out", str(tmp_path), "--results", str(tmp_path / "docs")]) == 2
    assert "earlier run's errors.csv" in capsys.readouterr().err
    assert not (tmp_path / "docs").exists()


def test_tables_only_renders_the_run_again_with_its_command(em, tmp_path):
    e = screening_errors((("dynamic", 0.5, 10.0), ("abs", 0.4, 6.0)), held=False)
    e.to_csv(tmp_path / "errors.csv", index=False)
    pd.DataFrame([em.summary(e, "abs", 12.0, {}, {})]).to_csv(tmp_path / "variants.csv", index=False)
    (tmp_path / "tables.md").write_text("Command: `python benchmarks/esso_multistep.py --seed 1`\nold\n")
    assert em.main(["--tables-only", "--out", str(tmp_path), "--results", str(tmp_path / "docs")]) == 0
    text = (tmp_path / "docs" / "tables.md").read_text()
    assert text.startswith("Command: `python benchmarks/esso_multistep.py --seed 1`\n") and "old" not in text
    assert sorted(p.name for p in (tmp_path / "docs").iterdir()) == ["errors.csv", "tables.md", "variants.csv"]


def test_the_permutation_importance_is_in_the_tables_and_the_results(em, tmp_path):
    """``--permutation``'s files are results too: ``tables.md`` shows them and ``--results`` copies them."""
    e = screening_errors((("dynamic", 0.5, 10.0), ("abs", 0.4, 6.0)), held=False)
    e.to_csv(tmp_path / "errors.csv", index=False)
    pd.DataFrame([em.summary(e, "abs", 12.0, {}, {})]).to_csv(tmp_path / "variants.csv", index=False)
    imp = pd.DataFrame([{"feature": "(none)", "dist30_m": 0.8, "head30_deg": 12.0, "d_dist30_m": 0.0,
                         "d_head30_deg": 0.0},
                        {"feature": "r_hat_rad_s", "dist30_m": 0.89512, "head30_deg": 17.9004,
                         "d_dist30_m": 0.09512, "d_head30_deg": 5.9004}])
    lines = em.tables(e, pd.read_csv(tmp_path / "variants.csv"), "c", {"abs": imp}).splitlines()
    assert "| r_hat_rad_s | 0.8951 | 17.9 | 0.0951 | 5.9 |" in lines
    assert any(line.startswith("Permutation importance of `abs` (`importance_abs.csv`)") for line in lines)
    imp.to_csv(tmp_path / "importance_abs.csv", index=False)
    (tmp_path / "tables.md").write_text("Command: `python benchmarks/esso_multistep.py --permutation`\n")
    assert em.main(["--tables-only", "--out", str(tmp_path), "--results", str(tmp_path / "docs")]) == 0
    assert sorted(p.name for p in (tmp_path / "docs").iterdir()) == ["errors.csv", "importance_abs.csv",
                                                                      "tables.md", "variants.csv"]
    assert "| r_hat_rad_s | 0.8951 | 17.9 | 0.0951 | 5.9 |" in (tmp_path / "docs" / "tables.md").read_text()


def test_the_command_regime_is_fitted_on_a_hybrid_built_without_the_guard(em):
    """The fit leaves the weights out unless ``command_guard`` is set (as HybridPredictor's does):
    the screen's ``+cg`` rows would otherwise score the nets without the guard."""
    from types import SimpleNamespace

    class Hybrid(SimpleNamespace):
        def _held_back(self, logs, cal, dp_only):
            return [len(a) for a in logs], [None for _ in logs]

        def _fit_command_guard(self, logs, cuts, masks, cal, dp_only, stride):
            self.command_regime = "weights" if self.command_guard else None
            return [], {}

    q = Hybrid(calibration_config=None, command_guard=False, command_regime=None)
    em.with_command_regime(q, [[0, 1]], 1)
    assert q.command_guard and q.command_regime == "weights"
    q.command_guard, q.command_regime = False, None
    q._fit_command_guard = lambda *a: None           # a fit that finds no weights is not a +cg row
    with pytest.raises(RuntimeError, match="no command-regime weights"):
        em.with_command_regime(q, [[0, 1]], 1)


def test_a_runs_permutation_importance_is_published_with_its_tables(em, tmp_path, capsys):
    """The run's own path (not ``--tables-only``): ``write_outputs`` shows the importance in
    ``tables.md`` and copies its file to ``--results``; without it, no importance file."""
    e = screening_errors((("dynamic", 0.5, 10.0), ("abs", 0.4, 6.0)), held=False)
    row = em.summary(e, "abs", 12.0, {}, {})
    imp = pd.DataFrame([{"feature": "(none)", "dist30_m": 0.8, "head30_deg": 12.0, "d_dist30_m": 0.0,
                         "d_head30_deg": 0.0}])
    out, docs = tmp_path / "out", tmp_path / "docs"
    out.mkdir()
    imp.to_csv(out / em.importance_name("abs"), index=False)
    em.write_outputs(out, docs, e, [row], "c", {"abs": imp})
    assert sorted(p.name for p in docs.iterdir()) == ["errors.csv", "importance_abs.csv", "tables.md",
                                                      "variants.csv"]
    assert "Permutation importance of `abs` (`importance_abs.csv`)" in (docs / "tables.md").read_text()
    (tmp_path / "out2").mkdir()
    em.write_outputs(tmp_path / "out2", tmp_path / "docs2", e, [row], "c")
    assert sorted(p.name for p in (tmp_path / "docs2").iterdir()) == ["errors.csv", "tables.md", "variants.csv"]


def test_a_later_run_in_the_same_out_keeps_the_earlier_variants_and_replaces_its_own(em, tmp_path, capsys):
    """``write_outputs`` merges ``errors.csv`` and ``variants.csv`` with an earlier run's in the same
    ``--out``: other variants stay, a variant (or the physics) run again replaces its old rows, and
    ``tables.md`` shows this run's rows alone."""
    out = tmp_path / "out"
    out.mkdir()
    first = screening_errors((("dynamic", 0.5, 10.0), ("abs", 0.4, 6.0)), held=False)
    em.write_outputs(out, None, first, [em.summary(first, "abs", 1.0, {}, {})], "c1")
    second = screening_errors((("dynamic", 0.5, 10.0), ("huber", 0.3, 5.0)), held=False)
    em.write_outputs(out, None, second, [em.summary(second, "huber", 2.0, {}, {})], "c2")
    again = screening_errors((("dynamic", 0.5, 10.0), ("abs", 0.25, 4.0)), held=False)
    errors, table = em.write_outputs(out, None, again, [em.summary(again, "abs", 3.0, {}, {})], "c3")
    capsys.readouterr()

    variants = pd.read_csv(out / "variants.csv")
    assert sorted(variants.variant) == ["abs", "huber"]
    assert variants.set_index("variant").dist30_m.to_dict() == {"abs": 0.5, "huber": 0.6}   # 0.25 (0.3) x 2, pooled
    saved = pd.read_csv(out / "errors.csv")
    per_model = len(first) // 2
    assert saved.model.value_counts().to_dict() == {"dynamic": per_model, "abs": per_model, "huber": per_model}
    pooled30 = saved[(saved.kind == "all") & (saved.horizon_s == 30.0) & (saved.state == "distance_m")]
    assert pooled30.set_index("model").mae.to_dict() == {"dynamic": 1.0, "abs": 0.5, "huber": 0.6}
    assert len(errors) == len(saved) and sorted(table.variant) == ["abs", "huber"]
    text = (out / "tables.md").read_text()
    assert text.startswith("Command: `c3`") and "huber" not in text


def test_every_setting_that_changes_the_one_step_nets_has_its_own_cache_file(em, tmp_path):
    """The one-step nets are read back from ``cache_file`` when it exists (only the features and
    the hull correction are checked on loading): members, seed, hidden units, hull correction and
    its fit, the features and the held wind must each name a different file, and the screening
    config must carry the command line's settings."""
    from hybridship.residual.features import MEMORY_FEATURES

    argvs = ([], ["--members", "3"], ["--seed", "7"], ["--hidden", "32"], ["--hull"],
             ["--hull", "--hull-fit", "multi_step"], ["--hull", "--hull-fit", "multi_step", "--hull-iterations", "50"],
             ["--no-memory"])
    cfgs = [em.screening_config(em.parse_args(argv), (5.0, 30.0)) for argv in argvs]
    names = [em.cache_file(tmp_path, c, False).name for c in cfgs] + [em.cache_file(tmp_path, cfgs[0], True).name]
    assert len(set(names)) == len(names), names
    assert all(c.calibration.horizon_s == 30.0 for c in cfgs)
    members, seed, hidden, hull, multi, iters, no_memory = cfgs[1:]
    assert (members.ensemble.n_members, seed.ensemble.seed, hidden.ensemble.hidden) == (3, 7, 32)
    assert hull.hull_correction and hull.hull_fit == "one_step" and multi.hull_fit == "multi_step"
    assert iters.multistep.hull_iterations == 50
    assert set(cfgs[0].residual.features) - set(no_memory.residual.features) == set(MEMORY_FEATURES) != set()


def test_variants_parse_into_python_values_with_strings_as_they_are(em):
    """``--variants``: each field's value is a Python literal (a number) where it is one, else
    the text; empty parts and fields are skipped."""
    got = em.parse_variants("abs: loss=absolute, lr = 1e-3 ,steps=5;base:; ")
    assert got == {"abs": {"loss": "absolute", "lr": 0.001, "steps": 5}, "base": {}}
    assert type(got["abs"]["lr"]) is float
    # a bracketed value keeps its commas (a tuple, not two broken fields)
    got = em.parse_variants("m:steps=(5, 10), loss='absolute';n:tags=['a', 'b']")
    assert got == {"m": {"steps": (5, 10), "loss": "absolute"}, "n": {"tags": ["a", "b"]}}
    # ... beside an unquoted word, which stays text
    assert em.parse_variants("m:steps=(5, 10), loss=absolute") == {"m": {"steps": (5, 10), "loss": "absolute"}}


@pytest.mark.parametrize("bad", [["--variants", "a:nosuch=1"], ["--variants", "abs:loss='absolute';b:lr=-1"],
                                 ["--horizons-s", "5,x"], ["--horizons-s", "-5"]])
def test_a_bad_variant_field_or_horizon_is_a_usage_error_before_any_work(bad, tmp_path, capsys):
    """A --variants field MultiStepConfig refuses stopped the run with a traceback only after
    the one-step nets were trained, and a --horizons-s item that is not a number with a
    traceback; both are now usage errors (exit 2) naming the option, before the split is read."""
    from conftest import load_benchmark

    ms = load_benchmark("esso_multistep")
    with pytest.raises(SystemExit) as exc:
        ms.main([*bad, "--split", str(tmp_path / "absent"), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert f"error: {bad[0]}: " in capsys.readouterr().err


def test_a_feature_to_drop_that_the_benchmark_does_not_use_is_a_usage_error(tmp_path, capsys):
    """A misspelt --drop-features name dropped nothing and the run went on with every
    feature; it is now a usage error (exit 2) naming it, before any work. The names the
    committed screening dropped are accepted."""
    from conftest import load_benchmark

    ms = load_benchmark("esso_multistep")
    with pytest.raises(SystemExit) as exc:
        ms.main(["--drop-features", "rpm_main_rate_rel_s,wind_rel_u_ms", "--split", str(tmp_path / "absent"),
                 "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert "error: --drop-features: wind_rel_u_ms: not among" in capsys.readouterr().err
    args = ms.parse_args(["--drop-features", "rpm_main_rate_rel_s,angle_main_rate_rad_s,wind_rel_u_m_s"])
    assert args.drop_features.count(",") == 2
