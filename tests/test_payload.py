"""Payload (Thesis Sec. 6.4.1-6.4.2): known-mass models, holding efforts, capacity, B_c/G_c, mass estimate."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qprr import charts as co
from qprr import kinematics as qm
from qprr import payload as pl
from qprr import sim
from qprr.control import PayloadIDC
from qprr.errors import InputError, LimitError, UnknownNameError
from qprr.thesis import gains
from qprr.thesis import payload as tp
from qprr.trajectory import Hold

from .conftest import random_xi

SEED = 64


def _d(robot):
    p = robot.params
    return (p.d0, p.d1, p.d2, p.d3)


# --------------------------------------------------------------- known-mass models
def test_with_payload_copies_and_adds_the_spatial_inertia(robot):
    before = pin.Inertia(robot.model.inertias[robot.model.frames[robot.ee_frame].parentJoint])
    P = pl.Payload.sphere(0.1, 0.03, (0.01, 0.0, 0.02))
    loaded = pl.with_payload(robot, P)
    j = robot.model.frames[robot.ee_frame].parentJoint
    assert robot.model.inertias[j] == before  # nominal model untouched
    assert loaded.model.inertias[j].mass == pytest.approx(before.mass + 0.1, abs=1e-15)
    data = loaded.model.createData()
    q = co.xi_to_q(np.array([0, 0, 0, 0, 0, 0, 0.02, 0.4, -0.7]))
    # total mass and CoM of the loaded system = nominal system + point at the payload CoM (world)
    c0 = pin.centerOfMass(robot.model, robot.data(), q).copy()
    pin.framesForwardKinematics(robot.model, robot.data(), q)
    dd = robot.data()
    pin.framesForwardKinematics(robot.model, dd, q)
    p_payload = dd.oMf[robot.ee_frame].act(np.array(P.com_ee))
    m0 = robot.params.total_mass
    c1 = pin.centerOfMass(loaded.model, data, q)
    assert np.allclose(c1, (m0 * c0 + 0.1 * p_payload) / (m0 + 0.1), atol=1e-14)


def test_link3_approach_drops_payload_inertia_body_approach_keeps_it(robot):
    P = pl.Payload.sphere(0.2, 0.05)
    j = robot.model.frames[robot.ee_frame].parentJoint
    a = pl.with_payload(robot, P, "link3").model.inertias[j]
    b = pl.with_payload(robot, P, "body").model.inertias[j]
    assert b.inertia - a.inertia == pytest.approx(0.4 * 0.2 * 0.05**2 * np.eye(3), abs=1e-15)
    with pytest.raises(UnknownNameError):
        pl.with_payload(robot, P, "glued")


@settings(max_examples=40, deadline=None)
@given(st.floats(0.01, 1.0), st.floats(0.01, 1.0), st.lists(st.floats(-0.2, 0.2), min_size=6, max_size=6))
def test_combine_inertias_equals_pinocchio_inertia_sum(ma, mb, cc):
    rng = np.random.default_rng(int(1e6 * ma) % 1000)
    A = rng.normal(size=(3, 3)) * 1e-3
    Ia, Ib = A @ A.T, np.diag(rng.uniform(0, 1e-4, 3))
    ca, cb = np.array(cc[:3]), np.array(cc[3:])
    ours = pl.combine_inertias(pl.RigidInertia(ma, ca, Ia), pl.RigidInertia(mb, cb, Ib))
    theirs = pin.Inertia(ma, ca, Ia) + pin.Inertia(mb, cb, Ib)
    assert ours.mass == pytest.approx(theirs.mass, rel=1e-14)
    assert np.allclose(ours.com, theirs.lever, atol=1e-14)
    assert np.allclose(ours.inertia, theirs.inertia, atol=1e-14)


def test_6_40b_printed_is_a_misprint(robot):
    """(6.40b) multiplies the squared distance by m3' = m3 + m_cl: counter-example against Inertia.__add__."""
    link3 = robot.params.links[2]
    m3, m_cl = link3.mass, 0.1
    c3 = np.array(link3.com)
    tip = np.array([0.0, 0.0, link3.length])  # the end effector, a point mass on link 3's axis
    total = pin.Inertia(m3, c3, link3.inertia_matrix()) + pin.Inertia(m_cl, tip, np.zeros((3, 3)))
    delta = tip - c3  # (x_cm, z_cm) = (0, d3/2) from link 3's CoM
    _, printed = tp.link3_inertia_6_40(m3, link3.inertia_matrix(), m_cl, delta[0], delta[2])
    # joint-axis (yy) entry: printed uses m3' = 0.1961 kg, Pinocchio the reduced mass 0.049 kg
    reduced = m3 * m_cl / (m3 + m_cl)
    assert total.inertia[1, 1] == pytest.approx(link3.inertia[1] + reduced * delta @ delta, rel=1e-12)
    assert abs(printed[1, 1] - total.inertia[1, 1]) > 3e-4  # 4.9e-4 vs 1.3e-4 kg m^2
    # about link 3's own CoM the correct factor is m_cl, still not m3'
    s = total.lever - c3
    about_c3 = total.inertia + (m3 + m_cl) * (np.eye(3) * (s @ s) - np.outer(s, s))
    assert about_c3[1, 1] == pytest.approx(link3.inertia[1] + m_cl * delta @ delta, rel=1e-12)


