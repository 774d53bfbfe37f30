"""Answers people can read: the ranked table, Pareto figures, the closed-loop check of the top designs."""

from .figures import parallel_coordinates, pareto_2d
from .rank import front, markdown_table, ranked, scores
from .write import design_report, flights, load_study

__all__ = ["flights", "front", "load_study", "markdown_table", "parallel_coordinates", "pareto_2d", "design_report", "ranked", "scores"]
