"""Ctrl-C bookkeeping shared by the command line and the atomic writers.

The command line marks an interrupt (:func:`mark_interrupted`) as soon as Ctrl-C
arrives; a library may swallow the KeyboardInterrupt (a reader turning it into its own
error, then handled as a bad file), so the atomic writers ask
(:func:`stop_if_interrupted`) before they put any output in place.

After a Ctrl-C the command line also raises KeyboardInterrupt again at short intervals
until the command stops (an extension module's import can turn it into an ImportError
that a fallback import catches). The repeats must not cut a cleanup short: cleanups
run inside :func:`cleanup`, and a repeat that falls inside one is skipped (the next
one comes after it).

Examples
--------
>>> from vidiscover._interrupt import cleanup, in_cleanup
>>> with cleanup():
...     in_cleanup()
True
>>> in_cleanup()
False
>>> from vidiscover._interrupt import interrupted
>>> interrupted()
False
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = ["cleanup", "in_cleanup", "mark_interrupted", "interrupted", "stop_if_interrupted"]

_depth = [0]
_interrupted = [False]


def mark_interrupted(value: bool = True) -> None:
    """Record that Ctrl-C arrived (``False``: a new command starts, nothing arrived)."""
    _interrupted[0] = bool(value)


def interrupted() -> bool:
    """Whether Ctrl-C arrived during the running command."""
    return _interrupted[0]


def stop_if_interrupted() -> None:
    """Raise KeyboardInterrupt if Ctrl-C arrived, even if some library swallowed it."""
    if _interrupted[0]:
        raise KeyboardInterrupt


@contextlib.contextmanager
def cleanup() -> Iterator[None]:
    """Mark a cleanup (temporary files being removed): no repeated interrupt inside."""
    _depth[0] += 1
    try:
        yield
    finally:
        _depth[0] -= 1


def in_cleanup() -> bool:
    """Whether a cleanup is running."""
    return _depth[0] > 0
