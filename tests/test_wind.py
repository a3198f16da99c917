"""Physical checks for the wind-load curves (Isherwood 1972, Blendermann 1994, user tables).

Check values come from the project's reference README (sections 2 and 3).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hybridship.physics.wind import (
    blendermann_coefficients,
    blendermann_vessel_types,
    coefficient_table,
    interpolate_table,
    isherwood_coefficients,
    relative_wind,
    tabulated_coefficients,
)

# MSS example ship used for the Isherwood check values.
ISHERWOOD_SHIP = dict(L_oa_m=100.0, B_m=30.0, A_L_m2=900.0, A_F_m2=300.0, A_SS_m2=100.0, S_m=100.0, C_m=50.0, M=2)
# Research vessel used for the Blendermann check values.
RESEARCH_VESSEL = dict(vessel_type="Research vessel", A_F_m2=160.7, A_L_m2=434.8, L_oa_m=55.0, s_L_m=1.48)

# RV Gunnerus (original hull) published wind table, 0..180 deg, symmetric.
GUNNERUS_ANGLE = np.arange(0.0, 181.0, 10.0)
GUNNERUS_CX = [-0.53, -0.59, -0.65, -0.59, -0.51, -0.47, -0.40, -0.29, -0.20, -0.18,
               -0.14, -0.05, 0.12, 0.37, 0.61, 0.82, 0.86, 0.72, 0.62]
GUNNERUS_CY = [0, 0.22, 0.40, 0.66, 0.83, 0.90, 0.88, 0.87, 0.86, 0.85,
               0.83, 0.82, 0.81, 0.73, 0.58, 0.46, 0.26, 0.09, 0]
GUNNERUS_CN = [0, 0.05, 0.10, 0.135, 0.149, 0.148, 0.114, 0.093, 0.075, 0.04,
               0.02, -0.013, -0.035, -0.041, -0.045, -0.04, -0.029, -0.014, 0]
GUNNERUS_TABLE = dict(angle_deg=GUNNERUS_ANGLE, C_X=GUNNERUS_CX, C_Y=GUNNERUS_CY, C_N=GUNNERUS_CN)


def _periodic_table():
    """An asymmetric full-circle table (-180..180) built from smooth shapes."""
    ang = np.arange(-180.0, 181.0, 15.0)
    r = np.radians(ang)
    return dict(
        angle_deg=ang,
        C_X=-0.6 * np.cos(r) + 0.05 * np.sin(r),
        C_Y=0.8 * np.sin(r) + 0.1 * (1.0 + np.cos(r)),
        C_N=0.1 * np.sin(2.0 * r) + 0.02,
    )


CURVES = {
    "isherwood": functools.partial(isherwood_coefficients, **ISHERWOOD_SHIP),
    "blendermann": functools.partial(blendermann_coefficients, **RESEARCH_VESSEL),
    "tabulated": functools.partial(tabulated_coefficients, **GUNNERUS_TABLE),
}


# ------------------------------------------------------------------ check values


def _assert_rounds_to(value, printed):
    """``value`` rounds to the README's printed number (half a unit in its last digit)."""
    if float(printed) == 0.0:  # exact zeros by symmetry (or cos(pi/2) rounding)
        assert abs(float(value)) < 1e-12, printed
        return
    decimals = len(printed.split(".")[1])
    assert float(value) == pytest.approx(float(printed), abs=0.5 * 10.0**-decimals + 1e-12), printed


@pytest.mark.parametrize(
    "gamma_deg, cx, cy, cn",
    [(0.0, "-0.867", "0", "0"), (90.0, "-0.144", "0.651", "0.0087"), (180.0, "0.767", "0", "0")],
)
def test_isherwood_check_values(gamma_deg, cx, cy, cn):
    C_X, C_Y, C_N = isherwood_coefficients(np.radians(gamma_deg), **ISHERWOOD_SHIP)
    _assert_rounds_to(C_X, cx)
    _assert_rounds_to(C_Y, cy)
    _assert_rounds_to(C_N, cn)


