"""Run a design study: evaluate its designs on a campaign backend, save each row as it arrives, resume.

:func:`run_design` evaluates the references and the grid, or, with ``search.method = "nsga2"``,
one NSGA-II per architecture over the ranged parameters, generation by generation (every
architecture's generation is submitted at once, so the workers stay busy).  Rows go to a campaign
results file (CSV/Parquet, :mod:`qprr.design.engine.campaign_io`) the moment they arrive.  Running
the same study to the same file again resumes: the saved rows are read back, the optimisers are
replayed (same seed, same told values, so the same designs are asked again) and only the missing
designs are evaluated.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import InputError
from ..evaluate.task import ID_COLUMNS, TAIL_COLUMNS, columns, evaluate_design, exclusions
from ..search.optimiser import make_optimiser
from ..search.points import fixed_params, grid_points, n_points, point, reference_points
from ..spec.metrics import DESIGN_METRICS, sign
from ..spec.parameters import PARAMETERS
from ..spec.study import DesignSpec
from . import campaign_io as io

FAILED = 1e9
"""Objective value (minimisation form) and violation told to the optimiser for a design that failed."""


@dataclass
class DesignRun:
    """What :func:`run_design` did: the results file, designs evaluated now / resumed / failed, wall time, the table."""

    path: Path
    executed: int
    skipped: int
    failed: int
    wall_time: float
    backend: str
    results: io.Results
    interrupted: bool = False


def meta_of(spec: DesignSpec) -> dict:
    return {
        "name": spec.name,
        "fingerprint": spec.fingerprint,
        "design_spec": spec.to_dict(),
        "kind": "design",
        "params": [*ID_COLUMNS[2:], *PARAMETERS],
        "metrics": ["status", "reason", *DESIGN_METRICS, TAIL_COLUMNS[1]],
        "names": [],
        "n_runs": n_points(spec),
    }


def _error_row(spec: DesignSpec, p: dict, exc: Exception) -> dict:
    row = {k: p[k] for k in ID_COLUMNS}
    row.update({k: float(p["params"].get(k, math.nan)) for k in PARAMETERS})
    row.update(status="error", reason=f"{type(exc).__name__}: {exc}", **dict.fromkeys(DESIGN_METRICS, math.nan), feasible=0, wall_time=math.nan)
    return row


def told(spec: DesignSpec, rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """Objectives (minimisation form) and constraint violations (<= 0 feasible; the first: the design failed) of ``rows``."""
    F = np.empty((len(rows), len(spec.objectives)))
    G = np.empty((len(rows), 1 + len(spec.constraints)))
    for i, r in enumerate(rows):
        if r["status"] != "ok":
            F[i], G[i] = FAILED, FAILED
            continue
        F[i] = [sign(k) * float(r[k]) for k in spec.objectives]
        G[i, 0] = -1.0
        for j, (k, (lo, hi)) in enumerate(spec.constraints.items(), start=1):
            v = float(r[k])
            G[i, j] = max(lo - v if lo is not None else -math.inf, v - hi if hi is not None else -math.inf)
    return F, G


class _Study:
    """One call of :func:`run_design`: its campaign :class:`~qprr.campaign.session.Session` (the results file, the
    progress line, the backend opened at the first design to evaluate) and the rows known."""

    def __init__(self, spec: DesignSpec, session: io.Session, done: dict[int, dict]) -> None:
        self.spec, self.session, self.rows, self.bar = spec, session, done, session.bar
        self.executed, self.failed = 0, 0

    def on_row(self, row: dict) -> None:
        self.session.store.append(row)
        self.rows[int(row["run"])] = row
        self.executed += 1
        self.failed += row["status"] != "ok"
        self.bar.update(str(row["status"]))

    def evaluate(self, points: list[dict]) -> list[dict]:
        """The rows of ``points`` (evaluated now when not saved before)."""
        todo = [p for p in points if p["run"] not in self.rows or self.rows[p["run"]]["status"] == "error"]
        if todo:
            be = self.session.be
            if be is None:
                be = self.session.backend()
                self.bar.message(f"{self.bar.total - self.bar.done} designs to evaluate on {be.describe()}")
            on_error = functools.partial(_error_row, self.spec)
            io.evaluate_points(be, evaluate_design, self.spec.to_dict(), todo, self.spec.fingerprint, self.on_row, on_error)
        return [self.rows[p["run"]] for p in points]


def _nsga2(study: _Study) -> None:
    spec = study.spec
    s = spec.search
    names = spec.optimised
    low = [spec.parameters[k].low for k in names]
    high = [spec.parameters[k].high for k in names]
    base = fixed_params(spec)
    opts = [
        make_optimiser(
            s.optimiser,
            low,
            high,
            len(spec.objectives),
            1 + len(spec.constraints),
            s.population,
            int(np.random.SeedSequence(spec.seed, spawn_key=(2**20, a)).generate_state(1)[0]),
        )
        for a in range(len(spec.architectures))
    ]
    start = len(spec.references)
    for g in range(s.generations):
        pts = []
        for a, (arch, opt) in enumerate(zip(spec.architectures, opts)):
            X = opt.ask()
            first = start + (a * s.generations + g) * s.population
            pts.append([point(spec, first + k, "nsga2", arch, {**base, **{n: float(v) for n, v in zip(names, x)}}, g) for k, x in enumerate(X)])
        rows = study.evaluate([p for group in pts for p in group])
        for a, opt in enumerate(opts):
            F, G = told(spec, rows[a * s.population : (a + 1) * s.population])
            opt.tell(F, G)
        study.bar.message(f"generation {g + 1}/{s.generations} done")


def run_design(
    spec: DesignSpec,
    output,
    *,
    backend="local",
    workers: int | None = None,
    scheduler: str | None = None,
    fresh: bool = False,
    progress: bool = True,
    stream=None,
) -> DesignRun:
    """Run ``spec``, saving rows to ``output`` (.csv or .parquet) as they arrive; resume what is there.

    ``backend``: "local" (process pool, default), "dask" (``scheduler`` address or a LocalCluster
    of ``workers``), "inline", or a campaign :class:`~qprr.campaign.Backend` (not closed here).
    Returns a :class:`DesignRun` whose ``results`` is the table (one row per design, by run).
    """
    if not isinstance(spec, DesignSpec):
        raise InputError(f"spec must be a DesignSpec (DesignSpec.load(path)), got {type(spec).__name__}")
    session = io.Session(output, columns(), meta_of(spec), io.BackendChoice(backend, workers, scheduler), fresh)
    done: dict[int, dict] = {}
    if session.store.rows_before:
        t = io.read_table(session.store.path).table
        done = {int(r["run"]): {k: r[k].item() for k in t.dtype.names} for r in t}
    total = n_points(spec)
    skipped = sum(1 for r in done.values() if r["status"] != "error")
    bar = session.progress(f"design {spec.name}", total, skipped, quiet=not progress, stream=stream, unit="design")
    study = _Study(spec, session, done)
    t0 = time.perf_counter()
    interrupted = False
    try:
        study.evaluate(reference_points(spec))
        if spec.search.method == "grid":
            study.evaluate(grid_points(spec))
        else:
            _nsga2(study)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        try:
            session.stop()  # the workers released normally (a design's running evaluations finish)
        finally:
            session.close()
    wall = time.perf_counter() - t0
    if interrupted:
        bar.message(f"interrupted after {study.executed} designs; run the same command again to resume")
    name = backend if isinstance(backend, str) else backend.name
    path = session.store.path
    return DesignRun(path, study.executed, skipped, study.failed, wall, name, io.read_table(path), interrupted)


def infeasible_reasons(results, spec: DesignSpec) -> list[str]:
    """Why designs of a study's table are not feasible (:func:`~qprr.design.evaluate.task.exclusions`), for the terminal:
    the failed evaluations' reasons and what each constraint excludes, otherwise only in the table's columns."""
    table = results.table
    return exclusions(({k: r[k].item() for k in table.dtype.names} for r in table), spec.constraints)
