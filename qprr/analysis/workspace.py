"""Workspace of the end effector: in the base frame B and, under hover, about the base (Thesis (3.1)-(3.3)).

Thesis Sec. 3.2.1.3: the reachable set is the image W_eb = W_e(q_e) (3.2) of the joint box
q_im <= q_i <= q_iM (3.1).  (3.3) writes the whole workspace as W_e = W_b U W_eb: the base
positions W_b are unbounded, so what characterises a design is W_eb.  Two forms here:

* **body frame**: the end-effector positions in B over the joint box (the base held still);
* **under hover** (world axes, about the base position): a multirotor hovers level and may turn
  about the vertical freely, so W_eb^hover is the body-frame set swept by a full turn of yaw
  about z_B: the solid of revolution of the profile (rho = |p_xy|, z) (Thesis (3.68),
  (3.82)).  Its volume is the number a designer compares.

Each region is computed with every joint free and with chosen joints locked (the thesis's
Fig. 3.14/3.15: with and without the slider r0); the gain of the free joints is reported as a
ratio and a difference, with error bars.  With a collision model (:mod:`qprr.analysis.collision`: the arm
against the body, the propeller discs and itself) every region is measured twice: over the whole
joint box, and over its collision-free configurations only (the image of the grid cells whose
corners are all collision-free, counted in the same pass on the same counting grid as the whole
region: :meth:`qprr.analysis.voxels.CellImage.estimate_pair`); both numbers are reported.  Measures come from :mod:`qprr.analysis.voxels`
(cell counting over the linearised images of the joint-grid cells, error bar from the
convergence in the grid size).  A planar arm (all joints moving the end effector in one
plane, the Q-PRR's x-z plane of B) has an *area* in B and a *volume* under hover.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InputError
from ..model import Platform
from ._common import (
    CollisionMask,
    JointGrid,
    MapStatus,
    affine_span,
    check_arm_platform,
    check_int,
    check_locked,
    check_progress,
    collision_mask,
    make_grid,
    resolve_collision,
)
from .budget import SampleChoice, check_budget, check_clock, grid_work, within_budget
from .chain import ArmChain
from .voxels import CellImage, MeasureEstimate, display_occupancy


@dataclass(frozen=True)
class Ratio:
    """a / b with its error bar (first-order propagation of the two error bars)."""

    value: float
    error: float

    @staticmethod
    def of(a: MeasureEstimate, b: MeasureEstimate) -> Ratio:
        if b.measure <= 0.0:
            return Ratio(float("inf"), float("nan"))
        r = a.measure / b.measure
        rel = np.hypot(a.error / a.measure if a.measure else 0.0, b.error / b.measure)
        return Ratio(float(r), float(r * rel))


@dataclass(frozen=True)
class WorkspaceRegion:
    """The workspace for one set of locked joints.

    ``points_body`` (n, 3) end-effector positions in B [m] on the joint ``grid`` (C order);
    ``origin``, ``basis`` (dim, 3): the affine hull of the set in B (a planar arm: basis (x_B,
    z_B)); ``coords`` (n, dim) the points in that basis; ``measure`` its length/area/volume in B;
    ``hover_volume`` the volume swept under hover (yaw about z_B), None if not asked;
    ``occupancy``: (cells covered, origin, cell side) in ``coords``: the cells the measure counted (the set
    :func:`reachable` tests); ``profile``: (s, z) (n, 2) of the hover workspace, ``hover_counted`` the cells its
    volume counted (the half section s >= 0).  For drawing, computed when first read: ``outline``, the same cells as ``occupancy`` or, for a
    redundant arm, the finer cells its samples fill without holes (:func:`qprr.analysis.voxels.display_occupancy`);
    ``boundary``, closed polylines (m, 3) in B along ``outline`` (planar sets) or the centres (m, 3) of its boundary
    cells (3-D sets), [] without a measure; ``hover_occupancy``, the profile's whole
    section (s of either sign) drawn from its samples and their mirror image.
    ``collision_free``: (n,) bool, the grid configurations free of self-collision (None: not checked);
    ``collision_check``: how the mask was obtained (:meth:`qprr.analysis._common.CollisionMask.describe`);
    ``free_measure``, ``free_hover_volume``: the measures over the collision-free cells only (counted on the counting
    grid of ``measure`` / ``hover_volume``: same cell side and frame), ``free_occupancy``, ``free_hover_counted`` the
    cells they counted (as ``occupancy`` / ``hover_counted``, on the same grids).
    """

    label: str
    locked: dict
    grid: JointGrid
    points_body: np.ndarray
    origin: np.ndarray
    basis: np.ndarray
    coords: np.ndarray
    measure: MeasureEstimate | None
    hover_volume: MeasureEstimate | None
    occupancy: tuple | None
    profile: np.ndarray
    hover_counted: tuple | None
    collision_free: np.ndarray | None = None
    collision_check: str = ""
    free_measure: MeasureEstimate | None = None
    free_hover_volume: MeasureEstimate | None = None
    free_occupancy: tuple | None = None
    free_hover_counted: tuple | None = None

    @property
    def dim(self) -> int:
        return int(self.basis.shape[0])

    @property
    def free_joints(self) -> int:
        """The joints the grid moves (axes with more than one value)."""
        return sum(1 for n in self.grid.shape if n > 1)

    @property
    def redundant(self) -> bool:
        """More free joints than the set's dimension (the cells of the joint grid overlap)."""
        return self.free_joints > self.dim

    @functools.cached_property
    def outline(self) -> tuple | None:
        if self.occupancy is None or not self.redundant:
            return self.occupancy
        fine = display_occupancy(self.coords)
        return fine if fine[2] < self.occupancy[2] else self.occupancy

    @functools.cached_property
    def boundary(self) -> list:
        return [] if self.outline is None else _boundary(self.outline, self.origin, self.basis)

    @functools.cached_property
    def hover_occupancy(self) -> tuple | None:
        if self.hover_counted is None:
            return None
        # the volume counts the half section s >= 0 only (qprr.analysis.voxels): the whole section is drawn from the
        # profile's samples and their mirror image
        return display_occupancy(np.vstack([self.profile, self.profile * np.array([-1.0, 1.0])]))


