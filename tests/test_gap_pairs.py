"""Two effects at once: shares of a jointly fitted pair (fast, no simulation), and the tilt
look behind unequal walls (slow: simulated cases)."""

from __future__ import annotations

import math

import pytest

from vidiscover.effects import Effects
from vidiscover.gap.components import GapComponents
from vidiscover.gap.diagnose import GapReport, _keep_pair, _pair_items, _pair_search, _split_pair
from vidiscover.gap.fit import PROFILES_WALLS, CandidateFit


def _tried_once_but_walls_both_ways(items: set) -> None:
    """Each pair is tried once, except constants per wall with a 1-D effect: jointly
    (walls first) and the effect's own fit first with the walls on top (seed-0 battery
    #74: 78 one way, 1.3 the other)."""
    walls = "asymmetric_restitution"
    twice = {frozenset(i) for i in items if walls in i and set(i) & set(PROFILES_WALLS)}
    for pair in twice:
        (other,) = pair - {walls}
        assert {(walls, other), (other, walls)} <= items
    assert len(items) == len({frozenset(i) for i in items}) + len(twice)


def _fit(name, gap, params=None, n_params=1):
    return CandidateFit(name=name, params=params or {}, n_params=n_params, r=0.7,
                        effects=Effects(), gap=GapComponents({"s": float(gap)}, {}),
                        signature=None)


def test_pair_shares_are_shapley_and_add_up_to_what_the_pair_removed():
    nominal = _fit("nominal", 100.0, n_params=0)
    fa, fb = _fit("inclination", 40.0), _fit("coulomb_friction", 70.0)
    pair = _fit("inclination+coulomb_friction", 2.0,
                {"inclination": {"theta": 3.0}, "coulomb_friction": {"mu": 0.15}}, 2)
    selected = _split_pair(pair, [fa, fb])
    assert [c.name for c in selected] == ["inclination", "coulomb_friction"]
    assert selected[0].params == {"theta": 3.0} and selected[1].params == {"mu": 0.15}
    rep = GapReport(name="x", model=None, nominal=nominal, candidates=[fa, fb],
                    selected=selected, significant=True)
    shares = {a["name"]: a["share"] for a in rep.attributed()}
    # inclination: (100 - 40 + 70 - 2) / 2 / 100; friction: (100 - 70 + 40 - 2) / 2 / 100
    assert shares["inclination"] == pytest.approx(0.64)
    assert shares["coulomb_friction"] == pytest.approx(0.34)
    assert sum(shares.values()) == pytest.approx((100 - 2) / 100)
    assert rep.gap_after == 2.0 and rep.verdict == "inclination"


def test_pair_order_follows_the_better_single_effect():
    fa, fb = _fit("inclination", 70.0), _fit("coulomb_friction", 40.0)
    pair = _fit("inclination+coulomb_friction", 2.0,
                {"inclination": {"theta": 3.0}, "coulomb_friction": {"mu": 0.15}}, 2)
    assert [c.name for c in _split_pair(pair, [fa, fb])] == ["coulomb_friction",
                                                             "inclination"]


def test_pairs_are_searched_where_the_best_effect_leaves_more_than_one_effect_does():
    # a gap above 8 left, or 4-8 left by a small effect: pairs of any size
    assert _pair_search(_fit("asymmetric_restitution", 12.0, n_params=2)) == (True, None)
    assert _pair_search(_fit("asymmetric_restitution", 5.9, n_params=2)) == (True, None)
    # what correct single effects leave (below 4): no pair
    assert _pair_search(_fit("coulomb_friction", 3.5)) == (False, None)
    # a law per wall: pairs no richer than itself, whatever it leaves
    law = "velocity_dependent_restitution"
    assert _pair_search(_fit(law, 3.5, n_params=4)) == (True, 4)
    assert _pair_search(_fit(law, 6.0, n_params=4)) == (True, 4)


def test_a_pair_after_a_small_gap_must_remove_4_and_leave_at_most_30_percent():
    best = _fit("asymmetric_restitution", 5.9, n_params=2)

    def pair(gap):
        return _fit("asymmetric_restitution+inclination", gap, n_params=3)

    assert _keep_pair(best, pair(1.7), None)          # removes 4.2, leaves 29 %
    assert not _keep_pair(best, pair(2.0), None)      # removes 3.9
    assert _keep_pair(_fit("coulomb_friction", 4.5), pair(0.4), None)      # removes 4.1
    assert not _keep_pair(_fit("coulomb_friction", 4.5), pair(0.6), None)  # 3.9
    assert not _keep_pair(best, None, None)
    # above 8 the share-of-what-is-left rule holds (removes > 0.3 * (gap - 1) and > 2)
    big = _fit("asymmetric_restitution", 20.0, n_params=2)
    assert _keep_pair(big, pair(10.0), None)
    assert not _keep_pair(big, pair(16.0), None)


