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
