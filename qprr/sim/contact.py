"""Contact models at the end effector, integrated with the robot by the simulator (Thesis Sec. 6.4.3).

Each model is an :class:`~qprr.sim.environment.Environment`: the simulator's ``external_wrench``
hook (world wrench at the end effector, evaluated at every integration stage, its own state
integrated with the robot's by the same integrator) and a force sensor for the controllers
(:meth:`measured`, sampled at the control ticks).

* :class:`PushedMass`: a point object on a straight line, pushed through a unilateral compliant
  contact (spring k, damper d, force never negative), with optional Coulomb friction on the line;
* :class:`CompliantWall`: a fixed unilateral compliant plane;
* :class:`PrescribedWrench`: a wrench given as a function of time (Sec. 6.4.3.4's h).

Each control tick is logged (:meth:`history`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..model import Platform
from ..validation import as_vector
from .environment import Environment


@dataclass(frozen=True)
class ContactHistory:
    """Log of a contact model, one row per control tick of the run (the rows of ``SimResult``).

    ``t`` [s]; ``force`` (n,) normal force the environment exerts on the end effector along
    -normal [N] (>= 0); ``wrench`` (n, 6) world wrench on the end effector; ``position``,
    ``velocity`` (n,) object coordinate along its line [m, m/s] (zeros for a wall);
    ``penetration`` (n,) [m] (> 0 in contact).
    """

    t: np.ndarray
    force: np.ndarray
    wrench: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    penetration: np.ndarray


class _Contact(Environment):
    """Unilateral compliant contact at the end effector: F = max(0, k delta + d delta_dot) while delta > 0.

    Subclasses give the penetration delta (:meth:`_gap`) and, if the obstacle moves, its state
    and derivative.  An :class:`qprr.sim.environment.Environment`: the simulator integrates the
    state with the robot and evaluates the force at every integration stage.
    """

    def __init__(self, platform: Platform, normal, stiffness: float, damping: float) -> None:
        n = as_vector(normal, 3, "normal")
        norm = float(np.linalg.norm(n))
        if norm < 1e-12:
            raise InputError(f"normal must be a non-zero vector, got {n.tolist()}")
        if not (np.isfinite(stiffness) and stiffness > 0.0):
            raise InputError(f"stiffness must be > 0 N/m, got {stiffness!r}")
        if not (np.isfinite(damping) and damping >= 0.0):
            raise InputError(f"damping must be >= 0 N s/m, got {damping!r}")
        self.platform = platform
        self.normal = n / norm
        self.k = float(stiffness)
        self.d = float(damping)
        self._data = platform.model.createData()
        self.reset()

    def reset(self) -> None:
        """Empty log, no reading (the simulator calls it at the start of a run)."""
        super().reset()
        self._log: list[tuple] = []

    def _gap(self, p_e: np.ndarray, v_e: np.ndarray, z: np.ndarray) -> tuple[float, float]:
        raise NotImplementedError

    def _object_derivative(self, z: np.ndarray, force: float) -> np.ndarray:
        return _NO_STATE

    def _force(self, p_e: np.ndarray, v_e: np.ndarray, z: np.ndarray) -> tuple[float, float]:
        """(F, delta): normal force on the obstacle [N] (>= 0) and the penetration [m]."""
        pen, pen_dot = self._gap(p_e, v_e, z)
        if pen <= 0.0:
            return 0.0, pen
        F = self.k * pen + self.d * pen_dot
        return (F if F > 0.0 else 0.0), pen  # unilateral: the damper never pulls

    def evaluate(self, t: float, p_world, R_world, twist_world, z) -> tuple[np.ndarray, np.ndarray]:
        """(h_world, z_dot): -F normal on the end effector, and the obstacle's state derivative."""
        F, _ = self._force(p_world, twist_world[0:3], z)
        h = np.zeros(6)
        h[0:3] = -F * self.normal
        return h, self._object_derivative(z, F)

    def observe(self, t: float, p_world, R_world, twist_world, z, h_world) -> None:
        F, pen = self._force(p_world, twist_world[0:3], z)
        self._h = np.array(h_world, dtype=float)
        s, sd = (float(z[0]), float(z[1])) if len(z) else (0.0, 0.0)
        self._log.append((float(t), F, s, sd, pen))

    def wrench(self, t: float, q, v, z=None) -> np.ndarray:
        """World wrench on the end effector with the robot at (q, v) and the obstacle at ``z`` (default: its initial state)."""
        model, data = self.platform.model, self._data
        J = pin.computeFrameJacobian(model, data, as_vector(q, model.nq, "q"), self.platform.ee_frame, pin.LOCAL_WORLD_ALIGNED)
        M = data.oMf[self.platform.ee_frame]
        z = self.initial_state() if z is None else np.asarray(z, dtype=float)
        return self.evaluate(t, M.translation, M.rotation, J @ as_vector(v, model.nv, "v"), z)[0]

    def history(self) -> ContactHistory:
        if not self._log:
            z = np.zeros(0)
            return ContactHistory(z, z, np.zeros((0, 6)), z, z, z)
        a = np.array(self._log)
        wrench = -a[:, 1:2] * self.normal[None, :]
        return ContactHistory(a[:, 0], a[:, 1], np.hstack([wrench, np.zeros((a.shape[0], 3))]), a[:, 2], a[:, 3], a[:, 4])


_NO_STATE = np.zeros(0)


