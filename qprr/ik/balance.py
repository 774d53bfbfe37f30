"""The prismatic joint value that puts the CoG on the thrust axis, given the other arm joints (closed form).

A multirotor whose rotors all push along one axis hovers with equal thrusts only when the CoG of
the whole system lies on that axis (Thesis Sec. 2.5); the Q-PRR carries its prismatic joint r0 for
this purpose, and Thesis (3.79)-(3.81) choose r0 so that x_cm = 0.  :func:`balance_prismatic` does
it for any platform with a prismatic arm joint.

Why a closed form exists: moving a prismatic joint by ds translates the subtree it carries (mass
m_s) rigidly along the joint axis, whose direction in B depends only on the joints before it.  The
CoG therefore moves by (m_s / m) a ds, and the CoG offset from the thrust axis
(:func:`qprr.kinematics.cog_offset_body`, in the plane normal to the axis) is affine in s::

    o(s) = o(s0) + g (s - s0),   g = d o / d s  (2,)  [m/m]

The offset along the direction the slider can move it vanishes at s* = s0 - g.o(s0) / g.g (the
least-squares zero of o; for the Q-PRR, whose slider moves the CoG along x_B and whose arm has no
y offset, o(s*) = 0: Thesis (3.81), r0 = -(k0 + a_s s2 + a_c c2 + b_s s23 + b_c c23) / M_s).  The
component of o normal to g, if any, no value of this joint can remove: it is reported as the
residual.  g is the joint's column of Pinocchio's CoM Jacobian, expressed in B
(:func:`qprr.kinematics.com_jacobian_body`): no iteration and no finite difference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
import pinocchio as pin

from ..errors import InputError, UnknownNameError
from ..kinematics import cog_offset_body, com_jacobian_body
from ..model import Platform
from ..validation import as_vector

NO_EFFECT_TOL = 1e-9
"""The joint has no effect on the CoG offset when |g| < NO_EFFECT_TOL m_s / m: its axis is within 1e-9 rad of the
thrust axis (it moves the CoG along the axis only)."""


class BalanceStatus(str, Enum):
    """How :func:`balance_prismatic` ended (:attr:`BalanceResult.status`, equal to its string)."""

    BALANCED = "balanced"
    """The offset along the joint's direction is zero."""
    LIMITED = "limited"
    """The joint stops at a limit before."""
    NO_EFFECT = "no_effect"
    """The joint moves the CoG along the thrust axis only."""

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class BalanceResult:
    """Outcome of :func:`balance_prismatic`.

    ``joint``: the prismatic joint's name; ``value`` [m]: its balancing value inside its limits;
    ``unclamped`` [m]: the value that zeroes the offset along ``slope`` (may lie outside the
    limits, or be ``nan`` when the joint has no effect); ``lower``, ``upper`` [m]: its limits;
    ``within_limits``: ``unclamped`` lies inside them; ``q_arm`` (n_arm,): the given arm
    posture with ``value`` in the joint; ``offset`` (2,) [m]: the CoG offset from the thrust axis
    at ``q_arm`` (:func:`qprr.kinematics.cog_offset_body`, in B; zero when balanced);
    ``slope`` (2,) [m/m]: d offset / d joint; ``status`` (:class:`BalanceStatus`): "balanced" (the offset along ``slope``
    is zero), "limited" (the joint stops at a limit before) or "no_effect" (the joint moves the
    CoG along the thrust axis only); ``reason`` says why in words when not "balanced".
    """

    joint: str
    value: float
    unclamped: float
    lower: float
    upper: float
    within_limits: bool
    q_arm: np.ndarray
    offset: np.ndarray
    slope: np.ndarray
    status: BalanceStatus
    reason: str