def test_pairs_tried_include_forward_selection_and_effects_that_failed_alone():
    nominal = _fit("nominal", 800.0, n_params=0)
    fits = [_fit("clearance_error", 100.0), _fit("inclination", 540.0),
            _fit("coulomb_friction", 570.0), _fit("contact_duration", 799.0),
            _fit("asymmetric_restitution", 1500.0, n_params=2),
            _fit("velocity_dependent_restitution", 1500.0, n_params=4)]
    items = {(a.name, b) for a, b in _pair_items(nominal, fits)}
    # the pool (the three that removed something) among themselves
    assert {("clearance_error", "inclination"), ("clearance_error", "coulomb_friction"),
            ("inclination", "coulomb_friction")} <= items
    # forward selection: everything with the best (a restitution per wall first)
    assert {("clearance_error", f.name) for f in fits[1:4]} <= items
    assert {(f.name, "clearance_error") for f in fits[4:]} <= items
    # an effect whose fit alone ended far above the nominal gap is paired with the
    # pool (friction + restitution: the restitution fitted to r lowered by friction);
    # the restitution per wall goes first, so that the other effect is fitted with the
    # walls re-fitted at every trial (a joint fit)
    assert ("asymmetric_restitution", "coulomb_friction") in items
    assert ("velocity_dependent_restitution", "inclination") in items
    # nested effects are never paired, noise-level ones only with the best
    assert not any({a, b} == {"asymmetric_restitution", "velocity_dependent_restitution"}
                   for a, b in items)
    assert ("inclination", "contact_duration") not in items
    _tried_once_but_walls_both_ways(items)
    # a parameter budget (a law per wall checked against no-richer pairs)
    small = {(a.name, b) for a, b in _pair_items(nominal, fits, max_params=3)}
    assert small and all(n not in {"velocity_dependent_restitution"} for p in small for n in p)


def test_wall_levels_shift_for_constants_and_linear_laws_within_0_1():
    from vidiscover.gap.fit import _shift_walls

    fx = Effects.parse(["asymmetric_restitution=0.8,0.4", "coulomb_friction=0.1"])
    out = _shift_walls(fx, 0.05, -0.1)
    assert dict(out.active["asymmetric_restitution"]) == pytest.approx(
        {"r_right": 0.85, "r_left": 0.3})
    assert out.active["coulomb_friction"] == fx.active["coulomb_friction"]
    assert _shift_walls(fx, 0.5, -0.5).active["asymmetric_restitution"]["r_left"] == 0.0
    law = Effects({"velocity_dependent_restitution": {"right": "linear:0.9:0.2",
                                                      "left": "power:0.3:0.5"}})
    out = _shift_walls(law, -0.1, 0.2)
    assert out.active["velocity_dependent_restitution"]["right"] == "linear:0.8:0.2"
    assert out.active["velocity_dependent_restitution"]["left"] == "power:0.3:0.5"
    assert _shift_walls(Effects(), 0.1, 0.1) == Effects()


def test_a_law_per_wall_counts_as_one_only_when_r_varies_over_the_recorded_speeds():
    import numpy as np

    from vidiscover.gap.diagnose import LAW_SPREAD, _law_spread

    rng = np.random.default_rng(0)
    speed = np.concatenate([rng.normal(0.5, 0.2, 200), rng.normal(0.4, 0.01, 200)])
    real = type("Sig", (), {"impacts": {"speed": speed, "side": np.repeat([-1, 1], 200)}})

    def law(left_a, right_a=0.0):
        return _fit("velocity_dependent_restitution", 1.0,
                    {"right": f"linear:0.8:{right_a}", "left": f"linear:0.8:{left_a}"}, 4)

    # left: r changes by a x 2 x std(speed) = 0.6 x 0.4 over the left wall's speeds
    assert _law_spread(law(0.6), real) == pytest.approx(0.6 * 2 * np.std(speed[:200]))
    assert _law_spread(law(0.6), real) > LAW_SPREAD
    # slopes of 0.05 change r by 0.02: constants per wall in disguise
    assert _law_spread(law(0.05), real) < LAW_SPREAD
    # a steep law on a wall whose impacts all come at one speed changes nothing
    assert _law_spread(law(0.0, right_a=1.0), real) < LAW_SPREAD
    assert _law_spread(_fit("asymmetric_restitution", 1.0, {"r_right": 0.8}, 2), real) == 0.0


