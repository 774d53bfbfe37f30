"""Kinematics of any platform: end-effector pose and Jacobians, centre of mass, the CoG offset from the thrust axis.

Algorithms take ``(platform, data, q)`` (Pinocchio configuration, see :mod:`qprr.charts`) and
write only ``data``; functions whose name ends in ``_xi`` take thesis coordinates.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from . import charts as ch
from .errors import InputError
from .model import Platform, check_model_data, check_platform
from .validation import as_matrix, as_vector

_BASE_JOINT = 1  # the free flyer: B is its frame


def check_q(platform: Platform, q, name: str = "q") -> np.ndarray:
    """``q`` as a finite configuration of ``platform`` with a unit quaternion, else a qprr error naming it."""
    q = as_vector(q, check_platform(platform).nq, name)
    ch.unit_quaternion(q[3:7], f"{name}[3:7]")
    return q


def _frame(platform: Platform, frame) -> int:
    return platform.ee_frame if frame is None else platform.frame_id(frame)


def ee_placement(platform: Platform, data: pin.Data, q, frame=None) -> pin.SE3:
    """World pose oMf of ``frame`` (default: the end effector), ^eT_eb of Thesis (3.61) for the Q-PRR."""
    check_model_data(platform, data)
    fid = _frame(platform, frame)
    pin.framesForwardKinematics(platform.model, data, check_q(platform, q))
    return data.oMf[fid].copy()


def ee_placement_body(platform: Platform, data: pin.Data, q, frame=None) -> pin.SE3:
    """Pose bMf of ``frame`` (default: the end effector) in B, ^bT_eb of Thesis (3.58) for the Q-PRR."""
    check_model_data(platform, data)
    fid = _frame(platform, frame)
    pin.framesForwardKinematics(platform.model, data, check_q(platform, q))
    return data.oMi[_BASE_JOINT].actInv(data.oMf[fid])


def ee_pose_xi(platform: Platform, data: pin.Data, xi, frame=None) -> tuple[np.ndarray, np.ndarray]:
    """(p_e_world, R_e_world) of thesis coordinates, Thesis (3.61)."""
    check_model_data(platform, data)
    M = ee_placement(platform, data, ch.xi_to_q(ch.as_xi(xi, "xi", platform.n_xi)), frame)
    return M.translation.copy(), M.rotation.copy()


def ee_jacobian_world(platform: Platform, data: pin.Data, q, frame=None) -> np.ndarray:
    """6 x nv Jacobian of [p_dot_world; omega_world] of ``frame`` (default: end effector) w.r.t. Pinocchio's v."""
    check_model_data(platform, data)
    fid = _frame(platform, frame)
    return pin.computeFrameJacobian(platform.model, data, check_q(platform, q), fid, pin.LOCAL_WORLD_ALIGNED)


def jacobian_xi(platform: Platform, data: pin.Data, xi, frame=None) -> np.ndarray:
    """J_e (6 x (6 + n)) with [p_e_dot; omega_e] (world) = J_e xi_dot, Thesis (4.11)-(4.13)."""
    check_model_data(platform, data)
    xi = ch.as_xi(xi, "xi", platform.n_xi)
    return ee_jacobian_world(platform, data, ch.xi_to_q(xi), frame) @ ch.rate_map(xi)


def arm_jacobian_body(platform: Platform, data: pin.Data, q_arm, frame=None) -> np.ndarray:
    """J_eb (6 x n_arm) of the arm in B: [p_eb_dot; omega_eb] = J_eb q_arm_dot, Thesis (4.26)."""
    check_model_data(platform, data)
    q = pin.neutral(platform.model)
    q[7:] = as_vector(q_arm, platform.n_arm, "q_arm")
    return ee_jacobian_world(platform, data, q, frame)[:, 6:]


# ------------------------------------------------------------------- centre of mass
def com_world(platform: Platform, data: pin.Data, q) -> np.ndarray:
    """Centre of mass of the whole system in the world frame [m]."""
    check_model_data(platform, data)
    return pin.centerOfMass(platform.model, data, check_q(platform, q), False).copy()


