"""Command and in-process times vs DESIGN.md section 8 (issue 13), side by side in one run.

Prints, each with its target and ``MET`` / ``MISSED`` (median and best of ``--runs``):

* ``vidiscover --help`` start-up (target <= 0.2 s), beside a bare ``python -c pass``
  and ``import numpy, scipy.optimize`` for reference;
* ``analyze`` in-process, no figures, on one 5.12 s recording of the paper rig (b = 9
  mm, our default sensors), with the pulse response known (``pulse=PulseModel()``,
  target <= 6 ms; median and best of at least 30 calls after 3 warm-up calls, see
  :data:`KNOWN_WARM`) and, for information, learned from the recording (the default
  for a recording of unknown instrument; no target);
* ``vidiscover gap REC --no-figures`` as a CLI process on one 5.12 s recording
  (target <= 5 s), with its default worker processes (all cores);
* ``vidiscover discover R1 R2 R3 --no-figures`` as a CLI process on three 5.12 s
  recordings at b = 6, 7.5, 9 mm (target <= 3 s).

The recordings are written once into a temporary folder first (not timed). Timings
depend on the machine's load: the load average is printed; quote figures from an idle
machine only. Each row also gives the median CPU time (user + system, worker processes
included), which a busy machine changes much less: compare versions by it there.

Usage: ``python benchmarks/bench_cli.py [--runs 5]``
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGETS = {"help": 0.2, "analyze_known": 6e-3, "gap": 5.0, "discover": 3.0}


def _children_cpu() -> float:
    """User + system CPU (s) of the finished child processes (and theirs)."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


class _Times(list):
    """Wall times (s) of runs, with their CPU times (user + system) in ``cpu``."""

    cpu: list[float] = []


def _time(cmd: list[str], runs: int, cwd: Path | None = None) -> _Times:
    """Wall and CPU times of ``runs`` runs (CPU of the process and its workers)."""
    out, cpu = _Times(), []
    for _ in range(runs):
        c = _children_cpu()
        t = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, cwd=cwd)
        out.append(time.perf_counter() - t)
        cpu.append(_children_cpu() - c)
    out.cpu = cpu
    return out


def _row(name: str, times: list[float], target: float | None, unit: str = "s") -> str:
    scale = 1e3 if unit == "ms" else 1.0
    med, best = statistics.median(times), min(times)
    line = f"  {name:44s} median {med * scale:8.2f} {unit}   best {best * scale:8.2f} {unit}"
    if target is not None:
        line += (f"   target <= {target * scale:g} {unit}: "
                 f"{'MET' if med <= target else 'MISSED'}")
    cpu = getattr(times, "cpu", None)
    if cpu:
        line += f"   (CPU median {statistics.median(cpu) * scale:.2f} {unit})"
    return line


def _write_recordings(folder: Path) -> None:
    code = (
        "import sys\n"
        "from vidiscover.params import preset\n"
        "from vidiscover.io import write_recording\n"
        "from vidiscover.workflows import simulate_to_memory\n"
        "for b in (0.006, 0.0075, 0.009):\n"
        "    rec, truth, _ = simulate_to_memory(preset('paper', b=b), seed=1, label=False)\n"
        "    write_recording(rec, f'b{b * 1e4:.0f}.csv')\n")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=folder)


#: In-process analyses of the pulse-known case: warm-up calls, then at least this many
#: timed (a 6 ms call: the first few after the imports run 10-20 % slower while the
#: CPU's caches and clock settle, which a 5-run median still shows).
KNOWN_WARM, KNOWN_RUNS = 3, 30


def _in_process(runs: int) -> dict[str, _Times]:
    from vidiscover.analysis import PulseModel, analyze
    from vidiscover.params import preset
    from vidiscover.workflows import simulate_to_memory

    rec, _, _ = simulate_to_memory(preset("paper", b=0.009), seed=1, label=False)
    out = {"known": _Times(), "learned": _Times()}
    for key, kw in (("known", {"pulse": PulseModel()}), ("learned", {})):
        known = key == "known"
        for _ in range(KNOWN_WARM if known else 1):
            analyze(rec, n_boot=0, **kw)             # imports, caches
        cpu = []
        for _ in range(max(runs, KNOWN_RUNS) if known else runs):
            c = time.process_time()
            t = time.perf_counter()
            analyze(rec, n_boot=0, **kw)
            out[key].append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
        out[key].cpu = cpu
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    exe = shutil.which("vidiscover") or os.path.join(os.path.dirname(sys.executable),
                                                     "vidiscover")
    print(f"machine: {platform.platform()}, {os.cpu_count()} cpus, python "
          f"{platform.python_version()}; load average {os.getloadavg()[0]:.2f}; "
          f"{args.runs} runs each")
    start = {
        "python -c pass": [sys.executable, "-c", "pass"],
        "import numpy, scipy.optimize": [sys.executable, "-c", "import numpy, scipy.optimize"],
        "vidiscover --help": [exe, "--help"],
    }
    print("start-up")
    for name, cmd in start.items():
        print(_row(name, _time(cmd, args.runs), TARGETS["help"] if "help" in name else None))
    print("analyze in-process, no figures, one 5.12 s recording")
    ana = _in_process(args.runs)
    print(_row(f"pulse known, {len(ana['known'])} calls", ana["known"],
               TARGETS["analyze_known"], "ms"))
    print(_row("pulse learned from the recording (default)", ana["learned"], None, "ms"))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        _write_recordings(folder)
        recs = ["b60.csv", "b75.csv", "b90.csv"]
        print("CLI processes (start-up, reading, work and writing included)")
        gap = _time([exe, "gap", "b90.csv", "--out", "gap_out", "--no-figures"],
                    args.runs, folder)
        print(_row("vidiscover gap (one recording)", gap, TARGETS["gap"]))
        disc = _time([exe, "discover", *recs, "--out", "disc_out", "--no-figures"],
                     args.runs, folder)
        print(_row("vidiscover discover (three recordings)", disc, TARGETS["discover"]))
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
