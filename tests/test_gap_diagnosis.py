"""Sim-to-real gap diagnosis: statistics, fits, verdicts, the quick battery.

Ground truth is the effect (and its parameters) switched on when simulating the
"real" recording; the diagnosis is never told.
"""

from __future__ import annotations

import cmath
import json
import math

import numpy as np
import pytest
from gap_cases import quick_battery, recording

from vidiscover.analysis import analyze
from vidiscover.errors import InputError
from vidiscover.gap import STATS, GapReport, diagnose, measure
from vidiscover.gap.components import (
    GROUPS,
    LASER_FIT_MAX,
    LASER_STATS,
    compare,
    energy_distance,
    gate_laser,
    laser_fit_quality,
    mirror,
)
from vidiscover.gap.diagnose import SIGNIFICANT_DROP


def test_energy_distance_of_point_masses_and_identical_clouds():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(40, 2))
    assert energy_distance(p, p) == pytest.approx(0.0, abs=1e-12)
    a, b = np.zeros((5, 2)), np.zeros((7, 2)) + [0.3, 0.4]
    assert energy_distance(a, b) == pytest.approx(2 * 0.5, rel=1e-12)
    q = rng.normal(size=(30, 2)) + [1.0, 0.0]
    assert energy_distance(p, q) == pytest.approx(energy_distance(q, p), rel=1e-12)
    assert energy_distance(p, q) > energy_distance(p, rng.normal(size=(30, 2)))
    assert math.isnan(energy_distance(p, np.zeros((0, 2))))


def test_every_statistic_has_a_group_and_a_positive_floor():
    assert {g for g, _, _ in STATS.values()} <= set(GROUPS)
    assert all(floor > 0 for _, floor, _ in STATS.values())


def test_measure_recovers_the_base_harmonics():
    rec, _ = recording(0.009, ("excitation_distortion=0.06,0.5,0.02,-1.0",))
    v = measure(rec).values
    h2 = complex(v["excitation.h2"], v["excitation.h2s"])
    h3 = complex(v["excitation.h3"], v["excitation.h3s"])
    assert abs(h2 - cmath.rect(0.06, 0.5)) < 1e-3
    assert abs(h3 - cmath.rect(0.02, -1.0)) < 1e-3
    nominal = measure(recording(0.009)[0]).values
    assert abs(complex(nominal["excitation.h2"], nominal["excitation.h2s"])) < 1e-3


def test_pulse_width_grows_with_the_contact_duration():
    widths = [measure(recording(0.009, spec)[0]).values["sensors.pulse_width"]
              for spec in ((), ("contact_duration=0.0005",), ("contact_duration=0.0015",))]
    assert widths[0] < widths[1] < widths[2]
    # area / peak of a 1.5 ms half-sine is 2 tau / pi = 6.1 samples at 6400 Hz; the
    # detector's pulse model (fitted peak and area) reads wide pulses narrower
    assert math.exp(widths[2]) > 3 * math.exp(widths[0])
    assert 3.0 < math.exp(widths[2]) < 6.5


def test_flight_drag_reads_the_friction_coefficient_and_nothing_else():
    # the LO's own equation leaves mu m2 g along the ball's relative motion during
    # flights; a tilt or a contact duration leave less than the statistic's floor
    # (0.02). Measured 0.233 +- 0.005 for mu = 0.25 (the fitted LO stiffness and
    # damping take a little of the square wave), 0.016 for a 5 deg tilt
    def drag(spec):
        s = measure(recording(0.009, spec)[0])
        return s.values["flights.drag"], s.errors["flights.drag"]

    d, e = drag(("coulomb_friction=0.25",))
    assert d == pytest.approx(0.25, abs=0.03), (d, e)
    assert 0 < e < 0.01
    for spec in ((), ("inclination=5",), ("contact_duration=0.0015",)):
        d, e = drag(spec)
        assert abs(d) < 0.02, (spec, d, e)


def test_laser_momentum_reads_a_clearance_error():
    # the laser's LO velocity jumps against the flight speeds (which assume the
    # metadata b): the statistic moves with ln((b + db) / b), read at 0.7-0.85 of it at
    # 15 mm (-0.048 for -1 mm, +0.033 for +0.6 mm; errors 0.004-0.005)
    def laser(spec):
        s = measure(recording(0.015, spec)[0])
        return s.values["momentum.laser"], s.errors["momentum.laser"]

    v0, e0 = laser(())
    assert 0 < e0 < 0.008
    for db in (-0.001, 0.0006):
        v, e = laser((f"clearance_error={db}",))
        assert 0 < e < 0.008
        assert (v - v0) / math.log1p(db / 0.015) == pytest.approx(0.8, abs=0.2), (db, v, v0)