def test_6_41b_printed_vs_centroidal_inertia(robot):
    """(6.41b): the system inertia about the new CoM gets the reduced mass, and a tensor, not a scalar."""
    q = co.xi_to_q(np.array([0, 0, 0, 0, 0, 0, 0.03, 0.9, 0.4]))
    P = pl.Payload.sphere(0.1, 0.03)
    loaded = pl.with_payload(robot, P)
    d0, d1 = robot.data(), loaded.model.createData()
    pin.ccrba(robot.model, d0, q, np.zeros(9))
    pin.ccrba(loaded.model, d1, q, np.zeros(9))
    pin.framesForwardKinematics(robot.model, d0, q)
    p_c = d0.oMf[robot.ee_frame].translation
    sys0 = pl.RigidInertia(d0.Ig.mass, d0.com[0].copy(), d0.Ig.inertia.copy())
    ours = pl.combine_inertias(sys0, pl.RigidInertia(P.mass, p_c, P.inertia_matrix()))
    assert ours.mass == pytest.approx(d1.Ig.mass, rel=1e-14)
    assert np.allclose(ours.inertia, d1.Ig.inertia, atol=1e-12)
    delta = p_c - d0.com[0]
    _, printed = tp.system_inertia_6_41(sys0.mass, sys0.inertia, P.mass, P.inertia_matrix(), delta[0], delta[2])
    assert abs(printed[1, 1] - d1.Ig.inertia[1, 1]) > 1e-4  # m_cl vs reduced mass on |delta| = 0.3 m
    assert abs(printed[0, 2] - d1.Ig.inertia[0, 2]) > 1e-4  # missing product term -mu x z


def test_6_43_sphere_integral_printed_gives_three_fifths():
    assert tp.sphere_inertia_6_43(2.0, 0.1) == pytest.approx(0.6 * 2.0 * 0.01, rel=1e-12)
    assert tp.sphere_inertia_6_43(2.0, 0.1, corrected=True) == pytest.approx(0.4 * 2.0 * 0.01, rel=1e-12)
    assert pl.Payload.sphere(2.0, 0.1).inertia[0] == pytest.approx(tp.sphere_inertia_6_43(2.0, 0.1, corrected=True), rel=1e-12)


def test_6_42_com_printed_misprint_corrected_matches_pinocchio(robot, data):
    rng = np.random.default_rng(SEED)
    worst = 0.0
    for _ in range(10):
        qa = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
        ref = pl.com_with_payload(robot, data, qa, 0.1)
        assert np.allclose(tp.com_6_42_corrected(qa, robot.params, 0.1), ref, atol=1e-14)
        worst = max(worst, np.abs(tp.com_6_42(qa, robot.params, 0.1) - ref).max())
    assert worst > 1e-3  # the payload term misses m_cl (r0 + d2 s2), link 1's CoM height is off


# --------------------------------------------------------------- holding, capacity
def test_holding_efforts_equal_corrected_closed_form(robot):
    rng = np.random.default_rng(SEED)
    for _ in range(10):
        qa = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
        h = pl.holding_efforts(robot, qa, 0.3)
        assert h.thrust == pytest.approx((robot.params.total_mass + 0.3) * robot.params.g, rel=1e-14)
        assert np.allclose(h.arm_effort, tp.holding_torques_corrected(qa, robot.params, 0.3), atol=1e-13)
        assert np.allclose(h.arm_effort_nominal, tp.holding_torques_corrected(qa, robot.params, 0.0), atol=1e-13)
    with pytest.raises(LimitError):
        pl.holding_efforts(robot, (0.1, 0.0, 0.0), 0.1)


