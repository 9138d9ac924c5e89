"""Discovery (pysindy): the impact law per wall and the flight law, from recordings."""

from .flight_law import (
    FLIGHT_TERMS,
    MAX_TILT_DEG,
    FlightLawResult,
    discover_flight_law,
    flight_law_mu_theta,
    reconstruct_with_law,
)
from .impact_law import MIN_EFFECT, discover_impact_law
from .impact_result import EQUIVALENT_EXPONENTS, RESULT_KINDS, ImpactLawResult, same_form
from .impact_terms import (
    CONSTANT_TERM,
    HUNT_CROSSLEY_TERM,
    IMPACT_TERMS,
    ImpactTerm,
    hunt_crossley_restitution,
    register_impact_term,
)
from .pipeline import DiscoveryResult, discover

__all__ = [
    "CONSTANT_TERM",
    "FLIGHT_TERMS",
    "HUNT_CROSSLEY_TERM",
    "MAX_TILT_DEG",
    "MIN_EFFECT",
    "FlightLawResult",
    "DiscoveryResult",
    "EQUIVALENT_EXPONENTS",
    "IMPACT_TERMS",
    "ImpactLawResult",
    "ImpactTerm",
    "RESULT_KINDS",
    "discover",
    "discover_flight_law",
    "discover_impact_law",
    "flight_law_mu_theta",
    "hunt_crossley_restitution",
    "reconstruct_with_law",
    "register_impact_term",
    "same_form",
]
