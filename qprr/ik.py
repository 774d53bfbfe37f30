"""Inverse kinematics of the Q-PRR: one call, four methods, one result type.

    result = solve(robot, data, target, method="qp", xi0=None, options=None)

``target``: the desired end-effector placement in the world, a ``pin.SE3`` or a pair
``(p_world, R_world)``.  The problem solved is the *static* IK of an aerial manipulator:
the end effector at the target, the arm inside its joint limits and, unless an option
says otherwise, the multirotor able to hover there (roll = pitch = 0: a multirotor holds
still only with its thrust axis vertical).  Under hover the end-effector y axis stays
horizontal (R_e = Rz(psi) Ry(theta2 + theta3), Thesis (3.58), (3.61)), so a target whose
y axis is tilted out of the horizontal plane is *unreachable in hover*: every method then
returns ``success = False`` with a reason.  The CoG offset [x_cm, y_cm] (body frame) is
reported, never a failure: with the +-0.04 m slider some poses are reachable but not
balanceable.

Methods (``METHODS``):

* ``"igm"``   thesis analytic inverse geometric model, Algorithm 3 under the hover
  assumption (3.66)-(3.72), Levenberg-Marquardt (Algorithm 4) on the reduced system, r0
  from the centre-of-mass criterion (3.79)-(3.81) and the prismatic check of Algorithm 5,
  with the printed steps corrected where they are wrong (docs/thesis-errata.md).
* ``"clika"`` closed-loop inverse kinematics (4.38)-(4.41) with the right pseudo-inverse
  (4.36) or the weighted one (4.34), Euler-integrated in thesis coordinates (4.30).
* ``"dls"``   damped least squares (Levenberg-Marquardt) on the SE(3) error log6, joint
  limits by projection.
* ``"qp"``    strict task-priority QP IK (:mod:`qprr.tasks`): 1 end-effector pose,
  2 hover (thrust axis vertical), 3 CoG on the thrust axis, 4 posture; joint limits hard
  at every level; ProxQP per level.

Position error: ||p_e - p_d|| [m]; orientation error: ||log3(R_d^T R_e)|| [rad], both
from Pinocchio's forward kinematics at the returned configuration.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields

import numpy as np
import pinocchio as pin

from . import coordinates as co
from .coordinates import as_vector
from .errors import (
    InputError,
    NonFiniteError,
    ShapeError,
    SolverError,
    UnknownNameError,
)
from .model import Robot
from .params import QPRRParams
from .tasks import ComTask, HierarchySolver, HoverTask, PoseTask, PostureTask, Task, update_kinematics

METHODS = ("igm", "clika", "dls", "qp")
TWO_PI = 2.0 * math.pi
_HOVER_V = np.array([0, 1, 2, 5, 6, 7, 8])  # tangent directions that keep roll = pitch = 0
_HOVER_XI = np.array([0, 1, 2, 5, 6, 7, 8])  # x, y, z, psi, r0, theta2, theta3


# ============================================================================ options
def _check_pos(name: str, value, strict: bool = True) -> None:
    ok = isinstance(value, (int, float)) and math.isfinite(value) and (value > 0 if strict else value >= 0)
    if not ok:
        raise InputError(f"option {name} must be a finite number {'>' if strict else '>='} 0, got {value!r}")


def _check_int(name: str, value) -> None:
    if not (isinstance(value, int) and value >= 1):
        raise InputError(f"option {name} must be an integer >= 1, got {value!r}")


@dataclass(frozen=True)
class _Tolerances:
    position_tol: float = 1e-6  # [m] success threshold on ||p_e - p_d||
    orientation_tol: float = 1e-6  # [rad] success threshold on ||log3(R_d^T R_e)||
    hover_tol: float = 1e-6  # [rad] |roll|, |pitch| below it count as hover-feasible

    def _check_tolerances(self) -> None:
        for name in ("position_tol", "orientation_tol", "hover_tol"):
            _check_pos(name, getattr(self, name))


@dataclass(frozen=True)
class IGMOptions(_Tolerances):
    """Thesis analytic IGM.  ``theta2``: "lm" (thesis: theta2 is what Algorithm 4 returns
    from the initial guess) or "balance" (extension: theta2 chosen so that the CoG can be
    put on the thrust axis with r0 inside its range, closest to the guess)."""

    theta2: str = "lm"
    lm_tol: float = 1e-10  # [m] stop Algorithm 4 when ||F|| <= lm_tol
    max_iter: int = 50
    damping: float = 1e-3  # initial lambda of (3.74)

    def __post_init__(self):
        self._check_tolerances()
        if self.theta2 not in ("lm", "balance"):
            raise UnknownNameError("IGM theta2 mode", self.theta2, ("lm", "balance"))
        _check_pos("lm_tol", self.lm_tol)
        _check_pos("damping", self.damping)
        _check_int("max_iter", self.max_iter)


@dataclass(frozen=True)
class ClikaOptions(_Tolerances):
    """CLIKA (4.41): xi_dot = J^+ K e, xi <- xi + dt xi_dot.  ``gains``: diag K (thesis example
    values); ``weights``: diag W of (4.34) in xi order (None: W = I, the right pseudo-inverse
    (4.36)); ``hover``: keep roll = pitch = 0 (drop their columns of J; the thesis uses all 9)."""

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
            w = as_vector(self.weights, 9, "option weights")
            if np.any(w <= 0):
                raise InputError(f"option weights must be positive, got {w.tolist()}")
        _check_pos("dt", self.dt)
        _check_int("max_iter", self.max_iter)
        if not isinstance(self.hover, bool):
            raise InputError(f"option hover must be a bool, got {self.hover!r}")


@dataclass(frozen=True)
class DLSOptions(_Tolerances):
    """Levenberg-Marquardt on f = log6(M_d^-1 M_e): (J^T J + lambda I) dv = -J^T f, lambda
    adapted (/3 on success, x4 on failure); arm joints projected on their limits; ``hover``
    restricts dv to the directions that keep roll = pitch = 0."""

    hover: bool = True
    damping: float = 1e-3
    max_iter: int = 100

    def __post_init__(self):
        self._check_tolerances()
        _check_pos("damping", self.damping)
        _check_int("max_iter", self.max_iter)
        if not isinstance(self.hover, bool):
            raise InputError(f"option hover must be a bool, got {self.hover!r}")


@dataclass(frozen=True)
class QPOptions(_Tolerances):
    """Strict task-priority QP IK.  ``init``: "igm" (analytic IGM with balanced theta2, when
    no xi0 is given) or "guess" (hover at the target minus the arm reach).  ``posture``:
    [r0, theta2, theta3] of level 4 (default: the initial guess).  ``levels``: replace the
    default hierarchy by your own sequence of sequences of :class:`qprr.tasks.Task`.
    ``require_hover``: success needs roll = pitch = 0 (within hover_tol).  ``step_tol``:
    stop when the pose is reached and max |dv| < step_tol."""

    init: str = "igm"
    require_hover: bool = True
    posture: tuple | None = None
    levels: Sequence | None = None
    max_iter: int = 50
    step_tol: float = 1e-7
    eps_abs: float = 1e-9
    regularization: float = 1e-7
    rank_tol: float = 1e-9
    elimination: str = "nullspace"

    def __post_init__(self):
        self._check_tolerances()
        if self.init not in ("igm", "guess"):
            raise UnknownNameError("QP init", self.init, ("igm", "guess"))
        if self.elimination not in ("nullspace", "equality"):
            raise UnknownNameError("elimination", self.elimination, ("nullspace", "equality"))
        _check_int("max_iter", self.max_iter)
        for name in ("step_tol", "eps_abs", "rank_tol"):
            _check_pos(name, getattr(self, name))
        _check_pos("regularization", self.regularization, strict=False)
        if self.posture is not None:
            as_vector(self.posture, 3, "option posture")
        if self.levels is not None:
            ok = len(self.levels) > 0 and all(
                len(level) > 0 and all(isinstance(t, Task) for t in level) for level in self.levels
            )
            if not ok:
                raise InputError("option levels must be a non-empty sequence of non-empty sequences of qprr.tasks.Task")


OPTIONS = {"igm": IGMOptions, "clika": ClikaOptions, "dls": DLSOptions, "qp": QPOptions}
_DEFAULT_OPTIONS = {k: v() for k, v in OPTIONS.items()}
_IGM_BALANCE = IGMOptions(theta2="balance")


def make_options(method: str, options=None):
    """The options object of ``method`` from None, a dict of overrides or an options instance."""
    if method not in OPTIONS:
        raise UnknownNameError("IK method", method, METHODS)
    cls = OPTIONS[method]
    if options is None:
        return _DEFAULT_OPTIONS[method]
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
@dataclass(slots=True)
class IKResult:
    """Outcome of :func:`solve`.

    ``success``: pose within tolerance, arm within limits and (when the method requires
    it) hover-feasible.  ``status``: "converged", "unreachable", "not_hover_feasible",
    "limits", "max_iterations", "stalled", "diverged" or "solver_error"; ``reason`` says
    why in words when ``success`` is False (empty otherwise).  ``xi`` and ``q`` hold the
    returned (best-effort when failed) configuration.  Errors: world position [m] and
    rotation angle [rad]; ``x_cm``, ``y_cm``: system CoG in the body frame B [m];
    ``roll``, ``pitch``: base ZYX angles [rad]; ``wall_time`` [s]; ``initial_guess``: how
    the starting configuration was obtained; ``level_errors`` (method "qp"): the norm
    of each level's task error ||e_k|| at the returned configuration.
    """

    method: str
    success: bool
    status: str
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


# ============================================================================= inputs
def parse_target(target) -> tuple[np.ndarray, np.ndarray]:
    """(p_world, R_world) of a ``pin.SE3`` or a ``(p_world, R_world)`` pair, validated.

    Raises ShapeError / NonFiniteError / InputError (R not a rotation: |R^T R - I| > 1e-9
    entry-wise or det R < 0).
    """
    if isinstance(target, pin.SE3):
        p, R = target.translation, target.rotation
    elif isinstance(target, (tuple, list)) and len(target) == 2:
        p = as_vector(target[0], 3, "target position")
        R = np.array(target[1], dtype=float)
        if R.shape != (3, 3):
            raise ShapeError(f"target rotation must have shape (3, 3), got {R.shape}")
    else:
        raise InputError(f"target must be a pinocchio.SE3 or a (p_world, R_world) pair, got {type(target).__name__}")
    (a, b, c), (d, e, f), (g, h, i) = R.tolist()
    x, y, z = p.tolist()
    if not all(map(math.isfinite, (a, b, c, d, e, f, g, h, i, x, y, z))):
        raise NonFiniteError(f"target must be finite, got p = {[x, y, z]}, R = {R.tolist()}")
    dev = max(abs(a * a + d * d + g * g - 1.0), abs(b * b + e * e + h * h - 1.0), abs(c * c + f * f + i * i - 1.0),
              abs(a * b + d * e + g * h), abs(a * c + d * f + g * i), abs(b * c + e * f + h * i))
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    if dev > 1e-9 or det < 0.0:
        raise InputError(
            f"target rotation must be a rotation matrix (R^T R = I within 1e-9, det = +1); "
            f"max |R^T R - I| = {dev:.3g}, det = {det:.3g}"
        )
    return p, R


def hover_yaw(R_world) -> float:
    """Yaw psi of the hover configuration whose end effector has orientation R (y_e = Rz(psi) e_y)."""
    return math.atan2(-R_world[0, 1], R_world[1, 1])


def default_guess(robot: Robot, p_world, R_world) -> np.ndarray:
    """Initial guess xi0: hovering (roll = pitch = 0) below the target by the arm reach
    d0 + d1 + d2 + d3, yaw of the target's y axis, arm at zero (straight up)."""
    p = robot.params
    reach = p.d0 + p.d1 + p.d2 + p.d3
    return np.array([p_world[0], p_world[1], p_world[2] - reach, 0.0, 0.0, hover_yaw(R_world), 0.0, 0.0, 0.0])


