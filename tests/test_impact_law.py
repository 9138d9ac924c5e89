"""Impact-law discovery against ground truth: synthetic (v, r) data and simulated rigs.

Simulated recordings: paper preset, b in {6, 7.5, 9} mm, default sensor noise,
per-wall restitution laws switched on with ``velocity_dependent_restitution``.
The form must be recovered exactly (kind and exponent, no grouping of exponents)
and the fitted r(v) must stay within 0.02 of the true law over the observed
speed range. The full recovery rate over many seeds is the ``slow`` test (and
``benchmarks/bench_discover.py`` prints it).
"""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest

from vidiscover import Effects, SensorConfig, preset, record, simulate
from vidiscover.analysis import analyze
from vidiscover.analysis.restitution import R_MAX
from vidiscover.discovery import (
    IMPACT_TERMS,
    ImpactLawResult,
    discover,
    discover_impact_law,
    impact_law,
    same_form,
)
from vidiscover.discovery.impact_law import (
    EFFECT_PER_SIGMA,
    RISING_FACTOR,
    SCALED_EFFECT_FLOOR,
    UNESTIMATED_SCATTER,
    _change_error,
)
from vidiscover.errors import InputError
from vidiscover.restitution_laws import RestitutionLaw
from vidiscover.workflows import known_pulse

CLEARANCES = (0.006, 0.0075, 0.009)
#: Per-wall laws (right, left): every form of the brief, distinct per wall.
CASES = (
    ("linear:0.95:0.12", "power:0.9:0.2"),
    ("power:0.15:0.5", "0.3"),
    ("0.88", "linear:0.6:0.6"),
    ("power:0.1:0.2", "power:0.7:0.5"),
)
R_TOL = 0.02


def exact_form(found: RestitutionLaw | None, truth: RestitutionLaw) -> bool:
    """Same kind and, for power laws, the same exponent (no equivalence groups)."""
    if found is None or found.kind != truth.kind:
        return False
    return truth.kind != "power" or math.isclose(found.p, truth.p)


def max_error(res: ImpactLawResult, truth: RestitutionLaw) -> float:
    grid = np.linspace(*res.speed_range, 200)
    return float(np.max(np.abs(res.predict(grid) - truth(grid))))


# ---------------------------------------------------------------- registry contract
@pytest.mark.parametrize("name", list(IMPACT_TERMS))
def test_every_registered_term_is_finite_and_consistent(name):
    term = IMPACT_TERMS[name]
    v = np.linspace(1e-3, 3.0, 400)
    out = term(v)
    assert out.shape == v.shape and np.all(np.isfinite(out))
    assert np.array_equal(term(-v), out)            # a function of |v|
    if term.exponent is not None:
        assert np.allclose(out, v ** term.exponent, rtol=1e-12)


# ---------------------------------------------------------------- synthetic truth
def synthetic(law: str, seed: int, n: int = 240, noise: float = 0.004,
              v_range=(0.2, 1.0)):
    rng = np.random.default_rng(seed)
    v = rng.uniform(*v_range, n)
    truth = RestitutionLaw.parse(law)
    return v, truth(v) + rng.normal(0.0, noise, n), truth


@pytest.mark.parametrize("law", ["0.85", "linear:0.95:0.2", "power:0.4:0.2",
                                 "power:0.3:0.5"])
def test_synthetic_forms_recovered_over_seeds(law):
    hits, errors = 0, []
    for seed in range(10):
        v, r, truth = synthetic(law, seed)
        res = discover_impact_law(v, r, seed=seed, n_boot=0)
        hits += exact_form(res.law, truth)
        errors.append(max_error(res, truth))
    assert hits >= 9, f"{law}: form recovered in {hits}/10"
    assert max(errors) < 0.01


def test_intervals_cover_the_true_coefficients():
    covered = 0
    for seed in range(10):
        v, r, _ = synthetic("linear:0.95:0.2", 100 + seed, n=150)
        res = discover_impact_law(v, r, seed=seed, n_boot=100)
        assert res.terms == ("1", "v")
        lo0, hi0 = res.ci["1"]
        lo1, hi1 = res.ci["v"]
        covered += (lo0 <= 0.95 <= hi0) and (lo1 <= -0.2 <= hi1)
    assert covered >= 7
    lo, mid, hi = res.band(np.linspace(*res.speed_range, 20))
    assert np.all(lo <= mid) and np.all(mid <= hi)


def test_comparison_with_a_constant_r():
    v, r, _ = synthetic("power:0.3:0.5", 3)
    dep = discover_impact_law(v, r, n_boot=0)
    assert dep.delta_aicc_vs_constant > 10 and dep.p_value_vs_constant < 1e-6
    v, r, _ = synthetic("0.85", 3)
    const = discover_impact_law(v, r, n_boot=0)
    assert not const.velocity_dependent
    assert const.delta_aicc_vs_constant < 4 and const.p_value_vs_constant > 1e-3
    assert const.alternative                      # the best rival is named


def test_weights_and_outlier_rejection_stop_chatter_faking_a_law():
    """Chatter: many slow impacts with noisy r, a few gross errors."""
    rng = np.random.default_rng(7)
    v = np.concatenate([rng.uniform(0.01, 0.1, 300), rng.uniform(0.3, 0.8, 120)])
    sigma = 2e-4 / v
    r = 0.3 + rng.normal(0.0, 1.0, v.size) * sigma
    r[:6] += 0.5                                  # missed re-impacts: r way off
    res = discover_impact_law(v, r, sigma=sigma, n_boot=0)
    assert res.formula == "r = 0.3" and res.n_outliers >= 6
    assert res.n + res.n_outliers == v.size
    naive = discover_impact_law(v, r, n_boot=0, outlier_z=None)
    assert abs(naive.predict(0.05) - 0.3) > abs(res.predict(0.05) - 0.3)


def test_same_seed_same_result_and_json_ready():
    v, r, _ = synthetic("linear:0.95:0.2", 5)
    a = discover_impact_law(v, r, seed=4, n_boot=30)
    b = discover_impact_law(v, r, seed=4, n_boot=30)
    assert np.array_equal(a.boot_coefficients, b.boot_coefficients)
    assert a.to_dict() == b.to_dict()
    doc = json.loads(json.dumps(a.to_dict(), allow_nan=False))
    assert doc["formula"] == a.formula and doc["n_boot"] == 30


def test_cv_criterion_also_recovers_the_form():
    v, r, truth = synthetic("power:0.3:0.5", 11)
    groups = np.arange(v.size) % 4
    res = discover_impact_law(v, r, groups=groups, criterion="cv", n_boot=0)
    assert exact_form(res.law, truth)


def test_degenerate_inputs_fall_back_with_a_warning():
    few = discover_impact_law([0.5, 0.6, 0.7], [0.8, 0.8, 0.8], n_boot=10)
    assert few.kind == "constant" and "min_impacts" in few.warning
    v = np.full(30, 0.5) + np.linspace(0, 0.01, 30)
    narrow = discover_impact_law(v, np.full(30, 0.7), n_boot=0)
    assert narrow.kind == "constant" and "span" in narrow.warning
    none = discover_impact_law([np.nan], [0.5], n_boot=0)
    assert none.kind == "undetermined" and none.n == 0 and none.n_dropped == 1


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"v": [0.1, 0.2], "r": [0.5]}, "same length"),
    ({"v": [-0.1] * 10, "r": [0.5] * 10}, "impact speeds >= 0"),
    ({"n_boot": -1}, "n_boot must be an integer >= 0"),
    ({"criterion": "bic"}, "criterion must be one of"),
    ({"terms": ["v^3"]}, "unknown impact term"),
    ({"sigma": [0.1]}, "one standard error per impact"),
    ({"outlier_z": 0}, "outlier_z must be None or a number > 0"),
])
def test_bad_input_names_the_problem(kwargs, match):
    args = {"v": np.linspace(0.2, 1, 10), "r": np.full(10, 0.8), **kwargs}
    with pytest.raises(InputError, match=match):
        discover_impact_law(args.pop("v"), args.pop("r"), **args)


