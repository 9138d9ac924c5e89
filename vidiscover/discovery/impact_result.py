"""The result of impact-law discovery and the notion of "same functional form".

:class:`ImpactLawResult` is a frozen value: the selected law, its coefficients with
bootstrap intervals, the table of all candidates, the comparison with a constant r
and the bootstrap band of r(v). :func:`same_form` says whether two laws have the same
functional form *as far as pooled impact data can tell* (:data:`EQUIVALENT_EXPONENTS`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..analysis.restitution import R_MAX
from ..errors import InputError
from ..restitution_laws import RestitutionLaw
from .impact_terms import (
    CONSTANT_TERM,
    HUNT_CROSSLEY_TERM,
    IMPACT_TERMS,
    hunt_crossley_restitution,
)

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

__all__ = ["ImpactLawResult", "same_form", "EQUIVALENT_EXPONENTS", "RESULT_KINDS"]

#: Groups of power-law exponents that :func:`same_form` treats as one form: the
#: best-fitting curves ``1 - a v^0.2`` and ``1 - a' v^0.25`` differ by at most
#: ~0.04 a in r over 0.3-1.3 m/s (0.011 for a = 0.3), about the scatter of a real
#: rig's r estimates. Simulated data at the default sensor noise do resolve them;
#: the tests check exact exponents.
EQUIVALENT_EXPONENTS: tuple[frozenset[float], ...] = (frozenset({0.2, 0.25}),)

#: Values of :attr:`ImpactLawResult.kind`: a :data:`~vidiscover.LAW_KINDS` kind,
#: ``"hunt-crossley"`` (``r = r_HC(alpha v)``), ``"generic"`` (a formula with no
#: RestitutionLaw kind) or ``"undetermined"``.
RESULT_KINDS = ("constant", "linear", "power", "hunt-crossley", "generic", "undetermined")
#: Points of the machine-readable band in :meth:`ImpactLawResult.to_dict`.
BAND_POINTS = 25



def _exponent_group(p: float) -> frozenset[float]:
    for group in EQUIVALENT_EXPONENTS:
        if any(math.isclose(p, q, rel_tol=1e-9) for q in group):
            return group
    return frozenset({round(float(p), 9)})


def _normal_law(law: RestitutionLaw) -> RestitutionLaw:
    """``1 - a v^1`` is the linear law with ``r0 = 1``."""
    if law.kind == "power" and math.isclose(law.p, 1.0):
        return RestitutionLaw("linear", r0=1.0, a=law.a)
    return law


def same_form(a: RestitutionLaw | str | None, b: RestitutionLaw | str | None) -> bool:
    """Whether two laws have the same functional form, as far as data can tell.

    Same kind (``1 - a v`` counts as linear), and for power laws exponents in the
    same group of :data:`EQUIVALENT_EXPONENTS` (or equal). Coefficients are ignored.

    Parameters
    ----------
    a, b : RestitutionLaw, spec string or None
        Laws to compare; None (a generic discovered formula) matches nothing.

    Returns
    -------
    bool
        True when the forms agree.

    Examples
    --------
    >>> same_form("power:0.3:0.2", "power:0.1:0.25"), same_form("power:0.3:0.5", "0.9")
    (True, False)
    """
    if a is None or b is None:
        return False
    a, b = _normal_law(RestitutionLaw.parse(a)), _normal_law(RestitutionLaw.parse(b))
    if a.kind != b.kind:
        return False
    return a.kind != "power" or _exponent_group(a.p) == _exponent_group(b.p)


# --------------------------------------------------------------------------- result
def _num(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _evaluate(terms: Sequence[str], coefs: np.ndarray, v) -> np.ndarray:
    """Restitution at speeds ``v``.

    Shape ``v.shape``, or ``v.shape + (n_sets,)`` for a 2-D ``coefs`` holding one
    coefficient set per row.
    """
    v = np.asarray(v, dtype=float)
    coefs = np.asarray(coefs, dtype=float)
    if tuple(terms) == (HUNT_CROSSLEY_TERM,):
        alpha = coefs[..., 0] if coefs.ndim == 2 else coefs[0]
        return hunt_crossley_restitution(np.multiply.outer(v, alpha))
    cols = np.stack([IMPACT_TERMS[t](v) for t in terms], axis=-1)
    return cols @ coefs.T


@dataclass(frozen=True, eq=False)
class ImpactLawResult:
    """Discovered impact law of one wall, with uncertainty and model comparison.

    Attributes
    ----------
    formula : str
        E.g. ``'r = 1 - 0.3 v^0.5'`` (the law's formula when ``law`` is set).
    kind : str
        One of :data:`RESULT_KINDS`.
    law : RestitutionLaw or None
        The law, when the selected candidate matches a RestitutionLaw kind.
    terms : tuple of str
        Terms of ``r = sum_k c_k f_k(v)`` (registry names; ``"1"`` is the intercept).
    coefficients : Mapping[str, float]
        ``c_k`` per term.
    ci : Mapping[str, tuple of float]
        Bootstrap percentile interval at ``level`` per term (NaN without bootstrap).
    fixed_intercept : bool
        The intercept is fixed at 1 (``1 - r`` was regressed), not estimated.
    candidates : pandas.DataFrame
        One row per candidate: ``name, n_params, rss, aicc, delta_aicc, cv_rmse,
        effect, admissible, source, selected, bootstrap_frequency`` (``admissible``:
        its r stays in ``(0, R_MAX]`` from rest through the fastest impact).
    delta_aicc_vs_constant : float
        ``AICc(constant) - AICc(alternative)``; > 0 favours a velocity dependence.
    p_value_vs_constant : float
        F-test p-value of the constant law against ``alternative`` (post-selection).
    alternative : str
        Candidate compared with the constant: the selected one, or the best
        velocity-dependent candidate when a constant is selected.
    speed_range : tuple of float
        Min and max impact speed used (m/s).
    n, n_dropped, n_outliers : int
        Impacts used; rows dropped for NaN/inf; rows dropped as gross outliers.
    sigma : float
        Residual RMS of the selected fit (unweighted, in units of r).
    support_frequency : float
        Share of bootstrap resamples in which the selection picks the same candidate.
    selection_frequency : Mapping[str, float]
        Share of bootstrap resamples picking each candidate (decreasing).
    criterion : str
        ``"aicc"`` or ``"cv"``.
    level : float
        Confidence level of ``ci`` and :meth:`band`.
    warning : str or None
        Which impacts were excluded as inconsistent (:attr:`n_inconsistent`), why
        the fit fell back to a constant (or found nothing), that the estimates rise
        with speed beyond the threshold, and that r exceeds 1 over the observed
        speeds (a passive wall cannot), saying whether by more than twice the
        standard error of an r estimate (biased estimates); else None.
    boot_coefficients : ndarray, shape (n_boot, len(terms))
        Refitted coefficients per resample.
    effect : float
        Max - min of the selected law over the observed speeds (1st-99th
        percentile); 0 for a constant.
    effect_threshold : float
        Smallest effect a speed dependence needed to be reported:
        ``max(min_effect, EFFECT_PER_SCATTER * precision, EFFECT_PER_SIGMA *
        s_ends)``; a law in which r rises with speed is reported only with
        ``rising=True``, and then needs ``RISING_FACTOR`` times it.
    precision : float
        Weighted RMS scatter of the r estimates about the best law.
    note : str or None
        Why a speed dependence that AICc prefers was not reported (its effect
        was below ``effect_threshold``, or its r leaves the admissible range over
        :attr:`valid_range`), else None.
    n_inconsistent : int
        Impacts excluded because their incoming speed contradicts their outgoing
        one (the outgoing speed of a populous cluster of impacts after a much
        faster or slower impact: the incoming flight probably spans a missed
        impact); :attr:`warning` says which.
    valid_range : tuple of float
        Speeds (m/s) the law claims: from rest to 1.4 times the fastest impact
        used (the band's upper end). Its r stays admissible there
        (``0 < r <= R_MAX``, :data:`vidiscover.analysis.restitution.R_MAX`): the
        selection takes no law that does not. How far the law is *identified* is
        :attr:`speed_range`; outside it, read :meth:`band`.
    form_scatter : float
        Model-form scatter of the r estimates the fit was given (``form_scatter``
        of :func:`~vidiscover.discovery.impact_law.discover_impact_law`; a compliant
        wall's in ``discover``), 0 for none: systematic errors that the bootstrap
        over impacts cannot see; :meth:`band` adds them.
    """

    formula: str
    kind: str
    law: RestitutionLaw | None
    terms: tuple[str, ...]
    coefficients: Mapping[str, float]
    ci: Mapping[str, tuple[float, float]]
    fixed_intercept: bool
    candidates: pd.DataFrame = field(repr=False)
    delta_aicc_vs_constant: float
    p_value_vs_constant: float
    alternative: str
    speed_range: tuple[float, float]
    n: int
    n_dropped: int
    n_outliers: int
    sigma: float
    support_frequency: float
    selection_frequency: Mapping[str, float] = field(repr=False)
    criterion: str
    level: float
    warning: str | None
    boot_coefficients: np.ndarray = field(repr=False)
    effect: float = math.nan
    effect_threshold: float = math.nan
    precision: float = math.nan
    note: str | None = None
    n_inconsistent: int = 0
    valid_range: tuple[float, float] = (math.nan, math.nan)
    form_scatter: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in RESULT_KINDS:
            raise ValueError(f"kind must be one of {', '.join(RESULT_KINDS)}, was {self.kind!r}")
        unknown = [t for t in self.terms if t not in IMPACT_TERMS
                   and t != HUNT_CROSSLEY_TERM]
        if unknown:
            raise ValueError(f"terms must be registered impact terms, unknown: {unknown}")
        if tuple(self.coefficients) != tuple(self.terms) or tuple(self.ci) != tuple(self.terms):
            raise ValueError("coefficients and ci must have one entry per term, in order")
        boot = np.asarray(self.boot_coefficients, dtype=float)
        if boot.ndim != 2 or boot.shape[1] != len(self.terms):
            raise ValueError(f"boot_coefficients must have shape (n_boot, "
                             f"{len(self.terms)}), was {boot.shape}")
        if not 0.0 < self.level < 1.0:
            raise ValueError(f"level must be in (0, 1), was {self.level!r}")

    @property
    def velocity_dependent(self) -> bool:
        """True when the selected law depends on the impact speed."""
        return any(t != CONSTANT_TERM for t in self.terms)

    def predict(self, v) -> np.ndarray:
        """Point estimate of r at speeds ``v`` (m/s).

        Not clipped: NaN where the law's r is impossible (``r <= 0`` or ``r >
        R_MAX``; the selection keeps that from happening over :attr:`valid_range`).
        """
        if not self.terms:
            return np.full(np.shape(v), np.nan)
        r = _evaluate(self.terms, np.array([self.coefficients[t] for t in self.terms]), v)
        return np.where((r > 0.0) & (r <= R_MAX), r, np.nan)

    def band_table(self, n_points: int = BAND_POINTS) -> dict:
        """The band on a grid from 0.6 x the slowest to 1.4 x the fastest observed speed.

        Returns
        -------
        dict
            ``level``, ``v``, ``lo``, ``mid``, ``hi`` (lists; NaN becomes None in
            :meth:`to_dict`), empty lists without impacts.
        """
        v0, v1 = self.speed_range
        if not (self.terms and math.isfinite(v0) and math.isfinite(v1)):
            return {"level": float(self.level), "v": [], "lo": [], "mid": [], "hi": []}
        grid = np.linspace(0.6 * v0, 1.4 * v1, n_points)
        lo, mid, hi = self.band(grid)
        return {"level": float(self.level), "v": grid.tolist(), "lo": lo.tolist(),
                "mid": mid.tolist(), "hi": hi.tolist()}

    def band(self, v_grid, level: float | None = None) -> tuple[np.ndarray, np.ndarray,
                                                                np.ndarray]:
        """Pointwise band of r(v) that widens outside the observed speeds.

        Inside :attr:`speed_range`: percentiles of the bootstrap curves. Outside
        it, the bootstrap curves extrapolate the selected form, and a speed
        dependence too small to be reported (an effect up to
        :attr:`effect_threshold` over the observed span) may continue there: the
        band is widened on both sides by ``effect_threshold * d / span``, ``d``
        the distance (m/s) to the observed range. Where no speed dependence could
        be told at all (the impact speeds form one cluster: an infinite
        :attr:`effect_threshold`), r is not identified outside the observed speeds:
        the band is infinite there (None in :meth:`to_dict`). A model-form
        scatter (:attr:`form_scatter`, what repeats at every impact of a speed and
        the bootstrap over impacts cannot see) widens the band everywhere by its
        normal quantile at ``level`` times it (1.96 x at 95 %).

        Parameters
        ----------
        v_grid : array_like
            Speeds (m/s).
        level : float, optional
            Coverage of the bootstrap part (default :attr:`level`).

        Returns
        -------
        lo, mid, hi : ndarray
            Lower bound, point estimate and upper bound at each speed (``lo``/``hi``
            are NaN without bootstrap resamples).
        """
        level = self.level if level is None else float(level)
        if not 0.0 < level < 1.0:
            raise InputError(f"band level must be in (0, 1), was {level!r}")
        v_grid = np.asarray(v_grid, dtype=float)
        mid = self.predict(v_grid)
        if self.boot_coefficients.shape[0] == 0 or not self.terms:
            nan = np.full(v_grid.shape, np.nan)
            return nan, mid, nan.copy()
        curves = _evaluate(self.terms, self.boot_coefficients, v_grid)  # (..., n_boot)
        q = 50.0 * (1.0 - level)
        lo, hi = np.percentile(curves, [q, 100.0 - q], axis=-1)
        v0, v1 = self.speed_range
        span = max(v1 - v0, 1e-12)
        dist = np.maximum(v0 - v_grid, 0.0) + np.maximum(v_grid - v1, 0.0)
        thr = self.effect_threshold
        if math.isinf(thr):   # no speed dependence could be told (one speed cluster)
            extra = np.where(dist > 0.0, math.inf, 0.0)
        else:
            extra = (thr if math.isfinite(thr) else 0.0) * dist / span
        if self.form_scatter > 0.0:
            from scipy.stats import norm

            extra = extra + float(norm.ppf(0.5 + level / 2.0)) * self.form_scatter
        return np.minimum(lo, mid) - extra, mid, np.maximum(hi, mid) + extra

    def to_dict(self) -> dict:
        """JSON-ready form (NaN becomes None)."""
        cands = []
        for row in self.candidates.to_dict("records"):
            cands.append({k: (_num(v) if isinstance(v, (float, np.floating)) else
                              (bool(v) if isinstance(v, (bool, np.bool_)) else
                               (int(v) if isinstance(v, (int, np.integer)) else v)))
                          for k, v in row.items()})
        return {
            "formula": self.formula, "kind": self.kind,
            "law": None if self.law is None else self.law.to_dict(),
            "terms": list(self.terms),
            "coefficients": {t: {"value": _num(self.coefficients[t]),
                                 "ci": [_num(self.ci[t][0]), _num(self.ci[t][1])]}
                             for t in self.terms},
            "fixed_intercept": bool(self.fixed_intercept),
            "velocity_dependent": self.velocity_dependent,
            "delta_aicc_vs_constant": _num(self.delta_aicc_vs_constant),
            "p_value_vs_constant": _num(self.p_value_vs_constant),
            "alternative": self.alternative,
            "speed_range": [_num(self.speed_range[0]), _num(self.speed_range[1])],
            "n": int(self.n), "n_dropped": int(self.n_dropped),
            "n_outliers": int(self.n_outliers), "n_inconsistent": int(self.n_inconsistent),
            "valid_range": [_num(self.valid_range[0]), _num(self.valid_range[1])],
            "sigma": _num(self.sigma),
            "support_frequency": _num(self.support_frequency),
            "selection_frequency": {k: _num(f) for k, f in self.selection_frequency.items()},
            "criterion": self.criterion, "level": float(self.level),
            "n_boot": int(self.boot_coefficients.shape[0]),
            "effect": _num(self.effect), "effect_threshold": _num(self.effect_threshold),
            "precision": _num(self.precision), "note": self.note,
            "form_scatter": _num(self.form_scatter),
            "band": {k: ([_num(x) for x in val] if isinstance(val, list) else val)
                     for k, val in self.band_table().items()},
            "warning": self.warning, "candidates": cands,
        }