def hover_tilt(R_world) -> float:
    """Angle [rad] by which the end-effector y axis leaves the horizontal plane (0 iff reachable in hover)."""
    return math.asin(min(1.0, abs(float(R_world[2, 1]))))


# ================================================================ thesis IGM helpers
@dataclass(frozen=True)
class ArmConstants:
    """Scalars of the arm used by the analytic IGM, from the parameters (any variant).

    m_G x_cm = M_s r0 + k0 + a_s s2 + a_c c2 + b_s s23 + b_c c23 with M_s the mass carried
    by the slider; for homogeneous links (Hypothesis 1) a_s = (m2/2 + m3) d2, b_s = m3 d3 / 2,
    k0 = a_c = b_c = 0: Thesis (3.78), (3.80).
    """

    d01: float
    d2: float
    d3: float
    lower: tuple
    upper: tuple
    m_G: float
    M_s: float
    k0: float
    a_s: float
    a_c: float
    b_s: float
    b_c: float
    y0: float


_ARM_CACHE: dict = {}


def arm_constants(params: QPRRParams) -> ArmConstants:
    """:class:`ArmConstants` of ``params`` (cached by identity: hashing the parameters costs more)."""
    hit = _ARM_CACHE.get(id(params))
    if hit is not None and hit[0] is params:
        return hit[1]
    if len(_ARM_CACHE) > 32:
        _ARM_CACHE.clear()
    K = _arm_constants(params)
    _ARM_CACHE[id(params)] = (params, K)
    return K


