"""Interaction with the environment at the end effector of the Q-PRR, Thesis Sec. 6.4.3: printed forms and corrections.

* (6.58)-(6.59): the generalised force u_e(h) of a wrench at the end effector; the generic form
  is :func:`qprr.actuation.generalized_wrench_xi` (u_e = S^T J_e^T h, any platform), the closed
  block forms below are the thesis's, printed (:func:`generalized_wrench_6_59`) and corrected
  (:func:`generalized_wrench_blocks`);
* (6.66): the planar reduced model of pushing with the thrust, printed (:func:`push_model_6_66`)
  and corrected (:func:`push_model`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..validation import as_vector, checked_module
from .printed import T_3_25, J_eb_4_26, rotation_3_4


def generalized_wrench_blocks(xi, h_world, d) -> np.ndarray:
    """The corrected block form of (6.59) in closed form (docstring of :func:`generalized_wrench_xi`)."""
    xi = as_vector(xi, 9, "xi")
    h = as_vector(h_world, 6, "h_world")
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    Rb = rotation_3_4(*xi[3:6])
    T = T_3_25(xi[3], xi[4])
    r0, t2, t3 = xi[6:9]
    p_eb = np.array([r0 + d2 * math.sin(t2) + d3 * math.sin(t2 + t3), 0.0, d0 + d1 + d2 * math.cos(t2) + d3 * math.cos(t2 + t3)])
    Jeb = J_eb_4_26(xi[6:9], (d0, d1, d2, d3))
    fb, mb = Rb.T @ h[0:3], Rb.T @ h[3:6]
    return np.concatenate([h[0:3], T.T @ (pin.skew(p_eb) @ fb + mb), Jeb[0:3].T @ fb + Jeb[3:6].T @ mb])


def generalized_wrench_6_59(xi, h, d) -> np.ndarray:
    """u_e of Thesis (6.59) as printed: [I 0; T^T p_eb^ T^T; J_ebP^T J_ebO^T] h (one h for all rows).

    Consistent only at level attitude (R_b = I): the first row needs h_f in world axes, the
    other rows need it in B.  Corrected form: :func:`generalized_wrench_blocks`.
    """
    xi = as_vector(xi, 9, "xi")
    h = as_vector(h, 6, "h")
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    T = T_3_25(xi[3], xi[4])
    r0, t2, t3 = xi[6:9]
    p_eb = np.array([r0 + d2 * math.sin(t2) + d3 * math.sin(t2 + t3), 0.0, d0 + d1 + d2 * math.cos(t2) + d3 * math.cos(t2 + t3)])
    Jeb = J_eb_4_26(xi[6:9], (d0, d1, d2, d3))
    return np.concatenate([h[0:3], T.T @ pin.skew(p_eb) @ h[0:3] + T.T @ h[3:6], Jeb[0:3].T @ h[0:3] + Jeb[3:6].T @ h[3:6]])


@dataclass(frozen=True)
class PushState:
    """Derivative of the planar push model's state [x, x_dot, theta, theta_dot]."""

    x_ddot: float
    theta_ddot: float


def push_model_6_66(theta: float, T1: float, T3: float, F_oj: float, M_G: float, I_yy: float, L: float, p_cb_z: float) -> PushState:
    """Thesis (6.66) as printed: x_ddot = -F/M_G + sin(theta)/M_G (T1 + T3),
    theta_ddot = F p_cb^T e3 / I_yy + L/(2 I_yy) (T3 - T1).

    With the "+" rotor numbering of (3.36) (pitch torque l (f1 - f3)) and z up, the rotor
    term has the wrong sign, and the contact term is the moment for a z-down p_cb
    (arm hanging below the CoG): :func:`push_model`.
    """
    return PushState((-F_oj + math.sin(theta) * (T1 + T3)) / M_G, (F_oj * p_cb_z + 0.5 * L * (T3 - T1)) / I_yy)


def push_model(theta: float, T1: float, T3: float, F_oj: float, M_G: float, I_yy: float, l: float, contact_b, com_b=(0.0, 0.0, 0.0)) -> PushState:
    """Thesis (6.66) corrected: planar model of pushing along world x with the thrust, arm locked (z up, "+" rotors).

    Rotors 1 (at -l x_B) and 3 (at +l x_B) give the thrust T1 + T3 along z_B (rotors 2, 4 off or
    balanced), the object pushes back with F_oj along -x (world) at the contact point
    ``contact_b`` (in B); ``com_b`` is the CoG in B (x_cm, z_cm).  For the CoG:
    x_G_ddot = (sin(theta) (T1 + T3) - F_oj) / M_G,
    theta_ddot = [l (T1 - T3) + x_cm (T1 + T3) - F_oj (cos(theta) z_c - sin(theta) x_c)] / I_yy,
    with (x_c, z_c) = contact_b - com_b and I_yy about the CoG (at rest, no coupling with roll/yaw).
    """
    c = as_vector(contact_b, 3, "contact_b") - as_vector(com_b, 3, "com_b")
    x_cm = float(as_vector(com_b, 3, "com_b")[0])
    st, ct = math.sin(theta), math.cos(theta)
    moment = l * (T1 - T3) + x_cm * (T1 + T3) - F_oj * (ct * c[2] - st * c[0])
    return PushState((st * (T1 + T3) - F_oj) / M_G, moment / I_yy)


checked_module(globals())  # every formula refuses NaN, strings, complex, wrong types in its annotated arguments