def test_laser_momentum_opposite_reads_a_tilt_and_flips_in_the_mirror():
    # a steady force along the axis moves the flight speeds apart from the impact
    # speeds, the other way at each wall: the walls' laser log ratios part by about
    # 0.0090-0.0111 per degree at 15 mm (0.0031 without tilt; errors 0.004-0.005)
    def opposite(spec):
        s = measure(recording(0.015, spec)[0])
        assert 0 < s.errors["momentum.laser_opposite"] < 0.006
        assert mirror(s).values["momentum.laser_opposite"] == pytest.approx(
            -s.values["momentum.laser_opposite"], abs=1e-15)
        return s.values["momentum.laser_opposite"]

    v0 = opposite(())
    assert abs(v0) < 0.008
    for theta in (2.0, 5.0, -5.0):
        v = opposite((f"inclination={theta}",))
        assert (v - v0) / theta == pytest.approx(0.0098, abs=0.002), (theta, v, v0)


def test_a_ringing_sensor_sheet_leaves_the_laser_statistics_out():
    # the kink fits read the ringing (fit quality 4.6 against 1.7 for a clean laser
    # at 15 mm): the real recording's laser statistics are left out for every candidate
    def signature(spec):
        rec = recording(0.015, spec)[0]
        an = analyze(rec, n_boot=0)
        return measure(rec, an), laser_fit_quality(rec, an)

    clean, q_clean = signature(())
    ringing, q_ringing = signature(("sensor_resonance=180,0.01",))
    assert 1.0 < q_clean < LASER_FIT_MAX
    assert q_ringing > 2 * LASER_FIT_MAX
    assert gate_laser(clean, q_clean) is clean
    gated = gate_laser(ringing, q_ringing)
    assert all(math.isnan(gated.values[k]) for k in LASER_STATS)
    assert all(math.isfinite(ringing.values[k]) for k in LASER_STATS)
    assert compare(gated, clean, {}).restricted(LASER_STATS) == 0.0


def test_the_laser_statistics_are_a_second_look_where_the_others_see_no_gap():
    import dataclasses

    from vidiscover.effects import Effects
    from vidiscover.gap.components import without
    from vidiscover.gap.diagnose import _second_look, build_model
    from vidiscover.gap.fit import CandidateFit

    full = build_model(recording(0.015)[0])
    real = full.real
    assert all(math.isfinite(real.values[k]) for k in LASER_STATS)
    plain = dataclasses.replace(full, real=without(real, LASER_STATS))

    def nominal(**shift):
        # the nominal model is scored without the laser statistics
        vals = dict(real.values)
        for k, d in shift.items():
            vals[k.replace("__", ".")] += d
        sim = dataclasses.replace(real, values=vals)
        return CandidateFit(name="nominal", params={}, n_params=0, r=full.params.r,
                            effects=Effects(), gap=compare(plain.real, sim, {}),
                            signature=sim)

    # no gap on the other statistics: the laser statistics are put back and seen
    n0 = nominal(momentum__laser=0.1)
    assert n0.gap.total == 0.0
    m, n = _second_look(plain, n0, real)
    assert m.real is real and n.gap.total > SIGNIFICANT_DROP
    assert n.gap.total == pytest.approx(n.gap.restricted(LASER_STATS), rel=1e-12)
    # a gap the other statistics see: they stay out (unless always)
    n1 = nominal(momentum__laser=0.1, flights__speed_ratio=0.05)
    assert n1.gap.total > SIGNIFICANT_DROP
    m, n = _second_look(plain, n1, real)
    assert m is plain and n is n1
    assert all(math.isnan(m.real.values[k]) for k in LASER_STATS)
    m, n = _second_look(plain, n1, real, always=True)
    assert n.gap.total > n1.gap.total + 4


