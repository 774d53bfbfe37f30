"""Mobile manipulation: an arm on a wheeled base, task-priority IK under the Pfaffian constraint.

:class:`MobileManipulator` mounts any fixed-base Pinocchio arm model (an end-effector frame
name, a mount placement in the chassis frame) on a kinematic model of
:mod:`qprr.wheeled.robots`.  The combined Pinocchio model is the planar chassis (prismatic x,
prismatic y, revolute z joints, the lecture's posture (x, y, theta)) with the arm appended by
``pin.appendModel``; the user's arm model is never modified.  The configuration is
z = [q_base, q_arm] (q_base: the wheeled model's coordinates, e.g. [x, y, theta, psi] for the
car) and the IK step dz = [dq_base, v_arm].

:func:`solve_ik` is a strict task-priority IK (levels solved in order, each keeping the
optimum of those above) on the project's lexicographic engine :class:`qprr.actuation.lexicographic.Lexicographic`
(null-space elimination on proxsuite's dense ProxQP), where **every level** carries

* the Pfaffian constraint of the base, A^T(q_base) dq_base = 0 (the base can only move along
  B(q_base): Lecture "forme pfaffienne", "q_dot in ker A^T(q)"), as the engine's hard
  ``equality``: every level's unknowns are restricted to the kernel of E = [A^T, 0], so each
  step meets it to rounding,
* the joint limits of the arm and the steering limits, and a trust region on the step,

and the levels are: 1. the end-effector position; 2. for a steered base, the steering angle
under which level 1 would progress most (:func:`lookahead_steering`: the end-effector task
cannot see the steering angle to first order, which acts only through the heading rate it
gives the drive).  A Levenberg damping in every level keeps each QP strictly convex.
After each QP the base moves by the exact flow of the inputs u = B^+ dq_base
(:mod:`qprr.wheeled.sim`), so the base path is a motion the wheels can roll along.
``respect_constraint=False`` drops the equality and moves the base by dq_base directly: the
IK that ignores the constraint, whose violation ``slip`` measures.  :func:`step_problem` builds
the levels, the constraint and the bounds of one step; :func:`step_solver` the engine.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, fields, replace
from enum import Enum
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..actuation.lexicographic import Lexicographic, QPSettings
from ..errors import InputError, LimitError, SolverError, UnknownNameError
from ..validation import as_real, as_vector
from .kinematics import KinematicModel
from .robots import Car, FrontTricycle, RearTricycle


# ============================================================================ arms
def qprr_arm(urdf_path: str | Path | None = None) -> pin.Model:
    """The Q-PRR's arm as a fixed-base model: the multirotor body is the fixed root link.

    Joints r0 (prismatic along x), theta2, theta3 (about y), end-effector frame "end_effector";
    from ``urdf_path`` (a URDF without a free flyer) or :meth:`qprr.Platform.arm_model` of
    ``qprr.load()`` (the default platform, :data:`qprr.platforms.DEFAULT_PLATFORM`: the Q-PRR).
    """
    if urdf_path is None:
        from ..platforms import DEFAULT_PLATFORM, load

        return load(DEFAULT_PLATFORM).arm_model()
    return pin.buildModelFromUrdf(str(urdf_path))


def three_r_arm(l1: float = 0.25, l2: float = 0.35, l3: float = 0.3) -> pin.Model:
    """A 3R arm (yaw, shoulder pitch, elbow pitch) built in Pinocchio; frame "end_effector".

    Shoulder at height l1 above the base, upper arm l2, forearm l3 [m]; links are thin rods of
    1 kg/m.  Limits: yaw +-pi, shoulder +-pi/2, elbow +-2.6 rad.
    """
    l1, l2, l3 = (as_real(v, name, positive=True, unit="m") for name, v in (("l1", l1), ("l2", l2), ("l3", l3)))
    m = pin.Model()
    m.name = "3R arm"
    j1 = m.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "yaw")
    j2 = m.addJoint(j1, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.0, 0.0, l1])), "shoulder")
    j3 = m.addJoint(j2, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.0, 0.0, l2])), "elbow")
    for j, length in ((j1, l1), (j2, l2), (j3, l3)):
        m.appendBodyToJoint(j, pin.Inertia.FromCylinder(length, 0.01, length), pin.SE3(np.eye(3), np.array([0.0, 0.0, length / 2])))
    m.addFrame(pin.Frame("end_effector", j3, pin.SE3(np.eye(3), np.array([0.0, 0.0, l3])), pin.FrameType.OP_FRAME))
    m.lowerPositionLimit = np.array([-math.pi, -math.pi / 2, -2.6])
    m.upperPositionLimit = np.array([math.pi, math.pi / 2, 2.6])
    return m


# ============================================================================ the robot
class MobileManipulator:
    """An arm (fixed-base Pinocchio model, end-effector frame ``ee_frame``) on a wheeled base.

    ``mount``: placement of the arm's root frame in the chassis frame (origin O_R of the
    wheeled model: the rear-axle centre for the car).  Steering limits: the base's
    ``psi_max`` when it has one (the car), else ``steering_limit`` [rad].
    """

    def __init__(
        self, base: KinematicModel, arm: pin.Model, ee_frame: str = "end_effector", mount: pin.SE3 | None = None, *, steering_limit: float = 1.2
    ):
        if not isinstance(base, KinematicModel):
            raise InputError(f"base must be a wheeled KinematicModel, got {type(base).__name__}")
        if tuple(base.coordinates[:3]) != ("x", "y", "theta"):
            raise InputError(f"base {base.name!r} must start with the posture (x, y, theta), has {base.coordinates}")
        if not isinstance(arm, pin.Model):
            raise InputError(f"arm must be a pinocchio.Model, got {type(arm).__name__}")
        for j in range(1, arm.njoints):
            if arm.joints[j].shortname() in ("JointModelFreeFlyer", "JointModelPlanar", "JointModelSpherical"):
                raise InputError(f"arm joint {arm.names[j]!r} is a {arm.joints[j].shortname()}: pass a fixed-base arm model")
        if not arm.existFrame(ee_frame):
            raise UnknownNameError("end-effector frame", ee_frame, [f.name for f in arm.frames])
        if mount is None:
            mount = pin.SE3.Identity()
        if not isinstance(mount, pin.SE3):
            raise InputError(f"mount must be a pinocchio.SE3, got {type(mount).__name__}")
        self.base = base
        self.ee_frame_name = ee_frame
        self.mount = mount.copy()
        bm = pin.Model()
        bm.name = f"{base.name} base"
        jx = bm.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "base_x")
        jy = bm.addJoint(jx, pin.JointModelPY(), pin.SE3.Identity(), "base_y")
        jt = bm.addJoint(jy, pin.JointModelRZ(), pin.SE3.Identity(), "base_theta")
        chassis = bm.addFrame(pin.Frame("chassis", jt, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
        self.model = pin.appendModel(bm, arm, chassis, self.mount)
        self.model.name = f"{arm.name or 'arm'} on {base.name}"
        self.data = self.model.createData()
        self.ee_frame = self.model.getFrameId(ee_frame)
        self.n_base = base.n
        self.nq_arm = arm.nq
        self.nv_arm = arm.nv
        self.nz = self.n_base + self.nv_arm
        # bounds on z (configuration) for the coordinates that have them: arm joints with nq = nv = 1, steering
        lo, up = np.full(self.nz, -np.inf), np.full(self.nz, np.inf)
        for j in range(4, self.model.njoints):
            jm = self.model.joints[j]
            if jm.nq == 1 and jm.nv == 1:
                iv = self.n_base + jm.idx_v - 3
                lo[iv] = self.model.lowerPositionLimit[jm.idx_q]
                up[iv] = self.model.upperPositionLimit[jm.idx_q]
        psi_max = float(base.psi_max if isinstance(base, Car) else steering_limit)
        lo[3 : self.n_base], up[3 : self.n_base] = -psi_max, psi_max
        lo[lo < -1e300], up[up > 1e300] = -np.inf, np.inf
        self.lower, self.upper = lo, up

    # ------------------------------------------------------------ configurations
    def neutral(self, base_pose=(0.0, 0.0, 0.0)) -> np.ndarray:
        """z with the base at ``base_pose`` (x, y, theta), steering 0 and the arm at Pinocchio's neutral."""
        z = np.zeros(self.n_base + self.nq_arm)
        z[0:3] = as_vector(base_pose, 3, "base_pose")
        z[self.n_base :] = pin.neutral(self.model)[3:]
        return z

    def check_z(self, z, name: str = "z") -> np.ndarray:
        return as_vector(z, self.n_base + self.nq_arm, f"{name} (base {list(self.base.coordinates)} + {self.nq_arm} arm)")

    def pin_q(self, z) -> np.ndarray:
        """Pinocchio configuration [x, y, theta, q_arm] of z."""
        return np.concatenate([z[0:3], z[self.n_base :]])

    def ee_position(self, z) -> np.ndarray:
        """End-effector position in the world frame [m]."""
        z = self.check_z(z)
        pin.framesForwardKinematics(self.model, self.data, self.pin_q(z))
        return self.data.oMf[self.ee_frame].translation.copy()

    def ee_jacobian(self, z) -> np.ndarray:
        """d p_ee / d z (3 x nz) in the world frame: columns x, y, theta, steering (zero), arm."""
        q = self.pin_q(z)
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        J6 = pin.getFrameJacobian(self.model, self.data, self.ee_frame, pin.LOCAL_WORLD_ALIGNED)
        J = np.zeros((3, self.nz))
        J[:, 0:3] = J6[0:3, 0:3]
        J[:, self.n_base :] = J6[0:3, 3:]
        return J

    def within_limits(self, z, tol: float = 1e-9) -> bool:
        z = self.check_z(z)
        v = self.config_as_tangent(z)
        return bool(np.all(v >= self.lower - tol) and np.all(v <= self.upper + tol))

    def config_as_tangent(self, z) -> np.ndarray:
        """The bounded coordinates of z laid out like dz (arm joints with nq = nv = 1): what the limits bound."""
        out = np.zeros(self.nz)
        out[0 : self.n_base] = z[0 : self.n_base]
        for j in range(4, self.model.njoints):
            jm = self.model.joints[j]
            if jm.nq == 1 and jm.nv == 1:
                out[self.n_base + jm.idx_v - 3] = z[self.n_base + jm.idx_q - 3]
        return out

    def __repr__(self) -> str:
        return f"MobileManipulator({self.model.name!r}, z = {list(self.base.coordinates)} + {self.nq_arm} arm coordinates)"


