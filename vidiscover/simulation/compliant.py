"""Compliant-contact simulation: walls as clipped penalty forces.

Model (state x, x', z = y - x, z'; ``delta = s z - b`` the penetration beyond the
wall ``s`` = +1 right / -1 left, ``F >= 0`` the clipped law of that wall,
:mod:`.contact`)::

    m1 x'' = c1 (xe' - x') + k1 (xe - x) + s F + mu m2 g tanh(z' / v_s)
    m2 y'' = -s F - mu m2 g tanh(z' / v_s) + m2 g sin(theta)

A contact episode starts when ``|z|`` crosses ``b`` outward and ends when the force
returns to zero for the last time before the ball is back inside the clearance
(if the force comes back while ``delta > 0``, the ball never left the wall: same
episode). Each episode is one row of the ground truth: ``t`` = ``t_in``, ``t_out``,
``u_minus`` = ``v_in`` (z' at entry), ``u_plus`` = ``v_out`` (z' at exit),
``r = -v_out / v_in``.

Speed design
------------
* Without friction (``mu = 0``) flights are closed form: the exact engine's flight
  (:class:`~.engine._Loop`, its event grid and bracketed Newton search for
  ``|z| = b``) is reused unchanged.
* Kelvin-Voigt contacts are linear: closed form by the eigen-decomposition of the
  4x4 system matrix (once per wall and sign of friction) plus the particular
  response to the harmonic base forcing and the constant forces; the exit
  (force = 0) is found on a grid of 1/32 of the contact half-period, refined by
  bracketed Newton.
* Hunt-Crossley contacts, and friction inside the band below, are integrated with
  ``scipy.integrate.odeint`` (LSODA, rtol ``SimOptions.contact_rtol``; its Fortran
  loop calls the Python right-hand side with far less overhead than ``solve_ivp``'s
  Python stepping) of the whole clipped model (beyond a contact's exit the force is
  zero: integrating past it is the true flow), on a grid of 1/256 of the contact's
  duration (contacts) or 1/20 of the friction law's time scale (band). Events (force
  zero, wall entry, band edge) are located on the grid, refined on the cubic Hermite
  interpolant of the grid's states and derivatives, and the state there is integrated
  from the last grid point; the grids are the dense output of
  :meth:`CompliantResult.evaluate`. ~1.5 ms per HC contact.
* Friction is regularised, ``tanh(z'/v_s)`` with ``v_s`` = ``SimOptions.friction_speed``
  (1 mm/s default). While ``|z'| >= 20 v_s`` the tanh is +/-1 in double precision:
  flights are the exact engine's closed form with Coulomb friction of fixed sign,
  KV contacts the closed form with that constant force; inside the band
  ``|z'| < 20 v_s`` (every reversal, in contacts too, and the ball held by
  friction) the flow is integrated (friction is a stiff viscous law there, rate
  ``mu g / v_s``, 1.5e3 1/s at mu = 0.15): ~100 right-hand sides per reversal. A
  closed-form phase started on the band's edge finds a return into the band after
  its start (a deflated root), never a zero-length phase.
* Paper rig, 25.12 s simulated (CPU time on a loaded machine): KV 0.24-0.29 s,
  HC (k 1e9, alpha 0.3) 0.56-0.82 s, KV with mu 0.15 and tilt 2 deg 1.0-1.1 s.

A contact episode still open at the end of the span is not in the impact table.
The number of phases is bounded (``max_events``), so a ball resting on a wall or
chattering cannot hang the engine.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.integrate import odeint, solve_ivp
from scipy.optimize import brentq

from ..effects import Effects
from ..errors import InputError, SimulationError
from ..params import G_ACCEL, SystemParams
from .contact import ContactModel
from .engine import SimOptions, _Loop, _Model, initial_state, merge_options
from .result import ImpactTable, SimulationResult
from .roots import bracketed_newton

__all__ = ["simulate_compliant", "simulate_reference", "CompliantResult", "as_contact_model"]

RIGHT, LEFT = 1, -1
FLIGHT, KV, NUM = 0, 1, 2
#: Friction is closed form (saturated) while |z'| >= BAND v_s: 1 - tanh(20) < 2**-53.
BAND = 20.0
#: Effects that fix the restitution or the impact duration: the contact law does.
_CONFLICTS = ("asymmetric_restitution", "velocity_dependent_restitution",
              "restitution_drift", "contact_duration")


def as_contact_model(contact) -> ContactModel:
    """A :class:`ContactModel` from a model, a spec string or a list of specs."""
    if isinstance(contact, ContactModel):
        return contact
    if isinstance(contact, (str, list, tuple)):
        return ContactModel.parse(contact)
    raise InputError(f"contact must be a ContactModel or --contact spec string(s), "
                     f"was {type(contact).__name__}")


def _check_effects(fx: Effects) -> None:
    bad = [n for n in _CONFLICTS if n in fx]
    if bad:
        raise InputError(f"effect(s) {', '.join(bad)} cannot be used with --contact: the "
                         "walls' restitution and contact duration come from the contact "
                         "law; drop the effect or the --contact option")


class _Wall:
    """One wall's law resolved for the pair's masses."""

    def __init__(self, side: int, law, m_eff: float) -> None:
        self.side, self.law = side, law
        self.kv = law.kind == "kelvin-voigt"
        self.k = law.k
        self.c = law.damping(m_eff) if self.kv else 0.0
        self.a15 = 0.0 if self.kv else 1.5 * law.alpha
        self.n = law.n

    def gate(self, delta: float, ddelta: float) -> float:
        """Sign of the (unclipped) force: positive while the wall pushes."""
        if self.kv:
            return self.k * delta + self.c * ddelta
        return 1.0 + self.a15 * ddelta

    def force(self, delta, ddelta):
        """Clipped force magnitude (0 where ``delta <= 0``), arrays or floats."""
        d = np.maximum(delta, 0.0)
        if self.kv:
            f = self.k * d + self.c * ddelta
        else:
            f = self.k * d ** self.n * (1.0 + self.a15 * ddelta)
        return np.where(d > 0.0, np.maximum(f, 0.0), 0.0)

    def duration(self, speed: float, m_eff: float) -> float:
        """Rough contact duration (s) at an impact speed, to bound integration steps."""
        if self.kv:
            return math.pi / math.sqrt(self.k / m_eff)
        n = self.n
        # time scale of m d'' = -k d^n with d' = v at d = 0
        dmax = ((n + 1) * m_eff * max(speed, 1e-3) ** 2 / (2 * self.k)) ** (1 / (n + 1))
        return 3.0 * dmax / max(speed, 1e-3)


class _KVSystem:
    """Closed form of a Kelvin-Voigt contact on one wall: X' = A X + f(t), X = (x, v, z, u)."""

    def __init__(self, cm: _CModel, wall: _Wall, fsign: int = 0) -> None:
        p, s = cm.p, wall.side
        m1, m2, k, c = p.m1, p.m2, wall.k, wall.c
        A = np.array([[0.0, 1.0, 0.0, 0.0],
                      [-p.k1 / m1, -p.c1 / m1, k / m1, c / m1],
                      [0.0, 0.0, 0.0, 1.0],
                      [p.k1 / m1, p.c1 / m1, -k / m1 - k / m2, -c / m1 - c / m2]])
        f0 = np.array([0.0, -s * k * cm.b / m1, 0.0, s * k * cm.b * (1 / m1 + 1 / m2) + cm.gs])
        # saturated friction of sign fsign: +fric on the LO, -fric on the ball
        f0 += fsign * cm.fric * np.array([0.0, 1 / m1, 0.0, -1 / m1 - 1 / m2])
        self.side, self.k, self.c, self.b = s, k, c, cm.b
        self.lam, self.V = np.linalg.eig(A)
        self.Vinv = np.linalg.inv(self.V)
        self.Xc = -np.linalg.solve(A, f0)
        ev = np.array([0.0, 1.0 / m1, 0.0, -1.0 / m1])
        self.w = cm.base.omegas
        self.P = np.array([np.linalg.solve(1j * w * np.eye(4) - A, ev * (p.k1 + 1j * w * p.c1) * bj)
                           for w, bj in zip(self.w, cm.base.complex_amplitudes, strict=True)])
        fast = int(np.argmax(np.abs(self.lam.imag)))
        self.wc = abs(self.lam[fast].imag)
        self.sigma = -self.lam[fast].real
        self.h = math.pi / self.wc / 32.0

    def particular(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Particular state and its derivative at times ``t`` (N,) -> (N, 4) each."""
        e = np.exp(1j * np.outer(t, self.w))                  # (N, H)
        Xp = self.Xc + (e @ self.P).imag
        dXp = ((e * (1j * self.w)) @ self.P).imag
        return Xp, dXp

    def coeffs(self, t0: float, X0: np.ndarray) -> np.ndarray:
        """Modal coefficients of the homogeneous part for state ``X0`` at ``t0``."""
        return self.Vinv @ (X0 - self.particular(np.array([t0]))[0][0])

    def state(self, t: np.ndarray, t0, c) -> tuple[np.ndarray, np.ndarray]:
        """State (N, 4) and derivative at ``t``; ``t0`` (N,) or scalar, ``c`` (N, 4) or (4,)."""
        Xp, dXp = self.particular(t)
        E = np.atleast_2d(c) * np.exp(np.outer(t - t0, self.lam))   # (N, 4)
        return Xp + (E @ self.V.T).real, dXp + ((E * self.lam) @ self.V.T).real

    def gate(self, X: np.ndarray, dX: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unclipped force k delta + c delta' and its time derivative."""
        s = self.side
        return (self.k * (s * X[:, 2] - self.b) + self.c * s * X[:, 3],
                self.k * s * X[:, 3] + self.c * s * dX[:, 3])


class _CModel:
    """Everything the compliant loop needs, resolved once."""

    def __init__(self, p: SystemParams, fx: Effects, contact: ContactModel,
                 opt: SimOptions) -> None:
        _check_effects(fx)
        self.exact = _Model(p, fx, opt)          # flights, base, grid, validation
        self.p, self.fx, self.opt, self.contact = p, fx, opt, contact
        self.b, self.gs, self.base = self.exact.b, self.exact.gs, self.exact.base
        self.free = self.exact.free
        self.m_eff = p.m1 * p.m2 / (p.m1 + p.m2)
        self.walls = {RIGHT: _Wall(RIGHT, contact.right, self.m_eff),
                      LEFT: _Wall(LEFT, contact.left, self.m_eff)}
        self.fric = fx.mu * p.m2 * G_ACCEL
        self.vs = opt.friction_speed
        signs = (-1, 1) if self.fric > 0 else (0,)
        #: closed-form KV contact per (wall, sign of saturated friction), and their ids
        self.kv = {(s, f): _KVSystem(self, w, f) for s, w in self.walls.items() if w.kv
                   for f in signs}
        self.kv_ids = {key: i for i, key in enumerate(self.kv)}
        self._terms = [(float(w), float(bj.real), float(bj.imag)) for w, bj in
                       zip(self.base.omegas, self.base.complex_amplitudes, strict=True)]

    # ---------------------------------------------------------------- right-hand side
    def rhs(self, active: int):
        """Scalar right-hand side with the contact of wall ``active`` (0: none) switched on.

        In a contact phase the law is not clipped (the phase ends where it would
        be): the flow stays smooth inside every integration step.
        """
        p, terms, gs, fric, vs = self.p, self._terms, self.gs, self.fric, self.vs
        m1, m2, c1, k1 = p.m1, p.m2, p.c1, p.k1
        wall = self.walls.get(active)
        b = self.b
        tanh, sin, cos = math.tanh, math.sin, math.cos

        def f(t, X):
            x, v, z, u = X.tolist()
            xe = vxe = 0.0
            for w, br, bi in terms:
                sn, cs = sin(w * t), cos(w * t)
                xe += br * sn + bi * cs
                vxe += w * (br * cs - bi * sn)
            flo = c1 * (vxe - v) + k1 * (xe - x)
            fb = 0.0
            if fric:
                fr = fric * tanh(u / vs)
                flo += fr
                fb -= fr
            if wall is not None:
                s = wall.side
                d, dd = s * z - b, s * u
                if wall.kv:
                    F = wall.k * d + wall.c * dd
                else:
                    F = wall.k * max(d, 0.0) ** wall.n * (1.0 + wall.a15 * dd)
                flo += s * F
                fb -= s * F
            a = flo / m1
            return [v, a, u, fb / m2 + gs - a]
        return f

    def flow(self):
        """Scalar right-hand side of the whole clipped model (both walls, friction).

        The fast engine's ``odeint`` integrates this: beyond a contact's exit the
        clipped force is zero, so integrating past the exit is the true flow.
        """
        p, terms, gs, fric, vs, b = self.p, self._terms, self.gs, self.fric, self.vs, self.b
        m1, m2, c1, k1 = p.m1, p.m2, p.c1, p.k1
        tanh, sin, cos = math.tanh, math.sin, math.cos

        def force(w, d, dd):
            F = w.k * d + w.c * dd if w.kv else w.k * d ** w.n * (1.0 + w.a15 * dd)
            return F if F > 0.0 else 0.0
        right, left = self.walls[RIGHT], self.walls[LEFT]

        def f(t, X):
            x, v, z, u = X.tolist()
            xe = vxe = 0.0
            for w, br, bi in terms:
                sn, cs = sin(w * t), cos(w * t)
                xe += br * sn + bi * cs
                vxe += w * (br * cs - bi * sn)
            fc = 0.0
            if z > b:
                fc = force(right, z - b, u)
            elif z < -b:
                fc = -force(left, -z - b, -u)
            if fric:
                fc += fric * tanh(u / vs)
            a = (c1 * (vxe - v) + k1 * (xe - x) + fc) / m1
            return (v, a, u, gs - fc / m2 - a)
        return f

    def deriv(self, t: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """Vectorised :meth:`flow`: derivatives (N, 4) of states ``Y`` (N, 4) at ``t`` (N,)."""
        x, v, z, u = Y.T
        fc = self._reactions(z, u)
        a = (self._spring(t, x, v) + fc) / self.p.m1
        return np.column_stack([v, a, u, self.gs - fc / self.p.m2 - a])

    def _spring(self, t, x, v):
        """Spring and damper force on the LO (N), vectorised."""
        p = self.p
        xe = np.zeros_like(t)
        vxe = np.zeros_like(t)
        for w, br, bi in self._terms:
            sn, cs = np.sin(w * t), np.cos(w * t)
            xe += br * sn + bi * cs
            vxe += w * (br * cs - bi * sn)
        return p.c1 * (vxe - v) + p.k1 * (xe - x)

    def _reactions(self, z, u):
        """Contact and friction forces on the LO (N; minus those on the ball), vectorised."""
        f = np.zeros_like(z)
        for s, wall in self.walls.items():
            f += s * wall.force(s * z - self.b, s * u)
        if self.fric:
            f += self.fric * np.tanh(u / self.vs)
        return f

    def accel(self, t, x, v, z, u):
        """Full LO acceleration (contact and friction reactions included), vectorised."""
        return (self._spring(t, x, v) + self._reactions(z, u)) / self.p.m1


def _deflated(f, t0: float):
    """``f(t) / (t - t0)`` with its derivative, for ``f(t0) = 0`` (a root after ``t0``).

    At ``t0`` it is the limit ``f'(t0)``: a function leaving zero at ``t0`` and
    coming back to it keeps one sign change, the return.
    """
    def g(t):
        v, d = f(t)
        tau = t - t0
        if tau <= 0.0:
            return d, 0.0
        q = v / tau
        return q, (d - q) / tau
    return g


def _hermite(t, ta, hh, ya, yb, da, db):
    """Cubic Hermite interpolant on ``[ta, ta + hh]`` (arrays broadcast along the last axis)."""
    q = (t - ta) / hh
    q2 = q * q
    q3 = q2 * q
    return ((2 * q3 - 3 * q2 + 1) * ya + (q3 - 2 * q2 + q) * hh * da
            + (3 * q2 - 2 * q3) * yb + (q3 - q2) * hh * db)


class _Grid:
    """Dense output of an ``odeint`` segment: states on a grid, cubic Hermite interpolation.

    The derivatives at the grid points come from ``deriv`` (the model's vectorised
    flow) when the segment is first evaluated.
    """

    def __init__(self, t: np.ndarray, Y: np.ndarray, deriv) -> None:
        self.t, self.Y, self.deriv, self.dY = t, Y, deriv, None

    def __call__(self, tq) -> np.ndarray:
        """States (4, N) at times ``tq`` (N,) inside the grid."""
        tq = np.atleast_1d(np.asarray(tq, dtype=float))
        t = self.t
        if t.size == 1:
            return np.repeat(self.Y[:1].T, tq.size, axis=1)
        if self.dY is None:
            self.dY = self.deriv(t, self.Y)
        i = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, t.size - 2)
        ta, hh = t[i][:, None], (t[i + 1] - t[i])[:, None]
        return _hermite(tq[:, None], ta, hh, self.Y[i], self.Y[i + 1], self.dY[i],
                        self.dY[i + 1]).T


class _Event:
    """A terminal solve_ivp event."""

    terminal = True

    def __init__(self, fun, direction: float) -> None:
        self.fun, self.direction = fun, direction

    def __call__(self, t, X):
        return self.fun(t, X)


class _CompliantLoop(_Loop):
    """Event loop of the compliant engine (flights of the exact engine reused when mu = 0)."""

    def __init__(self, cm: _CModel, numeric: bool, rtol: float, atol: float,
                 steps: tuple[float, float] = (16.0, 1.0)) -> None:
        super().__init__(cm.exact)
        self.cm = cm
        # bounds of solve_ivp steps: contact duration / steps[0], flight grid * steps[1]
        self.steps = steps
        self.numeric = numeric
        self.flow = cm.flow()
        self.friction = cm.fric > 0.0
        # grid step of the fast engine in the friction band: 1/20 of the time scale
        # of the viscous law there, mu g (1 + m2 / m1) / v_s
        rate = cm.fric * (1.0 / cm.p.m2 + 1.0 / cm.p.m1) / cm.vs if self.friction else 0.0
        self.band_step = min(0.5 * self.m.h, 0.05 / rate) if rate else 0.5 * self.m.h
        self.rtol = rtol
        w0 = math.sqrt(cm.p.k1 / cm.p.m1)
        self.atol = np.array([atol, atol * w0, atol, atol * w0])
        self.kvsegs: list[tuple] = []            # (t0, t1, side, c0..c3)
        self.numsegs: list = []                  # OdeSolution per numeric segment
        self.index: list[tuple] = []             # (t0, t1, kind, i)

    # ---------------------------------------------------------------- bookkeeping
    def _seg(self, kind: int, t0: float, t1: float, i: int) -> None:
        self.index.append((t0, t1, kind, i))

    def _count(self, t: float) -> bool:
        if self.n_events >= self.max_events:
            self.status = 1
            self.message = f"stopped after {self.n_events} events (max_events) at t = {t:.6g} s"
            return False
        self.n_events += 1
        return True

    # ---------------------------------------------------------------- loop
    def run(self) -> CompliantResult:
        cm, opt = self.cm, self.cm.opt
        x, v, y, w = initial_state(opt, cm.b)
        self.status, self.message = 0, "reached the end of the record"
        t, X = 0.0, np.array([x, v, y - x, w - v])
        start_wall = 0
        while t < self.t_end and self._count(t):
            # ---- flight from inside the clearance
            t, X, side = self._flight_phase(t, X, start_wall)
            if side == 0:
                break
            entry = (t, X.copy())
            # ---- contact episode: contact phases, and flights beyond the wall
            while True:
                if not self._count(t):
                    side = 0
                    break
                t, X, inside = self._contact_phase(t, X, side)
                if inside is None:       # end of the simulated span inside a contact
                    side = 0
                    break
                t_out, X_out = t, X.copy()
                if inside:
                    break
                if not self._count(t):
                    side = 0
                    break
                t, X, back = self._beyond_phase(t, X, side)
                if back is None:
                    side = 0
                    break
                if back:                 # the ball is inside the clearance again
                    break
            if side == 0:
                break
            ti, Xi = entry
            u_in, u_out = Xi[3], X_out[3]
            self.impacts.append((ti, side, u_in, u_out, -u_out / u_in, Xi[1], X_out[1],
                                 Xi[1] + u_in, X_out[1] + u_out, Xi[0], False, t_out))
            X[2] = side * cm.b
            start_wall = side
        return CompliantResult.from_compliant(self)

    # ---------------------------------------------------------------- flights
    @staticmethod
    def _flight_functions(osc, t0, C1, C2, F0, y0, w0, ab, b):
        """LO state and event functions of a flight: z and its derivatives, closed form.

        The same arithmetic as ``Oscillator.state`` (term by term, in the same
        order, so the values are bit-identical), inlined with the per-flight
        constants hoisted. The exact engine's loop has the compiled twin of these
        (``_flight_kernel``); the compliant engine's flights with friction and its
        contacts need them as Python callables (:func:`.roots.bracketed_newton`).
        """
        exp, sin, cos = math.exp, math.sin, math.cos
        sg, wd, km = osc.sigma, osc.wd, osc.k / osc.m
        nsg, m2sg = -sg, -2.0 * sg
        cv1, cv2 = C2 * wd - sg * C1, C1 * wd + sg * C2
        xs = F0 / osc.k
        hab = 0.5 * ab
        terms = [(w, w * w, pa, pb) for w, pa, pb in osc._terms]

        def lo_xv(t):
            x, v = xs, 0.0
            for w, _, pa, pb in terms:
                sn, cs = sin(w * t), cos(w * t)
                x += pa * sn + pb * cs
                v += w * (pa * cs - pb * sn)
            tau = t - t0
            e = exp(nsg * tau)
            cs, sn = cos(wd * tau), sin(wd * tau)
            return tau, x + e * (C1 * cs + C2 * sn), v + e * (cv1 * cs - cv2 * sn)

        def zf(t):
            x, v, a = xs, 0.0, 0.0
            for w, ww, pa, pb in terms:
                sn, cs = sin(w * t), cos(w * t)
                x += pa * sn + pb * cs
                v += w * (pa * cs - pb * sn)
                a -= ww * (pa * sn + pb * cs)
            tau = t - t0
            e = exp(nsg * tau)
            cs, sn = cos(wd * tau), sin(wd * tau)
            xh = e * (C1 * cs + C2 * sn)
            vh = e * (cv1 * cs - cv2 * sn)
            ah = m2sg * vh - km * xh
            return (y0 + w0 * tau + hab * tau * tau - (x + xh), w0 + ab * tau - (v + vh),
                    ab - (a + ah))

        def f_right(t):
            tau, x, v = lo_xv(t)
            return y0 + w0 * tau + hab * tau * tau - x - b, w0 + ab * tau - v

        def f_left(t):
            tau, x, v = lo_xv(t)
            return y0 + w0 * tau + hab * tau * tau - x + b, w0 + ab * tau - v

        def f_zero(t):
            _, zd, zdd = zf(t)
            return zd, zdd

        return lo_xv, zf, f_right, f_left, f_zero

    def _flight_phase(self, t, X, start_wall):
        """Flight inside the clearance up to a wall (side) or the end (0)."""
        if self.numeric:
            return self._ivp_flight(t, X, start_wall, beyond=0)[:3]
        if self.friction:
            return self._friction_flight(t, X, start_wall)
        x, v, z, u = X.tolist()
        n0 = len(self.segs)
        te, x, v, y, w, kind = self._flight(t, x, v, x + z, v + u, 1 if u > 0 else -1,
                                            start_wall)
        for i in range(n0, len(self.segs)):
            self._seg(FLIGHT, self.segs[i][0], self.segs[i][1], i)
        side = 0 if kind == "end" else kind
        return te, np.array([x, v, y - x, w - v]), side

    def _friction_flight(self, t, X, start_wall):
        """Flight with regularised friction, up to a wall (side) or the end (0).

        Closed form while ``|z'| >= BAND v_s`` (there ``tanh(z'/v_s)`` is +/-1 in
        double precision and z is monotone), ``solve_ivp`` inside the band.
        """
        cm = self.cm
        vb = BAND * cm.vs
        while t < self.t_end:
            if not self._count(t):
                return t, X, 0
            if abs(X[3]) < vb or (abs(X[3]) == vb and not self._leaving_band(t, X)):
                t, X, k = self._ivp(t, X, 0, self._band_events(t, start_wall, vb),
                                    max_step=self.m.h * self.steps[1], h=self.band_step,
                                    span=64 * self.band_step)
                if k in (0, 1):
                    side = RIGHT if k == 0 else LEFT
                    X[2] = side * cm.b
                    return t, X, side
                if k < 0:
                    return t, X, 0
                X[3] = vb if k == 2 else -vb
                start_wall = 0
                continue
            t, X, side = self._sign_flight(t, X, start_wall, vb)
            if side != 0 or t >= self.t_end:
                return t, X, side
            start_wall = 0
        return t, X, 0

    def _leaving_band(self, t, X, active: int = 0) -> bool:
        """Whether ``|z'|`` grows at ``|z'| = BAND v_s`` (leaving the band)."""
        s = 1.0 if X[3] > 0 else -1.0
        return s * self.cm.rhs(active)(t, X)[3] > 0.0

    def _wall_events(self, t0, start_wall):
        """Entry events of the two walls for a flight started at ``t0``.

        The wall the flight starts on has ``z = +/-b`` at ``t0``: its event function is
        divided by ``t - t0`` (with its sign just after ``t0`` at ``t0``), so that a
        quick return to that wall inside the first step is a sign change, not a root
        at the start.
        """
        b = self.cm.b
        out = []
        for side in (RIGHT, LEFT):
            if side == start_wall:
                def ev(t, X, side=side):
                    tau = np.asarray(t - t0)
                    pos = tau > 0.0
                    return np.where(pos, (X[2] - side * b) / np.where(pos, tau, 1.0),
                                    -float(side))
            else:
                def ev(t, X, side=side):
                    return X[2] - side * b
            out.append(_Event(ev, float(side)))
        return out

    def _band_events(self, t0, start_wall, vb):
        return self._wall_events(t0, start_wall) + [
            _Event(lambda t, X: X[3] - vb, 1.0), _Event(lambda t, X: X[3] + vb, -1.0)]

    def _sign_flight(self, t0, X, start_wall, vb):
        """Closed-form flight with saturated friction up to a wall or ``|z'| = vb``."""
        cm, m = self.cm, self.m
        osc, b = cm.free, cm.b
        x0, v0, z0, u0 = X.tolist()
        s = 1 if u0 > 0 else -1
        F0 = cm.fric * s
        ab = cm.gs - m.mug * s
        y0, w0 = x0 + z0, v0 + u0
        C1, C2 = osc.coefficients(t0, x0, v0, F0)
        lo_xv, zf, f_right, f_left, f_zero = self._flight_functions(osc, t0, C1, C2, F0, y0,
                                                                    w0, ab, b)

        def f_band(tt):
            _, zd, zdd = zf(tt)
            return s * zd - vb, s * zdd
        n, h, B01 = 64, m.h, m.free_basis
        ta, te, kind = t0, self.t_end, 0
        while ta < self.t_end and kind == 0:
            cz = [-c for c in osc.window_coeffs(ta, t0, C1, C2, F0)]
            tau = ta - t0
            cz[0] += y0 + w0 * tau + 0.5 * ab * tau * tau
            cz[1] += w0 + ab * tau
            cz[2] += 0.5 * ab
            zz = (B01 @ cz).tolist()
            z, zd = zz[:n + 1], zz[n + 1:]
            for k in range(n):
                p, q = ta + k * h, ta + (k + 1) * h
                if s * z[k + 1] >= b and s * z[k] < b and not (k == 0 and ta == t0
                                                                and start_wall == s):
                    f = f_right if s > 0 else f_left
                    te, kind = bracketed_newton(f, p, q, z[k] - s * b, z[k + 1] - s * b), s
                    break
                if s * zd[k + 1] <= vb:
                    if k == 0 and ta == t0 and s * u0 <= vb:
                        # started on the band's edge, leaving it: a return within the
                        # first step is a root after t0, not the start itself
                        fd = _deflated(f_band, t0)
                        te = bracketed_newton(fd, p, q, fd(p)[0], fd(q)[0])
                    else:
                        te = bracketed_newton(f_band, p, q, s * zd[k] - vb,
                                              s * zd[k + 1] - vb)
                    kind = 2
                    break
            ta += n * h
        te = min(te, self.t_end)
        _, x, v = lo_xv(te)
        tau = te - t0
        y, w = y0 + w0 * tau + 0.5 * ab * tau * tau, w0 + ab * tau
        self.segs.append((t0, te, 0, C1, C2, F0, y0, w0, ab, 0.0))
        self._seg(FLIGHT, t0, te, len(self.segs) - 1)
        Xe = np.array([x, v, y - x, w - v])
        if kind == 2:
            Xe[3] = s * vb
            return te, Xe, 0
        if kind != 0:
            Xe[2] = kind * b
            return te, Xe, kind
        return te, Xe, 0

    def _beyond_phase(self, t, X, side):
        """Flight with the ball beyond wall ``side`` and no force.

        Returns (t, X, back): back True when the ball is inside the clearance again,
        False when the force comes back (same episode), None at the end of the span.
        """
        if self.numeric or self.friction:
            t, X, ev = self._ivp_flight(t, X, 0, beyond=side)
            return t, X, (None if ev == 0 else ev == 1)
        cm, wall = self.cm, self.cm.walls[side]
        osc = cm.free
        x, v, z, u = X.tolist()
        C1, C2 = osc.coefficients(t, x, v, 0.0)
        y0, w0 = x + z, v + u
        _, zf, _, _, _ = self._flight_functions(osc, t, C1, C2, 0.0, y0, w0, cm.gs, cm.b)
        b, s = cm.b, side

        def g_delta(tt):
            zz, zd, _ = zf(tt)
            return s * zz - b, s * zd

        def g_force(tt):
            zz, zd, zdd = zf(tt)
            if wall.kv:
                return wall.k * (s * zz - b) + wall.c * s * zd, wall.k * s * zd + wall.c * s * zdd
            return 1.0 + wall.a15 * s * zd, wall.a15 * s * zdd

        d0, dd0 = g_delta(t)
        # steps of 1/16 of the time to get back inside, growing, at most the flight grid
        h = min(max(d0 / -dd0 / 16.0, 1e-12) if dd0 < 0 else 1e-6, self.m.h)
        ta, fa, ga = t, d0, min(g_force(t)[0], 0.0)   # the force has just vanished
        kind = None
        while ta < self.t_end:
            tb = min(ta + h, self.t_end)
            fb, gb = g_delta(tb)[0], g_force(tb)[0]
            found = []
            if fb <= 0.0:
                found.append((bracketed_newton(g_delta, ta, tb, fa, fb), True))
            if gb > 0.0 >= ga:
                tf = bracketed_newton(g_force, ta, tb, ga, gb)
                if g_delta(tf)[0] > 0.0:
                    found.append((tf, False))
            if found:
                te, kind = min(found)
                break
            ta, fa, ga = tb, fb, gb
            h = min(1.5 * h, self.m.h)
        te = ta if kind is None else te
        xx, vv, _ = osc.state(te, t, C1, C2, 0.0)
        tau = te - t
        yy, ww = y0 + w0 * tau + 0.5 * cm.gs * tau * tau, w0 + cm.gs * tau
        self.segs.append((t, te, 0, C1, C2, 0.0, y0, w0, cm.gs, 0.0))
        self._seg(FLIGHT, t, te, len(self.segs) - 1)
        Xe = np.array([xx, vv, yy - xx, ww - vv])
        if kind is True:
            Xe[2] = s * b
        return te, Xe, kind

    # ---------------------------------------------------------------- contacts
    def _contact_phase(self, t, X, side):
        """The wall pushes until its force is zero.

        Returns (t, X, inside): inside True when the penetration is zero there, False
        when the ball is still beyond the wall, None at the end of the span.
        """
        if self.cm.walls[side].kv and not self.numeric:
            return self._kv_contact(t, X, side)
        return self._ivp_contact(t, X, side)

    def _kv_contact(self, t0, X0, side):
        """Kelvin-Voigt contact: closed form, friction saturated; solve_ivp inside the band."""
        vb = BAND * self.cm.vs
        t, X = t0, X0
        while True:
            if self.friction and (abs(X[3]) < vb or (abs(X[3]) == vb
                                                     and not self._leaving_band(t, X, side))):
                t, X, k = self._ivp_contact(t, X, side, band=vb)
                if k != 2:
                    return t, X, k
                continue
            fs = (1 if X[3] > 0 else -1) if self.friction else 0
            t, X, inside = self._kv_closed(t, X, side, fs, vb)
            if inside != 2:
                return t, X, inside
            if not self._count(t):
                return t, X, None

    def _kv_closed(self, t0, X0, side, fs, vb):
        """Closed-form KV contact up to the force's zero (or, with friction, the band)."""
        key = (side, fs)
        sysm = self.cm.kv[key]
        c = sysm.coeffs(t0, X0)
        n = 64
        h = sysm.h
        ta = t0
        t_end = self.t_end
        grid = np.arange(n + 1, dtype=float)
        te, kind = None, None
        while ta < t_end:
            tt = ta + h * grid
            X, dX = sysm.state(tt, t0, c)
            g, _ = sysm.gate(X, dX)
            if ta == t0:
                g[0] = max(g[0], 0.0)
            ev = g[1:] <= 0.0
            if fs:
                ev |= fs * X[1:, 3] <= vb
            hit = np.flatnonzero(ev)
            if hit.size:
                k = int(hit[0])
                if g[k + 1] <= 0.0:
                    def fg(s):
                        Xs, dXs = sysm.state(np.array([s]), t0, c)
                        gg, dg = sysm.gate(Xs, dXs)
                        return float(gg[0]), float(dg[0])
                    te, kind = bracketed_newton(fg, tt[k], tt[k + 1], float(g[k]),
                                                float(g[k + 1])), 0
                if fs and fs * X[k + 1, 3] <= vb:
                    def fb(s):
                        Xs, dXs = sysm.state(np.array([s]), t0, c)
                        return fs * float(Xs[0, 3]) - vb, fs * float(dXs[0, 3])
                    if k == 0 and ta == t0 and fs * X[0, 3] <= vb:   # on the band's edge
                        fd = _deflated(fb, t0)
                        tb = bracketed_newton(fd, tt[0], tt[1], fd(tt[0])[0], fd(tt[1])[0])
                    else:
                        tb = bracketed_newton(fb, tt[k], tt[k + 1], fs * X[k, 3] - vb,
                                              fs * X[k + 1, 3] - vb)
                    if te is None or tb < te:
                        te, kind = tb, 2
                break
            ta = tt[-1]
            if ta - t0 > 30.0 / sysm.sigma:      # the contact mode has died out
                h = max(h, self.m.h)
        inside = None
        if te is None or te >= t_end:
            te = t_end
        Xe = sysm.state(np.array([te]), t0, c)[0][0]
        if te < t_end:
            inside = 2 if kind == 2 else bool(side * Xe[2] - self.cm.b <= 0.0)
        self.kvsegs.append((t0, te, self.cm.kv_ids[key], *c))
        self._seg(KV, t0, te, len(self.kvsegs) - 1)
        if inside is True:
            Xe[2] = side * self.cm.b
        if inside == 2:
            Xe[3] = fs * vb
        return te, Xe, inside

    def _ivp(self, t0, X0, active, events, max_step, h: float, n: int = 32,
             span: float = 0.0):
        """Integrate from ``t0`` up to the first event (index k) or the end (k = -1).

        The reference integrates with ``solve_ivp`` (``max_step``); the fast engine with
        :meth:`_ode` (grid step ``h`` over ``span``, first window ``n`` steps).
        """
        if t0 >= self.t_end:
            return t0, np.asarray(X0, dtype=float).copy(), -1
        if not self.numeric:
            return self._ode(t0, X0, events, h, n, span)
        sol = solve_ivp(self.cm.rhs(active), (t0, self.t_end), X0, method="DOP853",
                        rtol=self.rtol, atol=self.atol, events=events, max_step=max_step,
                        first_step=min(max_step / 4, self.t_end - t0), dense_output=True)
        hit = [k for k, te in enumerate(sol.t_events) if te.size]
        self.numsegs.append(sol.sol)
        if not hit:
            te, Xe, k = float(sol.t[-1]), sol.y[:, -1].copy(), -1
        else:
            k = min(hit, key=lambda j: sol.t_events[j][0])
            te, Xe = float(sol.t_events[k][0]), sol.y_events[k][0].copy()
        self._seg(NUM, t0, te, len(self.numsegs) - 1)
        return te, Xe, k

    def _ode(self, t0, X0, events, h, n, span):
        """LSODA (``odeint``) of the clipped flow on windows of a grid, up to an event.

        Events are located on the grid (a sign change in their direction), refined on
        the cubic Hermite interpolant of the grid's states and derivatives, and the
        state there is integrated from the last grid point. Windows without an event
        are kept; the first has ``n`` steps of ``h``, each next one twice as many (at
        most 512), and beyond ``t0 + span`` steps twice as long (at most half the
        flight grid's). The grids are the dense output.
        """
        cm, t_end = self.cm, self.t_end
        hmax = max(h, 0.5 * self.m.h)
        t, X = t0, np.asarray(X0, dtype=float)
        ts, Ys = [np.array([t0])], [X[None]]
        flow = self.flow
        te, Xe, k = t_end, None, -1
        while t < t_end:
            grid = t + h * np.arange(n + 1)
            if grid[-1] >= t_end:
                grid = np.append(grid[grid < t_end], t_end)
            Y = self._odeint(X, grid)
            g = [(ev.fun(grid, Y.T), ev.direction) for ev in events]
            first = None
            for j, (gj, d) in enumerate(g):
                ga, gb = gj[:-1], gj[1:]
                cross = ((ga < 0) & (gb >= 0) if d > 0 else (ga > 0) & (gb <= 0)
                         if d < 0 else (ga * gb <= 0) & (ga != 0))
                hit = np.flatnonzero(cross)
                if hit.size and (first is None or hit[0] <= first[0]):
                    i = int(hit[0])
                    ta, hh = grid[i], grid[i + 1] - grid[i]

                    ends = (Y[i], Y[i + 1], np.array(flow(ta, Y[i])),
                            np.array(flow(grid[i + 1], Y[i + 1])))

                    def fz(tt, ev=events[j], ta=ta, hh=hh, ends=ends):
                        return float(ev.fun(tt, _hermite(tt, ta, hh, *ends)))
                    tr = brentq(fz, ta, grid[i + 1], xtol=1e-15, rtol=1e-15)
                    if first is None or i < first[0] or tr < first[1]:
                        first = (i, tr, j)
            if first is not None:
                i, te, k = first
                Xe = self._odeint(Y[i], np.array([grid[i], te]))[-1] if te > grid[i] else Y[i]
                ts += [grid[1:i + 1], [te]]
                Ys += [Y[1:i + 1], Xe[None]]
                break
            ts.append(grid[1:])
            Ys.append(Y[1:])
            t, X = float(grid[-1]), Y[-1]
            n = min(2 * n, 512)
            if t - t0 > span:
                h = min(2.0 * h, hmax)
        if Xe is None:
            te, Xe = t, X
        self.numsegs.append(_Grid(np.concatenate(ts), np.concatenate(Ys), cm.deriv))
        self._seg(NUM, t0, te, len(self.numsegs) - 1)
        return te, np.array(Xe, dtype=float), k

    def _odeint(self, X0, grid):
        Y, info = odeint(self.flow, X0, grid, tfirst=True, rtol=self.rtol, atol=self.atol,
                         full_output=True, mxstep=100000, h0=0.25 * (grid[1] - grid[0]))
        if info["message"] != "Integration successful.":
            raise SimulationError(f"compliant engine: odeint failed at t = {grid[0]:.9g} s: "
                                  f"{info['message']}")
        return Y

    def _ivp_contact(self, t0, X0, side, band: float | None = None):
        """Integrated contact up to the force's zero (see :meth:`_contact_phase`).

        With ``band``, also up to ``|z'| = band`` outward (then inside = 2).
        """
        cm, wall, b = self.cm, self.cm.walls[side], self.cm.b
        s = side

        def ev_gate(t, X):
            return wall.gate(s * X[2] - b, s * X[3])

        def ev_delta(t, X):
            return s * X[2] - b
        events = [_Event(ev_gate, -1.0), _Event(ev_delta, -1.0)]
        if band is not None:
            events += [_Event(lambda t, X: X[3] - band, 1.0),
                       _Event(lambda t, X: X[3] + band, -1.0)]
        dur = wall.duration(abs(X0[3]), cm.m_eff)
        te, Xe, k = self._ivp(t0, X0, side, events,
                              max_step=min(dur / self.steps[0], self.m.h),
                              h=min(dur / 256.0, 0.5 * self.m.h),
                              n=8 if band is not None else 384, span=2.0 * dur)
        if k < 0:
            return te, Xe, None
        if k >= 2:
            Xe[3] = band if k == 2 else -band
            return te, Xe, 2
        inside = bool(k == 1 or s * Xe[2] - b <= 0.0)
        if inside:
            Xe[2] = s * b
        return te, Xe, inside

    def _ivp_flight(self, t0, X0, start_wall, beyond):
        """Numerical flight (friction, reference path).

        Returns (t, X, side hit or 0 at the end) inside the clearance, or with
        ``beyond`` (ball beyond that wall): (t, X, 1 back inside / 2 force back / 0 end).
        """
        cm, b = self.cm, self.cm.b
        if beyond:
            s, wall = beyond, cm.walls[beyond]

            def ev_in(t, X):
                return s * X[2] - b

            def ev_force(t, X):
                d = s * X[2] - b
                return np.where(d > 0, wall.gate(d, s * X[3]), -1.0)
            # steps of at most the time to get back inside (a few microseconds): the
            # ball may come out and go back beyond the wall within one flight step
            d0, dd0 = s * X0[2] - b, s * X0[3]
            reach = d0 / -dd0 if dd0 < 0 else self.m.h
            te, Xe, k = self._ivp(t0, X0, 0, [_Event(ev_in, -1.0), _Event(ev_force, 1.0)],
                                  max_step=min(self.m.h * self.steps[1], max(reach, 1e-9)),
                                  h=min(0.5 * self.m.h, max(reach, 1e-9) / 8.0), n=64)
            if k == 0:
                Xe[2] = s * b
            return te, Xe, k + 1
        te, Xe, k = self._ivp(t0, X0, 0, self._wall_events(t0, start_wall),
                              max_step=self.m.h * self.steps[1], h=0.5 * self.m.h)
        if k < 0:
            return te, Xe, 0
        side = RIGHT if k == 0 else LEFT
        Xe[2] = side * b
        return te, Xe, side


@dataclasses.dataclass(frozen=True)
class CompliantResult(SimulationResult):
    """Result of the compliant engine: a :class:`SimulationResult` with contacts.

    Contacts last a finite time; ``impulsive`` is False: ``evaluate()["xdd"]`` is the
    full, continuous LO acceleration including the contact forces. ``sticking`` is
    empty (a ball resting on a wall is one long contact episode).
    """

    @classmethod
    def from_compliant(cls, loop: _CompliantLoop) -> CompliantResult:
        """Assemble from the compliant loop."""
        cm = loop.cm
        idx = np.array(loop.index, dtype=float).reshape(-1, 4)
        fl = np.array(loop.segs, dtype=float).reshape(-1, 10)
        kv = np.array(loop.kvsegs, dtype=complex).reshape(-1, 7)
        seg = {"t0": idx[:, 0], "t1": idx[:, 1], "kind": idx[:, 2].astype(int),
               "i": idx[:, 3].astype(int), "flight": fl, "kv_t0": kv[:, 0].real,
               "kv_id": kv[:, 2].real.astype(int), "kv_c": kv[:, 3:], "num": loop.numsegs}
        return cls(cm.p, cm.fx, cm.b, cm.opt.settle, cm.opt.duration,
                   ImpactTable.from_rows(loop.impacts), [], loop.status, loop.message,
                   loop.n_events, seg, cm, cm.contact)

    def _evaluate(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """State at times ``t`` (simulation clock), accurate inside contacts too.

        Returns
        -------
        dict
            ``x``, ``xd``, ``xdd`` (LO; ``xdd`` includes the contact forces and the
            friction reaction), ``y``, ``yd`` (ball), ``z`` = y - x, ``xe`` (base).
        """
        seg, cm = self._segments, self._model
        k = np.clip(np.searchsorted(seg["t0"], t, side="right") - 1, 0, seg["t0"].size - 1)
        kind, sub = seg["kind"][k], seg["i"][k]
        X = np.empty((t.size, 4))
        sel = kind == FLIGHT
        if sel.any():
            f = seg["flight"][sub[sel]]
            ts = t[sel]
            x, v, _ = cm.free.state_array(ts, f[:, 0], f[:, 3], f[:, 4], f[:, 5])
            tau = ts - f[:, 0]
            y = f[:, 6] + f[:, 7] * tau + 0.5 * f[:, 8] * tau ** 2
            X[sel] = np.column_stack([x, v, y - x, f[:, 7] + f[:, 8] * tau - v])
        kv_id = np.full(t.size, -1)
        is_kv = kind == KV
        kv_id[is_kv] = seg["kv_id"][sub[is_kv]]
        for key, sysm in cm.kv.items():
            sel = kv_id == cm.kv_ids[key]
            if sel.any():
                j = sub[sel]
                X[sel] = sysm.state(t[sel], seg["kv_t0"][j], seg["kv_c"][j])[0]
        sel = kind == NUM
        if sel.any():
            pos = np.flatnonzero(sel)
            j = sub[pos]
            order = np.argsort(j, kind="stable")
            pos, j = pos[order], j[order]
            cuts = np.flatnonzero(np.diff(j)) + 1
            for p, jj in zip(np.split(pos, cuts), j[np.r_[0, cuts]], strict=True):
                X[p] = seg["num"][int(jj)](t[p]).T
        x, v, z, u = X.T
        return {"x": x, "xd": v, "xdd": cm.accel(t, x, v, z, u), "y": x + z, "yd": v + u,
                "z": z, "xe": cm.base.displacement(t)}


def _prepare(params, effects, contact, options, option_kw) -> _CModel:
    effects = effects if effects is not None else Effects()
    return _CModel(params, effects, as_contact_model(contact), merge_options(options, option_kw))


def simulate_compliant(params: SystemParams, effects: Effects | None = None,
                       options: SimOptions | None = None, contact=None,
                       **option_kw) -> CompliantResult:
    """Simulate with compliant walls (use :func:`vidiscover.simulate` with ``contact=``).

    Parameters
    ----------
    params, effects, options
        As :func:`vidiscover.simulation.simulate`; effects that set the restitution
        or the impact duration are refused (the contact law sets them).
    contact : ContactModel, str or list of str
        The walls (see :mod:`vidiscover.simulation.contact`).

    Returns
    -------
    CompliantResult

    Examples
    --------
    >>> from vidiscover import preset
    >>> res = simulate_compliant(preset("paper", b=0.009), contact="kv:k=3e7,r=0.7",
    ...                          settle=0.0, duration=1.0)
    >>> res.status, res.impulsive, bool((res.impacts.t_out > res.impacts.t).all())
    (0, False, True)
    """
    cm = _prepare(params, effects, contact, options, option_kw)
    return _CompliantLoop(cm, numeric=False, rtol=cm.opt.contact_rtol, atol=1e-12,
                          steps=(4.0, 2.0)).run()


def simulate_reference(params: SystemParams, effects: Effects | None = None, contact=None,
                       options: SimOptions | None = None, *, rtol: float = 1e-10,
                       atol: float = 1e-12, **option_kw) -> CompliantResult:
    """Slow fully numerical compliant simulation (the test and benchmark reference).

    Flights and contacts alike are integrated by ``solve_ivp`` (DOP853, ``rtol``,
    ``atol`` in metres, scaled by the LO angular frequency for velocities), with
    terminal events at wall entry (``|z| = b``), contact exit (force = 0) and, beyond
    a wall, return inside or return of the force; the step is bounded by 1/64 of the
    shortest period of the system (1/16 of a contact's duration in contacts).

    Returns
    -------
    CompliantResult
    """
    cm = _prepare(params, effects, contact, options, option_kw)
    return _CompliantLoop(cm, numeric=True, rtol=rtol, atol=atol).run()
