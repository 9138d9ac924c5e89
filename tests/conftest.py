"""Shared fixtures (the realism corpus's development split) and test-run settings."""

import os

import pytest

from vidiscover.corpus import N_SUITE, realism_corpus


def pytest_configure(config):
    # Under pytest-xdist each worker process has a core: BLAS and OpenMP pools of their
    # own would oversubscribe the cores, and their spin-waits then cost far more than
    # they give on our small arrays (a 32k-sample dot product measured 12 ms instead of
    # 0.05 ms with the other core busy). One thread per worker, as joblib's loky does.
    if os.environ.get("PYTEST_XDIST_WORKER"):
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=1)


@pytest.fixture(scope="session")
def realism_dev():
    """The development cases of the realism corpus (never the held-back 'test' split)."""
    return realism_corpus("dev", N_SUITE)
