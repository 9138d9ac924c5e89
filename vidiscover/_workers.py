"""Worker processes for the stages that run independent tasks side by side.

One check of ``n_jobs`` (:func:`n_workers`, also used by :mod:`vidiscover.scale`'s
sweeps, which run on joblib or Dask) and one runner, :class:`WorkerPool`, shared by
:mod:`vidiscover.discovery` (recordings analysed and impact laws fitted side by side)
and :mod:`vidiscover.gap` (candidate fits).

A forked worker starts with this process's imports and inputs in memory: about 0.1 s,
where a spawned interpreter (loky's) first pays 1-2 s of imports, as long as one
analysis. Forking is used only where it is safe and available: Linux, and not from a
daemonic worker (which may not have children).
"""

from __future__ import annotations

import contextlib
import gc
import os
import sys
from collections.abc import Iterator

from .errors import InputError

__all__ = ["n_workers", "can_fork", "fork_executor", "gc_paused", "short_blas_spin",
           "WorkerPool"]

#: How long an idle OpenBLAS thread spins before it sleeps, as log2 of CPU cycles
#: (``OPENBLAS_THREAD_TIMEOUT``; OpenBLAS's default 28, about 0.1 s; 16, about 25 us).
BLAS_SPIN_LOG2_CYCLES = 16


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


@contextlib.contextmanager
def gc_paused() -> Iterator[None]:
    """The cyclic garbage collector off for a block of imports, as it was after it.

    Importing a library stack makes hundreds of thousands of objects that are kept
    (modules, classes, functions), and the collector walks them again and again to
    find none to free: about 8 % of the CPU of importing pandas, scipy and pysindy.
    Used by ``discover``'s command (its own imports) and its workers' warm-ups.
    """
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def short_blas_spin() -> bool:
    """Make OpenBLAS's idle threads sleep after ~25 us instead of spinning ~0.1 s.

    After every call it runs on several threads, OpenBLAS keeps its helper threads
    spinning for 2**28 cycles by default, waiting for the next call. With more busy
    processes than cores (``discover``'s analysts and law workers, two to four on two
    cores), those spinning threads take the cores from the processes doing the work:
    ``discover`` on three recordings used 5.3 instead of 5.9 s of CPU in all with
    :data:`BLAS_SPIN_LOG2_CYCLES` (interleaved runs). The number of threads and the
    split of every call stay the same, so results are bit for bit the same.

    OpenBLAS reads the setting when it loads: this sets ``OPENBLAS_THREAD_TIMEOUT``
    (unless the user did) only while numpy is not loaded yet, in a process of the
    command line's own (it stays in the environment of its children).

    Returns
    -------
    bool
        Whether the setting will apply (numpy not loaded yet).
    """
    if "numpy" in sys.modules:
        return False
    os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", str(BLAS_SPIN_LOG2_CYCLES))
    return True


def can_fork() -> bool:
    """Whether this process may fork workers: Linux, and not a daemonic worker itself."""
    import multiprocessing

    return (sys.platform.startswith("linux")
            and "fork" in multiprocessing.get_all_start_methods()
            and not multiprocessing.current_process().daemon)


def _follow_parent(parent: int) -> None:
    """Make this worker end with the process that forked it (run first in each worker).

    Linux's ``PR_SET_PDEATHSIG`` sends the worker SIGTERM when its parent ends, however
    it ends (an interrupt sent to the parent alone, a kill, a crash): otherwise a worker
    blocked writing a result nobody reads would wait forever. A parent already gone
    before the call ends the worker at once.
    """
    import ctypes
    import signal

    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGTERM))   # PR_SET_PDEATHSIG
    except (OSError, AttributeError):   # no prctl: the worker ends with its pipe instead
        pass
    if os.getppid() != parent:
        os._exit(1)


