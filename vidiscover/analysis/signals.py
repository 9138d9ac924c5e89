"""Input conditioning shared by the analysis stages.

Checks that a :class:`~vidiscover.recording.Recording` can be analysed (finite,
uniform time axis, enough samples), finds bad samples (NaN dropouts, clipped
accelerometer readings), fills them for filtering, estimates noise robustly and
fits the base excitation (forcing frequency, amplitude and phase) from ``xe``.

Examples
--------
>>> import numpy as np
>>> robust_std(np.array([0.0, 1.0, -1.0, 0.5, -0.5, 100.0])) < 2
True
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["Forcing", "check_recording", "robust_std", "fill_gaps", "bridge_gaps",
           "clipped_mask", "fit_forcing", "savgol_smooth", "savgol_taps", "Offsets",
           "estimate_offsets", "MIN_SAMPLES", "MAX_DISPLACEMENT", "MAX_ACCELERATION"]

#: Fewest samples an analysis accepts (10 ms at 6400 Hz): shorter records cannot
#: hold one impact pulse with its acquisition kernel.
MIN_SAMPLES = 64
#: Largest displacement (m) an analysis accepts in ``x`` and ``xe``: a rig with a
#: clearance of at most 1 m (the metadata limit on ``b``) never moves 10 m; larger
#: values are a units or scale error (and would overflow the noise statistics).
MAX_DISPLACEMENT = 10.0
#: Largest acceleration (m/s^2) an analysis accepts in ``a`` (1e6 g, beyond shock
#: accelerometers); larger values are a units or scale error.
MAX_ACCELERATION = 1e7


def check_recording(rec, min_samples: int = MIN_SAMPLES) -> float:
    """Validate the time axis and length of ``rec``; return the sampling rate.

    Parameters
    ----------
    rec : Recording
        The recording to analyse.
    min_samples : int
        Fewest samples accepted.

    Returns
    -------
    float
        Sampling rate (Hz).

    Raises
    ------
    InputError
        If the record is too short, or ``t`` is not finite, increasing and uniform.
    """
    n = rec.n
    if n < min_samples:
        raise InputError(f"{rec.name}: the record has {n} samples; the analysis needs at "
                         f"least {min_samples} (about {min_samples / 6400 * 1e3:.0f} ms at "
                         "6400 Hz); give a longer recording")
    t = rec.t
    if not np.isfinite(t).all():
        raise InputError(f"{rec.name}: column 't' has {int((~np.isfinite(t)).sum())} "
                         "non-finite value(s); time must be finite and uniform")
    d = np.diff(t)
    # (t is finite: no step <= 0 exactly when the smallest is > 0)
    lo, hi = float(d.min()), float(d.max())
    if not lo > 0:
        raise InputError(f"{rec.name}: column 't' must increase strictly; fix the time axis")
    dt = float(t[-1] - t[0]) / (n - 1)          # the mean step: cheap, and exact when uniform
    # max |d - dt| from the extreme steps (subtraction is monotonic: the same value)
    if max(hi - dt, dt - lo) > 1e-3 * dt:
        dt = float(np.median(d))
    if max(hi - dt, dt - lo) > 1e-3 * dt:
        raise InputError(f"{rec.name}: column 't' is not uniformly sampled (steps from "
                         f"{d.min():.6g} to {d.max():.6g} s); resample to a uniform grid")
    fs = rec.sample_rate
    if not (math.isfinite(fs) and fs > 0) or abs(fs * dt - 1.0) > 1e-3:
        raise InputError(f"{rec.name}: sample_rate {fs!r} Hz disagrees with the time step "
                         f"{dt:.6g} s of 't'; fix the metadata")
    for col, limit, unit in (("x", MAX_DISPLACEMENT, "m"), ("xe", MAX_DISPLACEMENT, "m"),
                             ("a", MAX_ACCELERATION, "m/s^2")):
        v = np.asarray(getattr(rec, col), dtype=float)
        if v.max() <= limit and v.min() >= -limit:    # fast path: all finite and in range
            continue
        with np.errstate(invalid="ignore"):
            big = np.abs(v) > limit            # NaN compares False; +/-inf is caught
        if big.any() and np.isfinite(v[big]).any():
            worst = float(np.max(np.abs(v[big & np.isfinite(v)])))
            raise InputError(f"{rec.name}: column '{col}' reaches {worst:.3g} {unit}, beyond "
                             f"any physical reading (limit {limit:g} {unit}); check the "
                             "units and scale of the column")
    return float(fs)


def robust_std(x: np.ndarray) -> float:
    """Standard deviation from the median absolute deviation (1.4826 MAD).

    Non-finite values are ignored; returns 0.0 for an empty input.
    """
    x = np.asarray(x, dtype=float)
    ok = np.isfinite(x)
    if not ok.all():
        x = x[ok]
    if x.size == 0:
        return 0.0
    med = _median(x)
    dev = np.subtract(x, med)           # (x - med, its absolute value in place)
    np.abs(dev, out=dev)
    return float(1.4826 * _median(dev, own=True))


#: :func:`_median` selects among the samples near a sample's middle from this size on.
_SELECT_MIN = 4096
_SELECT_STEP = 16


def _median(x: np.ndarray, own: bool = False) -> float:
    """Median of a finite 1-D array (``np.median`` without its checks).

    For an even count the lower middle value is the largest of the ``k`` values a
    partition at ``k`` leaves below: numpy's partition at two positions at once
    ``(k - 1, k)`` took 8x as long on 32768 normal samples (303 vs 38 us). ``own``:
    ``x`` may be reordered (no copy).

    From :data:`_SELECT_MIN` samples on, the middle values are selected from the
    samples between two order statistics of every :data:`_SELECT_STEP`-th sample
    (about 4 standard errors of rank either side of its middle; the samples below
    them counted): about 1/6 of them is partitioned, not all, after a few
    vectorised comparisons (robust_std of 8192 samples: 2 partitions of 60-80 us on
    this machine, 2026-11-27). The same values: the k-th smallest sample is one
    number whichever way it is selected (of equal values -0.0 and 0.0 either may be
    returned, as from a partition; :func:`robust_std` does not depend on the sign
    of a zero median). The whole array is partitioned when the bounds miss the
    middle: never for the arrays of tests/test_signals_median.py (normal, tied,
    sorted, random-walk, Cauchy, ...; 10 seeds, 1200 arrays and deviations).
    """
    n = x.size
    k = n // 2
    if n >= _SELECT_MIN:
        s = x[::_SELECT_STEP]
        m = s.size
        c = (k * (m - 1)) // (n - 1)
        d = int(2.0 * math.sqrt(m)) + 2
        i_lo, i_hi = max(0, c - d), min(m - 1, c + 1 + d)
        sp = np.partition(s, (i_lo, i_hi))
        lo, hi = sp[i_lo], sp[i_hi]
        inside = x >= lo
        j = k - (n - int(np.count_nonzero(inside)))     # rank among those >= lo
        inside &= x <= hi
        cand = x[inside]
        if 1 <= j < cand.size:
            x, k, own = cand, j, True
    if own:
        x.partition(k)
        p = x
    else:
        p = np.partition(x, k)
    if n % 2:
        return float(p[k])
    return 0.5 * (float(p[:k].max()) + float(p[k]))


#: :func:`release_freed_memory` acts after stages whose full-length arrays reach this size.
RELEASE_BYTES = 8 << 20


@functools.lru_cache(maxsize=1)
def _malloc_trim():
    """The C library's ``malloc_trim`` (glibc), or None (another C library, no ctypes)."""
    try:
        import ctypes
        import ctypes.util

        name = ctypes.util.find_library("c")
        trim = getattr(ctypes.CDLL(name), "malloc_trim", None) if name else None
    except (ImportError, OSError):
        return None
    if trim is not None:
        trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    return trim


