"""What every map shares: statuses, input checks, joint grids, payload description, progress.

A map samples the arm's joint space on a *grid* (deterministic, reproducible): each free joint
gets ``n_j`` evenly spaced values across its range, locked joints one value.  The numbers
``n_j`` are balanced so that a grid step moves the end effector about as far along every
joint (a joint that swings a long lever gets more values), with ``prod(n_j)`` close to the
``n_samples`` asked for.  Configurations are produced in chunks so that 1e7 samples never
sit in memory as one array.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..errors import InputError, LimitError, UnknownNameError
from ..model import Platform
from ..model import check_platform as _check_platform
from ..progress import FractionProgress
from ..validation import as_array, as_int, as_real, as_vector


@dataclass(frozen=True)
class MapReference:
    """Published numbers for one map of one platform: ``curves`` {label: (x, y)} drawn dashed on the map's
    figure (the singularity map's det(J J^T) panel), ``lines`` printed after the map's summary.

    Given by the providers of :data:`qprr.registry.MAP_REFERENCES` (the thesis plug-in's
    :func:`qprr.thesis.maps.analysis_reference`); :func:`qprr.analysis.cli.map_reference` asks them."""

    curves: Mapping = field(default_factory=dict)
    lines: tuple[str, ...] = ()


CHUNK = 16384
"""Configurations per batch: large enough to amortise numpy's per-call cost, small enough for the cache."""


class MapStatus(str, Enum):
    """Outcome of a map: ``OK`` (every quantity computed), ``EMPTY`` (the set asked for is empty,
    e.g. no configuration hovers), ``PARTIAL`` (computed, but a part is missing: the reason says which)."""

    OK = "ok"
    EMPTY = "empty"
    PARTIAL = "partial"


def check_arm_platform(platform) -> Platform:
    """:func:`qprr.model.check_platform`, and the platform must have an arm (the maps are over its configurations)."""
    _check_platform(platform)
    if platform.n_arm == 0:
        raise InputError(f"platform {platform.name!r} has no arm joints: there is no arm configuration space to map")
    return platform


def check_int(name: str, value, lo: int = 1) -> int:
    """:func:`qprr.validation.as_int` with the argument order of this package."""
    return as_int(value, name, lo=lo)


def check_pos(name: str, value, strict: bool = True) -> float:
    """:func:`qprr.validation.as_real` (> 0, or >= 0 when not ``strict``) with the argument order of this package."""
    return as_real(value, name, positive=strict, nonnegative=not strict)


def check_masses(masses, name: str = "payload_masses") -> np.ndarray:
    """A non-empty 1-D array of finite payload masses >= 0 [kg]."""
    m = np.atleast_1d(as_array(masses, name))
    if m.ndim != 1 or m.size == 0 or not np.all(np.isfinite(m)) or np.any(m < 0.0):
        raise InputError(f"{name} must be a non-empty list of finite masses >= 0 kg, got {masses!r}")
    return m


@dataclass(frozen=True)
class PayloadMount:
    """A point payload held by a frame of the arm (default: the end effector).

    ``offset_frame``: its position in that frame [m] (the thesis's d_cl along link 3 is
    ``(0, 0, d_cl)`` for the Q-PRR, whose end-effector z axis continues link 3).
    """

    offset_frame: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame: int | None = None


def make_payload_mount(platform: Platform, payload_offset, frame=None) -> PayloadMount:
    _check_platform(platform)
    off = as_vector(payload_offset, 3, "payload_offset")
    fid = platform.ee_frame if frame is None else platform.frame_id(frame)
    return PayloadMount(tuple(float(x) for x in off), fid)


# ------------------------------------------------------------------------------ joint grid
@dataclass(frozen=True)
class JointGrid:
    """A tensor grid over the arm joints: ``axes[k]`` the values of joint k (one value if locked).

    ``shape`` = (len(axes[0]), ...); ``size`` its product; configurations are in C order
    (the last joint varies fastest).  ``locked``: names of the joints held at one value.
    ``kinds``: "prismatic" or "revolute" per joint (the units of the maps' axes: m or rad).
    """

    names: tuple[str, ...]
    axes: tuple[np.ndarray, ...]
    locked: tuple[str, ...]
    kinds: tuple[str, ...] = ()

    def unit(self, k: int) -> str:
        """Unit of joint ``k``: m for a prismatic joint, rad for a revolute one ("m or rad" when unknown)."""
        return {"prismatic": "m", "revolute": "rad"}.get(self.kinds[k] if k < len(self.kinds) else "", "m or rad")

    def label(self, k: int) -> str:
        """Axis label of joint ``k``: its name and unit."""
        return f"{self.names[k]} [{self.unit(k)}]"

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a) for a in self.axes)

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))

    @property
    def spacing(self) -> np.ndarray:
        """Step of each axis (0 for a locked joint)."""
        return np.array([a[1] - a[0] if len(a) > 1 else 0.0 for a in self.axes])

    def configurations(self, start: int = 0, stop: int | None = None) -> np.ndarray:
        """The grid points with flat indices [start, stop) as an (m, n_arm) array."""
        stop = self.size if stop is None else stop
        idx = np.unravel_index(np.arange(start, stop), self.shape)
        return np.column_stack([ax[i] for ax, i in zip(self.axes, idx)])

    def configurations_at(self, flat) -> np.ndarray:
        """The grid points with the flat indices ``flat`` (m,) as an (m, n_arm) array."""
        idx = np.unravel_index(np.asarray(flat, dtype=np.int64), self.shape)
        return np.column_stack([ax[i] for ax, i in zip(self.axes, idx)])

    def chunks(self, chunk: int = CHUNK) -> Iterator[tuple[int, np.ndarray]]:
        """(start, configurations) batches covering the whole grid."""
        for start in range(0, self.size, chunk):
            yield start, self.configurations(start, min(start + chunk, self.size))


