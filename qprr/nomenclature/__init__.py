"""The thesis nomenclature of aerial manipulators (Thesis Sec. 2.4, formula (2.1)) as a builder.

(2.1) names a system ``n1 XXX ... - m1 YY..Y ...``: ``n`` vehicles of type ``XXX`` (Table 2.3:
``Q``/``QUA`` quadrotor, ``HEX`` hexarotor, ``OCT`` octorotor, ``HEL`` helicopter, ``FXW`` fixed
wing, ``FLW`` flying wing) carrying ``m`` arms whose letters give the joints (``R`` revolute,
``P`` prismatic, ``C`` cable); a count of 1 is not written (Hypothesis 1 of Sec. 2.4).  Examples:
``Q-PRR`` (the thesis's robot), ``HEL-RRR``, ``3Q-RR``, ``Q-3RP``.

:func:`parse` reads a name; :func:`build` makes a :class:`~qprr.model.Platform` of one
multirotor and one serial arm: ``Q``, ``HEX``, ``OCT`` (with ``X`` or ``+`` after the code for the
rotor layout, e.g. ``QX-PRR``, or the ``layout`` argument) and ``R``/``P`` joints.  Names that
(2.1) allows but :func:`build` does not make raise :class:`UnsupportedDesignError` saying why:
several vehicles (``3Q-RR``) or several arms (``Q-3RP``) close kinematic loops or branch the
tree, which needs constrained dynamics (Pinocchio's constraint models and a contact/loop
solver) and an allocation across vehicles; cables (``C``) need a cable model (unilateral,
tension-only); helicopters and fixed wings need other actuator models than rotors.

Generated geometry (the thesis's convention, Sec. 3.3.1): the arm is mounted at ``mount_xyz`` in
B; a ``P`` joint slides along the x axis of its parent frame, an ``R`` joint turns about its y
axis; each link extends along +z (``arm_direction="up"``, as the Q-PRR) or -z (``"down"``, a
hanging arm) by its length to the next joint; the end-effector frame is at the tip of the last
link.  Bodies are homogeneous (Hypothesis 1 of Sec. 3.3.2): links are solid cylinders, the
multirotor a solid disc.  Every default is a field of :class:`BuildSpec` (each also a keyword of :func:`build`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import InputError, QprrError
from ..model import Platform, from_urdf
from ..rotors import LAYOUTS, Rotor, layout_rotors
from ..urdf import writer as ug
from ..validation import as_name, as_real, as_settings, as_vector

UAV_ROTORS = {"Q": 4, "QUA": 4, "HEX": 6, "OCT": 8}
"""Multirotor codes of Table 2.3 that :func:`build` makes, and their rotor counts."""

OTHER_UAVS = {"HEL": "helicopter", "FXW": "fixed wing", "FLW": "flying wing"}
"""Codes of Table 2.3 that are not multirotors."""

JOINTS = {"R": "revolute", "P": "prismatic", "C": "cable"}

_NAME = re.compile(r"^(\d*)([A-Z+]+)-(\d*)([A-Z]+)$")


class UnsupportedDesignError(QprrError, NotImplementedError):
    """A name that formula (2.1) allows but :func:`build` does not make; the message says why."""


@dataclass(frozen=True)
class Designation:
    """A parsed (2.1) name: ``n_uav`` vehicles ``uav`` (layout ``layout`` or None), ``n_arms`` arms ``joints``."""

    name: str
    n_uav: int
    uav: str
    layout: str | None
    n_arms: int
    joints: str

    @property
    def n_rotors(self) -> int | None:
        return UAV_ROTORS.get(self.uav)


def parse(name: str) -> Designation:
    """Read a name of formula (2.1): ``[n]XXX[X|+]-[m]YY..Y`` (e.g. ``Q-PRR``, ``QX-PRR``, ``3Q-RR``)."""
    if not isinstance(name, str):
        raise InputError(f"a (2.1) name is a string such as 'Q-PRR', got {name!r}")
    m = _NAME.match(name.strip().upper())
    if m is None:
        raise InputError(f"{name!r} is not a name of formula (2.1) [n]XXX-[m]YY..Y (e.g. 'Q-PRR', 'HEX-RRR', 'QX-PRR', '3Q-RR')")
    n_uav, uav, n_arms, joints = m.groups()
    layout = ""
    if uav not in UAV_ROTORS and uav not in OTHER_UAVS and uav[-1] in "X+":
        uav, layout = uav[:-1], uav[-1]  # "QX": a quadrotor in the X layout
    if uav not in UAV_ROTORS and uav not in OTHER_UAVS:
        raise InputError(f"{name!r}: unknown vehicle code {uav!r}; Table 2.3 codes: {', '.join(list(UAV_ROTORS) + list(OTHER_UAVS))}")
    bad = set(joints) - set(JOINTS)
    if bad:
        raise InputError(f"{name!r}: unknown joint letter(s) {''.join(sorted(bad))!r}; (2.1) letters: R, P, C")
    layout = {"X": "x", "+": "plus", "": None}[layout]
    return Designation(name, int(n_uav or 1), uav, layout, int(n_arms or 1), joints)


def _check_buildable(d: Designation) -> None:
    if d.n_uav == 0:
        raise UnsupportedDesignError(f"{d.name}: n = 0 names a parallel robot (Hypothesis 1 of Sec. 2.4), not an aerial manipulator")
    if d.uav in OTHER_UAVS:
        raise UnsupportedDesignError(
            f"{d.name}: a {OTHER_UAVS[d.uav]} is not a multirotor; build() makes Q, HEX and OCT vehicles "
            "(it needs an actuator model other than rotors)"
        )
    if d.n_uav > 1:
        raise UnsupportedDesignError(
            f"{d.name}: {d.n_uav} cooperating vehicles sharing an arm form a closed kinematic chain; supporting it needs "
            "loop-closure constraints (Pinocchio's constraint models with constrained forward dynamics) and an allocation "
            "across the vehicles"
        )
    if d.n_arms > 1:
        raise UnsupportedDesignError(
            f"{d.name}: {d.n_arms} arms make the kinematic tree branch at the base; supporting it needs one end-effector task "
            "per arm and arm-indexed efforts (the platform core assumes one serial arm)"
        )
    if "C" in d.joints:
        raise UnsupportedDesignError(f"{d.name}: cable joints (C) need a tension-only cable model, not a rigid joint")


@dataclass(frozen=True)
class LinkSpec:
    """One arm joint and the link after it (lengths [m], masses [kg], inertias about the CoM in link axes).

    ``inertia`` None: a homogeneous solid cylinder of ``radius`` along the link; ``com`` None:
    mid-length.  ``axis`` None: x for a P joint, y for an R joint.
    """

    kind: str
    length: float = 0.15
    mass: float = 0.1
    radius: float = 0.01
    lower: float | None = None
    upper: float | None = None
    effort: float | None = None
    velocity: float | None = None
    axis: tuple[float, float, float] | None = None
    inertia: tuple[float, float, float, float, float, float] | None = None
    com: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        as_name(self.kind, "kind", tuple(JOINTS), "joint letter")
        for name in ("length", "mass", "radius"):
            object.__setattr__(self, name, as_real(getattr(self, name), f"link {name}", positive=True))
        for name in ("lower", "upper"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, as_real(getattr(self, name), f"link {name}"))
        for name in ("effort", "velocity"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, as_real(getattr(self, name), f"link {name}", positive=True))
        if self.lower is not None and self.upper is not None and not self.lower <= self.upper:
            raise InputError(f"link lower limit {self.lower!r} is above its upper limit {self.upper!r}")
        for name, n in (("axis", 3), ("inertia", 6), ("com", 3)):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, tuple(as_vector(getattr(self, name), n, f"link {name}").tolist()))


_JOINT_DEFAULTS = {"P": (-0.05, 0.05, 20.0, 0.5), "R": (-2.0 * math.pi / 3.0, 2.0 * math.pi / 3.0, 5.0, 6.0)}
_UAV_DEFAULTS = {4: (1.5, 0.225), 6: (2.5, 0.3), 8: (3.5, 0.35)}  # (body mass [kg], arm length l [m])


def _cylinder_inertia(mass: float, radius: float, length: float) -> tuple[float, float, float, float, float, float]:
    ixx = mass * (3.0 * radius**2 + length**2) / 12.0
    return (ixx, ixx, 0.5 * mass * radius**2, 0.0, 0.0, 0.0)


def _body(n_rot: int, body_mass, body_inertia, arm_length, body_height) -> tuple:
    """(mass [kg], rotor distance l [m], inertia (ixx, iyy, izz, ixy, ixz, iyz) [kg m^2], height [m]) of the multirotor
    body of :func:`build`: the given values checked, the defaults of its rotor count otherwise (a solid disc)."""
    body_height = as_real(body_height, "body_height", positive=True, unit="m")
    default_mass, default_l = _UAV_DEFAULTS[n_rot]
    m_body = default_mass if body_mass is None else as_real(body_mass, "body_mass", positive=True, unit="kg")
    l_rot = default_l if arm_length is None else as_real(arm_length, "arm_length", positive=True, unit="m")
    if body_inertia is None:
        ixx = m_body * (3.0 * l_rot**2 + body_height**2) / 12.0
        return m_body, l_rot, (ixx, ixx, 0.5 * m_body * l_rot**2, 0.0, 0.0, 0.0), body_height
    return m_body, l_rot, tuple(as_vector(body_inertia, 6, "body_inertia").tolist()), body_height


def _arm(name: str, d, links, joint_names, link_names) -> list[tuple]:
    """(LinkSpec, joint name, link name) per joint of the arm of :func:`build`, checked against the name's joints."""
    n = len(d.joints)
    if links is not None and (isinstance(links, str) or not all(isinstance(k, LinkSpec) for k in links)):
        raise InputError(f"links must be a sequence of LinkSpec, got {links!r:.80}")
    links = [LinkSpec(k) for k in d.joints] if links is None else list(links)
    if len(links) != n or any(spec.kind != k for spec, k in zip(links, d.joints)):
        raise InputError(f"{name!r} needs {n} links of kinds {d.joints!r}, got {[s.kind for s in links]}")
    joint_names = list(joint_names) if joint_names is not None else [f"joint{i + 1}" for i in range(n)]
    link_names = list(link_names) if link_names is not None else [f"link{i + 1}" for i in range(n)]
    if len(joint_names) != n or len(link_names) != n:
        raise InputError(f"joint_names and link_names need {n} entries each")
    return list(zip(links, joint_names, link_names))


