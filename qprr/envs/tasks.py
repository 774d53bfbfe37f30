"""The four tasks: what an episode starts from, the reference it offers, its reward weights and its success criterion.

Every episode has a *plan*: a reference trajectory in thesis coordinates xi = [x, y, z, phi, theta, psi, q_arm]
(a :class:`qprr.trajectory.MultiPhase` of septic transitions, or Track's ``mission``), which the ``reference`` action
mode's controller tracks and the observation reports (the base error to it, its velocity).  Roll and pitch are not
planned (the controllers derive them, Thesis (6.17)).  Drawn per episode from the episode's generator
(:func:`plan_episode`, in this order): the goals of the task, then the perturbation of the initial state.

=========  ==========================================================================================  ========
task       episode                                                                                     duration
=========  ==========================================================================================  ========
Hover      start near the home point (:class:`~qprr.envs.settings.Geometry`), hold it; the plan moves     5 s
           the base to it in 1.5 s
Reach      a goal pose (base within ``base_range`` of home, yaw, an arm posture within                     6 s
           ``reach_fraction`` of the joint limits); the target is the end effector's position there;
           the plan reaches the goal pose in 2.5 s
Carry      two goal poses: the payload hangs where the end effector is at the first (the pick point),     10 s
           the goal is where it is at the second; the plan reaches the pick pose in 3 s, holds 1 s,
           reaches the place pose in 3 s; the payload attaches when the end effector comes within
           ``ATTACH_RADIUS`` of it
Track      three waypoints within ``track_range`` of home (base, yaw, arm posture), 3 s each, under the     10 s
           wind of the default randomisation (or the given ``mission``)
=========  ==========================================================================================  ========

Success (:class:`Success`), judged at the end of an episode that reached its time limit: Hover, the base within
0.1 m of the home point over the last second; Reach, the end effector within 0.05 m of the target over the last
second; Carry, the payload attached and within 0.1 m of the goal over the last second; Track, the mean distance of
the base from its reference over the episode below 0.15 m.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..errors import InputError
from ..kinematics import check_q
from ..model import Platform, check_model_data, check_platform
from ..sim.loop import check_sample
from ..trajectory import MultiPhase, Phase, TrajectorySample
from ..validation import as_array, as_int, as_matrix, as_real, as_vector
from .randomize import Randomization, check_rng
from .settings import Geometry, TaskKind, task_kind


class Success(Enum):
    """How an episode's success is judged (module docstring)."""

    BASE_WINDOW = "base within tolerance of the home point over the last window"
    EE_WINDOW = "end effector within tolerance of the target over the last window"
    CARRY_WINDOW = "payload attached and within tolerance of the goal over the last window"
    MEAN_BASE = "mean base error to the reference over the episode below tolerance"


@dataclass(frozen=True)
class RewardWeights:
    """r = alive - base |e_p| - ee |e_ee| - yaw |e_psi| - rate |omega_B| - action mean(a^2) + pickup [attached now]
    - crash [terminated] per control period (docs/rl.md): ``base`` [1/m] on the base's distance to its reference,
    ``ee`` [1/m] on the end effector's distance to the task's target, ``yaw`` [1/rad], ``rate`` [s/rad] on the
    body angular rate, ``action`` on the mean squared action; ``pickup`` once when Carry's payload attaches, ``crash``
    once at a termination."""

    alive: float = 1.0
    base: float = 1.0
    ee: float = 0.0
    yaw: float = 0.1
    rate: float = 0.05
    action: float = 0.01
    pickup: float = 0.0
    crash: float = 10.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            weight = as_real(getattr(self, f.name), f"weights.{f.name}", nonnegative=f.name != "alive")  # alive < 0: a time penalty
            object.__setattr__(self, f.name, weight)


@dataclass(frozen=True)
class TaskSpec:
    """A task's constants: default ``duration`` [s], reward ``weights``, ``success`` criterion with its ``tolerance``
    [m] and ``window`` [s], and the ``randomize`` mapping used when the environment is given none."""

    kind: TaskKind
    duration: float
    weights: RewardWeights
    success: Success
    tolerance: float
    window: float = 1.0
    randomize: Mapping | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", task_kind(self.kind, "kind"))
        for name in ("duration", "tolerance", "window"):
            object.__setattr__(self, name, as_real(getattr(self, name), name, positive=True))
        if not isinstance(self.weights, RewardWeights):
            raise InputError(f"weights must be a qprr.envs.tasks.RewardWeights, got {type(self.weights).__name__} {self.weights!r}")
        if not isinstance(self.success, Success):
            raise InputError(f"success must be a qprr.envs.tasks.Success, got {self.success!r}: one of {[m.name for m in Success]}")
        if self.randomize is not None:
            Randomization.from_mapping(self.randomize)  # names and ranges checked


