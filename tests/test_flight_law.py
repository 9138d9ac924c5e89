"""Flight-law discovery against simulated ground truth (mu, theta known).

Simulations: paper preset, constant r = 0.88 on both walls, settle 10 s, record
5.12 s, default sensors. Tolerances (issue 4): the right support (which of
friction / inclination are present, and no distractor), |mu error| <= 0.03,
|theta error| <= 0.3 deg, no friction term when mu = 0. Issue 10: a law that
misfits, is confounded or inadmissible is "not identified" with a reason and
carries no numbers as results.
"""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest

from vidiscover import Effects, SensorConfig, preset, record, simulate
from vidiscover.analysis import analyze, match_impacts
from vidiscover.discovery.flight_law import (
    DEFAULT_LIBRARY,
    MAX_MU_SE,
    MAX_THETA_SE,
    MAX_TILT_DEG,
    FlightLawResult,
    discover_flight_law,
    flight_law_mu_theta,
    reconstruct_with_law,
)
from vidiscover.errors import InputError
from vidiscover.params import G_ACCEL
from vidiscover.workflows import known_pulse

R = "asymmetric_restitution=0.88,0.88"
CLEARANCES = (0.006, 0.0075, 0.009)
MU_TOL, THETA_TOL = 0.03, 0.3


@functools.cache
def _case(b: float, mu: float, theta: float, seed: int = 1, walls: str = R,
          known: bool = False):
    """Analysis and truth of one recording; ``known``: the instrument is given
    (:func:`known_pulse`) instead of learned from the recording."""
    sim = simulate(preset("paper", b=b), Effects.parse(
        [f"coulomb_friction={mu}", f"inclination={theta}", walls]), settle=10.0,
        duration=5.12)
    rec, truth = record(sim, SensorConfig(), seed=seed)
    return analyze(rec, n_boot=10, pulse=known_pulse() if known else None), truth


@functools.cache
def _pooled(mu: float, theta: float, seed: int = 1, n_boot: int = 50):
    outs = [_case(b, mu, theta, seed)[0] for b in CLEARANCES]
    return discover_flight_law(outs, seed=0, n_boot=n_boot)


def _expected_terms(mu, theta):
    return {t for t, on in (("sgn(z')", mu > 0), ("1", theta != 0)) if on}


def _check(res: FlightLawResult, mu, theta):
    assert res.identified and res.reason is None, res.reason
    assert set(res.terms) == _expected_terms(mu, theta), res.equation
    assert abs(res.mu - mu) <= MU_TOL, res.equation
    assert abs(res.theta_deg - theta) <= THETA_TOL, res.equation
    if mu == 0:
        assert "sgn(z')" not in res.terms and res.mu == 0.0


@pytest.mark.parametrize("mu,theta", [(0.0, 0.0), (0.3, 0.0), (0.0, 2.0), (0.1, 1.0)])
def test_pooled_clearances_recover_support_and_values(mu, theta):
    res = _pooled(mu, theta)
    _check(res, mu, theta)
    assert res.collinearity < 0.99 and not res.warnings
    # the intervals hold the estimate and are narrower than the tolerances
    assert res.mu_ci[0] <= res.mu <= res.mu_ci[1]
    assert res.theta_ci[0] <= res.theta_deg <= res.theta_ci[1]
    assert res.mu_ci[1] - res.mu_ci[0] < 2 * MU_TOL
    assert res.theta_ci[1] - res.theta_ci[0] < 2 * THETA_TOL
    assert res.n_flights > 200 and res.n_equations > 200


def _assert_no_numbers(res: FlightLawResult):
    """Not identified: a reason, and no mu, theta, terms or intervals as results."""
    assert not res.identified and res.reason and "\n" not in res.reason
    d = json.loads(json.dumps(res.to_dict()))
    assert d["identified"] is False and d["reason"] == res.reason
    assert d["mu"] is None and d["theta_deg"] is None and d["terms"] == []
    assert d["mu_ci"] == [None, None] and d["theta_ci"] == [None, None]
    assert d["equation"] == "not identified"
    with pytest.raises(InputError, match="not identified"):
        flight_law_mu_theta(res)


def _launch_error(out, truth, law) -> float:
    """RMS error (m/s) of the ball launch velocities re-solved with ``law``."""
    t_true, w_true = truth.impacts.t, truth.impacts.w_plus
    ie, it = match_impacts(out.detection.t, t_true)
    w_at = np.full(out.detection.n, np.nan)
    w_at[ie] = w_true[it]
    sol = reconstruct_with_law(out, law)
    ref = w_at[out.reconstruction.flight_columns["i_start"][sol["flight"]]]
    ok = np.isfinite(ref)
    return float(np.sqrt(np.mean((sol["w_start"][ok] - ref[ok]) ** 2)))