def _arm_parts(arm: list[tuple], base_name: str, ee_name: str, mount_xyz: tuple, sign: float) -> list[str]:
    """URDF links and joints of the arm (:func:`_arm`) from B's ``mount_xyz``, along +z (``sign`` 1) or -z, and the
    end-effector frame at its tip."""
    parts = []
    parent, origin = base_name, tuple(mount_xyz)
    for spec, jn, ln in arm:
        lo, hi, eff, vel = _JOINT_DEFAULTS[spec.kind]
        lo = lo if spec.lower is None else spec.lower
        hi = hi if spec.upper is None else spec.upper
        eff = eff if spec.effort is None else spec.effort
        vel = vel if spec.velocity is None else spec.velocity
        axis = spec.axis or ((1.0, 0.0, 0.0) if spec.kind == "P" else (0.0, 1.0, 0.0))
        inertia = spec.inertia or _cylinder_inertia(spec.mass, spec.radius, spec.length)
        com = spec.com or (0.0, 0.0, sign * spec.length / 2.0)
        visual = ug.cylinder_visual(spec.radius, spec.length, (0.0, 0.0, sign * spec.length / 2.0), rgba=(0.3, 0.3, 0.3, 1.0))
        parts.append(ug.link(ln, ug.inertial(spec.mass, com, inertia) + visual))
        kind = "prismatic" if spec.kind == "P" else "revolute"
        parts.append(ug.joint(jn, kind, parent, ln, origin, axis, (lo, hi, eff, vel)))
        parent, origin = ln, (0.0, 0.0, sign * spec.length)
    parts.append(ug.link(ee_name, ug.sphere_visual(0.015)))
    parts.append(ug.joint(f"{ee_name}_fixed", "fixed", parent, ee_name, origin))
    return parts


