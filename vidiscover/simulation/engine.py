"""Exact event-driven simulation of the LO + ball system.

Between events every flow is closed-form (see :mod:`.flows`): the LO is a linear
oscillator under harmonic base forcing plus a constant force, the ball has constant
acceleration. Events are found on a grid of at most ``1/grid_per_period`` of the
shortest period, by sign changes of the event functions and of z' (so that a
crossing hidden between two grid points, near grazing, is found via the extremum of
z), then refined by a bracketed Newton iteration:

* ``z = +b`` (right wall) and ``z = -b`` (left wall): an impact, Newton's law with
  momentum conservation and the wall's restitution law;
* ``z' = 0`` with friction: the ball sticks to the LO if static friction holds, or
  slides the other way;
* release of a stuck ball: the friction needed to keep it with the LO exceeds
  ``mu m2 g`` (or the wall no longer pushes it).

A rebound slower than ``stick_speed`` sticks the ball to the wall (no Zeno chatter)
and the number of events is bounded, so the loop always terminates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..effects import Effects
from ..errors import InputError
from ..params import G_ACCEL, SystemParams
from .flows import BaseMotion, Oscillator
from .result import SimulationResult

__all__ = ["simulate", "SimOptions"]

FLIGHT, STUCK = 0, 1
_WINDOW = 64  # event-grid intervals evaluated per vectorised window
RIGHT, LEFT, MIDDLE = 1, -1, 0
#: the kernel's event kinds (_flight_kernel: RIGHT, LEFT, ZERO, END) as the loop names them
_KINDS = {1: RIGHT, -1: LEFT, 2: "zero", 3: "end"}


@dataclass(frozen=True)
class SimOptions:
    """Numerical and initial-condition options of :func:`simulate`.

    Parameters
    ----------
    settle : float
        Time simulated before the record starts (s); long enough to reach the
        steady state (default 20 s, 160 forcing periods at 8 Hz).
    duration : float
        Length of the record after the settle (s).
    initial : tuple of 4 floats or None
        (x, x', y, y') at t = 0. Default: LO at rest, ball at the centre with
        velocity ``ball_speed`` (so that impacting branches are found at large b).
    ball_speed : float
        Initial ball speed (m/s) when ``initial`` is None.
    stick_speed : float
        A rebound with relative speed below this (m/s) sticks the ball to the wall.
    grid_per_period : int
        Event-search grid points per shortest period of the system.
    max_events : int or None
        Bound on the number of events (default: 400 per forcing period).
    friction_speed : float
        Compliant engine only: the regularisation speed v_s of dry friction,
        ``mu m2 g tanh(z'/v_s)`` (m/s, default 1 mm/s).
    contact_rtol : float
        Compliant engine only: ``solve_ivp`` relative tolerance of the contacts and
        flights it integrates numerically (Hunt-Crossley walls, friction).
    """

    settle: float = 20.0
    duration: float = 5.12
    initial: tuple | None = None
    ball_speed: float = 0.6
    stick_speed: float = 1e-4
    grid_per_period: int = 64
    max_events: int | None = None
    friction_speed: float = 1e-3
    contact_rtol: float = 1e-9

    def __post_init__(self) -> None:
        if not (math.isfinite(self.settle) and self.settle >= 0):
            raise InputError(f"settle must be >= 0 s, was {self.settle!r}")
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise InputError(f"duration must be > 0 s, was {self.duration!r}")
        if self.initial is not None and len(self.initial) != 4:
            raise InputError("initial must be (x, x', y, y'), 4 numbers, "
                             f"was {self.initial!r}")
        if self.grid_per_period < 8:
            raise InputError(f"grid_per_period must be >= 8, was {self.grid_per_period!r}")
        if not self.stick_speed >= 0:
            raise InputError(f"stick_speed must be >= 0 m/s, was {self.stick_speed!r}")
        if not (math.isfinite(self.friction_speed) and self.friction_speed > 0):
            raise InputError(f"friction_speed must be > 0 m/s, was {self.friction_speed!r}")
        if not (0 < self.contact_rtol < 1):
            raise InputError(f"contact_rtol must be in (0, 1), was {self.contact_rtol!r}")


class _Model:
    """Everything the loop needs, resolved once from params + effects."""

    def __init__(self, p: SystemParams, fx: Effects, opt: SimOptions) -> None:
        self.p, self.fx, self.opt = p, fx, opt
        self.b = p.b + fx.db
        if self.b <= 0:
            raise InputError(f"clearance_error db = {fx.db!r} m makes the half-clearance "
                             f"b + db <= 0 (b = {p.b!r} m)")
        self.m1, self.m2, self.M = p.m1, p.m2, p.m1 + p.m2
        self.mu = fx.mu
        self.gs = G_ACCEL * math.sin(math.radians(fx.theta_deg))
        self.mug = self.mu * G_ACCEL
        self.base = BaseMotion(p.amplitude, p.frequency, tuple(fx.harmonics()))
        self._base_terms = [(float(w), float(bj.real), float(bj.imag)) for w, bj in
                            zip(self.base.omegas, self.base.complex_amplitudes, strict=True)]
        self.free = Oscillator(p.m1, p.c1, p.k1, self.base)
        self.stuck = Oscillator(self.M, p.c1, p.k1, self.base)
        shortest = min(2 * math.pi / float(self.base.omegas.max()),
                       2 * math.pi / self.free.wd, 2 * math.pi / self.stuck.wd)
        self.h = shortest / opt.grid_per_period
        # z and z' of a flight on a window of the event grid, in one product
        self.free_basis = np.vstack(self.free.window_basis(self.h, _WINDOW)[:2])
        # the constants of the compiled event search (_flight_kernel) of flights and of
        # the stuck phases (LO and ball moving as one)
        from ._flight_kernel import pack_model
        self.flight_consts = pack_model(self.free, self.b, self.h, _WINDOW)
        self.stuck_consts = pack_model(self.stuck, self.b, self.h, _WINDOW)
        self.stuck_basis = self.stuck.window_basis(self.h, _WINDOW)[2]
        self.laws = fx.restitution_laws(p.r)
        self.drift = None
        if "restitution_drift" in fx:
            self.drift = (fx.value("restitution_drift", "side"),
                          float(fx.value("restitution_drift", "rate")))

    def restitution(self, side: int, speed: float, t: float) -> float:
        name = "right" if side == RIGHT else "left"
        r = self.laws[name](speed)
        if self.drift is not None and self.drift[0] == name:
            r = min(1.0, max(0.0, r + self.drift[1] * max(t - self.opt.settle, 0.0)))
        return r

    def stuck_q(self, t: float, x: float, v: float) -> float:
        """Friction acceleration needed to keep the ball with the LO, minus g sin(theta)."""
        xe = vxe = 0.0
        for w, br, bi in self._base_terms:
            s, c = math.sin(w * t), math.cos(w * t)
            xe += br * s + bi * c
            vxe += w * (br * c - bi * s)
        acc = (self.p.c1 * (vxe - v) + self.p.k1 * (xe - x) + self.m2 * self.gs) / self.M
        return acc - self.gs


def simulate(params: SystemParams, effects: Effects | None = None,
             options: SimOptions | None = None, contact=None, **option_kw
             ) -> SimulationResult:
    """Simulate the LO + ball system exactly (event-driven, closed-form flows).

    With ``contact`` the walls are compliant instead (penalty forces, contacts of
    finite duration; :mod:`vidiscover.simulation.compliant`).

    Parameters
    ----------
    params : SystemParams
        Physical parameters (``params.b`` is the nominal half-clearance).
    effects : Effects, optional
        Switched-on effects (default: none, the paper's nominal model).
    options : SimOptions, optional
        Numerical and initial-condition options; keyword arguments override fields.
    contact : ContactModel, str or list of str, optional
        Compliant walls, e.g. ``"hunt-crossley:k=1e9,alpha=0.3"`` (see
        :mod:`vidiscover.simulation.contact`); None (default): rigid walls with
        Newton's restitution law (this exact engine).

    Returns
    -------
    SimulationResult
        Piecewise closed-form trajectory, impacts, sticking phases, status
        (a :class:`~vidiscover.simulation.compliant.CompliantResult` with ``contact``).

    Examples
    --------
    >>> from vidiscover import preset, simulate
    >>> res = simulate(preset("paper", b=0.009), settle=2.0, duration=1.0)
    >>> res.status, res.impacts.n > 0
    (0, True)
    """
    if contact is not None:
        from .compliant import simulate_compliant
        return simulate_compliant(params, effects, options, contact, **option_kw)
    effects = effects if effects is not None else Effects()
    model = _Model(params, effects, merge_options(options, option_kw))
    return _Loop(model).run()


def merge_options(options: SimOptions | None, option_kw: dict) -> SimOptions:
    """``options`` (default :class:`SimOptions`) with keyword overrides, checked by name."""
    import dataclasses

    options = options if options is not None else SimOptions()
    if not option_kw:
        return options
    known = {f.name for f in dataclasses.fields(SimOptions)}
    unknown = sorted(set(option_kw) - known)
    if unknown:
        raise InputError(f"unknown simulation option(s) {', '.join(unknown)}; "
                         f"known: {', '.join(sorted(known))}")
    return dataclasses.replace(options, **option_kw)


def initial_state(opt: SimOptions, b: float) -> tuple[float, float, float, float]:
    """The state (x, x', y, y') at t = 0 of both engines.

    ``opt.initial``, or the LO at rest and the ball at the centre moving at
    ``opt.ball_speed``; a one-line error if the ball starts outside |z| <= b.
    """
    if opt.initial is None:
        return 0.0, 0.0, 0.0, float(opt.ball_speed)
    x, v, y, w = (float(s) for s in opt.initial)
    if abs(y - x) > b:
        raise InputError(f"initial ball position is outside the clearance: "
                         f"|y - x| = {abs(y - x)!r} m > b = {b!r} m")
    return x, v, y, w


class _Loop:
    def __init__(self, model: _Model) -> None:
        self.m = model
        opt = model.opt
        self.t_end = opt.settle + opt.duration
        periods = self.t_end * model.p.frequency
        self.max_events = opt.max_events or int(400 * max(periods, 1.0)) + 100
        self.segs: list[tuple] = []
        self.impacts: list[tuple] = []
        self.sticks: list[tuple] = []
        self.n_events = 0
        # the compiled event search: numba is imported with the first model (_Model),
        # never with the package
        from ._flight_kernel import next_event, stuck_release
        self._next_event, self._stuck_release = next_event, stuck_release

    # ------------------------------------------------------------------ loop
    def run(self) -> SimulationResult:
        m = self.m
        x, v, y, w = initial_state(m.opt, m.b)
        t = 0.0
        mode, where, wall = FLIGHT, MIDDLE, MIDDLE
        status, message = 0, "reached the end of the record"
        s = self._slide_sign(t, x, v, w - v, wall)
        if s is None:
            mode, s = STUCK, 0
        while t < self.t_end:
            if self.n_events >= self.max_events:
                status = 1
                message = (f"stopped after {self.n_events} events (max_events) at t = {t:.6g} s")
                break
            self.n_events += 1
            if mode == FLIGHT:
                t, x, v, y, w, kind = self._flight(t, x, v, y, w, s, wall)
                wall = MIDDLE
                if kind == "end":
                    break
                if kind == "zero":
                    w = v  # exactly zero relative velocity at the reversal
                    s = self._slide_sign(t, x, v, 0.0, MIDDLE)
                    if s is None:
                        mode, where, w = STUCK, MIDDLE, v
                    continue
                side = kind
                v, w, stuck = self._impact(t, x, v, y, w, side)
                wall = side
                if stuck:
                    s = self._slide_sign(t, x, v, 0.0, side)
                    if s is None:
                        mode, where = STUCK, side
                else:
                    s = 1 if (w - v) > 0 else -1
            else:
                t0 = t
                t, x, v, y, w, s = self._stuck(t, x, v, y, where)
                self.sticks.append((t0, t, where))
                wall = where
                mode = FLIGHT
                if s == 0:
                    break
        return SimulationResult.from_loop(self.m, self.segs, self.impacts, self.sticks,
                                          status, message, self.n_events)

    def _slide_sign(self, t: float, x: float, v: float, zd: float, wall: int) -> int | None:
        """Direction of relative sliding, or None if the ball stays with the LO."""
        m = self.m
        if abs(zd) > 0.0:
            return 1 if zd > 0 else -1
        q = m.stuck_q(t, x, v)
        if wall == RIGHT:
            holds = q <= m.mug
        elif wall == LEFT:
            holds = q >= -m.mug
        else:
            holds = abs(q) <= m.mug and m.mug > 0
        if holds:
            return None
        if m.mug == 0.0 and wall == MIDDLE:
            return 1 if q < 0 else -1
        return -1 if q > 0 else 1

    # ------------------------------------------------------------------ flight
    def _flight(self, t0, x0, v0, y0, w0, s, start_wall):
        """The free flight from ``t0`` to its first event (compiled: ``_flight_kernel``)."""
        m = self.m
        ab = m.gs - m.mug * s
        F0 = m.mu * m.m2 * G_ACCEL * s
        te, kind, x, v, C1, C2 = self._next_event(
            m.flight_consts, m.free_basis, t0, x0, v0, y0, w0, F0, ab, self.t_end,
            start_wall, m.mug > 0.0)
        tau = te - t0
        y = y0 + w0 * tau + 0.5 * ab * tau * tau
        w = w0 + ab * tau
        if kind == RIGHT:
            y = x + m.b
        elif kind == LEFT:
            y = x - m.b
        self.segs.append((t0, te, FLIGHT, C1, C2, F0, y0, w0, ab, 0.0))
        return te, x, v, y, w, _KINDS[kind]

    # ------------------------------------------------------------------ impact
    def _impact(self, t, x, v, y, w, side):
        m = self.m
        u = w - v                                # relative velocity before (z'-)
        speed = abs(u)
        r = m.restitution(side, speed, t)
        up = -r * u
        P = m.m1 * v + m.m2 * w
        stuck = abs(up) < m.opt.stick_speed
        if stuck:
            up = 0.0
        vp = (P - m.m2 * up) / m.M
        wp = vp + up
        self.impacts.append((t, side, u, up, r, v, vp, w, wp, x, stuck))
        return vp, wp, stuck

    # ------------------------------------------------------------------ stuck
    def _stuck(self, t0, x0, v0, y0, where):
        """A phase with the ball stuck to the LO, up to its release (``_flight_kernel``)."""
        m = self.m
        F0 = m.m2 * m.gs
        te, s, x, v, C1, C2 = self._stuck_release(
            m.stuck_consts, m.stuck_basis, t0, x0, v0, F0, m.gs, m.mug, where, self.t_end)
        zc = y0 - x0
        self.segs.append((t0, te, STUCK, C1, C2, F0, zc, 0.0, 0.0, 1.0))
        return te, x, v, x + zc, v, s
