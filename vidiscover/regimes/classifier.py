"""Regime classifier: labels a recording from sensor data alone.

* :class:`RegimeClassifier` -- a scikit-learn estimator: histogram gradient boosting
  (balanced class weights, NaN-aware) whose class probabilities are calibrated by
  :class:`~sklearn.calibration.CalibratedClassifierCV`; it also remembers the range
  of every training feature (the training domain).
* :class:`RuleBaseline` -- the the README's 'Regime labels' rules applied to the detected
  features, a transparent baseline to compare with.
* :class:`RegimeModel` -- a fitted classifier with its feature names, the parameter
  ranges of its training sweep and its training metadata; :meth:`RegimeModel.classify`
  labels a recording and warns when it lies outside the training domain.
* :func:`train` / :func:`evaluate` -- simulate a sweep (:mod:`.dataset`), fit,
  and score on a held-out set simulated with other seeds and parameter draws.
* :func:`save_model` / :func:`load_model` -- skops files, loaded only with an
  explicit list of trusted types (:data:`TRUSTED_TYPES`), never as a pickle;
  :func:`load_default_model` loads the model shipped in ``vidiscover/data``.
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import ClassVar

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from threadpoolctl import threadpool_limits

from ..errors import InputError
from .labels import LABELS

__all__ = ["RegimeClassifier", "RuleBaseline", "RegimeModel", "Classification", "REFUSED",
           "model_features", "train", "evaluate", "save_model", "load_model",
           "load_default_model", "TRUSTED_TYPES", "DEFAULT_MODEL", "DEFAULT_SEED",
           "choose_rule_labels", "choose_rule_gate",
           "DEFAULT_N_TRAIN", "DEFAULT_N_TEST", "format_report", "fit_model"]

#: Registered features not used by the model (``n_impacts`` grows with the record
#: length; the per-cycle features carry the same information; the rules alone read
#: ``saturated_cycle_share``, which the shipped model was not trained with).
EXCLUDED_FEATURES: tuple[str, ...] = ("n_impacts", "saturated_cycle_share")

#: The label of a recording that is not classified: too few impacts were counted to
#: tell an impacting motion, and a channel is saturated on too many cycles for
#: ``no_impact`` to be claimed (:meth:`RuleBaseline.refused`). Not a regime: never a
#: truth, never trained on; it counts as wrong in every score.
REFUSED = "not_classified"
#: The rules' ``no_impact`` bound (impacts per cycle below it) that the cycles where
#: impacts cannot be counted must not be able to reach (:meth:`RuleBaseline.refused`).
NO_IMPACT_IPC = 0.05

#: The shipped model's file name, and the defaults of :func:`train` (a paper-rig set
#: only). The shipped model comes out of ``vidiscover train --seed 0 --n 1200 --n-test
#: 300 --n-realism 600 --n-corpus-train 192 --n-corpus-test 0`` (the command is kept in
#: its report, ``regime_model.json``).
DEFAULT_MODEL = "regime_model.skops"
DEFAULT_SEED, DEFAULT_N_TRAIN, DEFAULT_N_TEST, DEFAULT_N_REALISM = 0, 2500, 800, 0
#: Seed offset of the held-out test set (other seeds and draws than training).
TEST_SEED_OFFSET = 100_003

#: Types a regime-model file may contain; :func:`load_model` refuses anything else.
TRUSTED_TYPES: tuple[str, ...] = (
    "vidiscover.regimes.classifier.RegimeClassifier",
    "sklearn.calibration.CalibratedClassifierCV",
    "sklearn.calibration._CalibratedClassifier",
    "sklearn.calibration._SigmoidCalibration",
    "sklearn.isotonic.IsotonicRegression",
    "sklearn.ensemble._hist_gradient_boosting.gradient_boosting."
    "HistGradientBoostingClassifier",
    "sklearn.ensemble._hist_gradient_boosting.predictor.TreePredictor",
    "sklearn.ensemble._hist_gradient_boosting.binning._BinMapper",
    "sklearn._loss.loss.HalfMultinomialLoss",
    "sklearn._loss.link.MultinomialLogit",
    "sklearn._loss.link.Interval",
    "sklearn._loss._loss.CyHalfMultinomialLoss",
    "sklearn.model_selection._split.StratifiedKFold",
    "sklearn.utils._bunch.Bunch",
    "builtins.bool_", "numpy.dtype",
)


def model_features() -> list[str]:
    """Names of the features the model uses: the analysis's and the regime features.

    Taken from the explicit set :data:`vidiscover.regimes.features.ALL_FEATURES`, the
    set every training and classifying analysis computes.
    """
    from .features import ALL_FEATURES

    return [n for n in ALL_FEATURES if n not in EXCLUDED_FEATURES]


# --------------------------------------------------------------------------- estimator
class RegimeClassifier(ClassifierMixin, BaseEstimator):
    """Gradient-boosted trees with calibrated class probabilities.

    Parameters
    ----------
    max_iter : int
        Boosting iterations (trees per class).
    learning_rate : float
        Shrinkage of each tree.
    max_leaf_nodes : int
        Leaves per tree.
    min_samples_leaf : int
        Smallest leaf (small, so that rare regimes get leaves of their own).
    calibration : {"isotonic", "sigmoid", None}
        Probability calibration (cross-validated); None keeps the raw scores.
    cv : int
        Folds of the calibration (reduced to the smallest class count if needed;
        calibration is skipped when a class has a single sample).
    random_state : int
        Seed of the trees and of the calibration folds.

    Attributes
    ----------
    classes_ : ndarray
        Labels seen in ``fit``.
    model_ : estimator
        The fitted (calibrated) model.
    n_iter_ : int
        Boosting iterations run (``max_iter``: no early stopping).
    feature_low_, feature_high_ : ndarray
        Per-feature minimum and maximum over the training rows (NaN ignored).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(60, 2)); y = np.where(X[:, 0] > 0, "a", "b")
    >>> clf = RegimeClassifier(max_iter=20).fit(X, y)
    >>> float((clf.predict(X) == y).mean()) > 0.9
    True
    """

    def __init__(self, max_iter: int = 150, learning_rate: float = 0.1,
                 max_leaf_nodes: int = 8, min_samples_leaf: int = 5,
                 calibration: str | None = "isotonic", cv: int = 3, random_state: int = 0):
        self.max_iter = max_iter
        self.learning_rate = learning_rate
        self.max_leaf_nodes = max_leaf_nodes
        self.min_samples_leaf = min_samples_leaf
        self.calibration = calibration
        self.cv = cv
        self.random_state = random_state

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = True
        return tags

    def fit(self, X, y):
        """Fit on features ``X`` (n_samples, n_features; NaN allowed) and labels ``y``.

        Returns
        -------
        self
        """
        from sklearn.calibration import CalibratedClassifierCV
        from sklearn.ensemble import HistGradientBoostingClassifier
        from sklearn.model_selection import StratifiedKFold

        if self.calibration not in ("isotonic", "sigmoid", None):
            raise ValueError("calibration must be 'isotonic', 'sigmoid' or None, "
                             f"was {self.calibration!r}")
        if not (isinstance(self.cv, (int, np.integer)) and self.cv >= 2):
            raise ValueError(f"cv must be an integer >= 2, was {self.cv!r}")
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan")
        check_classification_targets(y)
        self.classes_, y_idx, counts = np.unique(y, return_inverse=True, return_counts=True)
        if self.classes_.size < 2:
            raise ValueError(f"RegimeClassifier needs at least 2 classes in y, got "
                             f"{self.classes_.size} class")
        trees = HistGradientBoostingClassifier(
            max_iter=self.max_iter, learning_rate=self.learning_rate,
            max_leaf_nodes=self.max_leaf_nodes, min_samples_leaf=self.min_samples_leaf,
            class_weight="balanced",
            early_stopping=False, random_state=self.random_state)
        folds = int(min(self.cv, counts.min()))
        if self.calibration is not None and folds >= 2:
            model = CalibratedClassifierCV(
                trees, method=self.calibration, ensemble=False,
                cv=StratifiedKFold(folds, shuffle=True, random_state=self.random_state))
        else:
            model = trees
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=UserWarning)
            self.model_ = model.fit(X, y_idx)
        self.n_iter_ = int(self.max_iter)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)   # all-NaN columns
            self.feature_low_ = np.nanmin(np.where(np.isfinite(X), X, np.nan), axis=0)
            self.feature_high_ = np.nanmax(np.where(np.isfinite(X), X, np.nan), axis=0)
        return self

    def predict_proba(self, X) -> np.ndarray:
        """Calibrated class probabilities, columns in the order of ``classes_``."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        proba = np.zeros((X.shape[0], self.classes_.size))
        # OpenMP threads only slow the prediction of a few rows down (and spin on a
        # busy machine): predict on one thread.
        with threadpool_limits(limits=1, user_api="openmp"):
            proba[:, self.model_.classes_] = self.model_.predict_proba(X)
        return proba

    def predict(self, X) -> np.ndarray:
        """Most probable label of each row."""
        check_is_fitted(self)
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]

    def outside_domain(self, X, margin: float = 0.1) -> list[list[int]]:
        """Indices of the features of each row outside the training domain.

        The domain of a feature is its training range widened by ``margin`` of its
        width on both sides.
        """
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        width = np.nan_to_num(self.feature_high_ - self.feature_low_)
        lo = self.feature_low_ - margin * width
        hi = self.feature_high_ + margin * width
        with np.errstate(invalid="ignore"):
            bad = (X < lo) | (X > hi)
        return [list(np.flatnonzero(row)) for row in bad]


