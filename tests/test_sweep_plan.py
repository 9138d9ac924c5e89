"""Planning a sweep (SweepSpec) in the parent process: same checks, no simulator import."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from vidiscover.errors import InputError
from vidiscover.simulation.engine import SimOptions
from vidiscover.sweep import _check_times

TIMES = [0.0, 1.0, 10.0, 5.12, -1.0, -0.0, 1e-300, math.inf, -math.inf, math.nan, 3, True]


def _verdict(func, settle, duration):
    try:
        func(settle, duration)
    except (InputError, TypeError) as err:
        return type(err).__name__, str(err)
    return None


@pytest.mark.parametrize("settle", TIMES + ["x", None])
def test_times_are_checked_as_the_simulator_checks_them(settle):
    for duration in TIMES + ["x"]:
        want = _verdict(lambda s, d: SimOptions(settle=s, duration=d), settle, duration)
        assert _verdict(_check_times, settle, duration) == want, (settle, duration)


def test_planning_a_sweep_does_not_import_the_simulator():
    code = ("import sys; from vidiscover.sweep import SweepSpec; "
            "SweepSpec('b', (0.005, 0.01)); SweepSpec('mu', (0.1,)); SweepSpec('noise', (2.0,)); "
            "print('vidiscover.simulation' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"
