"""Comparison of analysis results with simulated ground truth.

The single definition of which true impacts a detector can be asked to find lives
here (:func:`detectable`), with the matching of detected to true impacts
(:func:`match_impacts`) and the detection scores built on them
(:func:`detection_scores`). Tests, benchmarks and the gap diagnosis use these, so
the criterion is stated once.

Detectability criterion
-----------------------
A true impact changes the LO velocity by dv; the accelerometer renders it as a
unit-area pulse whose centre value is ``dv * k0`` with ``k0 = 2 * cutoff * fs``
(the band-limited kernel's peak, :meth:`PulseModel.peak`). Against white noise
of RMS ``sigma_a`` its peak SNR is ``|dv| k0 / sigma_a``. A true impact is
*detectable* when

* ``|dv| k0 / sigma_a >= DETECTABLE_SNR`` (8: comfortably above the detection
  threshold of 5.5, so that recall is not decided by noise: at the edge the
  matched-filter SNR is 8.4 and a miss needs a -2.9 sigma noise excursion), and
* no stronger true impact lies within ``RESOLUTION`` seconds (two samples at
  6400 Hz): pulses closer than that merge into one.

The chatter tail of a sticking sequence (relative speeds 0.006 m/s, 0.001 m/s,
... at the left wall) falls below the first condition; those impacts are
physically present but not observable in the acceleration.

With compliant walls a contact lasts a finite time, and the LO's velocity change
from contact entry to exit (the truth's ``dv``) adds the LO's own smooth motion
over the contact to the impulse of the contact force. For an impact (0.1-1 ms)
that part is negligible; for a *resting contact*, where the ball arrives at
0.1 mm/s and lies on the wall for milliseconds while the LO carries it, it is
everything (realism corpus dev-011: 200 m/s^2 x 7 ms = 1.4 m/s, no pulse in the
recording). The criterion is therefore applied to the impulse of the contact,
:func:`contact_dv`: the LO velocity jump of an instantaneous impact with the same
relative velocities at entry and exit, ``m2 / (m1 + m2) |v_in - v_out|``. On the
exact engine that is the truth's ``dv`` exactly (momentum conservation).

Examples
--------
>>> import numpy as np
>>> bool(detectable(np.array([0.0, 0.5]), np.array([1e-3, 1e-6]), 0.05, 6400.0)[1])
False
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..truth import GroundTruth

__all__ = ["DETECTABLE_SNR", "RESOLUTION", "contact_dv", "detectable", "detectable_truth",
           "match_impacts", "match_impacts_by_wall", "detection_scores", "DetectionScores"]

#: Peak SNR a true impact must reach to count as detectable.
DETECTABLE_SNR = 8.0
#: Two true impacts closer than this (s) are one pulse; only the stronger counts.
RESOLUTION = 2.0 / 6400.0


def detectable(t: np.ndarray, dv: np.ndarray, a_noise: float, sample_rate: float,
               cutoff: float = 0.45, snr: float = DETECTABLE_SNR,
               resolution: float = RESOLUTION) -> np.ndarray:
    """Boolean mask of the true impacts a detector can be asked to find.

    Parameters
    ----------
    t, dv : ndarray
        True impact times (s) and LO velocity jumps (m/s).
    a_noise : float
        Accelerometer noise RMS (m/s^2).
    sample_rate : float
        Hz.
    cutoff : float
        Acquisition low-pass cut-off as a fraction of the sampling rate.
    snr : float
        Required peak SNR (default :data:`DETECTABLE_SNR`).
    resolution : float
        Impacts closer than this to a stronger one are not separately detectable.

    Returns
    -------
    ndarray of bool
    """
    t = np.asarray(t, dtype=float)
    dv = np.abs(np.asarray(dv, dtype=float))
    k0 = 2.0 * cutoff * sample_rate
    if a_noise <= 0:
        strong = dv > 0
    else:
        strong = dv * k0 / a_noise >= snr
    ok = strong.copy()
    order = np.argsort(t)
    ts, ds = t[order], dv[order]
    for k in range(ts.size):
        lo = np.searchsorted(ts, ts[k] - resolution, side="left")
        hi = np.searchsorted(ts, ts[k] + resolution, side="right")
        others = np.r_[ds[lo:k], ds[k + 1:hi]]
        if others.size and (others > ds[k]).any():
            ok[order[k]] = False
    return ok


def contact_dv(v_in, v_out, m1: float, m2: float) -> np.ndarray:
    """LO velocity jump (m/s) of the impulse of contacts with these relative velocities.

    ``m2 / (m1 + m2) |v_in - v_out|``: what an instantaneous impact that turns the
    relative velocity ``v_in`` at contact entry into ``v_out`` at exit gives the LO
    (momentum conservation), without the LO's own motion during the contact (see the
    module's notes on resting contacts).

    Parameters
    ----------
    v_in, v_out : array_like
        Relative velocities z' at contact entry and exit (m/s).
    m1, m2 : float
        LO and ball masses (kg).

    Returns
    -------
    ndarray
    """
    v_in, v_out = np.asarray(v_in, dtype=float), np.asarray(v_out, dtype=float)
    return m2 / (m1 + m2) * np.abs(v_in - v_out)


def detectable_truth(truth: GroundTruth) -> np.ndarray:
    """:func:`detectable` applied to the true impacts of a :class:`GroundTruth`.

    The criterion is applied to the impulse of each contact (:func:`contact_dv`).
    """
    sensors = truth.sensors
    p = truth.params
    dv = contact_dv(truth.impacts.v_in, truth.impacts.v_out, p.m1, p.m2)
    return detectable(truth.impacts.t, dv, float(sensors.get("a_noise", 0.05)),
                      float(sensors.get("sample_rate", 6400.0)),
                      float(sensors.get("cutoff", 0.45)))


def match_impacts(t_est: np.ndarray, t_true: np.ndarray, tol: float = 0.5e-3
                  ) -> tuple[np.ndarray, np.ndarray]:
    """One-to-one matching of estimated to true impact times, nearest first.

    Parameters
    ----------
    t_est, t_true : ndarray
        Times (s).
    tol : float
        Largest accepted time difference (s).

    Returns
    -------
    i_est, i_true : ndarray of int
        Indices of the matched pairs, sorted by ``i_est``.
    """
    t_est = np.asarray(t_est, dtype=float)
    t_true = np.asarray(t_true, dtype=float)
    if t_est.size == 0 or t_true.size == 0:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    order = np.argsort(t_true)
    ts = t_true[order]
    pairs = []
    for i, te in enumerate(t_est):
        k = np.searchsorted(ts, te)
        for kk in (k - 2, k - 1, k, k + 1):
            if 0 <= kk < ts.size and abs(ts[kk] - te) <= tol:
                pairs.append((abs(ts[kk] - te), i, int(order[kk])))
    pairs.sort()
    used_e, used_t, out = set(), set(), []
    for _, i, j in pairs:
        if i not in used_e and j not in used_t:
            used_e.add(i)
            used_t.add(j)
            out.append((i, j))
    out.sort()
    if not out:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    arr = np.array(out, dtype=int)
    return arr[:, 0], arr[:, 1]


def match_impacts_by_wall(t_est, side_est, t_true, side_true, tol: float = 0.5e-3
                          ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`match_impacts` within each wall: an impact only matches one on its side.

    Parameters
    ----------
    t_est, t_true : ndarray
        Times (s).
    side_est, side_true : array of str
        ``"right"`` / ``"left"``.
    tol : float
        Largest accepted time difference (s).

    Returns
    -------
    i_est, i_true : ndarray of int
        Indices of the matched pairs (right wall first).
    """
    side_est, side_true = np.asarray(side_est), np.asarray(side_true)
    t_est, t_true = np.asarray(t_est, dtype=float), np.asarray(t_true, dtype=float)
    ie, it = [], []
    for side in ("right", "left"):
        ke, kt = np.flatnonzero(side_est == side), np.flatnonzero(side_true == side)
        e, t = match_impacts(t_est[ke], t_true[kt], tol)
        ie.append(ke[e])
        it.append(kt[t])
    return np.concatenate(ie), np.concatenate(it)


