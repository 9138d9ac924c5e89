"""Simulators: the exact event-driven engine and the compliant-contact engine."""

from .compliant import CompliantResult, simulate_reference
from .contact import ContactModel, WallContact
from .engine import SimOptions, simulate
from .result import ImpactTable, SimulationResult

__all__ = ["simulate", "SimOptions", "SimulationResult", "ImpactTable", "ContactModel",
           "WallContact", "CompliantResult", "simulate_reference"]
