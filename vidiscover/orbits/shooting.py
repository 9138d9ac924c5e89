"""Periodic impacting orbits by Newton shooting on the exact impact map.

The section is "just after an impact on a given wall": its coordinates are
``q = (t, x, x', y')`` (the ball position is ``y = x + side b`` there). The impact map
flies the exact engine's closed-form flow to the next event (the engine's own event
location, :mod:`vidiscover.simulation.engine`), applies Newton's impact law, and
repeats for the ``n`` impacts of an orbit with ``n`` impacts per ``p`` forcing periods,
whose side sequence is prescribed. A periodic orbit is a zero of
``F(q) = P(q) - q - (p T, 0, 0, 0)``; Newton's method uses the exact Jacobian of
``P`` (flow Jacobians, event-time derivatives and saltation matrices, see
:mod:`.monodromy`), whose eigenvalues are the Floquet multipliers.

Stick phases are part of the map, as in the engine: a rebound slower than
``stick_speed`` leaves the ball stuck to the wall (the end of a chatter sequence),
and with dry friction the ball can stick to the LO where its relative velocity
vanishes. The flow then is the closed-form flow of the LO carrying the ball; the
release (friction or wall force limit reached, a time-dependent event) contributes
its own saltation term, and the collapsed dimension gives zero multipliers.

Whatever is not a clean orbit of the prescribed sequence is reported as not found
with the reason: the impact sequence changes (grazing or another orbit), the ball
stays stuck or creeps, Newton diverges.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..effects import Effects
from ..errors import InputError
from ..params import G_ACCEL, SystemParams
from ..simulation.engine import LEFT, MIDDLE, RIGHT, SimOptions, _Loop, _Model
from .monodromy import (
    flow_jacobian,
    impact_reset_jacobian,
    law_derivative,
    piece_jacobian,
    vector_field,
)

__all__ = ["ImpactMap", "MapError", "Orbit", "solve_orbit", "orbit_kind", "SIDE_NAME",
           "SIDE_CODE", "UNSUPPORTED_EFFECTS"]

SIDE_NAME = {RIGHT: "right", LEFT: "left"}
SIDE_CODE = {"right": RIGHT, "left": LEFT, RIGHT: RIGHT, LEFT: LEFT}
#: Effects the impact map refuses (time-dependent walls: no periodic orbit).
UNSUPPORTED_EFFECTS = ("restitution_drift",)
_GRAD_ZERO = np.array([0.0, -1.0, 0.0, 1.0])
_MAX_EVENTS = 200   # reversals / stick phases between two impacts of an orbit


def _base(m, t: float) -> tuple[float, float, float]:
    """Base displacement, velocity and acceleration at ``t``."""
    xe = vxe = axe = 0.0
    for om, br, bi in m._base_terms:
        sn, cs = math.sin(om * t), math.cos(om * t)
        xe += br * sn + bi * cs
        vxe += om * (br * cs - bi * sn)
        axe -= om * om * (br * sn + bi * cs)
    return xe, vxe, axe


def stuck_field(m, t: float, X) -> np.ndarray:
    """``X'`` while the ball moves with the LO (mass m1 + m2, constant m2 g sin theta)."""
    xe, vxe, _ = _base(m, t)
    p = m.p
    a = (p.c1 * (vxe - X[1]) + p.k1 * (xe - X[0]) + m.m2 * m.gs) / m.M
    return np.array([X[1], a, X[1], a])


class MapError(Exception):
    """The impact map is not defined at this state; ``reason`` says why."""

    def __init__(self, reason: str, kind: str = "other") -> None:
        super().__init__(reason)
        self.reason = reason
        self.kind = kind  # "sequence" (grazing / other impact), "stick", "other"


@dataclass(frozen=True)
class Piece:
    """One flight of an orbit, from ``t0`` (state ``X0``) to the event at ``t1``.

    A piece whose event is ``release`` is a stick phase (the ball moves with the LO).
    """

    t0: float
    t1: float
    X0: tuple
    s: int
    event: str          # "right", "left", "reversal", "stick" (flight ends stuck), "release"
    u_minus: float      # relative velocity z' just before the event


