"""Position-based impedance control of the Q-PRR, Thesis Sec. 6.4.3.3 ((6.71), (6.74)-(6.81)).

Impedance filters (second order, diagonal) turn the measured interaction into a deviation of
the reference that the inner loop then tracks:

* (6.71): M_e Delta_ddot + D_e Delta_dot + K_e Delta = gamma, gamma = T_A(phi_e)^T h
  (:func:`analytic_wrench`), for an end-effector pose chi_e = [p_e; phi_e];
* (6.74), base: M_D Delta_eta_ddot + D_D Delta_eta_dot + K_P Delta_eta = h_b,
  eta = [x, y, z, psi], h_b the generalised force of the environment on eta;
* (6.75), arm (joint space): M_D^q Delta_q_ddot + D_D^q Delta_q_dot + K_P^q Delta_q = J_eb^T h_q,
  with J_eb^T h_q = u_e,mu, the arm rows of u_e(h) (6.59).

Sign: the thesis writes Delta = (desired) - (reference) with h the wrench exerted ON the robot
by the environment (6.59).  Then the reference moves against the force (chi_r = chi_d - K^-1 h),
which stiffens the robot instead of making it compliant: the printed sign belongs to
Siciliano's convention where h is the wrench the robot exerts on the environment.  Here
Delta = (reference) - (desired): the reference yields along the external force and the
steady-state deflection is +K^-1 h.

Control law (6.76): u = B alpha + C xi_dot + G - u_e(h), i.e. the inverse dynamics of
:class:`qprr.control.payload_idc.LayeredIDC` plus the compensation of the measured wrench
(it cancels u_e in (6.58) exactly when the measurement is exact); (6.80) and (6.81) are its
position and arm rows.  alpha comes from (6.77) (attitude PD), (6.78) (position) and (6.79)
(arm PI) around the impedance-filtered references; gains :meth:`LayeredGains.table_6_7`
(printed) or :meth:`LayeredGains.impedance_default` (made stable, see there).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..coordinates import as_vector, euler_rate_matrix, euler_to_rotation
from ..errors import InputError
from ..model import Robot
from .base import Reference, State
from .payload_idc import LayeredGains, LayeredIDC

Quad = tuple[float, float, float, float]
Triple = tuple[float, float, float]


@dataclass(frozen=True)
class ImpedanceGains:
    """Diagonal impedance parameters of (6.74) (base, eta = [x, y, z, psi]) and (6.75) (arm, [r0, theta2, theta3])."""

    M_base: Quad = (0.1, 0.1, 0.1, 0.1)
    D_base: Quad = (1.0, 1.0, 1.0, 1.0)
    K_base: Quad = (0.5, 0.5, 0.5, 0.5)
    M_arm: Triple = (0.02, 0.02, 0.02)
    D_arm: Triple = (1.0, 1.0, 1.0)
    K_arm: Triple = (0.08, 0.08, 0.08)

    def __post_init__(self) -> None:
        for name in ("M_base", "D_base", "K_base", "M_arm", "D_arm", "K_arm"):
            v = getattr(self, name)
            n = 4 if name.endswith("base") else 3
            if len(v) != n or not all(np.isfinite(x) and x > 0.0 for x in v):
                raise InputError(f"impedance {name} must be {n} finite numbers > 0, got {v!r}")

    @classmethod
    def table_6_7(cls) -> ImpedanceGains:
        """Thesis Table 6.7: M_D = 0.1 I4, D_D = I4, K_P = 0.5 I4; M_D^q = 0.02 I3, D_D^q = I3, K_P^q = 0.08 I3."""
        return cls()

    @classmethod
    def default(cls) -> ImpedanceGains:
        """Table 6.7 with the slider stiffness raised to 2.5 N/m.

        With K_P^q = 0.08 N/m the slider yields 0.625 m under the 0.05 N of Sec. 6.4.3.4,
        15 times its +-0.04 m stroke; 2.5 N/m gives 0.02 m.  Its damping follows to keep the
        printed time constant of the fast pole (D = 1 N s/m).
        """
        return replace(cls(), K_arm=(2.5, 0.08, 0.08))


def _expm(A: np.ndarray) -> np.ndarray:
    """Matrix exponential by scaling and squaring of a degree-18 Taylor series (small dense matrices)."""
    norm = float(np.abs(A).sum(axis=1).max())
    s = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0.5 else 0
    X = A / (2.0**s)
    E = np.eye(A.shape[0])
    term = np.eye(A.shape[0])
    for k in range(1, 19):
        term = term @ X / k
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


class ImpedanceFilter:
    """n decoupled second-order filters M Delta_ddot + D Delta_dot + K Delta = f, integrated exactly under a ZOH input.

    ``step(f, dt)`` advances (Delta, Delta_dot) by dt with f held, and returns
    (Delta, Delta_dot, Delta_ddot) at the end of the step.  Steady state: Delta = f / K.
    """

    def __init__(self, M, D, K) -> None:
        self.M = np.asarray(M, dtype=float)
        self.D = np.asarray(D, dtype=float)
        self.K = np.asarray(K, dtype=float)
        n = self.M.shape[0]
        if self.M.shape != (n,) or self.D.shape != (n,) or self.K.shape != (n,) or not np.all((self.M > 0) & (self.D > 0) & (self.K > 0)):
            raise InputError(f"M, D, K must be positive vectors of one length, got {M!r}, {D!r}, {K!r}")
        self.n = n
        self._dt = None
        self.reset()

    def reset(self, delta=None, delta_dot=None) -> None:
        self.delta = np.zeros(self.n) if delta is None else as_vector(delta, self.n, "delta").copy()
        self.delta_dot = np.zeros(self.n) if delta_dot is None else as_vector(delta_dot, self.n, "delta_dot").copy()
        self.delta_ddot = np.zeros(self.n)

    def _discretise(self, dt: float) -> None:
        self._Phi = np.zeros((self.n, 2, 2))
        self._Gam = np.zeros((self.n, 2))
        for i in range(self.n):
            A = np.zeros((3, 3))
            A[0, 1] = 1.0
            A[1, 0], A[1, 1], A[1, 2] = -self.K[i] / self.M[i], -self.D[i] / self.M[i], 1.0 / self.M[i]
            E = _expm(A * dt)
            self._Phi[i], self._Gam[i] = E[0:2, 0:2], E[0:2, 2]
        self._dt = dt

    def step(self, f, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        f = as_vector(f, self.n, "f")
        if dt != self._dt:
            if not dt > 0.0:
                raise InputError(f"dt must be > 0 s, got {dt!r}")
            self._discretise(dt)
        x0, x1 = self.delta, self.delta_dot
        P, G = self._Phi, self._Gam
        self.delta = P[:, 0, 0] * x0 + P[:, 0, 1] * x1 + G[:, 0] * f
        self.delta_dot = P[:, 1, 0] * x0 + P[:, 1, 1] * x1 + G[:, 1] * f
        self.delta_ddot = (f - self.D * self.delta_dot - self.K * self.delta) / self.M
        return self.delta, self.delta_dot, self.delta_ddot

    def steady_state(self, f) -> np.ndarray:
        """K^-1 f."""
        return as_vector(f, self.n, "f") / self.K


def analytic_wrench(euler_e, h_world) -> np.ndarray:
    """gamma = T_A(phi_e)^T h of Thesis (6.71): the wrench h = [f; mu] (world) as a force on chi_e = [p_e; phi_e] (ZYX).

    T_A = blockdiag(I3, R_e T(phi_e)) maps chi_e_dot to [p_dot; omega_world], so gamma . chi_e_dot = h . [p_dot; omega].
    """
    e = as_vector(euler_e, 3, "euler_e")
    h = as_vector(h_world, 6, "h_world")
    Tw = euler_to_rotation(e) @ euler_rate_matrix(e)
    return np.concatenate([h[0:3], Tw.T @ h[3:6]])


class ImpedanceController(LayeredIDC):
    """Layered IDC tracking impedance-filtered references, with measured-wrench compensation (6.74)-(6.81).

    ``ee_sensor(t) -> h`` (6,) world wrench on the end effector; ``base_sensor(t) -> h_b``
    (4,) generalised force on [x, y, z, psi].  Either may be None (no interaction there).
    ``compensate`` adds -u_e(h) (6.76).  Arm references are kept inside the joint limits
    (less ``limit_margin``); ``saturated_steps`` counts the steps where that bound acted.
    """

    name = "impedance"

    def __init__(self, robot: Robot, gains: LayeredGains | None = None, impedance: ImpedanceGains | None = None, *,
                 ee_sensor: Callable[[float], np.ndarray] | None = None,
                 base_sensor: Callable[[float], np.ndarray] | None = None,
                 compensate: bool = True, limit_margin: float = 1e-3) -> None:
        super().__init__(robot, LayeredGains.impedance_default() if gains is None else gains,
                         ee_sensor=ee_sensor, base_sensor=base_sensor, compensate=compensate)
        self.name = "impedance"
        self.impedance = ImpedanceGains.default() if impedance is None else impedance
        self.limit_margin = float(limit_margin)

    def reset(self, state: State, ref: Reference, dt: float) -> None:
        super().reset(state, ref, dt)
        imp = self.impedance
        self.base_filter = ImpedanceFilter(imp.M_base, imp.D_base, imp.K_base)
        self.arm_filter = ImpedanceFilter(imp.M_arm, imp.D_arm, imp.K_arm)
        self.saturated_steps = 0
        self._u_e = np.zeros(9)
        self._h_b = np.zeros(4)
        self.log: list[np.ndarray] = []

    def update_references(self, t: float, state: State, ref: Reference) -> None:
        """(6.74) on eta = [x, y, z, psi] driven by h_b, (6.75) on the arm driven by u_e,mu = J_eb^T h_q."""
        h_b, u_e = self._h_b, self._u_e  # measured in LayeredIDC.step
        dt = self.dt
        d, dd, ddd = self.base_filter.step(h_b, dt)
        idx = [0, 1, 2, 5]
        ref.xi[idx] += d
        ref.xi_dot[idx] += dd
        ref.xi_ddot[idx] += ddd
        qa, qad, qadd = self.arm_filter.step(u_e[6:9], dt)
        lo = self.robot.params.lower_limits + self.limit_margin
        hi = self.robot.params.upper_limits - self.limit_margin
        target = ref.xi[6:9] + qa
        clipped = np.clip(target, lo, hi)
        if np.any(clipped != target):
            self.saturated_steps += 1
            over = clipped != target
            f = self.arm_filter
            f.delta[over] = clipped[over] - ref.xi[6:9][over]
            f.delta_dot[over] = 0.0
            f.delta_ddot[over] = 0.0
            qa, qad, qadd = f.delta, f.delta_dot, f.delta_ddot
        ref.xi[6:9] += qa
        ref.xi_dot[6:9] += qad
        ref.xi_ddot[6:9] += qadd
        self.log.append(np.concatenate([[t], d, qa, u_e]))

    def history(self) -> dict[str, np.ndarray]:
        """Logged t, base deflection Delta_eta (n, 4), arm deflection Delta_q (n, 3), u_e (n, 9)."""
        a = np.array(self.log) if self.log else np.zeros((0, 17))
        return {"t": a[:, 0], "delta_eta": a[:, 1:5], "delta_q": a[:, 5:8], "u_e": a[:, 8:17]}
