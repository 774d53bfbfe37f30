"""Centre of gravity on the thrust axis (Thesis Sec. 2.5: the reason for the prismatic joint)."""

from __future__ import annotations

import pinocchio as pin

from ...validation import as_vector
from .base import Task, scaled, scaled_error, sqrt_weights, task_name


class ComTask(Task):
    """The CoG offset from the thrust axis (:func:`qprr.kinematics.cog_offset_body`) -> ``target_xy``.

    For the Q-PRR the offset is [x_cm, y_cm] in B (Thesis (3.79)-(3.81)).  Jacobian from
    Pinocchio's CoM Jacobian (:func:`qprr.kinematics.com_jacobian_body`).
    """

    dim = 2

    def __init__(self, target_xy=(0.0, 0.0), weights=None, name: str = "com"):
        self.target = as_vector(target_xy, 2, "ComTask target_xy").copy()
        self._sw = sqrt_weights(weights, 2, "ComTask weights")
        self.name = task_name(name)

    def linearize(self, platform, data, q):
        point, E = platform.thrust_axis[0], platform.thrust_axis_basis
        base = data.oMi[1]
        R = base.rotation
        c_b = R.T @ (data.com[0] - base.translation)
        # the body-frame CoM Jacobian of qprr.kinematics.com_jacobian_body_from, from the data filled by
        # update_kinematics (no argument checks on this per-iteration path): R^T Jcom - [I, -hat(c_b), 0], times E
        J = (E @ R.T) @ data.Jcom
        J[:, 0:3] -= E
        J[:, 3:6] += E @ pin.skew(c_b)
        return scaled(self._sw, J, self.target - E @ (c_b - point))

    def error(self, platform, data, q):
        point, E = platform.thrust_axis[0], platform.thrust_axis_basis
        base = data.oMi[1]
        c_b = base.rotation.T @ (data.com[0] - base.translation)
        return scaled_error(self._sw, self.target - E @ (c_b - point))
