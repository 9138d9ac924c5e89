"""Ball flights between two known positions, with or without Coulomb friction.

Between impacts the ball obeys ``y'' = -mu g sgn(y' - x')`` (paper eq. 1): dry
friction of coefficient ``mu`` opposes the relative velocity z' = y' - x'. Two
positions of the ball are known from the impacts, ``y(t_s)`` and ``y(t_e)``; the
velocity it left with is not. Three estimators:

* ``mu = 0``: a straight line (paper eq. 6), ``w = (y_e - y_s) / (t_e - t_s)``.
* :func:`eq8_velocities` -- the paper's eq. 8: constant deceleration ``mu g``
  against the relative velocity, whose sign is taken from the direction of the
  flight (towards the right wall: z' > 0). Closed form, but wrong whenever z'
  changes sign inside the flight: a chatter flight leaves a wall and comes back
  to it (z' always changes sign), and a slow ball can be overtaken by the LO.
* :func:`solve_flights` -- the friction law integrated along the *measured* LO
  velocity, with z' free to change sign and the ball allowed to stick to the LO
  (when z' reaches 0 while |x''| <= mu g) and to slide again; the launch
  velocity is found by bracketing (the end position is monotone in it, and
  |y''| <= mu g bounds it to ``w_mean +/- mu g (t_e - t_s) / 2``), on a grid of
  candidates refined twice, all flights vectorised together.

Examples
--------
>>> import numpy as np
>>> ws, we = eq8_velocities(np.array([0.0]), np.array([0.1]), np.array([0.0]),
...                         np.array([0.05]), np.array([1]), mu=0.1)
>>> round(float(ws[0]), 4), round(float(we[0]), 4)
(0.5491, 0.4509)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import G_ACCEL

__all__ = ["eq8_velocities", "solve_flights", "integrate_flights", "falling_frame",
           "FlightSolution", "STEPS"]

#: Integration steps per flight of :func:`solve_flights`.
STEPS = 96
_PART = 2048          # flights solved together by :func:`solve_flights`


def eq8_velocities(t_s: np.ndarray, t_e: np.ndarray, y_s: np.ndarray, y_e: np.ndarray,
                   direction: np.ndarray, mu: float) -> tuple[np.ndarray, np.ndarray]:
    """Ball velocity after the start and before the end impact, paper eq. 8.

    Parameters
    ----------
    t_s, t_e : ndarray
        Start and end times of the flights (s).
    y_s, y_e : ndarray
        Ball positions at the start and the end (m).
    direction : ndarray of int
        Sign assumed for z' during the flight (+1 towards the right wall).
    mu : float
        Friction coefficient.

    Returns
    -------
    w_start, w_end : ndarray
        ``w_mean + s mu g dt / 2`` and ``w_mean - s mu g dt / 2`` (m/s).
    """
    dt = t_e - t_s
    w = (y_e - y_s) / dt
    corr = np.sign(direction) * mu * G_ACCEL * dt / 2.0
    return w + corr, w - corr


@dataclass(frozen=True, eq=False)
class FlightSolution:
    """Friction flights solved by :func:`solve_flights` (arrays over flights).

    Attributes
    ----------
    w_start, w_end : ndarray
        Ball velocity at the start and at the end (m/s).
    closure : ndarray
        End position of the solved trajectory minus the target (m); non-zero when
        the target is out of reach of the bracket.
    sign_changes : ndarray of int
        Times z' changed sign (or the ball stuck) along the flight.
    t : ndarray
        Integration times, shape (n_flights, STEPS + 1).
    y, w : ndarray
        Ball position and velocity along the flight, same shape.
    """

    w_start: np.ndarray
    w_end: np.ndarray
    closure: np.ndarray
    sign_changes: np.ndarray
    t: np.ndarray
    y: np.ndarray
    w: np.ndarray


def _integrate(w0, v, acc, h, mu, record=False):
    """Integrate the ball from launch velocities ``w0`` (F, K) along LO velocity ``v``.

    ``v``, ``acc``: (F, M + 1) LO velocity and acceleration at the steps; ``h``: (F,)
    step. Returns end displacement, end velocity, sign changes (and the history).
    """
    F, K = w0.shape
    M = v.shape[1] - 1
    mug = mu * G_ACCEL
    w = w0.copy()
    y = np.zeros_like(w)
    s = np.sign(w - v[:, :1])
    stuck = s == 0
    s = np.where(stuck, 1.0, s)
    changes = np.zeros((F, K), dtype=np.int64)
    hh = h[:, None]
    hist_y = hist_w = None
    if record:
        hist_y = np.zeros((F, K, M + 1))
        hist_w = np.zeros((F, K, M + 1))
        hist_w[:, :, 0] = w
    for k in range(M):
        v1 = v[:, k + 1:k + 2]
        a1 = acc[:, k + 1:k + 2]
        holds = np.abs(a1) <= mug
        # free ball: constant deceleration against z'
        w_free = w - mug * s * hh
        crossed = (s * (w_free - v1) < 0) & ~stuck
        stick_now = crossed & holds
        flip = crossed & ~holds
        # stuck ball: follows the LO while friction can hold it
        release = stuck & ~holds
        w_new = np.where(stuck | stick_now, v1, w_free)
        changes += (crossed | release).astype(np.int64)
        s = np.where(flip, -s, s)
        s = np.where(release, -np.sign(a1) + (a1 == 0), s)
        stuck = (stuck & holds) | stick_now
        y = y + 0.5 * hh * (w + w_new)
        w = w_new
        if record:
            hist_y[:, :, k + 1] = y
            hist_w[:, :, k + 1] = w
    return y, w, changes, hist_y, hist_w


def _grid(t_s, t_e, lo_velocity, lo_acceleration, v_start, v_end, steps):
    F = t_s.size
    frac = np.linspace(0.0, 1.0, steps + 1)
    T = t_s[:, None] + (t_e - t_s)[:, None] * frac[None, :]
    V = np.asarray(lo_velocity(T), dtype=float).reshape(F, steps + 1)
    A = np.asarray(lo_acceleration(T), dtype=float).reshape(F, steps + 1)
    if v_start is not None:
        V[:, 0] = v_start
    if v_end is not None:
        V[:, -1] = v_end
    return T, V, A, (t_e - t_s) / steps


def integrate_flights(t_s: np.ndarray, t_e: np.ndarray, y_s: np.ndarray, w_s: np.ndarray,
                      lo_velocity, lo_acceleration, mu: float,
                      v_start: np.ndarray | None = None, v_end: np.ndarray | None = None,
                      steps: int = STEPS) -> tuple[np.ndarray, np.ndarray]:
    """Ball position and velocity at ``t_e`` when launched at ``t_s`` with ``w_s``.

    Parameters are those of :func:`solve_flights` with the launch velocity ``w_s``
    (m/s) given instead of the end position.

    Returns
    -------
    y_end, w_end : ndarray
    """
    t_s, t_e = np.asarray(t_s, float), np.asarray(t_e, float)
    if t_s.size == 0:
        return np.zeros(0), np.zeros(0)
    F = t_s.size
    if F > _PART:                   # independent flights: a part at a time (as solve_flights)
        y_end, w_end = np.empty(F), np.empty(F)
        for lo in range(0, F, _PART):
            sl = slice(lo, lo + _PART)
            y_end[sl], w_end[sl] = integrate_flights(
                t_s[sl], t_e[sl], _part(y_s, F, sl), _part(w_s, F, sl), lo_velocity,
                lo_acceleration, mu, _part(v_start, F, sl), _part(v_end, F, sl), steps)
        return y_end, w_end
    T, V, A, h = _grid(t_s, t_e, lo_velocity, lo_acceleration, v_start, v_end, int(steps))
    Y, W, _, _, _ = _integrate(np.asarray(w_s, float)[:, None], V, A, h, mu)
    return np.asarray(y_s, float) + Y[:, 0], W[:, 0]


def _part(v, n: int, sl: slice):
    """Rows ``sl`` of a per-flight value (an array of ``n``, a scalar, or None)."""
    return None if v is None else np.broadcast_to(np.asarray(v, dtype=float), (n,))[sl]


def falling_frame(lo_velocity, lo_acceleration, g0: float):
    """The LO's velocity and acceleration seen from a ball falling with ``g0`` along the base.

    A constant acceleration of the ball along the base (``g0 = g sin(theta)``, m/s^2)
    is absorbed by a change of frame: with ``Y = y - g0 (t - t_s)^2 / 2`` and the LO
    velocity ``V = x' - g0 (t - t_s)`` the relative motion, and so friction's sticking
    and sliding, are unchanged, and :func:`solve_flights` / :func:`integrate_flights`
    solve the flights in that frame. ``t_s`` is the first time of each row of the
    flights' time grids (their launch). Without an inclination the callables are
    returned as they are.
    """
    if not g0:
        return lo_velocity, lo_acceleration

    def velocity(tq):
        tq = np.asarray(tq, dtype=float)
        return lo_velocity(tq) - g0 * (tq - tq[:, :1])

    def acceleration(tq):
        return lo_acceleration(tq) - g0

    return velocity, acceleration


def solve_flights(t_s: np.ndarray, t_e: np.ndarray, y_s: np.ndarray, y_e: np.ndarray,
                  lo_velocity, lo_acceleration, mu: float, v_start: np.ndarray | None = None,
                  v_end: np.ndarray | None = None, candidates: int = 16,
                  steps: int = STEPS) -> FlightSolution:
    """Launch velocities that carry the ball from ``y_s`` to ``y_e`` under friction.

    Parameters
    ----------
    t_s, t_e, y_s, y_e : ndarray
        Flight start/end times (s) and ball positions (m), one entry per flight.
    lo_velocity, lo_acceleration : callable
        ``f(t) -> ndarray`` evaluating the LO velocity (between impacts, without
        jumps) and the smooth LO acceleration at any times (s).
    mu : float
        Friction coefficient (> 0; use a straight line for 0).
    v_start, v_end : ndarray, optional
        LO velocity just after the start / before the end impact (override the
        evaluation at the flight ends, which may straddle a velocity jump).
    candidates : int
        Launch velocities tried per refinement pass.
    steps : int
        Integration steps per flight.

    Returns
    -------
    FlightSolution
    """
    t_s, t_e = np.asarray(t_s, float), np.asarray(t_e, float)
    y_s, y_e = np.asarray(y_s, float), np.asarray(y_e, float)
    F = t_s.size
    M = int(steps)
    if F == 0:
        z = np.zeros(0)
        return FlightSolution(z, z, z, np.zeros(0, dtype=np.int64), np.zeros((0, M + 1)),
                              np.zeros((0, M + 1)), np.zeros((0, M + 1)))
    if F > _PART:
        # flights are independent: solve them a part at a time (the temporaries of the
        # integration are several times the result; a long record has many flights)
        out = FlightSolution(np.empty(F), np.empty(F), np.empty(F),
                             np.empty(F, dtype=np.int64), np.empty((F, M + 1)),
                             np.empty((F, M + 1)), np.empty((F, M + 1)))
        for lo in range(0, F, _PART):
            sl = slice(lo, lo + _PART)
            part = solve_flights(t_s[sl], t_e[sl], y_s[sl], y_e[sl], lo_velocity,
                                 lo_acceleration, mu,
                                 _part(v_start, F, sl), _part(v_end, F, sl),
                                 candidates, steps)
            for name in ("w_start", "w_end", "closure", "sign_changes", "t", "y", "w"):
                getattr(out, name)[sl] = getattr(part, name)
        return out
    T, V, A, h = _grid(t_s, t_e, lo_velocity, lo_acceleration, v_start, v_end, M)
    dt = t_e - t_s
    w_mean = (y_e - y_s) / dt
    half = mu * G_ACCEL * dt / 2.0 * 1.02 + 1e-9
    lo, hi = w_mean - half, w_mean + half
    target = y_e - y_s
    for _ in range(3):
        grid = np.linspace(0.0, 1.0, candidates)
        W0 = lo[:, None] + (hi - lo)[:, None] * grid[None, :]
        Y, _, _, _, _ = _integrate(W0, V, A, h, mu)
        # end position is non-decreasing in the launch velocity: bracket the target
        k = np.clip((Y < target[:, None]).sum(axis=1) - 1, 0, candidates - 2)
        rows = np.arange(F)
        lo, hi = W0[rows, k], W0[rows, k + 1]
    Y0, _, _, _, _ = _integrate(np.stack([lo, hi], axis=1), V, A, h, mu)
    with np.errstate(divide="ignore", invalid="ignore"):
        wgt = np.where(Y0[:, 1] > Y0[:, 0], (target - Y0[:, 0]) / (Y0[:, 1] - Y0[:, 0]), 0.5)
    w0 = lo + np.clip(wgt, 0.0, 1.0) * (hi - lo)
    Yf, Wf, ch, hy, hw = _integrate(w0[:, None], V, A, h, mu, record=True)
    return FlightSolution(w_start=w0, w_end=Wf[:, 0], closure=Yf[:, 0] - target,
                          sign_changes=ch[:, 0], t=T, y=y_s[:, None] + hy[:, 0, :],
                          w=hw[:, 0, :])
