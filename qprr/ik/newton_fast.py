"""The QP IK's Newton loop on the default tasks, compiled (numba, ``pip install qprr[fast]``).

The readable loop is :meth:`qprr.ik.solver.QPMethod.__call__` with its helpers ``_BaseShift`` (the base moved onto
level 1's position), ``_StepShaper`` (the step control, the freezing of lower levels, the stopping tests) and the
polished-pose stop at the top of an iteration; they stay the reference.  :func:`newton` is one pass of that loop --
from the kinematics Pinocchio left in ``data`` at q to the step to integrate -- with the step itself taken by
:func:`qprr.ik.iteration_fast.iterate` (the tasks' (J, e) and the lexicographic step).  Between two passes Python
calls Pinocchio only: :func:`qprr.ik.tasks.update_kinematics` at q and ``pin.integrate`` of the step
(:class:`NewtonLoop`); the base move onto level 1's position shifts the kinematics it read instead of asking
Pinocchio again (:func:`_shifted`: the answers then differ from the readable loop's by rounding, which the free
directions of an under-determined hierarchy amplify).  A pass it cannot take -- a level that needs ProxQP, a task's J
or e not finite -- ends the compiled loop with ``FALLBACK``: the readable loop then solves the target from its start.
``tests/test_ik_fast.py`` checks both loops give the same statuses, iteration counts and answers (q, xi and the level
errors to 1e-9, the pose errors and attitude to 1e-12) on cold starts of four platforms with the default levels; with
a custom under-determined hierarchy they agree less closely, with no bound tested (hextilt_flying_arm_5 with the
levels pose > CoM: 5.7e-8 in q and 2.7e-8 rad in roll measured, the same verdicts; docs/ik.md).

The state the readable loop keeps in Python objects lives in three arrays, ``istate`` (counters and flags, ``I_*``),
``scal`` (scalars, ``S_*``) and ``prev`` (one row per quantity of each level, ``P_*``); ``control`` holds the
options and the target (``C_*``, filled by :meth:`NewtonLoop.run`); the step control's constants are
:mod:`qprr.ik.stepping`'s, shared with the readable loop.  numba caches the machine code beside this file, with those
constants frozen in, and checks only this file's time stamp: after editing ``iteration_fast.py``,
``qprr/actuation/lexicographic_fast.py`` or ``stepping.py``, delete this module's ``.nbi`` / ``.nbc`` files in
``qprr/ik/__pycache__`` too.
"""

from __future__ import annotations

import math
from enum import IntEnum

import numba
import numpy as np
import pinocchio as pin

from ..charts import EULER_TOL
from .iteration_fast import NEEDS_NUMPY, NOT_FINITE, iterate, level_norms
from .stepping import FLAT_STEPS, FREEZE_SCALE, LEVEL1_RATE, LIMITS_SLACK, PROGRESS_RTOL, REST_FACTOR, SATISFIABLE_RATIO, STATIONARY_STEP
from .tasks import update_kinematics

_JIT = {"cache": True, "nogil": True}


class Pass(IntEnum):
    """What :func:`newton` asks of its caller: STEP (integrate ``dv`` into q, compute the kinematics, call again),
    STOP (the solve ended: ``istate``, ``scal`` and ``prev`` hold how), FALLBACK (a pass the compiled loop cannot take:
    solve with the readable loop)."""

    STEP = 0
    STOP = 1
    FALLBACK = 2


class Outcome(IntEnum):
    """How the compiled loop ended (``istate[I_STATUS]``): the readable loop's statuses of a solve that did not fail
    inside it, named as ``qprr.ik.solver.IKOutcome``'s members (the solver maps them by name)."""

    CONVERGED = 0
    STALLED = 1
    MAX_ITERATIONS = 2


STEP, STOP, FALLBACK = (int(p) for p in Pass)
CONVERGED, STALLED, MAX_ITERATIONS = (int(o) for o in Outcome)

