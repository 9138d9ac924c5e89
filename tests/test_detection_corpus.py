"""Impact detection on failure classes of the realism corpus's tuning splits (issue 10).

Scored as ``benchmarks/bench_realism.py``: the detectable true contact episodes
(:func:`vidiscover.analysis.detectable` with the case's true anti-alias peak and
the contact impulses of :func:`vidiscover.analysis.contact_dv`), matches on the same
wall within 0.5 ms of the contact entry; the analysis learns the instrument.
"""

from __future__ import annotations

import numpy as np
from corpus_scoring import episodes


def test_periodic_re_impacts_are_not_taken_for_the_instrument_s_ringing():
    """Kelvin-Voigt walls behind a Chebyshev-1 filter at 2560 Hz (test-050): every
    impact is followed 6.75 ms (17 samples) later by a re-impact on its wall at 0.28 of
    its impulse. Every learning window held one; the learned error envelope read it as
    ringing (0.2 of the peak at lags 15-19) and the detector dropped all 80 re-impacts
    (80 of 160 found). The re-impacts are now taken out of the learning windows as
    copies of the response: 159 of 160 found, none false."""
    imp, ok, det, ie, it = episodes("test", 50)
    assert ok.sum() == 160
    assert ok[it].sum() >= 158                                # measured 159, was 80
    assert ie.size == det.n                                   # none false
    assert det.response.error_at(np.arange(15.0, 20.0)).max() < 0.03   # was 0.2


def test_a_coarse_adc_s_smooth_troughs_are_not_clipped_pulses():
    """Hunt-Crossley walls behind a Butterworth-6 filter at 10240 Hz and a 12-bit ADC
    (test-056, step 0.24 m/s^2 above the 0.07 noise): the forced response's troughs
    hold the record's minimum (-477.8 m/s^2; the rail is 490.3) for 1-3 samples each.
    Read as clipped pulses they gave 4 false impacts (SNR 6-38) 6.5-6.7 ms before right
    impacts (84 for 80). Within 1.3 noise sigmas of the smooth part, they are no clip;
    the 2-sample clipped tops of the strong pulses (1050 sigmas above it) still are."""
    imp, ok, det, ie, it = episodes("test", 56)
    assert ok.sum() == 80 and ok[it].all()
    assert det.n == ie.size == 80                             # was 84, 4 false
    assert 0 < det.n_clipped < 98                             # was 98 (71 trough runs)


def test_a_long_hunt_crossley_contact_behind_a_butterworth_filter_is_one_impact():
    """Hunt-Crossley walls behind a causal Butterworth-5 filter at 12.8 kHz (dev-072):
    the weak impacts' contacts last 11 samples, the strong ones' (which the response
    is learned from) 9; the learned pulse fitted to a long contact left a residual of
    up to 24 noise sigmas that later rounds took for a second impact 3-5 samples after
    the first (185 detections for 175 episodes, 11 false). A longer-contact variant of
    the learned pulse is now fitted where it explains that residual: one impact per
    contact, the entries 87 us from the truth instead of 187.

    The compliant engine's trajectory depends on the CPU's last bits (libm): 175
    detectable episodes on one x86_64 machine, 173 on another (found 174 and 173, 87
    and 88 us); the bounds hold on both."""
    imp, ok, det, ie, it = episodes("dev", 72)
    assert ok.sum() >= 170
    assert ok[it].sum() >= ok.sum() - 2                       # measured all but 1 / 0
    assert det.n - ie.size <= 1                               # measured 0 false, was 11
    assert np.median(np.abs(det.t[ie] - imp.t_in[it])) < 110e-6   # measured 87-88 us, was 187


def test_a_wall_with_few_strong_pulses_gets_its_own_contact_duration():
    """Hunt-Crossley walls behind a Bessel-4 filter at 2560 Hz (dev-033): at the SNR
    level where learning stopped (28), 2 of the 12 isolated pulses were the soft right
    wall's, too few for its own contact duration; it took the left wall's tau 0 and its
    2-sample contacts were timed 0.87 sample late (median 278 us over both walls). The
    next level (SNR 20) is now tried for it: 18 right pulses of 40, tau 1.9 samples.

    The compliant engine's trajectory depends on the CPU's last bits (libm): on a second
    x86_64 machine the record holds 125 detectable episodes, not 134, all found, none
    false, tau 1.94 samples, median 134 us (70 us on the first); the fault gave 278."""
    imp, ok, det, ie, it = episodes("dev", 33)
    fs = det.sample_rate
    assert det.response.model.tau * fs > 1.0                  # measured 1.9, was 0
    assert ok[it].sum() >= ok.sum() - 3                       # measured 132 of 134; 125 of 125
    assert ie.size == det.n                                   # none false
    assert np.median(np.abs(det.t[ie] - imp.t_in[it])) < 150e-6   # measured 70 / 134 us, was 278
