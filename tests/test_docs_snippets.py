"""The Python examples a new user copies first run as written: the README's API block and
the equations page's, each executed whole in a fresh namespace (and folder, for the files
they write)."""

import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = {"README.md": "## Python API", "docs/concepts/equations.md": "# "}


def _first_python_block(page: str, after: str) -> str:
    text = (ROOT / page).read_text(encoding="utf-8")
    m = re.search(r"```python\n(.*?)```", text[text.index(after):], flags=re.S)
    assert m, f"{page}: no python block after {after!r}"
    return m.group(1)


def _check_the_rollout_as_the_comments_say(res, eta0, nu0):
    """``res.eta, res.nu, res.nu_dot  # (B, 61, 3) each``: 60 steps of 1 s after the start, whose
    row 0 is the start state the example gave (``eta0`` [m, m, rad], ``nu0`` [m/s, m/s, rad/s])."""
    B = len(eta0)
    for name in ("eta", "nu", "nu_dot"):
        assert getattr(res, name).shape == (B, 61, 3), name
    np.testing.assert_array_equal(res.time_s, np.arange(61.0))
    np.testing.assert_array_equal(res.eta[:, 0], eta0)
    np.testing.assert_array_equal(res.nu[:, 0], nu0)


@pytest.mark.parametrize("page", sorted(PAGES))
def test_the_pages_python_example_runs_as_written(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(_first_python_block(page, PAGES[page]), page, "exec"), namespace)   # noqa: S102 (our own docs)
    res = namespace["res"]
    assert res.eta.shape[1:] == (61, 3)
    _check_the_rollout_as_the_comments_say(res, *((namespace["eta0"], namespace["nu0"]) if page == "README.md"
                                                  else (namespace["eta"], namespace["nu"])))
    if page == "docs/concepts/equations.md":      # the page's two calls, at the same start: the same acceleration
        np.testing.assert_allclose(res.nu_dot[:, 0], namespace["nu_dot"], rtol=1e-9, atol=1e-12)
    if page == "README.md":
        assert (tmp_path / "gunnerus.hybrid.npz").is_file() and namespace["fc"].eta.shape[:2] == (2, 61)


def test_the_command_memorys_angle_wrap_is_the_one_the_residual_page_states():
    """docs/concepts/residual.md gives the range the command memory wraps an angle step to;
    a step of exactly half a turn tells the two half-open ranges apart (+pi is kept by
    (-pi, pi], taken as -pi by [-pi, pi))."""
    from hybridship.residual.features import command_memory

    page = (ROOT / "docs" / "concepts" / "residual.md").read_text(encoding="utf-8")
    stated = re.search(r"Angle steps are\s+wrapped to (\S+, \S+?)\.", page).group(1)
    c = np.exp(-1.0 / 10.0)
    m = command_memory(np.array([[[0.0, np.pi]]]), np.zeros((1, 2)), np.zeros((1, 2)), 1.0, 10.0)
    step = -m[0, 0, 1] / c                      # m = -c dx for one step from rest
    assert step == pytest.approx(-np.pi) and stated == "[-pi, pi)", (step, stated)


