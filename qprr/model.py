"""The Q-PRR in Pinocchio: loading, kinematics, centre of mass and the coupled dynamics.

Algorithms take ``(robot, data, state)``: :class:`Robot` holds the immutable description
(the ``pin.Model``, frame ids and parameters), a ``pin.Data`` from :meth:`Robot.data`
holds the scratch space.  Nothing here modifies ``robot.model``.

States are Pinocchio's ``(q, v)`` (see :mod:`qprr.coordinates`) or the thesis's
``(xi, xi_dot)``; functions whose name ends in ``_xi`` take and return thesis coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from . import coordinates as co
from .coordinates import as_vector
from .errors import LimitError, UnknownNameError
from .params import LAYOUTS, VARIANTS, QPRRParams, thesis_params
from .urdf import URDF_PATH, build_urdf

ARM_JOINTS = ("r0", "theta2", "theta3")
EE_FRAME = "end_effector"


@dataclass(frozen=True)
class Robot:
    """Immutable description of a Q-PRR: the Pinocchio model and what names it.

    ``model.gravity`` is set from ``params.g`` at load time (the thesis uses 9.8 m/s^2).
    """

    model: pin.Model
    params: QPRRParams
    ee_frame: int
    base_frame: int
    arm_joint_ids: tuple[int, int, int]
    rotor_frames: dict

    @property
    def nq(self) -> int:
        return self.model.nq

    @property
    def nv(self) -> int:
        return self.model.nv

    def data(self) -> pin.Data:
        """A fresh ``pin.Data`` for this model."""
        return self.model.createData()

    def neutral_xi(self) -> np.ndarray:
        """xi = 0: at the origin, level, arm straight along +z_B."""
        return np.zeros(9)

    def check_arm_limits(self, q_arm, name: str = "q_arm") -> np.ndarray:
        """Return ``q_arm`` = [r0, theta2, theta3] if inside the joint limits, else raise LimitError."""
        q_arm = as_vector(q_arm, 3, name)
        lo, hi = self.params.lower_limits, self.params.upper_limits
        bad = [i for i in range(3) if not lo[i] - 1e-12 <= q_arm[i] <= hi[i] + 1e-12]
        if bad:
            parts = [f"{ARM_JOINTS[i]} = {float(q_arm[i])!r} not in [{float(lo[i])!r}, {float(hi[i])!r}]" for i in bad]
            raise LimitError(f"{name}: " + "; ".join(parts))
        return q_arm


def load(params: QPRRParams | str | None = None, *, urdf_path: Path | str | None = None) -> Robot:
    """Load the Q-PRR with a free-flyer root (nq = 10, nv = 9).

    ``params``: a :class:`QPRRParams`, a variant name (``"thesis"`` default, ``"cad"``), or
    None.  With default parameters the committed ``urdf/qprr.urdf`` is read; otherwise the
    URDF is generated in memory from ``params``.
    """
    if params is None:
        params = thesis_params()
    elif isinstance(params, str):
        if params not in VARIANTS:
            raise UnknownNameError("parameter variant", params, tuple(VARIANTS))
        params = VARIANTS[params]()
    if urdf_path is not None:
        model = pin.buildModelFromUrdf(str(urdf_path), pin.JointModelFreeFlyer())
    elif params == thesis_params() and URDF_PATH.exists():
        model = pin.buildModelFromUrdf(str(URDF_PATH), pin.JointModelFreeFlyer())
    else:
        model = pin.buildModelFromXML(build_urdf(params), pin.JointModelFreeFlyer())
    model.gravity = pin.Motion(np.array([0.0, 0.0, -params.g]), np.zeros(3))
    rotor_frames = {
        layout: tuple(model.getFrameId(f"rotor_{layout}_{i}") for i in range(1, 5)) for layout in LAYOUTS
    }
    return Robot(
        model=model,
        params=params,
        ee_frame=model.getFrameId(EE_FRAME),
        base_frame=model.getFrameId("multirotor"),
        arm_joint_ids=tuple(model.getJointId(n) for n in ARM_JOINTS),
        rotor_frames=rotor_frames,
    )


# --------------------------------------------------------------------------- kinematics
def _check_q(robot: Robot, q) -> np.ndarray:
    return as_vector(q, robot.nq, "q")


def ee_placement(robot: Robot, data: pin.Data, q) -> pin.SE3:
    """World pose of the end-effector frame, ^eT_eb of Thesis (3.61)."""
    q = _check_q(robot, q)
    pin.framesForwardKinematics(robot.model, data, q)
    return data.oMf[robot.ee_frame].copy()


def ee_placement_body(robot: Robot, data: pin.Data, q) -> pin.SE3:
    """End-effector pose in B, ^bT_eb of Thesis (3.58) (depends on the arm joints only)."""
    q = _check_q(robot, q)
    pin.framesForwardKinematics(robot.model, data, q)
    return data.oMi[1].actInv(data.oMf[robot.ee_frame])


def ee_pose_xi(robot: Robot, data: pin.Data, xi) -> tuple[np.ndarray, np.ndarray]:
    """(p_e_world, R_e) of thesis coordinates, Thesis (3.61)."""
    M = ee_placement(robot, data, co.xi_to_q(xi))
    return M.translation.copy(), M.rotation.copy()


def ee_jacobian_world(robot: Robot, data: pin.Data, q) -> np.ndarray:
    """6x9 Jacobian of [p_e_dot_world; omega_e_world] with respect to Pinocchio's v."""
    q = _check_q(robot, q)
    return pin.computeFrameJacobian(robot.model, data, q, robot.ee_frame, pin.LOCAL_WORLD_ALIGNED)