@pytest.mark.parametrize("mu,theta", [(0.0, 0.0), (0.3, 0.0), (0.0, 2.0), (0.1, 1.0)])
def test_single_recording_at_9mm_is_right_or_says_it_is_confounded(mu, theta):
    """At b = 9 mm the orbit is period-1 with two impacts per cycle: every tent sees
    the same pair of flights, so only one combination of mu and theta is determined.
    The result must then say so (not identified, no numbers); the combination kept
    as a diagnostic still removes at least half of the launch-velocity error of
    straight flights (measured: 20-44 % left) or is below 1 mm/s; otherwise it must
    meet the tolerances."""
    out, truth = _case(0.009, mu, theta)
    res = discover_flight_law([out], n_boot=100)
    if res.collinearity > 0.99:
        _assert_no_numbers(res)
        assert "confounded" in res.reason
        diag = res.diagnostic
        combo = _launch_error(out, truth, (max(diag["mu"], 0.0), diag["theta_deg"]))
        assert combo <= max(0.5 * _launch_error(out, truth, (0.0, 0.0)), 1e-3)   # m/s
    else:
        if mu == 0 and theta == 0:
            assert res.terms == [], res.equation        # nothing to explain
        _check(res, mu, theta)


def test_standard_errors_say_what_the_flights_determine():
    """Pooled clearances determine mu and theta (standard errors measured 0.0027 and
    0.036 deg, far below MAX_MU_SE and MAX_THETA_SE); one clearance does not (0.16 and
    2.7 deg): not identified, with the reason. The jumps' precision through the default
    sensors, measured in the recordings: 0.58 %."""
    pooled = _pooled(0.1, 1.0)
    assert pooled.identified
    assert pooled.mu_se < 0.005 and pooled.theta_se < 0.06
    assert 0.004 < pooled.precision < 0.008 and pooled.misfit < max(0.01, pooled.precision)
    d = pooled.to_dict()
    assert d["precision"] == pytest.approx(pooled.precision)
    assert d["mu_se"] == pytest.approx(pooled.mu_se)
    single = discover_flight_law([_case(0.009, 0.1, 1.0)[0]], n_boot=0)
    assert not single.identified and single.mu_se > MAX_MU_SE
    assert single.theta_se > MAX_THETA_SE
    assert "do not determine the friction" in single.reason
    assert "pool recordings at several clearances" in single.reason


def test_feedback_into_reconstruction_matches_true_ball_velocities():
    """Flights re-solved with the identified law give the true launch velocities;
    the straight-line (mu = 0) reconstruction does not."""
    mu, theta = 0.3, 1.0
    res = discover_flight_law([_case(b, mu, theta)[0] for b in CLEARANCES], n_boot=0)
    m, th = flight_law_mu_theta(res)
    assert abs(m - mu) <= MU_TOL and abs(th - theta) <= THETA_TOL
    out, truth = _case(0.009, mu, theta)
    errs = {name: _launch_error(out, truth, law)
            for name, law in (("identified", res), ("straight", (0.0, 0.0)))}
    assert errs["identified"] < 0.01                   # m/s, ball speeds ~0.3-0.6 m/s
    assert errs["straight"] > 5 * errs["identified"]


def test_paper_walls_with_chatter_are_flagged_not_trusted():
    """With the paper's walls (r_left = 0.2) the ball chatters on the left wall and
    its last re-impacts are too weak to detect: the velocity links of the weak form
    break. The result must say so instead of passing for a law."""
    outs = [_case(b, 0.1, 1.0, walls="asymmetric_restitution=0.88,0.20")[0]
            for b in CLEARANCES]
    res = discover_flight_law(outs, n_boot=0, max_iter=3)
    assert res.misfit > 0.01
    _assert_no_numbers(res)
    assert "weak form does not hold" in res.reason
    assert res.to_dict()["diagnostic_fit"]["terms"]          # the raw fit is kept apart
    clean = _pooled(0.1, 1.0)
    assert clean.misfit < 0.005                      # ~0.1 %: pulse-area precision