@dataclass(frozen=True)
class WorkspaceResult:
    """Workspace of ``frame`` of ``platform_name`` (see the module docstring).

    ``regions[0]`` has every joint free (apart from ``locked``); the others lock the joints of
    each variant.  ``gain[i]`` (i >= 1): regions[0] over regions[i] in B (``Ratio``) and
    ``gain_hover[i]`` under hover; ``difference[i]`` = measure(regions[0]) - measure(regions[i])
    with its error bar.  ``status``/``reason``: see :class:`~qprr.analysis.MapStatus`.  With a collision check:
    ``gain_free[i]`` = (in B, under hover) ratios of the collision-free measures (None where not measured);
    ``collision_note``: why collisions were not checked, if they were not.  ``sampling``: how ``n_samples`` was
    set (:class:`qprr.analysis.budget.SampleChoice`: given, or chosen for a time budget).
    """

    platform_name: str
    frame: str
    regions: tuple[WorkspaceRegion, ...]
    gain: dict = field(default_factory=dict)
    gain_hover: dict = field(default_factory=dict)
    difference: dict = field(default_factory=dict)
    status: MapStatus = MapStatus.OK
    reason: str = ""
    collision_note: str = ""
    gain_free: dict = field(default_factory=dict)
    sampling: SampleChoice | None = None

    def summary(self) -> str:
        """A few lines with the measures and the gains (all configurations, then the collision-free ones)."""
        lines = [f"workspace of {self.frame!r} on {self.platform_name}"]
        for i, r in enumerate(self.regions):
            m = str(r.measure) if r.measure is not None else "n/a"
            hv = f"; under hover (yaw free) {r.hover_volume}" if r.hover_volume is not None else ""
            lines.append(f"  [{i}] {r.label}: {r.grid.size} configurations, in B {m}{hv}")
            if r.collision_free is not None:
                fm = str(r.free_measure) if r.free_measure is not None else "n/a"
                fh = f"; under hover {r.free_hover_volume}" if r.free_hover_volume is not None else ""
                lines.append(
                    f"      collision-free: {int(r.collision_free.sum())} of {r.grid.size} configurations "
                    f"({100.0 * r.collision_free.mean():.2f}%), in B {fm}{fh} [{r.collision_check}]"
                )
        if self.collision_note:
            lines.append(f"  {self.collision_note}")
        for i in self.gain:
            g, d = self.gain[i], self.difference[i]
            lines.append(f"  gain of [0] over [{i}] in B: x{g.value:.4f} +- {g.error:.2g} (+{d[0]:.5g} +- {d[1]:.2g} {self.regions[0].measure.unit})")
            if i in self.gain_hover:
                gh = self.gain_hover[i]
                lines.append(f"  gain of [0] over [{i}] under hover: x{gh.value:.4f} +- {gh.error:.2g}")
            if i in self.gain_free:
                parts = [f"{where} x{g.value:.4f} +- {g.error:.2g}" for where, g in zip(("in B", "under hover"), self.gain_free[i]) if g is not None]
                lines.append(f"  gain of [0] over [{i}], collision-free parts: " + ", ".join(parts))
        if self.reason:
            lines.append(f"  status {self.status.value}: {self.reason}")
        if self.sampling is not None:
            lines.append(f"  {self.sampling.describe()}")
        return "\n".join(lines)


