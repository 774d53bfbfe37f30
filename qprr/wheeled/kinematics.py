"""Kinematic models q_dot = B(q) u of wheeled robots (the interface; the lecture's robots are in
:mod:`qprr.wheeled.robots`).

Lecture: "q_dot = B(q) u ... Im(B(q)) = ker(A^T(q))": the columns of B(q) span the velocities
allowed by the Pfaffian constraints A^T(q) q_dot = 0, and u is the vector of inputs (a choice
of coordinates on that kernel: the lecture's front- and rear-driven tricycles share A and
differ only in B).

A model writes A(q) and B(q) once against a namespace ``m`` (:mod:`math` or :mod:`sympy`,
see :mod:`qprr.wheeled._backend`): the same code gives numbers for simulation and
expressions for the symbolic checks (A^T B = 0) and the Lie brackets.  ``flow(q, u, h)`` is
the exact solution for an input held constant over h (:mod:`qprr.wheeled.sim`).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from ..errors import InputError
from ..validation import as_vector
from ._backend import is_symbolic, sympy_module
from .chassis import WheeledRobot, rotation
from .wheels import WheelKind


class KinematicModel(ABC):
    """q_dot = B(q) u with named coordinates and inputs.

    Subclasses set ``name``, ``description``, ``lecture`` (the slide it implements),
    ``coordinates``, ``inputs``, ``input_units``, ``robot`` (the wheels on the chassis, or
    None) and implement :meth:`B` and :meth:`flow`.  :meth:`A` defaults to the robot's
    posture-level Pfaffian matrix.
    """

    name: str = "model"
    description: str = ""
    lecture: str = ""
    coordinates: tuple[str, ...] = ()
    inputs: tuple[str, ...] = ()
    input_units: tuple[str, ...] = ()
    robot: WheeledRobot | None = None

    @property
    def n(self) -> int:
        """Dimension of q."""
        return len(self.coordinates)

    @property
    def n_inputs(self) -> int:
        return len(self.inputs)

    # ------------------------------------------------------------ checks
    def check_q(self, q) -> np.ndarray:
        return as_vector(q, self.n, f"q of {self.name!r} {list(self.coordinates)}")

    def check_u(self, u) -> np.ndarray:
        return as_vector(u, self.n_inputs, f"u of {self.name!r} {list(self.inputs)}")

    # ------------------------------------------------------------ the model
    def A(self, q, m=math):
        """Pfaffian matrix A(q) (n x k) of the constraints A^T(q) q_dot = 0 (Lecture: "forme pfaffienne")."""
        if self.robot is None:  # pragma: no cover - every model of the package has a robot or overrides A
            raise NotImplementedError
        return self.robot.pfaffian(q if is_symbolic(m) else self.check_q(q), m)

    @abstractmethod
    def B(self, q, m=math):
        """B(q) (n x n_inputs), a basis of ker A^T(q): q_dot = B(q) u (Lecture: Im B(q) = ker A^T(q))."""

    @abstractmethod
    def flow(self, q, u, h: float) -> np.ndarray:
        """q(h) for q(0) = q and the input u held constant over [0, h] (exact)."""

    def singularity(self, q) -> str | None:
        """Why B is undefined at q (None where the model is valid)."""
        return None

    def velocity(self, q, u) -> np.ndarray:
        """q_dot = B(q) u."""
        return self.B(self.check_q(q)) @ self.check_u(u)

    def residual(self, q, q_dot) -> np.ndarray:
        """A^T(q) q_dot: the constraint violation of a velocity (zero for admissible ones)."""
        return self.A(self.check_q(q)).T @ as_vector(q_dot, self.n, "q_dot")

    def inputs_of(self, q, q_dot) -> np.ndarray:
        """u with B(q) u closest to q_dot (least squares): the inputs of an admissible velocity."""
        Bq = self.B(self.check_q(q))
        return np.linalg.lstsq(Bq, as_vector(q_dot, self.n, "q_dot"), rcond=None)[0]

    # ------------------------------------------------------------ wheels
    def body_twist(self, q, u) -> np.ndarray:
        """xi_R = R^T(theta) [x_dot, y_dot, theta_dot], the chassis twist in the robot frame."""
        qv = self.check_q(q)
        return rotation(qv[2]).T @ self.velocity(qv, u)[0:3]

    def wheel_speeds(self, q, u) -> dict[str, float]:
        """Spin rate phi_dot [rad/s] of every wheel with a rolling constraint, by wheel name.

        From the rolling rows (Lecture: J1 R^T(theta) q_dot_I - J2 phi_dot = 0, and the
        Swedish row with r cos gamma): phi_dot = row . xi_R / (r or r cos gamma).  Castors
        are skipped (their angle is not part of q).
        """
        if self.robot is None:
            return {}
        qv = self.check_q(q)
        xi = self.body_twist(qv, u)
        angles = dict(zip((id(w) for w in self.robot.steered_wheels), self.robot.steering_angles(qv[3 : 3 + self.robot.n_steering])))
        out = {}
        for w in self.robot.wheels:
            if w.kind is WheelKind.OFF_CENTRED_STEERABLE:
                continue
            row = w.rolling(angles.get(id(w), 0.0))
            out[w.name] = float(np.dot(row.xi, xi)) / -float(row.phi_dot)
        return out

    # ------------------------------------------------------------ symbolic
    def symbols(self):
        """sympy symbols of q (real), named as ``coordinates``."""
        sp = sympy_module()
        return sp.symbols(" ".join(self.coordinates), real=True, seq=True)

    def symbolic(self):
        """(q symbols, A(q), B(q)) as sympy objects (needs sympy: ``pip install "qprr[symbolic]"``)."""
        sp = sympy_module()
        q = self.symbols()
        return q, self.A(q, sp), self.B(q, sp)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, q={list(self.coordinates)}, u={list(self.inputs)})"


def check_duration(h) -> float:
    try:
        h = float(h)
    except (TypeError, ValueError):
        raise InputError(f"h must be a real number of seconds, got {h!r}") from None
    if not (math.isfinite(h) and h >= 0.0):
        raise InputError(f"h must be finite and >= 0 s, got {h!r}")
    return h


__all__ = ["KinematicModel", "check_duration"]
