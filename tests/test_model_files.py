"""Model files (issue 9): damaged, foreign or hostile files are refused; writes are atomic.

A small hybrid is trained once on a short synthetic log; every test then damages a copy
of its model file in one way and checks that :meth:`HybridPredictor.load` refuses it with
a :class:`ModelFileError` that says what is wrong, without running code from the file.
The tampering works on the file's arrays generically (load every array, change one,
save again), so it does not depend on which arrays a model version stores.
"""

from __future__ import annotations

import json
import os
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

from hybridship.physics.model import DynamicModel
from hybridship.predictors import HybridPredictor, ModelFileError
from hybridship.residual.ensemble import EnsembleConfig
from hybridship.residual.features import ResidualConfig
from hybridship.sim.synthetic import physics_log
from hybridship.vessel import vessel_from_dict

TINY = EnsembleConfig(n_members=2, hidden=8, max_epochs=15, patience=5, seed=0)


@pytest.fixture(scope="module")
def saved(model, tmp_path_factory):
    """(predictor, path of its model file, raw bytes of the file)."""
    log = physics_log(model, seed=2, duration_s=300.0, t_shutdown_s=None, current=(0.2, 1.0))
    hp = HybridPredictor(model.vessel, ensemble_config=TINY).fit([log])
    path = hp.save(tmp_path_factory.mktemp("model") / "model.npz")
    return hp, path, path.read_bytes()


def _arrays(path) -> dict:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _meta(arrays) -> dict:
    return json.loads(bytes(arrays["metadata_json"]).decode("utf-8"))


def _rewrite(saved, tmp_path, *, meta_change=None, array_change=None, name="tampered.npz",
             restamp=False, restamp_metadata=True) -> Path:
    """A copy of the saved model with its metadata and/or arrays changed.

    ``restamp`` recomputes the content checksum after the change (a consistently written
    file with bad contents), so that the checks behind the checksum are reached;
    ``restamp_metadata`` (default) does the same for the metadata's own checksum after a
    metadata change (``test_edited_settings_are_refused`` turns it off).
    """
    _, path, _ = saved
    arrays = _arrays(path)
    if meta_change is not None:
        from hybridship.predictors.model_file import _metadata_hash

        meta = _meta(arrays)
        meta_change(meta)
        if restamp_metadata and "metadata_sha256" in meta:   # a consistently written file with these settings
            meta["metadata_sha256"] = _metadata_hash(meta)
        arrays["metadata_json"] = np.frombuffer(json.dumps(meta).encode("utf-8"), dtype=np.uint8)
    if array_change is not None:
        array_change(arrays)
    if restamp:
        from hybridship.predictors.model_file import _content_hash

        meta = _meta(arrays)
        meta["content_sha256"] = _content_hash({k: v for k, v in arrays.items() if k != "metadata_json"})
        if "metadata_sha256" in meta:
            from hybridship.predictors.model_file import _metadata_hash

            meta["metadata_sha256"] = _metadata_hash(meta)
        arrays["metadata_json"] = np.frombuffer(json.dumps(meta).encode("utf-8"), dtype=np.uint8)
    out = tmp_path / name
    np.savez(out, **arrays)
    return out


def _refused(path, pattern, **kw):
    with pytest.raises(ModelFileError, match=pattern):
        HybridPredictor.load(path, **kw)


def test_round_trip_still_loads(saved):
    hp, path, raw = saved
    back = HybridPredictor.load(path)
    for a, b in zip(hp.ensemble.weights, back.ensemble.weights):
        np.testing.assert_array_equal(a, b)
    assert path.read_bytes() == raw                  # loading never writes


def test_a_point_envelope_guard_saves_and_loads(saved, tmp_path):
    """Training features mostly at their mean give the guard d0 = 0 and the default scale
    d0 / 2 = 0 (weight 1 on the point, 0 beyond): such a model loads back, it was refused as
    'guard.scale: expected a number > 0'."""
    import copy
    import dataclasses

    hp = copy.deepcopy(saved[0])
    hp.guard = dataclasses.replace(hp.guard, d0=0.0, scale=0.0)
    back = HybridPredictor.load(hp.save(tmp_path / "point.npz"))
    assert (back.guard.d0, back.guard.scale) == (0.0, 0.0)
    x = np.stack([hp.guard.mean, hp.guard.mean + 0.1])
    np.testing.assert_array_equal(back.guard.weight(x), [1.0, 0.0])


def test_save_never_replaces_a_file_that_is_not_a_model(saved, tmp_path):
    """Review: ``save`` replaced a user's own archive or file under the model's name (the
    command line refused it, the API did not); a model file, or an empty file, is replaced."""
    hp, path, raw = saved
    mine = tmp_path / "mine.npz"
    np.savez(mine, important=np.arange(5))
    notes = tmp_path / "notes.npz"
    notes.write_text("x")
    for p in (mine, notes):
        before = p.read_bytes()
        with pytest.raises(ValueError, match=r"path: .*exists and is not a hybridship model file"):
            hp.save(p)
        assert p.read_bytes() == before
    (tmp_path / "folder.npz").mkdir()
    with pytest.raises(ValueError, match="exists and is not a file"):
        hp.save(tmp_path / "folder.npz")
    again = tmp_path / "model.npz"
    again.write_bytes(raw)                               # an earlier model: replaced
    hp.save(again)
    (tmp_path / "empty.npz").write_bytes(b"")
    hp.save(tmp_path / "empty.npz")
    for path in (again, tmp_path / "empty.npz"):           # the model written there is this one
        for a, b in zip(hp.ensemble.weights, HybridPredictor.load(path).ensemble.weights):
            np.testing.assert_array_equal(a, b)


