"""Running design studies on the campaign backends (:func:`run_design`), resumable, with progress lines."""

from .run import DesignRun, run_design

__all__ = ["DesignRun", "run_design"]
