"""How fast are one-minute forecasts on one CPU core?

Prints, for the Gunnerus model, how many 60-step (1 Hz, RK4, four-quadrant propellers and
wind included) physics-only forecasts per second the batched integrator does for
B = 1, 1 000 and 100 000 start states, and the latency of a single forecast.

Usage::

    python benchmarks/speed.py            # human-readable table
    python benchmarks/speed.py --json     # one JSON object (keys below) for tracking
    python benchmarks/speed.py --quick    # smaller batches, for CI smoke tests
    python benchmarks/speed.py --long-log           # the long-log forecast cost only (JSON)
    python benchmarks/speed.py --profile-long-log   # cProfile of the long-log forecast only
    python benchmarks/speed.py --start-windows      # the start-window checks' cost only (JSON)

JSON keys: ``physics_forecasts_per_s`` (at the largest B), ``physics_single_forecast_ms``,
``physics_vessel_steps_per_s`` and ``physics_by_batch`` (B -> forecasts/s); for the hybrid
(10-member ensemble, guard on) ``hybrid_forecasts_per_s`` (at the largest hybrid batch),
``hybrid_single_forecast_ms``, ``hybrid_by_batch``, ``train_s`` (training on 3 000
samples of a synthetic log with default settings) and ``train_samples`` (the rows it trained
on); for the cost of a forecast against the
length of its log ``forecast_long_log_ms`` (a hybrid forecast, 60 s ahead from 2 start times,
on a 1-hour 10-Hz log passed as a DataFrame, ingest included), ``forecast_short_log_ms``
(the same forecast on the last 2 minutes of that log), ``forecast_long_short_ratio`` (their
ratio; the target is at most 2; CPU times, the ratio the median over alternating pairs),
``forecast_long_log_ingested_ms`` (the long log passed as already ingested LogArrays, so its
validation is not repeated), ``forecast_2h_log_ms`` and ``forecast_2h_1h_ratio`` (a 2-hour
log against the 1-hour one: the cost stops growing beyond what the forecast reads),
``forecast_long_log_rows`` and ``forecast_short_log_rows`` (the two logs' rows);
``manoeuvre_train_s`` (training the
manoeuvre benchmark's hybrid, :class:`hybridship.evaluation.manoeuvre.ManoeuvreConfig` as it stands,
on the Esso Osaka training runs of the benchmark's split, seed 0, one core; null when the
data are absent or with ``--quick``) and ``manoeuvre_training`` (its training mode);
for drift-off analysis
``driftoff_samples_per_s`` (Monte-Carlo blackouts per second: 8 headings x 100 samples of
one weather state, 300 s horizon, all default loads) and ``driftoff_state_s`` (wall time of
that weather state); ``environment_filter_ms`` (CPU time of the environment estimator over
``environment_filter_minutes`` = 30 minutes of a 1-Hz Gunnerus log, reporting at its last row);
``start_window_ms_per_1000_starts`` (CPU time of the start-window checks over every start of
a 1-hour 1-Hz log without faults, per 1000 starts) and
``start_window_detectors_ms_per_1000_starts`` (the same with every start through the detectors).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

# One core: pin every threaded library before it is imported.
for _v in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

from hybridship.physics.model import DynamicModel  # noqa: E402


def _states(B: int, rng: np.random.Generator):
    """Random drift-like start states and held commands for B vessels."""
    eta0 = np.column_stack([rng.normal(0, 5, B), rng.normal(0, 5, B), rng.uniform(-np.pi, np.pi, B)])
    nu0 = np.column_stack([rng.normal(0, 0.3, B), rng.normal(0, 0.3, B), rng.normal(0, 0.005, B)])
    rpm = rng.uniform(-50, 150, (B, 3))
    az = rng.uniform(-np.pi, np.pi, (B, 3))
    wind = np.column_stack([rng.uniform(0, 15, B), rng.uniform(0, 2 * np.pi, B)])
    return eta0, nu0, dict(rpm=rpm, azimuth_rad=az, wind=wind)


def _time(fn, min_time_s: float = 1.0, max_repeats: int = 200) -> float:
    """Best wall time [s] of repeated calls (after one warm-up call)."""
    fn()
    best = np.inf
    total = 0.0
    n = 0
    while (total < min_time_s and n < max_repeats) or n < 3:
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        best = min(best, dt)
        total += dt
        n += 1
    return best


def physics_speed(batches=(1, 1_000, 100_000), seed: int = 0) -> dict:
    """Measure physics-only forecast throughput and single-forecast latency."""
    model = DynamicModel("gunnerus")
    rng = np.random.default_rng(seed)
    by_batch = {}
    # compile once on a tiny batch so that large batches are timed in a single run
    eta0, nu0, kw = _states(2, rng)
    model.rollout(eta0, nu0, 60, **kw)
    for B in batches:
        eta0, nu0, kw = _states(B, rng)
        if B >= 10_000:
            t0 = time.perf_counter()
            model.rollout(eta0, nu0, 60, **kw)
            t = time.perf_counter() - t0
        else:
            t = _time(lambda: model.rollout(eta0, nu0, 60, **kw), min_time_s=1.0)
        by_batch[B] = B / t
    eta0, nu0, kw = _states(1, rng)
    single = _time(lambda: model.rollout(eta0[0], nu0[0], 60, rpm=kw["rpm"][0], azimuth_rad=kw["azimuth_rad"][0],
                                         wind=kw["wind"][0]), min_time_s=1.0, max_repeats=2000)
    largest = max(batches)
    return {
        "physics_forecasts_per_s": by_batch[largest],
        "physics_vessel_steps_per_s": by_batch[largest] * 60,
        "physics_single_forecast_ms": single * 1e3,
        "physics_by_batch": {str(k): v for k, v in by_batch.items()},
    }


def hybrid_speed(batches=(1, 1_000, 10_000), seed: int = 0) -> dict:
    """Train a default hybrid on 3 000 samples, then time batched 60-step hybrid forecasts."""
    import torch

    torch.set_num_threads(1)
    from hybridship.predictors import HybridPredictor
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    log = physics_log(model, duration_s=3000.0, t_shutdown_s=None, seed=seed, current=(0.3, 1.0))
    hp = HybridPredictor(model.vessel)
    t0 = time.perf_counter()
    hp.fit([log])
    train_s = time.perf_counter() - t0
    rng = np.random.default_rng(seed)
    by_batch = {}

    def states(B):
        eta0, nu0, kw = _states(B, rng)
        dev0 = np.zeros((B, 3))
        bias0 = rng.normal(0, 0.002, (B, 3))
        return (eta0, nu0, dev0, bias0, kw["rpm"][:, None].copy(), kw["azimuth_rad"][:, None].copy(),
                kw["wind"][:, None].copy())

    hp.rollout(*states(2), 60, 1.0)  # warm-up
    for B in batches:
        args = states(B)
        if B >= 10_000:
            t0 = time.perf_counter()
            hp.rollout(*args, 60, 1.0)
            t = time.perf_counter() - t0
        else:
            t = _time(lambda: hp.rollout(*args, 60, 1.0), min_time_s=1.0)
        by_batch[B] = B / t
    return {"hybrid_forecasts_per_s": by_batch[max(batches)], "hybrid_single_forecast_ms": 1e3 / by_batch[min(batches)],
            "hybrid_by_batch": {str(k): v for k, v in by_batch.items()}, "train_s": train_s,
            "train_samples": hp.training_info["n_rows"]}


def _long_log_case(seed: int = 0, hours: float = 1.0, rate_hz: float = 10.0, short_s: float = 120.0):
    """(hybrid, long log, short log, start times) of the long-log forecast benchmark."""
    import torch

    torch.set_num_threads(1)
    from hybridship.predictors import HybridPredictor
    from hybridship.residual.ensemble import EnsembleConfig
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    long = physics_log(model, duration_s=hours * 3600.0, dt_s=1.0 / rate_hz, t_shutdown_s=None, seed=seed,
                       current=(0.3, 1.0))
    t_end = float(long.time_s.iloc[-1])
    short = long[long.time_s >= t_end - short_s].reset_index(drop=True)
    hp = HybridPredictor(model.vessel, ensemble_config=EnsembleConfig(max_epochs=30, patience=10, seed=seed))
    hp.fit([short])         # its 10-Hz rows thinned to 1 s for the residual fit (ResidualConfig.residual_step_s)
    return hp, long, short, [t_end - 20.0, t_end - 10.0]


def _cpu_time(fn, repeats: int = 3) -> float:
    """Best CPU time [s] of this process over ``repeats`` calls (one core: torch and numba use
    one thread here), so that other programs on a shared machine do not count."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def long_log_speed(seed: int = 0, pairs: int = 7) -> dict:
    """Time one hybrid forecast (2 starts, 60 s) on a 1-hour 10-Hz log and on its last 2 minutes.

    The hybrid (10 members, a short training on the short log) forecasts from 20 s and 10 s
    before the end of each log, with the commands held; both logs are passed as DataFrames,
    so each call ingests (re-sorts, validates, converts) its log, as a user's call would.
    The two forecasts are timed in turn, ``pairs`` times (CPU time, best of 3 each), and the
    ratio is the median of the pairs' ratios, which holds when the machine's speed drifts.
    A 2-hour log shows that the cost stops growing once the log is longer than what the
    forecast reads (the environment estimator's 30-minute window).
    """
    from hybridship.logs.ingest import ingest
    from hybridship.sim.synthetic import physics_log

    hp, long, short, starts = _long_log_case(seed)
    model = hp.model
    longer = physics_log(model, duration_s=7200.0, dt_s=0.1, t_shutdown_s=None, seed=seed, current=(0.3, 1.0))
    starts_2h = [float(longer.time_s.iloc[-1]) - 20.0, float(longer.time_s.iloc[-1]) - 10.0]
    ingested = ingest(long, model.vessel, purpose="forecast")
    for log, st in ((long, starts), (short, starts), (longer, starts_2h), (ingested, starts)):
        hp.forecast(log, st, 60.0)                          # warm-up (compilation, caches)
    rows = []
    for _ in range(pairs):
        rows.append([_cpu_time(lambda: hp.forecast(long, starts, 60.0)),
                     _cpu_time(lambda: hp.forecast(short, starts, 60.0)),
                     _cpu_time(lambda: hp.forecast(longer, starts_2h, 60.0)),
                     _cpu_time(lambda: hp.forecast(ingested, starts, 60.0))])
    rows = np.array(rows)
    t_long, t_short, t_2h, t_ingested = np.median(rows, axis=0)
    return {"forecast_long_log_ms": t_long * 1e3, "forecast_short_log_ms": t_short * 1e3,
            "forecast_long_short_ratio": float(np.median(rows[:, 0] / rows[:, 1])),
            "forecast_long_log_ingested_ms": t_ingested * 1e3,
            "forecast_2h_log_ms": t_2h * 1e3, "forecast_2h_1h_ratio": float(np.median(rows[:, 2] / rows[:, 0])),
            "forecast_long_log_rows": len(long), "forecast_short_log_rows": len(short)}


