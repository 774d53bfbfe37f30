"""The strict task-priority (lexicographic) step of the QP IK.

Level k is the QP

    min_dv  ||J_k dv - e_k||^2 + eps ||dv - dv_{k-1}*||^2     (dv_0* = 0)
    s.t.    J_j dv = J_j dv_j*   for every level j < k   (their optimum is kept)
            lower - q_arm <= dv_arm <= upper - q_arm     (joint limits, hard, every level)

solved by :class:`qprr.optim.Lexicographic` (``"nullspace"``: the free directions of the earlier
levels as unknowns, the default) or literally with the earlier levels as equality constraints
(``"equality"``, a cross-check).  The minimisers of a least-squares objective over a convex set
all share the same J_k dv, so both forms keep the earlier optimum exactly; a test checks they
agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from proxsuite import proxqp

from ..charts import as_int, as_real
from ..errors import SolverError, UnknownNameError
from ..optim import Lexicographic, QPSettings, polish_box_qp, right_singular
from ..platform import Platform, check_platform
from .tasks.base import check_linearized

ELIMINATIONS = ("nullspace", "equality")
_SOLVED = proxqp.QPSolverOutput.PROXQP_SOLVED
_MAX_ITER = proxqp.QPSolverOutput.PROXQP_MAX_ITER_REACHED


@dataclass(frozen=True)
class HierarchyStep:
    """One solve of the hierarchy: the step dv, the linearised levels (J_k, e_k), ProxQP iterations,
    and ``dv_first``, the step of level 1 alone (its optimum closest to 0)."""

    dv: np.ndarray
    linearized: list
    qp_iterations: int
    dv_first: np.ndarray | None = None

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

    ``eps_abs``: ProxQP absolute tolerance (eps_rel = 0).  ``regularization``: eps of the module
    docstring, a Levenberg damping of every level: it makes each QP strictly convex and keeps
    rounding noise out of the directions a level does not see; it never moves a fixed point.
    1e-7 needs the fewest Newton iterations on the benchmark targets (1e-12..1e-5 tried).
    ``rank_tol``: singular values below it (absolute) count as zero when a kernel is computed.
    ``lower_damping``: c in the damping c ||J_k^T e_k|| of the levels after the first.
    The object owns its QPs: one solver per thread.
    """

    def __init__(self, platform: Platform, *, eps_abs: float = 1e-9, regularization: float = 1e-7, rank_tol: float = 1e-9,
                 elimination: str = "nullspace", max_qp_iter: int = 1000, lower_damping: float = 1.0) -> None:
        check_platform(platform)
        if elimination not in ELIMINATIONS:
            raise UnknownNameError("elimination", elimination, ELIMINATIONS)
        max_qp_iter = as_int(max_qp_iter, "max_qp_iter", lo=1)
        eps_abs = as_real(eps_abs, "eps_abs", positive=True)
        regularization = as_real(regularization, "regularization", nonnegative=True)
        rank_tol = as_real(rank_tol, "rank_tol", positive=True)
        lower_damping = as_real(lower_damping, "lower_damping", nonnegative=True)
        # Each level is feasible by construction (the previous optimum satisfies all its
        # constraints) and strictly convex: an infeasibility verdict could only be a false positive,
        # so the detection thresholds sit far below eps_abs.  A small primal proximal step and a
        # stiff inequality penalty cut the iterations with an active joint limit from ~12 to ~4
        # (benchmarks/ik_benchmark.py) without changing the optimum.
        self.settings = QPSettings(eps_abs=eps_abs, eps_primal_inf=1e-14, eps_dual_inf=1e-14, max_iter=max_qp_iter,
                                   default_rho=1e-8, default_mu_in=1e-4, default_mu_eq=1e-6)
        self.platform = platform
        self.nv = platform.nv
        self.elimination = elimination
        self.regularization = float(regularization)
        self.lower_damping = float(lower_damping)
        self.rank_tol = float(rank_tol)
        self.iv = slice(6, platform.nv)
        self.iq = slice(7, platform.nq)
        self.lower = np.array(platform.arm_lower)
        self.upper = np.array(platform.arm_upper)
        self._lex = Lexicographic(platform.nv, range(6, platform.nv), settings=self.settings, regularization=regularization,
                                  rank_tol=rank_tol, warm_start=True)

    def reset(self) -> None:
        """Forget warm starts (called at the start of every IK solve: results depend on the inputs only)."""
        self._lex.reset()

    def solve(self, platform: Platform, data, q: np.ndarray, levels) -> HierarchyStep:
        """The hierarchical step dv at q for ``levels`` (a sequence of sequences of tasks).

        Call :func:`qprr.ik.tasks.update_kinematics` at q first.  Raises SolverError if a QP fails.
        """
        lin = []
        nv = self.nv
        for tasks in levels:
            if len(tasks) == 1:
                lin.append(check_linearized(tasks[0], tasks[0].linearize(platform, data, q), nv))
            else:
                Js, es = zip(*(check_linearized(t, t.linearize(platform, data, q), nv) for t in tasks))
                lin.append((np.vstack(Js), np.concatenate(es)))
        q_arm = q[self.iq]
        lo_arm = self.lower - q_arm
        up_arm = self.upper - q_arm
        # Levenberg-Marquardt damping of the lower levels, proportional to their gradient
        # ||J_k^T e_k||: iterated full steps of an unsatisfiable lower level whose projection is
        # ill-conditioned would otherwise cycle between huge steps (measured on the 11-DOF
        # hextilt_flying_arm_5); it fades as the task is met.  Both eliminations use it (the same QPs).
        damping = [0.0] + [self.lower_damping * float(np.linalg.norm(J.T @ e)) for J, e in lin[1:]]
        if self.elimination == "nullspace":
            res = self._lex.solve(lin, lo_arm, up_arm, damping=damping)
            dv, iters, first = res.x, res.iterations, res.x_levels[0]
        else:
            dv, iters, first = self._solve_equality(lin, lo_arm, up_arm, damping)
        return HierarchyStep(dv, lin, iters, first)

    def _solve_equality(self, lin, lo_arm, up_arm, damping):
        nv = self.nv
        C = np.eye(nv)[self.iv]
        stack = np.zeros((0, nv))
        A = None  # orthonormal rows spanning the stacked earlier Jacobians
        dv = np.zeros(nv)
        iters = 0
        first = None
        for k, (J, e) in enumerate(lin):
            if A is not None and A.shape[0] == nv:
                break  # the earlier levels fix dv completely
            reg = self.regularization + damping[k]
            H = J.T @ J
            H.flat[:: nv + 1] += reg
            g = -J.T @ e - reg * dv  # damping of the increment dv - dv_{k-1}*, as in "nullspace"
            # J_j dv = J_j dv_j* for all j < k  <=>  A dv = A dv_{k-1}*, with A the rank-revealing
            # compression of the stack (redundant rows stall ProxQP).
            b = None if A is None else A @ dv
            n_eq = 0 if A is None else A.shape[0]
            d_arm = dv[self.iv]  # keep the earlier optimum feasible despite ProxQP's eps_abs slack
            qp = proxqp.dense.QP(nv, n_eq, C.shape[0])
            self.settings.apply(qp)
            qp.init(H, g, A, b, C, np.minimum(lo_arm, d_arm), np.maximum(up_arm, d_arm))
            qp.solve()
            info = qp.results.info
            # exact on ProxQP's active set, as the "nullspace" levels; it also certifies (KKT checked
            # exactly) an answer whose residuals met eps_abs while the duality gap would not close
            # (MAX_ITER with 8 equality rows, primal and dual residuals ~1e-12: seen on a seeded target)
            polished = polish_box_qp(H, g, C, np.minimum(lo_arm, d_arm), np.maximum(up_arm, d_arm), qp.results.x, A, b)
            residuals_met = max(info.pri_res, info.dua_res) <= self.settings.eps_abs
            if info.status != _SOLVED and not (info.status == _MAX_ITER and residuals_met and polished is not None):
                raise SolverError(f"ProxQP did not solve level {k + 1} (n = {nv}, n_eq = {n_eq}): status {info.status.name}, "
                                  f"primal residual {info.pri_res:.3g}, dual residual {info.dua_res:.3g}")
            dv = qp.results.x.copy() if polished is None else polished
            first = dv if first is None else first
            iters += info.iter
            stack = np.vstack([stack, J])
            s, Vt = right_singular(stack)
            A = Vt[: int(np.count_nonzero(s > self.rank_tol))]
        return dv, iters, first
