"""Bad-input catalogue over the files a user writes: URDFs and rotor descriptions (issue 22; engine of tests/test_catalogue.py).

:mod:`tests.catalogue` feeds bad *Python arguments*; this module feeds bad *files*.  From a valid URDF and its rotor
file (examples/my_platform, the page docs/platforms.md walks through) it generates one variant per element and per
mistake - every joint's origin, axis and limit attributes (NaN, a missing or malformed number, a zero axis, degrees,
millimetres, a missing effort), every link's name, inertial and mass (duplicates, grams, a root without
``<inertial>``), the tree (a second parent, an unknown child), every rotor's values (millimetres, grams-force) and
the rotor set (same spins, zero kappa, one line, centre, too few, a table pasted twice) - and loads each with
:func:`qprr.from_urdf`.  A variant is ``good`` when it ends in a :class:`qprr.errors.QprrError` whose message names
the element (joint, link, or rotor and file); ``unclear`` for a qprr error that does not, ``silent`` when it loads,
``crash`` for any other exception.  :func:`valid_variants` are near-mistakes that are legitimate and must load.
"""

from __future__ import annotations

import math
import re
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "examples" / "my_platform" / "quad_rrr.urdf"
ROTORS = ROOT / "examples" / "my_platform" / "quad_rrr.rotors.toml"
EE = "gripper"

VALID_BY_DESIGN = (
    "coaxial pairs: the rotor table repeated 8 cm higher with the other spins (an X8)",
    "a massless root link (explicit zero <inertial>) with the body's mass on a link fixed to it",
    "revolute limits of +-pi",
    "a plausible link mass the rotors cannot lift is refused by the lift check, which names the heaviest link",
)
"""Variants near a mistake that are legitimate: :func:`valid_variants` builds the first three, they must load."""


@dataclass(frozen=True)
class Variant:
    label: str
    element: str  # the name the error must contain
    urdf: str
    rotors: str


@dataclass(frozen=True)
class FileOutcome:
    label: str
    verdict: str
    detail: str


def _edit_attr(text: str, tag: str, name: str, child: str, attr: str, value: str | None) -> str:
    """``text`` with attribute ``attr`` of the ``<child>`` of ``<tag name=name>`` set to ``value`` (None: removed)."""
    root = ET.fromstring(text)
    el = next(e for e in root.findall(tag) if e.get("name") == name)
    target = el
    for part in child.split("/"):
        target = target.find(part)
    if value is None:
        del target.attrib[attr]
    else:
        target.set(attr, value)
    return ET.tostring(root, encoding="unicode")


