"""Compare an analysis with the ground truth of a simulated recording.

The ground truth (``rec.truth.json``, :func:`vidiscover.io.read_truth`) lists the
true impacts with their restitution coefficient; detected impacts are matched to
them one to one on the same wall (:func:`vidiscover.analysis.detection_scores`,
0.5 ms tolerance), and only *detectable* true impacts count in the recall.
"""

from __future__ import annotations

import numpy as np

__all__ = ["truth_impacts", "matched_true_r", "compare_truth"]


def truth_impacts(truth: dict | None):
    """True impacts as arrays ``(t, side, r)``, or None without truth or impacts.

    Parameters
    ----------
    truth : dict or None
        Ground truth of a simulated recording.

    Returns
    -------
    tuple of ndarray or None
    """
    if not truth or not truth.get("impacts"):
        return None
    imps = truth["impacts"]
    return (np.array([i["t"] for i in imps], dtype=float),
            np.array([str(i["side"]) for i in imps]),
            np.array([i.get("r", np.nan) for i in imps], dtype=float))


def _scores(result, truth: dict):
    from ..analysis import detection_scores

    return detection_scores(result.detection.t, result.detection.side, truth)


def matched_true_r(result, truth: dict | None) -> np.ndarray:
    """True r of every detected impact (NaN where it matches no true impact).

    Detections are matched to true impacts of the same wall
    (:func:`vidiscover.analysis.detection_scores`).

    Parameters
    ----------
    result : AnalysisResult
    truth : dict or None

    Returns
    -------
    ndarray
        One value per detected impact, in detection order.
    """
    out = np.full(result.detection.n, np.nan)
    ti = truth_impacts(truth)
    if ti is not None and out.size:
        sc = _scores(result, truth)
        out[sc.i_est] = ti[2][sc.i_true]
    return out


def compare_truth(result, truth: dict) -> dict:
    """Estimates against truth: detection scores, per-wall r RMS, regime.

    Parameters
    ----------
    result : AnalysisResult
    truth : dict
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
    if truth.get("impacts"):
        sc = _scores(result, truth)
        impacts = {"n": sc.n_true, "detectable": sc.n_detectable, "matched": sc.n_matched,
                   "precision": sc.precision, "recall": sc.recall,
                   "timing_median": sc.timing_median}
    else:
        impacts = {"n": 0, "detectable": 0, "matched": 0,
                   "precision": 1.0 if result.detection.n == 0 else 0.0, "recall": 1.0,
                   "timing_median": float("nan")}
    regime = truth.get("regime") or {}
    return {"impacts": impacts, "restitution": rest, "regime": {"label": regime.get("label")},
            "effects": truth.get("effects"), "b_true": truth.get("b_true")}