class ImpactMap:
    """The exact impact map of one parameter set.

    Parameters
    ----------
    params : SystemParams
    effects : Effects, optional
    stick_speed : float
        A rebound slower than this (m/s) sticks the ball to the wall (as in the engine);
        an orbit that does so is refused.
    """

    def __init__(self, params: SystemParams, effects: Effects | None = None,
                 stick_speed: float = 1e-4) -> None:
        effects = effects if effects is not None else Effects()
        bad = [n for n in UNSUPPORTED_EFFECTS if n in effects]
        if bad:
            raise InputError(f"effect {bad[0]} makes the walls change in time: it has no "
                             "periodic orbits; remove it for orbits/continue")
        self.params, self.effects = params, effects
        self.model = _Model(params, effects, SimOptions(settle=0.0, duration=1.0,
                                                        stick_speed=stick_speed))
        self.loop = _Loop(self.model)
        self.T = 1.0 / params.frequency
        self.b = self.model.b
        self.friction = self.model.mug > 0.0
        self.vscale = self.b * 2 * math.pi * params.frequency

    # ------------------------------------------------------------------ the map
    def embed(self, q, side: int) -> np.ndarray:
        """Full state ``(x, x', y, y')`` of section coordinates ``q`` on ``side``."""
        t, x, v, w = q
        return np.array([x, v, x + side * self.b, w])

    def trip(self, q0, sides, jac: bool = True):
        """Fly from ``q0`` (just after an impact on ``sides[0]``) through the sequence.

        Returns
        -------
        q_end : ndarray (4,)
            Section coordinates just after the ``n``-th impact (on ``sides[0]`` again).
        J : ndarray (4, 4) or None
            ``d q_end / d q0`` (the impact map's Jacobian), if ``jac``.
        pieces : list of Piece
            The flights, events and sliding directions.

        Raises
        ------
        MapError
            Another wall is hit first (grazing), the ball sticks, or no impact comes.
        """
        m, loop = self.model, self.loop
        n = len(sides)
        side0 = sides[0]
        t = float(q0[0])
        X = self.embed(q0, side0)
        if jac:
            E = np.zeros((5, 4))
            E[0, 1] = E[1, 2] = E[2, 1] = E[3, 3] = E[4, 0] = 1.0
            Jt = E
        pieces: list[Piece] = []
        wall = side0
        horizon = 3.0 * self.T * max(n, 1)
        released = None
        for k in range(1, n + 1):
            target = sides[k % n]
            if released is not None:       # the ball left a wall it was stuck to
                s = released
            else:
                u = X[3] - X[1]
                if u * wall >= 0.0:
                    raise MapError(f"the ball does not leave the {SIDE_NAME[wall]} wall "
                                   f"(z' = {u:.3g} m/s)", "stick")
                s = 1 if u > 0 else -1
            for _ in range(_MAX_EVENTS):
                loop.t_end = t + horizon
                loop.segs.clear()
                te, x, v, y, w, kind = loop._flight(t, X[0], X[1], X[2], X[3], s, wall)
                Xm = np.array([x, v, y, w])
                if kind == "end":
                    raise MapError(f"no impact within {horizon:.3g} s of t = {t:.6g} s",
                                   "sequence")
                if kind == "zero":
                    s_new = loop._slide_sign(te, x, v, 0.0, MIDDLE)
                    Xm[3] = Xm[1]
                    pieces.append(Piece(t, te, tuple(X), s, "reversal" if s_new else "stick",
                                        0.0))
                    if jac:
                        f0 = vector_field(m, t, X, s)
                        fm = vector_field(m, te, Xm, s)
                        P = piece_jacobian(flow_jacobian(m.free, te - t), f0, fm, _GRAD_ZERO,
                                           np.eye(4))
                        Jt = P @ Jt
                    t, X, s, wall = te, Xm, s_new, MIDDLE
                    if s_new is None:   # stick phase: the ball moves with the LO
                        t, X, s, Jt = self._stick(t, X, Jt if jac else None, pieces)
                    continue
                break
            else:
                raise MapError(f"more than {_MAX_EVENTS} reversals or stick phases before "
                               f"impact {k} (the ball creeps with the LO)", "stick")
            if kind != target:
                raise MapError(f"impact {k} of the sequence hits the {SIDE_NAME[kind]} wall, "
                               f"not the {SIDE_NAME[target]} one (grazing or another orbit)",
                               "sequence")
            Xm[2] = Xm[0] + kind * self.b
            um = Xm[3] - Xm[1]
            pieces.append(Piece(t, te, tuple(X), s, SIDE_NAME[kind], um))
            speed = abs(um)
            law = m.laws[SIDE_NAME[kind]]
            r = m.restitution(kind, speed, te)
            up = -r * um
            stuck = abs(up) < m.opt.stick_speed   # as the engine: the ball stays at the wall
            if stuck:
                if k == n:
                    raise MapError(f"the closing impact on the {SIDE_NAME[kind]} wall sticks "
                                   "(start the sequence at an impact that rebounds)", "sequence")
                up = 0.0
            vp = (m.m1 * Xm[1] + m.m2 * Xm[3] - m.m2 * up) / m.M
            Xp = np.array([Xm[0], vp, Xm[2], vp + up])
            if jac:
                rho = 0.0 if stuck else r + law_derivative(law, speed) * speed
                f0 = vector_field(m, t, X, s)
                fm = vector_field(m, te, Xm, s)
                grad = kind * np.array([-1.0, 0.0, 1.0, 0.0])
                P = piece_jacobian(flow_jacobian(m.free, te - t), f0, fm, grad,
                                   impact_reset_jacobian(m.m1, m.m2, rho))
                Jt = P @ Jt
            t, X, wall = te, Xp, kind
            released = None
            if stuck:   # the wall holds the ball, or it slides off at once (as the engine)
                released = loop._slide_sign(t, X[0], X[1], 0.0, kind)
                if released is None:
                    t, X, released, Jt = self._stick(t, X, Jt if jac else None, pieces, kind)
        q_end = np.array([t, X[0], X[1], X[3]])
        J = None
        if jac:
            J = Jt[[4, 0, 1, 3]]
        return q_end, J, pieces

    def _stick(self, t, X, Jt, pieces, where=MIDDLE):
        """A stick phase (on the LO, or at wall ``where``) from ``(t, X)`` to the release.

        The extended Jacobian ``Jt`` is carried through the stuck flow and the release
        event (None: no Jacobian).
        """
        m, loop = self.model, self.loop
        loop.segs.clear()
        te, x, v, y, w, s_new = loop._stuck(t, X[0], X[1], X[2], where)
        if s_new == 0:
            raise MapError(f"the ball stays stuck to the LO from t = {t:.6g} s", "stick")
        Xr = np.array([x, v, y, w])
        pieces.append(Piece(t, te, tuple(X), 0, "release", 0.0))
        if Jt is not None:
            ph = flow_jacobian(m.stuck, te - t)
            phi = np.zeros((4, 4))
            phi[:2, :2] = ph[:2, :2]
            phi[2, :2] = ph[0, :2]
            phi[2, 0] -= 1.0
            phi[2, 2] = 1.0
            phi[3, :2] = ph[1, :2]
            f0 = stuck_field(m, t, X)
            fm = stuck_field(m, te, Xr)
            p = m.p
            grad = np.array([-p.k1 / m.M, -p.c1 / m.M, 0.0, 0.0])
            _, vxe, axe = _base(m, te)
            g_t = (p.c1 * axe + p.k1 * vxe) / m.M
            Jt = piece_jacobian(phi, f0, fm, grad, np.eye(4), g_t) @ Jt
        return te, Xr, s_new, Jt

    def residual(self, q, sides, p: int, jac: bool = True):
        """``F(q) = P(q) - q - (p T, 0, 0, 0)`` and its Jacobian ``DP - I``."""
        qe, J, pieces = self.trip(q, sides, jac)
        F = qe - np.asarray(q, dtype=float)
        F[0] -= p * self.T
        return F, (None if J is None else J - np.eye(4)), J, pieces

    def scale(self) -> np.ndarray:
        """Typical sizes of ``q``'s components (s, m, m/s, m/s), for norms."""
        return np.array([self.T, self.b, self.vscale, self.vscale])

    def flight_margin(self, pieces) -> tuple[float, float]:
        """Grazing measures of an orbit: (min interior wall distance / b, min impact speed).

        The distance is ``b - |z|`` at the interior extrema of z over the flights (an
        extremum reaching a wall is a grazing impact); the speed is ``|z'-|`` over the
        impacts (a vanishing impact speed is the other grazing).
        """
        osc, m = self.model.free, self.model
        dist, speed = 1.0, math.inf
        for pc in pieces:
            if pc.event == "release":   # a stick phase: z is constant
                continue
            if pc.event in ("right", "left"):
                speed = min(speed, abs(pc.u_minus))
            x0, v0, y0, w0 = pc.X0
            ab = m.gs - m.mug * pc.s
            F0 = m.mu * m.m2 * G_ACCEL * pc.s
            C1, C2 = osc.coefficients(pc.t0, x0, v0, F0)
            tt = np.linspace(pc.t0, pc.t1, 129)
            tau = tt - pc.t0
            x, v, a = osc.state_array(tt, pc.t0, C1, C2, F0)
            zd = w0 + ab * tau - v
            for i in np.flatnonzero(zd[1:-2] * zd[2:-1] < 0) + 1:
                ta, tb = tt[i], tt[i + 1]
                for _ in range(40):  # bisection on z' = 0
                    tm = 0.5 * (ta + tb)
                    xm, vm, _ = osc.state(tm, pc.t0, C1, C2, F0)
                    zdm = w0 + ab * (tm - pc.t0) - vm
                    if zdm * zd[i] > 0:
                        ta = tm
                    else:
                        tb = tm
                xm, vm, _ = osc.state(ta, pc.t0, C1, C2, F0)
                zm = y0 + w0 * (ta - pc.t0) + 0.5 * ab * (ta - pc.t0) ** 2 - xm
                dist = min(dist, (self.b - abs(zm)) / self.b)
        return dist, speed


