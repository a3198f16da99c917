"""Esso Osaka loader and manoeuvre benchmark helpers on synthetic runs (no data needed).

The files here are made in the data set's layout (:data:`~hybridship.datasets.esso_osaka.ESSO_COLUMNS`,
10 Hz); the real runs are tested in ``test_esso_osaka.py`` (skipped without them).
"""

from __future__ import annotations

import os
import re
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from hybridship.datasets.esso_osaka import ESSO_COLUMNS, convention_checks, esso_to_log, list_runs


def _raw(n: int = 300, dt_s: float = 0.1) -> pd.DataFrame:
    """A straight run at 0.3 m/s along x0, heading 0, 10 rps, no rudder, 1 m/s of wind."""
    t = np.arange(n) * dt_s
    raw = pd.DataFrame({c: np.zeros(n) for c in ESSO_COLUMNS})
    raw["t [s]"] = t
    raw["x_position_mid [m]"] = 0.3 * t
    raw["u_velo [m/s]"] = 0.3 + 0.01 * np.sin(t)       # varies, so a shift shows
    raw["n_prop [rps]"] = 10.0
    raw["wind_velo_true [m/s]"] = 1.0
    return raw


# ------------------------------------------------------------------------- esso_to_log


def test_velocity_lead_longer_than_the_run_holds_the_last_value():
    raw = _raw(5)
    log = esso_to_log(raw, velocity_lead_s=1.0)          # 10 steps on a 5-row run
    assert len(log) == 5
    np.testing.assert_allclose(log.u_m_s, raw["u_velo [m/s]"].iloc[-1])
    # shorter leads: the rows k later, the last held (as before)
    log = esso_to_log(_raw(50), velocity_lead_s=0.6)
    u = _raw(50)["u_velo [m/s]"].to_numpy()
    np.testing.assert_allclose(log.u_m_s, np.concatenate([u[6:], np.repeat(u[-1], 6)]))



def test_an_infinite_wind_direction_is_refused_by_the_log_checks_not_taken_as_not_logged():
    """esso_to_log wrapped the wind direction with % 360, which makes inf NaN: a raw run's
    infinite true wind direction became wind not logged at that row (the previous row's wind
    held, with numpy's RuntimeWarning) where an infinite value in any other column is refused."""
    from hybridship.datasets.esso_osaka import esso_log_arrays
    from hybridship.logs.io import LogFormatError

    raw = _raw(50)
    raw.loc[10, "wind_dir_true [rad]"] = np.inf
    assert np.isinf(esso_to_log(raw).wind_dir_deg[10])
    with pytest.raises(LogFormatError, match="^wind_dir_deg: infinite value inf at row 10"):
        esso_log_arrays(raw)
    raw.loc[10, "wind_dir_true [rad]"] = -0.5 * np.pi          # finite directions are wrapped as before
    assert esso_to_log(raw).wind_dir_deg[10] == pytest.approx(270.0)

@pytest.mark.parametrize("lead", [-0.6, float("nan"), float("inf")])
def test_a_velocity_lead_that_is_not_a_finite_non_negative_time_is_refused(lead):
    with pytest.raises(ValueError, match="velocity_lead_s"):
        esso_to_log(_raw(50), velocity_lead_s=lead)


def test_a_one_row_run_with_a_velocity_lead():
    log = esso_to_log(_raw(1), velocity_lead_s=0.6)
    assert len(log) == 1 and log.u_m_s.iloc[0] == pytest.approx(0.3)


def test_esso_log_arrays_read_a_run_from_any_path_object(tmp_path):
    """A path object other than str or pathlib.Path (os.PathLike, e.g. pytest's py.path) was
    refused as 'run: expected a path, EssoRun or DataFrame'."""
    from hybridship.datasets.esso_osaka import esso_log_arrays

    class _Path(os.PathLike):
        def __init__(self, p):
            self.p = p

        def __fspath__(self):
            return str(self.p)

    path = tmp_path / "random_01-Jan-2020_00_00_00.csv"
    _raw(100).to_csv(path, index=False)
    got, want = esso_log_arrays(_Path(path)), esso_log_arrays(path)
    np.testing.assert_array_equal(got.eta, want.eta)
    np.testing.assert_array_equal(got.rpm, want.rpm)
    np.testing.assert_array_equal(got.time_s, np.arange(100) * 0.1)


@pytest.mark.parametrize("lead", [0.6, -5.0])
def test_esso_log_arrays_refuse_a_velocity_lead_for_a_converted_log(lead):
    """A log DataFrame is already converted: the lead was ignored without a word (the same
    arrays with 0.6 s as without, and -5 s accepted), while a raw run of the same data is
    shifted by it."""
    from hybridship.datasets.esso_osaka import esso_log_arrays

    raw = _raw(50)
    log = esso_to_log(raw)
    with pytest.raises(ValueError, match="^velocity_lead_s: "):
        esso_log_arrays(log, velocity_lead_s=lead)
    np.testing.assert_array_equal(esso_log_arrays(log, velocity_lead_s=0.0).nu, esso_log_arrays(raw).nu)
    assert not np.array_equal(esso_log_arrays(raw, velocity_lead_s=0.6).nu, esso_log_arrays(raw).nu)



@pytest.mark.parametrize("column", ["wind_dir_true [rad]", "wind_velo_relative_mid [m/s]"])
def test_an_infinite_value_in_a_run_is_refused_naming_its_column_and_row(tmp_path, column):
    """An 'inf' passed read_esso_raw (only NaN was looked for): in the true wind direction it
    became a NaN wind_dir_deg (inf % 360), which the log took as not logged, and the run was
    read without a word; in the apparent wind it made convention_checks' rms NaN."""
    from hybridship.datasets.esso_osaka import read_esso_osaka, read_esso_raw
    from hybridship.logs.io import LogFormatError

    raw = _raw(50).astype({column: object})
    raw.loc[10, column] = "inf"
    path = tmp_path / "berthing_inf.csv"
    raw.to_csv(path, index=False)
    msg = rf"^{re.escape(column)}: missing, non-numeric or infinite value at row 10 \(file line 12, t = 1 s"
    with pytest.raises(LogFormatError, match=msg):
        read_esso_raw(path)
    with pytest.raises(LogFormatError, match=msg):
        read_esso_osaka(path)


