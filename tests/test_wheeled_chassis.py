"""Robots as wheels on a chassis: the lecture's matrices, the (delta_m, delta_s) table by computation,
the ICR, the Ackermann relation, and the Pfaffian matrix against the printed tricycle form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from qprr.errors import InputError, ShapeError
from qprr.wheeled.chassis import ICRStatus, MobilityStatus, WheeledRobot, admissible_types, kernel, rank
from qprr.wheeled.robots import (
    ROBOTS,
    TYPE_EXAMPLES,
    Car,
    FrontTricycle,
    RearTricycle,
    Unicycle,
    _bicycle_lecture,
    bicycle_exercise,
    differential_drive,
    differential_drive_inverse,
    get_robot,
    icr_offset,
)
from qprr.wheeled.wheels import FixedWheel


def test_the_five_admissible_types_follow_from_the_lecture_conditions():
    """Lecture: table delta_m = 3 2 2 1 1, delta_s = 0 0 1 1 2, enumerated from a), b), c)."""
    assert admissible_types() == [(3, 0), (2, 0), (2, 1), (1, 1), (1, 2)]


@pytest.mark.parametrize("lecture_type", list(TYPE_EXAMPLES))
def test_three_wheel_robots_have_the_type_the_lecture_gives(lecture_type):
    robot = TYPE_EXAMPLES[lecture_type]
    mob = robot.mobility()
    assert mob.type == lecture_type
    assert mob.status is MobilityStatus.ADMISSIBLE
    assert mob.rank_C1s == mob.delta_s  # independent steering: the lecture's rank C1s
    assert mob.delta_M == sum(lecture_type)


def test_example_1_unicycle_matrices():
    """Lecture Example 1: C1f R^T q_dot = [0 1 0] R^T q_dot (one independent row), J1f = [[1, 0, l], [1, 0, -l]],
    J2 = diag(r, r), delta_m = 2, delta_s = 0, delta_M = 2."""
    u = Unicycle(r=0.05, L=0.15)
    C1f = u.robot.C1f()
    assert np.allclose(C1f, [[0, 1, 0], [0, 1, 0]], atol=1e-15) and rank(C1f) == 1
    assert np.allclose(u.robot.J1()[0:2], [[1, 0, u.L], [1, 0, -u.L]], atol=1e-15)
    assert np.allclose(u.robot.J2()[0:2, 0:2], np.diag([u.r, u.r]))
    mob = u.robot.mobility()
    assert (mob.delta_m, mob.delta_s, mob.delta_M) == (2, 0, 2)


def test_example_2_fixed_bicycle_and_the_steerable_bicycle_exercise():
    """Lecture Example 2: C1f = [[0, 1, l], [0, 1, -l]], J1f = [[1, 0, 0], [1, 0, 0]], delta_m = 1, delta_s = 0,
    delta_M = 1 (not admissible); Exercise: front-steered delta_m = delta_s = 1; rear-steered the same."""
    ell = 0.5
    fixed = _bicycle_lecture("fixed", "fixed", ell)
    assert np.allclose(fixed.C1f(), [[0, 1, ell], [0, 1, -ell]], atol=1e-15)
    assert np.allclose(fixed.J1(), [[1, 0, 0], [1, 0, 0]], atol=1e-15)
    ex = bicycle_exercise(ell)
    assert (ex.fixed.delta_m, ex.fixed.delta_s, ex.fixed.delta_M) == (1, 0, 1)
    assert ex.fixed.status is MobilityStatus.NOT_ADMISSIBLE
    assert (ex.front_steered.delta_m, ex.front_steered.delta_s) == (1, 1)
    assert (ex.rear_steered.delta_m, ex.rear_steered.delta_s, ex.rear_steered.delta_M) == (1, 1, 2)


def test_pfaffian_of_the_tricycle_is_the_printed_one():
    """Lecture "forme pfaffienne": A^T = [[-sin th, cos th, 0, 0], [-sin(th + psi), cos(th + psi), D cos psi, 0]]."""
    rng = np.random.default_rng(0)
    for model in (FrontTricycle(D=0.3), RearTricycle(D=0.45)):
        for _ in range(5):
            x, y, th, psi = rng.uniform(-3, 3, 4)
            printed = np.array([[-math.sin(th), math.cos(th), 0, 0], [-math.sin(th + psi), math.cos(th + psi), model.D * math.cos(psi), 0]])
            assert np.allclose(model.A([x, y, th, psi]).T, printed, atol=1e-14)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_model_B_spans_the_kernel_of_the_pfaffian(name):
    """Im B(q) = ker A^T(q) (Lecture), B of the named model vs an SVD kernel of the wheels' A."""
    model = get_robot(name)
    rng = np.random.default_rng(1)
    for _ in range(4):
        q = rng.uniform(-1.2, 1.2, model.n)
        A, B = model.A(q), model.B(q)
        N = kernel(A.T, n=model.n) if A.size else np.eye(model.n)
        assert rank(B) == N.shape[1]
        assert np.allclose(N @ (N.T @ B), B, atol=1e-12)  # B inside ker A^T, of the same dimension
        if model.robot is not None and name != "fixed-wheel":
            V = model.robot.velocity_basis(q)
            assert V.shape[1] == N.shape[1]