# ============================================================================ IK
class IKStatus(str, Enum):
    CONVERGED = "converged"
    STALLED = "stalled"
    MAX_ITERATIONS = "max_iterations"
    SOLVER_ERROR = "solver_error"


@dataclass(frozen=True)
class MobileIKOptions:
    """Options of :func:`solve_ik` (lengths in m, angles in rad).

    ``tol``: end-effector position error for convergence; ``max_iter``; ``stall_iter``:
    iterations without a relative error decrease of 1e-9 before "stalled"; trust region per
    iteration: ``step_xy``, ``step_theta``, ``step_steer``, ``step_arm``;
    ``respect_constraint``: impose the Pfaffian constraint (False: the IK that ignores it).
    The QP engine is :class:`qprr.actuation.lexicographic.Lexicographic` (:func:`step_solver`): ``eps_abs``,
    ``eps_duality_gap`` (absolute, checked) and ``max_qp_iter`` are its
    :class:`~qprr.actuation.lexicographic.QPSettings` (eps_rel = 0, infeasibility thresholds 1e-14);
    ``regularization``: its Levenberg damping of every level, which also picks the smallest
    step among a level's minimisers; ``polish``: each QP answer replaced by the exact optimum on
    its active set (residuals compared by :func:`lookahead_steering` exact, not to eps_abs);
    ``exact_fallback``: a level where ProxQP stops at ``max_qp_iter`` is solved exactly by
    :func:`qprr.actuation.lexicographic.active_set_qp` instead of ending the run with "solver_error" (ProxQP
    0.8 stalls at degenerate vertices, e.g. 2 free directions and 5 bounds, two of them rows
    of rounding size active at 0, met in ``benchmarks/wheeled_ik_benchmark.py``);
    ``rank_tol``: its kernel tolerance, **absolute** (as everywhere in :mod:`qprr.actuation.lexicographic`):
    singular values of the Pfaffian matrix and of each level's Jacobian restricted to the free
    directions below it count as zero.  (The rows are O(1): unit no-slip rows with lever arms of
    ~0.5 m, end-effector Jacobians in m/m and m/rad, largest singular values 1.1-1.8 on the car
    scenarios, so this differs from a tolerance relative to the largest singular value by that
    factor only.)
    """

    tol: float = 1e-6
    max_iter: int = 400
    stall_iter: int = 40
    step_xy: float = 0.05
    step_theta: float = 0.1
    step_steer: float = 0.1
    step_arm: float = 0.1
    respect_constraint: bool = True
    eps_abs: float = 1e-9
    eps_duality_gap: float = 1e-9
    max_qp_iter: int = 1000
    regularization: float = 1e-3
    rank_tol: float = 1e-9
    polish: bool = True
    exact_fallback: bool = True

    def __post_init__(self):
        for f in ("respect_constraint", "polish", "exact_fallback"):
            if not isinstance(getattr(self, f), bool):
                raise InputError(f"option {f} must be True or False, got {getattr(self, f)!r}")
        for f in ("tol", "step_xy", "step_theta", "step_steer", "step_arm", "eps_abs", "eps_duality_gap", "rank_tol"):
            v = getattr(self, f)
            as_real(v, f"option {f}", positive=True)
        as_real(self.regularization, "option regularization", nonnegative=True)
        for f in ("max_iter", "stall_iter", "max_qp_iter"):
            v = getattr(self, f)
            if not (isinstance(v, int) and v >= 1):
                raise InputError(f"option {f} must be an integer >= 1, got {v!r}")

    def qp_settings(self) -> QPSettings:
        """The :class:`~qprr.actuation.lexicographic.QPSettings` of these options."""
        return QPSettings(
            eps_abs=self.eps_abs, eps_primal_inf=1e-14, eps_dual_inf=1e-14, eps_duality_gap=self.eps_duality_gap, max_iter=self.max_qp_iter
        )