def com_body(platform: Platform, data: pin.Data, q) -> np.ndarray:
    """Centre of mass of the whole system in B: p_cm of Thesis (3.76)-(3.78) [m]."""
    check_model_data(platform, data)
    q = check_q(platform, q)
    c = pin.centerOfMass(platform.model, data, q, False)
    return data.oMi[_BASE_JOINT].actInv(c)


def cog_offset_body(platform: Platform, data: pin.Data, q) -> np.ndarray:
    """Distance of the CoG from the thrust axis, (2,) [m] in B: [x_cm, y_cm] for a thrust axis along z_B.

    The thrust axis is :attr:`Platform.thrust_axis`; the offset is the CoG minus the axis point,
    projected on the plane normal to the axis (:attr:`Platform.thrust_axis_basis`: x_B, y_B when
    the axis is z_B).  Zero means the
    platform hovers with equal thrusts (Thesis Sec. 2.5, (3.79)-(3.81)).
    """
    check_model_data(platform, data)
    return platform.thrust_axis_basis @ (com_body(platform, data, q) - platform.thrust_axis[0])


def arm_com(platform: Platform, data: pin.Data, q) -> tuple[float, np.ndarray, np.ndarray]:
    """(m_arm, c_arm_world, c_arm_body): mass and CoM of the arm subtree, Thesis (3.44)."""
    check_model_data(platform, data)
    q = check_q(platform, q)
    pin.centerOfMass(platform.model, data, q, True)
    j = platform.arm[0].joint_id
    c_world = data.oMi[j].act(data.com[j])  # subtree CoMs (j > 0) are expressed in joint j's frame
    return float(data.mass[j]), c_world, data.oMi[_BASE_JOINT].actInv(c_world)


def com_jacobian_body(platform: Platform, data: pin.Data, q) -> np.ndarray:
    """3 x nv Jacobian of the CoM position expressed in B, d(p_cm^B)/dt = J v (v: Pinocchio velocity).

    From Pinocchio's CoM Jacobian: d/dt R^T (c - p) = R^T J_c v - v_lin - omega x (R^T (c - p)).
    """
    check_model_data(platform, data)
    q = check_q(platform, q)
    Jc = pin.jacobianCenterOfMass(platform.model, data, q, False)
    return com_jacobian_body_from(data, Jc)


def com_jacobian_body_from(data: pin.Data, Jc: np.ndarray) -> np.ndarray:
    """:func:`com_jacobian_body` from a ``data`` that already holds the CoM and its world Jacobian ``Jc``."""
    if not isinstance(data, pin.Data):
        raise InputError(f"data must be a pinocchio.Data, got {type(data).__name__}")
    Jc = as_matrix(Jc, (3, None), "Jc")
    R = data.oMi[_BASE_JOINT].rotation
    c_b = R.T @ (data.com[0] - data.oMi[_BASE_JOINT].translation)
    J = R.T @ Jc
    J[:, 0:3] -= np.eye(3)
    J[:, 3:6] += pin.skew(c_b)
    return J


def arm_gravity_torque_body(platform: Platform, data: pin.Data, q) -> np.ndarray:
    """Torque about B, in B, that the arm's weight exerts on the multirotor [N m], Thesis (3.43).

    Sign: world z up, tau = m_G xi_c x R_b^T (-g e3); the printed (3.43) has the opposite sign
    because (3.42) takes gravity along +e3 (NED), see docs/thesis-errata.md.  Read from RNEA at
    rest: ``data.f`` of the first arm joint is the wrench the base applies to the arm subtree.
    """
    check_model_data(platform, data)
    q = check_q(platform, q)
    zero = np.zeros(platform.nv)
    pin.rnea(platform.model, data, q, zero, zero)
    j = platform.arm[0].joint_id
    return -(data.liMi[j].act(data.f[j])).angular.copy()
