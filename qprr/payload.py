"""Payload carried at the end effector: models, holding efforts, capacity, the split B + B_c, mass estimate.

Thesis Sec. 6.4.1-6.4.2.  A payload is a rigid body attached to link 3 (the end effector's
parent joint): mass m_c, centre of mass ``com_ee`` in the end-effector frame, rotational
inertia I_c about its CoM (zero for a point mass).

* Known mass, Thesis (6.40)/(6.41): :func:`with_payload` returns a copy of the robot whose
  link-3 spatial inertia is nominal + payload (``pin.Inertia.__add__``); ``approach="link3"``
  folds a point mass into link 3 as (6.40) does, ``approach="body"`` adds the payload as a
  rigid body with its own inertia I_cl as (6.41) does.  :class:`PayloadModel` does the same
  at run time on a model copy it owns.
* Holding efforts and capacity, Sec. 6.4.1.1: :func:`holding_efforts`, :func:`payload_capacity`.
* Unknown mass, Thesis (6.49)-(6.53): :func:`payload_terms_xi` gives B_c, C_c, G_c as the
  difference between the dynamics with and without the payload; :func:`payload_terms_closed_form`
  gives B_c = m_c J_P^T J_P + J_O^T R_c I_c R_c^T J_O and G_c = m_c g J_P,z (the corrected
  (6.51), (6.52)).
* :class:`MassEstimator`: exponentially weighted least squares on the joint-torque residual.

The printed closed forms of the section are kept as ``*_6_xx`` functions (implemented as
printed) next to their corrected forms; ``tests/test_payload.py`` proves each verdict.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from . import coordinates as co
from .coordinates import as_vector
from .errors import InputError, UnknownNameError
from .model import Robot, dynamics_xi
from .params import QPRRParams

APPROACHES = ("link3", "body")
"""Known-mass models: "link3" = point mass folded into link 3 (Thesis (6.40)); "body" = rigid
body with its own inertia (Thesis (6.41))."""

MISSIONS = ("transport", "manipulation")
"""Payload-capacity missions of Thesis Sec. 6.4.1.1."""


# ==================================================================================== payload
@dataclass(frozen=True)
class Payload:
    """A payload rigidly held by the end effector.

    ``mass`` [kg]; ``com_ee`` its centre of mass in the end-effector frame [m];
    ``inertia`` = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) about its CoM in end-effector axes [kg m^2]
    (zeros: a point mass, the assumption of (6.40) and (6.44)).
    """

    mass: float
    com_ee: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[float, float, float, float, float, float] = (0.0,) * 6

    def __post_init__(self) -> None:
        if not (np.isfinite(self.mass) and self.mass >= 0.0):
            raise InputError(f"payload mass must be a finite number >= 0 kg, got {self.mass!r}")
        as_vector(self.com_ee, 3, "com_ee")
        as_vector(self.inertia, 6, "inertia")
        if np.any(np.linalg.eigvalsh(self.inertia_matrix()) < -1e-15):
            raise InputError(f"payload inertia must be positive semi-definite, got {self.inertia!r}")

    @classmethod
    def sphere(cls, mass: float, radius: float, com_ee=(0.0, 0.0, 0.0)) -> Payload:
        """Solid homogeneous sphere: I_xx = I_yy = I_zz = 2/5 m R^2 (the result stated after Thesis (6.43))."""
        if not (np.isfinite(radius) and radius >= 0.0):
            raise InputError(f"sphere radius must be a finite number >= 0 m, got {radius!r}")
        i = 0.4 * mass * radius * radius
        return cls(mass, tuple(float(x) for x in as_vector(com_ee, 3, "com_ee")), (i, i, i, 0.0, 0.0, 0.0))

    def inertia_matrix(self) -> np.ndarray:
        """I_c (3x3) about the payload CoM, end-effector axes (Thesis (6.47))."""
        ixx, iyy, izz, ixy, ixz, iyz = self.inertia
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)

    def spatial_inertia_ee(self, approach: str = "body") -> pin.Inertia:
        """Spatial inertia in the end-effector frame; ``approach="link3"`` drops I_c (point mass, (6.40))."""
        _check_approach(approach)
        I = self.inertia_matrix() if approach == "body" else np.zeros((3, 3))
        return pin.Inertia(float(self.mass), np.asarray(self.com_ee, dtype=float), I)


def _check_approach(approach: str) -> None:
    if approach not in APPROACHES:
        raise UnknownNameError("payload approach", approach, APPROACHES)


def _as_payload(payload: Payload | float) -> Payload:
    if isinstance(payload, Payload):
        return payload
    try:
        return Payload(float(payload))
    except (TypeError, ValueError) as exc:
        raise InputError(f"payload must be a Payload or a mass in kg, got {payload!r}") from exc


def payload_joint_inertia(robot: Robot, payload: Payload | float, approach: str = "body") -> tuple[int, pin.Inertia]:
    """(joint id, spatial inertia of the payload expressed in that joint's frame): what is added to link 3."""
    payload = _as_payload(payload)
    frame = robot.model.frames[robot.ee_frame]
    return int(frame.parentJoint), frame.placement.act(payload.spatial_inertia_ee(approach))


def with_payload(robot: Robot, payload: Payload | float, approach: str = "body") -> Robot:
    """A copy of ``robot`` carrying ``payload`` (known-mass model, Thesis (6.40) or (6.41)).

    The copy's model has ``inertias[j3] = nominal + payload`` (``pin.Inertia`` addition: mass,
    CoM and parallel-axis term at once); ``robot.model`` is untouched.  ``robot.params`` is
    kept as is (its ``total_mass`` does not include the payload).
    """
    j, I = payload_joint_inertia(robot, payload, approach)
    model = pin.Model(robot.model)
    model.inertias[j] = model.inertias[j] + I
    return replace(robot, model=model)


class PayloadModel:
    """A model copy whose link-3 inertia can be set to nominal + payload at run time.

    ``model`` is the copy (``robot.model`` is never touched); :meth:`set` changes it in place,
    which is cheap (one ``pin.Inertia`` sum), so controllers can follow a mass estimate.
    """

    def __init__(self, robot: Robot, com_ee=(0.0, 0.0, 0.0)) -> None:
        self.robot = robot
        self.model = pin.Model(robot.model)
        self.data = self.model.createData()
        frame = robot.model.frames[robot.ee_frame]
        self.joint = int(frame.parentJoint)
        self.placement = frame.placement
        self.nominal = pin.Inertia(robot.model.inertias[self.joint])
        self.com_joint = self.placement.act(as_vector(com_ee, 3, "com_ee"))
        self.mass = 0.0

    def set_mass(self, mass: float) -> None:
        """Point mass ``mass`` [kg] at ``com_ee`` (the controller's model of an unknown payload, (6.44))."""
        self.mass = float(mass)
        self.model.inertias[self.joint] = self.nominal + pin.Inertia(self.mass, self.com_joint, np.zeros((3, 3)))

    def set(self, payload: Payload | float, approach: str = "body") -> None:
        """Nominal + ``payload`` (Thesis (6.40) with approach "link3", (6.41) with "body")."""
        payload = _as_payload(payload)
        self.mass = payload.mass
        self.model.inertias[self.joint] = self.nominal + self.placement.act(payload.spatial_inertia_ee(approach))


# ============================================================== (6.40), (6.41): inertia sums
@dataclass(frozen=True)
class RigidInertia:
    """Mass [kg], CoM [m] and rotational inertia about the CoM [kg m^2] of a body, in one frame."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray


def combine_inertias(a: RigidInertia, b: RigidInertia) -> RigidInertia:
    """Two rigidly joined bodies as one (parallel-axis theorem in tensor form).

    m = m_a + m_b, c = (m_a c_a + m_b c_b)/m and, about the new CoM,
    I = I_a + I_b + mu (|delta|^2 I3 - delta delta^T), mu = m_a m_b / m, delta = c_b - c_a.
    This is the corrected form of (6.40b) and (6.41b) (see :func:`link3_inertia_6_40`).
    """
    m = a.mass + b.mass
    if m <= 0.0:
        raise InputError(f"combined mass must be > 0, got {a.mass!r} + {b.mass!r}")
    ca, cb = np.asarray(a.com, dtype=float), np.asarray(b.com, dtype=float)
    delta = cb - ca
    mu = a.mass * b.mass / m
    I = np.asarray(a.inertia, dtype=float) + np.asarray(b.inertia, dtype=float) + mu * (delta @ delta * np.eye(3) - np.outer(delta, delta))
    return RigidInertia(m, (a.mass * ca + b.mass * cb) / m, I)


def link3_inertia_6_40(m3: float, I3, m_cl: float, x_cm: float, z_cm: float) -> tuple[float, np.ndarray]:
    """(m3', I3') as printed in Thesis (6.40): m3' = m3 + m_cl, I3' = I3 + m3' (x_cm^2 + z_cm^2).

    The scalar is read as added to every diagonal entry (the printed bold I3 plus a scalar).
    Misprint: a point mass m_cl at (x_cm, z_cm) from link 3's CoM adds m_cl (not m3') times the
    squared distance to the axis about link 3's CoM, and the reduced mass
    m3 m_cl / m3' about the combined CoM (:func:`combine_inertias`); and only the axis normal
    to the x-z plane (y, the joint axis) has x_cm^2 + z_cm^2 as squared distance.
    """
    m3p = m3 + m_cl
    return m3p, np.asarray(I3, dtype=float) + m3p * (x_cm**2 + z_cm**2) * np.eye(3)


def system_inertia_6_41(m: float, I, m_cl: float, I_cl, x_cm: float, z_cm: float) -> tuple[float, np.ndarray]:
    """(m', I') as printed in Thesis (6.41): m' = m + m_cl, I' = I + I_cl + m_cl (x_cm^2 + z_cm^2).

    The scalar is added to every diagonal entry.  Correct for the yy entry about the OLD system
    CoM when (x_cm, z_cm) is the payload's offset from it; about the new CoM the factor is the
    reduced mass m m_cl / (m + m_cl), and the xx, zz entries need z_cm^2 and x_cm^2 alone, with
    a product term -m_cl x_cm z_cm off the diagonal (:func:`combine_inertias`).
    """
    return m + m_cl, np.asarray(I, dtype=float) + np.asarray(I_cl, dtype=float) + m_cl * (x_cm**2 + z_cm**2) * np.eye(3)


def sphere_inertia_6_43(mass: float, radius: float, n: int = 64, corrected: bool = False) -> float:
    """Moment of inertia of a solid sphere by the triple integral of Thesis (6.43), Gauss-Legendre quadrature.

    As printed the integrand is rho r^2 dV (r^2: distance to the CENTRE), which gives
    3/5 m R^2, not the 2/5 m R^2 stated after it.  ``corrected=True`` integrates
    rho (r sin theta)^2 dV (distance to the z AXIS), which gives 2/5 m R^2.
    """
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
    from .thesis import com_3_78_corrected

    r0, t2, t3 = as_vector(q_arm, 3, "q_arm")
    d0, d1, d2, d3 = params.d0, params.d1, params.d2, params.d3
    p_eb = np.array([r0 + d2 * math.sin(t2) + d3 * math.sin(t2 + t3), 0.0, d0 + d1 + d2 * math.cos(t2) + d3 * math.cos(t2 + t3)])
    mG = params.total_mass
    return (mG * com_3_78_corrected((r0, t2, t3), params) + m_cl * p_eb) / (mG + m_cl)


def com_with_payload(robot: Robot, data: pin.Data, q_arm, payload: Payload | float) -> np.ndarray:
    """System CoM in B with the payload (corrected (6.42)), from the Pinocchio model copy of :func:`with_payload`."""
    q_arm = as_vector(q_arm, 3, "q_arm")
    loaded = with_payload(robot, payload)
    q = pin.neutral(loaded.model)
    q[7:10] = q_arm
    return pin.centerOfMass(loaded.model, loaded.model.createData(), q, False).copy()


# ============================================================ Sec. 6.4.1.1: holding, capacity
@dataclass(frozen=True)
class HoldingEffort:
    """Efforts that hold the Q-PRR level at rest with a payload (Thesis Sec. 6.4.1.1).

    ``thrust`` total rotor thrust [N] = (m + m_c) g; ``arm_effort`` = [f_r0 (N), tau_theta2,
    tau_theta3 (N m)] the actuators must apply (= the arm rows of G, Pinocchio generalised
    gravity of the loaded model); ``arm_effort_nominal`` the same without payload.
    ``status`` is "ok" or "exceeds": ``reason`` names the limits exceeded.
    """

    q_arm: np.ndarray
    payload_mass: float
    thrust: float
    arm_effort: np.ndarray
    arm_effort_nominal: np.ndarray
    status: str
    reason: str


def holding_efforts(robot: Robot, q_arm, payload: Payload | float) -> HoldingEffort:
    """Thrust and arm efforts that hold the system level and at rest with ``payload``, from Pinocchio's G."""
    q_arm = robot.check_arm_limits(q_arm)
    payload = _as_payload(payload)
    q = pin.neutral(robot.model)
    q[7:10] = q_arm
    g0 = pin.computeGeneralizedGravity(robot.model, robot.model.createData(), q).copy()
    loaded = with_payload(robot, payload)
    g1 = pin.computeGeneralizedGravity(loaded.model, loaded.model.createData(), q).copy()
    p = robot.params
    thrust = float(g1[2])
    reasons = []
    if thrust > 4 * p.thrust_max:
        reasons.append(f"thrust {thrust:.3f} N > 4 x {p.thrust_max} N")
    names = ("f_r0", "tau_theta2", "tau_theta3")
    for i in range(3):
        if abs(g1[6 + i]) > p.effort_limits[i]:
            reasons.append(f"{names[i]} |{g1[6 + i]:.4f}| > {p.effort_limits[i]}")
    return HoldingEffort(q_arm, payload.mass, thrust, g1[6:9].copy(), g0[6:9].copy(),
                         "exceeds" if reasons else "ok", "; ".join(reasons) if reasons else "within thrust and effort limits")