def test_truncated_file_is_refused(saved, tmp_path):
    _, _, raw = saved
    for cut in (0, 10, len(raw) // 2, len(raw) - 1):
        p = tmp_path / f"cut{cut}.npz"
        p.write_bytes(raw[:cut])
        _refused(p, rf"{p.name}: not a readable hybridship model file \((the file is empty|a damaged \.npz "
                    rf"archive)\)$")
    text = tmp_path / "log_as_model.npz"              # a text file (a log) given as the model
    text.write_text("time_s,north_m\n0,0\n")
    _refused(text, r"log_as_model.npz: not a readable hybridship model file \(not an \.npz archive \(a text")
    (tmp_path / "folder.npz").mkdir()
    _refused(tmp_path / "folder.npz", r"folder.npz: is a folder; expected a model file")
    npy = tmp_path / "array.npz"                     # a .npy array renamed
    with open(npy, "wb") as fh:
        np.save(fh, np.zeros(3))
    _refused(npy, r"array.npz: not a readable hybridship model file \(a single \.npy array, not the \.npz archive")


def test_flipped_bytes_are_refused_or_harmless(saved, tmp_path):
    """A flipped byte anywhere is refused, unless it sits in zip bookkeeping the reader does
    not use (a local header's extra field or timestamp): then the model is unchanged."""
    hp, _, raw = saved
    refused = 0
    positions = np.linspace(0, len(raw) - 1, 61).astype(int)
    for pos in positions:
        b = bytearray(raw)
        b[pos] ^= 0xFF
        p = tmp_path / f"flip{pos}.npz"
        p.write_bytes(bytes(b))
        try:
            back = HybridPredictor.load(p)
        except ModelFileError as err:
            assert p.name in str(err)
            refused += 1
            continue
        for a, w in zip(hp.ensemble.weights, back.ensemble.weights):
            np.testing.assert_array_equal(a, w)
        np.testing.assert_array_equal(hp.guard.inv_cov, back.guard.inv_cov)
        assert back.training_info == hp.training_info
    assert refused >= 0.8 * positions.size


def test_missing_file_is_a_model_file_error(tmp_path):
    _refused(tmp_path / "nope.npz", "model file not found")


def test_incompatible_format_version_is_refused(saved, tmp_path):
    for version, shown in ((0, "0"), (99, "99"), ("1", '"1"'), (None, "null"), ("13", '"13"'), (13.0, "13.0")):
        p = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(format_version=version), name=f"v{version}.npz")
        # as written in the file: the text "13" is not said as 13, which this hybridship reads
        _refused(p, rf"model format version {shown} is not supported "
                    rf"\(this hybridship reads versions 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21\)"
                    + (r"; expected a whole number$" if not isinstance(version, int) else ""))
    p = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(format_version=22), name="v22.npz")
    _refused(p, r"written by a newer hybridship \(format 22\); upgrade hybridship to read it")


def test_the_cli_reference_names_the_formats_that_load():
    """docs/reference/cli.md says which older model files still load; it said 7 to 16 once
    this hybridship read 17 as well."""
    from hybridship.predictors.model_file import MODEL_FORMAT_VERSION, READABLE_MODEL_FORMAT_VERSIONS

    page = (Path(__file__).parents[1] / "docs" / "reference" / "cli.md").read_text(encoding="utf-8")
    said = [tuple(int(v) for v in m) for m in re.findall(r"Model files of formats (\d+) to (\d+)", page)]
    older = [v for v in READABLE_MODEL_FORMAT_VERSIONS if v != MODEL_FORMAT_VERSION]
    assert said == [(min(older), max(older))], said


def test_an_older_format_says_retrain(saved, tmp_path):
    for old in (2, 3, 5, 6):
        p = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(format_version=old), name=f"v{old}.npz")
        _refused(p, rf"written by an older hybridship \(format {old}\).*retrain with `hybridship train`")


def test_a_version_7_file_reads_as_spread_exponent_1(saved, model, tmp_path):
    """Version 7 had no spread exponent: its three-row calibration arrays read as exponent 1,
    and the forecast is the same; a version-8 file with three rows is refused."""
    import copy

    from hybridship.residual.calibration import SpreadCalibration

    hp = copy.deepcopy(saved[0])                 # with a calibration of scale 2 and floor 0.1
    cal = SpreadCalibration([1.0, 60.0], [2.0, 2.0], [0.1, 0.1])
    hp.calibration = {"held": {"position": cal, "heading": cal}}
    saved = (hp, hp.save(tmp_path / "calibrated.npz"), None)
    log = physics_log(model, seed=2, duration_s=300.0, t_shutdown_s=None, current=(0.2, 1.0))

    def drop_exponent(arrays):
        for k in [k for k in arrays if k.startswith("cal_")]:
            arrays[k] = arrays[k][:3]

    def as_v7(meta):
        meta["format_version"] = 7
        meta["calibration_config"].pop("spread_exponent")

    p7 = _rewrite(saved, tmp_path, meta_change=as_v7, array_change=drop_exponent, restamp=True, name="v7.npz")
    back = HybridPredictor.load(p7)
    assert back.calibration and all(c.exponent == 1.0 for d in back.calibration.values() for c in d.values())
    starts = [150.0]
    np.testing.assert_array_equal(back.forecast(log, starts, 20.0).eta_std, hp.forecast(log, starts, 20.0).eta_std)
    p8 = _rewrite(saved, tmp_path, array_change=drop_exponent, restamp=True, name="v8_3rows.npz")
    _refused(p8, r"expected \(4, H\)")


def test_a_calibration_for_an_unknown_command_mode_is_refused(saved, tmp_path):
    """A spread calibration stored under a mode a forecast never asks for ("Held", "bogus")
    loaded without a word, and the forecasts of the mode it was meant for kept the raw spread.
    The modes a model may have, the forecasts' and those after a stop, all load back."""
    import copy

    from hybridship.predictors.hybrid import AFTER_STOP, AFTER_STOP_LATE
    from hybridship.residual.calibration import SpreadCalibration

    hp = copy.deepcopy(saved[0])
    cal = SpreadCalibration([1.0, 60.0], [2.0, 2.0], [0.1, 0.1])
    modes = ("held", "known", AFTER_STOP, AFTER_STOP_LATE)
    hp.calibration = {mode: {"position": cal, "heading": cal} for mode in modes}
    assert set(HybridPredictor.load(hp.save(tmp_path / "modes.npz")).calibration) == set(modes)

    def add(arrays):
        cal = np.stack([[1.0, 60.0], [2.0, 2.0], [0.1, 0.1], [1.0, 1.0]])
        arrays.update(cal_Held_position=cal, cal_Held_heading=cal)

    path = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(calibrated_commands=["Held"]),
                    array_change=add, restamp=True, name="mode.npz")
    _refused(path, r"damaged model metadata \(calibrated_commands: expected a list of command modes \(held, "
                   r"known, after_stop, after_stop_late\), got \['Held'\]")


def test_a_calibration_whose_exponent_row_varies_is_refused(saved, tmp_path):
    """The fourth row of a ``cal_*`` array repeats one exponent; a row that varies (a damaged
    or hand-made file) is refused by name, not read as its first entry."""
    import copy

    from hybridship.residual.calibration import SpreadCalibration

    hp = copy.deepcopy(saved[0])
    cal = SpreadCalibration([1.0, 60.0], [2.0, 2.0], [0.1, 0.1])
    hp.calibration = {"held": {"position": cal, "heading": cal}}
    calibrated = (hp, hp.save(tmp_path / "calibrated.npz"), None)

    for row in ([1.0, 0.5], [1.0, np.nan]):        # a NaN after the first entry was read as the first
        def two_exponents(arrays, row=row):
            a = arrays["cal_held_heading"].copy()
            a[3] = row
            arrays["cal_held_heading"] = a

        _refused(_rewrite(calibrated, tmp_path, array_change=two_exponents, restamp=True, name="exponents.npz"),
                 r"damaged model contents: cal_held_heading: the exponent row must hold one value")


