"""qprr: the Q-PRR aerial manipulator (quadrotor + prismatic/revolute/revolute arm) on Pinocchio.

Thesis: K. Bouzgou, *Contribution a l'architecture, la modelisation et la commande d'un bras
manipulateur aerien*, Universite Paris-Saclay, 2021.  Equation numbers in docstrings refer to it.
"""

from .coordinates import qv_to_xi, xi_to_q, xi_to_qv
from .errors import (
    DivergenceError,
    EulerSingularityError,
    InputError,
    LimitError,
    NonFiniteError,
    NonPhysicalError,
    QprrError,
    ShapeError,
    SolverError,
    UnknownNameError,
)
from .model import Robot, load
from .params import QPRRParams, cad_params, thesis_params

__all__ = [
    "DivergenceError",
    "EulerSingularityError",
    "InputError",
    "LimitError",
    "NonFiniteError",
    "NonPhysicalError",
    "QPRRParams",
    "QprrError",
    "Robot",
    "ShapeError",
    "SolverError",
    "UnknownNameError",
    "cad_params",
    "load",
    "qv_to_xi",
    "thesis_params",
    "xi_to_q",
    "xi_to_qv",
]
__version__ = "0.1.0"