def holding_torques_6_4_1(params: QPRRParams, m_cl: float) -> tuple[float, float]:
    """(tau_theta2, tau_theta3) as printed in Sec. 6.4.1.1: ((d2 m2/2 + m3 + m_cl) g, (d3 m3/2 + m_cl) g).

    Dimensionally inconsistent: each sum adds kg m to kg, so the value is not a torque (it
    does not scale linearly with the length unit).  Corrected: :func:`holding_torques_corrected`.
    """
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
    _, t2, t3 = as_vector(q_arm, 3, "q_arm")
    _, m2, m3 = (link.mass for link in params.links)
    g, d2, d3 = params.g, params.d2, params.d3
    s2, s23 = math.sin(t2), math.sin(t2 + t3)
    return np.array([0.0, -g * ((m2 / 2 + m3 + m_cl) * d2 * s2 + (m3 / 2 + m_cl) * d3 * s23), -g * (m3 / 2 + m_cl) * d3 * s23])


@dataclass(frozen=True)
class PayloadCapacity:
    """Largest payload for a mission (Thesis Sec. 6.4.1.1).

    ``max_mass`` [kg]; ``limiting`` the constraint that sets it ("thrust", "f_r0",
    "tau_theta2", "tau_theta3"); ``q_arm`` the configuration where it binds (None for
    thrust); ``per_limit`` the bound of every constraint.  ``status`` "ok" or "none" (even an
    empty gripper exceeds a limit); ``reason`` says which.
    """

    mission: str
    max_mass: float
    limiting: str
    q_arm: np.ndarray | None
    per_limit: dict
    status: str
    reason: str


