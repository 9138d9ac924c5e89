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

Everything random is drawn from ``numpy.random.default_rng(seed)``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy.special import i0 as _i0

from .errors import InputError
from .params import G_ACCEL
from .recording import PAPER_SENSITIVITY, Metadata, Recording
from .simulation import SimulationResult

__all__ = ["SensorConfig", "record", "pulse_kernel"]


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
    """

    sample_rate: float = 6400.0
    x_noise: float = 1e-6
    xe_noise: float = 1e-6
    a_noise: float = 0.05
    cutoff: float = 0.45
    a_range: float | None = None
    kernel_halfwidth: int = 24

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

    def scaled_noise(self, factor: float) -> SensorConfig:
        """A copy with every noise level multiplied by ``factor``."""
        from dataclasses import replace

        return replace(self, x_noise=self.x_noise * factor, xe_noise=self.xe_noise * factor,
                       a_noise=self.a_noise * factor)

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return asdict(self)


_GAUSS16 = np.polynomial.legendre.leggauss(16)


def pulse_kernel(dt_samples: np.ndarray, sample_rate: float, cutoff: float, tau: float,
                 halfwidth: int) -> np.ndarray:
    """Sampled response (1/s) of the acquisition chain to a unit-area impact pulse.

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
        win = np.where(np.abs(t) < span, _i0(8.0 * np.sqrt(np.clip(1 - (t / span) ** 2,
                                                                      0, None))) / _i0(8.0),
                       0.0)
        return 2 * fc * np.sinc(2 * fc * t) * win

    if tau <= 0:
        return lowpass(dt_samples)
    nodes, weights = _GAUSS16
    s = 0.5 * tau * nodes                                        # pulse on [-tau/2, tau/2]
    p = (math.pi / (2 * tau)) * np.cos(math.pi * s / tau) * 0.5 * tau * weights
    return np.tensordot(lowpass(dt_samples[..., None] - s), p, axes=([-1], [0]))


def record(result: SimulationResult, sensors: SensorConfig | None = None, seed: int = 0,
           units: str = "SI", name: str = "simulated") -> tuple[Recording, dict]:
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
        "mV" rounds the signals through the paper's sensor sensitivities (the
        returned :class:`Recording` is always SI; writers use ``meta.extra["units"]``).
    name : str
        Recording label.

    Returns
    -------
    recording : Recording
    truth : dict
        JSON-ready ground truth (impacts, sticking, ball motion, effects, parameters).
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

    # accelerometer: smooth part + band-limited impact pulses
    a = st["xdd"].copy()
    hw = sensors.kernel_halfwidth
    for ti, dvi in zip(imp.t - result.settle, dv):
        c = int(round(ti * fs))
        lo, hi = max(c - hw - 2, 0), min(c + hw + 3, n)
        if hi <= lo:
            continue
        a[lo:hi] += dvi * pulse_kernel(t_rec[lo:hi] - ti, fs, sensors.cutoff, fx.tau, hw)
    a += rng.normal(0.0, sensors.a_noise, n) if sensors.a_noise > 0 else 0.0

    # laser: true displacement (+ sheet resonance) + noise
    x = st["x"].copy()
    if "sensor_resonance" in fx:
        x += _sheet_response(result, st, imp, dv, t_rec, fx.value("sensor_resonance", "f_s"),
                             fx.value("sensor_resonance", "zeta_s"))
    x += rng.normal(0.0, sensors.x_noise, n) if sensors.x_noise > 0 else 0.0
    xe = st["xe"] + (rng.normal(0.0, sensors.xe_noise, n) if sensors.xe_noise > 0 else 0.0)
    if sensors.a_range is not None:
        a = np.clip(a, -sensors.a_range, sensors.a_range)

    extra = {"units": units}
    if units == "mV":
        sens = PAPER_SENSITIVITY
        x = np.round(x * 1e3 * sens["x_mV_per_mm"], 3) / (1e3 * sens["x_mV_per_mm"])
        xe = np.round(xe * 1e3 * sens["xe_mV_per_mm"], 3) / (1e3 * sens["xe_mV_per_mm"])
        a = np.round(a / G_ACCEL * sens["a_mV_per_g"], 4) / sens["a_mV_per_g"] * G_ACCEL
    meta = Metadata.from_params(result.params, sample_rate=fs, extra=extra, source=name)
    rec = Recording(t_rec, x, a, xe, meta, name=name)
    truth = _truth(result, st, imp, dv, t_rec, sensors, seed)
    return rec, truth


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


def _truth(result, st, imp, dv, t_rec, sensors, seed) -> dict:
    recs = imp.to_records(t_offset=result.settle)
    for r, d in zip(recs, dv):
        r["dv"] = float(d)
    return {
        "version": 1,
        "params": result.params.to_dict(),
        "effects": result.effects.to_dict(),
        "b_true": result.b,
        "settle": result.settle,
        "duration": result.duration,
        "seed": seed,
        "sensors": sensors.to_dict(),
        "status": result.status,
        "message": result.message,
        "impacts": recs,
        "sticking": [{"t_start": a, "t_end": b, "where": w}
                     for a, b, w in result.record_sticking()],
        "motion": {"t0": 0.0, "dt": float(t_rec[1] - t_rec[0]),
                   "x": st["x"].tolist(), "xd": st["xd"].tolist(),
                   "y": st["y"].tolist(), "yd": st["yd"].tolist()},
        "regime": None,
    }