@pytest.mark.parametrize("key, dtype", [("cal_held_position", str), ("cal_held_heading", complex),
                                        ("hull_theta", str), ("hull_offset", complex)])
def test_calibration_and_hull_arrays_that_hold_no_real_numbers_are_refused_by_name(saved, tmp_path, key, dtype):
    """Text in a calibration or hull array was refused with numpy's "could not convert string
    to float", naming no array, and complex values were read with their imaginary part dropped."""
    import copy

    from hybridship.residual.calibration import SpreadCalibration
    from hybridship.residual.hull import HULL_REGRESSORS

    hp = copy.deepcopy(saved[0])
    cal = SpreadCalibration([1.0, 60.0], [2.0, 2.0], [0.1, 0.1])
    hp.calibration = {"held": {"position": cal, "heading": cal}}
    full = (hp, hp.save(tmp_path / "calibrated.npz"), None)
    P = len(HULL_REGRESSORS)
    hull = {"hull_theta": np.zeros((P, 3)), "hull_phi_mean": np.zeros(P), "hull_phi_std": np.ones(P),
            "hull_offset": np.zeros(3)}

    def change(arrays):
        if key.startswith("hull_"):
            arrays.update(hull)
        arrays[key] = (arrays[key] + 1j) if dtype is complex else arrays[key].astype(str)

    def with_hull(meta):
        meta["has_hull"] = key.startswith("hull_")

    path = _rewrite(full, tmp_path, meta_change=with_hull, array_change=change, restamp=True, name=f"{key}.npz")
    _refused(path, rf"damaged model contents: {key}: expected real numbers, got dtype")


def test_files_written_before_a_vessel_field_was_added_still_load(saved, tmp_path):
    """A vessel field added later (``lift_speed``) at its default leaves the fingerprint as it
    was, so a file whose embedded description lacks it loads; the packaged vessels keep the
    fingerprints files recorded before the field existed; a non-default value changes it."""
    from hybridship.vessel import Vessel, fingerprint, load_vessel

    def before(m):
        m["vessel_description"]["damping"]["nonlinear"].pop("lift_speed", None)
    p = _rewrite(saved, tmp_path, meta_change=before, name="before_lift_speed.npz")
    assert HybridPredictor.load(p).model.vessel == saved[0].model.vessel
    # (Gunnerus's changed with its file's added-mass coupling, 2026-11-29; it was b61e6889e81e74fa)
    assert [fingerprint(load_vessel(n)) for n in ("gunnerus", "esso_osaka_model")] == \
        ["511b94ecc84f39f0", "6649ecc0be379c86"]
    d = load_vessel("gunnerus").model_dump()
    d["damping"]["nonlinear"]["lift_speed"] = "signed"
    assert fingerprint(Vessel.model_validate(d)) != "511b94ecc84f39f0"


def test_a_file_from_before_the_station_keeping_spread_option_reads_as_ensemble(saved, tmp_path):
    """Files written before ``CalibrationConfig.station_keeping_spread`` were calibrated on the
    members' spread: they read as ``"ensemble"``, not as today's default."""
    def before(m):
        m["calibration_config"].pop("station_keeping_spread")
    back = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=before, name="before_sk_spread.npz"))
    assert back.calibration_config.station_keeping_spread == "ensemble"
    assert HybridPredictor.load(saved[1]).calibration_config.station_keeping_spread == "held_load"


def test_the_model_file_carries_its_vessel(saved, model, tmp_path):
    from hybridship.vessel import portable_description

    hp, path, _ = saved
    meta = _meta(_arrays(path))
    assert meta["vessel_description"] == portable_description(model.vessel)
    assert "lift_speed" not in meta["vessel_description"]["damping"]["nonlinear"]    # readable by older releases
    # loads from the embedded description alone: the packaged name is not looked up
    p = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(vessel="no_such_ship"), name="renamed.npz")
    assert HybridPredictor.load(p).model.vessel == model.vessel
    # an edited embedded description no longer matches the fingerprint
    def heavier(m):
        m["vessel_description"]["rigid_body"]["mass_kg"] *= 1.2
    _refused(_rewrite(saved, tmp_path, meta_change=heavier, name="heavier.npz"),
             "embedded description of vessel 'gunnerus' does not match its fingerprint")
    def invalid(m):
        m["vessel_description"]["rigid_body"]["mass_kg"] = -1.0
    _refused(_rewrite(saved, tmp_path, meta_change=invalid, name="invalid.npz"),
             r"embedded vessel is invalid: .*rigid_body.mass_kg")
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m.pop("vessel_description"), name="novessel.npz"),
             "damaged model metadata")


def test_a_file_that_is_not_a_model_is_refused(saved, tmp_path):
    p = tmp_path / "other.npz"
    np.savez(p, x=np.arange(3.0))
    _refused(p, "metadata missing or damaged")
    p = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(format="something-else"), name="fmt.npz")
    _refused(p, "not a hybridship model file")
    p = _rewrite(saved, tmp_path, array_change=lambda a: a.update(metadata_json=np.frombuffer(b"{not json", np.uint8)),
                 name="json.npz")
    _refused(p, "metadata missing or damaged")


def test_damaged_weights_are_refused(saved, tmp_path):
    def nan_weight(a):
        w = a["w0"].copy()
        w.flat[0] = np.nan
        a["w0"] = w

    _refused(_rewrite(saved, tmp_path, array_change=nan_weight, name="nan.npz"), r"checksum does not match")
    _refused(_rewrite(saved, tmp_path, array_change=nan_weight, name="nan2.npz", restamp=True),
             r"damaged model contents: .*NaN")
    _refused(_rewrite(saved, tmp_path, array_change=lambda a: a.update(w2=a["w2"][:, :-1]), name="shape.npz",
                      restamp=True), r"damaged model contents: weight shapes")
    _refused(_rewrite(saved, tmp_path, array_change=lambda a: a.pop("w5"), name="missing.npz", restamp=True),
             r"damaged model contents")


