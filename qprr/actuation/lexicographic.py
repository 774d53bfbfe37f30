"""Lexicographic (strict-priority) bounded least squares on proxsuite: the engine of the IK and the allocation.

Level k of ``levels = [(A_1, b_1), ..., (A_K, b_K)]`` solves

    min_x  ||A_k x - b_k||^2 + eps ||x - x_{k-1}*||^2
    s.t.   A_j x = A_j x_j*   for every level j < k   (their optimum is kept)
           E x = E x0                                (optional, hard at every level)
           lower <= x[bounded] <= upper              (hard at every level)

by null-space elimination: x = x_{k-1}* + Z z with Z an orthonormal basis of the kernel of the
stacked earlier matrices (and E), so each level is a small QP in the free directions z with the bounds
as inequalities (the minimisers of a least-squares objective over a convex set all share the
same A_k x, so keeping that value keeps the level's optimum).  A level with a single free
direction is solved in closed form (the unconstrained minimiser clamped to the interval the
bounds leave); the others by proxsuite's dense ProxQP.

proxsuite's defaults can call a feasible QP infeasible or an inaccurate optimum solved
(eps_abs 1e-5, eps_rel 1e-4, no duality-gap test).  :class:`QPSettings` sets the absolute
tolerance, eps_rel = 0, the infeasibility thresholds and the duality-gap check explicitly, and
every status is tested.  Even so ProxQP calls some levels infeasible (never true: z = 0 meets
their bounds) or runs out of iterations at degenerate vertices, where more bounds are active
than there are free directions; such a level is solved exactly by :func:`active_set_qp` (always
for an infeasibility verdict, for an iteration limit when ``exact_fallback`` is set).  Any other
failure, after one cold retry, raises :class:`~qprr.errors.SolverError`.  A solver object owns its QPs and warm starts (no module-level
state): two threads with two solvers are independent.

:attr:`QPSettings.kernel` chooses who runs :meth:`Lexicographic.solve`: this module's numpy code (the reference) or its
compiled form, ``lexicographic_fast.py`` (numba, ``pip install qprr[fast]``), which takes the same steps in one call
and hands a problem back to this path whenever a level needs ProxQP.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from importlib.util import find_spec

import numpy as np
from proxsuite import proxqp

from ..errors import InputError, MissingDependencyError, SolverError

try:  # LAPACK without numpy.linalg's wrapper: 3x cheaper on these tiny matrices
    from scipy.linalg.lapack import dgesdd as _dgesdd  # scipy is a dependency of proxsuite
    from scipy.linalg.lapack import dposv as _dposv
except ImportError:  # pragma: no cover
    _dgesdd = _dposv = None

_SOLVED = proxqp.QPSolverOutput.PROXQP_SOLVED
_INFEASIBLE = (proxqp.QPSolverOutput.PROXQP_PRIMAL_INFEASIBLE, proxqp.QPSolverOutput.PROXQP_DUAL_INFEASIBLE)
_MAX_ITER = proxqp.QPSolverOutput.PROXQP_MAX_ITER_REACHED


def right_singular(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(singular values, V^T full) of B."""
    if _dgesdd is not None and B.size:
        _, s, Vt, info = _dgesdd(B)
        if info == 0:
            return s, Vt
    _, s, Vt = np.linalg.svd(B)
    return s, Vt


