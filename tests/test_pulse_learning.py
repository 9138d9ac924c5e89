"""The acquisition model and learning the pulse response from a recording.

References not used to build the code: ``scipy.signal.impulse`` / ``freqs`` of the
analog filters, numerical convolution with the contact half-sine, an instrument built
here with ``scipy.signal`` (oversampled digital filter, decimated), and the exact
engine recorded through the sensor model's causal chains.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from analysis_sim import ASYM, simulation
from scipy import signal

from vidiscover import InputError, Metadata, Recording, SensorConfig, record
from vidiscover.acquisition import (
    CHEBY1_RIPPLE_DB,
    contact_shape,
    dc_group_delay,
    kelvin_voigt_shape,
    max_cutoff,
    pulse_response,
    pulse_responses,
)
from vidiscover.analysis import PulseModel, detect_impacts, detectable, match_impacts
from vidiscover.analysis.pulse import learn_pulse


def _analog(kind, order, cutoff):
    wc = 2 * np.pi * cutoff
    if kind == "butter":
        return signal.butter(order, wc, analog=True)
    if kind == "bessel":
        return signal.bessel(order, wc, analog=True, norm="phase")
    return signal.cheby1(order, CHEBY1_RIPPLE_DB, wc, analog=True)


@pytest.mark.parametrize("kind", ["butter", "bessel", "cheby1"])
@pytest.mark.parametrize("order", [2, 5, 8])
def test_causal_response_is_scipys_impulse_response(kind, order):
    b, a = _analog(kind, order, 0.3)
    t = np.arange(0, 40, 0.05)
    _, h = signal.impulse((b, a), T=t)
    h = h / (b[-1] / a[-1])                           # unit DC gain
    g = pulse_response(t, kind, order, 0.3, 0.0)
    assert np.abs(g - h).max() < 1e-9 * np.abs(h).max() + 1e-12
    assert np.all(pulse_response(-t[1:], kind, order, 0.3, 0.0) == 0)


@pytest.mark.parametrize("order", range(2, 9))
def test_bessel_cutoff_limit_puts_its_minus_3_db_point_at_the_nyquist_frequency(order):
    # anti-alias Bessels are specified by their -3 dB point (scipy's norm="mag"); ours
    # are phase-normalised, so one at 0.5 fs "-3 dB" lies beyond 0.5 fs here
    c = max_cutoff("bessel", order)
    _, h = signal.freqs(*_analog("bessel", order, c), [2 * np.pi * 0.5])
    assert abs(h[0]) ** 2 == pytest.approx(0.5, abs=1e-9)
    pm = signal.bessel(order, 2 * np.pi * 0.5, analog=True, norm="mag", output="zpk")[1]
    pp = signal.bessel(order, 2 * np.pi * c, analog=True, norm="phase", output="zpk")[1]
    assert np.allclose(np.sort_complex(pm), np.sort_complex(pp), rtol=1e-8)
    assert max_cutoff("butter", order) == max_cutoff("cheby1", order) == 0.5


def test_a_bessel_cutoff_may_pass_the_nyquist_frequency_up_to_its_limit_only():
    m = PulseModel(0.7, kind="bessel", order=4)        # -3 dB at 0.46 fs
    t = np.arange(0, 400) / 16.0
    assert np.sum(m.response(t / 6400.0, 6400.0)) / 16.0 / 6400.0 == pytest.approx(1.0, abs=2e-3)
    for kind, order, c in [("bessel", 4, 0.76), ("bessel", 2, 0.64), ("butter", 4, 0.5),
                           ("cheby1", 8, 0.6), ("linear-phase", 0, 0.5)]:
        with pytest.raises(InputError, match=r"cutoff must be in \(0, 0\.[0-9]+\)") as e:
            PulseModel(c, kind=kind, order=order)
        assert "\n" not in str(e.value)
    with pytest.raises(InputError, match="bessel-4 .* Nyquist"):
        pulse_response(t, "bessel", 4, 0.76, 0.0)


def test_a_bessel_beyond_nyquist_is_searched_when_any_family_sits_at_the_top():
    """Our sensors' Bessel-4 at 0.70 fs (its -3 dB point at 0.46 fs) on the exact engine's
    instantaneous impacts: the best in-range model is a Chebyshev-2 at the top of the
    range (0.49 fs, with a 350 us "contact"), not a Bessel, and its impacts came out 34 us
    late. The Bessels beyond 0.5 fs are searched whenever the best causal model sits at
    the top: a Bessel beyond 0.5 fs is learned and the impacts are 17 us late (measured;
    the cut-off still trades against the contact duration: not the true Bessel-4)."""
    from vidiscover import preset, simulate

    res = simulate(preset("paper", b=0.009), settle=3.0, duration=5.12)
    rec, _ = record(res, SensorConfig(anti_alias="bessel", aa_order=4, aa_cutoff=0.70 * 6400))
    det = detect_impacts(rec)
    m = det.pulse
    assert m.kind == "bessel" and m.cutoff > 0.5
    t_true = res.record_impacts().t - res.settle
    assert det.n == t_true.size
    err = np.array([np.min(np.abs(t_true - t)) for t in det.t])
    assert np.median(err) <= 20e-6                   # measured 17.1 us (34 us before)


@pytest.mark.parametrize("kind,order", [("butter", 4), ("bessel", 6), ("cheby1", 3)])
def test_contact_response_is_the_convolution_and_its_centroid_the_group_delay(kind, order):
    tau = 1.7                                          # samples
    ds = tau / 400
    s = (np.arange(400) + 0.5) * ds
    f = np.pi / (2 * tau) * np.sin(np.pi * s / tau)
    t = np.arange(-2, 30, 0.25)
    num = np.array([np.sum(f * pulse_response(x - s, kind, order, 0.3, 0.0)) * ds for x in t])
    g = pulse_response(t, kind, order, 0.3, tau)
    assert np.abs(g - num).max() < 2e-5 * np.abs(g).max()
    # centroid = DC group delay (scipy.signal.freqs phase slope) + tau / 2
    b, a = _analog(kind, order, 0.3)
    w = np.array([1e-4, 2e-4])
    _, hw = signal.freqs(b, a, worN=w)
    gd = -np.diff(np.unwrap(np.angle(hw)))[0] / np.diff(w)[0]
    assert dc_group_delay(kind, order, 0.3) == pytest.approx(gd, rel=1e-4)
    tt = np.arange(0, 400, 1 / 16)
    gg = pulse_response(tt, kind, order, 0.3, tau)
    assert np.sum(gg) / 16 == pytest.approx(1.0, abs=1e-5)
    assert np.sum(tt * gg) / np.sum(gg) == pytest.approx(gd + tau / 2, abs=1e-4)


def _scipy_instrument(seed=0, fs=6400.0, kind="butter", order=4, fc=2500.0, tau=0.15e-3,
                      n_imp=60, os=16, tau_left=None):
    """A record made with scipy.signal: impulses through an oversampled digital filter.

    Contacts last ``tau`` (``tau_left`` for the negative, left-wall pulses if given).
    """
    rng = np.random.default_rng(seed)
    fo = fs * os
    n = int(3.0 * fs)
    to = np.arange(n * os) / fo
    a = -12.0 * np.sin(2 * np.pi * 8.0 * to)
    t_in = np.sort(rng.uniform(0.05, 2.95, n_imp))
    t_in = t_in[np.r_[True, np.diff(t_in) > 0.01]]
    dv = rng.choice([-1, 1], t_in.size) * rng.uniform(2e-3, 1e-2, t_in.size)
    for ti, d in zip(t_in, dv):
        tc = tau if d > 0 or tau_left is None else tau_left
        m = int(round(tc * fo))
        k = int(np.ceil(ti * fo))
        s = (np.arange(k, k + m) / fo - ti)
        a[k:k + m] += d * np.pi / (2 * tc) * np.sin(np.pi * s / tc)
    if kind == "butter":
        sos = signal.butter(order, fc, fs=fo, output="sos")
    else:
        sos = signal.bessel(order, fc, fs=fo, output="sos", norm="phase")
    zi = signal.sosfilt_zi(sos) * a[0]
    af = signal.sosfilt(sos, a, zi=zi)[0][::os]
    af = af + 0.05 * rng.standard_normal(af.size)
    t = np.arange(af.size) / fs
    rec = Recording(t, np.zeros_like(t), af, np.zeros_like(t), Metadata(b=0.009, sample_rate=fs))
    return rec, t_in, dv


def test_learned_response_times_a_scipy_instrument():
    rec, t_in, dv = _scipy_instrument()
    det = detect_impacts(rec)
    r = det.response
    assert r is not None and r.model.kind == "butter" and r.model.order == 4
    assert r.model.cutoff * 6400 == pytest.approx(2500, rel=0.03)
    assert r.model.tau == pytest.approx(0.15e-3, rel=0.3)
    assert det.n == t_in.size
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size
    err = det.t[ie] - t_in[it]
    assert np.median(np.abs(err)) < 8e-6                  # measured 3 us
    assert np.all(np.abs(det.dv[ie] / dv[it] - 1) < 0.02)
    # the super-resolved template agrees with the model
    assert r.misfit < 0.01 and r.n_pulses >= 20


def test_walls_of_two_stiffnesses_get_their_own_contact_duration():
    # right-wall contacts last 0.1 ms, left-wall ones 0.6 ms
    rec, t_in, dv = _scipy_instrument(seed=2, tau=0.1e-3, tau_left=0.6e-3)
    det = detect_impacts(rec)
    r = det.response
    assert r.model.kind == "butter" and r.model.order == 4
    assert r.model.tau == pytest.approx(0.1e-3, abs=0.05e-3)          # measured 0.125 ms
    assert r.model_left.tau == pytest.approx(0.6e-3, rel=0.1)        # measured 0.600 ms
    assert det.n == t_in.size
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size
    assert np.all(np.sign(det.dv[ie]) == np.sign(dv[it]))
    err = det.t[ie] - t_in[it]
    for sgn in (1, -1):                    # each wall timed with its own delay
        assert np.median(np.abs(err[dv[it] * sgn > 0])) < 13e-6     # measured 9.5, 2.6 us
    # one shared duration times the left wall 0.25 ms late (measured 247 us)
    shared = detect_impacts(rec, pulse=r.model)
    je, jt = match_impacts(shared.t, t_in, 0.5e-3)
    left = dv[jt] < 0
    assert np.median(np.abs(shared.t[je][left] - t_in[jt][left])) > 100e-6


def test_pulse_responses_are_pulse_response_row_by_row():
    t = np.linspace(-4.0, 60.0, 500)[None, :] + np.array([[0.0], [0.37], [1.5], [2.25]])
    cutoffs, taus = np.array([0.1, 0.3, 0.45, 0.2]), np.array([0.0, 0.7, 3.0, 8.0])
    for kind, order in (("butter", 4), ("bessel", 8), ("cheby1", 3), ("linear-phase", 0)):
        got = pulse_responses(t, kind, order, cutoffs, taus)
        for m in range(4):
            ref = pulse_response(t[m], kind, order, cutoffs[m], taus[m])
            assert np.abs(got[m] - ref).max() <= 1e-12 * np.abs(ref).max()


@pytest.mark.parametrize("model", [PulseModel(), PulseModel(tau=0.3e-3),
                                   PulseModel(kind="cheby1", order=4, cutoff=0.37)])
def test_kernel_rows_at_delays_next_to_a_whole_sample(model):
    """rows(j, delta) at delays a rounding away from a whole sample (a back-fit's
    4e-17) equals the row at that sample: u - floor(u) rounds to 1.0 there, which read
    a phase past the table and raised IndexError at the support's edge (a
    clipped-pulse refit of an other-rig training case, seed 14003 #231)."""
    fs = 10240.0
    span = model.span(fs)
    j = np.arange(-span - 8, span + 9)
    for d in (4.16e-17, 1e-300, -4e-17, 2.0 + 4.4e-16, -3.0):
        got = model.rows(j, np.array([d, 0.0]), fs)
        ref = model.rows(j, np.array([round(d), 0.0]), fs)
        # (1e-5 of the peak: a causal kernel's truncated tail at the support's last
        # sample, 6e-6 of the peak for the Chebyshev, is read from one side only)
        assert np.abs(got - ref).max() <= 1e-5 * np.abs(ref).max()


