"""The model file of :class:`~hybridship.predictors.hybrid.HybridPredictor`: format version,
errors, writing and reading (in named steps), content checksum and the embedded vessel.

A model file is one ``.npz`` (arrays only, read with ``allow_pickle=False``) whose JSON
metadata carry the validated vessel description, so a model loads without its vessel file
and without executing code from the file.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..config import check_number, real_array
from ..fileio import as_path, atomic_write, starts_with
from ..forecast_inputs.wind import WindForecast
from ..residual.calibration import CalibrationConfig, SpreadCalibration
from ..residual.ensemble import EnsembleConfig, MLPEnsemble
from ..residual.environment import EnvironmentConfig, EnvironmentEstimator
from ..residual.features import ResidualConfig
from ..residual.guard import CommandRegime, EnvelopeGuard, ThrustRegime
from ..residual.hull import HullCorrection
from ..residual.multistep import MultiStepConfig
from .forecast_setup import AFTER_STOP, AFTER_STOP_LATE, COMMAND_MODES

__all__ = ["MODEL_FORMAT_VERSION", "ModelFileError", "load_model", "model_metadata", "save_model"]

#: Version of the model-file format written by :func:`save_model` (:meth:`HybridPredictor.save`).
#: 21: the NED load's prior narrowed across the wind (``environment_config.load_prior_across_wind``;
#: older files read 1, the same prior in every direction, as they were fitted);
#: 20: the current's prior scaled by the wind at the filter's start (``environment_config.
#: current_prior_wind_ref_m_s``, ``current_prior_max_m_s``; older files read None, a fixed
#: prior, as they were fitted);
#: 19: the yaw load turned with the waves chosen by ``fit`` (``environment_config.wave_turned_yaw_load``
#: may be ``"auto"``, and ``wave_yaw_turned`` records the choice; older files read False);
#: 18: the environment load's random walks while the thrusters are stopped
#: (``environment_config.load_walk_after_stop_m_s2``, ``load_yaw_walk_after_stop_rad_s2``;
#: older files read the station-keeping walks, as they were fitted);
#: 17: the environment estimator filters across short gaps (``environment_config.max_bridged_gap_s``;
#: older files read 0, every gap restarting the filter, as they were fitted);
#: 16: the step of the one-step residual fit (``residual_config.residual_step_s``; older files
#: read None, the log's own step, as they were fitted);
#: 15: the actuator-load features (``residual_config.features`` may name them, so an older
#: hybridship says "another version" of such a file instead of "damaged");
#: 14: the environment estimator's settling time (``environment_config.settle_s``);
#: 13: the metadata's own checksum (``metadata_sha256``: an edited setting, such as the feature
#: order or the spread calibration, no longer loads silently);
#: 12: the command-memory features and their time constant (``residual_config.command_memory_s``);
#: 11: the environment estimator uses the hull's yaw moment in a drift after a failure too
#: (``drift_yaw_in_filter``); 10: the hull's yaw moment in a drift (``drift_hull``, ``drift_yaw_uv_rad_per_m2``);
#: 9: the wind futures of the spread (``wind_samples`` and the wind forecast's error
#: paths, ``wind_error_paths``); 8: the spread calibration's exponent (a fourth row of
#: ``cal_*``, the value at every lead); 7: the wind forecast (``wind_forecast``: the fitted gust decay, or held); 6: the
#: environment estimator's thrust-model error per thruster (its prior has one entry
#: per thruster); 5: the spread calibration, the nets' training mode and the command regime; 4: the
#: validated vessel description is embedded in the metadata (``vessel_description``), so a
#: model loads without its vessel file; 3 added the environment estimator; 2 and earlier
#: stored only the vessel's name.
MODEL_FORMAT_VERSION = 21
#: Versions :func:`load_model` reads: a version-7 file is a version-8 one without the spread
#: exponent (three rows per ``cal_*`` array), read as exponent 1, which is what it was fitted with;
#: versions 7 and 8 have no wind futures in the spread (``wind_samples = 0``, as they were fitted);
#: versions 7 to 9 no hull's yaw moment in a drift (``drift_hull`` off, ``k = 0``); in version 10
#: only the forecasts use it, not the environment estimator (``drift_yaw_in_filter`` false), as
#: its coefficient was chosen; versions 7 to 11 use no command memory (the time constant is
#: the default, unused); versions 7 to 12 carry no checksum of their metadata; versions 7 to
#: 13 no settling of the environment estimator (``settle_s = 0``, as they were fitted); versions 7 to
#: 14 no actuator-load features; versions 7 to 15 were fitted at the logs' own step
#: (``residual_step_s = None``); versions 7 to 16 restart the environment estimator at every
#: gap of a log (``max_bridged_gap_s = 0``); versions 7 to 17 filter a drift with the station
#: keeping's load walks; versions 7 to 18 choose no yaw load turned with the waves (``wave_yaw_turned``
#: false; their ``wave_turned_yaw_load`` is true or false, false where the file predates it);
#: versions 7 to 19 take the current's prior as fixed (``current_prior_wind_ref_m_s = None``);
#: versions 7 to 20 take the load's prior as the same in every direction (``load_prior_across_wind = 1``).
READABLE_MODEL_FORMAT_VERSIONS = (7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21)


class ModelFileError(ValueError):
    """A model file is unreadable, tampered, truncated, from another version or vessel."""


def _embedded_vessel(description, path):
    """The :class:`~hybridship.vessel.Vessel` embedded in a model file's metadata (validated again)."""
    from ..vessel import VesselFileError, vessel_from_dict

    if not isinstance(description, dict):
        raise ModelFileError(f"{path}: damaged model metadata: vessel_description is not a table")
    try:
        return vessel_from_dict(description, source=f"{Path(path).name} (embedded vessel)")
    except VesselFileError as err:
        raise ModelFileError(f"{path}: damaged model metadata: the embedded vessel is invalid: {err}") from None


