"""A quick (tiny) run of the high-speed-craft benchmark: table columns, contents and files."""

import numpy as np
import pandas as pd
import pytest

from hybridship.hsc.benchmark import COLUMNS, run_benchmark, score_model


def test_quick_benchmark_writes_the_table(tmp_path):
    table = run_benchmark(tmp_path, seed=0, quick=True, progress=False)
    on_disk = pd.read_csv(tmp_path / "table.csv")
    assert list(on_disk.columns) == COLUMNS == ["model", "sea_state", "split", "mode", "output", "R", "MAE"]
    assert len(on_disk) == len(table) == 4 * 2 * 2 * 2 * 2
    assert set(on_disk.model) == {"ss", "arx", "ann", "hybrid"}
    assert set(on_disk.sea_state) == {1, 2}
    assert set(on_disk.split) == {"train", "validation"}
    assert set(on_disk["mode"]) == {"one_step", "free_run"}
    assert set(on_disk.output) == {"speed_kn", "pitch_deg"}
    assert not on_disk.duplicated(["model", "sea_state", "split", "mode", "output"]).any()
    # one-step prediction of the speed is close to the measurement (the quick run's NARX
    # network is too little trained to be held to that)
    one = on_disk[(on_disk["mode"] == "one_step") & (on_disk.output == "speed_kn") & (on_disk.model != "ann")]
    assert np.all(one.MAE < 1.0) and np.all(one.R > 0.95)
    md = (tmp_path / "table.md").read_text()
    assert "Table 1 layout" in md and "Table 2 layout" in md and "hybrid (ours)" in md and "ann (paper)" in md
    for name in ("hsc_speed_trim.png", "hsc_validation_ss1.png", "hsc_validation_ss2.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    curves = pd.read_csv(tmp_path / "speed_trim.csv")
    assert list(curves.columns) == ["boat", "device", "rpm", "speed_kn", "trim_deg"]
    assert set(curves.boat) == {"nominal", "truth"} and set(curves.device) == {"none", "interceptor", "trim_tab"}
    assert "Calm-water equilibria" in md
    assert not list(tmp_path.glob(".*.tmp"))                  # atomic writes left nothing behind


def test_arguments_checked_before_the_work(tmp_path):
    with pytest.raises(ValueError, match="^seed"):
        run_benchmark(tmp_path, seed=-1, quick=True, progress=False)
    (tmp_path / "a_file").write_text("x")
    with pytest.raises(NotADirectoryError, match="not a folder"):
        run_benchmark(tmp_path / "a_file", quick=True, progress=False)
    with pytest.raises(TypeError, match="^out_dir"):
        run_benchmark(None, quick=True, progress=False)
    (tmp_path / "table.md").write_text("my notes")       # a file of the user's: refused, kept
    with pytest.raises(FileExistsError, match="table.md: exists and was not written by hybridship"):
        run_benchmark(tmp_path, quick=True, progress=False)
    assert (tmp_path / "table.md").read_text() == "my notes"
    from hybridship.cli import main

    assert main(["benchmark", "hsc", "--quick", "--out", str(tmp_path)]) == 2
    with pytest.raises(ValueError, match="^mode"):
        score_model(None, np.zeros((3, 3)), np.zeros((3, 2)), "one-step")