def test_printed_holding_torques_are_not_torques(robot):
    """tau_theta2 = (d2 m2/2 + m3 + m_cl) g adds kg m to kg: changing the length unit (m -> mm) must scale a
    torque by exactly 1000 (N m -> N mm); the printed value does not, the corrected one does."""
    p = robot.params
    p_mm = p.with_changes(d0=1e3 * p.d0, d1=1e3 * p.d1, d2=1e3 * p.d2, d3=1e3 * p.d3)
    t2, t3 = tp.holding_torques_6_4_1(p, 0.1)
    t2mm, t3mm = tp.holding_torques_6_4_1(p_mm, 0.1)
    assert abs(t2mm / t2 - 1000.0) > 100.0 and abs(t3mm / t3 - 1000.0) > 100.0
    qa = (0.0, math.pi / 2, 0.0)
    c, cmm = tp.holding_torques_corrected(qa, p, 0.1), tp.holding_torques_corrected(qa, p_mm, 0.1)
    assert cmm[1:] == pytest.approx(1000.0 * c[1:], rel=1e-12)
    # the dimensionally consistent reading (m2/2 + m3 + m_cl) d2 g holds with link 2 horizontal, link 3 vertical
    m2, m3 = p.links[1].mass, p.links[2].mass
    h = pl.holding_efforts(robot, (0.0, math.pi / 2, -math.pi / 2), 0.1)
    assert abs(h.arm_effort[1]) == pytest.approx((m2 / 2 + m3 + 0.1) * p.d2 * p.g, rel=1e-12)
    # and (m3/2 + m_cl) d3 g with link 3 horizontal
    h = pl.holding_efforts(robot, (0.0, math.pi / 2, 0.0), 0.1)
    assert abs(h.arm_effort[2]) == pytest.approx((m3 / 2 + 0.1) * p.d3 * p.g, rel=1e-12)


def test_capacity_worst_case_matches_closed_form(robot):
    p = robot.params
    g, d2, d3 = p.g, p.d2, p.d3
    m2, m3 = p.links[1].mass, p.links[2].mass
    cap = pl.payload_capacity(robot, "manipulation")
    # theta2 binds with both links horizontal: limit = g [(m2/2 + m3 + m) d2 + (m3/2 + m) d3]
    expected = (p.effort_limits[1] / g - (m2 / 2 + m3) * d2 - m3 * d3 / 2) / (d2 + d3)
    # constraints are named by their arm joint (qprr.payload is generic): "theta2" is the effort tau_theta2
    assert cap.limiting == "theta2" and cap.status == "ok"
    assert cap.max_mass == pytest.approx(expected, rel=1e-12)
    assert abs(math.sin(cap.q_arm[1])) == pytest.approx(1.0) and cap.q_arm[2] == pytest.approx(0.0, abs=1e-12)
    assert cap.per_limit["theta3"] == pytest.approx((p.effort_limits[2] / g - m3 * d3 / 2) / d3, rel=1e-12)
    tr = pl.payload_capacity(robot, "transport")
    assert tr.max_mass == pytest.approx(4 * p.thrust_max / g - p.total_mass, rel=1e-14) and tr.limiting == "thrust"
    # at the capacity the worst configuration is exactly at the effort limit
    h = pl.holding_efforts(robot, cap.q_arm, cap.max_mass)
    assert abs(h.arm_effort[1]) == pytest.approx(p.effort_limits[1], rel=1e-12)
    with pytest.raises(UnknownNameError):
        pl.payload_capacity(robot, "juggling")


# --------------------------------------------------------------- B_c, C_c, G_c
def test_payload_terms_closed_form_equal_pinocchio_difference(robot, data):
    rng = np.random.default_rng(SEED)
    P = pl.Payload(0.15, (0.01, -0.005, 0.02), (2e-5, 3e-5, 1.5e-5, 1e-6, -2e-6, 0.0))  # a physical body (triangle inequality)
    for _ in range(8):
        xi = random_xi(rng, robot)
        terms = pl.payload_terms_xi(robot, data, xi, rng.normal(size=9), P)
        Bc, Gc = pl.payload_terms_closed_form(robot, data, xi, P)
        assert np.allclose(terms.B_c, Bc, atol=1e-13)
        assert np.allclose(terms.G_c, Gc, atol=1e-13)


