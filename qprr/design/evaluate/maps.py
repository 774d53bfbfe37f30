"""Evaluate one platform on the design maps of :mod:`qprr.analysis` (the numbers of :data:`METRICS`)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...analysis import balance, capacity, hover, singularity, workspace
from ...model import check_platform
from ..spec.metrics import METRICS
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


def evaluate_platform(platform, effort: Effort, seed: int, collision: bool = False) -> dict[str, float]:
    """Every metric of :data:`METRICS` for ``platform`` at ``effort`` (``seed``: the measure's counting-grid shifts).

    ``collision``: check self-collision (:mod:`qprr.collision`) and give ``free_hover_volume`` (NaN without: the
    check costs time, so a study asks for it only when it names that metric)."""
    n = effort.samples
    ws = workspace(platform, n_samples=n, variants=[], hover=True, n_shifts=effort.shifts, seed=seed, collision=bool(collision))
    hv = ws.regions[0].hover_volume
    free = ws.regions[0].free_hover_volume if collision else None
    bal = balance(platform, slider=slider_of(platform), n_samples=n, tol=effort.balance_tol, n_shifts=effort.shifts)
    hov = hover(platform, n_samples=n, collision=False)
    cap = capacity(platform, n_samples=n)
    far = axis_distance(platform, cap.ee_body) >= effort.payload_reach
    sing = singularity(platform, n_samples=n, task="position")
    m_total = float(pin.computeTotalMass(platform.model))
    m_arm = m_total - float(platform.model.inertias[1].mass)  # every body but the base's (joint 1: the free flyer)
    out = {
        "hover_volume": float(hv.measure) if hv is not None else 0.0,
        "free_hover_volume": (float(free.measure) if free is not None else 0.0) if collision else float("nan"),
        "balance_fraction": balanced_share(ws.regions[0], bal),
        "thrust_margin": float(hov.min_thrust_margin[0]),
        "payload_at_reach": float(cap.capacity[far].max()) if far.any() else 0.0,
        "manipulability": float(np.median(sing.manipulability)),
        "arm_mass": m_arm,
        "mass": m_total,
    }
    return {k: out[k] for k in METRICS}
