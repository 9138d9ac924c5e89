"""Initial guesses for the shooting, and the search behind ``vidiscover orbits``.

Guesses come from two places: long simulations of the exact engine from several
initial conditions (they settle on the stable orbits; the impacts of the last
periods give the side sequence, the period and the section state), and the closed
form of the symmetric two-impact orbit of the frictionless single-r model (both of
its solutions, the stable and the unstable one; for other models it is only a guess).
"""

from __future__ import annotations

import cmath
import math

import numpy as np
from scipy.optimize import brentq

from ..effects import Effects
from ..params import SystemParams
from ..simulation import simulate
from .shooting import ImpactMap, Orbit, solve_orbit

__all__ = ["seed_from_simulation", "symmetric_two_impact_guesses", "find_orbits"]


def seed_from_simulation(params: SystemParams, effects: Effects | None = None, *,
                         settle_periods: int = 160, record_periods: int = 12,
                         ball_speed: float = 0.6, initial=None, max_period: int = 4):
    """The periodic impact pattern a simulation settles on, as a shooting guess.

    Returns
    -------
    tuple (q, sides, p) or None
        Section state just after an impact, the side sequence of one orbit period and
        the number of forcing periods p; None when the simulation is not periodic
        with p <= ``max_period`` (or does not impact, or sticks).
    """
    T = 1.0 / params.frequency
    settle = settle_periods * T
    res = simulate(params, effects, settle=settle, duration=record_periods * T,
                   ball_speed=ball_speed, initial=initial)
    imp = res.impacts
    idx = np.flatnonzero(imp.t > settle)
    if idx.size < 2 or imp.t[idx[-1]] < res.t_end - 2 * max_period * T:
        return None   # no impacts, or the ball stays stuck
    t = imp.t[idx]
    for p in range(1, max_period + 1):
        for n in range(1, idx.size // 2 + 1):
            if t.size < 2 * n + 1:
                break
            gap = t[n:] - t[:-n]
            if np.all(np.abs(gap[-n - 1:] - p * T) < 1e-4 * T) and np.all(
                    imp.side[idx][n:][-n - 1:] == imp.side[idx][:-n][-n - 1:]):
                i = idx[-n - 1]
                while imp.stuck[i]:         # start the sequence at an impact that rebounds
                    i -= 1
                if i < idx[0] or imp.stuck[idx[-n - 1]:].all():
                    return None
                q = np.array([imp.t[i], imp.x[i], imp.v_plus[i], imp.w_plus[i]])
                sides = tuple(int(s) for s in imp.side[i:i + n])
                return q, sides, p
            if gap[-1] > p * T * 1.01:
                break
    return None


def symmetric_two_impact_guesses(params: SystemParams, r: float | None = None) -> list:
    """Closed-form symmetric two-impact orbits of the frictionless single-r model.

    The LO response is the harmonic one plus the response to an alternating train of
    impulses ``+J`` (right impacts at ``t1 + k T``) and ``-J`` (left, ``t1 + T/2 + kT``),
    summed in closed form; the ball flies at constant speed between the walls. Unknowns
    ``t1`` and ``J`` follow from momentum and Newton's law (see the module tests).

    Returns
    -------
    list of (q, sides, p)
        Section states just after the right impact, for each solution.
    """
    m, c, k, m2 = params.m1, params.c1, params.k1, params.m2
    A, f, b = params.amplitude, params.frequency, params.b
    r = params.r if r is None else r
    w, T = 2 * math.pi * f, 1.0 / f
    P = A * (k + 1j * c * w) / (k - m * w * w + 1j * c * w)
    sg = c / (2 * m)
    wd = math.sqrt(k / m - sg * sg)
    lam = complex(-sg, wd)
    qh = cmath.exp(lam * T / 2)
    G0 = (1 / (1 + qh)).imag / (m * wd)
    G1 = (lam / (1 + qh)).imag / (m * wd)

    def parts(t1):
        e = cmath.exp(1j * w * t1)
        xp, vp = (P * e).imag, (1j * w * P * e).imag
        J = 8 * m2 * (xp + b) / (T - 8 * m2 * G0)
        x1 = xp + J * G0
        vplus = vp + J * G1
        vminus = vplus - J / m
        wplus = -4 * (x1 + b) / T
        return x1, vplus, vminus, wplus, J

    def resid(t1):
        _, vplus, vminus, wplus, _ = parts(t1)
        return (wplus - vplus) - r * (wplus + vminus)

    grid = np.linspace(0.0, T, 241)
    vals = [resid(t) for t in grid]
    out = []
    for a, bb, fa, fb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]):
        if fa * fb < 0:
            t1 = brentq(resid, a, bb, xtol=1e-16, rtol=1e-15)
            x1, vplus, _, wplus, J = parts(t1)
            if J > 0 and wplus - vplus < 0:
                out.append((np.array([t1, x1, vplus, wplus]), (1, -1), 1))
    return out


def _same(o1: Orbit, o2: Orbit) -> bool:
    if o1.period_cycles != o2.period_cycles or o1.n_impacts != o2.n_impacts:
        return False
    period = o1.period_cycles * o1.T
    for shift in range(o1.period_cycles):  # an orbit shifted by whole forcing periods
        if all(any(d1["side"] == d2["side"] and min(
                (d1["t"] + shift * o1.T - d2["t"]) % period,
                (d2["t"] - d1["t"] - shift * o1.T) % period) < 1e-7 for d2 in o2.impacts)
               for d1 in o1.impacts):
            return True
    return False


def find_orbits(params: SystemParams, effects: Effects | None = None, *,
                ball_speeds=(0.2, 0.6, 1.2), settle_periods: int = 160,
                max_period: int = 4) -> tuple[list[Orbit], list[str]]:
    """Periodic impacting orbits at one parameter set, with their stability.

    Seeds: simulations from the LO at rest with the ball at the centre moving at each
    of ``ball_speeds``, and the closed-form symmetric two-impact orbits (both
    solutions). Each seed is refined by Newton shooting; duplicates are merged.

    Returns
    -------
    orbits : list of Orbit
        Distinct found orbits, stable ones first.
    notes : list of str
        Seeds that led nowhere, with the reason.
    """
    effects = effects if effects is not None else Effects()
    imap = ImpactMap(params, effects)
    seeds, notes = [], []
    for speed in ball_speeds:
        s = seed_from_simulation(params, effects, settle_periods=settle_periods,
                                 ball_speed=speed, max_period=max_period)
        if s is None:
            notes.append(f"simulation from ball speed {speed:g} m/s: no periodic impacting "
                         f"pattern with p <= {max_period} (no impact, stick, or not periodic)")
        else:
            seeds.append(("simulation", s))
    seeds += [("closed form", s) for s in symmetric_two_impact_guesses(
        params, r=float(effects.restitution_laws(params.r)["right"](0.0)))]
    found: list[Orbit] = []
    for origin, (q, sides, p) in seeds:
        orb = solve_orbit(imap, q, sides, p)
        if not orb.found:
            notes.append(f"{origin} guess ({len(sides)} impacts / {p} periods): {orb.reason}")
            continue
        if not any(_same(orb, o) for o in found):
            found.append(orb)
    found.sort(key=lambda o: (not o.stable, o.period_cycles, o.n_impacts))
    return found, notes
