"""Pooled flight laws on the realism corpus, next to the issue-10 targets.

Each corpus case (compliant walls, friction 0-0.3, tilt 0-3 deg, causal anti-alias
filters, other rigs and sampling rates; :mod:`vidiscover.corpus`) is recorded at
three clearances, its own ``b`` and ``0.83 b`` and ``0.67 b`` (the paper's ratios
9 : 7.5 : 6 mm), with the sensor noise of its seed plus the clearance's index. Each
recording is analysed as a user's would be (the instrument learned from it, mu = 0),
and the three analyses are pooled in
:func:`vidiscover.discovery.flight_law.discover_flight_law`.

Scores (targets of the issue):

* *within*: identified, ``|mu - mu_true| <= 0.03`` and ``|theta - theta_true| <=
  0.3 deg``: in >= 90 % of the cases. "Not identified" counts as a miss here (it is
  an honest answer, but not the result asked for);
* *bad*: a reported mu < 0 or |theta| > 10 deg: none, anywhere;
* *wrong but identified*: a reported law outside the tolerances (the worst kind of
  miss; listed case by case).

``--oracle`` separates the analysis's errors from the estimator's: each case is also
fitted with the TRUE ball velocity jumps in place of the pulse areas (``truth jumps``),
and with the true jumps at the equivalent instantaneous impacts of the compliant
contacts (``+ equivalent impacts``: where the straight approach line of z, from the
wall at the entry, and the rebound line, from where the ball leaves the contact
``z_out = z(t_out)``, meet: ``t* = (z_out - z_wall + u- t_in - u+ t_out) / (u- - u+)``,
beyond the wall by ``u- (t* - t_in)``; a Kelvin-Voigt wall releases the ball with its
spring still compressed, so ``z_out`` is inside it).
The recordings are simulated again for their truth (the analyses come from the cache).

``--periods N`` records each clearance for N forcing periods instead of the corpus's
``RECORD_PERIODS`` = 40 (the case's ``duration``; everything else of the case, the
settling included, is kept): how long a user must record for the law to be identified.
The cache keys the analyses by it (``<case>-p<N>.pkl``; the corpus's 40 keep their
plain names).

Figures are quoted on the held-back ``holdout16`` split (``test`` and ``holdout`` to
``holdout15`` were looked at case by case); ``--split dev`` is for tuning.

Measured (holdout16, 60 cases, 2026-11-27, at 99efb4c and again at 48d06b8 after the rule
for the LO's friction changed (it joins the fit only where the flights confound mu and
theta; the change came from an exact-engine unit test), both runs alike): identified 7,
within 6 (0.100; target 0.9: 003, 004, 029, 035, 039, 051), outside
1 (032: theta 0.63 for 0.00 deg, standard error 0.07; Kelvin-Voigt walls of unequal
stiffness; the same without the LO's friction, diagnosed after the run), bad 0, failed 0.
The LO's friction beside the law: identified 29, within 28, outside 1 (056: 0.240 +/- 0.003
for 0.272, Hunt-Crossley walls behind a linear-phase filter).
Earlier (holdout15, at 604270c): identified 4, all within
(0.067; target 0.9: 019, 024, 033, 047), outside 0, bad 0, failed 0; refused 56: friction
or inclination undetermined 34, weak form misfit 16, the law moves between recordings 4,
placement in the contact 1, wall pulse areas 1.
Earlier (holdout14, at ee2348a): identified 4, all within
(0.067; target 0.9: 000, 003, 007, 040), outside 0, bad 0; 2 input errors (044, 049: 7 and
0 usable impacts); refused 54: friction or inclination undetermined 25, weak form misfit
21, placement in the contact 4, the law moves between recordings 3, wall pulse areas 1.
``--periods`` (flight26, spent holdout13, first 24 cases): 40, 80, 160 and 320 periods per
clearance identified 3, 3, 3 and 2 laws, all within; the fit's own se falls as
1/sqrt(periods) (ratio 0.40 at 320), the placement's does not (1.0), and weak-form
refusals rise (9 -> 13): record length is not what limits the law here.
Earlier (holdout13, 60 cases, run once, 2026-11-27, at 30d925b, with the contact placement
as a standard error, 8c52138): identified 5, all within (0.083; target 0.9: 003, 005,
017, 024, 040), outside 0, bad 0; 3 input errors (012, 038, 045: no usable impacts);
refused 52: friction or inclination undetermined 25, weak form misfit 21, placement in the
contact 3, the law moves between recordings 2, wall pulse areas 1.
Earlier (holdout12, at cccbf5f, the placement bounded by itself): identified 1, within
(0.017; target 0.9: 030), outside 0, bad 0; 1 input error (054: 9 usable impacts); of
the 58 refused, 009, 010, 014 and 052 had fitted mu and theta within tolerance (refused
as a misfit of the weak form, a law depending on the placement in the contact, and an
undetermined inclination); the leave-one-recording-out check refused one law, a wrong
one (015: theta -2.00 for -1.24). Earlier (holdout11, at 4530ce1): identified 5, all within
(0.083; target 0.9: 025, 028, 032, 035, 047), outside 0, bad 0; 2 input errors (009,
020: no usable flight in a recording). The leave-one-recording-out check refused one
law that no other test refuses and that was right (029: mu 0.287 for 0.295, theta 0;
spread 0.28 deg). Earlier (holdout10, at 24ace70, before that check): identified 9, within 5
(0.083; target 0.9: 015, 022, 027, 033, 044), **outside 4** (002, 030, 036, 045: theta
0.35-0.95 deg off with standard errors 0.06-0.12 deg, mu within 0.03 on all but 002,
0.014 off; Hunt-Crossley walls of unequal stiffness), bad 0, no input error. The same
code on holdout9 gives what 209dbb3 gave. Earlier (holdout9, at 209dbb3): identified 5, all within
(0.083; target 0.9: 005, 011, 038, 044, 058), outside 0, bad 0; 1 input error (holdout9-025:
1 usable impact for 5 candidate terms). Earlier (holdout8, at e634b4a): identified 7, all within
(0.117; target 0.9: 003, 010, 014, 030, 052, 058, 059), outside 0, bad 0, no input error.
Earlier (holdout7, at 8fdbcdd): identified 3, all within
(0.050; target 0.9), outside 0, bad 0; 1 input error (holdout7-037: no impact read, the
accelerometer saturated over 71 % of the record). Earlier (holdout6, at 89bcbab):
identified 2, within 1
(0.017; target 0.9), outside 1 (holdout6-026: theta 0.36 deg for 0.00), bad 0; 1 input
error (no impacts: a no_impact case). Earlier (holdout5): identified 5, 4 within.
Earlier (holdout4, fresh analyses): identified 1,
within, bad 0 (0.017; target 0.9); the 59 others "not identified" (the flights do not
determine mu or theta, the weak form misfits, or the law moves when the impacts are
placed where a compliant contact's lines meet). The dev split's first 24 cases
identify none, before and after this stop's detection changes. Earlier (holdout3):
identified 9, all within, bad 0; 3 cases ended in an input error (at most 9 usable
flights for the 5 candidate terms). Earlier (holdout2): identified 2, both within.
Earlier (holdout, 2026-11-25): within 1 (0.017),
identified but outside 1 (holdout-057), bad 0; ``--oracle``: true jumps 4 within / 2 wrong, true
jumps at the equivalent impacts 10 / 0. Per-wall pulse-area errors of 0.25 % already
move theta by 0.2-1.6 deg (dev-000/002/007): the jumps, not the estimator, limit the law.

Usage::

    python benchmarks/bench_realism_flight.py [--split holdout16] [--n 60] [--start 0]
        [--cache DIR] [--oracle] [--periods 40]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import time

import numpy as np
from _case_cache import cached

from vidiscover.analysis import analyze
from vidiscover.corpus import N_CASES, RECORD_PERIODS, realism_corpus
from vidiscover.discovery.flight_law import discover_flight_law

#: Clearances of the pool, as fractions of the case's own.
RATIOS = (1.0, 0.83, 0.67)
MU_TOL, THETA_TOL = 0.03, 0.3
TARGET_WITHIN = 0.90


def analyses(case, cache: str | None = None) -> list:
    """The case's three analyses (recorded at the three clearances), cached in ``cache``.

    The cache holds the analyses only (pickles named after the case): the flight law is
    always evaluated by the code under test. Delete the directory when the simulation,
    the sensors or the analysis change. A record length other than the corpus's
    ``RECORD_PERIODS`` forcing periods is part of the key.
    """
    def compute():
        return [analyze(dataclasses.replace(case, b=case.b * ratio, seed=case.seed + k)
                        .simulate(label=False).recording, n_boot=0)
                for k, ratio in enumerate(RATIOS)]

    return cached(cache, _cache_key(case), compute)


def record_periods(case) -> int:
    """The case's record length in forcing periods (``duration`` x ``frequency``)."""
    return int(round(case.duration * case.frequency))


