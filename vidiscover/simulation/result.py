"""The result of a simulation: a piecewise closed-form trajectory plus its events."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..effects import Effects
from ..params import SystemParams

if TYPE_CHECKING:  # pragma: no cover
    from .engine import _Model

__all__ = ["SimulationResult", "ImpactTable"]

SIDE_NAMES = {1: "right", -1: "left"}


@dataclass(frozen=True)
class ImpactTable:
    """True impacts (arrays of equal length, simulation time).

    Attributes
    ----------
    t : ndarray
        Impact times (s, simulation clock: the record starts at ``settle``).
    side : ndarray of int
        +1 right wall (z = +b), -1 left wall (z = -b).
    u_minus, u_plus : ndarray
        Relative velocity z' before / after (m/s); ``u_plus = -r u_minus`` unless
        the ball stuck to the wall (``stuck``), when ``u_plus = 0``.
    r : ndarray
        Restitution coefficient given by the wall's law at this impact.
    v_minus, v_plus : ndarray
        LO velocity before / after (m/s).
    w_minus, w_plus : ndarray
        Ball velocity before / after (m/s).
    x : ndarray
        LO displacement at the impact (m).
    stuck : ndarray of bool
        The rebound was slower than ``stick_speed``: the ball stuck to the wall.
    t_out : ndarray
        End of the contact (s): equal to ``t`` for instantaneous impacts; for the
        compliant engine ``t`` is the start of the contact episode (``t_in``) and
        ``t_out`` its end, and ``u_minus``/``u_plus`` are the relative velocities
        at entry/exit (``v_in``/``v_out``).
    """

    t: np.ndarray
    side: np.ndarray
    u_minus: np.ndarray
    u_plus: np.ndarray
    r: np.ndarray
    v_minus: np.ndarray
    v_plus: np.ndarray
    w_minus: np.ndarray
    w_plus: np.ndarray
    x: np.ndarray
    stuck: np.ndarray
    t_out: np.ndarray

    @classmethod
    def from_rows(cls, rows: list[tuple]) -> ImpactTable:
        """Build from the loop's tuples (without ``t_out``, instantaneous: ``t_out = t``)."""
        names = [f for f in cls.__dataclass_fields__]
        if rows and len(rows[0]) == len(names) - 1:
            rows = [(*row, row[0]) for row in rows]
        if not rows:
            cols = {n: np.zeros(0) for n in names}
            cols["side"] = np.zeros(0, dtype=np.int8)
            cols["stuck"] = np.zeros(0, dtype=bool)
            return cls(**cols)
        arr = list(zip(*rows))
        cols = {n: np.asarray(a, dtype=float) for n, a in zip(names, arr)}
        cols["side"] = cols["side"].astype(np.int8)
        cols["stuck"] = cols["stuck"].astype(bool)
        return cls(**cols)

    @property
    def n(self) -> int:
        """Number of impacts."""
        return int(self.t.size)

    @property
    def speed(self) -> np.ndarray:
        """Impact speed |z'-| (m/s)."""
        return np.abs(self.u_minus)

    def select(self, mask: np.ndarray) -> ImpactTable:
        """Rows where ``mask`` is true."""
        return ImpactTable(**{k: getattr(self, k)[mask] for k in self.__dataclass_fields__})

    def to_records(self, t_offset: float = 0.0) -> list[dict]:
        """JSON-ready list of dicts with sides as strings and times shifted by ``-t_offset``.

        Besides the fields, ``t_in`` (= ``t``), ``t_out``, ``v_in`` (= ``u_minus``) and
        ``v_out`` (= ``u_plus``) describe the contact episode (the README's 'Realistic recordings').
        """
        out = []
        for i in range(self.n):
            out.append({
                "t": float(self.t[i] - t_offset), "t_in": float(self.t[i] - t_offset),
                "t_out": float(self.t_out[i] - t_offset),
                "v_in": float(self.u_minus[i]), "v_out": float(self.u_plus[i]),
                "side": SIDE_NAMES[int(self.side[i])],
                "u_minus": float(self.u_minus[i]), "u_plus": float(self.u_plus[i]),
                "r": float(self.r[i]), "v_minus": float(self.v_minus[i]),
                "v_plus": float(self.v_plus[i]), "w_minus": float(self.w_minus[i]),
                "w_plus": float(self.w_plus[i]), "x": float(self.x[i]),
                "stuck": bool(self.stuck[i])})
        return out


