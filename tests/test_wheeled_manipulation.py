"""Mobile manipulation: the combined model, the task-priority IK under the Pfaffian constraint
(never violated), its step against the closed form and the KKT conditions, the manoeuvre scenario,
and the slip of the IK that ignores the constraint."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import qprr
from qprr.actuation.lexicographic import Lexicographic
from qprr.errors import InputError, LimitError, NonFiniteError, UnknownNameError
from qprr.wheeled.manipulation import (
    IKStatus,
    MobileIKOptions,
    MobileManipulator,
    car_scenario,
    lookahead_steering,
    qprr_arm,
    solve_ik,
    step_problem,
    step_solver,
    three_r_arm,
)
from qprr.wheeled.robots import Car, Unicycle
from tests.test_optim import assert_kkt

# Every step lies in the kernel of E = [A^T, 0] by construction (null-space elimination): its residual
# E dz is rounding, |E| |dz| eps with |E| ~ 2 and |dz| <= 0.2 (trust region): 1e-14 leaves a factor ~100.
ROUNDING = 1e-14


@pytest.fixture(scope="module")
def scenarios():
    return {arm: car_scenario(arm) for arm in ("qprr", "3r")}


@pytest.fixture(scope="module")
def solved(scenarios):
    return {
        (arm, respect): solve_ik(sc.robot, sc.target, sc.z0, {"respect_constraint": respect})
        for arm, sc in scenarios.items()
        for respect in (True, False)
    }


def test_combined_model_is_chassis_then_mount_then_arm(scenarios):
    """EE placement of the appended model = planar chassis pose * mount * the arm's own FK."""
    rng = np.random.default_rng(0)
    for arm_name, make in (("qprr", qprr_arm), ("3r", three_r_arm)):
        mm = scenarios[arm_name].robot
        arm = make()
        adata = arm.createData()
        for _ in range(5):
            z = mm.neutral(rng.uniform(-2, 2, 3))
            z[3] = rng.uniform(-0.5, 0.5)
            z[4:] = rng.uniform(arm.lowerPositionLimit, arm.upperPositionLimit)
            pin.framesForwardKinematics(arm, adata, z[4:])
            chassis = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, z[2]), np.array([z[0], z[1], 0.0]))
            expect = chassis * mm.mount * adata.oMf[arm.getFrameId("end_effector")]
            assert np.allclose(mm.ee_position(z), expect.translation, atol=1e-14)


def test_ee_jacobian_against_finite_differences(scenarios):
    mm = scenarios["3r"].robot
    z = np.array([0.3, -0.2, 0.7, 0.1, 0.4, -0.3, 1.1])
    J = mm.ee_jacobian(z)
    h = 1e-6
    for i in range(mm.nz):
        e = np.zeros(mm.nz)
        e[i] = h
        fd = (mm.ee_position(z + e) - mm.ee_position(z - e)) / (2 * h)
        assert np.allclose(J[:, i], fd, atol=1e-8)
    assert np.allclose(J[:, 3], 0.0)  # the steering angle does not move the end effector


def test_the_target_needs_a_manoeuvre(scenarios):
    """The Q-PRR arm reaches only the chassis's vertical x-z plane (y_R = 0); the 3R arm's reach from its
    shoulder is l2 + l3 = 0.65 m: from the start pose, or driving straight ahead, neither reaches the target
    1.2 m to the side."""
    rng = np.random.default_rng(1)
    mm = scenarios["qprr"].robot
    for _ in range(20):
        z = mm.neutral()
        z[4:] = rng.uniform(mm.lower[4:], mm.upper[4:])
        z[0] = rng.uniform(-3, 3)  # straight drive along x
        assert abs(mm.ee_position(z)[1]) < 1e-14
    sc = scenarios["3r"]
    shoulder = np.array([0.6, 0.0, 0.3 + 0.25])
    assert np.linalg.norm(sc.target[1:] - shoulder[1:]) > 0.35 + 0.3  # lateral + height alone exceed the reach


