"""Inverse kinematics (qprr.ik, qprr.thesis.igm): every method against Pinocchio's forward
kinematics, the thesis steps and their errata, the strict priority of the QP hierarchy,
joint limits, unreachable targets and bad input."""

from __future__ import annotations

import math
import sys

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
import qprr.ik
import qprr.thesis
from qprr import charts as co
from qprr import kinematics as kin
from qprr.errors import InputError, LimitError, NonFiniteError, ShapeError, UnknownNameError
from qprr.ik import tasks
from qprr.thesis import igm

POS_TOL = ORI_TOL = 1e-6
_ROBOT = qprr.thesis.load_qprr()  # for the hypothesis tests (no function-scoped fixtures there)


# ----------------------------------------------------------------------------- helpers
def random_hover_xi(rng, robot, box=3.0):
    """A hover configuration (roll = pitch = 0) with the arm inside its limits."""
    xi = np.zeros(9)
    xi[0:3] = rng.uniform(-box, box, 3)
    xi[5] = rng.uniform(-np.pi, np.pi)
    xi[6:9] = rng.uniform(robot.params.lower_limits, robot.params.upper_limits)
    return xi


def target_of(robot, data, xi) -> pin.SE3:
    return kin.ee_placement(robot, data, co.xi_to_q(xi))


def tilted(M: pin.SE3, angle: float) -> pin.SE3:
    """M with its y axis turned ``angle`` out of the horizontal plane (unreachable in hover)."""
    y = M.rotation[:, 1]
    u = np.cross([0.0, 0.0, 1.0], y)
    u /= np.linalg.norm(u)
    return pin.SE3(pin.exp3(angle * u) @ M.rotation, M.translation.copy())


def fk_errors(robot, data, q, M_d):
    M = kin.ee_placement(robot, data, q)
    return np.linalg.norm(M.translation - M_d.translation), np.linalg.norm(pin.log3(M_d.rotation.T @ M.rotation))


def zyz_3_64(R):
    """Thesis (3.64): ZYZ angles (phi_e, theta_e, psi_e) of R."""
    return (
        math.atan2(R[1, 2], R[0, 2]),
        math.atan2(math.hypot(R[0, 2], R[1, 2]), R[2, 2]),
        math.atan2(R[2, 1], -R[2, 0]),
    )


def assert_valid_solution(robot, data, res, M_d, hover=True):
    assert res.success, res.reason
    assert res.reason == ""
    pos, ori = fk_errors(robot, data, res.q, M_d)  # independent check by Pinocchio FK
    assert pos < POS_TOL and ori < ORI_TOL
    assert abs(pos - res.position_error) < 1e-12 and abs(ori - res.orientation_error) < 1e-12
    robot.check_arm_limits(res.q[7:10])
    np.testing.assert_allclose(co.xi_to_q(res.xi), res.q, atol=1e-12)
    c_b = kin.com_body(robot, data, res.q)
    assert abs(c_b[0] - res.x_cm) < 1e-12 and abs(c_b[1] - res.y_cm) < 1e-12
    if hover:
        assert res.hover_feasible and abs(res.xi[3]) < 1e-6 and abs(res.xi[4]) < 1e-6


@pytest.fixture(scope="module")
def rob():
    return qprr.thesis.load_qprr()


@pytest.fixture(scope="module")
def dat(rob):
    return rob.data()


@pytest.fixture(scope="module")
def hover_targets(rob, dat):
    rng = np.random.default_rng(20210101)
    return [target_of(rob, dat, random_hover_xi(rng, rob)) for _ in range(25)]


# ----------------------------------------------------------------- every method converges
@pytest.mark.parametrize(
    "method, options",
    [
        ("igm", None),
        ("igm", {"theta2": "balance"}),
        ("dls", None),
        ("qp", None),
        ("qp", {"init": "guess"}),
        ("clika", {"hover": True, "weights": (1, 1, 1, 1, 1, 1, 1e4, 1, 1)}),
    ],
)
def test_methods_reach_reachable_hover_targets(rob, dat, hover_targets, method, options):
    n = 8 if method == "clika" else len(hover_targets)  # CLIKA takes ~60 Euler steps
    for M_d in hover_targets[:n]:
        res = igm.solve_qprr(rob, dat, M_d, method, options=options)
        assert_valid_solution(rob, dat, res, M_d)
        assert res.method == method and res.iterations >= 0 and res.wall_time > 0


def test_igm_levenberg_marquardt_converges_from_a_far_guess(rob, dat, hover_targets):
    """Algorithm 4 on (3.72) from a guess metres away with a bent arm: a few iterations."""
    for M_d in hover_targets[:10]:
        xi0 = np.r_[M_d.translation + [3.0, -2.0, 4.0], 0.0, 0.0, 1.0, 0.03, 1.5, -1.0]
        res = igm.solve_qprr(rob, dat, M_d, "igm", xi0=xi0)
        assert_valid_solution(rob, dat, res, M_d)
        assert 1 <= res.iterations <= 10 and res.initial_guess == "xi0 (given)"


def test_igm_is_exact_and_puts_r0_at_the_cog_optimum(rob, dat, hover_targets):
    """(3.79)-(3.81): r0 minimises |x_cm| over the slider range for the theta2, theta3 found;
    the base compensates (3.71) so that the end effector stays on the target."""
    lo, hi = rob.params.r0_limits
    for M_d in hover_targets:
        res = igm.solve_qprr(rob, dat, M_d, "igm")
        assert res.position_error < 1e-9 and res.orientation_error < 1e-12
        xs = []
        for r0 in np.linspace(lo, hi, 41):
            q = res.q.copy()
            q[7] = r0
            xs.append(abs(kin.com_body(rob, dat, q)[0]))
        assert abs(res.x_cm) <= min(xs) + 1e-12
        if min(xs) > 0:  # unbalanceable with this theta2: r0 saturated (Algorithm 5)
            assert res.xi[6] in (lo, hi) or abs(res.x_cm) < 1e-12


