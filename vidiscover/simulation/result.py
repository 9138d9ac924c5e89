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
        idx = np.clip(np.searchsorted(seg["t0"], t, side="right") - 1, 0, seg["t0"].size - 1)
        out = {k: np.empty_like(t) for k in ("x", "xd", "xdd", "y", "yd")}
        model = self._model
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

    def record_impacts(self) -> ImpactTable:
        """Impacts inside the record window [settle, settle + duration]."""
        t = self.impacts.t
        return self.impacts.select((t >= self.settle) & (t <= self.settle + self.duration))

    def record_sticking(self) -> list:
        """Sticking phases overlapping the record, clipped to it, in record time."""
        t0, t1 = self.settle, self.settle + self.duration
        return [(max(a, t0) - t0, min(b, t1) - t0, w) for a, b, w in self.sticking
                if b > t0 and a < t1]
