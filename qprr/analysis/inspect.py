"""What a platform is, in one report: its tree, inertias, joints, rotors, what the rotors can do, and notes.

:func:`inspect_platform` gathers it (the ``qprr inspect`` command prints it): every number comes from the loaded
:class:`~qprr.model.Platform` (the URDF's inertials and limits, the rotor file's rotors), nothing from a table.
The notes are the checks a designer looks at before flying: thrust-to-weight, hover margin, the CoG's distance
from the thrust axis at the neutral pose, and the step under which the URDF's joint friction stays explicit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..dynamics.friction import STIFF, JointFriction
from ..model import Platform, check_platform, max_lift
from ..rotors import ActuationSummary


@dataclass(frozen=True)
class PlatformReport:
    """The sections of a platform's report (:func:`inspect_platform`), each a list of text lines."""

    name: str
    tree: tuple[str, ...]
    bodies: tuple[str, ...]
    joints: tuple[str, ...]
    rotors: tuple[str, ...]
    actuation: ActuationSummary
    notes: tuple[str, ...]

    def text(self) -> str:
        """The report as the command prints it."""
        s = self.actuation
        lines = [f"platform {self.name}", "", "kinematic tree (joint: type, parent -> child frame):", *self.tree]
        lines += ["", "bodies (mass [kg], CoM in the joint frame [m], principal moments [kg m^2]):", *self.bodies]
        lines += ["", "arm joints (limits [m or rad], effort [N or N m], velocity, damping, friction):", *self.joints]
        lines += ["", "rotors (position_body [m], axis_body, spin, kappa [m], thrust bounds [N]):", *self.rotors]
        lines += [
            "",
            "actuation at the neutral pose:",
            f"  wrench rank {s.rank}/6 ({'fully actuated' if s.fully_actuated else 'under-actuated'}); producible on "
            f"their own: {', '.join(s.directions) or 'none'}",
            f"  attitude map rank {s.attitude_rank}/4 (collective thrust and three torques), condition {s.condition:.4g}",
            f"  hover thrusts [{', '.join(f'{x:.4g}' for x in s.hover_thrusts)}] N, margin to the bounds {s.hover_margin:.4g} N",
        ]
        lines += ["", "notes:", *(f"  - {note}" for note in self.notes)]
        return "\n".join(lines)


def inspect_platform(platform: Platform) -> PlatformReport:
    """The report of ``platform`` (module docstring)."""
    check_platform(platform)
    return PlatformReport(
        name=platform.name,
        tree=_tree(platform.model),
        bodies=_bodies(platform.model),
        joints=_joints(platform),
        rotors=tuple(
            f"  {r.name or f'rotor {i + 1}'}: [{_numbers(r.position_body)}], [{_numbers(r.axis_body)}], {r.spin:+d}, "
            f"{r.kappa:.4g}, [{r.f_min:.4g}, {r.f_max:.4g}]"
            for i, r in enumerate(platform.rotors)
        ),
        actuation=platform.actuation_summary(),
        notes=_notes(platform),
    )


def _numbers(values) -> str:
    return ", ".join(f"{x:.4g}" for x in np.asarray(values, dtype=float).ravel())


def _tree(model: pin.Model) -> tuple[str, ...]:
    """One line per joint: its type, its parent joint and the frames it carries, indented by depth."""
    depth = [0] * model.njoints
    lines = []
    for j in range(1, model.njoints):
        parent = model.parents[j]
        depth[j] = depth[parent] + 1
        frames = [f.name for f in model.frames if f.parentJoint == j and f.type == pin.FrameType.BODY]
        kind = model.joints[j].shortname().replace("JointModel", "")
        lines.append(f"  {'  ' * (depth[j] - 1)}{model.names[j]}: {kind}, {model.names[parent]} -> {', '.join(frames) or '(no body)'}")
    return tuple(lines)


def _bodies(model: pin.Model) -> tuple[str, ...]:
    """Mass, CoM and principal moments of the inertia each joint carries (its links merged, as Pinocchio holds them)."""
    lines = []
    for j in range(1, model.njoints):
        inertia = model.inertias[j]
        moments = np.linalg.eigvalsh(inertia.inertia)
        lines.append(f"  {model.names[j]}: {inertia.mass:.4g} kg, CoM [{_numbers(inertia.lever)}], moments [{_numbers(moments)}]")
    return tuple(lines)


def _joints(platform: Platform) -> tuple[str, ...]:
    model = platform.model
    unit = {"prismatic": ("m", "N", "m/s", "N s/m"), "revolute": ("rad", "N m", "rad/s", "N m s/rad")}
    lines = []
    for joint in platform.arm:
        length, force, rate, damping = unit[joint.kind]
        lines.append(
            f"  {joint.name} ({joint.kind}): [{joint.lower:.4g}, {joint.upper:.4g}] {length}, {joint.effort:.4g} {force}, "
            f"{joint.velocity:.4g} {rate}, damping {model.damping[joint.idx_v]:.4g} {damping}, friction {model.friction[joint.idx_v]:.4g} {force}"
        )
    return tuple(lines) or ("  (no arm)",)


def _notes(platform: Platform) -> tuple[str, ...]:
    """The designer's checks (module docstring), measured on the loaded platform."""
    weight = platform.total_mass * platform.g
    lift = max_lift(platform)
    notes = [
        f"total mass {platform.total_mass:.4g} kg; thrust-to-weight {lift / weight:.3g} (the rotors' largest total thrust "
        f"along z_B / m g; below about 1.5 leaves little for control)",
    ]
    com = platform.com_neutral_body
    offset = float(np.hypot(com[0], com[1]))
    summary = platform.actuation_summary()
    effect = "it hovers level all the same (fully actuated)" if summary.fully_actuated else "the base tilts to hover when it is off the axis"
    notes.append(f"CoG at the neutral pose: [{_numbers(com)}] m in B, {offset * 1e3:.3g} mm from the z_B axis through B ({effect})")
    if not summary.can_hover:
        notes.append(f"cannot hover with every thrust inside its bounds at the neutral pose (margin {summary.hover_margin:.4g} N)")
    friction = JointFriction.from_model(platform.model)
    if friction is not None:
        rate = friction.max_rate(platform.model, platform.neutral_q())
        notes.append(
            f"joint friction: stiffest rate {rate:.3g} 1/s at the neutral pose; the simulators take it explicitly for "
            f"dt <= {STIFF / rate:.3g} s and implicitly (one Newton solve per step) above"
        )
    return tuple(notes)
