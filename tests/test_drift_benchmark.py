"""The drift benchmark on a tiny folder of physics-made logs (seconds)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hybridship.cli import main
from hybridship.evaluation.drift import run_drift_benchmark
from hybridship.logs.io import write_log
from hybridship.physics.model import DynamicModel
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.sim.synthetic import physics_log

TINY = EnsembleConfig(n_members=3, max_epochs=40, patience=10, seed=0)


@pytest.fixture(scope="module")
def tiny_folder(tmp_path_factory):
    model = DynamicModel("gunnerus")
    folder = tmp_path_factory.mktemp("logs")
    for seed in (1, 2):
        write_log(physics_log(model, seed=seed), folder / f"physics_{seed}.csv")
    return folder


def test_tables_have_the_papers_layout_and_physics_is_exact_on_its_own_logs(tiny_folder, tmp_path):
    res = run_drift_benchmark(tiny_folder, None, tmp_path / "out", ensemble_config=TINY, plots=False,
                              calibration_scenarios=1,
                              progress=False)
    errors = pd.read_csv(tmp_path / "out" / "errors.csv")
    assert list(errors.columns) == ["model", "state", "window", "horizon_s", "mae"]
    assert set(errors.model) == {"hybrid", "hybrid_nets_unguarded", "hybrid_mean_bias", "dynamic", "dead_reckoning", "data_only"}
    assert set(errors.state) == {"north_m", "east_m", "yaw_deg"}
    assert set(errors.window) == {5, 20} and set(errors.horizon_s) == {15, 30, 45, 60}
    assert len(errors) == 6 * 3 * 2 * 4 and np.isfinite(errors.mae).all()
    cov = pd.read_csv(tmp_path / "out" / "coverage.csv")
    assert list(cov.columns) == ["model", "horizon_s", "sigma", "coverage"]
    assert {"hybrid", "hybrid_nets_unguarded", "data_only"} <= set(cov.model)
    assert cov.coverage.between(0, 1).all()
    ci = pd.read_csv(tmp_path / "out" / "coverage_intervals.csv")
    assert list(ci.columns) == ["model", "horizon_s", "sigma", "coverage", "low", "high", "n_failures"]
    two = cov[cov.sigma == 2].set_index(["model", "horizon_s"]).coverage
    ci = ci.set_index(["model", "horizon_s"])
    np.testing.assert_allclose(ci.coverage, two.loc[ci.index], atol=1e-6)
    assert set(ci.index.get_level_values(0)) >= {"hybrid", "data_only"}
    dyn = errors[errors.model == "dynamic"]
    # the log was made by the same model: only the 3-s start average separates them
    assert dyn[dyn.state != "yaw_deg"].mae.max() < 0.15, dyn
    assert dyn[dyn.state == "yaw_deg"].mae.max() < 0.3, dyn
    dr = errors[errors.model == "dead_reckoning"]
    pos = ["north_m", "east_m"]
    at60 = lambda df: df[(df.horizon_s == 60) & df.state.isin(pos)].mae.to_numpy()  # noqa: E731
    assert np.all(at60(dyn) < 0.25 * at60(dr)), (at60(dyn), at60(dr))
    table = (tmp_path / "out" / "tables.md").read_text()
    assert "| hybrid_nets_unguarded | north_m |" in table and "/" in table.split("| hybrid | north_m |")[1].split("\n")[0]
    assert res.table2.shape == (18, 4)


def test_benchmark_is_deterministic_and_the_cli_reports_bad_folders(tiny_folder, tmp_path, capsys):
    a = run_drift_benchmark(tiny_folder, None, tmp_path / "a", ensemble_config=TINY, plots=False, progress=False,
                            calibration_scenarios=0)
    b = run_drift_benchmark(tiny_folder, None, tmp_path / "b", ensemble_config=TINY, plots=False, progress=False,
                            calibration_scenarios=0)
    pd.testing.assert_frame_equal(a.errors, b.errors)
    assert main(["benchmark", "drift", "--train", str(tmp_path / "missing"), "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("hybridship benchmark drift: error: --train") and "not a folder" in err
    assert main(["benchmark"]) == 2
