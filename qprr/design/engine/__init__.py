"""Running design studies on the campaign backends (:func:`run_design`), resumable, with progress lines."""

from .run import DesignRun, infeasible_reasons, run_design

__all__ = ["DesignRun", "infeasible_reasons", "run_design"]
