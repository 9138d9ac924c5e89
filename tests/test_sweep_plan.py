"""Planning a sweep (SweepSpec) in the parent process: the simulator's own checks, and
none of the heavy imports a worker needs (scipy.integrate/optimize, numba)."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from vidiscover.errors import InputError
from vidiscover.sweep import SweepSpec


@pytest.mark.parametrize(("settle", "duration", "message"), [
    (-1.0, 5.0, "settle must be >= 0 s"), (math.nan, 5.0, "settle must be >= 0 s"),
    (1.0, 0.0, "duration must be > 0 s"), (1.0, math.inf, "duration must be > 0 s")])
def test_times_are_checked_by_the_simulator_options(settle, duration, message):
    with pytest.raises(InputError, match=message):
        SweepSpec("b", (0.005,), settle=settle, duration=duration)


def test_planning_a_sweep_loads_no_heavy_simulator_import():
    code = ("import sys; from vidiscover.sweep import SweepSpec; "
            "SweepSpec('b', (0.005, 0.01)); SweepSpec('mu', (0.1,)); SweepSpec('noise', (2.0,)); "
            "print(sorted({'scipy.integrate', 'scipy.optimize', 'numba',"
            " 'vidiscover.simulation.compliant'} & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"
