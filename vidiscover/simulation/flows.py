"""Closed-form flows between events.

The LO obeys ``m x'' + c x' + k x = c xe' + k xe + F0`` with a base motion
``xe = Im(sum_j B_j exp(i w_j t))`` and a constant force ``F0``; its solution is a
particular (steady harmonic + static) part plus a damped homogeneous part fixed by
the state at the start of the segment. The ball has constant acceleration.

Everything works on scalars (``math``, fast in the event loop) and on arrays
(``numpy``, for grids and for sampling a whole record).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["BaseMotion", "Oscillator"]


@dataclass(frozen=True)
class BaseMotion:
    """Base displacement ``xe(t) = A sum_j h_j sin(j w t + phi_j)``.

    Parameters
    ----------
    amplitude : float
        A (m).
    frequency : float
        f (Hz), w = 2 pi f.
    harmonics : tuple of (order, relative amplitude, phase)
        Order 1 first; pure sine is ``((1, 1.0, 0.0),)``.
    """

    amplitude: float
    frequency: float
    harmonics: tuple = ((1, 1.0, 0.0),)

    @property
    def omegas(self) -> np.ndarray:
        """Angular frequencies of the harmonics (rad/s)."""
        return np.array([n * 2 * math.pi * self.frequency for n, _, _ in self.harmonics])

    @property
    def complex_amplitudes(self) -> np.ndarray:
        """B_j such that xe = Im(sum B_j exp(i w_j t))."""
        return np.array([self.amplitude * h * np.exp(1j * ph) for _, h, ph in self.harmonics])

    def displacement(self, t, trig=None):
        """xe(t) (m); ``trig``: the (sin w_j t, cos w_j t) pairs if already evaluated."""
        t = np.asarray(t, dtype=float)
        out = np.zeros_like(t)
        for j, (w, bj) in enumerate(zip(self.omegas, self.complex_amplitudes)):
            sn, cs = trig[j] if trig is not None else (np.sin(w * t), np.cos(w * t))
            out += bj.real * sn + bj.imag * cs
        return out

    def trig(self, t: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """(sin w_j t, cos w_j t) of every harmonic: shared by the LO's and the base's flows."""
        return [(np.sin(w * t), np.cos(w * t)) for w in self.omegas]


class Oscillator:
    """A damped linear oscillator of mass ``m`` driven through its base.

    Parameters
    ----------
    m, c, k : float
        Mass, damping, stiffness.
    base : BaseMotion
        Base displacement.
    """

    def __init__(self, m: float, c: float, k: float, base: BaseMotion) -> None:
        self.m, self.c, self.k = m, c, k
        self.sigma = c / (2.0 * m)
        self.wd = math.sqrt(k / m - self.sigma ** 2)
        w = base.omegas
        p = base.complex_amplitudes * (k + 1j * c * w) / (k - m * w ** 2 + 1j * c * w)
        # x_p = sum (pa sin(w t) + pb cos(w t)) + F0/k
        self.w = w
        self.pa = p.real.copy()
        self.pb = p.imag.copy()
        self._terms = list(zip(w.tolist(), self.pa.tolist(), self.pb.tolist()))
        self._basis_cache: dict = {}

    # -- particular solution --------------------------------------------------------
    def particular(self, t: float, F0: float) -> tuple[float, float, float]:
        """Scalar (x_p, x_p', x_p'') at time ``t`` with constant force ``F0``."""
        x = F0 / self.k
        v = a = 0.0
        for w, pa, pb in self._terms:
            s, c = math.sin(w * t), math.cos(w * t)
            x += pa * s + pb * c
            v += w * (pa * c - pb * s)
            a -= w * w * (pa * s + pb * c)
        return x, v, a

    def particular_array(self, t: np.ndarray, F0, trig=None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorised (x_p, x_p', x_p''); ``F0`` may be an array matching ``t``.

        ``trig``: the (sin w_j t, cos w_j t) pairs if already evaluated
        (:meth:`BaseMotion.trig`).
        """
        x = np.asarray(F0, dtype=float) / self.k + np.zeros_like(t)
        v = np.zeros_like(t)
        a = np.zeros_like(t)
        for j, (w, pa, pb) in enumerate(self._terms):
            s, c = trig[j] if trig is not None else (np.sin(w * t), np.cos(w * t))
            x += pa * s + pb * c
            v += w * (pa * c - pb * s)
            a -= w * w * (pa * s + pb * c)
        return x, v, a

    # -- a segment: homogeneous coefficients from the initial state -----------------
    def coefficients(self, t0: float, x0: float, v0: float, F0: float) -> tuple[float, float]:
        """Homogeneous coefficients (C1, C2) for state (x0, v0) at ``t0``."""
        xp, vp, _ = self.particular(t0, F0)
        h0, hv0 = x0 - xp, v0 - vp
        return h0, (hv0 + self.sigma * h0) / self.wd

    def state(self, t: float, t0: float, C1: float, C2: float, F0: float
              ) -> tuple[float, float, float]:
        """Scalar (x, x', x'') at ``t`` of the segment started at ``t0``."""
        xp, vp, ap = self.particular(t, F0)
        tau = t - t0
        e = math.exp(-self.sigma * tau)
        cs, sn = math.cos(self.wd * tau), math.sin(self.wd * tau)
        sg, wd = self.sigma, self.wd
        xh = e * (C1 * cs + C2 * sn)
        vh = e * ((C2 * wd - sg * C1) * cs - (C1 * wd + sg * C2) * sn)
        ah = -2.0 * sg * vh - (self.k / self.m) * xh
        return xp + xh, vp + vh, ap + ah

    def state_array(self, t: np.ndarray, t0, C1, C2, F0, trig=None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorised (x, x', x''); segment values may be arrays matching ``t``."""
        xp, vp, ap = self.particular_array(t, F0, trig)
        tau = t - t0
        e = np.exp(-self.sigma * tau)
        cs, sn = np.cos(self.wd * tau), np.sin(self.wd * tau)
        sg, wd = self.sigma, self.wd
        xh = e * (C1 * cs + C2 * sn)
        vh = e * ((C2 * wd - sg * C1) * cs - (C1 * wd + sg * C2) * sn)
        ah = -2.0 * sg * vh - (self.k / self.m) * xh
        return xp + xh, vp + vh, ap + ah

    # -- windows: the flow on a uniform grid as basis matrix @ coefficients --------
    def window_basis(self, h: float, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Basis of the flow on the grid ``s = 0, h, ..., n h`` and its derivatives.

        Columns: 1, s, s^2, (sin w_j s, cos w_j s) per harmonic, and the damped
        homogeneous pair exp(-sigma s) (cos, sin)(wd s). Any LO or ball trajectory of
        a segment, restricted to a window starting at ``ta``, is ``B @ c`` with
        ``c`` from :meth:`window_coeffs` (plus the ball's polynomial).
        """
        key = (h, n)
        if key not in self._basis_cache:
            s = h * np.arange(n + 1)
            one, zero = np.ones_like(s), np.zeros_like(s)
            c0 = [one, s, s * s]
            c1 = [zero, one, 2 * s]
            c2 = [zero, zero, 2 * one]
            for w in self.w:
                sn, cs = np.sin(w * s), np.cos(w * s)
                c0 += [sn, cs]
                c1 += [w * cs, -w * sn]
                c2 += [-w * w * sn, -w * w * cs]
            sg, wd = self.sigma, self.wd
            e = np.exp(-sg * s)
            cs, sn = np.cos(wd * s), np.sin(wd * s)
            c0 += [e * cs, e * sn]
            c1 += [e * (-sg * cs - wd * sn), e * (-sg * sn + wd * cs)]
            k2 = sg * sg - wd * wd
            c2 += [e * (k2 * cs + 2 * sg * wd * sn), e * (k2 * sn - 2 * sg * wd * cs)]
            self._basis_cache[key] = tuple(np.ascontiguousarray(np.stack(c, axis=1))
                                           for c in (c0, c1, c2))
        return self._basis_cache[key]

    def window_coeffs(self, ta: float, t0: float, C1: float, C2: float, F0: float) -> list:
        """Coefficients of x(ta + s) on the :meth:`window_basis` columns."""
        coef = [F0 / self.k, 0.0, 0.0]
        xp = vp = 0.0
        for w, pa, pb in self._terms:
            sn, cs = math.sin(w * ta), math.cos(w * ta)
            xj = pa * sn + pb * cs
            vj = pa * cs - pb * sn  # v_j / w
            coef += [vj, xj]
            xp += xj
            vp += w * vj
        tau = ta - t0
        e = math.exp(-self.sigma * tau)
        cs, sn = math.cos(self.wd * tau), math.sin(self.wd * tau)
        sg, wd = self.sigma, self.wd
        xh = e * (C1 * cs + C2 * sn)
        vh = e * ((C2 * wd - sg * C1) * cs - (C1 * wd + sg * C2) * sn)
        coef += [xh, (vh + sg * xh) / wd]
        return coef
