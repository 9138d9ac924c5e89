"""Periodic impacting orbits of the exact model, their stability, and continuation.

See the docs page 'Periodic orbits and continuation' (docs/orbits.md): Newton
shooting on the exact impact map
(:mod:`.shooting`), Floquet multipliers from flow Jacobians and saltation matrices
(:mod:`.monodromy`), initial guesses and the orbit search (:mod:`.find`),
pseudo-arclength continuation with fold, period-doubling, Neimark-Sacker and grazing
detection (:mod:`.continuation`), figures and the sweep overlay (:mod:`.figures`).

Examples
--------
>>> from vidiscover import preset
>>> from vidiscover.orbits import find_orbits
>>> orbits, notes = find_orbits(preset("paper", b=0.012))
>>> [(o.kind, o.stable) for o in orbits]
[('2ipc_sym', True), ('2ipc_sym', False)]
"""

from .continuation import Branch, continue_orbit
from .find import find_orbits
from .shooting import ImpactMap, MapError, Orbit, solve_orbit

__all__ = ["ImpactMap", "MapError", "Orbit", "solve_orbit", "find_orbits", "continue_orbit",
           "Branch"]