def test_same_form_groups_only_what_it_declares():
    assert same_form("linear:1:0.2", "power:0.2:1")
    assert same_form("power:0.3:0.2", "power:0.1:0.25")
    assert not same_form("power:0.3:0.5", "power:0.3:0.2")
    assert not same_form("0.9", "linear:0.9:0.1") and not same_form(None, "0.9")


# ---------------------------------------------------------------- simulated rigs
@functools.cache
def _simulation(case: tuple[str, str], b: float):
    fx = Effects.parse([f"velocity_dependent_restitution=right={case[0]},left={case[1]}"])
    return simulate(preset("paper", b=b), fx, settle=5.0, duration=5.12)


def _recordings(case, seed: int, sensors: SensorConfig | None = None):
    return [record(_simulation(case, b), sensors or SensorConfig(), seed=100 * seed + k)[0]
            for k, b in enumerate(CLEARANCES)]


@pytest.mark.parametrize("case", CASES[:2], ids=lambda c: "/".join(c))
def test_simulated_clearance_sweep_recovers_each_wall(case):
    res = discover(_recordings(case, seed=1), n_boot=50, flight=False)
    for side, spec in zip(("right", "left"), case, strict=True):
        law, truth = res.impact_laws[side], RestitutionLaw.parse(spec)
        assert exact_form(law.law, truth), f"{side}: {law.formula} for {truth.formula}"
        assert max_error(law, truth) < R_TOL
        assert law.n >= 60 and set(res.impact_data[side]["group"]) == {0, 1, 2}
        lo, _, hi = law.band(np.linspace(*law.speed_range, 20))
        assert np.all(hi - lo < 0.02)
    summary = res.summary()
    assert summary["impact_law"]["right"]["formula"] == res.impact_laws["right"].formula
    assert summary["n_recordings"] == 3 and summary["flight"]["identified"] is False
    assert summary["flight"]["mu"] is None and summary["flight"]["reason"]


@pytest.mark.slow
def test_simulated_form_recovery_rate_over_seeds():
    """The impact law's own statistics over 4 cases x 5 seeds, with the instrument
    given (:func:`known_pulse`): the learned instrument's share is checked by the
    clearance-sweep test above and on the realism corpus (learning costs ~2 s per
    recording, 60 here)."""
    hits, total, worst = 0, 0, 0.0
    for case in CASES:
        for seed in range(5):
            analyses = [analyze(rec, n_boot=0, pulse=known_pulse())
                        for rec in _recordings(case, seed)]
            res = discover(analyses, n_boot=0, flight=False)
            for side, spec in zip(("right", "left"), case, strict=True):
                truth = RestitutionLaw.parse(spec)
                hits += exact_form(res.impact_laws[side].law, truth)
                total += 1
                worst = max(worst, max_error(res.impact_laws[side], truth))
    assert hits >= 0.9 * total, f"form recovered in {hits}/{total}"
    assert worst < R_TOL


def test_discovery_public_names_import():
    import vidiscover.discovery as disc

    assert all(not n.startswith("_") for n in disc.__all__)
    for n in disc.__all__:
        assert getattr(disc, n) is not None, n
    assert {"discover", "DiscoveryResult", "discover_impact_law"} <= set(disc.__all__)


def test_identified_friction_is_used_for_the_impact_laws():
    """With friction, r estimated at mu = 0 is biased; discover re-analyses at mu_id."""
    pytest.importorskip("vidiscover.discovery.flight_law")
    fx = Effects.parse(["coulomb_friction=0.3", "asymmetric_restitution=0.88,0.88"])
    recs = [record(simulate(preset("paper", b=b), fx, settle=5.0, duration=3.0), seed=k)[0]
            for k, b in enumerate(CLEARANCES)]
    refined = discover(recs, n_boot=0)
    assert refined.flight is not None and refined.mu_impacts == pytest.approx(0.3, abs=0.03)
    naive = discover(recs, n_boot=0, refine_mu=False)
    assert naive.mu_impacts == 0.0
    for side in ("right", "left"):
        grid = np.linspace(*refined.impact_laws[side].speed_range, 50)
        assert np.max(np.abs(refined.impact_laws[side].predict(grid) - 0.88)) < R_TOL
        assert np.max(np.abs(naive.impact_laws[side].predict(grid) - 0.88)) > 5 * R_TOL


# ---------------------------------------------------------------- no false discoveries
#: Constant-r walls recorded with seeds that the calibration of MIN_EFFECT and
#: EFFECT_PER_SCATTER did not see (tuning: 1000 * {0..3} + k; here 1000 * {20, 21} + k).
CONSTANT_CASES = (((0.88, 0.5), 1.0), ((0.7, 0.3), 3.0), ((0.95, 0.8), 10.0))


@functools.cache
def _constant_sims(walls: tuple[float, float], resonance: bool = True):
    fx = Effects.parse([f"asymmetric_restitution={walls[0]},{walls[1]}"]
                       + (["sensor_resonance"] if resonance else []))
    return tuple(simulate(preset("paper", b=b), fx, settle=5.0, duration=5.12)
                 for b in CLEARANCES)


def _constant_discovery(walls, noise: float, seed: int):
    sensors = SensorConfig().scaled_noise(noise)
    recs = [record(s, sensors, seed=1000 * seed + k)[0]
            for k, s in enumerate(_constant_sims(walls))]
    return discover(recs, n_boot=0, flight=False)


@pytest.mark.parametrize(("walls", "noise"), CONSTANT_CASES[:1])
def test_constant_r_with_sensor_resonance_is_reported_constant(walls, noise):
    """AICc alone calls these walls speed-dependent (sensor resonance biases r by
    ~1e-3); the effect rule reports a constant, within 0.01 of the truth."""
    res = _constant_discovery(walls, noise, seed=20)
    for side, r_true in zip(("right", "left"), walls, strict=True):
        law = res.impact_laws[side]
        assert law.kind == "constant", f"{side}: {law.formula} ({law.note})"
        assert abs(law.coefficients["1"] - r_true) < 0.01
        assert law.effect == 0.0 and law.effect_threshold >= 0.004


@pytest.mark.slow
@pytest.mark.parametrize(("walls", "noise"), CONSTANT_CASES)
@pytest.mark.parametrize("seed", [20, 21])
def test_constant_r_is_constant_on_held_back_seeds(walls, noise, seed):
    res = _constant_discovery(walls, noise, seed)
    for side in ("right", "left"):
        law = res.impact_laws[side]
        assert law.kind == "constant", f"{side}: {law.formula} ({law.note})"


def test_kelvin_voigt_walls_behind_a_butterworth_filter_are_constant():
    """Compliant Kelvin-Voigt walls (constant r) recorded through a causal 4th-order
    Butterworth anti-alias filter: the r estimates of the weak wall carry a ~1 %
    systematic curvature over the speeds, which a cancelling pair of nearly
    collinear terms (``1 - 2.6 v^0.2 + 2.2 v^0.25``) used to fit; both walls are
    reported constant."""
    fx = Effects.parse([])
    sims = [simulate(preset("paper", b=b), fx, settle=5.0, duration=5.12,
                     contact=["right=kelvin-voigt:k=3e7,r=0.85", "left=kelvin-voigt:k=3e7,r=0.5"])
            for b in CLEARANCES]
    sensors = SensorConfig(anti_alias="butter", aa_order=4, aa_cutoff=2500)
    res = discover([record(s, sensors, seed=30_000 + k)[0] for k, s in enumerate(sims)],
                   n_boot=0, flight=False)
    for side in ("right", "left"):
        law = res.impact_laws[side]
        assert law.kind == "constant" and law.n >= 100, f"{side}: {law.formula}"
    assert (res.impact_laws["left"].candidates["aicc"] == np.inf).any()   # cancelling fits


