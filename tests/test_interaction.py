"""Interaction (Thesis Sec. 6.4.3): u_e(h) of (6.58)-(6.59), contact models, the push model (6.66)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
from qprr import actuation as act
from qprr import coordinates as co
from qprr import interaction as it
from qprr import model as qm
from qprr.errors import InputError

from .conftest import random_xi

SEED = 65


def _d(robot):
    p = robot.params
    return (p.d0, p.d1, p.d2, p.d3)


# ------------------------------------------------------------------ (6.58)-(6.59)
@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10**6))
def test_u_e_is_S_T_J_T_h_and_its_block_form(robot, seed):
    rng = np.random.default_rng(seed)
    data = robot.data()
    xi = random_xi(rng, robot)
    h = rng.normal(size=6)
    u = it.generalized_wrench_xi(robot, data, xi, h)
    tau = act.generalized_force_from_wrench(robot, data, co.xi_to_q(xi), h)
    assert np.allclose(u, co.rate_map(xi).T @ tau, atol=1e-12)
    assert np.allclose(u, it.generalized_wrench_blocks(xi, h, _d(robot)), atol=1e-12)


def test_u_e_virtual_power(robot, data):
    """u_e . xi_dot = h . [p_e_dot; omega_e] (world): the power of the wrench, by finite differences on the manifold."""
    rng = np.random.default_rng(SEED)
    for _ in range(5):
        xi, xd = random_xi(rng, robot), rng.normal(size=9)
        h = rng.normal(size=6)
        eps = 1e-6
        Mp = qm.ee_placement(robot, data, co.xi_to_q(xi + eps * xd))
        Mm = qm.ee_placement(robot, data, co.xi_to_q(xi - eps * xd))
        pdot = (Mp.translation - Mm.translation) / (2 * eps)
        omega = pin.log3(Mp.rotation @ Mm.rotation.T) / (2 * eps)  # world angular velocity
        assert it.generalized_wrench_xi(robot, data, xi, h) @ xd == pytest.approx(h[0:3] @ pdot + h[3:6] @ omega, rel=1e-6, abs=1e-8)


def test_6_59_printed_holds_level_only(robot, data):
    rng = np.random.default_rng(SEED)
    h = rng.normal(size=6)
    xi = random_xi(rng, robot)
    level = xi.copy()
    level[3:6] = 0.0
    assert np.allclose(it.generalized_wrench_6_59(level, h, _d(robot)), it.generalized_wrench_xi(robot, data, level, h), atol=1e-12)
    err = np.abs(it.generalized_wrench_6_59(xi, h, _d(robot)) - it.generalized_wrench_xi(robot, data, xi, h)).max()
    assert err > 1e-2


# ------------------------------------------------------------------ contact models
def _q_with_ee_at(robot, x_e: float, base_z: float = 1.0) -> np.ndarray:
    """A level configuration (arm links 2-3 horizontal) whose end effector is at world x = x_e."""
    xi = np.array([0.0, 0.0, base_z, 0.0, 0.0, 0.0, 0.0, math.pi / 2, 0.0])
    p, _ = qm.ee_pose_xi(robot, robot.data(), xi)
    xi[0] = x_e - p[0]
    return co.xi_to_q(xi)


def test_pushed_mass_force_is_never_negative_and_zero_when_apart(robot):
    """EE pressed in, then pulled away fast: the damper would pull (k delta + d delta_dot < 0) but the force stays >= 0."""
    obj = it.PushedMass(robot, mass=0.5, origin=(0.0, 0.0, 0.0), stiffness=500.0, damping=200.0)
    dt = 1e-3
    forces = []
    for k in range(400):
        t = k * dt
        x = 0.01 * math.sin(2 * math.pi * 2.0 * t)  # in and out of the object at 0.13 m/s peak
        v = np.zeros(9)
        v[0] = 0.01 * 2 * math.pi * 2.0 * math.cos(2 * math.pi * 2.0 * t)
        h = obj(t, _q_with_ee_at(robot, x), v)
        forces.append(-h[0])
        assert h[1] == h[2] == 0.0 and not np.any(h[3:])
    hist = obj.history()
    assert np.all(hist.force >= 0.0)
    # separated (penetration <= 0) means exactly zero force; pulling phases with delta > 0 exist and are clipped
    assert np.all(hist.force[hist.penetration <= 0.0] == 0.0)
    raw = 500.0 * hist.penetration + 200.0 * (np.gradient(hist.penetration, dt))
    assert np.any((hist.penetration > 0) & (raw < 0))
    assert np.allclose(forces, hist.force)


def test_pushed_mass_momentum_equals_contact_impulse(robot):
    """Frictionless line: m (s_dot_end - s_dot_0) = sum F dt over the completed steps (discrete impulse balance)."""
    obj = it.PushedMass(robot, mass=0.3, origin=(0.0, 0.0, 0.0), stiffness=800.0, damping=10.0)
    dt = 1e-3
    for k in range(300):
        t = k * dt
        x = 0.05 * (t / 0.3) ** 2  # end effector accelerating into the object
        v = np.zeros(9)
        v[0] = 0.05 * 2 * t / 0.09
        obj(t, _q_with_ee_at(robot, x), v)
    hist = obj.history()
    impulse = hist.force[:-1].sum() * dt  # the last force has not been integrated yet
    assert hist.force.max() > 0.05
    assert 0.3 * (hist.velocity[-1] - hist.velocity[0]) == pytest.approx(impulse, rel=1e-12)


def test_pushed_mass_coulomb_stick_and_slip(robot):
    """A held push below mu m g does not move the object; above it, s_ddot = (F - mu m g) / m."""
    m, mu, g = 0.5, 0.3, robot.params.g
    dt = 1e-3
    for push, moves in ((0.9 * mu * m * g, False), (2.0 * mu * m * g, True)):
        k_c = 1e4
        obj = it.PushedMass(robot, mass=m, origin=(0.0, 0.0, 0.0), stiffness=k_c, damping=0.0, friction=mu)
        for k in range(200):
            # keep the penetration at push / k by moving the end effector with the object
            obj(k * dt, _q_with_ee_at(robot, obj.s + push / k_c), np.zeros(9))
        hist = obj.history()
        if moves:
            a = np.diff(hist.velocity) / dt
            sliding = hist.velocity[1:] > 0.0
            assert sliding.sum() > 150
            assert np.allclose(a[sliding], (hist.force[:-1][sliding] - mu * m * g) / m, rtol=1e-9, atol=1e-9)
        else:
            assert np.all(hist.force == pytest.approx(push)) and np.all(hist.velocity == 0.0) and np.all(hist.position == 0.0)


def test_compliant_wall_static_force(robot):
    wall = it.CompliantWall(robot, point=(0.2, 0.0, 0.0), normal=(-1.0, 0.0, 0.0), stiffness=2000.0, damping=50.0)
    h = wall(0.0, _q_with_ee_at(robot, 0.203), np.zeros(9))
    assert h[0] == pytest.approx(-2000.0 * 0.003, rel=1e-9)  # pushed back along the outward normal
    assert np.all(wall(0.001, _q_with_ee_at(robot, 0.19), np.zeros(9)) == 0.0)


def test_contact_models_are_stateful_in_time(robot):
    obj = it.PushedMass(robot, mass=0.5, origin=(0.0, 0.0, 0.0))
    q = _q_with_ee_at(robot, 0.001)
    h1 = obj(0.01, q, np.zeros(9))
    assert np.array_equal(obj(0.01, q, np.zeros(9)), h1)  # repeated call at one time: no integration
    with pytest.raises(InputError):
        obj(0.005, q, np.zeros(9))
    obj.reset()
    assert obj.history().t.size == 0
    with pytest.raises(InputError):
        it.PushedMass(robot, mass=0.0, origin=(0, 0, 0))
    with pytest.raises(InputError):
        it.CompliantWall(robot, point=(0, 0, 0), normal=(0, 0, 0))


def test_prescribed_wrench_window():
    w = it.PrescribedWrench([1, 2, 3, 0, 0, 0], 1.0, 2.0)
    assert np.all(w(0.5) == 0) and w(1.0)[1] == 2.0 and np.all(w(2.0) == 0)
    with pytest.raises(InputError):
        it.PrescribedWrench([1, 2, 3, 0, 0, 0], 2.0, 1.0)


# ------------------------------------------------------------------ (6.66)
def _locked_arm_check(robot, q_arm, theta, T1, T3, F):
    """(x_G_ddot, theta_ddot, M, I_yy, contact_b, com_b) from Pinocchio with the arm locked (buildReducedModel)."""
    m = robot.model
    qref = pin.neutral(m)
    qref[7:10] = q_arm
    red = pin.buildReducedModel(m, [int(j) for j in robot.arm_joint_ids], qref)
    d = red.createData()
    q = np.zeros(7)
    q[2] = 1.0
    q[3:7] = pin.Quaternion(co.rot_y(theta)).coeffs()
    tau = act.rotor_matrix(robot) @ np.array([T1, 0.0, T3, 0.0])
    ee = red.getFrameId("end_effector")
    J = pin.computeFrameJacobian(red, d, q, ee, pin.LOCAL_WORLD_ALIGNED)
    tau = tau + J.T @ np.array([-F, 0.0, 0.0, 0.0, 0.0, 0.0])
    a = pin.aba(red, d, q, np.zeros(6), tau)
    pin.centerOfMass(red, d, q, np.zeros(6), a)
    acom = d.acom[0].copy()
    pin.ccrba(red, d, q, np.zeros(6))
    pin.framesForwardKinematics(red, d, q)
    R, p = d.oMi[1].rotation, d.oMi[1].translation
    return acom[0], a[4], d.Ig.mass, d.Ig.inertia[1, 1], R.T @ (d.oMf[ee].translation - p), R.T @ (d.com[0] - p)


def test_push_model_corrected_matches_locked_arm_pinocchio():
    """Corrected (6.66) = full rigid-body dynamics with the arm locked, at rest (products Ixy = Iyz = 0 so pitch decouples)."""
    p0 = qprr.load().params
    I = p0.multirotor_inertia
    robot = qprr.load(p0.with_changes(multirotor_inertia=(I[0], I[1], I[2], 0.0, I[4], 0.0)))
    rng = np.random.default_rng(SEED)
    for _ in range(5):
        qa = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
        theta, T1, T3, F = rng.uniform(-0.4, 0.4), rng.uniform(5, 12), rng.uniform(5, 12), rng.uniform(0, 3)
        xdd, thdd, M, Iyy, contact_b, com_b = _locked_arm_check(robot, qa, theta, T1, T3, F)
        model = it.push_model(theta, T1, T3, F, M, Iyy, robot.params.arm_length, contact_b, com_b)
        assert model.x_ddot == pytest.approx(xdd, rel=1e-12, abs=1e-12)
        assert model.theta_ddot == pytest.approx(thdd, rel=1e-10, abs=1e-10)


def test_push_model_6_66_printed_rotor_sign():
    """Printed rotor term L/(2 I)(T3 - T1) has the opposite sign of (3.36)'s l (f1 - f3) (no contact, CoG on the thrust axis)."""
    p0 = qprr.load().params
    I = p0.multirotor_inertia
    robot = qprr.load(p0.with_changes(multirotor_inertia=(I[0], I[1], I[2], 0.0, I[4], 0.0)))
    _, thdd, M, Iyy, contact_b, com_b = _locked_arm_check(robot, (0.0, 0.0, 0.0), 0.0, 9.0, 8.0, 0.0)
    printed = it.push_model_6_66(0.0, 9.0, 8.0, 0.0, M, Iyy, 2 * robot.params.arm_length, 0.0)
    # arm straight up: the CoG is on z_B (x_cm = 0), so the thrust has no moment about it
    assert abs(com_b[0]) < 1e-15
    assert thdd == pytest.approx(it.push_model(0.0, 9.0, 8.0, 0.0, M, Iyy, robot.params.arm_length, contact_b, com_b).theta_ddot, rel=1e-10)
    assert printed.theta_ddot == pytest.approx(-thdd, rel=1e-10)
    # the printed contact moment F p_cb^T e3 / I_yy matches at theta = 0 if p_cb is read with z down
    xdd, thdd_c, M, Iyy, contact_b, com_b = _locked_arm_check(robot, (0.0, math.pi / 2, 0.0), 0.0, 0.0, 0.0, 2.0)
    printed_c = it.push_model_6_66(0.0, 0.0, 0.0, 2.0, M, Iyy, 0.45, -(contact_b - com_b)[2])
    assert printed_c.theta_ddot == pytest.approx(thdd_c, rel=1e-10)
    assert printed_c.x_ddot == pytest.approx(xdd, rel=1e-12)
