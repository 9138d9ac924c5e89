"""1000-point b sweep (simulate + record + label + analyse each) vs its targets.

Targets: a 1000-point b sweep <= 10 s on 2 cores (issue 13; it was 60 s), and Dask
within 1.25x of joblib on the same cores. Runs the same sweep
(paper preset, b = 3-30 mm, settle 10 s, record 5.12 s, no bootstrap) side by side:

- serial (``n_jobs=1``, one process, no pool),
- joblib, 2 loky worker processes (the default backend),
- Dask on loopback: a ``dask scheduler`` and 2 ``dask worker`` processes x 1 thread
  started from the command line as a user would (``--local-cluster``: a
  ``distributed.LocalCluster`` of 2 worker processes instead),

prints the wall-clock of each (pool/cluster start included and shown apart), checks
that the three tables are identical, and times the stages of one point (simulate,
sensor record, ground-truth label, analyse) on a sample to show where the time goes.
The machine's load average is printed too: on a shared machine it matters.

Usage: ``python benchmarks/bench_sweep.py [--n 1000] [--skip-serial] [--skip-dask]
[--local-cluster]``
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

TARGET_S = 10.0
#: Dask's wall-clock over joblib's, at most.
DASK_RATIO = 1.25


def _stage_times(values, settle, duration, sample):
    """Mean per-point time of each stage over ``sample`` points (serial).

    Returns wall-clock and CPU time (``time.process_time``) of each stage: on a shared
    machine the wall-clock includes waiting for a core, the CPU time does not.
    """
    from vidiscover import preset
    from vidiscover.analysis import analyze
    from vidiscover.effects import Effects
    from vidiscover.regimes.features import ALL_FEATURES
    from vidiscover.regimes.labels import label_simulation
    from vidiscover.sensors import SensorConfig, record
    from vidiscover.simulation import simulate
    from vidiscover.workflows import known_pulse

    def now():
        return time.perf_counter(), time.process_time()

    stages = {"simulate": [], "record": [], "label": [], "analyze": []}
    for b in np.asarray(values)[np.linspace(0, len(values) - 1, sample).astype(int)]:
        t0 = now()
        res = simulate(preset("paper", b=float(b)), settle=settle, duration=duration)
        t1 = now()
        rec, _ = record(res, SensorConfig(), seed=0)
        t2 = now()
        label_simulation(res)
        t3 = now()
        analyze(rec, n_boot=0, features=ALL_FEATURES, pulse=known_pulse(None, Effects()))
        t4 = now()
        for k, (a, z) in zip(stages, ((t0, t1), (t1, t2), (t2, t3), (t3, t4))):
            stages[k].append((z[0] - a[0], z[1] - a[1]))
    return {k: tuple(float(x) for x in np.mean(v, axis=0)) for k, v in stages.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=1000, help="number of sweep points")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--settle", type=float, default=10.0)
    ap.add_argument("--duration", type=float, default=5.12)
    ap.add_argument("--sample", type=int, default=40, help="points timed stage by stage")
    ap.add_argument("--skip-serial", action="store_true")
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--local-cluster", action="store_true",
                    help="Dask on a distributed.LocalCluster instead of command-line "
                         "scheduler and worker processes")
    ap.add_argument("--no-classify", action="store_true",
                    help="skip the regime classifier (issue 5 times simulate + analyze + "
                         "classify)")
    args = ap.parse_args()

    from vidiscover.sweep import sweep

    values = np.linspace(0.003, 0.03, args.n)
    kw = dict(settle=args.settle, duration=args.duration, seed=0, progress=False)
    if not args.no_classify:
        from vidiscover.regimes.classifier import load_default_model

        kw["classify"] = load_default_model()
    print(f"machine: {platform.platform()}, {os.cpu_count()} cpus, python "
          f"{platform.python_version()}; load average {os.getloadavg()[0]:.2f} (1 min)")
    print(f"sweep: b = 3-30 mm, {args.n} points, settle {args.settle:g} s + record "
          f"{args.duration:g} s each, analyze(n_boot=0)"
          f"{'' if args.no_classify else ' + classify'}; target <= {TARGET_S:g} s on "
          f"{args.workers} cores\n")

    _stage_times(values[:1], args.settle, args.duration, 1)  # imports, first calls
    stages = _stage_times(values, args.settle, args.duration, args.sample)
    total = sum(v[0] for v in stages.values())
    cpu = sum(v[1] for v in stages.values())
    print(f"per point, serial (mean of {args.sample} points across the range), wall-clock "
          "and CPU time:")
    for k, (v, c) in stages.items():
        print(f"  {k:<9} {1e3 * v:7.1f} ms  ({100 * v / total:4.1f} %)   CPU {1e3 * c:7.2f} ms")
    print(f"  {'total':<9} {1e3 * total:7.1f} ms            CPU {1e3 * cpu:7.2f} ms -> "
          f"{args.n} points ideal on {args.workers} cores: {args.n * total / args.workers:.1f} s "
          f"(CPU: {args.n * cpu / args.workers:.1f} s)\n")

    results, times = {}, {}
    if not args.skip_serial:
        t, c = time.perf_counter(), time.process_time()
        results["serial"] = sweep("b", values, n_jobs=1, **kw)
        times["serial"] = (time.perf_counter() - t, 0.0)
        cpu = time.process_time() - c
        print(f"serial: {cpu:.1f} CPU-s for {args.n} points ({1e3 * cpu / args.n:.1f} ms "
              f"CPU per point) -> {cpu / args.workers:.1f} s of work per core on "
              f"{args.workers} idle cores\n")

    t = time.perf_counter()
    results["joblib"] = sweep("b", values, n_jobs=args.workers, **kw)
    times["joblib"] = (time.perf_counter() - t, 0.0)   # pool start is inside

    if not args.skip_dask:
        import distributed

        t = time.perf_counter()
        if args.local_cluster:
            cluster = distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1,
                                               processes=True, host="127.0.0.1",
                                               dashboard_address=None)
        else:
            sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
            from dask_cluster import command_line_cluster

            cluster = command_line_cluster(args.workers)
        with cluster as where, distributed.Client(where) as client:
            start = time.perf_counter() - t
            t = time.perf_counter()
            results["dask"] = sweep("b", values, scheduler=client, **kw)
            times["dask"] = (time.perf_counter() - t, start)
        print("dask: " + ("LocalCluster, " if args.local_cluster else
                          "command-line 'dask scheduler' + 'dask worker' processes, ")
              + f"{args.workers} workers x 1 thread on loopback")

    print(f"{'backend':<8} {'wall (s)':>9} {'start (s)':>10} {'per point':>10} "
          f"{'vs target':>10}")
    for name, (wall, start) in times.items():
        print(f"{name:<8} {wall:9.1f} {start:10.1f} {1e3 * wall / args.n:8.1f}ms "
              f"{wall / TARGET_S:9.2f}x")
    wall_jl = times["joblib"][0] * 1000.0 / args.n
    print(f"1000 points on joblib: {wall_jl:.1f} s vs target {TARGET_S:g} s -> "
          f"{'MET' if wall_jl <= TARGET_S else 'MISSED'}")
    if "dask" in times:
        ratio = times["dask"][0] / times["joblib"][0]
        print(f"dask / joblib: {ratio:.2f} vs target <= {DASK_RATIO:g} -> "
              f"{'MET' if ratio <= DASK_RATIO else 'MISSED'}")
    if "serial" in times:
        for name in ("joblib", "dask"):
            if name in times:
                print(f"speed-up {name} vs serial: {times['serial'][0] / times[name][0]:.2f}x")
    ref_name = next(iter(results))
    for name, df in results.items():
        if name == ref_name:
            continue
        try:
            pd.testing.assert_frame_equal(df, results[ref_name], check_exact=True)
            same = "identical"
        except AssertionError as err:
            same = f"DIFFERENT: {str(err).splitlines()[0]}"
        print(f"rows {name} vs {ref_name}: {same}")
    labels = results[ref_name]["label"].value_counts()
    print("labels: " + ", ".join(f"{k} {v}" for k, v in labels.items()))
    if "label_pred" in results[ref_name] and results[ref_name]["label_pred"].notna().any():
        df = results[ref_name]
        agree = (df["label"] == df["label_pred"]).mean()
        print(f"classifier agrees with the true label on {agree:.1%}"
              " of the points")
    print(f"load average at the end: {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main()
