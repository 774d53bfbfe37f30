"""What the end effector touches, as the simulator integrates it: the stateful-environment interface.

An :class:`Environment` has a state vector z (Euclidean, possibly empty), a derivative and an
output wrench, all functions of time, the end effector's kinematics and z:

    (h_world, z_dot) = env.evaluate(t, p_world, R_world, twist_world, z)

* ``p_world`` (3,) end-effector frame origin [m], ``R_world`` (3, 3) its orientation,
  ``twist_world`` (6,) = [linear velocity of the origin; angular velocity], world axes
  (Pinocchio's LOCAL_WORLD_ALIGNED frame velocity) [m/s, rad/s];
* ``h_world`` (6,) = [force; moment] the environment applies at the end-effector origin,
  world axes [N, N m]; the simulator adds J_e^T h to the generalised force (Thesis (5.38));
* ``z_dot`` (nz,) the derivative of the environment's own state.

The simulator owns z (initialised from :meth:`Environment.initial_state`) and integrates it
together with the robot's (q, v) with the same integrator, evaluating :meth:`evaluate` at
every stage; it therefore keeps the integrator's order (tests/test_convergence.py).  Once per
control period, at the tick, it calls :meth:`Environment.observe` (logging, the value a
sensor reads, events of the control grid) and after every integration step
:meth:`Environment.settle` (discrete events of the environment, e.g. static friction
catching a sliding object, resolved at step boundaries like the joint stops).

A plain callable ``h = wrench(t, q, v)`` (stateless) is also accepted by the simulator
(:class:`qprr.sim.ExternalWrench`); it is evaluated at every stage too.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

_EMPTY = np.zeros(0)


class Environment(ABC):
    """Base class of the environments the simulator integrates with the robot (module docstring)."""

    _h: np.ndarray | None = None  # the wrench at the last control tick (None before a run: :meth:`measured` reads zero)

    def initial_state(self) -> np.ndarray:
        """z at the start of a run (nz,); empty for a stateless environment."""
        return _EMPTY

    @property
    def state_size(self) -> int:
        return int(np.size(self.initial_state()))

    @abstractmethod
    def evaluate(self, t: float, p_world: np.ndarray, R_world: np.ndarray, twist_world: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(h_world (6,), z_dot (nz,)) at one integration stage; must not change the object."""

    def settle(self, t: float, z_before: np.ndarray, z_after: np.ndarray) -> np.ndarray:
        """Discrete events at the end of an integration step from t (default: none, returns ``z_after``)."""
        return z_after

    def reset(self) -> None:
        """Forget the previous run (logs, last reading); the simulator calls it at the start of a run."""
        self._h = np.zeros(6)

    def observe(self, t: float, p_world: np.ndarray, R_world: np.ndarray, twist_world: np.ndarray, z: np.ndarray, h_world: np.ndarray) -> None:
        """Called at every control tick with the state and the wrench there (default: keep the wrench for :meth:`measured`)."""
        self._h = np.array(h_world, dtype=float)

    def on_tick(self, t: float) -> None:
        """Called at every control tick before the first stage of the period (events of the control grid; default: none)."""
        return None

    def measured(self, t: float | None = None) -> np.ndarray:
        """Wrench at the last control tick (world, on the end effector): what a wrist force sensor sampled
        at the control rate reads; a controller calling it during its step gets the previous tick's value."""
        return np.zeros(6) if self._h is None else self._h.copy()
