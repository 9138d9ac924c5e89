"""Independent reference integrator for the LO + ball system (test-only).

This is a deliberately plain implementation of the model of DESIGN.md section 1,
written from the equations of motion and integrated numerically with
``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-10, atol 1e-12 scaled per component),
with terminal events and a restart after every event. It shares no code with
``vidiscover.simulation``: only :class:`~vidiscover.params.SystemParams` and
:class:`~vidiscover.effects.Effects` are used, to read parameters and the
restitution laws. It exists to check the exact event-driven simulator.

Model (state in flight: x, x', z = y - x, z')::

    m1 x'' + c1 (x' - xe') + k1 (x - xe) = mu m2 g s
    m2 y'' = -mu m2 g s + m2 g sin(theta)          s = sgn(z'), fixed per flight

    stuck ball (combined mass M = m1 + m2, ball at fixed z):
    M x'' + c1 (x' - xe') + k1 (x - xe) = m2 g sin(theta)
    q = x'' - g sin(theta)    (friction acceleration the ball needs to stay)

Events (all terminal; the integration restarts after each one):

* ``z = +b_true`` crossed upwards (right wall), ``z = -b_true`` crossed downwards
  (left wall): Newton's law ``z'+ = -r(|z'-|) z'-`` with momentum conservation; a
  rebound slower than ``stick_speed`` sticks the ball to the wall (``z'+ = 0``),
  where it stays while the wall pushes it: right wall ``q <= mu g``, left wall
  ``q >= -mu g``;
* ``z' = 0`` (an extremum of z): with friction the ball sticks to the LO if
  ``|q| <= mu g``, otherwise it slides with ``s = -sgn(q)``; without friction the
  flight simply goes on. Stopping at every extremum makes z monotone inside each
  integration, so a wall cannot be crossed twice unseen inside one step (a grazing
  impact): if z is found beyond a wall at an extremum, the crossing is located by
  re-integrating that last step finely;
* release of a stuck ball: ``q`` leaves the holding range above (by 1e-9 m/s^2,
  ``Q_MARGIN``, so that the flight that follows starts unambiguously released).

The wall a flight starts from, and z' when a flight starts with z' = 0, are zero at
the start time by construction; those event functions are divided by ``t - t0``
(and given their sign just after ``t0`` at ``t0``) so that only a later root is found.

Accuracy: the step is bounded by 1/64 of the shortest period of the system. With
DOP853's own step control at rtol 1e-10 the global error is ~1e-11 m, which the
sensitive transients of this system (b = 9 mm, paper preset) amplify to more than
1e-6 s within 20 forcing periods; with the bounded step the error is ~1e-15 m
(checked against the closed-form LO response in the tests).

Examples
--------
>>> from vidiscover.params import preset
>>> ref = reference_impacts(preset("paper", b=0.009), duration=0.2)
>>> ref.status, ref.n > 0
(0, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from vidiscover.effects import Effects
from vidiscover.params import G_ACCEL, SystemParams

__all__ = ["ReferenceResult", "reference_impacts"]

RIGHT, LEFT, MIDDLE = 1, -1, 0
#: How far (m/s^2) q must pass the holding limit for a stuck ball to be released.
Q_MARGIN = 1e-9
_WHERE = {RIGHT: "right", LEFT: "left", MIDDLE: "middle"}


@dataclass
class ReferenceResult:
    """Impacts (and sticking phases) found by the reference integrator.

    Attributes
    ----------
    t, side, u_minus, u_plus, r, v_minus, v_plus, w_minus, w_plus, x, stuck : ndarray
        Same meaning as :class:`vidiscover.simulation.ImpactTable`.
    sticking : list of (t0, t1, where)
        Phases where the ball moved with the LO.
    status : int
        0 when the end time was reached, 1 when stopped by ``max_events``.
    n_events : int
        Number of solve_ivp restarts (segments).
    n_steps : int
        Total accepted DOP853 steps.
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
    sticking: list = field(default_factory=list)
    status: int = 0
    n_events: int = 0
    n_steps: int = 0

    @property
    def n(self) -> int:
        """Number of impacts."""
        return int(self.t.size)


