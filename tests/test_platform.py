"""Loading a platform: every bad physical input or name is refused with a message naming it (issue 16, items 2-3).

Physics: a mass and a rotational inertia about the CoM belong to a rigid body iff the mass is
>= 0 and the second moments of mass int x_i^2 dm are >= 0, i.e. the principal moments are
>= 0 and satisfy the triangle inequalities I_a + I_b >= I_c.  Random point clouds (real bodies)
always pass; moments breaking a triangle inequality never do.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
import qprr.thesis
from qprr.errors import InputError, NonPhysicalError, UnknownNameError
from qprr.model import from_model, from_urdf
from qprr.thesis.urdf import URDF_PATH, build_urdf
from qprr.urdf.inertia import check_rigid_body

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)
P = qprr.thesis.thesis_params()
ROTORS = qprr.thesis.rotor_set(P)
TEXT = build_urdf()


def _load(text, **kw):
    kw.setdefault("ee_frame", "end_effector")
    return from_urdf(text, ROTORS, **kw)


def _with_mass(text: str, body: str, value: str) -> str:
    """The URDF with the mass of link ``body`` replaced by the string ``value``."""
    pattern = rf'(<link name="{body}">.*?<mass value=")[^"]*(")'
    out, n = re.subn(pattern, rf"\g<1>{value}\g<2>", text, count=1, flags=re.S)
    assert n == 1
    return out


# ------------------------------------------------------------------- rigid-body inertia
@SETTINGS
@given(st.integers(1, 40), st.integers(0, 2**32 - 1))
def test_every_point_cloud_is_a_rigid_body(n, seed):
    """Masses m_k at points x_k: the inertia about their CoM passes the check (and a mirror copy too)."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.01, 2.0, n)
    x = rng.normal(0.0, rng.uniform(0.01, 1.0), (n, 3)) * rng.uniform(0.0, 1.0, 3)  # flat and thin clouds too
    c = m @ x / m.sum()
    d = x - c
    I = sum(mk * ((dk @ dk) * np.eye(3) - np.outer(dk, dk)) for mk, dk in zip(m, d))
    check_rigid_body("cloud", float(m.sum()), c, I)
    np.testing.assert_allclose(pin.Inertia(float(m.sum()), c, I).inertia, I, atol=1e-15)  # Pinocchio takes it as given


@SETTINGS
@given(st.floats(1e-6, 1.0), st.floats(1e-6, 1.0), st.floats(1.0001, 3.0), st.integers(0, 2**32 - 1))
def test_moments_breaking_the_triangle_inequality_are_refused(a, b, excess, seed):
    """Principal moments a, b, c with c > a + b (a negative second moment of mass), in any orientation."""
    c = excess * (a + b)
    R = pin.exp3(np.random.default_rng(seed).normal(size=3))
    I = R @ np.diag([a, b, c]) @ R.T
    with pytest.raises(NonPhysicalError, match="triangle inequality"):
        check_rigid_body("rod", 1.0, (0.0, 0.0, 0.0), I)


@pytest.mark.parametrize(
    "mass, inertia, match",
    [
        (float("nan"), np.eye(3), "mass must be finite"),
        (-0.1, np.eye(3), "mass must be finite and >= 0"),
        (math.inf, np.eye(3), "mass must be finite"),
        (1.0, np.diag([1.0, 1.0, -0.5]), "not positive semi-definite"),
        (1.0, np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "symmetric"),
        (1.0, np.full((3, 3), np.nan), "finite 3x3"),
        (0.0, np.eye(3), "massless body"),
    ],
)
def test_bad_inertials_name_the_body(mass, inertia, match):
    with pytest.raises(NonPhysicalError, match=match) as exc:
        check_rigid_body("link7", mass, (0.0, 0.0, 0.0), inertia, allow_massless=True)
    assert "link7" in str(exc.value)
    assert isinstance(exc.value, ValueError)