def joint_ranges(platform: Platform, ranges: Mapping[str, tuple[float, float]] | None = None) -> np.ndarray:
    """(n_arm, 2) ranges of the arm joints: the joint limits, or ``ranges[name]`` where given.

    A revolute joint without limits gets [-pi, pi]; a prismatic joint without limits needs
    an explicit range (InputError).  A given range must lie inside the joint limits.
    """
    _check_platform(platform)
    out = np.empty((platform.n_arm, 2))
    ranges = {} if ranges is None else dict(ranges)
    unknown = set(ranges) - set(platform.arm_names)
    if unknown:
        raise UnknownNameError("arm joint in ranges", sorted(unknown)[0], platform.arm_names)
    for k, j in enumerate(platform.arm):
        lo, hi = j.lower, j.upper
        if j.name in ranges:
            r = as_vector(ranges[j.name], 2, f"ranges[{j.name!r}]")
            if not r[0] <= r[1]:
                raise InputError(f"ranges[{j.name!r}] must be (low, high) with low <= high, got {r.tolist()}")
            if r[0] < lo - 1e-12 or r[1] > hi + 1e-12:
                raise LimitError(f"ranges[{j.name!r}] = {r.tolist()} leaves the joint limits [{lo!r}, {hi!r}]")
            lo, hi = float(r[0]), float(r[1])
        if not (math.isfinite(lo) and math.isfinite(hi)):
            if j.kind == "revolute":
                lo, hi = max(lo, -math.pi), min(hi, math.pi)
            else:
                raise InputError(f"prismatic joint {j.name!r} has no limits: give its range, e.g. ranges={{{j.name!r}: (-0.1, 0.1)}}")
        out[k] = lo, hi
    return out


