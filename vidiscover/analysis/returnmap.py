"""Stage 4: first return map of impact time differences and per-recording features.

The first return map (paper Sec. 4, Fig. 5) plots consecutive impact time
differences ``(dt_i, dt_{i+1})`` with ``dt_i = t_{i+1} - t_i``: a periodic regime
is a few points (two asymmetric impacts per cycle: two points mirrored about the
diagonal), a quasi-periodic one a closed curve, an irregular one a cloud.

Features come in explicit sets (:class:`FeatureSet`, name -> function of a
:class:`FeatureContext`): the analysis's own is :data:`ANALYSIS_FEATURES`; a set is
passed to :func:`compute_features` and :func:`~vidiscover.analysis.analyze` as a value,
and extended with ``|``. Every feature returns a float; NaN means "undefined for this
record" (e.g. no impacts).

Examples
--------
>>> import numpy as np
>>> rm = return_map(np.arange(10) * 0.0625, np.array(["right", "left"] * 5), 0.125)
>>> rm.n_points, rm.n_clusters
(8, 1)
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .signals import Forcing

if TYPE_CHECKING:      # pandas is imported where a table is built, not to analyse
    import pandas as pd

__all__ = ["ReturnMap", "return_map", "FeatureContext", "FeatureSet", "ANALYSIS_FEATURES",
           "compute_features", "EDGE_MARGIN"]

#: Cycle starts closer than this (s) to either end of the reconstructed LO motion are
#: not used by the features that read x at or between cycle starts
#: (:meth:`FeatureContext.motion_cycles`): there the drift smoother of
#: :func:`~vidiscover.analysis.reconstruction.reconstruct` (``drift_window`` 0.1 s, as
#: :func:`~vidiscover.analysis.analyze` calls it) fits one-sided and x is off (realism
#: corpus test-051: by 0.39 of max |x| at the last sample, 0.26 at the first). Half
#: that window. :meth:`FeatureContext.amplitude` (max |x|) leaves those samples out too.
EDGE_MARGIN = 0.05


@dataclass(frozen=True, eq=False)
class ReturnMap:
    """First return map of impact time differences.

    Attributes
    ----------
    dt : ndarray
        Time differences ``dt_i = t_{i+1} - t_i`` (s), n - 1 values.
    x, y : ndarray
        Points ``(dt_i, dt_{i+1})`` (s), n - 2 values.
    side : ndarray of str
        Wall of the impact between the two intervals of each point.
    cluster : ndarray of int
        Cluster of each point (single linkage at ``radius * period``).
    centres : ndarray
        Cluster centres, shape (k, 2) (s).
    period : float
        Forcing period (s).
    radius : float
        Cluster radius as a fraction of the period.
    """

    dt: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    y: np.ndarray = field(repr=False)
    side: np.ndarray = field(repr=False)
    cluster: np.ndarray = field(repr=False)
    centres: np.ndarray = field(repr=False)
    period: float
    radius: float

    @property
    def n_points(self) -> int:
        """Number of return-map points."""
        return int(self.x.size)

    @property
    def n_clusters(self) -> int:
        """Number of clusters."""
        return int(self.centres.shape[0])

    def to_frame(self) -> pd.DataFrame:
        """Points as a DataFrame: ``dt_i``, ``dt_next``, ``side``, ``cluster``."""
        import pandas as pd

        return pd.DataFrame({"dt_i": self.x, "dt_next": self.y, "side": self.side,
                             "cluster": self.cluster})


def return_map(t: np.ndarray, side: np.ndarray, period: float, radius: float = 0.02
               ) -> ReturnMap:
    """Build the first return map of impact times ``t`` (sorted, s).

    Parameters
    ----------
    t : ndarray
        Impact times (s).
    side : ndarray of str
        Impact sides.
    period : float
        Forcing period (s), the scale of the clustering.
    radius : float
        Cluster radius as a fraction of the period.

    Returns
    -------
    ReturnMap
    """
    t = np.asarray(t, dtype=float)
    side = np.asarray(side)
    dt = np.diff(t) if t.size > 1 else np.zeros(0)
    x, y = dt[:-1], dt[1:]
    s = side[1:-1] if t.size > 2 else np.zeros(0, dtype=side.dtype if side.size else "<U5")
    cluster, centres = _linkage_clusters(np.column_stack([x, y]), radius * period)
    return ReturnMap(dt=dt, x=x, y=y, side=s, cluster=cluster, centres=centres,
                     period=float(period), radius=float(radius))


def _linkage_clusters(points: np.ndarray, radius: float):
    """Single-linkage clusters and their centres.

    Points closer than ``radius`` chain together; above 2000 points, cells of size
    ``radius`` instead.
    """
    n = points.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2))
    if n == 1:
        return np.zeros(1, dtype=np.int64), points.copy()
    if n <= 2000 and radius > 0:
        labels = _single_linkage_labels(points, radius) - 1
    else:
        cells = np.floor(points / max(radius, 1e-300)).astype(np.int64)
        labels = np.unique(cells, axis=0, return_inverse=True)[1].ravel()
    labels = labels.astype(np.int64)
    k = int(labels.max()) + 1
    counts = np.bincount(labels, minlength=k)
    centres = np.column_stack([np.bincount(labels, points[:, 0], k) / counts,
                               np.bincount(labels, points[:, 1], k) / counts])
    return labels, centres


def _single_linkage_labels(points: np.ndarray, radius: float) -> np.ndarray:
    """``fcluster(linkage(points, "single"), radius, "distance")`` without the checks.

    scipy's public functions validate the linkage matrix they made themselves (about
    half their time on a few hundred points); the same compiled steps are called
    directly when this scipy has them (same labels), else the public functions.
    """
    from scipy.spatial.distance import pdist

    n = points.shape[0]
    try:
        from scipy.cluster import _hierarchy

        single, cut = _hierarchy.mst_single_linkage, _hierarchy.cluster_dist
    except (ImportError, AttributeError):       # pragma: no cover - another scipy
        single = cut = None
    y = pdist(points)
    if single is None or n < 3 or not np.isfinite(y).all():
        from scipy.cluster.hierarchy import fcluster, linkage

        return fcluster(linkage(points, method="single"), radius, criterion="distance")
    labels = np.zeros(n, dtype="i")
    cut(np.ascontiguousarray(single(y, n), dtype=np.float64), labels, float(radius), int(n))
    return labels


def cycle_counts(t: np.ndarray, cycles: np.ndarray) -> np.ndarray:
    """Impacts at times ``t`` in each cycle ``[c_k, c_k+1)`` of the bounds ``cycles``.

    The last bin is closed (as ``np.histogram``); a read-only array, empty for fewer
    than two bounds.
    """
    if cycles.size < 2:
        return np.zeros(0, dtype=np.int64)
    t = np.sort(np.asarray(t, dtype=float))
    k = np.searchsorted(t, cycles, side="left")
    k[-1] = np.searchsorted(t, cycles[-1], side="right")
    out = np.diff(k)
    out.flags.writeable = False
    return out


@dataclass(frozen=True, eq=False)
class FeatureContext:
    """What the feature functions see.

    Attributes
    ----------
    t, side, dv : ndarray
        Impact times (s), sides ("right"/"left") and LO velocity jumps (m/s).
    t_start, t_end : float
        Span of the record (s).
    forcing : Forcing
        Fitted base excitation (cycle cuts at base phase 0).
    ts, x : ndarray
        Sample times (s) and LO displacement (m).
    returnmap : ReturnMap
    saturated_t : ndarray or None
        Times (s) of the samples where the accelerometer sits on its rail for longer than
        a clipped pulse (:func:`~vidiscover.analysis.impacts.saturated_samples`), where
        impacts can be neither seen nor timed; None when not known (a context made by
        hand), read as no saturation.
    """

    t: np.ndarray = field(repr=False)
    side: np.ndarray = field(repr=False)
    dv: np.ndarray = field(repr=False)
    t_start: float
    t_end: float
    forcing: Forcing
    ts: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    returnmap: ReturnMap
    saturated_t: np.ndarray | None = field(default=None, repr=False)

    @classmethod
    def of(cls, detection, forcing: Forcing, reconstruction, returnmap: ReturnMap,
           recording=None) -> FeatureContext:
        """The context of an analysis's parts.

        The one construction used by :func:`~vidiscover.analysis.analyze` and by
        :func:`vidiscover.regimes.dataset.feature_context` (features of another set on
        an analysis already made), so that both see the same record span:
        ``detection.t0`` to ``t0 + n_samples / sample_rate``.

        Parameters
        ----------
        detection : Detection
            The impacts (``t``, ``side``, ``dv``) and the record's span.
        forcing : Forcing
        reconstruction : Reconstruction
            Its sample times ``t`` and LO displacement ``x_impacts``.
        returnmap : ReturnMap
        recording : Recording, optional
            The recording analysed: gives :attr:`saturated_t` (None without it).
        """
        t0 = float(detection.t0)
        sat = None
        if recording is not None:
            mask = detection.saturated               # the detector's, when it gave it
            if mask is None:
                from .impacts import saturated_samples

                mask = saturated_samples(np.asarray(recording.a, dtype=float), detection.bad)
            sat = np.asarray(recording.t, dtype=float)[mask]
        return cls(t=detection.t, side=detection.side, dv=detection.dv, t_start=t0,
                   t_end=t0 + detection.n_samples / detection.sample_rate, forcing=forcing,
                   ts=reconstruction.t, x=reconstruction.x_impacts, returnmap=returnmap,
                   saturated_t=sat)

    @property
    def period(self) -> float:
        """Forcing period (s)."""
        return self.forcing.period

    def cycles(self) -> np.ndarray:
        """Start times of the complete cycles plus the end of the last one."""
        return self._cycles

    def counts(self) -> np.ndarray:
        """Impacts per complete cycle."""
        return self._counts

    def motion_cycles(self) -> np.ndarray:
        """The cycle starts at least :data:`EDGE_MARGIN` inside the finite LO motion.

        What the features that read x at or between cycle starts use: consecutive
        starts of :meth:`cycles`, so they bound complete cycles, none of them reaching
        into the reconstruction's ends (empty without a finite sample).
        """
        return self._motion_cycles

    def finite_motion(self) -> tuple[np.ndarray, np.ndarray]:
        """(ts, x) at the samples where x is finite.

        ``ts`` and ``x`` themselves (no copy of a long record) when every sample is.
        """
        return self._finite_motion

    @functools.cached_property
    def _finite_motion(self) -> tuple[np.ndarray, np.ndarray]:
        ok = np.isfinite(self.x)
        if ok.all():
            return self.ts, self.x
        return self.ts[ok], self.x[ok]

    def memo(self, key, func: Callable[[FeatureContext], object]):
        """``func(self)``, computed once per context under ``key``.

        For work several features share (the regime features' cycle waveforms); keep
        what it returns unmodified.
        """
        cache = self._memo
        if key not in cache:
            cache[key] = func(self)
        return cache[key]

    @functools.cached_property
    def _memo(self) -> dict:
        return {}

    def amplitude(self) -> float:
        """The largest |x| over the finite samples (NaN without any).

        Over those at least :data:`EDGE_MARGIN` inside the record's ends, where x is
        off (all of them when none is).
        """
        return self._amplitude

    @functools.cached_property
    def _amplitude(self) -> float:
        ts, xf = self.finite_motion()
        if not xf.size:
            return _NAN
        lo = np.searchsorted(ts, ts[0] + EDGE_MARGIN, side="left")
        hi = np.searchsorted(ts, ts[-1] - EDGE_MARGIN, side="right")
        x = xf[lo:hi] if hi > lo else xf
        return max(float(x.max()), -float(x.min()))

    @functools.cached_property
    def _cycles(self) -> np.ndarray:
        c = self.forcing.cycle_starts(self.t_start, self.t_end)
        c.flags.writeable = False
        return c

    @functools.cached_property
    def _motion_cycles(self) -> np.ndarray:
        c = self._cycles
        ts, _ = self.finite_motion()
        out = (c[(c >= ts[0] + EDGE_MARGIN) & (c <= ts[-1] - EDGE_MARGIN)] if ts.size
               else c[:0].copy())
        out.flags.writeable = False
        return out

    @functools.cached_property
    def _counts(self) -> np.ndarray:
        return cycle_counts(self.t, self._cycles)


class FeatureSet(Mapping):
    """An explicit, ordered, immutable set of named features.

    Maps a feature's name to its function of a :class:`FeatureContext` (returning a
    float, NaN when undefined). A set is passed to :func:`compute_features` and
    :func:`~vidiscover.analysis.analyze` as a value; nothing is registered globally,
    so what a process computes never depends on which modules it imported.

    Sets combine with ``|`` (a name may appear in both only with the same function)
    and :meth:`select` keeps some of the names.

    Examples
    --------
    >>> extra = FeatureSet({"first_impact": lambda ctx: float(ctx.t[0])})
    >>> mine = ANALYSIS_FEATURES | extra
    >>> list(mine)[-1], len(mine) == len(ANALYSIS_FEATURES) + 1
    ('first_impact', True)
    """

    __slots__ = ("_funcs",)

    def __init__(self, features: Mapping[str, Callable[[FeatureContext], float]]
                 | Iterable[tuple[str, Callable[[FeatureContext], float]]] = ()):
        funcs = dict(features)
        for name, func in funcs.items():
            if not isinstance(name, str) or not name:
                raise TypeError(f"feature names are non-empty strings, got {name!r}")
            if not callable(func):
                raise TypeError(f"feature {name!r} is not callable: {func!r}")
        self._funcs = funcs

    def __getitem__(self, name: str) -> Callable[[FeatureContext], float]:
        return self._funcs[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._funcs)

    def __len__(self) -> int:
        return len(self._funcs)

    def __repr__(self) -> str:
        return f"FeatureSet({', '.join(self._funcs)})"

    def __or__(self, other: Mapping) -> FeatureSet:
        other = other if isinstance(other, FeatureSet) else FeatureSet(other)
        clash = [n for n in other if n in self and other[n] is not self[n]]
        if clash:
            raise ValueError(f"features {clash} are defined differently in the two sets; "
                             "rename one of them")
        return FeatureSet({**self._funcs, **other._funcs})

    def select(self, names: Iterable[str]) -> FeatureSet:
        """The features ``names`` of this set, in the order given."""
        names = list(names)
        missing = [n for n in names if n not in self._funcs]
        if missing:
            raise KeyError(f"features {missing} are not in this set; it has: "
                           f"{', '.join(self._funcs)}")
        return FeatureSet({n: self._funcs[n] for n in names})


def compute_features(ctx: FeatureContext, features: Mapping | None = None
                     ) -> dict[str, float]:
    """Evaluate a feature set on ``ctx`` (default :data:`ANALYSIS_FEATURES`).

    Returns
    -------
    dict
        Name -> float, in the set's order.
    """
    features = ANALYSIS_FEATURES if features is None else features
    if not isinstance(features, Mapping):
        raise TypeError("features is a FeatureSet (name -> function), e.g. "
                        "ANALYSIS_FEATURES.select([...]); got "
                        f"{type(features).__name__}")
    return {n: float(f(ctx)) for n, f in features.items()}


_NAN = float("nan")


def _n_impacts(ctx: FeatureContext) -> float:
    """Number of detected impacts."""
    return float(ctx.t.size)


def _ipc(ctx: FeatureContext) -> float:
    """Mean impacts per complete forcing cycle."""
    c = ctx.counts()
    return float(c.mean()) if c.size else _NAN


def _phi(ctx: FeatureContext) -> float:
    """Share of complete cycles with at least one impact."""
    c = ctx.counts()
    return float((c >= 1).mean()) if c.size else _NAN


def _share2(ctx: FeatureContext) -> float:
    """Share of complete cycles with exactly two impacts."""
    c = ctx.counts()
    return float((c == 2).mean()) if c.size else _NAN


def alternation_share(side: np.ndarray) -> float:
    """Share of consecutive impacts on opposite walls (paper eq. 5); NaN below two."""
    if side.size < 2:
        return _NAN
    return float((side[1:] != side[:-1]).mean())


def alternation_asymmetry(t: np.ndarray, side: np.ndarray, period: float) -> float:
    """|mean dt after a right impact - mean dt after a left impact| / T (alternating pairs).

    ``t`` impact times (s), ``side`` their walls ("right"/"left"), ``period`` T (s); NaN
    below three impacts or without a pair of each kind.
    """
    if t.size < 3:
        return _NAN
    dt = np.diff(t)
    alt = side[1:] != side[:-1]
    ar = dt[alt & (side[:-1] == "right")]
    al = dt[alt & (side[:-1] == "left")]
    if not (ar.size and al.size):
        return _NAN
    return float(abs(ar.mean() - al.mean()) / period)


def _alternation(ctx: FeatureContext) -> float:
    """Share of consecutive impacts on opposite walls (paper eq. 5)."""
    return alternation_share(ctx.side)


def _chatter(ctx: FeatureContext) -> float:
    """Share of impacts on the same wall as the previous one."""
    if ctx.t.size < 2:
        return _NAN
    return float((ctx.side[1:] == ctx.side[:-1]).sum() / ctx.t.size)


def _right_share(ctx: FeatureContext) -> float:
    """Share of impacts on the right wall."""
    return float((ctx.side == "right").mean()) if ctx.t.size else _NAN


def _asym(ctx: FeatureContext) -> float:
    """|mean dt after a right impact - mean dt after a left impact| / T (alternating pairs)."""
    return alternation_asymmetry(ctx.t, ctx.side, ctx.period)


def _dt_cv(ctx: FeatureContext) -> float:
    """Coefficient of variation of the impact time differences."""
    dt = ctx.returnmap.dt
    return float(dt.std() / dt.mean()) if dt.size >= 2 and dt.mean() > 0 else _NAN


def _clusters(ctx: FeatureContext) -> float:
    """Clusters of the return map holding at least 5 % of its points."""
    rm = ctx.returnmap
    if rm.n_points == 0:
        return 0.0
    counts = np.bincount(rm.cluster)
    return float((counts >= max(1, 0.05 * rm.n_points)).sum())


def _spread(ctx: FeatureContext) -> float:
    """RMS distance of return-map points to their cluster centre, in periods."""
    rm = ctx.returnmap
    if rm.n_points == 0:
        return _NAN
    c = rm.centres[rm.cluster]
    d = np.hypot(rm.x - c[:, 0], rm.y - c[:, 1])
    return float(np.sqrt(np.mean(d ** 2)) / rm.period)


def _diag(ctx: FeatureContext) -> float:
    """Mean distance of return-map points to the diagonal, in periods."""
    rm = ctx.returnmap
    if rm.n_points == 0:
        return _NAN
    return float(np.mean(np.abs(rm.y - rm.x)) / math.sqrt(2) / rm.period)


def _dv_cv(ctx: FeatureContext) -> float:
    """Coefficient of variation of the impact strengths |dv|."""
    a = np.abs(ctx.dv)
    return float(a.std() / a.mean()) if a.size >= 2 and a.mean() > 0 else _NAN


def _cycle_amplitudes(ctx: FeatureContext) -> np.ndarray:
    """Half peak-to-peak of the finite LO displacement in each complete cycle.

    Over the cycles of :meth:`FeatureContext.motion_cycles` (away from the
    reconstruction's ends).
    """
    c = ctx.motion_cycles()
    if c.size < 2 or ctx.x.size == 0:
        return np.zeros(0)
    all_finite = ctx.finite_motion()[1] is ctx.x
    idx = np.searchsorted(ctx.ts, c)
    lo, hi = idx[:-1], idx[1:]
    keep = hi > lo
    if not all_finite:
        ok = np.isfinite(ctx.x)
        cnt = np.concatenate([[0], np.cumsum(ok)])
        keep &= cnt[hi] > cnt[lo]                   # cycles with a finite sample
    if not keep.any():
        return np.zeros(0)
    lo = lo[keep]
    end = int(hi[keep][-1])
    # each segment runs to the next kept start; cycles skipped in between hold no
    # finite sample, and non-finite samples are neutral (-inf / +inf; no copy of a long
    # record when every sample is finite)
    x = ctx.x
    xmax = np.maximum.reduceat((x if all_finite else np.where(ok, x, -np.inf))[:end], lo)
    xmin = np.minimum.reduceat((x if all_finite else np.where(ok, x, np.inf))[:end], lo)
    return 0.5 * (xmax - xmin)


def _modulation(ctx: FeatureContext) -> float:
    """(P95 - P5) / (P95 + P5) of the per-cycle LO half peak-to-peak (label index M)."""
    amp = _cycle_amplitudes(ctx)
    if amp.size == 0:
        return _NAN
    p5, p95 = np.percentile(amp, [5, 95])
    return float((p95 - p5) / (p95 + p5)) if p95 + p5 > 0 else _NAN


def _strobe(ctx: FeatureContext) -> float:
    """Periodicity error of the stroboscopic LO displacement (~0 when periodic).

    Min over p <= 4 of the largest change over p cycles (last half of the record),
    relative to max |x|, at the cycle starts of :meth:`FeatureContext.motion_cycles`
    (none within :data:`EDGE_MARGIN` of the reconstruction's ends, where x is off).
    """
    c = ctx.motion_cycles()
    ts, xf = ctx.finite_motion()
    if c.size < 6 or xf.size == 0:
        return _NAN
    xs = np.interp(c, ts, xf)
    xs = xs[xs.size // 2:]
    amp = ctx.amplitude()
    best = _NAN
    for p in range(1, 5):
        if xs.size <= p:
            break
        e = float(np.abs(xs[p:] - xs[:-p]).max() / amp) if amp > 0 else _NAN
        best = e if not (best <= e) else best
    return best


#: The features the analysis itself defines: what :func:`vidiscover.analysis.analyze`
#: computes unless given another set (the regime classifier's set is
#: ``vidiscover.regimes.features.ALL_FEATURES``, which includes these).
ANALYSIS_FEATURES = FeatureSet({
    "n_impacts": _n_impacts,
    "impacts_per_cycle": _ipc,
    "impacting_cycle_share": _phi,
    "two_per_cycle_share": _share2,
    "alternation": _alternation,
    "chatter_share": _chatter,
    "right_share": _right_share,
    "asymmetry": _asym,
    "dt_cv": _dt_cv,
    "returnmap_clusters": _clusters,
    "returnmap_spread": _spread,
    "diagonal_distance": _diag,
    "dv_cv": _dv_cv,
    "envelope_modulation": _modulation,
    "strobe_period_error": _strobe,
})
