"""Evaluate one platform on the design maps of :mod:`qprr.analysis` (the numbers of :data:`METRICS`)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...analysis import balance, capacity, hover, singularity, workspace
from ..spec.metrics import METRICS
from ..spec.study import Effort


def slider_of(platform) -> str | None:
    """The first prismatic joint (the one :func:`qprr.analysis.balance` moves), or None."""
    return next((j.name for j in platform.arm if j.kind == "prismatic"), None)


def axis_distance(platform, p_body: np.ndarray) -> np.ndarray:
    """Distance [m] of points in B (n, 3) from the thrust axis."""
    point, axis = platform.thrust_axis
    d = np.asarray(p_body) - np.asarray(point)
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.linalg.norm(d - np.outer(d @ a, a), axis=1)


def evaluate_platform(platform, effort: Effort, seed: int) -> dict[str, float]:
    """Every metric of :data:`METRICS` for ``platform`` at ``effort`` (``seed``: the measure's counting-grid shifts)."""
    n = effort.samples
    ws = workspace(platform, n_samples=n, variants=[], hover=True, n_shifts=effort.shifts, seed=seed)
    hv = ws.regions[0].hover_volume
    bal = balance(platform, slider=slider_of(platform), n_samples=n, tol=effort.balance_tol, n_shifts=effort.shifts)
    hov = hover(platform, n_samples=n)
    cap = capacity(platform, n_samples=n)
    far = axis_distance(platform, cap.ee_body) >= effort.payload_reach
    sing = singularity(platform, n_samples=n, task="position")
    m_total = float(pin.computeTotalMass(platform.model))
    m_arm = m_total - float(platform.model.inertias[1].mass)  # every body but the base's (joint 1: the free flyer)
    out = {
        "hover_volume": float(hv.measure) if hv is not None else 0.0,
        "balance_fraction": float(bal.fraction_workspace.value) if bal.fraction_workspace is not None else 0.0,
        "thrust_margin": float(hov.min_thrust_margin[0]),
        "payload_at_reach": float(cap.capacity[far].max()) if far.any() else 0.0,
        "manipulability": float(np.median(sing.manipulability)),
        "arm_mass": m_arm,
        "mass": m_total,
    }
    return {k: out[k] for k in METRICS}
