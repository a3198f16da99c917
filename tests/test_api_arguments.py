"""Arguments of the public API refused by name where a wrong kind used to pass silently or
fail deep inside numpy or torch (flags given as text, seeds out of range, synthetic-log settings)."""

from __future__ import annotations

import numpy as np
import pytest

from hybridship.driftoff.live import environment_from_log
from hybridship.physics.model import DynamicModel
from hybridship.predictors import DataOnlyPredictor, DynamicPredictor, HybridPredictor
from hybridship.residual.calibration import CalibrationConfig
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.environment import EnvironmentConfig
from hybridship.residual.multistep import MultiStepConfig
from hybridship.sim.synthetic import physics_log


@pytest.mark.parametrize("kw, field", [(dict(guard="no"), "guard"), (dict(drift_hull=1), "drift_hull"),
                                       (dict(nets_after_stop="False"), "nets_after_stop"),
                                       (dict(hull_ridge=-1.0), "hull_ridge"),
                                       (dict(environment_window_s=0.0), "environment_window_s")])
def test_hybrid_settings_of_the_wrong_kind_are_refused_by_name(kw, field):
    """A text 'no' is truthy: it used to switch the guard on."""
    with pytest.raises((TypeError, ValueError), match=f"^{field}: "):
        HybridPredictor("gunnerus", **kw)


@pytest.mark.parametrize("make, field", [
    (lambda: DynamicPredictor(stop_after_failure="no"), "stop_after_failure"),
    (lambda: DataOnlyPredictor(stop_after_failure="false"), "stop_after_failure"),
    (lambda: DynamicModel("gunnerus", true_vessel="no"), "true_vessel"),
    (lambda: DynamicModel("gunnerus").acceleration(np.zeros(3), np.zeros(3), return_parts="no"), "return_parts")])
def test_text_flags_of_the_physics_and_the_plain_predictors_are_refused(make, field):
    """Review: these read a text 'no' as True (the perturbed "true" vessel, for one)."""
    with pytest.raises(TypeError, match=f"^{field}: expected True or False, got "):
        make()


def test_settings_given_as_a_dict_are_taken_as_the_config_class():
    """Review: ``DynamicPredictor(residual_config={...})`` failed at forecast time with an
    AttributeError; a dict is validated as the class's fields, as elsewhere."""
    from hybridship.residual.features import ResidualConfig

    p = DynamicPredictor(residual_config={"start_average_s": 5.0})
    assert isinstance(p.residual_config, ResidualConfig) and p.residual_config.start_average_s == 5.0
    with pytest.raises(TypeError, match="^residual_config: expected an instance of ResidualConfig"):
        DynamicPredictor(residual_config=None)


def test_fit_flags_are_checked_before_reading_the_logs():
    with pytest.raises(TypeError, match="^dp_only: expected True or False, got 'no'"):
        HybridPredictor("gunnerus").fit(["not read"], dp_only="no")


@pytest.mark.parametrize("seed, message", [(-1, "must be >= 0"), (2 ** 70, "must be <"), (True, "not a bool")])
def test_seeds_out_of_the_generators_range_are_refused_at_construction(seed, message):
    with pytest.raises(ValueError, match=f"seed: .*{message}"):
        EnsembleConfig(seed=seed)


def test_environment_from_log_names_its_seed_and_takes_numpy_numbers():
    log = physics_log(DynamicModel("gunnerus"), duration_s=1000.0, t_shutdown_s=None, seed=1)
    with pytest.raises(ValueError, match="^seed: expected a whole number >= 0, got None"):
        environment_from_log(log, seed=None)
    # a numpy integer is taken as the number it is: the estimate of the same window given as a
    # float, not the default 900 s window's (a window left unused passed with np.int64(900))
    est = environment_from_log(log, window_s=np.int64(600), n_members=2)
    same = environment_from_log(log, window_s=600.0, n_members=2)
    default = environment_from_log(log, n_members=2)
    np.testing.assert_array_equal(est.accel_members, same.accel_members)
    np.testing.assert_array_equal(est.current_members_ned_m_s, same.current_members_ned_m_s)
    assert np.isfinite(est.accel_members).all() and not np.array_equal(est.accel_members, default.accel_members)
    from hybridship.logs.io import LogFormatWarning

    with pytest.warns(LogFormatWarning, match="^my_log.csv: ignoring 1 column"):     # the log named as given
        environment_from_log(log.assign(extra=1.0), n_members=2, name="my_log.csv")


@pytest.mark.parametrize("kw, field", [(dict(hold_s=(-10.0, -5.0)), r"hold_s\[0\]"), (dict(dt_s=0.0), "dt_s"),
                                       (dict(duration_s=-10.0), "duration_s"), (dict(seed=None), "seed"),
                                       (dict(rpm_scale=-1.0), "rpm_scale"), (dict(hold_s=(5.0, 1.0)), "hold_s"),
                                       (dict(wind=(-1.0, 0.0)), r"wind\[0\]")])
