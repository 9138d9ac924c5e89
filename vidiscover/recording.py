"""Recordings as values: the measured signals plus their metadata.

A :class:`Recording` holds uniformly sampled ``t``, ``x`` (LO displacement, m),
``a`` (LO acceleration, m/s^2) and ``xe`` (base displacement, m) in SI units, and a
:class:`Metadata` value (the README's 'Recording format'). Reading and writing files lives in
:mod:`vidiscover.io`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from .errors import InputError
from .params import SystemParams

__all__ = ["Metadata", "Recording", "PAPER_SENSITIVITY"]

#: Sensor sensitivities of the paper's rig.
PAPER_SENSITIVITY = {"x_mV_per_mm": 10000.0, "xe_mV_per_mm": 10000.0, "a_mV_per_g": 50.34}


def _positive(where: str, name: str, value: Any, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{where}: '{name}' must be a number ({unit}), was {value!r}") from None
    if not math.isfinite(v) or v <= 0:
        raise InputError(f"{where}: '{name}' must be > 0 ({unit}), was {value!r}; "
                         "fix the metadata")
    return v


@dataclass(frozen=True)
class Metadata:
    """Metadata of a recording (the README's 'Recording format'); only ``b`` is required.

    Parameters
    ----------
    b : float
        Nominal half-clearance (m).
    sample_rate : float or None
        Sampling rate (Hz); None: taken from ``t``.
    m1, m2, c1, k1 : float
        LO and ball parameters (paper's values by default).
    excitation : dict
        ``{"amplitude": m, "frequency": Hz}``.
    sensitivity : dict
        ``x_mV_per_mm``, ``xe_mV_per_mm``, ``a_mV_per_g`` for files in mV: only the
        keys given (a file in mV without its sensitivities is refused, never
        converted with assumed values such as the paper's :data:`PAPER_SENSITIVITY`).
    extra : dict
        Any other keys found in the file (kept, not interpreted).
    source : str
        Where the metadata came from, used in error messages.
    """

    b: float
    sample_rate: float | None = None
    m1: float = 4.168
    m2: float = 0.032
    c1: float = 3.02
    k1: float = 11.47e3
    excitation: Mapping[str, float] = field(
        default_factory=lambda: {"amplitude": 0.5e-3, "frequency": 8.0})
    sensitivity: Mapping[str, float] = field(default_factory=dict)
    extra: Mapping[str, Any] = field(default_factory=dict)
    source: str = "metadata"

    def __post_init__(self) -> None:
        where = self.source
        b = _positive(where, "b", self.b, "half-clearance in m")
        if b > 1.0:
            raise InputError(f"{where}: 'b' = {self.b!r} m is implausibly large; b is in "
                             "metres (e.g. 0.009 for 9 mm)")
        object.__setattr__(self, "b", b)
        for name, unit in (("m1", "kg"), ("m2", "kg"), ("k1", "N/m")):
            object.__setattr__(self, name, _positive(where, name, getattr(self, name), unit))
        try:
            c1 = float(self.c1)
        except (TypeError, ValueError):
            raise InputError(f"{where}: 'c1' must be a number (N s/m), was {self.c1!r}") from None
        if not math.isfinite(c1) or c1 < 0:
            raise InputError(f"{where}: 'c1' must be >= 0 (N s/m), was {self.c1!r}")
        object.__setattr__(self, "c1", c1)
        if self.sample_rate is not None:
            object.__setattr__(self, "sample_rate",
                               _positive(where, "sample_rate", self.sample_rate, "Hz"))
        exc = dict(self.excitation or {})
        unknown = sorted(set(exc) - {"amplitude", "frequency"})
        if unknown:
            raise InputError(f"{where}: unknown excitation key(s) {', '.join(unknown)}; "
                             "use 'amplitude' (m) and 'frequency' (Hz)")
        exc = {"amplitude": _positive(where, "excitation.amplitude",
                                      exc.get("amplitude", 0.5e-3), "m"),
               "frequency": _positive(where, "excitation.frequency",
                                      exc.get("frequency", 8.0), "Hz")}
        if exc["amplitude"] > 0.1:
            raise InputError(f"{where}: excitation.amplitude = {exc['amplitude']!r} m is "
                             "implausibly large; it is in metres (e.g. 0.0005 for 0.5 mm)")
        object.__setattr__(self, "excitation", exc)
        sens = {}
        given = dict(self.sensitivity or {})
        unknown = sorted(set(given) - set(PAPER_SENSITIVITY))
        if unknown:
            raise InputError(f"{where}: unknown sensitivity key(s) {', '.join(unknown)}; "
                             f"known: {', '.join(PAPER_SENSITIVITY)}")
        for k, v in given.items():
            sens[k] = _positive(where, f"sensitivity.{k}", v, "mV per unit")
        object.__setattr__(self, "sensitivity", sens)

    @property
    def amplitude(self) -> float:
        """Nominal base amplitude (m)."""
        return float(self.excitation["amplitude"])

    @property
    def frequency(self) -> float:
        """Nominal forcing frequency (Hz)."""
        return float(self.excitation["frequency"])

    def params(self, r: float = 0.88) -> SystemParams:
        """The nominal :class:`SystemParams` these metadata describe."""
        return SystemParams(m1=self.m1, c1=self.c1, k1=self.k1, m2=self.m2, b=self.b,
                            amplitude=self.amplitude, frequency=self.frequency, r=r)

    @classmethod
    def from_params(cls, p: SystemParams, sample_rate: float | None = None,
                    **kw: Any) -> Metadata:
        """Metadata describing parameters ``p``."""
        return cls(b=p.b, sample_rate=sample_rate, m1=p.m1, m2=p.m2, c1=p.c1, k1=p.k1,
                   excitation={"amplitude": p.amplitude, "frequency": p.frequency}, **kw)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the sidecar file's content)."""
        d = asdict(self)
        d.pop("source")
        extra = d.pop("extra")
        d["excitation"] = dict(self.excitation)
        d["sensitivity"] = dict(self.sensitivity)
        d.update(extra)
        return d


@dataclass(frozen=True, eq=False)
class Recording:
    """A uniformly sampled recording in SI units.

    Parameters
    ----------
    t : ndarray
        Time (s), uniform and increasing.
    x : ndarray
        LO displacement (m).
    a : ndarray
        LO acceleration (m/s^2).
    xe : ndarray
        Base displacement (m).
    meta : Metadata
    name : str
        A label for messages and reports (file stem for files).
    """

    t: np.ndarray
    x: np.ndarray
    a: np.ndarray
    xe: np.ndarray
    meta: Metadata
    name: str = "recording"

    def __post_init__(self) -> None:
        n = None
        for col in ("t", "x", "a", "xe"):
            arr = np.asarray(getattr(self, col), dtype=float)
            if arr.ndim != 1:
                raise InputError(f"{self.name}: column '{col}' must be one-dimensional, "
                                 f"has shape {arr.shape}")
            if n is None:
                n = arr.size
            elif arr.size != n:
                raise InputError(f"{self.name}: column '{col}' has {arr.size} samples, "
                                 f"'t' has {n}")
            arr.flags.writeable = False
            object.__setattr__(self, col, arr)

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def dt(self) -> float:
        """Sampling interval (s)."""
        return float(self.t[1] - self.t[0]) if self.n > 1 else float("nan")

    @property
    def sample_rate(self) -> float:
        """Sampling rate (Hz): metadata if given, else from ``t``."""
        return float(self.meta.sample_rate) if self.meta.sample_rate else 1.0 / self.dt

    @property
    def duration(self) -> float:
        """Record length n * dt (s)."""
        return self.n / self.sample_rate

    def to_frame(self):
        """The signals as a pandas DataFrame with columns t, x, a, xe."""
        import pandas as pd

        return pd.DataFrame({"t": self.t, "x": self.x, "a": self.a, "xe": self.xe})
