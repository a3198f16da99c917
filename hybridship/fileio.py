"""Atomic file writes: a crash never leaves a half-written log, model or table behind, and a
command's output folder never loses a file the user put there."""

from __future__ import annotations

import hashlib
import json
import os
import stat
import uuid
from collections.abc import Mapping
from pathlib import Path
from typing import BinaryIO, Callable


def path_argument(text: str) -> Path:
    """A command-line path (argparse ``type=``): refused when empty, which ``Path`` would
    read as the current folder."""
    import argparse

    if not str(text).strip():
        raise argparse.ArgumentTypeError(f"expected a path, got {text!r}")
    return Path(text)


def vessel_argument(text: str) -> str:
    """A command-line ``--vessel`` (argparse ``type=``): a packaged name or a file path, refused
    when empty (the library's TypeError would name its Python argument, with exit status 1)."""
    import argparse

    if not str(text).strip():
        raise argparse.ArgumentTypeError(f"expected a packaged vessel name or a vessel file, got {text!r}")
    return text


def as_path(value, name: str = "path") -> Path:
    """``value`` as a Path, or a TypeError naming ``name`` when it is not a path (None, a
    DataFrame, a number) rather than os.fspath's own message."""
    if isinstance(value, (str, os.PathLike)) and str(value):
        return Path(value)
    if isinstance(value, (str, os.PathLike)):
        raise ValueError(f"{name}: expected a file path, got an empty one")
    raise TypeError(f"{name}: expected a file path (str or os.PathLike), got {type(value).__name__}")