@pytest.mark.parametrize("arm", ["qprr", "3r"])
def test_ik_under_the_pfaffian_constraint_reaches_the_target_by_driving_and_turning(solved, scenarios, arm):
    r = solved[(arm, True)]
    sc = scenarios[arm]
    assert r.success and r.status is IKStatus.CONVERGED
    assert np.linalg.norm(sc.robot.ee_position(r.z) - sc.target) < 1e-6
    assert r.within_limits
    assert np.max(r.qp_residual) <= ROUNDING  # exact by construction: every step lies in ker A^T
    assert np.max(r.applied_residual) < 1e-14 and r.slip < 1e-13  # the applied motion is B u: round-off
    P = r.path
    heading = np.array([np.cos(P[:-1, 2]), np.sin(P[:-1, 2])])
    forward = np.einsum("ij,ji->i", np.diff(P[:, 0:2], axis=0), heading)
    assert forward.sum() > 0.5  # drove forwards
    assert P[-1, 2] - P[0, 2] > 0.5  # and turned left
    # every base step is the exact flow of the recorded admissible input (replayed)
    base = sc.robot.base
    for k in range(len(P) - 1):
        assert np.allclose(base.flow(P[k, 0:4], r.base_inputs[k], 1.0), P[k + 1, 0:4], atol=1e-15, rtol=0)


@pytest.mark.parametrize("arm", ["qprr", "3r"])
def test_ik_ignoring_the_constraint_slides_sideways(solved, arm):
    """Without the equality the base moves straight at the target: it converges, but its wheels skid."""
    r = solved[(arm, False)]
    assert r.success
    assert r.slip > 0.5  # metres of sideways skid of the constrained wheels
    assert np.max(r.applied_residual) > 0.05
    assert r.slip > 1e12 * solved[(arm, True)].slip


@settings(max_examples=20, deadline=None)
@given(
    pose=st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-math.pi, math.pi)),
    psi=st.floats(-0.6, 0.6),
    arm=st.tuples(*(st.floats(-1.0, 1.0),) * 3),
    target=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(0.2, 1.0)),
)
# found by hypothesis: near-zero projected bound rows (1e-11) at a joint limit made the exact fallback cycle
@example(pose=(-0.5, 1.0, -1.0), psi=0.0, arm=(-0.125, 1.0, 1e-10), target=(0.0, 0.0, 1.0))
def test_ik_never_violates_the_pfaffian_constraint(pose, psi, arm, target):
    sc = _SC3R
    mm = sc.robot
    z0 = mm.neutral(pose)
    z0[3] = psi
    z0[4:] = mm.lower[4:] + (np.array(arm) + 1.0) / 2.0 * (mm.upper[4:] - mm.lower[4:])
    r = solve_ik(mm, target, z0, {"max_iter": 15})
    assert r.status in (IKStatus.CONVERGED, IKStatus.MAX_ITERATIONS, IKStatus.STALLED)
    assert np.max(r.qp_residual, initial=0.0) <= ROUNDING
    assert np.max(r.applied_residual, initial=0.0) < 1e-13
    assert r.slip < 1e-12
    opts = MobileIKOptions()
    for z in r.path:
        assert mm.within_limits(z, tol=10 * opts.eps_abs)  # ProxQP meets bounds to eps_abs (exact when polished)
    # the trust region: steering and arm joints move by dz itself (the flow of a constant steering rate, q + v)
    d = np.abs(np.diff(r.path, axis=0))
    assert np.all(d[:, 3] <= opts.step_steer + 10 * opts.eps_abs)
    assert np.all(d[:, 4:] <= opts.step_arm + 10 * opts.eps_abs)


_SC3R = car_scenario("3r")


def test_unicycle_base_and_user_arm():
    """Any fixed-base arm on any base: a 3R arm on the unicycle (rotation in place available)."""
    mm = MobileManipulator(Unicycle(), three_r_arm(), "end_effector", pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.2])))
    r = solve_ik(mm, [1.5, 1.0, 0.6], mm.neutral())
    assert r.success and r.slip < 1e-13 and r.within_limits