def payload_capacity(robot: Robot, mission: str = "manipulation", q_arm=None, *, thrust_reserve: float = 0.0,
                     n_grid: int = 121, com_ee=(0.0, 0.0, 0.0)) -> PayloadCapacity:
    """Largest point payload at the end effector (``com_ee``) for ``mission``.

    * "transport" (arm at rest, joints on their stops): thrust only, Hypothesis 5
      (4 f_max (1 - thrust_reserve) >= (m + m_c) g).
    * "manipulation": thrust and every arm effort limit, body level and at rest
      (gravity holding, dynamic efforts excluded), at ``q_arm`` or, if None, over a
      ``n_grid`` x ``n_grid`` grid of (theta2, theta3) inside the joint limits (worst case).
      Each effort is affine in m_c, u_j = a_j + m_c b_j (a, b from Pinocchio's G), so
      m_max = min over configurations of (limit_j - a_j sgn(b_j)) / |b_j|.
    """
    if mission not in MISSIONS:
        raise UnknownNameError("mission", mission, MISSIONS)
    if not (0.0 <= thrust_reserve < 1.0):
        raise InputError(f"thrust_reserve must be in [0, 1), got {thrust_reserve!r}")
    p = robot.params
    m_thrust = 4 * p.thrust_max * (1.0 - thrust_reserve) / p.g - p.total_mass
    per = {"thrust": m_thrust}
    if mission == "transport":
        best, where = "thrust", None
    else:
        if q_arm is None:
            if not (isinstance(n_grid, int) and n_grid >= 2):
                raise InputError(f"n_grid must be an integer >= 2, got {n_grid!r}")
            lo, hi = p.lower_limits, p.upper_limits
            grid = [(0.0, a, b) for a in np.linspace(lo[1], hi[1], n_grid) for b in np.linspace(lo[2], hi[2], n_grid)]
        else:
            grid = [tuple(robot.check_arm_limits(q_arm))]
        unit = PayloadModel(robot, com_ee)
        unit.set_mass(1.0)
        d0, d1 = robot.model.createData(), unit.model.createData()
        q = pin.neutral(robot.model)
        names = ("f_r0", "tau_theta2", "tau_theta3")
        best_m = {n: (math.inf, None) for n in names}
        for qa in grid:
            q[7:10] = qa
            a = pin.computeGeneralizedGravity(robot.model, d0, q)[6:9].copy()
            b = pin.computeGeneralizedGravity(unit.model, d1, q)[6:9] - a
            for i, n in enumerate(names):
                lim = p.effort_limits[i]
                if abs(b[i]) < 1e-12:
                    m = math.inf if abs(a[i]) <= lim else -math.inf
                else:
                    m = (lim - a[i] * math.copysign(1.0, b[i])) / abs(b[i])
                if m < best_m[n][0]:
                    best_m[n] = (m, np.array(qa))
        per.update({n: v[0] for n, v in best_m.items()})
        best = min(per, key=per.get)
        where = None if best == "thrust" else best_m[best][1]
    m_max = per[best]
    if m_max < 0.0:
        return PayloadCapacity(mission, 0.0, best, where, per, "none", f"{best} is exceeded without payload (bound {m_max:.4f} kg)")
    return PayloadCapacity(mission, float(m_max), best, where, per, "ok", f"limited by {best}")