def test_the_second_look_chooses_the_nominal_draw_again_with_the_laser_statistics():
    # like for like: every candidate's validation draw is chosen with the laser
    # statistics once they are back, so the nominal model's is too (a no-effect exact
    # draw at 7.9 mm kept a draw that read laser_opposite 0.05 off the recording, the
    # other start's read 0.04 closer, and a 0.03 mm clearance error "removed" 4.2)
    import dataclasses

    from vidiscover.effects import Effects
    from vidiscover.gap.components import without
    from vidiscover.gap.diagnose import _second_look, build_model
    from vidiscover.gap.fit import CandidateFit

    full = build_model(recording(0.015)[0])
    real = full.real
    plain = dataclasses.replace(full, real=without(real, LASER_STATS))

    def draw(d_opposite):
        vals = dict(real.values)
        vals["momentum.laser_opposite"] += d_opposite
        return dataclasses.replace(real, values=vals)

    kept, other = draw(0.2), draw(0.01)         # the same on every other statistic
    n0 = CandidateFit(name="nominal", params={}, n_params=0, r=full.params.r,
                      effects=Effects(), gap=compare(plain.real, kept, {}), signature=kept)
    assert n0.gap.total == 0.0
    m, n = _second_look(plain, n0, real)                        # the draw kept
    assert n.signature is kept and n.gap.total > SIGNIFICANT_DROP
    m, n = _second_look(plain, n0, real, draws=[kept, other])   # chosen again
    assert n.signature is not kept and n.gap.total < 1.0


def test_effects_tied_without_the_laser_statistics_are_ranked_again_with_them():
    # a tilt and a clearance error leaving the same score without the laser statistics
    # (fresh draw 7001 #15: 2.93 against 2.94) are told apart by the laser's momentum
    import dataclasses

    from vidiscover.effects import Effects
    from vidiscover.gap.components import without
    from vidiscover.gap.diagnose import SIGNIFICANT_DROP, TIE, _laser_tie, build_model
    from vidiscover.gap.fit import CandidateFit

    built = build_model(recording(0.015)[0])
    real = built.real
    plain = dataclasses.replace(built, real=without(real, LASER_STATS), full=real)

    def fit(name, d_opposite, n_params=1, **params):
        vals = dict(real.values)
        vals["momentum.laser_opposite"] += d_opposite
        sig = dataclasses.replace(real, values=vals)
        return CandidateFit(name=name, params=params, n_params=n_params, r=built.params.r,
                            effects=Effects().with_effect(name, **params),
                            gap=compare(plain.real, sig, {}), signature=sig)

    clearance = fit("clearance_error", 0.2, db=1e-4)     # off on the laser statistic
    tilt = fit("inclination", 0.0, theta=2.0)
    assert clearance.score == tilt.score
    assert _laser_tie(plain, [clearance, tilt])[0] is tilt
    assert _laser_tie(plain, [tilt, clearance])[0] is tilt

    def leaving(f, g):
        return dataclasses.replace(f, gap=dataclasses.replace(
            f.gap, per_stat={**f.gap.per_stat, "flights.direction": g}))

    # not tied: a score TIE or more behind stays behind
    behind = leaving(tilt, TIE)
    assert behind.score >= clearance.score + TIE
    assert _laser_tie(plain, [clearance, behind])[0] is clearance
    # both leaving a significant gap: a pair search follows, and decides
    far = [leaving(clearance, SIGNIFICANT_DROP), leaving(tilt, SIGNIFICANT_DROP)]
    assert _laser_tie(plain, far)[0] is far[0]
    # the laser statistics already in the scores (second look): nothing to rank again
    seen = dataclasses.replace(plain, real=real)
    assert _laser_tie(seen, [clearance, tilt])[0] is clearance


def test_constants_per_wall_at_one_speed_per_wall_leave_a_law_not_excluded():
    # a law per wall gives the same r as a constant at the one speed a wall is hit
    # with: the parsimonious name is given and the law is said not to be excluded
    from types import SimpleNamespace

    from vidiscover.gap.fit import ONE_SPEED, walls_at_one_speed

    rng = np.random.default_rng(1)

    def report(spread, name="asymmetric_restitution", second=None, n=40):
        # speeds uniform within +/- spread/2 of the wall's: standard deviation / mean
        # = spread / sqrt(12)
        side = np.repeat([1, -1], n)
        base = np.where(side == 1, 0.30, 0.18)
        speed = base * (1 + spread * rng.uniform(-0.5, 0.5, side.size))
        real = SimpleNamespace(impacts={"speed": speed, "side": side})
        fit = SimpleNamespace(name=name, gap=SimpleNamespace(total=2.0))
        nominal = SimpleNamespace(gap=SimpleNamespace(total=100.0))
        selected = [fit] if second is None else [
            SimpleNamespace(name=second, gap=SimpleNamespace(total=50.0)), fit]
        return GapReport(name="x", model=SimpleNamespace(real=real), nominal=nominal,
                         candidates=[fit], selected=selected, significant=True)

    at, apart = 0.3 * ONE_SPEED, 3 * ONE_SPEED * 12 ** 0.5
    one = report(at)
    assert walls_at_one_speed(one.model.real.impacts)
    assert one.verdict == "asymmetric_restitution"
    assert one.not_excluded == ["velocity_dependent_restitution"]
    two = report(apart)
    assert not walls_at_one_speed(two.model.real.impacts)
    assert two.not_excluded == []                                   # speeds spread: told apart
    assert report(at, "coulomb_friction").not_excluded == []
    # a pair holding constants per wall (first or second) leaves the law open too
    pair = report(at, second="clearance_error")
    assert pair.confident and pair.not_excluded == ["velocity_dependent_restitution"]
    assert report(apart, second="clearance_error").not_excluded == []
    assert report(at, "coulomb_friction", "clearance_error").not_excluded == []
    unsure = report(at)
    unsure.selected[0].gap.total = 80.0                             # not confident
    assert unsure.verdict == "unexplained" and unsure.not_excluded == []
    few = report(at)
    few.model.real.impacts["side"][:] = 1                           # no left impacts
    assert few.not_excluded == []
    # too few impacts for the law's regression: no slope read, but no speed either
    # (the same walls the law's fit leaves at its level without searching a slope)
    assert report(at, n=7).not_excluded == []
    assert report(at, n=8).not_excluded == ["velocity_dependent_restitution"]


