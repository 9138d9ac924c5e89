"""``DiscoveryResult.equations``: the text lines say where a law stops holding."""

from __future__ import annotations

import numpy as np

from vidiscover.discovery.impact_law import discover_impact_law
from vidiscover.discovery.pipeline import DiscoveryResult


def _result(right, left) -> DiscoveryResult:
    return DiscoveryResult(recordings=("a",), analyses=(), impact_data={},
                           impact_laws={"right": right, "left": left}, flight=None, mu=0.0,
                           mu_impacts=0.0, theta_impacts=0.0, warnings=())


def test_a_law_reaching_r_zero_within_its_band_says_up_to_where_it_holds():
    rng = np.random.default_rng(0)
    v = rng.uniform(0.3, 1.0, 200)
    sigma = np.full(v.size, 0.003)
    falling = discover_impact_law(v, 0.7 - 0.6 * v + rng.normal(0, 0.003, v.size),
                                  sigma=sigma, n_boot=0)
    const = discover_impact_law(v, 0.8 + rng.normal(0, 0.003, v.size), sigma=sigma, n_boot=0)
    top = falling.valid_range[1]
    assert 1.1 < top < 1.2                      # 0.7 / 0.6 = 1.17 m/s, below 1.4 x 0.998
    right, left = _result(falling, const).equations()[1:]
    assert right.endswith(f"holds up to {top:.3g} m/s (r reaches 0 there))")
    assert "holds up to" not in left and "inconsistent" not in left