def _layout(name: str, d, layout) -> str:
    """The rotor layout of :func:`build`: the one given (checked against the name's), else the name's, else "plus"."""
    if layout is not None:
        as_name(layout, "layout", LAYOUTS, "rotor layout")
    layout = layout or d.layout or "plus"
    if d.layout is not None and layout != d.layout:
        raise InputError(f"{name!r} names the {d.layout!r} layout but layout={layout!r} was given")
    return layout


def _ring_settings(kappa, thrust_to_weight, f_min, tilt, g) -> tuple[float, float, float, float, float]:
    """The rotor ring's settings of :func:`build` checked: kappa [m], thrust-to-weight ratio, f_min [N], tilt [rad],
    g [m/s^2]."""
    return (
        as_real(kappa, "kappa", nonnegative=True, unit="m"),
        as_real(thrust_to_weight, "thrust_to_weight", positive=True),
        as_real(f_min, "f_min", nonnegative=True, unit="N"),
        as_real(tilt, "tilt", unit="rad"),
        as_real(g, "g", positive=True, unit="m/s^2"),
    )


def _names_and_direction(base_name: str, ee_name: str, platform_name, arm_direction: str) -> tuple[str, str, float]:
    """(base name, end-effector name, +1 for an arm along +z "up" or -1 "down") of :func:`build`, checked."""
    base_name, ee_name = ug.xml_name(base_name, "base_name"), ug.xml_name(ee_name, "ee_name")
    if platform_name is not None:
        ug.xml_name(platform_name, "platform_name")
    if arm_direction not in ("up", "down"):
        raise InputError(f"arm_direction must be 'up' or 'down', got {arm_direction!r}")
    return base_name, ee_name, 1.0 if arm_direction == "up" else -1.0


