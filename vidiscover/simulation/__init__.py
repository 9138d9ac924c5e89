"""Simulators: the exact event-driven engine and the compliant-contact engine.

The compliant engine (:mod:`.compliant`) is imported when first used: it loads
``scipy.integrate`` and ``scipy.optimize`` (~0.4 s), which a process that only runs
the exact engine (a sweep worker, ``vidiscover simulate`` without ``--contact``) does
not need.
"""

from .contact import ContactModel, WallContact
from .engine import SimOptions, simulate
from .result import ImpactTable, SimulationResult

__all__ = ["simulate", "SimOptions", "SimulationResult", "ImpactTable", "ContactModel",
           "WallContact", "CompliantResult", "simulate_reference"]

_LAZY = {"CompliantResult", "simulate_reference"}


def __getattr__(name: str):
    if name in _LAZY:
        from . import compliant

        return getattr(compliant, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | _LAZY)
