"""Hybrid, dynamic and dead-reckoning predictors: facts on logs with known physics."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from hybridship.frames import body_to_ned, wrap_pi
from hybridship.logs.io import LogFormatError
from hybridship.predictors import (DataOnlyPredictor, DeadReckoning, DynamicPredictor, HybridPredictor,
                                   ModelFileError, as_log_arrays)
from hybridship.residual.calibration import CalibrationConfig
from hybridship.residual.ensemble import EnsembleConfig, MLPEnsemble, fit_ensemble
from hybridship.residual.features import COMMAND_FEATURES, ResidualConfig, prepare_log
from hybridship.residual.guard import EnvelopeGuard, ThrustRegime
from hybridship.sim.synthetic import physics_log

SMALL = EnsembleConfig(n_members=4, max_epochs=250, patience=40, seed=1)


@pytest.fixture(scope="module")
def exact_logs(model):
    """Logs made by the forecast model itself: nothing is unknown."""
    return [physics_log(model, seed=s) for s in (1, 2, 3)]


@pytest.fixture(scope="module")
def current_logs(model):
    """Logs of the same ship in a steady 0.3 m/s current the forecast model does not know."""
    return [physics_log(model, seed=s, current=(0.3, 1.0)) for s in (1, 2, 3)]


def _errors_60s(predictor, log, starts, **kw):
    fc = predictor.forecast(log, starts, 60, **kw)
    truth = log[["north_m", "east_m"]].to_numpy()
    return np.abs(fc.eta[:, -1, :2] - truth[starts + 60]).mean(axis=0)


def test_residual_is_zero_on_a_log_the_model_made(model, exact_logs):
    prep = prepare_log(model, as_log_arrays(exact_logs[0], model.vessel))
    rows = prep.trainable_rows()
    # the synthetic log integrates with 4 substeps, the forecast model with 1: O(dt^4) apart
    assert np.abs(prep.residual[rows]).max() < 1e-5


def test_hybrid_matches_physics_when_nothing_is_unknown(model, exact_logs):
    hp = HybridPredictor(model.vessel, ensemble_config=SMALL).fit(exact_logs[:2])
    starts = np.arange(900, 920)
    e_h = _errors_60s(hp, exact_logs[2], starts)
    e_d = _errors_60s(DynamicPredictor(model.vessel), exact_logs[2], starts)
    assert np.all(e_d < 0.1)                     # physics is (nearly) exact here
    assert np.all(np.abs(e_h - e_d) < 0.1)       # and the hybrid adds (nearly) nothing


def test_hybrid_learns_a_steady_current(model, current_logs):
    hp = HybridPredictor(model.vessel, ensemble_config=SMALL).fit(current_logs[:2])
    starts = np.arange(900, 920)
    e_h = _errors_60s(hp, current_logs[2], starts)
    e_d = _errors_60s(DynamicPredictor(model.vessel), current_logs[2], starts)
    assert e_d.sum() > 3.0                       # the current matters over a minute
    assert e_h.sum() < 0.6 * e_d.sum()           # the hybrid removes much of that error


def test_dead_reckoning_is_exact_for_constant_velocity(model):
    log = physics_log(model, seed=4, t_shutdown_s=None, rpm_scale=0.0, wind=(0.0, 0.0))
    # no forces at all: the ship stays at rest, and dead reckoning predicts exactly that
    e = _errors_60s(DeadReckoning(model.vessel), log, np.array([100, 200]))
    assert np.all(e < 1e-9)
    # a ship at rest has no velocity to carry: on a straight track at 1.5 m/s ahead and 0.4 m/s
    # to port, heading 060, the body velocity is rotated into north/east (its transpose, or a
    # position held, misses by tens of metres in a minute)
    t = log.time_s.to_numpy()
    psi, u, v = np.radians(60.0), 1.5, -0.4
    vn, ve = np.cos(psi) * u - np.sin(psi) * v, np.sin(psi) * u + np.cos(psi) * v
    moving = log.assign(north_m=100.0 + vn * t, east_m=-50.0 + ve * t, heading_deg=60.0, u_m_s=u, v_m_s=v,
                        r_deg_s=0.0)
    starts = np.array([100, 200])
    fc = DeadReckoning(model.vessel).forecast(moving, starts, 60)
    truth = moving[["north_m", "east_m"]].to_numpy()[starts[:, None] + np.arange(61)]
    np.testing.assert_allclose(fc.eta[..., :2], truth, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fc.eta[..., 2], psi, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fc.nu, np.broadcast_to([u, v, 0.0], fc.nu.shape), rtol=0, atol=1e-12)


def test_save_load_round_trip_gives_identical_forecasts(model, current_logs, tmp_path):
    hp = HybridPredictor(model.vessel, ensemble_config=SMALL).fit(current_logs[:1])
    path = hp.save(tmp_path / "m.npz")
    hp2 = HybridPredictor.load(path)
    starts = np.array([900, 905])
    a = hp.forecast(current_logs[2], starts)
    b = hp2.forecast(current_logs[2], starts)
    np.testing.assert_array_equal(a.eta, b.eta)
    np.testing.assert_array_equal(a.eta_std, b.eta_std)
    assert not list(tmp_path.glob(".*tmp"))      # atomic write left no temporary file
    # the model file knows the rate it was trained at, and says so on a log at another
    assert hp2.training_info["log_step_s"] == [1.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hp2.forecast(current_logs[2], starts)
    with pytest.warns(UserWarning, match=r"log: its step is 2 s, but the model was trained on logs with a step "
                                         r"of 1 s"):
        hp2.forecast(current_logs[2].iloc[::2].reset_index(drop=True), [900.0], 30)
    # and that its logs had wind: a log without wind columns is forecast without the wind's force
    assert hp2.training_info["trained_with_wind"] is True
    with pytest.warns(UserWarning, match=r"log: no wind columns \(wind_speed_m_s, wind_dir_deg\), but the model "
                                         r"was trained on logs with wind"):
        hp2.forecast(current_logs[2].drop(columns=["wind_speed_m_s", "wind_dir_deg"]), [900.0], 30)


def test_a_forecast_step_between_two_training_steps_is_warned_about():
    """Trained on 0.1-s and 1-s logs, a 0.5-s log is at a rate the nets never saw; only steps
    outside 0.09..1.1 s were warned about (the range from the shortest to the longest)."""
    from hybridship.predictors.training_logs import warn_other_rate

    info = {"log_step_s": [0.1, 1.0]}
    with pytest.warns(UserWarning, match=r"log: its step is 0.5 s, but the model was trained on logs with a step "
                                         r"of 0.1, 1 s"):
        warn_other_rate(info, 0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for dt in (0.1, 0.105, 0.95, 1.0, 1.1):
            warn_other_rate(info, dt)
        warn_other_rate({}, 0.5)                      # a model file from before the entry


def test_training_logs_with_and_without_wind_are_named_once_at_fit(model, current_logs):
    """A training log without wind columns beside logs with them is warned about by name, once,
    in the words of training; before, the calibration's own forecasts on it warned "log: ...
    the forecast leaves out the wind's force" (twice, naming no log, as if forecasting)."""
    logs = [current_logs[0], current_logs[1].drop(columns=["wind_speed_m_s", "wind_dir_deg"])]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        HybridPredictor(model.vessel, ensemble_config=SMALL).fit(logs)
    texts = [str(w.message) for w in caught if "wind" in str(w.message)]
    assert len(texts) == 1, texts
    assert texts[0].startswith("logs[1]: no wind columns (wind_speed_m_s, wind_dir_deg)") and "logs[0]" in texts[0]
    assert "forecast" not in texts[0]


def test_the_data_only_baseline_warns_as_the_hybrid_about_rate_and_wind(model, current_logs):
    """The data-only baseline forecast a log at another rate, or one without wind columns
    after training with wind, and trained on logs with and without wind, all without a word;
    it now says so in the hybrid's words."""
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=15, patience=5, seed=0)
    dp = DataOnlyPredictor(model.vessel, ensemble_config=tiny).fit(current_logs[:1])
    assert dp.training_info == {"log_step_s": [1.0], "trained_with_wind": True}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        dp.forecast(current_logs[2], [900.0], 30)
    with pytest.warns(UserWarning, match=r"log: its step is 2 s, but the model was trained on logs with a step "
                                         r"of 1 s"):
        dp.forecast(current_logs[2].iloc[::2].reset_index(drop=True), [900.0], 30)
    with pytest.warns(UserWarning, match=r"log: no wind columns \(wind_speed_m_s, wind_dir_deg\), but the model "
                                         r"was trained on logs with wind"):
        dp.forecast(current_logs[2].drop(columns=["wind_speed_m_s", "wind_dir_deg"]), [900.0], 30)
    logs = [current_logs[0], current_logs[1].drop(columns=["wind_speed_m_s", "wind_dir_deg"])]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        DataOnlyPredictor(model.vessel, ensemble_config=tiny).fit(logs)
    texts = [str(w.message) for w in caught if "wind" in str(w.message)]
    assert len(texts) == 1 and texts[0].startswith("logs[1]: no wind columns (wind_speed_m_s, wind_dir_deg)"), texts
    assert [w.filename for w in caught if "wind" in str(w.message)] == [__file__]


