"""Hover: the thrust axis vertical (an under-actuated multirotor holds still only so)."""

from __future__ import annotations

import numpy as np

from .base import Task, task_name


class HoverTask(Task):
    """Hover feasibility: the base z axis vertical, i.e. roll = pitch = 0.

    A multirotor whose rotors all push along z_B holds still only with z_B along gravity.  The
    task drives the horizontal components of z_B = R_b e3 (world) to zero; unlike the Euler
    angles it has no singularity.  d(R_b e3)/dt = -R_b hat(e3) omega_body.
    """

    dim = 2

    def __init__(self, name: str = "hover"):
        self.name = task_name(name)

    def linearize(self, platform, data, q):
        R = data.oMi[1].rotation
        J = np.zeros((2, platform.nv))
        # -R hat(e3) = [-r_y, r_x, 0] (columns of R)
        J[:, 3] = -R[0:2, 1]
        J[:, 4] = R[0:2, 0]
        return J, -R[0:2, 2]
