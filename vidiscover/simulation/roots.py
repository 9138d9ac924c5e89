"""Bracketed scalar root finding for the event loop.

A safeguarded Newton iteration (Newton steps kept inside a shrinking bracket,
bisection when a step leaves it) converges in a handful of evaluations for the
smooth closed-form event functions, far fewer than derivative-free methods.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["bracketed_newton"]


def bracketed_newton(f: Callable[[float], tuple[float, float]], a: float, b: float,
                     fa: float, fb: float, xtol: float = 1e-14, maxiter: int = 100,
                     x0: float | None = None, stall: float = 1e-11) -> float:
    """Root of ``f`` in ``[a, b]`` where ``f(a)`` and ``f(b)`` differ in sign.

    Parameters
    ----------
    f : callable
        Returns ``(value, derivative)`` at a point.
    a, b : float
        Bracket, ``a < b``.
    fa, fb : float
        ``f`` at the ends (already known to the caller); ``fa * fb <= 0``.
    xtol : float
        Absolute tolerance on the root.
    maxiter : int
        Iteration bound (bisection guarantees convergence well before it).
    x0 : float, optional
        First iterate (default: the secant point of the bracket). Inside ``[a, b]``.
    stall : float
        Newton steps below this that shrink by less than half are taken as the
        rounding noise of ``f`` near the root: the iteration stops there.

    Returns
    -------
    float
        The root.
    """
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if fa * fb > 0:
        raise ValueError(f"root not bracketed: f(a)={fa!r}, f(b)={fb!r}")
    lo, hi = (a, b) if fa < 0 else (b, a)  # f(lo) < 0 < f(hi)
    x = a - fa * (b - a) / (fb - fa) if x0 is None else x0  # secant start
    dx_prev = float("inf")
    for _ in range(maxiter):
        fx, dfx = f(x)
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
                # converged, or stalled: a tiny step that no longer shrinks
                # quadratically is the rounding noise of f, not progress
                return xn
            dx_prev = dx
            # a Newton step must land strictly inside the bracket: at the rounding
            # noise of f it can bounce between the two ends forever (bisect instead)
            if left < xn < right:
                x = xn
                continue
        x = 0.5 * (left + right)
    return x