# ------------------------------------------------------------------------ URDF inertials
@pytest.mark.parametrize("value, match", [("abc", "non-numeric mass"), ("nan", "mass must be finite"), ("-1.0", ">= 0 kg")])
def test_bad_urdf_mass_is_refused_not_dropped(value, match):
    """Pinocchio's parser alone drops an inertial whose mass is not a number: the dynamics would then use the
    arm alone (0.49 kg instead of 3.52 kg).  The platform refuses it, naming the link."""
    text = _with_mass(TEXT, "multirotor", value)
    with pytest.raises(NonPhysicalError, match=match) as exc:
        _load(text)
    assert "multirotor" in str(exc.value)


def test_urdf_with_a_non_physical_link_is_refused_unless_asked():
    printed = qprr.thesis.thesis_params(table_3_2="printed-nonphysical")
    i2 = printed.links[1].inertia  # Table 3.2's link 2 as printed: 2.274e-5 + 2.2767e-5 < 5.013e-5 kg m^2
    assert i2[0] + i2[2] < i2[1]
    text = build_urdf(printed)
    with pytest.raises(NonPhysicalError, match="link2.*triangle inequality"):
        _load(text)
    platform = _load(text, allow_nonphysical=True)
    assert "WARNING" in platform.provenance


def test_total_mass_is_the_sum_of_the_urdf_masses():
    masses = [float(m) for m in re.findall(r'<mass value="([^"]*)"', TEXT)]
    platform = _load(TEXT, allow_nonphysical=True)
    assert platform.total_mass == pytest.approx(sum(masses), rel=1e-15)
    assert platform.total_mass == pytest.approx(P.total_mass, rel=1e-15)


# ------------------------------------------------------------------------- arm joints
def _joint(text: str, name: str, new_type: str) -> str:
    return text.replace(f'<joint name="{name}" type="revolute">', f'<joint name="{name}" type="{new_type}">')


def test_reversed_joint_limits_are_refused():
    text = TEXT.replace('lower="-0.04" upper="0.04"', 'lower="0.04" upper="-0.04"')
    with pytest.raises(InputError, match=r"joint 'r0': lower limit 0.04 is above the upper limit -0.04"):
        _load(text, allow_nonphysical=True)


@pytest.mark.parametrize("kind, match", [("continuous", "continuous"), ("floating", "not supported"), ("planar", "not supported")])
def test_unsupported_arm_joint_types_are_named(kind, match):
    with pytest.raises(InputError, match=match) as exc:
        _load(_joint(TEXT, "theta3", kind), allow_nonphysical=True)
    assert "theta3" in str(exc.value)


def test_massless_arm_link_makes_a_singular_mass_matrix_and_is_refused():
    model = qprr.thesis.load_qprr().model
    massless = pin.Model(model)
    massless.inertias[4] = pin.Inertia.Zero()  # link 3 (theta3) carries nothing
    with pytest.raises(NonPhysicalError, match="theta3.*moves no mass"):
        from_model(massless, ROTORS, ee_frame="end_effector", allow_nonphysical=True)


# --------------------------------------------------------------------------------- names
def test_unknown_end_effector_frame_lists_the_frames():
    with pytest.raises(UnknownNameError, match="unknown ee_frame 'gripper'; valid: .*'end_effector'") as exc:
        _load(TEXT, ee_frame="gripper", allow_nonphysical=True)
    assert isinstance(exc.value, KeyError)
    assert "'link3'" in str(exc.value) and "'rotor_plus_1'" in str(exc.value)


def test_unknown_rotor_frame_lists_the_frames():
    desc = {"defaults": {"kappa": 0.02, "f_max": 10.0}, "rotor": [{"frame": "rotor_plus_1", "spin": "cw"}, {"frame": "propeller_9", "spin": 1}]}
    with pytest.raises(UnknownNameError, match="frame of rotor 2 'propeller_9'; valid: .*'rotor_plus_1'"):
        from_urdf(TEXT, desc, ee_frame="end_effector", allow_nonphysical=True)