# control: the options and the target
C_POS_TOL, C_ROT_TOL, C_HOVER_TOL, C_POLISHED, C_SETTLE, C_STEP, C_MAX_STEP, C_HOVER, C_MAX_ITER, C_SHIFT_TOL = range(10)
C_HAS_R, C_PD, C_RD, C_SHIFT_TARGET, C_AXIS, C_EULER_TOL = 10, 11, 14, 23, 26, 35
C_SIZE = 36
# istate: counters and flags
I_IT, I_SHIFT, I_STALE, I_FLAT, I_KEPT, I_NPREV, I_SETTLED, I_FINAL, I_STATUS, I_XI, I_NSTEP = range(11)
I_SIZE = 11
# scal: scalars
S_MOVED, S_E1_PREV, S_REST, S_LARGEST, S_POS, S_ROT, S_XCM, S_YCM, S_ROLL, S_PITCH, S_WITHIN = range(11)
S_SIZE = 11
# prev: per level
P_LOWER, P_RESIDUALS, P_OUT = range(3)


@numba.njit(**_JIT)
def _pose_errors(M_frame, control):
    """(||p - p_d||, ||log3(R_d^T R)||) of the frame placement M_frame (4 x 4) against the target
    (``qprr.ik.solver.pose_error_values``: the angle from sin = |skew(N)| / 2 and cos = (tr N - 1) / 2, N = R_d^T R)."""
    d0 = M_frame[0, 3] - control[C_PD]
    d1 = M_frame[1, 3] - control[C_PD + 1]
    d2 = M_frame[2, 3] - control[C_PD + 2]
    pos = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if control[C_HAS_R] == 0.0:
        return pos, 0.0
    Rd = control[C_RD : C_RD + 9].reshape(3, 3)
    N = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            N[i, j] = Rd[0, i] * M_frame[0, j] + Rd[1, i] * M_frame[1, j] + Rd[2, i] * M_frame[2, j]
    s0, s1, s2 = N[2, 1] - N[1, 2], N[0, 2] - N[2, 0], N[1, 0] - N[0, 1]
    sin = 0.5 * np.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    return pos, np.arctan2(sin, 0.5 * (N[0, 0] + N[1, 1] + N[2, 2] - 1.0))


@numba.njit(**_JIT)
def _hovering(M_base, tol):
    """|roll|, |pitch| < tol for the base placement M_base (``qprr.ik.solver._hovering``)."""
    r20, r21, r22 = M_base[2, 0], M_base[2, 1], M_base[2, 2]
    return abs(np.arctan2(r21, r22)) < tol and abs(np.arctan2(-r20, np.hypot(r21, r22))) < tol


@numba.njit(**_JIT)
def _lexicographic_progress(errors, previous, n_previous):
    """``qprr.ik.solver._lexicographic_progress`` (``n_previous`` < 0: no previous errors)."""
    if n_previous < 0:
        return True
    for i in range(min(errors.shape[0], n_previous)):
        e, e0 = errors[i], previous[i]
        if abs(e - e0) > PROGRESS_RTOL * max(e, e0):
            return e < e0
    return False


@numba.njit(**_JIT)
def _satisfiable_prefix(errors, residuals, met):
    """``qprr.ik.solver._satisfiable_prefix``: level 1, then each level the step's linear model meets."""
    kept = 1
    for k in range(1, errors.shape[0]):
        e, r = errors[k], residuals[k]
        if not (e <= met or r <= SATISFIABLE_RATIO * e):
            break
        kept += 1
    return kept


@numba.njit(**_JIT)
def _max_abs(v):
    """max |v_i| (0 for an empty v)."""
    m = 0.0
    for x in v:
        m = max(m, abs(x))
    return m