def test_balanced_igm_centres_the_cog_when_possible(rob, dat, hover_targets):
    n_balanced = 0
    for M_d in hover_targets:
        lm = igm.solve_qprr(rob, dat, M_d, "igm")
        bal = igm.solve_qprr(rob, dat, M_d, "igm", options={"theta2": "balance"})
        assert abs(bal.x_cm) <= abs(lm.x_cm) + 1e-12
        n_balanced += abs(bal.x_cm) < 1e-12
    assert n_balanced >= 0.8 * len(hover_targets)


def test_igm_cog_closed_form_matches_pinocchio_for_cad_parameters(cad_robot):
    """The general x_cm of ArmConstants (link CoM offsets, rail) against Pinocchio."""
    data = cad_robot.data()
    rng = np.random.default_rng(3)
    for _ in range(10):
        M_d = target_of(cad_robot, data, random_hover_xi(rng, cad_robot))
        res = igm.solve_qprr(cad_robot, data, M_d, "igm")
        assert res.success, res.reason
        K = igm.arm_constants(cad_robot.params)
        r0, t2, t3 = res.xi[6:9]
        x_cm = (K.M_s * r0 + K.k0 + K.a_s * math.sin(t2) + K.a_c * math.cos(t2) + K.b_s * math.sin(t2 + t3) + K.b_c * math.cos(t2 + t3)) / K.m_G
        c_b = kin.com_body(cad_robot, data, res.q)
        assert abs(x_cm - c_b[0]) < 1e-12 and abs(K.y0 / K.m_G - c_b[1]) < 1e-12


# -------------------------------------------------------------------- thesis errata
def test_3_64_singularity_condition():
    """(3.64) is stated valid for r13 != 0 and r33 != 0; it is singular iff r13 = r23 = 0
    (sin theta_e = 0), whatever r33: it works with r13 = 0 and fails with r33 = 1."""
    R = co.rot_z(math.pi / 2) @ co.rot_y(0.5) @ co.rot_z(0.2)  # r13 = 0
    assert abs(R[0, 2]) < 1e-15
    a, b, c = zyz_3_64(R)
    np.testing.assert_allclose(co.rot_z(a) @ co.rot_y(b) @ co.rot_z(c), R, atol=1e-12)
    R = co.rot_z(0.3)  # r13 = r23 = 0, r33 = 1 != 0
    a, b, c = zyz_3_64(R)
    assert np.abs(co.rot_z(a) @ co.rot_y(b) @ co.rot_z(c) - R).max() > 0.1  # only a + c is defined


