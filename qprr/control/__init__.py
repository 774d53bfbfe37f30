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
``decoupled``    :class:`DecoupledController` (multirotor + fixed-base   Sec. 6.2.2, Fig. 6.2, (5.53)
                 arm controllers, coupling as a disturbance)
``mpc``          :class:`qprr.control.mpc.MPCController` (receding        not in the thesis (its "MPC" is
                 horizon, thrust bounds; needs crocoddyl)                ``dsid``)
``opspace-       :class:`OperationalSpaceImpedance` (end-effector        (6.72)-(6.73)
impedance``      impedance as a task on the inverse-dynamics core)
===============  ======================================================  ================================

The registry :data:`CONTROLLERS` (:mod:`qprr.control.registry`) holds these and the plug-ins' controllers, each with
how its gains follow from a platform (:class:`DerivedGains`) or why it has none (:class:`NoGains`); adding a
controller is one file (docs/extending.md).

Default gains: :func:`make_controller` derives them from the platform (:func:`qprr.control.gains.platform_gains`:
critically damped poles (s + w)^2, (s + w)^3 with bandwidths w from the thrust, torque and joint effort
authority); the classes' own defaults (``IDCGains.default`` ...) apply only when a class is built
directly.  The thesis's gain tables are in :mod:`qprr.thesis.gains`; its CoG stabiliser (BSG) in
:mod:`qprr.thesis.bsg`.  ``mpc`` is registered only when crocoddyl can be imported (the
``mpc`` extra, docs/mpc.md); otherwise :func:`make_controller` raises
:class:`~qprr.errors.MissingDependencyError` with the install command.
"""

from __future__ import annotations

from importlib.util import find_spec

from ..errors import MissingDependencyError, UnknownNameError
from ..model import Platform
from .base import Controller, Reference
from .decoupled import DecoupledController, lock_arm
from .filters import CommandFilter, SingleTiltReference, TiltReference, tilt_6_17
from .gains import derive_decoupled, derive_dsid, derive_idc, derive_impedance, derive_mfc, derive_opspace_impedance, platform_gains, replace_fields
from .impedance import ImpedanceController, ImpedanceFilter, ImpedanceGains, analytic_wrench
from .inverse_dynamics import (
    AntiWindup,
    DesiredStateInverseDynamics,
    IDCGains,
    InverseDynamicsController,
    LayeredIDC,
    PayloadAwareness,
    PayloadIDC,
)
from .mfc import MFCGains, ModelFreeController, ipid
from .mpc_stats import INSTALL as _MPC_INSTALL
from .opspace_impedance import EndEffectorImpedance, OperationalSpaceImpedance
from .registry import CONTROLLERS, DEFAULT_CONTROLLER, GAIN_ARGUMENTS, ControllerEntry, DerivedGains, NoGains

MPC_INSTALL = _MPC_INSTALL
"""Install command of the ``mpc`` extra (docs/mpc.md): crocoddyl with the pinocchio its wheel is built for."""

OPTIONAL = {"mpc": ("crocoddyl", "the receding-horizon MPC (controller 'mpc')", MPC_INSTALL)}
"""Controllers that need an optional dependency: name -> (package, purpose, install command)."""


def _mpc(platform: Platform, **kwargs) -> Controller:
    """:class:`qprr.control.mpc.MPCController` (imported on first use: crocoddyl takes ~0.8 s to import); ``weights`` and
    ``settings`` given as tables of fields (a gains file's ``[mpc.weights]``, ``[mpc.settings]``) replace fields of
    the platform's default weights (:func:`qprr.control.mpc.platform_weights`) and of :class:`~qprr.control.mpc.MPCSettings`."""
    from .mpc import MPCController, MPCSettings, platform_weights

    if isinstance(kwargs.get("weights"), dict):
        kwargs["weights"] = replace_fields(platform_weights(platform), kwargs["weights"], platform.n_xi, "mpc.weights")
    if isinstance(kwargs.get("settings"), dict):
        kwargs["settings"] = replace_fields(MPCSettings(), kwargs["settings"], platform.n_xi, "mpc.settings")
    return MPCController(platform, **kwargs)


_IDC = DerivedGains(("gains",), derive_idc)
_CORE = {
    "idc": ControllerEntry(InverseDynamicsController, _IDC, "inverse dynamics (6.17)-(6.24)"),
    "dsid": ControllerEntry(DesiredStateInverseDynamics, DerivedGains(("gains",), derive_dsid), "desired-state inverse dynamics (A.2)-(A.3)"),
    "mfc": ControllerEntry(ModelFreeController, DerivedGains(("gains",), derive_mfc), "model-free control, iPID (6.36)-(6.39)"),
    "layered-idc": ControllerEntry(LayeredIDC, _IDC, "layered IDC with force feedback (6.53)-(6.57), (6.76)"),
    "payload-idc": ControllerEntry(PayloadIDC, _IDC, "IDC with an estimated payload mass (6.53)-(6.57)"),
    "impedance": ControllerEntry(
        ImpedanceController, DerivedGains(("gains", "impedance"), derive_impedance), "impedance filters on the IDC (6.71)-(6.81)"
    ),
    "decoupled": ControllerEntry(
        DecoupledController, DerivedGains(("gains",), derive_decoupled), "multirotor + fixed-base arm controllers, coupling as a disturbance"
    ),
    "opspace-impedance": ControllerEntry(
        OperationalSpaceImpedance, DerivedGains(("impedance",), derive_opspace_impedance), "end-effector impedance (6.72)-(6.73)"
    ),
}
"""The core's controllers (registered into :data:`CONTROLLERS` below; ``mpc`` too when crocoddyl is installed)."""
if find_spec("crocoddyl") is not None:  # registered only when the optional dependency is installed
    _MPC_GAINS = NoGains(
        "cost weights and a horizon of its own, not gains; its default weights follow the platform's hover thrusts "
        "(qprr.control.mpc.platform_weights), not bandwidth targets",
        ("weights", "settings"),
    )
    _CORE["mpc"] = ControllerEntry(_mpc, _MPC_GAINS, "receding-horizon MPC")
for _name, _entry in _CORE.items():
    CONTROLLERS.register(_name, _entry)
del _name, _entry


def make_controller(name: str, platform: Platform, *, defaults: str = "platform", **kwargs) -> Controller:
    """A new controller by name (see :data:`CONTROLLERS`) with gains derived from ``platform``; keyword arguments
    go to its constructor.

    Default gains: for every controller whose entry has :class:`DerivedGains` (:data:`GAIN_ARGUMENTS`: all the
    core's but ``mpc``, which has cost weights, mapped onto the platform by :func:`qprr.control.mpc.platform_weights`),
    ``platform_gains(name, platform)``: each coordinate of xi gets a
    bandwidth w from the platform's actuator authority at its neutral configuration and a critically damped error
    polynomial, (s + w)^3 on roll, pitch, yaw (k_D = 3 w, k_P = 3 w^2, k_I = w^3) and (s + w)^2 on position and arm
    (k_D = 2 w, k_P = w^2); the impedance filters get M = the moved inertia, K = M w^2, D = 2 M w (the
    formulas for w: :mod:`qprr.control.gains`).  An explicit ``gains=`` or ``impedance=`` replaces that
    argument only (the other stays derived); ``gains=IDCGains.default(n_arm)`` gives the class's fixed
    defaults, ``qprr.thesis.gains`` the thesis's tables.  ``opspace-impedance``'s derived impedance has a
    desired mass (m / ratio^2), so it needs ``ee_sensor`` (the contact force).  A platform whose rotors cannot hover it has no
    derived gains: :class:`~qprr.errors.InputError` (pass ``gains=`` explicitly).

    ``defaults="class"``: the gains not given are the controller class's own fixed defaults instead (tuned for the
    Q-PRR), nothing derived.  The MPC has no gains, so both choices build it the same: its class's default weights are
    the Q-PRR's mapped onto the platform (:func:`qprr.control.mpc.platform_weights`); ``weights=MPCWeights()`` gives
    the Q-PRR's unmapped.

    An optional controller whose dependency is missing raises :class:`~qprr.errors.MissingDependencyError`
    with the install command.
    """
    if name not in CONTROLLERS:
        if name in OPTIONAL:
            raise MissingDependencyError(*OPTIONAL[name])
        raise UnknownNameError("controller", name, tuple(CONTROLLERS))
    if defaults not in ("platform", "class"):
        raise UnknownNameError("gain defaults of make_controller", defaults, ("platform", "class"))
    entry = CONTROLLERS[name]
    missing = [arg for arg in entry.gain_arguments if arg not in kwargs] if defaults == "platform" else []
    if missing:
        derived = platform_gains(name, platform)
        kwargs = {**{arg: derived[arg] for arg in missing}, **kwargs}
    return entry.factory(platform, **kwargs)


__all__ = [
    "AntiWindup",
    "CONTROLLERS",
    "DEFAULT_CONTROLLER",
    "GAIN_ARGUMENTS",
    "CommandFilter",
    "Controller",
    "ControllerEntry",
    "DecoupledController",
    "DerivedGains",
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
    "NoGains",
    "OperationalSpaceImpedance",
    "PayloadAwareness",
    "PayloadIDC",
    "Reference",
    "SingleTiltReference",
    "TiltReference",
    "analytic_wrench",
    "ipid",
    "lock_arm",
    "make_controller",
    "tilt_6_17",
]