def test_result_contract_and_determinism():
    res = _pooled(0.1, 1.0)
    again = discover_flight_law([_case(b, 0.1, 1.0)[0] for b in CLEARANCES], seed=0,
                                n_boot=50)
    assert again.to_dict() == res.to_dict()
    d = json.loads(json.dumps(res.to_dict()))
    for key in ("mu", "theta_deg", "terms", "equation", "mu_ci", "theta_ci", "n_flights",
                "identified", "reason", "diagnostic_fit", "level"):
        assert key in d
    assert d["identified"] is True and d["reason"] is None
    assert d["diagnostic_fit"]["mu"] == d["mu"]
    assert d["terms"] == res.terms and len(d["mu_ci"]) == 2
    assert res.equation.startswith("y'' = ")
    # the equation is the kept terms with their coefficients (3 significant digits)
    c = dict(zip(res.terms, res.coefficients, strict=True))
    c_sgn = c["sgn(z')"]
    assert f"{abs(c_sgn):.3g} sgn(z')" in res.equation
    assert math.isclose(res.mu, -c_sgn / G_ACCEL, rel_tol=1e-9)
    assert set(res.inclusion) == set(DEFAULT_LIBRARY)
    assert res.inclusion["sgn(z')"] > 0.9 and res.inclusion["1"] > 0.9
    assert flight_law_mu_theta(res) == (res.mu, res.theta_deg)


def test_bad_input_errors():
    out = _case(0.009, 0.0, 0.0)[0]
    with pytest.raises(InputError, match="at least one AnalysisResult"):
        discover_flight_law([])
    with pytest.raises(InputError, match="unknown flight-law term"):
        discover_flight_law([out], library=("1", "sgn(z')", "drag"))
    with pytest.raises(InputError, match="library must contain '1'"):
        discover_flight_law([out], library=("sgn(z')", "z'"))
    with pytest.raises(InputError, match="n_boot must be"):
        discover_flight_law([out], n_boot=-1)
    with pytest.raises(InputError, match="max_tilt_deg must be"):
        discover_flight_law([out], max_tilt_deg=0)
    with pytest.raises(InputError, match="max_terms must be"):
        discover_flight_law([out], max_terms=1)
    with pytest.raises(InputError, match="FlightLawResult"):
        flight_law_mu_theta((0.1, 0.0))


def test_tilt_beyond_the_admissible_bound_is_not_a_result():
    """theta = 2 deg pooled, with the admissible tilt narrowed to 1 deg: the fit is
    inadmissible, so no numbers; the default bound (10 deg) identifies it."""
    outs = [_case(b, 0.0, 2.0)[0] for b in CLEARANCES]
    narrow = discover_flight_law(outs, n_boot=0, max_tilt_deg=1.0)
    _assert_no_numbers(narrow)
    assert "inadmissible inclination" in narrow.reason and "--max-tilt" in narrow.reason
    assert abs(narrow.diagnostic["theta_deg"] - 2.0) <= THETA_TOL
    wide = discover_flight_law(outs, n_boot=0)
    assert wide.identified and wide.max_tilt_deg == MAX_TILT_DEG == 10.0
    _check(wide, 0.0, 2.0)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_full_grid_pooled(seed):
    """mu in {0, 0.1, 0.3} x theta in {0, 1, 2} deg, clearances pooled.

    The flight law's own statistics over the grid, with the instrument given (the
    learned instrument's share is checked on the grid's corners above and on the
    realism corpus; learning it costs ~2 s per recording, 81 here)."""
    rights = 0
    for mu in (0.0, 0.1, 0.3):
        for theta in (0.0, 1.0, 2.0):
            res = discover_flight_law([_case(b, mu, theta, seed, known=True)[0]
                                       for b in CLEARANCES], n_boot=0)
            rights += set(res.terms) == _expected_terms(mu, theta)
            assert abs(res.mu - mu) <= MU_TOL and abs(res.theta_deg - theta) <= THETA_TOL
            if mu == 0:
                assert "sgn(z')" not in res.terms
    assert rights >= 9 * 0.95


def _rows(seed: int, n: int = 120):
    """Synthetic weak-form rows: tent integrals of (1, sgn(z')) over flights of varied
    durations (s) and speeds, as pooled clearances give."""
    rng = np.random.default_rng(seed)
    T = rng.uniform(0.01, 0.03, (n, 2))
    X = np.column_stack([T.sum(axis=1) / 2,
                         (T[:, 0] * rng.choice([-1, 1], n) + T[:, 1] * rng.choice([-1, 1], n)) / 2])
    return X, rng


