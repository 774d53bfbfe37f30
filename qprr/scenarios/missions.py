"""Generic mission scenarios: any platform (named, built or loaded from a URDF), gains derived from it.

Every scenario here runs on the platform it is given (``qprr simulate NAME --platform P`` or
``--urdf F --rotors F.toml``), with the gains of :func:`qprr.control.gains.platform_gains` unless
the option ``gains`` names others, and scales its timing with ``duration`` (so a 2 s run and a
20 s run fly the same mission, faster or slower).  Each records the physical check it reaches in
``result.metrics`` and reports it in its summary.

==================  ==========================================================================
scenario            what (check in ``result.metrics``)
==================  ==========================================================================
``takeoff-hover``   climb from the ground to ``z`` in the first 40 % of the run, hold
                    (``final_position_error`` [m])
``fly-to``          climb, then move the base to ``target`` and the arm ``reach_fraction`` of
                    the way to its upper limits (``final_position_error``, ``final_arm_error``)
``mission``         phases of base and arm coordinates by name given as data (a TOML file or a
                    mapping of tables: :mod:`qprr.scenarios.mission_file`), with payload grasps and
                    releases, wind, gusts, drag, motor lag and the controller, flown as written
``grasp-drop``      hover with the arm reached out; a mass attaches at the end effector
                    (grasp), then drops (``final_position_error`` after the drop,
                    ``max_position_error``)
``ee-push``         the end effector pushed into a compliant wall under end-effector impedance
                    (``contact_force`` against ``predicted_force``, two springs in series)
``hover-wind``      hover under a mean wind and a 1 - cos gust on the base's drag
``motor-lag``       point-to-point through first-order rotor dynamics (time constant ``tau``)
``hover-noise``     hover under uniform white noise on every generalised force (Thesis (6.27)),
                    ``fraction`` of each coordinate's authority
``hover-pulses``    hover hit by force pulses on z, then x and y, then the arm (Thesis (6.28))
==================  ==========================================================================

The option ``gains``: ``"platform"`` (derived, the default), ``"class"`` (the controller class's
own defaults), a name of :data:`qprr.registry.GAIN_TABLES` or a TOML file (:func:`qprr.control.gains.load_gains`);
from Python also a gains object (``IDCGains``, ``MFCGains``, ``ImpedanceGains``, ``EndEffectorImpedance``).

Plug-ins reproduce a study's runs as instances of these scenarios: the functions take, besides the
options, a :class:`MissionSettings` (the reference flown, a built controller, a disturbance, the
plant, the result's name), :func:`noise` absolute ``amplitude`` s and :func:`pulses` a ``train`` of
pulses; :func:`phase_tables` turns phases into the data :func:`mission` reads.  The thesis's
Chapter 6 flights on the Q-PRR are built so (:mod:`qprr.thesis.scenarios`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from ..control import CONTROLLERS, PayloadAwareness, make_controller
from ..control.base import Controller
from ..control.gains import GAIN_ARGUMENTS, platform_gains
from ..control.gains import load_gains as load_gain_file
from ..control.impedance import ImpedanceGains
from ..control.inverse_dynamics import IDCGains, InverseDynamicsController, LayeredIDC
from ..control.mfc import MFCGains
from ..control.opspace_impedance import EndEffectorImpedance
from ..errors import InputError, ScheduleWarning, UnknownNameError
from ..kinematics import ee_pose_xi
from ..model import Platform, check_platform, max_lift
from ..registry import SCENARIOS
from ..sim import simulate
from ..sim.actuators import RotorDynamics, rotor_dynamics_from_mapping
from ..sim.contact import CompliantWall
from ..sim.disturbances import Disturbances, Pulse, WhiteNoise
from ..sim.payload import PayloadChange, PayloadSchedule
from ..sim.wind import AerodynamicDrag, Gust, Wind
from ..trajectory import Hold, MultiPhase, Phase, Trajectory
from ..urdf.plausibility import DEFAULT, Plausibility, check_plausibility_setting, check_time_constant
from ..validation import as_name, as_real, as_vector
from .mission_file import PAYLOAD_KEYS, PHASE_KEYS, MissionFile, motor_stage_of, read_mission_file

_GAIN_TYPES = (IDCGains, MFCGains, ImpedanceGains, EndEffectorImpedance)


@dataclass(frozen=True)
class MissionSettings:
    """What a Python caller (a plug-in reproducing a study) sets on a generic mission beyond its options.

    ``trajectory``: the reference flown instead of the scenario's own (an object with ``sample(t)``,
    :mod:`qprr.trajectory`); the recorded errors are then measured against it.  ``controller``: a built
    :class:`~qprr.control.base.Controller` flown instead of ``controller_for(name, platform, gains)``
    (a wrapper such as a CoG stabiliser, a variant); the option ``gains`` is then not read.
    ``disturbance``: a generalised-force disturbance (:mod:`qprr.sim.disturbances`); a scenario that has
    its own (hover-noise, hover-pulses, hover-wind) refuses it.  ``plant``: the robot flown when it
    differs from the controller's model (:func:`qprr.sim.simulate`).  ``name``: the result's scenario
    name ("" keeps the scenario's own).  None everywhere: the scenario as registered.  ``plausibility``: the ranges
    the inputs a mission adds are checked against (the motor time constant of ``motor-lag``; None: no range check).
    """

    trajectory: object = None
    controller: Controller | None = None
    disturbance: object = None
    plant: Platform | None = None
    name: str = ""
    plausibility: Plausibility | None = DEFAULT

    def __post_init__(self) -> None:
        if self.trajectory is not None and not isinstance(self.trajectory, Trajectory):
            raise InputError(f"MissionSettings.trajectory must have sample(t) (a qprr.trajectory object), got {type(self.trajectory).__name__}")
        if self.controller is not None and not isinstance(self.controller, Controller):
            raise InputError(f"MissionSettings.controller must be a qprr Controller (make_controller), got {type(self.controller).__name__}")
        if self.plant is not None and not isinstance(self.plant, Platform):
            raise InputError(f"MissionSettings.plant must be a qprr Platform, got {type(self.plant).__name__}")
        if not isinstance(self.name, str):
            raise InputError(f"MissionSettings.name must be a string, got {self.name!r}")
        check_plausibility_setting(self.plausibility)


_AS_REGISTERED = MissionSettings()


# ------------------------------------------------------------------------- building blocks
def gain_arguments(name: str, platform: Platform, gains) -> dict[str, object]:
    """The constructor keyword arguments of controller ``name`` for the gain set ``gains`` (module docstring; "class": none;
    a mapping: a gains file's tables, :func:`qprr.control.gains.load_gains`).

    A gains object (:data:`_GAIN_TYPES`) is passed as is: ``gains=`` or, for impedance gains, ``impedance=`` (refused
    when controller ``name`` takes no such argument, :data:`qprr.control.gains.GAIN_ARGUMENTS`)."""
    if isinstance(gains, _GAIN_TYPES):
        arg = "impedance" if isinstance(gains, (ImpedanceGains, EndEffectorImpedance)) else "gains"
        takes = GAIN_ARGUMENTS.get(name, ())
        if arg not in takes:
            raise InputError(f"gains {type(gains).__name__} do not fit controller {name!r} (it takes {', '.join(takes) or 'no gains'})")
        return {arg: gains}
    if isinstance(gains, Mapping):  # a gains file's tables given inline (a campaign's gains = { targets = { ... } })
        return load_gain_file(gains, name, platform, "the gains tables")
    if not isinstance(gains, str):
        raise InputError(
            f"gains must be 'platform', 'class', a registered gain table, a TOML file, its tables or a gains object of qprr.control, got {gains!r}"
        )
    if gains == "platform":
        return platform_gains(name, platform)
    if gains.endswith(".toml"):
        return load_gain_file(gains, name, platform)
    if gains == "class":
        return {}
    from ..registry import GAIN_TABLES

    table = GAIN_TABLES[gains]()
    if not isinstance(table, _GAIN_TYPES):
        raise InputError(f"gain table {gains!r} gives a {type(table).__name__}, not gains of qprr.control")
    return gain_arguments(name, platform, table)


def controller_for(name: str, platform: Platform, gains, **kwargs):
    """``make_controller(name, platform)`` with the gain set ``gains`` (:func:`gain_arguments`; "class": the class's own
    defaults, nothing derived); ``kwargs`` to the constructor."""
    defaults = "class" if gains == "class" else "platform"
    return make_controller(name, platform, defaults=defaults, **{**gain_arguments(name, platform, gains), **kwargs})


def reach_posture(platform: Platform, fraction: float) -> np.ndarray:
    """Arm joints ``fraction`` of the way from the neutral posture to the upper limits (neutral + 1 where unlimited)."""
    platform = check_platform(platform)
    if not (isinstance(fraction, (int, float)) and 0.0 <= fraction <= 1.0):
        raise InputError(f"reach_fraction must be in [0, 1], got {fraction!r}")
    q0 = platform.neutral_q()[7:]
    hi = np.where(np.isfinite(platform.arm_upper), platform.arm_upper, q0 + 1.0)
    return q0 + fraction * (hi - q0)


def _platform(platform: Platform | None) -> Platform:
    from ..platforms import load

    return load() if platform is None else platform


def fly(platform: Platform, ctrl, trajectory, o: dict, progress: bool, name: str, settings: MissionSettings = _AS_REGISTERED, **inputs):
    """:func:`qprr.sim.simulate` of a mission: options ``o`` (``duration``, ``dt``, ``integrator``, ``seed``), the
    result named ``name`` unless ``settings`` names it, ``settings.disturbance`` and ``settings.plant`` added to
    ``inputs`` (:class:`qprr.sim.SimInputs` fields; one the scenario sets itself cannot be replaced)."""
    if not isinstance(settings, MissionSettings):
        raise InputError(f"settings must be a MissionSettings, got {type(settings).__name__}")
    for key, value in (("disturbance", settings.disturbance), ("plant", settings.plant)):
        if value is not None:
            if inputs.get(key) is not None:
                raise InputError(f"scenario {name!r} sets its own {key}: MissionSettings.{key} cannot replace it (leave it None)")
            inputs[key] = value
    return simulate(
        platform,
        ctrl,
        trajectory,
        o["duration"],
        dt=o["dt"],
        integrator=o["integrator"],
        seed=o["seed"],
        progress=progress,
        scenario=settings.name or name,
        **inputs,
    )


def _controller(name: str, platform: Platform, o: dict, settings: MissionSettings, payload: PayloadSchedule | None = None, **kwargs):
    """``settings.controller`` if given, else ``controller_for(name, platform, o["gains"], **kwargs)`` told about the
    payload as the option ``payload_model`` says (:func:`payload_awareness`; ``payload``: the mission's events)."""
    if settings.controller is not None:
        return _built(settings, o)
    return controller_for(name, platform, o["gains"], **payload_awareness(name, o, payload), **kwargs)


def _built(settings: MissionSettings, o: dict):
    """``settings.controller``, flown as it is: refused with a ``payload_model`` it would not hear."""
    if o.get("payload_model", PAYLOAD_MODELS[0]) != PAYLOAD_MODELS[0]:
        raise InputError(
            f"payload_model = {o['payload_model']!r} and MissionSettings.controller: the built controller is flown as it is; "
            "give it its PayloadAwareness yourself, or leave payload_model out"
        )
    return settings.controller


# ------------------------------------------------------------------------- payload awareness (issue 35)
PAYLOAD_MODELS = ("unknown", "announced", "estimate")
"""The option ``payload_model`` of the generic missions, the first the default: ``unknown`` (the controller's model has no
payload; integral action, :mod:`qprr.control.gains`, rejects it), ``announced`` (the mission's payload events are told to
the controller's model, (6.40)), ``estimate`` (the controller estimates the mass online, Thesis Sec. 6.4.2)."""


def payload_awareness(controller: str, o: dict, payload: PayloadSchedule | None) -> dict[str, object]:
    """The keyword ``payload_awareness`` (:class:`qprr.control.PayloadAwareness`) of an inverse-dynamics controller for the
    option ``payload_model`` (:data:`PAYLOAD_MODELS`; absent: the default), {} for ``unknown``.  A controller that is
    not the inverse-dynamics core (``mfc``, ``payload-idc`` with its own estimator ...) is refused for the others."""
    if not isinstance(o, Mapping):
        raise InputError(f"o must be the mission's options (a mapping of option name -> value), got {type(o).__name__}")
    if payload is not None and not isinstance(payload, PayloadSchedule):
        raise InputError(f"payload must be the mission's qprr.sim.PayloadSchedule or None, got {type(payload).__name__}")
    mode = o.get("payload_model", PAYLOAD_MODELS[0])
    if not isinstance(mode, str) or mode not in PAYLOAD_MODELS:
        raise UnknownNameError("payload_model", mode, PAYLOAD_MODELS)
    if mode == PAYLOAD_MODELS[0]:
        return {}
    factory = CONTROLLERS[controller].factory
    if not (isinstance(factory, type) and issubclass(factory, InverseDynamicsController) and not issubclass(factory, LayeredIDC)):
        raise InputError(
            f"payload_model = {mode!r} needs an inverse-dynamics controller (idc, dsid), not {controller!r}; "
            "use payload_model = 'unknown' (integral action) or controller payload-idc (its own estimator)"
        )
    if mode == "estimate":
        return {"payload_awareness": PayloadAwareness(estimate=True)}
    events = tuple((c.time, c.mass) for c in payload.changes) if payload is not None else ()
    if not events:
        raise InputError(
            "payload_model = 'announced' tells the controller the mission's payload events, and this mission has none "
            "(grasp-drop and a mission file's [[payload]] tables have); leave payload_model out"
        )
    return {"payload_awareness": PayloadAwareness(announced=events)}


def _errors(res) -> None:
    """Record the final position and arm errors against the reference at the run's last tick (the mission's end when
    its phases end within the run, as every registered mission's do) and the largest position error."""
    e = res.xi[-1] - res.xi_d[-1]
    res.metrics["final_position_error"] = float(np.linalg.norm(e[0:3]))
    res.metrics["final_arm_error"] = float(np.max(np.abs(e[6:]))) if e.shape[0] > 6 else 0.0
    res.metrics["max_position_error"] = float(np.max(np.linalg.norm(res.xi[:, 0:3] - res.xi_d[:, 0:3], axis=1)))


def _hover_xi(platform, o: dict) -> np.ndarray:
    return np.concatenate([[0.0, 0.0, float(o["z"]), 0.0, 0.0, 0.0], reach_posture(platform, o["reach_fraction"])])


def _hover(platform, o: dict, settings: MissionSettings):
    """The reference of a hovering scenario: ``settings.trajectory`` if given, else a hold at ``z`` with the arm out."""
    return settings.trajectory if settings.trajectory is not None else Hold(tuple(_hover_xi(platform, o)))


def phase_tables(phases) -> list[dict]:
    """The tables of :func:`read_mission` (keys :data:`PHASE_KEYS`) of ``phases`` (:class:`qprr.trajectory.Phase`): a mission
    built in Python, as data (a TOML file's ``[[phase]]`` tables, or ``mission(..., mission={"phase": phase_tables(...)})``)."""
    out = []
    for p in phases:
        if not isinstance(p, Phase):
            raise InputError(f"phase_tables takes qprr.trajectory.Phase objects, got {type(p).__name__}")
        out.append({"coordinate": p.coordinate, "start": p.t1, "end": p.t2, "target": p.value})
    return out


# ------------------------------------------------------------------------- the scenarios
def takeoff_hover(platform=None, controller="idc", progress=False, settings: MissionSettings = _AS_REGISTERED, **o):
    """Climb from z = 0 to ``z`` over the first 40 % of the run (transition law ``law``), then hold."""
    platform = _platform(platform)
    xi0 = platform.neutral_xi()
    D = o["duration"]
    traj = settings.trajectory
    if traj is None:
        traj = MultiPhase((Phase("z", 0.0, 0.4 * D, o["z"]),), tuple(xi0), name="takeoff-hover", law=o["law"], names=platform.xi_names)
    res = fly(platform, _controller(controller, platform, o, settings), traj, o, progress, "takeoff-hover", settings)
    _errors(res)
    return res


def fly_to(platform=None, controller="idc", progress=False, settings: MissionSettings = _AS_REGISTERED, **o):
    """Climb to ``target``'s height (first 30 %), then fly to ``target`` while the arm reaches out (30-70 %), hold."""
    platform = _platform(platform)
    if settings.trajectory is not None:
        res = fly(platform, _controller(controller, platform, o, settings), settings.trajectory, o, progress, "fly-to", settings)
        _errors(res)
        return res
    D = o["duration"]
    x, y, z = _target(o["target"])
    xi0 = platform.neutral_xi()
    q = reach_posture(platform, o["reach_fraction"])
    phases = [Phase("z", 0.0, 0.3 * D, z), Phase("x", 0.3 * D, 0.7 * D, x), Phase("y", 0.3 * D, 0.7 * D, y)]
    phases += [Phase(n, 0.3 * D, 0.7 * D, float(v)) for n, v in zip(platform.arm_names, q)]
    traj = MultiPhase(tuple(phases), tuple(xi0), name="fly-to", law=o["law"], names=platform.xi_names)
    res = fly(platform, _controller(controller, platform, o, settings), traj, o, progress, "fly-to", settings)
    _errors(res)
    return res


def _target(value) -> tuple[float, float, float]:
    """The option ``target``: the base position (x, y, z) [m] to reach, world frame."""
    if isinstance(value, (str, bytes)) or np.ndim(value) != 1 or np.size(value) != 3:
        raise InputError(f"target must be the base position (x, y, z) [m] to reach, three numbers, got {value!r}; e.g. target=(1.0, 0.5, 2.0)")
    x, y, z = as_vector(value, 3, "target").tolist()
    return x, y, z


def check_mission_schedule(platform: Platform, phases, payload: PayloadSchedule | None, duration: float, gusts=()) -> None:
    """Say what a run of ``duration`` [s] would silently skip or cannot carry.

    Refused: a payload the rotors cannot lift with the platform (the mass in grams?).  Warned about, once per run: the
    phases that start at or after the end (never flown), end after it (flown in part: the final errors are measured
    against an unfinished reference), the payload events at or after it (never applied) and the ``gusts``
    (:class:`qprr.sim.wind.Gust`) that start at or after it or end after it - a run shorter than its
    mission is legal (the first seconds of a long mission), a mission file longer than the run by mistake is not
    noticed otherwise.  Each message names the phase or event, its time and the duration that flies it all."""
    platform = check_platform(platform)
    D = as_real(duration, "duration", positive=True, unit="s")
    skipped, cut = [], []
    for k, p in enumerate(phases):
        if not isinstance(p, Phase):
            raise InputError(f"mission phase {k + 1} must be a qprr.trajectory.Phase, got {type(p).__name__}")
        if p.t1 >= D:
            skipped.append(f"phase {k + 1} ({p.coordinate!r} to {p.value:g}, start = {p.t1:g} s)")
        elif p.t2 > D:
            cut.append(f"phase {k + 1} ({p.coordinate!r} to {p.value:g}, end = {p.t2:g} s)")
    changes = payload.changes if payload is not None else ()
    lift = max_lift(platform)
    for k, ev in enumerate(changes):
        if ev.time >= D:
            skipped.append(f"payload event {k + 1} (mass = {ev.mass:g} kg, time = {ev.time:g} s)")
            continue
        weight = (platform.total_mass + ev.mass) * platform.g
        if weight > lift:
            raise InputError(
                f"mission payload event {k + 1} (time = {ev.time:g} s): mass = {ev.mass:g} kg with the platform's "
                f"{platform.total_mass:.4g} kg weighs {weight:.4g} N, more than its rotors lift ({lift:.4g} N along z_B, "
                f"{lift / platform.g - platform.total_mass:.4g} kg of payload at most); the mass is in kg (grams? "
                f"{ev.mass:g} g = {ev.mass / 1000:g} kg)"
            )
    for k, g in enumerate(gusts):
        if g.start >= D or g.start + g.duration > D:
            (skipped if g.start >= D else cut).append(f"gust {k + 1} (start = {g.start:g} s, end = {g.start + g.duration:g} s)")
    if skipped or cut:
        end = max([p.t2 for p in phases] + [ev.time for ev in changes] + [g.start + g.duration for g in gusts])
        said = ([f"never flown or applied: {', '.join(skipped)}"] if skipped else []) + ([f"flown in part: {', '.join(cut)}"] if cut else [])
        warnings.warn(
            f"mission longer than the run (duration = {D:g} s): {'; '.join(said)}; the run reports only what it flew. "
            f"Give duration > {end:g} s to fly the whole mission",
            ScheduleWarning,
            stacklevel=3,
        )


def read_mission(source, *, phases_required: bool = True) -> tuple[tuple[Phase, ...], PayloadSchedule | None]:
    """Phases and payload events of a mission given as data (:func:`qprr.scenarios.mission_file.read_mission_file`,
    which reads and checks the whole file: the air, the motors and the controller too).

    ``source``: a TOML file (``[[phase]]`` tables with :data:`PHASE_KEYS`, optional ``[[payload]]``
    tables with :data:`PAYLOAD_KEYS`) or a mapping ``{"phase": [...], "payload": [...]}`` of the same
    tables.  A phase moves ``coordinate`` (a name of the platform's xi: "z", "psi", an arm joint's
    name) to ``target`` between ``start`` and ``end`` [s].  ``phases_required=False`` accepts payload
    events alone (a mission whose reference is given otherwise, :class:`MissionSettings`)."""
    data = read_mission_file(source, phases_required=phases_required)
    return data.phases, data.payload


def default_mission(platform: Platform, duration: float) -> dict:
    """The mission flown when none is given: climb to 2 m (0-30 %), fly 1 m along x (30-60 %), reach the arm out
    (50-80 %, every joint 60 % of the way to its upper limit), as data (:func:`read_mission`)."""
    platform = check_platform(platform)
    D = as_real(duration, "duration", positive=True)
    q = reach_posture(platform, 0.6)
    phases = [{"coordinate": "z", "start": 0.0, "end": 0.3 * D, "target": 2.0}, {"coordinate": "x", "start": 0.3 * D, "end": 0.6 * D, "target": 1.0}]
    phases += [{"coordinate": n, "start": 0.5 * D, "end": 0.8 * D, "target": float(v)} for n, v in zip(platform.arm_names, q)]
    return {"phase": phases}


def mission(platform=None, controller=None, progress=False, settings: MissionSettings = _AS_REGISTERED, **o):
    """The phases of ``o["mission"]`` (file or mapping; "" for :func:`default_mission`) from the neutral posture on the ground,
    with what the mission data carries besides (:mod:`qprr.scenarios.mission_file`): payload events, the wind, gusts and
    drag, the motor stage, the controller and its gains, flown as written.

    ``controller``: None flies the data's ``[controller] name`` (else "idc"); a name that differs from the data's is
    refused.  The result is labelled ``mission NAME`` by the data's name (its file's stem).  With
    ``settings.trajectory`` the mission data gives the rest only (phases there are refused)."""
    platform = _platform(platform)
    if settings.trajectory is None:
        data = read_mission_file(o["mission"] or default_mission(platform, o["duration"]))
        traj = MultiPhase(data.phases, tuple(platform.neutral_xi()), name="mission", law=o["law"], names=platform.xi_names)
    else:
        data = read_mission_file(o["mission"], phases_required=False) if o["mission"] else MissionFile("mission", (), None)
        if data.phases:
            raise InputError("mission: phases in the mission data and MissionSettings.trajectory both give the reference; give one")
        traj = settings.trajectory
    check_mission_schedule(platform, data.phases, data.payload, o["duration"], data.gusts)
    stage = motor_stage_of(platform, data.motor, settings.plausibility) if data.motor else None
    ctrl = _mission_controller(_mission_controller_name(controller, data), platform, o, settings, data, stage)
    disturbance = data.drag
    if disturbance is not None and settings.disturbance is not None:  # the caller's and the file's: both act
        mine = settings.disturbance.parts if isinstance(settings.disturbance, Disturbances) else (settings.disturbance,)
        disturbance, settings = Disturbances((*mine, disturbance)), replace(settings, disturbance=None)
    label = "mission" if data.name == "mission" else f"mission {data.name}"
    res = fly(platform, ctrl, traj, o, progress, label, settings, payload=data.payload, disturbance=disturbance, actuators=stage)
    _errors(res)
    return res


def _mission_controller_name(controller: str | None, data: MissionFile) -> str:
    """The controller a mission flies: the caller's ``controller``, the data's ``[controller] name`` (one of those the
    ``mission`` scenario flies), or "idc"; the caller's and the data's must agree."""
    written = data.controller.name
    if not written:
        return controller or "idc"
    as_name(written, "name", SCENARIOS["mission"].controller_names(), f"controller of mission {data.name!r} ([controller] name)")
    if controller is not None and controller != written:
        raise InputError(
            f"mission {data.name!r} names the controller {written!r} ([controller] name) and the run asks for {controller!r}: "
            "name it in one place (leave out --controller, or remove name from [controller])"
        )
    return written


def _mission_controller(name: str, platform: Platform, o: dict, settings: MissionSettings, data: MissionFile, stage):
    """``settings.controller``, else the controller ``name`` with the gains of :func:`mission_gain_arguments`, told
    about the mission's payload events as the option ``payload_model`` says (:func:`payload_awareness`)."""
    if settings.controller is not None:
        if data.controller.name or data.controller.gains != "":
            raise InputError(f"mission {data.name!r}: MissionSettings.controller is flown, its [controller] table would be ignored; remove one")
        return _built(settings, o)
    defaults = "class" if o["gains"] == "class" and data.controller.gains == "" else "platform"
    gains = mission_gain_arguments(name, platform, o["gains"], data, stage)
    return make_controller(name, platform, defaults=defaults, **gains, **payload_awareness(name, o, data.payload))


def mission_gain_arguments(name: str, platform: Platform, gains, data: MissionFile, stage: RotorDynamics | None) -> dict[str, object]:
    """The gain arguments controller ``name`` flies a mission with: the data's ``[controller]`` gains (a gain set's
    name or file, or a gains file's tables), else the option ``gains`` (:func:`gain_arguments`; both given: refused);
    derived gains know the motor ``stage``'s time constant (``Targets(rotor_time_constant=tau)``, :func:`lag_gains`)."""
    choice = data.controller
    if choice.gains != "":
        if gains != "platform":
            raise InputError(
                f"mission {data.name!r} sets the gains in [controller] and the run's option gains = {gains!r} too: give them in one place"
            )
        gains = choice.gains
    derived = stage is not None and name in GAIN_ARGUMENTS  # gains derived from targets: they learn the rotors' lag
    tau = float(np.max(stage.time_constant)) if stage is not None else 0.0
    if isinstance(gains, Mapping):
        where = f"the [controller] tables of mission {data.name!r}" if choice.gains != "" else "the gains tables"
        return load_gain_file(with_rotor_lag(gains, name, tau) if derived else gains, name, platform, where)
    if gains == "platform" and derived:
        return lag_gains(name, platform, tau)
    return gain_arguments(name, platform, gains)


def flown_gain_source(scenario: str, gains, options: dict) -> str:
    """What gives the gains of the generic ``scenario`` (``--print-gains``'s header): a mission's ``[controller]`` table
    when its data sets the gains, else the option ``gains``."""
    if scenario == "mission" and options.get("mission"):
        data = read_mission_file(options["mission"], phases_required=False)
        if data.controller.gains != "":
            return f"[controller] of mission {data.name!r}"
    return str(gains)


def flown_controller(scenario: str, controller: str | None, options: dict) -> str:
    """The controller the generic ``scenario`` flies when ``controller`` is asked (None: none): for ``mission``, the
    mission data's ``[controller] name`` (:func:`_mission_controller_name`), else ``controller`` or the scenario's first."""
    if scenario == "mission" and options.get("mission"):
        return _mission_controller_name(controller, read_mission_file(options["mission"], phases_required=False))
    return controller or SCENARIOS[scenario].controllers[0]


def grasp_drop(platform=None, controller="idc", progress=False, settings: MissionSettings = _AS_REGISTERED, **o):
    """Hover with the arm out; a mass ``mass_fraction`` of the platform's mass attaches at the end effector at 25 % of
    the run (grasp) and drops at 55 %."""
    platform = _platform(platform)
    traj = _hover(platform, o, settings)
    if not 0.0 < o["mass_fraction"] < 1.0:
        raise InputError(f"mass_fraction must be in (0, 1), got {o['mass_fraction']!r}")
    m = o["mass_fraction"] * platform.total_mass
    D = o["duration"]
    schedule = PayloadSchedule((PayloadChange(0.25 * D, m), PayloadChange(0.55 * D, 0.0)))
    res = fly(platform, _controller(controller, platform, o, settings, schedule), traj, o, progress, "grasp-drop", settings, payload=schedule)
    _errors(res)
    res.metrics.update({"payload_mass": m, "t_grasp": 0.25 * D, "t_drop": 0.55 * D})
    return res


def push(platform=None, controller="opspace-impedance", progress=False, settings: MissionSettings = _AS_REGISTERED, **o):
    """The end effector pressed ``penetration`` into a compliant wall ``gap`` ahead (world x) between 20 % and 50 % of
    the run, held: impedance K (derived: m w_pos^2) and wall k in series give F = penetration K k / (K + k).

    Its reference comes from the wall's place and its controller reads the wall's force sensor: a
    ``MissionSettings.trajectory`` or ``.controller`` is refused."""
    platform = _platform(platform)
    if settings.trajectory is not None or settings.controller is not None:
        raise InputError(
            "ee-push builds its own reference and controller around the wall (its place, its force sensor): "
            "MissionSettings.trajectory and MissionSettings.controller must be None"
        )
    xi0 = _hover_xi(platform, o)
    p_e0, _ = ee_pose_xi(platform, platform.data(), xi0)
    wall = CompliantWall(
        platform, point=p_e0 + np.array([o["gap"], 0.0, 0.0]), normal=(-1.0, 0.0, 0.0), stiffness=o["wall_stiffness"], damping=o["wall_damping"]
    )
    D = o["duration"]
    traj = MultiPhase((Phase("x", 0.2 * D, 0.5 * D, o["gap"] + o["penetration"]),), tuple(xi0), name="ee-push", law=o["law"], names=platform.xi_names)
    sensor = {"ee_sensor": wall.measured} if controller == "opspace-impedance" else {}
    ctrl = controller_for(controller, platform, o["gains"], **sensor)
    res = fly(platform, ctrl, traj, o, progress, "ee-push", settings, external_wrench=wall)
    force = wall.history().wrench[:, 0:3]
    res.series["ee_force"] = force
    tail = res.t >= 0.85 * D
    res.metrics["contact_force"] = float(np.mean(-force[tail, 0]))
    if controller == "opspace-impedance":
        K = float(ctrl.impedance.stiffness[0, 0])
        res.metrics["impedance_stiffness"] = K
        res.metrics["predicted_force"] = o["penetration"] * K * o["wall_stiffness"] / (K + o["wall_stiffness"])
    return res


def hover_wind(platform=None, controller="idc", progress=False, settings: MissionSettings = _AS_REGISTERED, **o):
    """Hover under base drag (``drag`` [N s/m] linear per axis) in a mean wind ``mean_wind`` [m/s] plus a 1 - cos gust
    ``gust`` [m/s] peaking at 50 % of the run (lasting 20 %)."""
    platform = _platform(platform)
    traj = _hover(platform, o, settings)
    D = o["duration"]
    air = Wind(mean=o["mean_wind"], gusts=(Gust(0.4 * D, 0.2 * D, o["gust"]),))
    drag = AerodynamicDrag(linear=o["drag"], wind=air)
    res = fly(platform, _controller(controller, platform, o, settings), traj, o, progress, "hover-wind", settings, disturbance=drag)
    _errors(res)
    return res


def motor_lag(platform=None, controller="idc", progress=False, settings: MissionSettings = _AS_REGISTERED, **o):
    """:func:`point_to_point` (at height) through first-order rotor dynamics: time constant ``tau`` [s], thrust b w^2
    (``thrust_factor``); the stage of :func:`motor_stage` (the platform's ``[motor]`` table where ``tau`` and
    ``thrust_factor`` are 0, their defaults).

    With ``gains="platform"`` the gains are derived knowing the rotor time constant
    (``Targets(rotor_time_constant=tau)``: the attitude loop and the roll/pitch reference filter bounded
    by the rotors' bandwidth, :mod:`qprr.control.gains`, "Rotor lag").  ``settings`` (:class:`MissionSettings`):
    another reference (the options ``target`` and ``reach_fraction`` are then not read), a built controller, a
    disturbance, the result's name."""
    platform = _platform(platform)
    actuators = motor_stage(platform, o["tau"], o["thrust_factor"], settings.plausibility)
    tau = float(np.max(actuators.time_constant))
    if o["gains"] == "platform" and settings.controller is None:
        ctrl = make_controller(controller, platform, **lag_gains(controller, platform, tau), **payload_awareness(controller, o, None))
    elif isinstance(o["gains"], Mapping) and settings.controller is None:  # inline tables: their targets learn the lag too
        gains = load_gain_file(with_rotor_lag(o["gains"], controller, tau), controller, platform, "the gains tables")
        ctrl = make_controller(controller, platform, **gains, **payload_awareness(controller, o, None))
    else:
        ctrl = _controller(controller, platform, o, settings)
    traj = settings.trajectory if settings.trajectory is not None else _lag_reference(platform, o)
    res = fly(platform, ctrl, traj, o, progress, "motor-lag", settings, actuators=actuators)
    _errors(res)
    return res


MOTOR_DEFAULTS = {"time_constant": 0.005, "thrust_factor": 1e-5}
"""The motor stage ``motor-lag`` flies on a platform whose rotor file has no ``[motor]`` table (tau 5 ms, b 1e-5 N s^2)."""


def motor_stage(platform: Platform, tau: float = 0.0, thrust_factor: float = 0.0, plausibility: Plausibility | None = DEFAULT) -> RotorDynamics:
    """The actuator stage ``motor-lag`` flies, starting at hover: the platform's ``[motor]`` table (its rotor file's,
    :attr:`qprr.model.Platform.motor`), with ``tau`` [s] and ``thrust_factor`` [N s^2] replacing its time constant and
    thrust factor when > 0 (0: the table's, else :data:`MOTOR_DEFAULTS`).  The time constants are checked against
    ``plausibility`` (milliseconds written as seconds: ``tau = 5``)."""
    platform = check_platform(platform)
    given = {}
    for key, value in (("time_constant", tau), ("thrust_factor", thrust_factor)):
        name = "tau" if key == "time_constant" else key
        v = as_real(value, name, nonnegative=True, unit="s" if name == "tau" else "N s^2")
        if v > 0.0:
            given[key] = v
    table = {**MOTOR_DEFAULTS, **platform.motor} if platform.motor else dict(MOTOR_DEFAULTS)
    source = f"the [motor] table of {platform.provenance.get('rotors', 'the rotor file')!r}" if platform.motor else "motor-lag's default"
    try:
        stage = rotor_dynamics_from_mapping({"motor": table}, platform.rotors, initial="hover", **given)
    except (InputError, UnknownNameError) as exc:  # named where the values come from, the error's kind kept
        exc.args = (f"motor-lag on platform {platform.name!r}, {source}: {exc}", *exc.args[1:])
        raise
    check_time_constant(stage.time_constant, plausibility, "tau" if "time_constant" in given else f"time_constant ({source})")
    return stage


def _lag_reference(platform: Platform, o: dict) -> MultiPhase:
    """The reference of :func:`motor_lag`: from hover at ``target``'s height, to ``target`` with the arm out (10-60 %)."""
    D = o["duration"]
    x, y, z = _target(o["target"])
    xi0 = np.concatenate([[0.0, 0.0, z, 0.0, 0.0, 0.0], platform.neutral_q()[7:]])
    q = reach_posture(platform, o["reach_fraction"])
    phases = [Phase("x", 0.1 * D, 0.6 * D, x), Phase("y", 0.1 * D, 0.6 * D, y)]
    phases += [Phase(n, 0.1 * D, 0.6 * D, float(v)) for n, v in zip(platform.arm_names, q)]
    return MultiPhase(tuple(phases), tuple(xi0), name="motor-lag", law=o["law"], names=platform.xi_names)


def flown_gain_arguments(scenario: str, controller: str, platform: Platform, gains, options: dict) -> dict[str, object]:
    """The gain arguments ``controller`` is built with in the generic ``scenario`` (``--print-gains``): those of
    :func:`gain_arguments`, except motor-lag's derived gains, which know its rotor time constant (:func:`lag_gains`;
    ``options`` the run's, missing ones at the scenario's defaults) and a mission's, which its data may give
    (:func:`mission_gain_arguments`)."""
    if scenario == "mission" and options.get("mission"):
        data = read_mission_file(options["mission"], phases_required=False)
        stage = motor_stage_of(platform, data.motor) if data.motor else None
        if data.controller.gains != "" or stage is not None:
            return mission_gain_arguments(controller, platform, gains, data, stage)
    if gains == "platform" and controller not in GAIN_ARGUMENTS:  # e.g. mpc: cost weights, make_controller's own
        return {}
    if scenario == "motor-lag" and gains == "platform":
        stage = motor_stage(platform, options["tau"], options["thrust_factor"])
        return lag_gains(controller, platform, float(np.max(stage.time_constant)))
    return gain_arguments(controller, platform, gains)


def with_rotor_lag(gains: Mapping, controller: str, tau: float) -> dict:
    """A gains file's tables for ``controller`` whose derived gains learn rotors of time constant ``tau`` [s]
    (``Targets(rotor_time_constant=tau)``), unless their ``targets`` table gives its own."""
    if controller not in GAIN_ARGUMENTS:
        return dict(gains)
    return {**gains, "targets": {"rotor_time_constant": tau, **gains.get("targets", {})}}


def lag_gains(controller: str, platform: Platform, tau: float) -> dict[str, object]:
    """The derived gains of ``controller`` for rotors of time constant ``tau`` [s] (motor-lag's default, and what
    ``--print-gains`` shows for it): :func:`qprr.control.gains.platform_gains` with ``Targets(rotor_time_constant=tau)``."""
    from ..control.gains import Targets

    return platform_gains(controller, platform, Targets(rotor_time_constant=tau))


def noise(platform=None, controller="idc", progress=False, settings: MissionSettings = _AS_REGISTERED, *, amplitude=None, **o):
    """Hover under uniform white noise on every generalised force (Thesis (6.27)), new each tick: ``fraction`` of each
    coordinate's authority (the thrust margin on x, y, z, the rotors' torques on the angles, the effort limits on the arm).

    ``amplitude`` (Python): the noise's half-width per generalised force instead (6 + n_arm values, N or N m, >= 0);
    the option ``fraction`` is then not read."""
    platform = _platform(platform)
    traj = _hover(platform, o, settings)
    res = fly(
        platform,
        _controller(controller, platform, o, settings),
        traj,
        o,
        progress,
        "hover-noise",
        settings,
        disturbance=WhiteNoise(_noise_amplitude(platform, o, amplitude)),
    )
    _errors(res)
    return res


def _noise_amplitude(platform: Platform, o: dict, amplitude) -> tuple[float, ...]:
    if amplitude is not None:
        amp = as_vector(amplitude, platform.n_xi, "amplitude")
        if not np.all(amp >= 0.0):
            raise InputError(f"amplitude must be >= 0 (the noise's half-width per generalised force, N or N m), got {amplitude!r}")
        return tuple(amp.tolist())
    from ..control.gains import Authority

    a = Authority.from_platform(platform)
    amp = np.array([a.thrust_margin] * 3 + list(a.torque) + [e if np.isfinite(e) else 1.0 for e in a.arm_effort])
    fraction = o["fraction"]
    if isinstance(fraction, bool) or not isinstance(fraction, (int, float)) or not 0.0 <= fraction <= 1.0:
        raise InputError(
            f"fraction must be a number in [0, 1] (the noise's half-width as a fraction of each coordinate's actuator "
            f"authority; 0.02 is 2 %), got {fraction!r}"
        )
    return tuple(fraction * amp)


def pulse_train(platform: Platform, duration: float, force: float, torque: float) -> tuple[Pulse, ...]:
    """The pulses (Thesis (6.28)) of :func:`pulses`, each 5 % of ``duration``: ``force`` [N] on z at 10 %, on x and y at
    40 %, ``torque`` [N m or N] on every arm joint at 70 %."""
    n = check_platform(platform).n_xi
    duration = as_real(duration, "duration", positive=True, unit="s")
    force, torque = as_real(force, "force", unit="N"), as_real(torque, "torque", unit="N m or N")
    shots = []
    for start, idx, value in ((0.1, (2,), force), (0.4, (0, 1), force), (0.7, tuple(range(6, n)), torque)):
        if idx:
            g = np.zeros(n)
            g[list(idx)] = value
            shots.append(Pulse(start * duration, (start + 0.05) * duration, tuple(g)))
    return tuple(shots)


def pulses(platform=None, controller="idc", progress=False, settings: MissionSettings = _AS_REGISTERED, *, train=None, **o):
    """Hover hit by the pulses of :func:`pulse_train` (options ``force``, ``torque``); the run ends 25 % after the last.

    ``train`` (Python): the pulses instead (:class:`qprr.sim.Pulse`, each Gamma of 6 + n_arm values); the options
    ``force`` and ``torque`` are then not read."""
    platform = _platform(platform)
    traj = _hover(platform, o, settings)
    if train is None:
        train = pulse_train(platform, o["duration"], o["force"], o["torque"])
    elif not (isinstance(train, (tuple, list)) and train and all(isinstance(p, Pulse) for p in train)):
        raise InputError(f"train must be a non-empty tuple of qprr.sim.Pulse, got {train!r}")
    ctrl = _controller(controller, platform, o, settings)
    res = fly(platform, ctrl, traj, o, progress, "hover-pulses", settings, disturbance=Disturbances(tuple(train)))
    _errors(res)
    return res


def mission_summary(result) -> list[str]:
    """The physical checks a generic scenario recorded (``result.metrics``), one line."""
    m = result.metrics
    parts = []
    if "final_position_error" in m:
        parts.append(
            f"final position error {1e3 * m['final_position_error']:.3f} mm, final arm error {m['final_arm_error']:.3e}, "
            f"max position error {1e3 * m['max_position_error']:.2f} mm"
        )
    if "payload_mass" in m:
        parts.append(f"payload {m['payload_mass']:.3f} kg grasped at {m['t_grasp']:.2f} s, dropped at {m['t_drop']:.2f} s")
    if "contact_force" in m:
        pred = f" (impedance and wall in series: {m['predicted_force']:.4f} N)" if "predicted_force" in m else ""
        parts.append(f"steady contact force {m['contact_force']:.4f} N{pred}")
    return ["; ".join(parts)] if parts else []


__all__ = [
    "PAYLOAD_KEYS",
    "PAYLOAD_MODELS",
    "payload_awareness",
    "PHASE_KEYS",
    "MissionSettings",
    "check_mission_schedule",
    "controller_for",
    "default_mission",
    "fly",
    "flown_controller",
    "flown_gain_source",
    "flown_gain_arguments",
    "gain_arguments",
    "mission_gain_arguments",
    "MOTOR_DEFAULTS",
    "mission",
    "motor_lag",
    "motor_stage",
    "noise",
    "grasp_drop",
    "phase_tables",
    "fly_to",
    "pulse_train",
    "pulses",
    "push",
    "reach_posture",
    "read_mission",
    "mission_summary",
    "takeoff_hover",
    "hover_wind",
]
