"""benchmarks/esso_training.py: the mirrored log of the ``+mirror`` variant."""

from __future__ import annotations

import math
import re
import tomllib

import numpy as np
import pytest

from hybridship.logs.ingest import ingest
from hybridship.physics.model import DynamicModel
from hybridship.predictors import DynamicPredictor
from hybridship.residual.environment import EnvironmentConfig
from hybridship.sim.synthetic import physics_log
from hybridship.vessel import load_vessel, packaged_vessel_text, vessel_from_dict

from conftest import load_benchmark, screening_errors


@pytest.fixture(scope="module")
def et():
    return load_benchmark("esso_training")


@pytest.fixture(scope="module")
def symmetric_esso():
    """The Esso model with equal flow straightening on both sides (port/starboard symmetric)."""
    d = tomllib.loads(packaged_vessel_text("esso_osaka_model"))
    d["rudders"][0]["flow_straightening_pos"] = d["rudders"][0]["flow_straightening_neg"]
    return vessel_from_dict(d, "symmetric.toml")


@pytest.fixture(scope="module")
def manoeuvre(symmetric_esso):
    """A noise-free 10-Hz log of random rudder and propeller commands with a side wind."""
    log = physics_log(DynamicModel(symmetric_esso), duration_s=120.0, t_shutdown_s=None, dt_s=0.1,
                      seed=3, wind=(1.5, math.radians(60.0)), hold_s=(5.0, 15.0), rpm_scale=0.5)
    return ingest(log, symmetric_esso, purpose="fit")


def test_mirroring_twice_gives_the_log_back(et, manoeuvre, symmetric_esso):
    m = et.mirror_log(manoeuvre, symmetric_esso)
    np.testing.assert_array_equal(m.eta[:, 0], manoeuvre.eta[:, 0])
    np.testing.assert_array_equal(m.eta[:, 1:], -manoeuvre.eta[:, 1:])
    np.testing.assert_array_equal(m.rpm, manoeuvre.rpm)
    mm = et.mirror_log(m, symmetric_esso)
    for field in ("eta", "nu", "azimuth_rad", "wind", "rpm"):
        np.testing.assert_array_equal(getattr(mm, field), getattr(manoeuvre, field))


def test_a_symmetric_ship_forecasts_the_mirrored_log_as_the_mirror_of_its_forecast(et, manoeuvre,
                                                                                 symmetric_esso):
    """Physics invariant: for a port/starboard symmetric vessel, forecasting the mirrored log
    gives the mirrored forecast (the wind's direction, rudder and motion all flip)."""
    p = DynamicPredictor(symmetric_esso)
    starts = manoeuvre.time_s[[100, 400, 800]]
    f = p.forecast(manoeuvre, starts, horizon_s=20.0, commands="known")
    g = p.forecast(et.mirror_log(manoeuvre, symmetric_esso), starts, horizon_s=20.0, commands="known")
    assert np.ptp(f.eta[..., 2]) > 0.1  # the forecasts turn, so the check has teeth
    np.testing.assert_allclose(g.eta[..., 0], f.eta[..., 0], atol=1e-9)
    np.testing.assert_allclose(g.eta[..., 1], -f.eta[..., 1], atol=1e-9)
    # headings mirrored about north, each on its start's branch in [0, 2 pi)
    np.testing.assert_allclose(np.mod(g.eta[..., 2] + f.eta[..., 2] + np.pi, 2 * np.pi) - np.pi, 0.0, atol=1e-9)
    # the packaged model's rudder is not symmetric (MMG gamma_R 0.395 / 0.640): the mirror
    # is then an assumption, not an identity
    q = DynamicPredictor(load_vessel("esso_osaka_model"))
    fq = q.forecast(manoeuvre, starts, horizon_s=20.0, commands="known")
    gq = q.forecast(et.mirror_log(manoeuvre, symmetric_esso), starts, horizon_s=20.0, commands="known")
    assert np.abs(gq.eta[..., 1] + fq.eta[..., 1]).max() > 1e-3


def test_a_vessel_that_changes_in_the_mirror_is_refused(et, manoeuvre):
    with pytest.raises(ValueError, match=r"mirror_log: port: y_m must be 0"):
        et.mirror_log(manoeuvre, load_vessel("gunnerus"))
    d = tomllib.loads(packaged_vessel_text("esso_osaka_model"))
    d["thrusters"].append({**d["thrusters"][0], "name": "bow", "type": "tunnel", "x_m": 1.2,
                           "angle_deg": None})
    with pytest.raises(ValueError, match=r"mirror_log: bow: .*got type 'tunnel'"):
        et.mirror_log(manoeuvre, vessel_from_dict(d, "bow.toml"))


