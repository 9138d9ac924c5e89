"""savgol_smooth from an earlier smoothing (``prev``): the values of a whole one."""

from __future__ import annotations

import numpy as np
import pytest

from vidiscover.analysis.signals import _savgol_parts, savgol_smooth


@pytest.mark.parametrize("win", [7, 41])
def test_changed_runs_give_the_whole_smoothing_bit_for_bit(win, monkeypatch):
    sizes = []
    correlate = np.correlate

    def counted(a, v, mode="valid"):
        sizes.append(a.size)
        return correlate(a, v, mode)

    monkeypatch.setattr(np, "correlate", counted)
    rng = np.random.default_rng(34021 + win)
    n = 20000
    y0 = np.cumsum(rng.normal(size=n))
    out0 = savgol_smooth(y0, win)
    for trial in range(12):
        y = y0.copy()
        # local changes (pulses), at the ends too, some closer than a window
        for c in rng.integers(0, n, size=rng.integers(1, 60) if trial else 0):
            w = rng.integers(1, 3 * win)
            y[c:c + w] += rng.normal(size=y[c:c + w].size)
        if trial == 1:
            y[:3] += 1.0
            y[-2:] -= 1.0
        whole = savgol_smooth(y, win)
        sizes.clear()
        again = savgol_smooth(y, win, prev=(y0, out0))
        assert np.array_equal(again, whole)
        assert trial == 0 or 0 < sizes[0] < n / 2         # only about the changes
        assert np.array_equal(y0, y0) and np.array_equal(out0, savgol_smooth(y0, win))
    # everything changed: computed whole
    y = y0 + 1.0
    sizes.clear()
    assert np.array_equal(savgol_smooth(y, win, prev=(y0, out0)), savgol_smooth(y, win))
    assert sizes == [n, n]


def test_dot_product_does_not_depend_on_alignment():
    # the reuse correlates gathered copies of the samples: each window's dot product
    # must not depend on the address of its first sample
    rng = np.random.default_rng(34022)
    taps = _savgol_parts(41)[0]
    for _ in range(10):
        y = rng.normal(size=3000) * 10.0 ** rng.uniform(-3, 3)
        full = np.correlate(y, taps, mode="valid")
        for off in range(1, 9):
            buf = np.empty(y.size + 16)
            z = buf[off:off + y.size]
            z[:] = y
            assert np.array_equal(np.correlate(z, taps, mode="valid"), full)
            seg = y[100 * off:100 * off + 500].copy()
            assert np.array_equal(np.correlate(seg, taps, mode="valid"),
                                  full[100 * off:100 * off + 460])