@dataclass
class Orbit:
    """A periodic impacting orbit (or the reason why none was found).

    Attributes
    ----------
    found : bool
    reason : str
        Why not found ("" when found).
    sides : tuple of int
        Side sequence (+1 right, -1 left), starting with the section's wall.
    period_cycles : int
        p: the orbit repeats after p forcing periods.
    q : ndarray (4,)
        Section coordinates (t, x, x', y') just after the first impact.
    multipliers : ndarray (4,) complex
        Floquet multipliers (eigenvalues of the impact map's Jacobian), largest first.
    jacobian : ndarray (4, 4)
        The impact map's Jacobian over one period of the orbit.
    pieces : list of Piece
    iterations : int
    residual : float
        Scaled residual norm at the solution.
    """

    found: bool
    reason: str
    sides: tuple
    period_cycles: int
    q: np.ndarray
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    jacobian: np.ndarray | None = None
    pieces: list = field(default_factory=list)
    iterations: int = 0
    residual: float = math.inf
    T: float = 0.125
    margin: float = math.nan
    min_speed: float = math.nan

    @property
    def n_impacts(self) -> int:
        """Impacts per orbit period."""
        return len(self.sides)

    @property
    def max_multiplier(self) -> float:
        """Largest Floquet multiplier modulus."""
        return float(np.max(np.abs(self.multipliers))) if self.multipliers.size else math.nan

    @property
    def stable(self) -> bool:
        """Found and all multipliers inside the unit circle."""
        return bool(self.found and self.max_multiplier < 1.0)

    @property
    def impacts(self) -> list[dict]:
        """Impacts of one period: time (s, in [t_first, t_first + pT)), side, z'- (m/s)."""
        return [{"t": pc.t1, "side": pc.event, "v": pc.u_minus}
                for pc in self.pieces if pc.event in ("right", "left")]

    @property
    def kind(self) -> str:
        """Regime label of the orbit (:func:`orbit_kind`), ``not_found`` if not found."""
        return orbit_kind(self) if self.found else "not_found"

    def to_dict(self) -> dict:
        """JSON-ready form (keys: docs page 'Periodic orbits and continuation', JSON)."""
        if not self.found:
            return {"kind": "not_found", "found": False, "reason": self.reason,
                    "impacts_per_period": len(self.sides) / self.period_cycles,
                    "period_cycles": self.period_cycles,
                    "sides": [SIDE_NAME[s] for s in self.sides]}
        imps = self.impacts
        t0 = imps[-1]["t"] - self.period_cycles * self.T
        shift = math.floor(t0 / self.T) * self.T
        ordered = sorted(({**d, "t": d["t"] - shift} for d in imps), key=lambda d: d["t"])
        for d in ordered:  # within [0, pT): phase of the orbit in the forcing
            d["t"] = d["t"] % (self.period_cycles * self.T)
        ordered.sort(key=lambda d: d["t"])
        return {"kind": self.kind, "found": True, "reason": "",
                "impacts_per_period": len(self.sides) / self.period_cycles,
                "period_cycles": self.period_cycles, "stable": self.stable,
                "max_multiplier": self.max_multiplier,
                "multipliers": [{"re": float(z.real), "im": float(z.imag), "abs": float(abs(z))}
                                for z in self.multipliers],
                "impacts": ordered, "sides": [SIDE_NAME[s] for s in self.sides],
                "grazing_margin": self.margin, "min_impact_speed": self.min_speed,
                "iterations": self.iterations, "residual": self.residual}


