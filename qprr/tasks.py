"""Tasks and the strict task-priority (lexicographic) QP solver behind ``qprr.ik`` method "qp".

A task linearises one wish about the configuration at q as ``J dv = e``: ``J`` (dim x nv)
maps Pinocchio's tangent step dv (body-frame base twist, then arm rates, see
:mod:`qprr.coordinates`) to the change of the task quantity, ``e`` is the change wanted.
Tasks are plain objects: add one by subclassing :class:`Task` and implementing
``linearize``.

Contract of ``Task.linearize(robot, data, q)``: ``data`` already holds, at q, the joint
placements, frame placements, joint Jacobians and the centre of mass with its Jacobian,
as left by :func:`update_kinematics` (the solver calls it once per iteration).

:class:`HierarchySolver` solves levels in order.  Level k is the QP

    min_dv  ||J_k dv - e_k||^2 + eps ||dv - dv_{k-1}*||^2     (dv_0* = 0)
    s.t.    J_j dv = J_j dv_j*   for every level j < k   (their optimum is kept)
            lower - q_arm <= dv_arm <= upper - q_arm     (joint limits, hard, every level)

solved with proxsuite's dense ProxQP.  Two equivalent ways of keeping the optimum of the
earlier levels are implemented: ``"nullspace"`` (default: dv = dv_{k-1}* + Z z with Z an
orthonormal basis of the kernel of the stacked earlier Jacobians, so each QP has only the
free directions as unknowns and the joint limits as inequalities) and ``"equality"``
(the literal form above, the earlier levels as equality constraints of a QP in dv).
The minimisers of a least-squares objective over a convex set all share the same J_k dv,
so both forms keep the earlier optimum exactly; a test checks they agree.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from proxsuite import proxqp

from .coordinates import as_vector
from .errors import InputError, LimitError, SolverError, UnknownNameError
from .model import Robot

try:  # LAPACK's SVD without numpy.linalg's wrapper: 3x cheaper on these tiny matrices
    from scipy.linalg.lapack import dgesdd as _dgesdd  # scipy is a dependency of proxsuite
except ImportError:  # pragma: no cover
    _dgesdd = None


def _right_singular(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(singular values, V^T full) of B."""
    if _dgesdd is not None:
        _, s, Vt, info = _dgesdd(B)
        if info == 0:
            return s, Vt
    _, s, Vt = np.linalg.svd(B)
    return s, Vt


_SOLVED = proxqp.QPSolverOutput.PROXQP_SOLVED


def update_kinematics(robot: Robot, data: pin.Data, q: np.ndarray) -> None:
    """Fill ``data`` at q with what :meth:`Task.linearize` may read.

    Joint placements and Jacobians (``computeJointJacobians``), frame placements and the
    centre of mass with its world Jacobian ``data.Jcom`` (``jacobianCenterOfMass``).
    """
    model = robot.model
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    pin.jacobianCenterOfMass(model, data, False)