def default_variants(platform: Platform) -> list[dict[str, float]]:
    """One variant per prismatic joint, locked at 0 (or the limit nearest 0): "without the slider"."""
    check_arm_platform(platform)
    out = []
    for j in platform.arm:
        if j.kind == "prismatic":
            out.append({j.name: float(np.clip(0.0, j.lower, j.upper))})
    return out


def _label(locked: Mapping[str, float]) -> str:
    if not locked:
        return "all joints free"
    return ", ".join(f"{k} locked at {v:g}" for k, v in locked.items())


@dataclass(frozen=True)
class WorkspaceOptions:
    """Settings of :func:`workspace` (each can also be given to it as a keyword).

    ``n_samples``: joint-grid size per region (balanced grid, :func:`qprr.analysis._common.make_grid`);
    ``variants``: sets of joints to lock, ``[{name: value}, ...]`` [m or rad] (default: each prismatic joint
    locked at 0, the workspace "without the slider"); ``locked``: joints locked in every region; ``ranges``:
    {name: (low, high)} narrower joint ranges than the limits (needed for a prismatic joint without limits);
    ``frame``: the frame whose origin is mapped (name or id; default the end effector); ``hover``: also compute
    the volume swept under hover (yaw free about z_B); ``n_shifts``, ``seed``: counting-grid shifts of the
    measure estimator (:mod:`qprr.analysis.voxels`); ``collision``: also measure the collision-free part of each
    region (None: when the platform has a collision model, :func:`qprr.analysis._common.resolve_collision`; True:
    required; False: off).  Cost: the collision check and the collision-free measures (counted with the whole
    ones, in one pass) make the map about 1.4x slower (Q-PRR, 1e6 configurations per region: ~3.8 s against ~2.8 s;
    docs/analysis.md, Speed).  ``budget``: wall time [s] the map may take; when given, ``n_samples`` is chosen from
    pilot runs timed with ``clock`` (default :func:`time.perf_counter`) and the given one is not used
    (:mod:`qprr.analysis.budget`; the choice is the result's ``sampling``).
    """

    n_samples: int = 1_000_000
    variants: Sequence[Mapping[str, float]] | None = None
    locked: Mapping[str, float] | None = None
    ranges: Mapping[str, tuple[float, float]] | None = None
    frame: object = None
    hover: bool = True
    n_shifts: int = 4
    seed: int = 0
    collision: bool | None = None
    budget: float | None = None
    clock: Callable[[], float] | None = None

    def __post_init__(self) -> None:  # the platform-free settings are checked however the options are built
        object.__setattr__(self, "n_samples", check_int("n_samples", self.n_samples, 8))
        object.__setattr__(self, "budget", check_budget(self.budget))
        check_clock(self.clock)
        object.__setattr__(self, "n_shifts", check_int("n_shifts", self.n_shifts, 2))
        object.__setattr__(self, "seed", check_int("seed", self.seed, 0))
        if not isinstance(self.hover, (bool, np.bool_)):
            raise InputError(f"hover must be True or False, got {self.hover!r}")
        if self.collision is not None and not isinstance(self.collision, (bool, np.bool_)):
            raise InputError(f"collision must be None (when a collision model exists), True or False, got {self.collision!r}")


def workspace(platform: Platform, options: WorkspaceOptions | None = None, *, progress=None, **settings) -> WorkspaceResult:
    """The workspace of the frame (default: the end effector), with every joint free and per variant.

    ``platform``: any serial arm of prismatic/revolute joints; ``options``: :class:`WorkspaceOptions`, and/or its
    fields as keywords (``workspace(p, n_samples=200_000, hover=False)``; an unknown keyword is a TypeError);
    ``progress``: None, True (stderr) or a callable (fraction, message).
    """
    o = replace(options or WorkspaceOptions(), **settings) if settings else (options or WorkspaceOptions())
    if not isinstance(o, WorkspaceOptions):
        raise InputError(f"options must be a WorkspaceOptions, got {type(o).__name__}")
    check_arm_platform(platform)
    base_locked = check_locked(platform, o.locked)
    variants = default_variants(platform) if o.variants is None else o.variants
    sets = [dict(base_locked)] + [{**base_locked, **check_locked(platform, v)} for v in variants]
    work = grid_work(platform, sets, o.ranges)
    collisions = resolve_collision(platform, o.collision)  # built once, not per pilot (seconds for a 5-joint arm)
    return within_budget(o, lambda oo, pr: _workspace(platform, oo, sets, collisions, pr), work, check_progress(progress))


