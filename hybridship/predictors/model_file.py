"""The model file of :class:`~hybridship.predictors.hybrid.HybridPredictor`: format version,
errors, content checksum and the embedded vessel.

A model file is one ``.npz`` (arrays only, read with ``allow_pickle=False``) whose JSON
metadata carry the validated vessel description, so a model loads without its vessel file
and without executing code from the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["MODEL_FORMAT_VERSION", "ModelFileError"]

#: Version of the model-file format written by :meth:`HybridPredictor.save`.
#: 5: the spread calibration, the nets' training mode and the command regime; 4: the
#: validated vessel description is embedded in the metadata (``vessel_description``), so a
#: model loads without its vessel file; 3 added the environment estimator; 2 and earlier
#: stored only the vessel's name.
MODEL_FORMAT_VERSION = 5


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


def _vessel_fingerprint(vessel) -> str:
    """A stable hash of the validated vessel description (so a model is not used on another ship)."""
    from ..vessel import fingerprint

    return fingerprint(vessel)
