"""Stage 2: LO velocity, ball motion and flight segments against simulated truth.

Figures: reconstructed ball position within 0.5 mm RMS of the true one at
b = 9 mm (asked) -- measured a few micrometres -- and at 6 and 7.5 mm; LO velocity
from the integrated acceleration within 1 mm/s RMS; pre-impact LO velocities within
1 mm/s; every truth sticking phase that follows a detected chatter sequence shows
up as a ``stick`` flight released within 1 ms of the true release.
"""

import numpy as np
import pytest
from analysis_sim import ASYM, CLEARANCES, analysed, recording

from vidiscover import InputError, Recording
from vidiscover.analysis import (
    FLIGHT_COLUMNS,
    detect_impacts,
    eq8_velocities,
    integrate_flights,
    reconstruct,
    solve_flights,
)
from vidiscover.analysis.reconstruction import IMPACT_STATE_COLUMNS
from vidiscover.params import G_ACCEL


def _ball_rms(out, truth):
    rec_t = out.reconstruction.t
    y = out.reconstruction.ball_position(rec_t)
    ok = np.isfinite(y)
    y_true = truth.motion.y
    return float(np.sqrt(np.mean((y[ok] - y_true[ok]) ** 2))), ok.mean()


def test_rigid_walls_take_no_contact_time():
    """The exact engine's walls are rigid (a learned or given contact duration of 0):
    every flight starts at its impact, from the impact's own states."""
    out, _ = analysed(0.009)
    det, rc = out.detection, out.reconstruction
    fl, ic = rc.flight_columns, rc.impact_columns
    assert det.pulse.tau == 0 and (det.response is None or det.response.model_for(-1).tau == 0)
    i = fl["i_start"]
    assert np.array_equal(fl["t_start"], det.t[i])
    assert np.array_equal(fl["y_start"], ic["y"][i])
    assert np.array_equal(fl["v_start"], ic["v_plus"][i])
    assert np.array_equal(ic["u_plus"], ic["w_plus"] - ic["v_plus"], equal_nan=True)


@pytest.mark.parametrize("b", CLEARANCES)
def test_ball_position_is_reconstructed(b):
    out, truth = analysed(b)
    rms, coverage = _ball_rms(out, truth)
    assert rms <= 0.5e-3, rms
    assert coverage > 0.97             # all but before the first / after the last impact


@pytest.mark.parametrize("b", CLEARANCES)
def test_lo_velocity_from_acceleration(b):
    out, truth = analysed(b)
    R = out.reconstruction
    xd = truth.motion.xd
    assert np.sqrt(np.mean((R.v - xd) ** 2)) < 1e-3
    assert np.sqrt(np.mean((R.x - truth.motion.x) ** 2)) < 5e-6
    # the laser derivative (paper Fig. 13, nonsmooth curve) is much noisier
    assert np.sqrt(np.mean((R.v_disp - xd) ** 2)) > 3 * np.sqrt(np.mean((R.v - xd) ** 2))


def test_pre_and_post_impact_lo_velocities():
    out, truth = analysed(0.009)
    from vidiscover.analysis import detection_scores
    det = out.detection
    s = detection_scores(det.t, det.side, truth)
    ic = out.reconstruction.impact_columns
    for key in ("v_minus", "v_plus"):
        true = getattr(truth.impacts, key)[s.i_true]
        assert np.sqrt(np.mean((ic[key][s.i_est] - true) ** 2)) < 1e-3, key


def test_stick_flights_match_the_true_sticking_phases():
    out, truth = analysed(0.009)
    fc = out.reconstruction.flight_columns
    stick = fc["kind"] == "stick"
    assert stick.sum() >= 35
    ends = np.array([s.t_end for s in truth.sticking if s.where == "left"])
    for tr in fc["t_release"][stick]:
        assert np.min(np.abs(ends - tr)) < 1e-3
    # the stick hypothesis closes to micrometres where it holds, to millimetres elsewhere
    cl = np.abs(fc["closure"])
    assert np.nanmax(cl[stick]) < 2e-5
    assert np.nanmin(cl[~stick]) > 5e-4