class PushedMass(_Contact):
    """A point object of mass ``mass`` sliding on a straight line, pushed by the end effector.

    The line passes through ``origin`` (world) along the unit ``direction`` (also the
    contact normal); the object's face is at origin + s direction.  Penetration
    delta = direction . (p_e - origin) - s; in contact (delta > 0) the force on the object is
    F = max(0, k delta + d delta_dot) along +direction, and -F direction on the end effector.

    State z = [s, s_dot] [m, m/s] (``initial``: its value at the start, default at rest at the origin),
    integrated with the robot by the simulator's integrator: s_ddot = (F - F_f) / m with Coulomb
    friction (coefficient ``friction``, normal force m g, g the platform's gravity):
    F_f = mu m g sign(s_dot) while sliding, and F_f = clip(F, -mu m g, mu m g) at rest (static
    friction: the object sticks while F <= mu m g).  A sliding object whose velocity changes
    sign during an integration step is caught by static friction at the end of that step
    (:meth:`settle`, an event resolved at step boundaries).
    """

    def __init__(
        self,
        platform: Platform,
        *,
        mass: float,
        origin,
        direction=(1.0, 0.0, 0.0),
        initial=(0.0, 0.0),
        stiffness: float = 500.0,
        damping: float = 20.0,
        friction: float = 0.0,
    ) -> None:
        if not (np.isfinite(mass) and mass > 0.0):
            raise InputError(f"mass must be > 0 kg, got {mass!r}")
        if not (np.isfinite(friction) and friction >= 0.0):
            raise InputError(f"friction must be >= 0, got {friction!r}")
        self.mass = float(mass)
        self.origin = as_vector(origin, 3, "origin").copy()
        self.s0, self.sd0 = as_vector(initial, 2, "initial (position [m], velocity [m/s])").tolist()
        self.mu = float(friction)
        self.g = platform.g
        super().__init__(platform, direction, stiffness, damping)

    def initial_state(self) -> np.ndarray:
        return np.array([self.s0, self.sd0])

    def _gap(self, p_e, v_e, z):
        n = self.normal
        return float(n @ (p_e - self.origin)) - float(z[0]), float(n @ v_e) - float(z[1])

    def friction_force(self, s_dot: float, force: float) -> float:
        """Coulomb friction on the object along +direction's opposite [N] (static: balances ``force`` up to mu m g)."""
        limit = self.mu * self.mass * self.g
        if s_dot > 0.0:
            return limit
        if s_dot < 0.0:
            return -limit
        return force if -limit <= force <= limit else math.copysign(limit, force)

    def _object_derivative(self, z, force: float) -> np.ndarray:
        sd = float(z[1])
        return np.array([sd, (force - self.friction_force(sd, force)) / self.mass])

    def settle(self, t: float, z_before, z_after) -> np.ndarray:
        """Static friction catches an object whose velocity changed sign (or reached zero) during the step."""
        if self.mu > 0.0:
            v0, v1 = float(z_before[1]), float(z_after[1])
            if v0 != 0.0 and (v0 > 0.0) != (v1 > 0.0):
                return np.array([z_after[0], 0.0])
        return z_after


class CompliantWall(_Contact):
    """A fixed plane through ``point`` with outward unit ``normal`` (towards the robot): F = max(0, k delta + d delta_dot),
    delta = -normal . (p_e - point) > 0 when the end effector is inside.  No state of its own."""

    def __init__(self, platform: Platform, *, point, normal, stiffness: float = 2000.0, damping: float = 20.0) -> None:
        self.point = as_vector(point, 3, "point").copy()
        super().__init__(platform, -as_vector(normal, 3, "normal"), stiffness, damping)

    def _gap(self, p_e, v_e, z):
        n = self.normal  # points into the wall
        return float(n @ (p_e - self.point)), float(n @ v_e)


class PrescribedWrench(Environment):
    """A world wrench on the end effector given in time: h(t) = ``wrench`` for t_on <= t < t_off, else 0.

    ``wrench`` is a 6-vector or a callable t -> 6-vector (evaluated at every integration stage).
    In a simulation the window opens and closes at control ticks (the first tick at or after
    t_on, t_off), like every other switched input.  Also a perfect sensor (:meth:`measured`).
    """

    def __init__(self, wrench, t_on: float = 0.0, t_off: float = math.inf) -> None:
        if not (t_off > t_on):
            raise InputError(f"need t_on < t_off, got {t_on!r}, {t_off!r}")
        self._fn: Callable[[float], np.ndarray]
        if callable(wrench):
            self._fn = lambda t: as_vector(wrench(t), 6, "wrench(t)")
        else:
            w = as_vector(wrench, 6, "wrench").copy()
            self._fn = lambda t: w
        self.t_on, self.t_off = float(t_on), float(t_off)
        self.reset()

    def reset(self) -> None:
        super().reset()
        self._on = None

    def on_tick(self, t: float) -> None:
        self._on = self.t_on <= t < self.t_off

    def evaluate(self, t: float, p_world=None, R_world=None, twist_world=None, z=None) -> tuple[np.ndarray, np.ndarray]:
        on = self._on if self._on is not None else self.t_on <= t < self.t_off
        return (self._fn(t).copy() if on else np.zeros(6)), _NO_STATE

    def measured(self, t: float | None = None) -> np.ndarray:
        if t is None:
            return super().measured()
        return self._fn(t).copy() if self.t_on <= t < self.t_off else np.zeros(6)

    def __call__(self, t: float, q=None, v=None) -> np.ndarray:
        return self.measured(t)