def test_constrained_fit_reports_zero_friction_where_the_free_fit_dips_below_zero():
    """True mu = 0 with a 2 deg tilt: the free least squares lands at mu < 0 (the
    noise), which is inadmissible; the fit constrained to mu >= 0 keeps the constant
    alone and the tilt within 0.05 deg."""
    from vidiscover.discovery.flight_law import _select

    X, rng = _rows(3)
    g0 = G_ACCEL * math.sin(math.radians(2.0))
    # a small bias along the friction column, as the pulse areas' errors give
    Yn = (X @ np.array([g0, 0.0]) + rng.normal(0, 2e-4, X.shape[0])
          + 4e-4 * X[:, 1] / np.abs(X[:, 1]).mean())
    free = np.linalg.lstsq(X, Yn, rcond=None)[0]
    assert free[1] > 0                              # the free fit: mu < 0
    cands = [(), (0,), (1,), (0, 1)]
    coef, _ = _select(X, Yn, np.ones(2), cands, 1e-3, 4.0, friction=1)
    assert coef[1] == 0.0
    assert abs(math.degrees(math.asin(coef[0] / G_ACCEL)) - 2.0) < 0.05
    unconstrained, _ = _select(X, Yn, np.ones(2), cands, 1e-3, 4.0)
    assert unconstrained[1] > 0                     # what the constraint refuses


def test_wall_scale_test_sees_a_biased_wall_and_passes_a_clean_one():
    """A 3 % scale error of one wall's pulse areas moves the law: the statistic is far
    above chi2(2) 99 % (9.21); without it, it stays below."""
    from vidiscover.discovery.flight_law import _wall_scale_test

    X, rng = _rows(5, 300)
    side = rng.choice([1.0, -1.0], X.shape[0])
    jumps = side * rng.uniform(1.0, 3.0, X.shape[0]) + 0.5 * X[:, 1] * 100
    walls = np.column_stack([np.where(side > 0, jumps, 0.0), np.where(side < 0, jumps, 0.0)])
    law = np.array([G_ACCEL * math.sin(math.radians(1.0)), -0.1 * G_ACCEL])
    noise = rng.normal(0, 1e-3, X.shape[0])
    clean = _wall_scale_test(X, X @ law + noise, walls, 1e-3)
    biased = _wall_scale_test(X, X @ law + noise + 0.03 * walls[:, 0], walls, 1e-3)
    assert clean[0] < 9.21
    assert biased[0] > 9.21 and (biased[1] > 0.015 or biased[2] > 0.15)


def _exact_jumps(out, truth):
    """The analysis's flights with the true LO velocity jumps of the matched impacts."""
    from vidiscover.analysis.flights import FlightData

    fd = FlightData.of(out)
    t_true = np.asarray(truth.impacts.t, float)
    j = np.clip(np.searchsorted(t_true, fd.t_imp), 1, t_true.size - 1)
    j = np.where(np.abs(t_true[j - 1] - fd.t_imp) < np.abs(t_true[j] - fd.t_imp), j - 1, j)
    ok = np.abs(t_true[j] - fd.t_imp) < 5e-4
    dv = np.where(ok, np.asarray(truth.impacts.dv, float)[j], fd.dv)
    return fd.with_impacts(dv=dv, area=dv)


def test_exact_jumps_passed_as_flight_data_close_the_tents():
    """The true jumps in place of the pulse areas (FlightData.with_impacts, the
    benchmark's --oracle): the tents close (misfit ~0.1 %) and the law is mu = 0, no
    tilt."""
    recs = [_exact_jumps(*_case(b, 0.0, 0.0)) for b in CLEARANCES]
    res = discover_flight_law(recs, n_boot=0)
    assert res.identified, res.reason
    assert res.mu == 0.0 and abs(res.theta_deg) < 0.05
    assert res.misfit < 0.003


def test_with_impacts_moves_the_flights_and_checks_lengths():
    from vidiscover.analysis.flights import FlightData

    fd = FlightData.of(_case(0.006, 0.0, 0.0)[0])
    moved = fd.with_impacts(t=fd.t_imp + 1e-4)
    np.testing.assert_allclose(moved.ts, fd.ts + 1e-4)
    np.testing.assert_allclose(moved.te, fd.te + 1e-4)
    np.testing.assert_array_equal(moved.dv, fd.dv)
    np.testing.assert_array_equal(fd.t_imp + 1e-4, moved.t_imp)    # the original kept
    with pytest.raises(InputError, match="one value per impact"):
        fd.with_impacts(dv=fd.dv[:-1])


def test_a_negligible_negative_friction_is_zero_not_a_refusal():
    """dev-001 (no friction, no tilt) with the true jumps at the equivalent impacts
    closes to 0.00 % and lands at mu = -5e-5 with a standard error ~0: that is mu = 0.
    A fit clearly below 0 (beyond 0.005 and twice its standard error) is still refused."""
    from vidiscover.discovery.flight_law import _negative_friction

    assert not _negative_friction(-5e-5, 0.0)
    assert not _negative_friction(-0.004, 1e-4)
    assert not _negative_friction(-0.03, 0.02)
    assert _negative_friction(-0.02, 0.001)
    assert _negative_friction(-0.006, 0.0)