# --------------------------------------------------------------------------- baseline
@dataclass(frozen=True)
class RuleBaseline:
    """The label rules of the README's 'Regime labels' applied to the *detected* features.

    ``impacts_per_cycle`` < 0.05 -> ``no_impact``, unless the accelerometer is
    saturated on so many cycles (``saturated_cycle_share``) that impacts hidden there,
    one per saturated cycle, would reach 0.05: then :data:`REFUSED` (:meth:`refused`);
    ``impacting_cycle_share`` < 0.9 and
    ``envelope_modulation`` >= 0.15 -> ``smr``; otherwise, when the share is >= 0.9
    and the response is periodic (``strobe_state_error``, the labels' test on the
    stroboscopic LO state x and x', <= ``periodic_tol``; ``strobe_period_error``, x
    alone, where the state's is undefined):
    ``one_per_cycle_share`` >= 0.9 -> ``1ipc``; ``two_per_cycle_share`` >= 0.9 and
    ``alternation`` >= 0.9 -> ``2ipc_asym`` if ``asymmetry`` >= 0.1 else
    ``2ipc_sym``; the same when the *strong* impacts (``strong_two_share``,
    ``strong_alternation``) say so and repeat (``impact_period_error`` <=
    ``repeat_tol``): weak detections a few hundredths of a period after a strong
    impact on the same wall (a long compliant contact split in pulses, a ringing
    chain's lobe) are not impacts of their own; else ``multi_ipc``. A periodic
    response with a share below 0.9 is ``multi_ipc`` too when the strong impacts
    repeat (``impact_period_error`` <= ``repeat_tol`` periods; the labels'
    :func:`~vidiscover.regimes.labels.impacts_repeat`).
    Everything else is ``chaotic``.

    The impacts counted are those the labels count: the rules read the *merged*
    features (:data:`MERGED`, :data:`~vidiscover.regimes.features.MERGED_FEATURES`:
    a detection on the same wall less than
    :data:`~vidiscover.regimes.labels.RETURN_TAU` periods after the one before is part
    of that impact) in place of the plain ones named above; of a table without a
    merged column (computed before they existed), the plain one.

    Parameters
    ----------
    periodic_tol : float
        Largest stroboscopic change (relative to max |x|) that counts as periodic.
    repeat_tol : float
        Largest ``impact_period_error`` (periods) at which the impacts repeat.
    """

    periodic_tol: float = 0.01
    repeat_tol: float = 0.01
    #: Features the rules read.
    FEATURES: ClassVar[tuple[str, ...]] = (
        "impacts_per_cycle", "impacting_cycle_share", "envelope_modulation",
        "strobe_period_error", "one_per_cycle_share", "two_per_cycle_share", "alternation",
        "asymmetry", "impact_period_error", "strong_two_share", "strong_alternation",
        "strobe_state_error", "merged_per_cycle", "merged_cycle_share", "merged_one_share",
        "merged_two_share", "merged_alternation", "merged_asymmetry",
        "saturated_cycle_share")
    #: The merged feature the rules read in place of a plain one (when the table has it).
    MERGED: ClassVar[dict[str, str]] = {
        "impacts_per_cycle": "merged_per_cycle", "impacting_cycle_share": "merged_cycle_share",
        "one_per_cycle_share": "merged_one_share", "two_per_cycle_share": "merged_two_share",
        "alternation": "merged_alternation", "asymmetry": "merged_asymmetry"}

    def predict(self, features: pd.DataFrame) -> np.ndarray:
        """Label every row of a DataFrame of features (columns named as in ALL_FEATURES).

        A missing column is NaN, which no rule reads as met; a missing merged column
        (:data:`MERGED`) is its plain one.
        """
        f = {k: (features[k].to_numpy(float) if k in features
                 else np.full(len(features), np.nan)) for k in self.FEATURES}
        for plain, merged in self.MERGED.items():
            if merged in features:
                f[plain] = f[merged]
        with np.errstate(invalid="ignore"):
            ipc = np.nan_to_num(f["impacts_per_cycle"])
            phi = np.nan_to_num(f["impacting_cycle_share"])
            # the labels test x and x' (weakly irregular motions of other rigs repeat
            # within 1 % in x and not in x': tuning sets 18001 / 18003, other rigs,
            # 12 / 13 chaotic truths the rules called multi_ipc)
            state = f["strobe_state_error"]
            periodic = np.where(np.isfinite(state), state,
                                f["strobe_period_error"]) <= self.periodic_tol
            one = f["one_per_cycle_share"] >= 0.9
            repeat = f["impact_period_error"] <= self.repeat_tol
            two = (((f["two_per_cycle_share"] >= 0.9) & (f["alternation"] >= 0.9))
                   | ((f["strong_two_share"] >= 0.9) & (f["strong_alternation"] >= 0.9)
                      & repeat))
            asym = np.nan_to_num(f["asymmetry"]) >= 0.1
            low = ipc < NO_IMPACT_IPC
            hidden = self._hidden(ipc, f["saturated_cycle_share"])
            out = np.select(
                [low & ~hidden, low, (phi < 0.9) & (f["envelope_modulation"] >= 0.15),
                 (phi >= 0.9) & periodic & one, (phi >= 0.9) & periodic & two & asym,
                 (phi >= 0.9) & periodic & two, ((phi >= 0.9) | repeat) & periodic],
                ["no_impact", REFUSED, "smr", "1ipc", "2ipc_asym", "2ipc_sym", "multi_ipc"],
                "chaotic")
        return out.astype(object)

    @staticmethod
    def _hidden(ipc: np.ndarray, saturated: np.ndarray) -> np.ndarray:
        """Whether impacts hidden on the saturated cycles could reach the bound.

        A saturated cycle (the accelerometer on its rail for longer than a pulse)
        may hold an impact the detector cannot count: with one there per saturated
        cycle, ``ipc + saturated`` would be the rate, and ``no_impact`` stands only
        while that stays below :data:`NO_IMPACT_IPC` (NaN: nothing known, 0).
        """
        return np.nan_to_num(ipc) + np.nan_to_num(saturated) >= NO_IMPACT_IPC

    def refused(self, features: pd.DataFrame) -> np.ndarray:
        """Rows on which ``no_impact`` may not be claimed (the accelerometer saturated).

        Where fewer than :data:`NO_IMPACT_IPC` impacts per cycle were counted but
        the saturated cycles could hide enough to reach it: neither the rules nor
        the classifier (which reads the same missing impacts) may then call the
        recording ``no_impact``; :meth:`RegimeModel.decide` labels it
        :data:`REFUSED`.
        """
        frame = _rule_frame(features)
        ipc = frame[self.MERGED["impacts_per_cycle"]] if (
            self.MERGED["impacts_per_cycle"] in frame) else frame["impacts_per_cycle"]
        ipc = np.nan_to_num(ipc.to_numpy(float))
        sat = frame["saturated_cycle_share"].to_numpy(float)
        return (ipc < NO_IMPACT_IPC) & self._hidden(ipc, sat)


