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
