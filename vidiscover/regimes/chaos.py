"""The 0-1 test for chaos (Gottwald & Melbourne) on a scalar sequence.

For an observable ``phi(j)``, ``j = 1..N`` (impact-time differences, or the
stroboscopic LO displacement), and a frequency ``c`` in (pi/5, 4 pi/5), the
translation variables

    p_c(n) = sum_{j<=n} phi(j) cos(j c),   q_c(n) = sum_{j<=n} phi(j) sin(j c)

stay bounded for regular (periodic or quasi-periodic) dynamics and behave like a
Brownian motion for chaotic dynamics. The growth of their mean square displacement

    M_c(n) = mean_j [(p_c(j+n) - p_c(j))^2 + (q_c(j+n) - q_c(j))^2],  n <= N/10,

is measured by the correlation ``K_c = corr(n, D_c(n))`` of the modified
displacement ``D_c = M_c - (E phi)^2 (1 - cos n c) / (1 - cos c)`` (the oscillating
term removed, which makes the test converge faster), and the result is the median of
``K_c`` over random ``c``: ``K ~ 0`` regular, ``K ~ 1`` chaotic. Values of ``c`` near
a resonance with the dynamics give outliers; the median ignores them.

References
----------
G. A. Gottwald and I. Melbourne, "A new test for chaos in deterministic systems",
Proc. R. Soc. A 460 (2004) 603-611; "On the implementation of the 0-1 test for
chaos", SIAM J. Appl. Dyn. Syst. 8 (2009) 129-145 (the correlation method used here).

Measurement noise is itself irregular: i.i.d. noise gives ``K ~ 1``. The test
says whether a sequence is regular or not; whether its irregular part is larger
than the precision of the measurement is a separate question (see
:func:`irregular_beyond_noise`), and a chaotic label needs both.

Examples
--------
>>> import numpy as np
>>> x = np.empty(3000); x[0] = 0.3
>>> for j in range(1, x.size):
...     x[j] = 3.97 * x[j - 1] * (1 - x[j - 1])
>>> zero_one_test(x, seed=0).K > 0.9
True
>>> zero_one_test(np.tile([0.1, 0.5, 0.9, 0.3], 500), seed=0).K < 0.1
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import fftconvolve

from ..errors import InputError

__all__ = ["ZeroOneResult", "zero_one_test", "irregular_beyond_noise"]

#: Fewest samples the test is run on (Gottwald & Melbourne use N >= 1000; the
#: correlation method still separates regular from chaotic at a few hundred).
MIN_SAMPLES = 100


@dataclass(frozen=True)
class ZeroOneResult:
    """Outcome of :func:`zero_one_test`.

    Attributes
    ----------
    K : float
        Median of ``K_c`` over the drawn frequencies: ~0 regular, ~1 chaotic.
    K_c : ndarray
        Correlation per frequency.
    c : ndarray
        The frequencies drawn.
    n_samples : int
        Length of the sequence tested.
    """

    K: float
    K_c: np.ndarray
    c: np.ndarray
    n_samples: int


def _msd(p: np.ndarray, ncut: int) -> np.ndarray:
    """Mean square displacement of every row of ``p`` for lags 1..ncut (via FFT)."""
    n = p.shape[1]
    csum = np.cumsum(p * p, axis=1)
    total = csum[:, -1:]
    lags = np.arange(1, ncut + 1)
    # sum_j p(j+n)^2 over j < N-n  and  sum_j p(j)^2 over j < N-n
    head = csum[:, n - lags - 1]                       # sum_{j < N-n} p(j)^2
    tail = total - csum[:, lags - 1]                   # sum_{j >= n} p(j)^2
    cross = fftconvolve(p, p[:, ::-1], axes=1)[:, n - 1 + lags]   # sum_j p(j+n) p(j)
    return (head + tail - 2.0 * cross) / (n - lags)


def zero_one_test(phi, n_c: int = 100, seed: int = 0, ncut: int | None = None
                  ) -> ZeroOneResult:
    """Gottwald-Melbourne 0-1 test (correlation method) on the sequence ``phi``.

    Parameters
    ----------
    phi : array_like
        The observable, one value per step (e.g. one per impact or per forcing cycle).
    n_c : int
        Number of random frequencies ``c`` in (pi/5, 4 pi/5).
    seed : int
        Seed of the frequency draws.
    ncut : int, optional
        Largest lag (default N/10).

    Returns
    -------
    ZeroOneResult

    Raises
    ------
    InputError
        If the sequence is shorter than :data:`MIN_SAMPLES` or not finite.
    """
    phi = np.asarray(phi, dtype=float).ravel()
    if phi.size < MIN_SAMPLES:
        raise InputError(f"the 0-1 test needs at least {MIN_SAMPLES} samples, got {phi.size}; "
                         "use a longer record")
    if not np.all(np.isfinite(phi)):
        raise InputError("the 0-1 test needs finite samples; remove NaN/inf first")
    n = phi.size
    ncut = n // 10 if ncut is None else int(ncut)
    if not 2 <= ncut < n:
        raise InputError(f"ncut must be in [2, {n - 1}], was {ncut!r}")
    if np.ptp(phi) == 0.0:                    # a constant sequence is regular
        c = np.zeros(0)
        return ZeroOneResult(0.0, np.zeros(0), c, n)
    rng = np.random.default_rng(seed)
    c = rng.uniform(math.pi / 5, 4 * math.pi / 5, n_c)
    j = np.arange(1, n + 1)
    phase = np.outer(c, j)
    p = np.cumsum(phi * np.cos(phase), axis=1)
    q = np.cumsum(phi * np.sin(phase), axis=1)
    m = _msd(p, ncut) + _msd(q, ncut)
    lags = np.arange(1, ncut + 1)
    osc = phi.mean() ** 2 * (1 - np.cos(np.outer(c, lags))) / (1 - np.cos(c))[:, None]
    d = m - osc
    xi = lags - lags.mean()
    dc = d - d.mean(axis=1, keepdims=True)
    denom = np.sqrt((xi * xi).sum() * (dc * dc).sum(axis=1))
    k_c = np.where(denom > 0, (dc @ xi) / np.where(denom > 0, denom, 1.0), 0.0)
    return ZeroOneResult(float(np.median(k_c)), k_c, c, n)


def irregular_beyond_noise(phi, precision: float, period: int | None = None,
                           factor: float = 3.0) -> bool:
    """Whether the irregular part of ``phi`` exceeds the measurement precision.

    The irregular part is what a periodic model of period ``period`` (or, when None,
    the best of periods 1-4) leaves: the RMS of ``phi(j + p) - phi(j)`` divided by
    sqrt(2). It must exceed ``factor`` times ``precision`` (the RMS measurement error
    of one value of ``phi``) for an irregularity to be claimed.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> periodic = np.tile([1.0, 2.0], 200) + rng.normal(0, 0.01, 400)
    >>> irregular_beyond_noise(periodic, precision=0.01)
    False
    """
    phi = np.asarray(phi, dtype=float).ravel()
    periods = [period] if period else [1, 2, 3, 4]
    spread = min(np.sqrt(np.mean((phi[p:] - phi[:-p]) ** 2) / 2.0) for p in periods
                 if phi.size > p + 1)
    return bool(spread > factor * precision)