def test_the_data_only_baseline_takes_each_rows_own_step_on_a_log_with_uneven_steps(model, monkeypatch):
    """The data-only baseline divided every velocity change by the log's median step: on a log
    whose steps alternate between 0.8 and 1.2 s, a constant surge acceleration of 0.01 m/s^2
    was learned as 0.008 and 0.012 (targets and previous accelerations), and a forecast's start
    acceleration was off too. Each now uses the time between its own rows."""
    import hybridship.predictors.data_only as data_only

    steps = np.tile([0.8, 1.2], 100)
    t = np.concatenate([[0.0], np.cumsum(steps)])
    log = physics_log(model, duration_s=len(t) - 1, t_shutdown_s=None, seed=1).iloc[:len(t)].copy()
    log["time_s"] = t
    log["u_m_s"], log["v_m_s"], log["r_deg_s"] = 0.01 * t, 0.0, 0.0
    log["north_m"], log["east_m"], log["heading_deg"] = 0.005 * t ** 2, 0.0, 0.0
    seen = {}

    class Members:
        n_members = 1

        def predict_members(self, X):
            seen.setdefault("X0", X.copy())
            return np.zeros(X.shape[:-1] + (3,))

    def fit_ensemble(X, Y, config, **kw):
        seen.update(X=X, Y=Y)
        return Members()

    monkeypatch.setattr(data_only, "fit_ensemble", fit_ensemble)
    dp = DataOnlyPredictor(model.vessel).fit([log])
    np.testing.assert_allclose(seen["Y"][:, 0], 0.01, rtol=1e-9)          # the targets
    np.testing.assert_allclose(seen["X"][:, -3], 0.01, rtol=1e-9)         # the previous acceleration
    dp.forecast(log, [t[101]], 10.0)
    np.testing.assert_allclose(seen["X0"][0, 0, -3], 0.01, rtol=1e-9)     # the start acceleration


def test_the_fit_warning_about_a_log_without_wind_points_at_the_callers_line(model, current_logs, monkeypatch):
    """The warning named the decorator's line in forecast_setup.py as its place (one frame
    short), so a filter on the caller's module missed it and the shown line was library code.
    The fit is stopped right after the warning."""
    class Stop(Exception):
        pass

    def stop(*args, **kwargs):
        raise Stop

    monkeypatch.setattr("hybridship.predictors.hybrid.EnvironmentEstimator", stop)
    logs = [current_logs[0], current_logs[1].drop(columns=["wind_speed_m_s", "wind_dir_deg"])]
    with warnings.catch_warnings(record=True) as caught, pytest.raises(Stop):
        warnings.simplefilter("always")
        HybridPredictor(model.vessel, ensemble_config=SMALL).fit(logs)
    places = [w.filename for w in caught if "no wind columns" in str(w.message)]
    assert places == [__file__]


def test_damaged_or_foreign_model_files_are_refused(model, current_logs, tmp_path):
    hp = HybridPredictor(model.vessel, ensemble_config=SMALL).fit(current_logs[:1])
    path = hp.save(tmp_path / "m.npz")
    raw = path.read_bytes()
    (tmp_path / "trunc.npz").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(ModelFileError, match="not a readable"):
        HybridPredictor.load(tmp_path / "trunc.npz")
    d = model.vessel.model_dump()
    d["rigid_body"]["mass_kg"] *= 1.1
    from hybridship.vessel import vessel_from_dict
    other = vessel_from_dict(d)
    with pytest.raises(ModelFileError, match="refusing"):
        HybridPredictor.load(path, vessel=other)


def test_forecast_outputs_are_tidy_and_batched(model, current_logs):
    hp = HybridPredictor(model.vessel, ensemble_config=SMALL).fit(current_logs[:1])
    fc = hp.forecast(current_logs[2], [900, 901, 902], horizon_s=30)
    assert fc.eta.shape == (3, 31, 3) and fc.eta_std.shape == (3, 31, 3)
    # no spread at the start, a spread after 30 s (a standard deviation is >= 0 whatever the forecast)
    assert np.all(fc.eta_std[:, 0] == 0) and np.all(fc.eta_std[:, -1] > 0)
    df = fc.to_frame()
    assert len(df) == 93 and {"north_m", "east_m", "heading_deg", "north_std_m", "guard_weight"} <= set(df)
    assert df["heading_deg"].between(0, 360).all()
    # one row per start and lead, start after start: each row holds its own start's values at
    # its own lead, every state in its column, in degrees where the name says so
    np.testing.assert_array_equal(df.start_time_s, np.repeat([900.0, 901.0, 902.0], 31))
    np.testing.assert_array_equal(df.lead_s, np.tile(np.arange(31.0), 3))
    np.testing.assert_array_equal(df.time_s, df.start_time_s + df.lead_s)
    k, j = 2, 17
    row = df.iloc[31 * k + j]
    assert (row.start_time_s, row.lead_s) == (902.0, 17.0)
    want = {"north_m": fc.eta[k, j, 0], "east_m": fc.eta[k, j, 1],
            "heading_deg": np.degrees(fc.eta[k, j, 2]) % 360.0, "u_m_s": fc.nu[k, j, 0], "v_m_s": fc.nu[k, j, 1],
            "r_deg_s": np.degrees(fc.nu[k, j, 2]), "north_std_m": fc.eta_std[k, j, 0],
            "east_std_m": fc.eta_std[k, j, 1], "heading_std_deg": np.degrees(fc.eta_std[k, j, 2]),
            "guard_weight": fc.guard_weight[k, j]}
    for col, value in want.items():
        assert row[col] == pytest.approx(value, rel=1e-12, abs=1e-12), col
    assert len({round(float(row[c]), 9) for c in want}) == len(want)          # no two columns alike here


def test_bad_logs_and_start_times_name_the_problem(model, current_logs):
    hp = DynamicPredictor(model.vessel)
    log = current_logs[0]
    with pytest.raises(LogFormatError, match="north_m"):
        hp.forecast(log.drop(columns=["north_m"]), [100])
    bad = log.copy()
    bad.loc[50, "east_m"] = np.nan
    with pytest.raises(LogFormatError, match="east_m"):       # training data must be complete
        HybridPredictor(model.vessel, ensemble_config=SMALL).fit([bad])
    fc = hp.forecast(bad, [100])                              # a forecast uses what is valid ...
    assert not any(v[0] for v in fc.flags.values())           # ... and a gap 50 s back is no fault
    bad = log.copy()
    bad.loc[60, "time_s"] = bad.loc[59, "time_s"]
    with pytest.raises(LogFormatError, match="time_s"):         # training: strictly increasing time
        HybridPredictor(model.vessel, ensemble_config=SMALL).fit([bad])
    # forecasting: a late/duplicate sample is re-sorted or dropped (see test_reliability_integration)
    assert np.isfinite(hp.forecast(bad, [100]).eta).all()
    bad = log.copy()
    bad["heading_deg"] = np.radians(bad["heading_deg"])
    with pytest.raises(LogFormatError, match="heading_deg"):
        hp.forecast(bad, [100])
    with pytest.raises(ValueError, match="start_times_s"):
        hp.forecast(log, [100.5])
    assert log["north_m"].notna().all()          # the caller's frame was not modified


def test_ensemble_fits_a_known_function_and_members_disagree_off_data():
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, size=(600, 2))
    Y = np.column_stack([np.sin(2 * X[:, 0]), X[:, 0] * X[:, 1], 0.5 * X[:, 1]])
    ens = fit_ensemble(X, Y, EnsembleConfig(n_members=5, max_epochs=600, patience=100, seed=3))
    mean, std = ens.predict(X)
    assert np.sqrt(np.mean((mean - Y) ** 2)) < 0.05
    _, std_far = ens.predict(np.array([[6.0, -6.0]]))
    assert std_far.mean() > 5 * std.mean()       # spread grows outside the data


