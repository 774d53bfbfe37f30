"""Interaction (Thesis Sec. 6.4.3): u_e(h) of (6.58)-(6.59), contact models, the push model (6.66)."""

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
from qprr import kinematics as qm
from qprr import sim as it
from qprr.errors import InputError
from qprr.thesis import interaction as ti

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
    u = act.generalized_wrench_xi(robot, data, xi, h)
    tau = act.generalized_force_from_wrench(robot, data, co.xi_to_q(xi), h)
    assert np.allclose(u, co.rate_map(xi).T @ tau, atol=1e-12)
    assert np.allclose(u, ti.generalized_wrench_blocks(xi, h, _d(robot)), atol=1e-12)


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
        assert act.generalized_wrench_xi(robot, data, xi, h) @ xd == pytest.approx(h[0:3] @ pdot + h[3:6] @ omega, rel=1e-6, abs=1e-8)


def test_6_59_printed_holds_level_only(robot, data):
    rng = np.random.default_rng(SEED)
    h = rng.normal(size=6)
    xi = random_xi(rng, robot)
    level = xi.copy()
    level[3:6] = 0.0
    assert np.allclose(ti.generalized_wrench_6_59(level, h, _d(robot)), act.generalized_wrench_xi(robot, data, level, h), atol=1e-12)
    err = np.abs(ti.generalized_wrench_6_59(xi, h, _d(robot)) - act.generalized_wrench_xi(robot, data, xi, h)).max()
    assert err > 1e-2


# ------------------------------------------------------------------ contact models
def _q_with_ee_at(robot, x_e: float, base_z: float = 1.0) -> np.ndarray:
    """A level configuration (arm links 2-3 horizontal) whose end effector is at world x = x_e."""
    xi = np.array([0.0, 0.0, base_z, 0.0, 0.0, 0.0, 0.0, math.pi / 2, 0.0])
    p, _ = qm.ee_pose_xi(robot, robot.data(), xi)
    xi[0] = x_e - p[0]
    return co.xi_to_q(xi)


def _ee_kinematics(robot, q, v):
    data = robot.data()
    J = pin.computeFrameJacobian(robot.model, data, q, robot.ee_frame, pin.LOCAL_WORLD_ALIGNED)
    M = data.oMf[robot.ee_frame]
    return M.translation.copy(), M.rotation.copy(), J @ v


def test_pushed_mass_force_is_never_negative_and_zero_when_apart(robot):
    """EE pressed in, then pulled away fast: the damper would pull (k delta + d delta_dot < 0) but the force stays >= 0."""
    obj = it.PushedMass(robot, mass=0.5, origin=(0.0, 0.0, 0.0), stiffness=500.0, damping=200.0)
    z = obj.initial_state()  # object at rest at s = 0: penetration = x_e
    pulled = 0
    for k in range(400):
        t = k * 1e-3
        x = 0.01 * math.sin(2 * math.pi * 2.0 * t)  # in and out of the object at 0.13 m/s peak
        xd = 0.01 * 2 * math.pi * 2.0 * math.cos(2 * math.pi * 2.0 * t)
        v = np.zeros(9)
        v[0] = xd
        q = _q_with_ee_at(robot, x)
        h = obj.wrench(t, q, v, z)
        F = -h[0]
        assert h[1] == h[2] == 0.0 and not np.any(h[3:])
        assert F >= 0.0
        if x <= 0.0:
            assert F == 0.0  # separated: exactly zero
        else:
            raw = 500.0 * x + 200.0 * xd
            assert F == pytest.approx(max(raw, 0.0), rel=1e-9, abs=1e-12)
            pulled += raw < 0.0
        # the object's derivative sees the same force: s_ddot = F / m (no friction)
        zd = obj.evaluate(t, *_ee_kinematics(robot, q, v), z)[1]
        assert zd[0] == 0.0 and zd[1] == pytest.approx(F / 0.5, rel=1e-12, abs=1e-15)
    assert pulled > 10  # pulling phases with delta > 0 exist and are clipped


