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


def _image_grids(platform, n: int, locked=None):
    """(points in B (x, z), hover profile (s, z)) of the end effector over the joint grid, one axis per free joint."""
    from qprr.analysis import ArmChain, make_grid

    chain = ArmChain(platform)
    grid = make_grid(platform, n, locked)
    pts = np.concatenate([chain.frame_position(chain.pose(q), platform.ee_frame) for _, q in grid.chunks()])
    shape = tuple(k for k in grid.shape if k > 1)
    prof = np.column_stack([np.hypot(pts[:, 0], pts[:, 1]) * np.sign(pts[:, 0]), pts[:, 2]])
    return pts, prof.reshape(*shape, 2), shape


def _reference_cells(z, h, origin, shape):
    """The occupancy of :func:`covered_cells` by its definition, zonotope by zonotope and cell by cell: a cell is covered
    when its centre, written as the box's first candidate centre (lo + 1/2) h plus its offset in cells, passes every
    facet test |n . (x - centre)| <= offset."""
    import itertools

    occ = np.zeros(shape, dtype=bool)
    d = z.centre.shape[1]
    for i in range(z.size):
        c, N, off, half = z.centre[i], z.normals[i], z.offset[i], z.half[i]
        lo = [max(int(np.ceil((c[k] - half[k] - origin[k]) / h - 0.5)), 0) for k in range(d)]
        hi = [min(int(np.floor((c[k] + half[k] - origin[k]) / h - 0.5)), shape[k] - 1) for k in range(d)]
        rel = [origin[k] + (lo[k] + 0.5) * h - c[k] for k in range(d)]
        for cell in itertools.product(*[range(lo[k], hi[k] + 1) for k in range(d)]):
            inside = True
            for j in range(N.shape[0]):
                base = N[j, 0] * rel[0]
                for k in range(1, d):
                    base += N[j, k] * rel[k]
                proj = base + (h * N[j, 0]) * float(cell[0] - lo[0])
                for k in range(1, d):
                    proj += (h * N[j, k]) * float(cell[k] - lo[k])
                inside &= bool(abs(proj) <= off[j])
            occ[cell] |= inside
    return occ


@pytest.mark.parametrize("locked", [{}, {"r0": 0.0}], ids=["redundant", "planar-2R"])
def test_covered_cells_are_those_of_the_cell_by_cell_definition(qprr_platform, locked):
    """The batched count (candidate boxes by coordinate rows, one-candidate boxes in rounds skipping covered cells,
    any batching) marks exactly the cells the zonotope-by-zonotope definition marks."""
    from qprr.analysis.voxels import CellImage, _grid_frame, covered_cells, default_cell

    _, P, _ = _image_grids(qprr_platform, 6000, locked)
    for revolve in (False, True):
        for z in CellImage(P, revolve).zonotopes():
            h = default_cell(z)
            origin, shape = _grid_frame(np.vstack(z.bounds), h, np.array([0.37, 0.81]), 0.0)
            ref = _reference_cells(z, h, origin, shape)
            assert ref.any()
            for chunk in (97, 4096, 1 << 20):
                assert np.array_equal(covered_cells(z, h, origin, shape, chunk=chunk), ref)


@pytest.mark.parametrize("name,locked", [("q-prr", {}), ("q-prr", {"r0": 0.0}), ("hextilt_flying_arm_5", {})])
def test_zonotope_rows_are_those_of_cell_zonotopes_and_prepare(name, locked):
    """The zonotopes the measures use (built by coordinate rows, the collision-free subset taken from the whole grid's)
    equal, bit for bit, those of cell_zonotopes + prepare on the grid, with and without a valid mask: redundant
    (3 joints onto a plane, no growth), planar 2R (growth), a spatial 5-joint arm (cross-product normals)."""
    from qprr.analysis._common import affine_span
    from qprr.analysis.voxels import CellImage, cell_zonotopes, prepare

    p = qprr.load(name)
    pts, prof, shape = _image_grids(p, 4000, locked)
    origin, basis = affine_span(pts)
    dim = basis.shape[0]
    P = ((pts - origin) @ basis.T).reshape(*shape, dim)
    valid = np.random.default_rng(3).uniform(size=shape) > 0.03  # a cell keeps its 2^k corners valid often enough
    grow = len(shape) <= dim
    for grid in (P, prof) if dim == 2 else (P,):
        image = CellImage(grid)
        for mask in (None, valid):
            (got,) = image.zonotopes(mask)
            ref = prepare(*cell_zonotopes(grid, mask, grow_cells=grow))
            assert got.size == ref.size > 0
            for a, b in ((got.centre, ref.centre), (got.normals, ref.normals), (got.offset, ref.offset), (got.half, ref.half)):
                assert np.array_equal(a, b)


