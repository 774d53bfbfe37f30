"""Payload capacity map: the transport limit of Sec. 6.4.1.1, the corrected holding torques, Pinocchio, limiting factors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import qprr
from qprr.analysis import LIMITS, capacity
from qprr.analysis._common import boundary_share, lipschitz_halo, share_error
from qprr.errors import InputError


@pytest.fixture(scope="module")
def qp():
    return qprr.load("q-prr")


@pytest.fixture(scope="module")
def cap(qp):
    return capacity(qp, n_samples=20_000)


def test_transport_limit_is_the_collective_thrust(qp, cap):
    """Thesis Sec. 6.4.1.1, transport: the thrust alone carries the system, 4 f_max >= (m_G + m_c) g."""
    assert abs(cap.m_thrust - (4 * qp.params.thrust_max / qp.params.g - qp.params.total_mass)) < 1e-12
    i = int(np.argmax(cap.capacity))
    assert abs(cap.capacity[i] - cap.m_thrust) < 1e-9 and LIMITS[cap.limiting[i]] == "thrust"  # arm straight up: CoG on the axis


def test_manipulation_limit_is_the_corrected_holding_torque(qp):
    """Arm horizontal (theta2 = pi/2, theta3 = 0): tau_theta2 = g [(m2/2 + m3 + m_c) d2 + (m3/2 + m_c) d3] reaches 5 N m.

    The corrected form of the holding torque printed in Sec. 6.4.1.1 (docs/thesis-errata.md); solved for m_c.
    """
    p = qp.params
    m1, m2, m3 = (k.mass for k in p.links)
    r = capacity(qp, n_samples=20_000, ranges={"theta2": (np.pi / 2, np.pi / 2), "theta3": (0.0, 0.0)})
    g, d2, d3 = p.g, p.d2, p.d3
    m_c = (p.effort_limits[1] / g - (m2 / 2 + m3) * d2 - m3 / 2 * d3) / (d2 + d3)
    np.testing.assert_allclose(r.m_effort, m_c, rtol=1e-12)
    assert np.all(r.effort_joint == 1)


def test_limits_agree_with_pinocchio_at_the_capacity(qp, cap):
    q = cap.grid.configurations()
    for i in np.random.default_rng(3).choice(len(q), 20, replace=False):
        m = cap.capacity[i]
        model = pin.Model(qp.model)
        f = qp.model.frames[qp.ee_frame]
        model.inertias[f.parentJoint] = model.inertias[f.parentJoint] + pin.Inertia(m, f.placement.translation, np.zeros((3, 3)))
        qq = pin.neutral(qp.model)
        qq[7:] = q[i]
        gg = pin.computeGeneralizedGravity(model, model.createData(), qq)
        thrust = np.linalg.solve(qp.rotor_matrix[2:6], gg[2:6])  # four coplanar rotors: the allocation is unique
        what = LIMITS[cap.limiting[i]]
        if what in ("thrust", "attitude"):
            assert abs(thrust.max() - qp.params.thrust_max) < 1e-8 or abs(thrust.min()) < 1e-8
        elif what == "effort":
            k = cap.effort_joint[i]
            assert abs(abs(gg[6 + k]) - qp.params.effort_limits[k]) < 1e-9
        assert np.all(thrust <= qp.params.thrust_max + 1e-8) and np.all(np.abs(gg[6:]) <= np.array(qp.params.effort_limits) + 1e-9)


def test_torque_reserve_lowers_the_capacity_and_keeps_authority(qp):
    from qprr.analysis import hover

    r0 = capacity(qp, n_samples=5000)
    r1 = capacity(qp, n_samples=5000, torque_reserve=0.5)
    assert np.all(r1.capacity <= r0.capacity + 1e-12)
    # at the reserved capacity every axis keeps at least 0.5 N m in both directions
    i = np.random.default_rng(0).choice(len(r1.capacity), 10, replace=False)
    q = r1.grid.configurations()
    for k in i:
        rng = {n: (q[k][j], q[k][j]) for j, n in enumerate(qp.arm_names)}
        h = hover(qp, n_samples=2, ranges=rng, payload_masses=[r1.capacity[k]])
        if LIMITS[r1.limiting[k]] in ("attitude", "thrust"):
            assert h.authority[0, 0].min() >= 0.5 - 1e-9


def test_workspace_map_keeps_the_best_configuration_per_cell(cap):
    best = cap.map_capacity
    inside = ~np.isnan(best)
    assert inside.sum() > 500
    # every configuration's capacity is at most the best of its cell
    coords = (cap.ee_body - cap.origin) @ cap.basis.T
    idx = np.floor((coords - cap.map_origin) / cap.cell).astype(int)
    assert np.all(cap.capacity <= best[tuple(idx.T)] + 1e-12)
    fr = cap.map_fractions()
    assert abs(sum(fr.values()) - 1.0) < 1e-12


@pytest.mark.parametrize("name", ["borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR"])
def test_capacity_any_platform(name):
    p = qprr.build(name) if name.isupper() else qprr.load(name)
    r = capacity(p, n_samples=5000)
    assert r.status.value == "ok"
    assert np.all(r.capacity <= r.m_thrust + 1e-9)
    assert np.all((r.limiting >= 0) & (r.limiting < len(LIMITS)))


def test_capacity_input_errors(qp):
    with pytest.raises(InputError, match="thrust_tol"):
        capacity(qp, n_samples=100, thrust_tol=-1.0)
    with pytest.raises(InputError, match="payload_offset"):
        capacity(qp, n_samples=100, payload_offset=[0.0, 0.0])


@pytest.mark.parametrize("name", ["q-prr", "borinot_flying_arm_2", "hextilt_flying_arm_5"])
def test_payload_capacity_is_the_maps_implementation(name):
    """qprr.payload.payload_capacity reads the map's limits (one implementation): at given configurations its per-joint
    bounds equal (L - a sgn b) / |b| from Pinocchio's generalised gravity with and without 1 kg at the end effector,
    its thrust bound the map's collective limit, and at the capacity the binding joint is exactly at its effort limit."""
    from qprr import payload as pl

    p = qprr.load(name)
    rng = np.random.default_rng(11)
    rows = rng.uniform(p.arm_lower, p.arm_upper, size=(40, p.n_arm))
    off = (0.01, -0.02, 0.03)
    r = pl.payload_capacity(p, "manipulation", configurations=rows, com_ee=off)
    loaded = pl.with_payload(p, pl.Payload(1.0, off))
    d0, d1 = p.model.createData(), loaded.model.createData()
    q = p.neutral_q()
    ref = np.full(p.n_arm, np.inf)
    for row in rows:
        q[7:] = row
        a = pin.computeGeneralizedGravity(p.model, d0, q)[6:].copy()
        b = pin.computeGeneralizedGravity(loaded.model, d1, q)[6:] - a
        for j in range(p.n_arm):
            if abs(b[j]) > 1e-12:
                ref[j] = min(ref[j], (p.arm_effort_limits[j] - a[j] * np.sign(b[j])) / abs(b[j]))
    got = np.array([r.per_limit[n] for n in p.arm_names])
    fin = np.isfinite(ref)
    assert np.array_equal(fin, np.isfinite(got)) and np.allclose(got[fin], ref[fin], rtol=1e-12)
    assert abs(r.per_limit["thrust"] - capacity(p, n_samples=200).m_thrust) < 1e-12
    if r.limiting != "thrust":
        h = pl.holding_efforts(p, r.q_arm, pl.Payload(r.max_mass, off))
        j = p.arm_names.index(r.limiting)
        assert abs(abs(h.arm_effort[j]) - p.arm_effort_limits[j]) < 1e-10 * p.arm_effort_limits[j]


