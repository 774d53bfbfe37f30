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
dt * rate below about 2 (midpoint) or 2.8 (rk4) (:meth:`JointFriction.stable_step`).  With ``step`` = h > 0 the plant
takes the friction linearly implicitly, as MuJoCo does for joint damping: the acceleration is

    a = (M + h K(v))^-1 (tau + tau_f(v) - h(q, v))                        (one Rosenbrock-Euler step on tau_f)

(:meth:`JointFriction.apply`: K(v) h is written into the plant's ``model.armature``, a model copy the simulator
owns).  This is stable at any dt (the friction's rate becomes K/(M + h K) < 1/h) and converges to the exact
dynamics at first order in h where the friction acts (and at the integrator's order where it does not); with h = 0
the force is explicit and the integrator keeps its order while dt * max_rate stays inside its stability interval.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from .errors import InputError

VELOCITY_SCALE = 1e-2
"""v_s [rad/s or m/s]: the velocity over which the Coulomb term of :class:`JointFriction` goes from 0 to ~F (tanh)."""

STABILITY = {"euler": 2.0, "midpoint": 2.0, "rk4": 2.785}
"""|lambda dt| bounds of the explicit integrators on a real negative eigenvalue lambda (the stability intervals of
forward Euler and explicit midpoint, [-2, 0], and of RK4, [-2.785, 0])."""


class JointFriction:
    """The joint friction of a Pinocchio model (see the module docstring); build with :meth:`from_model`."""

    def __init__(self, damping, friction, velocity_scale: float = VELOCITY_SCALE, step: float = 0.0, armature=None) -> None:
        d = np.array(damping, dtype=float).ravel()
        F = np.array(friction, dtype=float).ravel()
        if d.shape != F.shape or not (np.all(np.isfinite(d)) and np.all(np.isfinite(F))) or np.any(d < 0.0) or np.any(F < 0.0):
            raise InputError(f"joint damping and friction must be finite values >= 0 of one size, got {d.tolist()} and {F.tolist()}")
        if not (isinstance(velocity_scale, (int, float)) and math.isfinite(velocity_scale) and velocity_scale > 0.0):
            raise InputError(f"velocity_scale (v_s of the Coulomb term) must be a number > 0 [rad/s or m/s], got {velocity_scale!r}")
        if not (isinstance(step, (int, float)) and math.isfinite(step) and step >= 0.0):
            raise InputError(f"step (h of the implicit friction) must be a number >= 0 [s], got {step!r}")
        self.damping, self.friction, self.velocity_scale, self.step = d, F, float(velocity_scale), float(step)
        self.armature = np.zeros(d.shape[0]) if armature is None else np.array(armature, dtype=float).ravel()
        self._idx = np.flatnonzero((d > 0.0) | (F > 0.0))

    @classmethod
    def from_model(cls, model: pin.Model, step: float = 0.0, velocity_scale: float = VELOCITY_SCALE) -> JointFriction | None:
        """The friction of ``model`` (``model.damping``, ``model.friction``), None when every entry is zero; ``step``: h of
        the implicit treatment (0: explicit); the model's own ``armature`` is kept as the base of :meth:`apply`."""
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
        return cls(d, F, velocity_scale, step, np.array(model.armature))

    def add_generalized_force(self, v, out: np.ndarray) -> np.ndarray:
        """``out += tau_f(v)`` in place (``v``: Pinocchio's generalised velocity, ``out``: a generalised force); returns ``out``."""
        i = self._idx
        vi = np.asarray(v)[i]
        out[i] -= self.damping[i] * vi + self.friction[i] * np.tanh(vi / self.velocity_scale)
        return out

    def stiffness(self, v) -> np.ndarray:
        """K(v) = -dtau_f/dv (nv,), the diagonal of the friction's Jacobian [N m s/rad or N s/m]."""
        x = np.asarray(v, dtype=float) / self.velocity_scale
        return self.damping + self.friction / np.cosh(np.clip(x, -350.0, 350.0)) ** 2 / self.velocity_scale

    def apply(self, model: pin.Model, v, out: np.ndarray) -> np.ndarray:
        """The plant's friction at one stage: ``out += tau_f(v)`` and, with ``step`` h > 0, ``model.armature = armature +
        h K(v)`` (the linearly implicit form of the module docstring; ``model`` must be the simulator's own copy)."""
        if self.step > 0.0:
            model.armature = self.armature + self.step * self.stiffness(v)
        return self.add_generalized_force(v, out)

    def generalized_force(self, v) -> np.ndarray:
        """tau_f(v) (nv,) [N m or N]."""
        return self.add_generalized_force(v, np.zeros(self.damping.shape[0]))

    def viscous_xi(self) -> np.ndarray:
        """The viscous coefficients in thesis coordinates (6 + n_arm,): the diagonal of F_v of Thesis (5.36) (zero on the base;
        the arm's xi_dot entries are its joint rates), the ``coefficients`` of :class:`qprr.sim.wind.ViscousFriction`."""
        return self.damping.copy()

    def max_rate(self, model: pin.Model, q) -> float:
        """Largest eigenvalue [1/s] of M(q)^-1 K with K = diag(d_i + F_i / v_s), the friction's Jacobian at v = 0."""
        M = pin.crba(model, model.createData(), np.asarray(q, dtype=float))
        M = np.triu(M) + np.triu(M, 1).T
        K = np.diag(self.damping + self.friction / self.velocity_scale)
        return float(np.max(np.linalg.eigvals(np.linalg.solve(M, K)).real))

    def stable_step(self, model: pin.Model, q, integrator: str = "midpoint") -> float:
        """The largest step [s] for which ``integrator`` is stable on the friction alone at ``q``: STABILITY / max_rate."""
        if integrator not in STABILITY:
            from .errors import UnknownNameError

            raise UnknownNameError("integrator", integrator, tuple(STABILITY))
        rate = self.max_rate(model, q)
        return math.inf if rate <= 0.0 else STABILITY[integrator] / rate


__all__ = ["STABILITY", "VELOCITY_SCALE", "JointFriction"]