def test_G_c_6_52_is_the_gradient_of_y_not_z(robot, data):
    """Printed (6.52) = d(m_c g y_e)/dxi up to two more misprints (d2 for d3, a spurious 1/2); the model needs z_e."""
    rng = np.random.default_rng(SEED)
    d = _d(robot)
    m, g = 0.1, robot.params.g
    worst = 0.0
    for _ in range(6):
        xi = random_xi(rng, robot)
        _, Gc = pl.payload_terms_closed_form(robot, data, xi, m)
        printed = tp.G_c_6_52(xi, m, d, g)
        worst = max(worst, np.abs(printed - Gc).max())
        # gradient of y_e by central differences
        grad = np.zeros(9)
        for i in range(9):
            e = np.zeros(9)
            e[i] = 1e-6
            grad[i] = (qm.ee_pose_xi(robot, data, xi + e)[0][1] - qm.ee_pose_xi(robot, data, xi - e)[0][1]) / 2e-6
        # fix the two typos: rows 5, 6 with d3 in the s23 terms, row 9 without 1/2
        fixed = printed.copy()
        fixed[4:6] += _d2_to_d3_rows(xi, m, g, d)
        fixed[8] = 2.0 * printed[8]
        assert np.allclose(fixed, m * g * grad, atol=1e-7)
    assert worst > 0.1


def _d2_to_d3_rows(xi, m, g, d):
    """Rows 5, 6 of (6.52) written with d3 s23 minus as printed (d2 s23)."""
    f, t, s = xi[3:6]
    s23 = math.sin(xi[7] + xi[8])
    corr = (d[3] - d[2]) * s23
    return np.array([-m * g * math.sin(s) * math.sin(t) * corr, m * g * math.cos(s) * math.cos(t) * corr])


def test_B_c_6_51_printed_blocks(robot, data):
    """(6.51), with its T(phi_b) the world-frame rate map that its own Q = R_b^T T implies: B11c, B12c, B13c, B23c and
    B33c hold exactly; B22c is misprinted (counter-example at a tilted state; its printed block is not symmetric)."""
    xi = np.array([0.3, -0.2, 1.0, 0.4, -0.3, 0.7, 0.02, 0.5, -0.4])
    Ic = np.diag([2e-5, 3e-5, 1e-5])
    P = pl.Payload(0.1, inertia=(2e-5, 3e-5, 1e-5, 0.0, 0.0, 0.0))
    Bc, _ = pl.payload_terms_closed_form(robot, data, xi, P)
    printed = tp.B_c_6_51(xi, 0.1, Ic, _d(robot))
    blk = lambda M, i, j: M[3 * i : 3 * i + 3, 3 * j : 3 * j + 3]  # noqa: E731
    for i, j in ((0, 0), (0, 1), (0, 2), (1, 2), (2, 2)):
        assert np.allclose(blk(printed, i, j), blk(Bc, i, j), atol=1e-14)
    assert np.abs(blk(printed, 1, 1) - blk(Bc, 1, 1)).max() > 1e-4
    assert np.abs(blk(printed, 1, 1) - blk(printed, 1, 1).T).max() > 1e-4
    assert np.allclose(tp.B_c_6_51(xi, 0.1, Ic, _d(robot), corrected=True), Bc, atol=1e-14)
    # level attitude and zero yaw: R_b = I, T = I, so the printed blocks coincide with the model
    xi0 = xi.copy()
    xi0[3:6] = 0.0
    Bc0, _ = pl.payload_terms_closed_form(robot, data, xi0, P)
    assert np.allclose(tp.B_c_6_51(xi0, 0.1, Ic, _d(robot)), Bc0, atol=1e-14)


# --------------------------------------------------------------- mass estimate
def test_estimator_is_exact_on_a_noise_free_step(robot):
    """tau = RNEA_nominal + m Y holds exactly for the simulator's semi-implicit Euler step: one step suffices."""
    loaded = pl.with_payload(robot, 0.137)
    rng = np.random.default_rng(SEED)
    est = pl.MassEstimator(robot, prior_weight=1e-12)
    xi = random_xi(rng, robot)
    q, v = co.xi_to_qv(xi, rng.normal(size=9))
    tau = rng.normal(size=9)
    a = pin.aba(loaded.model, loaded.model.createData(), q, v, tau)
    dt = 1e-3
    m = est.update(q, v, tau, v + dt * a, dt)
    assert m == pytest.approx(0.137, abs=1e-9)


