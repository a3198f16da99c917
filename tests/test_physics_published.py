"""The packaged coefficient tables and vessel files against the published values in
``../shared/data/reference`` (each row there names its source); skipped without the data."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pandas as pd
import pytest

from hybridship.physics import hull
from hybridship.physics.propeller import ct_cq_star, load_wageningen
from hybridship.vessel import load_vessel, packaged_vessel_text, vessel_from_dict


@pytest.fixture(scope="module")
def published(shared_data):
    """``published(file)`` -> {parameter: value} of a ``*_published.csv`` (numeric rows)."""

    def read(name):
        t = pd.read_csv(shared_data("reference", name), dtype=str)
        return {(p, h if isinstance(h, str) else ""): v for p, v, h in
                zip(t["parameter"], t["value"], t.get("hull_version", [None] * len(t)))}

    return read


def num(table, key, hull_version=""):
    return float(table[(key, hull_version)])


@pytest.mark.parametrize("name", ["wageningen_b_series_4q.csv", "isherwood_1972_wind.csv",
                                  "blendermann_1994_wind.csv"])
def test_packaged_tables_are_the_published_tables(shared_data, name):
    """The copies under hybridship/data that the models read hold the reference numbers, every one."""
    from importlib import resources

    with resources.files("hybridship.data").joinpath(name).open("r") as fh:
        packaged = pd.read_csv(fh)
    pd.testing.assert_frame_equal(packaged, pd.read_csv(shared_data("reference", name)), check_exact=True)


def test_four_quadrant_model_agrees_with_smogelis_independent_b4_70_set(shared_data):
    """B4-70 P/D 1.0 from Roddy et al. (2006), as the model evaluates it, against Smogeli's (2006)
    independent 21-term transcription over the full circle of beta: the reference README gives
    their difference as at most 0.027 in C_T* (RMS 0.0066) and 0.0077 in C_Q* (RMS 0.0015), and
    Smogeli's quoted K_T0 0.445, K_Q0 0.0666."""
    s = pd.read_csv(shared_data("reference", "wageningen_b4_70_smogeli2006_4q.csv")).sort_values("k")
    beta = np.radians(np.arange(-180.0, 180.0, 1.0))
    k = s["k"].to_numpy()[:, None]
    cos, sin = np.cos(k * beta), np.sin(k * beta)
    ct_s = (s["A_T"].to_numpy()[:, None] * cos + s["B_T"].to_numpy()[:, None] * sin).sum(axis=0)
    cq_s = (s["A_Q"].to_numpy()[:, None] * cos + s["B_Q"].to_numpy()[:, None] * sin).sum(axis=0)
    ct, cq = ct_cq_star(beta, load_wageningen("B4-70", 1.0))
    # bounds: the README's figures rounded up; halving A(0) (a classic Fourier slip) moves C_T*
    # by 0.013 everywhere and the RMS to 0.014
    assert np.abs(ct - ct_s).max() < 0.03 and np.sqrt(np.mean((ct - ct_s) ** 2)) < 0.008
    assert np.abs(cq - cq_s).max() < 0.008 and np.sqrt(np.mean((cq - cq_s) ** 2)) < 0.002
    fac = math.pi / 8 * (0.7 * math.pi) ** 2                    # K = C* (pi/8)(J^2 + (0.7 pi)^2) at J = 0
    assert ct_s[180] * fac == pytest.approx(0.445, abs=5e-4)    # the set is read as the README says
    assert cq_s[180] * fac == pytest.approx(0.0666, abs=5e-5)


