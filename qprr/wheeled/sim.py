"""Simulation of kinematic models, exact on the non-holonomic constraints.

Inputs are held constant over each step (zero-order hold, as a digital controller applies
them).  For a constant input the solution of q_dot = B(q) u is computed in closed form by the
model's ``flow``: a circular arc (the SE(2) exponential of a constant chassis twist) when the
steering does not move, and, while it moves, the exact steering angle psi(t) and heading
theta(t) with the position as a quadrature of the exact velocity (Gauss-Legendre, converged
to round-off).  The trajectory is therefore the robot's true motion under the applied input:
its constraint residual A^T(q(t)) q_dot(t) is zero up to round-off at every instant, not
only at the samples.  A general-purpose integrator (Euler, RK4) instead follows chords that
no wheel can roll along; :func:`rk4_step` is kept to measure that slip.

``simulate_wheeled(model, q0, inputs, duration, dt)``: ``inputs`` is a constant input vector, an
array with one row per step, a callable ``u = f(t, q)`` or a :class:`~qprr.wheeled.control.FeedbackLaw`
(``control(t, q, dt)``: controllers with an internal state, :mod:`qprr.wheeled.control`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..errors import InputError, KinematicSingularityError, NonFiniteError
from ..progress import Progress
from .control import FeedbackLaw
from .kinematics import KinematicModel, check_duration

# ------------------------------------------------------------------------- exact flows
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(8)
MAX_ANGLE_PER_PIECE = 0.5
"""Largest heading/steering change [rad] over one Gauss-Legendre piece (8 nodes): the
quadrature error is then ~0.5^16/16! relative, far below round-off."""


def sinc(x: float) -> float:
    """sin(x)/x, 1 at 0."""
    return math.sin(x) / x if abs(x) > 1e-8 else 1.0 - x * x / 6.0


def se2_flow(pose, twist_R, h: float) -> np.ndarray:
    """Exact motion over h of a chassis with a constant body twist xi_R = (v_x, v_y, omega).

    The SE(2) exponential: theta(h) = theta + omega h and the displacement, in the robot
    frame at the start, [[sin a, -(1 - cos a)], [1 - cos a, sin a]] [v_x, v_y] / omega with
    a = omega h (written with sinc, regular at omega = 0).  With v_y = 0 this is the
    unicycle's arc (Lecture: unicycle model, v and omega constant).
    """
    x, y, th = (float(v) for v in pose)
    vx, vy, w = (float(v) for v in twist_R)
    a = w * h
    s1 = h * sinc(a)  # sin(a)/w
    c1 = h * math.sin(a / 2) * sinc(a / 2)  # (1 - cos a)/w
    dx_R = s1 * vx - c1 * vy
    dy_R = c1 * vx + s1 * vy
    c, s = math.cos(th), math.sin(th)
    return np.array([x + c * dx_R - s * dy_R, y + s * dx_R + c * dy_R, th + a])


def heading_quadrature(x0: float, y0: float, speed, heading, h: float, rate_bound: float) -> tuple[float, float]:
    """(x(h), y(h)) = (x0, y0) + int_0^h speed(t) (cos, sin)(heading(t)) dt by composite Gauss-Legendre.

    ``speed`` and ``heading`` are exact closed forms (vectorised in t); ``rate_bound`` bounds
    |d heading/dt| + |d steering/dt| over [0, h] and sets the number of pieces so that no
    piece turns by more than :data:`MAX_ANGLE_PER_PIECE`.
    """
    n = max(1, math.ceil(h * rate_bound / MAX_ANGLE_PER_PIECE))
    if n > 200_000:
        raise KinematicSingularityError(f"the heading turns by {h * rate_bound:.3g} rad in {h:g} s: too close to a singularity")
    edges = np.linspace(0.0, h, n + 1)
    half = 0.5 * (edges[1:] - edges[:-1])
    mid = 0.5 * (edges[1:] + edges[:-1])
    t = (mid[:, None] + half[:, None] * _GL_NODES[None, :]).ravel()
    w = (half[:, None] * _GL_WEIGHTS[None, :]).ravel()
    v = speed(t)
    th = heading(t)
    return x0 + float(np.dot(w, v * np.cos(th))), y0 + float(np.dot(w, v * np.sin(th)))


def rk4_step(model: KinematicModel, q, u, h: float) -> np.ndarray:
    """One classical Runge-Kutta step of q_dot = B(q) u (for comparison: it does not keep the constraints)."""
    k1 = model.velocity(q, u)
    k2 = model.velocity(q + 0.5 * h * k1, u)
    k3 = model.velocity(q + 0.5 * h * k2, u)
    k4 = model.velocity(q + h * k3, u)
    return q + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def euler_step(model: KinematicModel, q, u, h: float) -> np.ndarray:
    """One explicit Euler step of q_dot = B(q) u (for comparison)."""
    return q + h * model.velocity(q, u)


def chord_slip(q0, q1) -> float:
    """Lateral slip [m] of a step of the reference point (x, y) with headings theta0 -> theta1.

    A rolling reference point (the unicycle's axle centre, the tricycle's rear-axle centre)
    moving with its steering held follows a circular arc, whose chord is along the mean
    heading: -dx sin(theta_mid) + dy cos(theta_mid) = 0 exactly.  This returns that
    component: 0 for an exact arc, the sideways skid of an approximate step.
    """
    th = 0.5 * (q0[2] + q1[2])
    return float(-(q1[0] - q0[0]) * math.sin(th) + (q1[1] - q0[1]) * math.cos(th))


# ------------------------------------------------------------------------- simulation
class SimStatus(str, Enum):
    OK = "ok"
    SINGULAR = "singular"


@dataclass
class WheeledSimResult:
    """A simulated run.  ``t`` (N+1,) [s]; ``q`` (N+1, n); ``u`` (N, n_inputs), the input held on
    [t_k, t_k+1); ``residual`` (N,) = |A^T(q_k) B(q_k) u_k| (m/s or rad/s: the constraint
    violation of the applied velocity); ``wheel_speeds`` {name: (N,)} [rad/s]; ``status``
    "ok" or "singular" (the model's B is undefined at the last state) with ``reason``."""

    model: str
    coordinates: tuple[str, ...]
    inputs: tuple[str, ...]
    t: np.ndarray
    q: np.ndarray
    u: np.ndarray
    residual: np.ndarray
    wheel_speeds: dict[str, np.ndarray]
    dt: float
    status: SimStatus
    reason: str
    wall_time: float
    extras: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.t) - 1

    def final(self) -> np.ndarray:
        return self.q[-1].copy()


