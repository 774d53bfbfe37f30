"""Rotor sets as data (qprr.rotors): the wrench each thrust applies, ring layouts, ranks, rotor description files."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
import qprr.thesis
from qprr import rotors as ro
from qprr.charts import rot_z
from qprr.errors import InputError, UnknownNameError

SETTINGS = settings(max_examples=50, deadline=None, derandomize=True)


def _frame(rotor: ro.Rotor) -> pin.SE3:
    """A frame at the rotor centre whose z axis is the thrust axis (in B)."""
    R = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), np.array(rotor.axis_body)).toRotationMatrix()
    return pin.SE3(R, np.array(rotor.position_body))


# ------------------------------------------------------------------------- the wrench of a thrust
@SETTINGS
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    st.sampled_from([1, -1]),
    st.floats(0.0, 0.1),
    st.floats(0.0, 30.0),
)
def test_column_is_the_rotor_force_moved_to_b(p, a, spin, kappa, f):
    """Omega f = the force f a and drag torque spin kappa f a at the rotor, transported to B by Pinocchio's SE3."""
    if np.linalg.norm(a) < 1e-3:
        return
    rotor = ro.Rotor(tuple(p), tuple(a), spin, kappa, 0.0, 100.0)
    local = pin.Force(np.array([0.0, 0.0, f]), np.array([0.0, 0.0, spin * kappa * f]))  # in the rotor frame
    at_b = _frame(rotor).act(local)
    np.testing.assert_allclose(ro.rotor_matrix([rotor])[:, 0] * f, np.r_[at_b.linear, at_b.angular], atol=1e-13)


@pytest.mark.parametrize("n", [4, 6, 8])
@pytest.mark.parametrize("layout", ["plus", "x"])
def test_equal_thrusts_on_a_ring_lift_without_torque(n, layout):
    """Alternating spins on a symmetric ring: equal thrusts cancel every torque, the force is n f along z_B."""
    rotors = ro.layout_rotors(n, 0.3, layout, kappa=0.016, f_max=10.0)
    w = ro.rotor_matrix(rotors) @ np.full(n, 2.5)
    np.testing.assert_allclose(w, [0, 0, 2.5 * n, 0, 0, 0], atol=1e-14)