def test_equivalent_impacts_move_by_the_contact_geometry():
    """The centroid of the contact force later, along the approach line (|u-| dt beyond
    the wall); a scale on the centroids scales the move; the moved impacts are
    instantaneous; nothing moves for an instantaneous impact. (Until flight16 the time
    was tau / (1 + r), the lines through the entry and the exit on the wall: 170 us late
    on holdout6-001's r = 0.3 walls, and a Kelvin-Voigt exit is not on the wall.)"""
    from vidiscover.analysis.flights import FlightData

    fd = FlightData.of(_case(0.006, 0.0, 0.0)[0])
    assert not np.any(fd.centroid)                 # the exact engine's impacts
    fd.tau = np.full(fd.dv.size, 2e-4)
    fd.centroid = np.full(fd.dv.size, 1e-4)
    eq = fd.equivalent_impacts()
    ok = np.isfinite(fd.u_minus)
    assert ok.mean() > 0.9
    np.testing.assert_allclose(eq.t_imp - fd.t_imp, 1e-4, rtol=1e-9)
    beyond = np.abs(fd.u_minus[ok]) * 1e-4
    np.testing.assert_allclose((eq.y_imp - fd.y_imp)[ok],
                               fd.v_minus[ok] * 1e-4 + fd.sign[ok] * beyond, rtol=1e-9)
    assert not np.any(eq.tau) and not np.any(eq.centroid)
    short = fd.equivalent_impacts(0.5)
    np.testing.assert_allclose(short.t_imp - fd.t_imp, 5e-5, rtol=1e-9)
    with pytest.raises(InputError, match="scale"):
        fd.equivalent_impacts(-1.0)
    fd.centroid = np.zeros(fd.dv.size)
    still = fd.equivalent_impacts()
    np.testing.assert_array_equal(still.t_imp, fd.t_imp)
    np.testing.assert_array_equal(still.y_imp, fd.y_imp)


def test_force_centroids_are_the_learned_shapes_per_wall():
    """A half-sine given pulse: tau / 2 on both walls; a learned response: each wall's
    shape centroid times its duration (a front-loaded viscous shape well before tau / 2)."""
    from types import SimpleNamespace

    from vidiscover.acquisition import shape_centroid
    from vidiscover.analysis.flights import force_centroids

    sign = np.array([1.0, -1.0, 1.0])
    det = SimpleNamespace(sign=sign, response=None,
                          pulse=SimpleNamespace(tau=2e-4, skew=0.0, phase=0.0))
    np.testing.assert_allclose(force_centroids(det, np.full(3, 2e-4)), 1e-4, rtol=1e-6)
    right = SimpleNamespace(tau=4e-4, skew=0.4, phase=0.8)
    left = SimpleNamespace(tau=2e-4, skew=0.0, phase=0.0)
    det = SimpleNamespace(sign=sign, response=SimpleNamespace(
        model_for=lambda s: right if s > 0 else left))
    got = force_centroids(det, np.array([4e-4, 2e-4, 4e-4]))
    want = shape_centroid(0.4, 0.8) * 4e-4
    np.testing.assert_allclose(got, [want, 1e-4, want], rtol=1e-9)
    assert want < 2e-4 * 0.9


def test_a_law_that_moves_with_the_contact_geometry_is_not_identified():
    """The pooled mu = 0.1, theta = 1 deg law (identified, instantaneous impacts): told
    that the contacts lasted 1 ms, the equivalent impacts move the law far beyond its
    accuracy and it is not identified; with 20 us contacts it stays identified."""
    from vidiscover.analysis.flights import FlightData

    recs = [FlightData.of(_case(b, 0.1, 1.0)[0]) for b in CLEARANCES]
    for rec in recs:
        rec.tau = np.full(rec.dv.size, 1e-3)
        rec.centroid = rec.tau / 2
    res = discover_flight_law(recs, n_boot=0)
    assert not res.identified
    assert "where in the contact" in res.reason
    # the depths free do not excuse the contacts' times (with the placement test at
    # 0.5 instead of 0.3 this was identified at mu 0.132)
    res = discover_flight_law(recs, n_boot=0, penetration="free")
    assert not res.identified
    assert "where in the contact" in res.reason
    for rec in recs:
        rec.tau = np.full(rec.dv.size, 2e-5)
        rec.centroid = rec.tau / 2
    res = discover_flight_law(recs, n_boot=0)
    assert res.identified, res.reason
    assert abs(res.mu - 0.1) < MU_TOL and abs(res.theta_deg - 1.0) < THETA_TOL