def test_wall_restitution_statistics_match_the_truth():
    rec, _ = recording(0.009, ("asymmetric_restitution=0.85,0.3",))
    v = measure(rec).values
    assert v["right.r_level"] == pytest.approx(0.85, abs=0.01)
    assert v["left.r_level"] == pytest.approx(0.3, abs=0.02)


def test_a_signature_has_no_gap_with_itself():
    sig = measure(recording(0.009)[0])
    gap = compare(sig, sig, {})
    assert gap.total == 0.0
    assert set(gap.by_group()) == set(GROUPS)


def test_unknown_candidate_is_rejected():
    with pytest.raises(InputError, match="unknown gap candidate"):
        diagnose(recording(0.009)[0], candidates=["gravity_waves"])


@pytest.fixture(scope="module")
def small_report():
    rec, _ = recording(0.009, ("excitation_distortion=0.06,0.5",))
    return diagnose(rec, n_jobs=1, candidates=["excitation_distortion", "inclination"])


def test_report_has_the_design_keys_and_is_json_ready(small_report):
    d = small_report.to_dict()
    for key in ("gap_before", "effects", "attributed", "unexplained"):
        assert key in d
    for e in d["effects"]:
        assert {"name", "params", "gap_after", "shrink"} <= set(e)
    json.dumps(d)
    assert isinstance(small_report, GapReport)
    assert d["verdict"] == "excitation_distortion"
    fitted = d["attributed"][0]["params"]
    assert fitted["h2"] == pytest.approx(0.06, abs=2e-3)
    assert fitted["phi2"] == pytest.approx(0.5, abs=0.05)
    assert d["effects"][0]["shrink"] > 0.9


def test_same_seed_same_report(small_report):
    rec, _ = recording(0.009, ("excitation_distortion=0.06,0.5",))
    again = diagnose(rec, n_jobs=1, candidates=["excitation_distortion", "inclination"])
    assert json.dumps(again.to_dict()) == json.dumps(small_report.to_dict())


def test_a_worker_process_gives_the_same_report(small_report):
    # the candidates shared between this process and a worker started at once (its
    # BLAS may round the last bits differently: values to 1e-9, decisions exactly)
    rec, _ = recording(0.009, ("excitation_distortion=0.06,0.5",))
    d2 = diagnose(rec, n_jobs=2, candidates=["excitation_distortion", "inclination"]
                  ).to_dict()
    d1 = small_report.to_dict()
    assert (d2["verdict"], d2["selected"], d2["n_sims"]) == (
        d1["verdict"], d1["selected"], d1["n_sims"])
    assert [e["name"] for e in d2["effects"]] == [e["name"] for e in d1["effects"]]
    for e2, e1 in zip(d2["effects"], d1["effects"]):
        assert e2["gap_after"] == pytest.approx(e1["gap_after"], rel=1e-9)
        assert e2["params"] == pytest.approx(e1["params"], rel=1e-9, abs=1e-12)


def test_runner_shares_a_batch_in_input_order_and_raises_its_errors():
    from vidiscover.gap.diagnose import _Runner

    run = _Runner(2, None)
    items = [float(i) for i in range(12)]
    assert run(math.sqrt, items, cost=lambda x: x) == [math.sqrt(x) for x in items]
    with pytest.raises(ValueError):
        run(math.sqrt, [4.0, -1.0, 9.0, 16.0])
    assert _Runner(1, None)(math.sqrt, [4.0]) == [2.0]
    with pytest.raises(InputError, match="n_jobs"):
        _Runner(0, None)


