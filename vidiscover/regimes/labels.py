"""Ground-truth regime labels from a simulated state (the README's 'Regime labels', a contract).

The label contract defines the labels from "impacts" and does not say what chatter
is; this module says which impacts count (:func:`chatter_mask`). An impact is chatter
of the impact before it on the same wall (no impact on the other wall between) when

- the ball got less than :data:`CHATTER_SHARE` (0.1 %) of the clearance 2b away from
  the wall since that impact (a ball resting against the wall, bouncing microns before
  it sticks), or
- it comes back to that wall less than :data:`RETURN_TAU` (0.06) forcing periods after
  it (:func:`same_wall_returns`): the height (4-40 um) is below what a recording
  resolves, a time is not, and the regime features merge detections by the same rule.

Every other impact counts. With T = 1/f and cycles cut at base phase 0
(simulation times k T), n_k (counted) impacts in cycle k, ipc = mean n_k, phi =
share of cycles with n_k >= 1, A_k = half the peak-to-peak LO displacement in cycle k,
M = (P95(A) - P5(A)) / (P95(A) + P5(A)) and
asym = |mean(dt after a right impact) - mean(dt after a left impact)| / T over
alternating pairs:

- ``no_impact``: ipc < 0.05
- ``smr``: phi < 0.9 and M >= 0.15
- ``1ipc``: phi >= 0.9, periodic, n_k = 1 in >= 90 % of cycles
- ``2ipc_sym``: phi >= 0.9, periodic, n_k = 2 in >= 90 % of cycles, sides alternate,
  asym < 0.1
- ``2ipc_asym``: as ``2ipc_sym`` but asym >= 0.1
- ``multi_ipc``: phi >= 0.9, periodic, anything else; or periodic with phi < 0.9 (and
  not ``smr``) when the impacts themselves repeat (:func:`impacts_repeat`)
- ``chaotic``: everything else

"Periodic": over the last half of the record, the stroboscopic LO state (x, x') at
cycle starts repeats with some period p <= 4 cycles, each component to within 1 %
of that component's amplitude (max |x|, max |x'| over the record).

The README's ``chaotic`` is "impacts, but neither periodic nor SMR". A periodic
motion that impacts in only some of its cycles (a period-3 orbit hitting in two of
every three, phi ~ 2/3, M < 0.15) met no other rule and fell into ``chaotic``; it is
``multi_ipc`` when its impacts repeat after q <= 4 cycles. When they do not (a ball
grazing the wall at irregular cycles of an LO whose state repeats: at mass ratios
of a few % the LO barely feels the ball), the motion is not periodic and stays
``chaotic``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["LABELS", "RegimeTruth", "label_simulation", "label_from_events", "chatter_mask",
           "CHATTER_SHARE", "RETURN_TAU", "same_wall_returns", "impacts_repeat"]

#: Regime labels, a contract (the README's 'Regime labels'), from simple to complex.
LABELS: tuple[str, ...] = ("no_impact", "1ipc", "2ipc_sym", "2ipc_asym", "multi_ipc",
                           "smr", "chaotic")


#: A bounce that takes the ball less than this share of the clearance 2b off the wall
#: it hit is chatter of that impact, not an impact of its own (:func:`chatter_mask`).
CHATTER_SHARE = 1e-3

#: A return to the same wall less than this many forcing periods after the impact
#: before it is chatter of that impact (:func:`same_wall_returns`), however far the
#: ball got. :data:`CHATTER_SHARE` alone is a height of 4-40 um on the rigs drawn,
#: below what any recording resolves: a tilted rig's first rebound reaching 6e-4 of
#: 2b was chatter and one reaching 1.5e-3 an impact, both detected alike as a
#: same-wall pulse 0.035-0.05 T after the impact at 0.1-0.3 of its dv, so the
#: regime features (:mod:`vidiscover.regimes.features`, which merge such returns
#: with the same rule) could not tell a 1ipc from a multi_ipc. A time is what a
#: recording resolves. 0.06 relabels 2 of 458 rows of a paper-rig set (multi_ipc ->
#: 1ipc and -> 2ipc_asym) and none of 369 floor-noise and 381 other-rig rows (seed
#: 21001 and 31337 sets, diag19b); 0.08 relabels 6 other-rig multi_ipc and >= 0.1
#: 8-15 rows per set.
RETURN_TAU = 0.06


def same_wall_returns(t, side, period: float, tau: float | None = None) -> np.ndarray:
    """Impacts that return to the wall of the impact before them within ``tau`` periods.

    Impact k is one when impact k - 1 is on the same wall and
    ``t[k] - t[k-1] < tau * period``; a run of such returns is one impact, its first
    (the rule chains, as :func:`chatter_mask`'s height does). The one rule of both the
    labels and the regime features.

    Parameters
    ----------
    t : array_like
        Impact times (s), sorted.
    side : array_like
        Their walls (any two values: +-1, "right"/"left").
    period : float
        Forcing period T (s).
    tau : float, optional
        In periods (default :data:`RETURN_TAU`); 0 marks none.

    Returns
    -------
    ndarray of bool
        True where an impact is a return to be merged with the one before it.

    Examples
    --------
    >>> same_wall_returns([0.0, 0.03, 0.05, 0.5, 0.52], [1, 1, 1, -1, 1], 1.0)
    array([False,  True,  True, False, False])
    """
    tau = RETURN_TAU if tau is None else tau
    t = np.asarray(t, dtype=float)
    side = np.asarray(side)
    out = np.zeros(t.size, dtype=bool)
    if t.size < 2 or not tau > 0:
        return out
    out[1:] = (side[1:] == side[:-1]) & (np.diff(t) < tau * period)
    return out


@dataclass(frozen=True)
class RegimeTruth:
    """A label with the quantities that decided it.

    Attributes
    ----------
    label : str
        One of :data:`LABELS`.
    ipc, phi, M, asym : float
        Impacts per cycle, share of impacting cycles, modulation index, asymmetry.
    periodic : bool
        Stroboscopic state repeats with a period <= 4 cycles.
    period : int or None
        The smallest such period.
    share_n1, share_n2 : float
        Share of cycles with exactly one / two impacts.
    alternate : float
        Share of consecutive impact pairs on opposite walls.
    n_cycles : int
        Number of complete cycles in the record.
    """

    label: str
    ipc: float
    phi: float
    M: float
    asym: float
    periodic: bool
    period: int | None
    share_n1: float
    share_n2: float
    alternate: float
    n_cycles: int

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return asdict(self)


def _is_periodic(strobe_x: np.ndarray, strobe_v: np.ndarray, amp_x: float, amp_v: float,
                 max_period: int = 4, tol: float = 0.01) -> int | None:
    n = strobe_x.size
    half = strobe_x[n // 2:], strobe_v[n // 2:]
    for p in range(1, max_period + 1):
        if half[0].size <= p:
            break
        dx = np.abs(half[0][p:] - half[0][:-p]).max()
        dv = np.abs(half[1][p:] - half[1][:-p]).max()
        if dx <= tol * amp_x and dv <= tol * amp_v:
            return p
    return None


def impacts_repeat(t_imp: np.ndarray, cycle_starts: np.ndarray, period: float,
                   max_period: int = 4, tol: float = 0.01) -> int | None:
    """Smallest q <= ``max_period`` after which the impacts repeat, or None.

    Over the last half of the cycles: the impact counts per cycle repeat after q
    cycles, and every impact with q periods after it inside those cycles has an
    impact within ``tol`` of the period of that time.

    Parameters
    ----------
    t_imp : ndarray
        Impact times (s), sorted.
    cycle_starts : ndarray
        Start times of the complete cycles, plus the end of the last.
    period : float
        Forcing period T (s).

    Examples
    --------
    >>> import numpy as np
    >>> starts = np.arange(41.0)
    >>> t = np.array([k + 0.3 for k in range(40) if k % 3])     # cycles 1, 2, 4, 5, ...
    >>> jitter = np.random.default_rng(0).uniform(-0.05, 0.05, t.size)  # irregular times
    >>> impacts_repeat(t, starts, 1.0), impacts_repeat(t + jitter, starts, 1.0)
    (3, None)
    """
    n = cycle_starts.size - 1
    if n < 2 or not period > 0:
        return None
    counts = np.histogram(t_imp, bins=cycle_starts)[0][n // 2:]
    half, end = cycle_starts[n // 2], cycle_starts[-1]
    late = t_imp[(t_imp >= half) & (t_imp < end)]
    for q in range(1, max_period + 1):
        if counts.size <= q or not np.array_equal(counts[q:], counts[:-q]):
            continue
        src = late[late + q * period < end]
        if src.size:
            want = src + q * period
            j = np.clip(np.searchsorted(late, want), 1, max(late.size - 1, 1))
            d = np.minimum(np.abs(late[j] - want), np.abs(late[j - 1] - want))
            if d.max() > tol * period:
                continue
        return q
    return None


def chatter_mask(result, imp, share: float | None = None, points: int = 32,
                 tau: float | None = None) -> np.ndarray:
    """Impacts that are part of the previous impact's chatter on the same wall.

    Between two consecutive impacts on the same wall the ball's largest distance from
    that wall (its relative position z = y - x against the wall at +-b, evaluated at
    ``points`` instants of the flight) below ``share`` of the clearance 2b
    (:data:`CHATTER_SHARE`) makes the second a bounce of a ball resting against the
    wall (a chatter sequence towards sticking), not an impact of its own; so does a
    return less than ``tau`` forcing periods after the first (:data:`RETURN_TAU`,
    :func:`same_wall_returns`), however far the ball got.

    Parameters
    ----------
    result : SimulationResult
        The simulation.
    imp : ImpactTable
        Its impacts (those of the record), sorted by time.
    share : float, optional
        Height criterion (default :data:`CHATTER_SHARE`); 0 turns it off.
    points : int
        Instants of each flight at which the height is evaluated.
    tau : float, optional
        Time criterion in periods (default :data:`RETURN_TAU`); 0 turns it off.

    Returns
    -------
    ndarray of bool
        True where an impact continues the previous one.
    """
    share = CHATTER_SHARE if share is None else share
    out = same_wall_returns(imp.t, imp.side, result.params.period, tau)
    b = float(result.params.b)
    if imp.n < 2 or not share > 0:
        return out
    side = np.asarray(imp.side)
    pairs = np.flatnonzero(side[1:] == side[:-1])
    if not pairs.size:
        return out
    a = np.asarray(imp.t_out, float)[pairs]
    e = np.asarray(imp.t, float)[pairs + 1]
    frac = (np.arange(1, points + 1) / (points + 1))[None, :]
    grid = (a[:, None] + (e - a)[:, None] * frac).ravel()
    order = np.argsort(grid, kind="stable")
    z = np.empty(grid.size)
    z[order] = np.asarray(result.evaluate(grid[order])["z"], float)
    gap = b - side[pairs][:, None] * z.reshape(a.size, points)   # distance from the wall
    out[pairs + 1] |= gap.max(axis=1) < share * 2 * b
    return out


def label_from_events(t_imp: np.ndarray, side_imp: np.ndarray, cycle_starts: np.ndarray,
                      amp_cycle: np.ndarray, strobe_x: np.ndarray, strobe_v: np.ndarray,
                      amp_x: float, amp_v: float, period: float) -> RegimeTruth:
    """Apply the label rules to impact events and per-cycle LO quantities.

    Parameters
    ----------
    t_imp, side_imp : ndarray
        Impact times (s) and sides (+1 right, -1 left), sorted by time.
    cycle_starts : ndarray
        Start times of the complete cycles (base phase 0), plus the end of the last.
    amp_cycle : ndarray
        Half peak-to-peak LO displacement per cycle.
    strobe_x, strobe_v : ndarray
        LO displacement and velocity at the cycle starts.
    amp_x, amp_v : float
        max |x| and max |x'| over the record.
    period : float
        Forcing period T (s).
    """
    n_cycles = cycle_starts.size - 1
    counts = np.histogram(t_imp, bins=cycle_starts)[0] if n_cycles > 0 else np.zeros(0)
    ipc = float(counts.mean()) if n_cycles else 0.0
    phi = float((counts >= 1).mean()) if n_cycles else 0.0
    if amp_cycle.size:
        p5, p95 = np.percentile(amp_cycle, [5, 95])
        M = float((p95 - p5) / (p95 + p5)) if (p95 + p5) > 0 else 0.0
    else:
        M = 0.0
    dt = np.diff(t_imp)
    alt = side_imp[1:] != side_imp[:-1]
    alternate = float(alt.mean()) if alt.size else 0.0
    after_right = dt[alt & (side_imp[:-1] > 0)]
    after_left = dt[alt & (side_imp[:-1] < 0)]
    if after_right.size and after_left.size:
        asym = float(abs(after_right.mean() - after_left.mean()) / period)
    else:
        asym = 0.0
    per = _is_periodic(strobe_x, strobe_v, amp_x, amp_v) if strobe_x.size >= 4 else None
    share1 = float((counts == 1).mean()) if n_cycles else 0.0
    share2 = float((counts == 2).mean()) if n_cycles else 0.0
    if ipc < 0.05:
        label = "no_impact"
    elif phi < 0.9 and M >= 0.15:
        label = "smr"
    elif per is not None and (phi >= 0.9
                              or impacts_repeat(t_imp, cycle_starts, period) is not None):
        if share1 >= 0.9:
            label = "1ipc"
        elif share2 >= 0.9 and alternate >= 0.9:
            label = "2ipc_sym" if asym < 0.1 else "2ipc_asym"
        else:
            label = "multi_ipc"
    else:
        label = "chaotic"
    return RegimeTruth(label, ipc, phi, M, asym, per is not None, per, share1, share2,
                       alternate, int(n_cycles))


def label_simulation(result, sample_rate: float = 6400.0) -> RegimeTruth:
    """Ground-truth label of the record window of a :class:`SimulationResult`.

    Parameters
    ----------
    result : SimulationResult
        The simulation (its record is [settle, settle + duration]).
    sample_rate : float
        Rate at which the true LO motion is sampled for amplitudes.

    Returns
    -------
    RegimeTruth
    """
    T = result.params.period
    t0, t1 = result.settle, result.settle + result.duration
    k0, k1 = int(np.ceil(t0 / T - 1e-9)), int(np.floor(t1 / T + 1e-9))
    starts = np.arange(k0, k1 + 1) * T
    imp = result.record_impacts()
    ts = np.arange(int(round(result.duration * sample_rate))) / sample_rate + t0
    st = result.evaluate(ts)
    x, v = st["x"], st["xd"]
    # half peak-to-peak per cycle [start_k, start_k+1) (ts is sorted), empty cycles skipped
    edges = np.searchsorted(ts, starts, side="left")
    lo, hi = edges[:-1], edges[1:]
    lo = lo[hi > lo]                  # the kept cycles tile [edges[0], edges[-1])
    xc = x[:edges[-1]] if edges.size else x
    amp = (0.5 * (np.maximum.reduceat(xc, lo) - np.minimum.reduceat(xc, lo)) if lo.size
           else np.zeros(0))
    strobe = result.evaluate(starts[:-1]) if starts.size > 1 else {"x": np.zeros(0),
                                                                   "xd": np.zeros(0)}
    keep = ~chatter_mask(result, imp)
    return label_from_events(imp.t[keep], imp.side[keep], starts, np.asarray(amp), strobe["x"],
                             strobe["xd"], float(np.abs(x).max()), float(np.abs(v).max()), T)