def test_gain_basis_takes_out_a_gain_per_recording_and_wall():
    """The rows' transform (:meth:`_Tents.basis`): free gains, an orthonormal basis of the
    complement of the jumps per recording and wall (one row less each); a finite spread,
    the random-effects weighting ``T'T = (I + N N' sd^2 / s^2)^-1``; none, the identity."""
    from vidiscover.analysis.flights import FlightData
    from vidiscover.discovery.flight_law import _Tents

    recs = [FlightData.of(_case(b, 0.0, 0.0)[0]) for b in CLEARANCES[:2]]
    free = _Tents(recs, DEFAULT_LIBRARY, gain_sd=math.inf)
    N = free.gain_columns()
    assert N.shape == (free.n_rows, 4)                 # 2 recordings x 2 walls
    T = free.basis()
    assert free.n == free.n_rows - 4 == T.shape[0]
    np.testing.assert_allclose(T @ N, 0.0, atol=1e-12 * np.abs(N).max())
    np.testing.assert_allclose(T @ T.T, np.eye(free.n), atol=1e-10)
    sd = 0.004
    some = _Tents(recs, DEFAULT_LIBRARY, gain_sd=sd)
    s2 = (some.precision() * np.sqrt(np.mean(some.jumps() ** 2))) ** 2
    W = np.linalg.inv(np.eye(some.n_rows) + N @ N.T * sd ** 2 / s2)
    np.testing.assert_allclose(some.basis().T @ some.basis(), W, atol=1e-10)
    assert some.n == some.n_rows
    none = _Tents(recs, DEFAULT_LIBRARY, gain_sd=0.0)
    assert none.n == none.n_rows
    shared = _Tents(recs, DEFAULT_LIBRARY, gain_sd=math.inf, gain_per="recording")
    Ns = shared.gain_columns()
    np.testing.assert_array_equal(Ns, np.column_stack([N[:, 0] + N[:, 1], N[:, 2] + N[:, 3]]))
    assert shared.n == shared.n_rows - 2
    # a gain put into the residuals comes back (free) or shrunk towards 0 (finite sd)
    g = np.array([0.004, -0.002, 0.006, 0.001])
    np.testing.assert_allclose(free.gains(N @ g), g, rtol=1e-9)
    assert np.all(np.abs(some.gains(N @ g)) < np.abs(g))


def test_free_jump_gains_refuse_a_wall_whose_areas_are_far_off():
    """One recording's right-wall jumps 6 % too large (far beyond the pulse-area gains of
    +0.03..+0.6 % the corpus shows): with the gains free the law is not identified, and
    the reason says which gain it would take; a bad spread is an input error."""
    recs = [_exact_jumps(*_case(b, 0.1, 1.0)) for b in CLEARANCES]
    fd = recs[1]
    g = np.where(fd.sign > 0, 0.06, 0.0)
    recs[1] = fd.with_impacts(dv=fd.dv * (1 + g), area=fd.area * (1 + g))
    res = discover_flight_law(recs, n_boot=0, jump_gain_sd=math.inf)
    _assert_no_numbers(res)
    assert "pulse areas of one recording at one wall would be +" in res.reason
    gains = res.diagnostic["jump_gains"]
    assert len(gains) == 6 and abs(gains[2] - 0.06) < 0.02, gains
    with pytest.raises(InputError, match="jump_gain_sd"):
        discover_flight_law(recs, n_boot=0, jump_gain_sd=-1.0)
    with pytest.raises(InputError, match="jump_gain_per"):
        discover_flight_law(recs, n_boot=0, jump_gain_per="impact")


def test_a_kept_distractor_has_the_standard_errors_of_its_own_support():
    """A distractor nearly collinear with sgn(z') (as z' is over a flight's speeds): the
    friction coefficient of the law that keeps it is far less certain than in the
    (constant, friction) fit, and that is the standard error the law carries."""
    from vidiscover.discovery.flight_law import _standard_errors, _support_errors

    X, rng = _rows(7, 200)
    extra = X[:, 1] * rng.uniform(0.9, 1.1, X.shape[0])
    Theta = np.column_stack([X, extra])
    Y = X @ np.array([0.17, -0.98]) + rng.normal(0, 1e-4, X.shape[0])
    base = _standard_errors(X, Y, 1e-4)
    sup = _support_errors(Theta, Y, [0, 1, 2], 0, 1, 1e-4)
    assert sup[0] > 5 * base[0] and sup[1] >= 0.0
    assert _support_errors(Theta, Y, [0, 1], 0, 1, 1e-4) == (0.0, 0.0)


