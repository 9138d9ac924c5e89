"""Impact-law discovery: the restitution coefficient r as a function of impact speed.

Per wall, the per-impact estimates ``(v_i, r_i)`` (``v = |z'-|`` in m/s) are
regressed on a library of candidate functions of v (:data:`IMPACT_TERMS`) in two
ways: ``r = sum_k c_k f_k(v)`` (free intercept) and ``1 - r = sum_k c_k f_k(v)``
(intercept fixed at 1: perfectly elastic as v -> 0, the power law ``1 - a v^p``).

0. **Weights and outliers.** With per-impact standard errors ``sigma`` every fit is
   weighted by ``1 / sigma^2``: the slow re-impacts of a chattering wall have far
   noisier r than fast impacts and would otherwise fake a speed dependence. Gross
   outliers (a re-impact next to a missed one) are dropped first: weighted
   residuals of the full-library fit beyond ``outlier_z`` robust sigmas.
1. **Candidates.** A pysindy threshold sweep (``STLSQ`` and ``SR3``-L0 on the
   feature matrix of a pysindy ``CustomLibrary``, for both targets) lists the
   supports it visits, up to ``max_terms`` terms. The nested
   physical forms are always added: ``r0``, ``r0 - a v``, ``1 - a v^p`` for every
   power term and ``r0 + c f(v)`` for every term, so the comparison with a constant
   r is explicit. Over 0.3-1.3 m/s the library columns are nearly collinear, and a
   threshold sweep mostly jumps from dense to empty supports: it proposes extra
   candidates, it does not decide.
2. **Selection.** Every candidate is refitted by (weighted) least squares and scored by AICc
   and by K-fold cross-validation (whole recordings per fold when ``groups`` is
   given). The default rule keeps the candidates within ``aicc_window`` (4) of the
   best AICc and takes the sparsest; among equally sparse ones a RestitutionLaw
   kind (``r0``, ``r0 - a v``, ``1 - a v^p``) before another nested form, before a
   sweep-only support, then the lowest AICc. A term is thus added only if it lowers
   AICc by more than 4 (chi-square(1) > 6, p ~ 0.014 per comparison), which keeps
   false speed dependences of a constant r near 5 % despite a dozen correlated
   candidates; with the usual 2 the rate is ~10 %. ``criterion="cv"`` takes the
   sparsest candidate within one standard error of the best CV error instead.
3. **Uncertainty.** Impacts are resampled with ``numpy.random.default_rng(seed)``;
   each resample refits the chosen terms (coefficient percentile CIs, pointwise
   band of r(v)) and re-runs the selection over the same candidate list (how often
   each candidate is chosen).
4. **Comparison with a constant r.** ``AICc(constant) - AICc(alternative)`` and the
   F-test p-value of the constant nested in ``r0 + sum c_k f_k(v)`` over the
   alternative's terms. The alternative is the selected law, or, when a constant is
   selected, the best velocity-dependent candidate. The p-value is computed after
   selection and is therefore optimistic; read it with the AICc difference.

What the data can tell apart (measured on simulated clearance sweeps, b = 6, 7.5
and 9 mm pooled, ``benchmarks/bench_discover.py``):

* the one-parameter power laws ``1 - a v^p`` (r = 1 at rest) are told apart by
  their slope at a given level of r, even over the narrow band of speeds of the
  right wall (~0.55-0.75 m/s): p = 0.2 and 0.5 (the cases tested) are resolved at the
  default sensor noise;
* the two-parameter laws ``r0 + c f(v)`` are *not* told apart over such a band:
  all of them fall inside the AICc window, and ``r0 - a v`` is reported because a
  catalogue law is preferred among equally sparse adequate candidates. What such
  data determine is the curve, not the function; the rivals and their bootstrap
  frequencies are in :attr:`ImpactLawResult.candidates`;
* simulated r estimates are precise to ~1e-4, so AICc also resolves differences
  of ~5e-4 that sensor imperfections (the laser's sheet resonance) introduce as
  systematic errors: the form is then misread while the curve stays within ~1e-3.
  ``min_effect`` (a practical tolerance on r) trades form resolution for
  robustness against such biases.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..restitution_laws import RestitutionLaw
from .impact_result import (
    EQUIVALENT_EXPONENTS,
    RESULT_KINDS,
    ImpactLawResult,
    same_form,
)
from .impact_terms import CONSTANT_TERM, IMPACT_TERMS

__all__ = ["discover_impact_law", "ImpactLawResult", "same_form", "EQUIVALENT_EXPONENTS",
           "RESULT_KINDS", "SIGMA_FLOOR"]

_CRITERIA = ("aicc", "cv")
#: Per-impact standard errors are floored at this share of their median.
SIGMA_FLOOR = 0.1
_N_THRESHOLDS = 8


# ----------------------------------------------------------------------- candidates
@dataclass(frozen=True)
class _Candidate:
    """Regression of r (free intercept) or 1 - r (intercept fixed at 1) on ``terms``."""

    terms: tuple[str, ...]
    fixed_intercept: bool

    @property
    def name(self) -> str:
        return ("1 - r ~ " if self.fixed_intercept else "r ~ ") + " + ".join(self.terms)

    @property
    def n_params(self) -> int:
        return len(self.terms)

    @property
    def r_terms(self) -> tuple[str, ...]:
        """Terms of the r-equation (with the fixed intercept)."""
        return ((CONSTANT_TERM,) + self.terms) if self.fixed_intercept else self.terms

    @property
    def velocity_dependent(self) -> bool:
        return self.fixed_intercept or any(t != CONSTANT_TERM for t in self.terms)


class _Design:
    """Feature matrix over the registry terms and weighted least-squares fits.

    ``sw`` holds the square roots of the row weights (1 / sigma_i, up to a common
    factor); every RSS is a weighted RSS.
    """

    def __init__(self, theta: np.ndarray, names: Sequence[str], sw: np.ndarray) -> None:
        self.theta = theta
        self.sw = sw
        self.col = {nm: j for j, nm in enumerate(names)}

    def fit(self, cand: _Candidate, r: np.ndarray, rows=None) -> tuple[np.ndarray, float]:
        """Coefficients of ``cand.r_terms`` in the r-equation and the weighted RSS."""
        theta = self.theta if rows is None else self.theta[rows]
        r = r if rows is None else r[rows]
        sw = self.sw if rows is None else self.sw[rows]
        X = theta[:, [self.col[t] for t in cand.terms]] * sw[:, None]
        y = (r - 1.0 if cand.fixed_intercept else r) * sw
        coef = np.linalg.lstsq(X, y, rcond=None)[0]
        rss = float(np.sum((y - X @ coef) ** 2))
        return (np.concatenate(([1.0], coef)) if cand.fixed_intercept else coef), rss

    def cv(self, cand: _Candidate, r: np.ndarray, folds: np.ndarray,
           rows=None) -> tuple[float, float, float]:
        """Pooled out-of-fold (weighted) RMSE and mean and s.e. of per-fold MSE."""
        idx = np.arange(r.size) if rows is None else np.asarray(rows)
        f = folds[idx]
        sq_all, per_fold = [], []
        for k in np.unique(f):
            test, train = idx[f == k], idx[f != k]
            if train.size == 0:
                continue
            coef, _ = self.fit(cand, r, train)
            pred = self.theta[test][:, [self.col[t] for t in cand.r_terms]] @ coef
            sq = ((r[test] - pred) * self.sw[test]) ** 2
            sq_all.append(sq)
            per_fold.append(float(np.mean(sq)))
        if not per_fold:
            return math.nan, math.nan, math.nan
        per_fold = np.asarray(per_fold)
        se = float(np.std(per_fold, ddof=1) / np.sqrt(per_fold.size)) if per_fold.size > 1 \
            else 0.0
        return float(np.sqrt(np.mean(np.concatenate(sq_all)))), float(per_fold.mean()), se


def _aicc(rss: float, n: int, n_params: int) -> float:
    k = n_params + 1  # + the noise variance
    if n - k - 1 <= 0:
        return math.inf
    return n * math.log(max(rss, 1e-300) / n) + 2 * k + 2 * k * (k + 1) / (n - k - 1)


def _tier(cand: _Candidate, nested: frozenset[_Candidate]) -> int:
    """Preference among equally sparse adequate candidates.

    0: a RestitutionLaw kind (``r0``, ``r0 - a v``, ``1 - a v^p``); 1: another nested
    form ``r0 + c f(v)``; 2: a support found only by the sweep.
    """
    if cand not in nested:
        return 2
    if cand.fixed_intercept or cand.terms in ((CONSTANT_TERM,), (CONSTANT_TERM, "v")):
        return 0
    return 1


def _select(cands: Sequence[_Candidate], tiers: np.ndarray, aicc: np.ndarray,
            cv_mse: np.ndarray, cv_se: np.ndarray, criterion: str, window: float,
            curves: np.ndarray | None = None, min_effect: float = 0.0) -> int:
    """Index of the sparsest adequate candidate (then lowest tier, then lowest AICc).

    Adequate: within the AICc window (or the CV one-SE rule) of the best, or, when
    ``min_effect > 0``, with a fitted curve (``curves``, one row per candidate on
    a grid of observed speeds) within ``min_effect`` of the best one everywhere.
    """
    n_params = np.array([c.n_params for c in cands])
    if criterion == "cv" and np.isfinite(cv_mse).any():
        best = int(np.nanargmin(cv_mse))
        ok = cv_mse <= cv_mse[best] + (cv_se[best] if np.isfinite(cv_se[best]) else 0.0)
    else:
        best = int(np.argmin(aicc))
        ok = np.isfinite(aicc) & (aicc <= aicc[best] + window)
    if min_effect > 0 and curves is not None:
        ok |= np.max(np.abs(curves - curves[best]), axis=1) <= min_effect
    idx = np.flatnonzero(ok)
    key = np.lexsort((aicc[idx], tiers[idx], n_params[idx]))
    return int(idx[key[0]])


def _unary(func):
    return lambda x: func(x)


def _name_of(name: str):
    return lambda x: name.replace("v", x)


def _library(v: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """Feature matrix of the registry terms in |v|, built by a pysindy CustomLibrary."""
    import pysindy as ps

    lib = ps.CustomLibrary(library_functions=[_unary(IMPACT_TERMS[nm]) for nm in names],
                           function_names=[_name_of(nm) for nm in names])
    theta = np.asarray(lib.fit_transform(np.abs(v)[:, None]), dtype=float)
    got = lib.get_feature_names(["v"])
    if list(got) != list(names):  # pragma: no cover - guards a pysindy API change
        raise RuntimeError(f"pysindy library columns {got} differ from terms {list(names)}")
    return theta


def _sweep(theta: np.ndarray, r: np.ndarray, sw: np.ndarray, names: Sequence[str],
           max_terms: int) -> set[_Candidate]:
    """Supports visited by STLSQ and SR3-L0 threshold sweeps, for r and for 1 - r.

    The regression of r is centred (weighted means: the intercept is always free);
    1 - r is not (the intercept is fixed at 1). Rows are scaled by ``sw``. Columns
    are scaled so that ``X.T @ X`` has a unit diagonal, which makes one threshold
    grid, relative to the target norm, fit both.
    Over a narrow speed range the library is nearly collinear, so the sweep often
    jumps from dense to empty supports: it proposes candidates, the nested physical
    forms guarantee that the meaningful ones are compared, and AICc/CV decide.
    """
    import pysindy as ps

    rest = [nm for nm in names if nm != CONSTANT_TERM]  # names always hold the constant
    F = theta[:, [list(names).index(nm) for nm in rest]]
    w = sw ** 2 / np.sum(sw ** 2)
    problems = [((F - w @ F) * sw[:, None], (r - w @ r) * sw, False),
                (F * sw[:, None], (1.0 - r) * sw, True)]
    found: set[_Candidate] = set()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for X, y, fixed in problems:
            norm = np.sqrt(np.sum(X ** 2, axis=0))
            ok = norm > 1e-12 * max(1.0, float(np.max(norm, initial=0.0)))
            X = X[:, ok] / norm[ok]
            cols = [nm for nm, keep in zip(rest, ok, strict=True) if keep]
            ynorm = float(np.sqrt(np.sum(y ** 2)))
            if not cols or ynorm == 0.0:
                continue
            zero = np.zeros((1, X.shape[1]))
            opts = []
            for thr in ynorm * np.geomspace(1e-2, 1.0, _N_THRESHOLDS):
                opts.append(ps.STLSQ(threshold=thr, alpha=1e-5, max_iter=50))
            for thr in ynorm * np.geomspace(3e-2, 1.0, _N_THRESHOLDS // 2):
                opts.append(ps.SR3(reg_weight_lam=thr ** 2 / 2, regularizer="L0",
                                   relax_coeff_nu=1.0, max_iter=100, unbias=True,
                                   initial_guess=zero))
            for opt in opts:
                try:
                    opt.fit(X, y)
                except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                    # a failed sweep point proposes nothing
                    continue
                support = tuple(c for c, w in zip(cols, np.ravel(opt.coef_), strict=True) if w != 0)
                terms = support if fixed else (CONSTANT_TERM,) + support
                if 0 < len(terms) <= max_terms:
                    found.add(_Candidate(terms, fixed))
    return found


def _nested(names: Sequence[str]) -> list[_Candidate]:
    """List the nested physical forms: r0, r0 - a v, 1 - a v^p, r0 + c f(v)."""
    out = [_Candidate((CONSTANT_TERM,), False)]
    for nm in names:
        if nm == CONSTANT_TERM:
            continue
        p = IMPACT_TERMS[nm].exponent
        if p is not None and p > 0:
            out.append(_Candidate((nm,), True))
        out.append(_Candidate((CONSTANT_TERM, nm), False))
    return out


# ------------------------------------------------------------------------ mapping
def _to_law(cand: _Candidate, coefs: np.ndarray) -> RestitutionLaw | None:
    c = dict(zip(cand.r_terms, map(float, coefs), strict=True))
    try:
        if not cand.fixed_intercept and cand.terms == (CONSTANT_TERM,):
            return RestitutionLaw.constant(c[CONSTANT_TERM])
        if not cand.fixed_intercept and cand.terms == (CONSTANT_TERM, "v"):
            return RestitutionLaw("linear", r0=c[CONSTANT_TERM], a=-c["v"])
        if cand.fixed_intercept and len(cand.terms) == 1:
            term = IMPACT_TERMS[cand.terms[0]]
            if term.exponent is not None and term.exponent > 0:
                a = -c[term.name]
                if math.isclose(term.exponent, 1.0):
                    return RestitutionLaw("linear", r0=1.0, a=a)
                return RestitutionLaw("power", r0=1.0, a=a, p=term.exponent)
    except InputError:  # e.g. r rising with speed, r0 > 1: no RestitutionLaw kind
        return None
    return None


def _generic_formula(terms: Sequence[str], coefs: np.ndarray) -> str:
    parts = []
    for t, c in zip(terms, map(float, coefs), strict=True):
        mag = f"{abs(c):.4g}" + ("" if t == CONSTANT_TERM else f" {t}")
        if not parts:
            parts.append(("-" if c < 0 else "") + mag)
        else:
            parts.append(("- " if c < 0 else "+ ") + mag)
    return "r = " + " ".join(parts)


# ------------------------------------------------------------------------ helpers
def _as_1d(name: str, x) -> np.ndarray:
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a 1-D array of numbers") from None
    if arr.ndim != 1:
        raise InputError(f"{name} must be a 1-D array, was {arr.ndim}-D with shape {arr.shape}")
    return arr


def _check_options(seed, n_bootstrap, criterion, aicc_window, n_folds, max_terms,
                   min_impacts, min_speed_span, level, terms) -> list[str]:
    if not isinstance(n_bootstrap, (int, np.integer)) or isinstance(n_bootstrap, bool) \
            or n_bootstrap < 0:
        raise InputError(f"n_bootstrap must be an integer >= 0, was {n_bootstrap!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed must be an integer >= 0, was {seed!r}")
    if criterion not in _CRITERIA:
        raise InputError(f"criterion must be one of {', '.join(_CRITERIA)}, was {criterion!r}")
    if not (isinstance(aicc_window, (int, float)) and math.isfinite(aicc_window)
            and aicc_window >= 0):
        raise InputError(f"aicc_window must be a finite number >= 0, was {aicc_window!r}")
    for name, value, lo in (("n_folds", n_folds, 2), ("max_terms", max_terms, 1),
                            ("min_impacts", min_impacts, 3)):
        if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < lo:
            raise InputError(f"{name} must be an integer >= {lo}, was {value!r}")
    if not (isinstance(min_speed_span, (int, float)) and min_speed_span >= 0):
        raise InputError(f"min_speed_span must be a number >= 0 (m/s), was {min_speed_span!r}")
    if not (isinstance(level, (int, float)) and 0.0 < level < 1.0):
        raise InputError(f"level must be in (0, 1), was {level!r}")
    names = list(IMPACT_TERMS) if terms is None else list(dict.fromkeys(terms))
    unknown = [t for t in names if t not in IMPACT_TERMS]
    if unknown:
        raise InputError(f"terms: unknown impact term(s) {', '.join(map(repr, unknown))}; "
                         f"registered: {', '.join(IMPACT_TERMS)}")
    if CONSTANT_TERM not in names:
        names.insert(0, CONSTANT_TERM)
    if len(names) < 2:
        raise InputError("terms must name at least one velocity-dependent term, e.g. ['v']")
    return [t for t in IMPACT_TERMS if t in names]  # registry order


def _folds(n: int, n_folds: int, groups: np.ndarray | None,
           rng: np.random.Generator) -> np.ndarray:
    """Fold label per row: whole groups per fold when ``groups`` is given."""
    if groups is not None:
        uniq, inv = np.unique(groups, return_inverse=True)
        if uniq.size >= 2:
            k = min(n_folds, uniq.size)
            return (rng.permutation(uniq.size) % k)[inv]
    k = min(n_folds, n)
    out = np.empty(n, dtype=int)
    out[rng.permutation(n)] = np.arange(n) % k
    return out


def _inliers(theta: np.ndarray, r: np.ndarray, sw: np.ndarray, z: float) -> np.ndarray:
    """Rows whose weighted residual from the full fit is within ``z`` robust sigmas."""
    keep = np.ones(r.size, dtype=bool)
    X, y = theta * sw[:, None], r * sw
    for _ in range(2):
        coef = np.linalg.lstsq(X[keep], y[keep], rcond=None)[0]
        e = y - X @ coef
        scale = 1.4826 * float(np.median(np.abs(e[keep] - np.median(e[keep]))))
        if not scale > 0:
            break
        keep = np.abs(e - np.median(e[keep])) <= z * scale
    return keep


def _percentile_ci(samples: np.ndarray, level: float) -> np.ndarray:
    if samples.shape[0] == 0:
        return np.full((2,) + samples.shape[1:], np.nan)
    q = 50.0 * (1.0 - level)
    return np.percentile(samples, [q, 100.0 - q], axis=0)


# ------------------------------------------------------------------------- public
def discover_impact_law(v, r, *, seed: int = 0, n_bootstrap: int = 200, groups=None,
                        sigma=None, terms: Sequence[str] | None = None, criterion: str = "aicc",
                        aicc_window: float = 4.0, n_folds: int = 5, max_terms: int = 2,
                        min_impacts: int = 8, min_speed_span: float = 0.05,
                        level: float = 0.95, outlier_z: float | None = 5.0,
                        min_effect: float = 0.0) -> ImpactLawResult:
    """Discover the restitution law r(v) of one wall from per-impact estimates.

    Parameters
    ----------
    v : array_like, shape (n,)
        Impact speeds |z'-| (m/s), >= 0; may pool several recordings.
    r : array_like, shape (n,)
        Restitution coefficient estimated at each impact.
    seed : int, optional
        Seed of ``numpy.random.default_rng`` (folds and bootstrap).
    n_bootstrap : int, optional
        Bootstrap resamples over impacts (0: no CIs, no band).
    groups : array_like, shape (n,), optional
        Recording of each impact: cross-validation folds then hold out whole
        recordings (pooled clearances cover different speed ranges).
    sigma : array_like, shape (n,), optional
        Standard error of each r (e.g. ``r_rel_error * r`` of the analysis impact
        table): the fits are then weighted by ``1 / sigma**2`` (a common scale
        factor does not matter). Low-speed impacts (chatter) have far noisier r
        than fast ones; unweighted fits let them fake a speed dependence. Values
        are floored at :data:`SIGMA_FLOOR` times their median; rows with a
        non-finite or non-positive sigma are dropped.
    terms : sequence of str, optional
        Registry names to use (default: all of :data:`IMPACT_TERMS`); ``"1"`` is
        always included.
    criterion : {"aicc", "cv"}, optional
        Selection rule: sparsest candidate within ``aicc_window`` of the best AICc,
        or sparsest within one standard error of the best CV error.
    aicc_window : float, optional
        Width of the AICc window of adequate candidates.
    n_folds : int, optional
        Number of cross-validation folds (at most the number of groups).
    max_terms : int, optional
        Largest support kept from the sparse-regression sweep. The default 2 is
        the size of the largest catalogue law (``r0 - a v``); over a pooled speed
        range of a few tenths of m/s, three nearly collinear columns fit sub-1e-3
        systematic errors of the r estimates with large cancelling coefficients.
    min_impacts : int, optional
        Below this many finite impacts, return the constant law with a warning.
    min_speed_span : float, optional
        Below this speed span (m/s), return the constant law with a warning.
    level : float, optional
        Confidence level of coefficient intervals and of the band.
    outlier_z : float or None, optional
        Before selection, drop impacts whose weighted residual from the full-library
        fit exceeds ``outlier_z`` robust standard deviations (1.4826 MAD), twice
        over; None keeps every impact. Chatter re-impacts next to a missed weak
        impact give gross r errors that no smooth law explains.
    min_effect : float, optional
        Practical tolerance on r (0: off). A sparser candidate whose fitted curve
        stays within ``min_effect`` of the best candidate's curve over the
        observed speeds (1st-99th percentile) is adequate even outside the AICc
        window. Simulated r estimates are precise to ~1e-4 and AICc then resolves
        differences far below the systematic errors of a real rig (the sensor
        resonance shifts r by ~5e-4); a ``min_effect`` of ~2e-3 stops such
        differences from deciding the form, at the price of merging forms whose
        curves differ by less than that over the observed speeds.

    Returns
    -------
    ImpactLawResult
        Selected law, coefficients with CIs, candidate table, comparison with a
        constant r, bootstrap band and selection frequencies.

    Raises
    ------
    InputError
        Non-numeric or mismatched inputs, negative speeds, bad options.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> v = rng.uniform(0.3, 1.3, 150)
    >>> res = discover_impact_law(v, 0.95 - 0.15 * v + rng.normal(0, 0.01, 150),
    ...                           n_bootstrap=50)
    >>> res.kind, res.terms
    ('linear', ('1', 'v'))
    """
    names = _check_options(seed, n_bootstrap, criterion, aicc_window, n_folds, max_terms,
                           min_impacts, min_speed_span, level, terms)
    if not (isinstance(min_effect, (int, float)) and not isinstance(min_effect, bool)
            and math.isfinite(min_effect) and min_effect >= 0):
        raise InputError(f"min_effect must be a number >= 0 (tolerance on r), "
                         f"was {min_effect!r}")
    if outlier_z is not None and not (isinstance(outlier_z, (int, float))
                                      and not isinstance(outlier_z, bool)
                                      and math.isfinite(outlier_z) and outlier_z > 0):
        raise InputError(f"outlier_z must be None or a number > 0 (robust standard "
                         f"deviations), was {outlier_z!r}")
    v, r = _as_1d("v", v), _as_1d("r", r)
    if v.size != r.size:
        raise InputError(f"v and r must have the same length, were {v.size} and {r.size}")
    sig = None
    if sigma is not None:
        sig = _as_1d("sigma", sigma)
        if sig.size != v.size:
            raise InputError(f"sigma must have one standard error per impact ({v.size}), "
                             f"had {sig.size}")
    g = None
    if groups is not None:
        g = np.asarray(groups)
        if g.ndim != 1 or g.size != v.size:
            raise InputError(f"groups must be 1-D with one label per impact ({v.size}), "
                             f"had shape {g.shape}")
    finite = np.isfinite(v) & np.isfinite(r)
    if sig is not None:
        finite &= np.isfinite(sig) & (sig > 0)
    neg = finite & (v < 0)
    if neg.any():
        raise InputError(f"v must be impact speeds >= 0 (m/s, |z'-|); found {int(neg.sum())} "
                         f"negative value(s), min {v[neg].min():.4g}")
    n_dropped = int((~finite).sum())
    v, r = v[finite], r[finite]
    g = None if g is None else g[finite]
    n = int(v.size)
    if sig is None or n == 0:
        sw = np.ones(n)
    else:
        sig = sig[finite]
        sw = 1.0 / np.maximum(sig, SIGMA_FLOOR * float(np.median(sig)))
    n_outliers = 0
    if outlier_z is not None and n >= max(min_impacts, len(names) + 3):
        keep = _inliers(_library(v, names), r, sw, float(outlier_z))
        n_outliers = int((~keep).sum())
        v, r, sw = v[keep], r[keep], sw[keep]
        g = None if g is None else g[keep]
        n = int(v.size)
    if n:
        sw = sw / float(np.sqrt(np.mean(sw ** 2)))
    rng = np.random.default_rng(seed)
    note = f" ({n_dropped} non-finite row(s) dropped)" if n_dropped else ""

    if n == 0:
        return _fallback(v, r, sw, n_dropped, n_outliers, rng, n_bootstrap, criterion, level,
                         f"no finite impacts{note}: restitution law undetermined")
    span = float(v.max() - v.min())
    if n < min_impacts:
        return _fallback(v, r, sw, n_dropped, n_outliers, rng, n_bootstrap, criterion, level,
                         f"only {n} impact(s) (< min_impacts={min_impacts}){note}: "
                         f"constant r reported, speed dependence not tested")
    if span < min_speed_span:
        return _fallback(v, r, sw, n_dropped, n_outliers, rng, n_bootstrap, criterion, level,
                         f"impact speeds span {span:.3g} m/s (< min_speed_span="
                         f"{min_speed_span} m/s){note}: constant r reported, "
                         f"speed dependence not identifiable")

    design = _Design(_library(v, names), names, sw)
    nested = _nested(names)
    swept = _sweep(design.theta, r, sw, names, max_terms)
    order = {nm: j for j, nm in enumerate(names)}
    cands = list(nested) + sorted(swept - set(nested),
                                  key=lambda c: (c.n_params, c.fixed_intercept,
                                                 [order[t] for t in c.terms]))
    source = ["nested+sweep" if c in swept else "nested" for c in nested] + \
        ["sweep"] * (len(cands) - len(nested))
    folds = _folds(n, n_folds, g, rng)

    grid = np.quantile(v, np.linspace(0.01, 0.99, 50))
    theta_grid = np.stack([IMPACT_TERMS[nm](grid) for nm in names], axis=1)

    def score(rows=None):
        m = n if rows is None else len(rows)
        fits = [design.fit(c, r, rows) for c in cands]
        rss = np.array([f[1] for f in fits])
        aicc = np.array([_aicc(s, m, c.n_params) for s, c in zip(rss, cands, strict=True)])
        if criterion == "cv" or rows is None:
            cvs = np.array([design.cv(c, r, folds, rows) for c in cands])
        else:
            cvs = np.full((len(cands), 3), np.nan)
        curves = None
        if min_effect > 0:
            curves = np.array([theta_grid[:, [design.col[t] for t in c.r_terms]] @ f[0]
                               for c, f in zip(cands, fits, strict=True)])
        return rss, aicc, cvs, curves

    rss, aicc, cvs, curves = score()
    tiers = np.array([_tier(c, frozenset(nested)) for c in cands])
    best = _select(cands, tiers, aicc, cvs[:, 1], cvs[:, 2], criterion, aicc_window,
                   curves, min_effect)
    chosen = cands[best]
    coef, _ = design.fit(chosen, r)

    boot = np.empty((n_bootstrap, len(chosen.r_terms)))
    picks = np.zeros(len(cands))
    for b in range(n_bootstrap):
        rows = rng.integers(0, n, n)
        boot[b] = design.fit(chosen, r, rows)[0]
        _, a_b, c_b, k_b = score(rows)
        picks[_select(cands, tiers, a_b, c_b[:, 1], c_b[:, 2], criterion,
                      aicc_window, k_b, min_effect)] += 1
    freq = picks / n_bootstrap if n_bootstrap else np.full(len(cands), np.nan)

    # comparison with a constant r
    const_idx = 0  # nested[0] is the constant
    dep = [i for i, c in enumerate(cands) if c.velocity_dependent and np.isfinite(aicc[i])]
    alt_idx = best if chosen.velocity_dependent else \
        (min(dep, key=lambda i: aicc[i]) if dep else None)
    if alt_idx is None:
        delta, p_value, alt_name = math.nan, math.nan, ""
    else:
        alt = cands[alt_idx]
        delta = float(aicc[const_idx] - aicc[alt_idx])
        p_value = _f_test(design, r, alt, rss[const_idx])
        alt_name = alt.name

    import pandas as pd

    table = pd.DataFrame({
        "name": [c.name for c in cands], "n_params": [c.n_params for c in cands],
        "rss": rss, "aicc": aicc, "delta_aicc": aicc - np.min(aicc), "cv_rmse": cvs[:, 0],
        "source": source, "selected": np.arange(len(cands)) == best,
        "bootstrap_frequency": freq})
    law = _to_law(chosen, coef)
    kind = "generic" if law is None else law.kind
    formula = _generic_formula(chosen.r_terms, coef) if law is None else law.formula
    ci = _percentile_ci(boot, level)
    order_f = np.argsort(-picks, kind="stable")
    sel_freq = {cands[i].name: float(freq[i]) for i in order_f if picks[i] > 0}
    fitted = design.theta[:, [design.col[t] for t in chosen.r_terms]] @ coef
    return ImpactLawResult(
        formula=formula, kind=kind, law=law, terms=chosen.r_terms,
        coefficients={t: float(c) for t, c in zip(chosen.r_terms, coef, strict=True)},
        ci={t: (float(ci[0, j]), float(ci[1, j])) for j, t in enumerate(chosen.r_terms)},
        fixed_intercept=chosen.fixed_intercept, candidates=table,
        delta_aicc_vs_constant=delta, p_value_vs_constant=p_value, alternative=alt_name,
        speed_range=(float(v.min()), float(v.max())), n=n, n_dropped=n_dropped,
        n_outliers=n_outliers, sigma=float(np.sqrt(np.mean((r - fitted) ** 2))),
        support_frequency=float(freq[best]),
        selection_frequency=sel_freq, criterion=criterion, level=float(level),
        warning=None, boot_coefficients=boot)


def _f_test(design: _Design, r: np.ndarray, alt: _Candidate, rss0: float) -> float:
    """p-value of r = r0 against r0 + sum c_k f_k(v) over ``alt``'s non-constant terms."""
    from scipy import stats

    extra = tuple(t for t in alt.terms if t != CONSTANT_TERM)
    full = _Candidate((CONSTANT_TERM,) + extra, False)
    _, rss1 = design.fit(full, r)
    n, k1 = r.size, full.n_params
    dof = n - k1
    if dof <= 0 or not extra:
        return math.nan
    if rss1 <= 0:
        return 0.0
    f_stat = max((rss0 - rss1) / len(extra), 0.0) / (rss1 / dof)
    return float(stats.f.sf(f_stat, len(extra), dof))


