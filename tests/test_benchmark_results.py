"""benchmarks/_results.py: the screening scripts' committed tables."""

import pytest

from conftest import load_benchmark, screening_errors


def test_kind_table_gives_30_s_errors_per_kind_and_pooled_ratios():
    table = load_benchmark("_results").kind_table(screening_errors(), "dynamic").splitlines()
    assert table[0] == "| model | random | zigzag | all | pooled / dynamic |"
    assert table[2] == "| dynamic | 0.500 / 10.00 | 1.500 / 30.00 | 1.000 / 20.00 | 1.00 / 1.00 |"
    assert table[3] == "| hybrid | 0.400 / 6.00 | 1.200 / 18.00 | 0.800 / 12.00 | 0.80 / 0.60 |"


def test_kind_table_pools_the_ratio_from_the_all_rows_when_the_kinds_ratios_differ():
    """With the hybrid's zigzag errors 0.75 of the linear table's (0.9 m / 13.5 deg at 30 s) and its
    pooled rows the mean of its two kinds (equal counts: (0.4 + 0.9) / 2 = 0.65 m, (6 + 13.5) / 2 =
    9.75 deg), the kinds' ratios to the dynamic model differ (random 0.80 / 0.60, zigzag 0.60 / 0.45)
    and the pooled one is that of the ``all`` rows: 0.65 / 1.0 and 9.75 / 20 = 0.4875, by hand."""
    errors = screening_errors()
    hybrid = errors["model"] == "hybrid"
    errors.loc[hybrid & (errors["kind"] == "zigzag"), "mae"] *= 0.75
    errors.loc[hybrid & (errors["kind"] == "all"), "mae"] *= 0.65 / 0.8       # 0.8: the linear table's pooled
    table = load_benchmark("_results").kind_table(errors, "dynamic").splitlines()
    assert table[2] == "| dynamic | 0.500 / 10.00 | 1.500 / 30.00 | 1.000 / 20.00 | 1.00 / 1.00 |"
    assert table[3] == "| hybrid | 0.400 / 6.00 | 0.900 / 13.50 | 0.650 / 9.75 | 0.65 / 0.49 |"


def test_publish_copies_the_named_files_only(tmp_path, monkeypatch):
    results = load_benchmark("_results")
    out = tmp_path / "out"
    (out / "split").mkdir(parents=True)
    (out / "errors.csv").write_text("a\n")
    (out / "tables.md").write_text("b\n")
    monkeypatch.chdir(tmp_path)                           # a relative default folder would land here
    results.publish(out, None, ("errors.csv",))           # nothing without a folder
    assert sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*")) == [
        "out", "out/errors.csv", "out/split", "out/tables.md"]
    results.publish(out, tmp_path / "docs", ("errors.csv", "tables.md"))
    assert sorted(p.name for p in (tmp_path / "docs").iterdir()) == ["errors.csv", "tables.md"]
    assert (tmp_path / "docs" / "tables.md").read_text() == "b\n"


def test_command_line_quotes_the_arguments_a_shell_would_split():
    results = load_benchmark("_results")
    assert results.command_line("x.py", ["--out", "out/a b", "--n", "3"]) == "python benchmarks/x.py --out 'out/a b' --n 3"
    assert results.command_line("x.py", []) == "python benchmarks/x.py"       # no trailing space


def test_command_line_without_argv_records_this_process_arguments_after_the_script(monkeypatch):
    """``argv=None`` takes ``sys.argv[1:]``: the script as run (``sys.argv[0]``) is not repeated
    as an argument, and an argument with a space is quoted."""
    monkeypatch.setattr("sys.argv", ["benchmarks/x.py", "--out", "out/a b", "--quick"])
    assert load_benchmark("_results").command_line("x.py") == "python benchmarks/x.py --out 'out/a b' --quick"


@pytest.mark.parametrize("script", ["esso_error_sources", "esso_multistep", "esso_online_adaptation",
                                    "esso_physics_fit", "esso_training", "esso_wind_predictability"])
def test_a_screening_script_without_the_benchmarks_split_exits_2_naming_the_missing_folder(script, tmp_path,
                                                                                          capsys):
    mod = load_benchmark(script)
    assert mod.main(["--split", str(tmp_path / "nosplit"), "--out", str(tmp_path / "out")]) == 2
    assert f"{tmp_path / 'nosplit' / 'train'}: not found; run benchmarks/esso_osaka.py first" in capsys.readouterr().err
    assert not (tmp_path / "out" / "split").exists()
