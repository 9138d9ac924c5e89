"""parallel_map: order, determinism and backends (serial, joblib, Dask on loopback)."""

import math
import sys

import numpy as np
import pandas as pd
import pytest

from vidiscover import scale
from vidiscover.errors import InputError
from vidiscover.scale import parallel_map

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def cluster():
    """A one-worker Dask cluster on loopback (worker in its own process)."""
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as lc:
        yield lc


@pytest.fixture(scope="module")
def client(cluster):
    with distributed.Client(cluster) as c:
        yield c


def _items(n=300, seed=0):
    # uneven work (factorials of very different sizes) in shuffled order
    return [int(v) for v in np.random.default_rng(seed).integers(0, 3000, n)]


def test_serial_is_a_plain_loop_in_input_order():
    items = _items()
    assert parallel_map(math.factorial, items, n_jobs=1, progress=False) == \
        [math.factorial(i) for i in items]


def test_serial_accepts_closures_because_nothing_is_pickled():
    offset = 3
    assert parallel_map(lambda v: v + offset, range(5), n_jobs=1, progress=False) == \
        [3, 4, 5, 6, 7]


def test_joblib_processes_keep_input_order():
    items = _items()
    assert parallel_map(math.factorial, items, n_jobs=2, progress=False) == \
        [math.factorial(i) for i in items]


@pytest.mark.parametrize("n, workers", [(1, 2), (5, 2), (1000, 2), (1000, 1), (7, 16)])
def test_chunks_cover_the_items_in_order_and_batch_cheap_items(n, workers):
    chunks = scale._chunks(list(range(n)), workers)
    assert [i for c in chunks for i in c] == list(range(n))
    assert len(chunks) <= workers * scale._CHUNKS_PER_WORKER
    if n >= workers * scale._CHUNKS_PER_WORKER:
        assert len(chunks) >= workers  # every worker gets work


def test_empty_input_gives_empty_output(client):
    assert parallel_map(math.sqrt, [], progress=False) == []
    assert parallel_map(math.sqrt, [], scheduler=client, progress=False) == []


def test_exceptions_of_func_propagate():
    with pytest.raises(ValueError, match="math domain error"):
        parallel_map(math.sqrt, [4.0, -1.0], n_jobs=1, progress=False)
    with pytest.raises(ValueError, match="math domain error"):
        parallel_map(math.sqrt, [4.0, -1.0, 9.0], n_jobs=2, progress=False)


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_bad_n_jobs_is_an_input_error(bad):
    with pytest.raises(InputError, match=r"n_jobs must be a positive integer or None.*was"):
        parallel_map(math.sqrt, [1.0, 4.0], n_jobs=bad, progress=False)


def test_progress_bar_shows_the_description(capsys):
    parallel_map(math.sqrt, range(4), n_jobs=1, progress=True, desc="roots")
    err = capsys.readouterr().err
    assert "roots" in err and "4/4" in err


def test_dask_client_and_address_give_the_serial_results(cluster, client):
    items = _items(200, seed=1)
    serial = [math.factorial(i) for i in items]
    assert parallel_map(math.factorial, items, scheduler=client, progress=False) == serial
    assert parallel_map(math.factorial, items, scheduler=cluster.scheduler_address,
                        progress=False) == serial
    assert client.status == "running"  # a client passed in is left open


def test_unreachable_scheduler_is_a_one_line_input_error(monkeypatch):
    monkeypatch.setattr(scale, "CONNECT_TIMEOUT", "1s")
    with pytest.raises(InputError, match=r"cannot connect to the Dask scheduler at "
                                         r"'tcp://127.0.0.1:9'.*dask scheduler"):
        parallel_map(math.sqrt, [1.0], scheduler="tcp://127.0.0.1:9", progress=False)


@pytest.mark.parametrize("bad", [42, "  "])
def test_bad_scheduler_is_an_input_error(bad):
    with pytest.raises(InputError, match="scheduler must be a Dask scheduler address"):
        parallel_map(math.sqrt, [1.0], scheduler=bad, progress=False)


def test_missing_dask_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import now fails
    with pytest.raises(InputError, match=r"pip install 'vidiscover\[dask\]'"):
        parallel_map(math.sqrt, [1.0], scheduler="tcp://127.0.0.1:8786", progress=False)


def test_sweep_rows_identical_serial_joblib_and_local_cluster(client):
    from vidiscover.sweep import sweep

    kw = dict(settle=3.0, duration=1.5, seed=7, progress=False)
    values = [0.004, 0.009, 0.016]
    serial = sweep("b", values, n_jobs=1, **kw)
    on_dask = sweep("b", values, scheduler=client, **kw)
    on_joblib = sweep("b", values, n_jobs=2, **kw)
    pd.testing.assert_frame_equal(on_dask, serial, check_exact=True)
    pd.testing.assert_frame_equal(on_joblib, serial, check_exact=True)
    assert serial["n_impacts_true"].gt(0).all()  # rows that carry information


@pytest.fixture(scope="module")
def real_cluster(tmp_path_factory):
    """A ``dask scheduler`` and two ``dask worker`` processes on loopback, started as a
    user would start them (command line), stopped afterwards."""
    from dask_cluster import command_line_cluster, dask_command

    if dask_command() is None:
        pytest.skip("the dask command line is not installed")
    with command_line_cluster(2, log_dir=str(tmp_path_factory.mktemp("dask"))) as address:
        yield address


@pytest.mark.slow
def test_sweep_on_a_real_scheduler_and_two_worker_processes(real_cluster):
    """The command-line scheduler and workers give the serial rows exactly."""
    from vidiscover.sweep import sweep

    kw = dict(settle=3.0, duration=1.5, seed=11, progress=False)
    values = [0.005, 0.008, 0.011, 0.014]
    serial = sweep("b", values, n_jobs=1, **kw)
    on_dask = sweep("b", values, scheduler=real_cluster, **kw)
    pd.testing.assert_frame_equal(on_dask, serial, check_exact=True)
    with distributed.Client(real_cluster) as c:
        assert len(c.nthreads()) == 2