def check_locked(platform: Platform, locked: Mapping[str, float] | None) -> dict[str, float]:
    """``locked`` as {arm joint name: value inside the limits}; unknown names list the valid ones."""
    _check_platform(platform)
    if locked is None:
        return {}
    if not isinstance(locked, Mapping):
        raise InputError(f"locked must be a mapping {{joint name: value}}, got {locked!r}")
    out = {}
    for name, value in locked.items():
        if name not in platform.arm_names:
            raise UnknownNameError("arm joint in locked", name, platform.arm_names)
        k = platform.arm_names.index(name)
        j = platform.arm[k]
        v = float(as_vector([value], 1, f"locked[{name!r}]")[0])
        if not j.lower - 1e-12 <= v <= j.upper + 1e-12:
            raise LimitError(f"locked[{name!r}] = {v!r} is outside the joint limits [{j.lower!r}, {j.upper!r}]")
        out[name] = v
    return out


def lever_lengths(platform: Platform, ranges: np.ndarray) -> np.ndarray:
    """Per joint, an upper bound of |d p_ee / d q_k| over the ranges: 1 for a prismatic joint, the
    distance from the joint to the farthest point its subtree can place the end effector for a
    revolute one (sum of the joint-to-joint offsets after it plus the prismatic strokes)."""
    _check_platform(platform)
    model = platform.model
    ee_joint = model.frames[platform.ee_frame].parentJoint
    chain = []  # joints from the end effector up to the base
    j = ee_joint
    while j > 1:
        chain.append(j)
        j = model.parents[j]
    chain = chain[::-1]
    out = np.zeros(platform.n_arm)
    for k, jt in enumerate(platform.arm):
        if jt.kind == "prismatic":
            out[k] = 1.0 if jt.joint_id in chain else 0.0
            continue
        if jt.joint_id not in chain:
            continue
        reach = float(np.linalg.norm(model.frames[platform.ee_frame].placement.translation))
        for jj in chain[chain.index(jt.joint_id) + 1 :]:
            reach += float(np.linalg.norm(model.jointPlacements[jj].translation))
            kk = jj - 2
            if platform.arm[kk].kind == "prismatic":
                reach += float(np.max(np.abs(ranges[kk])))
        out[k] = reach
    return out


def make_grid(
    platform: Platform, n_samples: int, locked: Mapping[str, float] | None = None, ranges: Mapping[str, tuple[float, float]] | None = None
) -> JointGrid:
    """The balanced joint grid of about ``n_samples`` configurations (see the module docstring).

    Joint k gets n_k values with n_k proportional to its lever (:func:`lever_lengths`) times its
    range, odd (every other value is a grid with twice the step and the same ends) and at least
    3.  Joints that do not move the end effector (after it in the tree) get the same count as
    the others' geometric mean.
    """
    _check_platform(platform)
    n_samples = check_int("n_samples", n_samples, 2)
    locked = check_locked(platform, locked)
    rng = joint_ranges(platform, ranges)
    free = [k for k, j in enumerate(platform.arm) if j.name not in locked]
    if not free:
        axes = tuple(np.array([locked[j.name]]) for j in platform.arm)
        return JointGrid(platform.arm_names, axes, tuple(locked), tuple(j.kind for j in platform.arm))
    lever = lever_lengths(platform, rng)
    span = np.array([lever[k] * (rng[k, 1] - rng[k, 0]) for k in free])
    moving = span > 0
    if not np.any(moving):
        span = np.ones(len(free))
    else:
        span[~moving] = np.exp(np.mean(np.log(span[moving])))
    # n_k = c span_k with prod n_k = n_samples
    c = (n_samples / np.prod(span)) ** (1.0 / len(free))
    counts = np.maximum(3, 2 * np.round((c * span - 1.0) / 2.0) + 1).astype(int)  # odd: halving keeps both ends
    for k in range(len(free)):  # a joint with a zero range gets one value
        if rng[free[k], 1] == rng[free[k], 0]:
            counts[k] = 1
    axes = []
    for k, j in enumerate(platform.arm):
        if j.name in locked:
            axes.append(np.array([locked[j.name]]))
        else:
            i = free.index(k)
            axes.append(np.linspace(rng[k, 0], rng[k, 1], int(counts[i])))
    return JointGrid(platform.arm_names, tuple(axes), tuple(locked), tuple(j.kind for j in platform.arm))


