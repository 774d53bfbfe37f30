"""The Pinocchio model against physics: kinematics by finite differences, CoM, energies."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr
import qprr.thesis
from qprr import charts as co
from qprr import dynamics as dyn
from qprr import kinematics as kin
from qprr.errors import LimitError, NonFiniteError, ShapeError, UnknownNameError

from .conftest import random_xi


def _pose_error(M_ref: pin.SE3, M: pin.SE3) -> np.ndarray:
    """[p - p_ref; log(R_ref^T R) rotated to world] for finite differences on SE(3)."""
    return np.concatenate([M.translation - M_ref.translation, M_ref.rotation @ pin.log3(M_ref.rotation.T @ M.rotation)])


@pytest.mark.parametrize("seed", range(5))
def test_jacobian_xi_matches_finite_differences(robot, data, seed):
    """Thesis (4.13): [p_e_dot; omega_e] = J_e xi_dot, checked on the SE(3) manifold."""
    rng = np.random.default_rng(seed)
    xi = random_xi(rng, robot)
    J = kin.jacobian_xi(robot, data, xi)
    h = 1e-6
    for k in range(9):
        e = np.zeros(9)
        e[k] = h
        Mp = kin.ee_placement(robot, data, co.xi_to_q(xi + e))
        Mm = kin.ee_placement(robot, data, co.xi_to_q(xi - e))
        fd = _pose_error(Mm, Mp) / (2 * h)
        np.testing.assert_allclose(J[:, k], fd, atol=1e-7)


def test_arm_jacobian_body_matches_finite_differences(robot, data):
    """Thesis (4.26): arm Jacobian in B depends on the arm joints only."""
    rng = np.random.default_rng(11)
    for _ in range(5):
        q_arm = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
        J = kin.arm_jacobian_body(robot, data, q_arm)
        h = 1e-6
        for k in range(3):
            q = pin.neutral(robot.model)
            qp, qm_ = q.copy(), q.copy()
            qp[7:10], qm_[7:10] = q_arm, q_arm
            qp[7 + k] += h
            qm_[7 + k] -= h
            fd = _pose_error(kin.ee_placement_body(robot, data, qm_), kin.ee_placement_body(robot, data, qp)) / (2 * h)
            np.testing.assert_allclose(J[:, k], fd, atol=1e-8)


def test_body_frame_pose_is_independent_of_the_base(robot, data):
    rng = np.random.default_rng(5)
    xi = random_xi(rng, robot)
    xi0 = np.zeros(9)
    xi0[6:9] = xi[6:9]
    a = kin.ee_placement_body(robot, data, co.xi_to_q(xi))
    b = kin.ee_placement_body(robot, data, co.xi_to_q(xi0))
    assert a.isApprox(b, 1e-12)
    # and the world pose composes as Thesis (3.61): T_e = T_b T_eb
    Tb = pin.SE3(co.euler_to_rotation(xi[3:6]), xi[0:3])
    assert kin.ee_placement(robot, data, co.xi_to_q(xi)).isApprox(Tb * a, 1e-12)


def test_com_body_is_the_mass_weighted_mean_of_the_bodies(robot, data):
    """Thesis (3.75)-(3.77) computed body by body from the joint placements."""
    rng = np.random.default_rng(6)
    xi = random_xi(rng, robot)
    q = co.xi_to_q(xi)
    pin.forwardKinematics(robot.model, data, q)
    m_tot, acc = 0.0, np.zeros(3)
    for j in range(1, robot.model.njoints):
        I = robot.model.inertias[j]
        acc += I.mass * data.oMi[j].act(I.lever)
        m_tot += I.mass
    c_world = acc / m_tot
    np.testing.assert_allclose(kin.com_world(robot, data, q), c_world, atol=1e-13)
    R, p = co.euler_to_rotation(xi[3:6]), xi[0:3]
    np.testing.assert_allclose(kin.com_body(robot, data, q), R.T @ (c_world - p), atol=1e-13)
    m_arm, c_arm_w, c_arm_b = kin.arm_com(robot, data, q)
    assert m_arm == pytest.approx(robot.params.arm_mass)
    np.testing.assert_allclose(m_arm * c_arm_b, m_tot * R.T @ (c_world - p), atol=1e-12)  # base CoM at B


def test_com_jacobian_body_matches_finite_differences(robot, data):
    rng = np.random.default_rng(7)
    q = co.xi_to_q(random_xi(rng, robot))
    J = kin.com_jacobian_body(robot, data, q)
    h = 1e-6
    for k in range(9):
        dv = np.zeros(9)
        dv[k] = h
        fd = (kin.com_body(robot, data, pin.integrate(robot.model, q, dv)) - kin.com_body(robot, data, pin.integrate(robot.model, q, -dv))) / (2 * h)
        np.testing.assert_allclose(J[:, k], fd, atol=1e-9)


def test_arm_gravity_torque_is_the_weight_moment_about_b(robot, data):
    """Thesis (3.43) physically: tau = c_arm^B x (R^T (-m_arm g e3)); equals minus the base rows of G."""
    rng = np.random.default_rng(8)
    for _ in range(5):
        xi = random_xi(rng, robot)
        q = co.xi_to_q(xi)
        tau = kin.arm_gravity_torque_body(robot, data, q)
        m_arm, _, c_b = kin.arm_com(robot, data, q)
        R = co.euler_to_rotation(xi[3:6])
        np.testing.assert_allclose(tau, np.cross(c_b, R.T @ np.array([0, 0, -m_arm * 9.8])), atol=1e-12)
        g = pin.computeGeneralizedGravity(robot.model, data, q)
        np.testing.assert_allclose(tau, -g[3:6], atol=1e-12)


def test_kinetic_energy_is_half_xi_dot_B_xi_dot(robot, data):
    """Thesis (5.25)."""
    rng = np.random.default_rng(9)
    xi, xi_dot = random_xi(rng, robot), rng.uniform(-1, 1, 9)
    B, _, _ = dyn.dynamics_xi(robot, data, xi, xi_dot)
    q, v = co.xi_to_qv(xi, xi_dot)
    assert dyn.kinetic_energy(robot, data, q, v) == pytest.approx(0.5 * xi_dot @ B @ xi_dot, rel=1e-12)
    np.testing.assert_allclose(B, B.T, atol=1e-14)
    assert np.linalg.eigvalsh(B).min() > 0


def test_gravity_vector_is_the_gradient_of_the_potential(robot, data):
    """Thesis (5.37): G = dU/dxi with U = sum m g z (5.29)."""
    rng = np.random.default_rng(10)
    xi = random_xi(rng, robot)
    _, _, G = dyn.dynamics_xi(robot, data, xi, np.zeros(9))
    h = 1e-6
    fd = np.array(
        [
            (dyn.potential_energy(robot, data, co.xi_to_q(xi + h * e)) - dyn.potential_energy(robot, data, co.xi_to_q(xi - h * e))) / (2 * h)
            for e in np.eye(9)
        ]
    )
    np.testing.assert_allclose(G, fd, atol=1e-7)
    assert G[2] == pytest.approx(robot.params.total_mass * 9.8, rel=1e-12)  # dU/dz is the total weight


def test_christoffel_matrix_matches_finite_differences_of_B(robot, data):
    """Thesis (5.35): c_ij = sum_k 1/2 (dB_ij/dxi_k + dB_ik/dxi_j - dB_jk/dxi_i) xi_dot_k."""
    rng = np.random.default_rng(12)
    xi, xi_dot = random_xi(rng, robot), rng.uniform(-2, 2, 9)
    _, C, _ = dyn.dynamics_xi(robot, data, xi, xi_dot)
    h = 1e-6
    dB = np.array(
        [(dyn.dynamics_xi(robot, data, xi + h * e, xi_dot)[0] - dyn.dynamics_xi(robot, data, xi - h * e, xi_dot)[0]) / (2 * h) for e in np.eye(9)]
    )
    C_fd = 0.5 * (np.einsum("kij,k->ij", dB, xi_dot) + np.einsum("jik,k->ij", dB, xi_dot) - np.einsum("ijk,k->ij", dB, xi_dot))
    np.testing.assert_allclose(C, C_fd, atol=1e-8)
    B_dot = np.einsum("kij,k->ij", dB, xi_dot)
    N = B_dot - 2 * C
    np.testing.assert_allclose(N, -N.T, atol=1e-8)  # Hypothesis 7


def test_forward_dynamics_xi_is_5_39(robot, data):
    rng = np.random.default_rng(13)
    xi, xi_dot, u = random_xi(rng, robot), rng.uniform(-1, 1, 9), rng.uniform(-5, 5, 9)
    B, C, G = dyn.dynamics_xi(robot, data, xi, xi_dot)
    np.testing.assert_allclose(dyn.forward_dynamics_xi(robot, data, xi, xi_dot, u), np.linalg.solve(B, u - C @ xi_dot - G), atol=1e-9)


def test_algorithms_do_not_modify_the_model(robot):
    before = [robot.model.inertias[j].copy() for j in range(robot.model.njoints)]
    gravity = robot.model.gravity.copy()
    data = robot.data()
    rng = np.random.default_rng(14)
    xi = random_xi(rng, robot)
    dyn.dynamics_xi(robot, data, xi, np.ones(9))
    kin.arm_gravity_torque_body(robot, data, co.xi_to_q(xi))
    assert all(a == b for a, b in zip(before, robot.model.inertias))
    assert robot.model.gravity == gravity


def test_bad_input(robot, data):
    with pytest.raises(ShapeError, match="q must have shape"):
        kin.com_body(robot, data, np.zeros(9))
    with pytest.raises(NonFiniteError, match="xi_dot"):
        dyn.dynamics_xi(robot, data, np.zeros(9), np.full(9, np.inf))
    with pytest.raises(LimitError, match=r"r0 = 0.05 not in \[-0.04, 0.04\]"):
        robot.check_arm_limits([0.05, 0.0, 0.0])
    with pytest.raises(UnknownNameError, match="valid: 'thesis', 'cad'"):
        qprr.thesis.load_qprr("heavy")
    xi = np.zeros(9)
    xi[4] = np.pi / 2
    with pytest.raises(qprr.errors.EulerSingularityError):
        dyn.dynamics_xi(robot, data, xi, np.zeros(9))
