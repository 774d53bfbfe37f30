"""Closed-loop simulation of any platform (see :mod:`qprr.sim.loop` for the step).

===============================  ==================================================================
module                           what
===============================  ==================================================================
:mod:`qprr.sim.loop`             :func:`simulate` (setup, loop, result)
:mod:`qprr.sim.config`           :class:`SimConfig` (step, integrator, screens, logging: one default each),
                                 :class:`SimInputs`, :class:`Limits`
:mod:`qprr.sim.result`           :class:`SimResult` (RMSE (6.26), extras, versioned .npz files)
:mod:`qprr.sim.integrators`      Lie-group Euler, midpoint, RK4 of the stated orders
:mod:`qprr.sim.disturbances`     white noise (6.27), pulses (6.28), drag
:mod:`qprr.sim.environment`      the stateful-environment interface the simulator integrates
:mod:`qprr.sim.contact`          pushed object, compliant wall, prescribed wrench
:mod:`qprr.sim.payload`          payload changes during a run
:mod:`qprr.sim.stops`            mechanical stops of the arm joints
:mod:`qprr.sim.actuators`        motor lag, speed limits, thrust b w^2 (the optional actuator stage)
:mod:`qprr.sim.wind`             wind (mean, gusts, Dryden), drag D and friction F_v of (5.36)
===============================  ==================================================================
"""

from ..actuation import AllocationFlag
from .actuators import RotorDynamics
from .config import Limits, SimConfig, SimInputs
from .contact import CompliantWall, ContactHistory, PrescribedWrench, PushedMass
from .disturbances import BaseDrag, Disturbance, Disturbances, Pulse, StateDisturbance, WhiteNoise
from .environment import Environment
from .integrators import INTEGRATORS, ORDERS, STEPPERS, Integrator
from .loop import simulate
from .payload import PayloadChange, PayloadSchedule
from .result import FORMAT_VERSION, SimResult, Status
from .wind import AerodynamicDrag, Dryden, Gust, ViscousFriction, Wind

__all__ = [
    "FORMAT_VERSION",
    "AllocationFlag",
    "INTEGRATORS",
    "Integrator",
    "ORDERS",
    "STEPPERS",
    "AerodynamicDrag",
    "BaseDrag",
    "CompliantWall",
    "ContactHistory",
    "Disturbance",
    "Disturbances",
    "Dryden",
    "Environment",
    "Gust",
    "Limits",
    "PayloadChange",
    "PayloadSchedule",
    "PrescribedWrench",
    "Pulse",
    "PushedMass",
    "RotorDynamics",
    "SimConfig",
    "SimInputs",
    "SimResult",
    "StateDisturbance",
    "Status",
    "ViscousFriction",
    "WhiteNoise",
    "Wind",
    "simulate",
]
