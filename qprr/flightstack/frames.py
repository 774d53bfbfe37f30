"""The flight stacks' frames: the one place qprr's frames are converted to and from PX4's (and ArduPilot's).

qprr's body frame B is FLU (x forward, y left, z up) and its world frame W has z up.  PX4 and ArduPilot write
body vectors in FRD (x forward, y right, z down) and world vectors in NED (x north, y east, z down).  qprr's world
frame is read as NWU (x north, y west, z up), so both conversions are the same proper rotation

    C = diag(1, -1, -1)        (a half turn about x; C = C^T = C^-1, det C = +1)

    v_frd = C v_body,   v_ned = C v_world,   R_ned_frd = C R_world_body C.

qprr's identity attitude is then PX4's level attitude heading north (yaw 0).  Because C is a rotation,
C (a x b) = (C a) x (C b): moments computed in one frame map to the other like any vector.

PX4's attitude quaternion ``q`` (``vehicle_attitude.q``, ``vehicle_attitude_setpoint.q_d``) is Hamilton, ordered
(w, x, y, z), and rotates FRD vectors into NED (PX4's ``matrix::Dcm(Quaternion)``, src/lib/matrix/matrix/Dcm.hpp).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError, ShapeError
from ..validation import as_array

FLU_TO_FRD = np.diag([1.0, -1.0, -1.0])
"""C: the rotation from qprr's body frame (FLU) to FRD, and from qprr's world frame (NWU) to NED (its own inverse)."""
FLU_TO_FRD.setflags(write=False)

_FLIP = np.array([1.0, -1.0, -1.0])


def _vectors(v, name: str) -> np.ndarray:
    """``v`` as a finite (3,) or (N, 3) float array, else a ShapeError naming ``name``."""
    a = as_array(v, name, finite=True)
    if a.shape[-1:] != (3,) or a.ndim not in (1, 2):
        raise ShapeError(f"{name} must have shape (3,) or (N, 3), got shape {a.shape}")
    return a


def frd_from_body(v_body) -> np.ndarray:
    """A vector (3,) or vectors (N, 3) of qprr's body frame B (FLU) written in PX4's FRD body frame."""
    return _vectors(v_body, "v_body") * _FLIP


def body_from_frd(v_frd) -> np.ndarray:
    """A vector (3,) or vectors (N, 3) of PX4's FRD body frame written in qprr's body frame B (FLU)."""
    return _vectors(v_frd, "v_frd") * _FLIP


def ned_from_world(v_world) -> np.ndarray:
    """A vector (3,) or vectors (N, 3) of qprr's world frame (NWU, z up) written in NED."""
    return _vectors(v_world, "v_world") * _FLIP


def world_from_ned(v_ned) -> np.ndarray:
    """A vector (3,) or vectors (N, 3) of NED written in qprr's world frame (NWU, z up)."""
    return _vectors(v_ned, "v_ned") * _FLIP


def _rotations(R, name: str) -> np.ndarray:
    a = as_array(R, name, finite=True)
    if a.shape[-2:] != (3, 3) or a.ndim not in (2, 3):
        raise ShapeError(f"{name} must have shape (3, 3) or (N, 3, 3), got shape {a.shape}")
    return a


def R_world_body_from_ned_frd(R_ned_frd) -> np.ndarray:
    """qprr's attitude R_world_body (3, 3) or (N, 3, 3) from PX4's R_ned_frd (FRD -> NED): C R_ned_frd C."""
    R = _rotations(R_ned_frd, "R_ned_frd")
    return R * _FLIP[:, None] * _FLIP[None, :]


def R_ned_frd_from_world_body(R_world_body) -> np.ndarray:
    """PX4's attitude R_ned_frd (FRD -> NED) (3, 3) or (N, 3, 3) from qprr's R_world_body: C R_world_body C."""
    R = _rotations(R_world_body, "R_world_body")
    return R * _FLIP[:, None] * _FLIP[None, :]


def R_ned_frd_from_quaternion_wxyz(q) -> np.ndarray:
    """R_ned_frd (3, 3), or (N, 3, 3) for (N, 4), from PX4's attitude quaternion (w, x, y, z), FRD -> NED.

    The quaternion is normalised first (a zero quaternion is refused); q and -q give the same matrix."""
    a = as_array(q, "q", finite=True)
    if a.shape[-1:] != (4,) or a.ndim not in (1, 2):
        raise ShapeError(f"q must have shape (4,) or (N, 4) ordered (w, x, y, z), got shape {a.shape}")
    norm = np.linalg.norm(a, axis=-1, keepdims=True)
    if np.any(norm < 1e-9):
        raise InputError("q: a zero quaternion is no attitude (PX4 logs unit quaternions (w, x, y, z))")
    w, x, y, z = np.moveaxis(a / norm, -1, 0)
    R = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )
    return R


def R_world_body_from_quaternion_wxyz(q) -> np.ndarray:
    """qprr's R_world_body (3, 3) or (N, 3, 3) from PX4's attitude quaternion (w, x, y, z) (FRD -> NED)."""
    return R_world_body_from_ned_frd(R_ned_frd_from_quaternion_wxyz(q))