def test_a_pair_whose_law_per_wall_has_no_slope_is_reported_as_constants_per_wall():
    from vidiscover.gap.diagnose import _constant_laws

    laws = {"right": "linear:0.868:0", "left": "linear:0.492:0"}
    fx = Effects({"velocity_dependent_restitution": laws, "coulomb_friction": {"mu": 0.16}})
    pair = CandidateFit(name="coulomb_friction+velocity_dependent_restitution",
                        params={"coulomb_friction": {"mu": 0.16},
                                "velocity_dependent_restitution": laws},
                        n_params=5, r=0.7, effects=fx, gap=GapComponents({"s": 3.0}, {}),
                        signature=None)
    out = _constant_laws(pair)
    assert out.name == "coulomb_friction+asymmetric_restitution" and out.n_params == 3
    assert out.params["asymmetric_restitution"] == {"r_right": 0.868, "r_left": 0.492}
    assert set(out.effects.active) == {"coulomb_friction", "asymmetric_restitution"}
    assert out.score == pytest.approx(3.0 + 2.0 * 3)
    sloped = dict(laws, left="linear:0.492:0.1")
    pair2 = _fit("coulomb_friction+velocity_dependent_restitution", 3.0,
                 {"coulomb_friction": {"mu": 0.16}, "velocity_dependent_restitution": sloped}, 5)
    assert _constant_laws(pair2) is pair2


def test_a_best_law_per_wall_gets_forward_selection_on_its_constants_per_wall_too():
    # drawn asym + friction at 10 mm: the law per wall was best alone (gap 29, its
    # slope bent to what friction does to each wall); asym + friction (gap 1.3) was
    # never tried, as the constants per wall neither led nor removed enough to be pooled
    nominal = _fit("nominal", 2546.0, n_params=0)
    fits = [_fit("velocity_dependent_restitution", 28.6, n_params=4),
            _fit("asymmetric_restitution", 337.0, n_params=2),
            _fit("clearance_error", 632.0), _fit("inclination", 1144.0),
            _fit("coulomb_friction", 2435.0), _fit("contact_duration", 2545.0)]
    items = {(a.name, b) for a, b in _pair_items(nominal, fits)}
    assert ("asymmetric_restitution", "coulomb_friction") in items
    assert ("asymmetric_restitution", "inclination") in items
    assert ("velocity_dependent_restitution", "coulomb_friction") in items
    _tried_once_but_walls_both_ways(items)


def test_a_direct_estimate_joins_the_grid_of_a_1d_search():
    from vidiscover.gap.fit import _minimise_1d

    # a well narrower than the grid step (the gap of friction with unequal walls is
    # sharp in mu): the grid 0, 0.1, ..., 0.6 steps over it, the estimate does not
    def gap(mu):
        return 2.0 if abs(mu - 0.237) < 0.01 else 50.0 + 100.0 * abs(mu - 0.1)

    assert _minimise_1d(gap, 0.0, 0.6, n_grid=7) == pytest.approx(0.1, abs=0.03)
    assert _minimise_1d(gap, 0.0, 0.6, n_grid=7, extra=0.236) == pytest.approx(0.237, abs=0.01)
    # an estimate outside the range or undefined is ignored
    assert _minimise_1d(gap, 0.0, 0.6, n_grid=7, extra=float("nan")) == pytest.approx(
        0.1, abs=0.03)


def test_an_interval_is_never_narrower_than_the_direct_statistics_resolution(monkeypatch):
    import math
    from types import SimpleNamespace

    from vidiscover.gap import fit as gapfit
    from vidiscover.gap.components import STATS

    # a gap far sharper in the walls than r_level resolves (an attractor near a
    # bifurcation) and a flat-ish one in nothing else
    def gap_of(model, fx, _fx):
        p = fx.active["asymmetric_restitution"]
        return SimpleNamespace(total=1e6 * (p["r_right"] - 0.8) ** 2
                               + 1e2 * (p["r_left"] - 0.4) ** 2)

    monkeypatch.setattr(gapfit, "simulate_signature", lambda model, fx, r=None: fx)
    monkeypatch.setattr(gapfit, "gap_of", gap_of)
    fx = Effects.parse(["asymmetric_restitution=0.8,0.4"])
    fit = CandidateFit(name="asymmetric_restitution", params=dict(fx.active[
        "asymmetric_restitution"]), n_params=2, r=0.7, effects=fx, gap=None, signature=None)
    ci = gapfit.profile_ci(SimpleNamespace(real=None), fit)
    m = math.sqrt(3.84) * STATS["right.r_level"][1]
    assert ci["r_right"] == pytest.approx([0.8 - m, 0.8 + m])          # floor: 0.0196
    half = math.sqrt(3.84 / 1e2)                                        # curvature: 0.196
    assert ci["r_left"] == pytest.approx([0.4 - half, 0.4 + half], rel=1e-6)