def test_3_68_hover_zyz_angles_corrected_forms(rob):
    """(3.68) lines 4-6 at phi = theta = 0: phi_e = atan2(s_psi s23, c_psi s23),
    theta_e = atan2(|s23|, c23), psi_e = (pi/2)(1 - sgn s23); the printed lines fail."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        psi, t23 = rng.uniform(-np.pi, np.pi), rng.uniform(-3.0, 3.0)
        s23, c23, sp, cp = math.sin(t23), math.cos(t23), math.sin(psi), math.cos(psi)
        phi_e, theta_e, psi_e = zyz_3_64(co.rot_z(psi) @ co.rot_y(t23))
        assert abs(phi_e - math.atan2(sp * s23, cp * s23)) < 1e-12
        assert abs(theta_e - math.atan2(abs(s23), c23)) < 1e-12
        assert abs(psi_e - 0.5 * math.pi * (1 - math.copysign(1.0, s23))) < 1e-12
    # printed: phi_e = atan2(s_psi c23, c_psi s23), theta_e = atan2(s23, c23), psi_e = -(pi sgn(s23) - 1)/2
    psi, t23 = 0.4, -0.7
    phi_e, theta_e, psi_e = zyz_3_64(co.rot_z(psi) @ co.rot_y(t23))
    assert abs(phi_e - math.atan2(math.sin(psi) * math.cos(t23), math.cos(psi) * math.sin(t23))) > 0.1
    assert abs(theta_e - math.atan2(math.sin(t23), math.cos(t23))) > 0.1
    assert abs(psi_e - (-0.5 * (math.pi * np.sign(math.sin(t23)) - 1))) > 0.1


def test_3_69_3_70_paired_branches(rob):
    """(3.69)-(3.70) corrected: (psi, t23) = (phi_e, theta_e) or (phi_e + pi, -theta_e), told
    apart by psi_e; the printed alternative t23 = theta_e - pi never reproduces R_e."""
    rng = np.random.default_rng(6)
    for _ in range(100):
        psi, t23 = rng.uniform(-np.pi, np.pi), rng.uniform(-3.0, 3.0)
        if abs(math.sin(t23)) < 1e-3:
            continue
        R = co.rot_z(psi) @ co.rot_y(t23)
        p, t = igm.hover_angles_from_zyz(*zyz_3_64(R))
        np.testing.assert_allclose(co.rot_z(p) @ co.rot_y(t), R, atol=1e-12)
    psi, t23 = 0.4, -0.7  # sin t23 < 0: the second branch
    phi_e, theta_e, _ = zyz_3_64(co.rot_z(psi) @ co.rot_y(t23))
    R = co.rot_z(psi) @ co.rot_y(t23)
    printed = [(p, t) for p in (phi_e, phi_e - math.pi) for t in (theta_e, theta_e - math.pi)]
    assert all(np.abs(co.rot_z(p) @ co.rot_y(t) - R).max() > 0.1 for p, t in printed)


def test_3_71_3_72_reduced_system_corrected(rob, dat):
    """(3.72) corrected: x_e = x_b' + c_psi (d2 s2 + d3 s23) (r0 already inside x_b' by (3.71)).
    The printed form keeps r0 in the bracket and uses c_phi_e, s_theta_e: wrong for r0 != 0
    and, on the sin t23 < 0 branch, for the d2 s2 term."""
    p = rob.params
    xi = np.array([0.3, -0.2, 1.0, 0.0, 0.0, 0.4, 0.03, 0.5, -1.4])  # s23 < 0
    x_b, y_b, z_b, _, _, psi, r0, t2, t3 = xi
    p_e = kin.ee_placement(rob, dat, co.xi_to_q(xi)).translation
    xp, yp = x_b + math.cos(psi) * r0, y_b + math.sin(psi) * r0  # (3.71), second line read as y_b'
    h = p.d2 * math.sin(t2) + p.d3 * math.sin(t2 + t3)
    corrected = [xp + math.cos(psi) * h, yp + math.sin(psi) * h, z_b + p.d0 + p.d1 + p.d2 * math.cos(t2) + p.d3 * math.cos(t2 + t3)]
    np.testing.assert_allclose(corrected, p_e, atol=1e-12)
    phi_e, theta_e, _ = zyz_3_64(co.rot_z(psi) @ co.rot_y(t2 + t3))
    hp = r0 + p.d2 * math.sin(t2) + p.d3 * math.sin(theta_e)
    printed = [xp + math.cos(phi_e) * hp, yp + math.sin(phi_e) * hp]
    assert np.linalg.norm(np.subtract(printed, p_e[:2])) > 0.05


def test_algorithm_5_printed_moves_the_end_effector(rob, dat):
    """Algorithm 5 as printed shifts |x_b| by the excess of r0 with the sign of x_b; the
    corrected form saturates r0 and re-applies (3.71), which keeps the end effector fixed."""
    K = igm.arm_constants(rob.params)
    xi = np.array([-0.5, 0.3, 1.0, 0.0, 0.0, math.pi / 2, 0.0, 0.9, 0.2])
    psi, t2, t3 = xi[5], xi[7], xi[8]
    r0_free = 0.07  # beyond r0_max = 0.04
    xp, yp = xi[0] + math.cos(psi) * r0_free, xi[1] + math.sin(psi) * r0_free  # EE fixed by these
    M_d = kin.ee_placement(rob, dat, co.xi_to_q(np.r_[xi[0:6], 0.0, t2, t3]))
    target = M_d.translation + np.array([math.cos(psi), math.sin(psi), 0.0]) * r0_free
    x_b, y_b, r0 = igm.prismatic_check(xp, yp, psi, r0_free, *rob.params.r0_limits)
    assert r0 == K.upper[0]
    good = kin.ee_placement(rob, dat, co.xi_to_q([x_b, y_b, xi[2], 0, 0, psi, r0, t2, t3])).translation
    np.testing.assert_allclose(good, target, atol=1e-12)
    x_bad = igm.prismatic_check_printed(xp - math.cos(psi) * r0_free, r0_free, K.upper[0])
    bad = kin.ee_placement(rob, dat, co.xi_to_q([x_bad, yp - math.sin(psi) * r0_free, xi[2], 0, 0, psi, K.upper[0], t2, t3])).translation
    assert np.linalg.norm(bad - target) > 0.02


def test_3_78_cog_height_misprint(rob, dat):
    """(3.78): x_cm is right; z_cm as printed, [sum m_i (d0 + d1) + (m2 + m3) d2 c2 / 2 + m3 d3 c23 / 2] / m_G,
    misses link 1's half length and weighs d2 c2 by (m2 + m3)/2 instead of m2/2 + m3."""
    p = rob.params
    m1, m2, m3 = (link.mass for link in p.links)
    mG = p.total_mass
    for r0, t2, t3 in [(0.01, 0.7, -0.3), (-0.03, 0.0, 0.9)]:  # the two misprints cancel near cos t2 = 0.37
        q = co.xi_to_q([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, r0, t2, t3])
        c = kin.com_body(rob, dat, q)
        x = ((m1 + m2 + m3) * r0 + (m2 / 2 + m3) * p.d2 * math.sin(t2) + m3 * p.d3 * math.sin(t2 + t3) / 2) / mG
        z_printed = ((m1 + m2 + m3) * (p.d0 + p.d1) + (m2 + m3) * p.d2 * math.cos(t2) / 2 + m3 * p.d3 * math.cos(t2 + t3) / 2) / mG
        z_fixed = (m1 * (p.d0 + p.d1 / 2) + (m2 + m3) * (p.d0 + p.d1) + (m2 / 2 + m3) * p.d2 * math.cos(t2) + m3 * p.d3 * math.cos(t2 + t3) / 2) / mG
        assert abs(c[0] - x) < 1e-15 and abs(c[2] - z_fixed) < 1e-15
        assert abs(c[2] - z_printed) > 5e-4  # ~1 mm (4 %) off, against 1e-15 for the fixed form


def test_3_81_minimising_the_signed_cog_offset_is_wrong(rob):
    """(3.81) minimises F = x_cm itself; F is affine in r0, so that always picks r0_min.
    The criterion that centres the CoG is min |F| (the text's x_cm < eps)."""
    K = igm.arm_constants(rob.params)
    t2, t3 = -0.3, 0.1  # F < 0 at r0 = 0: |F| is smallest at some r0 > 0
    F = lambda r0: (K.M_s * r0 + K.a_s * math.sin(t2) + K.b_s * math.sin(t2 + t3)) / K.m_G  # noqa: E731
    grid = np.linspace(K.lower[0], K.upper[0], 801)
    assert grid[np.argmin([F(r) for r in grid])] == K.lower[0]
    r_abs = grid[np.argmin([abs(F(r)) for r in grid])]
    assert r_abs > 0 and abs(F(r_abs)) < abs(F(K.lower[0])) - 1e-3


# --------------------------------------------------------------------------- CLIKA
THESIS_TARGET = [10.0, 18.0, 25.0, 0.0, 0.0, 1.57]


def thesis_example_target():
    """x_e = [10, 18, 25, 0, 0, 1.57] of Sec. 4.4.1, orientation read as the ZYZ angles of (3.64):
    R = Rz(0) Ry(0) Rz(1.57) = Rz(1.57) (a ZYX reading gives the same matrix)."""
    p = np.array(THESIS_TARGET[:3])
    a, b, c = THESIS_TARGET[3:]
    R = co.rot_z(a) @ co.rot_y(b) @ co.rot_z(c)
    np.testing.assert_allclose(R, co.euler_to_rotation([a, b, c]), atol=1e-15)  # ZYX [phi, theta, psi]
    return pin.SE3(R, p)


