"""Continuation of orbit branches: bifurcations located and confirmed by simulation."""

import math

import numpy as np
import pytest

from vidiscover import Effects, preset, simulate
from vidiscover.errors import InputError
from vidiscover.orbits.continuation import continue_orbit, with_value
from vidiscover.orbits.find import find_orbits
from vidiscover.orbits.shooting import ImpactMap, solve_orbit, state_at


def _orbit(p, effects=None, stable=True):
    orbs, _ = find_orbits(p, effects)
    return next(o for o in orbs if o.stable == stable)


def _simulate_from(p_orbit, orbit_q, sides, p_sim, periods):
    """Start the engine at p_sim on the orbit solved at p_orbit; impacts and strobe x."""
    imap = ImpactMap(p_orbit)
    orb = solve_orbit(imap, orbit_q, sides, 1)
    assert orb.found, orb.reason
    T = orb.T
    ts = math.ceil(orb.pieces[0].t0 / T) * T
    X0 = state_at(imap, orb, ts)
    Ts = 1 / p_sim.frequency
    res = simulate(p_sim, settle=0.0, duration=periods * Ts, initial=tuple(X0))
    return res, X0


def test_period_doubling_of_the_paper_rigs_asymmetric_branch_in_b():
    p = preset("paper", b=0.009)
    orb = _orbit(p)
    assert orb.kind == "2ipc_asym"
    br = continue_orbit(p, None, orb, "b", 0.006)
    pds = [b for b in br.bifurcations if b.type == "period_doubling"]
    assert len(pds) == 1
    b_pd = pds[0].value
    assert 0.0075 < b_pd < 0.0078
    # located to 1e-4 of b: the multiplier is on either side of -1 there
    lowest = []
    for rel in (-1e-4, 1e-4):
        pr = p.replace(b=b_pd * (1 + rel))
        o = solve_orbit(ImpactMap(pr), pds[0].q, orb.sides, 1)
        assert o.found, o.reason
        lowest.append(min(o.multipliers.real))
    assert lowest[0] < -1.0 < lowest[1]
    # simulations either side, started on the orbit: period 1 above, period 2 below
    for rel, period in ((0.01, 1), (-0.01, 2)):
        pr = p.replace(b=b_pd * (1 + rel))
        res, _ = _simulate_from(pr, pds[0].q, orb.sides, pr, 600)
        ev = res.evaluate(np.arange(590, 600) * pr.period)["x"]
        one = np.abs(np.diff(ev)).max() / np.abs(ev).max()
        two = np.abs(ev[2:] - ev[:-2]).max() / np.abs(ev).max()
        if period == 1:
            assert one < 1e-6
        else:
            assert one > 1e-3 and two < 1e-6


def test_fold_of_the_symmetric_branch_in_frequency():
    p = preset("paper", b=0.012)
    orb = _orbit(p)
    br = continue_orbit(p, None, orb, "frequency", 12.5, ds_max=0.2)
    folds = [b for b in br.bifurcations if b.type == "fold"]
    assert len(folds) == 1
    f_fold = folds[0].value
    assert 11.8 < f_fold < 12.0
    # two Neimark-Sacker points on the way: a complex pair crosses the unit circle
    ns = [b for b in br.bifurcations if b.type == "neimark_sacker"]
    assert len(ns) == 2
    for bif in ns:
        moduli = []
        for rel in (-1e-4, 1e-4):
            o = solve_orbit(ImpactMap(p.replace(frequency=bif.value * (1 + rel))), bif.q,
                            orb.sides, 1)
            pair = o.multipliers[np.abs(o.multipliers.imag) > 1e-9]
            moduli.append(np.abs(pair).max())
        assert (moduli[0] - 1) * (moduli[1] - 1) < 0
    # Newton finds the orbit just below the fold and none just above
    below = solve_orbit(ImpactMap(p.replace(frequency=f_fold * (1 - 1e-4))), folds[0].q,
                        orb.sides, 1)
    above = solve_orbit(ImpactMap(p.replace(frequency=f_fold * (1 + 1e-4))), folds[0].q,
                        orb.sides, 1)
    assert below.found and below.stable
    assert not above.found and above.reason
    # simulations started on the near-fold orbit: it persists below, is left above
    p_near = p.replace(frequency=f_fold * (1 - 3e-3))
    q_near = solve_orbit(ImpactMap(p_near), folds[0].q, orb.sides, 1).q
    for rel, stays in ((-3e-3, True), (3e-3, False)):
        ps = p.replace(frequency=f_fold * (1 + rel))
        res, X0 = _simulate_from(p_near, q_near, orb.sides, ps, 300)
        ev = res.evaluate(np.arange(280, 300) * ps.period)["x"]
        spread = np.ptp(ev) / np.abs(X0[0])
        if stays:
            assert spread < 1e-9
        else:
            assert spread > 0.05


def test_branch_document_and_grazing_end():
    p = preset("paper", b=0.012)
    saddle = _orbit(p, stable=False)
    br = continue_orbit(p, None, saddle, "b", 0.004)
    d = br.to_dict()
    assert d["kind"] == "2ipc_sym" and d["points"]
    assert {"value", "stable", "max_multiplier"} <= set(d["points"][0])
    assert not any(pt["stable"] for pt in d["points"])
    assert br.bifurcations[-1].type == "grazing"
    assert "grazing" in br.end_reason
    assert 0.006 < br.bifurcations[-1].value < 0.0065
    values = [pt["value"] for pt in d["points"]]
    assert values[0] == pytest.approx(0.012) and min(values) < 0.0065


def test_grazing_with_a_wall_ends_the_branch_where_the_sequence_changes():
    p = preset("paper", b=0.012)
    fx = Effects.parse(["asymmetric_restitution=0.88,0.7"])
    br = continue_orbit(p, fx, _orbit(p, fx), "b", 0.004)
    end = br.bifurcations[-1]
    assert end.type == "grazing" and "hits the left wall" in end.detail
    assert 0.0049 < end.value < 0.0051
    assert br.points[-1].margin < 1e-3       # an interior extremum of z at the left wall


def test_continuation_in_an_effect_parameter_finds_the_period_doubling():
    p = preset("paper", b=0.012)
    fx = Effects.parse(["asymmetric_restitution=0.88,0.7"])
    orb = _orbit(p, fx)
    br = continue_orbit(p, fx, orb, "r_left", 0.6)
    pds = [b for b in br.bifurcations if b.type == "period_doubling"]
    assert len(pds) == 1 and 0.67 < pds[0].value < 0.69
    assert br.points[0].stable and not br.points[-1].stable


def test_bad_parameter_is_refused():
    p = preset("paper", b=0.012)
    orb = _orbit(p)
    with pytest.raises(InputError, match="cannot continue"):
        continue_orbit(p, None, orb, "nonsense", 1.0)
    with pytest.raises(InputError, match="cannot continue"):
        with_value(p, Effects.parse(["velocity_dependent_restitution"]), "r_left", 0.5)
