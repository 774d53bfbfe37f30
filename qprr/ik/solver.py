"""Inverse kinematics of any platform: options, the result type, the methods and the solver object.

    solver = IKSolver(platform, method="qp")          # owns its QPs: one per thread
    result = solver.solve(data, target, xi0=None)     # or ik.solve(platform, data, target, ...)

``target``: the desired end-effector placement in the world, a ``pin.SE3`` or a pair
``(p_world, R_world)``, or a position ``p_world`` (3,) alone (the orientation is then left free).
The problem solved is the *static* IK of an aerial manipulator: the end effector at the target,
the arm inside its joint limits and, unless an option says otherwise, the multirotor able to
hover there (roll = pitch = 0: a multirotor whose rotors all push along z_B holds still only
with its thrust vertical).  The CoG offset from the thrust axis is reported, never a failure.

Methods (the registry :data:`IK_METHODS`, default ``"qp"``; a plug-in adds its own, docs/extending.md):

* ``"qp"``    strict task-priority QP IK: 1 end-effector pose (or position), 2 hover (thrust
  axis vertical; on a fully actuated platform: the base level, :class:`BaseOrientationTask`), 3 CoG
  on the thrust axis, 4 arm posture; joint limits hard at every level (:mod:`qprr.ik.hierarchy`).
* ``"clika"`` closed-loop inverse kinematics (4.38)-(4.41) with the right pseudo-inverse
  (4.36) or the weighted one (4.34), Euler-integrated in thesis coordinates (4.30).
* ``"dls"``   damped least squares (Levenberg-Marquardt) on the SE(3) error log6, joint limits by
  an active set.

The thesis's analytic IGM (Algorithms 3-5) is the Q-PRR's own: the thesis plug-in registers it as method
``"igm"`` (on the Q-PRR only) and :func:`qprr.thesis.igm.solve_qprr` uses it as the QP's initial guess.

A method is an :class:`IKMethod`: its options class (a frozen dataclass deriving from :class:`Tolerances`) and
``make(platform, options) -> run``, called once per :class:`IKSolver`, whose ``run(ctx, xi) -> IKResult`` solves from
the start xi with the :class:`SolveContext` ``ctx``.  A method's parts are public, for methods written elsewhere:
:func:`finish` (evaluate a configuration and decide success, from an :class:`Ending`), :func:`failed_result`,
:func:`parse_target`, :func:`check_resolvable`, :func:`prepare_xi0`, :func:`hover_q`, :func:`pose_error_values`,
and the option checks :func:`check_positive` and :func:`check_count`.

Self-collision (option ``collision_free`` of every method, :class:`Tolerances`): success also needs the returned
configuration free of self-collision (:mod:`qprr.analysis.collision`: the arm against the body, the propeller discs and
itself).  A solve whose answer collides is restarted from other arm postures (``collision_restarts`` of them, drawn
uniformly in the joint limits with a fixed seed, the base placed so the end effector starts on the target); when
every answer collides the result is a failure with status "collision" naming the pairs in contact.  The check is
exact at the returned configuration (:meth:`qprr.analysis.collision.CollisionModel.colliding_pairs`); the path to it is not
checked.

Position error: ||p_e - p_d|| [m]; orientation error: ||log3(R_d^T R_e)|| [rad], both from
Pinocchio's forward kinematics at the returned configuration.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from enum import Enum

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..actuation.lexicographic import resolve_kernel
from ..errors import InputError, NonFiniteError, ShapeError, SolverError, UnknownNameError
from ..model import Platform, check_data, check_model_data, check_platform
from ..registry import Registry
from ..validation import as_array, as_int, as_matrix, as_real, as_vector
from .hierarchy import DEFAULT_KERNEL, MET, HierarchySolver
from .stepping import FLAT_STEPS, FREEZE_SCALE, LEVEL1_RATE, LIMITS_SLACK, PROGRESS_RTOL, REST_FACTOR, SATISFIABLE_RATIO, STATIONARY_STEP
from .tasks import BaseOrientationTask, BasePoseTask, ComTask, HoverTask, PoseTask, PositionTask, PostureTask, Task, update_kinematics

POLISHED = 1e-3
"""The QP IK stops before linearising again (the last step below ``settle_tol``, or every lower level met) only when
the pose (and hover) errors are below this fraction of their tolerances: with the quadratic convergence of the pose
level, one more step would take them to round-off, so an answer that is merely within its tolerance is polished."""

DEFAULT_METHOD = "qp"
"""The method of :class:`IKSolver` and :func:`solve` unless one is named: the strict task-priority QP."""

__all__ = [
    "DEFAULT_METHOD",
    "IK_METHODS",
    "METHODS",
    "OPTIONS",
    "ClikaOptions",
    "DLSOptions",
    "Ending",
    "IKMethod",
    "IKResult",
    "IKSolver",
    "QPMethod",
    "QPOptions",
    "SolveContext",
    "Tolerances",
    "check_count",
    "check_positive",
    "check_resolvable",
    "default_guess",
    "default_levels",
    "failed_result",
    "finish",
    "hover_q",
    "make_options",
    "parse_target",
    "pose_error_values",
    "pose_errors",
    "prepare_xi0",
    "solve",
    "solve_clika",
    "solve_dls",
]
"""The public API: the solver, the registry of methods, and the parts a method is written with (module docstring)."""


# ============================================================================ options
def check_positive(name: str, value, strict: bool = True) -> None:
    """An option's value checked: a finite number > 0 (``strict``) or >= 0; :class:`~qprr.errors.InputError` names ``name``."""
    as_real(value, f"option {name}", positive=strict, nonnegative=not strict)


def check_count(name: str, value) -> None:
    """An option's value checked: an integer >= 1 (an iteration count); :class:`~qprr.errors.InputError` names ``name``."""
    as_int(value, f"option {name}", lo=1)


def _check_bool(name: str, value) -> None:
    if not isinstance(value, bool):
        raise InputError(f"option {name} must be a bool, got {value!r}")


@dataclass(frozen=True)
class Tolerances:
    """What every method's options share: the success tolerances and the self-collision option (module docstring).
    A method's own options class derives from it and calls ``self._check_tolerances()`` in its ``__post_init__``."""

    position_tol: float = 1e-6  # [m] success threshold on ||p_e - p_d||
    orientation_tol: float = 1e-6  # [rad] success threshold on ||log3(R_d^T R_e)||
    hover_tol: float = 1e-6  # [rad] |roll|, |pitch| below it count as hover-feasible
    collision_free: bool = False  # success needs no self-collision (qprr.analysis.collision); restarts when the answer collides
    collision_restarts: int = 8  # other arm postures tried when the answer collides (collision_free)
    require_hover: bool | None = None  # success needs roll = pitch = 0 within hover_tol (None: for under-actuated platforms)

    def __post_init__(self):
        self._check_tolerances()

    def _check_tolerances(self) -> None:
        for name in ("position_tol", "orientation_tol", "hover_tol"):
            check_positive(name, getattr(self, name))
        _check_bool("collision_free", self.collision_free)
        as_int(self.collision_restarts, "option collision_restarts", lo=0)
        if self.require_hover is not None:
            _check_bool("require_hover", self.require_hover)


@dataclass(frozen=True)
class ClikaOptions(Tolerances):
    """CLIKA (4.41): xi_dot = J^+ K e, xi <- xi + dt xi_dot.  ``gains``: diag K (thesis example
    values); ``weights``: diag W of (4.34) in xi order (None: W = I, the right pseudo-inverse
    (4.36)); ``hover``: keep roll = pitch = 0 (drop their columns of J; the thesis uses all).
    ``require_hover``: success needs roll = pitch = 0 within ``hover_tol`` (default: for
    under-actuated platforms, as every method: the iteration may tilt the base, a multirotor
    cannot hold the pose so)."""

    gains: tuple = (40.0, 35.0, 10.0, 15.0, 12.0, 10.0)
    dt: float = 0.02
    weights: tuple | None = None
    hover: bool = False
    max_iter: int = 2000

    def __post_init__(self):
        self._check_tolerances()
        k = as_vector(self.gains, 6, "option gains")
        if np.any(k <= 0):
            raise InputError(f"option gains must be positive, got {k.tolist()}")
        if self.weights is not None:
            w = as_array(self.weights, "option weights")
            if w.ndim != 1 or w.shape[0] < 6 or np.any(~np.isfinite(w)) or np.any(w <= 0):
                raise InputError(f"option weights must be 6 + n_arm positive numbers, got {np.asarray(self.weights).tolist()}")
        check_positive("dt", self.dt)
        check_count("max_iter", self.max_iter)
        _check_bool("hover", self.hover)


