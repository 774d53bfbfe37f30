"""Frame pose and position tasks (the end effector by default, or the base)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...charts import check_rotation
from ...errors import InputError
from ...model import Platform, check_platform
from ...validation import as_vector
from .base import Task, scaled, scaled_error, sqrt_weights, task_name


class PoseTask(Task):
    """Frame pose: f = log6(M_d^-1 M(q)) -> 0, J = Jlog6(M_d^-1 M) J_local.

    ``target`` is the desired world placement of ``frame`` (default: the end effector);
    ``weights`` (6,) scale the [translation, rotation] rows of the error (metres and radians).
    """

    dim = 6

    def __init__(self, platform: Platform, target: pin.SE3, frame=None, weights=None, name: str = "pose"):
        check_platform(platform)
        self.set_target(target)
        self.frame = platform.ee_frame if frame is None else platform.frame_id(frame)
        self._sw = sqrt_weights(weights, 6, "PoseTask weights")
        self.name = task_name(name)

    def set_target(self, target: pin.SE3) -> None:
        """Aim the task at another world placement (a solver keeps its tasks and retargets them per solve)."""
        if not isinstance(target, pin.SE3):
            raise InputError(f"PoseTask target must be a pinocchio.SE3, got {type(target).__name__}")
        if not (np.isfinite(target.translation.sum()) and np.isfinite(target.rotation.sum())):
            raise InputError(f"PoseTask target must be finite, got {target}")
        self.target = target
        self._target_inv = target.inverse()

    def linearize(self, platform, data, q):
        J = pin.getFrameJacobian(platform.model, data, self.frame, pin.LOCAL)
        M = self._target_inv * data.oMf[self.frame]
        return scaled(self._sw, pin.Jlog6(M) @ J, -pin.log6(M).vector)

    def error(self, platform, data, q):
        return scaled_error(self._sw, -pin.log6(self._target_inv * data.oMf[self.frame]).vector)


class BasePoseTask(PoseTask):
    """Pose of the base frame B: the level-2 task of a fully actuated platform (it may hold any attitude)."""

    def __init__(self, platform: Platform, target: pin.SE3, weights=None, name: str = "base_pose"):
        super().__init__(platform, target, check_platform(platform).base_frame, weights, name)


class BaseOrientationTask(Task):
    """Orientation of the base frame B: log3(R_d^T R_b) -> 0 (3), the level-2 task of a fully actuated platform.

    A tilted-rotor platform can hold any attitude whose wrench its rotors produce, but a level base
    costs the least thrust; its position is left to the levels above (the end effector).
    J = Jlog3(R_d^T R_b) [0 I 0] (body angular velocity of the free flyer).
    """

    dim = 3

    def __init__(self, platform: Platform, R_target, weights=None, name: str = "base_orientation"):
        check_platform(platform)
        self.set_target(R_target)
        self._sw = sqrt_weights(weights, 3, "BaseOrientationTask weights")
        self.name = task_name(name)

    def set_target(self, R_target) -> None:
        """Another world orientation of the base (a solver keeps its tasks and retargets them per solve)."""
        self.target = check_rotation(R_target, "BaseOrientationTask R_target").copy()

    def linearize(self, platform, data, q):
        Rerr = self.target.T @ data.oMi[1].rotation
        J = np.zeros((3, platform.nv))
        J[:, 3:6] = pin.Jlog3(Rerr)
        return scaled(self._sw, J, -pin.log3(Rerr))

    def error(self, platform, data, q):
        return scaled_error(self._sw, -pin.log3(self.target.T @ data.oMi[1].rotation))


class PositionTask(Task):
    """Frame position only: p(q) -> ``p_world`` (world axes), the orientation left free.

    J = rows 0..2 of the LOCAL_WORLD_ALIGNED frame Jacobian (d p_world / dt = J v).
    """

    dim = 3

    def __init__(self, platform: Platform, p_world, frame=None, weights=None, name: str = "position"):
        self.frame = check_platform(platform).ee_frame if frame is None else platform.frame_id(frame)
        self.set_target(p_world)
        self._sw = sqrt_weights(weights, 3, "PositionTask weights")
        self.name = task_name(name)

    def set_target(self, p_world) -> None:
        """Aim the task at another world position [m] (a solver keeps its tasks and retargets them per solve)."""
        self.target = as_vector(p_world, 3, "PositionTask p_world").copy()

    def linearize(self, platform, data, q):
        J = pin.getFrameJacobian(platform.model, data, self.frame, pin.LOCAL_WORLD_ALIGNED)[0:3]
        return scaled(self._sw, J, self.target - data.oMf[self.frame].translation)

    def error(self, platform, data, q):
        return scaled_error(self._sw, self.target - data.oMf[self.frame].translation)