def test_flight_table_contract():
    out, _ = analysed(0.009)
    fl = out.reconstruction.flights
    assert tuple(fl.columns)[:len(FLIGHT_COLUMNS)] == FLIGHT_COLUMNS
    assert len(fl) == out.detection.n - 1
    assert np.all(fl["duration"] > 0)
    assert set(fl["kind"]) <= {"free", "stick"}
    assert np.all(fl["penetration"] < 1e-5)           # ball stays inside the clearance
    assert tuple(out.reconstruction.impacts.columns) == IMPACT_STATE_COLUMNS
    # eq. 6: y_end - y_start = w_mean * duration
    assert np.allclose(fl["y_end"] - fl["y_start"], fl["w_mean"] * fl["duration"])


def test_sensor_resonance_does_not_spoil_the_ball():
    out, truth = analysed(0.009, ASYM + ("sensor_resonance",))
    rms, _ = _ball_rms(out, truth)
    assert rms < 0.05e-3


def test_friction_reconstruction():
    fx = ASYM + ("coulomb_friction=0.3",)
    out, truth = analysed(0.009, fx, mu=0.3)
    rms, _ = _ball_rms(out, truth)
    assert rms < 0.1e-3
    fl = out.reconstruction.flight_columns
    assert (fl["sign_changes"] > 0).any()   # z' changes sign inside some flights
    # straight lines (mu = 0) are clearly worse on the same data
    out0, _ = analysed(0.009, fx, mu=0.0)
    rms0, _ = _ball_rms(out0, truth)
    assert rms0 > 2 * rms


def test_eq8_is_the_constant_deceleration_limit_of_the_solver():
    """Without a sign change of z' the exact solver gives back paper eq. 8."""
    t_s, t_e = np.array([0.0, 0.0]), np.array([0.05, 0.08])
    y_s, y_e = np.array([0.0, 0.01]), np.array([0.02, -0.01])
    direction = np.array([1, -1])
    mu = 0.2

    def lo_v(t):
        return np.zeros_like(t)

    def lo_a(t):
        return np.zeros_like(t)

    ws, we = eq8_velocities(t_s, t_e, y_s, y_e, direction, mu)
    sol = solve_flights(t_s, t_e, y_s, y_e, lo_v, lo_a, mu)
    assert np.allclose(sol.w_start, ws, atol=1e-6)
    assert np.allclose(sol.w_end, we, atol=1e-6)
    assert np.all(np.abs(sol.closure) < 1e-9)
    # forward integration returns to the end position
    y_end, w_end = integrate_flights(t_s, t_e, y_s, sol.w_start, lo_v, lo_a, mu)
    assert np.allclose(y_end, y_e, atol=1e-8) and np.allclose(w_end, we, atol=1e-6)
    assert np.allclose(ws - we, 2 * direction * mu * G_ACCEL * (t_e - t_s) / 2)


def test_ball_sticks_to_a_slow_lo_under_friction():
    """z' reaches 0 while |x''| <= mu g: the ball rides with the LO (no sign flip)."""
    mu = 0.5
    t_s, t_e = np.array([0.0]), np.array([0.1])

    def lo_v(t):
        return 0.1 + 0.0 * t

    def lo_a(t):
        return np.zeros_like(t)

    # launched at 0.2 m/s against an LO at 0.1 m/s: slides 0.1 / (mu g) = 20 ms, then rides
    y_end, w_end = integrate_flights(t_s, t_e, np.zeros(1), np.array([0.2]), lo_v, lo_a, mu)
    t_slide = 0.1 / (mu * G_ACCEL)
    expect = 0.2 * t_slide - 0.5 * mu * G_ACCEL * t_slide ** 2 + 0.1 * (0.1 - t_slide)
    assert w_end[0] == pytest.approx(0.1)
    assert y_end[0] == pytest.approx(expect, abs=2e-6)


