"""Length, area or volume of the image of a joint-space grid, by counting covered cell centres.

A map sends the arm's joint box Q to a set W = f(Q) (a workspace, a CoG region) of dimension
d = 1, 2 or 3.  It is known through the images f(q) of a joint grid: ``points_grid`` of shape
(n_1, ..., n_k, d), one axis per free joint.  Each grid cell [q, q + dq] maps to a small
curved patch; W is the union of the patches.

Estimator (:func:`estimate_measure`), "voxel counting" made unbiased:

1. Every grid cell is replaced by a zonotope, its affine model: from the corner image f(q) and
   the edge vectors g_j = f(q + dq_j) - f(q), Z = f(q) + sum_j [0, 1] g_j.  When the joint
   count k equals d (a non-redundant map, the cells tile W) each zonotope is grown by the
   distance E the curved patch can stray from it (the mixed second differences
   |f(q + dq_i + dq_j) - f(q + dq_i) - f(q + dq_j) + f(q)| summed over pairs, plus an eighth of
   the second differences along each axis), so that neighbouring zonotopes leave no gap: their
   union exceeds W by O(dq^2).  When k > d (redundant: the cells overlap many times over, the
   Q-PRR with its slider) the union closes itself and the zonotopes are not grown; it then
   differs from W by O(dq^2) at the boundary, of either sign.
2. Cells of side h on a randomly shifted grid are counted when their centre lies in that
   union.  For a uniformly random shift the expected count times h^d equals the measure of
   the union exactly (whatever h), so the only bias is the O(dq^2) of step 1.
3. Convergence in the grid size: the same count on the grid with every other joint value
   (steps 2 dq, same ends: grids have an odd number of values) estimates the discretisation
   error as |count(dq) - count(2 dq)| / 2 (what Richardson extrapolation gives for convergence
   of order log2(3) ~ 1.6; O(dq^2) is expected).  The estimate is the count on the full grid;
   its error bar is that discretisation error plus twice the standard error over the shifts.
   Tested against closed forms (the planar 2R and 2R + P arm of the Q-PRR, and the solid of
   revolution of the 2R one) from 1e4 to 1e6 samples.  For the solid, over 40 seeds, the error
   bar held 39 times at 2e5 samples and 37 times at 1e6 (misses up to 1.6 bars: with 4 shifts,
   2 standard errors is about a 86 % interval, and there the shifts' spread makes most of it).

Generic in the joint count k >= d (redundant arms such as the Q-PRR with its slider included:
the zonotopes of all cells overlap); cells whose edge vectors do not span d dimensions (at a
singular configuration) are flat and skipped.  With ``revolve=True`` the points are profile
coordinates (s, z) of a set turning about the z axis, |s| = rho the distance to the axis (s may
be signed, see :func:`qprr.analysis.workspace.hover_profile`).  The solid's meridian section is
the union U of the profile's zonotopes and of their mirror images (s -> -s; so the axis is no
boundary), symmetric about x = 0; its volume is pi times the integral of |x| over U (Pappus),
that is 2 pi times the integral of x over the half U+ = U with x >= 0.  Only that half is
counted: the counting grid's cells have their centres at x = (i + u) h, i = 0, 1, ... (u the
shift along x, uniform in [0, 1): no centre with x < 0, none with x >= 0 left out; a cell
straddling the axis counts when its centre is at x >= 0) and each covered centre counts
2 pi x h^2, whose expected total over the shift is the volume exactly (as in step 2).  The
zonotopes tested are the profile's whose bounding box reaches x >= 0 and the mirror images of
those reaching x <= 0 (about half of the profile's zonotopes and of their mirrors): the others
hold no centre of the half plane.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ..errors import InputError

UNITS = {1: "m", 2: "m^2", 3: "m^3"}


@dataclass(frozen=True)
class MeasureEstimate:
    """A length, area or volume estimated by :func:`estimate_measure`.

    ``measure`` [unit] and its error bar ``error``; ``raw`` the count on the full grid (mean over
    the shifts) with its standard error ``stderr``, ``coarse`` the count on the grid with twice
    the step, ``cell`` the counting cell side h [m], ``n_cells`` the joint-grid cells used.
    """

    dim: int
    measure: float
    error: float
    unit: str
    raw: float
    stderr: float
    coarse: float
    cell: float
    n_cells: int

    def __str__(self) -> str:
        return f"{self.measure:.6g} +- {self.error:.2g} {self.unit}"


# ---------------------------------------------------------------------------- cell zonotopes
def _shifted(a: np.ndarray, axes: list[int], hi: set[int]) -> np.ndarray:
    """a[..., 1: on the axes in hi, :-1 on the other axes of ``axes``, ...]."""
    sl = [slice(None)] * a.ndim
    for ax in axes:
        sl[ax] = slice(1, None) if ax in hi else slice(0, -1)
    return a[tuple(sl)]


def cell_zonotopes(points_grid: np.ndarray, valid: np.ndarray | None = None, *, grow_cells: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(corner (m, d), generators (m, k, d), growth E (m,)) of the m grid cells (see the module docstring).

    ``valid``: a boolean grid (the grid's shape): only cells whose 2^k corners are all valid are kept.
    ``grow_cells``: compute E (False: zeros, what a redundant map uses).
    """
    P = np.asarray(points_grid, dtype=float)
    axes = [a for a in range(P.ndim - 1) if P.shape[a] > 1]
    if not axes:
        raise InputError("the grid has no free axis: its image is a point")
    if valid is not None:
        keep = _valid_cells(valid, axes)
        c, g, e = cell_zonotopes(P, grow_cells=grow_cells)
        return c[keep], g[keep], e[keep]
    d = P.shape[-1]
    base = _shifted(P, axes, set())
    corner = base.reshape(-1, d)
    gens = np.empty((corner.shape[0], len(axes), d))
    by_cell = gens.reshape(base.shape[:-1] + (len(axes), d))  # a view: each generator written in place
    for j, a in enumerate(axes):
        np.subtract(_shifted(P, axes, {a}), base, out=by_cell[..., j, :])
    grow = _growth(P, axes) if grow_cells else np.zeros(corner.shape[0])
    return corner, gens, grow


