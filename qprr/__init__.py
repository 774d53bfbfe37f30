"""qprr: aerial manipulators on Pinocchio - any multirotor with any serial arm; the thesis's Q-PRR as flagship.

* :func:`load` a named platform (``"q-prr"``, ``"borinot_flying_arm_2"``, ``"hextilt_flying_arm_5"``),
  :func:`build` one from the thesis nomenclature (2.1) (``"Q-PRR"``, ``"HEX-RRR"``...), or
  :func:`from_urdf` any URDF with a rotor description;
* :mod:`qprr.charts` the thesis coordinates xi = [x, y, z, phi, theta, psi, q_arm];
  :mod:`qprr.kinematics`, :mod:`qprr.dynamics`, :mod:`qprr.actuation` (allocation);
  :mod:`qprr.ik`, :mod:`qprr.control`, :mod:`qprr.sim`, :mod:`qprr.scenarios`;
* :mod:`qprr.thesis`: what only the thesis has (parameters, printed equations and their checks).

Thesis: K. Bouzgou, *Contribution a l'architecture, la modelisation et la commande d'un bras
manipulateur aerien*, Universite Paris-Saclay, 2021.  Equation numbers in docstrings refer to it.
"""

from .charts import qv_to_xi, xi_to_q, xi_to_qv
from .errors import (
    DivergenceError,
    EulerSingularityError,
    InputError,
    LimitError,
    MissingDependencyError,
    NonFiniteError,
    NonPhysicalError,
    QprrError,
    ShapeError,
    SolverError,
    UnknownNameError,
)
from .nomenclature import build
from .platform import ArmJoint, Platform, from_model, from_urdf
from .platforms import load
from .rotors import Rotor

__all__ = [
    "ArmJoint",
    "DivergenceError",
    "EulerSingularityError",
    "InputError",
    "LimitError",
    "MissingDependencyError",
    "NonFiniteError",
    "NonPhysicalError",
    "Platform",
    "QprrError",
    "Rotor",
    "ShapeError",
    "SolverError",
    "UnknownNameError",
    "build",
    "from_model",
    "from_urdf",
    "load",
    "qv_to_xi",
    "xi_to_q",
    "xi_to_qv",
]
__version__ = "0.2.0"