def test_learned_response_at_a_high_sample_rate():
    rec, t_in, dv = _scipy_instrument(seed=1, fs=25600.0, kind="bessel", order=6, fc=3000.0,
                                      tau=0.3e-3, n_imp=40, os=4)
    det = detect_impacts(rec)
    assert det.n == t_in.size
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    # measured 28.8 us (0.74 sample; the contact duration and the filter order trade off:
    # bessel 7 with 0.275 ms learned for bessel 6 with 0.3 ms). Before the isolation test
    # kept each pulse's own main lobe out, 19 of 40 pulses were taken (bessel 4, 0.34 ms,
    # < 20 us here) and a 1 ms contact at 12.8 kHz was never learned at all
    assert np.median(np.abs(det.t[ie] - t_in[it])) < 35e-6


def test_a_long_soft_wall_contact_is_learned_and_counted_once():
    # a 1.05 ms contact spans 13 samples at 12.8 kHz: its own shoulders were taken for
    # another transient, no left pulse was "isolated", the left wall got the right
    # wall's 0.4 ms and every left impact was fitted as two (a realism-corpus case)
    rec, t_in, dv = _scipy_instrument(seed=3, fs=12800.0, kind="butter", order=6,
                                      fc=3873.0, tau=0.37e-3, tau_left=1.05e-3, n_imp=60)
    det = detect_impacts(rec)
    r = det.response
    assert r.model.tau == pytest.approx(0.37e-3, rel=0.2)
    assert r.model_left.tau == pytest.approx(1.05e-3, rel=0.1)
    assert det.n == t_in.size
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size
    assert np.median(np.abs(det.t[ie] - t_in[it])) < 30e-6


