"""Controllers for any platform: one inverse-dynamics core, model-free control, impedance control.

Each controller is a :class:`~qprr.control.base.Controller` with one method
``step(t, state, ref) -> u`` (u: generalised forces in thesis coordinates, or Pinocchio's tau
for ``output = "pinocchio"``); the simulator (:func:`qprr.sim.simulate`) never needs to know
which one runs.

===============  ======================================================  ================================
name             controller                                              thesis
===============  ======================================================  ================================
``idc``          :class:`InverseDynamicsController`                      Sec. 6.3.1, (6.17)-(6.24)
``dsid``         :class:`DesiredStateInverseDynamics` (thesis: "MPC")     Annex A.2, (A.2)-(A.3)
``mfc``          :class:`ModelFreeController` (iPID)                     Sec. 6.3.3.2, (6.36)-(6.39)
``layered-idc``  :class:`LayeredIDC`                                     Sec. 6.4.2, (6.53)-(6.57), (6.76)
``payload-idc``  :class:`PayloadIDC` (estimated payload mass)            (6.53)-(6.57)
``impedance``    :class:`ImpedanceController`                            Sec. 6.4.3.3, (6.71)-(6.81)
``opspace-       :class:`OperationalSpaceImpedance` (end-effector        (6.72)-(6.73)
impedance``      impedance as a task on the inverse-dynamics core)
===============  ======================================================  ================================

The thesis's gain tables are in :mod:`qprr.thesis.gains`; its CoG stabiliser (BSG) in
:mod:`qprr.thesis.bsg`; a receding-horizon MPC on crocoddyl in :mod:`qprr.control.mpc` (extra ``mpc``).
"""

from __future__ import annotations

from ..errors import UnknownNameError
from ..platform import Platform
from .base import Controller, Reference
from .filters import CommandFilter, SingleTiltReference, TiltReference, tilt_6_17
from .impedance import ImpedanceController, ImpedanceFilter, ImpedanceGains, analytic_wrench
from .inverse_dynamics import (
    DesiredStateInverseDynamics,
    IDCGains,
    InverseDynamicsController,
    LayeredIDC,
    PayloadIDC,
)
from .mfc import MFCGains, ModelFreeController, ipid
from .opspace_impedance import EndEffectorImpedance, OperationalSpaceImpedance

CONTROLLERS = {
    "idc": InverseDynamicsController,
    "dsid": DesiredStateInverseDynamics,
    "mfc": ModelFreeController,
    "layered-idc": LayeredIDC,
    "payload-idc": PayloadIDC,
    "impedance": ImpedanceController,
    "opspace-impedance": OperationalSpaceImpedance,
}
"""Controller classes by name."""


def make_controller(name: str, platform: Platform, **kwargs) -> Controller:
    """A new controller by name (see :data:`CONTROLLERS`); keyword arguments go to its constructor."""
    if name not in CONTROLLERS:
        raise UnknownNameError("controller", name, tuple(CONTROLLERS))
    return CONTROLLERS[name](platform, **kwargs)


__all__ = [
    "CONTROLLERS",
    "CommandFilter",
    "Controller",
    "DesiredStateInverseDynamics",
    "EndEffectorImpedance",
    "IDCGains",
    "ImpedanceController",
    "ImpedanceFilter",
    "ImpedanceGains",
    "InverseDynamicsController",
    "LayeredIDC",
    "MFCGains",
    "ModelFreeController",
    "OperationalSpaceImpedance",
    "PayloadIDC",
    "Reference",
    "SingleTiltReference",
    "TiltReference",
    "analytic_wrench",
    "ipid",
    "make_controller",
    "tilt_6_17",
]