def _arm_constants(params: QPRRParams) -> ArmConstants:
    (m1, c1), (m2, c2), (m3, c3) = ((link.mass, link.com) for link in params.links)
    rail_m, rail_c = (params.rail.mass, params.rail.com) if params.rail is not None else (0.0, (0.0, 0.0, 0.0))
    return ArmConstants(
        d01=params.d0 + params.d1,
        d2=params.d2,
        d3=params.d3,
        lower=tuple(float(v) for v in params.lower_limits),
        upper=tuple(float(v) for v in params.upper_limits),
        m_G=params.total_mass,
        M_s=m1 + m2 + m3,
        k0=m1 * c1[0] + rail_m * rail_c[0],
        a_s=m2 * c2[2] + m3 * params.d2,
        a_c=m2 * c2[0],
        b_s=m3 * c3[2],
        b_c=m3 * c3[0],
        y0=m1 * c1[1] + m2 * c2[1] + m3 * c3[1] + rail_m * rail_c[1],
    )


def hover_angles_from_zyz(phi_e: float, theta_e: float, psi_e: float) -> tuple[float, float]:
    """(psi, theta2 + theta3) of a hover configuration from the ZYZ angles of (3.64), corrected (3.69)-(3.70).

    Under hover R_e = Rz(psi) Ry(t23), so (3.64) gives phi_e = psi, theta_e = t23, psi_e = 0
    when sin t23 > 0 and phi_e = psi - pi, theta_e = -t23, psi_e = pi when sin t23 < 0.  The
    two cases are *paired* and told apart by psi_e: (psi, t23) = (phi_e, theta_e) or
    (phi_e + pi, -theta_e).  (The printed (3.70) alternative t23 = theta_e - pi is wrong.)
    Undefined at the ZYZ singularity sin theta_e = 0.
    """
    if math.cos(psi_e) >= 0.0:
        return phi_e, theta_e
    return math.remainder(phi_e + math.pi, TWO_PI), -theta_e


def prismatic_check_printed(x_b: float, r0: float, r0_max: float) -> float:
    """Algorithm 5 as printed: if |r0| > r0*, |x_b| <- |x_b| + (|r0| - r0*) keeping the sign of x_b."""
    if -r0_max <= r0 <= r0_max:
        return x_b
    return math.copysign(abs(x_b) + (abs(r0) - abs(r0_max)), x_b)