@dataclass(frozen=True)
class DLSOptions(Tolerances):
    """Levenberg-Marquardt on f = log6(M_d^-1 M_e): (J^T J + lambda I) dv = -J^T f, lambda adapted
    (/3 on success, x4 on failure); arm joints held on their limits by an active set; ``hover``
    restricts dv to the directions that keep roll = pitch = 0.  ``require_hover``: as
    :class:`ClikaOptions` (default: for under-actuated platforms)."""

    hover: bool = True
    damping: float = 1e-3
    max_iter: int = 100

    def __post_init__(self):
        self._check_tolerances()
        check_positive("damping", self.damping)
        check_count("max_iter", self.max_iter)
        _check_bool("hover", self.hover)


@dataclass(frozen=True)
class QPOptions(Tolerances):
    """Strict task-priority QP IK.  ``posture``: q_arm of the posture level (default: the initial
    guess).  ``levels``: your own sequence of sequences of :class:`qprr.ik.tasks.Task` instead of
    :func:`default_levels`.  ``require_hover``: success needs roll = pitch = 0 (within
    ``hover_tol``; default: for under-actuated platforms).  ``step_tol``: stop when max |dv| < step_tol (a failure
    unless the pose is reached); ``settle_tol``: once the pose is reached, stop when max |dv| < settle_tol (the lower
    levels' tail converges linearly at best and moves nothing a tolerance sees).  ``eps_abs``, ``regularization``, ``rank_tol``,
    ``kernel`` ("auto", "numpy", "numba": the lexicographic steps compiled or not): of :class:`qprr.ik.hierarchy.HierarchySolver`."""

    posture: tuple | None = None
    levels: Sequence | None = None
    max_iter: int = 50
    step_tol: float = 1e-7
    settle_tol: float = 1e-5
    max_step: float = 2.0
    eps_abs: float = 1e-9
    regularization: float = 1e-7
    rank_tol: float = 1e-9
    kernel: str = DEFAULT_KERNEL.value

    def __post_init__(self):
        self._check_tolerances()
        resolve_kernel(self.kernel)
        check_count("max_iter", self.max_iter)
        for name in ("step_tol", "settle_tol", "max_step", "eps_abs", "rank_tol"):
            check_positive(name, getattr(self, name))
        check_positive("regularization", self.regularization, strict=False)
        if self.posture is not None:
            as_array(self.posture, "option posture")
        if self.levels is not None:
            ok = len(self.levels) > 0 and all(len(level) > 0 and all(isinstance(t, Task) for t in level) for level in self.levels)
            if not ok:
                raise InputError("option levels must be a non-empty sequence of non-empty sequences of qprr.ik.tasks.Task")


def make_options(method: str, options=None, table: Mapping | None = None):
    """The options object of ``method`` from None, a dict of overrides or an options instance (``table``: method name
    -> options class, default :data:`OPTIONS`, the classes of the registered methods)."""
    table = OPTIONS if table is None else table
    if method not in table:
        raise UnknownNameError("IK method", method, tuple(table))
    cls = table[method]
    if options is None:
        return cls()
    if isinstance(options, cls):
        return options
    if isinstance(options, Mapping):
        valid = [f.name for f in fields(cls)]
        for key in options:
            if key not in valid:
                raise UnknownNameError(f"option of IK method {method!r}", key, valid)
        return cls(**options)
    raise InputError(f"options for method {method!r} must be None, a dict or {cls.__name__}, got {type(options).__name__}")


# ============================================================================= result
class IKOutcome(str, Enum):
    """How an IK solve ended, :attr:`IKResult.status`: a ``str`` Enum equal to its value (``res.status == "converged"``
    holds; printed and written to JSON as the value)."""

    CONVERGED = "converged"
    UNREACHABLE = "unreachable"
    NOT_HOVER_FEASIBLE = "not_hover_feasible"
    LIMITS = "limits"
    MAX_ITERATIONS = "max_iterations"
    STALLED = "stalled"
    DIVERGED = "diverged"
    SOLVER_ERROR = "solver_error"
    COLLISION = "collision"

    def __str__(self) -> str:
        return self.value


@dataclass(slots=True)
class IKResult:
    """Outcome of an IK solve.

    ``success``: pose within tolerance, arm within limits and (when required) hover-feasible.
    ``status`` (:class:`IKOutcome`): "converged", "unreachable", "not_hover_feasible", "limits", "max_iterations",
    "stalled", "diverged", "solver_error" or "collision" (option ``collision_free``); ``reason`` says why in words when ``success`` is
    False (empty otherwise).  ``xi`` and ``q`` hold the returned (best-effort when failed)
    configuration.  Errors: world position [m] and rotation angle [rad] (0 for a position-only
    target); ``x_cm``, ``y_cm``: CoG offset from the thrust axis in B [m]; ``roll``, ``pitch``:
    base ZYX angles [rad]; ``wall_time`` [s]; ``initial_guess``: how the starting configuration
    was obtained; ``level_errors`` (method "qp"): ||e_k|| of each level at the returned
    configuration.
    """

    method: str
    success: bool
    status: IKOutcome
    reason: str
    xi: np.ndarray | None
    q: np.ndarray | None
    iterations: int
    position_error: float
    orientation_error: float
    x_cm: float
    y_cm: float
    roll: float
    pitch: float
    hover_feasible: bool
    within_limits: bool
    wall_time: float
    initial_guess: str
    level_errors: tuple = field(default=())

    def __post_init__(self) -> None:
        self.status = IKOutcome(self.status)  # a status given by its string (a method of a plug-in) becomes the Enum


# ============================================================================= inputs
def parse_target(target) -> tuple[np.ndarray, np.ndarray | None]:
    """(p_world, R_world) of a ``pin.SE3``, a ``(p_world, R_world)`` pair or a position alone (R None), validated.

    Raises ShapeError / NonFiniteError / InputError (R not a rotation: |R^T R - I| > 1e-9
    entry-wise or det R < 0).
    """
    if isinstance(target, pin.SE3):
        p, R = target.translation.copy(), target.rotation.copy()
    elif isinstance(target, (tuple, list)) and len(target) == 2:
        p = as_vector(target[0], 3, "target position")
        R = as_array(target[1], "target rotation")
        if R.shape != (3, 3):
            raise ShapeError(f"target rotation must have shape (3, 3), got {R.shape}")
    else:
        try:
            p = as_array(target, "target")
        except InputError:
            raise InputError(f"target must be a pinocchio.SE3, a (p_world, R_world) pair or a position (3,), got {target!r}") from None
        if p.shape != (3,):
            raise ShapeError(
                f"target must be a pinocchio.SE3, a (p_world, R_world) pair or a position of shape (3,), got an array of shape {p.shape}"
            )
        if not np.all(np.isfinite(p)):
            raise NonFiniteError(f"target must be finite, got p = {p.tolist()}")
        return p, None
    px, py, pz = p.tolist()
    if not (math.isfinite(px + py + pz) and math.isfinite(sum(R.ravel().tolist()))):
        raise NonFiniteError(f"target must be finite, got p = {p.tolist()}, R = {R.tolist()}")
    dev = _rotation_deviation(R)
    if not dev <= 1e-9:
        raise InputError(
            f"target rotation must be a rotation matrix (R^T R = I and det = +1 within 1e-9); deviation {dev:.3g}, "
            f"det = {float(np.linalg.det(R)):.3g}"
        )
    return p, R