def test_input_noise_flattens_the_fit_and_none_is_the_default():
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, size=(400, 1))
    Y = np.tanh(8 * X)                           # a steep step: its slope is 8 at 0
    cfg = EnsembleConfig(n_members=3, max_epochs=400, patience=400, seed=1)
    x = np.linspace(-0.2, 0.2, 41)[:, None]
    slopes = {}
    for noise in (0.0, 0.5):
        ens = fit_ensemble(X, Y, replace(cfg, input_noise_std=noise))
        slopes[noise] = np.max(np.diff(ens.predict(x)[0][:, 0]) / np.diff(x[:, 0]))
    assert slopes[0.0] > 4.0 and slopes[0.5] < 0.6 * slopes[0.0], slopes
    assert EnsembleConfig().input_noise_std == 0.0
    with pytest.raises(ValueError, match="^input_noise_std: "):
        EnsembleConfig(input_noise_std=-0.1)



def test_ensemble_arguments_are_refused_by_name_and_settings_may_be_a_dict():
    rng = np.random.default_rng(0)
    X, Y = rng.normal(size=(40, 3)), rng.normal(size=(40, 2))
    tiny = {"n_members": 2, "hidden": 4, "max_epochs": 3}
    ens = fit_ensemble(X, Y, tiny)                   # before: AttributeError 'dict' ... 'val_fraction'
    assert ens.n_members == 2
    with pytest.raises(TypeError, match="config: expected an instance of EnsembleConfig"):
        fit_ensemble(X, Y, None)
    # before: a segment_id for 5 rows trained on those 5 rows only, NaN made each row a segment
    with pytest.raises(ValueError, match=r"segment_id: expected one per row of X \(40,\), got shape \(5,\)"):
        fit_ensemble(X, Y, tiny, segment_id=np.zeros(5, int))
    with pytest.raises(TypeError, match="segment_id: expected whole numbers"):
        fit_ensemble(X, Y, tiny, segment_id=np.full(40, np.nan))
    with pytest.raises(TypeError, match="progress: expected True or False"):
        fit_ensemble(X, Y, tiny, progress="no")      # before: a text "no" showed the bar
    # before: numpy's "could not convert string to float", a net with no input, complex parts dropped
    with pytest.raises(TypeError, match="X: expected an array of real numbers"):
        fit_ensemble([["a"] * 3] * 40, Y, tiny)
    with pytest.raises(ValueError, match=r"n_in, n_out >= 1, got \(40, 0\)"):
        fit_ensemble(X[:, :0], Y, tiny)
    with pytest.raises(TypeError, match="Y: expected an array of real numbers, got dtype complex"):
        fit_ensemble(X, Y + 1j, tiny)
    # before: numpy's broadcast messages, or a 1-D row read as (E, n_out) members' outputs
    for bad in (np.zeros((5, 4)), np.zeros(3), np.zeros((3, 5, 3))):
        with pytest.raises(ValueError, match=r"X: expected shape \(N, 3\) or \(2, N, 3\).*got " + str(bad.shape)
                           .replace("(", r"\(").replace(")", r"\)")):
            ens.predict_members(bad)
    assert ens.predict(X[:4])[0].shape == (4, 2) and ens.predict_members(np.zeros((2, 4, 3))).shape == (2, 4, 2)

def test_guard_is_one_inside_and_shrinks_outside():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(2000, 3))
    g = EnvelopeGuard.fit(X, quantile=0.99)
    assert np.mean(g.weight(X) == 1.0) > 0.98
    w = g.weight(np.array([[0, 0, 0], [10, 0, 0], [30, 0, 0]], float))
    assert w[0] == 1.0 and 0 < w[2] < w[1] < 1.0


def test_guard_of_features_mostly_at_their_mean_is_one_there_not_nan():
    """Training features of which more than the quantile's share lie at their mean give an
    envelope edge d0 = 0 and the default scale d0 / 2 = 0: the weight on the edge was
    exp(-0 / 0) = NaN (and NaN corrections); it is 1 there and 0 beyond, and NaN stays NaN."""
    X = np.zeros((1000, 2))
    X[:4] = [[1.0, 1.0], [-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0]]
    g = EnvelopeGuard.fit(X)
    assert g.d0 == 0.0 and g.scale == 0.0
    np.testing.assert_array_equal(g.weight(np.array([[0.0, 0.0], [0.5, 0.0]])), [1.0, 0.0])
    assert np.isnan(g.weight(np.array([[np.nan, 0.0]]))[0])


@pytest.mark.parametrize("scale", [-1.0, float("nan"), float("inf"), "1", True])
def test_guard_scale_that_is_not_a_finite_number_at_least_0_is_refused_by_name(scale):
    with pytest.raises((TypeError, ValueError), match="EnvelopeGuard.fit: scale"):
        EnvelopeGuard.fit(np.random.default_rng(0).normal(size=(50, 2)), scale=scale)


def test_thrust_regime_switches_the_nets_off_when_thrusters_stop():
    from hybridship.residual.guard import ThrustRegime

    rng = np.random.default_rng(0)
    working = rng.normal([0.02, -0.01, 0.0005], [0.01, 0.01, 0.0003], size=(2000, 3))   # station keeping
    regime = ThrustRegime.fit(working)
    assert np.median(regime.weight(working)) == 1.0            # station keeping: nets fully on
    assert np.mean(regime.weight(working) == 1.0) > 0.98
    assert regime.weight(np.zeros(3)) == 0.0                   # all thrusters stopped: nets off
    # trained on drifting rows as well (zero thrust seen): the nets stay on
    both = ThrustRegime.fit(np.vstack([working, np.zeros((200, 3))]))
    assert both.weight(np.zeros(3)) == 1.0


def test_bias_members_are_centred_on_the_bias_and_reproducible(model, current_logs):
    prep = prepare_log(model, as_log_arrays(current_logs[0], model.vessel))
    i = 850                                                    # DP part, 850 s of history
    m1 = prep.bias_members(i, 10, seed=3)
    m2 = prep.bias_members(i, 10, seed=3)
    np.testing.assert_array_equal(m1, m2)
    np.testing.assert_allclose(m1.mean(axis=0), prep.bias_ned[i], atol=1e-12)
    assert np.all(m1.std(axis=0)[:2] > 0)                      # a spread from the residual blocks
    # ... and the members differ as 60-s means of the causal residuals (turned to north/east by
    # the heading each was seen at) over the 900-s window do: m_k = c + (mean of block k) for
    # one c, each block 60 consecutive usable rows of the window
    a, r = prep.arrays, prep.residual_c
    psi = a.eta[:, 2]
    ned = body_to_ned(r, psi)
    assert np.ptp(psi[: i + 1]) > 0.3                          # the turn to NED matters
    rows = np.arange(max(0, i - 899), i + 1)
    v = ned[rows][np.isfinite(ned[rows]).all(1) & (a.dp_active[rows] == 1)]
    blocks = np.array([v[k:k + 60].mean(axis=0) for k in range(len(v) - 59)])
    fits = [np.abs((m1 - m1[0] + b0)[:, None] - blocks[None]).max(-1).min(-1).max() for b0 in blocks]
    assert min(fits) < 1e-9 * np.abs(blocks).max()


@pytest.mark.slow
def test_guarded_hybrid_beats_physics_after_a_simulated_dp_loss():
    """Trained on the DP part only; first 20 forecasts after the failure, 60 s ahead."""
    from hybridship.evaluation import metrics
    from hybridship.sim.scenario import embedded_scenarios

    scen = embedded_scenarios(2, 0)
    hp = HybridPredictor("gunnerus", ensemble_config=SMALL)
    logs = [as_log_arrays(s.log, hp.model.vessel) for s in scen]
    hp.fit(logs)
    dyn = DynamicPredictor("gunnerus")
    e_h = np.stack([metrics.drift_errors(hp, a) for a in logs])[:, :, -1, :2].mean(axis=(0, 1))
    e_d = np.stack([metrics.drift_errors(dyn, a) for a in logs])[:, :, -1, :2].mean(axis=(0, 1))
    assert np.all(e_h < 0.8 * e_d), (e_h, e_d)
    fc = hp.forecast(logs[0], logs[0].time_s[[metrics.shutdown_index(logs[0]) + 1]], 60)
    assert fc.guard_weight[0, 0] == 0.0                        # thrusters stopped: nets off


