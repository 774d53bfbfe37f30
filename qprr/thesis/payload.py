"""Payload of the Q-PRR, Thesis Sec. 6.4.1-6.4.2: the printed closed forms and their corrections.

The generic, model-based forms (any platform) are in :mod:`qprr.payload`; each printed form here
is implemented as printed next to its corrected form, and ``tests/test_payload.py`` proves each
verdict (docs/thesis-errata.md).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..charts import rot_y
from ..errors import InputError
from ..validation import as_int, as_matrix, as_real, as_vector, checked_module
from .params import QPRRParams
from .printed import T_3_25, com_3_78_corrected, rotation_3_4


def _masses(**masses: float) -> None:
    """Masses [kg] of these formulas: link masses > 0, payload masses (m_cl, m_c) >= 0."""
    for name, m in masses.items():
        as_real(m, name, **({"nonnegative": True} if name in ("m_cl", "m_c") else {"positive": True}), unit="kg")


def link3_inertia_6_40(m3: float, I3, m_cl: float, x_cm: float, z_cm: float) -> tuple[float, np.ndarray]:
    """(m3', I3') as printed in Thesis (6.40): m3' = m3 + m_cl, I3' = I3 + m3' (x_cm^2 + z_cm^2).

    The scalar is read as added to every diagonal entry (the printed bold I3 plus a scalar).
    Misprint: a point mass m_cl at (x_cm, z_cm) from link 3's CoM adds m_cl (not m3') times the
    squared distance to the axis about link 3's CoM, and the reduced mass
    m3 m_cl / m3' about the combined CoM (:func:`combine_inertias`); and only the axis normal
    to the x-z plane (y, the joint axis) has x_cm^2 + z_cm^2 as squared distance.
    """
    _masses(m3=m3, m_cl=m_cl)
    I3 = as_matrix(I3, (3, 3), "I3")
    m3p = m3 + m_cl
    return m3p, np.asarray(I3, dtype=float) + m3p * (x_cm**2 + z_cm**2) * np.eye(3)


def system_inertia_6_41(m: float, I, m_cl: float, I_cl, x_cm: float, z_cm: float) -> tuple[float, np.ndarray]:
    """(m', I') as printed in Thesis (6.41): m' = m + m_cl, I' = I + I_cl + m_cl (x_cm^2 + z_cm^2).

    The scalar is added to every diagonal entry.  Correct for the yy entry about the OLD system
    CoM when (x_cm, z_cm) is the payload's offset from it; about the new CoM the factor is the
    reduced mass m m_cl / (m + m_cl), and the xx, zz entries need z_cm^2 and x_cm^2 alone, with
    a product term -m_cl x_cm z_cm off the diagonal (:func:`combine_inertias`).
    """
    _masses(m=m, m_cl=m_cl)
    I = as_matrix(I, (3, 3), "I")
    I_cl = as_matrix(I_cl, (3, 3), "I_cl")
    return m + m_cl, np.asarray(I, dtype=float) + np.asarray(I_cl, dtype=float) + m_cl * (x_cm**2 + z_cm**2) * np.eye(3)


def sphere_inertia_6_43(mass: float, radius: float, n: int = 64, corrected: bool = False) -> float:
    """Moment of inertia of a solid sphere by the triple integral of Thesis (6.43), Gauss-Legendre quadrature.

    As printed the integrand is rho r^2 dV (r^2: distance to the CENTRE), which gives
    3/5 m R^2, not the 2/5 m R^2 stated after it.  ``corrected=True`` integrates
    rho (r sin theta)^2 dV (distance to the z AXIS), which gives 2/5 m R^2.
    """
    _masses(mass=mass)
    as_real(radius, "radius", nonnegative=True, unit="m")
    as_int(n, "n", lo=2)
    if not (mass >= 0.0 and radius > 0.0):
        raise InputError(f"need mass >= 0 and radius > 0, got {mass!r}, {radius!r}")
    x, w = np.polynomial.legendre.leggauss(n)
    r, wr = 0.5 * radius * (x + 1.0), 0.5 * radius * w
    th, wt = 0.5 * math.pi * (x + 1.0), 0.5 * math.pi * w
    rho = mass / (4.0 / 3.0 * math.pi * radius**3)
    R, TH = np.meshgrid(r, th, indexing="ij")
    W = np.outer(wr, wt)
    lever2 = (R * np.sin(TH)) ** 2 if corrected else R**2
    dV = R**2 * np.sin(TH)  # r^2 sin(theta) dr dtheta dphi, phi integrated analytically (2 pi)
    return float(rho * 2.0 * math.pi * np.sum(W * lever2 * dV))


def com_6_42(q_arm, params: QPRRParams, m_cl: float) -> np.ndarray:
    """[x_cm, 0, z_cm] of the system with a payload m_cl at the end effector, Thesis (6.42) as printed.

    m_G is read as params.total_mass + m_cl.  Misprint: the payload term is m_cl d3 s23
    (m_cl d3 c23) where the payload at p_eb (3.58) needs m_cl (r0 + d2 s2 + d3 s23)
    (m_cl (d0 + d1 + d2 c2 + d3 c23)); z_cm also keeps the m1 (d0 + d1) of (3.78), where link
    1's CoM is at d0 + d1/2.  Corrected forms: :func:`com_6_42_corrected` (closed form) and
    :func:`com_with_payload` (Pinocchio).
    """
    _masses(m_cl=m_cl)
    r0, t2, t3 = as_vector(q_arm, 3, "q_arm")
    m1, m2, m3 = (link.mass for link in params.links)
    d0, d1, d2, d3 = params.d0, params.d1, params.d2, params.d3
    mG = params.total_mass + m_cl
    s2, c2, s23, c23 = math.sin(t2), math.cos(t2), math.sin(t2 + t3), math.cos(t2 + t3)
    x = ((m1 + m2 + m3) * r0 + (m2 / 2 + m3) * d2 * s2 + m3 * d3 * s23 / 2 + m_cl * d3 * s23) / mG
    z = ((m1 + m2 + m3) * (d0 + d1) + (m2 / 2 + m3) * d2 * c2 + m3 * d3 * c23 / 2 + m_cl * d3 * c23) / mG
    return np.array([x, 0.0, z])


def com_6_42_corrected(q_arm, params: QPRRParams, m_cl: float) -> np.ndarray:
    """(6.42) corrected: [m_G p_cm (3.78 corrected) + m_cl p_eb (3.58)] / (m_G + m_cl), payload at the end effector."""
    _masses(m_cl=m_cl)
    r0, t2, t3 = as_vector(q_arm, 3, "q_arm")
    d0, d1, d2, d3 = params.d0, params.d1, params.d2, params.d3
    p_eb = np.array([r0 + d2 * math.sin(t2) + d3 * math.sin(t2 + t3), 0.0, d0 + d1 + d2 * math.cos(t2) + d3 * math.cos(t2 + t3)])
    mG = params.total_mass
    return (mG * com_3_78_corrected((r0, t2, t3), params) + m_cl * p_eb) / (mG + m_cl)


def holding_torques_6_4_1(params: QPRRParams, m_cl: float) -> tuple[float, float]:
    """(tau_theta2, tau_theta3) as printed in Sec. 6.4.1.1: ((d2 m2/2 + m3 + m_cl) g, (d3 m3/2 + m_cl) g).

    Dimensionally inconsistent: each sum adds kg m to kg, so the value is not a torque (it
    does not scale linearly with the length unit).  Corrected: :func:`holding_torques_corrected`.
    """
    _masses(m_cl=m_cl)
    _, m2, m3 = (link.mass for link in params.links)
    g = params.g
    return (params.d2 * m2 / 2 + m3 + m_cl) * g, (params.d3 * m3 / 2 + m_cl) * g


def holding_torques_corrected(q_arm, params: QPRRParams, m_cl: float) -> np.ndarray:
    """Thesis 6.4.1.1 corrected: efforts holding the arm and a point payload m_cl at the tip, body level (Hypothesis 1).

    u_theta2 = -g [(m2/2 + m3 + m_cl) d2 s2 + (m3/2 + m_cl) d3 s23],
    u_theta3 = -g (m3/2 + m_cl) d3 s23, u_r0 = 0 (the slider is horizontal).
    Largest magnitudes, with both links horizontal (s2 = s23 = 1):
    |u_theta2| = g [(m2/2 + m3 + m_cl) d2 + (m3/2 + m_cl) d3], |u_theta3| = g (m3/2 + m_cl) d3.
    The printed tau_theta2 read as (m2/2 + m3 + m_cl) d2 g is the case link 2 horizontal,
    link 3 vertical (s23 = 0).
    """
    _masses(m_cl=m_cl)
    _, t2, t3 = as_vector(q_arm, 3, "q_arm")
    _, m2, m3 = (link.mass for link in params.links)
    g, d2, d3 = params.g, params.d2, params.d3
    s2, s23 = math.sin(t2), math.sin(t2 + t3)
    return np.array([0.0, -g * ((m2 / 2 + m3 + m_cl) * d2 * s2 + (m3 / 2 + m_cl) * d3 * s23), -g * (m3 / 2 + m_cl) * d3 * s23])


def G_c_6_52(xi, m_c: float, d, g: float) -> np.ndarray:
    """G_c as printed in Thesis (6.52) (point payload at the end effector).

    Printed form is d(m_c g y_e)/dxi (gravity along world y) with two more misprints: d2
    where d3 belongs in the s23 terms of rows 5-6 and a spurious 1/2 in row 9.  With gravity
    along -z (5.29) the correct vector is m_c g d z_e / d xi (:func:`payload_terms_closed_form`).
    """
    _masses(m_c=m_c)
    as_real(g, "g", positive=True, unit="m/s^2")
    xi = as_vector(xi, 9, "xi")
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    _, _, _, f, t, s, r0, t2, t3 = xi
    sf, cf, st, ct, ss, cs = math.sin(f), math.cos(f), math.sin(t), math.cos(t), math.sin(s), math.cos(s)
    s2, c2, s23, c23 = math.sin(t2), math.cos(t2), math.sin(t2 + t3), math.cos(t2 + t3)
    pz = d0 + d1 + c2 * d2 + c23 * d3
    px_printed = r0 + s2 * d2 + s23 * d2
    mg = m_c * g
    return np.array(
        [
            0.0,
            mg,
            0.0,
            -mg * (cf * cs + sf * ss * st) * pz,
            -mg * (ss * st * px_printed - cf * ct * ss * pz),
            mg * ((sf * ss + cf * cs * st) * pz + cs * ct * px_printed),
            mg * ct * ss,
            mg * ((cs * sf - cf * ss * st) * (s2 * d2 + s23 * d3) + ct * ss * (c2 * d2 + c23 * d3)),
            0.5 * mg * d3 * (s23 * (cs * sf - cf * ss * st) + ct * ss * c23),
        ]
    )


def B_c_6_51(xi, m_c: float, I_c, d, corrected: bool = False) -> np.ndarray:
    """B_c as printed in Thesis (6.51), point payload at the end effector with inertia I_c (payload axes = link 3).

    Read as (6.51) itself implies: Q = R_b^T T(phi_b) maps the Euler rates to the body rate, so the
    T(phi_b) of (6.51) is the world-frame map T_w = R_b T (omega_world = T_w phi_dot, with T of
    (3.25), omega_body = T phi_dot) and Q is (3.25)'s T; R_c^b = Ry(theta2 + theta3).  Then B12c
    (-m_c (R_b p_c)^ T_w = -m_c R_b p_c^ Q) and B23c hold exactly; B22c alone is misprinted: its
    first term ends in R_b where T_w belongs (the printed block is not even symmetric).
    ``corrected=True`` (body-frame p_c, T of (3.25)): B12c = -m_c R_b p_c^ T, B22c = T^T (m_c p_c^T^
    p_c^ + R_c I_c R_c^T) T, B23c = T^T (m_c p_c^ j_Pc + R_c I_c R_c^T j_Oc); B11c, B13c, B33c as
    printed.  Model-based form: :func:`payload_terms_closed_form`.
    """
    _masses(m_c=m_c)
    I_c = as_matrix(I_c, (3, 3), "I_c")
    xi = as_vector(xi, 9, "xi")
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    Ic = np.asarray(I_c, dtype=float).reshape(3, 3)
    f, t, s, r0, t2, t3 = xi[3:9]
    Rb = rotation_3_4(f, t, s)
    T = T_3_25(f, t)  # body rate map (3.25); (6.51)'s T(phi_b) is the world one, R_b T, and its Q = R_b^T T_w is T
    Tw, Q = Rb @ T, T
    s2, c2, s23, c23 = math.sin(t2), math.cos(t2), math.sin(t2 + t3), math.cos(t2 + t3)
    p_c = np.array([r0 + d2 * s2 + d3 * s23, 0.0, d0 + d1 + d2 * c2 + d3 * c23])
    p1 = np.array([r0, 0.0, d0 + d1])
    p2 = np.array([r0 + d2 * s2, 0.0, d0 + d1 + d2 * c2])
    z = np.array([0.0, 1.0, 0.0])
    jP = np.column_stack([[1.0, 0.0, 0.0], np.cross(z, p_c - p1), np.cross(z, p_c - p2)])
    jO = np.column_stack([np.zeros(3), z, z])
    Rc = rot_y(t2 + t3)
    Icb = Rc @ Ic @ Rc.T
    hat = pin.skew(Rb @ p_c)
    B11 = m_c * np.eye(3)
    B13 = m_c * Rb @ jP
    B33 = m_c * jP.T @ jP + jO.T @ Icb @ jO
    if corrected:
        ph = pin.skew(p_c)
        B12 = -m_c * Rb @ ph @ T
        B22 = T.T @ (m_c * ph.T @ ph + Icb) @ T
        B23 = T.T @ (m_c * ph @ jP + Icb @ jO)
    else:
        B12 = -m_c * hat @ Tw
        B22 = m_c * Tw.T @ hat.T @ hat @ Rb + Q.T @ Icb @ Q
        B23 = Q.T @ Icb @ jO - m_c * Tw.T @ hat.T @ Rb @ jP
    return np.block([[B11, B12, B13], [B12.T, B22, B23], [B13.T, B23.T, B33]])


checked_module(globals())  # every formula refuses NaN, strings, complex, wrong types in its annotated arguments
