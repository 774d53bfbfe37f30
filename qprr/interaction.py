"""Interaction with the environment at the end effector, Thesis Sec. 6.4.3.

* :func:`generalized_wrench_xi`: u_e(h) of Thesis (6.58)-(6.59), the generalised force in
  thesis coordinates of a wrench h = [f; mu] (world axes) applied at the end-effector origin,
  u_e = S^T J_e^T h; :func:`generalized_wrench_6_59` is the printed block form.
* Contact models, usable as the simulator's ``external_wrench`` hook (``h = env(t, q, v)``,
  world axes, at the end effector) and as force sensors for the controllers
  (:meth:`measured`):

  - :class:`PushedMass`: a point object on a straight line, pushed through a unilateral
    compliant contact (spring k, damper d, force never negative), with optional Coulomb
    friction on the line;
  - :class:`CompliantWall`: a fixed unilateral compliant plane;
  - :class:`PrescribedWrench`: a wrench given as a function of time (Sec. 6.4.3.4's h).

  The contact models carry their own state, integrated with the simulator's zero-order
  hold: the call at t_k first advances the object from t_(k-1) to t_k under the force of
  t_(k-1) (semi-implicit Euler, the simulator's default), then returns the force at t_k.
  Every call is logged (:meth:`history`).
* :func:`push_model_6_66` / :func:`push_model`: the planar reduced model of pushing with the
  thrust (Thesis (6.66)), printed and corrected.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from . import coordinates as co
from .coordinates import as_vector
from .errors import InputError
from .model import Robot


# ===================================================================== (6.58)-(6.59): u_e(h)
def generalized_wrench_xi(robot: Robot, data: pin.Data, xi, h_world) -> np.ndarray:
    """u_e(h) (9,) of Thesis (6.58): u_e = S(xi)^T J_e(q)^T h, h = [f; mu] in world axes at the end-effector origin.

    Block form (corrected (6.59)), with p_eb and J_eb in B and T of (3.25) (omega_body = T phi_dot):
    u_e,f = h_f;  u_e,tau = T^T (p_eb^ R_b^T h_f + R_b^T h_tau);  u_e,mu = J_eb,P^T R_b^T h_f + J_eb,O^T R_b^T h_tau.
    """
    xi = as_vector(xi, 9, "xi")
    h = as_vector(h_world, 6, "h_world")
    q = co.xi_to_q(xi)
    J = pin.computeFrameJacobian(robot.model, data, q, robot.ee_frame, pin.LOCAL_WORLD_ALIGNED)
    return co.rate_map(xi).T @ (J.T @ h)


def generalized_wrench_blocks(xi, h_world, d) -> np.ndarray:
    """The corrected block form of (6.59) in closed form (docstring of :func:`generalized_wrench_xi`)."""
    from .thesis import T_3_25, J_eb_4_26, rotation_3_4

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
    from .thesis import T_3_25, J_eb_4_26

    xi = as_vector(xi, 9, "xi")
    h = as_vector(h, 6, "h")
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    T = T_3_25(xi[3], xi[4])
    r0, t2, t3 = xi[6:9]
    p_eb = np.array([r0 + d2 * math.sin(t2) + d3 * math.sin(t2 + t3), 0.0, d0 + d1 + d2 * math.cos(t2) + d3 * math.cos(t2 + t3)])
    Jeb = J_eb_4_26(xi[6:9], (d0, d1, d2, d3))
    return np.concatenate([h[0:3], T.T @ pin.skew(p_eb) @ h[0:3] + T.T @ h[3:6], Jeb[0:3].T @ h[0:3] + Jeb[3:6].T @ h[3:6]])


# ======================================================================= contact models
@dataclass(frozen=True)
class ContactHistory:
    """Log of a contact model, one row per simulator step.

    ``t`` [s]; ``force`` (n,) normal force the environment exerts on the end effector along
    -normal [N] (>= 0); ``wrench`` (n, 6) world wrench on the end effector; ``position``,
    ``velocity`` (n,) object coordinate along its line [m, m/s] (zeros for a wall);
    ``penetration`` (n,) [m] (> 0 in contact).
    """

    t: np.ndarray
    force: np.ndarray
    wrench: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    penetration: np.ndarray


class _Contact:
    """Shared machinery: end-effector kinematics, time bookkeeping, log."""

    def __init__(self, robot: Robot, normal, stiffness: float, damping: float) -> None:
        n = as_vector(normal, 3, "normal")
        norm = float(np.linalg.norm(n))
        if norm < 1e-12:
            raise InputError(f"normal must be a non-zero vector, got {n.tolist()}")
        if not (np.isfinite(stiffness) and stiffness > 0.0):
            raise InputError(f"stiffness must be > 0 N/m, got {stiffness!r}")
        if not (np.isfinite(damping) and damping >= 0.0):
            raise InputError(f"damping must be >= 0 N s/m, got {damping!r}")
        self.robot = robot
        self.normal = n / norm
        self.k = float(stiffness)
        self.d = float(damping)
        self._data = robot.model.createData()
        self.reset()

    def reset(self) -> None:
        """Back to the initial state, empty log (call before reusing the object for a new run)."""
        self._t = None
        self._force = 0.0
        self._h = np.zeros(6)
        self._log: list[tuple] = []

    def _ee(self, q, v) -> tuple[np.ndarray, np.ndarray]:
        model, data = self.robot.model, self._data
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacement(model, data, self.robot.ee_frame)
        p = data.oMf[self.robot.ee_frame].translation.copy()
        vel = pin.getFrameVelocity(model, data, self.robot.ee_frame, pin.LOCAL_WORLD_ALIGNED).linear.copy()
        return p, vel

    def _advance(self, dt: float) -> None:
        """Integrate the object's own state over dt under the held force (default: nothing moves)."""

    def _gap(self, p_e: np.ndarray, v_e: np.ndarray) -> tuple[float, float]:
        raise NotImplementedError

    def _coordinates(self) -> tuple[float, float]:
        return 0.0, 0.0

    def __call__(self, t: float, q, v) -> np.ndarray:
        """World wrench on the end effector at time ``t`` (the simulator's ``external_wrench`` hook)."""
        if self._t is not None:
            if t < self._t - 1e-12:
                raise InputError(f"contact model called at t = {t!r} after t = {self._t!r}: it is stateful, call reset() before a new run")
            if abs(t - self._t) <= 1e-12:
                return self._h.copy()
            self._advance(t - self._t)
        self._t = float(t)
        p_e, v_e = self._ee(q, v)
        pen, pen_dot = self._gap(p_e, v_e)
        F = 0.0
        if pen > 0.0:
            F = max(0.0, self.k * pen + self.d * pen_dot)  # unilateral: the damper never pulls
        self._force = F
        self._h = np.zeros(6)
        self._h[0:3] = -F * self.normal
        s, sd = self._coordinates()
        self._log.append((self._t, F, s, sd, pen))
        return self._h.copy()

    def measured(self, t: float | None = None) -> np.ndarray:
        """Last wrench computed (world, on the end effector): what a wrist force sensor reads, one step late in the loop."""
        return self._h.copy()

    def history(self) -> ContactHistory:
        if not self._log:
            z = np.zeros(0)
            return ContactHistory(z, z, np.zeros((0, 6)), z, z, z)
        a = np.array(self._log)
        wrench = -a[:, 1:2] * self.normal[None, :]
        return ContactHistory(a[:, 0], a[:, 1], np.hstack([wrench, np.zeros((a.shape[0], 3))]), a[:, 2], a[:, 3], a[:, 4])