def _content_hash(arrays: dict) -> str:
    """sha256 over every array's name, dtype, shape and bytes (sorted by name)."""
    import hashlib

    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _metadata_hash(meta: dict) -> str:
    """sha256 of the metadata's canonical JSON, without its own checksum (``metadata_sha256``)."""
    import hashlib

    body = {k: v for k, v in meta.items() if k != "metadata_sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode("utf-8")).hexdigest()


def _vessel_fingerprint(vessel) -> str:
    """A stable hash of the validated vessel description (so a model is not used on another ship)."""
    from ..vessel import fingerprint

    return fingerprint(vessel)


# --------------------------------------------------------------------------- writing


def model_metadata(predictor) -> dict:
    """The JSON metadata of a fitted :class:`~hybridship.predictors.hybrid.HybridPredictor`:
    settings, the embedded vessel and its fingerprint, the scalar learned state."""
    from ..vessel import portable_description

    p = predictor
    v = p.model.vessel
    return {
        "format": "hybridship-model", "format_version": MODEL_FORMAT_VERSION,
        "kind": "HybridPredictor", "vessel": v.name,
        "vessel_description": portable_description(v),
        "vessel_fingerprint": _vessel_fingerprint(v),
        "features": list(p.residual_config.features),
        "residual_config": asdict(p.residual_config),
        "ensemble_config": asdict(p.ensemble_config),
        "use_guard": p.use_guard, "guard_quantile": p.guard_quantile,
        "stop_after_failure": p.stop_after_failure,
        "guard": {"d0": p.guard.d0, "scale": p.guard.scale},
        "thrust_regime": {"lo": p.thrust_regime.lo},
        "environment": p.environment,
        "environment_config": p.environment_config.model_dump(mode="json"),
        "environment_window_s": p.environment_window_s,
        "nets_after_stop": p.nets_after_stop,
        "thrust_error_prior": {"mean": p.estimator.thrust_error_mean.tolist(),
                               "std": p.estimator.thrust_error_std.tolist()},
        "calibration_config": asdict(p.calibration_config),
        "training": p.training, "multistep_config": asdict(p.multistep_config),
        "command_guard": p.command_guard,
        "hull_correction": p.hull_correction, "hull_ridge": p.hull_ridge, "hull_fit": p.hull_fit, "has_hull": p.hull is not None,
        "command_regime": None if p.command_regime is None else {
            k: getattr(p.command_regime, k) for k in ("rpm_eps", "froude_lo", "angle_hard_rad", "length_m")},
        "calibrated_commands": sorted(p.calibration),
        "wind_forecast": {"option": "fit" if p.wind_forecast_option == "fit" else "given",
                          **asdict(p.wind_forecast)},
        "wind_samples": p.wind_samples, "wind_error_dt_s": p.wind_error_dt_s,
        "has_wind_error_paths": p.wind_error_paths is not None,
        "drift_hull": p.drift_hull, "drift_yaw_uv_rad_per_m2": p.drift_yaw_uv_rad_per_m2,
        "drift_yaw_in_filter": p._drift_yaw_in_filter, "wave_yaw_turned": p.wave_yaw_turned,
        "training_info": p.training_info,
    }


def save_model(predictor, path) -> Path:
    """Write a fitted hybrid as one ``.npz`` (arrays only, no pickle) with JSON metadata, atomically."""
    p = predictor
    path = as_path(path)
    if path.suffix.lower() != ".npz":
        raise ValueError(f"path: {path}: expected a .npz model file name")
    if path.exists() and not path.is_file():
        raise ValueError(f"path: {path}: exists and is not a file")
    if path.is_file() and path.stat().st_size and not is_model_file(path):
        # a user's own archive or file under that name: never replaced (as 'hybridship train --out')
        raise ValueError(f"path: {path}: exists and is not a hybridship model file (it would be lost); give "
                         f"another path or remove it")
    e, g = p.ensemble, p.guard
    arrays = {f"w{i}": w for i, w in enumerate(e.weights)}
    arrays.update(x_mean=e.x_mean, x_std=e.x_std, y_mean=e.y_mean, y_std=e.y_std,
                  guard_mean=g.mean, guard_inv_cov=g.inv_cov, thrust_scale=p.thrust_regime.scale)
    if p.command_regime is not None:
        cr = p.command_regime
        arrays.update(cmd_regime_weights=cr.weights, cmd_regime_n_train=cr.n_train, cmd_regime_n_held=cr.n_held)
    if p.hull is not None:
        arrays.update(p.hull.arrays())
    if p.wind_error_paths is not None:
        arrays["wind_error_paths"] = p.wind_error_paths
    for mode, c in p.calibration.items():
        for what, sc in c.items():
            arrays[f"cal_{mode}_{what}"] = np.stack([sc.lead_s, sc.scale, sc.floor,
                                                     np.full(sc.lead_s.size, sc.exponent)])
    meta_d = model_metadata(p)
    meta_d["content_sha256"] = _content_hash(arrays)
    meta_d["metadata_sha256"] = _metadata_hash(meta_d)
    meta = json.dumps(meta_d, sort_keys=True)
    arrays["metadata_json"] = np.frombuffer(meta.encode("utf-8"), dtype=np.uint8)
    return atomic_write(path, lambda fh: np.savez(fh, **arrays))


# --------------------------------------------------------------------------- reading


def is_model_file(path) -> bool:
    """Whether ``path`` is a hybridship model file of any format version (its metadata says
    so; read without pickles), so that writing a new model there loses nothing else."""
    try:
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            meta = json.loads(bytes(z["metadata_json"]).decode("utf-8")) if "metadata_json" in z.files else None
    except Exception:  # not an archive, damaged, pickled, unreadable: not a model file
        return False
    return isinstance(meta, dict) and meta.get("format") == "hybridship-model"


def load_model(cls, path, vessel=None):
    """Load a model file written by :func:`save_model` as an instance of ``cls`` (never executes
    code from the file); see :meth:`~hybridship.predictors.hybrid.HybridPredictor.load`.

    The steps: read the arrays, check the header (format, version) and the content
    checksum, build the predictor from its settings and vessel (checking the vessel against
    the fingerprint before any setting that depends on it), then restore the learned state
    (nets, guard, thrust regime, spread calibration, environment prior, command regime).
    """
    path = as_path(path)
    data = _read_arrays(path)
    meta = _read_checked_metadata(data, path)
    obj, embedded, state = _build_predictor(cls, meta, vessel, path)   # checks the vessel
    _restore_learned_state(obj, data, state, path)
    try:
        obj.training_info = _checked_training_info(meta.get("training_info", {}))
    except (TypeError, ValueError) as err:
        raise ModelFileError(f"{path}: damaged model metadata ({err})") from None
    return obj


def _checked_training_info(info) -> dict:
    """``training_info``: a record of the fit, of which forecasts read four entries; each
    checked for what they read (ValueError or TypeError naming the entry otherwise)."""
    if not isinstance(info, dict):
        raise ValueError(f"training_info: expected a table of entries, got {type(info).__name__}")
    steps = info.get("log_step_s")
    if steps is not None and not (isinstance(steps, list) and steps and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and x > 0 for x in steps)):
        raise ValueError(f"training_info.log_step_s: expected a list of positive steps [s], got {steps!r}")
    if not isinstance(info.get("trained_with_wind", False), bool):
        raise ValueError("training_info.trained_with_wind: expected true or false")
    calibration = info.get("calibration", {})
    if not isinstance(calibration, dict) or not isinstance(calibration.get("dp_only", False), bool):
        raise ValueError("training_info.calibration: expected a table whose dp_only is true or false")
    after_stop = calibration.get("after_stop", {})
    if not isinstance(after_stop, dict):
        raise ValueError(f"training_info.calibration.after_stop: expected a table, got {after_stop!r}")
    if "starts_within_s" in after_stop:
        check_number("training_info.calibration.after_stop.starts_within_s", after_stop["starts_within_s"],
                     lo=0.0, lo_open=True)
    return info


