"""Volume of revolution (qprr.analysis.voxels with revolve=True): the count on the half plane x >= 0 (weight 2 pi x)
against solids with exact volumes, against the former count over the whole plane (profile and mirror, weight pi |x|),
and the counting grid cell by cell."""

from __future__ import annotations

import math

import numpy as np
import pytest

import qprr
from qprr.analysis.voxels import CellImage, _count, _grid_frame, _union_bounds, covered_cells

from .test_analysis_workspace import _image_grids, _reference_cells


def _sheet(x0: float, x1: float, z0: float, z1: float, n: int, shear: float = 0.0) -> np.ndarray:
    """(n, n, 2) profile points [m] of a linear map onto the parallelogram with corners (x0, z0), (x1, z0) and edge
    (shear, z1 - z0): its cell zonotopes tile it exactly (no growth: the second differences vanish)."""
    u, v = np.meshgrid(np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, n), indexing="ij")
    return np.stack([x0 + (x1 - x0) * u + shear * v, z0 + (z1 - z0) * v], axis=-1)


def _disc(c: float, a: float, n: int) -> np.ndarray:
    """(n, 2 n - 1, 2) profile points [m] of the polar map (r, t) -> (c + r cos t, r sin t) onto the disc of radius a
    centred at (c, 0) (a non-redundant map: its cell zonotopes are grown)."""
    r, t = np.meshgrid(np.linspace(0.0, a, n), np.linspace(-np.pi, np.pi, 2 * n - 1), indexing="ij")
    return np.stack([c + r * np.cos(t), r * np.sin(t)], axis=-1)


def _disc_solid(c: float, a: float) -> float:
    """Volume [m^3] of the solid swept about the z axis by the disc of radius a centred at (c, 0), c >= 0: the torus
    2 pi^2 c a^2 when c >= a; otherwise 2 pi times the integral of x over the disc's part at x >= 0 (Pappus; the
    mirrored disc adds nothing there), (2/3)(a^2 - c^2)^(3/2) + c (pi a^2 / 2 + c sqrt(a^2 - c^2) + a^2 asin(c / a)),
    the sphere 4 pi a^3 / 3 at c = 0."""
    if c >= a:
        return 2.0 * math.pi**2 * c * a * a
    w = math.sqrt(a * a - c * c)
    return 2.0 * math.pi * (2.0 / 3.0 * w**3 + c * (math.pi * a * a / 2.0 + c * w + a * a * math.asin(c / a)))


CASES = {
    # a rectangle across the axis, x in [-0.3, 0.5]: with its mirror x in [-0.5, 0.5], a cylinder of radius 0.5
    "cylinder": (_sheet(-0.3, 0.5, 0.1, 0.4, 41), math.pi * 0.5**2 * 0.3, True),
    # a parallelogram at x > 0: 2 pi times its centroid's x (0.35 + 0.15 / 2) times its area 0.3 * 0.3
    "parallelogram ring": (_sheet(0.2, 0.5, -0.2, 0.1, 41, shear=0.15), 2.0 * math.pi * 0.425 * 0.09, True),
    "sphere": (_disc(0.0, 0.5, 81), 4.0 / 3.0 * math.pi * 0.5**3, False),
    "disc across the axis": (_disc(0.2, 0.5, 81), _disc_solid(0.2, 0.5), False),
    "torus, profile at x < 0": (_disc(-0.6, 0.25, 81), _disc_solid(0.6, 0.25), False),
}


def _full_plane(z, h: float, shift: np.ndarray) -> float:
    """The former count: every zonotope of the profile and of its mirror on a counting grid over the whole plane
    (framed by their bounding boxes, shifted by ``shift``), each covered centre x counting pi |x| h^2 [m^3]."""
    parts = (z, z.mirrored())
    origin, shape = _grid_frame(np.vstack(_union_bounds(parts)), h, shift, 0.0)
    occ = np.zeros(shape, dtype=bool)
    for part in parts:
        covered_cells(part, h, origin, shape, out=occ)
    x = origin[0] + (np.arange(shape[0]) + 0.5) * h
    return float((occ * (math.pi * np.abs(x) * h * h)[:, None]).sum())