def _rotor_parts(name: str, rotor: Rotor, base_name: str) -> list[str]:
    """URDF link (a propeller disc) and fixed joint of one rotor frame in B, its z axis along the thrust."""
    return [
        ug.link(name, ug.cylinder_visual(0.127, 0.005, rgba=(0.2, 0.6, 0.2, 0.5))),
        ug.joint(f"{name}_fixed", "fixed", base_name, name, rotor.position_body, rpy=ug.rpy_of_axis(rotor.axis_body)),
    ]


@dataclass(frozen=True)
class BuildSpec:
    """How :func:`build` makes the platform a (2.1) name designates, beyond the name (SI units).

    layout : "plus" or "x" rotor ring (default: from the name, else "plus").
    links : one :class:`LinkSpec` per joint letter (default: 0.15 m, 0.1 kg solid cylinders of
        radius 1 cm; P joints +-0.05 m, 20 N, 0.5 m/s; R joints +-2pi/3, 5 N m, 6 rad/s).
    body_mass, body_inertia : the multirotor (default: Q 1.5 kg, HEX 2.5 kg, OCT 3.5 kg, a solid
        disc of radius ``arm_length`` and height ``body_height``).
    arm_length : rotor distance from z_B (default Q 0.225 m, HEX 0.3 m, OCT 0.35 m).
    mount_xyz : position of the first joint in B.  arm_direction : "up" (+z, the thesis) or "down".
    rotors : an explicit rotor set (overrides the ring); otherwise ``kappa`` [m] (0.016, a 10-inch
        propeller's drag ratio), ``f_min``, ``f_max = thrust_to_weight m g / n`` and ``tilt`` [rad]
        (alternating tilts about the rotor arms: ``tilt > 0`` on a HEX is fully actuated).
    g : gravity [m/s^2].  joint_names, link_names, base_name, ee_name : URDF names; platform_name : the
        platform's name (default: the designation).
    allow_nonphysical : skip the inertia checks (as :func:`qprr.model.from_urdf`), e.g. to
        rebuild a printed table that no rigid body has.
    """

    layout: str | None = None
    links: Sequence[LinkSpec] | None = None
    body_mass: float | None = None
    body_inertia: tuple[float, float, float, float, float, float] | None = None
    arm_length: float | None = None
    body_height: float = 0.1
    mount_xyz: tuple[float, float, float] = (0.0, 0.0, 0.04)
    arm_direction: str = "up"
    rotors: Sequence[Rotor] | None = None
    kappa: float = 0.016
    thrust_to_weight: float = 2.0
    f_min: float = 0.0
    tilt: float = 0.0
    g: float = 9.81
    joint_names: Sequence[str] | None = None
    link_names: Sequence[str] | None = None
    base_name: str = "base"
    ee_name: str = "end_effector"
    platform_name: str | None = None
    allow_nonphysical: bool = False

    def __post_init__(self) -> None:  # what needs no name to check, checked however the spec is built
        if self.layout is not None:
            as_name(self.layout, "layout", LAYOUTS, "rotor layout")
        as_real(self.body_height, "body_height", positive=True, unit="m")
        object.__setattr__(self, "mount_xyz", tuple(as_vector(self.mount_xyz, 3, "mount_xyz").tolist()))
        ring = _ring_settings(self.kappa, self.thrust_to_weight, self.f_min, self.tilt, self.g)
        for key, value in zip(("kappa", "thrust_to_weight", "f_min", "tilt", "g"), ring):
            object.__setattr__(self, key, value)
        _names_and_direction(self.base_name, self.ee_name, self.platform_name, self.arm_direction)
        rotors = self.rotors
        if rotors is not None and (isinstance(rotors, str) or not isinstance(rotors, Sequence) or not all(isinstance(r, Rotor) for r in rotors)):
            raise InputError(f"rotors must be a sequence of qprr.rotors.Rotor, got {rotors!r:.80}")


