"""Mobile manipulation: the combined model, the task-priority IK under the Pfaffian constraint
(never violated), the manoeuvre scenario, and the slip of the IK that ignores the constraint."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr
from qprr.errors import InputError, LimitError, NonFiniteError, UnknownNameError
from qprr.wheeled.manipulation import (
    IKStatus,
    MobileIKOptions,
    MobileManipulator,
    _Lexicographic,
    car_scenario,
    qprr_arm,
    solve_ik,
    three_r_arm,
)
from qprr.wheeled.robots import Car, Unicycle


@pytest.fixture(scope="module")
def scenarios():
    return {arm: car_scenario(arm) for arm in ("qprr", "3r")}


@pytest.fixture(scope="module")
def solved(scenarios):
    return {(arm, respect): solve_ik(sc.robot, sc.target, sc.z0, {"respect_constraint": respect})
            for arm, sc in scenarios.items() for respect in (True, False)}


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
    assert np.max(r.qp_residual) <= 10 * MobileIKOptions().eps_abs  # ProxQP meets the equality to its tolerance
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
@given(pose=st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-math.pi, math.pi)),
       psi=st.floats(-0.6, 0.6), arm=st.tuples(*(st.floats(-1.0, 1.0),) * 3),
       target=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(0.2, 1.0)))
def test_ik_never_violates_the_pfaffian_constraint(pose, psi, arm, target):
    sc = _SC3R
    mm = sc.robot
    z0 = mm.neutral(pose)
    z0[3] = psi
    z0[4:] = mm.lower[4:] + (np.array(arm) + 1.0) / 2.0 * (mm.upper[4:] - mm.lower[4:])
    r = solve_ik(mm, target, z0, {"max_iter": 15})
    assert r.status in (IKStatus.CONVERGED, IKStatus.MAX_ITERATIONS, IKStatus.STALLED)
    assert np.max(r.qp_residual, initial=0.0) <= 10 * MobileIKOptions().eps_abs
    assert np.max(r.applied_residual, initial=0.0) < 1e-13
    assert r.slip < 1e-12
    for z in r.path:
        assert mm.within_limits(z, tol=1e-8)


_SC3R = car_scenario("3r")


def test_unicycle_base_and_user_arm():
    """Any fixed-base arm on any base: a 3R arm on the unicycle (rotation in place available)."""
    mm = MobileManipulator(Unicycle(), three_r_arm(), "end_effector", pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.2])))
    r = solve_ik(mm, [1.5, 1.0, 0.6], mm.neutral())
    assert r.success and r.slip < 1e-13 and r.within_limits


def test_lexicographic_levels_match_the_closed_form():
    """Levels (J, e) then (I, 0) under E x = 0, bounds inactive: the damped least-squares minimiser on
    ker E, x = N M^T (M M^T + reg I)^-1 e with M = J N, N an orthonormal basis of ker E (it is already the
    smallest x with its J x, so the second level keeps it)."""
    rng = np.random.default_rng(2)
    n = 6
    opts = MobileIKOptions()
    J, e, E = rng.normal(size=(3, n)), rng.normal(size=3), rng.normal(size=(2, n))
    for elim in ("equality", "nullspace"):
        x = _Lexicographic(n, replace(opts, elimination=elim)).solve([(J, e), (np.eye(n), np.zeros(n))], E,
                                                                     -np.full(n, 1e3), np.full(n, 1e3))
        N = np.linalg.svd(E)[2][2:].T
        M = J @ N
        ref = N @ M.T @ np.linalg.solve(M @ M.T + opts.regularization * np.eye(3), e)
        assert np.allclose(x, ref, atol=10 * opts.eps_abs / opts.regularization)
        assert np.allclose(E @ x, 0.0, atol=10 * opts.eps_abs)


@pytest.mark.parametrize("active", [False, True])
def test_equality_and_nullspace_forms_give_the_same_step(active):
    """Both ways of keeping the constraint and the earlier optima solve the same lexicographic problem
    (to eps_abs / regularization along the direction only the damping fixes)."""
    rng = np.random.default_rng(3)
    n = 7
    J1, e1, J2, e2, E = rng.normal(size=(3, n)), rng.normal(size=3), rng.normal(size=(1, n)), rng.normal(size=1), rng.normal(size=(2, n))
    bound = 0.05 if active else 1e3
    steps = [_Lexicographic(n, MobileIKOptions(elimination=f)).solve([(J1, e1), (J2, e2)], E, -np.full(n, bound), np.full(n, bound))
             for f in ("equality", "nullspace")]
    opts = MobileIKOptions()
    assert np.allclose(steps[0], steps[1], atol=10 * opts.eps_abs / opts.regularization)
    assert np.allclose(E @ steps[1], 0.0, atol=1e-14) and np.allclose(E @ steps[0], 0.0, atol=1e-8)
    if active:
        assert np.isclose(np.max(np.abs(steps[0])), bound, atol=1e-8)  # some bound is active


def test_solver_failure_is_reported_not_hidden(scenarios):
    sc = scenarios["qprr"]
    r = solve_ik(sc.robot, sc.target, sc.z0, {"max_qp_iter": 1})
    assert r.status is IKStatus.SOLVER_ERROR and not r.success and "ProxQP" in r.reason


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
    with pytest.raises(NonFiniteError):
        solve_ik(sc.robot, [0.0, float("nan"), 0.0], sc.z0)
    with pytest.raises(InputError, match="step_xy"):
        MobileIKOptions(step_xy=0.0)