def fork_executor(max_workers: int):
    """A process pool of ``max_workers`` forks of this process, forked now.

    Call it before this process starts threads of its own (a progress bar's monitor):
    a fork copies no thread but may copy a lock one holds. The standard streams are
    flushed first, so that no child writes this process's buffered output again.
    Python >= 3.12's warning about forking a process with threads is silenced: the
    only ones at this point are the BLAS library's idle pool, which its own fork
    handler re-forms in the child. Each worker ends with this process, however it ends
    (:func:`_follow_parent`). Shut it down with ``shutdown(wait=True)``.

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
                                   mp_context=multiprocessing.get_context("fork"),
                                   initializer=_follow_parent, initargs=(os.getpid(),))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r".*use of fork\(\) may lead",
                                category=DeprecationWarning)
        executor.submit(os.getpid)     # a fork pool forks all its workers in its first submit
    return executor


class WorkerPool:
    """Independent tasks shared between this process and ``n`` worker processes.

    One runner for every stage that runs independent tasks side by side (the
    analyses and impact laws of :func:`~vidiscover.discovery.discover`, the candidate
    fits of :func:`~vidiscover.gap.diagnose`):

    * :meth:`map` keeps one queue of tasks, the costliest first; this process and
      every worker take the next task when they are free, so no core waits for a
      worker still starting and no task waits behind a long one it could pass;
    * :meth:`submit` / :meth:`result` start one task ahead while this process does
      something else;
    * a task lost with its worker (killed, out of memory) is run again here;
    * a task's exception is raised in the caller, after the running tasks are done.

    A task gives the same result wherever it runs, so results never depend on the
    number of workers. On Linux the workers are forks of this process
    (:func:`fork_executor`: they start with its imports and inputs in memory, in
    about 0.1 s). Elsewhere, or inside a daemonic worker, there are no workers and
    this process runs every task, unless ``spawn_env`` asks for loky's reusable
    spawned workers (with that environment), which outlive the pool.

    Parameters
    ----------
    n : int
        Worker processes besides this one (0: run everything here).
    warm_up : callable, optional
        Run once in each worker when it starts (imports, caches); a worker takes
        tasks after its warm-up, and not at all if the warm-up fails.
    spawn_env : dict, optional
        Environment of loky's workers where forking is not available; None: no
        spawned workers.
    """

    def __init__(self, n: int, *, warm_up=None, spawn_env: dict | None = None) -> None:
        self.executor = fork_executor(n) if n >= 1 else None
        self.forked = self.executor is not None
        if n >= 1 and not self.forked and spawn_env is not None:
            from joblib.externals.loky import get_reusable_executor

            self.executor = get_reusable_executor(max_workers=n, timeout=300, env=spawn_env)
        self.ready: list = []
        if self.executor is not None:
            self.ready = [self.executor.submit(warm_up or os.getpid) for _ in range(n)]

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Stop forked workers (loky's reusable ones stay for the next pool)."""
        if self.forked and self.executor is not None:
            self.executor.shutdown(wait=True, cancel_futures=True)
        self.executor = None
        self.ready = []

    def submit(self, func, *args):
        """Start ``func(*args)`` in a worker; a handle for :meth:`result` (None: not started)."""
        if self.executor is None:
            return None
        from concurrent.futures.process import BrokenProcessPool

        try:
            return self.executor.submit(func, *args)
        except (BrokenProcessPool, RuntimeError):
            return None

    @staticmethod
    def result(handle, func, *args):
        """The result of a :meth:`submit`: computed here if not started yet, or lost."""
        if handle is None or handle.cancel():
            return func(*args)
        from concurrent.futures.process import BrokenProcessPool

        try:
            return handle.result()
        except BrokenProcessPool:        # the worker died (e.g. out of memory): redo it here
            return func(*args)

    def map(self, func, items, *, cost=None, bar=None, first=None) -> list:
        """``[func(i) for i in items]``, shared with the workers.

        Parameters
        ----------
        func : callable
            A module-level function (it is pickled by reference) of one item.
        items : iterable
        cost : callable, optional
            ``cost(item)``: a task's relative cost; the costliest are started first.
        bar : tqdm, optional
            Advanced by one per finished task.
        first : callable, optional
            Run here once before this process takes a task, while the workers start on
            the queue (e.g. the imports of the next stage, which these tasks do not
            need). Run whatever the number of workers.
        """
        import threading
        from collections import deque

        items = list(items)
        out: list = [None] * len(items)
        lock = threading.Lock()

        def finished(i: int, value) -> None:
            out[i] = value
            if bar is not None:
                with lock:
                    bar.update(1)

        # one task goes to a worker only while this process runs ``first``
        if self.executor is None or (len(items) <= 1 and first is None) or not items:
            if first is not None:
                first()
            for i, item in enumerate(items):
                finished(i, func(item))
            return out
        order = sorted(range(len(items)), key=lambda i: -cost(items[i])) \
            if cost is not None else list(range(len(items)))
        queue = deque(order)
        lost: list[int] = []
        errors: list[BaseException] = []

        def take():
            with lock:
                return queue.popleft() if queue else None

        def remote(ready) -> None:
            import concurrent.futures
            from concurrent.futures.process import BrokenProcessPool

            while not ready.done():       # a worker still starting takes nothing
                if not queue:
                    return
                concurrent.futures.wait([ready], timeout=0.02)
            if ready.exception() is not None:
                return
            while (i := take()) is not None:
                handle = self.submit(func, items[i])
                try:
                    if handle is None:           # the pool is gone
                        raise BrokenProcessPool
                    value = handle.result()
                except BrokenProcessPool:        # lost with its worker: redo it here
                    with lock:
                        lost.append(i)
                    return
                except BaseException as exc:  # noqa: BLE001 - raised again in the caller
                    errors.append(exc)
                    return
                finished(i, value)

        threads = [threading.Thread(target=remote, args=(r,), daemon=True) for r in self.ready]
        for t in threads:
            t.start()
        try:
            if first is not None:
                first()
            while (i := take()) is not None:
                finished(i, func(items[i]))
        finally:
            with lock:
                queue.clear()
            for t in threads:
                t.join()
        if errors:
            raise errors[0]
        for i in lost:
            finished(i, func(items[i]))
        return out
