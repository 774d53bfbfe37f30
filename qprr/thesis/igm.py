"""The thesis's analytic inverse geometric model (Algorithms 3-5) and the Q-PRR's IK front end.

* Algorithm 3 under the hover assumption (3.66)-(3.72), Levenberg-Marquardt (Algorithm 4) on the
  reduced system, r0 from the centre-of-mass criterion (3.79)-(3.81) and the prismatic check of
  Algorithm 5, with the printed steps corrected where they are wrong (docs/thesis-errata.md);
* :func:`solve_qprr`: the generic IK of :mod:`qprr.ik` with the thesis's defaults for the Q-PRR - the
  method ``"igm"`` added, the hover guess "below the target by the arm reach, yaw of the target's
  y axis", the QP started from the analytic IGM (balanced theta2), and the reason a target is
  unreachable in hover (its y axis must be horizontal: R_e = Rz(psi) Ry(theta2 + theta3),
  Thesis (3.58), (3.61)).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..charts import check_rotation
from ..errors import InputError, UnknownNameError
from ..ik import IKOutcome
from ..ik.solver import (
    OPTIONS,
    Ending,
    IKMethod,
    IKResult,
    IKSolver,
    SolveContext,
    Tolerances,
    check_count,
    check_positive,
    check_resolvable,
    failed_result,
    finish,
    hover_q,
    make_options,
    parse_target,
    prepare_xi0,
)
from ..model import Platform, check_data
from ..validation import as_vector, checked_module
from .params import QPRRParams
from .robot import params_of

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class IGMOptions(Tolerances):
    """Thesis analytic IGM.  ``theta2``: "lm" (thesis: theta2 is what Algorithm 4 returns
    from the initial guess) or "balance" (extension: theta2 chosen so that the CoG can be
    put on the thrust axis with r0 inside its range, closest to the guess).  ``require_hover``: always (Algorithm 3
    returns hover configurations only)."""

    theta2: str = "lm"
    lm_tol: float = 1e-10  # [m] stop Algorithm 4 when ||F|| <= lm_tol
    max_iter: int = 50
    damping: float = 1e-3  # initial lambda of (3.74)
    require_hover: bool = True

    def __post_init__(self):
        self._check_tolerances()
        if self.theta2 not in ("lm", "balance"):
            raise UnknownNameError("IGM theta2 mode", self.theta2, ("lm", "balance"))
        check_positive("lm_tol", self.lm_tol)
        check_positive("damping", self.damping)
        check_count("max_iter", self.max_iter)
        if self.require_hover is not True:
            raise InputError(f"option require_hover of the IGM is always True (Algorithm 3 returns hover configurations), got {self.require_hover!r}")


def hover_yaw(R_world) -> float:
    """Yaw psi of the hover configuration whose end effector has orientation R (y_e = Rz(psi) e_y)."""
    return _yaw_of(check_rotation(R_world, "R_world", 1e-6))


def _yaw_of(R_world: np.ndarray) -> float:
    """:func:`hover_yaw` of a rotation already checked."""
    return math.atan2(-R_world[0, 1], R_world[1, 1])


def hover_guess(params: QPRRParams, p_world, R_world) -> np.ndarray:
    """Initial guess xi0: hovering (roll = pitch = 0) below the target by the arm reach
    d0 + d1 + d2 + d3, yaw of the target's y axis, arm at zero (straight up)."""
    return _hover_guess(params, as_vector(p_world, 3, "p_world"), check_rotation(R_world, "R_world", 1e-6))


def _hover_guess(p: QPRRParams, p_world: np.ndarray, R_world: np.ndarray) -> np.ndarray:
    """:func:`hover_guess` of a position and a rotation already checked (the IK's parsed target)."""
    reach = p.d0 + p.d1 + p.d2 + p.d3
    return np.array([p_world[0], p_world[1], p_world[2] - reach, 0.0, 0.0, _yaw_of(R_world), 0.0, 0.0, 0.0])


def hover_tilt(R_world) -> float:
    """Angle [rad] by which the end-effector y axis leaves the horizontal plane (0 iff reachable in hover)."""
    return _tilt(check_rotation(R_world, "R_world", 1e-6))


def _tilt(R: np.ndarray) -> float:
    """:func:`hover_tilt` of a rotation already checked (the IK's parsed target)."""
    return math.asin(min(1.0, abs(float(R[2, 1]))))


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