def _workspace(platform: Platform, o: WorkspaceOptions, sets: list[dict], collisions: tuple, progress) -> WorkspaceResult:
    """:func:`workspace` at ``o.n_samples`` per region over the locked ``sets`` (the first: every joint free);
    ``collisions``: (collision model or None, note) of :func:`qprr.analysis._common.resolve_collision`."""
    n_samples, ranges, frame, hover, n_shifts, seed = o.n_samples, o.ranges, o.frame, o.hover, o.n_shifts, o.seed
    fid = platform.ee_frame if frame is None else platform.frame_id(frame)
    chain = ArmChain(platform)
    cmodel, note = collisions
    regions, reasons = [], []
    for i, lk in enumerate(sets):
        grid = make_grid(platform, n_samples, lk, ranges)
        pts = np.empty((grid.size, 3))
        for start, q in grid.chunks():
            pts[start : start + len(q)] = chain.frame_position(chain.pose(q), fid)
            if progress:
                progress((i + (start + len(q)) / grid.size * 0.3) / len(sets), f"workspace [{i}] {_label(lk)}")
        mask = None
        if cmodel is not None:
            sub = (lambda f, m, i=i: progress((i + 0.3 + 0.4 * f) / len(sets), f"workspace [{i}] collisions")) if progress else None
            mask = collision_mask(cmodel, grid, sub)
        region, why = _region(pts, grid, lk, hover, n_shifts, seed, mask)
        if why:
            reasons.append(f"[{i}] {why}")
        regions.append(region)
        if progress:
            progress((i + 1) / len(sets), f"workspace [{i}] {_label(lk)}")
    gain, gain_hover, diff, gain_free = {}, {}, {}, {}
    r0 = regions[0]
    for i, r in enumerate(regions[1:], start=1):
        if r0.measure is not None and r.measure is not None and r0.measure.dim == r.measure.dim:
            gain[i] = Ratio.of(r0.measure, r.measure)
            diff[i] = (r0.measure.measure - r.measure.measure, float(np.hypot(r0.measure.error, r.measure.error)))
        if r0.hover_volume is not None and r.hover_volume is not None:
            gain_hover[i] = Ratio.of(r0.hover_volume, r.hover_volume)
        free_gains = tuple(
            Ratio.of(a, b) if a is not None and b is not None and a.dim == b.dim else None
            for a, b in ((r0.free_measure, r.free_measure), (r0.free_hover_volume, r.free_hover_volume))
        )
        if any(g is not None for g in free_gains):
            gain_free[i] = free_gains
    status = MapStatus.PARTIAL if reasons else MapStatus.OK
    return WorkspaceResult(
        platform.name, platform.model.frames[fid].name, tuple(regions), gain, gain_hover, diff, status, "; ".join(reasons), note, gain_free
    )


def _measures(image: CellImage, mask: CollisionMask | None, shape: tuple, n_shifts: int, seed: int):
    """(measure of ``image``, occupancy of its first counting grid, measure over the cells whose corners are all
    collision-free or None: no mask, or no such cell, the occupancy of those cells on the same counting grid or None),
    the measures from one counting pass on one counting grid (:meth:`qprr.analysis.voxels.CellImage.estimate_pair`: the
    whole image's cell side and frame)."""
    if mask is None or not mask.free.any():
        measure, occ = image.estimate(n_shifts=n_shifts, seed=seed, return_occupancy=True)
        return measure, occ, None, None
    whole, free, occ, free_occ = image.estimate_pair(
        mask.free.reshape(shape), n_shifts=n_shifts, seed=seed, return_occupancy=True, return_free_occupancy=True
    )
    return whole, occ, free, free_occ if free is not None else None