def test_laser_without_values_is_an_input_error():
    rec, _ = recording(0.009)
    det = detect_impacts(rec)
    bad = Recording(rec.t, np.full(rec.n, np.nan), rec.a, rec.xe, rec.meta)
    with pytest.raises(InputError, match="column 'x' has no finite value"):
        reconstruct(det, bad)
    with pytest.raises(InputError, match="mu must be in"):
        reconstruct(det, rec, mu=-0.1)


def test_a_recording_without_impacts_is_analysed():
    """No impact at all (a ball at rest in a wide clearance: the gap diagnosis's
    candidate models produce such recordings): the LO motion is still reconstructed,
    the tables are empty, nothing fails (bincount of no impacts is an integer array)."""
    from vidiscover.analysis import analyze
    from vidiscover.io import Metadata

    fs = 6400.0
    t = np.arange(32768) / fs
    rng = np.random.default_rng(3)
    xe = 1e-4 * np.sin(2 * np.pi * 8 * t)
    x = 3e-4 * np.sin(2 * np.pi * 8 * t) + 1e-6 * rng.standard_normal(t.size)
    a = -(2 * np.pi * 8) ** 2 * 3e-4 * np.sin(2 * np.pi * 8 * t) + 0.05 * rng.standard_normal(
        t.size)
    out = analyze(Recording(t, x, a, xe, Metadata(b=0.02, sample_rate=fs)),
                  n_boot=0)
    assert out.detection.n == 0 and out.reconstruction.n_flights == 0
    assert out.reconstruction.v.dtype == np.float64
    assert np.max(np.abs(out.reconstruction.x - x)) < 2e-5


@pytest.mark.slow
def test_the_filter_lag_is_taken_out_of_the_laser():
    """A causal anti-alias filter delays the laser as much as the accelerometer (its DC
    group delay, 343 us here); ``analyze`` advances the smooth acceleration by it, and
    the reconstruction pins its integral to the laser read as much later (``lo_lag``)
    for the impact states, exits and flights, so that they share the impacts' time
    frame. dev-009 (Hunt-Crossley walls, Chebyshev 6 at 5120 Hz): the laser then agrees
    with that LO to its noise (2.8 um for 2.9 um; 5.2 um with the laser left delayed) and
    r RMS per wall is off by 0.0001 and 0.0006 (0.0094 and 0.0078 before). The arrays
    x and v (read by the regime features) stay pinned to the laser as recorded."""
    from vidiscover.analysis import analyze
    from vidiscover.analysis.reconstruction import lo_lag
    from vidiscover.corpus import realism_case

    case = realism_case("dev", 9)
    sim = case.simulate()
    rec, imp = sim.recording, sim.truth.impacts
    out = analyze(rec, flight_law=(case.mu, case.theta), n_boot=0)
    assert lo_lag(out.detection) == pytest.approx(343e-6, abs=10e-6)
    assert out.reconstruction.position_noise <= 1.2 * case.sensors["x_noise"]
    side = np.asarray(imp.side)
    for s in ("right", "left"):
        w = out.restitution.wall(s)
        r_true = float(np.sqrt(np.mean(np.asarray(imp.r)[side == s] ** 2)))
        assert w.n >= 30 and abs(w.rms - r_true) <= 0.002, (s, w.rms, r_true)


def test_no_filter_lag_without_a_causal_filter():
    """The exact engine's linear-phase chain is delay-compensated: nothing is shifted."""
    from vidiscover.analysis.reconstruction import _advanced, lo_lag

    out, _ = analysed(0.009)
    assert lo_lag(out.detection) == 0.0
    y = np.arange(5.0)
    assert _advanced(y, y, 0.0) is y
    assert np.allclose(_advanced(y, y, 0.5), [0.5, 1.5, 2.5, 3.5, 4.0])