def test_a_row_of_text_is_refused_and_a_row_of_blanks_dropped(tmp_path):
    """Only empty rows are dropped: a row whose every field is text (a second header line of two
    files joined) was read as all NaN and dropped as empty, leaving a gap without a word."""
    from hybridship.datasets.esso_osaka import read_esso_raw
    from hybridship.logs.io import LogFormatError

    lines = _raw(50).to_csv(index=False).splitlines()
    path = tmp_path / "berthing_text.csv"
    path.write_text("\n".join(lines[:11] + [lines[0]] + lines[11:]) + "\n")
    with pytest.raises(LogFormatError, match=r"^t \[s\]: missing, non-numeric or infinite value at row 10 "
                                             r"\(file line 12;"):
        read_esso_raw(path)
    path.write_text("\n".join(lines[:11] + [",".join([" "] * len(ESSO_COLUMNS))] + lines[11:]) + "\n")
    pd.testing.assert_frame_equal(read_esso_raw(path), _raw(50))

# ------------------------------------------------------------------------- convention_checks


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")     # no yaw: its correlations are NaN
def test_convention_checks_take_a_negative_lag():
    """A lag scan on both sides of zero: a negative lag compares with earlier velocities
    (it failed with an IndexError); positive lags give what they gave."""
    raw = _raw(600)
    neg = convention_checks(raw, lag_s=-0.6)
    assert all(np.isfinite(v) for k, v in neg.items() if k.startswith("rms_"))
    pos = convention_checks(raw, lag_s=0.6)
    # the same rows as before the change: i in [k, n - k - lag)
    t = raw["t [s]"].to_numpy()
    x = raw["x_position_mid [m]"].to_numpy()
    u = raw["u_velo [m/s]"].to_numpy()
    i = np.arange(5, 600 - 5 - 6)
    xd = (x[i + 5] - x[i - 5]) / (t[i + 5] - t[i - 5])
    assert pos["rms_north_m_s"] == pytest.approx(np.sqrt(np.mean((xd - u[i + 6]) ** 2)), rel=1e-12)
    # the negative lag by hand: rows i in [k + lag, n - k), each against u 6 rows earlier (a lag
    # read as its size, or as no lag, gives another value: u varies)
    i = np.arange(5 + 6, 600 - 5)
    xd = (x[i + 5] - x[i - 5]) / (t[i + 5] - t[i - 5])
    assert neg["rms_north_m_s"] == pytest.approx(np.sqrt(np.mean((xd - u[i - 6]) ** 2)), rel=1e-12)
    assert neg["rms_north_m_s"] != pytest.approx(pos["rms_north_m_s"], rel=1e-3)


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")     # no yaw: its correlations are NaN
@pytest.mark.parametrize("kwargs, field", [({"diff_s": -1.0}, "diff_s"), ({"diff_s": 0.0}, "diff_s"),
                                           ({"lag_s": float("nan")}, "lag_s"), ({"diff_s": 60.0}, "raw"),
                                           ({"lag_s": -30.0}, "raw")])
def test_convention_checks_refuse_a_difference_or_lag_they_cannot_take_by_name(kwargs, field):
    """A negative or zero ``diff_s`` was read as one step, a NaN ``lag_s`` was numpy's 'cannot
    convert float NaN to integer', and a difference or lag longer than the run gave NaN for
    every rms with numpy's warnings about empty slices."""
    with pytest.raises(ValueError, match=rf"^{field}\b"):
        convention_checks(_raw(300), **kwargs)
    with pytest.raises(ValueError, match=r"^raw: 1 row"):
        convention_checks(_raw(1))
    # the shortest run that holds one difference: 2 k + lag + 1 rows (k = 5, lag = 6)
    c = convention_checks(_raw(17), lag_s=0.6)
    assert c["rms_north_m_s"] == pytest.approx(abs(0.3 - 0.3 - 0.01 * np.sin(1.1)), rel=1e-9)


# ------------------------------------------------------------------------- list_runs


def _write_runs(folder, names):
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        _raw(100).to_csv(folder / name, index=False)


def test_two_files_of_one_run_are_refused(tmp_path):
    """A run decompressed beside its .csv.gz (or copied to a second folder) would be
    counted twice: twice the weight in training, its starts twice in the test tables."""
    _write_runs(tmp_path / "zigzag", ["zigzag_a.csv", "zigzag_b.csv"])
    _raw(100).to_csv(tmp_path / "zigzag" / "zigzag_a.csv.gz", index=False)
    with pytest.raises(ValueError, match=r"zigzag_a.*two files"):
        list_runs(tmp_path)
    os.remove(tmp_path / "zigzag" / "zigzag_a.csv.gz")
    assert [r.name for r in list_runs(tmp_path)] == ["zigzag_a", "zigzag_b"]


def test_list_runs_refuses_an_include_duplicates_flag_that_is_not_true_or_false(tmp_path):
    """``include_duplicates="no"`` is truthy: the cut copy of a run present in full was listed
    as a run of its own (counted twice) without a word."""
    _write_runs(tmp_path / "turning", ["turn_14-Sep-2020_15_58_08.csv", "turn_cut_14-Sep-2020_15_58_08.csv"])
    assert [r.name for r in list_runs(tmp_path)] == ["turn_14-Sep-2020_15_58_08"]
    for flag in ("no", "False", 0):
        with pytest.raises(TypeError, match=r"^include_duplicates: expected True or False"):
            list_runs(tmp_path, include_duplicates=flag)
    assert len(list_runs(tmp_path, include_duplicates=True)) == 2


