"""The hull's speed-proportional (lift) terms, and what they do to the drift's heading.

The Gunnerus vessel file takes the hull's linear manoeuvring derivatives from Clarke et
al. (1983) and applies them in proportion to |u_r| (``lift_speed = "abs"``): sway damping
stays dissipative astern, and the hull's lift moment keeps its sign while the Munk moment
of ``C_A`` reverses. The one published identification of this vessel's hull, the PMM model
of Hassani et al. (2015) for the original 28.9-m hull (``Nuv`` etc. in
``../shared/data/reference/gunnerus_published.csv``), differs in two ways:

* its net linear yaw moment in sway, ``N_uv + (Y_vdot - X_udot)``, is a small part of the
  Munk moment (the hull's lift nearly cancels it ahead), where Clarke's regression leaves
  most of it;
* it is a polynomial in signed ``u`` (``N_uv u v``), so every lift term reverses astern
  (``lift_speed = "signed"``).

This script scores four hulls, each combination of {Clarke, PMM} x {abs, signed}, with
the drift benchmark's protocol on truthsim-dev (paper protocol, trained on the DP parts,
60 s, the first 5 / 20 intervals after the failure): the physics alone and the default
environment estimator (nets off, as the default hybrid is after a failure). The PMM
derivatives are made non-dimensional on the MMG basis with the original hull's length
and its largest draught (2.70 m; the draught of the PMM tests is not given) and applied
to the lengthened hull.

The sign convention is then checked on real data: the physics alone (nothing fitted) on
every Esso Osaka development run, with the packaged KVLCC2 MMG derivatives applied with
|u_r| and with u_r (commands known, 30-s errors per run kind); these runs include berthing
with the propeller reversed.

Writes ``hull_lift.csv`` and ``hull_lift.md`` to ``--out``. Example::

    python benchmarks/hull_lift_convention.py --out docs/results/hull-lift-convention
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from _results import check_out
from hybridship.evaluation import metrics
from hybridship.evaluation.drift import log_files
from hybridship.fileio import atomic_write, markdown_table
from hybridship.frames import ned_to_body
from hybridship.physics.model import DynamicModel
from hybridship.predictors import DynamicPredictor, HybridPredictor, as_log_arrays
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.vessel import Vessel, load_vessel

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TRUTHSIM = SHARED / "truthsim-dev" / "logs"
REFERENCE = SHARED / "reference" / "gunnerus_published.csv"
ESSO = SHARED / "esso-osaka-frt" / "data"
TINY = EnsembleConfig(n_members=2, hidden=4, max_epochs=1, patience=1, seed=0)   # nets are off in the drift
PMM_DRAUGHT_M = 2.70          # largest draught of the original hull (the PMM tests' draught is not given)


def pmm_mmg_derivatives(reference: Path) -> dict[str, float]:
    """The PMM model's (Hassani et al. 2015) linear terms as MMG derivatives (non-dimensional).

    MMG writes ``(m + m_x) u r`` in sway on the left-hand side and no added-mass term in
    yaw, so ``Y'_v = Y_uv / (q L)``, ``Y'_r = Y_ur / (q L^2)``,
    ``N'_v = (N_uv + Y_vdot - X_udot) / (q L^2)`` (the Munk moment included) and
    ``N'_r = (N_ur + (N_vdot + Y_rdot) / 2) / (q L^3)``, with ``q = rho d / 2`` and the
    original hull's L_pp.
    """
    t = pd.read_csv(reference)
    t = t[t.hull_version == "original_2006"].drop_duplicates("parameter").set_index("parameter")["value"]
    t = pd.to_numeric(t.loc[["Lpp", "rho_water", "Xudot", "Yvdot", "Yrdot", "Nvdot", "Yuv", "Yur", "Nuv", "Nur"]])
    L, q = t["Lpp"], 0.5 * t["rho_water"] * PMM_DRAUGHT_M
    return {"Y_v": t["Yuv"] / (q * L), "Y_r": t["Yur"] / (q * L**2),
            "N_v": (t["Nuv"] + t["Yvdot"] - t["Xudot"]) / (q * L**2),
            "N_r": (t["Nur"] + 0.5 * (t["Nvdot"] + t["Yrdot"])) / (q * L**3)}


def mmg_equivalent(vessel: Vessel) -> dict[str, float]:
    """The vessel's lift terms with C_A's part added back, as MMG derivatives (the inverse of
    :func:`~hybridship.physics.hull.mmg_lift`), to compare with :func:`pmm_mmg_derivatives`."""
    a, p = DynamicModel(vessel).arrays, vessel.particulars
    d = a.d_lift[:4] + a.d_lift[4:]
    q, L = 0.5 * p.rho_water_kg_m3 * p.T_m, p.L_pp_m
    return {"Y_v": -d[0] / (q * L), "Y_r": -d[1] / (q * L**2),
            "N_v": -(d[2] + a.m_a[1, 1] - a.m_a[0, 0]) / (q * L**2), "N_r": -(d[3] + a.m_a[1, 2]) / (q * L**3)}


def with_lift(vessel: Vessel, lift_speed: str, mmg: dict | None = None) -> Vessel:
    """The vessel with its lift terms applied with ``lift_speed`` and, given ``mmg``, taken from it."""
    d = vessel.model_dump()
    nl = d["damping"]["nonlinear"]
    nl["lift_speed"] = lift_speed
    if mmg is not None:
        nl["lift"], nl["mmg"] = "mmg", dict(mmg)
    return Vessel.model_validate(d)


def drift_errors(pred, arrays, **kw) -> np.ndarray:
    """60-s absolute errors (logs, 20 intervals, north/east/heading) after each failure."""
    all_h = tuple(float(h) for h in range(1, 61))
    out = []
    for a in arrays:
        p, t, _ = metrics.drift_forecasts(pred, a, n_intervals=20, horizons_s=all_h, **kw)
        out.append(metrics.absolute_errors(p[:, [59]], t[:, [59]])[:, 0])
    return np.stack(out)


def astern_shares(logs: list[pd.DataFrame]) -> str:
    """The share of drift samples with the logged (over-ground) surge speed below zero and,
    from the simulator's true current, with the surge speed through the water ``u_r`` (what
    the lift terms use) below zero, pooled and per log."""
    def shares(x):
        drift = x.dp_active.to_numpy() == 0
        u = x.u_m_s.to_numpy(float)[drift]
        psi = np.radians(x.heading_deg.to_numpy(float)[drift])
        c = x.truth_current_speed_mps.to_numpy(float)[drift]
        beta = np.radians(x.truth_current_dir_to_deg.to_numpy(float)[drift])
        v_c = np.column_stack([c * np.cos(beta), c * np.sin(beta), np.zeros_like(c)])   # NED [m/s]
        return u, u - ned_to_body(v_c, psi)[:, 0]
    per = [shares(x) for x in logs]
    u, u_r = (np.concatenate(z) for z in zip(*per))
    each = ", ".join(f"{np.mean(a < 0):.2f}/{np.mean(b < 0):.2f}" for a, b in per)
    return (f"Drift samples moving astern, over ground / through the water (u < 0 / u_r < 0): "
            f"{np.mean(u < 0):.2f} / {np.mean(u_r < 0):.2f} of {u.size}; per log {each}.")


def truthsim_rows(logs: list[pd.DataFrame], hulls: dict[str, Vessel]) -> list[dict]:
    rows = []
    for name, vessel in hulls.items():
        arrays = [as_log_arrays(x, vessel) for x in logs]
        # scored on the training logs' own drifts: nothing is learned from them (drift_hull off)
        hp = HybridPredictor(vessel, ensemble_config=TINY, drift_hull=False).fit(arrays, dp_only=True)
        for model, e in (("physics", drift_errors(DynamicPredictor(vessel), arrays)),
                         ("estimator", drift_errors(hp, arrays, nets=False))):
            row = {"data": "truthsim-dev", "hull": name, "model": model}
            for j, state in enumerate(metrics.STATES):
                row[f"{state}_first5"] = e[:, :5, j].mean()
                row[f"{state}_first20"] = e[:, :, j].mean()
            rows.append(row)
            print({k: round(v, 3) if isinstance(v, float) else v for k, v in row.items()}, flush=True)
    return rows


def esso_rows(folder: Path) -> list[dict]:
    from hybridship.evaluation.manoeuvre import ManoeuvreConfig, error_table, forecast_errors, load_runs, start_rows

    cfg = ManoeuvreConfig()
    rows = []
    for lift_speed in ("abs", "signed"):
        v = with_lift(load_vessel("esso_osaka_model"), lift_speed)
        runs = load_runs(folder, v)
        p = DynamicPredictor(v, residual_config=cfg.residual)
        steps = np.array([int(round(30.0 / runs[0].arrays.dt_s))])
        per = {("physics", "known"): [
            forecast_errors(lambda a, st, h: p.forecast(a, st, horizon_s=h, commands="known"), r.arrays,
                            start_rows(r.arrays, int(steps.max()), cfg.start_every_s), steps) for r in runs]}
        e = error_table(per, runs, (30.0,))
        for kind, g in e.groupby("kind", sort=False):
            m = g.set_index("state")["mae"]
            rows.append({"data": "esso-osaka (30 s)", "hull": f"kvlcc2_mmg_{lift_speed}", "model": "physics",
                         "kind": kind, "distance_m": m["distance_m"], "heading_deg": m["heading_deg"]})
        print(rows[-1], flush=True)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    check_out(ap, args.out)
    if not (TRUTHSIM.is_dir() and REFERENCE.is_file()):
        print(f"skipping: {TRUTHSIM} or {REFERENCE} not found", file=sys.stderr)
        return 0
    gunnerus = load_vessel("gunnerus")
    pmm = pmm_mmg_derivatives(REFERENCE)
    hulls = {"clarke_abs (default)": gunnerus, "clarke_signed": with_lift(gunnerus, "signed"),
             "pmm_abs": with_lift(gunnerus, "abs", pmm), "pmm_signed": with_lift(gunnerus, "signed", pmm)}
    logs = [pd.read_csv(f) for f in log_files(TRUTHSIM)]
    drift = pd.DataFrame(truthsim_rows(logs, hulls))
    base = drift[(drift.hull == "clarke_abs (default)") & (drift.model == "physics")].iloc[0]
    md = ["Drift after the failure on truthsim-dev, 60 s, mean absolute error over the first 5 / "
          "first 20 intervals (north, east [m], heading [deg]); in brackets the ratio to the default "
          "hull's physics alone.", ""]
    tab = drift[["hull", "model"]].copy()
    for state in metrics.STATES:
        f5, f20 = drift[f"{state}_first5"], drift[f"{state}_first20"]
        tab[state] = [f"{a:.2f}/{b:.2f} ({a / base[f'{state}_first5']:.2f}/{b / base[f'{state}_first20']:.2f})"
                      for a, b in zip(f5, f20)]
    md += [markdown_table(tab), ""]
    md += [astern_shares(logs), ""]
    for name, dv in (("PMM (Hassani et al. 2015)", pmm), ("Clarke (default)", mmg_equivalent(gunnerus))):
        md += [f"{name} linear derivatives, MMG basis: " + ", ".join(f"{k}' = {v:.4f}" for k, v in dv.items()),
               ""]
    out = [drift]
    if ESSO.is_dir():
        esso = pd.DataFrame(esso_rows(ESSO))
        piv = esso.pivot_table(index="kind", columns="hull", values=["distance_m", "heading_deg"], sort=False)
        piv.columns = [f"{s} {h}" for s, h in piv.columns]
        md += ["Esso Osaka development runs, the physics alone, commands known, 30 s (distance [m], "
               "heading [deg]), lift terms with |u_r| and with u_r:", "",
               markdown_table(piv.reset_index().round(3)), ""]
        out.append(esso)
    else:
        print(f"skipping Esso Osaka: {ESSO} not found", file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    # 10 significant digits: the last bits of a sum can differ from run to run (summation order)
    csv = pd.concat(out, ignore_index=True).to_csv(index=False, float_format="%.10g").encode("utf-8")
    atomic_write(args.out / "hull_lift.csv", lambda fh: fh.write(csv))
    atomic_write(args.out / "hull_lift.md", lambda fh: fh.write("\n".join(md).encode("utf-8")))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