def _speeds(seed: int, n: int = 200):
    """Impact speeds like a pooled clearance sweep (m/s) and a seeded generator."""
    rng = np.random.default_rng(seed)
    return rng.uniform(0.3, 0.9, n), rng


def test_linear_law_is_found_speed_dependent():
    """r = 0.95 - 0.15 v at a scatter of 0.004: linear, within 0.005 of the truth."""
    for seed in range(5):
        v, rng = _speeds(seed)
        res = discover_impact_law(v, 0.95 - 0.15 * v + rng.normal(0, 0.004, v.size),
                                  n_boot=0, seed=seed)
        assert res.kind == "linear" and res.velocity_dependent, res.formula
        assert res.effect > res.effect_threshold
        assert max_error(res, RestitutionLaw.parse("linear:0.95:0.15")) < 0.005


def test_hunt_crossley_law_is_found_with_its_alpha():
    """Exact Hunt-Crossley restitution, alpha = 0.35 s/m (the independent P02 walls)."""
    from vidiscover.discovery.impact_terms import hunt_crossley_restitution

    for seed in range(5):
        v, rng = _speeds(seed)
        r = hunt_crossley_restitution(0.35 * v) + rng.normal(0, 0.004, v.size)
        res = discover_impact_law(v, r, n_boot=0, seed=seed)
        assert res.kind == "hunt-crossley", res.formula
        alpha = res.coefficients["hunt_crossley(alpha v)"]
        assert abs(alpha - 0.35) < 0.01
        grid = np.linspace(*res.speed_range, 50)
        assert np.max(np.abs(res.predict(grid) - hunt_crossley_restitution(0.35 * grid))) \
            < 0.004


def test_hunt_crossley_shape_matches_its_closed_forms():
    """r_HC(x) against a root of the implicit relation and its series 1 - x + x^2."""
    from scipy.optimize import brentq

    from vidiscover.discovery.impact_terms import hunt_crossley_restitution

    for x in (0.02, 0.1, 0.3, 1.0, 3.0):
        s = 1.5 * x
        ref = brentq(lambda q, s=s: s - np.log1p(s) + q * s + np.log1p(-q * s),
                     1e-9, (1 - 1e-12) / max(s, 1.0))
        assert abs(float(hunt_crossley_restitution(x)) - ref) < 1e-9
    x = np.array([1e-3, 5e-3])
    assert np.allclose(hunt_crossley_restitution(x), 1 - x + x ** 2, atol=2e-8)


def test_power_033_outside_the_library_is_reported_as_a_neighbour():
    """r = 1 - 0.3 v^0.33 is not in the library. What it reports (measured, 5 seeds):
    a two-parameter neighbour ``r0 + c f(v)`` such as ``r = 1.08 - 0.38 v^0.25`` or
    ``r = 0.61 + 0.25 exp(-v)`` (kind "generic": no one-parameter power law fits
    within the AICc window), speed-dependent, its curve
    within 0.004 of the truth over the observed speeds; the band at 1.4 x the
    fastest speed still holds the truth."""
    truth = RestitutionLaw("power", a=0.3, p=0.33)
    for seed in range(5):
        v, rng = _speeds(seed)
        res = discover_impact_law(v, truth(v) + rng.normal(0, 0.004, v.size), n_boot=50,
                                  seed=seed)
        assert res.velocity_dependent and res.kind == "generic", res.formula
        assert len(res.terms) == 2 and res.terms[0] == "1", res.formula
        assert max_error(res, truth) < 0.004, res.formula
        far = 1.4 * res.speed_range[1]
        lo, _, hi = res.band(np.array([far]))
        assert lo[0] <= truth(far) <= hi[0], (lo, truth(far), hi)


def test_band_widens_outside_the_observed_speeds():
    for law, spec in (("constant", "0.8"), ("linear", "linear:0.95:0.15")):
        v, rng = _speeds(3)
        res = discover_impact_law(v, RestitutionLaw.parse(spec)(v)
                                  + rng.normal(0, 0.004, v.size), n_boot=100, seed=3)
        assert res.kind == law
        v0, v1 = res.speed_range
        lo, mid, hi = res.band(np.array([0.5 * v0, 0.5 * (v0 + v1), 1.4 * v1]))
        width = hi - lo
        assert width[0] > 2 * width[1] and width[2] > 2 * width[1], width
        assert np.all(lo <= mid) and np.all(mid <= hi)
        band = res.to_dict()["band"]
        assert band["v"][0] == pytest.approx(0.6 * v0) and band["v"][-1] == \
            pytest.approx(1.4 * v1)
        assert len(band["lo"]) == len(band["hi"]) == len(band["v"])


def test_small_effect_is_not_reported_and_the_note_says_why():
    """A 0.002 change of r over the speeds, resolved by AICc (scatter 1e-4), stays
    below min_effect: constant, with a note; min_effect=0 reports it."""
    v, rng = _speeds(4, n=300)
    r = 0.8 - 0.003 * v + rng.normal(0, 1e-4, v.size)
    res = discover_impact_law(v, r, n_boot=0)
    assert res.kind == "constant" and "below the reporting threshold" in res.note
    assert res.delta_aicc_vs_constant > 10
    strict = discover_impact_law(v, r, n_boot=0, min_effect=0.0)
    assert strict.velocity_dependent and strict.note is None
    with pytest.raises(InputError, match="min_effect must be a number >= 0"):
        discover_impact_law(v, r, min_effect=-1.0)


def test_an_error_repeated_by_every_cycle_is_not_a_law():
    """A periodic orbit hits one wall at two speeds, each repeating its own
    systematic error (realism corpus dev-010, left wall: r 0.552 at 0.84 m/s and
    0.585 at 1.84 m/s where the truth is 0.557 throughout). The scatter about a law
    is 1e-3, so the scatter rule alone reports a law of effect 0.033; the analysis's
    standard errors (0.046 and 0.026) say that a change of r between the two speeds
    is known to 0.053 only: constant, and the note names that standard error (and
    that r rising with speed is not a catalogue law). With standard errors at the
    scatter's level the same change is a law only when rising laws are asked for
    (effect 0.033, threshold 4 x 0.004)."""
    rng = np.random.default_rng(10)
    v = np.r_[np.full(10, 0.836), np.full(19, 1.841)] + rng.normal(0, 0.002, 29)
    r = np.r_[np.full(10, 0.552), np.full(19, 0.585)] + rng.normal(0, 0.001, 29)
    sigma = np.r_[np.full(10, 0.0464), np.full(19, 0.0265)]
    res = discover_impact_law(v, r, sigma=sigma, n_boot=0)
    assert res.kind == "constant", res.formula
    assert "standard error 0.054 of the change of r" in res.note
    # two speed clusters: hypot of their errors (each with the unestimated excess
    # scatter: the best law passes through both means), scaled from the clusters' mean
    # speeds to the 1st-99th percentile span of the speeds
    s2 = UNESTIMATED_SCATTER ** 2
    assert res.effect_threshold == pytest.approx(
        1.5 * math.sqrt(0.0464 ** 2 + 0.0265 ** 2 + 2 * s2), rel=0.01)
    assert "r rises with speed" in res.note and "rising=True" in res.note
    assert res.warning is None  # below the threshold: no claim of biased estimates
    # two clusters: the unestimated excess scatter (0.005 per cluster) holds the rise
    # below 4 x the threshold; without it the precise errors let it through
    precise = discover_impact_law(v, r, sigma=np.full(29, 0.001), n_boot=0, rising=True)
    assert precise.kind == "constant"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(impact_law, "UNESTIMATED_SCATTER", 0.0)
        precise = discover_impact_law(v, r, sigma=np.full(29, 0.001), n_boot=0, rising=True)
    assert precise.velocity_dependent and precise.effect > 0.03


