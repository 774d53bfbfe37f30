"""Hover map and the rotors' wrench set: linear programmes, the Allocator, Pinocchio; the 2 s simulation check."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import linprog

import qprr
from qprr.actuation import AllocationFlag, Allocator
from qprr.analysis import hover, wrench_set
from qprr.analysis.hover import check_reserve
from qprr.errors import InputError

PLATFORMS = ("q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR")


def by_name(name):
    return qprr.build(name) if name.isupper() else qprr.load(name)


def lp_feasible(p, w):
    res = linprog(np.zeros(p.n_rotors), A_eq=p.rotor_matrix, b_eq=w, bounds=list(zip(p.thrust_min, p.thrust_max)), method="highs")
    return res.status == 0


def lp_margin(p, w):
    n = p.n_rotors
    c = np.zeros(n + 1)
    c[-1] = -1.0
    A_ub = np.vstack([np.hstack([-np.eye(n), np.ones((n, 1))]), np.hstack([np.eye(n), np.ones((n, 1))])])
    res = linprog(
        c,
        A_ub=A_ub,
        b_ub=np.concatenate([-p.thrust_min, p.thrust_max]),
        A_eq=np.hstack([p.rotor_matrix, np.zeros((6, 1))]),
        b_eq=w,
        bounds=[(None, None)] * (n + 1),
        method="highs",
    )
    return -res.fun


def lp_ray(p, w, e):
    n = p.n_rotors
    c = np.zeros(n + 1)
    c[-1] = -1.0
    res = linprog(
        c, A_eq=np.hstack([p.rotor_matrix, -e[:, None]]), b_eq=w, bounds=list(zip(p.thrust_min, p.thrust_max)) + [(None, None)], method="highs"
    )
    return -res.fun if res.status == 0 else -np.inf


@pytest.mark.parametrize("name", PLATFORMS)
def test_wrench_set_is_the_linear_programme(name):
    """Membership, best uniform thrust margin and the largest step along a torque axis, against HiGHS."""
    p = by_name(name)
    W = wrench_set(p)
    assert W.rank == p.wrench_rank
    rng = np.random.default_rng(5)
    span = p.thrust_max - p.thrust_min
    for _ in range(60):
        f = rng.uniform(p.thrust_min - 0.2 * span, p.thrust_max + 0.2 * span)
        w = p.rotor_matrix @ f
        assert bool(W.contains(w)) == lp_feasible(p, w)
    for _ in range(10):
        w = p.rotor_matrix @ rng.uniform(p.thrust_min, p.thrust_max)
        assert abs(float(W.thrust_margin(w[None])[0]) - lp_margin(p, w)) < 1e-9
        for ax in (3, 4, 5):
            e = np.zeros(6)
            e[ax] = 1.0
            assert abs(float(W.ray(w, e)[1][0]) - lp_ray(p, w, e)) < 1e-9
    # a lateral force is not producible by coplanar rotors
    if W.rank == 4:
        assert not W.contains(p.rotor_matrix @ (0.5 * (p.thrust_min + p.thrust_max)) + np.array([1e-3, 0, 0, 0, 0, 0]))
    zmax = linprog(-p.rotor_matrix[2], A_eq=p.rotor_matrix[0:2], b_eq=np.zeros(2), bounds=list(zip(p.thrust_min, p.thrust_max)), method="highs")
    assert abs(W.force_max() + zmax.fun) < 1e-9


@pytest.fixture(scope="module", params=PLATFORMS)
def hover_map(request):
    p = by_name(request.param)
    return p, hover(p, n_samples=4000, payload_masses=[0.0, 1.0, 2.5])


def test_hover_feasible_configurations_have_an_allocation_inside_the_bounds(hover_map):
    """The Allocator, given Pinocchio's generalised gravity, meets every producible component within [f_min, f_max]."""
    p, r = hover_map
    alloc = Allocator(p)
    d = p.data()
    q = r.grid.configurations()
    rng = np.random.default_rng(4)
    feas = np.flatnonzero(r.feasible[0])
    infeas = np.flatnonzero(~r.rotor_ok[-1])
    for i in rng.choice(feas, min(25, len(feas)), replace=False):
        qq = pin.neutral(p.model)
        qq[7:] = q[i]
        g = pin.computeGeneralizedGravity(p.model, d, qq)
        out = alloc.allocate(g)
        f = out.f[: p.n_rotors]
        assert np.all(f >= p.thrust_min - 1e-9) and np.all(f <= p.thrust_max + 1e-9)
        assert np.abs(out.residual[0:6]).max() < 1e-7, out.reason
        assert np.abs(g[6:]).max() <= np.max(p.arm_effort_limits)
        # the reported thrusts are the Allocator's exact allocation when it lies inside the bounds
        if not out.rotor_saturated:
            np.testing.assert_allclose(r.thrusts[i], f, atol=1e-9)
    # configurations reported rotor-infeasible with the heavy payload: no allocation meets the wrench
    for i in infeas[:10]:
        assert not lp_feasible(p, r.hover_wrench[i] + r.masses[-1] * _per_kg(p, q[i]))


def _per_kg(p, q_arm):
    from qprr.analysis import ArmChain

    ch = ArmChain(p)
    return ch.statics(ch.pose(q_arm), p.ee_frame).wrench1[0]


