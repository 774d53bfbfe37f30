"""Lexicographic (strict-priority) bounded least squares on proxsuite: the engine of the IK and the allocation.

Level k of ``levels = [(A_1, b_1), ..., (A_K, b_K)]`` solves

    min_x  ||A_k x - b_k||^2 + eps ||x - x_{k-1}*||^2
    s.t.   A_j x = A_j x_j*   for every level j < k   (their optimum is kept)
           lower <= x[bounded] <= upper              (hard at every level)

by null-space elimination: x = x_{k-1}* + Z z with Z an orthonormal basis of the kernel of the
stacked earlier matrices, so each level is a small QP in the free directions z with the bounds
as inequalities (the minimisers of a least-squares objective over a convex set all share the
same A_k x, so keeping that value keeps the level's optimum).  A level with a single free
direction is solved in closed form (the unconstrained minimiser clamped to the interval the
bounds leave); the others by proxsuite's dense ProxQP.

proxsuite's defaults can call a feasible QP infeasible or an inaccurate optimum solved
(eps_abs 1e-5, eps_rel 1e-4, no duality-gap test).  :class:`QPSettings` sets the absolute
tolerance, eps_rel = 0, the infeasibility thresholds and the duality-gap check explicitly, and
every status is tested: anything but PROXQP_SOLVED, after one cold retry, raises
:class:`~qprr.errors.SolverError`.  A solver object owns its QPs and warm starts (no module-level
state): two threads with two solvers are independent.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from proxsuite import proxqp

from .errors import InputError, SolverError

try:  # LAPACK's SVD without numpy.linalg's wrapper: 3x cheaper on these tiny matrices
    from scipy.linalg.lapack import dgesdd as _dgesdd  # scipy is a dependency of proxsuite
except ImportError:  # pragma: no cover
    _dgesdd = None

_SOLVED = proxqp.QPSolverOutput.PROXQP_SOLVED


def right_singular(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(singular values, V^T full) of B."""
    if _dgesdd is not None and B.size:
        _, s, Vt, info = _dgesdd(B)
        if info == 0:
            return s, Vt
    _, s, Vt = np.linalg.svd(B)
    return s, Vt