def fraction_error(mask: np.ndarray, shape: tuple[int, ...]) -> float:
    """Error bar of the share of a grid's configurations where ``mask`` (n,) holds: |share on the grid - share on the
    grid with twice the step (every other value along each axis of 3 values or more, the same ends)|, the
    discretisation error of the finer share when it converges at first order in the step (a set's boundary cuts
    the cells); 0 on a grid that has no coarser one."""
    m = np.asarray(mask, dtype=bool).reshape(shape)
    coarse = m[tuple(slice(None, None, 2) if n >= 3 else slice(None) for n in shape)]
    if coarse.size == m.size:
        return 0.0
    return float(abs(m.mean() - coarse.mean()))


def neighbourhood_max(a: np.ndarray, axes: list[int], radius: int = 1) -> np.ndarray:
    """The largest value of ``a`` over each entry's neighbours within ``radius`` steps along every axis of ``axes``
    (itself included): a (2 radius + 1)^d box maximum filter, one axis and one step at a time (-inf for NaN)."""
    out = np.where(np.isnan(a), -np.inf, a)
    for _ in range(radius):
        for k in axes:
            lo = [slice(None)] * a.ndim
            hi = [slice(None)] * a.ndim
            lo[k], hi[k] = slice(None, -1), slice(1, None)
            m = out.copy()
            m[tuple(hi)] = np.maximum(m[tuple(hi)], out[tuple(lo)])
            m[tuple(lo)] = np.maximum(m[tuple(lo)], out[tuple(hi)])
            out = m
    return out


