"""The reduced withheld-effect battery (slow tier): every catalogue effect, three
clearances, both magnitudes, no-effect and out-of-catalogue cases.

What it covers (``vidiscover.gap.battery.CASES_CI``): each of the 8 catalogue effects
once on the exact engine (clearances 6, 9 and 15 mm; small and large magnitudes
alternating), two no-effect cases (6 and 15 mm) and one ``restitution_drift`` case
(9 mm); every case is offered three candidates, the true effect and the two it is
most often confused with. The full battery (80 cases, every effect offered, with
compliant walls, another rig and effect pairs) is ``benchmarks/bench_gap.py``.

Measured with the model-form scales calibrated on compliant recordings
(``components.FORM_SCALE``) and the flight-drag statistic: 5/8 attributions right,
2/2 no-effect, the drift case 88 % unexplained, median shrink 0.99 over all
catalogue cases, 6 of 8 true parameters inside their intervals; about 45 s of CPU
in one process. The three misses are effects that the model-form spread covers: a
2 deg tilt at 15 mm (gap 5.7 < 8), a -1 mm clearance error at 15 mm (1.4) and a
0.5 ms contact at 6 mm (6.2); without the model-form scales all 8 were found, and
compliant recordings with no effect were blamed on catalogue effects. The intervals
that miss: the 2nd harmonic's amplitude (undetermined) and a resonance's damping
(the speed-dependent laws' string parameters get none and are not counted).
"""

from __future__ import annotations

import pytest

from vidiscover.effects import EFFECTS
from vidiscover.gap.battery import CASES_CI, TARGETS, gap_check, summarise, verdicts


def test_reduced_battery_covers_every_effect_clearance_and_kind():
    cat = [c for c in CASES_CI if c.kind == "catalogue"]
    assert {c.effect for c in cat} == set(EFFECTS)
    assert len({c.b for c in CASES_CI}) >= 3
    assert {c.magnitude for c in cat} == {"small", "large"}
    assert {c.kind for c in CASES_CI} == {"catalogue", "none", "outside"}
    for c in CASES_CI:
        assert c.candidates is not None and len(c.candidates) >= 2
        assert c.kind != "catalogue" or c.effect in c.candidates
    assert len({c.seed for c in CASES_CI}) == len(CASES_CI)


def _row(effect, predicted, shrink, kind="catalogue"):
    expected = {"catalogue": effect, "none": "none", "outside": "unexplained"}[kind]
    return {"effect": effect, "expected": expected, "predicted": predicted,
            "correct": predicted == expected, "kind": kind, "shrink": shrink,
            "unexplained": 0.9 if predicted == "unexplained" else 0.0}


def test_shrink_counts_every_catalogue_case_and_verdicts_flag_misses():
    rows = [_row("inclination", "inclination", 0.9),
            _row("coulomb_friction", "asymmetric_restitution", 0.3),
            _row("clearance_error", "none", 0.0),
            _row("none", "none", 0.0, "none"),
            _row("restitution_drift", "unexplained", 0.1, "outside")]
    s = summarise(rows)
    assert s["median_shrink"] == pytest.approx(0.3)          # over all three
    assert s["median_shrink_correct"] == pytest.approx(0.9)  # the old, flattering one
    assert s["accuracy"] == pytest.approx(1 / 3)
    assert s["confusion"]["coulomb_friction"] == {"asymmetric_restitution": 1}
    v = {x["key"]: x["verdict"] for x in verdicts(s)}
    assert set(v) == set(TARGETS)
    assert v["accuracy"] == "MISSED" and v["median_shrink"] == "MISSED"
    assert v["none_accuracy"] == "MET" and v["outside_unexplained"] == "MET"


@pytest.mark.slow
def test_reduced_battery_scores_as_measured():
    res = gap_check(cases=CASES_CI, n_jobs=1)
    rows = {(c["effect"], c["b"]): c for c in res["cases"]}
    wrong = [f"{c['effect']} at {c['b'] * 1e3:g} mm -> {c['predicted']}"
             for c in res["cases"] if not c["correct"]]
    # measured 5/8; a wrong attribution (not just a miss) is never accepted
    assert res["accuracy"] >= 5 / 8, wrong
    assert all(c["predicted"] in (c["expected"], "none") for c in res["cases"]), wrong
    assert res["none_accuracy"] == 1.0, wrong
    assert res["outside_unexplained"] == 1.0, wrong
    assert res["median_shrink"] >= 0.9                      # measured 0.99
    v = {x["key"]: x["verdict"] for x in res["verdicts"]}
    assert v["none_accuracy"] == "MET" and v["median_shrink"] == "MET"
    # intervals: measured 6 of 8 true parameters covered
    assert res["ci_coverage"] >= 0.7, [c for r in res["cases"] for c in r["coverage"]]
    # the large effects are found with their parameters
    asym = rows[("asymmetric_restitution", 0.006)]
    assert asym["predicted"] == "asymmetric_restitution"
    assert asym["fitted"]["r_right"] == pytest.approx(0.85, abs=0.02)
    assert asym["fitted"]["r_left"] == pytest.approx(0.3, abs=0.03)
    res_ = rows[("sensor_resonance", 0.006)]
    assert res_["predicted"] == "sensor_resonance"
    assert res_["fitted"]["f_s"] == pytest.approx(180.0, abs=10.0)
    # friction 0.25 read from the flights (measured 0.235, interval [0.206, 0.264])
    fr = rows[("coulomb_friction", 0.009)]
    assert fr["fitted"]["mu"] == pytest.approx(0.25, abs=0.04)
    lo, hi = fr["attributed"][0]["ci"]["mu"]
    assert lo <= 0.25 <= hi
    for key in (("velocity_dependent_restitution", 0.015), ("coulomb_friction", 0.009),
                ("excitation_distortion", 0.009)):
        assert rows[key]["predicted"] == key[0]