def prismatic_check(x_b_prime: float, y_b_prime: float, psi: float, r0: float, r0_min: float, r0_max: float) -> tuple[float, float, float]:
    """Algorithm 5 corrected: saturate r0, then (x_b, y_b) from (3.71) with the saturated r0.

    Returns (x_b, y_b, r0).  The end effector does not move: x_b' = x_b + c_psi r0 and
    y_b' = y_b + s_psi r0 are what (3.72) fixed.
    """
    r0 = min(max(r0, r0_min), r0_max)
    return x_b_prime - math.cos(psi) * r0, y_b_prime - math.sin(psi) * r0, r0


def _balanced_theta2(K: ArmConstants, s23: float, c23: float, lo2: float, hi2: float, guess: float) -> float:
    """theta2 in [lo2, hi2] for which some r0 in its range puts the CoG on z_B (x_cm = 0),
    closest to ``guess``; if none, the theta2 minimising |x_cm| after r0 saturation.

    x_cm m_G = M_s r0 + kk + rho sin(theta2 + delta), kk = k0 + b_s s23 + b_c c23.
    """
    rho = math.hypot(K.a_s, K.a_c)
    if rho < 1e-15:  # x_cm does not depend on theta2
        return min(max(guess, lo2), hi2)
    delta = math.atan2(K.a_c, K.a_s)
    kk = K.k0 + K.b_s * s23 + K.b_c * c23
    smin = (-K.M_s * K.upper[0] - kk) / rho
    smax = (-K.M_s * K.lower[0] - kk) / rho

    def violation(t2: float) -> float:
        s = math.sin(t2 + delta)
        return max(smin - s, s - smax, 0.0)

    g0 = min(max(guess, lo2), hi2)
    if violation(g0) == 0.0:
        return g0
    cands = [g0, lo2, hi2]
    for base in (math.pi / 2, -math.pi / 2) + tuple(
        v for s in (smin, smax) if -1.0 <= s <= 1.0 for v in (math.asin(s), math.pi - math.asin(s))
    ):
        for k in (-2, -1, 0, 1, 2):
            t2 = base + k * TWO_PI - delta
            if lo2 <= t2 <= hi2:
                cands.append(t2)
    return min(cands, key=lambda t2: (round(violation(t2), 12), abs(t2 - guess)))


def _igm_core(K: ArmConstants, p, R, guess, opts: IGMOptions):
    """Algorithm 3 (corrected).  Returns (xi list, lm iterations, status, reason)."""
    px, py, pz = p.tolist()
    (r00, r01, r02), (r10, r11, r12), _ = R.tolist()
    # (3.68)-(3.70), corrected and singularity-free: under hover y_e = Rz(psi) e_y and
    # Rz(psi)^T R_e = Ry(theta2 + theta3).
    psi = math.atan2(-r01, r11)
    cps, sps = math.cos(psi), math.sin(psi)
    t = math.atan2(cps * r02 + sps * r12, cps * r00 + sps * r10)
    lo0, lo2, lo3 = K.lower
    hi0, hi2, hi3 = K.upper
    g_x, g_y, g_z, g_r0, g2, g3 = guess[0], guess[1], guess[2], guess[6], guess[7], guess[8]
    t23 = None
    for cand in (t, t - TWO_PI, t + TWO_PI):  # t23 = t (mod 2 pi) within the joint ranges
        if lo2 + lo3 - 1e-12 <= cand <= hi2 + hi3 + 1e-12 and (t23 is None or abs(cand - g2 - g3) < abs(t23 - g2 - g3)):
            t23 = cand
    if t23 is None:
        reason = (
            f"the target orientation needs theta2 + theta3 = {t:.6g} rad (mod 2 pi), outside "
            f"[{lo2 + lo3:.6g}, {hi2 + hi3:.6g}] allowed by the joint limits"
        )
        return None, 0, "limits", reason
    lo2 = max(lo2, t23 - hi3)
    hi2 = min(hi2, t23 - lo3)
    s23, c23 = math.sin(t23), math.cos(t23)
    d01, d2, d3 = K.d01, K.d2, K.d3
    if opts.theta2 == "balance":
        th2 = _balanced_theta2(K, s23, c23, lo2, hi2, g2)
        h = d2 * math.sin(th2) + d3 * s23
        xp, yp, zb = px - cps * h, py - sps * h, pz - d01 - d2 * math.cos(th2) - d3 * c23
    else:  # thesis: theta2 from the guess (kept inside the range where theta3 is feasible)
        th2 = min(max(g2, lo2), hi2)
        xp, yp, zb = g_x + cps * g_r0, g_y + sps * g_r0, g_z  # (3.71) at the guess

    # Algorithm 4 on the corrected reduced system (3.72): unknowns (x_b', y_b', z_b, theta2),
    # F = [x_b' + c_psi h - x_e, y_b' + s_psi h - y_e, z_b + d0 + d1 + d2 c2 + d3 c23 - z_e],
    # h = d2 s2 + d3 s23, J_F = [I3 | a] with a = dF/dtheta2 = [c_psi d2 c2, s_psi d2 c2, -d2 s2].
    kx, ky, kz = d3 * s23 * cps - px, d3 * s23 * sps - py, d01 + d3 * c23 - pz
    s2, c2 = math.sin(th2), math.cos(th2)
    f0, f1, f2 = xp + cps * d2 * s2 + kx, yp + sps * d2 * s2 + ky, zb + d2 * c2 + kz
    cost = f0 * f0 + f1 * f1 + f2 * f2
    lam = opts.damping
    it = 0
    tol = max(opts.lm_tol, 1e-14 * (1.0 + abs(px) + abs(py) + abs(pz)))  # not below rounding of p
    tol2 = tol * tol
    while cost > tol2:
        if it >= opts.max_iter:
            return None, it, "max_iterations", f"Algorithm 4 did not converge in {it} iterations (|F| = {math.sqrt(cost):.3g} m)"
        it += 1
        a0, a1, a2 = cps * d2 * c2, sps * d2 * c2, -d2 * s2
        aa = a0 * a0 + a1 * a1 + a2 * a2
        while True:  # (3.74) through (J J^T + lam I)^-1 = ((1 + lam) I + a a^T)^-1 (Sherman-Morrison)
            af = (a0 * f0 + a1 * f1 + a2 * f2) / (1.0 + lam + aa)
            w0, w1, w2 = (f0 - a0 * af) / (1.0 + lam), (f1 - a1 * af) / (1.0 + lam), (f2 - a2 * af) / (1.0 + lam)
            nxp, nyp, nzb, nth2 = xp - w0, yp - w1, zb - w2, th2 - (a0 * w0 + a1 * w1 + a2 * w2)
            ns2, nc2 = math.sin(nth2), math.cos(nth2)
            g0, g1, g2_ = nxp + cps * d2 * ns2 + kx, nyp + sps * d2 * ns2 + ky, nzb + d2 * nc2 + kz
            new = g0 * g0 + g1 * g1 + g2_ * g2_
            if new < cost:
                xp, yp, zb, th2, s2, c2 = nxp, nyp, nzb, nth2, ns2, nc2
                f0, f1, f2, cost = g0, g1, g2_, new
                lam = max(lam / 3.0, 1e-15)
                break
            lam *= 4.0
            if lam > 1e12:
                return None, it, "stalled", f"Algorithm 4 stalled at |F| = {math.sqrt(cost):.3g} m"
    if not lo2 <= th2 <= hi2:  # Algorithm 4 left the feasible range: project, re-solve (3.72) exactly
        th2 = min(max(th2, lo2), hi2)
        h = d2 * math.sin(th2) + d3 * s23
        xp, yp, zb = px - cps * h, py - sps * h, pz - d01 - d2 * math.cos(th2) - d3 * c23
    # (3.79)-(3.81): r0 minimising |x_cm|, then Algorithm 5 (corrected) and (3.71)
    gx = K.k0 + K.a_s * math.sin(th2) + K.a_c * math.cos(th2) + K.b_s * s23 + K.b_c * c23
    xb, yb, r0 = prismatic_check(xp, yp, psi, -gx / K.M_s, lo0, hi0)
    return [xb, yb, zb, 0.0, 0.0, psi, r0, th2, t23 - th2], it, "converged", ""


