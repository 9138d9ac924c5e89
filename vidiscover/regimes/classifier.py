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

__all__ = ["RegimeClassifier", "RuleBaseline", "RegimeModel", "Classification",
           "model_features", "train", "evaluate", "save_model", "load_model",
           "load_default_model", "TRUSTED_TYPES", "DEFAULT_MODEL", "DEFAULT_SEED",
           "DEFAULT_N_TRAIN", "DEFAULT_N_TEST", "format_report", "fit_model"]

#: Registered features not used by the model (``n_impacts`` grows with the record
#: length; the per-cycle features carry the same information).
EXCLUDED_FEATURES: tuple[str, ...] = ("n_impacts",)

#: The shipped model and its training settings (``vidiscover train --seed 0 --n 2500
#: --n-test 800 --out vidiscover/data/regime_model.skops`` reproduces it).
DEFAULT_MODEL = "regime_model.skops"
DEFAULT_SEED, DEFAULT_N_TRAIN, DEFAULT_N_TEST = 0, 2500, 800
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
    """Names of the registered features the model uses, in registry order."""
    from ..analysis.returnmap import FEATURES

    return [n for n in FEATURES if n not in EXCLUDED_FEATURES]


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

    ``impacts_per_cycle`` < 0.05 -> ``no_impact``; ``impacting_cycle_share`` < 0.9 and
    ``envelope_modulation`` >= 0.15 -> ``smr``; otherwise, when the share is >= 0.9
    and the response is periodic (``strobe_period_error`` <= ``periodic_tol``):
    ``one_per_cycle_share`` >= 0.9 -> ``1ipc``; ``two_per_cycle_share`` >= 0.9 and
    ``alternation`` >= 0.9 -> ``2ipc_asym`` if ``asymmetry`` >= 0.1 else
    ``2ipc_sym``; else ``multi_ipc``. Everything else is ``chaotic``.

    Parameters
    ----------
    periodic_tol : float
        Largest stroboscopic change (relative to max |x|) that counts as periodic.
    """

    periodic_tol: float = 0.01
    #: Features the rules read.
    FEATURES: ClassVar[tuple[str, ...]] = (
        "impacts_per_cycle", "impacting_cycle_share", "envelope_modulation",
        "strobe_period_error", "one_per_cycle_share", "two_per_cycle_share", "alternation",
        "asymmetry")

    def predict(self, features: pd.DataFrame) -> np.ndarray:
        """Label every row of a DataFrame of features (columns named as registered)."""
        f = {k: features[k].to_numpy(float) for k in self.FEATURES}
        with np.errstate(invalid="ignore"):
            ipc = np.nan_to_num(f["impacts_per_cycle"])
            phi = np.nan_to_num(f["impacting_cycle_share"])
            periodic = f["strobe_period_error"] <= self.periodic_tol
            one = f["one_per_cycle_share"] >= 0.9
            two = (f["two_per_cycle_share"] >= 0.9) & (f["alternation"] >= 0.9)
            asym = np.nan_to_num(f["asymmetry"]) >= 0.1
            out = np.select(
                [ipc < 0.05, (phi < 0.9) & (f["envelope_modulation"] >= 0.15),
                 (phi >= 0.9) & periodic & one, (phi >= 0.9) & periodic & two & asym,
                 (phi >= 0.9) & periodic & two, (phi >= 0.9) & periodic],
                ["no_impact", "smr", "1ipc", "2ipc_asym", "2ipc_sym", "multi_ipc"],
                "chaotic")
        return out.astype(object)


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
        Probability of every label of :data:`LABELS` (0 for labels never trained).
    warnings : tuple of str
        Why the recording may lie outside the training domain.
    features : dict
        The features the label was computed from.
    """

    file: str
    label: str
    proba: dict
    warnings: tuple = ()
    features: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        """``{file, label, proba, warnings}`` (JSON-ready)."""
        return {"file": self.file, "label": self.label, "proba": dict(self.proba),
                "warnings": list(self.warnings)}


