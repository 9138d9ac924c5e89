"""Periodic impacting orbits of the exact model, their stability, and continuation.

See DESIGN.md section 10: Newton shooting on the exact impact map
(:mod:`.shooting`), Floquet multipliers from flow Jacobians and saltation matrices
(:mod:`.monodromy`), pseudo-arclength continuation with fold, period-doubling,
Neimark-Sacker and grazing detection (:mod:`.continuation`), figures (:mod:`.figures`).
"""

from .shooting import ImpactMap, MapError, Orbit, solve_orbit

__all__ = ["ImpactMap", "MapError", "Orbit", "solve_orbit"]
