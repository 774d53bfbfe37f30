"""What the pictures show: the arm polyline against the thesis's closed form, hover thrusts against gravity, IK paths."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr import kinematics
from qprr.actuation import Allocator
from qprr.charts import euler_to_rotation, rot_y, xi_to_q
from qprr.dynamics import generalized_gravity
from qprr.viz import hover_report, ik_path, robot_pose

RNG = np.random.default_rng(1414)


@pytest.fixture(scope="module")
def qprr_platform():
    return qprr.load()


def _random_xi(platform, max_angle=1.2):
    xi = np.empty(platform.n_xi)
    xi[0:3] = RNG.uniform(-3.0, 3.0, 3)
    xi[3:6] = RNG.uniform(-max_angle, max_angle, 3)
    xi[6:] = RNG.uniform(platform.arm_lower, platform.arm_upper)
    return xi


def test_arm_polyline_is_the_thesis_chain(qprr_platform):
    """B, the slider before and after r0, theta2, theta3 and the end effector: Thesis (3.58) mapped by (3.61)."""
    pf = qprr_platform
    P = pf.params
    data = pf.data()
    for _ in range(20):
        xi = _random_xi(pf)
        r0, t2, t3 = xi[6:]
        R, p = euler_to_rotation(xi[3:6]), xi[0:3]
        body = np.array(
            [
                [0.0, 0.0, 0.0],
                [0.0, 0.0, P.d0],
                [r0, 0.0, P.d0],
                [r0, 0.0, P.d0 + P.d1],
                [r0 + P.d2 * math.sin(t2), 0.0, P.d0 + P.d1 + P.d2 * math.cos(t2)],
                [r0 + P.d2 * math.sin(t2) + P.d3 * math.sin(t2 + t3), 0.0, P.d0 + P.d1 + P.d2 * math.cos(t2) + P.d3 * math.cos(t2 + t3)],
            ]
        )
        pose = robot_pose(pf, data, xi_to_q(xi))
        np.testing.assert_allclose(pose.arm_world, p + body @ R.T, atol=1e-13)
        np.testing.assert_allclose(pose.ee_world, kinematics.ee_placement(pf, pf.data(), xi_to_q(xi)).translation, atol=1e-13)
        np.testing.assert_allclose(pose.com_world, kinematics.com_world(pf, pf.data(), xi_to_q(xi)), atol=1e-13)
        np.testing.assert_allclose(pose.axis_dir_world, R[:, 2], atol=1e-15)
        np.testing.assert_allclose(pose.axis_point_world, p, atol=1e-13)
        np.testing.assert_allclose(pose.rotor_world, p + np.array([r.position_body for r in pf.rotors]) @ R.T, atol=1e-13)


def test_hover_thrusts_balance_gravity(qprr_platform):
    """Level base: Omega f = g(q)[0:6] (virtual power), sum f = m g; CoG on z_B: f_i = m g / 4."""
    pf = qprr_platform
    alloc, data = Allocator(pf), pf.data()
    mg = pf.total_mass * pf.g
    r = hover_report(alloc, data, pf.neutral_q())
    np.testing.assert_allclose(r.f, mg / 4.0, rtol=1e-14)
    np.testing.assert_allclose(r.margin_low, r.f - pf.thrust_min, rtol=0, atol=0)
    np.testing.assert_allclose(r.margin_high, pf.thrust_max - r.f, rtol=0, atol=0)
    assert r.feasible and r.reason == ""
    for _ in range(20):
        xi = _random_xi(pf)
        xi[3:5] = 0.0
        q = xi_to_q(xi)
        r = hover_report(alloc, data, q)
        np.testing.assert_allclose(pf.rotor_matrix @ r.f, generalized_gravity(pf, pf.data(), q)[0:6], atol=1e-12)
        assert r.f.sum() == pytest.approx(mg, rel=1e-13)
        assert r.unproduced < 1e-12


@pytest.mark.parametrize("phi", [0.05, 0.3, -0.7])
def test_tilted_coplanar_rotors_cannot_hover(qprr_platform, phi):
    """Rolled by phi, the weight has a component m g sin(phi) along y_B that coplanar rotors cannot produce."""
    pf = qprr_platform
    xi = pf.neutral_xi()
    xi[3] = phi
    r = hover_report(Allocator(pf), pf.data(), xi_to_q(xi))
    assert r.unproduced == pytest.approx(pf.total_mass * pf.g * abs(math.sin(phi)), rel=1e-12)
    assert not r.feasible and "not vertical" in r.reason


def test_fully_actuated_platform_hovers_tilted():
    pf = qprr.load("hextilt_flying_arm_5")
    xi = pf.neutral_xi()
    xi[3] = 0.1
    q = xi_to_q(xi)
    r = hover_report(Allocator(pf), pf.data(), q)
    assert r.unproduced < 1e-9
    np.testing.assert_allclose(pf.rotor_matrix @ r.f, generalized_gravity(pf, pf.data(), q)[0:6], atol=1e-10)


def test_thrust_bound_violation_is_reported(qprr_platform):
    heavy = qprr_platform.replace(
        rotors=tuple(r.__class__(r.position_body, r.axis_body, r.spin, r.kappa, 0.0, 5.0, r.name) for r in qprr_platform.rotors)
    )
    r = hover_report(Allocator(heavy), heavy.data(), heavy.neutral_q())
    assert not r.feasible
    np.testing.assert_allclose(r.margin_high, 5.0 - heavy.total_mass * heavy.g / 4.0, rtol=1e-14)
    assert r.reason.count("above its maximum") == 4


def test_ik_path_reaches_every_target_hovering_with_the_cog_on_the_axis(qprr_platform):
    pf = qprr_platform
    t = np.linspace(0.0, 2.0, 9)
    p = np.stack([0.2 * np.cos(t), 0.2 * np.sin(t), 1.3 + 0.05 * t], axis=1)
    R = np.array([rot_y(0.6 * math.sin(s)) for s in t])
    path = ik_path(pf, t, p, R)
    assert path.success.all(), path.status
    run, data = path.run, pf.data()
    assert run.xi.shape == (9, 9) and run.f.shape == (9, 4) and run.platform == pf.name
    mg = pf.total_mass * pf.g
    for k in range(len(t)):
        M = kinematics.ee_placement(pf, data, xi_to_q(run.xi[k]))
        np.testing.assert_allclose(M.translation, p[k], atol=1e-8)
        assert np.linalg.norm(pin.log3(R[k].T @ M.rotation)) < 1e-8
        assert abs(run.xi[k, 3]) < 1e-9 and abs(run.xi[k, 4]) < 1e-9  # hover: level base
        assert np.abs(path.x_cm[k]).max() < 1e-6  # CoG on the thrust axis
        assert run.f[k].sum() == pytest.approx(mg, rel=1e-12)
        np.testing.assert_allclose(run.f[k], mg / 4.0, rtol=1e-6)  # CoG on the axis: equal thrusts


def test_ik_path_checks_shapes(qprr_platform):
    with pytest.raises(qprr.errors.ShapeError):
        ik_path(qprr_platform, np.zeros(3), np.zeros((2, 3)))
    with pytest.raises(qprr.errors.ShapeError):
        ik_path(qprr_platform, np.zeros(2), np.zeros((2, 3)), np.zeros((2, 3)))