def test_unicycle_step_is_the_damped_least_squares_step_on_the_kernel():
    """With the bounds inactive, the step of the one-level IK on a unicycle is the closed form of the damped
    least squares restricted to ker A^T: dz = N M^T (M M^T + reg I)^-1 e, M = J N, N an orthonormal basis
    of ker E (E = [A^T, 0]).  Bounds inactive: a target 3 cm away and a wide trust region."""
    mm = MobileManipulator(Unicycle(), three_r_arm(), "end_effector", pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.2])))
    rng = np.random.default_rng(4)
    opts = MobileIKOptions(step_xy=10.0, step_theta=10.0, step_arm=10.0)
    solver = step_solver(mm, opts)
    for _ in range(10):
        z = mm.neutral(rng.uniform([-2, -2, -np.pi], [2, 2, np.pi]))
        z[3:] = rng.uniform(0.5 * mm.lower[3:], 0.5 * mm.upper[3:])
        target = mm.ee_position(z) + rng.normal(size=3) * 0.03 / math.sqrt(3)
        prob = step_problem(mm, z, target, opts)
        assert len(prob.levels) == 1 and prob.equality.shape == (1, 6)
        dz = solver.solve(prob.levels, prob.lower, prob.upper, equality=prob.equality).x
        J, e = prob.levels[0]
        N = np.linalg.svd(prob.equality)[2][1:].T
        M = J @ N
        ref = N @ M.T @ np.linalg.solve(M @ M.T + opts.regularization * np.eye(3), e)
        assert np.all(ref > prob.lower + 1e-3) and np.all(ref < prob.upper - 1e-3)  # the bounds are inactive
        assert np.allclose(dz, ref, atol=1e-13, rtol=0)  # exact (polished), not to ProxQP's eps_abs
        assert np.abs(prob.equality @ dz).max() <= ROUNDING


@pytest.mark.parametrize("arm", ["qprr", "3r"])
def test_car_step_keeps_the_end_effector_optimum_and_the_pfaffian_constraint(scenarios, arm):
    """The car's two levels at random configurations (steering and arm joints often at a limit, default trust
    region, so bounds are active): level 1 (end effector) is optimal (KKT of its QP on ker E), the steering
    level 2 does not cost it anything (||J dz - e|| unchanged to rounding) and is optimal (KKT of its QP in the
    directions level 1 leaves free), E dz = 0 to rounding, bounds held."""
    mm = scenarios[arm].robot
    opts = MobileIKOptions()
    solver = step_solver(mm, opts)
    rng = np.random.default_rng(5)
    moved = 0
    for k in range(16):
        z = mm.neutral(rng.uniform([-2, -2, -np.pi], [2, 2, np.pi]))
        z[3:] = rng.uniform(mm.lower[3:], mm.upper[3:])
        for j in np.flatnonzero(rng.random(mm.nz - 3) < 0.3) + 3:
            z[j] = mm.lower[j] if rng.random() < 0.5 else mm.upper[j]
        target = rng.uniform([-3, -3, 0.2], [3, 3, 1.0])
        if k == 15 and arm == "qprr":  # ProxQP 0.8 stops at its iteration limit on level 2 (2 free directions, 5 bounds,
            # two of them rows of rounding size active at 0): the engine's exact fallback solves it
            z, target = np.array(_DEGENERATE_Z), np.array(_DEGENERATE_TARGET)
        prob = step_problem(mm, z, target, opts)
        (J, e), (Js, es) = prob.levels
        E = prob.equality
        res = solver.solve(prob.levels, prob.lower, prob.upper, equality=prob.equality)
        dz, dz1 = res.x, res.x_levels[0]
        scale = 1.0 + np.linalg.norm(e)
        assert abs(np.linalg.norm(J @ dz - e) - np.linalg.norm(J @ dz1 - e)) <= 1e-12 * scale
        assert np.abs(E @ dz).max() <= ROUNDING and np.abs(E @ dz1).max() <= ROUNDING
        assert np.all(dz >= prob.lower - 10 * opts.eps_abs) and np.all(dz <= prob.upper + 10 * opts.eps_abs)
        # level 1 in the free directions w (dz = N w): min ||M w - e||^2 + reg ||w||^2 s.t. lo <= N w <= up
        N = np.linalg.svd(E)[2][np.linalg.matrix_rank(E) :].T
        M = J @ N
        H = 2 * (M.T @ M + opts.regularization * np.eye(N.shape[1]))
        assert_kkt(H, -2 * M.T @ e, N, prob.lower, prob.upper, N.T @ dz1)
        # level 2 (steering angle) in the directions level 1 leaves free, dz = dz1 + Z2 w with Z2 = N ker(M):
        # min ||Js Z2 w - (es - Js dz1)||^2 + reg ||w||^2 s.t. lo - dz1 <= Z2 w <= up - dz1
        s, Vt = np.linalg.svd(M)[1:]
        Z2 = N @ Vt[int(np.count_nonzero(s > opts.rank_tol)) :].T
        K = Js @ Z2
        H2 = 2 * (K.T @ K + opts.regularization * np.eye(Z2.shape[1]))
        assert_kkt(H2, -2 * K.T @ (es - Js @ dz1), Z2, prob.lower - dz1, prob.upper - dz1, Z2.T @ (dz - dz1))
        assert np.allclose(Z2 @ (Z2.T @ (dz - dz1)), dz - dz1, atol=1e-14, rtol=0)  # level 2 moved only there
        moved += abs(dz[3] - dz1[3]) > 1e-6
    assert moved > 0  # the steering level did act on some of these steps


