"""Acquisition model: how an accelerometer chain renders one impact.

An impact changes the LO velocity by ``dv`` during a contact of duration ``tau``
(a half-sine force pulse of unit area starting at the contact entry); the
accelerometer's anti-alias filter turns it into the sampled pulse ``dv * g(t)``.
This module is the one place that says what ``g`` is, for the sensor model (which
renders pulses) and for the analysis (which fits them):

* ``linear-phase``: a Kaiser-windowed sinc low-pass (delay-compensated, as in
  delta-sigma front ends): symmetric about the contact midpoint, no delay;
* ``butter``, ``bessel`` (phase-normalised), ``cheby1`` (0.5 dB ripple): causal
  analog all-pole low-passes of order 2-8, ``H(s) = K / prod(s - p_i)``, scaled to
  unit DC gain (unit area), whose impulse response ``sum_i r_i exp(p_i t)`` is exact.
  The response to the half-sine is exact too (each pole term integrates in closed
  form). Its centroid is the DC group delay ``sum_i -1/p_i`` plus ``tau / 2``.

Times are in samples and cut-offs in fractions of the sampling rate, so one
response serves every sampling rate.

Examples
--------
>>> import numpy as np
>>> t = np.arange(0, 400) / 16.0                    # samples
>>> g = pulse_response(t, "butter", 4, 0.39, 0.0)
>>> round(float(np.sum(g) / 16.0), 3)               # unit area
1.0
>>> round(float(np.sum(t * g) / np.sum(g)), 3) == round(dc_group_delay("butter", 4, 0.39), 3)
True
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.special import i0 as _i0

from .errors import InputError

__all__ = ["FILTER_KINDS", "CAUSAL_KINDS", "CHEBY1_RIPPLE_DB", "pulse_kernel", "pulse_response",
           "pulse_responses",
           "dc_group_delay", "check_filter"]

#: Anti-alias filter kinds (``--anti-alias KIND:ORDER:CUTOFF_HZ``; the README's
#: 'Realistic recordings').
FILTER_KINDS = ("linear-phase", "butter", "bessel", "cheby1")
#: The causal analog kinds.
CAUSAL_KINDS = ("butter", "bessel", "cheby1")
#: Pass-band ripple of the Chebyshev type I filters (dB).
CHEBY1_RIPPLE_DB = 0.5
#: Kaiser window parameter of the linear-phase kernel.
_KAISER_BETA = 8.0

_GAUSS16 = np.polynomial.legendre.leggauss(16)


def check_filter(kind: str, order: int, cutoff: float) -> None:
    """Raise :class:`InputError` unless (kind, order, cutoff) is an acquisition filter.

    Parameters
    ----------
    kind : str
        One of :data:`FILTER_KINDS`.
    order : int
        Filter order, 2-8 for the causal kinds (ignored for ``linear-phase``).
    cutoff : float
        Cut-off as a fraction of the sampling rate, in (0, 0.5).
    """
    if kind not in FILTER_KINDS:
        raise InputError(f"anti-alias kind must be one of {', '.join(FILTER_KINDS)}, "
                         f"was {kind!r}")
    if kind in CAUSAL_KINDS and not (isinstance(order, (int, np.integer)) and 2 <= order <= 8):
        raise InputError(f"anti-alias order must be an integer in [2, 8], was {order!r}")
    if not (isinstance(cutoff, (int, float, np.floating)) and 0 < cutoff < 0.5):
        raise InputError(f"cutoff must be in (0, 0.5) of the sampling rate, was {cutoff!r}")


def pulse_kernel(dt_samples: np.ndarray, sample_rate: float, cutoff: float, tau: float,
                 halfwidth: int) -> np.ndarray:
    """Sampled response (1/s) of the linear-phase chain to a unit-area impact pulse.

    The contact half-sine of width ``tau`` is centred on the pulse centre.

    Parameters
    ----------
    dt_samples : ndarray
        Sample times minus the pulse centre (s).
    sample_rate : float
        Sampling rate (Hz).
    cutoff : float
        Anti-alias cut-off as a fraction of the sampling rate.
    tau : float
        Contact duration (s); 0 for an instantaneous impact.
    halfwidth : int
        Kernel half-width (samples); the kernel is 0 beyond it.

    Returns
    -------
    ndarray
        Kernel values; they sum to about ``sample_rate`` (unit area).
    """
    fc = cutoff * sample_rate
    span = halfwidth / sample_rate

    def lowpass(t):
        win = np.where(np.abs(t) < span,
                       _i0(_KAISER_BETA * np.sqrt(np.clip(1 - (t / span) ** 2, 0, None)))
                       / _i0(_KAISER_BETA), 0.0)
        return 2 * fc * np.sinc(2 * fc * t) * win

    if tau <= 0:
        return lowpass(dt_samples)
    nodes, weights = _GAUSS16
    s = 0.5 * tau * nodes                                        # pulse on [-tau/2, tau/2]
    p = (math.pi / (2 * tau)) * np.cos(math.pi * s / tau) * 0.5 * tau * weights
    return np.tensordot(lowpass(dt_samples[..., None] - s), p, axes=([-1], [0]))


@functools.lru_cache(maxsize=64)
def _unit_poles(kind: str, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Poles and residues (unit DC gain) of the low-pass at 1 rad per sample."""
    from scipy import signal

    if kind == "butter":
        _, p, k = signal.butter(order, 1.0, analog=True, output="zpk")
    elif kind == "bessel":
        _, p, k = signal.bessel(order, 1.0, analog=True, output="zpk", norm="phase")
    elif kind == "cheby1":
        _, p, k = signal.cheby1(order, CHEBY1_RIPPLE_DB, 1.0, analog=True, output="zpk")
    else:
        raise InputError(f"{kind!r} is not a causal anti-alias kind ({', '.join(CAUSAL_KINDS)})")
    p = np.asarray(p, dtype=complex)
    k = np.prod(-p).real                           # unit DC gain: H(0) = 1
    res = np.array([k / np.prod(p[i] - np.delete(p, i)) for i in range(p.size)])
    p.flags.writeable = False
    res.flags.writeable = False
    return p, res