class _Event:
    """A solve_ivp event: a callable with ``terminal`` and ``direction``."""

    terminal = True

    def __init__(self, fun, direction: float) -> None:
        self.fun = fun
        self.direction = direction

    def __call__(self, t, y):
        return self.fun(t, y)


def reference_impacts(params: SystemParams, effects: Effects | None = None, *,
                      settle: float = 0.0, duration: float = 2.5,
                      initial: tuple | None = None, ball_speed: float = 0.6,
                      stick_speed: float = 1e-4, rtol: float = 1e-10, atol: float = 1e-12,
                      max_step: float | None = None,
                      max_events: int | None = None) -> ReferenceResult:
    """Integrate the model with solve_ivp and return the impacts.

    Parameters
    ----------
    params : SystemParams
        Physical parameters.
    effects : Effects, optional
        Switched-on effects; sensor-only effects are ignored.
    settle, duration : float
        Simulated span is ``[0, settle + duration]`` (s).
    initial : (x, x', y, y') or None
        Initial state; default LO at rest, ball at the centre with ``ball_speed``.
    ball_speed, stick_speed : float
        As in :class:`vidiscover.simulation.SimOptions`.
    rtol, atol : float
        DOP853 tolerances; ``atol`` is in metres for positions and is scaled by the
        LO natural angular frequency for velocities.
    max_step : float, optional
        Largest step (default: 1/64 of the shortest period of the system).
    max_events : int, optional
        Bound on restarts (default 400 per forcing period + 100).

    Returns
    -------
    ReferenceResult
    """
    fx = effects if effects is not None else Effects()
    unsupported = [n for n in fx.names if n not in {
        "asymmetric_restitution", "velocity_dependent_restitution", "coulomb_friction",
        "inclination", "sensor_resonance", "excitation_distortion", "clearance_error",
        "contact_duration", "restitution_drift"}]
    if unsupported:
        raise NotImplementedError(f"reference integrator does not model {unsupported}")

    m1, c1, k1, m2 = params.m1, params.c1, params.k1, params.m2
    M = m1 + m2
    g = G_ACCEL
    mu = fx.mu
    mug = mu * g
    gs = g * math.sin(math.radians(fx.theta_deg))
    b = params.b + fx.db
    A, f = params.amplitude, params.frequency
    harm = [(n * 2.0 * math.pi * f, A * h, ph) for n, h, ph in fx.harmonics()]
    laws = fx.restitution_laws(params.r)
    drift = None
    if "restitution_drift" in fx:
        drift = (fx.value("restitution_drift", "side"),
                 float(fx.value("restitution_drift", "rate")))

    t_end = settle + duration
    omega0 = math.sqrt(k1 / m1)
    if max_step is None:
        w_max = max(max(w for w, _, _ in harm), omega0, math.sqrt(k1 / M))
        max_step = 2.0 * math.pi / w_max / 64.0
    q_lim = mug + Q_MARGIN
    atol_flight = np.array([atol, atol * omega0, atol, atol * omega0])
    atol_stuck = atol_flight[:2]
    if max_events is None:
        max_events = int(400 * max(t_end * f, 1.0)) + 100

    def base(t):
        xe = xed = 0.0
        for w, amp, ph in harm:
            arg = w * t + ph
            xe += amp * math.sin(arg)
            xed += amp * w * math.cos(arg)
        return xe, xed

    def q_stuck(t, x, v):
        """x''_combined - g sin(theta) for a ball moving with the LO."""
        xe, xed = base(t)
        acc = (c1 * (xed - v) + k1 * (xe - x) + m2 * gs) / M
        return acc - gs

    def restitution(side, speed, t):
        name = _WHERE[side]
        r = float(laws[name](float(speed)))
        if drift is not None and drift[0] == name:
            r = min(1.0, max(0.0, r + drift[1] * max(t - settle, 0.0)))
        return r

    def flight_rhs(s):
        fric = mu * m2 * g * s
        ydd = -mug * s + gs

        def rhs(t, y):
            x, v, _z, u = y
            xe, xed = base(t)
            xdd = (c1 * (xed - v) + k1 * (xe - x) + fric) / m1
            return [v, xdd, u, ydd - xdd]
        return rhs

    def stuck_rhs(t, y):
        x, v = y
        xe, xed = base(t)
        return [v, (c1 * (xed - v) + k1 * (xe - x) + m2 * gs) / M]

    def flight_events(t0, s, start_wall, u0):
        """Terminal events of a flight started at t0: the two walls and z' = 0.

        A function that is zero at t0 by construction (the wall the flight starts
        from; z' when the flight starts with z' = 0) is divided by t - t0, and takes
        at t0 the sign it has just after t0, so that only a later root is found.
        """
        def wall_event(sign, direction):
            if start_wall == sign:
                def ev(t, y):
                    tau = t - t0
                    return (y[2] - sign * b) / tau if tau > 0.0 else -sign
            else:
                def ev(t, y):
                    return y[2] - sign * b
            return _Event(ev, direction)

        if u0 == 0.0:
            def extremum(t, y):
                tau = t - t0
                return y[3] / tau if tau > 0.0 else float(s)
        else:
            def extremum(t, y):
                return y[3]
        return [wall_event(RIGHT, 1.0), wall_event(LEFT, -1.0), _Event(extremum, 0.0)]

    def missed_crossing(rhs, sol, side):
        """Locate a wall crossed and re-crossed inside the step that ended at an extremum.

        Between the last accepted step start and the extremum, z is monotone, so with
        a fine step the crossing is found by a plain sign change.
        """
        t_prev, y_prev, te = float(sol.t[-2]), sol.y[:, -2], float(sol.t[-1])
        ev = _Event(lambda t, y: y[2] - side * b, float(side))
        sub = solve_ivp(rhs, (t_prev, te), y_prev, method="DOP853", rtol=rtol,
                        atol=atol_flight, events=[ev], max_step=(te - t_prev) / 64.0)
        if not sub.t_events[0].size:
            raise RuntimeError(f"could not locate the wall crossing before t = {te!r}")
        return float(sub.t_events[0][0]), [float(c) for c in sub.y_events[0][0]]

    def zdd_sign(t, x, v):
        """z'' of a frictionless ball at z' = 0 (sets the new flight direction)."""
        xe, xed = base(t)
        return gs - (c1 * (xed - v) + k1 * (xe - x)) / m1

    def slide_sign(t, x, v, wall):
        """Direction of sliding of a ball at rest relative to the LO, or None if it stays."""
        q = q_stuck(t, x, v)
        if wall == RIGHT:
            holds = q <= mug
        elif wall == LEFT:
            holds = q >= -mug
        else:
            holds = mug > 0.0 and abs(q) <= mug
        if holds:
            return None
        return -1 if q > 0 else 1

    # ------------------------------------------------------------------ state
    if initial is None:
        x, v, y, w = 0.0, 0.0, 0.0, float(ball_speed)
    else:
        x, v, y, w = (float(c) for c in initial)
    z, u = y - x, w - v
    t = 0.0
    rows: list[tuple] = []
    sticking: list[tuple] = []
    mode, where, start_wall = "flight", MIDDLE, MIDDLE
    status, n_events, n_steps = 0, 0, 0
    if u != 0.0:
        s = 1 if u > 0 else -1
    else:
        s = slide_sign(t, x, v, MIDDLE)
        if s is None:
            mode = "stuck"

    while t < t_end:
        if n_events >= max_events:
            status = 1
            break
        n_events += 1
        if mode == "flight":
            rhs = flight_rhs(s)
            sol = solve_ivp(rhs, (t, t_end), [x, v, z, u], method="DOP853", rtol=rtol,
                            atol=atol_flight, events=flight_events(t, s, start_wall, u),
                            max_step=max_step)
            n_steps += sol.t.size - 1
            hit = [k for k, te in enumerate(sol.t_events) if te.size]
            if not hit:
                break
            k = min(hit, key=lambda j: sol.t_events[j][0])
            t = float(sol.t_events[k][0])
            x, v, z, u = (float(c) for c in sol.y_events[k][0])
            start_wall = MIDDLE
            if k == 2:                                      # extremum of z
                if abs(z) > b:                              # a wall grazed inside the step
                    k = 0 if z > 0 else 1
                    t, (x, v, z, u) = missed_crossing(rhs, sol, 1 if k == 0 else -1)
                else:
                    u = 0.0
                    if mu > 0.0:
                        s = slide_sign(t, x, v, MIDDLE)
                        if s is None:
                            mode, where = "stuck", MIDDLE
                    else:
                        s = 1 if zdd_sign(t, x, v) > 0 else -1
                    continue
            side = RIGHT if k == 0 else LEFT
            z = side * b
            wm = v + u
            r = restitution(side, abs(u), t)
            up = -r * u
            P = m1 * v + m2 * wm
            stuck = abs(up) < stick_speed
            if stuck:
                up = 0.0
            vp = (P - m2 * up) / M
            wp = vp + up
            rows.append((t, side, u, up, r, v, vp, wm, wp, x, stuck))
            v, u = vp, up
            start_wall = side
            if stuck:
                s = slide_sign(t, x, v, side)
                if s is None:
                    mode, where = "stuck", side
            else:
                s = 1 if up > 0 else -1
        else:
            t0 = t
            evs = []
            # released when q passes the holding limit by Q_MARGIN (shifts the release
            # by ~1e-11 s): the flight then starts unambiguously away from the wall
            if where in (RIGHT, MIDDLE):
                evs.append(_Event(lambda tt, yy: q_stuck(tt, yy[0], yy[1]) - q_lim, 1.0))
            if where in (LEFT, MIDDLE):
                evs.append(_Event(lambda tt, yy: q_stuck(tt, yy[0], yy[1]) + q_lim, -1.0))
            sol = solve_ivp(stuck_rhs, (t, t_end), [x, v], method="DOP853", rtol=rtol,
                            atol=atol_stuck, events=evs, max_step=max_step)
            n_steps += sol.t.size - 1
            hit = [k for k, te in enumerate(sol.t_events) if te.size]
            if not hit:
                sticking.append((t0, t_end, _WHERE[where]))
                break
            k = min(hit, key=lambda j: sol.t_events[j][0])
            t = float(sol.t_events[k][0])
            x, v = (float(c) for c in sol.y_events[k][0])
            sticking.append((t0, t, _WHERE[where]))
            u = 0.0
            s = slide_sign(t, x, v, where)
            if s is None:  # on the limit within rounding: leave away from the wall
                s = -where if where != MIDDLE else (-1 if q_stuck(t, x, v) > 0 else 1)
            start_wall = where
            mode = "flight"

    cols = list(zip(*rows, strict=True)) if rows else [()] * 11
    names = ("t", "side", "u_minus", "u_plus", "r", "v_minus", "v_plus", "w_minus",
             "w_plus", "x", "stuck")
    arr = {n: np.asarray(c, dtype=float) for n, c in zip(names, cols, strict=True)}
    arr["side"] = arr["side"].astype(np.int8)
    arr["stuck"] = arr["stuck"].astype(bool)
    return ReferenceResult(**arr, sticking=sticking, status=status, n_events=n_events,
                           n_steps=n_steps)
