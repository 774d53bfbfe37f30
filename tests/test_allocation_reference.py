"""Allocator.allocate_into (numpy, the in-loop form) against the allocation written step by step on plain floats.

:func:`reference_allocate_into` below is the specification: the exact allocation, a bound test per rotor,
the prioritised QP when one fails, the arm efforts clipped one by one, N f.  (It was the production class's
``reference_allocate_into`` while a second, faster copy of it ran in the loop; the in-loop form now reads as
the steps, and the step-by-step form lives here, as crocoddyl keeps its readable reference models in its tests.)
Two twin allocators (same QP warm-start history) receive the same demands, one through ``allocate_into``, one
through the reference: thrusts, efforts, N f and flags must agree bit for bit, and bad input must raise the
same error.  ``allocate_screened_into`` is ``allocate_into`` behind the screen of a NaN, infinite or absurd
demand, for the base class and for a subclass that overrides ``allocate_into``.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import qprr
import qprr.thesis
from qprr.actuation import AllocationFlag, Allocator, IdealAllocator
from qprr.rotors import ideal_wrench_set


def reference_allocate_into(alloc: Allocator, tau_d: np.ndarray, f_out: np.ndarray, tau_out: np.ndarray | None = None) -> int:
    """:meth:`Allocator.allocate_into` step by step on plain floats: same arguments, writes and flags (as integers)."""
    lo, hi, lim = alloc.f_min.tolist(), alloc.f_max.tolist(), alloc.effort_limits.tolist()
    n = alloc.n_rotors
    rows = alloc.rows
    f = alloc.Omega_P_inv.dot(tau_d[rows])  # the exact allocation of the producible rows
    flags = 0
    if not all(a <= x <= b for a, x, b in zip(lo, f.tolist(), hi)):  # NaN fails
        f = alloc._solve_qp(tau_d[rows], f)
        flags = 1
    td = tau_d.tolist()
    arm = td[6:]
    if alloc.clip_arm:
        for k, a in enumerate(arm):
            if not -lim[k] <= a <= lim[k]:  # beyond the limit, or NaN
                alloc._check_arm_finite(tau_d[6:])
                arm = [min(max(x, -b), b) for x, b in zip(arm, lim)]
                flags |= 2
                break
    elif arm and not math.isfinite(sum(arm)):
        alloc._check_arm_finite(tau_d[6:])
    fl = f.tolist()
    for k in range(n):
        f_out[k] = fl[k]
    for k, a in enumerate(arm):
        f_out[n + k] = a
    if tau_out is not None:
        if flags or not alloc.square:
            wrench = (alloc.Omega @ f).tolist()
        else:  # exact: Omega f = tau_d on the producible rows, zero on the others
            wrench = [td[i] if i in rows else 0.0 for i in range(6)]
        for i, x in enumerate(wrench + arm):
            tau_out[i] = x
    return flags


def _non_uniform(p):
    """``p`` with per-rotor bounds that differ (f_min 0..0.3 N, f_max scaled 0.7..1.2)."""
    rotors = tuple(dataclasses.replace(r, f_min=0.1 * (i % 4), f_max=r.f_max * (0.7 + 0.1 * i)) for i, r in enumerate(p.rotors))
    return p.replace(rotors=rotors)


CASES = {  # (platform, Allocator keyword arguments)
    "q-prr+": lambda: (qprr.thesis.load_qprr(), {}),
    "q-prr-x no arm clip": lambda: (qprr.thesis.load_qprr(layout="x"), {"clip_arm": False}),
    "hextilt_flying_arm_5": lambda: (qprr.load("hextilt_flying_arm_5"), {}),
    "HEX-RRR": lambda: (qprr.build("HEX-RRR"), {}),
    "HEX-RRR non-uniform bounds": lambda: (_non_uniform(qprr.build("HEX-RRR")), {}),
    "q-prr+ non-uniform bounds": lambda: (_non_uniform(qprr.thesis.load_qprr()), {}),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request):
    return CASES[request.param]()


def _run(alloc_into, tau, n_act, nv):
    f, t = np.full(n_act, -7.0), np.full(nv, -7.0)
    try:
        flags = alloc_into(tau, f, t)
    except Exception as err:  # the two forms must raise the same error
        return ("error", type(err), str(err))
    return flags, f, t


def _demand(p, thrust_scale, arm_scale, nan_at, lateral):
    w = p.rotor_matrix @ (np.asarray(thrust_scale) * p.thrust_max)
    if not p.fully_actuated:
        w[0:2] += lateral
    tau = np.concatenate([w, np.asarray(arm_scale) * p.arm_effort_limits])
    if nan_at is not None:
        tau[nan_at % p.nv] = np.nan
    return tau


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_in_loop_form_is_the_reference(case, data):
    p, kwargs = case
    fast, ref = Allocator(p, **kwargs), Allocator(p, **kwargs)  # fresh twins: the same (empty) QP warm start
    thrust = data.draw(st.lists(st.floats(-0.5, 1.5), min_size=p.n_rotors, max_size=p.n_rotors))
    inside = data.draw(st.booleans())  # half the cases on the exact path
    if inside:
        thrust = [0.05 + 0.9 * (x + 0.5) / 2.0 for x in thrust]
    arm = data.draw(st.lists(st.floats(-2.0, 2.0), min_size=p.n_arm, max_size=p.n_arm))
    nan_at = data.draw(st.none() | st.integers(0, 100))
    lateral = data.draw(st.lists(st.floats(-3.0, 3.0), min_size=2, max_size=2))
    tau = _demand(p, thrust, arm, nan_at, lateral)
    a = _run(fast.allocate_into, tau, p.n_actuators, p.nv)
    b = _run(lambda *args: reference_allocate_into(ref, *args), tau, p.n_actuators, p.nv)
    if b[0] == "error":
        assert a == b
        return
    assert a[0] == b[0]
    np.testing.assert_array_equal(a[1], b[1])
    np.testing.assert_array_equal(a[2], b[2])
    # and the physics: N f is what tau_out holds, thrusts within the bounds
    np.testing.assert_allclose(a[2], p.actuation_matrix @ a[1], rtol=0, atol=1e-9 * (1 + np.abs(tau[np.isfinite(tau)]).max()))
    assert np.all(a[1][: p.n_rotors] >= fast.f_min - 1e-12) and np.all(a[1][: p.n_rotors] <= fast.f_max + 1e-12)


def test_nan_wrench_and_nan_arm_effort_raise_the_generic_messages():
    alloc = Allocator(qprr.thesis.load_qprr())
    p = alloc.platform
    base = p.actuation_matrix @ np.concatenate([alloc.hover_thrusts(), np.zeros(p.n_arm)])
    for i, pattern in ((2, "non-finite rotor wrench"), (7, "non-finite effort on arm joint")):
        tau = base.copy()
        tau[i] = np.nan
        with pytest.raises(qprr.errors.DivergenceError, match=pattern) as fast_err:
            alloc.allocate_into(tau, np.empty(p.n_actuators))
        with pytest.raises(qprr.errors.DivergenceError) as ref_err:
            reference_allocate_into(Allocator(p), tau, np.empty(p.n_actuators))
        assert str(fast_err.value) == str(ref_err.value)


def test_copies_allocate_for_themselves():
    alloc = Allocator(qprr.build("HEX-RRR"))
    p = alloc.platform
    tau = p.actuation_matrix @ np.concatenate([1.4 * p.thrust_max, 3.0 * p.arm_effort_limits])  # rotors and arm saturated
    for other in (copy.deepcopy(alloc), pickle.loads(pickle.dumps(alloc))):
        assert other.allocate_into.__self__ is other
        f1, f2 = np.empty(p.n_actuators), np.empty(p.n_actuators)
        calls = other.qp_calls
        both = AllocationFlag.ROTOR_SATURATED | AllocationFlag.ARM_SATURATED
        assert other.allocate_into(tau, f1) == alloc.allocate_into(tau, f2) == both
        np.testing.assert_allclose(f1, f2, rtol=0, atol=1e-7 * p.thrust_max.max())
        assert other.qp_calls == calls + 1  # the copy's own counter and QPs


@settings(max_examples=40, deadline=None)
@given(scale=st.floats(-2.0, 2.0), bad_at=st.integers(0, 8), bad=st.sampled_from([np.nan, np.inf, -np.inf, 1e151, -3e200]))
def test_screened_form_refuses_exactly_the_bad_demands(scale, bad_at, bad):
    """The simulator's ``allocate_screened_into``: REFUSED and nothing written when the norm of tau_d is NaN, inf or
    >= DEMAND_BOUND (even on a row no rotor produces), else allocate_into's answer."""
    alloc = Allocator(qprr.thesis.load_qprr())
    p = alloc.platform
    tau = p.actuation_matrix @ np.concatenate([alloc.hover_thrusts() * (1.0 + 0.2 * scale), scale * p.arm_effort_limits])
    f1, t1, f2, t2 = (np.zeros(n) for n in (p.n_actuators, p.nv, p.n_actuators, p.nv))
    assert alloc.allocate_screened_into(tau, f1, t1) == alloc.allocate_into(tau, f2, t2)
    assert AllocationFlag.REFUSED not in alloc.allocate_into(tau, f2, t2)
    np.testing.assert_array_equal(f1, f2)
    np.testing.assert_array_equal(t1, t2)
    tau[bad_at] = bad
    f1[:], t1[:] = -7.0, -7.0
    assert alloc.allocate_screened_into(tau, f1, t1) is AllocationFlag.REFUSED
    assert np.all(f1 == -7.0) and np.all(t1 == -7.0)


