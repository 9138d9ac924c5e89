"""Stage 3: restitution per impact and per wall against simulated truth.

Figures: per-wall RMS of the estimated r within 0.02 of the RMS of the true r of
the same impacts, for b in {6, 7.5, 9} mm and two noise seeds; with Coulomb
friction mu = 0.3 in the data and mu = 0.3 assumed, the same tolerance. The mu
table (paper Table 2) moves monotonically with mu -- upwards: the physically
consistent friction correction makes the ball faster at departure and slower at
arrival than its mean velocity, so r rises with mu (the paper reports a slow
decrease, which a friction force opposing z' cannot produce).
"""

import json

import numpy as np
import pytest
from analysis_sim import ASYM, CLEARANCES, SEEDS, analysed, recording, true_r_rms

from vidiscover import InputError
from vidiscover.analysis import MU_TABLE, estimate_restitution, mu_table
from vidiscover.analysis.restitution import R_MAX, RESTITUTION_COLUMNS

TOL = 0.02


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("b", CLEARANCES)
def test_per_wall_rms_matches_the_truth(b, seed):
    out, truth = analysed(b, ASYM, seed)
    for side, r0 in (("right", 0.88), ("left", 0.20)):
        w = out.restitution.wall(side)
        true_rms, n = true_r_rms(out, truth, side)
        assert n == w.n and n >= 30, (side, n, w.n)
        assert abs(w.rms - true_rms) <= TOL, (side, w.rms, true_rms)
        assert w.ci_low <= w.rms <= w.ci_high
        assert abs(w.median - r0) <= TOL


def test_chatter_policy():
    """The last seen re-impact before sticking has no observable rebound: 'sticks'."""
    out, _ = analysed(0.009)
    c = out.restitution.columns
    fc = out.reconstruction.flight_columns
    stick_starts = fc["i_start"][fc["kind"] == "stick"]
    assert np.all(c["status"][stick_starts] == "sticks")
    assert not c["used"][stick_starts].any()
    # earlier re-impacts of the chatter sequences with an observed rebound do count
    side = c["side"]
    rechatter = np.flatnonzero((side[1:] == side[:-1]) & c["used"][1:]) + 1
    assert rechatter.size >= 30
    assert np.all(np.abs(c["r"][rechatter] - 0.2) < 0.03)
    assert set(np.unique(c["status"])) <= {"ok", "edge", "sticks", "pulse", "direction",
                                           "implausible", "noisy"}
    assert tuple(out.restitution.table.columns) == RESTITUTION_COLUMNS


@pytest.mark.parametrize("b", [0.006, 0.009])
def test_friction_corrected_r(b):
    fx = ASYM + ("coulomb_friction=0.3",)
    out, truth = analysed(b, fx, 1, mu=0.3)
    for side in ("right", "left"):
        w = out.restitution.wall(side)
        true_rms, n = true_r_rms(out, truth, side)
        assert n >= 30
        assert abs(w.rms - true_rms) <= TOL, (side, w.rms, true_rms)
    # ignoring the friction underestimates r clearly
    out0, _ = analysed(b, fx, 1, mu=0.0)
    assert out0.restitution.right.rms < 0.88 - 0.1


def test_mu_table_trend_on_friction_data():
    """On data with mu = 0.3 the table brackets the truth between mu = 0.2 and 0.4,
    r grows with mu on both walls, and large mu raises the 'too slow' flag."""
    rec, _ = recording(0.009, ASYM + ("coulomb_friction=0.3",))
    out, _ = analysed(0.009, ASYM + ("coulomb_friction=0.3",))
    tab = out.mu_table()
    assert tab["mu"].tolist() == list(MU_TABLE)
    right = tab["right_rms"].to_numpy()
    ok = np.isfinite(right)
    assert np.all(np.diff(right[ok]) > 0)
    assert right[2] < 0.88 < right[3]                 # mu = 0.2 | 0.4
    left = tab["left_rms"].to_numpy()
    assert np.all(np.diff(left[np.isfinite(left)]) > 0)
    assert not tab["right_warn"].iloc[0] and tab["right_warn"].iloc[-2]


def test_mu_table_on_frictionless_data_changes_slowly_at_small_mu():
    out, _ = analysed(0.009)
    tab = out.mu_table([0.0, 0.01, 0.02])
    r = tab["right_rms"].to_numpy()
    assert np.all(np.diff(r) > 0)
    assert r[-1] - r[0] < 0.03                      # a slow change for a fast ball
    assert abs(r[0] - 0.88) < TOL


def test_wall_stats_are_json_ready():
    out, _ = analysed(0.0075)
    d = out.restitution.right.to_dict()
    json.dumps(d, allow_nan=False)
    assert set(d) >= {"n", "mean", "median", "rms", "std", "ci_low", "ci_high"}


def test_bootstrap_is_seeded():
    out, _ = analysed(0.009)
    a = estimate_restitution(out.reconstruction, out.detection, seed=5)
    b = estimate_restitution(out.reconstruction, out.detection, seed=5)
    assert a.left.ci_low == b.left.ci_low and a.left.ci_high == b.left.ci_high


def test_implausible_r_is_not_used():
    out, _ = analysed(0.009)
    c = out.restitution.columns
    assert np.all(c["r"][c["used"]] <= R_MAX)


def test_bad_arguments():
    out, _ = analysed(0.009)
    with pytest.raises(InputError, match="level .of the confidence interval. must be in"):
        estimate_restitution(out.reconstruction, level=1.5)
    with pytest.raises(InputError, match="side must be"):
        out.restitution.wall("middle")


@pytest.mark.slow
def test_restitution_over_many_seeds():
    for b in CLEARANCES:
        for seed in range(3, 9):
            out, truth = analysed(b, ASYM, seed)
            for side in ("right", "left"):
                true_rms, _ = true_r_rms(out, truth, side)
                assert abs(out.restitution.wall(side).rms - true_rms) <= TOL


def test_mu_table_function_matches_the_method():
    rec, _ = recording(0.009)
    out, _ = analysed(0.009)
    a = mu_table(out.detection, rec, [0.0, 0.1])
    b = out.mu_table([0.0, 0.1])
    assert np.allclose(a["right_rms"], b["right_rms"])


@pytest.mark.parametrize("mu", [0.0, 0.2])
def test_friction_table_reuses_the_lo_motion_and_equals_a_full_reconstruction(mu):
    """refly (the table's path) solves the ball's flights only; the LO motion is shared."""
    from vidiscover.analysis import reconstruct
    from vidiscover.analysis.reconstruction import refly

    fx = ASYM + ("coulomb_friction=0.3",)
    out, _ = analysed(0.009, fx, 1, mu=0.3)
    full = reconstruct(out.detection, out._recording, b=out.b, mu=mu)
    fast = refly(out.reconstruction, out.detection, mu)
    assert fast.x is out.reconstruction.x and fast.v is out.reconstruction.v
    assert fast.n_flights == full.n_flights >= 60
    for cols in ("impact_columns", "flight_columns"):
        for k, want in getattr(full, cols).items():
            got = getattr(fast, cols)[k]
            if want.dtype.kind == "f":
                # measured: <= 2.2e-16 (one subtraction's rounding in the LO velocity)
                np.testing.assert_allclose(got, want, rtol=0, atol=1e-12, err_msg=k)
            else:
                np.testing.assert_array_equal(got, want, err_msg=k)
