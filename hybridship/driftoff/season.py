"""Season sweeps: many weather states x headings x samples, in one process or on Dask.

The states are cut into chunks of ``chunk_size`` consecutive states; one task runs one
chunk (:func:`run_chunk`: a :func:`~hybridship.driftoff.planning.simulate_blackouts` call
per state, reduced to summary numbers). With ``scheduler=None`` the chunks run in this
process; otherwise each chunk is a future of a :class:`dask.distributed.Client`
(``client.submit``, gathered with ``as_completed``): Dask schedules them, nothing here
does. ``scheduler="local"`` starts a :class:`~dask.distributed.LocalCluster` of
``n_workers`` single-threaded worker processes; any other string is the address of a
running scheduler (``tcp://host:8786``), e.g. a multi-machine cluster started with
``dask scheduler`` and ``dask worker`` (see ``docs/drift-off.md``).

Every state draws its samples from ``SeedSequence(seed, spawn_key=(state_index,))``, so
the result does not depend on the chunking or on where a chunk ran: single-process and
cluster runs are identical (a test checks it).

Dask is an optional extra: ``pip install -e ".[cluster]"``.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Iterable, Mapping, Set
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..config import as_config, check_flags
from .planning import DriftOffSettings, check_headings, simulate_blackouts
from .weather import WeatherState, WeatherUncertainty, label_list

__all__ = ["SeasonResult", "run_chunk", "season_sweep", "require_dask"]


def require_dask():
    """Import ``dask.distributed`` or raise an ImportError that says how to install it."""
    try:
        import dask.distributed as dd  # noqa: F401
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("drift-off sweeps on a cluster need Dask: pip install -e \".[cluster]\" "
                          "(or pip install \"dask[distributed]>=2024.1\"); run without a scheduler "
                          "to sweep in one process") from exc
    return dd


def run_chunk(vessel, states, indices, headings_rad, uncertainty, settings: DriftOffSettings,
              quantile: float, labels=None) -> dict:
    """Summaries of consecutive weather states (one Dask task).

    Returns arrays keyed by name, first axis = state: ``t_quantiles_s`` (S, H, R, 3) (10, 50,
    90 %), ``p_exceed`` (S, H, R, Q), ``watch_radius_m`` (S, H, Q), ``weather_rel_rad`` (S, H),
    ``reached_frac`` (S, H, R: the samples that reach the radius within the horizon),
    ``over_capacity_frac`` (S, H: :attr:`DriftOffResult.over_capacity_frac`), ``index`` (S,). A state whose drifts diverge gives ``{"index": ..., "error": message}``
    (naming the state's label from ``labels``, one per state), which :func:`season_sweep`
    raises: returned, not raised, so that a Dask worker does not log it as a crash.
    """
    tq, pe, wc, rel, reached, over = [], [], [], [], [], []
    for k, (state, i) in enumerate(zip(states, indices)):
        try:
            r = simulate_blackouts(vessel, state, headings_rad, uncertainty=uncertainty, settings=settings,
                                   index=int(i))
        except FloatingPointError as exc:
            label = "" if labels is None else f" (label {labels[k]!r})"
            return dict(index=np.asarray(indices, int), error=f"{exc}{label}")
        tq.append(r.time_quantiles((0.1, 0.5, 0.9)))
        pe.append(r.p_exceed())
        wc.append(r.watch_circle(quantile))
        rel.append(r.weather_rel_rad)
        reached.append(np.isfinite(r.t_reach_s).mean(axis=1))
        over.append(r.over_capacity_frac)
    return dict(index=np.asarray(indices, int), t_quantiles_s=np.array(tq), p_exceed=np.array(pe),
                watch_radius_m=np.array(wc), weather_rel_rad=np.array(rel), reached_frac=np.array(reached),
                over_capacity_frac=np.array(over))


@dataclass(frozen=True)
class SeasonResult:
    """Per-state summaries of a sweep (arrays as :func:`run_chunk`, states in input order).

    Attributes
    ----------
    labels : list of str
        Weather-state labels (e.g. the hindcast times).
    headings_rad, radii_m, reaction_times_s : ndarray
    quantile : float
        Quantile of the watch circles.
    t_quantiles_s, p_exceed, watch_radius_m, weather_rel_rad : ndarray
    wall_s : float
        Wall time of the sweep [s].
    n_samples : int
        Samples per state and heading.
    reached_frac : ndarray (S, H, R) or None
        Share of the samples that reach each radius within the horizon.
    over_capacity_frac : ndarray (S, H) or None
        Share of the samples over the thrusters' capacity before the blackout
        (:attr:`~hybridship.driftoff.planning.DriftOffResult.over_capacity_frac`).
    """

    labels: list
    headings_rad: np.ndarray
    radii_m: np.ndarray
    reaction_times_s: np.ndarray
    quantile: float
    t_quantiles_s: np.ndarray
    p_exceed: np.ndarray
    watch_radius_m: np.ndarray
    weather_rel_rad: np.ndarray
    wall_s: float
    n_samples: int
    reached_frac: np.ndarray | None = None
    over_capacity_frac: np.ndarray | None = None

    def to_frame(self) -> pd.DataFrame:
        """Tidy table: one row per (state, heading, radius); watch radii as columns per reaction time."""
        S, H, R = self.p_exceed.shape[:3]
        rows = []
        for s in range(S):
            for h in range(H):
                for r in range(R):
                    row = {"state": s, "label": self.labels[s],
                           "heading_deg": math.degrees(self.headings_rad[h]) % 360.0,
                           "wind_rel_deg": math.degrees(self.weather_rel_rad[s, h]) % 360.0,
                           "radius_m": self.radii_m[r], "t_p10_s": self.t_quantiles_s[s, h, r, 0],
                           "t_p50_s": self.t_quantiles_s[s, h, r, 1], "t_p90_s": self.t_quantiles_s[s, h, r, 2]}
                    if self.reached_frac is not None:       # as in a planning report's times.csv
                        row["reached_frac"] = self.reached_frac[s, h, r]
                    if self.over_capacity_frac is not None:
                        row["over_capacity_frac"] = self.over_capacity_frac[s, h]
                    for q, tr in enumerate(self.reaction_times_s):
                        row[f"p_exceed_{tr:g}s"] = self.p_exceed[s, h, r, q]
                    for q, tr in enumerate(self.reaction_times_s):
                        row[f"watch_{tr:g}s_m"] = self.watch_radius_m[s, h, q]
                    rows.append(row)
        return pd.DataFrame(rows)

    def operability(self, max_p_exceed: float = 0.1) -> pd.DataFrame:
        """Per heading, radius and reaction time: the share of states with P(exceed) <= ``max_p_exceed``."""
        if (isinstance(max_p_exceed, bool) or not isinstance(max_p_exceed, numbers.Real)
                or not 0.0 <= float(max_p_exceed) <= 1.0):
            raise ValueError(f"max_p_exceed: expected a probability in [0, 1], got {max_p_exceed!r}")
        rows = []
        for h, psi in enumerate(self.headings_rad):
            for r, rad in enumerate(self.radii_m):
                for q, tr in enumerate(self.reaction_times_s):
                    rows.append({"heading_deg": math.degrees(psi) % 360.0, "radius_m": rad, "reaction_time_s": tr,
                                 "operable_frac": float(np.mean(self.p_exceed[:, h, r, q] <= max_p_exceed)),
                                 "median_t_p10_s": float(np.median(self.t_quantiles_s[:, h, r, 0]))})
        return pd.DataFrame(rows)


def _client(scheduler, n_workers):
    dd = require_dask()
    if scheduler == "local":
        cluster = dd.LocalCluster(n_workers=int(n_workers), threads_per_worker=1, processes=True,
                                  dashboard_address=":0", env={"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"})
        try:
            return dd.Client(cluster), cluster
        except BaseException:
            cluster.close()     # its worker processes would outlive the failed call
            raise
    if hasattr(scheduler, "submit"):      # a Client given by the caller
        return scheduler, None
    try:
        return dd.Client(str(scheduler)), None
    except (OSError, ValueError, TypeError) as exc:  # dask's own words, with the argument named
        raise OSError(f"scheduler {str(scheduler)!r}: could not connect ({' '.join(str(exc).split())}); "
                      f"expected 'local', no scheduler or a running scheduler's address such as tcp://host:8786") from None
    except MemoryError:     # another service answered: dask read its reply's first bytes as a frame's length
        raise OSError(f"scheduler {str(scheduler)!r}: could not connect (what answers there does not speak Dask's "
                      f"protocol); expected 'local', no scheduler or a running scheduler's address such as "
                      f"tcp://host:8786") from None


def season_sweep(vessel, states, headings_rad, *, uncertainty: WeatherUncertainty | None = None,
                 settings: DriftOffSettings | None = None, labels=None, quantile: float = 0.9,
                 scheduler=None, n_workers: int = 2, chunk_size: int = 24, progress: bool = True) -> SeasonResult:
    """Sweep weather states x headings x samples (see the module notes).

    Parameters
    ----------
    vessel : str or Vessel
        Packaged vessel name or vessel-file path (sent to the workers), or a Vessel.
    states : WeatherState or sequence of WeatherState
        The weather states in order; one state is a sweep of one.
    headings_rad : array_like (H,)
    uncertainty : WeatherUncertainty, optional
        Applied to every state.
    settings : DriftOffSettings, optional
    labels : sequence of str, optional
        One per state (default: the index).
    quantile : float
        Watch-circle quantile.
    scheduler : None, "local", an address string or a dask.distributed.Client
        Where the chunks run (None: this process).
    n_workers : int
        Workers of the LocalCluster (``scheduler="local"``).
    chunk_size : int
        Weather states per task.
    progress : bool
        Show a tqdm progress bar over the states.
    """
    if isinstance(states, WeatherState):
        states = [states]          # one state, as simulate_blackouts takes it: a sweep of one
    elif isinstance(states, (Set, Mapping)) or not isinstance(states, Iterable):   # a set has no order for the labels
        raise TypeError(f"states: expected a WeatherState or a list of them, got {type(states).__name__}")
    states = list(states)
    if not states:
        raise ValueError("states: expected at least one weather state")
    for i, s in enumerate(states):
        if not isinstance(s, WeatherState):
            raise TypeError(f"states[{i}]: expected a WeatherState, got {type(s).__name__}")
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise ValueError(f"chunk_size: expected a positive int, got {chunk_size!r}")
    if isinstance(n_workers, bool) or not isinstance(n_workers, (int, np.integer)) or n_workers < 1:
        raise ValueError(f"n_workers: expected a positive int, got {n_workers!r}")
    if isinstance(quantile, bool) or not isinstance(quantile, (int, float, np.integer, np.floating)) \
            or not 0.0 < float(quantile) < 1.0:
        raise ValueError(f"quantile: expected a number in (0, 1), got {quantile!r}")
    check_flags(progress=progress)          # a text "no" is truthy and would show the bar
    if uncertainty is not None and not isinstance(uncertainty, WeatherUncertainty):   # not each worker's failure
        raise TypeError(f"uncertainty: expected a WeatherUncertainty or None, got {type(uncertainty).__name__}")
    st = as_config(settings, DriftOffSettings, "settings") if settings is not None else DriftOffSettings()
    psi = check_headings(headings_rad)
    labels = ([str(i) for i in range(len(states))] if labels is None
              else [str(x) for x in label_list(labels, len(states))])     # text is no list of labels
    if len(set(labels)) != len(labels):     # the season table's rows would not say which state they are
        raise ValueError(f"labels: expected distinct labels (a weather table's time column names each state once), "
                         f"got {next(x for x in labels if labels.count(x) > 1)!r} more than once")
    chunks = [(states[i:i + chunk_size], list(range(i, min(i + chunk_size, len(states)))))
              for i in range(0, len(states), chunk_size)]

    def collected(out: dict) -> dict:
        if "error" in out:
            raise FloatingPointError(out["error"])
        return out
    from tqdm.auto import tqdm

    bar = tqdm(total=len(states), unit="state", desc="drift-off sweep", disable=not progress)
    t0 = time.perf_counter()
    parts = []
    try:
        if scheduler is None:
            for ch, idx in chunks:
                parts.append(collected(run_chunk(vessel, ch, idx, psi, uncertainty, st, quantile,
                                                 [labels[i] for i in idx])))
                bar.update(len(idx))
        else:
            dd = require_dask()
            client, cluster = _client(scheduler, n_workers)
            try:
                futs = [client.submit(run_chunk, vessel, ch, idx, psi, uncertainty, st, quantile,
                                      [labels[i] for i in idx], pure=False)
                        for ch, idx in chunks]
                for fut in dd.as_completed(futs):
                    out = collected(fut.result())
                    parts.append(out)
                    bar.update(len(out["index"]))
            finally:
                if client is not scheduler:      # made here (for "local" or an address): closed here
                    client.close()
                if cluster is not None:
                    cluster.close()
    finally:
        bar.close()
    wall = time.perf_counter() - t0
    parts.sort(key=lambda p: int(p["index"][0]))
    cat = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    return SeasonResult(labels=labels, headings_rad=psi, radii_m=np.asarray(st.radii_m),
                        reaction_times_s=np.asarray(st.reaction_times_s), quantile=float(quantile),
                        t_quantiles_s=cat["t_quantiles_s"], p_exceed=cat["p_exceed"],
                        watch_radius_m=cat["watch_radius_m"], weather_rel_rad=cat["weather_rel_rad"], wall_s=wall,
                        n_samples=st.n_samples, reached_frac=cat["reached_frac"],
                        over_capacity_frac=cat["over_capacity_frac"])
