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


def _search_arrays(rng, n=3, g=5, k=40):
    """Random (P, Tw, Q, Qt, y0) shaped as one chunk of the resting-load search."""
    V = rng.normal(size=(n, k, 6))
    Q = np.linalg.qr(V)[0]
    Qt = Q.transpose(0, 2, 1)
    y = rng.normal(size=(n, k))
    y0 = y - (Q @ (Qt @ y[:, :, None]))[:, :, 0]
    P = rng.normal(size=(n, g, k))
    Tw = np.cumsum(rng.normal(size=(n, g, k)), axis=2) / k
    return P, Tw, Q, Qt, y0


def test_inner_products_equal_projections_where_well_posed():
    P, Tw, Q, Qt, y0 = _search_arrays(np.random.default_rng(5))
    gains, step2, rss, ill = impacts._rest_inner(P, Tw, Q, y0)
    want = impacts._rest_projected(P, Tw, Q, Qt, y0)
    assert not ill.any()
    for got, ref in zip((gains, step2, rss), want):
        np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-10)


def test_inner_products_flag_a_pulse_inside_the_basis():
    """A pulse column (nearly) in the window's basis keeps no digit of its remainder in
    the inner products: that search is flagged for the projections (the overflow of
    b66c85a on three classifier training draws), and only that one."""
    P, Tw, Q, Qt, y0 = _search_arrays(np.random.default_rng(6))
    P[1, 2] = Q[1] @ np.arange(1.0, 7.0) * 1e3 + 1e-12      # all but rounding in the basis
    Tw[2, 0] = np.inf                                         # not finite
    with np.errstate(all="ignore"):
        ill = impacts._rest_inner(P, Tw, Q, y0)[3]
    assert ill.tolist() == [False, True, True]