def test_icr_of_the_differential_drive_is_the_lecture_rho():
    """Lecture: rho = L (phi_d - phi_g) / (phi_d + phi_g) (slide convention), v_d = (rho + L) omega,
    v_g = (rho - L) omega; the ICR set without inputs is the axle line."""
    u = Unicycle(r=0.05, L=0.15)
    line = u.robot.icr()
    assert line.status is ICRStatus.LINE and abs(line.point_R[0]) < 1e-15 and abs(line.direction[0]) < 1e-15
    for pd, pg in ((-9.0, 7.0), (-3.0, 8.0), (2.0, 5.0)):
        v, w = differential_drive(pd, pg, u.r, u.L)
        rho = icr_offset(pd, pg, u.L)
        icr = u.robot.icr(twist=(v, 0.0, w))
        assert icr.status is ICRStatus.UNIQUE
        assert icr.point_R == pytest.approx([0.0, rho], abs=1e-12)
        assert -u.r * pd == pytest.approx((rho + u.L) * w) and u.r * pg == pytest.approx((rho - u.L) * w)


def test_differential_drive_formulas_against_the_wheel_model():
    """The slide's (v, omega) formulas and sign remarks; the chassis model (Example 1 convention) spins the
    right wheel the other way: phi_d(slide) = -phi_d(Example 1)."""
    u = Unicycle()
    v, w = differential_drive(-4.0, 4.0, u.r, u.L)  # phi_d = -phi_g: straight ahead
    assert w == 0.0 and v > 0
    v, w = differential_drive(3.0, 3.0, u.r, u.L)  # phi_d = phi_g: clockwise spin
    assert v == 0.0 and w < 0
    for v, w in ((0.5, 0.3), (-0.2, 1.1)):
        pd, pg = differential_drive_inverse(v, w, u.r, u.L)
        assert differential_drive(pd, pg, u.r, u.L) == pytest.approx((v, w))
        speeds = u.wheel_speeds([0.3, -0.2, 0.7], [v, w])
        assert speeds["right"] == pytest.approx(-pd) and speeds["left"] == pytest.approx(pg)


@pytest.mark.parametrize("psi", [-0.55, -0.2, 0.05, 0.3, 0.6])
def test_ackermann_relation_and_the_virtual_wheel(psi):
    """Lecture: cot psi_o - cot psi_i = 2L/D; cot psi_tr = cot psi_i + L/D = cot psi_o - L/D; a unique ICR on
    the rear axle line, the virtual tricycle's."""
    car = Car(D=0.5, L=0.2)
    left, right = car.front_angles(psi)
    inner, outer = (left, right) if psi > 0 else (right, left)
    cot = lambda a: math.cos(a) / math.sin(a)  # noqa: E731
    sign = math.copysign(1.0, psi)
    assert sign * (cot(outer) - cot(inner)) == pytest.approx(2 * car.L / car.D, rel=1e-12)
    assert sign * (cot(psi) - cot(inner)) == pytest.approx(car.L / car.D, rel=1e-12)
    assert sign * (cot(outer) - cot(psi)) == pytest.approx(car.L / car.D, rel=1e-12)
    icr = car.robot.icr([psi])
    assert icr.status is ICRStatus.UNIQUE
    assert icr.point_R == pytest.approx([0.0, car.D / math.tan(psi)], abs=1e-9)
    assert icr.point_R == pytest.approx(car.virtual.robot.icr([psi]).point_R, abs=1e-9)
    # every wheel axis passes through the ICR
    for w, s in zip(car.robot.steered_wheels, (left, right)):
        axle, _ = w.directions(s)
        d = icr.point_R - w.contact_point(s)
        assert abs(d[0] * axle[1] - d[1] * axle[0]) < 1e-9