# --------------------------------------------------------------------------- model
@dataclass(frozen=True)
class Classification:
    """Label of one recording.

    Attributes
    ----------
    file : str
        Recording name or path.
    label : str
        Most probable regime.
    proba : dict
        Probability of every label of :data:`LABELS` (0 for labels never trained):
        the classifier's calibrated probabilities, or, when the rules gave the label,
        the share of each true label among the training recordings to which the
        rules gave it (out of fold; :attr:`RegimeModel.rule_proba`).
    warnings : tuple of str
        Why the recording may lie outside the training domain.
    features : dict
        The features the label was computed from.
    method : str
        Which method labelled the recording: ``"classifier"`` or ``"rules"`` (the
        rule baseline, kept for the labels where it beats the classifier; see
        :attr:`RegimeModel.rule_labels`).
    """

    file: str
    label: str
    proba: dict
    warnings: tuple = ()
    features: dict = field(default_factory=dict, repr=False)
    method: str = "classifier"

    def to_dict(self) -> dict:
        """``{file, label, method, proba, warnings}`` (JSON-ready)."""
        return {"file": self.file, "label": self.label, "method": self.method,
                "proba": dict(self.proba), "warnings": list(self.warnings)}


@dataclass(frozen=True, eq=False)
class RegimeModel:
    """A fitted :class:`RegimeClassifier` with what is needed to use it honestly.

    Attributes
    ----------
    classifier : RegimeClassifier
    feature_names : tuple of str
        Feature columns, in the classifier's order.
    param_ranges : dict
        Rig ranges of the training sweep (name -> (low, high)): ``mass_ratio``
        (m2 / m1), ``drive_ratio`` (forcing over natural frequency),
        ``record_periods`` (record length in forcing periods) and ``b`` (m).
    metadata : dict
        Training settings and scores.
    rule_inputs : bool
        Give the classifier the rule baseline's label (one-hot) as extra inputs
        besides the features (off: the classifier learns from the features alone,
        so that it can be compared with the rules; kept for old model files).
    rule_labels : tuple of str
        Labels the rule baseline keeps: when the rules name one of them, that is
        the label (``method`` "rules"); every other recording gets the classifier's
        label. Chosen in training where the rules' label was right more often than
        the classifier's on the recordings the rules gave it (out-of-fold).
    rule_min_proba : dict
        For a label of :attr:`rule_labels`, the smallest probability the classifier
        must give that label for the rules' label to be kept (missing: 0, the rules'
        label is always kept): the rules stand unless the classifier is confident
        of another label (:func:`choose_rule_gate`).
    rule_proba : dict
        For each of :attr:`rule_labels`, the share of every true label among the
        training recordings the rules gave it: the probabilities reported with it.
    """

    classifier: RegimeClassifier
    feature_names: tuple
    param_ranges: Mapping = field(default_factory=dict)
    metadata: Mapping = field(default_factory=dict)
    rule_inputs: bool = False
    rule_labels: tuple = ()
    rule_proba: Mapping = field(default_factory=dict)
    rule_min_proba: Mapping = field(default_factory=dict)

    def matrix(self, features) -> np.ndarray:
        """Feature matrix of a DataFrame or of a list of feature dicts.

        Columns are found as ``NAME`` or ``feature:NAME``; missing ones are NaN.
        """
        if not isinstance(features, pd.DataFrame):
            features = pd.DataFrame(list(features))
        names = list(self.feature_names)
        if self.rule_inputs:
            names += [n for n in RuleBaseline.FEATURES if n not in names]
        cols = {}
        for n in names:
            key = n if n in features else f"feature:{n}"
            cols[n] = (features[key].to_numpy(float) if key in features
                       else np.full(len(features), np.nan))
        x = [cols[n] for n in self.feature_names]
        if self.rule_inputs:
            rule = RuleBaseline().predict(_rule_frame(features))
            x += [(rule == lab).astype(float) for lab in LABELS]
        return np.column_stack(x) if x else np.zeros((len(features), 0))

    @property
    def column_names(self) -> list[str]:
        """Names of the columns of :meth:`matrix`."""
        extra = [f"rule:{lab}" for lab in LABELS] if self.rule_inputs else []
        return list(self.feature_names) + extra

    def predict(self, features) -> np.ndarray:
        """The classifier's labels of a DataFrame / list of feature dicts."""
        return self.classifier.predict(self.matrix(features))

    def decide(self, features, clf=None, proba=None) -> tuple[np.ndarray, np.ndarray]:
        """Labels as :meth:`classify` gives them, and the method of each.

        The rule baseline's label where it is one of :attr:`rule_labels` and the
        classifier gives it at least its :attr:`rule_min_proba`, the classifier's
        elsewhere (``clf``, ``proba``: its labels and :meth:`predict_proba` when
        already computed). A ``no_impact`` either gives where a channel is saturated
        on too many cycles (:meth:`RuleBaseline.refused`) becomes :data:`REFUSED`
        (method ``"refused"``): it would rest on impacts that could not be counted.
        """
        gated = any(v > 0 for v in self.rule_min_proba.values())
        if gated and proba is None:
            proba = self.predict_proba(features)
        if clf is None:
            clf = (_top_labels(self.classifier, proba) if proba is not None
                   else self.predict(features))
        clf = np.asarray(clf, dtype=object)
        rules = RuleBaseline().predict(_rule_frame(features))
        keep = np.isin(rules, list(self.rule_labels))
        if gated:
            p = np.asarray(proba, float)
            cols = list(proba.columns)
            least = np.array([float(self.rule_min_proba.get(r, 0.0)) for r in rules])
            have = np.array([p[i, cols.index(r)] if r in cols else 0.0
                             for i, r in enumerate(rules)])
            keep &= have >= least
        labels = np.where(keep, rules, clf).astype(object)
        methods = np.where(keep, "rules", "classifier").astype(object)
        refuse = (labels == "no_impact") & RuleBaseline().refused(features)
        labels[refuse] = REFUSED
        methods[refuse] = "refused"
        return labels, methods

    def predict_proba(self, features) -> pd.DataFrame:
        """Probabilities of every label of :data:`LABELS`, one row per case."""
        p = self.classifier.predict_proba(self.matrix(features))
        out = pd.DataFrame(0.0, index=range(p.shape[0]), columns=list(LABELS))
        for j, lab in enumerate(self.classifier.classes_):
            out[str(lab)] = p[:, j]
        return out

    def domain_warnings(self, features: Mapping, meta=None, duration: float | None = None
                        ) -> list[str]:
        """Reasons why a recording lies outside the training domain (empty if none)."""
        out = []
        x = self.matrix([features])
        bad = self.classifier.outside_domain(x)[0]
        clf = self.classifier
        for i in bad[:5]:
            out.append(f"feature {self.column_names[i]} = {x[0, i]:.4g} outside the "
                       f"training range [{clf.feature_low_[i]:.4g}, "
                       f"{clf.feature_high_[i]:.4g}]")
        if meta is not None:
            vals = {"b": meta.b, "mass_ratio": meta.m2 / meta.m1,
                    "drive_ratio": meta.frequency / (math.sqrt(meta.k1 / meta.m1) / (2 * math.pi))}
            for k, v in vals.items():
                lo, hi = self.param_ranges.get(k, (-math.inf, math.inf))
                if not lo * 0.95 <= v <= hi * 1.05:
                    out.append(f"{k} = {v:.4g} outside the training range "
                               f"[{lo:.4g}, {hi:.4g}]")
            lo, hi = self.param_ranges.get("record_periods", (0.0, math.inf))
            if duration is not None and not 0.5 * lo <= duration * meta.frequency <= 2 * hi:
                out.append(f"record length {duration * meta.frequency:.3g} forcing periods "
                           f"far from the training lengths {lo:.3g}-{hi:.3g}")
        return out

    def classify_analysis(self, analysis, file: str | None = None) -> Classification:
        """Label an :class:`~vidiscover.analysis.AnalysisResult`.

        The analysis must carry the model's features: make it with
        ``analyze(rec, features=vidiscover.regimes.features.ALL_FEATURES)``.

        Raises
        ------
        InputError
            If the analysis lacks some of the model's features.
        """
        feats = dict(analysis.features)
        missing = [n for n in self.feature_names if n not in feats]
        if missing:
            raise InputError(
                f"analysis of {file or analysis.name!r} lacks {len(missing)} of the model's "
                f"features ({', '.join(missing[:3])}{', ...' if len(missing) > 3 else ''}); "
                "analyze it with features=vidiscover.regimes.features.ALL_FEATURES")
        proba = self.predict_proba([feats]).iloc[0]
        # (decide takes the classifier's label from these probabilities)
        label, method = (str(v[0]) for v in self.decide([feats], proba=proba.to_frame().T))
        if method == "rules" and label in self.rule_proba:
            proba = pd.Series({lab: float(self.rule_proba[label].get(lab, 0.0))
                               for lab in LABELS})
        rec = analysis.recording
        warn = self.domain_warnings(feats, rec.meta if rec is not None else None,
                                    analysis.detection.duration)
        if method == "refused":
            warn.insert(0, refusal_message(feats))
        return Classification(file=file or analysis.name, label=label,
                              proba={k: float(v) for k, v in proba.items()},
                              warnings=tuple(warn), features=feats, method=method)

    def classify(self, rec, file: str | None = None) -> Classification:
        """Analyse (stages 1-4) and label a :class:`~vidiscover.recording.Recording`."""
        from ..analysis import analyze
        from .features import ALL_FEATURES

        return self.classify_analysis(analyze(rec, n_boot=0, features=ALL_FEATURES),
                                      file=file or rec.name)

    def __call__(self, analysis) -> dict:
        """``{label, proba}`` of an analysis (the ``classify`` hook of sweeps)."""
        c = self.classify_analysis(analysis)
        return {"label": c.label, "method": c.method, "proba": c.proba}