def test_pulses_behind_a_slow_filter_at_a_low_rate_are_learned():
    # Bessel at 0.24 fs, 2.56 kHz: the smoother's residual has lobes of 0.35-0.42 of
    # each peak within half its window; no pulse passed the isolation test, the default
    # linear-phase model timed every impact one filter delay (~0.9 ms) late
    rec, t_in, dv = _scipy_instrument(seed=4, fs=2560.0, kind="bessel", order=7, fc=614.0,
                                      tau=0.1e-3, n_imp=60, os=16)
    det = detect_impacts(rec)
    assert det.response is not None and det.response.model.kind == "bessel"
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size == det.n
    # measured 96 us, a quarter of a sample (bessel 7 learned as a higher order with a
    # shorter contact: the two trade off at this rate)
    assert np.median(np.abs(det.t[ie] - t_in[it])) < 120e-6


@pytest.mark.parametrize("sensors,timing", [
    (SensorConfig(anti_alias="butter", aa_order=4, aa_cutoff=2500.0), 12e-6),
    (SensorConfig(anti_alias="cheby1", aa_order=3, aa_cutoff=1800.0, sample_rate=5120.0,
                  a_bias=0.4, x_offset=3e-4, xe_offset=-2e-4), 40e-6)])
def test_exact_engine_through_causal_chains(sensors, timing):
    rec, truth = record(simulation(0.009, ASYM), sensors, seed=1)
    det = detect_impacts(rec)
    fs = rec.sample_rate
    model = PulseModel(cutoff=sensors.aa_cutoff / fs, kind=sensors.anti_alias,
                       order=sensors.aa_order)
    ok = detectable(truth.impacts.t, truth.impacts.dv, sensors.a_noise, fs,
                    cutoff=model.peak(fs) / (2 * fs))
    ie, it = [], []
    for side in ("right", "left"):
        ke = np.flatnonzero(det.side == side)
        kt = np.flatnonzero(truth.impacts.side == side)
        e, t = match_impacts(det.t[ke], truth.impacts.t[kt])
        ie.append(ke[e])
        it.append(kt[t])
    ie, it = np.concatenate(ie), np.concatenate(it)
    assert ie.size / det.n >= 0.99
    assert ok[it].sum() / ok.sum() >= 0.99
    assert np.median(np.abs(det.t[ie] - truth.impacts.t[it])) <= timing   # measured 8, 32 us
    assert det.response.model.kind == sensors.anti_alias
    assert det.response.model.order == sensors.aa_order