TASKS = {
    TaskKind.HOVER: TaskSpec(TaskKind.HOVER, 5.0, RewardWeights(), Success.BASE_WINDOW, 0.1),
    TaskKind.REACH: TaskSpec(TaskKind.REACH, 6.0, RewardWeights(base=0.2, ee=2.0), Success.EE_WINDOW, 0.05),
    TaskKind.CARRY: TaskSpec(TaskKind.CARRY, 10.0, RewardWeights(base=0.2, ee=1.0, pickup=10.0), Success.CARRY_WINDOW, 0.1),
    TaskKind.TRACK: TaskSpec(
        TaskKind.TRACK, 10.0, RewardWeights(), Success.MEAN_BASE, 0.15, randomize={"mean_wind": (0.0, 2.0), "gust": (0.0, 3.0), "drag": 0.3}
    ),
}
"""Each task's constants (module docstring)."""

HOVER_MOVE = 1.5
"""Hover: the plan moves the base from its start to the home point in this time [s]."""
REACH_MOVE = 2.5
"""Reach: the plan reaches the goal pose in this time [s]."""
CARRY_PICK = (0.0, 3.0)
"""Carry: the plan reaches the pick pose over this interval [s] ..."""
CARRY_PLACE = (4.0, 7.0)
"""... and the place pose over this one [s]."""
ATTACH_RADIUS = 0.05
"""Carry: the payload attaches when the end effector comes this close to it [m]."""
CARRY_MASS_FRACTION = 0.015
"""Carry: the payload's mass as a fraction of the platform's when ``model.payload`` is not randomised (53 g on the
Q-PRR: the IDC, which does not know it, carries it; 5 % crashes it there, docs/rl.md)."""
TRACK_LEG = 3.0
"""Track: each of the three legs of the random mission lasts this long [s]."""
TRACK_WAYPOINTS = 3


@dataclass(frozen=True)
class EpisodePlan:
    """One episode's start and plan: ``xi0`` (n_xi,) the initial thesis coordinates (at rest), ``trajectory`` the
    reference (``sample(t)``), ``goals`` the goal poses (thesis coordinates) whose end-effector positions are the
    task's targets: Reach's one, Carry's pick and place poses (none for Hover and Track, whose target is the plan's
    end effector at t)."""

    xi0: np.ndarray
    trajectory: object
    goals: tuple[np.ndarray, ...] = ()


def posture(platform: Platform, u: np.ndarray, fraction: float) -> np.ndarray:
    """Arm joints q0 + fraction u (q_limit - q0): ``u`` (n_arm,) in [-1, 1] picks, per joint, the way from the neutral
    posture q0 towards the upper (u > 0) or lower (u < 0) limit (to +-pi for an unlimited joint)."""
    check_platform(platform)
    u = as_vector(u, platform.n_arm, "u")
    if np.abs(u).max(initial=0.0) > 1.0:
        raise InputError(f"u must pick, per arm joint, a way in [-1, 1] towards a limit, got {u.tolist()}")
    fraction = as_real(fraction, "fraction", lo=0.0, hi=1.0)
    q0 = platform.neutral_q()[7:]
    up = np.where(np.isfinite(platform.arm_upper), platform.arm_upper - q0, math.pi)
    down = np.where(np.isfinite(platform.arm_lower), q0 - platform.arm_lower, math.pi)
    return q0 + fraction * np.where(u >= 0.0, u * up, u * down)


def home_xi(platform: Platform, geometry: Geometry) -> np.ndarray:
    """The home pose: the base at ``geometry.home``, level, yaw 0, the arm at its neutral posture."""
    check_platform(platform)
    _check_geometry(geometry)
    xi = platform.neutral_xi()
    xi[0:3] = geometry.home
    return xi


def plan_episode(kind: TaskKind, platform: Platform, rng: np.random.Generator, geometry: Geometry, mission=None) -> EpisodePlan:
    """Draw one episode of the task ``kind`` from ``rng`` (module docstring): goals, then the initial state."""
    kind = task_kind(kind, "kind")
    check_rng(rng)
    home = home_xi(platform, geometry)
    if kind is TaskKind.HOVER:
        xi0 = _perturbed(home, platform, rng, geometry)
        return EpisodePlan(xi0, _multiphase(platform, xi0, [((0.0, HOVER_MOVE), home)]))
    if kind is TaskKind.REACH:
        goal = _goal(home, platform, rng, geometry.base_range, geometry)
        xi0 = _perturbed(home, platform, rng, geometry)
        return EpisodePlan(xi0, _multiphase(platform, xi0, [((0.0, REACH_MOVE), goal)]), (goal,))
    if kind is TaskKind.CARRY:
        pick = _goal(home, platform, rng, geometry.base_range, geometry)
        place = _goal(home, platform, rng, geometry.base_range, geometry)
        xi0 = _perturbed(home, platform, rng, geometry)
        return EpisodePlan(xi0, _multiphase(platform, xi0, [(CARRY_PICK, pick), (CARRY_PLACE, place)]), (pick, place))
    if mission is not None:
        start = mission_sample(mission, np.zeros(1), platform.n_xi).xi[0].copy()
        start[3:5] = 0.0
        return EpisodePlan(_perturbed(start, platform, rng, geometry), mission)
    waypoints = [_goal(home, platform, rng, geometry.track_range, geometry) for _ in range(TRACK_WAYPOINTS)]
    xi0 = _perturbed(home, platform, rng, geometry)
    legs = [((k * TRACK_LEG, (k + 1) * TRACK_LEG), w) for k, w in enumerate(waypoints)]
    return EpisodePlan(xi0, _multiphase(platform, xi0, legs))


