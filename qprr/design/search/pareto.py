"""Pareto dominance, non-dominated sorting and the 2-D hypervolume, in minimisation form."""

from __future__ import annotations

import numpy as np


def dominated(F: np.ndarray) -> np.ndarray:
    """(n,) True where a row of ``F`` (n, m), to minimise, is dominated by another row (<= everywhere, < somewhere)."""
    F = np.asarray(F, dtype=float)
    le = np.all(F[:, None, :] <= F[None, :, :], axis=2)  # le[j, i]: j <= i everywhere
    lt = np.any(F[:, None, :] < F[None, :, :], axis=2)
    return np.any(le & lt, axis=0)


def front_levels(F: np.ndarray) -> np.ndarray:
    """Non-dominated sorting: level 1 for the Pareto front, 2 for the front of the rest, ..."""
    F = np.asarray(F, dtype=float)
    level = np.zeros(len(F), dtype=int)
    left = np.arange(len(F))
    k = 1
    while left.size:
        d = dominated(F[left])
        level[left[~d]] = k
        left = left[d]
        k += 1
    return level


def hypervolume_2d(F: np.ndarray, ref) -> float:
    """Area dominated by the points ``F`` (n, 2), to minimise, and bounded by ``ref`` (exact, sweep)."""
    F = np.asarray(F, dtype=float)
    F = F[np.all(F < np.asarray(ref), axis=1)]
    if not len(F):
        return 0.0
    F = F[np.argsort(F[:, 0], kind="stable")]
    hv, best = 0.0, ref[1]
    for x, y in F:
        if y < best:
            hv += (ref[0] - x) * (best - y)
            best = y
    return float(hv)