def test_figures_are_written(small_report, tmp_path):
    from vidiscover.gap.figures import write_figures

    names = write_figures(small_report, tmp_path)
    assert sorted(names) == ["restitution.png", "returnmap.png", "waterfall.png"]
    assert all((tmp_path / n).stat().st_size > 1000 for n in names)


# ------------------------------------------------------------------ the quick battery
@pytest.fixture(scope="module")
def battery():
    return quick_battery()


def _case(battery, effect, engine="exact"):
    return next(c for c in battery["cases"]
                if c["effect"] == effect and c["engine"] == engine)


def test_quick_battery_has_the_design_keys(battery):
    assert {"accuracy", "confusion", "cases", "verdicts"} <= set(battery)
    assert len(battery["cases"]) == 6
    assert {c["engine"] for c in battery["cases"]} == {"exact", "compliant"}
    assert any("+" in c["effect"] for c in battery["cases"])
    json.dumps(battery)


@pytest.mark.parametrize("engine", ["exact", "compliant"])
def test_no_effect_is_no_significant_gap(battery, engine):
    # the compliant case: Kelvin-Voigt walls behind a 4th-order Butterworth, no
    # catalogue effect; its model form stays within the calibrated spread
    c = _case(battery, "none", engine)
    assert c["predicted"] == "none" and not c["significant"]
    # a nominal gap no effect can make significant: candidates on their grids only
    assert c["refined"] == (c["gap_before"] >= SIGNIFICANT_DROP)


def test_an_unrefined_search_returns_the_best_grid_point_after_the_grid_alone():
    from vidiscover.gap.fit import _minimise_1d

    calls = []

    def f(x):
        calls.append(x)
        return (x - 0.3) ** 2

    assert _minimise_1d(f, 0.0, 1.0, n_grid=5, refine=False) == 0.25
    assert len(calls) == 5
    assert _minimise_1d(f, 0.0, 1.0, n_grid=5) == pytest.approx(0.3, abs=0.02)


def test_two_effects_at_once_are_both_named_and_explain_the_gap(battery):
    # asymmetric Kelvin-Voigt walls plus friction: both named (the friction by the
    # force it puts on the LO during the flights; before that statistic it hid within
    # the model-form spread and only the walls were named)
    c = _case(battery, "asymmetric_restitution+coulomb_friction", "compliant")
    assert c["significant"]
    assert set(c["named"]) == {"asymmetric_restitution", "coulomb_friction"}, c["named"]
    assert c["predicted"] == c["expected"]
    assert c["unexplained"] < 0.5


def test_withheld_asymmetric_restitution_is_found_with_its_parameters(battery):
    c = _case(battery, "asymmetric_restitution")
    assert c["predicted"] == "asymmetric_restitution"
    assert c["fitted"]["r_right"] == pytest.approx(0.85, abs=0.02)
    assert c["fitted"]["r_left"] == pytest.approx(0.3, abs=0.03)
    assert c["shrink"] >= 0.6
    ci = c["attributed"][0]["ci"]
    assert ci["r_right"][0] <= 0.85 <= ci["r_right"][1]
    assert ci["r_left"][0] <= 0.3 <= ci["r_left"][1]


def test_withheld_inclination_is_found_with_its_angle(battery):
    c = _case(battery, "inclination")
    assert c["predicted"] == "inclination"
    assert c["fitted"]["theta"] == pytest.approx(5.0, abs=0.75)
    assert c["shrink"] >= 0.6
    lo, hi = c["attributed"][0]["ci"]["theta"]
    assert lo < c["fitted"]["theta"] < hi


def test_out_of_catalogue_drift_stays_unexplained(battery):
    c = _case(battery, "restitution_drift")
    assert c["significant"]
    assert c["unexplained"] >= 0.5
    assert c["predicted"] == "unexplained"


def test_quick_battery_accuracy_and_confusion(battery):
    assert battery["accuracy"] == 1.0
    assert battery["n_catalogue_cases"] == 2
    assert sum(sum(row.values()) for row in battery["confusion"].values()) == 6


def test_public_names_exist_and_are_not_private():
    import importlib

    for mod in ("gap", "gap.components", "gap.fit", "gap.diagnose", "gap.battery",
                "gap.figures", "commands.gap"):
        m = importlib.import_module(f"vidiscover.{mod}")
        assert all(not n.startswith("_") for n in m.__all__), mod
        assert all(hasattr(m, n) for n in m.__all__), mod