def _read_arrays(path: Path) -> dict:
    """Every array of the ``.npz`` file (``allow_pickle=False``)."""
    try:
        # the file opened here, so that it is closed even when numpy fails to parse it
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise ModelFileError(f"{path}: model file not found") from None
    except IsADirectoryError:
        raise ModelFileError(f"{path}: is a folder; expected a model file (.npz)") from None
    except PermissionError:
        raise ModelFileError(f"{path}: cannot be read (no permission)") from None
    except Exception as err:  # zip/npy parse errors of a damaged file
        raise ModelFileError(f"{path}: not a readable hybridship model file ({_why_unreadable(path, err)})") from None


def _why_unreadable(path: Path, err: Exception) -> str:
    """What the file is instead of a model file, from its first bytes (numpy's own message
    suggests loading pickles, which a model file never needs)."""
    if path.stat().st_size == 0:
        return "the file is empty"
    if starts_with(path, b"PK"):
        return ("an archive holding pickled objects, which hybridship never loads (they could run code)"
                if "pickle" in str(err) or "Object arrays" in str(err) else "a damaged .npz archive")
    if starts_with(path, b"\x93NUMPY"):
        return "a single .npy array, not the .npz archive a model file is"
    if starts_with(path, b"\x80"):
        return "a pickle file, which hybridship never loads (it could run code)"
    return "not an .npz archive (a text or other file)"


