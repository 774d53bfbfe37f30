"""Wheel types: every constraint row is a component of the contact point's velocity (rigid-body
kinematics), the lecture's fixed-wheel derivation, Remark 2, and the Swedish-wheel erratum."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qprr.errors import InputError
from qprr.wheeled.robots import FixedWheelModel
from qprr.wheeled.wheels import CentredSteerableWheel, FixedWheel, OffCentredSteerableWheel, SwedishWheel, WheelKind

ANG = st.floats(-math.pi, math.pi)
RATE = st.floats(-3.0, 3.0)
WHEELS = {
    "fixed": lambda a, b: FixedWheel(a, b, 0.4, 0.1),
    "centred": lambda a, b: CentredSteerableWheel(a, 0.4, 0.1, beta0=b),
    "castor": lambda a, b: OffCentredSteerableWheel(a, 0.4, 0.05, 0.1, beta0=b),
    "swedish": lambda a, b: SwedishWheel(a, b, 0.4, 0.1, gamma=math.pi / 4, r_sw=0.02),
}


@pytest.mark.parametrize("kind", list(WHEELS))
@settings(max_examples=30, deadline=None)
@given(a=ANG, b=ANG, s=ANG, xi=st.tuples(RATE, RATE, RATE), s_dot=RATE, phi_dot=RATE, roller=RATE)
def test_rows_are_components_of_the_contact_point_velocity(kind, a, b, s, xi, s_dot, phi_dot, roller):
    """no-slip row = slip . axle direction, rolling row = slip . rolling direction (Lecture rows)."""
    w = WHEELS[kind](a, b)
    slip = w.slip_velocity(xi, s, s_dot, phi_dot, roller)
    axle, rolling = w.directions(s)
    ns, ro = w.constraints(s)
    assert ns.value(xi, s_dot, phi_dot, roller) == pytest.approx(slip @ axle, abs=1e-13)
    assert ro.value(xi, s_dot, phi_dot, roller) == pytest.approx(slip @ rolling, abs=1e-13)


def test_swedish_no_slip_printed_sign_is_wrong():
    """A roll without slipping (contact velocity 0): the corrected rows hold, the printed no-slip row
    ("- r phi_dot sin gamma") is off by -2 r phi_dot sin gamma.  Lecture: "Roue suédoise"."""
    w = SwedishWheel(alpha=0.3, beta=0.2, ell=0.25, r=0.05, gamma=math.pi / 4, r_sw=0.01)
    xi = np.array([0.4, -0.3, 0.7])
    axle, rolling = w.directions()
    # choose phi_dot and phi_sw_dot that cancel the contact velocity (two equations, two unknowns)
    M = np.column_stack([w.slip_velocity(xi, phi_dot=1.0) - w.slip_velocity(xi), w.slip_velocity(xi, roller_dot=1.0) - w.slip_velocity(xi)])
    phi_dot, roller = np.linalg.solve(M, -w.slip_velocity(xi))
    assert np.allclose(w.slip_velocity(xi, phi_dot=phi_dot, roller_dot=roller), 0.0, atol=1e-14)
    assert w.no_slip().value(xi, 0.0, phi_dot, roller) == pytest.approx(0.0, abs=1e-14)
    assert w.rolling().value(xi, 0.0, phi_dot, roller) == pytest.approx(0.0, abs=1e-14)
    printed = w.no_slip_printed().value(xi, 0.0, phi_dot, roller)
    assert printed == pytest.approx(-2 * w.r * phi_dot * math.sin(w.gamma), rel=1e-12)
    assert abs(printed) > 1e-3


def test_swedish_gamma_zero_is_the_fixed_wheel_rolling_and_gamma_half_pi_is_degenerate():
    """Lecture remark: gamma = 0 ("suédoise 90°") rolls like the fixed wheel, its no-slip row only fixes
    the roller speed; gamma = pi/2 is the degenerate wheel."""
    sw = SwedishWheel(0.7, 0.4, 0.3, 0.05, gamma=0.0)
    fw = FixedWheel(0.7, 0.4, 0.3, 0.05)
    assert np.allclose(sw.rolling().xi, fw.rolling().xi) and sw.rolling().phi_dot == fw.rolling().phi_dot
    assert sw.no_slip().phi_dot == 0.0 and sw.no_slip().roller_dot != 0.0
    with pytest.raises(InputError, match="gamma"):
        SwedishWheel(0.0, 0.0, 0.3, 0.05, gamma=math.pi / 2)


def test_fixed_wheel_constraints_from_the_cross_product():
    """Lecture: v_Q = v_P + omega x PQ = 0 with omega = theta_dot z + phi_dot (x sin th - y cos th),
    PQ = -r z, premultiplied by R(theta): rows (1) and (2) = A^T(q) q_dot of the printed A."""
    model = FixedWheelModel(r=0.1)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qd = rng.normal(size=4), rng.normal(size=4)
        th, r = q[2], model.r
        omega = np.array([qd[3] * math.sin(th), -qd[3] * math.cos(th), qd[2]])
        vQ = np.array([qd[0], qd[1], 0.0]) + np.cross(omega, [0.0, 0.0, -r])
        rows = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]) @ np.array([vQ[1], vQ[0]])
        assert np.allclose(rows, model.A(q).T @ qd, atol=1e-14)


def test_remark_2_alpha_half_pi_gives_the_fixed_wheel_up_to_the_sign_of_phi():
    """Lecture Remark 2: alpha = pi/2, ell = 0, beta = 0: the chassis rows, times R^T(theta), are the
    fixed wheel's (1) exactly and (2) with phi -> -phi."""
    w = FixedWheel(math.pi / 2, 0.0, 0.0, 0.1)
    model = FixedWheelModel(r=0.1)
    rng = np.random.default_rng(4)
    for _ in range(5):
        q, qd = rng.normal(size=4), rng.normal(size=4)
        xi = np.array([[math.cos(q[2]), math.sin(q[2]), 0], [-math.sin(q[2]), math.cos(q[2]), 0], [0, 0, 1]]) @ qd[0:3]
        c1, c2 = model.A(q).T @ qd
        assert w.no_slip().value(xi) == pytest.approx(c1, abs=1e-14)
        assert w.rolling().value(xi, phi_dot=-qd[3]) == pytest.approx(c2, abs=1e-14)


@pytest.mark.parametrize("bad", [dict(r=-0.1), dict(r=float("nan")), dict(ell=-1.0), dict(alpha=float("inf"))])
def test_wheel_rejects_bad_geometry_naming_the_argument(bad):
    args = dict(alpha=0.0, beta=0.0, ell=0.3, r=0.1) | bad
    with pytest.raises(InputError, match=next(iter(bad))):
        FixedWheel(**args)


def test_only_fixed_and_centred_wheels_constrain_the_posture():
    kinds = {k: f(0.1, 0.2) for k, f in WHEELS.items()}
    assert {k for k, w in kinds.items() if w.constrains_posture} == {"fixed", "centred"}
    assert kinds["castor"].kind is WheelKind.OFF_CENTRED_STEERABLE
