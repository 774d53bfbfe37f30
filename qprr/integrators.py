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
simulator computes it to log the state; it saves one evaluation).  The right-hand side is
evaluated at every stage with that stage's (t, q, v, z): anything that depends on the state
(contact forces, Jacobians, payload inertia) must be computed inside ``f``.

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
  plain RK4 on v would) leaves a local error (dt^3/8) [v, a]: second order for the base.

Stages never straddle a discontinuity if the caller only changes inputs between steps (the
simulator changes held inputs, payloads and noise samples at control ticks, which are step
boundaries).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

_integrate = pin.integrate
_ddifference = pin.dDifference
_ARG1 = pin.ArgumentPosition.ARG1


def semi_implicit_euler(model: pin.Model, f: Callable, t: float, q: np.ndarray, v: np.ndarray, dt: float,
                        z: np.ndarray | None = None, first=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """One semi-implicit (symplectic) Euler step on the Lie group: v+ = v + dt a, q+ = q (+) dt v+, z+ = z + dt z_dot (first order)."""
    if z is None:
        a = f(t, q, v) if first is None else first
        v = v + dt * a
        return _integrate(model, q, dt * v), v, None
    a, zd = f(t, q, v, z) if first is None else first
    v = v + dt * a
    return _integrate(model, q, dt * v), v, z + dt * zd


def explicit_midpoint(model: pin.Model, f: Callable, t: float, q: np.ndarray, v: np.ndarray, dt: float,
                      z: np.ndarray | None = None, first=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """One explicit-midpoint step on the Lie group (second order; see the module docstring)."""
    h = 0.5 * dt
    if z is None:
        a1 = f(t, q, v) if first is None else first
        vh = v + h * a1
        a2 = f(t + h, _integrate(model, q, h * v), vh)
        return _integrate(model, q, dt * vh), v + dt * a2, None
    a1, zd1 = f(t, q, v, z) if first is None else first
    vh = v + h * a1
    a2, zd2 = f(t + h, _integrate(model, q, h * v), vh, z + h * zd1)
    return _integrate(model, q, dt * vh), v + dt * a2, z + dt * zd2


def rk4(model: pin.Model, f: Callable, t: float, q: np.ndarray, v: np.ndarray, dt: float,
        z: np.ndarray | None = None, first=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """One classical Runge-Kutta 4 step in the tangent chart at q (fourth order on the group; see the module docstring)."""
    h = 0.5 * dt
    has_z = z is not None
    if has_z:
        a1, z1 = f(t, q, v, z) if first is None else first
    else:
        a1 = f(t, q, v) if first is None else first
    d1 = v  # J(0) = I
    v2 = v + h * a1
    q2 = _integrate(model, q, h * d1)
    d2 = _ddifference(model, q, q2, _ARG1) @ v2
    if has_z:
        a2, z2 = f(t + h, q2, v2, z + h * z1)
    else:
        a2 = f(t + h, q2, v2)
    v3 = v + h * a2
    q3 = _integrate(model, q, h * d2)
    d3 = _ddifference(model, q, q3, _ARG1) @ v3
    if has_z:
        a3, z3 = f(t + h, q3, v3, z + h * z2)
    else:
        a3 = f(t + h, q3, v3)
    v4 = v + dt * a3
    q4 = _integrate(model, q, dt * d3)
    d4 = _ddifference(model, q, q4, _ARG1) @ v4
    if has_z:
        a4, z4 = f(t + dt, q4, v4, z + dt * z3)
    else:
        a4 = f(t + dt, q4, v4)
    s = dt / 6.0
    q_next = _integrate(model, q, s * (d1 + 2.0 * (d2 + d3) + d4))
    v_next = v + s * (a1 + 2.0 * (a2 + a3) + a4)
    z_next = z + s * (z1 + 2.0 * (z2 + z3) + z4) if has_z else None
    return q_next, v_next, z_next


STEPPERS: dict[str, Callable] = {"euler": semi_implicit_euler, "midpoint": explicit_midpoint, "rk4": rk4}
"""Integrator name -> one-step function ``step(model, f, t, q, v, dt, z=None, first=None) -> (q, v, z)``."""

ORDERS: dict[str, int] = {"euler": 1, "midpoint": 2, "rk4": 4}
"""Integrator name -> order of accuracy on smooth problems (global error O(dt^order))."""


def integrate_fixed(model: pin.Model, f: Callable, method: str, t0: float, q0, v0, dt: float, n: int,
                    z0=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """``n`` steps of ``method`` (a key of :data:`STEPPERS`) from (t0, q0, v0[, z0]); returns the final (q, v, z)."""
    if method not in STEPPERS:
        from .errors import UnknownNameError

        raise UnknownNameError("integrator", method, tuple(STEPPERS))
    step = STEPPERS[method]
    q, v = np.array(q0, dtype=float), np.array(v0, dtype=float)
    z = None if z0 is None else np.array(z0, dtype=float)
    for k in range(n):
        q, v, z = step(model, f, t0 + k * dt, q, v, dt, z)
    return q, v, z