def _goal(home: np.ndarray, platform: Platform, rng: np.random.Generator, base_range, geometry: Geometry) -> np.ndarray:
    """A goal pose: base uniform within ``base_range`` of home (3 draws), yaw within ``yaw_range`` (1), arm posture
    within ``reach_fraction`` of the limits (n_arm draws)."""
    xi = home.copy()
    xi[0:3] += rng.uniform(-1.0, 1.0, 3) * np.asarray(base_range)
    xi[5] = rng.uniform(-1.0, 1.0) * geometry.yaw_range
    xi[6:] = posture(platform, rng.uniform(-1.0, 1.0, platform.n_arm), geometry.reach_fraction)
    return xi


def _perturbed(start: np.ndarray, platform: Platform, rng: np.random.Generator, geometry: Geometry) -> np.ndarray:
    """``start`` with its position (3 draws), yaw (1) and arm (n_arm) perturbed uniformly (:class:`Geometry`'s init_*)."""
    xi = start.copy()
    xi[0:3] += rng.uniform(-1.0, 1.0, 3) * geometry.init_position
    xi[5] += rng.uniform(-1.0, 1.0) * geometry.init_yaw
    offset = posture(platform, rng.uniform(-1.0, 1.0, platform.n_arm), geometry.init_arm) - platform.neutral_q()[7:]
    xi[6:] = np.clip(xi[6:] + offset, platform.arm_lower, platform.arm_upper)
    return xi


def _multiphase(platform: Platform, xi0: np.ndarray, legs) -> MultiPhase:
    """Septic transitions of x, y, z, psi and the arm joints from ``xi0`` to each leg's pose over its interval."""
    coordinates = [0, 1, 2, 5, *range(6, platform.n_xi)]
    phases = tuple(Phase(i, t1, t2, float(pose[i])) for (t1, t2), pose in legs for i in coordinates)
    return MultiPhase(phases, tuple(float(x) for x in xi0), name="episode", names=platform.xi_names)


def mission_sample(mission, t: np.ndarray, n_xi: int) -> TrajectorySample:
    """``mission.sample(t)`` checked (finite xi, xi_dot, xi_ddot of shape (len(t), n_xi), :func:`qprr.sim.check_sample`)."""
    t = as_array(t, "t", finite=True, ndim=1)
    n_xi = as_int(n_xi, "n_xi", lo=6)
    try:
        sample = mission.sample(t)
    except AttributeError:
        raise InputError(f"mission must be a trajectory with a sample(t) method (qprr.trajectory), got {type(mission).__name__}") from None
    check_sample(sample, t.shape[0], n_xi)
    return sample


def ee_positions(platform: Platform, data, xi: np.ndarray) -> np.ndarray:
    """End-effector positions (m, 3) [m], world frame, of the thesis coordinates ``xi`` (m, n_xi), one
    forward-kinematics call per row (the nominal model)."""
    check_model_data(platform, data)
    xi = as_matrix(xi, (None, platform.n_xi), "xi")
    out = np.empty((xi.shape[0], 3))
    for k in range(xi.shape[0]):
        out[k] = _ee_origin(platform, data, ch.xi_to_q(xi[k]))
    return out


def frame_position(platform: Platform, data, q: np.ndarray) -> np.ndarray:
    """The end-effector frame's origin [m], world frame, at configuration ``q`` (a copy)."""
    check_model_data(platform, data)
    return _ee_origin(platform, data, check_q(platform, q))


def _check_geometry(geometry) -> Geometry:
    if not isinstance(geometry, Geometry):
        raise InputError(f"geometry must be a qprr.envs.settings.Geometry, got {type(geometry).__name__} {geometry!r}")
    return geometry


def _ee_origin(platform: Platform, data, q: np.ndarray) -> np.ndarray:
    """:func:`frame_position` on checked arguments."""
    pin.forwardKinematics(platform.model, data, q)
    return pin.updateFramePlacement(platform.model, data, platform.ee_frame).translation.copy()


__all__ = [
    "ATTACH_RADIUS",
    "CARRY_MASS_FRACTION",
    "CARRY_PICK",
    "CARRY_PLACE",
    "HOVER_MOVE",
    "REACH_MOVE",
    "TASKS",
    "TRACK_LEG",
    "TRACK_WAYPOINTS",
    "EpisodePlan",
    "RewardWeights",
    "Success",
    "TaskSpec",
    "ee_positions",
    "frame_position",
    "home_xi",
    "mission_sample",
    "plan_episode",
    "posture",
]