# ------------------------------------------------------------------------- split_runs


def _runs_folder(tmp_path):
    data = tmp_path / "data"
    _write_runs(data / "zigzag", [f"zigzag_31-Jul-2020_13_0{i}_00.csv" for i in range(4)])
    _write_runs(data / "turning", [f"turn_14-Sep-2020_15_0{i}_00.csv" for i in range(3)])
    return data


@pytest.mark.parametrize("fraction", [1.5, 1.0, 0.0, -0.2, float("nan")])
def test_split_refuses_a_test_fraction_outside_0_1(tmp_path, fraction):
    from hybridship.evaluation.manoeuvre import split_runs

    data = _runs_folder(tmp_path)
    with pytest.raises(ValueError, match="test_fraction"):
        split_runs(data, tmp_path / "split", test_fraction=fraction)
    assert not (tmp_path / "split").exists()


@pytest.mark.parametrize("fraction", ["0.3", True, None])
def test_split_refuses_a_test_fraction_that_is_not_a_number(tmp_path, fraction):
    """A text share ("0.3") passed the range check through float() and failed in round()'s
    words ("type str doesn't define __round__ method"); True was read as 1."""
    from hybridship.evaluation.manoeuvre import split_runs

    data = _runs_folder(tmp_path)
    with pytest.raises(TypeError, match="^test_fraction: expected a number"):
        split_runs(data, tmp_path / "split", test_fraction=fraction)
    assert not (tmp_path / "split").exists()

def test_split_puts_whole_recordings_per_kind_on_one_side(tmp_path):
    """Per kind, round(0.3 x recordings), at least one, are test runs (zigzag 4 -> 1, turning
    3 -> 1, random 5 -> 2), every run on exactly one side, the pieces of one recording
    together, and the same seed draws the same split. (The other split tests only count the
    links, which a split putting every run in train, or keeping one kind's test runs, passes.)"""
    from hybridship.evaluation.manoeuvre import split_runs

    data = _runs_folder(tmp_path)
    _write_runs(data / "random", [f"random_01-Aug-2020_10_0{i}_00_{p}.csv" for i in range(5) for p in (1, 2)])

    def sides(seed, out):
        train, test = split_runs(data, tmp_path / out, seed=seed)
        return ({p.name.removesuffix(".csv") for p in train.rglob("*.csv")},
                {p.name.removesuffix(".csv") for p in test.rglob("*.csv")})

    train, test = sides(0, "a")
    assert not train & test and len(train | test) == 17
    for kind, n_test in (("zigzag", 1), ("turn", 1), ("random", 2)):
        recs = {n.rsplit("_", 1)[0] if kind == "random" else n for n in test if n.startswith(kind)}
        assert len(recs) == n_test, (kind, sorted(test))
    for n in test | train:                                   # a recording's two pieces on one side
        if n.startswith("random"):
            other = n[:-1] + ("2" if n.endswith("1") else "1")
            assert (n in test) == (other in test)
    assert sides(0, "b") == (train, test)
    assert any(sides(s, f"s{s}")[1] != test for s in range(1, 6))     # the seed draws


def test_split_keeps_the_data_it_splits(tmp_path):
    """An output folder that is, or holds, the data folder is refused before anything is
    removed (validation_split(d, d) replaced the benchmark's links by links to themselves),
    and a file that is not a link is never removed."""
    from hybridship.evaluation.manoeuvre import split_runs, validation_split

    data = _runs_folder(tmp_path)
    train, test = split_runs(data, tmp_path / "bench")
    before = sorted(p.name for p in train.rglob("*.csv"))
    with pytest.raises(ValueError, match="out_dir"):
        validation_split(tmp_path / "bench", tmp_path / "bench")
    assert sorted(p.name for p in train.rglob("*.csv")) == before
    assert all(p.resolve().parent.parent == data.resolve() for p in train.rglob("*.csv"))
    with pytest.raises(ValueError, match="out_dir"):
        split_runs(data, data)                                  # out_dir/train inside the data
    inner = _runs_folder(tmp_path / "x" / "train")              # out_dir/train holds the data
    with pytest.raises(ValueError, match="out_dir"):
        split_runs(inner, tmp_path / "x")
    assert len(list(inner.rglob("*.csv"))) == 7
    # a real file in an output folder is the user's: refused, kept
    (tmp_path / "other" / "train").mkdir(parents=True)
    (tmp_path / "other" / "train" / "mine.csv").write_text("x\n")
    with pytest.raises(FileExistsError, match="mine.csv"):
        split_runs(data, tmp_path / "other")
    assert (tmp_path / "other" / "train" / "mine.csv").read_text() == "x\n"
    # a second split into the same folder replaces its own links
    split_runs(data, tmp_path / "bench", seed=3)
    links = list((tmp_path / "bench").rglob("*.csv"))
    assert len(links) == 7 and all(p.is_symlink() and p.resolve().parent.parent == data.resolve() for p in links)


# ------------------------------------------------------------------------- errors and coverage


def _arrays(n=200, dt=0.1):
    t = np.arange(n) * dt
    eta = np.column_stack([0.3 * t, np.zeros(n), np.zeros(n)])
    return SimpleNamespace(time_s=t, eta=eta, segment_id=np.zeros(n, int))