def test_isherwood_at_130_deg_by_hand_from_the_published_row():
    """At 130 deg every ship term but ``C/L`` in ``C_X`` enters (the superstructure ratio
    ``A_SS/A_L``, ``S/L`` and ``L/B`` have zero weight at the 0, 90 and 180-deg check angles):
    the README's formulas worked by hand with Isherwood's 130-deg row (MSS ``isherwood72.m``)."""
    s = ISHERWOOD_SHIP
    L, B = s["L_oa_m"], s["B_m"]
    terms = np.array([1.0, 2.0 * s["A_L_m2"] / L**2, 2.0 * s["A_F_m2"] / B**2, L / B, s["S_m"] / L, s["C_m"] / L])
    a_row = [-0.142, 3.58, 0.0, 0.047, -0.700, 0.0]                     # A0..A5, A6 = -0.028 on M
    b_row = [1.014, 0.0, 0.191, 0.0, -0.280, -0.69]                     # B0..B5, B6 = 0.44 on A_SS/A_L
    c_row = [-0.0189, 0.0, -0.0488, 0.0101, 0.1128, -0.420]             # C0..C5
    want_x = -(terms @ a_row - 0.028 * s["M"])
    want_y = terms @ b_row + 0.44 * s["A_SS_m2"] / s["A_L_m2"]
    want_n = terms @ c_row
    assert (want_x, want_y, want_n) == pytest.approx((0.0969, 0.5652, -0.1150), abs=1e-4)   # worked on paper
    for sign in (1.0, -1.0):
        C_X, C_Y, C_N = isherwood_coefficients(sign * np.radians(130.0), **ISHERWOOD_SHIP)
        assert (C_X, C_Y, C_N) == pytest.approx((want_x, sign * want_y, sign * want_n), abs=1e-12)


@pytest.mark.parametrize(
    "gamma_deg, cx, cy, cn",
    [
        (0.0, "-0.550", "0", "0"),
        (60.0, "-0.332", "0.888", "0.108"),
        (90.0, "0", "0.850", "0.0229"),
        (150.0, "0.671", "0.507", "-0.0819"),
    ],
)
def test_blendermann_research_vessel_check_values(gamma_deg, cx, cy, cn):
    C_X, C_Y, C_N = blendermann_coefficients(np.radians(gamma_deg), **RESEARCH_VESSEL)
    _assert_rounds_to(C_X, cx)
    _assert_rounds_to(C_Y, cy)
    _assert_rounds_to(C_N, cn)


def test_blendermann_yaw_moment_is_odd_at_beam_wind():
    # The published-code caveat: signed gamma in the C_N bracket gives -0.50 at -90 deg.
    _, _, C_N = blendermann_coefficients(np.radians(-90.0), **RESEARCH_VESSEL)
    assert C_N == pytest.approx(-0.0229, abs=5e-5)


def test_blendermann_unknown_vessel_type_lists_valid_names():
    with pytest.raises(ValueError) as info:
        blendermann_coefficients(0.0, **{**RESEARCH_VESSEL, "vessel_type": "Submarine"})
    msg = str(info.value)
    assert "Submarine" in msg
    assert len(blendermann_vessel_types()) == 17
    for name in blendermann_vessel_types():
        assert name in msg


def test_blendermann_name_matching_forgives_case_and_commas():
    a = blendermann_coefficients(1.0, **{**RESEARCH_VESSEL, "vessel_type": "Tanker, loaded"})
    b = blendermann_coefficients(1.0, **{**RESEARCH_VESSEL, "vessel_type": "tanker  LOADED"})
    np.testing.assert_array_equal(a, b)


# ------------------------------------------------------------------ symmetry