@dataclass(frozen=True, eq=False)
class RegimeModel:
    """A fitted :class:`RegimeClassifier` with what is needed to use it honestly.

    Attributes
    ----------
    classifier : RegimeClassifier
    feature_names : tuple of str
        Feature columns, in the classifier's order.
    param_ranges : dict
        Parameter ranges of the training sweep (name -> (low, high)).
    metadata : dict
        Training settings and scores.
    rule_inputs : bool
        Give the classifier the rule baseline's label (one-hot) as extra inputs
        besides the features: the trees learn where the rules hold and where the
        detected features mislead them.
    """

    classifier: RegimeClassifier
    feature_names: tuple
    param_ranges: Mapping = field(default_factory=dict)
    metadata: Mapping = field(default_factory=dict)
    rule_inputs: bool = True

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
            rule = RuleBaseline().predict(pd.DataFrame({n: cols[n] for n in RuleBaseline.FEATURES}))
            x += [(rule == lab).astype(float) for lab in LABELS]
        return np.column_stack(x) if x else np.zeros((len(features), 0))

    @property
    def column_names(self) -> list[str]:
        """Names of the columns of :meth:`matrix`."""
        extra = [f"rule:{lab}" for lab in LABELS] if self.rule_inputs else []
        return list(self.feature_names) + extra

    def predict(self, features) -> np.ndarray:
        """Labels of a DataFrame / list of feature dicts."""
        return self.classifier.predict(self.matrix(features))

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
        if bad:
            names = ", ".join(self.column_names[i] for i in bad[:5])
            out.append(f"features outside the training range: {names}")
        if meta is not None:
            vals = {"b": meta.b, "amplitude": meta.amplitude, "frequency": meta.frequency,
                    "mass_ratio": meta.m2 / meta.m1}
            for k, v in vals.items():
                lo, hi = self.param_ranges.get(k, (-math.inf, math.inf))
                if not lo * 0.95 <= v <= hi * 1.05:
                    out.append(f"{k} = {v:.4g} outside the training range "
                               f"[{lo:.4g}, {hi:.4g}]")
        d0 = self.metadata.get("duration")
        if duration is not None and d0 and not 0.5 * d0 <= duration <= 2 * d0:
            out.append(f"record length {duration:.3g} s far from the training length "
                       f"{d0:.3g} s")
        return out

    def classify_analysis(self, analysis, file: str | None = None) -> Classification:
        """Label an :class:`~vidiscover.analysis.AnalysisResult`."""
        from ..analysis.returnmap import compute_features
        from .dataset import feature_context

        feats = dict(analysis.features)
        missing = [n for n in self.feature_names if n not in feats]
        if missing:
            feats.update(compute_features(feature_context(analysis), missing))
        proba = self.predict_proba([feats]).iloc[0]
        label = str(proba.idxmax())
        rec = analysis.recording
        warn = self.domain_warnings(feats, rec.meta if rec is not None else None,
                                    analysis.detection.duration)
        return Classification(file=file or analysis.name, label=label,
                              proba={k: float(v) for k, v in proba.items()},
                              warnings=tuple(warn), features=feats)

    def classify(self, rec, file: str | None = None) -> Classification:
        """Analyse (stages 1-4) and label a :class:`~vidiscover.recording.Recording`."""
        from ..analysis import analyze

        return self.classify_analysis(analyze(rec, n_boot=0), file=file or rec.name)

    def __call__(self, analysis) -> dict:
        """``{label, proba}`` of an analysis (the ``classify`` hook of sweeps)."""
        c = self.classify_analysis(analysis)
        return {"label": c.label, "proba": c.proba}


# --------------------------------------------------------------------------- train/eval
def _scores(y_true, y_pred) -> dict:
    from sklearn.metrics import balanced_accuracy_score, confusion_matrix

    present = [lab for lab in LABELS if lab in set(y_true)]
    cm = confusion_matrix(y_true, y_pred, labels=list(LABELS))
    recall = {}
    for i, lab in enumerate(LABELS):
        if lab in present:
            recall[lab] = float(cm[i, i] / cm[i].sum())
    with warnings.catch_warnings():   # a label predicted but absent from the set
        warnings.filterwarnings("ignore", "y_pred contains classes not in y_true")
        bacc = float(balanced_accuracy_score(y_true, y_pred))
    return {"balanced_accuracy": bacc,
            "recall": recall,
            "confusion": {"labels": list(LABELS), "matrix": cm.tolist()},
            "n": int(len(y_true)), "labels_present": present}


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
    feats = pd.DataFrame({n: data[f"feature:{n}"] for n in RuleBaseline.FEATURES})
    out["baseline"] = _scores(y, (baseline or RuleBaseline()).predict(feats))
    return out