def _region(pts: np.ndarray, grid: JointGrid, locked: dict, hover: bool, n_shifts: int, seed: int, mask: CollisionMask | None = None):
    """The region of the points ``pts`` (n, 3) of ``grid`` and why a measure is missing; with ``mask``, also its
    collision-free measures (:func:`_measures`: both measures of an image from one counting pass over its cell
    zonotopes, each image dropped once they are taken)."""
    origin, basis = affine_span(pts)
    coords = (pts - origin) @ basis.T if basis.shape[0] else np.zeros((pts.shape[0], 0))
    free = sum(1 for n in grid.shape if n > 1)
    shape = tuple(n for n in grid.shape if n > 1)
    why = ""
    measure = occ = free_measure = free_hover = free_occ = free_hocc = None
    dim = basis.shape[0]
    if dim == 0:
        why = "the frame does not move (a point)"
    elif free < dim:
        why = f"{free} free joint(s) sweep a curved {free}-dimensional set inside a {dim}-dimensional hull: no {dim}-D measure"
    else:
        image = CellImage(coords.reshape(*shape, dim))
        measure, occ, free_measure, free_occ = _measures(image, mask, shape, n_shifts, seed)
        del image
    profile = hover_profile(pts, origin, basis)
    hv = hocc = None
    if hover:
        pdim = affine_span(np.column_stack([profile[:, 0], np.zeros(len(profile)), profile[:, 1]]))[1].shape[0]
        if pdim == 2 and free >= 2:
            hover_image = CellImage(profile.reshape(*shape, 2), revolve=True)
            hv, hocc, free_hover, free_hocc = _measures(hover_image, mask, shape, n_shifts, seed)
            del hover_image
        elif not why:
            why = "the hover profile (rho, z) is not two-dimensional: no volume under hover"
    region = WorkspaceRegion(_label(locked), dict(locked), grid, pts, origin, basis, coords, measure, hv, occ, profile, hocc)
    if mask is not None:
        region = replace(
            region,
            collision_free=mask.free,
            collision_check=mask.describe(),
            free_measure=free_measure,
            free_hover_volume=free_hover,
            free_occupancy=free_occ,
            free_hover_counted=free_hocc,
        )
    return region, why


def hover_profile(pts: np.ndarray, origin: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """(n, 2) profile (s, z) of points in B turning about z_B: |s| = rho = |p_xy|.

    For a planar set whose plane contains the z_B axis (the Q-PRR's x-z plane) s is the signed
    in-plane horizontal coordinate, so the profile has no fold where the arm crosses the axis;
    otherwise s = rho.
    """
    if basis.shape[0] == 2:
        normal = np.cross(basis[0], basis[1])
        normal /= np.linalg.norm(normal)
        if abs(normal[2]) < 1e-12 and abs(float(origin @ normal)) < 1e-12:  # the plane contains the z axis
            u = np.array([normal[1], -normal[0], 0.0])
            return np.column_stack([pts @ u, pts[:, 2]])
    return np.column_stack([np.hypot(pts[:, 0], pts[:, 1]), pts[:, 2]])


def _boundary(occ, origin: np.ndarray, basis: np.ndarray) -> list:
    """Outline of the covered cells: closed polylines in B (2-D sets), boundary-cell centres (3-D), ends (1-D)."""
    grid, o, h = occ
    d = basis.shape[0]
    if d == 2:
        import contourpy

        x = o[0] + (np.arange(grid.shape[0]) + 0.5) * h
        y = o[1] + (np.arange(grid.shape[1]) + 0.5) * h
        gen = contourpy.contour_generator(x, y, grid.T.astype(float), line_type=contourpy.LineType.Separate)
        lines = gen.lines(0.5)
        return [origin + np.asarray(ln) @ basis for ln in lines if len(ln) > 2]
    from .voxels import boundary_cells

    cells = np.argwhere(boundary_cells(grid))
    centres = o + (cells + 0.5) * h
    if d == 1:
        return [origin + np.array([centres.min(axis=0), centres.max(axis=0)]) @ basis]
    return [origin + centres @ basis]


def reachable(result: WorkspaceResult, points_body, region: int = 0) -> np.ndarray:
    """Which of ``points_body`` (m, 3) [m, B] lie in the covered cells of ``region`` (and in its hull, to 1e-9 m)."""
    r = result.regions[region]
    if r.occupancy is None:
        raise InputError(f"region {region} has no measure (its reason: {result.reason})")
    P = np.atleast_2d(np.asarray(points_body, dtype=float))
    local = (P - r.origin) @ r.basis.T
    off_hull = np.linalg.norm(P - (r.origin + local @ r.basis), axis=1) > 1e-9
    grid, o, h = r.occupancy
    idx = np.floor((local - o) / h).astype(np.int64)
    ok = np.all((idx >= 0) & (idx < np.array(grid.shape)), axis=1) & ~off_hull
    out = np.zeros(P.shape[0], dtype=bool)
    out[ok] = grid[tuple(idx[ok].T)]
    return out
