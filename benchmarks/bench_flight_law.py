"""Flight-law discovery over the issue-4 grid, against simulated ground truth.

mu in {0, 0.1, 0.3} x theta in {0, 1, 2} deg x seeds; paper preset, constant
r = 0.88, settle 10 s, record 5.12 s, default sensors. Each case is identified
from the three clearances b = 6, 7.5, 9 mm pooled (the main claim) and, for
information, from every clearance alone. Prints the support-recovery rate, the
largest errors and the bootstrap-interval coverage, side by side with the targets;
``ok|n.i.``: within all tolerances, or "not identified" (with a reason, no numbers);
``bad``: a reported mu < 0 or |theta| > 10 deg (target 0).

Run: ``python benchmarks/bench_flight_law.py [n_seeds]``.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from vidiscover import Effects, SensorConfig, preset, record, simulate
from vidiscover.analysis import analyze
from vidiscover.discovery.flight_law import discover_flight_law

CLEARANCES = (0.006, 0.0075, 0.009)
MUS, THETAS = (0.0, 0.1, 0.3), (0.0, 1.0, 2.0)


def main(n_seeds: int = 3) -> None:
    rows = {"pooled": [], **{f"b={b * 1e3:g}mm": [] for b in CLEARANCES}}
    t_fit = []
    for seed in range(1, n_seeds + 1):
        for mu in MUS:
            for th in THETAS:
                outs = []
                for b in CLEARANCES:
                    sim = simulate(preset("paper", b=b), Effects.parse(
                        [f"coulomb_friction={mu}", f"inclination={th}",
                         "asymmetric_restitution=0.88,0.88"]), settle=10.0, duration=5.12)
                    outs.append(analyze(record(sim, SensorConfig(), seed=seed)[0], n_boot=10))
                want = {t for t, on in (("sgn(z')", mu > 0), ("1", th != 0)) if on}
                for key, lst in [("pooled", outs)] + [(f"b={b * 1e3:g}mm", [o])
                                                      for b, o in zip(CLEARANCES, outs)]:
                    t0 = time.perf_counter()
                    r = discover_flight_law(lst, seed=0, n_boot=200)
                    if key == "pooled":
                        t_fit.append(time.perf_counter() - t0)
                    good = r.identified and set(r.terms) == want
                    rows[key].append(dict(
                        mu=mu, th=th, seed=seed, ok=good,
                        phys=r.identified and set(r.terms) & {"1", "sgn(z')"} == want,
                        dmu=r.mu - mu if r.identified else 0.0,
                        dth=r.theta_deg - th if r.identified else 0.0,
                        fric0=(mu == 0 and "sgn(z')" in r.terms),
                        cov=r.identified and (r.mu_ci[0] <= mu <= r.mu_ci[1])
                        and (r.theta_ci[0] <= th <= r.theta_ci[1]),
                        ni=not r.identified, eq=r.equation if r.identified else
                        f"not identified: {r.reason[:60]}",
                        bad=r.identified and (r.mu < 0 or abs(r.theta_deg) > 10),
                        ok_or_ni=(good and abs(r.mu - mu) <= 0.03
                                  and abs(r.theta_deg - th) <= 0.3) or not r.identified))
                p = rows["pooled"][-1]
                print(f"seed={seed} mu={mu} theta={th}: {p['eq']:<40s} dmu={p['dmu']:+.4f} "
                      f"dtheta={p['dth']:+.3f} support={'ok' if p['ok'] else 'WRONG'}",
                      flush=True)
    print()
    print(f"{'data':<10s} {'cases':>5s} {'support':>8s} {'phys.sup':>8s} {'max|dmu|':>9s} "
          f"{'max|dth|':>9s} {'fric@mu0':>8s} {'CI cov.':>7s} {'n.i.':>6s} {'ok|n.i.':>9s} "
          f"{'bad':>4s}")
    print(f"{'target':<10s} {'':>5s} {'>=95%':>8s} {'':>8s} {'<=0.03':>9s} {'<=0.3':>9s} "
          f"{'0':>8s} {'':>7s} {'':>6s} {'':>9s} {'0':>4s}")
    for key, rs in rows.items():
        n = len(rs)
        print(f"{key:<10s} {n:5d} {np.mean([r['ok'] for r in rs]):8.1%} "
              f"{np.mean([r['phys'] for r in rs]):8.1%} "
              f"{max(abs(r['dmu']) for r in rs):9.4f} {max(abs(r['dth']) for r in rs):9.3f} "
              f"{sum(r['fric0'] for r in rs):8d} {np.mean([r['cov'] for r in rs]):7.1%} "
              f"{sum(r['ni'] for r in rs):6d} {np.mean([r['ok_or_ni'] for r in rs]):9.1%} "
              f"{sum(r['bad'] for r in rs):4d}")
    print(f"\npooled fit time (3 recordings, 200 bootstrap resamples): median "
          f"{np.median(t_fit):.2f} s, max {np.max(t_fit):.2f} s")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