def test_clika_thesis_example(rob, dat):
    """Sec. 4.4.1: from xi = 0 with K = diag(40, 35, 10, 15, 12, 10) CLIKA converges to the
    pose; with W = I the min-norm step gives a share of the 20 m displacement to r0, which
    leaves its +-0.04 m range (reported as a failure with the reason); weighting r0 by
    (4.34) keeps it inside."""
    M_d = thesis_example_target()
    res = igm.solve_qprr(rob, dat, M_d, "clika", xi0=np.zeros(9))
    pos, ori = fk_errors(rob, dat, res.q, M_d)
    assert pos < POS_TOL and ori < ORI_TOL
    assert not res.success and res.status == "limits" and "out of limits" in res.reason
    assert abs(res.xi[6]) > rob.params.r0_limits[1] and not res.within_limits
    w = (1, 1, 1, 1, 1, 1, 1e6, 1, 1)
    # the thesis's CLIKA moves every coordinate: it reaches the pose with the base pitched 0.12 rad,
    # which a quadrotor cannot hold: not a success by default (issue 16 item 6) ...
    tilted_res = igm.solve_qprr(rob, dat, M_d, "clika", xi0=np.zeros(9), options={"weights": w})
    assert not tilted_res.success and tilted_res.status == "not_hover_feasible" and "not in hover" in tilted_res.reason
    assert abs(tilted_res.pitch - 0.1202) < 1e-3 and tilted_res.within_limits
    # ... and the pose alone when the caller says so
    res_w = igm.solve_qprr(rob, dat, M_d, "clika", xi0=np.zeros(9), options={"weights": w, "require_hover": False})
    assert_valid_solution(rob, dat, res_w, M_d, hover=False)


def test_clika_step_is_the_printed_weighted_pseudo_inverse(rob, dat):
    """At a full-rank configuration W^-1/2 (J W^-1/2)^+ = W^-1 J^T (J W^-1 J^T)^-1 (4.34), and
    = J^T (J J^T)^-1 (4.36) for W = I."""
    rng = np.random.default_rng(8)
    xi = np.r_[rng.uniform(-1, 1, 3), 0.2, -0.1, 0.5, 0.01, 0.7, -0.4]
    J = kin.jacobian_xi(rob, dat, xi)
    for w in (np.ones(9), rng.uniform(0.5, 5.0, 9)):
        printed = np.diag(1 / w) @ J.T @ np.linalg.inv(J @ np.diag(1 / w) @ J.T)
        ours = np.diag(1 / np.sqrt(w)) @ np.linalg.pinv(J / np.sqrt(w), rcond=1e-10)
        np.testing.assert_allclose(ours, printed, atol=1e-10)


# ------------------------------------------------------------------ the QP hierarchy
def _lin_step(rob, dat, q, levels, eps_abs=1e-9):
    tasks.update_kinematics(rob, dat, q)
    eng = qprr.ik.HierarchySolver(rob, eps_abs=eps_abs, max_qp_iter=100000)
    eng.reset()
    return eng.solve(rob, dat, q, levels)


def _random_step_problem(seed):
    rob = _ROBOT
    dat = rob.data()
    rng = np.random.default_rng(seed)
    xi = random_hover_xi(rng, rob)
    xi[3:5] = rng.uniform(-0.3, 0.3, 2)
    xi[6] = rng.choice([rob.params.r0_limits[0], rob.params.r0_limits[1], 0.0])  # often on a limit
    q = co.xi_to_q(xi)
    M_d = kin.ee_placement(rob, dat, co.xi_to_q(xi + rng.normal(0, 0.05, 9)))
    full = qprr.ik.default_levels(rob, M_d, rng.uniform(rob.params.lower_limits, rob.params.upper_limits))
    return rob, dat, q, full


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_lower_levels_never_degrade_higher_ones(seed):
    """Level-1 residual ||J1 dv - e1|| with levels {1}, {1, 2}, {1, 2, 3, 4} is the same
    (to rounding), also when a joint limit is active; same for level 2 under 3, 4."""
    rob, dat, q, full = _random_step_problem(seed)
    r1 = [_lin_step(rob, dat, q, full[:k]).residuals[0] for k in (1, 2, 4)]
    assert max(r1) - min(r1) < 1e-8 * (1 + min(r1))
    r2 = [_lin_step(rob, dat, q, full[:k]).residuals[1] for k in (2, 4)]
    assert abs(r2[0] - r2[1]) < 1e-8 * (1 + r2[0])


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_each_level_is_its_qp_optimum_under_the_earlier_levels(seed):
    """KKT conditions of level k written with the earlier levels as equality constraints (not the engine's kernel
    form): min ||J_k dv - e_k||^2 + eps_k ||dv - dv_{k-1}||^2 s.t. J_j dv = J_j dv_{k-1} (j < k), limits on dv_arm.
    Projected on ker [J_1; ...; J_{k-1}], the gradient must be a non-negative combination of the active bounds."""
    from scipy.optimize import nnls

    rob, dat, q, full = _random_step_problem(seed)
    step = _lin_step(rob, dat, q, full)
    lo = rob.arm_lower - q[7:]
    up = rob.arm_upper - q[7:]
    eng = qprr.ik.HierarchySolver(rob)
    prev = np.zeros(rob.nv)
    for k, ((J, e), dv) in enumerate(zip(step.linearized, step.dv_levels)):
        arm = dv[6:]
        assert np.all(arm >= np.minimum(lo, prev[6:]) - 1e-12) and np.all(arm <= np.maximum(up, prev[6:]) + 1e-12)
        eps = eng.regularization + step.damping[k]
        grad = 2 * (J.T @ (J @ dv - e) + eps * (dv - prev))
        if k:
            earlier = np.vstack([Jj for Jj, _ in step.linearized[:k]])
            assert np.abs(earlier @ (dv - prev)).max() < 1e-10  # the earlier optima are kept
            _, s, Vt = np.linalg.svd(earlier)
            Z = Vt[int(np.count_nonzero(s > 1e-9)) :].T  # ker of the earlier levels
        else:
            Z = np.eye(rob.nv)
        act_lo = arm <= np.minimum(lo, prev[6:]) + 1e-10
        act_up = arm >= np.maximum(up, prev[6:]) - 1e-10
        E = np.eye(rob.nv)[6:]
        G = np.hstack([E[act_lo].T, -E[act_up].T])  # grad = G nu (+ earlier rows), nu >= 0
        g_z = Z.T @ grad
        if G.shape[1]:
            _, res = nnls(Z.T @ G, g_z)
        else:
            res = float(np.linalg.norm(g_z))
        assert res < 1e-7 * (1 + np.linalg.norm(J.T @ e)), (k, res)
        prev = dv


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), tilt=st.sampled_from([0.0, 0.0, 0.3]), cold=st.booleans())
def test_qp_never_violates_joint_limits(seed, tilt, cold):
    """Random targets (reachable or not) and random in-limit starts: the arm joints of every
    iterate stay inside [lower, upper] (checked on the result of every truncated run)."""
    rob = _ROBOT
    dat = rob.data()
    rng = np.random.default_rng(seed)
    M_d = target_of(rob, dat, random_hover_xi(rng, rob))
    if tilt:
        M_d = tilted(M_d, tilt)
    xi0 = random_hover_xi(rng, rob) if cold else None
    if xi0 is not None:
        xi0[0:3] = M_d.translation + rng.normal(0, 0.2, 3)
    lo, hi = rob.params.lower_limits, rob.params.upper_limits
    for max_iter in (1, 2, 3, 50):
        res = igm.solve_qprr(rob, dat, M_d, "qp", xi0=xi0, options={"max_iter": max_iter})
        assert np.all(res.q[7:10] >= lo) and np.all(res.q[7:10] <= hi), res.q[7:10]
        assert res.within_limits


