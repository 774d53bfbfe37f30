"""Payload changes during a run: the plant's inertia changes at scheduled control ticks (Thesis Sec. 6.4).

The simulator owns a COPY of the platform's model and sets the inertia of the end effector's
parent joint to nominal + payload at the first control tick at or after each change;
``platform.model`` is never touched and the controller keeps its own model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..model import Platform, check_platform
from ..validation import as_array, as_real, as_vector


@dataclass(frozen=True)
class PayloadChange:
    """From ``time`` on [s], the end effector carries ``mass`` [kg] (a point mass) at ``com_ee`` (end-effector frame) [m].

    mass = 0 removes the payload (e.g. a release).  In a simulation the change takes effect at
    the first control tick at or after ``time`` (payload changes sit on the control grid).
    """

    time: float
    mass: float
    com_ee: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not (isinstance(self.time, (int, float)) and np.isfinite(self.time) and self.time >= 0.0):
            raise InputError(f"payload change time must be a number >= 0 s, got {self.time!r}")
        if not (isinstance(self.mass, (int, float)) and np.isfinite(self.mass) and self.mass >= 0.0):
            raise InputError(f"payload mass must be a number >= 0 kg, got {self.mass!r}")
        as_vector(self.com_ee, 3, "com_ee")


@dataclass(frozen=True)
class PayloadSchedule:
    """Payload changes applied during a run, in time order (see :class:`PayloadChange`)."""

    changes: tuple[PayloadChange, ...] = ()

    def __post_init__(self) -> None:
        if not all(isinstance(c, PayloadChange) for c in self.changes):
            raise InputError("payload changes must be PayloadChange objects")
        times = [c.time for c in self.changes]
        if times != sorted(times):
            raise InputError(f"payload changes must be in time order, got times {times}")

    def mass_at(self, t: float) -> float:
        """The payload mass [kg] at time ``t`` [s] (the last change at or before t; 0 before the first)."""
        t = as_real(t, "t", unit="s")
        m = 0.0
        for c in self.changes:
            if c.time <= t:
                m = c.mass
        return m


class PlantPayload:
    """Owns a copy of the model and sets the end effector's parent-joint inertia to nominal + payload."""

    def __init__(self, platform: Platform, schedule: PayloadSchedule) -> None:
        check_platform(platform)
        if not isinstance(schedule, PayloadSchedule):
            raise InputError(f"schedule must be a qprr.sim.PayloadSchedule, got {type(schedule).__name__}")
        self.model = pin.Model(platform.model)
        frame = self.model.frames[platform.ee_frame]
        self.joint = frame.parentJoint
        self.placement = frame.placement
        self.nominal = pin.Inertia(self.model.inertias[self.joint])
        self.changes = list(schedule.changes)
        self.next = 0

    @property
    def pending(self) -> bool:
        return self.next < len(self.changes)

    def carried(self, t) -> tuple[np.ndarray, np.ndarray]:
        """(mass (m,) [kg], com_ee (m, 3) [m, end-effector frame]) of the payload at each time of ``t`` (m,) [s]: the
        last change at or before it, as :meth:`apply_until` applies them at the ticks (no payload before the first)."""
        t = as_array(t, "t", finite=True, ndim=1)
        mass, com_ee = np.zeros(t.shape[0]), np.zeros((t.shape[0], 3))
        for c in self.changes:  # in time order: a later change overrides an earlier one
            on = c.time <= t + 1e-12
            mass[on] = c.mass
            com_ee[on] = c.com_ee
        return mass, com_ee

    def apply_until(self, t: float) -> bool:
        """Apply every change at or before ``t`` [s] (the simulator calls it at its ticks while changes are pending)."""
        t = as_real(t, "t", unit="s")
        changed = False
        while self.next < len(self.changes) and self.changes[self.next].time <= t + 1e-12:
            c = self.changes[self.next]
            lever = self.placement.act(np.asarray(c.com_ee, dtype=float))
            self.model.inertias[self.joint] = self.nominal + pin.Inertia(c.mass, lever, np.zeros((3, 3)))
            self.next += 1
            changed = True
        return changed