def profile_long_log(seed: int = 0, top: int = 25) -> None:
    """Print a cProfile of the long-log forecast (cumulative time), after one warm-up call."""
    import cProfile
    import pstats

    hp, long, _, starts = _long_log_case(seed)
    hp.forecast(long, starts, 60.0)
    prof = cProfile.Profile()
    prof.enable()
    hp.forecast(long, starts, 60.0)
    prof.disable()
    pstats.Stats(prof).sort_stats("cumulative").print_stats(r"hybridship", top)


def manoeuvre_train_speed() -> dict:
    """Wall time of training the manoeuvre benchmark's hybrid on the Esso Osaka training runs."""
    import tempfile

    import torch

    torch.set_num_threads(1)
    from hybridship.datasets.esso_osaka import default_data_dir
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig, _fit, load_runs, make_predictors, split_runs

    data = default_data_dir() / "data"
    if not data.is_dir():
        return {"manoeuvre_train_s": None, "manoeuvre_training": None}
    cfg = ManoeuvreConfig()
    with tempfile.TemporaryDirectory() as tmp:
        train_dir, _ = split_runs(data, tmp, seed=0)
        runs = load_runs(train_dir, "esso_osaka_model")
        hp = make_predictors("esso_osaka_model", cfg)["hybrid"]
        t0 = time.perf_counter()
        _fit("hybrid", hp, runs, cfg)
        return {"manoeuvre_train_s": time.perf_counter() - t0, "manoeuvre_training": cfg.training}


