"""The one reader of a robot's URDF text: parsed once, every load-time check run on the result.

:func:`read_urdf` parses the XML with Python's parser (Pinocchio's own parser drops a malformed element silently or
reports it without naming it) into a :class:`UrdfFile`: its links with their inertials, its joints with their origin,
axis, limits and dynamics.  Each number is read by one parser, :func:`attribute_numbers`.  The checks, in order:

1. the structure (:func:`read_urdf` while it reads): a ``<robot>`` root, unique link and joint names, joints whose
   ``<parent>`` and ``<child>`` are links, one parent per link, finite numbers of the right count in every
   ``<origin xyz rpy>``, ``<axis xyz>``, ``<limit>`` and ``<dynamics>``, a non-zero axis, ``effort`` and
   ``velocity`` given and >= 0, ``damping`` and ``friction`` >= 0;
2. the magnitudes a real aerial robot has (:func:`qprr.urdf.plausibility.check_urdf`, the unit slips);
3. the shape qprr flies (:func:`check_serial_arm`): one root link (the multirotor body), 1-DOF revolute or
   prismatic joints with position limits, or fixed ones;
4. the inertials (:func:`check_inertials`): numbers that make a rigid body, on the root link and on every link a
   joint moves.

Each refusal raises a :class:`~qprr.errors.QprrError` naming the file, the element (link or joint) and the attribute.
:func:`qprr.model.from_urdf` reads every file through here.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, NonPhysicalError, UnknownNameError
from .inertia import check_rigid_body
from .plausibility import DEFAULT, Plausibility, check_plausibility_setting, check_urdf

INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
"""The attributes of ``<inertia>``, in the order of :attr:`Inertial.inertia`."""

ARM_JOINT_TYPES = ("revolute", "prismatic", "fixed")
"""The joint types of an arm qprr flies (the free-flyer joint of the body is added by qprr)."""

_MASSLESS = '<inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>'


def attribute_numbers(text: str | None) -> tuple[float, ...] | None:
    """The numbers of a URDF attribute's text (``"0 0 -0.25"`` -> ``(0.0, 0.0, -0.25)``); None when the attribute is
    absent or a part of it is not a number.  The one parser of URDF numbers: the checks decide what is acceptable."""
    if text is None:
        return None
    try:
        return tuple(float(part) for part in text.split())
    except ValueError:
        return None


def _one(text: str | None) -> float | None:
    """The number of a one-number attribute, None when absent or not exactly one number."""
    values = attribute_numbers(text)
    return values[0] if values is not None and len(values) == 1 else None


def _checked_numbers(el: ET.Element, attr: str, count: int, where: str, *, required: bool = False) -> tuple[float, ...] | None:
    """The ``count`` finite numbers of attribute ``attr`` of ``el`` (None when absent and not ``required``)."""
    text = el.get(attr)
    tag = f"<{el.tag} {attr}>"
    if text is None:
        if required:
            raise InputError(f"{where}: {tag} is missing")
        return None
    values = attribute_numbers(text)
    if values is None or len(values) != count or not all(math.isfinite(v) for v in values):
        want = "a finite number" if count == 1 else f"{count} finite numbers separated by spaces"
        raise InputError(f"{where}: {tag} = {text!r} must be {want}")
    return values


def _checked_number(el: ET.Element, attr: str, where: str, *, required: bool = False) -> float | None:
    values = _checked_numbers(el, attr, 1, where, required=required)
    return None if values is None else values[0]


# ============================================================================ what a URDF says
@dataclass(frozen=True)
class Origin:
    """An ``<origin>``: ``xyz`` [m] and ``rpy`` [rad] in the parent frame (None: the attribute is absent, 0)."""

    xyz: tuple[float, float, float] | None = None
    rpy: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class Inertial:
    """A link's ``<inertial>`` as written: ``mass`` [kg] and ``inertia`` (ixx, ixy, ixz, iyy, iyz, izz) [kg m^2] about
    the CoM in the inertial's axes.  ``None`` in them: absent or not a number (refused by :func:`check_inertials`, or
    kept for a non-physical study); ``has_mass``/``has_inertia``: whether the elements are there; ``text``: the
    attributes that are not numbers, as written (for the messages)."""

    origin: Origin
    mass: float | None
    inertia: tuple[float | None, ...]
    has_mass: bool
    has_inertia: bool
    text: str


@dataclass(frozen=True)
class UrdfLink:
    """A ``<link>``: its name and its inertial (None: it has none)."""

    name: str
    inertial: Inertial | None


@dataclass(frozen=True)
class Limit:
    """A ``<limit>`` of a 1-DOF joint: ``lower``/``upper`` [rad or m] (None: absent), ``effort`` [N m or N] and
    ``velocity`` [rad/s or m/s] (both required).  Fixed joints and unknown types keep None (Pinocchio ignores it)."""

    lower: float | None
    upper: float | None
    effort: float | None
    velocity: float | None


@dataclass(frozen=True)
class UrdfJoint:
    """A ``<joint>``: its ``kind`` (the ``type`` attribute), the links it joins, its origin, ``axis`` (in the joint
    frame) and ``limit`` (1-DOF joints only; None otherwise or absent), ``<dynamics>`` ``damping``/``friction``
    (None: absent)."""

    name: str
    kind: str | None
    parent: str
    child: str
    origin: Origin
    axis: tuple[float, float, float] | None
    limit: Limit | None
    damping: float | None
    friction: float | None


@dataclass(frozen=True)
class UrdfFile:
    """A URDF read once: ``source`` (the file or "URDF text", named in every message), ``name`` (the robot's),
    ``links`` and ``joints`` in the order written, and ``text`` (what Pinocchio's parser is given)."""

    source: str
    name: str
    links: tuple[UrdfLink, ...]
    joints: tuple[UrdfJoint, ...]
    text: str

    @property
    def link_names(self) -> tuple[str, ...]:
        return tuple(link.name for link in self.links)

    @property
    def roots(self) -> tuple[str, ...]:
        """The links no joint has as child (a URDF of a robot has one: the multirotor body)."""
        children = {j.child for j in self.joints}
        return tuple(name for name in self.link_names if name not in children)


def _checked_file(urdf) -> UrdfFile:
    if not isinstance(urdf, UrdfFile):
        raise InputError(f"urdf must be a qprr.urdf.reader.UrdfFile (read by parse_urdf), got {type(urdf).__name__} {urdf!r:.60}")
    return urdf


# ============================================================================ 1. structure
def _origin(el: ET.Element | None, where: str) -> Origin:
    origin = el.find("origin") if el is not None else None
    if origin is None:
        return Origin()
    return Origin(_checked_numbers(origin, "xyz", 3, where), _checked_numbers(origin, "rpy", 3, where))


def _unique_names(root: ET.Element, source: str) -> None:
    for tag in ("link", "joint"):
        seen: dict[str, int] = {}
        for k, el in enumerate(root.findall(tag)):
            name = el.get("name")
            if not name:
                raise InputError(f'{source}: <{tag}> number {k + 1} has no name="..."')
            if name in seen:
                raise InputError(
                    f"{source}: two <{tag}> elements are named {name!r} (numbers {seen[name] + 1} and {k + 1}); {tag} names must be unique"
                )
            seen[name] = k


def _ends(joint: ET.Element, links: set, where: str, source: str) -> tuple[str, str]:
    """(parent, child) link names of a joint, each a link of the file."""
    name = joint.get("name")
    ends = []
    for tag in ("parent", "child"):
        el = joint.find(tag)
        if el is None or el.get("link") is None:
            raise InputError(f'{where}: <{tag} link="..."/> is missing')
        if el.get("link") not in links:
            raise UnknownNameError(f"<{tag} link> of joint {name!r} in {source}", el.get("link"), tuple(sorted(links)))
        ends.append(el.get("link"))
    if ends[0] == ends[1]:
        raise InputError(f"{where}: <parent link> and <child link> are both {ends[0]!r}")
    return ends[0], ends[1]


def _axis_and_limit(joint: ET.Element, where: str) -> tuple[tuple | None, Limit | None]:
    """The axis (non-zero) and the limit (effort and velocity given, >= 0) of a 1-DOF joint."""
    axis = None
    axis_el = joint.find("axis")
    if axis_el is not None:
        axis = _checked_numbers(axis_el, "xyz", 3, where)
        if axis is not None and not math.hypot(*axis) > 1e-9:
            raise InputError(
                f"{where}: <axis xyz> = {axis_el.get('xyz')!r} is the zero vector; give the unit direction of "
                f'the joint axis in the joint frame, e.g. "0 0 1"'
            )
    limit = joint.find("limit")
    if limit is None:
        return axis, None
    lower, upper = (_checked_number(limit, attr, where) for attr in ("lower", "upper"))
    bounds = []
    for attr in ("effort", "velocity"):
        v = _checked_number(limit, attr, where, required=True)
        if v < 0.0:
            raise InputError(f"{where}: <limit {attr}> = {v!r} must be >= 0 (the largest |{attr}|)")
        bounds.append(v)
    return axis, Limit(lower, upper, *bounds)


def _dynamics(joint: ET.Element, where: str) -> tuple[float | None, float | None]:
    dyn = joint.find("dynamics")
    if dyn is None:
        return None, None
    values = []
    for attr in ("damping", "friction"):
        v = _checked_number(dyn, attr, where)
        if v is not None and v < 0.0:
            raise InputError(f"{where}: <dynamics {attr}> = {v!r} must be >= 0 (a passive joint {attr}, SI per radian or metre)")
        values.append(v)
    return values[0], values[1]


def _joint(joint: ET.Element, links: set, source: str) -> UrdfJoint:
    """One <joint> after checking its links, origin, axis, limit and dynamics attributes."""
    name, kind = joint.get("name"), joint.get("type")
    where = f"{source}: joint {name!r}"
    parent, child = _ends(joint, links, where, source)
    origin = _origin(joint, where)
    axis, limit = _axis_and_limit(joint, where) if kind in ("revolute", "prismatic", "continuous") else (None, None)
    damping, friction = _dynamics(joint, where)
    return UrdfJoint(name, kind, parent, child, origin, axis, limit, damping, friction)


def _inertial(link: ET.Element, source: str) -> Inertial | None:
    """A link's <inertial>: its origin checked here, its mass and inertia by :func:`check_inertials`."""
    el = link.find("inertial")
    if el is None:
        return None
    origin = _origin(el, f"{source}: link {link.get('name')!r}")
    mass_el, inertia_el = el.find("mass"), el.find("inertia")
    written = {"mass value": mass_el.get("value") if mass_el is not None else None}
    written.update({f"inertia {k}": inertia_el.get(k) if inertia_el is not None else None for k in INERTIA_KEYS})
    numbers = {key: _one(text) for key, text in written.items()}
    not_numbers = ", ".join(f"<{key}> = {written[key]!r}" for key, v in numbers.items() if v is None)
    inertia = tuple(numbers[f"inertia {k}"] for k in INERTIA_KEYS)
    return Inertial(origin, numbers["mass value"], inertia, mass_el is not None, inertia_el is not None, not_numbers)


def parse_urdf(xml_text: str, source: str = "URDF") -> UrdfFile:
    """The :class:`UrdfFile` of a URDF text after the structural checks (step 1 of the module docstring): raises
    :class:`~qprr.errors.InputError` naming the element (link or joint) and the attribute."""
    if not isinstance(xml_text, str):
        raise InputError(f"xml_text must be the URDF text (str), got {type(xml_text).__name__}")
    try:
        root = ET.fromstring(xml_text)
    except ET.ParseError as exc:
        raise InputError(f"{source} (xml_text) is not valid XML: {exc}") from exc
    if root.tag != "robot":
        raise InputError(f"{source}: the root element is <{root.tag}>, not <robot>: not a URDF")
    _unique_names(root, source)
    link_names = {el.get("name") for el in root.findall("link")}
    joints, parent_of = [], {}
    for el in root.findall("joint"):
        joint = _joint(el, link_names, source)
        if joint.child in parent_of:
            raise InputError(
                f"{source}: link {joint.child!r} has two parents: it is the <child> of joints {parent_of[joint.child]!r} and "
                f"{joint.name!r} (a URDF is a tree: each link has at most one parent joint)"
            )
        parent_of[joint.child] = joint.name
        joints.append(joint)
    links = tuple(UrdfLink(el.get("name"), _inertial(el, source)) for el in root.findall("link"))
    return UrdfFile(source, root.get("name", ""), links, tuple(joints), xml_text)


# ============================================================================ 3. the shape qprr flies
def check_serial_arm(urdf: UrdfFile) -> None:
    """One multirotor body (the root link) carrying 1-DOF joints: every joint ``revolute``, ``prismatic`` (both with
    ``<limit lower upper>``) or ``fixed``.  A ``floating``, ``planar`` or ``continuous`` joint raises
    :class:`~qprr.errors.InputError` naming the joint and saying what to write instead (qprr adds the free-flyer joint
    itself)."""
    source = _checked_file(urdf).source
    children = {j.child for j in urdf.joints}
    for joint in urdf.joints:
        name, kind = joint.name, joint.kind
        if kind in ("floating", "planar"):
            if joint.parent not in children:  # a "world" link holding the body
                raise InputError(
                    f"{source}: joint {name!r} is {kind}: qprr adds the multirotor's free-flyer joint itself; remove "
                    f"link {joint.parent!r} and joint {name!r} so that the multirotor body is the URDF's root link"
                )
            raise InputError(f"{source}: joint {name!r} is {kind}: not supported as an arm joint (1-DOF revolute or prismatic only)")
        if kind == "continuous":
            raise InputError(
                f"{source}: joint {name!r} is continuous (unbounded): not supported as an arm joint yet; make it "
                'type="revolute" with <limit lower="..." upper="..." effort="..." velocity="..."/>'
            )
        if kind not in ARM_JOINT_TYPES:
            raise UnknownNameError(f"type of joint {name!r} in {source}", kind, ARM_JOINT_TYPES)
        if kind != "fixed" and (joint.limit is None or joint.limit.lower is None or joint.limit.upper is None):
            raise InputError(
                f'{source}: {kind} joint {name!r} needs <limit lower="..." upper="..." effort="..." '
                f'velocity="..."/> ({"rad" if kind == "revolute" else "m"}, N{" m" if kind == "revolute" else ""})'
            )
    roots = list(urdf.roots)
    if len(roots) != 1:
        raise InputError(f"{source}: a URDF has exactly one root link (the multirotor body), found {len(roots)}: {roots}")


# ============================================================================ 4. inertials
def check_inertials(urdf: UrdfFile) -> None:
    """Every ``<inertial>`` a rigid body (Pinocchio's parser drops a malformed one silently): the mass and the six
    inertia entries numbers passing :func:`qprr.urdf.inertia.check_rigid_body`.  The root link (the multirotor body)
    and every link a joint moves need an ``<inertial>`` (explicit zeros for a massless one); else
    :class:`~qprr.errors.NonPhysicalError` naming the link."""
    source = _checked_file(urdf).source
    for link in urdf.links:
        inertial = link.inertial
        if inertial is None:
            continue
        if not (inertial.has_mass and inertial.has_inertia):
            raise NonPhysicalError(f"{source}: link {link.name!r} has an <inertial> without <mass> or <inertia>")
        if inertial.mass is None or None in inertial.inertia:
            raise NonPhysicalError(f"{source}: link {link.name!r} has a non-numeric mass or inertia ({inertial.text})")
        xx, xy, xz, yy, yz, zz = inertial.inertia
        I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        check_rigid_body(f"{source}: link {link.name!r}", inertial.mass, (0.0, 0.0, 0.0), I, allow_massless=True)
    with_inertial = {link.name for link in urdf.links if link.inertial is not None}
    roots = urdf.roots
    if len(roots) == 1 and roots[0] not in with_inertial:
        raise NonPhysicalError(
            f"{source}: the root link {roots[0]!r} (the multirotor body) has no <inertial>: Pinocchio would "
            "load the body massless and the platform with the wrong total mass; give its mass and inertia, or an "
            f"explicit {_MASSLESS} when the body's mass sits on links fixed to it"
        )
    for joint in urdf.joints:
        if joint.kind != "fixed" and joint.child not in with_inertial:
            raise NonPhysicalError(
                f"{source}: link {joint.child!r}, moved by joint {joint.name!r}, has no <inertial> "
                f"(Pinocchio would make it massless); give its mass and inertia, or write an explicit {_MASSLESS} "
                "for a link that is massless on purpose"
            )


# ============================================================================ all of them
def read_urdf(xml_text: str, source: str = "URDF", *, plausibility: Plausibility | None = DEFAULT, inertials: bool = True) -> UrdfFile:
    """A URDF text parsed once and checked (the module docstring's steps 1-4, in that order): its :class:`UrdfFile`.

    ``plausibility``: the ranges of the magnitudes (:class:`~qprr.urdf.plausibility.Plausibility`; None: no range
    check).  ``inertials=False`` skips step 4 (a non-physical table studied on purpose)."""
    plausibility = check_plausibility_setting(plausibility)
    urdf = parse_urdf(xml_text, source)
    check_urdf(urdf, plausibility)
    check_serial_arm(urdf)
    if inertials:
        check_inertials(urdf)
    return urdf


__all__ = [
    "ARM_JOINT_TYPES",
    "INERTIA_KEYS",
    "Inertial",
    "Limit",
    "Origin",
    "UrdfFile",
    "UrdfJoint",
    "UrdfLink",
    "attribute_numbers",
    "check_inertials",
    "check_serial_arm",
    "parse_urdf",
    "read_urdf",
]
