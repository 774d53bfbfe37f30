"""Operational-space model (5.47)-(5.52): Lambda^-1 = J M^-1 J^T by an independent route (ABA), finite differences,
the square case of (5.51) and the printed (5.50)-(5.51)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.analysis import opspace_map, opspace_model
from qprr.errors import InputError

PLATFORMS = ("q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")


def by_name(name):
    return qprr.build(name) if name.isupper() else qprr.load(name)


def random_state(p, seed):
    rng = np.random.default_rng(seed)
    q = p.neutral_q()
    q[0:3] = rng.uniform(-1, 1, 3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    q[7:] = rng.uniform(p.arm_lower, p.arm_upper)
    return q, rng.normal(size=p.nv), rng


@pytest.mark.parametrize("name", PLATFORMS)
def test_lambda_inverse_by_articulated_body_responses(name):
    """Column i of Lambda^-1 = the end-effector acceleration ABA gives for the unit wrench e_i (no gravity, at rest)."""
    p = by_name(name)
    q, v, _ = random_state(p, 1)
    m = opspace_model(p, p.data(), q, v)
    assert m.rank == 6
    model0 = pin.Model(p.model)
    model0.gravity = pin.Motion.Zero()
    d0 = model0.createData()
    Li = np.column_stack([m.J @ pin.aba(model0, d0, q, np.zeros(p.nv), m.J.T @ e) for e in np.eye(6)])
    np.testing.assert_allclose(m.Lambda_inv, Li, rtol=1e-10, atol=1e-12 * np.abs(Li).max())
    np.testing.assert_allclose(m.Lambda @ m.Lambda_inv, np.eye(6), atol=1e-8)
    np.testing.assert_allclose(m.Lambda, m.Lambda.T, atol=1e-9 * np.abs(m.Lambda).max())


@pytest.mark.parametrize("name", PLATFORMS)
def test_operational_space_equation_by_finite_differences(name):
    """x_ddot = Lambda^-1 (F - mu - p) (5.52) against central differences of J(q(t)) v(t) along the ABA motion, O(h^2)."""
    p = by_name(name)
    q, v, rng = random_state(p, 2)
    d = p.data()
    m = opspace_model(p, d, q, v)
    F = rng.normal(size=6)
    a = pin.aba(p.model, d, q, v, m.J.T @ F)
    pred = m.acceleration(F)

    def xdot(t):
        qt = pin.integrate(p.model, q, v * t + 0.5 * a * t * t)
        return pin.computeFrameJacobian(p.model, d, qt, m.frame, pin.LOCAL_WORLD_ALIGNED) @ (v + a * t)

    errs = [np.abs((xdot(h) - xdot(-h)) / (2 * h) - pred).max() for h in (1e-3, 1e-4)]
    assert errs[1] < 2e-2 * errs[0] + 1e-9  # second order
    assert errs[1] < 1e-4 * max(1.0, np.abs(pred).max())


def test_fixed_base_square_case_is_5_51():
    """Fixed-base Q-PRR arm, rows (x, z, omega_y): J* is 3 x 3 and invertible (off theta2 = 0), and
    B_A = J*^-T B J*^-1, C_A x_dot = J*^-T (C q_dot) - B_A J*_dot q_dot, G_A = J*^-T G (5.51) equal Lambda, mu, p."""
    p = qprr.load("q-prr")
    am = p.arm_model()
    d = am.createData()
    rng = np.random.default_rng(3)
    rows = [0, 2, 4]
    for _ in range(5):
        q = rng.uniform(p.arm_lower, p.arm_upper)
        v = rng.normal(size=3)
        m = opspace_model(p, d, q, v, fixed_base=True)
        assert m.rank == 3
        J = m.J[rows]
        Ji = np.linalg.inv(J)
        B_A = Ji.T @ m.M @ Ji
        pin.computeJointJacobiansTimeVariation(am, d, q, v)
        Jdot = pin.getFrameJacobianTimeVariation(am, d, m.frame, pin.LOCAL_WORLD_ALIGNED)[rows]
        Cqd = m.h - m.g
        CA_xdot = Ji.T @ Cqd - B_A @ (m.J_dot_v[rows])
        np.testing.assert_allclose(B_A, np.linalg.inv(J @ np.linalg.solve(m.M, J.T)), rtol=1e-9)
        # Lambda on the row space: the pseudo-inverse of the 6 x 6 J M^-1 J^T restricted to these rows
        np.testing.assert_allclose(m.Lambda[np.ix_(rows, rows)], B_A, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(m.mu[rows], CA_xdot, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(m.p[rows], Ji.T @ m.g, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(Jdot @ v, m.J_dot_v[rows], atol=1e-12)


def test_printed_5_50_is_not_the_inverse_of_the_kinematics():
    """(5.50) line 3 prints xi_ddot = J^-T [chi_ddot - J_dot^-T J chi_dot].  With the square J* of the fixed-base arm
    the correct inverse xi_ddot = J^-1 (chi_ddot - J_dot xi_dot) gives back the joint accelerations; the printed line
    needs J_dot^-1, which does not exist: the slider's column of J_dot is zero (its axis x_B never turns)."""
    p = qprr.load("q-prr")
    am = p.arm_model()
    d = am.createData()
    rng = np.random.default_rng(4)
    rows = [0, 2, 4]
    fid = am.getFrameId(p.model.frames[p.ee_frame].name)
    for _ in range(5):
        q = rng.uniform(p.arm_lower, p.arm_upper)
        qd, qdd = rng.normal(size=3), rng.normal(size=3)
        pin.computeJointJacobians(am, d, q)
        J = pin.getFrameJacobian(am, d, fid, pin.LOCAL_WORLD_ALIGNED)[rows]
        pin.computeJointJacobiansTimeVariation(am, d, q, qd)
        Jd = pin.getFrameJacobianTimeVariation(am, d, fid, pin.LOCAL_WORLD_ALIGNED)[rows]
        chidd = J @ qdd + Jd @ qd
        np.testing.assert_allclose(np.linalg.solve(J, chidd - Jd @ qd), qdd, atol=1e-9)
        np.testing.assert_array_equal(Jd[:, 0], 0.0)
        assert np.linalg.matrix_rank(Jd) < 3
        # even read with J^-1 for J^-T and J_dot for J_dot^-T (the nearest defined reading), it misses qdd
        chid = J @ qd
        reading = np.linalg.solve(J, chidd - Jd.T @ J @ chid)
        assert np.abs(reading - qdd).max() > 1e-3


