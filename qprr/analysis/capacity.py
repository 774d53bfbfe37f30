"""Payload capacity over the workspace, with the limiting factor (Thesis Fig. 6.46 generalised).

Thesis Sec. 6.4.1.1 (Fig. 6.46) distinguishes a transport mission, where the payload depends
on the thrust alone, and a manipulation mission, where it depends on the joint torques; it
prints the two holding torques for one configuration (misprinted: docs/thesis-errata.md, Sec.
6.4.1.1 rows).  Here, for every arm configuration (base level, at rest, point payload at the
end effector) the largest payload m is the smallest of three limits, each exact and affine in
m (:class:`qprr.analysis.hover.PayloadLimits`):

* **thrust**: the collective thrust, F_max / g - m_platform, F_max the largest vertical force
  of the rotors (what a transport mission can lift);
* **attitude**: the rotors must also produce the torque of the off-axis weight, keeping
  ``torque_reserve`` [N m] about every axis: the hover wrench leaves the wrench set (shrunk by
  the reserve) before the collective thrust runs out;
* **effort**: an arm joint reaches its effort limit (which joint is named).

The limiting factor is "effort" when the joints bind first; otherwise "thrust" when the
rotors' limit is within ``thrust_tol`` (relative) of the collective one (the off-axis torque
costs less than that), else "attitude".  Over the workspace, each cell of end-effector
positions keeps the configuration with the largest capacity (a redundant arm - the Q-PRR's
slider - chooses the one that balances the CoG).

Error bars.  The grid samples the box of joint ranges; what it reports about the box has a discretisation
error, bounded from the grid itself under one stated assumption each:

* the **largest** and **smallest** capacity over the box (``best``, ``worst``): every configuration lies
  within half a step along every joint of a grid point, and the capacity (the smallest of three Lipschitz
  limits, clipped at 0) changes over that half step by at most half the steepest change measured between
  neighbouring grid points around it, summed over the joints
  (:func:`qprr.analysis._common.lipschitz_halo`), *assuming* its slope is no steeper between the grid
  points than the steepest change measured around them.  So the box's largest capacity lies in [grid best,
  max(cap + halo)] (and below the collective-thrust limit), its smallest in [max(min(cap - halo), 0), grid
  worst];
* the **shares** limited by each factor: a cell of the grid (2^d neighbouring points) whose corners agree
  is counted wholly in their factor, *assuming* no region of one factor is smaller than a cell; the
  box's share then lies between the share of cells whose corners all have that factor and the share
  where one at least has it (the boundary cells make the difference;
  :func:`qprr.analysis._common.share_error`).

* the **smallest best capacity over the workspace** (``worst_reachable``), over the cells the map holds (its cells,
  as binned): a cell's best over the box is at least the grid's; it is at most the largest capacity + halo of
  the grid points whose half-step box can reach the cell, which lie within K cells of it, K the largest
  distance an end-effector coordinate can move within a half step (the same halo, of the coordinates) in cells.
  So the workspace's smallest best lies in [grid value, min over the held cells of that dilated largest].

The workspace cells' shares (:meth:`CapacityResult.map_fractions`) have no error bar.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from ..errors import InputError
from ..model import Platform
from ..validation import as_vector
from ._common import (
    JointGrid,
    MapStatus,
    affine_span,
    best_per_cell,
    check_arm_platform,
    check_int,
    check_locked,
    check_pos,
    check_progress,
    error_bar_text,
    lipschitz_halo,
    make_grid,
    make_payload_mount,
    neighbourhood_max,
    share_error,
)
from .budget import SampleChoice, check_budget, check_clock, grid_work, within_budget
from .chain import ArmChain
from .hover import check_reserve, payload_limits
from .voxels import map_cell
from .wrenchset import wrench_set

MAP_CELLS = 120
"""Cells across the largest extent of the capacity map, unless the samples are too sparse for them
(:func:`qprr.analysis.voxels.map_cell`: then coarser cells, never empty ones between samples)."""

LIMITS = ("thrust", "attitude", "effort", "infeasible")
"""Limiting factors, in the order of the integer codes of :attr:`CapacityResult.limiting`."""


@dataclass(frozen=True)
class CapacityResult:
    """Largest payload per configuration and over the workspace (see the module docstring).

    Per configuration of ``grid`` (n): ``ee_body`` (n, 3) [m]; ``m_thrust`` (scalar), ``m_attitude``,
    ``m_effort`` (n,) [kg] the three limits; ``effort_joint`` (n,) the binding joint (-1: none);
    ``capacity`` (n,) [kg] (clipped at 0: a configuration that cannot hover even empty has
    capacity 0 and factor "infeasible"); ``limiting`` (n,) codes into :data:`LIMITS`.
    Over the workspace, in the hull ``origin`` + ``basis`` coordinates with cells of side ``cell``
    [m]: ``map_capacity`` (grid, NaN outside), ``map_limiting`` (codes, -1 outside),
    ``map_origin``.  ``best`` = (capacity, q_arm, ee_body) of the best configuration;
    ``worst_reachable``: the smallest per-cell best capacity over the workspace [kg].

    ``worst`` [kg]: the smallest capacity over the joint grid (the worst configuration).

    Error bars of the joint grid against the joint box it samples (the module docstring, "Error bars"):
    ``best_error`` [kg] bounds |largest capacity over the box - ``best[0]``|, ``worst_error`` [kg] |smallest
    capacity over the box - ``worst``| (:func:`_extreme_errors`); ``fraction_errors`` (4,) [share of
    the box, 0-1] bounds |share of the box limited by each factor of :data:`LIMITS` - :meth:`fractions`|
    (:func:`qprr.analysis._common.share_error`); ``worst_reachable_error`` [kg] bounds |smallest best capacity
    over the box, on the map's cells - ``worst_reachable``| (:func:`_workspace_error`).
    """

    platform_name: str
    grid: JointGrid
    ee_body: np.ndarray
    m_thrust: float
    m_attitude: np.ndarray
    m_effort: np.ndarray
    effort_joint: np.ndarray
    capacity: np.ndarray
    limiting: np.ndarray
    joint_names: tuple[str, ...]
    torque_reserve: np.ndarray
    origin: np.ndarray
    basis: np.ndarray
    cell: float
    map_capacity: np.ndarray
    map_limiting: np.ndarray
    map_origin: np.ndarray
    best: tuple
    worst_reachable: float
    status: MapStatus
    reason: str
    worst: float
    best_error: float
    worst_error: float
    fraction_errors: np.ndarray
    worst_reachable_error: float
    sampling: SampleChoice | None = None

    def fractions(self) -> dict[str, float]:
        """Share of the configurations limited by each factor."""
        return {name: float(np.mean(self.limiting == k)) for k, name in enumerate(LIMITS)}

    def map_fractions(self) -> dict[str, float]:
        """Share of the workspace cells limited by each factor (at their best configuration)."""
        inside = self.map_limiting >= 0
        n = max(int(inside.sum()), 1)
        return {name: float(np.sum(self.map_limiting == k)) / n for k, name in enumerate(LIMITS)}

    def summary(self) -> str:
        cap, q, ee = self.best
        fr = self.map_fractions()
        share = self.fractions()
        lines = [
            f"payload capacity of {self.platform_name} (torque reserve {np.round(self.torque_reserve, 4).tolist()} N m): "
            f"collective-thrust limit {self.m_thrust:.4g} kg",
            f"  best {error_bar_text(cap, self.best_error, 'kg')} at q_arm = {np.round(q, 4).tolist()} (end effector "
            f"{np.round(ee, 4).tolist()} m in B); worst configuration {error_bar_text(self.worst, self.worst_error, 'kg')}",
            "  configurations limited by "
            + ", ".join(f"{k} {error_bar_text(100 * share[k], 100 * e, '%')}" for k, e in zip(LIMITS, self.fraction_errors)),
            f"  over the workspace ({int((self.map_limiting >= 0).sum())} cells of {self.cell * 1000:.3g} mm): smallest best "
            f"capacity {error_bar_text(self.worst_reachable, self.worst_reachable_error, 'kg')}; limited by "
            + ", ".join(f"{k} {100 * v:.1f}%" for k, v in fr.items()),
        ]
        per = {}
        for j in self.effort_joint[self.limiting == 2]:
            per[self.joint_names[j]] = per.get(self.joint_names[j], 0) + 1
        if per:
            lines.append("  effort-limited configurations by joint: " + ", ".join(f"{k} {v}" for k, v in per.items()))
        lines.append(
            "  error bars: the joint grid against the joint box (capacity: the steepest change between neighbouring "
            "configurations; shares: the cells whose corners disagree); the workspace cells' shares have none"
        )
        if self.reason:
            lines.append(f"  status {self.status.value}: {self.reason}")
        if self.sampling is not None:
            lines.append(f"  {self.sampling.describe()}")
        return "\n".join(lines)


@dataclass(frozen=True)
class CapacityOptions:
    """Settings of :func:`capacity` (each can also be given to it as a keyword).

    ``n_samples``: joint-grid size; ``payload_offset``: payload centre in the end-effector frame [m];
    ``locked``, ``ranges``: as in :func:`qprr.analysis.workspace`; ``torque_reserve``: torque [N m]
    kept available about x, y, z of B (one value or three); ``thrust_tol``: relative gap below which
    the rotors' limit counts as the collective thrust's; ``cell``: workspace cell side [m] (default:
    the largest extent / :data:`MAP_CELLS`, coarser when the samples would leave empty cells between them,
    :func:`qprr.analysis.voxels.map_cell`); ``budget``, ``clock``: wall time [s] the map may take, ``n_samples`` then chosen from
    pilot runs timed with ``clock`` (:mod:`qprr.analysis.budget`; None: ``n_samples`` is used).
    """

    n_samples: int = 200_000
    payload_offset: object = (0.0, 0.0, 0.0)
    locked: Mapping[str, float] | None = None
    ranges: Mapping[str, tuple[float, float]] | None = None
    torque_reserve: object = 0.0
    thrust_tol: float = 0.01
    cell: float | None = None
    budget: float | None = None
    clock: Callable[[], float] | None = None

    def __post_init__(self) -> None:  # the platform-free settings, checked however the options are built
        check_int("n_samples", self.n_samples, 2)
        check_budget(self.budget)
        check_clock(self.clock)
        as_vector(self.payload_offset, 3, "payload_offset")
        check_reserve(self.torque_reserve)
        check_pos("thrust_tol", self.thrust_tol, strict=False)
        if self.cell is not None:
            check_pos("cell", self.cell)


def capacity(platform: Platform, options: CapacityOptions | None = None, *, progress=None, **settings) -> CapacityResult:
    """Payload capacity map (see the module docstring) of any platform with finite thrust bounds and arm effort limits.

    ``options``: :class:`CapacityOptions`, and/or its fields as keywords (``capacity(p, n_samples=2e4,
    torque_reserve=0.5)``; an unknown keyword is a TypeError); ``progress``: None, True (stderr) or a
    callable (fraction, message).
    """
    o = options if options is not None else CapacityOptions()
    if not isinstance(o, CapacityOptions):
        raise InputError(f"options must be a CapacityOptions, got {type(o).__name__}")
    o = replace(o, **settings) if settings else o
    check_arm_platform(platform)
    work = grid_work(platform, [check_locked(platform, o.locked)], o.ranges)
    return within_budget(o, lambda oo, pr: _capacity(platform, oo, pr), work, check_progress(progress))


def _capacity(platform: Platform, o: CapacityOptions, progress) -> CapacityResult:
    """:func:`capacity` at ``o.n_samples``."""
    n_samples, payload_offset, locked, ranges, cell = o.n_samples, o.payload_offset, o.locked, o.ranges, o.cell
    torque_reserve = check_reserve(o.torque_reserve)
    thrust_tol = check_pos("thrust_tol", o.thrust_tol, strict=False)
    payload = make_payload_mount(platform, payload_offset)
    grid = make_grid(platform, n_samples, locked, ranges)
    W = wrench_set(platform)
    chain = ArmChain(platform)
    eff_lim = np.array(platform.arm_effort_limits)
    n = grid.size
    ee = np.empty((n, 3))
    m_att, m_eff, joint = np.empty(n), np.empty(n), np.empty(n, dtype=np.int64)
    m_thr = None
    for start, q in grid.chunks():
        sl = slice(start, start + len(q))
        pose = chain.pose(q)
        st = chain.statics(pose, payload.frame, payload.offset_frame)
        ee[sl] = chain.frame_position(pose, platform.ee_frame)
        pl = payload_limits(st, W, eff_lim, platform.g, torque_reserve)
        m_att[sl], m_eff[sl], joint[sl] = pl.rotors, pl.effort, pl.effort_joint
        m_thr = pl.collective
        if progress:
            progress((start + len(q)) / n, "capacity map")
    cap = np.minimum(np.minimum(m_att, m_eff), m_thr)
    lim = np.where(m_eff < m_att, 2, np.where(m_att >= (1.0 - thrust_tol) * m_thr, 0, 1))
    lim = np.where(cap < 0.0, 3, lim)
    cap = np.clip(cap, 0.0, None)
    origin, basis = affine_span(ee)
    coords = (ee - origin) @ basis.T
    h = map_cell(coords, MAP_CELLS) if cell is None else check_pos("cell", cell)
    best_map, arg, morigin = best_per_cell(coords, np.where(lim == 3, -1.0, cap), h)
    map_lim = np.where(arg >= 0, lim[np.clip(arg, 0, None)], -1)
    best_map = np.where(arg >= 0, cap[np.clip(arg, 0, None)], np.nan)
    i = int(np.argmax(cap))
    allq = grid.configurations(i, i + 1)[0]
    halo = lipschitz_halo(cap, grid.shape)
    status, reason = MapStatus.OK, ""
    if np.all(lim == 3):
        status, reason = MapStatus.EMPTY, "no configuration hovers even without payload"
    return CapacityResult(
        platform.name,
        grid,
        ee,
        float(m_thr),
        m_att,
        m_eff,
        joint,
        cap,
        lim,
        platform.arm_names,
        torque_reserve,
        origin,
        basis,
        h,
        best_map,
        map_lim,
        morigin,
        (float(cap[i]), allq, ee[i]),
        float(np.nanmin(best_map)),
        status,
        reason,
        float(cap.min()),
        *_extreme_errors(cap, halo, float(m_thr)),
        np.array([share_error(lim == k, grid.shape) for k in range(len(LIMITS))]),
        _workspace_error(coords, np.minimum(cap + halo, m_thr), grid.shape, h, morigin, best_map),
    )


def _extreme_errors(cap: np.ndarray, halo: np.ndarray, m_thrust: float) -> tuple[float, float]:
    """(best_error, worst_error) [kg]: bounds of how far the largest and the smallest capacity over the joint box lie
    from the grid's (the module docstring, "Error bars"; :func:`qprr.analysis._common.lipschitz_halo`).  The box's
    largest capacity is in [max cap, max(cap + halo)] (at most ``m_thrust`` [kg], the collective limit), its
    smallest in [max(min(cap - halo), 0), min cap] (a capacity is >= 0 by definition: clipped)."""
    top = min(float(np.max(cap + halo)), m_thrust)  # the collective limit is a ceiling: at it, no error but rounding
    best_error = top - float(np.max(cap)) if top - float(np.max(cap)) > 1e-12 * max(m_thrust, 1.0) else 0.0
    worst_error = float(np.min(cap) - max(float(np.min(cap - halo)), 0.0))
    return best_error, worst_error


def _workspace_error(coords: np.ndarray, upper: np.ndarray, shape: tuple[int, ...], h: float, origin, best_map) -> float:
    """Bound [kg] of |smallest best capacity over the box, on the cells ``best_map`` holds - its smallest value|
    (the module docstring, "Error bars").

    ``coords`` (n, d) [m]: the grid points' end effectors in the hull coordinates, binned in cells of side ``h``
    from ``origin`` as ``best_map``; ``upper`` (n,) [kg]: capacity + halo, the most each point's half-step box
    holds; ``shape``: the joint grid's.  Each coordinate's halo (:func:`qprr.analysis._common.lipschitz_halo`)
    bounds how far the end effector moves within a point's half-step box, so that box reaches cells within
    K = ceil(largest halo / h) of the point's: a held cell's best is at most the largest ``upper`` within K
    cells, and at least the grid's."""
    reach = max((float(np.max(lipschitz_halo(coords[:, i], shape))) for i in range(coords.shape[1])), default=0.0)
    idx = np.floor((coords - origin) / h).astype(np.int64)  # the cells of best_map (best_per_cell's binning)
    top = np.full(best_map.size, -np.inf)
    np.maximum.at(top, np.ravel_multi_index(tuple(idx.T), best_map.shape), upper)
    top = neighbourhood_max(top.reshape(best_map.shape), list(range(best_map.ndim)), int(np.ceil(reach / h)))
    held = np.isfinite(best_map)
    return float(max(np.min(top[held]) - np.min(best_map[held]), 0.0))