def _read_checked_metadata(data: dict, path: Path) -> dict:
    """The JSON metadata, after the format, version and content-checksum checks."""
    try:
        meta = json.loads(bytes(data["metadata_json"]).decode("utf-8"))
    except Exception:
        raise ModelFileError(f"{path}: metadata missing or damaged") from None
    if not isinstance(meta, dict) or meta.get("format") != "hybridship-model":
        raise ModelFileError(f"{path}: not a hybridship model file")
    version = meta.get("format_version")
    if not isinstance(version, int) or version not in READABLE_MODEL_FORMAT_VERSIONS or isinstance(version, bool):
        whole = isinstance(version, int) and not isinstance(version, bool)
        if whole and 1 <= version < READABLE_MODEL_FORMAT_VERSIONS[0]:
            why = (f": written by an older hybridship (format {version}); retrain with `hybridship train` "
                   f"(or HybridPredictor.fit) to write a version-{MODEL_FORMAT_VERSION} file, which carries "
                   f"its vessel, its environment estimator and its spread calibration")
        elif whole and version > MODEL_FORMAT_VERSION:
            why = f": written by a newer hybridship (format {version}); upgrade hybridship to read it"
        else:       # not a whole number (text "13", 13.0, null): said as written, not as 13
            why = "" if whole else "; expected a whole number"
        raise ModelFileError(f"{path}: model format version {version if whole else json.dumps(version)} is not "
                             f"supported (this hybridship reads versions "
                             f"{', '.join(str(v) for v in READABLE_MODEL_FORMAT_VERSIONS)}){why}")
    # checked whenever present: a version-13 file relabelled as 12 would otherwise skip it
    if (version >= 13 or "metadata_sha256" in meta) and meta.get("metadata_sha256") != _metadata_hash(meta):
        raise ModelFileError(f"{path}: metadata checksum does not match: the model's settings were edited "
                             f"or damaged")
    content = {k: v for k, v in data.items() if k != "metadata_json"}
    if meta.get("content_sha256") != _content_hash(content):
        raise ModelFileError(f"{path}: content checksum does not match the metadata: the file was "
                             f"tampered with or damaged")
    return meta


def _read_wind_forecast(d: dict) -> WindForecast:
    """The wind forecast the model was fitted with (a fitted one is fixed from then on)."""
    if not isinstance(d, dict) or d.get("option", "given") not in ("fit", "given"):
        raise ValueError(f"wind_forecast: expected a table of settings with option 'fit' or 'given', got {d!r}")
    return WindForecast(**{k: v for k, v in d.items() if k != "option"})


