"""Helpers of the discover pipeline's speed-ups that must not change the caller's process."""

from __future__ import annotations

import gc

import pytest

from vidiscover._workers import gc_paused as _gc_paused


@pytest.mark.parametrize("enabled", [True, False])
def test_gc_paused_turns_the_collector_off_and_restores_its_state(enabled):
    was = gc.isenabled()
    try:
        (gc.enable if enabled else gc.disable)()
        with _gc_paused():
            assert not gc.isenabled()
        assert gc.isenabled() is enabled
        with pytest.raises(RuntimeError), _gc_paused():
            raise RuntimeError("an import failed")
        assert gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()


def test_fitting_imports_leave_no_first_call_lookup_to_the_law_fits():
    """After ``_fitting_imports`` a fit no longer scans the installed distributions.

    scikit-learn's input check looks up dataframe plugins (``entry_points``) on its
    first call in a process; the warm-up pays that once before the law workers fork.
    Run in a fresh interpreter: this test process may have fitted already.
    """
    import subprocess
    import sys

    code = (
        "import cProfile, pstats, io\n"
        "import numpy as np\n"
        "from vidiscover.discovery.pipeline import _fitting_imports\n"
        "from vidiscover.discovery.sparse import library_matrix, threshold_sweep\n"
        "_fitting_imports()\n"
        "x = np.linspace(0.2, 1.0, 12)\n"
        "pr = cProfile.Profile(); pr.enable()\n"
        "X = library_matrix(x, ('v', 'v^3'), {'v': lambda v: v, 'v^3': lambda v: v ** 3})\n"
        "threshold_sweep(X, 1 - 0.2 * x, (0.01, 0.1), sr3_thresholds=(0.01,))\n"
        "pr.disable()\n"
        "st = pstats.Stats(pr, stream=io.StringIO())\n"
        "print(sum(1 for f in st.stats if f[2] in ('entry_points', '_discover_entrypoints')))\n")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True)
    assert out.stdout.split()[-1] == "0"
