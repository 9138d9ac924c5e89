"""Cached gap diagnoses shared by tests/test_gap.py and tests/features/test_gap.py.

Each diagnosis costs seconds of simulation, so every case is computed once per test
session.
"""

from __future__ import annotations

import functools


@functools.cache
def quick_battery():
    """``vidiscover gap-check --quick --json`` (2 workers), parsed."""
    import json

    from click.testing import CliRunner

    from vidiscover.cli import main

    res = CliRunner().invoke(main, ["gap-check", "--quick", "--json", "--n-jobs", "2"])
    assert res.exit_code == 0, res.output
    return json.loads(res.output)


@functools.cache
def recording(b: float, effects: tuple = (), seed: int = 3):
    """A simulated recording with its truth (paper preset, r = 0.7)."""
    from vidiscover import Effects, preset
    from vidiscover.gap.battery import BASE_R
    from vidiscover.workflows import simulate_to_memory

    rec, truth, _ = simulate_to_memory(preset("paper", b=b, r=BASE_R),
                                       Effects.parse(list(effects)), seed=seed)
    return rec, truth