def test_two_precise_clusters_need_more_than_their_standard_errors(monkeypatch):
    """Realism test split, test-042 right (Kelvin-Voigt, r 0.394 throughout): two speed
    clusters at 3.6 and 4.0 m/s read r 0.4262 and 0.4197 with standard errors of 2e-4
    and 3e-4. A two-coefficient law passes through both means, so nothing estimates
    the systematic scatter of the cluster means: UNESTIMATED_SCATTER stands in for it
    and the 0.0066 change stays below the threshold (constant). Without it the change
    is 18 standard errors: ``0.48 - 0.0149 v`` was reported."""
    rng = np.random.default_rng(42)
    v = np.r_[np.full(19, 3.595), np.full(20, 4.035)] + rng.normal(0, 0.01, 39)
    r = np.r_[np.full(19, 0.4262), np.full(20, 0.4197)] + rng.normal(0, 1e-4, 39)
    sigma = np.r_[np.full(19, 2e-4), np.full(20, 3e-4)]
    res = discover_impact_law(v, r, sigma=sigma, n_boot=0)
    assert res.kind == "constant", res.formula
    assert res.effect_threshold == pytest.approx(0.0114, abs=0.0003)
    monkeypatch.setattr(impact_law, "UNESTIMATED_SCATTER", 0.0)
    assert discover_impact_law(v, r, sigma=sigma, n_boot=0).velocity_dependent


@pytest.mark.slow
@pytest.mark.parametrize(("index", "side"), [(17, "left"), (24, "left"), (27, "left"),
                                             (31, "right"), (76, "right")])
def test_kelvin_voigt_walls_of_the_corpus_are_constant(index, side):
    """Constant-r (Kelvin-Voigt) walls of the realism corpus that the scatter rule
    alone reported speed-dependent (effects 0.006-0.03: dev-017 ``0.53 + 0.028 v``,
    dev-027 ``0.64 - 0.069 v``, ...), and dev-076's right wall, where the standard
    error rule let ``0.38 + 0.077 v^0.2`` through (slow impacts read r 0.35 for 0.45):
    each recording alone, its instrument learned, the case's friction and tilt given."""
    from vidiscover.corpus import realism_case

    case = realism_case("dev", index)
    rec = case.simulate(label=False).recording
    out = analyze(rec, flight_law=(case.mu, case.theta), n_boot=0)
    law = discover([out], mu=case.mu, flight=False, n_boot=0, refine_mu=False).impact_laws[side]
    assert law.n >= 30 and law.kind == "constant", law.formula


def test_json_keeps_terms_and_coefficients_machine_readable():
    v, rng = _speeds(5)
    res = discover_impact_law(v, 0.95 - 0.15 * v + rng.normal(0, 0.004, v.size), n_boot=20)
    doc = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert doc["terms"] == ["1", "v"] and doc["formula"] == res.formula
    assert set(doc["coefficients"]) == {"1", "v"}
    assert doc["coefficients"]["v"]["value"] == pytest.approx(res.coefficients["v"])
    for key in ("speed_range", "band", "effect", "effect_threshold", "precision", "n_boot",
                "note", "kind", "law", "candidates"):
        assert key in doc, key
    assert doc["n_boot"] == 20 and doc["effect"] > doc["effect_threshold"]


# ------------------------------------------------- recorded walls of the realism corpus
#: Pooled impact tables (v, r, sigma, recording) of realism dev walls as the analysis
#: gave them on 2026-11-25 (``discover(...).impact_data``), and for the Hunt-Crossley
#: walls the true (|v_in|, r) of the recording at the third clearance.
_REALISM = Path(__file__).parent / "data" / "impact_law"


@functools.cache
def _realism_tables(split: str = "dev"):
    import pandas as pd

    return (pd.read_csv(_REALISM / f"realism_{split}_walls.csv"),
            pd.read_csv(_REALISM / f"realism_{split}_hc_truth.csv"))


def _realism_law(case: str, side: str, **kwargs):
    walls, _ = _realism_tables(case.split("-")[0])
    d = walls[(walls["case"] == case) & (walls["side"] == side)]
    return discover_impact_law(d["v"].to_numpy(), d["r"].to_numpy(), n_boot=0,
                               sigma=d["sigma"].to_numpy(), groups=d["group"].to_numpy(),
                               **kwargs)


@pytest.mark.parametrize(("case", "side"), [("dev-010", "right"), ("dev-040", "right"),
                                            ("dev-042", "left"), ("dev-069", "left"),
                                            ("dev-076", "right")])
def test_rising_r_of_kelvin_voigt_walls_is_not_a_law(case, side):
    """Constant-r walls whose r estimates rise with the speed (slow impacts read too
    low an r: dev-076 0.35 at 0.06 m/s, 0.45 at 1 m/s for 0.448), by 1.1-3.2 times the
    threshold of a falling law (effects 0.012-0.15): constant, the note says that r
    rises with speed and the warning that the estimates are probably biased. Asked
    for rising laws, these stay below 4 times the threshold."""
    law = _realism_law(case, side)
    assert law.kind == "constant", law.formula
    assert "r rises with speed" in law.note
    assert "rise with speed" in law.warning and "probably biased" in law.warning
    top = law.candidates.loc[law.candidates["aicc"].idxmin()]
    assert law.effect_threshold < top["effect"] < RISING_FACTOR * law.effect_threshold
    assert not _realism_law(case, side, rising=True).velocity_dependent


def test_a_rising_r_far_beyond_the_threshold_is_not_a_law_unless_asked_for():
    """A periodic orbit hitting a constant-r wall at two speeds whose r estimates
    read 0.035 low at the slow and 0.019 high at the fast one, with standard errors of
    1e-3 (as on corpus walls where a slow re-impact is missed): the rise, 0.054, is 12
    times the reporting threshold. No contact law rises: constant (their weighted
    mean), a note and a warning that quantify the rise; with rising=True, a law."""
    rng = np.random.default_rng(91)
    v = np.r_[np.full(40, 0.383), np.full(39, 1.258)] + rng.normal(0, 0.001, 79)
    r = np.r_[np.full(40, 0.471), np.full(39, 0.522)] + rng.normal(0, 3e-4, 79)
    sigma = np.r_[np.full(40, 0.0012), np.full(39, 0.0004)]
    law = discover_impact_law(v, r, sigma=sigma, n_boot=0)
    assert law.kind == "constant" and "r rises with speed" in law.note
    assert "rise with speed by 0.05" in law.warning and "x the reporting threshold" in law.warning
    assert 0.47 < law.coefficients["1"] < 0.522
    assert discover_impact_law(v, r, sigma=sigma, n_boot=0, rising=True).velocity_dependent
    with pytest.raises(InputError, match="rising must be True or False"):
        discover_impact_law(v, r, rising="yes")


@pytest.mark.parametrize(("case", "side"), [("dev-026", "right"), ("dev-026", "left"),
                                            ("dev-077", "left"), ("dev-095", "right")])
def test_hunt_crossley_walls_with_conservative_errors_predict_the_third_clearance(case, side):
    """Hunt-Crossley walls pooled over two clearances whose falling r (effects
    0.07-0.14) lay between 1.5 and 2 times the standard error of the ends (held back
    as constant at 2, RMS 0.033-0.050 at the third clearance): a law, predicting the
    true r of the third clearance (up to 1.4 x the pooled speeds) within 0.02
    (measured 0.011-0.016)."""
    law = _realism_law(case, side)
    assert law.velocity_dependent, law.formula
    _, truth = _realism_tables()
    t = truth[(truth["case"] == case) & (truth["side"] == side)]
    t = t[t["v"] <= 1.4 * law.speed_range[1]]
    assert len(t) >= 10
    assert np.sqrt(np.mean((law.predict(t["v"].to_numpy()) - t["r"]) ** 2)) < 0.02