@pytest.mark.parametrize("name", list(CASES))
def test_half_plane_count_is_the_full_plane_count_in_expectation(name):
    """Over 64 random shifts the half-plane count (2 pi x h^2 per centre at x >= 0) and the whole-plane count
    (pi |x| h^2 per centre, profile and mirror) have the same mean within 4 standard errors: both are unbiased for the
    same union of zonotopes.  Where that union is the profile exactly (linear maps) both means are the exact volume
    within 4 standard errors; for the discs the union exceeds the disc by O(dq^2), and estimate()'s error bar covers
    the closed form."""
    P, exact, tiled = CASES[name]
    image = CellImage(P, revolve=True)
    (z,) = CellImage(P).zonotopes()
    est = image.estimate()
    shifts = np.random.default_rng(11).uniform(0.0, 1.0, (64, 2))
    half = np.array([_count(image.zonotopes(), est.cell, s, True)[0] for s in shifts])
    full = np.array([_full_plane(z, est.cell, s) for s in shifts])
    se_half, se_full = (v.std(ddof=1) / math.sqrt(v.size) for v in (half, full))
    assert se_half > 0.0
    assert abs(half.mean() - full.mean()) <= 4.0 * math.hypot(se_half, se_full), (name, half.mean(), full.mean(), se_half, se_full)
    if tiled:
        assert abs(half.mean() - exact) <= 4.0 * se_half, (name, half.mean(), exact, se_half)
        assert abs(full.mean() - exact) <= 4.0 * se_full + 1e-12 * exact, (name, full.mean(), exact, se_full)
    else:  # (the tiled profiles' edges along z make the half-plane count's spread, and its error bar, a few % there)
        assert est.error < 1e-2 * exact
    assert abs(est.measure - exact) <= est.error, (name, est, exact)


def _profiles(platform):
    """(label, profile grid (s, z)) of the Q-PRR's hover profile (across the axis), a disc across the axis and one at x > 0."""
    _, prof, _ = _image_grids(platform, 6000)
    return [("q-prr hover profile", prof), ("disc across the axis", _disc(0.2, 0.5, 31)), ("disc at x > 0", _disc(0.6, 0.25, 31))]


def test_counting_grid_holds_every_centre_at_x_ge_0_and_none_below():
    """The cells counted are those of the half plane: the first centre is at x = shift_0 h in [0, h), the last one
    beyond every zonotope; the cells the profile's zonotopes tested cover are, cell by cell, those whose centre lies in
    any zonotope of the profile, likewise for the mirror's (the zonotopes left untested cover no centre at x >= 0), and
    the volume is 2 pi x h^2 summed over the covered centres."""
    p = qprr.load("q-prr")
    for label, P in _profiles(p):
        image = CellImage(P, revolve=True)
        (z,) = CellImage(P).zonotopes()
        every = (z, z.mirrored())
        h = image.estimate().cell
        for shift in (np.array([0.0, 0.5]), np.array([0.37, 0.81]), np.array([0.999, 0.2])):
            v, occ, origin = _count(image.zonotopes(), h, shift, True)
            x = origin[0] + (np.arange(occ.shape[0]) + 0.5) * h
            assert abs(x[0] - shift[0] * h) <= 1e-12 * h and x[0] < h, label
            assert x[-1] > max(float(part.box[1][0].max()) for part in every), label
            ref = np.zeros_like(occ)
            for part, whole in zip(image.zonotopes(), every):  # the profile's, the mirror's: each part alone
                own = _reference_cells(whole, h, origin, occ.shape)
                assert np.array_equal(covered_cells(part, h, origin, occ.shape), own), label
                ref |= own
            assert ref.any() and np.array_equal(occ, ref), label
            assert v == pytest.approx(float((occ * (2.0 * math.pi * np.abs(x) * h * h)[:, None]).sum()), rel=1e-14)


def test_a_profile_and_its_mirror_give_the_same_volume_bit_for_bit():
    """The solid does not depend on the side the profile is drawn on: the profile (s, z) and (-s, z) give the same
    estimate and the same counted cells, bit for bit (the zonotopes counted are the same, in another order), alone and
    with a valid mask."""
    p = qprr.load("q-prr")
    for label, P in _profiles(p):
        M = P.copy()
        M[..., 0] *= -1.0
        a, occ_a = CellImage(P, revolve=True).estimate(return_occupancy=True)
        b, occ_b = CellImage(M, revolve=True).estimate(return_occupancy=True)
        assert a == b and np.array_equal(occ_a[0], occ_b[0]) and np.array_equal(occ_a[1], occ_b[1]), label
        valid = np.random.default_rng(2).uniform(size=P.shape[:-1]) < 0.5 ** (1.0 / 2 ** (P.ndim - 1))
        assert CellImage(P, revolve=True).estimate_pair(valid) == CellImage(M, revolve=True).estimate_pair(valid), label