def _forecaster(nan_start=None, nan_std=False):
    """Perfect forecasts (constant 0.3 m/s north) with a 0.1-m spread; NaN at one start."""
    def forecast(arrays, starts, horizon_s):
        H = int(round(horizon_s / 0.1))
        lead = np.arange(H + 1) * 0.1
        eta = np.zeros((len(starts), H + 1, 3))
        eta[..., 0] = 0.3 * (np.asarray(starts)[:, None] + lead[None, :])
        std = np.full(eta.shape, 0.1)
        if nan_start is not None:
            k = int(np.flatnonzero(np.isclose(starts, nan_start))[0])
            (std if nan_std else eta)[k, 5:] = np.nan
        return SimpleNamespace(eta=eta, eta_std=std)
    return forecast


def test_start_rows_by_hand():
    """20 s at 10 Hz, 2-s horizon: starts from 3 s (the warm-up) every 1 s while 2 s of
    truth remain (rows 30, 40, ..., 170), or every row; with a new segment from row 100, none
    whose horizon crosses into it (rows <= 79) or whose warm-up lies before it (rows < 130).
    The other tests only read whatever rows start_rows gives."""
    from hybridship.evaluation.manoeuvre import start_rows

    a = _arrays()
    np.testing.assert_array_equal(start_rows(a, 20, 1.0), np.arange(30, 171, 10))
    np.testing.assert_array_equal(start_rows(a, 20, None), np.arange(30, 180))
    np.testing.assert_array_equal(start_rows(a, 20, 1.0, warmup_s=0.0), np.arange(0, 171, 10))
    a.segment_id = np.where(np.arange(200) < 100, 0, 1)
    np.testing.assert_array_equal(start_rows(a, 20, 1.0), [30, 40, 50, 60, 70, 130, 140, 150, 160, 170])


def test_forecast_errors_score_the_truth_the_horizon_later():
    from hybridship.evaluation.manoeuvre import forecast_errors, start_rows

    a = _arrays()
    rows = start_rows(a, 20, 1.0)
    err, z = forecast_errors(_forecaster(), a, rows, np.array([10, 20]), return_z=True)
    assert err.shape == (rows.size, 2, 4) and np.abs(err).max() < 1e-12 and np.abs(z).max() < 1e-9


def test_forecast_errors_are_the_absolute_misses_in_metres_and_degrees_and_over_their_spreads():
    """A forecast off by a known amount, growing with the lead (0.03 m north and -0.04 m east
    per step, so 0.05 m of distance per step) and 0.1 rad in heading across +-180 deg: by hand,
    the errors at steps 10 and 20 are 0.3/0.4/5.73 deg/0.5 m and 0.6/0.8/5.73 deg/1.0 m, and
    over the spreads (0.1 m, 0.2 m, 0.05 rad) 3/2/2 and 6/4/2. A perfect forecast (the test
    above) gives zeros whatever the formulas; these values need the right ones."""
    from hybridship.evaluation.manoeuvre import forecast_errors, start_rows

    a = _arrays()
    a.eta[:, 2] = np.pi - 0.05                         # the truth's heading, just short of 180 deg

    def off(arrays, starts, horizon_s):
        fc = _forecaster()(arrays, starts, horizon_s)
        k = np.arange(fc.eta.shape[1])
        fc.eta[..., 0] += 0.03 * k
        fc.eta[..., 1] -= 0.04 * k
        fc.eta[..., 2] = -np.pi + 0.05                 # 0.1 rad to port of the truth, across the wrap
        fc.eta_std[..., 1], fc.eta_std[..., 2] = 0.2, 0.05
        return fc

    rows = start_rows(a, 20, 1.0)
    err, z, std = forecast_errors(off, a, rows, np.array([10, 20]), return_z=True, return_std=True, heading_z=True)
    heading = np.degrees(0.1)
    np.testing.assert_allclose(err, np.broadcast_to([[0.3, 0.4, heading, 0.5], [0.6, 0.8, heading, 1.0]],
                                                    err.shape), atol=1e-9)
    np.testing.assert_allclose(z, np.broadcast_to([[3.0, 2.0, 2.0], [6.0, 4.0, 2.0]], z.shape), atol=1e-9)
    np.testing.assert_allclose(std, np.broadcast_to([0.1, 0.2], std.shape))


def test_an_exact_forecast_without_spread_is_inside_its_band_and_an_error_without_one_outside():
    from hybridship.evaluation.manoeuvre import forecast_errors, start_rows

    a = _arrays()
    rows = start_rows(a, 20, 1.0)

    def no_spread(arrays, starts, horizon_s, **kw):
        fc = _forecaster()(arrays, starts, horizon_s, **kw)
        fc.eta_std[:] = 0.0
        fc.eta[1, :, 0] += 0.5                         # one start off by 0.5 m in x0
        return fc

    _, z = forecast_errors(no_spread, a, rows, np.array([10, 20]), return_z=True, heading_z=True)
    assert z.shape == (rows.size, 2, 3) and np.all(np.isinf(z[1, :, 0]))
    assert np.all(np.delete(z, 1, axis=0) == 0.0) and np.all(z[1, :, 1:] == 0.0)


@pytest.mark.parametrize("nan_std", [False, True])
def test_a_forecast_with_nan_is_refused_naming_its_start(nan_std):
    """A NaN forecast (or spread) would make the pooled MAE NaN or count as a band miss
    without a word; it is refused naming the start time."""
    from hybridship.evaluation.manoeuvre import forecast_errors, start_rows

    a = _arrays()
    rows = start_rows(a, 20, 1.0)
    with pytest.raises(ValueError, match=r"start time_s 5 "):
        forecast_errors(_forecaster(nan_start=5.0, nan_std=nan_std), a, rows, np.array([10, 20]), return_z=True,
                        heading_z=True)
    if nan_std:     # without the spread asked for, a NaN spread is not read
        forecast_errors(_forecaster(nan_start=5.0, nan_std=True), a, rows, np.array([10, 20]))