def test_capacity_options_and_keywords_agree(qp):
    from qprr.analysis import CapacityOptions

    a = capacity(qp, CapacityOptions(n_samples=2000, torque_reserve=0.5))
    b = capacity(qp, n_samples=2000, torque_reserve=0.5)
    np.testing.assert_array_equal(a.capacity, b.capacity)
    np.testing.assert_array_equal(a.limiting, b.limiting)
    with pytest.raises(TypeError):
        capacity(qp, n_sample=2000)


# ------------------------------------------------------------------------------ error bars (module docstring)
ROOT = Path(__file__).resolve().parents[1]


def _platform(name):
    if name == "my_platform":
        return qprr.from_urdf(ROOT / "examples/my_platform/quad_rrr.urdf", ROOT / "examples/my_platform/quad_rrr.rotors.toml")
    return qprr.load(name)


@pytest.mark.parametrize("name", ["q-prr", "borinot_flying_arm_2", "my_platform"])
def test_coarse_error_bars_hold_the_fine_grid(name):
    """The error bars a coarse grid reaches contain what a grid 40 times as fine finds: the best and worst capacity
    (the steepest neighbour changes), every share of limiting factors (the cells whose corners disagree) and the
    smallest best capacity over the workspace on the coarse map's cells."""
    p = _platform(name)
    coarse = capacity(p, n_samples=1500)
    fine = capacity(p, n_samples=60_000)
    assert fine.grid.size > 30 * coarse.grid.size
    assert coarse.best_error >= 0.0 and coarse.worst_error >= 0.0
    assert abs(fine.best[0] - coarse.best[0]) <= coarse.best_error + 1e-9
    assert abs(fine.worst - coarse.worst) <= coarse.worst_error + 1e-9
    fc, ff = coarse.fractions(), fine.fractions()
    for k, name_k in enumerate(LIMITS):
        assert abs(ff[name_k] - fc[name_k]) <= coarse.fraction_errors[k] + 1e-12, name_k
    assert fine.worst_error <= coarse.worst_error + 1e-12  # the finer grid's bar where the capacity is smooth
    # the smallest best capacity over the workspace, on the coarse map's cells: both grids' configurations binned there
    w = _smallest_best_on_cells(coarse, fine)
    assert coarse.worst_reachable - 1e-12 <= w <= coarse.worst_reachable + coarse.worst_reachable_error + 1e-9
    assert coarse.worst_reachable_error > 0.0 and fine.worst_reachable_error < coarse.worst_reachable_error


