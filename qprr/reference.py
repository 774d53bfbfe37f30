"""Reference multirotors from ``example-robot-data``, to run qprr's generic tools on other robots.

The Q-PRR's conversion (:mod:`qprr.coordinates`) and the xi-coordinate dynamics only assume a
free-flyer root followed by joints with v = q_dot; loading a third-party quadrotor checks that
they are not specialised to our URDF (see ``tests/test_reference.py``).
"""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

import pinocchio as pin

from .errors import QprrError, UnknownNameError

_URDFS = {
    "hector": "hector_description/robots/quadrotor_base.urdf",
    "iris": "iris_description/robots/iris_simple.urdf",
}


def robots_dir() -> Path:
    """Folder of example-robot-data's robot descriptions (installed by the ``example-robot-data`` wheel)."""
    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError as exc:  # pragma: no cover - runtime dependency
        raise QprrError("example-robot-data is not installed: pip install example-robot-data") from exc
    path = Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))
    if not path.is_dir():  # pragma: no cover - layout of a future wheel
        raise QprrError(f"example-robot-data robots folder not found at {path}")
    return path


def load_reference(name: str = "hector") -> pin.Model:
    """A free-flyer Pinocchio model of an example-robot-data multirotor (``"hector"`` or ``"iris"``)."""
    if name not in _URDFS:
        raise UnknownNameError("reference robot", name, tuple(_URDFS))
    path = robots_dir() / _URDFS[name]
    return pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