def orbit_kind(orbit: Orbit) -> str:
    """The regime label a simulation sitting on ``orbit`` would get (docs page 'Regime labels').

    ``1ipc``: one impact in every forcing cycle; ``2ipc_sym``/``2ipc_asym``: two
    alternating impacts in every cycle, with the asymmetry of the label definition;
    ``multi_ipc``: any other pattern with an impact in every cycle; ``subharmonic``:
    some cycles without impact (not a regime label: such orbits are rare attractors).
    """
    T, p = orbit.T, orbit.period_cycles
    imps = orbit.impacts
    counts = [0] * p
    for d in imps:
        counts[int(math.floor((d["t"] % (p * T)) / T + 1e-12)) % p] += 1
    if min(counts) == 0:
        return "subharmonic"
    if all(c == 1 for c in counts):
        return "1ipc"
    sides = [d["side"] for d in imps]
    alternating = all(sides[i] != sides[(i + 1) % len(sides)] for i in range(len(sides)))
    if all(c == 2 for c in counts) and alternating:
        times = [d["t"] for d in imps]
        n = len(times)
        dts = {"right": [], "left": []}
        for i in range(n):
            dt = (times[(i + 1) % n] - times[i]) % (p * T)
            dts[sides[i]].append(dt)
        asym = abs(np.mean(dts["right"]) - np.mean(dts["left"])) / T
        return "2ipc_sym" if asym < 0.1 else "2ipc_asym"
    return "multi_ipc"