def _walls_alone(case):
    """Nominal model of a battery case and unequal walls fitted alone on it."""
    from vidiscover.gap.battery import case_recording
    from vidiscover.gap.diagnose import nominal_model
    from vidiscover.gap.fit import fit_candidate

    rec, _ = case_recording(case)
    model, _, _ = nominal_model(rec)
    return model, fit_candidate(model, "asymmetric_restitution")


def _here(worker, items, cost=None):
    return [worker(i) for i in items]


#: Drawn unequal walls plus a tilt where the walls alone leave a small gap
#: (:func:`vidiscover.gap.diagnose._tilt_look`'s docstring): (battery seed, case index).
TILT_HIDDEN = ((7, 11), (4242, 11), (8, 11), (31415, 11), (13001, 23), (13007, 11))


@pytest.mark.slow
def test_a_tilt_hidden_by_unequal_walls_is_fitted_with_them():
    """Six drawn cases (four compliant, two exact) whose walls alone leave 0.4-3.8: the
    tilt is found jointly with the walls, with its sign, within 1.5 deg. Measured: 6 of
    6. 7 #11 (compliant walls r 0.83 / 0.55 and -3.03 deg at 12.8 mm) was lost with one
    pair fit from 2aba00d on: the walls' restitution moved by 1e-5 and that fit settled
    on an orbit whose momentum residuals split badly between the walls (reading 17.1);
    the look's replicates (:data:`~vidiscover.gap.diagnose.TILT_REPLICATES`) find the
    other (5.9); theta errors 0.02-1.35 deg."""
    from vidiscover.gap.battery import drawn_cases
    from vidiscover.gap.diagnose import SIGNIFICANT_DROP, _tilt_look

    found = 0
    for seed, index in TILT_HIDDEN:
        case = drawn_cases(seed, 24)[index]
        theta = float(dict(s.split("=") for s in case.spec)["inclination"])
        model, walls = _walls_alone(case)
        assert walls.gap.total < SIGNIFICANT_DROP, (seed, index)
        pair, n = _tilt_look(model, walls, _here)
        if pair is None:
            continue
        assert n > 0 and pair.name == "asymmetric_restitution+inclination"
        fitted = pair.params["inclination"]["theta"]
        assert (fitted > 0) == (theta > 0) and abs(fitted - theta) < 1.5, (
            seed, index, fitted, theta)
        assert pair.gap.total < 1.5, (seed, index)          # 0.23-1.02
        found += 1
    assert found == len(TILT_HIDDEN)


@pytest.mark.slow
def test_a_hidden_tilt_survives_a_move_of_the_walls_by_1e_5():
    """Drawn 7 #11 with the walls' fitted restitution moved by -1e-5 and +1e-5 (what a
    change of the analysis did to them): one pair fit read 17.1 at both and the tilt was
    not kept; the replicates keep it at both (and at every move of -1e-3 to 1e-3
    measured, 9 of 9, against 1 of 9 with one fit)."""
    import dataclasses

    from vidiscover.gap.battery import drawn_cases
    from vidiscover.gap.diagnose import _tilt_look
    from vidiscover.gap.fit import _shift_walls, compare, validation_signature

    model, walls = _walls_alone(drawn_cases(7, 24)[11])
    for d in (-1e-5, 1e-5):
        fx = _shift_walls(walls.effects, d, d)
        sig = validation_signature(model, fx, walls.r)
        moved = dataclasses.replace(walls, effects=fx, signature=sig,
                                    gap=compare(model.real, sig, model.rep_var))
        pair, _ = _tilt_look(model, moved, _here)
        assert pair is not None, d
        assert -4.0 < pair.params["inclination"]["theta"] < -2.5, d      # -3.03 true