def test_rotor_frames_give_the_rotor_positions_and_axes():
    """A rotor described by a URDF frame sits where Pinocchio puts that frame (in B), thrusting along its z."""
    desc = {
        "defaults": {"kappa": P.kappa, "f_max": P.thrust_max},
        "rotor": [{"frame": f"rotor_x_{i}", "spin": s} for i, s in zip(range(1, 5), (1, -1, 1, -1))],
    }
    platform = from_urdf(TEXT, desc, ee_frame="end_effector", allow_nonphysical=True)
    ref = qprr.thesis.load_qprr(layout="x")
    np.testing.assert_allclose(platform.rotor_matrix, ref.rotor_matrix, atol=1e-15)


def test_a_model_without_free_flyer_or_with_sideways_gravity_is_refused():
    model = pin.buildModelFromXML(TEXT)  # fixed base
    with pytest.raises(InputError, match="free-flyer root"):
        from_model(model, ROTORS, ee_frame="end_effector", allow_nonphysical=True)
    model = pin.Model(qprr.thesis.load_qprr().model)
    model.gravity = pin.Motion(np.array([1.0, 0.0, -9.8]), np.zeros(3))
    with pytest.raises(InputError, match="gravity"):
        from_model(model, ROTORS, ee_frame="end_effector", allow_nonphysical=True)


def test_user_model_is_never_modified():
    model = pin.buildModelFromXML(TEXT, pin.JointModelFreeFlyer())
    before = [model.inertias[j].copy() for j in range(model.njoints)], model.gravity.copy(), model.nframes
    platform = from_model(model, ROTORS, ee_frame="end_effector", allow_nonphysical=True)
    assert platform.model is not model
    assert all(a == b for a, b in zip(before[0], model.inertias)) and model.gravity == before[1] and model.nframes == before[2]


# ------------------------------------------------------ the thesis loader: URDF and parameters agree
def test_thesis_loader_refuses_parameters_that_contradict_the_urdf():
    """issue 16 item 3: a parameter the URDF contradicts is an error naming it and both values, not a silent mix."""
    with pytest.raises(InputError, match=r"params\.d3 = 0\.5 m contradicts .*qprr\.urdf, which has 0\.1\b"):
        qprr.thesis.load_qprr(P.with_changes(d3=0.5), urdf_path=URDF_PATH)
    link2 = P.links[1]
    heavier = (P.links[0], type(link2)(link2.name, 0.5, link2.length, link2.com, link2.inertia), P.links[2])
    with pytest.raises(InputError, match=r"params\.links\[1\]\.mass \(link2\) = 0\.5 kg contradicts .* which has 0\.2773"):
        qprr.thesis.load_qprr(P.with_changes(links=heavier), urdf_path=URDF_PATH)
    with pytest.raises(InputError, match=r"params\.theta2_limits\[1\] = 1\.0 contradicts"):
        qprr.thesis.load_qprr(P.with_changes(theta2_limits=(P.theta2_limits[0], 1.0)), urdf_path=URDF_PATH)
    with pytest.raises(InputError, match=r"params\.arm_length \(rotor rotor_plus_1 at x, y\) = 0\.3 m contradicts .* which has 0\.225"):
        qprr.thesis.load_qprr(P.with_changes(arm_length=0.3), urdf_path=URDF_PATH)
    # parameters the URDF does not hold (rotor factors, thrust bound, g) are the parameters' own
    assert qprr.thesis.load_qprr(P.with_changes(thrust_max=25.0), urdf_path=URDF_PATH).thrust_max.tolist() == [25.0] * 4


def test_thesis_loader_refuses_an_unrelated_robot():
    path = qprr.platforms.robots_dir() / "borinot_description/urdf/borinot_flying_arm_2.urdf"
    with pytest.raises((InputError, UnknownNameError)):
        qprr.thesis.load_qprr(urdf_path=path)


def test_named_platform_registry_lists_names():
    with pytest.raises(UnknownNameError, match="valid: 'q-prr', 'borinot_flying_arm_2', 'hextilt_flying_arm_5'"):
        qprr.load("crazyflie")
    with pytest.raises(UnknownNameError, match="option of platform"):
        qprr.load("borinot_flying_arm_2", layout="x")
