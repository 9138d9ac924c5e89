"""Restitution per wall on the realism corpus's tuning splits (issue 10, must-show 2).

Scored as ``benchmarks/bench_realism.py``: |RMS(r_est) - RMS(r_true)| per wall, the
truth over every true contact of the wall; the analysis learns the instrument and is
given the case's flight law.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from vidiscover.acquisition import shape_centroid
from vidiscover.analysis import PulseModel, analyze
from vidiscover.analysis.reconstruction import _release_durations, contact_durations
from vidiscover.corpus import realism_case


@functools.cache
def _wall_errors(split: str, index: int):
    """(analysis, {side: r error}) of one corpus case."""
    case = realism_case(split, index)
    sim = case.simulate(label=False)
    rec, imp = sim.recording, sim.truth.impacts
    out = analyze(rec, flight_law=(case.mu, case.theta), n_boot=0)
    side_true = np.where(np.asarray(imp.side) == "right", 1, -1)
    err = {}
    for side, sg in (("right", 1), ("left", -1)):
        est = getattr(out.restitution, side)
        r_true = np.asarray(imp.r, dtype=float)[side_true == sg]
        assert est.n >= 10 and r_true.size
        err[side] = float(est.rms - np.sqrt(np.mean(r_true ** 2)))
    return out, err


def test_a_long_skewed_learned_contact_releases_the_ball_at_twice_its_centroid():
    """Kelvin-Voigt walls (contacts 0.12 / 0.17 ms) behind a Bessel-3 filter at 1.7 kHz,
    sampled at 5120 Hz (test-006). The pulses fit a Butterworth-2 filter with a
    front-loaded arch of 1.03 ms (skew 3.6, centroid 0.17 ms) better than the true
    chain: duration and filter trade, the force's centroid is what the pulses fix.
    Released at the learned duration, the ball's outgoing flight started 0.9 ms late
    and r was off by -0.012 / -0.043 (right / left); released at twice the centroid
    (0.33 ms), +0.0043 / -0.0014. Which of the two the learner picks is on a knife
    edge: on another CPU (AMD EPYC, numpy 2.4.6) it learns the true Bessel (skew 0,
    0.24 ms) and r is off by +0.0021 / -0.0007; either way r holds."""
    out, err = _wall_errors("test", 6)
    m = out.detection.response.model_for(-1)
    if m.skew > 3:                                                # the misidentification
        assert m.kind == "butter" and m.tau > 0.9e-3
    assert abs(err["left"]) < 0.004                               # measured 0.0014 / 0.0007
    assert abs(err["right"]) < 0.006                              # measured 0.0043 / 0.0021


def test_a_hunt_crossley_wall_behind_a_bessel_filter_with_a_skewed_contact():
    """Hunt-Crossley walls behind a Bessel filter (test-053): learned a front-loaded
    arch of 0.81 ms (skew 4.5); r was off by -0.0125 / -0.0133 released at its
    duration, +0.0022 / +0.0015 at twice its centroid; +0.0041 / +0.0006 since weak
    impacts may take a longer contact (19ee4db: their entry times move by up to a
    sample)."""
    out, err = _wall_errors("test", 53)
    assert out.detection.response.model.skew > 3
    assert abs(err["right"]) < 0.006 and abs(err["left"]) < 0.004   # measured 0.0041/0.0006


class _Det:
    """The few fields :func:`_release_durations` reads."""

    def __init__(self, right: PulseModel, left: PulseModel):
        self.sign = np.array([1, -1, 1, -1])
        self.pulse = right
        self.response = type("R", (), {"model_for": lambda _, s: right if s > 0 else left})()


@pytest.mark.parametrize("skew", [3.625, -1.0])
def test_release_at_twice_the_centroid_of_an_arch_only(skew):
    """A half-sine and a viscous wall's shape release at ``tau`` (bit for bit the
    contact duration); an arch at twice its centroid; the given pulse of the exact
    engine (no learned response) at its contact duration."""
    half = PulseModel(cutoff=0.3, tau=4e-4, kind="bessel", order=3)
    arch = PulseModel(cutoff=0.3, tau=1e-3, kind="butter", order=2, skew=skew)
    det = _Det(half, arch)
    got = _release_durations(det)
    assert np.array_equal(got[::2], contact_durations(det)[::2])
    assert np.allclose(got[1::2], 2 * shape_centroid(skew) * 1e-3, rtol=0, atol=1e-15)
    viscous = PulseModel(cutoff=0.3, tau=1e-3, kind="butter", order=2, skew=0.37,
                         phase=0.7)
    det = _Det(viscous, viscous)
    assert np.array_equal(_release_durations(det), contact_durations(det))
    det.response = None
    assert np.array_equal(_release_durations(det), contact_durations(det))


def test_a_saturated_laser_does_not_pin_the_lo_to_its_rails():
    """A 10 mm laser on an LO of 10.7 mm RMS (test-033, Kelvin-Voigt walls, Chebyshev-8
    at 10240 Hz): 2 of 3 laser samples sit on its rails. Pinned to them, the integrated
    acceleration was pulled onto the rails: the laser's misfit read 2.7 mm, the right
    wall kept fewer than 10 impacts (the others 'noisy') and the left's r was off by
    -0.023. Left out of the pinning: misfit 0.13 mm, r off by +0.0033 / +0.0024; with
    the partly-kept blocks' means carried to their centres (1b700d3) misfit 1.4 um, r off
    by +0.0005 / +0.0000."""
    out, err = _wall_errors("test", 33)
    assert 0.5 < out.reconstruction.laser_rail_share < 0.8      # 2 of 3 samples on a rail
    assert any("laser 'x' saturated" in w for w in out.warnings)  # and the user is told
    assert out.reconstruction.position_noise < 10e-6            # 1.4 um (0.13 mm, was 2.7)
    assert abs(err["right"]) < 0.002 and abs(err["left"]) < 0.002   # 0.0005 / 0.0000


def test_laser_rails_are_long_runs_at_the_extreme_value_only():
    """A sine clipped at a full scale: the samples on both rails; the same sine
    within range, quantised to 5 um (its crests hold the extreme code a few samples),
    and a laser without a finite sample: none."""
    from vidiscover.analysis.reconstruction import _laser_rails

    t = np.arange(20000) / 10240.0
    x = 0.012 * np.sin(2 * np.pi * 11.0 * t)
    ok = np.ones(t.size, dtype=bool)
    clipped = np.clip(x, -0.01, 0.01)
    rails = _laser_rails(clipped, ok)
    assert rails is not None and np.array_equal(rails, np.abs(x) >= 0.01)
    quantised = np.round(0.009 * np.sin(2 * np.pi * 11.0 * t) / 5e-6) * 5e-6
    assert _laser_rails(quantised, ok) is None
    assert _laser_rails(np.full(t.size, np.nan), np.zeros(t.size, dtype=bool)) is None


def test_pulses_clipped_at_the_adc_rail_count_for_r():
    """Hunt-Crossley walls hit at up to 4.6 m/s (dev-020, Bessel-2 at 2560 Hz): the
    fastest half of the impacts clip the accelerometer's ADC. The detector fits those on
    their unclipped samples; their r was left out ('pulse'), and the wall's RMS was
    that of the slow half (0.67 against 0.50 over every impact: off by +0.167). Counted,
    the RMS is off by 0.0094 / 0.0085 (right / left)."""
    out, err = _wall_errors("dev", 20)
    table = out.impact_table
    clipped = table["clipped"].to_numpy(dtype=bool)
    assert clipped.sum() >= 70 and table["r_used"].to_numpy(dtype=bool)[clipped].mean() > 0.9
    assert abs(err["right"]) < 0.012 and abs(err["left"]) < 0.012   # 0.0094 / 0.0085


def test_an_analysis_in_the_filter_delay_frame_pickles_and_reads_the_same():
    """A result must cross process boundaries (a sweep's or discover's worker sends it
    back; the benchmarks cache it). test-033's LO is read in the impacts' time frame of
    a causal filter with its laser on its rails (the frame shift is kept on the
    reconstruction): that used to hold local functions, which do not pickle."""
    import pickle

    out, _ = _wall_errors("test", 33)
    assert out.reconstruction._shift is not None
    back = pickle.loads(pickle.dumps(out))
    t = out.detection.t[:5]
    for a, b in zip(out.reconstruction._shift(t), back.reconstruction._shift(t)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(out.restitution.table["r"], back.restitution.table["r"])


def test_the_lo_between_impacts_is_not_pinned_to_a_saturated_laser():
    """holdout4-011 (Kelvin-Voigt walls, r 0.38, mu 0.28, tilt -2.3 deg, linear-phase
    chain): a 10 mm laser on an LO of 16 mm amplitude, 58 % of its samples on a rail.
    The impact states were pinned off the rails, but the LO's own x and v (the regime
    features and the flights solved under a flight law read them) were still pinned to
    the rails: 3.2 mm and 69 mm/s RMS off the truth, and under the case's friction and
    tilt the left wall's r read 0.62 for 0.38 (error 0.233). Pinned off the rails: 0.08
    mm and 1.9 mm/s, r errors -0.009 / +0.012."""
    from vidiscover.analysis import analyze
    from vidiscover.corpus import realism_case

    case = realism_case("holdout4", 11)
    sim = case.simulate()
    rec, res, imp = sim.recording, sim.result, sim.truth.impacts
    out = analyze(rec, flight_law=(case.mu, case.theta), n_boot=0)
    rc = out.reconstruction
    assert 0.5 < rc.laser_rail_share < 0.65                        # 0.58
    true = res.evaluate(rc.t + res.settle)
    m = slice(rc.t.size // 20, -(rc.t.size // 20))
    assert np.sqrt(np.mean((rc.x - true["x"])[m] ** 2)) < 0.1e-3   # 0.046 mm (0.08, was 3.2)
    assert np.sqrt(np.mean((rc.v - true["xd"])[m] ** 2)) < 2e-3    # 0.8 mm/s (1.9, was 69)
    side = np.asarray(imp.side)
    for s, bound in (("right", 0.005), ("left", 0.02)):           # 0.0012 / 0.011
        r_true = float(np.sqrt(np.mean(np.asarray(imp.r)[side == s] ** 2)))
        w = out.restitution.wall(s)
        assert w.n >= 20 and abs(w.rms - r_true) < bound, (s, w.rms, r_true)   # left 0.233
