"""benchmarks/drift_oracles.py: the physics given parts of the simulator's truth."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import load_benchmark
from hybridship.forecast_inputs.wind import WindForecast
from hybridship.physics.model import DynamicModel
from hybridship.sim.scenario import embedded_scenarios
from hybridship.vessel import load_vessel


@pytest.fixture(scope="module")
def oracles():
    return load_benchmark("drift_oracles")


@pytest.fixture(scope="module")
def scenario_log():
    return embedded_scenarios(1, 100)[0].log


def test_truth_given_to_the_model_that_made_it(oracles, scenario_log):
    """On our own simulator, whose hull is the model's, the true loads and current leave far
    less heading error than the model wind alone; every oracle row is there, with the logged
    wind's rows only when a wind forecast is given."""
    model = DynamicModel(load_vessel("gunnerus"))
    rows = oracles.failure_oracles(model, scenario_log, WindForecast(mean_window_s=300.0, time_constant_s=20.0))
    assert {"model wind", "model wind, logged held", "model wind, fitted forecast", "model wind, true future",
            "true loads and current"} <= set(rows)
    assert all(np.isfinite(v).all() and min(v) >= 0 for v in rows.values())
    assert rows["true loads and current"][0] < 0.5 * rows["model wind"][0]
    assert "model wind, logged held" not in oracles.failure_oracles(model, scenario_log)


def test_yaw_damping_variant_and_bad_vessel(oracles, tmp_path, capsys):
    """The yaw-damping variant file differs from the packaged one in its linear yaw damping
    only (twice it); an unreadable --vessel is refused by name."""
    packaged = load_vessel("gunnerus")
    variant = load_vessel(oracles.Path(oracles.__file__).parent / "vessel_variants" / "gunnerus_yaw_damping_x2.toml")
    d_packaged, d_variant = (DynamicModel(v).arrays.d_lin.copy() for v in (packaged, variant))
    assert d_variant[2, 2] == pytest.approx(2 * d_packaged[2, 2])
    d_variant[2, 2] = d_packaged[2, 2]
    np.testing.assert_array_equal(d_variant, d_packaged)
    np.testing.assert_array_equal(DynamicModel(variant).mass_matrix, DynamicModel(packaged).mass_matrix)
    assert oracles.main(["--vessel", str(tmp_path / "missing.toml"), "--own", "1", "--out", str(tmp_path)]) == 2
    assert "--vessel" in capsys.readouterr().err


def test_per_log_table_written(oracles, tmp_path, monkeypatch):
    """One row per log and oracle beside the pooled table."""
    monkeypatch.setattr(oracles, "TRUTHSIM", tmp_path / "absent")
    assert oracles.main(["--own", "1", "--own-seed", "100", "--out", str(tmp_path)]) == 0
    per_log = pd.read_csv(tmp_path / "drift_oracles_per_log.csv")
    pooled = pd.read_csv(tmp_path / "drift_oracles.csv")
    assert set(per_log.log) == {"embedded_seed0100"} and len(per_log) == len(pooled)