@numba.njit(**_JIT)
def _shape(step, pose_ok, control, state, met, n_levels):
    """``qprr.ik.solver._StepShaper.shape`` on the ``step`` (x, x_levels, norms of :func:`iterate`; ``state`` =
    (istate, scal, prev), :func:`newton`'s): (dv or an empty array, stop: 0 go on, 1 "converged_stationary",
    2 "converged"); ``n_levels``: how many levels the hierarchy has (``istate[I_KEPT]`` below it: the lower ones are
    frozen)."""
    x, x_levels, norms = step
    istate, scal, prev = state
    errors, residuals = norms[0], norms[2]
    K = errors.shape[0]
    tol = control[C_SETTLE] if pose_ok else control[C_STEP]
    largest = _max_abs(x)
    small = largest < tol
    if small and largest < STATIONARY_STEP:
        return np.zeros(0), 1
    lower = errors[1 : istate[I_KEPT]].copy()
    progress = _lexicographic_progress(lower, prev[P_LOWER], istate[I_NPREV])
    istate[I_FLAT] = istate[I_FLAT] + 1 if (pose_ok and not progress) else 0
    prev[P_LOWER, : lower.shape[0]] = lower
    istate[I_NPREV] = lower.shape[0]
    if istate[I_FLAT] >= FLAT_STEPS:
        return np.zeros(0), 2
    e1 = math.hypot(errors[0], scal[S_MOVED])  # level 1's error before the base was moved onto its position
    if not pose_ok and e1 > LEVEL1_RATE * scal[S_E1_PREV]:
        scal[S_REST] *= REST_FACTOR
    elif scal[S_REST] < 1.0:
        scal[S_REST] = min(1.0, scal[S_REST] / REST_FACTOR)
    scal[S_E1_PREV] = e1
    dv = x
    if scal[S_REST] <= FREEZE_SCALE:  # _StepShaper._freeze
        kept = max(K - 1, _satisfiable_prefix(errors, residuals, met))
        if kept < K:
            istate[I_KEPT], istate[I_NPREV] = kept, -1
            scal[S_REST], scal[S_E1_PREV] = 1.0, np.inf
    if istate[I_KEPT] < n_levels:
        dv = x_levels[istate[I_KEPT] - 1]
        largest = _max_abs(dv)
        small = largest < tol
    max_step = control[C_MAX_STEP]
    if largest > max_step or scal[S_REST] < 1.0:
        d1 = x_levels[0]
        rest = (dv - d1) * scal[S_REST]
        m1, m2 = _max_abs(d1), _max_abs(rest)
        dv = (d1 if m1 <= max_step else d1 * (max_step / m1)) + (rest if m2 <= max_step else rest * (max_step / m2))
        largest = _max_abs(dv)
    scal[S_LARGEST] = largest
    return dv, 1 if small else 0


@numba.njit(**_JIT)
def _stop(status, norms, at, control, state):
    """End the solve with ``status`` and the levels' errors ``norms`` at q, and measure q as
    ``qprr.ik.solver.finish`` does from ``at`` = (frame, base, q, bounds), the kinematics at q and the arm's limits:
    the pose errors, the CoG offset from the thrust axis in B (``Platform.thrust_axis``: E (R_b^T (c - p_b) - point)),
    roll and pitch, whether the arm is within its limits (``LIMITS_SLACK`` of rounding slack), and xi (thesis coordinates,
    ``istate[I_XI]`` 0 at the ZYX singularity, ``qprr.ik.solver._xi_of_q``)."""
    istate, scal, prev, _, xi, _ = state
    (_, M_frame), (M_base, com, _), q, (lower, upper) = at
    q_arm = q[7:]
    scal[S_WITHIN] = np.all(q_arm >= lower - LIMITS_SLACK) and np.all(q_arm <= upper + LIMITS_SLACK)
    istate[I_STATUS] = status
    prev[P_OUT, : norms.shape[0]] = norms
    scal[S_POS], scal[S_ROT] = _pose_errors(M_frame, control)
    c = com - M_base[0:3, 3]
    point, E = control[C_AXIS : C_AXIS + 3], control[C_AXIS + 3 : C_AXIS + 9].reshape(2, 3)
    for i in range(2):
        off = 0.0
        for j in range(3):
            c_b = M_base[0, j] * c[0] + M_base[1, j] * c[1] + M_base[2, j] * c[2]  # (R_b^T (c - p_b))_j
            off += E[i, j] * (c_b - point[j])
        scal[S_XCM + i] = off
    r20, r21, r22 = M_base[2, 0], M_base[2, 1], M_base[2, 2]
    pitch = np.arctan2(-r20, np.hypot(r21, r22))
    scal[S_ROLL], scal[S_PITCH] = np.arctan2(r21, r22), pitch
    istate[I_XI] = abs(np.cos(pitch)) >= control[C_EULER_TOL]
    xi[0:3] = q[0:3]
    xi[3], xi[4], xi[5] = scal[S_ROLL], pitch, np.arctan2(M_base[1, 0], M_base[0, 0])
    xi[6:] = q[7:]
    return STOP


