"""Compare an analysis with the ground truth of a simulated recording.

The ground truth (``rec.truth.json``, :func:`vidiscover.io.read_truth`) lists the
true impacts with their restitution coefficient; detected impacts are matched to
them one to one on the same wall (:func:`vidiscover.analysis.detection_scores`,
0.5 ms tolerance), and only *detectable* true impacts count in the recall.
"""

from __future__ import annotations

import numpy as np

from ..truth import GroundTruth

__all__ = ["matched_true_r", "compare_truth"]


def _scores(result, truth: GroundTruth):
    from ..analysis import detection_scores

    return detection_scores(result.detection.t, result.detection.side, truth)


def matched_true_r(result, truth: GroundTruth | None) -> np.ndarray:
    """True r of every detected impact (NaN where it matches no true impact).

    Detections are matched to true impacts of the same wall
    (:func:`vidiscover.analysis.detection_scores`).

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth or None

    Returns
    -------
    ndarray
        One value per detected impact, in detection order.
    """
    out = np.full(result.detection.n, np.nan)
    if truth is not None and truth.impacts.n and out.size:
        sc = _scores(result, truth)
        out[sc.i_est] = truth.impacts.r[sc.i_true]
    return out


def compare_truth(result, truth: GroundTruth) -> dict:
    """Estimates against truth: detection scores, per-wall r RMS, regime.

    Parameters
    ----------
    result : AnalysisResult
    truth : GroundTruth
        Ground truth of the same recording.

    Returns
    -------
    dict
        ``impacts`` {``n`` true, ``detectable``, ``matched``, ``precision``,
        ``recall`` (of the detectable impacts), ``timing_median`` (s)},
        ``restitution`` {side: {``rms`` of the true r over the impacts whose
        estimate was used, ``n``, ``rms_error`` = estimated RMS minus that}},
        ``regime`` {``label``: true label}, ``effects`` (simulated), ``b_true``.
    """
    r_true = matched_true_r(result, truth)
    c = result.restitution.columns
    used = np.asarray(c["used"], dtype=bool)
    side = np.asarray(c["side"])
    rest = {}
    for sd in ("right", "left"):
        m = used & (side == sd) & np.isfinite(r_true)
        rms = float(np.sqrt(np.mean(r_true[m] ** 2))) if m.any() else float("nan")
        rest[sd] = {"rms": rms, "n": int(m.sum()),
                    "rms_error": float(result.restitution.wall(sd).rms - rms)}
    if truth.impacts.n:
        sc = _scores(result, truth)
        impacts = {"n": sc.n_true, "detectable": sc.n_detectable, "matched": sc.n_matched,
                   "precision": sc.precision, "recall": sc.recall,
                   "timing_median": sc.timing_median}
    else:
        impacts = {"n": 0, "detectable": 0, "matched": 0,
                   "precision": 1.0 if result.detection.n == 0 else 0.0, "recall": 1.0,
                   "timing_median": float("nan")}
    return {"impacts": impacts, "restitution": rest, "regime": {"label": truth.label},
            "effects": truth.effects.to_dict(), "b_true": truth.b_true}