def test_a_forecast_on_a_log_slower_than_1_hz_takes_1_s_rk4_substeps_as_the_pages_say(monkeypatch):
    """The forecast loop's physics step on a 0.5-Hz log is two RK4 substeps of 1 s, not one
    RK4 step of 2 s; the pages that describe the loop (frames, the hybrid, the residual
    scheme) say so beside their 'one RK4 step'."""
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import HybridPredictor
    from hybridship.residual.ensemble import EnsembleConfig
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    logs = [physics_log(model, seed=s, dt_s=2.0, duration_s=1200.0) for s in (1, 2)]
    hp = HybridPredictor(model.vessel, ensemble_config=EnsembleConfig(n_members=2, max_epochs=5)).fit(logs[:1])
    seen = []
    step = DynamicModel.step_unchecked

    def spy(self, *args):
        seen.append(args[-1])                   # the substeps of each forecast step
        return step(self, *args)

    monkeypatch.setattr(DynamicModel, "step_unchecked", spy)
    fc = hp.forecast(logs[1], [600.0], horizon_s=60)
    assert fc.lead_s[1] == 2.0 and set(seen) == {2}
    for page, sentence in (("docs/concepts/frames.md", r"one RK4 step per sample in the hybrid[^)]*"),
                           ("docs/hybrid.md", r"one RK4 physics step of the mean state[^,]*"),
                           ("docs/concepts/residual.md", r"the ensemble-mean state one RK4 step[^;]*")):
        text = " ".join((ROOT / page).read_text(encoding="utf-8").split())
        assert "substeps of at most 1 s" in re.search(sentence, text).group(0), page


def test_the_environment_filter_steps_over_every_tenth_row_of_a_10_hz_log_as_its_page_says(monkeypatch):
    """docs/concepts/environment.md: the filter's process model takes one RK4 step per
    sample, except on a log faster than ``filter_step_s`` (1 s), whose every m-th row it
    steps over (a 10-Hz log: every tenth)."""
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import as_log_arrays
    from hybridship.residual import environment
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    arrays = as_log_arrays(physics_log(model, seed=1, dt_s=0.1, duration_s=120.0, t_shutdown_s=None),
                           model.vessel)
    steps = []
    run = environment.kernel.filter_grid

    def spy(grid, *args):
        steps.append(np.diff(grid))             # the rows between two filter steps
        return run(grid, *args)

    monkeypatch.setattr(environment.kernel, "filter_grid", spy)
    environment.EnvironmentEstimator(model).run(arrays)
    assert environment.EnvironmentConfig().filter_step_s == 1.0
    assert set(np.concatenate(steps).tolist()) == {10}
    text = " ".join((ROOT / "docs" / "concepts" / "environment.md").read_text(encoding="utf-8").split())
    said = re.search(r"The process model is the dynamic model itself \(one RK4 step per sample[^)]*", text).group(0)
    assert "`filter_step_s`" in said and "every tenth row" in said, said


def test_the_simulators_measured_columns_have_the_resolution_its_page_states():
    """docs/simulator.md gives the logger's resolution of each measured column; a simulated
    log's columns hold no finer digits, and each uses the last one it is given."""
    from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

    df = simulate_dp_loss(DPLossConfig(seed=3, t_shutdown_s=120.0, t_shutdown_jitter_s=0.0, drift_s=60.0))
    text = " ".join((ROOT / "docs" / "simulator.md").read_text(encoding="utf-8").split())
    said = re.search(r"Values are rounded to a logger's resolution in the measured columns: (.*?) The truth columns",
                     text)
    assert said, "docs/simulator.md: no per-column resolution of the measured columns"
    said = said.group(1)
    step = {"north_m": 1e-3, "east_m": 1e-3, "heading_deg": 1e-3, "u_m_s": 1e-4, "v_m_s": 1e-4, "r_deg_s": 1e-4,
            "wind_speed_m_s": 1e-3, "wind_dir_deg": 1e-2, "port_azimuth_deg": 1e-2, "stbd_azimuth_deg": 1e-2,
            "tunnel_rpm": 1e-2, "port_rpm": 1e-2, "stbd_rpm": 1e-2}
    for col, q in step.items():
        x = df[col].to_numpy() / q
        assert np.allclose(x, np.round(x), atol=1e-6), col               # nothing finer than stated
        assert not np.allclose(x / 10, np.round(x / 10), atol=1e-6), col  # and that digit is used
    for phrase in ("positions to 1 mm", "heading to 0.001°", "0.1 mm/s", "`r_deg_s` to 0.0001°/s",
                   "wind speed to 1 mm/s", "wind direction and the azimuths to 0.01°", "rpm to 0.01"):
        assert phrase in said, phrase
