"""Analysis of a recording (the README, stages 1-4), one idea per module.

* :mod:`.signals` -- input checks, bad samples, robust noise, forcing fit;
* :mod:`.impacts` -- stage 1, impacts as pulses in the LO acceleration;
* :mod:`.friction` -- ball flights with or without Coulomb friction (eqs. 6, 8);
* :mod:`.lo_reaction` -- friction read from the LO's acceleration between impacts;
* :mod:`.reconstruction` -- stage 2, LO velocity, ball position, flight segments;
* :mod:`.restitution` -- stage 3, r per impact (eq. 9), per wall, mu table;
* :mod:`.returnmap` -- stage 4, first return map and the feature sets;
* :mod:`.pipeline` -- :func:`analyze`, stages 1-4 in one call;
* :mod:`.validation` -- comparison with simulated ground truth (the single
  detectability criterion).
"""

from .friction import eq8_velocities, integrate_flights, solve_flights
from .impacts import (
                      IMPACT_COLUMNS,
                      DetectionOptions,
                      ImpactDetection,
                      PulseModel,
                      detect_impacts,
)
from .pipeline import AnalysisResult, analyze
from .reconstruction import FLIGHT_COLUMNS, Reconstruction, reconstruct
from .restitution import MU_TABLE, RestitutionEstimate, WallStats, estimate_restitution, mu_table
from .returnmap import (
                          ANALYSIS_FEATURES,
                          FeatureContext,
                          FeatureSet,
                          ReturnMap,
                          compute_features,
                          return_map,
)
from .signals import Forcing, fit_forcing
from .validation import (
                          DETECTABLE_SNR,
                          DetectionScores,
                          contact_dv,
                          detectable,
                          detectable_truth,
                          detection_scores,
                          match_impacts,
)

__all__ = [
    "ANALYSIS_FEATURES", "AnalysisResult", "DETECTABLE_SNR", "DetectionOptions",
    "DetectionScores",
    "FLIGHT_COLUMNS", "FeatureContext", "FeatureSet", "Forcing", "IMPACT_COLUMNS",
    "ImpactDetection", "MU_TABLE",
    "PulseModel", "Reconstruction", "RestitutionEstimate", "ReturnMap", "WallStats",
    "analyze", "compute_features", "contact_dv", "detect_impacts", "detectable",
    "detectable_truth",
    "detection_scores", "eq8_velocities", "estimate_restitution", "fit_forcing",
    "integrate_flights", "match_impacts", "mu_table", "reconstruct",
    "return_map", "solve_flights",
]