def lipschitz_halo(values: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """(n,) per grid point, how far a function sampled on a tensor grid can differ from its value there within half a
    step along every axis (the box of the joint space that point stands for).

    ``values`` (n,) on the grid of ``shape`` (C order, :class:`JointGrid`).  Along axis k, the steepest change between
    neighbouring grid points on the edges within one step of the point, max |dv_k|, measures the slope there:
    L_k = max |dv_k| / h_k (h_k the step).  The point's half-step box is then within sum_k L_k h_k / 2 = sum_k max
    |dv_k| / 2 of its value, *if* the function's slope along each axis in that box does not exceed the steepest
    change measured around it (the grid resolves the function: no peak or dip narrower than a step).  The largest
    (smallest) value over the whole box is then at most max(v + halo) (at least min(v - halo)).  Non-finite
    changes count as 0."""
    v = np.asarray(values, dtype=float).reshape(shape)
    axes = [k for k, n in enumerate(shape) if n >= 2]  # a locked joint's axis has one value: no step
    halo = np.zeros(shape)
    for k in axes:
        d = np.nan_to_num(np.abs(np.diff(v, axis=k)), nan=0.0, posinf=0.0)
        lo = [slice(None)] * v.ndim
        hi = [slice(None)] * v.ndim
        lo[k], hi[k] = slice(None, -1), slice(1, None)
        edge = np.zeros(shape)  # the steeper of the two edges along k at each point
        edge[tuple(lo)] = d
        edge[tuple(hi)] = np.maximum(edge[tuple(hi)], d)
        halo += 0.5 * neighbourhood_max(edge, axes)
    return halo.reshape(-1)


def boundary_share(mask: np.ndarray, shape: tuple[int, ...]) -> tuple[float, float]:
    """(low, high): the share of a tensor grid's cells (boxes of 2^d neighbouring grid points) whose corners all
    hold ``mask`` (n,), and the share of those where one corner at least holds it.

    When the set where ``mask`` holds has no part smaller than a cell (its boundary crosses a cell's edges, it never
    enters and leaves a cell between the corners), a cell whose corners all agree lies wholly inside or outside it,
    so its share of the box lies in [low, high]; high - low is the share of boundary cells (corners disagreeing)."""
    lo = np.asarray(mask, dtype=bool).reshape(shape)
    hi = lo
    for k in [k for k, n in enumerate(shape) if n >= 2]:
        a = [slice(None)] * lo.ndim
        b = [slice(None)] * lo.ndim
        a[k], b[k] = slice(None, -1), slice(1, None)
        lo = lo[tuple(a)] & lo[tuple(b)]
        hi = hi[tuple(a)] | hi[tuple(b)]
    return float(lo.mean()), float(hi.mean())


def share_error(mask: np.ndarray, shape: tuple[int, ...]) -> float:
    """Bound of |share of the box where ``mask`` holds - share of the grid's points where it holds|, from
    :func:`boundary_share` (its assumption): the farther end of [low, high] from the points' share."""
    share = float(np.mean(mask))
    low, high = boundary_share(mask, shape)
    return max(share - low, high - share, 0.0)


def error_bar_text(value: float, error: float, unit: str) -> str:
    """A value with its error bar as a reader writes it: ``0.2004 ± 0.0004 m²`` (the value to the error bar's first
    digit, the error with one significant figure; ``m^2``, ``m^3`` as powers); the value alone when the error is 0
    or not finite."""
    for k, v in {"^2": "\u00b2", "^3": "\u00b3"}.items():
        unit = unit.replace(k, v)
    if not (np.isfinite(error) and error > 0):
        return f"{value:.4g} {unit}"
    digits = max(0, -int(np.floor(np.log10(error))))
    return f"{value:.{digits}f} ± {error:.1g} {unit}"


# ------------------------------------------------------------------------------ progress
ProgressFn = Callable[[float, str], None]


def check_progress(progress) -> ProgressFn | None:
    if progress is None or progress is False:
        return None
    if progress is True:
        return FractionProgress()
    if not callable(progress):
        raise InputError(f"progress must be None, True or a callable (fraction, message), got {progress!r}")
    return progress


def affine_span(points: np.ndarray, rel_tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """(origin (3,), basis (r, 3)): the affine hull of ``points`` (n, 3) [m].

    r = number of singular values of the centred points above ``rel_tol`` times the largest.
    When the hull is normal to an axis of the frame (a planar arm in the x-z plane of B) the
    basis is those axes in order (x, z), else the right singular vectors (oriented so their
    largest entry is positive).
    """
    pts = np.asarray(points, dtype=float)
    step = max(1, pts.shape[0] // 20000)
    sub = pts[::step]
    origin = sub.mean(axis=0)
    _, s, vt = np.linalg.svd(sub - origin, full_matrices=False)
    r = int(np.sum(s > rel_tol * max(s[0], 1e-300))) if s[0] > 0 else 0
    basis = vt[:r]
    if 0 < r < 3:
        axes = [i for i in range(3) if np.abs(vt[r:, i]).max() < 1e-9]  # axes lying in the hull
        if len(axes) == r:
            basis = np.eye(3)[axes]
    if basis.shape[0] and not np.allclose(basis, np.eye(3)[[int(np.argmax(np.abs(b))) for b in basis]]):
        basis = basis * np.sign(basis[np.arange(basis.shape[0]), np.argmax(np.abs(basis), axis=1)])[:, None]
    if r == 3:
        basis = np.eye(3)
    return origin, basis


def best_per_cell(coords: np.ndarray, values: np.ndarray, h: float, origin=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For points ``coords`` (n, d) binned in cells of side ``h``: (grid of the largest value per cell
    (NaN where empty), grid of the index of the point holding it (-1 where empty), grid origin)."""
    pts = np.asarray(coords, dtype=float)
    vals = np.asarray(values, dtype=float)
    lo = pts.min(axis=0) - h if origin is None else np.asarray(origin, dtype=float)
    shape = tuple(int(x) for x in np.floor((pts.max(axis=0) - lo) / h).astype(np.int64) + 2)
    idx = np.floor((pts - lo) / h).astype(np.int64)
    flat = np.ravel_multi_index(tuple(idx.T), shape)
    key = np.where(np.isnan(vals), -np.inf, vals)
    order = np.lexsort((-key, flat))
    fs = flat[order]
    first = np.ones(fs.size, dtype=bool)
    first[1:] = fs[1:] != fs[:-1]
    best = np.full(int(np.prod(shape)), np.nan)
    arg = np.full(int(np.prod(shape)), -1, dtype=np.int64)
    best[fs[first]] = vals[order[first]]
    arg[fs[first]] = order[first]
    return best.reshape(shape), arg.reshape(shape), lo


def default_map_cell(coords: np.ndarray, cells_across: int = 120) -> float:
    """Cell side [m] for maps over a workspace: its largest extent over ``cells_across``."""
    ext = float((coords.max(axis=0) - coords.min(axis=0)).max())
    return max(ext / cells_across, 1e-9)


def resolve_collision(platform: Platform, collision) -> tuple[object, str]:
    """(the :class:`qprr.analysis.collision.CollisionModel` a map filters with, or None; a note saying why it is None).

    ``collision``: None (default: filter when the platform has a collision model, i.e. a URDF with ``<collision>``
    geometry on its arm links), True (filter; an error when there is no model) or False (no filter)."""
    from .collision import collision_model

    if collision is False:
        return None, "collisions not checked (collision=False)"
    if collision is not None and collision is not True:
        raise InputError(f"collision must be None (check when the platform has a collision model), True or False, got {collision!r}")
    try:
        return collision_model(platform), ""
    except InputError as exc:
        if collision is True:
            raise
        return None, f"collisions not checked: {exc}"


@dataclass(frozen=True)
class CollisionMask:
    """Which configurations of a joint grid are free of self-collision (:func:`collision_mask`).

    ``free`` (n,) bool; ``evaluated``: how many configurations :meth:`qprr.analysis.collision.CollisionModel.colliding_batch` checked (the others took
    the value on which the corners of their cell of the twice-coarser grid agree); ``audited``, ``mismatches``: a
    random sample of the inferred configurations checked afterwards, and how many of them were wrong (the error bar of
    the inference: a collision set thinner than a coarse cell could hide between agreeing corners)."""

    free: np.ndarray
    evaluated: int
    audited: int
    mismatches: int

    def describe(self) -> str:
        n = self.free.size
        if self.evaluated == n:
            failed = f" (the coarse-to-fine inference failed its audit: {self.mismatches} wrong of {self.audited})" if self.mismatches else ""
            return f"every one of the {n} configurations checked{failed}"
        return (
            f"{self.evaluated} of {n} configurations checked, the others inferred from agreeing corners of the "
            f"twice-coarser grid (audit: {self.mismatches} wrong of {self.audited} checked at random)"
        )


COLLISION_AUDIT_TOLERANCE = 0.01
"""Largest fraction of wrong inferences in the audit of :func:`collision_mask` before every configuration is checked."""

COLLISION_EXACT_BELOW = 4096
"""Grids smaller than this are checked configuration by configuration (no coarse-to-fine inference)."""


def collision_mask(model, grid: JointGrid, progress=None, label: str = "collision check", *, audit: int = 1000, seed: int = 0) -> CollisionMask:
    """The self-collision mask of the configurations of ``grid`` (``model``: a :class:`qprr.analysis.collision.CollisionModel`).

    Coarse to fine: the grid with every other value along each axis (when every axis has an odd number of values,
    so the ends are kept; else, and below :data:`COLLISION_EXACT_BELOW` configurations, every one is checked) is done
    first (recursively); a configuration whose cell of that grid has all its corners free (or
    all colliding) takes that value; the others (cells that straddle the boundary) are checked with
    :meth:`qprr.analysis.collision.CollisionModel.colliding_batch`.  ``audit`` inferred configurations, drawn with
    ``seed``, are then checked too; their
    mismatches are reported (:class:`CollisionMask`) and corrected.  When more than :data:`COLLISION_AUDIT_TOLERANCE`
    of the audited ones are wrong (collision sets thinner than the coarse cells: a coarse grid in many joints), every
    configuration is checked instead."""
    free, evaluated = _free_coarse_to_fine(model, grid, progress, label)
    inferred = np.flatnonzero(~evaluated)
    audited = mismatches = 0
    if inferred.size and audit:
        pick = np.random.default_rng(seed).choice(inferred, size=min(audit, inferred.size), replace=False)
        truth = ~model.colliding_batch(grid.configurations_at(pick))
        audited, mismatches = int(pick.size), int(np.count_nonzero(truth != free[pick]))
        free[pick] = truth
        evaluated[pick] = True
        if mismatches > COLLISION_AUDIT_TOLERANCE * audited:
            rest = np.flatnonzero(~evaluated)
            for k in range(0, rest.size, CHUNK):
                free[rest[k : k + CHUNK]] = ~model.colliding_batch(grid.configurations_at(rest[k : k + CHUNK]))
                if progress:
                    progress(min(1.0, (k + CHUNK) / rest.size), f"{label} (every configuration)")
            evaluated[:] = True
    return CollisionMask(free, int(evaluated.sum()), audited, mismatches)


def _free_coarse_to_fine(model, grid: JointGrid, progress, label: str) -> tuple[np.ndarray, np.ndarray]:
    """(free (n,), evaluated (n,) bool) of :func:`collision_mask` before the audit."""
    shape = grid.shape
    if grid.size < COLLISION_EXACT_BELOW or all(n < 3 for n in shape) or any(n >= 3 and n % 2 == 0 for n in shape):
        free = np.empty(grid.size, dtype=bool)
        for start, q in grid.chunks():
            free[start : start + len(q)] = ~model.colliding_batch(q)
            if progress:
                progress((start + len(q)) / grid.size, label)
        return free, np.ones(grid.size, dtype=bool)
    coarse = JointGrid(grid.names, tuple(a[::2] if len(a) >= 3 else a for a in grid.axes), grid.locked)
    cfree_flat, cevaluated = _free_coarse_to_fine(model, coarse, None, label)
    cfree = cfree_flat.reshape(coarse.shape)
    lo = [np.arange(n) // 2 if n >= 3 else np.zeros(n, dtype=np.int64) for n in shape]
    hi = [(np.arange(n) + 1) // 2 if n >= 3 else np.zeros(n, dtype=np.int64) for n in shape]
    all_free = np.ones(shape, dtype=bool)
    any_free = np.zeros(shape, dtype=bool)
    for corner in itertools.product((0, 1), repeat=len(shape)):
        idx = np.ix_(*[(hi if c else lo)[k] for k, c in enumerate(corner)])
        all_free &= cfree[idx]
        any_free |= cfree[idx]
    free = all_free.reshape(-1)
    todo = np.flatnonzero((any_free & ~all_free).reshape(-1))
    for k in range(0, todo.size, CHUNK):
        sel = todo[k : k + CHUNK]
        free[sel] = ~model.colliding_batch(grid.configurations_at(sel))
        if progress:
            progress(min(1.0, (k + sel.size) / todo.size), label)
    evaluated = np.zeros(grid.size, dtype=bool)
    evaluated[todo] = True
    nodes = np.ix_(*[np.arange(0, n, 2) if n >= 3 else np.arange(n) for n in shape])  # the coarse grid's own points
    evaluated.reshape(shape)[nodes] = cevaluated.reshape(coarse.shape)
    return free, evaluated