def _rotation_deviation(R: np.ndarray) -> float:
    """How far R is from a rotation: the sum of |unit norm - 1| of its first two columns, |their dot product| and
    |third column - first x second| (0 for a rotation; any of R^T R != I or det R != +1 shows; NaN propagates)."""
    (A, B, C), (D, E, F), (G, H, I) = R.tolist()
    return (
        abs(A * A + D * D + G * G - 1.0)
        + abs(B * B + E * E + H * H - 1.0)
        + abs(A * B + D * E + G * H)
        + abs(D * H - G * E - C)
        + abs(G * B - A * H - F)
        + abs(A * E - D * B - I)
    )


def pose_errors(M: pin.SE3, p_d: np.ndarray, R_d: np.ndarray | None) -> tuple[float, float]:
    """(||p - p_d|| [m], ||log3(R_d^T R)|| [rad]) of a placement M against the target (angle 0 if R_d is None).

    The angle comes from sin = |skew(N)| / 2 and cos = (tr N - 1) / 2 with N = R_d^T R,
    accurate near 0 and pi (scalar code: cheaper than numpy on 3x3 matrices).
    """
    if not isinstance(M, pin.SE3):
        raise InputError(f"M must be a pinocchio.SE3, got {type(M).__name__}")
    if not (isinstance(p_d, np.ndarray) and p_d.shape == (3,) and p_d.dtype.kind == "f"):
        p_d = as_vector(p_d, 3, "p_d")
    if R_d is not None and not (isinstance(R_d, np.ndarray) and R_d.shape == (3, 3) and R_d.dtype.kind == "f"):
        R_d = as_matrix(R_d, (3, 3), "R_d")
    if not math.isfinite(float(p_d.sum())):
        raise NonFiniteError(f"p_d must be finite, got {p_d.tolist()}")
    if R_d is not None:
        dev = _rotation_deviation(R_d)  # R_d a rotation: unit orthogonal columns, right-handed
        if not dev < 1e-9:
            raise InputError(f"R_d must be a rotation matrix (R^T R = I, det = +1): deviation {dev:.3g}")
    return pose_error_values(M, p_d, R_d)


def pose_error_values(M: pin.SE3, p_d: np.ndarray, R_d: np.ndarray | None) -> tuple[float, float]:
    """:func:`pose_errors` of a target already checked (:func:`parse_target`): the IK's loop checks it once per solve."""
    x, y, z = M.translation.tolist()
    px, py, pz = p_d.tolist()
    pos = math.sqrt((x - px) ** 2 + (y - py) ** 2 + (z - pz) ** 2)
    if R_d is None:
        return pos, 0.0
    (a, b, c), (d, e, f), (g, h, i) = M.rotation.tolist()
    (A, B, C), (D, E, F), (G, H, I) = R_d.tolist()
    n21_12 = (C * b + F * e + I * h) - (B * c + E * f + H * i)
    n02_20 = (A * c + D * f + G * i) - (C * a + F * d + I * g)
    n10_01 = (B * a + E * d + H * g) - (A * b + D * e + G * h)
    trace = A * a + D * d + G * g + B * b + E * e + H * h + C * c + F * f + I * i
    sin = 0.5 * math.sqrt(n21_12 * n21_12 + n02_20 * n02_20 + n10_01 * n10_01)
    return pos, math.atan2(sin, 0.5 * (trace - 1.0))


def hover_q(platform: Platform, xi) -> np.ndarray:
    """q of a level configuration xi (roll = pitch = 0): quaternion of the yaw alone."""
    half = 0.5 * xi[5]
    return np.array([xi[0], xi[1], xi[2], 0.0, 0.0, math.sin(half), math.cos(half), *xi[6:]])


def default_guess(platform: Platform, data: pin.Data, p_world, R_world, q_arm=None) -> np.ndarray:
    """Initial guess xi0: level base, arm at its neutral posture (or at ``q_arm``), placed so that the end effector
    is at ``p_world`` with the yaw that best aligns its orientation with ``R_world`` (keeps the
    current yaw convention of a position target: yaw 0)."""
    check_model_data(platform, data)
    p_world = as_vector(p_world, 3, "p_world")
    if R_world is not None:
        R_world = ch.check_rotation(R_world, "R_world", 1e-9)
    q0 = platform.neutral_q()
    if q_arm is not None:
        q0[7:] = platform.check_arm_limits(q_arm, "q_arm")
    pin.framesForwardKinematics(platform.model, data, q0)
    bMe = data.oMi[1].actInv(data.oMf[platform.ee_frame])
    if R_world is None:
        psi = 0.0
    else:
        Bm = bMe.rotation @ R_world.T  # maximise tr(R_d^T Rz(psi) R_e0) = tr(Rz(psi) Bm)
        psi = math.atan2(Bm[0, 1] - Bm[1, 0], Bm[0, 0] + Bm[1, 1])
    c, s = math.cos(psi), math.sin(psi)
    pe = bMe.translation
    offset = (c * pe[0] - s * pe[1], s * pe[0] + c * pe[1], pe[2])
    xi = np.zeros(platform.n_xi)
    xi[0:3] = np.asarray(p_world) - offset
    xi[5] = psi
    xi[6:] = q0[7:]
    return xi


# ======================================================================== evaluation
@dataclass(frozen=True, slots=True)
class SolveContext:
    """What one solve is about, shared by the method and :func:`finish`: the platform and its data, the method's name,
    the parsed and checked target (p_d, R_d; R_d None for a position: :func:`parse_target`), the options, the start
    time t0 (perf_counter), the label of the initial guess, whether success needs hover, and ``unreachable_hint(R_d) -> str``, a platform-specific
    explanation of why a target is not reachable in hover (the Q-PRR: its end-effector y axis must be horizontal),
    "" if it is (None: no explanation)."""

    platform: Platform
    data: pin.Data
    method: str
    p_d: np.ndarray
    R_d: np.ndarray | None
    opts: object
    t0: float
    init: str
    require_hover: bool
    unreachable_hint: Callable | None = None


@dataclass(frozen=True, slots=True)
class Ending:
    """How a method's iteration ended: ``status``, ``reason`` (non-empty: a failure whatever the errors),
    ``iterations``, the levels' errors (method "qp"), whether ``data`` already holds FK, frames and CoM at q, and
    the pose errors at q when the method measured them there (else :func:`finish` measures them)."""

    status: IKOutcome
    reason: str = ""
    iterations: int = 0
    level_errors: tuple = ()
    kinematics_ready: bool = False
    pose_errors: tuple | None = None  # (position [m], angle [rad]) already measured at q with ``data``'s kinematics


def finish(ctx: SolveContext, q: np.ndarray, end: Ending, xi=None) -> IKResult:
    """Evaluate q with Pinocchio (FK, CoM) and build the result; decide success (``xi``: q's thesis coordinates
    when the method has them, else computed from q)."""
    platform, data = ctx.platform, ctx.data
    if end.kinematics_ready:  # data already holds FK, frames and CoM at q
        c = data.com[0]
        M = data.oMf[platform.ee_frame]
    else:
        c = pin.centerOfMass(platform.model, data, q, False)
        M = pin.updateFramePlacement(platform.model, data, platform.ee_frame)
    pos_err, rot_err = pose_error_values(M, ctx.p_d, ctx.R_d) if end.pose_errors is None else end.pose_errors
    base = data.oMi[1]
    Rb = base.rotation
    off = platform.thrust_axis_basis @ (base.actInv(c) - platform.thrust_axis[0])
    r20, r21, r22 = Rb[2].tolist()
    roll = math.atan2(r21, r22)
    pitch = math.atan2(-r20, math.hypot(r21, r22))
    q_arm = q[7:]
    within = bool(np.all(q_arm >= platform.arm_lower - LIMITS_SLACK) and np.all(q_arm <= platform.arm_upper + LIMITS_SLACK))
    if xi is None:
        xi = _xi_of_q(q, Rb)
    return _verdict(ctx, q, end, (pos_err, rot_err, float(off[0]), float(off[1]), roll, pitch, within), xi)


