"""The regime features: an explicit feature set beside the analysis's own.

:data:`REGIME_FEATURES` is a :class:`~vidiscover.analysis.returnmap.FeatureSet`;
:data:`ALL_FEATURES` adds it to the analysis's
(:data:`~vidiscover.analysis.returnmap.ANALYSIS_FEATURES`), and is what the classifier
needs: ``analyze(rec, features=ALL_FEATURES)``. Importing this module registers
nothing. Like the stage-4 features they see only the recording (detected impacts, the
LO displacement and the fitted forcing), never the simulated truth; each returns a
float, NaN when undefined for the record.

* cycle counts: ``one_per_cycle_share``, ``multi_per_cycle_share``, ``count_std``,
  ``modal_count_share``, ``quiet_run`` (longest run of impact-free cycles);
* impact timing: ``phase_coherence`` (impacts locked to the forcing phase),
  ``dt_max`` / ``dt_min`` (longest / shortest gap, in periods), ``side_run`` (longest
  run of impacts on one wall, per cycle);
* return map: ``returnmap_top_share`` (points in the four largest clusters),
  ``returnmap_cluster_density`` (clusters per point);
* LO response: ``waveform_period_error`` (the displacement over a cycle repeats
  after p <= 4 cycles), ``waveform_period`` (that p, 0 if none), ``strobe_dispersion``
  (spread of the stroboscopic section), ``envelope_cv``; in :data:`STATE_FEATURES`
  (part of :data:`ALL_FEATURES`), ``strobe_state_error`` (the labels' periodicity
  test on the stroboscopic LO state, x and x');
* strengths: ``dv_side_ratio`` (|log| of the mean pulse ratio right/left);
* saturation: ``saturated_cycle_share``, the share of complete cycles in which the
  accelerometer is on its rail for longer than a clipped pulse (the forced response
  saturates and hides the impacts there): impacts cannot be counted there, and the
  rules claim ``no_impact`` only where they can
  (:class:`~vidiscover.regimes.classifier.RuleBaseline`). The model does not read it
  (:data:`~vidiscover.regimes.classifier.EXCLUDED_FEATURES`);
* in :data:`IMPACT_FEATURES` (part of :data:`ALL_FEATURES`), the strong impacts
  (|dv| >= :data:`STRONG_SHARE` of their wall's 90th percentile): ``strong_per_cycle``,
  ``strong_one_share``, ``strong_two_share``, ``strong_alternation``, ``weak_share``,
  and the repetition of their sequence after p <= 4 cycles, ``impact_period_error``
  (timing, in periods) and ``impact_dv_error`` (relative |dv|);
* in :data:`MERGED_FEATURES` (part of :data:`ALL_FEATURES`), the impacts as the labels
  count them: consecutive detections on the same wall less than
  :data:`~vidiscover.regimes.labels.RETURN_TAU` periods apart are one impact, the first
  (:func:`merged_impacts`): ``merged_per_cycle``, ``merged_cycle_share``,
  ``merged_one_share``, ``merged_two_share``, ``merged_alternation`` and
  ``merged_asymmetry``, the analysis's ``impacts_per_cycle``,
  ``impacting_cycle_share``, ``two_per_cycle_share``, ``alternation``, ``asymmetry``
  and ``one_per_cycle_share`` of the merged impacts (what the rule baseline reads).

Examples
--------
>>> from vidiscover.regimes.features import ALL_FEATURES, REGIME_FEATURES
>>> len(REGIME_FEATURES), set(REGIME_FEATURES) < set(ALL_FEATURES)
(17, True)
"""

from __future__ import annotations

import math

import numpy as np

from ..analysis.returnmap import (
    ANALYSIS_FEATURES,
    FeatureContext,
    FeatureSet,
    alternation_asymmetry,
    alternation_share,
    cycle_counts,
)
from .labels import same_wall_returns

__all__ = ["REGIME_FEATURES", "ALL_FEATURES", "STATE_FEATURES", "IMPACT_FEATURES",
           "MERGED_FEATURES", "cycle_waveforms", "merged_impacts"]

_NAN = float("nan")
#: Samples per cycle of the resampled LO waveform.
_WAVE_POINTS = 64
#: ``waveform_period_error`` below this (relative to max |x|) counts as periodic.
PERIODIC_TOL = 0.02


def _counts(ctx: FeatureContext) -> np.ndarray:
    return ctx.counts()