def test_pushed_mass_coulomb_stick_and_slip(robot):
    """Static friction holds the object while F <= mu m g (derivative exactly zero); sliding, s_ddot = (F -+ mu m g) / m;
    a velocity that changes sign during a step is caught by static friction."""
    m, mu, g = 0.5, 0.3, robot.params.g
    k_c = 1e4
    obj = it.PushedMass(robot, mass=m, origin=(0.0, 0.0, 0.0), stiffness=k_c, damping=0.0, friction=mu)
    for push in (0.9 * mu * m * g, 2.0 * mu * m * g):
        kin = _ee_kinematics(robot, _q_with_ee_at(robot, push / k_c), np.zeros(9))
        h, zd = obj.evaluate(0.0, *kin, np.zeros(2))
        assert -h[0] == pytest.approx(push, rel=1e-9)
        if push < mu * m * g:
            assert zd[0] == 0.0 and zd[1] == 0.0  # stuck: exactly at rest
        else:
            assert zd[1] == pytest.approx((push - mu * m * g) / m, rel=1e-9)  # breaks away
        kin = _ee_kinematics(robot, _q_with_ee_at(robot, 0.01 + push / k_c), np.array([0.05, *np.zeros(8)]))
        for sd, sign in ((0.05, 1.0), (-0.05, -1.0)):
            zd = obj.evaluate(0.0, *kin, np.array([0.01, sd]))[1]
            assert zd[0] == sd and zd[1] == pytest.approx((push - sign * mu * m * g) / m, rel=1e-9)
    np.testing.assert_array_equal(obj.settle(0.0, np.array([0.1, 0.02]), np.array([0.11, -1e-4])), [0.11, 0.0])
    np.testing.assert_array_equal(obj.settle(0.0, np.array([0.1, 0.02]), np.array([0.11, 0.01])), [0.11, 0.01])
    frictionless = it.PushedMass(robot, mass=m, origin=(0.0, 0.0, 0.0))
    np.testing.assert_array_equal(frictionless.settle(0.0, np.array([0.1, 0.02]), np.array([0.11, -1e-4])), [0.11, -1e-4])


@pytest.fixture(scope="module")
def free_robot():
    return qprr.thesis.load_qprr(qprr.thesis.thesis_params().with_changes(g=0.0))


def _push_run(robot, integrator, duration=0.045, dt=1e-3):
    """No gravity, no input: the robot (arm horizontal, end effector 5 mm into a 0.5 kg object) drifts into it at 0.2 m/s."""
    from qprr.control.base import Controller
    from qprr.sim import simulate
    from qprr.trajectory import Hold

    class Zero(Controller):
        def step(self, t, state, ref):
            return np.zeros(9)

    xi0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, math.pi / 2, 0.0])
    p0, _ = qm.ee_pose_xi(robot, robot.data(), xi0)
    obj = it.PushedMass(robot, mass=0.5, origin=p0 - np.array([0.005, 0.0, 0.0]), stiffness=500.0, damping=0.0)
    xd0 = np.r_[0.2, np.zeros(8)]
    res = simulate(
        robot, Zero(), Hold(tuple(xi0)), duration, dt=dt, integrator=integrator, xi0=xi0, xi_dot0=xd0, external_wrench=obj, joint_stops=False
    )
    return res, obj


def test_pushed_object_and_robot_conserve_momentum_and_energy(free_robot):
    """The contact force is internal to robot + object: with no gravity, input or damping, the total momentum along the
    line and the total energy (kinetic + contact spring) are conserved by the simulation, which integrates the object's
    state with the robot's (RK4 at 1 ms: measured 1e-15 and 6.5e-10 relative over the 45 ms of contact; the free arm
    then folds and the contact opens at 52 ms, a kink of the force that no fixed-step method crosses at full order)."""
    res, obj = _push_run(free_robot, "rk4")
    c = obj.history()
    assert c.t.size == res.n and np.all(c.force > 0.0)  # in contact throughout
    assert c.velocity[-1] > 0.1 and c.position[-1] > 0.002  # pushed from rest
    m_d = free_robot.model.createData()
    P, E = [], []
    for k in range(res.n):
        q, v = co.xi_to_qv(res.xi[k], res.xi_dot[k])
        hg = pin.computeCentroidalMomentum(free_robot.model, m_d, q, v)
        P.append(hg.linear[0] + obj.mass * c.velocity[k])
        E.append(pin.computeKineticEnergy(free_robot.model, m_d, q, v) + 0.5 * obj.mass * c.velocity[k] ** 2 + 0.5 * obj.k * c.penetration[k] ** 2)
    P, E = np.array(P), np.array(E)
    assert np.abs(P - P[0]).max() < 1e-12 * abs(P[0])
    assert np.abs(E - E[0]).max() < 5e-9 * E[0]
    # the run is reproducible: the simulator resets the environment's log and starts from its initial state
    again, obj2 = _push_run(free_robot, "rk4")
    np.testing.assert_array_equal(obj2.history().position, c.position)


def test_compliant_wall_static_force(robot):
    wall = it.CompliantWall(robot, point=(0.2, 0.0, 0.0), normal=(-1.0, 0.0, 0.0), stiffness=2000.0, damping=50.0)
    h = wall.wrench(0.0, _q_with_ee_at(robot, 0.203), np.zeros(9))
    assert h[0] == pytest.approx(-2000.0 * 0.003, rel=1e-9)  # pushed back along the outward normal
    assert np.all(wall.wrench(0.001, _q_with_ee_at(robot, 0.19), np.zeros(9)) == 0.0)
    assert wall.state_size == 0


