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
                    list of tables: :func:`read_mission`), payload grasps and releases included
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
own defaults), a name of :data:`qprr.registry.GAIN_TABLES` or a TOML file (:func:`qprr.control.gains.load_gains`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the tomli backport, a dependency there
    import tomli as tomllib

from .control import make_controller
from .control.gains import load_gains as load_gain_file
from .control.gains import platform_gains
from .control.impedance import ImpedanceGains
from .control.inverse_dynamics import IDCGains
from .control.mfc import MFCGains
from .control.opspace_impedance import EndEffectorImpedance
from .errors import InputError, UnknownNameError
from .kinematics import ee_pose_xi
from .model import Platform, check_platform
from .sim import simulate
from .sim.actuators import RotorDynamics
from .sim.contact import CompliantWall
from .sim.disturbances import Disturbances, Pulse, WhiteNoise
from .sim.payload import PayloadChange, PayloadSchedule
from .sim.wind import AerodynamicDrag, Gust, Wind
from .trajectory import Hold, MultiPhase, Phase
from .validation import as_real

PHASE_KEYS = ("coordinate", "start", "end", "target")
"""Keys of one phase of a mission given as data (``[[phase]]`` tables of a TOML file)."""
PAYLOAD_KEYS = ("time", "mass")
"""Keys of one payload event of a mission (``[[payload]]`` tables): from ``time`` [s] the end effector carries ``mass`` [kg]."""


# ------------------------------------------------------------------------- building blocks
def gain_arguments(name: str, platform: Platform, gains="platform") -> dict[str, object]:
    """The constructor keyword arguments of controller ``name`` for the gain set ``gains`` (module docstring; "class": none)."""
    if not isinstance(gains, str):
        raise InputError(f"gains must be 'platform', 'class', a registered gain table or a TOML file, got {gains!r}")
    if gains == "platform":
        return platform_gains(name, platform)
    if gains.endswith(".toml"):
        return load_gain_file(gains, name, platform)
    if gains == "class":
        return {}
    from .registry import GAIN_TABLES

    table = GAIN_TABLES[gains]()
    if not isinstance(table, (IDCGains, MFCGains, ImpedanceGains, EndEffectorImpedance)):
        raise InputError(f"gain table {gains!r} gives a {type(table).__name__}, not gains of qprr.control")
    return {"impedance" if isinstance(table, (ImpedanceGains, EndEffectorImpedance)) else "gains": table}


def controller_for(name: str, platform: Platform, gains="platform", **kwargs):
    """``make_controller(name, platform)`` with the gain set ``gains`` (:func:`gain_arguments`); ``kwargs`` to the constructor."""
    return make_controller(name, platform, **{**gain_arguments(name, platform, gains), **kwargs})


def reach_posture(platform: Platform, fraction: float) -> np.ndarray:
    """Arm joints ``fraction`` of the way from the neutral posture to the upper limits (neutral + 1 where unlimited)."""
    platform = check_platform(platform)
    if not (isinstance(fraction, (int, float)) and 0.0 <= fraction <= 1.0):
        raise InputError(f"reach_fraction must be in [0, 1], got {fraction!r}")
    q0 = platform.neutral_q()[7:]
    hi = np.where(np.isfinite(platform.arm_upper), platform.arm_upper, q0 + 1.0)
    return q0 + fraction * (hi - q0)


def _platform(platform: Platform | None) -> Platform:
    from .platforms import load

    return load() if platform is None else platform


def _fly(platform, ctrl, trajectory, o: dict, progress: bool, name: str, **extra):
    return simulate(
        platform, ctrl, trajectory, o["duration"], dt=o["dt"], integrator=o["integrator"], seed=o["seed"], progress=progress, scenario=name, **extra
    )


def _errors(res, final: np.ndarray) -> None:
    """Record the final position and arm errors against ``final`` (the reference's last xi) and the largest position error."""
    e = res.xi[-1] - final
    res.metrics["final_position_error"] = float(np.linalg.norm(e[0:3]))
    res.metrics["final_arm_error"] = float(np.max(np.abs(e[6:]))) if e.shape[0] > 6 else 0.0
    res.metrics["max_position_error"] = float(np.max(np.linalg.norm(res.xi[:, 0:3] - res.xi_d[:, 0:3], axis=1)))


def _hover(platform, o: dict) -> tuple[np.ndarray, Hold]:
    xi = np.concatenate([[0.0, 0.0, float(o["z"]), 0.0, 0.0, 0.0], reach_posture(platform, o["reach_fraction"])])
    return xi, Hold(tuple(xi))


# ------------------------------------------------------------------------- the scenarios
def takeoff_hover(platform=None, controller="idc", progress=False, **o):
    """Climb from z = 0 to ``z`` over the first 40 % of the run (transition law ``law``), then hold."""
    platform = _platform(platform)
    xi0 = platform.neutral_xi()
    D = o["duration"]
    traj = MultiPhase((Phase("z", 0.0, 0.4 * D, o["z"]),), tuple(xi0), name="takeoff-hover", law=o["law"], names=platform.xi_names)
    res = _fly(platform, controller_for(controller, platform, o["gains"]), traj, o, progress, "takeoff-hover")
    _errors(res, traj.final())
    return res


def point_to_point(platform=None, controller="idc", progress=False, **o):
    """Climb to ``target``'s height (first 30 %), then fly to ``target`` while the arm reaches out (30-70 %), hold."""
    platform = _platform(platform)
    D = o["duration"]
    x, y, z = (float(v) for v in o["target"])
    xi0 = platform.neutral_xi()
    q = reach_posture(platform, o["reach_fraction"])
    phases = [Phase("z", 0.0, 0.3 * D, z), Phase("x", 0.3 * D, 0.7 * D, x), Phase("y", 0.3 * D, 0.7 * D, y)]
    phases += [Phase(n, 0.3 * D, 0.7 * D, float(v)) for n, v in zip(platform.arm_names, q)]
    traj = MultiPhase(tuple(phases), tuple(xi0), name="fly-to", law=o["law"], names=platform.xi_names)
    res = _fly(platform, controller_for(controller, platform, o["gains"]), traj, o, progress, "fly-to")
    _errors(res, traj.final())
    return res


def read_mission(source) -> tuple[tuple[Phase, ...], PayloadSchedule | None]:
    """Phases and payload events of a mission given as data.

    ``source``: a TOML file (``[[phase]]`` tables with :data:`PHASE_KEYS`, optional ``[[payload]]``
    tables with :data:`PAYLOAD_KEYS`) or a mapping ``{"phase": [...], "payload": [...]}`` of the same
    tables.  A phase moves ``coordinate`` (a name of the platform's xi: "z", "psi", an arm joint's
    name) to ``target`` between ``start`` and ``end`` [s]."""
    if isinstance(source, (str, Path)):
        path = Path(source)
        if not path.is_file():
            raise InputError(f"mission file {str(path)!r} does not exist (a TOML file of [[phase]] tables: {', '.join(PHASE_KEYS)})")
        with path.open("rb") as fh:
            try:
                source = tomllib.load(fh)
            except tomllib.TOMLDecodeError as exc:
                raise InputError(f"mission file {str(path)!r}: not valid TOML ({exc})") from exc
    if not hasattr(source, "get"):
        raise InputError(f"a mission is a TOML file or a mapping of 'phase' (and 'payload') tables, got {type(source).__name__}")
    for key in source:
        if key not in ("phase", "payload"):
            raise UnknownNameError("mission table", key, ("phase", "payload"))
    phases, events = [], []
    for k, table in enumerate(source.get("phase", ())):
        if set(table) != set(PHASE_KEYS):
            raise InputError(f"mission phase {k + 1} has keys {sorted(table)}; a phase needs exactly {list(PHASE_KEYS)}")
        phases.append(Phase(table["coordinate"], table["start"], table["end"], table["target"]))
    for k, table in enumerate(source.get("payload", ())):
        if set(table) != set(PAYLOAD_KEYS):
            raise InputError(f"mission payload event {k + 1} has keys {sorted(table)}; an event needs exactly {list(PAYLOAD_KEYS)}")
        events.append(PayloadChange(float(table["time"]), float(table["mass"])))
    if not phases:
        raise InputError("a mission needs at least one [[phase]] table")
    return tuple(phases), (PayloadSchedule(tuple(events)) if events else None)


def default_mission(platform: Platform, duration: float) -> dict:
    """The mission flown when none is given: climb to 2 m (0-30 %), fly 1 m along x (30-60 %), reach the arm out
    (50-80 %, every joint 60 % of the way to its upper limit), as data (:func:`read_mission`)."""
    platform = check_platform(platform)
    D = as_real(duration, "duration", positive=True)
    q = reach_posture(platform, 0.6)
    phases = [{"coordinate": "z", "start": 0.0, "end": 0.3 * D, "target": 2.0}, {"coordinate": "x", "start": 0.3 * D, "end": 0.6 * D, "target": 1.0}]
    phases += [{"coordinate": n, "start": 0.5 * D, "end": 0.8 * D, "target": float(v)} for n, v in zip(platform.arm_names, q)]
    return {"phase": phases}


def mission(platform=None, controller="idc", progress=False, **o):
    """The phases of ``o["mission"]`` (file or mapping; "" for :func:`default_mission`) from the neutral posture on the ground."""
    platform = _platform(platform)
    phases, payload = read_mission(o["mission"] or default_mission(platform, o["duration"]))
    traj = MultiPhase(phases, tuple(platform.neutral_xi()), name="mission", law=o["law"], names=platform.xi_names)
    res = _fly(platform, controller_for(controller, platform, o["gains"]), traj, o, progress, "mission", payload=payload)
    _errors(res, traj.final())
    return res


def payload(platform=None, controller="idc", progress=False, **o):
    """Hover with the arm out; a mass ``mass_fraction`` of the platform's mass attaches at the end effector at 25 % of
    the run (grasp) and drops at 55 %."""
    platform = _platform(platform)
    xi, traj = _hover(platform, o)
    if not 0.0 < o["mass_fraction"] < 1.0:
        raise InputError(f"mass_fraction must be in (0, 1), got {o['mass_fraction']!r}")
    m = o["mass_fraction"] * platform.total_mass
    D = o["duration"]
    schedule = PayloadSchedule((PayloadChange(0.25 * D, m), PayloadChange(0.55 * D, 0.0)))
    res = _fly(platform, controller_for(controller, platform, o["gains"]), traj, o, progress, "grasp-drop", payload=schedule)
    _errors(res, xi)
    res.metrics.update({"payload_mass": m, "t_grasp": 0.25 * D, "t_drop": 0.55 * D})
    return res


def push(platform=None, controller="opspace-impedance", progress=False, **o):
    """The end effector pressed ``penetration`` into a compliant wall ``gap`` ahead (world x) between 20 % and 50 % of
    the run, held: impedance K (derived: m w_pos^2) and wall k in series give F = penetration K k / (K + k)."""
    platform = _platform(platform)
    xi0, _ = _hover(platform, o)
    p_e0, _ = ee_pose_xi(platform, platform.data(), xi0)
    wall = CompliantWall(
        platform, point=p_e0 + np.array([o["gap"], 0.0, 0.0]), normal=(-1.0, 0.0, 0.0), stiffness=o["wall_stiffness"], damping=o["wall_damping"]
    )
    D = o["duration"]
    traj = MultiPhase((Phase("x", 0.2 * D, 0.5 * D, o["gap"] + o["penetration"]),), tuple(xi0), name="ee-push", law=o["law"], names=platform.xi_names)
    sensor = {"ee_sensor": wall.measured} if controller == "opspace-impedance" else {}
    ctrl = controller_for(controller, platform, o["gains"], **sensor)
    res = _fly(platform, ctrl, traj, o, progress, "ee-push", external_wrench=wall)
    force = wall.history().wrench[:, 0:3]
    res.series["ee_force"] = force
    tail = res.t >= 0.85 * D
    res.metrics["contact_force"] = float(np.mean(-force[tail, 0]))
    if controller == "opspace-impedance":
        K = float(ctrl.impedance.stiffness[0, 0])
        res.metrics["impedance_stiffness"] = K
        res.metrics["predicted_force"] = o["penetration"] * K * o["wall_stiffness"] / (K + o["wall_stiffness"])
    return res


def wind(platform=None, controller="idc", progress=False, **o):
    """Hover under base drag (``drag`` [N s/m] linear per axis) in a mean wind ``mean_wind`` [m/s] plus a 1 - cos gust
    ``gust`` [m/s] peaking at 50 % of the run (lasting 20 %)."""
    platform = _platform(platform)
    xi, traj = _hover(platform, o)
    D = o["duration"]
    air = Wind(mean=o["mean_wind"], gusts=(Gust(0.4 * D, 0.2 * D, o["gust"]),))
    drag = AerodynamicDrag(linear=o["drag"], wind=air)
    res = _fly(platform, controller_for(controller, platform, o["gains"]), traj, o, progress, "hover-wind", disturbance=drag)
    _errors(res, xi)
    return res


def motor_lag(platform=None, controller="idc", progress=False, **o):
    """:func:`point_to_point` (at height) through first-order rotor dynamics: time constant ``tau`` [s], thrust b w^2 (``thrust_factor``).

    With ``gains="platform"`` the gains are derived knowing the rotor time constant
    (``Targets(rotor_time_constant=tau)``: the attitude loop and the roll/pitch reference filter bounded
    by the rotors' bandwidth, :mod:`qprr.control.gains`, "Rotor lag")."""
    platform = _platform(platform)
    if o["gains"] == "platform":
        from .control.gains import Targets

        ctrl = make_controller(controller, platform, **platform_gains(controller, platform, Targets(rotor_time_constant=o["tau"])))
    else:
        ctrl = controller_for(controller, platform, o["gains"])
    actuators = RotorDynamics.for_rotors(platform.rotors, o["thrust_factor"], o["tau"], initial="hover")
    D = o["duration"]
    x, y, z = (float(v) for v in o["target"])
    xi0 = np.concatenate([[0.0, 0.0, z, 0.0, 0.0, 0.0], platform.neutral_q()[7:]])
    q = reach_posture(platform, o["reach_fraction"])
    phases = [Phase("x", 0.1 * D, 0.6 * D, x), Phase("y", 0.1 * D, 0.6 * D, y)]
    phases += [Phase(n, 0.1 * D, 0.6 * D, float(v)) for n, v in zip(platform.arm_names, q)]
    traj = MultiPhase(tuple(phases), tuple(xi0), name="motor-lag", law=o["law"], names=platform.xi_names)
    res = _fly(platform, ctrl, traj, o, progress, "motor-lag", actuators=actuators)
    _errors(res, traj.final())
    return res


def noise(platform=None, controller="idc", progress=False, **o):
    """Hover under uniform white noise on every generalised force (Thesis (6.27)), new each tick: ``fraction`` of each
    coordinate's authority (the thrust margin on x, y, z, the rotors' torques on the angles, the effort limits on the arm)."""
    from .control.gains import Authority

    platform = _platform(platform)
    xi, traj = _hover(platform, o)
    a = Authority.from_platform(platform)
    amp = np.array([a.thrust_margin] * 3 + list(a.torque) + [e if np.isfinite(e) else 1.0 for e in a.arm_effort])
    res = _fly(
        platform,
        controller_for(controller, platform, o["gains"]),
        traj,
        o,
        progress,
        "hover-noise",
        disturbance=WhiteNoise(tuple(o["fraction"] * amp)),
    )
    _errors(res, xi)
    return res


def pulses(platform=None, controller="idc", progress=False, **o):
    """Hover hit by pulses (Thesis (6.28)), each 5 % of the run: ``force`` [N] on z at 10 %, on x and y at 40 %,
    ``torque`` [N m or N] on every arm joint at 70 %; the run ends 25 % after the last."""
    platform = _platform(platform)
    xi, traj = _hover(platform, o)
    D, n = o["duration"], platform.n_xi
    shots = []
    for start, idx, value in ((0.1, (2,), o["force"]), (0.4, (0, 1), o["force"]), (0.7, tuple(range(6, n)), o["torque"])):
        if idx:
            g = np.zeros(n)
            g[list(idx)] = value
            shots.append(Pulse(start * D, (start + 0.05) * D, tuple(g)))
    res = _fly(platform, controller_for(controller, platform, o["gains"]), traj, o, progress, "hover-pulses", disturbance=Disturbances(tuple(shots)))
    _errors(res, xi)
    return res


def summary(result) -> list[str]:
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
    "PHASE_KEYS",
    "controller_for",
    "default_mission",
    "gain_arguments",
    "mission",
    "motor_lag",
    "noise",
    "payload",
    "point_to_point",
    "pulses",
    "push",
    "reach_posture",
    "read_mission",
    "summary",
    "takeoff_hover",
    "wind",
]
