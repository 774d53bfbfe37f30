"""Model errors: a simulated robot (the plant) that differs from the model its controller knows.

A controller is built on a platform (its model); :func:`qprr.sim.simulate` flies it on
``plant=`` another platform of the same structure, typically :func:`perturbed`'s copy with
scaled masses, inertias and rotor constants and an unknown payload.  In such a run

* the controller and the allocation use the model (``platform``): the allocator computes the
  thrust commands with the nominal rotor matrix and the nominal thrust bounds;
* the plant integrates its own inertias; its rotors produce the commanded thrusts clipped to
  their own bounds [f_min, f_max], and the wrench of those thrusts through its own rotor
  matrix (its drag-to-thrust ratios kappa): :class:`PlantActuators`.

``platform.model`` is never modified: :func:`perturbed` works on copies.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..actuation import AllocationFlag, Allocator
from ..errors import InputError
from ..model import Platform


def _factor(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not (math.isfinite(value) and value > 0.0):
        raise InputError(f"model error {name} must be a finite factor > 0, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class ModelError:
    """Multiplicative errors of the plant against the nominal model (1.0: no error), and an unknown payload.

    Parameters
    ----------
    mass : factor on the mass of every body (base and arm links; centres of mass kept).
    arm_mass : further factor on the arm links' masses (the base keeps ``mass``).
    inertia : factor on every body's rotational inertia about its centre of mass.
    kappa : factor on every rotor's drag-to-thrust ratio kappa [m] (the yaw torque per newton).
    f_max : factor on every rotor's maximum thrust [N].
    payload : mass [kg] of a point payload at the end-effector frame's origin, unknown to the controller.
    """

    mass: float = 1.0
    arm_mass: float = 1.0
    inertia: float = 1.0
    kappa: float = 1.0
    f_max: float = 1.0
    payload: float = 0.0

    def __post_init__(self) -> None:
        for f in ("mass", "arm_mass", "inertia", "kappa", "f_max"):
            object.__setattr__(self, f, _factor(getattr(self, f), f))
        p = self.payload
        if isinstance(p, bool) or not isinstance(p, (int, float, np.integer, np.floating)) or not (math.isfinite(p) and p >= 0.0):
            raise InputError(f"model error payload must be a mass >= 0 kg, got {p!r}")
        object.__setattr__(self, "payload", float(p))

    @property
    def is_nominal(self) -> bool:
        """True when every factor is 1 and there is no payload (the plant is the model)."""
        return self == ModelError()


def perturbed(platform: Platform, error: ModelError) -> Platform:
    """A copy of ``platform`` whose bodies and rotors carry ``error`` (``platform`` is not modified).

    Body j of the copy has mass ``m_j * mass`` (``* arm_mass`` for the arm links), the same
    centre of mass and the rotational inertia ``inertia * I_j`` about it; rotor i has
    ``kappa_i * kappa`` and ``f_max,i * f_max``; ``payload`` is added as a point mass at the
    end-effector frame (:func:`qprr.payload.with_payload`).
    """
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    if not isinstance(error, ModelError):
        raise InputError(f"error must be a ModelError, got {type(error).__name__}")
    model = pin.Model(platform.model)
    for j in range(1, model.njoints):
        Y = model.inertias[j]
        m = error.mass * (error.arm_mass if j >= 2 else 1.0)
        model.inertias[j] = pin.Inertia(float(Y.mass) * m, np.array(Y.lever), np.array(Y.inertia) * error.inertia)
    rotors = tuple(dataclasses.replace(r, kappa=r.kappa * error.kappa, f_max=r.f_max * error.f_max) for r in platform.rotors)
    for r in rotors:
        if not r.f_max > r.f_min:
            raise InputError(f"model error f_max = {error.f_max!r} puts rotor {r.name!r}'s f_max ({r.f_max} N) below its f_min ({r.f_min} N)")
    out = platform.with_model(model).replace(rotors=rotors)
    if error.payload > 0.0:
        from ..payload import with_payload

        out = with_payload(out, error.payload)
    return out


def check_plant(platform: Platform, plant: Platform) -> Platform:
    """``plant`` if it has ``platform``'s structure (joints, frames, rotor count), else InputError."""
    if not isinstance(plant, Platform):
        raise InputError(f"plant must be a qprr Platform, got {type(plant).__name__}")
    m, p = platform.model, plant.model
    if (
        (p.nq, p.nv, p.njoints, p.nframes) != (m.nq, m.nv, m.njoints, m.nframes)
        or plant.n_rotors != platform.n_rotors
        or plant.ee_frame != platform.ee_frame
    ):
        raise InputError(f"plant {plant!r} does not have the structure of the model {platform!r} (joints, frames, rotors)")
    return plant


class PlantActuators:
    """The allocation of the model, the actuators of the plant (see the module docstring).

    ``allocate_into`` has :meth:`qprr.actuation.Allocator.allocate_into`'s contract: ``f_out``
    receives the thrusts the plant's rotors produce (commands clipped to the plant's bounds)
    and the arm efforts, ``tau_out`` the plant's N f; ``AllocationFlag.ROTOR_SATURATED`` is set when the model's or the
    plant's thrust bounds were active.  ``allocate_screened_into`` (the simulator's call) has
    :meth:`qprr.actuation.Allocator.allocate_screened_into`'s: ``AllocationFlag.REFUSED`` and nothing written on a NaN,
    infinite or absurd demand.
    """

    def __init__(self, allocator: Allocator, plant: Platform) -> None:
        self.allocator = allocator
        self.n_rotors = plant.n_rotors
        self.Omega = np.array(plant.rotor_matrix)
        self.f_min, self.f_max = np.array(plant.thrust_min), np.array(plant.thrust_max)
        self._same_bounds = bool(np.array_equal(self.f_min, allocator.f_min) and np.array_equal(self.f_max, allocator.f_max))

    def allocate_into(self, tau_d: np.ndarray, f_out: np.ndarray, tau_out: np.ndarray | None = None) -> AllocationFlag:
        """The model's allocation, the plant's thrusts (see the class docstring)."""
        return self._plant_side(self.allocator.allocate_into(tau_d, f_out, None), f_out, tau_out)

    def allocate_screened_into(self, tau_d: np.ndarray, f_out: np.ndarray, tau_out: np.ndarray | None = None) -> AllocationFlag:
        """:meth:`allocate_into` behind the allocator's screen: ``AllocationFlag.REFUSED`` (nothing written) on a NaN,
        infinite or absurd ``tau_d``."""
        flags = self.allocator.allocate_screened_into(tau_d, f_out, None)
        return flags if AllocationFlag.REFUSED in flags else self._plant_side(flags, f_out, tau_out)

    def _plant_side(self, flags: AllocationFlag, f_out: np.ndarray, tau_out: np.ndarray | None) -> AllocationFlag:
        """The commanded thrusts in ``f_out`` clipped to the plant's bounds; the plant's N f into ``tau_out``."""
        nr = self.n_rotors
        f = f_out[:nr]
        if not self._same_bounds:
            clipped = np.clip(f, self.f_min, self.f_max)
            if not np.array_equal(clipped, f):
                flags |= AllocationFlag.ROTOR_SATURATED
                f[:] = clipped
        if tau_out is not None:
            tau_out[0:6] = self.Omega @ f
            tau_out[6:] = f_out[nr:]
        return flags
