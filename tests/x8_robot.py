"""The X8 test robot of issue 35 (tests/robots/x8_arm4/): a coaxial octocopter of 3.0 kg with a 4-joint arm (base yaw,
shoulder pitch, a 0-0.25 m telescope, wrist pitch) and the end-effector frame "gripper", built for the tests only.

``load()`` builds it with :func:`qprr.from_urdf`; ``CLI`` is the same platform as command-line options; the names
come from its files (``ROTOR_NAMES`` read from the rotor file, ``JOINTS`` as the URDF writes them).
"""

from __future__ import annotations

from pathlib import Path

import qprr
from qprr.model import Platform

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

DIR = Path(__file__).resolve().parent / "robots" / "x8_arm4"
URDF = DIR / "x8_arm4.urdf"
ROTORS = DIR / "x8_arm4.rotors.toml"
EE_FRAME = "gripper"
CLI = ["--urdf", str(URDF), "--rotors", str(ROTORS), "--ee-frame", EE_FRAME]
"""The options of every ``qprr`` command that takes a platform."""
JOINTS = ("base_yaw", "shoulder_pitch", "telescope", "wrist_pitch")
ROTOR_NAMES = tuple(r["name"] for r in tomllib.loads(ROTORS.read_text())["rotor"])
TOTAL_MASS = 3.0  # [kg] the sum of the URDF's link masses (2.50 + 0.12 + 0.15 + 0.10 + 0.08 + 0.05)
TELESCOPE_STROKE = 0.25  # [m] the telescope's upper limit (its lower one is 0)


def load() -> Platform:
    """The X8 as a :class:`~qprr.model.Platform` (gravity 9.81 m/s^2, qprr.from_urdf's default)."""
    return qprr.from_urdf(URDF, ROTORS, ee_frame=EE_FRAME)