def _all_curves():
    curves = dict(CURVES)
    curves["tabulated_periodic_symmetric"] = functools.partial(
        tabulated_coefficients,
        angle_deg=np.concatenate([-GUNNERUS_ANGLE[:0:-1], GUNNERUS_ANGLE]),
        C_X=np.concatenate([np.asarray(GUNNERUS_CX)[:0:-1], GUNNERUS_CX]),
        C_Y=np.concatenate([-np.asarray(GUNNERUS_CY)[:0:-1], GUNNERUS_CY]),
        C_N=np.concatenate([-np.asarray(GUNNERUS_CN)[:0:-1], GUNNERUS_CN]),
    )
    return curves


@pytest.mark.parametrize("name", sorted(_all_curves()))
@settings(max_examples=60, deadline=None)
@given(gamma=st.floats(min_value=-np.pi, max_value=np.pi, allow_nan=False))
def test_cx_even_cy_cn_odd(name, gamma):
    curve = _all_curves()[name]
    cx_p, cy_p, cn_p = curve(gamma)
    cx_m, cy_m, cn_m = curve(-gamma)
    assert cx_p == pytest.approx(cx_m, abs=1e-12)
    assert cy_p == pytest.approx(-cy_m, abs=1e-12)
    assert cn_p == pytest.approx(-cn_m, abs=1e-12)


@pytest.mark.parametrize("name", sorted(_all_curves()))
def test_symmetry_on_dense_grid_and_2pi_periodicity(name):
    curve = _all_curves()[name]
    g = np.linspace(0.0, np.pi, 1441)
    cx_p, cy_p, cn_p = curve(g)
    cx_m, cy_m, cn_m = curve(-g)
    np.testing.assert_allclose(cx_p, cx_m, atol=1e-12)
    np.testing.assert_allclose(cy_p, -cy_m, atol=1e-12)
    np.testing.assert_allclose(cn_p, -cn_m, atol=1e-12)
    # Angles outside (-pi, pi] wrap: gamma + 2 pi is the same wind.
    for a, b in zip(curve(g), curve(g - 2.0 * np.pi)):
        np.testing.assert_allclose(a, b, atol=1e-9)


@pytest.mark.parametrize("name", sorted(_all_curves()))
def test_head_and_following_wind(name):
    cx0, cy0, cn0 = _all_curves()[name](0.0)
    assert cx0 < 0.0  # head wind pushes the ship aft
    assert cy0 == 0.0 and cn0 == 0.0
    cx180, cy180, cn180 = _all_curves()[name](np.pi)
    assert cx180 > 0.0  # following wind pushes the ship ahead
    assert abs(cy180) < 1e-12 and abs(cn180) < 1e-12


@pytest.mark.parametrize("name", sorted(_all_curves()))
def test_beam_wind_from_port_pushes_to_starboard(name):
    _, cy, _ = _all_curves()[name](np.pi / 2)
    assert cy > 0.5


def test_curves_keep_input_shape():
    g = np.linspace(-3.0, 3.0, 24).reshape(2, 3, 4)
    for curve in CURVES.values():
        for c in curve(g):
            assert c.shape == g.shape


# ------------------------------------------------------------------ relative wind


def test_ship_ahead_in_still_air_sees_head_wind():
    V, gamma = relative_wind(0.0, 1.234, 0.7, 5.0, 0.0)
    assert V == pytest.approx(5.0)
    assert gamma == 0.0


def test_wind_from_port_on_stationary_ship():
    # Heading north, wind from the west (270 deg): port beam wind.
    V, gamma = relative_wind(12.0, np.radians(270.0), 0.0, 0.0, 0.0)
    assert V == pytest.approx(12.0)
    assert gamma == pytest.approx(np.pi / 2)
    for curve in CURVES.values():
        _, C_Y, _ = curve(gamma)
        assert C_Y > 0.0


def test_wind_from_starboard_on_stationary_ship():
    # Heading east, wind from the south: starboard beam wind.
    _, gamma = relative_wind(8.0, np.pi, np.pi / 2, 0.0, 0.0)
    assert gamma == pytest.approx(-np.pi / 2)