def jacobian_xi(robot: Robot, data: pin.Data, xi) -> np.ndarray:
    """J_e (6x9) with [p_e_dot; omega_e] (world) = J_e xi_dot, Thesis (4.11)-(4.13)."""
    return ee_jacobian_world(robot, data, co.xi_to_q(xi)) @ co.rate_map(xi)


def arm_jacobian_body(robot: Robot, data: pin.Data, q_arm) -> np.ndarray:
    """J_eb (6x3) of the arm in B: [p_eb_dot; omega_eb] = J_eb [r0_dot, theta2_dot, theta3_dot], Thesis (4.26)."""
    q_arm = as_vector(q_arm, 3, "q_arm")
    q = pin.neutral(robot.model)
    q[7:10] = q_arm
    return ee_jacobian_world(robot, data, q)[:, 6:9]


# ------------------------------------------------------------------- centre of mass
def com_world(robot: Robot, data: pin.Data, q) -> np.ndarray:
    """Centre of mass of the whole system in the world frame [m]."""
    return pin.centerOfMass(robot.model, data, _check_q(robot, q), False).copy()


def com_body(robot: Robot, data: pin.Data, q) -> np.ndarray:
    """Centre of mass of the whole system in B: p_cm of Thesis (3.76)-(3.78) [m].

    [x_cm, y_cm] = 0 means the CoG lies on the thrust axis z_B.
    """
    q = _check_q(robot, q)
    c = pin.centerOfMass(robot.model, data, q, False)
    return data.oMi[1].actInv(c)


def arm_com(robot: Robot, data: pin.Data, q) -> tuple[float, np.ndarray, np.ndarray]:
    """(m_arm, c_arm_world, c_arm_body): mass and CoM of the arm subtree, Thesis (3.44)."""
    q = _check_q(robot, q)
    pin.centerOfMass(robot.model, data, q, True)
    j = robot.arm_joint_ids[0]
    c_world = data.oMi[j].act(data.com[j])  # subtree CoMs (j > 0) are expressed in joint j's frame
    return float(data.mass[j]), c_world, data.oMi[1].actInv(c_world)


def com_jacobian_body(robot: Robot, data: pin.Data, q) -> np.ndarray:
    """3x9 Jacobian of the CoM position expressed in B, d(p_cm^B)/dt = J v (v: Pinocchio velocity).

    From Pinocchio's CoM Jacobian: d/dt R^T (c - p) = R^T J_c v - v_lin - omega x (R^T (c - p)).
    """
    q = _check_q(robot, q)
    Jc = pin.jacobianCenterOfMass(robot.model, data, q, False)
    R = data.oMi[1].rotation
    c_b = R.T @ (data.com[0] - data.oMi[1].translation)
    J = R.T @ Jc
    J[:, 0:3] -= np.eye(3)
    J[:, 3:6] += pin.skew(c_b)
    return J


