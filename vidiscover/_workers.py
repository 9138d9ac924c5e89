"""Worker processes for the stages that run independent tasks side by side.

Shared by :mod:`vidiscover.discovery` (recordings analysed and impact laws fitted side
by side), :mod:`vidiscover.gap` (candidate fits) and :mod:`vidiscover.scale` (sweeps):
one check of ``n_jobs`` and one way to start forked workers.

A forked worker starts with this process's imports and inputs in memory: about 0.1 s,
where a spawned interpreter (loky's) first pays 1-2 s of imports, as long as one
analysis. Forking is used only where it is safe and available: Linux, and not from a
daemonic worker (which may not have children).
"""

from __future__ import annotations

import os
import sys

from .errors import InputError

__all__ = ["n_workers", "can_fork", "fork_executor"]


def n_workers(n_jobs: int | None) -> int:
    """The number of processes ``n_jobs`` asks for (``None``: all cores).

    Raises
    ------
    InputError
        If ``n_jobs`` is not a positive integer or None.
    """
    if n_jobs is None:
        return os.cpu_count() or 1
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, int) or n_jobs < 1:
        raise InputError(f"n_jobs must be a positive integer or None (all cores), "
                         f"was {n_jobs!r}")
    return n_jobs


def can_fork() -> bool:
    """Whether this process may fork workers: Linux, and not a daemonic worker itself."""
    import multiprocessing

    return (sys.platform.startswith("linux")
            and "fork" in multiprocessing.get_all_start_methods()
            and not multiprocessing.current_process().daemon)


def fork_executor(max_workers: int):
    """A process pool of ``max_workers`` forks of this process, forked now.

    Call it before this process starts threads of its own (a progress bar's monitor):
    a fork copies no thread but may copy a lock one holds. The standard streams are
    flushed first, so that no child writes this process's buffered output again.
    Python >= 3.12's warning about forking a process with threads is silenced: the
    only ones at this point are the BLAS library's idle pool, which its own fork
    handler re-forms in the child. Shut it down with ``shutdown(wait=True)``.

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor or None
        None where forking is not available (see :func:`can_fork`) or
        ``max_workers < 1``: the caller runs its tasks itself.
    """
    if max_workers < 1 or not can_fork():
        return None
    import multiprocessing
    import warnings
    from concurrent.futures import ProcessPoolExecutor

    sys.stdout.flush()
    sys.stderr.flush()
    executor = ProcessPoolExecutor(max_workers=max_workers,
                                   mp_context=multiprocessing.get_context("fork"))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r".*use of fork\(\) may lead",
                                category=DeprecationWarning)
        executor.submit(os.getpid)     # a fork pool forks all its workers in its first submit
    return executor