def _poles(kind: str, order: int, cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """Poles (1/sample) and residues of the unit-DC-gain all-pole low-pass.

    A low-pass at ``wc`` is the one at 1 rad/sample with time scaled by ``wc``:
    poles and residues scale by ``wc``.
    """
    p, res = _unit_poles(kind, int(order))
    wc = 2 * math.pi * cutoff
    return p * wc, res * wc


def _exp_outer(t: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``exp(outer(t, p))``; on a uniform 1-D grid by a running product (faster)."""
    if t.ndim == 1 and t.size > 32:
        step = (t[-1] - t[0]) / (t.size - 1)
        if step > 0 and np.abs(np.diff(t) - step).max() <= 1e-9 * max(1.0, abs(t[-1])):
            z = np.empty((t.size, p.size), dtype=complex)
            z[0] = np.exp(p * t[0])
            z[1:] = np.exp(p * step)
            return np.cumprod(z, axis=0)
    return np.exp(np.multiply.outer(t, p))


def _exp_rows(t: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``exp(t[m, n] * P[m, k])``, an (M, N, K) array.

    By running products from the first positive point when every row is a uniform
    grid clipped at 0 (faster than ``exp``).
    """
    M, N = t.shape
    step = t[:, -1:] - t[:, -2:-1] if N > 32 else None
    if step is not None and (step > 0).all():
        j0 = np.argmax(t > 0, axis=1)                       # first point past the clip
        n = np.arange(N)[None, :] - j0[:, None]
        uniform = np.abs(np.where(n >= 0, t - (t[np.arange(M), j0][:, None] + n * step), 0))
        if uniform.max() <= 1e-9 * max(1.0, float(np.abs(t).max())):
            z = np.empty((M, N, P.shape[1]), dtype=complex)
            z[:] = np.exp(P[:, None, :] * step[:, :, None])
            z[np.arange(M), j0] = np.exp(P * t[np.arange(M), j0][:, None])
            first = np.arange(N)[None, :] < j0[:, None]
            z[first] = 1.0
            return np.cumprod(z, axis=1)
    return np.exp(t[..., None] * P[:, None, :])


def dc_group_delay(kind: str, order: int, cutoff: float) -> float:
    """DC group delay (samples) of a causal kind: the centroid of its impulse response.

    ``-H'(0) / H(0) = sum_i -1/p_i`` for ``H(s) = K / prod(s - p_i)``; 0 for
    ``linear-phase`` (delay-compensated).
    """
    if kind == "linear-phase":
        return 0.0
    p, _ = _poles(kind, int(order), float(cutoff))
    return float(np.sum(-1.0 / p).real)


def pulse_response(t: np.ndarray, kind: str, order: int, cutoff: float, tau: float,
                   halfwidth: int = 24) -> np.ndarray:
    """Response (1/sample) of an anti-alias filter to a unit-area contact pulse.

    Parameters
    ----------
    t : ndarray
        Times (samples) from the contact entry (causal kinds) or from the contact
        midpoint (``linear-phase``).
    kind : str
        One of :data:`FILTER_KINDS`.
    order : int
        Order of a causal kind (2-8).
    cutoff : float
        Cut-off as a fraction of the sampling rate.
    tau : float
        Contact duration (samples), 0 for an instantaneous impact.
    halfwidth : int
        Half-width (samples) of the ``linear-phase`` kernel.

    Returns
    -------
    ndarray
        Response values, integrating to 1 over t (in samples).
    """
    check_filter(kind, order, cutoff)
    t = np.asarray(t, dtype=float)
    if kind == "linear-phase":
        return pulse_kernel(t, 1.0, cutoff, tau, halfwidth)
    p, res = _poles(kind, int(order), float(cutoff))
    out = np.zeros(t.shape)
    pos = t >= 0
    tp = t[pos]
    E = _exp_outer(tp, p)                                # (m, order)
    if tau <= 0:
        out[pos] = (E @ res).real
        return out
    # half-sine f(s) = (pi / 2 tau) sin(pi s / tau) on [0, tau]; per pole
    # int_0^u f(s) e^{p (t - s)} ds in closed form, u = min(t, tau):
    # c (w e^{p t} - p sin(w t) - w cos(w t)) during the contact,
    # c w (1 + e^{-p tau}) e^{p t} after it, with c = r w / (2 (p^2 + w^2))
    w = math.pi / tau
    c = res * (0.5 * w) / (p * p + w * w)
    late = tp > tau
    vals = np.empty(tp.shape)
    vals[late] = (E[late] @ (c * w * (1.0 + np.exp(-p * tau)))).real
    early = ~late
    te = tp[early]
    vals[early] = ((E[early] @ (c * w)).real - np.sin(w * te) * np.sum(c * p).real
                   - w * np.cos(w * te) * np.sum(c).real)
    out[pos] = vals
    return out


def pulse_responses(t: np.ndarray, kind: str, order: int, cutoffs: np.ndarray,
                    taus: np.ndarray, halfwidth: int = 24) -> np.ndarray:
    """:func:`pulse_response` of many (cut-off, contact duration) pairs at once.

    Parameters
    ----------
    t : ndarray
        Times (samples), shape (M, N): row m for the m-th pair (from the contact
        entry for the causal kinds, from the contact midpoint for ``linear-phase``).
    kind, order : str, int
        The filter family (as :func:`pulse_response`).
    cutoffs, taus : ndarray
        Shape (M,): cut-offs (fraction of the sampling rate) and contact durations
        (samples, >= 0).
    halfwidth : int
        Half-width (samples) of the ``linear-phase`` kernel.

    Returns
    -------
    ndarray
        Shape (M, N), equal to :func:`pulse_response` row by row.
    """
    t = np.asarray(t, dtype=float)
    fc = np.asarray(cutoffs, dtype=float)[:, None]
    tau = np.asarray(taus, dtype=float)[:, None]
    if kind == "linear-phase":
        # the half-sine by 16-point Gauss quadrature (exact limit at tau = 0)
        nodes, weights = _GAUSS16
        p = 0.25 * math.pi * np.cos(0.5 * math.pi * nodes) * weights
        u = t[..., None] - (0.5 * tau * nodes)[:, None, :]           # (M, N, 16)
        # the window does not depend on the cut-off: once per distinct (tau, t) row
        _, first, inv = np.unique(np.column_stack([tau, t]), axis=0, return_index=True,
                                  return_inverse=True)
        uu = u[first]
        win = np.where(np.abs(uu) < halfwidth,
                       _i0(_KAISER_BETA * np.sqrt(np.clip(1 - (uu / halfwidth) ** 2, 0, None)))
                       / _i0(_KAISER_BETA), 0.0)[inv.ravel()]
        return (2 * fc[..., None] * np.sinc(2 * fc[..., None] * u) * win) @ p
    pu, ru = _unit_poles(kind, int(order))
    wc = 2 * math.pi * fc                                             # (M, 1)
    P, R = pu[None, :] * wc, ru[None, :] * wc                         # (M, K)
    tp = np.maximum(t, 0.0)
    E = _exp_rows(tp, P)                                              # (M, N, K)
    out = np.zeros(t.shape)
    inst = tau[:, 0] <= 0
    if inst.any():
        out[inst] = np.einsum("mnk,mk->mn", E[inst], R[inst]).real
    wide = ~inst
    if wide.any():
        T, Pw, Rw, tw = tau[wide], P[wide], R[wide], tp[wide]
        w = math.pi / T                                               # (M', 1)
        c = Rw * (0.5 * w) / (Pw * Pw + w * w)
        late = np.einsum("mnk,mk->mn", E[wide], c * w * (1.0 + np.exp(-Pw * T))).real
        early = (np.einsum("mnk,mk->mn", E[wide], c * w).real
                 - np.sin(w * tw) * np.sum(c * Pw, axis=1, keepdims=True).real
                 - w * np.cos(w * tw) * np.sum(c, axis=1, keepdims=True).real)
        out[wide] = np.where(tw > T, late, early)
    return np.where(t >= 0, out, 0.0)