def null_space(B: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal basis (columns) of the kernel of B; singular values <= ``tol`` count as zero."""
    s, Vt = right_singular(B)
    return Vt[int(np.count_nonzero(s > tol)):].T


@dataclass(frozen=True)
class QPSettings:
    """ProxQP settings that make ``PROXQP_SOLVED`` mean solved (see the module docstring).

    ``default_rho``, ``default_mu_in``, ``default_mu_eq``: proximal parameters (None keeps
    proxsuite's); small well-scaled problems converge in fewer iterations with a small rho and
    a stiff inequality penalty.
    """

    eps_abs: float = 1e-9
    eps_primal_inf: float = 1e-14
    eps_dual_inf: float = 1e-14
    check_duality_gap: bool = True
    max_iter: int = 1000
    default_rho: float | None = None
    default_mu_in: float | None = None
    default_mu_eq: float | None = None

    def __post_init__(self) -> None:
        for name in ("eps_abs", "eps_primal_inf", "eps_dual_inf"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise InputError(f"QP setting {name} must be a finite number > 0, got {v!r}")
        if not (isinstance(self.max_iter, int) and self.max_iter >= 1):
            raise InputError(f"QP setting max_iter must be an integer >= 1, got {self.max_iter!r}")

    def apply(self, qp) -> None:
        s = qp.settings
        s.eps_abs = self.eps_abs
        s.eps_rel = 0.0
        s.eps_primal_inf = self.eps_primal_inf
        s.eps_dual_inf = self.eps_dual_inf
        s.check_duality_gap = self.check_duality_gap
        s.eps_duality_gap_abs = self.eps_abs
        s.eps_duality_gap_rel = 0.0
        s.max_iter = self.max_iter
        if self.default_rho is not None:
            s.default_rho = self.default_rho
        if self.default_mu_in is not None:
            s.default_mu_in = self.default_mu_in
        if self.default_mu_eq is not None:
            s.default_mu_eq = self.default_mu_eq
        s.verbose = False


@dataclass(frozen=True)
class LexResult:
    """``x`` the solution; ``residuals[k]`` = ||A_k x - b_k||; ``iterations`` ProxQP iterations summed over levels;
    ``x_levels[k]`` the solution after level k (the optimum of levels 1..k)."""

    x: np.ndarray
    residuals: tuple[float, ...]
    iterations: int
    x_levels: tuple = ()


class Lexicographic:
    """Strict-priority bounded least squares over ``n`` variables (see the module docstring).

    Parameters
    ----------
    n : number of variables.
    bounded : indices of the variables with bounds (None: all).
    settings : :class:`QPSettings`.
    regularization : eps >= 0 of the module docstring, a Levenberg damping of every level (it
        makes each QP strictly convex; it never moves a point where every level is satisfied).
    rank_tol : singular values below it (absolute) count as zero when a kernel is computed.
    warm_start : reuse each level's last primal-dual solution as the next initial guess
        (:meth:`reset` forgets them).

    The object owns its ProxQP instances; it can be deep-copied or pickled (the copy builds its
    own QPs on first use).
    """

    def __init__(self, n: int, bounded=None, *, settings: QPSettings | None = None, regularization: float = 0.0,
                 rank_tol: float = 1e-9, warm_start: bool = True) -> None:
        if not (isinstance(n, (int, np.integer)) and n >= 1):
            raise InputError(f"n must be an integer >= 1, got {n!r}")
        if not (np.isfinite(regularization) and regularization >= 0):
            raise InputError(f"regularization must be finite and >= 0, got {regularization!r}")
        if not (np.isfinite(rank_tol) and rank_tol > 0):
            raise InputError(f"rank_tol must be finite and > 0, got {rank_tol!r}")
        self.n = int(n)
        idx = np.arange(n) if bounded is None else np.asarray(bounded, dtype=int)
        if idx.size and (idx.min() < 0 or idx.max() >= n):
            raise InputError(f"bounded indices must lie in [0, {n}), got {idx.tolist()}")
        contiguous = idx.size and np.array_equal(idx, np.arange(idx[0], idx[0] + idx.size))
        self.bounded = slice(int(idx[0]), int(idx[0]) + idx.size) if contiguous else idx
        self.n_bounded = int(idx.size)
        self.settings = settings or QPSettings()
        self.regularization = float(regularization)
        self.rank_tol = float(rank_tol)
        self.warm_start = bool(warm_start)
        self._C_full = np.eye(n)[self.bounded]
        self._qps: dict[int, object] = {}
        self._warm: dict[int, tuple] = {}
        self._fresh: set[int] = set()

    # ------------------------------------------------------------------ copying
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_qps"] = {}  # ProxQP objects are rebuilt by the copy (copying them is unsafe)
        state["_warm"] = {}
        state["_fresh"] = set()
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    def __deepcopy__(self, memo):
        new = type(self).__new__(type(self))
        memo[id(self)] = new
        new.__setstate__(copy.deepcopy(self.__getstate__(), memo))
        return new

    def reset(self) -> None:
        """Forget the warm starts and preconditioners (results then depend on the inputs only)."""
        self._warm.clear()
        self._fresh = set(self._qps)

    # ------------------------------------------------------------------ QP
    def _qp(self, m: int, n_in: int):
        key = (m, n_in)
        qp = self._qps.get(key)
        if qp is None:
            qp = proxqp.dense.QP(m, 0, n_in)
            self.settings.apply(qp)
            self._qps[key] = qp
            return qp, True
        if key in self._fresh:
            self._fresh.discard(key)
            return qp, True
        return qp, False

    def solve_box_qp(self, level: int, H: np.ndarray, g: np.ndarray, C: np.ndarray, lo: np.ndarray, up: np.ndarray) -> tuple[np.ndarray, int]:
        """min 1/2 z^T H z + g^T z s.t. lo <= C z <= up with the checked settings; (z, iterations).

        Rows of C that are zero to rounding (a bounded variable the free directions do not move)
        are dropped: they hold at every z when lo <= 0 <= up, and left in they make ProxQP's
        infeasibility test fire on a feasible problem (observed on the 11-DOF hextilt_flying_arm_5).
        """
        m = H.shape[0]
        keep = np.abs(C).max(axis=1) > 1e-12 * max(1.0, float(np.abs(C).max())) if C.shape[0] else np.zeros(0, dtype=bool)
        if not keep.all():
            C, lo, up = C[keep], lo[keep], up[keep]
        qp, fresh = self._qp(m, C.shape[0])
        if fresh:
            qp.init(H, g, None, None, C, lo, up)
        else:
            qp.update(H, g, None, None, C, lo, up)
        warm = self._warm.get(level) if self.warm_start else None
        if warm is not None and warm[0].shape[0] == m and warm[1].shape[0] == C.shape[0]:
            qp.solve(warm[0], None, warm[1])
        else:
            qp.solve()
        res = qp.results
        if res.info.status != _SOLVED:  # a stalled warm start: retry cold once
            qp.init(H, g, None, None, C, lo, up)
            qp.solve()
            res = qp.results
        if res.info.status != _SOLVED:
            raise SolverError(
                f"ProxQP did not solve level {level + 1} ({m} variables, {C.shape[0]} bounds): status {res.info.status.name}, "
                f"primal residual {res.info.pri_res:.3g}, dual residual {res.info.dua_res:.3g}")
        z = res.x.copy()
        if self.warm_start:
            self._warm[level] = (z, res.z.copy())
        return z, int(res.info.iter)

    # ------------------------------------------------------------------ solve
    def solve(self, levels: Sequence[tuple[np.ndarray, np.ndarray]], lower, upper, x0=None, damping=None) -> LexResult:
        """Solve ``levels`` (sequence of (A_k, b_k)) under ``lower <= x[bounded] <= upper``.

        ``x0`` (default 0) is the point the regularisation of level 1 pulls towards; it must
        satisfy the bounds.  ``damping`` (one value per level) is added to the regularisation of
        each level (damped least squares: it shortens steps, it never moves a point where every
        level's gradient vanishes).
        """
        n, tol, b_idx = self.n, self.rank_tol, self.bounded
        lo = np.asarray(lower, dtype=float)
        up = np.asarray(upper, dtype=float)
        x = np.zeros(n) if x0 is None else np.array(x0, dtype=float)
        iters = 0
        x_levels = []
        Z = None  # basis of the free directions (None: the whole space)
        for k, (A, b) in enumerate(levels):
            reg = self.regularization
            if Z is not None and Z.shape[1] == 0:
                x_levels.append(x)
                continue
            B = A if Z is None else A @ Z
            r = b - A @ x
            if damping is not None:
                reg += float(damping[k])
            xb = x[b_idx]
            # the earlier optimum (z = 0) must stay feasible: ProxQP meets bounds only to eps_abs
            lo_z = np.minimum(lo - xb, 0.0)
            up_z = np.maximum(up - xb, 0.0)
            Cz = self._C_full if Z is None else Z[b_idx]
            m = B.shape[1]
            if m == 1:
                z = _clamped_1d(B[:, 0], r, reg, Cz[:, 0], lo_z, up_z)
            else:
                H = B.T @ B
                H.flat[:: m + 1] += reg
                z, it = self.solve_box_qp(k, H, -(B.T @ r), Cz, lo_z, up_z)
                iters += it
            x = x + (z if Z is None else Z @ z)
            x_levels.append(x)
            if k < len(levels) - 1:
                N = null_space(B, tol)
                Z = N if Z is None else Z @ N
        residuals = tuple(float(np.linalg.norm(A @ x - b)) for A, b in levels)
        return LexResult(x, residuals, iters, tuple(x_levels))


def _clamped_1d(B: np.ndarray, r: np.ndarray, reg: float, c: np.ndarray, lo: np.ndarray, up: np.ndarray) -> np.ndarray:
    """argmin_z ||B z - r||^2 + reg z^2 over the interval {z : lo <= c z <= up} (contains 0), as a (1,) array."""
    bb = float(B @ B) + reg
    z = float(B @ r) / bb if bb > 0.0 else 0.0
    zl, zu = -np.inf, np.inf
    for ci, li, ui in zip(c.tolist(), lo.tolist(), up.tolist()):
        if ci > 0.0:
            zl, zu = max(zl, li / ci), min(zu, ui / ci)
        elif ci < 0.0:
            zl, zu = max(zl, ui / ci), min(zu, li / ci)
    if zl <= zu:
        z = min(max(z, zl), zu)
    else:  # rounding made the interval empty: stay at the earlier optimum
        z = 0.0
    return np.array([z])