def arm_constants(params: QPRRParams) -> ArmConstants:
    """:class:`ArmConstants` of ``params``."""
    return _arm_constants(params)


_LAST_CONSTANTS: tuple = (None, None)  # (params, constants) of the last call: the IK asks for the same ones per solve


def _arm_constants(params: QPRRParams) -> ArmConstants:
    """:func:`arm_constants` remembered for the last (immutable) parameter set."""
    global _LAST_CONSTANTS
    last = _LAST_CONSTANTS
    if last[0] is params:
        return last[1]
    K = _compute_arm_constants(params)
    _LAST_CONSTANTS = (params, K)
    return K


def _compute_arm_constants(params: QPRRParams) -> ArmConstants:
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
    return _prismatic(x_b_prime, y_b_prime, psi, r0, r0_min, r0_max)


def _prismatic(x_b_prime: float, y_b_prime: float, psi: float, r0: float, r0_min: float, r0_max: float) -> tuple[float, float, float]:
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
    for base in (math.pi / 2, -math.pi / 2) + tuple(v for s in (smin, smax) if -1.0 <= s <= 1.0 for v in (math.asin(s), math.pi - math.asin(s))):
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
        return None, 0, IKOutcome.LIMITS, reason
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
            return None, it, IKOutcome.MAX_ITERATIONS, f"Algorithm 4 did not converge in {it} iterations (|F| = {math.sqrt(cost):.3g} m)"
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
                return None, it, IKOutcome.STALLED, f"Algorithm 4 stalled at |F| = {math.sqrt(cost):.3g} m"
    if not lo2 <= th2 <= hi2:  # Algorithm 4 left the feasible range: project, re-solve (3.72) exactly
        th2 = min(max(th2, lo2), hi2)
        h = d2 * math.sin(th2) + d3 * s23
        xp, yp, zb = px - cps * h, py - sps * h, pz - d01 - d2 * math.cos(th2) - d3 * c23
    # (3.79)-(3.81): r0 minimising |x_cm|, then Algorithm 5 (corrected) and (3.71)
    gx = K.k0 + K.a_s * math.sin(th2) + K.a_c * math.cos(th2) + K.b_s * s23 + K.b_c * c23
    xb, yb, r0 = _prismatic(xp, yp, psi, -gx / K.M_s, lo0, hi0)
    return [xb, yb, zb, 0.0, 0.0, psi, r0, th2, t23 - th2], it, IKOutcome.CONVERGED, ""


_IGM_BALANCE = IGMOptions(theta2="balance")