def _urdf_variants(text: str) -> Iterator[tuple[str, str, str]]:
    root = ET.fromstring(text)
    for joint in root.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        if joint.find("origin") is not None:
            xyz = [float(x) for x in joint.find("origin").get("xyz").split()]
            for bad, what in (("nan 0 0", "NaN"), ("0 0", "two numbers"), ("a b c", "text"), ("inf 0 0", "inf")):
                yield f"joint {name!r} <origin xyz> {what}", name, _edit_attr(text, "joint", name, "origin", "xyz", bad)
            if math.hypot(*xyz) > 0.0:
                mm = " ".join(f"{1000 * x:g}" for x in xyz)
                yield f"joint {name!r} <origin xyz> in millimetres", name, _edit_attr(text, "joint", name, "origin", "xyz", mm)
        if kind in ("revolute", "prismatic"):
            for bad, what in (("0 0 0", "zero"), ("nan 0 1", "NaN"), ("0 1", "two numbers")):
                yield f"joint {name!r} <axis xyz> {what}", name, _edit_attr(text, "joint", name, "axis", "xyz", bad)
            lim = joint.find("limit")
            for attr in ("lower", "upper"):
                yield f"joint {name!r} <limit {attr}> NaN", name, _edit_attr(text, "joint", name, "limit", attr, "nan")
                deg = f"{math.degrees(float(lim.get(attr))):g}"
                yield f"joint {name!r} <limit {attr}> in degrees", name, _edit_attr(text, "joint", name, "limit", attr, deg)
            for attr in ("effort", "velocity"):
                yield f"joint {name!r} <limit {attr}> missing", name, _edit_attr(text, "joint", name, "limit", attr, None)
                yield f"joint {name!r} <limit {attr}> NaN", name, _edit_attr(text, "joint", name, "limit", attr, "nan")
                yield f"joint {name!r} <limit {attr}> negative", name, _edit_attr(text, "joint", name, "limit", attr, "-1")
            for bad, what in (("nan", "NaN"), ("stiff", "text"), ("0.1 0.2", "two numbers"), ("-0.1", "negative")):
                dyn = ET.fromstring(text)
                j = next(e for e in dyn.findall("joint") if e.get("name") == name)
                ET.SubElement(j, "dynamics", damping=bad, friction="0.1")
                yield f"joint {name!r} <dynamics damping> {what}", name, ET.tostring(dyn, encoding="unicode")
            yield (
                f"joint {name!r} <limit effort> in N mm",
                name,
                _edit_attr(text, "joint", name, "limit", "effort", f"{1e6 * float(lim.get('effort')):g}"),
            )
        dup = ET.tostring(joint, encoding="unicode").replace(f'<child link="{joint.find("child").get("link")}"', '<child link="extra"', 1)
        extra = (
            '<link name="extra"><inertial><mass value="0.01"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial></link>'
        )
        yield f"joint {name!r} name twice", name, text.replace("</robot>", dup + extra + "</robot>")
        yield (f"joint {name!r} <child> unknown", name, _edit_attr(text, "joint", name, "child", "link", joint.find("child").get("link") + "_typo"))
        child = joint.find("child").get("link")
        second = f'<joint name="second_{name}" type="fixed"><parent link="{root.find("link").get("name")}"/><child link="{child}"/></joint>'
        if joint.find("parent").get("link") != root.find("link").get("name"):
            yield f"link {child!r} with two parents", child, text.replace("</robot>", second + "</robot>")
    for k, link in enumerate(root.findall("link")):
        name = link.get("name")
        copy = f'<link name="{name}"/>'
        yield f"link {name!r} name twice", name, text.replace("</robot>", copy + "</robot>")
        inertial = link.find("inertial")
        if inertial is not None:
            mass = float(inertial.find("mass").get("value"))
            yield (f"link {name!r} <mass> in grams", name, _edit_attr(text, "link", name, "inertial/mass", "value", f"{1000 * mass:g}"))
            yield f"link {name!r} <mass> NaN", name, _edit_attr(text, "link", name, "inertial/mass", "value", "nan")
            if k == 0:
                t = ET.fromstring(text)
                t.find("link").remove(t.find("link").find("inertial"))
                yield f"root link {name!r} without <inertial>", name, ET.tostring(t, encoding="unicode")


def _mm(m: re.Match) -> str:
    return "position = [" + ", ".join(f"{1000 * float(x):g}" for x in m.group(1).split(",")) + "]"


def _rotor_variants(text: str) -> Iterator[tuple[str, str, str]]:
    n = text.count("[[rotor]]")
    kappa_mm = re.sub(r"^kappa = ([\d.]+)", lambda m: f"kappa = {1000 * float(m.group(1)):g}", text, count=1, flags=re.M)
    yield "kappa in millimetres", "kappa", kappa_mm
    gf = re.sub(r"^f_max = ([\d.]+)", lambda m: f"f_max = {float(m.group(1)) * 1000 / 9.80665:.6g}", text, count=1, flags=re.M)
    yield "f_max in grams-force", "grams-force", gf
    yield "every rotor spins cw", "same spin", text.replace('"ccw"', '"cw"')
    yield "every kappa zero", "kappa is 0", re.sub(r"^kappa = [\d.]+", "kappa = 0.0", text, count=1, flags=re.M)
    head, *rotors = text.split("[[rotor]]")
    yield "a single rotor", "rotor", head + "[[rotor]]" + rotors[0]
    yield "three rotors", "rotor", head + "[[rotor]]" + "[[rotor]]".join(rotors[:3])
    yield "the rotor table pasted twice", "written twice", text + "\n" + "[[rotor]]" + "[[rotor]]".join(rotors)
    heights = iter(range(1, n + 1))
    yield "rotors at the centre", "rotor", re.sub(r"position = \[[^\]]*\]", lambda m: f"position = [0.0, 0.0, {0.03 * next(heights):g}]", text)
    yield (
        "rotors on one line",
        "one line",
        re.sub(r"position = \[([-\d.]+), ([-\d.]+), ([-\d.]+)\]", lambda m: f"position = [{m.group(1)}, 0.0, {m.group(3)}]", text),
    )
    yield "positions in millimetres", "rotor 1", re.sub(r"position = \[([-\d., ]+)\]", _mm, text)
    raw = re.sub(r"^kappa = [\d.]+", "kappa = 1.3677728e-7", text, count=1, flags=re.M)
    yield "kappa a raw drag coefficient (N m s^2)", "kappa_min", raw
    yield "radius in millimetres", "radius", text.replace("[[rotor]]", "[[rotor]]\nradius = 120.0", 1)
    x8 = coaxial(text)
    head, *tables = x8.split("[[rotor]]")
    down = tables[:-1] + [tables[-1].replace("spin =", "axis = [0.0, 0.0, -1.0]\nspin =", 1)]
    yield "a coaxial lower rotor pointing down", "against the collective thrust", head + "[[rotor]]" + "[[rotor]]".join(down)