def _valid_cells(valid: np.ndarray, axes: list[int]) -> np.ndarray:
    """(m,) bool: the cells (C order) of a grid whose 2^k corners are all True in the boolean grid ``valid``."""
    V = np.asarray(valid, dtype=bool)[..., None]
    keep = np.ones(_shifted(V, axes, set()).shape, dtype=bool)
    for r in range(len(axes) + 1):
        for sub in itertools.combinations(axes, r):
            keep &= _shifted(V, axes, set(sub))
    return keep.reshape(-1)


def _growth(P: np.ndarray, axes: list[int]) -> np.ndarray:
    """E (m,) of every cell of the grid ``P`` (see the module docstring), in the cells' C order."""
    d = P.shape[-1]
    grow = np.zeros(_shifted(P[..., 0], axes, set()).size)
    for a, b in itertools.combinations(axes, 2):
        mixed = _shifted(P, axes, {a, b}) - _shifted(P, axes, {a}) - _shifted(P, axes, {b}) + _shifted(P, axes, set())
        mixed = mixed.reshape(-1, d)
        grow += np.sqrt(_rowdot(mixed, mixed))
    for a in axes:
        if P.shape[a] < 3:
            continue
        second = np.diff(P, n=2, axis=a)  # at interior nodes 1..n-2 along a
        mag = np.sqrt(_rowdot(second, second))
        # the cell [i, i + 1] along a takes the larger of the second differences at its two nodes
        pad = np.concatenate([np.take(mag, [0], axis=a), mag, np.take(mag, [-1], axis=a)], axis=a)
        cellmag = np.maximum(np.take(pad, range(pad.shape[a] - 1), axis=a), np.take(pad, range(1, pad.shape[a]), axis=a))
        sl = [slice(None)] * cellmag.ndim
        for ax in axes:
            if ax != a:
                sl[ax] = slice(0, -1)
        grow += cellmag[tuple(sl)].reshape(-1) / 8.0
    return grow


