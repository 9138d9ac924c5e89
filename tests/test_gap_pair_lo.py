"""Pairs are ranked with the LO response statistics on their floors (``PAIR_SHARP_LO``).

A second effect that shows mostly in the LO's response at f (spent draw 25103 #23,
compliant unequal walls and a 2.8 deg tilt at 7.6 mm in a multi_ipc orbit) scored
behind a clearance error on the model's blunt LO scales (walls + clearance 6.97,
walls + tilt 7.18) and ahead of it on the sharp ones (7.37 and 7.23); the fits keep
the model's scales, only the choice among the fitted pairs reads the sharp ones.
"""

from __future__ import annotations

import importlib
import types

import pytest

from vidiscover.effects import Effects
from vidiscover.gap.components import LO_FORM, LO_STATS, GapComponents, blunt_lo, sharpen_lo
from vidiscover.gap.fit import CandidateFit

#: the module (``vidiscover.gap.diagnose`` is also the function's name in the package)
D = importlib.import_module("vidiscover.gap.diagnose")


def _pair(name, blunt, sig):
    return CandidateFit(name=name, params={}, n_params=2, r=0.7, effects=Effects(),
                        gap=GapComponents({"s": float(blunt)}, {}), signature=sig)


def test_sharpen_lo_undoes_blunt_lo_and_leaves_the_other_statistics():
    rv = {"lo.amplitude": 1e-8, "lo.phase": 0.0, "flights.drag": 2e-4}
    back = sharpen_lo(blunt_lo(rv))
    for k in rv:
        assert back[k] == pytest.approx(rv[k], abs=1e-15)
    assert all(blunt_lo(rv)[k] - rv[k] == pytest.approx(LO_FORM ** 2) for k in LO_STATS)


def test_pairs_are_chosen_on_sharp_lo_scales_and_keep_their_own_gap(monkeypatch):
    sharp = {"clear": 7.37, "tilt": 7.23}
    seen = []

    def fake_compare(real, sig, rep_var, allow_mirror=False):
        seen.append(rep_var)
        return GapComponents({"s": sharp[sig]}, {})

    monkeypatch.setattr(D, "compare", fake_compare)
    clear = _pair("asymmetric_restitution+clearance_error", 6.97, "clear")
    tilt = _pair("asymmetric_restitution+inclination", 7.18, "tilt")
    model = types.SimpleNamespace(real=None, rep_var=blunt_lo({}), sharp_lo=False)
    pick = D._choose_pair(model, [clear, tilt])
    assert pick is tilt and pick.gap.total == 7.18
    assert all(v["lo.amplitude"] == pytest.approx(0.0) for v in seen)
    # off, or a model whose scales are sharp already: the pairs' own gaps decide
    monkeypatch.setattr(D, "PAIR_SHARP_LO", False)
    assert D._choose_pair(model, [clear, tilt]) is clear
    monkeypatch.setattr(D, "PAIR_SHARP_LO", True)
    sharp_model = types.SimpleNamespace(real=None, rep_var={}, sharp_lo=True)
    assert D._choose_pair(sharp_model, [clear, tilt]) is clear