@pytest.mark.parametrize("part", [1 << 16, 37])
def test_penetration_is_each_flights_largest_excursion(monkeypatch, part):
    """_penetration (by parts, a reduceat per part) is, per flight, the largest
    |ball - LO| - b over the decimated samples strictly inside the flight, 0 where it
    never leaves the clearance or has no sample: checked against a plain loop over
    random flights, with parts small enough to split them across parts."""
    from vidiscover.analysis import reconstruction as rc

    monkeypatch.setattr(rc, "_PEN_PART", part)
    rng = np.random.default_rng(3)
    seen = []
    for _ in range(40):
        n, fs = int(rng.integers(50, 5000)), 1000.0
        t = np.arange(n) / fs
        x_f = rng.normal(size=n) * 1e-3
        m = int(rng.integers(1, 60))
        ts = np.sort(rng.uniform(0, t[-1], m))
        te = ts + rng.uniform(0, 0.3, m) * rng.integers(0, 2, m)   # some without samples
        ss, b = rng.choice([-1.0, 1.0], m), abs(rng.normal()) * 1e-3
        y0, w = rng.normal(size=m) * 2e-3, rng.normal(size=m) * 0.01
        got = rc._penetration(t, x_f, ts, te, ts.copy(), y0, w, ss, b, {}, 0.0, None, None)
        step = rc._PEN_STEP
        want = np.zeros(m)
        for i in range(m):
            k = np.arange(0, n, step)
            k = k[(t[k] > ts[i]) & (t[k] < te[i])]
            if k.size:
                y = y0[i] + w[i] * (t[k] - ts[i])
                want[i] = max(0.0, float(np.max(np.abs(y - x_f[k]) - b)))
        assert np.array_equal(got, want)
        seen.append(got)
    seen = np.concatenate(seen)
    assert 0.2 < (seen > 0).mean() < 0.8          # both kinds of flights were checked


@pytest.mark.parametrize("kept", [0.4, 1.0])
def test_the_drift_is_read_at_block_centres_when_the_laser_has_gaps(kept):
    """A laser on its rails 60 % of the time (other-rig regime case 111 of seed 14001:
    the unknown initial velocity puts a 2.4 m/s slope on the drift). A block of the
    drift smoother partly on a rail has its mean at its kept samples' mean time, up to
    half a block (3 ms) from its centre: read at the centre, the smoothed drift was off
    by 4.6 mm and its derivative by 61 mm/s here (a quadratic drift, noise-free laser).
    Carried along the slope: 16 um (linear fills across the 15 ms rails of a curved
    drift) and 0.28 mm/s. Without gaps, the centres as they are: 4.5 um (linear
    between the centres)."""
    from vidiscover.analysis.reconstruction import _drift

    fs = 2560.0
    tr = np.arange(int(1.8 * fs)) / fs
    drift = 1.8e-3 + 2.4 * tr - 0.35 * tr ** 2
    x = 0.0175 * np.sin(2 * np.pi * 22.1 * tr)              # the LO, clipped at 10 mm
    ok = (np.abs(x) < 0.01) if kept < 1 else np.ones(tr.size, dtype=bool)
    assert abs(ok.mean() - kept) < 0.05
    xl = np.where(ok, x + drift, np.nan)
    D, Dd = _drift(tr, xl, x, ok, fs, 0.1)(tr)
    assert np.abs(D - drift).max() < (3e-5 if kept < 1 else 6e-6)    # 16 / 4.5 um
    inner = slice(100, -100)                 # (Dd is held beyond the end block centres)
    assert np.abs(Dd - (2.4 - 0.7 * tr))[inner].max() < 5e-4          # 0.28 mm/s


