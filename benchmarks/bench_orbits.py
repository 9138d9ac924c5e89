"""Speed of the orbit solver and of the continuation (issue 14 targets).

* one orbit solve (Newton shooting, paper preset, b = 12 mm, symmetric two-impact
  orbit, from the closed-form guess shifted by 0.2 ms and 1 % in the state; includes
  the multipliers and the grazing margins): target <= 10 ms (median of 50);
* a 200-point continuation (the same orbit in the forcing frequency from 8 Hz
  upwards, with bifurcation location): target <= 5 s;
* for information: the same for the asymmetric-wall period-2 orbit and a friction case.

Prints measured vs target and a verdict, with the load average (the machine should be
idle: the numbers are wall-clock). Run: ``python benchmarks/bench_orbits.py``.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np

from vidiscover import Effects, preset
from vidiscover.orbits.continuation import continue_orbit
from vidiscover.orbits.find import seed_from_simulation, symmetric_two_impact_guesses
from vidiscover.orbits.shooting import ImpactMap, solve_orbit

SOLVE_TARGET_S = 0.010
CONT_TARGET_S = 5.0


def _time_solves(imap, guess, sides, p, n=50):
    times, orb = [], None
    for _ in range(n):
        t0 = time.perf_counter()
        orb = solve_orbit(imap, guess, sides, p)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), orb


def main() -> None:
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average (1 min): {load:.2f}")
    p = preset("paper", b=0.012)
    imap = ImpactMap(p)
    q, sides, per = next(g for g in symmetric_two_impact_guesses(p))
    guess = np.array([q[0] + 2e-4, q[1] * 1.01, q[2] * 0.99, q[3] * 1.01])
    t_solve, orb = _time_solves(imap, guess, sides, per)
    print(f"orbit solve (2ipc_sym, b = 12 mm): {1e3 * t_solve:.2f} ms median, "
          f"{orb.iterations} Newton iterations, stable={orb.stable}  "
          f"(target <= {1e3 * SOLVE_TARGET_S:.0f} ms)")

    extra = [("asymmetric walls 0.88/0.6 (period 2)", p,
              Effects.parse(["asymmetric_restitution=0.88,0.6"])),
             ("coulomb_friction 0.05", p, Effects.parse(["coulomb_friction=0.05"]))]
    for name, pr, fx in extra:
        seed = seed_from_simulation(pr, fx)
        t, o = _time_solves(ImpactMap(pr, fx), *seed, n=20)
        print(f"  info: orbit solve, {name}: {1e3 * t:.2f} ms median (from a simulation "
              f"seed; {o.iterations} iterations)")

    stable = solve_orbit(imap, q, sides, per)
    t0 = time.perf_counter()
    br = continue_orbit(p, None, stable, "frequency", 30.0, max_points=200)
    t_cont = time.perf_counter() - t0
    n = len(br.points)
    per200 = t_cont / n * 200
    print(f"continuation in frequency: {n} points in {t_cont:.2f} s "
          f"({per200:.2f} s per 200 points; {len(br.bifurcations)} bifurcations located; "
          f"target <= {CONT_TARGET_S:.0f} s)")
    ok_solve = t_solve <= SOLVE_TARGET_S
    ok_cont = per200 <= CONT_TARGET_S
    print(f"verdict: orbit solve {'PASS' if ok_solve else 'FAIL'}, "
          f"200-point continuation {'PASS' if ok_cont else 'FAIL'}"
          + ("" if load < 1.0 else f"  (machine not idle: load {load:.2f})"))


if __name__ == "__main__":
    main()
