"""The compiled form of one QP-IK iteration on the default tasks (numba, ``pip install qprr[fast]``).

One call linearises every level of a hierarchy made of the default tasks of :mod:`qprr.ik.tasks` (``PoseTask``,
``PositionTask``, ``HoverTask``, ``BaseOrientationTask``, ``ComTask``, ``PostureTask``, one task per level) from what
:func:`qprr.ik.tasks.update_kinematics` left in Pinocchio's data -- the frame's LOCAL Jacobian and placement, the base
placement, the centre of mass and its Jacobian -- and solves the levels with
:func:`qprr.actuation.lexicographic_fast.lex_solve`: the tasks' ``linearize``, the levels' error norms and damping of
:meth:`qprr.ik.hierarchy.HierarchySolver.solve` and the lexicographic step, without returning to Python in between.
The readable forms are the tasks' ``linearize`` methods and ``HierarchySolver``'s numpy path, which stay the reference:
``tests/test_ik_fast.py`` checks every task's (J, e) and the whole step against them on random configurations and
targets of four platforms.

log6 and Jlog6 are those of Pinocchio (``pin.log6``, ``pin.Jlog6``: the body-frame logarithm of SE(3) and its
derivative along a right perturbation, M exp(delta)), written from their closed forms below; a test compares them.
This module is imported only when the numba kernel is asked for (``kernel="numba"``, or ``"auto"`` with numba
installed); numba caches its machine code beside the source.  That cache holds ``lex_solve`` compiled in, and numba
checks only this file's time stamp: after editing ``lexicographic_fast.py``, delete
``qprr/ik/__pycache__/iteration_fast.*.nbi`` and ``.nbc`` (or touch this file), or the IK runs the old kernel.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numba
import numpy as np
import pinocchio as pin

from ..actuation.lexicographic_fast import lex_solve
from ..actuation.lexicographic_fast import mm as _mm
from ..actuation.lexicographic_fast import mv as _mv
from ..model import Platform
from .tasks import BaseOrientationTask, ComTask, HoverTask, PoseTask, PositionTask, PostureTask

_JIT = {"cache": True, "nogil": True}


class FastTask(IntEnum):
    """The default tasks :func:`_task_rows` linearises, and the parameters each packs into its row of ``params``
    (followed by its row scale, one factor per row)."""

    POSE = 1  # M_d^-1: rotation (9, row-major), translation (3)
    POSITION = 2  # p_world target (3)
    HOVER = 3  # nothing
    BASE_ORIENTATION = 4  # R_target (9, row-major)
    COM = 5  # target_xy (2), thrust-axis point in B (3), basis E (2 x 3, row-major)
    POSTURE = 6  # q_arm reference (n_arm)


class FastStatus(IntEnum):
    """How :func:`iterate` ended: OK (the step), ALL_MET (every error entry below MET: the step is 0), NEEDS_NUMPY (a
    level needs the readable path's ProxQP; the levels' (J, e), errors and damping are valid), NOT_FINITE (a task's J
    or e)."""

    OK = 0
    ALL_MET = 1
    NEEDS_NUMPY = 2
    NOT_FINITE = 3


POSE, POSITION, HOVER, BASE_ORIENTATION, COM, POSTURE = (int(kind) for kind in FastTask)  # numba's constants
OK, ALL_MET, NEEDS_NUMPY, NOT_FINITE = (int(status) for status in FastStatus)


@numba.njit(**_JIT)
def _skew(v):
    """[v]x: [v]x u = v x u."""
    S = np.zeros((3, 3))
    S[0, 1], S[0, 2] = -v[2], v[1]
    S[1, 0], S[1, 2] = v[2], -v[0]
    S[2, 0], S[2, 1] = -v[1], v[0]
    return S


@numba.njit(**_JIT)
def log3(R):
    """(w, theta): the rotation vector of R (R = exp([w]x), |w| = theta in [0, pi]).

    With s = vee(R - R^T) / 2 = sin(theta) u and cos(theta) = (tr R - 1) / 2: w = theta s / sin(theta); near pi, where
    sin(theta) vanishes, the axis comes from the symmetric part (R + R^T) / 2 - cos(theta) I = (1 - cos(theta)) u u^T
    (its largest column), signed like s.
    """
    s = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    sin = np.sqrt(s @ s)
    cos = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    theta = np.arctan2(sin, cos)
    if theta < 1e-4:  # theta / sin(theta) = 1 + theta^2 / 6 + 7 theta^4 / 360
        return (1.0 + theta * theta / 6.0) * s, theta
    if cos > -0.9:
        return (theta / sin) * s, theta
    S = 0.5 * (R + R.T)
    for i in range(3):
        S[i, i] -= cos
    i = np.argmax(np.array([S[0, 0], S[1, 1], S[2, 2]]))
    u = S[:, i] / np.sqrt(S[i, i] * (1.0 - cos))
    if u @ s < 0.0:
        u = -u
    return theta * u, theta


# |B_2n| / (2n)! for n = 1..7 (Bernoulli numbers 1/6, 1/30, 1/42, 1/30, 5/66, 691/2730, 7/6): beta's series
_BETA_SERIES = np.array([1 / 6 / 2, 1 / 30 / 24, 1 / 42 / 720, 1 / 30 / 40320, 5 / 66 / 3628800, 691 / 2730 / 479001600, 7 / 6 / 87178291200])
SERIES_BELOW = 0.5  # [rad] beta from its series below it: the closed form loses 1e-8 to cancellation at 0.05 rad


@numba.njit(**_JIT)
def _beta(theta):
    """(beta, beta'(theta) / theta) with beta = 1 / theta^2 - sin(theta) / (2 theta (1 - cos(theta))), the coefficient
    of [w]x^2 in Jlog3 and in the inverse of SE(3)'s V(w).  Below SERIES_BELOW from cot's series,
    beta = sum_n |B_2n| theta^(2n - 2) / (2n)! (n >= 1; truncation below 1e-15 of beta'/theta there)."""
    t2 = theta * theta
    if theta < SERIES_BELOW:
        beta, dbeta_over_theta, power = _BETA_SERIES[0], 0.0, 1.0
        for n in range(2, _BETA_SERIES.shape[0] + 1):  # power = theta^(2n - 4) at the top of the loop
            # beta's term theta^(2n - 2) and its derivative over theta, (2n - 2) theta^(2n - 4)
            dbeta_over_theta += (2 * n - 2) * _BETA_SERIES[n - 1] * power
            power *= t2
            beta += _BETA_SERIES[n - 1] * power
        return beta, dbeta_over_theta
    sin, cos = np.sin(theta), np.cos(theta)
    beta = 1.0 / t2 - sin / (2.0 * theta * (1.0 - cos))
    dbeta_over_theta = -2.0 / (t2 * t2) + (1.0 + sin / theta) / (2.0 * t2 * (1.0 - cos))
    return beta, dbeta_over_theta


@numba.njit(**_JIT)
def jlog3(w, theta):
    """d log3(R exp([d]x)) / dd at d = 0 (Pinocchio's Jlog3): I + [w]x / 2 + beta(theta) [w]x^2."""
    W = _skew(w)
    beta, _ = _beta(theta)
    return np.eye(3) + 0.5 * W + beta * _mm(W, W)


@numba.njit(**_JIT)
def log6(R, p):
    """(v, w) = log6(M) of M = (R, p) in M's body frame (Pinocchio's log6): w = log3(R), v = V(w)^-1 p with
    V(w)^-1 = I - [w]x / 2 + beta(theta) [w]x^2."""
    w, theta = log3(R)
    W = _skew(w)
    beta, _ = _beta(theta)
    v = p - 0.5 * _mv(W, p) + beta * _mv(W, _mv(W, p))
    return v, w, theta


@numba.njit(**_JIT)
def jlog6(R, p):
    """d log6(M exp(delta)) / d delta at 0 (Pinocchio's Jlog6), delta = (dv, dw) a body twist: [[Jl, C Jl], [0, Jl]]
    with Jl = Jlog3(w) (d/d dv of V(w)^-1 (p + R dv) is V(w)^-1 R = Jlog3(w)) and C = d(V(w)^-1 p)/dw =
    [p]x / 2 + beta ((w . p) I + w p^T - 2 p w^T) + (beta' / theta) ((w . p) w - theta^2 p) w^T."""
    _, w, theta = log6(R, p)
    Jl = jlog3(w, theta)
    beta, dbeta = _beta(theta)
    wp = w @ p
    C = 0.5 * _skew(p) + beta * (wp * np.eye(3) + np.outer(w, p) - 2.0 * np.outer(p, w)) + dbeta * np.outer(wp * w - theta * theta * p, w)
    J = np.zeros((6, 6))
    J[0:3, 0:3] = Jl
    J[0:3, 3:6] = _mm(C, Jl)
    J[3:6, 3:6] = Jl
    return J


@numba.njit(**_JIT)
def _hover_gain(s, wz):
    """(g, c, ok): HoverTask's gain of e = g w_xy at |w_xy| = s, w_z = wz and c = (dg/ds) / s (``hover._gain``);
    ok False within 1e-6 rad of upside down."""
    if s > 1e-4 or (wz < 0.0 and s > 1e-6):
        a = np.arctan2(s, wz)
        return a / s, (wz * s - a) / s**3, True
    if wz > 0.0:
        return 1.0 + s * s / 6.0, -2.0 / 3.0 - 0.2 * s * s, True
    return 0.0, 0.0, False


@numba.njit(**_JIT)
def _hover_rows(R_base, J, e, jacobian):
    """HoverTask.linearize into J (2, nv) and e (2,): e = g(s, w_z) w_xy with w = R_b e3, and its Jacobian from
    dw = -R_b hat(e3) omega_body (columns 3, 4), unless ``jacobian`` is False (e alone)."""
    w = np.ascontiguousarray(R_base[:, 2])
    D = np.empty((3, 2))  # dw / d(omega_x, omega_y)
    D[:, 0] = -R_base[:, 1]
    D[:, 1] = R_base[:, 0]
    s = np.hypot(w[0], w[1])
    g, c, ok = _hover_gain(s, w[2])
    if not ok:  # upside down: tilt about body x, |e| = the angle (hover._upside_down_error)
        if jacobian:
            J[:, 3:5] = D[0:2]
        n = max(np.hypot(R_base[0, 1], R_base[1, 1]), 1e-300)
        a = np.arctan2(s, w[2])
        e[0], e[1] = -a * R_base[0, 1] / n, -a * R_base[1, 1] / n
        return
    if jacobian:  # de = g dw_xy + w_xy (c w_xy . dw_xy - dw_z)
        v = c * (w[0:2] @ D[0:2]) - D[2]
        J[:, 3:5] = g * D[0:2] + np.outer(w[0:2], v)
    e[0], e[1] = -g * w[0], -g * w[1]


@numba.njit(**_JIT)
def _task_rows(kind, par, frame, base, q, J, e, jacobian):
    """One task's (J, e) written into J (dim, nv) and e (dim,), before its row scale (``par``: its parameters); e alone
    (J untouched) when ``jacobian`` is False."""
    J_local, M_frame = frame
    M_base, com, Jcom = base
    R_b, p_b = np.ascontiguousarray(M_base[0:3, 0:3]), np.ascontiguousarray(M_base[0:3, 3])
    R_f, p_f = np.ascontiguousarray(M_frame[0:3, 0:3]), np.ascontiguousarray(M_frame[0:3, 3])
    par = np.ascontiguousarray(par)
    if kind == POSE:  # log6(M_d^-1 M) -> 0, J = Jlog6 J_local
        Rdi = par[0:9].copy().reshape(3, 3)
        R = _mm(Rdi, R_f)
        p = _mv(Rdi, p_f) + par[9:12]
        v, w, _ = log6(R, p)
        if jacobian:
            J[:, :] = _mm(jlog6(R, p), J_local)
        e[0:3], e[3:6] = -v, -w
    elif kind == POSITION:  # p -> target, J = rows 0..2 of the LOCAL_WORLD_ALIGNED Jacobian
        if jacobian:
            J[:, :] = _mm(R_f, J_local[0:3])
        e[:] = par[0:3] - p_f
    elif kind == HOVER:
        _hover_rows(R_b, J, e, jacobian)
    elif kind == BASE_ORIENTATION:  # log3(R_d^T R_b) -> 0, J = Jlog3 on the base angular velocity
        Rerr = _mm(par[0:9].copy().reshape(3, 3).T, R_b)
        w, theta = log3(Rerr)
        if jacobian:
            J[:, :] = 0.0
            J[:, 3:6] = jlog3(w, theta)
        e[:] = -w
    elif kind == COM:  # the CoG offset from the thrust axis, in B: E (c_b - point) -> target
        point, E = par[2:5], par[5:11].copy().reshape(2, 3)
        c_b = _mv(R_b.T, com - p_b)
        if jacobian:
            J[:, :] = _mm(_mm(E, R_b.T), Jcom)
            J[:, 0:3] -= E
            J[:, 3:6] += _mm(E, _skew(c_b))
        e[:] = par[0:2] - _mv(E, c_b - point)
    else:  # POSTURE: q_arm -> reference
        n_arm = e.shape[0]
        if jacobian:
            J[:, :] = 0.0
            for i in range(n_arm):
                J[i, 6 + i] = 1.0
        e[:] = par[0:n_arm] - q[7:]


@numba.njit(**_JIT)
def linearize(levels, frame, base, q, nv):
    """Every level's (J, e), stacked: (A (m, nv), b (m,)); ``levels`` = (kinds, dims, params) with params[k] the
    parameters of level k's task followed by its row scale (:func:`_task_rows`)."""
    return _stacked(levels, frame, base, q, nv, True)


@numba.njit(**_JIT)
def _stacked(levels, frame, base, q, nv, jacobian):
    """:func:`linearize`, or every level's e alone when ``jacobian`` is False (pass nv = 0: A is then empty)."""
    kinds, dims, params = levels
    offsets = np.zeros(kinds.shape[0] + 1, dtype=np.int64)
    offsets[1:] = np.cumsum(dims)
    A = np.zeros((offsets[-1], nv))
    b = np.zeros(offsets[-1])
    for k in range(kinds.shape[0]):
        J, e = A[offsets[k] : offsets[k + 1]], b[offsets[k] : offsets[k + 1]]
        _task_rows(kinds[k], params[k], frame, base, q, J, e, jacobian)
        scale = params[k, params.shape[1] - dims[k] :]
        for i in range(dims[k]):
            J[i] *= scale[i]
            e[i] *= scale[i]
    return A, b, offsets


@numba.njit(**_JIT)
def level_norms(levels, frame, base, q):
    """||e_k|| of every level (:func:`linearize`'s e_k, row scales included; no Jacobian is computed)."""
    _, b, offsets = _stacked(levels, frame, base, q, 0, False)
    norms = np.zeros(offsets.shape[0] - 1)
    for k in range(norms.shape[0]):
        e = b[offsets[k] : offsets[k + 1]]
        norms[k] = np.sqrt(np.sum(e * e))
    return norms


@numba.njit(**_JIT)
def iterate(levels, frame, base, q, bounds, weights, guesses):
    """One iteration of HierarchySolver.solve on compiled levels: (status, A, b, x, x_levels, norms).

    ``bounds`` = (arm lower, arm upper) limits; ``weights`` = (regularisation, lower_damping, rank_tol, met) with met
    :data:`qprr.ik.hierarchy.MET`; ``guesses``: lex_solve's active-set guesses, updated in place.  A, b: the levels'
    (J, e) stacked; norms rows: each level's error ||e_k||, damping, residual ||J_k x - e_k||.  status
    (:class:`FastStatus`): OK (x the step, x_levels each level's optimum), ALL_MET (every error entry below met:
    x = 0), NEEDS_NUMPY (a level needs the readable path's ProxQP: A, b, errors and damping are valid) or NOT_FINITE
    (a task's J or e).
    """
    arm_lower, arm_upper = bounds
    reg, lower_damping, rank_tol, met = weights
    nv = frame[0].shape[1]
    A, b, offsets = linearize(levels, frame, base, q, nv)
    K = offsets.shape[0] - 1
    norms = np.zeros((3, K))  # errors, damping, residuals
    x = np.zeros(nv)
    x_levels = np.zeros((K, nv))
    if not (np.isfinite(A.sum()) and np.isfinite(b.sum())):
        return NOT_FINITE, A, b, x, x_levels, norms
    for k in range(K):
        J, e = A[offsets[k] : offsets[k + 1]], b[offsets[k] : offsets[k + 1]]
        norms[0, k] = np.sqrt(np.sum(e * e))
        if k > 0:  # Levenberg damping of the lower levels, lower_damping ||J_k^T e_k||
            g = _mv(np.ascontiguousarray(J.T), e)
            norms[1, k] = lower_damping * np.sqrt(np.sum(g * g))
    if np.abs(b).max() <= met:
        norms[1] = 0.0
        norms[2] = norms[0]
        return ALL_MET, A, b, x, x_levels, norms
    lo_arm = arm_lower - q[7:]
    up_arm = arm_upper - q[7:]
    x, x_levels, ok = lex_solve(A, b, offsets, (lo_arm, up_arm, 6), np.zeros(0), (reg, norms[1].copy(), rank_tol), guesses)
    if not ok:
        return NEEDS_NUMPY, A, b, x, x_levels, norms
    r = _mv(A, x) - b
    for k in range(K):
        rk = r[offsets[k] : offsets[k + 1]]
        norms[2, k] = np.sqrt(np.sum(rk * rk))
    return OK, A, b, x, x_levels, norms


# ============================================================================ the Python side
_KINDS = {PoseTask: POSE, PositionTask: POSITION, HoverTask: HOVER, BaseOrientationTask: BASE_ORIENTATION, ComTask: COM, PostureTask: POSTURE}
"""The default tasks by their exact type (a subclass may linearise otherwise: it takes the readable path)."""


@dataclass(frozen=True)
class CompiledLevels:
    """A hierarchy of default tasks packed for :func:`iterate`: ``levels`` = (kinds, dims, params), ``frame`` the
    Pinocchio frame of its pose or position task (the end effector when it has none), ``rows`` each level's (start,
    end) in the stacked (J, e), ``no_com`` None when a level reads the centre of mass, else the (com, Jcom) of zeros
    :func:`kinematics` passes instead (its layout, F for Jcom, that of Pinocchio's)."""

    levels: tuple
    frame: int
    rows: tuple
    no_com: tuple | None
    tasks: tuple = ()  # the tasks packed, one per level (:func:`refill` rewrites their parameters)


def _fill(platform: Platform, task, kind: int, row: np.ndarray) -> int:
    """Write one default task's parameters into ``row`` (as :func:`_task_rows` reads them: :class:`FastTask`); its
    dimension."""
    if kind == POSE:
        inv = task.target.inverse()
        row[0:9] = inv.rotation.ravel()
        row[9:12] = inv.translation
        return 6
    if kind == POSITION:
        row[0:3] = task.target
        return 3
    if kind == HOVER:
        return 2
    if kind == BASE_ORIENTATION:
        row[0:9] = task.target.ravel()
        return 3
    if kind == COM:
        row[0:2] = task.target
        row[2:5] = platform.thrust_axis[0]
        row[5:11] = platform.thrust_axis_basis.ravel()
        return 2
    row[0 : platform.n_arm] = task.ref  # POSTURE
    return platform.n_arm


def compiled_levels(platform: Platform, levels) -> CompiledLevels | None:
    """``levels`` packed for :func:`iterate`, or None when they are not all default tasks, one per level, with at most
    one frame (pose or position) among them (the readable path then solves them)."""
    if any(len(tasks) != 1 for tasks in levels):
        return None
    tasks = [level[0] for level in levels]
    kinds = [_KINDS.get(type(task)) for task in tasks]
    if None in kinds:
        return None
    frames = {task.frame for task, kind in zip(tasks, kinds) if kind in (POSE, POSITION)}
    if len(frames) > 1:
        return None
    width = max(18, 2 * platform.n_arm)  # the widest parameters and row scale: a pose's 12 + 6, a posture's 2 n_arm
    params = np.zeros((len(tasks), width))
    dims = [_fill(platform, task, kind, row) for task, kind, row in zip(tasks, kinds, params)]
    ends = np.cumsum(dims).tolist()
    rows = tuple(zip([0, *ends[:-1]], ends))
    no_com = None if COM in kinds else (np.zeros(3), np.zeros((3, platform.nv), order="F"))
    packed = CompiledLevels((np.array(kinds, dtype=np.int64), np.array(dims, dtype=np.int64), params), 0, rows, no_com, tuple(tasks))
    refill(platform, packed)
    return CompiledLevels(packed.levels, frames.pop() if frames else platform.ee_frame, rows, no_com, tuple(tasks))


def refill(platform: Platform, packed: CompiledLevels) -> None:
    """Rewrite the parameters and row scales of ``packed``'s tasks (retargeted since they were packed) in place."""
    kinds, dims, params = packed.levels
    width = params.shape[1]
    for task, kind, row, dim in zip(packed.tasks, kinds.tolist(), params, dims.tolist()):
        _fill(platform, task, kind, row)
        row[width - dim :] = 1.0 if task.row_scale is None else task.row_scale


def same_tasks(levels, packed: CompiledLevels) -> bool:
    """Whether ``levels`` hold the very tasks ``packed`` was made of, one per level (then :func:`refill` suffices)."""
    return len(levels) == len(packed.tasks) and all(len(level) == 1 and level[0] is task for level, task in zip(levels, packed.tasks))


def kinematics(platform: Platform, data: pin.Data, packed: CompiledLevels) -> tuple[tuple, tuple]:
    """What :func:`iterate` reads from ``data`` (filled by :func:`qprr.ik.tasks.update_kinematics`): (the frame's
    LOCAL Jacobian, its placement), (the base placement, the centre of mass, its world Jacobian; zeros when no level
    reads them)."""
    J_local = pin.getFrameJacobian(platform.model, data, packed.frame, pin.LOCAL)
    com, Jcom = (data.com[0], data.Jcom) if packed.no_com is None else packed.no_com
    return (J_local, data.oMf[packed.frame].homogeneous), (data.oMi[1].homogeneous, com, Jcom)
