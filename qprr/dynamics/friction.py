"""Joint friction from the URDF's ``<dynamics damping friction>``: viscous damping and smoothed Coulomb friction.

Pinocchio's URDF parser stores ``<dynamics damping="d" friction="F"/>`` of each joint in ``model.damping``
and ``model.friction`` (one entry per velocity coordinate).  The plant applies, per arm joint i, the
generalised force

    tau_f,i = -d_i v_i - F_i tanh(v_i / v_s)                                   [N m or N]

viscous damping d_i [N m s/rad or N s/m] plus Coulomb friction of magnitude F_i [N m or N] smoothed
by the hyperbolic tangent over the velocity scale v_s (:data:`VELOCITY_SCALE`, 0.01 rad/s or m/s:
at |v| = 3 v_s the Coulomb term is 99.5 % of F).  The smooth law keeps the right-hand side
differentiable, so the integrators keep their order.  The free-flyer coordinates carry no joint friction
(their entries of ``model.damping`` / ``model.friction`` must be zero).  This is the F_v q_dot term of
Thesis (5.36) for the viscous part (in the thesis's coordinates the arm rows of F_v are the d_i).

The force is stiff on light links: its Jacobian K(v) = -dtau_f/dv = diag(d_i + F_i / v_s sech^2(v_i / v_s))
over the joint-space inertia M gives rates up to :meth:`JointFriction.max_rate` [1/s] (hextilt_flying_arm_5:
9.3e3 1/s from the damping alone, its last link has 1.1e-5 kg m^2), and an explicit integrator is stable only for
dt * rate below about 2 (euler, midpoint) or 2.8 (rk4) (:data:`STABILITY`, :meth:`JointFriction.stable_step`).

Each joint is taken one of two ways (:class:`Treatment`), chosen once per run by :meth:`JointFriction.choose` from its
stiffness at the run's first configuration: joint i's rate is r_i = K_i(0) (M^-1)_ii (K at v = 0, the largest; 1 /
(M^-1)_ii <= M_ii is the joint's inertia with the other joints free), the joints are added to the explicit set in the
order of r_i while dt times the largest eigenvalue of (M^-1)_EE K_E over the explicit set E stays at or below
:data:`STIFF` = 1 (half the stability bound of euler and midpoint: a margin for the changes of M(q) during a run);
the others are implicit.

* **explicit**: tau_f(V) at each stage's velocity V, an ordinary term of the right-hand side.  The integrator keeps its
  order (1, 2, 4 for euler, midpoint, rk4: tests/test_friction_orders.py measures them).
* **implicit**: every stage takes the implicit joints S over the whole step dt from the step's start velocity v0
  (:meth:`JointFriction.start`): at a stage (t, q, V), with a0 = M^-1 (tau + tau_f,E(V) - h(q, V)) the forward dynamics
  without the implicit joints' friction and W = (M^-1)_SS, the acceleration is

      a = a0 + (M^-1)_{:,S} W^-1 ((x - v0_S) / dt - a0_S)                                               (1)

  (a_S = (x - v0_S) / dt: the stage's estimate of the step's increment), where x, the implicit joints' velocity at
  the end of the step, is that of v' = a0_S + W tau_f,S over [0, dt] from v0_S with a0 and W held, the damping
  -D v exact and the Coulomb force at x (exponential Euler for the linear part, Hochbruck & Ostermann, "Exponential
  integrators", Acta Numerica 19, 2010, Sec. 2.1; backward Euler for the Coulomb part):

      x = exp(-dt W D) v0_S + dt phi1(-dt W D) (a0_S + W tau_c(x)),   phi1(z) = (exp(z) - 1) / z,         (2)

  tau_c(x) = -F tanh(x / v_s).  This is exact for damping plus a constant force (v0 -> v_inf along
  exp(-dt W D), the 0.1 ms transient of the hextilt's wrist included, where backward Euler's 1 / (1 + dt d / M) lagged
  it by 15 % at 1 ms).  With W = L L^T and L^T D L = U diag(lam) U^T, f(W D) = L U f(lam) (L U)^-1, so
  Q = phi1(-dt W D) W = L U phi1(-dt lam) (L U)^T is symmetric positive definite, and as tau_c = -grad Psi with the
  convex Psi(x) = sum F v_s log cosh(x / v_s), x is the minimiser of the strictly convex

      (x - b)^T Q^-1 (x - b) / 2 + dt Psi(x),   b = exp(-dt W D) v0_S + dt phi1(-dt W D) a0_S:           (3)

  :meth:`JointFriction.solve` finds it by Newton's method with a backtracking line search, which converges from any
  start on such a function (Boyd & Vandenberghe, *Convex Optimization*, Sec. 9.5).  A linearisation of tanh at V
  (one Newton step, a Rosenbrock-Euler step) is not enough: from V = 0.32 rad/s, where tanh is flat, it jumps to
  -0.32 and back (a two-cycle where the joint sticks).  Every stage of every integrator estimates the increment from
  v0 over the whole dt and the weights sum to 1, so on v' = -lambda v all three give v+ = exp(-lambda dt) v0:
  L-stable, monotone (the rate of a stiff joint never changes sign spuriously), and a state at rest under
  tau + tau_f = h stays there (x = v0 solves (2): no spurious fixed point).  The stage's own fraction of the step
  instead of dt (dt / 2 at midpoint's first stage) would not be: rk4's weights then give v+ -> -v0 / 2 as
  lambda dt -> inf with backward Euler; and the earlier form, the linearisation at V taken from V instead of v0, had
  a fixed point of midpoint at -0.645 rad/s where the exact motion settles at +1 rad/s (issue 34).  Measured against
  MuJoCo on the hextilt's stiff wrist (tests/test_friction_orders.py): first order with euler (its position
  q+ = q + dt v+ takes the end rate over the whole step), 1.7-2.4 per halving with midpoint and rk4 (their stages
  at t + dt / 2 make (2) the exponential midpoint rule; the Coulomb part, taken at the step's end, is first order).
"""

