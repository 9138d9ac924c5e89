"""Tests of the exact event-driven simulator against exact answers and a reference.

Exact answers: the closed-form LO response (derived here, independently of
``vidiscover.simulation.flows``), momentum and the Newton-law energy balance at
every impact, the parabolic ball flight under friction and inclination. Reference:
``reference_ivp.py`` (solve_ivp DOP853 with events), for the nominal model and for
every catalogue effect switched on alone. Tolerances are stated where they are used.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vidiscover.effects import EFFECTS, Effects
from vidiscover.params import G_ACCEL, preset
from vidiscover.simulation import simulate
from vidiscover.simulation.roots import bracketed_newton

sys.path.insert(0, str(Path(__file__).resolve().parent))
from reference_ivp import reference_impacts  # noqa: E402

PAPER = preset("paper", b=0.009)
T20 = 20.0 / PAPER.frequency      # 20 forcing periods = 2.5 s

#: Values used when an effect is switched on alone; an effect added to the catalogue
#: later is picked up with its defaults.
EFFECT_VALUES = {
    "asymmetric_restitution": "asymmetric_restitution=0.8782,0.2018",
    "velocity_dependent_restitution":
        "velocity_dependent_restitution=right=power:0.3:0.5,left=linear:0.4:0.2",
    "coulomb_friction": "coulomb_friction=0.3",
    "inclination": "inclination=2",
    "sensor_resonance": "sensor_resonance=180,0.02",
    "excitation_distortion": "excitation_distortion=0.05,0.3,0.02,-1.0",
    "clearance_error": "clearance_error=0.0005",
    "contact_duration": "contact_duration=1e-4",
}


def effect_alone(name: str) -> Effects:
    return Effects.parse([EFFECT_VALUES.get(name, name)])


IMPACT_FIELDS = ("t", "side", "u_minus", "u_plus", "r", "v_minus", "v_plus", "w_minus",
                 "w_plus", "x", "stuck")

#: Cases with many impacts of every kind (chatter, sticking at walls and in the middle).
MIXED_CASES = {
    "nominal": [],
    "asymmetric": ["asymmetric_restitution=0.88,0.2"],
    "speed_law": [EFFECT_VALUES["velocity_dependent_restitution"]],
    "chatter_tilt": ["asymmetric_restitution=0.88,0.2", "inclination=3"],
    "friction_tilt": ["coulomb_friction=0.3", "inclination=3"],
}


# --------------------------------------------------------------------------- LO alone
def lo_closed_form(p, harmonics, t):
    """x, x', x'' of m x'' + c x' + k x = c xe' + k xe from rest, xe = A sum h sin(n w t + phi).

    Particular part: x_p = Im(H(w_n) A h e^{i(n w t + phi)}), H = (k + i c w)/(k - m w^2 + i c w);
    homogeneous part: exp(-s t)(C1 cos(wd t) + C2 sin(wd t)) with x(0) = x'(0) = 0.
    """
    m, c, k = p.m1, p.c1, p.k1
    xp = np.zeros_like(t)
    vp = np.zeros_like(t)
    ap = np.zeros_like(t)
    xp0 = vp0 = 0.0
    for n, h, phi in harmonics:
        w = n * 2 * math.pi * p.frequency
        amp = (k + 1j * c * w) / (k - m * w * w + 1j * c * w) * p.amplitude * h
        e = amp * np.exp(1j * (w * t + phi))
        xp += e.imag
        vp += (1j * w * e).imag
        ap += (-w * w * e).imag
        e0 = amp * np.exp(1j * phi)
        xp0 += e0.imag
        vp0 += (1j * w * e0).imag
    s = c / (2 * m)
    wd = math.sqrt(k / m - s * s)
    C1 = -xp0
    C2 = (-vp0 + s * C1) / wd
    E = np.exp(-s * t)
    cs, sn = np.cos(wd * t), np.sin(wd * t)
    xh = E * (C1 * cs + C2 * sn)
    vh = E * ((C2 * wd - s * C1) * cs - (C1 * wd + s * C2) * sn)
    ah = -(c / m) * vh - (k / m) * xh
    return xp + xh, vp + vh, ap + ah


@pytest.mark.parametrize("spec", [[], ["excitation_distortion=0.2,1.0,0.1,-0.5"]],
                         ids=["sine", "distorted"])
def test_lo_without_impacts_is_the_closed_form_forced_response(spec):
    fx = Effects.parse(spec)
    # ball at rest at the centre of a 0.5 m clearance: it never reaches a wall
    res = simulate(PAPER.replace(b=0.5), fx, settle=0.0, duration=3.0, initial=(0, 0, 0, 0))
    assert res.status == 0 and res.impacts.n == 0 and res.sticking == []
    t = np.linspace(0.0, 3.0, 4001)
    out = res.evaluate(t)
    x, v, a = lo_closed_form(PAPER, fx.harmonics(), t)
    # rounding only: 1e-12 of the response amplitude (x ~ 1e-2 m, x' ~ 0.5 m/s, x'' ~ 30 m/s^2)
    np.testing.assert_allclose(out["x"], x, rtol=0, atol=1e-12 * np.abs(x).max())
    np.testing.assert_allclose(out["xd"], v, rtol=0, atol=1e-12 * np.abs(v).max())
    np.testing.assert_allclose(out["xdd"], a, rtol=0, atol=1e-12 * np.abs(a).max())
    xe = sum(PAPER.amplitude * h * np.sin(n * 2 * np.pi * PAPER.frequency * t + ph)
             for n, h, ph in fx.harmonics())
    np.testing.assert_allclose(out["xe"], xe, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(out["y"], 0.0)   # no force on a frictionless ball


# --------------------------------------------------------------------------- impacts
@pytest.fixture(scope="module", params=sorted(MIXED_CASES))
def mixed(request):
    res = simulate(PAPER, Effects.parse(MIXED_CASES[request.param]), settle=0.0, duration=T20)
    assert res.status == 0 and res.impacts.n > 20
    return res


def test_momentum_is_conserved_at_every_impact(mixed):
    imp, p = mixed.impacts, mixed.params
    before = p.m1 * imp.v_minus + p.m2 * imp.w_minus
    after = p.m1 * imp.v_plus + p.m2 * imp.w_plus
    scale = p.m1 * np.abs(imp.v_minus) + p.m2 * np.abs(imp.w_minus)
    # 1e-12 relative to the momenta involved (the update is a few flops)
    assert np.all(np.abs(after - before) <= 1e-12 * scale)


def test_energy_loss_at_every_impact_is_newtons_law(mixed):
    imp, p = mixed.impacts, mixed.params
    mred = p.m1 * p.m2 / (p.m1 + p.m2)
    # the table is self-consistent: relative velocities, Newton's law, the stick rule
    np.testing.assert_allclose(imp.u_minus, imp.w_minus - imp.v_minus, rtol=0, atol=1e-15)
    np.testing.assert_allclose(imp.u_plus, imp.w_plus - imp.v_plus, rtol=0, atol=1e-15)
    free = ~imp.stuck
    np.testing.assert_allclose(imp.u_plus[free], -imp.r[free] * imp.u_minus[free], rtol=1e-12)
    assert np.all(imp.u_plus[imp.stuck] == 0.0)
    assert np.all(imp.r[imp.stuck] * np.abs(imp.u_minus[imp.stuck]) < 1e-4)   # default stick_speed
    assert np.all(np.sign(imp.u_minus) == imp.side)                          # moving into the wall
    r_eff = np.where(imp.stuck, 0.0, imp.r)
    ke_before = 0.5 * p.m1 * imp.v_minus ** 2 + 0.5 * p.m2 * imp.w_minus ** 2
    ke_after = 0.5 * p.m1 * imp.v_plus ** 2 + 0.5 * p.m2 * imp.w_plus ** 2
    expected = 0.5 * mred * (1.0 - r_eff ** 2) * imp.u_minus ** 2
    # rel 1e-9, with a floor at the rounding of the kinetic energies themselves
    err = np.abs((ke_before - ke_after) - expected)
    assert np.all(err <= 1e-9 * expected + 1e-14 * ke_before)


def test_restitution_follows_the_wall_laws():
    fx = Effects.parse([EFFECT_VALUES["velocity_dependent_restitution"]])
    res = simulate(PAPER, fx, settle=0.0, duration=T20)
    laws = fx.restitution_laws(PAPER.r)
    imp = res.impacts
    for side, name in ((1, "right"), (-1, "left")):
        sel = imp.side == side
        assert sel.sum() > 5
        np.testing.assert_allclose(imp.r[sel], laws[name](np.abs(imp.u_minus[sel])), rtol=1e-15)


# --------------------------------------------------------------------------- flights
def _flight_pieces(res, t):
    """Runs of grid points inside one smooth flight piece (no impact, no sticking,
    constant sign of z'), as index arrays."""
    out = res.evaluate(t)
    zd = out["yd"] - out["xd"]
    dt = t[1] - t[0]
    cut = np.zeros(t.size, dtype=bool)
    events = list(res.impacts.t)
    for a, b, _ in res.sticking:
        cut |= (t >= a - 2 * dt) & (t <= b + 2 * dt)
        events += [a, b]
    events = np.sort(np.asarray(events))
    # a boundary between two grid points: an event in between, or a reversal of z'
    boundary = np.sign(zd[1:]) != np.sign(zd[:-1])
    if events.size:
        k = np.searchsorted(events, t[:-1], side="right")
        nxt = events[np.clip(k, 0, events.size - 1)]
        boundary |= (k < events.size) & (nxt <= t[1:])
    pieces, start = [], 0
    for i in np.flatnonzero(boundary):
        pieces.append(np.arange(start, i + 1))
        start = i + 1
    pieces.append(np.arange(start, t.size))
    return out, zd, [p[~cut[p]] for p in pieces if (~cut[p]).sum() >= 3]


@pytest.mark.parametrize("spec,b", [
    (["coulomb_friction=0.3"], 0.009),
    (["coulomb_friction=0.3", "inclination=3"], 0.009),
    (["coulomb_friction=1.0"], 0.003),       # frequent stick-slip and quick reversals
    (["coulomb_friction=0.2", "inclination=20"], 0.006),
], ids=["mu0.3", "mu0.3_tilt3", "mu1.0_b3mm", "mu0.2_tilt20"])
def test_flights_are_parabolas_with_the_friction_and_tilt_acceleration(spec, b):
    fx = Effects.parse(spec)
    params = PAPER.replace(b=b)
    res = simulate(params, fx, settle=0.0, duration=T20)
    assert res.status == 0
    gs = G_ACCEL * math.sin(math.radians(fx.theta_deg))
    t = np.arange(0.0, T20, 1.5e-4)
    out, zd, pieces = _flight_pieces(res, t)
    assert len(pieces) > 10
    checked = 0
    for idx in pieces:
        s = np.sign(zd[idx])
        assert np.all(s == s[0])
        a = -fx.mu * G_ACCEL * s[0] + gs
        t0, y0, w0 = t[idx[0]], out["y"][idx[0]], out["yd"][idx[0]]
        tau = t[idx] - t0
        # exact up to rounding: 1e-12 m and 1e-10 m/s over flights of < 0.2 s
        np.testing.assert_allclose(out["y"][idx], y0 + w0 * tau + 0.5 * a * tau ** 2,
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(out["yd"][idx], w0 + a * tau, rtol=0, atol=1e-10)
        checked += idx.size
    assert checked > 0.3 * t.size
    # and anchored on the impact table: the flight leaving each wall, up to its first
    # reversal, is y = (x_i +/- b) + w_i^+ tau + a tau^2 / 2 with a from sgn(z'^+)
    imp = res.impacts
    for i in np.flatnonzero(~imp.stuck):
        t_next = imp.t[i + 1] if i + 1 < imp.n else T20
        tt = np.linspace(imp.t[i], t_next, 50)[1:-1]
        ev = res.evaluate(tt)
        # up to the first reversal (or stick, where z' = 0)
        keep = np.cumprod(np.sign(ev["yd"] - ev["xd"]) == np.sign(imp.u_plus[i])).astype(bool)
        a = -fx.mu * G_ACCEL * np.sign(imp.u_plus[i]) + gs
        tau = tt[keep] - imp.t[i]
        y0 = imp.x[i] + imp.side[i] * res.b
        np.testing.assert_allclose(ev["y"][keep], y0 + imp.w_plus[i] * tau + 0.5 * a * tau ** 2,
                                   rtol=0, atol=1e-12)


def test_frictionless_flight_is_a_straight_line():
    res = simulate(PAPER, settle=0.0, duration=T20)
    imp = res.impacts
    for i in range(imp.n - 1):
        tt = np.linspace(imp.t[i], imp.t[i + 1], 20)[1:-1]
        y = res.evaluate(tt)["y"]
        y0 = imp.x[i] + imp.side[i] * res.b
        np.testing.assert_allclose(y, y0 + imp.w_plus[i] * (tt - imp.t[i]), rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- reference
def _compare_with_reference(params, fx, duration, **kw):
    res = simulate(params, fx, settle=0.0, duration=duration, **kw)
    ref = reference_impacts(params, fx, duration=duration, **kw)
    assert res.status == 0 and ref.status == 0
    imp = res.impacts
    assert imp.n == ref.n, f"{imp.n} impacts, reference {ref.n}"
    np.testing.assert_array_equal(imp.side, ref.side)
    np.testing.assert_array_equal(imp.stuck, ref.stuck)
    return res, ref


@pytest.mark.parametrize("name", ["nominal"] + sorted(EFFECTS))
def test_impact_times_match_the_solve_ivp_reference(name):
    fx = Effects() if name == "nominal" else effect_alone(name)
    res, ref = _compare_with_reference(PAPER, fx, T20)
    assert res.impacts.n > 20
    # same impacts to 1e-6 s over 20 forcing periods (typically 1e-13 s; the nominal
    # transient amplifies the reference's ~1e-15 error to ~1e-7 s by 2.5 s)
    np.testing.assert_allclose(res.impacts.t, ref.t, rtol=0, atol=1e-6)
    assert len(res.sticking) == len(ref.sticking)
    if name != "nominal" and EFFECTS[name].acts_on == "sensor":
        # a sensor effect must not touch the dynamics at all
        nominal = simulate(PAPER, settle=0.0, duration=T20)
        for f in IMPACT_FIELDS:
            np.testing.assert_array_equal(getattr(res.impacts, f), getattr(nominal.impacts, f))
        t = np.linspace(0.0, T20, 2001)
        for key, val in nominal.evaluate(t).items():
            np.testing.assert_array_equal(res.evaluate(t)[key], val)


@pytest.mark.parametrize("spec,b", [
    (["coulomb_friction=1.0"], 0.003),
    (["coulomb_friction=1.0"], 0.0175),
    (["coulomb_friction=0.1", "excitation_distortion=0.2,1,0.1,-1"], 0.006),
    (["coulomb_friction=0.2", "clearance_error=-0.002"], 0.003),
    (["asymmetric_restitution=0.88,0.2", "inclination=-3"], 0.006),
], ids=["mu1_b3", "mu1_b17.5", "mu0.1_distorted", "mu0.2_b1mm", "chatter_tilt-3"])
def test_stick_slip_cases_match_the_reference(spec, b):
    # cases with quick slip-stick reversals, a grazing first flight (b = 17.5 mm) and
    # chatter; all agree to 1e-6 s (typically 1e-13 s)
    res, ref = _compare_with_reference(PAPER.replace(b=b), Effects.parse(spec), T20)
    np.testing.assert_allclose(res.impacts.t, ref.t, rtol=0, atol=1e-6)
    assert len(res.sticking) == len(ref.sticking)
    for (a0, a1, w), (b0, b1, v) in zip(res.sticking, ref.sticking, strict=True):
        # the reference releases a stuck ball 1e-9 m/s^2 past the friction limit
        assert w == v and abs(a0 - b0) <= 1e-6 and abs(a1 - b1) <= 1e-6


def test_first_impact_is_where_the_closed_form_lo_meets_the_resting_ball():
    # a ball at rest in the absolute frame stays at y = 0 until the LO, started from
    # rest, brings a wall to it: the first impact is the first root of x(t) = -/+ b of
    # the closed-form response, which both integrators must reproduce
    from scipy.optimize import brentq

    t = np.linspace(0.0, 2.5, 250001)
    x = lo_closed_form(PAPER, [(1, 1.0, 0.0)], t)[0]
    b = 0.8 * np.abs(x).max()
    k = int(np.argmax(np.abs(x) >= b))
    side = -int(np.sign(x[k]))          # x > 0 brings the left wall (z = -b) to the ball
    t_star = brentq(lambda s: abs(lo_closed_form(PAPER, [(1, 1.0, 0.0)], np.array([s]))[0][0])
                    - b, t[k - 1], t[k], xtol=1e-15)
    params = PAPER.replace(b=float(b))
    res = simulate(params, settle=0.0, duration=2.5, initial=(0, 0, 0, 0))
    ref = reference_impacts(params, duration=2.5, initial=(0, 0, 0, 0))
    assert res.impacts.side[0] == side and ref.side[0] == side
    assert abs(res.impacts.t[0] - t_star) <= 1e-12     # closed form vs closed form
    assert abs(ref.t[0] - t_star) <= 1e-9              # DOP853 with events


# --------------------------------------------------------------------------- chatter
def test_chatter_terminates_and_reports_sticking():
    fx = Effects.parse(["asymmetric_restitution=0.88,0.2", "inclination=3"])
    res = simulate(PAPER, fx, settle=5.0, duration=5.12)
    assert res.status == 0, res.message
    assert 0 < res.n_events < 400 * 10.12 * PAPER.frequency
    assert res.sticking, "a ball chattering on the left wall must stick to it"
    assert res.impacts.stuck.any()
    wheres = {w for _, _, w in res.sticking}
    assert wheres <= {"left", "right", "middle"} and "left" in wheres
    ends = np.array([(a, b) for a, b, _ in res.sticking])
    assert np.all(ends[:, 1] >= ends[:, 0]) and np.all(ends[1:, 0] >= ends[:-1, 1])
    # the ball really rests on the wall while stuck there
    for a, b, w in res.sticking:
        if w != "middle" and b - a > 1e-4:
            z = res.evaluate(np.linspace(a, b, 7))["z"]
            np.testing.assert_allclose(z, res.b if w == "right" else -res.b, rtol=0, atol=1e-15)
    # a record of it is finite and the record window is covered
    assert res.t_end == pytest.approx(10.12)
    assert np.isfinite(res.evaluate(np.linspace(0, 10.12, 5001))["x"]).all()


# --------------------------------------------------------------------------- grazing
def _max_excursion(params, fx, initial, t_end):
    """max |z| of a flight that never meets a wall (huge clearance), and where."""
    res = simulate(params.replace(b=0.5), fx, settle=0.0, duration=t_end, initial=initial)
    assert res.impacts.n == 0
    t = np.linspace(0.0, t_end, 200001)
    z = np.abs(res.evaluate(t)["z"])
    k = int(np.argmax(z))
    lo, hi = t[max(k - 1, 0)], t[min(k + 1, t.size - 1)]
    for _ in range(200):                      # golden-section refinement of the maximum
        m1, m2 = lo + 0.382 * (hi - lo), lo + 0.618 * (hi - lo)
        z1, z2 = np.abs(res.evaluate([m1, m2])["z"])
        lo, hi = (m1, hi) if z1 < z2 else (lo, m2)
        if hi - lo < 1e-13:
            break
    return float(np.abs(res.evaluate(0.5 * (lo + hi))["z"])[0])


GRAZING = {
    # ball at rest in the absolute frame: z = -x, the LO amplitude grows from rest
    "ball_at_rest": (Effects(), (0.0, 0.0, 0.0, 0.0), 2.5),
    # a ball thrown at 0.6 m/s and stopped by friction right at the wall
    "friction_stop": (Effects.parse(["coulomb_friction=1.0"]), (0.0, 0.0, 0.0, 0.6), 0.3),
}


@pytest.fixture(scope="module")
def grazing_b():
    return {k: _max_excursion(PAPER, fx, init, t_end) for k, (fx, init, t_end) in GRAZING.items()}


def _check_grazing(case, b, expect_impact):
    fx, init, t_end = GRAZING[case]
    res = simulate(PAPER.replace(b=b), fx, settle=0.0, duration=t_end, initial=init)
    assert res.status == 0
    if expect_impact is not None:
        assert (res.impacts.n > 0) == expect_impact, (case, b, res.impacts.n)
    # every impact where |z| = b (from the flight before it), to 1e-9 m
    before = np.nextafter(res.impacts.t, -np.inf)
    if res.impacts.n:
        z = res.evaluate(before)["z"]
        np.testing.assert_allclose(np.abs(z), b, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(np.sign(z), res.impacts.side)
    # and no wall was crossed unseen: |z| <= b everywhere (1e-9 m)
    z = res.evaluate(np.linspace(0.0, t_end, 50001))["z"]
    assert np.abs(z).max() <= b + 1e-9
    return res


@pytest.mark.parametrize("case", sorted(GRAZING))
@pytest.mark.parametrize("rel", [-1e-3, -1e-6, -1e-9, 1e-9, 1e-6, 1e-3])
def test_grazing_is_detected_on_both_sides_of_tangency(grazing_b, case, rel):
    # b a relative 1e-9 below the largest excursion (a 1e-11 m touch) must give an
    # impact, 1e-9 above must give none
    _check_grazing(case, grazing_b[case] * (1.0 + rel), expect_impact=rel < 0)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(rel=st.floats(-1e-4, 1e-4, allow_nan=False), case=st.sampled_from(sorted(GRAZING)))
def test_grazing_clearances_terminate_with_impacts_on_the_walls(grazing_b, rel, case):
    b = grazing_b[case] * (1.0 + rel)
    _check_grazing(case, b, expect_impact=None if abs(rel) < 1e-12 else rel < 0)


# --------------------------------------------------------------------------- determinism
def test_same_input_gives_identical_results():
    fx = Effects.parse(["asymmetric_restitution=0.88,0.2", "inclination=2",
                        "coulomb_friction=0.1", "excitation_distortion=0.05"])
    a = simulate(PAPER, fx, settle=1.0, duration=2.0)
    b = simulate(PAPER, fx, settle=1.0, duration=2.0)
    for f in IMPACT_FIELDS:
        np.testing.assert_array_equal(getattr(a.impacts, f), getattr(b.impacts, f))
    assert a.sticking == b.sticking and a.n_events == b.n_events
    t = np.linspace(0.0, 3.0, 3001)
    ea, eb = a.evaluate(t), b.evaluate(t)
    for key in ea:
        np.testing.assert_array_equal(ea[key], eb[key])


# --------------------------------------------------------------------------- root finder
def test_root_finder_stops_at_the_rounding_noise_of_f():
    # near a slow impact f = z - b is known only to ~1e-18 m while z' ~ 3e-4 m/s, so
    # Newton steps of ~1e-14 s bounce across the root: the iteration must stop there
    # (it used to cycle between two floats until maxiter)
    r = 1.974025213479369
    calls = []

    def f(x):
        calls.append(x)
        return (-3.469e-18 if x > r else 3.469e-18), -2.931e-4

    a, b = r - 1e-6, r + 1e-6
    root = bracketed_newton(f, a, b, f(a)[0], f(b)[0])
    assert abs(root - r) < 1e-13
    assert len(calls) < 20


def test_root_finder_is_exact_on_smooth_functions():
    root = bracketed_newton(lambda x: (math.cos(x) - x, -math.sin(x) - 1.0), 0.0, 1.0,
                            1.0, math.cos(1.0) - 1.0)
    assert abs(root - 0.7390851332151607) <= 2e-16
