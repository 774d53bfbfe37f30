"""Modified Denavit-Hartenberg (Khalil-Kleinfinger) chains, Thesis (3.27)-(3.30), Table 3.4 and (3.48)-(3.56).

The builder (qprr.nomenclature.mdh) is checked on its own (a planar 2R arm and a prismatic joint, in
closed form), then the thesis's table and transforms are compared with the URDF model
frame by frame: joint origins, joint axes (with their sign) and the end-effector pose.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qprr.charts import rot_y, rot_z
from qprr.errors import InputError, ShapeError
from qprr.nomenclature import mdh
from qprr.thesis import ARM_JOINTS, EE_FRAME
from qprr.thesis import printed as th
from qprr.thesis.checks import fixed_base_arm, mdh_frame_errors, urdf_arm_frames
from qprr.thesis.params import thesis_params

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)
P = thesis_params()
D = th.d_lengths(P)
_angle = st.floats(-math.pi, math.pi)
_len = st.floats(-2.0, 2.0)
_arm = st.tuples(*(st.floats(float(a), float(b)) for a, b in zip(P.lower_limits, P.upper_limits))).map(np.array)


@pytest.fixture(scope="module")
def urdf_arm(robot):
    return fixed_base_arm(robot)


def chain_3_4(rows, q, transform=None, tool=None):
    kw = {} if transform is None else {"transform": transform}
    return mdh.chain(rows, q, base=th.T_b0_3_49(), tool=th.T_4eb_3_51() if tool is None else tool, **kw)


# ======================================================================== the convention (3.27)
@SETTINGS
@given(_angle, _len, _angle, _len)
def test_kk_transform_3_27_closed_form(alpha, d, theta, r):
    # Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r), multiplied out by hand
    ca, sa, ct, st_ = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    expected = np.array([[ct, -st_, 0, d], [ca * st_, ca * ct, -sa, -r * sa], [sa * st_, sa * ct, ca, r * ca], [0, 0, 0, 1]])
    np.testing.assert_allclose(mdh.kk_transform(alpha, d, theta, r), expected, atol=1e-14)
    np.testing.assert_allclose(th.mdh_3_28_corrected(alpha, d, theta, r), expected, atol=1e-14)


def test_mdh_3_28_printed_sign_of_sin_theta():
    alpha, d, theta, r = 0.4, 0.1, 0.7, -0.2
    printed, true = th.mdh_3_28(alpha, d, theta, r), mdh.kk_transform(alpha, d, theta, r)
    diff = printed - true
    assert diff[0, 1] == pytest.approx(2 * math.sin(theta))  # +sin(theta) printed where (3.27) gives -sin(theta)
    diff[0, 1] = 0.0
    np.testing.assert_allclose(diff, 0.0, atol=1e-15)  # every other entry is right
    R = printed[0:3, 0:3]
    assert (R.T @ R)[0, 1] == pytest.approx(math.sin(2 * theta))  # columns 1 and 2 not orthogonal: not a rotation


def test_planar_2r_arm_by_chain_and_pinocchio():
    l1, l2, t1, t2 = 0.7, 0.4, 0.3, -1.1
    rows = (mdh.MDHRow(0, 0.0, 0.0, 0.0, 0.0), mdh.MDHRow(0, 0.0, l1, 0.0, 0.0))
    tool = np.eye(4)
    tool[0, 3] = l2
    frames = mdh.chain(rows, [t1, t2], tool=tool)
    tip = [l1 * math.cos(t1) + l2 * math.cos(t1 + t2), l1 * math.sin(t1) + l2 * math.sin(t1 + t2), 0.0]
    np.testing.assert_allclose(frames[-1][0:3, 3], tip, atol=1e-15)
    np.testing.assert_allclose(frames[-1][0:3, 0:3], rot_z(t1 + t2), atol=1e-15)
    model = mdh.build_model(rows, tool=tool)
    data = model.createData()
    q = np.array([t1, t2])
    pin.framesForwardKinematics(model, data, q)
    np.testing.assert_allclose(data.oMf[model.getFrameId(mdh.TOOL_FRAME)].homogeneous, frames[-1], atol=1e-15)
    J = pin.computeFrameJacobian(model, data, q, model.getFrameId(mdh.TOOL_FRAME), pin.LOCAL_WORLD_ALIGNED)
    dtip = [-tip[1], tip[0], 0.0]  # d tip / d t1 = e_z x tip
    np.testing.assert_allclose(J[0:3, 0], dtip, atol=1e-15)
    np.testing.assert_allclose(J[3:6], [[0, 0], [0, 0], [1, 1]], atol=1e-15)


def test_prismatic_row_adds_its_variable_to_r():
    row = mdh.MDHRow(1, math.pi / 2, 0.2, 0.3, 0.05)
    np.testing.assert_allclose(row.transform(0.1), mdh.kk_transform(math.pi / 2, 0.2, 0.3, 0.15), atol=1e-15)
    model = mdh.build_model([row])
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.array([0.1]))
    np.testing.assert_allclose(data.oMf[model.getFrameId(mdh.frame_name(1))].homogeneous, row.transform(0.1), atol=1e-15)
    assert model.nq == 1 and mdh.n_joints([row, mdh.MDHRow(0, 0, 1, 0, 0, joint=False)]) == 1


def test_mdh_inputs_are_validated():
    with pytest.raises(InputError, match="sigma"):
        mdh.MDHRow(2, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(InputError, match="joint"):
        mdh.MDHRow(0, 0.0, 0.0, 0.0, 0.0, joint=1)
    with pytest.raises(InputError, match="alpha"):
        mdh.MDHRow(0, float("nan"), 0.0, 0.0, 0.0)
    rows = th.table_3_4_corrected(D)
    with pytest.raises(ShapeError, match="q"):
        mdh.chain(rows, [0.0, 0.0])  # three joint rows
    with pytest.raises(InputError, match="base"):
        mdh.chain(rows, np.zeros(3), base=2 * np.eye(4))
    with pytest.raises(ShapeError, match="tool"):
        mdh.build_model(rows, tool=np.eye(3))
    with pytest.raises(InputError, match="rows"):
        mdh.chain([], [])
    with pytest.raises(InputError, match="transform"):
        mdh.chain(rows, np.zeros(3), transform="kk")


# ======================================================================== Table 3.4 vs the URDF
@SETTINGS
@given(_arm)
def test_corrected_table_3_4_is_the_urdf_frame_by_frame(urdf_arm, q):
    model, data = urdf_arm
    rows = th.table_3_4_corrected(D)
    frames = chain_3_4(rows, q)
    e = mdh_frame_errors(frames, model, data, q)
    assert max(e["origins"], e["axes"], e["end effector"]) < 1e-15
    # the MDH frames differ from the URDF link frames by constant rotations (the ones at q = 0)
    e0 = mdh_frame_errors(chain_3_4(rows, np.zeros(3)), model, data, np.zeros(3))
    np.testing.assert_allclose(e["offsets"], e0["offsets"], atol=1e-15)
    # and the Pinocchio model built from the table has the URDF's frame Jacobians, joint by joint
    m = mdh.build_model(rows, base=th.T_b0_3_49(), tool=th.T_4eb_3_51())
    dm = m.createData()
    for j, name in enumerate(ARM_JOINTS, start=1):
        Jm = pin.computeFrameJacobian(m, dm, q, m.getFrameId(mdh.frame_name(j)), pin.LOCAL_WORLD_ALIGNED)
        Ju = pin.computeFrameJacobian(model, data, q, model.getFrameId(name), pin.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(Jm, Ju, atol=1e-15)
    Jm = pin.computeFrameJacobian(m, dm, q, m.getFrameId(mdh.TOOL_FRAME), pin.LOCAL_WORLD_ALIGNED)
    Ju = pin.computeFrameJacobian(model, data, q, model.getFrameId(EE_FRAME), pin.LOCAL_WORLD_ALIGNED)
    np.testing.assert_allclose(Jm, Ju, atol=1e-15)


def test_table_3_4_alpha_pi_turns_theta2_about_the_slider(urdf_arm):
    model, data = urdf_arm
    q = np.array([0.0, math.pi / 2, 0.0])  # arm bent forward: the tip is at x_B = d2 + d3
    _, axes, ee = urdf_arm_frames(model, data, q)
    np.testing.assert_allclose(axes[1], [0, 1, 0], atol=1e-15)  # the URDF turns theta2 about +y_B
    printed = chain_3_4(th.table_3_4(D), q)
    np.testing.assert_allclose(printed[1][0:3, 2], [-1, 0, 0], atol=1e-15)  # printed alpha = pi: z_2 = -x_B
    np.testing.assert_allclose(ee[0:3, 3], [P.d2 + P.d3, 0, P.d0 + P.d1], atol=1e-15)
    assert abs(printed[-1][0, 3] - ee[0, 3]) > 0.1  # the printed table misses the tip
    np.testing.assert_allclose(chain_3_4(th.table_3_4_corrected(D), q)[-1], ee, atol=1e-15)
    # (3.53) is printed with alpha = pi/2: it is (3.27) of the corrected row, not of the printed one
    np.testing.assert_allclose(th.T_12_3_53(0.4, P.d1), th.table_3_4_corrected(D)[1].transform(0.4), atol=1e-15)
    assert np.abs(th.T_12_3_53(0.4, P.d1) - th.table_3_4(D)[1].transform(0.4)).max() > 0.9


def test_mdh_3_28_in_the_chain_misses_the_urdf(urdf_arm):
    model, data = urdf_arm
    q = np.array([0.01, 0.6, -0.4])
    rows = th.table_3_4_corrected(D)
    e = mdh_frame_errors(chain_3_4(rows, q, transform=th.mdh_3_28), model, data, q)
    assert e["end effector"] > 0.1
    e = mdh_frame_errors(chain_3_4(rows, q, transform=th.mdh_3_28_corrected), model, data, q)
    assert max(e["origins"], e["axes"], e["end effector"]) < 1e-15


# ======================================================================== (3.48)-(3.56)
def test_T_b0_3_48_is_its_printed_matrix_3_49():
    np.testing.assert_allclose(th.T_b0_3_48(), th.T_b0_3_49(), atol=1e-15)
    np.testing.assert_allclose(th.T_b0_3_49()[0:3, 2], [1, 0, 0])  # z_0 is the slider axis x_B
    assert np.linalg.det(th.T_b0_3_49()[0:3, 0:3]) == pytest.approx(1.0)


def test_T_4eb_3_50_product_is_not_its_printed_matrix_3_51(urdf_arm):
    model, data = urdf_arm
    np.testing.assert_allclose(th.T_4eb_3_50()[0:3, 0:3], [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-15)
    np.testing.assert_allclose(th.T_4eb_3_50_corrected(), th.T_4eb_3_51(), atol=1e-15)  # Rot(z, +pi/2)
    np.testing.assert_allclose(rot_y(math.pi / 2) @ rot_z(math.pi / 2), th.T_4eb_3_51()[0:3, 0:3], atol=1e-15)
    # at q = 0 the end effector is aligned with B (R_eb = Ry(0) of (3.58)); the stated product turns it
    rows = th.table_3_4_corrected(D)
    stated = chain_3_4(rows, np.zeros(3), tool=th.T_4eb_3_50())[-1]
    ee = urdf_arm_frames(model, data, np.zeros(3))[2]
    np.testing.assert_allclose(ee[0:3, 0:3], np.eye(3), atol=1e-15)
    assert np.abs(stated[0:3, 0:3] - np.eye(3)).max() > 0.9
    np.testing.assert_allclose(chain_3_4(rows, np.zeros(3))[-1], ee, atol=1e-15)


@SETTINGS
@given(_arm)
def test_printed_3_52_to_3_55_chain_to_3_56_3_58_and_the_urdf(urdf_arm, q):
    model, data = urdf_arm
    r0, t2, t3 = q
    rows = th.table_3_4_corrected(D)
    printed = (th.T_01_3_52(r0, P.d0), th.T_12_3_53(t2, P.d1), th.T_23_3_54(t3, P.d2), th.T_34_3_55(P.d3))
    for T, row, v in zip(printed, rows, (r0, t2, t3, 0.0)):
        np.testing.assert_allclose(T, row.transform(v), atol=1e-15)
    frames = th.mdh_frames_3_56(q, D)
    e = mdh_frame_errors(frames, model, data, q)
    assert max(e["origins"], e["axes"], e["end effector"]) < 1e-15
    np.testing.assert_allclose(th.T_eb_3_56(q, D), th.T_eb_3_58(q, D), atol=1e-15)
