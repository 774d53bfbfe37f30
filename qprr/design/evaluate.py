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
from ..campaign.metrics import RunStatus
from ..errors import InputError, QprrError
from ..model import check_platform
from ..nomenclature import LinkSpec, build, parse
from .metrics import DESIGN_METRICS
from .spec import DesignSpec, Effort, MassModel, StudyKind

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
    w = [1.0] + [params["taper"] ** k for k in range(1, n_r)]  # taper applies from a second revolute link on
    rev = iter(params["reach"] * x / sum(w) for x in w)
    return [params["slider_link"] if k == "P" else next(rev) for k in joints]


def arm_links(joints: str, params: Mapping[str, float], mass: MassModel) -> list[LinkSpec]:
    """The :class:`~qprr.nomenclature.LinkSpec` of each joint (masses from ``mass``)."""
    out = []
    for kind, length in zip(joints, link_lengths(joints, params)):
        if kind == "P":
            stroke = params["slider_stroke"]
            out.append(LinkSpec("P", length=length, mass=mass.link_mass("P", length, stroke), lower=-stroke / 2.0, upper=stroke / 2.0))
        else:
            out.append(LinkSpec("R", length=length, mass=mass.link_mass("R", length)))
    return out


def _has_slider(joints: str) -> bool:
    return "P" in joints


def _has_two_revolute(joints: str) -> bool:
    return joints.count("R") >= 2


APPLIES_TO = {"slider_stroke": _has_slider, "slider_link": _has_slider, "taper": _has_two_revolute}
"""The nomenclature's parameters that apply only to some arms: name -> whether it applies to an arm's joints ("PRR")."""


def applies(spec: DesignSpec, family: str, name: str, chosen: Mapping[str, float | str]) -> bool:
    """Whether parameter ``name`` applies to a candidate of ``family`` (an architecture, or a URDF study's robot) whose
    earlier parameters have the values ``chosen``: a slider's parameters need a P joint, ``taper`` two R joints (a
    parameter that does not apply is not varied, its cell is left empty); a URDF study's need their ``when``."""
    if spec.kind is StudyKind.URDF:
        return spec.parameters[name].applies(chosen)
    return name not in APPLIES_TO or APPLIES_TO[name](parse(family).joints)


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
"""Leading columns of a design table; then the study's parameters (:data:`PARAMETERS` for the nomenclature), the status,
the metrics."""

TAIL_COLUMNS = ("feasible", "wall_time")


def columns(spec: DesignSpec) -> tuple[str, ...]:
    return (*ID_COLUMNS, *spec.parameters, "status", "reason", *DESIGN_METRICS, *TAIL_COLUMNS)


def cells(spec: DesignSpec, params: Mapping[str, float | str]) -> dict[str, float | str]:
    """The parameter cells of a row: each value, or empty where the parameter does not apply (NaN, or "" for words)."""
    return {k: params[k] if k in params else "" if p.words else math.nan for k, p in spec.parameters.items()}


def params_of_row(spec: DesignSpec, row: Mapping) -> dict[str, float | str]:
    """The parameters of a table row that apply to its design (the point's ``params``)."""
    out: dict[str, float | str] = {}
    for k, p in spec.parameters.items():
        if applies(spec, row["architecture"], k, out):
            out[k] = str(row[k]) if p.words else float(row[k])
    return out


def design_platform(spec: DesignSpec, kind: str, family: str, params: Mapping[str, float | str]):
    """The platform of a design: a reference as registered, a URDF study's robot instantiated (the parameters that do not
    apply get their ``otherwise``), or the nomenclature's candidate (:func:`build_candidate`)."""
    if kind == "reference":
        from ..platforms import load

        return load(family)
    if spec.kind is StudyKind.URDF:
        return spec.robot.platform({**{k: p.otherwise for k, p in spec.parameters.items() if k not in params}, **params})
    return build_candidate(Candidate(family, params), spec.mass)