def variants() -> list[Variant]:
    urdf, rotors = URDF.read_text(), ROTORS.read_text()
    out = [Variant(f"URDF: {label}", element, t, rotors) for label, element, t in _urdf_variants(urdf)]
    out += [Variant(f"rotor file: {label}", element, urdf, t) for label, element, t in _rotor_variants(rotors)]
    return out


def judge_file(variant: Variant, load: Callable) -> FileOutcome:
    import qprr.errors as errors

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bad.rotors.toml"
        path.write_text(variant.rotors)
        try:
            load(variant.urdf, path)
        except errors.QprrError as exc:
            msg = str(exc)
            named = variant.element in msg and (not variant.label.startswith("rotor file") or "bad.rotors.toml" in msg)
            return FileOutcome(variant.label, "good" if named else "unclear", f"{type(exc).__name__}: {msg[:300]}")
        except Exception as exc:
            return FileOutcome(variant.label, "crash", f"{type(exc).__name__}: {exc}"[:300])
    return FileOutcome(variant.label, "silent", "loaded")


def run_files() -> list[FileOutcome]:
    import warnings

    import qprr

    def load(urdf: str, rotors: Path):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return qprr.from_urdf(urdf, rotors, ee_frame=EE)

    return [judge_file(v, load) for v in variants()]


def coaxial(rotors: str) -> str:
    """The rotor file ``rotors`` made an X8: every rotor table repeated 8 cm higher with the other spin."""
    head, *tables = rotors.split("[[rotor]]")
    upper = [
        re.sub(
            r"position = \[([-\d.]+), ([-\d.]+), ([-\d.]+)\]", lambda m: f"position = [{m.group(1)}, {m.group(2)}, {float(m.group(3)) + 0.08:g}]", t
        )
        for t in tables
    ]
    upper = [t.replace('"cw"', '"x"').replace('"ccw"', '"cw"').replace('"x"', '"ccw"') for t in upper]
    return rotors + "\n[[rotor]]" + "[[rotor]]".join(upper)


def valid_variants() -> list[Variant]:
    """The first three entries of :data:`VALID_BY_DESIGN`, as files."""
    urdf, rotors = URDF.read_text(), ROTORS.read_text()
    x8 = coaxial(rotors)
    root = ET.fromstring(urdf)
    base = root.find("link")
    body = ET.SubElement(root, "link", name="body_mass")
    inertial = base.find("inertial")
    base.remove(inertial)
    body.append(inertial)
    zero = ET.fromstring('<inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>')
    base.append(zero)
    joint = ET.SubElement(root, "joint", name="body_fixed", type="fixed")
    ET.SubElement(joint, "parent", link=base.get("name"))
    ET.SubElement(joint, "child", link="body_mass")
    massless_root = ET.tostring(root, encoding="unicode")
    pi_limits = _edit_attr(_edit_attr(urdf, "joint", "yaw", "limit", "lower", "-3.14159"), "joint", "yaw", "limit", "upper", "3.14159")
    return [Variant("X8 coaxial", "", urdf, x8), Variant("massless root", "", massless_root, rotors), Variant("+-pi limits", "", pi_limits, rotors)]
