"""The exact engine's innermost loop, compiled: one free flight to its next event.

A flight is the ball's free motion between two events (impact, reversal with friction,
release): the LO follows its closed-form flow (:class:`.flows.Oscillator`), the ball a
parabola. :func:`next_event` scans the flight on the event grid, a window of ``n``
intervals at a time, and refines the first event with the bracketed Newton iteration of
:func:`.roots.bracketed_newton`. The arithmetic is that of the Python flows, term by term
in the same order; only the window's matrix-vector product sums in another order, which
moves the grid values (used to bracket, not as results) by rounding.

Compiled with numba (``cache=True``): the first call in a fresh installation compiles
(a few seconds) and writes the machine code next to this file (or in numba's user cache
directory when that is not writable); every later process, joblib and Dask workers
included, loads it in a fraction of a second. The module is imported only by the exact
engine, so the CLI and the analysis never load numba.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["next_event", "stuck_release", "pack_model", "RIGHT", "LEFT", "ZERO", "END"]

RIGHT, LEFT, MIDDLE, ZERO, END = 1, -1, 0, 2, 3

# event functions (the `mode` of _fev)
_F_RIGHT, _F_LEFT, _F_ZERO, _F_ZERO_DEFLATED, _F_RELEASE = 1, -1, 2, 3, 4

# layout of the model vector of pack_model
_SG, _WD, _KM, _K, _B, _H, _N, _NH = range(8)
_HEAD = 8


def pack_model(osc, b: float, h: float, n: int) -> np.ndarray:
    """The constants of a flow in one float vector (one argument to unbox per call).

    Parameters
    ----------
    osc : Oscillator
        The LO's flow (:class:`.flows.Oscillator`: the free LO, or LO and ball as one).
    b, h : float
        Half-clearance and event-grid step.
    n : int
        Intervals of a window of the grid (the rows of its basis, minus one).
    """
    head = [osc.sigma, osc.wd, osc.k / osc.m, osc.k, b, h, float(n), float(len(osc.w))]
    return np.ascontiguousarray(np.concatenate([head, osc.w, osc.pa, osc.pb]),
                                dtype=np.float64)


@njit(cache=True, nogil=True)
def _particular(M, t, F0):
    """(x_p, x_p') at ``t``: Oscillator.particular's arithmetic."""
    nh = int(M[_NH])
    x = F0 / M[_K]
    v = 0.0
    for j in range(nh):
        w, pa, pb = M[_HEAD + j], M[_HEAD + nh + j], M[_HEAD + 2 * nh + j]
        s, c = math.sin(w * t), math.cos(w * t)
        x += pa * s + pb * c
        v += w * (pa * c - pb * s)
    return x, v


@njit(cache=True, nogil=True)
def _lo_xv(M, S, t):
    """(tau, x, x') of the LO at ``t``; ``S`` = the flight's constants (see next_event)."""
    nh = int(M[_NH])
    t0, C1, C2, xs, cv1, cv2 = S[0], S[1], S[2], S[3], S[4], S[5]
    x, v = xs, 0.0
    for j in range(nh):
        w, pa, pb = M[_HEAD + j], M[_HEAD + nh + j], M[_HEAD + 2 * nh + j]
        sn, cs = math.sin(w * t), math.cos(w * t)
        x += pa * sn + pb * cs
        v += w * (pa * cs - pb * sn)
    tau = t - t0
    e = math.exp(-M[_SG] * tau)
    wd = M[_WD]
    cs, sn = math.cos(wd * tau), math.sin(wd * tau)
    return tau, x + e * (C1 * cs + C2 * sn), v + e * (cv1 * cs - cv2 * sn)


@njit(cache=True, nogil=True)
def _lo_aj(M, S, t):
    """Acceleration and jerk of the LO at ``t`` (the release function of a stuck phase)."""
    nh = int(M[_NH])
    t0, C1, C2, cv1, cv2 = S[0], S[1], S[2], S[4], S[5]
    a, j3 = 0.0, 0.0
    for j in range(nh):
        w, pa, pb = M[_HEAD + j], M[_HEAD + nh + j], M[_HEAD + 2 * nh + j]
        sn, cs = math.sin(w * t), math.cos(w * t)
        a -= (w * w) * (pa * sn + pb * cs)
        j3 -= (w * w * w) * (pa * cs - pb * sn)
    tau = t - t0
    sg, wd, km = M[_SG], M[_WD], M[_KM]
    e = math.exp(-sg * tau)
    cs, sn = math.cos(wd * tau), math.sin(wd * tau)
    xh = e * (C1 * cs + C2 * sn)
    vh = e * (cv1 * cs - cv2 * sn)
    ah = (-2.0 * sg) * vh - km * xh
    return a + ah, (-2.0 * sg) * ah - km * vh + j3


@njit(cache=True, nogil=True)
def _zf(M, S, t):
    """(z, z', z'') of the flight at ``t``."""
    nh = int(M[_NH])
    t0, C1, C2, xs, cv1, cv2 = S[0], S[1], S[2], S[3], S[4], S[5]
    y0, w0, ab, hab = S[6], S[7], S[8], S[9]
    x, v, a = xs, 0.0, 0.0
    for j in range(nh):
        w, pa, pb = M[_HEAD + j], M[_HEAD + nh + j], M[_HEAD + 2 * nh + j]
        sn, cs = math.sin(w * t), math.cos(w * t)
        x += pa * sn + pb * cs
        v += w * (pa * cs - pb * sn)
        a -= (w * w) * (pa * sn + pb * cs)
    tau = t - t0
    sg, wd = M[_SG], M[_WD]
    e = math.exp(-sg * tau)
    cs, sn = math.cos(wd * tau), math.sin(wd * tau)
    xh = e * (C1 * cs + C2 * sn)
    vh = e * (cv1 * cs - cv2 * sn)
    ah = (-2.0 * sg) * vh - M[_KM] * xh
    return (y0 + w0 * tau + hab * tau * tau - (x + xh), w0 + ab * tau - (v + vh),
            ab - (a + ah))


@njit(cache=True, nogil=True)
def _fev(mode, M, S, t, td):
    """Event function ``mode`` and its derivative at ``t`` (``td``: the deflated root)."""
    if mode == _F_RELEASE:
        a, j = _lo_aj(M, S, t)
        return a - S[6], j
    if mode == _F_RIGHT or mode == _F_LEFT:
        tau, x, v = _lo_xv(M, S, t)
        y0, w0, ab, hab = S[6], S[7], S[8], S[9]
        wall = M[_B] if mode == _F_RIGHT else -M[_B]
        return y0 + w0 * tau + hab * tau * tau - x - wall, w0 + ab * tau - v
    _, zd, zdd = _zf(M, S, t)
    if mode == _F_ZERO:
        return zd, zdd
    tau = t - td
    if tau == 0.0:
        return zdd, 0.0  # the limit; no slope: the root finder bisects
    return zd / tau, (zdd - zd / tau) / tau


@njit(cache=True, nogil=True)
def _newton(mode, M, S, td, a, b, fa, fb, x0):
    """:func:`.roots.bracketed_newton` on event function ``mode`` (x0 NaN: secant start)."""
    xtol, stall = 1e-14, 1e-11
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if fa * fb > 0:
        raise ValueError("root not bracketed")
    if fa < 0:
        lo, hi = a, b
    else:
        lo, hi = b, a
    x = a - fa * (b - a) / (fb - fa) if math.isnan(x0) else x0
    dx_prev = math.inf
    for _ in range(100):
        fx, dfx = _fev(mode, M, S, x, td)
        if fx == 0.0:
            return x
        if fx < 0:
            lo = x
        else:
            hi = x
        left, right = (lo, hi) if lo < hi else (hi, lo)
        if right - left <= xtol:
            return 0.5 * (left + right)
        if dfx != 0.0:
            dx = fx / dfx
            xn = x - dx
            if left <= xn <= right and (abs(dx) <= xtol or (
                    abs(dx) <= stall and abs(dx) > 0.5 * abs(dx_prev))):
                return xn
            dx_prev = dx
            if left < xn < right:
                x = xn
                continue
        x = 0.5 * (left + right)
    return x


@njit(cache=True, nogil=True)
def _after_extremum(p, q, fp, fq):
    """Root estimate of f on [p, q] when f'(p) = 0: f ~ fp + (fq - fp) ((t - p)/(q - p))^2.

    The secant start is poor there (f is flat at p: Newton from it overshoots and then
    creeps back, halving the error per step); the root of this parabola is not.
    """
    return p + (q - p) * math.sqrt(fp / (fp - fq))


@njit(cache=True, nogil=True)
def _interval(M, S, ta, tb, za, zb, zda, zdb, start_wall, friction, rest):
    """The first event in one grid interval: (time, kind), kind MIDDLE for none."""
    b, t0 = M[_B], S[0]
    # up to two pieces, split at an extremum of z
    two = False
    te = ze = 0.0
    if rest:
        # z'(t0) = 0: find a root of z'/(t - t0), which starts at z''(t0)
        g0, g1 = _zf(M, S, ta)[2], zdb / (tb - ta)
        if g0 * g1 < 0.0:
            te = _newton(_F_ZERO_DEFLATED, M, S, ta, ta, tb, g0, g1, math.nan)
            ze = _zf(M, S, te)[0]
            two = True
    elif zda * zdb < 0.0:
        te = _newton(_F_ZERO, M, S, 0.0, ta, tb, zda, zdb, math.nan)
        ze = _zf(M, S, te)[0]
        two = True
    npieces = 2 if two else 1
    for i in range(npieces):
        if two and i == 0:
            p, zp, q, zq, ends = ta, za, te, ze, True
        elif two:
            p, zp, q, zq, ends = te, ze, tb, zb, False
        else:
            p, zp, q, zq, ends = ta, za, tb, zb, False
        at_start = abs(p - t0) <= 1e-15 * max(1.0, abs(t0))
        if not (at_start and start_wall == RIGHT) and zp - b < 0.0 <= zq - b:
            x0 = _after_extremum(p, q, zp - b, zq - b) if i else math.nan
            return _newton(_F_RIGHT, M, S, 0.0, p, q, zp - b, zq - b, x0), RIGHT
        if not (at_start and start_wall == LEFT) and zp + b > 0.0 >= zq + b:
            x0 = _after_extremum(p, q, zp + b, zq + b) if i else math.nan
            return _newton(_F_LEFT, M, S, 0.0, p, q, zp + b, zq + b, x0), LEFT
        if ends and friction and q - t0 > 1e-12:
            return q, ZERO
    return 0.0, MIDDLE


@njit(cache=True, nogil=True)
def _segment(M, t0, x0, v0, F0):
    """The constants ``S`` of a segment of the LO's flow started at ``t0`` in (x0, v0).

    ``S[0:6]`` = (t0, C1, C2, F0 / k, cv1, cv2): the homogeneous coefficients
    (Oscillator.coefficients) and those of its velocity; ``S[6:10]`` are left for the
    ball's (y0, w0, ab, ab / 2) in a flight, ``S[6]`` for the threshold of a release.
    """
    sg, wd = M[_SG], M[_WD]
    xp, vp = _particular(M, t0, F0)
    h0, hv0 = x0 - xp, v0 - vp
    C1, C2 = h0, (hv0 + sg * h0) / wd
    S = np.zeros(10)
    S[0], S[1], S[2], S[3] = t0, C1, C2, F0 / M[_K]
    S[4], S[5] = C2 * wd - sg * C1, C1 * wd + sg * C2
    return S


@njit(cache=True, nogil=True)
def _window_coeffs(M, S, ta, F0, sign, cz):
    """``sign`` times the coefficients of x(ta + s) on the window basis, into ``cz``.

    :meth:`.flows.Oscillator.window_coeffs`: constant, the harmonics' (v_j / w, x_j)
    at ``ta``, and the homogeneous pair; ``S`` holds the segment's (t0, C1, C2, ., cv1,
    cv2).
    """
    nh = int(M[_NH])
    ncols = cz.size
    cz[0], cz[1], cz[2] = sign * (F0 / M[_K]), sign * 0.0, sign * 0.0
    for j in range(nh):
        w, pa, pb = M[_HEAD + j], M[_HEAD + nh + j], M[_HEAD + 2 * nh + j]
        sn, cs = math.sin(w * ta), math.cos(w * ta)
        cz[3 + 2 * j] = sign * (pa * cs - pb * sn)
        cz[4 + 2 * j] = sign * (pa * sn + pb * cs)
    sg, wd = M[_SG], M[_WD]
    tau = ta - S[0]
    e = math.exp(-sg * tau)
    cs, sn = math.cos(wd * tau), math.sin(wd * tau)
    xh = e * (S[1] * cs + S[2] * sn)
    vh = e * (S[4] * cs - S[5] * sn)
    cz[ncols - 2], cz[ncols - 1] = sign * xh, sign * ((vh + sg * xh) / wd)


@njit(cache=True, nogil=True)
def _matvec(B, c, out):
    """Write B @ c into ``out``, row by row (a window is a few hundred numbers)."""
    for i in range(B.shape[0]):
        acc = 0.0
        for j in range(B.shape[1]):
            acc += B[i, j] * c[j]
        out[i] = acc


@njit(cache=True, nogil=True)
def next_event(M, B01, t0, x0, v0, y0, w0, F0, ab, t_end, start_wall, friction):
    """The first event of the flight that starts at ``t0`` in state (x0, v0, y0, w0).

    Parameters
    ----------
    M : ndarray
        The model's constants (:func:`pack_model`).
    B01 : ndarray, shape (2 (n + 1), ncols)
        The flow's window basis and its derivative (``Oscillator.window_basis``).
    F0, ab : float
        The constant friction force on the LO and the ball's acceleration.
    t_end : float
        End of the simulation.
    start_wall : int
        RIGHT, LEFT or MIDDLE: the wall the flight leaves (not an event at t0).
    friction : bool
        Whether a reversal of z' (ZERO) is an event.

    Returns
    -------
    te, kind, x, v, C1, C2
        Time and kind of the event (RIGHT, LEFT, ZERO, or END at ``t_end``), the LO's
        state there and the homogeneous coefficients of the flight's LO flow.
    """
    n, h = int(M[_N]), M[_H]
    S = _segment(M, t0, x0, v0, F0)
    C1, C2 = S[1], S[2]
    S[6], S[7], S[8], S[9] = y0, w0, ab, 0.5 * ab
    ncols = B01.shape[1]
    cz = np.empty(ncols)
    zz = np.empty(B01.shape[0])
    # a flight that starts with z' = 0 has a root of z' at t0 itself: its first interval
    # is always examined, with that root deflated, so a quick second reversal is not lost
    rest = w0 == v0
    te, kind = t_end, END
    ta = t0
    while ta < t_end:
        # the window's z = y - x: the LO's coefficients negated plus the ball's parabola
        _window_coeffs(M, S, ta, F0, -1.0, cz)
        tau = ta - t0
        cz[0] += y0 + w0 * tau + 0.5 * ab * tau * tau
        cz[1] += w0 + ab * tau
        cz[2] += 0.5 * ab
        _matvec(B01, cz, zz)
        found = False
        for k in range(n):
            zk = zz[k + 1]
            first = k == 0 and rest and ta == t0
            zdk, zdk1 = zz[n + 1 + k], zz[n + 2 + k]
            if not (zk >= M[_B] or zk <= -M[_B] or zdk * zdk1 < 0.0 or first):
                continue
            tev, kev = _interval(M, S, ta + k * h, ta + (k + 1) * h, zz[k], zk, zdk, zdk1,
                                 start_wall, friction, first)
            if kev != MIDDLE:
                if tev >= t_end:
                    break
                te, kind, found = tev, kev, True
                break
        if found:
            break
        ta += n * h
    _, x, v = _lo_xv(M, S, te)
    return te, kind, x, v, C1, C2


@njit(cache=True, nogil=True)
def stuck_release(M, B2, t0, x0, v0, F0, gs, mug, where, t_end):
    """The end of a phase with the ball stuck to the LO (engine._Loop._stuck).

    The ball is released when the friction needed to keep it with the LO, ``q = x'' -
    g sin(theta)`` per unit mass, leaves what the contact can give: ``q > mu g`` on the
    right wall, ``q < -mu g`` on the left one, ``|q| > mu g`` in the middle.

    Parameters
    ----------
    M : ndarray
        The stuck system's constants (:func:`pack_model` of the LO + ball oscillator).
    B2 : ndarray, shape (n + 1, ncols)
        Second derivative of the stuck flow's window basis.
    F0, gs, mug : float
        Constant force on the stuck system, g sin(theta) and mu g.
    where : int
        RIGHT, LEFT or MIDDLE.

    Returns
    -------
    te, s, x, v, C1, C2
        Release time (``t_end`` if none), the sign of the sliding that follows (0 at
        the end), the LO's state at ``te`` and the phase's homogeneous coefficients.
    """
    n, h = int(M[_N]), M[_H]
    S = _segment(M, t0, x0, v0, F0)
    C1, C2 = S[1], S[2]
    ncols = B2.shape[1]
    cz = np.empty(ncols)
    q = np.empty(B2.shape[0])
    ta = t0
    while ta < t_end:
        _window_coeffs(M, S, ta, F0, 1.0, cz)
        _matvec(B2, cz, q)
        q -= gs
        for k in range(1, n + 1):
            qk = q[k]
            if where == RIGHT:
                rel = qk > mug
            elif where == LEFT:
                rel = qk < -mug
            else:
                rel = abs(qk) > mug
            if not rel:
                continue
            thr = mug if qk > 0 else -mug
            lo, hi = ta + (k - 1) * h, ta + k * h
            if (q[k - 1] - thr) * (qk - thr) > 0:   # released already at the start
                te = lo
            else:
                S[6] = gs + thr
                fa = _fev(_F_RELEASE, M, S, lo, 0.0)[0]
                fb = _fev(_F_RELEASE, M, S, hi, 0.0)[0]
                if fa * fb > 0:      # the grid's rounding, not the flow's: the nearer end
                    te = lo if abs(fa) < abs(fb) else hi
                else:
                    te = _newton(_F_RELEASE, M, S, 0.0, lo, hi, fa, fb, math.nan)
            te = min(te, t_end)
            s = -1 if qk > 0 else 1
            if te >= t_end:
                s = 0
            _, x, v = _lo_xv(M, S, te)
            return te, s, x, v, C1, C2
        ta += n * h
    _, x, v = _lo_xv(M, S, t_end)
    return t_end, 0, x, v, C1, C2