def test_qp_result_respects_the_hierarchy(rob, dat, hover_targets):
    """On reachable targets the QP IK ends with pose and hover exact, the CoG on the thrust
    axis whenever the slider range allows it, and never a worse |x_cm| than the thesis IGM."""
    for M_d in hover_targets:
        qp = igm.solve_qprr(rob, dat, M_d, "qp", options={"init": "guess"})
        assert_valid_solution(rob, dat, qp, M_d)
        igm_res = igm.solve_qprr(rob, dat, M_d, "igm", options={"theta2": "balance"})
        if abs(igm_res.x_cm) < 1e-12:  # balanceable; the CoG level settles to ~ |dx_cm/dq| step_tol
            assert abs(qp.x_cm) < 0.1 * qprr.ik.QPOptions().step_tol


def test_user_tasks_extend_the_hierarchy(rob, dat, hover_targets):
    """A task written by a user (theta2 -> 0.2 rad) slots in below the pose; a shifted CoM
    target is honoured below hover."""

    class Theta2Task(tasks.Task):
        dim, name = 1, "theta2"

        def linearize(self, robot, data, q):
            J = np.zeros((1, robot.nv))
            J[0, 7] = 1.0
            return J, np.array([0.2 - q[8]])

    M_d = next(M for M in hover_targets if abs(igm.solve_qprr(rob, dat, M, "igm", options={"theta2": "balance"}).xi[6]) < 0.02)
    levels = ((tasks.PoseTask(rob, M_d),), (Theta2Task(),), (tasks.HoverTask(),))
    res = igm.solve_qprr(rob, dat, M_d, "qp", options={"levels": levels, "require_hover": False})
    assert res.success and abs(res.xi[7] - 0.2) < 0.1 * qprr.ik.QPOptions().step_tol
    assert res.hover_feasible  # 9 dof - 6 (pose) - 1 (theta2) leave room for hover (rank 1 here)
    levels = ((tasks.PoseTask(rob, M_d),), (tasks.HoverTask(),), (tasks.ComTask((0.001, 0.0)),))
    res = igm.solve_qprr(rob, dat, M_d, "qp", options={"levels": levels})
    assert res.success and abs(res.x_cm - 0.001) < 0.1 * qprr.ik.QPOptions().step_tol


@pytest.mark.parametrize("task_factory", ["pose", "hover", "com", "posture"])
def test_task_jacobians_by_finite_differences(rob, dat, task_factory):
    """J of each task against central differences of its error on the manifold (pin.integrate)."""
    rng = np.random.default_rng(13)
    xi = random_hover_xi(rng, rob)
    xi[3:5] = [0.2, -0.3]
    q = co.xi_to_q(xi)
    M_d = kin.ee_placement(rob, dat, co.xi_to_q(xi + 0.1))
    task = {
        "pose": lambda: tasks.PoseTask(rob, M_d),
        "hover": tasks.HoverTask,
        "com": tasks.ComTask,
        "posture": lambda: tasks.PostureTask(rob, [0.0, 0.1, -0.1]),
    }[task_factory]()

    def err(qq):
        tasks.update_kinematics(rob, dat, qq)
        return task.linearize(rob, dat, qq)[1]

    tasks.update_kinematics(rob, dat, q)
    J, _ = task.linearize(rob, dat, q)
    h = 1e-6
    J_fd = np.column_stack(
        [-(err(pin.integrate(rob.model, q, h * ei)) - err(pin.integrate(rob.model, q, -h * ei))) / (2 * h) for ei in np.eye(rob.nv)]
    )
    np.testing.assert_allclose(J, J_fd, atol=1e-7)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(phi=st.floats(-math.pi, math.pi), theta=st.floats(-1.5, 1.5), psi=st.floats(-math.pi, math.pi))
