"""Periodic orbits by shooting on the exact impact map: against the engine and a closed form."""

import cmath
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from vidiscover import Effects, preset, simulate
from vidiscover.orbits.find import find_orbits, seed_from_simulation
from vidiscover.orbits.shooting import ImpactMap, solve_orbit, state_at

CASES = {
    "nominal": (0.012, []),
    "asymmetric_r": (0.012, ["asymmetric_restitution=0.88,0.7"]),
    "r_of_v": (0.012, ["velocity_dependent_restitution=linear:0.95:0.3,linear:0.9:0.2"]),
    "tilt": (0.012, ["inclination=2"]),
    "friction_no_stick": (0.012, ["coulomb_friction=0.05"]),
    "friction_with_stick": (0.006, ["coulomb_friction=0.6"]),
    # the paper's Table 2 walls, weak wall on the right: the chatter on it ends stuck to
    # the wall; mirrored so that the ball is in flight at the forcing period's start,
    # where the engine (which starts at phase 0) can be started on the orbit
    "wall_stick": (0.009, ["asymmetric_restitution=0.2018,0.8782"]),
}


def _stable_orbit(name):
    b, fx = CASES[name]
    p, effects = preset("paper", b=b), Effects.parse(fx)
    seed = seed_from_simulation(p, effects)
    assert seed is not None
    imap = ImpactMap(p, effects)
    orb = solve_orbit(imap, *seed)
    assert orb.found, orb.reason
    return p, effects, imap, orb


def _start_on_orbit(imap, orb):
    """A multiple of T at which to start the engine, and the orbit's state there."""
    ts = math.ceil(orb.pieces[0].t0 / orb.T) * orb.T
    return ts, state_at(imap, orb, ts)


@pytest.mark.parametrize("name", list(CASES))
def test_stable_orbit_impact_times_match_a_long_simulation(name):
    p, effects, imap, orb = _stable_orbit(name)
    assert orb.stable
    ts, X0 = _start_on_orbit(imap, orb)
    T, period = orb.T, orb.period_cycles * orb.T
    res = simulate(p, effects, settle=0.0, duration=50 * T, initial=tuple(X0))
    t_sim = res.impacts.t + ts
    assert res.impacts.n == 50 * orb.n_impacts // orb.period_cycles
    t_orb = np.array([d["t"] for d in orb.impacts])
    k = np.round((t_sim[:, None] - t_orb[None, :]) / period)
    err = np.min(np.abs(t_sim[:, None] - t_orb[None, :] - k * period), axis=1)
    assert err.max() < 1e-9


def _period_map_fd(p, effects, X0, period, rel=1e-6):
    def pmap(X):
        r = simulate(p, effects, settle=0.0, duration=period, initial=tuple(X))
        e = r.evaluate(period)
        return np.array([e["x"][0], e["xd"][0], e["y"][0], e["yd"][0]])

    sc = np.array([p.b, 0.1, p.b, 0.1])
    J = np.zeros((4, 4))
    for k in range(4):
        d = np.zeros(4)
        d[k] = rel * sc[k]
        J[:, k] = (pmap(X0 + d) - pmap(X0 - d)) / (2 * d[k])
    return J


@pytest.mark.parametrize("name", list(CASES))
def test_multipliers_match_finite_differences_of_the_simulated_period_map(name):
    p, effects, imap, orb = _stable_orbit(name)
    ts, X0 = _start_on_orbit(imap, orb)
    J = _period_map_fd(p, effects, X0, orb.period_cycles * orb.T)
    fd = np.linalg.eigvals(J)
    for mu in orb.multipliers:
        nearest = fd[np.argmin(np.abs(fd - mu))]
        # relative; a stick phase collapses a dimension: that multiplier is zero
        assert abs(nearest - mu) <= 1e-6 * max(abs(mu), 1e-3), (mu, fd)


def _closed_form_symmetric(p):
    """Symmetric two-impact orbit of the frictionless single-r model, derived here.

    With impacts at t1 (right, impulse +J on the LO) and t1 + T/2 (left, -J), the LO
    is the harmonic response plus the response to the alternating impulse train:
    sum_k (-1)^k h(tau + k T/2) with h = exp(-s t) sin(wd t) / (m1 wd), i.e.
    Im(exp(lam tau) / (1 + exp(lam T/2))) / (m1 wd), lam = -s + i wd. The ball flies
    at constant speed w+ from x(t1) + b to -x(t1) - b in T/2, so w+ = -4 (x1 + b) / T;
    symmetry gives w- = -w+, so J = -2 m2 w+; Newton's law w+ - v+ = -r (w- - v-).
    """
    m, c, k, m2, r = p.m1, p.c1, p.k1, p.m2, p.r
    w, T = 2 * math.pi * p.frequency, 1 / p.frequency
    P = p.amplitude * (k + 1j * c * w) / (k - m * w ** 2 + 1j * c * w)
    s = c / (2 * m)
    wd = math.sqrt(k / m - s * s)
    lam = complex(-s, wd)
    den = 1 + cmath.exp(lam * T / 2)
    g0, g1 = (1 / den).imag / (m * wd), (lam / den).imag / (m * wd)

    def state(t1):
        e = cmath.exp(1j * w * t1)
        xp, vp = (P * e).imag, (1j * w * P * e).imag
        J = 8 * m2 * (xp + p.b) / (T - 8 * m2 * g0)
        x1, vplus = xp + J * g0, vp + J * g1
        return x1, vplus, vplus - J / m, -4 * (x1 + p.b) / T

    def f(t1):
        _, vplus, vminus, wplus = state(t1)
        return (wplus - vplus) + r * (-wplus - vminus)

    grid = np.linspace(0, T, 400)
    roots = [brentq(f, a, b_, xtol=1e-16, rtol=1e-15)
             for a, b_ in zip(grid[:-1], grid[1:]) if f(a) * f(b_) < 0]
    return [(t1, *state(t1)) for t1 in roots if state(t1)[3] - state(t1)[1] < 0]


