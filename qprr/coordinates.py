"""The one conversion between the thesis coordinates and Pinocchio's.

Thesis: xi = [x, y, z, phi, theta, psi, r0, theta2, theta3] with p_world = [x, y, z] and
ZYX Euler angles R = Rz(psi) Ry(theta) Rx(phi) (Thesis (3.4)); rates xi_dot.

Pinocchio (free-flyer root): q = [p_world, quat_xyzw, r0, theta2, theta3] (nq = 10) and
v = [v_body, omega_body, r0_dot, theta2_dot, theta3_dot] (nv = 9), both velocities in B.

The rate map is v = S(xi) xi_dot with S = blockdiag(R^T, T(phi_b), I3), where
omega_body = T(phi_b) [phi_dot, theta_dot, psi_dot] (Thesis (3.25)-(3.26)).  S is also
the tangent map of xi -> q, so generalised forces transform as u_xi = S^T tau.
T is singular at theta = +-pi/2 (cos theta = 0): functions that need T^-1 raise
:class:`EulerSingularityError` when |cos theta| < ``EULER_TOL``.
"""

from __future__ import annotations

from math import atan2, cos, hypot, sin

import numpy as np
import pinocchio as pin

from .errors import EulerSingularityError, NonFiniteError, ShapeError

EULER_TOL = 1e-6
"""|cos(theta)| below which ZYX Euler angles are treated as singular."""


def as_vector(x, n: int, name: str) -> np.ndarray:
    """``x`` as a finite float vector of length ``n``; raise naming ``name`` otherwise."""
    a = np.asarray(x, dtype=float)
    if a.shape != (n,):
        raise ShapeError(f"{name} must have shape ({n},), got shape {a.shape}")
    if not np.isfinite(a.sum()):  # a sum is finite iff every entry is (and far cheaper than isfinite().all())
        if not np.all(np.isfinite(a)):
            raise NonFiniteError(f"{name} must be finite, got {a.tolist()}")
    return a


_EX, _EY, _EZ = (pin.skew(np.eye(3)[i]) for i in range(3))


def rot_x(a: float) -> np.ndarray:
    c, s = cos(a), sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = cos(a), sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = cos(a), sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation(phi: float, theta: float, psi: float) -> np.ndarray:
    sf, cf, st, ct, sp, cp = sin(phi), cos(phi), sin(theta), cos(theta), sin(psi), cos(psi)
    return np.array([
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ])


def euler_to_rotation(euler_zyx) -> np.ndarray:
    """R_b = Rz(psi) Ry(theta) Rx(phi) for ``euler_zyx = [phi, theta, psi]``, expanded as Thesis (3.4)."""
    phi, theta, psi = as_vector(euler_zyx, 3, "euler_zyx").tolist()
    return _rotation(phi, theta, psi)


def _check_pitch(theta: float, what: str) -> None:
    if abs(cos(theta)) < EULER_TOL:
        raise EulerSingularityError(
            f"{what}: ZYX Euler angles are singular at pitch theta = {theta!r} rad "
            f"(|cos theta| < {EULER_TOL:g}); roll and yaw rates are not defined there"
        )


def rotation_to_euler(R) -> np.ndarray:
    """[phi, theta, psi] of a rotation matrix, theta in (-pi/2, pi/2) (Thesis (3.8), corrected).

    Raises :class:`EulerSingularityError` at theta = +-pi/2 where roll and yaw are not unique.
    The printed (3.8) swaps the roll and yaw formulas: see docs/thesis-errata.md.
    """
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3):
        raise ShapeError(f"R must have shape (3, 3), got {R.shape}")
    if not np.all(np.isfinite(R)):
        raise NonFiniteError("R must be finite")
    theta = atan2(-R[2, 0], hypot(R[2, 1], R[2, 2]))
    _check_pitch(theta, "rotation_to_euler")
    phi = atan2(R[2, 1], R[2, 2])
    psi = atan2(R[1, 0], R[0, 0])
    return np.array([phi, theta, psi])


def euler_rate_matrix(euler_zyx) -> np.ndarray:
    """T(phi_b) with omega_body = T [phi_dot, theta_dot, psi_dot] (Thesis (3.25)).

    The world-frame angular velocity is omega_world = R_b T phi_b_dot.
    """
    phi, theta, _ = as_vector(euler_zyx, 3, "euler_zyx").tolist()
    return _rate_matrix(phi, theta)


def _rate_matrix(phi: float, theta: float) -> np.ndarray:
    sf, cf, st, ct = sin(phi), cos(phi), sin(theta), cos(theta)
    return np.array([[1.0, 0.0, -st], [0.0, cf, sf * ct], [0.0, -sf, cf * ct]])


def rate_map(xi) -> np.ndarray:
    """S(xi) = blockdiag(R^T, T, I3) (9x9): v = S xi_dot, u_xi = S^T tau."""
    phi, theta, psi = as_vector(xi, 9, "xi")[3:6].tolist()
    S = np.eye(9)
    S[0:3, 0:3] = _rotation(phi, theta, psi).T
    S[3:6, 3:6] = _rate_matrix(phi, theta)
    return S


