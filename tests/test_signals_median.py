"""The selection median of :func:`vidiscover.analysis.signals._median` and robust_std.

Above ``_SELECT_MIN`` samples the median is selected among the samples between two
order statistics of a strided sample; it must be the very value of ``np.median`` (and
robust_std the MAD of its definition), with and without the whole-array fallback.
"""

from __future__ import annotations

import numpy as np
import pytest

from vidiscover.analysis.signals import _median, robust_std


def _arrays(rng, n):
    yield rng.normal(size=n)
    yield np.abs(rng.normal(size=n))
    yield np.round(rng.normal(size=n) * 3) / 3            # many ties
    yield np.sort(rng.normal(size=n))                     # strided sample = quantiles
    yield np.sort(rng.normal(size=n))[::-1].copy()
    yield np.cumsum(rng.normal(size=n))                   # random walk
    yield rng.standard_cauchy(size=n)
    yield np.r_[np.zeros(n // 2 + 1), rng.normal(size=n - n // 2 - 1)]   # zero median
    yield np.where(rng.random(n) < 0.01, 1e6, rng.normal(size=n))       # outliers
    yield np.full(n, 2.5)


@pytest.mark.parametrize("n", [4095, 4096, 4097, 8192, 8193, 10922, 32768])
def test_selection_median_is_numpys_median(n):
    rng = np.random.default_rng(34011 + n)
    for x in _arrays(rng, n):
        keep = x.copy()
        assert _median(x) == np.median(x)
        assert np.array_equal(x, keep)                    # not reordered
        dev = np.abs(x - _median(x))
        assert robust_std(x) == 1.4826 * np.median(dev)


def test_fallback_when_the_sample_misses_the_middle(monkeypatch):
    # a strided sample blind to the middle: every 16th sample large, the rest small
    n = 8192
    x = np.linspace(-1.0, 1.0, n)
    x[::16] = 1e3 + np.arange(n // 16)
    sizes = []
    partition = np.partition

    def counted(a, kth, *args, **kw):
        sizes.append(np.asarray(a).size)
        return partition(a, kth, *args, **kw)

    monkeypatch.setattr(np, "partition", counted)
    assert _median(x) == np.median(x)
    assert sizes == [n // 16, n]                      # the sample, then the whole array
    sizes.clear()
    y = np.random.default_rng(34012).normal(size=n)
    assert _median(y) == np.median(y)
    assert sizes == [n // 16]                         # the sample only
