"""Sim-to-real gap diagnosis (the README's gap section).

* :mod:`.components` -- where: localised, normalised gap statistics;
* :mod:`.fit` -- which: every catalogue effect added, fitted, validated;
* :mod:`.diagnose` -- :func:`diagnose` one recording, :class:`GapReport`;
* :mod:`.battery` -- :func:`gap_check`, the withheld-effect battery;
* :mod:`.figures` -- waterfall and sim vs real overlays.
"""

from .battery import gap_check
from .components import STATS, GapComponents, Signature, measure
from .diagnose import SIGNIFICANT_GAP, GapReport, diagnose

__all__ = ["diagnose", "GapReport", "gap_check", "measure", "Signature", "GapComponents",
           "STATS", "SIGNIFICANT_GAP"]