def _cell_columns(P: np.ndarray, grow_cells: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`cell_zonotopes` (no ``valid``) by columns: (corner (d, m), generators (k, d, m), growth (m,)), the same
    numbers laid out for contiguous per-coordinate arithmetic."""
    axes = [a for a in range(P.ndim - 1) if P.shape[a] > 1]
    if not axes:
        raise InputError("the grid has no free axis: its image is a point")
    d = P.shape[-1]
    cells = _shifted(P, axes, set()).shape[:-1]
    m = int(np.prod(cells))
    corner = np.empty((d, m))
    gens = np.empty((len(axes), d, m))
    for c in range(d):
        Pc = np.ascontiguousarray(P[..., c])  # one coordinate, contiguous: the differences below read it along its axes
        base = _shifted(Pc, axes, set())
        corner[c].reshape(cells)[...] = base
        for j, a in enumerate(axes):
            np.subtract(_shifted(Pc, axes, {a}), base, out=gens[j, c].reshape(cells))
    grow = _growth(P, axes) if grow_cells else np.zeros(m)
    return corner, gens, grow


def _normals(gens: np.ndarray) -> np.ndarray:
    """Facet normals (m, f, d) of zonotopes with generators (m, k, d): perp of each generator in 2-D,
    cross products of generator pairs in 3-D, the axis in 1-D."""
    m, k, d = gens.shape
    if d == 1:
        return np.ones((m, 1, 1))
    if d == 2:
        return np.stack([-gens[:, :, 1], gens[:, :, 0]], axis=-1)
    pairs = list(itertools.combinations(range(k), 2))
    return np.stack([np.cross(gens[:, i], gens[:, j]) for i, j in pairs], axis=1)


def _spanning(gens: np.ndarray, rel: float = 1e-9) -> np.ndarray:
    """Cells whose generators span R^d (a non-flat zonotope): det of the d x d Gram matrix > (rel |g|_max^2)^d."""
    m, k, d = gens.shape
    if k < d:
        return np.zeros(m, dtype=bool)
    scale2 = _rowdot(gens[:, 0, :], gens[:, 0, :])
    for j in range(1, k):
        scale2 = np.maximum(scale2, _rowdot(gens[:, j, :], gens[:, j, :]))
    gram = np.empty((m, d, d))
    for a in range(d):
        for b in range(a, d):
            gram[:, a, b] = gram[:, b, a] = _rowdot(gens[:, :, a], gens[:, :, b])
    if d == 1:
        det = gram[:, 0, 0]
    elif d == 2:
        det = gram[:, 0, 0] * gram[:, 1, 1] - gram[:, 0, 1] ** 2
    else:
        det = np.linalg.det(gram)
    return det > (rel * np.maximum(scale2, 1e-300)) ** d


@dataclass(frozen=True)
class Zonotopes:
    """Grown cell zonotopes ready for point tests, stored by coordinate (contiguous rows for the counts):
    ``centre_cols`` (d, m), facet normals ``normal_cols`` (f, d, m) with offsets ``offset_cols`` (f, m) (x is inside
    iff |n . (x - centre)| <= offset for every facet), bounding-box half-widths ``half_cols`` (d, m).  ``centre``,
    ``normals``, ``offset``, ``half`` are the same numbers per zonotope ((m, d), (m, f, d), (m, f), (m, d) views)."""

    centre_cols: np.ndarray
    normal_cols: np.ndarray
    offset_cols: np.ndarray
    half_cols: np.ndarray

    @staticmethod
    def of_rows(centre: np.ndarray, normals: np.ndarray, offset: np.ndarray, half: np.ndarray) -> Zonotopes:
        """From per-zonotope arrays (m, d), (m, f, d), (m, f), (m, d)."""
        cols = (centre.T, normals.transpose(1, 2, 0), offset.T, half.T)
        return Zonotopes(*(np.ascontiguousarray(a) for a in cols))

    @property
    def centre(self) -> np.ndarray:
        return self.centre_cols.T

    @property
    def normals(self) -> np.ndarray:
        return self.normal_cols.transpose(2, 0, 1)

    @property
    def offset(self) -> np.ndarray:
        return self.offset_cols.T

    @property
    def half(self) -> np.ndarray:
        return self.half_cols.T

    @property
    def size(self) -> int:
        return int(self.centre_cols.shape[1])

    @functools.cached_property
    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """(centre - half, centre + half) (d, m): the bounding boxes' corners, the same for every shift's count."""
        return self.centre_cols - self.half_cols, self.centre_cols + self.half_cols

    @functools.cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lowest, highest) corner of the union of the bounding boxes (d,), computed once for every shift's count."""
        low, high = self.box
        return np.array([float(r.min()) for r in low]), np.array([float(r.max()) for r in high])

    def take(self, index: np.ndarray) -> Zonotopes:
        """The zonotopes ``index`` (integer array) of this set, numbers unchanged."""

        def rows(a: np.ndarray) -> np.ndarray:  # row by row: numpy's gather along a contiguous row is the fast one
            flat = a.reshape(-1, a.shape[-1])
            out = np.empty((flat.shape[0], index.size))
            for r in range(flat.shape[0]):
                np.take(flat[r], index, out=out[r])
            return out.reshape(a.shape[:-1] + (index.size,))

        return Zonotopes(rows(self.centre_cols), rows(self.normal_cols), rows(self.offset_cols), rows(self.half_cols))

    def mirrored(self) -> Zonotopes:
        """The zonotopes mirrored about the plane x_0 = 0, exactly (negations): what :func:`prepare` gives for the
        cells of the mirrored grid (2-D normals (-g_1, g_0) become (n_0, -n_1); offsets and half-widths unchanged)."""
        if self.normal_cols.shape[1] != 2:
            raise InputError("mirrored zonotopes are implemented for profiles (d = 2) only")
        c = self.centre_cols.copy()
        c[0] *= -1.0
        N = self.normal_cols.copy()
        N[:, 1] *= -1.0
        return Zonotopes(c, N, self.offset_cols, self.half_cols)


def _rowdot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Sum over the last (short) axis of a * b, without numpy's slow short-axis reduction."""
    out = a[..., 0] * b[..., 0]
    for k in range(1, a.shape[-1]):
        out += a[..., k] * b[..., k]
    return out


def prepare(corner: np.ndarray, gens: np.ndarray, grow: np.ndarray) -> Zonotopes:
    """:class:`Zonotopes` of the cells of :func:`cell_zonotopes` that span their dimension."""
    keep = _spanning(gens)
    if not keep.all():
        corner, gens, grow = corner[keep], gens[keep], grow[keep]
    gsum, gabs = gens[:, 0, :].copy(), np.abs(gens[:, 0, :])
    for k in range(1, gens.shape[1]):
        gsum += gens[:, k, :]
        gabs += np.abs(gens[:, k, :])
    centre = corner + 0.5 * gsum
    N = _normals(gens)
    nn = np.sqrt(_rowdot(N, N))
    offset = grow[:, None] * nn
    for k in range(gens.shape[1]):
        offset += 0.5 * np.abs(_rowdot(N, gens[:, None, k, :]))
    half = 0.5 * gabs + grow[:, None]
    return Zonotopes.of_rows(centre, N, offset, half)


def _coldot(a: np.ndarray, b: np.ndarray, out: np.ndarray | None = None, tmp: np.ndarray | None = None) -> np.ndarray:
    """Sum over the first (short) axis of a * b: :func:`_rowdot` of the transposed arrays, term for term
    (``out``, ``tmp``: buffers of one row's shape to write into, fewer fresh arrays)."""
    out = np.multiply(a[0], b[0], out=out)
    for k in range(1, a.shape[0]):
        out += np.multiply(a[k], b[k], out=tmp)
    return out


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products (3, m) of the columns of a, b (3, m), with the products and differences of ``np.cross``."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _prepare_columns(corner: np.ndarray, gens: np.ndarray, grow: np.ndarray) -> tuple[Zonotopes, np.ndarray]:
    """(:func:`prepare` of the cells of :func:`_cell_columns`, the indices of the cells kept): the same arithmetic,
    operation for operation, on contiguous coordinate rows (tests compare the two bit for bit)."""
    K, d, m = gens.shape
    if K < d:  # no cell spans R^d
        return Zonotopes(np.empty((d, 0)), np.empty((0, d, 0)), np.empty((0, 0)), np.empty((d, 0))), np.empty(0, dtype=np.int64)
    tmp, buf = np.empty(m), np.empty(m)
    scale2 = _coldot(gens[0], gens[0], tmp=tmp)
    for j in range(1, K):
        np.maximum(scale2, _coldot(gens[j], gens[j], buf, tmp), out=scale2)
    gram = {(a, b): _coldot(gens[:, a], gens[:, b], tmp=tmp) for a in range(d) for b in range(a, d)}
    if d == 1:
        det = gram[0, 0]
    elif d == 2:  # g00 g11 - g01^2, in place
        det = np.multiply(gram[0, 0], gram[1, 1], out=gram[0, 0])
        det -= np.multiply(gram[0, 1], gram[0, 1], out=gram[0, 1])
    else:
        G = np.empty((m, d, d))
        for (a, b), v in gram.items():
            G[:, a, b] = G[:, b, a] = v
        det = np.linalg.det(G)
    del gram
    keep = det > (1e-9 * np.maximum(scale2, 1e-300)) ** d
    kept = np.flatnonzero(keep)
    if kept.size < m:
        corner, gens, grow = corner[:, kept], gens[:, :, kept], grow[kept]
    gsum, gabs = gens[0].copy(), np.abs(gens[0])
    for k in range(1, K):
        gsum += gens[k]
        gabs += np.abs(gens[k])
    gsum *= 0.5
    centre = np.add(corner, gsum, out=gsum)
    if d == 1:
        N = np.ones((1, 1, kept.size))
    elif d == 2:
        N = np.empty((K, 2, kept.size))
        np.negative(gens[:, 1], out=N[:, 0])
        N[:, 1] = gens[:, 0]
    else:  # numpy's cross product, term for term
        N = np.stack([_cross(gens[i], gens[j]) for i, j in itertools.combinations(range(K), 2)])
    offset = np.empty((N.shape[0], kept.size))
    tmp, buf = tmp[: kept.size], buf[: kept.size]
    for f in range(N.shape[0]):  # grow |n_f| + sum_k |n_f . g_k| / 2
        np.sqrt(_coldot(N[f], N[f], buf, tmp), out=buf)
        np.multiply(grow, buf, out=offset[f])
        for k in range(K):
            _coldot(N[f], gens[k], buf, tmp)
            np.abs(buf, out=buf)
            buf *= 0.5
            offset[f] += buf
    gabs *= 0.5
    gabs += grow
    return Zonotopes(centre, N, offset, gabs), kept


def covered_cells(
    z: Zonotopes,
    h: float,
    origin: np.ndarray,
    shape: tuple[int, ...],
    chunk: int = 1 << 20,
    out: np.ndarray | None = None,
    scratch: np.ndarray | None = None,
) -> np.ndarray:
    """Boolean grid of the cells of side ``h`` (lower corner ``origin``) whose centre lies in a grown zonotope
    (``out``: a grid of that shape to add them to, e.g. the cells of other zonotopes of the same set).

    A candidate cell is one whose centre lies in a zonotope's bounding box; it is covered when
    |n_j . (x - centre)| <= offset_j for every facet j, evaluated as the projection of the box's first
    candidate centre plus h n_j . (its offset in cells).  The occupancy is an OR over the zonotopes, so a
    candidate cell already covered needs no test: the boxes holding one candidate are tested in rounds (a
    sample spread over the set first), each round skipping the cells the earlier ones covered (a redundant
    map covers each cell many times over).  ``chunk``: candidates tested per batch (memory only); ``scratch``: a float
    buffer (2 d, >= z.size) to work in (the same one for every shift's count: fewer fresh arrays)."""
    d = z.centre.shape[1]
    occ = np.zeros(shape, dtype=bool) if out is None else out
    flat_occ = occ.reshape(-1)  # a view: occ is C-contiguous
    which, lo, span = _candidate_boxes(z, h, origin, shape, scratch)
    counts = span[0].copy()
    for k in range(1, d):
        counts *= span[k]
    multi = np.flatnonzero(counts > 1)
    ends = np.cumsum(counts[multi])
    start = 0
    while start < multi.size:  # boxes of several candidates, in batches of about ``chunk`` candidates
        stop = max(int(np.searchsorted(ends, ends[start] - counts[multi[start]] + chunk, side="right")), start + 1)
        sel = multi[start:stop]
        _cover(z, h, origin, which[sel], lo[:, sel], span[:, sel], counts[sel], occ)
        start = stop
    single = np.flatnonzero(counts == 1)
    cell = lo[0][single]
    for k in range(1, d):
        cell = cell * shape[k] + lo[k][single]
    todo = np.ones(single.size, dtype=bool)
    for stride in (16, 4, 1):
        part = np.flatnonzero(todo)[::stride]
        if stride < 16:  # skip the cells covered already
            part = part[~flat_occ[cell[part]]]
        todo[part] = False
        for s in range(0, part.size, chunk):
            sel = single[part[s : s + chunk]]
            _cover(z, h, origin, which[sel], lo[:, sel], span[:, sel], counts[sel], occ)
    return occ


def _candidate_boxes(z: Zonotopes, h: float, origin: np.ndarray, shape: tuple[int, ...], scratch: np.ndarray | None = None):
    """(zonotope indices (m,), first candidate cell lo (d, m), cells per axis span (d, m)) of the zonotopes whose
    bounding box holds at least one cell centre: lo = ceil((low - origin) / h - 1/2) clipped to the grid, likewise
    the last one from the box's high corner."""
    low, high = z.box
    d, m = low.shape
    if scratch is None or scratch.shape[0] < 2 * d or scratch.shape[1] < m:
        scratch = np.empty((2 * d, m))
    los, spans, ok = [], [], None
    for k in range(d):
        a = np.subtract(low[k], origin[k], out=scratch[2 * k, :m])
        a /= h
        a -= 0.5
        np.ceil(a, out=a)
        np.maximum(a, 0.0, out=a)
        b = np.subtract(high[k], origin[k], out=scratch[2 * k + 1, :m])
        b /= h
        b -= 0.5
        np.floor(b, out=b)
        np.minimum(b, float(shape[k] - 1), out=b)
        b -= a
        b += 1.0  # the span, exact in floating point (small integers)
        ok = b > 0.0 if ok is None else ok & (b > 0.0)
        los.append(a)
        spans.append(b)
    which = np.flatnonzero(ok)
    lo = np.empty((d, which.size), dtype=np.int64)
    span = np.empty((d, which.size), dtype=np.int64)
    for k in range(d):
        lo[k] = los[k][which]
        span[k] = spans[k][which]
    return which, lo, span


def _cover(z: Zonotopes, h: float, origin: np.ndarray, which, lo, span, counts, occ: np.ndarray) -> None:
    """Mark in ``occ`` the candidate cells of the boxes ``which`` (see :func:`_candidate_boxes`) whose centre passes
    every facet test |base_j + h n_j . off| <= offset_j, base_j = n_j . (origin + (lo + 1/2) h - centre)."""
    d = lo.shape[0]
    centre, normals, offset = z.centre_cols, z.normal_cols, z.offset_cols
    single = not counts.size or int(counts.max()) == 1
    if single:  # one candidate per box (offset 0)
        rep = slice(None)
        offs = [0.0] * d
    else:
        rep = np.repeat(np.arange(which.size), counts)
        local = np.arange(rep.size) - np.repeat(np.cumsum(counts) - counts, counts)
        offs = [None] * d
        for k in range(d - 1, -1, -1):  # unravel local in the box span[rep] (last axis fastest)
            sk = span[k][rep]
            offs[k] = (local % sk).astype(float)
            local //= sk
    rel = [origin[k] + (lo[k] + 0.5) * h - centre[k][which] for k in range(d)]
    hit = None
    for j in range(normals.shape[0]):  # facet by facet
        n = [normals[j][k][which] for k in range(d)]
        base = n[0] * rel[0]
        for k in range(1, d):
            base += n[k] * rel[k]
        proj = base[rep] + (h * n[0])[rep] * offs[0]
        for k in range(1, d):
            proj += (h * n[k])[rep] * offs[k]
        test = np.abs(proj) <= offset[j][which][rep]
        hit = test if hit is None else hit & test
    if single:
        occ[tuple(lo[k][hit] for k in range(d))] = True
    else:
        sel = rep[hit]
        occ[tuple(lo[k][sel] + offs[k][hit].astype(np.int64) for k in range(d))] = True


def _grid_frame(points: np.ndarray, h: float, shift: np.ndarray, pad: float) -> tuple[np.ndarray, tuple[int, ...]]:
    lo = points.min(axis=0) - pad - (1.0 + shift) * h
    hi = points.max(axis=0) + pad
    shape = tuple(int(x) for x in np.floor((hi - lo) / h).astype(np.int64) + 2)
    return lo, shape


def _counting_frame(bounds, h: float, shift: np.ndarray, revolve: bool) -> tuple[np.ndarray, tuple[int, ...]]:
    """(origin (d,) [m], shape) of the counting grid of cell side ``h`` [m] shifted by ``shift`` (d,) in [0, 1) and framing
    the (low, high) corners ``bounds`` [m].  With ``revolve`` its x axis covers the half plane x >= 0 only: cell i has
    its centre at x = (i + shift_0) h, i = 0, 1, ... up to the high corner (the other axes as without)."""
    origin, shape = _grid_frame(np.vstack(bounds), h, shift, 0.0)
    if revolve:
        origin[0] = (shift[0] - 0.5) * h
        shape = (int(math.floor(max(float(bounds[1][0]), 0.0) / h - shift[0])) + 2,) + shape[1:]
    return origin, shape


def _union_bounds(parts: tuple[Zonotopes, ...]) -> tuple[np.ndarray, np.ndarray] | None:
    """(lowest, highest) corner (d,) [m] of the bounding boxes of every zonotope of ``parts`` (None: no zonotope)."""
    if sum(z.size for z in parts) == 0:
        return None
    return np.min([z.bounds[0] for z in parts if z.size], axis=0), np.max([z.bounds[1] for z in parts if z.size], axis=0)


def _value(occ: np.ndarray, origin: np.ndarray, h: float, revolve: bool) -> float:
    """The measure of the covered cells ``occ`` of side ``h`` [m] (lower corner ``origin`` [m]): count h^d, or with
    ``revolve`` (a grid of the half plane x >= 0, :func:`_counting_frame`) the sum of 2 pi x h^2 over the covered centres
    x (the volume of revolution, Pappus) [m^3] (|x|: a centre at x = 0 may come out as -0 or a rounding below it)."""
    if revolve:
        x = origin[0] + (np.arange(occ.shape[0]) + 0.5) * h
        w = 2.0 * math.pi * np.abs(x) * h * h
        return float((occ * w.reshape((-1,) + (1,) * (occ.ndim - 1))).sum())
    return float(occ.sum()) * h**occ.ndim


def _count(
    parts: tuple[Zonotopes, ...], h: float, shift: np.ndarray, revolve: bool, scratch=None, bounds=None
) -> tuple[float, np.ndarray, np.ndarray]:
    """(measure, occupancy, origin) of the union of the zonotope sets ``parts`` counted on the grid shifted by ``shift``
    (``scratch``: see :func:`covered_cells`; ``bounds``: the (low, high) corners [m] framing the counting grid, default
    :func:`_union_bounds` of ``parts``)."""
    d = parts[0].centre.shape[1]
    if sum(z.size for z in parts) == 0:
        return 0.0, np.zeros((1,) * d, dtype=bool), np.zeros(d)
    origin, shape = _counting_frame(_union_bounds(parts) if bounds is None else bounds, h, shift, revolve)
    occ = np.zeros(shape, dtype=bool)
    for z in parts:
        if z.size:
            covered_cells(z, h, origin, shape, out=occ, scratch=scratch)
    return _value(occ, origin, h, revolve), occ, origin


def _count_pair(free: tuple[Zonotopes, ...], rest: tuple[Zonotopes, ...], bounds, h: float, shift: np.ndarray, revolve: bool, scratch):
    """(measure of free + rest, measure of free, occupancy of free + rest, occupancy of free, origin): one counting grid (framed by
    ``bounds``, the union's), the zonotopes ``free`` covered first, their cells copied and the ``rest`` covered on
    top (:func:`covered_cells` skips the cells the free ones covered).  The occupancy is an OR, whatever the order:
    each value is that of :func:`_count` of its set on this grid, bit for bit."""
    origin, shape = _counting_frame(bounds, h, shift, revolve)
    occ = np.zeros(shape, dtype=bool)
    for z in free:
        if z.size:
            covered_cells(z, h, origin, shape, out=occ, scratch=scratch)
    v_free = _value(occ, origin, h, revolve)
    occ_free = occ
    occ = occ.copy()
    for z in rest:
        if z.size:
            covered_cells(z, h, origin, shape, out=occ, scratch=scratch)
    return _value(occ, origin, h, revolve), v_free, occ, occ_free, origin


def _result(values, coarse: float | None, h: float, n: int, d: int, revolve: bool) -> MeasureEstimate:
    """The estimate from the counts ``values`` over the shifts and the mean count on the coarse grid (None: nothing
    to coarsen, the fine count stands for it)."""
    values = np.array(values)
    raw = float(values.mean())
    se = float(values.std(ddof=1) / math.sqrt(values.size))
    coarse = raw if coarse is None else coarse
    return MeasureEstimate(d, raw, abs(raw - coarse) / 2.0 + 2.0 * se, UNITS[3 if revolve else d], raw, se, coarse, h, n)


class CellImage:
    """The cell zonotopes of a joint grid's image, on the grid and on the twice-coarser one, built once for every
    measure of it: :meth:`estimate` over the whole grid or over the cells whose corners are all valid (a subset of
    the same zonotopes, numbers unchanged), :meth:`estimate_pair` both from one counting pass.  ``points_grid``,
    ``revolve``: see :func:`estimate_measure`."""

    def __init__(self, points_grid, revolve: bool = False):
        P = np.asarray(points_grid, dtype=float)
        if P.ndim < 2 or P.shape[-1] not in (1, 2, 3):
            raise InputError(f"points_grid must have shape (n_1, ..., n_k, d) with d in 1..3, got {P.shape}")
        if not np.all(np.isfinite(P)):
            raise InputError("points_grid must be finite")
        if revolve and P.shape[-1] != 2:
            raise InputError("revolve=True needs (s, z) profile points (d = 2)")
        self.points_grid, self.revolve = P, bool(revolve)
        self._cells: dict[bool, tuple] = {}
        self._parts: dict[bool, tuple[Zonotopes, ...]] = {}

    def _zonotopes(self, coarse: bool) -> tuple[Zonotopes, np.ndarray, list[int], tuple]:
        """(the zonotopes of the grid's cells, the grid cells they come from, the free axes, the parts counted: (selection,
        mirror) pairs, see :meth:`_parts_of`)."""
        if coarse not in self._cells:
            P = _coarsen(self.points_grid) if coarse else self.points_grid
            axes = [a for a in range(P.ndim - 1) if P.shape[a] > 1]
            # redundant (more free joints than dimensions): the cells overlap, the union closes itself, no growth
            z, kept = _prepare_columns(*_cell_columns(P, len(axes) <= P.shape[-1]))
            parts: tuple = ((None, False),)
            if self.revolve:  # the profile's zonotopes reaching x >= 0, the mirror of those reaching x <= 0 (module docstring)
                low, high = z.box
                parts = ((high[0] >= 0.0, False), (low[0] <= 0.0, True))
            self._cells[coarse] = z, kept, axes, parts
        return self._cells[coarse]

    @staticmethod
    def _parts_of(z: Zonotopes, parts: tuple, inside: np.ndarray | None) -> tuple[Zonotopes, ...]:
        """The zonotopes of each part (selection: bool (m,) or None: all; mirror) of ``z``, of the cells ``inside`` only
        (bool (m,) or None: all).  A mirrored part is the mirror image (s -> -s) of its selection, taken from ``z`` and
        negated: exactly what cell_zonotopes + prepare compute on the mirrored grid (tests compare the two)."""
        out = []
        for sel, mirror in parts:
            keep = inside if sel is None else (sel if inside is None else sel & inside)
            part = z if keep is None else z.take(np.flatnonzero(keep))
            out.append(part.mirrored() if mirror else part)
        return tuple(out)

    def _inside(self, valid: np.ndarray | None, coarse: bool) -> np.ndarray | None:
        """bool (m,): which zonotopes of :meth:`_zonotopes` come from cells whose corners are all ``valid`` (None: all)."""
        if valid is None:
            return None
        _, kept, axes, _ = self._zonotopes(coarse)
        return _valid_cells(_coarsen(valid, 0) if coarse else valid, axes)[kept]

    def _extent(self, inside: np.ndarray | None, coarse: bool) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray] | None]:
        """(bounding-box sides (n,) [m] of the n zonotopes of the cells ``inside`` (None: all), the (low, high) corners
        (d,) [m] of their union, with ``revolve`` of their union with its mirror image; None when n = 0)."""
        z = self._zonotopes(coarse)[0]
        sides = 2.0 * functools.reduce(np.maximum, z.half_cols)
        if inside is not None:
            sides = sides[inside]
        if sides.size == 0:
            return sides, None
        if inside is None:
            low, high = (a.copy() for a in z.bounds)  # copies: the cached bounds stay the set's
        else:
            box_low, box_high = z.box
            low = np.array([float(np.min(r, where=inside, initial=np.inf)) for r in box_low])
            high = np.array([float(np.max(r, where=inside, initial=-np.inf)) for r in box_high])
        if self.revolve:
            low[0], high[0] = min(low[0], -high[0]), max(high[0], -low[0])
        return sides, (low, high)

    def zonotopes(self, valid=None, coarse: bool = False) -> tuple[Zonotopes, ...]:
        """The zonotopes counted for the cells (of the grid, or of the twice-coarser one) whose corners are all ``valid``:
        one set, or with ``revolve`` two, the profile's that reach the half plane x >= 0 and the mirror images of those
        that reach x <= 0 (see the module docstring)."""
        if valid is None:
            if coarse not in self._parts:
                z, _, _, parts = self._zonotopes(coarse)
                self._parts[coarse] = self._parts_of(z, parts, None)
            return self._parts[coarse]
        return self._split(self._inside(valid, coarse), coarse)[0]

    def _split(self, inside: np.ndarray, coarse: bool, rest: bool = False) -> tuple[tuple[Zonotopes, ...], tuple[Zonotopes, ...] | None]:
        """(the zonotopes counted for the cells ``inside`` (see :meth:`_inside`), the others' if ``rest`` else None)."""
        z, _, _, parts = self._zonotopes(coarse)
        free = self._parts_of(z, parts, inside)
        return free, (self._parts_of(z, parts, ~inside) if rest else None)

    def _checked(self, n_shifts: int, valid) -> np.ndarray | None:
        """``valid`` as a boolean grid of the grid's shape (None stays None), after checking it and ``n_shifts``."""
        if n_shifts < 2:
            raise InputError(f"n_shifts must be >= 2 (the error bar needs a spread), got {n_shifts!r}")
        if valid is None:
            return None
        valid = np.asarray(valid, dtype=bool)
        if valid.shape != self.points_grid.shape[:-1]:
            raise InputError(f"valid must have the grid's shape {self.points_grid.shape[:-1]}, got {valid.shape}")
        return valid

    def _has_coarse(self) -> bool:
        """Whether the twice-coarser grid differs from the grid (some free axis has more than 2 values)."""
        return _coarsen(self.points_grid).shape != self.points_grid.shape

    def estimate(
        self, *, cell: float | None = None, n_shifts: int = 4, seed: int = 0, valid=None, return_occupancy: bool = False, shared_grid: bool = False
    ):
        """:func:`estimate_measure` of this image (same arguments).

        ``shared_grid`` (with ``valid``): count on the counting grid of the whole image, the one :meth:`estimate_pair`
        shares between its two measures: framed by the bounding boxes of every cell zonotope (not only the valid
        ones'), with the whole image's default cell side h unless ``cell`` is given.  False: the grid and h are fitted
        to the valid cells.  Both are unbiased; their numbers differ by the position of the shifted grid."""
        P, revolve = self.points_grid, self.revolve
        d = P.shape[-1]
        valid = self._checked(n_shifts, valid)
        inside = self._inside(valid, False)
        sides, _ = self._extent(inside, False)
        if sides.size == 0:
            raise InputError("every grid cell maps to a flat set (the map has rank < d everywhere): the measure is 0")
        fine = self.zonotopes() if inside is None else self._split(inside, False)[0]
        h = _cell_side(self._extent(None, False)[0] if shared_grid else sides, cell)
        bounds = {c: (self._extent(None, c)[1] if shared_grid else None) for c in (False, True)}
        shifts = np.random.default_rng(seed).uniform(0.0, 1.0, (n_shifts, d))
        scratch = np.empty((2 * d, max(z.size for z in fine)))  # one work buffer for every count below
        values, first = [], None
        for i, s in enumerate(shifts):
            v, occ, origin = _count(fine, h, s, revolve, scratch, bounds[False])
            values.append(v)
            if i == 0:
                first = (occ, origin, h)
        coarse = None
        if self._has_coarse():
            coarse_z = self.zonotopes(valid, coarse=True)
            coarse = float(np.mean([_count(coarse_z, h, s, revolve, scratch, bounds[True])[0] for s in shifts]))
        est = _result(values, coarse, h, sides.size, d, revolve)
        return (est, first) if return_occupancy else est

    def estimate_pair(
        self,
        valid,
        *,
        cell: float | None = None,
        n_shifts: int = 4,
        seed: int = 0,
        return_occupancy: bool = False,
        return_free_occupancy: bool = False,
    ):
        """The measure of the whole image and of its valid cells, from one counting pass on one counting grid.

        On each shifted counting grid (and on the twice-coarser joint grid's) the zonotopes of the valid cells are
        covered first, then the others on a copy of their cells: the whole image's cells are those of the valid ones
        plus the rest, and :func:`covered_cells` skips the cells already covered.

        Parameters
        ----------
        valid : boolean grid of the joint grid's shape (n_1, ..., n_k): a cell is valid when its 2^k corners are
            all True (e.g. the collision-free configurations).
        cell : side h [m] of the counting cells of both measures (default: :func:`default_cell` of every cell
            zonotope of the image, the h of :meth:`estimate`).
        n_shifts, seed : random shifts of the counting grid (>= 2) and their seed, as in :meth:`estimate`.
        return_occupancy : also return (occupancy grid, origin [m], h [m]) of the whole image at the first shift.
        return_free_occupancy : (with ``return_occupancy``) also return the same of the valid cells (same grid).

        Returns
        -------
        whole : MeasureEstimate [m, m^2 or m^3], bit for bit ``estimate(cell=cell, n_shifts=n_shifts, seed=seed)``.
        free : MeasureEstimate of the valid cells, bit for bit ``estimate(cell=whole.cell, valid=valid,
            shared_grid=True, ...)``; None when no valid cell spans the dimension (nothing to measure).
        occupancy : the tuple of ``return_occupancy``, when asked.
        """
        P, revolve = self.points_grid, self.revolve
        d = P.shape[-1]
        valid = self._checked(n_shifts, valid)
        if valid is None:
            raise InputError("estimate_pair needs a valid mask (a boolean grid of the grid's shape); without one use estimate()")
        sides, _ = self._extent(None, False)
        if sides.size == 0:
            raise InputError("every grid cell maps to a flat set (the map has rank < d everywhere): the measure is 0")
        h = _cell_side(sides, cell)
        shifts = np.random.default_rng(seed).uniform(0.0, 1.0, (n_shifts, d))
        scratch = np.empty((2 * d, sides.size))  # one work buffer for every count below (no part has more zonotopes)
        fine, n_free, first = self._pair_counts(valid, False, h, shifts, scratch)
        coarse = self._pair_counts(valid, True, h, shifts, scratch)[0] if self._has_coarse() else None
        # each column reduced as a 1-D array of its own, as estimate() reduces its list of counts (the same sums)
        means = [None if coarse is None else float(np.mean(np.array(coarse[:, j]))) for j in (0, 1)]
        whole = _result(np.array(fine[:, 0]), means[0], h, sides.size, d, revolve)
        free = _result(np.array(fine[:, 1]), means[1], h, n_free, d, revolve) if n_free else None
        if return_occupancy and return_free_occupancy:
            return whole, free, first[0], first[1]
        return (whole, free, first[0]) if return_occupancy else (whole, free)

    def _pair_counts(self, valid: np.ndarray, coarse: bool, h: float, shifts: np.ndarray, scratch) -> tuple[np.ndarray, int, tuple]:
        """(values (n_shifts, 2): measure of every cell zonotope and of the valid ones per shift, the number of valid
        zonotopes, ((occupancy, origin, h) of the whole set, the same of the valid cells) at the first shift) on the
        grid or the coarse one."""
        inside = self._inside(valid, coarse)
        free, rest = self._split(inside, coarse, rest=True)
        bounds = self._extent(None, coarse)[1]
        n_free = int(np.count_nonzero(inside))
        values, first = np.empty((len(shifts), 2)), None
        for i, s in enumerate(shifts):
            if bounds is None:  # no zonotope at all on this grid (the coarse one may have none): both counts are 0
                values[i] = 0.0
                continue
            values[i, 0], values[i, 1], occ, occ_free, origin = _count_pair(free, rest, bounds, h, s, self.revolve, scratch)
            if i == 0:
                first = ((occ, origin, h), (occ_free, origin, h))
        return values, n_free, first