def test_the_tables_pool_the_starts_of_every_run_by_hand():
    """errors.csv and coverage.csv from two zigzag runs (1 and 2 starts) and a turning run
    (1 start): per kind the mean over its starts, and ``all`` over the four starts (not the
    mean of the kinds' means), for each state and horizon in its own column; a run without
    a spread counts in no coverage. (The benchmark test on the real runs checks only that
    these figures are finite, ordered and pooled between the kinds.)"""
    from hybridship.evaluation.manoeuvre import Run, coverage_table, error_table

    runs = [Run(SimpleNamespace(kind=k, name=n), None) for k, n in (("zigzag", "z1"), ("turning", "t1"),
                                                                       ("zigzag", "z2"), ("zigzag", "z3"))]
    state = np.array([1.0, 2.0, 30.0, 100.0])                # x0, y0, heading, distance: apart
    horizon = np.array([1.0, 10.0])[:, None]                  # the 10-s errors 10 times the 5-s ones
    start = lambda f: f * horizon * state[None]               # noqa: E731  (one start's errors (2, 4))
    errs = [np.stack([start(1.0)]), np.stack([start(4.0)]), np.stack([start(2.0), start(3.0)]), np.zeros((0, 2, 4))]
    e = error_table({("hybrid", "known"): errs}, runs, (5.0, 10.0)).set_index(["kind", "state", "horizon_s"]).mae
    for kind, f in (("zigzag", 2.0), ("turning", 4.0), ("all", 2.5)):     # all: (1 + 4 + 2 + 3) / 4
        for j, s in enumerate(("x0_m", "y0_m", "heading_deg", "distance_m")):
            assert e[(kind, s, 5.0)] == pytest.approx(f * state[j]) and e[(kind, s, 10.0)] == pytest.approx(
                10 * f * state[j])
    # coverage: z of x0 and y0 pooled; zigzag {0.5, 1.5 | 0.5, 2.5 | 3, 0.2}, turning {0.9, 1.1}
    zs = [np.array([[[0.5, 1.5]]]), np.array([[[0.9, 1.1]]]), np.array([[[0.5, 2.5]], [[3.0, 0.2]]]), None]
    c = coverage_table({("hybrid", "known"): zs}, runs, (5.0,)).set_index(["kind", "sigma"]).coverage
    assert c[("zigzag", 1)] == pytest.approx(3 / 6) and c[("zigzag", 2)] == pytest.approx(4 / 6)
    assert c[("turning", 1)] == pytest.approx(1 / 2) and c[("turning", 2)] == pytest.approx(1.0)
    assert c[("all", 1)] == pytest.approx(4 / 8) and c[("all", 2)] == pytest.approx(6 / 8)



@pytest.mark.parametrize("sigma, error", [(0, ValueError), (-1.0, ValueError), (float("nan"), ValueError),
                                          ("2", TypeError), (True, TypeError)])
def test_the_spread_tables_refuse_a_sigma_that_is_not_a_band_width_by_name(sigma, error):
    """A sigma of 0, below 0 or NaN gave a coverage of 0 in coverage.csv and
    coverage_intervals.csv without a word; a text "2" failed in numpy's words (sharpness_table
    first read it as 2 through float()), and sharpness_table took True as sigma 1."""
    from hybridship.evaluation.manoeuvre import Run, coverage_intervals, coverage_table, sharpness_table

    runs = [Run(SimpleNamespace(kind="zigzag", name="z1"), None), Run(SimpleNamespace(kind="turning", name="t1"), None)]
    z = {("hybrid", "known"): [np.full((3, 1, 2), 0.5), np.full((2, 1, 2), 1.5)]}
    err = {("hybrid", "known"): [np.ones((3, 1, 4)), np.ones((2, 1, 4))]}
    sd = {("hybrid", "known"): [np.ones((3, 1, 2)), np.ones((2, 1, 2))]}
    with pytest.raises(error, match="^sigmas: "):
        coverage_table(z, runs, (5.0,), sigmas=(1, sigma))
    with pytest.raises(error, match="^sigma: "):
        coverage_intervals(z, (5.0,), sigma=sigma)
    with pytest.raises(error, match="^sigma: "):
        sharpness_table(err, sd, runs, (5.0,), sigma=sigma)
    # the labels stay as they were: whole sigmas as ints
    assert coverage_table(z, runs, (5.0,), sigmas=(1, 1.5)).sigma.tolist()[:2] == [1, 1.5]
    assert coverage_intervals(z, (5.0,)).sigma.tolist() == [2]
    assert sharpness_table(err, sd, runs, (5.0,)).sigma.tolist() == [2, 2, 2]


@pytest.mark.parametrize("horizons", [(10.0,), (5.0, 10.0, 20.0)])
def test_the_tables_refuse_horizons_that_are_not_the_errors_ones(horizons):
    """Errors at two horizons tabulated with one label wrote the 5-s errors as the 10-s ones
    and dropped the rest without a word; with three labels numpy's IndexError named nothing."""
    from hybridship.evaluation.manoeuvre import Run, coverage_intervals, coverage_table, error_table, sharpness_table

    runs = [Run(SimpleNamespace(kind="zigzag", name="z1"), None)]
    key = ("hybrid", "known")
    z, err, sd = {key: [np.full((3, 2, 2), 0.5)]}, {key: [np.ones((3, 2, 4))]}, {key: [np.ones((3, 2, 2))]}
    msg = rf"^horizons_s: {len(horizons)} lead times given, but per_run\w*\[\('hybrid', 'known'\)\] has 2 per forecast"
    for call in (lambda h: coverage_table(z, runs, h), lambda h: coverage_intervals(z, h),
                 lambda h: error_table(err, runs, h), lambda h: sharpness_table(err, sd, runs, h)):
        with pytest.raises(ValueError, match=msg):
            call(horizons)
        assert sorted(call((5.0, 10.0)).horizon_s.unique()) == [5.0, 10.0]