def test_authority_and_margin_are_where_the_rotors_saturate(hover_map):
    p, r = hover_map
    W = r.wrench_set
    for i in np.random.default_rng(6).choice(np.flatnonzero(r.rotor_ok[0]), 10, replace=False):
        w = r.hover_wrench[i]
        for j, ax in enumerate((3, 4, 5)):
            t = r.authority[0, i, j]
            for sgn in (1.0, -1.0):
                e = np.zeros(6)
                e[ax] = sgn
                lo, hi = W.ray(w, e)
                assert hi[0] >= t - 1e-9  # the weaker direction is the authority
                assert lp_feasible(p, w + (hi[0] - 1e-7) * e) and not lp_feasible(p, w + (hi[0] + 1e-5) * e)
        assert abs(r.thrust_margin[0, i] - lp_margin(p, w)) < 1e-8


def test_payload_envelope_is_where_hover_becomes_impossible(hover_map):
    """At the payload limit the rotors or an arm joint are exactly at their bound (Pinocchio with the payload added)."""
    p, r = hover_map
    q = r.grid.configurations()
    pl = r.payload
    for i in np.random.default_rng(8).choice(len(q), 10, replace=False):
        m = pl.total[i]
        if not np.isfinite(m) or m <= 0:
            continue
        model = pin.Model(p.model)
        f = p.model.frames[p.ee_frame]
        model.inertias[f.parentJoint] = model.inertias[f.parentJoint] + pin.Inertia(m, f.placement.translation, np.zeros((3, 3)))
        qq = pin.neutral(p.model)
        qq[7:] = q[i]
        g = pin.computeGeneralizedGravity(model, model.createData(), qq)
        if pl.effort[i] <= pl.rotors[i]:
            k = pl.effort_joint[i]
            assert abs(abs(g[6 + k]) - p.arm_effort_limits[k]) < 1e-9
            assert lp_feasible(p, g[0:6])
        else:
            assert lp_feasible(p, g[0:6] - 1e-9 * _per_kg(p, q[i]))
            assert abs(lp_margin(p, g[0:6])) < 1e-7  # on the boundary of the wrench set


def test_q_prr_hover_closed_forms():
    """Four coplanar rotors: thrusts of the "+" layout in closed form, f = M g / 4 -+ torque / (2 l)."""
    p = qprr.load("q-prr")
    r = hover(p, n_samples=2000)
    l, kappa = p.params.arm_length, p.params.kappa
    M = p.total_mass * p.g
    c = r.hover_wrench
    tx, ty = c[:, 3], c[:, 4]
    f1 = M / 4 + ty / (2 * l)
    f3 = M / 4 - ty / (2 * l)
    f2 = M / 4 - tx / (2 * l)
    f4 = M / 4 + tx / (2 * l)
    np.testing.assert_allclose(r.thrusts, np.column_stack([f1, f2, f3, f4]), atol=1e-12)
    np.testing.assert_allclose(r.thrust_margin[0], np.minimum(r.thrusts, 20.0 - r.thrusts).min(axis=1), atol=1e-12)
    assert kappa > 0 and r.min_thrust_margin[0] > 0


def test_hover_input_errors():
    p = qprr.load("q-prr")
    with pytest.raises(InputError, match="torque_reserve"):
        check_reserve([1.0, -1.0, 0.0])
    with pytest.raises(InputError, match="payload_masses"):
        hover(p, n_samples=100, payload_masses=[np.nan])


def test_hover_feasible_configuration_holds_in_simulation():
    """A configuration reported hover-feasible holds for 2 s in closed loop (inverse dynamics, the allocator), no rotor
    at a bound, with the thrusts the map reports; with a payload 2 % inside the map's rotor limit of the tightest
    configuration it still does, 2 % outside a rotor saturates."""
    from qprr import control, sim, trajectory
    from qprr.payload import with_payload

    p = qprr.load("q-prr")
    r = hover(p, n_samples=2000, payload_masses=[0.0])
    i = int(np.argmin(np.where(r.feasible[0], r.thrust_margin[0], np.inf)))  # the tightest feasible configuration
    xi0 = np.concatenate([[0.0, 0.0, 2.0, 0.0, 0.0, 0.0], r.grid.configurations(i, i + 1)[0]])
    res = sim.simulate(p, control.InverseDynamicsController(p), trajectory.Hold(xi0), 2.0)
    assert not np.any(res.flags & (AllocationFlag.ROTOR_SATURATED | AllocationFlag.ARM_SATURATED)), "a rotor bound or an effort limit was active"
    assert np.abs(res.xi[:, 0:3] - xi0[0:3]).max() < 1e-3
    assert np.abs(res.f[:, 0 : p.n_rotors] - r.thrusts[i]).max() < 1e-9
    # the payload envelope at the configuration where the rotors limit it most
    k = int(np.argmin(np.where(r.payload.rotors < r.payload.effort, r.payload.rotors, np.inf)))
    m_lim = float(r.payload.rotors[k])
    xi0 = np.concatenate([[0.0, 0.0, 2.0, 0.0, 0.0, 0.0], r.grid.configurations(k, k + 1)[0]])
    for factor, saturates in ((0.98, False), (1.02, True)):
        m = factor * m_lim
        loaded = with_payload(p, m)
        expect = hover(p, n_samples=2, ranges={n: (x, x) for n, x in zip(p.arm_names, xi0[6:])}, payload_masses=[m])
        assert bool(expect.rotor_ok[0, 0]) is not saturates
        try:
            res = sim.simulate(loaded, control.InverseDynamicsController(loaded), trajectory.Hold(xi0), 2.0)
        except qprr.errors.DivergenceError as err:  # an unheld platform may leave the bounds
            res = err.result
        assert bool(np.any(res.flags & AllocationFlag.ROTOR_SATURATED)) is saturates
        if not saturates:
            assert np.abs(res.f[:, 0 : p.n_rotors] - expect.thrusts[0]).max() < 1e-9
            assert np.abs(res.xi[:, 0:3] - xi0[0:3]).max() < 1e-3