def feasible(row: Mapping, constraints: Mapping) -> int:
    """1 if the row is ok and meets every ``{metric: (min, max)}`` bound, else 0."""
    if row["status"] != RunStatus.OK:
        return 0
    for k, (lo, hi) in constraints.items():
        v = row[k]
        if (lo is not None and not v >= lo) or (hi is not None and not v <= hi):
            return 0
    return 1


def violations(row: Mapping, constraints: Mapping) -> list[str]:
    """The bounds ``{metric: (min, max)}`` an evaluated row misses, each with its value (e.g. "thrust_margin = -0.4 N,
    below its min 0")."""
    out = []
    for k, (lo, hi) in constraints.items():
        unit = f" {DESIGN_METRICS[k].unit}" if DESIGN_METRICS[k].unit else ""
        if lo is not None and not row[k] >= lo:
            out.append(f"{k} = {row[k]:.4g}{unit}, below its min {lo:g}")
        if hi is not None and not row[k] <= hi:
            out.append(f"{k} = {row[k]:.4g}{unit}, above its max {hi:g}")
    return out


def describe(spec: DesignSpec, row: Mapping) -> str:
    """``design RUN NAME (the varied parameters that apply)``: how a design is named on the terminal."""
    shown = spec.optimised or spec.swept
    vals = params_of_row(spec, row) if row["kind"] != "reference" else {}
    text = ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in vals.items() if k in shown)
    return f"design {row['run']} {row['name']}" + (f" ({text})" if text else "")


def exclusions(rows, spec: DesignSpec) -> list[str]:
    """Why designs are not feasible, on the terminal: each constraint with the number of evaluated designs it excludes
    (one may be excluded by several), the count of failed evaluations, then every design that is not feasible with its
    reason (the failure, or the bounds it misses and its values); [] when every design is feasible."""
    rows = list(rows)
    ok = [r for r in rows if r["status"] == RunStatus.OK]
    lines = []
    for k, (lo, hi) in spec.constraints.items():
        bound = " and ".join(b for b in ((f"{k} >= {lo:g}" if lo is not None else ""), (f"{k} <= {hi:g}" if hi is not None else "")) if b)
        out = sum(1 for r in ok if violations(r, {k: (lo, hi)}))
        if out:
            lines.append(f"  constraint {bound} excludes {out} of the {len(ok)} evaluated design(s)")
    n_failed = len(rows) - len(ok)
    if n_failed:
        lines.append(f"  {n_failed} design(s) could not be evaluated (failed: the design is refused; error: a bug, re-run on resume)")
    for r in rows:
        if r["status"] != RunStatus.OK:
            reason = " ".join(str(r.get("reason", "")).split())
            lines.append(f"  {describe(spec, r)}: {r['status']}: {reason}")
        elif not feasible(r, spec.constraints):
            lines.append(f"  {describe(spec, r)}: infeasible: {'; '.join(violations(r, spec.constraints))}")
    n_feasible = sum(feasible(r, spec.constraints) for r in rows)
    return [f"not feasible: {len(rows) - n_feasible} of {len(rows)} design(s):", *lines] if lines else []


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
    status, reason = RunStatus.OK, ""
    values = dict.fromkeys(DESIGN_METRICS, math.nan)
    try:
        named = {*spec.objectives, *spec.constraints}
        collision = any(DESIGN_METRICS[k].collision for k in named)  # a metric the study names needs the self-collision check
        platform = design_platform(spec, point["kind"], point["architecture"], point["params"])
        values = evaluate_platform(platform, spec.effort, point["seed"], collision=collision)
    except QprrError as exc:
        status, reason = RunStatus.FAILED, f"{type(exc).__name__}: {exc}"
    except Exception as exc:  # a bug must not lose the study: recorded, visible in the table, re-run on resume
        status, reason = RunStatus.ERROR, f"{type(exc).__name__}: {exc}"
    row = {k: point[k] for k in ID_COLUMNS}
    row.update(cells(spec, point["params"]))
    row.update(status=status, reason=reason, **values)
    row["feasible"] = feasible(row, spec.constraints)
    row["wall_time"] = time.perf_counter() - t0
    return row
