"""The thesis's closed forms, implemented AS PRINTED, each named by its equation number.

These functions exist to be compared with the Pinocchio model (see :mod:`qprr.thesis.checks`,
``tests/test_thesis.py`` and ``docs/thesis-errata.md``); the library itself never
uses them.  Where a printed formula is wrong, a ``*_corrected`` function gives the form
that matches the model and the physics, and the errata file explains the difference.

Conventions of the printed formulas (the ones of the thesis, not always ours):

* ``d = (d0, d1, d2, d3)`` link lengths [m]; ``q_arm = (r0, theta2, theta3)``.
* ``xi = [x, y, z, phi, theta, psi, r0, theta2, theta3]``, ZYX Euler angles (3.4).
* Masses and inertias are read from a :class:`~qprr.thesis.params.QPRRParams` where a formula
  needs many of them; ``I_x3`` etc. are the principal moments (Ixx, Iyy, Izz) of
  Table 3.2 in the link frame (y parallel to the joint axis, as in the URDF).
* The modified Denavit-Hartenberg convention of (3.27)-(3.30) is implemented once, in
  :mod:`qprr.nomenclature.mdh`; Table 3.4 and the transforms (3.48)-(3.56) are here.
* "c" in (3.36), (3.45)-(3.46) and (A.1) multiplies forces, so only c/b (kappa) makes
  those rows consistent with (3.31)-(3.35): the ``_corrected`` forms take (b, c).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..charts import check_rotation, rot_y, rot_z
from ..errors import InputError
from ..nomenclature.mdh import MDHRow, kk_transform
from ..nomenclature.mdh import chain as chain_frames
from ..validation import as_vector, checked_module
from .params import QPRRParams

E3 = np.array([0.0, 0.0, 1.0])


def _hat(v) -> np.ndarray:
    """Skew matrix of Thesis (3.18): hat(x) y = x cross y."""
    x1, x2, x3 = v
    return np.array([[0.0, -x3, x2], [x3, 0.0, -x1], [-x2, x1, 0.0]])


def _arm(q_arm) -> tuple[float, float, float]:
    r0, t2, t3 = as_vector(q_arm, 3, "q_arm")
    return float(r0), float(t2), float(t3)


def _lengths(d) -> tuple[float, float, float, float]:
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    return float(d0), float(d1), float(d2), float(d3)


def d_lengths(params: QPRRParams) -> tuple[float, float, float, float]:
    """(d0, d1, d2, d3) of a parameter set, the ``d`` argument of this module."""
    return (params.d0, params.d1, params.d2, params.d3)


# =========================================================================== chapter 3
def rotation_3_4(phi: float, theta: float, psi: float) -> np.ndarray:
    """R_b = Rz(psi) Ry(theta) Rx(phi) written out entry by entry, Thesis (3.4)."""
    sf, cf, st, ct, ss, cs = np.sin(phi), np.cos(phi), np.sin(theta), np.cos(theta), np.sin(psi), np.cos(psi)
    return np.array(
        [
            [ct * cs, sf * st * cs - cf * ss, cf * st * cs + sf * ss],
            [ct * ss, sf * st * ss + cf * cs, cf * st * ss - sf * cs],
            [-st, sf * ct, cf * ct],
        ]
    )


def euler_3_8(R) -> np.ndarray:
    """[phi, theta, psi] from R as printed, Thesis (3.8): phi = atan2(r21, r11), psi = atan2(r32, r33).

    Misprint: the roll and yaw formulas are swapped (see :func:`euler_3_8_corrected`).
    """
    R = check_rotation(R, "R", 1e-6)
    R = np.asarray(R, dtype=float)
    return np.array([np.arctan2(R[1, 0], R[0, 0]), np.arctan2(-R[2, 0], np.hypot(R[2, 1], R[2, 2])), np.arctan2(R[2, 1], R[2, 2])])


def euler_3_8_corrected(R) -> np.ndarray:
    """(3.8) with roll and yaw swapped back: phi = atan2(r32, r33), psi = atan2(r21, r11)."""
    R = check_rotation(R, "R", 1e-6)
    R = np.asarray(R, dtype=float)
    return np.array([np.arctan2(R[2, 1], R[2, 2]), np.arctan2(-R[2, 0], np.hypot(R[2, 1], R[2, 2])), np.arctan2(R[1, 0], R[0, 0])])


def T_3_25(phi: float, theta: float) -> np.ndarray:
    """T(phi_b) with omega = T [phi_dot, theta_dot, psi_dot], Thesis (3.25).

    omega is the BODY-frame angular velocity (R^T R_dot)^vee of (3.19), although (3.15)
    calls it the inertial-frame velocity.
    """
    sf, cf, st, ct = np.sin(phi), np.cos(phi), np.sin(theta), np.cos(theta)
    return np.array([[1.0, 0.0, -st], [0.0, cf, sf * ct], [0.0, -sf, cf * ct]])


# ------------------------------------------------ modified Denavit-Hartenberg, (3.27)-(3.30)
def mdh_3_28(alpha: float, d: float, theta: float, r: float) -> np.ndarray:
    """^(i-1)T_i (4x4) written out as printed in Thesis (3.28) (printed with a_(i-1), alpha_(i-1) for d_i, alpha_i).

    Misprint: entry (1, 2) is printed +sin(theta); the product (3.27)
    Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r) gives -sin(theta)
    (:func:`mdh_3_28_corrected`).  As printed the rotation block is not orthogonal.
    """
    sa, ca, st, ct = np.sin(alpha), np.cos(alpha), np.sin(theta), np.cos(theta)
    return np.array(
        [
            [ct, st, 0.0, d],
            [ca * st, ca * ct, -sa, -r * sa],
            [sa * st, sa * ct, ca, r * ca],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def mdh_3_28_corrected(alpha: float, d: float, theta: float, r: float) -> np.ndarray:
    """(3.28) with entry (1, 2) = -sin(theta): the product (3.27), :func:`qprr.nomenclature.mdh.kk_transform`."""
    return kk_transform(alpha, d, theta, r)


def table_3_4(d) -> tuple[MDHRow, ...]:
    """Table 3.4 as printed: rows (sigma, alpha, d, theta, r) = (1, 0, d0, 0, r0), (0, pi, d1, theta2, 0),
    (0, 0, d2, theta3, 0), (0, 0, d3, 0, 0); the variables r0, theta2, theta3 are the joints.

    The table numbers its rows 0..3 and row i gives ^iT_(i+1) ((3.52)-(3.55)).  Misprint:
    alpha = pi on the theta2 row makes z_2 = -x_B (theta2 would turn about the slider
    axis); (3.53) is printed with alpha = pi/2 (:func:`table_3_4_corrected`).
    """
    d0, d1, d2, d3 = _lengths(d)
    return (
        MDHRow(1, 0.0, d0, 0.0, 0.0),
        MDHRow(0, np.pi, d1, 0.0, 0.0),
        MDHRow(0, 0.0, d2, 0.0, 0.0),
        MDHRow(0, 0.0, d3, 0.0, 0.0, joint=False),
    )


def table_3_4_corrected(d) -> tuple[MDHRow, ...]:
    """Table 3.4 with alpha = pi/2 on the theta2 row (as (3.53) is printed): z_2 = +y_B."""
    rows = table_3_4(d)
    return (rows[0], MDHRow(0, np.pi / 2, rows[1].d, 0.0, 0.0), *rows[2:])


def _rot4(R) -> np.ndarray:
    R = check_rotation(R, "R", 1e-6)
    T = np.eye(4)
    T[0:3, 0:3] = R
    return T


def T_b0_3_48() -> np.ndarray:
    """^bT_0 = Rot(y, pi/2) Rot(z, pi), the product stated in Thesis (3.48)."""
    return _rot4(rot_y(np.pi / 2) @ rot_z(np.pi))


def T_b0_3_49() -> np.ndarray:
    """^bT_0 as printed in Thesis (3.49): rows (0 0 1 0), (0 -1 0 0), (1 0 0 0)."""
    return np.array([[0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def T_4eb_3_50() -> np.ndarray:
    """^4T_eb = Rot(y, pi/2) Rot(z, -pi/2), the product stated in Thesis (3.50).

    Misprint: that product is [[0 0 1], [-1 0 0], [0 -1 0]], not the matrix printed as its
    result in (3.51); the chain needs (3.51), which is Rot(y, pi/2) Rot(z, +pi/2)
    (:func:`T_4eb_3_50_corrected`).
    """
    return _rot4(rot_y(np.pi / 2) @ rot_z(-np.pi / 2))


def T_4eb_3_50_corrected() -> np.ndarray:
    """(3.50) with Rot(z, +pi/2): Rot(y, pi/2) Rot(z, pi/2) = the matrix (3.51)."""
    return _rot4(rot_y(np.pi / 2) @ rot_z(np.pi / 2))


def T_4eb_3_51() -> np.ndarray:
    """^4T_eb as printed in Thesis (3.51): rows (0 0 1 0), (1 0 0 0), (0 1 0 0)."""
    return np.array([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def T_01_3_52(r0: float, d0: float) -> np.ndarray:
    """^0T_1 as printed in Thesis (3.52): translation (d0, 0, r0)."""
    return np.array([[1.0, 0.0, 0.0, d0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, r0], [0.0, 0.0, 0.0, 1.0]])


def T_12_3_53(theta2: float, d1: float) -> np.ndarray:
    """^1T_2 as printed in Thesis (3.53): [[c2, -s2, 0, d1], [0, 0, -1, 0], [s2, c2, 0, 0]] (alpha = pi/2)."""
    s, c = np.sin(theta2), np.cos(theta2)
    return np.array([[c, -s, 0.0, d1], [0.0, 0.0, -1.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def T_23_3_54(theta3: float, d2: float) -> np.ndarray:
    """^2T_3 as printed in Thesis (3.54): Rot(z, theta3) with translation (d2, 0, 0)."""
    s, c = np.sin(theta3), np.cos(theta3)
    return np.array([[c, -s, 0.0, d2], [s, c, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def T_34_3_55(d3: float) -> np.ndarray:
    """^3T_4 as printed in Thesis (3.55): translation (d3, 0, 0)."""
    T = np.eye(4)
    T[0, 3] = d3
    return T


def mdh_frames_3_56(q_arm, d) -> list[np.ndarray]:
    """[^bT_1, ^bT_2, ^bT_3, ^bT_4, ^bT_eb] from the printed (3.49), (3.52)-(3.55), (3.51), Thesis (3.56)."""
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = _lengths(d)
    out = [T_b0_3_49() @ T_01_3_52(r0, d0)]
    for T in (T_12_3_53(t2, d1), T_23_3_54(t3, d2), T_34_3_55(d3), T_4eb_3_51()):
        out.append(out[-1] @ T)
    return out


def T_eb_3_56(q_arm, d) -> np.ndarray:
    """^bT_eb = ^bT_0 ^0T_1 ^1T_2 ^2T_3 ^3T_4 ^4T_eb with the printed matrices, Thesis (3.56)."""
    return mdh_frames_3_56(q_arm, d)[-1]


def allocation_3_36(l: float, c: float) -> np.ndarray:
    """[f_b, tau_phi, tau_theta, tau_psi] = A [f1..f4], Thesis (3.36) as printed (yaw row c, -c, c, -c).

    Misprint: the yaw row multiplies forces, so its entries must be c/b (3.31).
    """
    return np.array([[1.0, 1.0, 1.0, 1.0], [0.0, -l, 0.0, l], [l, 0.0, -l, 0.0], [c, -c, c, -c]])


def allocation_3_36_corrected(l: float, b: float, c: float) -> np.ndarray:
    """(3.36) with the yaw row kappa (1, -1, 1, -1), kappa = c/b (from (3.31): tau_i = (c/b) f_i)."""
    return allocation_3_36(l, c / b)


def allocation_3_37(b: float, l: float, c: float) -> np.ndarray:
    """[u1..u4] = A [w1^2..w4^2], Thesis (3.37) as printed (row 3: -lb, 0, lb, 0).

    Misprint: row 3 contradicts (3.34)-(3.36), tau_theta = bl(w1^2 - w3^2).
    """
    return np.array([[b, b, b, b], [0.0, -l * b, 0.0, l * b], [-l * b, 0.0, l * b, 0.0], [c, -c, c, -c]])


def allocation_3_37_corrected(b: float, l: float, c: float) -> np.ndarray:
    """(3.37) with row 3 = (lb, 0, -lb, 0) as (3.34) states."""
    A = allocation_3_37(b, l, c)
    A[2] *= -1.0
    return A


def det_3_37(b: float, l: float, c: float) -> float:
    """det of the (3.37) matrix as printed: 8 c l^2 b^3 (Thesis, text after (3.37))."""
    return 8.0 * c * l**2 * b**3


def det_3_37_corrected(b: float, l: float, c: float) -> float:
    """det of the corrected (3.37) matrix: -8 c l^2 b^3 (flipping row 3 flips the sign)."""
    return -det_3_37(b, l, c)


def rotor_inverse_A1(l: float, c: float) -> np.ndarray:
    """[f1..f4] = A^-1 [u_b, u_tau_phi, u_tau_theta, u_tau_psi], Thesis Annex A (A.1) as printed.

    Misprint: the tau_theta column has the wrong sign for f1 and f3 (it is not the inverse
    of (3.36)/(A.1)).
    """
    h, q = 1.0 / (2.0 * l), 1.0 / (4.0 * c)
    return np.array([[0.25, 0.0, -h, q], [0.25, -h, 0.0, -q], [0.25, 0.0, h, q], [0.25, h, 0.0, -q]])


def rotor_inverse_A1_corrected(l: float, b: float, c: float) -> np.ndarray:
    """Inverse of the corrected (3.36): tau_theta column (+1/2l, 0, -1/2l, 0), yaw column +-b/(4c)."""
    h, q = 1.0 / (2.0 * l), b / (4.0 * c)
    return np.array([[0.25, 0.0, h, q], [0.25, -h, 0.0, -q], [0.25, 0.0, -h, q], [0.25, h, 0.0, -q]])


def link_coms_3_78(q_arm, d) -> np.ndarray:
    """Centres of mass p_c1, p_c2, p_c3 of the links in B (rows), Thesis (3.78) list, Hypothesis 1."""
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = _lengths(d)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    return np.array(
        [
            [r0, 0.0, d0 + d1 / 2.0],
            [r0 + d2 * s2 / 2.0, 0.0, d0 + d1 + d2 * c2 / 2.0],
            [r0 + d2 * s2 + d3 * s23 / 2.0, 0.0, d0 + d1 + d2 * c2 + d3 * c23 / 2.0],
        ]
    )


def _link_masses(params: QPRRParams) -> np.ndarray:
    return np.array([link.mass for link in params.links])


def arm_com_3_44(q_arm, params: QPRRParams) -> np.ndarray:
    """xi_c = (1/m_G) sum m_i xi_ci, the arm's CoM in B, Thesis (3.44) with the p_ci of (3.78)."""
    m = _link_masses(params)
    return m @ link_coms_3_78(q_arm, d_lengths(params)) / m.sum()


