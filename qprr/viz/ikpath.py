"""IK with switchable levels, and an IK solution path as a run to animate.

:func:`ik_levels` is the task hierarchy of the viewer's draggable target: the end-effector
position (or pose) first, then, each optional, hover (the thrust axis vertical,
:class:`~qprr.ik.tasks.HoverTask`) and the CoG on the thrust axis
(:class:`~qprr.ik.tasks.ComTask`), the arm posture last.  :func:`ik_solve` solves it with the
strict task-priority QP of :class:`qprr.ik.IKSolver`; :func:`ik_path` follows a sequence of
targets (warm-started) and returns a :class:`~qprr.viz.run.RunLog` with the hover thrusts of
every sample, ready for :func:`qprr.viz.animate_result`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..actuation import Allocator
from ..charts import as_xi
from ..errors import InputError, ShapeError
from ..ik import IKOutcome, IKResult, IKSolver, QPOptions
from ..ik.tasks import ComTask, HoverTask, PoseTask, PositionTask, PostureTask
from ..kinematics import cog_offset_body
from ..model import Platform, check_model_data, check_platform
from ..validation import as_array, as_matrix, as_vector
from .run import RunLog
from .scene import hover_report


def ik_levels(platform: Platform, target, q_arm_posture, *, hover: bool = True, cog: bool = True) -> list[list]:
    """Levels: end-effector pose (``target`` a ``pin.SE3``) or position ((3,) world) > [hover] > [CoG on the thrust axis] > posture."""
    check_platform(platform)
    if not isinstance(target, pin.SE3):
        target = as_vector(target, 3, "target")
    q_arm_posture = platform.check_arm_limits(q_arm_posture, "q_arm_posture")
    first = PoseTask(platform, target) if isinstance(target, pin.SE3) else PositionTask(platform, target)
    levels = [[first]]
    if hover:
        levels.append([HoverTask()])
    if cog:
        levels.append([ComTask()])
    levels.append([PostureTask(platform, q_arm_posture)])
    return levels


def ik_solve(platform: Platform, data: pin.Data, target, xi0=None, *, hover: bool = True, cog: bool = True, posture=None) -> IKResult:
    """Strict task-priority IK of ``target`` with the levels of :func:`ik_levels` (from ``xi0``, default the solver's guess).

    ``posture``: q_arm of the posture level (default: that of ``xi0``, else the neutral arm).
    Success requires hover only when the hover level is on.
    """
    check_model_data(platform, data)
    if xi0 is not None:
        xi0 = as_xi(xi0, "xi0", platform.n_xi)
    if not isinstance(target, pin.SE3):
        target = as_vector(target, 3, "target")
    if posture is None:
        posture = platform.neutral_q()[7:] if xi0 is None else np.clip(np.asarray(xi0, dtype=float)[6:], platform.arm_lower, platform.arm_upper)
    levels = ik_levels(platform, target, posture, hover=hover, cog=cog)
    solver = IKSolver(platform, "qp", QPOptions(levels=levels, require_hover=bool(hover)))
    return solver.solve(data, target, xi0)


@dataclass(frozen=True)
class IKPath:
    """An IK solution path: ``run`` (a :class:`RunLog`: xi, hover thrusts f), ``x_cm`` (n, 2) [m] the CoG offset from
    the thrust axis in B, and each sample's IK outcome.

    ``success`` (n,) bool, ``status`` (n,) the :class:`~qprr.ik.IKResult` statuses (:class:`~qprr.ik.IKOutcome`); ``position_error`` (n,) [m].
    """

    run: RunLog
    x_cm: np.ndarray
    success: np.ndarray
    status: tuple[IKOutcome, ...]
    position_error: np.ndarray


def ik_path(platform: Platform, t, p_world, R_world=None, *, hover: bool = True, cog: bool = True, xi0=None) -> IKPath:
    """Solve the IK along end-effector targets and log the result as a run.

    Parameters
    ----------
    t : (n,) sample times [s], non-decreasing.
    p_world : (n, 3) end-effector positions [m], world frame.
    R_world : optional (n, 3, 3) end-effector orientations (world); None: positions only.
    hover, cog : switch the hover and CoG levels (:func:`ik_levels`).
    xi0 : starting configuration of the first solve (default: the solver's guess); each next
        solve starts from the previous answer.

    ``f`` of the run holds the hover thrusts of every sample (:func:`qprr.viz.scene.hover_report`,
    also when a bound is violated); ``x_cm`` of the path the CoG offset from the thrust axis.
    """
    check_platform(platform)
    p_world = as_matrix(p_world, (None, 3), "p_world")
    t = as_array(t, "t")
    p = as_array(p_world, "p_world")
    n = t.shape[0] if t.ndim == 1 else -1
    if n < 1 or p.shape != (n, 3):
        raise ShapeError(f"t must have shape (n,) and p_world (n, 3); got {t.shape} and {p.shape}")
    if R_world is not None:
        R_world = as_array(R_world, "R_world")
        if R_world.shape != (n, 3, 3):
            raise ShapeError(f"R_world must have shape ({n}, 3, 3), got {R_world.shape}")
    data = platform.data()
    allocator = Allocator(platform)
    xi = np.empty((n, platform.n_xi))
    f = np.empty((n, platform.n_rotors))
    x_cm = np.empty((n, 2))
    ok = np.zeros(n, dtype=bool)
    err = np.empty(n)
    status = []
    prev = None if xi0 is None else ch.as_xi(xi0, "xi0", platform.n_xi)
    for k in range(n):
        target = p[k] if R_world is None else pin.SE3(R_world[k], p[k])
        res = ik_solve(platform, data, target, prev, hover=hover, cog=cog)
        if res.xi is None:
            raise InputError(f"the IK produced no configuration at sample {k} (t = {t[k]} s): {res.reason}")
        xi[k] = res.xi
        q = ch.xi_to_q(res.xi)
        f[k] = hover_report(allocator, data, q).f
        x_cm[k] = cog_offset_body(platform, data, q)
        ok[k], err[k] = res.success, res.position_error
        status.append(res.status)
        prev = res.xi
    return IKPath(RunLog(t, xi, f=f, platform=platform.name), x_cm, ok, tuple(status), err)