def fit_model(data: pd.DataFrame, *, random_state: int = 0, metadata: Mapping | None = None,
              rule_inputs: bool = True, **params) -> RegimeModel:
    """Fit a :class:`RegimeModel` on a labelled set (``feature:NAME`` columns)."""
    from .dataset import PARAM_RANGES

    names = tuple(model_features())
    model = RegimeModel(RegimeClassifier(random_state=random_state, **params), names,
                        {k: tuple(v) for k, v in PARAM_RANGES.items()}, dict(metadata or {}),
                        rule_inputs)
    model.classifier.fit(model.matrix(data), data["label"].to_numpy(object).astype(str))
    return model


def train(n: int = DEFAULT_N_TRAIN, seed: int = DEFAULT_SEED, *, n_test: int = DEFAULT_N_TEST,
          n_jobs: int | None = 1, scheduler=None, progress: bool = False
          ) -> tuple[RegimeModel, dict]:
    """Simulate a training sweep, fit the classifier, evaluate on a held-out sweep.

    Parameters
    ----------
    n, n_test : int
        Random cases of the training and the test sets (plus targeted draws).
    seed : int
        Seed of the training set; the test set uses ``seed + 100003``.
    n_jobs, scheduler, progress
        Passed to :func:`vidiscover.scale.parallel_map`.

    Returns
    -------
    model : RegimeModel
    report : dict
        :func:`evaluate` on the test set plus ``n_train``, ``train_labels``.
    """
    from .dataset import generate

    kw = dict(n_jobs=n_jobs, scheduler=scheduler, progress=progress)
    data = generate(n, seed, **kw)
    test = generate(n_test, seed + TEST_SEED_OFFSET, **kw) if n_test else None
    return _fit_and_report(data, test, seed=seed, n=n, n_test=n_test)


def _fit_and_report(data: pd.DataFrame, test: pd.DataFrame | None, *, seed: int, n: int,
                    n_test: int) -> tuple[RegimeModel, dict]:
    """The fitting and scoring half of :func:`train`, on simulated sets."""
    import sklearn

    meta = {"seed": seed, "n": n, "n_test": n_test, "n_train": len(data),
            "train_labels": data["label"].value_counts().to_dict(),
            "duration": float(data["param:duration"].iloc[0]),
            "settle": float(data["param:settle"].iloc[0]),
            "sklearn_version": sklearn.__version__,
            "command": f"vidiscover train --seed {seed} --n {n} --n-test {n_test} --out MODEL"}
    model = fit_model(data, random_state=seed, metadata=meta)
    report = {"n_train": len(data), "train_labels": meta["train_labels"]}
    if test is not None:
        report.update(evaluate(model, test))
        report["test_labels"] = test["label"].value_counts().to_dict()
        model.metadata.update({k: report[k] for k in ("balanced_accuracy", "recall")})
        model.metadata["baseline_balanced_accuracy"] = report["baseline"]["balanced_accuracy"]
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
             "rule_inputs": bool(model.rule_inputs)}
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
                       json.loads(state["metadata"]), bool(state.get("rule_inputs", False)))


def load_default_model() -> RegimeModel:
    """The model shipped with vidiscover (``vidiscover/data/regime_model.skops``)."""
    ref = resources.files("vidiscover") / "data" / DEFAULT_MODEL
    with resources.as_file(ref) as path:
        return load_model(path)


def format_report(report: Mapping) -> str:
    """Text of an :func:`evaluate` report.

    Balanced accuracy and recall per label of the classifier beside the rule
    baseline, then both confusion tables.
    """
    base = report["baseline"]
    labels = list(report["confusion"]["labels"])
    w = 22
    lines = [f"held-out test set: {report['n']} recordings",
             f"{'':{w}s}{'classifier':>12s}{'rules':>12s}",
             f"{'balanced accuracy':{w}s}{report['balanced_accuracy']:12.3f}"
             f"{base['balanced_accuracy']:12.3f}"]
    for lab in labels:
        if lab in report["recall"]:
            lines.append(f"{'recall ' + lab:{w}s}{report['recall'][lab]:12.3f}"
                         f"{base['recall'][lab]:12.3f}")
    for title, part in (("classifier", report), ("rule baseline", base)):
        m = np.asarray(part["confusion"]["matrix"])
        lines += ["", f"confusion ({title}; rows true, columns predicted)",
                  " " * 11 + "".join(f"{lab[:9]:>10s}" for lab in labels)]
        lines += [f"{lab:11s}" + "".join(f"{v:10d}" for v in row)
                  for lab, row in zip(labels, m)]
    return "\n".join(lines)