def potential_3_42(R_b, q_arm, params: QPRRParams) -> float:
    """U = -sum m_i g e3^T R_b xi_ci, Thesis (3.42): correct in an NED world (gravity +g e3), base at the origin."""
    R_b = check_rotation(R_b, "R_b", 1e-6)
    R_b = np.asarray(R_b, dtype=float)
    m = _link_masses(params)
    coms = link_coms_3_78(q_arm, d_lengths(params))
    return float(-sum(mi * params.g * E3 @ R_b @ c for mi, c in zip(m, coms)))


def arm_torque_3_43(R_b, q_arm, params: QPRRParams) -> np.ndarray:
    """tau_arm = m_G g xi_c x R_b^T e3 (in B), Thesis (3.43), m_G the arm mass.

    Correct under the NED convention of (3.42) (gravity +g e3); with our z-up world
    (gravity -g e3) the sign is opposite: :func:`arm_torque_3_43_corrected`.
    """
    R_b = check_rotation(R_b, "R_b", 1e-6)
    R_b = np.asarray(R_b, dtype=float)
    return params.arm_mass * params.g * np.cross(arm_com_3_44(q_arm, params), R_b.T @ E3)


def arm_torque_3_43_corrected(R_b, q_arm, params: QPRRParams) -> np.ndarray:
    """(3.43) in the z-up world of (5.27)-(5.29): tau_arm = -m_G g xi_c x R_b^T e3."""
    R_b = check_rotation(R_b, "R_b", 1e-6)
    return -arm_torque_3_43(R_b, q_arm, params)


