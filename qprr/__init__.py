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
:class:`Platform`, :func:`make_controller`, the references (:class:`Hold`, :class:`Phase`, :class:`MultiPhase`,
:class:`Spiral`), :func:`simulate` with its settings (:class:`SimConfig`, :class:`SimInputs`) and its
:class:`SimResult`, :class:`IKSolver`, :class:`Allocator`, and :class:`QprrError`, the base of every qprr error.
All but the platform model are loaded on first access (the module's ``__getattr__``, :data:`LAZY`): ``import qprr``
stays as fast as the model alone, and ``qprr.simulate is qprr.sim.simulate``.

Deprecated: the names of :data:`DEPRECATED` (the other exceptions, :class:`~qprr.model.ArmJoint`,
:class:`~qprr.rotors.Rotor`, :func:`~qprr.model.from_model`, the coordinate maps ``xi_to_q``, ``xi_to_qv``,
``qv_to_xi``), kept here for code written against earlier versions: deprecated since 0.2.0, each access warns
(:class:`DeprecationWarning`) naming their home (``qprr.errors.InputError``, ``qprr.charts.xi_to_q``...); they are
removed in qprr :data:`REMOVED_IN`.

Thesis: K. Bouzgou, *Contribution a l'architecture, la modelisation et la commande d'un bras
manipulateur aerien*, Universite Paris-Saclay, 2021.  Equation numbers in docstrings refer to it.
"""

import warnings
from importlib import import_module

from . import charts as charts  # the submodules the deprecated names live in stay loaded (qprr.charts.xi_to_q)
from . import errors as errors
from . import rotors as rotors
from .errors import QprrError
from .model import Platform, from_urdf
from .nomenclature import build
from .platforms import load
from .version import __version__ as __version__

LAZY = {
    "simulate": "qprr.sim",
    "SimConfig": "qprr.sim",
    "SimInputs": "qprr.sim",
    "SimResult": "qprr.sim",
    "make_controller": "qprr.control",
    "IKSolver": "qprr.ik",
    "Allocator": "qprr.actuation",
    "Hold": "qprr.trajectory",
    "Phase": "qprr.trajectory",
    "MultiPhase": "qprr.trajectory",
    "Spiral": "qprr.trajectory",
}
"""Names of the public face loaded on first access: name -> the module that defines it (imported then)."""

REMOVED_IN = "0.4.0"
"""The version that removes the names of :data:`DEPRECATED` from the package."""

DEPRECATED = {
    **{
        name: "qprr.errors"
        for name in (
            "DivergenceError",
            "EulerSingularityError",
            "InputError",
            "LimitError",
            "MissingDependencyError",
            "NonFiniteError",
            "NonPhysicalError",
            "ShapeError",
            "SolverError",
            "UnknownNameError",
        )
    },
    "ArmJoint": "qprr.model",
    "from_model": "qprr.model",
    "Rotor": "qprr.rotors",
    "xi_to_q": "qprr.charts",
    "xi_to_qv": "qprr.charts",
    "qv_to_xi": "qprr.charts",
}
"""Names importable from ``qprr`` before 0.2.0, deprecated since 0.2.0 and removed in :data:`REMOVED_IN`: name -> the
module that is their home (each access warns, naming it)."""


def __getattr__(name: str):
    """``qprr.simulate`` and the other names of :data:`LAZY`: import their module on first access (then cached here).
    A name of :data:`DEPRECATED`: its object, with a :class:`DeprecationWarning` naming its home."""
    if name in LAZY:
        value = getattr(import_module(LAZY[name]), name)
        globals()[name] = value
        return value
    if name in DEPRECATED:
        home = DEPRECATED[name]
        warnings.warn(f"qprr.{name} is deprecated and will be removed in qprr {REMOVED_IN}: use {home}.{name}", DeprecationWarning, stacklevel=2)
        return getattr(import_module(home), name)
    raise AttributeError(f"module 'qprr' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *LAZY})


__all__ = [
    "Allocator",
    "Hold",
    "IKSolver",
    "MultiPhase",
    "Phase",
    "Platform",
    "QprrError",
    "SimConfig",
    "SimInputs",
    "SimResult",
    "Spiral",
    "build",
    "from_urdf",
    "load",
    "make_controller",
    "simulate",
]