def test_a_run_that_cannot_be_resampled_is_named(tmp_path):
    """load_runs' step_s errors named no run: among a folder of runs, the one too short for
    the step, or logged at a rate the step is no whole multiple of, could not be found."""
    from hybridship.evaluation.manoeuvre import load_runs

    _write_runs(tmp_path / "zigzag", ["zigzag_31-Jul-2020_13_00_00.csv"])
    _raw(4).to_csv(tmp_path / "zigzag" / "zigzag_31-Jul-2020_13_01_00.csv", index=False)
    _raw(100, dt_s=0.3).to_csv(tmp_path / "zigzag" / "zigzag_31-Jul-2020_13_02_00.csv", index=False)
    with pytest.raises(ValueError, match=r"^step_s: 0.5 s leaves fewer than two samples of a 0.3-s run \(run "
                                         r".*zigzag_31-Jul-2020_13_01_00.csv\)$"):
        load_runs(tmp_path, "esso_osaka_model", step_s=0.5)
    (tmp_path / "zigzag" / "zigzag_31-Jul-2020_13_01_00.csv").unlink()
    with pytest.raises(ValueError, match=r"^step_s: 0.5 s is not a whole multiple of the data step 0.3 s \(run "
                                         r".*zigzag_31-Jul-2020_13_02_00.csv\)$"):
        load_runs(tmp_path, "esso_osaka_model", step_s=0.5)
    (tmp_path / "zigzag" / "zigzag_31-Jul-2020_13_02_00.csv").unlink()
    assert len(load_runs(tmp_path, "esso_osaka_model", step_s=0.5)[0].arrays) == 20

def test_readme_says_every_sample_when_every_sample_starts():
    from hybridship.evaluation.manoeuvre import BenchmarkResult, ManoeuvreConfig, markdown_report

    from dataclasses import replace

    e = pd.DataFrame(columns=["model", "kind", "state", "horizon_s", "mae", "commands"])
    res = BenchmarkResult(e, [], [], {}, (5.0,), replace(ManoeuvreConfig(), start_every_s=None), {}, {})
    md = markdown_report(res)
    assert "every None" not in md and "(every sample)" in md
    res = BenchmarkResult(e, [], [], {}, (5.0,), ManoeuvreConfig(), {}, {})
    assert "(every 1.0 s)" in markdown_report(res)


@pytest.mark.parametrize("bad, field", [
    ({"start_every_s": float("nan")}, "start_every_s"), ({"start_every_s": 0.0}, "start_every_s"),
    ({"step_s": -0.1}, "step_s"), ({"train_row_stride": 0}, "train_row_stride"),
    ({"data_only_row_stride": 1.5}, "data_only_row_stride"), ({"guard_quantile": 1.0}, "guard_quantile"),
    ({"training": "free_run"}, "training"), ({"hull_fit": "ridge"}, "hull_fit"), ({"wind_samples": -1}, "wind_samples"),
])
def test_manoeuvre_config_refuses_bad_settings_naming_the_field(bad, field):
    from dataclasses import replace

    from hybridship.evaluation.manoeuvre import ManoeuvreConfig

    with pytest.raises(ValueError, match=rf"^{field}: .*\[ManoeuvreConfig\]"):
        ManoeuvreConfig(**bad)
    with pytest.raises(ValueError, match=rf"^{field}: "):
        replace(ManoeuvreConfig(), **bad)          # replace re-validates
    assert replace(ManoeuvreConfig(), start_every_s=None).start_every_s is None


# ------------------------------------------------------------------------- a review's findings


def test_a_renamed_copy_of_a_training_run_or_test_runs_at_two_rates_are_refused(tmp_path):
    """A training run copied under another name was scored as a test run (the check compared
    paths and names); a 5-Hz run beside 10-Hz ones was scored at twice the labelled horizons;
    a one-row run ended in "cannot convert float NaN to integer"."""
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig, _checked_steps, load_runs

    _write_runs(tmp_path / "train", ["zigzag_31-Jul-2020_13_00_00.csv"])
    raw = _raw(100)
    raw["x_position_mid [m]"] += 1.0                      # another recording
    (tmp_path / "test").mkdir()
    raw.to_csv(tmp_path / "test" / "zigzag_31-Jul-2020_14_00_00.csv", index=False)
    train = load_runs(tmp_path / "train", "esso_osaka_model")
    cfg = ManoeuvreConfig.quick(0)
    assert list(_checked_steps(train, load_runs(tmp_path / "test", "esso_osaka_model"), (1.0, 2.0), cfg)) == [10, 20]
    _raw(100).to_csv(tmp_path / "test" / "zigzag_31-Jul-2020_99_99_99.csv", index=False)    # a renamed copy
    with pytest.raises(ValueError, match=r"test_dir: 1 run\(s\) hold the samples of a train_dir run .*"
                                         r"zigzag_31-Jul-2020_99_99_99 is training run zigzag_31-Jul-2020_13_00_00"):
        _checked_steps(train, load_runs(tmp_path / "test", "esso_osaka_model"), (1.0, 2.0), cfg)
    (tmp_path / "test" / "zigzag_31-Jul-2020_99_99_99.csv").unlink()
    _raw(50, dt_s=0.2).to_csv(tmp_path / "test" / "zigzag_31-Jul-2020_15_00_00.csv", index=False)
    with pytest.raises(ValueError, match=r"test_dir: the test runs have different sample steps .*0\.2 s"):
        _checked_steps(train, load_runs(tmp_path / "test", "esso_osaka_model"), (1.0, 2.0), cfg)


