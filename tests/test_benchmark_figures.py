"""The figures of the benchmark scripts are written atomically."""

import os

import pytest

from conftest import load_benchmark


def _disk_full(*a, **k):
    raise OSError("disk full")


def test_plot_scenario_leaves_an_earlier_figure_when_the_write_fails(tmp_path, monkeypatch):
    """A figure whose write fails leaves the one before it whole (it was written in place,
    and a failure part way left a truncated PNG), and no temporary file beside it."""
    from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

    ps = load_benchmark("plot_scenario")
    df = simulate_dp_loss(DPLossConfig(seed=7, t_shutdown_s=60.0, drift_s=30.0))
    out = tmp_path / "scenario.png"
    out.write_bytes(b"earlier figure")
    monkeypatch.setattr(os, "replace", _disk_full)
    with pytest.raises(OSError):
        ps.plot(df, out, "title")
    assert out.read_bytes() == b"earlier figure"
    assert [p.name for p in tmp_path.iterdir()] == ["scenario.png"]
    monkeypatch.undo()
    ps.plot(df, out, "title")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_gunnerus_response_leaves_an_earlier_figure_when_the_write_fails(tmp_path, monkeypatch):
    """As above, for docs/figures/gunnerus_response.png."""
    from hybridship.physics.model import DynamicModel

    gr = load_benchmark("gunnerus_response")
    model = DynamicModel("gunnerus")
    out = gr.run(model)
    path = tmp_path / "gunnerus_response.png"
    path.write_bytes(b"earlier figure")
    monkeypatch.setattr(os, "replace", _disk_full)
    with pytest.raises(OSError):
        gr.plot(out, model, path)
    assert path.read_bytes() == b"earlier figure"
    assert [p.name for p in tmp_path.iterdir()] == ["gunnerus_response.png"]


def test_compare_truthsim_leaves_an_earlier_figure_when_the_write_fails(tmp_path, monkeypatch):
    """As above, for docs/figures/drift_comparison.png (one truthsim-dev scenario, our side
    a short simulation)."""
    import pandas as pd

    from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

    ct = load_benchmark("compare_truthsim")
    if not (ct.TRUTHSIM / "scenarios.csv").is_file():
        pytest.skip("the truthsim-dev data set is not on this machine")
    src = pd.read_csv(ct.TRUTHSIM / "scenarios.csv").head(1)
    (tmp_path / "ts" / "logs").mkdir(parents=True)
    src.to_csv(tmp_path / "ts" / "scenarios.csv", index=False)
    (tmp_path / "ts" / "logs" / src.file[0]).symlink_to(ct.TRUTHSIM / "logs" / src.file[0])
    monkeypatch.setattr(ct, "simulate_dp_loss",
                        lambda cfg: simulate_dp_loss(DPLossConfig(seed=1, t_shutdown_s=60.0, drift_s=60.0)))
    path = tmp_path / "drift_comparison.png"
    path.write_bytes(b"earlier figure")
    replace = os.replace
    monkeypatch.setattr(os, "replace", lambda a, b: _disk_full() if str(b) == str(path) else replace(a, b))
    with pytest.raises(OSError):
        ct.main(["--truthsim", str(tmp_path / "ts"), "--out", str(path)])
    assert path.read_bytes() == b"earlier figure"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["drift_comparison.png", "ts"]


@pytest.mark.parametrize("bad", [["--t-shutdown-s", "-5"], ["--drift-s", "nan"], ["--seed", "-1"]])
def test_plot_scenario_settings_it_cannot_use_are_usage_errors(bad, tmp_path, capsys):
    """A scenario the simulator refuses stops with a usage error (exit 2) naming the option
    and the reason (it ended in DPLossConfig's traceback), and no figure is written."""
    ps = load_benchmark("plot_scenario")
    with pytest.raises(SystemExit) as exc:
        ps.main([*bad, "--out", str(tmp_path / "s.png")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"error: {bad[0]}: " in err and ("must be" in err or "expected" in err), err
    assert not any(tmp_path.iterdir())
