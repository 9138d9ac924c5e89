"""``discover``'s workers: imports loaded before the fork, the law workers' priority.

An import left to the first analysis is paid again in every forked analyst, on cores
the other analyses need (scipy.ndimage, about 35 ms of CPU in each of three).
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from vidiscover import Effects, preset, record, simulate
from vidiscover._workers import can_fork
from vidiscover.io import write_recording

_RUN = """
import sys
from vidiscover.io import read_recording
from vidiscover.discovery.pipeline import _analysis_imports, _analysis_task
rec = read_recording(sys.argv[1])
_analysis_imports()
before = set(sys.modules)
_analysis_task((rec, 0.0, None, None))
print(" ".join(sorted(set(sys.modules) - before)))
"""


def test_an_analysis_imports_nothing_after_the_analysis_imports(tmp_path):
    sim = simulate(preset("paper", b=0.0075),
                   Effects.parse(["velocity_dependent_restitution=right=linear:0.95:0.12,"
                                  "left=power:0.9:0.2"]), settle=5.0, duration=2.0)
    rec, truth = record(sim, seed=1)
    path = tmp_path / "rec.csv"
    write_recording(rec, path, truth=truth)
    out = subprocess.run([sys.executable, "-c", _RUN, str(path)], capture_output=True,
                         text=True, check=True)
    assert out.stdout.split() == []


@pytest.mark.skipif(not can_fork(), reason="workers are forked on Linux only")
def test_law_workers_run_below_this_process_and_analysts_do_not():
    import os

    from vidiscover.discovery.pipeline import LAW_WORKER_NICE, _workers_for

    here = os.nice(0)
    for fitting, added in ((True, LAW_WORKER_NICE), (False, 0)):
        with _workers_for(2, 2, fitting=fitting) as run:
            assert run.forked
            run.ready[0].result()
            seen = run.submit(os.nice, 0).result()
        assert seen == min(here + added, 19)