def test_a_known_pulse_model_is_used_as_given():
    rec, _ = record(simulation(0.009, ASYM), seed=1)
    det = detect_impacts(rec, pulse=PulseModel())
    assert det.response is None and det.pulse == PulseModel()
    learned = detect_impacts(rec)
    assert learned.response.model.kind == "linear-phase"
    assert learned.response.model.cutoff == pytest.approx(0.45, abs=0.01)
    assert learned.n == det.n


def test_without_strong_pulses_nothing_is_learned():
    t = np.arange(32768) / 6400.0
    a = -12 * np.sin(2 * np.pi * 8 * t) + 0.05 * np.random.default_rng(0).standard_normal(t.size)
    assert learn_pulse(a, 6400.0) is None
    rec = Recording(t, np.zeros_like(t), a, np.zeros_like(t), Metadata(b=0.009, sample_rate=6400))
    det = detect_impacts(rec)
    assert det.n == 0 and any("too few strong" in w for w in det.warnings)


def test_bad_learning_options_are_input_errors():
    with pytest.raises(InputError, match="kinds must be among"):
        learn_pulse(np.zeros(1000), 6400.0, kinds=("fir",))
    with pytest.raises(InputError, match="anti-alias order"):
        PulseModel(kind="butter", order=1)
    with pytest.raises(InputError, match="pulse must be a PulseModel"):
        detect_impacts(Recording(np.arange(100) / 6400.0, np.zeros(100), np.zeros(100),
                                 np.zeros(100), Metadata(b=0.009, sample_rate=6400.0)),
                       pulse="butter")


def test_analysis_does_not_import_the_simulator_discovery_or_regimes():
    code = ("import vidiscover.analysis, sys; bad = [m for m in sys.modules if m.startswith("
            "('vidiscover.simulation', 'vidiscover.discovery', 'vidiscover.regimes'))]; "
            "assert not bad, bad")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-500:]


@pytest.mark.parametrize("kind,order", [("butter", 4), ("bessel", 7), ("cheby1", 5),
                                        ("linear-phase", 0)])
