"""All-or-nothing file output (used through :mod:`vidiscover.io`).

Files are written to temporary names in their target directory and renamed into place
(``os.replace``, atomic on one file system) only when every one of them was written;
a failure while renaming restores what was there before. :func:`atomic_directory`
does the same for a whole output directory.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import tempfile
import uuid
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ._interrupt import cleanup, stop_if_interrupted
from .errors import InputError

_replace = os.replace  # seam: tests inject a failure while committing files


def to_jsonable(obj: Any) -> Any:
    """Return a JSON-ready copy of ``obj``.

    Numpy scalars and arrays become Python numbers and lists, paths strings, objects
    with ``to_dict()`` their dict, tuples and sets lists; non-finite floats become
    None (``null``), which strict JSON readers accept.

    Parameters
    ----------
    obj : any
        Nested dicts, lists, numbers, strings, numpy values, paths.

    Returns
    -------
    any
        Plain dicts, lists, str, int, float, bool and None.

    Raises
    ------
    TypeError
        An object of another type.

    Examples
    --------
    >>> import numpy as np
    >>> to_jsonable({"r": np.float64(0.88), "n": np.arange(2), "rms": float("nan")})
    {'r': 0.88, 'n': [0, 1], 'rms': None}
    """
    if obj is None or isinstance(obj, (str, bool)):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):              # also numpy.float64, a float subclass
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if hasattr(obj, "to_dict"):
        return to_jsonable(obj.to_dict())
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def dump_json(tmp: Path, obj: Any, indent: int | None) -> None:
    """Write ``obj`` as strict JSON to the new file ``tmp``."""
    text = json.dumps(to_jsonable(obj), indent=indent, allow_nan=False)
    with open(tmp, "x", encoding="utf-8") as fh:
        fh.write(text + "\n")


def _temp_name(target: Path, tag: str) -> Path:
    return target.with_name(f".{target.name}.{uuid.uuid4().hex[:12]}.{tag}")


def write_group(jobs: list[tuple[Path, Callable[[Path], None]]],
                remove: tuple[Path, ...] = ()) -> list[Path]:
    """Write every target through a temp file; commit all or leave everything as it was.

    Parameters
    ----------
    jobs : list of (Path, callable)
        Each target with a function that writes a given (new) temp path.
    remove : tuple of Path
        Files to delete in the same commit (stale sidecars).

    Returns
    -------
    list of Path
        The targets.
    """
    temps: list[Path] = []
    try:
        for target, write in jobs:
            tmp = _temp_name(target, "tmp")
            temps.append(tmp)
            write(tmp)
        stop_if_interrupted()
        _commit([(tmp, target) for tmp, (target, _) in zip(temps, jobs, strict=True)], remove)
    except BaseException:
        with cleanup():
            for tmp in temps:
                with contextlib.suppress(OSError):
                    tmp.unlink()
        raise
    return [target for target, _ in jobs]


def _commit(pairs: list[tuple[Path, Path]], remove: tuple[Path, ...]) -> None:
    """Move temps onto targets; on failure restore what was there before."""
    done: list[tuple[Path, Path | None]] = []   # (target, backup of its old content)
    try:
        for target in remove:
            if target.exists():
                backup = _temp_name(target, "bak")
                _replace(target, backup)
                done.append((target, backup))
        for tmp, target in pairs:
            backup = None
            if target.exists():
                backup = _temp_name(target, "bak")
                _replace(target, backup)
            done.append((target, backup))
            _replace(tmp, target)
    except BaseException:
        with cleanup():
            for target, backup in reversed(done):
                with contextlib.suppress(OSError):
                    if backup is not None:
                        _replace(backup, target)
                    elif target.exists():
                        target.unlink()
        raise
    for _, backup in done:
        if backup is not None:
            with contextlib.suppress(OSError):
                backup.unlink()


def write_json(path: str | os.PathLike, obj: Any, indent: int | None = 2) -> Path:
    """Write ``obj`` as JSON atomically (temp file + rename).

    Parameters
    ----------
    path : str or path-like
        Target file; its directory must exist.
    obj : any
        Converted with :func:`to_jsonable` (numpy values, paths; NaN -> null).
    indent : int or None
        JSON indentation; None for compact output.

    Returns
    -------
    Path
        The file written.
    """
    path = Path(path)
    write_group([(path, lambda tmp: dump_json(tmp, obj, indent))])
    return path


#: File that marks a directory as an output of vidiscover (replaced as a whole).
MARKER = ".vidiscover"
_MARKER_TEXT = ("This folder was written by vidiscover. The next command writing here "
                "replaces it as a whole.\n")


def check_output_dir(out: str | os.PathLike) -> Path:
    """Refuse, in one line, an output directory that cannot be replaced or written.

    A directory may be written when it does not exist yet, is empty, or was written
    by vidiscover (it holds :data:`MARKER`); it is then replaced as a whole. A file,
    a folder holding anything else, or a location that cannot be written is refused.

    Raises
    ------
    InputError
        With what is wrong and how to fix it.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a directory; choose another --out")
    if out.is_dir() and not (out / MARKER).exists() and any(out.iterdir()):
        raise InputError(f"{out}: holds files that vidiscover did not write; choose a new "
                         "or empty --out (a folder vidiscover wrote is replaced as a whole)")
    check_writable(out)
    return out


