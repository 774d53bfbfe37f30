"""Evaluate designs: the metrics (:data:`METRICS`), the maps that give them, the backend task."""

from ..spec.metrics import METRICS, label, sign
from .maps import evaluate_platform
from .task import columns, evaluate_design, exclusions, feasible

__all__ = ["METRICS", "columns", "evaluate_design", "evaluate_platform", "exclusions", "feasible", "label", "sign"]
