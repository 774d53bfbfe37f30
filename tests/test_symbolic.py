"""The independent sympy Lagrange model of Thesis Sec. 5.2 checked against its own energies.

Everything here is Pinocchio-free: finite differences of the symbolic energies T and U
are the arbiter for B, dB/dxi, C and G; the closed-form blocks printed after (5.25) are
checked (and their errata pinned) against the derived B.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings

from qprr.errors import EulerSingularityError, InputError, NonFiniteError, ShapeError
from qprr.thesis import symbolic as sy
from qprr.thesis.params import Link, cad_params, thesis_params

from .strategies import rates_strategy, xi_strategy

SETTINGS = settings(max_examples=25, deadline=None, derandomize=True)
VARIANTS = {"thesis": thesis_params(), "cad": cad_params()}

_p = thesis_params()


@pytest.fixture(scope="module", params=list(VARIANTS))
def sm(request) -> sy.SymbolicModel:
    return sy.symbolic_model(VARIANTS[request.param])


def _central(f, x, h):
    """Central difference of f (array-valued) at x along each coordinate: shape (len(x), *f.shape)."""
    out = []
    for k in range(len(x)):
        e = np.zeros(len(x))
        e[k] = h
        out.append((np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2 * h))
    return np.array(out)


def _kinetic_momentum(sm, xi, w):
    """p = dT/dxi_dot by central differences of T; exact for a quadratic T whatever the step."""
    return _central(lambda v: sm.kinetic_energy(xi, v), w, 1.0)


# ----------------------------------------------------------------------- B from T
@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy())
def test_inertia_is_hessian_of_kinetic_energy(sm, xi, w):
    """Thesis (5.24)-(5.25): T = 1/2 xi_dot^T B xi_dot, with B read back from T by polarisation."""
    B = sm.B(xi)
    T = sm.kinetic_energy(xi, w)
    assert T == pytest.approx(0.5 * w @ B @ w, rel=1e-12, abs=1e-14)
    # B_ij = T(e_i + e_j) - T(e_i) - T(e_j) for a quadratic form
    eye = np.eye(9)
    Ti = np.array([sm.kinetic_energy(xi, eye[i]) for i in range(9)])
    for i, j in [(0, 4), (2, 7), (3, 5), (4, 8), (6, 7), (7, 8), (5, 6)]:
        Bij = sm.kinetic_energy(xi, eye[i] + eye[j]) - Ti[i] - Ti[j]
        assert Bij == pytest.approx(B[i, j], rel=1e-9, abs=1e-12 * np.linalg.norm(B))


@SETTINGS
@given(xi=xi_strategy())
def test_inertia_symmetric_positive_definite(sm, xi):
    """Hypothesis 7: B symmetric positive definite; B11 = m_G I3 (total mass)."""
    B = sm.B(xi)
    np.testing.assert_array_equal(B, B.T)
    assert np.linalg.eigvalsh(B)[0] > 0.0
    np.testing.assert_allclose(B[0:3, 0:3], sm.params.total_mass * np.eye(3), rtol=1e-14)


def test_body_rates_are_thesis_3_25():
    """The derivation uses omega_b of (3.22)-(3.24); check it is (R^T R_dot)^vee (3.19) by finite differences."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        e = rng.uniform([-3, -1.3, -3], [3, 1.3, 3])
        ed = rng.uniform(-2, 2, 3)
        R = lambda a: sy._np_rot(2, a[2]) @ sy._np_rot(1, a[1]) @ sy._np_rot(0, a[0])  # noqa: E731
        h = 1e-6
        Rdot = (R(e + h * ed) - R(e - h * ed)) / (2 * h)
        W = R(e).T @ Rdot
        omega_fd = np.array([W[2, 1], W[0, 2], W[1, 0]])
        # the derived T of a unit-inertia multirotor with a negligible arm is 1/2 |omega_b|^2
        sf, cf, st_, ct = math.sin(e[0]), math.cos(e[0]), math.sin(e[1]), math.cos(e[1])
        T = np.array([[1, 0, -st_], [0, cf, sf * ct], [0, -sf, cf * ct]])
        np.testing.assert_allclose(T @ ed, omega_fd, atol=1e-8)
        xi = np.r_[0, 0, 0, e, 0, 0, 0]
        w = np.r_[0, 0, 0, ed, 0, 0, 0]
        np.testing.assert_allclose(_unit_model().kinetic_energy(xi, w), 0.5 * omega_fd @ omega_fd, rtol=1e-8)