def solve_orbit(imap: ImpactMap, q_guess, sides, p: int = 1, *, tol: float = 1e-12,
                maxiter: int = 40) -> Orbit:
    """Newton shooting for the orbit of side sequence ``sides`` over ``p`` periods.

    Parameters
    ----------
    imap : ImpactMap
    q_guess : array-like (4,)
        (t, x, x', y') just after an impact on ``sides[0]``.
    sides : sequence of int or str
        Walls hit in one period of the orbit, e.g. ``("right", "left")``.
    p : int
        Forcing periods per orbit period.
    tol : float
        Convergence on the scaled Newton step and residual.

    Returns
    -------
    Orbit
        ``found`` False with the reason when Newton fails or the map is undefined.
    """
    sides = tuple(SIDE_CODE[s] for s in sides)
    if not sides or p < 1:
        raise InputError(f"an orbit needs >= 1 impact and p >= 1 periods, got "
                         f"{len(sides)} impact(s), p = {p!r}")
    q = np.array(q_guess, dtype=float)
    sc = imap.scale()
    T = imap.T
    fail = Orbit(False, "", sides, p, q, T=T)
    try:
        F, JF, J, pieces = imap.residual(q, sides, p)
    except MapError as err:
        fail.reason = f"the guess is not on the sequence: {err.reason}"
        return fail
    norm = float(np.linalg.norm(F / sc))
    for it in range(1, maxiter + 1):
        try:
            dq = np.linalg.solve(JF, -F)
        except np.linalg.LinAlgError:
            fail.reason = "singular Newton matrix (a multiplier at 1: fold)"
            return fail
        lam = 1.0
        for _ in range(12):
            qn = q + lam * dq
            try:
                Fn, JFn, Jn, pn = imap.residual(qn, sides, p)
            except MapError as err:
                last = err.reason
                lam *= 0.5
                continue
            nn = float(np.linalg.norm(Fn / sc))
            if nn < norm or nn < tol:
                break
            last = "residual does not decrease"
            lam *= 0.5
        else:
            fail.reason = f"Newton stalled after {it} iterations ({last})"
            fail.iterations = it
            return fail
        step = float(np.linalg.norm(lam * dq / sc))
        q, F, JF, J, pieces, norm = qn, Fn, JFn, Jn, pn, nn
        if norm < tol or (step < tol and norm < 1e3 * tol):
            break
    else:
        fail.reason = f"Newton did not converge in {maxiter} iterations (residual {norm:.2g})"
        fail.iterations = maxiter
        return fail
    shift = math.floor(q[0] / T) * T
    if shift:
        q = q.copy()
        q[0] -= shift
        _, _, J, pieces = imap.residual(q, sides, p)
    mult = np.linalg.eigvals(J)
    mult = mult[np.argsort(-np.abs(mult), kind="stable")]
    dist, speed = imap.flight_margin(pieces)
    return Orbit(True, "", sides, p, q, mult, J, pieces, it, norm, T, dist, speed)