def make_mobile_ik_options(options=None) -> MobileIKOptions:
    """Options from None, a :class:`MobileIKOptions` or a dict of overrides (unknown keys raise)."""
    if options is None:
        return MobileIKOptions()
    if isinstance(options, MobileIKOptions):
        return options
    if not isinstance(options, dict):
        raise InputError(f"options must be a dict or MobileIKOptions, got {type(options).__name__}")
    valid = [f.name for f in fields(MobileIKOptions)]
    for k in options:
        if k not in valid:
            raise UnknownNameError("mobile IK option", k, valid)
    return replace(MobileIKOptions(), **options)


@dataclass
class MobileIKResult:
    """Outcome of :func:`solve_ik`.

    ``path`` (iterations+1, n_base + nq_arm): z at every iteration; ``ee_error`` [m] per
    iterate (Pinocchio FK); ``qp_residual`` [m or rad per iteration]: max |A^T dq_base| of
    each QP solution (round-off when the constraint is imposed: every step lies in ker A^T by
    construction; the violation otherwise); ``applied_residual``: the same for the motion
    actually applied (B u: round-off when the constraint is respected); ``slip`` [m]: sum over
    iterations of |A^T dq_base| of the applied motion (the sideways skid of the constrained
    wheels; 0 up to round-off when the constraint is respected); ``base_travel`` [m]: path
    length of (x, y); ``base_inputs`` (iterations, n_inputs): the inputs u of each base step
    (its exact flow over 1 s; empty when the constraint is ignored).
    """

    success: bool
    status: IKStatus
    reason: str
    iterations: int
    z: np.ndarray
    path: np.ndarray
    ee_error: np.ndarray
    qp_residual: np.ndarray
    applied_residual: np.ndarray
    slip: float
    base_travel: float
    within_limits: bool
    respect_constraint: bool
    target: np.ndarray
    wall_time: float
    base_inputs: np.ndarray


