"""CLI start-up time: `vidiscover --help` vs the 0.5 s target (DESIGN.md section 8).

Prints, side by side in one run, the start-up of `vidiscover --help`, of a bare
`python -c pass` and of `python -c "import numpy, scipy.optimize"` for reference.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time


def _time(cmd: list[str], runs: int) -> list[float]:
    out = []
    for _ in range(runs):
        t = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        out.append(time.perf_counter() - t)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    exe = shutil.which("vidiscover") or os.path.join(os.path.dirname(sys.executable),
                                                     "vidiscover")
    cases = {
        "python -c pass": [sys.executable, "-c", "pass"],
        "import numpy, scipy.optimize": [sys.executable, "-c", "import numpy, scipy.optimize"],
        "vidiscover --help": [exe, "--help"],
    }
    print(f"machine: {platform.platform()}, {os.cpu_count()} cpus, python "
          f"{platform.python_version()}; {args.runs} runs each (median, best)")
    res = {k: _time(v, args.runs) for k, v in cases.items()}
    for k, v in res.items():
        med, best = statistics.median(v) * 1e3, min(v) * 1e3
        print(f"  {k:32s} median {med:7.1f} ms   best {best:7.1f} ms")
    help_t = statistics.median(res["vidiscover --help"])
    print(f"vidiscover --help: {help_t:.3f} s vs target 0.5 s -> "
          f"{'OK' if help_t <= 0.5 else 'MISSED'} (ratio {help_t / 0.5:.2f} of the budget)")


if __name__ == "__main__":
    main()
