"""SimulationResult.evaluate: the per-segment path of sorted grids equals the general one.

A sorted grid of at least ``_MIN_RUNS`` instants is evaluated segment by segment
(``_segment_runs``, ``_flow_runs``); any other grid by the general path (one search
and one gather per instant, ``Oscillator.state_array``). Both must give the same
states to the bit: the sensor model, the labeller and the shipped regime model's
training recordings read them.
"""

from __future__ import annotations

import numpy as np
import pytest

from vidiscover import preset
from vidiscover.effects import Effects
from vidiscover.simulation import simulate
from vidiscover.simulation.result import _MIN_RUNS, _segment_runs

CASES = {
    "nominal": ([], 0.009),
    "chatter": ([], 0.004),
    "stick-slip": (["coulomb_friction=0.3"], 0.005),
    "tilt+distortion": (["inclination=2", "excitation_distortion=h2=0.1,h3=0.05"], 0.012),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def result(request):
    fx, b = CASES[request.param]
    return simulate(preset("paper", b=b), Effects.parse(fx), settle=2.0, duration=1.5)


def _general(res, t):
    """States of ``t`` through the general path: evaluate a shuffled copy, unshuffle."""
    perm = np.random.default_rng(0).permutation(t.size)
    assert _segment_runs(res._segments["t0"], t[perm]) is None
    out = res._evaluate(t[perm])
    inv = np.empty_like(perm)
    inv[perm] = np.arange(t.size)
    return {k: v[inv] for k, v in out.items()}


def _grids(res):
    rng = np.random.default_rng(1)
    s, d = res.settle, res.duration
    t_imp = res.impacts.t[res.impacts.t > 0.5][:200]
    return {
        "record": s + np.arange(int(d * 6400)) / 6400,
        "whole span and beyond": np.linspace(-0.5, s + d + 0.5, 5000),
        "ties and segment starts": np.sort(np.r_[np.repeat(rng.uniform(0, s + d, 300), 3),
                                                res._segments["t0"][:400], t_imp]),
    }


def test_sorted_grids_equal_the_general_path_bit_for_bit(result):
    for name, t in _grids(result).items():
        assert _segment_runs(result._segments["t0"], t) is not None, name
        fast, slow = result._evaluate(t), _general(result, t)
        assert list(fast) == list(slow)
        for key in fast:
            assert fast[key].dtype == slow[key].dtype == np.float64
            assert fast[key].tobytes() == slow[key].tobytes(), (name, key)


def test_runs_are_the_segments_a_search_gives(result):
    t0s = result._segments["t0"]
    for name, t in _grids(result).items():
        j0, j1, counts = _segment_runs(t0s, t)
        idx = np.clip(np.searchsorted(t0s, t, side="right") - 1, 0, t0s.size - 1)
        assert np.array_equal(np.repeat(np.arange(j0, j1), counts), idx), name


def test_grids_the_runs_do_not_take():
    t0s = np.array([0.0, 1.0, 2.0])
    t = np.linspace(0.0, 3.0, _MIN_RUNS)
    assert _segment_runs(t0s, t) is not None
    assert _segment_runs(t0s, t[:-1]) is None                 # short
    assert _segment_runs(t0s, t[::-1]) is None                # descending
    bad = t.copy()
    bad[5] = np.nan
    assert _segment_runs(t0s, bad) is None                    # NaN is not sorted
    assert _segment_runs(t0s, np.tile(t, (2, 1))) is None     # not 1-D
