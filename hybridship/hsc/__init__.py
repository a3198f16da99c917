"""High-speed (planing) craft: simulator, identified baselines and the residual hybrid.

Modules
-------
vessel          planing-craft vessel files (``kind = "planing_craft"``), e.g. ``volcano71``
simulator       Savitsky surge/heave/pitch simulator with engines, interceptor/tabs, waves
trials          the paper's simulated sea trials (sensors, GPS delay re-alignment, splits)
contract        the surge/pitch models' contract (``SurgePitchModel``) and input checks
identification  subspace state space, MIMO ARX and the paper's NARX network
hybrid          grey-box surge/pitch physics plus the residual ensemble
scoring         R and MAE as in the paper's Tables 1 and 2
benchmark       ``run_benchmark(out_dir, seed=0, quick=False, progress=True)``
"""
