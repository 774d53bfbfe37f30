"""IK tasks, one per module: each linearises one wish about the configuration as J dv = e.

======================  =====================================================================
task                    what it asks
======================  =====================================================================
:class:`PoseTask`       a frame (the end effector) at a world placement (6)
:class:`PositionTask`   a frame at a world position, orientation free (3)
:class:`BasePoseTask`   the base frame at a placement (6)
:class:`BaseOrientationTask`  the base frame at an orientation (3): level 2 of fully actuated platforms
:class:`HoverTask`      the base z axis vertical, roll = pitch = 0 (2)
:class:`ComTask`        the CoG on the thrust axis (2)
:class:`PostureTask`    the arm at a preferred configuration (n_arm)
======================  =====================================================================

Write your own by subclassing :class:`Task` and implementing ``linearize`` (and ``error``, when e alone costs less:
the first step of a solve asks for it to find a start that is already the answer). The default tasks of a solver
are built once and aimed per solve (``set_target``, ``set_reference``).
"""

from .base import Task, update_kinematics
from .com import ComTask
from .hover import HoverTask
from .pose import BaseOrientationTask, BasePoseTask, PoseTask, PositionTask
from .posture import PostureTask

__all__ = ["BaseOrientationTask", "BasePoseTask", "ComTask", "HoverTask", "PoseTask", "PositionTask", "PostureTask", "Task", "update_kinematics"]
