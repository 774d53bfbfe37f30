"""Generate ``urdf/qprr.urdf`` from the parameters (the committed file is this output).

Tree: ``multirotor`` (root; the free-flyer is added when loading) -> prismatic ``r0``
along +x_B at height d0 -> ``link1`` -> revolute ``theta2`` about +y at d1 -> ``link2``
-> revolute ``theta3`` about +y at d2 -> ``link3`` -> fixed ``end_effector`` at d3
(Thesis (3.58): R_eb = Ry(theta2 + theta3)).  Rotors are massless frames
``rotor_<layout>_<i>`` on the multirotor, for both layouts.

Visual shapes (``<visual>``, no effect on the dynamics: Pinocchio's model reads the inertials
only) are primitives sized from the parameters: the hub, a boom from the hub to each rotor,
the motor and a propeller disc on each rotor frame of ``layout`` (the other layout's frames stay
bare), the slider rail at height d0, the links as cylinders of lengths d1, d2, d3, the
revolute joint housings about y and a sphere at the end effector.  Each of these shapes is also a
``<collision>`` element (same origin and geometry, :mod:`qprr.urdf.writer`): the collision model of
:mod:`qprr.analysis.collision` (the propeller discs included, so qprr adds no disc of its own for the Q-PRR).
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

from ..urdf import writer as ug
from .params import LAYOUTS, QPRRParams, thesis_params

URDF_PATH = Path(__file__).resolve().parent.parent.parent / "urdf" / "qprr.urdf"

PROPELLER_RADIUS = 0.127
"""Propeller disc radius [m] drawn on each rotor: a 10-inch propeller, the class the chosen b and c assume."""

_HUB = (0.25, 0.27, 0.32, 1.0)
_BOOM = (0.35, 0.35, 0.38, 1.0)
_MOTOR = (0.1, 0.1, 0.1, 1.0)
_DISC = (0.25, 0.55, 0.95, 0.35)
_ARM = (0.93, 0.55, 0.12, 1.0)
_JOINT = (0.45, 0.45, 0.5, 1.0)
_EE = (0.85, 0.15, 0.15, 1.0)


def _visuals(p: QPRRParams, layout: str) -> dict[str, str]:
    """``<visual>`` elements of each link (name -> XML), every size from the parameters ``p``."""
    l = p.arm_length
    hub_r, hub_h = 0.3 * l, 0.04
    lo, hi = p.r0_limits
    rail_h = max(p.d0 - hub_h / 2.0, 0.005)
    vis = {
        "multirotor": ug.cylinder_visual(hub_r, hub_h, rgba=_HUB)
        + ug.box_visual((hi - lo + 0.04, 0.02, rail_h), (0.5 * (lo + hi), 0.0, p.d0 - rail_h / 2.0), rgba=_JOINT),
        "link1": ug.box_visual((0.03, 0.03, 0.012), (0.0, 0.0, 0.006), rgba=_JOINT)
        + ug.cylinder_visual(0.008, p.d1, (0.0, 0.0, p.d1 / 2.0), rgba=_ARM),
    }
    y_axis = (math.pi / 2.0, 0.0, 0.0)  # a cylinder about y_B
    for name, length, radius in (("link2", p.d2, 0.008), ("link3", p.d3, 0.007)):
        vis[name] = ug.cylinder_visual(0.014, 0.03, rpy=y_axis, rgba=_JOINT) + ug.cylinder_visual(radius, length, (0.0, 0.0, length / 2.0), rgba=_ARM)
    vis["end_effector"] = ug.sphere_visual(0.012, rgba=_EE)
    pitch = min(math.dist(a.position, b.position) for a, b in itertools.combinations(p.rotors(layout), 2))
    disc_r = min(PROPELLER_RADIUS, 0.45 * pitch)
    for i, rotor in enumerate(p.rotors(layout), start=1):
        x, y, _ = rotor.position
        dist = math.hypot(x, y)
        boom = dist - hub_r
        inward = (-x / dist, -y / dist, 0.0)  # from the rotor towards z_B
        centre = tuple(c * boom / 2.0 for c in inward)
        vis[f"rotor_{layout}_{i}"] = (
            ug.cylinder_visual(0.008, boom, centre, ug.rpy_of_axis(inward), rgba=_BOOM)
            + ug.cylinder_visual(0.016, 0.03, (0.0, 0.0, 0.0), rgba=_MOTOR)
            + ug.cylinder_visual(disc_r, 0.004, (0.0, 0.0, 0.017), rgba=_DISC)
        )
    return vis


def build_urdf(params: QPRRParams | None = None, *, layout: str = "plus", visuals: bool = True) -> str:
    """The URDF text of the Q-PRR for ``params`` (default: :func:`thesis_params`).

    ``layout`` ("plus" or "x") chooses which rotor frames carry the booms, motors and
    propeller discs; ``visuals=False`` writes the inertial tree alone (the same dynamics).
    """
    p = params if params is not None else thesis_params()
    if not isinstance(p, QPRRParams):
        from ..errors import InputError

        raise InputError(f"params must be None or a QPRRParams, got {type(p).__name__}")
    if layout not in LAYOUTS:
        from ..errors import UnknownNameError

        raise UnknownNameError("layout", layout, LAYOUTS)
    vis = _visuals(p, layout) if visuals else {}
    l1, l2, l3 = p.links
    e, v = p.effort_limits, p.velocity_limits

    def link(name: str, body=None, *, mass=None, com=None, inertia=None) -> str:
        if body is not None:
            mass, com, inertia = body.mass, body.com, body.inertia
        inner = ug.inertial(mass, com, inertia) if mass is not None else ""
        return ug.link(name, inner + vis.get(name, ""))

    out = [link("multirotor", mass=p.multirotor_mass, com=(0.0, 0.0, 0.0), inertia=p.multirotor_inertia)]
    if p.rail is not None:
        out.append(link("rail", p.rail))
        out.append(ug.joint("rail_fixed", "fixed", "multirotor", "rail", (0.0, 0.0, 0.0)))
    out.append(link("link1", l1))
    out.append(ug.joint("r0", "prismatic", "multirotor", "link1", (0.0, 0.0, p.d0), (1, 0, 0), (*p.r0_limits, e[0], v[0])))
    out.append(link("link2", l2))
    out.append(ug.joint("theta2", "revolute", "link1", "link2", (0.0, 0.0, p.d1), (0, 1, 0), (*p.theta2_limits, e[1], v[1])))
    out.append(link("link3", l3))
    out.append(ug.joint("theta3", "revolute", "link2", "link3", (0.0, 0.0, p.d2), (0, 1, 0), (*p.theta3_limits, e[2], v[2])))
    out.append(link("end_effector"))
    out.append(ug.joint("end_effector_fixed", "fixed", "link3", "end_effector", (0.0, 0.0, p.d3)))
    for lay in LAYOUTS:
        for i, rotor in enumerate(p.rotors(lay), start=1):
            name = f"rotor_{lay}_{i}"
            out.append(link(name))
            out.append(ug.joint(f"{name}_fixed", "fixed", "multirotor", name, rotor.position))
    return ug.robot(f"qprr_{p.variant}", out, "qprr.thesis.urdf.build_urdf")


def write_urdf(path: Path | str = URDF_PATH, params: QPRRParams | None = None, *, layout: str = "plus") -> Path:
    """Write the generated URDF to ``path`` and return it."""
    from ..validation import as_output_path

    path = as_output_path(path, "path", suffixes=(".urdf",))
    text = build_urdf(params, layout=layout)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


if __name__ == "__main__":  # python -m qprr.thesis.urdf  regenerates the committed file
    print(write_urdf())