# ===================================================================== shared helpers
def _q_of_hover(xi) -> np.ndarray:
    half = 0.5 * xi[5]
    return np.array([xi[0], xi[1], xi[2], 0.0, 0.0, math.sin(half), math.cos(half), xi[6], xi[7], xi[8]])


def _xi_of_q(q: np.ndarray, R: np.ndarray) -> np.ndarray | None:
    """xi of q whose base rotation is R (None at the ZYX singularity |cos theta| < EULER_TOL)."""
    (r00, _, _), (r10, _, _), (r20, r21, r22) = R.tolist()
    pitch = math.atan2(-r20, math.hypot(r21, r22))
    if abs(math.cos(pitch)) < co.EULER_TOL:
        return None
    x, y, z, _, _, _, _, r0, t2, t3 = q.tolist()
    return np.array([x, y, z, math.atan2(r21, r22), pitch, math.atan2(r10, r00), r0, t2, t3])


def pose_errors(M: pin.SE3, p_d: np.ndarray, R_d: np.ndarray) -> tuple[float, float]:
    """(||p - p_d|| [m], ||log3(R_d^T R)|| [rad]) of a placement M against the target.

    The angle comes from sin = |skew(N)| / 2 and cos = (tr N - 1) / 2 with N = R_d^T R,
    accurate near 0 and pi (scalar code: cheaper than numpy on 3x3 matrices).
    """
    (a, b, c), (d, e, f), (g, h, i) = M.rotation.tolist()
    (A, B, C), (D, E, F), (G, H, I) = R_d.tolist()
    x, y, z = M.translation.tolist()
    px, py, pz = p_d.tolist()
    n21_12 = (C * b + F * e + I * h) - (B * c + E * f + H * i)
    n02_20 = (A * c + D * f + G * i) - (C * a + F * d + I * g)
    n10_01 = (B * a + E * d + H * g) - (A * b + D * e + G * h)
    trace = A * a + D * d + G * g + B * b + E * e + H * h + C * c + F * f + I * i
    sin = 0.5 * math.sqrt(n21_12 * n21_12 + n02_20 * n02_20 + n10_01 * n10_01)
    return math.sqrt((x - px) ** 2 + (y - py) ** 2 + (z - pz) ** 2), math.atan2(sin, 0.5 * (trace - 1.0))


def _prepare_xi0(robot: Robot, xi0, hover: bool) -> np.ndarray:
    xi0 = as_vector(xi0, 9, "xi0")
    robot.check_arm_limits(xi0[6:9], "xi0[6:9]")
    if hover and (xi0[3] != 0.0 or xi0[4] != 0.0):
        raise InputError(f"xi0 roll and pitch must be 0 for a hover method (got phi = {xi0[3]!r}, theta = {xi0[4]!r}); set hover=False or level xi0")
    return xi0


