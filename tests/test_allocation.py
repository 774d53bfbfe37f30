"""Control allocation: bounds, priorities, optimality against an independent solver, proxsuite traps."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qprr.actuation import Allocator
from qprr.errors import InputError, ShapeError


def allocation_inverse(robot):
    """Omega_z^-1 (4x4), rotor thrusts of [f_bz, tau_x, tau_y, tau_z]: the allocator's exact path (Thesis (A.1) corrected)."""
    return Allocator(robot).Omega_P_inv


def rotor_matrix(robot):
    return robot.rotor_matrix


wrench = st.tuples(st.floats(-20, 120), st.floats(-8, 8), st.floats(-8, 8), st.floats(-3, 3))


@pytest.fixture(scope="module")
def alloc(robot):
    return Allocator(robot)


def _tau(w, arm=(0.0, 0.0, 0.0)):
    return np.r_[0.0, 0.0, w, arm]


def test_inside_bounds_is_the_exact_inverse(robot, alloc):
    """Fast path: when Omega_z^-1 w is inside the bounds it is returned unchanged (all priorities met)."""
    w = np.array([40.0, 0.3, -0.2, 0.05])
    res = alloc.allocate(_tau(w))
    np.testing.assert_allclose(res.f[0:4], allocation_inverse(robot) @ w, atol=1e-12)
    np.testing.assert_allclose(res.residual[2:6], 0.0, atol=1e-12)
    assert res.status == "exact" and not res.rotor_saturated


@settings(max_examples=150, deadline=None)
@given(w=wrench)
def test_thrusts_never_leave_bounds_and_saturation_is_reported(robot, w):
    alloc = Allocator(robot)
    res = alloc.allocate(_tau(np.array(w)))
    f = res.f[0:4]
    assert np.all(f >= alloc.f_min) and np.all(f <= alloc.f_max)
    free = allocation_inverse(robot) @ np.array(w)
    inside = np.all(free >= 0.0) and np.all(free <= alloc.f_max)
    assert res.rotor_saturated == (not inside)
    if not inside:
        assert "rotor thrust bounds" in res.reason
    # the achieved wrench is N f
    np.testing.assert_allclose(res.tau_achieved[0:6], rotor_matrix(robot) @ f, atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(w=wrench)
def test_level_one_is_optimal_against_bounded_least_squares(robot, w):
    """Level 1 (thrust, roll, pitch) matches scipy's bounded least squares (an independent solver)."""
    opt = pytest.importorskip("scipy.optimize")
    alloc = Allocator(robot)
    w = np.array(w)
    f = alloc.allocate(_tau(w)).f[0:4]
    W = np.diag([1.0, 10 / robot.params.arm_length, 10 / robot.params.arm_length])
    A1 = rotor_matrix(robot)[2:5]
    ref = opt.lsq_linear(W @ A1, W @ w[0:3], bounds=(0.0, alloc.f_max), method="bvls", tol=1e-14)
    ours = np.sum((W @ (A1 @ f - w[0:3])) ** 2)
    best = np.sum((W @ (A1 @ ref.x - w[0:3])) ** 2)
    assert ours <= best + 1e-8 * (1.0 + best)


@settings(max_examples=100, deadline=None)
@given(w=wrench)
def test_level_two_is_optimal_for_yaw_given_level_one(robot, w):
    """No in-bounds thrust with the same (f_bz, tau_x, tau_y) gets closer to the yaw demand (grid search)."""
    alloc = Allocator(robot)
    w = np.array(w)
    f = alloc.allocate(_tau(w)).f[0:4]
    Oz = rotor_matrix(robot)[2:6]
    n = np.linalg.svd(Oz[0:3])[2][-1]
    lam = np.linspace(-40, 40, 80001)
    cand = f[None, :] + lam[:, None] * n[None, :]
    ok = np.all((cand >= -1e-9) & (cand <= alloc.f_max + 1e-9), axis=1)
    yaw_err = np.abs(cand[ok] @ Oz[3] - w[3])
    assert abs(Oz[3] @ f - w[3]) <= yaw_err.min() + 1e-6


def test_priorities_thrust_roll_pitch_before_yaw(robot):
    """An infeasible yaw demand is cut; thrust, roll and pitch are still met exactly (PX4-like)."""
    alloc = Allocator(robot)
    w = np.array([30.0, 0.2, -0.3, 2.0])  # 2 N m of yaw needs 20 N of differential thrust
    res = alloc.allocate(_tau(w))
    np.testing.assert_allclose(res.tau_achieved[2:5], w[0:3], atol=1e-8)
    assert abs(res.residual[5]) > 0.5
    assert res.rotor_saturated


def test_warm_start_after_bound_change_is_not_fooled(robot):
    """proxsuite trap: a warm start after the active set changes can return the previous point as SOLVED.

    Sequence found while developing (level 2 then): the third answer must equal a fresh allocator's.
    """
    alloc = Allocator(robot)
    ws = [np.array([100.0, 0, 0, 0]), np.array([30.0, 2.0, 3.0, 1.0]), np.array([30.0, 0.0, 0.0, 1.0])]
    for w in ws:
        f_seq = alloc.allocate(_tau(w)).f
    f_fresh = Allocator(robot).allocate(_tau(ws[-1])).f
    np.testing.assert_allclose(f_seq, f_fresh, atol=1e-7)
    np.testing.assert_allclose(f_fresh[0:4], [15.0, 0.0, 15.0, 0.0], atol=1e-7)  # thrust 30 kept, yaw 0.75 of 1


def test_large_demands_are_allocated(robot):
    """Demands far beyond the machine (a diverging controller) still get a bounded answer."""
    alloc = Allocator(robot)
    for w in ([27.6, -0.31, -741.1, 2.39], [23.2, -0.03, 630.7, -2.0], [-191.0, -41.4, 74.6, 68.8]):
        res = alloc.allocate(_tau(np.array(w)))
        assert np.all(res.f[0:4] >= 0) and np.all(res.f[0:4] <= alloc.f_max)


def test_arm_efforts_are_clipped_and_reported(robot):
    alloc = Allocator(robot)
    lim = robot.params.effort_limits
    res = alloc.allocate(_tau([34.5, 0, 0, 0], arm=(2 * lim[0], -0.5 * lim[1], -3 * lim[2])))
    np.testing.assert_allclose(res.f[4:7], [lim[0], -0.5 * lim[1], -lim[2]])
    assert res.arm_saturated and res.status == "saturated" and "arm effort" in res.reason


def test_lateral_body_force_is_reported_unallocated(robot):
    alloc = Allocator(robot)
    res = alloc.allocate(np.r_[1.0, -2.0, 34.5, 0, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(res.residual[0:2], [1.0, -2.0])
    assert "lateral" in res.reason


def test_bad_input(robot):
    alloc = Allocator(robot)
    with pytest.raises(ShapeError):
        alloc.allocate(np.zeros(6))
    with pytest.raises(InputError):
        Allocator(robot, thrust_bounds=(5.0, 1.0))
    with pytest.raises(InputError):
        Allocator(robot, weight_force=-1.0)