#: Grids of at least this many instants are evaluated segment by segment when sorted
#: (:func:`_segment_runs`); smaller ones by the general path.
_MIN_RUNS = 64


def _segment_runs(t0s: np.ndarray, t: np.ndarray):
    """The segments of a sorted grid ``t`` as runs: ``(j0, j1, counts)`` or None.

    ``counts[k]`` instants of ``t``, after each other, lie in segment ``j0 + k``,
    exactly the segments ``clip(searchsorted(t0s, t, "right") - 1, 0, n - 1)`` gives
    (segment starts ``t0s`` sorted): one search per segment start instead of one per
    instant. None when ``t`` is short, not 1-D or not sorted (NaN included).
    """
    n = t.size
    if t.ndim != 1 or n < _MIN_RUNS or t0s.size == 0 or not (t[1:] >= t[:-1]).all() \
            or not (t0s[1:] >= t0s[:-1]).all():
        return None
    # instant i lies in the segment of the last start <= t[i]; instants before the
    # first start lie in the first segment
    bounds = np.searchsorted(t, t0s, side="left")
    bounds[0] = 0
    counts = np.diff(np.append(bounds, n))
    nz = np.flatnonzero(counts)
    j0, j1 = int(nz[0]), int(nz[-1]) + 1
    return j0, j1, counts[j0:j1]


def _flow_runs(osc, t, trig, t0, C1, C2, F0, counts):
    """``osc.state_array(t, t0, C1, C2, F0, trig)`` with per-segment constants.

    The segment values (``t0``, ``C1``, ``C2``, ``F0``, one per segment) hold for
    ``counts`` consecutive instants each. Same operations in the same order as
    :meth:`~.flows.Oscillator.state_array` and ``particular_array`` (the states are
    identical to the bit: a test compares them), with the expressions of segment
    constants computed once per segment and fewer temporaries.

    Returns
    -------
    x, xd, xdd, tau : ndarray
        The state and the time since the segment's start.
    """
    def rep(v):
        return np.repeat(v, counts)

    sg, wd = osc.sigma, osc.wd
    # particular part: F0 / k + sum_j (pa s + pb c), w (pa c - pb s), -w^2 (pa s + pb c)
    x = rep(F0 / osc.k + 0.0)
    v = np.zeros_like(t)
    a = np.zeros_like(t)
    tmp = np.empty_like(t)
    tmp2 = np.empty_like(t)
    for (w, pa, pb), (sn, cs) in zip(osc._terms, trig, strict=True):
        np.multiply(sn, pa, out=tmp)
        np.multiply(cs, pb, out=tmp2)
        tmp += tmp2
        x += tmp
        tmp *= w * w
        a -= tmp
        np.multiply(cs, pa, out=tmp)
        np.multiply(sn, pb, out=tmp2)
        tmp -= tmp2
        tmp *= w
        v += tmp
    # homogeneous part: e (C1 cs + C2 sn), e ((C2 wd - sg C1) cs - (C1 wd + sg C2) sn)
    tau = np.subtract(t, rep(t0))
    e = np.exp(np.multiply(tau, -sg))
    arg = np.multiply(tau, wd)
    cs, sn = np.cos(arg), np.sin(arg)
    xh = rep(C1)
    xh *= cs
    np.multiply(sn, rep(C2), out=tmp)
    xh += tmp
    xh *= e
    vh = rep(C2 * wd - sg * C1)
    vh *= cs
    np.multiply(sn, rep(C1 * wd + sg * C2), out=tmp)
    vh -= tmp
    vh *= e
    ah = np.multiply(vh, -2.0 * sg)
    np.multiply(xh, osc.k / osc.m, out=tmp)
    ah -= tmp
    x += xh
    v += vh
    a += ah
    return x, v, a, tau


#: Grids of at least this many instants are cached by :meth:`SimulationResult.evaluate`.
_MIN_CACHED = 256
#: How many evaluated grids a result keeps.
_N_EVALUATED = 2


