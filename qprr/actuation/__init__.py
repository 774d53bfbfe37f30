"""From rotor thrusts and arm efforts to generalised forces, and back: u = R_Q N f and the allocation.

The actuator vector is f = [f_1..f_n (rotor thrusts, N), arm efforts (N or N m)].  Pinocchio's
generalised force is tau = N f with N = blockdiag(Omega, I) (Thesis (5.44)-(5.46),
:attr:`Platform.actuation_matrix`); in thesis coordinates u = R_Q N f with R_Q = S(xi)^T =
blockdiag(R_b, T^T, I) (Thesis (5.41), corrected: the thesis prints R_b^T T and R_b T in the
middle block; by virtual power it must be T^T).

:class:`Allocator` inverts tau = N f under the rotor bounds (control allocation): an exact
solution when one lies inside the bounds, otherwise PX4-like priorities on proxsuite: first
the force and the roll/pitch torque, then the yaw torque, then (redundant rotor sets) the
thrusts closest to the unconstrained ones.  The base wrench the rotors cannot produce at all
(the body-lateral force of coplanar rotors) is reported as unallocated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum, IntFlag
from math import hypot

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..dynamics import generalized_gravity
from ..errors import DivergenceError, InputError
from ..kinematics import ee_jacobian_world
from ..model import Platform, check_model_data, check_platform
from ..rotors import ideal_wrench_set, rotor_matrix
from ..validation import as_real, as_vector
from .lexicographic import Lexicographic, QPSettings


def input_map_matrix(xi) -> np.ndarray:
    """R_Q(xi) = blockdiag(R_b, T(phi_b)^T, I) = S(xi)^T, Thesis (5.41) corrected."""
    return ch.rate_map(xi).T


def input_map(platform: Platform, xi, f) -> np.ndarray:
    """u = R_Q N f: generalised forces in thesis coordinates of the actuator vector ``f``, Thesis (5.43)."""
    f = as_vector(f, check_platform(platform).n_actuators, "f")
    return input_map_matrix(ch.as_xi(xi, "xi", platform.n_xi)) @ (platform.actuation_matrix @ f)


def generalized_force_from_wrench(platform: Platform, data: pin.Data, q, wrench_world, frame=None) -> np.ndarray:
    """Pinocchio generalised force J^T h of a wrench h = [f; mu] (world axes, applied at the frame origin; default: end effector)."""
    check_model_data(platform, data)
    h = as_vector(wrench_world, 6, "wrench_world")
    return ee_jacobian_world(platform, data, q, frame).T @ h


def generalized_wrench_xi(platform: Platform, data: pin.Data, xi, wrench_world, frame=None) -> np.ndarray:
    """u_e(h) (6 + n_arm,) of Thesis (6.58): u_e = S(xi)^T J_e(q)^T h, thesis coordinates.

    h = [f; mu] in world axes at the frame origin (default: the end effector).  The Q-PRR's
    printed block form (6.59) and its correction are in :mod:`qprr.thesis.interaction`.
    """
    check_model_data(platform, data)
    xi = ch.as_xi(xi, "xi", platform.n_xi)
    return ch.force_to_xi(xi, generalized_force_from_wrench(platform, data, ch.xi_to_q(xi), wrench_world, frame))


# ================================================================================ allocation
_WRENCH_NAMES = ("f_x", "f_y", "f_z", "tau_x", "tau_y", "tau_z")

DEMAND_BOUND = 1e150
"""Bound on the norm of a demanded generalised force in the simulator's screened allocation (beyond it, or NaN: refused)."""

ALLOCATION_SETTINGS = QPSettings(eps_abs=1e-10, eps_primal_inf=1e-12, eps_dual_inf=1e-12, max_iter=10000)
"""proxsuite settings of the allocation QPs: thrusts to 1e-10 N in the scaled problem."""


class AllocationFlag(IntFlag):
    """What limited the allocation of a control tick: the bits :meth:`Allocator.allocate_into` returns and
    :attr:`qprr.sim.SimResult.flags` logs (saved runs store these integer values: 1, 2, 4).

    ``REFUSED`` is returned, alone, by :meth:`Allocator.allocate_screened_into` for a NaN, infinite or absurd
    demand (nothing allocated, nothing written); the simulator then stops the run, so it is never logged.
    """

    NONE = 0
    ROTOR_SATURATED = 1
    """A rotor thrust bound was active (the prioritised QP allocated the thrusts)."""
    ARM_SATURATED = 2
    """An arm effort was clipped to its limit."""
    JOINT_STOP = 4
    """An arm joint reached its mechanical stop during the tick (set by the simulator, :mod:`qprr.sim.stops`)."""
    REFUSED = 8
    """The demanded generalised force was NaN, infinite or absurd: refused (:data:`DEMAND_BOUND`)."""