def check_writable(target: str | os.PathLike) -> None:
    """Refuse, in one line, a path whose nearest existing folder cannot be written.

    Probes by creating and removing a temporary file (permission bits do not tell:
    root may write a mode 555 folder but not a read-only file system).
    """
    target = Path(target)
    parent = target if target.is_dir() else target.parent
    while not parent.exists():
        parent = parent.parent
    try:
        fd, probe = tempfile.mkstemp(dir=parent, prefix=".vidiscover-probe.")
    except OSError as err:
        raise InputError(f"{target}: cannot write in {parent} ({err.strerror or err}); "
                         "choose a writable --out") from None
    os.close(fd)
    os.unlink(probe)


@contextlib.contextmanager
def atomic_directory(out_dir: str | os.PathLike) -> Iterator[Path]:
    """Write a stage's outputs into a temporary sibling, then put it in place whole.

    Parameters
    ----------
    out_dir : str or path-like
        The output directory (created on success, with its parents).

    Yields
    ------
    Path
        A temporary directory beside ``out_dir`` to write into.

    Raises
    ------
    InputError
        ``out_dir`` is a file, a folder holding files vidiscover did not write, or
        cannot be created (:func:`check_output_dir`).

    Notes
    -----
    On success the temporary directory, marked with :data:`MARKER`, replaces
    ``out_dir`` as a whole (nothing of an earlier run survives). On any exception,
    Ctrl-C included, the temporary directory and the parents created for it are
    removed, ``out_dir`` is left as it was and the exception propagates.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> base = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_directory(base / "out") as tmp:
    ...     _ = (tmp / "summary.json").write_text("{}")
    >>> sorted(p.name for p in (base / "out").iterdir())
    ['.vidiscover', 'summary.json']
    >>> import shutil; shutil.rmtree(base)
    """
    out = check_output_dir(out_dir)
    created = []                    # parents to create, deepest first
    parent = out.parent
    while not parent.exists():
        created.append(parent)
        parent = parent.parent
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp"))
    except OSError as err:
        _remove_dirs(created)
        raise InputError(f"{out}: cannot create the output directory "
                         f"({err.strerror or err}); check the path and permissions") from None
    try:
        yield tmp
        (tmp / MARKER).write_text(_MARKER_TEXT, encoding="utf-8")
        stop_if_interrupted()
    except BaseException:
        with cleanup():
            shutil.rmtree(tmp, ignore_errors=True)
            _remove_dirs(created)
        raise
    old = None
    try:
        if out.exists():
            old = _temp_name(out, "old")
            out.rename(old)
        tmp.rename(out)
    except BaseException:
        with cleanup():
            if old is not None and not out.exists():
                old.rename(out)
            shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        if old is not None and out.exists():
            shutil.rmtree(old, ignore_errors=True)


def _remove_dirs(created: list[Path]) -> None:
    for d in created:
        with contextlib.suppress(OSError):
            d.rmdir()
