"""Ctrl-C bookkeeping shared by the command line and the atomic writers.

After a Ctrl-C the command line raises KeyboardInterrupt again at short intervals
until the command stops, because some libraries swallow it (an extension module's
import can turn it into an ImportError that a fallback import catches). The repeats
must not cut a cleanup short: cleanups run inside :func:`cleanup`, and a repeat that
falls inside one is skipped (the next one comes after it).

Examples
--------
>>> from vidiscover._interrupt import cleanup, in_cleanup
>>> with cleanup():
...     in_cleanup()
True
>>> in_cleanup()
False
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = ["cleanup", "in_cleanup"]

_depth = [0]


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
