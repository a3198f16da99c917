"""Snapshot the outputs of the long numerical routines, to check that a refactor keeps them bit for bit.

    python benchmarks/refactor_snapshot.py snap --out /tmp/before.npz     # before the change
    python benchmarks/refactor_snapshot.py snap --out /tmp/after.npz      # after it
    python benchmarks/refactor_snapshot.py compare /tmp/before.npz /tmp/after.npz

Covered, each with fixed seeds: the drift-off kernel (planning blackouts with and without
tracks, and a spinning-down, unbalanced run from a moving start with an extra acceleration),
the DP-loss simulator (one scenario's log), :func:`hybridship.residual.ensemble.fit_ensemble`
(with and without bootstrap) and multi-step training (weights through a hybrid forecast and
the training history). ``compare`` exits 1 if any array differs.

The kernels are compiled without the fast-math flags that made their last bits depend on
whether numba compiled them in the run or loaded them from its cache
(``KERNEL_FASTMATH``); running ``snap`` twice on an empty ``NUMBA_CACHE_DIR`` and comparing
the two checks that this still holds.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from hybridship.fileio import atomic_write


def _drift(out: dict):
    from hybridship.driftoff import engine, planning
    from hybridship.driftoff.weather import WeatherState, WeatherUncertainty

    captured = {}
    original = engine.run_kernel

    def spy(*a, **k):
        captured["a"] = a
        return original(*a, **k)

    engine.run_kernel = spy
    try:
        st = planning.DriftOffSettings(n_samples=12, horizon_s=200.0, radii_m=(3.0, 5.0, 10.0, 20.0),
                                       reaction_times_s=(30.0, 60.0, 150.0))
        w = WeatherState(wind_speed_m_s=14.0, wind_dir_from_rad=0.5, hs_m=2.5, tp_s=8.0, wave_dir_from_rad=0.7,
                         current_speed_m_s=0.4, current_dir_to_rad=2.0)
        for keep in (False, True):
            r = planning.simulate_blackouts("gunnerus", w, np.radians([0, 90, 200]),
                                            uncertainty=WeatherUncertainty.typical(), settings=st, keep_tracks=keep)
            out[f"drift_t_reach_{keep}"], out[f"drift_exc_{keep}"] = r.t_reach_s, r.excursion_m
            if keep:
                out["drift_tracks"] = r.tracks
    finally:
        engine.run_kernel = original
    a = list(captured["a"])
    B, K = a[3].shape
    a[4] = np.full((B, K), 150.0)                       # rpm0: spinning down
    a[6] = False                                        # no holding load
    a[13] = np.tile([0.001, -0.002, 1e-5], (B, 1))      # acc_ned
    t, e, track = engine.run_kernel(*a[:20], keep_tracks=True, nu0=np.array([0.5, 0.1, 0.002]))
    out["drift2_t"], out["drift2_e"], out["drift2_track"] = t, e, track


def _simulator(out: dict):
    from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss

    log = simulate_dp_loss(DPLossConfig(seed=3, t_shutdown_s=400.0, drift_s=200.0, beaufort=(4, 5)))
    num = log.select_dtypes("number")
    out["sim_log"], out["sim_cols"] = num.to_numpy(float), np.array(list(num.columns))
    out["sim_attrs"] = np.array([repr(sorted(log.attrs.items(), key=str))])


def _ensemble(out: dict):
    from hybridship.residual.ensemble import EnsembleConfig, fit_ensemble

    rng = np.random.default_rng(0)
    X = rng.normal(size=(300, 4))
    Y = np.column_stack([np.sin(X[:, 0]) + 0.1 * rng.normal(size=300), X[:, 1] * X[:, 2]])
    for boot in (True, False):
        ens = fit_ensemble(X, Y, EnsembleConfig(n_members=3, hidden=8, max_epochs=120, patience=15, seed=4,
                                                bootstrap=boot), segment_id=np.repeat([0, 1], 150))
        for i, w in enumerate(ens.weights):
            out[f"ens{boot}_w{i}"] = w
        for k in ("x_mean", "x_std", "y_mean", "y_std"):
            out[f"ens{boot}_{k}"] = getattr(ens, k)
        for k, v in ens.history.items():
            out[f"ens{boot}_h_{k}"] = np.asarray(v, float)


def _multistep(out: dict):
    from hybridship.physics.model import DynamicModel
    from hybridship.predictors import HybridPredictor
    from hybridship.residual.ensemble import EnsembleConfig
    from hybridship.residual.multistep import MultiStepConfig
    from hybridship.sim.synthetic import physics_log

    m = DynamicModel("gunnerus")
    logs = [physics_log(m, seed=s, duration_s=400.0, t_shutdown_s=None, current=(0.3, 1.0)) for s in (5, 6)]
    hp = HybridPredictor(m.vessel, ensemble_config=EnsembleConfig(n_members=2, hidden=8, max_epochs=30, patience=5),
                         training="multi_step",
                         multistep_config=MultiStepConfig(horizon_s=10.0, iterations=7, batch_starts=16,
                                                          start_every_s=5.0, lr=3e-3, val_every=2))
    hp.fit(logs)
    for k, v in hp.training_info["multi_step"].items():
        try:
            out[f"ms_info_{k}"] = np.asarray(v, float)
        except (TypeError, ValueError):
            pass
    fc = hp.forecast(logs[1], [200.0, 250.0], 30.0)
    out["ms_fc_eta"], out["ms_fc_std"], out["ms_fc_nu"] = fc.eta, fc.eta_std, fc.nu


def snap(path: str):
    out: dict = {}
    for part in (_drift, _simulator, _ensemble, _multistep):
        part(out)
    # atomically, to the path given: np.savez(path) wrote in place (a run stopped part way left a
    # truncated snapshot over the previous one) and added .npz to a path without it
    atomic_write(path, lambda fh: np.savez(fh, **out))
    print(f"{len(out)} arrays -> {path}")


def compare(a_path: str, b_path: str) -> int:
    a, b = np.load(a_path), np.load(b_path)
    if set(a.files) != set(b.files):
        print(f"different arrays: {sorted(set(a.files) ^ set(b.files))}")
        return 1
    same = lambda x, y: x.shape == y.shape and np.array_equal(x, y, equal_nan=x.dtype.kind in "fc")  # noqa: E731
    bad = [k for k in sorted(a.files) if not same(a[k], b[k])]
    print(f"identical: {len(a.files) - len(bad)} of {len(a.files)}" + (f"; differ: {bad}" if bad else ""))
    return 1 if bad else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("snap", help="write a snapshot")
    s.add_argument("--out", required=True)
    c = sub.add_parser("compare", help="compare two snapshots")
    c.add_argument("a")
    c.add_argument("b")
    args = ap.parse_args(argv)
    if args.cmd == "snap":
        snap(args.out)
        return 0
    return compare(args.a, args.b)


if __name__ == "__main__":
    sys.exit(main())
