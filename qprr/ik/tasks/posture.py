"""Arm posture: a preferred configuration of the arm joints (the last, lowest-priority level)."""

from __future__ import annotations

import numpy as np

from ...model import check_platform
from ...validation import as_vector
from .base import Task, scaled, scaled_error, sqrt_weights, task_name


class PostureTask(Task):
    """Arm posture: q_arm -> ``q_arm_ref`` (inside the joint limits), the configuration entries 7 onwards."""

    dim = 0

    def __init__(self, platform, q_arm_ref, weights=None, name: str = "posture"):
        self.platform = check_platform(platform)
        self.set_reference(q_arm_ref)
        self.dim = platform.n_arm
        self._sw = sqrt_weights(weights, platform.n_arm, "PostureTask weights")
        self.name = task_name(name)
        self._J = np.zeros((platform.n_arm, platform.nv))
        self._J[:, 6:] = np.eye(platform.n_arm)

    def set_reference(self, q_arm_ref) -> None:
        """Another preferred arm configuration (inside the joint limits; a solver retargets its task per solve)."""
        self.ref = self.platform.check_arm_limits(as_vector(q_arm_ref, self.platform.n_arm, "PostureTask q_arm_ref"), "PostureTask q_arm_ref").copy()

    def linearize(self, platform, data, q):
        return scaled(self._sw, self._J, self.ref - q[7:])

    def error(self, platform, data, q):
        return scaled_error(self._sw, self.ref - q[7:])
