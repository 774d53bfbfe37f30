"""The strict task-priority (lexicographic) step of the QP IK.

Level k is the QP

    min_dv  ||J_k dv - e_k||^2 + eps ||dv - dv_{k-1}*||^2     (dv_0* = 0)
    s.t.    J_j dv = J_j dv_j*   for every level j < k   (their optimum is kept)
            lower - q_arm <= dv_arm <= upper - q_arm     (joint limits, hard, every level)

solved by :class:`qprr.actuation.lexicographic.Lexicographic` (the free directions of the earlier levels as unknowns:
the earlier optima hold by construction).  The minimisers of a least-squares objective over a
convex set all share the same J_k dv, so keeping J_j dv fixed keeps level j's optimum; a test checks
every level's KKT conditions, equalities included, independently of the elimination.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..actuation.lexicographic import Kernel, Lexicographic, QPSettings, resolve_kernel
from ..model import Platform, check_platform
from ..validation import as_int, as_real
from .tasks.base import check_linearized

DEFAULT_KERNEL = Kernel.AUTO
"""The IK's lexicographic kernel (:class:`qprr.actuation.lexicographic.Kernel`): the compiled one when numba is installed
(``pip install qprr[fast]``), else the readable numpy one."""

MET = 1e-14
"""A level whose error entries are all below MET (m, rad: the rounding of forward kinematics near the origin) is met."""


@dataclass(frozen=True)
class HierarchyStep:
    """One solve of the hierarchy: the step dv, the linearised levels (J_k, e_k; J_k None when every level was met
    and dv = 0 needed no Jacobian), ProxQP iterations,
    ``dv_levels[k]`` the optimum of levels 1..k (``dv_first`` = ``dv_levels[0]``, the step of level 1
    alone), ``damping[k]`` the damping each level's QP added to the regularisation, ``errors[k]`` = ||e_k||, each
    task's error before the step."""

    dv: np.ndarray
    linearized: list
    qp_iterations: int
    dv_levels: tuple = ()
    damping: tuple = ()
    errors: tuple = ()
    level_residuals: tuple = ()  # ||J_k dv - e_k|| per level when the solver computed them (else :attr:`residuals` does)

    def __post_init__(self) -> None:
        if not self.errors:
            object.__setattr__(self, "errors", _norms(self.linearized))

    @property
    def dv_first(self) -> np.ndarray | None:
        return self.dv_levels[0] if self.dv_levels else None

    @property
    def residuals(self) -> tuple[float, ...]:
        """||J_k dv - e_k|| per level: what is left of each task after the step (linear model)."""
        if self.level_residuals:
            return self.level_residuals
        return tuple(math.sqrt(float(e @ e)) if J is None else math.sqrt(float((J @ self.dv - e) @ (J @ self.dv - e))) for J, e in self.linearized)


def _norms(linearized) -> tuple[float, ...]:
    """||e_k|| per level."""
    return tuple(math.sqrt(float(e @ e)) for _, e in linearized)


def _met(linearized, errors) -> bool:
    """Every entry of every e_k within MET (a level whose norm exceeds MET sqrt(dim) has an entry above it: no entry
    test needed, the usual case)."""
    if any(err > MET * math.sqrt(e.shape[0]) for err, (_, e) in zip(errors, linearized)):
        return False
    return all(float(np.abs(e).max(initial=0.0)) <= MET for _, e in linearized)