def test_another_vessels_model_is_refused(saved, model, tmp_path):
    _, path, _ = saved
    d = model.vessel.model_dump()
    d["name"] = "gunnerus-sister"
    d["rigid_body"]["mass_kg"] *= 1.2
    other = vessel_from_dict(d)
    _refused(path, r"trained for vessel 'gunnerus' with other parameters; refusing to use it with vessel "
                   r"'gunnerus-sister'; different: name \(trained 'gunnerus', given 'gunnerus-sister'\), "
                   r"rigid_body.mass_kg \(trained ", vessel=other)
    # a file claiming gunnerus but trained on other parameters (fingerprint mismatch)
    p = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(vessel_fingerprint="0" * 16), name="fp.npz")
    _refused(p, "trained for vessel 'gunnerus' with other parameters", vessel="gunnerus")
    _refused(p, "embedded description of vessel 'gunnerus' does not match its fingerprint")
    # a model that learned the hull's yaw moment in a drift (a multiple of its vessel's Munk
    # coefficient) is refused for another vessel as such, not as damaged metadata
    from hybridship.residual.drift_hull import MUNK_MULTIPLES, munk_coefficient

    yaw = float(MUNK_MULTIPLES[-1] * munk_coefficient(model))
    p = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(drift_hull=True, drift_yaw_uv_rad_per_m2=yaw),
                 name="drift_yaw.npz")
    assert HybridPredictor.load(p).drift_yaw_uv_rad_per_m2 == yaw
    d["particulars"]["B_m"] *= 1.1                      # another Munk coefficient too
    wider = vessel_from_dict(d)
    assert munk_coefficient(DynamicModel(wider)) != munk_coefficient(model)
    _refused(p, r"trained for vessel 'gunnerus' with other parameters; refusing to use it with vessel "
                r"'gunnerus-sister'", vessel=wider)


class _Payload:
    """Unpickling this creates a marker file: proof that code from the file ran."""

    marker = ""

    def __reduce__(self):
        return (open, (self.marker, "w"))


def test_loading_never_executes_code_from_the_file(saved, tmp_path):
    marker = tmp_path / "code_ran"
    _Payload.marker = str(marker)
    # 1. an object (pickled) array inside an otherwise valid model file
    arrays = _arrays(saved[1])
    arrays["w0"] = np.array([_Payload()], dtype=object)
    p = tmp_path / "pickled_array.npz"
    np.savez(p, **arrays)                     # numpy pickles object arrays when saving
    # 2. the metadata itself as a pickled object
    arrays = _arrays(saved[1])
    arrays["metadata_json"] = np.array([_Payload()], dtype=object)
    q = tmp_path / "pickled_meta.npz"
    np.savez(q, **arrays)
    # 3. a plain pickle file named like a model
    r = tmp_path / "plain_pickle.npz"
    r.write_bytes(pickle.dumps(_Payload()))
    for f, what in ((p, "an archive holding pickled objects"), (q, "an archive holding pickled objects"),
                    (r, "a pickle file")):
        with pytest.raises(ModelFileError, match=f"{f.name}: not a readable hybridship model file \\({what}") as info:
            HybridPredictor.load(f)
        assert "unsafely" not in str(info.value)       # never advises loading it anyway
    assert not marker.exists()
    # the payload is live: unpickling it really would have run code
    pickle.loads(r.read_bytes()).close()
    assert marker.exists()


def test_a_crash_while_saving_leaves_no_half_written_model(saved, tmp_path, monkeypatch):
    hp, _, _ = saved
    path = tmp_path / "m.npz"
    hp.save(path)
    good = path.read_bytes()
    real_savez = np.savez

    def crash_midway(fh, **arrays):
        real_savez(fh, **{k: arrays[k] for k in list(arrays)[:2]})   # part of the output ...
        raise OSError("disk full")                                      # ... then the crash

    monkeypatch.setattr(np, "savez", crash_midway)
    with pytest.raises(OSError, match="disk full"):
        hp.save(path)
    assert path.read_bytes() == good                      # the previous model is intact
    with pytest.raises(OSError, match="disk full"):
        hp.save(tmp_path / "new.npz")
    assert not (tmp_path / "new.npz").exists()            # no half-written new model
    assert sorted(os.listdir(tmp_path)) == ["m.npz"]      # and no temporary files
    monkeypatch.setattr(np, "savez", real_savez)
    HybridPredictor.load(path)


def test_wind_futures_of_the_spread_are_checked_and_older_files_have_none(saved, tmp_path):
    def as_v8(meta):
        meta["format_version"] = 8
        for k in ("wind_samples", "wind_error_dt_s", "has_wind_error_paths"):
            meta.pop(k)
    back = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v8, restamp=True, name="v8.npz"))
    assert back.wind_samples == 0 and back.wind_error_paths is None
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m.pop("wind_samples"), restamp=True, name="no_ws.npz"),
             "damaged model metadata.*wind_samples")
    # a file that says it adds wind futures to its spread but carries no paths
    claims = _rewrite(saved, tmp_path, meta_change=lambda m: m.update(wind_samples=4), restamp=True, name="ws.npz")
    _refused(claims, "wind_samples is 4 but the file has 0 wind_error_paths")
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m.update(wind_samples=10 ** 12), restamp=True,
                      name="huge.npz"), "wind_samples: expected a whole number from 0 to 256")

    def with_paths(meta):
        meta.update(wind_samples=3, has_wind_error_paths=True)

    for bad, pattern in ((np.full((3, 5, 2), np.nan), "wind_error_paths contains NaN"),
                         (np.zeros((3, 5)), r"wind_error_paths: expected shape \(N >= 1, L >= 1, 2\)"),
                         (np.zeros((3, 0, 2)), r"expected shape"),
                         (np.full((3, 5, 2), 1e300), "a wind error above 100 m/s"),
                         (np.zeros((3, 5, 2), complex), "expected real numbers")):
        def put(arrays, bad=bad):
            arrays["wind_error_paths"] = bad
        _refused(_rewrite(saved, tmp_path, meta_change=with_paths, array_change=put, restamp=True, name="p.npz"),
                 pattern)
    for dt in (0.0, 1e-300, None, "1"):
        _refused(_rewrite(saved, tmp_path, meta_change=lambda m, dt=dt: m.update(wind_error_dt_s=dt), restamp=True,
                          name="dt.npz"), "wind_error_dt_s: expected a step from 0.001 to 60 s")