def test_r_above_one_is_flagged():
    """A wall whose r estimates sit at 1.066 (realism holdout-022 reported that as its
    constant r, with standard errors 0.058): the law carries a warning that says
    whether r exceeds 1 beyond twice the standard error of an r estimate (biased
    estimates) or within it; below 1, no warning."""
    rng = np.random.default_rng(22)
    v = rng.uniform(0.3, 1.0, 60)
    r = 1.066 + rng.normal(0, 0.005, v.size)
    law = discover_impact_law(v, r, sigma=np.full(v.size, 0.02), n_boot=0)
    assert law.warning and "above 1 by more than 2 standard errors (0.02)" in law.warning
    few = discover_impact_law(v[:5], r[:5], sigma=np.full(5, 0.02), n_boot=0)
    assert "only 5 impact(s)" in few.warning and "r reaches 1.06" in few.warning
    near = discover_impact_law(v, r, sigma=np.full(v.size, 0.058), n_boot=0).warning
    assert "above 1 but within 2 standard errors (0.058)" in near
    assert discover_impact_law(v, r - 0.1, sigma=np.full(v.size, 0.02),
                               n_boot=0).warning is None


def test_single_speed_wall_above_one_is_constrained_or_not_identified():
    """A single-speed wall (one speed cluster) whose constant r comes out above 1
    (realism holdout-022 right: 1.066, standard errors 0.058, reported kind
    "generic"): within 2 standard errors of 1 the constrained estimate r = 1 is
    reported (kind constant, interval [r0 - 2 s, 1], a note that says r is not
    identified beyond that); beyond them, r is not identified and the note says why.
    Below 1 nothing changes."""
    rng = np.random.default_rng(22)
    v = 0.5 * (1.0 + rng.uniform(-0.01, 0.01, 40))
    r = 1.066 + rng.normal(0.0, 0.003, v.size)
    near = discover_impact_law(v, r, sigma=np.full(v.size, 0.058), n_boot=50)
    assert near.kind == "constant" and near.coefficients == {"1": 1.0}
    assert near.law is not None and near.law.r0 == 1.0
    lo, hi = near.ci["1"]
    assert hi == 1.0 and abs(lo - (np.mean(r) - 2 * 0.058)) < 1e-3
    assert np.all(near.boot_coefficients <= 1.0) and near.predict([0.5])[0] == 1.0
    assert "constrained estimate r = 1" in near.note and "no further than" in near.note
    far = discover_impact_law(v, r, sigma=np.full(v.size, 0.01), n_boot=50)
    assert far.kind == "undetermined" and far.terms == () and far.law is None
    assert far.formula.startswith("r not identified")
    assert "by more than 2 standard errors (0.01)" in far.note
    assert "constant r reported" not in far.warning and "r not identified" in far.warning
    assert np.isnan(far.predict([0.5])[0])
    assert far.to_dict()["kind"] == "undetermined"
    below = discover_impact_law(v, r - 0.1, sigma=np.full(v.size, 0.058), n_boot=0)
    assert below.kind == "constant" and abs(below.coefficients["1"] - (np.mean(r) - 0.1)) < 1e-3
    assert below.note is None


#: Hunt-Crossley walls of the realism test split (pooled over two clearances) and the
#: RMS error of their prediction at the third clearance (<= 1.4 x the pooled speeds)
#: with one standard error per speed cluster (measured 0.0271, 0.0276, 0.0219, 0.0066).
_TEST_HC = [("test-080", "right", 0.029), ("test-080", "left", 0.029),
            ("test-066", "right", 0.025), ("test-052", "right", 0.01)]


@pytest.mark.parametrize(("case", "side", "tol"), _TEST_HC)
def test_hunt_crossley_walls_with_a_few_imprecise_slow_impacts_are_laws(case, side, tol):
    """Hunt-Crossley walls whose slowest tenth of impacts carries standard errors of
    0.07-0.09 while the many clusters in between are known to 0.02-0.05: the error of
    the change of r is that of a line through the speed clusters, not that of the two
    ends, so the falling r is reported (it was held back as a constant, RMS
    0.038-0.076 at the third clearance) and predicts the third clearance."""
    law = _realism_law(case, side)
    assert law.velocity_dependent, law.formula
    _, truth = _realism_tables("test")
    t = truth[(truth["case"] == case) & (truth["side"] == side)]
    t = t[t["v"] <= 1.4 * law.speed_range[1]]
    assert len(t) >= 10
    assert np.sqrt(np.mean((law.predict(t["v"].to_numpy()) - t["r"]) ** 2)) < tol


def test_rising_r_of_a_test_split_wall_is_not_a_law():
    """test-042 left (Kelvin-Voigt, r = 0.664 at both of its speeds): the estimates read
    0.659 at 3.16 m/s and 0.674 at 3.33 m/s with standard errors of 5e-4; the rise
    (0.016, 4 x min_effect) was reported as ``0.378 + 0.089 v``; now constant with a
    warning."""
    law = _realism_law("test-042", "left")
    assert law.kind == "constant" and "r rises with speed" in law.note
    assert "rise with speed" in law.warning
    assert abs(law.coefficients["1"] - 0.664) < 0.01


def test_change_error_counts_each_speed_cluster_once():
    """Two clusters: the standard error of the change is hypot of their median
    standard errors, whatever the number of impacts; a third cluster between them
    lowers it; one cluster: infinite."""
    v = np.r_[np.full(30, 0.5), np.full(10, 1.0)] + np.linspace(0, 0.004, 40)
    sig = np.r_[np.full(30, 0.03), np.full(10, 0.01)]
    assert _change_error(v, sig) == pytest.approx(math.hypot(0.03, 0.01), rel=0.02)
    v3 = np.r_[v, np.full(10, 0.75)]
    assert _change_error(v3, np.r_[sig, np.full(10, 0.01)]) < math.hypot(0.03, 0.01)
    assert _change_error(np.full(20, 0.8) + np.linspace(0, 0.01, 20), np.full(20, 0.01)) \
        == math.inf
    assert _change_error(v, None) == 0.0


def test_speeds_of_one_cluster_identify_no_speed_dependence():
    """A period-1 orbit at 2.86 m/s whose v_in estimates scatter by 1 % (noise) while
    the rebound speed is measured apart: r = v_out / v_in falls with the estimated
    v_in (errors in variables; realism walls were reported ``1.18 - 0.21 v`` that
    way). The speeds form one cluster: constant, with a warning that says why."""
    rng = np.random.default_rng(76)
    v_in = 2.86 * (1 + rng.normal(0, 0.01, 40))
    r = 0.59 * 2.86 / v_in + rng.normal(0, 1e-4, 40)
    law = discover_impact_law(v_in, r, sigma=np.full(40, 1e-3), n_boot=0)
    assert law.kind == "constant" and "form one cluster" in law.warning
    assert law.coefficients["1"] == pytest.approx(0.59, abs=0.005)


def test_one_cluster_band_is_unbounded_outside_the_observed_speeds():
    """One speed cluster tells no speed dependence (infinite reporting threshold): the
    band of its constant is the bootstrap's inside the observed speeds and infinite
    outside them (None in the JSON band), not the bootstrap's narrow width of the mean
    (it was 0.0002 wide at 1.4 x the fastest impact: realism test-067 right, a
    Hunt-Crossley wall whose single cluster's constant missed the third clearance
    by 0.033 behind a band of zero width)."""
    rng = np.random.default_rng(76)
    v = 2.86 * (1 + rng.normal(0, 0.01, 40))
    law = discover_impact_law(v, 0.59 + rng.normal(0, 1e-3, 40), sigma=np.full(40, 1e-3),
                              n_boot=50)
    assert math.isinf(law.effect_threshold)
    v0, v1 = law.speed_range
    lo, mid, hi = law.band(np.array([0.5 * (v0 + v1), 1.4 * v1, 0.6 * v0]))
    assert 0 < hi[0] - lo[0] < 0.002 and lo[0] <= mid[0] <= hi[0]
    assert np.all(np.isinf(lo[1:])) and np.all(np.isinf(hi[1:]))
    band = law.to_dict()["band"]
    assert band["hi"][0] is None and band["hi"][-1] is None
    assert any(x is not None for x in band["hi"])