@numba.njit(**_JIT)
def _all_norms(levels, frame, base, q):
    """Every level's ||e_k|| at q (``HierarchySolver.level_errors``), and whether they are finite."""
    norms = level_norms(levels, frame, base, q)
    return norms, np.isfinite(norms.sum())


@numba.njit(**_JIT)
def _active(levels, kept):
    """The leading ``kept`` levels (the lower ones frozen), packed as ``levels`` are."""
    kinds, dims, params = levels
    return kinds[:kept].copy(), dims[:kept].copy(), params[:kept].copy()


@numba.njit(**_JIT)
def _shifted(frame, base, q, control, istate):
    """``qprr.ik.solver._BaseShift.apply`` (while ``istate[I_SHIFT]``): q's base moved (in place) by the world
    translation d that puts the frame on ``control``'s shift target when it is off by more than the threshold, and
    the kinematics at the moved q without Pinocchio: a translation of the free-flyer base adds d to every placement's
    translation and to the centre of mass, and changes neither the frame's LOCAL Jacobian nor the world CoM
    Jacobian (the base twist is in B).  Returns (frame, base, |d|), copies (d = 0: unmoved); ``istate[I_STALE]`` set
    when q moved (``data`` no longer holds its kinematics)."""
    M_frame, M_base, com = frame[1].copy(), base[0].copy(), base[1].copy()
    moved = 0.0
    if istate[I_SHIFT]:
        d = control[C_SHIFT_TARGET : C_SHIFT_TARGET + 3] - M_frame[0:3, 3]
        if _max_abs(d) > control[C_SHIFT_TOL]:
            q[0:3] += d
            M_frame[0:3, 3] += d
            M_base[0:3, 3] += d
            com += d
            moved = np.sqrt(d @ d)
            istate[I_STALE] = 1
    return (frame[0], M_frame), (M_base, com, base[2]), moved


