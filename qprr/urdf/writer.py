"""Small URDF writer: links with inertials and primitive visuals, joints, and a robot around them.

Each primitive visual also writes a ``<collision>`` element with the same origin and geometry (``collision=True``,
the default), so the generated robots carry the collision model :mod:`qprr.analysis.collision` reads.

Numbers are written with ``repr`` so a URDF read back gives the same doubles.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ..errors import InputError
from ..validation import as_array, as_real, as_vector


def num(x: float, name: str = "x") -> str:
    """A finite real number as its exact ``repr`` (InputError naming ``name`` otherwise)."""
    return repr(as_real(x, name))


def vec(v, name: str = "v", n: int | None = None) -> str:
    """A 1-D vector of finite numbers (``n`` of them when given), space-separated."""
    a = as_vector(v, n, name) if n is not None else as_array(v, name, finite=True, ndim=1)
    if a.size == 0:
        raise InputError(f"{name} must hold at least one number, got an empty vector")
    return " ".join(repr(x) for x in a.tolist())


def _rgba(rgba) -> tuple[str, str]:
    """(material name, rgba text) of a colour: 4 numbers in [0, 1]."""
    c = as_vector(rgba, 4, "rgba")
    if c.min() < 0.0 or c.max() > 1.0:
        raise InputError(f"rgba must be 4 numbers in [0, 1], got {c.tolist()}")
    return "c" + "".join(f"{int(255 * x):02x}" for x in c[:3]), vec(c)


def xml_name(x, name: str) -> str:
    """``x`` if it can name a URDF link, joint or robot (a non-empty string without <, >, quotes or &)."""
    if not isinstance(x, str) or not x or any(ch in x for ch in '<>"&'):
        raise InputError(f"{name} must be a non-empty XML name, got {x!r}")
    return x


def inertial(mass: float, com, inertia6) -> str:
    """``<inertial>`` of a body: mass [kg], CoM [m] and (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) about the CoM [kg m^2]."""
    ixx, iyy, izz, ixy, ixz, iyz = as_vector(inertia6, 6, "inertia6").tolist()
    return (
        "    <inertial>\n"
        f'      <origin xyz="{vec(com, "com", 3)}" rpy="0 0 0"/>\n'
        f'      <mass value="{num(as_real(mass, "mass", nonnegative=True), "mass")}"/>\n'
        f'      <inertia ixx="{num(ixx)}" ixy="{num(ixy)}" ixz="{num(ixz)}" iyy="{num(iyy)}" iyz="{num(iyz)}" izz="{num(izz)}"/>\n'
        "    </inertial>\n"
    )


def _shape(origin: str, geometry: str, material: str, color: str, collision: bool) -> str:
    """A ``<visual>`` (and, with ``collision``, a ``<collision>`` of the same origin and geometry)."""
    if not isinstance(collision, bool):
        raise InputError(f"collision must be a bool, got {collision!r}")
    out = (
        "    <visual>\n"
        f"      {origin}\n"
        f"      <geometry>{geometry}</geometry>\n"
        f'      <material name="{material}"><color rgba="{color}"/></material>\n'
        "    </visual>\n"
    )
    if collision:
        out += f"    <collision>\n      {origin}\n      <geometry>{geometry}</geometry>\n    </collision>\n"
    return out


def cylinder_visual(
    radius: float, length: float, xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0), rgba=(0.6, 0.6, 0.6, 1.0), *, collision: bool = True
) -> str:
    """``<visual>`` (and ``<collision>``) of a cylinder along the local z axis (after ``rpy``) centred at ``xyz``."""
    material, color = _rgba(rgba)
    radius, length = as_real(radius, "radius", positive=True), as_real(length, "length", positive=True)
    return _shape(
        f'<origin xyz="{vec(xyz, "xyz", 3)}" rpy="{vec(rpy, "rpy", 3)}"/>',
        f'<cylinder radius="{num(radius)}" length="{num(length)}"/>',
        material,
        color,
        collision,
    )


def box_visual(size, xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0), rgba=(0.6, 0.6, 0.6, 1.0), *, collision: bool = True) -> str:
    """``<visual>`` (and ``<collision>``) of a box of side lengths ``size`` (3,) [m] centred at ``xyz``."""
    material, color = _rgba(rgba)
    if as_vector(size, 3, "size").min() <= 0.0:
        raise InputError(f"size must be 3 positive lengths [m], got {list(size)!r}")
    return _shape(
        f'<origin xyz="{vec(xyz, "xyz", 3)}" rpy="{vec(rpy, "rpy", 3)}"/>', f'<box size="{vec(size, "size", 3)}"/>', material, color, collision
    )


def rpy_of_axis(axis) -> tuple[float, float, float]:
    """Roll-pitch-yaw (URDF convention) of a frame whose z axis is ``axis`` (a unit vector)."""
    ax, ay, az = as_vector(axis, 3, "axis").tolist()
    norm = math.sqrt(ax * ax + ay * ay + az * az)
    if not abs(norm - 1.0) < 1e-6:
        raise InputError(f"axis must be a unit vector, got {[ax, ay, az]} of norm {norm!r}")
    # z = Rz(yaw) Ry(pitch) Rx(roll) e3 with yaw = 0: (cos r sin p, -sin r, cos r cos p)
    roll = math.asin(max(-1.0, min(1.0, -ay)))
    pitch = math.atan2(ax, az)
    return (roll, pitch, 0.0)


def sphere_visual(radius: float, xyz=(0.0, 0.0, 0.0), rgba=(0.8, 0.2, 0.2, 1.0), *, collision: bool = True) -> str:
    """``<visual>`` (and ``<collision>``) of a sphere of ``radius`` [m] centred at ``xyz``."""
    material, color = _rgba(rgba)
    radius = as_real(radius, "radius", positive=True)
    return _shape(f'<origin xyz="{vec(xyz, "xyz", 3)}" rpy="0 0 0"/>', f'<sphere radius="{num(radius)}"/>', material, color, collision)


def link(name: str, inner: str = "") -> str:
    """``<link>`` named ``name`` around the XML ``inner``."""
    if not isinstance(inner, str):
        raise InputError(f"inner must be XML text, got {type(inner).__name__}")
    return f'  <link name="{xml_name(name, "name")}">\n{inner}  </link>\n'


def joint(name: str, kind: str, parent: str, child: str, xyz, axis=None, limits=None, rpy=(0.0, 0.0, 0.0)) -> str:
    """``<joint>``; ``limits`` = (lower, upper, effort, velocity)."""
    kinds = ("fixed", "prismatic", "revolute", "continuous", "floating", "planar")
    if kind not in kinds:
        from ..errors import UnknownNameError

        raise UnknownNameError("joint kind", kind, kinds)
    s = f'  <joint name="{xml_name(name, "name")}" type="{kind}">\n'
    s += f'    <parent link="{xml_name(parent, "parent")}"/>\n    <child link="{xml_name(child, "child")}"/>\n'
    s += f'    <origin xyz="{vec(xyz, "xyz", 3)}" rpy="{vec(rpy, "rpy", 3)}"/>\n'
    if axis is not None:
        s += f'    <axis xyz="{vec(axis, "axis", 3)}"/>\n'
    if limits is not None:
        lo, hi, effort, velocity = as_vector(limits, 4, "limits").tolist()
        if not lo <= hi or effort <= 0.0 or velocity <= 0.0:
            raise InputError(f"limits must be (lower <= upper, effort > 0, velocity > 0), got {tuple(limits)!r}")
        s += f'    <limit lower="{num(lo)}" upper="{num(hi)}" effort="{num(effort)}" velocity="{num(velocity)}"/>\n'
    return s + "  </joint>\n"


def robot(name: str, parts: Sequence[str], generator: str) -> str:
    """The URDF document of robot ``name`` around the ``parts`` (links and joints)."""
    if isinstance(parts, str) or not isinstance(parts, Sequence) or not all(isinstance(p, str) for p in parts):
        raise InputError("parts must be a sequence of XML strings (links and joints)")
    if not isinstance(generator, str):
        raise InputError(f"generator must be a string, got {generator!r}")
    xml_name(name, "name")
    head = ['<?xml version="1.0"?>\n', f"<!-- Generated by {generator}: do not edit by hand. -->\n", f'<robot name="{name}">\n']
    return "".join(head) + "".join(parts) + "</robot>\n"