def test_estimator_converges_on_a_seeded_noisy_hover(robot):
    """Hover carrying 0.1 kg (unknown to the controller), white force noise 0.3 N (Thesis (6.27)) on x, y, z."""
    xi = (0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -0.04, 0.3, 0.5)
    ctrl = PayloadIDC(robot, gains.payload_idc(), payload="estimate")
    res = sim.simulate(
        robot,
        ctrl,
        Hold(xi),
        1.5,
        payload=sim.PayloadSchedule((sim.PayloadChange(0.0, 0.1),)),
        disturbance=sim.WhiteNoise(0.3, components=(0, 1, 2)),
        seed=7,
    )
    m = np.asarray(ctrl.mass_log)
    late = m[res.t >= 0.5]
    assert np.abs(late - 0.1).max() < 0.01  # measured 0.0034 kg (time constant 0.05 s)
    assert abs(late.mean() - 0.1) < 1e-3
    # the controller's model then holds the hover: static equilibrium with the payload
    f_total = res.f[-200:].sum(axis=1).mean()
    assert f_total == pytest.approx((robot.params.total_mass + 0.1) * robot.params.g, rel=2e-3)


def test_estimator_forgets_a_released_payload(robot):
    est = pl.MassEstimator(robot, time_constant=0.05, prior_weight=1e-12)
    loaded = pl.with_payload(robot, 0.1)
    rng = np.random.default_rng(SEED)
    q, v = co.xi_to_qv(random_xi(rng, robot), np.zeros(9))
    tau = pin.computeGeneralizedGravity(loaded.model, loaded.model.createData(), q)
    dt = 1e-3
    for _ in range(100):
        est.update(q, v, tau, v, dt)  # static: the loaded model's gravity holds it
    assert est.mass == pytest.approx(0.1, abs=1e-9)
    tau0 = pin.computeGeneralizedGravity(robot.model, robot.data(), q)
    for k in range(1, 501):
        est.update(q, v, tau0, v, dt)
        if k == 50:  # one time constant: the weight of old data is e^-1 of the total
            assert 0.02 < est.mass < 0.06
    assert est.mass < 0.1 * math.exp(-10.0) * 1.01 + 1e-12


def test_payload_and_estimator_validate_inputs(robot):
    with pytest.raises(InputError):
        pl.Payload(-0.1)
    with pytest.raises(InputError):
        pl.Payload(0.1, inertia=(-1.0, 0, 0, 0, 0, 0))
    with pytest.raises(InputError):
        pl.MassEstimator(robot, time_constant=0.0)
    with pytest.raises(UnknownNameError):
        PayloadIDC(robot, gains.payload_idc(), payload="guess")


def test_hypothesis_5_payload_moment_is_a_pitch_moment(robot):
    """Hypothesis 5 bounds the arm + payload moment by tau_phi (roll); the arm moves in the x-z plane of B, so the
    moment it exerts on the base is about y_B: a pitch moment, bounded by tau_theta."""
    rng = np.random.default_rng(SEED)
    loaded = pl.with_payload(robot, 0.5)
    data = loaded.model.createData()
    for _ in range(5):
        xi = random_xi(rng, robot)
        xi[3] = xi[4] = 0.0  # level hover, any position, yaw and arm configuration
        tau = qm.arm_gravity_torque_body(loaded, data, co.xi_to_q(xi))
        assert abs(tau[0]) < 1e-14 and abs(tau[2]) < 1e-14
    tau = qm.arm_gravity_torque_body(loaded, data, co.xi_to_q(np.array([0, 0, 0, 0, 0, 0, 0.04, 0.8, 0.3])))
    assert abs(tau[1]) > 1.0  # 1.8 N m about y_B


def test_closed_loop_static_equilibrium_with_payload(robot):
    """Hovering with a known 0.3 kg payload, the applied generalised force N f equals the loaded model's gravity G(q):
    thrust (m + m_c) g, rotor torques balancing the arm's moment, joint efforts = the holding torques."""
    xi = (0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.03, 0.6, 0.5)
    ctrl = PayloadIDC(robot, gains.payload_idc(), payload="known", known_mass=0.3)
    res = sim.simulate(robot, ctrl, Hold(xi), 2.0, payload=sim.PayloadSchedule((sim.PayloadChange(0.0, 0.3),)))
    loaded = pl.with_payload(robot, 0.3)
    q = co.xi_to_q(res.xi[-1])
    G = pin.computeGeneralizedGravity(loaded.model, loaded.model.createData(), q)
    tau = robot.actuation_matrix @ np.r_[res.f[-1], res.arm_effort[-1]]
    assert np.allclose(tau, G, atol=1e-9)
    h = pl.holding_efforts(robot, xi[6:9], 0.3)
    assert res.f[-1].sum() == pytest.approx(h.thrust, rel=1e-10)
    assert np.allclose(res.arm_effort[-1], h.arm_effort, atol=1e-9)
    assert np.abs(res.xi[-1] - np.array(xi)).max() < 1e-9