@pytest.mark.parametrize("skew", [-0.5, 1.5, 4.0])
def test_skewed_contact_response_is_the_convolution(kind, order, skew):
    tau = 6.0                                          # samples
    ds = tau / 2000
    s = (np.arange(2000) + 0.5) * ds
    f = np.sin(np.pi * s / tau) * np.exp(-skew * np.pi * s / tau)
    f /= f.sum() * ds                                  # unit impulse
    t = np.arange(-2, 30, 0.25) if kind != "linear-phase" else np.arange(-30, 30, 0.25)
    if kind == "linear-phase":                         # its time origin: the contact midpoint
        num = np.array([np.sum(f * pulse_response(x - (s - tau / 2), kind, order, 0.3, 0.0))
                        * ds for x in t])
    else:
        num = np.array([np.sum(f * pulse_response(x - s, kind, order, 0.3, 0.0)) * ds
                        for x in t])
    g = pulse_response(t, kind, order, 0.3, tau, skew=skew)
    assert np.abs(g - num).max() < 1e-5 * np.abs(g).max()
    rows = pulse_responses(np.vstack([t, t]), kind, order, np.array([0.3, 0.3]),
                           np.array([tau, tau]), 24, np.array([skew, 0.0]))
    assert np.abs(rows[0] - g).max() <= 1e-12 * np.abs(g).max()
    assert np.abs(rows[1] - pulse_response(t, kind, order, 0.3, tau)).max() \
        <= 1e-12 * np.abs(g).max()


def _kelvin_voigt_force(fo, k_over_m, r):
    """Contact force per unit impulse of a Kelvin-Voigt wall (exact linear ODE), on 1/fo."""
    zeta = -np.log(r) / np.sqrt(np.pi ** 2 + np.log(r) ** 2)   # r = exp(-zeta pi / sqrt(1-z^2))
    w = np.sqrt(k_over_m)
    wd = w * np.sqrt(1 - zeta ** 2)
    s = np.arange(0, 4 * np.pi / wd, 1 / fo)
    z = np.exp(-zeta * w * s) * np.sin(wd * s) / wd            # penetration per unit v_in
    zd = np.exp(-zeta * w * s) * (np.cos(wd * s) - zeta * w / wd * np.sin(wd * s))
    force = w * w * z + 2 * zeta * w * zd                       # per unit mass and v_in
    end = np.argmax((force <= 0) & (s > 0))                     # the ball leaves the wall
    f = force[:end]
    return f / (f.sum() / fo)


@pytest.mark.parametrize("r", [0.2, 0.41, 0.8])
def test_the_viscous_contact_shape_is_the_kelvin_voigt_force(r):
    fo = 1e7
    f = _kelvin_voigt_force(fo, 1e8, r)
    s = (np.arange(f.size) + 0.5) / fo
    zeta = -np.log(r) / np.sqrt(np.pi ** 2 + np.log(r) ** 2)
    g = contact_shape(s, f.size / fo, *kelvin_voigt_shape(zeta))
    assert np.abs(g - f).max() < 2e-3 * f.max()


def test_a_viscous_wall_s_contact_shape_is_learned_from_a_scipy_instrument():
    # dev-057's rig in a scipy instrument: Kelvin-Voigt walls with r = 0.41 (the
    # force jumps at entry) and 0.56 ms contacts behind a 5th-order Butterworth at
    # 3.6 kHz, 10240 Hz.
    fs, os = 10240.0, 16
    fo = fs * os
    f = _kelvin_voigt_force(fo, 1.406e6 / 0.06086, 0.41)
    rng = np.random.default_rng(5)
    n = int(3.0 * fs)
    to = np.arange(n * os) / fo
    a = -12.0 * np.sin(2 * np.pi * 8.0 * to)
    t_in = np.arange(0.05, 2.95, 0.037) + rng.uniform(-0.004, 0.004, 79)
    dv = rng.choice([-1, 1], t_in.size) * rng.uniform(2e-3, 1.5e-2, t_in.size)
    for ti, d in zip(t_in, dv):
        k = int(np.ceil(ti * fo))
        a[k:k + f.size] += d * f
    sos = signal.butter(5, 3600.0, fs=fo, output="sos")
    af = signal.sosfilt(sos, a, zi=signal.sosfilt_zi(sos) * a[0])[0][::os]
    af = af + 0.1 * rng.standard_normal(af.size)
    t = np.arange(af.size) / fs
    rec = Recording(t, np.zeros_like(t), af, np.zeros_like(t), Metadata(b=0.009, sample_rate=fs))
    det = detect_impacts(rec)
    m = det.response.model
    assert m.phase > 0                                  # the force jumps at entry ...
    assert m.tau == pytest.approx(0.56e-3, rel=0.1)     # ... for 0.56 ms (measured 0.575)
    assert det.n == t_in.size
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size
    # measured 78 us: a 2nd-order Chebyshev with this contact shape fits 2.5x worse
    # than the true instrument but is what the search finds; the entry moves with it
    assert np.median(np.abs(det.t[ie] - t_in[it])) < 100e-6
    # worst area error measured 0.037, median 0.0078 (0.034 and 0.0074 before the
    # smoother's bridge covered strong pulses' learned model error)
    assert np.all(np.abs(det.dv[ie] / dv[it] - 1) < 0.04)


