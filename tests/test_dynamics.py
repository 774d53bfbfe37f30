"""Pinocchio's coupled dynamics in thesis coordinates (qprr.dynamics.dynamics_xi) against the
independent sympy Lagrange model (qprr.thesis.symbolic), Thesis (5.25)-(5.39).

The arbiter when the two disagree is the Lagrange equation evaluated by finite
differences of Pinocchio's energy functions (test_lagrange_equations_from_pinocchio_energies).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import qprr.thesis
from qprr import charts as co
from qprr import dynamics as dyn
from qprr.errors import EulerSingularityError, NonFiniteError, ShapeError
from qprr.thesis import symbolic as sy

from .strategies import rates_strategy, xi_strategy

SETTINGS = settings(max_examples=30, deadline=None, derandomize=True)
REL = 1e-9


@pytest.fixture(scope="module", params=["thesis", "cad"])
def pair(request):
    """(robot, data, symbolic model) of one parameter variant."""
    robot = qprr.thesis.load_qprr(request.param)
    return robot, robot.data(), sy.symbolic_model(robot.params)


def _rel(a, b) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


# ------------------------------------------------------------- B, C, G agree
@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy())
def test_B_C_G_match_symbolic_model(pair, xi, w):
    robot, data, sm = pair
    B, C, G = dyn.dynamics_xi(robot, data, xi, w)
    Bs, Cs, Gs = sm.dynamics(xi, w)
    assert _rel(B, Bs) <= REL
    assert _rel(G, Gs) <= REL
    # C is linear in xi_dot and vanishes at rest or where the rates do not couple (xi = 0, w = e_z: |Cs| = 2.5e-18):
    # relative to the scale |B| |xi_dot| of its entries (per metre of the robot's size), where the rounding of both
    # models lives (5.9e-16 there, with the pre-port code too).
    assert np.linalg.norm(C - Cs) <= REL * max(np.linalg.norm(Cs), np.linalg.norm(B) * np.linalg.norm(w))


@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy())
def test_C_xi_dot_equals_pinocchio_bias(pair, xi, w):
    """C xi_dot = S^T (M S_dot xi_dot + nle(q, v) - g(q)), from tau = M a + nle and a = S xi_ddot + S_dot xi_dot."""
    robot, data, sm = pair
    q, v = co.xi_to_qv(xi, w)
    S, S_dot = co.rate_map(xi), co.rate_map_dot(xi, w)
    M = pin.crba(robot.model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    nle = pin.nonLinearEffects(robot.model, data, q, v).copy()
    g = pin.computeGeneralizedGravity(robot.model, data, q).copy()
    bias = S.T @ (M @ S_dot @ w + nle - g)
    _, Cs, _ = sm.dynamics(xi, w)
    assert np.linalg.norm(Cs @ w - bias) <= REL * max(np.linalg.norm(bias), 1e-12)


@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy(), u=st.lists(st.floats(-20.0, 20.0), min_size=9, max_size=9))
def test_aba_forward_dynamics_matches_5_39(pair, xi, w, u):
    """ABA on the Lie group vs xi_ddot = B^-1 (u - C xi_dot - G) of the symbolic model, Thesis (5.39)."""
    robot, data, sm = pair
    u = np.array(u)
    a_pin = dyn.forward_dynamics_xi(robot, data, xi, w, u)
    a_sym = sm.forward_dynamics(xi, w, u)
    # relative to B^-1 times the size of the force terms (B^-1 amplifies with 1/cos(theta))
    B, C, G = sm.dynamics(xi, w)
    scale = np.linalg.norm(np.linalg.solve(B, np.abs(u) + np.abs(C @ w) + np.abs(G)))
    assert np.linalg.norm(a_pin - a_sym) <= 1e-8 * scale


@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy())
def test_energies_match(pair, xi, w):
    """Kinetic (Thesis (5.13)) and potential (5.29) energies: Pinocchio vs the symbolic expressions."""
    robot, data, sm = pair
    q, v = co.xi_to_qv(xi, w)
    T = dyn.kinetic_energy(robot, data, q, v)
    U = dyn.potential_energy(robot, data, q)
    assert T == pytest.approx(sm.kinetic_energy(xi, w), rel=1e-12, abs=1e-12)
    assert U == pytest.approx(sm.potential_energy(xi), rel=1e-12, abs=1e-10)


# ------------------------------------------------------------- physics of Pinocchio's B, C, G
def _pin_T(robot, data, xi, w) -> float:
    q, v = co.xi_to_qv(xi, w)
    return dyn.kinetic_energy(robot, data, q, v)


def _pin_U(robot, data, xi) -> float:
    return dyn.potential_energy(robot, data, co.xi_to_q(xi))


def _grad(f, x, h):
    out = np.empty(len(x))
    for k in range(len(x)):
        e = np.zeros(len(x))
        e[k] = h
        out[k] = (f(x + e) - f(x - e)) / (2 * h)
    return out


@settings(max_examples=10, deadline=None, derandomize=True)
@given(xi=xi_strategy(), w=rates_strategy())
def test_lagrange_equations_from_pinocchio_energies(pair, xi, w):
    """The arbiter: with xi_ddot = 0, Thesis (5.30)-(5.33) give
    C xi_dot = d/dt(dT/dxi_dot) - dT/dxi and G = dU/dxi, evaluated by finite differences of
    Pinocchio's computeKineticEnergy / computePotentialEnergy through xi -> (q, v)."""
    robot, data, sm = pair
    B, C, G = dyn.dynamics_xi(robot, data, xi, w)

    def momentum(x):  # dT/dxi_dot: central difference, exact for a quadratic T at any step
        return _grad(lambda v: _pin_T(robot, data, x, v), w, 1.0)

    np.testing.assert_allclose(momentum(xi), B @ w, rtol=0, atol=1e-12 * np.linalg.norm(B) * (1 + np.linalg.norm(w)))
    h = 1e-5
    dpdt = (momentum(xi + h * w) - momentum(xi - h * w)) / (2 * h)
    dTdxi = _grad(lambda x: _pin_T(robot, data, x, w), xi, h)
    scale = np.linalg.norm(B) * (w @ w)
    assert np.linalg.norm(C @ w - (dpdt - dTdxi)) <= 1e-7 * scale
    G_fd = _grad(lambda x: _pin_U(robot, data, x), xi, 1e-6)
    assert np.linalg.norm(G - G_fd) <= 1e-7 * np.linalg.norm(G)


