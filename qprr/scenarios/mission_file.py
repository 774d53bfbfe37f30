"""The mission file: phases, payload events, the air, the motors and the controller of a run, as data.

A mission is a TOML file (or the same tables as a mapping: a campaign carries a file's content so) read by
:func:`read_mission_file` and flown by the ``mission`` scenario (:func:`qprr.scenarios.missions.mission`).  Every
table and key is checked: an unknown one is refused with the list of the valid ones, every number is range-checked
(:mod:`qprr.validation`), and what the file says is what is flown (a wind without a drag to act through, a seed
of a wind that has no turbulence, gains given both in the file and by the caller: refused, with the reason).

==================  ================================================================================================
table               keys (units)
==================  ================================================================================================
``name``            (top-level key, optional) the run's label in its summary and figure titles; default: the
                    file's stem ("mission" for a mapping)
``[[phase]]``       ``coordinate`` (a name of the platform's xi), ``start``, ``end`` [s], ``target`` [m or rad]
``[[payload]]``     ``time`` [s], ``mass`` [kg] carried by the end effector from then on (0: released)
``[wind]``          ``model`` = "mean" (mean wind only) or "dryden" (mean + Dryden turbulence, MIL-F-8785C);
                    ``mean_world`` [m/s] (3, world axes; default 0).  Dryden only: either ``sigma`` [m/s] and
                    ``length`` [m] (u, v, w) or ``w20`` [m/s] (the wind 20 ft above ground) and ``altitude`` [m]
                    (the low-altitude model); ``airspeed`` [m/s] (default: the mean wind's speed); ``seed``
                    (an integer >= 0; default: the run's seed)
``[[gust]]``        a "1 - cos" gust: ``start`` [s], ``duration`` [s], ``amplitude_world`` [m/s] (3, world axes)
``[drag]``          the base's drag, through which the wind acts (Thesis (5.36) D): ``linear`` [N s/m],
                    ``quadratic`` [N s^2/m^2] (one value or three, body axes), ``angular`` [N m s/rad]
``[motor]``         the rotors' first-order lag flown (:class:`qprr.sim.actuators.RotorDynamics`, starting at
                    hover): ``thrust_factor`` [N s^2], ``time_constant`` [s], ``w_min``, ``w_max`` [rad/s] (one
                    value, or one per rotor); a key left out comes from the rotor file's ``[motor]`` table
``[controller]``    ``name`` (a controller the mission scenario flies), ``gains`` ("platform", "class", a
                    registered gain table or a gains file, relative to the mission file; a mission given as
                    data takes an absolute path only), or the tables of a gains
                    file written inside it (:func:`qprr.control.gains.load_gains`): ``[controller.targets]``,
                    ``[controller.idc.gains]``, ``[controller.mpc.weights]``, ``[controller.mpc.settings]``...
==================  ================================================================================================

The wind is recorded in the run (``result.series["wind_velocity"]``, world axes, one row per tick) and drawn by
:func:`qprr.viz.plot_result`.  Phases, payload events and gusts at or after the end of the run are reported
(:func:`qprr.scenarios.missions.check_mission_schedule`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError, UnknownNameError
from ..model import Platform, check_platform
from ..sim.actuators import MOTOR_KEYS, RotorDynamics, rotor_dynamics_from_mapping
from ..sim.payload import PayloadChange, PayloadSchedule
from ..sim.wind import AerodynamicDrag, Dryden, Gust, Wind
from ..trajectory import Phase
from ..urdf.plausibility import DEFAULT, Plausibility, check_time_constant
from ..validation import as_int, as_name, as_real, as_vector, read_toml

PHASE_KEYS = ("coordinate", "start", "end", "target")
"""Keys of one phase of a mission given as data (``[[phase]]`` tables of a TOML file)."""
PAYLOAD_KEYS = ("time", "mass")
"""Keys of one payload event of a mission (``[[payload]]`` tables): from ``time`` [s] the end effector carries ``mass`` [kg]."""
TABLES = ("name", "phase", "payload", "wind", "gust", "drag", "motor", "controller")
"""The top-level keys of a mission file (module docstring)."""
WIND_MODELS = ("mean", "dryden")
"""``[wind] model``: the mean wind alone, or with Dryden turbulence."""
WIND_KEYS = ("model", "mean_world", "sigma", "length", "w20", "altitude", "airspeed", "seed")
"""Keys of the ``[wind]`` table; all but ``model`` and ``mean_world`` belong to the Dryden model."""
GUST_KEYS = ("start", "duration", "amplitude_world")
"""Keys of one ``[[gust]]`` table."""
DRAG_KEYS = ("linear", "quadratic", "angular")
"""Keys of the ``[drag]`` table (:class:`qprr.sim.wind.AerodynamicDrag`)."""
WIND_SPEED_MAX = 40.0
"""The largest wind speed component a mission may carry [m/s] (a storm; km/h written as m/s is refused)."""


@dataclass(frozen=True)
class ControllerChoice:
    """The ``[controller]`` table: ``name`` ("": the caller's or the scenario's), ``gains``: "" (the caller's option),
    a gain set's name or file (a string; a file relative to the mission file), or the tables of a gains file (a mapping)."""

    name: str = ""
    gains: str | Mapping = ""


@dataclass(frozen=True)
class MissionFile:
    """A mission read from its file: ``name`` (the run's label), the ``phases`` and ``payload`` events, the base's
    ``drag`` with the wind it flies in (None: still air, no drag), the ``motor`` table flown ({}: thrusts applied at
    once) and the ``controller`` choice."""

    name: str
    phases: tuple[Phase, ...]
    payload: PayloadSchedule | None
    drag: AerodynamicDrag | None = None
    motor: Mapping = field(default_factory=dict)
    controller: ControllerChoice = ControllerChoice()

    @property
    def gusts(self) -> tuple[Gust, ...]:
        """The gusts of the file's wind (their times are checked against the run's duration)."""
        return () if self.drag is None or self.drag.wind is None else self.drag.wind.gusts


def _keys(table, valid: tuple[str, ...], what: str, required: tuple[str, ...] = ()) -> dict:
    """``table`` as a dict whose keys are among ``valid`` (an unknown one refused, listing them) and include ``required``."""
    if not isinstance(table, Mapping):
        raise InputError(f"mission {what} must be a table of {', '.join(valid)}, got {table!r:.80}")
    for key in table:
        if key not in valid:
            raise UnknownNameError(f"key of mission {what}", key, valid)
    missing = [k for k in required if k not in table]
    if missing:
        raise InputError(f"mission {what} needs {missing} (keys: {', '.join(valid)})")
    return dict(table)


def _tables(source, key: str) -> list:
    """The array of tables ``[[key]]`` of a mission (a list of tables)."""
    value = source.get(key, [])
    if not isinstance(value, (list, tuple)):
        raise InputError(f"mission {key!r} must be an array of tables ([[{key}]]), got {value!r:.80}")
    return value


def _wind_vector(value, what: str) -> tuple[float, float, float]:
    v = as_vector(value, 3, what)
    if np.any(np.abs(v) > WIND_SPEED_MAX):
        raise InputError(f"{what} = {v.tolist()} m/s: a component beyond {WIND_SPEED_MAX:g} m/s (km/h written as m/s? 36 km/h = 10 m/s)")
    return tuple(float(x) for x in v)


def _three(value, what: str, unit: str) -> tuple[float, float, float]:
    """One value or three (body or turbulence axes), each >= 0."""
    v = np.full(3, as_real(value, what, nonnegative=True, unit=unit)) if np.ndim(value) == 0 else as_vector(value, 3, what)
    if np.any(v < 0.0):
        raise InputError(f"{what} must be >= 0 {unit}, got {v.tolist()}")
    return tuple(float(x) for x in v)


def _dryden(table: dict, mean: tuple[float, float, float]) -> Dryden:
    """The turbulence of a ``model = "dryden"`` wind: (sigma, length) or the low-altitude model (w20, altitude)."""
    explicit, low = ("sigma" in table or "length" in table), ("w20" in table or "altitude" in table)
    if explicit == low:
        raise InputError('mission [wind] model = "dryden" needs either sigma [m/s] and length [m], or w20 [m/s] and altitude [m]')
    speed = float(np.linalg.norm(mean))
    if "airspeed" in table:
        airspeed = as_real(table["airspeed"], "mission [wind] airspeed", positive=True, hi=WIND_SPEED_MAX, unit="m/s")
    elif speed > 0.0:
        airspeed = speed
    else:
        raise InputError("mission [wind]: a Dryden wind without a mean wind needs airspeed [m/s] (the speed the turbulence passes at)")
    if low:
        if "w20" not in table or "altitude" not in table:
            raise InputError("mission [wind]: the low-altitude Dryden model needs both w20 [m/s] and altitude [m]")
        w20 = as_real(table["w20"], "mission [wind] w20", nonnegative=True, hi=WIND_SPEED_MAX, unit="m/s")
        return Dryden.low_altitude(as_real(table["altitude"], "mission [wind] altitude", positive=True, unit="m"), w20, airspeed)
    if "sigma" not in table or "length" not in table:
        raise InputError("mission [wind]: the Dryden model needs both sigma [m/s] and length [m] (u, v, w)")
    sigma = _three(table["sigma"], "mission [wind] sigma", "m/s")
    length = as_vector(table["length"], 3, "mission [wind] length")
    if np.any(length <= 0.0):
        raise InputError(f"mission [wind] length must be > 0 m, got {length.tolist()}")
    return Dryden(sigma, tuple(float(x) for x in length), airspeed)


def read_wind(source: Mapping) -> Wind | None:
    """The :class:`Wind` of a mission's ``[wind]`` table and ``[[gust]]`` tables (None when it has neither)."""
    gusts = []
    for k, g in enumerate(_tables(source, "gust")):
        g = _keys(g, GUST_KEYS, f"gust {k + 1}", GUST_KEYS)
        start = as_real(g["start"], f"mission gust {k + 1} start", nonnegative=True, unit="s")
        duration = as_real(g["duration"], f"mission gust {k + 1} duration", positive=True, unit="s")
        gusts.append(Gust(start, duration, _wind_vector(g["amplitude_world"], f"mission gust {k + 1} amplitude_world")))
    if "wind" not in source:
        return Wind(gusts=tuple(gusts)) if gusts else None
    table = _keys(source["wind"], WIND_KEYS, "[wind]", ("model",))
    model = as_name(table["model"], "model", WIND_MODELS, "mission [wind] model")
    mean = _wind_vector(table.get("mean_world", (0.0, 0.0, 0.0)), "mission [wind] mean_world")
    if model == "mean":
        extra = [k for k in table if k not in ("model", "mean_world")]
        if extra:
            raise InputError(f'mission [wind] model = "mean" has no turbulence: {extra} belong to model = "dryden"')
        return Wind(mean=mean, gusts=tuple(gusts))
    seed = as_int(table["seed"], "mission [wind] seed", lo=0) if "seed" in table else None
    return Wind(mean=mean, turbulence=_dryden(table, mean), gusts=tuple(gusts), seed=seed)


def read_drag(source: Mapping, wind: Wind | None) -> AerodynamicDrag | None:
    """The base's :class:`AerodynamicDrag` of a mission's ``[drag]`` table, in ``wind`` (a wind needs a drag)."""
    if "drag" not in source:
        if wind is not None:
            raise InputError(
                "mission: a [wind] or [[gust]] acts on the vehicle through its drag: add a [drag] table "
                "(linear [N s/m] and/or quadratic [N s^2/m^2], body axes; e.g. linear = 0.3)"
            )
        return None
    table = _keys(source["drag"], DRAG_KEYS, "[drag]")
    linear = _three(table.get("linear", 0.0), "mission [drag] linear", "N s/m")
    quadratic = _three(table.get("quadratic", 0.0), "mission [drag] quadratic", "N s^2/m^2")
    angular = as_real(table.get("angular", 0.0), "mission [drag] angular", nonnegative=True, unit="N m s/rad")
    if wind is not None and not (any(linear) or any(quadratic)):
        raise InputError("mission: the [wind] acts through [drag] linear or quadratic, both 0 here: the wind would do nothing")
    return AerodynamicDrag(linear=linear, quadratic=quadratic, angular=angular, wind=wind)


def read_controller(source: Mapping, folder: Path | None) -> ControllerChoice:
    """The ``[controller]`` table: ``name``, and ``gains`` (a gains file relative to ``folder``) or a gains file's tables."""
    table = source.get("controller", {})
    if not isinstance(table, Mapping):
        raise InputError(f"mission [controller] must be a table (name = ..., gains = ... or gains tables), got {table!r:.80}")
    table = dict(table)
    name = table.pop("name", "")
    if not isinstance(name, str):
        raise InputError(f"mission [controller] name must be a controller's name (a string), got {name!r}")
    gains = table.pop("gains", "")
    if gains != "" and table:
        raise InputError(f"mission [controller]: gains = {gains!r} and the gains tables {sorted(table)} both set the gains; give one")
    if not isinstance(gains, str):
        raise InputError(
            f"mission [controller] gains must be 'platform', 'class', a gain table or a FILE.toml, got {gains!r:.80} "
            "(tables of a gains file go in [controller.targets], [controller.idc.gains], ...)"
        )
    if gains.endswith(".toml") and not Path(gains).is_absolute():
        if folder is None:  # data without its file (a campaign carries the content): relative to what?
            raise InputError(
                f"mission [controller] gains = {gains!r}: a mission given as data has no folder to find a relative gains file "
                "in; write its tables in [controller] ([controller.targets], [controller.idc.gains]...) or give an absolute path"
            )
        gains = str(folder / gains)
    return ControllerChoice(name, table if table else gains)


def read_motor(source: Mapping) -> dict:
    """The ``[motor]`` table (keys :data:`qprr.sim.actuators.MOTOR_KEYS`), as written."""
    return _keys(source.get("motor", {}), MOTOR_KEYS, "[motor]")


def read_events(source: Mapping) -> tuple[tuple[Phase, ...], PayloadSchedule | None]:
    """The ``[[phase]]`` and ``[[payload]]`` tables (keys :data:`PHASE_KEYS`, :data:`PAYLOAD_KEYS`, all required)."""
    phases, events = [], []
    for k, table in enumerate(_tables(source, "phase")):
        if not isinstance(table, Mapping) or set(table) != set(PHASE_KEYS):
            raise InputError(f"mission phase {k + 1} has keys {sorted(table)}; a phase needs exactly {list(PHASE_KEYS)}")
        phases.append(Phase(table["coordinate"], table["start"], table["end"], table["target"]))
    for k, table in enumerate(_tables(source, "payload")):
        if not isinstance(table, Mapping) or set(table) != set(PAYLOAD_KEYS):
            raise InputError(f"mission payload event {k + 1} has keys {sorted(table)}; an event needs exactly {list(PAYLOAD_KEYS)}")
        time = as_real(table["time"], f"mission payload event {k + 1} time", nonnegative=True, unit="s")
        events.append(PayloadChange(time, as_real(table["mass"], f"mission payload event {k + 1} mass", nonnegative=True, unit="kg")))
    return tuple(phases), (PayloadSchedule(tuple(events)) if events else None)


def read_mission_file(source, *, phases_required: bool = True) -> MissionFile:
    """A mission from a TOML file or a mapping of the same tables (module docstring).

    ``phases_required=False`` accepts a mission without phases (its reference given otherwise,
    :class:`qprr.scenarios.missions.MissionSettings`)."""
    folder, name = None, "mission"
    if isinstance(source, (str, Path)):
        path = Path(source)
        folder, name = path.parent, path.stem
        source = read_toml(path, "mission file", f"a TOML file of [[phase]] tables: {', '.join(PHASE_KEYS)}")
    if not isinstance(source, Mapping):
        raise InputError(f"a mission is a TOML file or a mapping of 'phase' (and 'payload') tables, got {type(source).__name__}")
    for key in source:
        if key not in TABLES:
            raise UnknownNameError("mission table", key, TABLES)
    name = source.get("name", name)
    if not isinstance(name, str) or not name.strip():
        raise InputError(f"mission name must be a non-empty string (the run's label), got {name!r}")
    phases, payload = read_events(source)
    if phases_required and not phases:
        raise InputError("a mission needs at least one [[phase]] table")
    drag = read_drag(source, read_wind(source))
    return MissionFile(name, phases, payload, drag, read_motor(source), read_controller(source, folder))


def motor_stage_of(platform: Platform, table: Mapping, plausibility: Plausibility | None = DEFAULT) -> RotorDynamics:
    """The rotor stage a mission's ``[motor]`` ``table`` flies on ``platform``, starting at hover: the table's keys over the
    rotor file's ``[motor]`` table (:attr:`qprr.model.Platform.motor`); the time constants checked against ``plausibility``."""
    platform = check_platform(platform)
    merged = {**platform.motor, **table}
    missing = [k for k in ("thrust_factor", "time_constant") if k not in merged]
    if missing:
        raise InputError(
            f"mission [motor] needs {missing} (thrust_factor [N s^2], time_constant [s]): the rotor file of platform "
            f"{platform.name!r} has no [motor] table giving them"
        )
    stage = rotor_dynamics_from_mapping({"motor": merged}, platform.rotors, initial="hover")
    check_time_constant(stage.time_constant, plausibility, "mission [motor] time_constant")
    return stage


__all__ = [
    "DRAG_KEYS",
    "GUST_KEYS",
    "PAYLOAD_KEYS",
    "PHASE_KEYS",
    "TABLES",
    "WIND_KEYS",
    "WIND_MODELS",
    "WIND_SPEED_MAX",
    "ControllerChoice",
    "MissionFile",
    "motor_stage_of",
    "read_controller",
    "read_drag",
    "read_events",
    "read_mission_file",
    "read_motor",
    "read_wind",
]
