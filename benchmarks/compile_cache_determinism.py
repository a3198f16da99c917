"""Do the compiled kernels give the same bits whether numba compiles them now or loads them
from its on-disk cache?

Runs a child process twice on a copy of the package in a temporary folder: first with the
copy's compiled-kernel cache emptied (the kernels are compiled), then with the cache the
first run wrote (the kernels are loaded). Each child prints a digest of a 300-step physics
rollout (``DynamicModel.rollout``), one acceleration and one step, for the Gunnerus and
for the Esso Osaka model (which has a rudder), and of a simulated DP-loss log (seed 0, 10
minutes of DP, 5 of drift). Equal digests: the bits do not depend on
the cache. Prints per vessel ``same`` or ``differ`` per quantity, and the rollouts' largest
difference.

Usage::

    python benchmarks/compile_cache_determinism.py
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import hashlib, sys
import numpy as np
from hybridship.physics.model import DynamicModel

def digest(x):
    return hashlib.sha256(np.ascontiguousarray(x).tobytes()).hexdigest()[:12]

for name, rpm, az, dt in (("gunnerus", [[100.0, 100.0, 100.0]], [[0.0, 0.3, -0.3]], 1.0),
                          ("esso_osaka_model", [[600.0, 0.0]], [[0.0, 0.2]], 0.1)):
    m = DynamicModel(name)
    eta, nu = np.zeros((4, 3)), np.tile([[0.4, 0.02, 0.01]], (4, 1))
    r = m.rollout(eta, nu, 300, dt_s=dt, rpm=rpm, azimuth_rad=az, wind=[[8.0, 1.0]])
    a = m.acceleration(eta, nu, rpm=rpm, azimuth_rad=az, wind=[[8.0, 1.0]])
    s = m.step(eta, nu, dt_s=dt, rpm=rpm, azimuth_rad=az, wind=[[8.0, 1.0]])
    print(name, digest(r.eta), digest(a), digest(s[0]))
    np.save(f"{sys.argv[1]}_{name}.npy", r.eta)

from hybridship.sim.scenario import DPLossConfig, simulate_dp_loss
log = simulate_dp_loss(DPLossConfig(seed=0, t_shutdown_s=600.0, drift_s=300.0))
print("simulator", digest(log.select_dtypes("number").to_numpy(float)), "-", "-")
np.save(f"{sys.argv[1]}_simulator.npy", log.select_dtypes("number").to_numpy(float))
"""


def _run(copy: Path, tag: str) -> list[list[str]]:
    out = subprocess.run([sys.executable, "-c", CHILD, tag], cwd=copy, capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(copy), "PATH": "/usr/bin:/bin", "NUMBA_NUM_THREADS": "1"})
    return [line.split() for line in out.stdout.splitlines()]


def compiled_and_loaded() -> tuple[list[list[str]], list[list[str]], dict[str, float]]:
    """Digest rows (name, digests...) of the child run that compiles the kernels and of the one
    that loads them, and per case the largest difference between the two runs' arrays."""
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp)
        shutil.copytree(ROOT / "hybridship", copy / "hybridship",
                        ignore=shutil.ignore_patterns("*.nbi", "*.nbc", "compiled-kernels.sha256"))
        # the packaged vessel files, where a source tree keeps them (an installed hybridship
        # maps them as hybridship.vessels, which the copy on PYTHONPATH does not have)
        shutil.copytree(ROOT / "vessels", copy / "vessels")
        compiled, loaded = _run(copy, "compiled"), _run(copy, "loaded")
        gaps = {a[0]: float(np.abs(np.load(copy / f"compiled_{a[0]}.npy") - np.load(copy / f"loaded_{a[0]}.npy")).max())
                for a in compiled}
    return compiled, loaded, gaps


def main(argv=None) -> int:
    # no options; --help (or a misspelt option) ran the whole check without a word on it
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args(argv)
    compiled, loaded, gaps = compiled_and_loaded()
    for a, b in zip(compiled, loaded):
        same = ["same" if x == y else "differ" for x, y in zip(a[1:], b[1:])]
        gap = gaps[a[0]]
        if a[0] == "simulator":
            print(f"simulator: log {same[0]} (largest difference {gap:.1e}; compiled {a[1]}, loaded {b[1]})")
            continue
        print(f"{a[0]}: rollout {same[0]} (largest difference {gap:.1e} m or rad), acceleration {same[1]}, "
              f"step {same[2]} (compiled {' '.join(a[1:])}; loaded {' '.join(b[1:])})")
    return 0

if __name__ == "__main__":
    sys.exit(main())
