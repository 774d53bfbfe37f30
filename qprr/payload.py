"""Payload carried at the end effector of any platform: models, holding efforts, capacity, B + B_c, mass estimate.

Thesis Sec. 6.4.1-6.4.2.  A payload is a rigid body attached to the end effector's parent link
(link 3 of the Q-PRR): mass m_c, centre of mass ``com_ee`` in the end-effector frame,
rotational inertia I_c about its CoM (zero for a point mass).

* Known mass, Thesis (6.40)/(6.41): :func:`with_payload` returns a copy of the platform whose
  parent-link spatial inertia is nominal + payload (``pin.Inertia.__add__``); ``approach="link3"``
  folds a point mass into the link as (6.40) does, ``approach="body"`` adds the payload as a
  rigid body with its own inertia I_cl as (6.41) does.  :class:`PayloadModel` does the same
  at run time on a model copy it owns.
* Holding efforts and capacity, Sec. 6.4.1.1: :func:`holding_efforts`, :func:`payload_capacity`.
* Unknown mass, Thesis (6.49)-(6.53): :func:`payload_terms_xi` gives B_c, C_c, G_c as the
  difference between the dynamics with and without the payload; :func:`payload_terms_closed_form`
  gives B_c = m_c J_P^T J_P + J_O^T R_c I_c R_c^T J_O and G_c = m_c g J_P,z (the corrected
  (6.51), (6.52)).
* :class:`MassEstimator`: exponentially weighted least squares on the joint-torque residual.

The printed closed forms of the section and their corrections are in :mod:`qprr.thesis.payload`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
import pinocchio as pin

from . import charts as co
from .dynamics import dynamics_xi
from .errors import InputError, NonPhysicalError, PlausibilityError, UnknownNameError
from .kinematics import check_q
from .model import Platform, check_flight, check_model_data, check_platform, max_lift
from .urdf.inertia import check_rigid_body
from .urdf.plausibility import DEFAULT as PLAUSIBLE
from .urdf.plausibility import check_plausibility_setting
from .validation import as_int, as_real, as_vector

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
        object.__setattr__(self, "mass", as_real(self.mass, "payload mass", nonnegative=True, unit="kg"))
        object.__setattr__(self, "com_ee", tuple(as_vector(self.com_ee, 3, "com_ee").tolist()))
        object.__setattr__(self, "inertia", tuple(as_vector(self.inertia, 6, "inertia").tolist()))
        if np.any(np.linalg.eigvalsh(self.inertia_matrix()) < -1e-15):
            raise InputError(f"payload inertia must be positive semi-definite, got {self.inertia!r}")

    @classmethod
    def sphere(cls, mass: float, radius: float, com_ee=(0.0, 0.0, 0.0)) -> Payload:
        """Solid homogeneous sphere: I_xx = I_yy = I_zz = 2/5 m R^2 (the result stated after Thesis (6.43))."""
        radius = as_real(radius, "sphere radius", nonnegative=True, unit="m")
        mass = as_real(mass, "payload mass", nonnegative=True, unit="kg")
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
    if isinstance(payload, (bool, str)) or payload is None or not isinstance(payload, (int, float, np.number)):
        raise InputError(f"payload must be a Payload or a mass in kg, got {payload!r}")
    return Payload(as_real(payload, "payload (mass)", nonnegative=True, unit="kg"))


def payload_joint_inertia(platform: Platform, payload: Payload | float, approach: str = "body") -> tuple[int, pin.Inertia]:
    """(joint id, spatial inertia of the payload expressed in that joint's frame): what is added to link 3."""
    check_platform(platform)
    payload = _as_payload(payload)
    frame = platform.model.frames[platform.ee_frame]
    return int(frame.parentJoint), frame.placement.act(payload.spatial_inertia_ee(approach))


def with_payload(platform: Platform, payload: Payload | float, approach: str = "body", *, plausibility=PLAUSIBLE) -> Platform:
    """A copy of ``platform`` carrying ``payload`` (known-mass model, Thesis (6.40) or (6.41)).

    The copy's model has ``inertias[j] = nominal + payload`` for the end effector's parent joint j
    (``pin.Inertia`` addition: mass, CoM and parallel-axis term at once); ``platform.model`` is
    untouched.  ``platform.params`` is kept as is.  The checks of a loaded platform apply to the copy
    (:func:`qprr.model.check_flight`: inertias, lift, hover and attitude authority) and to the payload (a rigid body,
    com and size within ``plausibility``, :class:`qprr.urdf.plausibility.Plausibility`, None: no range check): a payload the
    rotors cannot lift raises :class:`~qprr.errors.NonPhysicalError` suggesting grams.
    """
    plausibility = check_plausibility_setting(plausibility)
    out = _loaded(platform, payload, approach)
    payload = _as_payload(payload)
    _check_payload(platform, payload, plausibility)
    check_flight(out, f"platform {platform.name!r} with a {payload.mass:g} kg payload")
    return out


def _loaded(platform: Platform, payload: Payload | float, approach: str = "body") -> Platform:
    """The platform with the payload's inertia added, unchecked (the analyses that report whether it can be held)."""
    j, I = payload_joint_inertia(platform, payload, approach)
    model = pin.Model(platform.model)
    model.inertias[j] = model.inertias[j] + I
    return platform.with_model(model)


def _check_payload(platform: Platform, payload: Payload, plausibility) -> None:
    """The payload's own body (:func:`qprr.urdf.inertia.check_rigid_body`), its plausibility and the lift with it."""
    check_rigid_body("payload", payload.mass, payload.com_ee, payload.inertia, allow_massless=True)
    if plausibility is not None:
        d = float(np.linalg.norm(payload.com_ee))
        if d > plausibility.length_max:
            raise PlausibilityError(
                f"payload com_ee is {d:g} m from the end effector, outside the plausible range (<= "
                f"{plausibility.length_max:g} m): millimetres? {d:g} mm = {d / 1000:g} m. If you mean it, pass "
                "plausibility=dataclasses.replace(qprr.urdf.plausibility.DEFAULT, length_max=...)"
            )
        radius = math.sqrt(max(payload.inertia[:3]) / payload.mass) if payload.mass > 0.0 else 0.0
        if radius > plausibility.gyration_radius_max:
            raise PlausibilityError(
                f"payload inertia {payload.inertia!r} with mass {payload.mass:g} kg has a radius of gyration "
                f"of {radius:g} m (> {plausibility.gyration_radius_max:g} m): kg mm^2 or g mm^2? If you mean it, "
                "pass plausibility=dataclasses.replace(qprr.urdf.plausibility.DEFAULT, gyration_radius_max=...)"
            )
    lift, g = max_lift(platform), platform.g
    weight = (platform.total_mass + payload.mass) * g
    if weight > lift:
        raise NonPhysicalError(
            f"payload mass {payload.mass:g} kg: platform {platform.name!r} ({platform.total_mass:.4g} kg) with it "
            f"weighs {weight:.6g} N, its rotors push at most {lift:.6g} N along z_B, so at most "
            f"{max(lift / g - platform.total_mass, 0.0) if g > 0 else math.inf:.4g} kg can be carried; a mass "
            f"in grams? {payload.mass:g} g = {payload.mass / 1000:g} kg"
        )


class PayloadModel:
    """A model copy whose link-3 inertia can be set to nominal + payload at run time.

    ``model`` is the copy (``platform.model`` is never touched); :meth:`set` changes it in place,
    which is cheap (one ``pin.Inertia`` sum), so controllers can follow a mass estimate.
    """

    def __init__(self, platform: Platform, com_ee=(0.0, 0.0, 0.0)) -> None:
        self.platform = check_platform(platform)
        self.model = pin.Model(platform.model)
        self.data = self.model.createData()
        frame = platform.model.frames[platform.ee_frame]
        self.joint = int(frame.parentJoint)
        self.placement = frame.placement
        self.nominal = pin.Inertia(platform.model.inertias[self.joint])
        self.com_joint = self.placement.act(as_vector(com_ee, 3, "com_ee"))
        self.mass = 0.0

    def set_mass(self, mass: float) -> None:
        """Point mass ``mass`` [kg] (>= 0) at ``com_ee`` (the controller's model of an unknown payload, (6.44))."""
        self.mass = as_real(mass, "mass", nonnegative=True, unit="kg")
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
    for name, body in (("a", a), ("b", b)):
        if not isinstance(body, RigidInertia):
            raise InputError(f"{name} must be a RigidInertia, got {type(body).__name__}")
        as_real(body.mass, f"{name}.mass", nonnegative=True, unit="kg")
        as_vector(body.com, 3, f"{name}.com")
        co.as_matrix(body.inertia, (3, 3), f"{name}.inertia")
    m = a.mass + b.mass
    if m <= 0.0:
        raise InputError(f"combined mass must be > 0, got {a.mass!r} + {b.mass!r}")
    ca, cb = np.asarray(a.com, dtype=float), np.asarray(b.com, dtype=float)
    delta = cb - ca
    mu = a.mass * b.mass / m
    I = np.asarray(a.inertia, dtype=float) + np.asarray(b.inertia, dtype=float) + mu * (delta @ delta * np.eye(3) - np.outer(delta, delta))
    return RigidInertia(m, (a.mass * ca + b.mass * cb) / m, I)


def com_with_payload(platform: Platform, data: pin.Data, q_arm, payload: Payload | float) -> np.ndarray:
    """System CoM in B with the payload (corrected (6.42)), from the Pinocchio model copy of :func:`with_payload`."""
    check_model_data(platform, data)
    q_arm = as_vector(q_arm, platform.n_arm, "q_arm")
    loaded = _loaded(platform, payload)
    q = pin.neutral(loaded.model)
    q[7:] = q_arm
    return pin.centerOfMass(loaded.model, loaded.model.createData(), q, False).copy()


# ============================================================ Sec. 6.4.1.1: holding, capacity
class HoldingStatus(str, Enum):
    """Whether the platform can hold a payload (:attr:`HoldingEffort.status`, equal to its string)."""

    OK = "ok"
    EXCEEDS = "exceeds"

    def __str__(self) -> str:
        return self.value


class CapacityStatus(str, Enum):
    """Whether a mission can carry any payload (:attr:`PayloadCapacity.status`, equal to its string): ``none`` when even
    an empty gripper exceeds a limit."""

    OK = "ok"
    NONE = "none"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class HoldingEffort:
    """Efforts that hold the platform level at rest with a payload (Thesis Sec. 6.4.1.1).

    ``thrust`` total force the rotors must produce [N] = (m + m_c) g; ``arm_effort`` (n_arm,) the
    efforts the arm actuators must apply (the arm rows of G, Pinocchio generalised gravity of the
    loaded model); ``arm_effort_nominal`` the same without payload.  ``status`` (:class:`HoldingStatus`) is "ok" or
    "exceeds": ``reason`` names the limits exceeded (the largest total thrust along the thrust
    axis, the arm effort limits).
    """

    q_arm: np.ndarray
    payload_mass: float
    thrust: float
    arm_effort: np.ndarray
    arm_effort_nominal: np.ndarray
    status: HoldingStatus
    reason: str


def max_total_thrust(platform: Platform) -> float:
    """Largest force [N] the rotors produce along the thrust axis with no force across it (all at f_max for rotors along
    one axis): the collective-thrust limit of :meth:`qprr.analysis.WrenchSet.force_max`."""
    from .analysis.wrenchset import wrench_set

    return wrench_set(check_platform(platform)).force_max(platform.thrust_axis[1])


def holding_efforts(platform: Platform, q_arm, payload: Payload | float) -> HoldingEffort:
    """Thrust and arm efforts that hold the platform level and at rest with ``payload``, from Pinocchio's G."""
    q_arm = check_platform(platform).check_arm_limits(q_arm)
    payload = _as_payload(payload)
    q = pin.neutral(platform.model)
    q[7:] = q_arm
    g0 = pin.computeGeneralizedGravity(platform.model, platform.model.createData(), q).copy()
    loaded = _loaded(platform, payload)
    g1 = pin.computeGeneralizedGravity(loaded.model, loaded.model.createData(), q).copy()
    thrust = float(g1[2])
    reasons = []
    f_total = max_total_thrust(platform)
    if thrust > f_total:
        reasons.append(f"thrust {thrust:.3f} N > {f_total:.3f} N (all rotors at f_max)")
    for k, joint in enumerate(platform.arm):
        if abs(g1[6 + k]) > joint.effort:
            reasons.append(f"{joint.name} |{g1[6 + k]:.4f}| > {joint.effort}")
    return HoldingEffort(
        q_arm,
        payload.mass,
        thrust,
        g1[6:].copy(),
        g0[6:].copy(),
        HoldingStatus.EXCEEDS if reasons else HoldingStatus.OK,
        "; ".join(reasons) if reasons else "within thrust and effort limits",
    )


@dataclass(frozen=True)
class PayloadCapacity:
    """Largest payload for a mission (Thesis Sec. 6.4.1.1).

    ``max_mass`` [kg]; ``limiting`` the constraint that sets it ("thrust" or an arm joint's
    name); ``q_arm`` the configuration where it binds (None for thrust); ``per_limit`` the bound
    of every constraint.  ``status`` (:class:`CapacityStatus`) "ok" or "none" (even an empty gripper exceeds a limit);
    ``reason`` says which.
    """

    mission: str
    max_mass: float
    limiting: str
    q_arm: np.ndarray | None
    per_limit: dict
    status: CapacityStatus
    reason: str


def payload_capacity(
    platform: Platform,
    mission: str = "manipulation",
    q_arm=None,
    *,
    thrust_reserve: float = 0.0,
    n_grid: int = 121,
    com_ee=(0.0, 0.0, 0.0),
    configurations=None,
) -> PayloadCapacity:
    """Largest point payload at the end effector (``com_ee``) for ``mission``.

    * "transport" (arm at rest, joints on their stops): thrust only, Hypothesis 5
      (F_max (1 - thrust_reserve) >= (m + m_c) g with F_max the total thrust of :func:`max_total_thrust`).
    * "manipulation": thrust and every arm effort limit, body level and at rest (gravity
      holding, dynamic efforts excluded), at ``q_arm``, over ``configurations`` (an array of
      q_arm rows) or, if both are None, over a grid of ``n_grid`` values of each revolute joint
      inside its limits (prismatic joints at 0; the worst case).  Each effort is affine in m_c,
      u_j = a_j + m_c b_j, so m_max = min over configurations of (limit_j - a_j sgn(b_j)) / |b_j|.

    The numbers come from the capacity map's implementation (:func:`qprr.analysis.hover.payload_limits` on the
    batched statics of :class:`qprr.analysis.ArmChain`, equal to Pinocchio's generalised gravity to round-off);
    the map (:func:`qprr.analysis.capacity`) adds the attitude authority and the best configuration per workspace cell.
    """
    from .analysis.chain import ArmChain
    from .analysis.hover import payload_limits
    from .analysis.wrenchset import wrench_set

    check_platform(platform)
    if mission not in MISSIONS:
        raise UnknownNameError("mission", mission, MISSIONS)
    thrust_reserve = as_real(thrust_reserve, "thrust_reserve", nonnegative=True)
    if not thrust_reserve < 1.0:
        raise InputError(f"thrust_reserve must be in [0, 1), got {thrust_reserve!r}")
    offset = as_vector(com_ee, 3, "com_ee")
    if mission == "transport":  # the thrust alone: one configuration gives it
        rows = platform.neutral_q()[7:].reshape(1, -1) if q_arm is None else platform.check_arm_limits(q_arm).reshape(1, -1)
    else:
        rows = np.array(_configurations(platform, q_arm, configurations, n_grid), dtype=float).reshape(-1, platform.n_arm)
    W = wrench_set(platform)
    chain = ArmChain(platform)
    names = platform.arm_names
    limits = np.array(platform.arm_effort_limits, dtype=float)
    best_m = np.full(platform.n_arm, math.inf)
    best_q = [None] * platform.n_arm
    m_thrust = None
    for start in range(0, rows.shape[0], 16384):
        chunk = rows[start : start + 16384]
        pl = payload_limits(chain.statics(chain.pose(chunk), platform.ee_frame, offset), W, limits, platform.g)
        # collective thrust F_max / g - m, F_max reduced by the reserve
        m_thrust = (pl.collective + platform.total_mass) * (1.0 - thrust_reserve) - platform.total_mass
        lim = pl.effort_per_joint
        k = lim.argmin(axis=0)
        for i in range(platform.n_arm):
            if lim[k[i], i] < best_m[i]:
                best_m[i], best_q[i] = float(lim[k[i], i]), chunk[k[i]].copy()
    per = {"thrust": float(m_thrust)}
    if mission == "transport":
        best, where = "thrust", None
    else:
        per.update({n: best_m[i] for i, n in enumerate(names)})
        best = min(per, key=per.get)
        where = None if best == "thrust" else best_q[names.index(best)]
    m_max = per[best]
    if m_max < 0.0:
        return PayloadCapacity(mission, 0.0, best, where, per, CapacityStatus.NONE, f"{best} is exceeded without payload (bound {m_max:.4f} kg)")
    return PayloadCapacity(mission, float(m_max), best, where, per, CapacityStatus.OK, f"limited by {best}")


def _configurations(platform: Platform, q_arm, configurations, n_grid: int) -> list:
    if q_arm is not None:
        return [tuple(platform.check_arm_limits(q_arm))]
    if configurations is not None:
        rows = np.atleast_2d(co.as_array(configurations, "configurations"))
        if rows.shape[1] != platform.n_arm:
            raise InputError(f"configurations must have {platform.n_arm} columns (q_arm), got shape {rows.shape}")
        for k, row in enumerate(rows):
            platform.check_arm_limits(row, f"configurations[{k}]")
        return [tuple(r) for r in rows]
    n_grid = as_int(n_grid, "n_grid", lo=2)
    axes = []
    for joint in platform.arm:
        if joint.kind == "revolute":
            lo = joint.lower if math.isfinite(joint.lower) else -math.pi
            hi = joint.upper if math.isfinite(joint.upper) else math.pi
            axes.append(np.linspace(lo, hi, n_grid))
        else:
            axes.append(np.array([min(max(0.0, joint.lower), joint.upper)]))
    mesh = np.meshgrid(*axes, indexing="ij")
    return [tuple(r) for r in np.stack([m.ravel() for m in mesh], axis=1)]


# ============================================================ (6.49)-(6.53): B + B_c, G + G_c
@dataclass(frozen=True)
class PayloadTerms:
    """The payload's share of the dynamics in thesis coordinates, Thesis (6.50): B_c, C_c (9x9), G_c (9,)."""

    B_c: np.ndarray
    C_c: np.ndarray
    G_c: np.ndarray


def payload_terms_xi(platform: Platform, data: pin.Data, xi, xi_dot, payload: Payload | float, approach: str = "body") -> PayloadTerms:
    """B_c, C_c, G_c of Thesis (6.50) as (loaded model) - (nominal model), each from :func:`qprr.dynamics.dynamics_xi`."""
    _check_approach(approach)
    payload = _as_payload(payload)
    B, C, G = dynamics_xi(platform, data, xi, xi_dot)
    loaded = _loaded(platform, payload, approach)
    Bl, Cl, Gl = dynamics_xi(loaded, loaded.model.createData(), xi, xi_dot)
    return PayloadTerms(Bl - B, Cl - C, Gl - G)


def payload_point_jacobian_xi(platform: Platform, data: pin.Data, xi, com_ee=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(J_P, J_O), each 3 x (6 + n) in world axes w.r.t. xi_dot, of the payload CoM point (Thesis (6.48) and its Jacobians).

    J_P = J_lin - (R_e c)^ J_ang at the point c = ``com_ee`` of the end-effector frame; J_O = J_ang.
    """
    check_model_data(platform, data)
    xi = co.as_xi(xi, "xi", platform.n_xi)
    q = co.xi_to_q(xi)
    J = pin.computeFrameJacobian(platform.model, data, q, platform.ee_frame, pin.LOCAL_WORLD_ALIGNED) @ co.rate_map(xi)
    R_e = data.oMf[platform.ee_frame].rotation
    lever = R_e @ as_vector(com_ee, 3, "com_ee")
    return J[0:3] - pin.skew(lever) @ J[3:6], J[3:6].copy()


def payload_terms_closed_form(platform: Platform, data: pin.Data, xi, payload: Payload | float) -> tuple[np.ndarray, np.ndarray]:
    """(B_c, G_c) of the corrected Thesis (6.51)-(6.52).

    B_c = m_c J_P^T J_P + J_O^T (R_c I_c R_c^T) J_O (R_c: payload axes in the world),
    G_c = m_c g J_P^T e3 = d(m_c g z_c)/dxi (z up, U = m g z as (5.29)).
    """
    payload = _as_payload(payload)
    JP, JO = payload_point_jacobian_xi(platform, data, xi, payload.com_ee)
    R_e = data.oMf[platform.ee_frame].rotation
    Iw = R_e @ payload.inertia_matrix() @ R_e.T
    m = payload.mass
    B_c = m * JP.T @ JP + JO.T @ Iw @ JO
    G_c = m * platform.g * JP[2]
    return B_c, G_c


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

    def __init__(
        self,
        platform: Platform,
        *,
        time_constant: float = 0.05,
        com_ee=(0.0, 0.0, 0.0),
        initial: float = 0.0,
        min_mass: float = 0.0,
        max_mass: float = math.inf,
        prior_weight: float = 1e-3,
    ) -> None:
        check_platform(platform)
        time_constant = as_real(time_constant, "time_constant", positive=True, unit="s")
        initial = as_real(initial, "initial", nonnegative=True, unit="kg")
        min_mass = as_real(min_mass, "min_mass", nonnegative=True, unit="kg")
        max_mass = as_real(max_mass, "max_mass", nonnegative=True, allow_inf=True, unit="kg")
        prior_weight = as_real(prior_weight, "prior_weight", positive=True)
        if not (min_mass <= initial <= max_mass):
            raise InputError(f"need min_mass <= initial <= max_mass, got {min_mass!r}, {initial!r}, {max_mass!r}")
        self.platform = platform
        self.time_constant = float(time_constant)
        self.initial = float(initial)
        self.min_mass, self.max_mass = float(min_mass), float(max_mass)
        self.prior_weight = float(prior_weight)
        self._nominal = platform.model
        self._dn = platform.model.createData()
        unit = PayloadModel(platform, com_ee)
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
        nv = self.platform.nv
        q, v, a = check_q(self.platform, q), as_vector(v, nv, "v"), as_vector(a, nv, "a")
        tn = pin.rnea(self._nominal, self._dn, q, v, a).copy()
        return tn, pin.rnea(self._unit, self._du, q, v, a) - tn

    def update(self, q_prev, v_prev, tau_prev, v_now, dt: float) -> float:
        """Add the step (q_prev, v_prev) -> v_now under the applied Pinocchio force ``tau_prev``; return the estimate."""
        dt = as_real(dt, "dt", positive=True, unit="s")
        nv = self.platform.nv
        v_prev, v_now, tau_prev = as_vector(v_prev, nv, "v_prev"), as_vector(v_now, nv, "v_now"), as_vector(tau_prev, nv, "tau_prev")
        q_prev = check_q(self.platform, q_prev, "q_prev")
        if dt != self._last_dt:
            self._lam = math.exp(-dt / self.time_constant)
            self._last_dt = dt
        a = (v_now - v_prev) / dt
        tn, Y = self.regressor(q_prev, v_prev, a)
        r = tau_prev - tn
        lam = self._lam
        self._P = lam * self._P + float(Y @ Y)
        self._b = lam * self._b + float(Y @ r)
        self.samples += 1
        self.mass = min(self.max_mass, max(self.min_mass, self._b / self._P))
        return self.mass

    def estimate(self) -> MassEstimate:
        return MassEstimate(self.mass, self._P, self.samples)