def test_hover_error_is_the_tilt_angle(rob, dat, phi, theta, psi):
    """|e| of the hover task = the angle between z_B and the vertical (pi upside down, never 0 there), along w_xy."""
    xi = rob.neutral_xi()
    xi[3:6] = phi, theta, psi
    q = co.xi_to_q(xi)
    tasks.update_kinematics(rob, dat, q)
    _, e = tasks.HoverTask().linearize(rob, dat, q)
    z_b = dat.oMi[1].rotation[:, 2]
    tilt = math.atan2(math.hypot(z_b[0], z_b[1]), z_b[2])  # (acos of z_b[2] loses half the digits near 0)
    assert abs(np.linalg.norm(e) - tilt) < 1e-12
    if 1e-12 < tilt < math.pi - 1e-6:
        np.testing.assert_allclose(e, -tilt * z_b[0:2] / np.linalg.norm(z_b[0:2]), atol=1e-12)


@pytest.mark.parametrize("name", ["q-prr", "HEX-RRR"])
def test_qp_ik_from_upside_down_ends_in_hover(name):
    """Started with the rotors pushing down (roll 3.0 rad), the QP IK turns the base upright: the hover error
    vanishes only at z_B = e3 (the horizontal part of z_B alone also vanishes at z_B = -e3).  The way round from
    upside down is long (65 iterations on the Q-PRR): 100 allowed."""
    p = qprr.load(name) if name == "q-prr" else qprr.build(name)
    data = p.data()
    xi = p.neutral_xi()
    xi[0:3] = 1.0, -0.5, 2.0
    xi[5] = 0.3
    xi[6:] = 0.5 * p.arm_upper
    target = kin.ee_placement(p, data, co.xi_to_q(xi))
    start = p.neutral_xi()
    start[3] = 3.0
    res = qprr.ik.IKSolver(p, "qp", {"max_iter": 100}).solve(data, target, xi0=start)
    assert res.success and res.hover_feasible, res.reason
    assert abs(res.roll) < 1e-6 and abs(res.pitch) < 1e-6 and res.position_error < 1e-6


def test_a_failing_qp_raises_solver_error(rob, dat):
    """The ProxQP status is checked: a QP stopped before convergence is an error, not a step (ProxQP alone: the exact
    active-set path, tried first by default, solves this level without it)."""
    xi = np.array([0.0, 0.0, 1.0, 0.2, -0.1, 0.3, 0.04, 1.2, 0.5])  # r0 on its upper limit
    q = co.xi_to_q(xi)
    M_d = kin.ee_placement(rob, dat, co.xi_to_q(xi + 0.3))
    levels = qprr.ik.default_levels(rob, M_d, [-0.04, -1.0, 1.0])
    tasks.update_kinematics(rob, dat, q)
    eng = qprr.ik.HierarchySolver(rob, max_qp_iter=1, eps_abs=1e-14, active_set_first=False)
    eng.reset()
    with pytest.raises(qprr.errors.SolverError, match="ProxQP did not solve level"):
        eng.solve(rob, dat, q, levels)


# --------------------------------------------------------- unreachable and bad requests
@pytest.mark.parametrize(
    "method, options",
    [("igm", None), ("dls", None), ("qp", None), ("qp", {"init": "guess"}), ("clika", {"hover": True})],
)
def test_unreachable_in_hover_fails_with_a_reason(rob, dat, hover_targets, method, options):
    for angle in (1e-3, 0.3):
        M_d = tilted(hover_targets[1], angle)
        res = igm.solve_qprr(rob, dat, M_d, method, options=options)
        assert not res.success
        assert res.reason and "hover" in res.reason
        assert res.status in ("unreachable", "not_hover_feasible", "stalled", "max_iterations")


def test_qp_reaches_the_pose_of_an_unreachable_target_by_tilting(rob, dat, hover_targets):
    """Level 1 is kept; level 2 (hover) is what gives: the best-effort solution is tilted."""
    M_d = tilted(hover_targets[2], 0.3)
    res = igm.solve_qprr(rob, dat, M_d, "qp")
    assert res.status == "not_hover_feasible"
    assert res.position_error < POS_TOL and res.orientation_error < ORI_TOL
    assert max(abs(res.roll), abs(res.pitch)) > 0.05
    relaxed = igm.solve_qprr(rob, dat, M_d, "qp", options={"require_hover": False})
    assert relaxed.success and not relaxed.hover_feasible


def test_targets_outside_the_joint_range_fail_cleanly(rob, dat):
    """A Q-PRR whose revolute joints only reach +-0.5 rad cannot point its end effector
    sideways: theta2 + theta3 = pi/2 is outside [-1, 1]."""
    narrow = qprr.thesis.load_qprr(rob.params.with_changes(theta2_limits=(-0.5, 0.5), theta3_limits=(-0.5, 0.5)))
    data = narrow.data()
    M_d = pin.SE3(co.rot_y(math.pi / 2), np.array([0.0, 0.0, 1.0]))
    res = igm.solve_qprr(narrow, data, M_d, "igm")
    assert not res.success and res.status == "limits" and "theta2 + theta3" in res.reason
    res = igm.solve_qprr(narrow, data, M_d, "dls")  # hover only: the orientation cannot be reached
    assert not res.success and "orientation error" in res.reason
    assert res.within_limits and res.orientation_error > 0.1
    res = igm.solve_qprr(narrow, data, M_d, "qp")  # level 1 is reached by tilting the base, level 2 gives
    assert not res.success and res.status == "not_hover_feasible" and "hover" in res.reason
    assert res.within_limits and res.orientation_error < ORI_TOL


def test_out_of_limit_requests_raise(rob, dat, hover_targets):
    M_d = hover_targets[0]
    with pytest.raises(LimitError, match="r0"):
        igm.solve_qprr(rob, dat, M_d, "qp", xi0=[0, 0, 0, 0, 0, 0, 0.1, 0, 0])
    with pytest.raises(LimitError, match="theta2"):
        igm.solve_qprr(rob, dat, M_d, "qp", options={"posture": (0.0, 3.0, 0.0)})
    with pytest.raises(InputError, match="roll and pitch"):
        igm.solve_qprr(rob, dat, M_d, "dls", xi0=[0, 0, 0, 0.1, 0, 0, 0, 0, 0])


