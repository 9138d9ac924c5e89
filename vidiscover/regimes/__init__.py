"""Regimes: ground-truth labels, features and the classifier."""

from .labels import LABELS, RegimeTruth, label_simulation

__all__ = ["LABELS", "RegimeTruth", "label_simulation"]