def test_gunnerus_file_holds_the_published_particulars_and_tables(published):
    """Every number the vessel file attributes to a source equals that source's value within
    the rounding of the file (the file's comments name the keys)."""
    g = published("gunnerus_published.csv")
    v = load_vessel("gunnerus")
    p, rb, L19 = v.particulars, v.rigid_body, "lengthened_2019"
    assert (p.L_oa_m, p.L_pp_m, p.B_m) == (num(g, "LOA", L19), num(g, "Lpp", L19), num(g, "B_moulded", L19))
    assert (p.T_m, p.C_B) == (num(g, "draught_model", L19), num(g, "C_B", L19))
    assert rb.mass_kg == pytest.approx(num(g, "displacement_mass", L19), abs=5.0)       # 574.13 t
    assert rb.r_z_m == num(g, "r66_yaw_radius_of_gyration", L19)
    assert v.damping.nonlinear.wetted_surface_m2 == pytest.approx(num(g, "wetted_surface", L19), abs=0.05)
    # the origin is the CG, LCG from Lpp/2 forward of midships; positions in the sources are from the AP
    x_cg_ap = 0.5 * p.L_pp_m + num(g, "LCG_from_midship", L19)
    tunnel, port, stbd = v.thrusters
    assert tunnel.x_m == pytest.approx(num(g, "tunnel_x_rel_AP", "unknown") - x_cg_ap, abs=5e-3)
    assert port.x_m == stbd.x_m == pytest.approx(num(g, "azimuth_x_rel_AP", "unknown") - x_cg_ap, abs=5e-3)
    assert (stbd.y_m, -port.y_m) == (2.0, 2.0)          # OSP "2.0 / -2.0"
    assert tunnel.diameter_m == num(g, "tunnel_prop_diameter", "unknown")
    assert port.diameter_m == stbd.diameter_m == num(g, "azimuth_prop_diameter", "unknown")
    assert port.thrust_deduction == stbd.thrust_deduction == num(g, "azimuth_thrust_deduction_t", "unknown")
    # sway-yaw added-mass coupling: SIMVAL's PMM value, as stated
    assert v.added_mass.Y_rdot_kg_m == num(g, "Yrdot", "original_2006")
    assert v.added_mass.N_vdot_kg_m == num(g, "Nvdot", "original_2006")
    w, O06 = v.wind, "original_2006"
    for name in ("C_X", "C_Y", "C_N"):
        pub = [num(g, f"wind_{name.replace('_', '')}_{a:03.0f}deg", O06) for a in w.table.angle_deg]
        assert getattr(w.table, name) == pub, name
    assert w.A_F_m2 == num(g, "wind_A_F", O06)
    # A_L: SIMVAL's 172 m^2 plus the 5 m extension times the freeboard, to the whole m^2
    added = (p.L_pp_m - num(g, "Lpp", O06)) * (num(g, "depth_to_1deck", L19) - p.T_m)
    assert abs(w.A_L_m2 - (num(g, "wind_A_L", O06) + added)) <= 0.5
    assert w.L_oa_m == p.L_pp_m            # the table's moment length is Lpp (SIMVAL: wind_moment_length)
    assert num(g, "wind_moment_length", O06) == num(g, "Lpp", O06)


def test_gunnerus_added_mass_is_what_the_named_methods_give():
    """X_udot by Soding (1982), Y_vdot and N_rdot by Clarke et al. (1983) from the file's own
    particulars, to the file's 4 decimals."""
    v = load_vessel("gunnerus")
    p, am = v.particulars, v.added_mass
    c = hull.clarke1983_derivatives(p.L_pp_m, p.B_m, p.T_m, p.C_B, p.rho_water_kg_m3)
    assert am.X_udot_kg == pytest.approx(hull.added_mass_surge_soding(v.rigid_body.mass_kg, p.L_pp_m,
                                                                      p.rho_water_kg_m3), abs=5e-5)
    assert am.Y_vdot_kg == pytest.approx(c["Y_vdot_kg"], abs=5e-5)
    assert am.N_rdot_kg_m2 == pytest.approx(c["N_rdot_kg_m2"], abs=5e-5)


