"""From rotor thrusts and arm efforts to generalised forces: u = R_Q N f (Thesis (5.40)-(5.46)).

The actuator vector is f = [f1, f2, f3, f4, f_r0, tau_theta2, tau_theta3] (rotor thrusts [N],
prismatic force [N], joint torques [N m]).

* ``rotor_matrix`` (Omega, 6x4): body wrench [f_B; tau_B] at B, in B, per unit thrust,
  built from the rotor frames of the Pinocchio model and their spin signs.  For the "+"
  layout its rows 3..6 are (3.36) with c read as c/b (see docs/thesis-errata.md).
* ``actuation_matrix`` (N, 9x7): [Omega 0; 0 I3] (5.44)-(5.46).  N f is directly the
  generalised force in Pinocchio's coordinates (body wrench at B, then arm efforts).
* ``input_map_matrix`` (R_Q, 9x9) = S(xi)^T = blockdiag(R_b, T^T, I3): the generalised
  force in thesis coordinates is u = R_Q N f.  (The thesis prints R_b^T T and R_b T in the
  middle block; by virtual power it must be T^T.)
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from . import coordinates as co
from .coordinates import as_vector
from .errors import UnknownNameError
from .model import Robot
from .params import LAYOUTS


def _check_layout(layout: str) -> None:
    if layout not in LAYOUTS:
        raise UnknownNameError("layout", layout, LAYOUTS)


def rotor_matrix(robot: Robot, layout: str = "plus") -> np.ndarray:
    """Omega (6x4): [f_B; tau_B] = Omega [f1..f4], from the rotor frames (thrust along each frame's z).

    Column i: [z_i; p_i x z_i + spin_i kappa z_i] with p_i, z_i the rotor position and axis
    in B and kappa = c/b the yaw torque per newton (Thesis (3.31), (3.36)).
    """
    _check_layout(layout)
    model = robot.model
    base = model.frames[robot.base_frame].placement
    kappa = robot.params.kappa
    cols = []
    for fid, rotor in zip(robot.rotor_frames[layout], robot.params.rotors(layout)):
        frame = model.frames[fid]
        # both frames hang on the free-flyer joint: their placements are relative to B
        M = base.actInv(frame.placement)
        z = M.rotation[:, 2]
        cols.append(np.concatenate([z, np.cross(M.translation, z) + rotor.spin * kappa * z]))
    return np.array(cols).T


def actuation_matrix(robot: Robot, layout: str = "plus") -> np.ndarray:
    """N (9x7) = diag(Omega, I3), Thesis (5.44)-(5.46): Pinocchio's tau = N f."""
    N = np.zeros((9, 7))
    N[0:6, 0:4] = rotor_matrix(robot, layout)
    N[6:9, 4:7] = np.eye(3)
    return N


def input_map_matrix(xi) -> np.ndarray:
    """R_Q(xi) = blockdiag(R_b, T(phi_b)^T, I3) = S(xi)^T, Thesis (5.41) corrected."""
    return co.rate_map(xi).T


def input_map(robot: Robot, xi, f, layout: str = "plus") -> np.ndarray:
    """u = R_Q N f: generalised forces in thesis coordinates, Thesis (5.43)."""
    f = as_vector(f, 7, "f")
    return input_map_matrix(xi) @ (actuation_matrix(robot, layout) @ f)


def allocation_inverse(robot: Robot, layout: str = "plus") -> np.ndarray:
    """Omega_z^-1 (4x4): rotor thrusts from [f_bz, tau_phi, tau_theta, tau_psi] (Thesis Annex A (A.1), corrected)."""
    Omega = rotor_matrix(robot, layout)
    return np.linalg.inv(Omega[2:6, :])


def hover_thrusts(robot: Robot, layout: str = "plus") -> np.ndarray:
    """Rotor thrusts [N] that hold the system level at rest when its CoG is on z_B: f_i = m_G g / 4."""
    wrench = np.array([robot.params.total_mass * robot.params.g, 0.0, 0.0, 0.0])
    return allocation_inverse(robot, layout) @ wrench


def generalized_force_from_wrench(robot: Robot, data: pin.Data, q, wrench_world, frame: str | int = "end_effector") -> np.ndarray:
    """Pinocchio generalised force J^T h of a wrench h = [f; mu] (world axes, applied at the frame origin)."""
    q = as_vector(q, robot.nq, "q")
    h = as_vector(wrench_world, 6, "wrench_world")
    fid = robot.model.getFrameId(frame) if isinstance(frame, str) else int(frame)
    if fid >= len(robot.model.frames):
        names = [f.name for f in robot.model.frames]
        raise UnknownNameError("frame", frame, names)
    J = pin.computeFrameJacobian(robot.model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
    return J.T @ h