class AllocationStatus(str, Enum):
    """How an allocation ended: ``exact`` (every producible component met) or ``saturated`` (a bound was active)."""

    EXACT = "exact"
    SATURATED = "saturated"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class AllocationResult:
    """Outcome of one allocation.

    ``f`` = [rotor thrusts (N), arm efforts]; ``tau_desired`` and ``tau_achieved`` = N f are
    Pinocchio generalised forces (body wrench at B in B axes, then arm efforts); ``residual`` =
    desired - achieved (what could not be allocated).  ``status`` (:class:`AllocationStatus`, equal to
    its string) is "exact" (every producible component met) or "saturated" (a bound was active);
    ``reason`` says which.
    """

    f: np.ndarray
    tau_desired: np.ndarray
    tau_achieved: np.ndarray
    residual: np.ndarray
    rotor_saturated: bool
    arm_saturated: bool
    status: AllocationStatus
    reason: str


class Allocator:
    """Rotor thrusts and arm efforts from a desired generalised force tau_d (nv,) of ``platform``.

    * Producible rows: the rows of Omega that are not zero (coplanar rotors: f_z and the three
      torques; a tilted hexarotor: all six).  When they are independent (the usual case) the
      exact allocation is f = Omega_P^-1 w_P (square) or the minimum-norm Omega_P^+ w_P; in
      general, f = Omega^+ w.  Inside [f_min, f_max] this is the answer of every level below.
    * Otherwise, lexicographic bounded least squares (:class:`qprr.actuation.lexicographic.Lexicographic`):
      level 1 the force rows and the roll/pitch torques, weighted (``weight_force`` per newton,
      ``weight_torque`` per newton metre; default 10 / l with l the mean rotor distance from the
      thrust axis: a torque error counts ten times the same per-rotor force error, attitude
      authority first as PX4 does); level 2 the yaw torque; level 3 (redundant rotor sets) the
      thrusts closest to the exact allocation.  Variables are scaled by max f_max.
    * Arm efforts are clipped to the platform's effort limits.

    Calls: :meth:`allocate` validates its input and explains the result; :meth:`allocate_into`
    writes into given buffers without validation (the in-loop form); :meth:`allocate_screened_into`
    is :meth:`allocate_into` behind the screen of a NaN, infinite or absurd demand (``AllocationFlag.REFUSED``), the call of
    :func:`qprr.sim.simulate`.  A subclass changes the allocation by overriding :meth:`allocate_into`
    (as :class:`IdealAllocator` does); the screen then applies to it as well.  The object owns its
    QPs (warm-started between calls); it can be copied or pickled.
    """

    def __init__(
        self,
        platform: Platform,
        *,
        thrust_bounds: tuple[float, float] | None = None,
        weight_force: float = 1.0,
        weight_torque: float | None = None,
        clip_arm: bool = True,
        settings: QPSettings = ALLOCATION_SETTINGS,
    ) -> None:
        check_platform(platform)
        n = platform.n_rotors
        if thrust_bounds is None:
            f_min, f_max = platform.thrust_min.copy(), platform.thrust_max.copy()
        else:
            lo, hi = as_vector(thrust_bounds, 2, "thrust_bounds").tolist()
            if not 0.0 <= lo < hi:
                raise InputError(f"thrust_bounds must satisfy 0 <= min < max [N], got {thrust_bounds!r}")
            f_min, f_max = np.full(n, float(lo)), np.full(n, float(hi))
        weight_force = as_real(weight_force, "weight_force", positive=True)
        if weight_torque is not None:
            weight_torque = as_real(weight_torque, "weight_torque", positive=True)
        if not np.all(np.isfinite(f_max)):
            raise InputError(f"platform {platform.name!r} has rotors without a finite f_max: allocation needs thrust bounds")
        Omega = np.array(platform.rotor_matrix)
        if weight_torque is None:  # (only then is the thrust axis needed: a rotor set may have none, e.g. opposed thrusters)
            point, axis = platform.thrust_axis
            radial = [np.linalg.norm(np.cross(np.array(r.position_body) - point, axis)) for r in platform.rotors]
            l_mean = float(np.mean(radial))
            weight_torque = 10.0 / l_mean if l_mean > 0 else 10.0
        if not isinstance(settings, QPSettings):
            raise InputError(f"settings must be a qprr.actuation.lexicographic.QPSettings, got {type(settings).__name__}")
        self.platform = platform
        self.n_rotors, self.n_arm = n, platform.n_arm
        self.f_min, self.f_max = f_min, f_max
        self.effort_limits = np.array(platform.arm_effort_limits)
        self.clip_arm = bool(clip_arm)
        self.Omega = Omega
        rows = [i for i in range(6) if np.abs(Omega[i]).max() > 1e-12]
        rank = int(np.linalg.matrix_rank(Omega, tol=1e-9))
        self.aligned = len(rows) == rank  # the producible wrench set is spanned by axes of B
        self.rows = rows if self.aligned else list(range(6))
        self._rows = slice(rows[0], rows[-1] + 1) if self.aligned and rows == list(range(rows[0], rows[-1] + 1)) else self.rows
        Omega_P = Omega[self.rows]
        self.square = self.aligned and len(rows) == n
        self.Omega_P_inv = np.linalg.inv(Omega_P) if self.square else np.linalg.pinv(Omega_P)
        # level rows within the producible ones: forces and roll/pitch torques, then yaw
        self._lvl1 = [k for k, i in enumerate(self.rows) if i != 5]
        self._lvl2 = [k for k, i in enumerate(self.rows) if i == 5]
        self._W = np.array([weight_force if self.rows[k] < 3 else weight_torque for k in self._lvl1])
        self._scale = float(f_max.max())
        self._lex = Lexicographic(n, None, settings=settings, regularization=0.0, rank_tol=1e-9, warm_start=True, exact_fallback=True)
        self._zero_rows = [i for i in range(6) if i not in self.rows]  # base rows no rotor produces
        self.qp_calls = 0

    @property
    def weights(self) -> np.ndarray:
        """Level-1 row weights (force rows, then roll/pitch torque rows)."""
        return self._W.copy()

    # ------------------------------------------------------------------ rotors
    def _solve_qp(self, w: np.ndarray, f_exact: np.ndarray) -> np.ndarray:
        """Prioritised allocation of the producible wrench rows ``w`` (bounds active)."""
        self.qp_calls += 1
        if not np.all(np.isfinite(w)):
            bad = ", ".join(f"{_WRENCH_NAMES[i]} = {v!r}" for i, v in zip(self.rows, w.tolist()) if not math.isfinite(v))
            raise DivergenceError(f"the controller asked for a non-finite rotor wrench ({bad}, body axes at B): {w.tolist()}")
        s = self._scale
        OP = self.Omega[self.rows] * s  # x = f / s
        A1 = self._W[:, None] * OP[self._lvl1]
        b1 = self._W * w[self._lvl1]
        obj = max(1.0, float(np.linalg.norm(b1)) / (self.n_rotors * s))  # objective scale: eps_abs stays meaningful
        levels = [(A1 / obj, b1 / obj)]
        if self._lvl2:
            levels.append((OP[self._lvl2], w[self._lvl2]))
        if self.n_rotors > len(self.rows):  # redundant rotors: closest to the exact allocation
            levels.append((np.eye(self.n_rotors), np.clip(f_exact, self.f_min, self.f_max) / s))
        x = self._lex.solve(levels, self.f_min / s, self.f_max / s).x
        return np.clip(x * s, self.f_min, self.f_max)

    def rotor_thrusts(self, wrench_body) -> tuple[np.ndarray, bool]:
        """(f, saturated) for a body wrench [f_B; tau_B] (6,) at B in B axes."""
        w = as_vector(wrench_body, 6, "wrench_body")
        f = self.Omega_P_inv.dot(w[self._rows])
        if np.all(f >= self.f_min) and np.all(f <= self.f_max):
            return f, False
        return self._solve_qp(w[self.rows], f), True

    # ------------------------------------------------------------------ public API
    def allocate(self, tau_desired) -> AllocationResult:
        """Allocate a desired Pinocchio generalised force ``tau_desired`` (nv,): see the class docstring."""
        tau_d = as_vector(tau_desired, self.platform.nv, "tau_desired")
        f = np.empty(self.n_rotors + self.n_arm)
        flags = self.allocate_into(tau_d, f)
        achieved = self.platform.actuation_matrix @ f
        residual = tau_d - achieved
        rot, arm = AllocationFlag.ROTOR_SATURATED in flags, AllocationFlag.ARM_SATURATED in flags
        reasons = []
        if rot:
            reasons.append(f"rotor thrust bounds active: unallocated base wrench {np.round(residual[0:6], 12).tolist()}")
        if arm:
            reasons.append(f"arm effort limits {self.effort_limits.tolist()} active: unallocated {np.round(residual[6:], 12).tolist()}")
        if not rot:
            lost = float(np.linalg.norm(residual[0:6]))
            if lost > 1e-9:
                reasons.append(
                    f"base wrench {np.round(residual[0:6], 12).tolist()} outside what the rotors can produce "
                    f"(rank {self.platform.wrench_rank} of 6{self._unproducible()})"
                )
        status = AllocationStatus.SATURATED if (rot or arm) else AllocationStatus.EXACT
        return AllocationResult(f, tau_d.copy(), achieved, residual, rot, arm, status, "; ".join(reasons) or "all producible components met")

    def _unproducible(self) -> str:
        """Names the base-wrench components (in B) no rotor acts on, for the reasons of :meth:`allocate`."""
        if not self.aligned:
            return ""
        missing = [name for i, name in enumerate(_WRENCH_NAMES) if i not in self.rows]
        if not missing:
            return ""
        lateral = ", the body-lateral force: every thrust is along z_B" if missing == ["f_x", "f_y"] else ""
        return f"; no rotor acts on {', '.join(missing)}{lateral}"

    def allocate_into(self, tau_d: np.ndarray, f_out: np.ndarray, tau_out: np.ndarray | None = None) -> AllocationFlag:
        """In-loop allocation without validation: writes f into ``f_out`` and, if given, N f into ``tau_out``.

        ``tau_d`` (nv,) float64; ``f_out`` (n_rotors + n_arm,) and ``tau_out`` (nv,) float64 arrays.
        Returns the :class:`AllocationFlag` bits ROTOR_SATURATED (a rotor bound was active) and ARM_SATURATED
        (an arm effort was clipped).  A NaN demand raises :class:`~qprr.errors.DivergenceError` naming the
        wrench component or the arm joint (NaN fails every bound test).
        """
        flags = AllocationFlag.NONE
        f = self.Omega_P_inv.dot(tau_d[self._rows])  # the exact allocation of the producible rows
        if not (np.all(self.f_min <= f) and np.all(f <= self.f_max)):  # a bound is active (or NaN)
            f = self._solve_qp(tau_d[self.rows], f)
            flags = AllocationFlag.ROTOR_SATURATED
        arm = tau_d[6:]
        if self.clip_arm:
            if not np.all(np.abs(arm) <= self.effort_limits):  # beyond a limit (or NaN)
                self._check_arm_finite(arm)
                arm = np.clip(arm, -self.effort_limits, self.effort_limits)
                flags |= AllocationFlag.ARM_SATURATED
        elif not np.all(np.isfinite(arm)):
            self._check_arm_finite(arm)
        n = self.n_rotors
        f_out[:n] = f
        f_out[n:] = arm
        if tau_out is not None:
            self._applied_force(tau_d, f, arm, flags, tau_out)
        return flags

    def _applied_force(self, tau_d: np.ndarray, f: np.ndarray, arm: np.ndarray, flags: AllocationFlag, tau_out: np.ndarray) -> None:
        """N f into ``tau_out``: Omega f and the arm efforts; for an exact allocation by a square Omega_P, tau_d itself
        with zeros on the rows no rotor produces (Omega f = tau_d there, bit for bit)."""
        if flags or not self.square:
            tau_out[0:6] = self.Omega @ f
            tau_out[6:] = arm
        else:
            tau_out[:] = tau_d
            tau_out[self._zero_rows] = 0.0

    def allocate_screened_into(self, tau_d: np.ndarray, f_out: np.ndarray, tau_out: np.ndarray | None = None) -> AllocationFlag:
        """:meth:`allocate_into` behind the simulator's screen of the controller's output.

        Returns ``AllocationFlag.REFUSED`` and writes nothing when the norm of ``tau_d`` is NaN, inf or >=
        :data:`DEMAND_BOUND` (the simulator then names the controller's bad entry); otherwise ``self.allocate_into(tau_d,
        f_out, tau_out)``: a subclass that overrides :meth:`allocate_into` is screened the same way.
        This is the call :func:`qprr.sim.simulate` makes at every control tick.
        """
        if not hypot(*tau_d.tolist()) < DEMAND_BOUND:  # the norm; NaN fails
            return AllocationFlag.REFUSED
        return self.allocate_into(tau_d, f_out, tau_out)

    def _check_arm_finite(self, arm: np.ndarray) -> None:
        """DivergenceError naming the first arm joint asked for a non-finite effort."""
        for name, a in zip(self.platform.arm_names, arm.tolist()):
            if not math.isfinite(a):
                raise DivergenceError(f"the controller asked for a non-finite effort on arm joint {name!r}: {a!r}")

    def hover_thrusts(self, data: pin.Data | None = None, q=None) -> np.ndarray:
        """Rotor thrusts that hold the platform still at ``q`` (default: level at the origin, arm at 0).

        The base part of the generalised gravity g(q) allocated exactly; for the thesis's Q-PRR with
        its CoG on z_B, f_i = m_G g / 4.  Raises InputError if a bound is violated.
        """
        p = self.platform
        q = p.neutral_q() if q is None else q
        data = p.data() if data is None else data
        w = generalized_gravity(p, data, q)[0:6]
        f = self.Omega_P_inv.dot(w[self._rows])
        if np.any(f < self.f_min - 1e-12) or np.any(f > self.f_max + 1e-12):
            raise InputError(f"platform {p.name!r} cannot hover at this configuration within its thrust bounds: f = {f.tolist()} N")
        return f