def _stray_wall(n_stray: int):
    """A constant-r wall (0.816) hit at 0.86 and 1.30 m/s (sigma 0.007 and 0.005),
    plus ``n_stray`` impacts at 1.67-1.81 m/s with r = 0.70 / v: they leave as fast as
    the 0.86 m/s impacts, as after a missed impact (realism holdout-008 right read
    r 0.40 at 1.7 m/s that way)."""
    rng = np.random.default_rng(8)
    v = np.r_[np.full(32, 0.86), np.full(20, 1.30)] + rng.normal(0, 0.001, 52)
    r = 0.816 + rng.normal(0, 0.002, 52)
    sigma = np.r_[np.full(32, 0.007), np.full(20, 0.005)]
    vs = np.linspace(1.67, 1.81, n_stray)
    return (np.r_[v, vs], np.r_[r, 0.816 * 0.86 / vs + rng.normal(0, 0.002, n_stray)],
            np.r_[sigma, np.full(n_stray, 0.0045)])


def test_impacts_after_a_missed_impact_are_excluded():
    """Three impacts that arrive twice as fast as the 0.86 m/s cluster but leave as
    fast: their incoming flight spans a missed impact. Kept, they pull the constant
    to 0.778 (no residual test sees them: they are alone at their speeds); excluded,
    with the reason and the count, the wall is constant at its true r. Without such
    impacts nothing is excluded."""
    v, r, sigma = _stray_wall(3)
    law = discover_impact_law(v, r, sigma=sigma, n_boot=0)
    assert law.kind == "constant", law.formula
    assert law.n_inconsistent == 3 and law.n == 52
    assert "3 impact(s) excluded as inconsistent" in law.warning
    assert "leave as fast as the 32 impacts at 0.86 m/s" in law.warning
    assert law.coefficients["1"] == pytest.approx(0.816, abs=0.002)
    assert law.to_dict()["n_inconsistent"] == 3
    clean = discover_impact_law(*_stray_wall(0)[:2], sigma=_stray_wall(0)[2], n_boot=0)
    assert clean.n_inconsistent == 0 and clean.warning is None


def test_recorded_wall_with_merged_flights():
    """Realism test-020 left (Hunt-Crossley, pooled over two clearances): 3 + 4 impacts
    at 1.4 x the speed of the two populous clusters leave as fast as those (r 0.67
    for 0.95); the fit then reported ``1.21 - 4.822 v^2`` (RMS 0.17 at the third
    clearance). Excluded, the wall predicts the third clearance within 0.02
    (measured 0.013)."""
    law = _realism_law("test-020", "left")
    assert law.n_inconsistent == 7 and "spans a missed impact" in law.warning
    _, truth = _realism_tables("test")
    t = truth[(truth["case"] == "test-020") & (truth["side"] == "left")]
    assert np.sqrt(np.mean((law.predict(t["v"].to_numpy()) - t["r"]) ** 2)) < 0.02


def test_a_law_impossible_at_slow_speeds_is_not_selected():
    """Realism dev-023 right (Hunt-Crossley, impacts at 1.7-3.1 m/s): the best AICc is
    ``1.98 - 1.024 v^0.2``, whose r reaches 1.98 at rest. An admissible law is
    reported instead (its r stays in (0, R_MAX] from rest to 1.4 x the fastest
    impact), the note says why, and it predicts the third clearance's slower impacts
    (0.98-2.1 m/s) within 0.03 (measured 0.027; the impossible law 0.061)."""
    law = _realism_law("dev-023", "right")
    assert law.velocity_dependent and "its r reaches 1.98 at 0 m/s" in law.note
    grid = np.linspace(0.0, law.valid_range[1], 50)
    assert law.valid_range == (0.0, pytest.approx(1.4 * law.speed_range[1]))
    assert np.all((law.predict(grid) > 0) & (law.predict(grid) <= R_MAX))
    assert not law.candidates.set_index("name").loc["r ~ 1 + v^0.2", "admissible"]
    _, truth = _realism_tables("dev")
    t = truth[(truth["case"] == "dev-023") & (truth["side"] == "right")]
    assert np.sqrt(np.mean((law.predict(t["v"].to_numpy()) - t["r"]) ** 2)) < 0.03


def test_a_law_reaching_zero_beyond_the_impacts_holds_up_to_that_speed():
    """``r = 0.6 - 0.6 v`` observed at 0.3-0.8 m/s reaches r = 0 at 1 m/s, before 1.4 x
    the fastest impact: the law is reported (the data show it), said to hold from
    rest to ~1 m/s, and predict gives NaN beyond (an impossible r is no result)."""
    rng = np.random.default_rng(6)
    v = rng.uniform(0.3, 0.8, 120)
    law = discover_impact_law(v, 0.6 - 0.6 * v + rng.normal(0, 0.003, v.size), n_boot=0)
    assert law.kind == "linear" and "holds from rest to" in law.note
    assert 0.95 < law.valid_range[1] < 1.0 and law.valid_range[0] == 0.0
    assert np.isnan(law.predict(1.05)) and law.predict(0.9) > 0


@pytest.mark.parametrize(("case", "side", "tol"), [("dev-073", "right", 0.02),
                                                   ("test-093", "left", 0.006)])
def test_the_form_is_chosen_in_the_speed_clusters_means(case, side, tol):
    """Hunt-Crossley walls pooled over two clearances whose best per-impact AICc is a
    two-coefficient curve (``0.5353 + 0.5644 exp(-v)``, ``0.9371 - 0.2636 v``; RMS
    0.033 and 0.034 at the third clearance) while the one-coefficient contact laws
    reported now are 12 and 283 AICc behind (beyond the window of 4), on standard
    errors that repeat at every impact of a speed cluster. In the clusters' means a
    law with r = 1 at rest is adequate and, sparser, is reported: RMS 0.016 and 0.004
    (measured)."""
    law = _realism_law(case, side)
    assert law.velocity_dependent and law.fixed_intercept and len(law.terms) == 1 + (
        law.kind != "hunt-crossley"), law.formula
    assert law.candidates.set_index("name").loc[law.alternative, "delta_aicc"] > 10
    _, truth = _realism_tables(case.split("-")[0])
    t = truth[(truth["case"] == case) & (truth["side"] == side)]
    t = t[t["v"] <= 1.4 * law.speed_range[1]]
    assert len(t) >= 10
    assert np.sqrt(np.mean((law.predict(t["v"].to_numpy()) - t["r"]) ** 2)) < tol


@pytest.mark.parametrize(("case", "side", "tol"), [("test-017", "left", 0.025),
                                                   ("test-068", "left", 0.015)])
def test_conservative_standard_errors_are_scaled_to_the_clusters_scatter(case, side, tol):
    """Hunt-Crossley walls whose 3-4 speed clusters lie on their law within a tenth of
    their standard errors (0.03-0.07): the threshold (0.062 and 0.10) held back
    effects of 0.058 and 0.099, and the constant missed the third clearance by RMS
    0.29 and 0.087. Scaled to the clusters' scatter the threshold is the floor, 0.045:
    a law, within 0.021 and 0.013 of the third clearance (measured)."""
    law = _realism_law(case, side)
    assert law.velocity_dependent, law.formula
    assert law.effect_threshold == pytest.approx(SCALED_EFFECT_FLOOR)
    _, truth = _realism_tables("test")
    t = truth[(truth["case"] == case) & (truth["side"] == side)]
    t = t[t["v"] <= 1.4 * law.speed_range[1]]
    assert len(t) >= 10
    assert np.sqrt(np.mean((law.predict(t["v"].to_numpy()) - t["r"]) ** 2)) < tol


