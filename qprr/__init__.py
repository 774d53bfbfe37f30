"""qprr: aerial manipulators on Pinocchio - any multirotor with any serial arm; the thesis's Q-PRR as flagship.

* :func:`load` a named platform (``"q-prr"``, ``"borinot_flying_arm_2"``, ``"hextilt_flying_arm_5"``),
  :func:`build` one from the thesis nomenclature (2.1) (``"Q-PRR"``, ``"HEX-RRR"``...), or
  :func:`from_urdf` any URDF with a rotor description;
* :mod:`qprr.charts` the thesis coordinates xi = [x, y, z, phi, theta, psi, q_arm];
  :mod:`qprr.kinematics`, :mod:`qprr.dynamics`, :mod:`qprr.actuation` (allocation);
  :mod:`qprr.ik`, :mod:`qprr.control`, :mod:`qprr.sim`, :mod:`qprr.scenarios`;
* :mod:`qprr.thesis`: what only the thesis has (parameters, printed equations and their checks), a
  plug-in that fills the core's registries (:mod:`qprr.registry`); the core never imports it.

The workflow in one import (``__all__``): :func:`load`, :func:`build`, :func:`from_urdf`,
:class:`Platform`, :func:`make_controller`, :func:`simulate` and its :class:`SimResult`,
:class:`IKSolver`, :class:`Allocator`, and :class:`QprrError`, the base of every qprr error.
``simulate``, ``SimResult``, ``make_controller``, ``IKSolver`` and ``Allocator`` are loaded on first
access (the module's ``__getattr__``, :data:`LAZY`): ``import qprr`` stays as fast as the model
alone, and ``qprr.simulate is qprr.sim.simulate``.  Also importable from here for existing code: the
other exceptions of :mod:`qprr.errors`, :class:`ArmJoint`, :class:`Rotor`, :func:`from_model` and the
coordinate maps :func:`xi_to_q`, :func:`xi_to_qv`, :func:`qv_to_xi`.

Thesis: K. Bouzgou, *Contribution a l'architecture, la modelisation et la commande d'un bras
manipulateur aerien*, Universite Paris-Saclay, 2021.  Equation numbers in docstrings refer to it.
"""

from importlib import import_module

from .charts import qv_to_xi as qv_to_xi
from .charts import xi_to_q as xi_to_q
from .charts import xi_to_qv as xi_to_qv
from .errors import DivergenceError as DivergenceError
from .errors import EulerSingularityError as EulerSingularityError
from .errors import InputError as InputError
from .errors import LimitError as LimitError
from .errors import MissingDependencyError as MissingDependencyError
from .errors import NonFiniteError as NonFiniteError
from .errors import NonPhysicalError as NonPhysicalError
from .errors import QprrError
from .errors import ShapeError as ShapeError
from .errors import SolverError as SolverError
from .errors import UnknownNameError as UnknownNameError
from .model import ArmJoint as ArmJoint
from .model import Platform, from_urdf
from .model import from_model as from_model
from .nomenclature import build
from .platforms import load
from .rotors import Rotor as Rotor
from .version import __version__ as __version__

LAZY = {
    "simulate": "qprr.sim",
    "SimResult": "qprr.sim",
    "make_controller": "qprr.control",
    "IKSolver": "qprr.ik",
    "Allocator": "qprr.actuation",
}
"""Names of the public face loaded on first access: name -> the module that defines it (imported then)."""


def __getattr__(name: str):
    """``qprr.simulate`` and the other names of :data:`LAZY`: import their module on first access (then cached here)."""
    if name not in LAZY:
        raise AttributeError(f"module 'qprr' has no attribute {name!r}")
    value = getattr(import_module(LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *LAZY})


__all__ = [
    "Allocator",
    "IKSolver",
    "Platform",
    "QprrError",
    "SimResult",
    "build",
    "from_urdf",
    "load",
    "make_controller",
    "simulate",
]