@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy())
def test_pinocchio_bdot_minus_2c_skew_and_B_spd(pair, xi, w):
    """Hypothesis 7 for Pinocchio's B, C: B SPD; B_dot - 2C skew with B_dot by central difference along xi_dot."""
    robot, data, _ = pair
    B, C, _ = dyn.dynamics_xi(robot, data, xi, w)
    np.testing.assert_allclose(B, B.T, rtol=0, atol=1e-15 * np.linalg.norm(B))
    assert np.linalg.eigvalsh(B)[0] > 0.0
    h = 1e-6
    B_dot = (dyn.dynamics_xi(robot, data, xi + h * w, w)[0] - dyn.dynamics_xi(robot, data, xi - h * w, w)[0]) / (2 * h)
    N = B_dot - 2 * C
    assert np.linalg.norm(N + N.T) <= 1e-7 * np.linalg.norm(B) * max(np.linalg.norm(w), 1e-3)


# ------------------------------------------------------------- singularity and input checks
def test_euler_singularity_raises(pair):
    robot, data, _ = pair
    xi = np.zeros(9)
    xi[4] = math.pi / 2
    with pytest.raises(EulerSingularityError, match="theta"):
        dyn.dynamics_xi(robot, data, xi, np.zeros(9))
    with pytest.raises(EulerSingularityError, match="theta"):
        dyn.forward_dynamics_xi(robot, data, xi, np.zeros(9), np.zeros(9))


def test_bad_shapes_and_nan_name_the_argument(pair):
    robot, data, _ = pair
    z = np.zeros(9)
    with pytest.raises(ShapeError, match="xi"):
        dyn.dynamics_xi(robot, data, np.zeros(10), z)
    with pytest.raises(ShapeError, match="xi_dot"):
        dyn.dynamics_xi(robot, data, z, np.zeros((3, 3)))
    with pytest.raises(NonFiniteError, match="xi_dot"):
        dyn.dynamics_xi(robot, data, z, np.r_[np.inf, np.zeros(8)])
    with pytest.raises(NonFiniteError, match="xi"):
        dyn.dynamics_xi(robot, data, np.r_[np.nan, np.zeros(8)], z)
    with pytest.raises(ShapeError, match="u"):
        dyn.forward_dynamics_xi(robot, data, z, z, np.zeros(4))