def environment_filter_speed(seed: int = 0, minutes: float = 30.0) -> dict:
    """CPU time of the environment estimator over ``minutes`` of a 1-Hz log (one core).

    The filter runs from the first row to the last and reports the estimate there, as a
    forecast at the end of a log of that length does (after one warm-up call, which compiles).
    """
    from hybridship.logs.ingest import ingest
    from hybridship.residual.environment import EnvironmentEstimator
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    log = physics_log(model, duration_s=minutes * 60.0, dt_s=1.0, t_shutdown_s=None, seed=seed, current=(0.3, 1.0))
    arrays = ingest(log, model.vessel, purpose="forecast")
    est = EnvironmentEstimator(model)
    last = [len(arrays.time_s) - 1]
    est.run(arrays, last)
    return {"environment_filter_ms": _cpu_time(lambda: est.run(arrays, last), repeats=5) * 1e3,
            "environment_filter_minutes": minutes}


def start_window_speed(seed: int = 0, minutes: float = 60.0) -> dict:
    """CPU time [ms per 1000 starts] of the start-window checks over every start of a
    ``minutes``-long 1-Hz log without faults: as a forecast runs them (the quiet starts
    cleared at once, :mod:`hybridship.forecast_inputs.quiet_starts`), and with every start
    through the detectors one by one, as before."""
    from hybridship.forecast_inputs.faults import LogView, WindowSettings
    from hybridship.forecast_inputs.start_window import _assess_start, assess_start_window
    from hybridship.logs.ingest import ingest
    from hybridship.sim.synthetic import physics_log

    model = DynamicModel("gunnerus")
    log = physics_log(model, duration_s=minutes * 60.0, dt_s=1.0, t_shutdown_s=None, seed=seed, current=(0.3, 1.0))
    arrays = ingest(log, model.vessel, purpose="forecast")
    rows = np.arange(3, len(arrays.time_s))          # every start with a full window
    settings = WindowSettings()

    def one_by_one():
        view = LogView.build(arrays, settings, arrays.resorted_time_s)
        for i in rows:
            _assess_start(view, int(i), settings)

    per_1000 = 1e3 * 1e3 / rows.size
    return {"start_window_ms_per_1000_starts": _cpu_time(lambda: assess_start_window(arrays, rows)) * per_1000,
            "start_window_detectors_ms_per_1000_starts": _cpu_time(one_by_one, repeats=1) * per_1000}


