"""Gap verdicts on the independent simulator's recordings (``gap_truth.json``).

Compliant walls, causal anti-alias filters and noise on every channel, made by code
that shares nothing with vidiscover. Achieved (and tested here): P08 (no effect) ->
``none``, P09 (2.5 deg tilt) -> ``inclination``, P10 (walls 0.9 / 0.5) ->
``asymmetric_restitution``, P03 (friction 0.12) -> ``coulomb_friction`` (found since
the LO's force during the flights is a statistic: measured mu 0.106, interval
[0.049, 0.162]). Not achieved: P02 (Hunt-Crossley walls): once ``none`` (gap 2.9, within
the model-form spread), then (2026-11-26) ``clearance_error`` (gap 10.6, of which the
sensors' and flights' components 5.2 and 4.0; db = 0.2 mm leaves 3.9), then (2026-11-27,
after the LO statistics' sharper floors, a08a9ce / 5e50433) ``unexplained`` (gap 10.6,
no candidate kept), and at 1b24cf2 (2026-11-28, measured) ``none`` again (gap 1.1, of which
the sensors 0.9; the readings next to a saturated accelerometer and the learned pulse
changed since): no catalogue effect is blamed, which the last test guards, while the law
candidate fits no slope at its one impact speed per wall (13.5). A wider slope search
would not change that: both walls are hit at 0.644 m/s (std 1e-4) in a symmetric
orbit, where a law gives the orbit of a constant r; the true law (r0 = 1, slope 0.289,
the searched grid's steepest point) leaves 15.6 on the validation draw, steeper local
slopes (power laws 1 - a v^p, p 1.5-3, r(0) = 1) 13.7-16.6, constant walls 10.2: the
gap lies in the flights and sensors (the walls' compliance), not in a speed dependence
these statistics can see.
P09 is won narrowly: the tilt leaves a gap of 1.1, a 0.18 mm clearance error 1.4
(one parameter each).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from independent import GAP_TRUTH, load

from vidiscover.gap import diagnose

ACHIEVED = ("P08_gap_none", "P09_gap_tilt", "P10_gap_asym", "P03_b13_friction")


@functools.cache
def report(name: str):
    rec, key = load(name)
    return diagnose(rec, n_jobs=1), key


@pytest.mark.slow
@pytest.mark.parametrize("name", ACHIEVED)
def test_gap_verdict_matches_the_truth(name):
    rep, key = report(name)
    assert rep.verdict == (GAP_TRUTH[name] or "none")
    if GAP_TRUTH[name] is None:
        assert not rep.significant and rep.gap_before < 3.0          # measured 1.1
        return
    assert rep.unexplained < 0.1                                     # measured 0.00
    att = rep.attributed()[0]
    if name == "P09_gap_tilt":
        # fitted 2.04 deg, interval [1.0, 3.1]; the truth is 2.5 deg
        lo, hi = att["ci"]["theta"]
        assert lo <= key["setup"]["theta_deg"] <= hi
        assert att["params"]["theta"] == pytest.approx(2.5, abs=0.6)
    if name == "P03_b13_friction":
        # fitted 0.106, interval [0.049, 0.162]; the truth is 0.12
        lo, hi = att["ci"]["mu"]
        assert lo <= key["setup"]["mu"] <= hi
        assert att["params"]["mu"] == pytest.approx(0.12, abs=0.03)
    if name == "P10_gap_asym":
        # the truth: the measured r of the contacts (0.902 right, 0.549 left)
        for side in ("right", "left"):
            r = np.mean([i["r"] for i in key["impacts"] if i["side"] == side])
            assert att["params"][f"r_{side}"] == pytest.approx(r, abs=0.01)



@pytest.mark.slow
def test_p02_is_not_blamed_on_a_wrong_effect():
    """P02's truth is a speed law its one impact speed per wall cannot show (module
    docstring): the honest verdicts are the law or no significant gap; a clearance error,
    a tilt, a friction or a sensor resonance would be a false attribution (it was a
    clearance error once). Measured: ``none``, gap 1.1."""
    rep, _ = report("P02_b11_huntcrossley")
    assert rep.verdict in ("none", GAP_TRUTH["P02_b11_huntcrossley"])
    if rep.verdict == "none":
        assert not rep.significant and rep.gap_before < 3.0          # measured 1.1