def step_solver(robot: MobileManipulator, options=None) -> Lexicographic:
    """The engine of one IK step: :class:`qprr.actuation.lexicographic.Lexicographic` over dz (``robot.nz``), every
    coordinate bounded (trust region, limits), with ``options``' settings, damping and rank tolerance.

    It owns its QPs and warm starts: :func:`solve_ik` builds one per call (results depend on the
    inputs only).  A level it cannot solve raises :class:`~qprr.errors.SolverError`.
    """
    opts = make_mobile_ik_options(options)
    return Lexicographic(
        robot.nz,
        settings=opts.qp_settings(),
        regularization=opts.regularization,
        rank_tol=opts.rank_tol,
        polish=opts.polish,
        exact_fallback=opts.exact_fallback,
    )


def lookahead_solver(robot: MobileManipulator, options=None) -> Lexicographic:
    """The engine of :func:`lookahead_steering`: bounded least squares (one level) over (drive input, arm rates),
    with ``options``' QP settings and a damping of 1e-12 (the smallest minimiser; the residual it compares is
    unaffected)."""
    opts = make_mobile_ik_options(options)
    return Lexicographic(
        1 + robot.nv_arm,
        settings=opts.qp_settings(),
        regularization=1e-12,
        rank_tol=opts.rank_tol,
        polish=opts.polish,
        exact_fallback=opts.exact_fallback,
    )


