"""Wheeled mobile robots and mobile manipulation.

From the lecture ``003`` (F. Morbidi, *Robotique mobile*, UPJV, Master 2 3EA, ch. 2, part 5):
wheels and their rolling / no-slip constraints (:mod:`.wheels`), robots as wheels on a chassis
with their Pfaffian matrix, ICR and degrees of manoeuvrability (:mod:`.chassis`), the kinematic
models q_dot = B(q) u of the lecture's robots and exercises (:mod:`.robots`), the Frobenius test
by Lie brackets (:mod:`.liebracket`, needs sympy: ``pip install "qprr[symbolic]"``), exact
simulation (:mod:`.sim`), feedback laws (:mod:`.control`), figures (:mod:`.plots`) and an arm on a
wheeled base with a task-priority IK under the Pfaffian constraint (:mod:`.manipulation`).
``qprr wheeled --help`` lists the runnable robots and exercises; docs/wheeled.md maps every
slide to the function and test implementing it.
"""

from .chassis import ICR, AckermannSteering, Mobility, WheeledRobot, admissible_types, wheel_at
from .kinematics import KinematicModel
from .robots import ROBOTS, TYPE_EXAMPLES, get_robot, tricycle_exercise
from .sim import WheeledSimResult, simulate_wheeled
from .wheels import CentredSteerableWheel, FixedWheel, OffCentredSteerableWheel, SwedishWheel

__all__ = [
    "ICR",
    "ROBOTS",
    "TYPE_EXAMPLES",
    "AckermannSteering",
    "CentredSteerableWheel",
    "FixedWheel",
    "KinematicModel",
    "Mobility",
    "OffCentredSteerableWheel",
    "SwedishWheel",
    "WheeledRobot",
    "WheeledSimResult",
    "admissible_types",
    "get_robot",
    "simulate_wheeled",
    "tricycle_exercise",
    "wheel_at",
]