def release_freed_memory(nbytes: int) -> None:
    """Return the freed heap pages to the system after a stage with large temporaries.

    glibc raises its mmap threshold to the size of the largest block freed (up to
    32 MB): once a long record's first full-length array is freed, the later ones
    are carved from the heap, and their freed pages stay resident while anything
    allocated after them lives above. The detection frees a dozen full-length
    temporaries and keeps its results and small tables above them: a 200 MB CSV's
    ``analyze`` kept 547 MB resident after the detection for 413 MB in use, and the
    later stages (whose own peak sets the command's) grew from there: 601-608 MB,
    592-603 MB with the pages released (numpy's huge pages off, else the figure
    moves by +-10 MB from run to run). ``malloc_trim(0)`` gives those pages back
    (the addresses stay the heap's, for the next stages to reuse); no value
    changes. Only when the full-length arrays reach :data:`RELEASE_BYTES`
    (``nbytes``): short records keep their pages for the next stage.
    """
    if nbytes < RELEASE_BYTES:
        return
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


def fill_gaps(y: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """Copy of ``y`` with the ``bad`` samples replaced by linear interpolation.

    Gaps at the ends take the nearest good value; an all-bad input gives zeros.
    """
    return _fill_in_place(np.array(y, dtype=float), bad)


def _fill_in_place(y: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """:func:`fill_gaps` overwriting the float array ``y``; returns ``y``.

    Only the good samples next to a gap take part in the interpolation (the same
    brackets, so the same values, without full-length index arrays).
    """
    if not bad.any():
        return y
    good = ~bad
    if not good.any():
        y[...] = 0.0
        return y
    edge = np.zeros(y.size, dtype=bool)
    edge[:-1] |= bad[1:]
    edge[1:] |= bad[:-1]
    edge &= good
    del good
    xp = np.flatnonzero(edge)
    del edge
    xb = np.flatnonzero(bad)
    y[xb] = np.interp(xb, xp, y[xp])
    return y


_SAMPLE_BLOCK = 1 << 16


def good_sample(x: np.ndarray, bad: np.ndarray, count: int = 8192) -> np.ndarray:
    """``x[~bad][::max(1, n_good // count)]`` without a full-length copy."""
    if not bad.any():
        return x[:: max(1, x.size // count)]
    step = max(1, (x.size - int(np.count_nonzero(bad))) // count)
    return x[_ranked(lambda lo, hi: ~bad[lo:hi], x.size, step)]


def second_difference_sample(y: np.ndarray, bad: np.ndarray, count: int = 8192
                             ) -> np.ndarray:
    """``d2[::max(1, d2.size // count)]`` of ``d2 = np.diff(y, 2)`` over good triples.

    The same values as ``np.diff(y, 2)[~(bad[2:] | bad[1:-1] | bad[:-2])]`` sampled,
    computed at the sampled positions only.
    """
    m = y.size - 2
    if not bad.any():
        # (the samples k, k + 1, k + 2 at k = 0, step, ...: strided views, no gathers)
        step = max(1, m // count)
        y0, y1, y2 = y[0:m:step], y[1:m + 1:step], y[2:m + 2:step]
        return (y2 - y1) - (y1 - y0)

    def ok(lo, hi):
        return ~(bad[lo + 2:hi + 2] | bad[lo + 1:hi + 1] | bad[lo:hi])

    n_ok = sum(int(np.count_nonzero(ok(lo, min(lo + _SAMPLE_BLOCK, m))))
               for lo in range(0, m, _SAMPLE_BLOCK))
    k = _ranked(ok, m, max(1, n_ok // count))
    return (y[k + 2] - y[k + 1]) - (y[k + 1] - y[k])


def noise_sigma(y: np.ndarray, bad: np.ndarray) -> float:
    """White-noise standard deviation of ``y`` from its second differences (robust).

    ``robust_std`` of :func:`second_difference_sample` over ``sqrt(6)``: the second
    difference of white noise has 6 times its variance, and a smooth signal leaves
    almost nothing in it. Never below the quantisation noise ``q / sqrt(12)`` of the
    recording's smallest step ``q`` (:func:`quantisation_step`): behind a coarse ADC
    whose step exceeds the analog noise, most second differences are exactly 0 and
    their median absolute deviation is 0, although every sample carries an error of up
    to half a step (a 12-bit +/-50 g accelerometer: steps of 0.24 m/s^2, sigma 0.069).
    """
    d2 = second_difference_sample(y, bad)
    sigma = robust_std(d2) / math.sqrt(6.0)
    # the floor can only act where at least a quarter of the second differences vanish
    # (otherwise their median absolute deviation is at least one step): skip the search
    # for the step elsewhere
    ad2 = np.abs(d2)
    if d2.size and 4 * np.count_nonzero(ad2 <= _ZERO_REL * ad2.max()) >= d2.size:
        sigma = max(sigma, quantisation_step(y, bad) / math.sqrt(12.0))
    return sigma


_ZERO_REL = 1e-9    # a difference of quantised values this small (relative) is rounding


def quantisation_step(y: np.ndarray, bad: np.ndarray, windows: int = 16,
                      length: int = 512) -> float:
    """The smallest non-zero change between two good neighbouring samples of ``y``.

    Taken over ``windows`` runs of ``length`` samples spread over the record. For a
    quantised recording it is the ADC step (neighbours differ by whole steps); for an
    unquantised one it is a tiny fraction of the noise, so the floor it sets in
    :func:`noise_sigma` does not act. 0.0 when no two good neighbours differ.
    """
    n = y.size
    if n < 2:
        return 0.0
    length = min(length, n)
    starts = np.unique(np.linspace(0, n - length, windows).astype(np.int64))
    idx = (starts[:, None] + np.arange(length)).ravel()
    d = np.abs(y[idx[1:]] - y[idx[:-1]])
    ok = (idx[1:] == idx[:-1] + 1) & ~bad[idx[1:]] & ~bad[idx[:-1]]
    ok &= d > _ZERO_REL * (d[ok].max() if ok.any() else 0.0)
    return float(d[ok].min()) if ok.any() else 0.0


def smoother_window(ms: float, fs: float, n: int) -> int:
    """Odd smoother window (samples) of about ``ms`` milliseconds.

    At least 7, at most the record's ``n`` samples (the largest odd count within them).
    """
    win = max(7, int(round(ms * 1e-3 * fs)) | 1)
    if win > n:
        win = n if n % 2 else n - 1
    return win


def _ranked(ok, m: int, step: int) -> np.ndarray:
    """Positions of every ``step``-th True of the mask ``ok(lo, hi)`` over ``[0, m)``."""
    parts, rank = [], 0
    for lo in range(0, m, _SAMPLE_BLOCK):
        g = np.flatnonzero(ok(lo, min(lo + _SAMPLE_BLOCK, m)))
        parts.append(lo + g[(-rank) % step::step])
        rank += g.size
    return np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)


def max5(v: np.ndarray) -> np.ndarray:
    """max(v[i - 2 : i + 3]) for every i of a non-empty ``v``, by shifted maxima.

    The window is cut at the ends of ``v``.
    """
    p = np.empty(v.size + 4)
    p[:2], p[-2:], p[2:-2] = v[0], v[-1], v        # the ends repeated: the cut windows' max
    m = np.maximum(p[:-1], p[1:])                  # i, i + 1
    m = np.maximum(m[:-2], m[2:])                  # i .. i + 3
    return np.maximum(m[:-1], p[4:], out=m[:-1])   # i .. i + 4 of p: v[i - 2 .. i + 2]


def running_max(v: np.ndarray, half: int) -> np.ndarray:
    """max(v[i - half : i + half + 1]) for every i of a non-empty ``v`` (any dtype).

    The window is cut at the ends of ``v``; a boolean ``v`` gives the mask widened by
    ``half`` samples on both sides. By maxima of windows doubling in length (about
    log2(2 half + 1) passes), 5-70 times faster here than
    ``scipy.ndimage.maximum_filter1d`` on 32768 samples; :func:`max5` is the same for
    ``half`` = 2, faster still for that one width.

    Examples
    --------
    >>> running_max(np.array([0.0, 3.0, 1.0, 0.0, 0.0, 2.0]), 1)
    array([3., 3., 3., 1., 2., 2.])
    >>> running_max(np.array([False, False, True, False, False]), 1)
    array([False,  True,  True,  True, False])
    """
    w, n = 2 * half + 1, v.size
    r = np.empty(n + 2 * half, dtype=v.dtype)
    r[:half], r[n + half:], r[half:n + half] = v[0], v[-1], v   # the cut windows' max
    k = 1
    while 2 * k <= w:                   # r[i] = max of 2k samples from i, k doubling
        np.maximum(r[:-k], r[k:], out=r[:-k])
        k *= 2
    return np.maximum(r[:n], r[w - k:w - k + n])


def run_about(mask: np.ndarray, p: int) -> tuple[int, int]:
    """First and last index of the run of True in ``mask`` about index ``p``.

    The run is followed from ``p`` outwards (``p`` itself is taken whatever
    ``mask[p]``): e.g. a kernel's main lobe, the contiguous samples about its peak.

    Examples
    --------
    >>> run_about(np.array([1, 0, 1, 1, 1, 0, 1], dtype=bool), 3)
    (2, 4)
    >>> run_about(np.array([1, 1, 1], dtype=bool), 0)
    (0, 2)
    """
    before = np.flatnonzero(~mask[:p])
    after = np.flatnonzero(~mask[p + 1:])
    return (int(before[-1]) + 1 if before.size else 0,
            p + int(after[0]) if after.size else mask.size - 1)


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of the runs of True in ``mask``."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def bridge_gaps(y: np.ndarray, bad: np.ndarray, degree: int = 4,
                min_side: int = 1) -> np.ndarray:
    """Copy of ``y`` with each run of ``bad`` samples bridged by a local polynomial.

    Each interior run is replaced by the least-squares polynomial of ``degree``
    through the good samples on both sides (half as many on each side as the run is
    long, at least 8): a curved signal keeps its curvature across the gap, where the
    straight line of :func:`fill_gaps` cuts its chord (a 12.5 ms gap in a 19 Hz,
    500 m/s^2 acceleration sags by 114 m/s^2; the quartic misses it by 2.4 m/s^2 and
    passes white noise on with a gain of at most 1.5). Runs at the ends, and runs
    with fewer than ``degree + 3`` good samples about them or fewer than
    ``min_side`` on one side, fall back to :func:`fill_gaps`.

    ``min_side`` > 1 is for windows packed closely: a quartic held by one to three
    samples on one side extrapolates freely across the run (holdout6-040, pulse
    windows 25-45 samples apart: humps of 1000 m/s^2 under 230 m/s^2 pulses).
    """
    out = fill_gaps(y, bad)
    if not bad.any():
        return out
    for lo, hi in true_runs(bad):
        bridge_run(y, out, bad, lo, hi, degree, min_side)
    return out


def bridge_run(y: np.ndarray, out: np.ndarray, bad: np.ndarray, lo: int, hi: int,
               degree: int = 4, min_side: int = 1) -> bool:
    """Bridge the run ``[lo, hi)`` of ``out`` by a local polynomial through ``y``.

    The least-squares polynomial of ``degree`` through the good samples of ``y`` on
    both sides of the run (half as many on each side as the run is long, at least
    8), written into ``out[lo:hi]`` (``out`` may be ``y``). Returns False, leaving
    ``out`` as it is, for a run at an end of the record or with fewer than
    ``degree + 3`` good samples about it, or fewer than ``min_side`` on one side.
    """
    n = y.size
    if lo == 0 or hi == n:
        return False
    k = max((hi - lo + 1) // 2, 8)
    ctx = np.r_[max(lo - k, 0):lo, hi:min(hi + k, n)]
    ctx = ctx[~bad[ctx]]
    before = int(np.searchsorted(ctx, lo))
    if ctx.size < degree + 3 or min(before, ctx.size - before) < max(min_side, 1):
        return False
    mid, scale = 0.5 * (lo + hi - 1), float(k + hi - lo)
    V = np.vander((ctx - mid) / scale, degree + 1)
    coef = np.linalg.lstsq(V, y[ctx], rcond=None)[0]
    out[lo:hi] = np.vander((np.arange(lo, hi) - mid) / scale, degree + 1) @ coef
    return True


def savgol_taps(win: int, polyorder: int, deriv: int = 0, delta: float = 1.0,
                use: str = "dot") -> np.ndarray:
    """Centred Savitzky-Golay taps, as ``scipy.signal.savgol_coeffs(..., use=use)``.

    The same least-squares problem solved the same way (scipy.linalg.lstsq, scipy's
    ``cond``), so the same taps bit for bit (a test checks it): written out because
    importing scipy.signal costs 0.5-0.9 s per process (it imports scipy.stats), which
    every process that analyses a recording (the ``analyze`` command, a sweep worker)
    would pay for these taps.

    Parameters
    ----------
    win : int
        Odd window length (samples), > ``polyorder``.
    polyorder : int
        Degree of the local polynomial.
    deriv : int, optional
        Order of the derivative the taps evaluate at the window's centre.
    delta : float, optional
        Sample spacing, for derivatives.
    use : {"dot", "conv"}, optional
        "dot": ``taps @ y[j - win // 2: j + win // 2 + 1]`` is the fit's value (or
        derivative) at ``j``; "conv": the taps for a convolution, solved on the
        reversed abscissa as scipy does (``savgol_filter``'s, bit for bit).

    Returns
    -------
    ndarray
        ``win`` taps.
    """
    from scipy.linalg import lstsq

    h = win // 2
    x = np.arange(-h, win - h, dtype=np.float64)
    if use == "conv":
        x = x[::-1]
    A = x ** np.arange(polyorder + 1, dtype=np.float64).reshape(-1, 1)
    y = np.zeros(polyorder + 1)
    y[deriv] = math.factorial(deriv) / delta ** deriv
    return lstsq(A, y, cond=np.finfo(np.float64).eps * max(A.shape))[0]


@functools.lru_cache(maxsize=8)
def _quadratic_taps(win: int, h: float):
    c0 = savgol_taps(win, 2)
    c1 = savgol_taps(win, 2, deriv=1, delta=h)
    j = np.arange(win, dtype=float) - win // 2
    P = np.linalg.pinv(np.vander(j, 3, increasing=True))   # coefficients of the quadratic
    return c0, c1, P


def quadratic_smoother(y: np.ndarray, win: int, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Local quadratic fit's value and derivative (edge windows fitted as a whole).

    ``savgol_filter(y, win, 2)`` and ``savgol_filter(y, win, 2, deriv=1, delta=h)`` of
    mode "interp" (to rounding, ~1e-14 relative), without importing scipy.signal.
    """
    from scipy.ndimage import correlate1d

    half = win // 2
    c0, c1, P = _quadratic_taps(win, h)
    val = correlate1d(y, c0, mode="nearest")
    der = correlate1d(y, c1, mode="nearest")
    j = np.arange(win, dtype=float) - half
    for sl, jj in ((slice(0, half), j[:half]), (slice(y.size - half, y.size), j[-half:])):
        seg = y[:win] if sl.start == 0 else y[-win:]
        c = P @ seg
        val[sl] = c[0] + c[1] * jj + c[2] * jj ** 2
        der[sl] = (c[1] + 2 * c[2] * jj) / h
    return val, der


@functools.lru_cache(maxsize=8)
def _savgol_parts(win: int):
    """Savitzky-Golay (cubic) taps and the edge projections of mode 'interp'."""
    h = win // 2
    taps = savgol_taps(win, 3)
    j = np.arange(win, dtype=float)
    V = np.vander(j - h, 4, increasing=True)
    proj = V @ np.linalg.pinv(V)                    # fit a cubic to the edge window
    return taps, proj[:h], proj[-h:]


def savgol_smooth(y: np.ndarray, win: int, prev: tuple | None = None) -> np.ndarray:
    """Cubic Savitzky-Golay smoothing (as ``savgol_filter(y, win, 3, mode="interp")``).

    Parameters
    ----------
    y : ndarray
        Finite samples, at least ``win`` of them.
    win : int
        Odd window length (samples), >= 5.
    prev : (ndarray, ndarray), optional
        An earlier input of the same length and its smoothing by this function (with
        this ``win``), neither changed since: only the outputs whose window holds a
        changed sample are computed again (:func:`_smooth_changed`).

    Returns
    -------
    ndarray
    """
    taps, head, tail = _savgol_parts(win)
    h = win // 2
    out = None
    if prev is not None and prev[0].size == y.size == prev[1].size:
        out = _smooth_changed(y, prev[0], prev[1], taps, h)
    if out is None:
        out = np.empty(y.size)
        # numpy's direct correlation: a quarter faster than ndimage.correlate1d on 32k
        # samples and 41 taps (the edges it leaves are the projections below)
        out[h:y.size - h] = np.correlate(y, taps, mode="valid")
    out[:h] = head @ y[:win]
    out[-h:] = tail @ y[-win:]
    return out


#: :func:`_smooth_changed` computes everything again when more than this share of the
#: samples changed.
_CHANGED_MAX = 0.4
#: ... and when the runs about them span more than this share.
_GATHER_MAX = 0.7


def _smooth_changed(y, y0, out0, taps, h):
    """The smoothing of ``y`` from ``out0``, that of ``y0``; None when too many changed.

    The interior outputs whose window holds a sample where ``y != y0`` are correlated
    again, the others copied. The detector's second smoothing differs from its first
    about the fitted pulses only (the paper rig's 5.12 s record: 22 % of the outputs
    in 82 runs): those runs are gathered, each with its ``h`` samples of context
    either side, into one array correlated at once (the runs' junctions give outputs
    that are not kept). Each output is the same dot product (numpy's, per window) of
    the same samples as in a correlation of the whole record, so the same value: the
    dot product does not depend on where its samples lie in memory (checked at every
    alignment, tests/test_signals_savgol_reuse.py).
    """
    n = y.size
    if n < 8 * (2 * h + 1):
        return None
    ch = np.flatnonzero(y != y0)
    if ch.size > _CHANGED_MAX * n:
        return None
    out = out0.copy()
    if ch.size == 0:
        return out
    # runs of changed samples (merged when their outputs would touch), and the
    # interior outputs [a, b) they reach
    brk = np.flatnonzero(np.diff(ch) > 2 * h + 1)
    a = np.maximum(np.r_[ch[0], ch[brk + 1]] - h, h)
    b = np.minimum(np.r_[ch[brk], ch[-1]] + h + 1, n - h)
    keep = b > a
    a, b = a[keep], b[keep]
    if a.size == 0:
        return out
    lens = b - a                                   # outputs per run
    span = lens + 2 * h                            # samples per run
    if span.sum() > _GATHER_MAX * n:
        # (the gathering costs about a fifth of a whole correlation: on the paper
        # rig's Table-2 record, 52 % of the samples gathered, 380 against 450 us)
        return None
    first = np.cumsum(span) - span                 # where each run starts in the gather
    src = np.arange(int(span.sum())) + np.repeat(a - h - first, span)
    c = np.correlate(y[src], taps, mode="valid")
    k = np.arange(int(lens.sum()))
    shift = np.repeat(np.cumsum(lens) - lens, lens)
    out[k - shift + np.repeat(a, lens)] = c[k - shift + np.repeat(first, lens)]
    return out


def clipped_mask(a: np.ndarray, a_range: float | None = None) -> np.ndarray:
    """Samples that sit on the accelerometer's range limit.

    A sample is clipped when it equals the record's maximum (or minimum) value and
    that extreme value occurs at least twice (a saturating front end repeats its
    rail value exactly; noise makes exact repeats of an extreme improbable), or
    when ``|a| >= a_range`` for a known range.

    Parameters
    ----------
    a : ndarray
        Acceleration (NaN allowed).
    a_range : float, optional
        Known range of the accelerometer (m/s^2).

    Returns
    -------
    ndarray of bool
    """
    finite = np.isfinite(a)
    mask = np.zeros(a.shape, dtype=bool)
    every = bool(finite.all())          # the usual case: no masked copies
    if not every and not finite.any():
        return mask
    af = a if every else np.where(finite, a, 0.0)
    if a_range is not None:
        mask |= finite & (np.abs(af) >= a_range)
    vals = af if every else af[finite]
    hi, lo = vals.max(), vals.min()
    for rail in (hi, lo):
        if rail == 0.0:
            continue
        at = af == rail
        if not every:
            at &= finite
        if np.count_nonzero(at) >= 2:
            mask |= at
    return mask


@dataclass(frozen=True)
class Forcing:
    """The base excitation fitted to ``xe``: ``xe ~ c + amplitude sin(2 pi f t + phase)``.

    Attributes
    ----------
    frequency : float
        Forcing frequency f (Hz).
    amplitude : float
        Base displacement amplitude (m).
    phase : float
        Phase (rad) of the base sine at t = 0 (record time).
    source : str
        "xe" when fitted, "metadata" when ``xe`` was unusable.
    """

    frequency: float
    amplitude: float
    phase: float
    source: str = "xe"

    @property
    def period(self) -> float:
        """Forcing period 1/f (s)."""
        return 1.0 / self.frequency

    def cycle_starts(self, t0: float, t1: float) -> np.ndarray:
        """Times of base phase 0 (start of each cycle) within [t0, t1]."""
        T = self.period
        shift = -self.phase / (2 * math.pi) * T        # a time with phase 0
        k0 = math.ceil((t0 - shift) / T - 1e-9)
        k1 = math.floor((t1 - shift) / T + 1e-9)
        return shift + np.arange(k0, k1 + 1) * T


def fit_forcing(t: np.ndarray, xe: np.ndarray, f_hint: float, iterations: int = 3
                ) -> Forcing:
    """Fit a sine at (about) ``f_hint`` to the base displacement.

    The frequency is refined from the phase drift between the two halves of the
    record (complex demodulation at the current estimate, kept within 5 % of the
    hint), then amplitude and phase by linear least squares. The signal is
    decimated to at most about 2048 samples first (the forcing is slow).

    Parameters
    ----------
    t, xe : ndarray
        Time (s) and base displacement (m); NaN samples are ignored.
    f_hint : float
        Nominal forcing frequency (Hz), e.g. from the metadata.
    iterations : int
        Frequency refinement steps.

    Returns
    -------
    Forcing
        With ``source="metadata"`` (frequency = hint, phase 0) if ``xe`` has no
        usable sine (all NaN, constant or shorter than one period).
    """
    fallback = Forcing(float(f_hint), float("nan"), 0.0, "metadata")
    ok = np.isfinite(xe)
    if np.count_nonzero(ok) < 8 or (t[-1] - t[0]) < 1.0 / f_hint:
        return fallback
    step = max(1, int(ok.size // 1024))
    tt = t[::step][ok[::step]]
    yy = xe[::step][ok[::step]]
    if tt.size < 8:
        return fallback
    yy = yy - yy.mean()
    f = float(f_hint)
    half = tt.size // 2
    if (tt[-1] - tt[0]) * f_hint >= 4:            # frequency refinement needs a few cycles
        for _ in range(iterations):
            ph = np.exp(-2j * math.pi * f * tt)
            c1 = np.dot(yy[:half], ph[:half])
            c2 = np.dot(yy[half:], ph[half:])
            if c1 == 0 or c2 == 0:
                break
            gap = tt[half:].mean() - tt[:half].mean()
            f_new = f + float(np.angle(c2 / c1)) / (2 * math.pi * gap)
            if not math.isfinite(f_new) or abs(f_new - f_hint) > 0.05 * f_hint:
                break
            f = f_new
    w = 2 * math.pi * f
    A = np.column_stack([np.sin(w * tt), np.cos(w * tt), np.ones_like(tt)])
    coef = np.linalg.solve(A.T @ A + 1e-30 * np.eye(3), A.T @ yy)
    amp = math.hypot(coef[0], coef[1])
    noise = robust_std(yy - A @ coef)
    if not math.isfinite(amp) or amp == 0.0 or amp < 3 * noise / math.sqrt(tt.size):
        return fallback
    return Forcing(float(f), float(amp), float(math.atan2(coef[1], coef[0])), "xe")


@dataclass(frozen=True)
class Offsets:
    """Zero errors of the three channels (subtract them from the readings).

    Attributes
    ----------
    a_bias : float
        Accelerometer DC bias (m/s^2).
    x_offset : float
        Laser reading at the LO's rest position (m).
    xe_offset : float
        Base-sensor reading at the base's mean position (m).
    n_cycles : int
        Whole forcing cycles averaged (0: not estimated, all offsets 0).
    """

    a_bias: float = 0.0
    x_offset: float = 0.0
    xe_offset: float = 0.0
    n_cycles: int = 0

    def to_dict(self) -> dict:
        """JSON-ready form (``a_bias``, ``x_offset``, ``xe_offset``, ``n_cycles``)."""
        return {"a_bias": self.a_bias, "x_offset": self.x_offset, "xe_offset": self.xe_offset,
                "n_cycles": self.n_cycles}


def estimate_offsets(t: np.ndarray, x: np.ndarray, a: np.ndarray, xe: np.ndarray,
                     forcing: Forcing, impacts: np.ndarray | None = None,
                     edge_ms: float = 6.0) -> Offsets:
    """Accelerometer bias and displacement zero offsets from whole forcing cycles.

    Over a bounded motion, averages over N whole forcing cycles (window length
    ``N T``) give the zeros:

    * the base oscillates about its mean position: ``xe_offset = mean(xe)``;
    * the LO's springs relax about the base's mean position, and the momentum
      balance of LO and ball, ``m1 x'' + m2 y'' = -k1 (x - xe) - c1 (x' - xe') +
      m2 g sin(theta)``, averaged (mean accelerations and relative velocity -> 0)
      gives ``mean(x - xe) = m2 g sin(theta) / k1``: with the base at 0,
      ``x_offset = mean(x)``. Friction is internal to LO + ball and leaves no static
      deflection; the tilt's is ``m2 g sin(theta) / k1``, 0.4 um at 0.8 deg and
      1.2 um at 2.5 deg for the paper's rig (neglected: below the laser noise);
    * the mean LO acceleration is the velocity change over the window divided by
      its length, so ``a_bias = mean(a) - (v(end) - v(start)) / (N T)``, with the
      LO velocity at both ends from a local cubic fit of ``x`` (+/- ``edge_ms``);
      the window is placed so that no impact falls within ``edge_ms`` of its ends.

    Parameters
    ----------
    t, x, a, xe : ndarray
        Time (s), LO displacement (m), LO acceleration (m/s^2), base displacement
        (m); NaN samples are ignored.
    forcing : Forcing
        The forcing fitted to ``xe`` (its period sets the cycles).
    impacts : ndarray, optional
        Impact times (s), kept away from the window ends.
    edge_ms : float
        Half-window of the velocity fits at the ends (ms).

    Returns
    -------
    Offsets
        All zero (``n_cycles = 0``) when the record holds no whole cycle with
        clear ends.
    """
    n = t.size
    dt = float(t[1] - t[0]) if n > 1 else 0.0
    T = forcing.period
    span = float(t[-1] - t[0]) + dt
    if not (dt > 0 and math.isfinite(T) and T > 0) or span < T + 4 * edge_ms * 1e-3:
        return Offsets()
    W = max(4, int(round(edge_ms * 1e-3 / dt)))
    imp = np.sort(np.asarray(impacts, dtype=float)) if impacts is not None else np.zeros(0)
    n_cyc = int((span - 2 * (W + 1) * dt) // T)
    for n_try in (n_cyc, n_cyc - 1):
        if n_try < 1:
            break
        L = int(round(n_try * T / dt))
        for k0 in range(W + 1, n - L - W - 1, max(1, W // 2)):
            k1 = k0 + L
            ends = np.array([t[k0], t[k1]])
            if imp.size:
                near = np.abs(imp[None, :] - ends[:, None]).min(axis=1)
                if (near <= (W + 2) * dt).any():
                    continue
            v = [_slope(x[k - W:k + W + 1], dt) for k in (k0, k1)]
            if not all(math.isfinite(u) for u in v):
                continue
            seg = slice(k0, k1)
            a_bias = _nanmean(a[seg]) - (v[1] - v[0]) / (L * dt)
            return Offsets(a_bias=a_bias, x_offset=_nanmean(x[seg]),
                           xe_offset=_nanmean(xe[seg]), n_cycles=n_try)
    return Offsets()


def _nanmean(y: np.ndarray) -> float:
    """``np.nanmean(y)``, without its masked copy when ``y`` has no NaN.

    (The same pairwise sum of the same values, divided by the same count.) The NaN
    samples are looked for only when the mean is NaN.
    """
    m = float(np.mean(y))
    if m != m and np.isnan(y).any():
        return float(np.nanmean(y))
    return m


def _slope(y: np.ndarray, dt: float) -> float:
    """Derivative at the centre of ``y`` from a least-squares cubic (NaN if not finite).

    By the cubic's centred derivative taps (:func:`savgol_taps`, cached per window):
    the same least-squares derivative as a polynomial fit, without its Vandermonde
    solve per call.
    """
    if not np.isfinite(y).all():
        return float("nan")
    return float(_slope_taps(y.size) @ y) / dt


@functools.lru_cache(maxsize=8)
def _slope_taps(win: int) -> np.ndarray:
    return savgol_taps(win, 3, deriv=1)
