"""The compiled lexicographic kernel (qprr/actuation/lexicographic_fast.py, numba) against the readable numpy path
(qprr/actuation/lexicographic.py) on seeded random problems, bounds active and not, and on the IK's cold starts; the
kernel setting (auto, numpy, numba; numba missing)."""

from __future__ import annotations

import copy
import pickle
from importlib.util import find_spec

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr import ik
from qprr.actuation import lexicographic
from qprr.actuation.lexicographic import Kernel, Lexicographic, QPSettings, resolve_kernel
from qprr.errors import InputError, MissingDependencyError

needs_numba = pytest.mark.skipif(find_spec("numba") is None, reason="numba is not installed: pip install 'qprr[fast]'")

# the levels' regularisation (1e-7) lets condition numbers reach ~1e8: agreement to 1e-9 of the solution's size is
# agreement to round-off on these problems (the largest difference seen over 1200 solves: 2.6e-11)
RTOL = 1e-9


def random_problem(rng):
    """Levels (A_k, b_k) over n variables, the last nb of them bounded by [lo, up] (0 inside), often active."""
    n = int(rng.integers(4, 12))
    nb = int(rng.integers(1, n - 2))
    dims = [int(rng.integers(1, 7)) for _ in range(int(rng.integers(1, 5)))]
    levels = [(rng.normal(size=(d, n)), rng.normal(size=d) * rng.uniform(0.1, 5.0)) for d in dims]
    return n, nb, levels, -rng.uniform(0.01, 1.5, nb), rng.uniform(0.01, 1.5, nb)


def engines(n, nb):
    kw = {"regularization": 1e-7, "rank_tol": 1e-9, "active_set_first": True}
    reference = Lexicographic(n, range(n - nb, n), settings=QPSettings(kernel="numpy"), **kw)
    fast = Lexicographic(n, range(n - nb, n), settings=QPSettings(kernel="numba"), **kw)
    return reference, fast


@needs_numba
def test_kernel_matches_numpy_path_on_random_problems():
    rng = np.random.default_rng(36)
    active = 0
    for _ in range(120):
        n, nb, levels, lo, up = random_problem(rng)
        reference, fast = engines(n, nb)
        for _ in range(3):  # a sequence of similar problems: the active-set guesses of the previous call are used
            damping = rng.uniform(0.0, 1e-2, len(levels))
            ra = reference.solve(levels, lo, up, damping=damping)
            rf = fast.solve(levels, lo, up, damping=damping)
            for xa, xf in zip(ra.x_levels, rf.x_levels, strict=True):
                assert np.abs(xa - xf).max() <= RTOL * (1.0 + np.abs(xa).max())
            x_b = ra.x[n - nb :]
            active += int(np.any(np.isclose(x_b, lo, rtol=0, atol=1e-12) | np.isclose(x_b, up, rtol=0, atol=1e-12)))
            levels = [(A + 1e-3 * rng.normal(size=A.shape), b) for A, b in levels]
    assert active >= 100  # the bounds matter in many of the 360 solves (the KKT steps, not only the Cholesky solve)


@needs_numba
def test_kernel_keeps_x0_and_level_count_changes():
    rng = np.random.default_rng(7)
    n, nb, levels, lo, up = random_problem(rng)
    reference, fast = engines(n, nb)
    x0 = np.zeros(n)
    x0[n - nb :] = 0.5 * lo
    for k in (len(levels), 1, len(levels)):  # fewer levels, then all again (the frozen levels of the IK)
        ra = reference.solve(levels[:k], lo, up, x0=x0)
        rf = fast.solve(levels[:k], lo, up, x0=x0)
        assert np.abs(ra.x - rf.x).max() <= RTOL * (1.0 + np.abs(ra.x).max())
        assert len(rf.x_levels) == k


@needs_numba
def test_engine_with_numba_kernel_copies_and_pickles():
    rng = np.random.default_rng(3)
    n, nb, levels, lo, up = random_problem(rng)
    _, fast = engines(n, nb)
    x = fast.solve(levels, lo, up).x
    for other in (copy.deepcopy(fast), pickle.loads(pickle.dumps(fast))):
        np.testing.assert_allclose(other.solve(levels, lo, up).x, x, rtol=0, atol=RTOL * (1.0 + np.abs(x).max()))


@needs_numba
@pytest.mark.parametrize("name", ["q-prr", "hextilt_flying_arm_5"])
def test_ik_cold_starts_agree_between_kernels(name):
    """The QP IK's answers with the compiled kernel are the numpy path's to round-off: same verdicts, same
    iteration counts, the same level errors.  The configuration is the same to 1e-9 on the Q-PRR; on the hextilt, whose
    unsatisfiable lower levels are nearly flat along some joint directions (their errors agree to 1e-9 where q differs
    by 3e-7: the regularisation 1e-7 sets that conditioning), to 1e-6."""
    platform = qprr.load(name)
    data = platform.data()
    rng = np.random.default_rng(11)
    solvers = {k: ik.IKSolver(platform, "qp", {"kernel": k}) for k in ("numpy", "numba")}
    for _ in range(6):
        xi = np.zeros(platform.nv)
        xi[0:3] = rng.uniform(-2.0, 2.0, 3)
        xi[5] = rng.uniform(-np.pi, np.pi)
        xi[6:] = rng.uniform(np.maximum(platform.arm_lower, -np.pi), np.minimum(platform.arm_upper, np.pi))
        q = qprr.charts.xi_to_q(xi)
        pin.framesForwardKinematics(platform.model, data, q)
        target = data.oMf[platform.ee_frame].copy()
        ra, rf = (solvers[k].solve(data, target) for k in ("numpy", "numba"))
        assert ra.success and rf.success
        assert ra.iterations == rf.iterations
        np.testing.assert_allclose(rf.level_errors, ra.level_errors, rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(rf.q, ra.q, rtol=0, atol=1e-9 if name == "q-prr" else 1e-6)


def test_kernel_setting():
    assert resolve_kernel("numpy") is Kernel.NUMPY
    assert resolve_kernel("auto") is (Kernel.NUMPY if find_spec("numba") is None else Kernel.NUMBA)
    assert QPSettings().kernel is Kernel.NUMPY  # the engine's default: the readable path
    assert ik.IKSolver(qprr.load("q-prr"), "qp").options.kernel == "auto"
    with pytest.raises(InputError, match="kernel"):
        resolve_kernel("fortran")
    with pytest.raises(InputError, match="kernel"):
        ik.IKSolver(qprr.load("q-prr"), "qp", {"kernel": "fortran"})


def test_numba_asked_for_without_numba(monkeypatch):
    monkeypatch.setattr(lexicographic, "find_spec", lambda name: None)  # numba not installed
    assert resolve_kernel("auto") is Kernel.NUMPY
    with pytest.raises(MissingDependencyError, match=r"not available: pip install 'qprr\[fast\]'"):
        QPSettings(kernel="numba")
