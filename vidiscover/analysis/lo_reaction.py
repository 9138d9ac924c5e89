"""Friction read from the LO's own motion: the reaction of the ball's dry friction.

The ball's flights tell friction only through the velocity jumps at the impacts, and
in flights of equal duration its integrals cancel (the weak form of
:mod:`vidiscover.discovery.flight_law` then confounds it with the inclination). The
LO feels it directly: between impacts (the model of the README)::

    x'' = -(k1/m1) (x - xe) - (c1/m1) (x' - xe') + (m2/m1) mu g sgn(z')

so the measured acceleration, regressed on the laser's ``x - xe``, its derivative, a
constant (the accelerometer's bias) and ``sgn(z')`` over the samples away from every
impact, gives ``mu`` as the step that follows the ball's direction, without any pulse
area. The stiffness and damping are fitted too (a check of the recording's metadata:
a fit that disagrees with ``k1/m1`` by more than :data:`MAX_STIFFNESS_ERROR` is not
identified). The same linear smoothing (Savitzky-Golay, a 40th of a forcing period)
acts on every column, so filters and sensor gains that act on all channels alike (the
anti-alias filter of the acquisition chain) leave the relation linear.

``sgn(z')`` is the sign of the ball's velocity relative to the LO along each flight,
with the ball on the straight line between its impact positions (``mu = 0``); samples
where that relative velocity is within 5 % of the flight's mean speed are left out
(the sign is uncertain there, the ball may stick). Standard errors are cluster-robust
with one cluster per stretch of kept samples (a flight between two exclusion windows):
the residuals of a stretch share the model-form error of its flight.

The acceleration less this model, summed over each impact's window, is the LO's velocity
jump with no pulse shape assumed; tried as the flight law's jumps (2026-11-27) it was
0.0-0.6 % off per wall on the corpus but 1.6-2.7 % on the independent simulator: a sum of
samples misses a short pulse's aliased part, one scale per wall when the sample rate is a
multiple of the forcing (8 Hz at 6400 Hz), so it is not computed here.

Precision: ``(m2/m1) g`` is 0.08 m/s^2 on the paper's rig, so mu = 0.03 is a step of
2.3 mm/s^2 in the acceleration; a 40-period record at 5-13 kHz resolves it
(standard errors 0.001-0.03 on the spent ``dev`` split of the realism corpus).

Examples
--------
>>> from vidiscover.analysis import analyze
>>> from vidiscover.params import preset
>>> from vidiscover.effects import Effects
>>> from vidiscover.workflows import simulate_to_memory
>>> sim = simulate_to_memory(preset("paper", b=0.006),
...                          Effects.parse(["coulomb_friction=0.1"]), seed=1,
...                          duration=8.0, label=False)
>>> res = lo_reaction_of(analyze(sim.recording, n_boot=0))
>>> res.identified, abs(res.mu - 0.1) < 0.02
(True, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..params import G_ACCEL
from .signals import quadratic_smoother

__all__ = ["LoReaction", "lo_reaction", "lo_reaction_of", "pooled_lo_reaction",
           "MAX_STIFFNESS_ERROR", "MAX_SE"]


#: Largest relative difference between the fitted LO stiffness (k1/m1) and the
#: metadata's before the fit is refused: the regression then misses the LO's dynamics.
MAX_STIFFNESS_ERROR = 0.1
#: Largest standard error of a pooled mu reported as a result (the flight law's bound).
MAX_SE = 0.015
_PRE, _POST = 0.0015, 0.0045     # excluded around every impact (s, before / after) ...
_PRE_SAMPLES = 8                 # ... plus these samples before and 3x after
_SLOW = 0.05                     # |z'| below this share of the flight's speed: sign unsure
_MIN_FLIGHTS = 2                 # kept stretches of each sign
_MIN_SAMPLES = 200


@dataclass(frozen=True)
class LoReaction:
    """Friction from the LO's acceleration between impacts (one recording or pooled).

    Attributes
    ----------
    mu, mu_se : float
        Friction coefficient and its standard error (NaN when not identified).
    stiffness, damping : float
        Fitted ``k1/m1`` (1/s^2) and ``c1/m1`` (1/s); NaN when pooled.
    r2 : float
        Share of the acceleration's variance between impacts the LO model explains.
    n_samples, n_flights : int
        Samples and stretches (flights) used.
    identified : bool
    reason : str
        Why not identified ("" when identified).
    """

    mu: float
    mu_se: float
    stiffness: float = math.nan
    damping: float = math.nan
    r2: float = math.nan
    n_samples: int = 0
    n_flights: int = 0
    identified: bool = True
    reason: str = ""

    @classmethod
    def refused(cls, reason: str, **kw) -> LoReaction:
        """A result that is not identified, with its one-line reason."""
        return cls(mu=math.nan, mu_se=math.nan, identified=False, reason=reason, **kw)

    def to_dict(self) -> dict:
        """JSON-ready form (NaN as None)."""
        def num(v):
            return None if isinstance(v, float) and not math.isfinite(v) else v
        return {"mu": num(self.mu), "mu_se": num(self.mu_se),
                "stiffness": num(self.stiffness), "damping": num(self.damping),
                "r2": num(self.r2), "n_samples": self.n_samples,
                "n_flights": self.n_flights, "identified": self.identified,
                "reason": self.reason}


def _runs(mask: np.ndarray) -> np.ndarray:
    """Label of the contiguous run of True each sample belongs to (-1 where False)."""
    edges = np.diff(np.concatenate([[0], mask.view(np.int8)]))
    lab = np.cumsum(edges == 1) - 1
    return np.where(mask, lab, -1)


def lo_reaction(t: np.ndarray, x: np.ndarray, a: np.ndarray, xe: np.ndarray, *,
                t_imp: np.ndarray, y_imp: np.ndarray, bad: np.ndarray | None,
                tau: np.ndarray | float = 0.0, m1: float, m2: float, k1: float,
                frequency: float) -> LoReaction:
    """Friction coefficient from the LO's acceleration between impacts.

    Parameters
    ----------
    t, x, a, xe : ndarray
        Record times (s), laser ``x`` (m), acceleration (m/s^2), base displacement (m).
    t_imp, y_imp : ndarray
        Impact times (s, sorted) and the ball's positions there (m), from the analysis.
    bad : ndarray of bool or None
        Samples to leave out (clipped, missing).
    tau : ndarray or float
        Contact duration of each impact (s; 0 for rigid walls): the window left out
        after an impact is the contact plus the acquisition chain's settling.
    m1, m2, k1 : float
        LO mass, ball mass (kg) and LO stiffness (N/m) of the metadata.
    frequency : float
        Forcing frequency (Hz): sets the smoothing window.

    Returns
    -------
    LoReaction
    """
    t = np.asarray(t, float)
    n = t.size
    t_imp = np.asarray(t_imp, float)
    if t_imp.size < 4:
        return LoReaction.refused(f"only {t_imp.size} impacts: too few flights to read "
                                  "friction from the LO")
    fs = (n - 1) / (t[-1] - t[0])
    keep = np.ones(n, bool) if bad is None else ~np.asarray(bad, bool)
    pre = int(round(_PRE * fs)) + _PRE_SAMPLES
    tau = np.broadcast_to(np.nan_to_num(np.asarray(tau, float)), t_imp.shape)
    post = np.round((_POST + tau) * fs).astype(np.int64) + 3 * _PRE_SAMPLES
    idx = np.searchsorted(t, t_imp)
    # every impact's window as a +1/-1 pair of edges, cumulated: inside where > 0
    edges = np.zeros(n + 1, np.int64)
    np.add.at(edges, np.clip(idx - pre, 0, n), 1)
    np.add.at(edges, np.clip(idx + post, 0, n), -1)
    keep &= np.cumsum(edges[:n]) == 0
    keep[:idx[0]] = False
    keep[idx[-1]:] = False
    w = max(5, int(fs / frequency / 40) | 1)
    if n < 4 * w:
        return LoReaction.refused("the record is too short to read friction from the LO")
    x, xe = (np.nan_to_num(np.asarray(v, float)) for v in (x, xe))
    # one local quadratic (Savitzky-Golay) per channel: its value and derivative
    (xs, vx), (es, ve) = (quadratic_smoother(v, w, 1 / fs) for v in (x, xe))
    ac = quadratic_smoother(np.nan_to_num(np.asarray(a, float)), w, 1 / fs)[0]
    # a smoothed sample is clean only if its whole window was
    keep &= np.convolve(~keep, np.ones(w), "same") < 0.5
    # sgn(z') along each flight: ball on the straight line between its impact positions
    y_imp = np.asarray(y_imp, float)
    wbar = np.diff(y_imp) / np.diff(t_imp)
    k = np.clip(np.searchsorted(t_imp, t, side="right") - 1, 0, wbar.size - 1)
    z = wbar[k] - vx
    sg = np.sign(z)
    keep &= np.abs(z) > _SLOW * np.abs(wbar[k]) + 1e-9
    lab = _runs(keep)
    flights = lab[keep]
    n_flights = int(flights.max()) + 1 if flights.size else 0
    signs = [np.unique(flights[sg[keep] == s]).size for s in (1.0, -1.0)]
    if keep.sum() < _MIN_SAMPLES or min(signs) < _MIN_FLIGHTS:
        return LoReaction.refused(
            f"too little of the record between impacts ({int(keep.sum())} samples, "
            f"{signs[0]}/{signs[1]} stretches towards the right/left wall) to read "
            "friction from the LO", n_samples=int(keep.sum()), n_flights=n_flights)
    A = np.column_stack([xs - es, vx - ve, np.ones(n), sg])[keep]
    Y = ac[keep]
    scale = np.sqrt(np.mean(A ** 2, axis=0))
    scale[scale == 0] = 1.0
    As = A / scale
    coef, *_ = np.linalg.lstsq(As, Y, rcond=None)
    resid = Y - As @ coef
    coef = coef / scale
    r2 = 1.0 - float(np.var(resid) / max(np.var(Y), 1e-300))
    stiffness, damping = -float(coef[0]), -float(coef[1])
    k_meta = k1 / m1
    to_mu = m1 / (m2 * G_ACCEL)
    common = dict(stiffness=stiffness, damping=damping, r2=r2, n_samples=int(keep.sum()),
                  n_flights=n_flights)
    if not abs(stiffness / k_meta - 1.0) <= MAX_STIFFNESS_ERROR:
        return LoReaction.refused(
            f"the LO stiffness fitted between impacts, k1/m1 = {stiffness:.4g} 1/s^2, is "
            f"not the metadata's {k_meta:.4g} (more than {MAX_STIFFNESS_ERROR:.0%} off): "
            "check k1 and m1, or the record's impacts", **common)
    # cluster-robust (one cluster per stretch) covariance of the scaled coefficients
    try:
        bread = np.linalg.inv(As.T @ As)
    except np.linalg.LinAlgError:
        return LoReaction.refused("the LO regression is singular (the ball's direction "
                                  "follows the LO's motion exactly)", **common)
    score = np.zeros((n_flights, As.shape[1]))
    np.add.at(score, flights, As * resid[:, None])
    g = n_flights
    meat = score.T @ score * (g / max(g - 1, 1))
    cov = bread @ meat @ bread
    se = math.sqrt(max(float(cov[3, 3]), 0.0)) / scale[3]
    return LoReaction(mu=float(coef[3]) * to_mu, mu_se=se * to_mu, **common)


def lo_reaction_of(analysis) -> LoReaction:
    """:func:`lo_reaction` of an :class:`~vidiscover.analysis.AnalysisResult`.

    Uses its recording (offsets need not be removed: the constant column takes them),
    its impacts, their learned contact durations and the ball positions of its
    reconstruction.
    """
    from .reconstruction import contact_durations

    rec = analysis.recording
    det = analysis.detection
    tau = contact_durations(det)
    imp = analysis.reconstruction.impact_columns
    meta = rec.meta
    return lo_reaction(rec.t, rec.x, rec.a, rec.xe, t_imp=np.asarray(imp["t"], float),
                       y_imp=np.asarray(imp["y"], float), bad=det.bad,
                       tau=tau if tau.size == len(imp["t"]) else float(np.max(tau, initial=0)),
                       m1=float(meta.m1), m2=float(meta.m2), k1=float(meta.k1),
                       frequency=float(analysis.forcing.frequency))


def pooled_lo_reaction(results, max_se: float = MAX_SE) -> LoReaction:
    """Inverse-variance mean of the identified :class:`LoReaction` of several recordings.

    Not identified when none is, when they disagree beyond their standard errors
    (chi-square of the spread above its 99 % point: the recordings then carry a
    model-form error of their own that the errors do not cover), or when the pooled
    standard error exceeds ``max_se``.
    """
    from scipy.stats import chi2

    results = list(results)
    ok = [r for r in results if r.identified and math.isfinite(r.mu_se) and r.mu_se > 0]
    if not ok:
        why = "; ".join(sorted({r.reason for r in results if r.reason})) or "no recording"
        return LoReaction.refused(why)
    mu = np.array([r.mu for r in ok])
    se = np.array([r.mu_se for r in ok])
    wt = 1.0 / se ** 2
    mean = float(np.sum(wt * mu) / wt.sum())
    stat = float(np.sum(wt * (mu - mean) ** 2))
    kw = dict(n_samples=sum(r.n_samples for r in ok), n_flights=sum(r.n_flights for r in ok),
              r2=min(r.r2 for r in ok))
    if len(ok) > 1 and stat > chi2.ppf(0.99, len(ok) - 1):
        vals = ", ".join(f"{m:.3g} +/- {s:.2g}" for m, s in zip(mu, se, strict=True))
        return LoReaction.refused(f"the recordings' LO friction disagree ({vals}): a "
                                  "model-form error of each recording's own", **kw)
    se_pool = float(1.0 / math.sqrt(wt.sum()))
    if not se_pool <= max_se:
        return LoReaction.refused(f"the LO's acceleration does not determine the friction "
                                  f"(mu {mean:.3g}, standard error {se_pool:.2g} > "
                                  f"{max_se:g}): record longer or with less noise", **kw)
    if mean < -2.0 * se_pool:
        return LoReaction.refused(f"the LO's acceleration gives a negative friction, mu = "
                                  f"{mean:.3g} (standard error {se_pool:.2g}): its model "
                                  "misses something", **kw)
    # mu >= 0: a fit within two standard errors below zero is no friction
    return LoReaction(mu=max(mean, 0.0), mu_se=se_pool, **kw)
