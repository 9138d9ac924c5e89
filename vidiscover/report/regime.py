"""Regime label of an analysis from the regime classifier, when one is available."""

from __future__ import annotations

__all__ = ["attach_regime", "default_regime_model"]


def default_regime_model():
    """The regime model shipped with vidiscover, or None when none is installed."""
    from importlib import resources

    from ..regimes.classifier import DEFAULT_MODEL, load_default_model

    if not (resources.files("vidiscover") / "data" / DEFAULT_MODEL).is_file():
        return None
    return load_default_model()


def attach_regime(result, model):
    """Label the regime of an analysis with a classifier.

    Parameters
    ----------
    result : AnalysisResult
    model : RegimeModel or None
        Anything with ``classify_analysis(result)`` returning an object with
        ``label``, ``proba`` and ``warnings``; None leaves the result unlabelled.

    Returns
    -------
    result : AnalysisResult
        A copy with ``regime_label`` set and the classifier's out-of-domain warnings
        appended (``result`` itself when ``model`` is None).
    regime : dict or None
        ``{"proba": ..., "source": "classifier"}`` for ``summary.json``.
    """
    import dataclasses

    if model is None:
        return result, None
    from ..regimes.classifier import warning_text

    c = model.classify_analysis(result)
    warnings = tuple(result.warnings) + tuple(
        f"regime classifier: {warning_text(w)}" for w in c.warnings)
    result = dataclasses.replace(result, regime_label=str(c.label), warnings=warnings)
    return result, {"proba": dict(c.proba), "source": "classifier"}