def _build_predictor(cls, meta: dict, vessel, path: Path):
    """``(predictor, embedded, state)``: an unfitted ``cls`` with the file's settings, for
    ``vessel`` or else the embedded vessel (``embedded``), and the scalar learned state."""
    from pydantic import ValidationError

    from ..config import format_validation_error
    from ..vessel import Vessel, load_vessel

    if vessel is not None and not isinstance(vessel, Vessel):
        vessel = load_vessel(vessel)        # the caller's argument: its errors are not the file's
    try:
        for key in ("residual_config", "ensemble_config", "environment_config", "calibration_config",
                    "multistep_config"):
            if not isinstance(meta[key], dict):
                raise ValueError(f"{key}: expected a table of settings, got {meta[key]!r}")
        if not isinstance(meta["residual_config"].get("features", []), list):
            raise ValueError(f"residual_config.features: expected a list of feature names, got "
                             f"{meta['residual_config']['features']!r}")
        if meta["format_version"] >= 12 and "command_memory_s" not in meta["residual_config"]:
            raise KeyError("residual_config.command_memory_s")     # older files read the default, unused
        if meta["format_version"] >= 14 and "settle_s" not in meta["environment_config"]:
            raise KeyError("environment_config.settle_s")          # older files read 0, as they were fitted
        if meta["format_version"] >= 16 and "residual_step_s" not in meta["residual_config"]:
            raise KeyError("residual_config.residual_step_s")
        if meta["format_version"] >= 17 and "max_bridged_gap_s" not in meta["environment_config"]:
            raise KeyError("environment_config.max_bridged_gap_s")
        env = meta["environment_config"]
        for after_stop, on_station in (("load_walk_after_stop_m_s2", "load_walk_m_s2"),
                                       ("load_yaw_walk_after_stop_rad_s2", "load_yaw_walk_rad_s2")):
            if meta["format_version"] >= 18 and after_stop not in env:
                raise KeyError(f"environment_config.{after_stop}")
            # older files filtered a drift with the station keeping's walks, as they were fitted
            env = {after_stop: env.get(on_station, EnvironmentConfig.model_fields[on_station].default), **env}
        if meta["format_version"] >= 19 and "wave_turned_yaw_load" not in env:
            raise KeyError("environment_config.wave_turned_yaw_load")
        # files from before the option held the yaw load, as they were fitted (the default is now "auto")
        env = {"wave_turned_yaw_load": False, **env}
        for key, since in (("current_prior_wind_ref_m_s", 20), ("current_prior_max_m_s", 20),
                           ("load_prior_across_wind", 21)):
            # older files read the defaults: a fixed current prior and a load prior alike in every
            # direction, as they were fitted
            if meta["format_version"] >= since and key not in env:
                raise KeyError(f"environment_config.{key}")
        residual_config = ResidualConfig(**{"residual_step_s": None,     # older files: fitted at the log's step
                                            **{k: tuple(v) if k == "features" else v
                                               for k, v in meta["residual_config"].items()}})
        embedded = vessel is None
        if embedded:
            vessel = _embedded_vessel(meta["vessel_description"], path)
        obj = cls(vessel, residual_config=residual_config,
                  ensemble_config=EnsembleConfig(**meta["ensemble_config"]), guard=_checked_flag(meta, "use_guard"),
                  guard_quantile=meta["guard_quantile"],
                  stop_after_failure=_checked_flag(meta, "stop_after_failure"),
                  environment=meta["environment"],
                  # older files restarted the filter at every gap, as they were fitted
                  environment_config=EnvironmentConfig(**{"max_bridged_gap_s": 0.0, **env}),
                  environment_window_s=_checked_number(meta, "environment_window_s"),
                  nets_after_stop=_checked_flag(meta, "nets_after_stop"),
                  # files written before the option calibrated the members' spread
                  calibration_config=CalibrationConfig(**{"station_keeping_spread": "ensemble",
                                                          **meta["calibration_config"]}),
                  training=meta["training"], multistep_config=MultiStepConfig(**meta["multistep_config"]),
                  command_guard=meta["command_guard"], hull_correction=meta.get("hull_correction", False),
                  hull_ridge=meta.get("hull_ridge", 1e-3), hull_fit=meta.get("hull_fit", "one_step"),
                  wind_forecast=_read_wind_forecast(meta["wind_forecast"]),
                  wind_samples=meta["wind_samples"] if meta["format_version"] >= 9 else 0,
                  drift_hull=_checked_flag(meta, "drift_hull") if meta["format_version"] >= 10 else False)
        if meta["format_version"] >= 9:
            obj.wind_error_dt_s = _checked_wind_error_dt(meta["wind_error_dt_s"])
        # the vessel first: the drift-yaw candidates below are multiples of this vessel's Munk
        # coefficient, and another vessel's model must be refused as such
        _check_vessel(obj, meta, meta["vessel_fingerprint"], embedded, path)
        if meta["format_version"] >= 10:
            obj.drift_yaw_uv_rad_per_m2 = _checked_drift_yaw(meta["drift_yaw_uv_rad_per_m2"], obj)
            obj._drift_yaw_in_filter = _checked_flag(meta, "drift_yaw_in_filter") if meta["format_version"] >= 11 \
                else False
        if meta["format_version"] >= 19:
            obj.wave_yaw_turned = _checked_flag(meta, "wave_yaw_turned")
            if obj.wave_yaw_turned and obj.environment_config.wave_turned_yaw_load != "auto":
                raise ValueError("wave_yaw_turned: true in a model whose environment_config.wave_turned_yaw_load "
                                 "is not 'auto' (only 'auto' is chosen by fit)")
        if meta["wind_forecast"].get("option") == "fit":
            obj.wind_forecast_option = "fit"       # a refit chooses again; forecasts use the fitted one
        state = _scalar_state(meta)
        state["format_version"] = meta["format_version"]
    except ValidationError as err:
        raise ModelFileError(f"{path}: damaged model metadata ({format_validation_error(err)})") from None
    except KeyError as err:
        raise ModelFileError(f"{path}: damaged model metadata ({err.args[0]}: missing)") from None
    except (TypeError, ValueError, AttributeError) as err:
        if isinstance(err, ModelFileError) or "VesselFileError" in type(err).__name__:
            raise
        raise ModelFileError(f"{path}: damaged model metadata ({err})") from None
    return obj, embedded, state


#: Range of the stored wind paths' step [s] and of their values [m/s] that a model file may carry.
WIND_ERROR_DT_RANGE_S = (1e-3, 60.0)
MAX_WIND_ERROR_M_S = 100.0


def _checked_wind_error_dt(value) -> float:
    """The wind paths' step [s] from the metadata; ValueError naming the field otherwise."""
    lo, hi = WIND_ERROR_DT_RANGE_S
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
        raise ValueError(f"wind_error_dt_s: expected a step from {lo:g} to {hi:g} s, got {value!r}")
    return float(value)


