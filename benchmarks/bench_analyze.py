"""``analyze`` speed (DESIGN.md section 8) and its accuracy against simulated truth.

Speed: :func:`vidiscover.analysis.analyze` without figures on one 5.12 s
recording of the paper preset at b = 9 mm (asymmetric walls 0.88/0.20, default
sensors) with its pulse response known (``pulse=PulseModel()``, the exact engine's
default sensors, as ``bench_cli.py`` times it; ``bench_cli.py``'s recording has one
constant r and 82 impacts, this one the paper's Table 2 walls, 164 impacts in chatter
runs, whose ends the resting-load search visits: about 3 times as long, 18.6
against 6.0 ms on an idle 2-core machine, 2026-11-26; 14.5 ms median, 13.6 best, on
2026-11-27 after the searches were batched, 578f987-2c7bd81, with the same
detections; 8.4 ms median, 8.2 best, idle, 2026-11-27 after the resting-load search
read its fits from inner products, 66dbce0, same detections; 10.5 / 9.5 in a run
straight after the accuracy quotes; 8.6 ms median, 8.3 best, idle, 2026-11-27 after
fewer numpy calls per search, dc90d42-1e9521d, same results: in-process A/B against the
code before, interleaved, 300 pairs, CPU 9.8 -> 8.9 ms (0.90), within the spread of
separate runs, 8.3-9.6 ms for either); on the next stop's machine (2026-11-27, a slower
and noisier VM of the same kind) 12.5 ms best at ee2348a against 12.3 best for the code
before (68482a7), separate runs on the idle machine, medians 12.8-19 ms bimodal for
either: no change of the code's speed, a slower machine; 12.0 ms best, 13.0 median, at
604270c on that machine, after robust_std's selection and the smoother's reuse, a9badde
and before, bit-identical results), ``N``
runs after one warm-up, median
and best wall-clock time and the best CPU time, with the bootstrap at its default
(``n_boot=1000``) and small (100, 0), printed next to DESIGN.md section 8's 6 ms target
as a ratio (<= 1 meets it; the verdict is on ``n_boot=0``, the figure ``bench_cli.py``
quotes), plus the time of each stage; and, without a target, the default analysis of a
recording of unknown instrument, which learns its pulse response first. On a shared
machine the wall-clock median follows the load; the best run and the CPU time are the
figures to compare with the target, and the load average is printed.

Accuracy (issue 3 figures), per case: impact detection precision and recall on
the detectable true impacts (:func:`vidiscover.analysis.detection_scores`),
median / max timing error, the per-wall RMS of the estimated r against the RMS
of the true r of the same impacts, and the RMS error of the reconstructed ball
position. Cases: b in {6, 7.5, 9} mm x noise seeds {1, 2, 3}; mu = 0.3 in the
data analysed with mu = 0.3 (and with mu = 0 for contrast); ``sensor_resonance``
switched on. Then the mu table (paper Table 2) on frictionless and on mu = 0.3
data, with the friction-consistent correction of the package next to paper
eq. 8 as printed (its sign convention, see the note printed with the table).

Usage::

    python benchmarks/bench_analyze.py [N] [--seeds 1 2 3] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from analysis_sim import ASYM, true_r_rms  # noqa: E402

from vidiscover import Effects, SensorConfig, preset, record, simulate  # noqa: E402
from vidiscover.analysis import (  # noqa: E402
    MU_TABLE,
    PulseModel,
    analyze,
    detect_impacts,
    detection_scores,
    estimate_restitution,
    fit_forcing,
    reconstruct,
    return_map,
)
from vidiscover.params import G_ACCEL  # noqa: E402

TARGET = 6e-3             # s, DESIGN.md section 8 (in-process, no figures, pulse known)
SETTLE = 10.0             # s of transient simulated before the record
FIGURES = {"precision": 0.99, "recall": 0.99, "timing_median": 30e-6, "r_rms_diff": 0.02,
           "ball_rms": 0.5e-3}


def machine() -> dict:
    """Where the numbers were measured."""
    import numpy
    import scipy
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return {"platform": platform.platform(), "python": platform.python_version(),
            "processor": platform.processor() or platform.machine(),
            "cpu_count": os.cpu_count(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "loadavg": [round(v, 2) for v in load]}


def case(b: float, effects=ASYM, seed: int = 1):
    """(Recording, truth) of the paper preset at half-clearance b."""
    res = simulate(preset("paper", b=b), Effects.parse(list(effects)), settle=SETTLE,
                   duration=5.12)
    return record(res, SensorConfig(), seed=seed)


def timed(fn, n: int) -> dict:
    """Wall-clock (median, best) and best CPU time of ``n`` calls after a warm-up."""
    fn()
    wall, cpu = [], []
    for _ in range(n):
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return {"median": float(np.median(wall)), "best": float(min(wall)),
            "cpu_best": float(min(cpu)), "cpu_median": float(np.median(cpu)), "n": n}


def speed(rec, n: int) -> dict:
    out = {}
    known = PulseModel()
    for nb in (1000, 100, 0):
        out[f"analyze n_boot={nb}"] = timed(lambda nb=nb: analyze(rec, n_boot=nb, pulse=known),
                                            n)
    det = detect_impacts(rec, pulse=known)
    recon = reconstruct(det, rec)
    out["  stage 1 detect_impacts"] = timed(lambda: detect_impacts(rec, pulse=known), n)
    out["  stage 2 reconstruct"] = timed(lambda: reconstruct(det, rec), n)
    out["  stage 3 restitution (n_boot=1000)"] = timed(
        lambda: estimate_restitution(recon, det, n_boot=1000), n)
    out["  forcing + return map"] = timed(
        lambda: return_map(det.t, det.side, fit_forcing(rec.t, rec.xe, 8.0).period), n)
    out["analyze n_boot=0, pulse learned"] = timed(lambda: analyze(rec, n_boot=0),
                                                    max(3, n // 10))
    return out


def ball_rms(out, truth) -> float:
    """RMS (m) of reconstructed minus true ball position where a flight covers the sample."""
    y = out.reconstruction.ball_position(out.reconstruction.t)
    ok = np.isfinite(y)
    return float(np.sqrt(np.mean((y[ok] - truth.motion.y[ok]) ** 2)))


def accuracy(label: str, rec, truth, mu: float = 0.0) -> dict:
    out = analyze(rec, mu=mu)
    s = detection_scores(out.detection.t, out.detection.side, truth)
    row = {"case": label, "mu": mu, "n_det": s.n_est, "n_detectable": s.n_detectable,
           "precision": s.precision, "recall": s.recall,
           "timing_median": s.timing_median, "timing_max": s.timing_max,
           "ball_rms": ball_rms(out, truth)}
    for side in ("right", "left"):
        w = out.restitution.wall(side)
        true_rms, n = true_r_rms(out, truth, side)
        row.update({f"{side}_est": w.rms, f"{side}_true": true_rms, f"{side}_n": w.n,
                    f"{side}_diff": w.rms - true_rms})
    row["meets"] = bool(row["precision"] >= FIGURES["precision"]
                        and row["recall"] >= FIGURES["recall"]
                        and row["timing_median"] <= FIGURES["timing_median"]
                        and abs(row["right_diff"]) <= FIGURES["r_rms_diff"]
                        and abs(row["left_diff"]) <= FIGURES["r_rms_diff"]
                        and row["ball_rms"] <= FIGURES["ball_rms"])
    return row


def paper_eq8_rms(out, mu: float) -> dict:
    """Per-wall RMS of r with paper eq. 8 *as printed* on the mu = 0 reconstruction.

    Eq. 8 writes y'(t_{i-1})+ = w_i + f0 dt_i / 2, y'(t_i)- = w_i - f0 dt_i / 2 with
    f0 = mu g signed against the relative velocity: the ball leaves each wall
    slower and reaches the next one faster than its mean velocity, the reverse of
    a decelerating friction force. Same impacts as the package's estimate.
    """
    ic = out.reconstruction.impact_columns
    fc = out.reconstruction.flight_columns
    c = out.restitution.columns
    used = c["used"]
    fi, fo = ic["flight_in"][used], ic["flight_out"][used]
    s = np.where(c["side"][used] == "right", 1.0, -1.0)
    dt_in = fc["t_end"][fi] - fc["t_release"][fi]
    dt_out = fc["duration"][fo]
    w_minus = fc["w_end"][fi] + s * mu * G_ACCEL * dt_in / 2
    w_plus = fc["w_start"][fo] + s * mu * G_ACCEL * dt_out / 2
    r = -(w_plus - ic["v_plus"][used]) / (w_minus - ic["v_minus"][used])
    return {side: float(np.sqrt(np.mean(r[s == sg] ** 2)))
            for side, sg in (("right", 1.0), ("left", -1.0))}


def mu_tables(rec0, rec_f) -> dict:
    out0 = analyze(rec0)
    tab0 = out0.mu_table()
    tabf = analyze(rec_f).mu_table()
    rows = []
    for k, mu in enumerate(MU_TABLE):
        lit = paper_eq8_rms(out0, mu)
        rows.append({"mu": mu, "right": float(tab0["right_rms"][k]),
                     "left": float(tab0["left_rms"][k]), "paper_eq8_right": lit["right"],
                     "paper_eq8_left": lit["left"], "mu03_right": float(tabf["right_rms"][k]),
                     "mu03_left": float(tabf["left_rms"][k]),
                     "warn": bool(tab0["right_warn"][k] or tab0["left_warn"][k])})
    return {"rows": rows, "paper": [(0.0, 0.8782, 0.2018), (0.09, 0.8769, 0.2003),
                                    (0.2, 0.8752, 0.1984), (0.4, 0.8721, 0.1950),
                                    (0.6, 0.8691, 0.1916)]}


def _us(v):
    return f"{v * 1e6:7.1f}" if math.isfinite(v) else "    nan"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("repeat", nargs="?", type=int, default=30, help="timed runs (30)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--json", action="store_true", help="print one JSON document")
    args = ap.parse_args(argv)
    info = machine()

    rec9, _ = case(0.009)
    sp = speed(rec9, args.repeat)

    rows = []
    for b in (0.006, 0.0075, 0.009):
        for seed in args.seeds:
            rec, truth = case(b, ASYM, seed)
            rows.append(accuracy(f"b={b * 1e3:g}mm seed={seed}", rec, truth))
    fric = ASYM + ("coulomb_friction=0.3",)
    for b in (0.006, 0.009):
        rec, truth = case(b, fric, 1)
        rows.append(accuracy(f"b={b * 1e3:g}mm mu=0.3 data, mu=0.3", rec, truth, mu=0.3))
        rows.append(accuracy(f"b={b * 1e3:g}mm mu=0.3 data, mu=0  ", rec, truth, mu=0.0))
    for seed in args.seeds:
        rec, truth = case(0.009, ASYM + ("sensor_resonance",), seed)
        rows.append(accuracy(f"b=9mm sensor_resonance seed={seed}", rec, truth))
    rec0, _ = case(0.009)
    recf, _ = case(0.009, fric, 1)
    mt = mu_tables(rec0, recf)
    info["loadavg_end"] = [round(v, 2) for v in os.getloadavg()]

    if args.json:
        print(json.dumps({"machine": info, "target_s": TARGET, "speed": sp, "accuracy": rows,
                          "mu_table": mt}, indent=2))
        return 0
    print(f"machine: {info['platform']}, {info['processor']}, cpu_count {info['cpu_count']}, "
          f"python {info['python']}, numpy {info['numpy']}, scipy {info['scipy']}")
    print(f"load average at start {info['loadavg']}, at end {info['loadavg_end']}")
    print(f"\nanalyze() on one 5.12 s recording (paper preset, b = 9 mm), {args.repeat} runs;"
          f" target {TARGET * 1e3:.0f} ms (ratio = time / target)")
    print(f"{'':38s} {'median':>8s} {'best':>8s} {'cpu best':>9s} {'ratio best':>11s} "
          f"{'ratio cpu':>10s}")
    for k, v in sp.items():
        learned = "learned" in k
        print(f"{k:38s} {v['median'] * 1e3:6.1f}ms {v['best'] * 1e3:6.1f}ms "
              f"{v['cpu_best'] * 1e3:7.1f}ms "
              + ("   (no target: the pulse response is learned first)" if learned else
                 f"{v['best'] / TARGET:11.2f} {v['cpu_best'] / TARGET:10.2f}"))
    v = sp["analyze n_boot=0"]
    print(f"verdict (n_boot=0, pulse known): median {v['median'] * 1e3:.2f} ms, target <= "
          f"{TARGET * 1e3:g} ms: {'MET' if v['median'] <= TARGET else 'MISSED'} (measure on "
          "an idle machine)")
    print("\naccuracy against simulated truth (r_right 0.88, r_left 0.20, default sensors); "
          "figures: precision, recall >= 0.99, median timing <= 30 us, |r RMS est - true| "
          "<= 0.02, ball RMS <= 0.5 mm (asked at 9 mm)")
    print(f"{'case':36s} {'n':>4s} {'prec':>6s} {'recall':>6s} {'t_med':>7s} {'t_max':>7s} "
          f"{'right est/true (n)':>21s} {'left est/true (n)':>21s} {'ball':>8s} ok")
    print(f"{'':36s} {'':>4s} {'':>6s} {'':>6s} {'us':>7s} {'us':>7s} {'':>21s} {'':>21s} "
          f"{'um RMS':>8s}")
    for r in rows:
        print(f"{r['case']:36s} {r['n_det']:4d} {r['precision']:6.3f} {r['recall']:6.3f} "
              f"{_us(r['timing_median'])} {_us(r['timing_max'])} "
              f"{r['right_est']:6.4f}/{r['right_true']:6.4f} ({r['right_n']:3d}) "
              f"{r['left_est']:6.4f}/{r['left_true']:6.4f} ({r['left_n']:3d}) "
              f"{r['ball_rms'] * 1e6:8.1f} {'yes' if r['meets'] else 'NO'}")
    print("\n(the 'mu=0.3 data, mu=0' rows show what ignoring friction does; they are not "
          "expected to meet the r figure)")
    print("\nmu table (paper Table 2), b = 9 mm, RMS of r per wall")
    print(f"{'mu':>5s} | {'frictionless data':^17s} | {'paper eq. 8 as printed':^22s} | "
          f"{'paper Table 2':^15s} | {'mu = 0.3 data':^15s}")
    print(f"{'':>5s} | {'right':>8s} {'left':>8s} | {'right':>10s} {'left':>10s}  | "
          f"{'right':>7s} {'left':>7s} | {'right':>7s} {'left':>7s}")
    for r, p in zip(mt["rows"], mt["paper"]):
        print(f"{r['mu']:5.2f} | {r['right']:8.4f} {r['left']:8.4f} | "
              f"{r['paper_eq8_right']:10.4f} {r['paper_eq8_left']:10.4f}  | "
              f"{p[1]:7.4f} {p[2]:7.4f} | {r['mu03_right']:7.4f} {r['mu03_left']:7.4f}"
              f"{'  (warn)' if r['warn'] else ''}")
    print("(warn: on the frictionless data the friction correction is a large part of the "
          "relative impact speed on a wall, see vidiscover.analysis.restitution)")
    print("friction-consistent correction (package): r rises with mu and recovers the truth "
          "on mu = 0.3 data between the 0.2 and 0.4 rows; paper eq. 8 as printed (its sign "
          "of f0) makes r fall with mu, the paper's direction. Neither changes as little as "
          "the paper's 1 %: the simulated ball is slow compared with mu g dt.")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
