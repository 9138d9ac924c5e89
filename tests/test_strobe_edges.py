"""Features reading x at or between cycle starts keep away from the reconstruction's ends.

The reconstruction's drift smoother fits one-sided within half its window of either end
of the record, so x is off there (realism corpus test-051: 0.39 of max |x| at the last
sample, which was also a cycle start; ``strobe_period_error`` read 0.394 from it alone).
"""

import inspect

import numpy as np
import pytest

from vidiscover.analysis import FeatureContext, Forcing, return_map
from vidiscover.analysis.reconstruction import reconstruct
from vidiscover.analysis.returnmap import ANALYSIS_FEATURES, EDGE_MARGIN, compute_features
from vidiscover.regimes.features import ALL_FEATURES, STATE_FEATURES

F, FS, AMP = 8.0, 6400, 0.005


def _ctx(duration=5.0, start_error=0.3, end_error=0.4):
    """Period-1 LO motion whose first and last samples are cycle starts, its ends off.

    The error decays linearly over 0.03 s from the start and grows over 0.04 s to the
    end (``*_error`` of max |x| at the first / last sample), like the drift smoother's.
    """
    ts = np.arange(int(round(duration * FS)) + 1) / FS          # last sample = 5.0 s
    x = AMP * np.sin(2 * np.pi * F * ts + 0.5)
    x += AMP * start_error * np.clip(1 - ts / 0.03, 0, None)
    x -= AMP * end_error * np.clip(1 - (ts[-1] - ts) / 0.04, 0, None)
    t = np.arange(1, int(duration * F)) / F + 0.01
    side = np.array(["right", "left"] * (t.size // 2) + ["right"] * (t.size % 2))
    return FeatureContext(t=t, side=side, dv=np.where(side == "right", 0.01, -0.01),
                          t_start=0.0, t_end=float(ts[-1]) + 1 / FS,
                          forcing=Forcing(F, 5e-4, 0.0), ts=ts, x=x,
                          returnmap=return_map(t, side, 1 / F))


def test_edge_margin_is_half_the_reconstructions_drift_window():
    window = inspect.signature(reconstruct).parameters["drift_window"].default
    assert EDGE_MARGIN == pytest.approx(window / 2)


def test_motion_cycles_drop_the_starts_near_either_end_and_keep_the_rest_consecutive():
    ctx = _ctx()
    c, m = ctx.cycles(), ctx.motion_cycles()
    assert c[0] == 0.0 and c[-1] == pytest.approx(5.0)          # on the first / last sample
    assert np.array_equal(m, c[1:-1])
    assert np.allclose(np.diff(m), 1 / F)
    assert not m.flags.writeable


def test_a_last_cycle_start_on_the_last_sample_gives_no_strobe_or_waveform_error():
    ctx = _ctx()
    # what strobe_period_error read before: x at every cycle start, the last one on the
    # record's last sample
    c = ctx.cycles()
    xs = np.interp(c, ctx.ts, ctx.x)[c.size // 2:]
    assert np.abs(np.diff(xs)).max() / ctx.amplitude() > 0.3
    f = compute_features(ctx, ALL_FEATURES | STATE_FEATURES)
    assert f["strobe_period_error"] < 1e-9
    assert f["waveform_period_error"] < 1e-9
    assert f["waveform_period"] == 1.0
    assert f["envelope_modulation"] < 1e-9
    assert f["envelope_cv"] < 1e-9
    assert f["strobe_dispersion"] < 1e-9
    assert f["strobe_state_error"] < 1e-9


def test_the_same_motion_without_edge_errors_reads_the_same():
    clean = compute_features(_ctx(start_error=0.0, end_error=0.0), ANALYSIS_FEATURES)
    off = compute_features(_ctx(), ANALYSIS_FEATURES)
    for name in ("strobe_period_error", "envelope_modulation"):
        assert off[name] == pytest.approx(clean[name], abs=1e-12)


def test_too_few_cycles_away_from_the_ends_is_undefined():
    ctx = _ctx(duration=0.75)                                  # 7 starts, 5 kept
    assert ctx.motion_cycles().size == 5
    f = compute_features(ctx, ANALYSIS_FEATURES)
    assert np.isnan(f["strobe_period_error"])


def test_max_x_leaves_the_ends_out():
    ctx = _ctx(start_error=2.0, end_error=-2.0)                # ends 2 x max |x| off
    assert np.abs(ctx.x).max() > 2 * AMP
    assert ctx.amplitude() == pytest.approx(AMP, rel=1e-5)          # sampled peak
    short = _ctx(duration=0.0625, start_error=0.0, end_error=0.0)   # nothing inside
    assert short.amplitude() == pytest.approx(np.abs(short.x).max())
