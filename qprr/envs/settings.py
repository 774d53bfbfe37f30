"""The settings of the learning environments, written once: what an environment flies and how it is computed.

:class:`EnvSettings` holds every option of :class:`qprr.envs.vector.AerialVectorEnv` and
:class:`qprr.envs.scalar.AerialEnv` (their keyword arguments are its fields, as :func:`qprr.sim.simulate`'s are
those of :class:`~qprr.sim.config.SimConfig`); :class:`Geometry` the task geometry (home point, ranges of the drawn
goals); :class:`ActionMode` and :class:`TaskKind` the two choices an environment is built from.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from functools import lru_cache
from pathlib import Path

from ..errors import InputError, UnknownNameError
from ..model import Platform
from ..platforms import DEFAULT_PLATFORM, resolve
from ..sim.config import INTEGRATORS, SimConfig
from ..validation import as_file, as_int, as_name, as_real, as_vector
from .randomize import Randomization


class ActionMode(Enum):
    """What an action commands (every action is a vector in [-1, 1]; docs/rl.md, "Action modes").

    ``THRUSTS``: each rotor's thrust, -1 -> f_min, +1 -> f_max, then each arm joint's effort, -1 -> -limit, +1 ->
    +limit; ``WRENCH``: the producible rows of the body wrench [f_B; tau_B] around hover, then the arm efforts, the
    rotor thrusts by clipped least squares (:class:`qprr.envs.actions.WrenchMap`); ``REFERENCE``: offsets of the base
    position, yaw and arm joints added to the task's reference, which a qprr controller tracks (residual learning).
    """

    THRUSTS = "thrusts"
    WRENCH = "wrench"
    REFERENCE = "reference"


class TaskKind(Enum):
    """The four tasks (docs/rl.md): hover at a point, reach a target with the end effector while hovering, pick a
    payload and carry it to a goal, track a mission under wind."""

    HOVER = "hover"
    REACH = "reach"
    CARRY = "carry"
    TRACK = "track"


ENV_IDS = {
    TaskKind.HOVER: "qprr/Hover-v0",
    TaskKind.REACH: "qprr/Reach-v0",
    TaskKind.CARRY: "qprr/Carry-v0",
    TaskKind.TRACK: "qprr/Track-v0",
}
"""The Gymnasium id of each task (registered by importing :mod:`qprr.envs`)."""

REFERENCE_CONTROLLER_PERIOD = 0.005
"""The reference mode's default controller period [s] (4 controller calls per action at the default control period):
at 20 ms the IDC's wrist loop on the Q-PRR goes unstable once Carry's 53 g payload attaches, at 5 ms and 1 ms it
carries it (measured on Carry-v0, docs/rl.md)."""

REFERENCE_CONTROLLERS = ("idc", "dsid", "mfc", "decoupled", "mpc")
"""Controllers the ``reference`` action mode can run (names of :data:`qprr.control.CONTROLLERS`; ``mpc`` needs crocoddyl)."""


def task_kind(task, name: str = "task") -> TaskKind:
    """``task`` (a :class:`TaskKind`, its value such as ``"reach"`` or its Gymnasium id ``"qprr/Reach-v0"``) as a TaskKind;
    an unknown one raises :class:`~qprr.errors.UnknownNameError` naming the argument ``name`` and listing the tasks."""
    if isinstance(task, TaskKind):
        return task
    for kind, env_id in ENV_IDS.items():
        if task in (kind.value, env_id):
            return kind
    raise UnknownNameError(f"task or env id ({name})", task, tuple(k.value for k in TaskKind) + tuple(ENV_IDS.values()))


@dataclass(frozen=True)
class Geometry:
    """Where the tasks happen and how far their random goals reach (world frame, SI units).

    ``home`` [m]: the hover point every episode starts near (world x, y, z); ``init_position`` [m], ``init_yaw``
    [rad], ``init_arm`` (a fraction): half-widths of the uniform perturbation of the initial state around the
    task's start (the arm's as a fraction of the way from the neutral posture to its limits, the missions'
    ``reach_fraction`` vocabulary); ``base_range`` [m] (x, y, z) and ``yaw_range`` [rad]: half-widths of the base
    goals of Reach and Carry around ``home``; ``reach_fraction``: arm goals within this fraction of the way from the
    neutral posture to each joint limit (unlimited joints: to +-pi); ``track_range`` [m]: half-widths of Track's
    random waypoints around ``home``.
    """

    home: tuple[float, float, float] = (0.0, 0.0, 2.0)
    init_position: float = 0.1
    init_yaw: float = 0.1
    init_arm: float = 0.05
    base_range: tuple[float, float, float] = (0.3, 0.3, 0.2)
    yaw_range: float = 0.5
    reach_fraction: float = 0.5
    track_range: tuple[float, float, float] = (1.0, 1.0, 0.5)

    def __post_init__(self) -> None:
        for name in ("home", "base_range", "track_range"):
            v = as_vector(getattr(self, name), 3, f"geometry.{name}")
            if name != "home" and (v < 0.0).any():
                raise InputError(f"geometry.{name} must be half-widths >= 0 m, got {v.tolist()}")
            object.__setattr__(self, name, tuple(float(x) for x in v))
        for name in ("init_position", "init_yaw", "init_arm", "yaw_range", "reach_fraction"):
            object.__setattr__(self, name, as_real(getattr(self, name), f"geometry.{name}", nonnegative=True))
        for name in ("init_arm", "reach_fraction"):
            if getattr(self, name) > 1.0:
                raise InputError(f"geometry.{name} is a fraction of the way to the joint limits, in [0, 1]; got {getattr(self, name)!r}")


@dataclass(frozen=True)
class EnvSettings:
    """Every option of an environment (its keyword arguments; docs/rl.md).

    The robot: ``platform`` a name (``"q-prr"``, ``"borinot_flying_arm_2"``, ``"hextilt_flying_arm_5"``, a (2.1) name
    such as ``"HEX-RRR"``) or a :class:`~qprr.model.Platform`, or ``urdf`` + ``rotors`` files (+ ``ee_frame``) as
    :func:`qprr.platforms.resolve` takes them; default ``"q-prr"``.

    What is learnt: ``action_mode`` (an :class:`ActionMode` or its value); ``controller`` the qprr controller the
    ``reference`` mode runs (:data:`REFERENCE_CONTROLLERS`); ``residual`` the action's full scale in that mode:
    (base position [m], yaw [rad], arm as a fraction of the way from the reference to the joint limits);
    ``randomize`` the perturbations drawn per episode (:class:`qprr.envs.randomize.Randomization`: a mapping in the
    campaign vocabulary, e.g. ``{"model.mass": (0.9, 1.1), "tau": 0.02}``; None: the task's default, nothing but for
    Track); ``mission`` Track's reference (any trajectory with ``sample(t)``, :mod:`qprr.trajectory`; None: random
    waypoints); ``geometry`` a :class:`Geometry`.

    How it is computed: ``duration`` [s] of an episode (None: the task's, docs/rl.md); ``control_period`` [s]
    between actions, an integer multiple of the integration step ``dt`` [s] (the plant holds the command over the
    period: ``control_period / dt`` steps of ``integrator``, :class:`qprr.sim.batch.BatchSimulator`);
    ``controller_period`` [s] the reference mode's controller period, dividing ``control_period`` (None:
    :data:`REFERENCE_CONTROLLER_PERIOD`, or ``control_period`` when shorter; the policy's residual is held while the
    controller runs faster, as a flight controller's inner loop does; the rotor lag acts at this period); ``threads`` of
    the batched dynamics (Pinocchio's ``abaInParallel``; default 1: its OpenMP threads spin at barriers, and on a
    2-core machine shared with other work 2 threads made the forward dynamics of 64 copies 11 times slower, 4.3 ms
    against 0.4 ms, measured; give the number of idle cores on a machine of your own); ``box`` [m]: an episode terminates
    when the base is farther than this from its reference; ``max_tilt`` [rad]: ... or tilts more than this (angle
    between z_B and the world's z); ``render_mode``: None (no rendering).
    """

    platform: str | Platform | None = None
    urdf: str | Path | None = None
    rotors: str | Path | None = None
    ee_frame: str | None = None
    action_mode: ActionMode | str = ActionMode.THRUSTS
    controller: str = "idc"
    residual: tuple[float, float, float] = (0.5, 0.5, 0.25)
    randomize: Mapping | Randomization | None = None
    mission: object = None
    geometry: Geometry = field(default_factory=Geometry)
    duration: float | None = None
    control_period: float = 0.02
    controller_period: float | None = None
    dt: float = 1e-3
    integrator: str = "midpoint"
    threads: int = 1
    box: float = 2.0
    max_tilt: float = 1.2
    render_mode: str | None = None

    def __post_init__(self) -> None:
        self._check_robot()
        if not isinstance(self.action_mode, ActionMode):
            mode = as_name(self.action_mode, "action_mode", tuple(m.value for m in ActionMode), "action mode")
            object.__setattr__(self, "action_mode", ActionMode(mode))
        as_name(self.controller, "controller", REFERENCE_CONTROLLERS, "controller of the reference action mode")
        residual = as_vector(self.residual, 3, "residual")
        if (residual < 0.0).any() or residual[2] > 1.0:
            raise InputError(f"residual must be (position >= 0 m, yaw >= 0 rad, arm fraction in [0, 1]), got {residual.tolist()}")
        object.__setattr__(self, "residual", tuple(float(x) for x in residual))
        if not isinstance(self.randomize, Randomization):
            object.__setattr__(self, "randomize", None if self.randomize is None else Randomization.from_mapping(self.randomize))
        if not isinstance(self.geometry, Geometry):
            raise InputError(
                f"geometry must be a qprr.envs.Geometry (e.g. Geometry(home=(0, 0, 2))), got {type(self.geometry).__name__} {self.geometry!r}"
            )
        object.__setattr__(self, "dt", as_real(self.dt, "dt", positive=True, unit="s"))
        object.__setattr__(self, "control_period", as_real(self.control_period, "control_period", positive=True, unit="s"))
        as_name(self.integrator, "integrator", tuple(INTEGRATORS))
        self.sim_config()  # an integer number of integration steps per control period
        if self.duration is not None:
            object.__setattr__(self, "duration", as_real(self.duration, "duration", positive=True, unit="s"))
            if self.duration < self.control_period:
                raise InputError(
                    f"duration = {self.duration!r} s is shorter than one control period (control_period = {self.control_period!r} s): "
                    "an episode lasts at least one action; give a longer duration or a shorter control_period"
                )
        if self.controller_period is not None and self.action_mode is not ActionMode.REFERENCE:
            raise InputError(f"controller_period applies to action_mode='reference' (a controller runs there), not to {self.action_mode.value!r}")
        if self.action_mode is ActionMode.REFERENCE:
            self._check_controller_period()
        as_int(self.threads, "threads", lo=1)
        object.__setattr__(self, "box", as_real(self.box, "box", positive=True, unit="m"))
        tilt = as_real(self.max_tilt, "max_tilt", positive=True, unit="rad")
        if not tilt < math.pi:
            raise InputError(f"max_tilt must be in (0, pi) rad, got {tilt!r}")
        if self.render_mode is not None:
            raise UnknownNameError("render mode (render_mode)", self.render_mode, ("None: the environments do not render; qprr.viz draws a run",))

    def _check_robot(self) -> None:
        """The robot's options: a platform name (known, loaded once per process) or a Platform, or a URDF file with its
        rotor file (and an optional ee_frame), not a mixture (:func:`qprr.platforms.resolve`'s rules, checked here)."""
        if self.urdf is None:
            if self.rotors is not None or self.ee_frame is not None:
                given = ", ".join(f"{k} = {v!r}" for k, v in (("rotors", self.rotors), ("ee_frame", self.ee_frame)) if v is not None)
                raise InputError(f"a rotor file (rotors) and an end-effector frame (ee_frame) go with a URDF (urdf=...): got {given} without urdf")
            if not isinstance(self.platform, (str, Platform)) and self.platform is not None:
                raise InputError(
                    f"platform must be a name (e.g. {DEFAULT_PLATFORM!r}), a qprr Platform or None with urdf=..., "
                    f"got {type(self.platform).__name__} {self.platform!r}"
                )
            if not isinstance(self.platform, Platform):
                _named_platform(self.platform)  # an unknown name raises UnknownNameError listing the platforms
            return
        if self.platform is not None:
            raise InputError(f"give a platform (platform = {self.platform!r}) or URDF files (urdf = {str(self.urdf)!r}), not both")
        if self.rotors is None:
            raise InputError(f"the URDF (urdf = {str(self.urdf)!r}) needs its rotor description: give rotors= a TOML rotor file (docs/platforms.md)")
        as_file(self.urdf, "urdf", what="URDF file")
        as_file(self.rotors, "rotors", what="rotor file (TOML)")
        if self.ee_frame is not None and not isinstance(self.ee_frame, str):
            raise InputError(f"ee_frame must be the name of a frame of the URDF, got {type(self.ee_frame).__name__} {self.ee_frame!r}")

    def _check_controller_period(self) -> None:
        """The reference mode's controller period: a whole number of integration steps, dividing the control period."""
        given = self.controller_period is not None
        period = as_real(self.controller_period, "controller_period", positive=True, unit="s") if given else self.actuation_period
        SimConfig(dt=self.dt, control_period=period)  # an integer number of integration steps
        k = round(self.control_period / period)
        if k < 1 or abs(k * period - self.control_period) > 1e-9 * self.control_period:
            what = f"controller_period = {period!r} s" if given else f"the reference mode's default controller period {period!r} s"
            raise InputError(
                f"{what} must divide control_period = {self.control_period!r} s (a whole number of controller calls per "
                "action): give controller_period= a divisor of control_period"
            )

    @property
    def actuation_period(self) -> float:
        """The period at which thrusts are commanded [s]: in the reference mode ``controller_period`` (default
        :data:`REFERENCE_CONTROLLER_PERIOD`, or ``control_period`` when shorter), else ``control_period``."""
        if self.action_mode is not ActionMode.REFERENCE:
            return self.control_period
        if self.controller_period is not None:
            return float(self.controller_period)
        return min(REFERENCE_CONTROLLER_PERIOD, self.control_period)

    @property
    def actuation_steps(self) -> int:
        """Thrust commands per action (``control_period / actuation_period``)."""
        return int(round(self.control_period / self.actuation_period))

    def sim_config(self) -> SimConfig:
        """The plant's numerics as a :class:`~qprr.sim.config.SimConfig` (dt, integrator, control period; stops on)."""
        return SimConfig(dt=self.dt, integrator=self.integrator, control_period=self.control_period)

    @property
    def substeps(self) -> int:
        """Integration steps per actuation period (:attr:`actuation_period`)."""
        return int(round(self.actuation_period / self.dt))

    def resolve_platform(self) -> Platform:
        """The platform these settings name (:func:`qprr.platforms.resolve`; named platforms are loaded once per process)."""
        if isinstance(self.platform, Platform):
            return self.platform
        if self.urdf is not None:
            return resolve(urdf=self.urdf, rotors=self.rotors, ee_frame=self.ee_frame)
        return _named_platform(self.platform)


@lru_cache(maxsize=16)
def _named_platform(name: str | None) -> Platform:
    """A named platform, loaded once (platforms are never modified: the plant copies the model)."""
    return resolve(name)


def settings_with(settings: EnvSettings | None, options: Mapping) -> EnvSettings:
    """``settings`` (default ``EnvSettings()``) with the fields named in ``options`` replaced; an unknown name raises
    :class:`~qprr.errors.UnknownNameError` listing the fields."""
    base = EnvSettings() if settings is None else settings
    if not isinstance(base, EnvSettings):
        raise InputError(f"settings must be a qprr.envs.EnvSettings (or None: the defaults), got {type(base).__name__} {base!r}")
    if not isinstance(options, Mapping):
        raise InputError(f"options must be a mapping of EnvSettings fields to values (e.g. {{'duration': 1.0}}), got {options!r}")
    names = tuple(f.name for f in dataclasses.fields(EnvSettings))
    for key in options:
        if key not in names:
            raise UnknownNameError("environment option", key, names)
    return dataclasses.replace(base, **options) if options else base


__all__ = [
    "ENV_IDS",
    "REFERENCE_CONTROLLERS",
    "REFERENCE_CONTROLLER_PERIOD",
    "ActionMode",
    "EnvSettings",
    "Geometry",
    "TaskKind",
    "settings_with",
    "task_kind",
]
