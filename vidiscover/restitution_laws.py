"""Restitution laws r(v): the coefficient of restitution as a function of impact speed.

A law is a small frozen value. Laws are registered by kind so that the same tests,
the simulator, the CLI parser and the discovery stage all see the same catalogue.

Spec strings (CLI): ``"0.88"`` or ``"constant:0.88"`` (r = r0),
``"linear:0.95:0.12"`` (r = r0 - a v), ``"power:0.3:0.5"`` (r = 1 - a v^p).

Examples
--------
>>> law = RestitutionLaw.parse("linear:0.95:0.1")
>>> round(law(0.5), 3)
0.9
>>> law.formula
'r = 0.95 - 0.1 v'
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import InputError

__all__ = ["RestitutionLaw", "LAW_KINDS"]

#: kind -> (parameter names, formula template)
LAW_KINDS: dict[str, tuple[tuple[str, ...], str]] = {
    "constant": (("r0",), "r = {r0:.4g}"),
    "linear": (("r0", "a"), "r = {r0:.4g} - {a:.4g} v"),
    "power": (("a", "p"), "r = 1 - {a:.4g} v^{p:.4g}"),
}


@dataclass(frozen=True)
class RestitutionLaw:
    """Restitution coefficient as a function of the impact speed v = |z'-| (m/s).

    Parameters
    ----------
    kind : {"constant", "linear", "power"}
        Functional form.
    r0, a, p : float
        Coefficients; which ones are used depends on ``kind``
        (see :data:`LAW_KINDS`). The value is clipped to [0, 1].
    """

    kind: str = "constant"
    r0: float = 0.88
    a: float = 0.0
    p: float = 1.0

    def __post_init__(self) -> None:
        if self.kind not in LAW_KINDS:
            raise InputError(f"restitution law kind must be one of {', '.join(LAW_KINDS)}, "
                             f"was {self.kind!r}")
        for name in ("r0", "a", "p"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InputError(f"restitution law {name} must be a finite number, was {value!r}")
        if self.kind in ("constant", "linear") and not 0.0 <= self.r0 <= 1.0:
            raise InputError(f"restitution law r0 must be in [0, 1], was {self.r0!r}")
        if self.kind == "power" and not 0.0 < self.p <= 3.0:
            raise InputError(f"restitution law exponent p must be in (0, 3], was {self.p!r}")
        if self.kind != "constant" and self.a < 0:
            raise InputError(f"restitution law slope a must be >= 0 (r falls with speed), "
                             f"was {self.a!r}")

    @classmethod
    def constant(cls, r: float) -> RestitutionLaw:
        """A speed-independent coefficient ``r``."""
        return cls("constant", r0=float(r))

    @classmethod
    def parse(cls, spec: str | float | RestitutionLaw) -> RestitutionLaw:
        """Parse ``"0.88"``, ``"constant:0.88"``, ``"linear:r0:a"`` or ``"power:a:p"``."""
        if isinstance(spec, RestitutionLaw):
            return spec
        if isinstance(spec, (int, float)):
            return cls.constant(float(spec))
        text = str(spec).strip()
        parts = [s.strip() for s in text.split(":")]
        if len(parts) == 1:
            parts = ["constant", parts[0]]
        kind, values = parts[0], parts[1:]
        if kind not in LAW_KINDS:
            raise InputError(f"restitution law {text!r}: kind must be one of "
                             f"{', '.join(LAW_KINDS)} (e.g. 'linear:0.95:0.1', 'power:0.3:0.5')")
        names = LAW_KINDS[kind][0]
        if len(values) != len(names):
            raise InputError(f"restitution law {text!r}: '{kind}' takes {len(names)} value(s) "
                             f"({', '.join(names)}), e.g. '{kind}:" +
                             ":".join("0.5" for _ in names) + "'")
        try:
            nums = [float(v) for v in values]
        except ValueError:
            raise InputError(f"restitution law {text!r}: values must be numbers") from None
        return cls(kind, **dict(zip(names, nums)))

    def __call__(self, v):
        """Restitution coefficient at impact speed(s) ``v`` (m/s), clipped to [0, 1]."""
        if isinstance(v, float):
            v = abs(v)
            if self.kind == "constant":
                r = self.r0
            elif self.kind == "linear":
                r = self.r0 - self.a * v
            else:
                r = 1.0 - self.a * v ** self.p
            return min(1.0, max(0.0, r))
        v = np.abs(v)
        if self.kind == "constant":
            r = self.r0 + 0.0 * v
        elif self.kind == "linear":
            r = self.r0 - self.a * v
        else:
            r = 1.0 - self.a * v ** self.p
        r = np.clip(r, 0.0, 1.0)
        return float(r) if np.ndim(r) == 0 else r

    @property
    def formula(self) -> str:
        """Human-readable formula, e.g. ``'r = 1 - 0.3 v^0.5'``."""
        return LAW_KINDS[self.kind][1].format(r0=self.r0, a=self.a, p=self.p)

    @property
    def spec(self) -> str:
        """The spec string that :meth:`parse` reads back."""
        names = LAW_KINDS[self.kind][0]
        return ":".join([self.kind] + [repr(float(getattr(self, n))) for n in names])

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"kind": self.kind, "r0": self.r0, "a": self.a, "p": self.p,
                "formula": self.formula}