@dataclass(frozen=True)
class DetectionScores:
    """Detection quality against ground truth.

    Attributes
    ----------
    precision : float
        Matched detections / detections (1.0 when nothing was detected).
    recall : float
        Matched detectable true impacts / detectable true impacts (1.0 if none).
    timing_median, timing_max : float
        Median and largest |t_est - t_true| over the matches (s).
    side_accuracy : float
        Share of side-blind matches with the right side (matches counted by
        precision and recall need the same wall).
    n_est, n_true, n_detectable, n_matched : int
    undetectable_share : float
        Share of true impacts that are not detectable.
    i_est, i_true : ndarray
        Matched index pairs.
    """

    precision: float
    recall: float
    timing_median: float
    timing_max: float
    side_accuracy: float
    n_est: int
    n_true: int
    n_detectable: int
    n_matched: int
    undetectable_share: float
    i_est: np.ndarray
    i_true: np.ndarray


def detection_scores(t_est: np.ndarray, side_est: np.ndarray, truth: GroundTruth,
                     tol: float = 0.5e-3) -> DetectionScores:
    """Precision, recall (on detectable impacts), timing and side accuracy.

    Detections are matched to true impacts on the same wall only. A detection
    matched to an undetectable true impact counts as correct (not a false alarm)
    but does not enter the recall.

    Parameters
    ----------
    t_est, side_est : ndarray
        Detected times (s) and sides ("right"/"left").
    truth : GroundTruth
        Ground truth of the recording (:func:`vidiscover.record`).
    tol : float
        Matching tolerance (s).

    Returns
    -------
    DetectionScores
    """
    t_est = np.asarray(t_est, dtype=float)
    side_est = np.asarray(side_est).astype(str)
    t_true, s_true = truth.impacts.t, truth.impacts.side
    det = detectable_truth(truth)
    # a match needs the same wall: a pulse of the wrong sign is a false alarm
    pairs_e, pairs_t = [], []
    for side in ("right", "left"):
        ke, kt = np.flatnonzero(side_est == side), np.flatnonzero(s_true == side)
        e, t = match_impacts(t_est[ke], t_true[kt], tol)
        pairs_e.append(ke[e])
        pairs_t.append(kt[t])
    i_e, i_t = np.concatenate(pairs_e), np.concatenate(pairs_t)
    order = np.argsort(i_e)
    i_e, i_t = i_e[order], i_t[order]
    n_est = int(t_est.size)
    n_det = int(det.sum())
    precision = i_e.size / n_est if n_est else 1.0
    recall = det[i_t].sum() / n_det if n_det else 1.0
    err = np.abs(t_est[i_e] - t_true[i_t]) if i_e.size else np.zeros(0)
    a_e, a_t = match_impacts(t_est, t_true, tol)            # side-blind, for side accuracy
    side_ok = (side_est[a_e] == s_true[a_t]) if a_e.size else np.zeros(0, dtype=bool)
    return DetectionScores(
        precision=float(precision), recall=float(recall),
        timing_median=float(np.median(err)) if err.size else float("nan"),
        timing_max=float(err.max()) if err.size else float("nan"),
        side_accuracy=float(np.mean(side_ok)) if side_ok.size else float("nan"),
        n_est=n_est, n_true=int(t_true.size), n_detectable=n_det, n_matched=int(i_e.size),
        undetectable_share=float(1 - n_det / t_true.size) if t_true.size else 0.0,
        i_est=i_e, i_true=i_t)