def test_hull_yaw_moment_in_a_drift_is_checked_and_older_files_have_none(saved, tmp_path, model):
    """The coefficient round-trips; a version-9 file loads without it (as it was fitted); a
    coefficient outside the candidates, not a number, or a missing key is refused by name."""
    import copy

    from hybridship.residual.drift_hull import munk_coefficient

    hp = copy.deepcopy(saved[0])
    hp.drift_yaw_uv_rad_per_m2 = 0.5 * munk_coefficient(model)
    back = HybridPredictor.load(hp.save(tmp_path / "k.npz"))
    assert back.drift_yaw_uv_rad_per_m2 == hp.drift_yaw_uv_rad_per_m2 and back.drift_hull

    def as_v9(meta):
        meta["format_version"] = 9
        for k in ("drift_hull", "drift_yaw_uv_rad_per_m2"):
            meta.pop(k)
    old = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v9, restamp=True, name="v9.npz"))
    assert old.drift_yaw_uv_rad_per_m2 == 0.0 and not old.drift_hull
    assert back._drift_yaw_in_filter and back._filter_drift_yaw() == hp.drift_yaw_uv_rad_per_m2

    def as_v10(meta):
        meta["format_version"] = 10
        meta.pop("drift_yaw_in_filter")
    # version 10 chose its coefficient with the forecasts alone: the filter keeps not using it
    v10 = HybridPredictor.load(_rewrite((hp, tmp_path / "k.npz", None), tmp_path, meta_change=as_v10, restamp=True,
                                        name="v10.npz"))
    assert v10.drift_yaw_uv_rad_per_m2 == hp.drift_yaw_uv_rad_per_m2 and not v10._drift_yaw_in_filter
    assert v10._filter_drift_yaw() == 0.0
    back2 = HybridPredictor.load(v10.save(tmp_path / "v10_resaved.npz"))
    assert not back2._drift_yaw_in_filter                # and a re-save keeps what it was fitted with
    # a refit chooses again, and then the filter uses what it chose, as the forecasts do
    back2.fit([physics_log(model, seed=3, duration_s=300.0, t_shutdown_s=None)])
    assert back2._drift_yaw_in_filter
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m.update(drift_yaw_in_filter=1), restamp=True,
                      name="inf.npz"), "drift_yaw_in_filter: expected true or false")
    for bad in (1.0, float("nan"), "0.001", True, None):
        _refused(_rewrite(saved, tmp_path, meta_change=lambda m, bad=bad: m.update(drift_yaw_uv_rad_per_m2=bad),
                          restamp=True, name="k.npz"), r"drift_yaw_uv_rad_per_m2: expected a number from -0\.0112")
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m.update(drift_yaw_uv_rad_per_m2=0.51 * 0.005619),
                      restamp=True, name="grid.npz"), "drift_yaw_uv_rad_per_m2: .* is not one of the candidates")
    k = 0.5 * munk_coefficient(model)
    for change in ({"drift_hull": False}, {"environment": "mean"}, {"stop_after_failure": False}):
        _refused(_rewrite(saved, tmp_path, meta_change=lambda m, c=change: m.update(drift_yaw_uv_rad_per_m2=k, **c),
                          restamp=True, name="use.npz"), "non-zero in a model whose settings do not use it")
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m.update(drift_hull="yes"), restamp=True,
                      name="flag.npz"), "drift_hull: expected true or false")
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m.pop("drift_yaw_uv_rad_per_m2"), restamp=True,
                      name="nok.npz"), "damaged model metadata.*drift_yaw_uv_rad_per_m2")


def test_a_version_11_file_reads_without_command_memory(saved, tmp_path):
    """Version 11 had no command-memory features: its residual config reads with the default
    time constant, which its features do not use; a version-12 file without it is damaged."""
    def as_v11(meta):
        meta["format_version"] = 11
        meta["residual_config"].pop("command_memory_s")

    back = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v11, name="v11.npz"))
    assert back.residual_config.command_memory_s == ResidualConfig().command_memory_s
    assert not back.residual_config.uses_memory_features
    v12 = _rewrite(saved, tmp_path, meta_change=lambda m: m["residual_config"].pop("command_memory_s"), name="v12.npz")
    _refused(v12, r"damaged model metadata .*command_memory_s")


def test_a_version_13_file_reads_without_settling(saved, tmp_path):
    """Version 13 had no settling of the environment estimator: its config reads with
    ``settle_s = 0``, as it was fitted; a version-14 file without it is damaged."""
    def as_v13(meta):
        meta["format_version"] = 13
        meta["environment_config"].pop("settle_s")

    back = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v13, name="v13.npz"))
    assert back.environment_config.settle_s == 0.0
    v14 = _rewrite(saved, tmp_path, meta_change=lambda m: m["environment_config"].pop("settle_s"), name="v14.npz")
    _refused(v14, r"damaged model metadata .*settle_s")


def test_a_version_15_file_reads_as_fitted_at_the_logs_own_step(saved, tmp_path):
    """Version 15 had no ``residual_step_s``: its nets were fitted at the logs' own step, so
    it reads as None; a version-16 file without it is damaged."""
    def as_v15(meta):
        meta["format_version"] = 15
        meta["residual_config"].pop("residual_step_s")

    assert saved[0].residual_config.residual_step_s == 1.0
    back = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v15, name="v15r.npz"))
    assert back.residual_config.residual_step_s is None
    v16 = _rewrite(saved, tmp_path, meta_change=lambda m: m["residual_config"].pop("residual_step_s"),
                   name="v16r.npz")
    _refused(v16, r"damaged model metadata .*residual_step_s")


def test_a_version_16_file_reads_restarting_the_filter_at_every_gap(saved, tmp_path):
    """Version 16 restarted the environment estimator at every gap of a log: its config reads
    with ``max_bridged_gap_s = 0``, as it was fitted; a version-17 file without it is damaged."""
    def as_v16(meta):
        meta["format_version"] = 16
        meta["environment_config"].pop("max_bridged_gap_s")

    assert saved[0].environment_config.max_bridged_gap_s == 10.0
    back = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v16, name="v16g.npz"))
    assert back.environment_config.max_bridged_gap_s == 0.0
    v17 = _rewrite(saved, tmp_path, meta_change=lambda m: m["environment_config"].pop("max_bridged_gap_s"),
                   name="v17g.npz")
    _refused(v17, r"damaged model metadata .*max_bridged_gap_s")


