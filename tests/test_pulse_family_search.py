"""The pulse learner's family search: each filter kind's best family is refined, and a
"contact" that is an extra filter pole sends the search wide."""

from __future__ import annotations

import numpy as np
from corpus_scoring import episodes


def test_a_linear_phase_chain_is_not_outranked_by_six_smooth_causal_families():
    # dev-023: Hunt-Crossley walls behind a linear-phase filter at 6400 Hz. The six
    # families refined were all Bessels (the best coarse misfits), and a Bessel-2 was
    # learned: entries 71 us late. With each kind's best family refined beside them
    # (coarse misfit within 4x of the best), the linear-phase family is learned: 9.3 us
    imp, ok, det, ie, it = episodes("dev", 23)
    assert det.response.model.kind == "linear-phase"
    assert ie.size == det.n == ok.sum() == 120
    assert np.median(np.abs(det.t[ie] - imp.t_in[it])) < 20e-6   # measured 9.3 us; was 71


def test_a_steep_chain_behind_a_hunt_crossley_contact_is_not_a_smooth_one_with_a_pole():
    # holdout10-048 (a spent split): Butterworth-7 at 4136 Hz (0.40 fs, 10240 Hz), 692 us
    # Hunt-Crossley contacts. Ranked by the half-sine coarse grid no Butterworth was
    # refined (coarse misfit 0.033; refined with a skewed contact 0.0015), and a Bessel-5
    # with a 1.6 ms arch "contact" at the skew range's edge (an exponential force: one more
    # real pole) was learned at 0.0046: every entry 91 us late. That edge now sends the
    # search wide (every coarse shape, each kind's best two refined, no edge arch kept):
    # Butterworth-8 with a viscous-wall shape, measured 10.3 us late
    imp, ok, det, ie, it = episodes("holdout10", 48)
    assert det.response.model.kind == "butter"
    assert ie.size == det.n == imp.t_in.size == 80
    err = det.t[ie] - imp.t_in[it]
    assert abs(float(np.median(err))) < 20e-6                 # measured 10.3 us; was 91
