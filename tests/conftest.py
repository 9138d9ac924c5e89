"""Shared fixtures: the realism corpus's development split."""

import pytest

from vidiscover.corpus import N_SUITE, realism_corpus


@pytest.fixture(scope="session")
def realism_dev():
    """The development cases of the realism corpus (never the held-back 'test' split)."""
    return realism_corpus("dev", N_SUITE)