@numba.njit(**_JIT)
def newton(levels, frame, base, q, solver, control, state):
    """One pass of the readable loop from the kinematics at q (module docstring): :class:`Pass`'s code; q's base
    may be moved in place (:func:`_shifted`); on STEP ``dv_out`` holds the step and ``arm_out`` the arm's joints
    after it, q_arm + dv_arm clipped into the joint limits (what ``pin.integrate`` and the readable loop's clip give:
    an arm joint's q and v are one number).  ``solver`` = (bounds, weights, guesses) of :func:`iterate`; ``state`` =
    (istate, scal, prev, dv_out, xi, arm_out)."""
    bounds, weights, guesses = solver
    istate, scal, prev, dv_out, _, arm_out = state
    met = weights[3]
    K = levels[0].shape[0]
    istate[I_STALE] = 0  # the caller computed the kinematics at q
    if istate[I_FINAL]:  # after the last step was integrated: the answer's level errors
        norms, finite = _all_norms(levels, frame, base, q)
        return _stop(istate[I_STATUS], norms, (frame, base, q, bounds), control, state) if finite else FALLBACK
    if istate[I_IT] >= control[C_MAX_ITER]:
        norms, finite = _all_norms(levels, frame, base, q)
        return _stop(MAX_ITERATIONS, norms, (frame, base, q, bounds), control, state) if finite else FALLBACK
    frame, base, scal[S_MOVED] = _shifted(frame, base, q, control, istate)
    M_frame, M_base = frame[1], base[0]
    pos, rot = _pose_errors(M_frame, control)
    scal[S_POS], scal[S_ROT] = pos, rot
    pose_ok = pos < control[C_POS_TOL] and rot < control[C_ROT_TOL]
    if pose_ok:
        istate[I_SHIFT] = 0
    polish = control[C_POLISHED]
    polished = pos < polish * control[C_POS_TOL] and rot < polish * control[C_ROT_TOL]
    if istate[I_IT] and polished and (control[C_HOVER] == 0.0 or _hovering(M_base, polish * control[C_HOVER_TOL])):
        tol = min(control[C_POS_TOL], control[C_ROT_TOL], control[C_HOVER_TOL])
        if not istate[I_SETTLED] and np.all(prev[P_RESIDUALS, 1 : istate[I_NSTEP]] < tol):
            norms, finite = _all_norms(levels, frame, base, q)
            if not finite:
                return FALLBACK
            if np.all(norms[1:] < tol):
                return _stop(CONVERGED, norms, (frame, base, q, bounds), control, state)
        if istate[I_SETTLED]:
            norms, finite = _all_norms(levels, frame, base, q)
            return _stop(CONVERGED, norms, (frame, base, q, bounds), control, state) if finite else FALLBACK
    istate[I_IT] += 1
    active = levels if istate[I_KEPT] == K else _active(levels, istate[I_KEPT])
    status, _, _, x, x_levels, norms = iterate(active, frame, base, q, bounds, weights, guesses)
    if status == NEEDS_NUMPY or status == NOT_FINITE:
        return FALLBACK
    n = norms.shape[1]
    prev[P_RESIDUALS, :n] = norms[2]
    istate[I_NSTEP] = n
    dv, stop = _shape((x, x_levels, norms), pose_ok, control, (istate, scal, prev), met, K)
    if dv.shape[0]:
        dv_out[:] = dv
        arm_out[:] = np.clip(q[7:] + dv[6:], bounds[0], bounds[1])  # the QP's bound slack removed
        istate[I_SETTLED] = scal[S_LARGEST] < control[C_SETTLE]
        if stop:
            istate[I_STATUS] = STALLED if (stop == 1 and not pose_ok) else CONVERGED
            istate[I_FINAL] = 1
        return STEP
    status = STALLED if (stop == 1 and not pose_ok) else CONVERGED
    if istate[I_KEPT] == K:  # no step taken: the step's errors are those at q
        return _stop(status, norms[0].copy(), (frame, base, q, bounds), control, state)
    norms_all, finite = _all_norms(levels, frame, base, q)
    return _stop(status, norms_all, (frame, base, q, bounds), control, state) if finite else FALLBACK


# ============================================================================ the Python side
def _kinematics(platform, data, packed) -> tuple[tuple, tuple]:
    """``qprr.ik.iteration_fast.kinematics`` with the centre of mass always (:func:`_stop` measures the CoG offset
    of the answer whether a level reads it or not; :func:`qprr.ik.tasks.update_kinematics` computed it)."""
    J_local = pin.getFrameJacobian(platform.model, data, packed.frame, pin.LOCAL)
    Jcom = data.Jcom if packed.no_com is None else packed.no_com[1]
    return (J_local, data.oMf[packed.frame].homogeneous), (data.oMi[1].homogeneous, data.com[0], Jcom)


