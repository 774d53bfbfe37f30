"""Kinematics and dynamics of platforms other than the Q-PRR (borinot_flying_arm_2, hextilt_flying_arm_5, a
HEX-RRR from the nomenclature) against physics: differences on SE(3), Lagrange's equations from Pinocchio's
energies, the Christoffel identity dB/dt = C + C^T, and hovering on the allocated thrusts."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr import charts as ch
from qprr import dynamics as dyn
from qprr import kinematics as kin
from qprr.actuation import Allocator

NAMES = ("borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")


@pytest.fixture(scope="module", params=NAMES)
def platform(request):
    return qprr.build(request.param) if request.param == "HEX-RRR" else qprr.load(request.param)


def random_xi(rng, p, max_tilt: float = 1.2) -> np.ndarray:
    xi = np.empty(p.n_xi)
    xi[0:3] = rng.uniform(-2.0, 2.0, 3)
    xi[3:5] = rng.uniform(-max_tilt, max_tilt, 2)
    xi[5] = rng.uniform(-np.pi, np.pi)
    xi[6:] = rng.uniform(p.arm_lower, p.arm_upper)
    return xi


def _pose_error(M_ref: pin.SE3, M: pin.SE3) -> np.ndarray:
    return np.concatenate([M.translation - M_ref.translation, M_ref.rotation @ pin.log3(M_ref.rotation.T @ M.rotation)])


def _grad(f, x, h):
    out = np.empty(len(x))
    for k in range(len(x)):
        e = np.zeros(len(x))
        e[k] = h
        out[k] = (f(x + e) - f(x - e)) / (2 * h)
    return out


# ------------------------------------------------------------------------------ kinematics
def test_jacobian_xi_by_differences_on_se3(platform):
    p, data, rng = platform, platform.data(), np.random.default_rng(1)
    for _ in range(3):
        xi = random_xi(rng, p)
        J = kin.jacobian_xi(p, data, xi)
        h = 1e-6
        for k in range(p.n_xi):
            e = np.zeros(p.n_xi)
            e[k] = h
            fd = _pose_error(kin.ee_placement(p, data, ch.xi_to_q(xi - e)), kin.ee_placement(p, data, ch.xi_to_q(xi + e))) / (2 * h)
            np.testing.assert_allclose(J[:, k], fd, atol=1e-7)


def test_com_and_its_body_jacobian(platform):
    """The CoM is the mass-weighted mean of the bodies; its body-frame Jacobian matches differences along pin.integrate."""
    p, data, rng = platform, platform.data(), np.random.default_rng(2)
    q = ch.xi_to_q(random_xi(rng, p))
    pin.forwardKinematics(p.model, data, q)
    acc = sum(p.model.inertias[j].mass * data.oMi[j].act(p.model.inertias[j].lever) for j in range(1, p.model.njoints))
    np.testing.assert_allclose(kin.com_world(p, data, q), acc / p.total_mass, atol=1e-13)
    J = kin.com_jacobian_body(p, data, q)
    h = 1e-6
    for k in range(p.nv):
        dv = np.zeros(p.nv)
        dv[k] = h
        fd = (kin.com_body(p, data, pin.integrate(p.model, q, dv)) - kin.com_body(p, data, pin.integrate(p.model, q, -dv))) / (2 * h)
        np.testing.assert_allclose(J[:, k], fd, atol=1e-9)
    m_arm, c_w, c_b = kin.arm_com(p, data, q)
    assert 0.0 < m_arm < p.total_mass
    np.testing.assert_allclose(data.oMi[1].act(c_b), c_w, atol=1e-13)


def test_cog_offset_is_measured_from_the_thrust_axis(platform):
    """Equal thrusts apply a force F along the thrust axis (through ``point``) plus at most a couple along it: their
    torque about the CoG, in the plane normal to the axis, has magnitude |F| |offset| (zero iff the CoG is on it)."""
    p, data, rng = platform, platform.data(), np.random.default_rng(7)
    point, axis = p.thrust_axis
    w = p.rotor_matrix.sum(axis=1)  # equal unit thrusts: wrench at B, in B
    np.testing.assert_allclose(w[0:3] / np.linalg.norm(w[0:3]), axis, atol=1e-15)
    for _ in range(5):
        q = ch.xi_to_q(random_xi(rng, p))
        c = kin.com_body(p, data, q)
        off = kin.cog_offset_body(p, data, q)
        np.testing.assert_allclose(p.thrust_axis_basis.T @ off, (c - point) - ((c - point) @ axis) * axis, atol=1e-14)
        tau_c = w[3:6] - np.cross(c, w[0:3])  # torque about the CoG
        normal = p.thrust_axis_basis @ tau_c
        assert np.linalg.norm(normal) == pytest.approx(np.linalg.norm(w[0:3]) * np.linalg.norm(off), rel=1e-9, abs=1e-14)


# ------------------------------------------------------------------------------- dynamics
def test_lagrange_equations_from_pinocchio_energies(platform):
    """With xi_ddot = 0, Thesis (5.30)-(5.33): B xi_dot = dT/dxi_dot, C xi_dot = d/dt(dT/dxi_dot) - dT/dxi and
    G = dU/dxi, by differences of Pinocchio's kinetic and potential energies through xi -> (q, v)."""
    p, data, rng = platform, platform.data(), np.random.default_rng(3)
    for _ in range(3):
        xi, w = random_xi(rng, p), rng.uniform(-1.5, 1.5, p.n_xi)
        B, C, G = dyn.dynamics_xi(p, data, xi, w)

        def T(x, v):
            q, vv = ch.xi_to_qv(x, v)
            return dyn.kinetic_energy(p, data, q, vv)

        def momentum(x, w=w):  # exact for the quadratic T whatever the step
            return _grad(lambda v: T(x, v), w, 1.0)

        np.testing.assert_allclose(momentum(xi), B @ w, rtol=0, atol=1e-12 * np.linalg.norm(B) * (1 + np.linalg.norm(w)))
        h = 1e-5
        dpdt = (momentum(xi + h * w) - momentum(xi - h * w)) / (2 * h)
        dTdxi = _grad(lambda x, w=w: T(x, w), xi, h)
        assert np.linalg.norm(C @ w - (dpdt - dTdxi)) <= 1e-7 * np.linalg.norm(B) * (w @ w)
        G_fd = _grad(lambda x: dyn.potential_energy(p, data, ch.xi_to_q(x)), xi, 1e-6)
        assert np.linalg.norm(G - G_fd) <= 1e-7 * np.linalg.norm(G)
        assert G[2] == pytest.approx(p.total_mass * p.g, rel=1e-12)  # dU/dz is the weight