def _spd_solve(H: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """H^-1 b for a symmetric positive definite H by Cholesky (None if H is not positive definite to working precision)."""
    if _dposv is None:  # pragma: no cover
        try:
            return np.linalg.solve(H, b)
        except np.linalg.LinAlgError:
            return None
    _, x, info = _dposv(H, b)
    return x if info == 0 and bool(np.isfinite(x).all()) else None


def _within(Cz: np.ndarray, lo: np.ndarray, up: np.ndarray) -> bool:
    """lo <= Cz <= up within 1e-10 of the bound scale (1 + the largest finite |bound|)."""
    if not Cz.size:
        return True
    big = max(-float(lo.min()), float(up.max()), float(lo.max()), -float(up.min()))
    scale = 1.0 + (big if big < np.inf else _bound_scale(lo, up, np.isfinite(lo), np.isfinite(up)))
    ftol = 1e-10 * scale
    return float((Cz - lo).min()) >= -ftol and float((up - Cz).min()) >= -ftol


def null_space(B: np.ndarray, tol: float) -> np.ndarray:
    """Orthonormal basis (columns) of the kernel of B; singular values <= ``tol`` count as zero."""
    s, Vt = right_singular(B)
    return Vt[int(np.count_nonzero(s > tol)) :].T


class Kernel(str, Enum):
    """Who runs :meth:`Lexicographic.solve`: ``NUMPY`` the readable code of this module (the reference), ``NUMBA``
    its compiled form (``lexicographic_fast.py``; ``pip install qprr[fast]``), ``AUTO`` numba when it is installed,
    else numpy."""

    AUTO = "auto"
    NUMPY = "numpy"
    NUMBA = "numba"


def resolve_kernel(kernel) -> Kernel:
    """The kernel that will run: ``Kernel.AUTO`` becomes NUMBA when numba is installed, else NUMPY; NUMBA without numba
    raises :class:`~qprr.errors.MissingDependencyError` ("not available: pip install qprr[fast]")."""
    try:
        kernel = Kernel(kernel)
    except ValueError:
        raise InputError(f"kernel must be one of {[k.value for k in Kernel]}, got {kernel!r}") from None
    installed = find_spec("numba") is not None
    if kernel is Kernel.AUTO:
        return Kernel.NUMBA if installed else Kernel.NUMPY
    if kernel is Kernel.NUMBA and not installed:
        raise MissingDependencyError("numba", "the compiled lexicographic kernel (kernel='numba')", "not available: pip install 'qprr[fast]'")
    return kernel


@dataclass(frozen=True)
class QPSettings:
    """ProxQP settings that make ``PROXQP_SOLVED`` mean solved (see the module docstring).

    ``eps_duality_gap``: absolute duality-gap tolerance (None: ``eps_abs``; the relative one is 0).
    ``default_rho``, ``default_mu_in``, ``default_mu_eq``: proximal parameters (None keeps
    proxsuite's); small well-scaled problems converge in fewer iterations with a small rho and
    a stiff inequality penalty.
    ``kernel``: :class:`Kernel` (the module docstring); the engine's default is the readable numpy path.
    """

    eps_abs: float = 1e-9
    eps_primal_inf: float = 1e-14
    eps_dual_inf: float = 1e-14
    check_duality_gap: bool = True
    max_iter: int = 1000
    default_rho: float | None = None
    default_mu_in: float | None = None
    default_mu_eq: float | None = None
    eps_duality_gap: float | None = None
    kernel: Kernel = Kernel.NUMPY

    def __post_init__(self) -> None:
        object.__setattr__(self, "kernel", resolve_kernel(self.kernel))
        for name in ("eps_abs", "eps_primal_inf", "eps_dual_inf", "eps_duality_gap"):
            v = getattr(self, name)
            if name == "eps_duality_gap" and v is None:
                continue
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
        s.eps_duality_gap_abs = self.eps_abs if self.eps_duality_gap is None else self.eps_duality_gap
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
    """``x`` the solution; ``residuals[k]`` = ||A_k x - b_k|| (computed when asked); ``iterations`` ProxQP iterations
    summed over levels; ``x_levels[k]`` the solution after level k (the optimum of levels 1..k)."""

    x: np.ndarray
    levels: tuple
    iterations: int
    x_levels: tuple = ()

    @property
    def residuals(self) -> tuple[float, ...]:
        return tuple(float(np.linalg.norm(A @ self.x - b)) for A, b in self.levels)


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
    polish : replace each ProxQP answer by the exact optimum on its active set
        (:func:`polish_box_qp`): results to machine precision and the same from run to run
        (ProxQP's own vary in the last digits it does not guarantee); about doubles the cost
        of a level.
    exact_fallback : when ProxQP stops at its iteration limit on a level, solve that level
        exactly with :func:`active_set_qp` instead of raising (an infeasibility verdict on a
        level, always a false positive since z = 0 is feasible, takes that path in any case).
    active_set_first : solve each level first without its bounds (one Cholesky solve: when that minimiser
        meets the bounds it is the optimum), else by :func:`kkt_on_active_set` from the bounds that
        were active at that level in the previous call (none after :meth:`reset`); ProxQP (and the
        polish) only when those steps do not end at a KKT point.  The answer is then the exact
        optimum without a QP set-up: a sequence of similar problems (the IK's Newton iterations)
        mostly costs one linear solve per level.

    The object owns its ProxQP instances; it can be deep-copied or pickled (the copy builds its
    own QPs on first use).
    """

    def __init__(
        self,
        n: int,
        bounded=None,
        *,
        settings: QPSettings | None = None,
        regularization: float = 0.0,
        rank_tol: float = 1e-9,
        warm_start: bool = True,
        exact_fallback: bool = False,
        polish: bool = True,
        active_set_first: bool = False,
    ) -> None:
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
        self.exact_fallback = bool(exact_fallback)
        self.polish = bool(polish)
        self.active_set_first = bool(active_set_first)
        self._active: dict[int, tuple] = {}
        # the compiled kernel takes the active-set-first steps; without them every level goes to ProxQP (numpy path)
        self._fast = _FastState(self.n_bounded) if self.settings.kernel is Kernel.NUMBA and self.active_set_first else None
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
        state["_active"] = {}
        state["_fast"] = None if self._fast is None else _FastState(self.n_bounded)  # guesses forgotten, as _active
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    def __deepcopy__(self, memo):
        new = type(self).__new__(type(self))
        memo[id(self)] = new
        new.__setstate__(copy.deepcopy(self.__getstate__(), memo))
        return new

    def reset(self) -> None:
        """Forget the warm starts and the QP objects (results then depend on the inputs only).

        Re-initialising a ProxQP object is not enough: results then still differ in the last bits
        (~1e-14) with what it solved before, so the objects themselves are dropped and rebuilt.
        """
        self._warm.clear()
        self._qps.clear()
        self._fresh.clear()
        self._active.clear()
        if self._fast is not None:
            self._fast.reset()

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

        Rows of C that are zero to the rank tolerance (a bounded variable the free directions do
        not move; the free directions themselves are only known to ``rank_tol``) are dropped: they
        hold at every z when lo <= 0 <= up, and left in they make ProxQP's infeasibility test fire
        on a feasible problem (observed on the 11-DOF hextilt_flying_arm_5) and the exact
        active-set fallback cycle between collinear near-zero rows (a 3R arm on a unicycle, rows
        of 1e-11 at a joint limit).
        """
        m = H.shape[0]
        if self.active_set_first:
            # the usual case: no bound active, one Cholesky solve.  Tried first even when a bound was active at this
            # level in the previous call: an unconstrained minimiser that meets the bounds is the optimum, and the
            # active-set steps from that guess would end at it only after releasing the bound (a KKT solve more)
            z = _spd_solve(H, -g)
            if z is not None and _within(C @ z, lo, up):
                self._active[level] = None
                return z, 0
        keep = np.abs(C).max(axis=1) > self.rank_tol * max(1.0, float(np.abs(C).max())) if C.shape[0] else np.zeros(0, dtype=bool)
        if not keep.all():
            C, lo, up = C[keep], lo[keep], up[keep]
        if self.active_set_first:
            guess = self._active.get(level)
            nc = C.shape[0]
            if guess is not None and guess[0].shape[0] == nc:
                at_lo, at_up = guess[0].copy(), guess[1].copy()
            elif z is not None:  # no guess: the bounds the unconstrained minimiser violates (the active-set steps' first move)
                at_lo, at_up = _violated(C @ z, lo, up)
            else:
                at_lo, at_up = np.zeros(nc, dtype=bool), np.zeros(nc, dtype=bool)
            out = kkt_on_active_set(H, g, C, lo, up, at_lo, at_up)
            if out is not None:
                self._active[level] = (out[1], out[2]) if (out[1].any() or out[2].any()) else None
                return out[0], 0
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
        retry = res.info.status in _INFEASIBLE or (self.exact_fallback and res.info.status == _MAX_ITER)
        if retry and np.all(lo <= 0.0) and np.all(up >= 0.0):
            # z = 0 meets every bound and the objective is bounded below (as at every level of
            # :meth:`solve`): an infeasibility verdict is a false positive of ProxQP's test, seen at
            # degenerate vertices (more active bounds than free directions, e.g. 6 bounds on 4
            # variables at level 3 of an octorotor allocation), where it may also run out of
            # iterations.  These QPs are tiny: solve them exactly.
            z = active_set_qp(H, g, C, lo, up)
            if z is not None:
                self._warm.pop(level, None)
                return z, int(res.info.iter)
        if res.info.status != _SOLVED:
            raise SolverError(
                f"ProxQP did not solve level {level + 1} ({m} variables, {C.shape[0]} bounds): status {res.info.status.name}, "
                f"primal residual {res.info.pri_res:.3g}, dual residual {res.info.dua_res:.3g}"
            )
        z = res.x.copy()
        if self.warm_start:
            self._warm[level] = (z, res.z.copy())
        polished = polish_box_qp(H, g, C, lo, up, z) if self.polish else None
        return (z if polished is None else polished), int(res.info.iter)

    # ------------------------------------------------------------------ solve
    def solve(self, levels: Sequence[tuple[np.ndarray, np.ndarray]], lower, upper, x0=None, damping=None, equality=None) -> LexResult:
        """Solve ``levels`` (sequence of (A_k, b_k)) under ``lower <= x[bounded] <= upper``.

        ``x0`` (default 0, clipped to the bounds) is the point the regularisation of level 1 pulls
        towards; it must satisfy the bounds (each level keeps its bounds feasible by never
        tightening them past the current point).  ``damping`` (one value per level) is added to the regularisation of
        each level (damped least squares: it shortens steps, it never moves a point where every
        level's gradient vanishes).  ``equality`` (a matrix E with n columns, optional): a hard
        constraint E x = E x0 above every level, e.g. a Pfaffian constraint E dz = 0 with x0 = 0;
        every level is restricted to x0 + ker E (singular values of E below ``rank_tol`` count
        as zero), so it holds to rounding, as the earlier levels' optima do.
        """
        n, tol, b_idx = self.n, self.rank_tol, self.bounded
        lo = np.asarray(lower, dtype=float)
        up = np.asarray(upper, dtype=float)
        if self._fast is not None and equality is None and isinstance(b_idx, slice):
            fast = self._fast.solve(self, levels, lo, up, x0, damping)
            if fast is not None:  # else a level needs ProxQP: the readable path below solves the whole problem
                return fast
        if x0 is None:  # 0, moved into the bounds (a positive lower bound, e.g. a rotor's f_min > 0, excludes 0)
            x = np.zeros(n)
            x[b_idx] = np.clip(0.0, lo, up)
        else:
            x = np.array(x0, dtype=float)
        iters = 0
        x_levels = []
        Z = None  # basis of the free directions (None: the whole space)
        if equality is not None:
            E = np.asarray(equality, dtype=float)
            if E.ndim != 2 or E.shape[1] != n:
                raise InputError(f"equality must be a matrix with {n} columns, got shape {E.shape}")
            if E.shape[0]:
                Z = null_space(E, tol)
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
                z = _clamped_1d(B[:, 0], r, reg, Cz[:, 0], lo_z, up_z, tol)
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
        return LexResult(x, tuple(levels), iters, tuple(x_levels))


class _FastState:
    """The compiled kernel's active-set guesses (per level: the number of kept bound rows, -1 for none, and the masks
    of active lower and upper bounds), the counterpart of ``Lexicographic._active``."""

    def __init__(self, n_bounded: int) -> None:
        from .lexicographic_fast import lex_solve  # numba: only when this kernel is asked for

        self.kernel = lex_solve
        self.nb = n_bounded
        self.n = np.full(0, -1, dtype=np.int64)
        self.lo = np.zeros((0, n_bounded), dtype=bool)
        self.up = np.zeros((0, n_bounded), dtype=bool)
        self.offsets: dict[tuple, np.ndarray] = {}  # level sizes -> where each level starts in the stacked rows
        self.no_start = np.zeros(0)

    def reset(self) -> None:
        self.n[:] = -1

    def solve(self, lex: Lexicographic, levels, lo: np.ndarray, up: np.ndarray, x0, damping) -> LexResult | None:
        """:meth:`Lexicographic.solve` by ``lexicographic_fast.lex_solve``; None when a level needs ProxQP."""
        K = len(levels)
        if self.n.shape[0] < K:  # more levels than before: room for their guesses
            grow = K - self.n.shape[0]
            self.n = np.concatenate([self.n, np.full(grow, -1, dtype=np.int64)])
            self.lo = np.vstack([self.lo, np.zeros((grow, self.nb), dtype=bool)])
            self.up = np.vstack([self.up, np.zeros((grow, self.nb), dtype=bool)])
        A = np.concatenate([Ak for Ak, _ in levels], dtype=float)
        b = np.concatenate([bk for _, bk in levels], dtype=float)
        rows = tuple(bk.shape[0] for _, bk in levels)
        offsets = self.offsets.get(rows)
        if offsets is None:
            offsets = self.offsets[rows] = np.cumsum((0,) + rows)
        damp = np.zeros(K) if damping is None else np.asarray(damping, dtype=float)
        x = self.no_start if x0 is None else np.array(x0, dtype=float)  # no start: the kernel clips 0 into the bounds
        bounds, weights = (lo, up, lex.bounded.start), (lex.regularization, damp, lex.rank_tol)
        x, x_levels, ok = self.kernel(A, b, offsets, bounds, x, weights, (self.n, self.lo, self.up))
        if not ok:
            return None
        return LexResult(x, tuple(levels), 0, tuple(x_levels))


def polish_box_qp(
    H: np.ndarray,
    g: np.ndarray,
    C: np.ndarray,
    lo: np.ndarray,
    up: np.ndarray,
    z: np.ndarray,
) -> np.ndarray | None:
    """The exact optimum of min 1/2 z^T H z + g^T z s.t. lo <= C z <= up from an approximate ``z``.

    ProxQP stops within its tolerance, at a point that also depends in its last digits on
    memory alignment (the same QP on fresh objects returned answers 1e-9 apart, proxsuite
    0.8), and the IK's stopping tests turned that into configurations 1e-7 apart from run to
    run.  Here the bounds active at ``z`` (within 1e-6 of the bound scale) are taken as
    equalities and the KKT system is solved directly; a bound whose multiplier has the wrong
    sign is released, a violated one added (a few active-set steps), until a KKT point is
    found (returned) or the steps run out (None: keep ``z``).  Same active set, same bits.
    (The first guess uses positions only: ProxQP's multipliers of inactive bounds are
    +-1e-17 noise that changes from run to run.)  The solution is exact also along directions
    where the objective is nearly flat (a damping of 1e-7), where ProxQP's answer can be off by
    1e-7 within its tolerance.
    """
    fin_lo, fin_up = np.isfinite(lo), np.isfinite(up)
    scale = _bound_scale(lo, up, fin_lo, fin_up)
    ftol = 1e-10 * scale
    Cz = C @ z
    at_lo = fin_lo & (Cz - lo <= 1e-6 * scale)
    at_up = fin_up & (up - Cz <= 1e-6 * scale) & ~at_lo
    if not at_lo.any() and not at_up.any():  # the usual case: no bound active, one linear solve
        try:
            zp = np.linalg.solve(H, -g)
        except np.linalg.LinAlgError:
            zp = None
        if zp is not None:
            Czp = C @ zp
            if not (np.any(Czp < lo - ftol) or np.any(Czp > up + ftol)):
                return zp
    out = kkt_on_active_set(H, g, C, lo, up, at_lo, at_up)
    return None if out is None else out[0]


def _bound_scale(lo, up, fin_lo, fin_up) -> float:
    return 1.0 + float(np.abs(np.concatenate([lo[fin_lo], up[fin_up]])).max(initial=0.0))


def _violated(Cz: np.ndarray, lo: np.ndarray, up: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Masks of the lower and upper bounds that Cz violates by more than 1e-10 of the bound scale, as
    :func:`kkt_on_active_set` adds them to its active set."""
    ftol = 1e-10 * _bound_scale(lo, up, np.isfinite(lo), np.isfinite(up))
    viol_lo = lo - Cz > ftol
    return viol_lo, (Cz - up > ftol) & ~viol_lo


def kkt_on_active_set(H: np.ndarray, g: np.ndarray, C: np.ndarray, lo: np.ndarray, up: np.ndarray, at_lo: np.ndarray, at_up: np.ndarray):
    """(z, at_lo, at_up): the exact KKT point of min 1/2 z^T H z + g^T z s.t. lo <= C z <= up, found by active-set steps
    from the guessed active bounds ``at_lo``, ``at_up`` (boolean masks over the rows of C); None when the steps run out
    or a KKT system is not solved accurately.

    A returned point satisfies the KKT conditions (stationarity, primal feasibility within 1e-10 of the bound scale,
    multipliers of the right sign), so it is the global optimum of the convex QP.  Started from the active set of the
    previous call it usually ends after one linear solve: the IK's levels change little between iterations.
    """
    at_lo = at_lo & np.isfinite(lo)
    at_up = at_up & np.isfinite(up) & ~at_lo
    scale = _bound_scale(lo, up, np.isfinite(lo), np.isfinite(up))
    ftol = 1e-10 * scale  # bounds nearly implied by each other make the KKT matrix ill-conditioned (cond 1e11 seen)
    gscale0 = 1.0 + float(np.abs(g).max(initial=0.0))
    hmax = float(np.abs(H).max(initial=0.0))
    seen: set[bytes] = set()
    for _ in range(2 * C.shape[0] + 2):
        key = at_lo.tobytes() + at_up.tobytes()
        cycling = key in seen  # a degenerate vertex: a bound with a ~0 multiplier is dropped and re-added
        seen.add(key)
        idx = np.flatnonzero(at_lo | at_up)
        zp, mu, res_x, res_b = _kkt_solve(H, g, C[idx], np.where(at_lo, lo, up)[idx])
        gscale = gscale0 + hmax * (1.0 + float(np.abs(zp).max(initial=0.0)))
        if float(np.abs(res_x).max(initial=0.0)) > 1e-10 * gscale or float(np.abs(res_b).max(initial=0.0)) > ftol:
            return None  # not solved accurately
        # > 0: the bound pulls the wrong way (a lower bound's multiplier must be >= 0, an upper one's <= 0)
        wrong = np.where(at_lo[idx], -mu, mu)
        Czp = C @ zp
        viol_lo = lo - Czp > ftol  # (an infinite bound is never violated)
        viol_up = (Czp - up > ftol) & ~viol_lo
        release = wrong > (1e-9 if cycling else 1e-12) * gscale
        if not release.any() and not viol_lo.any() and not viol_up.any():
            return zp, at_lo, at_up
        if release.any():  # release the worst wrong-signed bound (one at a time: the others' multipliers change)
            i = idx[int(np.argmax(wrong))]
            at_lo[i] = at_up[i] = False
        else:
            _add_violated(at_lo, at_up, (viol_lo, viol_up), (lo - Czp, Czp - up), cycling)
    return None


def _kkt_solve(H: np.ndarray, g: np.ndarray, A: np.ndarray, b: np.ndarray):
    """(z, mu, stationarity residual, constraint residual) of min 1/2 z^T H z + g^T z s.t. A z = b, with
    H z + g = A^T mu (minimum-norm solution when the active rows are dependent or a flat direction is left free)."""
    n, k = H.shape[0], A.shape[0]
    if k == 0:
        z = _spd_solve(H, -g)
        if z is None:
            z = np.linalg.lstsq(H, -g, rcond=1e-13)[0]
        return z, np.zeros(0), H @ z + g, np.zeros(0)
    K = np.zeros((n + k, n + k))
    K[:n, :n] = H
    K[:n, n:] = A.T
    K[n:, :n] = A
    rhs = np.concatenate([-g, b])
    try:
        sol = np.linalg.solve(K, rhs)
    except np.linalg.LinAlgError:
        sol = np.linalg.lstsq(K, rhs, rcond=1e-13)[0]
    r = K @ sol - rhs
    return sol[:n], -sol[n:], r[:n], r[n:]


def _add_violated(at_lo: np.ndarray, at_up: np.ndarray, violated: tuple, gaps: tuple, cycling: bool) -> None:
    """Add the violated bounds to the active set in place: all of them, or (``cycling``) the most violated one only.
    ``violated`` = (masks of violated lower, upper bounds), ``gaps`` = (lo - Cz, Cz - up)."""
    viol_lo, viol_up = violated
    if not cycling:
        at_lo |= viol_lo
        at_up |= viol_up
        return
    gap = np.maximum(np.where(viol_lo, gaps[0], -np.inf), np.where(viol_up, gaps[1], -np.inf))
    i = int(np.argmax(gap))
    if viol_lo[i]:
        at_lo[i] = True
    else:
        at_up[i] = True


def active_set_qp(H: np.ndarray, g: np.ndarray, C: np.ndarray, lo: np.ndarray, up: np.ndarray, max_iter: int = 1000) -> np.ndarray | None:
    """argmin 1/2 z^T H z + g^T z s.t. lo <= C z <= up, from the feasible point z = 0 (None if not solved).

    Primal active-set method for convex QPs (Nocedal and Wright, *Numerical Optimization*,
    2nd ed., Algorithm 16.3), started with an empty working set so that the constraints it adds
    (one per blocking step) stay linearly independent.  ``H`` may be semi-definite when the
    objective is bounded below (a least-squares level: g in the range of H); each equality-
    constrained step is then the minimum-norm one.  Exact and finite on the tiny, degenerate
    QPs (more active bounds than variables) where ProxQP can fail.  Requires lo <= 0 <= up.
    """
    n = H.shape[0]
    fin_lo, fin_up = np.isfinite(lo), np.isfinite(up)
    A = np.vstack([C[fin_lo], -C[fin_up]])  # constraints A z >= b
    b = np.concatenate([lo[fin_lo], -up[fin_up]])
    if np.any(b > 0.0):
        return None
    scale = 1.0 + float(np.abs(H).max(initial=0.0)) + float(np.abs(g).max(initial=0.0))
    z = np.zeros(n)
    W: list[int] = []
    for _ in range(max_iter):
        grad = H @ z + g
        AW = A[W]
        k = len(W)
        if k < n:
            K = np.block([[H, AW.T], [AW, np.zeros((k, k))]])
            p = np.linalg.lstsq(K, np.concatenate([-grad, np.zeros(k)]), rcond=1e-13)[0][:n]
        else:  # the working set fixes z
            p = np.zeros(n)
        # stationary on the working set: no step, or one that decreases the objective by rounding only
        # (the minimum-norm step of a semi-definite H carries rounding noise of |H| eps)
        decrease = -float(grad @ p + 0.5 * (p @ (H @ p)))
        if float(np.abs(p).max(initial=0.0)) <= 1e-11 * (1.0 + float(np.abs(z).max(initial=0.0))) or decrease <= 1e-14 * scale * (
            1.0 + float(np.abs(z).max(initial=0.0))
        ):
            if k == 0:
                return z
            lam = np.linalg.lstsq(AW.T, grad, rcond=1e-13)[0]  # grad = A_W^T lam at a stationary point
            j = int(np.argmin(lam))
            if lam[j] >= -1e-12 * scale:
                return z
            W.pop(j)
            continue
        alpha, block = 1.0, None
        Ap = A @ p
        for i in np.flatnonzero(Ap < -1e-12 * np.linalg.norm(A, axis=1) * np.linalg.norm(p)):
            if i in W:
                continue
            t = (b[i] - A[i] @ z) / Ap[i]
            if t < alpha:
                alpha, block = max(t, 0.0), int(i)
        z = z + alpha * p
        if block is not None:
            W.append(block)
    return None


def _clamped_1d(B: np.ndarray, r: np.ndarray, reg: float, c: np.ndarray, lo: np.ndarray, up: np.ndarray, tol: float) -> np.ndarray:
    """argmin_z ||B z - r||^2 + reg z^2 over the interval {z : lo <= c z <= up} (contains 0), as a (1,) array.

    An entry of c zero to the rank tolerance ``tol`` (the free direction is known only to it) bounds nothing, as
    :meth:`Lexicographic.solve_box_qp` drops such rows: its sign is rounding, and with its bound active (a gap of 0)
    it would let rounding pick which way the level may move (seen on hextilt_flying_arm_5: a posture step of 0 or
    0.95 rad depending on a 1e-17)."""
    bb = float(B @ B) + reg
    z = float(B @ r) / bb if bb > 0.0 else 0.0
    zl, zu = -np.inf, np.inf
    small = tol * max(1.0, float(np.abs(c).max(initial=0.0)))
    for ci, li, ui in zip(c.tolist(), lo.tolist(), up.tolist()):
        if ci > small:
            zl, zu = max(zl, li / ci), min(zu, ui / ci)
        elif ci < -small:
            zl, zu = max(zl, ui / ci), min(zu, li / ci)
    if zl <= zu:
        z = min(max(z, zl), zu)
    else:  # rounding made the interval empty: stay at the earlier optimum
        z = 0.0
    return np.array([z])