def lookahead_steering(
    robot: MobileManipulator,
    z,
    J: np.ndarray,
    e: np.ndarray,
    lo: np.ndarray,
    up: np.ndarray,
    n_candidates: int = 13,
    *,
    solver: Lexicographic | None = None,
) -> float:
    """Steering angle under which the end-effector task would progress most (one-step lookahead).

    The end-effector position does not depend on the steering angle psi, so its task cannot
    steer (its Jacobian has a zero column there): psi acts only through the heading rate it
    gives the drive input.  For each candidate psi_c on a grid of [-psi_max, psi_max], the
    level-1 problem is solved with the base's drive column of B evaluated at psi_c (bounded
    least squares in the drive input and the arm rates, same trust region and limits, on
    ``solver``, default :func:`lookahead_solver`); the candidate leaving the smallest residual
    is returned (ties: the one closest to the current psi).  Reversing with the wheels turned
    the other way is found this way when driving forwards cannot help (the arm at a limit).
    Raises :class:`~qprr.errors.SolverError` if a QP fails.
    """
    base, nb = robot.base, robot.n_base
    if solver is None:
        solver = lookahead_solver(robot)
    elif not (isinstance(solver, Lexicographic) and solver.n == 1 + robot.nv_arm):
        raise InputError(
            f"solver must be a qprr.actuation.lexicographic.Lexicographic over {1 + robot.nv_arm} variables "
            f"(drive input and arm rates), got {solver!r}"
        )
    psi_max = float(robot.upper[3])
    cands = np.unique(np.concatenate([np.linspace(-psi_max, psi_max, n_candidates), [np.clip(z[3], -psi_max, psi_max)]]))
    arm = slice(nb, robot.nz)
    res = []
    for c in cands:
        qc = np.array([z[0], z[1], z[2], c])
        b = base.B(qc)[:, 0]
        col = J[:, 0:3] @ b[0:3]
        M = np.column_stack([col, J[:, arm]])
        scale = max(abs(b[0]), abs(b[1])) or 1.0
        lim = min(lo[0:2].min(), -1e-12) / scale, max(up[0:2].max(), 1e-12) / scale
        r = solver.solve([(M, e)], np.concatenate([[lim[0]], lo[arm]]), np.concatenate([[lim[1]], up[arm]]))
        res.append(r.residuals[0])
    res = np.array(res)
    best = res.min()
    ok = np.flatnonzero(res <= best * (1 + 1e-9) + 1e-15)
    return float(cands[ok[np.argmin(np.abs(cands[ok] - z[3]))]])


@dataclass(frozen=True)
class StepProblem:
    """One linearised step of :func:`solve_ik` at z: ``levels`` [(J_k, e_k)] in priority order (the
    end-effector position [m]; for a steered base under the constraint, the steering angle [rad]);
    ``equality`` E (n_constraints, nz): the Pfaffian constraint E dz = A^T(q_base) dq_base = 0 (None
    when ignored); ``lower``, ``upper`` (nz,): the bounds on dz (trust region, joint and steering
    limits; they contain 0)."""

    levels: list
    equality: np.ndarray | None
    lower: np.ndarray
    upper: np.ndarray