def test_car_degrees_count_the_linkage_not_the_two_wheels():
    """The car is type (1, 1) like its virtual tricycle; the literal rank C1s of the two coupled wheels is 2.
    Both front wheels at the same angle (no Ackermann): rank C1* = 3, no motion possible."""
    car = Car()
    mob = car.robot.mobility()
    assert mob.type == (1, 1) and mob.rank_C1s == 2
    assert mob.type == car.virtual.robot.mobility().type
    parallel = WheeledRobot("parallel", car.robot.wheels)
    stuck = parallel.mobility([0.3, 0.3])
    assert stuck.delta_m == 0 and stuck.status is MobilityStatus.IMMOBILE
    assert parallel.icr([0.3, 0.3]).status is ICRStatus.NONE


def test_icr_at_infinity_for_straight_motion_and_anywhere_for_the_omni():
    tri = FrontTricycle()
    assert tri.robot.icr([0.0]).status is ICRStatus.AT_INFINITY
    assert get_robot("omni").robot.icr().status is ICRStatus.ANYWHERE
    with pytest.raises(InputError, match="violates"):
        tri.robot.icr([0.2], twist=(0.0, 1.0, 0.0))  # sideways: not admissible


def test_robot_input_errors():
    with pytest.raises(InputError, match="at least one wheel"):
        WheeledRobot("empty", ())
    with pytest.raises(ShapeError, match="steering"):
        FrontTricycle().robot.mobility([0.1, 0.2])
    with pytest.raises(InputError, match="D"):
        FrontTricycle(D=-1.0)
    with pytest.raises(InputError, match="psi_max"):
        Car(psi_max=2.0)
    assert FixedWheel(0.0, 0.0, 0.0, 0.1).constrains_posture


@pytest.mark.parametrize("extra", ["fixed", "centred"])
def test_no_omnidirectional_robot_with_a_fixed_or_centred_steerable_wheel(extra):
    """Lecture: "il n'est pas possible de réaliser un robot omnidirectionnel avec des roues fixes ou des
    roues centrées orientables": one such wheel gives rank C1* >= 1, delta_m <= 2, at every steering."""
    from qprr.wheeled.chassis import wheel_at
    from qprr.wheeled.robots import Omnidirectional
    from qprr.wheeled.wheels import CentredSteerableWheel

    kind = FixedWheel if extra == "fixed" else CentredSteerableWheel
    robot = WheeledRobot("omni + 1", Omnidirectional().robot.wheels + (wheel_at(kind, 0.1, 0.05, 0.05, name="extra"),))
    for s in np.linspace(-3, 3, 7):
        assert robot.mobility([s] if robot.n_steering else None).delta_m <= 2


def test_mecanum_wheel_speeds_obey_one_relation():
    """Four Swedish 45 deg wheels for three chassis velocities: the wheel speeds satisfy
    phi_FL + phi_FR - phi_RL - phi_RR = 0 whatever the motion (Lecture, "Commandabilité": the four wheels
    must agree exactly for the robot to follow a line)."""
    m = get_robot("mecanum")
    rng = np.random.default_rng(5)
    for _ in range(5):
        s = m.wheel_speeds(rng.normal(size=3), rng.normal(size=3))
        assert s["front left"] + s["front right"] - s["rear left"] - s["rear right"] == pytest.approx(0.0, abs=1e-12)
    W = np.array([list(m.wheel_speeds([0, 0, 0], u).values()) for u in np.eye(3)]).T
    assert rank(W) == 3