from __future__ import annotations

import math
from enum import Enum

import numpy as np
import pinocchio as pin

from .. import charts as ch
from ..errors import InputError, UnknownNameError
from ..validation import as_real, as_vector

VELOCITY_SCALE = 1e-2
"""v_s [rad/s or m/s]: the velocity over which the Coulomb term of :class:`JointFriction` goes from 0 to ~F (tanh)."""

STABILITY = {"euler": 2.0, "midpoint": 2.0, "rk4": 2.785}
"""|lambda dt| bounds of the explicit integrators on a real negative eigenvalue lambda (the stability intervals of
forward Euler and explicit midpoint, [-2, 0], and of RK4, [-2.785, 0])."""

STIFF = 1.0
"""dt x rate above which a joint's friction is taken implicitly (:meth:`JointFriction.choose`): half the stability
bound of euler and midpoint (:data:`STABILITY`)."""


class Treatment(Enum):
    """How the plant integrates one joint's friction (the module docstring)."""

    EXPLICIT = "explicit"
    IMPLICIT = "implicit"


class JointFriction:
    """The joint friction of a Pinocchio model (see the module docstring); build with :meth:`from_model`.

    ``step`` > 0 with ``implicit`` None takes every joint with friction implicitly over ``step``; ``implicit`` (nv,)
    booleans choose the joints (:meth:`choose` picks them from the stiffness); ``step`` = 0: all explicit."""

    def __init__(self, damping, friction, velocity_scale: float = VELOCITY_SCALE, step: float = 0.0, implicit=None) -> None:
        d = np.array(damping, dtype=float).ravel()
        F = np.array(friction, dtype=float).ravel()
        if d.shape != F.shape or not (np.all(np.isfinite(d)) and np.all(np.isfinite(F))) or np.any(d < 0.0) or np.any(F < 0.0):
            raise InputError(f"joint damping and friction must be finite values >= 0 of one size, got {d.tolist()} and {F.tolist()}")
        if not (isinstance(velocity_scale, (int, float)) and math.isfinite(velocity_scale) and velocity_scale > 0.0):
            raise InputError(f"velocity_scale (v_s of the Coulomb term) must be a number > 0 [rad/s or m/s], got {velocity_scale!r}")
        if not (isinstance(step, (int, float)) and math.isfinite(step) and step >= 0.0):
            raise InputError(f"step (h of the implicit friction) must be a number >= 0 [s], got {step!r}")
        self.damping, self.friction, self.velocity_scale, self.step = d, F, float(velocity_scale), float(step)
        self._idx = np.flatnonzero((d > 0.0) | (F > 0.0))
        mask = np.full(d.shape[0], self.step > 0.0) if implicit is None else np.array(implicit, dtype=bool).ravel()
        if mask.shape != d.shape:
            raise InputError(f"implicit must hold one boolean per velocity coordinate ({d.shape[0]}), got {mask.shape[0]}")
        self._imp = self._idx[mask[self._idx]] if self.step > 0.0 else self._idx[:0]
        self._exp = np.setdiff1d(self._idx, self._imp)
        self._v0 = None

    @classmethod
    def from_model(cls, model: pin.Model, step: float = 0.0, velocity_scale: float = VELOCITY_SCALE, q=None) -> JointFriction | None:
        """The friction of ``model`` (``model.damping``, ``model.friction``), None when every entry is zero; ``step``: the
        integration step dt (0: every joint explicit), the implicit joints chosen by :meth:`choose` at ``q`` (default the
        neutral configuration)."""
        if not isinstance(model, pin.Model):
            raise InputError(f"model must be a pinocchio.Model, got {type(model).__name__}")
        d, F = np.array(model.damping), np.array(model.friction)
        if not (np.any(d != 0.0) or np.any(F != 0.0)):
            return None
        if model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer" and (np.any(d[:6] != 0.0) or np.any(F[:6] != 0.0)):
            raise InputError(
                f"the free-flyer joint of {model.name!r} has damping {d[:6].tolist()} / friction {F[:6].tolist()}: "
                "joint friction applies to the arm joints only"
            )
        out = cls(d, F, velocity_scale)
        if step > 0.0:
            implicit = [t is Treatment.IMPLICIT for t in out.choose(model, pin.neutral(model) if q is None else q, step)]
            out = cls(d, F, velocity_scale, step, implicit)
        return out

    def choose(self, model: pin.Model, q, dt: float) -> list[Treatment]:
        """The treatment of each velocity coordinate at the step ``dt`` (module docstring): the joints with friction in
        the order of their rates K_i(0) (M^-1)_ii join the explicit set while dt x the largest eigenvalue of
        (M^-1)_EE K_E stays <= :data:`STIFF`; the rest are implicit (coordinates without friction: explicit)."""
        dt = as_real(dt, "dt", positive=True)
        Minv = np.linalg.inv(self._inertia(model, q))
        K = self.damping + self.friction / self.velocity_scale
        explicit: list[int] = []
        for j in sorted(self._idx.tolist(), key=lambda i: K[i] * Minv[i, i]):
            trial = [*explicit, j]
            if dt * float(np.max(np.linalg.eigvals(Minv[np.ix_(trial, trial)] * K[trial]).real)) > STIFF:
                break
            explicit = trial
        out = [Treatment.EXPLICIT] * self.damping.shape[0]
        for j in set(self._idx.tolist()) - set(explicit):
            out[j] = Treatment.IMPLICIT
        return out

    @property
    def treatments(self) -> list[Treatment]:
        """The treatment of each velocity coordinate in :meth:`apply` (nv,)."""
        out = [Treatment.EXPLICIT] * self.damping.shape[0]
        for j in self._imp.tolist():
            out[j] = Treatment.IMPLICIT
        return out

    def add_generalized_force(self, v, out: np.ndarray) -> np.ndarray:
        """``out += tau_f(v)`` in place (``v``: Pinocchio's generalised velocity, ``out``: a generalised force); returns ``out``."""
        i = self._idx
        vi = np.asarray(v)[i]
        out[i] -= self.damping[i] * vi + self.friction[i] * np.tanh(vi / self.velocity_scale)
        return out

    def stiffness(self, v) -> np.ndarray:
        """K(v) = -dtau_f/dv (nv,), the diagonal of the friction's Jacobian [N m s/rad or N s/m]."""
        x = as_vector(v, self.damping.shape[0], "v") / self.velocity_scale
        return self.damping + self.friction / np.cosh(np.clip(x, -350.0, 350.0)) ** 2 / self.velocity_scale

    def start(self, v) -> None:
        """Set v0, the velocity at the start of the integration step (the implicit joints' (1) is taken from there)."""
        self._v0 = np.array(v, dtype=float)[self._imp]

    def apply(self, v, out: np.ndarray) -> np.ndarray:
        """The explicit joints' friction at one stage of velocity ``v``: ``out += tau_f,E(v)``; returns ``out`` (the implicit
        joints' comes after the forward dynamics, from :meth:`solve`).  ``v`` and ``out`` may be batches (n, nv): the
        last axis is the velocity coordinate (:mod:`qprr.sim.batch`)."""
        i = self._exp
        vi = np.asarray(v)[..., i]
        out[..., i] -= self.damping[i] * vi + self.friction[i] * np.tanh(vi / self.velocity_scale)
        return out

    def solve(self, model: pin.Model, data: pin.Data, q, v, a: np.ndarray) -> np.ndarray:
        """Equation (1) of the module docstring at a stage (q, v): ``a`` (a0, the forward dynamics without the implicit
        joints' friction) becomes a0 + (M^-1)_{:,S} W^-1 ((x - v0) / dt - a0_S), x the implicit joints' end-of-step
        velocity (2); returns ``a``."""
        i = self._imp
        if not i.size:
            return a
        Minv = pin.computeMinverse(model, data, np.asarray(q, dtype=float))
        Minv = np.triu(Minv) + np.triu(Minv, 1).T
        B = Minv[:, i]
        v0 = np.asarray(v, dtype=float)[i] if self._v0 is None else self._v0
        b, Qinv = self._exponential(B[i], v0, a[i])
        x = self._end_velocity(b, Qinv, np.asarray(v, dtype=float)[i])
        a += B @ np.linalg.solve(B[i], (x - v0) / self.step - a[i])
        return a

    def _exponential(self, W: np.ndarray, v0: np.ndarray, a0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(b, Q^-1) of (2): b = exp(-dt W D) v0 + dt phi1(-dt W D) a0, the exact end velocity under the damping and the
        constant a0, and Q = phi1(-dt W D) W, symmetric positive definite, through W = L L^T and L^T D L = U diag(lam) U^T:
        f(W D) = L U f(lam) U^T L^-1 (Hochbruck & Ostermann, Acta Numerica 19, 2010, Sec. 2.1)."""
        L = np.linalg.cholesky(W)
        lam, U = np.linalg.eigh(L.T @ (self.damping[self._imp, None] * L))  # the rates of the damping: W D = L U lam (L U)^-1
        z = self.step * np.maximum(lam, 0.0)  # dt lam >= 0 (L^T D L is positive semidefinite; round-off)
        phi = np.ones_like(z)  # phi1(-z) = (1 - exp(-z)) / z, 1 at z = 0
        np.divide(-np.expm1(-z), z, out=phi, where=z > 0.0)
        LU = L @ U
        G = np.linalg.inv(LU)  # U^T L^-1
        b = LU @ (np.exp(-z) * (G @ v0) + self.step * phi * (G @ a0))
        return b, G.T @ (G / phi[:, None])  # Q^-1 = (L U)^-T phi1(-dt lam)^-1 (L U)^-1

    def _end_velocity(self, b: np.ndarray, Qinv: np.ndarray, x: np.ndarray) -> np.ndarray:
        """argmin (x - b)^T Q^-1 (x - b) / 2 + dt Psi(x) (module docstring, (3)) by Newton's method with backtracking (Boyd &
        Vandenberghe, Convex Optimization, Algorithm 9.5), from ``x``, until the Newton decrement is at the objective's
        round-off (or the step below 1e-12 (1 + |x|) [rad/s])."""
        h, vs, F = self.step, self.velocity_scale, self.friction[self._imp]
        Qinv = 0.5 * (Qinv + Qinv.T)

        def objective(y: np.ndarray) -> float:
            e, s = y - b, np.abs(y) / vs
            return 0.5 * float(e @ Qinv @ e) + h * float(np.sum(F * vs * (s + np.log1p(np.exp(-2.0 * s)))))

        for _ in range(100):
            grad = Qinv @ (x - b) + h * F * np.tanh(x / vs)
            hess = Qinv + np.diag(h * F / np.cosh(np.clip(x / vs, -350.0, 350.0)) ** 2 / vs)
            dx = -np.linalg.solve(hess, grad)
            f0, slope, s = objective(x), float(grad @ dx), 1.0
            if -slope <= 1e-15 * abs(f0) or np.max(np.abs(dx)) <= 1e-12 * (1.0 + np.max(np.abs(x))):
                return x + dx  # the decrease left (the Newton decrement) is at the objective's round-off
            while objective(x + s * dx) > f0 + 1e-4 * s * slope and s > 1e-12:
                s *= 0.5
            x = x + s * dx
        raise ArithmeticError(f"the implicit joint friction did not converge (b = {b.tolist()}, x = {x.tolist()})")

    def generalized_force(self, v) -> np.ndarray:
        """tau_f(v) (nv,) [N m or N]."""
        return self.add_generalized_force(as_vector(v, self.damping.shape[0], "v"), np.zeros(self.damping.shape[0]))

    def viscous_xi(self) -> np.ndarray:
        """The viscous coefficients in thesis coordinates (6 + n_arm,): the diagonal of F_v of Thesis (5.36) (zero on the base;
        the arm's xi_dot entries are its joint rates), the ``coefficients`` of :class:`qprr.sim.wind.ViscousFriction`."""
        return self.damping.copy()

    def _inertia(self, model: pin.Model, q) -> np.ndarray:
        """M(q) of ``model`` (checked: the model this friction belongs to, ``q`` a configuration of it with a unit
        quaternion)."""
        if not isinstance(model, pin.Model) or model.nv != self.damping.shape[0]:
            raise InputError(f"model must be the pinocchio.Model of this friction ({self.damping.shape[0]} velocity coordinates), got {model!r}")
        q = as_vector(q, model.nq, "q")
        ch.unit_quaternion(q[3:7], "q[3:7]")  # the free flyer's orientation (its coordinates carry no friction: from_model)
        M = pin.crba(model, model.createData(), q)
        return np.triu(M) + np.triu(M, 1).T

    def max_rate(self, model: pin.Model, q) -> float:
        """Largest eigenvalue [1/s] of M(q)^-1 K with K = diag(d_i + F_i / v_s), the friction's Jacobian at v = 0."""
        K = np.diag(self.damping + self.friction / self.velocity_scale)
        return float(np.max(np.linalg.eigvals(np.linalg.solve(self._inertia(model, q), K)).real))

    def stable_step(self, model: pin.Model, q, integrator: str = "midpoint") -> float:
        """The largest step [s] for which ``integrator`` is stable on the friction alone at ``q``: STABILITY / max_rate."""
        if integrator not in STABILITY:
            raise UnknownNameError("integrator", integrator, tuple(STABILITY))
        rate = self.max_rate(model, q)
        return math.inf if rate <= 0.0 else STABILITY[integrator] / rate


__all__ = ["STABILITY", "STIFF", "VELOCITY_SCALE", "JointFriction", "Treatment"]
