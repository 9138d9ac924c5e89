"""Run one function over many items: in-process, on joblib processes or on Dask.

:func:`parallel_map` is the single entry point used by sweeps and by training-set
generation. Items are grouped into chunks so that the per-item overhead of
process/cluster dispatch stays small when there are many cheap items (a 1000-point
sweep is ~16 tasks on 2 workers, not 1000), and results always come back in input
order, whichever backend ran them. The backend never changes the results: ``func``
receives exactly the same item whichever way it is run, so a function that derives
its randomness from the item (not from global state) gives identical outputs
serially, on joblib and on a Dask cluster.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from vidiscover._workers import n_workers as _n_workers
from vidiscover.errors import InputError

__all__ = ["parallel_map"]

#: Chunks per worker: enough for a live progress bar and load balancing, few enough
#: that dispatch overhead (pickling ``func``, one round trip per chunk) is negligible.
_CHUNKS_PER_WORKER = 8

#: How long to wait for a Dask scheduler given by address.
CONNECT_TIMEOUT = "10s"

_DASK_HINT = "install the dask extra: pip install 'vidiscover[dask]'"


#: glibc's ``mallopt`` parameters and the values restored where a tiny trim threshold
#: was set (glibc's own dynamic thresholds grow to these).
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_TRIM_BYTES, _MMAP_BYTES = 64 << 20, 32 << 20
_malloc_relaxed = [False]


def _relax_malloc_trim() -> None:
    """Undo a small ``MALLOC_TRIM_THRESHOLD_`` in this worker process (glibc only).

    Dask's nanny sets ``MALLOC_TRIM_THRESHOLD_=65536`` for its workers, and a
    ``LocalCluster`` leaks it into its own process, so that joblib workers started
    later inherit it. glibc then also stops growing its mmap threshold: every array
    above 128 kB is mapped and unmapped afresh, and a sweep point costs twice as much
    (measured: a 1000-point sweep on 2 workers 36 s instead of 16-18 s). The worker
    gets glibc's usual large thresholds back; its memory is still returned to the
    system above 64 MB of free heap.
    """
    if _malloc_relaxed[0] or not os.environ.get("MALLOC_TRIM_THRESHOLD_"):
        return
    _malloc_relaxed[0] = True
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(_M_MMAP_THRESHOLD, _MMAP_BYTES)
        libc.mallopt(_M_TRIM_THRESHOLD, _TRIM_BYTES)
    except (OSError, AttributeError):        # not glibc: nothing to undo
        pass


def _apply_chunk(func: Callable[[Any], Any], chunk: Sequence[Any]) -> list[Any]:
    """Apply ``func`` to every item of one chunk (runs on the worker)."""
    _relax_malloc_trim()
    return [func(item) for item in chunk]


def _apply_chunk_one_thread(func: Callable[[Any], Any], chunk: Sequence[Any]) -> list[Any]:
    """:func:`_apply_chunk` with the BLAS/OpenMP pools of the worker held to one thread.

    Each Dask worker thread is one unit of parallelism (as each loky process is, where
    joblib limits the pools itself); native pools of the machine's width in every
    worker would oversubscribe the cores.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return _apply_chunk(func, chunk)


def _chunks(items: Sequence[Any], n_workers: int) -> list[list[Any]]:
    """Split ``items`` into contiguous chunks, about ``_CHUNKS_PER_WORKER`` per worker."""
    size = max(1, math.ceil(len(items) / (n_workers * _CHUNKS_PER_WORKER)))
    return [list(items[i : i + size]) for i in range(0, len(items), size)]


def _progress(total: int, progress: bool, desc: str):
    from tqdm.auto import tqdm

    return tqdm(total=total, disable=not progress, desc=desc or None, unit="item")


def _run_serial(func, items, bar) -> list[Any]:
    out = []
    for item in items:
        out.append(func(item))
        bar.update(1)
    return out


