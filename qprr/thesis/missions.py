"""The missions of Thesis Chapter 6 for the Q-PRR (Sec. 6.3.1.4 and 6.3.3.3), on :mod:`qprr.trajectory`."""

from __future__ import annotations

from ..errors import InputError, UnknownNameError
from ..scenarios.missions import phase_tables
from ..trajectory import DEFAULT_LAW, MultiPhase, Phase, line_phases
from ..validation import as_interval, as_real, as_vector, checked_module

PATHS = ("xy", "line")
"""Horizontal paths of the missions: x then y (Fig. 6.13), or the line y = a x + b (Sec. 6.3.1.2)."""

NAMES = ("x", "y", "z", "phi", "theta", "psi", "r0", "theta2", "theta3")
"""The Q-PRR's thesis coordinates (its arm joints' names)."""

STATIC_TARGET = (3.0, 6.0, 10.0, 0.0, 0.04, 0.2, 0.6)
"""xi_d = [x_b, y_b, z_b, psi, r0, theta2, theta3] of Thesis Sec. 6.3.1.4."""


def static_mission(
    target=STATIC_TARGET,
    *,
    z_phase=(0.0, 5.0),
    x_phase=(5.0, 10.0),
    y_phase=(10.0, 15.0),
    arm_phase=(15.0, 25.0),
    law: str = DEFAULT_LAW,
    path: str = "xy",
) -> MultiPhase:
    """The mission of Thesis Sec. 6.3.1.4 / 6.3.3.3: climb in z 0-5 s, x 5-10 s, y 10-15 s, arm 15-25 s.

    ``target`` = [x, y, z, psi, r0, theta2, theta3] (default [3, 6, 10, 0, 0.04, 0.2, 0.6]).
    The arm starts straight (r0 = theta2 = theta3 = 0); yaw is held at ``psi``.  ``path``: "xy" (x then y, the
    half rectangle of Fig. 6.13) or "line" (the option y = a x + b of Sec. 6.3.1.2: x and y together from the start
    of ``x_phase`` to the end of ``y_phase``, a = y / x, b = 0; :func:`qprr.trajectory.line_phases`).
    """
    x, y, z, psi, r0, t2, t3 = as_vector(target, 7, "target")
    z_phase, x_phase, y_phase, arm_phase = (
        as_interval(v, n, lo=0.0) for v, n in ((z_phase, "z_phase"), (x_phase, "x_phase"), (y_phase, "y_phase"), (arm_phase, "arm_phase"))
    )
    if path == "xy":
        phases = [Phase("z", *z_phase, z), Phase("x", *x_phase, x), Phase("y", *y_phase, y)]
    elif path == "line":
        if x == 0.0:
            raise InputError("path='line' needs a target x != 0 (y = a x + b with a = y / x)")
        phases = [Phase("z", *z_phase, z), *line_phases(y / x, 0.0, 0.0, x, x_phase[0], y_phase[1])]
    else:
        raise UnknownNameError("path", path, PATHS)
    phases += [Phase(c, *arm_phase, val) for c, val in (("r0", r0), ("theta2", t2), ("theta3", t3)) if val != 0.0]
    xi0 = (0.0, 0.0, 0.0, 0.0, 0.0, psi, 0.0, 0.0, 0.0)
    return MultiPhase(tuple(phases), xi0, name="static-mission", law=law, names=NAMES)


def dynamic_mission(p_target=(3.0, 6.0, 10.0), theta2_d: float = -0.5, *, arm_phase=(15.0, 25.0), law: str = DEFAULT_LAW) -> MultiPhase:
    """Mission of Thesis Sec. 6.3.3.3: same flight phases, theta2 -> ``theta2_d`` in 15-25 s.

    r0 and theta3 references are left at 0: the CoG stabiliser (BSG) computes them.
    """
    x, y, z = as_vector(p_target, 3, "p_target")
    arm_phase = as_interval(arm_phase, "arm_phase", lo=0.0)
    phases = (Phase("z", 0.0, 5.0, z), Phase("x", 5.0, 10.0, x), Phase("y", 10.0, 15.0, y), Phase("theta2", *arm_phase, float(theta2_d)))
    return MultiPhase(phases, name="dynamic-mission", law=law, names=NAMES)


def aggressive_reach(
    climb: float = 2.0,
    forward: float = 0.6,
    *,
    start: float = 0.5,
    duration: float = 1.0,
    arm=(0.03, 0.6, -0.3),
    z0: float = 2.0,
    law: str = "quintic",
) -> MultiPhase:
    """Not in the thesis: a fast reach of the Q-PRR that asks the rotors for more than they have (rotor-bound tests).

    From hover at z = ``z0`` [m] with the arm straight, during [start, start + duration] [s]
    the base climbs ``climb`` [m] and moves ``forward`` [m] along x while the arm goes to
    ``arm`` = (r0 [m], theta2, theta3 [rad]), all with the same transition law (6.16).  With the
    quintic the peak vertical acceleration is 5.77 climb / duration^2: the default 2 m in 1 s
    asks for 11.5 m/s^2 up, then down (more than g: not feasible with thrust >= 0, and the
    Q-PRR's 20 N rotors are near their top during the acceleration).
    """
    r0, t2, t3 = as_vector(arm, 3, "arm")
    duration = as_real(duration, "duration", positive=True, unit="s")
    t1, t2_ = start, start + duration
    phases = (
        Phase("z", t1, t2_, z0 + climb),
        Phase("x", t1, t2_, forward),
        Phase("r0", t1, t2_, float(r0)),
        Phase("theta2", t1, t2_, float(t2)),
        Phase("theta3", t1, t2_, float(t3)),
    )
    return MultiPhase(phases, xi0=(0.0, 0.0, z0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0), name="aggressive-reach", law=law, names=NAMES)


STATIC_MISSION = {"phase": tuple(phase_tables(static_mission().phases))}
"""The mission of Sec. 6.3.1.4 (:func:`static_mission`) as data (:func:`qprr.scenarios.missions.read_mission`): the
``static-*`` scenarios fly it through the generic ``mission`` (from the ground, yaw 0)."""
DYNAMIC_MISSION = {"phase": tuple(phase_tables(dynamic_mission().phases))}
"""The mission of Sec. 6.3.3.3 (:func:`dynamic_mission`) as data, flown by ``dynamic-bsg``."""

checked_module(globals())