def test_symmetric_two_impact_orbit_matches_the_closed_form():
    p = preset("paper", b=0.012)
    imap = ImpactMap(p)
    sols = _closed_form_symmetric(p)
    assert len(sols) == 2
    stabilities = []
    for t1, x1, vplus, _, wplus in sols:
        guess = np.array([t1 + 2e-4, x1 * 1.01, vplus * 0.99, wplus * 1.01])
        orb = solve_orbit(imap, guess, ("right", "left"), 1)
        assert orb.found, orb.reason
        assert abs(orb.q[0] - t1) < 1e-10
        assert abs(orb.q[1] - x1) < 1e-12 and abs(orb.q[3] - wplus) < 1e-9
        times = sorted(d["t"] for d in orb.impacts)
        assert abs(times[1] - times[0] - orb.T / 2) < 1e-10
        stabilities.append(orb.stable)
    assert sorted(stabilities) == [False, True]     # a stable and a saddle orbit


def test_unstable_orbit_departs_at_the_rate_of_its_largest_multiplier():
    p = preset("paper", b=0.012)
    imap = ImpactMap(p)
    orbs, _ = find_orbits(p)
    saddle = next(o for o in orbs if not o.stable)
    lead = saddle.multipliers[0]
    assert abs(lead.imag) == 0 and abs(lead) > 10
    ts, X0 = _start_on_orbit(imap, saddle)
    rng = np.random.default_rng(3)
    T = saddle.T
    pert = X0 + 1e-11 * rng.standard_normal(4) * np.array([p.b, 0.1, p.b, 0.1])
    res = simulate(p, settle=0.0, duration=5 * T, initial=tuple(pert))
    ev = res.evaluate(T * np.arange(1, 5))
    sc = np.array([p.b, 0.1, p.b, 0.1])
    dist = [np.linalg.norm((np.array([ev[k][i] for k in ("x", "xd", "y", "yd")]) - X0) / sc)
            for i in range(4)]
    ratios = np.array(dist[1:]) / np.array(dist[:-1])
    assert np.allclose(ratios[1:], abs(lead), rtol=0.03), (ratios, lead)


def test_stick_phase_is_in_the_orbit():
    *_, orb = _stable_orbit("friction_with_stick")
    events = [pc.event for pc in orb.pieces]
    assert events.count("stick") == 1 and events.count("release") == 1
    assert abs(orb.multipliers[-1]) < 1e-12 < abs(orb.multipliers[-2])


def test_off_sequence_guess_is_not_found_with_a_reason():
    p = preset("paper", b=0.012)
    imap = ImpactMap(p)
    orb = solve_orbit(imap, (0.01, 0.0, 0.0, -0.01), ("right", "right"), 1)
    assert not orb.found
    assert "sequence" in orb.reason or "leave" in orb.reason, orb.reason
    assert orb.to_dict()["kind"] == "not_found"


def test_paper_table2_walls_orbit_chatters_and_sticks_and_mirrors():
    p = preset("paper", b=0.009)
    paper, _ = find_orbits(p, Effects.parse(["asymmetric_restitution=0.8782,0.2018"]))
    mirror, _ = find_orbits(p, Effects.parse(["asymmetric_restitution=0.2018,0.8782"]))
    assert len(paper) == len(mirror) == 1
    a, m = paper[0], mirror[0]
    assert a.stable and a.n_impacts == 7 and a.kind == "multi_ipc"
    assert [pc.event for pc in a.pieces].count("release") == 1     # stuck at the left wall
    assert np.sum(np.abs(a.multipliers) < 1e-12) == 2              # a stick phase collapses
    assert np.allclose(np.sort_complex(a.multipliers), np.sort_complex(m.multipliers),
                       atol=1e-9)
    # the mirror image is the same orbit half a period later, with the walls swapped
    ta = sorted((d["t"] % a.T, d["side"]) for d in a.impacts)
    tm = sorted(((d["t"] + a.T / 2) % a.T, {"left": "right", "right": "left"}[d["side"]])
                for d in m.impacts)
    for (t1, s1), (t2, s2) in zip(ta, tm):
        assert s1 == s2 and abs(t1 - t2) < 1e-9


def test_a_ball_that_stays_stuck_gives_no_orbit_and_says_why():
    p = preset("paper", b=0.012)
    orbs, notes = find_orbits(p, Effects.parse(["coulomb_friction=1.0"]))
    assert orbs == []
    assert notes and all(("stick" in n or "no impact" in n or "not on the sequence" in n
                          or "Newton" in n) for n in notes), notes


def test_period_two_orbit_and_duplicates_merged():
    p = preset("paper", b=0.012)
    orbs, _ = find_orbits(p, Effects.parse(["asymmetric_restitution=0.88,0.6"]))
    assert len(orbs) == 1
    o = orbs[0]
    assert o.period_cycles == 2 and o.n_impacts == 4 and o.stable and o.kind == "2ipc_asym"
    d = o.to_dict()
    assert d["impacts_per_period"] == 2.0 and len(d["impacts"]) == 4
    assert all(0 <= i["t"] < 2 * o.T for i in d["impacts"])