def test_collision_free_measures_are_those_of_the_measure_with_a_valid_mask(qprr_platform):
    """The measures of the workspace (each image's two from one counting pass) equal estimate_measure of the whole image
    and, over the cells whose corners are all collision-free, the estimate on the whole image's counting grid (its
    cell side, its frame), computed on their own."""
    from qprr.analysis.voxels import CellImage

    res = workspace(qprr_platform, n_samples=20_000, collision=True)
    for r in res.regions:
        shape = tuple(k for k in r.grid.shape if k > 1)
        valid = r.collision_free.reshape(shape)
        assert 0 < valid.sum() < valid.size
        P, prof = r.coords.reshape(*shape, r.dim), r.profile.reshape(*shape, 2)
        assert r.measure == estimate_measure(P)
        assert r.hover_volume == estimate_measure(prof, revolve=True)
        assert r.free_measure == CellImage(P).estimate(cell=r.measure.cell, valid=valid, shared_grid=True)
        assert r.free_hover_volume == CellImage(prof, revolve=True).estimate(cell=r.hover_volume.cell, valid=valid, shared_grid=True)


def _spherical_grid(n: int) -> np.ndarray:
    """(n, n, n, 3) points [m] of a non-redundant 3-joint map onto a spherical-shell sector (radius 0.5..1 m, polar
    angle 0.3..1.4 rad, azimuth -1..2 rad): a 3-D image whose cell zonotopes are grown."""
    r, th, ph = np.meshgrid(np.linspace(0.5, 1.0, n), np.linspace(0.3, 1.4, n), np.linspace(-1.0, 2.0, n), indexing="ij")
    return np.stack([r * np.sin(th) * np.cos(ph), r * np.sin(th) * np.sin(ph), r * np.cos(th)], axis=-1)


def _pair_images(platform, name: str):
    """(label, joint grid of image points, revolve) of the images estimate_pair is checked on."""
    from qprr.analysis._common import affine_span

    if name == "sphere":
        return [("sphere, d = 3, grown cells", _spherical_grid(15), False)]
    locked = {"r0": 0.0} if name == "q-prr-2R" else {}
    pts, prof, shape = _image_grids(platform if name.startswith("q-prr") else qprr.load(name), 4000, locked)
    origin, basis = affine_span(pts)
    P = ((pts - origin) @ basis.T).reshape(*shape, basis.shape[0])
    out = [(f"{name} in B, d = {basis.shape[0]}", P, False)]
    if basis.shape[0] == 2:
        out.append((f"{name} hover profile", prof, True))
    return out


def _masks(shape: tuple) -> dict:
    """Valid masks of a joint grid: random (about half the cells keep all 2^k corners), all valid, none, and a
    checkerboard (half the points valid, but every cell has an invalid corner: no valid cell)."""
    p = 0.5 ** (1.0 / 2 ** len(shape))
    idx = np.indices(shape).sum(axis=0)
    return {
        "random": np.random.default_rng(5).uniform(size=shape) < p,
        "all": np.ones(shape, dtype=bool),
        "none": np.zeros(shape, dtype=bool),
        "checkerboard": idx % 2 == 0,
    }


