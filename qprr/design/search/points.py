"""Design points: the references, the grid, and the seeds and run indices of every evaluation.

Run indices: the references first (0..R-1), then the grid in C order (architecture slowest, then
the swept parameters in :data:`~qprr.design.spec.PARAMETERS` order); with NSGA-II, architecture
``a`` generation ``g`` member ``k`` is run ``R + (a * generations + g) * population + k``.  Every design is measured with the same seed,
drawn from ``SeedSequence(seed)`` (the workspace estimator's counting-grid shifts): common random
numbers, so that two designs differ by their geometry, never by the shifts (two identical
geometries give identical numbers).  The table depends on the study only.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..spec.study import DesignSpec


def run_seed(spec: DesignSpec) -> int:
    """The measurement seed of every design of ``spec`` (common random numbers, module docstring)."""
    return int(np.random.SeedSequence(spec.seed).generate_state(1)[0])


def point(spec: DesignSpec, index: int, kind: str, architecture: str, params: dict, generation: int = -1) -> dict:
    """A design point as plain data (the task's argument)."""
    name = f"{architecture} (reference)" if kind == "reference" else architecture  # a registered platform's name
    return {
        "run": index,
        "seed": run_seed(spec),
        "kind": kind,
        "architecture": architecture,
        "name": name,
        "generation": generation,
        "params": dict(params),
    }


def reference_points(spec: DesignSpec) -> list[dict]:
    return [point(spec, i, "reference", r, {}) for i, r in enumerate(spec.references)]


def fixed_params(spec: DesignSpec) -> dict[str, float]:
    """The parameters with one value."""
    return {k: p.values[0] for k, p in spec.parameters.items() if len(p.values) == 1}


def grid_points(spec: DesignSpec) -> list[dict]:
    """Every architecture x every combination of the swept parameters (after the references)."""
    swept = spec.swept
    base = fixed_params(spec)
    out = []
    i = len(spec.references)
    for arch in spec.architectures:
        for combo in itertools.product(*(spec.parameters[k].values for k in swept)):
            out.append(point(spec, i, "grid", arch, {**base, **dict(zip(swept, combo))}))
            i += 1
    return out


def n_points(spec: DesignSpec) -> int:
    """How many designs the study evaluates."""
    if spec.search.method == "grid":
        return len(spec.references) + len(grid_points(spec))
    return len(spec.references) + len(spec.architectures) * spec.search.generations * spec.search.population