def test_a_version_17_file_filters_a_drift_with_the_station_keeping_walks(saved, tmp_path):
    """Version 17 filtered a drift with the load's station-keeping random walks: its config
    reads with the after-stop walks equal to those, as it was fitted (also when the file set
    its own station-keeping walks); a version-18 file without them is damaged."""
    def as_v17(meta, own_walks=False):
        meta["format_version"] = 17
        env = meta["environment_config"]
        env.pop("load_walk_after_stop_m_s2")
        env.pop("load_yaw_walk_after_stop_rad_s2")
        if own_walks:
            env.update(load_walk_m_s2=5e-5, load_yaw_walk_rad_s2=2e-6)

    c = saved[0].environment_config
    assert (c.load_walk_after_stop_m_s2, c.load_yaw_walk_after_stop_rad_s2) != (c.load_walk_m_s2,
                                                                               c.load_yaw_walk_rad_s2)
    back = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v17, name="v17w.npz")).environment_config
    assert (back.load_walk_after_stop_m_s2, back.load_yaw_walk_after_stop_rad_s2) == (c.load_walk_m_s2,
                                                                                     c.load_yaw_walk_rad_s2)
    own = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=lambda m: as_v17(m, own_walks=True),
                                        name="v17o.npz")).environment_config
    assert (own.load_walk_after_stop_m_s2, own.load_yaw_walk_after_stop_rad_s2) == (5e-5, 2e-6)
    for field in ("load_walk_after_stop_m_s2", "load_yaw_walk_after_stop_rad_s2"):
        v18 = _rewrite(saved, tmp_path, meta_change=lambda m: m["environment_config"].pop(field), name=f"v18{field}.npz")
        _refused(v18, rf"damaged model metadata .*{field}")


def test_the_choice_of_the_turned_yaw_load_is_kept_and_checked(saved, tmp_path):
    """Format 19 records whether fit chose the yaw load turned with the waves (with
    ``wave_turned_yaw_load = "auto"``, the default): it loads back; a version-18 file reads False,
    and one written before the setting existed reads the setting False (held, as it was fitted);
    a version-19 file without either is damaged, and one that says True for a model whose
    setting is not "auto" is refused."""
    import copy

    from hybridship.residual.environment import EnvironmentConfig

    hp = copy.deepcopy(saved[0])
    hp.environment_config = EnvironmentConfig(**{**hp.environment_config.model_dump(), "wave_turned_yaw_load": "auto"})
    hp.wave_yaw_turned = True
    back = HybridPredictor.load(hp.save(tmp_path / "auto.npz"))
    assert back.environment_config.wave_turned_yaw_load == "auto" and back.wave_yaw_turned and back.turns_yaw_load
    auto = (hp, tmp_path / "auto.npz", None)

    def as_v18(meta):
        meta["format_version"] = 18
        meta.pop("wave_yaw_turned")

    assert not HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v18, name="v18t.npz")).wave_yaw_turned

    def before_the_option(meta):        # files written before the setting existed: held, as fitted
        as_v18(meta)
        meta["environment_config"].pop("wave_turned_yaw_load")

    old = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=before_the_option, name="v18o.npz"))
    assert old.environment_config.wave_turned_yaw_load is False and not old.turns_yaw_load
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m["environment_config"].pop("wave_turned_yaw_load"),
                      name="v19o.npz"), r"damaged model metadata .*wave_turned_yaw_load")
    _refused(_rewrite(auto, tmp_path, meta_change=lambda m: m.pop("wave_yaw_turned"), name="v19t.npz"),
             r"damaged model metadata .*wave_yaw_turned")
    _refused(_rewrite(auto, tmp_path, meta_change=lambda m: m["environment_config"].update(wave_turned_yaw_load=False),
                      name="v19f.npz"), r"wave_yaw_turned: true in a model whose .* is not 'auto'")


def test_the_current_prior_scaled_by_the_wind_is_kept(saved, tmp_path):
    """Format 20 records the current's prior scaled by the wind: it loads back and its filter
    uses it; a version-19 file without the settings reads a fixed prior (as it was fitted), a
    version-20 file without them is damaged."""
    import copy

    from hybridship.residual.environment import EnvironmentConfig

    hp = copy.deepcopy(saved[0])
    hp.environment_config = EnvironmentConfig(**{**hp.environment_config.model_dump(),
                                                 "current_prior_wind_ref_m_s": 8.0, "current_prior_max_m_s": 0.2})
    back = HybridPredictor.load(hp.save(tmp_path / "wind.npz"))
    assert back.environment_config.current_prior_wind_ref_m_s == 8.0
    assert back.estimator.config.current_prior_max_m_s == 0.2
    for key in ("current_prior_wind_ref_m_s", "current_prior_max_m_s"):
        def as_v19(meta, key=key):
            meta["format_version"] = 19
            meta["environment_config"].pop(key)

        old = HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v19, name=f"v19{key}.npz"))
        assert old.environment_config.current_prior_wind_ref_m_s is None
        _refused(_rewrite(saved, tmp_path, meta_change=lambda m, key=key: m["environment_config"].pop(key),
                          name=f"v20{key}.npz"), rf"damaged model metadata .*{key}")


def test_the_load_prior_narrowed_across_the_wind_is_kept(saved, tmp_path):
    """Format 21 records the load's prior across the wind: it loads back into the filter; a
    version-20 file without it reads 1 (as it was fitted), a version-21 file without it is damaged."""
    import copy

    from hybridship.residual.environment import EnvironmentConfig

    hp = copy.deepcopy(saved[0])
    hp.environment_config = EnvironmentConfig(**{**hp.environment_config.model_dump(), "load_prior_across_wind": 0.1})
    assert HybridPredictor.load(hp.save(tmp_path / "across.npz")).estimator.config.load_prior_across_wind == 0.1

    def as_v20(meta):
        meta["format_version"] = 20
        meta["environment_config"].pop("load_prior_across_wind")

    assert HybridPredictor.load(_rewrite(saved, tmp_path, meta_change=as_v20, name="v20a.npz")
                                ).environment_config.load_prior_across_wind == 1.0
    _refused(_rewrite(saved, tmp_path, meta_change=lambda m: m["environment_config"].pop("load_prior_across_wind"),
                      name="v21a.npz"), r"damaged model metadata .*load_prior_across_wind")


def test_edited_settings_are_refused(saved, tmp_path):
    """The metadata carry their own checksum (format 13): reordering the features, or dropping
    the spread's training information, changed forecasts silently before."""
    edits = {"features": lambda m: m["residual_config"]["features"].reverse(),
             "guard": lambda m: m["guard"].update(d0=-1.0),
             "training_info": lambda m: m.pop("training_info", None)}
    for name, edit in edits.items():
        p = _rewrite(saved, tmp_path, meta_change=edit, restamp_metadata=False, name=f"edit-{name}.npz")
        _refused(p, "metadata checksum does not match")
    # nor when the version is lowered to one from before the checksum, which it still carries
    for version in (7, 12):
        p = _rewrite(saved, tmp_path, meta_change=lambda m: (edits["features"](m), m.update(format_version=version)),
                     restamp_metadata=False, name=f"edit-as-v{version}.npz")
        _refused(p, "metadata checksum does not match")


