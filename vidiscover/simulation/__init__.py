"""Exact event-driven simulator (closed-form flows, bracketed events)."""

from .engine import SimOptions, simulate
from .result import ImpactTable, SimulationResult

__all__ = ["simulate", "SimOptions", "SimulationResult", "ImpactTable"]
