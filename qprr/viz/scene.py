"""What a picture of the robot shows at one configuration, in world coordinates (shared by the animation and the viewer).

:func:`robot_pose` evaluates, from Pinocchio's frames, the base pose, the arm as a polyline
through its joint origins, the end effector, the centre of gravity, the thrust axis and each
rotor's centre and thrust direction.  :class:`HoverReport` gives the rotor thrusts that hold a
configuration still and their margins to the thrust bounds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..actuation import Allocator
from ..dynamics import generalized_gravity
from ..errors import InputError
from ..kinematics import check_q
from ..model import Platform, check_model_data, check_platform


@dataclass(frozen=True)
class RobotPose:
    """The robot at one configuration; every point and direction in the world frame [m].

    ``arm_world`` (k, 3): polyline from B through the origin of each arm joint on the path to
    the end effector (a prismatic joint contributes its origin before and after the slide),
    ending at the end effector.  ``axis_point_world``/``axis_dir_world``: the thrust axis
    (:attr:`Platform.thrust_axis`).  ``rotor_world``/``rotor_axis_world`` (n, 3): rotor centres
    and unit thrust directions.
    """

    p_base_world: np.ndarray
    R_base_world: np.ndarray
    arm_world: np.ndarray
    ee_world: np.ndarray
    com_world: np.ndarray
    axis_point_world: np.ndarray
    axis_dir_world: np.ndarray
    rotor_world: np.ndarray
    rotor_axis_world: np.ndarray


def arm_chain(platform: Platform) -> list[int]:
    """Joint ids of the arm joints from the base to the end effector's joint, in order."""
    check_platform(platform)
    model = platform.model
    return [j for j in model.supports[model.frames[platform.ee_frame].parentJoint] if j >= 2]


def robot_pose(platform: Platform, data: pin.Data, q: np.ndarray, chain: list[int] | None = None) -> RobotPose:
    """:class:`RobotPose` at the Pinocchio configuration ``q`` (writes ``data``; ``chain`` from :func:`arm_chain`)."""
    check_model_data(platform, data)
    q = check_q(platform, q)
    model = platform.model
    chain = arm_chain(platform) if chain is None else chain
    pin.forwardKinematics(model, data, q)
    base = data.oMi[1]
    R, p = base.rotation, base.translation
    points = [p]
    for j in chain:
        before = data.oMi[model.parents[j]].act(model.jointPlacements[j].translation)
        points.append(before)
        if platform.arm[j - 2].kind == "prismatic":
            points.append(data.oMi[j].translation)
    ee = data.oMi[model.frames[platform.ee_frame].parentJoint].act(model.frames[platform.ee_frame].placement.translation)
    points.append(ee)
    com = pin.centerOfMass(model, data, q, False)
    point_b, dir_b = platform.thrust_axis
    rotors_b = np.array([r.position_body for r in platform.rotors])
    axes_b = np.array([r.axis_body for r in platform.rotors])
    return RobotPose(
        p_base_world=p.copy(),
        R_base_world=R.copy(),
        arm_world=np.array(points),
        ee_world=np.array(ee),
        com_world=np.array(com),
        axis_point_world=R @ point_b + p,
        axis_dir_world=R @ dir_b,
        rotor_world=rotors_b @ R.T + p,
        rotor_axis_world=axes_b @ R.T,
    )


@dataclass(frozen=True)
class HoverReport:
    """Rotor thrusts holding a configuration still, and how far they are from the bounds.

    ``f`` (n,) [N]: the allocation of the base part of the generalised gravity g(q) (the
    thrusts of :meth:`qprr.actuation.Allocator.hover_thrusts`, here also outside the bounds);
    ``margin_low = f - f_min``, ``margin_high = f_max - f`` [N] (negative: bound violated);
    ``unproduced`` [N or N m]: norm of the part of g(q)'s base wrench the rotors cannot produce
    (non-zero when a coplanar rotor set is tilted); ``feasible``: both margins >= 0 and nothing
    left unproduced; ``reason`` in words when not feasible.
    """

    f: np.ndarray
    margin_low: np.ndarray
    margin_high: np.ndarray
    unproduced: float
    feasible: bool
    reason: str


def hover_report(allocator: Allocator, data: pin.Data, q: np.ndarray) -> HoverReport:
    """:class:`HoverReport` of the allocator's platform at ``q`` (writes ``data``).

    At rest the generalised force N f must equal g(q) (Thesis (5.44)-(5.46)); its base rows
    Omega f = g(q)[0:6] are solved exactly on the rows the rotors produce.
    """
    if not isinstance(allocator, Allocator):
        raise InputError(f"allocator must be a qprr.actuation.Allocator, got {type(allocator).__name__}")
    p = allocator.platform
    w = generalized_gravity(p, data, q)[0:6]
    f = allocator.Omega_P_inv @ w[allocator.rows]
    unproduced = float(np.linalg.norm(w - allocator.Omega @ f))
    low, high = f - allocator.f_min, allocator.f_max - f
    tol = 1e-9 * p.total_mass * p.g
    reasons = []
    if unproduced > tol:
        reasons.append(f"the rotors cannot produce {unproduced:.3g} of the weight's base wrench (the thrust axis is not vertical)")
    for k in np.flatnonzero(low < -tol):
        reasons.append(f"rotor {k + 1} below its minimum by {-low[k]:.3g} N")
    for k in np.flatnonzero(high < -tol):
        reasons.append(f"rotor {k + 1} above its maximum by {-high[k]:.3g} N")
    return HoverReport(f, low, high, unproduced, not reasons, "; ".join(reasons))
