"""Workspace map: closed forms of the Q-PRR's planar 2R and 2R + P arm, Monte Carlo, IK, any platform."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy import ndimage

import qprr
from qprr.analysis import reachable, workspace
from qprr.analysis.voxels import estimate_measure
from qprr.errors import InputError, LimitError, UnknownNameError
from qprr.ik import IKSolver
from qprr.ik.tasks import BasePoseTask, PositionTask

from .analysis_closed_forms import PlanarArm


@pytest.fixture(scope="module")
def qprr_platform():
    return qprr.load("q-prr")


@pytest.fixture(scope="module")
def arm(qprr_platform):
    return PlanarArm(qprr_platform.params)


@pytest.fixture(scope="module")
def ws(qprr_platform):
    return workspace(qprr_platform, n_samples=200_000)


@pytest.fixture(scope="module")
def swept_area(arm):
    return arm.area_swept()


def test_workspace_without_slider_is_the_2r_closed_form(ws, arm):
    """r0 locked: area of the planar 2R region and the volume it sweeps under hover (yaw about z_B), both closed forms."""
    r = ws.regions[1]
    assert r.locked == {"r0": 0.0} and r.dim == 2
    np.testing.assert_allclose(r.basis, [[1, 0, 0], [0, 0, 1]])  # the x-z plane of B
    A, V = arm.area_2r(), arm.volume_2r_revolved()
    assert abs(r.measure.measure - A) <= r.measure.error, (r.measure, A)
    assert r.measure.error < 2e-3 * A  # the error bar is informative, not just large
    assert abs(r.hover_volume.measure - V) <= r.hover_volume.error, (r.hover_volume, V)
    assert r.hover_volume.error < 3e-3 * V


def test_workspace_with_slider_is_the_swept_closed_form(ws, swept_area):
    r = ws.regions[0]
    ref_err = 1e-4 * swept_area  # accuracy of the slice quadrature
    assert abs(r.measure.measure - swept_area) <= r.measure.error + ref_err, (r.measure, swept_area)
    assert r.measure.error < 1e-2 * swept_area


def test_slider_gain_is_the_closed_form_ratio(ws, arm, swept_area):
    g, d = ws.gain[1], ws.difference[1]
    ratio = swept_area / arm.area_2r()
    assert abs(g.value - ratio) <= g.error + 1e-4 * ratio
    assert abs(d[0] - (swept_area - arm.area_2r())) <= d[1] + 1e-4 * swept_area
    assert 1.45 < g.value < 1.52  # the slider buys about half as much area again


def test_measure_converges_under_grid_refinement(qprr_platform, arm):
    """The same estimator at 1e4, 1e5 and 4e5 samples: every error bar holds and they shrink."""
    A = arm.area_2r()
    errs = []
    for n in (10_000, 100_000, 400_000):
        r = workspace(qprr_platform, n_samples=n, variants=[], locked={"r0": 0.0}, hover=False).regions[0]
        assert abs(r.measure.measure - A) <= r.measure.error
        errs.append(r.measure.error)
    assert errs[0] > errs[1] > errs[2]


def test_hit_or_miss_monte_carlo_agrees(ws, arm):
    """Independent estimate: uniform points in a box, exact membership; the two agree within their error bars."""
    r = ws.regions[1]
    rng = np.random.default_rng(7)
    n, lo, hi = 2_000_000, -arm.rho_max, arm.rho_max
    x, z = rng.uniform(lo, hi, n), rng.uniform(lo, hi, n)
    p = arm.inside_2r(x, z).mean()
    box = (hi - lo) ** 2
    mc, mc_se = p * box, box * np.sqrt(p * (1 - p) / n)
    assert abs(mc - r.measure.measure) <= 3 * mc_se + r.measure.error
    # the covered cells are the region: the exact predicate at random points agrees with reachable() except within a cell of the boundary
    pts = np.column_stack([x[:200_000], np.zeros(200_000), z[:200_000] + arm.h])
    mine = reachable(ws, pts, region=1)
    exact = arm.inside_2r(x[:200_000], z[:200_000])
    h = r.occupancy[2]
    disagree = mine != exact
    bd = arm.boundary_2r()
    from scipy.spatial import cKDTree

    dist, _ = cKDTree(bd).query(pts[disagree][:, [0, 2]])
    assert np.all(dist < 1.5 * h)


def test_boundary_is_the_closed_form_boundary(ws, arm):
    """Hausdorff distance between the reported outline and the exact boundary of the 2R region, within 1.5 cells."""
    from scipy.spatial import cKDTree

    r = ws.regions[1]
    h = r.occupancy[2]
    ours = np.vstack([ln[:, [0, 2]] for ln in r.boundary])
    exact = arm.boundary_2r()
    d1, _ = cKDTree(exact).query(ours)
    d2, _ = cKDTree(ours).query(exact)
    assert d1.max() < 1.5 * h and d2.max() < 1.5 * h, (d1.max(), d2.max(), h)


@pytest.mark.parametrize("name", ["q-prr", "HEX-RRR"])
def test_points_reported_reachable_are_reached_by_ik(name):
    """Cell centres at least one cell inside the covered set: IK with the base held at the identity reaches them."""
    p = qprr.build(name) if name.isupper() else qprr.load(name)
    res = workspace(p, n_samples=50_000, variants=[], hover=False)
    r = res.regions[0]
    occ, o, h = r.occupancy
    inner = ndimage.binary_erosion(occ, structure=np.ones((3, 3), bool), iterations=2)
    cells = np.argwhere(inner)
    rng = np.random.default_rng(3)
    pick = cells[rng.choice(len(cells), 8, replace=False)]
    solver = IKSolver(p, "qp", {"levels": None, "require_hover": False, "max_iter": 200})
    d = p.data()
    for c in pick:
        target = r.origin + (o + (c + 0.5) * h) @ r.basis
        levels = [[BasePoseTask(p, pin.SE3.Identity())], [PositionTask(p, target)]]
        solver = IKSolver(p, "qp", {"levels": levels, "require_hover": False, "max_iter": 200})
        best = None
        for _ in range(6):  # a few starts: the arm's IK has branches
            xi0 = np.zeros(p.n_xi)
            xi0[6:] = rng.uniform(p.arm_lower, p.arm_upper)
            out = solver.solve(d, target, xi0)
            if best is None or out.position_error < best.position_error:
                best = out
            if out.position_error < 1e-7:
                break
        assert best.position_error < 1e-7, (target, best.status, best.position_error)
        assert best.within_limits


@pytest.mark.parametrize("name", ["borinot_flying_arm_2", "hextilt_flying_arm_5", "HEX-RRR"])
def test_random_configurations_land_in_the_measured_set(name):
    """Monte Carlo in joint space: end-effector positions of random configurations lie in the covered cells
    (dilated by one cell for points on the boundary), on every platform."""
    p = qprr.build(name) if name.isupper() else qprr.load(name)
    res = workspace(p, n_samples=60_000, variants=[], hover=False)
    from qprr.analysis import ArmChain

    ch = ArmChain(p)
    q = np.random.default_rng(11).uniform(p.arm_lower, p.arm_upper, (20_000, p.n_arm))
    pts = ch.frame_position(ch.pose(q), p.ee_frame)
    r = res.regions[0]
    occ, o, h = r.occupancy
    grown = ndimage.binary_dilation(occ, structure=np.ones((3,) * occ.ndim, bool))
    idx = np.floor(((pts - r.origin) @ r.basis.T - o) / h).astype(int)
    assert np.all(grown[tuple(idx.T)])


def test_a_second_independent_grid_agrees_within_error_bars():
    p = qprr.build("HEX-RRR")
    a = workspace(p, n_samples=80_000, variants=[], hover=True).regions[0]
    b = workspace(p, n_samples=150_000, variants=[], hover=True).regions[0]
    assert abs(a.measure.measure - b.measure.measure) <= a.measure.error + b.measure.error
    assert abs(a.hover_volume.measure - b.hover_volume.measure) <= a.hover_volume.error + b.hover_volume.error


def test_workspace_input_errors(qprr_platform):
    with pytest.raises(UnknownNameError, match="theta2"):
        workspace(qprr_platform, n_samples=1000, variants=[{"slider": 0.0}])
    with pytest.raises(LimitError, match="r0"):
        workspace(qprr_platform, n_samples=1000, locked={"r0": 1.0})
    with pytest.raises(InputError, match="n_samples"):
        workspace(qprr_platform, n_samples=-3)
    with pytest.raises(InputError, match="platform"):
        workspace("q-prr")
    with pytest.raises(TypeError):
        workspace(qprr_platform, n_sample=1000)  # unknown keyword
    with pytest.raises(InputError, match="n_shifts"):
        estimate_measure(np.zeros((5, 5, 2)), n_shifts=1)


def test_mirrored_zonotopes_are_those_of_the_mirrored_grid(qprr_platform):
    """The hover profile's mirror (s -> -s) is built by exact negations: bit for bit what cell_zonotopes + prepare
    give on the mirrored grid (the volume is the same as with the former two-grid computation)."""
    from qprr.analysis import ArmChain, make_grid
    from qprr.analysis.voxels import cell_zonotopes, prepare

    chain = ArmChain(qprr_platform)
    grid = make_grid(qprr_platform, 3000)
    pts = np.concatenate([chain.frame_position(chain.pose(q), qprr_platform.ee_frame) for _, q in grid.chunks()])
    P = np.column_stack([np.hypot(pts[:, 0], pts[:, 1]) * np.sign(pts[:, 0]), pts[:, 2]]).reshape(*grid.shape, 2)
    for grow in (True, False):
        z = prepare(*cell_zonotopes(P, grow_cells=grow))
        M = P.copy()
        M[..., 0] *= -1.0
        ref = prepare(*cell_zonotopes(M, grow_cells=grow))
        got = z.mirrored()
        for a, b in ((got.centre, ref.centre), (got.normals, ref.normals), (got.offset, ref.offset), (got.half, ref.half)):
            assert np.array_equal(a, b)


def test_covered_cells_do_not_depend_on_the_chunks(qprr_platform):
    """Skipping the cells and zonotopes already covered by earlier chunks leaves the occupancy unchanged."""
    from qprr.analysis import ArmChain, make_grid
    from qprr.analysis.voxels import _grid_frame, _zonotopes_of, covered_cells, default_cell

    chain = ArmChain(qprr_platform)
    for locked in ({}, {"r0": 0.0}):  # redundant (3 joints onto a plane) and not
        grid = make_grid(qprr_platform, 20_000, locked)
        pts = np.concatenate([chain.frame_position(chain.pose(q), qprr_platform.ee_frame) for _, q in grid.chunks()])
        P = pts[:, [0, 2]].reshape(*(n for n in grid.shape if n > 1), 2)
        (z,) = _zonotopes_of(P, False)
        h = default_cell(z)
        origin, shape = _grid_frame(np.vstack(z.bounds), h, np.array([0.37, 0.81]), 0.0)
        whole = covered_cells(z, h, origin, shape, chunk=z.size)  # one chunk: nothing skipped
        assert whole.any()
        for chunk in (97, 1000, 4096):
            assert np.array_equal(covered_cells(z, h, origin, shape, chunk=chunk), whole)


def test_options_object_and_keywords_agree(qprr_platform):
    from qprr.analysis import WorkspaceOptions

    a = workspace(qprr_platform, WorkspaceOptions(n_samples=5000, variants=[], hover=False))
    b = workspace(qprr_platform, n_samples=5000, variants=[], hover=False)
    c = workspace(qprr_platform, WorkspaceOptions(n_samples=9000), variants=[], hover=False, n_samples=5000)
    assert a.regions[0].measure == b.regions[0].measure == c.regions[0].measure
