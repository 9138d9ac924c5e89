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

import numpy as np
import pytest

from vidiscover import Effects, SensorConfig, preset, record, simulate
from vidiscover.discovery import (
    IMPACT_TERMS,
    ImpactLawResult,
    discover,
    discover_impact_law,
    same_form,
)
from vidiscover.errors import InputError
from vidiscover.restitution_laws import RestitutionLaw

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
        res = discover_impact_law(v, r, seed=seed, n_bootstrap=0)
        hits += exact_form(res.law, truth)
        errors.append(max_error(res, truth))
    assert hits >= 9, f"{law}: form recovered in {hits}/10"
    assert max(errors) < 0.01


def test_intervals_cover_the_true_coefficients():
    covered = 0
    for seed in range(10):
        v, r, _ = synthetic("linear:0.95:0.2", 100 + seed, n=150)
        res = discover_impact_law(v, r, seed=seed, n_bootstrap=100)
        assert res.terms == ("1", "v")
        lo0, hi0 = res.ci["1"]
        lo1, hi1 = res.ci["v"]
        covered += (lo0 <= 0.95 <= hi0) and (lo1 <= -0.2 <= hi1)
    assert covered >= 7
    lo, mid, hi = res.band(np.linspace(*res.speed_range, 20))
    assert np.all(lo <= mid) and np.all(mid <= hi)


def test_comparison_with_a_constant_r():
    v, r, _ = synthetic("power:0.3:0.5", 3)
    dep = discover_impact_law(v, r, n_bootstrap=0)
    assert dep.delta_aicc_vs_constant > 10 and dep.p_value_vs_constant < 1e-6
    v, r, _ = synthetic("0.85", 3)
    const = discover_impact_law(v, r, n_bootstrap=0)
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
    res = discover_impact_law(v, r, sigma=sigma, n_bootstrap=0)
    assert res.formula == "r = 0.3" and res.n_outliers >= 6
    assert res.n + res.n_outliers == v.size
    naive = discover_impact_law(v, r, n_bootstrap=0, outlier_z=None)
    assert abs(naive.predict(0.05) - 0.3) > abs(res.predict(0.05) - 0.3)


def test_same_seed_same_result_and_json_ready():
    v, r, _ = synthetic("linear:0.95:0.2", 5)
    a = discover_impact_law(v, r, seed=4, n_bootstrap=30)
    b = discover_impact_law(v, r, seed=4, n_bootstrap=30)
    assert np.array_equal(a.boot_coefficients, b.boot_coefficients)
    assert a.to_dict() == b.to_dict()
    doc = json.loads(json.dumps(a.to_dict(), allow_nan=False))
    assert doc["formula"] == a.formula and doc["n_bootstrap"] == 30


def test_cv_criterion_also_recovers_the_form():
    v, r, truth = synthetic("power:0.3:0.5", 11)
    groups = np.arange(v.size) % 4
    res = discover_impact_law(v, r, groups=groups, criterion="cv", n_bootstrap=0)
    assert exact_form(res.law, truth)


def test_degenerate_inputs_fall_back_with_a_warning():
    few = discover_impact_law([0.5, 0.6, 0.7], [0.8, 0.8, 0.8], n_bootstrap=10)
    assert few.kind == "constant" and "min_impacts" in few.warning
    v = np.full(30, 0.5) + np.linspace(0, 0.01, 30)
    narrow = discover_impact_law(v, np.full(30, 0.7), n_bootstrap=0)
    assert narrow.kind == "constant" and "span" in narrow.warning
    none = discover_impact_law([np.nan], [0.5], n_bootstrap=0)
    assert none.kind == "undetermined" and none.n == 0 and none.n_dropped == 1


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"v": [0.1, 0.2], "r": [0.5]}, "same length"),
    ({"v": [-0.1] * 10, "r": [0.5] * 10}, "impact speeds >= 0"),
    ({"n_bootstrap": -1}, "n_bootstrap must be an integer >= 0"),
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
    res = discover(_recordings(case, seed=1), n_bootstrap=50, flight=False)
    for side, spec in zip(("right", "left"), case, strict=True):
        law, truth = res.impact_laws[side], RestitutionLaw.parse(spec)
        assert exact_form(law.law, truth), f"{side}: {law.formula} for {truth.formula}"
        assert max_error(law, truth) < R_TOL
        assert law.n >= 60 and set(res.impact_data[side]["group"]) == {0, 1, 2}
        lo, _, hi = law.band(np.linspace(*law.speed_range, 20))
        assert np.all(hi - lo < 0.02)
    summary = res.summary()
    assert summary["impact_law"]["right"]["formula"] == res.impact_laws["right"].formula
    assert summary["n_recordings"] == 3 and summary["flight"] is None


@pytest.mark.slow
def test_simulated_form_recovery_rate_over_seeds():
    hits, total, worst = 0, 0, 0.0
    for case in CASES:
        for seed in range(5):
            res = discover(_recordings(case, seed), n_bootstrap=0, flight=False)
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
    refined = discover(recs, n_bootstrap=0)
    assert refined.flight is not None and refined.mu_impacts == pytest.approx(0.3, abs=0.03)
    naive = discover(recs, n_bootstrap=0, refine_mu=False)
    assert naive.mu_impacts == 0.0
    for side in ("right", "left"):
        grid = np.linspace(*refined.impact_laws[side].speed_range, 50)
        assert np.max(np.abs(refined.impact_laws[side].predict(grid) - 0.88)) < R_TOL
        assert np.max(np.abs(naive.impact_laws[side].predict(grid) - 0.88)) > 5 * R_TOL


def test_min_effect_trades_form_resolution_for_robustness():
    """A 5e-4 offset (a sensor bias) decides the form under AICc, not with a tolerance;
    the same tolerance merges linear and sqrt laws over a narrow speed band."""
    rng = np.random.default_rng(0)
    v = rng.uniform(0.02, 0.8, 300)
    r = 0.9995 - 0.9 * v ** 0.2 + rng.normal(0.0, 1e-4, v.size)
    assert discover_impact_law(v, r, n_bootstrap=0).kind != "power"
    tol = discover_impact_law(v, r, n_bootstrap=0, min_effect=2e-3)
    assert exact_form(tol.law, RestitutionLaw.parse("power:0.9:0.2"))
    v = rng.uniform(0.57, 0.72, 120)
    r = 0.95 - 0.12 * v + rng.normal(0.0, 1e-4, v.size)
    assert discover_impact_law(v, r, n_bootstrap=0).kind == "linear"
    merged = discover_impact_law(v, r, n_bootstrap=0, min_effect=2e-3)
    assert merged.kind == "power" and max_error(merged, RestitutionLaw.parse(
        "linear:0.95:0.12")) < 2e-3
