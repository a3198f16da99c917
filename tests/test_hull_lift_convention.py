"""benchmarks/hull_lift_convention.py: the PMM derivatives' conversion and the hull variants."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import load_benchmark
from hybridship.physics.model import DynamicModel
from hybridship.vessel import load_vessel

hlc = load_benchmark("hull_lift_convention")


def test_pmm_derivatives_on_the_mmg_basis(tmp_path):
    """Hand values: L = 10 m, d = 2.70 m, rho = 1000, so q = 1350 kg/m^2."""
    vals = {"Lpp": 10.0, "rho_water": 1000.0, "Xudot": -100.0, "Yvdot": -400.0, "Yrdot": 30.0, "Nvdot": 10.0,
            "Yuv": -1350.0, "Yur": 2700.0, "Nuv": 13800.0, "Nur": -1350000.0}
    rows = [{"parameter": k, "value": str(v), "unit": "-", "hull_version": "original_2006", "source": "s",
             "note": ""} for k, v in vals.items()]
    rows.append({"parameter": "Lpp", "value": "99", "unit": "m", "hull_version": "lengthened_2019",
                 "source": "s", "note": ""})
    rows.append({"parameter": "thruster_y", "value": "2.7 / -2.7", "unit": "m", "hull_version": "original_2006",
                 "source": "s", "note": ""})
    f = tmp_path / "ref.csv"
    pd.DataFrame(rows).to_csv(f, index=False)
    d = hlc.pmm_mmg_derivatives(f)
    q = 0.5 * 1000.0 * hlc.PMM_DRAUGHT_M
    assert d["Y_v"] == pytest.approx(-1350.0 / (q * 10))
    assert d["Y_r"] == pytest.approx(2700.0 / (q * 100))
    assert d["N_v"] == pytest.approx((13800.0 - 400.0 + 100.0) / (q * 100))     # the Munk moment included
    assert d["N_r"] == pytest.approx((-1350000.0 + 20.0) / (q * 1000))
    # a lift moment that exactly cancels the Munk moment (N_uv = -(Y_vdot - X_udot)) leaves no
    # net u v moment: N'_v = 0, whatever the sign conventions of the parts
    pd.DataFrame([r if r["parameter"] != "Nuv" else r | {"value": "300.0"} for r in rows]).to_csv(f, index=False)
    assert hlc.pmm_mmg_derivatives(f)["N_v"] == pytest.approx(0.0, abs=1e-15)


def test_with_lift_changes_only_the_lift_and_leaves_the_vessel_alone():
    v = load_vessel("gunnerus")
    before = v.model_dump()
    mmg = {"Y_v": -0.5, "Y_r": 0.1, "N_v": -0.02, "N_r": -0.06}
    w = hlc.with_lift(v, "signed", mmg)
    assert v.model_dump() == before
    nl = w.damping.nonlinear
    assert (nl.lift, nl.lift_speed, nl.mmg.N_v) == ("mmg", "signed", -0.02)
    a, b = DynamicModel(v).arrays, DynamicModel(w).arrays
    np.testing.assert_array_equal(a.m_a, b.m_a)
    assert np.all(b.d_lift[:4] == 0) and np.any(b.d_lift[4:] != 0)
    assert hlc.with_lift(v, "abs").model_dump() == before


@pytest.mark.parametrize("missing", ["TRUTHSIM", "REFERENCE"])
def test_missing_data_is_a_clear_skip(tmp_path, monkeypatch, capsys, missing):
    """Either input missing (the simulator's logs or the published derivatives) is a skip,
    not a traceback half-way through the run."""
    monkeypatch.setattr(hlc, missing, tmp_path / "nope")
    assert hlc.main(["--out", str(tmp_path / "out")]) == 0
    assert "skipping" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_mmg_equivalent_inverts_mmg_lift():
    v = load_vessel("esso_osaka_model")
    g = v.damping.nonlinear.mmg
    d = hlc.mmg_equivalent(v)
    np.testing.assert_allclose([d["Y_v"], d["Y_r"], d["N_v"], d["N_r"]], [g.Y_v, g.Y_r, g.N_v, g.N_r], rtol=1e-9)
    s = hlc.mmg_equivalent(hlc.with_lift(v, "signed"))
    np.testing.assert_allclose(list(s.values()), list(d.values()), rtol=1e-12)
