"""Gymnasium environments for any aerial manipulator (docs/rl.md): hover, reach, carry a payload, track a mission.

Importing this package registers four environments, each with a scalar ``entry_point`` (``gymnasium.make``) and a
batched ``vector_entry_point`` (``gymnasium.make_vec``: N robots stepped through one
:class:`qprr.sim.batch.BatchSimulator`, not N copies of the scalar environment):

=================  =====================================================================================
id                 task
=================  =====================================================================================
``qprr/Hover-v0``  hold the home point
``qprr/Reach-v0``  bring the end effector to a target while hovering
``qprr/Carry-v0``  pick a payload (it attaches when the end effector comes close) and carry it to a goal
``qprr/Track-v0``  follow a mission's reference under wind
=================  =====================================================================================

Every environment takes the platform (``platform="borinot_flying_arm_2"``, a Platform, or ``urdf=`` and ``rotors=``),
the action mode (:class:`~qprr.envs.settings.ActionMode`: ``"thrusts"``, ``"wrench"``, ``"reference"``) and the
randomisation (:mod:`qprr.envs.randomize`); the options are the fields of :class:`~qprr.envs.settings.EnvSettings`.
:func:`~qprr.envs.baseline.baseline_return` flies a classical qprr controller on the same seeds.

Needs Gymnasium (the ``rl`` extra): without it, importing this package raises
:class:`~qprr.errors.MissingDependencyError` with the install command.
"""

from __future__ import annotations

from ..errors import MissingDependencyError

try:
    import gymnasium
except ImportError as exc:
    raise MissingDependencyError("gymnasium", "the learning environments (qprr.envs)", 'pip install "qprr[rl]"') from exc

from .baseline import BaselineResult, BaselineStatus, baseline_return
from .core import BatchCore, EndReason
from .scalar import AerialEnv
from .settings import ENV_IDS, ActionMode, EnvSettings, Geometry, TaskKind
from .vector import AerialVectorEnv

ENTRY_POINT = "qprr.envs.scalar:AerialEnv"
VECTOR_ENTRY_POINT = "qprr.envs.vector:AerialVectorEnv"


def register_envs() -> tuple[str, ...]:
    """Register the four environments with Gymnasium (done on import; a second call changes nothing); their ids."""
    for kind, env_id in ENV_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=ENTRY_POINT, vector_entry_point=VECTOR_ENTRY_POINT, kwargs={"task": kind.value})
    return tuple(ENV_IDS.values())


register_envs()

__all__ = [
    "ENTRY_POINT",
    "ENV_IDS",
    "VECTOR_ENTRY_POINT",
    "ActionMode",
    "AerialEnv",
    "AerialVectorEnv",
    "BaselineResult",
    "BaselineStatus",
    "BatchCore",
    "EndReason",
    "EnvSettings",
    "Geometry",
    "TaskKind",
    "baseline_return",
    "register_envs",
]
