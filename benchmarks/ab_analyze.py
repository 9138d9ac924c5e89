"""Interleaved A/B timing of ``analyze`` between two versions of the package.

Two worker processes, one per version (``PYTHONPATH`` A and B), each analyze the
paper rig's 5.12 s recording (``bench_cli.py``'s: ``preset('paper', b=0.009)``, seed
1, ``pulse=PulseModel()``, ``n_boot=0``, no figures) when told; the runs alternate
A B A B ... after a warm-up, so that both see the same load. Prints per version the
median and best wall-clock time and the median and best CPU time (ms), the ratio
B/A of the medians, and the load average before and after.

Usage::

    python benchmarks/ab_analyze.py PATH_A PATH_B [--pairs 30] [--table2]

``--table2``: ``bench_analyze.py``'s recording (the paper's Table-2 walls) instead.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import numpy as np

WORKER = r"""
import sys, time
import vidiscover
from vidiscover.analysis import PulseModel, analyze
from vidiscover.params import preset
if sys.argv[1] == "table2":
    from vidiscover import Effects, SensorConfig, record, simulate
    res = simulate(preset("paper", b=0.009),
                   Effects.parse(["asymmetric_restitution=0.88,0.20"]), settle=10.0,
                   duration=5.12)
    rec, _ = record(res, SensorConfig(), seed=1)
else:
    from vidiscover.workflows import simulate_to_memory
    rec, _, _ = simulate_to_memory(preset("paper", b=0.009), seed=1, label=False)
pm = PulseModel()
for _ in range(5):
    analyze(rec, n_boot=0, pulse=pm)
print("ready", vidiscover.__file__, flush=True)
for line in sys.stdin:
    c, t = time.process_time(), time.perf_counter()
    analyze(rec, n_boot=0, pulse=pm)
    print(time.perf_counter() - t, time.process_time() - c, flush=True)
"""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("a")
    p.add_argument("b")
    p.add_argument("--pairs", type=int, default=30)
    p.add_argument("--table2", action="store_true")
    a = p.parse_args(argv)
    procs = []
    for path in (a.a, a.b):
        env = dict(os.environ, PYTHONPATH=path)
        # (run in the version's own directory: ``python -c`` puts the working
        # directory first on the path, before PYTHONPATH)
        procs.append(subprocess.Popen([sys.executable, "-c", WORKER,
                                       "table2" if a.table2 else "bench_cli"],
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                      text=True, env=env, cwd=path))
    for pr, path in zip(procs, (a.a, a.b)):
        ready, where = pr.stdout.readline().split()
        assert ready == "ready" and os.path.realpath(where).startswith(
            os.path.realpath(path)), (where, path)
        print(f"{path}: {where}")
    load0 = os.getloadavg()
    wall = [[], []]
    cpu = [[], []]
    for i in range(2 * a.pairs):
        k = i % 2
        procs[k].stdin.write("go\n")
        procs[k].stdin.flush()
        w, c = map(float, procs[k].stdout.readline().split())
        wall[k].append(w)
        cpu[k].append(c)
    for pr in procs:
        pr.stdin.close()
        pr.wait()
    for k, name in enumerate(("A", "B")):
        print(f"{name} {(a.a, a.b)[k]}: wall median {1e3 * np.median(wall[k]):.2f} ms, best "
              f"{1e3 * min(wall[k]):.2f}; CPU median {1e3 * np.median(cpu[k]):.2f}, best "
              f"{1e3 * min(cpu[k]):.2f}")
    print(f"B/A: wall median {np.median(wall[1]) / np.median(wall[0]):.3f}, CPU median "
          f"{np.median(cpu[1]) / np.median(cpu[0]):.3f}; {a.pairs} pairs; load average "
          f"before {load0[0]:.2f} after {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