def refusal_message(features: Mapping) -> str:
    """Why a recording is :data:`REFUSED` (one line, with how to fix it)."""
    sat = float(features.get("saturated_cycle_share", math.nan))
    ipc = features.get("merged_per_cycle", features.get("impacts_per_cycle", math.nan))
    return (f"not classified: the accelerometer is saturated (on its rail for longer than "
            f"a pulse) on {100 * sat:.0f} % of the cycles, where impacts cannot be "
            f"counted, and {float(ipc):.3f} impacts per cycle were counted elsewhere; "
            "no_impact would rest on the missing impacts. Record with a larger "
            "accelerometer range")


def warning_text(warning: str) -> str:
    """A :class:`Classification` warning as a user reads it.

    A refusal (:func:`refusal_message`) is said as it is; any other warning names a
    feature outside the training domain, and the label may be unreliable.
    """
    if warning.startswith("not classified"):
        return warning
    return f"outside the training domain ({warning}); the label may be unreliable"


# --------------------------------------------------------------------------- train/eval
def _scores(y_true, y_pred) -> dict:
    from sklearn.metrics import balanced_accuracy_score, confusion_matrix

    present = [lab for lab in LABELS if lab in set(y_true)]
    cm = confusion_matrix(y_true, y_pred, labels=list(LABELS))
    recall = {}
    y_true = np.asarray(y_true, dtype=object)
    for i, lab in enumerate(LABELS):
        if lab in present:       # a refused recording is in no column: count the truths
            recall[lab] = float(cm[i, i] / np.sum(y_true == lab))
    with warnings.catch_warnings():   # a label predicted but absent from the set
        warnings.filterwarnings("ignore", "y_pred contains classes not in y_true")
        bacc = float(balanced_accuracy_score(y_true, y_pred))
    return {"balanced_accuracy": bacc,
            "recall": recall,
            "confusion": {"labels": list(LABELS), "matrix": cm.tolist()},
            "n": int(len(y_true)), "labels_present": present,
            "refused": int(np.sum(np.asarray(y_pred, dtype=object) == REFUSED))}