def test_variant_names_set_the_multistep_fields(et):
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig

    names = ["multi_step_h30_b64_i100_abs_hl3_ad10_lr0.003_ema0.9_own+cmd", "multi_step_abs+cmd"]
    hybrid, plain = (et.variants(ManoeuvreConfig(), names)[n] for n in names)
    ms = hybrid.multistep_config
    assert (ms.horizon_s, ms.batch_starts, ms.iterations, ms.loss) == (30.0, 64, 100, "absolute")
    assert (ms.heading_length_m, ms.anchor_decay, ms.lr, ms.member_loss) == (3.0, 10.0, 0.003, "own")
    assert plain.multistep_config.anchor_decay == 0.0 and plain.multistep_config.heading_length_m is None
    assert (plain.multistep_config.lr, plain.multistep_config.member_loss) == (1e-3, "mean")
    assert (ms.weight_average, plain.multistep_config.weight_average) == (0.9, 0.0)


def test_the_env_variant_runs_the_estimator_with_froude_scaled_settings(et):
    """``+env``: the estimator's full-scale settings scaled by Lpp (Froude: speeds by sqrt)."""
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig
    from hybridship.residual.environment import EnvironmentConfig

    name = "multi_step_abs+cmd+env"
    hybrid, plain = (et.variants(ManoeuvreConfig(), [n])[n] for n in (name, "multi_step_abs+cmd"))
    assert (hybrid.environment, plain.environment) == ("estimator", "mean")
    d, c = EnvironmentConfig(), hybrid.environment_config
    lam = load_vessel("gunnerus").particulars.L_pp_m / load_vessel("esso_osaka_model").particulars.L_pp_m
    assert c.position_std_m == pytest.approx(d.position_std_m / lam)
    assert c.velocity_std_m_s == pytest.approx(d.velocity_std_m_s / math.sqrt(lam))
    assert c.yaw_accel_noise_rad_s2 == pytest.approx(d.yaw_accel_noise_rad_s2 * lam)
    # the load's walks after a stop scale as the station keeping's (a random walk gains lambda^(1/4)),
    # so they stay faster than those on station
    for after_stop, on_station in (("load_walk_after_stop_m_s2", "load_walk_m_s2"),
                                   ("load_yaw_walk_after_stop_rad_s2", "load_yaw_walk_rad_s2")):
        assert getattr(c, after_stop) / getattr(c, on_station) == pytest.approx(
            getattr(d, after_stop) / getattr(d, on_station))
    assert (c.accel_noise_m_s2, c.heading_std_deg, c.filter_step_s) == (d.accel_noise_m_s2, d.heading_std_deg, 0.3)
    assert hybrid.environment_window_s >= c.held_load_window_s
    same = et.froude_scaled_environment(load_vessel("gunnerus"))
    assert same == d


#: Froude power of lambda (the ratio of the Lpp) each scaled estimator setting takes from full scale to the
#: model: lengths lambda^-1, speeds and times lambda^-1/2, yaw rates lambda^1/2, yaw accelerations lambda;
#: a random walk's intensity [per sqrt(s)] gains lambda^1/4 on top of its quantity's power.
FROUDE_POWERS = {"position_std_m": -1.0, "velocity_std_m_s": -0.5, "current_prior_m_s": -0.5,
                 "yaw_rate_std_deg_s": 0.5, "yaw_accel_noise_rad_s2": 1.0, "load_yaw_prior_rad_s2": 1.0,
                 "load_walk_m_s2": 0.25, "load_walk_after_stop_m_s2": 0.25,                 # accelerations: 0
                 "load_yaw_walk_rad_s2": 1.25, "load_yaw_walk_after_stop_rad_s2": 1.25,
                 "wave_window_s": -0.5, "variance_window_s": -0.5, "held_load_window_s": -0.5,
                 "held_load_block_s": -0.5, "wave_axis_window_s": -0.5, "settle_s": -0.5,
                 "max_bridged_gap_s": -0.5, "current_std_at_stop_m_s": -0.5, "current_walk_m_s": -0.25,
                 "thrust_error_walk": 0.25, "current_prior_max_m_s": -0.5, "current_prior_wind_ref_m_s": -0.5}
#: Settings the scaling keeps: accelerations, angles, fractions, counts and choices.
FROUDE_KEPT = {"heading_std_deg", "accel_noise_m_s2", "load_prior_m_s2", "thrust_error_prior", "thrust_error_model",
               "load_prior_across_wind",
               "thrust_error_prior_per_thruster", "use_velocity", "adaptive_measurement_std",
               "reset_yaw_load_at_stop", "yaw_load_kept_at_stop", "yaw_load_std_at_stop", "load_to_current_at_stop",
               "innovation_gate_sigma", "max_gated_samples", "wave_turned_yaw_load", "min_wave_anisotropy",
               "min_wave_sin2", "load_model"}


