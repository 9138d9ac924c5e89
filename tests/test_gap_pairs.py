"""Two effects at once: shares of a jointly fitted pair (fast, no simulation)."""

from __future__ import annotations

import pytest

from vidiscover.effects import Effects
from vidiscover.gap.components import GapComponents
from vidiscover.gap.diagnose import GapReport, _split_pair
from vidiscover.gap.fit import CandidateFit


def _fit(name, gap, params=None, n_params=1):
    return CandidateFit(name=name, params=params or {}, n_params=n_params, r=0.7,
                        effects=Effects(), gap=GapComponents({"s": float(gap)}, {}),
                        signature=None)


def test_pair_shares_are_shapley_and_add_up_to_what_the_pair_removed():
    nominal = _fit("nominal", 100.0, n_params=0)
    fa, fb = _fit("inclination", 40.0), _fit("coulomb_friction", 70.0)
    pair = _fit("inclination+coulomb_friction", 2.0,
                {"inclination": {"theta": 3.0}, "coulomb_friction": {"mu": 0.15}}, 2)
    selected = _split_pair(pair, [fa, fb])
    assert [c.name for c in selected] == ["inclination", "coulomb_friction"]
    assert selected[0].params == {"theta": 3.0} and selected[1].params == {"mu": 0.15}
    rep = GapReport(name="x", model=None, nominal=nominal, candidates=[fa, fb],
                    selected=selected, significant=True)
    shares = {a["name"]: a["share"] for a in rep.attributed()}
    # inclination: (100 - 40 + 70 - 2) / 2 / 100; friction: (100 - 70 + 40 - 2) / 2 / 100
    assert shares["inclination"] == pytest.approx(0.64)
    assert shares["coulomb_friction"] == pytest.approx(0.34)
    assert sum(shares.values()) == pytest.approx((100 - 2) / 100)
    assert rep.gap_after == 2.0 and rep.verdict == "inclination"


def test_pair_order_follows_the_better_single_effect():
    fa, fb = _fit("inclination", 70.0), _fit("coulomb_friction", 40.0)
    pair = _fit("inclination+coulomb_friction", 2.0,
                {"inclination": {"theta": 3.0}, "coulomb_friction": {"mu": 0.15}}, 2)
    assert [c.name for c in _split_pair(pair, [fa, fb])] == ["coulomb_friction",
                                                             "inclination"]
