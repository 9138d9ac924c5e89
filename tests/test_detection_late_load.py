"""A resting load that sets in late on a compliant wall is not counted as an impact."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from vidiscover import Metadata, Recording
from vidiscover.analysis import detect_impacts, match_impacts


def _late_load(delay, seed=5, fs=5120.0, os=16, periods=20, m1=6.69, m2=0.0567):
    """Per 228-sample period: a fast left contact, a slow one 17.5 samples later after
    which the ball rests on the left wall (its load ``-m2 / (m1 + m2) a`` sets in
    ``delay`` samples after the slow entry, with the overshoot of a Kelvin-Voigt wall
    of damping ratio 0.45 at 768 Hz, until the acceleration changes sign), then a right
    impact; through a 3rd-order Butterworth at 1425 Hz (holdout5-039's instrument)."""
    fo = fs * os
    rng = np.random.default_rng(seed)
    per = 228.0 / fs
    to = np.arange(int((periods + 0.5) * per * fo)) / fo
    a = 260.0 * np.sin(2 * np.pi * (to + 1.0 / fs) / per)
    z, w0 = 0.453, 2 * np.pi * 768.0
    wd = w0 * np.sqrt(1 - z * z)
    t_in = []
    for k in range(periods):
        t0 = k * per
        for t, area, dur in ((t0 + 18.2 / fs, -0.011, 0.54e-3), (t0 + 35.7 / fs, -0.0038, 0.8e-3),
                             (t0 + 179.9 / fs, 0.038, 0.3e-3)):
            i, m = int(np.ceil(t * fo)), int(round(dur * fo))
            a[i:i + m] += area * np.pi / (2 * dur) * np.sin(
                np.pi * (np.arange(i, i + m) / fo - t) / dur)
            t_in.append(t)
        t1 = t0 + (35.7 + delay) / fs
        on = (to >= t1) & (to < t0 + 113.0 / fs)
        tt = to[on] - t1
        settle = 1 - np.exp(-z * w0 * tt) * (np.cos(wd * tt) + z / np.sqrt(1 - z * z)
                                             * np.sin(wd * tt))
        a[on] -= m2 / (m1 + m2) * a[on] * settle
    sos = signal.butter(3, 1425.0, fs=fo, output="sos")
    af = signal.sosfilt(sos, a, zi=signal.sosfilt_zi(sos) * a[0])[0][::os]
    af += 0.075 * rng.standard_normal(af.size)
    t = np.arange(af.size) / fs
    rec = Recording(t, np.zeros_like(t), af, np.zeros_like(t),
                    Metadata(b=0.009, sample_rate=fs, m1=m1, m2=m2))
    return rec, np.array(t_in)


def test_a_late_resting_load_on_a_soft_wall_is_not_an_impact():
    # holdout5-039: a soft Kelvin-Voigt wall lets the slow contact's force drop to zero
    # before the ball settles; the resting load comes back ~1 ms (5 samples) later and
    # its front was fitted as a weak pulse in every period (20 of 20 here, 40 of 120
    # there). The run's trailing weak pulse is now tried as the load's late step
    rec, t_in = _late_load(5.0)
    det = detect_impacts(rec)
    ie, _ = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size == 60
    assert det.n - ie.size == 0                               # was 20


@pytest.mark.parametrize("seed, was", [(5, 5), (6, 10)])
def test_a_late_load_rising_through_the_wall_is_not_an_impact(seed, was):
    # the load sets in 6 samples after the slow entry and rises with the wall's
    # overshoot (a Kelvin-Voigt wall of damping ratio 0.45): the instantaneous step did
    # not explain its front, left as weak pulses (5 and 10 of 20 periods). The step is
    # now also tried as the step response of the wall's oscillator (its learned contact
    # duration lasts over 2 samples): one extra left in each
    rec, t_in = _late_load(6.0, seed=seed)
    det = detect_impacts(rec)
    ie, _ = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size == 60
    assert det.n - ie.size <= 1 < was


@pytest.mark.slow
def test_a_chatter_run_ending_in_a_rest_on_a_soft_wall_counts_its_impacts():
    # holdout7-000 (spent): Kelvin-Voigt walls; each period's right chatter run ends in a
    # slow entry (0.07 m/s) and an 18 ms rest, whose load comes back about 1 ms later
    # with an overshoot at 0.17-0.23 of the entry's pulse; that lobe was counted in 17
    # of 37 periods (217 detections for 200 impacts). Now 203: within 3 %, none missed
    from vidiscover.analysis import analyze
    from vidiscover.analysis.validation import match_impacts_by_wall
    from vidiscover.corpus import realism_case

    case = realism_case("holdout7", 0)
    sim = case.simulate()
    det = analyze(sim.recording, flight_law=(case.mu, case.theta), n_boot=0).detection
    imp = sim.truth.impacts
    ie, _ = match_impacts_by_wall(det.t, det.side, imp.t_in, imp.side)
    assert imp.t_in.size == len(ie) == 200
    assert det.n - 200 <= 3                                   # was 17