class HierarchySolver:
    """Lexicographic least squares with hard joint limits, one ProxQP per level.

    ``eps_abs``: ProxQP absolute tolerance (eps_rel = 0).  ``regularization``: eps of the module
    docstring, a Levenberg damping of every level: it makes each QP strictly convex and keeps
    rounding noise out of the directions a level does not see; it never moves a fixed point.
    1e-7 needs the fewest Newton iterations on the benchmark targets (1e-12..1e-5 tried).
    ``rank_tol``: singular values below it (absolute) count as zero when a kernel is computed.
    ``lower_damping``: c in the damping c ||J_k^T e_k|| of the levels after the first.
    ``active_set_first``: each level solved exactly on the active set of the previous iteration first,
    ProxQP (then polished) only when that is not the optimum (:class:`qprr.actuation.lexicographic.Lexicographic`).
    ``kernel``: who runs those steps (:data:`DEFAULT_KERNEL`; "numpy", "numba" or "auto"); with numba, a hierarchy of
    default tasks (one per level) is also linearised in the same compiled call (:mod:`qprr.ik.iteration_fast`).
    The object owns its QPs: one solver per thread.
    """

    def __init__(
        self,
        platform: Platform,
        *,
        eps_abs: float = 1e-9,
        regularization: float = 1e-7,
        rank_tol: float = 1e-9,
        max_qp_iter: int = 1000,
        lower_damping: float = 0.1,
        active_set_first: bool = True,
        kernel: Kernel | str = DEFAULT_KERNEL,
    ) -> None:
        check_platform(platform)
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
        self.settings = QPSettings(
            eps_abs=eps_abs,
            eps_primal_inf=1e-14,
            eps_dual_inf=1e-14,
            max_iter=max_qp_iter,
            default_rho=1e-8,
            default_mu_in=1e-4,
            default_mu_eq=1e-6,
            kernel=kernel,
        )
        self.platform = platform
        self.nv = platform.nv
        self.regularization = float(regularization)
        self.lower_damping = float(lower_damping)
        self.rank_tol = float(rank_tol)
        self.iv = slice(6, platform.nv)
        self.iq = slice(7, platform.nq)
        self.lower = np.array(platform.arm_lower)
        self.upper = np.array(platform.arm_upper)
        self._limits = (self.lower, self.upper)
        self._lex = Lexicographic(
            platform.nv,
            range(6, platform.nv),
            settings=self.settings,
            regularization=regularization,
            rank_tol=rank_tol,
            warm_start=True,
            active_set_first=bool(active_set_first),
        )
        self._first = True  # the first step of a solve asks the tasks for their errors first (Task.error)
        self._fused = None  # qprr.ik.iteration_fast's functions, with the numba kernel
        if resolve_kernel(kernel) is Kernel.NUMBA and active_set_first:
            from . import iteration_fast, newton_fast  # numba: only when this kernel is asked for

            self._fused = _Fused(iteration_fast, newton_fast.NewtonLoop)
        self._loop = None  # the last compiled Newton loop made (newton_loop)
        self._packed: list = []  # [(levels, their CompiledLevels or None)], the last two sequences of levels asked for
        self._weights = (self.regularization, self.lower_damping, self.rank_tol, MET)  # iteration_fast.iterate's
        nb = platform.n_arm
        self._guesses = (np.full(0, -1, dtype=np.int64), np.zeros((0, nb), dtype=bool), np.zeros((0, nb), dtype=bool))

    def reset(self) -> None:
        """Forget warm starts (called at the start of every IK solve: results depend on the inputs only)."""
        self._lex.reset()
        self._first = True
        self._guesses[0][:] = -1

    def solve(self, platform: Platform, data, q: np.ndarray, levels, *, validate: bool = True, refresh: bool = True) -> HierarchyStep:
        """The hierarchical step dv at q for ``levels`` (a sequence of sequences of tasks).

        Call :func:`qprr.ik.tasks.update_kinematics` at q first.  Raises SolverError if a QP fails.
        ``validate``: check each task's (J, e) (shapes, types, finite: :func:`check_linearized`); the IK checks them
        at its first iteration and afterwards only that they are finite (a task's shapes do not change).
        ``refresh`` (the compiled path): read the tasks' targets and weights again; False when no task was retargeted
        since the last call with these very levels (the IK's steps after the first of a solve).
        """
        nv = self.nv
        if self._fused is not None:  # default tasks need no validation: their shapes are right by construction
            step = self._solve_compiled(platform, data, q, levels, refresh)
            if step is not None:
                return step
        first, self._first = self._first, False
        if first and not validate:  # started at the answer (every level met): dv = 0, no Jacobian needed
            met = [(None, np.concatenate([t.error(platform, data, q) for t in tasks])) for tasks in levels]
            if _met(met, _norms(met)):
                dv = np.zeros(nv)
                return HierarchyStep(dv, met, 0, (dv,) * len(levels), (0.0,) * len(levels))
        if validate:
            lin = []
            for tasks in levels:
                if len(tasks) == 1:
                    lin.append(check_linearized(tasks[0], tasks[0].linearize(platform, data, q), nv))
                else:
                    Js, es = zip(*(check_linearized(t, t.linearize(platform, data, q), nv) for t in tasks))
                    lin.append((np.vstack(Js), np.concatenate(es)))
        else:
            lin = [tasks[0].linearize(platform, data, q) if len(tasks) == 1 else _stack(platform, data, q, tasks) for tasks in levels]
        errors = _norms(lin)
        if not validate and not math.isfinite(sum(errors) + sum(float(J.sum()) for J, _ in lin)):
            for tasks in levels:  # name the task
                for t in tasks:
                    check_linearized(t, t.linearize(platform, data, q), nv)
        if _met(lin, errors):
            # every level met to rounding: dv = 0 is each level's optimum (zero objective, the regularisation pulls to
            # 0 and 0 is inside the joint bounds); a solve would return a step of rounding size (|dv| < 1e-11)
            dv = np.zeros(nv)
            return HierarchyStep(dv, lin, 0, (dv,) * len(lin), (0.0,) * len(lin), errors)
        q_arm = q[self.iq]
        lo_arm = self.lower - q_arm
        up_arm = self.upper - q_arm
        # Levenberg-Marquardt damping of the lower levels, proportional to their gradient
        # ||J_k^T e_k||: iterated full steps of an unsatisfiable lower level whose projection is
        # ill-conditioned would otherwise cycle between huge steps (measured on the 11-DOF
        # hextilt_flying_arm_5); it fades as the task is met.  c = 0.1 (``lower_damping``): with c = 1 an
        # unsatisfiable posture level kept its damping and converged linearly (Q-PRR cold starts: 6 Newton iterations
        # median, 23 at worst, against 5 and 7 with 0.1; c = 0 cycles on the hextilt's position-only targets).
        damping = [0.0] + [self.lower_damping * math.sqrt(float(g @ g)) for g in (J.T @ e for J, e in lin[1:])]
        res = self._lex.solve(lin, lo_arm, up_arm, damping=damping)
        return HierarchyStep(res.x, lin, res.iterations, res.x_levels, tuple(damping), errors)

    def level_errors(self, platform: Platform, data, q: np.ndarray, levels, *, refresh: bool = True) -> tuple[float, ...]:
        """||e_k|| of every level at q, each task's error (``data`` holds the kinematics at q:
        :func:`qprr.ik.tasks.update_kinematics`); with the numba kernel and default tasks, in one compiled call
        (``refresh``: as :meth:`solve`'s)."""
        packed = None if self._fused is None else self._packed_for(platform, levels, refresh)
        if packed is not None:
            norms = self._fused.level_norms(packed.levels, *self._fused.kinematics(platform, data, packed), q)
            if math.isfinite(float(norms.sum())):
                return tuple(norms.tolist())
        return tuple(math.sqrt(sum(float(e @ e) for e in (t.error(platform, data, q) for t in level))) for level in levels)

    def newton_loop(self, platform: Platform, levels, settings: tuple):
        """The QP IK's Newton loop compiled for ``levels`` (:class:`qprr.ik.newton_fast.NewtonLoop`, its targets read
        now, the warm starts of its compiled steps forgotten: a new solve), or None when there is no compiled kernel or
        ``levels`` are not all default tasks.  ``settings``: the loop's options (``NewtonLoop``'s)."""
        if self._fused is None:
            return None
        loop = self._loop
        reuse = loop is not None and loop.levels is levels and loop.guesses is self._guesses and loop.settings == settings
        if reuse and self._fused.same_tasks(levels, loop.packed):
            self._fused.refill(platform, loop.packed)  # the levels of the last solve, retargeted
        else:
            packed = self._packed_for(platform, levels, True)
            if packed is None:
                return None
            self._room_for(len(levels))
            loop = self._loop = self._fused.newton_loop(platform, levels, packed, (self._limits, self._weights, self._guesses), settings)
        self._guesses[0][:] = -1
        return loop

    def _room_for(self, K: int) -> None:
        """The compiled step's active-set guesses with room for K levels."""
        if self._guesses[0].shape[0] < K:
            nb = self.platform.n_arm
            self._guesses = (np.full(K, -1, dtype=np.int64), np.zeros((K, nb), dtype=bool), np.zeros((K, nb), dtype=bool))

    def _packed_for(self, platform: Platform, levels, refresh: bool = True):
        """``levels`` packed for the compiled iteration (qprr.ik.iteration_fast.CompiledLevels), None if they are not
        all default tasks; packed once for the same tasks, whose targets are read again at every call with
        ``refresh`` (a task may be retargeted between two steps, as the readable path reads it live).  The last two
        sequences of levels are kept packed (the IK alternates between its levels and their leading ones once the
        lower levels are frozen)."""
        fast = self._fused
        cache = self._packed
        if not refresh and cache and cache[0][0] is levels:  # the IK's steps: the levels of the previous call
            return cache[0][1]
        entry = next((e for e in cache if e[0] is levels), None)
        if entry is not None and not refresh:
            return entry[1]
        packed = None if entry is None else entry[1]
        if entry is None or (packed is not None and not fast.same_tasks(levels, packed)):
            packed = fast.compiled_levels(platform, levels)
        elif packed is not None:  # the same tasks: their current targets and weights
            fast.refill(platform, packed)
        self._packed = [(levels, packed)] + [e for e in cache if e[0] is not levels][:1]
        return packed

    def _solve_compiled(self, platform: Platform, data, q: np.ndarray, levels, refresh: bool = True) -> HierarchyStep | None:
        """:meth:`solve` in one compiled call (:mod:`qprr.ik.iteration_fast`), or None when ``levels`` are not all
        default tasks or a task's J or e is not finite (the readable path then solves them, or names the task)."""
        fast = self._fused
        packed = self._packed_for(platform, levels, refresh)
        if packed is None:
            return None
        self._room_for(len(levels))
        frame, base = fast.kinematics(platform, data, packed)
        status, A, b, x, x_levels, norms = fast.iterate(packed.levels, frame, base, q, self._limits, self._weights, self._guesses)
        if status == fast.FastStatus.NOT_FINITE:
            return None
        self._first = False
        lin = [(A[i:j], b[i:j]) for i, j in packed.rows]
        errors, damping, residuals = (tuple(row) for row in norms.tolist())
        if status == fast.FastStatus.NEEDS_NUMPY:  # a level needs ProxQP
            res = self._lex.solve(lin, self.lower - q[self.iq], self.upper - q[self.iq], damping=damping)
            return HierarchyStep(res.x, lin, res.iterations, res.x_levels, damping, errors)
        return HierarchyStep(x, lin, 0, tuple(x_levels), damping, errors, residuals)


class _Fused:
    """The functions of :mod:`qprr.ik.iteration_fast` a solver calls (a module cannot be pickled; functions can)."""

    def __init__(self, module, newton_loop) -> None:
        self.newton_loop = newton_loop  # qprr.ik.newton_fast.NewtonLoop
        self.compiled_levels, self.refill, self.same_tasks = module.compiled_levels, module.refill, module.same_tasks
        self.kinematics, self.iterate, self.FastStatus = module.kinematics, module.iterate, module.FastStatus
        self.level_norms = module.level_norms


def _stack(platform, data, q, tasks) -> tuple[np.ndarray, np.ndarray]:
    Js, es = zip(*(t.linearize(platform, data, q) for t in tasks))
    return np.vstack(Js), np.concatenate(es)
