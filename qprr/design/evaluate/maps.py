"""Evaluate one platform on the design maps of :mod:`qprr.analysis` (the numbers of :data:`DESIGN_METRICS`)."""

from __future__ import annotations

from functools import cached_property

import numpy as np
import pinocchio as pin

from ...analysis import balance, capacity, hover, singularity, workspace
from ...model import check_platform
from ..spec.metrics import DESIGN_METRICS
from ..spec.study import Effort


def slider_of(platform) -> str | None:
    """The first prismatic joint (the one :func:`qprr.analysis.balance` moves), or None."""
    platform = check_platform(platform)
    return next((j.name for j in platform.arm if j.kind == "prismatic"), None)


def axis_distance(platform, p_body: np.ndarray) -> np.ndarray:
    """Distance [m] of points in B (n, 3) from the thrust axis."""
    point, axis = platform.thrust_axis
    d = np.asarray(p_body) - np.asarray(point)
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.linalg.norm(d - np.outer(d @ a, a), axis=1)


CELLS_ACROSS = 40
"""Cells across the workspace's largest extent in :func:`balanced_share` (the hit count's resolution)."""


def balanced_share(region, bal) -> float:
    """Share of the workspace cells hit by a configuration whose CoG is within tolerance of the thrust axis.

    ``region``: the workspace region (all joints free) of :func:`qprr.analysis.workspace`; ``bal``: the
    :func:`qprr.analysis.balance` result (end effector at the balancing slider position, and which
    configurations balance).  Both point sets are binned on the same cells of the workspace's hull
    (side: largest extent / :data:`CELLS_ACROSS`); the share is (cells with a balanced point) / (cells
    with any point).  Unlike a measure of the balanced set's image, a hit count does not assume that the
    balancing slider position varies smoothly between neighbouring configurations (a slider at the tip
    makes it jump between its stops), at the price of a resolution bias of about one cell along the
    boundary (the same for every design of a study).
    """
    ws = (region.points_body - region.origin) @ region.basis.T
    if not bal.balanced.any() or ws.shape[1] == 0:
        return 0.0
    lo = ws.min(axis=0)
    h = float(np.max(ws.max(axis=0) - lo)) / CELLS_ACROSS
    if h <= 0.0:
        return 0.0
    cells = {tuple(c) for c in np.floor((ws - lo) / h).astype(np.int64)}
    b = (bal.ee_body[bal.balanced] - region.origin) @ region.basis.T
    hit = {tuple(c) for c in np.floor((b - lo) / h).astype(np.int64)}
    return len(hit & cells) / len(cells)


class DesignMaps:
    """The maps of one design, each computed on first use and shared by the metrics (:class:`DesignMetric` ``compute``).

    ``platform``, ``effort`` (:class:`~qprr.design.spec.study.Effort`), ``seed`` (the measure's counting-grid shifts),
    ``collision`` (the workspace checks self-collision: ``free_hover_volume``); the maps: :attr:`workspace`,
    :attr:`balance`, :attr:`hover`, :attr:`capacity`, :attr:`singularity` (:mod:`qprr.analysis`, ``effort.samples``
    configurations each); the masses :attr:`mass` and :attr:`arm_mass` [kg]."""

    def __init__(self, platform, effort: Effort, seed: int, collision: bool = False) -> None:
        self.platform, self.effort, self.seed, self.collision = check_platform(platform), effort, seed, bool(collision)

    @cached_property
    def workspace(self):
        e = self.effort
        return workspace(self.platform, n_samples=e.samples, variants=[], hover=True, n_shifts=e.shifts, seed=self.seed, collision=self.collision)

    @cached_property
    def balance(self):
        e = self.effort
        return balance(self.platform, slider=slider_of(self.platform), n_samples=e.samples, tol=e.balance_tol, n_shifts=e.shifts)

    @cached_property
    def hover(self):
        return hover(self.platform, n_samples=self.effort.samples, collision=False)

    @cached_property
    def capacity(self):
        return capacity(self.platform, n_samples=self.effort.samples)

    @cached_property
    def singularity(self):
        return singularity(self.platform, n_samples=self.effort.samples, task="position")

    @property
    def mass(self) -> float:
        """The whole platform [kg] (the take-off mass)."""
        return float(pin.computeTotalMass(self.platform.model))

    @property
    def arm_mass(self) -> float:
        """Every body but the base's [kg] (joint 1: the free flyer)."""
        return self.mass - float(self.platform.model.inertias[1].mass)

    def balanced_share(self) -> float:
        """:func:`balanced_share` of the workspace and the balance map."""
        return balanced_share(self.workspace.regions[0], self.balance)

    def payload_at_reach(self) -> float:
        """The largest payload held with the end effector at least ``effort.payload_reach`` from the thrust axis [kg]."""
        cap = self.capacity
        far = axis_distance(self.platform, cap.ee_body) >= self.effort.payload_reach
        return float(cap.capacity[far].max()) if far.any() else 0.0


def evaluate_platform(platform, effort: Effort, seed: int, collision: bool = False) -> dict[str, float]:
    """Every metric of :data:`DESIGN_METRICS` for ``platform`` at ``effort`` (``seed``: the measure's counting-grid shifts).

    ``collision``: check self-collision (:mod:`qprr.analysis.collision`) and give the metrics that need it (``free_hover_volume``;
    NaN without: the check costs time, so a study asks for it only when it names such a metric)."""
    maps = DesignMaps(platform, effort, seed, collision)
    return {k: m.compute(maps) if collision or not m.collision else float("nan") for k, m in DESIGN_METRICS.items()}