class Task(ABC):
    """One wish about the configuration, linearised as J dv = e (see the module docstring)."""

    name: str = "task"
    dim: int = 0

    @abstractmethod
    def linearize(self, robot: Robot, data: pin.Data, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(J, e): J of shape (dim, nv) and the wanted change e of shape (dim,)."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, dim={self.dim})"


def _sqrt_weights(weights, n: int, name: str) -> np.ndarray | None:
    """sqrt of positive row weights (None: unit weights, nothing to scale)."""
    if weights is None:
        return None
    w = as_vector(weights, n, name)
    if np.any(w <= 0.0):
        raise InputError(f"{name} must be positive, got {w.tolist()}")
    return np.sqrt(w)


def _scaled(sw, J, e):
    return (J, e) if sw is None else (sw[:, None] * J, sw * e)


class PoseTask(Task):
    """End-effector (or any frame) pose: f = log6(M_d^-1 M(q)) -> 0, J = Jlog6(M_d^-1 M) J_local.

    ``target`` is the desired world placement of ``frame`` (default: the end effector);
    ``weights`` (6,) scale the [translation, rotation] rows of the error (metres and radians).
    """

    dim = 6

    def __init__(self, robot: Robot, target: pin.SE3, frame: int | None = None, weights=None, name: str = "pose"):
        if not isinstance(target, pin.SE3):
            raise InputError(f"PoseTask target must be a pinocchio.SE3, got {type(target).__name__}")
        self.frame = robot.ee_frame if frame is None else int(frame)
        if not 0 <= self.frame < robot.model.nframes:
            raise InputError(f"frame id {self.frame} out of range [0, {robot.model.nframes})")
        self.target = target
        self._target_inv = target.inverse()
        self._sw = _sqrt_weights(weights, 6, "PoseTask weights")
        self.name = name

    def linearize(self, robot, data, q):
        J = pin.getFrameJacobian(robot.model, data, self.frame, pin.LOCAL)
        M = self._target_inv * data.oMf[self.frame]
        return _scaled(self._sw, pin.Jlog6(M) @ J, -pin.log6(M).vector)


class HoverTask(Task):
    """Hover feasibility: the thrust axis z_B vertical, i.e. roll = pitch = 0.

    A multirotor holds still only with its thrust along gravity.  The task drives the
    horizontal components of z_B = R_b e3 (world) to zero; unlike the Euler angles it has
    no singularity.  d(R_b e3)/dt = -R_b hat(e3) omega_body.
    """

    dim = 2

    def __init__(self, name: str = "hover"):
        self.name = name

    def linearize(self, robot, data, q):
        R = data.oMi[1].rotation
        J = np.zeros((2, robot.nv))
        # -R hat(e3) = [-r_y, r_x, 0] (columns of R)
        J[:, 3] = -R[0:2, 1]
        J[:, 4] = R[0:2, 0]
        return J, -R[0:2, 2]


class ComTask(Task):
    """System centre of gravity on the thrust axis: [x_cm, y_cm] (body frame B) -> ``target_xy``.

    Jacobian from Pinocchio's CoM Jacobian, as :func:`qprr.model.com_jacobian_body`:
    d/dt R^T (c - p) = R^T J_c v - v_lin - omega x (R^T (c - p)).
    """

    dim = 2

    def __init__(self, target_xy=(0.0, 0.0), weights=None, name: str = "com"):
        self.target = np.zeros(2) if target_xy == (0.0, 0.0) else as_vector(target_xy, 2, "ComTask target_xy")
        self._sw = _sqrt_weights(weights, 2, "ComTask weights")
        self.name = name

    def linearize(self, robot, data, q):
        base = data.oMi[1]
        Rt = base.rotation.T
        x, y, z = (Rt @ (data.com[0] - base.translation)).tolist()
        J = Rt[0:2] @ data.Jcom
        J[0, 0] -= 1.0
        J[1, 1] -= 1.0
        # rows 0, 1 of hat(c_b) = [[0, -z, y], [z, 0, -x]]
        J[0, 4] -= z
        J[0, 5] += y
        J[1, 3] += z
        J[1, 5] -= x
        return _scaled(self._sw, J, self.target - (x, y))


class PostureTask(Task):
    """Arm posture: [r0, theta2, theta3] -> ``q_arm_ref`` (the configuration entries 7..9)."""

    dim = 3

    def __init__(self, robot: Robot, q_arm_ref, weights=None, name: str = "posture"):
        ref = np.array(q_arm_ref, dtype=float)
        p = robot.params
        ok = ref.shape == (3,)
        if ok:
            r0, t2, t3 = ref.tolist()  # NaN fails every comparison below
            ok = (p.r0_limits[0] - 1e-12 <= r0 <= p.r0_limits[1] + 1e-12
                  and p.theta2_limits[0] - 1e-12 <= t2 <= p.theta2_limits[1] + 1e-12
                  and p.theta3_limits[0] - 1e-12 <= t3 <= p.theta3_limits[1] + 1e-12)
        if not ok:
            robot.check_arm_limits(ref, "PostureTask q_arm_ref")  # raises with the details
            raise LimitError(f"PostureTask q_arm_ref {ref.tolist()} invalid")  # pragma: no cover
        self.ref = ref
        self._sw = _sqrt_weights(weights, 3, "PostureTask weights")
        self.name = name
        self._J = np.zeros((3, robot.nv))
        self._J[:, 6:9] = np.eye(3)

    def linearize(self, robot, data, q):
        return _scaled(self._sw, self._J, self.ref - q[7:10])


# ----------------------------------------------------------------------------- solver
ELIMINATIONS = ("nullspace", "equality")


@dataclass(frozen=True)
class HierarchyStep:
    """One solve of the hierarchy: the step dv, the linearised levels (J_k, e_k) and the
    total number of ProxQP iterations."""

    dv: np.ndarray
    linearized: list
    qp_iterations: int

    @property
    def residuals(self) -> tuple[float, ...]:
        """||J_k dv - e_k|| per level: what is left of each task after the step (linear model)."""
        return tuple(math.sqrt(float((J @ self.dv - e) @ (J @ self.dv - e))) for J, e in self.linearized)

    @property
    def errors(self) -> tuple[float, ...]:
        """||e_k|| per level: each task's error before the step."""
        return tuple(math.sqrt(float(e @ e)) for _, e in self.linearized)


class HierarchySolver:
    """Lexicographic least squares with hard joint limits, one ProxQP per level.

    ``eps_abs``: ProxQP absolute tolerance (eps_rel = 0).  ``regularization``: eps of the
    module docstring, a Levenberg damping of every level: it makes each QP strictly convex
    and keeps rounding noise out of the directions a level does not see (noise / eps);
    it shortens the step, never moves a fixed point (where every gradient vanishes).
    1e-7 needs the fewest Newton iterations on the benchmark targets (1e-12..1e-5 tried).
    ``rank_tol``: singular values below it (absolute) count as zero when the kernel of a
    level is computed.  Not thread-safe: the QP objects are reused between calls.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        eps_abs: float = 1e-9,
        regularization: float = 1e-7,
        rank_tol: float = 1e-9,
        elimination: str = "nullspace",
        max_qp_iter: int = 1000,
    ):
        if elimination not in ELIMINATIONS:
            raise UnknownNameError("elimination", elimination, ELIMINATIONS)
        for name, val in (("eps_abs", eps_abs), ("rank_tol", rank_tol)):
            if not (np.isfinite(val) and val > 0):
                raise InputError(f"{name} must be finite and > 0, got {val!r}")
        if not (np.isfinite(regularization) and regularization >= 0):
            raise InputError(f"regularization must be finite and >= 0, got {regularization!r}")
        self.robot = robot
        self.nv = robot.nv
        self.eps_abs = float(eps_abs)
        self.regularization = float(regularization)
        self.rank_tol = float(rank_tol)
        self.elimination = elimination
        self.max_qp_iter = int(max_qp_iter)
        model = robot.model
        self.iq = np.array([model.joints[j].idx_q for j in robot.arm_joint_ids])
        self.iv = np.array([model.joints[j].idx_v for j in robot.arm_joint_ids])
        if np.array_equal(self.iv, np.arange(self.iv[0], self.iv[0] + len(self.iv))):  # views, not copies
            self.iv = slice(int(self.iv[0]), int(self.iv[0]) + len(self.iv))
        if np.array_equal(self.iq, np.arange(self.iq[0], self.iq[0] + len(self.iq))):
            self.iq = slice(int(self.iq[0]), int(self.iq[0]) + len(self.iq))
        self._C_full = np.eye(self.nv)[self.iv]
        self.lower = model.lowerPositionLimit[self.iq].copy()
        self.upper = model.upperPositionLimit[self.iq].copy()
        self._n_in = self._C_full.shape[0]
        self._qps: dict[tuple[int, int], proxqp.dense.QP] = {}
        self._warm: dict[int, tuple] = {}
        self._fresh: set = set()

    def reset(self) -> None:
        """Forget warm starts (called at the start of every IK solve, for determinism)."""
        self._warm.clear()
        self._fresh = set(self._qps)

    def _qp(self, n: int, n_eq: int) -> proxqp.dense.QP:
        key = (n, n_eq)
        qp = self._qps.get(key)
        if qp is None:
            qp = proxqp.dense.QP(n, n_eq, self._n_in)
            s = qp.settings
            s.eps_abs = self.eps_abs
            s.eps_rel = 0.0
            # Each level is feasible by construction (the previous optimum satisfies all its
            # constraints) and strictly convex: an infeasibility verdict could only be a false
            # positive, so the detection thresholds sit far below eps_abs.
            s.eps_primal_inf = 1e-14
            s.eps_dual_inf = 1e-14
            # Small primal proximal step and stiff inequality penalty: these QPs are tiny and
            # well scaled, and these values cut the iterations with an active joint limit
            # from ~12 to ~4 (benchmarks/ik_benchmark.py) without changing the optimum.
            s.default_rho = 1e-8
            s.default_mu_in = 1e-4
            s.default_mu_eq = 1e-6
            s.max_iter = self.max_qp_iter
            s.verbose = False
            self._qps[key] = qp
            self._fresh.add(key)
        return qp

    def _solve_qp(self, level: int, H, g, A, b, C, lo, up) -> tuple[np.ndarray, int]:
        n = H.shape[0]
        n_eq = 0 if A is None else A.shape[0]
        key = (n, n_eq)
        qp = self._qps.get(key) or self._qp(n, n_eq)
        if n_eq or key in self._fresh:  # stacked equalities change scale: fresh preconditioner
            qp.init(H, g, A, b, C, lo, up)
            self._fresh.discard(key)
        else:
            qp.update(H, g, A, b, C, lo, up)
        warm = self._warm.get(level)
        if warm is not None and warm[0].shape[0] == n and warm[1].shape[0] == n_eq:
            qp.solve(warm[0], warm[1], warm[2])
        else:
            qp.solve()
        res = qp.results
        info = res.info
        if info.status != _SOLVED:
            raise SolverError(
                f"ProxQP did not solve level {level + 1} (n = {n}, n_eq = {n_eq}): status {info.status.name}, "
                f"primal residual {info.pri_res:.3g}, dual residual {info.dua_res:.3g}"
            )
        x = res.x.copy()
        self._warm[level] = (x, res.y.copy(), res.z.copy())
        return x, info.iter

    def solve(self, robot: Robot, data: pin.Data, q: np.ndarray, levels) -> HierarchyStep:
        """The hierarchical step dv at q for ``levels`` (a sequence of sequences of tasks).

        Call :func:`update_kinematics` at q first.  Raises SolverError if a QP fails.
        """
        lin = []
        for tasks in levels:
            if len(tasks) == 1:
                lin.append(tasks[0].linearize(robot, data, q))
            else:
                Js, es = zip(*(t.linearize(robot, data, q) for t in tasks))
                lin.append((np.vstack(Js), np.concatenate(es)))
        q_arm = q[self.iq]
        lo_arm = self.lower - q_arm
        up_arm = self.upper - q_arm
        if self.elimination == "nullspace":
            dv, iters = self._solve_nullspace(lin, lo_arm, up_arm)
        else:
            dv, iters = self._solve_equality(lin, lo_arm, up_arm)
        return HierarchyStep(dv, lin, iters)

    def _solve_nullspace(self, lin, lo_arm, up_arm):
        reg, iv, tol = self.regularization, self.iv, self.rank_tol
        last = len(lin) - 1
        # level 1 over the whole tangent space
        J, e = lin[0]
        H = J.T @ J
        H.flat[:: self.nv + 1] += reg
        dv, iters = self._solve_qp(0, H, -(J.T @ e), None, None, self._C_full, lo_arm, up_arm)
        Z = None
        B = J
        for k in range(1, last + 1):
            s, Vt = _right_singular(B)  # kernel of the level just solved, inside the current Z
            N = Vt[int(np.count_nonzero(s > tol)):].T
            Z = N if Z is None else Z @ N
            m = Z.shape[1]
            if m == 0:
                break
            J, e = lin[k]
            B = J @ Z
            H = B.T @ B
            H.flat[:: m + 1] += reg
            d_arm = dv[iv]
            # z = 0 (the earlier optimum) must stay feasible: ProxQP meets the bounds only to
            # eps_abs, so a bound the earlier step overshot by that slack is moved onto it.
            lo_z = np.minimum(lo_arm - d_arm, 0.0)
            up_z = np.maximum(up_arm - d_arm, 0.0)
            z, it = self._solve_qp(k, H, B.T @ (J @ dv - e), None, None, Z[iv], lo_z, up_z)
            iters += it
            dv += Z @ z
        return dv, iters

    def _solve_equality(self, lin, lo_arm, up_arm):
        nv = self.nv
        reg = self.regularization
        C = self._C_full
        stack = np.zeros((0, nv))
        A = None  # orthonormal rows spanning the stacked earlier Jacobians
        dv = np.zeros(nv)
        iters = 0
        for k, (J, e) in enumerate(lin):
            if A is not None and A.shape[0] == nv:
                break  # the earlier levels fix dv completely
            H = J.T @ J
            H.flat[:: nv + 1] += reg
            g = -J.T @ e - reg * dv  # damping of the increment dv - dv_{k-1}*, as in "nullspace"
            # J_j dv = J_j dv_j* for all j < k  <=>  A dv = A dv_{k-1}*, with A the
            # rank-revealing compression of the stack (redundant rows stall ProxQP).
            b = None if A is None else A @ dv
            d_arm = dv[self.iv]  # keep the earlier optimum feasible despite ProxQP's eps_abs slack
            dv, it = self._solve_qp(k, H, g, A, b, C, np.minimum(lo_arm, d_arm), np.maximum(up_arm, d_arm))
            iters += it
            stack = np.vstack([stack, J])
            s, Vt = _right_singular(stack)
            A = Vt[: int(np.count_nonzero(s > self.rank_tol))]
        return dv, iters
