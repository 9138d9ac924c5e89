"""Peak memory of reading and analysing a 200 MB CSV recording, vs 3x the file size.

Writes a ~200 MB CSV (the paper rig at b = 9 mm, 6.4 kHz, about 500 s) into a
temporary folder, then measures in fresh child processes (peak resident set size,
``ru_maxrss`` of the child, which includes the interpreter and its libraries):

* ``read_recording`` alone;
* ``vidiscover analyze big.csv --no-figures`` (the whole command: read, analysis,
  friction table, regime features, report);
* ``python -c "import vidiscover.analysis"`` for reference (the libraries alone).

Target (issue 13): the analysis of a 200 MB CSV peaks at <= 3x the file size.

Run: ``python benchmarks/bench_memory.py [--seconds 500]``
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_RATIO = 3.0


def _peak_mb(cmd: list[str], cwd: Path) -> tuple[float, float]:
    """Peak RSS (MB) and wall time (s) of ``cmd`` run as a fresh child process."""
    # ru_maxrss of RUSAGE_CHILDREN is the largest of all children waited for so far:
    # run each measurement through its own intermediate process.
    probe = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
             "subprocess.run(sys.argv[1:], check=True, capture_output=True); "
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, "
             "time.perf_counter() - t)")
    out = subprocess.run([sys.executable, "-c", probe, *cmd], cwd=cwd, check=True,
                         capture_output=True, text=True).stdout.split()
    return float(out[0]) / 1024.0, float(out[1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=500.0,
                    help="record length (s); 500 s gives about 200 MB of CSV")
    args = ap.parse_args()
    load = os.getloadavg()[0]
    print(f"machine: {platform.platform()}, {os.cpu_count()} cpus, python "
          f"{platform.python_version()}, load average {load:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        t = time.perf_counter()
        make = ("import sys; from vidiscover.params import preset; "
                "from vidiscover.workflows import simulate_to_memory; "
                "from vidiscover.io import write_recording; "
                "s = simulate_to_memory(preset('paper', b=0.009), duration=float(sys.argv[1]), "
                "seed=1, label=False); write_recording(s[0], 'big.csv')")
        subprocess.run([sys.executable, "-c", make, str(args.seconds)], cwd=folder, check=True)
        size = (folder / "big.csv").stat().st_size / 1e6
        print(f"big.csv: {size:.0f} MB ({args.seconds:g} s at 6.4 kHz), written in "
              f"{time.perf_counter() - t:.0f} s")
        libs, _ = _peak_mb([sys.executable, "-c", "import vidiscover.analysis"], folder)
        read, t_read = _peak_mb([sys.executable, "-c", "from vidiscover.io import "
                                 "read_recording; read_recording('big.csv')"], folder)
        exe = [sys.executable, "-m", "vidiscover.cli"]
        full, t_full = _peak_mb([*exe, "analyze", "big.csv", "--out", "out",
                                 "--no-figures"], folder)
    budget = TARGET_RATIO * size
    print(f"  libraries alone (import vidiscover.analysis)  {libs:7.0f} MB")
    print(f"  read_recording                                {read:7.0f} MB "
          f"({read / size:.2f}x the file, {t_read:.1f} s)")
    print(f"  vidiscover analyze --no-figures               {full:7.0f} MB "
          f"({full / size:.2f}x the file, {t_full:.1f} s)")
    print(f"analyze peak memory: {full:.0f} MB vs target {budget:.0f} MB "
          f"({TARGET_RATIO:g}x {size:.0f} MB) -> {'OK' if full <= budget else 'MISSED'}")


if __name__ == "__main__":
    main()