def step_problem(robot: MobileManipulator, z, target, options=None, *, lookahead: Lexicographic | None = None) -> StepProblem:
    """The strict-priority problem :func:`solve_ik` solves at z for the world position ``target`` [m].

    ``lookahead``: the solver of :func:`lookahead_steering` (default :func:`lookahead_solver`).
    """
    opts = make_mobile_ik_options(options)
    p_t = as_vector(target, 3, "target (world position)")
    z = robot.check_z(z)
    base, nb, nz = robot.base, robot.n_base, robot.nz
    step = np.full(nz, opts.step_arm)
    step[0:2], step[2] = opts.step_xy, opts.step_theta
    step[3:nb] = opts.step_steer
    J = robot.ee_jacobian(z)
    e = p_t - robot.ee_position(z)
    cur = robot.config_as_tangent(z)
    lo = np.minimum(np.maximum(-step, robot.lower - cur), 0.0)
    up = np.maximum(np.minimum(step, robot.upper - cur), 0.0)
    levels = [(J, e)]
    E = None
    if opts.respect_constraint:
        if isinstance(base, (RearTricycle, FrontTricycle)) and nb == 4:  # steered: level 2 chooses the steering angle
            Js = np.zeros((1, nz))
            Js[0, 3] = 1.0
            psi = lookahead_steering(robot, z, J, e, lo, up, solver=lookahead or lookahead_solver(robot, opts))
            levels.append((Js, np.array([psi - z[3]])))
        A = base.A(z[0:nb])
        if A.size:
            E = np.zeros((A.shape[1], nz))
            E[:, 0:nb] = A.T
    return StepProblem(levels, E, lo, up)


def _apply_step(robot: MobileManipulator, z: np.ndarray, dz: np.ndarray, respect_constraint: bool):
    """(z after the step dz, |A^T dq_base|_max of the QP's step, (|A^T applied|_max, |A^T applied|) of the step taken,
    the base inputs u or None): with ``respect_constraint`` the base moves by the flow of the inputs that realise its
    step (the constraint holds exactly), else by dz itself (the QP's rounding slips)."""
    base, nb = robot.base, robot.n_base
    A = base.A(z[0:nb])
    dq_base = dz[0:nb]
    r_qp = float(np.max(np.abs(A.T @ dq_base))) if A.size else 0.0
    u = None
    if respect_constraint:
        u = base.inputs_of(z[0:nb], dq_base)
        applied = base.B(z[0:nb]) @ u
        z_base = base.flow(z[0:nb], u, 1.0)
    else:
        applied = dq_base
        z_base = z[0:nb] + dq_base
    r_app = (float(np.max(np.abs(A.T @ applied))), float(np.linalg.norm(A.T @ applied))) if A.size else (0.0, 0.0)
    q_pin = pin.integrate(robot.model, robot.pin_q(z), np.concatenate([np.zeros(3), dz[nb:]]))
    return np.concatenate([z_base, q_pin[3:]]), r_qp, r_app, u