def driftoff_speed(n_samples: int = 100) -> dict:
    """Time the Monte-Carlo blackouts of one weather state at 8 headings (planning mode)."""
    from hybridship.driftoff.planning import DriftOffSettings, simulate_blackouts
    from hybridship.driftoff.weather import WeatherState

    w = WeatherState.from_degrees(wind_speed_m_s=10.0, wind_dir_deg=30.0, hs_m=1.0, tp_s=6.0, current_m_s=0.2,
                                  current_dir_deg=200.0)
    st = DriftOffSettings(n_samples=n_samples)
    psi = np.radians(np.arange(0, 360, 45))
    t = _time(lambda: simulate_blackouts("gunnerus", w, psi, settings=st), min_time_s=1.0, max_repeats=20)
    return {"driftoff_samples_per_s": psi.size * n_samples / t, "driftoff_state_s": t}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--quick", action="store_true", help="small batches (smoke test)")
    ap.add_argument("--profile-long-log", action="store_true",
                    help="print a cProfile of the long-log hybrid forecast and stop")
    ap.add_argument("--long-log", action="store_true",
                    help="only the cost of a forecast against the length of its log (JSON)")
    ap.add_argument("--start-windows", action="store_true",
                    help="only the cost of the start-window checks per start (JSON)")
    args = ap.parse_args(argv)
    if args.profile_long_log:
        profile_long_log()
        return 0
    if args.long_log:
        print(json.dumps(long_log_speed(), sort_keys=True))
        return 0
    if args.start_windows:
        print(json.dumps(start_window_speed(), sort_keys=True))
        return 0
    batches = (1, 100, 1_000) if args.quick else (1, 1_000, 100_000)
    res = physics_speed(batches)
    res.update(hybrid_speed((1, 100) if args.quick else (1, 1_000, 10_000)))
    res.update(long_log_speed())
    res.update({"manoeuvre_train_s": None, "manoeuvre_training": None} if args.quick else manoeuvre_train_speed())
    res.update(driftoff_speed(20 if args.quick else 100))
    res.update(environment_filter_speed())
    res.update(start_window_speed(minutes=10.0 if args.quick else 60.0))
    if args.json:
        print(json.dumps(res, sort_keys=True))
        return 0
    print("one-minute (60 x 1 s RK4) physics-only forecasts, Gunnerus, one core")
    print(f"{'B':>8} {'forecasts/s':>14} {'vessel-steps/s':>16}")
    for b, f in res["physics_by_batch"].items():
        print(f"{int(b):>8} {f:>14,.0f} {f * 60:>16,.0f}")
    print(f"single forecast latency: {res['physics_single_forecast_ms']:.3f} ms")
    print()
    print("hybrid (physics + 10-member residual ensemble + guard), one core")
    print(f"{'B':>8} {'forecasts/s':>14}")
    for b, f in res["hybrid_by_batch"].items():
        print(f"{int(b):>8} {f:>14,.0f}")
    print(f"single forecast latency: {res['hybrid_single_forecast_ms']:.3f} ms")
    print(f"training on {res['train_samples']} samples: {res['train_s']:.1f} s")
    print()
    print("hybrid forecast from 2 start times (60 s ahead) against the length of the log, 10 Hz")
    print(f"  {res['forecast_long_log_rows']} rows (1 h): {res['forecast_long_log_ms']:.0f} ms "
          f"({res['forecast_long_log_ingested_ms']:.0f} ms when passed already ingested)")
    print(f"  {res['forecast_short_log_rows']} rows (2 min): {res['forecast_short_log_ms']:.0f} ms")
    print(f"  ratio {res['forecast_long_short_ratio']:.2f} (target <= 2); 2-hour log "
          f"{res['forecast_2h_log_ms']:.0f} ms, {res['forecast_2h_1h_ratio']:.2f}x the 1-hour one")
    if res["manoeuvre_train_s"] is not None:
        print(f"training the manoeuvre hybrid ({res['manoeuvre_training']}) on the Esso Osaka training runs: "
              f"{res['manoeuvre_train_s']:.0f} s")
    print(f"environment estimator over {res['environment_filter_minutes']:.0f} min of a 1-Hz log: "
          f"{res['environment_filter_ms']:.0f} ms")
    print(f"start-window checks: {res['start_window_ms_per_1000_starts']:.1f} ms per 1000 starts "
          f"({res['start_window_detectors_ms_per_1000_starts']:.0f} ms with every start through the detectors)")
    print(f"drift-off blackouts (8 headings x samples, 300 s horizon): {res['driftoff_samples_per_s']:,.0f} samples/s, "
          f"{res['driftoff_state_s']:.3f} s per weather state")
    return 0


if __name__ == "__main__":
    sys.exit(main())
