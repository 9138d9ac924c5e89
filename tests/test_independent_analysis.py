"""Stage 1-3 on recordings of an independent simulator (``tests/data/independent``).

Compliant walls, smooth friction, causal anti-alias filters that our sensor model did
not make, integrated by code that shares nothing with vidiscover. The analysis learns
the pulse response from each recording (no instrument is given).

Criteria
--------
* *Detectable* contact episodes (one criterion, :func:`vidiscover.analysis.detectable`):
  peak SNR ``|dv| k0 / sigma_a >= 8`` with ``k0`` the peak of the recording's true
  anti-alias response (the ``setup`` filter, as a :class:`PulseModel`) and no stronger
  episode within two samples. Every episode of these ten cases is detectable.
* Matching: same wall, within 0.5 ms of the true contact entry ``t_in``; the timing
  error is ``t_est - t_in`` (the detector reports the contact entry: the fitted pulse
  time less the learned delay from entry to peak).
* r per wall: RMS of the estimated r over the impacts the restitution stage used, against
  the RMS of the true ``r = -v_out / v_in`` over every contact on that wall. Friction and
  tilt are given to the analysis as the flight law (their identification is the flight-law
  stage's job).

Specification (issue 10): count within 3 %, precision and recall >= 0.98, median timing
error <= 50 us, no ringing lobe counted, r RMS within 0.03. Regression guards near the
measured values sit beside them (measured: see ``GUARD``).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from independent import CASES, load, true_impacts

from vidiscover.analysis import PulseModel, analyze, contact_dv, detectable, match_impacts
from vidiscover.recording import Recording

#: Measured median |t_est - t_in| (us) per case at the time of writing; the guard allows
#: 1.3x plus 5 us.
MEASURED_TIMING_US = {
    "P01_b8_chatter": 27.8, "P02_b11_huntcrossley": 19.2, "P03_b13_friction": 13.5,
    "P04_pool_b5": 9.4, "P05_pool_b8": 6.0, "P06_pool_b11": 31.2, "P07_otherrig": 26.3,
    "P08_gap_none": 4.9, "P09_gap_tilt": 7.2, "P10_gap_asym": 15.3}
#: Cases whose median timing error misses the 50 us specification. P02 did (65 us, a
#: Bessel-2 with an 89 us contact) while the learner kept Bessel cut-offs below 0.5 fs:
#: its Bessel-4 "2800 Hz" (-3 dB) at 6400 Hz is 0.66 fs phase-normalised; learned now
#: as a Bessel-5 at 0.74 fs (-3 dB 0.46 fs) with a 419 us arch contact, 19 us.
TIMING_MISSES: set[str] = set()


@functools.cache
def analysed(name: str):
    rec, key = load(name)
    s = key["setup"]
    out = analyze(rec, flight_law=(s["mu"], s["theta_deg"]), n_boot=20)
    return out, key


def _scores(name: str):
    out, key = analysed(name)
    s = key["setup"]
    det = out.detection
    tr = true_impacts(key)
    dv = contact_dv([i["v_in"] for i in key["impacts"]], [i["v_out"] for i in key["impacts"]],
                    float(s["m1"]), float(s["m2"]))
    fs = float(s["fs"])
    truth_filter = PulseModel(cutoff=s["aa_hz"] / fs, kind=s["aa_kind"], order=s["aa_order"])
    ok = detectable(tr["t_in"], dv, s["noise_a"], fs, cutoff=truth_filter.peak(fs) / (2 * fs))
    side = np.where(det.side == "right", 1, -1)
    ie, it = [], []
    for sgn in (1, -1):
        ke, kt = np.flatnonzero(side == sgn), np.flatnonzero(tr["side"] == sgn)
        e, t = match_impacts(det.t[ke], tr["t_in"][kt], 0.5e-3)
        ie.append(ke[e])
        it.append(kt[t])
    ie, it = np.concatenate(ie), np.concatenate(it)
    return out, key, tr, ok, ie, it


@pytest.mark.parametrize("name", CASES)
def test_one_impact_per_contact_episode(name):
    out, key, tr, ok, ie, it = _scores(name)
    det = out.detection
    assert ok.all()                                   # every episode is detectable here
    assert abs(det.n - ok.sum()) <= 0.03 * ok.sum()   # specification
    assert det.n == ok.sum()                          # measured: exact on all ten
    precision, recall = ie.size / det.n, ok[it].sum() / ok.sum()
    assert precision >= 0.98 and recall >= 0.98
    assert precision == 1.0 and recall == 1.0         # measured
    assert not det.columns["merged"].any()            # no unresolved chatter flagged


@pytest.mark.parametrize("name", CASES)
def test_no_ringing_lobe_is_counted(name):
    """No detection within the learned response's span after a stronger one, unmatched."""
    out, key, tr, ok, ie, it = _scores(name)
    det = out.detection
    span = det.pulse.span(det.sample_rate) / det.sample_rate
    unmatched = np.setdiff1d(np.arange(det.n), ie)
    for i in unmatched:
        before = (det.t < det.t[i]) & (det.t >= det.t[i] - span)
        assert not (np.abs(det.dv[before]) > np.abs(det.dv[i])).any(), det.t[i]
    # and the learned response is a causal filter, as in the recording
    assert det.response is not None and det.pulse.causal


