"""Inverse kinematics of any platform: tasks, the strict-priority hierarchy, methods, one result type.

    solver = qprr.ik.IKSolver(platform, method="qp")   # build once (owns its QPs)
    result = solver.solve(data, target)                # solve many
    batch = qprr.ik.solve_many(solver, targets, workers=2)   # or many in one call (qprr.ik.batch)

or ``qprr.ik.solve(platform, data, target, method="qp")``; :func:`balance_prismatic` gives the value of a
prismatic joint that puts the CoG on the thrust axis (closed form).  See :mod:`qprr.ik.solver` for the
problem and the methods (the registry :data:`IK_METHODS`: a plug-in adds its own, docs/extending.md),
:mod:`qprr.ik.tasks` for the tasks (write your own), and :mod:`qprr.thesis.igm` for the thesis's analytic IGM of the Q-PRR.
"""

from . import tasks
from .balance import BalanceResult, BalanceStatus, balance_prismatic
from .batch import IKBatch, solve_many
from .hierarchy import HierarchySolver, HierarchyStep
from .solver import (
    DEFAULT_METHOD,
    IK_METHODS,
    METHODS,
    OPTIONS,
    ClikaOptions,
    DLSOptions,
    IKMethod,
    IKOutcome,
    IKResult,
    IKSolver,
    QPOptions,
    default_guess,
    default_levels,
    make_options,
    parse_target,
    pose_errors,
    solve,
)

__all__ = [
    "DEFAULT_METHOD",
    "IK_METHODS",
    "BalanceResult",
    "BalanceStatus",
    "METHODS",
    "OPTIONS",
    "ClikaOptions",
    "DLSOptions",
    "HierarchySolver",
    "HierarchyStep",
    "IKBatch",
    "IKMethod",
    "IKOutcome",
    "IKResult",
    "IKSolver",
    "QPOptions",
    "balance_prismatic",
    "default_guess",
    "default_levels",
    "make_options",
    "parse_target",
    "pose_errors",
    "solve",
    "solve_many",
    "tasks",
]