def test_a_subclass_that_overrides_allocate_into_is_screened_and_allocated_by_its_own_method():
    """IdealAllocator overrides allocate_into: the screened call runs its allocation (N f = tau_d exactly on the ideal
    wrench set, where the base class's least squares would not) and refuses a NaN demand (REFUSED)."""
    p = qprr.thesis.load_qprr().replace(rotors=ideal_wrench_set(10.0, 10.0))
    alloc = IdealAllocator(p)
    tau = np.r_[0.3, -0.2, 4.0, 0.05, -0.02, 0.01, 0.0, 0.1, -0.1]
    f1, t1, f2, t2 = np.zeros(p.n_actuators), np.zeros(p.nv), np.zeros(p.n_actuators), np.zeros(p.nv)
    assert alloc.allocate_screened_into(tau, f1, t1) == alloc.allocate_into(tau, f2, t2) == 0
    np.testing.assert_array_equal(f1, f2)
    np.testing.assert_array_equal(t1, t2)
    np.testing.assert_allclose(t1, tau, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(p.actuation_matrix @ f1, tau, rtol=1e-14, atol=1e-14)
    tau[4] = np.nan
    f1[:] = -7.0
    assert alloc.allocate_screened_into(tau, f1, t1) is AllocationFlag.REFUSED and np.all(f1 == -7.0)
