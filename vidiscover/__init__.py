"""vidiscover: model discovery and regime classification of vibro-impact systems.

A ball rattles inside a clearance of a linear oscillator (LO) driven by a shaker.
From the LO displacement and acceleration and the base motion alone, vidiscover
simulates, analyses, discovers laws, classifies regimes and diagnoses the
sim-to-real gap. See README.md for the command line.
"""

from .effects import EFFECTS, Effects
from .errors import InputError
from .params import PRESETS, SystemParams, preset
from .recording import Metadata, Recording
from .restitution_laws import RestitutionLaw
from .sensors import SensorConfig, record
from .simulation import SimOptions, SimulationResult, simulate

__version__ = "0.1.0"

__all__ = [
    "EFFECTS",
    "Effects",
    "InputError",
    "Metadata",
    "PRESETS",
    "Recording",
    "RestitutionLaw",
    "SensorConfig",
    "SimOptions",
    "SimulationResult",
    "SystemParams",
    "preset",
    "record",
    "simulate",
]