def rate_map_derivatives(xi) -> np.ndarray:
    """dS/dxi_k for k = phi, theta, psi as an array of shape (3, 9, 9) (S depends on nothing else)."""
    phi, theta, psi = as_vector(xi, 9, "xi")[3:6].tolist()
    Rx, Ry, Rz = rot_x(phi), rot_y(theta), rot_z(psi)
    dR = (Rz @ Ry @ Rx @ _EX, Rz @ Ry @ _EY @ Rx, Rz @ _EZ @ Ry @ Rx)
    sf, cf, st, ct = sin(phi), cos(phi), sin(theta), cos(theta)
    dT = (
        np.array([[0.0, 0.0, 0.0], [0.0, -sf, cf * ct], [0.0, -cf, -sf * ct]]),
        np.array([[0.0, 0.0, -ct], [0.0, 0.0, -sf * st], [0.0, 0.0, -cf * st]]),
        np.zeros((3, 3)),
    )
    out = np.zeros((3, 9, 9))
    for k in range(3):
        out[k, 0:3, 0:3] = dR[k].T
        out[k, 3:6, 3:6] = dT[k]
    return out


def xi_to_q(xi) -> np.ndarray:
    """Pinocchio configuration q (nq = 10) of thesis coordinates xi."""
    xi = as_vector(xi, 9, "xi")
    hf, ht, hp = 0.5 * xi[3], 0.5 * xi[4], 0.5 * xi[5]
    cf, sf, ct, st, cp, sp = cos(hf), sin(hf), cos(ht), sin(ht), cos(hp), sin(hp)
    q = np.empty(10)
    q[0:3] = xi[0:3]
    # quaternion of Rz(psi) Ry(theta) Rx(phi), (x, y, z, w) order as in Pinocchio
    q[3] = sf * ct * cp - cf * st * sp
    q[4] = cf * st * cp + sf * ct * sp
    q[5] = cf * ct * sp - sf * st * cp
    q[6] = cf * ct * cp + sf * st * sp
    q[7:10] = xi[6:9]
    return q


def q_to_xi(q) -> np.ndarray:
    """Thesis coordinates of a Pinocchio configuration (raises at the Euler singularity)."""
    q = as_vector(q, 10, "q")
    norm = np.linalg.norm(q[3:7])
    if not abs(norm - 1.0) < 1e-6:
        raise ShapeError(f"q[3:7] must be a unit quaternion (x, y, z, w), got norm {norm!r}")
    R = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
    return np.concatenate([q[0:3], rotation_to_euler(R), q[7:10]])


def xi_dot_to_v(xi, xi_dot) -> np.ndarray:
    """Pinocchio velocity v = S(xi) xi_dot (body-frame linear and angular velocity)."""
    return rate_map(xi) @ as_vector(xi_dot, 9, "xi_dot")


def v_to_xi_dot(xi, v) -> np.ndarray:
    """Thesis rates xi_dot = S(xi)^-1 v (raises at the Euler singularity)."""
    xi = as_vector(xi, 9, "xi")
    v = as_vector(v, 9, "v")
    _check_pitch(xi[4], "v_to_xi_dot")
    S = rate_map(xi)
    out = np.empty(9)
    out[0:3] = S[0:3, 0:3].T @ v[0:3]
    out[3:6] = np.linalg.solve(S[3:6, 3:6], v[3:6])
    out[6:9] = v[6:9]
    return out


def xi_to_qv(xi, xi_dot) -> tuple[np.ndarray, np.ndarray]:
    """(q, v) of thesis coordinates and rates."""
    return xi_to_q(xi), xi_dot_to_v(xi, xi_dot)


def qv_to_xi(q, v) -> tuple[np.ndarray, np.ndarray]:
    """(xi, xi_dot) of a Pinocchio state (raises at the Euler singularity)."""
    xi = q_to_xi(q)
    return xi, v_to_xi_dot(xi, v)


def rate_map_dot(xi, xi_dot) -> np.ndarray:
    """dS/dt along xi_dot."""
    xi_dot = as_vector(xi_dot, 9, "xi_dot")
    dS = rate_map_derivatives(xi)
    return np.tensordot(xi_dot[3:6], dS, axes=1)


def xi_ddot_to_a(xi, xi_dot, xi_ddot) -> np.ndarray:
    """Pinocchio acceleration a = S xi_ddot + S_dot xi_dot."""
    xi_dot = as_vector(xi_dot, 9, "xi_dot")
    return rate_map(xi) @ as_vector(xi_ddot, 9, "xi_ddot") + rate_map_dot(xi, xi_dot) @ xi_dot


def a_to_xi_ddot(xi, xi_dot, a) -> np.ndarray:
    """Thesis accelerations xi_ddot = S^-1 (a - S_dot xi_dot) (raises at the Euler singularity)."""
    xi = as_vector(xi, 9, "xi")
    xi_dot = as_vector(xi_dot, 9, "xi_dot")
    _check_pitch(xi[4], "a_to_xi_ddot")
    rhs = as_vector(a, 9, "a") - rate_map_dot(xi, xi_dot) @ xi_dot
    return np.linalg.solve(rate_map(xi), rhs)
