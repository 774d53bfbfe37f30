"""The lexicographic engine's exact pieces (qprr.actuation.lexicographic): the active-set QP and the KKT polish, against the KKT
conditions; bounds that exclude 0; the degenerate vertex ProxQP called infeasible (octorotor allocation); the
hard equality (a Pfaffian constraint) against the closed form; the duality-gap setting."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from proxsuite import proxqp

from qprr.actuation.lexicographic import Lexicographic, QPSettings, active_set_qp, polish_box_qp
from qprr.errors import InputError

SETTINGS = settings(max_examples=80, deadline=None, derandomize=True)


def assert_kkt(H, g, C, lo, up, z, tol=1e-8):
    """z is optimal: feasible, and H z + g = C^T mu with mu >= 0 on lower-active, <= 0 on upper-active bounds, 0 else."""
    from scipy.optimize import nnls

    Cz = C @ z
    scale = 1.0 + np.abs(np.concatenate([lo[np.isfinite(lo)], up[np.isfinite(up)]])).max(initial=0.0)
    assert np.all(Cz >= lo - 1e-9 * scale) and np.all(Cz <= up + 1e-9 * scale)
    act_lo = np.isfinite(lo) & (Cz - lo <= 1e-7 * scale)
    act_up = np.isfinite(up) & (up - Cz <= 1e-7 * scale)
    G = np.hstack([C[act_lo].T, -C[act_up].T])  # H z + g = G nu, nu >= 0
    grad = H @ z + g
    if G.shape[1] == 0:
        assert np.abs(grad).max() <= tol * (1 + np.abs(g).max())
        return
    _, res = nnls(G, grad)
    assert res <= tol * (1 + np.abs(g).max() + np.abs(H).max())


@st.composite
def box_qp(draw):
    """A convex QP whose bounds contain z = 0, often at a degenerate vertex (bounds through 0, more than n)."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(1, 7)), int(rng.integers(1, 14))
    B = rng.normal(size=(int(rng.integers(1, n + 2)), n))
    H = B.T @ B + (1e-3 * np.eye(n) if rng.random() < 0.5 else 0.0)  # semi-definite half of the time
    g = -B.T @ rng.normal(size=B.shape[0])
    C = rng.normal(size=(m, n))
    lo, up = -rng.uniform(0, 1, m), rng.uniform(0, 1, m)
    lo[rng.random(m) < 0.3] = 0.0
    up[rng.random(m) < 0.2] = 0.0
    lo[rng.random(m) < 0.2] = -np.inf
    return H, g, C, lo, up


@SETTINGS
@given(box_qp())
def test_active_set_qp_meets_the_kkt_conditions(qp):
    H, g, C, lo, up = qp
    z = active_set_qp(H, g, C, lo, up)
    assert z is not None
    assert_kkt(H, g, C, lo, up, z)


@SETTINGS
@given(box_qp(), st.floats(1e-12, 1e-7))
def test_polish_recovers_the_exact_optimum_from_a_perturbed_one(qp, eps):
    """From the optimum perturbed by eps (as ProxQP's answer within its tolerance) the polish returns a KKT point
    that does not depend on the perturbation."""
    H, g, C, lo, up = qp
    z = active_set_qp(H, g, C, lo, up)
    rng = np.random.default_rng(1)
    a = polish_box_qp(H, g, C, lo, up, z + eps * rng.normal(size=z.shape))
    b = polish_box_qp(H, g, C, lo, up, z - eps * rng.normal(size=z.shape))
    if a is None or b is None:  # the polish declines (ProxQP's answer is kept): allowed, never wrong
        return
    assert_kkt(H, g, C, lo, up, a)
    f = lambda x: 0.5 * x @ H @ x + g @ x  # noqa: E731
    assert f(a) == pytest.approx(f(b), rel=1e-9, abs=1e-12)


def test_positive_lower_bounds_are_met_from_the_first_level():
    """Bounds that exclude 0 (rotors with f_min > 0): the level-1 optimum is the bounded least-squares one
    (scipy's BVLS), not that of the bounds [0, f_max]."""
    opt = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(3)
    for _ in range(30):
        A = rng.normal(size=(3, 6))
        b = rng.normal(size=3) * 5
        lo, up = np.full(6, 0.2), np.full(6, 1.0)
        x = Lexicographic(6).solve([(A, b)], lo, up).x
        ref = opt.lsq_linear(A, b, bounds=(lo, up), method="bvls", tol=1e-14)
        assert np.all(x >= lo - 1e-12) and np.all(x <= up + 1e-12)
        assert np.sum((A @ x - b) ** 2) <= np.sum((A @ ref.x - b) ** 2) * (1 + 1e-8) + 1e-12


def test_degenerate_vertex_from_an_octorotor_allocation():
    """Level 3 of an OCT-RR allocation: six of eight bounds active at z = 0 in four variables.  ProxQP 0.8 called
    it PRIMAL_INFEASIBLE (z = 0 is feasible); the engine now returns the exact optimum (here z = 0)."""
    C = np.array(
        [
            [0.0147, -0.0555, -0.4707, -0.5246],
            [0.3906, 0.3982, 0.4276, -0.0778],
            [-0.5093, 0.1656, -0.0185, 0.4614],
            [-0.1487, -0.6063, 0.0562, -0.3274],
            [0.6618, 0.0185, -0.1764, 0.1749],
            [-0.3089, 0.5539, -0.2642, -0.1672],
            [-0.1672, -0.1286, 0.6656, -0.1117],
            [0.067, -0.3459, -0.2195, 0.5724],
        ]
    )
    lo = np.array([-1.0, -0.8051, 0.0, 0.0, 0.0, -0.4413, -1.0, -1.0])
    up = np.array([3.2196e-15, 0.19492, 1.0, 1.0, 1.0, 0.55873, 3.6697e-10, 0.0])
    g = np.array([0.0421, -0.1541, 0.0808, 0.0353])
    H = np.eye(4)
    z = active_set_qp(H, g, C, lo, up)
    assert_kkt(H, g, C, lo, up, z)
    lex = Lexicographic(8, warm_start=False)  # eight thrusts; level 3 has four free directions
    out, _ = lex.solve_box_qp(2, H, g, C, lo, up)
    assert_kkt(H, g, C, lo, up, out)