def _prismatic_joint(platform: Platform, joint) -> int:
    """Index in the arm of the prismatic joint named (or indexed by) ``joint``; the only one when None."""
    prismatic = [k for k, j in enumerate(platform.arm) if j.kind == "prismatic"]
    if joint is None:
        if not prismatic:
            raise InputError(
                f"platform {platform.name!r} has no prismatic arm joint (its arm: "
                f"{', '.join(f'{j.name} ({j.kind})' for j in platform.arm) or 'none'})"
            )
        if len(prismatic) > 1:
            names = tuple(platform.arm[k].name for k in prismatic)
            raise InputError(f"platform {platform.name!r} has {len(names)} prismatic joints {names}: pass joint=<name>")
        return prismatic[0]
    names = platform.arm_names
    if isinstance(joint, str):
        if joint not in names:
            raise UnknownNameError("arm joint", joint, names)
        k = names.index(joint)
    elif isinstance(joint, (int, np.integer)) and not isinstance(joint, bool):
        if not 0 <= joint < platform.n_arm:
            raise UnknownNameError("arm joint index", joint, tuple(str(i) for i in range(platform.n_arm)))
        k = int(joint)
    else:
        raise InputError(f"joint must be an arm joint name or index, got {joint!r}")
    if platform.arm[k].kind != "prismatic":
        raise InputError(
            f"joint {names[k]!r} is {platform.arm[k].kind}, not prismatic; prismatic joints: "
            f"{tuple(platform.arm[i].name for i in prismatic) or 'none'}"
        )
    return k


def balance_prismatic(platform: Platform, data: pin.Data, q_arm, joint: str | int | None = None) -> BalanceResult:
    """The value of a prismatic arm joint that puts the CoG on the thrust axis, the other joints given.

    Parameters
    ----------
    platform : any platform with a prismatic arm joint.
    data : its ``pin.Data`` (written).
    q_arm : (n_arm,) arm posture [m, rad]; the other joints must lie inside their limits, the
        entry of ``joint`` is only where the computation starts (any finite value).
    joint : the prismatic joint (name or arm index); default: the platform's only one.

    Returns
    -------
    :class:`BalanceResult`: closed form (module docstring), the value clamped to the joint's
    limits, the residual offset evaluated by :func:`qprr.kinematics.cog_offset_body`.
    Thesis (3.79)-(3.81) for the Q-PRR, generalised.
    """
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    k = _prismatic_joint(platform, joint)
    arm = platform.arm[k]
    q_arm = as_vector(q_arm, platform.n_arm, "q_arm").copy()
    others = q_arm.copy()
    others[k] = min(max(q_arm[k], arm.lower), arm.upper)
    platform.check_arm_limits(others, "q_arm (the other joints)")
    q = platform.neutral_q()
    q[7:] = q_arm
    o0 = cog_offset_body(platform, data, q)
    g = platform.thrust_axis_basis @ com_jacobian_body(platform, data, q)[:, arm.idx_v]
    # mass moved by the joint: the subtree it carries
    pin.centerOfMass(platform.model, data, q, True)
    m_ratio = float(data.mass[arm.joint_id]) / platform.total_mass
    gg = float(g @ g)
    if not math.sqrt(gg) >= NO_EFFECT_TOL * max(m_ratio, 1e-300):
        value = float(others[k])
        status, unclamped = BalanceStatus.NO_EFFECT, math.nan
        reason = (
            f"joint {arm.name!r} moves the CoG along the thrust axis only at this posture (its axis is parallel "
            "to the thrust axis): no value of it changes the offset"
        )
        within = False
    else:
        unclamped = float(q_arm[k] - (g @ o0) / gg)
        within = arm.lower <= unclamped <= arm.upper
        value = min(max(unclamped, arm.lower), arm.upper)
        if within:
            status, reason = BalanceStatus.BALANCED, ""
        else:
            side = "upper" if unclamped > arm.upper else "lower"
            status = BalanceStatus.LIMITED
            limit = arm.upper if side == "upper" else arm.lower
            reason = f"joint {arm.name!r} would need {unclamped:.6g} m, beyond its {side} limit {limit:.6g} m: stopped there"
    q_arm[k] = value
    q[7:] = q_arm
    offset = cog_offset_body(platform, data, q)
    return BalanceResult(arm.name, value, unclamped, arm.lower, arm.upper, bool(within), q_arm, offset, g, status, reason)


__all__ = ["NO_EFFECT_TOL", "BalanceResult", "balance_prismatic"]
