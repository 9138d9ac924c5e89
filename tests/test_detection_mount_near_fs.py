"""A mounted resonance near the sampling rate: the step test keeps its pulses, quietly.

The learned or given response of such a chain (the classifier's training draws hold
three) has a kernel whose sampled sum is nearly 0, so the filtered unit step (the
cumulated kernel over that sum) is huge and the step test's least squares overflowed
(RuntimeWarnings; no finite score). Such a pulse is kept, not taken for a step.
"""

from __future__ import annotations

import warnings

import numpy as np

from vidiscover import preset
from vidiscover.analysis import detect_impacts
from vidiscover.analysis import impacts as impacts_module
from vidiscover.sensors import SensorConfig
from vidiscover.workflows import known_pulse, simulate_to_memory

FS = 10240.0
SENSORS = SensorConfig(sample_rate=FS, anti_alias="bessel", aa_order=2, aa_cutoff=0.297 * FS,
                       mount_resonance=1.0077 * FS)


def test_step_test_without_finite_score_keeps_the_pulse(monkeypatch):
    rec, _, _ = simulate_to_memory(preset("paper", b=0.006), ["asymmetric_restitution=0.88,0.20"],
                                   seed=1, sensors=SENSORS, label=False)
    pulse = known_pulse(SENSORS)
    fit = impacts_module._Fitter._step_fit
    unscored = []

    def counted(self, *args):
        p, s = fit(self, *args)
        unscored.append(int(np.isinf(p).sum()))
        return p, s

    monkeypatch.setattr(impacts_module._Fitter, "_step_fit", counted)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        det = detect_impacts(rec, pulse=pulse)
    assert sum(unscored) == 3                  # measured: 3 pulses without a finite score
    monkeypatch.setattr(impacts_module, "_STEP_MIN", np.inf)       # no step test at all
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        plain = detect_impacts(rec, pulse=pulse)
    assert det.n == plain.n == 167
    np.testing.assert_allclose(det.t, plain.t, rtol=0, atol=1e-12)
    assert det.warnings == plain.warnings