@pytest.mark.parametrize("n", [4, 6, 8])
@pytest.mark.parametrize("layout", ["plus", "x"])
def test_ring_geometry(n, layout):
    rotors = ro.layout_rotors(n, 0.3, layout, kappa=0.016)
    pos = np.array([r.position_body for r in rotors])
    np.testing.assert_allclose(np.linalg.norm(pos[:, 0:2], axis=1), 0.3, atol=1e-15)
    angles = np.unwrap(np.arctan2(pos[:, 1], pos[:, 0]))
    np.testing.assert_allclose(np.diff(angles), 2 * math.pi / n, atol=1e-14)  # counter-clockwise, evenly spaced
    start = {"plus": 0.0, "x": math.pi / n} if n != 4 else {"plus": math.pi, "x": 1.25 * math.pi}
    assert math.remainder(angles[0] - start[layout], 2 * math.pi) == pytest.approx(0.0, abs=1e-14)
    assert [r.spin for r in rotors] == [1, -1] * (n // 2)


def test_quadrotor_x_is_plus_turned_45_degrees():
    plus, x = ro.quadrotor(0.225, "plus"), ro.quadrotor(0.225, "x")
    for a, b in zip(plus, x):
        np.testing.assert_allclose(rot_z(math.pi / 4) @ np.array(a.position_body), b.position_body, atol=1e-15)
    # the thesis numbering, (3.34)-(3.36): rotor 1 on -x_B, 2 on -y_B, 3 on +x_B, 4 on +y_B
    np.testing.assert_allclose([r.position_body for r in plus], [[-0.225, 0, 0], [0, -0.225, 0], [0.225, 0, 0], [0, 0.225, 0]], atol=1e-15)
    for layout in ("plus", "x"):  # the Q-PRR's own rotor set is the "+"/"x" ring of its parameters
        P = qprr.thesis.thesis_params()
        ring = ro.quadrotor(P.arm_length, layout, kappa=P.kappa)
        np.testing.assert_allclose(ro.rotor_matrix(ring), qprr.thesis.load_qprr(layout=layout).rotor_matrix, atol=1e-15)


@pytest.mark.parametrize(
    "n, layout, tilt, rank",
    [
        (4, "plus", 0.0, 4),
        (4, "x", 0.0, 4),
        (6, "plus", 0.0, 4),
        (6, "x", 0.0, 4),
        (8, "plus", 0.0, 4),
        (8, "x", 0.0, 4),
        (6, "plus", 0.3, 6),
        (6, "x", 0.5, 6),
        (8, "plus", 0.3, 6),
        (4, "plus", 0.3, 4),
    ],
)
def test_wrench_rank(n, layout, tilt, rank):
    """Coplanar rotors produce thrust and three torques (rank 4); alternately tilted hexa- and octorotors all six
    (a tilted quadrotor has only four inputs)."""
    rotors = ro.layout_rotors(n, 0.3, layout, kappa=0.016, tilt=tilt)
    assert np.linalg.matrix_rank(ro.rotor_matrix(rotors), tol=1e-9) == rank


@pytest.mark.parametrize("tilt", [0.1, 0.3, -0.4])
def test_tilt_turns_the_axis_about_the_rotor_arm(tilt):
    for r in ro.ring(6, 0.3, tilt=tilt):
        a, p = np.array(r.axis_body), np.array(r.position_body)
        assert math.acos(a[2]) == pytest.approx(abs(tilt), abs=1e-12)  # away from z_B by |tilt|
        assert a @ p == pytest.approx(0.0, abs=1e-15)  # turned about the radial arm: stays normal to it


def test_named_platforms_rank():
    assert qprr.load("borinot_flying_arm_2").wrench_rank == 4
    hextilt = qprr.load("hextilt_flying_arm_5")
    assert hextilt.wrench_rank == 6 and hextilt.fully_actuated


# ------------------------------------------------------------------------- rotor descriptions
def test_hextilt_quaternions_give_the_frame_z_axes():
    desc = ro.read_rotor_file(qprr.platforms.DATA_DIR / "hextilt_flying_arm_5.rotors.toml")
    rotors = ro.rotors_from_mapping(desc)
    for entry, rotor in zip(desc["rotor"], rotors):
        x, y, z, w = entry["quaternion_xyzw"]
        R = pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()
        np.testing.assert_allclose(rotor.axis_body, R[:, 2], atol=1e-15)
        assert rotor.kappa == pytest.approx(1.3677728e-7 / 8.54858e-6, rel=1e-6)


def test_borinot_bounds_come_from_its_motor_model():
    desc = ro.read_rotor_file(qprr.platforms.DATA_DIR / "borinot_flying_arm_2.rotors.toml")
    rotors = ro.rotors_from_mapping(desc)
    assert all(r.f_max == pytest.approx(4.511e-6 * 2236.0**2, rel=1e-9) for r in rotors)  # c_f w_max^2
    assert sorted(r.spin for r in rotors) == [-1, -1, -1, 1, 1, 1]
    np.testing.assert_allclose([np.hypot(*r.position_body[0:2]) for r in rotors], 0.185, rtol=1e-9)


def _write(tmp_path, text: str):
    path = tmp_path / "rotors.toml"
    path.write_text(text)
    return path


GOOD = """
[defaults]
kappa = 0.02
f_max = 10.0

[[rotor]]
position = [0.2, 0.0, 0.0]
spin = "cw"
"""


@pytest.mark.parametrize(
    "text, error, match",
    [
        ("[defaults\nkappa = 1", InputError, "not valid TOML"),
        (GOOD + "\n[extra]\na = 1\n", UnknownNameError, "rotor description key 'extra'; valid: 'base_link', 'defaults', 'rotor'"),
        (GOOD.replace("kappa = 0.02", "kappa = 0.02\ndrag = 1"), UnknownNameError, "rotor default 'drag'"),
        (GOOD.replace('spin = "cw"', 'spin = "cw"\ncolour = "red"'), UnknownNameError, "key of rotor 1 'colour'"),
        (GOOD.replace('spin = "cw"', 'spin = "left"'), UnknownNameError, "spin of rotor 1 'left'"),
        (GOOD.replace("position = [0.2, 0.0, 0.0]\n", ""), InputError, "rotor 1 needs 'position'"),
        (GOOD.replace('spin = "cw"', 'spin = "cw"\naxis = [0, 0, 1]\nquaternion_xyzw = [0, 0, 0, 1]'), InputError, "not both"),
        (GOOD.replace('spin = "cw"', 'spin = "cw"\nquaternion_xyzw = [0, 0, 0, 0]'), InputError, "non-zero"),
        (GOOD.replace('spin = "cw"', 'spin = "cw"\naxis = [0, 0, 0]'), InputError, "non-zero vector"),
        (GOOD.replace("f_max = 10.0", "f_max = 10.0\nf_min = 12.0"), InputError, "f_min < f_max"),
        (GOOD.replace("kappa = 0.02", "kappa = -0.02"), InputError, "kappa must be >= 0 m, got -0.02"),
        (GOOD.replace("position = [0.2, 0.0, 0.0]", "position = [0.2, 0.0]"), InputError, "3 finite numbers"),
        ("[defaults]\nkappa = 0.02\n", InputError, "non-empty list 'rotor'"),
        # a new user's mistakes: each names the rotor and says what to write
        (GOOD.replace('spin = "cw"\n', ""), InputError, "rotor 1 needs 'spin': \"cw\""),
        (GOOD.replace('spin = "cw"', 'spin = "cw"\naxis = [0, 0, 2]'), InputError, r"axis \[0.0, 0.0, 2.0\] has norm 2: .*\[0.0, 0.0, 1.0\]"),
        (GOOD.replace("position = [0.2, 0.0, 0.0]", "position = [200.0, 0.0, 0.0]"), InputError, "200 m from B: positions are in metres"),
        (GOOD.replace("position = [0.2, 0.0, 0.0]", 'position = "0.2, 0, 0"'), InputError, "position .* list of 3 finite numbers"),
        (GOOD.replace("[[rotor]]", "[rotor]"), InputError, r"one \[\[rotor\]\] per rotor"),
        (GOOD.replace("[defaults]", "base_link = 3\n[defaults]"), InputError, "base_link must be the name of a link"),
    ],
)
def test_rotor_file_errors_name_the_entry(tmp_path, text, error, match):
    path = _write(tmp_path, text)
    with pytest.raises(error, match=match):
        ro.rotors_from_mapping(ro.read_rotor_file(path))


def test_good_rotor_file_and_missing_file(tmp_path):
    (rotor,) = ro.rotors_from_mapping(ro.read_rotor_file(_write(tmp_path, GOOD)))
    assert (rotor.spin, rotor.kappa, rotor.f_min, rotor.f_max) == (1, 0.02, 0.0, 10.0)
    assert rotor.axis_body == (0.0, 0.0, 1.0)
    with pytest.raises(InputError, match="does not exist"):
        ro.read_rotor_file(tmp_path / "nope.toml")


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"spin": 0}, "spin must be"),
        ({"f_min": -1.0}, "f_min must be >= 0"),
        ({"f_max": float("nan")}, "f_max must be a number, got nan"),
        ({"axis_body": (0.0, 0.0, 0.0)}, "non-zero"),
        ({"position_body": (0.0, float("inf"), 0.0)}, "finite"),
    ],
)
def test_bad_rotor_fields(kwargs, match):
    args = {"position_body": (0.2, 0.0, 0.0), **kwargs}
    with pytest.raises(InputError, match=match):
        ro.Rotor(**args)


def test_unknown_layout_lists_the_valid_ones():
    with pytest.raises(UnknownNameError, match="'plus', 'x'"):
        ro.layout_rotors(6, 0.3, "h")
    with pytest.raises(InputError, match="radius"):
        ro.ring(6, -0.3)