def _coarsen(points_grid: np.ndarray, extra_axes: int = 1) -> np.ndarray:
    """Every other value along each axis longer than 2 (the last ``extra_axes`` axes are kept whole)."""
    n = points_grid.ndim - extra_axes
    sl = tuple(slice(None, None, 2) if (a < n and points_grid.shape[a] > 2) else slice(None) for a in range(points_grid.ndim))
    return points_grid[sl]


def default_cell(z: Zonotopes) -> float:
    """Counting cell side: the median bounding-box side of the grown cell zonotopes (a few candidate centres per cell)."""
    return _cell_side(2.0 * functools.reduce(np.maximum, z.half_cols), None)


def _cell_side(sides: np.ndarray, cell: float | None) -> float:
    """The counting cell side h [m]: ``cell``, checked, or the median of the zonotopes' bounding-box sides ``sides`` [m]
    (with ``revolve`` those of the profile's zonotopes: their mirror images have the same)."""
    h = float(max(np.median(sides), 1e-12)) if cell is None else float(cell)
    if not (math.isfinite(h) and h > 0.0):
        raise InputError(f"cell must be a positive length in m, got {cell!r}")
    return h


def estimate_measure(
    points_grid, *, cell: float | None = None, n_shifts: int = 4, seed: int = 0, revolve: bool = False, valid=None, return_occupancy: bool = False
):
    """Measure of the image of a joint grid (see the module docstring).

    Parameters
    ----------
    points_grid : (n_1, ..., n_k, d) images of the grid points, d = 1, 2 or 3 (profile (rho, z)
        with ``revolve``); axes of length 1 (locked joints) are ignored.
    cell : side h of the counting cells [m] (default :func:`default_cell`).
    n_shifts : random shifts of the counting grid (seeded by ``seed``), >= 2 for an error bar.
    revolve : count the volume of the solid of revolution of an (s, z) profile (|s| = rho) about z.
    valid : boolean grid (n_1, ..., n_k): measure the image of the cells whose corners are all
        valid (a sub-domain of the joint box, e.g. the configurations where the CoG balances).
    return_occupancy : also return (occupancy grid, origin, h) of the first shift (for boundaries and plots).

    Returns
    -------
    MeasureEstimate (and the occupancy tuple when asked).
    """
    image = CellImage(points_grid, revolve)
    return image.estimate(cell=cell, n_shifts=n_shifts, seed=seed, valid=valid, return_occupancy=return_occupancy)


