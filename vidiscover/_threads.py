"""The native thread pools (BLAS), as threadpoolctl sees them, looked up once per process.

``threadpoolctl.threadpool_limits`` looks the loaded libraries up afresh on every call (a
scan of the process's memory map: about 0.4 ms and 24,000 Python calls here); numpy's
BLAS, the only pool limited here, is loaded with numpy, before the first call. Used by the
sensor model's matrix products and the pulse learner's search, in the simulator's and the
analysis's processes alike (a process forked later inherits the lookup).
"""

from __future__ import annotations

import functools

from threadpoolctl import ThreadpoolController


@functools.lru_cache(maxsize=1)
def blas_controller():
    """The process's :class:`threadpoolctl.ThreadpoolController`, built on first use."""
    return ThreadpoolController()


def one_blas_thread():
    """Context manager holding BLAS to one thread; the earlier limits come back on exit."""
    return blas_controller().limit(limits=1, user_api="blas")
