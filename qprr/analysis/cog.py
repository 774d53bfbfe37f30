"""Centre-of-gravity regions and the slider position that puts the CoG back on the thrust axis.

Thesis Sec. 3.3.2 (3.75)-(3.81) and Sec. 6.3.3 (6.29)-(6.35): the CoG of the whole system in B,
p_cm (3.76)-(3.78), moves with the arm; a multirotor hovers with equal thrusts only with p_cm
on its thrust axis (x_cm = y_cm = 0 for the Q-PRR, (3.79)-(3.81)); the prismatic joint r0 is
there to bring it back.  The thesis draws the region the CoG sweeps in the (x, z) plane of B
without and with the slider moving (Fig. 6.31/6.32) and with a payload (Fig. 6.47/6.48).

:func:`cog_regions` maps, for each set of locked joints and each payload mass, the CoG
positions in B over the joint grid (and, with ``pitch``, the world-aligned offsets
p_c - p_b = R_b p_cm of (6.29) for base pitches in a range, (6.31)-(6.32)), with the measure of
each region (:mod:`qprr.analysis.voxels`) and its offset from the thrust axis
(:func:`qprr.kinematics.cog_offset_body`, batched).

:func:`balance` answers the slider question for any platform.  Moving a prismatic joint
translates its whole subtree rigidly, so the CoG offset from the thrust axis is affine in the
slider position r: o(r) = o(r_lo) + (r - r_lo) s.  Over a grid of the other joints, the r*
minimising |o(r)| is read off directly; the CoG is balanced where the residual |o(r*)| is 0
(within ``tol``) and r* lies in the joint limits.  The end-effector positions of the balanced
configurations form a region whose share of the workspace is reported, measured on the grid cells
that resolve r* (:data:`RESOLVED_STROKE`; near s = 0 r* runs through infinity) with an error bar
for the cells lost at the region's edge (:data:`MASKED_RICHARDSON`); tests compare it with
point-by-point counts for the Q-PRR and for a slider at the tip (Q-RRP).  Without a prismatic
joint, the map is |o| over the whole joint grid and the configurations within ``tol`` of the
axis.  For the Q-PRR, r* = -((m2/2 + m3) d2 s2 + m3 d3 s23 / 2) / (m1 + m2 + m3), the zero of
(3.80) / (6.33) (tests compare).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..charts import euler_to_rotation_batch
from ..errors import InputError, UnknownNameError
from ..model import Platform
from ..validation import as_vector
from ._common import (
    JointGrid,
    MapStatus,
    affine_span,
    check_arm_platform,
    check_int,
    check_locked,
    check_masses,
    check_pos,
    check_progress,
    make_grid,
    make_payload_mount,
)
from .budget import SampleChoice, check_budget, check_clock, grid_work, within_budget
from .chain import ArmChain
from .voxels import MeasureEstimate, estimate_measure
from .workspace import Ratio, default_variants


# ================================================================================ regions
@dataclass(frozen=True)
class CoGRegion:
    """The CoG region for one set of locked joints and one payload mass.

    ``com`` (n, 3) [m]: CoG in B on the joint ``grid`` (with ``pitches``: p_c - p_b in world-aligned
    axes, n = grid.size * len(pitches)); ``offset`` (n, 2) [m]: distance from the thrust axis in
    B (:attr:`Platform.thrust_axis_basis` axes; [x_cm, y_cm] for the Q-PRR); ``origin``,
    ``basis``: the region's affine hull; ``measure``: its length/area/volume (None if the
    region is lower-dimensional than its hull); ``extent``: (min, max) of ``com`` per axis.
    """

    label: str
    locked: dict
    mass: float
    grid: JointGrid
    pitches: np.ndarray
    com: np.ndarray
    offset: np.ndarray
    origin: np.ndarray
    basis: np.ndarray
    measure: MeasureEstimate | None
    occupancy: tuple | None
    extent: tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class CoGResult:
    """CoG regions: ``regions[(v, k)]`` for locked-joint variant v (0: none) and payload ``masses[k]``."""

    platform_name: str
    masses: np.ndarray
    variants: tuple[dict, ...]
    regions: dict
    status: MapStatus
    reason: str
    sampling: SampleChoice | None = None

    def summary(self) -> str:
        lines = [f"CoG regions of {self.platform_name}"]
        for (v, _k), r in self.regions.items():
            lo, hi = r.extent
            m = str(r.measure) if r.measure is not None else "n/a"
            lines.append(
                f"  [{v}] {r.label}, payload {r.mass:g} kg: measure {m}; x in [{lo[0]:.4f}, {hi[0]:.4f}], "
                f"z in [{lo[2]:.4f}, {hi[2]:.4f}] m; |offset| <= {np.sqrt((r.offset**2).sum(axis=1)).max():.4f} m"
            )
        for k in range(len(self.masses)):
            a, b = self.regions.get((0, k)), self.regions.get((1, k))
            if a is not None and b is not None and a.measure is not None and b.measure is not None and a.measure.dim == b.measure.dim:
                g = Ratio.of(a.measure, b.measure)
                lines.append(f"  payload {self.masses[k]:g} kg: region [0] / [1] = {g.value:.4f} +- {g.error:.2g}")
        if self.reason:
            lines.append(f"  status {self.status.value}: {self.reason}")
        if self.sampling is not None:
            lines.append(f"  {self.sampling.describe()}")
        return "\n".join(lines)


def _label(locked) -> str:
    return ", ".join(f"{k} locked at {v:g}" for k, v in locked.items()) if locked else "all joints free"


def _settings(cls, options, settings: dict):
    """``options`` (an instance of ``cls`` or None) with the keyword ``settings`` replacing its fields."""
    o = options if options is not None else cls()
    if not isinstance(o, cls):
        raise InputError(f"options must be a {cls.__name__}, got {type(o).__name__}")
    return replace(o, **settings) if settings else o


@dataclass(frozen=True)
class CoGOptions:
    """Settings of :func:`cog_regions` (each can also be given to it as a keyword).

    ``n_samples``: joint-grid size per region; ``payload_masses`` [kg]: a point payload at
    ``payload_offset`` [m] in the end-effector frame; ``variants``: locked-joint sets compared with
    the free arm (default: each prismatic joint locked at 0); ``locked``, ``ranges``: as in
    :func:`qprr.analysis.workspace`; ``pitch``: (low, high) base pitch [rad]: map
    p_c - p_b = R_y(theta) p_cm in world-aligned axes, Thesis (6.29) with (6.31), over ``n_pitch``
    pitches (None: the CoG in B); ``n_shifts``: counting shifts of the measure estimator; ``budget``, ``clock``: wall
    time [s] the map may take, ``n_samples`` then chosen from pilot runs timed with ``clock``
    (:mod:`qprr.analysis.budget`; None: ``n_samples`` is used).
    """

    n_samples: int = 200_000
    payload_masses: Sequence[float] = (0.0,)
    payload_offset: Sequence[float] = (0.0, 0.0, 0.0)
    variants: Sequence[Mapping[str, float]] | None = None
    locked: Mapping[str, float] | None = None
    ranges: Mapping[str, tuple[float, float]] | None = None
    pitch: tuple[float, float] | None = None
    n_pitch: int = 9
    n_shifts: int = 4
    budget: float | None = None
    clock: Callable[[], float] | None = None

    def __post_init__(self) -> None:  # the platform-free settings, checked however the options are built
        check_int("n_samples", self.n_samples, 8)
        check_budget(self.budget)
        check_clock(self.clock)
        check_masses(self.payload_masses)
        as_vector(self.payload_offset, 3, "payload_offset")
        check_int("n_pitch", self.n_pitch, 2)
        check_int("n_shifts", self.n_shifts, 2)


def _pitches(pitch, n_pitch: int) -> np.ndarray:
    """The base pitches [rad] of :class:`CoGOptions` (one zero pitch without ``pitch``)."""
    if pitch is None:
        return np.zeros(1)
    lo, hi = (float(x) for x in pitch)
    if not (np.isfinite(lo) and np.isfinite(hi) and -np.pi / 2 < lo <= hi < np.pi / 2):
        raise InputError(f"pitch must be (low, high) inside (-pi/2, pi/2) rad, got {pitch!r}")
    return np.linspace(lo, hi, 2 * (check_int("n_pitch", n_pitch, 2) // 2) + 1)


def _region(lk: dict, m: float, grid: JointGrid, com_body: np.ndarray, pitches: np.ndarray, axis, n_shifts: int):
    """(CoGRegion, reason or "") of the CoG positions ``com_body`` (grid.size, 3) for one locked set and payload mass."""
    point, B = axis
    c = com_body
    off = (c - point) @ B.T
    if len(pitches) > 1:
        Rp = euler_to_rotation_batch(np.column_stack([np.zeros_like(pitches), pitches, np.zeros_like(pitches)]))
        c = np.einsum("pij,nj->npi", Rp, c).reshape(-1, 3)
        off = np.repeat(off, len(pitches), axis=0)
    origin, basis = affine_span(c)
    coords = (c - origin) @ basis.T
    shape = tuple(s for s in grid.shape if s > 1) + ((len(pitches),) if len(pitches) > 1 else ())
    measure = occ = None
    reason = ""
    if basis.shape[0] and len(shape) >= basis.shape[0]:
        measure, occ = estimate_measure(coords.reshape(*shape, basis.shape[0]), n_shifts=n_shifts, return_occupancy=True)
    else:
        reason = "the CoG region is lower-dimensional than its hull, no measure"
    region = CoGRegion(_label(lk), dict(lk), float(m), grid, pitches, c, off, origin, basis, measure, occ, (c.min(axis=0), c.max(axis=0)))
    return region, reason


def cog_regions(platform: Platform, options: CoGOptions | None = None, *, progress=None, **settings) -> CoGResult:
    """CoG regions in B per locked-joint variant and payload mass (Thesis (6.29)-(6.32), Fig. 6.31/6.32/6.47/6.48).

    ``options``: :class:`CoGOptions`, and/or its fields as keywords (``cog_regions(p, n_samples=2e4,
    payload_masses=(0, 0.5))``; an unknown keyword is a TypeError); ``progress``: None, True
    (stderr) or a callable (fraction, message).
    """
    o = _settings(CoGOptions, options, settings)
    check_arm_platform(platform)
    base = check_locked(platform, o.locked)
    variants = default_variants(platform) if o.variants is None else [check_locked(platform, v) for v in o.variants]
    sets = [base] + [{**base, **v} for v in variants]
    work = grid_work(platform, sets, o.ranges)
    return within_budget(o, lambda oo, pr: _cog_regions(platform, oo, sets, pr), work, check_progress(progress))


def _cog_regions(platform: Platform, o: CoGOptions, sets: list[dict], progress) -> CoGResult:
    """:func:`cog_regions` at ``o.n_samples`` per locked set of ``sets``."""
    masses = check_masses(o.payload_masses)
    payload = make_payload_mount(platform, o.payload_offset)
    pitches = _pitches(o.pitch, o.n_pitch)
    chain = ArmChain(platform)
    axis = (platform.thrust_axis[0], np.array(platform.thrust_axis_basis))
    regions, reasons = {}, []
    for v, lk in enumerate(sets):
        grid = make_grid(platform, o.n_samples, lk, o.ranges)
        coms = np.empty((len(masses), grid.size, 3))
        for start, q in grid.chunks():
            st = chain.statics(chain.pose(q), payload.frame, payload.offset_frame)
            for k, m in enumerate(masses):
                coms[k, start : start + len(q)] = st.com_loaded(m)
            if progress:
                progress((v + (start + len(q)) / grid.size) / len(sets), "CoG regions")
        for k, m in enumerate(masses):
            regions[(v, k)], why = _region(lk, m, grid, coms[k], pitches, axis, o.n_shifts)
            if why:
                reasons.append(f"[{v}] payload {m:g} kg: {why}")
    return CoGResult(platform.name, masses, tuple(sets), regions, MapStatus.PARTIAL if reasons else MapStatus.OK, "; ".join(reasons))


# ================================================================================ balance
@dataclass(frozen=True)
class CoGBalanceMap:
    """Where the CoG can be put on the thrust axis (see the module docstring).

    With a slider: ``grid`` over the other joints (the slider axis has one value), ``r_star``
    (n,) [m] the slider position minimising the offset (NaN where the offset does not depend on
    it), ``residual`` (n,) [m] the offset left at r* (across the slider's direction),
    ``offset_clamped`` (n,) [m] the offset at r* clamped to the limits, ``balanced`` (n,) the
    configurations with ``offset_clamped <= tol``.  Without a slider (``slider`` None): ``grid``
    over every joint, ``offset_clamped`` = |o| and ``balanced`` = |o| <= tol.
    ``ee_body`` (n, 3): end effector at the balanced slider position (or at the grid point).
    ``fraction_configurations``: share of the grid balanced; ``balanced_measure`` /
    ``workspace_measure`` (length/area/volume of the end-effector positions that can be reached
    balanced / of all) and ``fraction_workspace`` (their ratio with its error bar).
    """

    platform_name: str
    slider: str | None
    mass: float
    tol: float
    grid: JointGrid
    r_star: np.ndarray | None
    residual: np.ndarray | None
    offset_clamped: np.ndarray
    balanced: np.ndarray
    ee_body: np.ndarray
    fraction_configurations: float
    balanced_measure: MeasureEstimate | None
    workspace_measure: MeasureEstimate | None
    fraction_workspace: Ratio | None
    status: MapStatus
    reason: str
    sampling: SampleChoice | None = None

    def summary(self) -> str:
        what = f"slider {self.slider!r}" if self.slider else "no slider: |offset| over the joint grid"
        lines = [
            f"CoG balance of {self.platform_name} ({what}, payload {self.mass:g} kg, tol {self.tol:g} m): "
            f"{100 * self.fraction_configurations:.2f}% of the {self.grid.size} grid configurations"
        ]
        if self.fraction_workspace is not None:
            lines.append(
                f"  end-effector positions reachable balanced: {self.balanced_measure} of {self.workspace_measure} "
                f"= {100 * self.fraction_workspace.value:.2f} +- {100 * self.fraction_workspace.error:.2g}% of the workspace"
            )
        if self.reason:
            lines.append(f"  status {self.status.value}: {self.reason}")
        if self.sampling is not None:
            lines.append(f"  {self.sampling.describe()}")
        return "\n".join(lines)


@dataclass(frozen=True)
class BalanceOptions:
    """Settings of :func:`balance` (each can also be given to it as a keyword).

    ``slider``: name of the prismatic joint used to balance; "auto": the platform's only prismatic
    joint (an error names them if there are several); None: no slider (map |offset|).
    ``n_samples``: grid size over the other joints (over all joints without a slider).
    ``payload_mass``, ``payload_offset``: a point payload [kg] at [m] in the end-effector frame.
    ``locked``, ``ranges``: as in :func:`qprr.analysis.workspace` (the slider may not be locked).
    ``tol``: offset [m] that counts as balanced (the thesis's epsilon of (3.79); default 1e-6 m:
    exactly on the axis up to round-off).  ``n_shifts``: counting shifts of the measure estimator.  ``budget``,
    ``clock``: wall time [s] the map may take, ``n_samples`` then chosen from pilot runs timed with ``clock``
    (:mod:`qprr.analysis.budget`; None: ``n_samples`` is used).
    """

    slider: str | None = "auto"
    n_samples: int = 200_000
    payload_mass: float = 0.0
    payload_offset: Sequence[float] = (0.0, 0.0, 0.0)
    locked: Mapping[str, float] | None = None
    ranges: Mapping[str, tuple[float, float]] | None = None
    tol: float = 1e-6
    n_shifts: int = 4
    budget: float | None = None
    clock: Callable[[], float] | None = None

    def __post_init__(self) -> None:  # the platform-free settings, checked however the options are built
        if self.slider is not None and not isinstance(self.slider, str):
            raise InputError(f"slider must be a prismatic joint's name, 'auto' or None, got {self.slider!r}")
        check_int("n_samples", self.n_samples, 8)
        check_budget(self.budget)
        check_clock(self.clock)
        check_masses([self.payload_mass], "payload_mass")
        as_vector(self.payload_offset, 3, "payload_offset")
        check_pos("tol", self.tol)
        check_int("n_shifts", self.n_shifts, 2)


@dataclass(frozen=True)
class _BalanceMap:
    """The balance map on ``grid``: r*, residual (None without a slider), clamped offset, end effector, and
    ``smooth``: grid points where every grid cell at the point resolves the balancing slider position
    (:func:`_resolved_points`)."""

    grid: JointGrid
    r_star: np.ndarray | None
    residual: np.ndarray | None
    offset: np.ndarray
    ee_body: np.ndarray
    smooth: np.ndarray


@dataclass(frozen=True)
class _Loading:
    """What the CoG of a configuration depends on besides the joints: the chain, the payload (mass ``mass`` [kg]),
    the thrust axis (``point`` [m] and the (2, 3) ``basis`` of the offset, both in B)."""

    chain: ArmChain
    payload: object
    mass: float
    point: np.ndarray
    basis: np.ndarray

    def offset_body(self, pose) -> np.ndarray:
        """(n, 2) CoG offset [m] from the thrust axis in B (thrust-axis basis axes)."""
        c = self.chain.statics(pose, self.payload.frame, self.payload.offset_frame).com_loaded(self.mass)
        return (c - self.point) @ self.basis.T


def _slider_of(platform: Platform, slider, base: dict) -> str | None:
    """The balancing slider of :class:`BalanceOptions` resolved ("auto", a name or None)."""
    prism = [j.name for j in platform.arm if j.kind == "prismatic" and j.name not in base]
    if slider == "auto":
        if len(prism) > 1:
            raise InputError(f"platform {platform.name!r} has several prismatic joints {prism}: name the slider")
        return prism[0] if prism else None
    if slider is not None:
        if slider not in platform.arm_names:
            raise UnknownNameError("slider joint", slider, tuple(prism))
        if slider not in prism:
            raise InputError(f"slider {slider!r} must be a free prismatic joint (free prismatic joints: {prism})")
    return slider


def _offset_map(platform: Platform, load: _Loading, grid: JointGrid) -> _BalanceMap:
    """No slider: |offset| and the end effector over the whole joint grid."""
    off = np.empty(grid.size)
    ee = np.empty((grid.size, 3))
    for start, q in grid.chunks():
        pose = load.chain.pose(q)
        off[start : start + len(q)] = np.sqrt((load.offset_body(pose) ** 2).sum(axis=1))
        ee[start : start + len(q)] = load.chain.frame_position(pose, platform.ee_frame)
    return _BalanceMap(grid, None, None, off, ee, np.ones(grid.size, dtype=bool))


def _slider_map(platform: Platform, load: _Loading, grid: JointGrid, k: int, limits: tuple[float, float], progress) -> _BalanceMap:
    """With the slider (arm joint ``k``, ``limits`` [m]): o(r) = o(r_lo) + (r - r_lo) s is affine in r (the slider
    translates its subtree), so r* = argmin |o(r)| is read off; the end effector at r* clamped to the limits."""
    lo_r, hi_r = limits
    n = grid.size
    r_star, resid, off, ee, s_all = np.empty(n), np.empty(n), np.empty(n), np.empty((n, 3)), np.empty((n, load.basis.shape[0]))
    for start, q in grid.chunks():
        sl = slice(start, start + len(q))
        o_lo = load.offset_body(load.chain.pose(q))
        q_hi = q.copy()
        q_hi[:, k] = hi_r
        s = (load.offset_body(load.chain.pose(q_hi)) - o_lo) / (hi_r - lo_r)  # d offset / d r (exact: affine)
        s_all[sl] = s
        ss = (s**2).sum(axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(ss > 1e-24, -(s * o_lo).sum(axis=1) / ss, np.nan)
        r = lo_r + t
        r_star[sl] = r
        resid[sl] = np.sqrt(((o_lo + np.nan_to_num(t)[:, None] * s) ** 2).sum(axis=1))
        rc = np.clip(np.nan_to_num(r, nan=lo_r), lo_r, hi_r)
        off[sl] = np.sqrt(((o_lo + (rc - lo_r)[:, None] * s) ** 2).sum(axis=1))
        qb = q.copy()
        qb[:, k] = rc
        ee[sl] = load.chain.frame_position(load.chain.pose(qb), platform.ee_frame)
        if progress:
            progress((start + len(q)) / n, "CoG balance")
    return _BalanceMap(grid, r_star, resid, off, ee, _resolved_points(s_all, r_star, limits, grid.shape))


def _cell_corners(shape: tuple[int, ...]):
    """Per corner of the grid cells: the index tuple selecting that corner of every cell (axes of length 1 kept)."""
    axes = [a for a, n in enumerate(shape) if n > 1]
    for corner in itertools.product((0, 1), repeat=len(axes)):
        sl = [slice(None)] * len(shape)
        for a, c in zip(axes, corner):
            sl[a] = slice(1, None) if c else slice(0, -1)
        yield tuple(sl)


RESOLVED_STROKE = 0.25
"""Largest change of the balancing slider position r* across one grid cell, as a share of the stroke, for the cell to
count in the balanced measure (:func:`_resolved_points`)."""


def _resolved_points(s: np.ndarray, r_star: np.ndarray, limits: tuple[float, float], shape: tuple[int, ...]) -> np.ndarray:
    """Grid points all of whose cells resolve the balancing slider position r* = lo - o . s / |s|^2 (s = d offset / d r,
    (n, c)): s keeps one side (s . s_0 > 0 at every corner, s_0 the cell's first corner) and r* clamped to the
    ``limits`` changes by at most :data:`RESOLVED_STROKE` of the stroke across the cell.  Near s = 0, r* runs through infinity: inside a cell the
    end effector would move by a whole stroke (or jump between the stops where s changes sign), and the cell's
    affine model (a zonotope grown by the second differences, :mod:`qprr.analysis.voxels`) would cover ground that the
    balanced set does not reach.  The cells left out lie in a strip along s = 0 whose width shrinks with the grid
    step; the measure's coarse-grid comparison shows what they cost."""
    S = s.reshape(*shape, s.shape[1])
    R = np.clip(r_star, *limits).reshape(shape)  # the position used (clamped to the stops); NaN where s = 0
    corners = list(_cell_corners(shape))
    first = S[corners[0]]
    bad = np.zeros(first.shape[:-1], dtype=bool)
    r_lo, r_hi = R[corners[0]].copy(), R[corners[0]].copy()
    for c in corners:
        bad |= ~((S[c] * first).sum(axis=-1) > 0.0) | np.isnan(R[c])
        r_lo, r_hi = np.fmin(r_lo, R[c]), np.fmax(r_hi, R[c])
    with np.errstate(invalid="ignore"):
        bad |= ~(r_hi - r_lo <= RESOLVED_STROKE * (limits[1] - limits[0]))
    ok = np.ones(shape, dtype=bool)
    for c in corners:
        ok[c] &= ~bad
    return ok.reshape(-1)


MASKED_RICHARDSON = 2.0
"""Error bar of the balanced measure: this times |count(dq) - count(2 dq)| plus twice the shifts' standard error.  The
cells across the boundary of the balanced set (where r* reaches a stop) are left out whole, a loss that shrinks
slowly with the grid step: on the Q-PRR the count rose by 7.6e-5 then 5.0e-5 m^2 from 5e4 to 2e5 to 8e5 samples
(order ~0.6 in the step, ratio 2/3 per halving), so the error of the finer count is up to twice the difference
(the geometric tail 2/3 / (1 - 2/3)); :func:`qprr.analysis.voxels.estimate_measure` assumes order ~1.6 (half)."""


def _measures(platform: Platform, chain: ArmChain, ws_grid: JointGrid, bmap: _BalanceMap, ok: np.ndarray, n_shifts: int):
    """(balanced measure, workspace measure, their Ratio, reason or "") of the end-effector positions, in the workspace's hull."""
    ws_pts = np.empty((ws_grid.size, 3))
    for start, q in ws_grid.chunks():
        ws_pts[start : start + len(q)] = chain.frame_position(chain.pose(q), platform.ee_frame)
    origin, basis = affine_span(ws_pts)
    dim = basis.shape[0]
    ws_shape = tuple(s for s in ws_grid.shape if s > 1)
    bshape = tuple(s for s in bmap.grid.shape if s > 1)
    if not (dim and len(ws_shape) >= dim and len(bshape) >= dim):
        return None, None, None, "the balanced set has fewer free joints than the workspace dimension: no measure (see fraction_configurations)"
    ws_m = estimate_measure(((ws_pts - origin) @ basis.T).reshape(*ws_shape, dim), n_shifts=n_shifts)
    try:
        bal_m = estimate_measure(
            ((bmap.ee_body - origin) @ basis.T).reshape(*bshape, dim), n_shifts=n_shifts, valid=(ok & bmap.smooth).reshape(bshape)
        )
        bal_m = replace(bal_m, error=MASKED_RICHARDSON * abs(bal_m.raw - bal_m.coarse) + 2.0 * bal_m.stderr)
    except InputError:
        reason = (
            "no configuration balances the CoG within tol"
            if not ok.any()
            else "the balanced configurations cover no full grid cell (with a slider: none on which its balancing "
            "position is resolved): a curve or isolated points in the workspace, or a band too thin for the grid; no "
            "measure at this tol and n_samples"
        )
        return None, ws_m, None, reason
    if bal_m.coarse == 0.0 < bal_m.raw:
        return (
            bal_m,
            ws_m,
            Ratio.of(bal_m, ws_m),
            (
                "the grid with twice the step resolves none of the balanced band, so its "
                "error bar is no bound: the measure is a lower bound; raise n_samples"
            ),
        )
    return bal_m, ws_m, Ratio.of(bal_m, ws_m), ""


def balance(platform: Platform, options: BalanceOptions | None = None, *, progress=None, **settings) -> CoGBalanceMap:
    """The slider position that zeroes the CoG offset from the thrust axis, over the other joints.

    ``options``: :class:`BalanceOptions`, and/or its fields as keywords (``balance(p, n_samples=2e4,
    tol=1e-3)``; an unknown keyword is a TypeError); ``progress``: None, True (stderr) or a callable
    (fraction, message).  The balanced end-effector set is measured over the grid cells on which the
    balancing slider position is continuous (see :func:`_resolved_points`).
    """
    o = _settings(BalanceOptions, options, settings)
    check_arm_platform(platform)
    base = check_locked(platform, o.locked)
    slider = _slider_of(platform, o.slider, base)
    sets = [base] if slider is None else [base, {**base, slider: _slider_range(platform, slider, o.ranges)[0]}]
    work = grid_work(platform, sets, o.ranges)
    return within_budget(o, lambda oo, pr: _balance(platform, oo, base, slider, pr), work, check_progress(progress))


def _slider_range(platform: Platform, slider: str, ranges) -> tuple[float, float]:
    """(low, high) [m] of the balancing slider: its limits or its entry of ``ranges``."""
    js = platform.arm[platform.arm_names.index(slider)]
    return (float(js.lower), float(js.upper)) if ranges is None or slider not in ranges else tuple(float(x) for x in ranges[slider])


def _balance(platform: Platform, o: BalanceOptions, base: dict, slider: str | None, progress) -> CoGBalanceMap:
    """:func:`balance` at ``o.n_samples`` (``base``: the locked joints; ``slider``: the balancing joint or None)."""
    m = float(check_masses([o.payload_mass], "payload_mass")[0])
    payload = make_payload_mount(platform, o.payload_offset)
    tol = check_pos("tol", o.tol)
    chain = ArmChain(platform)
    point, _ = platform.thrust_axis
    load = _Loading(chain, payload, m, point, np.array(platform.thrust_axis_basis))
    ws_grid = make_grid(platform, o.n_samples, base, o.ranges)
    if slider is None:
        bmap = _offset_map(platform, load, ws_grid)
    else:
        k = platform.arm_names.index(slider)
        lo_r, hi_r = _slider_range(platform, slider, o.ranges)
        grid = make_grid(platform, o.n_samples, {**base, slider: float(lo_r)}, o.ranges)
        bmap = _slider_map(platform, load, grid, k, (lo_r, hi_r), progress)
    ok = bmap.offset <= tol
    bal_m, ws_m, ratio, reason = _measures(platform, chain, ws_grid, bmap, ok, o.n_shifts)
    status = MapStatus.OK if not reason else (MapStatus.EMPTY if not ok.any() else MapStatus.PARTIAL)
    return CoGBalanceMap(
        platform.name,
        slider,
        m,
        tol,
        bmap.grid,
        bmap.r_star,
        bmap.residual,
        bmap.offset,
        ok,
        bmap.ee_body,
        float(ok.mean()),
        bal_m,
        ws_m,
        ratio,
        status,
        reason,
    )