def test_a_free_gain_per_recording_takes_out_a_common_scale_of_its_pulse_areas():
    """Each recording's jumps 0.4 / 0.6 / 0.3 % too large (the corpus's pulse areas carry
    such gains, nearly equal at both walls): taken as they are, the law keeps the
    distractor z'^3 and friction 0.092; with one free gain per recording it is the law
    (mu 0.1000, theta 1.001 deg) and the gains come back to 0.01 %."""
    gains = (0.004, 0.006, 0.003)
    recs = []
    for b, g in zip(CLEARANCES, gains, strict=True):
        fd = _exact_jumps(*_case(b, 0.1, 1.0))
        recs.append(fd.with_impacts(dv=fd.dv * (1 + g), area=fd.area * (1 + g)))
    tied = discover_flight_law(recs, n_boot=0)
    assert not (tied.identified and set(tied.terms) == {"1", "sgn(z')"}
                and abs(tied.mu - 0.1) < 0.005), tied.equation
    res = discover_flight_law(recs, n_boot=0, jump_gain_sd=math.inf,
                              jump_gain_per="recording")
    _check(res, 0.1, 1.0)
    assert abs(res.mu - 0.1) < 0.002 and abs(res.theta_deg - 1.0) < 0.02
    np.testing.assert_allclose(res.diagnostic["jump_gains"], gains, atol=1e-4)


def _outward(recs, leads):
    """The records with every impact ``sign |u-| lead`` beyond its wall (the learned
    entry leading the true one by ``lead`` s, counted as penetration: holdout6-010's
    equivalent impacts 16-26 us early at the entry, 45-120 um outward)."""
    out = []
    for rec, lead in zip(recs, leads, strict=True):
        depth = rec.sign * np.nan_to_num(np.abs(rec.u_minus)) * lead
        out.append(rec.with_impacts(y=rec.y_imp + depth))
    return out


def test_depth_columns_are_the_rows_change_per_second_of_penetration():
    """Moving one recording's impacts sign |u-| d outward changes its raw rows by d
    times its depth column and leaves the others; the free depths' basis is orthonormal
    and annihilates the columns (one row less per recording)."""
    from vidiscover.discovery.flight_law import _Tents

    recs = [_exact_jumps(*_case(b, 0.0, 0.0)) for b in CLEARANCES]
    lib = ("1", "sgn(z')")
    tents = _Tents(recs, lib, depth_free=True)
    moved = _Tents(_outward(recs, (0.0, 2e-5, 0.0)), lib, depth_free=True)
    D = tents.depth_columns()
    assert D.shape == (tents.n_rows, 3)
    dY = moved.assemble_raw(0.0, 0.0)[1] - tents.assemble_raw(0.0, 0.0)[1]
    np.testing.assert_allclose(dY, 2e-5 * D[:, 1], rtol=1e-6, atol=1e-12)
    T = tents.basis()
    assert T.shape == (tents.n_rows - 3, tents.n_rows) and tents.n == tents.n_rows - 3
    np.testing.assert_allclose(T @ D, 0.0, atol=1e-9 * np.abs(D).max())
    np.testing.assert_allclose(T @ T.T, np.eye(T.shape[0]), atol=1e-10)


def test_free_penetration_depths_take_out_equivalent_impacts_placed_too_far_out():
    """The exact jumps of mu 0.1 / theta 1 deg with every impact 80-150 us x |u-|
    (35-90 um) beyond its wall (the analysis's equivalent impacts on holdout6-009/-010:
    35-120 um out, the learned entry leading the true one): taken as they are the law
    keeps z'^3 and lands at mu 0.109 / theta 1.04 deg; with one free penetration time per
    recording (``penetration="free"``) it is the law, mu 0.0995 / theta 0.989 deg."""
    recs = _outward([_exact_jumps(*_case(b, 0.1, 1.0)) for b in CLEARANCES],
                    (1e-4, 1.5e-4, 0.8e-4))
    tied = discover_flight_law(recs, n_boot=0)
    assert not (tied.identified and set(tied.terms) == {"1", "sgn(z')"}
                and abs(tied.mu - 0.1) < 0.005), tied.equation
    res = discover_flight_law(recs, n_boot=0, penetration="free")
    _check(res, 0.1, 1.0)
    assert abs(res.mu - 0.1) < 0.002 and abs(res.theta_deg - 1.0) < 0.02
    with pytest.raises(InputError, match="penetration"):
        discover_flight_law(recs, n_boot=0, penetration="true")


