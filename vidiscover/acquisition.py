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
           "pulse_responses", "contact_shape", "kelvin_voigt_shape", "shape_centroid",
           "dc_group_delay", "check_filter", "max_cutoff"]

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
        Cut-off as a fraction of the sampling rate, in (0, :func:`max_cutoff`): 0.5,
        or for ``bessel`` up to where its -3 dB point reaches the Nyquist frequency.
    """
    if kind not in FILTER_KINDS:
        raise InputError(f"anti-alias kind must be one of {', '.join(FILTER_KINDS)}, "
                         f"was {kind!r}")
    if kind in CAUSAL_KINDS and not (isinstance(order, (int, np.integer)) and 2 <= order <= 8):
        raise InputError(f"anti-alias order must be an integer in [2, 8], was {order!r}")
    hi = max_cutoff(kind, order)
    if not (isinstance(cutoff, (int, float, np.floating)) and 0 < cutoff < hi):
        what = (f"(0, {hi:.4f}) of the sampling rate for {kind}-{order} (its -3 dB point "
                f"below the Nyquist frequency)" if hi != 0.5 else "(0, 0.5) of the sampling rate")
        raise InputError(f"cutoff must be in {what}, was {cutoff!r}")


def max_cutoff(kind: str, order: int) -> float:
    """Largest cut-off (fraction of the sampling rate, exclusive) of a filter family.

    0.5 (the Nyquist frequency) for every kind but ``bessel``: its phase-normalised
    cut-off lies above its -3 dB point (by 1.27x at order 2 to 1.93x at order 8), and
    anti-alias Bessels are specified by the -3 dB point, which may lie near the
    Nyquist frequency (a Bessel-4 "at 2800 Hz" sampled at 6400 Hz is 0.66 fs here).
    Its limit is the cut-off whose -3 dB point is the Nyquist frequency.
    """
    if kind != "bessel" or not (isinstance(order, (int, np.integer)) and 2 <= order <= 8):
        return 0.5
    return 0.5 / _bessel_3db(int(order))


@functools.cache
def _bessel_3db(order: int) -> float:
    """-3 dB frequency of the phase-normalised Bessel low-pass, in units of its cut-off."""
    from scipy.optimize import brentq  # (only when a Bessel is checked)

    p, _ = _unit_poles("bessel", order)                # cut-off 1 rad/sample

    def excess(w):                                     # |H(jw)|^2 - 1/2, falls monotonically
        return float(np.prod(np.abs(p) ** 2 / np.abs(1j * w - p) ** 2)) - 0.5

    return float(brentq(excess, 0.1, 1.0, xtol=1e-15, rtol=4 * np.finfo(float).eps))


def pulse_kernel(dt_samples: np.ndarray, sample_rate: float, cutoff: float, tau: float,
                 halfwidth: int, skew: float = 0.0, phase: float = 0.0) -> np.ndarray:
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
    skew, phase : float
        Contact force shape (:func:`contact_shape`); 0, 0 is the half-sine.

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
    nodes, _ = _GAUSS16
    s = 0.5 * tau * nodes                                        # pulse on [-tau/2, tau/2]
    p = _shape_weights(np.array([float(skew)]), np.array([float(phase)]))[0]
    return np.tensordot(lowpass(dt_samples[..., None] - s), p, axes=([-1], [0]))


def contact_shape(s: np.ndarray, tau: float, skew: float = 0.0,
                  phase: float = 0.0) -> np.ndarray:
    """Contact force of unit impulse over ``0 <= s <= tau``: a damped sine arch.

    ``f(s) = N exp(-skew w s) sin(w s + phase)`` with ``w = (pi - phase) / tau``, so
    that the force ends at zero at ``tau``. ``skew = phase = 0`` is the half-sine of
    a linear elastic contact; ``skew > 0`` loads the contact's start (Hunt-Crossley
    with large alpha v), ``skew < 0`` its end; ``phase > 0`` makes the force jump at
    entry, as a viscous wall's does: a Kelvin-Voigt wall of damping ratio zeta is
    exactly ``skew = zeta / sqrt(1 - zeta^2)``, ``phase = 2 asin(zeta)``
    (:func:`kelvin_voigt_shape`).
    """
    s = np.asarray(s, dtype=float)
    w = (math.pi - phase) / tau
    g = skew * w
    norm = 1.0 / _arch_area(g, w, phase, tau)
    return np.where((s >= 0) & (s <= tau), norm * np.exp(-g * s) * np.sin(w * s + phase), 0.0)


def kelvin_voigt_shape(zeta: float) -> tuple[float, float]:
    """(skew, phase) of the contact force of a Kelvin-Voigt wall of damping ratio zeta."""
    return zeta / math.sqrt(1.0 - zeta * zeta), 2.0 * math.asin(zeta)


def _arch_area(g, w, phase, tau):
    """Integral of ``exp(-g s) sin(w s + phase)`` over [0, tau] (real g, w)."""
    return (np.exp(1j * phase) * (np.exp((1j * w - g) * tau) - 1.0) / (1j * w - g)).imag


def shape_centroid(skew, phase=0.0):
    """Centroid of :func:`contact_shape` as a fraction of the contact duration."""
    nodes, _ = _GAUSS16
    sk = np.atleast_1d(np.asarray(skew, dtype=float))
    p = _shape_weights(sk, np.broadcast_to(np.asarray(phase, dtype=float), sk.shape))
    out = p @ (0.5 * (1.0 + nodes))
    return out if np.ndim(skew) else float(out[0])


def _shape_weights(skews: np.ndarray, phases: np.ndarray | None = None) -> np.ndarray:
    """Gauss-Legendre weights (M, 16) of the contact shapes on [-1, 1], summing to 1."""
    nodes, weights = _GAUSS16
    base = 0.25 * math.pi * np.cos(0.5 * math.pi * nodes) * weights
    skews = np.asarray(skews, dtype=float)
    phases = np.zeros(skews.shape) if phases is None else np.asarray(phases, dtype=float)
    bent = (skews != 0) | (phases != 0)
    p = np.broadcast_to(base, (skews.size, base.size)).copy()
    if bent.any():
        x = 0.5 * (1.0 + nodes)                                    # s / tau
        ph = phases[bent][:, None]
        arch = (np.exp(-skews[bent][:, None] * (math.pi - ph) * x)
                * np.sin((math.pi - ph) * x + ph)) * weights
        p[bent] = arch / arch.sum(axis=1, keepdims=True)
    return p


@functools.lru_cache(maxsize=64)
def _unit_poles(kind: str, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Poles and residues (unit DC gain) of the low-pass at 1 rad per sample.

    The poles are scipy.signal's, tabulated in :mod:`vidiscover._prototypes` for the
    orders the instrument models allow (importing scipy.signal costs 0.5-0.9 s).
    """
    from ._prototypes import POLES, scipy_poles

    if kind not in CAUSAL_KINDS:
        raise InputError(f"{kind!r} is not a causal anti-alias kind ({', '.join(CAUSAL_KINDS)})")
    table = POLES.get((kind, order))
    if table is not None:
        p = np.array([complex(re, im) for re, im in table], dtype=complex)
    else:
        p = np.asarray(scipy_poles(kind, order, CHEBY1_RIPPLE_DB), dtype=complex)
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
        # |t - (t[j0] + n step)| where n >= 0, else 0 (in one buffer)
        dev = np.multiply(n, step)
        np.add(t[np.arange(M), j0][:, None], dev, out=dev)
        np.subtract(t, dev, out=dev)
        np.abs(dev, out=dev)
        first = n < 0
        dev[first] = 0.0
        if dev.max() <= 1e-9 * max(1.0, float(max(t.max(), -t.min()))):
            z = np.empty((M, N, P.shape[1]), dtype=complex)
            z[:] = np.exp(P[:, None, :] * step[:, :, None])
            z[np.arange(M), j0] = np.exp(P * t[np.arange(M), j0][:, None])
            np.copyto(z, 1.0, where=first[:, :, None])
            return np.cumprod(z, axis=1, out=z)
    return np.exp(t[..., None] * P[:, None, :])