def _verdict(ctx: SolveContext, q: np.ndarray, end: Ending, measured: tuple, xi: np.ndarray | None) -> IKResult:
    """The result of q, its success decided, from what :func:`finish` measured there: (position error [m], angle
    [rad], x_cm, y_cm [m], roll, pitch [rad], the arm within its joint limits), and its thesis coordinates xi (None at
    the ZYX singularity)."""
    opts = ctx.opts
    pos_err, rot_err, x_cm, y_cm, roll, pitch, within = measured
    hover_ok = abs(roll) < opts.hover_tol and abs(pitch) < opts.hover_tol
    q_arm = q[7:]
    pose_ok = pos_err < opts.position_tol and rot_err < opts.orientation_tol
    status, reason = end.status, end.reason
    success = pose_ok and within and (hover_ok or not ctx.require_hover) and not reason
    if not success:
        status, reason = _failure(ctx, end, q_arm, (pos_err, rot_err, roll, pitch), (pose_ok, within))
    return IKResult(
        method=ctx.method,
        success=bool(success),
        status=status if not success else IKOutcome.CONVERGED,
        reason=reason,
        xi=xi,
        q=q,
        iterations=int(end.iterations),
        position_error=pos_err,
        orientation_error=rot_err,
        x_cm=x_cm,
        y_cm=y_cm,
        roll=roll,
        pitch=pitch,
        hover_feasible=bool(hover_ok),
        within_limits=within,
        wall_time=time.perf_counter() - ctx.t0,
        initial_guess=ctx.init,
        level_errors=end.level_errors,
    )


def _failure(ctx: SolveContext, end: Ending, q_arm: np.ndarray, errors: tuple, verdicts: tuple) -> tuple[str, str]:
    """(status, reason) of a failed solve, in words from the measured errors (pos_err, rot_err, roll, pitch) and the
    verdicts (pose_ok, within limits)."""
    pos_err, rot_err, roll, pitch = errors
    pose_ok, within = verdicts
    status, reason = end.status, end.reason
    hint = ctx.unreachable_hint(ctx.R_d) if (ctx.unreachable_hint is not None and ctx.R_d is not None) else ""
    if not reason:
        if not within:
            lo, hi = ctx.platform.arm_lower, ctx.platform.arm_upper
            status = IKOutcome.LIMITS
            reason = f"joints out of limits: q_arm = {q_arm.tolist()} not in [{lo.tolist()}, {hi.tolist()}]"
        elif not pose_ok:
            status = status if status != IKOutcome.CONVERGED else IKOutcome.STALLED
            reason = f"pose not reached after {end.iterations} iterations: position error {pos_err:.3g} m, orientation error {rot_err:.3g} rad"
        else:
            status = IKOutcome.NOT_HOVER_FEASIBLE
            if hint:
                reason = f"the pose is reached only with roll = {roll:.3g} rad, pitch = {pitch:.3g} rad: not reachable in hover ({hint})"
            elif not ctx.platform.fully_actuated:
                reason = _tilt_reason(ctx.platform, ctx.method, roll, pitch)
            else:
                reason = (
                    f"the pose is reached with roll = {roll:.3g} rad, pitch = {pitch:.3g} rad, not in hover: the iteration "
                    "stopped at a tilted configuration (joint limit or local minimum from this start, or a target that "
                    "needs a tilted base); try another xi0"
                )
    if status != IKOutcome.NOT_HOVER_FEASIBLE and ctx.require_hover and "hover" not in reason and hint:
        reason += f"; the target is unreachable in hover ({hint})"
    return status, reason


def _tilt_reason(platform: Platform, method: str, roll: float, pitch: float) -> str:
    """Why a pose reached only with a tilted base fails on an under-actuated platform: it hovers only with its collective
    thrust axis d (in B) vertical, so the end effector's orientations are those of a hovering base (its yaw) and of the
    arm's joints.  Method "qp" holds the hover as its second priority, below the pose: a tilt there is what the pose
    needs, which another start cannot change; the other methods do not hold the base level at all."""
    d_body = platform.thrust_axis[1]
    axis = "z_B" if np.allclose(d_body, (0.0, 0.0, 1.0), atol=1e-12) else f"{np.round(d_body, 4).tolist()} in B"
    why = (
        f"{platform.name} is under-actuated (wrench rank {platform.wrench_rank}) with its collective thrust along {axis}, which "
        "must stay vertical at hover, so the end effector can only take the orientations its base yaw and arm joints give"
    )
    if method == DEFAULT_METHOD:
        return f"the target orientation needs the base at roll = {roll:.3g} rad, pitch = {pitch:.3g} rad, not in hover: {why}"
    return (
        f"method {method} reached the pose with the base at roll = {roll:.3g} rad, pitch = {pitch:.3g} rad, not in hover (it "
        f"does not hold the base level; method {DEFAULT_METHOD} does, below the pose): {why}"
    )


def failed_result(method: str, status: IKOutcome, reason: str, iterations: int, t0: float, init: str) -> IKResult:
    """A result without a configuration (the method could not produce one)."""
    nan = float("nan")
    return IKResult(method, False, status, reason, None, None, iterations, nan, nan, nan, nan, nan, nan, False, False, time.perf_counter() - t0, init)


def check_resolvable(p_d: np.ndarray, position_tol: float) -> None:
    """Refuse a target so far from the origin that doubles near it are too coarse to tell a position error below
    ``position_tol``: at |p| = 1e17 m neighbouring doubles are 16 m apart and a "1e-16 m" error means nothing.
    Forward kinematics rounds to a few units in the last place of |p|: 16 of them must stay below a tenth of
    the tolerance (with the default 1e-6 m: |p| below 2^25 m, about 3.4e7 m)."""
    if not (isinstance(p_d, np.ndarray) and p_d.shape == (3,) and p_d.dtype.kind == "f"):
        p_d = as_vector(p_d, 3, "p_d")
    if not math.isfinite(float(p_d.sum())):
        raise NonFiniteError(f"p_d must be finite, got {p_d.tolist()}")
    position_tol = as_real(position_tol, "position_tol", positive=True)
    pmax = float(np.abs(p_d).max())
    ulp = float(np.spacing(pmax))
    if 16.0 * ulp > 0.1 * position_tol:
        limit = _resolvable_below(position_tol)
        raise InputError(
            f"target position {p_d.tolist()} m is too far from the origin: neighbouring doubles there are "
            f"{ulp:.3g} m apart, too coarse to check the position tolerance {position_tol:.3g} m; express the "
            f"target in a frame near the robot (|p| below about {limit:.3g} m) or loosen position_tol"
        )


def _resolvable_below(position_tol: float) -> float:
    """The power of two below which every |p| passes :func:`check_resolvable` (neighbouring doubles there are at
    most half of it times eps apart: 16 of them stay below a tenth of ``position_tol``)."""
    return 2.0 ** (math.floor(math.log2(0.1 * position_tol / 16.0 / np.finfo(float).eps)) + 1)


def _xi_of_q(q: np.ndarray, R: np.ndarray) -> np.ndarray | None:
    """xi of q whose base rotation is R (None at the ZYX singularity |cos theta| < EULER_TOL)."""
    (r00, _, _), (r10, _, _), (r20, r21, r22) = R.tolist()
    pitch = math.atan2(-r20, math.hypot(r21, r22))
    if abs(math.cos(pitch)) < ch.EULER_TOL:
        return None
    ql = q.tolist()
    return np.array([ql[0], ql[1], ql[2], math.atan2(r21, r22), pitch, math.atan2(r10, r00), *ql[7:]])


def prepare_xi0(platform: Platform, xi0, hover: bool) -> np.ndarray:
    """``xi0`` validated: shape, finite, arm inside its limits, level when ``hover``."""
    xi0 = ch.as_xi(xi0, "xi0", platform.n_xi)
    q_arm = xi0[6:]
    if not ((q_arm >= platform.arm_lower - LIMITS_SLACK).all() and (q_arm <= platform.arm_upper + LIMITS_SLACK).all()):
        platform.check_arm_limits(q_arm, "xi0[6:]")  # names the joints out of their limits
    if hover and (xi0[3] != 0.0 or xi0[4] != 0.0):
        raise InputError(f"xi0 roll and pitch must be 0 for a hover method (got phi = {xi0[3]!r}, theta = {xi0[4]!r}); set hover=False or level xi0")
    return xi0


