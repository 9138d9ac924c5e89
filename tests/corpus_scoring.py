"""Impact detection scored against a realism-corpus case's truth.

As ``benchmarks/bench_realism.py`` scores it: the detectable true contact episodes
(:func:`vidiscover.analysis.detectable` with the peak of the case's true anti-alias
response and the contact impulses of :func:`vidiscover.analysis.contact_dv`), and
matches on the same wall within 0.5 ms of the contact entry.
"""

from __future__ import annotations

import functools

from vidiscover.analysis import PulseModel, contact_dv, detect_impacts, detectable
from vidiscover.analysis.validation import match_impacts_by_wall
from vidiscover.corpus import realism_case


def true_filter(sensors: dict, fs: float) -> PulseModel:
    """The anti-alias response a case's sensors were recorded through."""
    kind = sensors.get("anti_alias", "linear-phase")
    if kind == "linear-phase":
        return PulseModel()
    return PulseModel(cutoff=sensors["aa_cutoff"] / fs, kind=kind, order=sensors["aa_order"])


def scored(case, rec, imp, det):
    """``(dv, ok, ie, it)``: true contact impulses, detectable episodes, and the matched
    detections ``ie`` and true impacts ``it`` of detection ``det`` of ``rec``."""
    fs = rec.sample_rate
    dv = contact_dv(imp.v_in, imp.v_out, case.m1, case.m2)
    ok = detectable(imp.t_in, dv, float(case.sensors.get("a_noise", 0.05)), fs,
                    cutoff=true_filter(case.sensors, fs).peak(fs) / (2 * fs))
    ie, it = match_impacts_by_wall(det.t, det.side, imp.t_in, imp.side)
    return dv, ok, ie, it


@functools.cache
def episodes(split: str, index: int):
    """``(imp, ok, det, ie, it)`` of corpus case ``(split, index)``, the instrument learned
    (the detection of ``analyze`` under the case's own friction)."""
    case = realism_case(split, index)
    sim = case.simulate(label=False)
    rec, imp = sim.recording, sim.truth.impacts
    det = detect_impacts(rec, mu=case.mu)
    _, ok, ie, it = scored(case, rec, imp, det)
    return imp, ok, det, ie, it