def _share1(ctx: FeatureContext) -> float:
    """Share of complete cycles with exactly one impact."""
    c = _counts(ctx)
    return float((c == 1).mean()) if c.size else _NAN


def _share3(ctx: FeatureContext) -> float:
    """Share of complete cycles with three or more impacts."""
    c = _counts(ctx)
    return float((c >= 3).mean()) if c.size else _NAN


def _count_std(ctx: FeatureContext) -> float:
    """Standard deviation of the impacts per cycle."""
    c = _counts(ctx)
    return float(c.std()) if c.size else _NAN


def _modal(ctx: FeatureContext) -> float:
    """Share of cycles with the most common number of impacts."""
    c = _counts(ctx)
    return float(np.bincount(c).max() / c.size) if c.size else _NAN


def _quiet_run(ctx: FeatureContext) -> float:
    """Longest run of consecutive impact-free cycles, as a share of the cycles."""
    c = _counts(ctx)
    if c.size == 0:
        return _NAN
    best = run = 0
    for quiet in c == 0:
        run = run + 1 if quiet else 0
        best = max(best, run)
    return float(best / c.size)


def _phase(ctx: FeatureContext) -> float:
    """Locking of the impacts to the forcing phase.

    Mean resultant length of the impact phases on each wall, weighted by count: 1
    when every impact on a wall comes at the same forcing phase.
    """
    if ctx.t.size == 0:
        return _NAN
    ph = 2 * math.pi * ctx.t / ctx.period + ctx.forcing.phase
    total = 0.0
    for s in ("right", "left"):
        m = ctx.side == s
        if m.any():
            total += abs(np.exp(1j * ph[m]).sum())
    return float(total / ctx.t.size)


def _dt_max(ctx: FeatureContext) -> float:
    """Longest time between consecutive impacts, in forcing periods."""
    dt = ctx.returnmap.dt
    return float(dt.max() / ctx.period) if dt.size else _NAN


def _dt_min(ctx: FeatureContext) -> float:
    """Shortest time between consecutive impacts, in forcing periods."""
    dt = ctx.returnmap.dt
    return float(dt.min() / ctx.period) if dt.size else _NAN


def _side_run(ctx: FeatureContext) -> float:
    """Longest run of consecutive impacts on the same wall, per forcing cycle.

    In cycles rather than impacts, so that it does not grow with the record length
    (a one-sided motion gives its impacts per cycle, alternation about 1 / cycles).
    """
    if ctx.t.size == 0:
        return _NAN
    same = np.r_[False, ctx.side[1:] == ctx.side[:-1]]
    best = run = 1
    for s in same[1:]:
        run = run + 1 if s else 1
        best = max(best, run)
    n_cycles = max(ctx.cycles().size - 1, 1)
    return float(best / n_cycles)


def _top_share(ctx: FeatureContext) -> float:
    """Share of the return-map points in its four largest clusters."""
    rm = ctx.returnmap
    if rm.n_points == 0:
        return _NAN
    counts = np.sort(np.bincount(rm.cluster))[::-1]
    return float(counts[:4].sum() / rm.n_points)


def _density(ctx: FeatureContext) -> float:
    """Number of return-map clusters per point (1 for a cloud, ~0 for a few points)."""
    rm = ctx.returnmap
    return float(rm.n_clusters / rm.n_points) if rm.n_points else _NAN


def _dv_ratio(ctx: FeatureContext) -> float:
    """|log(mean |dv| right / mean |dv| left)|: how differently the walls push the LO."""
    a = np.abs(ctx.dv)
    r, le = a[ctx.side == "right"], a[ctx.side == "left"]
    if not (r.size and le.size) or r.mean() <= 0 or le.mean() <= 0:
        return _NAN
    return float(abs(math.log(r.mean() / le.mean())))


def cycle_waveforms(ctx: FeatureContext, points: int = _WAVE_POINTS) -> np.ndarray:
    """LO displacement over each complete cycle, resampled at ``points`` phases.

    The cycles between the starts of
    :meth:`~vidiscover.analysis.returnmap.FeatureContext.motion_cycles`: none reaches
    into the reconstruction's ends, where x is off.

    Parameters
    ----------
    ctx : FeatureContext
        The record.
    points : int
        Samples per cycle.

    Returns
    -------
    ndarray, shape (n_cycles, points)
        Empty when there is no complete cycle or no finite displacement.
    """
    return ctx.memo(("cycle_waveforms", points), lambda c: _cycle_waveforms(c, points))