def test_synthetic_log_settings_are_checked(kw, field):
    """A negative hold time used to loop for ever."""
    with pytest.raises(ValueError, match=f"^{field}"):
        physics_log(DynamicModel("gunnerus"), **kw)
    with pytest.raises(TypeError, match="^model: expected a DynamicModel"):
        physics_log("gunnerus")


def test_calibrate_after_stop_names_its_own_arguments(monkeypatch):
    """Its settings are checked before any forecast (a forecast fails the test: a bad ``cal``
    checked only after the logs' forecasts was refused by name all the same), and a
    settings dict is taken as the constructor takes one."""
    from hybridship.predictors import hybrid

    hp = HybridPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=2, max_epochs=2, seed=0))
    model = DynamicModel("gunnerus")
    logs = [physics_log(model, duration_s=700.0, t_shutdown_s=500.0, seed=s) for s in (1, 2)]
    hp.fit(logs)

    def no_forecast_yet(*args, **kwargs):
        raise RuntimeError("a forecast ran before the arguments were checked")
    monkeypatch.setattr(hybrid, "drift_forecasts", no_forecast_yet)
    for kw, field in ((dict(n_intervals=0), "n_intervals"), (dict(n_intervals=2.5), "n_intervals"),
                      (dict(horizon_s=0.0), "horizon_s"), (dict(horizon_s=0.4), "horizon_s"),
                      (dict(cal={"sigmaa": 2}), "cal")):
        with pytest.raises((TypeError, ValueError), match=f"^{field}"):
            hp.calibrate_after_stop(logs, **kw)


def test_high_speed_craft_models_check_their_settings_at_construction():
    """Orders, lags and steps are refused by name (they failed in LAPACK, in max() or fitted
    nonsense); a craft may be given by name, and settings as dicts, as elsewhere."""
    from hybridship.hsc.hybrid import HybridModel
    from hybridship.hsc.identification import ARXModel, NARXConfig, NARXModel, StateSpaceModel

    for make, field in ((lambda: StateSpaceModel(0), "order"), (lambda: ARXModel("2", 2), "na"),
                        (lambda: ARXModel(2, 2.5), "nb"), (lambda: HybridModel("volcano71", "interceptor", acc_lags=-1),
                                                           "acc_lags"),
                        (lambda: HybridModel("volcano71", "interceptor", dt_s=-0.1), "dt_s")):
        with pytest.raises(ValueError, match=f"^{field}: "):
            make()
    with pytest.raises(TypeError, match="^craft: expected a PlaningCraft"):
        HybridModel(3, "interceptor")
    assert NARXModel({"n_out": 2}).config == NARXConfig(n_out=2)
    assert HybridModel("volcano71", "interceptor", ensemble={"n_members": 2}).ensemble_config.n_members == 2


def test_physics_inputs_frames_and_channel_names_are_named_in_plain_words():
    from hybridship.frames import latlon_to_north_east, north_east_to_latlon
    from hybridship.logs.io import validate_log

    m = DynamicModel("gunnerus")
    with pytest.raises(ValueError, match="^eta: expected numbers, got 'abc'"):
        m.acceleration("abc", np.zeros(3))
    with pytest.raises(ValueError, match="^rpm: expected numbers"):
        m.acceleration(np.zeros(3), np.zeros(3), rpm="x")
    with pytest.raises(ValueError, match="^eta, nu: batches of 2 and 3 states"):
        m.acceleration(np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="^lat_deg: a latitude is within"):
        latlon_to_north_east(95.0, 10.0, 63.0, 10.0)
    # the inverse took a reference latitude beyond the pole and returned a latitude of 95 deg
    with pytest.raises(ValueError, match="^lat0_deg: a latitude is within"):
        north_east_to_latlon(0.0, 100.0, 95.0, 10.0)
    log = physics_log(m, duration_s=60.0, t_shutdown_s=None)
    with pytest.raises(ValueError, match="^channel_names: expected a sequence of names, got the string 'port'"):
        validate_log(log, channel_names="port")


def test_season_sweep_quantile_and_labels_are_checked(monkeypatch):
    """Before any state is simulated (a simulation fails the test): without the sweep's own
    check, a bad quantile was refused by the first state's watch circle, in the same words,
    after that state's blackouts had run."""
    from hybridship.driftoff import season
    from hybridship.driftoff.season import season_sweep
    from hybridship.driftoff.weather import WeatherState

    def no_simulation_yet(*args, **kwargs):
        raise RuntimeError("a state was simulated before the arguments were checked")
    monkeypatch.setattr(season, "simulate_blackouts", no_simulation_yet)
    states = [WeatherState(), WeatherState()]
    for kw, field in ((dict(quantile=None), "quantile"), (dict(quantile="0.9"), "quantile"),
                      (dict(labels=["a", "a"]), "labels: expected distinct")):
        with pytest.raises(ValueError, match=f"^{field}"):
            season_sweep("gunnerus", states, [0.0], progress=False, **kw)   # in this process