def test_the_env_variant_scales_every_dimensional_setting_by_its_froude_power(et):
    """Each scaled setting against the Froude law of its units (the test above checks three of them
    and the ratios of the walks, which a walk scaled wrongly on and after a stop alike keeps)."""
    d, c = EnvironmentConfig(), et.froude_scaled_environment(load_vessel("esso_osaka_model"))
    lam = load_vessel("gunnerus").particulars.L_pp_m / load_vessel("esso_osaka_model").particulars.L_pp_m
    assert lam > 10                                     # a 3 m model of a 36 m ship: every power matters
    # every setting is either scaled or kept on purpose (a new time or speed setting must be added)
    assert set(EnvironmentConfig.model_fields) == set(FROUDE_POWERS) | FROUDE_KEPT | {"filter_step_s"}
    # settings whose default is 0 are scaled from a non-zero value, so that their power is seen
    d = d.model_copy(update={"settle_s": 30.0, "current_std_at_stop_m_s": 0.05, "current_walk_m_s": 1e-3,
                             "thrust_error_walk": 1e-3, "current_prior_wind_ref_m_s": 8.0})
    c = et.froude_scaled_environment(load_vessel("esso_osaka_model"), defaults=d)
    for name, power in FROUDE_POWERS.items():
        assert getattr(c, name) == pytest.approx(getattr(d, name) * lam ** power, rel=1e-12), name
    for name in FROUDE_KEPT:
        assert getattr(c, name) == getattr(d, name), name
    # accelerations and angles are kept; the filter's step is the scaled 1 s on the 10-Hz rows
    assert (c.load_prior_m_s2, c.accel_noise_m_s2, c.heading_std_deg) == (d.load_prior_m_s2, d.accel_noise_m_s2,
                                                                          d.heading_std_deg)
    assert c.filter_step_s == round(d.filter_step_s / math.sqrt(lam), 1) == 0.3


def test_a_variant_name_with_an_unknown_token_is_refused(et):
    for good in ("multi_step_h30_b64_i100_abs+cmd+cg+wind+mem_sd1", "one_step+cmd+memang20",
                 "multi_step_ema0.9_own+prev", "one_step"):
        et.check_variant_name(good)
    for bad, token in (("multi_step_h30+cmdd", "+cmdd"), ("multi_step_abs_sd", "_sd"), ("multistep+cmd", "one_step"),
                       ("one_step2", "one_step"), ("one_step+ws", "+ws")):   # +ws: made by --with-wind-spread
        with pytest.raises(SystemExit, match=re.escape(token)):
            et.check_variant_name(bad)


def test_tables_give_the_pooled_errors_the_cells_below_the_physics_and_the_kinds(et):
    # the hybrid is below the physics everywhere except zigzag at 30 s
    e = screening_errors()
    e.loc[(e.model == "hybrid") & (e.kind == "zigzag") & (e.horizon_s == 30.0) & (e.state == "distance_m")
          & (e.commands == "known"), "mae"] = 2.0
    assert load_benchmark("_results").cells_below(e, "hybrid") == "3/4"
    lines = et.tables(e, "python benchmarks/esso_training.py --variants a").splitlines()
    assert lines[0] == "Command: `python benchmarks/esso_training.py --variants a`"
    assert "| hybrid | 0.267 | 0.800 | 12.00 | 3/4 |" in lines
    assert "| dynamic | 0.333 | 1.000 | 20.00 |  |" in lines
    assert "| hybrid | 0.400 / 6.00 | 2.000 / 18.00 | 0.800 / 12.00 | 0.80 / 0.60 |" in lines
    assert not any("99" in x for x in lines)            # the commands-held rows play no part


def test_tables_only_renders_the_run_again_with_its_command(et, tmp_path):
    screening_errors().to_csv(tmp_path / "errors.csv", index=False)
    (tmp_path / "timing.csv").write_text("model,train_s\nhybrid,1.0\n")
    (tmp_path / "tables.md").write_text("Command: `python benchmarks/esso_training.py --variants a`\nold\n")
    assert et.main(["--tables-only", "--out", str(tmp_path), "--results", str(tmp_path / "docs")]) == 0
    text = (tmp_path / "docs" / "tables.md").read_text()
    assert text.startswith("Command: `python benchmarks/esso_training.py --variants a`\n") and "old" not in text
    assert sorted(p.name for p in (tmp_path / "docs").iterdir()) == ["errors.csv", "tables.md", "timing.csv"]
    (tmp_path / "tables.md").write_text("something else\n")
    assert et.main(["--tables-only", "--out", str(tmp_path)]) == 2


@pytest.mark.parametrize("bad", [["--commands", "knwon"], ["--commands", "known,"], ["--horizons-s", "5,x"],
                                 ["--horizons-s", "0,10"]])
def test_a_misspelt_mode_or_horizon_is_a_usage_error(et, bad, tmp_path, capsys):
    """A command mode not in COMMAND_MODES was dropped without a word (``knwon`` scored
    nothing, after training every variant) and a horizon that is not a number ended in a
    traceback; both are now usage errors (exit 2) naming the option, before any work."""
    with pytest.raises(SystemExit) as exc:
        et.main([*bad, "--split", str(tmp_path / "absent"), "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert f"error: {bad[0]}: " in capsys.readouterr().err