def _cycle_waveforms(ctx: FeatureContext, points: int) -> np.ndarray:
    c = ctx.motion_cycles()
    ts, xf = ctx.finite_motion()
    if c.size < 2 or xf.size < 2:
        return np.zeros((0, points))
    grid = c[:-1, None] + np.diff(c)[:, None] * (np.arange(points) / points)[None, :]
    w = np.interp(grid.ravel(), ts, xf).reshape(grid.shape)
    w.flags.writeable = False                 # shared by the features of one context
    return w


def _waveform_errors(ctx: FeatureContext) -> tuple[float, ...]:
    """Worst RMS change of the cycle waveform over p = 1..4 cycles.

    Over the last half of the record, relative to max |x| (once per context).
    """
    return ctx.memo("waveform_errors", _waveform_errors_of)


def _waveform_errors_of(ctx: FeatureContext) -> tuple[float, ...]:
    w = cycle_waveforms(ctx)
    amp = ctx.amplitude()
    if w.shape[0] < 6 or not amp > 0:
        return ()
    w = w[w.shape[0] // 2:]
    out = []
    for p in range(1, 5):
        if w.shape[0] <= p:
            break
        rms = np.sqrt(np.mean((w[p:] - w[:-p]) ** 2, axis=1))
        out.append(float(rms.max() / amp))
    return tuple(out)


def _wave_err(ctx: FeatureContext) -> float:
    """How far the LO response is from periodic (~0 when periodic).

    Min over p <= 4 of the worst RMS change of the LO waveform over p cycles (last
    half of the record) relative to max |x|.
    """
    e = _waveform_errors(ctx)
    return float(min(e)) if e else _NAN


def _wave_period(ctx: FeatureContext) -> float:
    """Smallest p <= 4 with ``waveform_period_error`` below 2 %, 0 if none."""
    e = _waveform_errors(ctx)
    if not e:
        return _NAN
    for p, err in enumerate(e, start=1):
        if err < PERIODIC_TOL:
            return float(p)
    return 0.0


def _strobe_disp(ctx: FeatureContext) -> float:
    """Spread of the stroboscopic section of the LO displacement.

    Standard deviation of x at the cycle starts relative to max |x|: ~0 for period
    1, larger for subharmonic, quasi-periodic or irregular motion.
    """
    w = cycle_waveforms(ctx)
    amp = ctx.amplitude()
    if w.shape[0] < 2 or not amp > 0:
        return _NAN
    return float(w[:, 0].std() / amp)


def _lo_velocity(ctx: FeatureContext) -> tuple[np.ndarray, np.ndarray]:
    """(ts, v): the LO velocity, the derivative of a cubic Savitzky-Golay fit to x.

    Over windows of a sixteenth of the forcing period (at least 7 samples), on the
    record's sample grid (non-finite samples interpolated first), half a window
    short of either end of the record, where the fit would reach past it (once per
    context).
    """
    return ctx.memo("lo_velocity", _lo_velocity_of)


def _lo_velocity_of(ctx: FeatureContext) -> tuple[np.ndarray, np.ndarray]:
    from scipy.ndimage import correlate1d

    from ..analysis.signals import savgol_taps

    ts, xf = ctx.finite_motion()
    if xf.size < 16:
        return np.zeros(0), np.zeros(0)
    ts_all = np.asarray(ctx.ts, float)
    x = xf if ts is ts_all or xf.size == ts_all.size else np.interp(ts_all, ts, xf)
    dt = float(np.median(np.diff(ts_all)))
    win = max(7, int(round(ctx.period / (16 * dt))) | 1)
    if win >= x.size or not dt > 0:
        return np.zeros(0), np.zeros(0)
    h = win // 2                              # the fit reaches past the record there
    if x.size <= 2 * h + 1:
        return np.zeros(0), np.zeros(0)
    # savgol_filter(x, win, 3, deriv=1, delta=dt)'s interior, bit for bit, without
    # importing scipy.signal (0.5-0.9 s per process)
    taps = savgol_taps(win, 3, deriv=1, delta=dt, use="conv")[::-1]
    v = correlate1d(np.asarray(x, dtype=float), taps, mode="nearest")[h:x.size - h]
    v.flags.writeable = False
    return ts_all[h:x.size - h], v


def _strobe_state(ctx: FeatureContext) -> float:
    """Periodicity error of the stroboscopic LO state (x, x'), as the labels test it.

    Min over p <= 4 of the larger of the largest changes over p cycles of x and of
    x' at the cycle starts (last half of the record; those of
    :meth:`~vidiscover.analysis.returnmap.FeatureContext.motion_cycles` where x' is
    known), each relative to its largest magnitude over the record (max |x|, max |x'|;
    x' from :func:`_lo_velocity`).
    ``strobe_period_error`` reads x alone: a weakly irregular motion whose x repeats
    to within 1 % while x' does not is periodic to it and chaotic to the labels.
    """
    c = ctx.motion_cycles()
    ts, xf = ctx.finite_motion()
    tv, v = _lo_velocity(ctx)
    amp = ctx.amplitude()
    if c.size < 6 or xf.size == 0 or v.size == 0 or not amp > 0:
        return _NAN
    vmax = float(np.abs(v).max())
    if not vmax > 0:
        return _NAN
    c = c[(c >= tv[0]) & (c <= tv[-1])]       # cycle starts where x' is known
    if c.size < 6:
        return _NAN
    xs = np.interp(c, ts, xf)[c.size // 2:]
    vs = np.interp(c, tv, v)[c.size // 2:]
    best = _NAN
    for p in range(1, 5):
        if xs.size <= p:
            break
        e = max(float(np.abs(xs[p:] - xs[:-p]).max()) / amp,
                float(np.abs(vs[p:] - vs[:-p]).max()) / vmax)
        best = e if not (best <= e) else best
    return best


def _env_cv(ctx: FeatureContext) -> float:
    """Coefficient of variation of the per-cycle LO half peak-to-peak."""
    w = cycle_waveforms(ctx)
    if w.shape[0] < 2:
        return _NAN
    a = 0.5 * (w.max(axis=1) - w.min(axis=1))
    return float(a.std() / a.mean()) if a.mean() > 0 else _NAN


#: An impact is "strong" when its |dv| is at least this share of the 90th percentile
#: of |dv| on its wall: weaker detections are a contact split in two, a ringing
#: instrument's lobe or the tail of a chatter sequence, which the detection finds
#: in some recordings and not in others.
STRONG_SHARE = 0.1


def _strong(ctx: FeatureContext) -> np.ndarray:
    """Mask of the strong impacts (:data:`STRONG_SHARE`; once per context)."""
    return ctx.memo("strong", _strong_of)


def _strong_of(ctx: FeatureContext) -> np.ndarray:
    a = np.abs(np.asarray(ctx.dv, float))
    keep = np.zeros(a.size, dtype=bool)
    for s in ("right", "left"):
        m = ctx.side == s
        if m.any():
            keep[m] = a[m] >= STRONG_SHARE * np.percentile(a[m], 90)
    keep.flags.writeable = False
    return keep


def _strong_counts(ctx: FeatureContext) -> np.ndarray:
    """Strong impacts per complete cycle (once per context)."""
    return ctx.memo("strong_counts", lambda c: cycle_counts(np.asarray(c.t, float)[_strong(c)],
                                                            c.cycles()))


def _strong_ipc(ctx: FeatureContext) -> float:
    """Mean strong impacts (:data:`STRONG_SHARE`) per complete cycle."""
    c = _strong_counts(ctx)
    return float(c.mean()) if c.size else _NAN


def _strong_share1(ctx: FeatureContext) -> float:
    """Share of complete cycles with exactly one strong impact."""
    c = _strong_counts(ctx)
    return float((c == 1).mean()) if c.size else _NAN


def _strong_share2(ctx: FeatureContext) -> float:
    """Share of complete cycles with exactly two strong impacts."""
    c = _strong_counts(ctx)
    return float((c == 2).mean()) if c.size else _NAN


def _strong_alternation(ctx: FeatureContext) -> float:
    """Share of consecutive strong impacts on opposite walls."""
    s = ctx.side[_strong(ctx)]
    return float((s[1:] != s[:-1]).mean()) if s.size >= 2 else _NAN


def _weak_share(ctx: FeatureContext) -> float:
    """Share of the detected impacts that are not strong."""
    return float(1.0 - _strong(ctx).mean()) if ctx.t.size else _NAN


def _impact_period_error(ctx: FeatureContext) -> float:
    """How far the strong impacts are from repeating after p <= 4 cycles, in periods.

    Over the last half of the record: for each strong impact, the time from p periods
    after it to the nearest strong impact on the same wall (half a period when there
    is none); the 90th percentile of those, the smallest over p. Impact times are
    measured to tens of microseconds, so a slowly drifting (quasi-periodic or weakly
    chaotic) motion whose stroboscopic LO state repeats to within the reconstruction's
    error still shows here.
    """
    def wall(ts, av, src, shift, T):
        if not src.any():
            return None
        want = ts[src] + shift
        j = np.clip(np.searchsorted(ts, want), 1, ts.size - 1)
        d = np.minimum(np.abs(ts[j] - want), np.abs(ts[j - 1] - want))
        return np.minimum(d / T, 0.5)

    return _repeat_error(ctx, wall)


def _impact_dv_error(ctx: FeatureContext) -> float:
    """How far the strong impacts' |dv| are from repeating after p <= 4 cycles.

    As ``impact_period_error``, the relative change of |dv| to the impact nearest
    p periods later on the same wall (1 when none is within a tenth of a period),
    90th percentile, smallest over p.
    """
    def wall(ts, av, src, shift, T):
        if not src.any() or ts.size < 2:
            return None
        want = ts[src] + shift
        j = np.clip(np.searchsorted(ts, want), 1, ts.size - 1)
        j = np.where(np.abs(ts[j - 1] - want) < np.abs(ts[j] - want), j - 1, j)
        near = np.abs(ts[j] - want) <= 0.1 * T
        rel = np.abs(av[j] - av[src]) / np.maximum(av[src], 1e-300)
        return np.where(near, np.minimum(rel, 1.0), 1.0)

    return _repeat_error(ctx, wall)


def _repeat_error(ctx: FeatureContext, wall) -> float:
    """Smallest over p <= 4 of the 90th percentile of the strong impacts' repeat errors.

    ``wall(ts, abs_dv, src, p T, T)`` gives, for one wall's strong impacts (times
    ``ts``, ``|dv|``), the errors of those in ``src`` (the last half of the record,
    with p periods after them inside it) against the impacts p periods later, or None.
    NaN with fewer than 8 strong impacts or no forcing period.
    """
    m = _strong(ctx)
    t, side, a = np.asarray(ctx.t, float)[m], ctx.side[m], np.abs(np.asarray(ctx.dv, float))[m]
    T = ctx.period
    if t.size < 8 or not T > 0:
        return _NAN
    half = 0.5 * (ctx.t_start + ctx.t_end)
    best = _NAN
    for p in range(1, 5):
        errs = []
        for s in ("right", "left"):
            w = side == s
            ts = t[w]
            src = (ts >= half) & (ts + p * T <= ctx.t_end - 0.5 * T)
            e = wall(ts, a[w], src, p * T, T)
            if e is not None:
                errs.append(e)
        if not errs:
            continue
        e = float(np.percentile(np.concatenate(errs), 90))
        best = e if not (best <= e) else best
    return best


def merged_impacts(ctx: FeatureContext) -> np.ndarray:
    """Mask of the detections that are impacts as the labels count them (once per context).

    A detection on the same wall as the one before it and less than
    :data:`~vidiscover.regimes.labels.RETURN_TAU` periods after it is merged into it
    (:func:`~vidiscover.regimes.labels.same_wall_returns`, the labels' rule): a ball's
    first rebound off a wall it rests against, seen as a pulse 0.035-0.05 T after the
    impact at 0.1-0.3 of its dv, is chatter to the labels however high it bounced
    (diag19b: paper-rig 21001 #25, floor 31337 #133 and #351, 1ipc read as multi_ipc).
    """
    return ctx.memo("merged", _merged_of)


def _merged_of(ctx: FeatureContext) -> np.ndarray:
    keep = ~same_wall_returns(ctx.t, ctx.side, ctx.period)
    keep.flags.writeable = False
    return keep


def _merged_counts(ctx: FeatureContext) -> np.ndarray:
    """Merged impacts per complete cycle (once per context)."""
    return ctx.memo("merged_counts", lambda c: cycle_counts(
        np.asarray(c.t, float)[merged_impacts(c)], c.cycles()))


def _merged_ipc(ctx: FeatureContext) -> float:
    """Mean merged impacts (:func:`merged_impacts`) per complete cycle."""
    c = _merged_counts(ctx)
    return float(c.mean()) if c.size else _NAN


def _merged_phi(ctx: FeatureContext) -> float:
    """Share of complete cycles with at least one merged impact."""
    c = _merged_counts(ctx)
    return float((c >= 1).mean()) if c.size else _NAN


def _merged_share1(ctx: FeatureContext) -> float:
    """Share of complete cycles with exactly one merged impact."""
    c = _merged_counts(ctx)
    return float((c == 1).mean()) if c.size else _NAN


def _merged_share2(ctx: FeatureContext) -> float:
    """Share of complete cycles with exactly two merged impacts."""
    c = _merged_counts(ctx)
    return float((c == 2).mean()) if c.size else _NAN


def _merged_alternation(ctx: FeatureContext) -> float:
    """Share of consecutive merged impacts on opposite walls."""
    return alternation_share(ctx.side[merged_impacts(ctx)])


def _merged_asymmetry(ctx: FeatureContext) -> float:
    """``asymmetry`` of the merged impacts: |mean dt after right - after left| / T."""
    m = merged_impacts(ctx)
    return alternation_asymmetry(np.asarray(ctx.t, float)[m], ctx.side[m], ctx.period)


#: The cycle and side features of the impacts as the labels count them
#: (:func:`merged_impacts`), part of :data:`ALL_FEATURES`; the rule baseline reads them.
MERGED_FEATURES = FeatureSet({
    "merged_per_cycle": _merged_ipc,
    "merged_cycle_share": _merged_phi,
    "merged_one_share": _merged_share1,
    "merged_two_share": _merged_share2,
    "merged_alternation": _merged_alternation,
    "merged_asymmetry": _merged_asymmetry,
})


#: Features of the strong impacts (:data:`STRONG_SHARE`) and of the repetition of the
#: impact sequence, part of :data:`ALL_FEATURES`.
IMPACT_FEATURES = FeatureSet({
    "strong_per_cycle": _strong_ipc,
    "strong_one_share": _strong_share1,
    "strong_two_share": _strong_share2,
    "strong_alternation": _strong_alternation,
    "weak_share": _weak_share,
    "impact_period_error": _impact_period_error,
    "impact_dv_error": _impact_dv_error,
})


def _saturated_share(ctx: FeatureContext) -> float:
    """Share of complete cycles with the accelerometer on its rail.

    The saturated sample times are the context's ``saturated_t`` (the accelerometer on
    a rail for longer than a clipped pulse, known when the context was made with its
    recording); a context made without them (by hand) knows of no saturation and reads
    0, as every table computed before this feature existed is read by the rules.
    """
    c = _counts(ctx)
    if not c.size:
        return _NAN
    sat = ctx.saturated_t
    if sat is None:
        return 0.0
    return float((cycle_counts(sat, ctx.cycles()) > 0).mean())


#: The features this module defines.
REGIME_FEATURES = FeatureSet({
    "one_per_cycle_share": _share1,
    "multi_per_cycle_share": _share3,
    "count_std": _count_std,
    "modal_count_share": _modal,
    "quiet_run": _quiet_run,
    "phase_coherence": _phase,
    "dt_max": _dt_max,
    "dt_min": _dt_min,
    "side_run": _side_run,
    "returnmap_top_share": _top_share,
    "returnmap_cluster_density": _density,
    "dv_side_ratio": _dv_ratio,
    "waveform_period_error": _wave_err,
    "waveform_period": _wave_period,
    "strobe_dispersion": _strobe_disp,
    "envelope_cv": _env_cv,
    "saturated_cycle_share": _saturated_share,
})

#: ``strobe_state_error`` (the labels' periodicity test on x and x', which the rule
#: baseline reads too; ``strobe_period_error`` is x alone), a set of its own and part of
#: :data:`ALL_FEATURES`: other rigs' chaotic motions often repeat within 1 % in x
#: and not in x', and a model that reads x alone calls them ``multi_ipc`` (with the
#: end-of-record fix and ``--n-corpus-train 192``, other rigs' ``chaotic`` recall on
#: tuning seeds 555 / 100003: 0.875 -> 0.911 / 0.761 -> 0.913).
STATE_FEATURES = FeatureSet({"strobe_state_error": _strobe_state})

#: The analysis's own features, the regime features and the state's periodicity: the
#: set the classifier, sweeps and the ``analyze`` command compute
#: (``analyze(rec, features=ALL_FEATURES)``).
ALL_FEATURES = (ANALYSIS_FEATURES | REGIME_FEATURES | STATE_FEATURES | IMPACT_FEATURES
                | MERGED_FEATURES)