def test_heading_north_wind_from_north_is_head_wind():
    V, gamma = relative_wind(10.0, 0.0, 0.0, 3.0, 0.0)
    assert V == pytest.approx(13.0)
    assert gamma == 0.0


def test_tail_wind_faster_than_ship_gives_gamma_pi():
    # Wind from astern at 10 m/s, ship at 3 m/s: air overtakes the ship from behind.
    V, gamma = relative_wind(10.0, np.pi, 0.0, 3.0, 0.0)
    assert V == pytest.approx(7.0)
    assert gamma == pytest.approx(np.pi)  # (-pi, pi]: never -pi


def test_gamma_range_is_half_open_at_minus_pi():
    _, gamma = relative_wind(0.0, 0.0, 0.0, np.array([-3.0, -3.0]), np.array([0.0, -0.0]))
    np.testing.assert_array_equal(gamma, [np.pi, np.pi])


def test_no_relative_wind_gives_gamma_zero_whatever_the_signs_of_zero():
    """A ship at rest (u = -0.0, as a negated 0 gives) in calm air: the documented 0, not pi."""
    V, gamma = relative_wind(0.0, np.pi, 0.0, np.array([-0.0, 0.0, -0.0]), np.array([0.0, -0.0, -0.0]))
    np.testing.assert_array_equal(V, 0.0)
    np.testing.assert_array_equal(gamma, 0.0)


@settings(max_examples=80, deadline=None)
@given(
    speed=st.floats(0.0, 40.0),
    wind_dir=st.floats(-10.0, 10.0),
    psi=st.floats(-10.0, 10.0),
    u=st.floats(-8.0, 8.0),
    v=st.floats(-3.0, 3.0),
    rot=st.floats(-10.0, 10.0),
)
def test_invariant_under_joint_rotation_of_heading_and_wind(speed, wind_dir, psi, u, v, rot):
    V1, g1 = relative_wind(speed, wind_dir, psi, u, v)
    V2, g2 = relative_wind(speed, wind_dir + rot, psi + rot, u, v)
    assert V2 == pytest.approx(V1, abs=1e-9)
    assert -np.pi < g1 <= np.pi and -np.pi < g2 <= np.pi
    if V1 > 1e-6:
        # compare on the circle, since +-pi are the same angle
        assert abs(np.angle(np.exp(1j * (g2 - g1)))) < 1e-7


def test_relative_wind_broadcasts_and_matches_vector_geometry():
    rng = np.random.default_rng(1)
    speed = rng.uniform(0, 20, size=(4, 1))
    wind_dir = rng.uniform(-np.pi, np.pi, size=(1, 5))
    psi = rng.uniform(-np.pi, np.pi, size=(4, 5))
    u, v = rng.uniform(-5, 5, size=5), rng.uniform(-2, 2, size=5)
    V, gamma = relative_wind(speed, wind_dir, psi, u, v)
    assert V.shape == gamma.shape == (4, 5)
    # Independent construction: air velocity over ground in NED (blowing towards dir+pi),
    # ship velocity over ground in NED, difference rotated into body axes.
    wn, we = -speed * np.cos(wind_dir), -speed * np.sin(wind_dir)
    sn, se = u * np.cos(psi) - v * np.sin(psi), u * np.sin(psi) + v * np.cos(psi)
    dn, de = sn - wn, se - we
    u_rw = np.cos(psi) * dn + np.sin(psi) * de
    v_rw = -np.sin(psi) * dn + np.cos(psi) * de
    np.testing.assert_allclose(V, np.hypot(u_rw, v_rw), atol=1e-12)
    np.testing.assert_allclose(np.exp(1j * gamma), np.exp(-1j * np.arctan2(v_rw, u_rw)), atol=1e-12)


# ------------------------------------------------------------------ user tables