def evaluate(model: RegimeModel, data: pd.DataFrame, baseline: RuleBaseline | None = None
             ) -> dict:
    """Score ``model`` and the rule baseline on a labelled set.

    The set comes from :func:`vidiscover.regimes.dataset.generate`.

    Returns
    -------
    dict
        ``balanced_accuracy``, ``recall`` (per label present), ``confusion``
        (``labels``, ``matrix``: rows true, columns predicted), ``n``,
        ``labels_present`` and ``baseline`` (the same for :class:`RuleBaseline`).
    """
    y = data["label"].to_numpy(object)
    out = _scores(y, model.predict(data))
    out["baseline"] = _scores(y, (baseline or RuleBaseline()).predict(_rule_frame(data)))
    labels, methods = model.decide(data)
    out["classify"] = _scores(y, labels)
    out["classify"]["rules_share"] = float(np.mean(methods == "rules")) if len(y) else 0.0
    return out


def _top_labels(classifier, proba: pd.DataFrame) -> np.ndarray:
    """The classifier's labels from its probabilities (a column per label).

    As its ``predict`` gives them, without evaluating the trees again: the first
    maximum in its class order.
    """
    return proba[[str(c) for c in classifier.classes_]].idxmax(axis=1).to_numpy()


def _rule_frame(features) -> pd.DataFrame:
    """The rule baseline's features of a DataFrame (``NAME`` or ``feature:NAME``) or dicts."""
    if not isinstance(features, pd.DataFrame):
        features = pd.DataFrame(list(features))
    cols = {}
    merged = set(RuleBaseline.MERGED.values())
    for n in RuleBaseline.FEATURES:
        key = n if n in features else f"feature:{n}"
        if key in features:
            cols[n] = features[key].to_numpy(float)
        elif n not in merged:                # the rules read the plain one without it
            cols[n] = np.full(len(features), np.nan)
    return pd.DataFrame(cols, index=range(len(features)))


#: The rules' label when no rule holds: never kept over the classifier
#: (:func:`choose_rule_gate`).
RULE_DEFAULT = "chaotic"
#: Classifier probabilities tried as the least with which the rules' label is kept
#: (:func:`choose_rule_gate`).
RULE_GATE_GRID: tuple[float, ...] = (0.0, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5)
#: Repeats of the out-of-fold predictions that choose the gate (:func:`fit_with_gate`):
#: each repeat shuffles the folds anew, and a recording counts the share of repeats in
#: which the classifier was right.
GATE_REPEATS = 3
#: How many standard errors the classifier must win by, out of fold, for the rules'
#: label to be given up (:func:`choose_rule_gate`).
GATE_MARGIN = 2.0


def choose_rule_labels(y, clf_pred, rule_pred, min_cases: int = 5, groups=None,
                       margin: float = GATE_MARGIN) -> tuple[str, ...]:
    """Labels for which the rules beat the classifier, or lose within the noise.

    For every label ``L``, on the recordings to which the rules give ``L``, the
    rules' label is kept unless the classifier's is right more often by more than
    ``margin`` standard errors of the difference (each recording counted with the
    weight of its true label, as balanced accuracy counts it; within the noise the
    rules, the simpler method, stand) and when the rules are right in more than half
    of them -- in every group (e.g. the paper's rig, other rigs, recordings analysed
    as a user's) where the rules give ``L`` to at least ``min_cases`` recordings,
    and there must be one such group; never the rules' default ``chaotic``.
    (:func:`choose_rule_gate` without the classifier's probabilities.)
    """
    return tuple(choose_rule_gate(y, clf_pred, rule_pred, min_cases=min_cases,
                                  groups=groups, margin=margin))