@dataclass(frozen=True)
class SimulationResult:
    """Exact trajectory of a simulation, evaluable at any time.

    Attributes
    ----------
    params : SystemParams
    effects : Effects
    b : float
        True half-clearance (nominal b plus any ``clearance_error``).
    settle, duration : float
        The record covers [settle, settle + duration] of simulation time.
    impacts : ImpactTable
        All impacts, settle included (use :meth:`record_impacts`).
    sticking : list of (t_start, t_end, where)
        Phases where the ball moved with the LO; ``where`` is "right", "left"
        (stuck to a wall) or "middle" (held by static friction).
    status : int
        0: reached the end; 1: stopped by the event bound.
    message : str
    n_events : int
    contact : ContactModel or None
        The compliant walls, or None for the exact engine (instantaneous impacts).
    """

    params: SystemParams
    effects: Effects
    b: float
    settle: float
    duration: float
    impacts: ImpactTable
    sticking: list
    status: int
    message: str
    n_events: int
    _segments: dict = field(repr=False)
    _model: object = field(repr=False)
    contact: object = None
    #: The last grids evaluated and their states (see :meth:`evaluate`).
    _evaluated: list = field(default_factory=list, repr=False, compare=False)

    def __getstate__(self) -> dict:
        # evaluated states are a cache: not shipped to worker processes
        state = dict(self.__dict__)
        state["_evaluated"] = []
        return state

    @property
    def impulsive(self) -> bool:
        """True when impacts are instantaneous (the exact engine).

        Then the LO velocity jumps at impacts and ``evaluate()["xdd"]`` excludes the
        impulses; with compliant walls (False) ``xdd`` is the full, continuous LO
        acceleration including the contact forces.
        """
        return self.contact is None

    @classmethod
    def from_loop(cls, model: _Model, segs, impacts, sticks, status, message, n_events
                  ) -> SimulationResult:
        """Assemble from the event loop's lists."""
        names = ("t0", "t1", "mode", "C1", "C2", "F0", "y0", "w0", "ab", "stuck")
        if segs:
            arr = np.array(segs, dtype=float)
            seg = {n: arr[:, i] for i, n in enumerate(names)}
        else:  # pragma: no cover - the loop always writes a segment
            seg = {n: np.zeros(0) for n in names}
        where = {1: "right", -1: "left", 0: "middle"}
        return cls(model.p, model.fx, model.b, model.opt.settle, model.opt.duration,
                   ImpactTable.from_rows(impacts),
                   [(a, b, where[w]) for a, b, w in sticks], status, message, n_events,
                   seg, model)

    # ------------------------------------------------------------------ evaluate
    @property
    def t_end(self) -> float:
        """End of the simulated span (s)."""
        return float(self._segments["t1"][-1]) if self._segments["t1"].size else 0.0

    def evaluate(self, t) -> dict[str, np.ndarray]:
        """State at times ``t`` (simulation clock).

        The sensor model and the ground-truth labeller evaluate the same record grid:
        the states of the last :data:`_N_EVALUATED` grids of more than
        :data:`_MIN_CACHED` instants are kept and returned again for an equal grid
        (one comparison instead of a re-evaluation; ~6 ms per 32k instants). The
        arrays returned are read-only for that reason: copy one before changing it.

        Returns
        -------
        dict
            ``x``, ``xd``, ``xdd`` (LO displacement, velocity, smooth acceleration
            without the impact impulses; with compliant walls the full acceleration),
            ``y``, ``yd`` (ball), ``z`` = y - x, ``xe`` (base displacement).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if t.size < _MIN_CACHED:
            return self._evaluate(t)
        for grid, states in self._evaluated:
            if grid.shape == t.shape and grid[0] == t[0] and np.array_equal(grid, t):
                return dict(states)
        states = self._evaluate(t)
        for arr in states.values():
            arr.flags.writeable = False
        grid = t.copy()
        grid.flags.writeable = False
        self._evaluated.insert(0, (grid, states))
        del self._evaluated[_N_EVALUATED:]
        return dict(states)

    def _evaluate(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """:meth:`evaluate` without the cache (``t`` a 1-D float array)."""
        seg = self._segments
        model = self._model
        runs = _segment_runs(seg["t0"], t)
        if runs is not None:
            j0, j1, counts = runs
            modes = seg["mode"][j0:j1]
            if (modes == modes[0]).all():   # one mode throughout: the fused path
                return self._evaluate_runs(t, j0, j1, counts, int(modes[0]))
            idx = np.repeat(np.arange(j0, j1), counts)
        else:
            idx = np.clip(np.searchsorted(seg["t0"], t, side="right") - 1, 0,
                          seg["t0"].size - 1)
        out = {k: np.empty_like(t) for k in ("x", "xd", "xdd", "y", "yd")}
        trig = model.base.trig(t)          # the LO's and the base's harmonics, once
        modes = seg["mode"][idx]
        for mode, osc in ((0, model.free), (1, model.stuck)):
            sel = modes == mode
            if not sel.any():
                continue
            if sel.all():                  # one mode throughout: no masked copies
                sel, i, ts, tg = slice(None), idx, t, trig
            else:
                i, ts = idx[sel], t[sel]
                tg = [(sn[sel], cs[sel]) for sn, cs in trig]
            t0 = seg["t0"][i]
            x, v, a = osc.state_array(ts, t0, seg["C1"][i], seg["C2"][i], seg["F0"][i], tg)
            out["x"][sel], out["xd"][sel], out["xdd"][sel] = x, v, a
            if mode == 0:
                tau = ts - t0
                out["y"][sel] = seg["y0"][i] + seg["w0"][i] * tau + 0.5 * seg["ab"][i] * tau ** 2
                out["yd"][sel] = seg["w0"][i] + seg["ab"][i] * tau
            else:
                out["y"][sel] = x + seg["y0"][i]
                out["yd"][sel] = v
        out["z"] = out["y"] - out["x"]
        out["xe"] = model.base.displacement(t, trig)
        return out

    def _evaluate_runs(self, t: np.ndarray, j0: int, j1: int, counts: np.ndarray,
                       mode: int) -> dict[str, np.ndarray]:
        """:meth:`_evaluate` of a sorted grid spent in one mode, segment by segment.

        ``t`` holds ``counts[k]`` instants of segment ``j0 + k`` after each other
        (:func:`_segment_runs`). The arithmetic is that of the general path, operation
        for operation (so the states are the same to the bit): only the gathers of the
        segment constants become repeats, the expressions of segment constants alone
        are computed once per segment, and the temporaries are reused.
        """
        seg, model = self._segments, self._model
        sl = slice(j0, j1)
        osc = model.free if mode == 0 else model.stuck
        trig = model.base.trig(t)
        x, v, a, tau = _flow_runs(osc, t, trig, seg["t0"][sl], seg["C1"][sl], seg["C2"][sl],
                                  seg["F0"][sl], counts)
        if mode == 0:
            # y0 + w0 tau + (0.5 ab) tau^2, and w0 + ab tau
            ab = seg["ab"][sl]
            w0 = np.repeat(seg["w0"][sl], counts)
            y = np.repeat(seg["y0"][sl], counts)
            y += np.multiply(w0, tau)
            tau2 = np.multiply(tau, tau)
            tau2 *= np.repeat(0.5 * ab, counts)
            y += tau2
            yd = np.repeat(ab, counts)
            yd *= tau
            yd += w0
        else:
            y = np.repeat(seg["y0"][sl], counts)
            y += x
            yd = v.copy()
        return {"x": x, "xd": v, "xdd": a, "y": y, "yd": yd, "z": np.subtract(y, x),
                "xe": model.base.displacement(t, trig)}

    def record_impacts(self) -> ImpactTable:
        """Impacts inside the record window [settle, settle + duration]."""
        t = self.impacts.t
        return self.impacts.select((t >= self.settle) & (t <= self.settle + self.duration))

    def record_sticking(self) -> list:
        """Sticking phases overlapping the record, clipped to it, in record time."""
        t0, t1 = self.settle, self.settle + self.duration
        return [(max(a, t0) - t0, min(b, t1) - t0, w) for a, b, w in self.sticking
                if b > t0 and a < t1]