def test_symmetric_table_reproduces_nodes_and_mirrors():
    g = np.radians(GUNNERUS_ANGLE)
    C_X, C_Y, C_N = tabulated_coefficients(g, **GUNNERUS_TABLE)
    np.testing.assert_allclose(C_X, GUNNERUS_CX)
    np.testing.assert_allclose(C_Y, GUNNERUS_CY)
    np.testing.assert_allclose(C_N, GUNNERUS_CN)
    C_X, C_Y, C_N = tabulated_coefficients(-np.radians(45.0), **GUNNERUS_TABLE)
    assert C_X == pytest.approx(0.5 * (-0.51 - 0.47))
    assert C_Y == pytest.approx(-0.5 * (0.83 + 0.90))
    assert C_N == pytest.approx(-0.5 * (0.149 + 0.148))


def test_periodic_table_has_no_symmetry_assumed():
    tab = _periodic_table()
    g = np.radians(tab["angle_deg"])
    C_X, C_Y, C_N = tabulated_coefficients(g, **tab)
    np.testing.assert_allclose(C_X, tab["C_X"], atol=1e-12)
    np.testing.assert_allclose(C_Y, tab["C_Y"], atol=1e-12)
    np.testing.assert_allclose(C_N, tab["C_N"], atol=1e-12)
    # The same data written as 0..360 gives the same curve.
    ang360 = np.mod(tab["angle_deg"][:-1], 360.0)
    order = np.argsort(ang360)
    tab360 = {k: np.asarray(tab[k])[:-1][order] for k in ("C_X", "C_Y", "C_N")}
    tab360 = {k: np.append(val, val[0]) for k, val in tab360.items()}
    tab360["angle_deg"] = np.append(ang360[order], 360.0)
    gg = np.linspace(-np.pi, np.pi, 97)
    for a, b in zip(tabulated_coefficients(gg, **tab), tabulated_coefficients(gg, **tab360)):
        np.testing.assert_allclose(a, b, atol=1e-12)
    # Head wind with an asymmetric table keeps its non-zero side force.
    assert tabulated_coefficients(0.0, **tab)[1] == pytest.approx(0.2)


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(angle_deg=[0, 10, 10, 180]), r"wind\.angle_deg: must be strictly increasing"),
        (dict(angle_deg=[0, 20, 10, 180]), r"wind\.angle_deg: must be strictly increasing"),
        (dict(angle_deg=[0, np.nan, 20, 180]), r"wind\.angle_deg: must be finite"),
        (dict(C_X=[-0.5, np.nan, 0.1, 0.5]), r"wind\.C_X: must be finite"),
        (dict(C_N=[0.0, np.inf, 0.1, 0.0]), r"wind\.C_N: must be finite"),
        (dict(C_Y=[0.0, 0.5, 0.0]), r"wind\.C_Y: must have the same length"),
        (dict(C_Y=[0.1, 0.5, 0.5, 0.0]), r"wind\.C_Y: must be 0 at 0 deg for a symmetric table, got 0\.1"),
        (dict(C_N=[0.0, 0.1, 0.1, 0.02]), r"wind\.C_N: must be 0 at 180 deg for a symmetric table"),
        (dict(angle_deg=[0, 10, 20, 90]), r"wind\.angle_deg: must span 0\.\.180"),
        (dict(angle_deg=[0, 90, 180, 350]), r"wind\.angle_deg: must span"),
    ],
)
def test_bad_tables_raise_naming_the_field(change, match):
    tab = dict(angle_deg=[0, 10, 20, 180], C_X=[-0.5, -0.4, 0.1, 0.5], C_Y=[0, 0.5, 0.5, 0], C_N=[0, 0.1, 0.1, 0])
    tab.update(change)
    with pytest.raises(ValueError, match=match):
        tabulated_coefficients(0.3, **tab)