def _input_source(model: KinematicModel, inputs, n_steps: int):
    if isinstance(inputs, FeedbackLaw):
        inputs.reset()
        return lambda k, t, q, dt: inputs.control(t, q, dt)
    if callable(inputs):
        return lambda k, t, q, dt: inputs(t, q)
    arr = np.asarray(inputs, dtype=float)
    if arr.ndim == 1:
        u = model.check_u(arr)
        return lambda k, t, q, dt: u
    if arr.ndim == 2 and arr.shape == (n_steps, model.n_inputs):
        if not np.all(np.isfinite(arr)):
            raise NonFiniteError("inputs must be finite")
        return lambda k, t, q, dt: arr[k]
    raise InputError(
        f"inputs must be a vector of {model.n_inputs} inputs {list(model.inputs)}, an array of shape "
        f"({n_steps}, {model.n_inputs}), a callable f(t, q) or a controller; got an array of shape {arr.shape}"
    )


def simulate_wheeled(model: KinematicModel, q0, inputs, duration: float, dt: float = 0.01, *, progress: bool = False) -> WheeledSimResult:
    """Simulate ``model`` from ``q0`` for ``duration`` seconds with steps of ``dt`` (zero-order hold).

    Each step is the model's exact flow (see the module docstring).  When the motion
    reaches a singularity of the model (e.g. the rear-driven tricycle driven with its
    steering at psi = pi/2) the run stops before that step with status "singular" and the
    reason; the samples up to that instant are returned.  ``progress``: show the steps done
    (:class:`qprr.progress.Progress` on stderr: a bar on a terminal, lines in a log).
    """
    if not isinstance(model, KinematicModel):
        raise InputError(f"model must be a KinematicModel, got {type(model).__name__}")
    duration = check_duration(duration)
    dt = check_duration(dt)
    if dt <= 0.0:
        raise InputError(f"dt must be > 0 s, got {dt!r}")
    q = model.check_q(q0).copy()
    n_steps = int(round(duration / dt))
    if abs(n_steps * dt - duration) > 1e-9 * max(1.0, duration):
        raise InputError(f"duration {duration!r} s is not a whole number of steps dt = {dt!r} s")
    source = _input_source(model, inputs, n_steps)
    t = np.arange(n_steps + 1) * dt
    Q = np.empty((n_steps + 1, model.n))
    U = np.zeros((n_steps, model.n_inputs))
    res = np.zeros(n_steps)
    speeds: dict[str, list] = {}
    Q[0] = q
    status, reason = SimStatus.OK, f"{n_steps} steps of {dt:g} s"
    t0 = time.perf_counter()
    done = n_steps
    bar = Progress(n_steps, model.name, quiet=not progress, unit="step")
    for k in range(done):
        try:
            u = model.check_u(source(k, float(t[k]), q.copy(), dt))
            A = model.A(q)
            qd = model.velocity(q, u)
            q_next = model.flow(q, u, dt)
        except KinematicSingularityError as err:
            status, reason, done = SimStatus.SINGULAR, f"singular between t = {t[k]:.6g} s and {t[k + 1]:.6g} s: {err}", k
            break
        U[k] = u
        res[k] = float(np.max(np.abs(A.T @ qd))) if A.size else 0.0
        for name, val in model.wheel_speeds(q, u).items():
            speeds.setdefault(name, []).append(val)
        q = q_next
        Q[k + 1] = q
        bar.update()
    bar.close()
    return WheeledSimResult(
        model.name,
        model.coordinates,
        model.inputs,
        t[: done + 1],
        Q[: done + 1],
        U[:done],
        res[:done],
        {k: np.array(v[:done]) for k, v in speeds.items()},
        dt,
        status,
        reason,
        time.perf_counter() - t0,
    )


__all__ = ["SimStatus", "WheeledSimResult", "chord_slip", "euler_step", "heading_quadrature", "rk4_step", "se2_flow", "simulate_wheeled", "sinc"]