def _smallest_best_on_cells(coarse, fine) -> float:
    """The smallest per-cell best capacity [kg] over the cells the coarse map holds, with the fine grid's
    configurations binned on the coarse map's cells too (its end effectors in the coarse hull's coordinates)."""
    best = np.where(np.isfinite(coarse.map_capacity), coarse.map_capacity, -np.inf).reshape(-1)
    idx = np.floor(((fine.ee_body - coarse.origin) @ coarse.basis.T - coarse.map_origin) / coarse.cell).astype(np.int64)
    inside = np.all((idx >= 0) & (idx < np.array(coarse.map_capacity.shape)), axis=1)
    np.maximum.at(best, np.ravel_multi_index(tuple(idx[inside].T), coarse.map_capacity.shape), fine.capacity[inside])
    return float(best[np.isfinite(coarse.map_capacity).reshape(-1)].min())


def test_lipschitz_halo_bounds_a_kink_between_grid_points():
    """|x - 0.3| + 0.5 y on a grid that misses x = 0.3: the box's minimum 0 lies within the halo of the grid's, and
    the halo is the half-step steepest change (0.1 / 2 along x, 0.05 / 2 along y on a 0.1 step)."""
    x, y = np.meshgrid(np.linspace(0.0, 1.0, 11), np.linspace(0.0, 1.0, 11), indexing="ij")
    shifted = np.abs(x - 0.35) + 0.5 * y  # minimum 0 at x = 0.35, between two grid values
    halo = lipschitz_halo(shifted.reshape(-1), shifted.shape)
    np.testing.assert_allclose(halo, 0.05 + 0.025)
    lo = float(np.min(shifted.reshape(-1) - halo))
    assert lo <= 0.0 <= float(shifted.min())
    # a locked joint (one value) adds nothing
    np.testing.assert_allclose(lipschitz_halo(shifted[:, :1].reshape(-1), (11, 1)), 0.05)


def test_boundary_share_brackets_a_disc():
    """The share of [0, 1]^2 inside the disc of radius 0.8 about the origin (a quarter disc: pi 0.64 / 4) lies between the
    share of cells with every corner inside and the share with one corner inside, and the points' share is within
    share_error of it."""
    for n in (7, 21, 61):
        x, y = np.meshgrid(np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, n), indexing="ij")
        inside = (x**2 + y**2 <= 0.64).reshape(-1)
        low, high = boundary_share(inside, (n, n))
        true = np.pi * 0.64 / 4.0
        assert low <= true <= high
        assert abs(inside.mean() - true) <= share_error(inside, (n, n))
