"""Control allocation: from a desired generalised force to rotor thrusts and arm efforts.

The machine has 7 inputs f = [f1..f4, f_r0, tau_theta2, tau_theta3]; Pinocchio's generalised
force is tau = N f (Thesis (5.44)-(5.46), :func:`qprr.actuation.actuation_matrix`).  A
controller asks for tau_d (9 entries); the rotors can only produce the 4 entries
w = [f_bz, tau_x, tau_y, tau_z] (thrust along z_B and the body torque); the body's lateral
force (tau_d[0:2]) is never producible and is reported as unallocated.

Rotors, each bounded in [f_min, f_max]:

* fast path: f = Omega_z^-1 w (:func:`qprr.actuation.allocation_inverse`, Thesis (A.1)
  corrected).  When it lies inside the bounds it is the exact solution of every priority
  level below (zero error), so no QP is needed;
* otherwise two prioritised least-squares problems solved with proxsuite (PX4-like
  priorities: thrust and roll/pitch torque before yaw):

  1. min_f ||W (A1 f - w1)||^2, A1 = rows (f_bz, tau_x, tau_y) of Omega_z, f in bounds;
  2. min_f (a_psi f - tau_z)^2 subject to A1 f = A1 f*_1 and f in bounds.  The only freedom
     left is the line f = f*_1 + n mu (A1 n = 0, a_psi n = 1, n = yaw direction
     [+-10, -+10, +-10, -+10]); the bounds cut an interval of mu and the optimum is the
     unconstrained mu = tau_z - a_psi f*_1 clamped to it (closed form).  Handing this
     one-variable problem to proxsuite was tried: with the pairs of identical constraint
     rows (opposite rotors) it stalled (MAX_ITER in 17 of 3000 random saturated cases), and
     in the 4-variable form with A1 f = A1 f*_1 it stalls when f*_1 is a vertex.

  W = diag(w_thrust, w_rp, w_rp) weights thrust against roll/pitch inside level 1
  (default w_rp = 10 / l: a roll/pitch torque error counts ten times the thrust error of
  the same per-rotor size, so attitude authority is kept first, as PX4 does).

Arm efforts are clipped to ``params.effort_limits`` (they act on the arm joints only).

proxsuite settings: eps_abs = 1e-10, eps_rel = 0, infeasibility thresholds 1e-12 and the
duality-gap test on (``check_duality_gap``, 1e-10), so that ``PROXQP_SOLVED`` means solved.
The defaults (1e-5, 1e-4, no gap test) return optima off by ~1e-5 N and may flag these
small feasible problems infeasible; and without the gap test a warm-started solve after a
bound change can return the previous point as "solved" in 0 iterations (primal and dual
residuals are zero with the old multipliers, complementarity is not checked; observed with
proxsuite 0.8, see tests/test_allocation.py).  Any other status raises :class:`SolverError`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import proxsuite

from .actuation import rotor_matrix
from .coordinates import as_vector, write_floats
from .errors import InputError, SolverError
from .model import Robot

_SOLVED = proxsuite.proxqp.QPSolverOutput.PROXQP_SOLVED


@dataclass(frozen=True)
class AllocationResult:
    """Outcome of one allocation.

    ``f`` = [f1..f4 (N), f_r0 (N), tau_theta2, tau_theta3 (N m)]; ``tau_desired`` and
    ``tau_achieved`` = N f are Pinocchio generalised forces (body wrench at B in B axes, then
    arm efforts); ``residual`` = desired - achieved (what could not be allocated; its
    entries 0, 1 are the body-lateral force no rotor produces).  ``status`` is "exact"
    (every producible component met) or "saturated" (a bound was active); ``reason`` says which.
    """

    f: np.ndarray
    tau_desired: np.ndarray
    tau_achieved: np.ndarray
    residual: np.ndarray
    rotor_saturated: bool
    arm_saturated: bool
    status: str
    reason: str


def _new_qp(n_eq: int, eps: float, n: int = 4) -> proxsuite.proxqp.dense.QP:
    qp = proxsuite.proxqp.dense.QP(n, n_eq, 4)
    s = qp.settings
    s.eps_abs = eps
    s.eps_rel = 0.0
    s.eps_primal_inf = 1e-12
    s.eps_dual_inf = 1e-12
    s.max_iter = 10000
    s.check_duality_gap = True
    s.eps_duality_gap_abs = eps
    s.eps_duality_gap_rel = 0.0
    s.verbose = False
    return qp


class Allocator:
    """Rotor thrusts and arm efforts from a desired generalised force (see the module docstring).

    One object owns two proxsuite QPs built once and warm-started; :meth:`allocate` is the
    validated public call, :meth:`allocate_into` the allocation-free one the simulator uses.
    """

    def __init__(
        self,
        robot: Robot,
        layout: str = "plus",
        *,
        thrust_bounds: tuple[float, float] | None = None,
        weight_thrust: float = 1.0,
        weight_roll_pitch: float | None = None,
        clip_arm: bool = True,
        eps: float = 1e-10,
    ) -> None:
        p = robot.params
        lo, hi = (p.thrust_min, p.thrust_max) if thrust_bounds is None else thrust_bounds
        if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 <= lo < hi):
            raise InputError(f"thrust_bounds must satisfy 0 <= min < max, got {(lo, hi)!r}")
        if weight_roll_pitch is None:
            weight_roll_pitch = 10.0 / p.arm_length
        if not (weight_thrust > 0 and weight_roll_pitch > 0):
            raise InputError(f"allocation weights must be > 0, got {(weight_thrust, weight_roll_pitch)!r}")
        self.layout = layout
        self.f_min, self.f_max = float(lo), float(hi)
        self.effort_limits = np.asarray(p.effort_limits, dtype=float)
        self._lim = tuple(float(x) for x in p.effort_limits)
        self.clip_arm = bool(clip_arm)
        Omega = rotor_matrix(robot, layout)
        self.Omega = Omega
        self._axial = not np.any(np.abs(Omega[0:2]) > 1e-15)  # every rotor thrusts along z_B
        self.Omega_z = Omega[2:6, :].copy()
        self.Omega_z_inv = np.linalg.inv(self.Omega_z)
        self._A1 = self.Omega_z[0:3, :].copy()
        self._a4 = self.Omega_z[3, :].copy()
        W2 = np.diag([weight_thrust, weight_roll_pitch, weight_roll_pitch]) ** 2
        self._A1tW2 = self._A1.T @ W2
        # level 1 is only positive semi-definite (its optimum is a line along the yaw direction,
        # which level 2 then chooses).  proxsuite handles that; a small ridge (1e-9 I) instead
        # makes warm-started solves stall (MAX_ITER in 20 % of random saturated cases).
        H1 = self._A1tW2 @ self._A1
        _, _, Vt = np.linalg.svd(self._A1)
        self._null = Vt[-1] / np.linalg.norm(Vt[-1])  # A1 n = 0
        self._a4n = float(self._a4 @ self._null)
        # level-2 variable: mu = a4n lambda, the yaw torque moved along the line
        self._null_mu = self._null / self._a4n
        C = np.eye(4)
        self._l = np.full(4, self.f_min)
        self._u = np.full(4, self.f_max)
        self._qp1 = _new_qp(0, eps)
        # scaled variables x = f / f_max in [f_min / f_max, 1]; objective divided by s^2 with
        # s = max(1, |W w1| / (4 f_max)) so that eps_abs is meaningful for large demands too
        self._H1 = H1 * self.f_max**2
        w_hover = np.array([p.total_mass * p.g, 0.0, 0.0])
        self._qp1.init(self._H1, -(self._A1tW2 @ w_hover) * self.f_max, None, None, C, self._l / self.f_max, np.ones(4))
        self._W = np.array([weight_thrust, weight_roll_pitch, weight_roll_pitch])
        self._qp1.solve()  # warm start from a previous result needs one (else proxsuite 0.8 segfaults)
        self._qp1.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
        self.qp_calls = 0
        self.qp_retries = 0

    # ------------------------------------------------------------------ rotors
    def _solve_qp(self, w: np.ndarray) -> np.ndarray:
        """Two-level prioritised allocation of w = [f_bz, tau_x, tau_y, tau_z] (bounds active)."""
        self.qp_calls += 1
        if not np.all(np.isfinite(w)):
            from .errors import DivergenceError

            raise DivergenceError(f"the controller asked for a non-finite wrench [f_bz, tau_x, tau_y, tau_z] = {w.tolist()}")
        qp1 = self._qp1
        s = max(1.0, float(np.linalg.norm(self._W * w[0:3])) / (4.0 * self.f_max))
        qp1.update(H=self._H1 / (s * s), g=-(self._A1tW2 @ w[0:3]) * (self.f_max / (s * s)))
        qp1.solve()
        if qp1.results.info.status != _SOLVED:
            # warm starts occasionally stall just above eps on large demands: retry cold once
            self.qp_retries += 1
            qp1.settings.initial_guess = proxsuite.proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
            qp1.solve()
            qp1.settings.initial_guess = proxsuite.proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
        if qp1.results.info.status != _SOLVED:
            raise SolverError(f"allocation level 1 (thrust, roll, pitch) failed: proxsuite status {qp1.results.info.status} for w = {w.tolist()}")
        f1 = np.clip(qp1.results.x * self.f_max, self.f_min, self.f_max)
        # level 2: f = f1 + n_mu mu keeps level 1's achievement; yaw torque = a4 f1 + mu.
        # Bounds give an interval for mu; the optimum is the unconstrained mu clamped to it.
        mu = w[3] - self._a4 @ f1
        d = self._null_mu
        lo, hi = -np.inf, np.inf
        for i in range(4):
            a, b = (self.f_min - f1[i]) / d[i], (self.f_max - f1[i]) / d[i]
            if a > b:
                a, b = b, a
            lo, hi = max(lo, a), min(hi, b)
        mu = min(max(mu, lo), hi) if lo <= hi else 0.0
        return np.clip(f1 + d * mu, self.f_min, self.f_max)

    def rotor_thrusts(self, w) -> tuple[np.ndarray, bool]:
        """(f, saturated) for w = [f_bz, tau_x, tau_y, tau_z] (body, N and N m)."""
        f = self.Omega_z_inv.dot(w)  # = Omega_z_inv @ w (same BLAS product), less call overhead
        f0, f1, f2, f3 = f.tolist()
        lo, hi = self.f_min, self.f_max
        if min(f0, f1, f2, f3) >= lo and max(f0, f1, f2, f3) <= hi:
            return f, False
        return self._solve_qp(np.asarray(w, dtype=float)), True

    # ------------------------------------------------------------------ public API
    def allocate(self, tau_desired) -> AllocationResult:
        """Allocate a desired Pinocchio generalised force ``tau_desired`` (9,): see the module docstring."""
        tau_d = as_vector(tau_desired, 9, "tau_desired")
        f = np.empty(7)
        flags = self.allocate_into(tau_d, f)
        achieved = np.zeros(9)
        achieved[0:6] = self.Omega @ f[0:4]
        achieved[6:9] = f[4:7]
        residual = tau_d - achieved
        rot, arm = bool(flags & 1), bool(flags & 2)
        reasons = []
        if rot:
            reasons.append(
                f"rotor thrust bounds [{self.f_min:g}, {self.f_max:g}] N active: unallocated "
                f"[f_bz, tau_x, tau_y, tau_z] = {np.round(residual[2:6], 12).tolist()}"
            )
        if arm:
            reasons.append(f"arm effort limits {self.effort_limits.tolist()} active: unallocated {np.round(residual[6:9], 12).tolist()}")
        lateral = float(np.hypot(residual[0], residual[1]))
        if lateral > 0.0:
            reasons.append(f"body-lateral force {lateral:.3g} N cannot be produced by rotors (thrust is along z_B)")
        status = "saturated" if (rot or arm) else "exact"
        return AllocationResult(f, tau_d.copy(), achieved, residual, rot, arm, status, "; ".join(reasons) or "all producible components met")

    def allocate_into(self, tau_d: np.ndarray, f_out: np.ndarray, tau_out: np.ndarray | None = None) -> int:
        """In-loop allocation without validation: writes f (7,) into ``f_out`` and, if given, N f into ``tau_out``.

        ``tau_d`` (9,) float64; ``f_out`` (7,) and ``tau_out`` (9,) float64 arrays.
        Returns bit flags: 1 if a rotor bound was active, 2 if an arm effort was clipped.
        """
        td = tau_d.tolist()
        w = tau_d[2:6]
        f = self.Omega_z_inv.dot(w)  # fast path of :meth:`rotor_thrusts`, inlined
        f0, f1, f2, f3 = f.tolist()
        lo, hi = self.f_min, self.f_max
        if lo <= f0 <= hi and lo <= f1 <= hi and lo <= f2 <= hi and lo <= f3 <= hi:
            flags = 0
        elif min(f0, f1, f2, f3) >= lo and max(f0, f1, f2, f3) <= hi:  # rotor_thrusts's test (differs on NaN)
            flags = 0
        else:
            f = self._solve_qp(np.asarray(w, dtype=float))
            f0, f1, f2, f3 = f.tolist()
            flags = 1
        a0, a1, a2 = td[6:9]
        if self.clip_arm:
            l0, l1, l2 = self._lim
            if a0 > l0 or a0 < -l0 or a1 > l1 or a1 < -l1 or a2 > l2 or a2 < -l2:
                a0, a1, a2 = np.clip(tau_d[6:9], -self.effort_limits, self.effort_limits).tolist()
                flags |= 2
        write_floats(f_out, (f0, f1, f2, f3, a0, a1, a2))
        if tau_out is not None:
            if flags or not self._axial:
                tau_out[0:6] = self.Omega @ f
                tau_out[6:9] = (a0, a1, a2)
            else:  # exact: Omega f = [0, 0, w] (rotor axes along z_B), arm efforts unchanged
                td[0] = td[1] = 0.0
                write_floats(tau_out, td)
        return flags



