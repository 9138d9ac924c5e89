"""The sensor model's kept intermediates give the records they would give afresh.

``record`` keeps the spectra of the general path's polyphase taps
(``sensors._TAPS_SPECTRA``) and threadpoolctl's view of the thread pools; a record made
with them must equal, to the bit, one made with none kept.
"""

from __future__ import annotations

import numpy as np

from vidiscover import preset
from vidiscover.effects import Effects
from vidiscover.sensors import _TAPS_SPECTRA, SensorConfig, record
from vidiscover.simulation import simulate


def _arrays(rec, truth):
    return [rec.t, rec.x, rec.a, rec.xe, truth.motion.x, truth.motion.y]


def test_kept_taps_spectra_give_the_fresh_records():
    res = simulate(preset("paper", b=0.006), Effects.parse(["contact_duration"]), settle=2.0,
                   duration=1.0)
    chains = [SensorConfig(mount_resonance=2500.0),
              SensorConfig(mount_resonance=1800.0, sample_rate=5000.0, kernel_halfwidth=16),
              SensorConfig(mount_resonance=2500.0, oversample=8)]
    fresh = []
    for cfg in chains:
        _TAPS_SPECTRA.clear()
        fresh.append(_arrays(*record(res, cfg, seed=3)))
    _TAPS_SPECTRA.clear()
    for _ in range(2):                      # the second round takes every spectrum kept
        for cfg, want in zip(chains, fresh, strict=True):
            got = _arrays(*record(res, cfg, seed=3))
            for a, b in zip(got, want, strict=True):
                assert a.tobytes() == b.tobytes()
    assert len(_TAPS_SPECTRA) == len(chains)
    assert all(not spec.flags.writeable and np.iscomplexobj(spec) for _, spec in _TAPS_SPECTRA)