# ============================================================================ methods
def _hover_cols(platform: Platform) -> np.ndarray:
    """Tangent (and xi) directions that keep roll = pitch = 0: x, y, z, yaw, the arm."""
    return np.r_[0, 1, 2, 5, np.arange(6, platform.nv)]


def solve_clika(ctx: SolveContext, xi: np.ndarray) -> IKResult:
    """CLIKA, Thesis (4.38)-(4.41): xi_dot = W^-1/2 (J W^-1/2)^+ K e integrated with step dt (4.30)."""
    platform, data, p_d, R_d, opts = ctx.platform, ctx.data, ctx.p_d, ctx.R_d, ctx.opts
    if R_d is None:
        raise InputError("method 'clika' needs a full pose target (p_world, R_world); use 'qp' or 'dls' for a position")
    model, fid = platform.model, platform.ee_frame
    n = platform.n_xi
    cols = _hover_cols(platform) if opts.hover else np.arange(n)
    K = np.asarray(opts.gains, dtype=float)
    weights = np.ones(n) if opts.weights is None else as_vector(opts.weights, n, "option weights")
    w_isqrt = 1.0 / np.sqrt(weights[cols])
    e = np.empty(6)
    status, reason = IKOutcome.MAX_ITERATIONS, ""
    it, best, best_it = 0, math.inf, 0
    while True:
        q = ch.xi_to_q(xi)
        Jw = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        pin.updateFramePlacement(model, data, fid)
        M = data.oMf[fid]
        e[0:3] = p_d - M.translation  # (4.38) position part
        e[3:6] = pin.log3(R_d @ M.rotation.T)  # orientation error on SO(3), world axes
        if np.linalg.norm(e[0:3]) < opts.position_tol and np.linalg.norm(e[3:6]) < opts.orientation_tol:
            status = IKOutcome.CONVERGED
            break
        if not np.isfinite(e).all() or np.abs(xi).max() > 1e6:
            status, reason = IKOutcome.DIVERGED, f"CLIKA diverged after {it} iterations"
            break
        if it >= opts.max_iter:
            break
        err = float(e @ e)
        if err < best * (1.0 - 1e-9):
            best, best_it = err, it
        elif it - best_it >= 100:  # no progress in 100 steps: the target is out of reach
            status, reason = IKOutcome.STALLED, f"CLIKA stalled after {it} iterations (error stopped decreasing)"
            break
        it += 1
        J = (Jw @ ch.rate_map(xi))[:, cols]  # (4.13): [p_e_dot; omega_e] = J xi_dot
        # (4.41) with the weighted pseudo-inverse W^-1/2 (J W^-1/2)^+, equal to (4.34) (and to
        # (4.36) for W = I) when J has full row rank; under hover J may lose rank (the Q-PRR's
        # end-effector roll about x_e is not controllable), where (4.34) is singular.
        xi[cols] += opts.dt * (w_isqrt * (np.linalg.pinv(J * w_isqrt, rcond=1e-10) @ (K * e)))  # (4.30)
    xi[3:6] = ch.wrap_angle(xi[3:6])
    q = ch.xi_to_q(xi)
    if status == IKOutcome.MAX_ITERATIONS:
        reason = f"CLIKA did not converge in {opts.max_iter} iterations"
    return finish(ctx, q, Ending(status, reason, it))


def solve_dls(ctx: SolveContext, xi: np.ndarray) -> IKResult:
    """Damped least squares (Levenberg-Marquardt) on log6 (or on the position error for a position target)."""
    platform, data, p_d, R_d, opts = ctx.platform, ctx.data, ctx.p_d, ctx.R_d, ctx.opts
    model, fid = platform.model, platform.ee_frame
    cols = _hover_cols(platform) if opts.hover else np.arange(platform.nv)
    lo, hi = platform.arm_lower, platform.arm_upper
    q = ch.xi_to_q(xi)
    dv = np.zeros(platform.nv)
    M_d_inv = pin.SE3(R_d, p_d).inverse() if R_d is not None else None

    def evaluate(q):
        pin.framesForwardKinematics(model, data, q)
        Me = data.oMf[fid]
        if M_d_inv is None:
            f = Me.translation - p_d
            return Me, None, f, float(f @ f)
        Merr = M_d_inv * Me
        f = pin.log6(Merr).vector
        return Me, Merr, f, float(f @ f)

    Me, Merr, f, cost = evaluate(q)
    lam = opts.damping
    status, it, slow = IKOutcome.MAX_ITERATIONS, 0, 0  # finish() words the reason from the measured errors
    while True:
        pos_err, rot_err = pose_error_values(Me, p_d, R_d)
        if pos_err < opts.position_tol and rot_err < opts.orientation_tol:
            status = IKOutcome.CONVERGED
            break
        if it >= opts.max_iter:
            break
        it += 1
        if M_d_inv is None:
            J_all = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)[0:3]
        else:
            J_all = pin.Jlog6(Merr) @ pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
        # (J^T J + lam I)^-1 J^T f through the SVD J = U S V^T: V S/(S^2 + lam) U^T f.  An arm
        # joint on a limit whose step points outwards is frozen (active set), otherwise the
        # projection would halve the remaining error per iteration instead of converging.
        free = cols
        for _ in range(4):
            U, sv, Vt = np.linalg.svd(J_all[:, free], full_matrices=False)
            Utf = U.T @ f
            step = -(Vt.T @ (sv / (sv * sv + lam) * Utf))
            block = [
                j for j, d in zip(free, step) if j >= 6 and ((d < 0 and q[j + 1] <= lo[j - 6] + 1e-12) or (d > 0 and q[j + 1] >= hi[j - 6] - 1e-12))
            ]
            if not block:
                break
            free = np.array([j for j in free if j not in block])
        dv[:] = 0.0
        while True:
            dv[free] = -(Vt.T @ (sv / (sv * sv + lam) * Utf))
            q_new = pin.integrate(model, q, dv)
            np.clip(q_new[7:], lo, hi, out=q_new[7:])  # joint limits by projection
            Me_n, Merr_n, f_n, cost_n = evaluate(q_new)
            if cost_n < cost:
                slow = slow + 1 if cost_n > (1.0 - 1e-6) * cost else 0
                q, Me, Merr, f, cost = q_new, Me_n, Merr_n, f_n, cost_n
                lam = max(lam / 3.0, 1e-12)
                break
            lam *= 4.0
            if lam > 1e10:
                break
        if lam > 1e10 or slow >= 3:
            status = IKOutcome.STALLED
            break
    return finish(ctx, q, Ending(status, "", it))


def _require_hover(platform: Platform, opts) -> bool:
    """The success definition's hover clause: the option if given, else hover needed for an under-actuated platform."""
    return (not platform.fully_actuated) if opts.require_hover is None else bool(opts.require_hover)


def default_levels(platform: Platform, target, q_arm_posture, base_yaw: float = 0.0) -> list[list[Task]]:
    """The hierarchy of method "qp": end-effector pose (or position) > hover > CoG on the thrust axis > posture.

    On a fully actuated platform level 2 is the base orientation (level, yaw ``base_yaw`` [rad])
    instead of hover: such a platform may hold a tilted base, but a level one costs the least
    thrust.  A list you may edit and pass back through the ``levels`` option.
    """
    check_platform(platform)
    base_yaw = as_real(base_yaw, "base_yaw", unit="rad")
    q_arm_posture = platform.check_arm_limits(q_arm_posture, "q_arm_posture")
    if not isinstance(target, pin.SE3):
        target = as_vector(target, 3, "target")
    return _levels(platform, target, q_arm_posture, base_yaw)