def _checked_number(meta: dict, key: str) -> float:
    """A finite number from the metadata; ValueError naming the field otherwise."""
    value = meta[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise ValueError(f"{key}: expected a number, got {value!r}")
    return float(value)


def _checked_flag(meta: dict, key: str) -> bool:
    """A true/false setting from the metadata; ValueError naming the field otherwise."""
    if not isinstance(meta[key], bool):
        raise ValueError(f"{key}: expected true or false, got {meta[key]!r}")
    return meta[key]


def _checked_drift_yaw(value, predictor) -> float:
    """The hull's yaw coefficient in a drift [rad/m^2]: 0, or one of the candidates
    :func:`~hybridship.residual.drift_hull.choose_coefficient` chooses from, in a model whose
    settings use it (``drift_hull``, ``environment = "estimator"``, ``stop_after_failure``)."""
    from ..residual.drift_hull import MUNK_MULTIPLES, munk_coefficient

    munk = munk_coefficient(predictor.model)
    bound = float(np.abs(MUNK_MULTIPLES).max() * abs(munk))
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not abs(value) <= bound * (1 + 1e-9):
        raise ValueError(f"drift_yaw_uv_rad_per_m2: expected a number from {-bound:.6g} to {bound:.6g} "
                         f"rad/m^2, got {value!r}")
    if value != 0.0:
        if np.abs(MUNK_MULTIPLES - value / munk).min() > 1e-6:
            raise ValueError(f"drift_yaw_uv_rad_per_m2: {value!r} is not one of the candidates (multiples of "
                             f"{MUNK_MULTIPLES[1] - MUNK_MULTIPLES[0]:g} of the Munk coefficient {munk:.6g} rad/m^2)")
        if not predictor.uses_drift_hull:
            raise ValueError("drift_yaw_uv_rad_per_m2: non-zero in a model whose settings do not use it (needs "
                             "drift_hull true, environment 'estimator' and stop_after_failure true)")
    return float(value)


def _scalar_state(meta: dict) -> dict:
    """The learned state kept in the metadata: thrust-error prior, guard and thrust-regime
    scalars, command-regime settings, calibrated modes and the vessel fingerprint."""
    prior = meta["thrust_error_prior"]
    if not isinstance(prior, dict):
        raise ValueError(f"thrust_error_prior: expected a table of means and spreads, got {prior!r}")
    thr_mean, thr_std = (real_array(f"thrust_error_prior.{k}", prior[k]).ravel() for k in ("mean", "std"))
    if thr_mean.shape != thr_std.shape or not (np.all(np.isfinite(thr_mean)) and np.all(thr_std > 0)):
        raise ValueError("thrust_error_prior: expected finite means and positive spreads")
    modes = meta["calibrated_commands"]
    readable = (*COMMAND_MODES, AFTER_STOP, AFTER_STOP_LATE)      # the forecasts' modes and the after-stop ones
    if not isinstance(modes, list) or not all(isinstance(m, str) and m in readable for m in modes):
        raise ValueError(f"calibrated_commands: expected a list of command modes ({', '.join(readable)}), "
                         f"got {modes!r}")
    regime = meta["command_regime"]
    if regime is not None and not isinstance(regime, dict):
        raise ValueError(f"command_regime: expected a table of settings or null, got {regime!r}")
    # a guard scale of 0 is a point envelope's (d0 = 0): weight 1 on it, 0 beyond
    for key, table, entry in (("guard.d0", meta["guard"], "d0"), ("guard.scale", meta["guard"], "scale"),
                              ("thrust_regime.lo", meta["thrust_regime"], "lo")):
        if not isinstance(table, dict):
            raise ValueError(f"{key.split('.')[0]}: expected a table of settings, got {table!r}")
        v = _checked_number(table, entry)
        if v < 0:
            raise ValueError(f"{key}: expected a number >= 0, got {v!r}")
    return {"thr_mean": thr_mean, "thr_std": thr_std, "regime_meta": regime,
            "calibrated_commands": modes, "fingerprint": meta["vessel_fingerprint"],
            "guard_d0": float(meta["guard"]["d0"]), "guard_scale": float(meta["guard"]["scale"]),
            "thrust_lo": float(meta["thrust_regime"]["lo"]), "has_hull": _checked_flag(meta, "has_hull")
            if "has_hull" in meta else False,
            "has_wind_error_paths": _checked_flag(meta, "has_wind_error_paths") if meta["format_version"] >= 9
            else False}


def _check_vessel(obj, meta: dict, fingerprint: str, embedded: bool, path: Path) -> None:
    """Refuse a vessel (embedded or passed) whose fingerprint is not the one trained for."""
    if _vessel_fingerprint(obj.model.vessel) != fingerprint:
        if embedded:
            raise ModelFileError(f"{path}: the embedded description of vessel {meta['vessel']!r} does not "
                                 f"match its fingerprint: the metadata was edited or damaged")
        raise ModelFileError(f"{path}: trained for vessel {meta['vessel']!r} with other parameters; "
                             f"refusing to use it with vessel {obj.model.vessel.name!r}"
                             f"{_differences(meta.get('vessel_description'), obj.model.vessel)}")


def _differences(trained, vessel, shown: int = 5) -> str:
    """``"; different: a.b (trained 1, given 2), ..."``: the fields of the vessel given that
    differ from the description the model was trained with ("" when that is not readable)."""
    from ..vessel import portable_description

    if not isinstance(trained, dict):
        return ""
    given = portable_description(vessel)
    found = []

    def walk(a, b, where):
        if isinstance(a, dict) and isinstance(b, dict):
            for k in sorted(set(a) | set(b)):
                walk(a.get(k), b.get(k), f"{where}.{k}" if where else str(k))
        elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
            for i, (x, y) in enumerate(zip(a, b)):
                walk(x, y, f"{where}[{i}]")
        elif a != b:
            found.append(f"{where} (trained {a!r}, given {b!r})")
    walk(trained, given, "")
    if not found:
        return ""
    more = f" and {len(found) - shown} more" if len(found) > shown else ""
    return "; different: " + ", ".join(found[:shown]) + more


def _restore_learned_state(obj, data: dict, state: dict, path: Path) -> None:
    """Nets, guard, thrust regime, spread calibration, environment prior and command regime
    of ``obj`` from the file's arrays (shapes and values checked)."""
    try:
        ens, guard, thrust_regime = _read_nets(data, len(obj.residual_config.features), state)
        calibration = _read_calibration(data, state["calibrated_commands"], rows=3 if state["format_version"] == 7 else 4)
        _check_finite(ens, guard, thrust_regime)
        hull = (HullCorrection.from_arrays({k: _real_array(data, k) for k in data if k.startswith("hull_")},
                                           obj.model.vessel.particulars.L_pp_m, obj.hull_ridge)
                if state["has_hull"] else None)
        wind_paths = _read_wind_error_paths(data) if state["has_wind_error_paths"] else None
    except KeyError as err:
        raise ModelFileError(f"{path}: damaged model contents: {err.args[0]} is missing") from None
    except ValueError as err:
        raise ModelFileError(f"{path}: damaged model contents: {err}") from None
    obj.ensemble, obj.guard, obj.thrust_regime = ens, guard, thrust_regime
    obj.hull = hull
    obj.estimator = EnvironmentEstimator(obj.model, obj.environment_config)
    if state["thr_mean"].shape != obj.estimator.thrust_error_mean.shape:
        raise ModelFileError(f"{path}: damaged model metadata (thrust_error_prior: expected "
                             f"{obj.estimator.thrust_error_mean.size} entries, one per "
                             f"{obj.environment_config.thrust_error_model.replace('_', ' ')[4:]}, "
                             f"got {state['thr_mean'].size})")
    obj.estimator.thrust_error_mean, obj.estimator.thrust_error_std = state["thr_mean"], state["thr_std"]
    obj.calibration = calibration
    obj.command_regime = _read_command_regime(data, state["regime_meta"], path)
    n_paths = 0 if wind_paths is None else len(wind_paths)
    if obj.wind_samples != n_paths:
        raise ModelFileError(f"{path}: damaged model contents: wind_samples is {obj.wind_samples} but the "
                             f"file has {n_paths} wind_error_paths")
    obj.wind_error_paths = wind_paths


def _read_wind_error_paths(data: dict) -> np.ndarray:
    """The wind forecast's error paths (N, L, 2) [m/s]; ValueError on a wrong shape, type or value."""
    raw = data["wind_error_paths"]
    if raw.dtype.kind != "f":
        raise ValueError(f"wind_error_paths: expected real numbers, got dtype {raw.dtype}")
    paths = np.asarray(raw, dtype=float)
    if paths.ndim != 3 or paths.shape[0] < 1 or paths.shape[1] < 1 or paths.shape[2] != 2:
        raise ValueError(f"wind_error_paths: expected shape (N >= 1, L >= 1, 2), got {paths.shape}")
    if not np.all(np.isfinite(paths)):
        raise ValueError("wind_error_paths contains NaN or inf")
    if np.abs(paths).max() > MAX_WIND_ERROR_M_S:
        raise ValueError(f"wind_error_paths: a wind error above {MAX_WIND_ERROR_M_S:g} m/s")
    return paths


def _real_array(data: dict, key: str) -> np.ndarray:
    """The stored array ``key`` as floats; ValueError naming it when it holds no real numbers
    (text, objects), instead of numpy's conversion message."""
    if data[key].dtype.kind not in "fiu":
        raise ValueError(f"{key}: expected real numbers, got dtype {data[key].dtype}")
    return np.asarray(data[key], dtype=float)


def _read_nets(data: dict, n_in: int, state: dict):
    """``(MLPEnsemble, EnvelopeGuard, ThrustRegime)`` from the arrays; ValueError on wrong shapes."""
    weights = [_real_array(data, f"w{i}") for i in range(6)]
    if weights[0].ndim != 3:
        raise ValueError(f"w0: expected shape (members, inputs, hidden), got {weights[0].shape}")
    E, H = weights[0].shape[0], weights[0].shape[2]
    expected = [(E, n_in, H), (E, 1, H), (E, H, H), (E, 1, H), (E, H, 3), (E, 1, 3)]
    if [w.shape for w in weights] != expected:
        raise ValueError(f"weight shapes {[w.shape for w in weights]} do not match {expected}")
    norm = {k: _real_array(data, k) for k in ("x_mean", "x_std", "y_mean", "y_std")}
    for k, n in (("x_mean", n_in), ("x_std", n_in), ("y_mean", 3), ("y_std", 3)):
        if norm[k].shape != (n,):
            raise ValueError(f"{k}: expected {n} finite values, got shape {norm[k].shape}")
        if not np.all(np.isfinite(norm[k])):
            raise ValueError(f"{k}: expected {n} finite values, got NaN or inf at entry "
                             f"{int(np.argmax(~np.isfinite(norm[k])))}")
        if k.endswith("std") and not np.all(norm[k] > 0):
            raise ValueError(f"{k}: a normalisation scale must be > 0")
    ens = MLPEnsemble(weights, norm["x_mean"], norm["x_std"], norm["y_mean"], norm["y_std"])
    g_mean, g_inv = _real_array(data, "guard_mean"), _real_array(data, "guard_inv_cov")
    # the guard's envelope is over the nets' normalised inputs: one entry per feature
    if g_mean.shape != (n_in,) or g_inv.shape != (n_in, n_in) or not np.all(np.isfinite(g_mean)):
        raise ValueError(f"guard_mean / guard_inv_cov: expected shapes ({n_in},) and ({n_in}, {n_in}) (one per "
                         f"feature) with finite values, got {g_mean.shape} and {g_inv.shape}")
    for name, v in (("guard.d0", state["guard_d0"]), ("guard.scale", state["guard_scale"]),
                    ("thrust_regime.lo", state["thrust_lo"])):
        if not np.all(np.isfinite(np.asarray(v, dtype=float))):
            raise ValueError(f"{name}: not a finite number")
    guard = EnvelopeGuard(g_mean, g_inv, state["guard_d0"], state["guard_scale"])
    scale = _real_array(data, "thrust_scale")
    if scale.shape != (3,) or not np.all(scale > 0):
        raise ValueError(f"thrust_scale: expected 3 positive numbers (surge, sway, yaw), got shape {scale.shape}")
    thrust_regime = ThrustRegime(scale, state["thrust_lo"])
    return ens, guard, thrust_regime


def _check_finite(ens, guard, thrust_regime) -> None:
    """ValueError naming the first learned array with a NaN or inf."""
    for name, a in [("weights", np.concatenate([w.ravel() for w in ens.weights])), ("x_std", ens.x_std),
                    ("y_std", ens.y_std), ("guard_inv_cov", guard.inv_cov),
                    ("thrust_scale", thrust_regime.scale)]:
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} contains NaN or inf")


