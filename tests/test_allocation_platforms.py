"""Allocation on every kind of rotor set: the Q-PRR ("+" and "x"), borinot (coplanar hexarotor, redundant),
hextilt (tilted, fully actuated), an OCT-RR (coplanar octorotor).  Bounds always hold, the exact path is exact,
level 1 is optimal against scipy, yaw gives first, and a copied or pickled allocator still works (issue 16 item 10).
"""

from __future__ import annotations

import copy
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import qprr
import qprr.thesis
from qprr.actuation import Allocator

NAMES = ("q-prr+", "q-prr-x", "borinot_flying_arm_2", "hextilt_flying_arm_5", "OCT-RR")


def make(name: str):
    if name == "q-prr+":
        return qprr.thesis.load_qprr()
    if name == "q-prr-x":
        return qprr.thesis.load_qprr(layout="x")
    if name == "OCT-RR":
        return qprr.build("OCT-RR")
    return qprr.load(name)


@pytest.fixture(scope="module", params=NAMES)
def platform(request):
    return make(request.param)


def random_demands(p, rng, n: int) -> np.ndarray:
    """Generalised forces (n, nv): rotor wrenches of thrusts in [-0.5, 1.5] f_max (half of them out of bounds),
    a random unproducible part on coplanar sets, and arm efforts up to twice their limits."""
    f = rng.uniform(-0.5, 1.5, (n, p.n_rotors)) * p.thrust_max
    w = f @ p.rotor_matrix.T
    if not p.fully_actuated:
        w[:, 0:2] += rng.normal(0.0, 2.0, (n, 2))
    arm = rng.uniform(-2.0, 2.0, (n, p.n_arm)) * p.arm_effort_limits
    return np.hstack([w, arm])


def exact_rows(alloc) -> list[int]:
    return list(alloc.rows)


# ---------------------------------------------------------------------------------------- bounds
def test_random_demands_always_within_bounds(platform):
    """1,000 random demands per platform (5,000 over the five): thrusts in [f_min, f_max], efforts within their
    limits, achieved = N f, and 'saturated' exactly when the unconstrained exact allocation leaves the bounds."""
    p, rng = platform, np.random.default_rng(11)
    alloc = Allocator(p)
    for tau in random_demands(p, rng, 1000):
        res = alloc.allocate(tau)
        f = res.f[: p.n_rotors]
        assert np.all(f >= p.thrust_min) and np.all(f <= p.thrust_max), f
        assert np.all(np.abs(res.f[p.n_rotors :]) <= p.arm_effort_limits)
        np.testing.assert_allclose(res.tau_achieved, p.actuation_matrix @ res.f, atol=1e-12)
        free = alloc.Omega_P_inv @ tau[alloc.rows]
        assert res.rotor_saturated == bool(np.any(free < p.thrust_min) or np.any(free > p.thrust_max))


@pytest.mark.slow
def test_many_random_demands_within_bounds(platform):
    p, rng = platform, np.random.default_rng(12)
    alloc = Allocator(p)
    for tau in random_demands(p, rng, 20000):
        f = alloc.allocate(tau).f[: p.n_rotors]
        assert np.all(f >= p.thrust_min) and np.all(f <= p.thrust_max)


# ------------------------------------------------------------------------------------ exact path
def test_exact_path_meets_the_producible_rows(platform):
    """Thrusts strictly inside their bounds: N f = tau on the rows the rotors act on, zero on the others,
    and f is the minimum-norm solution (the thrusts themselves for a square set)."""
    p, rng = platform, np.random.default_rng(13)
    alloc = Allocator(p)
    rows = exact_rows(alloc)
    others = [i for i in range(6) if i not in rows]
    for _ in range(200):
        f0 = rng.uniform(0.2, 0.8, p.n_rotors) * p.thrust_max + 0.2 * p.thrust_min
        tau = np.r_[p.rotor_matrix @ f0, rng.uniform(-0.5, 0.5, p.n_arm) * p.arm_effort_limits]
        res = alloc.allocate(tau)
        assert res.status == "exact" and not res.rotor_saturated
        np.testing.assert_allclose(res.tau_achieved[rows], tau[rows], atol=1e-10 * (1 + np.abs(tau).max()))
        np.testing.assert_allclose(res.tau_achieved[others], 0.0, atol=1e-12)
        np.testing.assert_allclose(res.f[p.n_rotors :], tau[6:], atol=0)
        f = res.f[: p.n_rotors]
        np.testing.assert_allclose(f, np.linalg.pinv(p.rotor_matrix[rows]) @ tau[rows], atol=1e-10)
        if p.n_rotors == len(rows):
            np.testing.assert_allclose(f, f0, atol=1e-10)
        out = np.empty(p.n_actuators)
        tau_out = np.empty(p.nv)
        assert alloc.allocate_into(tau, out, tau_out) == 0  # the in-loop call: same answer, no flag
        np.testing.assert_array_equal(out, res.f)
        np.testing.assert_allclose(tau_out, res.tau_achieved, atol=1e-12)