def test_contact_model_arguments(robot):
    with pytest.raises(InputError):
        it.PushedMass(robot, mass=0.0, origin=(0, 0, 0))
    with pytest.raises(InputError):
        it.PushedMass(robot, mass=0.5, origin=(0, 0, 0), friction=-0.1)
    with pytest.raises(InputError):
        it.CompliantWall(robot, point=(0, 0, 0), normal=(0, 0, 0))
    with pytest.raises(InputError):
        it.CompliantWall(robot, point=(0, 0, 0), normal=(1, 0, 0), stiffness=0.0)


def test_prescribed_wrench_window():
    w = it.PrescribedWrench([1, 2, 3, 0, 0, 0], 1.0, 2.0)
    assert np.all(w(0.5) == 0) and w(1.0)[1] == 2.0 and np.all(w(2.0) == 0)
    # in a simulation the window follows the control ticks: a stage just past t_off still belongs to the tick before
    w.on_tick(1.999)
    assert w.evaluate(2.0)[0][1] == 2.0
    w.on_tick(2.0)
    assert np.all(w.evaluate(2.0)[0] == 0.0)
    with pytest.raises(InputError):
        it.PrescribedWrench([1, 2, 3, 0, 0, 0], 2.0, 1.0)


# ------------------------------------------------------------------ (6.66)
def _locked_arm_check(robot, q_arm, theta, T1, T3, F):
    """(x_G_ddot, theta_ddot, M, I_yy, contact_b, com_b) from Pinocchio with the arm locked (buildReducedModel)."""
    m = robot.model
    qref = pin.neutral(m)
    qref[7:10] = q_arm
    red = pin.buildReducedModel(m, [m.getJointId(n) for n in robot.arm_names], qref)
    d = red.createData()
    q = np.zeros(7)
    q[2] = 1.0
    q[3:7] = pin.Quaternion(co.rot_y(theta)).coeffs()
    tau = robot.rotor_matrix @ np.array([T1, 0.0, T3, 0.0])
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
    p0 = qprr.thesis.load_qprr().params
    I = p0.multirotor_inertia
    robot = qprr.thesis.load_qprr(p0.with_changes(multirotor_inertia=(I[0], I[1], I[2], 0.0, I[4], 0.0)))
    rng = np.random.default_rng(SEED)
    for _ in range(5):
        qa = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
        theta, T1, T3, F = rng.uniform(-0.4, 0.4), rng.uniform(5, 12), rng.uniform(5, 12), rng.uniform(0, 3)
        xdd, thdd, M, Iyy, contact_b, com_b = _locked_arm_check(robot, qa, theta, T1, T3, F)
        model = ti.push_model(theta, T1, T3, F, M, Iyy, robot.params.arm_length, contact_b, com_b)
        assert model.x_ddot == pytest.approx(xdd, rel=1e-12, abs=1e-12)
        assert model.theta_ddot == pytest.approx(thdd, rel=1e-10, abs=1e-10)


def test_push_model_6_66_printed_rotor_sign():
    """Printed rotor term L/(2 I)(T3 - T1) has the opposite sign of (3.36)'s l (f1 - f3) (no contact, CoG on the thrust axis)."""
    p0 = qprr.thesis.load_qprr().params
    I = p0.multirotor_inertia
    robot = qprr.thesis.load_qprr(p0.with_changes(multirotor_inertia=(I[0], I[1], I[2], 0.0, I[4], 0.0)))
    _, thdd, M, Iyy, contact_b, com_b = _locked_arm_check(robot, (0.0, 0.0, 0.0), 0.0, 9.0, 8.0, 0.0)
    printed = ti.push_model_6_66(0.0, 9.0, 8.0, 0.0, M, Iyy, 2 * robot.params.arm_length, 0.0)
    # arm straight up: the CoG is on z_B (x_cm = 0), so the thrust has no moment about it
    assert abs(com_b[0]) < 1e-15
    assert thdd == pytest.approx(ti.push_model(0.0, 9.0, 8.0, 0.0, M, Iyy, robot.params.arm_length, contact_b, com_b).theta_ddot, rel=1e-10)
    assert printed.theta_ddot == pytest.approx(-thdd, rel=1e-10)
    # the printed contact moment F p_cb^T e3 / I_yy matches at theta = 0 if p_cb is read with z down
    xdd, thdd_c, M, Iyy, contact_b, com_b = _locked_arm_check(robot, (0.0, math.pi / 2, 0.0), 0.0, 0.0, 0.0, 2.0)
    printed_c = ti.push_model_6_66(0.0, 0.0, 0.0, 2.0, M, Iyy, 0.45, -(contact_b - com_b)[2])
    assert printed_c.theta_ddot == pytest.approx(thdd_c, rel=1e-10)
    assert printed_c.x_ddot == pytest.approx(xdd, rel=1e-12)