@pytest.mark.slow
@pytest.mark.parametrize("index,before", [(37, 120), (57, 97)])
def test_viscous_and_long_contacts_of_the_corpus_are_counted_once(index, before):
    # dev cases where the half-sine contact model's misfit lobe was counted as a
    # second impact of every contact (``before`` detections of 80 true)
    from vidiscover.analysis import analyze
    from vidiscover.analysis.validation import match_impacts_by_wall
    from vidiscover.corpus import realism_case

    case = realism_case("dev", index)
    sim = case.simulate(label=False)
    out = analyze(sim.recording, flight_law=(case.mu, case.theta), n_boot=0)
    imp = sim.truth.impacts
    ie, it = match_impacts_by_wall(out.detection.t, out.detection.side, imp.t_in, imp.side)
    assert out.detection.n == len(imp.t_in) == 80 < before
    assert len(ie) == 80
    assert np.median(np.abs(out.detection.t[ie] - imp.t_in[it])) < 80e-6   # 8.5, 72 us


def test_learning_windows_are_bridged_along_the_curvature():
    """A 12.5 ms learning window of a 19 Hz, 500 m/s^2 acceleration sampled at 2560 Hz
    (realism dev-011): the straight line of fill_gaps sags by ~100 m/s^2 across it,
    the local quartic of bridge_gaps misses it by 2 % of that (measured 2.4 m/s^2)."""
    from vidiscover.analysis.signals import bridge_gaps, fill_gaps

    fs = 2560.0
    t = np.arange(2560) / fs
    y = 500.0 * np.sin(2 * np.pi * 19.1 * t + 0.3)
    bad = np.zeros(t.size, dtype=bool)
    bad[0:5] = True                      # an edge run: linear (nearest value) fallback
    for lo in (300, 777, 1500):
        bad[lo:lo + 32] = True
    lin = np.abs(fill_gaps(y, bad) - y)[bad].max()
    cub = np.abs(bridge_gaps(y, bad) - y)[bad[5:].nonzero()[0] + 5].max()
    assert lin > 50.0
    assert cub < 0.03 * lin
    assert np.array_equal(bridge_gaps(y, bad)[~bad], y[~bad])
    assert np.array_equal(bridge_gaps(y, bad)[:5], fill_gaps(y, bad)[:5])


def test_a_bridge_held_by_too_few_samples_on_one_side_stays_straight():
    """A run with two good samples before it (the next window starts there): with
    min_side=4 it keeps the straight bridge of fill_gaps, where a quartic through two
    samples on that side would be free to swing; with the default it is bridged."""
    from vidiscover.analysis.signals import bridge_gaps, fill_gaps

    rng = np.random.default_rng(3)
    y = np.sin(np.arange(400) / 15.0) + 0.01 * rng.standard_normal(400)
    bad = np.zeros(400, dtype=bool)
    bad[100:140] = True
    bad[142:180] = True                 # two good samples (140, 141) between the runs
    straight = fill_gaps(y, bad)
    guarded = bridge_gaps(y, bad, min_side=4)
    assert np.array_equal(guarded[142:180], straight[142:180])
    assert np.array_equal(guarded[100:140], straight[100:140])
    assert not np.array_equal(bridge_gaps(y, bad)[142:180], straight[142:180])


def test_a_mounted_resonance_s_ringing_is_not_counted():
    # a stud-mounted accelerometer ringing at 8.3 kHz (Q = 25, seen aliased at
    # 10240 Hz) behind a 4th-order Bessel at 4 kHz, very strong impacts (SNR ~ 4000):
    # its ringing lasts ~5 ms above the noise and was counted as impacts (105 of
    # them); 11 lobes of the smoother (ringing leaks into it, 25 samples early) remain
    fs, os = 10240.0, 16
    fo = fs * os
    rng = np.random.default_rng(11)
    n = int(3.0 * fs)
    to = np.arange(n * os) / fo
    a = -40.0 * np.sin(2 * np.pi * 6.0 * to)
    t_in = np.arange(0.05, 2.95, 0.031) + rng.uniform(-0.003, 0.003, 94)
    dv = rng.choice([-1, 1], t_in.size) * rng.uniform(0.01, 0.02, t_in.size)
    m = int(round(0.15e-3 * fo))
    for ti, d in zip(t_in, dv):
        k = int(np.ceil(ti * fo))
        s = (np.arange(k, k + m) / fo - ti)
        a[k:k + m] += d * np.pi / (2 * 0.15e-3) * np.sin(np.pi * s / 0.15e-3)
    w = 2 * np.pi * 8300.0
    b_m, a_m = signal.bilinear([w * w], [1.0, 2 * 0.02 * w, w * w], fo)
    a = signal.lfilter(b_m, a_m, a, zi=signal.lfilter_zi(b_m, a_m) * a[0])[0]
    sos = signal.bessel(4, 4000.0, fs=fo, output="sos", norm="phase")
    af = signal.sosfilt(sos, a, zi=signal.sosfilt_zi(sos) * a[0])[0][::os]
    af = af + 0.04 * rng.standard_normal(af.size)
    t = np.arange(af.size) / fs
    rec = Recording(t, np.zeros_like(t), af, np.zeros_like(t), Metadata(b=0.009, sample_rate=fs))
    det = detect_impacts(rec)
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert ie.size == t_in.size
    assert det.n <= t_in.size + 12           # measured 105 of 94; 199 before the error envelope