class IdealAllocator(Allocator):
    """Exact allocation on :func:`qprr.rotors.ideal_wrench_set` (an idealised, fully actuated vehicle): every desired
    base wrench is applied as is, within the set's bounds.

    Per axis the force w_f goes to its +e or -e thruster (f = max(+-w_f, 0)) and the couple w_m to the two
    thrusters of its sign (f = max(+-w_m, 0) / 2 each), so N f = tau_d exactly; beyond a thruster's bound the
    thrust is clipped (``AllocationFlag.ROTOR_SATURATED``).  For the thesis's point-to-point test (Sec. 6.3.1.1), which drives the model
    with u directly.
    """

    def __init__(self, platform: Platform, *, clip_arm: bool = True) -> None:
        ideal = ideal_pattern()
        check_platform(platform)
        if platform.n_rotors != 18 or not np.allclose(platform.rotor_matrix, rotor_matrix(ideal), rtol=0, atol=1e-15):
            raise InputError(f"IdealAllocator needs a platform with qprr.rotors.ideal_wrench_set rotors, got {platform!r}")
        super().__init__(platform, weight_torque=1.0, clip_arm=clip_arm)

    def allocate_into(self, tau_d: np.ndarray, f_out: np.ndarray, tau_out: np.ndarray | None = None) -> AllocationFlag:
        f = np.zeros(18)
        for k in range(3):
            wf, wm = float(tau_d[k]), float(tau_d[3 + k])
            f[6 * k + (0 if wf >= 0.0 else 1)] = abs(wf)
            j = 6 * k + (2 if wm >= 0.0 else 4)
            f[j] = f[j + 1] = 0.5 * abs(wm)
        flags = AllocationFlag.NONE
        if np.any(f > self.f_max):
            f = np.minimum(f, self.f_max)
            flags = AllocationFlag.ROTOR_SATURATED
        arm = tau_d[6:].copy()
        if self.clip_arm and np.any(np.abs(arm) > self.effort_limits):
            arm = np.clip(arm, -self.effort_limits, self.effort_limits)
            flags |= AllocationFlag.ARM_SATURATED
        f_out[:18] = f
        f_out[18:] = arm
        if tau_out is not None:
            tau_out[0:6] = self.Omega @ f
            tau_out[6:] = arm
        return flags


def ideal_pattern():
    """The rotor pattern :class:`IdealAllocator` expects (unit bounds; only the columns are compared)."""
    return ideal_wrench_set(1.0, 1.0)