def _finish(robot, data, method, q, xi, p_d, R_d, opts, *, status, reason, iterations, t0, init,
            require_hover, level_errors=(), kinematics_ready=False):
    """Evaluate q with Pinocchio (FK, CoM) and build the result; decide success."""
    model = robot.model
    if kinematics_ready:  # data already holds FK, frames and CoM at q
        c = data.com[0]
        M = data.oMf[robot.ee_frame]
    else:
        c = pin.centerOfMass(model, data, q, False)
        M = pin.updateFramePlacement(model, data, robot.ee_frame)
    pos_err, rot_err = pose_errors(M, p_d, R_d)
    base = data.oMi[1]
    Rb = base.rotation
    c_b = base.actInv(c).tolist()
    r20, r21, r22 = Rb[2].tolist()
    roll = math.atan2(r21, r22)
    pitch = math.atan2(-r20, math.hypot(r21, r22))
    hover_ok = abs(roll) < opts.hover_tol and abs(pitch) < opts.hover_tol
    K = arm_constants(robot.params)
    r0, t2, t3 = q_arm = q[7:10].tolist()
    within = (K.lower[0] - 1e-12 <= r0 <= K.upper[0] + 1e-12 and K.lower[1] - 1e-12 <= t2 <= K.upper[1] + 1e-12
              and K.lower[2] - 1e-12 <= t3 <= K.upper[2] + 1e-12)
    pose_ok = pos_err < opts.position_tol and rot_err < opts.orientation_tol
    success = pose_ok and within and (hover_ok or not require_hover) and not reason
    if not success and not reason:
        if not within:
            status = "limits"
            reason = f"joints out of limits: q_arm = {q_arm} not in [{list(K.lower)}, {list(K.upper)}]"
        elif not pose_ok:
            status = status if status != "converged" else "stalled"
            reason = f"pose not reached after {iterations} iterations: position error {pos_err:.3g} m, orientation error {rot_err:.3g} rad"
        else:
            status = "not_hover_feasible"
            tilt = hover_tilt(R_d)
            if tilt > opts.orientation_tol:
                reason = (
                    f"the pose is reached only with roll = {roll:.3g} rad, pitch = {pitch:.3g} rad: not reachable in "
                    f"hover (the target's y axis is tilted {tilt:.3g} rad out of the horizontal plane)"
                )
            else:
                reason = (
                    f"the pose is reached with roll = {roll:.3g} rad, pitch = {pitch:.3g} rad: the target is reachable "
                    "in hover but the iteration stopped at a tilted configuration (joint limit or local minimum "
                    "from this start); try another xi0 or init='igm'"
                )
    if not success and status != "not_hover_feasible" and require_hover and "hover" not in reason:
        tilt = hover_tilt(R_d)
        if tilt > opts.orientation_tol:
            reason += f"; the target is unreachable in hover (its y axis is tilted {tilt:.3g} rad out of the horizontal plane)"
    if xi is None:
        xi = _xi_of_q(q, Rb)
    return IKResult(
        method=method, success=bool(success), status=status if not success else "converged", reason=reason,
        xi=xi, q=q, iterations=int(iterations), position_error=pos_err, orientation_error=rot_err,
        x_cm=float(c_b[0]), y_cm=float(c_b[1]), roll=roll, pitch=pitch, hover_feasible=bool(hover_ok),
        within_limits=within, wall_time=time.perf_counter() - t0, initial_guess=init, level_errors=level_errors,
    )


