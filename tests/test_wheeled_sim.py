"""Exact flows and simulation: residuals at round-off, the tricycle exercise, singularities."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from qprr.errors import InputError, KinematicSingularityError, NonFiniteError, ShapeError
from qprr.wheeled.robots import ROBOTS, TRICYCLE_CASES, RearTricycle, Unicycle, get_robot, tricycle_exercise
from qprr.wheeled.sim import SimStatus, chord_slip, euler_step, rk4_step, simulate_wheeled


def _sample(model, rng):
    q = rng.uniform(-1.0, 1.0, model.n)
    u = rng.uniform(-1.0, 1.0, model.n_inputs)
    return q, u


@pytest.mark.parametrize("name", list(ROBOTS))
def test_flow_is_exact_semigroup(name):
    """flow(flow(q, u, h1), u, h2) = flow(q, u, h1 + h2): only an exact solution composes like this."""
    model = get_robot(name)
    rng = np.random.default_rng(5)
    for _ in range(4):
        q, u = _sample(model, rng)
        a = model.flow(model.flow(q, u, 0.37), u, 0.52)
        b = model.flow(q, u, 0.89)
        assert np.allclose(a, b, atol=1e-12, rtol=0)


@pytest.mark.parametrize("name", ["fixed-wheel", "unicycle", "tricycle-front", "tricycle-rear", "synchro", "car"])
def test_flow_matches_a_tight_ode_solution(name):
    """Independent reference: DOP853 on q_dot = B(q) u at rtol 1e-13."""
    model = get_robot(name)
    q, u = np.array([0.1, -0.2, 0.3, 0.4, 0.5])[: model.n], np.array([0.7, 0.9])
    sol = solve_ivp(lambda t, x: model.velocity(x, u), (0.0, 0.8), q, rtol=1e-13, atol=1e-14, method="DOP853")
    assert np.allclose(sol.y[:, -1], model.flow(q, u, 0.8), atol=1e-11, rtol=0)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_constraint_residual_along_the_flow_is_round_off(name):
    """A^T(q(t)) q_dot(t) = 0 at every instant of a step, not only at the samples: q_dot from a
    central difference of the exact flow (error ~1e-10), A from the wheels."""
    model = get_robot(name)
    rng = np.random.default_rng(7)
    q, u = _sample(model, rng)
    h = 1e-4
    for tau in (0.05, 0.31, 0.77):
        qd = (model.flow(q, u, tau + h) - model.flow(q, u, tau - h)) / (2 * h)
        A = model.A(model.flow(q, u, tau))
        if A.size:
            assert np.max(np.abs(A.T @ qd)) < 1e-8
        assert np.allclose(qd, model.velocity(model.flow(q, u, tau), u), atol=1e-7)


def test_exact_arcs_do_not_skid_euler_does():
    """Chord of a circular arc lies along the mean heading: lateral slip 0 for the exact unicycle step,
    (v omega h^2)/2 for an Euler step; RK4 keeps the chord direction (symmetric stages) but its length is
    v h (2 + cos(a/2))/3 instead of (2 v / omega) sin(a/2), a = omega h: off by v h a^4 / 2880."""
    m = Unicycle()
    q, u, h = np.array([0.0, 0.0, 0.4]), np.array([1.0, 0.8]), 0.05
    exact, rk4, eul = m.flow(q, u, h), rk4_step(m, q, u, h), euler_step(m, q, u, h)
    assert abs(chord_slip(q, exact)) < 1e-16
    assert abs(chord_slip(q, eul)) == pytest.approx(0.5 * 1.0 * 0.8 * h * h, rel=0.02)
    assert abs(chord_slip(q, rk4)) < 1e-16
    assert np.linalg.norm(rk4 - exact) == pytest.approx(1.0 * h * (0.8 * h) ** 4 / 2880, rel=0.01)


def test_tricycle_exercise_case_b_is_a_straight_line():
    """u1 = 1 m/s, u2 = 0 from q0 = [0, 0, pi/4, 0]: 30 m along the 45 degree line (both drives)."""
    for drive in ("rear", "front"):
        r = tricycle_exercise("b", drive, dt=0.5)
        assert r.status is SimStatus.OK
        assert r.q[-1] == pytest.approx([30 / math.sqrt(2), 30 / math.sqrt(2), math.pi / 4, 0.0], abs=1e-12)


def test_tricycle_exercise_case_c_turns_the_wheel_in_place():
    """u1 = 0, u2 = pi/6: the robot stays, psi(30 s) = 5 pi, even through psi = pi/2 (u1 = 0)."""
    for drive in ("rear", "front"):
        r = tricycle_exercise("c", drive, dt=0.25)
        assert r.status is SimStatus.OK
        assert r.q[-1] == pytest.approx([0.0, 0.0, math.pi / 4, 5 * math.pi], abs=1e-12)


def test_tricycle_exercise_case_a_front_driven_heading_closed_form_and_dt_independence():
    """Front-driven, u = (1, pi/6): psi = u2 t, theta = pi/4 + u1/(D u2) (1 - cos(u2 t)) along the whole run;
    an exact flow gives the same end state for any step."""
    u1, u2 = TRICYCLE_CASES["a"]
    fine = tricycle_exercise("a", "front", dt=0.05)
    th = math.pi / 4 + u1 / (0.3 * u2) * (1 - np.cos(u2 * fine.t))
    assert np.max(np.abs(fine.q[:, 2] - th)) < 1e-10
    assert np.max(np.abs(fine.q[:, 3] - u2 * fine.t)) < 1e-12
    coarse = tricycle_exercise("a", "front", dt=1.5)
    assert np.allclose(coarse.q[-1], fine.q[-1], atol=1e-9)
    assert np.max(fine.residual) < 1e-14


def test_tricycle_exercise_case_a_rear_driven_stops_at_the_singularity():
    """Exercise point 2: the rear-driven model is not valid everywhere: psi reaches pi/2 at t = 3 s."""
    r = tricycle_exercise("a", "rear", dt=0.01)
    assert r.status is SimStatus.SINGULAR
    assert 2.99 - 1e-9 <= r.t[-1] < 3.0
    assert "cos psi = 0" in r.reason
    m = RearTricycle(D=0.3)
    with pytest.raises(KinematicSingularityError, match="psi"):
        m.B([0.0, 0.0, 0.0, math.pi / 2])
    # at psi = pi/2 the constraints still leave a 2-D kernel: rotation about the rear axle and steering
    A = m.A([0.0, 0.0, 0.0, math.pi / 2])
    assert np.allclose(A.T @ [0.0, 0.0, 1.0, 0.0], 0.0) and np.allclose(A.T @ [0.0, 0.0, 0.0, 1.0], 0.0)


def test_rear_and_front_drive_differ_only_by_the_input_scale():
    """Same A; u1_rear = u1_front cos psi (rear-axle speed = front-wheel speed x cos psi)."""
    q = np.array([0.3, -0.1, 0.7, 0.4])
    f, r = get_robot("tricycle-front"), get_robot("tricycle-rear")
    assert np.allclose(f.A(q), r.A(q))
    assert np.allclose(f.velocity(q, [1.0, 0.2]), r.velocity(q, [math.cos(q[3]), 0.2]))


def test_simulate_input_errors():
    m = Unicycle()
    with pytest.raises(ShapeError, match="u of 'unicycle'"):
        simulate_wheeled(m, [0, 0, 0], [1.0, 2.0, 3.0], 1.0, 0.1)
    with pytest.raises(InputError, match="whole number"):
        simulate_wheeled(m, [0, 0, 0], [1.0, 0.0], 1.05, 0.1)
    with pytest.raises(InputError, match="dt"):
        simulate_wheeled(m, [0, 0, 0], [1.0, 0.0], 1.0, 0.0)
    with pytest.raises(NonFiniteError):
        simulate_wheeled(m, [0, float("nan"), 0], [1.0, 0.0], 1.0, 0.1)
    with pytest.raises(InputError, match="shape"):
        simulate_wheeled(m, [0, 0, 0], np.zeros((3, 2)), 1.0, 0.1)
    ok = simulate_wheeled(m, [0, 0, 0], np.tile([1.0, 0.5], (10, 1)), 1.0, 0.1)
    assert ok.q[-1] == pytest.approx(m.flow([0, 0, 0], [1.0, 0.5], 1.0))