@pytest.mark.slow
def test_unequal_walls_without_a_tilt_get_no_tilt():
    # the seed-0 battery's compliant unequal walls (r 0.9 / 0.5) at 10 mm, chaotic
    from vidiscover.gap.battery import extra_cases
    from vidiscover.gap.diagnose import _tilt_look

    model, walls = _walls_alone(extra_cases(0)[3])
    assert _tilt_look(model, walls, _here) == (None, 0)


def _sig(right, left, err=0.0005):
    from vidiscover.gap.components import Signature

    return Signature(values={"right.momentum": right, "left.momentum": left},
                     errors={"right.momentum": err, "left.momentum": err},
                     returnmap=None, impacts={})


def _tilt_model(right, left):
    from types import SimpleNamespace

    real = _sig(right, left)
    return SimpleNamespace(real=real, full=real, rep_var={})


def _read_fit(name, gap, n_params, right, left, theta=0.0):
    from dataclasses import replace

    sig = replace(_sig(right, left), flight_time=0.039)
    fx = Effects.parse([f"inclination={theta}"]) if theta else Effects()
    return CandidateFit(name=name, params={}, n_params=n_params, r=0.7, effects=fx,
                        gap=GapComponents({"s": float(gap)}, {}), signature=sig)


def test_the_tilt_reading_is_a_steady_force_on_both_walls():
    from vidiscover.gap.diagnose import _tilt_reading

    def walls(right, left, theta=0.0):
        return _read_fit("asymmetric_restitution", 1.0, 2, right, left, theta)

    # spent draw 13001 #23 (compliant walls and a 2.3 deg tilt): both walls' residuals
    # left by the walls alone, +0.026 / +0.025 m/s, on the floor 0.01 m/s: z^2 ~ 12.9
    z2, steady = _tilt_reading(_tilt_model(0.0262, 0.0247), walls(0.0, 0.0))
    assert steady and z2 == pytest.approx(12.9, abs=0.1)
    # compliant no-effect walls (calibration draws 7000, 7008): opposite signs, or one
    # wall 3.2 times the other, are no steady force
    assert not _tilt_reading(_tilt_model(-0.0355, 0.0343), walls(0.0, 0.0))[1]
    assert not _tilt_reading(_tilt_model(0.1597, 0.0497), walls(0.0, 0.0))[1]
    # a wall the recording has no residual on: no reading
    assert _tilt_reading(_tilt_model(math.nan, 0.03), walls(0.0, 0.0)) == (0.0, False)
    # one the simulation has none on gets the model's own (tuning draw 14902 #11, the
    # walls' multi_ipc orbit without right-wall residual): 0 without a tilt, ...
    z2, steady = _tilt_reading(_tilt_model(-0.0275, -0.0133), walls(math.nan, -0.0001))
    assert steady and z2 == pytest.approx(9.3, abs=0.1)
    # ... g sin(theta) x the mean flight time with one (-0.0287 m/s at -4.32 deg)
    z2, _ = _tilt_reading(_tilt_model(-0.0275, -0.0133), walls(math.nan, -0.0136, -4.32))
    assert z2 == pytest.approx(0.015, abs=0.005)


def test_a_steady_force_left_by_the_walls_counts_for_a_pair_with_a_tilt():
    from vidiscover.gap.diagnose import _parsimonious_pair, _steady_extra

    model = _tilt_model(0.0262, 0.0247)
    walls = _read_fit("asymmetric_restitution", 5.9, 2, 0.0, 0.0)
    tilt = _read_fit("asymmetric_restitution+inclination", 2.0, 3, 0.025, 0.025, 2.3)
    # removes 3.9 on the statistics: not kept without the reading (see above) ...
    assert not _keep_pair(walls, tilt, None)
    # ... with it the walls leave 5.9 + 12.9, the pair 2.0 + 0.0
    assert _keep_pair(walls, tilt, None, model)
    # the reading only ever helps a pair with a tilt
    other = _read_fit("asymmetric_restitution+clearance_error", 2.0, 3, 0.0, 0.0)
    assert not _keep_pair(walls, other, None, model)
    # no steady force left by the walls: no reading
    assert not _keep_pair(walls, tilt, None, _tilt_model(0.0262, -0.0247))
    # pairs are ranked with it (tuning draw 14003 #35: walls + a 0.13 mm clearance error
    # 1.61 against walls + the tilt 2.59)
    clear = _read_fit("asymmetric_restitution+clearance_error", 1.61, 3, 0.0, 0.0)
    tilt = _read_fit("asymmetric_restitution+inclination", 2.59, 3, 0.024, 0.026, 2.3)
    assert _parsimonious_pair([clear, tilt]) is clear
    assert _parsimonious_pair([clear, tilt], _steady_extra(model, walls)) is tilt


