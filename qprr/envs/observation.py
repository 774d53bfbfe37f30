"""The observation vector of every task: its entries, units, frames and bounds (docs/rl.md, "Observations").

One layout for the four tasks (a policy can move between them), float32, from the *measured* state (the sensor
noise of :mod:`qprr.envs.randomize` included):

======================  =========  ==========  ================================================================
entry                   size       unit        what
======================  =========  ==========  ================================================================
``base_error_world``    3          m           p_d(t) - p: the plan's base position minus the base's, world axes
``rotation_world_body`` 9          -           R, body to world, row-major (r00, r01, r02, r10, ...)
``v_body``              3          m/s         base linear velocity, body axes (Pinocchio's v[0:3])
``omega_body``          3          rad/s       base angular velocity, body axes
``q_arm``               n_arm      rad or m    arm joint positions
``q_arm_dot``           n_arm      rad/s, m/s  arm joint rates
``ee_error_world``      3          m           the task's end-effector target minus the end effector, world axes
``yaw_error``           1          rad         psi_d(t) - psi wrapped to [-pi, pi)
``v_ref_world``         3          m/s         the plan's base velocity, world axes
``thrust``              n_rotors   -           the rotors' thrusts at the end of the last period (the lag's
                                               state), 2 (f - f_min) / (f_max - f_min) - 1
``attached``            1          -           1 when Carry's payload is attached, else 0
======================  =========  ==========  ================================================================

Bounds (:meth:`ObservationLayout.bounds`): the position errors +-box (an episode terminates beyond it) and the end
effector's +-(box + 2 m), rotation entries +-1, velocities +-20 m/s, angular rates +-50 rad/s, joints within their
limits (+-2 pi where unlimited), joint rates +-50, yaw error +-pi, reference velocity +-20 m/s, thrusts and the flag in
their ranges.  An observation is clipped to the bounds (the noise can push a joint past its stop, a terminating
step's state past the box) and a non-finite entry (only on a terminating step) becomes 0.
"""

from __future__ import annotations

import math

import numpy as np

from ..model import Platform, check_platform
from ..validation import as_real

SPEED_BOUND = 20.0
"""Bound of the observed linear velocities [m/s]."""
RATE_BOUND = 50.0
"""Bound of the observed angular and joint rates [rad/s, m/s]."""
EE_MARGIN = 2.0
"""The end-effector error's bound exceeds the base error's by this much [m] (the arm's reach and the target's offset)."""


class ObservationLayout:
    """The entries (name, size) of the observation vector of ``platform`` and their bounds (module docstring)."""

    def __init__(self, platform: Platform, box: float) -> None:
        check_platform(platform)
        box = as_real(box, "box", positive=True, unit="m")
        na, nr = platform.n_arm, platform.n_rotors
        self.entries = (
            ("base_error_world", 3),
            ("rotation_world_body", 9),
            ("v_body", 3),
            ("omega_body", 3),
            ("q_arm", na),
            ("q_arm_dot", na),
            ("ee_error_world", 3),
            ("yaw_error", 1),
            ("v_ref_world", 3),
            ("thrust", nr),
            ("attached", 1),
        )
        self.size = sum(k for _, k in self.entries)
        lower = np.where(np.isfinite(platform.arm_lower), platform.arm_lower, -2.0 * math.pi)
        upper = np.where(np.isfinite(platform.arm_upper), platform.arm_upper, 2.0 * math.pi)
        ee = box + EE_MARGIN
        bounds = {
            "base_error_world": (np.full(3, -box), np.full(3, box)),
            "rotation_world_body": (np.full(9, -1.0), np.full(9, 1.0)),
            "v_body": (np.full(3, -SPEED_BOUND), np.full(3, SPEED_BOUND)),
            "omega_body": (np.full(3, -RATE_BOUND), np.full(3, RATE_BOUND)),
            "q_arm": (lower, upper),
            "q_arm_dot": (np.full(na, -RATE_BOUND), np.full(na, RATE_BOUND)),
            "ee_error_world": (np.full(3, -ee), np.full(3, ee)),
            "yaw_error": (np.array([-math.pi]), np.array([math.pi])),
            "v_ref_world": (np.full(3, -SPEED_BOUND), np.full(3, SPEED_BOUND)),
            "thrust": (np.full(nr, -1.0), np.full(nr, 1.0)),
            "attached": (np.zeros(1), np.ones(1)),
        }
        self.low = np.concatenate([bounds[name][0] for name, _ in self.entries]).astype(np.float32)
        self.high = np.concatenate([bounds[name][1] for name, _ in self.entries]).astype(np.float32)

    def names(self) -> tuple[str, ...]:
        """One name per entry of the vector: ``base_error_world[0]``, ..., ``attached[0]``."""
        return tuple(f"{name}[{k}]" for name, size in self.entries for k in range(size))

    def slices(self) -> dict[str, slice]:
        """Entry name -> its slice of the vector."""
        out, start = {}, 0
        for name, size in self.entries:
            out[name] = slice(start, start + size)
            start += size
        return out

    def build(self, parts: dict[str, np.ndarray]) -> np.ndarray:
        """The observations (n, size) float32 of ``parts`` (entry name -> (n, size) array), cleaned and clipped."""
        x = np.concatenate([parts[name] for name, _ in self.entries], axis=1)
        x = np.nan_to_num(x, nan=0.0, posinf=0.0, neginf=0.0)
        return np.clip(x, self.low, self.high).astype(np.float32)


def rotation_rows(quat: np.ndarray) -> np.ndarray:
    """R (n, 9), row-major, of unit quaternions (n, 4) stored (x, y, z, w) (the formula of :meth:`qprr.charts.State.update`)."""
    x, y, z, w = quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3]
    return np.column_stack(
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ]
    )


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles wrapped to [-pi, pi) [rad]."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


__all__ = ["EE_MARGIN", "RATE_BOUND", "SPEED_BOUND", "ObservationLayout", "rotation_rows", "wrap"]
