"""Compliant walls: penalty contact laws for the compliant-contact engine.

Each wall pushes the ball back with a force that depends on the penetration
``delta >= 0`` (how far the ball is beyond the wall, ``|z| - b``) and its rate
``delta'``, clipped to be compressive (``F >= 0``); the reaction acts on the LO
(the README's 'Realistic recordings').

``kelvin-voigt`` (``k`` N/m, ``r``)
    ``F = k delta + c delta'``; the damping ``c`` is matched to the restitution
    ``r`` of a linear (unclipped) contact of the pair's effective mass
    ``m_eff = m1 m2 / (m1 + m2)``: ``zeta = -ln r / sqrt(pi^2 + ln^2 r)``,
    ``c = 2 zeta sqrt(k m_eff)``. Because the clipped force returns to zero
    before the penetration does, the measured restitution of a contact is slightly
    above ``r``. Typical ``k``: 1e6-1e8 N/m.
``hunt-crossley`` (``k`` N/m^n, ``alpha`` s/m, ``n`` default 1.5)
    ``F = k delta^n (1 + 1.5 alpha delta')``; the restitution depends on the
    impact speed, ``r ~ 1 - alpha v`` at small ``alpha v``. Typical ``k``:
    1e8-1e10 N/m^1.5, ``alpha`` 0.1-0.6 s/m.

Syntax (CLI ``--contact``): ``KIND:key=value,...`` for both walls, or one spec per
wall prefixed by ``right=`` / ``left=``; ``kv`` and ``hc`` are aliases.

Examples
--------
>>> cm = ContactModel.parse("hunt-crossley:k=1e9,alpha=0.3")
>>> cm.right == cm.left, cm.right.n
(True, 1.5)
>>> cm = ContactModel.parse(["right=kv:k=3e7,r=0.88", "left=kv:k=3e7,r=0.2"])
>>> cm.describe()
'right kelvin-voigt(k=3e+07 N/m, r=0.88), left kelvin-voigt(k=3e+07 N/m, r=0.2)'
>>> ContactModel.from_dict(cm.to_dict()) == cm
True
>>> round(cm.left.damping(0.032), 3)  # c (N s/m) for a 32 g ball on a rigid LO
893.476
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from ..errors import InputError

__all__ = ["WallContact", "ContactModel", "CONTACT_KINDS"]

#: Contact kinds with their parameters (required, then optional with default).
CONTACT_KINDS = {
    "kelvin-voigt": {"required": ("k", "r"), "optional": {}},
    "hunt-crossley": {"required": ("k", "alpha"), "optional": {"n": 1.5}},
}
_ALIASES = {"kv": "kelvin-voigt", "hc": "hunt-crossley"}
_EXAMPLE = "e.g. --contact hunt-crossley:k=1e9,alpha=0.3 or --contact kelvin-voigt:k=3e7,r=0.7"


@dataclass(frozen=True)
class WallContact:
    """The contact law of one wall.

    Parameters
    ----------
    kind : {"kelvin-voigt", "hunt-crossley"}
    k : float
        Stiffness, N/m (Kelvin-Voigt) or N/m^n (Hunt-Crossley), > 0.
    r : float or None
        Kelvin-Voigt: restitution of the matched linear contact, in (0, 1].
    alpha : float or None
        Hunt-Crossley damping factor (s/m), >= 0.
    n : float
        Hunt-Crossley exponent in [1, 3] (1.5: Hertz).
    """

    kind: str
    k: float
    r: float | None = None
    alpha: float | None = None
    n: float = 1.5

    def __post_init__(self) -> None:
        where = f"contact {self.kind}"
        if self.kind not in CONTACT_KINDS:
            raise InputError(f"unknown contact kind {self.kind!r}; use kelvin-voigt (kv) or "
                             f"hunt-crossley (hc), {_EXAMPLE}")
        if not (math.isfinite(self.k) and self.k > 0):
            raise InputError(f"{where}: k must be > 0, was {self.k!r}; {_EXAMPLE}")
        if self.kind == "kelvin-voigt":
            if self.r is None or not (0.0 < self.r <= 1.0):
                raise InputError(f"{where}: r must be in (0, 1], was {self.r!r}")
            if self.alpha is not None:
                raise InputError(f"{where}: alpha is a hunt-crossley parameter; "
                                 "kelvin-voigt takes k and r")
        else:
            if self.alpha is None or not (math.isfinite(self.alpha) and self.alpha >= 0):
                raise InputError(f"{where}: alpha must be >= 0 s/m, was {self.alpha!r}")
            if not (1.0 <= self.n <= 3.0):
                raise InputError(f"{where}: n must be in [1, 3], was {self.n!r}")
            if self.r is not None:
                raise InputError(f"{where}: r is a kelvin-voigt parameter; "
                                 "hunt-crossley takes k, alpha and n")

    @property
    def zeta(self) -> float:
        """Damping ratio of the matched linear contact (Kelvin-Voigt only)."""
        lr = math.log(self.r)
        return -lr / math.sqrt(math.pi ** 2 + lr * lr)

    def damping(self, m_eff: float) -> float:
        """Kelvin-Voigt damping ``c = 2 zeta sqrt(k m_eff)`` (N s/m) for an effective mass.

        Parameters
        ----------
        m_eff : float
            ``m1 m2 / (m1 + m2)`` (kg).
        """
        if self.kind != "kelvin-voigt":
            raise ValueError("damping() is defined for kelvin-voigt walls only")
        return 2.0 * self.zeta * math.sqrt(self.k * m_eff)

    def force(self, delta, ddelta, c: float = 0.0):
        """Clipped compressive force magnitude for ``delta >= 0`` (arrays or floats).

        Parameters
        ----------
        delta, ddelta : float or ndarray
            Penetration (m) and its rate (m/s); ``delta > 0`` is assumed.
        c : float
            Kelvin-Voigt damping from :meth:`damping` (ignored for Hunt-Crossley).
        """
        import numpy as np

        if self.kind == "kelvin-voigt":
            f = self.k * delta + c * ddelta
        else:
            f = self.k * np.abs(delta) ** self.n * (1.0 + 1.5 * self.alpha * ddelta)
        return np.maximum(f, 0.0)

    def to_dict(self) -> dict:
        """JSON-ready parameters with the kind."""
        if self.kind == "kelvin-voigt":
            return {"kind": self.kind, "k": self.k, "r": self.r}
        return {"kind": self.kind, "k": self.k, "alpha": self.alpha, "n": self.n}

    def spec(self) -> str:
        """The ``KIND:key=value,...`` string that parses back to this wall."""
        d = self.to_dict()
        kind = d.pop("kind")
        return f"{kind}:" + ",".join(f"{k}={v!r}" for k, v in d.items())

    def describe(self) -> str:
        """Human one-liner, e.g. ``'kelvin-voigt(k=3e+07 N/m, r=0.7)'``."""
        if self.kind == "kelvin-voigt":
            return f"kelvin-voigt(k={self.k:.3g} N/m, r={self.r:g})"
        return f"hunt-crossley(k={self.k:.3g} N/m^{self.n:g}, alpha={self.alpha:g} s/m)"

    @classmethod
    def parse(cls, spec: str, where: str | None = None) -> WallContact:
        """Parse ``KIND:key=value,...`` (``where`` names the spec in messages)."""
        where = where or f"--contact {spec!r}"
        kind, sep, rest = str(spec).strip().partition(":")
        kind = _ALIASES.get(kind.strip().lower(), kind.strip().lower())
        if kind not in CONTACT_KINDS:
            raise InputError(f"{where}: unknown contact kind {kind!r}; use kelvin-voigt (kv) "
                             f"or hunt-crossley (hc), {_EXAMPLE}")
        info = CONTACT_KINDS[kind]
        allowed = set(info["required"]) | set(info["optional"])
        values: dict[str, float] = {}
        for part in (p.strip() for p in rest.split(",") if p.strip()) if sep else ():
            key, eq, val = part.partition("=")
            key = key.strip()
            if not eq or key not in allowed:
                raise InputError(f"{where}: unknown or malformed {part!r}; {kind} takes "
                                 f"{', '.join(sorted(allowed))} as key=value")
            try:
                values[key] = float(val)
            except ValueError:
                raise InputError(f"{where}: {key} must be a number, was {val.strip()!r}"
                                 ) from None
            if not math.isfinite(values[key]):
                raise InputError(f"{where}: {key} must be finite, was {val.strip()!r}")
        missing = [k for k in info["required"] if k not in values]
        if missing:
            raise InputError(f"{where}: missing {', '.join(missing)}; {kind} needs "
                             f"{', '.join(info['required'])}, {_EXAMPLE}")
        try:
            return cls(kind, **values)
        except InputError as err:
            raise InputError(f"{where}: {err}") from None


@dataclass(frozen=True)
class ContactModel:
    """The contact laws of the two walls (right: z = +b, left: z = -b).

    Parameters
    ----------
    right, left : WallContact
    """

    right: WallContact
    left: WallContact

    def wall(self, side: int) -> WallContact:
        """The wall at ``side`` (+1 right, -1 left)."""
        return self.right if side > 0 else self.left

    @classmethod
    def parse(cls, specs: str | Sequence[str]) -> ContactModel:
        """Parse one spec for both walls, or one ``right=``/``left=`` spec per wall.

        Raises
        ------
        InputError
            On an unknown kind or key, a non-number, a value out of range, a wall
            given twice or only one wall given.
        """
        if isinstance(specs, str):
            specs = [specs]
        specs = [str(s).strip() for s in specs]
        if not specs:
            raise InputError(f"--contact needs a contact spec, {_EXAMPLE}")
        walls: dict[str, WallContact] = {}
        both = None
        for s in specs:
            head, eq, tail = s.partition("=")
            if eq and head.strip().lower() in ("right", "left"):
                name = head.strip().lower()
                if name in walls:
                    raise InputError(f"--contact {s!r}: the {name} wall is given twice; "
                                     "give each wall once")
                walls[name] = WallContact.parse(tail, f"--contact {s!r}")
            else:
                if both is not None or len(specs) > 1:
                    raise InputError(f"--contact {s!r}: give one spec for both walls, or "
                                     "one right=... and one left=... spec")
                both = WallContact.parse(s, f"--contact {s!r}")
        if both is not None:
            return cls(both, both)
        if len(walls) != 2:
            given = next(iter(walls))
            raise InputError(f"--contact: only the {given} wall is given; give both walls "
                             "(right=... and left=...) or one spec without right=/left= "
                             "for both")
        return cls(walls["right"], walls["left"])

    def specs(self) -> list[str]:
        """``--contact`` strings that parse back to this model."""
        if self.right == self.left:
            return [self.right.spec()]
        return [f"right={self.right.spec()}", f"left={self.left.spec()}"]

    def to_dict(self) -> dict:
        """JSON-ready ``{"right": {...}, "left": {...}}``."""
        return {"right": self.right.to_dict(), "left": self.left.to_dict()}

    @classmethod
    def from_dict(cls, data: Mapping) -> ContactModel:
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(*(WallContact(**dict(data[w])) for w in ("right", "left")))
        except (KeyError, TypeError) as err:
            raise InputError(f"contact model {dict(data)!r} is malformed ({err}); expected "
                             "{'right': {'kind': ..., 'k': ...}, 'left': {...}}") from None

    def describe(self) -> str:
        """One human line."""
        if self.right == self.left:
            return f"both walls {self.right.describe()}"
        return f"right {self.right.describe()}, left {self.left.describe()}"