@pytest.mark.slow
def test_a_tilt_behind_exact_unequal_walls_is_read_from_the_momentum_residuals():
    # spent draw 13007 #11: exact walls r 0.745 / 0.525 and a 3.43 deg tilt at 9.4 mm
    # (2ipc_asym). The walls alone leave 3.75 (no pair search) and z^2 0.61 on the laser's
    # statistic (no laser look); both walls' momentum residuals read the tilt: +0.037 /
    # +0.036 m/s, z^2 ~ 26 on their noise scales
    from vidiscover.gap.battery import drawn_cases
    from vidiscover.gap.diagnose import SIGNIFICANT_DROP, _tilt_look, _tilt_reading

    model, walls = _walls_alone(drawn_cases(13007, 24)[11])
    assert walls.gap.total < SIGNIFICANT_DROP
    read, steady = _tilt_reading(model, walls)
    assert steady and read > 20
    pair, n = _tilt_look(model, walls, _here)
    assert pair is not None and n > 0
    assert 3.0 < pair.params["inclination"]["theta"] < 3.9     # 3.43 true


def test_the_tilt_look_keeps_the_best_of_its_replicates(monkeypatch):
    """A pair fit from one start that lands on an orbit reading the tilt badly is no
    evidence against it: the look's other starts (:data:`TILT_REPLICATES`) are fitted and
    the best kept; where the first start keeps the pair, no other is fitted."""
    import dataclasses
    import importlib
    from types import SimpleNamespace

    dg = importlib.import_module("vidiscover.gap.diagnose")   # the package exports diagnose()
    walls = dataclasses.replace(
        _fit("asymmetric_restitution", 1.0, {"r_right": 0.83, "r_left": 0.55}, 2),
        effects=Effects.parse(["asymmetric_restitution=0.83,0.55"]))
    @dataclasses.dataclass
    class _Model:
        real: object = None
        full: object = dataclasses.field(default_factory=SimpleNamespace)
        rep_var: dict = dataclasses.field(default_factory=dict)
        ball_speed: float = 0.6
        alt_speed: float = 0.45

    model = _Model()
    # the walls alone: 1.0 on the statistics (laser z^2 1.65 fires the look), reading 10
    monkeypatch.setattr(dg, "compare", lambda real, sig, rep: GapComponents(
        {"s": 1.0 - 1.65, "momentum.laser_opposite": 1.65}, {}))
    readings = {}

    def step(item):
        start, base, name = item
        k = len(readings)
        fx = base.effects.with_effect("inclination", theta=-3.1 - 0.01 * k)
        out = CandidateFit(name="inclination", params={"theta": -3.1}, n_params=1, r=0.7,
                           effects=fx, gap=GapComponents({"s": 0.6}, {}), signature=None,
                           n_sims=26)
        readings[id(fx)] = 17.0 if k in bad else 6.0
        return out

    monkeypatch.setattr(dg, "_pair_step", step)
    monkeypatch.setattr(dg, "_tilt_reading", lambda m, f: (
        10.0, True) if f is walls else (readings[id(f.effects)], True))
    calls = []

    def run(worker, items, cost=None):
        calls.append(len(items))
        return [worker(i) for i in items]

    # the walls leave 1 + 10 + 4 = 15; a replicate on the bad orbit 0.6 + 6 + 17 = 23.6
    bad = {0, 2, 4}
    pair, n = dg._tilt_look(model, walls, run)
    assert calls == [1, len(dg.TILT_REPLICATES) - 1] and n == 26 * len(dg.TILT_REPLICATES)
    assert pair is not None and pair.params["inclination"]["theta"] == pytest.approx(-3.11)
    # the first start keeps it: one fit only
    readings.clear(), calls.clear()
    bad = set()
    pair, n = dg._tilt_look(model, walls, run)
    assert calls == [1] and n == 26 and pair.params["inclination"]["theta"] == -3.1
    # every start on the bad orbit: nothing kept
    readings.clear(), calls.clear()
    bad = set(range(len(dg.TILT_REPLICATES)))
    assert dg._tilt_look(model, walls, run) == (None, 26 * len(dg.TILT_REPLICATES))
