"""Answers people can read: the ranked table, Pareto figures, the closed-loop check of the top designs."""

from .figures import parallel_coordinates, pareto_2d
from .rank import front, markdown_table, ranked, scores
from .write import flights, load_study, report

__all__ = ["flights", "front", "load_study", "markdown_table", "parallel_coordinates", "pareto_2d", "ranked", "report", "scores"]
