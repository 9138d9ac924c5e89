"""Candidate functions of the impact speed for impact-law discovery.

Each candidate is registered once in :data:`IMPACT_TERMS` under the name used in
formulas (``"v^0.5"``, ``"exp(-v)"``, ...). The discovery stage builds its feature
library from the registry, and the tests check the contract over the whole registry
(finite on v in (0, 3], a name, a consistent exponent), so a new candidate needs one
:func:`register_impact_term` call and nothing else.

Examples
--------
>>> term = IMPACT_TERMS["v^0.5"]
>>> float(term(0.25)), term.exponent
(0.5, 0.5)
>>> list(IMPACT_TERMS)[:3]
['1', 'v', 'v^2']
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["ImpactTerm", "IMPACT_TERMS", "CONSTANT_TERM", "HUNT_CROSSLEY_TERM",
           "hunt_crossley_restitution", "register_impact_term"]

#: Name of the constant term (the intercept r0).
CONSTANT_TERM = "1"

_NAME_RE = re.compile(r"^[A-Za-z0-9_.^()+\-*/ ]+$")


@dataclass(frozen=True)
class ImpactTerm:
    """One candidate function f(v) of the impact speed v = |z'-| (m/s).

    Parameters
    ----------
    name : str
        Name used in formulas and tables, written in the variable ``v``
        (e.g. ``"v^0.25"``).
    func : callable
        ``func(v) -> ndarray`` on an array of speeds >= 0, same shape.
    exponent : float or None
        ``p`` when ``f(v) = v**p`` (0 for the constant, 1 for ``v``), so that a
        discovered ``1 - a f(v)`` maps to a power law; None for other shapes.
    """

    name: str
    func: Callable[[np.ndarray], np.ndarray]
    exponent: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip() \
                or not _NAME_RE.match(self.name):
            raise InputError(f"impact term name must be a non-empty formula string such as "
                             f"'v^0.5', was {self.name!r}")
        if not callable(self.func):
            raise InputError(f"impact term {self.name!r}: func must be callable, "
                             f"was {type(self.func).__name__}")
        if self.exponent is not None and not (isinstance(self.exponent, (int, float))
                                              and math.isfinite(self.exponent)
                                              and self.exponent >= 0):
            raise InputError(f"impact term {self.name!r}: exponent must be None or a finite "
                             f"number >= 0, was {self.exponent!r}")

    def __call__(self, v) -> np.ndarray:
        """Evaluate f(|v|) as a float array of the shape of ``v``."""
        v = np.abs(np.asarray(v, dtype=float))
        out = np.asarray(self.func(v), dtype=float)
        return np.broadcast_to(out, v.shape).copy() if out.shape != v.shape else out

    @property
    def is_constant(self) -> bool:
        """True for the intercept term."""
        return self.name == CONSTANT_TERM


#: name -> ImpactTerm, in registration order (the order of library columns).
IMPACT_TERMS: dict[str, ImpactTerm] = {}


def register_impact_term(name: str, func: Callable[[np.ndarray], np.ndarray], *,
                         exponent: float | None = None, replace: bool = False) -> ImpactTerm:
    """Register a candidate function of the impact speed.

    Parameters
    ----------
    name : str
        Formula name in the variable ``v`` (unique in the registry).
    func : callable
        ``func(v) -> ndarray``, finite for v in (0, 3].
    exponent : float or None, optional
        ``p`` when ``func(v) == v**p``.
    replace : bool, optional
        Allow overwriting an existing entry.

    Returns
    -------
    ImpactTerm
        The registered term.
    """
    if name in IMPACT_TERMS and not replace:
        raise InputError(f"impact term {name!r} is already registered; "
                         f"pass replace=True to overwrite it")
    term = ImpactTerm(name, func, None if exponent is None else float(exponent))
    IMPACT_TERMS[name] = term
    return term


register_impact_term(CONSTANT_TERM, lambda v: np.ones_like(v), exponent=0.0)
register_impact_term("v", lambda v: v, exponent=1.0)
register_impact_term("v^2", lambda v: v ** 2, exponent=2.0)
register_impact_term("v^0.2", lambda v: v ** 0.2, exponent=0.2)
register_impact_term("v^0.25", lambda v: v ** 0.25, exponent=0.25)
register_impact_term("v^0.5", lambda v: np.sqrt(v), exponent=0.5)
register_impact_term("exp(-v)", lambda v: np.exp(-v))


# ------------------------------------------------------------- Hunt-Crossley shape
#: Name of the Hunt-Crossley candidate (one coefficient ``alpha``, s/m). It is not a
#: registry term: ``r = r_HC(alpha v)`` is not linear in ``alpha``.
HUNT_CROSSLEY_TERM = "hunt_crossley(alpha v)"

def hunt_crossley_restitution(x) -> np.ndarray:
    """Exact restitution of a Hunt-Crossley contact, as a function of ``x = alpha v``.

    The wall force ``k delta^n (1 + 1.5 alpha delta')`` (Hunt and Crossley 1975,
    J. Appl. Mech. 42:440; the parameterisation of the README's 'Realistic recordings') gives, on
    integrating ``m u du/d delta = -k delta^n (1 + chi u)`` (``chi = 1.5 alpha``)
    over the compression and the restitution phase, the implicit relation

        s - ln(1 + s) = -r s - ln(1 - r s),   s = 1.5 alpha v,

    independent of ``k``, ``n`` and the mass (the relation used e.g. by Flores et
    al. 2011, Mech. Mach. Theory 46:1610, for the Hunt-Crossley family). With
    ``e = 1 - r s`` it reads ``ln e - e = -(1 + s - ln(1 + s))``, solved in closed form
    by the principal branch of the Lambert W function:

        r = (1 + W0(-exp(-(1 + s - ln(1 + s))))) / s.

    Its series is ``r = 1 - x + x^2 - ...`` (``x = alpha v``: the ``r ~ 1 - alpha v``
    of small speeds, used below ``s = 0.01``), and ``1 / (1 + x)`` stays within 0.004
    of it up to ``x = 0.5``.

    Parameters
    ----------
    x : array_like
        ``alpha |v|`` (dimensionless, >= 0).

    Returns
    -------
    ndarray
        r in (0, 1], the shape of ``x``.
    """
    from scipy.special import lambertw

    x = np.abs(np.asarray(x, dtype=float))
    flat = x.reshape(-1)
    s = 1.5 * flat
    out = 1.0 - flat + flat ** 2                # series, exact to O(s^3) below s = 0.01
    big = s >= 1e-2
    if np.any(big):
        sb = s[big]
        w = lambertw(-np.exp(-(1.0 + sb - np.log1p(sb))), 0).real
        out[big] = (1.0 + w) / sb
    return out.reshape(x.shape)
