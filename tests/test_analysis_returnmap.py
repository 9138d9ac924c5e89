"""Stage 4: first return map and the feature sets."""

import math

import numpy as np
import pytest
from analysis_sim import analysed

from vidiscover.analysis import FeatureContext, FeatureSet, Forcing, analyze, return_map
from vidiscover.analysis.returnmap import ANALYSIS_FEATURES, compute_features
from vidiscover.errors import InputError

T = 0.125


def _ctx(t, side, dv=None, duration=5.12):
    t = np.asarray(t, dtype=float)
    side = np.asarray(side)
    dv = np.where(side == "right", 0.01, -0.005) if dv is None else dv
    ts = np.arange(int(duration * 6400)) / 6400
    x = 0.005 * np.sin(2 * np.pi * 8 * ts)
    return FeatureContext(t=t, side=side, dv=np.asarray(dv, float), t_start=0.0,
                          t_end=duration, forcing=Forcing(8.0, 5e-4, 0.0), ts=ts, x=x,
                          returnmap=return_map(t, side, T))


def _two_asymmetric(n_cycles=40, lag=0.03):
    t = np.sort(np.r_[np.arange(n_cycles) * T + 0.01, np.arange(n_cycles) * T + 0.01 + lag])
    side = np.array(["right", "left"] * n_cycles)
    return t, side


def test_two_asymmetric_impacts_per_cycle_give_two_mirrored_points():
    t, side = _two_asymmetric()
    rm = return_map(t, side, T)
    assert rm.n_points == t.size - 2 and rm.n_clusters == 2
    c = rm.centres[np.argsort(rm.centres[:, 0])]
    assert np.allclose(c[0], [0.03, T - 0.03], atol=1e-9)
    assert np.allclose(c[1], [T - 0.03, 0.03], atol=1e-9)
    f = compute_features(_ctx(t, side))
    assert f["impacts_per_cycle"] == pytest.approx(2.0)
    assert f["two_per_cycle_share"] == pytest.approx(1.0)
    assert f["alternation"] == 1.0 and f["chatter_share"] == 0.0
    assert f["asymmetry"] == pytest.approx((T - 0.06) / T)
    assert f["returnmap_clusters"] == 2 and f["returnmap_spread"] == pytest.approx(0.0)
    assert f["diagonal_distance"] == pytest.approx((T - 0.06) / math.sqrt(2) / T)


def test_symmetric_regime_sits_on_the_diagonal():
    t, side = _two_asymmetric(lag=T / 2)
    f = compute_features(_ctx(t, side))
    assert f["diagonal_distance"] == pytest.approx(0.0, abs=1e-9)
    assert f["asymmetry"] == pytest.approx(0.0, abs=1e-9)


def test_irregular_impacts_spread_out():
    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(0, 5.12, 80))
    side = np.where(rng.random(80) < 0.5, "right", "left")
    f = compute_features(_ctx(t, side))
    t2, s2 = _two_asymmetric()
    g = compute_features(_ctx(t2, s2))
    assert f["returnmap_spread"] > 10 * max(g["returnmap_spread"], 1e-6)
    assert f["dt_cv"] > g["dt_cv"]


@pytest.mark.parametrize("case", ["none", "one", "two", "regular"])
def test_every_feature_is_a_float_in_every_case(case):
    t, side = {"none": ([], []), "one": ([1.0], ["left"]),
               "two": ([1.0, 1.05], ["left", "right"]), "regular": _two_asymmetric()}[case]
    f = compute_features(_ctx(t, side))
    assert list(f) == list(ANALYSIS_FEATURES)
    assert all(isinstance(v, float) for v in f.values())
    assert f["n_impacts"] == len(t)


def test_feature_sets_combine_select_and_refuse_clashes():
    extra = FeatureSet({"first": lambda ctx: float(ctx.t[0]) if ctx.t.size else math.nan})
    both = ANALYSIS_FEATURES | extra
    assert list(both) == [*ANALYSIS_FEATURES, "first"]
    assert ANALYSIS_FEATURES | ANALYSIS_FEATURES == ANALYSIS_FEATURES   # same functions
    with pytest.raises(ValueError, match="defined differently"):
        ANALYSIS_FEATURES | {"n_impacts": lambda ctx: 0.0}
    sel = both.select(["first", "n_impacts"])
    t, side = _two_asymmetric()
    assert compute_features(_ctx(t, side), sel) == {"first": t[0], "n_impacts": t.size}
    with pytest.raises(KeyError, match="not in this set"):
        ANALYSIS_FEATURES.select(["first"])
    with pytest.raises(TypeError, match="not callable"):
        FeatureSet({"x": 1.0})
    assert "first" not in ANALYSIS_FEATURES        # combining changed neither set


def test_analyze_computes_the_set_it_is_given_and_refuses_names():
    out, _ = analysed(0.009)
    rec = out.recording
    sel = ANALYSIS_FEATURES.select(["alternation"])
    assert list(analyze(rec, n_boot=0, features=sel).features) == ["alternation"]
    with pytest.raises(InputError, match="FeatureSet"):
        analyze(rec, n_boot=0, features=("alternation",))


def test_simulated_paper_case_features():
    out, _ = analysed(0.009)
    f = out.features
    assert set(f) == set(ANALYSIS_FEATURES)     # the analysis's own set, by default
    assert f["impacting_cycle_share"] == 1.0
    assert f["chatter_share"] > 0.3                  # left-wall chatter
    assert f["strobe_period_error"] < 0.01          # periodic
    assert f["envelope_modulation"] < 0.05
    rm = out.returnmap
    assert rm.to_frame().shape == (rm.n_points, 4)