def check_writable(path) -> Path:
    """``path`` as a Path, refused when the folder it would be written in exists and does
    not let this process create files, or when ``path`` is a read-only file
    (PermissionError), or when a file stands where that folder, or one to be made for it,
    would be (NotADirectoryError): checked before the work (a model trained for minutes),
    not when the result is written."""
    path = Path(path)
    folder = next((p for p in path.parents if p.exists()), Path("."))
    if not folder.is_dir():
        raise NotADirectoryError(f"{path}: {folder} exists and is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise PermissionError(f"{path}: cannot be written (no permission to create files in {folder})")
    if path.is_file() and not path.stat().st_mode & stat.S_IWUSR:
        # the rename would replace it even so (a directory entry, not the file, is written)
        raise PermissionError(f"{path}: is read-only; not replaced")
    return path


def check_out_folder(path) -> Path:
    """``path`` as a Path, refused (NotADirectoryError) when it, or a folder it would be made
    in, exists and is not a folder: an output folder checked before the work, not when the
    first file is written."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise NotADirectoryError(f"{path}: exists and is not a folder")
    for parent in path.parents:  # a file on the way would fail only when the first file is written
        if parent.exists():
            if not parent.is_dir():
                raise NotADirectoryError(f"{path}: {parent} exists and is not a folder")
            break
    return path



def lies_within(path, folder) -> bool:
    """Whether ``path`` is ``folder`` or lies inside it (links resolved): an output folder
    there would be searched with the folder's sub-folders as input."""
    path, folder = Path(path).resolve(), Path(folder).resolve()
    return path == folder or folder in path.parents


def make_out_folder(path) -> Path:
    """Make the output folder ``path`` (and its parents); an OSError names it.

    ``Path.mkdir`` names only the first folder it could not make ("No such file or
    directory: '/proc/x'"), not the output folder the user gave."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise type(err)(f"{path}: cannot make the output folder ({err.strerror or err})") from None
    return path


def atomic_write(path, write: Callable[[BinaryIO], None]) -> Path:
    """Write ``path`` through ``write(fh)`` into a temporary file beside it, then rename.

    The temporary file is created exclusively in the same directory (so ``os.replace`` is
    atomic), flushed and fsynced before the rename, and removed if anything fails, in
    which case an existing file at ``path`` is left untouched. A ``path`` that is a
    symbolic link is written through: the file it points to is replaced, the link kept.
    A new file's permissions follow the umask; a file replaced keeps its own.

    Raises
    ------
    TypeError, ValueError
        ``path`` is not a file path (None, a number, an empty text, which ``Path`` reads as
        the current folder), or ``write`` is not callable.
    OSError
        ``path`` cannot be written (a folder, read-only, a file where its folder would be),
        naming ``path``.
    """
    path = as_path(path, "path")
    if not callable(write):
        raise TypeError(f"write: expected a function that writes to a binary file, got {type(write).__name__}")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory; expected the path of a file to write")
    # a symbolic link is written through, as open() does: the rename would replace the link itself
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    check_writable(target)        # a file where a folder should be is named as such; a read-only file
    # the name cut short (50 characters, 200 bytes at most in UTF-8): a file name near the limit of
    # 255 bytes left no room for the suffix
    tmp = target.with_name(f".{target.name[:50]}.{uuid.uuid4().hex}.tmp")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "xb") as fh:  # 'x': never clobber; mode follows the umask
            if target.is_file():    # a file replaced keeps its permissions (a private log stays private)
                os.chmod(fh.fileno(), stat.S_IMODE(target.stat().st_mode))
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except OSError as err:
        _discard(tmp)
        ours = ({os.fspath(tmp), os.fspath(path), os.fspath(target)} | {os.fspath(p) for p in path.parents}
                | {os.fspath(p) for p in target.parents})
        if err.filename is not None and os.fspath(err.filename) not in ours:
            raise   # about another file (one the writer reads), not the one written
        # the error names the hidden temporary file (or the folder); the user asked for ``path``
        exc = type(err)(f"{path}: cannot be written ({err.strerror or err})")
        exc.errno = err.errno       # kept for callers, out of the message ("[Errno 2] ...")
        raise exc from None
    except BaseException:
        _discard(tmp)
        raise
    return path


def write_text(path, text: str) -> Path:
    """Write UTF-8 text to ``path`` atomically (:func:`atomic_write`); TypeError naming
    ``text`` when it is not a str (bytes or None failed inside the writer, as an AttributeError)."""
    if not isinstance(text, str):
        raise TypeError(f"text: expected a str, got {type(text).__name__}")
    return atomic_write(path, lambda fh: fh.write(text.encode("utf-8")))


def _discard(tmp: Path) -> None:
    """Remove a temporary file if it is there; never raise (its folder may not exist, or be a file)."""
    try:
        tmp.unlink(missing_ok=True)
    except OSError:
        pass


def starts_with(path, magic: bytes) -> bool:
    """Whether the file's first bytes are ``magic`` (False when it cannot be read)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(magic)) == magic
    except OSError:
        return False


#: The record, in an output folder, of the files hybridship commands wrote there.
OUTPUTS_RECORD = ".hybridship-outputs.json"


def _recorded_outputs(folder: Path) -> set[str]:
    try:
        names = json.loads((folder / OUTPUTS_RECORD).read_text(encoding="utf-8"))
        return {str(n) for n in names} if isinstance(names, list) else set()
    except (OSError, ValueError):
        return set()


def earlier_run(names, marker: str, head: bytes) -> Callable[[str, Path], bool]:
    """An ``ours`` for :func:`check_output_files`: the files ``names`` of a command's run from
    before folders kept a record of their outputs, recognised by the run's ``marker`` file
    beside them starting with ``head`` (a benchmark's tables or README)."""
    names = frozenset(names)
    return lambda name, path: name in names and starts_with(path.with_name(marker), head)


def check_output_files(folder, written, removed=(), ours=None) -> None:
    """Refuse, before any work, output files that would replace or remove a file a hybridship
    command did not write, or be written where a folder is (FileExistsError), or a read-only
    one (PermissionError); see :func:`write_output_files` for ``ours``."""
    folder, written = Path(folder), list(written)
    recorded = _recorded_outputs(folder)
    for name in [*written, *removed]:
        path = folder / name
        if name in written and path.is_dir():      # found only when written, after the files before it
            raise FileExistsError(f"{path}: is a folder, where the file {name} would be written: give another "
                                  f"output folder or move it")
        if not path.is_file():
            continue
        if name not in recorded and not (ours is not None and ours(name, path)):
            raise FileExistsError(f"{path}: exists and was not written by hybridship; it would be "
                                  f"{'replaced' if name in written else 'removed'}: give another output folder "
                                  f"or move it")
        if not path.stat().st_mode & stat.S_IWUSR:
            raise PermissionError(f"{path}: is read-only; nothing was written (give another output folder)")


def write_output_files(folder, contents: dict, *, stale=(), ours=None) -> dict:
    """Write a command's files into ``folder`` and remove its ``stale`` ones (those only other
    options make), without losing a file the user put there.

    Before anything is written, every file to be replaced or removed must be one a
    hybridship command wrote (listed in the folder's :data:`OUTPUTS_RECORD`, or, for a
    folder from before that record, accepted by ``ours(name, path)``) and writable;
    otherwise FileExistsError or PermissionError names it and nothing changes. Each file is
    then written atomically (:func:`atomic_write`) and added to the record as it is written.

    Parameters
    ----------
    folder : path
        The output folder (created).
    contents : dict
        File name -> bytes.
    stale : iterable of str
        File names removed where present; none of them in ``contents``.
    ours : callable, optional
        ``ours(name, path) -> bool`` for files not in the record.

    Returns
    -------
    dict
        File name -> path written.
    """
    folder = as_path(folder, "folder")
    # checked before any file is written: a str content failed in the writer, after the
    # folder was made and the files before it were written
    if not isinstance(contents, Mapping):
        raise TypeError(f"contents: expected a dict of file name -> bytes, got {type(contents).__name__}")
    for name, data in contents.items():
        if not isinstance(name, str) or not name or not isinstance(data, (bytes, bytearray, memoryview)):
            raise TypeError(f"contents: expected file name -> bytes, got {name!r} -> {type(data).__name__}")
    if isinstance(stale, (str, bytes)):
        raise TypeError(f"stale: expected a list of file names, got {stale!r}")
    stale = list(stale)     # read three times below: a generator would be empty after the check
    both = [name for name in stale if name in contents]
    if both:    # it would be written, then removed, and its path returned
        raise ValueError(f"stale: {', '.join(both)} also in contents; a file written is not stale")
    check_output_files(folder, contents, stale, ours)
    paths = {}
    for name, data in contents.items():
        paths[name] = atomic_write(folder / name, lambda fh, b=data: fh.write(b))
        record_outputs(folder, [name])      # as it is written: an interrupted run's files are ours too
    remove_stale(folder, stale)
    record_outputs(folder, contents, removed=stale)
    return paths


def record_outputs(folder, names, removed=()) -> None:
    """Add ``names`` (and drop ``removed``) in the folder's record of the files hybridship
    commands wrote there (:data:`OUTPUTS_RECORD`), for commands that write their files
    themselves after :func:`check_output_files`."""
    folder = Path(folder)
    record = sorted((_recorded_outputs(folder) - set(removed)) | set(names))
    atomic_write(folder / OUTPUTS_RECORD, lambda fh: fh.write(json.dumps(record).encode("utf-8")))


def remove_stale(folder, names) -> list[Path]:
    """Remove the files ``names`` from ``folder`` where they exist; return those removed.

    For the outputs a command makes only with some options (a figure switched off): an
    earlier run's copy left in a reused output folder would sit beside this run's tables
    as if it belonged to them. Only the command's own file names are passed here.
    """
    removed = []
    for name in names:
        path = Path(folder) / name
        if path.is_file():
            path.unlink()
            removed.append(path)
    return removed


def markdown_table(df) -> str:
    """A pandas DataFrame (its columns, then its rows as they are) as a Markdown table; a
    ``|`` in a name or value is written ``\\|``, so that it stays in its cell."""
    def cell(v) -> str:
        return str(v).replace("|", "\\|")

    head = "| " + " | ".join(cell(c) for c in df.columns) + " |"
    sep = "| " + " | ".join("---" for _ in df.columns) + " |"
    rows = ["| " + " | ".join(cell(v) for v in r) + " |" for r in df.itertuples(index=False)]
    return "\n".join([head, sep, *rows])


def record_inputs(output, inputs) -> Path:
    """Write ``<output>.inputs.json`` beside ``output``: the SHA-256 of every file it was made
    from, keyed by that file's path relative to ``output``'s folder, so that a check can tell
    a result whose input (another committed result) has changed since it was made."""
    output = as_path(output, "output")
    if isinstance(inputs, (str, bytes, os.PathLike)):
        # a lone path would be read character by character, as files named "a", "/", ...
        raise TypeError(f"inputs: expected a list of file paths, got the single path {inputs!r}")
    inputs = [as_path(p, "inputs") for p in inputs]
    missing = [str(p) for p in inputs if not p.is_file()]
    if missing:
        raise FileNotFoundError(f"inputs: not a file: {', '.join(missing)}")
    made_from = {Path(os.path.relpath(Path(p).resolve(), output.parent.resolve())).as_posix():
                 hashlib.sha256(Path(p).read_bytes()).hexdigest() for p in inputs}
    text = json.dumps({"output": output.name, "made_from": made_from}, indent=1, sort_keys=True) + "\n"
    return write_text(output.with_name(output.name + ".inputs.json"), text)
