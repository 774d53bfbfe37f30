"""Issue 22 classes 2-4: implausible magnitudes (unit slips), URDF parts that were dropped, Pinocchio's generic errors.

Each mistake is made on the example quadrotor of docs/platforms.md (examples/my_platform) and must end in a qprr error
naming the element (link or joint), the attribute and, for a magnitude, the likely unit slip.  The plausibility
ranges can be widened on purpose with ``plausibility=``.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr.errors import InputError, NonPhysicalError, PlausibilityError, QprrError
from qprr.payload import Payload, with_payload
from qprr.urdf.plausibility import DEFAULT, Plausibility

ROOT = Path(__file__).resolve().parents[1]
URDF = (ROOT / "examples" / "my_platform" / "quad_rrr.urdf").read_text()
ROTORS = ROOT / "examples" / "my_platform" / "quad_rrr.rotors.toml"


def _load(text: str, rotors=ROTORS, **kw):
    return qprr.from_urdf(text, rotors, ee_frame="gripper", **kw)


def _sub(old: str, new: str, count: int = 1):
    def f(text: str) -> str:
        assert old in text, old
        return text.replace(old, new, count)

    return f


_EXTRA_LINK = '<link name="extra"><inertial><mass value="0.01"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial></link>'

XML_MISTAKES = {  # mistake -> (edit of the URDF, words the error must contain)
    "duplicate link name": (_sub("</robot>", _EXTRA_LINK.replace("extra", "turret") + "</robot>"), ["'turret'", "<link>", "unique"]),
    "duplicate joint name": (_sub('<joint name="elbow"', '<joint name="shoulder"'), ["'shoulder'", "<joint>", "unique"]),
    "nan in a limit": (_sub('lower="-2.0" upper="2.0"', 'lower="nan" upper="2.0"'), ["joint 'shoulder'", "<limit lower>", "'nan'"]),
    "nan in an axis": (_sub('<axis xyz="0 1 0"/>', '<axis xyz="0 nan 0"/>'), ["joint 'shoulder'", "<axis xyz>"]),
    "nan in an origin": (_sub('<origin xyz="0 0 -0.25"/>', '<origin xyz="0 0 nan"/>'), ["joint 'elbow'", "<origin xyz>"]),
    "two numbers in an origin": (_sub('<origin xyz="0 0 -0.25"/>', '<origin xyz="0 -0.25"/>'), ["joint 'elbow'", "<origin xyz>", "3 finite"]),
    "a missing effort": (_sub('effort="1.5" ', ""), ["joint 'elbow'", "<limit effort>", "missing"]),
    "a zero joint axis": (_sub('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>'), ["joint 'yaw'", "<axis xyz>", "zero vector"]),
    "a link with two parents": (
        _sub("</robot>", '<joint name="again" type="fixed"><parent link="base_link"/><child link="forearm"/></joint></robot>'),
        ["link 'forearm'", "two parents", "'elbow'", "'again'"],
    ),
    "a joint to a link that does not exist": (_sub('<child link="forearm"/>', '<child link="foream"/>'), ["'foream'", "joint 'elbow'"]),
    "a root link without <inertial>": (
        lambda t: t.replace(t[t.index("<inertial>") : t.index("</inertial>") + len("</inertial>")], "", 1),
        ["root link 'base_link'", "no <inertial>", "wrong total mass"],
    ),
}


@pytest.mark.parametrize("mistake", list(XML_MISTAKES))
def test_a_urdf_mistake_names_the_element_and_the_attribute(mistake):
    edit, words = XML_MISTAKES[mistake]
    with pytest.raises(QprrError) as exc:
        _load(edit(URDF))
    msg = str(exc.value)
    assert all(w in msg for w in words), f"{mistake}: {msg}"


UNIT_SLIPS = {  # mistake -> (edit of the URDF or of the rotor file, words of the error)
    "revolute limits in degrees": (
        _sub('lower="-2.0" upper="2.0"', 'lower="-150" upper="150"'),
        ["joint 'shoulder'", "<limit lower>", "degrees", "-2.61799 rad", "revolute_limit_max"],
    ),
    "an arm offset in millimetres": (
        _sub('<origin xyz="0 0 -0.25"/>', '<origin xyz="0 0 -250"/>'),
        ["joint 'elbow'", "<origin xyz>", "millimetres", "0.25 m", "length_max"],
    ),
    "a link mass in grams": (_sub('<mass value="0.10"/>', '<mass value="100"/>'), None),  # plausible (100 kg): the lift refuses it
    "a base mass in grams": (_sub('<mass value="1.20"/>', '<mass value="1200"/>'), ["link 'base_link'", "grams", "1.2 kg"]),
    "an inertia in kg mm^2": (
        _sub('ixx="5.21e-4" ixy="0" ixz="0" iyy="5.21e-4"', 'ixx="521" ixy="0" ixz="0" iyy="521"'),
        ["link 'upper_arm'", "radius of gyration", "kg mm^2"],
    ),
    "an effort in N mm": (_sub('effort="3.0"', 'effort="3000"'), ["joint 'shoulder'", "<limit effort>", "N mm", "3 N m"]),
}


@pytest.mark.parametrize("mistake", list(UNIT_SLIPS))
def test_an_implausible_magnitude_suggests_the_unit_slip(mistake):
    edit, words = UNIT_SLIPS[mistake]
    with pytest.raises(QprrError) as exc:
        _load(edit(URDF))
    msg = str(exc.value)
    if words is None:  # 100 kg is a possible link: the lift check says the rotors cannot carry it
        assert isinstance(exc.value, NonPhysicalError) and "cannot lift itself" in msg, msg
        return
    assert isinstance(exc.value, PlausibilityError) and all(w in msg for w in words), f"{mistake}: {msg}"


ROTOR_SLIPS = {
    "a drag/thrust ratio in millimetres": (("kappa = 0.016", "kappa = 16"), ["kappa", "millimetres", "0.016 m", "kappa_max"]),
    "thrust bounds in grams-force": (("f_max = 8.0", "f_max = 8000"), ["f_max", "grams-force", "78.45 N"]),
}


@pytest.mark.parametrize("mistake", list(ROTOR_SLIPS))
def test_a_rotor_file_in_the_wrong_unit_names_the_file_the_rotor_and_the_slip(tmp_path, mistake):
    (old, new), words = ROTOR_SLIPS[mistake]
    path = tmp_path / "rotors.toml"
    path.write_text(ROTORS.read_text().replace(old, new, 1))
    with pytest.raises(PlausibilityError) as exc:
        _load(URDF, path)
    msg = str(exc.value)
    assert "rotors.toml" in msg and "rotor 1" in msg and all(w in msg for w in words), msg


def test_plausibility_can_be_widened_on_purpose():
    """A robot whose shoulder turns +-3 turns: the revolute range is widened, the rest still checked."""
    text = _sub('lower="-2.0" upper="2.0"', 'lower="-18.8" upper="18.8"')(URDF)
    with pytest.raises(PlausibilityError):
        _load(text)
    platform = _load(text, plausibility=dataclasses.replace(DEFAULT, revolute_limit_max=20.0))
    assert platform.arm[1].upper == 18.8
    assert _load(text, plausibility=None).arm[1].lower == -18.8
    with pytest.raises(InputError, match="plausibility must be"):
        _load(URDF, plausibility={"revolute_limit_max": 20.0})
    with pytest.raises(InputError, match="revolute_limit_max must be a number > 0"):
        Plausibility(revolute_limit_max=-1.0)


def test_the_shipped_platforms_are_plausible():
    for name in ("q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5"):
        assert qprr.load(name).actuation_summary().can_hover


# ----------------------------------------------------------------------------------------------- payloads
def test_a_payload_the_rotors_cannot_lift_is_refused_with_a_grams_hint():
    p = qprr.load()
    lift = qprr.model.max_lift(p)  # 80 N for the thesis Q-PRR
    with pytest.raises(NonPhysicalError, match=r"payload mass 100 kg.*at most 80 N.*grams\? 100 g = 0.1 kg"):
        with_payload(p, 100.0)
    m_max = lift / p.g - p.total_mass
    assert with_payload(p, 0.99 * m_max).total_mass == pytest.approx(p.total_mass + 0.99 * m_max, rel=1e-12)


def test_with_payload_applies_the_inertia_checks_of_a_loaded_urdf():
    p = qprr.load()
    with pytest.raises(NonPhysicalError, match="payload: principal moments .* triangle inequality"):
        with_payload(p, Payload(0.2, (0.0, 0.0, 0.0), (1e-5, 1e-5, 3e-5, 0.0, 0.0, 0.0)))
    with pytest.raises(PlausibilityError, match="com_ee .* millimetres"):
        with_payload(p, Payload(0.2, (0.0, 0.0, 50.0)))
    with pytest.raises(PlausibilityError, match="radius of gyration"):
        with_payload(p, Payload(0.2, (0.0, 0.0, 0.0), (10.0, 10.0, 10.0, 0.0, 0.0, 0.0)))
    ok = with_payload(p, Payload.sphere(0.2, 0.03))
    assert ok.total_mass == pytest.approx(p.total_mass + 0.2, rel=1e-14)


def test_a_payload_that_moves_the_cog_beyond_the_rotors_cannot_hover():
    """A mass that the rotors lift (sum f_max >= m g) but far off the thrust axis: no thrusts inside the bounds balance it."""
    p = qprr.load()
    m = 0.5 * (qprr.model.max_lift(p) / p.g - p.total_mass)
    summary_ok = with_payload(p, Payload(m, (0.0, 0.0, 0.0))).actuation_summary()
    assert summary_ok.can_hover
    far = Payload(m, (1.5, 1.5, 1.5))  # 2.6 m from the end effector
    with pytest.raises(QprrError, match="cannot hover"):  # it lifts (above): the refusal is the hover's, not the lift's
        with_payload(p, far)
    assert math.isfinite(summary_ok.condition) and np.all(np.isfinite(summary_ok.hover_thrusts))


# ----------------------------------------------------------------------------------------------- the one reader
def test_the_reader_parses_once_what_pinocchio_loads():
    """qprr.urdf.reader.read_urdf: one parse gives every value the checks read, the same as the loaded model's
    (total mass, joint limits and efforts, the root link); a number that is not one is refused with the attribute."""
    from qprr.urdf.reader import attribute_numbers, read_urdf

    urdf = read_urdf(URDF, "quad_rrr.urdf")
    platform = _load(URDF)
    masses = [link.inertial.mass for link in urdf.links if link.inertial is not None]
    assert math.fsum(masses) == pytest.approx(platform.total_mass, rel=1e-14)
    moving = {j.name: j for j in urdf.joints if j.kind != "fixed"}
    for arm in platform.arm:
        j = moving[arm.name]
        assert (j.limit.lower, j.limit.upper, j.limit.effort, j.limit.velocity) == (arm.lower, arm.upper, arm.effort, arm.velocity)
    assert urdf.roots == (platform.model.frames[platform.base_frame].name,)
    assert attribute_numbers("0 0 -0.25") == (0.0, 0.0, -0.25) and attribute_numbers("0 x") is None and attribute_numbers(None) is None
    with pytest.raises(NonPhysicalError, match=r"link 'base_link' has a non-numeric mass or inertia \(<mass value> = '1.2kg'\)"):
        read_urdf(_sub('<mass value="1.20"/>', '<mass value="1.2kg"/>')(URDF))
    assert read_urdf(_sub('<mass value="1.20"/>', '<mass value="1.2kg"/>')(URDF), inertials=False).links[0].inertial.mass is None