@pytest.mark.parametrize("key, value, message", [
    ("w0", lambda a: a["w0"].ravel(), "w0: expected shape"),
    ("x_mean", lambda a: a["x_mean"][:-1], "x_mean: expected"),
    ("x_std", lambda a: np.zeros_like(a["x_std"]), "x_std: a normalisation scale must be > 0"),
    ("y_mean", lambda a: np.full_like(a["y_mean"], np.nan), "y_mean: expected 3 finite values"),
    ("guard_mean", lambda a: a["guard_mean"][:-1], "guard_mean / guard_inv_cov"),
    ("w1", lambda a: a["w1"].astype(complex), "w1: expected real numbers"),
    # text in a normalisation or guard array: named, not numpy's "could not convert string to float"
    ("x_mean", lambda a: a["x_mean"].astype(str), "x_mean: expected real numbers, got dtype <U"),
    ("guard_inv_cov", lambda a: a["guard_inv_cov"].astype(str), "guard_inv_cov: expected real numbers"),
    # NaN or inf of the right shape, which only the finiteness check after the shape checks sees
    ("guard_inv_cov", lambda a: np.full_like(a["guard_inv_cov"], np.nan), "guard_inv_cov contains NaN or inf"),
    ("thrust_scale", lambda a: np.full_like(a["thrust_scale"], np.inf), "thrust_scale contains NaN or inf"),
])
def test_consistently_written_bad_arrays_are_refused(saved, tmp_path, key, value, message):
    def change(arrays):
        arrays[key] = value(arrays)

    _refused(_rewrite(saved, tmp_path, array_change=change, restamp=True, name=f"bad-{key}.npz"), message)


@pytest.mark.parametrize("key, value, message", [
    ("thrust_scale", lambda a: a["thrust_scale"][:2], "thrust_scale: expected 3 positive numbers"),
    ("thrust_scale", lambda a: np.array(["a", "b", "c"]), "thrust_scale: expected real numbers, got dtype <U1"),
    ("guard_mean", lambda a: np.zeros(3), r"guard_mean / guard_inv_cov: expected shapes \(\d+,\)"),
    ("w3", None, "damaged model contents: w3 is missing"),
])
def test_consistently_written_arrays_are_checked_against_the_model(saved, tmp_path, key, value, message):
    """Arrays of the wrong size for the model's features and axes were loaded, and the
    forecast failed later with numpy's broadcasting message."""
    def change(arrays):
        if value is None:
            del arrays[key]
        else:
            arrays[key] = value(arrays)
            if key == "guard_mean":
                arrays["guard_inv_cov"] = np.eye(3)

    _refused(_rewrite(saved, tmp_path, array_change=change, restamp=True, name=f"size-{key}.npz"), message)


@pytest.mark.parametrize("name, edit, message", [
    ("training_info", lambda m: m.update(training_info="junk"), "training_info: expected a table"),
    ("log_step", lambda m: m["training_info"].update(log_step_s=5), "training_info.log_step_s"),
    ("calibration", lambda m: m["training_info"].update(calibration="x"), "training_info.calibration"),
    ("use_guard", lambda m: m.update(use_guard="no"), "use_guard: expected true or false"),
    ("nets_after_stop", lambda m: m.update(nets_after_stop=2), "nets_after_stop: expected true or false"),
    ("window", lambda m: m.update(environment_window_s="x"), "environment_window_s: expected a number"),
    ("guard_scale", lambda m: m["guard"].update(scale=-1.0), r"guard.scale: expected a number >= 0"),
    ("guard_d0", lambda m: m["guard"].update(d0=-1.0), r"guard.d0: expected a number >= 0"),
    ("guard_list", lambda m: m.update(guard=[1, 2]), "guard: expected a table"),
    ("wind_forecast", lambda m: m.update(wind_forecast=None), "wind_forecast: expected a table"),
    ("calibrated_commands", lambda m: m.update(calibrated_commands=None), "calibrated_commands: expected a list"),
    ("env_config", lambda m: m["environment_config"].update(position_std_m=float("nan")),
     r"position_std_m: (?!.*pydantic)"),
    ("missing", lambda m: m.pop("environment"), r"environment: missing"),
    ("thrust_prior_std", lambda m: m["thrust_error_prior"].update(std=[0.0] * len(m["thrust_error_prior"]["std"])),
     "thrust_error_prior: expected finite means and positive spreads"),
    ("thrust_prior_size", lambda m: m["thrust_error_prior"].update(mean=m["thrust_error_prior"]["mean"][:-1],
                                                                   std=m["thrust_error_prior"]["std"][:-1]),
     r"thrust_error_prior: expected \d+ entries, one per"),
    ("thrust_lo", lambda m: m["thrust_regime"].update(lo=-1.0), r"thrust_regime.lo: expected a number >= 0"),
    # a prior that is not a table, or holds text (number-like text loaded as its numbers)
    ("thrust_prior_table", lambda m: m.update(thrust_error_prior=[0.0, 1.0]), "thrust_error_prior: expected a table"),
    ("thrust_prior_text",
     lambda m: m["thrust_error_prior"].update(mean=[str(x) for x in m["thrust_error_prior"]["mean"]]),
     "thrust_error_prior.mean: expected an array of real numbers"),
    ("trained_with_wind", lambda m: m["training_info"].update(trained_with_wind="yes"),
     "training_info.trained_with_wind: expected true or false"),
    # read by every calibrated forecast: loaded, then each forecast failed with Python's message
    ("after_stop", lambda m: m["training_info"].setdefault("calibration", {}).update(after_stop="x"),
     "training_info.calibration.after_stop: expected a table"),
    ("starts_within", lambda m: m["training_info"].setdefault("calibration", {}).update(
        after_stop={"starts_within_s": "20"}), r"training_info.calibration.after_stop.starts_within_s: expected"),
    ("command_regime_list", lambda m: m.update(command_regime=[0.05]), "command_regime: expected a table"),
    # a settings table written as a list: Python's "argument after ** must be a mapping", or a
    # field of it said to be missing
    *[(f"{key}_list", lambda m, key=key: m.update({key: [1, 2]}), f"{key}: expected a table of settings")
      for key in ("residual_config", "ensemble_config", "environment_config", "calibration_config",
                  "multistep_config")],
    # the features as one name or a number: split into letters, or "'int' object is not iterable"
    ("features_text", lambda m: m["residual_config"].update(features="u_hat_m_s"),
     "residual_config.features: expected a list of feature names"),
    ("features_number", lambda m: m["residual_config"].update(features=5),
     "residual_config.features: expected a list of feature names"),
])
def test_consistently_written_bad_settings_are_refused_by_name(saved, tmp_path, name, edit, message):
    """Settings of the wrong type in a re-sealed file: refused naming the field, never with a
    Python or pydantic message (a JSON list for a table crashed the CLI with a traceback)."""
    _refused(_rewrite(saved, tmp_path, meta_change=edit, restamp=True, name=f"set-{name}.npz"),
             rf"damaged model metadata \(.*{message}")