def test_bad_cli_input_is_one_line_and_exit_2(tmp_path):
    from click.testing import CliRunner

    from vidiscover.cli import main

    rec, truth = recording(0.009)
    from vidiscover.io import write_recording

    path = tmp_path / "rec.csv"
    write_recording(rec, path, truth=truth)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["gap", str(path), "--out", str(out), "--n-jobs", "0"])
    assert res.exit_code == 2 and "--n-jobs" in res.output
    assert len(res.output.strip().splitlines()) == 1 and not out.exists()
    res = CliRunner().invoke(main, ["gap-check", "--seed", "-1"])
    assert res.exit_code == 2 and "--seed" in res.output


def test_a_small_gap_is_significant_only_when_one_effect_removes_most_of_it():
    from vidiscover.effects import Effects
    from vidiscover.gap.components import GapComponents
    from vidiscover.gap.diagnose import SIGNIFICANT_GAP, _significant
    from vidiscover.gap.fit import CandidateFit

    def fit(gap):
        return CandidateFit(name="x", params={}, n_params=1, r=0.7, effects=Effects(),
                            gap=GapComponents({"s": float(gap)}, {}), signature=None)

    assert _significant(fit(SIGNIFICANT_GAP + 0.1), [])
    # the seed-0 battery's 2 deg tilt at 15 mm (6.3 -> 1.2) and the other rig's 3 deg
    # (4.5 -> 0.1)
    assert _significant(fit(6.3), [fit(1.2)]) and _significant(fit(4.5), [fit(0.1)])
    # compliant walls without an effect: 4.9 -> 1.5 (removes 3.4), 2.7 -> 1.1 (40 % left)
    assert not _significant(fit(4.9), [fit(1.5)])
    assert not _significant(fit(7.0), [fit(2.5)])
    assert not _significant(fit(0.5), [fit(0.0)])


@pytest.mark.slow
def test_a_long_contact_absorbed_by_the_learned_instrument_is_fitted():
    # drawn case 31415 #19: a 0.82 ms contact at 8.5 mm, 6400 Hz. The instrument
    # learned from the recording absorbs part of the long pulse. Until 9e3546a the
    # nominal model's recordings through it detected no impact (their back-fit
    # diverged): the whole nominal gap (2231) was in the two walls' rates, the pulse
    # width showed nothing, and the contact was searched all the same (before that:
    # tau stayed at 2e-5, verdict unexplained). How much of the pulse the learned
    # instrument absorbs moves with the last bits of the learning (the nominal gap
    # read 1715 with one BLAS thread and 1021 with two until 31d7eb5, 332 after its
    # rounding-level smoother change, 46 since the learner refines six filter
    # families, ffd263e, with one or two threads): what stays is that the gap is far
    # above "none" (SIGNIFICANT_GAP 8), the pulse width shows the contact (35) and
    # the contact explains it (tau 0.823 ms for the true 0.82, gap left 0.27 of 46;
    # the verdict of diagnose is contact_duration).
    from vidiscover.effects import Effects
    from vidiscover.gap.battery import case_recording, drawn_cases
    from vidiscover.gap.diagnose import SIGNIFICANT_GAP, nominal_model
    from vidiscover.gap.fit import _SensorObjective, fit_candidate

    rec, _ = case_recording(drawn_cases(31415, 24)[19])
    model, nominal, _ = nominal_model(rec)
    assert nominal.gap.total > 3 * SIGNIFICANT_GAP    # 46 (1715 / 1021 / 332 before)
    so = _SensorObjective(model, Effects(), model.params.r)
    assert so.own_gap("sensors.pulse_width") > 10.0 and not so.impacts_lost()   # 35
    fit = fit_candidate(model, "contact_duration")
    assert 0.7e-3 < fit.params["tau"] < 0.95e-3     # 0.823 ms for a true 0.82
    assert fit.gap.total < 0.05 * nominal.gap.total  # 0.27 of 46


@pytest.mark.slow
def test_a_tilt_tied_with_a_clearance_error_is_named_by_the_laser_statistics():
    # drawn case 7001 #15: a 3.5 deg tilt at 9.2 mm in a 2ipc_asym orbit. Without the
    # laser statistics (nominal gap 55: left out) the tilt and a clearance error leave
    # the same score; with them the tilt is far closer (before: clearance_error)
    from vidiscover.gap.battery import case_recording, drawn_cases
    from vidiscover.gap.diagnose import TIE

    rec, _ = case_recording(drawn_cases(7001, 24)[15])
    rep = diagnose(rec, n_jobs=1, candidates=["clearance_error", "inclination"])
    score = {c.name: c.score for c in rep.candidates}
    assert abs(score["clearance_error"] - score["inclination"]) < TIE
    assert rep.verdict == "inclination"
    assert rep.selected[0].params["theta"] == pytest.approx(3.53, abs=0.3)


