"""benchmarks/esso_physics_fit.py: the identified coefficients scale the published ones."""

import copy
import tomllib

import numpy as np
import pytest

from conftest import load_benchmark
from hybridship.vessel import VesselFileError, load_vessel, vessel_from_dict, vessels_dir


@pytest.fixture(scope="module")
def pf():
    return load_benchmark("esso_physics_fit")


@pytest.fixture(scope="module")
def base():
    return tomllib.loads((vessels_dir() / "esso_osaka_model.toml").read_text())


def test_zero_factors_give_the_published_vessel(pf, base):
    assert pf.vessel_with_factors(base, np.zeros(len(pf.COEFFICIENTS))) == load_vessel("esso_osaka_model")


def test_each_factor_scales_its_own_coefficient_only(pf, base):
    theta = np.zeros(len(pf.COEFFICIENTS))
    theta[pf.COEFFICIENTS.index("thrusters.0.wake_fraction")] = np.log(1.5)
    theta[pf.COEFFICIENTS.index("damping.nonlinear.mmg.N_r")] = np.log(0.5)
    v = pf.vessel_with_factors(base, theta)
    v0 = load_vessel("esso_osaka_model")
    assert v.thrusters[0].wake_fraction == pytest.approx(1.5 * v0.thrusters[0].wake_fraction)
    assert v.damping.nonlinear.mmg.N_r == pytest.approx(0.5 * v0.damping.nonlinear.mmg.N_r)
    assert v.rudders[0] == v0.rudders[0] and v.rigid_body == v0.rigid_body
    # every other coefficient (the other damping terms, the wind areas, ...) as published: the
    # vessel file with just these two values scaled by hand
    d = copy.deepcopy(base)
    d["thrusters"][0]["wake_fraction"] *= 1.5
    d["damping"]["nonlinear"]["mmg"]["N_r"] *= 0.5
    assert v == vessel_from_dict(d)
    assert base["thrusters"][0]["wake_fraction"] == v0.thrusters[0].wake_fraction   # the parsed file untouched


def test_a_factor_outside_the_allowed_range_is_a_vessel_file_error(pf, base):
    theta = np.zeros(len(pf.COEFFICIENTS))
    theta[pf.COEFFICIENTS.index("thrusters.0.wake_fraction")] = np.log(3.0)   # wake fraction 1.2
    with pytest.raises(VesselFileError, match="wake_fraction"):
        pf.vessel_with_factors(base, theta)


def test_every_coefficient_takes_its_own_factor_at_once(pf, base):
    """All the factors set together, each different: every coefficient of the parsed vessel (read
    by its path through the vessel's attributes, not the file's dictionary) is the published one
    times its own factor, none skipped or paired with another's."""
    def attribute(vessel, path):
        for key in path.split("."):
            vessel = vessel[int(key)] if key.isdigit() else getattr(vessel, key)
        return vessel

    factors = 1.0 + 0.01 * np.arange(1, len(pf.COEFFICIENTS) + 1)
    v = pf.vessel_with_factors(base, np.log(factors))
    v0 = load_vessel("esso_osaka_model")
    for path, f in zip(pf.COEFFICIENTS, factors):
        assert attribute(v, path) == pytest.approx(f * attribute(v0, path), rel=1e-12), path


@pytest.mark.parametrize("n", ["0", "-1"])
def test_no_evaluations_is_a_usage_error(n, tmp_path, capsys):
    """--evaluations below 1 ended in scipy's internal _MaxFuncCallError traceback; it is
    now a usage error (exit 2) naming the option, before any work."""
    pf = load_benchmark("esso_physics_fit")
    with pytest.raises(SystemExit) as exc:
        pf.main(["--evaluations", n, "--split", str(tmp_path / "absent"), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert "error: --evaluations: expected a positive integer" in capsys.readouterr().err