def with_periods(case, periods: int):
    """The case recorded for ``periods`` forcing periods (the case itself at the corpus's)."""
    if periods <= 0:
        raise SystemExit(f"--periods {periods}: a record needs at least one forcing "
                         f"period; give a positive count (the corpus's is {RECORD_PERIODS})")
    if periods == record_periods(case):
        return case
    return dataclasses.replace(case, duration=periods / case.frequency)


def _cache_key(case) -> str:
    """The cache name: the case's, with ``-p<N>`` when not recorded for the corpus's length."""
    n = record_periods(case)
    return case.name if n == RECORD_PERIODS else f"{case.name}-p{n}"


def oracle_flights(case, outs) -> tuple[list, list]:
    """The analyses' flights with the true jumps, and also at the equivalent impacts.

    Each detected impact is matched to the true contact that starts within 0.5 ms of
    it; unmatched impacts (and two detections of one contact) keep their analysed
    values.
    """
    from vidiscover.analysis.flights import FlightData

    jumps, equivalent = [], []
    for k, (ratio, out) in enumerate(zip(RATIOS, outs, strict=True)):
        sim = dataclasses.replace(case, b=case.b * ratio, seed=case.seed + k).simulate(
            label=False)
        fd = FlightData.of(out)
        ti = sim.truth.impacts
        t_in, t_out = np.asarray(ti.t_in, float), np.asarray(ti.t_out, float)
        jj = np.clip(np.searchsorted(t_in, fd.t_imp + 2e-4) - 1, 0, max(t_in.size - 1, 0))
        ok = (np.abs(t_in[jj] - fd.t_imp) < 5e-4) if t_in.size else np.zeros(fd.dv.size, bool)
        ball = np.asarray(ti.w_plus, float) - np.asarray(ti.w_minus, float)
        ok &= np.isfinite(ball[jj]) if t_in.size else ok
        ok[1:] &= jj[1:] != jj[:-1]           # one detection per true contact (no splits)
        ok[:-1] &= jj[:-1] != jj[1:]
        dv = np.where(ok, -ball[jj] / fd.ratio, fd.dv)
        jumps.append(fd.with_impacts(dv=dv, area=dv))
        um, up = np.asarray(ti.u_minus, float)[jj], np.asarray(ti.u_plus, float)[jj]
        side = np.where(np.asarray(ti.side)[jj] == "right", 1.0, -1.0)
        wall = side * sim.truth.b_true
        # the rebound line starts where the ball leaves the contact, z(t_out): inside the
        # wall on a Kelvin-Voigt wall (its force reaches 0 with the spring still
        # compressed, 0.04-0.2 mm on the corpus), at it on a Hunt-Crossley or rigid one
        z_out = (np.asarray(sim.result.evaluate(t_out[jj] + sim.truth.settle)["z"], float)
                 if t_in.size else np.zeros(0))
        den = np.where(um != up, um - up, 1.0)
        t_eq = np.where(um != up,
                        (z_out - wall + um * t_in[jj] - up * t_out[jj]) / den, t_in[jj])
        z_eq = wall + um * (t_eq - t_in[jj])
        x_eq = np.asarray(sim.result.evaluate(t_eq + sim.truth.settle)["x"], float)
        eq = ok & np.isfinite(x_eq + z_eq) & np.isfinite(t_eq)
        equivalent.append(fd.with_impacts(t=np.where(eq, t_eq, fd.t_imp),
                                          y=np.where(eq, x_eq + z_eq, fd.y_imp), dv=dv,
                                          area=dv))
    return jumps, equivalent