def test_known_commands_reproduce_a_log_the_model_made(model, exact_logs):
    """With the logged future commands the physics retraces its own log; held ones do not."""
    from hybridship.residual.features import ResidualConfig

    log = exact_logs[0]
    dyn = DynamicPredictor(model.vessel, residual_config=ResidualConfig(start_average_s=1.0))
    rpm = log.filter(like="_rpm").to_numpy()
    change = np.flatnonzero(np.any(np.diff(rpm[:800], axis=0) != 0, axis=1)) + 1
    change = change[change > 100]
    starts = change[:5]                                       # at a command change; the next one comes
    first_change = change[1:6] - starts                       # 10-40 s later
    truth = log[["north_m", "east_m"]].to_numpy()[starts[:, None] + np.arange(61)]
    known = dyn.forecast(log, starts, 60, commands="known")
    held = dyn.forecast(log, starts, 60, commands="held")
    # 4 RK4 substeps made the log, 1 the forecast: O(dt^4) apart
    assert np.abs(known.eta[..., :2] - truth).max() < 0.01
    assert np.abs(held.eta[:, -1, :2] - truth[:, -1]).max() > 1.0
    # held is known with the start's commands: identical up to the first change
    for k, n in enumerate(first_change):
        np.testing.assert_allclose(known.eta[k, :n + 1], held.eta[k, :n + 1], atol=1e-12)
        assert np.abs(known.eta[k, n + 2] - held.eta[k, n + 2]).max() > 0


def test_a_start_whose_commands_were_clipped_says_so_in_its_note(model, exact_logs):
    """A start whose held rpm was clipped to max_rpm was flagged input_clipped but its note was
    empty, which the notes reserve for a clean start; the clip checks' note now reaches it."""
    log = exact_logs[0].copy()
    col = f"{model.vessel.thrusters[0].name}_rpm"
    log.loc[log.time_s.between(290, 300), col] = 1.2 * model.vessel.thrusters[0].max_rpm
    fc = DynamicPredictor(model.vessel).forecast(log, [300, 200], 10.0)
    np.testing.assert_array_equal(fc.flags["input_clipped"], [True, False])
    assert fc.notes == ("rpm clipped to its valid range", "")


def test_known_commands_need_the_logged_future(model, exact_logs):
    dyn = DynamicPredictor(model.vessel)
    with pytest.raises(ValueError, match="commands='known'.*log ends"):
        dyn.forecast(exact_logs[0], [1180], 60, commands="known")
    with pytest.raises(ValueError, match="commands: expected one of"):
        dyn.forecast(exact_logs[0], [100], 60, commands="future")
    # each step takes the command logged at its beginning: the last of 60 steps from 1140 s
    # takes the one at 1199 s, so a log that ends there serves it, and the message gives the time
    # needed (it said "commands for 60 steps after it", and the docstring asked for 60 s of log)
    end = exact_logs[0].time_s.iloc[-1]
    assert dyn.forecast(exact_logs[0], [end - 59], 60, commands="known").eta.shape == (1, 61, 3)
    with pytest.raises(ValueError, match=rf"start at {end - 58:g} s needs logged commands up to time_s "
                                         rf"{end + 1:g} s \(the command of each of its 60 steps"):
        dyn.forecast(exact_logs[0], [end - 58], 60, commands="known")
    # a dropped command sample holds the last valid one instead of poisoning the forecast
    log = exact_logs[0].copy()
    rpm_cols = log.filter(like="_rpm").columns
    held_value = log.loc[129, rpm_cols].to_numpy()
    log.loc[130:132, rpm_cols] = np.nan
    fc = dyn.forecast(log, [100], 60, commands="known")
    filled = exact_logs[0].copy()
    filled.loc[130:132, rpm_cols] = held_value
    np.testing.assert_allclose(fc.eta, dyn.forecast(filled, [100], 60, commands="known").eta, atol=1e-12)
    assert np.all(exact_logs[0].loc[130:132, rpm_cols].notna().to_numpy())   # the caller's log is untouched


def test_hybrid_guard_sees_known_commands_stop(model, exact_logs):
    """Nets trained in station keeping switch off at the step the known commands stop."""
    hp = HybridPredictor(model.vessel, ensemble_config=SMALL).fit(exact_logs[:2])
    log = exact_logs[2]                                        # thrusters stop at 900 s
    known = hp.forecast(log, [870], 60, commands="known")
    held = hp.forecast(log, [870], 60, commands="held")
    w = known.guard_weight[0]
    assert np.all(w[31:] == 0.0)                               # steps after the stop: nets off
    # before it: on (in part: after a few steps this rollout leaves the core of the two short
    # logs' envelope, where the weight falls to about 0.3, but not to 0 as at the stop)
    assert w[1:30].min() > 0.2 and w[1:6].min() == 1.0
    assert held.guard_weight[0, 31:].mean() > 0.5              # held commands never stop
    assert known.flags["out_of_envelope"][0]


