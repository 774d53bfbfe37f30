"""Position-based impedance control of any platform, Thesis Sec. 6.4.3.3 ((6.71), (6.74)-(6.81)).

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
:class:`qprr.control.inverse_dynamics.LayeredIDC` plus the compensation of the measured wrench
(it cancels u_e in (6.58) exactly when the measurement is exact); (6.80) and (6.81) are its
position and arm rows.  alpha comes from (6.77) (attitude PD), (6.78) (position) and (6.79)
(arm PI) around the impedance-filtered references; gains of :mod:`qprr.thesis.gains`
(``table_6_7()`` printed, ``impedance()`` made stable) or any :class:`IDCGains`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from ..charts import State, euler_rate_matrix, euler_to_rotation
from ..errors import InputError
from ..model import Platform, check_platform
from ..validation import as_array, as_int, as_real, as_vector
from .base import Reference
from .inverse_dynamics import IDCGains, LayeredIDC

Quad = tuple[float, float, float, float]


@dataclass(frozen=True)
class ImpedanceGains:
    """Diagonal impedance parameters of (6.74) (base, eta = [x, y, z, psi]) and (6.75) (arm joints).

    ``*_base``: 4 values > 0; ``*_arm``: one value per arm joint (or one for all) > 0.  Table 6.7's
    values are in :mod:`qprr.thesis.gains`.
    """

    M_base: Quad = (0.1, 0.1, 0.1, 0.1)
    D_base: Quad = (1.0, 1.0, 1.0, 1.0)
    K_base: Quad = (0.5, 0.5, 0.5, 0.5)
    M_arm: tuple[float, ...] | float = 0.02
    D_arm: tuple[float, ...] | float = 1.0
    K_arm: tuple[float, ...] | float = 2.5

    def __post_init__(self) -> None:
        for name in ("M_base", "D_base", "K_base", "M_arm", "D_arm", "K_arm"):
            v = np.atleast_1d(as_array(getattr(self, name), f"impedance {name}"))
            if (name.endswith("base") and v.shape != (4,)) or v.ndim != 1 or not np.all(np.isfinite(v) & (v > 0.0)):
                raise InputError(
                    f"impedance {name} must be {'4' if name.endswith('base') else 'n_arm (or 1)'} finite numbers > 0, got {getattr(self, name)!r}"
                )

    def arm(self, n_arm: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, D, K) of the arm filter for ``n_arm`` joints."""
        n_arm = as_int(n_arm, "n_arm", lo=0)
        out = []
        for name in ("M_arm", "D_arm", "K_arm"):
            v = np.atleast_1d(np.asarray(getattr(self, name), dtype=float))
            if v.shape[0] not in (1, n_arm):
                raise InputError(f"impedance {name} has {v.shape[0]} entries for {n_arm} arm joints")
            out.append(np.broadcast_to(v, (n_arm,)).copy())
        return tuple(out)


class ImpedanceFilter:
    """n decoupled second-order filters M Delta_ddot + D Delta_dot + K Delta = f, integrated exactly under a ZOH input.

    ``step(f, dt)`` advances (Delta, Delta_dot) by dt with f held, and returns
    (Delta, Delta_dot, Delta_ddot) at the end of the step.  Steady state: Delta = f / K.
    """

    def __init__(self, M, D, K) -> None:
        self.M = as_array(M, "M", finite=True, ndim=1)
        self.D = as_array(D, "D", finite=True, ndim=1)
        self.K = as_array(K, "K", finite=True, ndim=1)
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
            E = expm(A * dt)
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

    def __init__(
        self,
        platform: Platform,
        gains: IDCGains | None = None,
        impedance: ImpedanceGains | None = None,
        *,
        ee_sensor: Callable[[float], np.ndarray] | None = None,
        base_sensor: Callable[[float], np.ndarray] | None = None,
        compensate: bool = True,
        limit_margin: float = 1e-3,
    ) -> None:
        check_platform(platform)
        self.impedance = ImpedanceGains() if impedance is None else impedance
        if not isinstance(self.impedance, ImpedanceGains):
            raise InputError(f"impedance must be an ImpedanceGains, got {type(self.impedance).__name__}")
        self.impedance.arm(platform.n_arm)  # sizes checked now
        self.limit_margin = as_real(limit_margin, "limit_margin", nonnegative=True)
        super().__init__(platform, gains, ee_sensor=ee_sensor, base_sensor=base_sensor, compensate=compensate)
        self.name = "impedance"

    def _new_run(self) -> None:
        super()._new_run()
        imp = self.impedance
        self.base_filter = ImpedanceFilter(imp.M_base, imp.D_base, imp.K_base)
        self.arm_filter = ImpedanceFilter(*imp.arm(self.platform.n_arm))
        self.saturated_steps = 0
        self._u_e = np.zeros(self.platform.n_xi)
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
        qa, qad, qadd = self.arm_filter.step(u_e[6:], dt)
        lo = self.platform.arm_lower + self.limit_margin
        hi = self.platform.arm_upper - self.limit_margin
        target = ref.xi[6:] + qa
        clipped = np.clip(target, lo, hi)
        if np.any(clipped != target):
            self.saturated_steps += 1
            over = clipped != target
            f = self.arm_filter
            f.delta[over] = clipped[over] - ref.xi[6:][over]
            f.delta_dot[over] = 0.0
            f.delta_ddot[over] = 0.0
            qa, qad, qadd = f.delta, f.delta_dot, f.delta_ddot
        ref.xi[6:] += qa
        ref.xi_dot[6:] += qad
        ref.xi_ddot[6:] += qadd
        self.log.append(np.concatenate([[t], d, qa, u_e]))

    def history(self) -> dict[str, np.ndarray]:
        """Logged t, base deflection Delta_eta (m, 4), arm deflection Delta_q (m, n_arm), u_e (m, 6 + n_arm)."""
        n_arm, n_xi = self.platform.n_arm, self.platform.n_xi
        a = np.array(self.log) if self.log else np.zeros((0, 5 + n_arm + n_xi))
        return {"t": a[:, 0], "delta_eta": a[:, 1:5], "delta_q": a[:, 5 : 5 + n_arm], "u_e": a[:, 5 + n_arm :]}