def _drawn_fit(seed: int, index: int, name: str):
    """(nominal model, fit of candidate ``name``) of drawn case ``index`` of ``seed``."""
    from vidiscover.gap.battery import case_recording, drawn_cases
    from vidiscover.gap.diagnose import nominal_model
    from vidiscover.gap.fit import fit_candidate

    rec, _ = case_recording(drawn_cases(seed, 24)[index])
    model, _, _ = nominal_model(rec)
    return model, fit_candidate(model, name)


@pytest.mark.slow
def test_a_speed_law_at_one_speed_per_wall_gets_its_slopes_searched():
    # drawn case 7919 #1: a law per wall in a 2ipc_asym orbit, each wall hit at one
    # speed (spread 2e-4). The regression sees no slope; zero slopes at the recording's
    # r per wall land on another attractor (left 296) while the slope, which decides
    # which orbit is stable, is searched and reaches the recording's (before: 296)
    _, fit = _drawn_fit(7919, 1, "velocity_dependent_restitution")
    slopes = [float(fit.params[s].split(":")[2]) for s in ("right", "left")]
    assert all(a > 0 for a in slopes)                 # 0.16, 0.51 (truth 0.344, 0.522)
    assert fit.gap.total < 1.0                        # 0.16 (asym: 291)


def test_a_trial_off_the_attractor_is_retried_from_the_other_starts(monkeypatch):
    # the tilt's search ran every trial from the nominal model's start, which in an
    # asymmetric orbit may reach the other member of a near-mirror pair (spent draws
    # 5077 #3 / #15: fits at the window's edge with gaps 2122 / 11503). A trial above
    # ATTRACTOR_JUMP is retried from the other starts; the first that comes back is
    # kept for the next trials, an r re-fitted beyond ATTRACTOR_LOST does not carry
    # over, and the start is validated once more (fails on the old code: no starts)
    import dataclasses

    from vidiscover.effects import Effects
    from vidiscover.gap import fit as gfit

    calls = []

    def fake_sig(model, fx, r=None, *, ball_speed=None, noise_seed=0):
        v = model.ball_speed if ball_speed is None else ball_speed
        calls.append(v)
        home = v == -0.45                              # the recording's attractor
        return dataclasses.replace(real, values={**real.values, "x": 0.0 if home else 1.0},
                                   r_pooled=0.7 if home else 0.6)

    def fake_gap(model, sig, fx):
        class G:
            total = 1.0 if sig.values["x"] == 0.0 else 5000.0
        return G()

    rec, _ = recording(0.009)
    real = measure(rec, analyze(rec, n_boot=0))
    model = gfit.Model(params=rec.meta.params(r=0.7), phase=0.0, duration=1.0,
                    sample_rate=rec.sample_rate, noise=(0, 0, 0), real=real,
                    ball_speed=0.6, alt_speed=0.45)
    monkeypatch.setattr(gfit, "simulate_signature", fake_sig)
    monkeypatch.setattr(gfit, "gap_of", fake_gap)
    make = lambda th: Effects().with_effect("inclination", theta=th)  # noqa: E731
    obj = gfit._Objective(model, make, real.r_pooled, starts=gfit.tilt_starts(model))
    assert gfit.tilt_starts(model) == (0.6, -0.6, 0.45, -0.45)
    assert obj(2.0) == 1.0 and obj.start_at(2.0) == -0.45
    assert obj.bias == pytest.approx(obj.r_at(2.0) - 0.7)
    calls.clear()
    assert obj(3.0) == 1.0 and calls[0] == -0.45        # kept for the next trial
    plain = gfit._Objective(model, make, real.r_pooled)
    assert plain(2.0) == 5000.0 and plain.start_at(2.0) is None
    # nothing comes back: the bias as it was
    monkeypatch.setattr(gfit, "gap_of", lambda m, s, f: type("G", (), {"total": 5000.0})())
    lost = gfit._Objective(model, make, real.r_pooled, starts=gfit.tilt_starts(model))
    assert lost(2.0) == 5000.0 and lost.bias == 0.0 and lost.start_at(2.0) is None
    # the found start is one more validation draw, drawn at that speed
    speeds = gfit._validation_speeds(model, make(2.0), -0.45)
    assert len(speeds) == 5 and speeds[-1] * gfit.VALIDATION[0] == pytest.approx(-0.45)