def choose_rule_gate(y, clf_pred, rule_pred, clf_proba=None, min_cases: int = 5,
                     groups=None, grid=RULE_GATE_GRID, margin: float = GATE_MARGIN,
                     folds=None, details: dict | None = None) -> dict[str, float]:
    """Labels for which the rules beat the classifier, and from which probability on.

    For a label ``L`` and a threshold ``t`` of ``grid``, the rules' label would be
    kept on the recordings to which the rules give ``L`` and the classifier gives
    ``L`` a probability >= ``t`` (``clf_proba``: a DataFrame with a column per
    label, or None: ``t`` = 0 only). A threshold qualifies when, in every group
    (e.g. the paper's rig, other rigs, recordings analysed as a user's) where such
    recordings number at least ``min_cases`` (and in one at least), the rules'
    label is right in more than half of them and the classifier's is not right
    more often by more than ``margin`` standard errors (each recording counted with
    the weight of its true label in its group, 1 / its recordings, as balanced
    accuracy counts). "More than half" is within the same margin: more than
    ``0.5 - margin * 0.5 / sqrt(n)`` of the group's ``n`` recordings.

    The margin: the gain of the rules over the classifier is a sum over the
    recordings of ``w (rules right - classifier right)``. Its standard error is
    the larger of the recordings' (``sqrt(sum (w d)^2)``, McNemar's: a resample of
    the recordings moves it by that much) and the folds' (``sqrt(k)`` times the
    spread of the per-fold sums, averaged over the repeats; ``folds``: the fold of
    every recording in every repeat). A gate chosen on the sign of the gain alone
    followed the noise: the shipped model of e634b4a gave ``2ipc_sym`` to the
    classifier on its other rigs' out-of-fold 1-2 wins, and on the held-out other
    rigs (seed 19001) the rules then got 28 of 28 and the classifier 24.
    ``clf_pred`` may hold several repeats of the out-of-fold labels (a row per
    repeat): a recording counts the share of repeats in which the classifier was
    right.

    The rules' ``chaotic`` (:data:`RULE_DEFAULT`) is what they say when no rule
    holds, not a test of its own: it is never kept. It came out kept, on a
    training set (tuning seed 18501 with 80 more 1ipc rows) whose other rigs gave
    it 2 wins over 3 losses out of fold (chaotic recordings weighing more than
    multi_ipc ones), and on tuning set other 18003 it then lost 6 multi_ipc and
    won 1 chaotic.

    When ``t`` = 0 (the rules whenever they say ``L``) qualifies, it is kept. A
    threshold is there for a label the rules would otherwise lose: the rules stand
    unless the classifier is confident of another label. On the paper's rig the
    rules say ``no_impact`` for a record with one or two impacts in 30-50 cycles
    (the labels' contract), which the classifier may call ``chaotic`` or ``1ipc``;
    on other rigs the same rule reads records whose impacts the detection missed,
    and may be right in fewer than half of them. A threshold must gain (the rules
    right more often, so weighted, over the groups) on evidence: at least
    ``min_cases`` recordings the rules get right and the classifier does not (on
    seed 18501, ``multi_ipc`` from 0.2 gained on 2 other-rig recordings and lost 2
    ``1ipc`` of tuning set 18003 whose first bounce the detector sees). The
    qualifying one with the largest gain is kept (ties: the smallest). Taking the
    largest gain over every threshold, 0 included, picked 0.2 for ``1ipc`` on
    tuning seed 18501, which lost 2 ``1ipc`` recordings of tuning set 18003 that
    the classifier gave 0.11 and 0.00 and the rules got right.

    The weights matter for a rare label: out of fold on seed 18501's paper rig the
    rules' ``1ipc`` is right on fewer recordings than the classifier's label (31 of
    39 vs 32), but those it wins are ``1ipc`` (4, each weighing as much as 4
    ``multi_ipc``) and those it loses ``multi_ipc`` (5).

    The margin of 2 standard errors: on tuning training draws (seeds 22001 with
    three 85 % subsamples, 22003) the per-group ``gain / se`` sat at exactly -1 or
    +1 (one recording apart), +-1.41 (two) and between: a margin of 1 lies on them
    (``multi_ipc`` at -1.02 and ``smr`` at -1.41 dropped on one draw, kept on the
    three others), 2 leaves every one 0.59 away and gave the same labels on all
    four. With no recording the rules win, the classifier needs 5 clean wins of
    equal weight. On a full-size draw (22005) the old gate's three out-of-fold
    repeats gave three label sets (one without ``2ipc_sym``). The test "right in
    more than half" is within the margin too: taken exactly, it decided
    ``no_impact`` and ``smr`` on the 5-9 other-rig rows where the rules say them,
    and moved between draws (22003 without ``no_impact``, its subsample 22211
    with it; 22005 without ``smr``, where the rules were ahead of the classifier
    on both rigs).

    Parameters
    ----------
    details : dict, optional
        Filled with the comparison at ``t`` = 0: label -> group -> ``n``, ``gain``,
        ``se`` (the larger of ``se_rows`` and ``se_folds``), ``rules_right``,
        ``classifier_right`` (weighted sums) and ``kept``.

    Returns
    -------
    dict
        Label -> least classifier probability, for the labels the rules keep.
    """
    y, rule_pred = (np.asarray(v, dtype=object) for v in (y, rule_pred))
    clf_pred = np.asarray(clf_pred, dtype=object)
    if clf_pred.size % max(len(y), 1) or clf_pred.shape[-1] != len(y):
        raise InputError(f"choose_rule_gate: {clf_pred.shape} classifier labels for "
                         f"{len(y)} recordings; give one per recording (a row per repeat)")
    clf_pred = clf_pred.reshape(-1, len(y))               # a row per repeat
    if folds is not None:
        folds = np.asarray(folds, int)
        if folds.size != clf_pred.size:
            raise InputError(f"choose_rule_gate: folds have shape {folds.shape}, the labels "
                             f"{clf_pred.shape}; give a fold per recording and repeat")
        folds = folds.reshape(clf_pred.shape)
    groups = np.zeros(len(y), dtype=object) if groups is None else np.asarray(groups, object)
    grid = (0.0,) if clf_proba is None else tuple(sorted(set(float(t) for t in grid)))
    weight = np.zeros(len(y))
    for g in dict.fromkeys(groups):
        m = groups == g
        labs, inv, counts = np.unique(y[m].astype(str), return_inverse=True,
                                      return_counts=True)
        weight[m] = 1.0 / counts[inv]
    rule_right = (rule_pred == y).astype(float)
    each_right = (clf_pred == y[None, :]).astype(float)
    clf_right = each_right.mean(axis=0)
    diff = weight * (rule_right - clf_right)

    def spread(m) -> tuple[float, float]:
        """Standard errors of the gain on rows ``m``: the recordings', the folds'."""
        per = []
        for r in range(0 if folds is None else folds.shape[0]):
            d = weight[m] * (rule_right[m] - each_right[r, m])
            ks = np.unique(folds[r])
            sums = np.array([d[folds[r, m] == k].sum() for k in ks])
            if len(ks) > 1:
                per.append(math.sqrt(len(ks)) * float(np.std(sums, ddof=1)))
        return float(np.sqrt(np.sum(diff[m] ** 2))), float(np.mean(per)) if per else 0.0

    out = {}
    for lab in LABELS:
        if lab == RULE_DEFAULT:
            continue
        p = (np.ones(len(y)) if clf_proba is None or lab not in clf_proba
             else np.asarray(clf_proba[lab], float))
        best = None
        for t in grid:
            sub = (rule_pred == lab) & (p >= t)
            verdicts = []
            for g in dict.fromkeys(groups):
                m = sub & (groups == g)
                if m.sum() >= min_cases:
                    gain, (se_rows, se_folds) = float(diff[m].sum()), spread(m)
                    se = max(se_rows, se_folds)
                    # right in more than half, within the same margin (a share's
                    # standard error at one half is 0.5 / sqrt(n))
                    half = 0.5 - margin * 0.5 / math.sqrt(m.sum())
                    ok = bool(rule_right[m].mean() > half and gain >= -margin * se - 1e-12)
                    verdicts.append(ok)
                    if details is not None and t == 0:
                        details.setdefault(lab, {})[str(g)] = {
                            "n": int(m.sum()), "gain": gain, "se": se, "kept": ok,
                            "se_rows": se_rows, "se_folds": se_folds,
                            "rules_right": float(np.sum(weight[m] * rule_right[m])),
                            "classifier_right": float(np.sum(weight[m] * clf_right[m]))}
            if not (verdicts and all(verdicts)):
                continue
            if t == 0:                 # the rules whenever they say L: no threshold
                best = (0.0, 0.0)
                break
            gain = float(diff[sub].sum())
            wins = int(round(float(np.sum(np.clip(rule_right[sub] - clf_right[sub], 0, None)))))
            if wins >= min_cases and gain > 1e-12 and (best is None or gain > best[1] + 1e-12):
                best = (t, gain)
        if best is not None:
            out[lab] = best[0]
    return out


def _groups(data: pd.DataFrame) -> np.ndarray:
    """Origin of every training row: the paper's rig, other rigs, or a corpus case."""
    origin = (data["param:origin"].astype(str).to_numpy(object) if "param:origin" in data
              else np.full(len(data), "random", dtype=object))
    k1 = (data["param:k1"].to_numpy(float) if "param:k1" in data
          else np.zeros(len(data)))
    other = np.nan_to_num(k1) > 0
    corpus = np.isin(origin, ("corpus_dev", "corpus_draw"))
    return np.where(corpus, "corpus_dev",
                    np.where(other, "other_rigs", "paper_rig")).astype(object)


def fit_model(data: pd.DataFrame, *, random_state: int = 0, metadata: Mapping | None = None,
              rule_inputs: bool = False, **params) -> RegimeModel:
    """Fit a :class:`RegimeModel` on a labelled set (``feature:NAME`` columns)."""
    from .dataset import DOMAIN

    names = tuple(model_features())
    model = RegimeModel(RegimeClassifier(random_state=random_state, **params), names,
                        {k: tuple(v) for k, v in DOMAIN.items()}, dict(metadata or {}),
                        rule_inputs)
    model.classifier.fit(model.matrix(data), data["label"].to_numpy(object).astype(str))
    return model