def test_drawn_cases_are_a_pure_function_of_the_seed_and_cover_every_kind():
    from vidiscover.effects import Effects
    from vidiscover.gap.battery import drawn_cases

    a, b = drawn_cases(3, 24), drawn_cases(3, 24)
    assert a == b and drawn_cases(4, 24) != a
    assert {c.effect for c in a} == set(EFFECTS) | {
        "none", "asymmetric_restitution+coulomb_friction", "asymmetric_restitution+inclination"}
    for c in a:
        Effects.parse(list(c.spec))                       # every spec is valid
        assert 0.006 <= c.b <= 0.015
        assert c.kind == ("none" if c.effect == "none" else "catalogue")
        if c.contact and "asymmetric_restitution" in c.effect:
            # unequal compliant walls make the restitution effect; no spec for it
            assert not any(s.startswith("asymmetric_restitution") for s in c.spec)
            assert len(c.contact) == 2
    assert len({c.seed for c in a}) == len(a)


def test_case_without_switches_one_effect_off_and_keeps_the_rest():
    from vidiscover.gap.battery import BASE_R, CASES_FULL, case_without

    pair = CASES_FULL[76]                         # asym + friction 0.15 at 12 mm, exact
    assert pair.effect == "asymmetric_restitution+coulomb_friction" and not pair.contact
    walls = case_without(pair, "asymmetric_restitution")
    assert walls.spec == ("coulomb_friction=0.15",) and walls.effects == ("coulomb_friction",)
    assert (walls.seed, walls.b) == (pair.seed, pair.b)
    compliant = CASES_FULL[79]                    # unequal Kelvin-Voigt walls + a tilt
    assert compliant.contact and compliant.spec == ("inclination=2.5",)
    equal = case_without(compliant, "asymmetric_restitution")
    assert equal.contact == (f"kelvin-voigt:k=3e7,r={BASE_R}",)
    assert equal.spec == compliant.spec and equal.sensors == compliant.sensors
    tilt = case_without(compliant, "inclination")
    assert tilt.spec == () and tilt.contact == compliant.contact and tilt.effect == \
        "asymmetric_restitution"


def test_figures_over_detectable_cases_leave_out_only_the_undetectable_ones():
    def row(effect, named, detectable):
        r = _row(effect, "+".join(sorted(named)), 0.9)
        r.update(named=named, detectable=detectable, b=0.012, spec=[], regime="x")
        return r

    pair = "asymmetric_restitution+coulomb_friction"
    rows = [row(pair, ["coulomb_friction"], {"asymmetric_restitution": 0.0,
                                             "coulomb_friction": 2668.0}),
            row(pair, ["asymmetric_restitution", "coulomb_friction"],
                {"asymmetric_restitution": 2692.0, "coulomb_friction": 1863.0}),
            row("inclination", ["clearance_error"], {"inclination": 3.9}),
            row("inclination", ["inclination"], {"inclination": 4.1})]
    s = summarise(rows)
    assert s["pair_both_named"] == 0.5 and s["accuracy"] == 0.5        # all cases
    assert s["pair_both_named_detectable"] == 1.0 and s["n_pair_detectable"] == 1
    assert s["accuracy_detectable"] == 1.0 and s["n_catalogue_detectable"] == 1
    assert sorted(u["effect"] for u in s["undetectable"]) == [pair, "inclination"]
    assert summarise([dict(r, detectable=None) for r in rows])["n_detectability_measured"] == 0


@pytest.mark.slow
def test_an_effect_without_trace_in_the_recording_is_undetectable():
    # seed-0 battery #76: asym + friction at 12 mm in an orbit without impacts; walls
    # at 0.85 / 0.5 or at 0.7 give the same recording (measured 0.0), the friction
    # 2668. #79: the compliant chaotic asym + 2.5 deg tilt the diagnosis misses is not
    # exempted: the tilt moves the statistics by 9.8 (the walls' refit absorbs it)
    from vidiscover.gap.battery import CASES_FULL, DETECTABLE, case_recording, detectability
    from vidiscover.gap.diagnose import nominal_model

    for k, low in ((76, {"asymmetric_restitution"}), (79, set())):
        model, _, _ = nominal_model(case_recording(CASES_FULL[k])[0])
        d = detectability(CASES_FULL[k], model)
        assert set(d) == set(CASES_FULL[k].effects)
        assert {e for e, g in d.items() if g < DETECTABLE} == low, (k, d)
    assert d["inclination"] < 30.0                                    # measured 9.8