def build(name: str = "Q-PRR", spec: BuildSpec | None = None, **settings) -> Platform:
    """A platform of one multirotor and one serial arm from a (2.1) name (see the module docstring).

    ``name`` : "Q-PRR", "QX-PRR", "HEX-RRR", "OCT-RR", "Q-RRR", ...; ``spec`` : a :class:`BuildSpec` (None: its
    defaults) and/or its fields as keywords, which replace the spec's (``build("HEX-RRR", arm_length=0.3, tilt=0.3)``).
    """
    s = as_settings(spec, BuildSpec, "spec", **settings)
    d = parse(name)
    _check_buildable(d)
    n_rot = UAV_ROTORS[d.uav]
    layout = _layout(name, d, s.layout)
    body = _body(n_rot, s.body_mass, s.body_inertia, s.arm_length, s.body_height)
    mount_xyz = tuple(as_vector(s.mount_xyz, 3, "mount_xyz").tolist())
    kappa, thrust_to_weight, f_min, tilt, g = _ring_settings(s.kappa, s.thrust_to_weight, s.f_min, s.tilt, s.g)
    rotors = s.rotors
    base_name, ee_name, sign = _names_and_direction(s.base_name, s.ee_name, s.platform_name, s.arm_direction)
    arm = _arm(name, d, s.links, s.joint_names, s.link_names)
    parts = [
        ug.link(
            base_name,
            ug.inertial(body[0], (0.0, 0.0, 0.0), body[2]) + ug.cylinder_visual(0.3 * body[1], 0.4 * body[3], rgba=(0.55, 0.63, 0.75, 1.0)),
        )
    ]
    total_mass = body[0]
    for link, _, _ in arm:  # summed in this order: f_max below is the same to the last bit as before
        total_mass += link.mass
    parts += _arm_parts(arm, base_name, ee_name, mount_xyz, sign)
    if rotors is None:
        f_max = thrust_to_weight * total_mass * g / n_rot
        rotors = layout_rotors(n_rot, body[1], layout, kappa=kappa, f_min=f_min, f_max=f_max, tilt=tilt)
    for k, r in enumerate(rotors):  # a frame per rotor: its z axis is the thrust axis
        parts += _rotor_parts(f"rotor_{k + 1}", r, base_name)
    text = ug.robot(s.platform_name or d.name, parts, "qprr.nomenclature.build")
    prov = {
        "design": f"formula (2.1) name {d.name!r}: {n_rot} rotors ({layout}), arm {d.joints}",
        "defaults": "qprr.nomenclature.build keyword defaults (homogeneous bodies, Hypothesis 1 of Sec. 3.3.2)",
    }
    return from_urdf(
        text, tuple(rotors), ee_frame=ee_name, g=g, name=s.platform_name or d.name, params=d, provenance=prov, allow_nonphysical=s.allow_nonphysical
    )