def _levels(platform: Platform, target, q_arm_posture: np.ndarray, base_yaw: float) -> list[list[Task]]:
    """:func:`default_levels` of inputs already checked (the IK's entry point did)."""
    if isinstance(target, pin.SE3):
        first = PoseTask(platform, target)
    else:
        first = PositionTask(platform, target)
    if platform.fully_actuated:
        second = BaseOrientationTask(platform, ch.euler_to_rotation([0.0, 0.0, base_yaw]))
    else:
        second = HoverTask()
    return [[first], [second], [ComTask()], [PostureTask(platform, q_arm_posture)]]


class _DefaultLevels:
    """The tasks of :func:`default_levels`, built once per solver and retargeted per solve (building four tasks
    cost about a tenth of a solve started at the answer)."""

    def __init__(self, platform: Platform) -> None:
        self.platform = platform
        self.by_kind: dict[str, list[list[Task]]] = {}

    def levels(self, target, q_arm_posture: np.ndarray, base_yaw: float) -> list[list[Task]]:
        """The hierarchy aimed at ``target`` (a ``pin.SE3`` or a position), posture ``q_arm_posture``, base yaw [rad]."""
        kind = "pose" if isinstance(target, pin.SE3) else "position"
        levels = self.by_kind.get(kind)
        if levels is None:
            levels = self.by_kind[kind] = _levels(self.platform, target, q_arm_posture, base_yaw)
            return levels
        levels[0][0].set_target(target)
        if self.platform.fully_actuated:
            levels[1][0].set_target(ch.euler_to_rotation([0.0, 0.0, base_yaw]))
        levels[3][0].ref = q_arm_posture  # a copy, inside the limits (checked where the solve got it: prepare_xi0, option posture)
        return levels


class IKSolver:
    """An IK method bound to a platform, with the solver state it needs (QPs, warm starts).

    ``initial_guess``: callable ``(platform, data, p_world, R_world) -> (xi0, label)`` used when
    ``solve`` gets no ``xi0`` (default: :func:`default_guess`); ``unreachable_hint``: callable
    ``R_world -> str`` explaining why a target is not reachable in hover ("" if it is).  One
    solver per thread: its result depends on the inputs only (warm starts are reset per solve).
    """

    def __init__(
        self,
        platform: Platform,
        method: str = DEFAULT_METHOD,
        options=None,
        *,
        initial_guess: Callable | None = None,
        unreachable_hint: Callable | None = None,
    ) -> None:
        check_platform(platform)
        if initial_guess is not None and not callable(initial_guess):
            raise InputError(f"initial_guess must be a callable (platform, data, p_world, R_world) -> (xi0, label), got {initial_guess!r}")
        if unreachable_hint is not None and not callable(unreachable_hint):
            raise InputError(f"unreachable_hint must be a callable R_world -> str, got {unreachable_hint!r}")
        self.platform = platform
        self.method = method
        self.options = make_options(method, options)
        self.initial_guess = initial_guess
        self.unreachable_hint = unreachable_hint
        self._method_run = IK_METHODS[method].make(platform, self.options)  # the method's state (the QP's engine...)
        self._resolvable = _resolvable_below(self.options.position_tol)  # [m] targets nearer pass check_resolvable
        self._hover_needed = _require_hover(platform, self.options)  # the success definition's hover clause
        self._data = None  # the last pin.Data checked (check_data)
        self._collision = None
        if self.options.collision_free:
            from ..analysis.collision import collision_model

            self._collision = collision_model(platform)

    @property
    def engine(self) -> HierarchySolver | None:
        """The :class:`~qprr.ik.hierarchy.HierarchySolver` method ``"qp"`` keeps between solves (its QPs, joint limits,
        kernel and compiled loop; to read, not to replace), or None for a method that keeps none."""
        return self._method_run.engine if isinstance(self._method_run, QPMethod) else None

    def _guess(self, data, p_d, R_d, hover: bool):
        if self.initial_guess is not None:
            xi, label = self.initial_guess(self.platform, data, p_d, R_d)
            return prepare_xi0(self.platform, xi, hover).copy(), label
        return default_guess(self.platform, data, p_d, R_d), "level base, arm at its neutral posture, end effector on the target"

    def solve(self, data: pin.Data, target, xi0=None) -> IKResult:
        """Configuration reaching ``target`` from ``xi0`` (default: the initial guess); see the module docstring."""
        t0 = time.perf_counter()
        if data is None or data is not self._data:  # a pin.Data keeps the model it was made for: checked once
            self._data = check_data(self.platform, data)
        p_d, R_d = parse_target(target)
        opts = self.options
        if not np.abs(p_d).max() < self._resolvable:  # finite (parse_target): only a target far out needs the test
            check_resolvable(p_d, opts.position_tol)
        hover = isinstance(opts, (ClikaOptions, DLSOptions)) and opts.hover  # method "qp" reaches hover as its level 2
        if xi0 is not None:
            xi, init = prepare_xi0(self.platform, xi0, hover).copy(), "xi0 (given)"
        else:
            xi, init = self._guess(data, p_d, R_d, hover)
        result = self._run(data, p_d, R_d, xi, init, t0)
        if self._collision is not None:
            result = self._collision_free(data, p_d, R_d, result, t0)
        return result

    def _run(self, data: pin.Data, p_d, R_d, xi: np.ndarray, init: str, t0: float) -> IKResult:
        ctx = SolveContext(self.platform, data, self.method, p_d, R_d, self.options, t0, init, self._hover_needed, self.unreachable_hint)
        return self._method_run(ctx, xi)

    def _collision_free(self, data: pin.Data, p_d, R_d, result: IKResult, t0: float) -> IKResult:
        """Restart from other arm postures while the answer collides (module docstring); a colliding answer never
        leaves as a success."""
        platform, cm = self.platform, self._collision
        if not result.success:
            return result
        hits = cm.colliding_pairs(result.q)
        if not hits:
            return result
        rng = np.random.default_rng(0)
        lo, hi = np.maximum(platform.arm_lower, -math.pi), np.minimum(platform.arm_upper, math.pi)
        for k in range(self.options.collision_restarts):
            xi = default_guess(platform, data, p_d, R_d, rng.uniform(lo, hi))
            label = f"restart {k + 1} (collision-free option): random arm posture, end effector on the target"
            attempt = self._run(data, p_d, R_d, xi, label, t0)
            if attempt.success:
                attempt_hits = cm.colliding_pairs(attempt.q)
                if not attempt_hits:
                    return attempt
                result, hits = attempt, attempt_hits
        pairs = ", ".join(f"{a} / {b}" for a, b in hits)
        return replace(
            result,
            success=False,
            status=IKOutcome.COLLISION,
            wall_time=time.perf_counter() - t0,
            reason=f"the pose is reached only in self-collision ({pairs}) after {self.options.collision_restarts} "
            "restarts from other arm postures (collision_restarts)",
        )


