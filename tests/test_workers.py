"""``vidiscover._workers.WorkerPool``: tasks shared with forked workers, as if run here."""

from __future__ import annotations

import math
import os
import time

import pytest

from vidiscover._workers import WorkerPool, can_fork, n_workers
from vidiscover.errors import InputError

forking = pytest.mark.skipif(not can_fork(), reason="workers are forked on Linux only")
PARENT = os.getpid()


def _where(x: float) -> tuple[float, bool]:
    time.sleep(0.01)                 # long enough for the workers to take their share
    return math.sqrt(x), os.getpid() == PARENT


def _dies_in_a_worker(x: float) -> float:
    if os.getpid() != PARENT:
        os._exit(3)                  # a worker killed in the middle of its task
    return 2.0 * x


class _Bar:
    def __init__(self) -> None:
        self.n = 0

    def update(self, k: int) -> None:
        self.n += k


@forking
def test_map_keeps_input_order_and_shares_the_tasks():
    items = [float(i) for i in range(40)]
    bar = _Bar()
    with WorkerPool(2) as pool:
        out = pool.map(_where, items, cost=lambda x: x, bar=bar)
    assert [v for v, _ in out] == [math.sqrt(x) for x in items]
    here = sum(h for _, h in out)
    assert 0 < here < len(items)          # this process and the workers both worked
    assert bar.n == len(items)


def _touch(path: str) -> bool:
    with open(path, "a"):
        pass
    return os.getpid() == PARENT


@forking
def test_first_runs_here_once_while_the_workers_take_the_tasks(tmp_path):
    """``first`` (e.g. the next stage's imports) runs here before this process takes a
    task, and the workers work meanwhile: a task's mark appears while it runs."""
    marks = [str(tmp_path / f"{i}") for i in range(4)]
    seen = []

    def first():
        deadline = time.monotonic() + 10.0
        while not os.path.exists(marks[0]) and time.monotonic() < deadline:
            time.sleep(0.005)
        seen.append(os.path.exists(marks[0]))

    with WorkerPool(1) as pool:
        here = pool.map(_touch, marks, first=first)
    assert seen == [True]                 # run once, and a worker did a task meanwhile
    assert here[0] is False               # the first task was the worker's
    assert all(os.path.exists(m) for m in marks)


@forking
def test_a_single_task_goes_to_a_worker_while_first_runs_here(tmp_path):
    """One task (discover on one recording) runs beside ``first`` (the fitting
    libraries' load), not after it in this process."""
    mark = str(tmp_path / "0")
    seen = []

    def first():
        deadline = time.monotonic() + 10.0
        while not os.path.exists(mark) and time.monotonic() < deadline:
            time.sleep(0.005)
        seen.append(os.path.exists(mark))

    with WorkerPool(1) as pool:
        here = pool.map(_touch, [mark], first=first)
    assert seen == [True]
    assert here == [False]


def test_first_runs_once_also_without_workers():
    calls = []
    with WorkerPool(0) as pool:
        assert pool.map(math.sqrt, [], first=lambda: calls.append(1)) == []
        assert pool.map(math.sqrt, [4.0], first=lambda: calls.append(2)) == [2.0]
    assert calls == [1, 2]


@forking
def test_map_raises_a_task_error_after_the_running_tasks():
    with WorkerPool(1) as pool:
        with pytest.raises(ValueError, match="math domain error"):
            pool.map(math.sqrt, [4.0, 9.0, -1.0, 16.0, 25.0])
        assert pool.map(math.sqrt, [4.0, 9.0]) == [2.0, 3.0]   # the pool still works


@forking
def test_a_task_lost_with_its_worker_is_run_here():
    with WorkerPool(1) as pool:
        out = pool.map(_dies_in_a_worker, [float(i) for i in range(6)])
        assert out == [2.0 * i for i in range(6)]
        # submit/result: a lost handle is computed here too
        handle = pool.submit(_dies_in_a_worker, 5.0)
        assert WorkerPool.result(handle, _dies_in_a_worker, 5.0) == 10.0


def test_without_workers_everything_runs_here():
    pool = WorkerPool(0)
    assert pool.executor is None
    assert pool.map(_where, [4.0, 9.0]) == [(2.0, True), (3.0, True)]
    assert pool.submit(math.sqrt, 4.0) is None
    assert WorkerPool.result(None, math.sqrt, 4.0) == 2.0
    pool.close()


@forking
def test_submit_and_result_give_the_task_value():
    with WorkerPool(1) as pool:
        handle = pool.submit(_where, 16.0)
        handle.result()                   # started: result() does not compute it again
        assert WorkerPool.result(handle, _where, 16.0) == (4.0, False)


@pytest.mark.parametrize("bad", [0, -2, 1.5, True, "2"])
def test_n_workers_refuses_what_is_not_a_count(bad):
    with pytest.raises(InputError, match="n_jobs must be a positive integer"):
        n_workers(bad)
    assert n_workers(None) >= 1 and n_workers(3) == 3


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting for its reaper counts as ended)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@forking
def test_a_worker_ends_with_its_parent_however_the_parent_ends(tmp_path):
    # a parent interrupted alone (kill -INT of its pid, not of the group) used to leave
    # its workers blocked forever; here the parent leaves without any cleanup at all
    import subprocess
    import sys

    code = ("import os, time\n"
            "from vidiscover._workers import WorkerPool\n"
            "pool = WorkerPool(1)\n"
            "h = pool.submit(os.getpid)\n"
            "print(h.result(), flush=True)\n"
            "pool.submit(time.sleep, 60)\n"
            "time.sleep(0.2)\n"
            "os._exit(0)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True)
    worker = int(out.stdout.split()[0])
    deadline = time.monotonic() + 5.0
    while _alive(worker) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(worker)