def occupancy(points: np.ndarray, h: float, bounds: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(cells of side ``h`` holding a point as a boolean grid, grid origin), one empty cell all round.

    ``bounds``: (points.min(axis=0), points.max(axis=0)) when known (a caller trying several h)."""
    pts = np.asarray(points, dtype=float)
    pmin, pmax = _column_bounds(pts) if bounds is None else bounds
    origin = pmin - h
    shape = tuple(int(x) for x in np.floor((pmax - origin) / h).astype(np.int64) + 2)
    flat = np.zeros(int(np.prod(shape)), dtype=bool)
    lin = np.floor((pts[:, 0] - origin[0]) / h).astype(np.int64)
    for k in range(1, pts.shape[1]):  # C-order linear index of each point's cell
        lin *= shape[k]
        lin += np.floor((pts[:, k] - origin[k]) / h).astype(np.int64)
    flat[lin] = True
    return flat.reshape(shape), origin


def _column_bounds(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) of each column (a strided reduction per column: faster than numpy's short-axis one)."""
    return (np.array([float(pts[:, k].min()) for k in range(pts.shape[1])]), np.array([float(pts[:, k].max()) for k in range(pts.shape[1])]))


def boundary_cells(occ: np.ndarray) -> np.ndarray:
    """Occupied cells with an empty face neighbour (boolean grid)."""
    structure = ndimage.generate_binary_structure(occ.ndim, 1)
    return occ & ~ndimage.binary_erosion(occ, structure=structure, border_value=0)


def display_occupancy(points: np.ndarray, pinhole_fraction: float = 1e-3, max_steps: int = 40) -> tuple[np.ndarray, np.ndarray, float]:
    """(occupancy, origin, h) of the sample points at the finest cell side h where the sampling leaves no
    gaps (empty cells whose two face neighbours along some axis are both occupied: pinholes, and the stripes of a
    lattice of samples sparser than the cells) and no isolated cells (occupied cells with no occupied face
    neighbour: dots) beyond ``pinhole_fraction`` of the occupied cells: an outline for figures and boundaries (the
    measure comes from :func:`estimate_measure`).  The first h tried is the side of a cell holding one distinct point
    of the bounding box (repeated points, e.g. the hover profile of an arm whose first joint turns about the yaw axis,
    counted once)."""
    pts = np.asarray(points, dtype=float)
    d = pts.shape[1]
    bounds = _column_bounds(pts)
    ext = bounds[1] - bounds[0]
    ext = np.where(ext > 0, ext, ext.max())
    distinct = np.unique(pts, axis=0).shape[0] if pts.shape[0] <= UNIQUE_BELOW else pts.shape[0]
    h = float((np.prod(ext) / distinct) ** (1.0 / d))
    for _ in range(max_steps):
        occ, origin = occupancy(pts, h, bounds)
        if _gaps_and_dots(occ) <= pinhole_fraction * occ.sum():
            return occ, origin, h
        h *= 1.25
    return occ, origin, h


def _gaps_and_dots(occ: np.ndarray) -> int:
    """Empty cells between two occupied face neighbours along some axis, plus occupied cells with no occupied face
    neighbour (:func:`display_occupancy`)."""
    gap = np.zeros(occ.shape, dtype=bool)
    neighbours = np.zeros(occ.shape, dtype=np.int16)
    for axis in range(occ.ndim):
        before = np.zeros_like(occ)
        after = np.zeros_like(occ)
        inner = [slice(None)] * occ.ndim
        shifted = [slice(None)] * occ.ndim
        inner[axis], shifted[axis] = slice(1, None), slice(None, -1)
        before[tuple(inner)] = occ[tuple(shifted)]  # the neighbour at index - 1
        after[tuple(shifted)] = occ[tuple(inner)]  # the neighbour at index + 1
        gap |= before & after
        neighbours += before.astype(np.int16) + after
    return int(np.count_nonzero(~occ & gap) + np.count_nonzero(occ & (neighbours == 0)))


UNIQUE_BELOW = 200_000
""":func:`display_occupancy` counts the distinct points of sets up to this size (a sort; larger sets start from their
point count and coarsen in a few more steps)."""


def map_cell(points: np.ndarray, cells_across: int) -> float:
    """Cell side [m] of a map drawn from the sample points (n, d) [m] by binning (the best value per cell): the largest
    extent over ``cells_across``, or the side on which the samples leave no pinholes and no isolated cells
    (:func:`display_occupancy`) when that is coarser.  Finer cells than the samples fill would show the sampling's
    lattice (empty cells between the images of neighbouring grid points: a checkerboard), not the map."""
    pts = np.asarray(points, dtype=float)
    ext = float((pts.max(axis=0) - pts.min(axis=0)).max())
    return max(ext / cells_across, display_occupancy(pts, MAP_GAP_FRACTION)[2], 1e-9)


MAP_GAP_FRACTION = 0.02
"""Gaps and dots :func:`map_cell` allows, as a share of the filled cells: a few scattered empty cells read as texture,
more as the sampling's lattice.  Stricter (the outlines' 1e-3) made the maps of a 5-joint arm coarse: hextilt_flying_arm_5's
capacity map at 1.3e5 samples had 32 cells at 1e-3, 105 at 1e-2, 231 at 3e-2 (its x-z projection holds 2.4e4 distinct
points on a lattice)."""
