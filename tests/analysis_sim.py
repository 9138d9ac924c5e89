"""Simulated ground truth shared by the ``test_analysis_*`` modules.

Each case is simulated once per test session (settle 10 s, record 5.12 s) and
recorded with the default sensors for several noise seeds.
"""

from __future__ import annotations

import functools

import numpy as np

from vidiscover import Effects, SensorConfig, preset, record, simulate
from vidiscover.analysis import analyze, match_impacts

#: The paper's asymmetric walls (r_right = 0.88, r_left = 0.20).
ASYM = ("asymmetric_restitution=0.88,0.20",)
#: Clearances of the detection / restitution figures (m).
CLEARANCES = (0.006, 0.0075, 0.009)
SEEDS = (1, 2)


@functools.cache
def simulation(b: float, effects: tuple = ASYM, settle: float = 10.0):
    """The exact simulation of the paper preset at half-clearance ``b``."""
    return simulate(preset("paper", b=b), Effects.parse(list(effects)), settle=settle,
                    duration=5.12)


@functools.cache
def recording(b: float, effects: tuple = ASYM, seed: int = 1, sensors: SensorConfig = None):
    """(Recording, truth) for a simulated case."""
    return record(simulation(b, effects), sensors or SensorConfig(), seed=seed)


@functools.cache
def analysed(b: float, effects: tuple = ASYM, seed: int = 1, mu: float = 0.0,
             sensors: SensorConfig = None):
    """(AnalysisResult, truth) for a simulated case."""
    rec, truth = recording(b, effects, seed, sensors)
    return analyze(rec, mu=mu), truth


def true_r_rms(out, truth, side: str) -> tuple[float, int]:
    """RMS of the true r of the impacts whose r ``out`` used on wall ``side``."""
    t_true, r_true = truth.impacts.t, truth.impacts.r
    det = out.detection
    ie, it = match_impacts(det.t, t_true)
    matched = np.full(det.n, np.nan)
    matched[ie] = r_true[it]
    c = out.restitution.columns
    sel = c["used"] & (c["side"] == side) & np.isfinite(matched)
    return float(np.sqrt(np.mean(matched[sel] ** 2))), int(sel.sum())
