"""The thesis's printed closed forms (qprr.thesis) against the Pinocchio model.

For every erratum of docs/thesis-errata.md there is a test that shows the printed form
wrong on a concrete counter-example AND the corrected form right against the model;
the printed forms that are right are checked over random states.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
from qprr import actuation as act
from qprr import coordinates as co
from qprr import model as qm
from qprr import thesis as th
from qprr.checks import body_rate_fd, christoffel, fixed_base_arm
from qprr.errors import ShapeError
from qprr.params import thesis_params

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)

P = thesis_params()
D = th.link_lengths(P)
L, B_F, C_D = P.arm_length, P.thrust_factor, P.drag_factor
M1, M2, M3 = (link.mass for link in P.links)

_angle = st.floats(-math.pi, math.pi)
_tilt = st.floats(-1.3, 1.3)
_rate = st.floats(-3.0, 3.0)
_arm = st.tuples(*(st.floats(float(a), float(b)) for a, b in zip(P.lower_limits, P.upper_limits))).map(np.array)
_xi = st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3), _tilt, _tilt, _angle, _arm).map(
    lambda t: np.concatenate([t[:6], t[6]])
)
_rates9 = st.lists(_rate, min_size=9, max_size=9).map(np.array)
_rates3 = st.lists(_rate, min_size=3, max_size=3).map(np.array)


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


@pytest.fixture(scope="module")
def arm_fixed(robot):
    """The arm with its base locked level (z up)."""
    return fixed_base_arm(robot)


@pytest.fixture(scope="module")
def arm_fixed_down(robot):
    """The arm with its base pitched by +pi/2: gravity along +x_B, the convention of the printed Sec. 5.5 G."""
    return fixed_base_arm(robot, co.rot_y(np.pi / 2))


def ned(robot):
    model = pin.Model(robot.model)
    model.gravity = pin.Motion(np.array([0.0, 0.0, P.g]), np.zeros(3))
    return replace(robot, model=model)


# ================================================================== (3.4), (3.8), (3.25)
@SETTINGS
@given(_angle, _tilt, _angle)
def test_rotation_3_4_is_pinocchio_rpy(phi, theta, psi):
    R = th.rotation_3_4(phi, theta, psi)
    np.testing.assert_allclose(R, pin.rpy.rpyToMatrix(phi, theta, psi), atol=1e-14)
    np.testing.assert_allclose(R, co.euler_to_rotation([phi, theta, psi]), atol=1e-14)


def test_euler_3_8_swaps_roll_and_yaw():
    R = th.rotation_3_4(0.3, 0.2, -1.0)
    np.testing.assert_allclose(th.euler_3_8(R), [-1.0, 0.2, 0.3], atol=1e-14)  # printed: (psi, theta, phi)
    np.testing.assert_allclose(th.euler_3_8_corrected(R), [0.3, 0.2, -1.0], atol=1e-14)


@SETTINGS
@given(_angle, st.floats(-1.5, 1.5), _angle)
def test_euler_3_8_corrected_round_trip(phi, theta, psi):
    angles = th.euler_3_8_corrected(pin.rpy.rpyToMatrix(phi, theta, psi))
    np.testing.assert_allclose(wrap(angles - [phi, theta, psi]), 0.0, atol=1e-9)
    np.testing.assert_allclose(angles, co.rotation_to_euler(th.rotation_3_4(phi, theta, psi)), atol=1e-12)


@SETTINGS
@given(_angle, _tilt, _angle, _rates3)
def test_T_3_25_gives_the_body_frame_rate(phi, theta, psi, rates):
    w_body = body_rate_fd([phi, theta, psi], rates)
    np.testing.assert_allclose(th.T_3_25(phi, theta) @ rates, w_body, atol=1e-7)
    np.testing.assert_allclose(th.T_3_25(phi, theta), co.euler_rate_matrix([phi, theta, psi]), atol=1e-15)


def test_T_3_25_is_not_the_world_frame_rate_that_3_15_announces():
    e, rates = np.array([0.4, 0.3, 0.0]), np.array([0.0, 0.0, 1.0])  # pure yaw rate
    w_world = pin.rpy.rpyToMatrix(*e) @ body_rate_fd(e, rates)
    np.testing.assert_allclose(w_world, [0, 0, 1], atol=1e-8)  # yaw spins about world z
    assert np.linalg.norm(th.T_3_25(*e[:2]) @ rates - w_world) > 0.4


# ================================================================== allocation (3.36), (3.37), (A.1)
def test_allocation_3_36_yaw_row_needs_c_over_b(robot):
    Om = act.rotor_matrix(robot, "plus")
    np.testing.assert_allclose(Om[0:2], 0.0, atol=1e-15)
    printed = th.allocation_3_36(L, C_D)
    np.testing.assert_allclose(printed[0:3], Om[2:5], atol=1e-15)  # thrust, roll and pitch rows are right
    # one newton on rotor 1 gives a yaw torque of kappa = c/b = 0.025 N m, not c = 7.5e-7
    assert Om[5, 0] == pytest.approx(0.025) and printed[3, 0] == pytest.approx(7.5e-7)
    np.testing.assert_allclose(th.allocation_3_36_corrected(L, B_F, C_D), Om[2:6], atol=1e-15)


def test_allocation_3_36_corrected_for_other_rotor_parameters():
    other = P.with_changes(arm_length=0.31, thrust_factor=2.0e-5, drag_factor=9.0e-7)
    Om = act.rotor_matrix(qprr.load(other), "plus")
    np.testing.assert_allclose(th.allocation_3_36_corrected(0.31, 2.0e-5, 9.0e-7), Om[2:6], atol=1e-15)


def test_allocation_3_37_row3_contradicts_3_34(robot):
    w2 = np.array([1.0e5, 0.0, 0.0, 0.0])  # only rotor 1 (on -x_B) spins
    true = B_F * act.rotor_matrix(robot, "plus")[2:6] @ w2
    assert true[2] == pytest.approx(B_F * L * 1.0e5)  # (3.34): tau_theta = bl(w1^2 - w3^2) > 0
    printed = th.allocation_3_37(B_F, L, C_D) @ w2
    assert printed[2] == pytest.approx(-B_F * L * 1.0e5)
    np.testing.assert_allclose(th.allocation_3_37_corrected(B_F, L, C_D) @ w2, true, rtol=1e-12)


def test_det_3_37_is_that_of_the_printed_matrix_not_of_the_true_one(robot):
    printed_matrix = th.allocation_3_37(B_F, L, C_D)
    assert np.linalg.det(printed_matrix) == pytest.approx(th.det_3_37(B_F, L, C_D), rel=1e-12)
    true = np.linalg.det(B_F * act.rotor_matrix(robot, "plus")[2:6])
    assert true == pytest.approx(th.det_3_37_corrected(B_F, L, C_D), rel=1e-12)
    assert true == pytest.approx(-8 * C_D * L**2 * B_F**3, rel=1e-12)


def test_rotor_inverse_A1_has_the_wrong_tau_theta_sign(robot):
    u = np.array([0.0, 0.0, 1.0, 0.0])  # ask for +1 N m of pitch torque only
    f = th.rotor_inverse_A1(L, C_D) @ u
    achieved = th.allocation_3_36(L, C_D) @ f
    np.testing.assert_allclose(achieved, [0, 0, -1, 0], atol=1e-12)  # the printed inverse pitches the wrong way
    f_ok = th.rotor_inverse_A1_corrected(L, B_F, C_D) @ u
    np.testing.assert_allclose(act.rotor_matrix(robot, "plus")[2:6] @ f_ok, u, atol=1e-12)
    np.testing.assert_allclose(th.rotor_inverse_A1_corrected(L, B_F, C_D), act.allocation_inverse(robot), atol=1e-12)


# ================================================================== (3.42)-(3.44)
def test_potential_3_42_is_the_ned_potential(robot):
    rn, rng = ned(robot), np.random.default_rng(42)
    for _ in range(10):
        xi = np.concatenate([np.zeros(3), rng.uniform(-1.2, 1.2, 3), rng.uniform(P.lower_limits, P.upper_limits)])
        R, q = co.euler_to_rotation(xi[3:6]), co.xi_to_q(xi)
        U = th.potential_3_42(R, xi[6:9], P)
        assert U == pytest.approx(qm.potential_energy(rn, rn.data(), q), abs=1e-12)
        assert -U == pytest.approx(qm.potential_energy(robot, robot.data(), q), abs=1e-12)  # z up: opposite sign


def test_arm_torque_3_43_sign_is_that_of_ned(robot, data):
    # level base, arm bent forward (theta2 = pi/2): the arm's weight pitches the nose down,
    # i.e. a positive torque about y_B in our z-up frames
    xi = np.array([0, 0, 0, 0, 0, 0, 0.0, np.pi / 2, 0.0])
    q = co.xi_to_q(xi)
    model_tau = qm.arm_gravity_torque_body(robot, data, q)
    x_c = th.arm_com_3_44(xi[6:9], P)[0]
    assert model_tau[1] == pytest.approx(P.arm_mass * P.g * x_c) and model_tau[1] > 0.4
    printed = th.arm_torque_3_43(np.eye(3), xi[6:9], P)
    assert printed[1] == pytest.approx(-model_tau[1])
    np.testing.assert_allclose(th.arm_torque_3_43_corrected(np.eye(3), xi[6:9], P), model_tau, atol=1e-12)
    rn = ned(robot)
    np.testing.assert_allclose(printed, qm.arm_gravity_torque_body(rn, rn.data(), q), atol=1e-12)


@SETTINGS
@given(_xi)
def test_arm_torque_3_43_over_random_states(robot, xi):
    data, q, R = robot.data(), co.xi_to_q(xi), co.euler_to_rotation(xi[3:6])
    np.testing.assert_allclose(th.arm_torque_3_43_corrected(R, xi[6:9], P), qm.arm_gravity_torque_body(robot, data, q), atol=1e-12)
    np.testing.assert_allclose(th.arm_com_3_44(xi[6:9], P), qm.arm_com(robot, data, q)[2], atol=1e-14)


# ================================================================== geometric model (3.58)-(3.68)
@SETTINGS
@given(_xi)
def test_direct_geometric_model_3_58_3_62_3_65(robot, xi):
    data, q = robot.data(), co.xi_to_q(xi)
    R_e = th.R_e_3_62(*xi[3:6], xi[7], xi[8])
    zyz_defined = np.hypot(R_e[0, 2], R_e[1, 2]) > 1e-6  # (3.64) assumes r13, r23 not both 0
    np.testing.assert_allclose(th.T_eb_3_58(xi[6:9], D), qm.ee_placement_body(robot, data, q).homogeneous, atol=1e-14)
    M = qm.ee_placement(robot, data, q)
    np.testing.assert_allclose(th.R_e_3_62(*xi[3:6], xi[7], xi[8]), M.rotation, atol=1e-14)
    chi = th.fk_3_65(xi, D)
    np.testing.assert_allclose(chi[0:3], M.translation, atol=1e-13)
    if zyz_defined:
        np.testing.assert_allclose(th.zyz_to_rotation(chi[3:6]), M.rotation, atol=1e-9)
    np.testing.assert_allclose(th.p_e_3_61_corrected(xi, D), M.translation, atol=1e-13)


def test_p_e_3_61_y_row_misprint(robot, data):
    xi = np.array([0, 0, 0, 0, 0, np.pi / 2, 0.0, np.pi / 2, 0.0])  # yaw 90 deg, arm bent forward
    p = qm.ee_placement(robot, data, co.xi_to_q(xi)).translation
    x_eb = P.d2 + P.d3  # theta2 = pi/2: the arm points along x_B, which is world y after the yaw
    np.testing.assert_allclose(p[0:2], [0.0, x_eb], atol=1e-14)
    assert th.p_e_3_61(xi, D)[1] == pytest.approx(0.0, abs=1e-14)  # printed c_theta c_psi x_eb = 0
    np.testing.assert_allclose(th.p_e_3_61_corrected(xi, D), p, atol=1e-14)


def test_euler_3_64_is_a_zyz_extraction(robot, data):
    xi = np.array([0, 0, 0, 0.2, -0.3, 0.7, 0.0, 0.5, 0.4])
    R = qm.ee_placement(robot, data, co.xi_to_q(xi)).rotation
    ang = th.euler_3_64(R)
    np.testing.assert_allclose(th.zyz_to_rotation(ang), R, atol=1e-14)
    assert 0.0 <= ang[1] <= np.pi
    assert np.abs(th.rotation_3_4(*ang) - R).max() > 0.3  # not the ZYX angles of (3.4)/(3.8)


def test_hover_fk_3_68_angle_lines_misprint(robot, data):
    psi, q_arm = 0.5, np.array([0.01, 0.2, 0.1])  # s23 > 0
    xi = np.array([0.1, -0.2, 1.0, 0.0, 0.0, psi, *q_arm])
    M = qm.ee_placement(robot, data, co.xi_to_q(xi))
    printed = th.hover_fk_3_68(*xi[0:3], psi, q_arm, D)
    np.testing.assert_allclose(printed[0:3], M.translation, atol=1e-14)  # lines 1-3 are right
    true = th.euler_3_64(M.rotation)
    np.testing.assert_allclose(true, [psi, 0.3, 0.0], atol=1e-12)
    assert abs(printed[3] - psi) > 0.5  # atan2(s_psi c23, c_psi s23) != psi
    assert printed[5] == pytest.approx((1 - np.pi) / 2)  # -(1/2)(pi sgn(s23) - 1), not 0
    np.testing.assert_allclose(th.hover_fk_3_68_corrected(*xi[0:3], psi, q_arm, D)[3:6], true, atol=1e-12)


def test_hover_fk_3_68_theta_line_misprint_for_negative_s23(robot, data):
    psi, q_arm = -1.0, np.array([0.0, -0.6, 0.2])  # s23 < 0
    xi = np.array([0.0, 0.0, 0.0, 0.0, 0.0, psi, *q_arm])
    true = th.euler_3_64(qm.ee_placement(robot, data, co.xi_to_q(xi)).rotation)
    np.testing.assert_allclose(true, [psi + np.pi, 0.4, np.pi], atol=1e-12)
    assert th.hover_fk_3_68(0, 0, 0, psi, q_arm, D)[4] == pytest.approx(-0.4)  # atan2(s23, c23), outside [0, pi]
    np.testing.assert_allclose(wrap(th.hover_fk_3_68_corrected(0, 0, 0, psi, q_arm, D)[3:6] - true), 0, atol=1e-12)


@SETTINGS
@given(st.floats(-3, 3), _angle, _arm)
def test_hover_fk_3_68_corrected_is_3_65_at_zero_tilt(z, psi, q_arm):
    s23 = np.sin(q_arm[1] + q_arm[2])
    if abs(s23) < 1e-6:
        return
    xi = np.array([0.3, -0.4, z, 0.0, 0.0, psi, *q_arm])
    np.testing.assert_allclose(wrap(th.hover_fk_3_68_corrected(0.3, -0.4, z, psi, q_arm, D) - th.fk_3_65(xi, D)), 0, atol=1e-9)


# ================================================================== centre of mass (3.78)-(3.80)
@SETTINGS
@given(_arm)
def test_com_3_78_x_y_and_3_80(robot, q_arm):
    data = robot.data()
    c = qm.com_body(robot, data, co.xi_to_q(np.concatenate([np.zeros(6), q_arm])))
    np.testing.assert_allclose(th.com_3_78(q_arm, P)[0:2], c[0:2], atol=1e-15)
    assert th.x_cm_3_80(q_arm, P) == pytest.approx(c[0], abs=1e-15)
    np.testing.assert_allclose(th.com_3_78_corrected(q_arm, P), c, atol=1e-15)


def test_com_3_78_z_misprint(robot, data):
    c = qm.com_body(robot, data, co.xi_to_q(np.zeros(9)))  # arm straight up
    mG, d0, d1, d2, d3 = P.total_mass, *D
    true = (M1 * (d0 + d1 / 2) + M2 * (d0 + d1 + d2 / 2) + M3 * (d0 + d1 + d2 + d3 / 2)) / mG
    assert c[2] == pytest.approx(true, abs=1e-15)
    printed = th.com_3_78(np.zeros(3), P)[2]
    assert printed - true == pytest.approx((M1 * d1 / 2 - M3 * d2 / 2) / mG, abs=1e-15)
    assert abs(printed - true) > 1e-3
    assert th.com_3_78_corrected(np.zeros(3), P)[2] == pytest.approx(true, abs=1e-15)


# ================================================================== kinematics (4.12)-(4.28)
def _arm_jacobian_fd(q_arm, h=1e-6):
    J = np.zeros((6, 3))
    for k in range(3):
        Tp, Tm = th.T_eb_3_58(q_arm + h * np.eye(3)[k], D), th.T_eb_3_58(q_arm - h * np.eye(3)[k], D)
        J[0:3, k] = (Tp[0:3, 3] - Tm[0:3, 3]) / (2 * h)
        J[3:6, k] = pin.log3(Tp[0:3, 0:3] @ Tm[0:3, 0:3].T) / (2 * h)
    return J


@SETTINGS
@given(_arm)
def test_arm_jacobian_4_26_4_27_4_28(robot, q_arm):
    data = robot.data()
    J = th.J_eb_4_26(q_arm, D)
    Jm = qm.arm_jacobian_body(robot, data, q_arm)
    np.testing.assert_allclose(J, Jm, atol=1e-14)
    np.testing.assert_allclose(J, _arm_jacobian_fd(q_arm), atol=1e-8)
    np.testing.assert_allclose(th.J_4_27(q_arm, D), Jm[[0, 2, 4]], atol=1e-14)
    assert th.det_4_28(q_arm[1], P.d2) == pytest.approx(np.linalg.det(Jm[[0, 2, 4]]), abs=1e-14)


def _pose_fd(robot, data, xi, xid, h=1e-6):
    pp, Rp = qm.ee_pose_xi(robot, data, xi + h * xid)
    pm, Rm = qm.ee_pose_xi(robot, data, xi - h * xid)
    return np.concatenate([(pp - pm) / (2 * h), pin.log3(Rp @ Rm.T) / (2 * h)])


def test_J_e_4_12_lower_block_misprint(robot, data):
    xi = np.array([0, 0, 0, 0.6, 0.0, 0.0, 0.0, 0.3, 0.2])  # rolled by 0.6 rad
    xid = np.array([0, 0, 0, 0, 0, 1.0, 0, 0, 0])  # pure yaw rate: omega_e = e3 in the world
    fd = _pose_fd(robot, data, xi, xid)
    np.testing.assert_allclose(fd[3:6], [0, 0, 1], atol=1e-8)
    printed = th.J_e_4_12(xi, D) @ xid
    assert np.linalg.norm(printed[3:6] - [0, 0, 1]) > 0.5  # T e3 = (0, s_phi, c_phi): a body-frame vector
    np.testing.assert_allclose(th.J_e_4_12_corrected(xi, D) @ xid, fd, atol=1e-8)


@SETTINGS
@given(_xi, _rates9)
def test_J_e_4_12_corrected_is_the_model_jacobian(robot, xi, xid):
    data = robot.data()
    J = qm.jacobian_xi(robot, data, xi)
    np.testing.assert_allclose(th.J_e_4_12_corrected(xi, D), J, atol=1e-13)
    np.testing.assert_allclose(J @ xid, _pose_fd(robot, data, xi, xid), atol=1e-7)


def _det_zero_euler(robot, data, q_arm):
    J = qm.jacobian_xi(robot, data, np.concatenate([np.zeros(6), q_arm]))
    return np.linalg.det(J @ J.T)


@pytest.mark.parametrize("d3", [0.10, 0.02, 0.40])
def test_det_JJt_4_44_is_exact_and_independent_of_d3_and_theta3(d3):
    robot = qprr.load(P.with_changes(d3=d3))
    data, rng = robot.data(), np.random.default_rng(444)
    for _ in range(10):
        q_arm = rng.uniform([-0.04, -np.pi, -np.pi], [0.04, np.pi, np.pi])
        assert th.det_JJt_4_44(q_arm[0], q_arm[1], D) == pytest.approx(_det_zero_euler(robot, data, q_arm), rel=1e-13)


@pytest.mark.parametrize("fn, r0", [(th.sol_4_46, -0.04), (th.sol_4_47, 0.0), (th.sol_4_48, 0.04)])
def test_sol_4_46_to_4_48_are_4_44_for_the_thesis_lengths(robot, data, fn, r0):
    assert P.d0 + P.d1 == pytest.approx(0.095) and P.d2 == pytest.approx(0.18)
    for t in np.linspace(-np.pi, np.pi, 37):
        assert fn(t) == pytest.approx(th.det_JJt_4_44(r0, t, D), abs=6e-5)  # 4 printed digits
        assert fn(t) == pytest.approx(_det_zero_euler(robot, data, np.array([r0, t, -0.7])), abs=6e-5)
    # the exact constants the thesis rounded: 6 + 2 (d0 + d1)^2 + 4 r0^2 and 2 (d0 + d1) d2
    assert th.det_JJt_4_44(r0, np.pi / 2, D) - th.det_JJt_4_44(r0, -np.pi / 2, D) == pytest.approx(8 * P.d2 * r0, abs=1e-15)
    assert 6 + 2 * 0.095**2 + 4 * r0**2 == pytest.approx(fn(0.0) - 0.0342 - (0.0648 if r0 == 0 else 0.0649), abs=6e-5)


def test_jacobian_never_loses_rank_at_zero_euler_angles():
    # (4.44) >= 6 - 2 (d0 + d1) d2 > 0: the conclusion of Sec. 4.4.3 holds
    grid = [th.det_JJt_4_44(r0, t, D) for r0 in (-0.04, 0.0, 0.04) for t in np.linspace(-np.pi, np.pi, 181)]
    assert min(grid) > 6.0


# ================================================================== inertia blocks Sec. 5.2.2, (5.15)
@SETTINGS
@given(_xi)
def test_inertia_blocks_5_2_2(robot, xi):
    B = qm.dynamics_xi(robot, robot.data(), xi, np.zeros(9))[0]
    printed, corrected = th.B_blocks_5_2_2(xi, P), th.B_blocks_5_2_2_corrected(xi, P)
    np.testing.assert_allclose(printed.B11, B[0:3, 0:3], atol=1e-13)
    np.testing.assert_allclose(printed.B12, B[0:3, 3:6], atol=1e-13)
    np.testing.assert_allclose(printed.B13, B[0:3, 6:9], atol=1e-13)
    np.testing.assert_allclose(corrected.matrix(), B, atol=1e-13)


def test_inertia_blocks_5_2_2_misprints(robot, data):
    xi = np.array([0, 0, 0, 0.5, -0.4, 0.9, 0.02, 0.7, -0.5])
    B = qm.dynamics_xi(robot, data, xi, np.zeros(9))[0]
    printed = th.B_blocks_5_2_2(xi, P)
    assert np.abs(printed.B22 - B[3:6, 3:6]).max() > 1e-3  # Q = R_b^T T where T belongs
    assert np.abs(printed.B23 - B[3:6, 6:9]).max() > 1e-2  # sign of the mass term, Q, J_p^T for J_o
    # B33: the translational term has the wrong sign, so the printed "inertia" of the slider is negative
    assert printed.B33[0, 0] == pytest.approx(-(M1 + M2 + M3)) and B[6, 6] == pytest.approx(M1 + M2 + M3)
    assert np.linalg.eigvalsh(printed.B33).min() < 0


def test_inertia_blocks_5_2_2_at_level_attitude():
    # at R_b = I, Q = T = I: only the B23 / B33 misprints remain
    xi = np.array([0, 0, 0, 0, 0, 0, 0.0, 0.4, 0.3])
    printed, corrected = th.B_blocks_5_2_2(xi, P), th.B_blocks_5_2_2_corrected(xi, P)
    np.testing.assert_allclose(printed.B22, corrected.B22, atol=1e-15)
    assert np.abs(printed.B23 - corrected.B23).max() > 1e-2


def test_multirotor_kinetic_energy_5_15(robot):
    model = pin.Model(robot.model)
    for j in robot.arm_joint_ids:
        model.inertias[j] = pin.Inertia.Zero()
    data = model.createData()
    euler, rates = np.array([0.7, -0.5, 1.1]), np.array([0.3, -1.2, 2.0])
    v = np.zeros(9)
    v[3:6] = body_rate_fd(euler, rates)
    ke = pin.computeKineticEnergy(model, data, co.xi_to_q(np.r_[0, 0, 0, euler, 0, 0, 0]), v)
    assert abs(th.kinetic_multirotor_5_15(euler, rates, P) - ke) > 1e-3
    assert th.kinetic_multirotor_5_15_corrected(euler, rates, P) == pytest.approx(ke, rel=1e-9)


@SETTINGS
@given(_xi)
def test_potential_5_29(robot, xi):
    assert th.potential_5_29(xi, P) == pytest.approx(qm.potential_energy(robot, robot.data(), co.xi_to_q(xi)), abs=1e-11)


# ================================================================== input map (5.40)-(5.46)
def _power_error(RQ, xi, xid, f_body, tau_body, mu):
    u = RQ(xi) @ np.concatenate([f_body, tau_body, mu])
    power = (pin.rpy.rpyToMatrix(*xi[3:6]) @ f_body) @ xid[0:3] + tau_body @ body_rate_fd(xi[3:6], xid[3:6]) + mu @ xid[6:9]
    return abs(u @ xid - power)


def test_R_Q_5_41_and_5_43_violate_virtual_power():
    xi = np.array([0, 0, 0, 0.4, 0.3, -0.8, 0, 0, 0])
    xid = np.array([0, 0, 0, 0.5, -1.0, 0.7, 0, 0, 0])
    args = (np.zeros(3), np.array([1.0, -0.5, 0.8]), np.zeros(3))
    assert _power_error(th.R_Q_5_41, xi, xid, *args) > 0.1
    assert _power_error(th.R_Q_5_43, xi, xid, *args) > 0.1
    assert _power_error(th.R_Q_corrected, xi, xid, *args) < 1e-9


@SETTINGS
@given(_xi, _rates9, _rates9)
def test_R_Q_corrected_is_the_model_input_map(xi, xid, w):
    assert _power_error(th.R_Q_corrected, xi, xid, w[0:3], w[3:6], w[6:9]) < 1e-8
    np.testing.assert_allclose(th.R_Q_corrected(xi), act.input_map_matrix(xi), atol=1e-15)


def test_N_5_46(robot):
    N = act.actuation_matrix(robot, "plus")
    assert abs(th.N_5_46(L, C_D)[5, 0] - N[5, 0]) == pytest.approx(P.kappa - C_D)
    np.testing.assert_allclose(th.N_5_46_corrected(L, B_F, C_D), N, atol=1e-15)


# ================================================================== fixed-base arm, Sec. 5.5
@SETTINGS
@given(_arm)
def test_arm_inertia_5_54_and_corrected_b_ij(arm_fixed, q):
    model, data = arm_fixed
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    np.testing.assert_allclose(th.arm_B_5_54(q, P), M, atol=1e-15)
    np.testing.assert_allclose(th.arm_B_5_5_corrected(q, P), M, atol=1e-15)


def test_arm_b22_b33_misprints(arm_fixed):
    model, data = arm_fixed
    q = np.array([0.0, 0.3, 0.9])
    M = pin.crba(model, data, q)
    printed = th.arm_B_5_5(q, P)
    Ix2, Iy2, Iz2 = P.links[1].inertia[:3]
    Ix3, Iy3, Iz3 = P.links[2].inertia[:3]
    assert printed[1, 1] - M[1, 1] == pytest.approx(Iz2 - Iy2, abs=1e-15)  # I_z2 where the joint-axis I_y2 belongs
    s23 = np.sin(1.2)
    assert printed[2, 2] - M[2, 2] == pytest.approx(Iz3 + s23**2 * (Ix3 - Iz3), abs=1e-15)
    for i, j in [(0, 0), (0, 1), (0, 2), (1, 2)]:  # the others are right
        assert printed[i, j] == pytest.approx(M[i, j], abs=1e-15)
    # a rotation about the fixed y axis cannot make b33 configuration dependent
    M2 = pin.crba(model, data, np.array([0.0, -1.0, 0.4]))
    assert M2[2, 2] == pytest.approx(M[2, 2], abs=1e-15)


def test_christoffel_helper_matches_finite_differences(arm_fixed):
    model, data = arm_fixed
    q, v, h = np.array([0.01, 0.4, -0.8]), np.array([0.3, -1.1, 0.7]), 1e-6

    def Mq(x):
        M = pin.crba(model, data, x)
        return np.triu(M) + np.triu(M, 1).T

    dM = np.stack([(Mq(q + h * e) - Mq(q - h * e)) / (2 * h) for e in np.eye(3)], axis=2)
    C_fd = 0.5 * (np.einsum("ijk,k->ij", dM, v) + np.einsum("ikj,k->ij", dM, v) - np.einsum("jki,k->ij", dM, v))
    np.testing.assert_allclose(christoffel(model, data, q, v), C_fd, atol=1e-9)


@SETTINGS
@given(_arm, _rates3)
def test_arm_coriolis_5_5_1(arm_fixed, q, qd):
    model, data = arm_fixed
    C = christoffel(model, data, q, qd)
    np.testing.assert_allclose(th.arm_C_5_5_corrected(q, qd, P), C, atol=1e-14)
    g = pin.computeGeneralizedGravity(model, data, q)
    np.testing.assert_allclose(C @ qd, pin.rnea(model, data, q, qd, np.zeros(3)) - g, atol=1e-14)


def test_arm_coriolis_5_5_1_misprint(arm_fixed):
    model, data = arm_fixed
    q, qd = np.array([0.0, 0.3, 0.2]), np.array([0.0, 0.0, 2.0])
    printed, C = th.arm_C_5_5(q, qd, P), christoffel(model, data, q, qd)
    Ix3, _, Iz3 = P.links[2].inertia[:3]
    assert printed[2, 2] == pytest.approx(np.cos(0.5) * np.sin(0.5) * (Ix3 - Iz3) * 2.0)
    assert C[2, 2] == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(printed[0:2, 0:2], C[0:2, 0:2], atol=1e-15)


def test_arm_gravity_5_5_2_means_gravity_along_the_slider(arm_fixed, arm_fixed_down):
    q = np.array([0.02, 0.6, -0.3])
    printed = th.arm_G_5_5(q, P)
    model, data = arm_fixed_down
    np.testing.assert_allclose(printed, pin.computeGeneralizedGravity(model, data, q), atol=1e-14)
    lm, ld = arm_fixed  # with the base level (z up), gravity cannot load the horizontal slider
    assert pin.computeGeneralizedGravity(lm, ld, q)[0] == pytest.approx(0.0, abs=1e-15)
    assert printed[0] == pytest.approx(-P.g * (M1 + M2 + M3))


@SETTINGS
@given(_arm, _rates3, _rates3)
def test_arm_u_5_5_3_corrected_is_rnea(arm_fixed_down, q, qd, qdd):
    model, data = arm_fixed_down
    np.testing.assert_allclose(th.arm_u_5_5_corrected(q, qd, qdd, P), pin.rnea(model, data, q, qd, qdd), atol=1e-12)


def test_arm_u_5_5_3_misprints(arm_fixed_down):
    model, data = arm_fixed_down
    q = np.array([0.0, 0.0, 0.0])
    # u(1) from theta2_ddot alone: b12 = m3 (d3/2 + d2) + m2 d2/2; printed halves the m3 part
    tau = pin.rnea(model, data, q, np.zeros(3), np.array([0.0, 1.0, 0.0])) - pin.computeGeneralizedGravity(model, data, q)
    printed = th.arm_u_5_5(q, np.zeros(3), np.array([0.0, 1.0, 0.0]), P) - th.arm_G_5_5(q, P)
    assert tau[0] == pytest.approx(M3 * (P.d3 / 2 + P.d2) + M2 * P.d2 / 2)
    assert printed[0] == pytest.approx(0.5 * M3 * (P.d3 / 2 + P.d2) + 0.5 * M2 * P.d2)
    # u(2) theta2_ddot coefficient: m2 d2^2 / 2 and I_z2 instead of m2 d2^2 / 4 and I_y2
    Iy2, Iz2 = P.links[1].inertia[1:3]
    assert printed[1] - tau[1] == pytest.approx(M2 * P.d2**2 / 4 + Iz2 - Iy2, abs=1e-15)
    # u(2) multiplies its theta3 inertia term by theta3_dot: a pure theta3_dot gives a printed torque
    qd = np.array([0.0, 0.0, 1.0])
    u2 = th.arm_u_5_5(q, qd, np.zeros(3), P)[1] - th.arm_G_5_5(q, P)[1]
    assert u2 == pytest.approx(M3 * P.d3**2 / 4 + P.d2 * P.d3 * M3 / 2 + P.links[2].inertia[1])
    true2 = pin.rnea(model, data, q, qd, np.zeros(3))[1] - pin.computeGeneralizedGravity(model, data, q)[1]
    assert true2 == pytest.approx(0.0, abs=1e-15)  # -d2 d3 m3 s3 theta3_dot^2 / 2 = 0 at theta3 = 0
    # u(3) theta3_ddot coefficient carries I_z3 + s23^2 (I_x3 - I_z3)
    tau3 = pin.rnea(model, data, q, np.zeros(3), np.array([0.0, 0.0, 1.0]))[2] - pin.computeGeneralizedGravity(model, data, q)[2]
    p3 = th.arm_u_5_5(q, np.zeros(3), np.array([0.0, 0.0, 1.0]), P)[2] - th.arm_G_5_5(q, P)[2]
    assert p3 - tau3 == pytest.approx(P.links[2].inertia[2], abs=1e-15)


# ================================================================== inputs
def test_closed_forms_validate_their_vectors():
    with pytest.raises(ShapeError, match="xi"):
        th.fk_3_65(np.zeros(8), D)
    with pytest.raises(ShapeError, match="q_arm"):
        th.T_eb_3_58([0.0, 0.0], D)
    with pytest.raises(ShapeError, match="d"):
        th.J_eb_4_26(np.zeros(3), (0.1, 0.2))
