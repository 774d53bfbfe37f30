"""The task a backend runs for one design: plain data in, one result row out.

:func:`evaluate_design` is a module-level function of plain-data arguments (the study as a dict,
one point), so it runs unchanged in this process, a local process pool or on a Dask worker
(:mod:`qprr.design.engine.campaign_io`).  A design that cannot be built or evaluated becomes a row
of status ``failed`` (a qprr error: an arm heavier than the mass budget...) or ``error`` (any other
exception: a bug, recorded and re-run on resume), never a lost evaluation.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping

from ...errors import QprrError
from ..model.candidate import Candidate, build_candidate
from ..spec.metrics import DESIGN_METRICS
from ..spec.parameters import PARAMETERS
from ..spec.study import DesignSpec
from .maps import evaluate_platform

ID_COLUMNS = ("run", "seed", "kind", "architecture", "name", "generation")
"""Leading columns of a design table; then the parameters (:data:`PARAMETERS`), the status, the metrics."""

TAIL_COLUMNS = ("feasible", "wall_time")


def columns() -> tuple[str, ...]:
    return (*ID_COLUMNS, *PARAMETERS, "status", "reason", *DESIGN_METRICS, *TAIL_COLUMNS)


def feasible(row: Mapping, constraints: Mapping) -> int:
    """1 if the row is ok and meets every ``{metric: (min, max)}`` bound, else 0."""
    if row["status"] != "ok":
        return 0
    for k, (lo, hi) in constraints.items():
        v = row[k]
        if (lo is not None and not v >= lo) or (hi is not None and not v <= hi):
            return 0
    return 1


def exclusions(rows, constraints: Mapping, limit: int = 3) -> list[str]:
    """Why designs are not feasible, on the terminal: the failed evaluations per reason (the ``limit`` most frequent), then
    each constraint ``{metric: (min, max)}`` with the number of evaluated designs it excludes (one may be excluded by
    several); [] when every design is feasible."""
    rows = list(rows)
    failed: dict[str, int] = {}
    for r in rows:
        if r["status"] != "ok":
            key = f"{r['status']}: {r.get('reason', '')}"
            failed[key] = failed.get(key, 0) + 1
    ok = [r for r in rows if r["status"] == "ok"]
    lines = [f"  {n} design(s) {why}" for why, n in sorted(failed.items(), key=lambda kv: -kv[1])[:limit]]
    for k, (lo, hi) in constraints.items():
        bound = " and ".join(b for b in ((f"{k} >= {lo:g}" if lo is not None else ""), (f"{k} <= {hi:g}" if hi is not None else "")) if b)
        out = sum(1 for r in ok if (lo is not None and not r[k] >= lo) or (hi is not None and not r[k] <= hi))
        if out:
            lines.append(f"  constraint {bound} excludes {out} of the {len(ok)} evaluated design(s)")
    n_feasible = sum(feasible(r, constraints) for r in rows)
    return [f"not feasible: {len(rows) - n_feasible} of {len(rows)} design(s):", *lines] if lines else []


def _platform(spec: DesignSpec, point: Mapping):
    if point["kind"] == "reference":
        from ...platforms import load

        return load(point["architecture"])
    return build_candidate(Candidate(point["architecture"], point["params"]), spec.mass)


_SPECS: dict[str, DesignSpec] = {}
"""This process's validated study, keyed by its JSON text (validated once per worker, not once per design)."""


def study_of(spec_dict: dict) -> DesignSpec:
    """The :class:`DesignSpec` of a task's plain-data study (cached in this process)."""
    key = json.dumps(spec_dict, sort_keys=True)
    spec = _SPECS.get(key)
    if spec is None:
        _SPECS.clear()
        spec = _SPECS[key] = DesignSpec.from_mapping(spec_dict)
    return spec


def evaluate_design(spec_dict: dict, point: dict) -> dict:
    """The row of one design ``point`` (``run``, ``seed``, ``kind``, ``architecture``, ``name``, ``generation``, ``params``)."""
    spec = study_of(spec_dict)
    t0 = time.perf_counter()
    status, reason = "ok", ""
    values = dict.fromkeys(DESIGN_METRICS, math.nan)
    try:
        named = {*spec.objectives, *spec.constraints}
        collision = any(DESIGN_METRICS[k].collision for k in named)  # a metric the study names needs the self-collision check
        values = evaluate_platform(_platform(spec, point), spec.effort, point["seed"], collision=collision)
    except QprrError as exc:
        status, reason = "failed", f"{type(exc).__name__}: {exc}"
    except Exception as exc:  # a bug must not lose the study: recorded, visible in the table, re-run on resume
        status, reason = "error", f"{type(exc).__name__}: {exc}"
    row = {k: point[k] for k in ID_COLUMNS}
    row.update({k: float(point["params"].get(k, math.nan)) for k in PARAMETERS})
    row.update(status=status, reason=reason, **values)
    row["feasible"] = feasible(row, spec.constraints)
    row["wall_time"] = time.perf_counter() - t0
    return row