def test_bad_input_raises_with_names(rob, dat, hover_targets):
    M_d = hover_targets[0]
    with pytest.raises(UnknownNameError, match="'qp'"):
        igm.solve_qprr(rob, dat, M_d, "newton")
    with pytest.raises(UnknownNameError, match="max_iter"):
        igm.solve_qprr(rob, dat, M_d, "qp", options={"max_iters": 3})
    with pytest.raises(InputError, match="dt"):
        igm.solve_qprr(rob, dat, M_d, "clika", options={"dt": -1.0})
    with pytest.raises(NonFiniteError):
        igm.solve_qprr(rob, dat, (np.array([0.0, np.nan, 0.0]), np.eye(3)), "igm")
    with pytest.raises(ShapeError):
        igm.solve_qprr(rob, dat, (np.zeros(2), np.eye(3)), "igm")
    with pytest.raises(InputError, match="rotation"):
        igm.solve_qprr(rob, dat, (np.zeros(3), 1.01 * np.eye(3)), "igm")
    with pytest.raises(InputError, match="rotation"):
        igm.solve_qprr(rob, dat, (np.zeros(3), np.diag([1.0, 1.0, -1.0])), "igm")
    with pytest.raises(InputError, match="SE3"):
        igm.solve_qprr(rob, dat, np.eye(4), "igm")
    with pytest.raises(ShapeError, match="xi0"):
        igm.solve_qprr(rob, dat, M_d, "qp", xi0=np.zeros(8))


def test_target_forms_are_equivalent(rob, dat, hover_targets):
    M_d = hover_targets[3]
    a = igm.solve_qprr(rob, dat, M_d, "qp")
    b = igm.solve_qprr(rob, dat, (M_d.translation, M_d.rotation), "qp")
    np.testing.assert_array_equal(a.q, b.q)


def test_benchmark_targets_and_results_are_deterministic_for_a_seed(rob, dat):
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "benchmarks" / "ik_benchmark.py"
    spec = importlib.util.spec_from_file_location("ik_benchmark", path)
    bench = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("ik_benchmark", bench)  # dataclasses need their module registered
    spec.loader.exec_module(bench)
    a = bench.make_targets(rob, dat, 5, 3, seed=7)
    b = bench.make_targets(rob, dat, 5, 3, seed=7)
    for Ma, Mb in zip(a[0] + a[1], b[0] + b[1]):
        np.testing.assert_array_equal(Ma.homogeneous, Mb.homogeneous)
        np.testing.assert_array_equal(igm.solve_qprr(rob, dat, Ma, "qp").q, igm.solve_qprr(rob, dat, Mb, "qp").q)
    c = bench.make_targets(rob, dat, 5, 3, seed=8)
    assert not np.array_equal(a[0][0].homogeneous, c[0][0].homogeneous)


def test_results_are_deterministic(rob, dat, hover_targets):
    """Same inputs, same answers to the last bit, whatever was solved in between."""
    for method, opts in (("qp", {"init": "guess"}), ("dls", None), ("igm", None)):
        first = [igm.solve_qprr(rob, dat, M, method, options=opts).q for M in hover_targets[:6]]
        igm.solve_qprr(rob, dat, tilted(hover_targets[7], 0.2), method, options=opts)
        again = [igm.solve_qprr(rob, dat, M, method, options=opts).q for M in reversed(hover_targets[:6])][::-1]
        for x, y in zip(first, again):
            np.testing.assert_array_equal(x, y)


def test_settle_tol_only_cuts_the_tail_of_the_lower_levels(rob, dat, hover_targets):
    """Once the pose holds, steps below settle_tol end the iteration: from cold starts the same successes in no more
    iterations than with settle_tol = step_tol (the tail run to the end), the CoG offset within 1e-9 m of it, the pose
    still exact to 1e-10."""
    tail = igm.solver(rob, "qp", {"settle_tol": 1e-7}, init="guess")
    settled = igm.solver(rob, "qp", None, init="guess")
    for M in hover_targets[:12]:
        a, b = tail.solve(dat, M), settled.solve(dat, M)
        assert a.success and b.success, (a.reason, b.reason)
        assert b.iterations <= a.iterations
        assert abs(a.x_cm - b.x_cm) < 1e-9 and abs(a.y_cm - b.y_cm) < 1e-9
        assert b.position_error < 1e-10 and b.orientation_error < 1e-10


def test_solver_engine_is_the_qp_methods_hierarchy(rob):
    """IKSolver.engine: the HierarchySolver method "qp" keeps (one per solver, with the platform's joint limits), None
    for a method that keeps none; read-only."""
    from qprr.ik.hierarchy import HierarchySolver

    qp = qprr.ik.IKSolver(rob, "qp")
    assert isinstance(qp.engine, HierarchySolver) and qp.engine is qp.engine
    np.testing.assert_array_equal(qp.engine.lower, rob.arm_lower)
    assert qp.engine is not qprr.ik.IKSolver(rob, "qp").engine
    assert qprr.ik.IKSolver(rob, "dls").engine is None and qprr.ik.IKSolver(rob, "clika").engine is None
    with pytest.raises(AttributeError):
        qp.engine = None


