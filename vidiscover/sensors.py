"""Sensor model: from the exact simulated motion to a realistic recording.

* **Laser** (LO displacement): true x plus white noise; with ``sensor_resonance``
  the laser reads an aluminium sheet, a base-excited oscillator ``q'' + 2 zeta w q'
  + w^2 q = -x''`` that rings after every impact, so the reading is x + q.
* **Accelerometer**: the smooth acceleration plus one pulse per impact whose area is
  the LO velocity jump, shaped by the contact duration (half-sine of width tau,
  centred on the impact instant) and by a linear-phase (delay-compensated)
  anti-alias low-pass, as in delta-sigma acquisition front ends; then noise and
  optional saturation.
* **Base** displacement: the true base motion plus noise.

That analytic pulse path is used for the default chain (an impulsive result, i.e. the
exact engine, a ``linear-phase`` anti-alias filter and no mount resonance). Any other
chain (causal ``butter``/``bessel``/``cheby1`` anti-alias filters, an accelerometer
mount resonance, or a compliant-contact result whose contact forces are part of
``xdd``) goes through the general acquisition path of :func:`record`: every channel is
simulated at ``oversample`` times the sampling rate, filtered there, and decimated.
Offsets, bias, ADC quantisation and clipping act on the sampled values of both paths.

Everything random is drawn from ``numpy.random.default_rng(seed)``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field

import numpy as np

from ._threads import one_blas_thread
from .acquisition import CHEBY1_RIPPLE_DB, max_cutoff, pulse_kernel
from .errors import InputError
from .params import G_ACCEL
from .recording import PAPER_SENSITIVITY, Metadata, Recording
from .simulation import SimulationResult
from .truth import GroundTruth, TrueImpacts, TrueMotion

__all__ = ["SensorConfig", "record", "pulse_kernel", "ANTI_ALIAS_KINDS"]

#: Anti-alias filter kinds: the default delay-compensated FIR and causal analog designs.
ANTI_ALIAS_KINDS = ("linear-phase", "butter", "bessel", "cheby1")


def _aa_limit(kind: str, order: int, sample_rate: float) -> float:
    """Highest anti-alias cut-off (Hz, exclusive) of a filter family at ``sample_rate``."""
    return max_cutoff(kind, order) * sample_rate


def _aa_where(kind: str, order: int, sample_rate: float) -> str:
    """What that limit is, for an error message."""
    nyq = f"the Nyquist frequency {0.5 * sample_rate:g} Hz"
    lim = max_cutoff(kind, order)
    where = nyq if lim == 0.5 else (f"{lim * sample_rate:g} Hz, where a {kind}-{order}'s -3 dB "
                                    f"point reaches {nyq}")
    return f"{where}; lower the cut-off or raise the sample rate"


@dataclass(frozen=True)
class SensorConfig:
    """Acquisition settings and sensor imperfections.

    Parameters
    ----------
    sample_rate : float
        Sampling rate (Hz).
    x_noise, xe_noise : float
        RMS noise of the laser and of the base displacement (m).
    a_noise : float
        RMS noise of the accelerometer (m/s^2).
    cutoff : float
        Anti-alias cut-off as a fraction of the sampling rate (< 0.5).
    a_range : float or None
        Accelerometer range (m/s^2): readings are clipped to +/- a_range.
    kernel_halfwidth : int
        Half-width of the anti-alias kernel (samples).
    anti_alias : str
        Anti-alias filter: ``"linear-phase"`` (a Kaiser-windowed sinc, delay
        compensated, as in delta-sigma front ends), or the causal analog designs
        ``"butter"``, ``"bessel"`` (phase-normalised, scipy's default: its magnitude
        asymptotes are Butterworth's of the same order and cut-off, so it still
        rejects aliases; ``norm="delay"`` would put the -3 dB point up to ~3x above
        the cut-off, past the Nyquist frequency) or ``"cheby1"`` (0.5 dB ripple).
        Causal filters are scaled to unit DC gain (an even-order Chebyshev design
        would sit 0.5 dB low at DC).
    aa_order : int
        Order of a causal anti-alias filter (2-8; unused by ``linear-phase``).
    aa_cutoff : float or None
        Anti-alias cut-off (Hz, below the Nyquist frequency; a ``bessel``'s up to where
        its -3 dB point reaches it, :func:`vidiscover.acquisition.max_cutoff`: an
        anti-alias Bessel specified "at" f -3 dB is phase-normalised at 1.27-1.93 f);
        None: ``cutoff * sample_rate``.
    a_bias : float
        Accelerometer DC bias (m/s^2), added to ``a``.
    x_offset, xe_offset : float
        Zero offsets of the laser and of the base sensor (m), added to ``x``, ``xe``.
    adc_bits : int or None
        ADC resolution (2-32 bits): each channel is quantised to ``2**adc_bits``
        levels of ``2 * full_scale / 2**adc_bits`` (two's-complement codes, so the
        readings span ``[-full_scale, full_scale - LSB]``) and saturates there.
        None: no quantisation.
    x_full_scale, xe_full_scale : float
        ADC full scale of the laser and of the base sensor (m; +/- 10 mm).
    a_full_scale : float
        ADC full scale of the accelerometer (m/s^2; +/- 50 g).
    mount_resonance : float or None
        Mounted resonance of the accelerometer (Hz): ``a`` passes through
        ``w^2 / (s^2 + 2 zeta w s + w^2)``. None: a rigid mount.
    mount_zeta : float
        Damping ratio of the mounted resonance (default 0.02, i.e. Q = 25: a +28 dB
        peak, typical of stud-mounted piezoelectric accelerometers).
    sensitivity : mapping or None
        ``x_mV_per_mm``, ``xe_mV_per_mm``, ``a_mV_per_g`` used for ``units="mV"``
        (missing keys: the paper's); None: :data:`~vidiscover.recording.PAPER_SENSITIVITY`.
        The recording's metadata carry the sensitivities used.
    oversample : int
        Oversampling factor of the general acquisition path (1-64). The digital
        filters there converge to their analog designs as ``oversample**-2``: at 16
        the DC group delay is 0.26 % short of the analog one and the pulses lie
        within 0.5 % of their peak from the limit (0.1 % at 32, for twice the cost);
        pulse areas are exact at any factor.
    """

    sample_rate: float = 6400.0
    x_noise: float = 1e-6
    xe_noise: float = 1e-6
    a_noise: float = 0.05
    cutoff: float = 0.45
    a_range: float | None = None
    kernel_halfwidth: int = 24
    anti_alias: str = "linear-phase"
    aa_order: int = 4
    aa_cutoff: float | None = None
    a_bias: float = 0.0
    x_offset: float = 0.0
    xe_offset: float = 0.0
    adc_bits: int | None = None
    x_full_scale: float = 0.01
    xe_full_scale: float = 0.01
    a_full_scale: float = 50 * G_ACCEL
    mount_resonance: float | None = None
    mount_zeta: float = 0.02
    sensitivity: Mapping[str, float] | None = field(default=None, hash=False)
    oversample: int = 16

    def __post_init__(self) -> None:
        if not self.sample_rate > 0:
            raise InputError(f"sample_rate must be > 0 Hz, was {self.sample_rate!r}")
        for name in ("x_noise", "xe_noise", "a_noise"):
            if not getattr(self, name) >= 0:
                raise InputError(f"{name} must be >= 0, was {getattr(self, name)!r}")
        if not 0 < self.cutoff < 0.5:
            raise InputError(f"cutoff must be in (0, 0.5) of the sampling rate, "
                             f"was {self.cutoff!r}")
        if self.a_range is not None and not self.a_range > 0:
            raise InputError(f"a_range must be > 0 m/s^2 or None, was {self.a_range!r}")
        self._check_chain()

    def _check_chain(self) -> None:
        """Validate the instrument-chain fields (one-line InputError each)."""
        def integer(name, lo, hi):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
                raise InputError(f"sensor setting {name} must be an integer in [{lo}, {hi}], "
                                 f"was {v!r}")

        def number(name, positive):
            v = getattr(self, name)
            ok = isinstance(v, (int, float, np.number)) and not isinstance(v, bool) \
                and math.isfinite(v) and (v > 0 or not positive)
            if not ok:
                need = "a finite number > 0" if positive else "a finite number"
                raise InputError(f"sensor setting {name} must be {need}, was {v!r}")

        if self.anti_alias not in ANTI_ALIAS_KINDS:
            raise InputError(f"unknown anti_alias {self.anti_alias!r}; use one of "
                             f"{', '.join(ANTI_ALIAS_KINDS)}")
        integer("aa_order", 2, 8)
        integer("oversample", 1, 64)
        if self.aa_cutoff is not None:
            number("aa_cutoff", True)
            if self.aa_cutoff >= _aa_limit(self.anti_alias, self.aa_order, self.sample_rate):
                raise InputError(f"aa_cutoff {self.aa_cutoff!r} Hz must be below "
                                 f"{_aa_where(self.anti_alias, self.aa_order, self.sample_rate)}")
            if self.aa_cutoff >= 0.5 * self.oversample * self.sample_rate:
                raise InputError(f"aa_cutoff {self.aa_cutoff!r} Hz must be below half the "
                                 f"oversampled rate ({0.5 * self.oversample * self.sample_rate:g}"
                                 " Hz); raise oversample")
        for name in ("a_bias", "x_offset", "xe_offset"):
            number(name, False)
        for name in ("x_full_scale", "xe_full_scale", "a_full_scale"):
            number(name, True)
        if self.adc_bits is not None:
            integer("adc_bits", 2, 32)
        if self.mount_resonance is not None:
            number("mount_resonance", True)
            nyq = 0.5 * self.oversample * self.sample_rate
            if self.mount_resonance >= nyq:
                raise InputError(f"mount_resonance {self.mount_resonance!r} Hz must be below "
                                 f"half the oversampled rate ({nyq:g} Hz); raise oversample")
        number("mount_zeta", True)
        if not self.mount_zeta < 1:
            raise InputError(f"mount_zeta must be in (0, 1), was {self.mount_zeta!r}")
        if self.sensitivity is not None:
            if not isinstance(self.sensitivity, Mapping):
                raise InputError("sensor sensitivity must be a mapping like "
                                 f"{{'a_mV_per_g': 50.34}}, was {self.sensitivity!r}")
            unknown = sorted(set(self.sensitivity) - set(PAPER_SENSITIVITY))
            if unknown:
                raise InputError(f"unknown sensitivity key(s) {', '.join(map(str, unknown))}; "
                                 f"use {', '.join(PAPER_SENSITIVITY)}")
            sens = {**PAPER_SENSITIVITY, **self.sensitivity}
            for k, v in sens.items():
                if isinstance(v, bool) or not isinstance(v, (int, float, np.number)) \
                        or not (math.isfinite(v) and v > 0):
                    raise InputError(f"sensitivity {k} must be a finite number > 0, was {v!r}")
            object.__setattr__(self, "sensitivity", {k: float(v) for k, v in sens.items()})

    @property
    def fc(self) -> float:
        """Anti-alias cut-off (Hz)."""
        return float(self.aa_cutoff) if self.aa_cutoff is not None \
            else self.cutoff * self.sample_rate

    @property
    def sensitivities(self) -> dict[str, float]:
        """The sensitivities used for ``units="mV"`` (mV/mm, mV/mm, mV/g)."""
        return dict(self.sensitivity) if self.sensitivity is not None \
            else dict(PAPER_SENSITIVITY)

    @staticmethod
    def parse_anti_alias(spec: str, sample_rate: float | None = None) -> dict:
        """SensorConfig fields of an ``--anti-alias`` spec.

        Parameters
        ----------
        spec : str
            ``linear-phase``, ``linear-phase::CUTOFF_HZ`` or ``KIND[:ORDER[:CUTOFF_HZ]]``
            with KIND ``butter``, ``bessel``, ``cheby1`` and ORDER 2-8.
        sample_rate : float, optional
            Sampling rate (Hz) to check the cut-off against its Nyquist frequency
            (without it, :class:`SensorConfig` checks it).

        Returns
        -------
        dict
            ``anti_alias`` and, when given, ``aa_order`` (int) and ``aa_cutoff`` (Hz).

        Raises
        ------
        InputError
            Unknown kind, a bad order or cut-off, a cut-off at or above Nyquist.
        """
        example = "e.g. --anti-alias butter:4:2800 or --anti-alias linear-phase"
        if not isinstance(spec, str) or not spec.strip():
            raise InputError(f"--anti-alias {spec!r}: empty; {example}")
        parts = [p.strip() for p in spec.strip().split(":")]
        kind = parts[0].lower()
        if kind not in ANTI_ALIAS_KINDS or len(parts) > 3:
            raise InputError(f"--anti-alias {spec!r}: expected KIND[:ORDER[:CUTOFF_HZ]] with "
                             f"KIND one of {', '.join(ANTI_ALIAS_KINDS)}; {example}")
        out: dict = {"anti_alias": kind}
        order = parts[1] if len(parts) > 1 else ""
        if order:
            if kind == "linear-phase":
                raise InputError(f"--anti-alias {spec!r}: linear-phase has no order; use "
                                 "linear-phase or linear-phase::CUTOFF_HZ")
            if not order.isdigit() or not 2 <= int(order) <= 8:
                raise InputError(f"--anti-alias {spec!r}: ORDER must be an integer 2-8, was "
                                 f"{order!r}; {example}")
            out["aa_order"] = int(order)
        if len(parts) > 2 and parts[2]:
            try:
                fc = float(parts[2])
            except ValueError:
                fc = math.nan
            if not (math.isfinite(fc) and fc > 0):
                raise InputError(f"--anti-alias {spec!r}: CUTOFF_HZ must be a number > 0 "
                                 f"(Hz), was {parts[2]!r}; {example}")
            n = out.get("aa_order", SensorConfig.aa_order)
            if sample_rate is not None and fc >= _aa_limit(kind, n, sample_rate):
                raise InputError(f"--anti-alias {spec!r}: cut-off {fc:g} Hz must be below "
                                 f"{_aa_where(kind, n, sample_rate)}")
            out["aa_cutoff"] = fc
        return out

    def scaled_noise(self, factor: float) -> SensorConfig:
        """A copy with every noise level multiplied by ``factor``."""
        from dataclasses import replace

        return replace(self, x_noise=self.x_noise * factor, xe_noise=self.xe_noise * factor,
                       a_noise=self.a_noise * factor)

    def to_dict(self) -> dict:
        """JSON-ready form (``SensorConfig(**d)`` rebuilds it)."""
        return asdict(self)


def record(result: SimulationResult, sensors: SensorConfig | None = None, seed: int = 0,
           units: str = "SI", name: str = "simulated") -> tuple[Recording, GroundTruth]:
    """Turn a simulation into a recording plus its ground truth.

    Parameters
    ----------
    result : SimulationResult
        The exact motion; the record covers [settle, settle + duration].
    sensors : SensorConfig, optional
        Acquisition settings (default: :class:`SensorConfig`).
    seed : int
        Seed of the noise.
    units : {"SI", "mV"}
        "mV" rounds the signals through the sensitivities ``sensors.sensitivities``
        (the returned :class:`Recording` is always SI and its ``meta.sensitivity`` holds
        the sensitivities used; writers use ``meta.extra["units"]``).
    name : str
        Recording label.

    Returns
    -------
    recording : Recording
    truth : GroundTruth
        Ground truth (impacts, sticking, ball motion, effects, parameters; no regime).

    Notes
    -----
    An impulsive result (the exact engine) with a ``linear-phase`` anti-alias filter
    and no mount resonance takes the analytic pulse path (module docstring). Any
    other chain takes the general path, at ``fs_os = oversample * sample_rate``:

    1. the LO velocity at the edges of bins centred on the oversampled instants
       gives ``a_os = diff(v) / dt_os``, the bin-averaged acceleration: it keeps the
       area of every velocity jump or contact pulse exactly (the motion is evaluated
       at the samples and midpoints and interpolated between them where it is smooth,
       evaluated at every edge elsewhere: :func:`_os_signals`). For an
       impulsive result, each jump is then shared between its two nearest instants
       in proportion to their distance (keeping its area and its centroid, so the
       impact time is not rounded to a bin) and shaped by the ``contact_duration``
       half-sine (centred, unit area); the laser reading ``x`` and ``xe`` are taken
       at the same instants;
    2. ``sensor_resonance``: the sheet deflection driven by ``a_os`` is added to x;
    3. the mount resonance filters ``a_os``;
    4. the anti-alias filter acts on all three channels: causal designs by
       ``sosfilt`` at ``fs_os``, ``linear-phase`` as the windowed sinc sampled at
       ``fs_os`` with its delay compensated;
    5. every ``oversample``-th sample, aligned with the record times, is kept.

    The causal filters start in their steady state for the first value, a warm-up
    before the record (up to ``settle``) lets their start transient decay.
    Then, on both paths: noise, bias and offsets, ``a_range`` clipping, ADC
    quantisation and saturation, and the mV rounding.
    """
    sensors = sensors or SensorConfig()
    if units not in ("SI", "mV"):
        raise InputError(f"units must be 'SI' or 'mV', was {units!r}")
    fs = sensors.sample_rate
    n = int(round(result.duration * fs))
    if n < 16:
        raise InputError(f"duration {result.duration!r} s gives only {n} samples at {fs} Hz")
    t_rec = np.arange(n) / fs
    t_sim = result.settle + t_rec
    st = result.evaluate(t_sim)
    rng = np.random.default_rng(seed)
    fx = result.effects
    imp = result.record_impacts()
    dv = imp.v_plus - imp.v_minus

    if (getattr(result, "impulsive", True) and sensors.anti_alias == "linear-phase"
            and sensors.mount_resonance is None):
        # accelerometer: smooth part + band-limited impact pulses
        a = st["xdd"].copy()
        hw = sensors.kernel_halfwidth
        cutoff = sensors.cutoff if sensors.aa_cutoff is None else sensors.aa_cutoff / fs
        # every pulse at once: samples c-hw-2 .. c+hw+2 around each impact's sample
        ti = imp.t - result.settle
        idx = np.rint(ti * fs).astype(np.int64)[:, None] + np.arange(-hw - 2, hw + 3)
        inside = (idx >= 0) & (idx < n)
        k = pulse_kernel(idx / fs - ti[:, None], fs, cutoff, fx.tau, hw)
        np.add.at(a, idx[inside], (dv[:, None] * k)[inside])
        # laser: true displacement (+ sheet resonance)
        x = st["x"].copy()
        if "sensor_resonance" in fx:
            x += _sheet_response(result, st, imp, dv, t_rec,
                                 fx.value("sensor_resonance", "f_s"),
                                 fx.value("sensor_resonance", "zeta_s"))
        xe = st["xe"]
    else:
        x, a, xe = _oversampled_chain(result, sensors, n, st)
    a += rng.normal(0.0, sensors.a_noise, n) if sensors.a_noise > 0 else 0.0
    x += rng.normal(0.0, sensors.x_noise, n) if sensors.x_noise > 0 else 0.0
    xe = xe + (rng.normal(0.0, sensors.xe_noise, n) if sensors.xe_noise > 0 else 0.0)
    if sensors.a_bias:
        a = a + sensors.a_bias
    if sensors.x_offset:
        x = x + sensors.x_offset
    if sensors.xe_offset:
        xe = xe + sensors.xe_offset
    if sensors.a_range is not None:
        a = np.clip(a, -sensors.a_range, sensors.a_range)
    if sensors.adc_bits is not None:
        x = _quantise(x, sensors.x_full_scale, sensors.adc_bits)
        xe = _quantise(xe, sensors.xe_full_scale, sensors.adc_bits)
        a = _quantise(a, sensors.a_full_scale, sensors.adc_bits)

    extra = {"units": units}
    sens = sensors.sensitivities
    if units == "mV":
        x = np.round(x * 1e3 * sens["x_mV_per_mm"], 3) / (1e3 * sens["x_mV_per_mm"])
        xe = np.round(xe * 1e3 * sens["xe_mV_per_mm"], 3) / (1e3 * sens["xe_mV_per_mm"])
        a = np.round(a / G_ACCEL * sens["a_mV_per_g"], 4) / sens["a_mV_per_g"] * G_ACCEL
    meta = Metadata.from_params(result.params, sample_rate=fs, sensitivity=sens, extra=extra,
                                source=name)
    rec = Recording(t_rec, x, a, xe, meta, name=name)
    truth = _truth(result, st, imp, dv, t_rec, sensors, seed)
    return rec, truth


def _quantise(v: np.ndarray, full_scale: float, bits: int) -> np.ndarray:
    """Two's-complement ADC: codes -2^(bits-1) .. 2^(bits-1) - 1 of 2 FS / 2^bits."""
    lsb = 2.0 * full_scale / 2.0 ** bits
    half = 2.0 ** (bits - 1)
    return np.clip(np.round(v / lsb), -half, half - 1) * lsb


def _resonator(f: float, zeta: float, fs: float) -> np.ndarray:
    """``w^2 / (s^2 + 2 zeta w s + w^2)`` as one SOS section at ``fs``.

    Bilinear transform with the resonance pre-warped to ``f``: exact DC gain and
    resonance frequency.
    """
    if not f < 0.5 * fs:
        raise InputError(f"a resonance of {f:g} Hz needs an oversampled rate above {2 * f:g} "
                         f"Hz (it is {fs:g} Hz); raise the sensors' oversample")
    w = 2 * math.pi * f
    k = w / math.tan(w / (2 * fs))
    den = np.array([k * k + 2 * zeta * w * k + w * w, 2 * (w * w - k * k),
                    k * k - 2 * zeta * w * k + w * w])
    return np.concatenate([w * w * np.array([1.0, 2.0, 1.0]), den])[None, :] / den[0]


@functools.lru_cache(maxsize=32)
def _anti_alias_sos(kind: str, order: int, fc: float, fs_os: float) -> np.ndarray:
    """Causal anti-alias filter at ``fs_os`` as SOS, scaled to unit DC gain."""
    from scipy import signal

    if kind == "butter":
        sos = signal.butter(order, fc, fs=fs_os, output="sos")
    elif kind == "bessel":
        sos = signal.bessel(order, fc, norm="phase", fs=fs_os, output="sos")
    else:
        sos = signal.cheby1(order, CHEBY1_RIPPLE_DB, fc, fs=fs_os, output="sos")
    sos = np.array(sos)
    sos[0, :3] /= np.prod(sos[:, :3].sum(axis=1) / sos[:, 3:].sum(axis=1))
    sos.flags.writeable = False
    return sos


@functools.lru_cache(maxsize=32)
def _anti_alias_fir(fc: float, fs: float, halfwidth: int, oversample: int) -> np.ndarray:
    """The linear-phase kernel sampled at ``oversample * fs`` (unit sum, centred)."""
    m = np.arange(-halfwidth * oversample, halfwidth * oversample + 1)
    h = pulse_kernel(m / (fs * oversample), fs, fc / fs, 0.0, halfwidth)
    h = h / h.sum()
    h.flags.writeable = False
    return h


def _settling_samples(sos: np.ndarray) -> float:
    """Decay time of the slowest pole of an SOS cascade, in samples (e-fold)."""
    r = max(float(np.max(np.abs(np.roots(sec[3:])))) for sec in sos)
    return 1.0 / -math.log(r) if r < 1 else math.inf


def _filter(sos: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Causal ``sosfilt`` along the last axis, started in the steady state of u[..., 0]."""
    from scipy import signal

    zi = signal.sosfilt_zi(sos)
    zi = zi.reshape((zi.shape[0],) + (1,) * (u.ndim - 1) + (2,)) * u[..., :1, None] \
        .reshape((1,) + u.shape[:-1] + (1,))
    return signal.sosfilt(np.array(sos), u, axis=-1, zi=zi)[0]   # a writable copy


def _impulse_split(result, a_os, edges, dt, tau):
    """Replace each impact's bin-averaged jump by a split between its nearest instants.

    The box average puts a jump at its bin's centre (up to half a bin off); sharing
    ``dv / dt`` between the two nearest instants in proportion to their distance keeps
    its area and centroid; ``tau > 0`` spreads it with the centred half-sine.
    """
    imp = result.impacts
    sel = (imp.t > edges[0]) & (imp.t <= edges[-1])
    ti, dvi = imp.t[sel], (imp.v_plus - imp.v_minus)[sel]
    if ti.size == 0:
        return a_os
    n = a_os.size
    a_os = a_os.copy()
    np.subtract.at(a_os, np.searchsorted(edges, ti, side="left") - 1, dvi / dt)
    half = int(tau / (2 * dt)) if tau > 0 else 0
    m = np.arange(-half, half + 1)
    shape = np.cos(math.pi * m * dt / tau) if half else np.ones(1)
    shape = shape / shape.sum()
    f = (ti - (edges[0] + 0.5 * dt)) / dt
    k = np.floor(f).astype(int)
    w = f - k
    for kk, ww, d in zip(k, w, dvi / dt):
        for start, weight in ((kk - half, 1.0 - ww), (kk + 1 - half, ww)):
            lo, hi = max(start, 0), min(start + shape.size, n)
            if hi > lo:
                a_os[lo:hi] += d * weight * shape[lo - start:hi - start]
    return a_os


def _fir_decimate(h: np.ndarray, w: np.ndarray, big: int, n: int) -> np.ndarray:
    """``upfirdn(h, w, 1, big)[..., q:q + n]`` with ``q = (h.size - 1) / big``, polyphase.

    Each of the ``big`` phases of ``w`` is convolved with its phase of ``h`` at the
    output rate, all in one real FFT (several times faster than ``upfirdn``).
    """
    from scipy import fft

    q = (h.size - 1) // big
    rows = -(-w.shape[-1] // big) + 1
    pad = np.zeros(w.shape[:-1] + (rows * big,))
    pad[..., big:big + w.shape[-1]] = w
    grid = pad.reshape(w.shape[:-1] + (rows, big))
    # phase r holds w[p big - r]
    phases = np.empty(w.shape[:-1] + (rows - 1, big))
    phases[..., 0] = grid[..., 1:, 0]
    phases[..., 1:] = grid[..., :-1, big - 1:0:-1]
    size = fft.next_fast_len(rows + q, real=True)
    spec = (fft.rfft(phases, size, axis=-2) * _taps_spectrum(h, big, size)).sum(axis=-1)
    return fft.irfft(spec, size, axis=-1)[..., q:q + n]


#: Spectra of polyphase taps, newest first (:func:`_taps_spectrum`).
_TAPS_SPECTRA: list = []


def _taps_spectrum(h: np.ndarray, big: int, size: int) -> np.ndarray:
    """``rfft`` of the ``big`` phases of ``h`` at length ``size`` (read-only).

    The same for every record of one chain and length: the last few are kept (a
    quarter of :func:`_fir_decimate`'s transforms), and a kept one is the array the
    transform gave, so the records are the same to the bit.
    """
    from scipy import fft

    key = (h.tobytes(), big, size)
    for k, spec in _TAPS_SPECTRA:
        if k == key:
            return spec
    q = (h.size - 1) // big
    taps = np.zeros((q + 1) * big)
    taps[:h.size] = h
    spec = fft.rfft(taps.reshape(q + 1, big), size, axis=0)
    spec.flags.writeable = False
    _TAPS_SPECTRA.insert(0, (key, spec))
    del _TAPS_SPECTRA[4:]
    return spec


def _odd_pad(u: np.ndarray, before: int, after: int) -> np.ndarray:
    """Extend the last axis by point reflection about the end values (keeps the slope)."""
    parts = [u]
    if before > 0:
        parts.insert(0, 2 * u[..., :1] - u[..., before:0:-1])
    if after > 0:
        parts.append(2 * u[..., -1:] - u[..., -2:-after - 2:-1])
    return np.concatenate(parts, axis=-1) if len(parts) > 1 else u


#: Mismatch at an interval's midpoint beyond which it is evaluated at every oversampled
#: instant instead of interpolated: LO displacement (m), velocity (m/s), acceleration.
_SMOOTH_TOL = (1e-11, 1e-9, 1e-5)


def _quintic_basis(s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Quintic Hermite basis at ``s`` in [0, 1]: value, 1st and 2nd derivative rows.

    Columns multiply ``p0, p0', p0'', p1, p1', p1''`` (derivatives in units of s).
    """
    c = np.array([[1, 0, 0, -10, 15, -6], [0, 1, 0, -6, 8, -3], [0, 0, .5, -1.5, 1.5, -.5],
                  [0, 0, 0, 10, -15, 6], [0, 0, 0, -4, 7, -3], [0, 0, 0, .5, -1, .5]])
    k = np.arange(6)
    pw = s[:, None] ** k
    d1 = np.where(k > 0, k * s[:, None] ** np.maximum(k - 1, 0), 0.0)
    d2 = np.where(k > 1, k * (k - 1) * s[:, None] ** np.maximum(k - 2, 0), 0.0)
    return pw @ c.T, d1 @ c.T, d2 @ c.T


def _os_signals(result, st, fs: float, n: int, big: int, n_pre: int):
    """Displacements at the oversampled instants and the LO velocity at the bin edges.

    The instants are ``p_i = settle + (i / big - n_pre) / fs``, ``i = 0 .. (n_pre + n -
    1) big``; the record samples are every ``big``-th. The result is evaluated at the
    sample-rate knots (``st`` holds the record's) and at the midpoints between them.
    Between knots the motion is the quintic Hermite interpolant of x, x', x''
    (xe: the quadratic through knots and midpoint); an interval whose midpoint the
    interpolant misses by more than :data:`_SMOOTH_TOL` (an impact, a contact, a
    stick/slip or friction switch) is evaluated at all its instants instead.

    Returns
    -------
    edges : ndarray
        Bin edges ``p_i -/+ dt / 2`` (one more than the instants).
    x, v_edges, xe : ndarray
        LO displacement, LO velocity at the edges, base displacement.
    """
    dt = 1.0 / (fs * big)
    h = 1.0 / fs
    settle = result.settle
    knots = settle + np.arange(-n_pre, n) / fs
    if n_pre:
        pre = result.evaluate(knots[:n_pre])
        kx, kv, ka, kxe = (np.concatenate([pre[c], st[c]]) for c in ("x", "xd", "xdd", "xe"))
    else:
        kx, kv, ka, kxe = st["x"], st["xd"], st["xdd"], st["xe"]
    mid = result.evaluate(knots[:-1] + 0.5 * h)
    coef = np.stack([kx[:-1], h * kv[:-1], h * h * ka[:-1], kx[1:], h * kv[1:],
                     h * h * ka[1:]], axis=1)
    b0, b1, b2 = _quintic_basis(np.array([0.5]))
    bad = (np.abs(coef @ b0[0] - mid["x"]) > _SMOOTH_TOL[0]) \
        | (np.abs(coef @ b1[0] / h - mid["xd"]) > _SMOOTH_TOL[1]) \
        | (np.abs(coef @ b2[0] / (h * h) - mid["xdd"]) > _SMOOTH_TOL[2])
    m = np.arange(big)
    bx = _quintic_basis(m / big)[0]
    bv = _quintic_basis((m + 0.5) / big)[1] / h
    x = np.empty(knots.size * big - big + 1)
    v = np.empty(x.size + 1)
    xe = np.empty(x.size)
    u = m / big                 # xe: quadratic through the knots and the midpoint
    lag = np.stack([(2 * u - 1) * (u - 1), 4 * u * (1 - u), u * (2 * u - 1)])
    knots_mid = np.stack([kxe[:-1], mid["xe"], kxe[1:]], axis=1)
    # one BLAS thread: these products have an inner dimension of 3-6, and a
    # multi-threaded BLAS is 10-30x slower on them on a busy machine
    # the products are written in place (x[:-1] holds one row of `big` per interval)
    with one_blas_thread():
        np.matmul(coef, bx.T, out=x[:-1].reshape(-1, big))
        np.matmul(coef, bv.T, out=v[1:-1].reshape(-1, big))
        np.matmul(knots_mid, lag, out=xe[:-1].reshape(-1, big))
    x[-1] = kx[-1]
    xe[-1] = kxe[-1]
    ends = result.evaluate(np.array([knots[0] - 0.5 * dt, knots[-1] + 0.5 * dt]))["xd"]
    v[0], v[-1] = ends
    idx = np.flatnonzero(bad)
    if idx.size:
        t_c = (knots[idx][:, None] + m * dt).ravel()
        exact = result.evaluate(np.concatenate([t_c, t_c + 0.5 * dt]))
        sel = (idx[:, None] * big + m).ravel()
        x[sel], xe[sel] = exact["x"][:sel.size], exact["xe"][:sel.size]
        v[sel + 1] = exact["xd"][sel.size:]
    edges = np.arange(v.size, dtype=float)     # knots[0] + (i - 0.5) dt, in place
    edges -= 0.5
    edges *= dt
    edges += knots[0]
    return edges, x, v, xe
#: Warm-up of the causal filters in e-folds of their slowest pole, and its cap (s).
_WARM_EFOLDS, _WARM_MAX = 10.0, 0.5


def _oversampled_chain(result, cfg: SensorConfig, n: int, st: dict):
    """The general acquisition path (see :func:`record`): noise-free x, a, xe."""
    fs, big = cfg.sample_rate, cfg.oversample
    fs_os = fs * big
    dt = 1.0 / fs_os
    fx = result.effects
    causal = cfg.anti_alias != "linear-phase"
    pre_a = _resonator(cfg.mount_resonance, cfg.mount_zeta, fs_os) \
        if cfg.mount_resonance is not None else None
    sheet = None
    if "sensor_resonance" in fx:
        f_s = fx.value("sensor_resonance", "f_s")
        sheet = _resonator(f_s, fx.value("sensor_resonance", "zeta_s"), fs_os)
        sheet = sheet * np.array([-1.0 / (2 * math.pi * f_s) ** 2] * 3 + [1.0] * 3)
    if causal:
        aa = _anti_alias_sos(cfg.anti_alias, cfg.aa_order, cfg.fc, fs_os)
        half = 0
    else:
        aa = _anti_alias_fir(cfg.fc, fs, cfg.kernel_halfwidth, big)
        half = cfg.kernel_halfwidth * big
    cascades = [s for s in (pre_a, sheet, aa if causal else None) if s is not None]
    warm = max([_settling_samples(s) for s in cascades] + [0.0]) * _WARM_EFOLDS
    warm = int(min(warm, _WARM_MAX * fs_os))
    # oversampled instants: n_pre knots (sample intervals) before the record
    last = (n - 1) * big
    n_pre = max(min(-(-(warm + half) // big), int(result.settle * fs - 0.5 / big)), 0)
    pre, post = n_pre * big, 0
    edges, x_os, v, xe_os = _os_signals(result, st, fs, n, big, n_pre)
    a_os = np.diff(v) / dt
    if getattr(result, "impulsive", True):
        a_os = _impulse_split(result, a_os, edges, dt, fx.tau)
    if sheet is not None:
        x_os = x_os + _filter(sheet, a_os)
    if pre_a is not None:
        a_os = _filter(pre_a, a_os)
    u = _odd_pad(np.vstack([x_os, a_os, xe_os]), half - min(pre, half),
                 half - post)
    i0 = pre + half - min(pre, half)                # index of the first record sample
    if causal:
        y = _filter(aa, u)[:, i0:i0 + last + 1:big]
    else:
        y = _fir_decimate(aa, u[:, i0 - half:], big, n)
    return y[0].copy(), y[1].copy(), y[2].copy()


def _sheet_response(result, st, imp, dv, t_rec, f_s, zeta):
    """Deflection q of the aluminium sheet read by the laser (base-excited oscillator)."""
    from scipy import signal

    w = 2 * math.pi * f_s
    wd = w * math.sqrt(1 - zeta ** 2)
    fs = 1.0 / (t_rec[1] - t_rec[0])
    # smooth part: exact discretisation of q'' + 2 zeta w q' + w^2 q = -x''
    sysd = signal.cont2discrete(([-1.0], [1.0, 2 * zeta * w, w * w]), 1 / fs, method="foh")
    q = signal.lfilter(np.ravel(sysd[0]), sysd[1], st["xdd"])
    # impacts: impulse response to each LO velocity jump
    for ti, dvi in zip(imp.t - result.settle, dv):
        k0 = int(np.searchsorted(t_rec, ti))
        ts = t_rec[k0:] - ti
        ts = ts[ts < 12.0 / (zeta * w)]
        q[k0:k0 + ts.size] -= dvi / wd * np.exp(-zeta * w * ts) * np.sin(wd * ts)
    return q


def _truth(result, st, imp, dv, t_rec, sensors, seed) -> GroundTruth:
    contact = getattr(result, "contact", None)
    return GroundTruth(
        params=result.params, effects=result.effects, b_true=result.b, settle=result.settle,
        duration=result.duration, seed=seed, sensors=sensors.to_dict(),
        impacts=TrueImpacts.from_table(imp, t_offset=result.settle, dv=dv),
        motion=TrueMotion(t0=0.0, dt=float(t_rec[1] - t_rec[0]), x=st["x"], xd=st["xd"],
                          y=st["y"], yd=st["yd"]),
        sticking=result.record_sticking(), status=result.status, message=result.message,
        contact=None if contact is None else contact.to_dict())
