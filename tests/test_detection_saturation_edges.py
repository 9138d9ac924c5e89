"""Weak false pulses at the edges of a saturated forced response (issue 10, det18).

Where the forced response itself runs into the accelerometer's rail, the smooth part next
to each saturated stretch leans on the polynomial bridge across it; the bridge's error was
fitted as trains of weak pulses on the ramps into and out of the rail. The detector now
holds the bridge at or beyond the rail (a reading on the rail says the acceleration was
there or beyond), measures the remaining error on the record (hiding a few more read
samples at each edge) and asks a pulse there to exceed it. Impacts inside the stretches
stay unreadable.
"""

from __future__ import annotations

import dataclasses

import pytest


def _detect(case):
    from vidiscover.analysis import analyze
    from vidiscover.analysis.validation import match_impacts_by_wall

    sim = case.simulate()
    det = analyze(sim.recording, flight_law=(case.mu, case.theta), n_boot=0).detection
    imp = sim.truth.impacts
    ie, _ = match_impacts_by_wall(det.t, det.side, imp.t_in, imp.side)
    return det, len(ie)


@pytest.mark.slow
def test_weak_pulses_at_saturated_stretch_edges_are_not_impacts():
    # dev-016's rig recorded with a 46.5 m/s^2 full scale (35 % of the samples on the
    # rail; noise seed 22017, a det18 tuning seed): 70 false pulses before, now 6; 60
    # impacts found, was 52 (the rest lie inside the stretches)
    from vidiscover.corpus import realism_case

    case = realism_case("dev", 16)
    sensors = dict(case.sensors, a_full_scale=46.5)
    det, matched = _detect(dataclasses.replace(case, sensors=sensors, seed=22017))
    assert any("saturates over" in w for w in det.warnings)
    assert matched >= 58                                      # was 52
    assert det.n - matched <= 9                               # was 70


@pytest.mark.slow
def test_holdout8_048_saturated_forced_response_edges():
    # holdout8-048 (spent; Chebyshev-1 5, 47 % of the record on the rail): 76 false
    # pulses at the stretches' edges and on the ramps between them; now 11, and 104
    # impacts found, was 92 (diag18: all 28 misses before lay on the rail)
    from vidiscover.corpus import realism_case

    det, matched = _detect(realism_case("holdout8", 48))
    assert matched >= 102                                     # was 92
    assert det.n - matched <= 14                              # was 76