@pytest.mark.parametrize("kind", ["butter", "bessel", "cheby1"])
def test_tabulated_prototype_poles_are_scipys_bit_for_bit(kind):
    """The analog prototypes are tabulated (scipy.signal's import costs 0.5-0.9 s per
    process): the table must be scipy's poles exactly, order by order."""
    from vidiscover._prototypes import POLES, scipy_poles

    for order in range(2, 9):
        got = np.array([complex(re, im) for re, im in POLES[(kind, order)]])
        want = scipy_poles(kind, order, CHEBY1_RIPPLE_DB)
        assert got.shape == want.shape
        assert np.array_equal(got.view(float), want.view(float)), (kind, order)


def test_analysis_and_pulse_learning_do_not_import_scipy_signal():
    """Analysing a recording, pulse learned, loads neither scipy.signal nor scipy.stats
    (0.5-0.9 s of start-up per command or sweep worker)."""
    code = ("import sys\n"
            "from vidiscover.analysis import analyze\n"
            "from vidiscover.params import preset\n"
            "from vidiscover.workflows import simulate_to_memory\n"
            "rec, _, _ = simulate_to_memory(preset('paper'), settle=1.0, duration=2.0)\n"
            "sys.modules.pop('scipy.signal', None); sys.modules.pop('scipy.stats', None)\n"
            "an = analyze(rec, n_boot=0)\n"
            "assert an.detection.response is not None\n"
            "print(sorted({'scipy.signal', 'scipy.stats'} & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def _with_reimpacts(kind, seed=3, fs=2560.0, os=16, lag=6.75e-3, ratio=0.3, sos=None):
    """Impacts on alternate walls, each followed ``lag`` later by a re-impact on its wall
    of ``ratio`` times its impulse (a periodic motion: every learning window holds one),
    through ``sos`` (at ``fs * os``) or the instrument of ``kind``."""
    fo = fs * os
    rng = np.random.default_rng(seed)
    to = np.arange(int(3.0 * fs) * os) / fo
    a = -20.0 * np.sin(2 * np.pi * 9.0 * to)
    t_main = np.arange(0.05, 2.9, 0.0366) + rng.uniform(-0.002, 0.002, 78)
    dv_main = np.where(np.arange(78) % 2 == 0, 1.0, -1.0) * rng.uniform(0.015, 0.02, 78)
    order = np.argsort(np.r_[t_main, t_main + lag])
    t_in = np.r_[t_main, t_main + lag][order]
    dv = np.r_[dv_main, ratio * dv_main][order]
    tau = 0.1e-3
    m = int(round(tau * fo))
    for ti, d in zip(t_in, dv):
        k = int(np.ceil(ti * fo))
        a[k:k + m] += d * np.pi / (2 * tau) * np.sin(np.pi * (np.arange(k, k + m) / fo - ti) / tau)
    if sos is None:
        sos = (signal.cheby1(7, 1.0, 820.0, fs=fo, output="sos") if kind == "cheby1"
               else signal.butter(6, 800.0, fs=fo, output="sos"))
    af = signal.sosfilt(sos, a, zi=signal.sosfilt_zi(sos) * a[0])[0][::os]
    af = af + 0.07 * rng.standard_normal(af.size)
    t = np.arange(af.size) / fs
    rec = Recording(t, np.zeros_like(t), af, np.zeros_like(t), Metadata(b=0.009, sample_rate=fs))
    return rec, t_in


@pytest.mark.parametrize("kind", ["cheby1", "butter"])
def test_a_re_impact_in_every_learning_window_is_not_taken_for_ringing(kind):
    # test-050's failure: every strong pulse has a same-wall re-impact 0.3 times its
    # size 17 samples later (below the third that breaks isolation). The error
    # envelope took it for ringing the model lacks (0.27-0.30 at lags 15-19) and the
    # detector dropped every re-impact (78 of 156). A re-impact is one more copy of
    # the response: it is taken out of the learning windows (learned again without)
    rec, t_in = _with_reimpacts(kind)
    det = detect_impacts(rec)
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert det.n == t_in.size == ie.size == 156            # was 78 found
    assert np.median(np.abs(det.t[ie] - t_in[it])) < 95e-6   # measured 75 (cheby1), 23 us
    env = det.response.error_at(np.arange(14.0, 21.0))
    assert env.max() < 0.03                                   # measured 0.014, was 0.27


@pytest.mark.parametrize("lag", [3.9e-3, 4.7e-3])
def test_a_re_impact_on_a_chebyshev_s_ringing_lobes_is_not_taken_for_ringing(lag):
    # holdout5-022's second stage: a Chebyshev-1 of order 5 at 583 Hz (2560 Hz) rings
    # above a tenth of its peak from -8 to +12 samples. Those lobes were taken for the
    # main lobe, in which no other impact's copy is fitted in the learning windows, so
    # a re-impact 10-12 samples on (0.23 of the pulse) stayed in the residual, the
    # error envelope took it for ringing (0.17-0.20) and every re-impact was dropped
    # (78 of 156 found at both lags). Only the contiguous lobe about the peak is
    # excluded now
    rec, t_in = _with_reimpacts("cheby1", lag=lag, ratio=0.23,
                                sos=signal.cheby1(5, 1.0, 583.0, fs=2560.0 * 16,
                                                  output="sos"))
    det = detect_impacts(rec)
    ie, it = match_impacts(det.t, t_in, 0.5e-3)
    assert (det.response.model.kind, det.response.model.order) == ("cheby1", 5)
    assert ie.size >= 152 and det.n - ie.size <= 1           # measured 152 and 154 of 156
    assert np.median(np.abs(det.t[ie] - t_in[it])) < 110e-6  # measured 69, 100 us
    env = det.response.error_at(np.arange(9.0, 14.0))
    assert env.max() < 0.06                                   # measured 0.004, 0.039; was 0.2


@pytest.mark.slow
def test_a_steep_family_between_two_coarse_cut_offs_is_refined():
    # dev-016 (Chebyshev-1 of order 8 at 1891 Hz, 5120 Hz): the true family misses the
    # coarse cut-offs by up to 9 % and its misfit is steep in cut-off, so it ranked
    # below the four refined families and cheby1-7 was learned (misfit 0.013 against
    # 0.003). Six families are refined now (holdout5-022's first stage)
    from corpus_scoring import episodes

    _, ok, det, ie, it = episodes("dev", 16)
    m = det.response.model
    assert (m.kind, m.order) == ("cheby1", 8)
    assert abs(m.cutoff * 5120.0 / 1891.4 - 1.0) < 0.01      # measured 1898 Hz
    assert ie.size == det.n == ok.sum() == 80



@pytest.mark.slow
def test_closely_packed_learning_windows_are_bridged_from_both_sides(monkeypatch):
    """holdout6-040 (Kelvin-Voigt walls, Bessel-3 at 0.44 fs, 2560 Hz, impacts 25-45
    samples apart; a spent split): the quartic bridges of its learning windows, held by
    one to three samples on one side, overshot by ~1000 m/s^2 under 230 m/s^2 pulses and
    a 55 Hz 'filter' was learned (misfit 0.217; 14 detections, none right). With
    pulse._BRIDGE_SIDE good samples required on each side it learns Bessel-3 near the
    truth and finds the impacts (measured: 0.4486 fs, misfit 0.042, 120 detections of
    120, 119 matched). The old bridge (one sample per side) still learns the bad
    response, and the misfit above impacts._MISFIT_WARN (0.15) is then reported;
    dev-000, a sound learned response (misfit ~0.005), carries no such warning."""
    from vidiscover.analysis import pulse as pulse_mod
    from vidiscover.corpus import realism_case

    def learned(split, i):
        rec = realism_case(split, i).simulate().recording
        return detect_impacts(rec)

    det = learned("holdout6", 40)
    assert (det.response.model.kind, det.response.model.order) == ("bessel", 3)
    assert det.response.model.cutoff == pytest.approx(0.44, abs=0.02)
    assert det.response.misfit < 0.06
    assert 117 <= det.n <= 123
    assert not any("fits the strongest pulses poorly" in w for w in det.warnings)

    monkeypatch.setattr(pulse_mod, "_BRIDGE_SIDE", 1)
    bad = learned("holdout6", 40)
    assert bad.response.misfit == pytest.approx(0.217, abs=0.01)
    assert any("fits the strongest pulses poorly (misfit 0.22" in w for w in bad.warnings)
    monkeypatch.undo()
    good = learned("dev", 0)
    assert good.response.misfit < 0.02
    assert not any("fits the strongest pulses poorly" in w for w in good.warnings)