def test_simulate_blackouts_refuses_a_text_flag():
    from hybridship.driftoff.planning import simulate_blackouts
    from hybridship.driftoff.weather import WeatherState

    with pytest.raises(TypeError, match="^keep_tracks: expected True or False, got 'no'"):
        simulate_blackouts("gunnerus", WeatherState(), [0.0], keep_tracks="no")
    from hybridship.driftoff.season import season_sweep

    # a text "no" is truthy: the sweep's progress bar would show
    with pytest.raises(TypeError, match="^progress: expected True or False, got 'no'"):
        season_sweep("gunnerus", [WeatherState()], [0.0], progress="no")


def test_after_stop_errors_and_the_drift_hull_objective_bound_their_horizon_and_flags():
    """Review: ``calibrate_after_stop(horizon_s=1e9)`` built the leads before any check and was
    killed for memory; ``drift_hull_objective(horizon_s=nan)`` said "cannot convert float NaN
    to integer"; ``late="no"`` was read as True."""
    log = physics_log(DynamicModel("gunnerus"), duration_s=300.0, t_shutdown_s=None, seed=1)
    hp = HybridPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=2, hidden=8, max_epochs=3)).fit([log])
    for call in (lambda: hp.after_stop_errors([log], horizon_s=1e9),
                 lambda: hp.calibrate_after_stop([log], horizon_s=1e9),
                 lambda: hp.drift_hull_objective([log], horizon_s=float("nan"))):
        with pytest.raises(ValueError, match="^horizon_s: "):
            call()
    with pytest.raises(TypeError, match="^late: expected True or False, got 'no'"):
        hp.after_stop_errors([log], late="no")


@pytest.mark.parametrize("cls, field", [(EnsembleConfig, "bootstrap"), (CalibrationConfig, "refit"),
                                        (MultiStepConfig, "tune_hull"), (EnvironmentConfig, "use_velocity")])
def test_settings_flags_refuse_text_and_numbers(cls, field):
    """Review: pydantic read "no" as False and 1 as True in the settings' flags; the settings
    refuse them, as the functions' flags do (numpy's bools are taken)."""
    for bad in ("no", 1):
        with pytest.raises(ValueError, match=f"(?s){field}.*expected True or False, got"):
            cls(**{field: bad})
    assert getattr(cls(**{field: np.bool_(False)}), field) is False


def test_physics_inputs_given_as_text_that_reads_as_numbers_are_refused():
    m = DynamicModel("gunnerus")
    with pytest.raises(ValueError, match=r"^rpm: expected numbers, got \['100', '0', '0'\]"):
        m.acceleration(np.zeros(3), np.zeros(3), rpm=["100", "0", "0"])
    with pytest.raises(ValueError, match="^current: expected numbers"):
        m.rollout(np.zeros(3), np.zeros(3), 2, current=[1.0, "1"])
    with pytest.raises(ValueError, match="^nu: expected numbers"):
        m.step(np.zeros(3), ["1", "0", "0"])
    with pytest.raises(ValueError, match="^wind: expected numbers"):
        m.acceleration(np.zeros(3), np.zeros(3), wind=np.array([5.0 + 1j, 0.0]))
    assert m.acceleration(np.zeros(3), [1, 0, 0], rpm=np.array([100, 0, 0], dtype=np.int32)).shape == (1, 3)


def test_the_data_only_fit_names_a_training_log_too_short_for_a_derivative():
    """It used to skip such a log after numpy's 'Mean of empty slice' warning (one sample)."""
    good = physics_log(DynamicModel("gunnerus"), seed=2, duration_s=300.0, t_shutdown_s=None)
    dp = DataOnlyPredictor("gunnerus", ensemble_config=EnsembleConfig(n_members=1, hidden=4, max_epochs=2))
    for n in (1, 2):
        with pytest.raises(ValueError, match=rf"^logs\[1\]: a training log needs at least 3 samples, got {n}"):
            dp.fit([good, good.iloc[:n]])
        assert dp.ensemble is None


def test_a_horizon_beyond_any_float_is_refused_by_name():
    """``horizon_s=10**400`` was Python's OverflowError ('int too large to convert to float')."""
    log = physics_log(DynamicModel("gunnerus"), seed=2, duration_s=120.0, t_shutdown_s=None)
    with pytest.raises(ValueError, match=r"^horizon_s: must be > 0 and at most 86400 s \(one day\), got inf"):
        DynamicPredictor("gunnerus").fit().forecast(log, [10.0], horizon_s=10**400)
