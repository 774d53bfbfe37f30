"""Controllers of Thesis Chapter 6.

Each controller is a :class:`~qprr.control.base.Controller` with one method
``step(t, state, ref) -> u`` (u: generalised forces in thesis coordinates); the simulator
(:func:`qprr.sim.simulate`) never needs to know which one runs.

========  ============================================================  ===================
name      controller                                                    thesis
========  ============================================================  ===================
``idc``   :class:`InverseDynamicsController`                            Sec. 6.3.1, (6.17)-(6.24)
``dsid``  :class:`DesiredStateInverseDynamics` (the thesis's "MPC")      Annex A.2, (A.2)-(A.3)
``mfc``   :class:`ModelFreeController` (iPID)                           Sec. 6.3.3.2, (6.36)-(6.39)
========  ============================================================  ===================

:class:`CogStabilizer` (BSG, Sec. 6.3.3.1) wraps any of them.
"""

from __future__ import annotations

from ..errors import UnknownNameError
from ..model import Robot
from .base import CommandFilter, Controller, Reference, State
from .bsg import CogStabilizer, cog_betas, x_cm_thesis
from .idc import DesiredStateInverseDynamics, IDCGains, InverseDynamicsController
from .mfc import MFCGains, ModelFreeController, ipid, ipid_thesis_printed

CONTROLLERS = {
    "idc": InverseDynamicsController,
    "dsid": DesiredStateInverseDynamics,
    "mfc": ModelFreeController,
}
"""Controller classes by name."""

THESIS_NAMES = {"idc": "IDC", "dsid": "MPC", "mfc": "MFC"}
"""What the thesis calls each controller (Table 6.3 columns)."""


def make_controller(name: str, robot: Robot, **kwargs) -> Controller:
    """A new controller by name (``idc``, ``dsid``, ``mfc``); keyword arguments go to its constructor."""
    if name not in CONTROLLERS:
        raise UnknownNameError("controller", name, tuple(CONTROLLERS))
    return CONTROLLERS[name](robot, **kwargs)


__all__ = [
    "CONTROLLERS",
    "THESIS_NAMES",
    "CogStabilizer",
    "CommandFilter",
    "Controller",
    "DesiredStateInverseDynamics",
    "IDCGains",
    "InverseDynamicsController",
    "MFCGains",
    "ModelFreeController",
    "Reference",
    "State",
    "cog_betas",
    "ipid",
    "ipid_thesis_printed",
    "make_controller",
    "x_cm_thesis",
]
