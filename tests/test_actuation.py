"""Rotor allocation Omega, N and the input map u = R_Q N f (Thesis (3.36), (5.40)-(5.46))."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr.thesis
from qprr import actuation as act
from qprr import charts as co
from qprr.errors import UnknownNameError

from .conftest import random_xi


def _platform(layout: str):
    """The thesis's Q-PRR in ``layout`` ("plus" or "x")."""
    return qprr.thesis.load_qprr(layout=layout)


def test_plus_layout_is_3_36_with_c_over_b(robot):
    l, k = robot.params.arm_length, robot.params.kappa
    printed_rows = np.array([[1, 1, 1, 1], [0, -l, 0, l], [l, 0, -l, 0], [k, -k, k, -k]])
    Omega = robot.rotor_matrix
    np.testing.assert_allclose(Omega[2:6], printed_rows, atol=1e-15)
    np.testing.assert_allclose(Omega[0:2], 0.0)


def test_x_layout_is_the_plus_layout_turned_45_degrees(robot):
    P, X = robot.rotor_matrix, _platform("x").rotor_matrix
    Rz = co.rot_z(np.pi / 4)
    np.testing.assert_allclose(X[3:5], Rz[0:2, 0:2] @ P[3:5], atol=1e-15)
    np.testing.assert_allclose(X[[2, 5]], P[[2, 5]], atol=1e-15)


@pytest.mark.parametrize("layout", ["plus", "x"])
def test_N_f_equals_the_rotor_forces_applied_as_external_forces(robot, layout):
    """tau = N f must produce the same motion as the 4 thrusts and drag torques applied at the rotor frames."""
    rng = np.random.default_rng(1)
    data = robot.data()
    xi = random_xi(rng, robot)
    q, v = co.xi_to_qv(xi, rng.uniform(-1, 1, 9))
    f = np.concatenate([rng.uniform(0, 15, 4), rng.uniform(-2, 2, 3)])
    platform = _platform(layout)
    a_N = pin.aba(robot.model, data, q, v, platform.actuation_matrix @ f)
    fext = [pin.Force.Zero() for _ in range(robot.model.njoints)]
    rotor_frames = [robot.model.getFrameId(f"rotor_{layout}_{i}") for i in range(1, 5)]  # the URDF's rotor frames
    for fi, fid, rotor in zip(f[:4], rotor_frames, robot.params.rotors(layout)):
        frame = robot.model.frames[fid]  # attached to joint 1: placement is in B
        z = frame.placement.rotation[:, 2]
        local = pin.Force(fi * z, rotor.spin * robot.params.kappa * fi * z)  # at the rotor origin
        Rt = frame.placement.rotation.T
        fext[frame.parentJoint] += frame.placement.act(pin.Force(Rt @ local.linear, Rt @ local.angular))
    tau = np.concatenate([np.zeros(6), f[4:]])
    a_ext = pin.aba(robot.model, data, q, v, tau, fext)
    np.testing.assert_allclose(a_N, a_ext, atol=1e-10)


def test_input_map_preserves_power(robot):
    """u^T xi_dot = f_world . p_dot + tau_body . omega_body + mu . q_arm_dot: R_Q = S^T, not (5.41)'s R_b^T T."""
    rng = np.random.default_rng(2)
    for _ in range(10):
        xi, xi_dot = random_xi(rng, robot), rng.uniform(-1, 1, 9)
        f = np.concatenate([rng.uniform(0, 15, 4), rng.uniform(-2, 2, 3)])
        u = act.input_map(robot, xi, f)
        wrench = robot.rotor_matrix @ f[:4]
        R = co.euler_to_rotation(xi[3:6])
        omega_body = co.euler_rate_matrix(xi[3:6]) @ xi_dot[3:6]
        power = (R @ wrench[0:3]) @ xi_dot[0:3] + wrench[3:6] @ omega_body + f[4:] @ xi_dot[6:9]
        assert u @ xi_dot == pytest.approx(power, rel=1e-12, abs=1e-12)


def test_hover_thrusts_hold_the_balanced_system_still(robot):
    """At a CoG-balanced arm pose, equal thrusts m_G g / 4 and gravity-holding arm efforts give zero acceleration."""
    data = robot.data()
    f_h = act.Allocator(robot).hover_thrusts()
    np.testing.assert_allclose(f_h, robot.params.hover_thrust(), rtol=1e-12)
    q = pin.neutral(robot.model)  # arm straight up: CoG on z_B
    g = pin.computeGeneralizedGravity(robot.model, data, q)
    np.testing.assert_allclose(g[6:9], [0.0, 0.0, 0.0], atol=1e-12)  # arm efforts are zero there
    a = pin.aba(robot.model, data, q, np.zeros(9), robot.actuation_matrix @ np.concatenate([f_h, g[6:9]]))
    np.testing.assert_allclose(a, 0.0, atol=1e-12)


def test_allocation_inverse_recovers_thrusts(robot):
    rng = np.random.default_rng(3)
    f = rng.uniform(0, 15, 4)
    w = robot.rotor_matrix[2:6] @ f
    np.testing.assert_allclose(act.Allocator(robot).Omega_P_inv @ w, f, atol=1e-12)


def test_generalized_force_from_wrench_is_J_transpose_h(robot):
    rng = np.random.default_rng(4)
    data = robot.data()
    q = co.xi_to_q(random_xi(rng, robot))
    h = rng.uniform(-1, 1, 6)
    J = pin.computeFrameJacobian(robot.model, data, q, robot.ee_frame, pin.LOCAL_WORLD_ALIGNED)
    np.testing.assert_allclose(act.generalized_force_from_wrench(robot, data, q, h), J.T @ h)
    with pytest.raises(UnknownNameError, match="frame"):
        act.generalized_force_from_wrench(robot, data, q, h, frame="gripper")


def test_unknown_layout_lists_valid_ones(robot):
    with pytest.raises(UnknownNameError, match="valid: 'plus', 'x'"):
        _platform("hexa")
    with pytest.raises(KeyError):
        _platform("H")