def solve_ik(robot: MobileManipulator, target, z0, options=None) -> MobileIKResult:
    """Move the end effector to ``target`` (world position [m]) from z0 (see the module docstring).

    Each iteration solves :func:`step_problem` on :func:`step_solver` (both solvers are built
    once per call).  Returns a :class:`MobileIKResult`; raises on bad input (shape, non-finite,
    z0 outside the limits, unknown option).  A QP failure ends the run with status
    "solver_error" and the engine's message as reason.
    """
    if not isinstance(robot, MobileManipulator):
        raise InputError(f"robot must be a MobileManipulator, got {type(robot).__name__}")
    opts = make_mobile_ik_options(options)
    p_t = as_vector(target, 3, "target (world position)")
    z = robot.check_z(z0, "z0").copy()
    if not robot.within_limits(z):
        raise LimitError(f"z0 {z.tolist()} is outside the limits (steering and arm joints)")
    base = robot.base
    solver, lookahead = step_solver(robot, opts), lookahead_solver(robot, opts)
    t0 = time.perf_counter()
    path, errs, qp_res, app_res, inputs = [z.copy()], [], [], [], []
    slip = 0.0
    p = robot.ee_position(z)
    errs.append(float(np.linalg.norm(p_t - p)))
    best, since = errs[0], 0
    status, reason = IKStatus.MAX_ITERATIONS, f"{opts.max_iter} iterations, error {errs[-1]:.3g} m"
    it = 0
    for it in range(1, opts.max_iter + 1):
        if errs[-1] <= opts.tol:
            status, reason, it = IKStatus.CONVERGED, f"end-effector error {errs[-1]:.2g} m <= {opts.tol:g} m", it - 1
            break
        try:
            prob = step_problem(robot, z, p_t, opts, lookahead=lookahead)
            dz = solver.solve(prob.levels, prob.lower, prob.upper, equality=prob.equality).x
        except SolverError as err:
            status, reason, it = IKStatus.SOLVER_ERROR, str(err), it - 1
            break
        z, r_qp, r_app, u = _apply_step(robot, z, dz, opts.respect_constraint)
        if u is not None:
            inputs.append(u)
        slip += r_app[1]
        qp_res.append(r_qp)
        app_res.append(r_app[0])
        path.append(z.copy())
        p = robot.ee_position(z)
        errs.append(float(np.linalg.norm(p_t - p)))
        if errs[-1] < best * (1 - 1e-9):
            best, since = errs[-1], 0
        else:
            since += 1
            if since >= opts.stall_iter:
                status, reason = IKStatus.STALLED, f"no progress in {opts.stall_iter} iterations, error {errs[-1]:.3g} m"
                break
    else:
        if errs[-1] <= opts.tol:
            status, reason = IKStatus.CONVERGED, f"end-effector error {errs[-1]:.2g} m <= {opts.tol:g} m"
    P = np.array(path)
    travel = float(np.sum(np.hypot(np.diff(P[:, 0]), np.diff(P[:, 1]))))
    return MobileIKResult(
        status is IKStatus.CONVERGED,
        status,
        reason,
        len(path) - 1,
        z,
        P,
        np.array(errs),
        np.array(qp_res),
        np.array(app_res),
        slip,
        travel,
        robot.within_limits(z),
        opts.respect_constraint,
        p_t,
        time.perf_counter() - t0,
        np.array(inputs).reshape(-1, base.n_inputs),
    )


# ============================================================================ scenario
@dataclass(frozen=True)
class MobileScenario:
    """The lecture's manoeuvre: a target beside a car-like robot (or any base), out of the arm's reach."""

    robot: MobileManipulator
    z0: np.ndarray
    target: np.ndarray
    description: str


def car_scenario(arm: str = "qprr") -> MobileScenario:
    """Car (D = 0.5 m, front track 0.4 m, |psi| <= 0.6 rad) with an arm on its front bumper
    (0.6 m ahead of the rear axle, 0.3 m high), at the origin heading +x; target 1.2 m to
    the left, 1.0 m ahead, 0.5 m high.

    ``arm`` "qprr": the Q-PRR arm (planar: it reaches only the chassis's vertical x-z
    plane, so the car must turn until that plane passes through the target); "3r": the 3R
    arm of :func:`three_r_arm` (reach 0.65 m: the target 1.2 m to the side still needs the
    car to drive).  Either way the target is reachable only by moving forward and turning.
    """

    arms = {"qprr": (qprr_arm, "end_effector"), "3r": (three_r_arm, "end_effector")}
    if arm not in arms:
        raise UnknownNameError("arm", arm, tuple(arms))
    make, frame = arms[arm]
    mm = MobileManipulator(Car(), make(), frame, pin.SE3(np.eye(3), np.array([0.6, 0.0, 0.3])))
    text = f"car + {arm} arm: target 1.2 m to the left of the chassis, beyond the arm's reach"
    return MobileScenario(mm, mm.neutral(), np.array([1.0, 1.2, 0.5]), text)


__all__ = [
    "IKStatus",
    "MobileIKOptions",
    "MobileIKResult",
    "MobileManipulator",
    "MobileScenario",
    "StepProblem",
    "car_scenario",
    "lookahead_solver",
    "lookahead_steering",
    "make_mobile_ik_options",
    "qprr_arm",
    "solve_ik",
    "step_problem",
    "step_solver",
    "three_r_arm",
]