# ============================================================ (6.49)-(6.53): B + B_c, G + G_c
@dataclass(frozen=True)
class PayloadTerms:
    """The payload's share of the dynamics in thesis coordinates, Thesis (6.50): B_c, C_c (9x9), G_c (9,)."""

    B_c: np.ndarray
    C_c: np.ndarray
    G_c: np.ndarray


def payload_terms_xi(robot: Robot, data: pin.Data, xi, xi_dot, payload: Payload | float, approach: str = "body") -> PayloadTerms:
    """B_c, C_c, G_c of Thesis (6.50) as (loaded model) - (nominal model), each from :func:`qprr.model.dynamics_xi`."""
    B, C, G = dynamics_xi(robot, data, xi, xi_dot)
    loaded = with_payload(robot, payload, approach)
    Bl, Cl, Gl = dynamics_xi(loaded, loaded.model.createData(), xi, xi_dot)
    return PayloadTerms(Bl - B, Cl - C, Gl - G)


def payload_point_jacobian_xi(robot: Robot, data: pin.Data, xi, com_ee=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(J_P, J_O), each 3x9 in world axes w.r.t. xi_dot, of the payload CoM point (Thesis (6.48) and its Jacobians).

    J_P = J_lin - (R_e c)^ J_ang at the point c = ``com_ee`` of the end-effector frame; J_O = J_ang.
    """
    xi = as_vector(xi, 9, "xi")
    q = co.xi_to_q(xi)
    J = pin.computeFrameJacobian(robot.model, data, q, robot.ee_frame, pin.LOCAL_WORLD_ALIGNED) @ co.rate_map(xi)
    R_e = data.oMf[robot.ee_frame].rotation
    lever = R_e @ as_vector(com_ee, 3, "com_ee")
    return J[0:3] - pin.skew(lever) @ J[3:6], J[3:6].copy()


def payload_terms_closed_form(robot: Robot, data: pin.Data, xi, payload: Payload | float) -> tuple[np.ndarray, np.ndarray]:
    """(B_c, G_c) of the corrected Thesis (6.51)-(6.52).

    B_c = m_c J_P^T J_P + J_O^T (R_c I_c R_c^T) J_O (R_c: payload axes in the world),
    G_c = m_c g J_P^T e3 = d(m_c g z_c)/dxi (z up, U = m g z as (5.29)).
    """
    payload = _as_payload(payload)
    JP, JO = payload_point_jacobian_xi(robot, data, xi, payload.com_ee)
    R_e = data.oMf[robot.ee_frame].rotation
    Iw = R_e @ payload.inertia_matrix() @ R_e.T
    m = payload.mass
    B_c = m * JP.T @ JP + JO.T @ Iw @ JO
    G_c = m * robot.params.g * JP[2]
    return B_c, G_c


def G_c_6_52(xi, m_c: float, d, g: float) -> np.ndarray:
    """G_c as printed in Thesis (6.52) (point payload at the end effector).

    Printed form is d(m_c g y_e)/dxi (gravity along world y) with two more misprints: d2
    where d3 belongs in the s23 terms of rows 5-6 and a spurious 1/2 in row 9.  With gravity
    along -z (5.29) the correct vector is m_c g d z_e / d xi (:func:`payload_terms_closed_form`).
    """
    xi = as_vector(xi, 9, "xi")
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    _, _, _, f, t, s, r0, t2, t3 = xi
    sf, cf, st, ct, ss, cs = math.sin(f), math.cos(f), math.sin(t), math.cos(t), math.sin(s), math.cos(s)
    s2, c2, s23, c23 = math.sin(t2), math.cos(t2), math.sin(t2 + t3), math.cos(t2 + t3)
    pz = d0 + d1 + c2 * d2 + c23 * d3
    px_printed = r0 + s2 * d2 + s23 * d2
    mg = m_c * g
    return np.array([
        0.0,
        mg,
        0.0,
        -mg * (cf * cs + sf * ss * st) * pz,
        -mg * (ss * st * px_printed - cf * ct * ss * pz),
        mg * ((sf * ss + cf * cs * st) * pz + cs * ct * px_printed),
        mg * ct * ss,
        mg * ((cs * sf - cf * ss * st) * (s2 * d2 + s23 * d3) + ct * ss * (c2 * d2 + c23 * d3)),
        0.5 * mg * d3 * (s23 * (cs * sf - cf * ss * st) + ct * ss * c23),
    ])


def B_c_6_51(xi, m_c: float, I_c, d, corrected: bool = False) -> np.ndarray:
    """B_c as printed in Thesis (6.51), point payload at the end effector with inertia I_c (payload axes = link 3).

    Read with the thesis's T(phi) of (3.25) (omega_body = T phi_dot), Q = R_b^T T (5.15) and
    R_c^b = Ry(theta2 + theta3).  Misprints: B12c has (R_b p_c)^ T where R_b p_c^ T belongs;
    B22c ends in R_b where T belongs (the printed block is not even symmetric) and uses Q
    where T belongs; B23c carries an extra R_b (and Q for T).  ``corrected=True`` (body-frame
    p_c, as in (5.2.2) corrected): B12c = -m_c R_b p_c^ T, B22c = T^T (m_c p_c^T^ p_c^ + R_c I_c R_c^T) T,
    B23c = T^T (m_c p_c^ j_Pc + R_c I_c R_c^T j_Oc); B11c, B13c, B33c as printed.  Model-based
    form: :func:`payload_terms_closed_form`.
    """
    from .thesis import T_3_25, rotation_3_4  # the printed (3.4) and (3.25), as the thesis uses them

    xi = as_vector(xi, 9, "xi")
    d0, d1, d2, d3 = as_vector(d, 4, "d")
    Ic = np.asarray(I_c, dtype=float).reshape(3, 3)
    f, t, s, r0, t2, t3 = xi[3:9]
    Rb = rotation_3_4(f, t, s)
    T = T_3_25(f, t)
    Q = Rb.T @ T
    s2, c2, s23, c23 = math.sin(t2), math.cos(t2), math.sin(t2 + t3), math.cos(t2 + t3)
    p_c = np.array([r0 + d2 * s2 + d3 * s23, 0.0, d0 + d1 + d2 * c2 + d3 * c23])
    p1 = np.array([r0, 0.0, d0 + d1])
    p2 = np.array([r0 + d2 * s2, 0.0, d0 + d1 + d2 * c2])
    z = np.array([0.0, 1.0, 0.0])
    jP = np.column_stack([[1.0, 0.0, 0.0], np.cross(z, p_c - p1), np.cross(z, p_c - p2)])
    jO = np.column_stack([np.zeros(3), z, z])
    Rc = co.rot_y(t2 + t3)
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
        B12 = -m_c * hat @ T
        B22 = m_c * T.T @ hat.T @ hat @ Rb + Q.T @ Icb @ Q
        B23 = Q.T @ Icb @ jO - m_c * T.T @ hat.T @ Rb @ jP
    return np.block([[B11, B12, B13], [B12.T, B22, B23], [B13.T, B23.T, B33]])


# ================================================================ Sec. 6.4.2: mass estimate
@dataclass(frozen=True)
class MassEstimate:
    """Current estimate: ``mass`` [kg], ``information`` = sum_i lambda^(k-i) |Y_i|^2 (how much excitation backs it), ``samples`` used."""

    mass: float
    information: float
    samples: int


class MassEstimator:
    """Online estimate of an unknown payload mass from the joint-torque residual (Thesis Sec. 6.4.2).

    The payload enters the dynamics linearly (Thesis (6.53) with C_c kept):
    tau_applied = RNEA_nominal(q, v, a) + m_c Y(q, v, a),   Y = RNEA_unit(q, v, a) - RNEA_nominal(q, v, a),
    with RNEA_unit the model carrying a 1 kg point mass at the payload point.  Its first
    rows are the vertical force balance (m + m_c)(z_ddot + g) = thrust c_phi c_theta of the
    body, the last three the arm-torque residual.  Each step uses the acceleration measured
    over the previous step, a = (v_k - v_{k-1}) / dt, and the effort applied over it, and
    updates an exponentially weighted least-squares estimate

        m_c = sum_i lambda^(k-i) Y_i^T r_i / sum_i lambda^(k-i) Y_i^T Y_i,  lambda = exp(-dt / time_constant),

    so that the estimate forgets a released payload with ``time_constant`` [s].  The
    estimate is clipped to [``min_mass``, ``max_mass``].  ``prior_weight`` regularises the
    start (the estimate begins at ``initial``).
    """

    def __init__(self, robot: Robot, *, time_constant: float = 0.05, com_ee=(0.0, 0.0, 0.0), initial: float = 0.0,
                 min_mass: float = 0.0, max_mass: float = math.inf, prior_weight: float = 1e-3) -> None:
        if not (np.isfinite(time_constant) and time_constant > 0.0):
            raise InputError(f"time_constant must be > 0 s, got {time_constant!r}")
        if not (min_mass <= initial <= max_mass):
            raise InputError(f"need min_mass <= initial <= max_mass, got {min_mass!r}, {initial!r}, {max_mass!r}")
        self.robot = robot
        self.time_constant = float(time_constant)
        self.initial = float(initial)
        self.min_mass, self.max_mass = float(min_mass), float(max_mass)
        self.prior_weight = float(prior_weight)
        self._nominal = robot.model
        self._dn = robot.model.createData()
        unit = PayloadModel(robot, com_ee)
        unit.set_mass(1.0)
        self._unit = unit.model
        self._du = unit.model.createData()
        self.reset()

    def reset(self) -> None:
        """Forget everything; the estimate returns to ``initial``."""
        self._P = self.prior_weight
        self._b = self.prior_weight * self.initial
        self.mass = self.initial
        self.samples = 0
        self._last_dt = None
        self._lam = 1.0

    def regressor(self, q, v, a) -> tuple[np.ndarray, np.ndarray]:
        """(RNEA_nominal(q, v, a), Y(q, v, a)) in Pinocchio coordinates."""
        tn = pin.rnea(self._nominal, self._dn, q, v, a).copy()
        return tn, pin.rnea(self._unit, self._du, q, v, a) - tn

    def update(self, q_prev, v_prev, tau_prev, v_now, dt: float) -> float:
        """Add the step (q_prev, v_prev) -> v_now under the applied Pinocchio force ``tau_prev``; return the estimate."""
        if not (dt > 0.0):
            raise InputError(f"dt must be > 0 s, got {dt!r}")
        if dt != self._last_dt:
            self._lam = math.exp(-dt / self.time_constant)
            self._last_dt = dt
        a = (np.asarray(v_now) - np.asarray(v_prev)) / dt
        tn, Y = self.regressor(q_prev, v_prev, a)
        r = np.asarray(tau_prev) - tn
        lam = self._lam
        self._P = lam * self._P + float(Y @ Y)
        self._b = lam * self._b + float(Y @ r)
        self.samples += 1
        self.mass = min(self.max_mass, max(self.min_mass, self._b / self._P))
        return self.mass

    def estimate(self) -> MassEstimate:
        return MassEstimate(self.mass, self._P, self.samples)
