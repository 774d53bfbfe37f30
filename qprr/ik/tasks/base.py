"""The task contract: one wish about the configuration, linearised as J dv = e."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
import pinocchio as pin

from ...errors import InputError, NonFiniteError, ShapeError
from ...model import Platform
from ...validation import as_vector


def update_kinematics(platform: Platform, data: pin.Data, q: np.ndarray) -> None:
    """Fill ``data`` at q with what :meth:`Task.linearize` may read.

    Joint placements and Jacobians (``computeJointJacobians``), frame placements and the
    centre of mass with its world Jacobian ``data.Jcom`` (``jacobianCenterOfMass``).
    """
    model = platform.model
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    pin.jacobianCenterOfMass(model, data, False)


class Task(ABC):
    """One wish about the configuration, linearised at q as ``J dv = e``.

    ``J`` (dim x nv) maps Pinocchio's tangent step dv (body-frame base twist, then arm rates)
    to the change of the task quantity; ``e`` (dim,) is the change wanted.  ``linearize`` may
    read from ``data`` what :func:`update_kinematics` left there at q.
    """

    name: str = "task"
    dim: int = 0
    _sw: np.ndarray | None = None  # sqrt of the row weights (a task with weights sets it: :func:`sqrt_weights`)

    @property
    def row_scale(self) -> np.ndarray | None:
        """The factors the task's rows of (J, e) are multiplied by, the square roots of its weights (None: none)."""
        return self._sw

    @abstractmethod
    def linearize(self, platform: Platform, data: pin.Data, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(J, e): J of shape (dim, nv) and the wanted change e of shape (dim,)."""

    def error(self, platform: Platform, data: pin.Data, q: np.ndarray) -> np.ndarray:
        """The wanted change e alone, equal to the second value of :meth:`linearize` (a solver asks for it first: at a
        configuration where every level is met it needs no Jacobian).  Override it when e costs less than (J, e)."""
        return self.linearize(platform, data, q)[1]

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, dim={self.dim})"


def task_name(name) -> str:
    """A task's name (a non-empty string: errors and level reports use it)."""
    if not isinstance(name, str) or not name:
        raise InputError(f"a task name must be a non-empty string, got {name!r}")
    return name


def check_linearized(task, out, nv: int) -> tuple[np.ndarray, np.ndarray]:
    """The (J, e) a task's ``linearize`` returned, checked: J (dim, nv), e (dim,) (``dim`` when the task declares one),
    finite; else :class:`ShapeError` / :class:`NonFiniteError` naming the task (a custom task must not be broadcast)."""
    try:
        J, e = out
    except (TypeError, ValueError):
        raise ShapeError(f"task {task!r}: linearize must return a pair (J, e), got {type(out).__name__}") from None
    if not (isinstance(J, np.ndarray) and isinstance(e, np.ndarray)) or J.dtype.kind != "f" or e.dtype.kind != "f":
        raise ShapeError(f"task {task!r}: linearize must return float arrays (J, e), got {type(J).__name__}, {type(e).__name__}")
    dim = task.dim
    if e.ndim != 1 or J.shape != (e.shape[0], nv) or (dim and e.shape[0] != dim):
        want = f"({dim}, {nv}) and ({dim},)" if dim else f"(dim, {nv}) and (dim,)"
        raise ShapeError(f"task {task!r}: linearize returned J of shape {J.shape} and e of shape {e.shape}; they must be {want}")
    if not (np.isfinite(e.sum()) and np.isfinite(J.sum())):
        raise NonFiniteError(f"task {task!r}: linearize returned a non-finite J or e (e = {e.tolist()})")
    return J, e


def sqrt_weights(weights, n: int, name: str) -> np.ndarray | None:
    """sqrt of positive row weights (None: unit weights, nothing to scale)."""
    if weights is None:
        return None
    w = as_vector(weights, n, name)
    if np.any(w <= 0.0):
        raise InputError(f"{name} must be positive, got {w.tolist()}")
    return np.sqrt(w)


def scaled(sw, J, e):
    """Rows of (J, e) scaled by the square-root weights ``sw`` (None: unchanged)."""
    return (J, e) if sw is None else (sw[:, None] * J, sw * e)


def scaled_error(sw, e):
    """e scaled by the square-root weights ``sw`` (None: unchanged), as :func:`scaled` scales it."""
    return e if sw is None else sw * e
