"""Settings dataclasses: pydantic-validated, errors start with the field name, dataclass semantics kept."""

import dataclasses

import numpy as np
import pydantic
import pytest

from hybridship.driftoff.planning import DriftOffSettings
from hybridship.driftoff.weather import WeatherState, WeatherUncertainty
from hybridship.hsc.identification import NARXConfig
from hybridship.hsc.simulator import SeaConditions
from hybridship.residual.calibration import CalibrationConfig, SpreadCalibration
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import ResidualConfig
from hybridship.residual.multistep import MultiStepConfig
from hybridship.sim.environment import HullDimensions, MotionRAOs, SeaState
from hybridship.sim.scenario import DPLossConfig, SensorNoise

# (class, keyword arguments that break one field, the message's start)
BAD = [
    (EnsembleConfig, dict(n_members=0), "n_members: "),
    (EnsembleConfig, dict(val_fraction=0.95), "val_fraction: "),
    (MultiStepConfig, dict(fd_step=0.1), "fd_step: "),
    (ResidualConfig, dict(features=("nope",)), "features: unknown ['nope']"),
    # a feature named twice was a second, identical input of the nets; none was called "unknown []"
    (ResidualConfig, dict(features=("u_hat_m_s", "r_hat_rad_s", "u_hat_m_s")),
     "features: each at most once, got 'u_hat_m_s' more than once"),
    (ResidualConfig, dict(features=()), "features: expected at least one of "),
    (ResidualConfig, dict(bias_frame="enu"), "bias_frame: "),
    (CalibrationConfig, dict(commands=("held", "held")), "commands: "),
    (CalibrationConfig, dict(max_starts=5), "max_starts: "),
    (SpreadCalibration, dict(lead_s=[2.0, 1.0], scale=[1.0, 1.0], floor=[0.0, 0.0]), "lead_s: must increase"),
    (DPLossConfig, dict(sim_dt_s=0.3), "dt_s: must be a whole multiple"),
    (DPLossConfig, dict(noise={"uv_white_m_s": -0.1}), "noise.uv_white_m_s: "),
    (SensorNoise, dict(gnss_markov_tau_s=0.0), "noise.gnss_markov_tau_s: "),
    (SeaState, dict(hs_m=1.0, tp_s=6.0, wave_dir_from_rad=0.0, wind_speed_m_s=5.0, wind_dir_from_rad=0.0,
                    gamma=9.0), "gamma: "),
    (HullDimensions, dict(L_m=30.0, B_m=-1.0, T_m=3.0), "B_m: "),
    (MotionRAOs, dict(L_m=30.0, B_m=8.0, T_m=3.0, yaw_gain=6.0), "yaw_gain: "),
    (WeatherState, dict(tp_s=0.0), "weather.tp_s: "),
    (WeatherUncertainty, dict(hs_m=-1.0), "uncertainty.hs_m: "),
    (DriftOffSettings, dict(dt_s=1.0, horizon_s=0.5, reaction_times_s=(0.0,)), "dt_s: must be <= the horizon"),
    (SeaConditions, dict(n_components=0), "n_components: "),
    (NARXConfig, dict(hidden=()), "hidden: expected at least one value"),
]


@pytest.mark.parametrize("cls, kwargs, start", BAD, ids=[f"{c.__name__}-{s.split(':')[0]}" for c, _, s in BAD])
def test_bad_value_is_a_value_error_starting_with_the_field(cls, kwargs, start):
    assert pydantic.dataclasses.is_pydantic_dataclass(cls)
    with pytest.raises(ValueError) as info:
        cls(**kwargs)
    assert str(info.value).startswith(start), str(info.value)
    assert cls.__name__ in str(info.value)


def test_bools_strings_nan_and_unknown_keywords_are_refused():
    for kwargs, field in [(dict(n_members=True), "n_members"), (dict(lr="0.1"), "lr"),
                          (dict(n_members=np.True_), "n_members"), (dict(lr=np.True_), "lr"),
                          (dict(lr=float("nan")), "lr"), (dict(weight_decay=np.inf), "weight_decay"),
                          (dict(n_member=3), "n_member")]:
        with pytest.raises(ValueError, match=f"^{field}: "):
            EnsembleConfig(**kwargs)


def test_positional_arguments_are_named_in_errors_and_numpy_scalars_accepted():
    with pytest.raises(ValueError, match="^weather.hs_m: "):
        WeatherState(1.0, 0.0, -2.0)
    cfg = EnsembleConfig(np.int64(3), hidden=np.int32(8), lr=np.float32(0.5))
    assert (cfg.n_members, cfg.hidden) == (3, 8) and type(cfg.n_members) is int


def test_dataclass_semantics_kept():
    cfg = CalibrationConfig(commands=["known"])
    assert cfg.commands == ("known",)
    assert CalibrationConfig(**dataclasses.asdict(cfg)) == cfg  # the model-file round trip
    with pytest.raises(ValueError, match="^fraction: "):
        dataclasses.replace(cfg, fraction=0.9)  # replace validates again
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.fraction = 0.1
    assert DriftOffSettings(radii_m=[10.0, 3.0]).radii_m == (3.0, 10.0)
    assert DPLossConfig(t_shutdown_s=1000.0).t_shutdown_jitter_s == pytest.approx(40.0)


def test_arrays_are_copied_not_shared():
    lead = np.array([1.0, 2.0])
    cal = SpreadCalibration(lead, [1.0, 1.0], [0.0, 0.0])
    lead[0] = 5.0
    assert cal.lead_s[0] == 1.0