def _unit_model() -> sy.SymbolicModel:
    """Multirotor with unit inertia, arm of negligible mass: T = 1/2 |omega_b|^2 + tiny."""
    p = thesis_params()
    tiny = tuple(Link(l.name, 1e-14, l.length, l.com, (1e-14, 1e-14, 1e-14, 0.0, 0.0, 0.0)) for l in p.links)
    return sy.symbolic_model(p.with_changes(multirotor_mass=1.0, multirotor_inertia=(1, 1, 1, 0, 0, 0), links=tiny))


# ----------------------------------------------------------------------- derivatives
@SETTINGS
@given(xi=xi_strategy())
def test_inertia_derivatives_match_finite_differences(sm, xi):
    dB = sm.inertia_derivatives(xi)
    dB_fd = _central(sm.B, xi, 1e-6)
    scale = np.linalg.norm(sm.B(xi))
    assert np.abs(dB - dB_fd).max() <= 1e-8 * scale


@SETTINGS
@given(xi=xi_strategy())
def test_gravity_is_gradient_of_potential(sm, xi):
    """Thesis (5.37): G = dU/dxi."""
    G = sm.G(xi)
    G_fd = _central(sm.potential_energy, xi, 1e-6)
    assert np.linalg.norm(G - G_fd) <= 1e-7 * np.linalg.norm(G)
    # U does not depend on x, y, yaw; dU/dz = m_G g (world z up, Thesis (5.29))
    assert G[0] == G[1] == G[5] == 0.0
    assert G[2] == pytest.approx(sm.params.total_mass * sm.params.g, rel=1e-14)


@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy())
def test_coriolis_from_lagrange_equations_by_finite_differences(sm, xi, w):
    """C xi_dot = d/dt(dT/dxi_dot) - dT/dxi at xi_ddot = 0 (Thesis (5.30)-(5.33)), all from T by FD."""
    _, C, _ = sm.dynamics(xi, w)
    h = 1e-5
    dpdt = (_kinetic_momentum(sm, xi + h * w, w) - _kinetic_momentum(sm, xi - h * w, w)) / (2 * h)
    dTdxi = _central(lambda x: sm.kinetic_energy(x, w), xi, h)
    lhs = C @ w
    ref = dpdt - dTdxi
    scale = np.linalg.norm(sm.B(xi)) * (w @ w)
    assert np.linalg.norm(lhs - ref) <= 1e-7 * scale


@SETTINGS
@given(xi=xi_strategy(), w=rates_strategy())
def test_bdot_minus_2c_is_skew(sm, xi, w):
    """Hypothesis 7: B_dot - 2C is skew-symmetric; B_dot by a central difference along xi_dot and analytically."""
    B, C, _ = sm.dynamics(xi, w)
    h = 1e-6
    B_dot_fd = (sm.B(xi + h * w) - sm.B(xi - h * w)) / (2 * h)
    B_dot = sm.B_dot(xi, w)
    scale = np.linalg.norm(B) * max(np.linalg.norm(w), 1e-3)
    assert np.linalg.norm(B_dot - B_dot_fd) <= 1e-7 * scale
    N = B_dot - 2 * C
    assert np.linalg.norm(N + N.T) <= 1e-13 * scale
    assert np.linalg.norm(B_dot_fd - 2 * C + (B_dot_fd - 2 * C).T) <= 1e-7 * scale


def test_definition_5_h_iii_zero(sm):
    """Definition 5: db_ii/dxi_i = 0 for every coordinate of the Q-PRR (so h_iii = 0)."""
    rng = np.random.default_rng(5)
    for _ in range(10):
        xi = np.r_[
            rng.uniform(-1, 1, 3), rng.uniform(-3, 3), rng.uniform(-1.3, 1.3), rng.uniform(-3, 3), rng.uniform(_p.lower_limits, _p.upper_limits)
        ]
        dB = sm.inertia_derivatives(xi)
        assert max(abs(dB[i, i, i]) for i in range(9)) <= 1e-15


def test_energy_conserved_without_input(sm):
    """With u = 0 the flow of (5.39) conserves T + U (RK4, 0.5 s, tumbling with the arm moving)."""
    xi = np.array([0.0, 0.0, 1.0, 0.3, -0.4, 0.2, 0.0, 0.3, -0.5])
    w = np.array([0.5, -0.2, 0.1, 2.0, -1.5, 1.0, 0.05, 3.0, -2.0])
    u = np.zeros(9)
    E0 = sm.kinetic_energy(xi, w) + sm.potential_energy(xi)
    dt = 1e-3

    def f(s):
        return np.r_[s[9:], sm.forward_dynamics(s[:9], s[9:], u)]

    s = np.r_[xi, w]
    for _ in range(500):
        k1 = f(s)
        k2 = f(s + dt / 2 * k1)
        k3 = f(s + dt / 2 * k2)
        k4 = f(s + dt * k3)
        s = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert abs(s[4]) < 1.4  # stayed away from the Euler singularity (joint limits are not modelled)
    E1 = sm.kinetic_energy(s[:9], s[9:]) + sm.potential_energy(s[:9])
    assert abs(E1 - E0) <= 1e-8 * abs(E0)