@pytest.mark.parametrize("name", [
    pytest.param(c, marks=pytest.mark.xfail(strict=True, reason="learned delay off by 65 us"))
    if c in TIMING_MISSES else c for c in CASES])
def test_timing_error_against_contact_entry_spec(name):
    out, key, tr, ok, ie, it = _scores(name)
    err = out.detection.t[ie] - tr["t_in"][it]
    assert np.median(np.abs(err)) <= 50e-6


@pytest.mark.parametrize("name", CASES)
def test_timing_error_regression_guard(name):
    out, key, tr, ok, ie, it = _scores(name)
    err = out.detection.t[ie] - tr["t_in"][it]
    assert np.median(np.abs(err)) <= (1.3 * MEASURED_TIMING_US[name] + 5.0) * 1e-6
    # the spread about the bias is small: one delay fits every impact
    assert np.std(err) <= 25e-6


@pytest.mark.parametrize("name", CASES)
def test_restitution_per_wall_matches_the_contacts(name):
    out, key, tr, ok, ie, it = _scores(name)
    c = out.restitution.columns
    checked = 0
    for side, sgn in (("right", 1), ("left", -1)):
        used = c["used"] & (c["side"] == side) & np.isfinite(c["r"])
        if used.sum() < 10:
            continue
        est = np.sqrt(np.mean(c["r"][used] ** 2))
        true = np.sqrt(np.mean(tr["r"][tr["side"] == sgn] ** 2))
        assert abs(est - true) <= 0.03, (side, est, true)      # specification
        assert abs(est - true) <= 0.012, (side, est, true)     # measured <= 0.0096
        checked += 1
    assert checked == 2


@pytest.mark.parametrize("name", CASES)
def test_offsets_of_clean_channels_are_near_zero(name):
    out, key = analysed(name)
    off = out.summary()["offsets"]
    s = key["setup"]
    assert off["n_cycles"] >= 39
    assert abs(off["a_bias"]) <= 0.01                   # measured <= 0.0081 m/s^2
    assert abs(off["xe_offset"]) <= 2e-8
    # the laser's mean is the static deflection of the tilt, m2 g sin(theta) / k1
    static = s["m2"] * 9.81 * np.sin(np.radians(s["theta_deg"])) / s["k1"]
    assert off["x_offset"] == pytest.approx(static, abs=0.1e-6)


def test_offsets_are_estimated_and_removed():
    rec, key = load("P08_gap_none")
    biased = Recording(rec.t, rec.x + 1e-3, rec.a + 0.5, rec.xe - 2e-4, rec.meta, name="biased")
    out = analyze(biased, n_boot=20)
    clean, _ = analysed("P08_gap_none")
    off = out.summary()["offsets"]
    assert off["a_bias"] == pytest.approx(0.5 + clean.offsets.a_bias, abs=1e-9)
    assert off["x_offset"] == pytest.approx(1e-3 + clean.offsets.x_offset, abs=1e-12)
    assert off["xe_offset"] == pytest.approx(-2e-4 + clean.offsets.xe_offset, abs=1e-12)
    r, r0 = out.restitution.columns["r"], clean.restitution.columns["r"]
    assert np.array_equal(np.isnan(r), np.isnan(r0))
    assert np.nanmax(np.abs(r - r0)) < 1e-6
    assert np.abs(out.recording.x - rec.x).max() < 1e-6


def test_summary_carries_the_learned_response():
    out, key = analysed("P07_otherrig")
    pr = out.summary()["pulse_response"]
    assert pr["learned"] and pr["kind"] == "butter" and pr["order"] == 4
    assert pr["cutoff_hz"] == pytest.approx(2500, rel=0.05)
    assert 150e-6 < pr["delay"] < 300e-6
    assert 150e-6 < pr["width"] < 250e-6             # FWHM of the model: 192 us
    assert pr["n_pulses"] >= 20 and pr["misfit"] < 0.05
