"""The discover command's own process makes OpenBLAS's idle threads sleep soon.

With more busy processes than cores (analysts, law workers), OpenBLAS threads spinning
for ~0.1 s after each threaded call took the cores from the work (discover on three
recordings: 5.9 -> 5.3 s of CPU); the setting only acts if made before numpy loads.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from vidiscover._workers import BLAS_SPIN_LOG2_CYCLES, short_blas_spin

_RUN = """
import os, sys
from pathlib import Path
import vidiscover.cli as cli
from vidiscover.commands.discover import run_discover
from vidiscover.errors import InputError
cli._OWN_PROCESS[0] = {own}
assert "numpy" not in sys.modules
try:
    run_discover([Path("none.csv")], Path("out"), mu=-1.0)
except InputError:
    pass
assert "numpy" in sys.modules
print(os.environ.get("OPENBLAS_THREAD_TIMEOUT"))
"""


def _timeout_seen(tmp_path, own: bool, env_value: str | None) -> str:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_THREAD_TIMEOUT"}
    if env_value is not None:
        env["OPENBLAS_THREAD_TIMEOUT"] = env_value
    out = subprocess.run([sys.executable, "-c", _RUN.format(own=own)], cwd=tmp_path,
                         env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip()


@pytest.mark.parametrize(("own", "preset", "seen"), [
    (True, None, str(BLAS_SPIN_LOG2_CYCLES)),   # set before numpy loads
    (True, "28", "28"),                         # the user's setting is kept
    (False, None, "None"),                      # library callers: environment untouched
])
def test_discover_command_sets_the_blas_spin_before_numpy_loads(tmp_path, own, preset, seen):
    assert _timeout_seen(tmp_path, own, preset) == seen


def test_short_blas_spin_does_nothing_once_numpy_is_loaded(monkeypatch):
    import numpy  # noqa: F401

    monkeypatch.delenv("OPENBLAS_THREAD_TIMEOUT", raising=False)
    assert short_blas_spin() is False
    assert "OPENBLAS_THREAD_TIMEOUT" not in os.environ
