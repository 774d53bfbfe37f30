"""Evaluate designs: a candidate built into a platform, the maps that give the metrics of :data:`DESIGN_METRICS`, the backend task.

**Candidates.** A candidate design: an architecture of (2.1) and its parameter values, built into a platform.

:func:`build_candidate` turns ``("Q-PRR", {"reach": 0.28, ...})`` into a
:class:`~qprr.model.Platform` with :func:`qprr.nomenclature.build`: the revolute links share
``reach`` in the ratio ``taper`` (link k+1 = taper x link k), a prismatic joint gets the
``slider_link`` length and +-``slider_stroke``/2 limits, every link's mass comes from the
:class:`~qprr.design.spec.MassModel`, and the rotors are sized so that every design has the same
total maximum thrust ``thrust_to_weight * total_mass * g`` (a hexarotor splits it over six).

**The maps of a design.** Evaluate one platform on the design maps of :mod:`qprr.analysis` (the numbers of :data:`DESIGN_METRICS`).

**The backend task.** The task a backend runs for one design: plain data in, one result row out.

:func:`evaluate_design` is a module-level function of plain-data arguments (the study as a dict,
one point), so it runs unchanged in this process, a local process pool or on a Dask worker
(:mod:`qprr.design.search`).  A design that cannot be built or evaluated becomes a row
of status ``failed`` (a qprr error: an arm heavier than the mass budget...) or ``error`` (any other
exception: a bug, recorded and re-run on resume), never a lost evaluation.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin

from ..analysis import balance, capacity, hover, singularity, workspace
from ..errors import InputError, QprrError
from ..model import check_platform
from ..nomenclature import LinkSpec, build, parse
from .metrics import DESIGN_METRICS
from .spec import PARAMETERS, DesignSpec, Effort, MassModel

# ------------------------------------------------------------------------------------------------- Candidates
G = 9.81


@dataclass(frozen=True)
class Candidate:
    """An architecture (a (2.1) name) and its parameters (name -> value, SI units)."""

    architecture: str
    params: Mapping[str, float]


def link_lengths(joints: str, params: Mapping[str, float]) -> list[float]:
    """Lengths [m] of the links after each joint: the revolute ones share ``reach`` in the ratio ``taper``."""
    n_r = joints.count("R")
    w = [params["taper"] ** k for k in range(n_r)]
    rev = iter(params["reach"] * x / sum(w) for x in w)
    return [params["slider_link"] if k == "P" else next(rev) for k in joints]


def arm_links(joints: str, params: Mapping[str, float], mass: MassModel) -> list[LinkSpec]:
    """The :class:`~qprr.nomenclature.LinkSpec` of each joint (masses from ``mass``)."""
    stroke = params["slider_stroke"]
    out = []
    for kind, length in zip(joints, link_lengths(joints, params)):
        m = mass.link_mass(kind, length, stroke if kind == "P" else 0.0)
        if kind == "P":
            out.append(LinkSpec("P", length=length, mass=m, lower=-stroke / 2.0, upper=stroke / 2.0))
        else:
            out.append(LinkSpec("R", length=length, mass=m))
    return out


def build_candidate(candidate: Candidate, mass: MassModel):
    """The platform of ``candidate`` (module docstring); an :class:`InputError` if the arm outweighs the mass budget."""
    d = parse(candidate.architecture)
    p = candidate.params
    links = arm_links(d.joints, p, mass)
    m_arm = sum(k.mass for k in links)
    if mass.mode == "equal-total":
        body = p["total_mass"] - m_arm
        if body <= 0.0:
            raise InputError(
                f"{candidate.architecture}: the arm ({m_arm:.3f} kg) leaves no body mass within total_mass = "
                f"{p['total_mass']!r} kg; raise total_mass or shorten the arm"
            )
    else:
        body = mass.body
    total = body + m_arm
    # build() sizes f_max on its own total mass: scale so that the thrust is the study's, the same for every design
    ttw = p["thrust_to_weight"] * p["total_mass"] / total
    arm_len = p["rotor_arm_length"] or None
    return build(
        candidate.architecture, links=links, body_mass=body, arm_length=arm_len, mount_xyz=(0.0, 0.0, p["mount_height"]), thrust_to_weight=ttw, g=G
    )


# --------------------------------------------------------------------------------------- The maps of a design
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

    ``platform``, ``effort`` (:class:`~qprr.design.spec.Effort`), ``seed`` (the measure's counting-grid shifts),
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


# ------------------------------------------------------------------------------------------- The backend task
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
        from ..platforms import load

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
