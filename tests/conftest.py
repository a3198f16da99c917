"""Shared test fixtures: the Gunnerus model, and the one way to find ``../shared/data``.

Data never go into the repository: tests read them from ``../shared/data/`` relative to the
repository root and skip, saying where they looked, when they are absent. Use the
``shared_data`` fixture for that (``shared_data("truthsim-dev", "logs")``); the Esso Osaka
tests use :func:`hybridship.datasets.esso_osaka.default_data_dir`, the library's own locator of
the same folder (it also honours ``$HYBRIDSHIP_ESSO_OSAKA_DIR``).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import settings as hypothesis_settings

# The property tests draw the same examples on every run (a failure is one any run can
# reproduce, and the suite cannot turn red by chance); per-test settings add to this.
hypothesis_settings.register_profile("hybridship", derandomize=True)
hypothesis_settings.load_profile("hybridship")

#: The repository root (the folder holding ``hybridship/`` and ``tests/``).
ROOT = Path(__file__).resolve().parents[1]
#: Where the shared data sets live: ``../shared/data`` relative to the repository root.
SHARED_DATA = ROOT.parent / "shared" / "data"


def vessel_dict(name: str) -> dict:
    """A packaged vessel file as a dict (to edit before :func:`model_from`)."""
    import tomllib

    from hybridship.vessel import packaged_vessel_text

    return tomllib.loads(packaged_vessel_text(name))


def model_from(d: dict):
    """The dynamic model of a vessel dict (validated as a vessel file would be)."""
    from hybridship.physics.model import DynamicModel
    from hybridship.vessel import vessel_from_dict

    return DynamicModel(vessel_from_dict(d, "test.toml"))


def decoupled_model(linear: dict, nonlinear: dict):
    """Gunnerus's masses with the CG at the origin and no sway-yaw added-mass coupling, no
    actuators and no wind, with the damping ``linear`` and ``nonlinear``: a pure surge, sway
    (r = 0) or yaw (u = v = 0) motion has no Coriolis load and stays in its DOF, so its free
    decay has a closed form."""
    d = vessel_dict("gunnerus")
    d["rigid_body"]["x_g_m"] = 0.0
    d["added_mass"].update(Y_rdot_kg_m=0.0, N_vdot_kg_m=0.0)
    d["damping"] = {"linear": linear, "nonlinear": nonlinear}
    d["thrusters"] = []
    d["wind"] = {"method": "none"}
    return model_from(d)


def load_benchmark(name: str):
    """The script ``benchmarks/<name>.py`` as a module (the scripts are not a package)."""
    import importlib.util
    import sys

    if str(ROOT / "benchmarks") not in sys.path:       # as when the script runs: its siblings import
        sys.path.append(str(ROOT / "benchmarks"))
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def screening_errors(models=(("dynamic", 0.5, 10.0), ("hybrid", 0.4, 6.0)), held: bool = True):
    """A small errors table of the Esso screening scripts (``model,kind,state,horizon_s,mae,commands``):
    per model (name, 30-s distance [m], 30-s heading [deg]) two kinds and the pooled rows
    (``all``, twice the first kind's), horizons 10 and 30 s, growing linearly; with ``held``
    a commands-held distance of 99 m that no table of commands known may show."""
    import pandas as pd

    rows = []
    for model, d, h in models:
        for kind, f in (("random", 1.0), ("zigzag", 3.0), ("all", 2.0)):
            for horizon in (10.0, 30.0):
                rows += [(model, kind, "distance_m", horizon, d * f * horizon / 30.0, "known"),
                         (model, kind, "heading_deg", horizon, h * f * horizon / 30.0, "known")]
                if held:
                    rows.append((model, kind, "distance_m", horizon, 99.0, "held"))
    return pd.DataFrame(rows, columns=["model", "kind", "state", "horizon_s", "mae", "commands"])


def shared_data_path(*parts: str) -> Path:
    """``../shared/data/<parts>`` (the path may not exist)."""
    return SHARED_DATA.joinpath(*parts)


@pytest.fixture(scope="session")
def shared_data():
    """A function ``(*parts) -> Path`` under ``../shared/data`` that skips the calling test, naming
    the path, when it does not exist."""

    def locate(*parts: str) -> Path:
        path = shared_data_path(*parts)
        if not path.exists():
            pytest.skip(f"shared data not found at {path} (tests read ../shared/data beside the repository; "
                        "the data are never copied into it)")
        return path

    return locate


@pytest.fixture(scope="session")
def model():
    """The packaged Gunnerus dynamic model (read-only; shared by every test module)."""
    from hybridship.physics.model import DynamicModel

    return DynamicModel("gunnerus")