class PushedMass(_Contact):
    """A point object of mass ``mass`` sliding on a straight line, pushed by the end effector.

    The line passes through ``origin`` (world) along the unit ``direction`` (also the
    contact normal); the object's face is at origin + s direction.  Penetration
    delta = direction . (p_e - origin) - s; in contact (delta > 0) the force on the object is
    F = max(0, k delta + d delta_dot) along +direction, and -F direction on the end effector.
    The object obeys m s_ddot = F - Coulomb friction (coefficient ``friction``, normal force
    m g): it sticks while F <= mu m g.  Semi-implicit Euler with the simulator's step.
    """

    def __init__(self, robot: Robot, *, mass: float, origin, direction=(1.0, 0.0, 0.0), position: float = 0.0,
                 velocity: float = 0.0, stiffness: float = 500.0, damping: float = 20.0, friction: float = 0.0,
                 g: float | None = None) -> None:
        if not (np.isfinite(mass) and mass > 0.0):
            raise InputError(f"mass must be > 0 kg, got {mass!r}")
        if not (np.isfinite(friction) and friction >= 0.0):
            raise InputError(f"friction must be >= 0, got {friction!r}")
        self.mass = float(mass)
        self.origin = as_vector(origin, 3, "origin").copy()
        self.s0, self.sd0 = float(position), float(velocity)
        self.mu = float(friction)
        self.g = robot.params.g if g is None else float(g)
        super().__init__(robot, direction, stiffness, damping)

    def reset(self) -> None:
        super().reset()
        self.s, self.sd = self.s0, self.sd0

    def _gap(self, p_e, v_e):
        n = self.normal
        return float(n @ (p_e - self.origin)) - self.s, float(n @ v_e) - self.sd

    def _coordinates(self):
        return self.s, self.sd

    def _advance(self, dt: float) -> None:
        F, m = self._force, self.mass
        v_trial = self.sd + dt * F / m
        dv_fric = dt * self.mu * self.g
        if abs(v_trial) <= dv_fric:
            self.sd = 0.0  # static friction holds the object (stick)
        else:
            self.sd = v_trial - math.copysign(dv_fric, v_trial)
        self.s += dt * self.sd