def fit_with_gate(data: pd.DataFrame, *, random_state: int = 0, metadata: Mapping | None = None,
                  folds: int = 3, repeats: int = GATE_REPEATS, margin: float = GATE_MARGIN,
                  **params) -> tuple[RegimeModel, dict]:
    """Fit a :class:`RegimeModel` and choose its :attr:`~RegimeModel.rule_labels`.

    Out-of-fold predictions of the classifier (``folds`` stratified folds, shuffled
    anew in each of ``repeats`` repeats) are set beside the rules' labels on the
    training set, in each group of rows (the paper's rig, other rigs and
    instruments, realism-corpus recordings analysed as a user's;
    :func:`choose_rule_gate`, with ``margin``).

    Returns
    -------
    model : RegimeModel
    oof : dict
        Out-of-fold scores of the classifier (first repeat) and of the rules, the
        per-label comparison that chose the labels (``comparison``) and the chosen
        labels.
    """
    from dataclasses import replace

    from sklearn.model_selection import StratifiedKFold

    if not (isinstance(repeats, (int, np.integer)) and repeats >= 1):
        raise InputError(f"fit_with_gate: repeats must be an integer >= 1, was {repeats!r}; "
                         "give the number of out-of-fold repeats (default 3)")
    y = data["label"].to_numpy(object).astype(str)
    counts = pd.Series(y).value_counts()
    k = int(min(folds, counts.min())) if len(counts) > 1 else 0
    model = fit_model(data, random_state=random_state, metadata=metadata, **params)
    rules = RuleBaseline().predict(_rule_frame(data))
    if k < 2:
        return model, {}
    oof = np.empty((repeats, len(y)), dtype=object)
    fold_of = np.zeros((repeats, len(y)), dtype=int)
    oof_proba = pd.DataFrame(0.0, index=range(len(y)), columns=list(LABELS))
    for r in range(repeats):
        split = StratifiedKFold(k, shuffle=True, random_state=random_state + r).split(y, y)
        for i, (tr, te) in enumerate(split):
            part = fit_model(data.iloc[tr], random_state=random_state, **params)
            proba = part.predict_proba(data.iloc[te])
            oof_proba.iloc[te] += proba.to_numpy() / repeats
            oof[r, te] = _top_labels(part.classifier, proba)
            fold_of[r, te] = i
    groups = _groups(data)
    comparison: dict = {}
    gate = choose_rule_gate(y, oof, rules, oof_proba, groups=groups, margin=margin,
                            folds=fold_of, details=comparison)
    chosen = tuple(gate)
    least = {lab: t for lab, t in gate.items() if t > 0}
    kept = {lab: (rules == lab) & (oof_proba[lab].to_numpy() >= t) for lab, t in gate.items()}
    rule_proba = {lab: {k: float(np.mean(y[kept[lab]] == k)) for k in LABELS}
                  for lab in chosen}
    report = {"rule_labels": list(chosen), "rule_min_proba": least,
              "rule_proba": rule_proba, "folds": k, "repeats": int(repeats),
              "margin": float(margin), "comparison": comparison, "groups": {}}
    first = oof[0]
    for g in dict.fromkeys(groups):
        m = groups == g
        report["groups"][str(g)] = {"n": int(m.sum()), "classifier": _scores(y[m], first[m]),
                                    "rules": _scores(y[m], rules[m])}
    labels = np.where(np.isin(rules, list(chosen)) & np.any(list(kept.values()), axis=0),
                      rules, first).astype(object) if chosen else first
    for g in report["groups"]:
        m = groups == g
        report["groups"][g]["classify"] = _scores(y[m], labels[m])
    return (replace(model, rule_labels=chosen, rule_proba=rule_proba, rule_min_proba=least),
            report)


def train(n: int = DEFAULT_N_TRAIN, seed: int = DEFAULT_SEED, *, n_test: int = DEFAULT_N_TEST,
          n_realism: int = DEFAULT_N_REALISM, n_corpus_train: int = 0, n_corpus_test: int = 0,
          n_jobs: int | None = 1, scheduler=None, progress: bool = False
          ) -> tuple[RegimeModel, dict]:
    """Simulate a training sweep, fit the classifier, evaluate on held-out sets.

    Parameters
    ----------
    n : int
        Random training cases at the paper's rig (exact engine, default sensors),
        plus targeted draws for rare labels.
    seed : int
        Seed of the training set; the test sets use ``seed + 100003``.
    n_test : int
        Random cases of each simulated held-out set: the paper's rig (exact engine),
        and other rigs and instrument chains (as ``n_realism``).
    n_realism : int
        Random training cases of other rigs, compliant or exact walls and drawn
        instrument chains (:func:`vidiscover.regimes.dataset.draw_realism_cases`).
    n_corpus_train : int
        Recordings analysed as a user's recordings are (the pulse learned from
        each), added to the training set: they teach the classifier, and the choice
        of the rules' labels, what a learned pulse does to the features. The realism
        corpus's ``dev`` split first (96 cases), then, beyond it, cases drawn as the
        corpus draws them from ``seed``
        (:func:`vidiscover.regimes.dataset.draw_corpus_cases`).
    n_corpus_test : int
        Cases of the realism corpus's ``test`` split (:mod:`vidiscover.corpus`)
        analysed as a user's recordings are (the pulse learned from each); 0: none.
    n_jobs, scheduler, progress
        Passed to :func:`vidiscover.scale.parallel_map`.

    Returns
    -------
    model : RegimeModel
    report : dict
        :func:`evaluate` on the paper-rig test set (top level), every set under
        ``sets``, the out-of-fold comparison that chose the rules' labels under
        ``gate``, plus ``n_train``, ``train_labels``.
    """
    from ..corpus import N_CASES
    from .dataset import corpus_draw_set, corpus_set, generate

    kw = dict(n_jobs=n_jobs, scheduler=scheduler, progress=progress)
    data = generate(n, seed, n_realism=n_realism, **kw)
    if n_corpus_train:
        n_dev = min(n_corpus_train, N_CASES["dev"])
        dev = corpus_set("dev", n_dev, **kw).assign(**{"param:origin": "corpus_dev"})
        data = pd.concat([data, dev], ignore_index=True)
        if n_corpus_train > n_dev:
            more = corpus_draw_set(n_corpus_train - n_dev, seed, **kw)
            data = pd.concat([data, more.assign(**{"param:origin": "corpus_draw"})],
                             ignore_index=True)
    tests = {}
    if n_test:
        tests["exact_paper_rig"] = generate(n_test, seed + TEST_SEED_OFFSET, **kw)
        if n_realism:
            tests["other_rigs_instruments"] = generate(0, seed + TEST_SEED_OFFSET,
                                                       n_realism=n_test, rounds=0, **kw)
    if n_corpus_test:
        tests["corpus_test"] = corpus_set("test", n_corpus_test, **kw)
    return _fit_and_report(data, tests, seed=seed, n=n, n_test=n_test, n_realism=n_realism,
                           n_corpus_train=n_corpus_train, n_corpus_test=n_corpus_test)


#: What the held-out sets of :func:`train` are.
TEST_SETS: Mapping[str, str] = {
    "exact_paper_rig": "exact engine, the paper's rig and sensors (pulse known)",
    "other_rigs_instruments": "other rigs, compliant or exact walls, drawn instrument "
                              "chains (pulse known)",
    "corpus_test": "realism corpus test split: compliant walls, other rigs, instrument "
                   "chains (pulse learned, as a user's recording)",
    "independent": "recordings of an independent simulator (pulse learned)",
}


