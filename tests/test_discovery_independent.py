"""Discovery on recordings of an independent simulator (``tests/data/independent``).

Compliant walls, smooth friction and causal analog anti-alias filters that neither
our engine nor our sensor model made (see ``tests/independent.py``). The checks of
issue 10: the pooled P04-P06 flight law within mu 0.03 and theta 0.3 deg; P01's and
P08's walls constant; and nowhere a negative mu or a |theta| > 10 deg reported as a
result.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from independent import CASES, load, true_impacts

from vidiscover.analysis import analyze
from vidiscover.discovery import discover, discover_flight_law

POOL = ("P04_pool_b5", "P05_pool_b8", "P06_pool_b11")


@functools.cache
def _analysis(name: str):
    return analyze(load(name)[0], n_boot=0)


def _true_r(name: str, side: str) -> float:
    imp = true_impacts(load(name)[1])
    return float(np.sqrt(np.mean(imp["r"][imp["side"] == (1 if side == "right" else -1)] ** 2)))


@pytest.mark.slow
def test_pooled_p04_p06_flight_law_within_tolerance():
    """The weak form's misfit is judged against the precision of the jumps measured in
    these recordings (~1-3 % behind causal filters and compliant walls), not a fixed
    1 %: measured mu 0.121, theta 0.786 deg against 0.1 and 0.8 (leave-one-recording-out
    spread 0.0066 / 0.085 deg; an earlier version read 0.1008 / 0.714). The flights
    determine mu here, so the LO's friction (0.102 +/- 0.004) is reported beside the law,
    not used in it."""
    key = load(POOL[0])[1]["setup"]
    res = discover_flight_law([_analysis(n) for n in POOL], n_boot=50)
    assert res.identified, res.reason
    assert abs(res.mu - key["mu"]) <= 0.03 and abs(res.theta_deg - key["theta_deg"]) <= 0.3
    assert res.lo_friction.identified and abs(res.lo_friction.mu - key["mu"]) < 0.01
    doc = res.to_dict()
    assert doc["lo_friction"]["identified"] is True and doc["lo_friction_used"] is False


@pytest.mark.slow
def test_no_inadmissible_flight_law_is_reported_anywhere():
    """Every case alone and the pool: identified laws are admissible; the others
    carry a reason and no numbers."""
    for names in [(n,) for n in CASES] + [POOL]:
        res = discover_flight_law([_analysis(n) for n in names], n_boot=0)
        doc = res.to_dict()
        if res.identified:
            assert res.mu >= 0 and abs(res.theta_deg) <= 10, (names, res.equation)
        else:
            assert res.reason and doc["mu"] is None and doc["theta_deg"] is None, names


@pytest.mark.parametrize("name", ["P01_b8_chatter", "P08_gap_none"])
def test_constant_walls_are_reported_constant(name):
    res = discover([_analysis(name)], n_boot=0, flight=False)
    for side in ("right", "left"):
        law = res.impact_laws[side]
        assert law.kind == "constant" and law.n >= 30, f"{name} {side}: {law.formula}"


def test_p02_single_speed_says_speed_dependence_is_not_identifiable():
    """P02's Hunt-Crossley walls are hit at one speed only (0.6423 m/s in the truth, a
    period-1 orbit): no method can see a speed dependence there. The law says so
    (constant with a warning) and its r is the truth's at that speed."""
    res = discover([_analysis("P02_b11_huntcrossley")], n_boot=0, flight=False)
    for side in ("right", "left"):
        law = res.impact_laws[side]
        assert law.kind == "constant" and "not identifiable" in law.warning
        assert abs(law.coefficients["1"] - _true_r("P02_b11_huntcrossley", side)) < 0.03