def _guess_tuple(params: QPRRParams, p_d) -> tuple:
    """:func:`hover_guess` as a tuple (no array on the IGM's hot path; the yaw comes from the target)."""
    x, y, z = p_d.tolist()
    return (x, y, z - (params.d0 + params.d1 + params.d2 + params.d3), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def unreachable_hint(R_world) -> str:
    """Why a target is not reachable in hover: its y axis tilted out of the horizontal plane ("" if it is not)."""
    tilt = _tilt(check_rotation(R_world, "R_world", 1e-6))
    return f"the target's y axis is tilted {tilt:.3g} rad out of the horizontal plane" if tilt > 1e-6 else ""


def solve_igm(platform: Platform, data: pin.Data, target, xi0=None, options=None) -> IKResult:
    """Thesis Algorithm 3 (corrected) with Algorithm 4 and 5 for the Q-PRR: see the module docstring."""
    t0 = time.perf_counter()
    params = params_of(platform)
    check_data(platform, data)
    opts = make_options("igm", options, OPTIONS)
    p_d, R_d = parse_target(target)
    if R_d is None:
        raise InputError("method 'igm' needs a full pose target (p_world, R_world)")
    check_resolvable(p_d, opts.position_tol)
    if xi0 is not None:
        guess, init = prepare_xi0(platform, xi0, hover=False).tolist(), "xi0 (given)"
    else:  # (the guess's yaw is not used: psi comes from the target)
        guess, init = _guess_tuple(params, p_d), "hover below the target, arm straight"
    return _igm_run(SolveContext(platform, data, "igm", p_d, R_d, opts, t0, init, True), guess)


def _igm_run(ctx: SolveContext, guess) -> IKResult:
    """Algorithms 3-5 from ``guess`` (xi, its yaw not used) for the target and options of ``ctx``: the method's run."""
    p_d, R_d, opts = ctx.p_d, ctx.R_d, ctx.opts
    if R_d is None:
        raise InputError("method 'igm' needs a full pose target (p_world, R_world)")
    xi_l, it, status, reason = _igm_core(_arm_constants(params_of(ctx.platform)), p_d, R_d, [float(v) for v in guess], opts)
    if xi_l is None:
        return failed_result("igm", status, reason, it, ctx.t0, ctx.init)
    tilt = _tilt(R_d)
    if tilt > opts.orientation_tol:
        status = IKOutcome.UNREACHABLE
        reason = (
            f"the target orientation is not reachable in hover: its y axis is tilted {tilt:.3g} rad out of the "
            "horizontal plane, which needs a base roll/pitch (Algorithm 3 assumes phi = theta = 0)"
        )
    return finish(ctx, hover_q(ctx.platform, xi_l), Ending(status, reason, it), np.array(xi_l))


def _make_igm(platform: Platform, options: IGMOptions):
    """The ``make`` of the registered method ``"igm"``: the Q-PRR only (:func:`qprr.thesis.params_of` refuses others)."""
    params_of(platform)
    return _igm_run


IGM = IKMethod(IGMOptions, _make_igm, "the thesis's analytic IGM (Algorithms 3-5, corrected), the Q-PRR only")
"""The method ``"igm"`` the thesis plug-in registers into :data:`qprr.ik.solver.IK_METHODS`."""


def _thesis_guess(platform, data, p_d, R_d):
    params = params_of(platform)  # p_d, R_d: the IK's parsed and checked target
    if R_d is None:
        xi = _hover_guess(params, p_d, np.eye(3))
        xi[5] = 0.0
        return xi, "hover below the target, arm straight"
    return _hover_guess(params, p_d, R_d), "hover below the target, arm straight"


def _igm_guess(platform, data, p_d, R_d):
    params = params_of(platform)
    if R_d is not None:
        xi_l, _, _, _ = _igm_core(_arm_constants(params), p_d, R_d, _guess_tuple(params, p_d), _IGM_BALANCE)
        if xi_l is not None:
            return np.array(xi_l), "analytic IGM (balanced theta2)"
        return hover_guess(params, p_d, R_d), "hover below the target, arm straight (IGM failed)"
    return _thesis_guess(platform, data, p_d, R_d)


def solver(platform: Platform, method: str = "qp", options=None, *, init: str = "igm") -> IKSolver:
    """An :class:`qprr.ik.IKSolver` with the thesis's defaults for the Q-PRR (``init``: "igm" or "guess" for the QP)."""
    params_of(platform)
    if init not in ("igm", "guess"):
        raise UnknownNameError("QP init", init, ("igm", "guess"))
    guess = _igm_guess if (method == "qp" and init == "igm") else _thesis_guess
    return IKSolver(platform, method, options, initial_guess=guess, unreachable_hint=unreachable_hint)


def solve_qprr(platform: Platform, data: pin.Data, target, method: str = "qp", xi0=None, options=None) -> IKResult:
    """IK of the Q-PRR with the thesis's defaults: methods ``"igm"``, ``"clika"``, ``"dls"``, ``"qp"``.

    ``options`` may hold ``init`` ("igm" default, or "guess") for the QP's initial guess; the
    rest go to the method's options (:data:`OPTIONS`).
    """
    if method == "igm":
        return solve_igm(platform, data, target, xi0, options)
    if method not in OPTIONS:
        raise UnknownNameError("IK method", method, tuple(OPTIONS))
    init = "igm"
    if isinstance(options, dict) and "init" in options:
        if method != "qp":
            raise UnknownNameError(f"option of IK method {method!r}", "init", [f for f in OPTIONS[method].__dataclass_fields__])
        options = dict(options)
        init = options.pop("init")
    return solver(platform, method, options, init=init).solve(data, target, xi0)


# the closed forms refuse NaN, strings, complex, a non-QPRRParams, in their annotated arguments; the IK entry points
# check their own inputs once (a wrapper per call doubled the IGM's time)
checked_module(globals(), skip=("solve_igm", "solver", "solve_qprr"))