def test_the_command_regime_round_trips_and_a_damaged_one_is_refused_by_name(saved, tmp_path):
    """A model with a command regime (``command_guard``) keeps its weights, row counts and
    boundaries; weights outside [0, 1], counts that are not whole numbers >= 0, a boundary
    below 0 or a missing setting are refused naming the array or setting."""
    import copy

    from hybridship.residual.guard import CommandRegime

    hp = copy.deepcopy(saved[0])
    n = CommandRegime.N_REGIMES
    hp.command_regime = CommandRegime(np.linspace(0.0, 1.0, n), np.arange(n), np.arange(n)[::-1] + 100,
                                      rpm_eps=0.07, froude_lo=0.04, angle_hard_rad=0.3, length_m=36.25)
    with_regime = (hp, hp.save(tmp_path / "regime.npz"), None)
    back = HybridPredictor.load(with_regime[1]).command_regime
    for name in ("weights", "n_train", "n_held"):
        np.testing.assert_array_equal(getattr(back, name), getattr(hp.command_regime, name), err_msg=name)
    assert (back.rpm_eps, back.froude_lo, back.angle_hard_rad, back.length_m) == (0.07, 0.04, 0.3, 36.25)
    cases = [({"array_change": lambda a: a.update(cmd_regime_weights=np.full(n, 1.5))},
              r"cmd_regime_weights: expected 12 weights in \[0, 1\]"),
             ({"array_change": lambda a: a.update(cmd_regime_n_held=a["cmd_regime_n_held"] - 200)},
              r"cmd_regime_n_held: expected 12 counts \(whole numbers >= 0\)"),
             ({"array_change": lambda a: a.update(cmd_regime_n_train=a["cmd_regime_n_train"] + 0.5)},
              r"cmd_regime_n_train: expected 12 counts \(whole numbers >= 0\), got dtype float64"),
             ({"array_change": lambda a: a.pop("cmd_regime_n_held")}, "cmd_regime_n_held is missing"),
             ({"meta_change": lambda m: m["command_regime"].update(froude_lo=-0.1)},
              r"command_regime.froude_lo: expected a number >= 0"),
             ({"meta_change": lambda m: m["command_regime"].pop("length_m")},
              "command_regime: expected the settings rpm_eps, froude_lo, angle_hard_rad, length_m")]
    for i, (change, message) in enumerate(cases):
        _refused(_rewrite(with_regime, tmp_path, restamp=True, name=f"regime{i}.npz", **change),
                 rf"damaged model contents: {message}")


def test_metadata_that_is_not_a_table_is_refused(saved, tmp_path):
    def change(arrays):
        arrays["metadata_json"] = np.frombuffer(b"[1, 2, 3]", dtype=np.uint8)

    _refused(_rewrite(saved, tmp_path, array_change=change, name="list.npz"), "not a hybridship model file")


def test_a_bad_vessel_argument_is_not_blamed_on_the_file(saved):
    _, path, _ = saved
    with pytest.raises(TypeError, match="^vessel") as err:
        HybridPredictor.load(path, vessel=123)
    assert "damaged" not in str(err.value)


def test_a_model_file_name_and_an_unwritable_place_are_refused_by_name(saved, tmp_path):
    """save() wants a .npz name (as the CLI does); a place it cannot write names the model
    file asked for, not the hidden temporary file, and leaves nothing behind."""
    hp, _, _ = saved
    with pytest.raises(ValueError, match=r"path: .*model.csv: expected a .npz model file name"):
        hp.save(tmp_path / "model.csv")
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("x")
    with pytest.raises(OSError, match=r"not_a_folder/sub/m.npz: .*not_a_folder exists and is not a folder") as err:
        hp.save(blocker / "sub" / "m.npz")
    assert ".tmp" not in str(err.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["not_a_folder"]


def test_fit_names_an_empty_list_and_a_too_short_log(model):
    short = physics_log(model, seed=2, duration_s=300.0, t_shutdown_s=None).iloc[:2]
    with pytest.raises(ValueError, match=r"^logs: expected at least one log, got an empty list"):
        HybridPredictor(model.vessel, ensemble_config=TINY).fit([])
    with pytest.raises(ValueError, match=r"^logs\[0\]: a training log needs at least 3 samples, got 2"):
        HybridPredictor(model.vessel, ensemble_config=TINY).fit([short])


def test_a_model_that_embeds_an_added_mass_not_positive_definite_says_so(saved, tmp_path):
    """Gunnerus models trained before 2026-11-29 embed Clarke's sway-yaw coupling, whose
    added-mass matrix is not positive definite: the file is refused naming it (retrain)."""
    def clarke(m):
        m["vessel_description"]["added_mass"] = {"method": "clarke1983"}
    _refused(_rewrite(saved, tmp_path, meta_change=clarke, name="clarke.npz"),
             r"the embedded vessel is invalid: .*added_mass: M_A is not positive definite")


def test_a_round_trip_keeps_every_setting_and_the_forecasts_with_the_nets_on(model, tmp_path):
    from hybridship.predictors.model_file import model_metadata

    logs = [physics_log(model, seed=s, duration_s=600.0, t_shutdown_s=None, current=(0.2, 1.0)) for s in (3, 4)]
    hp = HybridPredictor(model.vessel, ensemble_config=TINY, hull_ridge=0.01).fit(logs)
    hp.estimator.thrust_error_mean = hp.estimator.thrust_error_mean + 0.05     # a learned prior
    back = HybridPredictor.load(hp.save(tmp_path / "m.npz"))
    as_json = lambda p: json.loads(json.dumps(model_metadata(p), sort_keys=True))  # noqa: E731
    assert as_json(back) == as_json(hp)
    # every setting the predictor holds comes back (a field model_metadata forgets is not compared above)
    for k, v in vars(hp).items():
        if v is None or isinstance(v, (bool, int, float, str)) or k.endswith("_config") or k == "wind_forecast":
            assert getattr(back, k) == v, k
    assert set(back.calibration) == set(hp.calibration)
    for commands in ("held", "known"):
        a = hp.forecast(logs[0], [300.0, 350.0], 30.0, commands=commands)
        b = back.forecast(logs[0], [300.0, 350.0], 30.0, commands=commands)
        np.testing.assert_array_equal(b.eta, a.eta)
        np.testing.assert_array_equal(b.eta_std, a.eta_std)