# ------------------------------------------------------------- printed blocks (errata)
@SETTINGS
@given(xi=xi_strategy())
def test_corrected_closed_form_blocks_equal_derived_inertia(sm, xi):
    """Sec. 5.2.2 blocks with the corrections of :func:`inertia_matrix_blocks` reproduce B exactly."""
    B = sm.B(xi)
    assert np.abs(sy.inertia_matrix_blocks(sm.params, xi) - B).max() <= 1e-13 * np.linalg.norm(B)


def _block(M, a, b):
    return M[3 * a : 3 * a + 3, 3 * b : 3 * b + 3]


def test_printed_inertia_blocks_are_wrong(sm):
    """Counter-example to the printed B22, B23, B33 after (5.25); B11, B12, B13 are right.

    State: xi = [0, 0, 0, 0.3, -0.4, 0.5, 0.02, 0.6, -0.9].
    """
    p = sm.params
    xi = np.array([0.0, 0.0, 0.0, 0.3, -0.4, 0.5, 0.02, 0.6, -0.9])
    B = sm.B(xi)
    Bp = sy.thesis_inertia_matrix(p, xi)
    scale = np.linalg.norm(B)
    for a, b in [(0, 0), (0, 1), (0, 2)]:
        assert np.abs(_block(Bp, a, b) - _block(B, a, b)).max() <= 1e-13 * scale
    # B33 printed with a leading minus: the prismatic entry is -m_arm, B is not positive definite
    assert Bp[6, 6] == pytest.approx(-(p.arm_mass), rel=1e-12)
    assert B[6, 6] == pytest.approx(p.arm_mass, rel=1e-12)
    assert np.linalg.eigvalsh(Bp)[0] < 0.0
    # B22 printed with Q = R_b^T T: wrong as soon as the body is tilted (right when R_b = I)
    assert np.abs(_block(Bp, 1, 1) - _block(B, 1, 1)).max() > 1e-4
    level = xi.copy()
    level[3:6] = 0.0
    np.testing.assert_allclose(_block(sy.thesis_inertia_matrix(p, level), 1, 1), _block(sm.B(level), 1, 1), atol=1e-15)
    # B23 printed: sign of the m T^T p^ J_p term and J_p^T in place of J_o
    assert np.abs(_block(Bp, 1, 2) - _block(B, 1, 2)).max() > 1e-2


# ------------------------------------------------------------------ input, cache
def test_bad_input_names_the_argument(sm):
    xi = np.zeros(9)
    with pytest.raises(ShapeError, match="xi"):
        sm.B(np.zeros(8))
    with pytest.raises(NonFiniteError, match="xi_dot"):
        sm.C(xi, np.r_[np.nan, np.zeros(8)])
    with pytest.raises(ShapeError, match="u"):
        sm.forward_dynamics(xi, xi, np.zeros(7))
    singular = xi.copy()
    singular[4] = math.pi / 2
    with pytest.raises(EulerSingularityError, match="theta"):
        sm.forward_dynamics(singular, xi, xi)
    with pytest.raises(InputError, match="params"):
        sy.symbolic_model("thesis")


def test_model_cached_in_process():
    assert sy.symbolic_model() is sy.symbolic_model(thesis_params())


def test_unwritable_cache_falls_back_to_fresh_derivation(tmp_path, monkeypatch):
    """A cache path that cannot be created still yields the same model (fresh derivation, not cached)."""
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("QPRR_CACHE_DIR", str(blocker / "sub"))
    fresh = sy._build(thesis_params())
    assert not fresh.from_disk_cache
    xi = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6, 0.01, 0.7, -0.3])
    w = np.linspace(-1, 1, 9)
    for a, b in zip(fresh.dynamics(xi, w), sy.symbolic_model().dynamics(xi, w)):
        np.testing.assert_array_equal(a, b)


def test_import_without_sympy_gives_install_command():
    code = "import sys; sys.modules['sympy'] = None\ntry:\n import qprr.thesis.symbolic\nexcept ImportError as e:\n print(e)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert 'pip install "qprr[test]"' in out.stdout, out.stdout + out.stderr