class NewtonLoop:
    """The compiled loop for ``levels`` (a sequence of levels of default tasks) packed as ``packed``
    (``qprr.ik.iteration_fast.CompiledLevels``) by a ``HierarchySolver``, with its ``solver`` = (joint limits (arm
    lower, upper), weights, active-set guesses), those of :func:`iterate` (the guesses shared with the solver, which
    clears them per solve), and ``settings`` = (position_tol, orientation_tol, hover_tol, polished, settle_tol,
    step_tol, max_step, max_iter), the QP IK's options."""

    def __init__(self, platform, levels, packed, solver: tuple, settings: tuple) -> None:
        self.platform, self.levels, self.packed = platform, levels, packed
        self.limits, self.weights, self.guesses = solver
        self.settings = settings
        self._control = np.zeros(C_SIZE)
        self._control[: C_MAX_ITER + 1] = settings[:7] + (0.0, settings[7])
        self._control[C_SHIFT_TOL] = settings[3] * settings[0]  # the base moves when level 1's frame is off by more
        self._control[C_AXIS : C_AXIS + 3] = platform.thrust_axis[0]
        self._control[C_AXIS + 3 : C_AXIS + 9] = platform.thrust_axis_basis.ravel()
        self._control[C_EULER_TOL] = EULER_TOL

    def run(self, data, q: np.ndarray, target: tuple, require_hover: bool, shift_target: np.ndarray | None):
        """Solve from q (not modified) for ``target`` = (p_d, R_d or None), the pose the success test measures at
        the packed frame; ``shift_target``: level 1's position the base is moved onto (None: no move).  Returns
        (q, iterations, :class:`Outcome`, the levels' errors at q, (position error, angle, x_cm, y_cm, roll, pitch,
        within the joint limits) at q, xi of q or None at the ZYX singularity), ``data`` holding the kinematics at q; or None when a pass needs
        the readable loop (:data:`FALLBACK`)."""
        platform, packed = self.platform, self.packed
        control = self._control.copy()
        p_d, R_d = target
        control[C_PD : C_PD + 3] = p_d
        if R_d is not None:
            control[C_HAS_R] = 1.0
            control[C_RD : C_RD + 9] = R_d.ravel()
        control[C_HOVER] = float(require_hover)
        K = packed.levels[0].shape[0]
        istate = np.zeros(I_SIZE, dtype=np.int64)
        istate[I_KEPT], istate[I_NPREV] = K, -1
        if shift_target is not None:
            istate[I_SHIFT] = 1
            control[C_SHIFT_TARGET : C_SHIFT_TARGET + 3] = shift_target
        scal = np.zeros(S_SIZE)
        scal[S_E1_PREV], scal[S_REST], scal[S_LARGEST] = np.inf, 1.0, np.inf
        prev = np.zeros((3, K))
        dv = np.zeros(platform.nv)
        q = q.copy()
        model = platform.model
        xi = np.zeros(platform.n_xi)
        arm = np.zeros(platform.n_arm)
        solver, state = (self.limits, self.weights, self.guesses), (istate, scal, prev, dv, xi, arm)
        while True:
            update_kinematics(platform, data, q)
            frame, base = _kinematics(platform, data, packed)
            code = newton(packed.levels, frame, base, q, solver, control, state)
            if code == STEP:
                q = pin.integrate(model, q, dv)
                q[7:] = arm  # clipped into the joint limits (newton)
            elif code == STOP:
                if istate[I_STALE]:  # the base was moved in this last pass
                    update_kinematics(platform, data, q)
                break
            elif code == FALLBACK:
                return None
        pos, rot, x_cm, y_cm = float(scal[S_POS]), float(scal[S_ROT]), float(scal[S_XCM]), float(scal[S_YCM])
        measured = (pos, rot, x_cm, y_cm, float(scal[S_ROLL]), float(scal[S_PITCH]), bool(scal[S_WITHIN]))  # as finish's
        return q, int(istate[I_IT]), Outcome(int(istate[I_STATUS])), tuple(prev[P_OUT].tolist()), measured, xi if istate[I_XI] else None
