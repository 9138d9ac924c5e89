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

__all__ = ["ImpactTerm", "IMPACT_TERMS", "CONSTANT_TERM", "register_impact_term"]

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
