"""Keep numba's on-disk cache of the compiled kernels in step with their sources.

numba invalidates a cached kernel only when the file that defines it changes, not when a
function it calls from another file does (numba's documentation, "Cache invalidation").
Our kernels call across files (the environment filter and the drift-off engine call the
hull and thruster kernels of ``rhs.py``), so after an edit of ``hull.py`` alone, or a
``git pull`` that changes only it, a cached ``rollout_batch`` would go on running the old
hull. Before any kernel is compiled, :func:`drop_stale_compiled_kernels` hashes the
sources of every module that defines one and, when the hash differs from the one stored
with the cache, deletes that cache so numba compiles anew.

This covers numba's default in-tree cache (``__pycache__`` beside each module). With
``NUMBA_CACHE_DIR`` set, numba caches elsewhere and the user manages that folder.
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1]
STAMP_NAME = "compiled-kernels.sha256"
_IMPORTS_NUMBA = re.compile(r"^\s*(import numba|from numba)\b", re.MULTILINE)
#: This module, hashed with the kernels' modules: numba's cache does not know the flags below.
_FLAGS_FILE = "physics/compiled_cache.py"

#: numba fast-math flags of every physics kernel: all but ``contract`` (fused multiply-add)
#: and ``reassoc`` (reordered sums). With either, LLVM could emit different instructions for
#: a kernel compiled in the running process and for the same kernel loaded from numba's
#: cache: on a CPU with AVX-512 a Gunnerus rollout differed by 1.8e-15 m and multi-step
#: training's validation loss in its last bits, so one command gave two results
#: (``benchmarks/compile_cache_determinism.py``, ``tests/test_compiled_cache.py``).
KERNEL_FASTMATH = {"nnan", "ninf", "nsz", "arcp", "afn"}


def kernel_source_files(package_dir: Path = PACKAGE_DIR) -> list[Path]:
    """The package's modules that import numba (every kernel's home) and this module (the
    kernels' fast-math flags), sorted by path."""
    return [path for path in sorted(package_dir.rglob("*.py"))
            if path.relative_to(package_dir).as_posix() == _FLAGS_FILE
            or _IMPORTS_NUMBA.search(path.read_text(encoding="utf-8"))]


def kernel_sources_hash(files: list[Path], package_dir: Path = PACKAGE_DIR) -> str:
    """SHA-256 over the files' package-relative paths and contents."""
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.relative_to(package_dir).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return digest.hexdigest()


def drop_stale_compiled_kernels(package_dir: Path = PACKAGE_DIR) -> bool:
    """Delete the cached kernels if any kernel module changed since they were cached.

    Returns True when cache files were deleted. A read-only install (no ``__pycache__``
    to write) or a user-chosen ``NUMBA_CACHE_DIR`` is left alone.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return False
    files = kernel_source_files(package_dir)
    current = kernel_sources_hash(files, package_dir)
    stamp = package_dir / "__pycache__" / STAMP_NAME
    try:
        if stamp.read_text(encoding="ascii").strip() == current:
            return False
    except (OSError, UnicodeDecodeError):
        pass  # no stamp yet (or unreadable): treat the cache as stale
    dropped = False
    try:
        for folder in {path.parent / "__pycache__" for path in files}:
            for cached in list(folder.glob("*.nbi")) + list(folder.glob("*.nbc")):
                try:
                    cached.unlink()
                    dropped = True
                except FileNotFoundError:
                    pass  # another process dropped it first
        stamp.parent.mkdir(exist_ok=True)
        tmp = stamp.with_name(f"{STAMP_NAME}.{os.getpid()}.tmp")
        tmp.write_text(current + "\n", encoding="ascii")
        os.replace(tmp, stamp)  # atomic: a concurrent reader sees the old or the new stamp
    except OSError:
        return dropped  # not writable here: numba then caches in the user's folder
    return dropped