class CompliantWall(_Contact):
    """A fixed plane through ``point`` with outward unit ``normal`` (towards the robot): F = max(0, k delta + d delta_dot),
    delta = -normal . (p_e - point) > 0 when the end effector is inside."""

    def __init__(self, robot: Robot, *, point, normal, stiffness: float = 2000.0, damping: float = 20.0) -> None:
        self.point = as_vector(point, 3, "point").copy()
        super().__init__(robot, -as_vector(normal, 3, "normal"), stiffness, damping)

    def _gap(self, p_e, v_e):
        n = self.normal  # points into the wall
        return float(n @ (p_e - self.point)), float(n @ v_e)


class PrescribedWrench:
    """A world wrench on the end effector given in time: h(t) = ``wrench`` for t_on <= t < t_off, else 0.

    ``wrench`` is a 6-vector or a callable t -> 6-vector.  Also a perfect sensor (:meth:`measured`).
    """

    def __init__(self, wrench, t_on: float = 0.0, t_off: float = math.inf) -> None:
        if not (t_off > t_on):
            raise InputError(f"need t_on < t_off, got {t_on!r}, {t_off!r}")
        self._fn: Callable[[float], np.ndarray]
        if callable(wrench):
            self._fn = lambda t: as_vector(wrench(t), 6, "wrench(t)")
        else:
            w = as_vector(wrench, 6, "wrench").copy()
            self._fn = lambda t: w
        self.t_on, self.t_off = float(t_on), float(t_off)

    def measured(self, t: float) -> np.ndarray:
        return self._fn(t).copy() if self.t_on <= t < self.t_off else np.zeros(6)

    def __call__(self, t: float, q=None, v=None) -> np.ndarray:
        return self.measured(t)


# ================================================================ (6.66): pushing with thrust
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


def push_model(theta: float, T1: float, T3: float, F_oj: float, M_G: float, I_yy: float, l: float,
               contact_b, com_b=(0.0, 0.0, 0.0)) -> PushState:
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