def test_row_stride_trains_on_every_kth_row(model, current_logs):
    cfg = EnsembleConfig(n_members=2, max_epochs=5, patience=5, seed=1)
    full = HybridPredictor(model.vessel, ensemble_config=cfg).fit(current_logs[:1])
    thin = HybridPredictor(model.vessel, ensemble_config=cfg).fit(current_logs[:1], row_stride=3)
    assert thin.training_info["n_rows"] == -(-full.training_info["n_rows"] // 3)
    for bad in (0, 1.5, True):
        with pytest.raises(ValueError, match="row_stride"):
            HybridPredictor(model.vessel, ensemble_config=cfg).fit(current_logs[:1], row_stride=bad)


def test_a_start_window_shorter_than_a_step_uses_the_start_row(model, exact_logs):
    from hybridship.residual.features import ResidualConfig

    log = exact_logs[0]
    fc = DynamicPredictor(model.vessel, residual_config=ResidualConfig(start_average_s=0.1)).forecast(log, [300], 10)
    np.testing.assert_allclose(fc.nu[0, 0], log.loc[300, ["u_m_s", "v_m_s"]].tolist() + [np.radians(log.r_deg_s[300])])


def test_a_diverging_rollout_stops_with_a_clear_error(model, exact_logs):
    """A learned correction that drives the state to non-finite values (here: nets forced to
    answer 1e300) stops the forecast with an error that says so, not deep in the physics."""
    hp = HybridPredictor(model.vessel, ensemble_config=SMALL, calibration_config=CalibrationConfig(fraction=0.0)
                         ).fit(exact_logs[:1])
    E = hp.ensemble.n_members
    hp.ensemble.predict_members = lambda X: np.full((E,) + X.shape[1:-1] + (3,), 1e300)
    with pytest.raises(FloatingPointError, match="diverged at lead"):
        hp.forecast(exact_logs[1], [900.0], 60.0, guard=False, nets_after_stop=True)


def test_heading_quantiles_stay_beside_the_wrapped_heading():
    """A band across north: ``heading_deg`` is wrapped to [0, 360) and its quantiles are
    that heading plus their offsets (358 +- 5 deg reads 353..363, not 353 and 3)."""
    from hybridship.predictors.result import ForecastResult

    eta = np.zeros((1, 2, 3))
    eta[0, :, 2] = np.radians([358.0, -2.0 + 720.0])
    std = np.zeros_like(eta)
    std[..., 2] = np.radians(5.0) / 1.6448536
    fc = ForecastResult(np.array([0.0]), np.array([0.0, 1.0]), eta, np.zeros_like(eta), eta_std=std)
    df = fc.to_frame(quantiles=[0.05, 0.95])
    np.testing.assert_allclose(df.heading_deg, [358.0, 358.0])
    np.testing.assert_allclose(df["heading_q0.05_deg"], [353.0, 353.0], atol=1e-6)
    np.testing.assert_allclose(df["heading_q0.95_deg"], [363.0, 363.0], atol=1e-6)



def test_a_forecast_result_of_mismatched_parts_is_refused_when_made_not_in_to_frame():
    """Before: pandas' "All arrays must be of the same length" from ``to_frame``, a KeyError for a
    missing flag, and an AttributeError for lists."""
    from hybridship.forecast_inputs import FaultFlags
    from hybridship.predictors.result import ForecastResult

    t, lead, eta = np.array([0.0, 10.0]), np.arange(3.0), np.zeros((2, 3, 3))
    with pytest.raises(ValueError, match=r"notes: expected one note per start time \(2\), got 1"):
        ForecastResult(t, lead, eta, eta, notes=("",))
    with pytest.raises(ValueError, match=r"flags: expected one flag per start time \(2,\).*missing \['nan_in_window'"):
        ForecastResult(t, lead, eta, eta, flags={})
    with pytest.raises(ValueError, match=r"eta_std: expected shape \(2, 3, 3\).*got \(2, 3\)"):
        ForecastResult(t, lead, eta, eta, eta_std=np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"nu: expected shape \(2, 3, 3\)"):
        ForecastResult(t, lead, eta, eta[:1])
    flags = {k: np.zeros(2, bool) for k in FaultFlags.ALL}
    fc = ForecastResult(t.tolist(), lead.tolist(), eta.tolist(), eta, flags=flags, notes=["", "x"])
    assert fc.to_frame().shape[0] == 6 and list(fc.to_frame()["notes"][::3]) == ["", "x"]

def test_fit_takes_one_log_or_many_and_start_errors_give_the_log_span(model, exact_logs, tmp_path):
    """One log (a path) is a list of one; something else is refused naming what it got. A
    start time that is not a sample time is reported with the whole log's span, not the
    part read for the forecast."""
    from hybridship.logs.io import write_log
    from hybridship.predictors.forecast_setup import log_list

    path = tmp_path / "one.csv"
    write_log(exact_logs[0], path)
    assert log_list(path) == [path] and log_list(str(path)) == [str(path)]
    assert log_list([path, path]) == [path, path]
    with pytest.raises(TypeError, match="logs: expected a log .* got int"):
        log_list(3)
    t = exact_logs[0].time_s
    with pytest.raises(ValueError, match=rf"log spans {t.iloc[0]}\.\.{t.iloc[-1]} s"):
        DynamicPredictor(model.vessel).forecast(path, [float(t.iloc[0]) + 0.5], 10.0)



def test_a_start_that_is_no_sample_is_a_request_error_despite_a_fault_outside_the_rows_read(model, exact_logs):
    """A format fault far from the start does not matter to a forecast (the rows read are
    fine); a start time that is not a sample time is then still the request's error
    (RequestError, a usage error on the command line), not the distant row's."""
    from hybridship.predictors.forecast_setup import RequestError

    bad = exact_logs[0].copy()
    bad.loc[len(bad) - 5, "wind_speed_m_s"] = -3.0          # refused by the format check, 1000 s later
    dyn = DynamicPredictor(model.vessel)
    assert np.isfinite(dyn.forecast(bad, [100.0], 30.0).eta).all()
    with pytest.raises(RequestError, match="100.5 s is not a sample time"):
        dyn.forecast(bad, [100.5], 30.0)

def test_drift_errors_read_a_path_or_dataframe_and_coverage_refuses_mismatched_inputs(tmp_path):
    from hybridship.evaluation import metrics
    from hybridship.logs.io import write_log
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import DynamicPredictor
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    log = physics_log(model, duration_s=400.0, t_shutdown_s=200.0, seed=2)
    write_log(log, tmp_path / "log.csv")
    p = DynamicPredictor("gunnerus")
    from_frame = metrics.drift_errors(p, log, n_intervals=3)
    np.testing.assert_array_equal(metrics.drift_errors(p, tmp_path / "log.csv", n_intervals=3), from_frame)
    a = np.zeros((2, 4, 3))
    with pytest.raises(ValueError, match="pred, truth, std: expected equal shapes"):
        metrics.coverage(a, a[:1], np.ones((2, 4, 3)))
    with pytest.raises(ValueError, match="std: expected finite, non-negative"):
        metrics.coverage(a, a, np.full((2, 4, 3), np.nan))
    with pytest.raises(ValueError, match="sigmas: expected positive"):
        metrics.coverage(a, a, np.ones((2, 4, 3)), sigmas=(-1.0,))
    nan_pred = a.copy()
    nan_pred[0, 1, 0] = np.nan
    with pytest.raises(ValueError, match="^pred: NaN or inf"):          # not counted as a miss
        metrics.coverage(nan_pred, a, np.ones((2, 4, 3)))
    g = np.zeros((2, 2, 1, 3))
    for args, kw, field in (((nan_pred[:, :, None], a[:, :, None], np.ones((2, 4, 1, 3))), {}, "pred"),
                            ((g, g, -np.ones_like(g)), {}, "std"), ((g, g, np.ones_like(g)), {"sigma": -2.0}, "sigma"),
                            ((g, g, np.ones((1, 3))), {}, "pred, truth, std")):
        with pytest.raises(ValueError, match=f"^{field}"):
            metrics.coverage_interval(*args, **kw)
    with pytest.raises(ValueError, match="windows: 20 intervals asked, but errors\\['m'\\] has 3"):
        metrics.error_table({"m": [from_frame]})
    with pytest.raises(ValueError, match="NaN or inf errors"):
        metrics.error_table({"m": [np.full_like(from_frame, np.nan)]}, windows=(1, 3))


def test_a_start_at_a_time_logged_twice_with_different_values_says_so(model, exact_logs):
    """Both samples of a conflicting duplicate are dropped for a forecast; a start at that time
    was reported as "not a sample time of the log (log spans ...)", although it is one."""
    import pandas as pd

    log = exact_logs[0].reset_index(drop=True)
    k = len(log) // 2
    extra = log.iloc[[k]].copy()
    extra["north_m"] += 3.0
    df = pd.concat([log.iloc[: k + 1], extra, log.iloc[k + 1:]]).reset_index(drop=True)
    t = float(log.time_s.iloc[k])
    with pytest.raises(ValueError, match=rf"start_times_s: {t:g} s is logged more than once with different values"):
        DynamicPredictor(model.vessel).forecast(df, [t], 10.0)
    DynamicPredictor(model.vessel).forecast(df, [float(log.time_s.iloc[k + 5])], 10.0)    # other starts are fine


def test_a_start_value_out_of_range_is_named_by_its_start_time(model, exact_logs):
    """A start state beyond the physics' envelope comes from the log: the error names the start
    time and the column, not the batch element of the integrator's input array."""
    from hybridship.forecast_inputs import InputRangeError

    log = exact_logs[0].reset_index(drop=True)
    starts = [float(log.time_s.iloc[len(log) // 2 + j]) for j in (0, 5)]
    df = log.copy()
    df.loc[df.time_s > starts[0], "north_m"] = 1e9      # a unit error after the first start
    with pytest.raises(InputRangeError, match=rf"^log: start time_s {starts[1]:g}: eta\[north_m\]: 1e\+09 is outside"):
        DynamicPredictor(model.vessel).forecast(df, starts, 10.0)


def test_heading_coverage_counts_the_wrapped_heading_error_against_its_own_spread():
    from hybridship.evaluation import metrics

    truth = np.zeros((2, 1, 4, 3))
    truth[..., 2] = np.pi - 0.01                       # just short of +-180 deg
    pred = truth.copy()
    pred[0, ..., 2] = -np.pi + 0.01                    # 0.02 rad away across the wrap, not 2 pi - 0.02
    pred[1, ..., 2] = truth[1, ..., 2] - 0.5
    pred[..., :2] = 100.0                              # position far outside its band: not counted here
    std = np.full_like(truth, 0.1)
    cov = metrics.coverage(pred, truth, std, state="heading")
    np.testing.assert_allclose(cov, 0.5)               # one of two inside at 1 and at 2 sigma
    np.testing.assert_allclose(metrics.coverage(pred, truth, std), 0.0)
    ci = metrics.coverage_interval(pred, truth, std, 2.0, state="heading", n_resamples=200)
    np.testing.assert_allclose(ci[:, 0], 0.5)
    with pytest.raises(ValueError, match="state: expected one of"):
        metrics.coverage(pred, truth, std, state="yaw")
    bad = std.copy()
    bad[0, 0, 0, 2] = np.nan
    with pytest.raises(ValueError, match="heading standard deviations"):
        metrics.coverage(pred, truth, bad, state="heading")


def test_mean_environment_spread_does_not_depend_on_the_other_starts(model):
    """With environment 'mean' the members' biases are drawn per start: a start's spread is
    the same alone and in a batch whose earliest start moves the window of log read."""
    tiny = EnsembleConfig(n_members=3, hidden=8, max_epochs=15, patience=5, seed=0)
    train = physics_log(model, seed=2, duration_s=400.0, t_shutdown_s=None, current=(0.2, 1.0))
    long = physics_log(model, seed=7, duration_s=2500.0, t_shutdown_s=None, current=(0.2, 1.0))
    hp = HybridPredictor(model.vessel, ensemble_config=tiny, environment="mean").fit([train])
    both = hp.forecast(long, [300.0, 2400.0], 30.0, calibrated=False)
    alone = hp.forecast(long, [2400.0], 30.0, calibrated=False)
    np.testing.assert_allclose(both.eta[1, :, :2], alone.eta[0, :, :2], rtol=0, atol=1e-9)
    # the heading is unwrapped from the first row read, so it may differ by whole turns
    np.testing.assert_allclose(wrap_pi(both.eta[1, :, 2] - alone.eta[0, :, 2]), 0.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(both.eta_std[1], alone.eta_std[0], rtol=0, atol=1e-12)


def test_estimator_forecast_does_not_depend_on_the_other_starts_or_the_log_read_before(model):
    """With the environment estimator (the default) a start's forecast, mean and spread, is
    the same alone, in a batch whose earliest start lies far earlier, and on the log cut to
    begin where its filter starts: that row is fixed by its own start time (the last
    multiple of 300 s at least one window before it)."""
    tiny = EnsembleConfig(n_members=3, hidden=8, max_epochs=15, patience=5, seed=0)
    train = physics_log(model, seed=2, duration_s=1200.0, t_shutdown_s=900.0, current=(0.2, 1.0))
    long = physics_log(model, seed=7, duration_s=1400.0, t_shutdown_s=1300.0, current=(0.2, 1.0),
                       tau_ext_N=(2e3, -1e3, 5e3))
    hp = HybridPredictor(model.vessel, ensemble_config=tiny, environment_window_s=600.0).fit([train])
    starts = [500.0, 1199.0, 1200.0, 1310.0]        # filters from 0, 300, 600 and 600 s
    both = hp.forecast(long, starts, 30.0)
    for k, t in enumerate(starts):
        cut = long[long["time_s"] >= ((t - 600.0) // 300.0) * 300.0].reset_index(drop=True)
        for log in (long, cut):
            alone = hp.forecast(log, [t], 30.0)
            np.testing.assert_allclose(both.eta[k, :, :2], alone.eta[0, :, :2], rtol=0, atol=1e-9)
            np.testing.assert_allclose(wrap_pi(both.eta[k, :, 2] - alone.eta[0, :, 2]), 0.0, rtol=0, atol=1e-9)
            np.testing.assert_allclose(both.eta_std[k], alone.eta_std[0], rtol=1e-9, atol=1e-12)
    # the filter's start is the start's: the log from after it changes the forecast
    late = long[long["time_s"] >= 650.0].reset_index(drop=True)
    assert not np.allclose(hp.forecast(late, [1310.0], 30.0).eta, both.eta[3:], rtol=0, atol=1e-9)


def test_training_features_that_are_all_constant_are_named(model):
    """A feature set that does not vary in the training rows (the azimuths never turned)
    is refused by name, not with a singular-matrix error from the guard."""
    tiny = EnsembleConfig(n_members=2, hidden=8, max_epochs=15, patience=5, seed=0)
    log = physics_log(model, seed=2, duration_s=400.0, t_shutdown_s=None)
    log["port_azimuth_deg"] = 30.0
    log["stbd_azimuth_deg"] = 30.0
    hp = HybridPredictor(model.vessel, ensemble_config=tiny, residual_config={"features": ("angle_main_rad",)})
    with pytest.raises(ValueError, match=r"features: .*angle_main_rad.* constant"):
        hp.fit([log])


def test_a_fast_log_is_fitted_on_rows_about_one_second_apart():
    """A residual is a velocity difference over one step divided by the step, so the noise
    of a 10-Hz log's velocities reaches the targets ten times larger than at 1 Hz; the nets
    of the paper's features (which hold the previous residual) then learned it and made
    station-keeping forecasts worse than the nets off. The one-step fit reads every 10th row
    (``ResidualConfig.residual_step_s`` = 1 s): targets as quiet as at 1 Hz; a 1-Hz log and
    ``residual_step_s=None`` keep every row."""
    from hybridship.physics.model import DynamicModel
    from hybridship.residual.features import ResidualConfig

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=400.0, dt_s=0.1, t_shutdown_s=None, current=(0.2, 1.0))
    rng = np.random.default_rng(0)
    for col, sd in (("u_m_s", 0.01), ("v_m_s", 0.01)):
        log[col] = log[col] + rng.normal(0.0, sd, len(log))          # a speed log's noise
    assert ResidualConfig().thinning(0.1) == 10 and ResidualConfig().thinning(1.0) == 1
    assert ResidualConfig().thinning(2.5) == 1 and ResidualConfig(residual_step_s=None).thinning(0.1) == 1
    rows, std = {}, {}
    for step in (1.0, None):
        hp = HybridPredictor(m.vessel, environment="mean", residual_config=ResidualConfig(residual_step_s=step))
        X, Y, _ = hp.training_data([log])
        rows[step], std[step] = X.shape[0], Y[:, :2].std()
    assert rows[None] > 9 * rows[1.0] > 9 * 300
    assert std[None] > 5 * std[1.0]                  # the noise / dt of 0.1-s differences, not 1-s ones


def test_a_thinned_log_takes_the_environment_at_the_velocities_of_its_residuals():
    """With the estimator, a deviation is the residual less the environment's acceleration at
    the row; the residual is taken at the smoothed velocities (deriv_window_s), and so was the
    environment on a log read row by row, but a thinned log's took the logged (noisy) ones."""
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors.forecast_setup import as_log_arrays
    from hybridship.residual.environment import EnvironmentEstimate, EnvironmentEstimator, environment_accel

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=5, duration_s=300.0, dt_s=0.1, t_shutdown_s=None, current=(0.5, 1.0))
    rng = np.random.default_rng(0)
    for col in ("u_m_s", "v_m_s"):
        log[col] = log[col] + rng.normal(0.0, 0.02, len(log))          # a speed log's noise
    hp = HybridPredictor(m.vessel, residual_config=ResidualConfig(deriv_window_s=2.0))
    hp.estimator = EnvironmentEstimator(hp.model, hp.environment_config)
    prep, every = hp._training_prep(log)
    assert every == 10
    full = as_log_arrays(log, m.vessel)
    est = hp.estimator.run(full)
    thinned = full.rows(slice(None, None, every))
    on = est.take(np.flatnonzero(est.rows % every == 0))          # the estimates at the rows read, renumbered
    on = EnvironmentEstimate(on.rows // every, on.time_s, on.x, on.P, on.thrust_error_model, on.load_map)
    want = environment_accel(m, thinned, on, prep.nu_s)
    logged = environment_accel(m, full, est)[::every]
    ok = np.isfinite(want).all(1)
    assert ok.sum() > 250 and np.abs(logged[ok] - want[ok]).max() > 1e-5      # the two can be told apart
    np.testing.assert_allclose(prep.env_body[ok], want[ok], rtol=1e-12, atol=1e-15)


def test_training_data_takes_one_log_as_a_list_of_one():
    """One DataFrame was iterated as its column names ("time_s: unsupported file extension")."""
    from hybridship.physics.model import DynamicModel

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=200.0, t_shutdown_s=None, current=(0.2, 1.0))
    hp = HybridPredictor(m.vessel, environment="mean")
    for one, listed in zip(hp.training_data(log), hp.training_data([log])):
        np.testing.assert_array_equal(one, listed)


def test_training_data_before_fit_with_the_estimator_says_to_fit_first():
    """With environment='estimator' the targets come from the fitted estimator; before fit
    the call failed in Python's words ("'NoneType' object has no attribute 'run'")."""
    from hybridship.physics.model import DynamicModel

    m = DynamicModel("gunnerus")
    log = physics_log(m, seed=3, duration_s=200.0, t_shutdown_s=None, current=(0.2, 1.0))
    with pytest.raises(RuntimeError, match=r"training_data: .*call fit\(\) or load\(\) first"):
        HybridPredictor(m.vessel).training_data([log])


def test_rollout_without_nets_on_an_unfitted_hybrid_needs_the_guard_off():
    """nets=False needs no ensemble, but the guard (on by default) reads the fitted envelope:
    an unfitted hybrid's rollout failed in Python's words ("'NoneType' object has no
    attribute 'x_mean'"); it now says to fit first, and with guard=False it runs."""
    hp = HybridPredictor("gunnerus")
    z, K = np.zeros((2, 3)), hp.model.n_channels
    held = dict(rpm=np.zeros((2, 1, K)), az=np.zeros((2, 1, K)), wind=np.zeros((2, 1, 2)))
    with pytest.raises(RuntimeError, match=r"^HybridPredictor: not fitted; call fit\(\) or load\(\) first$"):
        hp.rollout(z, z, z, z, n_steps=5, dt_s=1.0, nets=False, **held)
    eta, _, _, wgt = hp.rollout(z, z, z, z, n_steps=5, dt_s=1.0, guard=False, nets=False, **held)
    assert eta.shape == (2, 6, 3) and wgt is None


def test_rollout_refuses_held_rpm_with_angles_per_step():
    """Commands are held or per step together: with the rpm held, angles given per step were
    held at their first step without a word (the same rollout as angles held)."""
    hp = HybridPredictor("gunnerus")
    z, K = np.zeros((1, 3)), hp.model.n_channels
    rpm, wind = np.full((1, 1, K), 50.0), np.zeros((1, 1, 2))
    az = np.zeros((1, 5, K))
    az[:, 1:] = 1.5
    with pytest.raises(ValueError, match=r"^rpm, az: commands are both held .* got rpm held and az of 5 steps"):
        hp.rollout(z, z + [1.0, 0, 0], z, z, rpm, az, wind, 5, 1.0, guard=False, nets=False)
    both = hp.rollout(z, z + [1.0, 0, 0], z, z, np.repeat(rpm, 5, axis=1), az, wind, 5, 1.0, guard=False, nets=False)
    held = hp.rollout(z, z + [1.0, 0, 0], z, z, rpm, az[:, :1], wind, 5, 1.0, guard=False, nets=False)
    assert not np.allclose(both[0], held[0])


def test_rollout_refuses_a_current_per_step():
    """The rollout holds the current (S, 1, 2): one given per step was accepted and its first
    step held over the whole rollout without a word."""
    hp = HybridPredictor("gunnerus")
    z, K = np.zeros((1, 3)), hp.model.n_channels
    held = dict(rpm=np.zeros((1, 1, K)), az=np.zeros((1, 1, K)), wind=np.zeros((1, 1, 2)))
    current = np.zeros((1, 5, 2))
    current[:, 2:, 0] = 1.0
    with pytest.raises(ValueError, match=r"^current: expected a held current, shape \(1, 1, 2\), got \(1, 5, 2\)"):
        hp.rollout(z, z, z, z, n_steps=5, dt_s=1.0, guard=False, nets=False, current=current, **held)
    eta, _, _, _ = hp.rollout(z, z, z, z, n_steps=5, dt_s=1.0, guard=False, nets=False, current=current[:, 2:3],
                              **held)
    assert np.abs(eta[0, -1, :2]).max() > 0.01         # a held current of 1 m/s starts to carry the ship


def test_rollout_names_per_start_extras_of_another_length():
    """nets_weight, drift_yaw_uv and wave_axis hold one value (row) per start: another length
    failed in numpy's words ("operands could not be broadcast together"), naming none, and
    one value for two starts was spread over both without a word."""
    hp = HybridPredictor("gunnerus")
    z, K = np.zeros((2, 3)), hp.model.n_channels
    held = dict(rpm=np.zeros((2, 1, K)), az=np.zeros((2, 1, K)), wind=np.zeros((2, 1, 2)))
    for kw, match in ((dict(nets_weight=[1.0, 1.0, 1.0]), r"^nets_weight: expected shape \(2,\), one per start, got "
                                                         r"\(3,\)"),
                      (dict(nets_weight=[1.0]), r"^nets_weight: expected shape \(2,\)"),
                      (dict(drift_yaw_uv=[0.1, 0.1, 0.1]), r"^drift_yaw_uv: expected shape \(2,\)"),
                      (dict(drift_yaw_uv=[0.1, np.nan]), r"^drift_yaw_uv: contains NaN"),
                      (dict(wave_axis=np.zeros((3, 2))), r"^wave_axis: expected shape \(2, 2\)"),
                      (dict(nets_weight=["a", "b"]), r"^nets_weight: expected an array of real numbers")):
        with pytest.raises((TypeError, ValueError), match=match):
            hp.rollout(z, z, z, z, n_steps=3, dt_s=1.0, guard=False, nets=False, **held, **kw)
    eta, _, _, _ = hp.rollout(z, z, z, z, n_steps=3, dt_s=1.0, guard=False, nets=False, **held,
                              nets_weight=[0.0, 1.0], drift_yaw_uv=[0.0, 0.0], wave_axis=np.full((2, 2), np.nan))
    assert eta.shape == (2, 4, 3)


def test_calibrate_after_stop_names_the_log_without_a_failure(model, exact_logs, tmp_path):
    """Among several logs, one without a failure (or with too short a drift) was refused as
    "log: no DP shutdown", which did not say which; the log is now named (its path, else
    its place logs[i]), and a lone log is still "log"."""
    hp = HybridPredictor(model.vessel, ensemble_config=EnsembleConfig(n_members=2, hidden=8, max_epochs=3,
                                                                      patience=2, seed=0)).fit(exact_logs[:1])
    fail, calm = exact_logs[1], exact_logs[2].assign(dp_active=1)
    with pytest.raises(ValueError, match=r"^logs\[1\]: no DP shutdown \(dp_active never 0\)"):
        hp.calibrate_after_stop([fail, calm], horizon_s=20.0)
    calm.to_csv(tmp_path / "calm.csv", index=False)
    with pytest.raises(ValueError, match=r"calm\.csv: no DP shutdown"):
        hp.after_stop_errors([fail, tmp_path / "calm.csv"], horizon_s=20.0)
    short = fail[fail.time_s < 910].reset_index(drop=True)
    with pytest.raises(ValueError, match=r"^logs\[0\]: only 0 start times after the shutdown"):
        hp.after_stop_errors([short, fail], horizon_s=20.0)
    with pytest.raises(ValueError, match=r"^log: no DP shutdown"):
        hp.after_stop_errors([calm], horizon_s=20.0)
    assert len(hp.after_stop_errors([fail, fail], horizon_s=20.0)) == 2


def test_drift_hull_objective_names_the_log_without_a_drift(model, exact_logs):
    """drift_hull_objective refused a log without a failure as "logs: a log without a failure
    followed by ... of drift", which did not say which of the logs; it is now named."""
    hp = HybridPredictor(model.vessel, ensemble_config=EnsembleConfig(n_members=2, hidden=8, max_epochs=3,
                                                                      patience=2, seed=0)).fit(exact_logs[:1])
    calm = exact_logs[2].assign(dp_active=1)
    with pytest.raises(ValueError, match=r"^logs\[1\]: no failure followed by 20 s of drift in one gap-free segment"):
        hp.drift_hull_objective([exact_logs[1], calm], horizon_s=20.0)
    with pytest.raises(ValueError, match=r"^log: no failure followed by 20 s of drift"):
        hp.drift_hull_objective(calm, horizon_s=20.0)


def test_residual_is_the_unknown_load_over_the_mass(model):
    """On a log with a constant body-frame load the model does not know, the residual target
    (and its causal twin) is that load's acceleration ``M^-1 tau`` [m/s^2], with its sign."""
    tau = np.array([2.0e4, -1.0e4, 0.0])
    log = physics_log(model, seed=4, duration_s=200.0, t_shutdown_s=None, tau_ext_N=tuple(tau))
    prep = prepare_log(model, as_log_arrays(log, model.vessel), ResidualConfig(bias_window_s=0.0))
    rows = prep.trainable_rows()
    want = model.arrays.m_inv @ tau
    assert np.abs(want[:2]).min() > 1e-3
    for res in (prep.residual[rows], prep.residual_c[rows]):
        np.testing.assert_allclose(np.median(res, axis=0)[:2], want[:2], rtol=0.1)


def test_previous_residual_feature_is_the_deviation_one_row_earlier(model):
    """The autoregressive features of row i are the residual deviation of row i - 1 (the
    residual minus the bias known before it), never row i's own (its target)."""
    log = physics_log(model, seed=2, duration_s=300.0, t_shutdown_s=None, current=(0.3, 1.0))
    prep = prepare_log(model, as_log_arrays(log, model.vessel), ResidualConfig(bias_window_s=60.0))
    rows = prep.trainable_rows()[5:40]
    X = prep.features(rows)
    want = prep.residual[rows - 1] - prep.bias_body(rows - 2, prep.arrays.eta[rows - 1, 2])
    np.testing.assert_allclose(X[:, 6:9], want, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(X[:, 0:3], prep.nu_hat[rows])


def test_a_masked_row_removes_the_row_after_it_from_training(model):
    """A row outside the mask cannot be a target nor supply the previous residual of the next."""
    log = physics_log(model, seed=2, duration_s=100.0, t_shutdown_s=None)
    prep = prepare_log(model, as_log_arrays(log, model.vessel), ResidualConfig(bias_window_s=0.0))
    mask = np.ones(len(log), bool)
    mask[50] = False
    rows = prep.trainable_rows(mask)
    assert 50 not in rows and 51 not in rows and 49 in rows and 52 in rows


def test_ensemble_inference_is_the_standardised_mlp_and_its_mean_and_spread():
    """predict_members is tanh(tanh(z W1 + b1) W2 + b2) W3 + b3 on standardised inputs,
    de-standardised; predict gives the members' mean and population std (ddof 0)."""
    rng = np.random.default_rng(0)
    E, n_in, H, n_out = 3, 2, 4, 3
    shapes = [(E, n_in, H), (E, 1, H), (E, H, H), (E, 1, H), (E, H, n_out), (E, 1, n_out)]
    w = [rng.normal(size=sh) for sh in shapes]
    ens = MLPEnsemble(w, np.array([1.0, -2.0]), np.array([2.0, 0.5]), np.array([10.0, -5.0, 3.0]),
                      np.array([0.1, 2.0, 4.0]))
    X = rng.normal(size=(7, n_in))
    Y = ens.predict_members(X)
    for e in range(E):
        z = (X - [1.0, -2.0]) / [2.0, 0.5]
        h = np.tanh(np.tanh(z @ w[0][e] + w[1][e]) @ w[2][e] + w[3][e])
        np.testing.assert_allclose(Y[e], (h @ w[4][e] + w[5][e]) * [0.1, 2.0, 4.0] + [10.0, -5.0, 3.0])
    mean, std = ens.predict(X)
    np.testing.assert_allclose(mean, Y.mean(axis=0))
    np.testing.assert_allclose(std, Y.std(axis=0, ddof=0))


def _split_data(n=100):
    rng = np.random.default_rng(5)
    X = rng.normal(size=(n, 2))
    X[80:] += 3.0                                  # the validation part (last 20 %) lies elsewhere
    Y = np.column_stack([np.sin(X[:, 0]), X[:, 1] ** 2])
    return X, Y


def test_ensemble_is_standardised_on_training_rows_and_keeps_its_best_validation_weights():
    """The normalisation comes from the training rows only (the first 80 % in time, not the
    validation tail); the weights returned are those of the best validation epoch: their
    validation MSE is the recorded best."""
    X, Y = _split_data()
    cfg = EnsembleConfig(n_members=1, hidden=6, max_epochs=200, patience=10, lr=5e-2, bootstrap=False, seed=2)
    ens = fit_ensemble(X, Y, cfg)
    np.testing.assert_allclose(ens.x_mean, X[:80].mean(0))
    np.testing.assert_allclose(ens.y_std, Y[:80].std(0))
    assert ens.history["n_train"] == 80 and ens.history["epochs"] < 200   # stopped early
    Zy = (Y[80:] - ens.y_mean) / ens.y_std
    val = np.mean(((ens.predict_members(X[80:])[0] - ens.y_mean) / ens.y_std - Zy) ** 2)
    np.testing.assert_allclose(val, ens.history["best_val_mse"][0], rtol=1e-4)
    assert val == pytest.approx(min(ens.history["val_mse"]), rel=1e-4)


def test_ensemble_fit_is_reproducible_and_the_seed_matters():
    """Same seed, same weights (bootstrap draws and initial weights); another seed, others."""
    X, Y = _split_data()
    cfg = EnsembleConfig(n_members=3, hidden=4, max_epochs=5, patience=5, seed=7)
    a, b = fit_ensemble(X, Y, cfg), fit_ensemble(X, Y, cfg)
    c = fit_ensemble(X, Y, EnsembleConfig(**{**cfg.__dict__, "seed": 8}))
    for wa, wb, wc in zip(a.weights, b.weights, c.weights):
        np.testing.assert_array_equal(wa, wb)
    assert not np.array_equal(a.weights[0], c.weights[0])


def test_guard_decays_by_e_per_half_edge_distance_beyond_the_edge():
    """Beyond the edge d0 the weight is exp(-(d - d0) / s) with s = d0 / 2 by default."""
    rng = np.random.default_rng(1)
    g = EnvelopeGuard.fit(rng.normal(size=(4000, 2)), quantile=0.95)
    assert g.scale == pytest.approx(0.5 * g.d0)
    x = np.zeros((4, 2))
    x[:, 0] = np.array([0.5, 1.0, 1.5, 2.5]) * g.d0
    d = g.distance(x)
    assert d[0] < g.d0 < d[1]
    np.testing.assert_allclose(g.weight(x), np.exp(-np.maximum(d - g.d0, 0) / (0.5 * g.d0)), rtol=1e-12)


def test_thrust_regime_ramps_from_half_the_low_level_to_the_low_level():
    """The weight is 0 at and below lo / 2, 1 at lo and above, linear between."""
    rng = np.random.default_rng(0)
    regime = ThrustRegime.fit(rng.normal([0.02, -0.01, 0.0005], [0.01, 0.01, 0.0003], size=(2000, 3)))
    levels = regime.lo * np.array([0.25, 0.5, 0.75, 1.0, 2.0])
    acc = levels[:, None] * np.array([1.0, 0.0, 0.0]) * regime.scale
    np.testing.assert_allclose(regime.level(acc), levels)
    np.testing.assert_allclose(regime.weight(acc), [0.0, 0.0, 0.5, 1.0, 1.0], atol=1e-12)


def test_command_features_of_a_row_are_those_of_the_step_into_it(model):
    """Row i is predicted from row i - 1 with the commands of i - 1: at the rows after a command
    change the rpm feature is the previous row's and the rate the change over (i - 2, i - 1)."""
    log = physics_log(model, seed=7, duration_s=200.0, t_shutdown_s=None)
    a = as_log_arrays(log, model.vessel)
    prep = prepare_log(model, a, ResidualConfig(features=COMMAND_FEATURES[:2], bias_window_s=0.0))
    changed = np.flatnonzero(np.diff(a.rpm[:, 0]) != 0) + 1       # rpm[k] != rpm[k - 1]
    rows = np.intersect1d(np.r_[changed, changed + 1], prep.trainable_rows())
    assert rows.size > 4
    scale = model.vessel.thrusters[0].max_rpm
    np.testing.assert_allclose(prep.features(rows), np.column_stack(
        [a.rpm[rows - 1, 0] / scale, (a.rpm[rows - 1, 0] - a.rpm[rows - 2, 0]) / (scale * prep.dt_s)]))


def test_bias_is_the_trailing_mean_of_causal_residuals_turned_to_ned(model):
    """bias_ned[i] is the mean over the last bias_window_s of the causal residuals with their
    surge/sway rotated to north/east by the heading at which each was seen."""
    log = physics_log(model, seed=2, duration_s=300.0, t_shutdown_s=None, current=(0.3, 1.0))
    prep = prepare_log(model, as_log_arrays(log, model.vessel), ResidualConfig(bias_window_s=60.0))
    psi, r = prep.arrays.eta[:, 2], prep.residual_c
    assert np.ptp(psi[100:300]) > 0.5                          # the ship turns
    for i in (150, 220, 299):
        k = np.arange(i - 59, i + 1)
        c, s = np.cos(psi[k]), np.sin(psi[k])
        ned = np.column_stack([c * r[k, 0] - s * r[k, 1], s * r[k, 0] + c * r[k, 1], r[k, 2]])
        np.testing.assert_allclose(prep.bias_ned[i], ned.mean(axis=0), rtol=1e-9, atol=1e-15)


def test_a_start_residual_window_is_refused_where_it_would_be_ignored():
    """With the environment estimator every forecast starts its autoregressive input at zero
    (the estimator's state is the start), so a ResidualConfig.start_residual_window_s above 0
    was accepted and silently dropped; it is refused there and used with the mean residual."""
    from hybridship.predictors import HybridPredictor
    from hybridship.residual.features import ResidualConfig

    cfg = ResidualConfig(start_residual_window_s=10.0)
    with pytest.raises(ValueError, match=r"^residual_config.start_residual_window_s: must be 0 with "
                                         r"environment='estimator'"):
        HybridPredictor("gunnerus", residual_config=cfg)
    HybridPredictor("gunnerus", residual_config=cfg, environment="mean")