def test_printed_5_51_right_hand_side_needs_no_J_transpose():
    """(5.51) multiplies B xi_ddot + C xi_dot + G = tau = J^T gamma by J^-T: the right-hand side is gamma, not J^T gamma."""
    p = qprr.load("q-prr")
    am = p.arm_model()
    d = am.createData()
    q = np.array([0.01, 0.7, -0.4])
    m = opspace_model(p, d, q, None, fixed_base=True)
    J = m.J[[0, 2, 4]]
    gamma = np.array([1.0, -2.0, 0.3])
    lhs = np.linalg.inv(J).T @ (J.T @ gamma)  # J^-T tau with tau = J^T gamma (5.47)
    np.testing.assert_allclose(lhs, gamma, atol=1e-12)
    assert np.abs(J.T @ gamma - gamma).max() > 0.5


def test_opspace_map_is_the_model_at_each_configuration():
    p = qprr.load("q-prr")
    r = opspace_map(p, n_samples=300)
    q = r.grid.configurations()
    d = p.data()
    for i in np.random.default_rng(0).choice(len(q), 10, replace=False):
        qq = p.neutral_q()
        qq[7:] = q[i]
        m = opspace_model(p, d, qq)
        np.testing.assert_allclose(r.mass_xyz[i], 1.0 / np.diag(m.Lambda_inv)[0:3], rtol=1e-10)
        np.testing.assert_allclose(r.gravity_force[i], m.p[0:3], rtol=1e-8, atol=1e-10)
    # pushing along z with the arm straight up moves the whole platform: effective mass = total mass
    i = int(np.argmax(r.mass_xyz[:, 2]))
    assert abs(r.mass_xyz[i, 2] - p.total_mass) < 1e-9


def test_opspace_input_errors():
    p = qprr.load("q-prr")
    with pytest.raises(InputError):
        opspace_model(p, p.data(), np.zeros(3))
    with pytest.raises(InputError, match="F"):
        opspace_model(p, p.data(), p.neutral_q()).acceleration([1.0, 2.0])


# ------------------------------------------------------------------------ thesis coordinates, locked coordinates
@pytest.mark.parametrize("name", PLATFORMS)
def test_opspace_model_xi_equals_the_pinocchio_coordinates_one(name):
    """Lambda, mu, p do not depend on the coordinates: in thesis coordinates (B = S^T M S, n = C xi_dot + G) they equal
    opspace_model's at the same state; J = J_v S and the twist J xi_dot = J_v v."""
    from qprr import charts as ch
    from qprr.analysis import opspace_model_xi

    p = by_name(name)
    q, v, rng = random_state(p, 7)
    xi, xi_dot = ch.qv_to_xi(q, v)
    m0 = opspace_model(p, p.data(), q, v)
    m = opspace_model_xi(p, p.data(), xi, xi_dot)
    scale = np.abs(m0.Lambda).max()
    assert np.abs(m.Lambda - m0.Lambda).max() < 1e-12 * scale
    assert np.abs(m.mu - m0.mu).max() < 1e-11 * max(1.0, np.abs(m0.mu).max())
    assert np.abs(m.p - m0.p).max() < 1e-11 * max(1.0, np.abs(m0.p).max())
    assert np.allclose(m.J, m0.J @ ch.rate_map(xi), atol=1e-13)
    assert np.allclose(m.velocity, m0.J @ v, atol=1e-13)
    assert np.allclose(m.J_v, m0.J, atol=1e-13) and np.allclose(m.M, m0.M, atol=1e-13)


@pytest.mark.parametrize("name", PLATFORMS)
def test_locking_coordinates_makes_the_end_effector_heavier(name):
    """Roll and pitch locked (the attitude loop's coordinates): J_c J_bar_c = I and Lambda_c - Lambda is positive
    semi-definite (a constraint never makes the end effector lighter); rank and input errors."""
    from qprr import charts as ch
    from qprr.analysis import opspace_model_xi
    from qprr.errors import UnknownNameError

    p = by_name(name)
    q, v, _ = random_state(p, 8)
    xi, xi_dot = ch.qv_to_xi(q, v)
    free = opspace_model_xi(p, p.data(), xi, xi_dot, rows="position")
    cols = [i for i in range(p.n_xi) if i not in (3, 4)]
    lk = opspace_model_xi(p, p.data(), xi, xi_dot, rows="position", coordinates=cols)
    assert lk.rank == 3 and np.allclose(lk.J_c @ lk.J_bar, np.eye(3), atol=1e-10)
    w = np.linalg.eigvalsh(lk.Lambda - free.Lambda)
    assert w.min() > -1e-12 * np.abs(lk.Lambda).max()
    with pytest.raises(UnknownNameError):
        opspace_model_xi(p, p.data(), xi, rows="wrist")
    with pytest.raises(InputError, match="coordinates"):
        opspace_model_xi(p, p.data(), xi, coordinates=[0, 0, 1])