def _scored(res, case) -> str:
    """'ok' / 'WRONG' / 'n.i.' of a fit, for the oracle columns."""
    if not res.identified:
        return "n.i."
    return ("ok" if abs(res.mu - case.mu) <= MU_TOL and abs(res.theta_deg - case.theta)
            <= THETA_TOL else "WRONG")


def score_case(case, cache: str | None = None, oracle: bool = False) -> dict:
    """Record one case at three clearances, pool the analyses, score the flight law."""
    t0 = time.perf_counter()
    outs = analyses(case, cache)
    res = discover_flight_law(outs, n_boot=0)
    row = {"name": case.name, "mu": case.mu, "theta": case.theta,
           "identified": bool(res.identified), "reason": res.reason,
           "n_impacts": [o.detection.n for o in outs], "seconds": time.perf_counter() - t0,
           "misfit": float(res.misfit), "precision": float(res.precision),
           "mu_se": float(res.mu_se), "theta_se": float(res.theta_se),
           "diag_mu": float(res.diagnostic.get("mu", np.nan)),
           "diag_theta": float(res.diagnostic.get("theta_deg", np.nan))}
    if res.identified:
        row.update(mu_est=float(res.mu), theta_est=float(res.theta_deg),
                   within=bool(abs(res.mu - case.mu) <= MU_TOL
                               and abs(res.theta_deg - case.theta) <= THETA_TOL),
                   bad=bool(res.mu < 0 or abs(res.theta_deg) > 10.0))
    else:
        row.update(within=False, bad=False)
    lo = res.lo_friction
    row.update(lo_identified=bool(lo is not None and lo.identified),
               lo_mu=float(lo.mu) if lo is not None else np.nan,
               lo_se=float(lo.mu_se) if lo is not None else np.nan,
               lo_reason=lo.reason if lo is not None else "")
    row["lo_within"] = bool(row["lo_identified"] and abs(row["lo_mu"] - case.mu) <= MU_TOL)
    if oracle:
        for key, recs in zip(("oracle_jumps", "oracle_equivalent"), oracle_flights(case, outs),
                             strict=True):
            fit = discover_flight_law(recs, n_boot=0)
            d = fit.diagnostic
            row[key] = _scored(fit, case)
            row[key + "_fit"] = (f"mu {d.get('mu', np.nan):.3f} theta "
                                 f"{d.get('theta_deg', np.nan):.2f} misfit {fit.misfit:.2%}")
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--split", default="holdout16", choices=sorted(N_CASES))
    ap.add_argument("--n", type=int, default=60)
    ap.add_argument("--start", type=int, default=0, help="first case index")
    ap.add_argument("--cache", default=None,
                    help="directory caching the analyses (the slow part) between runs")
    ap.add_argument("--periods", type=int, default=RECORD_PERIODS,
                    help="forcing periods recorded per clearance (default: the corpus's "
                         f"{RECORD_PERIODS})")
    ap.add_argument("--oracle", action="store_true",
                    help="also fit with the true jumps (and equivalent impacts) of each case")
    args = ap.parse_args()
    cases = realism_corpus(args.split, min(args.start + args.n, N_CASES[args.split]))
    cases = [with_periods(c, args.periods) for c in cases[args.start:]]
    print(f"bench_realism_flight: {len(cases)} cases of the {args.split!r} split, "
          f"3 clearances each"
          + ("" if args.periods == RECORD_PERIODS
             else f" recorded for {args.periods} forcing periods (corpus: {RECORD_PERIODS})")
          + f"; {platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.2f}")
    rows = []
    for case in cases:
        try:
            r = score_case(case, args.cache, args.oracle)
        except Exception as err:  # noqa: BLE001 - a failing case is a result too
            print(f"  {case.name}: FAILED {type(err).__name__}: {err}", flush=True)
            rows.append({"name": case.name, "failed": str(err), "within": False,
                         "bad": False, "identified": False})
            continue
        rows.append(r)
        got = (f"mu {r['mu_est']:.3f} theta {r['theta_est']:.2f}" if r["identified"]
               else f"n.i. (fit mu {r['diag_mu']:.3f} theta {r['diag_theta']:.2f}): "
                    f"{str(r['reason'])[:40]}")
        got += (f" [misfit {r['misfit']:.2%} prec {r['precision']:.2%} se {r['mu_se']:.3f}/"
                f"{r['theta_se']:.2f}]")
        lo = (f"LO mu {r['lo_mu']:.3f}+/-{r['lo_se']:.3f} "
              f"{'ok' if r['lo_within'] else 'WRONG'}" if r["lo_identified"]
              else f"LO n.i. ({r['lo_reason'][:30]})")
        print(f"  {r['name']} true mu {r['mu']:.3f} theta {r['theta']:.2f} -> {got} "
              f"{'ok' if r['within'] else ('BAD' if r['bad'] else 'miss')}; {lo} "
              f"({r['seconds']:.1f} s)", flush=True)
        if args.oracle:
            print(f"      truth jumps: {r['oracle_jumps']} ({r['oracle_jumps_fit']}); "
                  f"+ equivalent impacts: {r['oracle_equivalent']} "
                  f"({r['oracle_equivalent_fit']})", flush=True)
    n = len(rows)
    within = float(np.mean([r["within"] for r in rows])) if rows else float("nan")
    ident = [r for r in rows if r["identified"]]
    wrong = [r for r in ident if not r["within"]]
    bad = sum(r["bad"] for r in rows)
    print(f"\n{n} cases: identified {len(ident)}, within tolerance {within:.3f}, "
          f"identified but outside tolerance {len(wrong)}, not identified "
          f"{n - len(ident)}, failed {sum('failed' in r for r in rows)}")
    for r in wrong:
        print(f"  outside: {r['name']} mu {r['mu_est']:.3f} vs {r['mu']:.3f}, theta "
              f"{r['theta_est']:.2f} vs {r['theta']:.2f}")
    lo_id = [r for r in rows if r.get("lo_identified")]
    lo_wrong = [r for r in lo_id if not r["lo_within"]]
    print(f"friction from the LO's reaction (pooled, beside the law): identified "
          f"{len(lo_id)}, within mu 0.03 {len(lo_id) - len(lo_wrong)}, outside "
          f"{len(lo_wrong)}; negative reported {sum(r['lo_mu'] < 0 for r in lo_id)}")
    for r in lo_wrong:
        print(f"  LO outside: {r['name']} mu {r['lo_mu']:.3f} +/- {r['lo_se']:.3f} vs "
              f"{r['mu']:.3f}")
    if args.oracle:
        for key, label in (("oracle_jumps", "truth jumps"),
                           ("oracle_equivalent", "truth jumps + equivalent impacts")):
            got = [r.get(key) for r in rows if key in r]
            print(f"  oracle, {label}: within {got.count('ok')}, wrong {got.count('WRONG')}, "
                  f"not identified {got.count('n.i.')} of {len(got)}")
    print("\nmeasured vs target:")
    print(f"  {'pooled law within mu 0.03, theta 0.3 deg':<44} {within:8.3f}  target >= "
          f"{TARGET_WITHIN}  {'MET' if within >= TARGET_WITHIN else 'MISSED'}")
    print(f"  {'negative mu or |theta| > 10 deg reported':<44} {bad:8d}  target == 0     "
          f"{'MET' if bad == 0 else 'MISSED'}")


if __name__ == "__main__":
    main()