@pytest.mark.parametrize("method", ["qp", "dls"])
def test_solve_many_gives_the_answers_of_one_solve_per_target(rob, dat, hover_targets, method):
    """qprr.ik.solve_many: reachable and unreachable targets, a position target and a given xi0 among them, the same
    results to the last bit as one solve per target; a bad target raises before any is solved."""
    solver = qprr.ik.IKSolver(rob, method)
    targets = [*hover_targets[:5], tilted(hover_targets[5], 0.3), hover_targets[6].translation.copy(), hover_targets[7]]
    xi0s = [None] * 7 + [random_hover_xi(np.random.default_rng(3), rob)]
    many = qprr.ik.solve_many(solver, targets, xi0=xi0s)
    one = [qprr.ik.IKSolver(rob, method).solve(dat, M, xi0) for M, xi0 in zip(targets, xi0s)]
    assert [r.success for r in many] == [r.success for r in one] and not many[5].success
    for a, b in zip(many, one):
        assert (a.status, a.reason, a.iterations, a.initial_guess) == (b.status, b.reason, b.iterations, b.initial_guess)
        np.testing.assert_array_equal(a.q, b.q)
    with pytest.raises(ShapeError, match=r"targets\[1\]"):
        qprr.ik.solve_many(solver, [hover_targets[0], np.zeros(4)])
    with pytest.raises(InputError, match="one entry per target"):
        qprr.ik.solve_many(solver, targets, xi0=xi0s[:2])


# --------------------------------------------------------- targets whose doubles cannot resolve the tolerance
@pytest.mark.parametrize("method", ["qp", "dls", "igm", "clika"])
def test_targets_too_far_for_the_tolerance_are_refused(rob, dat, method):
    """Issue 22.5: at |p| = 1e17 m neighbouring doubles are 16 m apart, a "1e-16 m" error would mean nothing: the target
    is refused with the reason; the largest accepted distance keeps 16 ulps below a tenth of the tolerance."""
    R = np.eye(3)
    for far in (1e17, 1e9):
        with pytest.raises(InputError, match="too far from the origin"):
            igm.solve_qprr(rob, dat, (np.array([far, 0.0, 1.0]), R), method)
    from qprr.ik.solver import check_resolvable

    # the bound follows the tolerance, not a fixed distance: 16 ulps of |p| below a tenth of it
    check_resolvable(np.array([3.0e7, 0.0, 0.0]), 1e-6)
    check_resolvable(np.array([1e9, 0.0, 0.0]), 1e-3)
    with pytest.raises(InputError, match="below about 3.36e"):
        check_resolvable(np.array([4.0e7, 0.0, 0.0]), 1e-6)
    assert 16 * np.spacing(3.0e7) <= 0.1 * 1e-6 < 16 * np.spacing(4.0e7)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_exact_active_set_step_equals_the_proxqp_step(seed):
    """The hierarchy's step by exact solves on the active set (default) equals the ProxQP + polish step (the two
    paths of qprr.actuation.lexicographic.Lexicographic), joint limits active included."""
    rob, dat, q, full = _random_step_problem(seed)
    tasks.update_kinematics(rob, dat, q)
    a = qprr.ik.HierarchySolver(rob, active_set_first=True)
    b = qprr.ik.HierarchySolver(rob, active_set_first=False, max_qp_iter=100000)
    sa, sb = a.solve(rob, dat, q, full), b.solve(rob, dat, q, full)
    assert np.abs(sa.dv - sb.dv).max() <= 1e-7 * (1 + np.abs(sb.dv).max())


def test_task_error_equals_the_linearized_error(rob, dat):
    """Task.error (asked first by the hierarchy's first step) is bit for bit the e of Task.linearize, for every built-in
    task, weighted or not, at tilted, level and near upside-down configurations."""
    rng = np.random.default_rng(21)
    M_d = kin.ee_placement(rob, dat, co.xi_to_q(random_hover_xi(rng, rob)))
    made = [
        tasks.PoseTask(rob, M_d),
        tasks.PoseTask(rob, M_d, weights=(1, 2, 3, 4, 5, 6)),
        tasks.PositionTask(rob, M_d.translation, weights=(2, 1, 3)),
        tasks.BaseOrientationTask(rob, M_d.rotation),
        tasks.HoverTask(),
        tasks.ComTask((0.001, -0.002), weights=(1, 4)),
        tasks.PostureTask(rob, [0.0, 0.1, -0.1]),
    ]
    for k in range(30):
        xi = random_hover_xi(rng, rob)
        xi[3:5] = (0.0, 0.0) if k % 3 == 0 else ((math.pi - 1e-7, 1e-8) if k % 3 == 1 else rng.uniform(-1.0, 1.0, 2))
        q = co.xi_to_q(xi)
        tasks.update_kinematics(rob, dat, q)
        for task in made:
            np.testing.assert_array_equal(task.error(rob, dat, q), task.linearize(rob, dat, q)[1])


def test_custom_task_is_linearized_once_per_step(rob, dat):
    """A task without its own ``error`` is linearised once per hierarchy step, not twice (custom levels are validated at
    the first step, where the error-first shortcut is not taken)."""
    calls = []

    class Counted(tasks.PostureTask):
        def linearize(self, platform, data, q):
            calls.append(1)
            return super().linearize(platform, data, q)

        error = tasks.Task.error

    rng = np.random.default_rng(5)
    M_d = kin.ee_placement(rob, dat, co.xi_to_q(random_hover_xi(rng, rob)))
    levels = [[tasks.PoseTask(rob, M_d)], [tasks.HoverTask()], [tasks.ComTask()], [Counted(rob, [0.0, 0.0, 0.0])]]
    res = qprr.ik.IKSolver(rob, "qp", {"levels": levels}).solve(dat, M_d)
    assert res.success and res.iterations >= 2
    assert len(calls) <= res.iterations + 1  # one per step, and the level errors at the returned q


def test_solve_checks_every_new_data_even_after_a_checked_one():
    """The solver checks a pinocchio.Data once and trusts it afterwards: None, or a Data of another model, given after
    a checked one is still refused with an InputError naming ``data``."""
    platform = qprr.load()
    solver = qprr.ik.IKSolver(platform)
    data = platform.data()
    assert solver.solve(data, [0.3, 0.0, 1.5]).success
    for wrong in (None, qprr.load("borinot_flying_arm_2").data()):
        with pytest.raises(qprr.errors.InputError, match="data"):
            solver.solve(wrong, [0.3, 0.0, 1.5])
    assert solver.solve(data, [0.3, 0.0, 1.5]).success