# --------------------------------------------------------------------------------- priorities
def test_level_one_is_optimal_against_scipy(platform):
    """Level 1 (force rows, roll and pitch torques, weighted) against scipy's bounded least squares."""
    opt = pytest.importorskip("scipy.optimize")
    p, rng = platform, np.random.default_rng(14)
    alloc = Allocator(p)
    lvl1 = [i for i in alloc.rows if i != 5]
    W = np.diag(alloc.weights)
    A1 = p.rotor_matrix[lvl1]
    for tau in random_demands(p, rng, 60):
        f = alloc.allocate(tau).f[: p.n_rotors]
        b = tau[lvl1]
        ref = opt.lsq_linear(W @ A1, W @ b, bounds=(p.thrust_min, p.thrust_max), method="bvls", tol=1e-14)
        ours, best = np.sum((W @ (A1 @ f - b)) ** 2), np.sum((W @ (A1 @ ref.x - b)) ** 2)
        assert ours <= best + 1e-8 * (1.0 + best)


def test_yaw_is_sacrificed_before_force_roll_and_pitch(platform):
    """A hover wrench with an impossible yaw torque: the force and roll/pitch rows are met exactly, the yaw is cut."""
    p = platform
    alloc = Allocator(p)
    f_mid = 0.5 * (p.thrust_min + p.thrust_max)
    w = p.rotor_matrix @ f_mid
    yaw_max = np.abs(p.rotor_matrix[5]).sum() * p.thrust_max.max()
    tau = np.r_[w + np.r_[0.0, 0.0, 0.0, 0.02 * yaw_max, -0.01 * yaw_max, 2.0 * yaw_max], np.zeros(p.n_arm)]
    if not p.fully_actuated:
        tau[3:5] = tau[3:5] * 0.5
    res = alloc.allocate(tau)
    lvl1 = [i for i in alloc.rows if i != 5]
    np.testing.assert_allclose(res.tau_achieved[lvl1], tau[lvl1], atol=1e-8)
    assert res.rotor_saturated and res.residual[5] > 0.1 * yaw_max


# ------------------------------------------------------------------------------- copies (item 10)
def test_deepcopy_and_pickle_then_a_saturated_allocation(platform):
    """A copied or unpickled allocator rebuilds its QPs and answers like a fresh one (in this process)."""
    p, rng = platform, np.random.default_rng(15)
    alloc = Allocator(p)
    demands = random_demands(p, rng, 20)
    for tau in demands[:5]:
        alloc.allocate(tau)  # warm QPs inside
    for other in (copy.deepcopy(alloc), pickle.loads(pickle.dumps(alloc))):
        fresh = Allocator(p)
        for tau in demands:
            a, b = other.allocate(tau), fresh.allocate(tau)
            np.testing.assert_allclose(a.f, b.f, atol=1e-7 * (1 + p.thrust_max.max()))
        assert other.qp_calls > 0


def test_copies_in_a_fresh_interpreter_do_not_crash():
    """The copy and the first saturated allocation in a child interpreter (a crash would kill it, not pytest)."""
    code = textwrap.dedent("""
        import copy, pickle, sys
        import numpy as np
        import qprr
        from qprr.actuation import Allocator
        for p in (qprr.load("q-prr"), qprr.build("OCT-RR"), qprr.load("hextilt_flying_arm_5")):
            a = Allocator(p)
            tau = np.r_[p.rotor_matrix @ (2.0 * p.thrust_max), np.zeros(p.n_arm)]  # every rotor asked twice its bound
            first = a.allocate(tau).f
            for b in (copy.deepcopy(a), pickle.loads(pickle.dumps(a)), copy.copy(a)):
                f = b.allocate(tau).f
                assert np.all(f[: p.n_rotors] <= p.thrust_max) and np.allclose(f, first, atol=1e-7), (f, first)
        print("ok")
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=_root())
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.strip() == "ok"


def _root() -> str:
    from pathlib import Path

    return str(Path(qprr.__file__).resolve().parent.parent)