def test_change_error_scales_down_to_the_floor_only():
    """Four clusters whose means lie on the law within 1e-4 while their standard
    errors say 0.05: the error is scaled down, but the threshold it gives stays at
    SCALED_EFFECT_FLOOR; means scattered as their errors say keep the error."""
    rng = np.random.default_rng(4)
    v = np.repeat([0.5, 0.8, 1.1, 1.4], 20) + rng.normal(0, 1e-3, 80)
    sig = np.full(80, 0.05)
    plain = _change_error(v, sig)
    tight = _change_error(v, sig, rng.normal(0, 1e-4, 80), 2)
    assert tight == pytest.approx(SCALED_EFFECT_FLOOR / EFFECT_PER_SIGMA)
    assert tight < plain
    lab = np.repeat(np.arange(4), 20)
    loose = _change_error(v, sig, np.array([0.05, -0.04, 0.06, -0.05])[lab], 2)
    assert loose >= plain


def test_law_above_one_at_rest_is_not_admissible():
    """r = 1.08 - 0.5 v^2 over three speed clusters (realism test-022, a Hunt-Crossley
    wall whose cluster estimates are biased by +-0.04, was reported ``1.086 - 0.586
    v^2``): r = 1.08 at rest, which no passive wall returns, beyond 2 standard errors
    (0.004) of an r estimate. The law reported stays at or below 1 + 2 s from rest to
    the fastest impact, and the note says why the best fit was not taken."""
    rng = np.random.default_rng(7)
    v = np.concatenate([c * (1 + rng.uniform(-0.01, 0.01, 40)) for c in (0.55, 0.7, 0.82)])
    r = 1.08 - 0.5 * v ** 2 + rng.normal(0, 0.002, v.size)
    law = discover_impact_law(v, r, sigma=np.full(v.size, 0.004), n_boot=0)
    assert law.velocity_dependent, law.formula
    assert np.nanmax(law.predict(np.linspace(0.0, v.max(), 50))) <= 1.008 + 1e-12
    assert "outside the admissible 0 < r <= 1.008" in law.note


def test_a_compliant_walls_model_form_scatter_keeps_a_small_smooth_bias_constant():
    """The r estimates of a compliant wall carry smooth speed-dependent biases that
    their standard errors do not (the contact taken as an impulse at its exit): five
    speed clusters of a constant r = 0.6 read 0.005 high at the slowest and 0.0005
    low at the fastest, each to 6e-4. From the standard errors alone that 0.0057
    fall is a law (threshold 0.004); with the model-form scatter that ``discover``
    gives a wall whose learned contact lasts (COMPLIANT_FORM_SCATTER, 0.005 at the
    fastest cluster, growing like 1 / v toward the slower ones: FORM_SLOW_GAIN) the
    threshold is 1.5 x the error of a straight line's change through the speed clusters'
    means with those errors (0.0075 with 0.005 at every cluster) and r is constant,
    while a real fall of 0.1 stays a law. Its form is told apart no better than those
    floors: ``0.8 - 0.08 v`` is reported as the sparser ``1 - 0.286 v^0.25`` (r = 1 at
    rest), within 0.0073 of it over the observed speeds, where the floors are
    0.005-0.05 (measured)."""
    rng = np.random.default_rng(3)
    v = np.repeat([0.4, 0.7, 1.0, 1.3, 1.6], 20) + rng.normal(0, 0.01, 100)
    bias = np.repeat([0.005, 0.0025, 0.001, 0.0, -0.0005], 20)
    r = 0.6 + bias + rng.normal(0, 0.0005, 100)
    sigma = np.full(100, 0.0006)
    assert discover_impact_law(v, r, sigma=sigma, n_boot=0).velocity_dependent
    floor = impact_law.COMPLIANT_FORM_SCATTER
    res = discover_impact_law(v, r, sigma=sigma, n_boot=0, form_scatter=floor)
    assert res.kind == "constant", res.formula
    lab = impact_law._speed_clusters(v)   # the 0.4 m/s impacts form a few clusters
    vc = np.array([np.mean(v[lab == k]) for k in range(lab.max() + 1)])
    form = floor * (1.0 + impact_law.FORM_SLOW_GAIN * (vc.max() / vc - 1.0))
    w = 1.0 / (0.0006 ** 2 + form ** 2)
    slope_se = 1.0 / np.sqrt(np.sum(w * (vc - np.sum(w * vc) / np.sum(w)) ** 2))
    span = np.diff(np.quantile(v, [0.01, 0.99]))[0]
    assert res.effect_threshold == pytest.approx(EFFECT_PER_SIGMA * slope_se * span, rel=0.03)
    falling = 0.8 - 0.08 * v + rng.normal(0, 0.0005, 100)
    law = discover_impact_law(v, falling, sigma=sigma, n_boot=0, form_scatter=floor)
    assert law.velocity_dependent and law.effect > law.effect_threshold
    grid = np.linspace(v.min(), v.max(), 50)
    assert np.max(np.abs(law.predict(grid) - (0.8 - 0.08 * grid))) < 0.008


def test_discover_gives_the_model_form_scatter_to_compliant_walls_only():
    """``discover`` pools each wall's impacts with its learned contact duration: a wall
    whose contact lasts in any recording is fitted with COMPLIANT_FORM_SCATTER, a rigid
    wall (the exact engine: contact 0) exactly as before."""
    import pandas as pd

    from vidiscover.discovery.pipeline import IMPACT_DATA_COLUMNS, _impact_law

    rng = np.random.default_rng(3)
    v = np.repeat([0.4, 0.7, 1.0, 1.3, 1.6], 20) + rng.normal(0, 0.01, 100)
    r = 0.6 + np.repeat([0.005, 0.0025, 0.001, 0.0, -0.0005], 20) + rng.normal(0, 5e-4, 100)
    d = pd.DataFrame({"recording": "a", "group": 0, "t": np.arange(100.0), "v": v, "r": r,
                      "sigma": 0.0006, "contact_s": 0.0})[list(IMPACT_DATA_COLUMNS)]
    rigid = _impact_law(d, {"n_boot": 0})
    same = discover_impact_law(v, r, sigma=np.full(100, 0.0006), groups=np.zeros(100),
                               n_boot=0)
    assert rigid.velocity_dependent and rigid.formula == same.formula
    compliant = _impact_law(d.assign(contact_s=np.r_[np.zeros(99), 3e-4]), {"n_boot": 0})
    assert compliant.kind == "constant", compliant.formula


def test_a_compliant_walls_model_form_scatter_lets_the_clusters_keep_hunt_crossley():
    """A Hunt-Crossley wall (alpha 0.6 s/m) at three speed clusters, as dev-080 right
    of the realism corpus: the slow cluster reads 0.006 low, each cluster to 1e-3.
    Without a model-form scatter its cluster means rule Hunt-Crossley out and the
    two-coefficient ``0.954 - 0.371 v`` is reported (RMS 0.010 against the truth from
    0.1 to 0.6 m/s); with COMPLIANT_FORM_SCATTER in the cluster means' errors too,
    Hunt-Crossley is adequate, sparser, and reported (RMS 0.0016)."""
    from vidiscover.discovery.impact_terms import hunt_crossley_restitution as r_hc

    rng = np.random.default_rng(0)
    n = [80, 40, 40]
    v = np.repeat([0.282, 0.371, 0.430], n) + rng.normal(0, 0.003, 160)
    r = r_hc(0.6 * v) + np.repeat([-0.006, 0.0, 0.0], n) + rng.normal(0, 0.0005, 160)
    sigma = np.repeat([0.001, 0.0008, 0.0006], n)
    grid = np.linspace(0.1, 0.6, 30)

    def rms(law):
        return float(np.sqrt(np.mean((law.predict(grid) - r_hc(0.6 * grid)) ** 2)))

    rigid = discover_impact_law(v, r, sigma=sigma, n_boot=0)
    assert rigid.kind == "linear" and rms(rigid) > 0.009, rigid.formula
    law = discover_impact_law(v, r, sigma=sigma, n_boot=0,
                              form_scatter=impact_law.COMPLIANT_FORM_SCATTER)
    assert law.kind == "hunt-crossley", law.formula
    assert law.coefficients[law.terms[0]] == pytest.approx(0.6, abs=0.015)
    assert rms(law) < 0.003