def _run_joblib(func, items, n_workers: int, bar) -> list[Any]:
    from joblib import Parallel, delayed

    chunks = _chunks(items, n_workers)
    parallel = Parallel(
        n_jobs=min(n_workers, len(chunks)),
        backend="loky",
        batch_size=1,
        return_as="generator",
    )
    out: list[Any] = []
    for chunk_result in parallel(delayed(_apply_chunk)(func, c) for c in chunks):
        out.extend(chunk_result)
        bar.update(len(chunk_result))
    return out


def _dask_client(scheduler):
    """Return ``(client, owned)`` for an address string or an existing Client."""
    try:
        import distributed
    except ImportError as exc:
        raise InputError(
            f"a Dask scheduler was given but Dask distributed is missing; {_DASK_HINT}"
        ) from exc
    if isinstance(scheduler, distributed.Client):
        return scheduler, False
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise InputError(
            "scheduler must be a Dask scheduler address such as 'tcp://127.0.0.1:8786' "
            f"or a distributed.Client, was {scheduler!r}"
        )
    try:
        client = distributed.Client(scheduler.strip(), timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(
            f"cannot connect to the Dask scheduler at {scheduler!r} ({exc}); "
            "check the address or start one with `dask scheduler`"
        ) from exc
    return client, True


def _run_dask(func, items, scheduler, bar) -> list[Any]:
    client, owned = _dask_client(scheduler)
    try:
        from distributed import as_completed

        n_workers = max(1, sum(client.nthreads().values()))
        chunks = _chunks(items, n_workers)
        # ``func`` (often a partial holding a regime model) travels to every worker
        # once, not once per chunk
        shared = client.scatter(func, broadcast=True, hash=False)
        # ``pure=False``: identical chunks must still run (and count) separately.
        futures = client.map(_apply_chunk_one_thread, [shared] * len(chunks), chunks,
                             pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        results: list[list[Any] | None] = [None] * len(chunks)
        for future in as_completed(futures):
            chunk_result = future.result()
            results[index[future.key]] = chunk_result
            bar.update(len(chunk_result))
        return [r for chunk_result in results for r in chunk_result]
    finally:
        if owned:
            client.close()


def parallel_map(
    func: Callable[[Any], Any],
    items: Iterable[Any],
    *,
    scheduler: Any = None,
    n_jobs: int | None = None,
    progress: bool = True,
    desc: str = "",
) -> list[Any]:
    """Apply ``func`` to every item, in parallel, and return results in input order.

    Parameters
    ----------
    func : callable
        ``func(item) -> result``. Must be a picklable top-level function (not a
        lambda or closure) unless ``n_jobs=1``; it should derive any randomness from
        ``item`` so that every backend gives the same results.
    items : iterable
        Inputs; consumed into a list first.
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (``"tcp://host:8786"``) or a connected
        ``distributed.Client``. When given, the work runs on that cluster and
        ``n_jobs`` is ignored. A client passed in is left open; one created from an
        address is closed on return.
    n_jobs : int, optional
        Number of joblib (loky) worker processes when no scheduler is given.
        ``None`` uses all cores; ``1`` runs a plain loop in this process (no pool).
    progress : bool, default True
        Show a tqdm progress bar (on stderr).
    desc : str, default ""
        Label of the progress bar.

    Returns
    -------
    list
        ``[func(item) for item in items]``, in the order of ``items``.

    Raises
    ------
    InputError
        If ``n_jobs`` is not a positive integer, the scheduler cannot be reached, or
        Dask is needed but not installed. Exceptions raised by ``func`` propagate.

    Examples
    --------
    >>> from math import sqrt
    >>> parallel_map(sqrt, [1, 4, 9], n_jobs=1, progress=False)
    [1.0, 2.0, 3.0]
    """
    items = list(items)
    n_workers = _n_workers(n_jobs) if scheduler is None else 1
    with _progress(len(items), progress, desc) as bar:
        if scheduler is not None:
            return _run_dask(func, items, scheduler, bar) if items else []
        if n_workers == 1 or len(items) <= 1:
            return _run_serial(func, items, bar)
        return _run_joblib(func, items, n_workers, bar)