def test_the_lo_in_the_impacts_frame_is_one_time_frame():
    """test-033 (Kelvin-Voigt walls, Chebyshev-8 at 10240 Hz, 67 % of the laser on its
    rails): ``x``, pinned to the laser as recorded, takes its slow part from the laser
    and its fast part from the advanced acceleration, 0.70 % RMS of max |x| off the
    true LO; ``x_impacts``, one frame, 0.006 %. Without a causal lag it is ``x``."""
    from vidiscover.analysis import analyze
    from vidiscover.corpus import realism_case

    case = realism_case("test", 33)
    sim = case.simulate()
    out = analyze(sim.recording, flight_law=(case.mu, case.theta), n_boot=0)
    rc = out.reconstruction
    true = sim.result.evaluate(rc.t + sim.result.settle)["x"]
    m = slice(rc.t.size // 20, -(rc.t.size // 20))
    amp = np.abs(true).max()

    def rms(y):
        e = (y - true)[m]
        return np.sqrt(np.mean((e - e.mean()) ** 2)) / amp

    assert rms(rc.x_impacts) < 3e-4 < 3e-3 < rms(rc.x)        # 0.006 % / 0.70 %
    assert not rc.x_impacts.flags.writeable
    plain, _ = analysed(0.009)
    assert plain.reconstruction.x_impacts is plain.reconstruction.x


def test_the_lo_position_holds_to_the_end_of_a_record_of_any_length():
    """A record whose length is not a multiple of the drift's block (16 samples): the
    last few samples made a block of their own, which the drift's smoother placed a
    block after the one before while its mean lay up to a block later, on a residual as
    steep as the LO's unknown initial velocity; the LO position at the last impacts was
    off by 35 um here (up to 0.9 mm on the corpus's compliant records). Now within a few
    um (measured 1.1 um)."""
    from vidiscover import Effects, SensorConfig, preset, record, simulate
    from vidiscover.analysis import PulseModel, analyze

    res = simulate(preset("paper", b=0.009), Effects.parse(list(ASYM)), settle=10.0,
                   duration=5.1210938)
    rec, _ = record(res, SensorConfig(), seed=1)
    assert rec.t.size % 16 != 0
    out = analyze(rec, n_boot=0, pulse=PulseModel())
    det = out.detection
    x_true = np.asarray(res.evaluate(det.t + res.settle)["x"], float)
    x_est = np.asarray(out.reconstruction.impact_columns["x"], float)
    last = det.t > det.t.max() - 0.05
    assert last.sum() >= 2
    assert np.max(np.abs(x_est - x_true)[last]) < 5e-6
    assert np.max(np.abs(x_est - x_true)) < 5e-6


def test_the_jumps_are_counted_at_the_force_centroid():
    """dev-004 (compliant walls, learned contacts of a few hundred us): each velocity
    jump counted at the contact entry put the integrated LO position off by ``dv c``
    after it (``c`` the force's centroid), a square wave by wall that the drift smoother
    halved. Measured on the LO position at the impacts against the truth (mid-record):
    spread 11.4 -> 2.9 um, right-minus-left offset -24.3 -> -5.4 um."""
    from vidiscover.analysis import analyze
    from vidiscover.corpus import realism_case

    case = realism_case("dev", 4)
    sim = case.simulate(label=False)
    out = analyze(sim.recording, n_boot=0)
    det, rec = out.detection, out.recording
    e = (np.asarray(out.reconstruction.impact_columns["x"], float)
         - np.asarray(sim.result.evaluate(det.t + sim.result.settle)["x"], float))
    mid = (det.t > rec.t[0] + 0.2) & (det.t < rec.t[-1] - 0.2)
    right = det.sign > 0
    assert (mid & right).sum() >= 20 and (mid & ~right).sum() >= 20
    offset = np.median(e[mid & right]) - np.median(e[mid & ~right])
    assert abs(offset) < 10e-6                   # -5.4 um (-24.3 at the entry)
    assert np.std(e[mid]) < 5e-6                 # 2.9 um (11.4 at the entry)