def _fallback(v: np.ndarray, r: np.ndarray, sw: np.ndarray, n_dropped: int, n_outliers: int,
              rng: np.random.Generator,
              n_bootstrap: int, criterion: str, level: float, warning: str) -> ImpactLawResult:
    """Constant law (weighted mean r) with a bootstrap CI, or nothing without impacts."""
    import pandas as pd

    n = int(r.size)
    columns = ["name", "n_params", "rss", "aicc", "delta_aicc", "cv_rmse", "source",
               "selected", "bootstrap_frequency"]
    if n == 0:
        return ImpactLawResult(
            formula="r undetermined (no impacts)", kind="undetermined", law=None, terms=(),
            coefficients={}, ci={}, fixed_intercept=False,
            candidates=pd.DataFrame(columns=columns), delta_aicc_vs_constant=math.nan,
            p_value_vs_constant=math.nan, alternative="", speed_range=(math.nan, math.nan),
            n=0, n_dropped=n_dropped, n_outliers=n_outliers, sigma=math.nan,
            support_frequency=math.nan,
            selection_frequency={}, criterion=criterion, level=float(level),
            warning=warning, boot_coefficients=np.empty((0, 0)))
    w = sw ** 2

    def wmean(rows):
        return float(np.sum(w[rows] * r[rows]) / np.sum(w[rows]))

    r0 = wmean(np.arange(n))
    boot = np.array([[wmean(rng.integers(0, n, n))] for _ in range(n_bootstrap)])
    boot = boot.reshape(n_bootstrap, 1)
    ci = _percentile_ci(boot, level)
    rss = float(np.sum(w * (r - r0) ** 2))
    try:
        law = RestitutionLaw.constant(r0)
    except InputError:
        law = None
    table = pd.DataFrame([["r ~ 1", 1, rss, _aicc(rss, n, 1), 0.0, math.nan, "nested", True,
                           math.nan]], columns=columns)
    return ImpactLawResult(
        formula=law.formula if law else _generic_formula((CONSTANT_TERM,), [r0]),
        kind="constant" if law else "generic", law=law, terms=(CONSTANT_TERM,),
        coefficients={CONSTANT_TERM: r0}, ci={CONSTANT_TERM: (float(ci[0, 0]), float(ci[1, 0]))},
        fixed_intercept=False, candidates=table, delta_aicc_vs_constant=math.nan,
        p_value_vs_constant=math.nan, alternative="",
        speed_range=(float(v.min()), float(v.max())), n=n, n_dropped=n_dropped,
        n_outliers=n_outliers, sigma=float(np.sqrt(np.mean((r - r0) ** 2))),
        support_frequency=math.nan, selection_frequency={},
        criterion=criterion, level=float(level), warning=warning, boot_coefficients=boot)