# a step of the benchmark (seed 0, problem 3, iteration 70) where ProxQP stalls on level 2
_DEGENERATE_Z = [
    -0.6162247543402657,
    0.9670442650284181,
    2.910775760511703,
    -9.970059759722982e-08,
    0.040000000000000424,
    1.3457760092993778,
    -0.005604897606805326,
]
_DEGENERATE_TARGET = [-2.495907938505691, 1.995864885920387, 0.8296786459909467]


def test_exact_fallback_follows_the_same_path(scenarios, solved):
    """With one ProxQP iteration per QP every level falls back on the primal active-set method: an independent
    exact solver of the same strictly convex QPs, so the IK follows the same path as with ProxQP + KKT polish
    (to rounding, amplified over ~50 iterations of the nonlinear map: 3e-11 m observed)."""
    sc = scenarios["qprr"]
    a = solved[("qprr", True)]
    b = solve_ik(sc.robot, sc.target, sc.z0, {"max_qp_iter": 1})
    assert a.success and b.success and a.iterations == b.iterations
    assert np.abs(a.path - b.path).max() <= 1e-9


def test_lookahead_steering_checks_its_solver(scenarios):
    sc = scenarios["3r"]
    mm, z = sc.robot, sc.z0
    prob = step_problem(mm, z, sc.target)
    J, e = prob.levels[0]
    psi = lookahead_steering(mm, z, J, e, prob.lower, prob.upper)
    assert abs(psi) <= mm.upper[3] and np.isclose(psi - z[3], prob.levels[1][1][0], atol=0)
    with pytest.raises(InputError, match="Lexicographic over 4 variables"):
        lookahead_steering(mm, z, J, e, prob.lower, prob.upper, solver=Lexicographic(3))


def test_solver_failure_is_reported_not_hidden(scenarios):
    """One ProxQP iteration per QP, without the exact fallback, cannot solve a level: the run stops with status
    solver_error and the engine's message, having applied no step."""
    sc = scenarios["qprr"]
    r = solve_ik(sc.robot, sc.target, sc.z0, {"max_qp_iter": 1, "exact_fallback": False})
    assert r.status is IKStatus.SOLVER_ERROR and not r.success
    assert "ProxQP did not solve level" in r.reason and "MAX_ITER" in r.reason
    assert r.iterations == 0 and np.array_equal(r.z, sc.z0) and r.path.shape == (1, sc.z0.size)


def test_mobile_manipulator_input_errors(scenarios):
    arm = qprr_arm()
    n_frames = arm.nframes
    with pytest.raises(UnknownNameError, match="end_effector"):
        MobileManipulator(Car(), arm, "gripper")
    MobileManipulator(Car(), arm, "end_effector")
    assert arm.nframes == n_frames and arm.njoints == 4  # the user's model is not modified
    ff = qprr.load("q-prr").model  # a free-flyer model
    with pytest.raises(InputError, match="fixed-base"):
        MobileManipulator(Car(), ff, "end_effector")
    sc = scenarios["qprr"]
    z = sc.z0.copy()
    z[3] = 1.0
    with pytest.raises(LimitError):
        solve_ik(sc.robot, sc.target, z)
    with pytest.raises(UnknownNameError, match="max_iters"):
        solve_ik(sc.robot, sc.target, sc.z0, {"max_iters": 3})
    with pytest.raises(UnknownNameError, match="'elimination'.*valid:.*'respect_constraint'.*'rank_tol'"):
        solve_ik(sc.robot, sc.target, sc.z0, {"elimination": "nullspace"})  # one form now (qprr.actuation.lexicographic's null space)
    with pytest.raises(NonFiniteError):
        solve_ik(sc.robot, [0.0, float("nan"), 0.0], sc.z0)
    with pytest.raises(InputError, match="step_xy"):
        MobileIKOptions(step_xy=0.0)
