"""Explicit one-step integrators on the configuration Lie group of a Pinocchio model.

The state is (q, v[, z]): q on the configuration manifold of ``model`` (SE(3) x R^n for a
free flyer with revolute/prismatic joints: position and unit quaternion, then the joint
values), v in its tangent space (Pinocchio's convention: the free flyer's velocity is the
body twist in LOCAL axes), and an optional Euclidean vector z of extra states integrated
together with the robot (the state of an environment, e.g. a pushed object).  The motion is

    dq/dt = v  (q(t + s) = q(t) (+) s v to first order, (+) = ``pin.integrate``),
    dv/dt = a = f(t, q, v),          without extra state,
    (dv/dt, dz/dt) = f(t, q, v, z),  with extra state (f returns the pair (a, z_dot)).

Every function takes one step of length ``dt`` from t and returns (q+, v+, z+) (z+ is None
without extra state); ``first`` is f at (t, q, v[, z]) when the caller has it already (the
simulator computes it to log the state; it saves one evaluation).  :func:`make_stepper`
gives the same step as a closure for a fixed dt (buffers preallocated: the simulator's
loop).  The right-hand side is evaluated at every stage with that stage's (t, q, v, z):
anything that depends on the state (contact forces, Jacobians, payload inertia) must be
computed inside ``f``.

* :func:`semi_implicit_euler` ("euler"): v+ = v + dt a(t, q, v), q+ = q (+) dt v+,
  z+ = z + dt z_dot.  One evaluation, first order.
* :func:`explicit_midpoint` ("midpoint"): a1 = f(t, q, v), v_h = v + dt/2 a1,
  q_h = q (+) dt/2 v, a2 = f(t + dt/2, q_h, v_h), q+ = q (+) dt v_h, v+ = v + dt a2.  Two
  evaluations, second order.  The midpoint chart velocity differs from v_h by
  -1/2 [dt/2 v, v_h] = O(dt^2) (the inverse of the right Jacobian of exp), a local error of
  O(dt^3): the uncorrected Lie-group midpoint keeps order 2.
* :func:`rk4` ("rk4"): classical Runge-Kutta 4 in the tangent chart at q_k (the
  Runge-Kutta-Munthe-Kaas construction with the exact inverse of the exponential's
  differential).  Writing q(t_k + s) = q_k (+) delta(s), delta obeys the Euclidean ODE
  d delta/ds = J(delta)^-1 v with J(delta) = d(q_k (+) delta)/d delta (``pin.dIntegrate``
  w.r.t. ARG1; for the free flyer the right Jacobian Jexp6(delta), identity for the arm
  joints).  J(delta)^-1 v is computed as ``pin.dDifference(model, q_k, q_k (+) delta, ARG1) v``,
  the differential of the chart delta = q_k (-) q.  Classical RK4 on (delta, v, z) with
  stages at delta = 0, dt/2 d1, dt/2 d2, dt d3 gives q+ = q_k (+) dt/6 (d1 + 2 d2 + 2 d3 + d4):
  fourth order on the group.  Summing the stage velocities v_i without the J^-1 map (as a
  plain RK4 on v would) leaves local errors of order dt^3 [v, a] (J(delta)^-1 v =
  v - 1/2 [delta, v] + ...): second order for the base.

Stages never straddle a discontinuity if the caller only changes inputs between steps (the
simulator changes held inputs, payloads and noise samples at control ticks, which are step
boundaries).

The registry :data:`INTEGRATORS` (default ``"midpoint"``) holds the three as :class:`Integrator` entries (the
stepper factory, the order, a description); :data:`STEPPERS` and :data:`ORDERS` are views of it, and
:class:`qprr.sim.SimConfig`, the scenarios' ``integrator`` option and ``qprr simulate --integrator`` accept its names.
A plug-in adds a scheme with ``INTEGRATORS.register(name, Integrator(factory, order, description))``
(docs/extending.md): ``factory(model, dt)`` returns ``step(f, t, q, v, z=None, first=None) -> (q+, v+, z+)``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..registry import Registry

_integrate = pin.integrate
_ddifference = pin.dDifference
_ARG1 = pin.ArgumentPosition.ARG1


def make_stepper(method: str, model: pin.Model, dt: float) -> Callable:
    """One-step function ``step(f, t, q, v, z=None, first=None) -> (q+, v+, z+)`` of ``method`` for the step ``dt``.

    The step sizes are kept as arrays and temporaries in buffers: the form the simulator's loop calls (one
    implementation of each scheme; :func:`semi_implicit_euler`, :func:`explicit_midpoint`, :func:`rk4` build
    one per call).  ``f`` must not keep references to the arrays it is given (buffers are reused).
    """
    return INTEGRATORS[method].factory(model, float(dt))  # an unknown name: UnknownNameError listing the registered ones


def _euler(model: pin.Model, dt: float) -> Callable:
    dt_v = np.full(model.nv, dt)
    buf = np.empty(model.nv)
    mul, integrate = np.multiply, _integrate

    def step(f, t, q, v, z=None, first=None):
        if z is None:
            a = f(t, q, v) if first is None else first
            v = v + mul(dt_v, a, buf)
            return integrate(model, q, mul(dt_v, v, buf)), v, None
        a, zd = f(t, q, v, z) if first is None else first
        v = v + mul(dt_v, a, buf)
        return integrate(model, q, mul(dt_v, v, buf)), v, z + dt * zd

    return step


def _midpoint(model: pin.Model, dt: float) -> Callable:
    h = 0.5 * dt
    half_v, dt_v = np.full(model.nv, h), np.full(model.nv, dt)
    buf, vh = np.empty(model.nv), np.empty(model.nv)
    mul, add, integrate = np.multiply, np.add, _integrate

    def step(f, t, q, v, z=None, first=None):
        if z is None:
            a1 = f(t, q, v) if first is None else first
            add(v, mul(half_v, a1, buf), vh)
            a2 = f(t + h, integrate(model, q, mul(half_v, v, buf)), vh)
            return integrate(model, q, mul(dt_v, vh, buf)), v + mul(dt_v, a2, buf), None
        a1, zd1 = f(t, q, v, z) if first is None else first
        add(v, mul(half_v, a1, buf), vh)
        a2, zd2 = f(t + h, integrate(model, q, mul(half_v, v, buf)), vh, z + h * zd1)
        return integrate(model, q, mul(dt_v, vh, buf)), v + mul(dt_v, a2, buf), z + dt * zd2

    return step


def _rk4(model: pin.Model, dt: float) -> Callable:
    h, s = 0.5 * dt, dt / 6.0
    integrate, ddiff = _integrate, _ddifference

    def step(f, t, q, v, z=None, first=None):
        has_z = z is not None
        if has_z:
            a1, z1 = f(t, q, v, z) if first is None else first
        else:
            a1 = f(t, q, v) if first is None else first
        d1 = v  # J(0) = I
        v2 = v + h * a1
        q2 = integrate(model, q, h * d1)
        d2 = ddiff(model, q, q2, _ARG1) @ v2
        if has_z:
            a2, z2 = f(t + h, q2, v2, z + h * z1)
        else:
            a2 = f(t + h, q2, v2)
        v3 = v + h * a2
        q3 = integrate(model, q, h * d2)
        d3 = ddiff(model, q, q3, _ARG1) @ v3
        if has_z:
            a3, z3 = f(t + h, q3, v3, z + h * z2)
        else:
            a3 = f(t + h, q3, v3)
        v4 = v + dt * a3
        q4 = integrate(model, q, dt * d3)
        d4 = ddiff(model, q, q4, _ARG1) @ v4
        if has_z:
            a4, z4 = f(t + dt, q4, v4, z + dt * z3)
        else:
            a4 = f(t + dt, q4, v4)
        q_next = integrate(model, q, s * (d1 + 2.0 * (d2 + d3) + d4))
        v_next = v + s * (a1 + 2.0 * (a2 + a3) + a4)
        z_next = z + s * (z1 + 2.0 * (z2 + z3) + z4) if has_z else None
        return q_next, v_next, z_next

    return step


@dataclass(frozen=True)
class Integrator:
    """A registered one-step scheme: ``factory(model, dt) -> step`` with ``step(f, t, q, v, z=None, first=None) ->
    (q+, v+, z+)`` (the module docstring's contract: q on the model's configuration group, ``f`` evaluated at every
    stage, ``first`` the value of f at (t, q, v[, z]) when the caller has it), its ``order`` of accuracy on smooth
    problems (global error O(dt^order); the convergence tests measure it) and a one-line ``description``."""

    factory: Callable[[pin.Model, float], Callable]
    order: int
    description: str = ""

    def __post_init__(self) -> None:
        if not callable(self.factory):
            raise InputError(f"Integrator.factory must be a function (model, dt) -> step, got {self.factory!r}")
        if isinstance(self.order, bool) or not isinstance(self.order, int) or self.order < 1:
            raise InputError(f"Integrator.order must be an integer >= 1 (global error O(dt^order)), got {self.order!r}")

    def step(self, model: pin.Model, f: Callable, t: float, q, v, dt: float, z=None, first=None):
        """One step of length ``dt`` (a new stepper per call; :func:`make_stepper` keeps one for a fixed dt)."""
        return self.factory(model, dt)(f, t, q, v, z, first)


def _check(name: str, entry: object) -> None:
    if not isinstance(entry, Integrator):
        raise InputError(f"integrator {name!r}: register a qprr.sim.integrators.Integrator(factory, order, description), got {type(entry).__name__}")


DEFAULT_INTEGRATOR = "midpoint"
"""The scheme of :class:`qprr.sim.SimConfig` and of every scenario unless one is named: second order, two evaluations."""
INTEGRATORS: Registry[Integrator] = Registry("integrator", default=DEFAULT_INTEGRATOR, check=_check)
"""Integrator name -> :class:`Integrator`: ``midpoint``, ``rk4``, ``euler`` here; plug-ins add theirs."""
INTEGRATORS.register("midpoint", Integrator(_midpoint, 2, "explicit midpoint, 2nd order, two evaluations"))
INTEGRATORS.register("rk4", Integrator(_rk4, 4, "Runge-Kutta 4 in the tangent chart, 4th order, four evaluations"))
INTEGRATORS.register("euler", Integrator(_euler, 1, "semi-implicit Euler, 1st order, one evaluation"))


def semi_implicit_euler(
    model: pin.Model, f: Callable, t: float, q: np.ndarray, v: np.ndarray, dt: float, z: np.ndarray | None = None, first=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """One semi-implicit (symplectic) Euler step on the Lie group: v+ = v + dt a, q+ = q (+) dt v+, z+ = z + dt z_dot (first order)."""
    return _euler(model, dt)(f, t, q, v, z, first)


def explicit_midpoint(
    model: pin.Model, f: Callable, t: float, q: np.ndarray, v: np.ndarray, dt: float, z: np.ndarray | None = None, first=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """One explicit-midpoint step on the Lie group (second order; see the module docstring)."""
    return _midpoint(model, dt)(f, t, q, v, z, first)


def rk4(
    model: pin.Model, f: Callable, t: float, q: np.ndarray, v: np.ndarray, dt: float, z: np.ndarray | None = None, first=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """One classical Runge-Kutta 4 step in the tangent chart at q (fourth order on the group; see the module docstring)."""
    return _rk4(model, dt)(f, t, q, v, z, first)


STEPPERS = INTEGRATORS.derived(lambda entry: entry.step)
"""Integrator name -> one-step function ``step(model, f, t, q, v, dt, z=None, first=None) -> (q, v, z)`` (a view of
:data:`INTEGRATORS`)."""

ORDERS = INTEGRATORS.derived(lambda entry: entry.order)
"""Integrator name -> order of accuracy on smooth problems (global error O(dt^order)) (a view of :data:`INTEGRATORS`)."""
