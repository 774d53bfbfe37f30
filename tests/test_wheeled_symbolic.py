"""Symbolic checks: A^T B = 0 for every robot, and the Lie-bracket (Frobenius) verdict of each."""

from __future__ import annotations

import math

import numpy as np
import pytest

sp = pytest.importorskip("sympy", reason="sympy is not installed: pip install 'qprr[symbolic]'")

from qprr.wheeled.kinematics import KinematicModel  # noqa: E402
from qprr.wheeled.liebracket import (  # noqa: E402
    Integrability,
    WithWheelAngles,
    commutator_motion,
    frobenius,
    integrable_alone,
    lie_bracket,
)
from qprr.wheeled.robots import ROBOTS, get_robot  # noqa: E402
from qprr.wheeled.sim import se2_flow  # noqa: E402


@pytest.mark.parametrize("name", list(ROBOTS))
def test_A_transpose_B_is_zero_symbolically(name):
    model = get_robot(name)
    q, A, B = model.symbolic()
    assert A.shape == (model.n, A.shape[1]) and B.shape == (model.n, model.n_inputs)
    assert (A.T * B).applyfunc(lambda e: sp.simplify(sp.expand_trig(e))) == sp.zeros(A.shape[1], model.n_inputs)


# (growth of the distribution, number of integrable constraints) expected from theory:
EXPECTED = {
    "fixed-wheel": ((2, 3, 4), 0),  # [b1, b2] turns the heading into a lateral motion, then phi
    "unicycle": ((2, 3), 0),
    "tricycle-front": ((2, 3, 4), 0),
    "tricycle-rear": ((2, 3, 4), 0),
    "car": ((2, 3, 4), 0),
    "bicycle": ((2, 3, 4), 0),
    "omni": ((3,), 0),
    "mecanum": ((3,), 0),
    "synchro": ((2, 3, 3), 1),  # theta_dot = 0 integrates: the chassis heading is not controllable
}


@pytest.mark.parametrize("name", list(ROBOTS))
def test_frobenius_verdict_of_each_robot(name):
    r = frobenius(get_robot(name))
    growth, h = EXPECTED[name]
    assert r.growth == growth and r.n_integrable == h
    assert r.status is {0: Integrability.NONHOLONOMIC if r.k else Integrability.UNCONSTRAINED}.get(h, Integrability.PARTIAL)
    assert not any(alone for _, alone in r.alone)  # no single wheel constraint integrates by itself
    if name == "synchro":
        assert list(r.integrable_forms[0]) == [0, 0, 1, 0]  # d theta


def test_wheel_angle_constraints_that_integrate():
    """Differential drive: theta = r (phi_d - phi_g) / (2L) + c is holonomic (Example 1 rolling rows);
    three Swedish wheels: r sum(phi_i) + 3 l theta = c."""
    u = get_robot("unicycle")
    r = frobenius(WithWheelAngles(u))
    assert r.n_integrable == 1 and r.status is Integrability.PARTIAL
    form = np.array([float(v) for v in r.integrable_forms[0]])
    expect = np.array([0, 0, 2 * u.L / u.r, -1, 1])
    assert np.allclose(form / form[2] * expect[2], expect)
    om = get_robot("omni")
    r = frobenius(WithWheelAngles(om))
    form = np.array([float(v) for v in r.integrable_forms[0]])
    ell, rad = om.robot.wheels[0].ell, om.robot.wheels[0].r
    assert r.n_integrable == 1 and np.allclose(form / form[3], [0, 0, 3 * ell / rad, 1, 1, 1])


class _FixedBicycle(KinematicModel):
    """Lecture Example 2 as a model: q = [x, y, theta], the only motion x_dot_R (delta_m = 1)."""

    name = "fixed bicycle"
    coordinates = ("x", "y", "theta")
    inputs = ("v",)

    def __init__(self):
        from qprr.wheeled.robots import _bicycle_lecture

        self.robot = _bicycle_lecture("fixed", "fixed", 0.5)

    def B(self, q, m=math):
        return sp.Matrix([[m.cos(q[2])], [m.sin(q[2])], [0]]) if m is sp else np.array([[math.cos(q[2])], [math.sin(q[2])], [0.0]])

    def flow(self, q, u, h):
        return se2_flow(q, (u[0], 0.0, 0.0), h)


def test_fixed_bicycle_constraints_are_holonomic():
    """Example 2: delta_M = 1, both no-slip constraints integrate (theta and the lateral coordinate are constant),
    although neither integrates alone."""
    r = frobenius(_FixedBicycle())
    assert r.status is Integrability.HOLONOMIC and r.n_integrable == 2 == r.k
    x, y, th = sp.symbols("x y theta", real=True)
    forms = sp.Matrix.vstack(*r.integrable_forms)
    assert forms.rank() == 2 and sp.simplify(forms * sp.Matrix([sp.cos(th), sp.sin(th), 0])) == sp.zeros(2, 1)
    assert [a for _, a in r.alone] == [False, False]


def test_single_form_integrability():
    x, y, th = sp.symbols("x y theta", real=True)
    q = [x, y, th]
    assert integrable_alone([0, 0, 1], q)
    assert integrable_alone([2 * x * y, x**2, 0], q)  # d(x^2 y)
    assert not integrable_alone([-sp.sin(th), sp.cos(th), 0], q)  # the no-slip constraint


@pytest.mark.parametrize("name", ["unicycle", "car"])
def test_four_leg_manoeuvre_moves_along_the_bracket(name):
    """flow_{-b2} o flow_{-b1} o flow_{b2} o flow_{b1} (eps each) = q + eps^2 [b1, b2] + O(eps^3)."""
    m = get_robot(name)
    q0 = np.array([0.2, 0.1, 0.3, 0.2])[: m.n]
    qs, _, B = m.symbolic()
    br = np.array(sp.lambdify(list(qs), lie_bracket(B[:, 0], B[:, 1], qs))(*q0), dtype=float).ravel()
    errs = [np.linalg.norm((commutator_motion(m, q0, 0, 1, e)[-1] - q0) / e**2 - br) for e in (0.04, 0.02)]
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.05)  # first-order convergence to the bracket
    assert errs[1] < 0.05


def test_missing_sympy_names_the_extra(monkeypatch):
    """sympy is optional: without it the symbolic entry points raise ImportError with the install command."""
    import sys

    from qprr.wheeled import _backend

    monkeypatch.setitem(sys.modules, "sympy", None)
    with pytest.raises(ImportError, match=r'pip install "qprr\[symbolic\]"'):
        _backend.sympy_module()
    with pytest.raises(ImportError, match="symbolic"):
        frobenius(get_robot("unicycle"))