def test_full_circle_table_must_close():
    tab = _periodic_table()
    tab["C_X"] = np.asarray(tab["C_X"]).copy()
    tab["C_X"][-1] += 0.1
    with pytest.raises(ValueError, match=r"wind\.C_X: a full-circle table must end with its first value"):
        tabulated_coefficients(0.0, **tab)


def test_error_prefix_can_be_set():
    with pytest.raises(ValueError, match=r"vessel\.wind\.angle_deg"):
        tabulated_coefficients(0.0, angle_deg=[0, 0], C_X=[0, 0], C_Y=[0, 0], C_N=[0, 0], name="vessel.wind")


def test_bad_geometry_raises_naming_the_field():
    with pytest.raises(ValueError, match="A_L_m2"):
        isherwood_coefficients(0.0, **{**ISHERWOOD_SHIP, "A_L_m2": np.nan})
    with pytest.raises(ValueError, match="L_oa_m"):
        blendermann_coefficients(0.0, **{**RESEARCH_VESSEL, "L_oa_m": -5.0})


def test_geometry_given_as_text_bool_or_none_is_refused_naming_the_field():
    """``float()`` read "100" and True as numbers and failed on None in its own words."""
    for bad in ("100", True, None):
        with pytest.raises(TypeError, match="^L_oa_m: expected a number"):
            blendermann_coefficients(0.3, **{**RESEARCH_VESSEL, "L_oa_m": bad})
        with pytest.raises(TypeError, match="^C_m: expected a number"):
            isherwood_coefficients(0.3, **{**ISHERWOOD_SHIP, "C_m": bad})
    assert np.isfinite(blendermann_coefficients(0.3, **{**RESEARCH_VESSEL, "L_oa_m": np.float32(55.0)})[2])


def test_a_negative_wind_speed_is_refused_as_its_docstring_requires():
    """The docstring asks for a speed >= 0; -10 m/s from the north was taken as 10 m/s from the
    south without a word (DynamicModel refuses it already)."""
    with pytest.raises(ValueError, match="^wind_speed_m_s: -10 m/s is negative; expected a speed >= 0"):
        relative_wind([5.0, -10.0], 0.0, 0.0, 0.0, 0.0)
    V, g = relative_wind(0.0, 0.0, 0.0, 0.0, 0.0)          # calm air is a speed
    assert V == 0.0 and g == 0.0


def test_angles_speeds_and_table_columns_given_as_text_are_refused_naming_them():
    """numpy read text as the number: a relative wind angle "0.5" as 0.5 rad, a wind speed "10"
    as 10 m/s, a table's angles ["0", "90", "180"] as degrees; other text failed in float()'s
    words ('could not convert string to float')."""
    for name, curve in CURVES.items():
        with pytest.raises(TypeError, match="^gamma_rad: expected an array of real numbers"):
            curve("0.5")
    with pytest.raises(TypeError, match="^gamma_rad: expected an array of real numbers"):
        interpolate_table(["0.5"], coefficient_table(CURVES["tabulated"])[1])
    for i, name in enumerate(("wind_speed_m_s", "wind_dir_from_rad", "psi_rad", "u_m_s", "v_m_s")):
        args = [10.0, 0.0, 0.0, 1.0, 0.0]
        args[i] = str(args[i])
        with pytest.raises(TypeError, match=f"^{name}: expected an array of real numbers"):
            relative_wind(*args)
    for key, bad in (("angle_deg", [str(a) for a in GUNNERUS_ANGLE]), ("C_Y", GUNNERUS_CY[:-1] + ["0"]),
                     ("C_X", GUNNERUS_CX[:1] + ["a"] + GUNNERUS_CX[2:])):
        with pytest.raises(ValueError, match=rf"^wind\.{key}: must be a list of numbers, got \["):
            tabulated_coefficients(0.3, **{**GUNNERUS_TABLE, key: bad})


# ------------------------------------------------------------------ kernel table