def dc_group_delay(kind: str, order: int, cutoff: float, mount: float = 0.0,
                   mount_zeta: float = 0.02) -> float:
    """DC group delay (samples) of a causal kind: the centroid of its impulse response.

    ``-H'(0) / H(0) = sum_i -1/p_i`` for ``H(s) = K / prod(s - p_i)``; 0 for
    ``linear-phase`` (delay-compensated). A mounted resonance at ``mount`` (fraction
    of the sampling rate) adds ``2 mount_zeta / w``.
    """
    if kind == "linear-phase":
        return 0.0
    p, _ = _poles(kind, int(order), float(cutoff))
    extra = 2.0 * mount_zeta / (2 * math.pi * mount) if mount > 0 else 0.0
    return float(np.sum(-1.0 / p).real) + extra


def _mount_poles(mount: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """Pole pairs (M, 2), 1/sample, of mounted resonances at ``mount`` x the sampling rate."""
    w = 2 * math.pi * np.asarray(mount, dtype=float)[:, None]
    z = np.asarray(zeta, dtype=float)[:, None]
    wd = w * np.sqrt(1.0 - z * z)
    return np.concatenate([-z * w + 1j * wd, -z * w - 1j * wd], axis=1)


def _residues(P: np.ndarray) -> np.ndarray:
    """Residues (M, K) of the unit-DC-gain all-pole systems with poles ``P`` (M, K)."""
    D = P[:, :, None] - P[:, None, :]
    K = P.shape[1]
    D[:, np.arange(K), np.arange(K)] = 1.0
    return np.prod(-P, axis=1, keepdims=True) / np.prod(D, axis=2)


def pulse_response(t: np.ndarray, kind: str, order: int, cutoff: float, tau: float,
                   halfwidth: int = 24, skew: float = 0.0, phase: float = 0.0,
                   mount: float = 0.0, mount_zeta: float = 0.02) -> np.ndarray:
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
    skew, phase : float
        Shape of the contact force (:func:`contact_shape`); 0, 0: half-sine.
    mount, mount_zeta : float
        A mounted accelerometer resonance ``w^2 / (s^2 + 2 zeta w s + w^2)`` before
        the filter, at ``mount`` times the sampling rate (0: rigid mount; causal
        kinds only).

    Returns
    -------
    ndarray
        Response values, integrating to 1 over t (in samples).
    """
    check_filter(kind, order, cutoff)
    t = np.asarray(t, dtype=float)
    if kind == "linear-phase":
        return pulse_kernel(t, 1.0, cutoff, tau, halfwidth, skew, phase)
    if (tau > 0 and (skew != 0 or phase != 0)) or mount > 0:
        return pulse_responses(t.reshape(1, -1), kind, order, np.array([cutoff]),
                               np.array([tau]), halfwidth, np.array([skew]),
                               np.array([phase]), np.array([mount]),
                               np.array([mount_zeta]))[0].reshape(t.shape)
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


def _scaled_sinc(c: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``c * np.sinc(c * u)``, the same operations as numpy's, in one buffer.

    (numpy's ``sinc`` makes three temporaries the size of ``u``; these grids are
    large.)
    """
    x = np.multiply(c, u)
    np.multiply(math.pi, x, out=x)
    zero = x == 0
    if zero.any():
        x[zero] = np.finfo(x.dtype).eps
    y = np.sin(x)
    np.divide(y, x, out=y)
    return np.multiply(c, y, out=y)


def _kaiser(u: np.ndarray, halfwidth: float) -> np.ndarray:
    """The linear-phase kernel's Kaiser window at times ``u`` (samples)."""
    return np.where(np.abs(u) < halfwidth,
                    _i0(_KAISER_BETA * np.sqrt(np.clip(1 - (u / halfwidth) ** 2, 0, None)))
                    / _i0(_KAISER_BETA), 0.0)


def pulse_responses(t: np.ndarray, kind: str, order: int, cutoffs: np.ndarray,
                    taus: np.ndarray, halfwidth: int = 24,
                    skews: np.ndarray | None = None,
                    phases: np.ndarray | None = None, mounts: np.ndarray | None = None,
                    mount_zetas: np.ndarray | None = None) -> np.ndarray:
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
    skews, phases : ndarray, optional
        Shape (M,): contact force shapes (:func:`contact_shape`); default 0.
    mounts, mount_zetas : ndarray, optional
        Shape (M,): mounted resonances (as :func:`pulse_response`); default none.

    Returns
    -------
    ndarray
        Shape (M, N), equal to :func:`pulse_response` row by row.
    """
    t = np.asarray(t, dtype=float)
    fc = np.asarray(cutoffs, dtype=float)[:, None]
    tau = np.asarray(taus, dtype=float)[:, None]
    skew = np.zeros(fc.shape[0]) if skews is None else np.asarray(skews, dtype=float)
    phase = np.zeros(fc.shape[0]) if phases is None else np.asarray(phases, dtype=float)
    if kind == "linear-phase":
        # the contact shape by 16-point Gauss quadrature (exact limit at tau = 0, where
        # the 16 nodes coincide and one evaluation does)
        out = np.empty(t.shape)
        inst = tau[:, 0] <= 0
        if inst.any():
            u = t[inst]
            # (the window is a function of t alone: once when the rows are alike)
            win = (_kaiser(u[:1], halfwidth) if u.shape[0] > 1 and np.all(u == u[:1])
                   else _kaiser(u, halfwidth))
            out[inst] = 2 * fc[inst] * np.sinc(2 * fc[inst] * u) * win
        wide = ~inst
        if wide.any():
            nodes, _ = _GAUSS16
            p = _shape_weights(skew[wide], phase[wide])               # (M', 16)
            tw, fw = t[wide], fc[wide][..., None]
            u = tw[..., None] - (0.5 * tau[wide] * nodes)[:, None, :]  # (M', N, 16)
            # the window does not depend on the cut-off: once per distinct (tau, t) row
            # (rows of t are often all alike: then the distinct taus suffice)
            if tw.shape[0] > 1 and np.all(tw == tw[:1]):
                _, first, inv = np.unique(tau[wide, 0], return_index=True,
                                          return_inverse=True)
            else:
                _, first, inv = np.unique(np.column_stack([tau[wide], tw]), axis=0,
                                          return_index=True, return_inverse=True)
            win = _kaiser(u[first], halfwidth)[inv.ravel()]
            out[wide] = np.einsum("mnk,mk->mn", _scaled_sinc(2 * fw, u) * win, p)
        return out
    # the leading columns before every row's entry are 0: computed without them (each
    # value is a function of its row from the entry on; a fourth of a learning grid's
    # columns); 33 columns at least kept, as _exp_rows's running products need
    lead = int(np.argmin((t < 0).all(axis=0))) if t.ndim == 2 and t.size else 0
    if 0 < lead < t.shape[1] - 32:
        out = np.zeros(t.shape)
        out[:, lead:] = pulse_responses(t[:, lead:], kind, order, cutoffs, taus, halfwidth,
                                        skews, phases, mounts, mount_zetas)
        return out
    pu, ru = _unit_poles(kind, int(order))
    wc = 2 * math.pi * fc                                             # (M, 1)
    P, R = pu[None, :] * wc, ru[None, :] * wc                         # (M, K)
    if mounts is not None and np.any(np.asarray(mounts) > 0):
        mounts = np.asarray(mounts, dtype=float)
        zetas = (np.full(mounts.shape, 0.02) if mount_zetas is None
                 else np.asarray(mount_zetas, dtype=float))
        has = mounts > 0
        if not has.all():                  # rows with and without: each on its own
            out = np.empty(t.shape)
            for rows in (has, ~has):
                out[rows] = pulse_responses(t[rows], kind, order, fc[rows, 0], tau[rows, 0],
                                            halfwidth, skew[rows], phase[rows],
                                            mounts[rows], zetas[rows])
            return out
        P = np.concatenate([P, _mount_poles(mounts, zetas)], axis=1)
        R = _residues(P)
    tp = np.maximum(t, 0.0)
    E = _exp_rows(tp, P)                                              # (M, N, K)
    out = np.zeros(t.shape)
    inst = tau[:, 0] <= 0
    if inst.any():
        out[inst] = np.einsum("mnk,mk->mn", E[inst], R[inst]).real
    wide = ~inst
    if wide.any():
        T, Pw, Rw, tw = tau[wide], P[wide], R[wide], tp[wide]
        ph = phase[wide][:, None]
        w = (math.pi - ph) / T                                        # (M', 1)
        g = skew[wide][:, None] * w                                   # decay of the shape
        # f(s) = N exp(-g s) sin(w s + ph) on [0, tau]; per pole p, with q = p + g,
        # int_0^u f(s) e^{p (t - s)} ds = N e^{p t} / 2i [e^{i ph} (e^{(iw - q) u} - 1)
        # / (iw - q) - e^{-i ph} (e^{(-iw - q) u} - 1) / (-iw - q)], u = min(t, tau)
        norm = 1.0 / _arch_area(g, w, ph, T)
        Q = Pw + g
        a1 = Rw * np.exp(1j * ph) / (1j * w - Q)                      # (M', K)
        a2 = Rw * np.exp(-1j * ph) / (-1j * w - Q)
        Ew = E if wide.all() else E[wide]
        late = np.einsum("mnk,mk->mn", Ew, a1 * (np.exp((1j * w - Q) * T) - 1.0)
                         - a2 * (np.exp((-1j * w - Q) * T) - 1.0))
        res = (norm * late / 2j).real
        # during the contact (0 <= t <= tau: a few points of a row) the other form;
        # exp((-iw - g) t) is the conjugate of exp((iw - g) t) (g, w, t real)
        mi, ni = np.nonzero((tw <= T) & (t[wide] >= 0))
        if mi.size:
            z = np.exp((1j * w[mi, 0] - g[mi, 0]) * tw[mi, ni])
            early = (a1.sum(axis=1)[mi] * z - a2.sum(axis=1)[mi] * np.conj(z)
                     - np.einsum("pk,pk->p", Ew[mi, ni], (a1 - a2)[mi]))
            res[mi, ni] = (norm[mi, 0] * early / 2j).real
        out[wide] = res
    return np.where(t >= 0, out, 0.0)