def test_array_fields_refuse_text_and_complex_numbers():
    """numpy parsed text entries as numbers and dropped an imaginary part with only a warning."""
    good = dict(lead_s=[1.0, 2.0], scale=[1.0, 1.0], floor=[0.0, 0.0])
    for field, value in (("lead_s", ["1", "2"]), ("scale", np.array([1.0 + 0.5j, 1.0])), ("floor", "0 0")):
        with pytest.raises(ValueError, match=f"^{field}: expected an array of real numbers, got dtype"):
            SpreadCalibration(**{**good, field: value})
    assert SpreadCalibration(**{**good, "lead_s": np.array([1, 2])}).lead_s.dtype == float


def test_predictors_take_settings_or_dicts_of_them_and_name_a_typo():
    """A dict of a settings class's fields is validated into it; a misspelt key or another
    type fails at construction, naming the argument, not later inside training."""
    from hybridship.predictors import DataOnlyPredictor, HybridPredictor

    h = HybridPredictor("gunnerus", ensemble_config={"n_members": 2}, environment_config={"current_prior_m_s": 0.05})
    assert h.ensemble_config == EnsembleConfig(n_members=2) and h.environment_config.current_prior_m_s == 0.05
    with pytest.raises(ValueError, match=r"^ensemble_config: n_membrs: not a known field"):
        HybridPredictor("gunnerus", ensemble_config={"n_membrs": 2})
    with pytest.raises(ValueError, match=r"^environment_config: foo: not a known field"):
        HybridPredictor("gunnerus", environment_config={"foo": 1})
    with pytest.raises(TypeError, match=r"^multistep_config: expected an instance of MultiStepConfig"):
        HybridPredictor("gunnerus", multistep_config=3)
    with pytest.raises(ValueError, match=r"^ensemble_config: hidden"):
        DataOnlyPredictor("gunnerus", ensemble_config={"hidden": [1]})


def test_command_line_lines_drop_the_settings_class_but_keep_units():
    from hybridship.messages import problem_lines

    err = ValueError("drift_s: must be > 0 (got -5.0) [DPLossConfig]\nlog: winch_load [N]\nload [kN m]")
    assert problem_lines(err, "x: ") == "x: drift_s: must be > 0 (got -5.0)\nx: log: winch_load [N]\nx: load [kN m]"
    assert problem_lines(err, "", lambda f: {"drift_s": "--drift-s"}.get(f, f)).splitlines()[0] == \
        "--drift-s: must be > 0 (got -5.0)"


def test_bounds_in_messages_keep_their_digits():
    from hybridship.residual.ensemble import EnsembleConfig

    with pytest.raises(ValueError, match=r"n_members: must be <= 1000 \(got 1001\)"):
        EnsembleConfig(n_members=1001)
    with pytest.raises(ValueError, match=r"lr: must be > 0 \(got -0.5\)"):
        EnsembleConfig(lr=-0.5)
    # each kind of bound in its own words (the table above only checks the field's name):
    # n_members >= 1, 0 < val_fraction < 0.9, as the fields declare them
    with pytest.raises(ValueError, match=r"^n_members: must be >= 1 \(got 0\)"):
        EnsembleConfig(n_members=0)
    with pytest.raises(ValueError, match=r"^val_fraction: must be < 0.9 \(got 0.95\)"):
        EnsembleConfig(val_fraction=0.95)


def test_the_guard_quantile_is_checked_when_the_hybrid_is_made():
    from hybridship.predictors import HybridPredictor

    for bad in (2, float("nan"), -1, 0.4, 1.0, "a", True):
        with pytest.raises(ValueError, match=r"guard_quantile: expected a number in \[0.5, 1\)"):
            HybridPredictor("gunnerus", guard_quantile=bad)
    assert HybridPredictor("gunnerus", guard_quantile=0.95).guard_quantile == 0.95


def test_real_array_refuses_text_in_an_object_array():
    """A pandas column of text ('1500') is an object array, which astype(float) parsed as numbers."""
    import pandas as pd

    from hybridship.config import real_array

    for value in (pd.Series(["1500", "1600"]), np.array([1.5, "2"], dtype=object), np.array([1.0, 1j], dtype=object)):
        with pytest.raises(TypeError, match="^rpm: expected an array of real numbers"):
            real_array("rpm", value)
    with pytest.raises(ValueError, match="^scale: expected an array of real numbers"):
        SpreadCalibration(lead_s=[1.0, 2.0], scale=pd.Series(["1", "1"]), floor=[0.0, 0.0])
    assert real_array("rpm", pd.Series([1500, 1600], dtype=object)).tolist() == [1500.0, 1600.0]


def test_check_number_names_a_whole_number_beyond_a_floats_range():
    """float(10**400) raised Python's own 'int too large to convert to float' (OverflowError)."""
    from hybridship.config import check_number

    with pytest.raises(ValueError, match="^horizon_s: must be finite"):
        check_number("horizon_s", 10**400)
    assert check_number("horizon_s", 10**300) == 1e300


def test_the_estimators_settings_built_directly_name_the_field_not_pydantic():
    """EnvironmentConfig(filter_step_s=-1) was pydantic's '1 validation error for
    EnvironmentConfig ... https://errors.pydantic.dev/...', unlike every other settings class."""
    from hybridship.residual.environment import EnvironmentConfig

    with pytest.raises(ValueError, match=r"^filter_step_s: must be > 0 \(got -1\) \[EnvironmentConfig\]$"):
        EnvironmentConfig(filter_step_s=-1)
    with pytest.raises(ValueError, match=r"^foo: not a known field") as err:
        EnvironmentConfig(foo=1)
    assert "pydantic" not in str(err.value)
    assert EnvironmentConfig(filter_step_s=2.0).filter_step_s == 2.0