@pytest.mark.slow
def test_a_tilt_in_an_asymmetric_orbit_is_fitted_on_the_recordings_attractor():
    # spent draw 5077 #3: a -2.31 deg tilt at 6.3 mm, multi_ipc. From the nominal
    # model's start every trial of the tilt's search reached an orbit of half the
    # impact rate (fit 0.24 deg at the window's edge, gap 2122) and the verdict was
    # unexplained; retried from the other starts the tilt is fitted (-2.26 deg, gap
    # 0.7) and named
    from vidiscover.gap.battery import case_recording, drawn_cases

    rec, _ = case_recording(drawn_cases(5077, 24)[3])
    rep = diagnose(rec, n_jobs=1, candidates=["clearance_error", "inclination"])
    fits = {c.name: c for c in rep.candidates}
    assert fits["inclination"].gap.total < 2.0                       # 0.72 (before 2122)
    assert fits["inclination"].params["theta"] == pytest.approx(-2.31, abs=0.4)  # -2.26
    assert rep.verdict == "inclination"                              # clearance left 12.5


def test_a_wall_law_needs_a_slope_beyond_its_error_and_the_precision_of_r():
    # spent draw 35107 #12 (unequal constant walls, chaotic): slopes of 6e-4 s/m moved r
    # by 1e-4 over the speeds, and the chaotic validation draw preferred that "law"
    # (4.5) to the constants (19.8); a slope now counts beyond SLOPE_Z standard errors
    # and MIN_LAW_EFFECT over the observed speeds, else the wall's law is its constant
    from vidiscover.gap.fit import MIN_LAW_EFFECT, _wall_law

    rng = np.random.default_rng(3)
    v = rng.uniform(0.3, 1.1, 40)
    side = np.ones(40, dtype=int)

    def law(r):
        return _wall_law({"speed": v, "side": side, "r": r}, 1, 0.7)

    noise = rng.normal(0.0, 0.002, 40)
    r0, a = law(0.9 - 0.3 * v + noise)                   # a real law: read
    assert a == pytest.approx(0.3, abs=0.01) and r0 == pytest.approx(0.9, abs=0.01)
    tiny = 0.5 * MIN_LAW_EFFECT / np.ptp(v)
    assert law(0.8 - tiny * v + 1e-6 * noise)[1] == 0.0  # 10 errors, 0.002 of r: constant
    # r moves by 0.016 but scatters by 0.05: the slope is within 3 of its errors (0.034)
    assert law(0.8 - 0.02 * v + 25 * noise)[1] == 0.0
    r_const = 0.8 + noise
    assert law(r_const) == (pytest.approx(np.sqrt(np.mean(r_const ** 2))), 0.0)


@pytest.mark.slow
def test_constant_walls_in_a_chaotic_orbit_are_not_offered_as_a_law():
    # spent draw 35107 #12: the law candidate was the constants per wall with slopes
    # of 6e-4 and 2e-4 s/m, and won on the chaotic validation draw (the verdict was
    # velocity_dependent_restitution for unequal constant walls). Now no wall shows a
    # slope, so the law is not fitted and says why
    from vidiscover.gap.battery import case_recording, drawn_cases

    rec, _ = case_recording(drawn_cases(35107, 24)[12])
    rep = diagnose(rec, n_jobs=1, candidates=["asymmetric_restitution",
                                              "velocity_dependent_restitution"])
    assert rep.verdict == "asymmetric_restitution"
    assert "velocity_dependent_restitution" in rep.not_fitted
    assert "constants per wall" in rep.to_dict()["not_fitted"][
        "velocity_dependent_restitution"]
    assert rep.selected[0].params["r_left"] == pytest.approx(0.382, abs=0.01)


@pytest.mark.slow
def test_a_speed_law_keeps_its_regressed_laws_when_the_level_shift_lands_elsewhere():
    # spent draw 35103 #1: laws per wall in a multi_ipc orbit at 13 mm. The regression
    # reads them (0.894 - 0.111 v, 0.860 - 0.584 v for the truth's 0.894 - 0.111 v and
    # 0.860 - 0.584 v); two shifts of r0 by the simulated orbit's mean r moved the left
    # r0 to 0.935 and the law left 333, above the constants' 182 (verdict: unequal
    # walls). The shifted laws are simulated too and the best is kept: gap 0.2
    from vidiscover.gap.fit import fit_candidate

    model, fit = _drawn_fit(35103, 1, "velocity_dependent_restitution")
    left = [float(x) for x in fit.params["left"].split(":")[1:]]
    assert left == pytest.approx([0.860, 0.584], abs=0.02)
    assert fit.gap.total < 2.0                           # 0.21 (333 before)
    asym = fit_candidate(model, "asymmetric_restitution")
    assert asym.gap.total > 50 * fit.gap.total           # 182