def test_the_band_carries_the_model_form_scatter_the_bootstrap_cannot_see():
    """Resampling impacts cannot see an error that repeats at every impact of a speed:
    a compliant wall's band is widened by 1.96 x its form scatter at 95 % (the realism
    dev and test splits: the bootstrap band held the third clearance's true r at 0.38
    and 0.36 of the impacts, with 1.96 x 0.005 added about 0.8-0.9), a rigid one's
    (form_scatter 0) not."""
    v, rng = _speeds(3)
    r = 0.8 + rng.normal(0, 0.004, v.size)
    rigid = discover_impact_law(v, r, n_boot=50, seed=3)
    soft = discover_impact_law(v, r, n_boot=50, seed=3, form_scatter=0.005)
    assert soft.form_scatter == 0.005 and rigid.form_scatter == 0.0
    grid = np.array([0.5 * sum(rigid.speed_range), 1.4 * rigid.speed_range[1]])
    lo0, mid0, hi0 = rigid.band(grid)
    lo1, mid1, hi1 = soft.band(grid)
    np.testing.assert_allclose(hi1 - hi0, 1.96 * 0.005, atol=1e-4)
    np.testing.assert_allclose(lo0 - lo1, 1.96 * 0.005, atol=1e-4)
    assert soft.to_dict()["form_scatter"] == 0.005


# ------------------------------- compliant walls whose slow impacts read low (1 / v)
#: Pooled impact tables of realism dev walls whose learned contact lasts (``discover``
#: gives them COMPLIANT_FORM_SCATTER) and whose slow speed clusters read r low, as the
#: analysis gave them on 2026-11-26, with the true (|v_in|, r) of the Hunt-Crossley
#: walls' third clearance.
_SLOW = Path(__file__).parent / "data" / "impact_law" / "realism_dev_slow_bias"


def _slow_law(case: str, side: str):
    import pandas as pd

    walls = pd.read_csv(f"{_SLOW}_walls.csv")
    d = walls[(walls["case"] == case) & (walls["side"] == side)]
    assert d["compliant"].all()
    return discover_impact_law(d["v"].to_numpy(), d["r"].to_numpy(), n_boot=0,
                               sigma=d["sigma"].to_numpy(), groups=d["group"].to_numpy(),
                               form_scatter=impact_law.COMPLIANT_FORM_SCATTER)


@pytest.mark.parametrize(("case", "side"), [("dev-085", "left"), ("dev-087", "right")])
def test_slow_clusters_reading_low_do_not_bend_a_hunt_crossley_law(case, side):
    """Wide-span Hunt-Crossley walls (pooled speeds 0.08-5.8 and 0.14-2.7 m/s) whose
    slow impacts read r low by about 0.03-0.04 m/s / v (dev-085 left: -0.08 at 0.5
    m/s, -0.018 at 1.65 m/s; standard errors 0.001-0.003): at the constant model-form
    floor they ruled the Hunt-Crossley shape out and ``0.783 - 0.074 v`` / ``0.845 -
    0.132 v`` bent through them (RMS 0.065 / 0.039 at the third clearance's 0.74-6.0 /
    0.41-2.9 m/s). With a floor growing like 1 / v toward the slow clusters:
    Hunt-Crossley, RMS 0.014 / 0.013 (measured)."""
    import pandas as pd

    law = _slow_law(case, side)
    assert law.kind == "hunt-crossley", law.formula
    truth = pd.read_csv(f"{_SLOW}_hc_truth.csv")
    t = truth[(truth["case"] == case) & (truth["side"] == side)]
    t = t[t["v"] <= 1.4 * law.speed_range[1]]
    assert len(t) >= 40
    assert np.sqrt(np.mean((law.predict(t["v"].to_numpy()) - t["r"]) ** 2)) < 0.02


@pytest.mark.parametrize(("case", "side"), [("dev-008", "left"), ("dev-036", "right"),
                                            ("dev-064", "left")])
def test_slow_clusters_reading_off_do_not_make_a_compliant_constant_wall_a_law(case, side):
    """Kelvin-Voigt (constant-r) walls whose slowest clusters read off by 1 / v: at the
    constant floor reported ``0.341 + 0.030 exp(-v)``, ``1 - 0.140 v^0.2``, ``1 - 0.115
    v^0.2``; with the floor growing toward the slow clusters, constant."""
    law = _slow_law(case, side)
    assert law.kind == "constant", law.formula


_FALSE_LAWS = Path(__file__).parent / "data" / "impact_law" / "realism_holdout_false_laws"


def _false_law_case(case: str, side: str):
    import pandas as pd

    walls = pd.read_csv(f"{_FALSE_LAWS}_walls.csv")
    d = walls[(walls["case"] == case) & (walls["side"] == side)]
    assert d["compliant"].all()
    law = discover_impact_law(d["v"].to_numpy(), d["r"].to_numpy(), n_boot=0,
                              sigma=d["sigma"].to_numpy(), groups=d["group"].to_numpy(),
                              form_scatter=impact_law.COMPLIANT_FORM_SCATTER)
    return law, float(d["r_true"].iloc[0])


@pytest.mark.parametrize(("case", "side", "n_bad", "tol"), [("holdout6-007", "left", 18, 0.0055),
                                                            ("holdout6-049", "right", 7, 0.0055),
                                                            ("holdout5-043", "right", 9, 0.11)])
def test_two_clusters_leaving_equally_fast_are_no_speed_law(case, side, n_bad, tol):
    """Kelvin-Voigt walls (spent holdouts; every true impact at one speed) whose r
    estimates form two speed clusters 6-14 % apart that leave the wall at the same
    speed (0.562/0.563, 0.776/0.775, 1.98/1.98 m/s): one cluster's incoming speed is
    wrong, and a law through both fell steeply (``1 - 0.504 v^0.5``, ``1 - 0.244 v^2``,
    ``1 - 0.030 v^2``). The smaller cluster is excluded as inconsistent and the
    constant reported: within 0.005 of the true r where the smaller cluster was the
    wrong one (measured 0.0049 and 0.0020); in holdout5-043 it was the right one
    (0.105 off), which the warning says may happen."""
    law, r_true = _false_law_case(case, side)
    assert law.kind == "constant", law.formula
    assert law.n_inconsistent == n_bad and "leave as fast as" in law.warning
    assert "r is known only between the two" in law.warning
    assert abs(law.coefficients["1"] - r_true) < tol


def test_a_law_far_worse_than_the_constant_is_not_the_admissible_fallback():
    """Realism holdout6-033 right (Kelvin-Voigt, two clusters at 0.65 and 2.49 m/s
    whose r estimates differ by 0.0005): the best AICc is a sweep support negative at
    rest; the only admissible laws strong enough to report were ~970 AICc behind the
    constant (``1 - 0.576 v^0.2`` was reported). The constant is reported and the note
    says why."""
    law, r_true = _false_law_case("holdout6-033", "right")
    assert law.kind == "constant", law.formula
    assert "within the AICc window of the best admissible one" in law.note
    assert abs(law.coefficients["1"] - r_true) < 0.001


def test_a_hunt_crossley_wall_with_close_clusters_keeps_them():
    """The other side of the rule above: Hunt-Crossley clusters 6 % apart at r ~ 0.4-0.7
    (the outgoing speed rises with about r times the incoming one's rate) are not
    excluded, and the law is reported."""
    from vidiscover.discovery.impact_terms import hunt_crossley_restitution

    rng = np.random.default_rng(16001)
    for alpha in (0.25, 0.6):
        v = np.concatenate([c * (1 + rng.normal(0, 2e-4, 30)) for c in (1.6, 1.7, 1.8)])
        sig = np.full(v.size, 4e-4)
        r = hunt_crossley_restitution(alpha * v) + rng.normal(0, 4e-4, v.size)
        law = discover_impact_law(v, r, sigma=sig, n_boot=0)
        assert law.n_inconsistent == 0 and law.kind == "hunt-crossley", law.formula