def _fit_and_report(data: pd.DataFrame, tests: Mapping[str, pd.DataFrame], *, seed: int,
                    n: int, n_test: int, n_realism: int = 0, n_corpus_train: int = 0,
                    n_corpus_test: int = 0) -> tuple[RegimeModel, dict]:
    """The fitting and scoring half of :func:`train`, on simulated sets."""
    import sklearn

    command = f"vidiscover train --seed {seed} --n {n} --n-test {n_test}"
    command += (f" --n-realism {n_realism} --n-corpus-train {n_corpus_train}"
                f" --n-corpus-test {n_corpus_test} --out MODEL")
    meta = {"seed": seed, "n": n, "n_test": n_test, "n_realism": n_realism,
            "n_corpus_train": n_corpus_train, "n_corpus_test": n_corpus_test,
            "n_train": len(data),
            "train_labels": data["label"].value_counts().to_dict(),
            "sklearn_version": sklearn.__version__, "command": command}
    from .dataset import probe_rows

    model, gate = fit_with_gate(data, random_state=seed, metadata=meta)
    model.metadata["rule_labels"] = list(model.rule_labels)
    model.metadata["rule_min_proba"] = dict(model.rule_min_proba)
    model.metadata["rule_gate"] = {"repeats": gate.get("repeats"), "margin": gate.get("margin")}
    # a few training rows, recomputed by the test suite: the model must keep coming
    # out of its own command (a change to the simulator, sensors or analysis moves them)
    model.metadata["probe"] = probe_rows(data)
    report = {"n_train": len(data), "train_labels": meta["train_labels"], "gate": gate,
              "sets": {}}
    for name, test in tests.items():
        if len(test):
            rep = evaluate(model, test)
            rep["test_labels"] = test["label"].value_counts().to_dict()
            rep["description"] = TEST_SETS.get(name, name)
            report["sets"][name] = rep
    first = next(iter(report["sets"].values()), None)
    if first is not None:
        report.update({k: v for k, v in first.items() if k not in ("description",)})
        model.metadata.update({k: report[k] for k in ("balanced_accuracy", "recall")})
        model.metadata["baseline_balanced_accuracy"] = report["baseline"]["balanced_accuracy"]
        model.metadata["scores"] = {
            name: {m: {"balanced_accuracy": part["balanced_accuracy"],
                       "recall": part["recall"]}
                   for m, part in (("classifier", rep), ("rules", rep["baseline"]),
                                   ("classify", rep["classify"]))}
            for name, rep in report["sets"].items()}
    return model, report


# --------------------------------------------------------------------------- files
def save_model(model: RegimeModel, path) -> Path:
    """Write ``model`` to a skops file (atomically) and return the path."""
    import zipfile

    import skops.io as sio

    from .._atomic import to_jsonable, write_group

    path = Path(path)
    state = {"classifier": model.classifier, "feature_names": list(model.feature_names),
             "param_ranges": {k: [float(a), float(b)] for k, (a, b) in
                              model.param_ranges.items()},
             "metadata": json.dumps(to_jsonable(model.metadata)),
             "rule_inputs": bool(model.rule_inputs),
             "rule_labels": [str(v) for v in model.rule_labels],
             "rule_proba": json.dumps(to_jsonable(model.rule_proba)),
             "rule_min_proba": json.dumps(to_jsonable(model.rule_min_proba))}
    write_group([(path, lambda tmp: tmp.write_bytes(
        sio.dumps(state, compression=zipfile.ZIP_DEFLATED, compresslevel=9)))])
    return path


def load_model(path) -> RegimeModel:
    """Load a model written by :func:`save_model`, trusting only :data:`TRUSTED_TYPES`.

    Raises
    ------
    InputError
        If the file is missing, not a skops file, or holds any other type.
    """
    import skops.io as sio

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such model file; train one with "
                         "`vidiscover train --out MODEL` or omit --model")
    try:
        untrusted = sio.get_untrusted_types(file=path)
    except Exception as err:  # zip/JSON errors of a file that is not a skops model
        raise InputError(f"{path}: not a skops model file ({type(err).__name__}); "
                         "train one with `vidiscover train --out MODEL`") from None
    refused = sorted(set(untrusted) - set(TRUSTED_TYPES))
    if refused:
        raise InputError(f"{path}: refusing to load untrusted types {', '.join(refused)}; "
                         "only vidiscover regime models are loaded")
    state = sio.load(path, trusted=list(TRUSTED_TYPES))
    if not (isinstance(state, dict) and isinstance(state.get("classifier"),
                                                   RegimeClassifier)):
        raise InputError(f"{path}: not a vidiscover regime model; "
                         "train one with `vidiscover train --out MODEL`")
    return RegimeModel(state["classifier"], tuple(state["feature_names"]),
                       {k: tuple(v) for k, v in state["param_ranges"].items()},
                       json.loads(state["metadata"]), bool(state.get("rule_inputs", False)),
                       tuple(str(v) for v in state.get("rule_labels", ())),
                       json.loads(state.get("rule_proba", "{}")),
                       json.loads(state.get("rule_min_proba", "{}")))


def load_default_model() -> RegimeModel:
    """The model shipped with vidiscover (``vidiscover/data/regime_model.skops``)."""
    ref = resources.files("vidiscover") / "data" / DEFAULT_MODEL
    with resources.as_file(ref) as path:
        return load_model(path)


def format_report(report: Mapping, confusion: bool = True) -> str:
    """Text of an :func:`evaluate` report, or of every set of a :func:`train` report.

    Balanced accuracy and recall per label of the classifier, the rule baseline and
    what ``classify`` gives (the classifier, or the rules for their labels) side by
    side, then the confusion tables of the classifier and the rules.
    """
    if "sets" in report and report["sets"]:
        parts = []
        for name, rep in report["sets"].items():
            parts.append(f"== {name}: {rep.get('description', '')}")
            parts.append(format_report(rep, confusion))
        return "\n\n".join(parts)
    base = report["baseline"]
    final = report.get("classify")
    labels = list(report["confusion"]["labels"])
    w = 22
    head = f"{'':{w}s}{'classifier':>12s}{'rules':>12s}" + (f"{'classify':>12s}" if final else "")
    lines = [f"held-out test set: {report['n']} recordings", head,
             f"{'balanced accuracy':{w}s}{report['balanced_accuracy']:12.3f}"
             f"{base['balanced_accuracy']:12.3f}"
             + (f"{final['balanced_accuracy']:12.3f}" if final else "")]
    for lab in labels:
        if lab in report["recall"]:
            n_lab = int(np.asarray(report["confusion"]["matrix"])[labels.index(lab)].sum())
            lines.append(f"{'recall ' + lab + f' ({n_lab})':{w}s}{report['recall'][lab]:12.3f}"
                         f"{base['recall'][lab]:12.3f}"
                         + (f"{final['recall'][lab]:12.3f}" if final else ""))
    if final:
        lines.append(f"classify used the rules for {100 * final['rules_share']:.0f} % of "
                     "the recordings")
        if final.get("refused"):
            lines.append(f"classify refused {final['refused']} recording(s): the "
                         "accelerometer saturated, too few impacts counted to tell")
    if not confusion:
        return "\n".join(lines)
    for title, part in (("classifier", report), ("rule baseline", base)):
        m = np.asarray(part["confusion"]["matrix"])
        lines += ["", f"confusion ({title}; rows true, columns predicted)",
                  " " * 11 + "".join(f"{lab[:9]:>10s}" for lab in labels)]
        lines += [f"{lab:11s}" + "".join(f"{v:10d}" for v in row)
                  for lab, row in zip(labels, m)]
    return "\n".join(lines)