@pytest.mark.parametrize("name", sorted(CURVES) + ["tabulated_periodic"])
def test_coefficient_table_matches_curve(name):
    curve = CURVES.get(name) or functools.partial(tabulated_coefficients, **_periodic_table())
    grid, table = coefficient_table(curve)
    assert grid.shape == (721,)
    np.testing.assert_array_equal(grid, np.linspace(-np.pi, np.pi, 721))
    assert table.shape == (721, 3) and table.dtype == np.float64 and table.flags.c_contiguous
    np.testing.assert_array_equal(table[0], table[-1])  # -pi and +pi are the same wind

    # On the table's own 0.5-deg nodes: exact up to rounding.
    g_nodes = np.radians(np.arange(-180.0, 180.01, 0.5))
    for a, b in zip(interpolate_table(g_nodes, table), curve(g_nodes)):
        np.testing.assert_allclose(a, b, atol=1e-12)
    # Half-way between nodes, and beyond +-pi: linear-interpolation error only.
    g_mid = np.radians(np.arange(-539.75, 540.0, 0.5))
    for a, b in zip(interpolate_table(g_mid, table), curve(g_mid)):
        assert np.max(np.abs(a - b)) < 2e-4


def test_coefficient_table_samples_the_number_of_points_asked_for():
    """``n=361`` is a 1-deg grid from -180 to 180 deg: row 270 is the beam wind from port (90 deg),
    where the research vessel's Blendermann values are the README's check values."""
    grid, table = coefficient_table(CURVES["blendermann"], n=361)
    assert grid.shape == (361,) and table.shape == (361, 3)
    np.testing.assert_allclose(grid, np.radians(np.arange(-180.0, 181.0, 1.0)), rtol=0, atol=1e-15)
    for value, printed in zip(table[270], ("0", "0.850", "0.0229")):
        _assert_rounds_to(value, printed)


def test_interpolate_table_keeps_shape_and_propagates_nan():
    _, table = coefficient_table(CURVES["blendermann"], n=361)
    g = np.array([[0.1, np.nan], [np.inf, -2.0]])
    out = interpolate_table(g, table)
    for c in out:
        assert c.shape == (2, 2)
        assert np.isnan(c[0, 1]) and np.isnan(c[1, 0])
        assert np.isfinite(c[0, 0]) and np.isfinite(c[1, 1])


def test_coefficient_table_names_a_curve_that_returns_the_wrong_shape_or_type():
    """Its docstring promises a ValueError for a curve of the wrong shape: that was numpy's
    'could not be broadcast together with remapped shapes', a curve returning one number
    'object of type 'int' has no len()', and text float()'s 'could not convert string'."""
    for curve, match in ((lambda g: (g[:-1], g, g), r"^curve_fn: C_X has shape \(10,\); expected one value per angle"),
                         (lambda g: (g, np.zeros((2, g.size)), g), r"^curve_fn: C_Y has shape \(2, 11\)"),
                         (lambda g: 5.0, "^curve_fn: must return \\(C_X, C_Y, C_N\\), got float")):
        with pytest.raises(ValueError, match=match):
            coefficient_table(curve, n=11)
    with pytest.raises(TypeError, match="^curve_fn: C_N: expected an array of real numbers"):
        coefficient_table(lambda g: (g, g, ["a"] * g.size), n=11)
    _, table = coefficient_table(lambda g: (np.cos(g), 0.0, np.zeros_like(g)), n=11)      # one value: as before
    np.testing.assert_array_equal(table[:, 1], 0.0)


def test_coefficient_table_rejects_bad_input():
    for n in (2, 3.7, "361"):        # 3.7 was taken as 3 points
        with pytest.raises(ValueError, match=r"^n: expected a whole number >= 3"):
            coefficient_table(CURVES["isherwood"], n=n)
    with pytest.raises(ValueError, match="C_Y"):
        coefficient_table(lambda g: (np.zeros_like(g), np.full_like(g, np.nan), np.zeros_like(g)))
