"""Physical parameters of the LO + ball system, as validated values.

The ``paper`` preset is Table 1 of Li et al. (2018) with the shaker settings of
their experiment (0.5 mm at 8 Hz). Reduced parameters of the paper's
dimensionless model (epsilon, lambda, Omega, G) are derived properties.

Examples
--------
>>> from vidiscover.params import preset
>>> p = preset("paper", b=0.009)
>>> round(p.epsilon, 4), round(p.lambda_, 2)
(0.0077, 1.8)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from .errors import InputError

__all__ = ["SystemParams", "PRESETS", "preset", "G_ACCEL"]

#: Standard gravity (m/s^2), used for friction and inclination forces.
G_ACCEL = 9.81


def _check_positive(name: str, value: float, unit: str, what: str,
                    upper: float | None = None, hint: str = "check the units") -> None:
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"{name} must be a finite number ({what}, {unit}), was {value!r}")
    if value <= 0:
        raise InputError(f"{name} must be > 0 ({what}, {unit}), was {value!r}")
    if upper is not None and value > upper:
        raise InputError(f"{name} = {value!r} {unit} is implausibly large for the {what} "
                         f"(limit {upper:g} {unit}); {hint}")


@dataclass(frozen=True)
class SystemParams:
    """Parameters of the linear oscillator, the ball and the base excitation.

    Parameters
    ----------
    m1, c1, k1 : float
        LO mass (kg), damping (N s/m) and stiffness (N/m).
    m2 : float
        Ball mass (kg).
    b : float
        Nominal half-clearance (m): the walls are at z = +b (right) and z = -b (left).
    amplitude, frequency : float
        Base displacement amplitude (m) and frequency (Hz): xe = A sin(2 pi f t).
    r : float
        Restitution coefficient of both walls in the nominal model (effects such as
        ``asymmetric_restitution`` override it per wall).
    """

    m1: float = 4.168
    c1: float = 3.02
    k1: float = 11.47e3
    m2: float = 0.032
    b: float = 0.0115
    amplitude: float = 0.5e-3
    frequency: float = 8.0
    r: float = 0.88

    def __post_init__(self) -> None:
        _check_positive("m1", self.m1, "kg", "LO mass", 1e4)
        _check_positive("m2", self.m2, "kg", "ball mass", 1e3)
        _check_positive("k1", self.k1, "N/m", "LO stiffness")
        _check_positive("b", self.b, "m", "half-clearance", 1.0,
                        "b is in metres, e.g. 0.009 for 9 mm")
        _check_positive("amplitude", self.amplitude, "m", "base amplitude", 0.1,
                        "the amplitude is in metres, e.g. 0.0005 for 0.5 mm")
        _check_positive("frequency", self.frequency, "Hz", "forcing frequency", 1e4)
        if not (isinstance(self.c1, (int, float)) and math.isfinite(self.c1) and self.c1 >= 0):
            raise InputError(f"c1 must be >= 0 (N s/m, LO damping), was {self.c1!r}")
        if self.c1 >= 2.0 * math.sqrt(self.k1 * self.m1):
            raise InputError(f"c1 = {self.c1!r} N s/m makes the LO overdamped; "
                             "vidiscover models an underdamped LO (c1 < 2 sqrt(k1 m1))")
        if not (isinstance(self.r, (int, float)) and 0.0 <= self.r <= 1.0):
            raise InputError(f"r must be in [0, 1] (restitution coefficient), was {self.r!r}")

    # --- reduced parameters of the paper (eq. 3) ---------------------------------
    @property
    def epsilon(self) -> float:
        """Mass ratio m2 / m1."""
        return self.m2 / self.m1

    @property
    def omega0(self) -> float:
        """LO natural angular frequency sqrt(k1/m1) (rad/s)."""
        return math.sqrt(self.k1 / self.m1)

    @property
    def lambda_(self) -> float:
        """Reduced damping c1 / (m2 omega0)."""
        return self.c1 / (self.m2 * self.omega0)

    @property
    def Omega(self) -> float:  # noqa: N802 - the paper's symbol
        """Frequency ratio omega / omega0."""
        return 2.0 * math.pi * self.frequency / self.omega0

    @property
    def G(self) -> float:  # noqa: N802 - the paper's symbol
        """Reduced forcing amplitude A / epsilon (m)."""
        return self.amplitude / self.epsilon

    @property
    def period(self) -> float:
        """Forcing period 1/f (s)."""
        return 1.0 / self.frequency

    def replace(self, **changes: float) -> SystemParams:
        """Return a copy with some fields changed (validated again).

        Raises
        ------
        InputError
            If a name is not a field of :class:`SystemParams`.
        """
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise InputError(f"unknown parameter(s) {', '.join(unknown)}; "
                             f"known: {', '.join(sorted(names))}")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, float]:
        """Plain-dict form (JSON-ready)."""
        return dataclasses.asdict(self)


#: Named parameter sets. ``paper``: Table 1 of the source paper (b = 11.5 mm as
#: tabulated; the clearances studied are 6, 7.5, 9, 15 and 17.5 mm).
PRESETS: dict[str, SystemParams] = {
    "paper": SystemParams(),
}


def preset(name: str, **changes: float) -> SystemParams:
    """Return the preset ``name`` with optional field changes.

    Raises
    ------
    InputError
        If the preset does not exist.
    """
    try:
        base = PRESETS[name]
    except KeyError:
        raise InputError(f"unknown preset {name!r}; choose one of: "
                         f"{', '.join(sorted(PRESETS))}") from None
    return base.replace(**changes) if changes else base
