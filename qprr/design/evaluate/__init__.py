"""Evaluate designs: the metrics (:data:`DESIGN_METRICS`), the maps that give them, the backend task."""

from ..spec.metrics import DESIGN_METRICS, label, sign
from .maps import evaluate_platform
from .task import columns, evaluate_design, exclusions, feasible

__all__ = ["DESIGN_METRICS", "columns", "evaluate_design", "evaluate_platform", "exclusions", "feasible", "label", "sign"]