def test_start_rows_and_the_split_check_their_arguments(tmp_path):
    from hybridship.evaluation.manoeuvre import load_runs, split_runs, start_rows

    a = _arrays()
    for kw, field in ((dict(horizon_steps=0), "horizon_steps"), (dict(start_every_s=0.0), "start_every_s"),
                      (dict(start_every_s=float("nan")), "start_every_s"), (dict(warmup_s=-3.0), "warmup_s")):
        args = {"horizon_steps": 20, "start_every_s": 1.0, **kw}
        with pytest.raises((TypeError, ValueError), match=f"^{field}: "):
            start_rows(a, **args)
    assert start_rows(_arrays(n=1), 20, 1.0).size == 0           # one row: no start, no NaN
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="^data_dir: .* holds no runs"):
        split_runs(tmp_path / "empty", tmp_path / "split")
    data = _runs_folder(tmp_path)
    with pytest.raises(ValueError, match="^seed: "):
        split_runs(data, tmp_path / "split", seed=-1)
    (tmp_path / "a_file").write_text("x")
    with pytest.raises(ValueError, match="^out_dir: .* is a file"):
        split_runs(data, tmp_path / "a_file")
    with pytest.raises(ValueError, match="^step_s: "):
        load_runs(data, "esso_osaka_model", step_s=float("nan"))


def test_esso_to_log_names_a_missing_column_and_a_lead_that_is_not_a_number():
    from hybridship.logs.io import LogFormatError

    with pytest.raises(LogFormatError, match=r"^u_velo \[m/s\]: missing from the raw run"):
        esso_to_log(_raw(50).drop(columns=["u_velo [m/s]"]))
    for lead in ("a", True):
        with pytest.raises(TypeError, match="^velocity_lead_s: expected a number"):
            esso_to_log(_raw(50), velocity_lead_s=lead)


def test_the_manoeuvre_benchmark_refuses_an_out_inside_its_inputs_and_a_text_quick(tmp_path, capsys):
    """Its tables inside --test were read as runs by the next run ("cannot tell the run
    kind"); ``quick="no"`` ran the quick configuration."""
    from hybridship.cli import main
    from hybridship.evaluation.manoeuvre import run_manoeuvre_benchmark

    data = _runs_folder(tmp_path)
    assert main(["benchmark", "manoeuvre", "--train", str(data / "zigzag"), "--test", str(data / "turning"),
                 "--out", str(data / "turning" / "results")]) == 2
    assert "lies inside the --test folder" in capsys.readouterr().err
    assert not (data / "turning" / "results").exists()
    with pytest.raises(TypeError, match="^quick: expected True or False"):
        run_manoeuvre_benchmark("esso_osaka_model", data / "zigzag", data / "turning", out_dir=tmp_path / "o",
                                quick="no")
    # a dict of settings failed with "'dict' object has no attribute 'ensemble'"
    with pytest.raises(TypeError, match="^config: expected a ManoeuvreConfig or None, got dict"):
        run_manoeuvre_benchmark("esso_osaka_model", data / "zigzag", data / "turning", out_dir=tmp_path / "o",
                                config={"start_every_s": 2.0})
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("horizons, error", [("15", TypeError), (30.0, TypeError), ([True], TypeError),
                                             (["5"], TypeError), ([5.0, float("nan")], ValueError),
                                             ([-5.0], ValueError), ([], ValueError)])
def test_the_manoeuvre_benchmark_refuses_horizons_that_are_not_a_sequence_of_numbers(tmp_path, horizons, error):
    """A text was read character by character ("15": horizons of 1 and 5 s, scored under those
    labels), True as a 1-s horizon, and a single number failed with "'float' object is not
    iterable"; each is refused naming horizons_s before anything is read or written."""
    from hybridship.evaluation.manoeuvre import run_manoeuvre_benchmark

    data = _runs_folder(tmp_path)
    with pytest.raises(error, match="^horizons_s: "):
        run_manoeuvre_benchmark("esso_osaka_model", data / "zigzag", data / "turning", horizons,
                                out_dir=tmp_path / "o", quick=True)
    assert not (tmp_path / "o").exists()


def test_ratio_to_physics_is_distance_and_heading_over_the_physics():
    from hybridship.evaluation.manoeuvre import md_ratio_to_physics

    rows = [{"model": m, "kind": k, "state": st, "horizon_s": 30.0, "mae": v, "commands": "known"}
            for k in ("turning", "all") for m, f in (("hybrid", 1.0), ("dynamic", 2.0))
            for st, v in (("distance_m", 0.3 * f), ("heading_deg", 5.0 * (f if m == "dynamic" else 1.5)))]
    md = md_ratio_to_physics(pd.DataFrame(rows), "known")
    assert "| turning | 0.50 / 0.75 |" in md and "| all | 0.50 / 0.75 |" in md
    assert md_ratio_to_physics(pd.DataFrame(rows), "held") == "(no rows)\n"


def test_the_committed_esso_results_state_their_ratio_from_their_errors():
    """The ratios docs/esso-osaka.md quotes are its generated block and the results README's
    section, both what markdown_report makes of the committed errors.csv."""
    from pathlib import Path

    from hybridship.evaluation.manoeuvre import BenchmarkResult, ManoeuvreConfig, markdown_report, md_ratio_to_physics

    docs = Path(__file__).resolve().parents[1] / "docs"
    e = pd.read_csv(docs / "results" / "esso-osaka" / "errors.csv")
    block = md_ratio_to_physics(e, "known")
    assert "| all |" in block
    page = (docs / "esso-osaka.md").read_text()
    assert "<!-- generated:ratio -->" in page and block in page.split("<!-- generated:ratio -->")[1]
    md = markdown_report(BenchmarkResult(e, [], [], {}, (5.0, 10.0, 20.0, 30.0), ManoeuvreConfig(), {}, {}))
    section = md[md.index("## hybrid as a ratio to dynamic"):md.index("\n\nAll states")]     # no coverage here
    assert section in (docs / "results" / "esso-osaka" / "README.md").read_text()