def T_eb_3_58(q_arm, d) -> np.ndarray:
    """^bT_eb (4x4): end-effector pose in B, Thesis (3.58)."""
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = _lengths(d)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    return np.array(
        [
            [c23, 0.0, s23, r0 + d2 * s2 + d3 * s23],
            [0.0, 1.0, 0.0, 0.0],
            [-s23, 0.0, c23, d0 + d1 + d2 * c2 + d3 * c23],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def p_e_3_61(xi, d) -> np.ndarray:
    """p_e expanded under Thesis (3.61) as printed (y_e carries c_theta c_psi x_eb).

    Misprint: the x_eb term of y_e must be c_theta s_psi x_eb (as in (3.65)).
    """
    xb, yb, zb, f, t, s, *arm = as_vector(xi, 9, "xi")
    x_eb, z_eb = T_eb_3_58(arm, d)[[0, 2], 3]
    sf, cf, st, ct, ss, cs = np.sin(f), np.cos(f), np.sin(t), np.cos(t), np.sin(s), np.cos(s)
    return np.array(
        [
            xb + z_eb * (sf * ss + cf * cs * st) + cs * ct * x_eb,
            yb - z_eb * (cs * sf - cf * ss * st) + ct * cs * x_eb,
            zb - st * x_eb + cf * ct * z_eb,
        ]
    )


def p_e_3_61_corrected(xi, d) -> np.ndarray:
    """(3.61) p_e with y_e = y_b - z_eb (c_psi s_phi - c_phi s_psi s_theta) + c_theta s_psi x_eb."""
    xi = as_vector(xi, 9, "xi")
    x_eb, z_eb = T_eb_3_58(xi[6:9], d)[[0, 2], 3]
    p = p_e_3_61(xi, d)
    p[1] += np.cos(xi[4]) * (np.sin(xi[5]) - np.cos(xi[5])) * x_eb
    return p


def R_e_3_62(phi: float, theta: float, psi: float, theta2: float, theta3: float) -> np.ndarray:
    """R_e = R_b R_eb written out entry by entry, Thesis (3.62)."""
    sf, cf, st, ct, ss, cs = np.sin(phi), np.cos(phi), np.sin(theta), np.cos(theta), np.sin(psi), np.cos(psi)
    s23, c23 = np.sin(theta2 + theta3), np.cos(theta2 + theta3)
    return np.array(
        [
            [c23 * cs * ct - s23 * (sf * ss + cf * cs * st), cs * sf * st - cf * ss, c23 * (sf * ss + cf * cs * st) + s23 * cs * ct],
            [s23 * (cs * sf - cf * ss * st) + c23 * ct * ss, cf * cs + sf * ss * st, s23 * ct * ss - c23 * (cs * sf - cf * ss * st)],
            [-c23 * st - s23 * cf * ct, ct * sf, c23 * cf * ct - s23 * st],
        ]
    )


def euler_3_64(R) -> np.ndarray:
    """[phi_e, theta_e, psi_e] of R_e, Thesis (3.64): a ZYZ extraction, R = Rz(phi_e) Ry(theta_e) Rz(psi_e).

    theta_e = atan2(sqrt(r13^2 + r23^2), r33) lies in [0, pi]; undefined when r13 = r23 = 0.
    """
    R = check_rotation(R, "R", 1e-6)
    R = np.asarray(R, dtype=float)
    return np.array([np.arctan2(R[1, 2], R[0, 2]), np.arctan2(np.hypot(R[0, 2], R[1, 2]), R[2, 2]), np.arctan2(R[2, 1], -R[2, 0])])


def zyz_to_rotation(angles) -> np.ndarray:
    """Rz(a) Ry(b) Rz(c): the convention under which (3.64) extracts its angles."""
    a, b, c = as_vector(angles, 3, "angles")
    return rot_z(a) @ rot_y(b) @ rot_z(c)


def fk_3_65(xi, d) -> np.ndarray:
    """chi_e = [x_e, y_e, z_e, phi_e, theta_e, psi_e], Thesis (3.65) (orientation as ZYZ angles)."""
    xb, yb, zb, f, t, s, r0, t2, t3 = as_vector(xi, 9, "xi")
    d0, d1, d2, d3 = _lengths(d)
    sf, cf, st, ct, ss, cs = np.sin(f), np.cos(f), np.sin(t), np.cos(t), np.sin(s), np.cos(s)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    xeb = r0 + d2 * s2 + d3 * s23
    zeb = d0 + d1 + d2 * c2 + d3 * c23
    r13 = c23 * (sf * ss + cf * cs * st) + s23 * cs * ct
    r23 = s23 * ct * ss - c23 * (cs * sf - cf * ss * st)
    r31 = -c23 * st - s23 * cf * ct
    r32 = ct * sf
    r33 = c23 * cf * ct - s23 * st
    return np.array(
        [
            xb + cs * ct * xeb + zeb * (sf * ss + cf * cs * st),
            yb + ct * ss * xeb - zeb * (cs * sf - cf * ss * st),
            zb - st * xeb + cf * ct * zeb,
            np.arctan2(r23, r13),
            np.arctan2(np.hypot(r13, r23), r33),
            np.arctan2(r32, -r31),
        ]
    )


def hover_fk_3_68(x_b: float, y_b: float, z_b: float, psi: float, q_arm, d) -> np.ndarray:
    """(3.65) simplified at phi = theta = 0 as printed, Thesis (3.68).

    Lines 1-3 are right.  Lines 4-6 are misprinted: phi_e = atan2(s_psi c23, c_psi s23)
    (c23 should be s23), theta_e = atan2(s23, c23) (should be atan2(|s23|, c23)) and
    psi_e = -(1/2)(pi sgn(s23) - 1) (should be (pi/2)(1 - sgn s23)).
    """
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = _lengths(d)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    ss, cs = np.sin(psi), np.cos(psi)
    xeb = r0 + d2 * s2 + d3 * s23
    return np.array(
        [
            x_b + cs * xeb,
            y_b + ss * xeb,
            z_b + d0 + d1 + d2 * c2 + d3 * c23,
            np.arctan2(ss * c23, cs * s23),
            np.arctan2(s23, c23),
            -0.5 * (np.pi * np.sign(s23) - 1.0),
        ]
    )


def hover_fk_3_68_corrected(x_b: float, y_b: float, z_b: float, psi: float, q_arm, d) -> np.ndarray:
    """(3.65) at phi = theta = 0: phi_e = atan2(s_psi s23, c_psi s23), theta_e = atan2(|s23|, c23),
    psi_e = (pi/2)(1 - sgn s23) (s23 != 0)."""
    out = hover_fk_3_68(x_b, y_b, z_b, psi, q_arm, d)
    s23, c23 = np.sin(q_arm[1] + q_arm[2]), np.cos(q_arm[1] + q_arm[2])
    out[3] = np.arctan2(np.sin(psi) * s23, np.cos(psi) * s23)
    out[4] = np.arctan2(abs(s23), c23)
    out[5] = 0.5 * np.pi * (1.0 - np.sign(s23))
    return out


def _payload_args(m_l, d_cl) -> tuple[float, float]:
    m_l, d_cl = float(m_l), float(d_cl)
    if not (np.isfinite(m_l) and m_l >= 0.0):
        raise InputError(f"m_l (payload mass) must be a finite number >= 0 kg, got {m_l!r}")
    if not np.isfinite(d_cl):
        raise InputError(f"d_cl (end effector to payload centre) must be finite, got {d_cl!r}")
    return m_l, d_cl


def payload_com_3_76(q_arm, d, d_cl: float) -> np.ndarray:
    """p_cl, the payload centre in B at d_cl [m] beyond the end effector along link 3, Thesis (3.76)-(3.77) list.

    p_cl = [r0 + d2 s2 + (d3 + d_cl) s23, 0, d0 + d1 + d2 c2 + (d3 + d_cl) c23].
    """
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = _lengths(d)
    _, d_cl = _payload_args(0.0, d_cl)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    return np.array([r0 + d2 * s2 + (d3 + d_cl) * s23, 0.0, d0 + d1 + d2 * c2 + (d3 + d_cl) * c23])


def com_3_78(q_arm, params: QPRRParams, *, m_l: float = 0.0, d_cl: float = 0.0) -> np.ndarray:
    """[x_cm, y_cm, z_cm] of the whole system in B [m], Thesis (3.78) as printed.

    ``m_l`` [kg] is a payload held with its centre at ``d_cl`` [m] beyond the end effector
    (p_cl of :func:`payload_com_3_76`); m_G = m_b + sum m_i + m_l (3.77).  Remark 3 sets
    p_cl = 0 when m_l = 0.  Two misprints:

    * the payload enters as "+ x_cl", "+ z_cl" (a length added to masses times lengths)
      where (3.76) has m_l p_cl;
    * z_cm: sum m_i (d0 + d1) ignores the half-length of link 1 (p_c1 has d0 + d1/2) and
      (1/2)(m2 + m3) d2 c2 should be (m2/2 + m3) d2 c2.

    The corrected form is :func:`com_3_78_corrected`.
    """
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = d_lengths(params)
    m_l, d_cl = _payload_args(m_l, d_cl)
    m1, m2, m3 = _link_masses(params)
    mG = params.total_mass + m_l
    x_cl, _, z_cl = payload_com_3_76(q_arm, (d0, d1, d2, d3), d_cl) if m_l > 0.0 else np.zeros(3)
    x = ((m1 + m2 + m3) * r0 + (m2 / 2 + m3) * d2 * np.sin(t2) + m3 * d3 * np.sin(t2 + t3) / 2 + x_cl) / mG
    z = ((m1 + m2 + m3) * (d0 + d1) + (m2 + m3) * d2 * np.cos(t2) / 2 + m3 * d3 * np.cos(t2 + t3) / 2 + z_cl) / mG
    return np.array([x, 0.0, z])


def com_3_78_corrected(q_arm, params: QPRRParams, *, m_l: float = 0.0, d_cl: float = 0.0) -> np.ndarray:
    """(3.78) corrected: m_l p_cl for the payload term (3.76) and, in z_cm,
    m1 (d0 + d1/2) + (m2 + m3)(d0 + d1) + (m2/2 + m3) d2 c2 + m3 d3 c23 / 2; divided by m_G of (3.77)."""
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = d_lengths(params)
    m_l, d_cl = _payload_args(m_l, d_cl)
    m1, m2, m3 = _link_masses(params)
    x = (m1 + m2 + m3) * r0 + (m2 / 2 + m3) * d2 * np.sin(t2) + m3 * d3 * np.sin(t2 + t3) / 2
    z = m1 * (d0 + d1 / 2) + (m2 + m3) * (d0 + d1) + (m2 / 2 + m3) * d2 * np.cos(t2) + m3 * d3 * np.cos(t2 + t3) / 2
    first_moment = np.array([x, 0.0, z]) + m_l * payload_com_3_76(q_arm, (d0, d1, d2, d3), d_cl)
    return first_moment / (params.total_mass + m_l)


def x_cm_3_80(q_arm, params: QPRRParams) -> float:
    """F(r0, theta2, theta3) = x_cm, Thesis (3.79)-(3.80)."""
    r0, t2, t3 = _arm(q_arm)
    _, _, d2, d3 = d_lengths(params)
    m1, m2, m3 = _link_masses(params)
    return float(((m1 + m2 + m3) * r0 + (m2 / 2 + m3) * d2 * np.sin(t2) + m3 * d3 * np.sin(t2 + t3) / 2) / params.total_mass)


# =========================================================================== chapter 4
def v_ee_4_24(q_arm, q_arm_dot, d, corrected: bool = False) -> np.ndarray:
    """^eb v_4: velocity of the end effector relative to B, in the end-effector axes eb, Thesis (4.24).

    As printed, the theta2_dot coefficient of the first row is d2 s3 + d3; ``corrected=True`` gives
    d2 c3 + d3 (the third row's d2 s3 theta2_dot is right): R_eb^T of the velocity of (3.58)'s origin,
    since cos(theta2 + theta3 - theta2) = c3 is the projection of link 2's velocity d2 theta2_dot on
    the first eb axis.
    """
    r0d, t2d, t3d = as_vector(q_arm_dot, 3, "q_arm_dot")
    _, t2, t3 = _arm(q_arm)
    _, _, d2, d3 = _lengths(d)
    s3, c3, s23, c23 = np.sin(t3), np.cos(t3), np.sin(t2 + t3), np.cos(t2 + t3)
    link2 = d2 * c3 if corrected else d2 * s3
    return np.array([c23 * r0d + (link2 + d3) * t2d + d3 * t3d, 0.0, s23 * r0d + d2 * s3 * t2d])


def J_eb_4_26(q_arm, d) -> np.ndarray:
    """J_eb (6x3): [p_eb_dot; omega_eb] (in B) = J_eb q_arm_dot, Thesis (4.26)."""
    _, t2, t3 = _arm(q_arm)
    _, _, d2, d3 = _lengths(d)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    return np.array(
        [
            [1.0, d2 * c2 + d3 * c23, d3 * c23],
            [0.0, 0.0, 0.0],
            [0.0, -(d2 * s2 + d3 * s23), -d3 * s23],
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 1.0],
            [0.0, 0.0, 0.0],
        ]
    )


def J_4_27(q_arm, d) -> np.ndarray:
    """J_eb* (3x3): rows (x, z, omega_y) of (4.26), Thesis (4.27)."""
    return J_eb_4_26(q_arm, d)[[0, 2, 4]]


def det_4_28(theta2: float, d2: float) -> float:
    """det J_eb* = -d2 s2, Thesis (4.28)."""
    return float(-d2 * np.sin(theta2))


def J_e_4_12(xi, d) -> np.ndarray:
    """J_e (6x9) assembled as printed in Thesis (4.10)-(4.12): v_e = J_b T_A q_b_dot + J_eb q_eb_dot.

    J_b T_A = [[I, -R_b hat(p_eb) T], [0, T]].  Misprint: omega_e is a world-frame
    velocity (4.7) and T maps Euler rates to the BODY rate (3.25), so the lower middle
    block must be R_b T (:func:`J_e_4_12_corrected`).
    """
    xi = as_vector(xi, 9, "xi")
    Rb = rotation_3_4(*xi[3:6])
    T = T_3_25(xi[3], xi[4])
    p_eb = T_eb_3_58(xi[6:9], d)[0:3, 3]
    Jeb = J_eb_4_26(xi[6:9], d)
    J = np.zeros((6, 9))
    J[0:3, 0:3] = np.eye(3)
    J[0:3, 3:6] = -Rb @ _hat(p_eb) @ T
    J[3:6, 3:6] = T
    J[0:3, 6:9] = Rb @ Jeb[0:3]
    J[3:6, 6:9] = Rb @ Jeb[3:6]
    return J


def J_e_4_12_corrected(xi, d) -> np.ndarray:
    """(4.12) with the lower middle block R_b T: omega_e (world) = R_b T phi_b_dot + R_b omega_eb."""
    xi = as_vector(xi, 9, "xi")
    J = J_e_4_12(xi, d)
    J[3:6, 3:6] = rotation_3_4(*xi[3:6]) @ J[3:6, 3:6]
    return J


def det_JJt_4_44(r0: float, theta2: float, d) -> float:
    """det(J J^T) at zero Euler angles expanded in theta2 and r0, Thesis (4.44) (no d3, theta3)."""
    d0, d1, d2, _ = _lengths(d)
    s2, c2 = np.sin(theta2), np.cos(theta2)
    return float(
        4 * d0 * d1
        + 2 * d2**2 * c2**2
        + 4 * d2**2 * s2**2
        + 2 * d0**2
        + 2 * d1**2
        + 4 * r0**2
        + 4 * d2 * r0 * s2
        + d2**2 * r0**2 * c2**2
        + d0**2 * d2**2 * s2**2
        + d1**2 * d2**2 * s2**2
        + 2 * d0 * d2 * c2
        + 2 * d1 * d2 * c2
        + 2 * d0 * d1 * d2**2 * s2**2
        - d0 * d2**2 * r0 * 2 * s2 * c2
        - d1 * d2**2 * r0 * 2 * s2 * c2
        + 6
    )


LU_L_NAMES = ("a31", "a42", "a51", "a53", "a62", "a64")
"""Below-diagonal entries of J_L in (4.42) (a31 appears in the matrix but no formula is printed for it)."""
LU_U_NAMES = ("b11", "b13", "b15", "b22", "b24", "b26", "b33", "b35", "b44", "b46", "b55", "b66")
"""Non-zero entries of J_U in (4.42)."""


def _lu_sums(q_arm, d):
    """The sums the printed factors repeat: x = x_eb, z = z_eb of (3.58), e = d2 s2 + d3 s23, a = d2 c2 + d3 c23."""
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = _lengths(d)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    x, z = r0 + d3 * s23 + d2 * s2, d0 + d1 + d3 * c23 + d2 * c2
    return r0, t2, t3, d0, d1, d2, d3, s2, c2, s23, c23, x, z, d3 * s23 + d2 * s2, d3 * c23 + d2 * c2


def lu_factors_4_42(q_arm, d) -> dict[str, float]:
    """a_ij, b_ij of J^gamma = J J^T = J_L J_U at zero Euler angles as printed after Thesis (4.42).

    J_L is unit lower triangular (entries a_ij), J_U upper triangular (entries b_ij); rows
    and columns are (x, y, z, omega_x, omega_y, omega_z).  The printed expressions repeat
    the sums x = r0 + d2 s2 + d3 s23, z = d0 + d1 + d2 c2 + d3 c23, e = d2 s2 + d3 s23,
    a = d2 c2 + d3 c23; they are named here, the expressions are otherwise as printed.
    a31 has no printed formula (returned as NaN).  Two misprints (see ``_corrected``):

    * a53: the text has one closing parenthesis too many; read literally,
      a53 = -(X - N b15/b11) - N^2/b11 + 1 with X = r0 + 3 d3 s23 + 2 d2 s2 and
      N = x z + e a + d3^2 c23 s23, where a53 = b35 / b33;
    * b55: inside its last denominator (which should be b33) the text has d2^4 s2 c2 for
      d2^2 sin(2 theta2) and 2 d2 d3 s23 c23 for 2 d2 d3 sin(2 theta2 + theta3).
    """
    r0, t2, t3, d0, d1, d2, d3, s2, c2, s23, c23, x, z, e, a = _lu_sums(q_arm, d)
    D = d3**2 * c23**2 + z**2 + a**2 + 2  # the repeated denominator (= b11)
    N = x * z + e * a + d3**2 * c23 * s23
    B15 = d0 + d1 + 3 * d3 * c23 + 2 * d2 * c2
    X = r0 + 3 * d3 * s23 + 2 * d2 * s2
    Q = x**2 + z**2 + 1  # the repeated denominator (= b22)
    f = {"a31": float("nan")}
    f["a42"] = -z / (z * z + x * x + 1)
    f["a51"] = B15 / D
    f["a53"] = -(X - N * B15 / D) - N * N / D + 1
    f["a62"] = x / Q
    f["a64"] = -(x * z) / ((z**2 / Q - 1) * Q)
    f["b11"] = D
    f["b13"] = -a * e - x * z - d3**2 * c23 * s23
    f["b15"] = B15
    f["b22"] = Q
    f["b24"] = -d0 - d1 - d3 * c23 - d2 * c2
    f["b26"] = x
    f["b33"] = d3**2 * s23**2 + x**2 - N**2 / D + e**2 + 1
    f["b35"] = N * B15 / D - 3 * d3 * s23 - 2 * d2 * s2 - r0
    f["b44"] = 1 - z**2 / Q
    f["b46"] = x * z / Q
    M = d2**2 * np.sin(2 * t2) / 2 + x * z + d3**2 * np.sin(2 * t2 + 2 * t3) + d2 * d3 * np.sin(2 * t2 + t3)
    Y = d2**4 * s2 * c2 + 2 * x * z + 2 * d3**2 * np.sin(2 * t2 + 2 * t3) + 2 * d2 * d3 * s23 * c23
    f["b55"] = 3 - B15**2 / D - (X - M * B15 / D) ** 2 / (d3**2 * s23**2 - Y**2 / (4 * D) + x**2 + e**2 + 1)
    f["b66"] = x**2 * z**2 / ((z**2 / Q - 1) * Q**2) - x**2 / Q + 1
    return {k: float(v) for k, v in f.items()}


def lu_factors_4_42_corrected(q_arm, d) -> dict[str, float]:
    """(4.42) factors with a31 = b13/b11, a53 = b35/b33 and b55 = 3 - b15^2/b11 - b35^2/b33 (Doolittle elimination)."""
    f = lu_factors_4_42(q_arm, d)
    f["a31"] = f["b13"] / f["b11"]
    f["a53"] = f["b35"] / f["b33"]
    f["b55"] = 3 - f["b15"] ** 2 / f["b11"] - f["b35"] ** 2 / f["b33"]
    return f


def _factors(factors) -> dict:
    if not isinstance(factors, dict):
        raise InputError(f"factors must be the dict of lu_factors_4_42, got {type(factors).__name__}")
    return factors


def lu_matrices_4_42(factors: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """(J_L, J_U) (6x6) assembled from a_ij, b_ij with the sparsity pattern printed in (4.42)."""
    factors = _factors(factors)
    L, U = np.eye(6), np.zeros((6, 6))
    for name in LU_L_NAMES:
        L[int(name[1]) - 1, int(name[2]) - 1] = factors[name]
    for name in LU_U_NAMES:
        U[int(name[1]) - 1, int(name[2]) - 1] = factors[name]
    return L, U


def det_4_43(factors: dict[str, float]) -> float:
    """det(J^gamma) = det(J_U) = b11 b22 b33 b44 b55 b66, Thesis (4.43) (the text says det(J_U) = 1 where it means det(J_L))."""
    factors = _factors(factors)
    return float(np.prod([factors[f"b{i}{i}"] for i in range(1, 7)]))


def basis_4_45(r0: float, theta2: float) -> np.ndarray:
    """The functions lambda_j multiplies in Thesis (4.45): r0^2, r0^2 c2^2, c2^2, s2^2, r0 s2 c2, c2, s2, 1.

    Misprint: (4.44) has a term 4 d2 r0 s2 and no s2 term, so the seventh function must be
    r0 s2 (:func:`basis_4_45_corrected`); no constant lambda_7 can stand for 4 d2 r0.
    """
    s2, c2 = np.sin(theta2), np.cos(theta2)
    return np.array([r0**2, r0**2 * c2**2, c2**2, s2**2, r0 * s2 * c2, c2, s2, 1.0])


def basis_4_45_corrected(r0: float, theta2: float) -> np.ndarray:
    """(4.45) with r0 s2 as seventh function (the 4 d2 r0 s2 term of (4.44))."""
    b = basis_4_45(r0, theta2)
    b[6] *= r0
    return b


def det_JJt_4_45(r0: float, theta2: float, lambdas) -> float:
    """det(J J^T) = lambda_1 r0^2 + lambda_2 r0^2 c2^2 + ... + lambda_7 s2 + lambda_8, Thesis (4.45) as printed."""
    return float(as_vector(lambdas, 8, "lambdas") @ basis_4_45(r0, theta2))


def lambdas_4_45_corrected(d) -> np.ndarray:
    """lambda_1..8 read off (4.44) for the corrected basis (lambda_7 multiplies r0 s2):
    (4, d2^2, 2 d2^2, d2^2 (4 + (d0 + d1)^2), -2 (d0 + d1) d2^2, 2 (d0 + d1) d2, 4 d2, 6 + 2 (d0 + d1)^2)."""
    d0, d1, d2, _ = _lengths(d)
    h = d0 + d1
    return np.array([4.0, d2**2, 2 * d2**2, d2**2 * (4 + h**2), -2 * h * d2**2, 2 * h * d2, 4 * d2, 6 + 2 * h**2])


def det_JJt_4_45_corrected(r0: float, theta2: float, d) -> float:
    """(4.45) with the basis of :func:`basis_4_45_corrected` and the lambda_j of (4.44)."""
    return float(lambdas_4_45_corrected(d) @ basis_4_45_corrected(r0, theta2))


def sol_4_46(theta2: float) -> float:
    """det(J J^T) at r0 = -0.04 as printed (numbers for d0 + d1 = 0.095, d2 = 0.18), Thesis (4.46)."""
    s, c = np.sin(theta2), np.cos(theta2)
    return float(1.2312e-04 * np.sin(2 * theta2) + 0.0342 * c - 0.0288 * s + 0.0649 * c**2 + 0.1299 * s**2 + 6.0244)


def sol_4_47(theta2: float) -> float:
    """det(J J^T) at r0 = 0 as printed, Thesis (4.47)."""
    s, c = np.sin(theta2), np.cos(theta2)
    return float(0.0342 * c + 0.0648 * c**2 + 0.1299 * s**2 + 6.0180)


def sol_4_48(theta2: float) -> float:
    """det(J J^T) at r0 = 0.04 as printed, Thesis (4.48)."""
    s, c = np.sin(theta2), np.cos(theta2)
    return float(0.0342 * c - 1.2312e-04 * np.sin(2 * theta2) + 0.0288 * s + 0.0649 * c**2 + 0.1299 * s**2 + 6.0244)


# =========================================================================== chapter 5
def link_jacobians_5_20(q_arm, d) -> tuple[np.ndarray, np.ndarray]:
    """(J_p^(ci), J_o^(ci)) for i = 1..3, each 3x3 in B axes w.r.t. q_arm, Thesis (5.16)-(5.21).

    Shapes (3, 3, 3): [link, row, joint].  Joint axes: x_B (prismatic), y_B (revolute).
    """
    _, t2, t3 = _arm(q_arm)
    _, _, d2, d3 = _lengths(d)
    s2, c2, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t2 + t3), np.cos(t2 + t3)
    Jp = np.zeros((3, 3, 3))
    Jp[:, 0, 0] = 1.0
    Jp[1, 0, 1], Jp[1, 2, 1] = d2 * c2 / 2, -d2 * s2 / 2
    Jp[2, 0, 1], Jp[2, 2, 1] = d2 * c2 + d3 * c23 / 2, -(d2 * s2 + d3 * s23 / 2)
    Jp[2, 0, 2], Jp[2, 2, 2] = d3 * c23 / 2, -d3 * s23 / 2
    Jo = np.zeros((3, 3, 3))
    Jo[1, 1, 1] = 1.0
    Jo[2, 1, 1] = Jo[2, 1, 2] = 1.0
    return Jp, Jo


def link_jacobians_5_20_frames(q_arm, d, index: str = "printed") -> tuple[np.ndarray, np.ndarray]:
    """(J_p^(ci), J_o^(ci)) built column by column from the thesis's own MDH frames, Thesis (5.20)-(5.21).

    The frames are those of Table 3.4 (corrected) after ^bT_0 (3.49); link centres of mass (3.78).
    ``index="printed"``: column j from z_{j-1} and p_{j-1}, as (5.20)-(5.21) print them (the index of
    the classical Denavit-Hartenberg convention); ``index="mdh"``: from z_j and p_j, the axis and origin
    of joint j in the modified (Khalil-Kleinfinger) frames of Sec. 3.2.2.3, which the thesis uses.
    With the printed index, joint 2's column is about z_1 = x_B, the slider axis.  Shapes as
    :func:`link_jacobians_5_20`: (3, 3, 3), [link, row, joint].
    """
    if index not in ("printed", "mdh"):
        raise InputError(f"index must be 'printed' (z_(j-1), p_(j-1)) or 'mdh' (z_j, p_j), got {index!r}")
    q = np.asarray(_arm(q_arm), dtype=float)
    base = T_b0_3_49()
    frames = [base, *chain_frames(table_3_4_corrected(d), q, base)]
    coms = link_coms_3_78(q, d)
    prismatic = (True, False, False)
    Jp, Jo = np.zeros((3, 3, 3)), np.zeros((3, 3, 3))
    for i in range(3):  # link i + 1 moves with joints 1 .. i + 1
        for j in range(i + 1):
            F = frames[j] if index == "printed" else frames[j + 1]
            z, p = F[:3, 2], F[:3, 3]
            if prismatic[j]:
                Jp[i, :, j] = z
            else:
                Jp[i, :, j] = np.cross(z, coms[i] - p)
                Jo[i, :, j] = z
    return Jp, Jo


def _link_inertias_in_B(q_arm, params: QPRRParams) -> list[np.ndarray]:
    """R_ci^b I_ci^i (R_ci^b)^T (5.12): link rotations I, Ry(theta2), Ry(theta2 + theta3)."""
    _, t2, t3 = _arm(q_arm)
    rots = (np.eye(3), rot_y(t2), rot_y(t2 + t3))
    return [R @ link.inertia_matrix() @ R.T for R, link in zip(rots, params.links)]


@dataclass(frozen=True)
class InertiaBlocks:
    """The 3x3 blocks of the 9x9 inertia matrix B of Thesis (5.25), Sec. 5.2.2."""

    B11: np.ndarray
    B12: np.ndarray
    B13: np.ndarray
    B22: np.ndarray
    B23: np.ndarray
    B33: np.ndarray

    def matrix(self) -> np.ndarray:
        """The assembled 9x9 B (B21 = B12^T, B31 = B13^T, B32 = B23^T)."""
        return np.block([[self.B11, self.B12, self.B13], [self.B12.T, self.B22, self.B23], [self.B13.T, self.B23.T, self.B33]])


def _blocks_common(xi, params: QPRRParams):
    xi = as_vector(xi, 9, "xi")
    Rb = rotation_3_4(*xi[3:6])
    T = T_3_25(xi[3], xi[4])
    d = d_lengths(params)
    coms = link_coms_3_78(xi[6:9], d)
    Jp, Jo = link_jacobians_5_20(xi[6:9], d)
    Ib = params.multirotor_inertia_matrix()
    Ic = _link_inertias_in_B(xi[6:9], params)
    return Rb, T, coms, Jp, Jo, Ib, Ic, _link_masses(params)


def B_blocks_5_2_2(xi, params: QPRRParams) -> InertiaBlocks:
    """B11..B33 as printed in Thesis Sec. 5.2.2, with the thesis's Q = R_b^T T (5.15).

    B22 and B23 use Q where T belongs, B23 has J_p^T where J_o belongs and the wrong sign
    on its mass term, B33 has the wrong sign on its mass term (see the ``_corrected`` form).
    """
    Rb, T, coms, Jp, Jo, Ib, Ic, m = _blocks_common(xi, params)
    Q = Rb.T @ T
    B11 = (params.multirotor_mass + m.sum()) * np.eye(3)
    B12 = -sum(mi * Rb @ _hat(p) @ T for mi, p in zip(m, coms))
    B13 = sum(mi * Rb @ J for mi, J in zip(m, Jp))
    B22 = Q.T @ Ib @ Q + sum(Q.T @ I @ Q - mi * T.T @ _hat(p) @ _hat(p) @ T for mi, p, I in zip(m, coms, Ic))
    B23 = -sum(mi * T.T @ _hat(p) @ J - Q.T @ I @ J.T for mi, p, J, I in zip(m, coms, Jp, Ic))
    B33 = -sum(mi * J.T @ J - O.T @ I @ O for mi, J, O, I in zip(m, Jp, Jo, Ic))
    return InertiaBlocks(B11, B12, B13, B22, B23, B33)


def B_blocks_5_2_2_corrected(xi, params: QPRRParams) -> InertiaBlocks:
    """Sec. 5.2.2 blocks derived from 1/2 m |v_ci|^2 + 1/2 omega_ci^T I_ci omega_ci with omega_b = T phi_dot (body):

    B22 = T^T (I_b + sum(R_ci I_ci R_ci^T - m_i hat(p_ci)^2)) T,
    B23 = sum(m_i T^T hat(p_ci) J_p + T^T R_ci I_ci R_ci^T J_o),
    B33 = sum(m_i J_p^T J_p + J_o^T R_ci I_ci R_ci^T J_o)  (= (5.54)).
    """
    Rb, T, coms, Jp, Jo, Ib, Ic, m = _blocks_common(xi, params)
    printed = B_blocks_5_2_2(xi, params)
    B22 = T.T @ (Ib + sum(I - mi * _hat(p) @ _hat(p) for mi, p, I in zip(m, coms, Ic))) @ T
    B23 = sum(mi * T.T @ _hat(p) @ J + T.T @ I @ O for mi, p, J, O, I in zip(m, coms, Jp, Jo, Ic))
    B33 = sum(mi * J.T @ J + O.T @ I @ O for mi, J, O, I in zip(m, Jp, Jo, Ic))
    return InertiaBlocks(printed.B11, printed.B12, printed.B13, B22, B23, B33)


def kinetic_multirotor_5_15(euler_zyx, euler_rates, params: QPRRParams) -> float:
    """Rotational kinetic energy of the multirotor 1/2 phi_dot^T Q^T I_b Q phi_dot, Q = R_b^T T, Thesis (5.14)-(5.15).

    Misprint: omega_b = T phi_dot is a body-frame rate (3.25), so the energy is
    1/2 phi_dot^T T^T I_b T phi_dot (:func:`kinetic_multirotor_5_15_corrected`).
    """
    f, t, s = as_vector(euler_zyx, 3, "euler_zyx")
    w = as_vector(euler_rates, 3, "euler_rates")
    Q = rotation_3_4(f, t, s).T @ T_3_25(f, t)
    return float(0.5 * w @ Q.T @ params.multirotor_inertia_matrix() @ Q @ w)


def kinetic_multirotor_5_15_corrected(euler_zyx, euler_rates, params: QPRRParams) -> float:
    """Thesis (5.15) corrected: 1/2 phi_dot^T T^T I_b T phi_dot (I_b in B axes, omega_body = T phi_dot)."""
    f, t, _ = as_vector(euler_zyx, 3, "euler_zyx")
    w = as_vector(euler_rates, 3, "euler_rates")
    T = T_3_25(f, t)
    return float(0.5 * w @ T.T @ params.multirotor_inertia_matrix() @ T @ w)


def potential_5_29(xi, params: QPRRParams) -> float:
    """U = m_b g e3^T p_b + sum m_ci g e3^T (p_b + R_b p_ci^b), Thesis (5.29) (z up)."""
    xi = as_vector(xi, 9, "xi")
    Rb = rotation_3_4(*xi[3:6])
    coms = link_coms_3_78(xi[6:9], d_lengths(params))
    m = _link_masses(params)
    g = params.g
    return float(params.multirotor_mass * g * xi[2] + sum(mi * g * (xi[2] + E3 @ Rb @ p) for mi, p in zip(m, coms)))


def R_Q_5_41(xi) -> np.ndarray:
    """R_Q = diag(R_b, R_b^T T, I3), Thesis (5.41) as printed.  Misprint: middle block must be T^T."""
    xi = as_vector(xi, 9, "xi")
    Rb = rotation_3_4(*xi[3:6])
    return _blockdiag(Rb, Rb.T @ T_3_25(xi[3], xi[4]), np.eye(3))


def R_Q_5_43(xi) -> np.ndarray:
    """R_Q = diag(R_b, R_b T, I3), Thesis (5.43) as printed (contradicts (5.41)).  Misprint: must be T^T."""
    xi = as_vector(xi, 9, "xi")
    Rb = rotation_3_4(*xi[3:6])
    return _blockdiag(Rb, Rb @ T_3_25(xi[3], xi[4]), np.eye(3))


def R_Q_corrected(xi) -> np.ndarray:
    """Thesis (5.41)/(5.43) corrected: R_Q = diag(R_b, T^T, I3), by virtual power u^T xi_dot = f_world . p_dot + tau_body . omega_body."""
    xi = as_vector(xi, 9, "xi")
    return _blockdiag(rotation_3_4(*xi[3:6]), T_3_25(xi[3], xi[4]).T, np.eye(3))


R_Q_5_41_corrected = R_Q_corrected
"""Alias: the corrected form of both (5.41) and (5.43)."""


def _blockdiag(*blocks) -> np.ndarray:
    n = sum(b.shape[0] for b in blocks)
    out = np.zeros((n, n))
    i = 0
    for b in blocks:
        k = b.shape[0]
        out[i : i + k, i : i + k] = b
        i += k
    return out


def N_5_46(l: float, c: float) -> np.ndarray:
    """N (9x7) = diag(Omega, I3) with Omega of (5.45), Thesis (5.46) as printed (yaw row c).

    Same misprint as (3.36): the yaw row multiplies forces and must be c/b.
    """
    N = np.zeros((9, 7))
    N[2:6, 0:4] = allocation_3_36(l, c)
    N[6:9, 4:7] = np.eye(3)
    return N


def N_5_46_corrected(l: float, b: float, c: float) -> np.ndarray:
    """(5.46) with the yaw row c/b."""
    return N_5_46(l, c / b)


# ------------------------------------------------------------ Sec. 5.5 fixed-base arm model
def _arm_consts(params: QPRRParams):
    m1, m2, m3 = _link_masses(params)
    _, _, d2, d3 = d_lengths(params)
    Ix2, Iy2, Iz2 = params.links[1].inertia[:3]
    Ix3, Iy3, Iz3 = params.links[2].inertia[:3]
    return m1, m2, m3, d2, d3, Iy2, Iz2, Ix3, Iy3, Iz3


def arm_B_5_54(q_arm, params: QPRRParams) -> np.ndarray:
    """B(q_eb) = sum m_ci J_p^T J_p + J_o^T R_i I_ci^i R_i^T J_o of the fixed-base arm, Thesis (5.54)."""
    Jp, Jo = link_jacobians_5_20(q_arm, d_lengths(params))
    Ic = _link_inertias_in_B(q_arm, params)
    return sum(mi * J.T @ J + O.T @ I @ O for mi, J, O, I in zip(_link_masses(params), Jp, Jo, Ic))


def arm_B_5_5(q_arm, params: QPRRParams) -> np.ndarray:
    """B(q_eb) (3x3) of the fixed-base arm, entries b_ij as printed in Thesis Sec. 5.5.

    b22 uses I_z2 (the joint-axis moment is I_y2) and b33 = I_y3 + I_z3 + m3 d3^2/4 +
    s23^2 (I_x3 - I_z3) has terms a rotation about a fixed y axis cannot produce.
    """
    _, t2, t3 = _arm(q_arm)
    m1, m2, m3, d2, d3, Iy2, Iz2, Ix3, Iy3, Iz3 = _arm_consts(params)
    c2, c3, c23, s23 = np.cos(t2), np.cos(t3), np.cos(t2 + t3), np.sin(t2 + t3)
    b11 = m1 + m2 + m3
    b12 = m3 * (d3 * c23 / 2 + d2 * c2) + m2 * d2 * c2 / 2
    b13 = d3 * m3 * c23 / 2
    b22 = Iy3 + Iz2 + m2 * d2**2 / 4 + m3 * d3**2 / 4 + m3 * d2**2 + d2 * d3 * m3 * c3
    b23 = Iy3 + m3 * d3**2 / 4 + d2 * d3 * m3 * c3 / 2
    b33 = Iy3 + Iz3 + m3 * d3**2 / 4 + s23**2 * (Ix3 - Iz3)
    return np.array([[b11, b12, b13], [b12, b22, b23], [b13, b23, b33]])


def arm_B_5_5_corrected(q_arm, params: QPRRParams) -> np.ndarray:
    """Sec. 5.5 B with b22 = I_y2 + I_y3 + m2 d2^2/4 + m3 (d2^2 + d3^2/4 + d2 d3 c3), b33 = I_y3 + m3 d3^2/4 (= (5.54))."""
    _, t2, t3 = _arm(q_arm)
    _, m2, m3, d2, d3, Iy2, _, _, Iy3, _ = _arm_consts(params)
    B = arm_B_5_5(q_arm, params)
    B[1, 1] = Iy2 + Iy3 + m2 * d2**2 / 4 + m3 * (d2**2 + d3**2 / 4 + d2 * d3 * np.cos(t3))
    B[2, 2] = Iy3 + m3 * d3**2 / 4
    return B


def arm_C_5_5(q_arm, q_arm_dot, params: QPRRParams) -> np.ndarray:
    """C(q_eb, q_eb_dot) (3x3), entries c_ij as printed in Thesis Sec. 5.5.1 (Christoffel of the printed B)."""
    _, t2, t3 = _arm(q_arm)
    _, w2, w3 = as_vector(q_arm_dot, 3, "q_arm_dot")
    _, m2, m3, d2, d3, _, _, Ix3, _, Iz3 = _arm_consts(params)
    s2, s3, s23, c23 = np.sin(t2), np.sin(t3), np.sin(t2 + t3), np.cos(t2 + t3)
    k = d2 * d3 * m3 * s3
    dI = Ix3 - Iz3
    c12 = -0.5 * (2 * m3 * (d3 * s23 / 2 + d2 * s2) + d2 * m2 * s2) * w2 - 0.5 * d3 * m3 * s23 * w3
    c13 = -0.5 * d3 * m3 * s23 * w2 - 0.5 * d3 * m3 * s23 * w3
    c22 = -0.5 * k * w3
    c23_ = -0.5 * k * w2 - 0.5 * (2 * s23 * c23 * dI + k) * w3
    c32 = 0.5 * k * w2 + c23 * s23 * dI * w3
    c33 = c23 * s23 * dI * w2 + c23 * s23 * dI * w3
    return np.array([[0.0, c12, c13], [0.0, c22, c23_], [0.0, c32, c33]])


def arm_C_5_5_corrected(q_arm, q_arm_dot, params: QPRRParams) -> np.ndarray:
    """Thesis 5.5.1 corrected: Christoffel matrix of the corrected B; the (I_x3 - I_z3) terms vanish,
    c23 = -(1/2) d2 d3 m3 s3 (theta2_dot + theta3_dot), c32 = (1/2) d2 d3 m3 s3 theta2_dot, c33 = 0."""
    _, _, t3 = _arm(q_arm)
    _, w2, w3 = as_vector(q_arm_dot, 3, "q_arm_dot")
    _, _, m3, d2, d3, _, _, _, _, _ = _arm_consts(params)
    k = d2 * d3 * m3 * np.sin(t3)
    C = arm_C_5_5(q_arm, q_arm_dot, params)
    C[1, 2] = -0.5 * k * (w2 + w3)
    C[2, 1] = 0.5 * k * w2
    C[2, 2] = 0.0
    return C


def arm_G_5_5(q_arm, params: QPRRParams) -> np.ndarray:
    """G(q_eb) of the fixed-base arm as printed, Thesis Sec. 5.5.2.

    Correct under the convention g0 = +g x_B in U = -sum m_i g0^T p_ci (gravity along the
    slider axis: the base pitched by +pi/2 so that x_B points down).
    """
    _, t2, t3 = _arm(q_arm)
    m1, m2, m3, d2, d3, *_ = _arm_consts(params)
    g = params.g
    c2, c23 = np.cos(t2), np.cos(t2 + t3)
    return np.array([-g * (m1 + m2 + m3), -g * (m3 * (d2 * c2 + d3 * c23 / 2) + d2 * m2 * c2 / 2), -g * (d3 * m3 * c23 / 2)])


def arm_u_5_5(q_arm, q_arm_dot, q_arm_ddot, params: QPRRParams) -> np.ndarray:
    """u(1), u(2), u(3) as printed, Thesis Sec. 5.5.3 (same gravity convention as the printed G).

    Misprints: u(1) halves the m3 part of the theta2_ddot coefficient; u(2) has m2 d2^2/2
    (b22 has /4), I_z2, and multiplies its third inertial term by theta3_dot instead of
    theta3_ddot; u(3) and u(2) carry the spurious (I_x3 - I_z3) terms of b33.
    """
    _, t2, t3 = _arm(q_arm)
    _, w2, w3 = as_vector(q_arm_dot, 3, "q_arm_dot")
    a1, a2, a3 = as_vector(q_arm_ddot, 3, "q_arm_ddot")
    m1, m2, m3, d2, d3, _, Iz2, Ix3, Iy3, Iz3 = _arm_consts(params)
    g = params.g
    s2, c2, s3, c3 = np.sin(t2), np.cos(t2), np.sin(t3), np.cos(t3)
    s23, c23 = np.sin(t2 + t3), np.cos(t2 + t3)
    S = np.sin(2 * t2 + 2 * t3)
    u1 = (
        (m1 + m2 + m3) * a1
        + 0.5 * (m3 * (d3 * c23 / 2 + d2 * c2) + d2 * m2 * c2) * a2
        + 0.5 * (d3 * m3 * c23) * a3
        - 0.5 * (2 * m3 * (d3 * s23 / 2 + d2 * s2) + d2 * m2 * s2) * w2**2
        - 0.5 * d3 * m3 * s23 * w3**2
        - d3 * m3 * s23 * w2 * w3
        - g * (m1 + m2 + m3)
    )
    u2 = (
        (m3 * (d3 * c23 / 2 + d2 * c2) + d2 * m2 * c2 / 2) * a1
        + (Iy3 + Iz2 + m2 * d2**2 / 2 + d2**2 * m3 + m3 * d3**2 / 4 + d2 * d3 * m3 * c3) * a2
        + (m3 * d3**2 / 4 + d2 * d3 * m3 * c3 / 2 + Iy3) * w3
        - 0.5 * (Ix3 * S - Iz3 * S + d2 * d3 * m3 * s3) * w3**2
        - d2 * d3 * m3 * s3 * w2 * w3
        - g * (m3 * (d3 * c23 / 2 + d2 * c2) + d2 * m2 * c2 / 2)
    )
    u3 = (
        d3 * m3 * c23 / 2 * a1
        + (Iy3 + m3 * d3**2 / 4 + d2 * d3 * m3 * c3 / 2) * a2
        + (Iy3 + Iz3 + m3 * d3**2 / 4 + Ix3 * s23**2 - Iz3 * s23**2) * a3
        + d2 * d3 * m3 * s3 * w2**2 / 2
        + 0.5 * (2 * Ix3 * c23 * s23 - 2 * Iz3 * c23 * s23) * w3**2
        + S * (Ix3 - Iz3) * w2 * w3
        - d3 * g * m3 * c23 / 2
    )
    return np.array([u1, u2, u3])


def arm_u_5_5_corrected(q_arm, q_arm_dot, q_arm_ddot, params: QPRRParams) -> np.ndarray:
    """u = B q_ddot + C q_dot + G with the corrected B and C of Sec. 5.5 and the printed G."""
    qd = as_vector(q_arm_dot, 3, "q_arm_dot")
    qdd = as_vector(q_arm_ddot, 3, "q_arm_ddot")
    return arm_B_5_5_corrected(q_arm, params) @ qdd + arm_C_5_5_corrected(q_arm, qd, params) @ qd + arm_G_5_5(q_arm, params)


# =========================================================================== chapter 6
# ------------------------------------------------------------ CoG motion, (6.29)-(6.35)
def p_c_6_29(p_b, R_b, p_cm) -> np.ndarray:
    """p_c = p_b + R_b p_cm: the system CoG in the world frame from its position p_cm in B [m], Thesis (6.29)."""
    R_b = check_rotation(R_b, "R_b", 1e-6)
    return as_vector(p_b, 3, "p_b") + np.asarray(R_b, dtype=float) @ as_vector(p_cm, 3, "p_cm")


def p_c_dot_6_29(p_b_dot, R_b, omega_b, p_cm, p_cm_dot) -> np.ndarray:
    """p_c_dot = p_b_dot + R_b (omega_b x p_cm + p_cm_dot) [m/s], the derivative of (6.29) printed under it.

    Holds with omega_b the BODY-frame rate T(phi_b) phi_b_dot of (3.25) (R_b_dot = R_b hat(omega_b));
    read as a world-frame rate (as (4.7) uses omega_b) it is wrong.
    """
    R_b = check_rotation(R_b, "R_b", 1e-6)
    R_b = np.asarray(R_b, dtype=float)
    w, p = as_vector(omega_b, 3, "omega_b"), as_vector(p_cm, 3, "p_cm")
    return as_vector(p_b_dot, 3, "p_b_dot") + R_b @ (np.cross(w, p) + as_vector(p_cm_dot, 3, "p_cm_dot"))


def com_6_30(q_arm, params: QPRRParams) -> np.ndarray:
    """[x_cm, y_cm, z_cm] in B as printed in Thesis (6.30a)-(6.30c) (no payload).

    x_cm and y_cm are those of (3.78).  z_cm fixes the (m2/2 + m3) d2 c2 term of (3.78) but
    keeps sum m_i (d0 + d1): link 1's CoM is at d0 + d1/2 (misprint, corrected form
    :func:`com_3_78_corrected`).
    """
    r0, t2, t3 = _arm(q_arm)
    d0, d1, d2, d3 = d_lengths(params)
    m1, m2, m3 = _link_masses(params)
    mG = params.total_mass
    x = ((m1 + m2 + m3) * r0 + (m2 / 2 + m3) * d2 * np.sin(t2) + m3 * d3 * np.sin(t2 + t3) / 2) / mG
    z = ((m1 + m2 + m3) * (d0 + d1) + (m2 / 2 + m3) * d2 * np.cos(t2) + m3 * d3 * np.cos(t2 + t3) / 2) / mG
    return np.array([x, 0.0, z])


def p_cm_prime_6_31(theta: float, p_cm) -> np.ndarray:
    """p'_cm = R_theta p_cm [m], Thesis (6.31): the CoG after a pitch theta, in axes that do not pitch.

    R_theta = Ry(theta), the pitch factor of (3.4); with phi = psi = 0 (Hypothesis 4 of
    Sec. 6.3.3) p'_cm is p_c - p_b of (6.29).
    """
    return rot_y(float(theta)) @ as_vector(p_cm, 3, "p_cm")


def nabla_p_cm_6_32(theta: float, p_cm) -> np.ndarray:
    """nabla p_cm = (R_theta - I) p_cm [m], Thesis (6.32): the displacement of (6.31)."""
    p = as_vector(p_cm, 3, "p_cm")
    return p_cm_prime_6_31(theta, p) - p


def theta_e_6_34(theta: float, theta2: float, theta3: float) -> float:
    """theta_e = theta + theta2 + theta3 [rad], Thesis (6.34), the end-effector pitch.

    Holds with phi = 0 and theta_e read as the angle of R_e = Rz(psi) Ry(theta_e) (the pitch
    about y), not the ZYZ theta_e of (3.64), which lies in [0, pi].
    """
    return float(theta) + float(theta2) + float(theta3)


def ipid_thesis_printed(
    F_est: float, y_ddot_ref: float, e: float, e_int: float, e_dot: float, alpha: float, kp: float, ki: float, kd: float
) -> float:
    """(6.37) exactly as printed: u = (F_est - y*_ddot - K_P e - K_I int e - K_D e_dot) / alpha (wrong sign, see module docstring)."""
    return (F_est - y_ddot_ref - kp * e - ki * e_int - kd * e_dot) / alpha


checked_module(globals())  # every formula refuses NaN, strings, complex, wrong types in its annotated arguments
