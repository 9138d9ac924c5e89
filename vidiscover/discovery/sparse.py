"""The sparse-selection kernel shared by the flight-law and the impact-law discovery.

Both laws are found the same way: a library of candidate functions of one variable
(the relative velocity z' between impacts, the impact speed v at the walls) is
evaluated by a pysindy ``CustomLibrary`` (:func:`library_matrix`); a pysindy
threshold sweep proposes supports (:func:`threshold_sweep`); every candidate
support is refitted by least squares and scored by one information criterion
(:func:`aicc`); whole units (tents, impacts) are resampled to give intervals and the
share of resamples keeping each term (:func:`bootstrap_rows`, :func:`inclusion`,
:func:`percentile_interval`).

pysindy's ``EnsembleOptimizer`` bags rows with the global numpy RNG and refits one
optimizer per bag; here each resample re-runs the whole *selection* (sweep
candidates, refit, AICc) on resampled units with a seeded generator, which is what
the inclusion probabilities must reflect, so the resampling is done by hand.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence

import numpy as np

__all__ = ["aicc", "library_matrix", "threshold_sweep", "bootstrap_rows", "inclusion",
           "percentile_interval"]


def aicc(rss: float, n: int, n_coef: int) -> float:
    """Corrected Akaike criterion of a least-squares fit with Gaussian errors.

    ``n log(RSS / n) + 2 k + 2 k (k + 1) / (n - k - 1)`` with ``k = n_coef + 1``
    (the coefficients and the noise variance); ``inf`` when ``n <= k + 1``.

    Parameters
    ----------
    rss : float
        Residual sum of squares (weighted, when the fit is).
    n : int
        Number of rows.
    n_coef : int
        Number of fitted coefficients.

    Returns
    -------
    float
    """
    k = int(n_coef) + 1
    if n - k - 1 <= 0:
        return math.inf
    return n * math.log(max(float(rss), 1e-300) / n) + 2 * k + 2 * k * (k + 1) / (n - k - 1)


def _one_arg(f: Callable) -> Callable:
    """A one-argument wrapper (pysindy reads the arity from ``__code__``)."""
    def g(x):
        return f(x)
    return g


def library_matrix(x: np.ndarray, names: Sequence[str],
                   funcs: Mapping[str, Callable[[np.ndarray], np.ndarray]],
                   variable: str = "v") -> np.ndarray:
    """Feature matrix of named functions of one variable, built by a pysindy CustomLibrary.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Values of the variable.
    names : sequence of str
        Names of the candidate functions, in column order; each name is written
        in ``variable`` (e.g. ``"v^0.5"``, ``"sgn(z')"``).
    funcs : Mapping
        ``name -> f(x)``.
    variable : str
        Name of the variable inside ``names``.

    Returns
    -------
    ndarray, shape (n, len(names))
    """
    import pysindy as ps

    lib = ps.CustomLibrary(
        library_functions=[_one_arg(funcs[nm]) for nm in names],
        function_names=[_one_arg(lambda s, nm=nm: nm.replace(variable, s)) for nm in names],
        include_bias=False)
    theta = np.asarray(lib.fit_transform(np.asarray(x, float).reshape(-1, 1)), dtype=float)
    got = lib.get_feature_names([variable])
    if list(got) != list(names):  # pragma: no cover - guards a pysindy API change
        raise RuntimeError(f"pysindy library columns {got} differ from terms {list(names)}")
    return theta


def threshold_sweep(X: np.ndarray, y: np.ndarray, thresholds: Sequence[float], *,
                    sr3_thresholds: Sequence[float] = ()) -> set[tuple[int, ...]]:
    """Supports visited by pysindy ``STLSQ`` (and ``SR3``-L0) threshold sweeps.

    Parameters
    ----------
    X : ndarray, shape (n, J)
        Scaled feature matrix (the caller chooses the column scaling that makes the
        thresholds meaningful).
    y : ndarray, shape (n,)
        Target.
    thresholds : sequence of float
        STLSQ thresholds (on the scaled coefficients).
    sr3_thresholds : sequence of float, optional
        SR3-L0 thresholds (``reg_weight_lam = thr**2 / 2``).

    Returns
    -------
    set of tuple of int
        Column indices kept at each sweep point (a failed point proposes nothing).
    """
    import pysindy as ps

    opts = [ps.STLSQ(threshold=float(t), alpha=1e-10, max_iter=50, normalize_columns=False)
            for t in thresholds]
    zero = np.zeros((1, X.shape[1]))
    opts += [ps.SR3(reg_weight_lam=float(t) ** 2 / 2, regularizer="L0", relax_coeff_nu=1.0,
                    max_iter=100, unbias=True, initial_guess=zero) for t in sr3_thresholds]
    out: set[tuple[int, ...]] = set()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for opt in opts:
            try:
                opt.fit(X, y)
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                continue
            out.add(tuple(np.flatnonzero(np.ravel(opt.coef_) != 0).tolist()))
    return out


def bootstrap_rows(n: int, n_boot: int, seed: int | np.random.Generator) -> Iterator[np.ndarray]:
    """Resampled row indices (with replacement), ``n_boot`` times.

    Parameters
    ----------
    n : int
        Number of units (rows, tents, impacts).
    n_boot : int
        Number of resamples.
    seed : int or numpy.random.Generator
        Seed of ``numpy.random.default_rng`` (or a generator to draw from).

    Yields
    ------
    ndarray of int, shape (n,)
    """
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    for _ in range(int(n_boot)):
        yield rng.integers(0, n, n)


def inclusion(coefs: np.ndarray, names: Sequence[str]) -> dict[str, float]:
    """Share of resamples keeping each term (a non-zero coefficient).

    Parameters
    ----------
    coefs : ndarray, shape (n_boot, len(names))
    names : sequence of str

    Returns
    -------
    dict
        ``name -> share`` (empty without resamples).
    """
    coefs = np.asarray(coefs, float)
    if coefs.shape[0] == 0:
        return {}
    return {nm: float(np.mean(coefs[:, j] != 0)) for j, nm in enumerate(names)}


def percentile_interval(samples: np.ndarray, level: float) -> np.ndarray:
    """Central percentile interval of ``samples`` along axis 0 (NaN when empty).

    Parameters
    ----------
    samples : ndarray, shape (n_boot, ...)
    level : float
        Coverage in (0, 1).

    Returns
    -------
    ndarray, shape (2, ...)
        Lower and upper bounds.
    """
    samples = np.asarray(samples, float)
    if samples.shape[0] == 0:
        return np.full((2,) + samples.shape[1:], np.nan)
    q = 50.0 * (1.0 - level)
    return np.percentile(samples, [q, 100.0 - q], axis=0)
