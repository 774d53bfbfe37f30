"""The thesis's printed closed forms (qprr.thesis.printed) against the Pinocchio model.

For every erratum of docs/thesis-errata.md there is a test that shows the printed form
wrong on a concrete counter-example AND the corrected form right against the model;
the printed forms that are right are checked over random states.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr.thesis
from qprr import actuation as act
from qprr import charts as co
from qprr import dynamics as dyn
from qprr import kinematics as kin
from qprr.errors import InputError, ShapeError
from qprr.thesis import printed as th
from qprr.thesis.checks import body_rate_fd, christoffel, doolittle, fixed_base_arm, ned_configuration
from qprr.thesis.params import thesis_params

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)

P = thesis_params()
D = th.d_lengths(P)
L, B_F, C_D = P.arm_length, P.thrust_factor, P.drag_factor
M1, M2, M3 = (link.mass for link in P.links)

_angle = st.floats(-math.pi, math.pi)
_tilt = st.floats(-1.3, 1.3)
_rate = st.floats(-3.0, 3.0)
_arm = st.tuples(*(st.floats(float(a), float(b)) for a, b in zip(P.lower_limits, P.upper_limits))).map(np.array)
_xi = st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3), _tilt, _tilt, _angle, _arm).map(lambda t: np.concatenate([t[:6], t[6]]))
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


def ned_model(robot):
    """A copy of the Pinocchio model with gravity +g e3 (the NED convention of (3.42))."""
    model = pin.Model(robot.model)
    model.gravity = pin.Motion(np.array([0.0, 0.0, P.g]), np.zeros(3))
    return model


def test_ned_configuration_is_the_ned_world(robot):
    """What the z-up model computes at ned_configuration(q) is what a model with gravity +g e3 computes
    at q: potential energy and the whole generalised gravity (base rows in B, arm rows)."""
    model = ned_model(robot)
    dn, rng = model.createData(), np.random.default_rng(3)
    for _ in range(10):
        xi = np.concatenate([rng.uniform(-2, 2, 3), rng.uniform(-1.2, 1.2, 3), rng.uniform(P.lower_limits, P.upper_limits)])
        q = co.xi_to_q(xi)
        q_up = ned_configuration(q)
        np.testing.assert_allclose(q_up[7:], q[7:], atol=0)
        assert dyn.potential_energy(robot, robot.data(), q_up) == pytest.approx(pin.computePotentialEnergy(model, dn, q), abs=1e-12)
        np.testing.assert_allclose(dyn.generalized_gravity(robot, robot.data(), q_up), pin.computeGeneralizedGravity(model, dn, q), atol=1e-12)


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
    Om = robot.rotor_matrix
    np.testing.assert_allclose(Om[0:2], 0.0, atol=1e-15)
    printed = th.allocation_3_36(L, C_D)
    np.testing.assert_allclose(printed[0:3], Om[2:5], atol=1e-15)  # thrust, roll and pitch rows are right
    # one newton on rotor 1 gives a yaw torque of kappa = c/b = 0.025 N m, not c = 7.5e-7
    assert Om[5, 0] == pytest.approx(0.025) and printed[3, 0] == pytest.approx(7.5e-7)
    np.testing.assert_allclose(th.allocation_3_36_corrected(L, B_F, C_D), Om[2:6], atol=1e-15)


def test_allocation_3_36_corrected_for_other_rotor_parameters():
    other = P.with_changes(arm_length=0.31, thrust_factor=2.0e-5, drag_factor=9.0e-7)
    Om = qprr.thesis.load_qprr(other).rotor_matrix
    np.testing.assert_allclose(th.allocation_3_36_corrected(0.31, 2.0e-5, 9.0e-7), Om[2:6], atol=1e-15)


def test_allocation_3_37_row3_contradicts_3_34(robot):
    w2 = np.array([1.0e5, 0.0, 0.0, 0.0])  # only rotor 1 (on -x_B) spins
    true = B_F * robot.rotor_matrix[2:6] @ w2
    assert true[2] == pytest.approx(B_F * L * 1.0e5)  # (3.34): tau_theta = bl(w1^2 - w3^2) > 0
    printed = th.allocation_3_37(B_F, L, C_D) @ w2
    assert printed[2] == pytest.approx(-B_F * L * 1.0e5)
    np.testing.assert_allclose(th.allocation_3_37_corrected(B_F, L, C_D) @ w2, true, rtol=1e-12)


def test_det_3_37_is_that_of_the_printed_matrix_not_of_the_true_one(robot):
    printed_matrix = th.allocation_3_37(B_F, L, C_D)
    assert np.linalg.det(printed_matrix) == pytest.approx(th.det_3_37(B_F, L, C_D), rel=1e-12)
    true = np.linalg.det(B_F * robot.rotor_matrix[2:6])
    assert true == pytest.approx(th.det_3_37_corrected(B_F, L, C_D), rel=1e-12)
    assert true == pytest.approx(-8 * C_D * L**2 * B_F**3, rel=1e-12)


def test_rotor_inverse_A1_has_the_wrong_tau_theta_sign(robot):
    u = np.array([0.0, 0.0, 1.0, 0.0])  # ask for +1 N m of pitch torque only
    f = th.rotor_inverse_A1(L, C_D) @ u
    achieved = th.allocation_3_36(L, C_D) @ f
    np.testing.assert_allclose(achieved, [0, 0, -1, 0], atol=1e-12)  # the printed inverse pitches the wrong way
    f_ok = th.rotor_inverse_A1_corrected(L, B_F, C_D) @ u
    np.testing.assert_allclose(robot.rotor_matrix[2:6] @ f_ok, u, atol=1e-12)
    np.testing.assert_allclose(th.rotor_inverse_A1_corrected(L, B_F, C_D), act.Allocator(robot).Omega_P_inv, atol=1e-12)


# ================================================================== (3.42)-(3.44)
def test_potential_3_42_is_the_ned_potential(robot):
    rng = np.random.default_rng(42)
    for _ in range(10):
        xi = np.concatenate([np.zeros(3), rng.uniform(-1.2, 1.2, 3), rng.uniform(P.lower_limits, P.upper_limits)])
        R, q = co.euler_to_rotation(xi[3:6]), co.xi_to_q(xi)
        U = th.potential_3_42(R, xi[6:9], P)
        assert U == pytest.approx(dyn.potential_energy(robot, robot.data(), ned_configuration(q)), abs=1e-12)
        assert -U == pytest.approx(dyn.potential_energy(robot, robot.data(), q), abs=1e-12)  # z up: opposite sign


def test_arm_torque_3_43_sign_is_that_of_ned(robot, data):
    # level base, arm bent forward (theta2 = pi/2): the arm's weight pitches the nose down,
    # i.e. a positive torque about y_B in our z-up frames
    xi = np.array([0, 0, 0, 0, 0, 0, 0.0, np.pi / 2, 0.0])
    q = co.xi_to_q(xi)
    model_tau = kin.arm_gravity_torque_body(robot, data, q)
    x_c = th.arm_com_3_44(xi[6:9], P)[0]
    assert model_tau[1] == pytest.approx(P.arm_mass * P.g * x_c) and model_tau[1] > 0.4
    printed = th.arm_torque_3_43(np.eye(3), xi[6:9], P)
    assert printed[1] == pytest.approx(-model_tau[1])
    np.testing.assert_allclose(th.arm_torque_3_43_corrected(np.eye(3), xi[6:9], P), model_tau, atol=1e-12)
    np.testing.assert_allclose(printed, kin.arm_gravity_torque_body(robot, robot.data(), ned_configuration(q)), atol=1e-12)


@SETTINGS
@given(_xi)
def test_arm_torque_3_43_over_random_states(robot, xi):
    data, q, R = robot.data(), co.xi_to_q(xi), co.euler_to_rotation(xi[3:6])
    np.testing.assert_allclose(th.arm_torque_3_43_corrected(R, xi[6:9], P), kin.arm_gravity_torque_body(robot, data, q), atol=1e-12)
    np.testing.assert_allclose(th.arm_com_3_44(xi[6:9], P), kin.arm_com(robot, data, q)[2], atol=1e-14)


# ================================================================== geometric model (3.58)-(3.68)
@SETTINGS
@given(_xi)
def test_direct_geometric_model_3_58_3_62_3_65(robot, xi):
    data, q = robot.data(), co.xi_to_q(xi)
    R_e = th.R_e_3_62(*xi[3:6], xi[7], xi[8])
    zyz_defined = np.hypot(R_e[0, 2], R_e[1, 2]) > 1e-6  # (3.64) assumes r13, r23 not both 0
    np.testing.assert_allclose(th.T_eb_3_58(xi[6:9], D), kin.ee_placement_body(robot, data, q).homogeneous, atol=1e-14)
    M = kin.ee_placement(robot, data, q)
    np.testing.assert_allclose(th.R_e_3_62(*xi[3:6], xi[7], xi[8]), M.rotation, atol=1e-14)
    chi = th.fk_3_65(xi, D)
    np.testing.assert_allclose(chi[0:3], M.translation, atol=1e-13)
    if zyz_defined:
        np.testing.assert_allclose(th.zyz_to_rotation(chi[3:6]), M.rotation, atol=1e-9)
    np.testing.assert_allclose(th.p_e_3_61_corrected(xi, D), M.translation, atol=1e-13)


def test_p_e_3_61_y_row_misprint(robot, data):
    xi = np.array([0, 0, 0, 0, 0, np.pi / 2, 0.0, np.pi / 2, 0.0])  # yaw 90 deg, arm bent forward
    p = kin.ee_placement(robot, data, co.xi_to_q(xi)).translation
    x_eb = P.d2 + P.d3  # theta2 = pi/2: the arm points along x_B, which is world y after the yaw
    np.testing.assert_allclose(p[0:2], [0.0, x_eb], atol=1e-14)
    assert th.p_e_3_61(xi, D)[1] == pytest.approx(0.0, abs=1e-14)  # printed c_theta c_psi x_eb = 0
    np.testing.assert_allclose(th.p_e_3_61_corrected(xi, D), p, atol=1e-14)


def test_euler_3_64_is_a_zyz_extraction(robot, data):
    xi = np.array([0, 0, 0, 0.2, -0.3, 0.7, 0.0, 0.5, 0.4])
    R = kin.ee_placement(robot, data, co.xi_to_q(xi)).rotation
    ang = th.euler_3_64(R)
    np.testing.assert_allclose(th.zyz_to_rotation(ang), R, atol=1e-14)
    assert 0.0 <= ang[1] <= np.pi
    assert np.abs(th.rotation_3_4(*ang) - R).max() > 0.3  # not the ZYX angles of (3.4)/(3.8)


def test_hover_fk_3_68_angle_lines_misprint(robot, data):
    psi, q_arm = 0.5, np.array([0.01, 0.2, 0.1])  # s23 > 0
    xi = np.array([0.1, -0.2, 1.0, 0.0, 0.0, psi, *q_arm])
    M = kin.ee_placement(robot, data, co.xi_to_q(xi))
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
    true = th.euler_3_64(kin.ee_placement(robot, data, co.xi_to_q(xi)).rotation)
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
    c = kin.com_body(robot, data, co.xi_to_q(np.concatenate([np.zeros(6), q_arm])))
    np.testing.assert_allclose(th.com_3_78(q_arm, P)[0:2], c[0:2], atol=1e-15)
    assert th.x_cm_3_80(q_arm, P) == pytest.approx(c[0], abs=1e-15)
    np.testing.assert_allclose(th.com_3_78_corrected(q_arm, P), c, atol=1e-15)


def test_com_3_78_z_misprint(robot, data):
    c = kin.com_body(robot, data, co.xi_to_q(np.zeros(9)))  # arm straight up
    mG, d0, d1, d2, d3 = P.total_mass, *D
    true = (M1 * (d0 + d1 / 2) + M2 * (d0 + d1 + d2 / 2) + M3 * (d0 + d1 + d2 + d3 / 2)) / mG
    assert c[2] == pytest.approx(true, abs=1e-15)
    printed = th.com_3_78(np.zeros(3), P)[2]
    assert printed - true == pytest.approx((M1 * d1 / 2 - M3 * d2 / 2) / mG, abs=1e-15)
    assert abs(printed - true) > 1e-3
    assert th.com_3_78_corrected(np.zeros(3), P)[2] == pytest.approx(true, abs=1e-15)


def test_payload_centre_3_76(robot, data):
    q_arm, d_cl = np.array([0.02, 0.8, 0.4]), 0.03
    M = kin.ee_placement_body(robot, data, co.xi_to_q(np.concatenate([np.zeros(6), q_arm])))
    np.testing.assert_allclose(th.payload_com_3_76(q_arm, D, d_cl), M.act(np.array([0.0, 0.0, d_cl])), atol=1e-15)


def test_com_3_78_payload_term_misprint(robot, data):
    from qprr.payload import Payload, com_with_payload

    q_arm, m_l, d_cl = np.array([0.02, 0.8, 0.4]), 0.1, 0.03
    model = com_with_payload(robot, data, q_arm, Payload(m_l, com_ee=(0.0, 0.0, d_cl)))
    printed = th.com_3_78(q_arm, P, m_l=m_l, d_cl=d_cl)
    x_cl = th.payload_com_3_76(q_arm, D, d_cl)[0]
    m_G = P.total_mass + m_l  # (3.77)
    # "+ x_cl" adds a length where (3.76) has m_l x_cl: printed - true = (1 - m_l) x_cl / m_G
    assert printed[0] - model[0] == pytest.approx((1.0 - m_l) * x_cl / m_G, abs=1e-15)
    assert abs(printed[0] - model[0]) > 0.02
    np.testing.assert_allclose(th.com_3_78_corrected(q_arm, P, m_l=m_l, d_cl=d_cl), model, atol=1e-15)
    # Remark 3: without load p_cl = 0, and the printed form is the no-load (3.78)
    np.testing.assert_allclose(th.com_3_78(q_arm, P, m_l=0.0, d_cl=d_cl), th.com_3_78(q_arm, P), atol=0)


@SETTINGS
@given(_arm, st.floats(0.0, 2.0), st.floats(-0.05, 0.2))
def test_com_3_78_corrected_with_any_payload_is_pinocchio(robot, q_arm, m_l, d_cl):
    from qprr.payload import Payload, com_with_payload

    model = com_with_payload(robot, robot.data(), q_arm, Payload(m_l, com_ee=(0.0, 0.0, d_cl)))
    np.testing.assert_allclose(th.com_3_78_corrected(q_arm, P, m_l=m_l, d_cl=d_cl), model, atol=1e-15)


def test_com_3_78_rejects_a_bad_payload():
    with pytest.raises(InputError, match="m_l"):
        th.com_3_78(np.zeros(3), P, m_l=-0.1)
    with pytest.raises(InputError, match="d_cl"):
        th.com_3_78_corrected(np.zeros(3), P, m_l=0.1, d_cl=float("inf"))
    with pytest.raises(TypeError):
        th.com_3_78(np.zeros(3), P, 0.1)  # the payload arguments are keyword-only


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
    Jm = kin.arm_jacobian_body(robot, data, q_arm)
    np.testing.assert_allclose(J, Jm, atol=1e-14)
    np.testing.assert_allclose(J, _arm_jacobian_fd(q_arm), atol=1e-8)
    np.testing.assert_allclose(th.J_4_27(q_arm, D), Jm[[0, 2, 4]], atol=1e-14)
    assert th.det_4_28(q_arm[1], P.d2) == pytest.approx(np.linalg.det(Jm[[0, 2, 4]]), abs=1e-14)


def _pose_fd(robot, data, xi, xid, h=1e-6):
    pp, Rp = kin.ee_pose_xi(robot, data, xi + h * xid)
    pm, Rm = kin.ee_pose_xi(robot, data, xi - h * xid)
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
    J = kin.jacobian_xi(robot, data, xi)
    np.testing.assert_allclose(th.J_e_4_12_corrected(xi, D), J, atol=1e-13)
    np.testing.assert_allclose(J @ xid, _pose_fd(robot, data, xi, xid), atol=1e-7)


def _det_zero_euler(robot, data, q_arm):
    J = kin.jacobian_xi(robot, data, np.concatenate([np.zeros(6), q_arm]))
    return np.linalg.det(J @ J.T)


@pytest.mark.parametrize("d3", [0.10, 0.02, 0.40])
def test_det_JJt_4_44_is_exact_and_independent_of_d3_and_theta3(d3):
    robot = qprr.thesis.load_qprr(P.with_changes(d3=d3))
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


def _model_lu(robot, data, q_arm):
    J = kin.jacobian_xi(robot, data, np.concatenate([np.zeros(6), q_arm]))
    A = J @ J.T
    return A, *doolittle(A)


def _entry(name, L, U):
    return (L if name[0] == "a" else U)[int(name[1]) - 1, int(name[2]) - 1]


LU_SAMPLES = [np.array([0.0, 0.0, 0.0]), np.array([0.03, 0.9, -0.6]), np.array([-0.02, -1.7, 1.2]), np.array([0.04, 2.0, 0.3])]
LU_MISPRINTS = ("a53", "b55")


@pytest.mark.parametrize("name", [n for n in th.LU_L_NAMES + th.LU_U_NAMES if n != "a31"])
def test_lu_factor_4_42_one_by_one(robot, data, name):
    for q in LU_SAMPLES:
        A, L, U = _model_lu(robot, data, q)
        np.testing.assert_allclose(L @ U, A, atol=1e-15)
        printed, corrected = th.lu_factors_4_42(q, D)[name], th.lu_factors_4_42_corrected(q, D)[name]
        assert corrected == pytest.approx(_entry(name, L, U), abs=1e-14)
        if name not in LU_MISPRINTS:
            assert printed == pytest.approx(_entry(name, L, U), abs=1e-14)
    if name in LU_MISPRINTS:  # wrong on at least one sample, by far more than round-off
        assert max(abs(th.lu_factors_4_42(q, D)[name] - _entry(name, *_model_lu(robot, data, q)[1:])) for q in LU_SAMPLES) > 1e-4


def test_lu_4_42_sparsity_and_factorisation(robot, data):
    for q in LU_SAMPLES:
        A, L, U = _model_lu(robot, data, q)
        Lc, Uc = th.lu_matrices_4_42(th.lu_factors_4_42_corrected(q, D))
        np.testing.assert_allclose(Lc, L, atol=1e-14)  # zeros exactly where (4.42) prints them
        np.testing.assert_allclose(Uc, U, atol=1e-14)
        assert th.lu_factors_4_42_corrected(q, D)["a31"] == pytest.approx(L[2, 0], abs=1e-15)  # a31: no printed formula


def test_lu_a53_no_reading_of_the_printed_parentheses_holds(robot, data):
    q = np.array([0.03, 0.9, -0.6])
    _, L, _ = _model_lu(robot, data, q)
    f = th.lu_factors_4_42(q, D)
    r0, t2, t3 = q
    X = r0 + 3 * P.d3 * np.sin(t2 + t3) + 2 * P.d2 * np.sin(t2)
    N = -f["b13"]
    literal = -(X - N * f["b15"] / f["b11"]) - N**2 / f["b11"] + 1  # the text, unmatched ")" dropped
    as_fraction = -(X - N * f["b15"] / f["b11"]) / (1 - N**2 / f["b11"])  # the missing "/(" restored
    assert f["a53"] == pytest.approx(literal)
    for reading in (literal, as_fraction):
        assert abs(reading - L[4, 2]) > 1e-2  # round-off is 1e-16
    assert f["b35"] / f["b33"] == pytest.approx(L[4, 2], abs=1e-15)  # a53 = b35 / b33


def test_det_4_43_product_of_the_printed_b_ii(robot, data):
    q = np.array([0.03, 0.9, -0.6])
    A, _, U = _model_lu(robot, data, q)
    det = np.linalg.det(A)
    assert np.prod(np.diag(U)) == pytest.approx(det, rel=1e-14)  # (4.43) as an identity
    assert th.det_4_43(th.lu_factors_4_42_corrected(q, D)) == pytest.approx(det, rel=1e-14)
    assert abs(th.det_4_43(th.lu_factors_4_42(q, D)) - det) > 1e-5  # the printed b55 spoils it
    assert th.det_4_43(th.lu_factors_4_42_corrected(q, D)) == pytest.approx(th.det_JJt_4_44(q[0], q[1], D), rel=1e-14)


def test_det_4_45_basis_needs_r0_s2(robot, data):
    rng = np.random.default_rng(45)
    qs = [np.array([rng.uniform(-0.04, 0.04), rng.uniform(-np.pi, np.pi), rng.uniform(-2, 2)]) for _ in range(60)]
    dets = np.array([_det_zero_euler(robot, data, q) for q in qs])
    B = np.array([th.basis_4_45(q[0], q[1]) for q in qs])
    lam = np.linalg.lstsq(B, dets, rcond=None)[0]
    assert np.abs(B @ lam - dets).max() > 1e-2  # no constant lambda_1..8 fits: the r0 s2 term is missing
    for q, det in zip(qs, dets):
        assert th.det_JJt_4_45_corrected(q[0], q[1], D) == pytest.approx(det, rel=1e-13)
        assert th.det_JJt_4_45_corrected(q[0], q[1], D) == pytest.approx(th.det_JJt_4_44(q[0], q[1], D), rel=1e-14)
    # lambda_7 r0 = 4 d2 r0 is the s2 coefficient of (4.46) and (4.48): -+0.0288 at r0 = -+0.04
    assert th.lambdas_4_45_corrected(D)[6] * 0.04 == pytest.approx(0.0288, abs=1e-15)
    with pytest.raises(ShapeError, match="lambdas"):
        th.det_JJt_4_45(0.0, 0.0, np.ones(7))


# ================================================================== inertia blocks Sec. 5.2.2, (5.15)
@SETTINGS
@given(_xi)
def test_inertia_blocks_5_2_2(robot, xi):
    B = dyn.dynamics_xi(robot, robot.data(), xi, np.zeros(9))[0]
    printed, corrected = th.B_blocks_5_2_2(xi, P), th.B_blocks_5_2_2_corrected(xi, P)
    np.testing.assert_allclose(printed.B11, B[0:3, 0:3], atol=1e-13)
    np.testing.assert_allclose(printed.B12, B[0:3, 3:6], atol=1e-13)
    np.testing.assert_allclose(printed.B13, B[0:3, 6:9], atol=1e-13)
    np.testing.assert_allclose(corrected.matrix(), B, atol=1e-13)


def test_inertia_blocks_5_2_2_misprints(robot, data):
    xi = np.array([0, 0, 0, 0.5, -0.4, 0.9, 0.02, 0.7, -0.5])
    B = dyn.dynamics_xi(robot, data, xi, np.zeros(9))[0]
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
    for j in (joint.joint_id for joint in robot.arm):
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
    assert th.potential_5_29(xi, P) == pytest.approx(dyn.potential_energy(robot, robot.data(), co.xi_to_q(xi)), abs=1e-11)


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
    N = robot.actuation_matrix
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


def test_arm_u3_5_5_3_with_velocities_and_s23_nonzero(arm_fixed_down):
    model, data = arm_fixed_down
    q, qd, qdd = np.array([0.01, 0.5, 0.4]), np.array([0.2, -1.1, 0.8]), np.array([0.3, -0.5, 0.7])
    Ix3, Iy3, Iz3 = P.links[2].inertia[:3]
    s23, c23, s3 = np.sin(0.9), np.cos(0.9), np.sin(0.4)
    w2, w3 = qd[1], qd[2]
    tau = pin.rnea(model, data, q, qd, qdd)[2]
    printed = th.arm_u_5_5(q, qd, qdd, P)[2]
    # printed - true: the spurious b33 terms, in the acceleration AND in the velocity products
    spurious = (Iz3 + s23**2 * (Ix3 - Iz3)) * qdd[2] + (Ix3 - Iz3) * s23 * c23 * (w3**2 + 2 * w2 * w3)
    assert printed - tau == pytest.approx(spurious, abs=1e-15)
    # the velocity part alone (zero accelerations): model = (1/2) d2 d3 m3 s3 theta2_dot^2 + G
    g3 = pin.computeGeneralizedGravity(model, data, q)[2]
    v_true = pin.rnea(model, data, q, qd, np.zeros(3))[2] - g3
    assert v_true == pytest.approx(0.5 * P.d2 * P.d3 * M3 * s3 * w2**2, abs=1e-15)
    v_printed = th.arm_u_5_5(q, qd, np.zeros(3), P)[2] - th.arm_G_5_5(q, P)[2]
    assert v_printed - v_true == pytest.approx((Ix3 - Iz3) * s23 * c23 * (w3**2 + 2 * w2 * w3), abs=1e-15)
    if Ix3 != Iz3:  # the velocity misprint is visible whenever link 3 is not axisymmetric about its axis
        assert abs(v_printed - v_true) > 0.1 * abs(Ix3 - Iz3)
    assert th.arm_u_5_5_corrected(q, qd, qdd, P)[2] == pytest.approx(tau, abs=1e-15)


# ================================================================== CoG motion and BSG, (6.29)-(6.35)
@SETTINGS
@given(_xi, _rates9)
def test_cog_6_29_position_and_rate(robot, xi, xid):
    data = robot.data()
    q, v = co.xi_to_qv(xi, xid)
    p_cm = kin.com_body(robot, data, q)
    R = co.euler_to_rotation(xi[3:6])
    np.testing.assert_allclose(th.p_c_6_29(xi[0:3], R, p_cm), kin.com_world(robot, data, q), atol=1e-14)
    pin.centerOfMass(robot.model, data, q, v)
    vcom = data.vcom[0].copy()
    p_cm_dot = kin.com_jacobian_body(robot, data, q) @ v
    np.testing.assert_allclose(th.p_c_dot_6_29(xid[0:3], R, v[3:6], p_cm, p_cm_dot), vcom, atol=1e-13)


def test_cog_6_29_rate_needs_the_body_rate(robot, data):
    xi = np.array([0, 0, 0, 0.6, 0.0, 0.0, 0.0, 1.0, 0.3])  # rolled, arm bent forward
    xid = np.array([0, 0, 0, 0, 0, 1.0, 0, 0, 0])  # pure yaw rate
    q, v = co.xi_to_qv(xi, xid)
    pin.centerOfMass(robot.model, data, q, v)
    p_cm, R = kin.com_body(robot, data, q), co.euler_to_rotation(xi[3:6])
    np.testing.assert_allclose(th.p_c_dot_6_29(np.zeros(3), R, v[3:6], p_cm, np.zeros(3)), data.vcom[0], atol=1e-15)
    world = th.p_c_dot_6_29(np.zeros(3), R, R @ v[3:6], p_cm, np.zeros(3))  # omega_b read as a world rate
    assert np.linalg.norm(world - data.vcom[0]) > 1e-3


@SETTINGS
@given(_arm)
def test_com_6_30_z_misprint(robot, q_arm):
    c = kin.com_body(robot, robot.data(), co.xi_to_q(np.concatenate([np.zeros(6), q_arm])))
    printed = th.com_6_30(q_arm, P)
    np.testing.assert_allclose(printed[0:2], c[0:2], atol=1e-15)
    assert printed[2] - c[2] == pytest.approx(M1 * P.d1 / (2 * P.total_mass), abs=1e-15)  # m1 (d0 + d1) for m1 (d0 + d1/2)
    assert th.com_3_78_corrected(q_arm, P)[2] == pytest.approx(c[2], abs=1e-15)


def test_cog_6_31_6_32_pitch_moves_the_cog_in_world_axes_only(robot, data):
    xi = np.array([0.5, -0.2, 1.0, 0.0, 0.25, 0.0, 0.02, -0.7, 0.4])  # phi = psi = 0
    q = co.xi_to_q(xi)
    p_cm = kin.com_body(robot, data, q)
    offset = kin.com_world(robot, data, q) - xi[0:3]
    np.testing.assert_allclose(th.p_cm_prime_6_31(0.25, p_cm), offset, atol=1e-15)
    np.testing.assert_allclose(th.nabla_p_cm_6_32(0.25, p_cm), offset - p_cm, atol=1e-15)
    level = xi.copy()
    level[4] = 0.0
    np.testing.assert_allclose(kin.com_body(robot, data, co.xi_to_q(level)), p_cm, atol=1e-15)  # in B nothing moved
    rolled = xi.copy()
    rolled[3] = 0.3
    q = co.xi_to_q(rolled)
    assert np.abs(th.p_cm_prime_6_31(0.25, p_cm) - (kin.com_world(robot, data, q) - xi[0:3])).max() > 1e-3


@SETTINGS
@given(_tilt, _angle, _arm)
def test_theta_e_6_34_is_the_end_effector_pitch_at_zero_roll(robot, theta, psi, q_arm):
    xi = np.array([0.0, 0.0, 0.0, 0.0, theta, psi, *q_arm])
    R_e = kin.ee_placement(robot, robot.data(), co.xi_to_q(xi)).rotation
    np.testing.assert_allclose(R_e, co.rot_z(psi) @ co.rot_y(th.theta_e_6_34(theta, q_arm[1], q_arm[2])), atol=1e-14)


def test_theta_e_6_34_is_not_the_zyz_angle_and_needs_zero_roll(robot, data):
    xi = np.array([0.0, 0.0, 0.0, 0.0, 0.1, 0.3, 0.0, -0.2, -0.3])  # theta + theta2 + theta3 = -0.4
    R_e = kin.ee_placement(robot, data, co.xi_to_q(xi)).rotation
    assert th.euler_3_64(R_e)[1] == pytest.approx(0.4)  # the ZYZ theta_e of (3.64) is |theta_e|
    xi[3] = 0.2
    R_e = kin.ee_placement(robot, data, co.xi_to_q(xi)).rotation
    assert np.abs(R_e - co.rot_z(0.3) @ co.rot_y(-0.4)).max() > 0.1


def test_bsg_6_35_references_put_the_cog_on_the_thrust_axis_in_the_model(robot, data):
    from qprr.control import make_controller
    from qprr.thesis.bsg import CogStabilizer

    bsg = CogStabilizer(robot, make_controller("mfc", robot))
    for theta, theta2_d, theta_e_d, psi in [(0.1, -0.3, 0.2, 0.5), (-0.2, 0.4, -0.1, -2.0), (0.0, 0.2, 0.0, 1.0)]:
        bsg.theta_e_d = theta_e_d
        r0_d, theta3_d = bsg.joint_references(theta, theta2_d)
        assert P.r0_limits[0] < r0_d < P.r0_limits[1]  # not clamped
        q = co.xi_to_q(np.array([0.3, 0.1, 2.0, 0.0, theta, psi, r0_d, theta2_d, theta3_d]))
        assert kin.com_body(robot, data, q)[0] == pytest.approx(0.0, abs=1e-15)
        R_e = kin.ee_placement(robot, data, q).rotation
        np.testing.assert_allclose(R_e, co.rot_z(psi) @ co.rot_y(theta_e_d), atol=1e-15)


# ================================================================== inputs
def test_closed_forms_validate_their_vectors():
    with pytest.raises(ShapeError, match="xi"):
        th.fk_3_65(np.zeros(8), D)
    with pytest.raises(ShapeError, match="q_arm"):
        th.T_eb_3_58([0.0, 0.0], D)
    with pytest.raises(ShapeError, match="d"):
        th.J_eb_4_26(np.zeros(3), (0.1, 0.2))
