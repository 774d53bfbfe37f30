"""Search over designs: the grid and its run indices, NSGA-II (pymoo / Optuna), Pareto dominance."""

from .optimiser import ENGINES, Optimiser, make_optimiser
from .pareto import dominated, front_levels, hypervolume_2d
from .points import grid_points, n_points, reference_points, run_seed

__all__ = [
    "ENGINES",
    "Optimiser",
    "dominated",
    "front_levels",
    "grid_points",
    "hypervolume_2d",
    "make_optimiser",
    "n_points",
    "reference_points",
    "run_seed",
]
