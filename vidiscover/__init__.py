"""vidiscover: model discovery and regime classification of vibro-impact systems.

A ball rattles inside a clearance of a linear oscillator (LO) driven by a shaker.
From the LO displacement and acceleration and the base motion alone, vidiscover
simulates, analyses, discovers laws, classifies regimes and diagnoses the
sim-to-real gap. See README.md for the command line.

Public names are imported lazily (PEP 562) so that ``vidiscover --help`` starts
fast; ``from vidiscover import simulate`` works as usual.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_LAZY = {
    "AnalysisResult": "analysis",
    "EFFECTS": "effects",
    "Effects": "effects",
    "GroundTruth": "truth",
    "InputError": "errors",
    "Metadata": "recording",
    "PRESETS": "params",
    "Recording": "recording",
    "RestitutionLaw": "restitution_laws",
    "SensorConfig": "sensors",
    "SimOptions": "simulation",
    "SimulationError": "errors",
    "SimulationResult": "simulation",
    "SystemParams": "params",
    "analyze": "analysis",
    "preset": "params",
    "record": "sensors",
    "simulate": "simulation",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'vidiscover' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