def test_equality_restricts_every_level_to_its_kernel():
    """``equality=E``: levels (J, e) then (I, 0) under E x = 0 with the bounds inactive give the damped least-squares
    minimiser on ker E, x = N M^T (M M^T + reg I)^-1 e with M = J N, N an orthonormal basis of ker E (already the
    smallest x with its J x, so level 2 keeps it); E x = 0 to rounding.  The same as E as a first level (E, 0)."""
    rng = np.random.default_rng(2)
    n, reg = 6, 1e-3
    lex = Lexicographic(n, regularization=reg)
    lo, up = -np.full(n, 1e3), np.full(n, 1e3)
    for _ in range(10):
        J, e, E = rng.normal(size=(3, n)), rng.normal(size=3), rng.normal(size=(2, n))
        x = lex.solve([(J, e), (np.eye(n), np.zeros(n))], lo, up, equality=E).x
        N = np.linalg.svd(E)[2][2:].T
        M = J @ N
        ref = N @ M.T @ np.linalg.solve(M @ M.T + reg * np.eye(3), e)
        assert np.allclose(x, ref, atol=1e-13, rtol=0)
        assert np.abs(E @ x).max() <= 1e-15 * (1 + np.abs(x).max()) * n
        first = lex.solve([(E, np.zeros(2)), (J, e), (np.eye(n), np.zeros(n))], lo, up).x
        assert np.allclose(first, x, atol=1e-13, rtol=0)
    with pytest.raises(InputError, match="equality must be a matrix with 6 columns"):
        lex.solve([(J, e)], lo, up, equality=np.ones((2, 5)))
    assert np.array_equal(lex.solve([(J, e)], lo, up, equality=np.zeros((0, n))).x, lex.solve([(J, e)], lo, up).x)


def test_qp_settings_duality_gap():
    qp = proxqp.dense.QP(2, 0, 0)
    QPSettings(eps_abs=1e-8).apply(qp)
    assert qp.settings.eps_duality_gap_abs == 1e-8 and qp.settings.eps_duality_gap_rel == 0.0
    QPSettings(eps_abs=1e-8, eps_duality_gap=1e-6).apply(qp)
    assert qp.settings.eps_duality_gap_abs == 1e-6
    with pytest.raises(InputError, match="eps_duality_gap"):
        QPSettings(eps_duality_gap=0.0)


@SETTINGS
@given(box_qp(), st.integers(0, 2**32 - 1))
def test_kkt_on_active_set_returns_only_the_optimum(qp, seed):
    """From any guessed active set the active-set steps end at a KKT point (the optimum) or decline (None)."""
    from qprr.actuation.lexicographic import kkt_on_active_set

    H, g, C, lo, up = qp
    H = H + 1e-6 * np.eye(H.shape[0])  # strictly convex, as every level of the engine (regularisation)
    rng = np.random.default_rng(seed)
    at_lo = rng.random(C.shape[0]) < 0.3
    at_up = (rng.random(C.shape[0]) < 0.3) & ~at_lo
    out = kkt_on_active_set(H, g, C, lo, up, at_lo, at_up)
    if out is not None:
        assert_kkt(H, g, C, lo, up, out[0])
        ref = active_set_qp(H, g, C, lo, up)
        assert np.abs(out[0] - ref).max() <= 1e-7 * (1 + np.abs(ref).max())  # the optimum is unique


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.integers(0, 2**32 - 1))
def test_active_set_first_gives_the_proxqp_and_polish_answer(seed):
    """Lexicographic(active_set_first=True) (exact solves on the previous active set, ProxQP only as fallback) returns
    the same levels as ProxQP + polish, over a sequence of related problems (as the IK's iterations)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 10))
    bounded = range(n // 2, n)
    a = Lexicographic(n, bounded, regularization=1e-7, active_set_first=True)
    b = Lexicographic(n, bounded, regularization=1e-7, active_set_first=False)
    A1, A2 = rng.normal(size=(min(3, n - 1), n)), rng.normal(size=(2, n))
    for _ in range(4):
        levels = [(A1, rng.normal(size=A1.shape[0])), (A2, rng.normal(size=2)), (np.eye(n), rng.normal(size=n))]
        nb = n - n // 2
        lo, up = -rng.uniform(0, 0.3, nb), rng.uniform(0, 0.3, nb)
        lo[rng.random(nb) < 0.3] = 0.0
        ra, rb = a.solve(levels, lo, up), b.solve(levels, lo, up)
        for xa, xb in zip(ra.x_levels, rb.x_levels):
            # two exact solutions of levels whose Hessian B^T B + 1e-7 I has a condition number up to ~1e8:
            # Cholesky and LU agree to cond * eps ~ 1e-8
            assert np.abs(xa - xb).max() <= 1e-7 * (1 + np.abs(xb).max())
        A1 = A1 + 0.05 * rng.normal(size=A1.shape)