class QPMethod:
    """Method ``"qp"``: the strict task-priority QP IK (module docstring), with the state one :class:`IKSolver` keeps
    between solves (its :class:`~qprr.ik.hierarchy.HierarchySolver`, the default levels).  ``QPMethod(platform, options)``
    is the method's ``make``; calling it, ``run(ctx, xi)``, solves."""

    def __init__(self, platform: Platform, options: QPOptions) -> None:
        self.platform, self.options = platform, options
        self.engine = HierarchySolver(
            platform, eps_abs=options.eps_abs, regularization=options.regularization, rank_tol=options.rank_tol, kernel=options.kernel
        )
        self.default_levels = _DefaultLevels(platform)
        self._settings = (  # the compiled loop's settings (qprr.ik.newton_fast.NewtonLoop)
            options.position_tol,
            options.orientation_tol,
            options.hover_tol,
            POLISHED,
            options.settle_tol,
            options.step_tol,
            options.max_step,
            options.max_iter,
        )

    def __call__(self, ctx: SolveContext, xi: np.ndarray) -> IKResult:
        platform, opts, engine = self.platform, self.options, self.engine
        q = ch.xi_to_q(xi)
        posture = None if opts.posture is None else platform.check_arm_limits(opts.posture, "option posture").copy()
        levels = opts.levels
        if levels is None:  # the default levels; their posture level holds the option's, else the start's arm
            target = pin.SE3(ctx.R_d, ctx.p_d) if ctx.R_d is not None else ctx.p_d
            levels = self.default_levels.levels(target, q[7:].copy() if posture is None else posture, float(xi[5]))
        loop = engine.newton_loop(platform, levels, self._settings)  # its warm starts forgotten (a new solve)
        if loop is not None and loop.packed.frame == platform.ee_frame:  # the success test's frame: the loop's pose errors
            shift = _BaseShift.of(levels, POLISHED * opts.position_tol)
            out = loop.run(ctx.data, q, (ctx.p_d, ctx.R_d), ctx.require_hover, None if shift is None else shift.target)
            if out is not None:  # the loop measured q as finish does (tested against it)
                q, it, outcome, level_errors, measured, xi = out
                return _verdict(ctx, q, Ending(IKOutcome[outcome.name], "", it, level_errors), measured, xi)
        engine.reset()  # the readable loop, warm starts forgotten: no compiled loop, or a pass it cannot take
        return self._readable(ctx, q, levels)

    def _readable(self, ctx: SolveContext, q: np.ndarray, levels) -> IKResult:
        """The readable Newton loop from q (the reference of :mod:`qprr.ik.newton_fast`'s compiled loop)."""
        platform, data, opts, engine = self.platform, ctx.data, self.options, self.engine
        it, step, end = 0, None, Ending(IKOutcome.MAX_ITERATIONS)
        shaper = _StepShaper(opts)
        shift = _BaseShift.of(levels, POLISHED * opts.position_tol)
        settled = False  # the last step was below settle_tol
        try:
            while it < opts.max_iter:
                update_kinematics(platform, data, q)
                moved = 0.0 if shift is None else shift.apply(platform, data, q)
                pos_err, rot_err = pose_error_values(data.oMf[platform.ee_frame], ctx.p_d, ctx.R_d)
                pose_ok = pos_err < opts.position_tol and rot_err < opts.orientation_tol
                if pose_ok:  # the base is moved on the way to the pose only (the step control then sees every error)
                    shift = None
                polished = pos_err < POLISHED * opts.position_tol and rot_err < POLISHED * opts.orientation_tol
                if it and polished and (not ctx.require_hover or _hovering(data, POLISHED * opts.hover_tol)):
                    tol = min(opts.position_tol, opts.orientation_tol, opts.hover_tol)
                    # the lower levels are tested only when the last step's linear model met them all (an unsatisfiable
                    # level, e.g. the posture, keeps its residual: no task is evaluated for nothing)
                    met = None
                    if not settled and all(r < tol for r in step.residuals[1:]):
                        met = _lower_levels_met(engine, data, q, levels, tol)
                    if settled or met is not None:
                        # the pose (and hover) holds after a step below settle_tol, or with every lower level met to the
                        # tightest tolerance: the step from here would be smaller still; stop without linearising
                        end = Ending(IKOutcome.CONVERGED, "", it, met or (), True, (pos_err, rot_err))
                        step = None
                        break
                it += 1
                # frozen levels are not solved; the tasks' targets are read at the first step only (none changes within a solve)
                step = engine.solve(platform, data, q, shaper.active(levels), validate=it == 1 and opts.levels is not None, refresh=it == 1)
                dv, stop = shaper.shape(step, pose_ok, moved)
                if dv is not None:
                    q = pin.integrate(platform.model, q, dv)
                    np.clip(q[7:], engine.lower, engine.upper, out=q[7:])  # remove the QP's bound slack
                    settled = shaper.largest < opts.settle_tol
                if stop:
                    ready = dv is None
                    status = IKOutcome.STALLED if stop == "converged_stationary" and not pose_ok else IKOutcome.CONVERGED
                    end = Ending(status, kinematics_ready=ready, pose_errors=(pos_err, rot_err) if ready else None)
                    break
        except SolverError as exc:
            return finish(ctx, q, Ending(IKOutcome.SOLVER_ERROR, str(exc), it))
        ready = end.kinematics_ready
        if not (end.level_errors or ready):  # the level errors and finish read the kinematics at the returned q
            update_kinematics(platform, data, q)
        levels_out = end.level_errors or _level_errors(engine, data, q, levels, ready and shaper.kept is None, step)
        return finish(ctx, q, Ending(end.status, "", it, levels_out, ready or not end.level_errors, end.pose_errors))


class _BaseShift:
    """The world translation of the base that puts level 1's frame on its target position, applied before each
    linearisation (a Newton step's first-order model misplaces a frame the base swings about: after a 2 rad turn of
    the yaw the first step leaves the frame 0.3 m off while its orientation is exact to 1e-7).  A translation of the
    free-flyer base moves every frame by the same world vector and turns none: it meets level 1's position exactly
    and changes no other error of these levels (roll, pitch, the base orientation, the CoG offset in B and the arm
    are the same), so the hierarchy's fixed points stay those of the Newton steps alone.  Only for a level 1 of one
    pose or position task above levels of the tasks that do not see the base position (:meth:`of`)."""

    UNMOVED = (HoverTask, BaseOrientationTask, ComTask, PostureTask)  # the tasks whose errors a base translation keeps

    def __init__(self, frame: int, target: np.ndarray, threshold: float) -> None:
        self.frame, self.target, self.threshold = frame, target, threshold

    @classmethod
    def of(cls, levels, threshold: float) -> _BaseShift | None:
        """The shift for ``levels``, or None when it does not apply; the frame moves when it is over ``threshold`` [m]
        (along an axis) from its target."""
        if len(levels[0]) != 1 or not all(type(t) in cls.UNMOVED for level in levels[1:] for t in level):
            return None
        first = levels[0][0]
        if type(first) in (PoseTask, BasePoseTask):  # exact types: a subclass may mean another target
            return cls(first.frame, first.target.translation, threshold)
        if type(first) is PositionTask:
            return cls(first.frame, first.target, threshold)
        return None

    def apply(self, platform: Platform, data: pin.Data, q: np.ndarray) -> float:
        """Move the base of q (in place) and ``data``'s kinematics when the frame is off its target; the distance
        moved [m] (0: not moved)."""
        d_world = self.target - data.oMf[self.frame].translation
        if np.abs(d_world).max() <= self.threshold:
            return 0.0
        q[0:3] += d_world  # the free flyer's translation is in the world frame
        update_kinematics(platform, data, q)
        return float(np.linalg.norm(d_world))