def _read_calibration(data: dict, modes, rows: int = 4) -> dict:
    """Command mode -> {"position", "heading"} :class:`SpreadCalibration` from the arrays
    (``rows`` 4: lead, scale, floor, exponent; 3: without the exponent, a version-7 file)."""
    calibration = {}
    for mode in modes:
        calibration[mode] = {}
        for what in ("position", "heading"):
            a = _real_array(data, f"cal_{mode}_{what}")
            if a.ndim != 2 or a.shape[0] != rows or a.shape[1] == 0:
                raise ValueError(f"cal_{mode}_{what} has shape {a.shape}, expected ({rows}, H)")
            exponent = 1.0
            if rows == 4:
                if np.unique(a[3]).size > 1:       # a NaN beside a number too (np.ptp passed it)
                    raise ValueError(f"cal_{mode}_{what}: the exponent row must hold one value")
                exponent = float(a[3, 0])
            calibration[mode][what] = SpreadCalibration(a[0], a[1], a[2], exponent)
    return calibration


def _read_command_regime(data: dict, regime_meta, path: Path):
    """The :class:`CommandRegime` stored with the model, or None when it has none."""
    if regime_meta is None:
        return None
    settings = ("rpm_eps", "froude_lo", "angle_hard_rad", "length_m")
    try:
        if sorted(regime_meta) != sorted(settings):
            raise ValueError(f"command_regime: expected the settings {', '.join(settings)}, got "
                             f"{', '.join(map(str, regime_meta))}")
        for key in settings:
            v = regime_meta[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (np.isfinite(v) and v >= 0):
                raise ValueError(f"command_regime.{key}: expected a number >= 0, got {v!r}")
        n = CommandRegime.N_REGIMES
        w = data["cmd_regime_weights"]
        if w.dtype.kind not in "fiu" or w.shape != (n,) or not np.all((w >= 0) & (w <= 1)):
            raise ValueError(f"cmd_regime_weights: expected {n} weights in [0, 1]")
        counts = {k: data[f"cmd_regime_{k}"] for k in ("n_train", "n_held")}
        for k, c in counts.items():
            if c.dtype.kind not in "iu" or c.shape != (n,) or np.any(c < 0):
                raise ValueError(f"cmd_regime_{k}: expected {n} counts (whole numbers >= 0), got dtype "
                                 f"{c.dtype} and shape {c.shape}")
        return CommandRegime(np.asarray(w, dtype=float), counts["n_train"], counts["n_held"], **regime_meta)
    except KeyError as err:
        raise ModelFileError(f"{path}: damaged model contents: {err.args[0]} is missing") from None
    except ValueError as err:
        raise ModelFileError(f"{path}: damaged model contents: {err}") from None