# ============================================================================ methods
def _guess_tuple(robot: Robot, p_d, R_d) -> tuple:
    """:func:`default_guess` as a tuple (no array on the IGM's hot path)."""
    p = robot.params
    x, y, z = p_d.tolist()
    return (x, y, z - (p.d0 + p.d1 + p.d2 + p.d3), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def _solve_igm(robot, data, p_d, R_d, xi0, opts: IGMOptions, t0):
    if xi0 is not None:
        guess, init = xi0.tolist(), "xi0 (given)"
    else:  # (the guess's yaw is not used: psi comes from the target)
        guess, init = _guess_tuple(robot, p_d, R_d), "hover below the target, arm straight"
    xi_l, it, status, reason = _igm_core(arm_constants(robot.params), p_d, R_d, guess, opts)
    if xi_l is None:
        return _failed(robot, "igm", status, reason, it, t0, init, p_d, R_d)
    tilt = hover_tilt(R_d)
    if tilt > opts.orientation_tol:
        status = "unreachable"
        reason = (
            f"the target orientation is not reachable in hover: its y axis is tilted {tilt:.3g} rad out of the "
            "horizontal plane, which needs a base roll/pitch (Algorithm 3 assumes phi = theta = 0)"
        )
    xi = np.array(xi_l)
    return _finish(robot, data, "igm", _q_of_hover(xi_l), xi, p_d, R_d, opts, status=status, reason=reason,
                   iterations=it, t0=t0, init=init, require_hover=True)


def _failed(robot, method, status, reason, it, t0, init, p_d, R_d):
    nan = float("nan")
    return IKResult(method, False, status, reason, None, None, it, nan, nan, nan, nan, nan, nan, False, False,
                    time.perf_counter() - t0, init)


def _solve_clika(robot, data, p_d, R_d, xi0, opts: ClikaOptions, t0):
    if xi0 is None:
        xi, init = default_guess(robot, p_d, R_d), "hover below the target, arm straight"
    else:
        xi, init = _prepare_xi0(robot, xi0, opts.hover).copy(), "xi0 (given)"
    model, fid = robot.model, robot.ee_frame
    cols = _HOVER_XI if opts.hover else np.arange(9)
    K = np.asarray(opts.gains, dtype=float)
    w_isqrt = 1.0 / np.sqrt((np.ones(9) if opts.weights is None else np.asarray(opts.weights, dtype=float))[cols])
    e = np.empty(6)
    status, reason = "max_iterations", ""
    it, best, best_it = 0, math.inf, 0
    while True:
        q = co.xi_to_q(xi)
        Jw = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        pin.updateFramePlacement(model, data, fid)
        M = data.oMf[fid]
        e[0:3] = p_d - M.translation  # (4.38) position part
        e[3:6] = pin.log3(R_d @ M.rotation.T)  # orientation error on SO(3), world axes
        if np.linalg.norm(e[0:3]) < opts.position_tol and np.linalg.norm(e[3:6]) < opts.orientation_tol:
            status = "converged"
            break
        if not np.isfinite(e).all() or np.abs(xi).max() > 1e6:
            status, reason = "diverged", f"CLIKA diverged after {it} iterations"
            break
        if it >= opts.max_iter:
            break
        err = float(e @ e)
        if err < best * (1.0 - 1e-9):
            best, best_it = err, it
        elif it - best_it >= 100:  # no progress in 100 steps: the target is out of reach
            status, reason = "stalled", f"CLIKA stalled after {it} iterations (error stopped decreasing)"
            break
        it += 1
        J = (Jw @ co.rate_map(xi))[:, cols]  # (4.13): [p_e_dot; omega_e] = J xi_dot
        # (4.41) with the weighted pseudo-inverse W^-1/2 (J W^-1/2)^+, equal to (4.34) (and to
        # (4.36) for W = I) when J has full row rank; under hover J is 6x7 of rank 5
        # (the end-effector roll about x_e is not controllable), where (4.34) is singular.
        xi[cols] += opts.dt * (w_isqrt * (np.linalg.pinv(J * w_isqrt, rcond=1e-10) @ (K * e)))  # (4.30)
    xi[3:6] = np.remainder(xi[3:6] + math.pi, TWO_PI) - math.pi
    q = co.xi_to_q(xi)
    if status == "max_iterations":
        reason = f"CLIKA did not converge in {opts.max_iter} iterations"
    return _finish(robot, data, "clika", q, None, p_d, R_d, opts, status=status, reason=reason, iterations=it,
                   t0=t0, init=init, require_hover=opts.hover)


def _solve_dls(robot, data, p_d, R_d, xi0, opts: DLSOptions, t0):
    if xi0 is None:
        xi, init = default_guess(robot, p_d, R_d), "hover below the target, arm straight"
    else:
        xi, init = _prepare_xi0(robot, xi0, opts.hover), "xi0 (given)"
    model, fid = robot.model, robot.ee_frame
    M_d_inv = pin.SE3(R_d, p_d).inverse()
    cols = _HOVER_V if opts.hover else np.arange(robot.nv)
    lo, hi = robot.params.lower_limits, robot.params.upper_limits
    q = co.xi_to_q(xi)
    dv = np.zeros(robot.nv)

    def evaluate(q):
        pin.framesForwardKinematics(model, data, q)
        Me = data.oMf[fid]
        Merr = M_d_inv * Me
        f = pin.log6(Merr).vector
        return Me, Merr, f, float(f @ f)

    Me, Merr, f, cost = evaluate(q)
    lam = opts.damping
    status, it, slow = "max_iterations", 0, 0  # _finish words the reason from the measured errors
    while True:
        pos_err, rot_err = pose_errors(Me, p_d, R_d)
        if pos_err < opts.position_tol and rot_err < opts.orientation_tol:
            status = "converged"
            break
        if it >= opts.max_iter:
            break
        it += 1
        J_all = pin.Jlog6(Merr) @ pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
        # (J^T J + lam I)^-1 J^T f through the SVD J = U S V^T: V S/(S^2 + lam) U^T f.  Under
        # hover J is 6x7 of rank 5; the SVD keeps rounding noise out of its kernel.  An arm
        # joint on a limit whose step points outwards is frozen (active set), otherwise the
        # projection would halve the remaining error per iteration instead of converging.
        free = cols
        for _ in range(4):
            U, sv, Vt = np.linalg.svd(J_all[:, free], full_matrices=False)
            Utf = U.T @ f
            step = -(Vt.T @ (sv / (sv * sv + lam) * Utf))
            block = [
                j for j, d in zip(free, step)
                if j >= 6 and ((d < 0 and q[j + 1] <= lo[j - 6] + 1e-12) or (d > 0 and q[j + 1] >= hi[j - 6] - 1e-12))
            ]
            if not block:
                break
            free = np.array([j for j in free if j not in block])
        dv[:] = 0.0
        while True:
            dv[free] = -(Vt.T @ (sv / (sv * sv + lam) * Utf))
            q_new = pin.integrate(model, q, dv)
            np.clip(q_new[7:10], lo, hi, out=q_new[7:10])  # joint limits by projection
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
            status = "stalled"  # _finish words the reason from the measured pose errors
            break
    # the failure (if any) is worded by _finish from the measured errors
    return _finish(robot, data, "dls", q, None, p_d, R_d, opts, status=status, reason="", iterations=it,
                   t0=t0, init=init, require_hover=opts.hover)


_ENGINES: dict = {}


def _engine(robot: Robot, opts: QPOptions) -> HierarchySolver:
    key = (id(robot), opts.eps_abs, opts.regularization, opts.rank_tol, opts.elimination)
    entry = _ENGINES.get(key)
    if entry is None or entry[0] is not robot:
        if len(_ENGINES) > 16:
            _ENGINES.clear()
        entry = (robot, HierarchySolver(robot, eps_abs=opts.eps_abs, regularization=opts.regularization,
                                        rank_tol=opts.rank_tol, elimination=opts.elimination))
        _ENGINES[key] = entry
    return entry[1]


_HOVER_TASK = HoverTask()
_COM_TASK = ComTask()


def default_levels(robot: Robot, target: pin.SE3, q_arm_posture) -> list[list[Task]]:
    """The hierarchy of method "qp": pose > hover > CoG on the thrust axis > posture.

    A list you may edit (insert levels, add tasks to a level) and pass back through the
    ``levels`` option.
    """
    return [[PoseTask(robot, target)], [_HOVER_TASK], [_COM_TASK], [PostureTask(robot, q_arm_posture)]]


def _solve_qp(robot, data, p_d, R_d, xi0, opts: QPOptions, t0):
    model = robot.model
    if xi0 is not None:
        q = co.xi_to_q(_prepare_xi0(robot, xi0, hover=False))
        init = "xi0 (given)"
    elif opts.init == "igm":
        xi_l, _, _, _ = _igm_core(arm_constants(robot.params), p_d, R_d, _guess_tuple(robot, p_d, R_d), _IGM_BALANCE)
        if xi_l is not None:
            q, init = _q_of_hover(xi_l), "analytic IGM (balanced theta2)"
        else:
            q, init = _q_of_hover(default_guess(robot, p_d, R_d)), "hover below the target, arm straight (IGM failed)"
    else:
        q, init = _q_of_hover(default_guess(robot, p_d, R_d)), "hover below the target, arm straight"
    posture = q[7:10].copy() if opts.posture is None else opts.posture
    M_d = pin.SE3(R_d, p_d)
    levels = default_levels(robot, M_d, posture) if opts.levels is None else opts.levels
    engine = _engine(robot, opts)
    engine.reset()
    lo, hi = engine.lower, engine.upper
    fid = robot.ee_frame
    status, it, step, ready = "max_iterations", 0, None, False
    try:
        while it < opts.max_iter:
            update_kinematics(robot, data, q)
            pos_err, rot_err = pose_errors(data.oMf[fid], p_d, R_d)
            pose_ok = pos_err < opts.position_tol and rot_err < opts.orientation_tol
            it += 1
            step = engine.solve(robot, data, q, levels)
            small = float(np.abs(step.dv).max()) < opts.step_tol
            if small and float(np.abs(step.dv).max()) < 1e-15:
                status, ready = ("converged" if pose_ok else "stalled"), True
                break
            q = pin.integrate(model, q, step.dv)
            np.clip(q[7:10], lo, hi, out=q[7:10])  # ProxQP meets the bounds to eps_abs; remove that slack
            if small:  # stationary: every level settled; the last (tiny) Newton step is kept
                status = "converged" if pose_ok else "stalled"
                break
    except SolverError as exc:
        return _finish(robot, data, "qp", q, None, p_d, R_d, opts, status="solver_error", reason=str(exc),
                       iterations=it, t0=t0, init=init, require_hover=opts.require_hover)
    return _finish(robot, data, "qp", q, None, p_d, R_d, opts, status=status, reason="", iterations=it, t0=t0,
                   init=init, require_hover=opts.require_hover, kinematics_ready=ready,
                   level_errors=_level_errors(robot, data, q, levels, ready, step))


def _level_errors(robot, data, q, levels, ready, step) -> tuple[float, ...]:
    """||e_k|| of every level at the returned q."""
    if step is not None and ready:
        return step.errors
    update_kinematics(robot, data, q)
    out = []
    for level in levels:
        out.append(math.sqrt(sum(float(e @ e) for e in (t.linearize(robot, data, q)[1] for t in level))))
    return tuple(out)


_SOLVERS = {"igm": _solve_igm, "clika": _solve_clika, "dls": _solve_dls, "qp": _solve_qp}


def solve(robot: Robot, data: pin.Data, target, method: str = "qp", xi0=None, options=None) -> IKResult:
    """Inverse kinematics of the Q-PRR: configuration reaching ``target`` (see the module docstring).

    ``method``: one of ``METHODS``; ``xi0``: initial guess in thesis coordinates (default:
    :func:`default_guess`, or the analytic IGM for "qp"); ``options``: dict of overrides
    or the method's options dataclass (``OPTIONS[method]``).  Bad input raises a qprr
    InputError / UnknownNameError / LimitError; a target that cannot be reached returns a
    result with ``success = False`` and a ``reason``.
    """
    t0 = time.perf_counter()
    opts = make_options(method, options)
    p_d, R_d = parse_target(target)
    if xi0 is not None:
        xi0 = as_vector(xi0, 9, "xi0")
        robot.check_arm_limits(xi0[6:9], "xi0[6:9]")
    return _SOLVERS[method](robot, data, p_d, R_d, xi0, opts, t0)