def test_christoffel_identity_and_positive_inertia(platform):
    """dB/dt = C + C^T (B_dot - 2C skew, Hypothesis 7) with dB/dt by central differences along xi_dot; B SPD."""
    p, data, rng = platform, platform.data(), np.random.default_rng(4)
    for _ in range(4):
        xi, w = random_xi(rng, p), rng.uniform(-2.0, 2.0, p.n_xi)
        B, C, _ = dyn.dynamics_xi(p, data, xi, w)
        np.testing.assert_allclose(B, B.T, rtol=0, atol=1e-15 * np.linalg.norm(B))
        assert np.linalg.eigvalsh(B)[0] > 0.0
        h = 1e-6
        B_dot = (dyn.dynamics_xi(p, data, xi + h * w, w)[0] - dyn.dynamics_xi(p, data, xi - h * w, w)[0]) / (2 * h)
        assert np.linalg.norm(B_dot - (C + C.T)) <= 1e-7 * np.linalg.norm(B) * np.linalg.norm(w)


def test_forward_dynamics_xi_is_5_39(platform):
    p, data, rng = platform, platform.data(), np.random.default_rng(5)
    for _ in range(3):
        xi, w, u = random_xi(rng, p), rng.uniform(-1, 1, p.n_xi), rng.uniform(-5, 5, p.n_xi)
        B, C, G = dyn.dynamics_xi(p, data, xi, w)
        np.testing.assert_allclose(dyn.forward_dynamics_xi(p, data, xi, w, u), np.linalg.solve(B, u - C @ w - G), atol=1e-8)


def test_allocated_hover_thrusts_hold_the_platform_still(platform):
    """At random level configurations, the allocator's hover thrusts and the arm's gravity efforts give a = 0 (ABA)."""
    p, data, rng = platform, platform.data(), np.random.default_rng(6)
    alloc = Allocator(p)
    n_ok = 0
    for _ in range(10):
        xi = random_xi(rng, p)
        xi[3:5] = 0.0
        q = ch.xi_to_q(xi)
        g = dyn.generalized_gravity(p, data, q)
        try:
            f = alloc.hover_thrusts(data, q)
        except qprr.errors.InputError:  # this arm pose needs more than the rotors' bounds
            continue
        n_ok += 1
        a = pin.aba(p.model, data, q, np.zeros(p.nv), p.actuation_matrix @ np.r_[f, g[6:]])
        np.testing.assert_allclose(a, 0.0, atol=1e-10)
    assert n_ok >= 5