@pytest.mark.parametrize("name", ["q-prr", "q-prr-2R", "hextilt_flying_arm_5", "sphere"])
def test_estimate_pair_is_the_two_estimates_bit_for_bit(qprr_platform, name):
    """One counting pass for both measures gives, bit for bit, the whole image's estimate() (and its occupancy) and
    the valid cells' estimate on the whole image's counting grid; its cells are a subset of the whole image's (so the
    counts are ordered shift by shift), and it agrees with the estimate on a grid fitted to the valid cells within
    their error bars (both unbiased).  No valid cell: None, where estimate() refuses."""
    from qprr.analysis.voxels import CellImage

    for label, grid, revolve in _pair_images(qprr_platform, name):
        shape = grid.shape[:-1]
        ref, ref_occ = CellImage(grid, revolve).estimate(return_occupancy=True)
        for kind, valid in _masks(shape).items():
            whole, free, occ = CellImage(grid, revolve).estimate_pair(valid, return_occupancy=True)
            assert whole == ref, (label, kind)
            assert all(np.array_equal(a, b) for a, b in zip(occ, ref_occ)) and occ[2] == ref_occ[2]
            if kind in ("none", "checkerboard"):
                assert free is None, (label, kind)
                with pytest.raises(InputError):
                    CellImage(grid, revolve).estimate(valid=valid)
                continue
            alone = CellImage(grid, revolve).estimate(cell=whole.cell, valid=valid, shared_grid=True)
            assert free == alone, (label, kind)
            assert free.cell == whole.cell and free.raw <= whole.raw and free.coarse <= whole.coarse
            if kind == "all":
                assert free == whole  # the same zonotopes on the same grid
                continue
            assert 0 < free.n_cells < whole.n_cells
            fitted = CellImage(grid, revolve).estimate(valid=valid)
            assert abs(free.measure - fitted.measure) <= free.error + fitted.error, (label, free, fitted)


def test_estimate_pair_refuses_bad_masks(qprr_platform):
    from qprr.analysis.voxels import CellImage

    _, P, _ = _pair_images(qprr_platform, "q-prr")[1]
    image = CellImage(P, True)
    with pytest.raises(InputError, match="valid must have the grid's shape"):
        image.estimate_pair(np.ones(P.shape[:-1])[:-1])
    with pytest.raises(InputError, match="valid mask"):
        image.estimate_pair(None)
    with pytest.raises(InputError, match="n_shifts"):
        image.estimate_pair(np.ones(P.shape[:-1], dtype=bool), n_shifts=1)


def test_options_object_and_keywords_agree(qprr_platform):
    from qprr.analysis import WorkspaceOptions

    a = workspace(qprr_platform, WorkspaceOptions(n_samples=5000, variants=[], hover=False))
    b = workspace(qprr_platform, n_samples=5000, variants=[], hover=False)
    c = workspace(qprr_platform, WorkspaceOptions(n_samples=9000), variants=[], hover=False, n_samples=5000)
    assert a.regions[0].measure == b.regions[0].measure == c.regions[0].measure


def test_drawing_data_are_computed_when_read_and_travel_with_the_region(ws):
    """outline, boundary and hover_occupancy: computed on first read from the region's samples (the redundant Q-PRR:
    the finer cells its samples fill), the same after a pickle round trip and on a dataclasses.replace copy."""
    import dataclasses
    import pickle

    from qprr.analysis.voxels import display_occupancy

    r = dataclasses.replace(ws.regions[0])  # a copy nothing has read yet (the fixture is shared)
    assert r.redundant and not {"outline", "boundary", "hover_occupancy"} & set(vars(r))
    fine = display_occupancy(r.coords)
    expected = fine if fine[2] < r.occupancy[2] else r.occupancy
    assert r.outline[2] == expected[2] and np.array_equal(r.outline[0], expected[0])
    assert len(r.boundary) > 0 and all(ln.shape[1] == 3 for ln in r.boundary)
    hover = display_occupancy(np.vstack([r.profile, r.profile * np.array([-1.0, 1.0])]))
    assert np.array_equal(r.hover_occupancy[0], hover[0])
    for copy in (pickle.loads(pickle.dumps(r)), dataclasses.replace(r, label="copy")):
        assert np.array_equal(copy.outline[0], r.outline[0]) and np.array_equal(copy.hover_occupancy[0], r.hover_occupancy[0])
        assert all(np.array_equal(a, b) for a, b in zip(copy.boundary, r.boundary))