class _StepShaper:
    """The QP IK's step control and stopping tests, iteration after iteration.

    ``shape(step, pose_ok, moved) -> (dv or None, stop)`` (``moved``: how far :class:`_BaseShift` moved the base
    before this step was linearised, m): dv the step to take (None: none, q is the answer and ``data``
    holds its kinematics), stop "" to go on, else "converged_stationary" (the step vanished: converged if the pose
    holds, stalled otherwise) or "converged" (the pose holds and the lower levels stopped improving).
    ``kept``: None, or the number of leading levels still solved once the lower ones were frozen (:meth:`_freeze`).
    """

    def __init__(self, opts: QPOptions) -> None:
        self.opts = opts
        self.lower_prev, self.flat = None, 0
        self.e1_prev, self.rest_scale = math.inf, 1.0
        self.kept = None  # None: every level steps; k: levels 1..k only, the levels after them are frozen
        self.largest = math.inf  # max |dv| of the last step :meth:`shape` returned
        self._prefix = None  # levels[:kept], sliced once (the compiled step keeps the levels it packed by identity)

    def active(self, levels):
        """The levels still solved: all of them, or the leading ``kept`` once the lower ones are frozen."""
        if self.kept is None:
            return levels
        if self._prefix is None or len(self._prefix) != self.kept:
            self._prefix = levels[: self.kept]
        return self._prefix

    def shape(self, step, pose_ok: bool, moved: float = 0.0):
        opts = self.opts
        largest = float(np.abs(step.dv).max())
        small = largest < (opts.settle_tol if pose_ok else opts.step_tol)
        if small and largest < STATIONARY_STEP:
            return None, "converged_stationary"
        # the lower levels may converge only linearly (damped, unsatisfiable): once the pose holds, stop when their
        # errors no longer decrease, compared in priority order (the first level that moved decides: a posture error
        # rising while the hover error falls is progress)
        errors = step.errors
        lower = errors[1 : self.kept]
        self.flat = self.flat + 1 if (pose_ok and not _lexicographic_progress(lower, self.lower_prev)) else 0
        self.lower_prev = lower
        if self.flat >= FLAT_STEPS:
            return None, "converged"
        # level 1 converges quadratically on its own; the lower levels' part of the step moves along level 1's kernel
        # at first order only, and its second-order effect can hold level 1 off its target: when level 1 stops halving
        # its error, that part is halved until it does again (doubled back, up to full, when level 1 progresses)
        e1 = math.hypot(errors[0], moved)  # level 1's error before the base was moved onto its position (_BaseShift)
        if not pose_ok and e1 > LEVEL1_RATE * self.e1_prev:
            self.rest_scale *= REST_FACTOR
        elif self.rest_scale < 1.0:
            self.rest_scale = min(1.0, self.rest_scale / REST_FACTOR)
        self.e1_prev = e1
        dv = step.dv
        if self.rest_scale <= FREEZE_SCALE:
            self._freeze(step)
        if self.kept is not None:
            dv = step.dv_levels[self.kept - 1]
            largest = float(np.abs(dv).max())
            small = largest < (opts.settle_tol if pose_ok else opts.step_tol)
        if largest > opts.max_step or self.rest_scale < 1.0:
            d1 = step.dv_first
            rest = (dv - d1) * self.rest_scale
            m1, m2 = float(np.abs(d1).max()), float(np.abs(rest).max())
            dv = (d1 if m1 <= opts.max_step else d1 * (opts.max_step / m1)) + (rest if m2 <= opts.max_step else rest * (opts.max_step / m2))
            largest = float(np.abs(dv).max())
        self.largest = largest  # max |dv| of the step returned
        # small: stationary, every level settled; the last (tiny) Newton step is kept
        return dv, ("converged_stationary" if small else "")

    def _freeze(self, step) -> None:
        """Level 1 failed twice in a row to halve its error although the lower share was halved: the lower levels hold
        it off.  A level the linearisation cannot meet keeps a Gauss-Newton step that ignores the curvature its
        residual carries (its own task's and the levels' above it): the iteration may cycle around its constrained
        optimum instead of converging to it.  The lowest level still stepping is frozen where it is (never one of the
        leading levels the linearisation meets: :func:`_satisfiable_prefix`) and the step control starts afresh."""
        n = len(step.errors) if self.kept is None else self.kept
        kept = max(n - 1, _satisfiable_prefix(step))
        if kept < n:
            self.kept, self.rest_scale, self.e1_prev, self.lower_prev = kept, 1.0, math.inf, None


def _satisfiable_prefix(step) -> int:
    """How many leading levels the linearisation meets: level 1 always, then each level whose error the step's
    linear model at least halves (||J_k dv - e_k|| <= SATISFIABLE_RATIO ||e_k||) or which is met (MET), up to the first
    that is not."""
    kept = 1
    for e, r in zip(step.errors[1:], step.residuals[1:]):
        if not (e <= MET or r <= SATISFIABLE_RATIO * e):
            break
        kept += 1
    return kept


def _lexicographic_progress(errors, previous) -> bool:
    """Whether ``errors`` (one norm per level, highest priority first) improve on ``previous``: the first level
    whose error changed by more than ``PROGRESS_RTOL`` (relative) decreased."""
    if previous is None:
        return True
    for e, e0 in zip(errors, previous):
        if abs(e - e0) > PROGRESS_RTOL * max(e, e0):
            return e < e0
    return False


def _level_errors(engine: HierarchySolver, data, q, levels, ready, step) -> tuple[float, ...]:
    """||e_k|| of every level at the returned q (``data`` holds its kinematics; ``ready``: the step's errors, when
    ``step`` is given, were computed at q).  The tasks' targets are those the solve's first step read."""
    if step is not None and ready:
        return step.errors
    return engine.level_errors(engine.platform, data, q, levels, refresh=False)


def _lower_levels_met(engine: HierarchySolver, data, q, levels, tol: float) -> tuple[float, ...] | None:
    """Every level's ||e_k|| at q (``data`` holds its kinematics) when each level after the first is below ``tol``
    (nothing left for a step to improve), else None.  The first level is the caller's (its own tolerances)."""
    errors = engine.level_errors(engine.platform, data, q, levels, refresh=False)
    return errors if all(e < tol for e in errors[1:]) else None


def _hovering(data, hover_tol: float) -> bool:
    """|roll|, |pitch| < hover_tol for the base orientation in ``data`` (as :func:`finish` measures them)."""
    r20, r21, r22 = data.oMi[1].rotation[2].tolist()
    return abs(math.atan2(r21, r22)) < hover_tol and abs(math.atan2(-r20, math.hypot(r21, r22))) < hover_tol


# ============================================================================ the registry
@dataclass(frozen=True)
class IKMethod:
    """A registered IK method: its ``options`` class (a frozen dataclass deriving from :class:`Tolerances`: the
    defaults, checked on construction) and ``make(platform, options) -> run``, called once per :class:`IKSolver`, with
    ``run(ctx, xi) -> IKResult`` solving from the start configuration xi (thesis coordinates) for the
    :class:`SolveContext` ``ctx`` (the parsed target, the options, the clock); a method ends with :func:`finish` (or
    :func:`failed_result`).  ``description``: one line."""

    options: type
    make: Callable[..., Callable[[SolveContext, np.ndarray], IKResult]]
    description: str = ""

    def __post_init__(self) -> None:
        if not (isinstance(self.options, type) and issubclass(self.options, Tolerances)):
            raise InputError(f"IKMethod.options must be an options class deriving from qprr.ik.solver.Tolerances, got {self.options!r}")
        if not callable(self.make):
            raise InputError(f"IKMethod.make must be a function (platform, options) -> run(ctx, xi), got {self.make!r}")


def _stateless(run: Callable[[SolveContext, np.ndarray], IKResult]) -> Callable:
    """The ``make`` of a method that keeps no state between solves: ``run`` itself."""

    def make(platform: Platform, options) -> Callable:
        return run

    return make


def _check_method(name: str, entry: object) -> None:
    if not isinstance(entry, IKMethod):
        raise InputError(f"IK method {name!r}: register a qprr.ik.solver.IKMethod(options, make, description), got {type(entry).__name__}")


IK_METHODS: Registry[IKMethod] = Registry("IK method", default=DEFAULT_METHOD, check=_check_method)
"""IK method name -> :class:`IKMethod`: ``qp``, ``clika``, ``dls`` here; the thesis plug-in adds ``igm`` (the Q-PRR's)."""
IK_METHODS.register("qp", IKMethod(QPOptions, QPMethod, "strict task-priority QP: pose, hover, CoG, posture; joint limits hard"))
IK_METHODS.register("clika", IKMethod(ClikaOptions, _stateless(solve_clika), "closed-loop inverse kinematics (4.38)-(4.41)"))
IK_METHODS.register("dls", IKMethod(DLSOptions, _stateless(solve_dls), "damped least squares on log6, joint limits by an active set"))

OPTIONS = IK_METHODS.derived(lambda entry: entry.options)
"""IK method name -> its options class (a view of :data:`IK_METHODS`)."""
METHODS = IK_METHODS.derived(lambda entry: entry.description)
"""IK method name -> its description (a view of :data:`IK_METHODS`; ``name in METHODS``, ``list(METHODS)``)."""


def solve(platform: Platform, data: pin.Data, target, method: str = DEFAULT_METHOD, xi0=None, options=None) -> IKResult:
    """Inverse kinematics: a configuration reaching ``target`` (see the module docstring).

    A new :class:`IKSolver` per call (its QPs are built each time); keep one
    :class:`IKSolver` to solve many targets fast.  Bad input raises a qprr InputError /
    UnknownNameError / LimitError; a target that cannot be reached returns a result with
    ``success = False`` and a ``reason``.
    """
    return IKSolver(platform, method, options).solve(data, target, xi0)