def test_esso_osaka_file_holds_the_published_model_and_mmg_values(published):
    """The 3 m model's particulars (FRT) and the KVLCC2 MMG set made dimensional with this
    model's Lpp, d and fresh water, within the rounding the file states."""
    e = published("esso_osaka_published.csv")
    v = load_vessel("esso_osaka_model")
    p, rb, (prop,), (rud,) = v.particulars, v.rigid_body, v.thrusters, v.rudders
    frt = {k: num(e, f"frt_model.{k}") for k in ("Lpp", "B", "d", "C_b", "m", "x_G", "D_P", "A_R", "A_T", "A_L")}
    assert (p.L_pp_m, p.B_m, p.T_m, p.C_B) == (frt["Lpp"], frt["B"], frt["d"], frt["C_b"])
    assert (rb.mass_kg, rb.x_g_m, prop.diameter_m, rud.area_m2) == (frt["m"], frt["x_G"], frt["D_P"], frt["A_R"])
    assert (v.wind.A_F_m2, v.wind.A_L_m2) == (frt["A_T"], frt["A_L"])
    assert p.rho_water_kg_m3 == num(e, "frt_model.rho_water")
    assert p.L_oa_m == pytest.approx(num(e, "abkowitz_full.LOA") / num(e, "frt_model.scale"), abs=5e-4)
    mmg = lambda k: num(e, f"kvlcc2_mmg.{k}")                               # noqa: E731
    L, d, q = p.L_pp_m, p.T_m, 0.5 * p.rho_water_kg_m3
    lin = v.damping.nonlinear.mmg
    assert (lin.Y_v, lin.Y_r, lin.N_v, lin.N_r) == (mmg("Y_v"), mmg("Y_r"), mmg("N_v"), mmg("N_r"))
    assert v.damping.nonlinear.d_uu == pytest.approx(mmg("R_0_prime") * q * L * d, abs=5e-4)
    am = v.added_mass                                                        # to 0.01 kg (kg m^2)
    assert -am.X_udot_kg == pytest.approx(mmg("m_x_prime") * q * L**2 * d, abs=5e-3)
    assert -am.Y_vdot_kg == pytest.approx(mmg("m_y_prime") * q * L**2 * d, abs=5e-3)
    assert -am.N_rdot_kg_m2 == pytest.approx(mmg("J_z_prime") * q * L**4 * d, abs=5e-3)
    assert (prop.wake_fraction, prop.thrust_deduction) == (mmg("w_P0"), mmg("t_P"))
    assert prop.x_m == pytest.approx(mmg("x_P_prime") * L, abs=5e-4)
    assert (rud.x_m, rud.x_H_m, rud.l_R_m) == pytest.approx(
        (mmg("x_R_prime") * L, mmg("x_H_prime") * L, mmg("l_R_prime") * L), abs=5e-4)
    assert (rud.wake_ratio, rud.slipstream_factor, rud.steering_resistance_deduction, rud.hull_force_factor) == (
        mmg("epsilon"), mmg("kappa"), mmg("t_R"), mmg("a_H"))
    assert (rud.flow_straightening_neg, rud.flow_straightening_pos) == (mmg("gamma_R_minus"), mmg("gamma_R_plus"))
    # span from the lab's aspect ratio: Lambda = H_R^2 / A_R to the file's 4 decimals of H_R
    assert rud.aspect_ratio == pytest.approx(num(e, "esso3m_labmmg.rudder_aspect_ratio"), rel=2 * 5e-5 / rud.span_m)
    assert v.wind.blendermann.s_L_m == pytest.approx(num(e, "esso3m_labmmg.C_wind"), abs=5e-4)


def test_fujii_rudder_lift_gradient_gives_the_published_values(published):
    """f_alpha = 6.13 Lambda / (Lambda + 2.25) (Fujii): KVLCC2's 2.747 at Lambda = 1.827
    (Yasukawa & Yoshimura 2015); a given lift_gradient replaces it."""
    e = published("esso_osaka_published.csv")
    d = tomllib.loads(packaged_vessel_text("esso_osaka_model"))
    area = num(e, "kvlcc2_mmg.L7.A_R")
    d["rudders"][0].update(area_m2=area, span_m=math.sqrt(1.827 * area))
    rud = vessel_from_dict(d, "kvlcc2_rudder.toml").rudders[0]
    assert rud.f_alpha == pytest.approx(num(e, "kvlcc2_mmg.f_alpha"), abs=5e-4)
    # the Esso file's rudder, LAB's 2.490 at Lambda 1.539: its span is given to 0.1 mm (0.1277 m, 4e-4 of
    # itself), which moves Lambda by up to 8e-4 and f_alpha by up to 1.2e-3 (it gives 2.4893)
    assert load_vessel("esso_osaka_model").rudders[0].f_alpha == pytest.approx(2.490, abs=1.5e-3)
    d["rudders"][0]["lift_gradient"] = 2.0
    assert vessel_from_dict(d, "given.toml").rudders[0].f_alpha == 2.0