def test_a_law_that_moves_between_recordings_is_not_identified():
    """The exact jumps of mu 0.1 / theta 1 deg with the 7.5 mm recording's pulse areas
    0.6 % too large at the right wall and 0.6 % too small at the left (walls of unequal
    stiffness, seen by that recording only; the wrong laws of spent holdout10): the fit
    lands at mu 0.117 / theta 1.28 deg, 13 and 18 of its standard errors off (0.0013,
    0.015 deg). Left out one at a time, the recordings spread theta by 0.27 deg
    (jackknife): not identified. The clean pool's jackknife spread is 0.003 deg; a pool of
    two recordings is not checked."""
    clean = [_exact_jumps(*_case(b, 0.1, 1.0)) for b in CLEARANCES]
    recs = list(clean)
    fd = clean[1]
    s = np.where(fd.sign > 0, 1.006, 0.994)
    recs[1] = fd.with_impacts(dv=fd.dv * s, area=fd.area * s)
    res = discover_flight_law(recs, n_boot=0)
    _assert_no_numbers(res)
    assert "moves between recordings" in res.reason
    jk = res.diagnostic["jackknife"]
    assert jk["G"] == 3 and 0.2 < jk["theta_se"] < 0.35 and res.theta_se < 0.03
    d = json.loads(json.dumps(res.to_dict()))       # the spread goes into discovery.json
    assert d["jackknife"] == {"n_recordings": 3, "mu_se": pytest.approx(jk["mu_se"]),
                              "theta_se": pytest.approx(jk["theta_se"])}
    assert abs(res.diagnostic["theta_deg"] - 1.0) > 10 * res.theta_se
    ok = discover_flight_law(clean, n_boot=0)
    _check(ok, 0.1, 1.0)
    assert ok.diagnostic["jackknife"]["theta_se"] < 0.01
    assert ok.diagnostic["jackknife"]["mu_se"] < 0.001
    # two recordings: the one left alone (9 mm, a periodic orbit) is confounded and its fit
    # moves by its own imprecision (0.26 deg); no check, the pooled law stands
    two = discover_flight_law([_case(b, 0.1, 1.0)[0] for b in (0.006, 0.009)], n_boot=0)
    _check(two, 0.1, 1.0)
    assert two.diagnostic["jackknife"]["G"] == 2 and two.to_dict()["jackknife"] is None


def test_the_contact_placement_joins_the_standard_errors(monkeypatch):
    """The placement check (:func:`_geometry_shift`: the law's move with the learned
    contact durations 0.3 times as long) as an uncertainty: half the move joins the fit's
    standard errors in quadrature, and the totals decide against MAX_MU_SE / MAX_THETA_SE.
    On the pooled mu 0.1 / theta 1 deg recordings (fit se measured 0.003 / 0.04 deg), a
    move of -0.02 in mu (1.3 times the bound: refused by the old rule, which bounded the
    move itself; spent holdout12-010 moved -0.023 with se 0.001 and was right) gives a
    total of 0.0104: identified, reported with that se; -0.03 gives 0.0153: refused,
    and so for theta (-0.25 deg -> 0.13 deg identified, -0.32 deg -> 0.166 refused)."""
    import vidiscover.discovery.flight_law as fl
    from vidiscover.analysis.flights import FlightData

    recs = [FlightData.of(_case(b, 0.1, 1.0)[0]) for b in CLEARANCES]

    def run(move):
        monkeypatch.setattr(fl, "_geometry_shift", lambda *a, **k: move)
        return discover_flight_law(recs, n_boot=0)

    still = run((0.0, 0.0))
    _check(still, 0.1, 1.0)
    se_mu, se_th = still.mu_se, still.theta_se
    assert 0.002 < se_mu < 0.004 and 0.03 < se_th < 0.05
    res = run((-0.02, 0.05))
    _check(res, 0.1, 1.0)
    assert res.mu_se == pytest.approx(math.hypot(se_mu, 0.01), rel=1e-9)
    assert res.theta_se == pytest.approx(math.hypot(se_th, 0.025), rel=1e-9)
    assert res.diagnostic["placement"] == {"mu": -0.02, "theta_deg": 0.05, "mu_se": 0.01,
                                           "theta_se": 0.025}
    # ... and discovery.json carries it beside the totals
    js = res.to_dict()
    assert js["placement"] == res.diagnostic["placement"]
    assert js["mu_se"] == pytest.approx(res.mu_se) and still.to_dict()["placement"] == {
        "mu": 0.0, "theta_deg": 0.0, "mu_se": 0.0, "theta_se": 0.0}
    res = run((-0.03, 0.05))
    _assert_no_numbers(res)
    assert "where in the contact" in res.reason and "do not determine" not in res.reason
    assert res.mu_se == pytest.approx(math.hypot(se_mu, 0.015), rel=1e-9)
    _check(run((0.0, -0.25)), 0.1, 1.0)
    res = run((0.0, -0.32))
    _assert_no_numbers(res)
    assert "where in the contact" in res.reason and res.theta_se > MAX_THETA_SE
