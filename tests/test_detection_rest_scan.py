"""The batched resting-load search finds what the one-by-one search finds."""

import numpy as np
import pytest

import vidiscover.analysis.impacts as impacts
from vidiscover import Effects, SensorConfig, preset, record, simulate
from vidiscover.analysis import PulseModel, detect_impacts


def _one_by_one(fit, y, base, bad, load_ratio, sigma, h, items):
    return [None if p_hi <= p_lo else
            impacts._rest_step(fit, y, base, bad, load_ratio, sigma, h, i, lift, p_lo, p_hi,
                               None)
            for i, lift, p_lo, p_hi in items]


@pytest.mark.parametrize("b, found", [(0.006, 3), (0.0075, 1)])
def test_batched_rest_search_equals_one_by_one(b, found, monkeypatch):
    """Paper's Table-2 walls: chatter runs, some ending at rest on a wall."""
    res = simulate(preset("paper", b=b), Effects.parse(["asymmetric_restitution=0.88,0.20"]),
                   settle=10.0, duration=5.12)
    rec = record(res, SensorConfig(), seed=1)[0]
    scan = impacts._rest_scan
    seen = []

    def both(*args):
        batched, single = scan(*args), _one_by_one(*args)
        seen.append((batched, single))
        return batched

    monkeypatch.setattr(impacts, "_rest_scan", both)
    detect_impacts(rec, pulse=PulseModel())
    pairs = [p for batched, single in seen for p in zip(batched, single)]
    assert len(pairs) >= 30                  # 41 searches at either clearance
    assert sum(b is not None for b, _ in pairs) == found
    for got, want in pairs:
        assert (got is None) == (want is None)
        if got is None:
            continue
        (k0, vals), entry, coef = got
        (k0_w, vals_w), entry_w, coef_w = want
        assert k0 == k0_w and entry == pytest.approx(entry_w, abs=1e-12)
        np.testing.assert_allclose(vals, vals_w, rtol=1e-12, atol=0)
        assert coef == pytest.approx(coef_w, rel=1e-9)