def test_the_manoeuvre_benchmarks_out_dir_that_is_not_a_path_is_refused_by_name():
    """out_dir=None ended in pathlib's 'expected str, bytes or os.PathLike object, not NoneType'."""
    from hybridship.evaluation.manoeuvre import check_output_folder

    with pytest.raises(TypeError, match=r"^out_dir: expected a file path \(str or os.PathLike\), got NoneType"):
        check_output_folder(None)


@pytest.mark.parametrize("where", ["turning", "turning/results", "zigzag/results"])
def test_the_manoeuvre_benchmark_function_refuses_an_out_dir_among_its_runs(tmp_path, monkeypatch, where):
    """The command refused an --out inside --train or --test, the function did not: it trained,
    and wrote its CSV tables where the next run on that folder reads them as runs. Now a
    ValueError naming out_dir and the folder, before anything is trained or written."""
    from hybridship.evaluation import manoeuvre

    def no_training(*args, **kwargs):
        raise AssertionError("trained before out_dir was checked")

    monkeypatch.setattr(manoeuvre, "_fit", no_training)
    data = tmp_path / "data"
    for kind, prefix, lengths in (("zigzag", "zigzag", (100, 110)), ("turning", "turn", (120, 130))):
        (data / kind).mkdir(parents=True)
        for i, n in enumerate(lengths):          # runs of other samples: no copy of a training run
            _raw(n).to_csv(data / kind / f"{prefix}_14-Sep-2020_15_0{i}_00.csv", index=False)
    kind = where.split("/")[0]
    with pytest.raises(ValueError, match=rf"^out_dir: .* lies inside {'test' if kind == 'turning' else 'train'}_dir"):
        manoeuvre.run_manoeuvre_benchmark("esso_osaka_model", data / "zigzag", data / "turning", (1.0,),
                                          out_dir=data / where, quick=True)
    assert not (data / kind / "results").exists() and not (data / kind / "errors.csv").exists()


def test_the_manoeuvre_benchmarks_docstring_names_every_output_file():
    """``coverage_heading.csv`` was written by every run but missing from out_dir's list."""
    from hybridship.evaluation.manoeuvre import OUTPUT_FILES, run_manoeuvre_benchmark

    assert [f for f in OUTPUT_FILES if f"``{f}``" not in run_manoeuvre_benchmark.__doc__] == []


def test_a_kind_of_one_recording_stays_in_training_as_split_runs_says(tmp_path):
    """Its docstring said every kind gives at least one test recording; a kind of a single
    recording gives none (it is kept for training), and the docstring now says so."""
    from hybridship.evaluation.manoeuvre import split_runs

    data = tmp_path / "data"
    _write_runs(data / "zigzag", [f"zigzag_31-Jul-2020_13_0{i}_00.csv" for i in range(4)])
    _write_runs(data / "turning", ["turn_14-Sep-2020_15_00_00.csv"])
    train, test = split_runs(data, tmp_path / "split")
    assert [r.kind for r in list_runs(test)] == ["zigzag"]
    assert [r.name for r in list_runs(train) if r.kind == "turning"] == ["turn_14-Sep-2020_15_00_00"]
    assert "a kind of a single recording has none" in " ".join(split_runs.__doc__.split())


def test_a_coverage_without_an_interval_reads_n_a_not_nan():
    """With one test run there is nothing to resample: the README showed "0.950 [nan, nan]"."""
    from hybridship.evaluation.manoeuvre import coverage_intervals, md_coverage_intervals

    z = np.abs(np.random.default_rng(0).normal(size=(10, 2, 3)))
    one = md_coverage_intervals(coverage_intervals({("hybrid", "known"): [z]}, (5.0, 10.0)))
    assert "nan" not in one and "| known | hybrid | 0.950 [n/a] | 1.000 [n/a] |" in one
    two = md_coverage_intervals(coverage_intervals({("hybrid", "known"): [z, z[:5]]}, (5.0, 10.0)))
    assert "[n/a]" not in two and "nan" not in two



def test_the_coverage_intervals_markdown_names_the_sigma_they_were_taken_at():
    """The heading said "2-sigma coverage" whatever sigma coverage_intervals had counted."""
    from hybridship.evaluation.manoeuvre import coverage_intervals, md_coverage_intervals

    z = np.abs(np.random.default_rng(0).normal(size=(10, 2, 3)))
    for sigma, head in ((1, "1-sigma coverage"), (1.5, "1.5-sigma coverage"), (2.0, "2-sigma coverage")):
        md = md_coverage_intervals(coverage_intervals({("hybrid", "known"): [z, z[:5]]}, (5.0, 10.0), sigma=sigma))
        assert md.startswith(head + " with a 90 % interval"), md

def test_coverage_table_labels_a_fractional_sigma_as_it_counted_it():
    """sigmas=(1, 1.5) wrote the 1.5-sigma coverage under sigma 1, beside the 1-sigma one."""
    from hybridship.evaluation.manoeuvre import coverage_table

    z = np.full((4, 1, 2), 1.2)           # every error 1.2 spreads: outside 1 sigma, inside 1.5
    cov = coverage_table({("hybrid", "known"): [z]}, [SimpleNamespace(kind="zigzag")], (5.0,), sigmas=(1, 1.5))
    got = cov[cov.kind == "all"].set_index("sigma").coverage.to_dict()
    assert got == {1: 0.0, 1.5: 1.0}
    assert sorted(cov.sigma.tolist()) == [1, 1, 1.5, 1.5]