def arm_gravity_torque_body(robot: Robot, data: pin.Data, q) -> np.ndarray:
    """Torque about B, in B, that the arm's weight exerts on the multirotor [N m], Thesis (3.43).

    Sign: world z up, tau = m_G xi_c x R_b^T (-g e3); the printed (3.43) has the opposite
    sign because (3.42) takes gravity along +e3 (NED), see docs/thesis-errata.md.

    Read from RNEA at rest: ``data.f`` of the prismatic joint is the wrench the base
    applies to the arm subtree; the arm applies its opposite to the base.
    """
    q = _check_q(robot, q)
    zero = np.zeros(robot.nv)
    pin.rnea(robot.model, data, q, zero, zero)
    j = robot.arm_joint_ids[0]
    return -(data.liMi[j].act(data.f[j])).angular.copy()


# ----------------------------------------------------------------------- dynamics
def dynamics_xi(robot: Robot, data: pin.Data, xi, xi_dot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """B(xi), C(xi, xi_dot), G(xi) of Thesis (5.36) in thesis coordinates, from CRBA/RNEA.

    With v = S xi_dot (:func:`qprr.coordinates.rate_map`) the kinetic energy is
    1/2 xi_dot^T B xi_dot with B = S^T M S (Thesis (5.25)); G = S^T g(q) = dU/dxi (5.37).
    C is the Christoffel matrix of (5.35), C = 1/2 B_dot + 1/2 (D - D^T) with
    D_ij = sum_k dB_ik/dxi_j xi_dot_k, built from Pinocchio's derivatives:
    B_dot = S_dot^T M S + S^T (C_p + C_p^T) S + S^T M S_dot (M_dot = C_p + C_p^T),
    D = d(S^T y)/dxi |_(y = M S w) + S^T d(M a)/dq|_(a = S w) S + S^T M d(S w)/dxi, w = xi_dot.
    Raises EulerSingularityError at theta = +-pi/2 (B is singular there).
    """
    xi = as_vector(xi, 9, "xi")
    w = as_vector(xi_dot, 9, "xi_dot")
    co._check_pitch(xi[4], "dynamics_xi")
    model = robot.model
    q = co.xi_to_q(xi)
    S = co.rate_map(xi)
    dS = co.rate_map_derivatives(xi)  # (3, 9, 9): dS/dphi, dS/dtheta, dS/dpsi
    v = S @ w
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    Cp = pin.computeCoriolisMatrix(model, data, q, v).copy()
    g = pin.computeGeneralizedGravity(model, data, q).copy()
    dtau_dq, _, _ = pin.computeRNEADerivatives(model, data, q, np.zeros(robot.nv), v)
    dg_dq = pin.computeGeneralizedGravityDerivatives(model, data, q)
    dMa_dq = dtau_dq - dg_dq  # d(M(q) a)/dq at a = v

    S_dot = np.tensordot(w[3:6], dS, axes=1)
    MS = M @ S
    B = S.T @ MS
    B_dot = S_dot.T @ MS + S.T @ (Cp + Cp.T) @ S + MS.T @ S_dot
    y = MS @ w
    D = S.T @ dMa_dq @ S
    for k in range(3):
        D[:, 3 + k] += dS[k].T @ y + MS.T @ (dS[k] @ w)
    C = 0.5 * B_dot + 0.5 * (D - D.T)
    G = S.T @ g
    return B, C, G


def forward_dynamics_xi(robot: Robot, data: pin.Data, xi, xi_dot, u) -> np.ndarray:
    """xi_ddot = B^-1 (u - C xi_dot - G), Thesis (5.39), evaluated with ABA on the Lie group.

    ``u`` are generalised forces in thesis coordinates (e.g. from
    :func:`qprr.actuation.input_map`); tau = S^-T u is applied in Pinocchio's coordinates.
    """
    xi = as_vector(xi, 9, "xi")
    xi_dot = as_vector(xi_dot, 9, "xi_dot")
    u = as_vector(u, 9, "u")
    co._check_pitch(xi[4], "forward_dynamics_xi")
    q, v = co.xi_to_qv(xi, xi_dot)
    tau = np.linalg.solve(co.rate_map(xi).T, u)
    a = pin.aba(robot.model, data, q, v, tau)
    return co.a_to_xi_ddot(xi, xi_dot, a)


def kinetic_energy(robot: Robot, data: pin.Data, q, v) -> float:
    """Kinetic energy [J], Thesis (5.13)."""
    return float(pin.computeKineticEnergy(robot.model, data, _check_q(robot, q), as_vector(v, robot.nv, "v")))


def potential_energy(robot: Robot, data: pin.Data, q) -> float:
    """Gravitational potential energy [J] with U = m g z (world z up), Thesis (5.29)."""
    return float(pin.computePotentialEnergy(robot.model, data, _check_q(robot, q)))