def state_at(imap: ImpactMap, orbit: Orbit, t: float) -> np.ndarray:
    """State ``(x, x', y, y')`` of a found orbit at time ``t`` (any t; the orbit repeats)."""
    if not orbit.found:
        raise InputError(f"no state: the orbit was not found ({orbit.reason})")
    m = imap.model
    period = orbit.period_cycles * orbit.T
    t_first = orbit.pieces[0].t0
    ts = t_first + (t - t_first) % period
    for pc in orbit.pieces:
        if pc.t0 <= ts <= pc.t1:
            break
    x0, v0, y0, w0 = pc.X0
    if pc.event == "release":
        F0 = m.m2 * m.gs
        C1, C2 = m.stuck.coefficients(pc.t0, x0, v0, F0)
        x, v, _ = m.stuck.state(ts, pc.t0, C1, C2, F0)
        return np.array([x, v, x + (y0 - x0), v])
    ab = m.gs - m.mug * pc.s
    F0 = m.mu * m.m2 * G_ACCEL * pc.s
    C1, C2 = m.free.coefficients(pc.t0, x0, v0, F0)
    x, v, _ = m.free.state(ts, pc.t0, C1, C2, F0)
    tau = ts - pc.t0
    return np.array([x, v, y0 + w0 * tau + 0.5 * ab * tau * tau, w0 + ab * tau])
