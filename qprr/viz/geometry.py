"""Visual geometry of a platform: its URDF's ``<visual>`` shapes and meshes, or primitives drawn from the model.

:func:`visual_model` returns a Pinocchio ``GeometryModel`` (``GeometryType.VISUAL``) for the
browser viewer.  It reads the URDF the platform was built from (:attr:`Platform.urdf`): the
Q-PRR's primitives sized from its parameters (:mod:`qprr.thesis.urdf`), the shapes of
:func:`qprr.build`, example-robot-data's meshes (``package://example-robot-data/...``, resolved in
the installed example-robot-data).  A platform without a URDF or without visual elements gets
:func:`primitive_visual_model`: a hub, a boom, motor and propeller disc per rotor (from
:attr:`Platform.rotors`), a cylinder between consecutive arm joints and a sphere at the end effector.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..model import Platform, check_platform

_HUB = np.array([0.25, 0.27, 0.32, 1.0])
_BOOM = np.array([0.35, 0.35, 0.38, 1.0])
_DISC = np.array([0.25, 0.55, 0.95, 0.35])
_ARM = np.array([0.93, 0.55, 0.12, 1.0])
_EE = np.array([0.85, 0.15, 0.15, 1.0])


def rotor_radius(platform: Platform) -> float:
    """Radius [m] of the propeller discs drawn on ``platform``: 0.45 x the closest rotor spacing (0.127 m at most, a 10-inch propeller)."""
    check_platform(platform)
    p = np.array([r.position_body for r in platform.rotors])
    if len(p) < 2:
        return 0.127
    d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=-1)
    closest = float(d[~np.eye(len(p), dtype=bool)].min())
    return min(0.127, 0.45 * closest) if closest > 0 else 0.127


def characteristic_length(platform: Platform) -> float:
    """Size [m] of the platform at its neutral configuration: the largest distance of a rotor or of the end effector from B."""
    check_platform(platform)
    data = platform.data()
    pin.framesForwardKinematics(platform.model, data, platform.neutral_q())
    ee = np.linalg.norm(data.oMf[platform.ee_frame].translation)
    rot = max(np.linalg.norm(r.position_body) for r in platform.rotors)
    return float(max(ee, rot + rotor_radius(platform), 0.05))


def default_package_dirs() -> list[str]:
    """Folders where ``package://`` URIs are looked up: example-robot-data's share folder, then ``ROS_PACKAGE_PATH``."""
    from ..platforms import robots_dir

    dirs = [str(robots_dir().parent.parent)]
    dirs += [d for d in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if d]
    return dirs


def visual_model(platform: Platform, urdf: str | Path | None = None, *, package_dirs: list[str] | None = None) -> pin.GeometryModel:
    """Visual ``GeometryModel`` of ``platform`` (see the module docstring).

    Parameters
    ----------
    urdf : URDF text or path to read the visuals from (default: :attr:`Platform.urdf`).
    package_dirs : folders for ``package://`` URIs (default: :func:`default_package_dirs`).
    """
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    text = platform.urdf if urdf is None else urdf
    if isinstance(text, Path) or (isinstance(text, str) and not text.lstrip().startswith("<")):
        path = Path(text)
        if not path.is_file():
            raise InputError(f"URDF file {str(path)!r} does not exist")
        text = path.read_text()
    if text is not None and "<visual" in text:
        dirs = default_package_dirs() if package_dirs is None else list(package_dirs)
        geom = pin.buildGeomFromUrdfString(platform.model, text, pin.GeometryType.VISUAL, package_dirs=dirs)
        if geom.ngeoms > 0:
            return geom
    return primitive_visual_model(platform)


def _along(axis: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is the unit vector ``axis``."""
    return pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), axis).matrix()


def primitive_visual_model(platform: Platform) -> pin.GeometryModel:
    """Primitive shapes drawn from the kinematic tree and the rotor set (any platform)."""
    model = check_platform(platform).model
    size = characteristic_length(platform)
    geom = pin.GeometryModel()

    def add(name, joint, frame, M, shape, color):
        obj = pin.GeometryObject(name, joint, frame, M, shape)
        obj.meshColor = np.asarray(color, dtype=float)
        geom.addGeometryObject(obj)

    base = platform.base_frame
    radial = [math.hypot(*r.position_body[0:2]) for r in platform.rotors]
    hub_r = max(0.25 * min(radial), 0.02) if min(radial) > 0 else 0.05
    add("hub", 1, base, pin.SE3.Identity(), coal.Cylinder(hub_r, 0.2 * hub_r), _HUB)
    disc_r = rotor_radius(platform)
    for k, r in enumerate(platform.rotors):
        p, a = np.array(r.position_body), np.array(r.axis_body)
        add(f"rotor_{k}_disc", 1, base, pin.SE3(_along(a), p), coal.Cylinder(disc_r, 0.004), _DISC)
        length = float(np.linalg.norm(p))
        if length > hub_r:
            d = -p / length
            add(
                f"rotor_{k}_boom",
                1,
                base,
                pin.SE3(_along(d), p + 0.5 * (length - hub_r) * d),
                coal.Cylinder(0.04 * hub_r + 0.004, length - hub_r),
                _BOOM,
            )
    chain = [j for j in model.supports[model.frames[platform.ee_frame].parentJoint] if j >= 2]
    ends = [model.jointPlacements[c].translation for c in chain[1:]] + [model.frames[platform.ee_frame].placement.translation]
    link_r = 0.02 * size + 0.002
    for j, end in zip(chain, ends):
        length = float(np.linalg.norm(end))
        if length > 1e-6:
            add(f"{model.names[j]}_link", j, 0, pin.SE3(_along(end / length), 0.5 * end), coal.Cylinder(link_r, length), _ARM)
        add(f"{model.names[j]}_joint", j, 0, pin.SE3.Identity(), coal.Sphere(1.6 * link_r), _BOOM)
    ee = model.frames[platform.ee_frame]
    add("end_effector", ee.parentJoint, platform.ee_frame, ee.placement, coal.Sphere(2.0 * link_r), _EE)
    return geom
